"""Plausibility of the installation and timing estimates (issue 39): the fixes' delay
(``TimeOffset``), the GNSS lever arm (``LeverArm``), the no-slip point (``NhcLever``) and the
mounting (``Mounting``).

Every case is a noise-free simulation whose answer is exact (the positions are the FEM's own
integration of the data, as in the models' own recovery examples), built with an installation
that is absurd, or with one that is normal:

- delay: navigation-frame data of a moving point with hard fixes stamped ``delay`` s late, the
  stated ``sigma_a = 1e-3`` m/s^2 (so the data, not the prior, set the estimate): stamped 0.3 s
  late against ``TimeOffset(sigma=0.05)`` the estimate is 0.3 s, 6 prior sigmas (warned, within
  the latency limit); stamped 0.485 s early (the IMU's stamps late by that) it is beyond the
  limit -0.1 s (warned, 4.85 sigmas of ``TimeOffset(sigma=0.1)`` named); 50 ms late with sigma 0.1,
  or 0.3 s late with no prior: nothing;
- lever arm: the turning strapdown motion with the antenna 6 m ahead (6.1 m away): warned;
  at ``(1, -0.3, 0.2)`` m: nothing;
- no-slip point: the car of the ``NhcLever`` tests with the point 7 m behind the IMU
  (7.02 m away): warned; 1.2 m behind (the tests' car): nothing;
- mounting: the straight drive of the ``Mounting`` tests with a 0.3 rad (17.2 deg) yaw: warned;
  0.6 and -0.4 deg: nothing.

Then the stated prior moves the limits (a known clock offset or a large vehicle's lever arm),
and :func:`check` on stand-ins: several components named together, a parameter the
conditioning check calls degenerate left out.
"""

from __future__ import annotations

import warnings
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from bvpnav import NavigationProblem
from bvpnav.constraints import NonHolonomic, Position, Velocity
from bvpnav.error_models import AttitudeError, CompositeErrorModel, LeverArm, Mounting, NhcLever, TimeOffset
from bvpnav.error_models.mounting import _straight_drive, mounting_slopes
from bvpnav.error_models.nhc_lever import _car_drive
from bvpnav.simulate import strapdown_3d_2010
from bvpnav.solve import plausibility as pl


