"""The shared contract every registered item must satisfy (runs over the registry).

The rules themselves live in :func:`bvpnav.testing.check_item` (public, so plug-in authors
can run them too); ``tests/test_testing.py`` runs it over every registered item. This
module keeps the registry's foundation and the original solved-problem check.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import bvpnav
from bvpnav.items import item_class, registry

ITEMS = sorted(registry())


def test_registry_holds_the_foundation_items():
    assert {"position", "velocity", "average_velocity", "symmetry", "zero_velocity", "linear"} <= set(ITEMS)


# The per-item contract (case-insensitive registry name, an Item, frozen, no cvxpy objects, an
# Affine -- or for cone items a Cone -- of m > 0 rows over every unknown, finite, deterministic,
# the same after pickling, one line of math(), every mode a switch with the same rows, sigma=-1
# and mode="sometimes" refused naming the class, axis selection respected, a verified hard and
# soft solve) is bvpnav.testing.check_item, run over the registry by tests/test_testing.py.


@pytest.mark.parametrize("name", ITEMS)
def test_item_in_a_solved_problem(name):
    """Every item (soft) joins a well-posed problem and the solve is verified."""
    cls = item_class(name)
    item = cls.example()
    model = cls.example_model()  # the model the example is written for, when it is not the default
    if model is None:
        t = np.linspace(0.0, 10.0, 101)
        acc = np.column_stack([np.sin(t), np.cos(t), 0.1 * t])
        prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc))
    else:
        prob = bvpnav.NavigationProblem(model.data, error_model=model.error_model if cls.needs_error_model
                                        else None)
    prob.add(bvpnav.constraints.Position(t=[0.0, 10.0], value=0.0))
    kw = {"mode": None, "tol": None, "huber": None, "sigma": 1.0 if item.kind != "cone" else None}
    prob.add(dataclasses.replace(item, **kw))
    sol = prob.solve()
    assert sol.stats["verified"]
    assert item.label in set(sol.items["item"])
