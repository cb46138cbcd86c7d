"""Diagnostics that say the model does not fit (issue 16, item 4).

Every case is built to trigger one warning (or to trigger none):

- misfit: a 1-D recording (T = 100 s at 20 Hz, acceleration ``0.3 sin(0.2 t)`` m/s^2)
  measured with white noise of 0.5 m/s^2 while sigma_a = 0.05 is stated. With exact
  hard fixes every 0.5 s the variance factor estimates ``(0.5 / 0.05)^2 = 100`` over 199
  degrees of freedom (its square root within ``1/sqrt(2 f)`` = 5 %); with fixes at every
  sample the residual is the noise itself, ``rms(w / sigma_a) = 10``. The same data with
  sigma_a = 0.5 stated for noise 0.05 gives a variance factor of 0.01: overstated.
- implausible estimates: strapdown data of a slow level circle (roll and pitch within
  0.03 rad) whose given attitude drifts in tilt by up to 0.02 rad (unmodelled), solved
  with ``Bias() + UnknownGravity() + Misalignment()``: the issue's absurd answer
  (bias_z ~ 9.7 m/s^2 with gravity_z ~ +0.1 m/s^2, misalignments of radians); wrong data
  (1.5 x the acceleration; a 2 m/s^2 offset) force a large scale factor and bias.
- gyro and attitude checks: :func:`check` on stand-ins of a solution and a formulation
  with the real ``GyroBias``, ``AttitudeError`` and ``GyroScaleFactor`` components.
"""

from __future__ import annotations

import warnings
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import Bias, Misalignment, ScaleFactor, UnknownGravity
from bvpnav.log import BvpnavWarning
from bvpnav.solve import plausibility as pl

T, RATE = 100.0, 20
TT = np.arange(0.0, T + 1e-9, 1.0 / RATE)
ACC = 0.3 * np.sin(0.2 * TT)  # m/s^2; from x(0) = 0, v(0) = 1.5 m/s
POS = 0.3 * (TT / 0.2 - np.sin(0.2 * TT) / 0.04)


