"""Lower and upper bounds on positions over a time interval (inequality items)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from bvpnav.errors import InputError
from bvpnav.items import Item
from bvpnav.model import Affine

from ._common import finite

__all__ = ["PositionBound"]


def optional_interval(t0, t1, label: str) -> tuple[float | None, float | None]:
    """Validate an optional interval (``None`` ends mean the window's ends), in s."""
    out = []
    for v, what in ((t0, "t0"), (t1, "t1")):
        if v is None:
            out.append(None)
            continue
        a = finite(v, label, what)
        if a.size != 1:
            raise InputError(f"{label}: {what} must be a single time in s, got {a.size} values")
        out.append(float(a.ravel()[0]))
    if out[0] is not None and out[1] is not None and not out[1] > out[0]:
        raise InputError(f"{label}: interval t0={out[0]!r} s, t1={out[1]!r} s has t1 <= t0; give t0 < t1")
    return out[0], out[1]


def resolve_interval(model, t0: float | None, t1: float | None, label: str) -> tuple[float, float]:
    """The item's interval with ``None`` ends replaced by the window's, checked inside it."""
    g = model.grid
    a = g.t0 if t0 is None else t0
    b = g.t1 if t1 is None else t1
    span = max(g.t1 - g.t0, 1.0)
    eps = 1e-12 * span
    if a < g.t0 - eps or b > g.t1 + eps:
        raise InputError(
            f"{label}: interval [{a:g}, {b:g}] s reaches outside the recording window "
            f"[{g.t0:g}, {g.t1:g}] s; give t0, t1 inside it (or omit them for the whole window)"
        )
    if not b > a:
        raise InputError(f"{label}: interval [{a:g}, {b:g}] s is empty; give t0 < t1")
    return float(min(max(a, g.t0), g.t1)), float(min(max(b, g.t0), g.t1))


def check_times(model, a: float, b: float, extra=()) -> np.ndarray:
    """Sorted unique times of every grid node in ``[a, b]``, ``a``, ``b`` and the
    ``extra`` times inside ``[a, b]`` (s)."""
    g = model.grid
    ex = np.asarray(extra, dtype=float).ravel()
    ts = np.concatenate([g.t[g.nodes_in(a, b)], [a, b], ex[(ex > a) & (ex < b)]])
    return np.unique(ts)


def profile(value, times_of, label: str, what: str):
    """Validate a bound: a scalar (``times_of`` None) or values at profile times (m, s)."""
    if value is None:
        if times_of is not None:
            raise InputError(f"{label}: {what}_t given without {what}")
        return None, None
    v = finite(value, label, what)
    if times_of is None:
        if v.ndim != 0 and v.size != 1:
            raise InputError(
                f"{label}: {what} has {v.size} values but no {what}_t; give {what}_t (s) for a "
                f"piecewise-linear profile or a single number (m)"
            )
        return v.reshape(()), None
    tt = finite(times_of, label, f"{what}_t").ravel()
    v = v.ravel()
    if tt.size != v.size or tt.size < 2:
        raise InputError(
            f"{label}: {what}_t has {tt.size} time(s) and {what} {v.size} value(s); give equally "
            "many, at least two"
        )
    if np.any(np.diff(tt) <= 0):
        k = int(np.flatnonzero(np.diff(tt) <= 0)[0]) + 1
        raise InputError(f"{label}: {what}_t must increase strictly; entry {k} is {tt[k]!r} s")
    return v, tt


def evaluate_profile(v: np.ndarray, tt: np.ndarray | None, times: np.ndarray, a: float, b: float,
                     label: str, what: str) -> np.ndarray:
    """The bound at ``times`` (no extrapolation: the profile must cover [a, b])."""
    if tt is None:
        return np.full(times.size, float(v))
    span = max(abs(b - a), 1.0) * 1e-12
    if tt[0] > a + span or tt[-1] < b - span:
        raise InputError(
            f"{label}: the {what} profile covers [{tt[0]:g}, {tt[-1]:g}] s but the interval is "
            f"[{a:g}, {b:g}] s; extend {what}_t/{what} over the interval (no extrapolation)"
        )
    return np.interp(times, tt, v)


@dataclass(frozen=True, kw_only=True, eq=False)
class PositionBound(Item):
    r"""The position of each chosen axis stays between bounds over an interval.

    Parameters
    ----------
    lower, upper : float or array_like, optional
        Bounds in m, at least one of them: a number (constant bound), or values of a
        piecewise-linear profile at the times ``lower_t`` / ``upper_t``.
    lower_t, upper_t : array_like of float, optional
        Strictly increasing profile times in s; the profile must cover ``[t0, t1]``
        (it is interpolated linearly, never extrapolated).
    t0, t1 : float, optional
        Interval in s; default the whole recording window.
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` and ``tol`` in m. ``soft`` and
        ``robust`` penalise only the violation, ``band`` allows ``tol`` of it.

    Notes
    -----
    Inequality residual (``g <= 0``) for every chosen axis ``a`` at every check time
    :math:`t_k` (the grid nodes inside the interval, ``t0``, ``t1`` and the profile's
    breakpoints inside it):

    .. math:: g = \ell(t_k) - r_a(t_k) \le 0, \qquad g = r_a(t_k) - u(t_k) \le 0.

    The FEM position is piecewise linear between nodes and so is a piecewise-linear
    bound between its breakpoints, so the bound holding at these times means it holds
    at every instant of the interval.

    Examples
    --------
    Starting at rest, 0.5 m/s^2 would carry the object 1 m in 2 s; a wall at 0.5 m holds it
    (an inequality: solved by a conic back end):

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
    >>> from bvpnav.constraints import Position, PositionBound, Velocity
    >>> prob = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=0.0), Velocity(t=0.0, value=0.0),
    ...                                           PositionBound(upper=0.5, t0=0.0, t1=2.0))
    >>> print(f"r(2) = {prob.solve(solver='clarabel').position('x')[-1]:.3f} m")
    r(2) = 0.500 m
    """

    lower: Any = None
    upper: Any = None
    lower_t: Any = None
    upper_t: Any = None
    t0: float | None = None
    t1: float | None = None
    units = "m"
    kind = "inequality"

    def validate(self) -> None:
        label = self.label
        if self.lower is None and self.upper is None:
            raise InputError(f"{label}: give lower= and/or upper= (m)")
        lo, lt = profile(self.lower, self.lower_t, label, "lower")
        up, ut = profile(self.upper, self.upper_t, label, "upper")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "lower_t", lt)
        object.__setattr__(self, "upper", up)
        object.__setattr__(self, "upper_t", ut)
        a, b = optional_interval(self.t0, self.t1, label)
        object.__setattr__(self, "t0", a)
        object.__setattr__(self, "t1", b)

    @classmethod
    def example(cls) -> PositionBound:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(lower=[-5.0, -4.0, -6.0], lower_t=[0.0, 5.0, 10.0], upper=8.0, t0=1.0, t1=9.0)

    def check_times(self, model) -> np.ndarray:
        """Times (s) at which the bounds are enforced."""
        a, b = resolve_interval(model, self.t0, self.t1, self.label)
        extra = [x for x in (self.lower_t, self.upper_t) if x is not None]
        return check_times(model, a, b, np.concatenate(extra) if extra else ())

    def compile(self, model):
        label = self.identify()
        ax = model.axes_of(self.axes, label)
        a, b = resolve_interval(model, self.t0, self.t1, label)
        ts = self.check_times(model)
        rows = model.position(ts, self.axes, what=f"{label}(t=...)")
        nax = len(ax)
        parts = []
        lo = up = None
        if self.lower is not None:
            lo = evaluate_profile(self.lower, self.lower_t, ts, a, b, label, "lower")
            parts.append(-rows + np.repeat(lo, nax))
        if self.upper is not None:
            up = evaluate_profile(self.upper, self.upper_t, ts, a, b, label, "upper")
            parts.append(rows - np.repeat(up, nax))
        if lo is not None and up is not None and np.any(lo > up):
            k = int(np.flatnonzero(lo > up)[0])
            raise InputError(
                f"{label}: lower bound {lo[k]:g} m exceeds upper bound {up[k]:g} m at t={ts[k]:g} s; "
                "no position satisfies it"
            )
        out = Affine.vstack(parts) if len(parts) > 1 else parts[0]
        return Affine(sp.csr_matrix(out.A), out.c)

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        parts = [p for p, v in ((r"\ell(t_k) - r(t_k)", self.lower), (r"r(t_k) - u(t_k)", self.upper))
                 if v is not None]
        return r",\ ".join(parts) + r" \leq 0"

    def math(self) -> str:
        which = " and ".join(w for w, v in (("lower - r(t_k)", self.lower), ("r(t_k) - upper", self.upper))
                             if v is not None)
        a = "T0" if self.t0 is None else f"{self.t0:g}"
        b = "T1" if self.t1 is None else f"{self.t1:g}"
        span = "the whole window" if self.t0 is None and self.t1 is None else f"[{a}, {b}] s"
        return f"{which} <= 0 at the nodes of {span}"
