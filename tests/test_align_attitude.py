"""Alignment helpers: roll/pitch at rest, heading from the motion, Euler angles in ENU and NED."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from bvpnav.align import (
    align,
    attitude_angles,
    heading_from_positions,
    heading_from_velocity,
    initial_attitude,
    roll_pitch_from_stationary,
)
from bvpnav.errors import InputError

G0 = 9.80665
GRAVITY = {"enu": np.array([0.0, 0.0, -G0]), "ned": np.array([0.0, 0.0, G0])}
#: ENU -> NED: (e, n, u) -> (n, e, -u); FLU body -> FRD body: diag(1, -1, -1).
T = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
B = np.diag([1.0, -1.0, -1.0])


def at_rest(c: Rotation, frame: str) -> np.ndarray:
    """What an ideal accelerometer triad at rest reads: f = -C^T g."""
    return -c.inv().apply(GRAVITY[frame])


def _angles(n=200, seed=0):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-math.pi, math.pi, n), rng.uniform(-1.5, 1.5, n), rng.uniform(-math.pi, math.pi, n))


# ------------------------------------------------------------------ roll and pitch
@pytest.mark.parametrize("frame", ["enu", "ned"])
def test_roll_pitch_round_trip(frame):
    """initial_attitude -> simulated stationary specific force -> roll, pitch back to 1e-12."""
    for r, p, y in zip(*_angles(), strict=True):
        f = at_rest(initial_attitude(r, p, y, frame), frame)
        got = roll_pitch_from_stationary(f, frame)
        assert got == pytest.approx((r, p), abs=1e-12)


def test_gravity_sign_and_known_values():
    # level triad, z up in ENU: reads +g on z; z down in NED: reads -g on z
    assert roll_pitch_from_stationary([0.0, 0.0, G0]) == (0.0, 0.0)
    assert roll_pitch_from_stationary([0.0, 0.0, -G0], "ned") == (0.0, 0.0)
    # the same reading is upside down in the other frame
    assert roll_pitch_from_stationary([0.0, 0.0, -G0])[0] == pytest.approx(math.pi, abs=1e-15)
    # ENU, pitch 0.3: Ry(0.3) tips body x down; the triad reads (-g sin 0.3, 0, g cos 0.3)
    r, p = roll_pitch_from_stationary([-G0 * math.sin(0.3), 0.0, G0 * math.cos(0.3)])
    assert (r, p) == pytest.approx((0.0, 0.3), abs=1e-15)
    # NED (aerospace), nose up 0.3: x axis points up, reads +g sin 0.3
    r, p = roll_pitch_from_stationary([G0 * math.sin(0.3), 0.0, -G0 * math.cos(0.3)], "ned")
    assert (r, p) == pytest.approx((0.0, 0.3), abs=1e-15)
    # roll 0.2 about x in ENU: y tips up, reads +g sin 0.2 on y
    r, p = roll_pitch_from_stationary([0.0, G0 * math.sin(0.2), G0 * math.cos(0.2)])
    assert (r, p) == pytest.approx((0.2, 0.0), abs=1e-15)


def test_roll_pitch_averages_noisy_samples():
    c = initial_attitude(0.05, -0.08, 1.0)
    rng = np.random.default_rng(1)
    f = at_rest(c, "enu") + rng.normal(scale=0.02, size=(4000, 3))  # 0.02 m/s^2 noise
    r, p = roll_pitch_from_stationary(f)
    # sigma of the mean 0.02/sqrt(4000)/g = 3.2e-5 rad; 5e-4 is > 10 sigma
    assert abs(r - 0.05) < 5e-4 and abs(p + 0.08) < 5e-4


def test_roll_pitch_refuses_a_moving_interval_or_wrong_units():
    # 10 % too much (|f| = 1.1 g) is refused; 2 % off (a bias, a slope) is accepted
    with pytest.raises(InputError, match=r"magnitude 10.79 m/s\^2, not about g"):
        roll_pitch_from_stationary([0.0, 0.0, 1.1 * G0])
    with pytest.raises(InputError, match="magnitude 8.826"):
        roll_pitch_from_stationary([0.0, 0.0, 0.9 * G0])
    assert roll_pitch_from_stationary([0.0, 0.0, 1.02 * G0]) == (0.0, 0.0)
    with pytest.raises(InputError, match="units of g"):
        roll_pitch_from_stationary(np.tile([0.0, 0.0, 1.0], (10, 1)))
    with pytest.raises(InputError, match="units of mg"):
        roll_pitch_from_stationary([0.0, 0.0, 1000.0])
    with pytest.raises(InputError, match="shape"):
        roll_pitch_from_stationary(np.zeros((5, 2)))
    with pytest.raises(InputError, match="finite"):
        roll_pitch_from_stationary([0.0, np.nan, G0])
    with pytest.raises(InputError, match="valid navigation frames"):
        roll_pitch_from_stationary([0.0, 0.0, G0], "nwu")


# ------------------------------------------------------------------ ENU versus NED
def test_enu_and_ned_describe_the_same_physical_attitude():
    """FLU body in ENU and FRD body in NED: C_ned = T C_enu B, with roll equal, pitch negated and
    yaw_ned = 90 deg - yaw_enu; the triads' readings at rest give the same angles."""
    for r, p, y in zip(*_angles(50, seed=2), strict=True):
        c_enu = initial_attitude(r, p, y, "enu")
        c_ned = initial_attitude(r, -p, math.pi / 2 - y, "ned")
        np.testing.assert_allclose(c_ned.as_matrix(), T @ c_enu.as_matrix() @ B, atol=1e-14)
        f_flu = at_rest(c_enu, "enu")
        f_frd = B @ f_flu                      # the same force in the FRD triad's axes
        np.testing.assert_allclose(f_frd, at_rest(c_ned, "ned"), atol=1e-13)
        assert roll_pitch_from_stationary(f_frd, "ned") == pytest.approx((r, -p), abs=1e-12)
        a_enu = attitude_angles(c_enu, "enu").iloc[0]
        a_ned = attitude_angles(c_ned, "ned").iloc[0]
        assert a_ned["roll_deg"] == pytest.approx(a_enu["roll_deg"], abs=1e-9)
        assert a_ned["pitch_deg"] == pytest.approx(-a_enu["pitch_deg"], abs=1e-9)
        dyaw = (a_ned["yaw_deg"] - (90.0 - a_enu["yaw_deg"]) + 180.0) % 360.0 - 180.0
        assert abs(dyaw) < 1e-9


