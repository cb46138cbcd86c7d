"""StrideDrift: each stride's displacement as an unknown with a prior, and its sigma from the
recording (issue 38: a walk's end claimed to its real drift, so a soft SamePosition weighs right).

The walks are simulated in the navigation frame (x, y): stances of zero acceleration (plus, for
:func:`stride_sigma`, gravity through a tilt that changes from stance to stance) and swings whose
acceleration is the minimum-jerk step of a known length.
"""

from __future__ import annotations

import numpy as np
import pytest

import bvpnav
from bvpnav.constraints import Position, SamePosition, ZeroVelocity
from bvpnav.error_models import StrideDrift
from bvpnav.error_models.stride_drift import MAD_TO_SIGMA, stride_sigma
from bvpnav.errors import InputError
from bvpnav.testing import check_error_model

G0 = 9.80665
#: The simulated walks are noise-free or nearly: the misfit and variance-factor notes are expected.
pytestmark = [pytest.mark.filterwarnings("ignore:misfit"), pytest.mark.filterwarnings("ignore:uncertainty")]


def walk(n_strides=8, rate=50.0, stance=0.4, swing=0.6, length=1.4, headings=None, tilts=None, noise=0.0,
         seed=0):
    """Nav-frame (x, y) walk: ``n_strides + 1`` stances and the swings between them.

    Returns (data, intervals, true end position). ``tilts`` (n_strides + 1, 2) rad puts gravity
    into each stance's horizontal acceleration; ``noise`` is white acceleration noise, m/s^2.
    """
    rng = np.random.default_rng(seed)
    headings = np.zeros(n_strides) if headings is None else np.asarray(headings, dtype=float)
    period = stance + swing
    T = n_strides * period + stance
    t = np.round(np.arange(0.0, T + 0.5 / rate, 1.0 / rate), 10)
    acc = np.zeros((t.size, 2))
    intervals = [(k * period, k * period + stance) for k in range(n_strides + 1)]
    end = np.zeros(2)
    for k in range(n_strides):
        a = intervals[k][1]
        tau = (t - a) / swing
        inside = (tau > 0.0) & (tau < 1.0)
        prof = np.where(inside, (60 * tau - 180 * tau**2 + 120 * tau**3) / swing**2, 0.0)
        u = np.array([np.cos(headings[k]), np.sin(headings[k])])
        acc += length * prof[:, None] * u[None, :]
        end += length * u
    if tilts is not None:
        for k, (a, b) in enumerate(intervals):
            inside = (t >= a - 1e-9) & (t <= b + 1e-9)
            acc[inside] += G0 * np.asarray(tilts[k])
    acc += noise * rng.standard_normal(acc.shape)
    return bvpnav.ImuData(t=t, acc=acc, axes=("x", "y")), intervals, end


def problem(data, intervals, model=None, same=None):
    prob = bvpnav.NavigationProblem(data, error_model=model, sigma_a=0.05)
    prob.add(Position(t=0.0, value=0.0), *[ZeroVelocity(t0=a, t1=b, sigma=0.01) for a, b in intervals])
    if same is not None:
        prob.add(SamePosition(t=(float(data.t[0]), float(data.t[-1])), sigma=same))
    return prob


def test_contract():
    check_error_model(StrideDrift)


def test_bad_input_is_named():
    with pytest.raises(InputError, match="at least two"):
        StrideDrift(intervals=[(0.0, 1.0)], sigma=0.01)
    with pytest.raises(InputError, match="sorted and apart"):
        StrideDrift(intervals=[(2.0, 3.0), (0.0, 1.0)], sigma=0.01)
    data, iv, _ = walk(2)
    with pytest.raises(InputError, match="not inside the data's window"):
        StrideDrift(intervals=[(0.0, 1.0), (9.0, 99.0)], sigma=0.01).columns(data)
    with pytest.raises(InputError, match="at least three"):
        stride_sigma(data, iv[:2])


