"""Gyro bias per body axis, constant or drifting (a random walk at knots), rad/s."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ._attitude import AttitudeErrorModel, _check_strapdown_gyro, at_point, hat_weights, knot_times
from ._base import _relabel

__all__ = ["GyroBias"]

_AXES = ("x", "y", "z")


def _positive(value, what: str) -> float | None:
    if value is None:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{what}={value!r}: give a positive number") from None
    if not (np.isfinite(v) and v > 0):
        raise InputError(f"{what}={value!r}: must be finite and > 0")
    return v


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class GyroBias(AttitudeErrorModel):
    """Bias of each gyro axis, rad/s: constant, or drifting as a random walk.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Body axes ``x``, ``y``, ``z``; default all.
    sigma : float or array_like, optional
        Prior standard deviation of the bias (every knot's total value when
        time-varying), rad/s: the datasheet's bias (turn-on) sigma.
    prior : float or array_like, optional
        Prior value, rad/s (default 0).
    interval : float, optional
        Time-varying bias: values at knots about ``interval`` s apart (see
        :func:`bvpnav.error_models._attitude.knot_times`), linear between them.
    drift : float, optional
        Random-walk density of the bias, rad/s/sqrt(s) (the datasheet's bias random walk
        or a factor graph's bias random-walk sigma): a prior
        :math:`(b_{m+1} - b_m) \\sim N(0, \\sigma_d^2 \\Delta t_m)` on successive knots.
        Needs ``interval``.

    Notes
    -----
    The gyro reads :math:`\\hat\\omega = (1 + s)\\omega + b`; with
    :class:`GyroScaleFactor` absent ``s = 0``. Parameters ``gyro_bias_<axis>`` (constant)
    or ``gyro_bias_<axis>[m]`` (knot ``m``), axis-major. The corrected rate is
    :math:`\\omega = (\\hat\\omega - b(t))/(1 + s)`, so a bias increment
    :math:`\\delta b_j` changes it by :math:`-\\delta b_j\\,\\varphi_m(t)/(1 + s_j)\\, e_j`
    (:math:`\\varphi_m` the knot's hat function, 1 for a constant bias); the attitude
    then changes by :math:`\\psi` of :func:`~bvpnav.error_models._attitude.propagate`
    (continuous limit :math:`\\psi(t) = -\\int_0^t C\\, b\\, ds`) and the acceleration by
    :math:`\\psi \\times C f`. Columns are exact first derivatives of the discrete
    integration; the re-integrated acceleration differs from the linearized one by
    :math:`O(\\delta^2)`.
    """

    interval: Any = None
    drift: Any = None
    units = "rad/s"
    default_step_scale = 1e-3

    def validate(self) -> None:
        object.__setattr__(self, "interval", _positive(self.interval, "GyroBias: interval (s)"))
        object.__setattr__(self, "drift", _positive(self.drift, "GyroBias: drift (rad/s/sqrt(s))"))
        if self.drift is not None and self.interval is None:
            raise InputError("GyroBias: drift= needs interval= (the knot spacing in s); without it the "
                             "bias is constant")
        if self.bounds is not None:
            raise InputError("GyroBias: bounds are not supported; give sigma= (a prior on the total)")

    def _sel(self) -> tuple[int, ...]:
        return self._select_axes(_AXES, "body")

    def knots(self, data) -> np.ndarray | None:
        """Knot times in s (None for a constant bias)."""
        return None if self.interval is None else knot_times(data.t, self.interval)

    def _weights(self, data) -> np.ndarray:
        k = self.knots(data)
        return np.ones((data.n, 1)) if k is None else hat_weights(data.t, k)

    def names(self, data) -> list[str]:
        k = self.knots(data)
        if k is None:
            return [f"gyro_bias_{_AXES[i]}" for i in self._sel()]
        return [f"gyro_bias_{_AXES[i]}[{m}]" for i in self._sel() for m in range(k.size)]

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

    def extra_terms(self, model) -> list:
        if self.drift is None:
            return []
        from ..terms import Term

        data = model.data
        k = self.knots(data)
        m = k.size
        names = self.names(data)
        base = self.base(data)
        rows, labels = [], []
        for a, i in enumerate(self._sel()):
            P = model.params(names[a * m:(a + 1) * m])
            D = P.rows(np.arange(1, m)) - P.rows(np.arange(m - 1))
            b = base[a * m:(a + 1) * m]
            rows.append(D + (b[1:] - b[:-1]))
            labels += [f"{_AXES[i]}[{j}]->[{j + 1}]" for j in range(m - 1)]
        from ..model import Affine

        res = _relabel(Affine.vstack(rows), labels, "drift")
        sigma = np.tile(self.drift * np.sqrt(np.diff(k)), len(self._sel()))
        return [Term(label="random walk GyroBias", item=None, residual=res, mode="soft", kind="equality",
                     sigma=sigma, scaled_by_lam=False, units=self.units)]

    @classmethod
    def example(cls) -> GyroBias:
        return cls()