def test_the_same_triad_in_both_frames():
    """One triad, two navigation frames: C_ned = T C_enu, and its one reading at rest gives the
    roll and pitch of each description."""
    for r, p, y in zip(*_angles(50, seed=3), strict=True):
        c_enu = initial_attitude(r, p, y, "enu")
        c_ned = Rotation.from_matrix(T @ c_enu.as_matrix())
        f = at_rest(c_enu, "enu")
        np.testing.assert_allclose(f, at_rest(c_ned, "ned"), atol=1e-13)
        ned = attitude_angles(c_ned, "ned").iloc[0]
        got = roll_pitch_from_stationary(f, "ned")
        assert got == pytest.approx((math.radians(ned["roll_deg"]), math.radians(ned["pitch_deg"])),
                                    abs=1e-12)


def test_heading_from_positions_in_both_frames():
    """ENU: counterclockwise from east; NED: clockwise from north. A path to the north-east at
    30 degrees above east is yaw 30 deg in ENU and 60 deg in NED."""
    t = np.arange(6.0)
    d = np.array([0.0, 0.0, 5.0, 10.0, 15.0, 20.0])  # at rest for a second, then 5 m/s
    east, north = d * math.cos(math.radians(30)), d * math.sin(math.radians(30))
    enu = np.column_stack([east, north, np.zeros(6)])
    ned = np.column_stack([north, east, np.zeros(6)])
    assert heading_from_positions(t, enu, "enu", min_distance=8.0) == pytest.approx(math.radians(30), 1e-12)
    assert heading_from_positions(t, ned, "ned", min_distance=8.0) == pytest.approx(math.radians(60), 1e-12)
    # the body pointing there has its x axis along the path
    c = initial_attitude(0.0, 0.0, heading_from_positions(t, enu[:, :2], min_distance=8.0))
    np.testing.assert_allclose(c.apply([1.0, 0.0, 0.0]), enu[-1] / 20.0, atol=1e-12)
    c = initial_attitude(0.0, 0.0, heading_from_positions(t, ned, "ned", min_distance=8.0), "ned")
    np.testing.assert_allclose(c.apply([1.0, 0.0, 0.0]), ned[-1] / 20.0, atol=1e-12)


def test_heading_from_positions_on_a_known_straight_path_with_noise():
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 20.0, 1.0)
    yaw = -2.5
    p = np.column_stack([3.0 * t * math.cos(yaw), 3.0 * t * math.sin(yaw), 0.1 * t])
    p[:, :2] += rng.normal(scale=0.5, size=(t.size, 2))
    # first fix >= 30 m away is ~10 fixes on: error ~ sqrt(2) 0.5 / 30 = 0.024 rad
    assert abs(heading_from_positions(t, p, min_distance=30.0) - yaw) < 0.1


