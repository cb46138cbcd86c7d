"""The direct back end's interior-point path (bvpnav.linalg.ipm): band and inequality rows
solved by Mehrotra steps, each one banded factorization, checked against Clarabel, against
hand-computed optima and for the paths around it (inactive rows, infeasible rows, the
least-squares path left as it was)."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import quintic, table1_problem

import bvpnav
from bvpnav.constraints import AverageVelocity, HalfSpace, Position, PositionBound, Velocity, ZeroVelocity
from bvpnav.error_models import Bias
from bvpnav.linalg.ipm import quadratic_form

T = np.linspace(0.0, 10.0, 101)
#: The interior-point method itself (the default tries the active set first,
#: tests/backends/test_direct_active_set.py).
IPM = {"qp": "interior point"}


def line_problem(*extra, end=10.0):
    """1-D, zero acceleration, r(0) = 0 hard, r(10 s) = ``end`` soft (sigma 1 m)."""
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=np.zeros_like(T)))
    return prob.add(Position(t=0.0, value=0.0, name="start"),
                    Position(t=10.0, value=end, sigma=1.0, name="fix"), *extra)


def velocity_band(n=401, noise=0.0, tol=0.05, seed=3):
    """The 2011 paper's biased quintic with a velocity band at every sample around the true
    velocity (plus ``noise``, m/s): the unmodelled bias drives the path against the band."""
    _, v, _ = quintic()
    prob, _ = table1_problem(n)
    t = prob.data.t
    vm = v(t) + np.random.default_rng(seed).normal(0.0, noise, t.size) if noise else v(t)
    return prob.add(Velocity(t=t, value=vm, mode="band", tol=tol, name="vel"))


def bias_stances(n=401):
    """A bias only the stances' zero-velocity bands reveal (the first factorization, without
    them, is singular), an error-model parameter in the border of the band."""
    t = np.linspace(0.0, 20.0, n)
    acc = np.where((t > 5.0) & (t < 15.0), np.sin(t), 0.0) + 0.05
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), error_model=Bias())
    return prob.add(Position(t=0.0, value=0.0), Position(t=20.0, value=1.0, sigma=0.1),
                    ZeroVelocity(t0=0.0, t1=5.0, mode="band", tol=0.01, name="still 1"),
                    ZeroVelocity(t0=15.0, t1=20.0, mode="band", tol=0.01, name="still 2"))


def plane_problem(*extra):
    """2-D (x, z), zero acceleration, start at the origin (hard), end wanted at (30, 0) m."""
    t = np.linspace(0.0, 10.0, 101)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.zeros((t.size, 2)), axes=("x", "z")))
    return prob.add(Position(t=0.0, value=[[0.0, 0.0]], name="start"),
                    Position(t=10.0, value=[[30.0, 0.0]], sigma=1.0, name="end"), *extra)


CASES = {
    "active bound": lambda: line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap")),
    "band bound": lambda: line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, mode="band", tol=0.5,
                                                    name="cap")),
    "velocity band, few active": lambda: velocity_band(),
    "velocity band, many active": lambda: velocity_band(noise=0.05),
    "loose velocity band": lambda: velocity_band(tol=0.5),
    "half space": lambda: plane_problem(HalfSpace(axes=("x", "z"), normal=[0.3, -1.0], b=5.0, name="ground")),
    "bias and zero-velocity bands": bias_stances,
    # a band on a row that reaches far (its multiplier in the border of the band): at least
    # 0.725 m/s over [2, 8] s where the truth averages 0.7056 m/s, the velocity band's room
    # (+-0.05 m/s) used to make up for it outside (the ends are hard)
    "average-velocity band": lambda: velocity_band(tol=0.05).add(
        AverageVelocity(t0=2.0, t1=8.0, value=0.735, mode="band", tol=0.01, name="average")),
}


def objective(prob, x) -> float:
    """``||A x + c||^2``: the weighted squares the solvers minimise (lam = 1)."""
    return float(np.sum(quadratic_form(prob.formulation, 1.0).ls.D.value(x) ** 2))


def active_rows(prob, x) -> int:
    """Inequality rows (a band's two sides each) within 1e-7 of their bound."""
    G = quadratic_form(prob.formulation, 1.0).G
    return int(np.sum(G.value(x) > -1e-7 * np.max(G.row_scale(x))))


@pytest.mark.parametrize("case", list(CASES))
def test_matches_clarabel_on_objective_and_solution(case):
    prob = CASES[case]()
    d = prob.solve(solver="direct", lam=1.0, accuracy="high", fallback=None, options=IPM)
    c = prob.solve(solver="clarabel", lam=1.0, accuracy="high", fallback=None)
    assert d.stats["solver"] == "direct" and d.stats["verified"]
    assert d.stats["factorization"].startswith("interior point on banded (")
    fd, fc = objective(prob, d.x), objective(prob, c.x)
    assert abs(fd - fc) <= 1e-6 * fc
    assert np.max(np.abs(d.x - c.x)) <= 1e-6 * np.max(np.abs(c.x))
    assert active_rows(prob, c.x) >= 1   # every case presses against its rows somewhere
    # the direct answer's duals make the Lagrangian stationary (verification recomputes it)
    assert d.stats["verification"]["stationarity"] < 1e-9


def test_active_at_many_samples():
    prob = velocity_band(noise=0.05)
    sol = prob.solve(solver="direct", lam=1.0, fallback=None, options=IPM)
    n_active = active_rows(prob, sol.x)
    assert n_active >= 100   # of 802 band sides
    assert sol.stats["verification"]["max_violation"] < 1e-9
    # more rows are pressed than a conic solver needs iterations: no active-set method's pace
    assert sol.stats["iterations"] < 60


def test_hand_computed_line_against_a_bound():
    # objective (r(10) - 10)^2 subject to r <= 8 on [9, 10] s: r(t) = 0.8 t (and r = 8.5 t / 10
    # with a band of 0.5 m), the first factorization (without the bound) reaching 10 m
    for kw, end in (({}, 8.0), ({"mode": "band", "tol": 0.5}, 8.5)):
        sol = line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap", **kw)).solve(
            solver="direct", fallback=None)
        np.testing.assert_allclose(sol.trajectory["x"].to_numpy(), end * T / 10, rtol=0, atol=1e-9)
        assert sol.stats["iterations"] >= 1


