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

import difflib
import inspect
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import numpy as np

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
    "check_options",
    "valid_options",
    "check_accuracy",
    "MEMORY_PER_SAMPLE",
    "available_memory",
    "memory_estimate",
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


def check_accuracy(accuracy) -> str:
    """``accuracy`` itself, or :class:`InputError` naming the presets."""
    if not isinstance(accuracy, str) or accuracy not in ACCURACIES:
        raise InputError(f"accuracy={accuracy!r}; choose one of {list(ACCURACIES)}")
    return accuracy


def solver_options(backend: Backend, accuracy: str, overrides: dict | None = None) -> dict:
    """Options in force for a back end and preset, with user overrides on top (checked
    by :func:`check_options` first)."""
    check_accuracy(accuracy)
    check_options(backend, overrides)
    opts = dict(backend.presets.get(accuracy, {}))
    opts.update(overrides or {})
    return opts


#: Values of the direct back ends' options: (check, what a valid value is).
_DIRECT_VALUES: dict[str, tuple[Callable[[Any], bool], str]] = {
    "method": (lambda v: v in ("auto", "lu", "ldl"), "one of ['auto', 'lu', 'ldl']"),
    "refine": (lambda v: _is_int(v) and 0 <= v <= 100, "an integer from 0 to 100"),
    "max_iter": (lambda v: _is_int(v) and 1 <= v <= 10_000, "an integer from 1 to 10000"),
    "ldl_accept": (lambda v: _is_real(v) and 0 < v < 1, "a number between 0 and 1"),
    "tol": (lambda v: _is_real(v) and 0 < v < 1, "a number between 0 and 1"),
}


def _is_int(v) -> bool:
    return isinstance(v, numbers.Integral) and not isinstance(v, bool | np.bool_)


def _is_real(v) -> bool:
    return (isinstance(v, numbers.Real) and not isinstance(v, bool | np.bool_)
            and bool(np.isfinite(float(v))))


def _cvxpy_keywords() -> set[str]:
    """cvxpy's own keywords of ``Problem.solve`` (accepted with every cvxpy solver)."""
    params = inspect.signature(cp.Problem._solve).parameters
    return {k for k, p in params.items() if k not in ("self", "solver")
            and p.kind is not inspect.Parameter.VAR_KEYWORD}


def valid_options(backend: Backend) -> list[str] | None:
    """Option names a back end accepts, or None when bvpnav cannot list them (the solver
    then judges them itself; an error is a recorded failed attempt)."""
    if backend.kind == "direct":
        return sorted(backend.presets.get("default", {}))
    if backend.name == "clarabel":
        try:
            import clarabel
        except ImportError:  # pragma: no cover - clarabel is a dependency of cvxpy
            return None
        settings = clarabel.DefaultSettings()
        names = {a for a in dir(settings) if not a.startswith("_")
                 and not callable(getattr(settings, a))}
        return sorted(names | _cvxpy_keywords())
    return None


def check_options(backend: Backend, options, what: str = "options") -> None:
    """Raise :class:`InputError` naming an option the back end does not know, or a value
    of a direct back end's option that it cannot use, with the valid ones."""
    if options is None:
        return
    if not isinstance(options, Mapping):
        raise InputError(f"{what}={options!r}: give a dict of solver options, e.g. "
                         f"{what}={{'max_iter': 500}}, or None")
    valid = valid_options(backend)
    for key in options:
        if not isinstance(key, str):
            raise InputError(f"{what}: option name {key!r} for solver {backend.name!r} is not a string")
        if valid is not None and key not in valid:
            close = difflib.get_close_matches(key, valid, n=1)
            raise InputError(
                f"{what}: solver {backend.name!r} has no option {key!r}"
                + (f" (did you mean {close[0]!r}?)" if close else "")
                + f"; valid options: {valid}")
    if backend.kind == "direct":
        for key, value in options.items():
            ok, want = _DIRECT_VALUES.get(key, (lambda v: True, ""))
            if not ok(value):
                raise InputError(f"{what}: solver {backend.name!r} option {key}={value!r}: must be "
                                 f"{want}")


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


