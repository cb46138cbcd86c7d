"""Sensor error models: exact reparametrisation, recovery, priors, bounds, composition."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import bvpnav
from bvpnav import simulate
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import (
    Bias,
    CompositeErrorModel,
    ErrorModel,
    Misalignment,
    ScaleFactor,
    SensorCorrection,
    UnknownGravity,
)
from bvpnav.errors import InputError

BIAS = np.array([0.12, -0.15, 0.2])
SCALE = np.array([0.01, -0.02, 0.015])
GRAVITY = np.array([0.03, -0.02, -9.815])
THETA = np.array([[0.0, 2e-3, -1e-3], [1.5e-3, 0.0, 3e-3], [-2e-3, 1e-3, 0.0]])
NINE = ["scale_x", "scale_y", "scale_z", "bias_x", "bias_y", "bias_z", "gravity_x", "gravity_y", "gravity_z"]


def nine_truth() -> np.ndarray:
    return np.concatenate([SCALE, BIAS, GRAVITY])


def paper_problem(sim, tv=None, **kw):
    """Positions at both ends and velocity at three instants (2010 paper, Sec. 5.3)."""
    data = kw.pop("data", None) or sim.imu_data()
    T = float(sim.t[-1])
    tv = [0.0, T / 2, T] if tv is None else tv
    em = kw.pop("error_model", None) or ScaleFactor() + Bias() + UnknownGravity()
    prob = bvpnav.NavigationProblem(data, error_model=em, **kw)
    prob.add(Position(t=[0.0, T], value=sim.position([0.0, T])), Velocity(t=tv, value=sim.velocity(tv)))
    return prob


@pytest.fixture(scope="module")
def sim20():
    return simulate.strapdown_3d_2010(rate=20.0)


# ------------------------------------------------------------- exact correction
def test_columns_correct_a_noise_free_measurement_exactly(sim20):
    """a_hat + G l with the exact internal l equals the true acceleration (no solver)."""
    th = THETA
    acc = simulate.SensorErrors(bias=BIAS, scale=SCALE, misalignment=th)
    sim = simulate.strapdown_3d_2010(rate=20.0, accel=acc)
    data = sim.imu_data()
    em = ScaleFactor() + Misalignment() + Bias() + UnknownGravity()
    D = np.diag(1 + SCALE) @ (np.eye(3) + th)
    Einv = np.linalg.inv(D)  # I + E
    E = Einv - np.eye(3)
    beta = -Einv @ BIAS
    dg = GRAVITY - data.gravity
    names = em.names(data)
    lookup = {f"scale_{a}": E[k, k] for k, a in enumerate("xyz")}
    lookup.update({f"misalignment_{a}{b}": E[i, j] for i, a in enumerate("xyz")
                   for j, b in enumerate("xyz") if i != j})
    lookup.update({f"bias_{a}": beta[k] for k, a in enumerate("xyz")})
    lookup.update({f"gravity_{a}": dg[k] for k, a in enumerate("xyz")})
    l = np.array([lookup[n] for n in names])
    G = em.columns(data)
    assert G.shape == (data.n, 3, 15)
    a_c = data.acc + np.einsum("nap,p->na", G, l)
    truth = sim.truth[["ax", "ay", "az"]].to_numpy()
    assert np.max(np.abs(a_c - truth)) < 1e-12 * np.max(np.abs(truth))
    # and the report maps l back to the physical values exactly
    model = bvpnav.NavModel(data, em)
    rep = em.report(l, model)
    assert np.allclose(rep[[f"scale_{a}" for a in "xyz"]], SCALE, rtol=0, atol=1e-15)
    assert np.allclose(rep[[f"bias_{a}" for a in "xyz"]], BIAS, rtol=0, atol=1e-15)
    assert np.allclose(rep[[f"gravity_{a}" for a in "xyz"]], GRAVITY, rtol=0, atol=1e-15)
    mis = rep[[f"misalignment_{a}{b}" for a in "xyz" for b in "xyz" if a != b]].to_numpy()
    assert np.allclose(mis, th[~np.eye(3, dtype=bool)], rtol=0, atol=1e-15)
    assert rep.attrs["units"]["bias_x"] == "m/s^2" and rep.attrs["units"]["misalignment_xy"] == "rad"


def test_sensor_correction_roundtrip():
    """D = (I + E)^-1 = (I + diag s)(I + Theta) is inverted to s, Theta, b."""
    rng = np.random.default_rng(3)
    s = rng.normal(0, 0.02, 3)
    th = rng.normal(0, 3e-3, (3, 3)) * (1 - np.eye(3))
    b = rng.normal(0, 0.2, 3)
    D = np.diag(1 + s) @ (np.eye(3) + th)
    E = np.linalg.inv(D) - np.eye(3)
    corr = SensorCorrection(E, -(np.eye(3) + E) @ b, np.zeros(3), np.zeros(3))
    from bvpnav.error_models import Param

    assert corr.value(Param("s", "scale", 1, 1)) == pytest.approx(s[1], abs=1e-15)
    assert corr.value(Param("m", "misalignment", 2, 0)) == pytest.approx(th[2, 0], abs=1e-15)
    assert corr.value(Param("b", "bias", 0)) == pytest.approx(b[0], abs=1e-15)


# --------------------------------------------------------------- acceptance
def test_nine_parameter_noise_free_recovery(sim20):
    """Acceptance: every parameter to 1e-6 relative, positions to 1e-6 m."""
    prob = paper_problem(sim20)
    assert prob.unobservable() == []
    sol = prob.solve(accuracy="high")
    est = sol.error_params
    assert list(est.index) == NINE
    rel = np.abs(est.to_numpy() - nine_truth()) / np.abs(nine_truth())
    assert rel.max() < 1e-6, dict(zip(NINE, rel, strict=True))
    err = np.abs(sol.position() - sim20.truth[["x", "y", "z"]].to_numpy()).max()
    assert err < 1e-6
    vel = np.abs(sol.velocity() - sim20.truth[["vx", "vy", "vz"]].to_numpy()).max()
    assert vel < 1e-6


@pytest.mark.parametrize("residual", ["acceleration", "load"])
def test_scale_bias_1d_exact_in_both_objective_forms(residual):
    """The 2010 paper's 1-D model (eq. 25) is recovered exactly in both objective forms."""
    tw = np.arange(11.0)
    motion = simulate.Motion.from_waypoints(tw, np.cumsum(np.r_[0.0, np.cos(tw[1:])]))
    t = simulate.sample_times(0.0, 10.0, 50.0)
    a = motion.acc(t)[:, 0]
    data = bvpnav.ImuData(t, 1.03 * a - 0.07)
    prob = bvpnav.NavigationProblem(data, residual=residual, error_model=ScaleFactor() + Bias())
    prob.add(Position(t=[0, 10], value=motion.pos([0, 10])[:, 0]),
             Velocity(t=[0, 10], value=motion.vel([0, 10])[:, 0]))
    sol = prob.solve(accuracy="high")
    assert sol.error_params["scale_x"] == pytest.approx(0.03, rel=1e-6)
    assert sol.error_params["bias_x"] == pytest.approx(-0.07, rel=1e-6)
    assert np.abs(sol.position("x") - motion.pos(t)[:, 0]).max() < 1e-6


