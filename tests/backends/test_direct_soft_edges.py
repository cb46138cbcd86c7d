"""Soft inequalities and bands with soft edges (``mode="band"`` with ``sigma``) in the direct back
end: each penalty row is a row of the active set / interior-point KKT system whose multiplier
carries the constant diagonal ``sigma^2 / lam`` (bvpnav.linalg.ipm.QuadraticForm.soft). Checked
against hand-computed optima, against Clarabel (the same convex problem through cvxpy), between
the active set and the interior-point method, and for the readers of a term's mode (describe,
uncertainty, validation)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _helpers import quintic, table1_problem

import bvpnav
from bvpnav.constraints import Position, PositionBound, SpeedLimit, Velocity

T = np.linspace(0.0, 10.0, 101)
METHODS = ({"qp": "active set"}, {"qp": "interior point"})


def line(*extra, end=10.0):
    """1-D, zero acceleration, r(0) = 0 hard, r(10 s) = ``end`` soft (sigma 1 m): every straight
    line r = v t has zero acceleration residual, so the optimum is a straight line."""
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=np.zeros_like(T)))
    return prob.add(Position(t=0.0, value=0.0, name="start"),
                    Position(t=10.0, value=end, sigma=1.0, name="fix"), *extra)


@pytest.mark.parametrize("opts", METHODS)
def test_band_with_soft_edges_at_one_instant_has_the_hand_computed_optimum(opts):
    """r(10) = x: the fix wants 10 m (sigma 1), the band 8 +- 0.5 m with soft edges of sigma 1 m:
    minimize (x - 10)^2 + max(|x - 8| - 0.5, 0)^2, x = (10 + 8.5) / 2 = 9.25 m."""
    prob = line(Position(t=10.0, value=8.0, mode="band", tol=0.5, sigma=1.0, name="edge"))
    sol = prob.solve(solver="direct", fallback=None, options=opts)
    assert sol.stats["verified"] and sol.stats["qp_method"] == opts["qp"]
    assert sol.position()[-1, 0] == pytest.approx(9.25, abs=1e-8)
    assert sol.item_residuals["edge"][0] == pytest.approx(1.25, abs=1e-8)


@pytest.mark.parametrize("opts", METHODS)
def test_inside_the_band_the_soft_edges_do_not_pull(opts):
    """The fix at 8.3 m lies inside 8 +- 0.5 m: the band adds nothing, x = 8.3 m exactly (a soft
    row of the same sigma would pull it to 8.15 m)."""
    prob = line(Position(t=10.0, value=8.0, mode="band", tol=0.5, sigma=1.0, name="edge"), end=8.3)
    sol = prob.solve(solver="direct", fallback=None, options=opts)
    assert sol.stats["verified"]
    assert sol.position()[-1, 0] == pytest.approx(8.3, abs=1e-9)


@pytest.mark.parametrize("opts", METHODS)
@pytest.mark.parametrize("kw", [{"mode": "soft", "sigma": 0.5}, {"mode": "band", "tol": 0.4, "sigma": 0.5}])
def test_soft_inequality_rows_over_a_second_match_clarabel(opts, kw):
    """A ceiling of 8 m over the last second (11 rows), soft or a band with soft edges: Clarabel's
    answer, and an end above the bound (a penalty, not a wall)."""
    prob = line(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap", **kw))
    sol = prob.solve(solver="direct", fallback=None, options=opts)
    ref = prob.solve(solver="clarabel", accuracy="high")
    assert sol.stats["verified"]
    np.testing.assert_allclose(sol.position(), ref.position(), atol=1e-6)
    assert sol.position()[-1, 0] > 8.0 + kw.get("tol", 0.0) + 0.1


def velocity_band(sigma: float, n: int = 401, tol: float = 0.05, noise: float = 0.05):
    """The 2011 paper's biased quintic with a velocity band at every sample around noisy
    velocities: many rows beyond the band."""
    _, v, _ = quintic()
    prob, _ = table1_problem(n)
    t = prob.data.t
    vm = v(t) + np.random.default_rng(3).normal(0.0, noise, t.size)
    return prob.add(Velocity(t=t, value=vm, mode="band", tol=tol, sigma=sigma, name="vel"))


def test_many_rows_beyond_the_edges_active_set_interior_point_and_clarabel_agree():
    prob = velocity_band(sigma=0.02)
    a = prob.solve(solver="direct", fallback=None, options={"qp": "active set"})
    b = prob.solve(solver="direct", fallback=None, options={"qp": "interior point"})
    c = prob.solve(solver="clarabel", accuracy="high")
    r = np.abs(a.item_residuals["vel"])
    assert np.sum(r > 0.05 * (1 + 1e-6)) >= 20 and np.sum(r < 0.05) >= 20     # both sides of the edge
    scale = np.max(np.abs(c.position()))
    for s in (a, b):
        assert s.stats["verified"]
        np.testing.assert_allclose(s.position(), c.position(), atol=1e-6 * scale)


def test_soft_edges_approach_the_hard_band_as_sigma_shrinks():
    """The answer tends to the hard band's as sigma shrinks, the gap like sigma^2 once sigma is
    small (measured: 3.64e-4 m at sigma 1e-3 m/s, 3.24e-5 m at 3e-4, a ratio of 11.2 for the
    11.1 of sigma^2)."""
    hard = velocity_band(sigma=None).solve(solver="direct", fallback=None)
    gaps = []
    for sigma in (1e-3, 3e-4):
        soft = velocity_band(sigma=sigma).solve(solver="direct", fallback=None)
        gaps.append(float(np.max(np.abs(soft.position() - hard.position()))))
    assert gaps[0] / gaps[1] > 11.1 / 1.5


def test_the_soft_edges_curvature_is_a_soft_rows_in_the_uncertainty():
    """Beyond the band the penalty's curvature is a soft row's of the same sigma: the standard
    deviation of r(10 s) equals the problem's with a soft position of sigma 1 m (1/sqrt(2) m
    with the fix's sigma 1 m)."""
    edge = line(Position(t=10.0, value=8.0, mode="band", tol=0.5, sigma=1.0, name="edge"))
    soft = line(Position(t=10.0, value=8.5, sigma=1.0, name="edge"))
    se = edge.solve(solver="direct", uncertainty=True).trajectory["x_std"].iloc[-1]
    ss = soft.solve(solver="direct", uncertainty=True).trajectory["x_std"].iloc[-1]
    assert se == pytest.approx(ss, rel=1e-6)
    assert se == pytest.approx(np.sqrt(0.5), rel=1e-3)


