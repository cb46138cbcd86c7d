"""Attitude error models and the damped outer loop (issue 16).

The truth of every noise-free case is built with bvpnav's own attitude integration
(:func:`bvpnav.attitude.integrate_gyro`) so that the exact answer is known to rounding:
the loop must find the gyro bias and the initial attitude to 1e-8 rad (rad/s).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from bvpnav import ImuData, NavigationProblem
from bvpnav.attitude import integrate_gyro
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import AttitudeError, AttitudeWalk, Bias, GyroBias, GyroScaleFactor, walk_interval
from bvpnav.error_models._attitude import hat_weights, knot_times, reintegrate
from bvpnav.errors import InputError

G = np.array([0.0, 0.0, -9.80665])


def _motion(duration=60.0, rate=50.0):
    """Rates (rad/s), true attitude and navigation-frame acceleration of a turning body."""
    t = np.linspace(0.0, duration, int(round(duration * rate)) + 1)
    w = np.column_stack([0.05 * np.sin(0.5 * t), 0.04 * np.cos(0.3 * t), 0.2 * np.sin(0.1 * t) + 0.05])
    c0 = Rotation.from_euler("ZYX", [0.7, 0.02, -0.03])
    att = integrate_gyro(t, w, c0)
    a = np.column_stack([np.sin(0.2 * t), 0.5 * np.cos(0.15 * t), 0.1 * np.sin(0.3 * t)])
    f = att.inv().apply(a - G)
    return t, w, c0, att, f


def _truth_positions(t, f, att):
    exact = ImuData(t, specific_force=f, attitude=att, gravity=G)
    sol = NavigationProblem(exact).add(Position(t=0.0, value=[0.0, 0.0, 0.0]),
                                       Velocity(t=0.0, value=[1.0, 0.0, 0.0])).solve(solver="direct")
    return sol.position().reshape(-1, 3)


@pytest.fixture(scope="module")
def motion():
    t, w, c0, att, f = _motion()
    return t, w, c0, att, f, _truth_positions(t, f, att)


# ------------------------------------------------------- columns vs re-integration
def _scales(names):
    return np.array([1e-2 if n.startswith("gyro_bias") else 0.2 if n.startswith("attitude") else 0.02
                     for n in names])


@pytest.mark.parametrize("em", [AttitudeError(), GyroBias(), GyroBias(interval=4.0), GyroScaleFactor(),
                                GyroBias(interval=5.0) + AttitudeError() + GyroScaleFactor(),
                                AttitudeWalk(arw=1e-3, interval=3.0),
                                GyroBias(interval=5.0) + AttitudeError()
                                + AttitudeWalk(arw=1e-3, interval=3.0)],
                         ids=["attitude", "gyro-bias", "gyro-bias-knots", "gyro-scale", "all", "walk",
                              "all-with-walk"])
def test_columns_are_the_derivative_of_the_reintegrated_acceleration(em):
    """||a(x + eps d) - a(x) - G eps d|| / ||a(x + eps d) - a(x)|| = O(eps): linearization
    error O(eps^2), at a point far from zero (heading 2.5 rad, tilts 0.2 rad)."""
    t, w, c0, _, f = _motion(duration=20.0, rate=40.0)
    data = ImuData.from_gyro(t, f, w, initial_attitude=c0, gravity=G)
    names = em.names(data)
    rng = np.random.default_rng(1)
    base = dict(zip(names, rng.normal(size=len(names)) * _scales(names), strict=True))
    if "attitude_z" in base:
        base["attitude_z"] = 2.5
    at = reintegrate(data, em, base)
    cols = em.columns(at)
    d = rng.normal(size=len(names)) * _scales(names)
    rel = []
    for eps in (1e-2, 1e-3, 1e-4):
        moved = reintegrate(data, em, {n: base[n] + eps * d[k] for k, n in enumerate(names)})
        da = moved.acc - at.acc
        rel.append(np.linalg.norm(da - np.einsum("nap,p->na", cols, eps * d)) / np.linalg.norm(da))
    ratios = np.array(rel[:-1]) / np.array(rel[1:])
    assert np.all((ratios > 9.0) & (ratios < 11.0)), rel  # the relative error falls as eps
    assert rel[-1] < 1e-3


def test_gyro_bias_attitude_change_matches_the_continuous_limit():
    """psi(t) = -int_0^t C b ds for a constant bias (trapezoid of C b to O(h^2))."""
    t, w, c0, _, f = _motion(duration=20.0, rate=100.0)
    data = ImuData.from_gyro(t, f, w, initial_attitude=c0, gravity=G)
    from bvpnav.error_models._attitude import propagate

    em = GyroBias()
    psi = propagate(data, em.rate_columns(data), em.initial_columns(data))
    C = data.attitude.as_matrix()
    from scipy.integrate import cumulative_trapezoid

    expect = -cumulative_trapezoid(C, t, axis=0, initial=0.0)
    assert np.max(np.abs(psi - expect)) < 1e-5 * np.max(np.abs(expect))


def test_walk_interval_and_the_bridge_it_leaves_out():
    """walk_interval's Notes: between knots a random walk minus its linear interpolation is a
    Brownian bridge whose integral over an interval has variance n^2 Delta^3 / 12 (checked by
    simulation, 4000 paths); the tactical grade's spacing is 4.4 s."""
    assert walk_interval(5e-4, 2e-5) == pytest.approx(np.sqrt(3.0) * 5e-4 / (9.80665 * 2e-5), rel=1e-15)
    assert walk_interval(5e-4, 2e-5) == pytest.approx(4.4155, abs=1e-4)
    assert walk_interval(5e-4, 2e-5, ratio=1.0) == pytest.approx(2.0 * walk_interval(5e-4, 2e-5))
    rng = np.random.default_rng(0)
    n, delta, steps = 3.0, 2.0, 400
    h = delta / steps
    walk = np.concatenate([np.zeros((4000, 1)), np.cumsum(rng.normal(0.0, n * np.sqrt(h), (4000, steps)),
                                                          axis=1)], axis=1)
    s = np.linspace(0.0, delta, steps + 1)
    bridge = walk - walk[:, -1:] * s / delta
    integral = np.sum(0.5 * (bridge[:, 1:] + bridge[:, :-1]), axis=1) * h
    assert np.var(integral) == pytest.approx(n**2 * delta**3 / 12.0, rel=0.06)
    with pytest.raises(InputError, match="arw"):
        walk_interval(5e-4, 0.0)


