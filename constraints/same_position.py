r"""The same place at two instants: a walk that ends where it started, a loop closed."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bvpnav.errors import InputError
from bvpnav.items import Item

from ._common import times

__all__ = ["SamePosition"]


def _pairs(t, label: str) -> np.ndarray:
    """Instant pairs (k, 2) in s from ``(ta, tb)`` or a list of such pairs."""
    arr = np.asarray(t, dtype=object)
    flat = times(np.asarray(t, dtype=float).ravel() if arr.size else t, label)
    if flat.size % 2 or flat.size == 0:
        raise InputError(f"{label}: t={t!r}; give two instants t=(ta, tb) in s, or a list of such pairs")
    pairs = flat.reshape(-1, 2)
    same = np.flatnonzero(pairs[:, 0] == pairs[:, 1])
    if same.size:
        raise InputError(f"{label}: pair {int(same[0])} names one instant twice ({pairs[same[0], 0]:g} s); "
                         "give two different instants")
    return pairs


@dataclass(frozen=True, kw_only=True, eq=False)
class SamePosition(Item):
    r"""The position is the same at the two instants of ``t = (ta, tb)`` (or of each pair).

    The information a walk carries and a filter cannot use: it ends where it started, or it
    passes a marked point twice. Soft with the repeatability of the place as ``sigma`` (a
    doorway: 0.1 m), or a band with ``tol``.

    Parameters
    ----------
    t : (float, float) or sequence of (float, float)
        The two instants in s (or several pairs), inside the window.
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` and ``tol`` in m. ``axes=("x", "y")``
        when only the horizontal place repeats (stairs).

    Notes
    -----
    Residual per pair and axis: :math:`\rho = r_a(t_b) - r_a(t_a)` with the FEM position
    :math:`r_a(t) = \sum_j r_{a,j} \phi_j(t)`.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav import ImuData, NavigationProblem
    >>> from bvpnav.constraints import Position, SamePosition, Velocity
    >>> t = np.linspace(0.0, 10.0, 1001)
    >>> acc = np.column_stack([np.cos(0.2 * np.pi * t), -np.sin(0.2 * np.pi * t)]) * 0.5 + 0.01  # biased
    >>> prob = NavigationProblem(ImuData(t, acc, axes=("x", "y")))
    >>> _ = prob.add(Position(t=[0.0], value=0.0), Velocity(t=[0.0], value=[0.0, -0.5 / (0.2 * np.pi)]),
    ...              SamePosition(t=(0.0, 10.0), sigma=0.01))
    >>> end = prob.solve(solver="direct").position()[-1]
    >>> bool(np.all(np.abs(end) < 0.02))
    True
    """

    t: Any
    units = "m"

    def validate(self) -> None:
        object.__setattr__(self, "t", _pairs(self.t, self.label))

    @classmethod
    def example(cls) -> SamePosition:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(t=[(0.0, 10.0), (2.0, 7.5)])

    def compile(self, model):
        what = f"{self.identify()}(t=...)"
        return (model.position(self.t[:, 1], self.axes, what=what)
                - model.position(self.t[:, 0], self.axes, what=what))

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"r(t_b) - r(t_a) = 0"

    def math(self) -> str:
        return f"r(t_b) - r(t_a) = 0 for {self.t.shape[0]} pair(s) of instants"
