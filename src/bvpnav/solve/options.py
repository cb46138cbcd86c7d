"""The user's solve options, checked once before any work and handed to every stage.

:func:`prepare` validates every option of :meth:`bvpnav.NavigationProblem.solve` (naming
a wrong one and the valid values) and returns one frozen :class:`SolveOptions`; every
stage of the pipeline (:mod:`bvpnav.solve.pipeline`) receives that same object, so an
option given by the user reaches every stage that needs it.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..backends import Backend, resolve_solver, solver_options
from ..errors import BvpnavError, InputError
from ..formulation import LAM_RANGE
from ..lam import rule_names
from ..lam.sweep import check_range

__all__ = ["SolveOptions", "prepare", "check_lam", "DEFAULT_FALLBACK", "fallback_chain", "RULE_KEYS",
           "SEQUENTIAL_KEYS", "SEQUENTIAL_DEFAULTS", "UNCERTAINTY"]

#: Options of the lambda sweep a solve with a rule name takes (``solve(rule={...})``).
RULE_KEYS = ("lam_range", "points", "tau", "probes", "seed", "progress", "engine")
#: Options of the sequential loop and their defaults (``solve(sequential={...})``; see
#: :func:`bvpnav.solve.sequential.with_sequential`).
SEQUENTIAL_DEFAULTS: dict[str, Any] = {"tol": 1e-4, "max_iter": 30, "initial": None, "lam_each": False,
                                       "continuation": True, "soft_tol": None, "progress": None}
SEQUENTIAL_KEYS = tuple(SEQUENTIAL_DEFAULTS)
#: Values of ``solve(uncertainty=...)`` other than True and False.
UNCERTAINTY = ("scaled",)

#: The automatic fallback chain (``fallback="auto"``) after a primary Clarabel attempt:
#: Clarabel again with static regularization, the direct sparse back end (equality-
#: constrained least squares only; skipped with a recorded reason otherwise), then SCS.
#: After another primary solver the first entry is plain Clarabel.
DEFAULT_FALLBACK: tuple = (("clarabel", {"static_regularization_enable": True}), "direct", "scs")


def check_lam(lam):
    """``lam`` as a float (or a rule name), or :class:`InputError` naming the value and
    the valid ones.

    Examples
    --------
    >>> import bvpnav
    >>> from bvpnav.solve import check_lam
    >>> check_lam(10), check_lam("lcurve")
    (10.0, 'lcurve')
    >>> try:
    ...     check_lam(-1.0)
    ... except bvpnav.InputError as exc:
    ...     print(exc)
    lam=-1.0: must be a finite number >= 0
    """
    rules = list(rule_names())
    if isinstance(lam, str):
        if lam not in rules:
            raise InputError(f"lam={lam!r} is not a known rule; choose one of {rules} or a "
                             f"number >= 0")
        return lam
    if isinstance(lam, bool | np.bool_) or not isinstance(lam, numbers.Real):
        raise InputError(f"lam={lam!r} ({type(lam).__name__}): give a finite number >= 0 (e.g. "
                         f"lam=1.0) or a rule name from {rules}")
    lam = float(lam)
    if not np.isfinite(lam) or lam < 0:
        raise InputError(f"lam={lam!r}: must be a finite number >= 0")
    if lam != 0 and not LAM_RANGE[0] <= lam <= LAM_RANGE[1]:
        raise InputError(
            f"lam={lam:g} is outside {LAM_RANGE[0]:g}..{LAM_RANGE[1]:g} (or 0), the range in which "
            "double precision still weighs the soft items against the data term. For items that "
            "must hold exactly make them hard (sigma=None); to ignore them use lam=0; otherwise "
            "choose a lam in that range (or a rule, e.g. lam='lcurve')")
    return lam


@dataclass(frozen=True, eq=False)
class SolveOptions:
    """Every option of a solve, checked (see :meth:`bvpnav.NavigationProblem.solve`).

    Attributes
    ----------
    backend : Backend
        The primary back end.
    accuracy : str
    verify : bool
    verbose : bool
        Pass the solver's own output through: cvxpy's ``verbose=True`` (its compilation
        and the solver's iteration log, printed to stdout by cvxpy and the solver, not
        through :mod:`logging`); the direct back end has no output of its own. bvpnav's
        own records (attempts, fallbacks, chosen lambda, iterations, timings) are on the
        ``bvpnav`` logger (:mod:`bvpnav.log`), independent of this flag.
    options : dict or None
        The user's extra options for the primary back end.
    fallback : Any
        As given (``"auto"``, a sequence, or None).
    chain : list of (Backend, dict)
        Primary back end with its options in force, then the fallback back ends.
    on_conflict : str
    priority, demote_sigma : Any
        For ``on_conflict="demote"``.
    sequential : dict
        Options of the sequential loop (``tol``, ``max_iter``, ``initial``,
        ``lam_each``, ``continuation``, ``soft_tol``, ``progress``).
    rule : dict
        Options of the lambda sweep (``lam_range``, ``points``, ``tau``, ``probes``,
        ``seed``, ``progress``, ``engine``).
    attitude : dict
        Options of the damped attitude loop (``tol``, ``max_iter``, ``heading``,
        ``candidates``, ``loop``, ``progress``; :func:`bvpnav.solve.attitude.with_attitude`).
    uncertainty : bool or str
        False, True (the covariance of the weights as stated) or ``"scaled"`` (times the
        a-posteriori variance factor); see :mod:`bvpnav.solve.uncertainty`.

    Examples
    --------
    >>> from bvpnav.solve import prepare
    >>> opts, lam = prepare(lam=2.0, solver="direct", accuracy="high")
    >>> opts.backend.name, opts.accuracy, opts.verify, lam
    ('direct', 'high', True, 2.0)
    >>> [backend.name for backend, _ in opts.chain]
    ['direct', ...]
    """

    backend: Backend
    accuracy: str = "default"
    verify: bool = True
    verbose: bool = False
    options: dict | None = None
    fallback: Any = "auto"
    chain: list = field(default_factory=list)
    on_conflict: str = "raise"
    priority: Any = None
    demote_sigma: Any = None
    sequential: dict = field(default_factory=dict)
    rule: dict = field(default_factory=dict)
    uncertainty: Any = False
    attitude: dict = field(default_factory=dict)

    @property
    def solver(self) -> str:
        """The primary back end's name."""
        return self.backend.name


