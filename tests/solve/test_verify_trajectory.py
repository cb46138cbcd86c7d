"""The final stage shares the answer's trajectory with the verification (issue 42: the
stationarity floor's velocity scale from the trajectory at the nodes instead of the nodes'
velocity rows built again), and the solve package brings its plug-in families with it."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import run_python

import bvpnav
from bvpnav.backends import resolve_solver
from bvpnav.constraints import Position
from bvpnav.error_models import Bias
from bvpnav.solve.verify import stationarity, verify


@pytest.fixture(scope="module")
def mesh_answer():
    """A two-axis coarse-mesh problem (``segment=0.4``) with a bias and soft fixes: its
    formulation, ``direct``'s answer and duals."""
    rng = np.random.default_rng(11)
    t = np.cumsum(rng.uniform(0.005, 0.015, 1200))
    acc = np.column_stack([np.sin(t), 0.5 * np.cos(2.0 * t)]) + 0.02 + 0.03 * rng.standard_normal((t.size, 2))
    data = bvpnav.ImuData(t=t, acc=acc, axes=("x", "y"))
    fix = t[::150]
    prob = bvpnav.NavigationProblem(data, sigma_a=0.05, error_model=Bias(), segment=0.4, items=[
        Position(t=[t[0]], value=[[0.0, 0.0]], name="start"),
        Position(t=fix, value=rng.normal(size=(fix.size, 2)) * 0.1, sigma=0.05, name="fixes")])
    form = prob.formulation
    be = resolve_solver("direct")
    raw = be.run(form, 1.0, be.presets["default"], workspace=None)
    return form, raw


def test_the_trajectory_velocities_at_the_nodes_are_the_mesh_node_velocities(mesh_answer):
    form, raw = mesh_answer
    model = form.model
    assert model.N < model.fine.n / 10   # a coarse mesh: the nodes' velocities are condensed rows
    v = model.trajectory(raw.x)["v"][model.node_samples]
    for a in range(model.d):
        rows = model.node_velocity_values(a, raw.x)
        assert np.max(np.abs(v[:, a] - rows)) <= 1e-12 * np.max(np.abs(rows))


def test_the_verification_from_the_trajectory_is_the_verification_without_it(mesh_answer):
    form, raw = mesh_answer
    x, duals = raw.x, raw.duals
    traj = form.model.trajectory(x)
    own = stationarity(form, x, 1.0, duals)
    shared = stationarity(form, x, 1.0, duals, traj["v"][form.model.node_samples])
    assert 0.0 < own < 1e-6   # a direct answer: stationary to rounding
    assert shared == pytest.approx(own, rel=1e-9)
    a = verify(form, x, 1.0, duals=duals, factored=raw.factored)
    b = verify(form, x, 1.0, duals=duals, factored=raw.factored, trajectory=traj)
    assert a.verified and b.verified
    for name in ("fem_residual", "max_violation", "forward_error"):
        assert getattr(a, name) == getattr(b, name)
    assert b.stationarity == pytest.approx(a.stationarity, rel=1e-9)


def test_importing_the_solve_package_registers_the_back_ends_and_the_rules():
    """The back ends and lambda rules are imported with ``bvpnav.solve`` (not by the first solve's
    option check, inside its time), and cvxpy still is not."""
    out = run_python("""
        import json, sys
        import bvpnav.solve
        print(json.dumps({m: m in sys.modules for m in ("bvpnav.backends.direct",
                          "bvpnav.backends.cvxpy_solvers", "bvpnav.lam.gcv", "bvpnav.lam.quasi", "cvxpy")}))
    """)
    assert out == {"bvpnav.backends.direct": True, "bvpnav.backends.cvxpy_solvers": True,
                   "bvpnav.lam.gcv": True, "bvpnav.lam.quasi": True, "cvxpy": False}