def test_inactive_rows_cost_one_factorization_and_give_the_least_squares_answer():
    prob = line_problem(PositionBound(upper=20.0, name="cap"))
    sol = prob.solve(solver="direct", fallback=None)
    plain = line_problem().solve(solver="direct", fallback=None)
    assert sol.stats["iterations"] == 0 and sol.stats["verified"]
    np.testing.assert_allclose(sol.x, plain.x, rtol=0, atol=1e-12 * np.max(np.abs(plain.x)))


def test_least_squares_problems_keep_the_plain_path():
    prob, _ = table1_problem(801)
    sol = prob.solve(solver="direct", lam=2.0, fallback=None)
    assert sol.stats["factorization"].startswith("banded (")   # not the interior-point path
    assert "interior point" not in sol.stats["factorization"]


def test_pivoted_lu_steps_agree_with_banded_steps():
    prob = velocity_band(n=201)
    b = prob.solve(solver="direct", lam=1.0, accuracy="high", fallback=None, options=IPM)
    u = prob.solve(solver="direct", lam=1.0, accuracy="high", fallback=None, options={"method": "lu", **IPM})
    assert u.stats["factorization"] == "interior point on lu" and u.stats["verified"]
    np.testing.assert_allclose(u.x, b.x, rtol=0, atol=1e-7 * np.max(np.abs(b.x)))


def test_infeasible_rows_take_the_certified_path():
    """r(10 s) = 10 m hard against r <= 9 m everywhere: direct stalls and says so; in the
    default chain Clarabel then proves the conflict and names both items."""
    prob = line_problem(Position(t=10.0, value=10.0, name="pinned"), PositionBound(upper=9.0, name="cap"))
    with pytest.raises(bvpnav.SolveError, match=r"direct: the interior-point method stopped.*clarabel"):
        prob.solve(solver="direct", fallback=None)
    with pytest.raises(bvpnav.Infeasible) as exc:
        prob.solve(solver="direct")
    msg = str(exc.value)
    assert "'pinned'" in msg and "'cap'" in msg
    assert exc.value.attempts[0]["solver"] == "direct" and exc.value.attempts[0]["status"] == "not converged"


@pytest.mark.parametrize("kw,mode", [({"mode": "robust", "sigma": 0.1}, "robust")])
def test_penalised_inequalities_are_refused_by_name(kw, mode):
    """Robust inequalities (an L1 penalty) are refused; soft ones are solved
    (tests/backends/test_direct_soft_edges.py)."""
    prob = line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap", **kw))
    with pytest.raises(bvpnav.InputError, match=rf"'direct' cannot take item 'cap' \(kind 'inequality', "
                                                rf"mode '{mode}'\).*clarabel"):
        prob.solve(solver="direct", fallback=None)


def test_a_lambda_sweep_over_a_band_problem_reads_direct_answers():
    """The sweep of a problem with bands (the cvxpy engine's, which calls the chosen back
    end at each lambda) measures the penalties at direct's answers, not at cvxpy's last
    variable values (NaN before: no cvxpy solver had run)."""
    _, v, _ = quintic()
    prob, _ = table1_problem(201)
    t = prob.data.t
    prob.add(Velocity(t=t[::20], value=v(t[::20]), mode="band", tol=0.05, name="vel"))
    d = bvpnav.lambda_curve(prob, lam_range=(1e-2, 1e2), points=7, solver="direct")
    c = bvpnav.lambda_curve(prob, lam_range=(1e-2, 1e2), points=7, solver="clarabel", accuracy="high")
    assert d.engine == "cvxpy" and np.all(np.isfinite(d.info_norm)) and np.all(d.info_norm > 0)
    np.testing.assert_allclose(d.info_norm, c.info_norm, rtol=1e-6)
    np.testing.assert_allclose(d.residual_norm, c.residual_norm, rtol=1e-6)