def _solve(prob, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sol = prob.solve(solver="direct", **kw)
    return sol, [str(w.message) for w in caught if issubclass(w.category, BvpnavWarning)]


def line(noise: float, sigma_a: float | None, every: int, seed: int = 1, error_model=None, acc=None,
         sigma: float | None = None):
    """The 1-D recording measured with ``noise`` (m/s^2) and exact fixes every ``every`` samples
    (hard, or soft with ``sigma`` in m)."""
    rng = np.random.default_rng(seed)
    a = (ACC if acc is None else acc) + rng.normal(0.0, noise, TT.size)
    data = bvpnav.ImuData(TT, a[:, None], axes=("x",))
    prob = bvpnav.NavigationProblem(data, sigma_a=sigma_a, error_model=error_model)
    kw = {} if sigma is None else {"sigma": sigma, "mode": "soft"}
    prob.add(Position(t=TT[::every], value=POS[::every], **kw))
    return prob


def _misfit(ws):
    return [w for w in ws if w.startswith("misfit")]


def _implausible(ws):
    return [w for w in ws if w.startswith("implausible")]


# ---------------------------------------------------------------- misfit
def test_understated_sigma_a_warns_with_the_right_ratio():
    sol, issued = _solve(line(0.5, 0.05, 10))
    rep = sol.stats["plausibility"]
    assert rep["dof"] == 199  # 201 fixes - 2 initial conditions
    assert rep["noise_ratio"] == pytest.approx(10.0, rel=0.10)
    (msg,) = _misfit(sol.warnings)
    assert "sigma_a = 0.05 m/s^2" in msg and "drifting bias" in msg and "wrong attitude" in msg
    assert f"variance factor is {rep['variance_factor']:.3g}" in msg
    assert msg in issued  # issued as a BvpnavWarning too, once
    assert issued.count(msg) == 1


def test_residual_as_large_as_the_noise_names_the_axis_and_ratio():
    sol, _ = _solve(line(0.5, 0.05, 1))  # a fix at every sample: w is the noise itself
    rep = sol.stats["plausibility"]
    assert rep["residual_ratio"]["x"] == pytest.approx(10.0, rel=0.10)
    assert rep["residual_ratio_overall"] == pytest.approx(10.0, rel=0.10)
    (msg,) = _misfit(sol.warnings)
    assert msg.startswith(f"misfit: the acceleration residual is {rep['residual_ratio']['x']:.2g} x the "
                          "stated sigma_a = 0.05 m/s^2 on axis x")


def test_overstated_sigma_a_warns():
    sol, _ = _solve(line(0.05, 0.5, 10))
    rep = sol.stats["plausibility"]
    assert rep["noise_ratio"] == pytest.approx(0.1, rel=0.10)
    (msg,) = _misfit(sol.warnings)
    assert "probably overstated" in msg and "sigma_a = 0.5 m/s^2" in msg


def test_a_fitting_model_does_not_warn():
    sol, issued = _solve(line(0.05, 0.05, 10))
    rep = sol.stats["plausibility"]
    assert rep["variance_factor"] == pytest.approx(1.0, abs=0.25)
    assert rep["residual_ratio_overall"] < 1.0  # sparse fixes see a part of the noise only
    assert not _misfit(sol.warnings) and not _implausible(sol.warnings)
    assert not _misfit(issued)


def test_sparse_fixes_see_a_small_residual_without_a_warning():
    """rms(w / sigma_a) is far below 1 for correct noise when fixes are sparse (every 5 s):
    the low side is judged on the variance factor, not on the residual's RMS."""
    sol, _ = _solve(line(0.05, 0.05, 100))
    rep = sol.stats["plausibility"]
    assert rep["residual_ratio_overall"] < pl.MISFIT_LOW
    assert not _misfit(sol.warnings)


def test_without_a_stated_sigma_a_there_is_no_misfit_check():
    sol, _ = _solve(line(0.5, None, 10))
    rep = sol.stats["plausibility"]
    assert "residual_ratio" not in rep and not _misfit(sol.warnings)


def test_a_rule_chosen_lam_skips_the_variance_factor():
    sol, _ = _solve(line(0.05, 0.05, 10, sigma=0.01), lam="gcv")
    rep = sol.stats["plausibility"]
    assert rep["variance_factor"] is None and rep["noise_ratio"] is None


# ------------------------------------------------------- implausible estimates
def _circle_with_tilt_drift(rate: int = 50, duration: float = 60.0):
    """A slow level circle (radius 20 m) whose given attitude drifts in tilt (unmodelled)."""
    t = np.arange(0.0, duration + 1e-9, 1.0 / rate)
    w = 2 * np.pi / duration
    pos = np.column_stack([20 * np.sin(w * t), 20 * (1 - np.cos(w * t)), 0 * t])
    acc = np.column_stack([-20 * w**2 * np.sin(w * t), 20 * w**2 * np.cos(w * t), 0 * t])
    ypr = np.column_stack([w * t, 0.03 * np.sin(0.7 * t), 0.03 * np.cos(0.5 * t)])
    true = Rotation.from_euler("ZYX", ypr)
    f = true.inv().apply(acc - np.array([0.0, 0.0, -9.80665]))
    drift = Rotation.from_rotvec(np.column_stack([0.02 * t / duration * np.sin(0.3 * t), 0.02 * t / duration,
                                                  0 * t]))
    data = bvpnav.ImuData(t, specific_force=f, attitude=drift * true)
    return data, t, pos, rate


def test_gravity_and_bias_that_cannot_be_told_apart():
    """The issue's case: bias_z ~ g next to a gravity_z of the wrong sign, misalignments of
    radians, whatever the singular-value test says."""
    data, t, pos, rate = _circle_with_tilt_drift()
    em = Bias() + UnknownGravity() + Misalignment()
    prob = bvpnav.NavigationProblem(data, sigma_a=0.05, error_model=em)
    prob.add(Position(t=t[::10 * rate], value=pos[::10 * rate]))
    sol, issued = _solve(prob)
    ep = sol.error_params
    assert ep["bias_z"] > 5.0 and abs(ep["gravity_z"]) < 1.0  # the absurd answer
    (both,) = [w for w in sol.warnings if "gravity and bias cannot be told apart here" in w]
    assert f"bias_z = {ep['bias_z']:+.3g} m/s^2" in both
    assert f"gravity_z = {ep['gravity_z']:+.3g} m/s^2" in both
    assert "UnknownGravity" in both and both in issued
    (mis,) = [w for w in sol.warnings if "misalignment_" in w and w.startswith("implausible")]
    assert "meaningless" in mis and "AttitudeError()" in mis
    assert f"misalignment_yx = {ep['misalignment_yx']:+.3g} rad" in mis


def test_gravity_alone_far_from_its_magnitude():
    """Data made with |g| = 9.0 m/s^2 (a wrong gravity), solved with UnknownGravity only."""
    data, t, pos, rate = _circle_with_tilt_drift()
    f = data.specific_force + data.attitude.inv().apply(np.array([0.0, 0.0, -0.8]))  # reads 0.8 less up
    data = bvpnav.ImuData(t, specific_force=f, attitude=data.attitude)
    prob = bvpnav.NavigationProblem(data, sigma_a=0.05, error_model=UnknownGravity(axes="z"))
    prob.add(Position(t=t[::10 * rate], value=pos[::10 * rate]))
    sol, _ = _solve(prob)
    (msg,) = [w for w in sol.warnings if w.startswith("implausible estimate: gravity")]
    assert "gravity_z" in msg and "limit +-0.5" in msg
    assert not [w for w in sol.warnings if "bias" in w and w.startswith("implausible")]


def test_scale_factor_forced_large_by_wrong_data():
    """The accelerometer reads 1.5 x the acceleration: scale_x = +0.5 (beyond +-0.2)."""
    sol, _ = _solve(line(0.0, None, 20, acc=1.5 * ACC, error_model=ScaleFactor()))
    assert sol.error_params["scale_x"] == pytest.approx(0.5, rel=1e-3)
    (msg,) = _implausible(sol.warnings)
    assert msg.startswith("implausible estimate: scale_x = +0.5 (+50 %) is beyond the limit +-0.2")


def test_bias_comparable_to_g():
    """A 2 m/s^2 offset (0.2 g): bias_x = 2 with the tilt that would put it there."""
    sol, _ = _solve(line(0.0, None, 20, acc=ACC + 2.0, error_model=Bias()))
    assert sol.error_params["bias_x"] == pytest.approx(2.0, rel=1e-6)
    (msg,) = _implausible(sol.warnings)
    assert "bias_x = +2 m/s^2" in msg and "0.2 g" in msg and "11.8 deg" in msg


def test_plausible_sensor_errors_do_not_warn():
    """The 2010 nine-parameter case (consumer-grade bias, scale and a tilted gravity) is fine."""
    from bvpnav.simulate import strapdown_3d_2010

    sim = strapdown_3d_2010(rate=50, duration=20, noise=0.0)
    prob = bvpnav.NavigationProblem(sim.imu_data(), error_model=ScaleFactor() + Bias() + UnknownGravity())
    tk = np.arange(0.0, 21.0, 1.0)
    prob.add(Position(t=tk, value=sim.position(tk)))
    sol, _ = _solve(prob)
    assert not _implausible(sol.warnings)


# ----------------------------------------------- gyro and attitude (stand-ins)
def _stub(values: dict, components, gyro=None, n: int = 1001, duration: float = 100.0):
    """A solution and a formulation with just what :func:`check` reads."""
    t = np.linspace(0.0, duration, n)
    data = SimpleNamespace(t=t, n=n, axes=("x", "y", "z"), is_strapdown=True, gyro=gyro,
                           gravity=np.array([0.0, 0.0, -9.80665]), ndim=3)
    em = bvpnav.error_models.CompositeErrorModel(*components)
    form = SimpleNamespace(error_model=em, data=data, residual="acceleration", sigma_a_given=False)
    ep = pd.Series(values, dtype=float)
    sol = SimpleNamespace(error_params=ep, residuals=pd.DataFrame(), lam=1.0, lam_rule="fixed", x=None)
    return sol, form


def _models():
    em = pytest.importorskip("bvpnav.error_models.gyro_bias").__name__.rsplit(".", 1)[0]
    mods = __import__(em, fromlist=["AttitudeError", "GyroBias", "GyroScaleFactor"])
    return mods.AttitudeError, mods.GyroBias, mods.GyroScaleFactor


def test_attitude_tilt_beyond_its_limit_but_heading_free():
    AttitudeError, _, _ = _models()
    sol, form = _stub({"attitude_x": 0.15, "attitude_y": -0.15, "attitude_z": 3.0}, [AttitudeError()])
    (msg,) = pl.check(sol, form)  # each within 0.2 rad, the tilt 0.212 rad beyond
    assert msg.startswith("implausible estimate: attitude_x = +0.15 rad (+8.59 deg), attitude_y = -0.15 rad")
    assert "by 0.212 rad (12.2 deg), beyond the limit 0.2 rad" in msg
    sol, form = _stub({"attitude_x": 0.01, "attitude_y": -0.02, "attitude_z": -3.1}, [AttitudeError()])
    assert pl.check(sol, form) == []


def test_gyro_bias_beyond_the_absolute_limit_names_the_knot():
    _, GyroBias, _ = _models()
    vals = {f"gyro_bias_{a}[{k}]": 1e-4 for a in "xyz" for k in range(4)}
    vals["gyro_bias_z[2]"] = -0.08
    sol, form = _stub(vals, [GyroBias(interval=33.0)])
    (msg,) = pl.check(sol, form)
    assert msg.startswith("implausible estimate: gyro_bias_z[2] = -0.08 rad/s (-4.58 deg/s) "
                          "(the largest of 4 knots)")
    assert "0.05 rad/s" in msg


def _turning(n: int = 1001, duration: float = 100.0, mean: float = 0.01, swing: float = 0.3):
    t = np.linspace(0.0, duration, n)
    g = np.zeros((n, 3))
    g[:, 2] = mean + swing * np.sin(2 * np.pi * t / 20.0)  # turns left and right, net mean * T
    return g


def test_gyro_bias_that_removed_the_turning():
    """The issue's slide: gyro_bias_z -> the drive's mean yaw rate while the car turns."""
    _, GyroBias, _ = _models()
    vals = {"gyro_bias_x": 1e-4, "gyro_bias_y": -1e-4, "gyro_bias_z": 0.0098}
    sol, form = _stub(vals, [GyroBias()], gyro=_turning())
    (msg,) = pl.check(sol, form)
    assert "gyro bias on axis z +0.0098 rad/s" in msg
    assert "removes 98 % of the axis's mean measured rate" in msg
    assert "removed real turning" in msg or "real turning as bias" in msg
    # within three sigma of the user's own prior: what the datasheet allows
    sol, form = _stub(vals, [GyroBias(sigma=5e-3)], gyro=_turning())
    assert pl.check(sol, form) == []
    # a bias well below the mean rate, or an axis that does not turn: no warning
    sol, form = _stub({**vals, "gyro_bias_z": 1e-3}, [GyroBias()], gyro=_turning())
    assert pl.check(sol, form) == []
    sol, form = _stub(vals, [GyroBias()], gyro=_turning(swing=0.001))
    assert pl.check(sol, form) == []


def test_gyro_scale_beyond_its_limit():
    _, _, GyroScaleFactor = _models()
    vals = {"gyro_scale_x": 0.0, "gyro_scale_y": 0.001, "gyro_scale_z": -0.25}
    sol, form = _stub(vals, [GyroScaleFactor()])
    (msg,) = pl.check(sol, form)
    assert msg.startswith("implausible estimate: gyro_scale_z = -0.25 (-25 %) is beyond the limit +-0.1")


def test_thresholds_are_recorded():
    sol, _ = _solve(line(0.05, 0.05, 10))
    th = sol.stats["plausibility"]["thresholds"]
    assert th["MISFIT_HIGH"] == pl.MISFIT_HIGH and th["ACC_BIAS_LIMIT"] == pytest.approx(0.980665)


def test_unmodelled_gyro_bias_is_a_misfit_that_the_attitude_models_remove():
    """The issue's signal on a turning strapdown body (60 s at 50 Hz, accelerometer noise
    0.05 m/s^2 = the stated sigma_a, fixes every 1 s): a gyro bias of (2, -1, 3) mrad/s
    tilts the attitude by up to 0.1 rad, so with Bias() alone the horizontal residual is
    about 6 x sigma_a (measured 6.3 and 6.2; the vertical one 1.9); GyroBias() +
    AttitudeError() fit (variance factor 0.94) and nothing is warned."""
    from bvpnav.attitude import integrate_gyro

    AttitudeError, GyroBias, _ = _models()
    g = np.array([0.0, 0.0, -9.80665])
    t = np.linspace(0.0, 60.0, 3001)
    w = np.column_stack([0.05 * np.sin(0.5 * t), 0.04 * np.cos(0.3 * t), 0.2 * np.sin(0.1 * t) + 0.05])
    c0 = Rotation.from_euler("ZYX", [0.7, 0.02, -0.03])
    att = integrate_gyro(t, w, c0)
    a = np.column_stack([np.sin(0.2 * t), 0.5 * np.cos(0.15 * t), 0.1 * np.sin(0.3 * t)])
    f = att.inv().apply(a - g)
    exact = bvpnav.NavigationProblem(bvpnav.ImuData(t, specific_force=f, attitude=att, gravity=g))
    exact.add(Position(t=0.0, value=[0.0, 0.0, 0.0]), Velocity(t=0.0, value=[1.0, 0.0, 0.0]))
    pos = exact.solve(solver="direct").position().reshape(-1, 3)
    noisy = f + np.random.default_rng(0).normal(0.0, 0.05, f.shape)
    wm = w + np.array([2e-3, -1e-3, 3e-3])
    data = bvpnav.ImuData.from_gyro(t, noisy, wm, initial_attitude=c0, gravity=g)
    k = np.arange(0, t.size, 50)

    prob = bvpnav.NavigationProblem(data, error_model=Bias(), sigma_a=0.05)
    prob.add(Position(t=t[k], value=pos[k]))
    sol, _ = _solve(prob)
    rep = sol.stats["plausibility"]
    ratio = rep["residual_ratio"]
    assert ratio["x"] > 5 and ratio["y"] > 5 and ratio["z"] < 3
    (msg,) = _misfit(sol.warnings)
    assert "on axes x, y" in msg and "GyroBias" in msg

    em = GyroBias() + AttitudeError(sigma=(0.05, 0.05, None))
    prob = bvpnav.NavigationProblem(data, error_model=em, sigma_a=0.05)
    prob.add(Position(t=t[k], value=pos[k]))
    sol, _ = _solve(prob, attitude={"heading": "given"})
    assert sol.stats["plausibility"]["noise_ratio"] == pytest.approx(1.0, abs=0.2)
    assert not _misfit(sol.warnings) and not _implausible(sol.warnings)
