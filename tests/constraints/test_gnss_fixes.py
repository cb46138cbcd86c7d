"""GNSS fixes on vehicles (issue 39 items 4-6): lever arm, fix delay, outlier gating.

Exactness on noise-free simulations: the positions are the FEM's own integration of the
data, so a lever arm or a delay the fixes were made with is recovered to rounding (each
asserted to 1e-6 of its true value); then the errors that name the item, and the gating's
rejected list on navigation-frame data with planted outliers.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import AttitudeError, LeverArm, TimeOffset
from bvpnav.errors import InputError
from bvpnav.log import BvpnavWarning
from bvpnav.simulate import strapdown_3d_2010
from bvpnav.testing import check_error_model, check_item

LEVER = np.array([1.0, -0.3, 0.2])


@pytest.fixture(scope="module")
def turning():
    """Strapdown data integrated from the gyro (rates known) and the FEM's own positions and
    velocities of it (m, m/s) from rest at the origin."""
    data = strapdown_3d_2010(rate=10.0).imu_data(attitude="gyro")
    free = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=0.0), Velocity(t=0.0, value=0.0))
    sol = free.solve(solver="direct")
    return data, sol.position(), sol.velocity()


def _omega_cross(data, k, lever):
    return data.attitude[k].apply(np.cross(data.gyro[k], lever))


def test_known_lever_arm_gives_the_imu_positions_exactly(turning):
    data, pos, _ = turning
    k = np.arange(0, data.n, 15)
    ant = pos[k] + data.attitude[k].apply(LEVER)
    prob = bvpnav.NavigationProblem(data).add(Position(t=data.t[k], value=ant, lever=LEVER),
                                              Velocity(t=0.0, value=0.0))
    sol = prob.solve(solver="direct")
    assert np.max(np.abs(sol.position() - pos)) < 1e-6
    # the same fixes without the lever put the IMU at the antenna: 1 m off at least somewhere
    off = bvpnav.NavigationProblem(data).add(Position(t=data.t[k], value=ant), Velocity(t=0.0, value=0.0))
    assert np.max(np.abs(off.solve(solver="direct").position() - pos)) > 0.5


def test_estimated_lever_arm_from_positions_and_from_velocities(turning):
    data, pos, vel = turning
    k = np.arange(0, data.n, 15)
    for item in (Position(t=data.t[k], value=pos[k] + data.attitude[k].apply(LEVER), lever="estimated"),
                 Velocity(t=data.t[k], value=vel[k] + _omega_cross(data, k, LEVER), lever="estimated")):
        prob = bvpnav.NavigationProblem(data, error_model=LeverArm(), grade=None)
        prob.add(item, Position(t=0.0, value=0.0, name="start"), Velocity(t=0.0, value=0.0, name="v0"))
        sol = prob.solve(solver="direct")
        est = sol.error_params[["lever_x", "lever_y", "lever_z"]].to_numpy()
        assert np.max(np.abs(est - LEVER)) <= 1e-6 * np.max(np.abs(LEVER)), (type(item).__name__, est)


def test_estimated_delay_of_position_and_velocity_fixes():
    data = TimeOffset.example_data()
    free = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=0.0), Velocity(t=0.0, value=1.0))
    sol0 = free.solve(solver="direct")
    pos, vel = sol0.position(), sol0.velocity()
    k = np.arange(5, data.n - 5, 7)
    delay = 0.3   # three samples: the fixes hold nodes
    for item in (Position(t=data.t[k] + delay, value=pos[k], delay="estimated", name="late"),
                 Velocity(t=data.t[k] + delay, value=vel[k], delay="estimated", name="late")):
        prob = bvpnav.NavigationProblem(data, error_model=TimeOffset(), grade=None)
        prob.add(item, Position(t=0.0, value=0.0, name="start"), Velocity(t=0.0, value=1.0, name="v0"))
        sol = prob.solve(solver="direct", sequential={"tol": 1e-10})
        assert abs(sol.error_params["time_offset"] - delay) <= 1e-6 * delay, type(item).__name__
        assert sol.stats["sequential"]["converged"]
        assert np.max(np.abs(sol.position() - pos)) < 1e-6


def test_known_delay_shifts_the_fixes():
    data = TimeOffset.example_data()
    free = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=0.0), Velocity(t=0.0, value=1.0))
    pos = free.solve(solver="direct").position()
    k = np.arange(5, data.n - 5, 10)
    prob = bvpnav.NavigationProblem(data).add(Position(t=data.t[k] + 0.2, value=pos[k], delay=0.2),
                                              Velocity(t=0.0, value=1.0))
    assert np.max(np.abs(prob.solve(solver="direct").position() - pos)) < 1e-6


def test_lever_and_delay_together_on_a_turning_body(turning):
    data, pos, _ = turning
    k = np.arange(3, data.n - 3, 9)
    delay = 0.2
    ant = pos[k] + data.attitude[k].apply(LEVER)
    prob = bvpnav.NavigationProblem(data, error_model=LeverArm() + TimeOffset(), grade=None)
    prob.add(Position(t=data.t[k] + delay, value=ant, lever="estimated", delay="estimated"),
             Position(t=0.0, value=0.0, name="start"), Velocity(t=0.0, value=0.0, name="v0"))
    sol = prob.solve(solver="direct", sequential={"tol": 1e-10})
    assert abs(sol.error_params["time_offset"] - delay) <= 1e-6 * delay
    est = sol.error_params[["lever_x", "lever_y", "lever_z"]].to_numpy()
    assert np.max(np.abs(est - LEVER)) <= 1e-6


def test_delay_seen_through_the_antennas_own_motion_about_a_still_imu():
    """The IMU stands still and turns about z at a varying rate, the antenna 2 m off: only the
    antenna moves, so the delay shows in the fixes only through :math:`d(C l)/dt`. The delay's
    linearization carries that rate (it had the IMU's velocity alone: zero here, and the solve
    refused the hard fixes as infeasible); noise-free, delay and lever arm are found to 1e-6."""
    t = np.linspace(0.0, 20.0, 201)
    w = np.column_stack([np.zeros(t.size), np.zeros(t.size), 0.5 + 0.3 * np.sin(0.4 * t)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # a rate that stays put for a while looks like saturation
        data = bvpnav.ImuData.from_gyro(t, np.tile([0.0, 0.0, 9.80665], (t.size, 1)), w)
    lever, delay = np.array([2.0, -0.5, 0.3]), 0.3
    k = np.arange(5, t.size - 5, 4)
    ant = data.attitude[k].apply(lever)
    ant_v = data.attitude[k].apply(np.cross(w[k], lever))
    cases = [(Position, ant, tuple(lever), TimeOffset()), (Velocity, ant_v, tuple(lever), TimeOffset()),
             (Position, ant, "estimated", TimeOffset() + LeverArm())]
    for item, value, lev, em in cases:
        prob = bvpnav.NavigationProblem(data, error_model=em, grade=None)
        prob.add(item(t=t[k] + delay, value=value, lever=lev, delay="estimated", name="antenna"),
                 Position(t=0.0, value=0.0, name="start"), Velocity(t=0.0, value=0.0, name="v0"))
        sol = prob.solve(solver="direct", sequential={"tol": 1e-12})
        assert sol.stats["sequential"]["converged"]
        assert abs(sol.error_params["time_offset"] - delay) <= 1e-6 * delay, (item.__name__, lev)
        if lev == "estimated":
            est = sol.error_params[["lever_x", "lever_y", "lever_z"]].to_numpy()
            assert np.max(np.abs(est - lever)) <= 1e-6 * np.max(np.abs(lever)), est
        assert np.max(np.abs(sol.position())) < 1e-6   # the IMU stays at the origin


def test_heading_seen_through_the_antenna_about_a_still_imu():
    r"""The IMU stands still and turns about z at a varying rate, its initial heading guessed
    10 degrees off; the antenna 2 m off is fixed to 1 cm. Only the antenna's place tells the
    heading (the accelerations do not change with it), through :math:`d(C l)/d\psi`, which the
    attitude loop's rows now carry (without it: "nothing determines parameter attitude_z").
    The heading correction is found to 1e-9 rad, and the IMU stays at the origin."""
    t = np.linspace(0.0, 20.0, 201)
    w = np.column_stack([np.zeros(t.size), np.zeros(t.size), 0.5 + 0.3 * np.sin(0.4 * t)])
    f = np.tile([0.0, 0.0, 9.80665], (t.size, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # a rate that stays put for a while looks like saturation
        true = bvpnav.ImuData.from_gyro(t, f, w)
        off = Rotation.from_rotvec([0.0, 0.0, np.pi / 18])
        data = bvpnav.ImuData.from_gyro(t, f, w, initial_attitude=off)
    k = np.arange(0, t.size, 4)
    prob = bvpnav.NavigationProblem(data, error_model=AttitudeError(axes="z"), grade=None)
    prob.add(Position(t=t[k], value=true.attitude[k].apply(LEVER * 2), lever=tuple(LEVER * 2), sigma=0.01,
                      name="antenna"),
             Position(t=0.0, value=0.0, name="start"), Velocity(t=0.0, value=0.0, name="v0"))
    sol = prob.solve(solver="direct", attitude={"heading": "given", "progress": False})
    assert sol.stats["sequential"]["converged"]
    assert abs(sol.error_params["attitude_z"] + np.pi / 18) < 1e-9
    assert np.max(np.abs(sol.position())) < 1e-9


@pytest.mark.parametrize("model", [LeverArm, TimeOffset])
def test_error_model_contract(model):
    assert check_error_model(model) is None


def test_item_contract_with_the_new_options():
    assert check_item(Position(t=[1.0, 4.0], value=[[0.0, 1.0, 2.0], [1.0, 2.0, 3.0]], delay=0.05,
                               name="known delay")) is None


# ----------------------------------------------------------------- errors naming the item
def _nav_data():
    t = np.linspace(0.0, 10.0, 101)
    return bvpnav.ImuData(t=t, acc=np.zeros((101, 3)))


def test_lever_on_data_without_attitude_names_the_item():
    prob = bvpnav.NavigationProblem(_nav_data()).add(
        Position(t=[0.0, 10.0], value=0.0, lever=(1.0, 0.0, 0.0), name="antenna fixes"))
    with pytest.raises(InputError, match=r"antenna fixes: lever=.*needs the attitude.*navigation-frame"):
        prob.solve(solver="direct")


def test_estimated_lever_without_the_error_model_names_the_item_and_the_fix(turning):
    data, _, _ = turning
    prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 5.0], value=0.0, lever="estimated",
                                                       name="gnss"))
    with pytest.raises(InputError, match=r"gnss: lever='estimated'.*LeverArm\(sigma=\.\.\.\)"):
        prob.solve(solver="direct")


def test_estimated_delay_without_the_error_model_names_the_item():
    prob = bvpnav.NavigationProblem(_nav_data()).add(
        Position(t=[1.0, 9.0], value=0.0, delay="estimated", name="gnss"), Velocity(t=0.0, value=0.0))
    with pytest.raises(InputError, match=r"gnss: delay='estimated'.*TimeOffset\(sigma=\.\.\.\)"):
        prob.solve(solver="direct")


@pytest.mark.parametrize("kw, match", [
    ({"lever": (1.0, 2.0)}, r"fix: lever=\(1.0, 2.0\); give three finite numbers"),
    ({"lever": "measured"}, r"fix: lever='measured'; give three numbers .* or 'estimated'"),
    ({"delay": "auto"}, r"fix: delay='auto'; give a number in s"),
    ({"delay": float("nan")}, r"fix: delay=nan must be finite"),
    ({"gate": 3.0}, r"fix: gate= judges residuals against sigma; give sigma="),
    ({"gate": -1.0, "sigma": 1.0}, r"fix: gate = -1.0: must be a finite positive number"),
])
def test_bad_options_are_refused_naming_the_item(kw, match):
    with pytest.raises(InputError, match=match):
        Position(t=[1.0], value=0.0, name="fix", **kw)


def test_lever_arm_model_refuses_axes_and_wrong_sizes():
    with pytest.raises(InputError, match="LeverArm: axes= is not supported"):
        LeverArm(axes="x")
    with pytest.raises(InputError, match="LeverArm: sigma has 2 values; give one or three"):
        LeverArm(sigma=(1.0, 2.0))
    with pytest.raises(InputError, match="TimeOffset: sigma has 2 values; give one number"):
        TimeOffset(sigma=(1.0, 2.0))


# ------------------------------------------------------------------------------ gating
def _gated_problem(seed: int = 3, n_bad: int = 4, gate: float | None = 5.0):
    """Navigation-frame data of a weaving motion (100 Hz over 60 s, accelerometer noise
    1e-3 m/s^2), fixes every second with sigma 0.1 m, ``n_bad`` of them 5-20 m off."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 60.0, 6001)
    r = np.column_stack([3.0 * t + 5.0 * np.sin(0.2 * t), 4.0 * np.cos(0.15 * t), 0.5 * np.sin(0.1 * t)])
    a = np.column_stack([-0.2 * np.sin(0.2 * t), -0.09 * np.cos(0.15 * t), -0.005 * np.sin(0.1 * t)])
    data = bvpnav.ImuData(t=t, acc=a + 1e-3 * rng.standard_normal(a.shape))
    k = np.arange(0, t.size, 100)
    fixes = r[k] + 0.1 * rng.standard_normal((k.size, 3))
    bad = np.sort(rng.choice(np.arange(1, k.size - 1), n_bad, replace=False))
    d = rng.standard_normal((n_bad, 3))
    fixes[bad] += d / np.linalg.norm(d, axis=1)[:, None] * rng.uniform(5.0, 20.0, n_bad)[:, None]
    prob = bvpnav.NavigationProblem(data, sigma_a=1e-3)
    prob.add(Position(t=t[k], value=fixes, sigma=0.1, gate=gate, name="gnss"))
    return prob, t[k], fixes, bad, r


