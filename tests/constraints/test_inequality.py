"""Inequality information: position bounds, half-spaces and speed limits (cones).

Most cases have closed-form optima: with zero measured acceleration, one hard start
position and soft information only about the end (or about every node velocity), the
straight line with zero acceleration residual reaches the best end point the inequality
allows at no data cost, so the optimum is that line and the inequality's effect is a
projection computed by hand.
"""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import conflict_problem

import bvpnav
from bvpnav.constraints import HalfSpace, Position, PositionBound, SpeedLimit, Velocity

T = np.linspace(0.0, 10.0, 101)  # h = 0.1 s


def line_problem(*extra, end=10.0):
    """1-D, zero acceleration, r(0) = 0 hard, r(10 s) = ``end`` soft (sigma 1 m)."""
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=np.zeros_like(T)))
    return prob.add(Position(t=0.0, value=0.0, name="start"),
                    Position(t=10.0, value=end, sigma=1.0, name="fix"), *extra)


def x_of(sol) -> np.ndarray:
    return sol.trajectory["x"].to_numpy()


def duals(prob, label: str) -> np.ndarray:
    """The inequality multipliers of an item after a cvxpy solve (cvxpy convention: >= 0)."""
    return np.asarray(prob.build()["cons"][label][0].dual_value, dtype=float)


# ------------------------------------------------------------------ (a) bounds
def test_active_upper_bound_gives_the_hand_computed_line_and_multiplier():
    # objective lam (r(10) - 10)^2 subject to r(10) <= 8: r(t) = 0.8 t; multiplier
    # y = -d/du of the optimum (u - 10)^2 at u = 8, i.e. 2 (10 - 8) = 4
    prob = line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap"))
    sol = prob.solve()
    np.testing.assert_allclose(x_of(sol), 0.8 * T, atol=1e-7)
    y = duals(prob, "cap")  # rows at the nodes 9.0, 9.1, ..., 10.0
    assert y[-1] == pytest.approx(4.0, abs=1e-6)
    assert np.max(np.abs(y[:-1])) < 1e-8
    assert sol.stats["verification"]["stationarity"] < 1e-9
    # the same answer as the hard equality r(10) = 8, solved without cvxpy
    eq = line_problem(Position(t=10.0, value=8.0, name="pinned")).solve(solver="direct")
    assert np.max(np.abs(x_of(eq) - x_of(sol))) < 1e-6
    # inactive (the unconstrained end 10 m is below 20 m): the line r = t, no multiplier
    free = line_problem(PositionBound(upper=20.0, t0=9.0, t1=10.0, name="cap"))
    np.testing.assert_allclose(x_of(free.solve()), T, atol=1e-7)
    assert np.max(np.abs(duals(free, "cap"))) < 1e-8


def test_lower_bound_pushes_up():
    # wanting r(10) = -5 above a floor of -2 over the whole window: r(t) = -0.2 t, y = 6
    prob = line_problem(PositionBound(lower=-2.0, name="floor"), end=-5.0)
    sol = prob.solve()
    np.testing.assert_allclose(x_of(sol), -0.2 * T, atol=1e-7)
    y = duals(prob, "floor")
    assert y[-1] == pytest.approx(6.0, abs=1e-6) and np.max(np.abs(y[:-1])) < 1e-8


def bump_problem(*extra):
    """r'' = a with r = 4 sin(pi t / 10) m, both ends hard at 0: an arch of height 4 m."""
    acc = -((np.pi / 10) ** 2) * 4.0 * np.sin(np.pi * T / 10)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=acc))
    return prob.add(Position(t=[0.0, 10.0], value=0.0, name="ends"), *extra)


