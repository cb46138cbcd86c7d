"""Stationary intervals: the velocity is zero (a zero-velocity update)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bvpnav.items import Item

from ._common import interval

__all__ = ["ZeroVelocity"]


@dataclass(frozen=True, kw_only=True, eq=False)
class ZeroVelocity(Item):
    r"""The object is at rest during ``[t0, t1]``.

    Parameters
    ----------
    t0, t1 : float
        Interval in s, ``t0 < t1``, inside the window.
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` in m/s.

    Notes
    -----
    One row per sample inside the interval plus its two ends:
    :math:`\rho_k = v(t_k) = 0` for :math:`t_k \in [t_0, t_1]`, with the consistent FEM
    velocity (see :class:`~bvpnav.constraints.Velocity`).

    Examples
    --------
    A sensor at rest for 2 s that reads 0.1 m/s^2: the stillness alone reveals its bias:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, ZeroVelocity
    >>> from bvpnav.error_models import Bias
    >>> data = bvpnav.ImuData(t=np.linspace(0.0, 2.0, 21), acc=np.full(21, 0.1))
    >>> prob = bvpnav.NavigationProblem(data, error_model=Bias())
    >>> sol = prob.add(Position(t=0.0, value=0.0), ZeroVelocity(t0=0.0, t1=2.0)).solve(solver="direct")
    >>> print(f"bias {sol.error_params['bias_x']:.3f} m/s^2")
    bias 0.100 m/s^2
    """

    t0: Any
    t1: Any
    units = "m/s"
    #: Zero velocity is the same in every horizontal direction: it says nothing about the
    #: heading (the attitude loop holds the yaw-rate gyro bias when nothing else does).
    heading_information = False

    def validate(self) -> None:
        a, b = interval(self.t0, self.t1, self.label)
        object.__setattr__(self, "t0", a)
        object.__setattr__(self, "t1", b)

    def instants(self, grid) -> np.ndarray:
        """Instants (s) where the velocity is set to zero."""
        inner = grid.t[(grid.t > self.t0) & (grid.t < self.t1)]
        return np.concatenate([[self.t0], inner, [self.t1]])

    @classmethod
    def example(cls) -> ZeroVelocity:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(t0=0.0, t1=1.0)

    def compile(self, model):
        return model.velocity(self.instants(model.grid), self.axes, f"{self.identify()}(t0/t1)")

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"v(t_k) = 0"

    def math(self) -> str:
        return f"v(t_k) = 0 for t_k in [{self.t0:g}, {self.t1:g}] s"