def test_gating_rejects_every_planted_outlier_and_no_good_fix():
    prob, tk, fixes, bad, truth = _gated_problem()
    with pytest.warns(BvpnavWarning, match=r"gating rejected 4 of 61 fix\(es\) .*gnss t=") as rec:
        sol = prob.solve(solver="direct")
    rej = sol.rejected
    assert sorted(rej["t"].tolist()) == sorted(tk[bad].tolist())
    assert (rej["normalized"] > 5.0).all() and (rej["gate"] == 5.0).all()
    np.testing.assert_array_equal(rej[["value_x", "value_y", "value_z"]].to_numpy(),
                                  fixes[np.searchsorted(tk, rej["t"].to_numpy())])
    # the residual listed is the fix against the estimate made without it: about the planted offset
    assert (np.linalg.norm(rej[["residual_x", "residual_y", "residual_z"]].to_numpy(), axis=1) > 4.9).all()
    assert sol.stats["gating"]["rejected"] == bad.size and sol.stats["gating"]["settled"]
    assert any("gating rejected 4 of 61 fix(es)" in w for w in sol.warnings)
    assert sum("gating rejected" in str(w.message) for w in rec) == 1
    assert "4 fix(es) rejected by gating" in repr(sol)
    # with the outliers gone the answer is as good as with clean fixes: within 0.1 m (sigma)
    assert np.sqrt(np.mean((sol.position() - truth) ** 2)) < 0.1


