"""Scale-factor error of each gyro axis (dimensionless)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ._attitude import AttitudeErrorModel, _check_strapdown_gyro, at_point

__all__ = ["GyroScaleFactor"]

@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class GyroScaleFactor(AttitudeErrorModel):
    r"""Scale-factor error of each gyro axis, dimensionless (0.01 = reads 1 % high).

    Parameters
    ----------
    axes : str or sequence of str, optional
        Body axes; default all.
    sigma, prior : float or array_like, optional
        Soft prior on the total scale factor (dimensionless).

    Notes
    -----
    The gyro reads :math:`\hat\omega_j = (1 + s_j)\omega_j + b_j`, so the corrected rate
    is :math:`\omega_j = (\hat\omega_j - b_j)/(1 + s_j)` and an increment
    :math:`\delta s_j` changes it by :math:`-\omega_j\,\delta s_j/(1 + s_j)`. The
    attitude and acceleration follow as for :class:`GyroBias`. A scale factor is
    identifiable only on an axis that turns enough (a heading error of
    :math:`s_z \Delta\psi` after a total turn :math:`\Delta\psi`).

    Examples
    --------
    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> f = np.tile([0.0, 0.0, 9.80665], (11, 1))  # at rest, z up (m/s^2)
    >>> w = np.tile([0.0, 0.0, 0.1], (11, 1))      # turning about z at 0.1 rad/s
    >>> data = bvpnav.ImuData.from_gyro(t, f, w)
    >>> from bvpnav.error_models import GyroScaleFactor
    >>> model = GyroScaleFactor(axes="z")  # only the axis that turns
    >>> model.names(data), model.columns(data).shape
    (['gyro_scale_z'], (11, 3, 1))
    """

    #: What the solve's plausibility check judges its estimates as (the limits are in
    #: :mod:`bvpnav.solve.plausibility`).
    plausibility_kind = "gyro_scale"

    units = ""
    default_step_scale = 1e-2

    def validate(self) -> None:
        if self.bounds is not None:
            raise InputError("GyroScaleFactor: bounds are not supported; give sigma= (a prior on the total)")

    def names(self, data) -> list[str]:
        return [f"gyro_scale_{self.AXES[i]}" for i in self._sel()]

    def rate_columns(self, data) -> np.ndarray:
        _check_strapdown_gyro(data, "GyroScaleFactor")
        p = at_point(data)
        sel = self._sel()
        out = np.zeros((data.n, 3, len(sel)))
        for a, i in enumerate(sel):
            out[:, i, a] = -p.rates[:, i] / (1.0 + p.scale[i])
        return out

    def apply(self, values, parts, data) -> None:
        for a, i in enumerate(self._sel()):
            parts["scale"][i] = values[a]
