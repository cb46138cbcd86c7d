"""Known average velocity over time intervals."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bvpnav.errors import InputError
from bvpnav.items import Item, as_values

from ._common import finite, times

__all__ = ["AverageVelocity"]


@dataclass(frozen=True, kw_only=True, eq=False)
class AverageVelocity(Item):
    r"""The mean velocity over one or many intervals ``[t0, t1]`` is known.

    Parameters
    ----------
    t0, t1 : float or array_like of float
        Interval starts and ends in s (``t0 < t1`` element-wise).
    value : float or array_like
        Mean velocity in m/s (scalar, per axis, per interval, or (n_intervals, n_axes)).
        By the broadcasting rule of :class:`bvpnav.items.Item`: a flat list of
        len(t) == n_axes > 1 values is refused (write shape (len(t), n_axes)).
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` in m/s.

    Notes
    -----
    The mean of v over an interval is exact in terms of positions:

    .. math:: \rho = \frac{r(t_1) - r(t_0)}{t_1 - t_0} - \bar v.

    Examples
    --------
    A mean velocity of 1.5 m/s over the two seconds (e.g. a distance over a time):

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
    >>> from bvpnav.constraints import AverageVelocity, Position
    >>> prob = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=0.0),
    ...                                           AverageVelocity(t0=0.0, t1=2.0, value=1.5))
    >>> sol = prob.solve(solver="direct")
    >>> print(f"v(0) = {sol.velocity('x')[0]:.3f} m/s, r(2) = {sol.position('x')[-1]:.3f} m")
    v(0) = 1.000 m/s, r(2) = 3.000 m
    """

    t0: Any
    t1: Any
    value: Any = 0.0
    units = "m/s"

    def validate(self) -> None:
        a = times(self.t0, self.label, "t0")
        b = times(self.t1, self.label, "t1")
        if a.size != b.size:
            raise InputError(f"{self.label}: {a.size} starts t0 but {b.size} ends t1")
        bad = np.flatnonzero(b <= a)
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"{self.label}: interval {k} has t1={float(b[k])!r} s <= t0={float(a[k])!r} s; give t0 < t1"
            )
        object.__setattr__(self, "t0", a)
        object.__setattr__(self, "t1", b)
        object.__setattr__(self, "value", finite(self.value, self.label))

    def n_instants(self) -> int:
        """Number of instants (rows per axis)."""
        return int(self.t0.size)

    @classmethod
    def example(cls) -> AverageVelocity:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(t0=[1.0, 3.0], t1=[2.0, 9.5], value=[0.2, -0.1])

    def compile(self, model):
        ax = model.axes_of(self.axes, self.identify())
        what = f"{self.identify()}(t0/t1)"
        dt = np.repeat(self.t1 - self.t0, len(ax))
        rows = (model.position(self.t1, self.axes, what) - model.position(self.t0, self.axes, what))
        rows = rows / dt
        return rows - as_values(self.value, self.t0.size, len(ax), f"{self.identify()}: value")

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"\frac{r(t_{1,k}) - r(t_{0,k})}{t_{1,k} - t_{0,k}} - \bar v_k = 0"

    def math(self) -> str:
        return f"(r(t1_k) - r(t0_k)) / (t1_k - t0_k) - vbar_k = 0 over {self.t0.size} interval(s)"