def test_without_a_gate_the_outliers_drag_the_answer():
    prob, _, _, _, truth = _gated_problem(gate=None)
    sol = prob.solve(solver="direct")
    gated, *_ = _gated_problem()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol_g = gated.solve(solver="direct")
    rms = np.sqrt(np.mean((sol.position() - truth) ** 2))
    rms_g = np.sqrt(np.mean((sol_g.position() - truth) ** 2))
    assert sol.rejected is None and rms > 3.0 * rms_g, (rms, rms_g)


def test_clean_fixes_are_all_kept():
    prob, *_ = _gated_problem(n_bad=0)
    sol = prob.solve(solver="direct")
    assert sol.rejected is not None and len(sol.rejected) == 0
    assert sol.stats["gating"] == {"passes": 1, "settled": True, "judged": 61, "rejected": 0,
                                   "items": ["gnss"]}
    assert not any("gating" in w for w in sol.warnings)


def test_attitude_slerp_between_samples_matches_the_rotation():
    """A fix between samples takes the attitude on the great circle between the two."""
    data = strapdown_3d_2010(rate=10.0).imu_data()
    model = bvpnav.NavModel(data)
    tq = np.array([0.05, 3.33])
    off = model.antenna_offset(tq, (1.0, 0.0, 0.0)).c.reshape(2, 3)
    from scipy.spatial.transform import Slerp

    expect = Slerp(data.t, data.attitude)(tq).apply([1.0, 0.0, 0.0])
    np.testing.assert_allclose(off, expect, atol=1e-12)
    assert isinstance(data.attitude, Rotation)


