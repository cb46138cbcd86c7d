"""Cyclic reduction of symmetric block-tridiagonal matrices against dense linear algebra."""

from __future__ import annotations

import numpy as np
import pytest

from bvpnav.linalg.selinv import CyclicReduction, block_tridiagonal_dense, equilibrated_inverse


def _random(n, b, seed, definite=False):
    rng = np.random.default_rng(seed)
    D = rng.normal(size=(n, b, b))
    D = D + np.swapaxes(D, 1, 2)
    U = rng.normal(size=(max(n - 1, 0), b, b))
    if definite:
        D = D + 4.0 * b * np.eye(b)
    else:  # indefinite, like a KKT matrix
        D = D + np.diag(np.linspace(-3.0, 3.0, b))
    return D, U


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 7, 8, 16, 31, 33, 100])
@pytest.mark.parametrize("b", [1, 3])
def test_selected_inverse_equals_the_dense_inverse_on_the_pattern(n, b):
    D, U = _random(n, b, seed=n * 10 + b)
    A = block_tridiagonal_dense(D, U)
    Z = np.linalg.inv(A)
    Zd, Zu = CyclicReduction(D, U).selected_inverse()
    scale = np.abs(Z).max()
    for i in range(n):
        assert np.abs(Zd[i] - Z[i * b:(i + 1) * b, i * b:(i + 1) * b]).max() <= 1e-10 * scale
        if i + 1 < n:
            assert np.abs(Zu[i] - Z[i * b:(i + 1) * b, (i + 1) * b:(i + 2) * b]).max() <= 1e-10 * scale


@pytest.mark.parametrize("n", [1, 2, 6, 9, 64])
def test_solve_one_and_several_right_hand_sides(n):
    b = 3
    D, U = _random(n, b, seed=n, definite=True)
    A = block_tridiagonal_dense(D, U)
    cr = CyclicReduction(D, U)
    rng = np.random.default_rng(n)
    r = rng.normal(size=(n, b))
    assert np.allclose(cr.solve(r).ravel(), np.linalg.solve(A, r.ravel()), rtol=1e-12, atol=1e-12)
    R = rng.normal(size=(n, b, 4))
    X = cr.solve(R)
    assert X.shape == (n, b, 4)
    assert np.allclose(X.reshape(n * b, 4), np.linalg.solve(A, R.reshape(n * b, 4)), rtol=1e-12, atol=1e-12)


def test_inverse_of_a_tridiagonal_laplacian_is_the_known_one():
    # the Dirichlet Laplacian tridiag(-1, 2, -1) of size n has inverse
    # min(i, j) (n + 1 - max(i, j)) / (n + 1) (1-based indices)
    n = 50
    D = np.full((n, 1, 1), 2.0)
    U = np.full((n - 1, 1, 1), -1.0)
    Zd, Zu = CyclicReduction(D, U).selected_inverse()
    i = np.arange(1, n + 1)
    assert np.allclose(Zd[:, 0, 0], i * (n + 1 - i) / (n + 1), rtol=1e-13)
    assert np.allclose(Zu[:, 0, 0], i[:-1] * (n + 1 - i[1:]) / (n + 1), rtol=1e-13)


def test_a_singular_pivot_is_refused():
    D, U = _random(8, 2, seed=1)
    D[3] = 0.0  # an odd block at the first level: a zero pivot
    with pytest.raises(np.linalg.LinAlgError, match="singular"):
        CyclicReduction(D, U)


def test_equilibrated_inverse_accepts_badly_scaled_but_regular_blocks():
    s = np.array([1e-6, 1.0, 1e6])
    B = np.array([[2.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 0.0]])
    scaled = (s[:, None] * B * s[None, :])[None]
    inv = equilibrated_inverse(scaled)[0]
    assert np.allclose(inv @ scaled[0], np.eye(3), atol=1e-9)
    with pytest.raises(np.linalg.LinAlgError):
        equilibrated_inverse(np.array([[[1.0, 1.0], [1.0, 1.0]]]))