def test_nine_parameter_load_form(sim20):
    """The 2011 paper's load-residual objective gives the same exact answer.

    Clarabel alone is inaccurate here (forward error ~3e-3, caught by verification); the
    default fallback chain hands the problem to the direct back end, and says so.
    """
    prob = paper_problem(sim20, residual="load")
    sol = prob.solve(accuracy="high")
    rel = np.abs(sol.error_params.to_numpy() - nine_truth()) / np.abs(nine_truth())
    assert rel.max() < 1e-6
    assert sol.stats["verified"]
    direct = prob.solve(solver="direct", accuracy="high", fallback=None)
    rel = np.abs(direct.error_params.to_numpy() - nine_truth()) / np.abs(nine_truth())
    assert rel.max() < 1e-6
    if sol.stats["solver"] != "clarabel":  # the fallback was used: recorded with its reason
        assert sol.stats["attempts"][0]["solver"] == "clarabel"
        assert any("failed" in w for w in sol.warnings)


def test_error_model_with_soft_tikhonov_items(sim20):
    """Soft (lam-weighted) velocity items plus hard ends: consistent data stay exact."""
    T = float(sim20.t[-1])
    tv = [0.0, T / 2, T]
    prob = bvpnav.NavigationProblem(sim20.imu_data(), error_model=ScaleFactor() + Bias() + UnknownGravity())
    prob.add(Position(t=[0.0, T], value=sim20.position([0.0, T])),
             Velocity(t=tv, value=sim20.velocity(tv), sigma=0.01))
    assert prob.has_soft_terms
    sol = prob.solve(lam=10.0, accuracy="high")
    rel = np.abs(sol.error_params.to_numpy() - nine_truth()) / np.abs(nine_truth())
    assert rel.max() < 1e-5


