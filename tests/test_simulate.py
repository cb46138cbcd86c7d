"""Simulator, gyro integration and the strapdown input path."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import bvpnav
from bvpnav import simulate
from bvpnav.attitude import body_rates, cumulative_product, integrate_gyro
from bvpnav.constraints import Position
from bvpnav.errors import InputError


@pytest.fixture(scope="module")
def motion():
    return simulate.strapdown_3d_2010(rate=20.0).motion


def test_specific_force_reconstructs_acceleration(motion):
    """Noise-free: C f + g is the true acceleration, and ImuData builds exactly that."""
    sim = simulate.simulate_imu(motion, 50.0, gravity=[0.1, 0.0, -9.8])
    acc = sim.truth[["ax", "ay", "az"]].to_numpy()
    back = sim.attitude.apply(sim.specific_force) + sim.gravity
    assert np.abs(back - acc).max() < 1e-12
    data = sim.imu_data(gravity=sim.gravity)
    assert data.is_strapdown and np.abs(data.acc - acc).max() < 1e-12
    # clamped splines: the motion starts and ends at rest
    v = sim.truth[["vx", "vy", "vz"]].to_numpy()
    assert np.abs(v[[0, -1]]).max() < 1e-12 and np.abs(v).max() > 1.0


def test_fem_is_exact_on_simulated_data(motion):
    """Waypoints on the sampling grid: the FEM reproduces the spline to rounding."""
    sim = simulate.simulate_imu(motion, 20.0)
    T = float(sim.t[-1])
    prob = bvpnav.NavigationProblem(sim.imu_data()).add(Position(t=[0, T], value=sim.position([0, T])))
    sol = prob.solve(accuracy="high")
    assert np.abs(sol.position() - sim.truth[["x", "y", "z"]].to_numpy()).max() < 1e-8
    assert np.abs(sol.velocity() - sim.truth[["vx", "vy", "vz"]].to_numpy()).max() < 1e-8


def test_body_rate_formula_matches_attitude(motion):
    """Analytic Euler-rate body rates agree with differences of the attitude (O(h^2))."""
    t = simulate.sample_times(0.0, 20.0, 1000.0)
    w = motion.body_rate(t)
    fd = body_rates(t, motion.attitude(t))
    inner = slice(1, -1)
    assert np.abs(w[inner] - fd[inner]).max() < 1e-4 * np.abs(w).max()
    assert np.abs(w).max() > 0.5  # the scenario really rotates


def test_sensor_errors_model_and_noise():
    rng = np.random.default_rng(0)
    e = simulate.SensorErrors(bias=[0.1, 0.2, 0.3], scale=0.01, misalignment={"xy": 0.002}, noise=0.0)
    u = rng.normal(size=(7, 3))
    out = e.apply(u, np.random.default_rng(1))
    D = np.diag([1.01] * 3) @ (np.eye(3) + np.array([[0, 0.002, 0], [0, 0, 0], [0, 0, 0]]))
    assert np.allclose(out, u @ D.T + [0.1, 0.2, 0.3], atol=1e-15)
    n = simulate.SensorErrors(noise=[0.5, 1.0, 2.0]).apply(np.zeros((20000, 3)), np.random.default_rng(2))
    assert np.allclose(n.std(axis=0), [0.5, 1.0, 2.0], rtol=0.03)
    assert np.allclose(n.mean(axis=0), 0.0, atol=0.05)
    with pytest.raises(InputError, match="misalignment"):
        simulate.SensorErrors(misalignment=np.eye(3)).matrix(3)
    with pytest.raises(InputError, match="bias"):
        simulate.SensorErrors(bias=[1, 2]).apply(np.zeros((2, 3)), rng)


def test_seed_reproducible_and_truth_independent_of_seed():
    a = simulate.strapdown_3d_2010(rate=20.0, noise=0.05, seed=7)
    b = simulate.strapdown_3d_2010(rate=20.0, noise=0.05, seed=7)
    c = simulate.strapdown_3d_2010(rate=20.0, noise=0.05, seed=8)
    assert np.array_equal(a.specific_force, b.specific_force)
    assert not np.array_equal(a.specific_force, c.specific_force)
    assert np.array_equal(a.truth.to_numpy(), c.truth.to_numpy())
    resid = a.specific_force - (a.specific_force_true @ a.accel.matrix(3).T + a.accel.bias)
    assert resid.std() == pytest.approx(0.05, rel=0.05)


def test_integrate_gyro_constant_rate_exact():
    t = np.linspace(0.0, 5.0, 501)
    w = np.tile([0.3, -0.2, 0.5], (t.size, 1))
    r0 = Rotation.from_euler("ZYX", [0.3, 0.1, -0.2])
    att = integrate_gyro(t, w, r0)
    exact = r0 * Rotation.from_rotvec(t[:, None] * w[0])
    assert (att.inv() * exact).magnitude().max() < 1e-12


def test_cumulative_product_matches_loop():
    rng = np.random.default_rng(4)
    steps = Rotation.from_rotvec(rng.normal(0, 0.3, (37, 3)))
    fast = cumulative_product(steps)
    acc = Rotation.identity()
    for k in range(37):
        acc = acc * steps[k]
        assert (fast[k].inv() * acc).magnitude() < 1e-13


def test_integrate_gyro_second_order(motion):
    """Attitude error from the true body rates falls by ~4 when the step halves."""
    errs = []
    for rate in (25.0, 50.0, 100.0):
        t = simulate.sample_times(0.0, 20.0, rate)
        att = integrate_gyro(t, motion.body_rate(t), motion.attitude(t[:1])[0])
        errs.append((att.inv() * motion.attitude(t)).magnitude().max())
    r1, r2 = errs[0] / errs[1], errs[1] / errs[2]
    assert 3.5 < r1 < 4.5 and 3.5 < r2 < 4.5, errs
    assert errs[-1] < 1e-3


def test_imu_from_gyro(motion):
    sim = simulate.simulate_imu(motion, 100.0)
    data = sim.imu_data(attitude="gyro")
    assert data.gyro is not None and data.gyro.shape == (sim.t.size, 3)
    assert (data.attitude.inv() * sim.attitude).magnitude().max() < 1e-3
    d2 = bvpnav.ImuData.from_gyro(sim.t, sim.specific_force, sim.gyro)  # identity start
    assert (d2.attitude[0].inv() * Rotation.identity()).magnitude() < 1e-15
    with pytest.raises(InputError, match="gyro"):
        bvpnav.ImuData.from_gyro(sim.t, sim.specific_force, sim.gyro[:, :2])
    bad = sim.gyro.copy()
    bad[5, 1] = np.nan
    with pytest.raises(InputError, match="sample 5"):
        bvpnav.ImuData.from_gyro(sim.t, sim.specific_force, bad)


def test_sample_times_and_motion_validation():
    t = simulate.sample_times(0.0, 2.0, 10.0)
    assert t.size == 21 and t[-1] == 2.0
    with pytest.raises(InputError, match="whole number"):
        simulate.sample_times(0.0, 1.0, 2.5 + 1e-3)
    with pytest.raises(InputError, match="euler"):
        simulate.Motion.from_waypoints([0, 1, 2], np.zeros((3, 3)), np.zeros((3, 2)))
    with pytest.raises(InputError, match="whole number"):
        simulate.strapdown_3d_2010(duration=10.5)


@pytest.mark.parametrize("test,revs", [(1, 7), (2, 62)])
def test_rate_table_geometry(test, revs):
    """Paper's numbers: 7 revolutions = 10.4 m in 20 s; 62 revolutions in 100 s."""
    sim = simulate.rate_table(test, 100.0, bias=0.0, scale=0.0, mounting=0.0, noise_density=0.0)
    assert sim.radius == pytest.approx(10.4 / (7 * 2 * np.pi))
    assert sim.position[-1] == pytest.approx(revs * 2 * np.pi * sim.radius, rel=1e-12)
    if test == 1:
        assert sim.position[-1] == pytest.approx(10.4, rel=1e-12)
    assert sim.duration == (20.0 if test == 1 else 100.0)
    assert sim.period == 2.0
    assert np.array_equal(sim.acc, sim.acceleration)  # no errors: the sensor reads the tangential acc
    # starts and ends each repeat at rest; v and a are consistent (trapezoid to O(h^2))
    assert sim.velocity[0] == 0 and sim.velocity[-1] == 0
    h = np.diff(sim.t)
    v = np.concatenate([[0.0], np.cumsum(0.5 * h * (sim.acc[:-1] + sim.acc[1:]))])
    assert np.abs(v - sim.velocity).max() < 1e-3 * sim.velocity.max()
    r, vq = sim.truth_at([sim.duration / 2])
    assert r[0] == pytest.approx(sim.position[-1] / 2, rel=1e-12) and vq[0] == pytest.approx(0.0, abs=1e-12)


def test_rate_table_errors_and_rest():
    sim = simulate.rate_table(1, 100.0, bias=0.3, scale=0.02, mounting=0.0, noise_density=0.0, rest=1.5)
    assert sim.rest_acc.size == 150 and np.allclose(sim.rest_acc, 0.3)
    assert np.allclose(sim.acc, 1.02 * sim.acceleration + 0.3)
    tilted = simulate.rate_table(1, 100.0, bias=0.0, scale=0.0, mounting=0.01, noise_density=0.0)
    leak = np.sin(0.01) * np.mean(tilted.centripetal)
    assert tilted.effective_bias == pytest.approx(leak) and leak > 0
    with pytest.raises(InputError, match="test"):
        simulate.rate_table(3)
