"""The GNSS antenna's lever arm, body frame, m: three unknowns read by the fix items."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ._base import _Installed

__all__ = ["LeverArm"]


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class LeverArm(_Installed):
    r"""Position of the GNSS antenna relative to the IMU in the body frame, m (estimated).

    Parameters
    ----------
    sigma : float or array_like of 3, optional
        Prior standard deviation, m (one value or one per body axis), e.g. the uncertainty
        of a tape measurement.
    prior : array_like of 3, optional
        Prior value, m (the measured lever arm; default zero). Used with ``sigma``.
    bounds : (lo, hi), optional
        Hard limits in m.

    Notes
    -----
    Parameters ``lever_x``, ``lever_y``, ``lever_z`` (body axes). They do not change the
    accelerations (their columns are zero); the fixes built with ``lever="estimated"``
    (:class:`~bvpnav.constraints.Position`, :class:`~bvpnav.constraints.Velocity`) read
    them through :meth:`bvpnav.NavModel.antenna_offset`:

    .. math:: r_\mathrm{ant}(t) = r(t) + C(t)\,l, \qquad
              v_\mathrm{ant}(t) = v(t) + C(t)\,(\omega(t) \times l),

    linear in :math:`l` for a given attitude :math:`C` (re-made at every step of the
    attitude loop). The lever arm is observable when the attitude changes (turns) or the
    car rotates: with a constant attitude :math:`C l` is a constant offset of every fix,
    indistinguishable from the start position.

    Examples
    --------
    >>> from bvpnav.error_models import LeverArm
    >>> LeverArm(sigma=0.5).names(LeverArm.example_data())
    ['lever_x', 'lever_y', 'lever_z']
    """

    units = "m"
    #: The role the fix items look the component up by (:meth:`bvpnav.NavModel.antenna_offset`).
    provides: ClassVar[str] = "lever_arm"

    NAMES: ClassVar[tuple[str, ...]] = ("lever_x", "lever_y", "lever_z")
    NO_AXES: ClassVar[str] = ("the lever arm has three body-frame components (give a tight sigma on a "
                              "component you know)")
    COUNTS: ClassVar[tuple[tuple[int, ...], str]] = ((1, 3), "one or three (x, y, z body axes, m)")

    @classmethod
    def example(cls) -> LeverArm:
        return cls(sigma=1.0)

    @staticmethod
    def example_data():
        """Strapdown data turning about z (the contract check's default data has no attitude)."""
        from ..simulate import strapdown_3d_2010

        return strapdown_3d_2010(rate=10.0).imu_data()

    @classmethod
    def example_recovery(cls, problem):
        """``(problem, truth, solve options)`` built with ``problem`` (the problem class, given
        by the contract check :func:`bvpnav.testing.check_error_model`, so that this layer imports
        nothing above it): hard fixes of an antenna at ``(1, -0.3, 0.2)`` m
        in the body frame on a turning motion (positions: the FEM's own integration of the
        data, so the answer is exact); the solve must find ``truth`` (m) to 1e-6."""
        from ..items import item_class

        Position, Velocity = item_class("position"), item_class("velocity")

        data = cls.example_data()
        free = problem(data).add(Position(t=data.t[0], value=0.0), Velocity(t=data.t[0], value=0.0))
        pos = free.solve(solver="direct").position()
        lever = np.array([1.0, -0.3, 0.2])
        k = np.arange(0, data.n, max(1, data.n // 12))
        ant = pos[k] + data.attitude[k].apply(lever)
        prob = problem(data, error_model=cls(), grade=None)
        prob.add(Position(t=data.t[k], value=ant, lever="estimated", name="antenna fixes"),
                 Velocity(t=data.t[0], value=0.0, name="start velocity"))
        return prob, dict(zip(cls().names(data), lever.tolist(), strict=True)), {"solver": "direct"}
