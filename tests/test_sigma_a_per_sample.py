"""sigma_a per sample (issue 38): an impact sample with a large sigma stops corrupting the path."""

from __future__ import annotations

import numpy as np
import pytest

from bvpnav import ImuData, NavigationProblem
from bvpnav.constraints import Position, Velocity
from bvpnav.errors import InputError

pytestmark = pytest.mark.filterwarnings("ignore:misfit")  # the spike is a misfit, said so

T = np.linspace(0.0, 2.0, 201)
SPIKE = slice(100, 103)  # an impact: 3 samples of 50 m/s^2 on x, nothing moves


def problem(sigma_a):
    acc = np.zeros((T.size, 2))
    acc[SPIKE, 0] = 50.0
    prob = NavigationProblem(ImuData(t=T, acc=acc), sigma_a=sigma_a)
    prob.add(Position(t=[0.0, 2.0], value=0.0), Velocity(t=[0.0, 2.0], value=0.0))
    return prob


def test_a_large_sigma_at_the_impact_removes_it():
    plain = problem(0.02).solve(solver="direct").position().reshape(-1, 2)
    assert np.abs(plain[:, 0]).max() > 1e-2  # the spike, spread over all samples, bends the path
    sa = np.full(T.size, 0.02)
    sa[SPIKE] = 1e4
    sol = problem(sa).solve(solver="direct")
    pos = sol.position().reshape(-1, 2)
    assert np.abs(pos).max() < 1e-6  # the residual takes the spike where its sigma is large
    w = sol.residuals["w_x"].to_numpy()
    assert w[SPIKE] == pytest.approx(-50.0, rel=1e-6)


def test_shapes_and_equivalence():
    base = problem(0.02).solve(solver="direct").position()
    for sa in (np.full(T.size, 0.02), np.full((T.size, 2), 0.02), np.full((T.size, 1), 0.02)):
        p = problem(sa)
        assert p.sigma_a.shape == (T.size, 2)
        np.testing.assert_allclose(p.solve(solver="direct").position(), base, rtol=0, atol=1e-12)
    sa = np.full((T.size, 2), 0.02)
    sa[SPIKE, 1] = 1e4  # per axis: only y's weight changes, x still sees the spike
    px = problem(sa).solve(solver="direct").position().reshape(-1, 2)[:, 0]
    np.testing.assert_allclose(px, base.reshape(-1, 2)[:, 0], rtol=0, atol=1e-9)


def test_bad_shapes_are_named():
    with pytest.raises(InputError, match=r"shape \(5,\) for 201 samples"):
        problem(np.full(5, 0.1))
    sa = np.full(T.size, 0.1)
    sa[7] = 1e13
    with pytest.raises(InputError, match="sample 7"):
        problem(sa)
    sa[7] = -1.0
    with pytest.raises(InputError, match="positive"):
        problem(sa)
