"""The direct back end's active-set path (bvpnav.linalg.active_set): band and inequality rows
solved by updates of the rows held at their bounds, each one banded factorization; checked
against Clarabel, against hand-computed optima and multipliers, by the KKT conditions, and for
the warm start and the interior-point fallback."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import quintic, table1_problem

import bvpnav
from bvpnav.constraints import HalfSpace, Position, PositionBound, Velocity
from bvpnav.linalg import active_set as AS
from bvpnav.linalg.ipm import quadratic_form
from bvpnav.linalg.workspace import Workspace

T = np.linspace(0.0, 10.0, 101)
ACTIVE = {"qp": "active set"}


def line_problem(*extra):
    """1-D, zero acceleration, r(0) = 0 hard, r(10 s) = 10 m soft (sigma 1 m): without other
    rows the answer is r(t) = t with zero residual."""
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=np.zeros_like(T)))
    return prob.add(Position(t=0.0, value=0.0, name="start"),
                    Position(t=10.0, value=10.0, sigma=1.0, name="fix"), *extra)


def velocity_band(n=401, noise=0.0, tol=0.05, seed=3):
    """The biased quintic with a velocity band at every sample around the true velocity (plus
    ``noise``): the unmodelled bias presses the path against the band at some samples."""
    _, v, _ = quintic()
    prob, _ = table1_problem(n)
    t = prob.data.t
    vm = v(t) + np.random.default_rng(seed).normal(0.0, noise, t.size) if noise else v(t)
    return prob.add(Velocity(t=t, value=vm, mode="band", tol=tol, name="vel"))


def plane_problem():
    t = np.linspace(0.0, 10.0, 101)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.zeros((t.size, 2)), axes=("x", "z")))
    return prob.add(Position(t=0.0, value=[[0.0, 0.0]], name="start"),
                    Position(t=10.0, value=[[30.0, 0.0]], sigma=1.0, name="end"),
                    HalfSpace(axes=("x", "z"), normal=[0.3, -1.0], b=5.0, name="ground"))


def kkt(prob, x, duals):
    """Relative KKT residuals of the quadratic program at ``x`` with the back end's duals:
    (stationarity, equality residual, inequality violation, most negative multiplier,
    complementarity), each against the size of its terms; and the number of rows at their
    bounds with a positive multiplier."""
    qp = quadratic_form(prob.formulation, 1.0)
    ls, G = qp.ls, qp.G
    y = np.zeros(ls.E.m)
    for label, sl in ls.eq_blocks:
        y[sl] = duals[label] if label == "fem" else duals[label][0]
    z = np.zeros(G.m)
    for label, pieces in qp.ineq_blocks:
        for sl, zi in zip(pieces, duals[label], strict=True):
            z[sl] = np.asarray(zi) * qp.scale[sl]
    grad = 2.0 * (ls.D.A.T @ ls.D.value(x))
    Ey, Gz = ls.E.A.T @ y, G.A.T @ z
    dscale = max(np.max(np.abs(grad)), np.max(np.abs(Ey)), np.max(np.abs(Gz)))
    g = G.value(x)
    gscale = np.max(abs(G.A) @ np.abs(x)) + np.max(np.abs(G.c))
    escale = np.max(abs(ls.E.A) @ np.abs(x)) + np.max(np.abs(ls.E.c))
    zmax = max(np.max(z), 1e-300)
    return (np.max(np.abs(grad + Ey + Gz)) / dscale, np.max(np.abs(ls.E.value(x))) / escale,
            max(np.max(g), 0.0) / gscale, min(np.min(z), 0.0) / zmax,
            np.max(np.abs(z * g)) / (zmax * gscale), int(np.sum(z > 0.0)))


CASES = {
    # few rows at their bounds
    "one bound": (lambda: line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap")), 1, 1),
    "band bound": (lambda: line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, mode="band", tol=0.5,
                                                      name="cap")), 1, 1),
    "half space": (plane_problem, 1, 1),
    "velocity band, few active": (lambda: velocity_band(), 10, 40),
    # many (173 of 802 band sides, measured)
    "velocity band, many active": (lambda: velocity_band(noise=0.05), 100, 300),
}


@pytest.mark.parametrize("case", list(CASES))
def test_active_set_matches_clarabel_and_meets_kkt(case):
    make, lo, hi = CASES[case]
    prob = make()
    d = prob.solve(solver="direct", lam=1.0, accuracy="high", fallback=None, options=ACTIVE)
    c = prob.solve(solver="clarabel", lam=1.0, accuracy="high", fallback=None)
    assert d.stats["verified"] and d.stats["qp_method"] == "active set"
    assert d.stats["factorization"].startswith("active set on banded (")
    assert lo <= d.stats["active_rows"] <= hi
    np.testing.assert_allclose(d.x, c.x, rtol=0, atol=1e-8 * np.max(np.abs(c.x)))
    x, info = AS.solve_bands(prob.formulation, 1.0, tol=1e-10, qp_method="active set")
    np.testing.assert_array_equal(x, d.x)
    stat, eq, viol, neg, comp, pressed = kkt(prob, x, info["duals"])
    assert stat < 1e-12 and eq < 1e-12 and viol < 1e-10 and neg == 0.0 and comp < 1e-10
    assert pressed == info["active_rows"]


def test_default_takes_the_active_set_and_agrees_with_the_interior_point():
    prob = velocity_band(noise=0.05)
    a = prob.solve(solver="direct", lam=1.0, accuracy="high", fallback=None)
    i = prob.solve(solver="direct", lam=1.0, accuracy="high", fallback=None, options={"qp": "interior point"})
    assert a.stats["qp_method"] == "active set" and i.stats["qp_method"] == "interior point"
    assert i.stats["factorization"].startswith("interior point on banded (")
    np.testing.assert_allclose(a.x, i.x, rtol=0, atol=1e-8 * np.max(np.abs(i.x)))


@pytest.mark.parametrize("margin", [1e-6, -1e-6])
def test_row_at_the_bound_with_a_margin(margin):
    """A cap 1e-6 m above the unconstrained end (10 m at 10 s): inactive, the least-squares
    line, no update; 1e-6 m below it: the end held at the cap with multiplier 2e-6 on the last
    row (the gradient of (r(10) - 10)^2), every other multiplier 0, one update."""
    cap = 10.0 + margin
    prob = line_problem(PositionBound(upper=cap, t0=9.0, t1=10.0, name="cap"))
    sol = prob.solve(solver="direct", lam=1.0, accuracy="high", fallback=None, options=ACTIVE)
    end = min(cap, 10.0)
    np.testing.assert_allclose(sol.trajectory["x"].to_numpy(), end * T / 10.0, rtol=0, atol=1e-12)
    x, info = AS.solve_bands(prob.formulation, 1.0, tol=1e-10, qp_method="active set")
    np.testing.assert_array_equal(x, sol.x)
    z = info["duals"]["cap"][0]
    if margin > 0:
        assert sol.stats["iterations"] == 0 and sol.stats["active_rows"] == 0 and np.all(z == 0.0)
    else:
        assert sol.stats["iterations"] == 1 and sol.stats["active_rows"] == 1
        np.testing.assert_allclose(z[-1], 2e-6, rtol=1e-6)
        assert np.all(z[:-1] == 0.0)


def test_warm_start_from_the_last_rows_costs_no_update():
    prob = velocity_band(noise=0.05)
    form = prob.formulation
    ws = Workspace()
    x1, i1 = AS.solve_bands(form, 1.0, tol=1e-10, workspace=ws, qp_method="active set")
    assert i1["iterations"] >= 3 and not i1["warm_start"]
    ws2 = Workspace(active_hint=ws.active_hint)
    x2, i2 = AS.solve_bands(form, 1.0, tol=1e-10, workspace=ws2, qp_method="active set")
    assert i2["iterations"] == 0 and i2["warm_start"] and i2["active_rows"] == i1["active_rows"]
    np.testing.assert_allclose(x2, x1, rtol=0, atol=1e-10 * np.max(np.abs(x1)))
    # a hint for other rows is not used
    other = line_problem(PositionBound(upper=8.0, t0=9.0, t1=10.0, name="cap")).formulation
    _, i3 = AS.solve_bands(other, 1.0, tol=1e-10, workspace=Workspace(active_hint=ws.active_hint))
    assert not i3["warm_start"] and i3["qp_method"] == "active set"


def test_interior_point_takes_over_when_the_active_set_gives_way(monkeypatch):
    """Two updates are not enough for the many-active band (it needs about ten): the active
    set gives way, the interior-point method answers, says why, and the next solve with the
    same workspace hint goes straight to it."""
    monkeypatch.setattr(AS, "MAX_UPDATES", 2)
    prob = velocity_band(noise=0.05)
    c = prob.solve(solver="clarabel", lam=1.0, accuracy="high", fallback=None)
    ws = Workspace()
    x, info = AS.solve_bands(prob.formulation, 1.0, tol=1e-10, workspace=ws)
    assert info["qp_method"] == "interior point"
    assert "the active set gave way: no answer in 2 updates" in info["factorization"]
    np.testing.assert_allclose(x, c.x, rtol=0, atol=1e-6 * np.max(np.abs(c.x)))
    assert ws.active_hint.gave_way and ws.active_hint.active.sum() == info["active_rows"] >= 100
    again_ws = Workspace(active_hint=ws.active_hint)
    _, again = AS.solve_bands(prob.formulation, 1.0, tol=1e-10, workspace=again_ws)
    assert again["qp_method"] == "interior point" and again["active_set"].startswith("not tried")
    with pytest.raises(bvpnav.SolveError, match=r"active-set method gave way: no answer in 2 updates"):
        prob.solve(solver="direct", lam=1.0, fallback=None, options=ACTIVE)


def test_bad_qp_option_refused():
    with pytest.raises(bvpnav.InputError, match="qp"):
        line_problem().solve(solver="direct", options={"qp": "simplex"})


def test_attitude_loop_warm_starts_the_active_set():
    """Noise-free turning body (30 s at 20 Hz), a constant gyro bias and a wrong initial
    attitude (the model's own form), hard fixes every 2.5 s, and a velocity band of +-0.02 m/s
    around the true velocity (the solver's own discretization of it) at every second: at the
    wrong attitude of the first linearization the band presses (3 updates, measured), at the
    truth it does not. Each solve of the loop after the first of its kind starts from the rows
    of the last one (1, then 0 updates, measured); the answer is the truth to 1e-8 and equals
    the interior point's."""

    from scipy.spatial.transform import Rotation

    from bvpnav.attitude import integrate_gyro
    from bvpnav.error_models import AttitudeError, GyroBias

    g = np.array([0.0, 0.0, -9.80665])
    t = np.linspace(0.0, 30.0, 601)
    w = np.column_stack([0.05 * np.sin(0.5 * t), 0.04 * np.cos(0.3 * t), 0.2 * np.sin(0.1 * t) + 0.05])
    c0 = Rotation.from_euler("ZYX", [0.7, 0.02, -0.03])
    att = integrate_gyro(t, w, c0)
    a = np.column_stack([np.sin(0.2 * t), 0.5 * np.cos(0.15 * t), 0.1 * np.sin(0.3 * t)])
    f = att.inv().apply(a - g)
    # the truth in the solver's own discretization: the exact attitude, start position and velocity
    exact = bvpnav.NavigationProblem(bvpnav.ImuData(t, specific_force=f, attitude=att, gravity=g)).add(
        Position(t=0.0, value=[0.0, 0.0, 0.0]), Velocity(t=0.0, value=[1.0, 0.0, 0.0])).solve(solver="direct")
    pos, vel = exact.position().reshape(-1, 3), exact.velocity().reshape(-1, 3)
    bg = np.array([1e-3, -2e-3, 1.5e-3])
    guess = Rotation.from_rotvec([0.004, -0.003, 0.02]) * c0

    def solve(qp):
        data = ImuData_from_gyro(t, f, w + bg, guess, g)
        prob = bvpnav.NavigationProblem(data, error_model=GyroBias() + AttitudeError(), grade=None)
        k = np.arange(0, t.size, 50)
        s = np.arange(0, t.size, 20)
        prob.add(Position(t=t[k], value=pos[k]),
                 Velocity(t=t[s], value=vel[s], mode="band", tol=0.02, name="vel band"))
        return prob.solve(solver="direct", attitude={"tol": 1e-11, "heading": "given"},
                          options={"qp": qp}, accuracy="high")

    calls = []
    inner = AS.active_set

    def counted(*args, **kw):
        ans, why = inner(*args, **kw)
        calls.append((kw.get("start") is not None, None if ans is None else ans.updates))
        return ans, why

    AS.active_set = counted
    try:
        sol = solve("auto")
    finally:
        AS.active_set = inner
    ipm = solve("interior point")
    assert sol.stats["qp_method"] == "active set" and sol.stats["warm_start"]
    assert len(calls) >= 4 and all(c[1] is not None for c in calls)   # every solve by the active set
    assert all(warm for warm, _ in calls[2:])
    assert max(calls[0][1], calls[1][1]) >= 1   # the band pressed at the first linearizations
    est = np.array([sol.error_params[f"gyro_bias_{ax}"] for ax in "xyz"])
    np.testing.assert_allclose(est, bg, rtol=0, atol=1e-8)
    np.testing.assert_allclose(sol.position().reshape(-1, 3), pos, rtol=0, atol=1e-6)
    np.testing.assert_allclose(sol.x, ipm.x, rtol=0, atol=1e-8 * np.max(np.abs(ipm.x)))


def ImuData_from_gyro(t, f, w, guess, g):
    return bvpnav.ImuData.from_gyro(t, f, w, initial_attitude=guess, gravity=g)


def _noisy_state_drive(n_seconds=20.0, rate=20.0, seed=5):
    """A turning drive (the model's own discretization, constant biases) with noisy rates,
    forces and fixes: the node-state loop converges over several steps."""
    from scipy.spatial.transform import Rotation

    from bvpnav.attitude import step_rotation_vectors

    g = np.array([0.0, 0.0, -9.80665])
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, n_seconds, int(n_seconds * rate) + 1)
    h = np.diff(t)
    a = np.column_stack([0.8 * np.sin(0.3 * t), 0.6 * np.cos(0.2 * t), 0.2 * np.sin(0.5 * t)])
    w = 8.0 * np.column_stack([0.05 * np.sin(0.7 * t), 0.04 * np.cos(0.5 * t), 0.15 * np.sin(0.2 * t) + 0.05])
    bg, ba = np.array([1e-3, -5e-4, 2e-4]), np.array([0.05, -0.03, 0.02])
    phi = step_rotation_vectors(t, w + bg) - h[:, None] * bg
    C = [Rotation.from_euler("ZYX", [0.4, 0.02, -0.01])]
    for k in range(t.size - 1):
        C.append(C[-1] * Rotation.from_rotvec(phi[k]))
    C = Rotation.concatenate(C)
    f = C.inv().apply(a - g) + ba
    v, r = np.zeros((t.size, 3)), np.zeros((t.size, 3))
    v[0] = [10.0, 1.0, 0.0]
    for k in range(t.size - 1):
        v[k + 1] = v[k] + h[k] * (a[k] + a[k + 1]) / 2
        r[k + 1] = r[k] + h[k] * v[k] + h[k] ** 2 * (2 * a[k] + a[k + 1]) / 6
    data = bvpnav.ImuData.from_gyro(t, f + 2e-2 * rng.standard_normal(f.shape),
                                    w + bg + 2e-3 * rng.standard_normal(w.shape), initial_attitude=C[0],
                                    gravity=g)
    return t, data, r + 1e-2 * rng.standard_normal(r.shape), v


def test_node_state_loop_takes_one_active_set_pass_per_intermediate_step():
    """Node states with a velocity band (+-0.01 m/s around the true velocity, every 0.5 s) that
    the noise presses: the loop's intermediate steps are quick active-set passes from the last
    step's rows (``iterations[k]["solve"] == "banded"``), the first and last go through the
    stage; the answer equals the loop whose every step is solved in full by the active set, and
    the one whose every step is the interior point's, to 1e-9, verified, with rows at their bounds."""
    from bvpnav.error_models import ErrorStates

    t, data, r, v = _noisy_state_drive()
    sols = {}
    for quick, qp in ((True, "auto"), (False, "auto"), (False, "interior point")):
        model = ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-4, acc_drift=1e-3)
        prob = bvpnav.NavigationProblem(data, error_model=model, sigma_a=2e-2)
        k, s = np.arange(0, t.size, 20), np.arange(0, t.size, 10)
        prob.add(Position(t=t[k], value=r[k], sigma=1e-2),
                 Velocity(t=t[s], value=v[s], mode="band", tol=0.01, name="vel band"))
        sols[quick, qp] = prob.solve(solver="direct", attitude={"progress": False, "quick": quick},
                                     options={"qp": qp})
    fast, slow = sols[True, "auto"], sols[False, "auto"]
    kinds = [it["solve"] for it in fast.records.attitude.iterations]
    assert kinds[0] == kinds[-1] == "stage" and kinds.count("banded") >= 2, kinds
    assert {it["solve"] for it in slow.records.attitude.iterations} == {"stage"}
    assert fast.stats["qp_method"] == "active set" and fast.stats["active_rows"] >= 1
    for other in (slow, sols[False, "interior point"]):
        assert other.records.attitude.converged and other.stats["verified"]
        y = other.x
        assert np.abs(fast.x - y).max() <= 1e-9 * np.abs(y).max(), np.abs(fast.x - y).max() / np.abs(y).max()
    assert fast.records.attitude.converged and fast.stats["verified"]


