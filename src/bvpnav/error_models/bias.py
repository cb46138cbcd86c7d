"""Constant accelerometer bias per sensor axis."""

from __future__ import annotations

from dataclasses import dataclass

from ._base import Param, SensorErrorModel, sensor_axes

__all__ = ["Bias"]


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class Bias(SensorErrorModel):
    """Constant bias of each accelerometer axis, m/s^2.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Sensor axes (body ``x, y, z`` for strapdown data, else the navigation axes);
        default all.
    prior, sigma, bounds
        Optional soft prior and hard bounds in m/s^2 (see
        :class:`~bvpnav.error_models.ErrorModel`).

    Notes
    -----
    Reported as ``bias_<axis>`` in m/s^2 with the sensor's sign: the sensor reads
    :math:`\\hat f = D f + b`, so a positive bias means it reads high. Internally the
    correction is :math:`f = (I + E)\\hat f + \\beta` with :math:`b = -(I + E)^{-1}\\beta`;
    the column of :math:`\\beta_k` is the sensor axis in the navigation frame,
    :math:`C_i e_k` (the 2010 paper's :math:`p_{kl1}` vectors, eq. 33, up to ``-M``).
    """

    units = "m/s^2"

    def params(self, data) -> list[Param]:
        ax = sensor_axes(data)
        return [Param(f"bias_{ax[i]}", "bias", i) for i in self._select_axes(ax, "sensor")]
