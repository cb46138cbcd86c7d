"""NonHolonomic(mounting="estimated") with the Mounting error model: the IMU's yaw and pitch
boresight against the vehicle (issue 39)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from _helpers import hard_vehicle_rows_solve
from scipy.spatial.transform import Rotation

from bvpnav import InputError, NavigationProblem, NavModel
from bvpnav.constraints import NonHolonomic, Position, Velocity
from bvpnav.error_models import AttitudeError, Bias, Mounting
from bvpnav.error_models.mounting import _straight_drive, mounting_angles, mounting_slopes
from bvpnav.model import LinearizationPoint
from bvpnav.testing import check_error_model, check_item

YAW, PITCH = np.radians(0.6), np.radians(-0.4)


def _drive_problem(mounting: str | None, error_model, nhc: dict | None = None):
    data, pos, vel = _straight_drive(mounting_slopes(YAW, PITCH))
    prob = NavigationProblem(data, error_model=error_model, grade=None)
    prob.add(Position(t=data.t[[0, -1]], value=pos[[0, -1]], name="fixes"),
             Velocity(t=data.t[0], value=vel[0], name="start velocity"),
             NonHolonomic(rate=2.0, mounting=mounting, name="non-holonomic", **(nhc or {"mode": "hard"})))
    return prob


def test_contract():
    check_error_model(Mounting)
    data = copy.copy(NonHolonomic.example_model().data)
    vel = np.column_stack([5.0 + 0.1 * data.t, 0.2 * np.sin(data.t), 0.05 * np.cos(data.t)])
    data.body_point = LinearizationPoint(velocity=vel, names=(), psi=np.zeros((data.n, 3, 0)))
    model = NavModel(data, AttitudeError(sigma=0.01) + Mounting(sigma=0.02))
    check_item(NonHolonomic(rate=5.0, mounting="estimated", sigma=0.1), model)
    rows = NonHolonomic(rate=5.0, mounting="estimated", sigma=0.1).compile(model)
    mount = rows.A[:, model.l_index[3:]].toarray()           # the slopes' columns: -v_x (y), +v_x (z)
    tk = NonHolonomic(rate=5.0).instants(model)
    k = np.searchsorted(data.t, tk)                           # the instants are samples
    vx = np.einsum("ki,ki->k", data.attitude[k].as_matrix()[:, :, 0], vel[k])   # e_x^T C^T v
    np.testing.assert_allclose(mount[0::2, 0], -vx, rtol=1e-12)
    np.testing.assert_allclose(mount[1::2, 1], vx, rtol=1e-12)
    assert not np.any(mount[0::2, 1]) and not np.any(mount[1::2, 0])


def test_angles_and_slopes_are_inverse_and_give_the_forward_axis():
    for yaw, pitch in ((0.3, -0.2), (-0.01, 0.004), (0.0, 0.0)):
        s = mounting_slopes(yaw, pitch)
        np.testing.assert_allclose(mounting_angles(s), [yaw, pitch], rtol=0, atol=1e-15)
        u = np.array([1.0, s[0], -s[1]]) / np.linalg.norm([1.0, s[0], -s[1]])
        np.testing.assert_allclose(u, Rotation.from_euler("ZY", [yaw, pitch]).apply([1.0, 0.0, 0.0]),
                                   rtol=0, atol=1e-15)


def test_mounting_recovered_exactly_and_the_rows_hold():
    sol = _drive_problem("estimated", AttitudeError(sigma=0.01) + Mounting()).solve(solver="direct")
    assert sol.stats["verified"]
    assert abs(sol.error_params["mounting_yaw"] - YAW) < 1e-9
    assert abs(sol.error_params["mounting_pitch"] - PITCH) < 1e-9
    # the attitude is the data's: nothing turned it to absorb the boresight
    assert max(abs(sol.error_params[f"attitude_{a}"]) for a in "xyz") < 1e-9
    assert np.max(np.abs(sol.item_residuals["non-holonomic"])) < 1e-9


def test_without_the_mounting_the_constraint_turns_the_attitude_by_the_boresight():
    """The failure the option removes: body-axis rows (soft) on a car whose IMU is 0.6 deg off
    turn the estimated heading towards the direction of travel, by about the boresight."""
    sol = _drive_problem(None, AttitudeError(sigma=0.05),
                         {"sigma": 0.001}).solve(solver="direct")
    yaw_turn = sol.error_params["attitude_z"]
    assert 0.5 * YAW < abs(yaw_turn) < 1.5 * YAW


# exact rows: the residuals are below the stated sigmas, and the check says so
@pytest.mark.filterwarnings("ignore:uncertainty. the a-posteriori variance")
def test_uncertainty_reports_the_angles_std():
    data, pos, vel = _straight_drive(mounting_slopes(YAW, PITCH))
    rng = np.random.default_rng(3)
    k = np.arange(0, data.n, 10)
    prob = NavigationProblem(data, error_model=AttitudeError(sigma=0.01) + Mounting(sigma=0.02),
                             sigma_a=0.01, grade=None)
    prob.add(Position(t=data.t[k], value=pos[k] + 0.01 * rng.standard_normal((k.size, 3)), sigma=0.01,
                      name="fixes"),
             NonHolonomic(rate=5.0, mounting="estimated", sigma=0.01, name="non-holonomic"))
    sol = prob.solve(solver="direct", uncertainty=True)
    std = sol.error_params_std
    assert {"mounting_yaw", "mounting_pitch"} <= set(std.index)
    for name, truth in (("mounting_yaw", YAW), ("mounting_pitch", PITCH)):
        assert 0.0 < std[name] < 0.02                     # below the prior: the data inform it
        assert abs(sol.error_params[name] - truth) < 4.0 * std[name]


@pytest.mark.parametrize("kwargs, match", [
    ({"mounting": "yes"}, "mounting='yes'"),
    ({"mounting": "estimated", "axes": ("x", "y")}, "axes among"),
])
def test_bad_arguments_refused(kwargs, match):
    with pytest.raises(InputError, match=match):
        NonHolonomic(**kwargs)


def test_missing_model_or_loop_refused_naming_the_item():
    with pytest.raises(InputError, match=r"non-holonomic.*Mounting\(sigma=\.\.\.\)"):
        _drive_problem("estimated", AttitudeError(sigma=0.01)).solve(solver="direct")
    with pytest.raises(InputError, match="non-holonomic.*no attitude error model"):
        _drive_problem("estimated", Bias() + Mounting(sigma=0.02)).solve(solver="direct")


@pytest.mark.filterwarnings("ignore:misfit")   # noise-free data: the residuals are far below the sigmas
def test_with_node_states():
    """The node-state loop linearizes the rows about its last step's velocity; with fixes every
    second the heading and the yaw boresight trade only through the priors (the drive does not
    turn), so the yaw comes back within 0.05 deg (0.023 measured) and the pitch within 0.005."""
    from bvpnav.error_models import ErrorStates

    data, pos, vel = _straight_drive(mounting_slopes(YAW, PITCH))
    k = np.arange(0, data.n, 10)
    em = ErrorStates(arw=1e-4, gyro_drift=1e-5, acc_drift=1e-4, attitude_sigma=[0.01, 0.01, 0.01],
                     gyro_sigma=1e-3, acc_sigma=0.01) + Mounting(sigma=0.05)
    prob = NavigationProblem(data, error_model=em, sigma_a=0.01, grade=None)
    prob.add(Position(t=data.t[k], value=pos[k], sigma=0.01, name="fixes"),
             NonHolonomic(rate=5.0, mounting="estimated", sigma=0.01, name="non-holonomic"))
    sol = prob.solve(solver="direct")
    assert sol.stats["verified"]
    assert abs(np.degrees(sol.error_params["mounting_yaw"] - YAW)) < 0.05
    assert abs(np.degrees(sol.error_params["mounting_pitch"] - PITCH)) < 0.005


@pytest.mark.parametrize("lever", [(-1.2, 0.5, 0.5), (0.3, -0.4, 0.8)])
def test_mounting_at_a_point_off_the_x_axis_on_a_winding_drive(lever):
    """The mounting term is the slope times the forward speed of the rows' point, not the IMU's:
    they differ by (omega x l)_x = w_y l_z - w_z l_y on a turning, pitching drive. Hard rows at
    such a point: both angles to 1e-9 rad and the path to 1e-8 m."""
    from bvpnav.error_models.nhc_lever import _car_drive

    data, pos, _ = _car_drive(np.asarray(lever), slopes=mounting_slopes(YAW, PITCH))
    sol = hard_vehicle_rows_solve(data, pos, AttitudeError(sigma=0.01) + Mounting(), lever=lever,
                                  mounting="estimated")
    assert abs(sol.error_params["mounting_yaw"] - YAW) < 1e-9
    assert abs(sol.error_params["mounting_pitch"] - PITCH) < 1e-9
    np.testing.assert_allclose(sol.position(), pos, rtol=0, atol=1e-8)
