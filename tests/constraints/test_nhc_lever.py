"""NonHolonomic(lever="estimated") with the NhcLever error model: where on the car the
non-holonomic constraint holds (issue 39), estimated with the navigation solution."""

from __future__ import annotations

import numpy as np
import pytest

from bvpnav import ImuData, InputError, NavigationProblem, NavModel
from bvpnav.constraints import ForwardMotion, NonHolonomic, Position
from bvpnav.error_models import AttitudeError, Bias, GyroBias, NhcLever
from bvpnav.error_models.nhc_lever import NAMES, _car_drive
from bvpnav.log import BvpnavWarning
from bvpnav.testing import check_error_model, check_item

#: The no-slip point from the IMU, m, body axes: the IMU 1.2 m ahead of the rear axle, 0.3 m
#: right of the car's middle and 0.5 m above the axle.
LEVER = np.array([-1.2, 0.3, -0.5])


def _problem(error_model, nhc: dict | None = None, every: int = 20, fixes=None, data=None, **kw):
    d, pos, _ = _car_drive(LEVER)
    data = d if data is None else data
    k = np.arange(0, data.n, every)
    prob = NavigationProblem(data, error_model=error_model, grade=None, **kw)
    prob.add(Position(t=data.t[k], value=pos[k] if fixes is None else fixes(pos[k]), name="fixes",
                      **({} if fixes is None else {"sigma": 0.01})),
             NonHolonomic(lever="estimated", name="non-holonomic", **(nhc or {"mode": "hard", "rate": None})))
    return prob, pos


def test_contracts():
    check_error_model(NhcLever)
    model = NavModel(NonHolonomic.example_model().data, NhcLever(sigma=2.0))
    check_item(NonHolonomic(lever="estimated", rate=5.0, sigma=0.1), model)
    check_item(NonHolonomic(lever="estimated", rate=5.0), model)                  # band
    check_item(ForwardMotion(lever="estimated", min_speed=0.5, rate=5.0), model)


def test_rows_are_omega_cross_the_offset_and_attitude_free():
    data = NonHolonomic.example_model().data
    model = NavModel(data, Bias() + NhcLever(sigma=2.0))
    item = NonHolonomic(lever="estimated", axes=("x", "y", "z"), rate=None, sigma=0.1)
    rows = item.compile(model)
    known = NonHolonomic(lever=(0.0, 0.0, 0.0), axes=("x", "y", "z"), rate=None, sigma=0.1).compile(model)
    cols = model.l_index[3:]                                     # the offset's three columns after the bias
    L = rows.A[:, cols].toarray().reshape(data.n, 3, 3)          # d rho_{k,j} / d l_i
    w = np.asarray(data.gyro)
    for i in range(3):                                           # omega x e_i, sample by sample
        np.testing.assert_allclose(L[:, :, i], np.cross(w, np.eye(3)[i]), rtol=0, atol=1e-15)
    # everything else is the IMU point's rows
    other = np.setdiff1d(np.arange(model.size), cols)
    assert abs(rows.A[:, other] - known.A[:, other]).max() == 0.0
    np.testing.assert_array_equal(rows.c, known.c)
    # a known offset gives the same rows as the estimated one at that value
    x = np.zeros(model.size)
    x[cols] = LEVER
    at = NonHolonomic(lever=tuple(LEVER), axes=("x", "y", "z"), rate=None, sigma=0.1).compile(model)
    np.testing.assert_allclose(rows.value(x), at.value(x), rtol=0, atol=1e-12)
    fm = ForwardMotion(lever="estimated", min_speed=0.5, rate=None).compile(model)
    fm_at = ForwardMotion(lever=tuple(LEVER), min_speed=0.5, rate=None).compile(model)
    np.testing.assert_allclose(fm.value(x), fm_at.value(x), rtol=0, atol=1e-12)
    assert abs(fm.A[:, cols]).max() > 0.0


def test_offset_and_trajectory_recovered_exactly():
    """Noise-free car, IMU 1.2 m ahead of the rear axle: hard rows at every sample and fixes every
    2 s; the offset to 1e-9 m and the positions at every sample to 1e-8 m."""
    prob, pos = _problem(NhcLever())
    sol = prob.solve(solver="direct")
    assert sol.stats["verified"]
    got = np.array([sol.error_params[n] for n in NAMES])
    np.testing.assert_allclose(got, LEVER, rtol=0, atol=1e-9)
    np.testing.assert_allclose(sol.position(), pos, rtol=0, atol=1e-8)
    assert np.max(np.abs(sol.item_residuals["non-holonomic"])) < 1e-9


def test_at_the_imu_the_same_rows_miss():
    """The failure the option removes: the same hard rows at the IMU point cannot hold on this
    drive (the IMU moves sideways at 1.2 m times the yaw rate), so the solve bends the path."""
    d, pos, _ = _car_drive(LEVER)
    k = np.arange(0, d.n, 20)
    prob = NavigationProblem(d, grade=None).add(Position(t=d.t[k], value=pos[k], name="fixes"),
                                                NonHolonomic(sigma=0.01, rate=None, name="non-holonomic"))
    err = np.max(np.linalg.norm(prob.solve(solver="direct").position() - pos, axis=1))
    assert err > 0.05


