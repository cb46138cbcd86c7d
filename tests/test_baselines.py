"""Initial-value integrators and the RTS smoother against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

import bvpnav
from bvpnav import baselines as B
from bvpnav.scenarios import tikhonov2011


def _profile(rate=400.0, T=4.0):
    t = np.arange(0.0, T + 1e-12, 1.0 / rate)
    w = 2 * np.pi * 3.0
    a = np.sin(w * t)
    v = (1 - np.cos(w * t)) / w
    r = t / w - np.sin(w * t) / w**2
    return t, a, v, r


@pytest.mark.parametrize("rule,order", [(B.trapezoid, 2), (B.simpson, 4)])
def test_convergence_orders(rule, order):
    errs = []
    for rate in (100.0, 200.0, 400.0):
        t, a, v, r = _profile(rate)
        vv, rr = rule(t, a)
        errs.append(np.max(np.abs(vv - v)) + np.max(np.abs(rr - r)))
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(rates > order - 0.3), rates


def test_romberg_block_is_exact_for_degree_7_polynomials():
    h = 0.1
    x = np.arange(9) * h
    y = 3 * x**7 - x**3 + 2
    exact = 3 * x[-1] ** 8 / 8 - x[-1] ** 4 / 4 + 2 * x[-1]
    assert abs(B.romberg_block(y, h) - exact) < 1e-13


def test_romberg_beats_trapezoid_and_checks_its_grid():
    t, a, v, r = _profile(400.0)
    vt, _ = B.trapezoid(t, a)
    vr, rr = B.romberg(t, a)
    # (at the end of whole periods the trapezoid rule is exact, so compare everywhere)
    assert np.max(np.abs(vr - v)) < np.max(np.abs(vt - v)) / 100
    assert np.max(np.abs(rr - r)) < 1e-7
    t2 = t.copy()
    t2[5] += 1e-4
    with pytest.raises(bvpnav.InputError, match="step 4"):
        B.romberg(t2, a)


def test_rts_brownian_bridge_variance():
    """Velocity as a random walk pinned at both ends: Var v_k = q k (n-1-k)/(n-1)."""
    n, sa = 101, 2.0
    t = np.linspace(0.0, 1.0, n)
    df = B.rts_smoother(t, np.zeros(n), [(0.0, "velocity", 0.0, 1e-9), (1.0, "velocity", 0.0, 1e-9)],
                        sigma_a=sa, bias0_std=0.0)
    k = np.arange(1, n - 1)
    q = (sa * t[1]) ** 2
    np.testing.assert_allclose(df.velocity_std.to_numpy()[1:-1] ** 2, q * k * (n - 1 - k) / (n - 1),
                               rtol=1e-9)


@pytest.mark.parametrize("sigma_a", [1e-2, 1e-3, 1e-4, 1e-6])
def test_rts_recovers_a_constant_bias_from_four_boundary_values(sigma_a):
    """Also a numerical-stability test: with tiny process noise against a 10 m/s^2 bias
    prior, a pseudo-inverse smoother gain lost the answer (0.2 m RMS at sigma_a = 1e-4);
    Joseph-form updates and a solved gain keep the ZOH discretisation error (~2e-4 m)."""
    sc = tikhonov2011(scale=0.0, bias=0.5, noise=0.0)
    meas = [(0.0, "position", 0.0, 1e-6), (0.0, "velocity", 0.0, 1e-6),
            (10.0, "position", 10.0, 1e-6), (10.0, "velocity", 0.0, 1e-6)]
    df = B.rts_smoother(sc.t, sc.data.acc[:, 0], meas, sigma_a=sigma_a)
    assert abs(df.bias.iloc[0] - 0.5) < 1e-3
    assert np.sqrt(np.mean((df.position.to_numpy() - sc.position) ** 2)) < 5e-4


def test_rts_rejects_measurements_between_samples():
    t = np.linspace(0, 1, 11)
    with pytest.raises(bvpnav.InputError, match="measurement 0.*not a sample time"):
        B.rts_smoother(t, np.zeros(11), [(0.05, "position", 0.0, 1.0)])
