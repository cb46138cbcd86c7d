"""Default priors from a sensor grade for a strapdown problem that states none (issue 42)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from bvpnav import ImuData, NavigationProblem
from bvpnav.constraints import Position
from bvpnav.error_models import AttitudeError, Bias, GyroBias, ScaleFactor
from bvpnav.errors import InputError
from bvpnav.scenarios import car_drive
from bvpnav.sensors import DEFAULT_GRADE, GRADES, from_datasheet, grade


def test_complete_fills_in_exactly_the_missing_priors_with_the_grades_figures():
    g = grade("tactical")
    model, filled = g.complete(Bias(interval=20.0) + GyroBias(sigma=1e-4) + AttitudeError(axes=("x", "y"))
                               + ScaleFactor())
    bias, gyro, att, scale = model.components
    assert (bias.sigma, bias.drift, bias.interval) == (5e-3, 1e-5, 20.0)
    assert gyro.sigma == 1e-4 and gyro.drift is None  # stated: kept; constant: no walk
    np.testing.assert_array_equal(att.sigma, [0.005, 0.005])  # only the selected axes
    assert scale.sigma is None  # the grade has no scale-factor figure
    assert filled == ["Bias: sigma 0.005 m/s^2", "Bias: drift 1e-05 m/s^2/sqrt(s)",
                      "AttitudeError: sigma tilt 0.005 rad, heading none (unknown)"]
    mine = from_datasheet(heading="2 deg", base="navigation")
    model, _ = mine.complete(AttitudeError())
    np.testing.assert_allclose(model.sigma, [0.001, 0.001, np.radians(2.0)], rtol=1e-12)
    full = Bias(sigma=0.1) + GyroBias(sigma=1e-3)
    assert g.complete(full) == (full, [])  # nothing missing: the same object back


def _drive_problem(drive, gap, **kw):
    step = int(round(gap * drive.params["gnss_rate"]))
    kept = np.arange(0, drive.fix_t.size, step)
    em = Bias() + GyroBias(interval=30.0) + AttitudeError()
    prob = NavigationProblem(drive.data(), error_model=em, **kw)
    prob.add(Position(t=drive.fix_t[kept], value=drive.fix_position[kept],
                      sigma=np.tile(drive.fix_sigma, (kept.size, 1))))
    return prob, kept


@pytest.fixture(scope="module")
def drive():
    return car_drive(150.0, 10.0, "consumer", seed=3)


def test_without_priors_or_grade_a_sparse_drive_is_refused_naming_the_fix(drive):
    prob, _ = _drive_problem(drive, 30.0, grade=None)
    with pytest.raises(InputError) as exc:
        prob.solve(solver="direct", attitude={"progress": False})
    msg = str(exc.value)
    assert "nothing determines" in msg and "gyro_bias_x[0]" in msg
    assert "grade='consumer'" in msg and "sigma=" in msg


def test_the_default_grade_solves_a_sparse_drive_and_says_so(drive):
    """Fixes every 30 s on a simulated consumer-grade drive: refused without priors, solved with
    the default (consumer) grade's, better than a spline through the kept fixes at the withheld
    1 Hz fixes, against the truth."""
    assert DEFAULT_GRADE == "consumer"
    prob, kept = _drive_problem(drive, 30.0)
    assert prob.grade is GRADES["consumer"] and prob.grade_report["name"] == "consumer"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = prob.solve(solver="direct", attitude={"progress": False})
    assert sol.stats["verified"] is True
    rep = sol.stats["grade"]
    assert rep["name"] == "consumer"
    assert rep["filled"] == ["Bias: sigma 0.05 m/s^2", "GyroBias: sigma 0.005 rad/s",
                             "GyroBias: drift 2e-05 rad/s/sqrt(s)",
                             "AttitudeError: sigma tilt 0.02 rad, heading none (unknown)"]
    assert "sensor grade assumed: consumer" in repr(sol)
    held = np.setdiff1d(np.arange(drive.fix_t.size), kept)
    t_w = drive.fix_t[held]
    truth = drive.truth_at(t_w)
    est = np.column_stack([np.interp(t_w, drive.t, sol.position()[:, k]) for k in range(3)])
    rms = float(np.sqrt(np.mean(np.sum((est - truth) ** 2, axis=1))))
    spline = CubicSpline(drive.fix_t[kept], drive.fix_position[kept])(t_w)
    rms_spline = float(np.sqrt(np.mean(np.sum((spline - truth) ** 2, axis=1))))
    assert rms < 0.5 * rms_spline, (rms, rms_spline)


def test_a_stated_grade_is_used_and_a_stated_prior_turns_the_defaults_off(drive):
    prob, _ = _drive_problem(drive, 30.0, grade="tactical")
    assert prob.grade_report["name"] == "tactical"
    assert prob.formulation.error_model.components[1].drift == 1e-6
    prob.grade = None
    assert prob.grade_report is None and prob.error_model.components[0].sigma is None
    own = NavigationProblem(drive.data(), error_model=Bias(sigma=0.2) + GyroBias() + AttitudeError())
    assert own.grade_report is None  # the user's own priors: nothing assumed
    assert own.error_model.components[1].sigma is None


def test_navigation_frame_data_or_no_gyro_model_gets_no_grade():
    t = np.linspace(0.0, 10.0, 101)
    nav = NavigationProblem(ImuData(t, np.sin(t)), error_model=Bias())
    assert nav.grade_report is None and nav.error_model.sigma is None
    f = np.tile([0.0, 0.0, 9.80665], (t.size, 1))
    strap = NavigationProblem(ImuData.from_gyro(t, f, np.zeros((t.size, 3))), error_model=Bias())
    assert strap.grade_report is None  # no gyro parameters: the accelerometer model alone


def test_an_unknown_grade_is_refused_listing_the_presets():
    t = np.linspace(0.0, 10.0, 101)
    with pytest.raises(InputError, match="unknown sensor grade; valid grades: consumer, tactical"):
        NavigationProblem(ImuData(t, np.sin(t)), grade="premium")
    with pytest.raises(InputError, match="grade=3: give a preset name"):
        NavigationProblem(ImuData(t, np.sin(t)), grade=3)
