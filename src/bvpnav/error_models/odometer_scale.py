r"""The scale-factor error of an odometer (wheel speed): one dimensionless parameter."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pandas as pd

from ..errors import InputError
from ..model import Affine
from ._base import _Installed, _per_param, _series

__all__ = ["OdometerScale"]

#: The parameter's name (reported by the solution, ``error_params["odometer_scale"]``).
NAME = "odometer_scale"


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class OdometerScale(_Installed):
    r"""Scale-factor error of an odometer or wheel-speed sensor, dimensionless.

    The odometer reads :math:`\hat s = (1 + k)\, s` with :math:`s` the true forward speed
    (a worn tyre, a wrong wheel radius: ``k = 0.02`` reads 2 % high). The
    :class:`~bvpnav.constraints.Odometer` items of the problem read their correction from
    this model (through :meth:`bvpnav.NavModel.speed_gain`); without it their scale is taken
    as exact.

    Parameters
    ----------
    sigma : float, optional
        Prior standard deviation of ``k`` (dimensionless, e.g. 0.05 for 5 %); a soft prior
        :math:`((k - k_0)/\sigma)^2`, not scaled by ``lam``.
    prior : float, optional
        Prior value :math:`k_0` (default 0; used with ``sigma``).
    bounds : (float, float), optional
        Hard bounds on ``k`` (each > -1).

    Notes
    -----
    The product of the unknown scale and the unknown velocity is not linear; the model is
    reparametrised so that it is, exactly (as :class:`~bvpnav.error_models.ScaleFactor`
    does for the accelerometer): the internal parameter is the gain correction
    :math:`e = 1/(1 + k) - 1`, so the true speed is :math:`s = (1 + e)\hat s`, linear in
    :math:`e`, and the odometer's residual :math:`u^T v_b - (1 + e)\hat s` is affine in the
    unknowns: no linearization and no outer loop. Reported is
    :math:`k = 1/(1 + e) - 1`. The prior and bound rows are
    :math:`(k - v)(1 + e) = -e - v(1 + e)`, exact and linear. The parameter does not act
    on the accelerations (its columns ``G`` are zero): only odometer items observe it,
    together with information that fixes the distance travelled (position fixes).

    Examples
    --------
    >>> from bvpnav.error_models import OdometerScale
    >>> OdometerScale(sigma=0.05)
    OdometerScale(sigma=0.05)
    """

    units = "1"
    NAMES: ClassVar[tuple[str, ...]] = (NAME,)
    #: A model of another sensor than the IMU: its prior does not stop a sensor grade from
    #: filling in the IMU models' priors (:class:`bvpnav.NavigationProblem`'s ``grade``).
    other_sensor = True
    #: Added to the error when nothing determines the scale.
    observability_hint = ("The odometer scale is observed only by Odometer items (scaled=True), beside "
                          "information that fixes the distance travelled (position fixes): add them, or "
                          "drop OdometerScale.")
    #: What the solve's plausibility check judges the estimate as.
    plausibility_kind = "odometer_scale"

    def validate(self) -> None:
        label = type(self).__name__
        if self.axes is not None:
            raise InputError(f"{label}: axes={self.axes!r}; an odometer scale has no axes (it scales the "
                             "measured speed): drop axes=")
        for what, v in (("sigma", self.sigma), ("prior", self.prior)):
            if v is not None and np.size(v) != 1:
                raise InputError(f"{label}: {what}={np.asarray(v).tolist()!r}; give one number (there is one "
                                 "scale factor)")
        if self.prior is not None and not float(np.ravel(self.prior)[0]) > -1.0:
            raise InputError(f"{label}: prior={float(np.ravel(self.prior)[0])!r}; a scale error must be > -1 "
                             "(-1 would be an odometer reading zero)")
        if self.bounds is not None:
            lo, hi = (np.ravel(b) for b in self.bounds)
            if lo.size != 1 or hi.size != 1 or not float(lo[0]) > -1.0:
                raise InputError(f"{label}: bounds={self.bounds!r}; give (lo, hi) with -1 < lo < hi")

    def speed_gain(self, model) -> Affine:
        """The gain ``1 + e`` that turns a measured speed into the true one, one row
        (read through :meth:`bvpnav.NavModel.speed_gain`)."""
        return model.params([NAME]) + 1.0

    def report(self, l, model) -> pd.Series:
        e = float(np.ravel(np.asarray(l, dtype=float))[0])
        with np.errstate(divide="ignore"):
            k = 1.0 / (1.0 + e) - 1.0 if 1.0 + e != 0.0 else np.inf
        return _series(np.array([k]), [NAME], self.units)

    def physical_rows(self, model, value) -> Affine:
        r"""Rows :math:`(k - v)(1 + e) = -e - v (1 + e)`, exact and linear in ``e``."""
        v = float(_per_param(value, 1, f"{type(self).__name__}: value")[0])
        return model.params([NAME]) * (-(1.0 + v)) - v

    @classmethod
    def example(cls) -> OdometerScale:
        return cls(sigma=0.05)

    @classmethod
    def example_data(cls):
        """Strapdown data on [0, 10] s (101 samples), driving forward along a turning path:
        the data :func:`bvpnav.testing.check_error_model` checks the model on."""
        from scipy.spatial.transform import Rotation

        from ..imu import ImuData

        t = np.linspace(0.0, 10.0, 101)
        yaw = 0.3 * np.sin(0.4 * t)
        att = Rotation.from_euler("z", yaw[:, None])
        acc = np.column_stack([1.0 + 0.2 * np.cos(t), 0.5 * np.sin(0.7 * t), np.zeros(t.size)])
        g = np.array([0.0, 0.0, -9.80665])
        return ImuData(t, specific_force=att.inv().apply(acc - g), attitude=att, gravity=g, frame="enu")

    @staticmethod
    def check_items(model, values: dict, t, velocities) -> list:
        """The information that observes the parameter on check data
        (:func:`bvpnav.testing.check_error_model`): an odometer along body x at the instants
        ``t`` (s) of the true navigation-frame ``velocities`` (m/s), read by a sensor whose
        internal parameter is ``values["odometer_scale"]``."""
        # by its registered name: the constraints sit above the error models
        from ..items import item_class

        Odometer = item_class("odometer")
        t = np.asarray(t, dtype=float)   # sample times of the check data
        k = np.clip(np.searchsorted(model.grid.t, t), 0, model.N - 1)
        C = model.data.attitude[k].as_matrix()
        forward = np.einsum("kij,ki->kj", C, np.asarray(velocities, dtype=float))[:, 0]
        return [Odometer(t=t, speed=forward / (1.0 + values[NAME]), mode="hard", name="check odometer")]
