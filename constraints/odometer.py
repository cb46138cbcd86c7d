r"""An odometer or wheel-speed sensor: the measured forward speed of a point of the vehicle."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from bvpnav.errors import InputError
from bvpnav.items import Item
from bvpnav.model import Affine, TimeLabels

from ._common import finite, times

__all__ = ["Odometer"]

_BODY = ("x", "y", "z")


@dataclass(frozen=True, kw_only=True, eq=False)
class Odometer(Item):
    r"""Measured speeds along a body axis at instants: an odometer or a wheel-speed sensor.

    The speed of the point ``lever`` of the vehicle along its body axis ``axis`` is
    ``speed`` at the times ``t``, up to the odometer's scale-factor error: add
    :class:`~bvpnav.error_models.OdometerScale` to the error model to estimate it
    (``sigma=`` its prior); without it the readings are taken as calibrated. Needs
    strapdown data (an attitude: :meth:`bvpnav.ImuData.from_gyro` or
    ``ImuData(t, specific_force=..., attitude=...)``), and gyro rates when the lever is
    not zero.

    Parameters
    ----------
    t : array_like of float
        Instants in s, inside the window.
    speed : array_like of float
        Measured speeds, m/s, one per instant, signed along ``axis`` (negative when
        reversing; unsigned wheel-speed readings fit a drive that never reverses).
    axis : {"x", "y", "z"}
        The body axis the odometer measures along (default ``"x"``, forward).
    lever : array_like (3,)
        Position of the measured point (the wheel's contact, the axle's middle) relative to
        the IMU in body axes, m (default the IMU itself).
    scaled : bool
        Whether the problem's :class:`~bvpnav.error_models.OdometerScale` applies to these
        readings (default True); False for speeds without a scale error (a GNSS receiver's
        speed over ground beside a wheel odometer whose scale is estimated).
    sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma``, ``huber`` and ``tol`` in m/s. The item
        needs ``sigma`` (soft, the usual case: the speed's noise), or ``mode="robust"``
        with ``sigma`` (wheel slip), ``mode="band"`` with ``tol``, or an explicit
        ``mode="hard"`` (noise-free data).

    Notes
    -----
    One row per instant:

    .. math:: \rho_k = u^T \left(C_k^T v(t_k) + \omega(t_k) \times \ell\right) - (1 + e)\,\hat s_k,

    with :math:`u` the body axis, :math:`C_k` the body-to-navigation attitude, :math:`v`
    the navigation-frame velocity, :math:`\omega` the body rate, :math:`\ell` the lever
    (:meth:`bvpnav.NavModel.body_velocity`) and :math:`1 + e = 1/(1 + k)` the gain of the
    odometer scale :math:`k` (:meth:`bvpnav.NavModel.speed_gain`; 1 without
    :class:`~bvpnav.error_models.OdometerScale`). The reading model
    :math:`\hat s = (1 + k)\, s + n` is bilinear in :math:`k` and the velocity; in the gain
    :math:`1 + e` it is affine, exactly, so the item needs no linearization. The residual is
    :math:`-(1 + e) n`: ``sigma`` weighs it as the reading's noise to within the scale
    error (2 % for a 2 % scale). The attitude is that of the current linearization point
    (re-integrated by the attitude loop when the error model estimates it).

    Examples
    --------
    A car accelerating straight along east at 0.5 m/s^2 (body x forward), its odometer
    reading 2 % high, with fixes at both ends: the scale is found exactly.

    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> import bvpnav
    >>> from bvpnav.constraints import Odometer, Position, Velocity
    >>> from bvpnav.error_models import OdometerScale
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> g = np.array([0.0, 0.0, -9.80665])
    >>> att = Rotation.identity(t.size)
    >>> data = bvpnav.ImuData(t, specific_force=np.tile([0.5, 0.0, 9.80665], (t.size, 1)), attitude=att,
    ...                       gravity=g, frame="enu")
    >>> tk = t[::10]
    >>> prob = bvpnav.NavigationProblem(data, error_model=OdometerScale()).add(
    ...     Position(t=[0.0, 10.0], value=[[0.0, 0.0, 0.0], [25.0, 0.0, 0.0]]),
    ...     Odometer(t=tk, speed=1.02 * 0.5 * tk, sigma=0.01))
    >>> print(f"scale error {prob.solve(solver='direct').error_params['odometer_scale']:.4f}")
    scale error 0.0200
    """

    t: Any
    speed: Any
    axis: str = "x"
    lever: Any = (0.0, 0.0, 0.0)
    scaled: bool = True
    units = "m/s"

    def __post_init__(self):
        if self.mode is None and self.sigma is None:
            raise InputError(f"{self.label}: give sigma= (m/s, the speed's noise: a soft item), or "
                             "mode='hard' for noise-free readings")
        super().__post_init__()

    def validate(self) -> None:
        label = self.label
        if self.axes is not None:
            raise InputError(f"{label}: axes={list(self.axes)!r}; an odometer reads the velocity on every "
                             "navigation axis through the attitude: drop axes= (axis= names the body axis "
                             "it measures along)")
        tt = times(self.t, label).ravel()
        s = finite(self.speed, label, "speed").ravel()
        if s.size != tt.size:
            raise InputError(f"{label}: speed has {s.size} values for {tt.size} instants t; give one speed "
                             "(m/s) per instant")
        if not isinstance(self.axis, str) or self.axis not in _BODY:
            raise InputError(f"{label}: axis={self.axis!r}; give one body axis among {list(_BODY)} "
                             "(\"x\": forward)")
        if not isinstance(self.scaled, bool | np.bool_):
            raise InputError(f"{label}: scaled={self.scaled!r}; give True (the problem's OdometerScale "
                             "applies) or False")
        lev = finite(self.lever, label, "lever").ravel()
        if lev.size != 3:
            raise InputError(f"{label}: lever={self.lever!r}; give three numbers (body x, y, z) in m")
        object.__setattr__(self, "t", tt)
        object.__setattr__(self, "speed", s)
        object.__setattr__(self, "lever", lev)
        object.__setattr__(self, "scaled", bool(self.scaled))

    def n_instants(self) -> int:
        return int(np.size(self.t))

    @property
    def heading_information(self) -> bool:
        r"""A speed says nothing about the heading or the yaw rate: False, unless the lever puts
        a body rate into the reading (:math:`(\omega \times \ell) \cdot u = \omega \cdot (\ell
        \times u)`, e.g. a wheel beside the IMU feels the yaw rate), which the attitude loop's hold
        of the yaw-rate gyro bias then leaves free."""
        u = np.eye(3)[_BODY.index(self.axis)]
        return bool(np.any(np.cross(self.lever, u)))

    @classmethod
    def example(cls) -> Odometer:
        """A valid instance for the window of :meth:`example_model`."""
        return cls(t=[2.0, 4.0, 6.0, 8.0], speed=[1.0, 2.0, 2.5, 2.0], sigma=0.05)

    @classmethod
    def example_model(cls):
        """Strapdown data on [0, 10] s (101 samples) with gyro rates, turning about z: the
        model the contract check compiles :meth:`example` for."""
        from bvpnav.imu import ImuData
        from bvpnav.model import NavModel

        t = np.linspace(0.0, 10.0, 101)
        f = np.column_stack([0.5 * np.cos(0.3 * t), 0.2 * np.sin(t), np.full(t.size, 9.80665)])
        w = np.column_stack([0.01 * np.sin(t), 0.02 * np.cos(t), 0.1 + 0.05 * np.sin(0.5 * t)])
        return NavModel(ImuData.from_gyro(t, f, w))

    def compile(self, model) -> Affine:
        what = f"{self.identify()}(t=...)"
        vb = model.body_velocity(self.t, self.axis, self.lever, what)
        if not self.scaled:
            return Affine(vb.A, vb.c - self.speed, TimeLabels(f"speed_{self.axis}", [""], self.t))
        gain = model.speed_gain(what)
        S = sp.csr_matrix(self.speed.reshape(-1, 1))
        A = (vb.A - S @ gain.A).tocsr()
        c = vb.c - self.speed * float(gain.c[0])
        return Affine(A, c, TimeLabels(f"odometer_{self.axis}", [""], self.t))

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"u^T (C_k^T v(t_k) + \omega_k \times \ell) - (1 + e)\,\hat s_k = 0"

    def math(self) -> str:
        return (f"u_{self.axis}^T (C^T v(t_k) + omega x lever) - (1 + e) s_k = 0 at {np.size(self.t)} "
                "instants (e: odometer gain correction)")