# ------------------------------------------------------------------ memory
#: Peak resident bytes per sample and axis by back end and objective form, measured at
#: N = 1,000,000 (one axis, Table 2 shape, each run in its own process, data and problem
#: included; README "Comparing solvers"): direct 1.95 / 2.96 GB, csne 2.77 / 3.06 GB,
#: Clarabel 5.75 GB (acceleration form; the load form was not run). Other cvxpy solvers
#: (not measured) are taken as Clarabel: cvxpy's compiled problem dominates.
MEMORY_PER_SAMPLE: dict[str, dict[str, float]] = {
    "direct": {"acceleration": 1950.0, "load": 2960.0},
    "csne": {"acceleration": 2770.0, "load": 3060.0},
    "clarabel": {"acceleration": 5750.0, "load": 5750.0},
}

#: Share of the available memory a solve may plan to use.
MEMORY_SHARE = 0.9


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation: ``MemAvailable`` of /proc/meminfo,
    else the free physical pages (``os.sysconf``), else None (unknown: no check)."""
    import os

    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def memory_estimate(backend: Backend, problem) -> float:
    """Estimated peak bytes of solving ``problem`` with ``backend`` (see
    :data:`MEMORY_PER_SAMPLE`): samples x axes x the measured bytes per sample."""
    per = MEMORY_PER_SAMPLE.get(backend.name, MEMORY_PER_SAMPLE["clarabel"])
    form = getattr(problem, "residual", "acceleration")
    return float(problem.data.n) * problem.data.ndim * per.get(form, max(per.values()))


def _gb(b: float) -> str:
    return f"{b / 1e9:.3g} GB"


def memory_shortfall(backend: Backend, problem, available: int | None = None) -> str | None:
    """Why ``backend`` would not fit in memory (a sentence naming N, the estimate and the
    limit), or None when it fits or the available memory is unknown."""
    avail = available_memory() if available is None else available
    if avail is None:
        return None
    need = memory_estimate(backend, problem)
    limit = MEMORY_SHARE * avail
    if need <= limit:
        return None
    return (f"solver {backend.name!r} needs about {_gb(need)} for N = {problem.data.n} samples x "
            f"{problem.data.ndim} axes (measured {need / (problem.data.n * problem.data.ndim):.0f} "
            f"bytes per sample and axis), more than the limit {_gb(limit)} "
            f"({MEMORY_SHARE:.0%} of {_gb(avail)} available)")


def _least_squares_items(problem) -> bool:
    """Whether every item is a hard or soft equality and no error-model bound exists,
    judged from the items' declared kind and mode (no compilation: N may be huge)."""
    for it in getattr(problem, "_items", ()):
        if getattr(it, "kind", "equality") != "equality" or it.mode in ("band", "robust"):
            return False
    em = getattr(problem, "error_model", None)
    comps = getattr(em, "components", (em,)) if em is not None else ()
    return all(getattr(c, "bounds", None) is None for c in comps)


def check_memory(problem, backend: Backend) -> None:
    """Raise :class:`InputError` before any work when ``backend`` would not fit in memory,
    naming N, the estimate, the limit and the options that would fit."""
    avail = available_memory()
    why = memory_shortfall(backend, problem, avail)
    if why is None:
        return
    limit = MEMORY_SHARE * avail
    per = memory_estimate(backend, problem) / problem.data.n
    n_fit = int(limit // per)
    t = problem.data.t
    fits = []
    if n_fit >= 2:
        dt = float(np.median(np.diff(t)))
        fits.append(f"a shorter window of at most {n_fit} samples (about {n_fit * dt:.4g} s)")
    for name in ("direct", "csne"):
        if name in _BACKENDS and name != backend.name:
            other = _BACKENDS[name]
            if memory_shortfall(other, problem, avail) is None and _least_squares_items(problem):
                fits.append(f"solver={name!r} (about {_gb(memory_estimate(other, problem))})")
    fits.append("a machine with more memory")
    raise InputError(f"not enough memory: {why}. Options that would fit: " + "; ".join(fits) + ".")