def test_attitude_walk_is_recovered_noise_free(motion):
    """A walk in the model's own form (linear between knots 10 s apart; the true attitude is the
    gyro-integrated one rotated by it) with a constant gyro bias and a wrong initial attitude:
    the damped loop finds every knot to 1e-8 rad."""
    t, w, c0, att, f, pos = motion
    knots = knot_times(t, 10.0)
    rng = np.random.default_rng(5)
    kw = np.vstack([np.zeros(3), 2e-3 * np.cumsum(rng.normal(size=(knots.size - 1, 3)), axis=0)])
    walked = Rotation.from_rotvec(hat_weights(t, knots) @ kw) * att  # the true attitude
    f_meas = walked.inv().apply(att.apply(f))  # the same navigation-frame acceleration, so the same path
    bg = np.array([1e-3, -2e-3, 5e-4])
    guess = Rotation.from_rotvec([0.005, -0.004, 0.03]) * c0
    em = GyroBias() + AttitudeError() + AttitudeWalk(interval=10.0)  # no prior: exact recovery
    prob = _problem(t, w + bg, f_meas, guess, pos, em, every=10)
    sol = prob.solve(solver="direct", attitude={"tol": 1e-11, "heading": "given"})
    est = np.array([[sol.error_params[f"attitude_walk_{a}[{m}]"] for a in "xyz"]
                    for m in range(1, knots.size)])
    np.testing.assert_allclose(est, kw[1:], rtol=0, atol=1e-8)
    np.testing.assert_allclose(sol.error_params[["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]], bg,
                               rtol=0, atol=1e-8)
    assert (sol.attitude * walked.inv()).magnitude().max() < 1e-8
    np.testing.assert_allclose(sol.position().reshape(-1, 3), pos, rtol=0, atol=1e-6)


def test_attitude_walk_prior_is_the_random_walk_law(motion):
    """The prior's share of the objective at a point: sum over knots of
    ((psi_m - psi_{m-1}) / (arw sqrt(dt)))^2 with psi_0 = 0, and the term's rows say the same."""
    t, w, c0, _, f, _ = motion
    data = ImuData.from_gyro(t, f, w, initial_attitude=c0, gravity=G)
    em = AttitudeWalk(arw=2e-4, interval=20.0, axes=("x", "z"))
    names = em.names(data)
    assert names == ["attitude_walk_x[1]", "attitude_walk_x[2]", "attitude_walk_x[3]",
                     "attitude_walk_z[1]", "attitude_walk_z[2]", "attitude_walk_z[3]"]
    vals = dict(zip(names, [1e-3, 3e-3, 2e-3, -1e-3, 0.0, 4e-3], strict=True))
    at = reintegrate(data, em, vals)
    sig = 2e-4 * np.sqrt(20.0)
    expect = sum(float(np.sum((np.diff([0.0, *v]) / sig) ** 2))
                 for v in ([1e-3, 3e-3, 2e-3], [-1e-3, 0.0, 4e-3]))
    assert em.prior_cost(at) == pytest.approx(expect, rel=1e-12)
    model = NavigationProblem(at, error_model=em).model
    (term,) = [tm for tm in em.terms(model) if "random walk" in tm.label]
    x = np.zeros(model.size)
    assert float(np.sum((term.residual.value(x) / term.sigma) ** 2)) == pytest.approx(expect, rel=1e-12)
    # the walk rotates the integrated attitude: knot 2 of x is exactly 3 mrad about nav x
    plain = reintegrate(data, AttitudeError(), {})
    k = np.argmin(np.abs(t - 40.0))
    np.testing.assert_allclose((at.attitude[k] * plain.attitude[k].inv()).as_rotvec(), [3e-3, 0.0, 0.0],
                               rtol=0, atol=1e-15)


def test_knots_and_hat_weights():
    t = np.linspace(0.0, 95.0, 951)
    k = knot_times(t, 30.0)
    np.testing.assert_allclose(k, [0.0, 31.666666666666668, 63.333333333333336, 95.0])
    W = hat_weights(t, k)
    np.testing.assert_allclose(W.sum(axis=1), 1.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(W @ k, t, rtol=0, atol=1e-12)  # linear functions are exact
    assert knot_times(t, 1e6).size == 2  # at least one interval


# ----------------------------------------------------------- noise-free recovery
def _problem(t, w_meas, f, guess, pos, em, every=50, sigma=None):
    data = ImuData.from_gyro(t, f, w_meas, initial_attitude=guess, gravity=G)
    k = np.arange(0, t.size, every)
    prob = NavigationProblem(data, error_model=em, grade=None)  # no priors: noise-free recovery is exact
    prob.add(Position(t=t[k], value=pos[k], sigma=sigma))
    return prob


def test_constant_gyro_bias_and_initial_attitude_from_170_degrees(motion):
    """Noise-free: the heading search and the damped loop find a 170-degree heading error,
    the tilts and a constant gyro bias to 1e-8, quadratically at the end."""
    t, w, c0, att, f, pos = motion
    bg = np.array([2e-3, -1e-3, 3e-3])
    guess = Rotation.from_rotvec([0.01, -0.01, 0.0]) * Rotation.from_rotvec([0.0, 0.0, np.radians(170)]) * c0
    prob = _problem(t, w + bg, f, guess, pos, GyroBias() + AttitudeError(), sigma=1e-3)
    sol = prob.solve(solver="direct", attitude={"tol": 1e-10})
    est = sol.error_params
    np.testing.assert_allclose(est[["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]], bg, rtol=0, atol=1e-8)
    corr = sol.attitude * att.inv()
    assert corr.magnitude().max() < 1e-8
    rep = sol.stats["sequential"]
    assert rep["kind"] == "attitude" and rep["converged"]
    best = min(rep["heading_search"], key=lambda c: c["objective"])
    assert abs(np.degrees(best["heading"])) == pytest.approx(180.0, abs=1e-9)  # 10 deg from the truth
    steps = [it["step"] for it in rep["iterations"]]
    assert steps[0] > 0.1 and steps[-1] < 1e-10
    assert steps[-2] < 1e-2 * steps[-3] ** 1.5  # superlinear at the end
    np.testing.assert_allclose(sol.position().reshape(-1, 3), pos, rtol=0, atol=1e-7)
    ang = sol.attitude_angles
    np.testing.assert_allclose(ang["yaw_deg"], np.degrees(att.as_euler("ZYX")[:, 0]), atol=1e-6)


def test_random_walk_gyro_bias_is_recovered_at_its_knots(motion):
    """A bias linear between knots 15 s apart (the model's own form) is found to 1e-8 rad/s,
    with the heading given (5 mrad tilts and 50 mrad heading off)."""
    t, w, c0, att, f, pos = motion
    knots = knot_times(t, 15.0)
    rng = np.random.default_rng(3)
    kb = 1e-3 * rng.normal(size=(knots.size, 3))
    bias = hat_weights(t, knots) @ kb
    guess = Rotation.from_rotvec([0.005, 0.004, 0.05]) * c0
    em = GyroBias(interval=15.0) + AttitudeError()
    prob = _problem(t, w + bias, f, guess, pos, em, every=25)
    sol = prob.solve(solver="direct", attitude={"tol": 1e-11, "heading": "given"})
    est = np.array([[sol.error_params[f"gyro_bias_{a}[{m}]"] for a in "xyz"] for m in range(knots.size)])
    np.testing.assert_allclose(est, kb, rtol=0, atol=1e-8)
    assert (sol.attitude * att.inv()).magnitude().max() < 1e-8


def test_gyro_scale_factor_is_identifiable_on_a_turning_axis(motion):
    t, w, c0, att, f, pos = motion
    s = np.array([0.0, 0.0, 0.02])
    guess = Rotation.from_rotvec([0.0, 0.0, 0.03]) * c0
    prob = _problem(t, (1.0 + s) * w + np.array([0, 0, 1e-3]), f, guess, pos,
                    GyroBias(axes="z") + GyroScaleFactor(axes="z") + AttitudeError(), every=25)
    sol = prob.solve(solver="direct", attitude={"tol": 1e-11, "heading": "given"})
    assert sol.error_params["gyro_scale_z"] == pytest.approx(0.02, abs=1e-8)
    assert sol.error_params["gyro_bias_z"] == pytest.approx(1e-3, abs=1e-9)


def test_time_varying_accelerometer_bias_is_recovered():
    """Navigation-frame data: a bias linear between knots, recovered exactly."""
    t = np.linspace(0.0, 30.0, 601)
    a = np.column_stack([np.sin(t), np.cos(0.5 * t)])
    knots = knot_times(t, 10.0)
    kb = np.array([[0.1, -0.05], [0.2, 0.0], [-0.1, 0.05], [0.0, 0.1]])
    meas = a + hat_weights(t, knots) @ kb
    exact = NavigationProblem(ImuData(t, a)).add(Position(t=0.0, value=[0.0, 0.0]),
                                                 Velocity(t=0.0, value=[0.0, 1.0])).solve(solver="direct")
    pos = exact.position().reshape(-1, 2)
    k = np.arange(0, t.size, 20)
    prob = NavigationProblem(ImuData(t, meas), error_model=Bias(interval=10.0))
    sol = prob.add(Position(t=t[k], value=pos[k])).solve(solver="direct")
    est = np.array([[sol.error_params[f"bias_{a}[{m}]"] for a in "xy"] for m in range(knots.size)])
    np.testing.assert_allclose(est, kb, rtol=0, atol=1e-9)


# --------------------------------------------------------------------- damping
def test_the_loop_never_accepts_a_step_that_raises_the_objective(motion):
    """Started 150 degrees off in heading and 0.2 rad in both tilts with the heading 'given'
    (no search), undamped steps overshoot (measured: 9 of 20 rejected): the loop rejects
    them, damps, and every accepted step lowers the objective, to the truth."""
    t, w, c0, att, f, pos = motion
    guess = Rotation.from_rotvec([0.2, -0.2, 0.0]) * Rotation.from_rotvec([0.0, 0.0, np.radians(150.0)]) * c0
    prob = _problem(t, w + np.array([1e-3, 0.0, -2e-3]), f, guess, pos,
                    GyroBias() + AttitudeError(), sigma=0.01)
    sol = prob.solve(solver="direct", attitude={"heading": "given", "tol": 1e-9, "max_iter": 60})
    its = sol.stats["sequential"]["iterations"]
    tried = [it for it in its if not it.get("converged")]
    assert any(not it["accepted"] for it in tried), "built to need damping"
    for it in tried:
        assert it["accepted"] == (it["trial"] < it["objective"])
    accepted = [it["trial"] for it in tried if it["accepted"]]
    assert all(b < a for a, b in zip(accepted, accepted[1:], strict=False))
    assert sol.stats["sequential"]["converged"]
    assert (sol.attitude * att.inv()).magnitude().max() < 1e-9


# ------------------------------------------------------------------ bad input
def test_attitude_models_need_strapdown_gyro_data():
    t = np.linspace(0.0, 10.0, 101)
    nav = NavigationProblem(ImuData(t, np.sin(t)), error_model=GyroBias())
    with pytest.raises(InputError, match="strapdown"):
        nav.add(Position(t=[0.0, 10.0], value=[0.0, 1.0])).solve(solver="direct")
    att = Rotation.identity(t.size)
    given = ImuData(t, specific_force=np.tile([0.0, 0.0, 9.80665], (t.size, 1)), attitude=att)
    with pytest.raises(InputError, match="from_gyro"):
        GyroBias().columns(given)


@pytest.mark.parametrize("opts, match", [({"tol": -1.0}, "positive angle"), ({"max_iter": 0}, "at least one"),
                                         ({"heading": "north"}, "heading"), ({"candidates": 1}, "at least 2"),
                                         ({"speed": 1}, "unknown option")])
def test_attitude_options_are_checked_before_any_work(opts, match):
    t, w, c0, _, f = _motion(duration=5.0, rate=10.0)
    prob = NavigationProblem(ImuData.from_gyro(t, f, w, initial_attitude=c0), error_model=GyroBias())
    with pytest.raises(InputError, match=match):
        prob.solve(attitude=opts)


def test_model_arguments_are_checked():
    with pytest.raises(InputError, match="drift= needs interval="):
        GyroBias(drift=1e-4)
    with pytest.raises(InputError, match="interval"):
        Bias(interval=-1.0)
    with pytest.raises(InputError, match="positive angles"):
        AttitudeError(sigma=(0.1, -0.1, None))
    with pytest.raises(InputError, match="interval="):
        AttitudeWalk(arw=1e-5)
    with pytest.raises(InputError, match="not supported"):
        AttitudeWalk(arw=1e-5, interval=5.0, sigma=0.1)
    assert np.isinf(AttitudeError(sigma=(0.1, 0.1, None)).sigma[2])


# ------------------------------------------------------------------ spec and CLI
def test_attitude_models_round_trip_through_spec_files(motion):
    from bvpnav.spec import parse_spec, to_spec

    t, w, c0, att, f, pos = motion
    em = (Bias(sigma=0.05, interval=20.0, drift=1e-4) + GyroBias(sigma=5e-3, interval=30.0, drift=2e-5)
          + AttitudeError(sigma=(0.02, 0.02, None)) + GyroScaleFactor(axes="z", sigma=0.01)
          + AttitudeWalk(arw=1e-4, interval=7.5, axes=("x", "y")))
    prob = NavigationProblem(ImuData.from_gyro(t, f, w, initial_attitude=c0), error_model=em, sigma_a=0.05)
    text = to_spec(prob, solve={"solver": "direct", "attitude": {"max_iter": 40, "heading": "search"}})
    assert "sigma = [0.02, 0.02, inf]" in text
    spec = parse_spec(text)
    back = spec.build(prob.data)
    assert back.model.param_names == prob.model.param_names
    assert spec.solve["attitude"] == {"max_iter": 40, "heading": "search"}
    assert to_spec(back, solve=spec.solve) == text
    with pytest.raises(InputError, match=r"line \d+: attitude heading='north'"):
        parse_spec(text.replace('heading = "search"', 'heading = "north"'))


def test_cli_solves_a_strapdown_recording_with_gyro_bias(tmp_path):
    """simulate walking -> spec with GyroBias + tilt AttitudeError -> solve: the gyro bias's
    horizontal components come back within 3e-4 rad/s of the simulation's 1e-3 (-0.48, 0.64),
    the loop's report is in the JSON summary, and the trajectory's shape is better than without.

    Stances and the start only: nothing carries heading information, so the yaw-rate bias is
    held at its prior (0; the truth's 6e-4 rad/s was estimated as 3.8e-4 from the swings before
    the hold) and the heading is not observable: the trajectory is compared after a rigid fit
    about the vertical (measured 0.018 m held, 0.0175 m estimated, 0.030 m without the models;
    without the fit 0.052, 0.039 and 0.064 m: the heading)."""
    import json

    import pandas as pd

    from bvpnav.cli import main

    rec = tmp_path / "walk"
    assert main(["simulate", "walking", "--out", str(rec)]) == 0
    spec = (rec / "spec.toml").read_text()
    extra = ('\n[[error_model]]\ntype = "gyro_bias"\nsigma = 0.01\n\n'
             '[[error_model]]\ntype = "attitude_error"\naxes = ["x", "y"]\nsigma = 0.05\n')
    (tmp_path / "spec.toml").write_text(spec + extra)
    out = tmp_path / "traj.csv"
    assert main(["solve", str(rec / "recording.csv"), "--spec", str(tmp_path / "spec.toml"),
                 "--out", str(out)]) == 0
    summary = json.loads(out.with_suffix(".json").read_text())
    est = summary["error_model"]
    assert est["gyro_bias_x"]["units"] == "rad/s"
    assert abs(est["gyro_bias_x"]["estimate"] - (-0.48e-3)) < 3e-4
    assert abs(est["gyro_bias_y"]["estimate"] - 0.64e-3) < 3e-4
    assert est["gyro_bias_z"]["estimate"] == pytest.approx(0.0, abs=1e-12)
    loop = summary["solver"]["sequential"]
    assert loop["kind"] == "attitude" and loop["converged"] and loop["held"] == ["gyro_bias_z"]
    from bvpnav.evaluate import Trajectory, ape

    got, truth = pd.read_csv(out), pd.read_csv(rec / "truth.csv")
    fit = ape(Trajectory(got["t"].to_numpy(), got[list("xyz")].to_numpy()),
              Trajectory(truth["t"].to_numpy(), truth[list("xyz")].to_numpy()), align="yaw")
    assert fit.rmse < 0.02  # without the models: 0.030 m


def test_a_loop_stopped_early_answers_with_its_last_accepted_point(motion):
    """max_iter reached (or the objective no longer falling): the answer is the accepted
    point itself: zero increments about it, the trajectory of the attitude fixed there,
    the loop's last objective, standard deviations of the attitude parameters."""
    t, w, c0, att, f, pos = motion
    guess = Rotation.from_rotvec([0.2, -0.2, 0.0]) * Rotation.from_rotvec([0.0, 0.0, np.radians(150.0)]) * c0
    prob = _problem(t, w + np.array([1e-3, 0.0, -2e-3]), f, guess, pos, GyroBias() + AttitudeError(),
                    sigma=0.01)
    from bvpnav.log import BvpnavWarning

    with pytest.warns(BvpnavWarning, match="did not converge in 2 iterations"):
        sol = prob.solve(solver="direct", uncertainty=True, attitude={"heading": "given", "max_iter": 2})
    rep = sol.stats["sequential"]
    assert rep["reason"] == "max_iter" and not rep["converged"]
    assert set(prob.model.param_names) <= set(sol.error_params_std.index)
    assert np.all(np.isfinite(sol.error_params_std[list(prob.model.param_names)]))
    # the reported totals reproduce the trajectory: re-integrated with them and solved with the
    # attitude fixed (no attitude unknowns), the positions are the answer's
    totals = {n: float(sol.error_params[n]) for n in prob.model.param_names}
    fixed = NavigationProblem(reintegrate(prob.data, prob.error_model, totals))
    fixed.add(*prob.items)
    again = fixed.solve(solver="direct")
    np.testing.assert_allclose(again.position(), sol.position(), rtol=0, atol=1e-6)
    objectives = [it["trial"] for it in rep["iterations"] if it["accepted"]]
    assert rep["objective"] == min([rep["objective_initial"], *objectives])
    loose = prob.solve(solver="direct", attitude={"heading": "given", "ftol": 0.5})
    assert loose.stats["sequential"]["reason"] == "objective"
