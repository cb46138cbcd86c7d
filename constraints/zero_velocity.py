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
    """

    t0: Any
    t1: Any
    units = "m/s"

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
