"""The node-state loop's course start (``solve(attitude={"start": "course"})``, issue 42).

A simulated car drive (120 s at 20 Hz, consumer grade) with a large constant gyro bias added
(0.01, -0.01, 0.1 rad/s: the raw-gyro attitude turns by 12 rad in heading over the drive), fixes
every 10 s. The course start reaches the answer of the same problem started at the TRUE
attitude (the same totals mechanism with the truth's rotation); the default start stops in
another minimum, tens of metres away, with a misfit warning.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import bvpnav.solve.course as course
from bvpnav import ImuData, InputError, NavigationProblem
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import Bias, ErrorStates
from bvpnav.scenarios import car_drive

BIAS = np.array([0.01, -0.01, 0.1])   # rad/s, added to the simulated gyro


@pytest.fixture(scope="module")
def drive():
    return car_drive(120.0, 20.0, "consumer", seed=0)


def problem(drive, segment=None, fixes=None, model=None):
    fig = drive.params["sensor"]
    data = ImuData.from_gyro(drive.t, drive.specific_force, drive.gyro + BIAS,
                             initial_attitude=drive.initial_attitude_guess, gravity=drive.gravity)
    if model is None:
        model = ErrorStates(arw=fig["gyro_noise"], gyro_drift=fig["gyro_bias_walk"],
                            acc_drift=fig["acc_bias_walk"], attitude_sigma=[fig["tilt"], fig["tilt"], np.inf],
                            gyro_sigma=0.2, acc_sigma=fig["acc_bias"])
    prob = NavigationProblem(data, error_model=model, sigma_a=fig["acc_noise"] * math.sqrt(20.0),
                             segment=segment)
    kept = np.arange(0, drive.fix_t.size, 10) if fixes is None else fixes
    if kept.size:
        prob.add(Position(t=drive.fix_t[kept], value=drive.fix_position[kept],
                          sigma=np.tile(drive.fix_sigma, (kept.size, 1)), name="fixes"))
    return prob


def solve(prob, start, **kw):
    return prob.solve(solver="direct", attitude={"progress": False, "start": start, **kw})


def truth_started(drive, monkeypatch, segment=None):
    """The same problem with the loop's first point at the true attitude."""
    with monkeypatch.context() as m:
        m.setattr(course, "course_totals",
                  lambda form: (drive.attitude * form.data.attitude.inv()).as_rotvec())
        return solve(problem(drive, segment), "course")


@pytest.mark.parametrize("segment", [None, 1.0], ids=["samples", "mesh"])
def test_course_start_reaches_the_truth_started_answer(drive, monkeypatch, segment):
    ref = truth_started(drive, monkeypatch, segment)
    sol = solve(problem(drive, segment), "course")
    assert sol.stats["sequential"]["converged"]
    assert len(sol.stats["sequential"]["iterations"]) <= 10
    assert np.max(np.abs(sol.position() - ref.position())) < 1e-6
    rms = np.sqrt(np.mean(np.sum((sol.position() - drive.position) ** 2, axis=1)))
    assert rms < 2.0   # measured 1.296 m (fix sigma 1 / 1 / 2 m)
    # the default start, from the raw-gyro attitude: another minimum, warned
    plain = solve(problem(drive, segment), "data")
    assert np.max(np.abs(plain.position() - ref.position())) > 10.0   # measured 61.5 m
    assert any("misfit" in w for w in plain.warnings)


def test_course_heading_holds_below_the_speed():
    t = np.linspace(0.0, 30.0, 301)
    # east at 10 m/s for 10 s, stopped 10 s, north at 10 m/s for 10 s
    fix_t = np.array([0.0, 10.0, 20.0, 30.0])
    xy = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 0.0], [100.0, 100.0]])
    yaw = course.course_heading(t, fix_t, xy)
    assert np.allclose(yaw[t < 9.9], 0.0, atol=1e-12)
    assert np.allclose(yaw[(t > 10.1) & (t < 19.9)], 0.0, atol=1e-12)   # held through the stop
    assert np.allclose(yaw[t > 20.1], np.pi / 2, atol=1e-12)
    # a stand first: the first motion's heading back to the start
    xy = np.array([[5.0, 5.0], [5.0, 5.0], [5.0, 105.0]])
    yaw = course.course_heading(t, np.array([0.0, 10.0, 20.0]), xy)
    assert np.allclose(yaw[t < 19.9], np.pi / 2, atol=1e-12)


def test_course_start_refusals(drive):
    with pytest.raises(InputError, match=r"start': 'course'.*no Position item"):
        solve(problem(drive, fixes=np.array([], dtype=int)).add(
            Velocity(t=[0.0], value=[0.0, 0.0, 0.0], name="rest")), "course")
    with pytest.raises(InputError, match=r"start': 'course'.*at least 2 fixes"):
        solve(problem(drive, fixes=np.array([0])), "course")
    with pytest.raises(InputError, match=r"start': 'course'.*never move faster than 1 m/s"):
        # two fixes of the 5 s stand (exact: 1 m noise between 1 s fixes reads as motion)
        solve(problem(drive, fixes=np.array([], dtype=int)).add(
            Position(t=[0.0, 4.0], value=np.tile(drive.position[0], (2, 1)), sigma=1.0)), "course")
    with pytest.raises(InputError, match=r"start': 'course'.*has none: use error_model=ErrorStates"):
        solve(problem(drive, model=Bias()), "course")
    with pytest.raises(InputError, match=r"start.*'data'.*'course'"):
        solve(problem(drive), "gyro")


