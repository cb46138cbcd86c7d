r"""The IMU's mounting misalignment against the vehicle: yaw and pitch boresight, read by NonHolonomic."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pandas as pd

from ._base import _Installed, _series

__all__ = ["Mounting"]

#: The parameters' names (``error_params["mounting_yaw"]``, ``["mounting_pitch"]``).
NAMES = ("mounting_yaw", "mounting_pitch")


def mounting_angles(slopes) -> np.ndarray:
    r"""Yaw and pitch (rad) of the vehicle's forward axis in body axes ``(1, s_y, -s_z)``.

    Parameters
    ----------
    slopes : array_like (2,)
        The internal parameters :math:`(s_y, s_z)`, dimensionless.

    Returns
    -------
    numpy.ndarray (2,)
        :math:`\psi = \arctan s_y`, :math:`\theta = \arctan(s_z / \sqrt{1 + s_y^2})`, rad.
    """
    sy, sz = (float(v) for v in np.ravel(np.asarray(slopes, dtype=float))[:2])
    return np.array([np.arctan(sy), np.arctan(sz / np.hypot(1.0, sy))])


def mounting_slopes(yaw: float, pitch: float) -> np.ndarray:
    r"""The internal parameters :math:`(s_y, s_z) = (\tan\psi, \tan\theta / \cos\psi)` of a
    yaw ``psi`` and pitch ``theta`` (rad): the inverse of :func:`mounting_angles`."""
    return np.array([np.tan(yaw), np.tan(pitch) / np.cos(yaw)])


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class Mounting(_Installed):
    r"""Yaw and pitch of the vehicle's forward axis in the IMU's body frame, rad (estimated).

    An IMU is never bolted in exactly along the car: a boresight of a fraction of a degree
    turns the forward speed into a false lateral or vertical velocity (0.5 deg at 15 m/s:
    0.13 m/s), which a :class:`~bvpnav.constraints.NonHolonomic` item would then force to
    zero by turning the attitude. With ``NonHolonomic(mounting="estimated")`` the item
    constrains the velocity across the *vehicle's* axes instead, through these two angles.

    Parameters
    ----------
    sigma : float or array_like of 2
        Prior standard deviation, rad (one value, or yaw and pitch), e.g. 0.02 for an IMU
        mounted by eye. Needed in practice: the angles are observed only through the
        accelerations (a yaw boresight rotates the forward acceleration sideways), weakly.
    prior : array_like of 2, optional
        Prior value, rad (default zero). Used with ``sigma``.
    bounds : (lo, hi), optional
        Hard limits on the internal slopes (see Notes).

    Notes
    -----
    The vehicle's forward axis in body axes is :math:`u = R_z(\psi) R_y(\theta)\, e_x
    \propto (1, s_y, -s_z)` with the internal parameters (the slopes)
    :math:`s_y = \tan\psi`, :math:`s_z = \tan\theta / \cos\psi`; the point of the vehicle
    that does not slide moves along :math:`u`, so its body-frame velocity :math:`v`
    satisfies

    .. math:: v_y - s_y\, v_x = 0, \qquad v_z + s_z\, v_x = 0,

    the rows of :meth:`bvpnav.NavModel.mounting_velocity`, bilinear in the slopes and the
    velocity: they take :math:`v_x` from the attitude loop's linearization point (its last
    evaluation), so they are exact at the loop's answer. Reported are the angles
    :math:`\psi = \arctan s_y` and :math:`\theta = \arctan(s_z/\sqrt{1 + s_y^2})`; the
    prior and bounds act on the slopes (the angles to within :math:`\theta^3/3`: 2e-7 rad at
    0.5 deg). A roll about the forward axis does not move :math:`u` and is not modelled.
    The columns are zero (the mounting does not change the accelerations).

    Examples
    --------
    >>> from bvpnav.error_models import Mounting
    >>> Mounting(sigma=0.02).names(Mounting.example_data())
    ['mounting_yaw', 'mounting_pitch']
    """

    units = "rad"
    #: The role the vehicle items look the component up by (:meth:`bvpnav.NavModel.mounting_velocity`).
    provides: ClassVar[str] = "mounting"
    #: A model of the installation, not of the IMU's errors: its prior does not stop a sensor
    #: grade from filling in the IMU models' priors.
    other_sensor = True

    NAMES: ClassVar[tuple[str, ...]] = NAMES
    NO_AXES: ClassVar[str] = ("the mounting has a yaw and a pitch (give one sigma per angle to hold one of "
                              "them)")
    COUNTS: ClassVar[tuple[tuple[int, ...], str]] = ((1, 2), "one or two (yaw, pitch, rad)")

    def report(self, l, model) -> pd.Series:
        """The yaw and pitch, rad, from the internal slopes (:func:`mounting_angles`)."""
        return _series(mounting_angles(l), list(NAMES), self.units)

    @classmethod
    def example(cls) -> Mounting:
        return cls(sigma=0.05)

    @staticmethod
    def example_data():
        """Strapdown data of a car driving straight at a constant attitude, speeding up."""
        return _straight_drive(np.array([0.0, 0.0]))[0]

    @classmethod
    def example_recovery(cls, problem):
        """``(problem, truth, solve options)`` built with ``problem`` (the problem class, given
        by the contract check): a noise-free straight drive whose IMU is mounted 0.6 deg to
        the left and 0.4 deg nose down, with position fixes at both ends, the start velocity
        and hard ``NonHolonomic(mounting="estimated")`` rows; the attitude loop (an initial
        attitude error with a prior) iterates the rows, and the solve must find the angles (rad)
        to 1e-6."""
        from ..items import item_class
        from .attitude_error import AttitudeError

        Position, Velocity, NonHolonomic = (item_class(n) for n in ("position", "velocity",
                                                                    "non_holonomic"))
        yaw, pitch = np.radians(0.6), np.radians(-0.4)
        data, pos, vel = _straight_drive(mounting_slopes(yaw, pitch))
        prob = problem(data, error_model=AttitudeError(sigma=0.01) + cls(), grade=None)
        prob.add(Position(t=data.t[[0, -1]], value=pos[[0, -1]], name="fixes"),
                 Velocity(t=data.t[0], value=vel[0], name="start velocity"),
                 NonHolonomic(mode="hard", rate=2.0, mounting="estimated", name="non-holonomic"))
        return prob, dict(zip(NAMES, (yaw, pitch), strict=True)), {"solver": "direct"}


def _straight_drive(slopes: np.ndarray):
    r"""A car driving straight on a slope at a constant attitude for 10 s, its speed
    :math:`2 + 0.5 t + 0.05 t^2` m/s, its IMU mounted with the internal slopes ``slopes``:
    the data (zero gyro rates, so the attitude stays exactly the given one), and the
    positions and velocities at the samples (the accelerations are linear in time, so the
    FEM integrates them exactly)."""
    from scipy.spatial.transform import Rotation

    from ..imu import ImuData

    t = np.linspace(0.0, 10.0, 101)
    att = Rotation.from_euler("ZYX", [0.5, 0.03, -0.02])
    u = np.array([1.0, slopes[0], -slopes[1]])
    d = att.apply(u / np.linalg.norm(u))                      # the direction of travel, navigation frame
    s = 2.0 + 0.5 * t + 0.05 * t ** 2
    dist = 2.0 * t + 0.25 * t ** 2 + t ** 3 / 60.0
    acc = np.outer(0.5 + 0.1 * t, d)
    g = np.array([0.0, 0.0, -9.80665])
    f = att.inv().apply(acc - g)
    data = ImuData.from_gyro(t, f, np.zeros((t.size, 3)), initial_attitude=att, gravity=g, checks=False)
    return data, np.outer(dist, d), np.outer(s, d)
