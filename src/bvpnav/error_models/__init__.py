r"""Sensor error models: plug-ins that add unknown parameters to the FEM equations.

An error model contributes columns ``G`` (acceleration change per unit of each
internal parameter) so that the corrected navigation-frame acceleration is
``a_c = a_hat + G l + w``; the 2010 paper's ``K r = f0 + F l`` with ``F = -M G``.
Models compose with ``+``; the paper's nine-parameter model (Section 5.3) is::

    from bvpnav.error_models import Bias, ScaleFactor, UnknownGravity
    model = ScaleFactor() + Bias() + UnknownGravity()

Built-in models, one per file of this package (each discovered on import):

==================  ============================  ==========================
model               parameters                    units
==================  ============================  ==========================
``Bias``            ``bias_<sensor axis>``        m/s^2 (sensor reads high)
``ScaleFactor``     ``scale_<sensor axis>``       dimensionless (0.01 = +1 %)
``Misalignment``    ``misalignment_<i><j>``       rad (small angle)
``UnknownGravity``  ``gravity_<nav axis>``        m/s^2 (gravity vector)
==================  ============================  ==========================

Measurement convention (the simulator :mod:`bvpnav.simulate` uses the same one):

.. math:: \hat f = (I + \mathrm{diag}(s)) (I + \Theta) f + b + n,

with ``f`` the true specific force in sensor axes, ``s`` the scale-factor errors,
``Theta`` the misalignment (zero diagonal, ``Theta_ij`` = how much of axis ``j`` sensor
``i`` picks up), ``b`` the bias and ``n`` noise. Sensor axes are the body axes
``x, y, z`` for strapdown data and the navigation axes for navigation-frame data
(``C = I``).

Write your own by subclassing :class:`ErrorModel` and implementing ``names(data)``
and ``columns(data)`` (see ``examples/custom_error_model.py``).

Examples
--------
An accelerometer that reads 0.1 m/s^2 high, its bias estimated from three known positions
and the initial velocity of the motion :math:`r = 0.5 \sin t` m:

>>> import numpy as np
>>> import bvpnav
>>> from bvpnav.constraints import Position, Velocity
>>> t = np.linspace(0.0, 10.0, 101)
>>> tk = [0.0, 5.0, 10.0]
>>> known = [Position(t=tk, value=0.5 * np.sin(tk)), Velocity(t=0.0, value=0.5)]  # r = 0.5 sin t (m)
>>> from bvpnav.error_models import Bias
>>> data = bvpnav.ImuData(t=t, acc=-0.5 * np.sin(t) + 0.1)
>>> sol = bvpnav.NavigationProblem(data, error_model=Bias(), items=known).solve(solver="direct")
>>> print(f"bias {sol.error_params['bias_x']:.3f} m/s^2")
bias 0.100 m/s^2
"""

from __future__ import annotations

from ..plugins import discover, export
from ._base import (
    CompositeErrorModel,
    ErrorModel,
    Param,
    SensorCorrection,
    SensorErrorModel,
    sensor_axes,
    sensor_frame,
    sensor_signal,
)

__all__ = [
    "CompositeErrorModel",
    "Param",
    "SensorCorrection",
    "ErrorModel",
    "SensorErrorModel",
    "sensor_axes",
    "sensor_frame",
    "sensor_signal",
]

__all__ += export(globals(), discover(__name__, __path__))
