"""Constant scale-factor error per sensor axis."""

from __future__ import annotations

from dataclasses import dataclass

from ._base import Param, SensorErrorModel, sensor_axes

__all__ = ["ScaleFactor"]


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class ScaleFactor(SensorErrorModel):
    r"""Scale-factor error of each accelerometer axis, dimensionless.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Sensor axes; default all.
    prior, sigma, bounds
        Optional soft prior and hard bounds (dimensionless).

    Notes
    -----
    Reported as ``scale_<axis>`` = :math:`s` with :math:`\hat f = (1 + s) f + \dots`
    (0.01 means the sensor reads 1 % high). Internally :math:`k = E_{ii}` multiplies
    the measured output, :math:`f = (1 + k)\hat f + \dots`, which is exact for
    :math:`k = 1/(1+s) - 1`; the column is :math:`C_i e_k \hat f_{i,k}` (the paper's
    :math:`p_{kl11}`, eq. 32-33).

    Examples
    --------
    An accelerometer that reads 2 % high, with a 0.1 m/s^2 bias, on 401 samples (the linear
    elements' error falls as the square of the step: 0.0191 with 101 samples):

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, Velocity
    >>> t = np.linspace(0.0, 10.0, 401)
    >>> tk = [0.0, 5.0, 10.0]
    >>> known = [Position(t=tk, value=0.5 * np.sin(tk)), Velocity(t=0.0, value=0.5)]  # r = 0.5 sin t (m)
    >>> from bvpnav.error_models import Bias, ScaleFactor
    >>> data = bvpnav.ImuData(t=t, acc=1.02 * -0.5 * np.sin(t) + 0.1)
    >>> prob = bvpnav.NavigationProblem(data, error_model=ScaleFactor() + Bias(), items=known)
    >>> est = prob.solve(solver="direct").error_params
    >>> print(f"scale {est['scale_x']:.3f}, bias {est['bias_x']:.3f} m/s^2")
    scale 0.020, bias 0.100 m/s^2
    """

    #: What the solve's plausibility check judges its estimates as (the limits are in
    #: :mod:`bvpnav.solve.plausibility`).
    plausibility_kind = "scale"

    units = "1"

    def params(self, data) -> list[Param]:
        ax = sensor_axes(data)
        return [Param(f"scale_{ax[i]}", "scale", i, i) for i in self._select_axes(ax, "sensor")]