@pytest.mark.parametrize("solver", ["clarabel", "osqp"])
def test_active_ceiling_equals_the_equality_problem_on_its_active_set(solver):
    free = bump_problem().solve(solver="direct")
    assert x_of(free)[50] == pytest.approx(4.0, abs=1e-3)  # FEM arch: 3.99967 m at t = 5 s
    prob = bump_problem(PositionBound(upper=3.0, t0=4.0, t1=6.0, name="ceiling"))
    sol = prob.solve(solver=solver)
    g = sol.item_residuals["ceiling"]  # r(t_k) - 3 at the 21 nodes of [4, 6] s
    y = duals(prob, "ceiling")
    active = (g > -1e-6) & (y > 1e-3 * y.max())
    ts = prob.items[1].check_times(prob.model)
    np.testing.assert_array_equal(ts[active], [5.0])  # the arch touches the ceiling at its top
    assert x_of(sol)[50] == pytest.approx(3.0, abs=1e-7)
    # pushes the right way: nowhere above the free arch, 1 m lower at the top
    assert np.all(x_of(sol) <= x_of(free) + 1e-9)
    # KKT: the inequality problem's optimum is the equality problem's on the active set,
    # with the same (non-negative) multiplier
    pinned = bump_problem(Position(t=ts[active], value=3.0, name="pinned"))
    eq = pinned.solve(solver="direct")
    assert np.max(np.abs(x_of(eq) - x_of(sol))) < 1e-6
    pinned.solve(solver="clarabel")
    y_eq = float(duals(pinned, "pinned")[0])
    assert y[active][0] > 0 and y[active][0] == pytest.approx(y_eq, rel=1e-5)
    # an inactive ceiling leaves the free arch unchanged
    high = bump_problem(PositionBound(upper=10.0, t0=4.0, t1=6.0, name="ceiling")).solve(solver=solver)
    assert np.max(np.abs(x_of(high) - x_of(free))) < 1e-6


def test_profile_bound_is_enforced_between_nodes_at_its_breakpoints():
    # a lower profile with a breakpoint at 9.95 s (between nodes): the bound holds there
    item = PositionBound(lower=[-1.0, 9.5, -1.0], lower_t=[9.0, 9.95, 10.0], t0=9.0, t1=10.0, name="spike")
    prob = line_problem(item, end=0.0)
    ts = item.check_times(prob.model)
    assert 9.95 in ts and ts.size == 12
    sol = prob.solve()
    r = np.interp(9.95, T, x_of(sol))
    assert r == pytest.approx(9.5, abs=1e-6)


def test_profile_must_cover_the_interval_and_be_consistent():
    prob = line_problem(PositionBound(lower=[0.0, 1.0], lower_t=[2.0, 10.0], name="short"))
    with pytest.raises(bvpnav.InputError, match=r"short.*covers \[2, 10\] s.*\[0, 10\] s"):
        prob.solve()
    with pytest.raises(bvpnav.InputError, match="bad.*give lower= and/or upper="):
        PositionBound(name="bad")
    with pytest.raises(bvpnav.InputError, match="crossed.*exceeds upper bound"):
        line_problem(PositionBound(lower=2.0, upper=1.0, name="crossed")).solve()
    with pytest.raises(bvpnav.InputError, match="late.*outside the recording window"):
        line_problem(PositionBound(upper=1.0, t0=5.0, t1=12.0, name="late")).solve()


# ------------------------------------------------------------------ (c) half-space
def plane_problem(item):
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=np.zeros((T.size, 2)), axes=("x", "z")))
    return prob.add(Position(t=0.0, value=[0.0, 0.0], name="start"),
                    Position(t=10.0, value=[30.0, 0.0], sigma=1.0, name="fix"), item)


def test_half_space_projects_the_end_point_onto_the_ground_plane():
    # z >= 0.3 x - 5  <=>  (0.3, -1) . (x, z) <= 5; the wanted end (30, 0) has n.q = 9 > 5:
    # the optimum end is its projection q - (n.q - b) n / |n|^2
    n, b, q = np.array([0.3, -1.0]), 5.0, np.array([30.0, 0.0])
    p = q - (n @ q - b) / (n @ n) * n  # (28.8991, 3.6697) m
    sol = plane_problem(HalfSpace(axes=("x", "z"), normal=n, b=b, name="ground")).solve()
    tr = sol.trajectory
    np.testing.assert_allclose([tr["x"].iloc[-1], tr["z"].iloc[-1]], p, atol=1e-6)
    np.testing.assert_allclose(tr["x"], p[0] * T / 10, atol=1e-6)  # still a straight line
    np.testing.assert_allclose(tr["z"], p[1] * T / 10, atol=1e-6)
    assert np.max(0.3 * tr["x"] - tr["z"]) <= 5.0 + 1e-7
    free = plane_problem(HalfSpace(axes=("x", "z"), normal=n, b=20.0, name="ground")).solve()
    np.testing.assert_allclose([free.trajectory["x"].iloc[-1], free.trajectory["z"].iloc[-1]], q, atol=1e-6)