def test_misalignment_with_scale_is_exact():
    """Fifteen parameters (scale, misalignment, bias, gravity) from eleven velocities."""
    acc = simulate.SensorErrors(bias=BIAS, scale=SCALE, misalignment=THETA)
    sim = simulate.strapdown_3d_2010(rate=20.0, accel=acc)
    em = ScaleFactor() + Misalignment() + Bias() + UnknownGravity()
    prob = paper_problem(sim, tv=np.linspace(0, 20, 11), error_model=em)
    sol = prob.solve(accuracy="high")
    mis = sol.error_params[[f"misalignment_{a}{b}" for a in "xyz" for b in "xyz" if a != b]]
    assert np.max(np.abs(mis.to_numpy() - THETA[~np.eye(3, dtype=bool)])) < 1e-9
    assert np.max(np.abs(sol.error_params[NINE].to_numpy() - nine_truth()) / np.abs(nine_truth())) < 1e-6


def test_noise_estimates_within_three_sigma_over_50_seeds():
    """Acceptance: with white noise the estimates scatter around the truth.

    Standard deviations are the spread across the 50 seeds (stated in the issue as
    acceptable). Checks: the mean of the 50 estimates is within 3 standard errors
    (sigma / sqrt(50)) of the truth for every parameter (no bias), and at least 95 %
    of the individual estimates are within 3 sigma of the truth.
    """
    noise = 0.01
    est = []
    for seed in range(50):
        sim = simulate.strapdown_3d_2010(rate=20.0, noise=noise, seed=seed)
        est.append(paper_problem(sim).solve().error_params[NINE].to_numpy())
    est = np.array(est)
    truth = nine_truth()
    sd = est.std(axis=0, ddof=1)
    assert np.all(sd > 0)
    z_mean = (est.mean(axis=0) - truth) / (sd / np.sqrt(len(est)))
    assert np.all(np.abs(z_mean) < 3.0), dict(zip(NINE, z_mean, strict=True))
    inside = np.abs(est - truth) <= 3.0 * sd
    assert inside.mean(axis=0).min() >= 0.95
    # the noise really matters: spread is far above the noise-free solver error
    assert sd[:3].min() > 1e-4


# ------------------------------------------------------------- observability
def test_unobservable_combination_named():
    """Nav-frame bias and gravity are the same constant: reported by name."""
    t = np.linspace(0, 10, 201)
    data = bvpnav.ImuData(t, np.sin(t))
    prob = bvpnav.NavigationProblem(data, error_model=Bias() + UnknownGravity())
    prob.add(Position(t=[0, 10], value=[0.0, 1.0]), Velocity(t=[0, 10], value=0.0))
    missing = prob.unobservable()
    assert any("parameter bias_x" in m and "parameter gravity_x" in m for m in missing), missing
    with pytest.raises(InputError, match="bias_x"):
        prob.solve()


def test_null_directions_at_some_unknowns_are_the_whole_matrix_rows():
    """The observability check fills the null directions only at the unknowns its items
    touch: those rows equal the whole matrix's, every other row is empty."""
    t = np.linspace(0, 10, 201)
    acc = np.column_stack([np.sin(t), np.cos(t)])
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t, acc), error_model=ScaleFactor() + Bias())
    form = prob.formulation
    whole, names = form._null_columns()
    at = np.array([0, 7, 150, form.model.v_end_index(1)[1], *form.model.l_index[:2]])
    part, names_at = form._null_columns(at=at)
    assert names_at == names and part.shape == whole.shape
    np.testing.assert_array_equal(part.toarray()[at], whole.toarray()[at])
    rest = np.setdiff1d(np.arange(whole.shape[0]), at)
    assert not part.toarray()[rest].any() and whole.toarray()[rest].any()