def test_invisible_to_the_stances():
    """With stances only, the estimate is the one without the model (to the quadrature error of
    the step's acceleration on the grid) and each stride keeps its prior."""
    data, iv, end = walk(8, noise=0.02)
    base = problem(data, iv).solve(solver="direct")
    sol = problem(data, iv, StrideDrift(intervals=iv, sigma=0.05)).solve(solver="direct")
    assert np.abs(sol.position() - base.position()).max() < 2e-3  # m, of an 11 m walk
    assert np.abs(sol.error_params.to_numpy()).max() < 2e-3       # m, against a prior of 0.05 m
    assert np.abs(base.position()[-1] - end).max() < 0.01 * end[0]  # the FEM on 30 samples per swing


def test_end_variance_grows_by_the_strides():
    """The claimed end variance per axis grows by the sum of the strides' variances."""
    data, iv, _ = walk(8)
    sig = 0.01 * (1.0 + np.arange(8))   # m, one per stride
    base = problem(data, iv).solve(solver="direct", uncertainty=True)
    sol = problem(data, iv, StrideDrift(intervals=iv, sigma=np.tile(sig, 2))).solve(solver="direct",
                                                                                    uncertainty=True)
    for ax in "xy":
        grow = sol.trajectory[f"{ax}_std"].iloc[-1] ** 2 - base.trajectory[f"{ax}_std"].iloc[-1] ** 2
        assert grow == pytest.approx(np.sum(sig**2), rel=0.02)


def test_same_position_pulls_by_the_variances():
    """A walk whose strides really drift (the data say 8 x 1.4 m east, the end is at the start):
    a soft SamePosition of sigma s moves the end by P / (P + s^2) of the gap, P its claimed
    variance; without the model P is the white noise's alone and the pull is a few per cent."""
    data, iv, end = walk(8)
    s = 0.1
    model = StrideDrift(intervals=iv, sigma=0.05)
    unc = problem(data, iv, model).solve(solver="direct", uncertainty=True)
    P = unc.trajectory["x_std"].iloc[-1] ** 2
    moved = end[0] - problem(data, iv, model, same=s).solve(solver="direct").position()[-1, 0]
    assert moved / end[0] == pytest.approx(P / (P + s**2), rel=0.02)
    assert 0.4 < P / (P + s**2) < 0.9
    plain = end[0] - problem(data, iv, same=s).solve(solver="direct").position()[-1, 0]
    assert plain / end[0] < 0.05


def test_stride_sigma_recovers_the_attitude_walk():
    """Monte Carlo: the tilt at each stance walks by a known sigma per stride; stride_sigma
    recovers it (the median-absolute estimator: its mean within 4 % over 200 walks, its spread
    that of 80 increments) and the strides' lengths."""
    true = np.radians(0.5)
    rng = np.random.default_rng(7)
    est = []
    for k in range(200):
        tilts = np.cumsum(true * rng.standard_normal((41, 2)), axis=0)
        data, iv, _ = walk(40, rate=25.0, headings=np.linspace(0.0, 3.0, 40), tilts=tilts, noise=0.01,
                           seed=k)
        sigma, info = stride_sigma(data, iv)
        est.append(info["sigma_psi"])
        if k == 0:
            assert info["lengths"] == pytest.approx(1.4, rel=0.03)  # trapezoids on 15 samples a swing
            assert sigma == pytest.approx(info["sigma_psi"] * info["lengths"])
    est = np.array(est) / true
    assert abs(est.mean() - 1.0) < 0.04
    # the median of |x| of 80 Gaussians: relative spread sqrt(pi/2 - ...) ~ 1.17 / sqrt(80) = 0.13
    assert 0.09 < est.std() < 0.18
    assert MAD_TO_SIGMA * np.median(np.abs(rng.standard_normal(200_000))) == pytest.approx(1.0, abs=0.01)


def test_from_stances_gives_the_recordings_sigma():
    tilts = np.cumsum(np.radians(1.0) * np.random.default_rng(3).standard_normal((9, 2)), axis=0)
    data, iv, _ = walk(8, tilts=tilts)
    model = StrideDrift.from_stances(data, iv)
    sigma, _ = stride_sigma(data, iv)
    assert model.sigma == pytest.approx(np.tile(sigma, 2))
    assert model.names(data)[:2] == ["stride_x[0]", "stride_x[1]"] and len(model.names(data)) == 16