def test_lever_and_delay_with_node_states(turning):
    """The same fixes with the node states (``ErrorStates``) as the IMU's error model: the
    node-state loop scores each step on the formulation the step solved, with the delay at its
    linearization (it compiled the unlinearized item and refused it); noise-free, every state
    stays at zero and the delay and lever arm are found to 1e-6."""
    from bvpnav.error_models import ErrorStates

    data, pos, _ = turning
    k = np.arange(3, data.n - 3, 9)
    delay = 0.2
    ant = pos[k] + data.attitude[k].apply(LEVER)
    em = ErrorStates(arw=1e-4, gyro_drift=1e-5, acc_drift=1e-4, attitude_sigma=0.01, gyro_sigma=1e-3,
                     acc_sigma=1e-2) + LeverArm() + TimeOffset()
    prob = bvpnav.NavigationProblem(data, error_model=em, grade=None)
    prob.add(Position(t=data.t[k] + delay, value=ant, lever="estimated", delay="estimated"),
             Position(t=0.0, value=0.0, name="start"), Velocity(t=0.0, value=0.0, name="v0"))
    sol = prob.solve(solver="direct", sequential={"tol": 1e-10})
    report = sol.records.attitude
    assert report.kind == "states" and report.converged
    assert abs(sol.error_params["time_offset"] - delay) <= 1e-6 * delay
    est = sol.error_params[["lever_x", "lever_y", "lever_z"]].to_numpy()
    assert np.max(np.abs(est - LEVER)) <= 1e-6
    assert np.max(np.abs(sol.position() - pos)) < 1e-6
    assert np.max(np.abs(sol.error_states.to_numpy())) < 1e-6
