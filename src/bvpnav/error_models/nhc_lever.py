r"""Where on the vehicle the non-holonomic constraint holds: the no-slip point's offset from the IMU, m."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ._base import _Installed

__all__ = ["NhcLever"]

#: The parameters' names (``error_params["nhc_lever_x"]``, ...), body axes.
NAMES = ("nhc_lever_x", "nhc_lever_y", "nhc_lever_z")


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class NhcLever(_Installed):
    r"""The point of the vehicle that does not slide, relative to the IMU in body axes, m (estimated).

    A car's lateral velocity is zero at the middle of its rear axle (the no-slip point of a
    car whose front wheels steer), not at the IMU: a point :math:`d` m ahead of the axle moves
    sideways at :math:`d` times the yaw rate (0.3 m/s for 1 m at 0.3 rad/s, three times a
    typical non-holonomic sigma). Where the IMU sits relative to the axle is rarely in the
    data; with ``NonHolonomic(lever="estimated")`` the constraint acts at the point these
    three parameters give, estimated with the navigation solution.

    Parameters
    ----------
    sigma : float or array_like of 3
        Prior standard deviation, m (one value, or one per body axis x, y, z), e.g. 2.0: a
        car's IMU is within about 2 m of its rear axle. Needed in practice: the offset is
        observed only while the vehicle turns (through the body rates), and a component
        along a rate that never changes (the lateral offset on a flat road) is not observed.
    prior : array_like of 3, optional
        Prior value, m (default zero: the IMU itself). Used with ``sigma``.
    bounds : (lo, hi), optional
        Hard limits in m.

    Notes
    -----
    Parameters ``nhc_lever_x``, ``nhc_lever_y``, ``nhc_lever_z``: the offset :math:`\ell`
    of the no-slip point from the IMU in body axes (x forward, y left, z up on a car; an
    IMU 1.2 m ahead of the rear axle has :math:`\ell_x = -1.2`). The vehicle items built
    with ``lever="estimated"`` (:class:`~bvpnav.constraints.NonHolonomic`,
    :class:`~bvpnav.constraints.ForwardMotion`) read them through
    :meth:`bvpnav.NavModel.vehicle_point_velocity`: the body-frame velocity of the point is

    .. math:: v_b = C^T v_n + \omega \times \ell ,

    and for the body rates :math:`\omega` at the current linearization point the term
    :math:`\omega \times \ell = [\omega\times]\,\ell` is linear in :math:`\ell`, with no
    attitude in it. The columns are zero (the offset does not change the accelerations).

    Examples
    --------
    >>> from bvpnav.error_models import NhcLever
    >>> NhcLever(sigma=2.0).names(NhcLever.example_data())
    ['nhc_lever_x', 'nhc_lever_y', 'nhc_lever_z']
    """

    units = "m"
    #: The role the vehicle items look the component up by (:meth:`bvpnav.NavModel.vehicle_point_velocity`).
    provides: ClassVar[str] = "nhc_lever"
    #: A model of the installation, not of the IMU's errors: its prior does not stop a sensor
    #: grade from filling in the IMU models' priors.
    other_sensor = True

    NAMES: ClassVar[tuple[str, ...]] = NAMES
    NO_AXES: ClassVar[str] = ("the point has three body-frame components (give a tight sigma on a component "
                              "you know, e.g. sigma=[2.0, 0.3, 1.0])")
    COUNTS: ClassVar[tuple[tuple[int, ...], str]] = ((1, 3), "one or three (x, y, z body axes, m)")

    @classmethod
    def example(cls) -> NhcLever:
        return cls(sigma=2.0)

    @staticmethod
    def example_data():
        """Strapdown data of a car driving a winding, undulating road (:func:`_car_drive`)."""
        return _car_drive(np.array([-1.2, 0.0, -0.5]))[0]

    @classmethod
    def example_recovery(cls, problem):
        """``(problem, truth, solve options)`` built with ``problem`` (the problem class, given
        by the contract check): a noise-free car whose IMU sits 1.2 m ahead of the rear axle,
        0.3 m right of its middle and 0.5 m above it (no-slip point at ``(-1.2, 0.3, -0.5)``
        m from the IMU), fixes every 2 s and hard ``NonHolonomic(lever="estimated")`` rows;
        the solve must find the offset (m) to 1e-6."""
        from ..items import item_class

        Position, NonHolonomic = item_class("position"), item_class("non_holonomic")
        lever = np.array([-1.2, 0.3, -0.5])
        data, pos, _ = _car_drive(lever)
        k = np.arange(0, data.n, 20)
        prob = problem(data, error_model=cls(), grade=None)
        prob.add(Position(t=data.t[k], value=pos[k], name="fixes"),
                 NonHolonomic(mode="hard", lever="estimated", rate=None, name="non-holonomic"))
        return prob, dict(zip(NAMES, lever.tolist(), strict=True)), {"solver": "direct"}


def _car_drive(lever: np.ndarray, duration: float = 20.0, rate: float = 10.0, slip=None, slopes=None):
    r"""A car on a winding, undulating road whose point ``lever`` (m, body axes from the IMU)
    moves along the body x axis, noise-free: the data, and the IMU's positions and velocities
    at the samples. ``slip`` (per sample, dimensionless; default none): the point slides
    sideways at ``-slip`` times its forward speed instead (``slip_drive`` of
    :mod:`bvpnav.error_models.side_slip`). ``slopes`` (:math:`(s_y, s_z)`, default none): the
    IMU is mounted with these slopes (:mod:`bvpnav.error_models.mounting`), so the point moves
    along :math:`(1, s_y, -s_z)` in the IMU's axes, at the forward speed times that vector.

    The yaw rate :math:`0.3 \sin(0.4 t)`, roll rate :math:`0.05 \cos(0.9 t)` and pitch rate
    :math:`0.04 \sin(0.7 t + 0.3)` rad/s are the gyro samples; the attitude is the one
    :meth:`bvpnav.ImuData.from_gyro` integrates from them, and the point's forward speed is
    :math:`8 + 2 \sin(0.3 t)` m/s. The IMU's velocity at sample :math:`k` is
    :math:`v_k = C_k (s_k e_x - \omega_k \times \ell)`; the accelerations at the samples are
    chosen so that, linear between samples as the FEM takes them, they integrate to exactly
    these velocities (:math:`v_{k+1} - v_k = h (a_k + a_{k+1}) / 2`), so the FEM's nodal
    positions and velocities are the returned ones to rounding and the constraint holds
    exactly at every sample.
    """
    from scipy.spatial.transform import Rotation

    from ..imu import ImuData

    t = np.linspace(0.0, duration, int(round(duration * rate)) + 1)
    h = float(t[1] - t[0])
    w = np.column_stack([0.05 * np.cos(0.9 * t), 0.04 * np.sin(0.7 * t + 0.3), 0.3 * np.sin(0.4 * t)])
    g = np.array([0.0, 0.0, -9.80665])
    att0 = Rotation.from_euler("ZYX", [0.7, 0.02, -0.01])
    first = ImuData.from_gyro(t, np.tile(-g, (t.size, 1)), w, initial_attitude=att0, gravity=g, checks=False)
    C = first.attitude.as_matrix()
    s = 8.0 + 2.0 * np.sin(0.3 * t)
    side = np.zeros(t.size) if slip is None else -np.asarray(slip, dtype=float) * s
    sy, sz = (0.0, 0.0) if slopes is None else (float(slopes[0]), float(slopes[1]))
    vb = np.column_stack([s, side + sy * s, -sz * s]) - np.cross(w, lever)
    v = np.einsum("kij,kj->ki", C, vb)
    acc = np.empty_like(v)
    dv = np.gradient(v, t, axis=0, edge_order=2)
    acc[0] = dv[0]
    for k in range(t.size - 1):                  # trapezoid: exact for accelerations linear between samples
        acc[k + 1] = 2.0 * (v[k + 1] - v[k]) / h - acc[k]
    pos = np.zeros_like(v)
    for k in range(t.size - 1):
        pos[k + 1] = pos[k] + h * v[k] + h * h * (2.0 * acc[k] + acc[k + 1]) / 6.0
    f = np.einsum("kji,kj->ki", C, acc - g)      # C^T (a - g): body-frame specific force
    data = ImuData.from_gyro(t, f, w, initial_attitude=att0, gravity=g, checks=False)
    return data, pos, v
