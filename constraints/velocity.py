"""Known velocities at given instants (Neumann conditions when at the ends)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bvpnav.items import Item

from ._common import finite, times
from ._fix import GnssFix

__all__ = ["Velocity"]


@dataclass(frozen=True, kw_only=True, eq=False)
class Velocity(GnssFix, Item):
    r"""The velocity is known at one or many instants.

    Parameters
    ----------
    t : float or array_like of float
        Instants in s, inside the recording window.
    value : float or array_like
        Velocity in m/s (scalar, per axis, per instant, or (len(t), n_axes)).
        By the broadcasting rule of :class:`bvpnav.items.Item`: a flat list of
        len(t) == n_axes > 1 values is refused (write shape (len(t), n_axes)).
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` in m/s.
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
    Residual :math:`\rho = v_a(t_k) - u_{k,a}`. At the window's ends the velocity is
    the FEM's natural boundary unknown :math:`v_0` or :math:`v_1` itself, so an end
    velocity in hard mode is an exact Neumann condition. Elsewhere
    :math:`v_j = (r_j - r_{j-1})/h_{j-1} + h_{j-1}(a_{j-1} + 2a_j)/6` with the corrected
    acceleration, integrated exactly between nodes.

    Examples
    --------
    The velocity at the end (2 m/s) and the start position fix the motion:

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
    >>> from bvpnav.constraints import Position, Velocity
    >>> prob = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=0.0), Velocity(t=2.0, value=2.0))
    >>> sol = prob.solve(solver="direct")
    >>> print(f"v(0) = {sol.velocity('x')[0]:.3f} m/s, r(2) = {sol.position('x')[-1]:.3f} m")
    v(0) = 1.000 m/s, r(2) = 3.000 m
    """

    t: Any
    value: Any = 0.0
    lever: Any = None
    delay: Any = None
    gate: Any = None
    quantity = "velocity"
    units = "m/s"

    def validate(self) -> None:
        object.__setattr__(self, "t", times(self.t, self.label))
        object.__setattr__(self, "value", finite(self.value, self.label))
        self._check_fix()

    def n_instants(self) -> int:
        """Number of instants (rows per axis)."""
        return int(self.t.size)

    @classmethod
    def example(cls) -> Velocity:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(t=[0.0, 4.2, 10.0], value=0.5)

    def compile(self, model):
        return self._fix_rows(model)

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"v(t_k) - u_k = 0"

    def math(self) -> str:
        extra = self._fix_math()
        return f"v(t_k){' ' + extra if extra else ''} - u_k = 0 at {self.t.size} instant(s)"
