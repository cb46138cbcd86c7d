"""Direct back ends: sparse factorizations of the least-squares KKT system, no cvxpy.

Registered in the solver table on import (``bvpnav.solvers`` imports this module):

- ``direct``: one sparse factorization of the augmented system (see :mod:`bvpnav.kkt`)
  with the error-model parameters eliminated through their Schur complement, then
  iterative refinement; the residuals are never squared, so the load form stays
  accurate. Option ``method``: ``"ldl"`` (QDLDL on the statically regularized
  quasi-definite matrix; the default for the acceleration form, several times faster),
  ``"lu"`` (SuperLU with pivoting; the default for the load form) or ``"auto"``.
- ``csne``: the 2011 paper's corrected semi-normal equations: the normal matrix
  :math:`\\tilde A = \\sum D_k^T D_k` (banded for banded items) is factorised once and the
  least-squares residual is corrected by iterative refinement
  (:math:`x \\leftarrow x + \\tilde A^{-1} D^T (d - D x)`); equality constraints are handled
  by the same refinement on the KKT system built with the normal matrix.

Both refuse problems that are not equality-constrained least squares (inequality, band,
robust or cone items), naming the item.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from .errors import InputError, SolveError
from .kkt import BorderedLU, least_squares_form, non_least_squares_term, solve_least_squares
from .solvers import Backend, register_backend

__all__ = ["run_direct", "run_csne"]


def _refuse(problem, name: str) -> None:
    term = non_least_squares_term(problem)
    if term is not None:
        raise InputError(
            f"solver {name!r} solves equality-constrained least squares only; item "
            f"{term.label!r} has mode {term.mode!r} ({term.kind}). Use solver='clarabel' "
            "(or 'scs')."
        )


def run_direct(problem, lam: float, accuracy: str, options: dict):
    """Back end ``direct``: returns ``(x, info)`` for :meth:`NavigationProblem.solve`."""
    _refuse(problem, "direct")
    t0 = time.perf_counter()
    refine = int(options["refine"])
    try:
        x, info = solve_least_squares(problem, lam, refine=refine, method=options.get("method", "auto"),
                                      ldl_accept=float(options.get("ldl_accept", 1e-7)))
        # verification reuses the factorization (one LU per solve, not two)
        info["factored"] = (info.pop("form"), info.pop("factor"))
    except (RuntimeError, np.linalg.LinAlgError) as exc:  # singular factorization / Schur complement
        raise SolveError(f"direct: the KKT matrix is singular ({exc}); some unknown is not "
                         "determined by the information",
                         attempts=[{"solver": "direct", "status": "singular", "reason": str(exc)}]) from exc
    dt = time.perf_counter() - t0
    info.update(status="optimal", iterations=info["refinements"], solve_time=dt, setup_time=0.0,
                compile_time=0.0, objective=None)
    return x, info


def run_csne(problem, lam: float, accuracy: str, options: dict):
    """Back end ``csne``: corrected semi-normal equations with iterative refinement.

    Notes
    -----
    With the weighted objective rows ``D`` (data and soft items), ``d = -c`` and the hard
    rows ``E x + e = 0``, each step solves

    .. math::

        \\begin{bmatrix} 2 D^T D & E^T \\\\ E & 0 \\end{bmatrix}
        \\begin{bmatrix} \\delta x \\\\ \\delta y \\end{bmatrix} =
        \\begin{bmatrix} -2 D^T (D x - d) - E^T y \\\\ -(E x + e) \\end{bmatrix}

    with one factorization of the (banded, for banded items) matrix, the residuals being
    recomputed from ``D`` itself each time. The normal matrix squares the condition
    number, so more steps are needed as N grows (as in the paper's Table 2).
    """
    _refuse(problem, "csne")
    t0 = time.perf_counter()
    form = least_squares_form(problem, lam)
    D, E = form.D, form.E
    H = (D.A.T @ D.A).tocsc()
    K = sp.bmat([[2.0 * H, E.A.T], [E.A, None]], format="csc")
    n = D.A.shape[1]
    try:
        # error-model parameters are dense columns (they touch every FEM row): eliminate
        # them through their Schur complement, or the LU fills in (8.8 GB and counting for
        # a 3-D nine-parameter problem of 12,000 samples)
        lu = BorderedLU(K, problem.model.l_index)
    except (RuntimeError, np.linalg.LinAlgError) as exc:
        raise SolveError(f"csne: singular normal matrix ({exc})",
                         attempts=[{"solver": "csne", "status": "singular", "reason": str(exc)}]) from exc
    z = np.zeros(K.shape[0])
    max_it, tol = int(options["max_iter"]), float(options["tol"])
    corr, k, converged = np.inf, 0, False
    for _ in range(max_it):
        k += 1
        x, y = z[:n], z[n:]
        r1 = -2.0 * (D.A.T @ D.value(x)) - E.A.T @ y
        r2 = -E.value(x)
        dz = lu.solve(np.concatenate([r1, r2]))
        z += dz
        corr = float(np.linalg.norm(dz[:n]) / np.sqrt(n))
        if np.max(np.abs(dz[:n])) <= tol * max(np.max(np.abs(z[:n])), 1e-300):
            converged = True
            break
    x, y = z[:n], z[n:]
    duals = {label: (y[sl] if label == "fem" else [y[sl]]) for label, sl in form.eq_blocks}
    dt = time.perf_counter() - t0
    return x, {"status": "optimal" if converged else "inaccurate", "iterations": k,
               "correction": corr, "solve_time": dt, "setup_time": 0.0, "compile_time": 0.0,
               "objective": None, "duals": duals}


register_backend(Backend("direct", "direct", run=run_direct,
                         presets={"low": {"refine": 1, "method": "auto", "ldl_accept": 1e-5},
                                  "default": {"refine": 3, "method": "auto", "ldl_accept": 1e-7},
                                  "high": {"refine": 6, "method": "auto", "ldl_accept": 1e-9}}))
register_backend(Backend("csne", "direct", run=run_csne,
                         presets={"low": {"max_iter": 5, "tol": 1e-8},
                                  "default": {"max_iter": 20, "tol": 1e-12},
                                  "high": {"max_iter": 50, "tol": 1e-15}}))
