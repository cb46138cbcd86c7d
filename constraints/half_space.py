"""A half-space the trajectory stays in over a time interval (inequality item)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from bvpnav.errors import InputError
from bvpnav.items import Item
from bvpnav.model import Affine

from ._common import finite
from .bounds import check_times, optional_interval, resolve_interval

__all__ = ["HalfSpace"]


@dataclass(frozen=True, kw_only=True, eq=False)
class HalfSpace(Item):
    r"""The position stays in the half-space ``n . r(t) <= b`` over an interval.

    Parameters
    ----------
    normal : array_like of float
        Outward normal ``n``, one dimensionless component per chosen axis (in the order
        of ``axes``; all axes of the data when ``axes`` is None). Not normalised: the
        residual is in m times ``|n|``.
    b : float
        Offset in m (times ``|n|``).
    t0, t1 : float, optional
        Interval in s; default the whole recording window.
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` and ``tol`` in the residual's units.

    Notes
    -----
    Inequality residual at every grid node inside the interval and at ``t0``, ``t1``:

    .. math:: g_k = \sum_a n_a\, r_a(t_k) - b \le 0.

    The FEM position is piecewise linear, so the half-space (a convex set) holding at
    the nodes means it holds at every instant. Example: a ground plane
    :math:`z \ge 0.3 x - 5` is ``HalfSpace(axes=("x", "z"), normal=(0.3, -1), b=5)``.

    Examples
    --------
    Moving diagonally from rest (0.5 m/s^2 on x and y), kept in :math:`x + y \le 1` m:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import HalfSpace, Position, Velocity
    >>> data = bvpnav.ImuData(t=np.linspace(0.0, 2.0, 21), acc=np.full((21, 2), 0.5), axes=("x", "y"))
    >>> prob = bvpnav.NavigationProblem(data).add(
    ...     Position(t=0.0, value=[0.0, 0.0]), Velocity(t=0.0, value=[0.0, 0.0]),
    ...     HalfSpace(normal=[1.0, 1.0], b=1.0, t0=0.0, t1=2.0))
    >>> sol = prob.solve(solver="clarabel")
    >>> print(f"x + y = {sol.position('x')[-1] + sol.position('y')[-1]:.3f} m at 2 s")
    x + y = 1.000 m at 2 s
    """

    normal: Any
    b: float = 0.0
    t0: float | None = None
    t1: float | None = None
    units = "m"
    kind = "inequality"

    def validate(self) -> None:
        label = self.label
        n = finite(self.normal, label, "normal").ravel()
        if n.size == 0 or not np.any(n != 0):
            raise InputError(f"{label}: normal={self.normal!r} must have a non-zero component per axis")
        if self.axes is not None and len(self.axes) != n.size:
            raise InputError(
                f"{label}: normal has {n.size} component(s) for {len(self.axes)} axis(es) "
                f"{list(self.axes)}; give one component per axis"
            )
        object.__setattr__(self, "normal", n)
        bb = finite(self.b, label, "b")
        if bb.size != 1:
            raise InputError(f"{label}: b must be one number (m), got {bb.size} values")
        object.__setattr__(self, "b", float(bb.ravel()[0]))
        a, b = optional_interval(self.t0, self.t1, label)
        object.__setattr__(self, "t0", a)
        object.__setattr__(self, "t1", b)

    @classmethod
    def example(cls) -> HalfSpace:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(axes=("x", "z"), normal=[0.3, -1.0], b=5.0, t0=2.0, t1=8.0)

    def compile(self, model):
        label = self.identify()
        ax = model.axes_of(self.axes, label)
        if len(ax) != self.normal.size:
            raise InputError(
                f"{label}: normal has {self.normal.size} component(s) but the data has {len(ax)} "
                f"axis(es) {list(model.axes)}; give axes= or one component per axis"
            )
        a, b = resolve_interval(model, self.t0, self.t1, label)
        ts = check_times(model, a, b)
        rows = model.position(ts, self.axes, what=f"{label}(t=...)")
        S = sp.kron(sp.identity(ts.size, format="csr"), sp.csr_matrix(self.normal[None, :]), format="csr")
        labels = tuple(f"n.r(t={tk:.6g})" for tk in ts)
        return Affine(S @ rows.A, S @ rows.c - self.b, labels)

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"n \cdot r(t_k) - b \leq 0"

    def math(self) -> str:
        n = ", ".join(f"{v:g}" for v in self.normal)
        return f"({n}) . r(t_k) - {self.b:g} <= 0 at the nodes of the interval"
