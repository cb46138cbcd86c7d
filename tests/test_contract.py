"""The shared contract every registered item must satisfy (runs over the registry)."""

from __future__ import annotations

import dataclasses
import pickle

import cvxpy as cp
import numpy as np
import pytest

import bvpnav
from bvpnav.items import MODES, item_class, registry
from bvpnav.model import Affine

ITEMS = sorted(registry())


def model3d():
    t = np.linspace(0.0, 10.0, 101)
    acc = np.column_stack([np.sin(t), np.cos(t), 0.1 * t])
    return bvpnav.NavModel(bvpnav.ImuData(t=t, acc=acc))


def test_registry_holds_the_foundation_items():
    assert {"position", "velocity", "average_velocity", "symmetry", "zero_velocity", "linear"} <= set(ITEMS)


@pytest.mark.parametrize("name", ITEMS)
def test_item_contract(name):
    cls = item_class(name)
    assert item_class(name.upper()) is cls  # names are case-insensitive
    item = cls.example()
    assert isinstance(item, bvpnav.Item)
    # the constructor stores data only: no cvxpy objects, and the item is frozen
    for v in vars(item).values():
        assert not isinstance(v, cp.Expression | cp.Constraint), name
    field = dataclasses.fields(item)[0].name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(item, field, None)
    model = model3d()
    res = item.compile(model)
    if item.kind == "cone":  # second-order-cone items return their own object
        return
    assert isinstance(res, Affine)
    assert res.m > 0 and res.A.shape == (res.m, model.size)
    assert np.all(np.isfinite(res.A.data)) and np.all(np.isfinite(res.c))
    # deterministic, and survives pickling (batch runs ship items to workers)
    again = pickle.loads(pickle.dumps(item)).compile(model)
    assert (again.A != res.A).nnz == 0 and np.array_equal(again.c, res.c)
    # one line of mathematics for describe()
    assert isinstance(item.math(), str) and item.math().strip()
    # every mode is a switch on the same object
    for mode in MODES:
        kw = {"mode": mode, "sigma": None, "tol": None, "huber": None}
        if mode in ("soft", "robust"):
            kw["sigma"] = 0.5
        if mode == "robust":
            kw["huber"] = 1.0
        if mode == "band":
            kw["tol"] = 0.1
        other = dataclasses.replace(item, **kw)
        assert other.mode == mode
        assert other.compile(model).m == res.m
    # bad weights are refused, naming the class
    with pytest.raises(bvpnav.InputError, match=cls.__name__):
        dataclasses.replace(item, sigma=-1.0, mode=None)
    with pytest.raises(bvpnav.InputError, match="mode"):
        dataclasses.replace(item, mode="sometimes")


@pytest.mark.parametrize("name", ITEMS)
def test_item_respects_axis_selection(name):
    item = item_class(name).example()
    model = model3d()
    one = dataclasses.replace(item, axes=("y",)) if item.axes is None else item
    sel = one.axes
    res = one.compile(model)
    cols = np.unique(res.A.nonzero()[1])
    allowed = set()
    for a, ax in enumerate(model.axes):
        if ax in sel:
            allowed |= set(range(a * model.block, (a + 1) * model.block))
    allowed |= set(model.l_index.tolist())
    assert set(cols.tolist()) <= allowed, f"{name} touches axes outside {sel}"


@pytest.mark.parametrize("name", ITEMS)
def test_item_in_a_solved_problem(name):
    """Every item (soft) joins a well-posed problem and the solve is verified."""
    item = item_class(name).example()
    t = np.linspace(0.0, 10.0, 101)
    acc = np.column_stack([np.sin(t), np.cos(t), 0.1 * t])
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc))
    prob.add(bvpnav.constraints.Position(t=[0.0, 10.0], value=0.0))
    kw = {"mode": None, "tol": None, "huber": None, "sigma": 1.0 if item.kind != "cone" else None}
    prob.add(dataclasses.replace(item, **kw))
    sol = prob.solve()
    assert sol.stats["verified"]
    assert item.label in set(sol.items["item"])
