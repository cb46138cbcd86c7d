"""Gyro bias per body axis, constant or drifting (a random walk at knots), rad/s."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ._attitude import (
    AttitudeErrorModel,
    _check_strapdown_gyro,
    at_point,
    hat_weights,
    knot_times,
    positive_option,
    random_walk_cost,
    random_walk_term,
)

__all__ = ["GyroBias"]

@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class GyroBias(AttitudeErrorModel):
    r"""Bias of each gyro axis, rad/s: constant, or drifting as a random walk.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Body axes ``x``, ``y``, ``z``; default all.
    sigma : float or array_like, optional
        Prior standard deviation of the bias, rad/s (one value, or one per axis): the
        datasheet's bias (turn-on) sigma. Time-varying, it applies to every knot without
        ``drift`` and to the first knot only with it (the random walk carries it on:
        putting it on every knot as well would count the same knowledge once per knot
        and pull the bias towards zero; measured on the car drive: a z bias of 1e-5
        against a true 6e-5 rad/s).
    prior : float or array_like, optional
        Prior value, rad/s (default 0).
    interval : float, optional
        Time-varying bias: values at knots about ``interval`` s apart (see
        :func:`bvpnav.error_models._attitude.knot_times`), linear between them.
    drift : float, optional
        Random-walk density of the bias, rad/s/sqrt(s) (the datasheet's bias random walk
        or a factor graph's bias random-walk sigma): a prior
        :math:`(b_{m+1} - b_m) \sim N(0, \sigma_d^2 \Delta t_m)` on successive knots.
        Needs ``interval``.
    hold : str or sequence of str, optional
        Body axes whose bias is not estimated but held at its prior value (``prior``, 0 by
        default) by a hard row on the total, e.g. ``hold="z"`` for the yaw-rate gyro of a
        level body when nothing carries heading information: the attitude loop does this
        itself then (and says so in a warning and ``stats["sequential"]["held"]``).

    Notes
    -----
    The gyro reads :math:`\hat\omega = (1 + s)\omega + b`; with
    :class:`GyroScaleFactor` absent ``s = 0``. Parameters ``gyro_bias_<axis>`` (constant)
    or ``gyro_bias_<axis>[m]`` (knot ``m``), axis-major. The corrected rate is
    :math:`\omega = (\hat\omega - b(t))/(1 + s)`, so a bias increment
    :math:`\delta b_j` changes it by :math:`-\delta b_j\,\varphi_m(t)/(1 + s_j)\, e_j`
    (:math:`\varphi_m` the knot's hat function, 1 for a constant bias); the attitude
    then changes by :math:`\psi` of :func:`~bvpnav.error_models._attitude.propagate`
    (continuous limit :math:`\psi(t) = -\int_0^t C\, b\, ds`) and the acceleration by
    :math:`\psi \times C f`. Columns are exact first derivatives of the discrete
    integration; the re-integrated acceleration differs from the linearized one by
    :math:`O(\delta^2)`.

    Examples
    --------
    The parameters and their columns on a short strapdown recording:

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> f = np.tile([0.0, 0.0, 9.80665], (11, 1))  # at rest, z up (m/s^2)
    >>> w = np.tile([0.0, 0.0, 0.1], (11, 1))      # turning about z at 0.1 rad/s
    >>> data = bvpnav.ImuData.from_gyro(t, f, w)
    >>> from bvpnav.error_models import GyroBias
    >>> GyroBias().names(data)
    ['gyro_bias_x', 'gyro_bias_y', 'gyro_bias_z']
    >>> GyroBias(interval=0.5).names(data)[:3]  # a bias at knots 0.5 s apart
    ['gyro_bias_x[0]', 'gyro_bias_x[1]', 'gyro_bias_x[2]']
    """

    #: What the solve's plausibility check judges its estimates as (the limits are in
    #: :mod:`bvpnav.solve.plausibility`).
    plausibility_kind = "gyro_bias"

    interval: Any = None
    drift: Any = None
    hold: Any = None
    units = "rad/s"
    default_step_scale = 1e-3

    def validate(self) -> None:
        object.__setattr__(self, "interval", positive_option(self.interval, "GyroBias: interval (s)"))
        object.__setattr__(self, "drift", positive_option(self.drift, "GyroBias: drift (rad/s/sqrt(s))"))
        if self.drift is not None and self.interval is None:
            raise InputError("GyroBias: drift= needs interval= (the knot spacing in s); without it the "
                             "bias is constant")
        if self.bounds is not None:
            raise InputError("GyroBias: bounds are not supported; give sigma= (a prior on the total)")
        if self.hold is not None:
            held = (self.hold,) if isinstance(self.hold, str) else tuple(self.hold)
            sel = [self.AXES[i] for i in self._sel()]
            bad = [a for a in held if a not in sel]
            if bad or not held:
                raise InputError(f"GyroBias: hold={self.hold!r}; give some of the estimated body axes {sel}")
            object.__setattr__(self, "hold", held)

    def knots(self, data) -> np.ndarray | None:
        """Knot times in s (None for a constant bias)."""
        return None if self.interval is None else knot_times(data.t, self.interval)

    def _weights(self, data) -> np.ndarray:
        k = self.knots(data)
        return np.ones((data.n, 1)) if k is None else hat_weights(data.t, k)

    def names(self, data) -> list[str]:
        k = self.knots(data)
        if k is None:
            return [f"gyro_bias_{self.AXES[i]}" for i in self._sel()]
        return [f"gyro_bias_{self.AXES[i]}[{m}]" for i in self._sel() for m in range(k.size)]

    def rate_columns(self, data) -> np.ndarray:
        _check_strapdown_gyro(data, "GyroBias")
        W = self._weights(data)
        m = W.shape[1]
        sel = self._sel()
        scale = at_point(data).scale
        out = np.zeros((data.n, 3, len(sel) * m))
        for a, i in enumerate(sel):
            out[:, i, a * m:(a + 1) * m] = -W / (1.0 + scale[i])
        return out

    def _sigma_per_param(self, data) -> np.ndarray:
        """``sigma`` (one value, or one per selected axis) repeated over the knots, rad/s."""
        q = len(self.names(data))
        if self.sigma is None:
            return np.full(q, np.inf)
        s = np.asarray(self.sigma, dtype=float).ravel()
        n_ax = len(self._sel())
        m = q // n_ax
        if s.size == 1:
            return np.full(q, float(s[0]))
        if s.size == n_ax:
            return np.repeat(s, m)
        if s.size == q:
            return s.copy()
        raise InputError(f"GyroBias: sigma has {s.size} values; give one, one per axis ({n_ax}) or one per "
                         f"parameter ({q})")

    def prior_sigma(self, data) -> np.ndarray:
        """Prior sigma per parameter: every value of a constant bias, every knot without
        ``drift``; with ``drift`` only the first knot of each axis (the turn-on bias; the
        random walk ties the rest to it, as a factor graph's bias chain does)."""
        s = self._sigma_per_param(data)
        k = self.knots(data)
        if k is not None and self.drift is not None:
            m = k.size
            keep = np.zeros(s.size, dtype=bool)
            keep[::m] = True
            s = np.where(keep, s, np.inf)
        return s

    def step_scale(self, data) -> np.ndarray:
        s = self._sigma_per_param(data)
        return np.where(np.isfinite(s), s, self.default_step_scale)

    def apply(self, values, parts, data) -> None:
        W = self._weights(data)
        m = W.shape[1]
        for a, i in enumerate(self._sel()):
            parts["bias"][:, i] += W @ values[a * m:(a + 1) * m]

    def bias(self, sol_or_values, data) -> np.ndarray:
        """The bias per sample (N, 3), rad/s, from a solution's ``error_params`` or totals."""
        vals = getattr(sol_or_values, "error_params", sol_or_values)
        names = self.names(data)
        v = np.array([float(vals[n]) for n in names])
        parts = {"bias": np.zeros((data.n, 3))}
        self.apply(v, parts, data)
        return parts["bias"]

    def extra_prior_cost(self, data) -> float:
        if self.drift is None:
            return 0.0
        return random_walk_cost(self.base(data), self.knots(data), self.drift)

    def held(self, data) -> np.ndarray:
        """Indices (into :meth:`names`) of the parameters ``hold`` keeps at their prior."""
        if not self.hold:
            return np.zeros(0, dtype=int)
        names = self.names(data)
        axes = [self.AXES[i] for i in self._sel()]
        m = len(names) // len(axes)
        idx = [a * m + k for a, ax in enumerate(axes) if ax in self.hold for k in range(m)]
        return np.array(idx, dtype=int)

    def extra_terms(self, model) -> list:
        from ..terms import Term
        from ._base import _relabel

        data = model.data
        out = []
        if self.drift is not None:
            out.append(random_walk_term(model, self.names(data), self.knots(data), self.drift, self.units,
                                        "random walk GyroBias", base=self.base(data)))
        idx = self.held(data)
        if idx.size:
            names = self.names(data)
            rows = self.physical_rows(model, self.prior_values(data)).rows(idx)
            out.append(Term(label=f"held GyroBias[{', '.join(self.hold)}]", item=None,
                            residual=_relabel(rows, [names[k] for k in idx], "held at its prior"),
                            mode="hard", kind="equality", scaled_by_lam=False, units=self.units))
        return out

    @classmethod
    def example(cls) -> GyroBias:
        return cls()