def _fallback_entries(backend: Backend, fallback) -> list:
    how = ("use 'auto', None, or a list of solver names or (name, options) pairs, e.g. "
           "fallback=['direct', ('scs', {'max_iters': 20000})]")
    if fallback is None:
        return []
    if isinstance(fallback, str):
        if fallback != "auto":
            raise InputError(f"fallback={fallback!r}; {how}")
        entries = list(DEFAULT_FALLBACK)
        if backend.name != "clarabel":
            entries[0] = "clarabel"
        return entries
    if not isinstance(fallback, list | tuple):
        raise InputError(f"fallback={fallback!r} ({type(fallback).__name__}); {how}")
    out = []
    for k, e in enumerate(fallback):
        if not (isinstance(e, str) or (isinstance(e, list | tuple) and len(e) == 2
                                       and isinstance(e[0], str) and isinstance(e[1], Mapping))):
            raise InputError(f"fallback entry {k} = {e!r}: {how}")
        out.append(e)
    return out


def fallback_chain(backend: Backend, accuracy: str, options, fallback) -> list:
    """The fallback back ends with their options in force (see :data:`DEFAULT_FALLBACK`)."""
    chain = []
    for e in _fallback_entries(backend, fallback):
        name, extra = (e, {}) if isinstance(e, str) else (e[0], dict(e[1]))
        try:
            be = resolve_solver(name)
        except BvpnavError:
            if fallback == "auto":
                continue  # an optional back end that is not installed
            raise
        if be.name == backend.name and not extra:
            continue
        chain.append((be, solver_options(be, accuracy, {**(options or {}), **extra}
                                         if be.name == backend.name else extra)))
    return chain


def prepare(lam=1.0, solver: str = "clarabel", accuracy: str = "default", verify: bool = True,
            options: dict | None = None, verbose: bool = False, fallback="auto",
            on_conflict: str = "raise", priority=None, demote_sigma=None,
            sequential: dict | None = None, rule: dict | None = None,
            uncertainty=False, attitude: dict | None = None) -> tuple[SolveOptions, Any]:
    """Check every option before any work: ``(SolveOptions, lam)`` (``lam`` as a float or
    a rule name, see :func:`check_lam`).

    Raises
    ------
    InputError
        Naming the option, its value and the valid ones (``SolverNotFound`` for an
        unknown solver name).

    Examples
    --------
    >>> import bvpnav
    >>> from bvpnav.solve import prepare
    >>> opts, lam = prepare(lam="gcv", solver="direct")
    >>> opts.backend.name, lam
    ('direct', 'gcv')
    >>> try:
    ...     prepare(accuracy="highest")
    ... except bvpnav.InputError as exc:
    ...     print(exc)
    accuracy='highest'; choose one of ['low', 'default', 'high']
    """
    if on_conflict not in ("raise", "demote"):
        raise InputError(f"on_conflict={on_conflict!r}; choose 'raise' or 'demote'")
    lam = check_lam(lam)
    for name, flag in (("verify", verify), ("verbose", verbose)):
        if not isinstance(flag, bool | np.bool_):
            raise InputError(f"{name}={flag!r}: must be True or False")
    for what, given, valid in (("sequential", sequential, SEQUENTIAL_KEYS), ("rule", rule, RULE_KEYS)):
        if given is None:
            continue
        if not isinstance(given, Mapping):
            raise InputError(f"{what}={given!r}: give a dict of options, e.g. {what}={{{valid[0]!r}: ...}}, "
                             f"with keys from {list(valid)}")
        unknown = sorted(str(k) for k in given if k not in valid)
        if unknown:
            raise InputError(f"{what}: unknown option(s) {unknown}; valid: {list(valid)}")
    if not (isinstance(uncertainty, bool | np.bool_) or uncertainty in UNCERTAINTY):
        raise InputError(f"uncertainty={uncertainty!r}: give False, True (the covariance of the "
                         "stated noise) or 'scaled' (scaled by the a-posteriori variance factor)")
    if isinstance(lam, str) and rule:
        check_range(rule.get("lam_range", (1e-6, 1e6)), rule.get("points", 25))
    if attitude is not None:
        from .attitude import check_attitude

        if not isinstance(attitude, Mapping):
            raise InputError(f"attitude={attitude!r}: give a dict of options, e.g. "
                             "attitude={'max_iter': 50}")
        check_attitude(attitude)
    backend = resolve_solver(solver)
    primary = solver_options(backend, accuracy, options)
    chain = [(backend, primary)] + fallback_chain(backend, accuracy, options, fallback)
    opts = SolveOptions(backend=backend, accuracy=accuracy, verify=bool(verify), verbose=bool(verbose),
                        options=None if options is None else dict(options), fallback=fallback,
                        chain=chain, on_conflict=on_conflict, priority=priority,
                        demote_sigma=demote_sigma, sequential=dict(sequential or {}),
                        rule=dict(rule or {}),
                        uncertainty=uncertainty if isinstance(uncertainty, str) else bool(uncertainty),
                        attitude=dict(attitude or {}))
    return opts, lam
