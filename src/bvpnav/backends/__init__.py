"""Back ends: how one formulation at one ``lam`` becomes a stacked solution vector.

Every back end is an object with the :class:`Backend` contract: a lowercase ``name``,
accuracy ``presets`` (options per ``low`` / ``default`` / ``high``), ``accepts(form)``
(None, or the reason it cannot take the problem), option checking that names a wrong
option and the valid ones, a measured memory use per sample, and
``run(form, lam, options, verbose) -> RawSolve``. The framework judges every answer by
its own recomputed residuals (:mod:`bvpnav.solve.verify`), never by a status word.

The family is a discovered folder, like ``bvpnav.constraints``: each module here
defines back ends and registers them with :func:`register_backend` on import; cvxpy's
installed solvers are back ends too (:mod:`bvpnav.backends.cvxpy_solvers`, a factory that
imports cvxpy only when a lookup needs it: registered back ends such as ``direct`` are
found without it). Adding a back end is one file (here, or anywhere that calls
:func:`register_backend`), checked by :func:`bvpnav.testing.check_backend`.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError, SolverNotFound
from ..formulation import Formulation
from ..linalg.lsq import Factored
from ..plugins import discover

__all__ = [
    "ACCURACIES",
    "VERIFY_RTOL",
    "Backend",
    "RawSolve",
    "register_backend",
    "unregister_backend",
    "registry",
    "discover_backends",
    "available_solvers",
    "resolve_solver",
    "solver_options",
    "check_accuracy",
    "check_options",
    "MEMORY_SHARE",
    "available_memory",
    "memory_estimate",
    "memory_shortfall",
    "check_memory",
]

ACCURACIES = ("low", "default", "high")

#: Relative tolerance of bvpnav's own residual verification per preset.
VERIFY_RTOL = {"low": 1e-5, "default": 1e-7, "high": 1e-9}


@dataclass(eq=False)
class RawSolve:
    """What a back end returns before verification.

    Attributes
    ----------
    x : ndarray
        The stacked solution (see :class:`bvpnav.model.NavModel`).
    info : dict
        ``status`` and whatever the back end measured (``iterations``, ``solve_time``,
        ``setup_time``, ``compile_time`` in s, ``objective``, ``solver_warnings``, ...).
    duals : dict, optional
        ``{"fem": y, label: [y per constraint]}`` in cvxpy's sign convention.
    factored : Factored, optional
        The least-squares form and its factorization at this ``lam``, reused by
        verification, with the last refinement step's correction of ``x``
        (:class:`bvpnav.linalg.lsq.Factored`).
    """

    x: np.ndarray
    info: dict = field(default_factory=dict)
    duals: dict | None = None
    factored: Factored | None = None


class Backend:
    """The contract of a back end (subclass it, or give the same attributes).

    Attributes
    ----------
    name : str
        Lowercase name users pass to ``solve(solver=...)``.
    presets : dict
        Options per accuracy preset (``low``, ``default``, ``high``).
    memory_per_sample : dict
        Peak bytes per sample and axis by objective form (``acceleration``, ``load``),
        measured; used to refuse a solve that cannot fit before any work.
    least_squares_only : bool
        True for back ends that solve equality-constrained least squares only.
    uses_workspace : bool
        True for back ends whose :meth:`run` takes the solve's
        :class:`~bvpnav.linalg.workspace.Workspace` as the keyword ``workspace`` (the
        direct back end: the band plan and a lambda sweep's band or factor at ``lam``).
    time_limit_option : str or None
        The back end's own option that stops it after a number of seconds, set from
        ``solve(time_limit=...)``; None: the chain enforces the limit by discarding an
        answer that took longer (:func:`bvpnav.solve.chain.attempt`).

    Examples
    --------
    The registered back ends are instances of this contract:

    >>> from bvpnav.backends import registry
    >>> direct = registry()["direct"]
    >>> direct
    <bvpnav back end 'direct' (DirectBackend)>
    >>> direct.least_squares_only, sorted(direct.presets)
    (True, ['default', 'high', 'low'])
    >>> direct.valid_options()
    ['ipm_max_iter', 'ipm_tol', 'ldl_accept', 'method', 'qp', 'refine', 'refine_tol']
    """

    name: str = ""
    time_limit_option: str | None = None
    presets: dict[str, dict[str, Any]] = {}
    memory_per_sample: dict[str, float] = {"acceleration": 5750.0, "load": 5750.0}
    least_squares_only: bool = False
    uses_workspace: bool = False

    def accepts(self, form: Formulation) -> str | None:
        """None when the back end can take ``form``, else the reason (naming the item)."""
        return None

    def valid_options(self) -> list[str] | None:
        """Option names the back end accepts, or None when it judges them itself."""
        return sorted(self.presets.get("default", {}))

    def check_value(self, key: str, value) -> str | None:
        """None when ``value`` is valid for option ``key``, else what a valid one is."""
        return None

    def run(self, form: Formulation, lam: float, options: dict, verbose: bool = False) -> RawSolve:
        """Solve ``form`` at ``lam`` with ``options`` (the preset plus the user's)."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"<bvpnav back end {self.name!r} ({type(self).__name__})>"


_BACKENDS: dict[str, Backend] = {}
_FACTORIES: list = []

#: Back ends a factory has offered in this process, by name: a later lookup of the same
#: name does not ask the factories again (cvxpy's ``installed_solvers()`` tries to import
#: some forty solver packages, and every solve resolves its fallback chain).
_FOUND: dict = {}


def register_backend(backend: Backend) -> Backend:
    """Add (or replace) a back end in the table under its lowercase name."""
    if not isinstance(getattr(backend, "name", None), str) or not backend.name:
        raise InputError(f"register_backend({backend!r}): a back end needs a non-empty name")
    _BACKENDS[backend.name.lower()] = backend
    return backend


def unregister_backend(name: str) -> None:
    """Remove a registered back end (e.g. one a test added)."""
    _BACKENDS.pop(name.lower(), None)


def register_factory(factory) -> None:
    """Register a callable returning back ends that exist only at run time (cvxpy's
    installed solvers); asked on every lookup, after the fixed table."""
    _FACTORIES.append(factory)


def _discover() -> None:
    """Import every module of this folder once (each registers its back ends)."""
    discover(__name__, __path__)


def discover_backends() -> None:
    """Import this folder's back-end modules now (each registers its back ends; cvxpy itself
    is still imported only when a lookup needs it) instead of at the first solve's lookup:
    :mod:`bvpnav.solve` calls it on import, so a solve pays for no module of its own.

    Examples
    --------
    >>> import sys
    >>> from bvpnav.backends import discover_backends
    >>> discover_backends()
    >>> "bvpnav.backends.direct" in sys.modules
    True
    """
    _discover()


def registry() -> dict[str, Backend]:
    """Every back end by lowercase name: registered ones, then the run-time factories'."""
    _discover()
    out = {}
    for factory in _FACTORIES:
        for be in factory():
            out.setdefault(be.name, be)
    _FOUND.update(out)
    out.update(_BACKENDS)
    return out


def available_solvers() -> list[str]:
    """Lowercase names of every usable solver: installed cvxpy solvers and direct back ends.

    Examples
    --------
    >>> import bvpnav
    >>> solvers = bvpnav.available_solvers()
    >>> "direct" in solvers and "clarabel" in solvers
    True
    """
    return sorted(registry())


def resolve_solver(name: str) -> Backend:
    """Back end for a case-insensitive name; unknown names list what is installed."""
    if not isinstance(name, str):
        raise SolverNotFound(f"solver must be a name (str), got {name!r}")
    key = name.strip().lower()
    _discover()
    if key in _BACKENDS:  # registered back ends win over the factories' (see registry()),
        return _BACKENDS[key]  # so 'direct' is found without asking cvxpy what is installed
    if key in _FOUND:
        return _FOUND[key]
    table = registry()
    if key in table:
        return table[key]
    raise SolverNotFound(
        f"solver {name!r} is not installed or not known; available: {sorted(table)}. "
        "Install the solver's Python package (cvxpy lists it in cvxpy.installed_solvers())."
    )


def check_accuracy(accuracy) -> str:
    """``accuracy`` itself, or :class:`InputError` naming the presets."""
    if not isinstance(accuracy, str) or accuracy not in ACCURACIES:
        raise InputError(f"accuracy={accuracy!r}; choose one of {list(ACCURACIES)}")
    return accuracy


def check_options(backend: Backend, options, what: str = "options") -> None:
    """Raise :class:`InputError` naming an option the back end does not know, or a value
    it cannot use, with the valid ones."""
    if options is None:
        return
    if not isinstance(options, Mapping):
        raise InputError(f"{what}={options!r}: give a dict of solver options, e.g. "
                         f"{what}={{'max_iter': 500}}, or None")
    valid = backend.valid_options()
    for key in options:
        if not isinstance(key, str):
            raise InputError(f"{what}: option name {key!r} for solver {backend.name!r} is not a string")
        if valid is not None and key not in valid:
            close = difflib.get_close_matches(key, valid, n=1)
            raise InputError(
                f"{what}: solver {backend.name!r} has no option {key!r}"
                + (f" (did you mean {close[0]!r}?)" if close else "")
                + f"; valid options: {valid}")
    for key, value in options.items():
        want = backend.check_value(key, value)
        if want is not None:
            raise InputError(f"{what}: solver {backend.name!r} option {key}={value!r}: must be {want}")


def solver_options(backend: Backend, accuracy: str, overrides: dict | None = None) -> dict:
    """Options in force for a back end and preset, with user overrides on top (checked
    by :func:`check_options` first)."""
    check_accuracy(accuracy)
    check_options(backend, overrides)
    opts = dict(backend.presets.get(accuracy, {}))
    opts.update(overrides or {})
    return opts


# ------------------------------------------------------------------ memory
#: Share of the available memory a solve may plan to use.
MEMORY_SHARE = 0.9


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation: ``MemAvailable`` of /proc/meminfo,
    else the free physical pages (``os.sysconf``), else None (unknown: no check)."""
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


def memory_estimate(backend: Backend, form: Formulation) -> float:
    """Estimated peak bytes of solving ``form`` with ``backend``: samples x axes x the
    back end's measured bytes per sample (:attr:`Backend.memory_per_sample`)."""
    per = backend.memory_per_sample
    return float(form.data.n) * form.data.ndim * per.get(form.residual, max(per.values()))


def _gb(b: float) -> str:
    return f"{b / 1e9:.3g} GB"


def memory_shortfall(backend: Backend, form: Formulation, available: int | None = None) -> str | None:
    """Why ``backend`` would not fit in memory (a sentence naming N, the estimate and the
    limit), or None when it fits or the available memory is unknown."""
    avail = available_memory() if available is None else available
    if avail is None:
        return None
    need = memory_estimate(backend, form)
    limit = MEMORY_SHARE * avail
    if need <= limit:
        return None
    return (f"solver {backend.name!r} needs about {_gb(need)} for N = {form.data.n} samples x "
            f"{form.data.ndim} axes (measured {need / (form.data.n * form.data.ndim):.0f} "
            f"bytes per sample and axis), more than the limit {_gb(limit)} "
            f"({MEMORY_SHARE:.0%} of {_gb(avail)} available)")


def check_memory(form: Formulation, backend: Backend) -> None:
    """Raise :class:`InputError` before any work when ``backend`` would not fit in memory,
    naming N, the estimate, the limit and the options that would fit."""
    avail = available_memory()
    why = memory_shortfall(backend, form, avail)
    if why is None:
        return
    limit = MEMORY_SHARE * avail
    per = memory_estimate(backend, form) / form.data.n
    n_fit = int(limit // per)
    fits = []
    if n_fit >= 2:
        dt = float(np.median(np.diff(form.data.t)))
        fits.append(f"a shorter window of at most {n_fit} samples (about {n_fit * dt:.4g} s)")
    table = registry()
    for other in table.values():
        if other.least_squares_only and other.name != backend.name and form.least_squares_items() \
                and memory_shortfall(other, form, avail) is None:
            fits.append(f"solver={other.name!r} (about {_gb(memory_estimate(other, form))})")
    fits.append("a machine with more memory")
    raise InputError(f"not enough memory: {why}. Options that would fit: " + "; ".join(fits) + ".")
