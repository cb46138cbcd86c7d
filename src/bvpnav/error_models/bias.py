"""Accelerometer bias per sensor axis: constant, or drifting (a random walk at knots)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ._attitude import hat_weights, knot_times, positive_option, random_walk_term
from ._base import Param, SensorErrorModel, _relabel, _series, sensor_axes, sensor_frame

__all__ = ["Bias"]


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class Bias(SensorErrorModel):
    r"""Bias of each accelerometer axis, m/s^2: constant, or drifting as a random walk.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Sensor axes (body ``x, y, z`` for strapdown data, else the navigation axes);
        default all.
    prior, sigma, bounds
        Optional soft prior and hard bounds in m/s^2 (see
        :class:`~bvpnav.error_models.ErrorModel`); time-varying: on every knot's value,
        except that with ``drift`` the prior is on the first knot only (the random walk
        carries it on, as for :class:`GyroBias`).
    interval : float, optional
        Time-varying bias: values at knots about ``interval`` s apart
        (:func:`bvpnav.error_models._attitude.knot_times`), linear between them.
    drift : float, optional
        Random-walk density of the bias, m/s^2/sqrt(s) (a datasheet's bias random walk,
        or a factor graph's accelerometer bias random-walk sigma): the prior
        :math:`(b_{m+1} - b_m) \sim N(0, \sigma_d^2\, \Delta t_m)`. Needs ``interval``.

    Notes
    -----
    Reported as ``bias_<axis>`` (constant) or ``bias_<axis>[m]`` (knot ``m``) in m/s^2
    with the sensor's sign: the sensor reads :math:`\hat f = D f + b`, so a positive bias
    means it reads high. Internally the correction is :math:`f = (I + E)\hat f + \beta`
    with :math:`b = -(I + E)^{-1}\beta`; the column of :math:`\beta_k` is the sensor
    axis in the navigation frame, :math:`C_i e_k` (the 2010 paper's :math:`p_{kl1}`
    vectors, eq. 33, up to ``-M``), times the knot's hat function :math:`\varphi_m(t_i)`
    when time-varying. The knot values are reported exactly as
    :math:`b_m = -(I + E)^{-1}\beta_m`; the random-walk prior is on
    :math:`-(\beta_{m+1} - \beta_m)`, which is :math:`b_{m+1} - b_m` without a scale
    factor and to first order in it with one.

    Examples
    --------
    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, Velocity
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> tk = [0.0, 5.0, 10.0]
    >>> known = [Position(t=tk, value=0.5 * np.sin(tk)), Velocity(t=0.0, value=0.5)]  # r = 0.5 sin t (m)
    >>> from bvpnav.error_models import Bias
    >>> data = bvpnav.ImuData(t=t, acc=-0.5 * np.sin(t) + 0.1)  # reads 0.1 m/s^2 high
    >>> sol = bvpnav.NavigationProblem(data, error_model=Bias(), items=known).solve(solver="direct")
    >>> print(f"bias {sol.error_params['bias_x']:.3f} m/s^2")
    bias 0.100 m/s^2
    """

    #: What the solve's plausibility check judges its estimates as (the limits are in
    #: :mod:`bvpnav.solve.plausibility`).
    plausibility_kind = "acc_bias"

    interval: Any = None
    drift: Any = None
    units = "m/s^2"

    def validate(self) -> None:
        object.__setattr__(self, "interval", positive_option(self.interval, "Bias: interval (s)"))
        object.__setattr__(self, "drift", positive_option(self.drift, "Bias: drift (m/s^2/sqrt(s))"))
        if self.drift is not None and self.interval is None:
            raise InputError("Bias: drift= needs interval= (the knot spacing in s); without it the bias is "
                             "constant")

    @property
    def time_varying(self) -> bool:
        """True with ``interval``: one value per knot."""
        return self.interval is not None

    def knots(self, data) -> np.ndarray | None:
        """Knot times in s (None for a constant bias)."""
        return None if self.interval is None else knot_times(data.t, self.interval)

    def params(self, data) -> list[Param]:
        ax = sensor_axes(data)
        sel = self._select_axes(ax, "sensor")
        if self.interval is None:
            return [Param(f"bias_{ax[i]}", "bias", i) for i in sel]
        m = self.knots(data).size
        return [Param(f"bias_{ax[i]}[{k}]", "bias_knot", i, k) for i in sel for k in range(m)]

    # ----------------------------------------------------- time-varying parts
    def columns(self, data) -> np.ndarray:
        if self.interval is None:
            return super().columns(data)
        C = sensor_frame(data)
        W = hat_weights(data.t, self.knots(data))
        return np.stack([C[:, :, p.i] * W[:, p.j, None] for p in self.params(data)], axis=2)

    def knot_values(self, l, corr, data) -> np.ndarray:
        """Physical knot values ``b_m = -D beta_m`` given the other sensor models' correction."""
        ps = self.params(data)
        ns = len(sensor_axes(data))
        m = self.knots(data).size
        beta = np.zeros((m, ns))
        for p, v in zip(ps, np.asarray(l, dtype=float), strict=True):
            beta[p.j, p.i] = v
        D = corr.D if corr is not None else np.eye(ns)
        return np.array([-(D[p.i] @ beta[p.j]) for p in ps])

    def report(self, l, model):
        if self.interval is None:
            return super().report(l, model)
        return _series(self.knot_values(l, None, model.data), self.names(model.data), self.units)

    def terms(self, model) -> list:
        if self.drift is None:
            return super().terms(model)
        import dataclasses

        from ..terms import Term
        from ._base import _per_param

        # the prior on the first knot only (the random walk carries it on; see GyroBias)
        out = dataclasses.replace(self, sigma=None, prior=None, drift=None).terms(model)
        if self.sigma is not None:
            names = self.names(model.data)
            q = len(names)
            m = self.knots(model.data).size
            p0 = np.zeros(q) if self.prior is None else _per_param(self.prior, q, "Bias: prior")
            first = np.arange(0, q, m)
            rows = self.physical_rows(model, p0).rows(first)
            out.append(Term(label=f"prior Bias[{', '.join(names[k] for k in first)}]", item=None,
                            residual=_relabel(rows, [names[k] for k in first], "prior"), mode="soft",
                            kind="equality", sigma=_per_param(self.sigma, q, "Bias: sigma")[first],
                            scaled_by_lam=False, units=self.units))

        out.append(random_walk_term(model, self.names(model.data), self.knots(model.data), self.drift,
                                    self.units, "random walk Bias", sign=-1.0))
        return out
