"""Known positions at given instants (Dirichlet conditions when at the ends)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bvpnav.items import Item

from ._common import finite, times
from ._fix import GnssFix

__all__ = ["Position"]


@dataclass(frozen=True, kw_only=True, eq=False)
class Position(GnssFix, Item):
    r"""The position is known at one or many instants.

    Parameters
    ----------
    t : float or array_like of float
        Instants in s, inside the recording window.
    value : float or array_like
        Position in m: a scalar, one value per axis, one per instant, or shape
        (len(t), n_axes).
        By the broadcasting rule of :class:`bvpnav.items.Item`: a flat list of
        len(t) == n_axes > 1 values is refused (write shape (len(t), n_axes)).
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` in m.
    lever : (float, float, float) or "estimated", optional
        The GNSS antenna's position relative to the IMU in the body frame, m: known, or
        ``"estimated"`` (the :class:`~bvpnav.error_models.LeverArm` error model's unknowns).
        Needs strapdown data (the attitude).
    delay : float or "estimated", optional
        The fixes' delay against the IMU clock, s: a fix stamped ``t_k`` holds the value at
        ``t_k - delay``. Known, or ``"estimated"`` (the
        :class:`~bvpnav.error_models.TimeOffset` error model's unknown, linearized by the
        sequential loop).
    gate : float, optional
        Outlier gate: after a solve, a fix whose normalized residual (see
        :func:`bvpnav.solve.gating.with_gating`) exceeds ``gate`` is rejected and the
        problem solved again without it; every rejection is listed in
        ``Solution.rejected`` and warned. Needs ``sigma``.

    Notes
    -----
    Residual per instant k and axis a: :math:`\rho = r_a(t_k) - p_{k,a}` with
    :math:`r_a(t) = \sum_j r_{a,j} \phi_j(t)`. At ``t = T0`` or ``T1`` in hard mode
    this is the Dirichlet boundary condition.

    Examples
    --------
    Known positions 0 m at 0 s and 3 m at 2 s under 0.5 m/s^2 give the initial velocity
    :math:`(3 - 0.25 \cdot 2^2) / 2 = 1` m/s:

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
    >>> from bvpnav.constraints import Position
    >>> prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 2.0], value=[0.0, 3.0]))
    >>> sol = prob.solve(solver="direct")
    >>> print(f"v(0) = {sol.velocity('x')[0]:.3f} m/s")
    v(0) = 1.000 m/s
    """

    t: Any
    value: Any = 0.0
    lever: Any = None
    delay: Any = None
    gate: Any = None
    quantity = "position"
    units = "m"

    def validate(self) -> None:
        object.__setattr__(self, "t", times(self.t, self.label))
        object.__setattr__(self, "value", finite(self.value, self.label))
        self._check_fix()

    def n_instants(self) -> int:
        """Number of instants (rows per axis)."""
        return int(self.t.size)

    @property
    def heading_information(self) -> bool:
        """Positions at one instant (a start) say nothing about the heading; at two or more
        they do (a displacement, or a loop that closes)."""
        return self.t.size > 1

    @classmethod
    def example(cls) -> Position:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(t=[0.0, 2.5, 6.0, 10.0], value=[0.0, 1.0, 2.0, 3.0])  # one per instant, any axes

    def compile(self, model):
        return self._fix_rows(model)

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"r(t_k) - p_k = 0"

    def math(self) -> str:
        extra = self._fix_math()
        return f"r(t_k){' ' + extra if extra else ''} - p_k = 0 at {self.t.size} instant(s)"
