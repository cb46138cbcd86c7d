"""Constant scale-factor error per sensor axis."""

from __future__ import annotations

from dataclasses import dataclass

from ._base import Param, SensorErrorModel, sensor_axes

__all__ = ["ScaleFactor"]


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class ScaleFactor(SensorErrorModel):
    """Scale-factor error of each accelerometer axis, dimensionless.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Sensor axes; default all.
    prior, sigma, bounds
        Optional soft prior and hard bounds (dimensionless).

    Notes
    -----
    Reported as ``scale_<axis>`` = :math:`s` with :math:`\\hat f = (1 + s) f + \\dots`
    (0.01 means the sensor reads 1 % high). Internally :math:`k = E_{ii}` multiplies
    the measured output, :math:`f = (1 + k)\\hat f + \\dots`, which is exact for
    :math:`k = 1/(1+s) - 1`; the column is :math:`C_i e_k \\hat f_{i,k}` (the paper's
    :math:`p_{kl11}`, eq. 32-33).
    """

    units = "1"

    def params(self, data) -> list[Param]:
        ax = sensor_axes(data)
        return [Param(f"scale_{ax[i]}", "scale", i, i) for i in self._select_axes(ax, "sensor")]