def test_through_the_attitude_loop():
    """With an initial attitude error estimated (the attitude loop re-linearizes the rows) the
    offset and the attitude come back to 1e-6."""
    prob, _ = _problem(AttitudeError(sigma=0.01) + NhcLever(), {"mode": "hard", "rate": 2.0})
    sol = prob.solve(solver="direct")
    assert sol.stats["verified"]
    np.testing.assert_allclose([sol.error_params[n] for n in NAMES], LEVER, rtol=0, atol=1e-6)
    assert max(abs(sol.error_params[f"attitude_{a}"]) for a in "xyz") < 1e-6


def test_with_a_gyro_bias_the_corrected_rates_carry_the_offset():
    """Gyro samples 2e-3 rad/s high on every axis, a GyroBias estimated: the rows take the
    corrected rates of the loop's point (omega x l with the biased rates would miss by 2.6 mm/s),
    so the offset and the bias come back to 1e-6."""
    d, pos, _ = _car_drive(LEVER)
    bias = np.array([2e-3, -2e-3, 2e-3])
    data = ImuData.from_gyro(d.t, d.specific_force, np.asarray(d.gyro) + bias,
                             initial_attitude=d.attitude[0], gravity=d.gravity, checks=False)
    prob, _ = _problem(GyroBias() + NhcLever(), {"mode": "hard", "rate": 2.0}, every=10, data=data)
    sol = prob.solve(solver="direct", attitude={"tol": 1e-11})
    assert sol.stats["verified"]
    np.testing.assert_allclose([sol.error_params[f"gyro_bias_{a}"] for a in "xyz"], bias, rtol=0, atol=1e-8)
    np.testing.assert_allclose([sol.error_params[n] for n in NAMES], LEVER, rtol=0, atol=1e-6)


def test_with_node_states():
    """The node-state loop: the offset within 0.2 mm (noise-free, fixes every second, soft rows
    beside the 2 m prior; 0.06 mm measured)."""
    from bvpnav.error_models import ErrorStates

    em = ErrorStates(arw=1e-4, gyro_drift=1e-5, acc_drift=1e-4, attitude_sigma=[0.01, 0.01, 0.01],
                     gyro_sigma=1e-3, acc_sigma=0.01) + NhcLever(sigma=2.0)
    d, pos, _ = _car_drive(LEVER)
    k = np.arange(0, d.n, 10)
    prob = NavigationProblem(d, error_model=em, sigma_a=0.01, grade=None)
    prob.add(Position(t=d.t[k], value=pos[k], sigma=0.01, name="fixes"),
             NonHolonomic(lever="estimated", sigma=0.001, rate=None, name="non-holonomic"))
    with pytest.warns(BvpnavWarning, match="misfit"):  # noise-free: the residuals are far below the sigmas
        sol = prob.solve(solver="direct")
    assert sol.stats["verified"]
    np.testing.assert_allclose([sol.error_params[n] for n in NAMES], LEVER, rtol=0, atol=2e-4)


@pytest.mark.filterwarnings("ignore:uncertainty. the a-posteriori variance")
def test_uncertainty_reports_the_offsets_std():
    """Fixes with 1 cm noise and soft rows: the std is far below the 2 m prior and the estimate
    within 4 of them of the truth."""
    rng = np.random.default_rng(5)
    prob, _ = _problem(NhcLever(sigma=2.0), {"sigma": 0.01, "rate": 5.0}, every=10,
                       fixes=lambda p: p + 0.01 * rng.standard_normal(p.shape), sigma_a=0.01)
    sol = prob.solve(solver="direct", uncertainty=True)
    std = sol.error_params_std
    for n, truth in zip(NAMES, LEVER, strict=True):
        assert 0.0 < std[n] < 0.1                   # 0.006 (x), 0.035 (y, z) measured
        assert abs(sol.error_params[n] - truth) < 4.0 * std[n]


def test_no_gyro_refused_naming_the_item():
    d, pos, _ = _car_drive(LEVER)
    data = ImuData(d.t, specific_force=d.specific_force, attitude=d.attitude, gravity=d.gravity)
    assert getattr(data, "gyro", None) is None
    prob, _ = _problem(NhcLever(sigma=2.0), data=data)
    with pytest.raises(InputError, match=r"non-holonomic.*lever='estimated' needs the gyro rates"):
        prob.solve(solver="direct")


def test_missing_model_refused_naming_the_item():
    prob, _ = _problem(Bias())
    with pytest.raises(InputError, match=r"non-holonomic.*NhcLever\(sigma=\.\.\.\)"):
        prob.solve(solver="direct")


@pytest.mark.parametrize("make, match", [
    (lambda: NonHolonomic(lever="guess"), "lever='guess'"),
    (lambda: ForwardMotion(lever="somewhere"), "lever='somewhere'"),
    (lambda: NhcLever(sigma=[1.0, 2.0]), "sigma has 2 values"),
    (lambda: NhcLever(sigma=1.0, axes=("x",)), "axes= is not supported"),
])
def test_bad_arguments_refused(make, match):
    with pytest.raises(InputError, match=match):
        make()
