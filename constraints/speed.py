"""A speed limit over a time interval (second-order cone item)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from bvpnav.errors import InputError
from bvpnav.items import Item
from bvpnav.model import Cone

from ._common import finite
from .bounds import check_times, optional_interval, resolve_interval

__all__ = ["SpeedLimit"]


@dataclass(frozen=True, kw_only=True, eq=False)
class SpeedLimit(Item):
    r"""The speed stays below a limit: ``|v(t)|_2 <= v_max`` at the grid nodes.

    Parameters
    ----------
    v_max : float
        Speed limit in m/s (> 0).
    t0, t1 : float, optional
        Interval in s; default the whole recording window.
    axes : sequence of str, optional
        Axes whose velocity components make up the speed; default all axes.
    sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` and ``tol`` in m/s, applied to the
        excess speed. ``soft`` penalises :math:`\max(|v| - v_{max}, 0)^2/\sigma^2`,
        ``robust`` :math:`\max(|v| - v_{max}, 0)/\sigma`, ``band`` allows
        :math:`|v| \le v_{max} + tol`.

    Notes
    -----
    One second-order cone per check time :math:`t_k` (the grid nodes inside the
    interval, and ``t0``, ``t1``):

    .. math:: \|v(t_k)\|_2 \le v_{max},

    with the node velocities of :meth:`bvpnav.model.NavModel.velocity` (affine in the
    positions, the acceleration residuals and the end velocities). Between nodes the
    velocity is quadratic in time and is not checked.

    Examples
    --------
    From rest, 0.5 m/s^2 would reach 1 m/s at 2 s; the speed is known to stay below 0.8 m/s
    (a second-order cone: solved by a conic back end):

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
    >>> from bvpnav.constraints import Position, SpeedLimit, Velocity
    >>> prob = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=0.0), Velocity(t=0.0, value=0.0),
    ...                                           SpeedLimit(v_max=0.8))
    >>> print(f"{np.abs(prob.solve(solver='clarabel').velocity('x')).max():.3f} m/s")
    0.800 m/s
    """

    v_max: float
    t0: float | None = None
    t1: float | None = None
    units = "m/s"
    kind = "cone"

    def validate(self) -> None:
        label = self.label
        v = finite(self.v_max, label, "v_max")
        if v.size != 1 or not float(v.ravel()[0]) > 0:
            raise InputError(f"{label}: v_max={self.v_max!r} must be one positive speed in m/s")
        object.__setattr__(self, "v_max", float(v.ravel()[0]))
        a, b = optional_interval(self.t0, self.t1, label)
        object.__setattr__(self, "t0", a)
        object.__setattr__(self, "t1", b)

    @classmethod
    def example(cls) -> SpeedLimit:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(v_max=20.0, t0=1.0, t1=9.0)

    def compile(self, model):
        label = self.identify()
        ax = model.axes_of(self.axes, label)
        a, b = resolve_interval(model, self.t0, self.t1, label)
        ts = check_times(model, a, b)
        vel = model.velocity(ts, self.axes, what=f"{label}(t=...)")
        nax, m = len(ax), ts.size
        k = nax + 1
        # group j: row j*k is the limit (constant), rows j*k+1.. the velocity components
        pos = (np.arange(m)[:, None] * k + 1 + np.arange(nax)[None, :]).ravel()
        P = sp.csr_matrix((np.ones(m * nax), (pos, np.arange(m * nax))), shape=(m * k, m * nax))
        c = P @ vel.c
        c[np.arange(m) * k] = self.v_max
        labels = tuple(lab for tk in ts for lab in
                       [f"v_max(t={tk:.6g})"] + [f"v{model.axes[i]}(t={tk:.6g})" for i in ax])
        return Cone(P @ vel.A, c, labels, size=k)

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"\|v(t_k)\|_2 - v_{max} \leq 0"

    def math(self) -> str:
        return f"|v(t_k)|_2 - {self.v_max:g} m/s <= 0 at the nodes of the interval"
