"""NonHolonomic(slip=...) with the SideSlip error model: a car's rear axle slides outwards in a turn
at v_y = -K f_y v_x (issue 39, the 10 s gap), K known or estimated with the navigation solution."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from _helpers import hard_vehicle_rows_solve

from bvpnav import InputError, NavigationProblem, NavModel
from bvpnav.constraints import NonHolonomic, Position
from bvpnav.error_models import AttitudeError, SideSlip
from bvpnav.error_models.side_slip import SIDE_SLIP_PRIOR, SIDE_SLIP_SIGMA, slip_drive
from bvpnav.log import BvpnavWarning
from bvpnav.model import LinearizationPoint
from bvpnav.testing import check_error_model, check_item

#: The drive's cornering compliance, s^2/m (4.6 deg/g).
K = 0.008


def _fixes(data, pos, every: int = 20):
    k = np.arange(0, data.n, every)
    return Position(t=data.t[k], value=pos[k], name="fixes")


def test_contracts():
    check_error_model(SideSlip)
    data = copy.copy(NonHolonomic.example_model().data)
    vel = np.column_stack([5.0 + 0.1 * data.t, 0.2 * np.sin(data.t), 0.05 * np.cos(data.t)])
    data.body_point = LinearizationPoint(velocity=vel, names=(), psi=np.zeros((data.n, 3, 0)))
    model = NavModel(data, AttitudeError(sigma=0.01) + SideSlip(sigma=SIDE_SLIP_SIGMA, prior=SIDE_SLIP_PRIOR))
    # axes ("z", "y"): the contract restricts the item to its second axis, and slip needs "y"
    check_item(NonHolonomic(axes=("z", "y"), rate=5.0, slip="estimated", sigma=0.1), model)
    check_item(NonHolonomic(axes=("z", "y"), rate=5.0, slip="estimated"), model)        # band
    check_item(NonHolonomic(axes=("z", "y"), rate=5.0, slip=0.007, sigma=0.1),
               NavModel(NonHolonomic.example_model().data))
    # the estimated rows: f_y v0_x in the compliance's column on the lateral rows, nothing elsewhere
    rows = NonHolonomic(rate=5.0, slip="estimated", sigma=0.1).compile(model)
    col = rows.A[:, model.l_index[3]].toarray().ravel()
    tk = NonHolonomic(rate=5.0).instants(model)
    k = np.searchsorted(data.t, tk)                           # the instants are samples
    vx = np.einsum("ki,ki->k", data.attitude[k].as_matrix()[:, :, 0], vel[k])
    np.testing.assert_allclose(col[0::2], data.specific_force[k, 1] * vx, rtol=1e-12)
    assert not np.any(col[1::2])


def test_known_slip_rows_are_the_lateral_rows_plus_k_fy_times_the_forward_ones():
    model = NonHolonomic.example_model()
    data = model.data
    x = np.random.default_rng(3).standard_normal(model.size)
    kw = {"rate": None, "sigma": 0.1, "lever": (-0.8, 0.1, -0.3)}
    plain = NonHolonomic(axes=("x", "y", "z"), **kw).compile(model).value(x).reshape(-1, 3)
    slid = NonHolonomic(axes=("z", "y"), slip=K, **kw).compile(model).value(x).reshape(-1, 2)
    np.testing.assert_allclose(slid[:, 1], plain[:, 1] + K * data.specific_force[:, 1] * plain[:, 0],
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(slid[:, 0], plain[:, 2], rtol=0, atol=1e-12)
    # slip=0 is the item without slip
    zero = NonHolonomic(axes=("y", "z"), slip=0.0, **kw).compile(model)
    np.testing.assert_allclose(zero.value(x), plain[:, 1:].ravel(), rtol=0, atol=1e-15)


def test_drive_has_the_slip():
    """The simulated truth: the IMU (at the rear axle) slides outwards at K f_y v_x at every sample."""
    data, _, vel = slip_drive(K)
    vb = np.einsum("kji,kj->ki", data.attitude.as_matrix(), vel)
    fy = data.specific_force[:, 1]
    np.testing.assert_allclose(vb[:, 1], -K * fy * vb[:, 0], rtol=0, atol=1e-13)
    assert np.max(np.abs(fy)) > 3.0 and np.max(np.abs(vb[:, 1])) > 0.25   # a real slip: 3.2 m/s^2, 0.25 m/s


def test_known_slip_holds_the_truth_and_no_slip_misses():
    data, pos, _ = slip_drive(K)
    for slip, ok in ((K, True), (None, False)):
        prob = NavigationProblem(data, grade=None).add(
            _fixes(data, pos), NonHolonomic(mode="hard", slip=slip, rate=None, name="non-holonomic"))
        sol = prob.solve(solver="direct")
        err = np.max(np.linalg.norm(sol.position() - pos, axis=1))
        if ok:
            assert sol.stats["verified"] and err < 1e-8
        else:
            assert err > 0.05                                    # the hard rows without slip bend the path


def test_compliance_and_trajectory_recovered_exactly():
    """Estimated through the attitude loop (an initial attitude error estimated, no prior on K):
    K to 1e-6 relative, the positions to 1e-8 m."""
    prob, truth, opts = SideSlip.example_recovery(NavigationProblem)
    data, pos, _ = slip_drive(K)
    sol = prob.solve(**opts)
    assert sol.stats["verified"]
    assert abs(sol.error_params["side_slip"] / truth["side_slip"] - 1.0) < 1e-6
    np.testing.assert_allclose(sol.position(), pos, rtol=0, atol=1e-8)


def test_with_a_lever_and_node_states():
    """The rear axle 1.2 m behind the IMU (known lever) and node states (soft rows, the published
    prior): K within 2e-4 relative and the positions within 0.1 mm; the node-state loop is not
    exact on these drives (as NhcLever's test)."""
    from bvpnav.error_models import ErrorStates

    lever = (-1.2, 0.0, 0.0)
    data, pos, _ = slip_drive(K, lever=lever)
    em = ErrorStates(arw=1e-4, gyro_drift=1e-5, acc_drift=1e-4, attitude_sigma=[0.01, 0.01, 0.01],
                     gyro_sigma=1e-3, acc_sigma=0.01) + SideSlip(sigma=SIDE_SLIP_SIGMA, prior=SIDE_SLIP_PRIOR)
    k = np.arange(0, data.n, 10)
    prob = NavigationProblem(data, error_model=em, sigma_a=0.01, grade=None)
    prob.add(Position(t=data.t[k], value=pos[k], sigma=0.01, name="fixes"),
             NonHolonomic(lever=lever, slip="estimated", sigma=1e-3, rate=None, name="non-holonomic"))
    with pytest.warns(BvpnavWarning, match="misfit"):  # noise-free: the residuals are far below the sigmas
        sol = prob.solve(solver="direct")
    assert sol.stats["verified"]
    assert abs(sol.error_params["side_slip"] / K - 1.0) < 2e-4
    np.testing.assert_allclose(sol.position(), pos, rtol=0, atol=1e-4)


@pytest.mark.parametrize("lever", [(-1.2, 0.5, 0.5), (0.3, -0.4, 0.8)])
def test_estimated_slip_at_a_point_off_the_x_axis(lever):
    """The slip is K f_y times the forward speed of the rows' point, not the IMU's: they differ by
    (omega x l)_x = w_y l_z - w_z l_y, zero only for a point on the body's x axis. Hard rows at
    such a point: K to 1e-6 relative and the path to 1e-8 m."""
    data, pos, _ = slip_drive(K, lever=lever)
    sol = hard_vehicle_rows_solve(data, pos, AttitudeError(sigma=0.01) + SideSlip(), lever=lever,
                                  slip="estimated")
    assert abs(sol.error_params["side_slip"] / K - 1.0) < 1e-6
    np.testing.assert_allclose(sol.position(), pos, rtol=0, atol=1e-8)


@pytest.mark.parametrize(("kw", "match"), [
    ({"slip": -0.004}, r"slip=-0.004 s\^2/m is outside \[0, 0.05\].*into the turn"),
    ({"slip": 0.2}, r"outside \[0, 0.05\]"),
    ({"slip": float("nan")}, r"outside \[0, 0.05\]"),
    ({"slip": "yes"}, r"slip='yes'; give the rear axle's cornering compliance K in s\^2/m"),
    ({"slip": True}, r"slip=True; give"),
    ({"slip": [0.1, 0.2]}, r"slip=\[0.1, 0.2\]; give"),
    ({"slip": 0.007, "axes": ("z",)}, r"the side slip acts on the lateral rows: give axes with 'y'"),
])
def test_bad_values_refused_naming_the_item(kw, match):
    with pytest.raises(InputError, match=r"NonHolonomic.*" + match):
        NonHolonomic(**kw)


def test_estimated_without_its_model_or_a_loop_refused():
    data, pos, _ = slip_drive(K)
    prob = NavigationProblem(data, error_model=AttitudeError(sigma=0.01), grade=None).add(
        _fixes(data, pos), NonHolonomic(slip="estimated", sigma=0.1, name="nhc"))
    with pytest.raises(InputError, match=r"nhc.*needs the error model SideSlip\(sigma=...\)"):
        prob.solve(solver="direct")
    prob = NavigationProblem(data, error_model=SideSlip(sigma=0.004), grade=None).add(
        _fixes(data, pos), NonHolonomic(slip="estimated", sigma=0.1, name="nhc"))
    with pytest.raises(InputError, match=r"slip='estimated' is linearized about the velocity of the attitude "
                                         r"loop.*slip=K in s\^2/m"):
        prob.solve(solver="direct")


def test_absurd_compliance_warned():
    """A drive whose IMU slides at 0.03 s^2/m (17 deg/g: no road tyre) is fitted, and warned."""
    data, pos, _ = slip_drive(0.03)
    prob = NavigationProblem(data, error_model=AttitudeError(sigma=0.01) + SideSlip(), grade=None).add(
        _fixes(data, pos), NonHolonomic(mode="hard", slip="estimated", rate=2.0, name="nhc"))
    with pytest.warns(BvpnavWarning, match="implausible estimate: side_slip"):
        sol = prob.solve(solver="direct")
    assert abs(sol.error_params["side_slip"] - 0.03) < 1e-6
    msg = next(w for w in sol.warnings if "side_slip" in w)
    assert msg.startswith("implausible estimate: side_slip = +0.03 s^2/m (+16.9 deg/g) is beyond the limits "
                          "-0.002..0.02 s^2/m of a road tyre")
    assert "Mounting" in msg and "NhcLever" in msg
    # the published prior does not move the limits (a tyre's physics, counted from zero)
    wide = AttitudeError(sigma=0.01) + SideSlip(sigma=1.0, prior=SIDE_SLIP_PRIOR)
    lax = NavigationProblem(*slip_drive(0.025)[:1], grade=None, error_model=wide)
    lax.add(_fixes(data, slip_drive(0.025)[1]),
            NonHolonomic(mode="hard", slip="estimated", rate=2.0, name="nhc"))
    with pytest.warns(BvpnavWarning, match="implausible estimate: side_slip = \\+0.025"):
        lax.solve(solver="direct")
    ok = NavigationProblem(*slip_drive(K)[:1], error_model=AttitudeError(sigma=0.01) + SideSlip(), grade=None)
    ok.add(_fixes(data, slip_drive(K)[1]), NonHolonomic(mode="hard", slip="estimated", rate=2.0, name="nhc"))
    assert not [w for w in ok.solve(solver="direct").warnings if "side_slip" in w]
