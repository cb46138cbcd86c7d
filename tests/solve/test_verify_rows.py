"""The verification's stationarity from each term's row weights (issue 18: no vector of
every unknown per item)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.terms import transposed_product


@pytest.mark.parametrize("density", [0.001, 0.01, 0.5])
def test_transposed_product_on_the_touched_columns_equals_the_dense_product(density):
    """``A^T u`` as ``(cols, values)``: few touched columns (summed there, repeated columns
    too), or many (the whole product), equal to scipy's product, zero elsewhere."""
    rng = np.random.default_rng(int(density * 1000))
    for trial in range(10):
        A = sp.random(int(rng.integers(1, 40)), 3000, density=density, format="csr", random_state=trial)
        A.data -= 0.5
        u = rng.normal(size=A.shape[0])
        cols, vals = transposed_product(A, u)
        got = np.zeros(A.shape[1])
        got[cols] = vals
        np.testing.assert_allclose(got, A.T @ u, rtol=1e-13, atol=1e-15)
        if A.nnz * 8 <= A.shape[1]:
            assert isinstance(cols, np.ndarray) and cols.size == np.unique(A.indices).size


def test_each_term_gradient_is_its_matrix_transposed_times_its_row_weights():
    """For hard (with duals), soft and robust (Huber) equality rows, ``Term.gradient`` is
    ``A^T gradient_rows``; without its duals a hard term has neither; and an answer judged
    from the row weights verifies with its stationarity at round-off."""
    rng = np.random.default_rng(2)
    t = np.linspace(0.0, 4.0, 401)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=0.2 * np.sin(t) + 0.05 * rng.normal(size=t.size)))
    prob.add(Position(t=[0.0, 4.0], value=[0.0, 1.0], name="ends"))
    prob.add(Position(t=np.arange(0.25, 4.0, 0.5), value=rng.normal(size=8) * 0.1, sigma=0.1, name="fixes"))
    prob.add(Velocity(t=2.0, value=0.3, sigma=0.05, mode="robust", huber=0.1, name="robust v"))
    x = rng.normal(size=prob.formulation.model.size)
    duals = {"ends": [rng.normal(size=2)]}
    modes = set()
    for term in prob.formulation.terms():
        u = term.gradient_rows(x, 2.0, duals.get(term.label))
        assert u is not None and u.shape == (term.residual.m,)
        np.testing.assert_allclose(term.gradient(x, 2.0, duals.get(term.label)), term.residual.A.T @ u,
                                   rtol=1e-13, atol=1e-15)
        modes.add(term.mode)
        if term.mode == "hard":
            assert term.gradient_rows(x, 2.0, None) is None and term.gradient(x, 2.0, None) is None
    assert modes == {"hard", "soft", "robust"}
    sol = prob.solve(solver="clarabel", lam=1.0)   # the robust row: a conic solver
    assert sol.stats["verified"] and sol.stats["verification"]["stationarity"] < 1e-6
