"""Direct back ends: the sparse KKT solve and the 2011 paper's CSNE refinement."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import kkt_reference, table1_problem

import bvpnav
from bvpnav.constraints import Position, Velocity


@pytest.mark.parametrize("residual", ["acceleration", "load"])
@pytest.mark.parametrize("solver", ["direct", "csne"])
def test_direct_matches_independent_kkt_reference(residual, solver):
    prob, truth = table1_problem(2001, residual=residual)
    sol = prob.solve(solver=solver, lam=0.7, fallback=None)
    ref = kkt_reference(prob, 0.7)
    assert sol.stats["solver"] == solver and sol.stats["verified"]
    np.testing.assert_allclose(sol.x, ref, rtol=0, atol=1e-8 * np.max(np.abs(ref)))
    if residual == "load":  # lam=0.7 lets the cubic prior absorb the bias drift (method III)
        assert np.sqrt(np.mean((sol.position()[:, 0] - truth) ** 2)) < 2.0


def test_direct_agrees_with_clarabel_and_returns_cvxpy_duals():
    prob, _ = table1_problem(801)
    d = prob.solve(solver="direct", lam=2.0)
    c = prob.solve(solver="clarabel", lam=2.0, accuracy="high")
    assert np.max(np.abs(d.position() - c.position())) < 1e-7
    # stationarity is checked with the direct back end's duals: they must be cvxpy's
    assert d.stats["verification"]["stationarity"] < 1e-8


def test_direct_is_accurate_where_clarabel_is_not():
    """The load form at N = 20,000: Clarabel's answer fails verification (see
    test_problem), the augmented-system solve is exact to refinement accuracy."""
    prob, _ = table1_problem(20000, residual="load")
    sol = prob.solve(solver="direct", lam=1.0, fallback=None)
    ref = kkt_reference(prob, 1.0, refinements=6)
    assert sol.stats["verification"]["forward_error"] < 1e-8
    assert np.max(np.abs(sol.x - ref)) < 1e-6 * np.max(np.abs(ref))


def test_exact_ends_are_exact():
    t = np.linspace(0.0, 4.0, 401)
    acc = np.column_stack([np.cos(t), 2.0 * np.ones_like(t)])
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc, axes=("x", "y")))
    prob.add(Position(t=[0.0], value=[[0.0, 0.0]]), Velocity(t=[0.0], value=[[0.0, 0.0]]))
    sol = prob.solve(solver="direct")
    # x = 1 - cos t ; y = t^2; FEM with piecewise-linear load is second order
    np.testing.assert_allclose(sol.position()[:, 0], 1 - np.cos(t), atol=2e-5)
    np.testing.assert_allclose(sol.position()[:, 1], t**2, atol=1e-10)
    np.testing.assert_allclose(sol.velocity()[-1], [np.sin(4.0), 8.0], atol=2e-5)


@pytest.mark.parametrize("solver,kw,mode", [("csne", {"mode": "band", "tol": 0.1}, "band"),
                                             ("direct", {"mode": "robust", "sigma": 0.1, "huber": 0.2},
                                              "robust")])
def test_refuses_items_it_cannot_take_by_name(solver, kw, mode):
    """csne takes hard and soft equalities only; direct also bands and inequalities (see
    test_direct_ipm), not robust penalties or cones."""
    prob, _ = table1_problem(201)
    prob.add(Velocity(t=[5.0], value=[1.0], name="speed window", **kw))
    with pytest.raises(bvpnav.InputError, match=f"speed window.*{mode}.*clarabel"):
        prob.solve(solver=solver, fallback=None)
    # the default chain skips them and Clarabel solves it
    assert prob.solve().stats["solver"] == "clarabel"


def test_csne_reports_its_refinement_steps():
    prob, _ = table1_problem(4001, residual="load")
    sol = prob.solve(solver="csne", fallback=None)
    assert 1 <= sol.stats["iterations"] <= 20
    assert sol.stats["verification"]["forward_error"] < 1e-8


def test_redundant_consistent_hard_rows_are_solved():
    """Average velocities over [0, 5] and [5, 10] with both end positions hard repeat one
    row; the multiplier block is singular but x is unique."""
    from bvpnav.constraints import AverageVelocity

    t = np.linspace(0.0, 10.0, 501)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.full(t.size, 0.2)))
    prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0]),
             AverageVelocity(t0=[0.0, 5.0], t1=[5.0, 10.0], value=[1.0, 1.0]))
    sol = prob.solve(solver="direct", fallback=None)
    assert sol.stats["verified"]
    # the same information without the repeated row gives the same trajectory
    ref = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.full(t.size, 0.2)))
    ref.add(Position(t=[0.0, 10.0], value=[0.0, 10.0]), AverageVelocity(t0=0.0, t1=5.0, value=1.0))
    np.testing.assert_allclose(sol.position(), ref.solve(solver="direct").position(), atol=1e-9)
    assert abs(sol.position()[250, 0] - 5.0) < 1e-9


@pytest.mark.parametrize("with_bias", [False, True])
def test_ldl_and_lu_factorizations_agree(with_bias):
    """QDLDL on the regularized quasi-definite matrix, refined against the exact one, gives
    the pivoted LU's answer; error-model columns are eliminated the same way for both."""
    from bvpnav.error_models import Bias

    prob, _ = table1_problem(3001)
    if with_bias:
        prob = bvpnav.NavigationProblem(prob.data, error_model=Bias())
        prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0]), Velocity(t=[0.0, 10.0], value=[0.0, 0.0]))
    a = prob.solve(solver="direct", lam=1.3, options={"method": "ldl"}, fallback=None)
    b = prob.solve(solver="direct", lam=1.3, options={"method": "lu"}, fallback=None)
    assert a.stats["factorization"] == "ldl" and b.stats["factorization"] == "lu"
    assert a.stats["verified"] and b.stats["verified"]
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-9 * np.max(np.abs(b.x)))