def test_fixes_that_do_not_move_are_refused_with_a_margin():
    t = np.arange(10.0)
    rng = np.random.default_rng(5)
    still = rng.normal(scale=1.0, size=(10, 3)) * np.array([1.0, 1.0, 0.0])
    d = np.hypot(*(still[:, :2] - still[0, :2]).T).max()
    with pytest.raises(InputError, match="do not define a direction of travel"):
        heading_from_positions(t, still, min_distance=2.0 * d)  # twice the largest spread
    heading_from_positions(t, still, min_distance=0.5 * d)  # half of it: a (noisy) direction
    up = np.column_stack([np.zeros(10), np.zeros(10), 5.0 * t])  # vertical motion has no heading
    with pytest.raises(InputError, match="stay within 0 m"):
        heading_from_positions(t, up, min_distance=1.0)
    with pytest.raises(InputError, match="strictly increasing"):
        heading_from_positions([0.0, 1.0, 1.0], np.zeros((3, 2)))
    with pytest.raises(InputError, match="one time per fix"):
        heading_from_positions([0.0, 1.0], np.zeros((3, 2)))
    with pytest.raises(InputError, match=r"\(N, 2\) or \(N, 3\)"):
        heading_from_positions([0.0, 1.0], np.zeros(2))


def test_heading_from_velocity():
    assert heading_from_velocity([0.0, 2.0, 0.3]) == pytest.approx(math.pi / 2, abs=1e-15)
    assert heading_from_velocity([0.0, 2.0], "ned") == pytest.approx(math.pi / 2, abs=1e-15)  # east
    v = np.array([[1.0, 1.0], [-1.0, 0.0], [0.0, -3.0]])
    np.testing.assert_allclose(heading_from_velocity(v), [math.pi / 4, math.pi, -math.pi / 2], atol=1e-15)
    with pytest.raises(InputError, match=r"horizontal speed 0.25 m/s is below min_speed = 0.5"):
        heading_from_velocity([0.25, 0.0, 3.0])
    assert heading_from_velocity([1.0, 0.0]) == 0.0  # twice min_speed: accepted
    with pytest.raises(InputError, match="row 1"):
        heading_from_velocity([[1.0, 0.0], [0.0, 0.1]])


# ------------------------------------------------------------------ angles
def test_attitude_angles_inverts_initial_attitude_per_sample():
    r, p, y = _angles(300, seed=6)
    c = initial_attitude(r, p, y)
    assert len(c) == 300
    ang = attitude_angles(c, t=np.arange(300) * 0.01)
    assert list(ang.columns) == ["roll_deg", "pitch_deg", "yaw_deg"] and ang.index.name == "t"
    np.testing.assert_allclose(ang["roll_deg"], np.degrees(r), atol=1e-9)
    np.testing.assert_allclose(ang["pitch_deg"], np.degrees(p), atol=1e-9)
    np.testing.assert_allclose(ang["yaw_deg"], np.degrees(y), atol=1e-9)
    # scalar angles give one rotation and a one-row frame
    one = attitude_angles(initial_attitude(0.1, 0.2, 0.3))
    assert isinstance(one, pd.DataFrame) and one.shape == (1, 3)


def test_attitude_angles_unwraps_the_yaw_on_request():
    yaw = np.linspace(0.0, 4 * math.pi, 101)
    c = initial_attitude(0.0, 0.0, yaw)
    assert attitude_angles(c)["yaw_deg"].abs().max() <= 180.0 + 1e-9
    np.testing.assert_allclose(attitude_angles(c, unwrap=True)["yaw_deg"], np.degrees(yaw), atol=1e-9)


def test_angle_helpers_refuse_bad_input():
    with pytest.raises(InputError, match="do not broadcast"):
        initial_attitude([0.0, 0.1], [0.0, 0.1, 0.2], 0.0)
    with pytest.raises(InputError, match="scipy Rotation"):
        attitude_angles(np.eye(3))
    with pytest.raises(InputError, match="one time per rotation"):
        attitude_angles(initial_attitude([0.0, 0.1], 0.0, 0.0), t=[0.0])


# ------------------------------------------------------------------ align
def _recording(c0, n=400, rate=100.0, noise=0.0, seed=7, frame="enu"):
    t = np.arange(n) / rate
    f = np.tile(at_rest(c0, frame), (n, 1))
    if noise:
        f += np.random.default_rng(seed).normal(scale=noise, size=f.shape)
    return t, f


