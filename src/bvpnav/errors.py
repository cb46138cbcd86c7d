"""One exception hierarchy for bvpnav.

Every error the library raises on purpose derives from :class:`BvpnavError`, so
callers can catch the library's failures without catching programming errors.

- :class:`InputError` (also a :class:`ValueError`): the caller gave data or
  parameters that cannot be used; the message names the culprit (index, column,
  item) and what to do.
- :class:`ConvexityError`: an item or objective is not DCP/DPP; the message names
  the item.
- :class:`SolverNotFound` (an :class:`InputError`): the requested solver is unknown
  or not installed; the message lists the installed ones.
- :class:`SolveError` and its subclasses :class:`Infeasible`, :class:`Unbounded`,
  :class:`Inaccurate`: the solver failed, or its answer failed bvpnav's own
  verification.
"""

from __future__ import annotations

__all__ = [
    "BvpnavError",
    "InputError",
    "ConvexityError",
    "SolverNotFound",
    "SolveError",
    "Infeasible",
    "Unbounded",
    "Inaccurate",
]


class BvpnavError(Exception):
    """Base class of every error raised on purpose by bvpnav.

    Examples
    --------
    Catch every failure of the library, and only those:

    >>> import bvpnav
    >>> try:
    ...     bvpnav.TimeGrid([0.0, 1.0, 0.5])
    ... except bvpnav.BvpnavError as exc:
    ...     print(type(exc).__name__)
    InputError
    """


class InputError(BvpnavError, ValueError):
    """Bad input: the message names the culprit and the fix.

    Examples
    --------
    >>> import bvpnav
    >>> try:
    ...     bvpnav.TimeGrid([0.0, 1.0, 0.5])
    ... except bvpnav.InputError as exc:
    ...     print(exc)
    time: sample 2 (0.5 s) is decreasing after sample 1 (1.0 s); times must be strictly increasing. ...
    >>> issubclass(bvpnav.InputError, ValueError)
    True
    """


class ConvexityError(BvpnavError):
    """An item or objective breaks the DCP/DPP rules; the message names the item.

    Examples
    --------
    It is raised while a problem is built (an item's ``compile`` that returns no affine
    residual, or a penalty that is not convex), not by the solver:

    >>> import bvpnav
    >>> issubclass(bvpnav.ConvexityError, bvpnav.BvpnavError)
    True
    >>> issubclass(bvpnav.ConvexityError, bvpnav.SolveError)
    False
    """


class SolverNotFound(InputError):
    """Unknown or uninstalled solver; the message lists what is installed.

    A bad solver name is bad input like any other, so ``except InputError`` catches it.

    Examples
    --------
    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, Velocity
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=[0.0, 0.5, 1.0], acc=np.zeros(3)))
    >>> _ = prob.add(Position(t=0.0, value=0.0), Velocity(t=0.0, value=0.0))
    >>> try:
    ...     prob.solve(solver="nosuch")
    ... except bvpnav.InputError as exc:
    ...     print(type(exc).__name__, "-", exc)
    SolverNotFound - solver 'nosuch' is not installed or not known; available: [...]. ...
    """


class SolveError(BvpnavError):
    """The solve failed or its answer did not pass verification.

    Attributes
    ----------
    attempts : list of dict
        One record per solver attempt (solver, status, reason).

    Examples
    --------
    Every failed attempt of the fallback chain is recorded:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=np.linspace(0.0, 1.0, 11), acc=np.zeros(11)))
    >>> _ = prob.add(Position(t=[0.0, 1.0], value=[0.0, 1.0]), Position(t=0.0, value=2.0, name="gps"))
    >>> try:
    ...     prob.solve(solver="clarabel")
    ... except bvpnav.SolveError as exc:
    ...     print(type(exc).__name__, [(a["solver"], a["status"]) for a in exc.attempts])
    Infeasible [('clarabel', 'infeasible')]
    """

    def __init__(self, message: str, attempts: list[dict] | None = None):
        super().__init__(message)
        self.attempts = list(attempts or [])


class Infeasible(SolveError):
    """Hard information cannot hold together, proved (a cvxpy solver's verdict is confirmed by its
    infeasibility certificate, recomputed with bvpnav's own rows).

    Examples
    --------
    Two hard positions at t = 0 s that disagree (0 m and 2 m):

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=np.linspace(0.0, 1.0, 11), acc=np.zeros(11)))
    >>> _ = prob.add(Position(t=[0.0, 1.0], value=[0.0, 1.0]), Position(t=0.0, value=2.0, name="gps"))
    >>> try:
    ...     prob.solve(solver="clarabel")
    ... except bvpnav.Infeasible as exc:
    ...     print(str(exc).split("These hard items ")[1])
    conflict: ['Position (t=[0, 1] s, value=[0, 1] m)', 'gps']. Soften one of them (give sigma=...).
    """


class Unbounded(SolveError):
    """The problem is unbounded: some unknown is not determined by anything.

    Examples
    --------
    >>> import bvpnav
    >>> issubclass(bvpnav.Unbounded, bvpnav.SolveError)
    True
    """


class Inaccurate(SolveError):
    """The solver returned an answer that failed bvpnav's residual verification.

    Examples
    --------
    >>> import bvpnav
    >>> issubclass(bvpnav.Inaccurate, bvpnav.SolveError)
    True
    """
