"""``bvpnav.linalg.covariance.redundancy``: each row group's redundancy against the dense hat
matrix, their sum against the degrees of freedom, the refusal of a non-least-squares problem, and
variance component estimation with it recovering a fix noise that was stated wrongly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_uncertainty import _random_zero_velocity, dense_covariance

import bvpnav
from bvpnav.constraints import AverageVelocity, Position, PositionBound, Velocity
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


def test_redundancy_of_hard_rows_singular_on_their_own_is_the_dense_hat_matrix():
    """Seed 6 of the uncertainty tests: a hard zero-velocity interval makes a run of nodes
    singular by itself; as for the covariance, its rows go through the border, and the
    redundancies are the dense hat matrix's and add up to the degrees of freedom."""
    from bvpnav.linalg.lsq import least_squares_form

    p = _random_zero_velocity(6)
    sol = p.solve(solver="direct")
    red = redundancy(sol.formulation, sol.x, sol.lam)
    C, _ = dense_covariance(sol.formulation, sol.x, sol.lam)
    D = least_squares_form(sol.formulation, sol.lam).D.A.toarray()
    h = np.einsum("ij,jk,ik->i", D, C, D)
    assert sum(r for _, r, _ in red.values()) == pytest.approx(D.shape[0] - h.sum(), abs=1e-8)
    assert sum(r for _, r, _ in red.values()) == pytest.approx(
        posterior(sol.formulation, sol.x, sol.lam).dof, abs=1e-8)


@pytest.mark.parametrize("item", [Velocity(t=[2.06, 6.01], value=[[0.5, 0.0], [0.1, 0.2]], sigma=0.05,
                                           name="between"),
                                  AverageVelocity(t0=1.0, t1=5.0, value=[0.2, 0.1], sigma=0.05,
                                                  name="between")])
def test_redundancy_names_an_item_whose_rows_reach_beyond_two_nodes(item):
    """A soft velocity between samples, or an average over an interval, reaches more than two
    neighbouring nodes: refused with the item's name and what to do, not an internal error."""
    p = _two_axis_problem()
    p.add(item)
    sol = p.solve(solver="direct")
    with pytest.raises(InputError, match="'between' reach more than two neighbouring nodes"):
        redundancy(sol.formulation, sol.x, sol.lam)


def test_redundancy_refuses_a_problem_that_is_not_least_squares():
    p = _two_axis_problem()
    p.add(PositionBound(upper=10.0, t0=3.8, t1=4.2))
    sol = p.solve(solver="clarabel")
    with pytest.raises(InputError, match="not least squares"):
        redundancy(sol.formulation, sol.x, sol.lam)


def _fix_noise_estimate(t, acc, sigma_a, ft, fixes, stated):
    """Foerstner's iteration on the fixes' group from ``stated`` (m): ``(sigma, m, r, omega)`` at
    convergence."""
    sigma = stated
    for _ in range(40):
        p = bvpnav.NavigationProblem(bvpnav.ImuData(t, acc[:, None], axes=("x",)), sigma_a=sigma_a)
        p.add(Position(t=ft, value=fixes, sigma=sigma, name="fixes"))
        sol = p.solve(solver="direct")
        m, r, omega = redundancy(sol.formulation, sol.x, sol.lam)["fixes"]
        ratio = omega / r
        if abs(ratio - 1.0) < 1e-4:
            break
        sigma *= math.sqrt(ratio)
    assert abs(ratio - 1.0) < 1e-4   # converged
    return sigma, m, r, omega


def test_variance_components_recover_a_wrongly_stated_fix_noise():
    """Foerstner's iteration on the fixes' group: true fix noise 0.5 m stated as 0.1 m (and as
    2 m), the accelerometer's noise stated right and large enough that the path follows the fixes
    (a redundancy of about 0.7 per fix); the estimate lands within three of its standard errors,
    sqrt(1 / (2 r)) relative, of the truth, from either side. Dividing by the rows instead of
    the redundancy (no hat matrix) would not do: over 20 draws with the noise stated right the
    fixes' square sum averages their redundancy (E[Omega] = r, within four standard errors of
    the mean), well below their rows."""
    rng = np.random.default_rng(11)
    t = np.linspace(0.0, 200.0, 2001)
    sigma_a, true = 1.0, 0.5
    acc = sigma_a * rng.normal(size=t.size)   # a body at rest: its true position is 0
    ft = np.arange(1.0, 200.0, 1.0)
    fixes = true * rng.normal(size=(ft.size, 1))
    for stated in (0.1, 2.0):
        sigma, m, r, _ = _fix_noise_estimate(t, acc, sigma_a, ft, fixes, stated)
        assert 10.0 < r < 0.8 * m                   # enough redundancy, and well below the rows
        assert abs(sigma / true - 1.0) < 3.0 * math.sqrt(1.0 / (2.0 * r))
    ratios = []
    for _ in range(20):
        p = bvpnav.NavigationProblem(bvpnav.ImuData(t, sigma_a * rng.normal(size=(t.size, 1)), axes=("x",)),
                                     sigma_a=sigma_a)
        p.add(Position(t=ft, value=true * rng.normal(size=(ft.size, 1)), sigma=true, name="fixes"))
        sol = p.solve(solver="direct")
        m, r, omega = redundancy(sol.formulation, sol.x, sol.lam)["fixes"]
        ratios.append((omega / r, omega / m, r / m))
    by_r, by_m, share = np.mean(ratios, axis=0)
    assert abs(by_r - 1.0) < 4.0 * math.sqrt(2.0 / r) / math.sqrt(20)
    assert by_m < 0.85 and share < 0.8
