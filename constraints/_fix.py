"""What GNSS fixes (:class:`Position`, :class:`Velocity`) share: the antenna's lever arm,
the fixes' delay against the IMU clock and the gate of outlier fixes (not an item kind)."""

from __future__ import annotations

import copy
import dataclasses
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from bvpnav.errors import InputError
from bvpnav.items import Linearizable, as_values, positive_array
from bvpnav.model import Affine, TimeLabels

__all__ = ["GnssFix"]

ESTIMATED = "estimated"


class _About(NamedTuple):
    """A delayed fix's linearization point: the delay (s), the rate of the IMU's fixed quantity
    (velocity for positions, acceleration for velocities) at ``t - delay``, (K, n_axes), and
    the lever arm (m, body frame) whose own motion the rows add to that rate (None: none)."""

    delay: float
    rate: np.ndarray
    outside: int = 0
    lever: tuple | None = None


class GnssFix(Linearizable):
    r"""Mixin of the fix items: ``lever``, ``delay`` and ``gate`` (see :class:`Position`).

    The residual of instant :math:`k` is

    .. math:: q(t_k - \delta) + C(t_k - \delta)\,\ell - p_k,
              \qquad \ell = l \text{ (position) or } \omega \times l \text{ (velocity)},

    with :math:`q` the FEM position or velocity, :math:`l` the lever arm (known, or the
    :class:`~bvpnav.error_models.LeverArm` unknowns) and :math:`\delta` the delay (known, or
    the :class:`~bvpnav.error_models.TimeOffset` unknown, linearized about the current
    estimate: :math:`q(t_k - \delta) \approx q(t_k - \hat\delta) - \dot{\hat q}(t_k - \hat\delta)
    (\delta - \hat\delta)`, with the antenna's own motion: :math:`\dot{\hat q}` holds
    :math:`\frac{d}{dt} C\ell` at the lever arm's current estimate as well as the IMU's rate).
    """

    #: ``"position"`` or ``"velocity"`` (set by the item class).
    quantity = "position"

    # ------------------------------------------------------------- checks
    def _check_fix(self) -> None:
        label = self.label
        lever = self.lever
        if lever is not None:
            if isinstance(lever, str):
                if lever != ESTIMATED:
                    raise InputError(f"{label}: lever={lever!r}; give three numbers (body x, y, z, m) or "
                                     f"'{ESTIMATED}' (with the LeverArm error model)")
            else:
                try:
                    lv = np.asarray(lever, dtype=float).ravel()
                except (TypeError, ValueError):
                    raise InputError(f"{label}: lever={lever!r} is not numeric; give (lx, ly, lz) in m in "
                                     "the body frame") from None
                if lv.size != 3 or not np.all(np.isfinite(lv)):
                    raise InputError(f"{label}: lever={lever!r}; give three finite numbers (lx, ly, lz) in m "
                                     "in the body frame (x, y, z body axes)")
                object.__setattr__(self, "lever", tuple(float(v) for v in lv))
        delay = self.delay
        if delay is not None:
            if isinstance(delay, str):
                if delay != ESTIMATED:
                    raise InputError(f"{label}: delay={delay!r}; give a number in s (known) or "
                                     f"'{ESTIMATED}' (with the TimeOffset error model)")
            else:
                try:
                    d = float(delay)
                except (TypeError, ValueError):
                    raise InputError(f"{label}: delay={delay!r} is not a number of seconds") from None
                if not np.isfinite(d):
                    raise InputError(f"{label}: delay={delay!r} must be finite (s)")
                object.__setattr__(self, "delay", d)
        if self.gate is not None:
            g = positive_array(self.gate, f"{label}: gate")
            if g.size != 1:
                raise InputError(f"{label}: gate={self.gate!r}; give one number (normalized residual)")
            if self.mode not in ("soft", "robust") or self.sigma is None:
                raise InputError(f"{label}: gate= judges residuals against sigma; give sigma= (soft or "
                                 f"robust mode), not mode={self.mode!r}")
            object.__setattr__(self, "gate", float(g.ravel()[0]))

    # ------------------------------------------------------- linearization
    @property
    def turns_with_attitude(self) -> bool:
        """With a lever arm the fixed point :math:`C l` turns with the attitude: the attitude loop
        hands the rows its linearization point (see :meth:`bvpnav.NavModel.antenna_offset`)."""
        return self.lever is not None

    @property
    def needs_linearization(self) -> bool:  # type: ignore[override]
        return self.delay == ESTIMATED and "_about" not in self.__dict__

    def first_phase(self):
        """The stand-in of the sequential loop's first phase: linearized at zero delay with the
        rate of the fixes' own values (their differences in time), so that the delay is an
        unknown of that phase too; with fewer than two fixes or values not given per fix,
        the fixes at their stamps (no delay)."""
        out = copy.copy(self)
        out.__dict__.pop("_about", None)
        v = np.asarray(self.value, dtype=float)
        if self.t.size >= 2 and v.ndim == 2 and v.shape[0] == self.t.size and np.all(np.diff(self.t) > 0):
            object.__setattr__(out, "_about", _About(0.0, np.gradient(v, self.t, axis=0)))
            return out
        object.__setattr__(out, "delay", None)
        return out

    def _delay0(self) -> float:
        about = self.__dict__.get("_about")
        return float(about.delay) if about is not None else 0.0

    def _at(self, rate_nodes: np.ndarray, t: np.ndarray, delay: float, axes_idx, lever=None) -> Linearizable:
        out = copy.copy(self)
        tt = self.t - delay
        rate = np.column_stack([np.interp(tt, t, rate_nodes[:, a]) for a in axes_idx])
        outside = int(np.sum((tt < t[0]) | (tt > t[-1])))
        if lever is None and self.lever is not None and not isinstance(self.lever, str):
            lever = self.lever
        object.__setattr__(out, "_about", _About(float(delay), rate, outside,
                                                 None if lever is None else tuple(float(v) for v in lever)))
        return out

    def _axes_idx(self, columns) -> list[int]:
        cols = list(columns)
        names = cols if self.axes is None else list(self.axes)
        bad = [a for a in names if a not in cols]
        if bad:
            raise InputError(f"{self.identify()}: axes {bad} not in the trajectory's {cols}")
        return [cols.index(a) for a in names]

    def linearization_counts(self) -> dict[str, int] | None:
        """Fixes whose delayed time falls outside the window at this linearization (they are
        linearized at the window's end), or None without an estimated delay."""
        about = self.__dict__.get("_about")
        if about is None:
            return None
        return {"outside the window": int(about.outside)}

    def linearization_change(self, previous) -> float | None:
        r"""The largest move of a fix's linearized rows between ``previous`` and this
        linearization, item units: :math:`|\hat\delta - \hat\delta_{prev}|\,\max_k |\dot{\hat q}_k|`
        (None when either has no linearization point or they hold other instants)."""
        a, b = self.__dict__.get("_about"), getattr(previous, "__dict__", {}).get("_about")
        if a is None or b is None or a.rate.shape != b.rate.shape:
            return None
        scale = max(float(np.max(np.abs(a.rate), initial=0.0)), float(np.max(np.abs(b.rate), initial=0.0)))
        return abs(a.delay - b.delay) * scale

    def linearized(self, t, positions):
        """A copy linearized about positions (N, d) or a trajectory DataFrame (m): the rate
        by differences of the positions, the delay kept at its last estimate (0 at first)."""
        import pandas as pd

        t = np.asarray(t, dtype=float)
        cols = list(positions.columns) if isinstance(positions, pd.DataFrame) else None
        p = np.asarray(positions, dtype=float)
        idx = self._axes_idx(cols) if cols is not None else (
            list(range(p.shape[1])) if self.axes is None else None)
        if idx is None:
            raise InputError(f"{self.identify()}: give the trajectory as a DataFrame (its columns name the "
                             "axes) to linearize an item with axes=")
        rate = np.gradient(p, t, axis=0)
        if self.quantity == "velocity":
            rate = np.gradient(rate, t, axis=0)
        return self._at(rate, t, self._delay0(), idx)

    def linearized_from(self, solution, t, trajectory):
        """A copy linearized about a solution: its delay estimate (``time_offset``, 0 when it
        has none), its nodal velocities (their differences for a velocity fix) and, for an
        estimated lever arm, its estimate (``lever_x``, ``lever_y``, ``lever_z``)."""
        if solution is None:
            return self.linearized(t, trajectory)
        t = np.asarray(solution.t, dtype=float)
        delay = float(solution.error_params.get("time_offset", self._delay0()))
        vel = solution.velocity().reshape(t.size, -1)
        rate = vel if self.quantity == "position" else np.gradient(vel, t, axis=0)
        lever = None
        names = [f"lever_{a}" for a in "xyz"]
        if self.lever == ESTIMATED and all(n in solution.error_params.index for n in names):
            lever = [float(solution.error_params[n]) for n in names]
        return self._at(rate, t, delay, self._axes_idx(solution._pos_cols), lever)

    def _antenna_rate(self, model, tt: np.ndarray, about: _About, what: str):
        r"""The rate of the antenna's offset from the IMU at the delayed times ``tt``, (K, n_axes):
        the time derivative of :math:`C\ell` for a position fix (:math:`C(\omega \times \ell)`,
        or differences at the samples for data without gyro rates), of
        :math:`C(\omega \times \ell)` for a velocity fix (by differences at the samples, as the
        IMU's own rate), at the linearization's lever arm; 0 without one (a first phase, whose
        rate is the fixes' own)."""
        if about.lever is None:
            return 0.0
        data = model.data
        rates = getattr(data, "attitude_point", None) is not None or getattr(data, "gyro", None) is not None
        if self.quantity == "position" and rates:   # C (omega x l), the derivative of C l
            rel = model.antenna_offset(tt, about.lever, self.axes, rate=True, what=what)
            return rel.c.reshape(tt.size, -1)
        g = model.grid.t
        rel = model.antenna_offset(g, about.lever, self.axes, rate=self.quantity == "velocity", what=what)
        d = np.gradient(rel.c.reshape(g.size, -1), g, axis=0)
        return np.column_stack([np.interp(tt, g, d[:, a]) for a in range(d.shape[1])])

    # ------------------------------------------------------------ the rows
    def _fix_rows(self, model) -> Affine:
        ident = self.identify()
        ax = model.axes_of(self.axes, ident)
        about = self.__dict__.get("_about")
        if self.delay == ESTIMATED and about is None:
            raise InputError(f"{ident}: delay='estimated' is linearized by the sequential loop; solve the "
                             "problem (NavigationProblem.solve) rather than compiling the item alone, or "
                             "linearize it first (item.linearized(t, positions))")
        shift = self.delay if isinstance(self.delay, float) else (about.delay if about is not None else 0.0)
        tt = self.t - shift
        if about is not None:
            # a linearization point may put a fix outside the window (an early estimate of the
            # delay): it is linearized at the window's end, and counted (linearization_counts)
            tt = np.clip(tt, model.grid.t[0], model.grid.t[-1])
        what = f"{ident}(t=...)" + (f" shifted by the delay {shift:g} s" if shift else "")
        if self.quantity == "position":
            rows = model.position(tt, self.axes, what=what)
        else:
            rows = model.velocity(tt, self.axes, what=what)
        if self.lever is not None:
            rows = rows + model.antenna_offset(tt, self.lever, self.axes, rate=self.quantity == "velocity",
                                               what=f"{ident}: lever={self.lever!r}")
        if self.delay == ESTIMATED:
            T = model.time_offset(f"{ident}: delay='estimated'")
            rate = about.rate + self._antenna_rate(model, tt, about, f"{ident}: lever={self.lever!r}")
            rate = rate.ravel()
            rows = rows - Affine(sp.csr_matrix(rate[:, None]) @ T.A, rate * (T.c[0] - about.delay))
        res = rows - as_values(self.value, self.t.size, len(ax), f"{ident}: value")
        prefix = "" if self.quantity == "position" else "v"
        return Affine(res.A, res.c, TimeLabels(prefix, [model.axes[a] for a in ax], self.t))

    # ------------------------------------------------------------- gating
    def with_instants(self, keep: np.ndarray, n_axes: int):
        """A copy holding the instants ``keep`` (indices) only: value, sigma and the
        linearization point taken along (``n_axes``: the axes the rows are on)."""
        keep = np.asarray(keep, dtype=int)
        k = self.t.size
        ident = self.identify()
        vals = as_values(self.value, k, n_axes, f"{ident}: value").reshape(k, n_axes)[keep]
        sig = self.weight_rows(k * n_axes).reshape(k, n_axes)[keep]
        out = dataclasses.replace(self, t=self.t[keep], value=vals, sigma=sig, name=self.label)
        about = self.__dict__.get("_about")
        if about is not None:
            object.__setattr__(out, "_about", about._replace(rate=about.rate[keep]))
        return out

    def _fix_math(self) -> str:
        extra = []
        if self.lever is not None:
            extra.append("+ C l" if self.quantity == "position" else "+ C (omega x l)")
        if self.delay is not None:
            extra.append("at t_k - delay")
        return " ".join(extra)
