r"""A car's side slip in turns: the rear axle's cornering compliance, read by NonHolonomic(slip=...)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ._base import _Installed

__all__ = ["SideSlip", "SIDE_SLIP_PRIOR", "SIDE_SLIP_SIGMA"]

#: The parameter's name (``error_params["side_slip"]``).
NAMES = ("side_slip",)

#: Standard gravity, m/s^2 (degrees per g <-> s^2/m).
_G = 9.80665

#: A passenger car's rear-axle cornering compliance, s^2/m: 4 degrees of side slip per g of
#: lateral specific force (see :class:`SideSlip`'s Notes for the published figures).
SIDE_SLIP_PRIOR = float(np.radians(4.0) / _G)

#: Its prior standard deviation, s^2/m: 2 degrees per g (the published range, 2.3 to 9 degrees
#: per g, within about 1 and 2.5 of it).
SIDE_SLIP_SIGMA = float(np.radians(2.0) / _G)


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class SideSlip(_Installed):
    r"""The rear axle's cornering compliance :math:`K`, s^2/m (estimated): how far a car's rear
    axle slides outwards in a turn.

    A car's tyres carry a lateral force by rolling at a slip angle to their heading, and in
    the linear range the force is proportional to it: in a turn the middle of the rear axle
    does not move along the car's axis but slides outwards at :math:`v_y = -K f_y v_x`, with
    :math:`f_y` the measured lateral specific force and :math:`v_x` the forward speed (the
    derivation is in :class:`~bvpnav.constraints.NonHolonomic`'s Notes). At 3 m/s^2 and 10
    m/s, :math:`K = 0.007` s^2/m is 0.2 m/s sideways: twice a typical non-holonomic sigma.
    With ``NonHolonomic(slip="estimated")`` the lateral rows hold the velocity at that
    slip, :math:`K` estimated with the navigation solution.

    Parameters
    ----------
    sigma : float
        Prior standard deviation, s^2/m, e.g. :data:`SIDE_SLIP_SIGMA` (2 degrees per g).
        :math:`K` is observed only in turns (through :math:`f_y`), so a drive with few turns
        needs the prior.
    prior : float, optional
        Prior value, s^2/m (default zero: no slip; :data:`SIDE_SLIP_PRIOR`, 4 degrees per g,
        is a passenger car's). Used with ``sigma``.
    bounds : (lo, hi), optional
        Hard limits in s^2/m.

    Notes
    -----
    Parameter ``side_slip``: :math:`K = D_r / g` with :math:`D_r = W_r / C_{\alpha r}` the rear
    axle's cornering compliance (rad per g of lateral acceleration: its load over its
    cornering stiffness), so that the side-slip angle at the rear axle is
    :math:`\beta = v_y / v_x = -K f_y`. Published figures: a radial tyre's cornering
    stiffness is 11-19 % of its load per degree of slip (about 15 %; low-aspect tyres 25-30
    %: Gillespie, *Fundamentals of Vehicle Dynamics*, SAE 1992, ch. 10, the cornering coefficient), so
    :math:`D_r` = 3.3-9 deg/g; the passenger car of Rajamani's examples (*Vehicle Dynamics
    and Control*, 2nd ed., Springer 2012, ch. 2-3: 1573 kg, the centre of gravity 1.1 m
    behind the front axle and 1.58 m ahead of the rear, 80,000 N/rad per tyre) has a rear
    axle load of 6,330 N on 160,000 N/rad, :math:`D_r` = 2.3 deg/g. Hence the prior
    :data:`SIDE_SLIP_PRIOR` (4 deg/g, 0.0071 s^2/m) and :data:`SIDE_SLIP_SIGMA` (2 deg/g,
    0.0036 s^2/m). The rows of :meth:`bvpnav.NavModel.side_slip_velocity` are
    :math:`K f_y v^0_x`, linear in :math:`K` about the forward velocity :math:`v^0_x` of the
    attitude loop's linearization point (exact at the loop's answer). The columns are zero
    (the slip does not change the accelerations). Beyond the tyres' linear range (above
    about 0.4 g) the slip grows faster than :math:`f_y`.

    Examples
    --------
    >>> from bvpnav.error_models import SideSlip
    >>> SideSlip(sigma=0.0036, prior=0.0071).names(SideSlip.example_data())
    ['side_slip']
    """

    units = "s^2/m"
    #: The role the vehicle items look the component up by (:meth:`bvpnav.NavModel.side_slip_velocity`).
    provides: ClassVar[str] = "side_slip"
    #: A model of the vehicle, not of the IMU's errors: its prior does not stop a sensor
    #: grade from filling in the IMU models' priors.
    other_sensor = True

    NAMES: ClassVar[tuple[str, ...]] = NAMES
    NO_AXES: ClassVar[str] = "the compliance is one number (the rear axle's, s^2/m)"
    COUNTS: ClassVar[tuple[tuple[int, ...], str]] = ((1,), "one (s^2/m)")

    @classmethod
    def example(cls) -> SideSlip:
        return cls(sigma=SIDE_SLIP_SIGMA, prior=SIDE_SLIP_PRIOR)

    @staticmethod
    def example_data():
        """Strapdown data of a car whose rear axle slides in the turns (:func:`slip_drive`)."""
        return slip_drive(0.008)[0]

    @classmethod
    def example_recovery(cls, problem):
        """``(problem, truth, solve options)`` built with ``problem`` (the problem class, given
        by the contract check): a noise-free car on a winding road whose IMU, at the middle of
        the rear axle, slides outwards at :math:`0.008 f_y v_x` (4.5 deg/g), fixes every 2 s,
        hard ``NonHolonomic(slip="estimated")`` rows and an initial attitude error estimated
        (the attitude loop iterates the rows); the solve must find :math:`K` (s^2/m) to 1e-6."""
        from ..items import item_class
        from .attitude_error import AttitudeError

        Position, NonHolonomic = item_class("position"), item_class("non_holonomic")
        k_true = 0.008
        data, pos, _ = slip_drive(k_true)
        k = np.arange(0, data.n, 20)
        prob = problem(data, error_model=AttitudeError(sigma=0.01) + cls(), grade=None)
        prob.add(Position(t=data.t[k], value=pos[k], name="fixes"),
                 NonHolonomic(mode="hard", slip="estimated", rate=2.0, name="non-holonomic"))
        return prob, {"side_slip": k_true}, {"solver": "direct", "attitude": {"tol": 1e-12}}


def slip_drive(k: float, lever=(0.0, 0.0, 0.0), duration: float = 20.0, rate: float = 10.0):
    r"""A noise-free car on a winding, undulating road whose rear axle's middle, at ``lever`` (m,
    body axes from the IMU), slides sideways at :math:`v_y = -k f_y v_x` (``k`` in s^2/m): the
    data, and the IMU's positions and velocities at the samples.

    The drive is :func:`bvpnav.error_models.nhc_lever._car_drive`'s (the same rates, forward
    speed :math:`s` and attitude) with the point's body velocity :math:`(s, u, 0)`. The lateral
    specific force :math:`f_y` at the samples is affine in the lateral velocities :math:`u`
    (through the accelerations ``_car_drive`` makes of the velocities, linear between samples:
    :math:`f_y = f_y^0 + M u` with :math:`M = \sum_a \mathrm{diag}(c_a)\, D\,
    \mathrm{diag}(c_a)`, :math:`c_a` the navigation axis :math:`a` of the body y axis and
    :math:`D` the samples' velocity-to-acceleration map), so :math:`u = -k\, s f_y` is one
    linear solve, :math:`(I + k\, \mathrm{diag}(s) M)\, u = -k\, s f_y^0`: the relation
    holds at every sample to rounding, and the accelerations integrate to the returned
    velocities exactly.
    """
    from .nhc_lever import _car_drive

    lever = np.asarray(lever, dtype=float)
    data0, _, vel0 = _car_drive(lever, duration, rate)
    t = data0.t
    n, h = t.size, float(t[1] - t[0])
    s = 8.0 + 2.0 * np.sin(0.3 * t)                         # _car_drive's forward speed
    D = np.empty((n, n))                                    # _car_drive's accelerations of velocities
    D[0] = np.gradient(np.eye(n), t, axis=0, edge_order=2)[0]
    for j in range(n - 1):
        D[j + 1] = -D[j]
        D[j + 1, j + 1] += 2.0 / h
        D[j + 1, j] -= 2.0 / h
    c = data0.attitude.as_matrix()[:, :, 1]                 # (n, 3): the body y axis in navigation axes
    M = sum(c[:, a, None] * D * c[None, :, a] for a in range(3))
    fy0 = np.asarray(data0.specific_force)[:, 1]
    u = np.linalg.solve(np.eye(n) + k * s[:, None] * M, -k * s * fy0)
    return _car_drive(lever, duration, rate, slip=-u / s)