def test_bias_with_end_positions_only_unobservable():
    """Bias with end positions only: offset, velocity offset and bias meet two rows."""
    t = np.linspace(0, 10, 201)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t, np.sin(t)), error_model=Bias())
    prob.add(Position(t=[0, 10], value=[0.0, 1.0]))
    missing = prob.unobservable()
    assert missing and any("bias_x" in m for m in missing), missing


def test_nine_parameters_with_end_positions_only_unobservable(sim20):
    T = float(sim20.t[-1])
    prob = bvpnav.NavigationProblem(sim20.imu_data(), error_model=ScaleFactor() + Bias() + UnknownGravity())
    prob.add(Position(t=[0.0, T], value=sim20.position([0.0, T])))
    assert prob.unobservable() != []


def test_prior_makes_it_observable_and_matches_closed_form():
    """Bias prior + end velocities: the MAP estimate is the precision-weighted average.

    Notes
    -----
    With a_c = a_hat - b + w, hard v(T) - v(0) and a penalty sum(w^2)/sa^2 + (b - p0)^2/sb^2,
    b = (sa^2 |m|^2 p0 + sb^2 T^2 b_true) / (sa^2 |m|^2 + sb^2 T^2), m = M 1 (trapezoid weights).
    """
    t = np.linspace(0, 10, 101)
    a_true = np.cos(t)
    b_true, p0, sa, sb = 0.3, 0.1, 0.05, 0.02
    data = bvpnav.ImuData(t, a_true + b_true)
    prob = bvpnav.NavigationProblem(data, sigma_a=sa, error_model=Bias(prior=p0, sigma=sb))
    m = bvpnav.NavModel(data).M @ np.ones(t.size)
    prob.add(Velocity(t=[0, 10], value=[0.0, m @ a_true]))  # FEM-consistent velocity change
    # position offset is free: fix it at the start (does not touch the bias)
    prob.add(Position(t=0.0, value=0.0))
    assert prob.unobservable() == []
    sol = prob.solve(accuracy="high")
    T = 10.0
    expect = (sa**2 * m @ m * p0 + sb**2 * T**2 * b_true) / (sa**2 * m @ m + sb**2 * T**2)
    assert sol.error_params["bias_x"] == pytest.approx(expect, rel=1e-7)
    assert 0.1 < expect < 0.3  # both pieces of information matter
    labels = list(sol.items["item"])
    assert any(lab.startswith("prior Bias") for lab in labels)


@pytest.mark.parametrize("with_scale", [False, True])
def test_bounds_are_exact_even_with_scale(with_scale):
    """A hard bound on the bias is met exactly (the bound is linear in the internal l)."""
    t = np.linspace(0, 10, 201)
    r = np.sin(t)
    a = -np.sin(t)
    data = bvpnav.ImuData(t, 1.02 * a + 0.2 if with_scale else a + 0.2)
    em = Bias(bounds=(-0.1, 0.1))
    if with_scale:
        em = ScaleFactor() + em
    prob = bvpnav.NavigationProblem(data, error_model=em)
    prob.add(Position(t=[0, 10], value=[r[0], r[-1]]), Velocity(t=[0, 10], value=[np.cos(0), np.cos(10)]))
    sol = prob.solve(accuracy="high")
    assert sol.error_params["bias_x"] == pytest.approx(0.1, abs=1e-7)
    # without the bound the truth is found
    em2 = (ScaleFactor() + Bias()) if with_scale else Bias()
    free = bvpnav.NavigationProblem(data, error_model=em2)
    free.add(Position(t=[0, 10], value=[r[0], r[-1]]), Velocity(t=[0, 10], value=[np.cos(0), np.cos(10)]))
    est = free.solve(accuracy="high").error_params["bias_x"]
    # FEM discretisation of sin at h = 0.05 s limits this one
    assert est == pytest.approx(0.2, abs=2e-3)


