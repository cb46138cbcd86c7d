r"""Direct back ends: sparse factorizations of the least-squares KKT system, no cvxpy.

Registered in the back-end table on import (the folder is discovered):

- ``direct``: one factorization of the KKT system (see :mod:`bvpnav.linalg.lsq`) with the
  error-model parameters eliminated through their Schur complement, then iterative
  refinement against the exact augmented system. Option ``method``: ``"banded"``
  (:mod:`bvpnav.linalg.banded`: unknowns ordered by time node, LAPACK's banded LU, far rows and
  parameters bordered; the default for the acceleration form), ``"ldl"`` (QDLDL on the
  statically regularized quasi-definite matrix; the fallback when rows are not local),
  ``"lu"`` (SuperLU with pivoting; the default for the load form, whose residuals must
  not be squared) or ``"auto"``. Option ``refine_tol``: the banded answer's refinement
  stops when the relative correction is below it (1e-6, 1e-8, 1e-10 for the ``low``,
  ``default`` and ``high`` presets: a hundredth of their forward-error bounds).
- ``csne``: the 2011 paper's corrected semi-normal equations: the normal matrix
  :math:`\tilde A = \sum D_k^T D_k` (banded for banded items) is factorised once and the
  least-squares residual is corrected by iterative refinement
  (:math:`x \leftarrow x + \tilde A^{-1} D^T (d - D x)`); equality constraints are handled
  by the same refinement on the KKT system built with the normal matrix.

``direct`` also takes band items (``|r| <= tol``) and hard or band inequality items
(``g <= 0``): first a primal-dual active-set method (:mod:`bvpnav.linalg.active_set`: the
rows guessed at their bounds held as hard rows, the guess updated from the violations and
the multipliers' signs, each update one banded factorization; an outer loop's next solve
starts from the last answer's rows), then, where it gives way (a repeated or stalled guess,
a singular KKT matrix), a primal-dual interior-point method (:mod:`bvpnav.linalg.ipm`,
Mehrotra's predictor-corrector) whose every Newton step is one banded factorization of the
same KKT system, the inequality rows held like hard rows whose multipliers carry a diagonal
that changes from step to step. Option ``qp``: ``"auto"`` (that order), ``"active set"``
(no fallback: fails saying why) or ``"interior point"``; ``stats["qp_method"]`` says which
answered, ``stats["active_rows"]`` how many rows are at their bounds and
``stats["active_set"]`` the active set's updates or why it gave way (options ``ipm_tol``: the
relative tolerance of both methods' residuals and gap, 1e-7, 1e-9, 1e-10 for the presets;
``ipm_max_iter``; ``method="lu"`` or ``"ldl"``: a pivoted sparse LU at every step instead of
the banded factorization). Soft inequalities and bands with soft edges are rows of the same
systems with a constant diagonal (:mod:`bvpnav.linalg.ipm`, "Penalty rows"). Robust penalties
and cones are refused, naming the item; ``csne`` refuses every item that
is not a hard or soft equality.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ..checks import Invalid, Rule, number, one_of
from ..errors import InputError, SolveError
from ..formulation import Formulation
from ..linalg.active_set import QP_METHODS, solve_bands
from ..linalg.ipm import IPM_TOL, unsupported_term
from ..linalg.lsq import (
    BANDED_TOL,
    BorderedLU,
    Factored,
    least_squares_form,
    non_least_squares_term,
    solve_least_squares,
)
from ..linalg.workspace import Workspace
from . import Backend, RawSolve, register_backend
from .cvxpy_solvers import use_conic

__all__ = ["DirectBackend", "CsneBackend"]


_FRACTION = number(0, 1, low_open=True, high_open=True, want="a number between 0 and 1")

#: Values of the direct back ends' options (:mod:`bvpnav.checks` rules: a rule's ``want`` says
#: what a valid value is).
VALUES: dict[str, Rule] = {
    "method": one_of("auto", "banded", "lu", "ldl"),
    "refine": number(0, 100, integer=True, want="an integer from 0 to 100"),
    "max_iter": number(1, 10_000, integer=True, want="an integer from 1 to 10000"),
    "ldl_accept": _FRACTION,
    "tol": _FRACTION,
    "refine_tol": _FRACTION,
    "ipm_tol": _FRACTION,
    "ipm_max_iter": number(1, 1000, integer=True, want="an integer from 1 to 1000"),
    "qp": one_of(*QP_METHODS),
}


class _LeastSquaresBackend(Backend):
    """Shared by the direct back ends: least squares only, options by :data:`VALUES`."""

    least_squares_only = True

    def check_value(self, key: str, value) -> str | None:
        rule = VALUES.get(key)
        if rule is None:
            return None
        try:
            rule(value)
        except Invalid:
            return rule.want
        return None

    def refuse(self, form: Formulation) -> None:
        """Raise :class:`InputError` when ``form`` is not least squares (naming the item)."""
        why = self.accepts(form)
        if why is not None:
            raise InputError(why)

    def accepts(self, form: Formulation) -> str | None:
        term = non_least_squares_term(form)
        if term is None:
            return None
        return (f"solver {self.name!r} cannot take item {term.label!r} (kind {term.kind!r}, mode "
                f"{term.mode!r}): it solves equality-constrained least squares only. {use_conic()}"
                + (", or give the item mode='soft'." if term.kind == "equality" else "."))


class DirectBackend(_LeastSquaresBackend):
    """``direct``: one factorization of the KKT system, then refinement.

    Peak memory measured at N = 1,000,000 (one axis, own process, data and problem
    included): 1.12 GB on the acceleration form (the banded path; the reference banded
    solve of ``examples/benchmarks/speed_memory.py`` peaks at 0.74 GB in the same setting;
    at N = 10,000,000: 9.4 GB) and 2.96 GB on the load form (the pivoted LU).
    """

    name = "direct"
    uses_workspace = True
    memory_per_sample = {"acceleration": 1300.0, "load": 2960.0}
    presets = {name: {"refine": refine, "method": "auto", "ldl_accept": accept,
                      "refine_tol": BANDED_TOL[name], "ipm_tol": IPM_TOL[name], "ipm_max_iter": 80,
                      "qp": "auto"}
               for name, refine, accept in (("low", 1, 1e-5), ("default", 3, 1e-7), ("high", 6, 1e-9))}

    def accepts(self, form: Formulation) -> str | None:
        term = unsupported_term(form)
        if term is None:
            return None
        return (f"solver {self.name!r} cannot take item {term.label!r} (kind {term.kind!r}, mode "
                f"{term.mode!r}): it solves least squares with hard and band equalities and hard, band "
                f"and soft inequalities (no robust penalties or cones). {use_conic()}"
                + (", or give the item mode='soft' or mode='band'." if term.kind == "equality" else "."))

    def run(self, form: Formulation, lam: float, options: dict, verbose: bool = False,
            workspace: Workspace | None = None) -> RawSolve:
        self.refuse(form)
        if non_least_squares_term(form) is not None:
            return self._interior_point(form, lam, options, workspace)
        t0 = time.perf_counter()
        try:
            x, info = solve_least_squares(form, lam, refine=int(options["refine"]),
                                          method=options.get("method", "auto"),
                                          ldl_accept=float(options.get("ldl_accept", 1e-7)),
                                          banded_tol=float(options.get("refine_tol", BANDED_TOL["default"])),
                                          workspace=workspace)
        except (RuntimeError, np.linalg.LinAlgError) as exc:  # singular factorization / Schur
            raise SolveError(f"direct: the KKT matrix is singular ({exc}); some unknown is not "
                             "determined by the information",
                             attempts=[{"solver": "direct", "status": "singular",
                                        "reason": str(exc)}]) from exc
        duals = info.pop("duals")
        # verification reuses the factorization (one LU per solve, not two)
        factored = Factored(info.pop("form"), info.pop("factor"), info.pop("refined"))
        info.update(status="optimal", iterations=info["refinements"], solve_time=time.perf_counter() - t0,
                    setup_time=0.0, compile_time=0.0, objective=None)
        return RawSolve(x, info, duals, factored)

    def _interior_point(self, form: Formulation, lam: float, options: dict,
                        workspace: Workspace | None) -> RawSolve:
        """Bands and inequalities: :func:`bvpnav.linalg.active_set.solve_bands`."""
        t0 = time.perf_counter()
        method = options.get("method", "auto")
        try:
            x, info = solve_bands(form, lam, tol=float(options.get("ipm_tol", IPM_TOL["default"])),
                                  max_iter=int(options.get("ipm_max_iter", 80)),
                                  method="lu" if method in ("lu", "ldl") else method, workspace=workspace,
                                  qp_method=options.get("qp", "auto"))
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            raise SolveError(f"direct: a Newton step's KKT matrix is singular ({exc}); some unknown is "
                             "not determined by the information",
                             attempts=[{"solver": "direct", "status": "singular",
                                        "reason": str(exc)}]) from exc
        duals = info.pop("duals")
        info.pop("residuals")
        info.update(solve_time=time.perf_counter() - t0, setup_time=0.0,
                    compile_time=0.0, objective=None)
        return RawSolve(x, info, duals)


class CsneBackend(_LeastSquaresBackend):
    r"""``csne``: corrected semi-normal equations with iterative refinement.

    Peak memory measured at N = 1,000,000 (one axis): 2.77 GB (acceleration form) and
    3.06 GB (load form).

    Notes
    -----
    With the weighted objective rows ``D`` (data and soft items), ``d = -c`` and the hard
    rows ``E x + e = 0``, each step solves

    .. math::

        \begin{bmatrix} 2 D^T D & E^T \\ E & 0 \end{bmatrix}
        \begin{bmatrix} \delta x \\ \delta y \end{bmatrix} =
        \begin{bmatrix} -2 D^T (D x - d) - E^T y \\ -(E x + e) \end{bmatrix}

    with one factorization of the (banded, for banded items) matrix, the residuals being
    recomputed from ``D`` itself each time. The normal matrix squares the condition
    number, so more steps are needed as N grows (as in the paper's Table 2).
    """

    name = "csne"
    memory_per_sample = {"acceleration": 2770.0, "load": 3060.0}
    presets = {"low": {"max_iter": 5, "tol": 1e-8},
               "default": {"max_iter": 20, "tol": 1e-12},
               "high": {"max_iter": 50, "tol": 1e-15}}

    def run(self, form: Formulation, lam: float, options: dict, verbose: bool = False) -> RawSolve:
        self.refuse(form)
        t0 = time.perf_counter()
        ls = least_squares_form(form, lam)
        D, E = ls.D, ls.E
        H = (D.A.T @ D.A).tocsc()
        K = sp.bmat([[2.0 * H, E.A.T], [E.A, None]], format="csc")
        n = D.A.shape[1]
        try:
            # error-model parameters are dense columns (they touch every FEM row): eliminate
            # them through their Schur complement, or the LU fills in (roughly like N^2)
            lu = BorderedLU(K, form.model.l_index)
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            raise SolveError(f"csne: singular normal matrix ({exc})",
                             attempts=[{"solver": "csne", "status": "singular",
                                        "reason": str(exc)}]) from exc
        z = np.zeros(K.shape[0])
        max_it, tol = int(options["max_iter"]), float(options["tol"])
        corr, k, converged = np.inf, 0, False
        for _ in range(max_it):
            k += 1
            x, y = z[:n], z[n:]
            dz = lu.solve(np.concatenate([-2.0 * (D.A.T @ D.value(x)) - E.A.T @ y, -E.value(x)]))
            z += dz
            corr = float(np.linalg.norm(dz[:n]) / np.sqrt(n))
            if np.max(np.abs(dz[:n])) <= tol * max(np.max(np.abs(z[:n])), 1e-300):
                converged = True
                break
        x, y = z[:n], z[n:]
        duals = {label: (y[sl] if label == "fem" else [y[sl]]) for label, sl in ls.eq_blocks}
        info = {"status": "optimal" if converged else "inaccurate", "iterations": k,
                "correction": corr, "solve_time": time.perf_counter() - t0, "setup_time": 0.0,
                "compile_time": 0.0, "objective": None}
        return RawSolve(x, info, duals)


register_backend(DirectBackend())
register_backend(CsneBackend())