# ------------------------------------------------------------------ (b) speed
def speed_problem(limit):
    """2-D, zero acceleration, start hard at 0, every node velocity soft at 12 m/s (sigma 1)
    at 30 degrees."""
    theta = np.deg2rad(30.0)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=np.zeros((T.size, 2))))
    return prob.add(Position(t=0.0, value=[0.0, 0.0], name="start"),
                    Velocity(t=T, value=[12 * np.cos(theta), 12 * np.sin(theta)], sigma=1.0,
                             name="ask 12"), limit)


def speeds(sol) -> tuple[np.ndarray, np.ndarray]:
    v = sol.trajectory[["vx", "vy"]].to_numpy()
    return np.hypot(v[:, 0], v[:, 1]), np.arctan2(v[:, 1], v[:, 0])


@pytest.mark.parametrize("solver", ["clarabel", "scs"])
def test_speed_limit_caps_the_speed_and_keeps_the_direction(solver):
    # each node wants 12 m/s at 30 degrees; the nearest point of the 10 m/s ball is
    # 10 m/s at 30 degrees, and the constant velocity reaches it at every node at once
    sol = speed_problem(SpeedLimit(v_max=10.0, name="limit")).solve(solver=solver)
    s, ang = speeds(sol)
    assert s.max() <= 10.0 + 1e-6 and s.max() == pytest.approx(10.0, abs=1e-6)
    np.testing.assert_allclose(s, 10.0, atol=1e-6)
    np.testing.assert_allclose(ang, np.deg2rad(30.0), atol=1e-7)
    end = sol.trajectory[["x", "y"]].iloc[-1].to_numpy()
    np.testing.assert_allclose(end, 100.0 * np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)]), atol=1e-5)
    row = sol.items.set_index("item").loc["limit"]
    assert row["kind"] == "cone" and row["rows"] == 101 * 3 and row["max_abs"] < 1e-6
    assert sol.stats["verification"]["stationarity"] < 1e-6  # cone duals enter the KKT check


def test_clarabel_and_scs_agree_on_the_speed_limit():
    a = speed_problem(SpeedLimit(v_max=10.0, name="limit")).solve(solver="clarabel")
    b = speed_problem(SpeedLimit(v_max=10.0, name="limit")).solve(solver="scs")
    diff = (a.trajectory - b.trajectory).abs().to_numpy().max()
    assert diff < 1e-5


def test_speed_limit_on_an_interval_leaves_the_rest_free():
    sol = speed_problem(SpeedLimit(v_max=10.0, t0=0.0, t1=5.0, name="limit")).solve()
    s, _ = speeds(sol)
    assert np.all(s[T <= 5.0] <= 10.0 + 1e-6)
    assert s[-1] > 11.0  # after 5 s the velocities drift back towards 12 m/s


# ------------------------------------------------------------------ (d) conflicts
def test_bound_conflicting_with_a_hard_position_is_named():
    prob = conflict_problem(Position(t=5.0, value=5.0, name="fix"),
                            PositionBound(upper=3.0, t0=4.0, t1=6.0, name="ceiling"))
    with pytest.raises(bvpnav.Infeasible) as exc:
        prob.solve()
    assert "These hard items conflict: ['fix', 'ceiling']" in str(exc.value)


def test_speed_limit_conflicting_with_a_hard_velocity_is_named():
    prob = conflict_problem(Velocity(t=5.0, value=5.0, name="fast"), SpeedLimit(v_max=3.0, name="lim"))
    with pytest.raises(bvpnav.Infeasible) as exc:
        prob.solve()
    assert "These hard items conflict: ['fast', 'lim']" in str(exc.value)


# ------------------------------------------------------------------ (e) solvers
def test_osqp_refuses_a_cone_before_solving_and_names_it():
    prob = speed_problem(SpeedLimit(v_max=10.0, name="limit"))
    with pytest.raises(bvpnav.InputError, match=r"'osqp' cannot take item 'limit'.*clarabel.*scs"):
        prob.solve(solver="osqp")
    assert prob.build()["problem"].status is None  # nothing was solved


