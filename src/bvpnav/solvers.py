"""Solvers by lowercase name, accuracy presets and verification tolerances.

One table maps a name to a back end. cvxpy solvers are used through cvxpy; bvpnav's
own direct back ends (registered by :mod:`bvpnav.direct` when available) solve the
same assembled problem without cvxpy. Every back end returns the stacked solution and
is judged by the same recomputed residuals (see :mod:`bvpnav.problem`).

Presets
-------
``low``, ``default`` and ``high`` map to each solver's own options (below) and to the
relative tolerance of bvpnav's verification (``VERIFY_RTOL``). Clarabel's static
regularization is switched off in every preset: with it on, the FEM problems at
N >= 1e5 fail to converge (measured; see README "Solvers").
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp

from .errors import InputError, SolverNotFound

__all__ = [
    "PRESETS",
    "VERIFY_RTOL",
    "available_solvers",
    "resolve_solver",
    "solver_options",
    "register_backend",
    "Backend",
    "unsupported_term",
    "check_support",
]

ACCURACIES = ("low", "default", "high")

#: Relative tolerance of bvpnav's own residual verification per preset.
VERIFY_RTOL = {"low": 1e-5, "default": 1e-7, "high": 1e-9}

#: Solver options per preset. cvxpy solver names in upper case as cvxpy spells them.
PRESETS: dict[str, dict[str, dict[str, Any]]] = {
    "CLARABEL": {
        "low": dict(tol_gap_abs=1e-6, tol_gap_rel=1e-6, tol_feas=1e-6, tol_ktratio=1e-5,
                    static_regularization_enable=False),
        "default": dict(tol_gap_abs=1e-9, tol_gap_rel=1e-9, tol_feas=1e-9,
                        static_regularization_enable=False, max_iter=300),
        "high": dict(tol_gap_abs=1e-11, tol_gap_rel=1e-11, tol_feas=1e-11, tol_ktratio=1e-9,
                     static_regularization_enable=False, max_iter=500,
                     iterative_refinement_reltol=1e-15, iterative_refinement_abstol=1e-15,
                     iterative_refinement_max_iter=50),
    },
    # OSQP (ADMM) cannot reach eps 1e-8 on these problems: at N = 2,000 (1D, soft priors) it
    # stops at 100,000 iterations with status user_limit (measured). ``high`` is therefore the
    # tightest setting it reaches there; polishing then solves the active set's KKT system.
    "OSQP": {
        "low": dict(eps_abs=1e-5, eps_rel=1e-5, max_iter=20000),
        "default": dict(eps_abs=1e-6, eps_rel=1e-6, max_iter=100000, polishing=True),
        "high": dict(eps_abs=1e-7, eps_rel=1e-7, max_iter=50000, polishing=True,
                     polish_refine_iter=50),
    },
    "SCS": {
        "low": dict(eps_abs=1e-5, eps_rel=1e-5, max_iters=20000),
        "default": dict(eps_abs=1e-8, eps_rel=1e-8, max_iters=100000),
        "high": dict(eps_abs=1e-10, eps_rel=1e-10, max_iters=400000),
    },
}


@dataclass(frozen=True)
class Backend:
    """A solver entry of the table.

    Attributes
    ----------
    name : str
        Lowercase name users pass to ``solve(solver=...)``.
    kind : {"cvxpy", "direct"}
    cvxpy_name : str, optional
        cvxpy's spelling, for ``kind == "cvxpy"``.
    run : callable, optional
        For ``kind == "direct"``: ``run(problem, lam, accuracy, options) -> (x, info)``.
    presets : dict
        Options per accuracy preset.
    """

    name: str
    kind: str
    cvxpy_name: str | None = None
    run: Callable | None = None
    presets: dict[str, dict[str, Any]] = field(default_factory=dict)


_BACKENDS: dict[str, Backend] = {}


def register_backend(backend: Backend) -> None:
    """Add or replace a back end in the table."""
    _BACKENDS[backend.name.lower()] = backend


def _cvxpy_backends() -> dict[str, Backend]:
    out = {}
    for s in cp.installed_solvers():
        out[s.lower()] = Backend(s.lower(), "cvxpy", s, presets=PRESETS.get(s, {}))
    return out


def available_solvers() -> list[str]:
    """Lowercase names of every usable solver: installed cvxpy solvers and direct back ends."""
    _load_direct()
    names = set(_cvxpy_backends()) | set(_BACKENDS)
    return sorted(names)


def _load_direct() -> None:
    try:  # direct back ends register themselves on import (optional module)
        from . import direct  # noqa: F401
    except ImportError:  # pragma: no cover - module not present in this build
        pass


def resolve_solver(name: str) -> Backend:
    """Back end for a case-insensitive name; unknown names list what is installed."""
    if not isinstance(name, str):
        raise SolverNotFound(f"solver must be a name (str), got {name!r}")
    _load_direct()
    key = name.strip().lower()
    if key in _BACKENDS:
        return _BACKENDS[key]
    cv = _cvxpy_backends()
    if key in cv:
        return cv[key]
    raise SolverNotFound(
        f"solver {name!r} is not installed or not known; available: {available_solvers()}. "
        "Install the solver's Python package (cvxpy lists it in cvxpy.installed_solvers())."
    )


def solver_options(backend: Backend, accuracy: str, overrides: dict | None = None) -> dict:
    """Options in force for a back end and preset, with user overrides on top."""
    if accuracy not in ACCURACIES:
        raise InputError(f"accuracy={accuracy!r}; choose one of {list(ACCURACIES)}")
    opts = dict(backend.presets.get(accuracy, {}))
    opts.update(overrides or {})
    return opts


def _takes_cones(backend: Backend) -> bool:
    """Whether a cvxpy back end accepts second-order cones (asks cvxpy's solver table)."""
    from cvxpy.constraints import SOC
    from cvxpy.reductions.solvers.defines import SOLVER_MAP_CONIC

    solver = SOLVER_MAP_CONIC.get(backend.cvxpy_name or "")
    return solver is not None and SOC in getattr(solver, "SUPPORTED_CONSTRAINTS", ())


def unsupported_term(backend: Backend, problem) -> Any:
    """The first term of ``problem`` that ``backend`` cannot take, or None.

    Direct back ends take equality-constrained least squares only (no inequality, band,
    robust or cone terms); QP-only cvxpy solvers (e.g. OSQP) take no cone terms.
    """
    if backend.kind == "direct":
        from .kkt import non_least_squares_term

        return non_least_squares_term(problem)
    if not _takes_cones(backend):
        for term in problem.terms():
            if term.kind == "cone":
                return term
    return None


def check_support(backend: Backend, problem) -> None:
    """Raise :class:`InputError` naming the item when ``backend`` cannot solve ``problem``."""
    term = unsupported_term(backend, problem)
    if term is None:
        return
    if backend.kind == "direct":
        why = "it solves equality-constrained least squares only"
    else:
        why = "it is a QP solver and this item is a second-order cone"
    conic = [n for n in ("clarabel", "scs") if n in available_solvers()]
    raise InputError(
        f"solver {backend.name!r} cannot take item {term.label!r} (kind {term.kind!r}, mode "
        f"{term.mode!r}): {why}. Use solver={conic[0] if conic else 'clarabel'!r}"
        + (f" or solver={conic[1]!r}" if len(conic) > 1 else "")
        + (", or give the item mode='soft'." if backend.kind == "direct" and term.kind == "equality"
           else ".")
    )