def test_describe_writes_the_soft_edges():
    prob = line(Position(t=10.0, value=8.0, mode="band", tol=0.5, sigma=1.0, name="edge"))
    text = prob.describe()
    assert "pos(|.| - tol)^2" in text and "[edge, band, sigma = 1 m, tol = 0.5 m, 1 rows]" in text
    assert r"\max(|" in prob.describe(format="latex")


def test_a_cone_item_refuses_soft_edges_by_name():
    with pytest.raises(bvpnav.InputError, match=r"SpeedLimit.*soft edges.*cone"):
        SpeedLimit(v_max=20.0, t0=1.0, t1=9.0, mode="band", tol=0.1, sigma=0.1)


def test_the_variance_factor_reads_the_excess_beyond_the_band():
    """r(10) = 9.25 m: the fix's residual -0.75 m and the band's excess 0.75 m (not the raw
    1.25 m), each over sigma 1 m: 2 x 0.5625 on one degree of freedom (two rows, one unknown
    slope) = 1.125."""
    prob = line(Position(t=10.0, value=8.0, mode="band", tol=0.5, sigma=1.0, name="edge"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # one degree of freedom: the factor is judged, and may warn
        sol = prob.solve(solver="direct", uncertainty=True)
    assert sol.stats["uncertainty"]["variance_factor"] == pytest.approx(1.125, rel=1e-6)


def test_at_lam_zero_the_penalty_rows_are_not_in_the_problem():
    """lam = 0 weighs the items' penalties by 0: direct solves without them (their 1 / p would
    be infinite), as without the items."""
    def ends(*extra):   # the hard ends 0 and 10 m (lam weighs no hard row)
        prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=np.zeros_like(T)))
        return prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends"), *extra)

    cap = PositionBound(upper=8.0, t0=9.0, t1=10.0, mode="band", tol=0.2, sigma=0.5, name="cap")
    with_cap = ends(cap).solve(solver="direct", lam=0.0, fallback=None)
    without = ends().solve(solver="direct", lam=0.0, fallback=None)
    assert with_cap.stats["verified"]
    np.testing.assert_allclose(with_cap.position(), without.position(), atol=1e-9)


def test_normalized_residuals_of_soft_edges_are_the_excess_over_sigma():
    """A row inside its band has no penalty and is reported at 0, not at r / sigma; one beyond
    it at its excess over sigma."""
    from bvpnav.report import normalized_residuals

    prob = line(Position(t=10.0, value=8.0, mode="band", tol=0.5, sigma=1.0, name="edge"),
                Position(t=10.0, value=9.1, mode="band", tol=0.5, sigma=0.1, name="inside"))
    tab = normalized_residuals(prob.solve(solver="direct"))
    edge = tab[tab["item"] == "edge"].iloc[0]
    inside = tab[tab["item"] == "inside"].iloc[0]
    assert abs(edge["residual"]) > 0.5 and abs(inside["residual"]) < 0.5
    assert edge["normalized"] == pytest.approx(np.sign(edge["residual"]) * (abs(edge["residual"]) - 0.5))
    assert inside["normalized"] == 0.0