@pytest.mark.parametrize("solver", ["direct", "csne"])
def test_direct_back_ends_refuse_what_they_cannot_take_by_name(solver):
    """csne refuses inequalities; direct takes them (its interior-point path) but refuses
    cones, naming the item and the solvers that take it."""
    if solver == "csne":
        with pytest.raises(bvpnav.InputError, match=rf"'{solver}' cannot take item 'cap'.*inequality"):
            line_problem(PositionBound(upper=8.0, name="cap")).solve(solver=solver)
    else:
        sol = line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap")).solve(solver=solver)
        np.testing.assert_allclose(x_of(sol), 0.8 * T, atol=1e-7)
    with pytest.raises(bvpnav.InputError, match=rf"'{solver}' cannot take item 'limit'.*cone.*clarabel"):
        speed_problem(SpeedLimit(v_max=10.0, name="limit")).solve(solver=solver)


def test_osqp_solves_a_position_bound_like_clarabel():
    sol = line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap")).solve(solver="osqp")
    np.testing.assert_allclose(x_of(sol), 0.8 * T, atol=1e-6)


def test_fallback_to_a_back_end_that_cannot_take_the_cone_says_so():
    prob = speed_problem(SpeedLimit(v_max=10.0, name="limit"))
    with pytest.raises(bvpnav.SolveError) as exc:  # SCS stopped after 2 iterations fails verification
        prob.solve(solver="scs", options={"max_iters": 2}, fallback=["direct"])
    msg = str(exc.value)
    assert "direct: not applicable" in msg and "cannot take item 'limit'" in msg


# ------------------------------------------------------------------ (f) modes
@pytest.mark.parametrize("kw,end", [
    # soft: min (r - 10)^2 + (r - 8)_+^2 / s^2  ->  r = (10 + 8/s^2) / (1 + 1/s^2)
    ({"sigma": 0.1}, (10 + 8 / 0.01) / (1 + 1 / 0.01)),
    ({"sigma": 0.01}, (10 + 8 / 1e-4) / (1 + 1 / 1e-4)),
    # robust: min (r - 10)^2 + (r - 8)_+ / s is exact (r = 8) when 1/s >= 2 (10 - 8)
    ({"mode": "robust", "sigma": 0.1}, 8.0),
    # band: r <= 8 + tol
    ({"mode": "band", "tol": 0.5}, 8.5),
])
def test_bound_modes(kw, end):
    sol = line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap", **kw)).solve()
    np.testing.assert_allclose(x_of(sol), end * T / 10, atol=1e-6)


@pytest.mark.parametrize("kw,speed", [
    ({"sigma": 0.1}, (12 + 10 / 0.01) / (1 + 1 / 0.01)),  # 10.0198 m/s
    ({"mode": "robust", "sigma": 0.1}, 10.0),             # exact penalty: 1/s >= 2 (12 - 10)
    ({"mode": "robust", "sigma": 0.5}, 11.0),             # 2 (u - 12) + 1/s = 0
    ({"mode": "band", "tol": 0.5}, 10.5),
])
def test_speed_limit_modes(kw, speed):
    sol = speed_problem(SpeedLimit(v_max=10.0, name="limit", **kw)).solve()
    s, ang = speeds(sol)
    np.testing.assert_allclose(s, speed, atol=1e-6)
    np.testing.assert_allclose(ang, np.deg2rad(30.0), atol=1e-7)


def test_half_space_soft_mode_allows_a_violation_of_order_sigma_squared():
    # soft: min |p - q|^2 + (n.p - b)_+^2 / s^2 moves p along n: the violation is
    # (n.q - b) s^2 / (s^2 + |n|^2)
    n, b, q, s = np.array([0.3, -1.0]), 5.0, np.array([30.0, 0.0]), 0.1
    sol = plane_problem(HalfSpace(axes=("x", "z"), normal=n, b=b, sigma=s, name="ground")).solve()
    p = sol.trajectory[["x", "z"]].iloc[-1].to_numpy()
    assert n @ p - b == pytest.approx((n @ q - b) * s**2 / (s**2 + n @ n), abs=1e-6)


# ------------------------------------------------------------------ describe
def test_describe_shows_inequalities_and_cones():
    text = speed_problem(SpeedLimit(v_max=10.0, name="limit")).describe(conditioning=False)
    assert "limit [hard, 303 rows]: |v(t_k)|_2 - 10 m/s <= 0" in text
    assert "second-order cone per node" in text and "101 cones" in text
    text = line_problem(PositionBound(upper=8.0, sigma=0.1, name="cap")).describe(conditioning=False)
    assert "pos(.)^2 of (r(t_k) - upper" in text