def _solve(prob, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # noise-free data: the misfit says the sigmas are overstated
        sol = prob.solve(solver="direct", **kw)
    return sol, [w for w in sol.warnings if w.startswith("implausible")]


@pytest.fixture(scope="module")
def moving():
    data = TimeOffset.example_data()
    free = NavigationProblem(data).add(Position(t=data.t[0], value=0.0), Velocity(t=data.t[0], value=1.0))
    return data, free.solve(solver="direct").position()


def _delayed(moving, delay: float, em: TimeOffset):
    data, pos = moving
    k = np.arange(5, data.n - 5, 10)
    prob = NavigationProblem(data, error_model=em, grade=None, sigma_a=1e-3)
    prob.add(Position(t=data.t[k] + delay, value=pos[k], delay="estimated", name="late fixes"),
             Velocity(t=data.t[0], value=1.0, name="start velocity"))
    return _solve(prob, sequential={"tol": 1e-12})


def test_delay_far_from_a_tight_prior_warns(moving):
    sol, (msg,) = _delayed(moving, 0.3, TimeOffset(sigma=0.05))
    assert sol.error_params["time_offset"] == pytest.approx(0.3, abs=1e-3)
    assert msg.startswith("implausible estimate: the fixes' delay: time_offset = +0.3 s")
    assert "is 6 prior sigmas (0.05 s) from its prior 0 s, beyond 3" in msg
    assert "along-track error" in msg and "one clock" in msg and "TimeOffset(prior=" in msg
    assert msg in sol.stats["plausibility"]["warnings"]


def test_delay_beyond_the_physical_limit_warns(moving):
    sol, (msg,) = _delayed(moving, -0.485, TimeOffset(sigma=0.1))
    assert sol.error_params["time_offset"] == pytest.approx(-0.485, abs=1e-3)
    assert msg.startswith("implausible estimate: time_offset = -0.485 s (-485 ms) is beyond the limits "
                          "-0.1..+0.5 s of the fixes' delay (the IMU's samples stamped that much late")
    assert "; 4.85 prior sigmas from its prior (TimeOffset(sigma=0.1), prior 0 s)" in msg


def test_plausible_delays_do_not_warn(moving):
    sol, found = _delayed(moving, 0.05, TimeOffset(sigma=0.1))
    assert sol.error_params["time_offset"] == pytest.approx(0.05, abs=1e-4) and found == []
    sol, found = _delayed(moving, 0.3, TimeOffset())  # a latency, large but real, and no prior to contradict
    assert sol.error_params["time_offset"] == pytest.approx(0.3, abs=1e-4) and found == []


@pytest.fixture(scope="module")
def turning():
    data = strapdown_3d_2010(rate=10.0).imu_data()
    free = NavigationProblem(data).add(Position(t=data.t[0], value=0.0), Velocity(t=data.t[0], value=0.0))
    return data, free.solve(solver="direct").position()


@pytest.mark.parametrize("lever, warned", [((6.0, -1.0, 0.5), True), ((1.0, -0.3, 0.2), False)])
def test_lever_arm_off_the_vehicle_warns(turning, lever, warned):
    data, pos = turning
    k = np.arange(0, data.n, max(1, data.n // 12))
    prob = NavigationProblem(data, error_model=LeverArm(), grade=None)
    prob.add(Position(t=data.t[k], value=pos[k] + data.attitude[k].apply(lever), lever="estimated"),
             Velocity(t=data.t[0], value=0.0))
    sol, found = _solve(prob)
    np.testing.assert_allclose(sol.error_params[["lever_x", "lever_y", "lever_z"]], lever, atol=1e-6)
    if not warned:
        assert found == []
        return
    (msg,) = found
    assert msg.startswith("implausible estimate: lever_x = +6 m, lever_y = -1 m, lever_z = +0.5 m put the "
                          "antenna 6.1 m from the IMU, beyond the limit 5 m of a car or a walker")
    assert "heading or attitude error" in msg and "LeverArm(prior=" in msg


@pytest.mark.parametrize("lever, warned", [((-7.0, 0.3, -0.5), True), ((-1.2, 0.3, -0.5), False)])
def test_no_slip_point_off_the_car_warns(lever, warned):
    data, pos, _ = _car_drive(np.array(lever))
    k = np.arange(0, data.n, 20)
    prob = NavigationProblem(data, error_model=NhcLever(), grade=None)
    prob.add(Position(t=data.t[k], value=pos[k], name="fixes"),
             NonHolonomic(mode="hard", lever="estimated", rate=None, name="non-holonomic"))
    sol, found = _solve(prob)
    np.testing.assert_allclose(sol.error_params[["nhc_lever_x", "nhc_lever_y", "nhc_lever_z"]], lever,
                               atol=1e-6)
    if not warned:
        assert found == []
        return
    (msg,) = found
    assert msg.startswith("implausible estimate: nhc_lever_x = -7 m, nhc_lever_y = +0.3 m, nhc_lever_z = "
                          "-0.5 m put the no-slip point 7.02 m from the IMU, beyond the limit 5 m of a car")
    assert "lateral slip" in msg and "NhcLever(prior=" in msg


@pytest.mark.parametrize("yaw, pitch, warned", [(0.3, -0.1, True),
                                                (np.radians(0.6), np.radians(-0.4), False)])
def test_mounting_beyond_mounted_by_eye_warns(yaw, pitch, warned):
    data, pos, vel = _straight_drive(mounting_slopes(yaw, pitch))
    prob = NavigationProblem(data, error_model=AttitudeError(sigma=0.01) + Mounting(), grade=None)
    prob.add(Position(t=data.t[[0, -1]], value=pos[[0, -1]], name="fixes"),
             Velocity(t=data.t[0], value=vel[0], name="start velocity"),
             NonHolonomic(mode="hard", rate=2.0, mounting="estimated", name="non-holonomic"))
    sol, found = _solve(prob)
    np.testing.assert_allclose(sol.error_params[["mounting_yaw", "mounting_pitch"]], [yaw, pitch], atol=1e-6)
    if not warned:
        assert found == []
        return
    (msg,) = found  # the pitch, -5.7 deg, is within the limit
    assert msg.startswith("implausible estimate: mounting_yaw = +0.3 rad (+17.2 deg) is beyond the limit "
                          "0.175 rad (10 deg) of an IMU mounted by eye:")
    assert "mounting_pitch" not in msg and "rotate the data into the vehicle's axes" in msg


# ------------------------------------------------------------------ stand-ins
def _stub(values: dict, components):
    """A solution and a formulation with just what :func:`check` reads (no gyro rates)."""
    t = np.linspace(0.0, 100.0, 1001)
    data = SimpleNamespace(t=t, n=t.size, axes=("x", "y", "z"), is_strapdown=True, gyro=None,
                           gravity=np.array([0.0, 0.0, -9.80665]), ndim=3)
    form = SimpleNamespace(error_model=CompositeErrorModel(*components), data=data, residual="acceleration",
                           sigma_a_given=False)
    sol = SimpleNamespace(error_params=pd.Series(values, dtype=float), residuals=pd.DataFrame(), lam=1.0,
                          lam_rule="fixed", x=None, stats={})
    return sol, form


def test_a_stated_prior_moves_the_limits():
    """A known clock offset (GPS time against UTC) or a bus's lever arm, stated as the prior."""
    sol, form = _stub({"time_offset": 18.02}, [TimeOffset(prior=18.0, sigma=0.05)])
    assert pl.check(sol, form) == []
    sol, form = _stub({"time_offset": 18.02}, [TimeOffset()])
    (msg,) = pl.check(sol, form)
    assert msg.startswith("implausible estimate: time_offset = +18 s (+1.802e+04 ms) is beyond the limits")
    assert "a latency beyond any receiver's output chain" in msg
    # 0.5 s before a stated 18 s clock offset: the IMU's stamps late, though the value is positive
    sol, form = _stub({"time_offset": 17.5}, [TimeOffset(prior=18.0, sigma=1.0)])
    (msg,) = pl.check(sol, form)
    assert msg.startswith("implausible estimate: time_offset = +17.5 s (+1.75e+04 ms) is beyond the limits "
                          "-0.1..+0.5 s of the fixes' delay (the IMU's samples stamped that much late")
    bus = {"lever_x": 8.1, "lever_y": -0.9, "lever_z": 2.8}
    sol, form = _stub(bus, [LeverArm(prior=(8.0, -1.0, 3.0), sigma=0.1)])
    assert pl.check(sol, form) == []
    sol, form = _stub(bus, [LeverArm(prior=(8.0, -1.0, 3.0), sigma=0.01)])  # 20 sigmas off in z
    (msg,) = pl.check(sol, form)
    assert msg.startswith("implausible estimate: the GNSS lever arm: lever_x = +8.1 m is 10 prior sigmas "
                          "(0.01 m) from its prior 8 m, lever_y = -0.9 m is 10 prior sigmas")
    assert "lever_z = +2.8 m is 20 prior sigmas (0.01 m) from its prior 3 m, beyond 3" in msg


def test_each_component_named_and_degenerate_parameters_left_out():
    vals = {"time_offset": 0.45, "mounting_yaw": 0.25, "mounting_pitch": -0.2,
            "nhc_lever_x": -1.2, "nhc_lever_y": 0.2, "nhc_lever_z": -0.4}
    comps = [TimeOffset(sigma=0.1), Mounting(sigma=0.02), NhcLever(sigma=2.0)]
    sol, form = _stub(vals, comps)
    delay, mount = pl.check(sol, form)
    assert delay.startswith("implausible estimate: the fixes' delay: time_offset = +0.45 s (+450 ms) is "
                            "4.5 prior sigmas")
    assert mount.startswith("implausible estimate: mounting_yaw = +0.25 rad (+14.3 deg), mounting_pitch = "
                            "-0.2 rad (-11.5 deg) is beyond the limit 0.175 rad")
    assert "; up to 12.5 prior sigmas from its prior (Mounting(sigma=0.02), prior 0 rad)" in mount
    # the yaw named degenerate by the conditioning check: its value says nothing, only the pitch is judged
    sol.stats = {"conditioning": {"degenerate_axes": [{"parameters": ["mounting_yaw"]}]}}
    _, mount = pl.check(sol, form)
    assert "mounting_yaw" not in mount and "mounting_pitch = -0.2 rad" in mount


def test_installation_thresholds_are_recorded(moving):
    sol, _ = _delayed(moving, 0.05, TimeOffset(sigma=0.1))
    th = sol.stats["plausibility"]["thresholds"]
    assert th["TIME_OFFSET_LATE_LIMIT"] == 0.5 and th["TIME_OFFSET_EARLY_LIMIT"] == 0.1
    assert th["LEVER_ARM_LIMIT"] == th["NHC_LEVER_LIMIT"] == 5.0
    assert th["MOUNTING_LIMIT"] == pytest.approx(np.radians(10.0))
    assert th["INSTALLATION_PRIOR_SIGMAS"] == 3.0
