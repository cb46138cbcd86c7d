"""The gravity vector as an unknown (2010 paper, Section 5.3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._base import Param, SensorErrorModel, _nominal_gravity

__all__ = ["UnknownGravity"]


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class UnknownGravity(SensorErrorModel):
    r"""Gravity vector in the navigation frame treated as unknown, m/s^2.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Navigation axes whose gravity component is unknown; default all.
    prior, sigma, bounds
        Optional soft prior and hard bounds in m/s^2; the default prior is the data's
        nominal gravity (``ImuData.gravity``; zero for navigation-frame data).

    Notes
    -----
    Reported as ``gravity_<axis>`` = :math:`g_a = g^{nom}_a + dg_a`, the full component.
    The corrected acceleration is :math:`a = C f + g^{nom} + dg`, so the column of
    :math:`dg_a` is the unit vector :math:`e_a` (the paper's :math:`\mathbf{p}`, eq. 33).
    Estimating it absorbs a small tilt of the initial attitude (the horizontal
    components) and the local value of g. With navigation-frame data it is a constant
    acceleration offset per axis (indistinguishable from a bias there).

    Examples
    --------
    With navigation-frame data it is a constant acceleration offset per axis, reported as the
    full component (here a tilt that leaked 0.05 m/s^2 of gravity into the axis):

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, Velocity
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> tk = [0.0, 5.0, 10.0]
    >>> known = [Position(t=tk, value=0.5 * np.sin(tk)), Velocity(t=0.0, value=0.5)]  # r = 0.5 sin t (m)
    >>> from bvpnav.error_models import UnknownGravity
    >>> data = bvpnav.ImuData(t=t, acc=-0.5 * np.sin(t) - 0.05)
    >>> sol = bvpnav.NavigationProblem(data, error_model=UnknownGravity(), items=known).solve(solver="direct")
    >>> print(f"gravity_x {sol.error_params['gravity_x']:.3f} m/s^2")
    gravity_x 0.050 m/s^2
    """

    #: What the solve's plausibility check judges its estimates as (the limits are in
    #: :mod:`bvpnav.solve.plausibility`).
    plausibility_kind = "gravity"

    units = "m/s^2"

    def params(self, data) -> list[Param]:
        ax = tuple(data.axes)
        return [Param(f"gravity_{ax[i]}", "gravity", i) for i in self._select_axes(ax, "navigation")]

    def default_prior(self, model) -> np.ndarray:
        g0 = _nominal_gravity(model.data)
        return np.array([g0[p.i] for p in self.params(model.data)])
