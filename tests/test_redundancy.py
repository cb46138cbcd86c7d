"""``bvpnav.linalg.covariance.redundancy``: each row group's redundancy against the dense hat
matrix, their sum against the degrees of freedom, the refusal of a non-least-squares problem, and
variance component estimation with it recovering a fix noise that was stated wrongly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_uncertainty import dense_covariance

import bvpnav
from bvpnav.constraints import Position, PositionBound, Velocity
from bvpnav.error_models import Bias
from bvpnav.errors import InputError
from bvpnav.linalg.covariance import DATA_GROUP, posterior, redundancy


def _two_axis_problem():
    """Two axes, a bias, soft fixes and velocities, a hard start, a soft prior-like item."""
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 8.0, 65)
    acc = np.column_stack([np.cos(t), 0.3 * np.sin(2 * t)]) + 0.02 * rng.normal(size=(t.size, 2))
    p = bvpnav.NavigationProblem(bvpnav.ImuData(t, acc, axes=("x", "y")), sigma_a=0.02,
                                 error_model=Bias(sigma=0.1))
    ft = np.arange(0.5, 8.0, 1.0)
    p.add(Position(t=0.0, value=[0.0, 0.0]),
          Position(t=ft, value=rng.normal(0.0, 0.3, (ft.size, 2)), sigma=0.2, name="fixes"),
          Velocity(t=[2.0, 6.0], value=[[0.5, 0.0], [0.1, 0.2]], sigma=0.05, name="speeds"))
    return p


def test_redundancy_is_the_dense_hat_matrix_and_sums_to_the_degrees_of_freedom():
    from bvpnav.linalg.lsq import least_squares_form

    p = _two_axis_problem()
    sol = p.solve(solver="direct")
    form = sol.formulation
    red = redundancy(form, sol.x, sol.lam)
    C, exact = dense_covariance(form, sol.x, sol.lam)
    assert exact
    ls = least_squares_form(form, sol.lam)
    D = ls.D.A.toarray()
    h = np.einsum("ij,jk,ik->i", D, C, D)
    res = ls.D.value(sol.x)
    start = 0
    for label in [DATA_GROUP, "fixes", "speeds"]:
        m = red[label][0]
        assert red[label][1] == pytest.approx(m - h[start:start + m].sum(), rel=1e-9, abs=1e-9)
        assert red[label][2] == pytest.approx(float(res[start:start + m] @ res[start:start + m]), rel=1e-12)
        start += m
    groups = set(red) - {DATA_GROUP, "fixes", "speeds"}   # the bias prior
    assert len(groups) == 1
    assert start + red[groups.pop()][0] == D.shape[0]
    total = sum(r for _, r, _ in red.values())
    assert total == pytest.approx(posterior(form, sol.x, sol.lam).dof, abs=1e-8)
    # the fixes are information about the path: each of their rows is less than redundant
    assert 0.0 < red["fixes"][1] < red["fixes"][0]


def test_redundancy_refuses_a_problem_that_is_not_least_squares():
    p = _two_axis_problem()
    p.add(PositionBound(upper=10.0, t0=3.8, t1=4.2))
    sol = p.solve(solver="clarabel")
    with pytest.raises(InputError, match="not least squares"):
        redundancy(sol.formulation, sol.x, sol.lam)


def test_variance_components_recover_a_wrongly_stated_fix_noise():
    """Foerstner's iteration on the fixes' group: true fix noise 0.5 m stated as 0.1 m (and as
    2 m), the accelerometer's noise stated right; the estimate lands within three of its standard
    errors, sqrt(1 / (2 r)) relative, of the truth, from either side."""
    rng = np.random.default_rng(11)
    t = np.linspace(0.0, 200.0, 2001)
    sigma_a, true = 0.01, 0.5
    acc = sigma_a * rng.normal(size=t.size)   # a car at rest; the truth is r = 0
    ft = np.arange(1.0, 200.0, 1.0)
    fixes = true * rng.normal(size=(ft.size, 1))
    for stated in (0.1, 2.0):
        sigma = stated
        for _ in range(30):
            p = bvpnav.NavigationProblem(bvpnav.ImuData(t, acc[:, None], axes=("x",)), sigma_a=sigma_a)
            p.add(Position(t=ft, value=fixes, sigma=sigma, name="fixes"))
            sol = p.solve(solver="direct")
            m, r, omega = redundancy(sol.formulation, sol.x, sol.lam)["fixes"]
            if abs(omega / r - 1.0) < 1e-4:
                break
            sigma *= math.sqrt(omega / r)
        assert abs(omega / r - 1.0) < 1e-4          # converged
        assert 10.0 < r < m                         # enough redundancy to estimate it
        assert abs(sigma / true - 1.0) < 3.0 * math.sqrt(1.0 / (2.0 * r))