def test_scale_bound_exact():
    t = np.linspace(0, 10, 201)
    a = -np.sin(t)
    data = bvpnav.ImuData(t, 1.05 * a + 0.1)
    prob = bvpnav.NavigationProblem(data, error_model=ScaleFactor(bounds=(-0.02, 0.02)) + Bias())
    prob.add(Position(t=[0, 10], value=[0.0, np.sin(10)]), Velocity(t=[0, 10], value=[1.0, np.cos(10)]))
    sol = prob.solve(accuracy="high")
    assert sol.error_params["scale_x"] == pytest.approx(0.02, abs=1e-7)


# --------------------------------------------------------------- composition
def test_composition_and_names():
    t = np.linspace(0, 1, 11)
    data = bvpnav.ImuData(t, np.zeros((11, 2)))
    em = ScaleFactor() + Bias(axes="y") + Misalignment()
    assert isinstance(em, CompositeErrorModel)
    assert em.names(data) == ["scale_x", "scale_y", "bias_y", "misalignment_xy", "misalignment_yx"]
    assert em.columns(data).shape == (11, 2, 5)
    assert sum([Bias(), ScaleFactor()]).names(data) == ["bias_x", "bias_y", "scale_x", "scale_y"]
    assert (Bias() + (ScaleFactor() + UnknownGravity())).names(data)[-1] == "gravity_y"
    with pytest.raises(InputError, match="bias_x"):
        (Bias() + Bias(axes="x")).names(data)
    with pytest.raises(InputError, match="unknown sensor axis 'q'"):
        Bias(axes="q").names(data)
    with pytest.raises(InputError, match="at least two"):
        Misalignment(axes="x").names(data)
    with pytest.raises(InputError, match="without sigma"):
        Bias(prior=0.1)
    with pytest.raises(InputError, match="lo < hi"):
        Bias(bounds=(1.0, -1.0))
    with pytest.raises(InputError, match="sigma"):
        ScaleFactor(sigma=-1.0)
    with pytest.raises(InputError, match="not an error model"):
        CompositeErrorModel(Bias(), "bias")
    assert repr(Bias(axes="x") + ScaleFactor(sigma=0.01)) == "Bias(axes=('x',)) + ScaleFactor(sigma=0.01)"


def test_strapdown_columns_follow_attitude():
    """Bias columns are the body axes in the navigation frame (paper eq. 33)."""
    from scipy.spatial.transform import Rotation

    t = np.linspace(0, 1, 5)
    rot = Rotation.from_euler("z", np.linspace(0, np.pi / 2, 5)[:, None])
    f = np.tile([0.0, 0.0, 9.80665], (5, 1))
    data = bvpnav.ImuData(t, specific_force=f, attitude=rot)
    G = (Bias() + ScaleFactor(axes="z") + UnknownGravity()).columns(data)
    C = rot.as_matrix()
    assert np.allclose(G[:, :, 0], C[:, :, 0])  # bias_x: body x in nav frame
    assert np.allclose(G[-1, :, 0], [0, 1, 0], atol=1e-15)  # body x points north after 90 deg
    assert np.allclose(G[:, :, 3], C[:, :, 2] * 9.80665)  # scale_z: C e_z f_z
    assert np.allclose(G[:, :, 4], [1, 0, 0]) and np.allclose(G[:, :, 6], [0, 0, 1])


def test_custom_model_defaults():
    """A subclass with names/columns only: identity report, linear priors and bounds."""
    from dataclasses import dataclass

    @dataclass(frozen=True, kw_only=True, eq=False)
    class Offset(ErrorModel):
        units = "m/s^2"

        def names(self, data):
            return ["offset"]

        def columns(self, data):
            return np.ones((data.n, data.ndim, 1))

    t = np.linspace(0, 10, 101)
    data = bvpnav.ImuData(t, np.cos(t) - 0.25)
    prob = bvpnav.NavigationProblem(data, error_model=Offset(bounds=(-1.0, 1.0)))
    prob.add(Position(t=0.0, value=0.0), Velocity(t=[0, 10], value=[0.0, np.sin(10)]))
    sol = prob.solve(accuracy="high")
    assert isinstance(sol.error_params, pd.Series)
    assert sol.error_params["offset"] == pytest.approx(0.25, abs=2e-3)
    assert sol.error_params.attrs["units"] == {"offset": "m/s^2"}
