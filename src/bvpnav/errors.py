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
    """Base class of every error raised on purpose by bvpnav."""


class InputError(BvpnavError, ValueError):
    """Bad input: the message names the culprit and the fix."""


class ConvexityError(BvpnavError):
    """An item or objective breaks the DCP/DPP rules; the message names the item."""


class SolverNotFound(InputError):
    """Unknown or uninstalled solver; the message lists what is installed.

    A bad solver name is bad input like any other, so ``except InputError`` catches it.
    """


class SolveError(BvpnavError):
    """The solve failed or its answer did not pass verification.

    Attributes
    ----------
    attempts : list of dict
        One record per solver attempt (solver, status, reason).
    """

    def __init__(self, message: str, attempts: list[dict] | None = None):
        super().__init__(message)
        self.attempts = list(attempts or [])


class Infeasible(SolveError):
    """Hard information cannot hold together (or the solver says so)."""


class Unbounded(SolveError):
    """The problem is unbounded: some unknown is not determined by anything."""


class Inaccurate(SolveError):
    """The solver returned an answer that failed bvpnav's residual verification."""