def test_auto_factorization_follows_the_residual_form_and_ldl_stalls_are_caught():
    acc, _ = table1_problem(2001)
    load, _ = table1_problem(2001, residual="load")
    assert acc.solve(solver="direct").stats["factorization"].startswith("banded (kl=")
    assert load.solve(solver="direct").stats["factorization"] == "lu"
    # forcing LDL on the load form (condition ~ N^4): refinement stalls and the LU takes over
    forced = load.solve(solver="direct", options={"method": "ldl"}, fallback=None)
    assert forced.stats["factorization"].startswith("lu (ldl refinement stalled")
    assert forced.stats["verification"]["forward_error"] < 1e-8


def test_ldl_handles_redundant_hard_rows():
    """The same position given twice as hard: LU needs its shift, the regularized LDL not."""
    prob, _ = table1_problem(1001)
    prob.add(Position(t=10.0, value=10.0, name="again"))
    a = prob.solve(solver="direct", options={"method": "ldl"}, fallback=None)
    b = prob.solve(solver="direct", options={"method": "lu"}, fallback=None)
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-9 * np.max(np.abs(b.x)))


def test_one_refinement_step_is_the_forward_error_estimate():
    """Verification takes the direct back end's one refinement step (the first solve's
    error) as the forward-error estimate: it bounds the answer's actual error (against the
    KKT reference refined six times; measured 4.9e-12 against 3.1e-13). A record that
    misses the preset's bound, or that is of another array, gets a fresh step instead."""
    from bvpnav.backends import resolve_solver, solver_options
    from bvpnav.linalg.lsq import FORWARD_RTOL, Factored, forward_error
    from bvpnav.solve.verify import verify

    prob, _ = table1_problem(2001)
    sol = prob.solve(solver="direct", lam=0.7, fallback=None)
    ref = kkt_reference(prob, 0.7, refinements=6)
    ver = sol.stats["verification"]
    assert sol.stats["refinements"] == 1 and ver["forward_error"] == sol.stats["correction"]
    actual = np.max(np.abs(sol.x - ref)) / np.max(np.abs(ref))
    assert actual < ver["forward_error"] < 1e-10

    be = resolve_solver("direct")
    form = prob.formulation
    raw = be.run(form, 0.7, solver_options(be, "default"))
    x, corr = raw.factored.refined
    assert x is raw.x and corr == raw.info["correction"]
    fresh = forward_error(form, raw.x, 0.7, raw.duals, Factored(*raw.factored[:2]))
    assert 0.0 < fresh < 1e-10 and fresh != corr
    missed = Factored(*raw.factored[:2], (raw.x, 2.0 * FORWARD_RTOL["default"]))
    other = Factored(*raw.factored[:2], (raw.x.copy(), corr))
    for factored in (missed, other):
        check = verify(form, raw.x, 0.7, "default", raw.duals, factored)
        assert check.forward_error == fresh and check.verified
    assert verify(form, raw.x, 0.7, "default", raw.duals, raw.factored).forward_error == corr


@pytest.mark.parametrize("axes, error_model", [(1, False), (3, True)])
def test_equality_rows_are_written_once_with_the_fem_rows_a_view_of_their_top(axes, error_model):
    """The least-squares form's equality rows are the FEM rows with the hard items' rows
    below them, entry for entry as stacking them would give, canonical, labelled; the
    model's FEM rows made with them are a view of their first rows (no second copy), and
    a model whose FEM rows exist already stacks them (the same matrix)."""
    import scipy.sparse as sp

    from bvpnav.error_models import Bias, ScaleFactor
    from bvpnav.linalg.lsq import least_squares_form

    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 5.0, 201)
    acc = rng.normal(size=(t.size, axes))

    def problem():
        prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc if axes > 1 else acc[:, 0]),
                                        error_model=ScaleFactor() + Bias() if error_model else None)
        prob.add(Position(t=[0.0, 5.0], value=np.zeros((2, axes)) if axes > 1 else [0.0, 0.0]))
        prob.add(Position(t=np.arange(0.5, 5.0, 0.5), value=rng.normal(size=(9, axes)) if axes > 1
                          else rng.normal(size=9), sigma=1.0))
        prob.add(Velocity(t=[0.0, 5.0], value=np.zeros((2, axes)) if axes > 1 else [0.0, 0.0], sigma=0.1))
        prob.add(Velocity(t=2.5, value=np.zeros(axes) if axes > 1 else 0.0))
        return prob.formulation

    form = problem()
    E = least_squares_form(form, 1.0).E
    fem = form.model.fem_rows()
    items = [t_.residual for t_ in form.terms() if t_.least_squares_role(False) == "E"]
    want = sp.vstack([fem.A] + [it.A for it in items], format="csr")
    assert E.A.has_canonical_format and E.m == fem.m + sum(it.m for it in items)
    np.testing.assert_array_equal(E.A.toarray(), want.toarray())
    np.testing.assert_array_equal(E.c, np.concatenate([fem.c] + [it.c for it in items]))
    assert list(E.labels) == list(fem.labels) + [lab for it in items for lab in it.labels]
    assert np.shares_memory(fem.A.data, E.A.data) and np.shares_memory(fem.A.indices, E.A.indices)
    # FEM rows made before: stacked, the same rows
    other = problem()
    other.model.fem_rows()
    E2 = least_squares_form(other, 1.0).E
    assert not np.shares_memory(other.model.fem_rows().A.data, E2.A.data)
    np.testing.assert_array_equal(E2.A.toarray(), E.A.toarray())
    np.testing.assert_array_equal(E2.c, E.c)