@pytest.mark.parametrize("frame", ["enu", "ned"])
def test_align_from_a_stationary_start_and_fixes(frame):
    c_true = initial_attitude(0.03, -0.02, 2.2, frame)
    t, f = _recording(c_true, frame=frame)
    fix_t = np.array([0.0, 5.0, 10.0])
    fix = np.array([[0.0, 0.0], [20.0 * math.cos(2.2), 20.0 * math.sin(2.2)],
                    [40.0 * math.cos(2.2), 40.0 * math.sin(2.2)]])
    for stationary in (slice(0, 200), np.arange(400) < 300, (0.0, 1.5)):
        c = align(t, f, stationary=stationary, positions=fix, position_times=fix_t, frame=frame)
        assert (c * c_true.inv()).magnitude() < 1e-12
    c = align(t, f, stationary=slice(None), velocity=[math.cos(2.2), math.sin(2.2), 0.0], frame=frame)
    assert (c * c_true.inv()).magnitude() < 1e-12
    c = align(t, f, stationary=slice(None), yaw=2.2, frame=frame)
    assert (c * c_true.inv()).magnitude() < 1e-12


def test_align_carries_a_late_interval_back_with_the_gyro():
    """The body turns at a constant rate for 1 s, then stops; the interval at rest after it and the
    gyro give the roll and pitch at t[0] (exact: a constant-rate step is integrated exactly)."""
    c0 = initial_attitude(0.1, -0.05, 1.0)
    rate, k = 100.0, 100
    t = np.arange(300) / rate
    w = np.zeros((300, 3))
    w[: k + 1] = [0.2, -0.1, 0.3]
    ck = c0 * Rotation.from_rotvec(np.array([0.2, -0.1, 0.3]) * t[k])
    f = np.tile(at_rest(ck, "enu"), (300, 1))  # readings during the turn do not matter here
    c = align(t, f, stationary=slice(k, None), yaw=1.0, gyro=w)
    assert (c * c0.inv()).magnitude() < 1e-12
    wrong = align(t[k:], f[k:], stationary=slice(None), yaw=1.0)  # the attitude at t[k], not t[0]
    assert (wrong * c0.inv()).magnitude() > 0.05
    with pytest.raises(InputError, match=r"starts at sample 100 \(t = 1 s\), after t\[0\].*gyro="):
        align(t, f, stationary=slice(k, None), yaw=1.0)


def test_align_refuses_what_it_cannot_use():
    c_true = initial_attitude(0.0, 0.0, 0.5)
    t, f = _recording(c_true)
    with pytest.raises(InputError, match="exactly one heading source.*none given.*yaw=0.0"):
        align(t, f, stationary=slice(0, 100))
    with pytest.raises(InputError, match="velocity and yaw given"):
        align(t, f, stationary=slice(0, 100), velocity=[1.0, 0.0], yaw=0.0)
    moving = f.copy()
    moving[:, 0] += 5.0  # a 5 m/s^2 push: |f| = 1.12 g, not at rest
    with pytest.raises(InputError, match=r"stationary: samples 0..99 \(t = 0..0.99 s\).*not about g"):
        align(t, moving, stationary=slice(0, 100), yaw=0.0)
    with pytest.raises(InputError, match="selects no sample"):
        align(t, f, stationary=(10.0, 20.0), yaw=0.0)
    with pytest.raises(InputError, match="boolean mask"):
        align(t, f, stationary=[0, 1, 2], yaw=0.0)
    with pytest.raises(InputError, match="position_times"):
        align(t, f, stationary=slice(0, 100), positions=np.zeros((3, 2)))
    with pytest.raises(InputError, match="do not define a direction"):
        align(t, f, stationary=slice(0, 100), positions=np.zeros((3, 2)), position_times=[0.0, 1.0, 2.0])
    with pytest.raises(InputError, match=r"expected \(400, 3\)"):
        align(t, f[:, :2], stationary=slice(0, 100), yaw=0.0)
    with pytest.raises(InputError, match="yaw="):
        align(t, f, stationary=slice(0, 100), yaw="north")
    with pytest.raises(InputError, match=r"gyro: shape \(400, 2\); expected \(400, 3\)"):
        align(t, f, stationary=slice(100, None), yaw=0.0, gyro=np.zeros((400, 2)))


def test_aligned_noisy_consumer_start_is_within_the_grade_tilt():
    """A consumer-grade triad (bias 0.05 m/s^2, noise) at rest for 5 s: the tilt error is about
    bias/g = 5 mrad, inside the grade's 0.02 rad prior."""
    from bvpnav.sensors import grade

    g = grade("consumer")
    c_true = initial_attitude(0.04, 0.07, -1.0)
    t, f = _recording(c_true, n=500, noise=g.sigma_a(100.0))
    f += [g.acc_bias, -g.acc_bias, 0.0]
    c = align(t, f, stationary=slice(None), yaw=-1.0)
    err = (c * c_true.inv()).magnitude()
    assert 1e-3 < err < g.tilt  # a real error (the bias), yet inside the prior
