r"""A known height profile: a flat floor, or a floor that rises as a known ramp."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bvpnav.errors import InputError
from bvpnav.items import Item, as_values

from ._common import finite, times

__all__ = ["FloorHeight"]


@dataclass(frozen=True, kw_only=True, eq=False)
class FloorHeight(Item):
    r"""The height at the instants ``t`` follows a known profile, up to one common unknown level.

    A walker on a flat floor stands at the same height at every stance; on a ramp or stairs
    the height changes by known amounts. The floor's own level is not needed: the residuals
    are height differences from the first instant. As a band (``tol``, the floor's
    flatness plus the foot's placement, e.g. 0.02 m) it says what a Kalman filter's tuned
    zero cannot: anywhere within the tolerance is equally right (``mode="band", tol=...``).

    Parameters
    ----------
    t : array_like of float
        Instants in s (at least two), e.g. the middle of each stance.
    value : float or array_like, optional
        The floor's height at each instant, m (default 0: flat). Only differences matter.
    axis : str
        The vertical axis (default ``"z"``).
    sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` and ``tol`` in m.

    Notes
    -----
    Residual for instant :math:`k \ge 2`:
    :math:`\rho_k = (r_z(t_k) - r_z(t_1)) - (h_k - h_1)`.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav import ImuData, NavigationProblem
    >>> from bvpnav.constraints import FloorHeight, Position
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> acc = np.column_stack([0 * t, 0.002 + 0 * t])            # a 2 mm/s^2 bias on z
    >>> prob = NavigationProblem(ImuData(t, acc, axes=("x", "z")))
    >>> floor = FloorHeight(t=[2.0, 5.0, 8.0], axis="z", mode="band", tol=0.001)
    >>> _ = prob.add(Position(t=[0.0, 10.0], value=0.0), floor)
    >>> z = prob.solve(solver="clarabel").position("z")
    >>> round(float(abs(z[50] - z[20])), 3) <= 0.001
    True
    """

    t: Any
    value: Any = 0.0
    axis: str = "z"
    units = "m"

    @property
    def heading_information(self) -> bool:
        """A height profile on the vertical axis says nothing about the heading."""
        return self.axis != "z"

    def validate(self) -> None:
        label = self.label
        t = times(self.t, label)
        if t.size < 2:
            raise InputError(f"{label}: t has {t.size} instant(s); a height profile relates at least two")
        object.__setattr__(self, "t", t)
        v = finite(self.value, label)
        if v.size not in (1, t.size):
            raise InputError(f"{label}: {v.size} heights for {t.size} instants; give one per instant or one "
                             "for all (m)")
        object.__setattr__(self, "value", np.broadcast_to(v.ravel(), t.shape).copy())
        if self.axes is not None:
            raise InputError(f"{label}: axes={self.axes!r}; a height profile acts on one axis: give axis='z' "
                             "(or the name of your vertical axis)")
        if not isinstance(self.axis, str):
            raise InputError(f"{label}: axis={self.axis!r}; give the vertical axis's name, e.g. 'z'")

    @classmethod
    def example(cls) -> FloorHeight:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(t=[1.0, 4.0, 8.5], value=[0.0, 0.0, 0.15])

    def compile(self, model):
        what = f"{self.identify()}(t=...)"
        axes = (self.axis,)
        z = model.position(self.t, axes, what=what)
        h = as_values(self.value, self.t.size, 1, f"{self.identify()}: value")
        return (z.rows(np.arange(1, self.t.size)) - z.rows(np.zeros(self.t.size - 1, dtype=int))
                - (h[1:] - h[0]))

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"(z(t_k) - z(t_1)) - (h_k - h_1) = 0"

    def math(self) -> str:
        return f"(z(t_k) - z(t_1)) - (h_k - h_1) = 0 at {self.t.size} instants on axis {self.axis}"
