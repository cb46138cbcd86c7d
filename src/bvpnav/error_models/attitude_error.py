"""The error of the initial attitude: two tilts and a heading, rad."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import InputError
from ._attitude import AttitudeErrorModel, _check_strapdown, left_jacobian

__all__ = ["AttitudeError"]

@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class AttitudeError(AttitudeErrorModel):
    r"""Correction of the initial attitude: tilts about the navigation x and y axes and a
    heading about the navigation z axis, rad.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Which of ``x``, ``y`` (tilts) and ``z`` (heading) to estimate; default all three.
    sigma : float or sequence, optional
        Prior standard deviation of each total correction, rad; ``None`` or ``inf`` on an
        axis means no prior there (the usual choice for an unknown heading), e.g.
        ``sigma=(0.01, 0.01, None)``.
    prior : float or sequence, optional
        Prior value of each correction, rad (default 0).

    Notes
    -----
    Parameters ``attitude_x``, ``attitude_y``, ``attitude_z`` = :math:`(\theta_x, \theta_y, \psi)`
    give the corrected initial attitude

    .. math:: C_1 = \exp([(\theta_x, \theta_y, 0)\times])\, R_z(\psi)\, \hat C_1,

    (body to navigation), so the heading correction is exact for any angle and the tilts
    are rotation-vector components. Every later attitude follows by integrating the
    (corrected) gyro rates from :math:`C_1`, so a change of :math:`C_1` by a small
    navigation-frame rotation :math:`\varepsilon` changes every :math:`C_k` by the same
    :math:`\varepsilon`; the acceleration :math:`a_k = C_k f_k + g` then changes by
    :math:`\varepsilon \times C_k f_k`. The columns are the exact first derivatives:
    :math:`\partial\varepsilon/\partial\theta = J_l(\theta)` (left Jacobian of SO(3))
    and :math:`\partial\varepsilon/\partial\psi = \exp([\theta\times]) e_z`; the
    linearization error of the acceleration is :math:`O(\delta^2)` in the increment.
    A tilt of 1 mrad puts about 0.01 m/s^2 of gravity into the horizontal acceleration.

    Examples
    --------
    Tilts with a 10 mrad prior and a free heading:

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> f = np.tile([0.0, 0.0, 9.80665], (11, 1))  # at rest, z up (m/s^2)
    >>> w = np.tile([0.0, 0.0, 0.1], (11, 1))      # turning about z at 0.1 rad/s
    >>> data = bvpnav.ImuData.from_gyro(t, f, w)
    >>> from bvpnav.error_models import AttitudeError
    >>> model = AttitudeError(sigma=(0.01, 0.01, None))
    >>> model.names(data), model.columns(data).shape
    (['attitude_x', 'attitude_y', 'attitude_z'], (11, 3, 3))
    """

    #: What the solve's plausibility check judges its estimates as (the limits are in
    #: :mod:`bvpnav.solve.plausibility`).
    plausibility_kind = "attitude"

    units = "rad"
    default_step_scale = 0.05
    axis_kind = "attitude"

    def __post_init__(self):
        # sigma may hold None/inf ("no prior on this axis"), which the base check refuses
        sig, prior = self.sigma, self.prior
        object.__setattr__(self, "sigma", None)
        object.__setattr__(self, "prior", None)
        super().__post_init__()
        if prior is not None:
            p = np.atleast_1d(np.asarray(prior, dtype=float))
            if not np.all(np.isfinite(p)):
                raise InputError(f"AttitudeError: prior={prior!r} must be finite angles in rad")
            object.__setattr__(self, "prior", p)
        if sig is not None:
            vals = np.atleast_1d(np.array([np.inf if v is None else v for v in np.atleast_1d(
                np.asarray(sig, dtype=object))], dtype=float))
            if np.any(np.isnan(vals)) or np.any(vals <= 0):
                raise InputError(f"AttitudeError: sigma={sig!r}; give positive angles in rad (None or inf "
                                 "for no prior on an axis)")
            object.__setattr__(self, "sigma", vals)

    def names(self, data) -> list[str]:
        return [f"attitude_{self.AXES[i]}" for i in self._sel()]

    def _totals(self, data) -> np.ndarray:
        full = np.zeros(3)
        full[list(self._sel())] = self.base(data)
        return full

    @staticmethod
    def rotation(theta_x: float, theta_y: float, heading: float) -> Rotation:
        r"""The correction :math:`\exp([(\theta_x, \theta_y, 0)\times]) R_z(\psi)` (rad)."""
        return Rotation.from_rotvec([theta_x, theta_y, 0.0]) * Rotation.from_rotvec([0.0, 0.0, heading])

    def initial_columns(self, data) -> np.ndarray:
        _check_strapdown(data, "AttitudeError")
        tx, ty, _ = self._totals(data)
        theta = np.array([tx, ty, 0.0])
        full = np.column_stack([left_jacobian(theta)[:, 0], left_jacobian(theta)[:, 1],
                                Rotation.from_rotvec(theta).apply([0.0, 0.0, 1.0])])
        return full[:, list(self._sel())]

    def prior_sigma(self, data) -> np.ndarray:
        q = len(self._sel())
        if self.sigma is None:
            return np.full(q, np.inf)
        s = self.sigma
        if s.size == 1:
            return np.full(q, float(s[0]))
        if s.size == 3 and q != 3:
            return s[list(self._sel())]
        if s.size != q:
            raise InputError(f"AttitudeError: sigma has {s.size} values for {q} parameters")
        return s.copy()

    def apply(self, values, parts, data) -> None:
        full = np.zeros(3)
        full[list(self._sel())] = values
        parts["initial"] = self.rotation(*full) * parts["initial"]

    @classmethod
    def example(cls) -> AttitudeError:
        return cls(sigma=(0.1, 0.1, None))