def test_band_plan_refitted_to_each_linearization_of_a_car_drive(monkeypatch):
    """Node states on the simulated car drive (60 s, 10 Hz, noisy sensors, a gyro bias, the
    heading 0.02 rad off) with NonHolonomic as a band of 0.05 m/s and ForwardMotion: the body-frame
    rows gain and lose entries from one linearization to the next (attitude terms about the last
    velocity), and each solve after the first refits the kept band plan to them
    (:func:`bvpnav.linalg.ipm._refit`) instead of analysing the pattern again. The answers of the
    quick loop, the loop solved in full by the active set and the interior point's agree to 1e-9,
    verified, with the vehicle rows pressing (13 rows at their bounds, measured)."""
    from scipy.spatial.transform import Rotation

    import bvpnav.linalg.banded as banded
    import bvpnav.linalg.ipm as ipm
    from bvpnav.constraints import ForwardMotion, NonHolonomic
    from bvpnav.error_models import ErrorStates
    from bvpnav.scenarios import car_drive

    drive = car_drive(duration=60.0, rate=10.0)
    rng = np.random.default_rng(1)
    t = drive.t
    f = drive.attitude.inv().apply(drive.acceleration - drive.gravity)
    w = drive.body_rate_true
    guess = Rotation.from_rotvec([0.0, 0.0, 0.02]) * drive.attitude[0]
    data = bvpnav.ImuData.from_gyro(t, f + 0.05 * rng.standard_normal(f.shape),
                                    w + 2e-3 + 1e-3 * rng.standard_normal(w.shape), initial_attitude=guess,
                                    gravity=drive.gravity)
    refits, builds = [], []
    refit, build = ipm._refit, banded.BandPlan.build.__func__
    monkeypatch.setattr(ipm, "_refit", lambda *a: refits.append(refit(*a)) or refits[-1])
    monkeypatch.setattr(banded.BandPlan, "build", classmethod(lambda cls, *a, **k: builds.append(1)
                                                             or build(cls, *a, **k)))
    sols = {}
    for quick, qp in ((True, "auto"), (False, "auto"), (False, "interior point")):
        refits.clear()
        builds.clear()
        model = ErrorStates(arw=1e-3, gyro_drift=1e-4, acc_drift=1e-3)
        prob = bvpnav.NavigationProblem(data, error_model=model, sigma_a=0.05)
        k = np.arange(0, t.size, 50)
        prob.add(Position(t=t[k], value=drive.position[k], sigma=0.1), NonHolonomic(tol=0.05, name="nhc"),
                 ForwardMotion(name="fwd"))
        sol = prob.solve(solver="direct", attitude={"progress": False, "quick": quick}, options={"qp": qp})
        assert sol.records.attitude.converged and sol.stats["verified"]
        steps = len(sol.records.attitude.iterations)
        assert len(builds) == 1 and len(refits) >= steps - 2 and all(r is not None for r in refits)
        assert sol.stats["active_rows"] == 13
        sols[quick, qp] = sol
    kinds = [it["solve"] for it in sols[True, "auto"].records.attitude.iterations]
    assert kinds.count("banded") >= 3, kinds
    y = sols[False, "interior point"].x
    for key in ((True, "auto"), (False, "auto")):
        assert np.abs(sols[key].x - y).max() <= 1e-9 * np.abs(y).max()