def test_a_course_start_is_no_reference_for_a_cheap_second_step():
    """A first step of at least CHEAP_FIRST from the data as measured may be followed by a cheap
    one, not from a course start: cheap steps rotate the reference pass's samples element by
    element, and the course start sets every sample's attitude (not the gyro's between the
    nodes), so cheap steps from it converge away from the full passes' point (measured on this
    tactical drive, 1 s mesh: the next full pass 6.7e-3 rad, 8 steps against 5)."""
    from bvpnav.solve.attitude import CHEAP_FIRST

    drive = car_drive(120.0, 20.0, "tactical", seed=0)
    fig = drive.params["sensor"]
    data = ImuData.from_gyro(drive.t, drive.specific_force, drive.gyro,
                             initial_attitude=drive.initial_attitude_guess, gravity=drive.gravity)
    model = ErrorStates(arw=fig["gyro_noise"], gyro_drift=fig["gyro_bias_walk"],
                        acc_drift=fig["acc_bias_walk"], attitude_sigma=[fig["tilt"], fig["tilt"], np.inf],
                        gyro_sigma=fig["gyro_bias"], acc_sigma=fig["acc_bias"])
    prob = NavigationProblem(data, error_model=model, sigma_a=fig["acc_noise"] * math.sqrt(20.0), segment=1.0)
    kept = np.arange(0, drive.fix_t.size, 10)
    prob.add(Position(t=drive.fix_t[kept], value=drive.fix_position[kept],
                      sigma=np.tile(drive.fix_sigma, (kept.size, 1)), name="fixes"))
    rec = solve(prob, "course").records.attitude
    steps = [(it["solve"], it["step"]) for it in rec.iterations]
    # measured: the first step 0.75 rad
    assert rec.converged and steps[0][1] >= CHEAP_FIRST and steps[1][0] == "banded", steps
    assert rec.cheap_steps >= 1 and rec.full_passes <= 4, steps   # measured: 4 full passes, 1 cheap step


def _outlying(seed: int = 0):
    """300 fixes 1 s apart along a gently weaving road (10 m/s, 5 cm noise), 15 of them 20-50 m
    off in random directions."""
    rng = np.random.default_rng(seed)
    t = np.arange(300.0)
    xy = np.column_stack([10.0 * t, 3.0 * np.sin(t / 10.0)]) + rng.normal(0.0, 0.05, (300, 2))
    bad = np.sort(rng.choice(300, 15, replace=False))
    ang = rng.uniform(0.0, 2.0 * np.pi, 15)
    xy[bad] += rng.uniform(20.0, 50.0, (15, 1)) * np.column_stack([np.cos(ang), np.sin(ang)])
    return t, xy, bad


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_screening_leaves_out_the_outlying_fixes_and_only_them(seed):
    t, xy, bad = _outlying(seed)
    keep = course.screened(t, xy, np.full(t.size, 0.05), np.full(t.size, 5.0))
    inner = bad[(bad > 0) & (bad < t.size - 1)]     # at an end an outlier and its neighbour can trade
    assert set(inner) <= set(np.flatnonzero(~keep)) <= set(bad) | {1, t.size - 2}
    # no gate, no screening
    assert course.screened(t, xy, np.full(t.size, 0.05), np.full(t.size, np.inf)).all()


def test_screening_lets_a_hard_turn_through():
    """A 0.5 g turn (radius 20 m at 10 m/s), fixes 1 s apart: within a car's curving, kept."""
    t = np.arange(20.0)
    xy = 20.0 * np.column_stack([np.cos(0.5 * t), np.sin(0.5 * t)])
    assert course.screened(t, xy, np.full(t.size, 0.05), np.full(t.size, 5.0)).all()


def test_gated_fixes_give_the_course_of_the_fixes_without_their_outliers(drive):
    """The course start of gated fixes with 20-50 m outliers is that of the fixes without them."""
    rng = np.random.default_rng(4)
    fix_t, clean = drive.fix_t, drive.fix_position
    bad = np.sort(rng.choice(np.arange(1, fix_t.size - 1), 6, replace=False))
    faulty = clean.copy()
    faulty[bad, :2] += rng.choice([-1.0, 1.0], (6, 2)) * rng.uniform(20.0, 50.0, (6, 2))
    sig = np.tile(drive.fix_sigma, (fix_t.size, 1))
    ok = np.setdiff1d(np.arange(fix_t.size), bad)
    gated = problem(drive, fixes=np.array([], dtype=int)).add(
        Position(t=fix_t, value=faulty, sigma=sig, gate=5.0, name="gnss"))
    clean_only = problem(drive, fixes=np.array([], dtype=int)).add(
        Position(t=fix_t[ok], value=clean[ok], sigma=sig[ok], name="gnss"))
    ungated = problem(drive, fixes=np.array([], dtype=int)).add(
        Position(t=fix_t, value=faulty, sigma=sig, name="gnss"))
    a, b, c = (course.course_totals(p.formulation) for p in (gated, clean_only, ungated))
    np.testing.assert_allclose(a, b, atol=1e-12)
    assert np.max(np.abs(c - b)) > 0.3     # the outliers turn the ungated course by radians
