"""``uncertainty="scaled"`` that cannot be scaled says so (issue 40, case 7): no degrees of
freedom leave the variance factor undefined, an exact fit makes it 0."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.log import BvpnavWarning
from bvpnav.solve.uncertainty import EXACT_FIT

T = np.linspace(0.0, 10.0, 101)


def _problem(noise: float, *extra) -> bvpnav.NavigationProblem:
    acc = 2.0 + noise * np.random.default_rng(3).standard_normal(T.size)  # r = t^2 without noise
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=acc), sigma_a=0.1).add(
        Position(t=0.0, value=0.0, name="start"), Velocity(t=0.0, value=0.0, name="at rest"), *extra)


def test_zero_degrees_of_freedom_warns_and_returns_the_stated_deviations():
    """A position and a velocity at one instant fix the estimate exactly: every residual
    row is used by the unknowns (dof = 0) and the variance factor is 0/0."""
    p = _problem(0.1)
    stated = p.solve(solver="direct", uncertainty=True)
    with pytest.warns(BvpnavWarning, match=r"0 degrees of freedom .* the a-posteriori variance factor "
                                           r"is undefined; the standard deviations returned are those "
                                           r"of the stated noise"):
        sol = p.solve(solver="direct", uncertainty="scaled")
    u = sol.stats["uncertainty"]
    assert u["dof"] == 0 and u["unscalable"] == "0 degrees of freedom" and u["scale"] == "stated"
    assert np.isnan(u["variance_factor"])
    assert np.allclose(sol.trajectory["x_std"], stated.trajectory["x_std"], rtol=1e-12, atol=0)
    # white acceleration noise sigma per sample of step h, integrated twice over T from a known
    # start: var r(T) ~ sigma^2 h T^3 / 3 (0.577 m): the stated deviations, not 0 and not NaN
    assert sol.trajectory["x_std"].iloc[-1] == pytest.approx(np.sqrt(0.1**2 * 0.1 * 10.0**3 / 3), rel=0.02)
    assert "unscalable" not in stated.stats["uncertainty"]  # nothing was asked to be scaled


def test_an_exact_fit_warns_that_the_zero_deviations_say_nothing():
    """Noise-free constant acceleration (the FEM is exact for it) and a fix on the truth:
    the residuals vanish to rounding, so the scaled deviations do too."""
    p = _problem(0.0, Position(t=10.0, value=100.0, sigma=0.5, name="fix"))
    with pytest.warns(BvpnavWarning, match=r"an exact fit.*every scaled standard deviation is about 0"):
        sol = p.solve(solver="direct", uncertainty="scaled")
    u = sol.stats["uncertainty"]
    assert u["dof"] == 1 and u["unscalable"] == "exact fit" and u["scale"] == "scaled"
    assert u["variance_factor"] < 1e-20  # measured ~1e-29: far below EXACT_FIT = 1e-12
    stated = p.solve(solver="direct", uncertainty=True).trajectory["x_std"]
    assert np.max(sol.trajectory["x_std"]) < 1e-9 * np.max(stated)


def test_a_noisy_fit_is_scaled_without_a_word():
    """The control: with 0.01 m/s^2 of noise against sigma_a = 0.1 the variance factor is
    about 1e-2, ten orders of magnitude above EXACT_FIT."""
    p = _problem(0.01, Position(t=10.0, value=100.0, sigma=0.5, name="fix"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", BvpnavWarning)
        sol = p.solve(solver="direct", uncertainty="scaled")
    u = sol.stats["uncertainty"]
    assert "unscalable" not in u and u["scale"] == "scaled"
    assert 1e-4 < u["variance_factor"] < 1.0 and u["variance_factor"] > 1e6 * EXACT_FIT
