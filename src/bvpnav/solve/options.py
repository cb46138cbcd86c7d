"""The user's solve options, checked once before any work and handed to every stage.

:func:`prepare` validates every option of :meth:`bvpnav.NavigationProblem.solve` (naming
a wrong one and the valid values) and returns one frozen :class:`SolveOptions`; every
stage of the pipeline (:mod:`bvpnav.solve.pipeline`) receives that same object, so an
option given by the user reaches every stage that needs it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..backends import Backend, discover_backends, resolve_solver, solver_options
from ..declare import RULE, SEQUENTIAL, SOLVE_OPTIONS, UNCERTAINTY, check_option, check_options, defaults
from ..errors import BvpnavError
from ..lam import rule_names
from ..lam.sweep import check_range

# the plug-in families every solve looks up (the back ends, the lambda rules its options are
# checked against) are imported with the solve's own modules, not by the first solve
discover_backends()
rule_names()

__all__ = ["Chain", "SolveOptions", "prepare", "check_lam", "DEFAULT_FALLBACK", "fallback_chain", "RULE_KEYS",
           "SEQUENTIAL_KEYS", "SEQUENTIAL_DEFAULTS", "UNCERTAINTY", "SEQUENTIAL"]

#: Options of the lambda sweep a solve with a rule name takes (``solve(rule={...})``).
RULE_KEYS = tuple(RULE)
#: Options of the sequential loop and their defaults (``solve(sequential={...})``; see
#: :func:`bvpnav.solve.sequential.with_sequential`).
SEQUENTIAL_DEFAULTS: dict[str, Any] = defaults(SEQUENTIAL)
SEQUENTIAL_KEYS = tuple(SEQUENTIAL_DEFAULTS)

#: The automatic fallback chain (``fallback="auto"``) after a primary Clarabel attempt:
#: Clarabel again with static regularization, the direct sparse back end (equality-
#: constrained least squares only; skipped with a recorded reason otherwise), then SCS.
#: After another primary solver the first entry is plain Clarabel.
DEFAULT_FALLBACK: tuple = (("clarabel", {"static_regularization_enable": True}), "direct", "scs")


def check_lam(lam):
    """``lam`` as a float (or a rule name), or :class:`InputError` naming the value and
    the valid ones (the declared rule: :data:`bvpnav.declare.SOLVE_OPTIONS`).

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
    lam=-1.0: must be a finite number >= 0 or a rule name from ['lcurve', 'gcv', 'discrepancy', 'quasi']
    """
    return check_option("lam", lam)


class Chain(Sequence):
    """The back ends of a solve in order, the fallbacks looked up on first use.

    ``fallback="auto"`` names optional back ends (Clarabel, SCS) that only cvxpy knows
    about, and asking cvxpy which solvers are installed imports it (a quarter of a second):
    a solve the primary back end answers never needs them, so the tail of the chain is
    built (by ``tail()``) only when an entry past ``head`` is read or the chain is iterated
    past it. Explicit fallback lists are resolved by :func:`prepare` up front (a wrong name
    is refused before any work).

    Examples
    --------
    >>> c = Chain([("a", {})], lambda: [("b", {})])
    >>> c[0], c.resolved
    (('a', {}), False)
    >>> list(c), c.resolved
    ([('a', {}), ('b', {})], True)
    """

    def __init__(self, head: list, tail: Callable[[], list] | None = None):
        self._head = list(head)
        self._tail = tail
        self._all: list | None = None if tail is not None else list(head)

    @property
    def resolved(self) -> bool:
        """Whether the fallback back ends have been looked up."""
        return self._all is not None

    def _full(self) -> list:
        if self._all is None:
            self._all = self._head + list(self._tail())
        return self._all

    def __getitem__(self, i):
        if isinstance(i, int) and 0 <= i < len(self._head):
            return self._head[i]
        return self._full()[i]

    def __iter__(self) -> Iterator:
        yield from self._head
        yield from self._full()[len(self._head):]

    def __len__(self) -> int:
        return len(self._full())

    def __bool__(self) -> bool:
        return bool(self._head) or bool(self._full())

    def __repr__(self) -> str:
        return f"Chain({self._full()!r})"


@dataclass(frozen=True, eq=False)
class SolveOptions:
    """Every option of a solve, checked (see :meth:`bvpnav.NavigationProblem.solve`).

    Every declared option (:data:`bvpnav.declare.SOLVE_OPTIONS`) is an attribute, checked
    and normalised: ``opts.accuracy``, ``opts.uncertainty``, ``opts.time_limit``, ... (the
    nested tables ``sequential``, ``rule`` and ``attitude`` as dicts, ``{}`` when not
    given), so an option registered there reaches every stage as ``opts.<name>``.

    Attributes
    ----------
    backend : Backend
        The primary back end.
    chain : Chain of (Backend, dict)
        Primary back end with its options in force, then the fallback back ends (with
        ``fallback="auto"`` looked up on first use: see :class:`Chain`).
    values : dict
        The declared options' values by name (read them as attributes).

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
    chain: list = field(default_factory=list)
    values: dict = field(default_factory=dict)

    def __getattr__(self, name: str):
        values = self.__dict__.get("values", {})
        if name in values:
            return values[name]
        if name in SOLVE_OPTIONS:
            return SOLVE_OPTIONS[name].default
        raise AttributeError(f"SolveOptions has no option {name!r}; declared: {list(SOLVE_OPTIONS)}")

    @property
    def solver(self) -> str:
        """The primary back end's name."""
        return self.backend.name


def _fallback_entries(backend: Backend, fallback) -> list:
    if fallback is None:
        return []
    if isinstance(fallback, str):  # "auto" (checked by the declaration)
        entries = list(DEFAULT_FALLBACK)
        if backend.name != "clarabel":
            entries[0] = "clarabel"
        return entries
    return list(fallback)


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


def prepare(lam=1.0, **options) -> tuple[SolveOptions, Any]:
    """Check every option before any work: ``(SolveOptions, lam)`` (``lam`` as a float or
    a rule name).

    Each value is checked by its declaration (:data:`bvpnav.declare.SOLVE_OPTIONS`: the
    same rule, and the same message, as the spec's ``[solve]`` and the command line), then
    what needs several options or the installed solvers: the sweep's range with a rule
    name, the solver's name and its options, the fallback chain.

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
    accuracy='highest': choose one of ['low', 'default', 'high']
    """
    values = check_options({"lam": lam, **options})
    lam = values["lam"]
    for name in ("sequential", "rule", "attitude"):
        values[name] = dict(values[name] or {})
    if isinstance(lam, str) and values["rule"]:
        check_range(values["rule"].get("lam_range", RULE["lam_range"][0]),
                    values["rule"].get("points", RULE["points"][0]))
    backend = resolve_solver(values["solver"])
    values["solver"] = backend.name
    primary = solver_options(backend, values["accuracy"], values["options"])
    fallback = values["fallback"]
    tail = lambda: fallback_chain(backend, values["accuracy"], values["options"], fallback)  # noqa: E731
    if fallback == "auto":   # optional back ends, skipped when not installed: looked up on first use
        chain = Chain([(backend, primary)], tail)
    else:
        chain = Chain([(backend, primary)] + tail())
    return SolveOptions(backend=backend, chain=chain, values=values), lam
