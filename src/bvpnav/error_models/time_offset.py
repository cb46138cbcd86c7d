"""The delay of the GNSS fixes against the IMU clock, s: one unknown read by the fix items."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ._base import _Installed

__all__ = ["TimeOffset"]


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class TimeOffset(_Installed):
    r"""A constant delay of the GNSS fixes against the IMU clock, s (estimated).

    Parameters
    ----------
    sigma : float, optional
        Prior standard deviation, s (e.g. 0.1 for a receiver whose latency is unknown).
    prior : float, optional
        Prior value, s (default 0). Used with ``sigma``.
    bounds : (lo, hi), optional
        Hard limits in s.

    Notes
    -----
    Parameter ``time_offset`` :math:`\delta` (s): a fix stamped :math:`t_k` is the
    position at IMU time :math:`t_k - \delta` (positive: the fixes are stamped late, as a
    receiver's latency makes them). Its column is zero; the fixes built with
    ``delay="estimated"`` (:class:`~bvpnav.constraints.Position`,
    :class:`~bvpnav.constraints.Velocity`) read it through
    :meth:`bvpnav.NavModel.time_offset` and are linearized about the current estimate
    :math:`(\hat r, \hat\delta)` by the sequential loop:

    .. math:: r(t_k - \delta) \approx r(t_k - \hat\delta) - \hat v(t_k - \hat\delta)\,
              (\delta - \hat\delta),

    exact at the fixed point. The velocity is the derivative of the fixed quantity, so that
    with noisy fixes the fixed point is the least-squares answer; with a lever arm it is the
    antenna's, :math:`\hat v + C(\omega \times \hat l)` (a turning vehicle's antenna moves
    even where the IMU stands still).
    Observable where the vehicle moves: :math:`\delta` shifts each fix along the velocity.

    Examples
    --------
    >>> from bvpnav.error_models import TimeOffset
    >>> TimeOffset(sigma=0.1).names(TimeOffset.example_data())
    ['time_offset']
    """

    units = "s"
    #: The role the fix items look the component up by (:meth:`bvpnav.NavModel.time_offset`).
    provides: ClassVar[str] = "time_offset"

    NAMES: ClassVar[tuple[str, ...]] = ("time_offset",)
    NO_AXES: ClassVar[str] = "the delay is one number for every fix"
    COUNTS: ClassVar[tuple[tuple[int, ...], str]] = ((1,), "one number (s)")

    @classmethod
    def example(cls) -> TimeOffset:
        return cls(sigma=0.1)

    @staticmethod
    def example_data():
        """Navigation-frame accelerations of a moving point on three axes, 10 Hz over 20 s."""
        from ..imu import ImuData

        t = np.linspace(0.0, 20.0, 201)
        acc = np.column_stack([np.sin(0.5 * t), 0.3 * np.cos(0.3 * t), 0.1 * np.sin(0.2 * t + 1.0)])
        return ImuData(t=t, acc=acc)

    @classmethod
    def example_recovery(cls, problem):
        """``(problem, truth, solve options)`` built with ``problem`` (the problem class, given
        by the contract check :func:`bvpnav.testing.check_error_model`, so that this layer imports
        nothing above it): hard fixes stamped 0.2 s after the samples whose
        position they hold (positions: the FEM's own integration of the data, so the answer
        is exact); the solve must find ``time_offset = 0.2`` s to 1e-6."""
        from ..items import item_class

        Position, Velocity = item_class("position"), item_class("velocity")

        data = cls.example_data()
        free = problem(data).add(Position(t=data.t[0], value=0.0), Velocity(t=data.t[0], value=1.0))
        pos = free.solve(solver="direct").position()
        k = np.arange(5, data.n - 5, 10)
        delay = 0.2
        prob = problem(data, error_model=cls(), grade=None)
        prob.add(Position(t=data.t[k] + delay, value=pos[k], delay="estimated", name="late fixes"),
                 Velocity(t=data.t[0], value=1.0, name="start velocity"))
        return prob, {"time_offset": delay}, {"solver": "direct", "sequential": {"tol": 1e-12}}
