"""The gyro's angle random walk: a time-varying attitude error at knots, rad."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ._attitude import (
    AttitudeErrorModel,
    _check_strapdown,
    acceleration_columns,
    at_point,
    hat_weights,
    knot_times,
    left_jacobian,
    positive_option,
    random_walk_cost,
    random_walk_term,
)

__all__ = ["AttitudeWalk", "walk_interval", "bridge_intensity"]

#: Standard gravity, m/s^2 (the scale of the specific force that turns a tilt into an
#: acceleration error in :func:`walk_interval`).
_G0 = 9.80665


def walk_interval(acc_noise: float, arw: float, gravity: float = _G0, ratio: float = 0.25) -> float:
    r"""Knot spacing of :class:`AttitudeWalk` from the sensor's two white noises, s.

    Parameters
    ----------
    acc_noise : float
        Accelerometer white-noise density :math:`n_a`, m/s^2/sqrt(Hz) (the noise that
        ``sigma_a`` states).
    arw : float
        Gyro angle random walk :math:`n_g`, rad/sqrt(s) (the gyro's white-noise density).
    gravity : float
        Magnitude of the specific force the tilt acts on, m/s^2 (default 9.80665).
    ratio : float
        Largest ratio of the velocity-error variance the knots leave out to the one the
        accelerometer noise contributes over the same interval (default 1/4).

    Returns
    -------
    float
        :math:`\Delta = \sqrt{12\,\rho}\; n_a / (g\, n_g)`, s.

    Notes
    -----
    Sampled at knots :math:`\Delta` apart and interpolated linearly, a random walk
    :math:`\psi` of intensity :math:`n_g^2` is replaced by its conditional mean given
    the knots (the mean of a Brownian bridge is linear), so what the model leaves out is
    the bridge between the knots: independent from one interval to the next, zero at the
    knots, variance :math:`n_g^2 s(\Delta - s)/\Delta` at :math:`s` into an interval.
    Through the specific force (:math:`\delta a = \psi\times f_n`, about
    :math:`g\,\psi` per tilt axis) it is a velocity error over one interval of variance

    .. math:: g^2 \int_0^\Delta\!\!\int_0^\Delta \mathrm{cov}(\beta(s), \beta(u))\,ds\,du
              = \frac{g^2 n_g^2 \Delta^3}{12},

    against :math:`n_a^2 \Delta` from the accelerometer's white noise, which the model
    does state (``sigma_a``). Their ratio :math:`g^2 n_g^2 \Delta^2 / (12 n_a^2)` is at
    most :math:`\rho` for the spacing above: with the default 1/4 the velocity error
    the knots leave out is at most half (in standard deviation) of the one the
    acceleration residual already accounts for, and the left-out part is smoother
    (correlated over :math:`\Delta`), so it is at most 12 % of the stated noise.
    The heading part acts on the horizontal specific force (a fraction of ``g`` on a
    car) and is covered by the same spacing. Tactical grade (:math:`n_a` = 5e-4,
    :math:`n_g` = 2e-5): 4.4 s; consumer (2e-3, 1e-4): 3.5 s; navigation (5e-5, 1e-6):
    8.8 s.

    Examples
    --------
    An accelerometer noise of 0.01 m/s^2/sqrt(Hz) and a gyro ARW of 1 mrad/sqrt(s):

    >>> from bvpnav.error_models import walk_interval
    >>> print(f"{walk_interval(0.01, 1e-3):.2f} s")
    1.77 s
    """
    for v, what in ((acc_noise, "acc_noise"), (arw, "arw"), (gravity, "gravity"), (ratio, "ratio")):
        positive_option(v, f"walk_interval: {what}")
    return math.sqrt(12.0 * float(ratio)) * float(acc_noise) / (float(gravity) * float(arw))


def bridge_intensity(drift: float, interval: float) -> float:
    r"""White-noise intensity of what knots leave out of a random walk, (unit/s)^2 s.

    Parameters
    ----------
    drift : float
        Density of the random walk :math:`q`, unit/sqrt(s): a bias's random walk
        (``GyroBias(drift=...)`` in rad/s/sqrt(s), ``Bias(drift=...)`` in
        m/s^2/sqrt(s)).
    interval : float
        Knot spacing :math:`\Delta` of the walk's model, s.

    Returns
    -------
    float
        :math:`q^2 \Delta^2 / 12`: for a gyro bias in rad^2/s (add it to the square of
        :class:`AttitudeWalk`'s ``arw``), for an accelerometer bias in m^2/s^4/Hz (add
        it to the square of the accelerometer noise density before
        :meth:`bvpnav.sensors.SensorGrade.sigma_a`).

    Notes
    -----
    A random walk :math:`b` of intensity :math:`q^2` modelled by its values at knots
    :math:`\Delta` apart, interpolated linearly, is replaced by its conditional mean
    given the knots; what is left out is a Brownian bridge :math:`\beta` on each
    interval, zero at the knots, independent from interval to interval, with
    :math:`\mathrm{cov}(\beta(s), \beta(u)) = q^2 (\min(s, u) - s u / \Delta)`. What the
    navigation sees is its integral (the attitude for a gyro bias, the velocity for an
    accelerometer bias), of variance

    .. math:: \int_0^\Delta\!\!\int_0^\Delta \mathrm{cov}(\beta(s), \beta(u))\,ds\,du
              = q^2 \left(\frac{\Delta^3}{3} - \frac{\Delta^3}{4}\right) = \frac{q^2 \Delta^3}{12}

    per interval: over times long against :math:`\Delta` the integral grows like that
    of a white noise of intensity :math:`q^2 \Delta^2 / 12`, which the model states by
    adding it to the white noise it already has (the angle random walk for the attitude,
    the accelerometer noise for the acceleration residual). Within one interval the
    left-out part is smoother than white noise (first order in :math:`\Delta`), so the
    addition is exact in the long run and an approximation inside an interval. Tactical
    grade with 30 s knots: gyro :math:`(10^{-6})^2 \cdot 900 / 12 = 7.5\times10^{-11}`
    rad^2/s against :math:`n_g^2 = 4\times10^{-10}`; accelerometer
    :math:`7.5\times10^{-9}` against :math:`n_a^2 = 2.5\times10^{-7}`.

    Examples
    --------
    A bias drifting at 1e-4 rad/s/sqrt(s), modelled at knots 10 s apart:
    :math:`q^2 \Delta^2 / 12 = 10^{-8} \cdot 100 / 12`:

    >>> from bvpnav.error_models import bridge_intensity
    >>> print(f"{bridge_intensity(1e-4, 10.0):.3e}")
    8.333e-08
    """
    q = positive_option(drift, "bridge_intensity: drift")
    d = positive_option(interval, "bridge_intensity: interval")
    if q is None or d is None:
        raise InputError("bridge_intensity: give drift= (the walk's density, unit/sqrt(s)) and interval= "
                         "(the knot spacing, s)")
    return q**2 * d**2 / 12.0


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class AttitudeWalk(AttitudeErrorModel):
    r"""The attitude error a gyro's white noise integrates to: a random walk in the
    navigation frame, at knots, rad.

    Parameters
    ----------
    arw : float
        Angle random walk of the gyro, rad/sqrt(s): its white-noise density (the
        ``gyro_noise`` of :mod:`bvpnav.sensors`; a datasheet's deg/sqrt(h) divided by
        60 and converted to rad). Sets the Gaussian prior of the increments. ``None``:
        no prior (a free piecewise-linear attitude correction, for data whose positions
        and velocities determine it, e.g. :func:`bvpnav.testing.check_error_model`).
    interval : float
        Knot spacing, s (see :func:`~bvpnav.error_models._attitude.knot_times`); choose
        it with :func:`walk_interval` from the accelerometer and gyro noise densities.
    axes : str or sequence of str, optional
        Navigation axes ``x``, ``y`` (tilts) and ``z`` (heading); default all three.

    Notes
    -----
    Parameters ``attitude_walk_<axis>[m]``, ``m = 1 .. M`` (axis-major) are the walk
    :math:`\psi_m` at the knots :math:`t_1 = \tau_0 < \tau_1 < \dots < \tau_M = t_N`;
    at :math:`\tau_0` the walk is zero (the initial attitude error is
    :class:`AttitudeError`'s). Between knots it is linear,
    :math:`\psi(t) = \sum_m \varphi_m(t)\,\psi_m` (hat functions), and it rotates the
    integrated attitude in the navigation frame,

    .. math:: C_k = \exp([\psi(t_k)\times])\, C_k^{\mathrm{int}},

    the form of the continuous error equation :math:`\dot\psi = -C\,n_\omega` of a
    gyro with white noise :math:`n_\omega` (a random walk of intensity :math:`n_g^2`
    per navigation axis, since :math:`C` is a rotation). The prior is that walk's law
    at the knots, on the totals:

    .. math:: \psi_1 - 0,\; \psi_{m+1} - \psi_m \sim N(0, n_g^2 (\tau_{m+1} - \tau_m)),

    exactly the distribution of a random walk sampled at the knots; what the linear
    interpolation leaves out, and why the spacing of :func:`walk_interval` is enough,
    is in that function's Notes. The acceleration :math:`a_k = C_k f_k + g` changes by
    :math:`\varepsilon_k \times C_k f_k` for a navigation-frame rotation
    :math:`\varepsilon_k`, and an increment :math:`\delta` of the knots gives
    :math:`\exp([(\psi + \delta_\psi)\times]) = \exp([J_l(\psi)\delta_\psi\times])
    \exp([\psi\times]) + O(\delta^2)`, so the columns are
    :math:`J_l(\psi(t_k))\, e_j\, \varphi_m(t_k) \times C_k f_k` (:math:`J_l` the left
    Jacobian of SO(3)), exact first derivatives: the re-integrated acceleration differs
    from the linearized one by :math:`O(\delta^2)`. They are local: a knot's column is
    zero outside its two intervals. The walk does not change the gyro-propagated columns
    of :class:`GyroBias` and :class:`AttitudeError` except by the rotation
    :math:`\exp([\psi\times])` (see :func:`~bvpnav.error_models._attitude.propagate`).

    Examples
    --------
    A walk at knots 0.5 s apart on a 1 s recording: two knots per axis after the first:

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> f = np.tile([0.0, 0.0, 9.80665], (11, 1))  # at rest, z up (m/s^2)
    >>> w = np.tile([0.0, 0.0, 0.1], (11, 1))      # turning about z at 0.1 rad/s
    >>> data = bvpnav.ImuData.from_gyro(t, f, w)
    >>> from bvpnav.error_models import AttitudeWalk
    >>> model = AttitudeWalk(arw=1e-3, interval=0.5)
    >>> model.names(data)[:2], model.columns(data).shape
    (['attitude_walk_x[1]', 'attitude_walk_x[2]'], (11, 3, 6))
    """

    arw: Any = None
    interval: Any = None
    units = "rad"
    axis_kind = "navigation"
    default_step_scale = 0.01

    def validate(self) -> None:
        object.__setattr__(self, "arw", positive_option(self.arw, "AttitudeWalk: arw (rad/sqrt(s))"))
        object.__setattr__(self, "interval", positive_option(self.interval, "AttitudeWalk: interval (s)"))
        if self.interval is None:
            raise InputError("AttitudeWalk: give interval= (the knot spacing, s; "
                             "bvpnav.error_models.walk_interval(acc_noise, arw) derives it) and arw= (the "
                             "gyro's angle random walk, rad/sqrt(s))")
        if self.sigma is not None or self.prior is not None or self.bounds is not None:
            raise InputError("AttitudeWalk: sigma, prior and bounds are not supported; its prior is the "
                             "random walk of density arw= (zero at the first sample)")

    def knots(self, data) -> np.ndarray:
        """Knot times in s, the first one (where the walk is zero) included."""
        return knot_times(data.t, self.interval)

    def _weights(self, data) -> np.ndarray:
        """Hat weights of the knots that are parameters (all but the first), (N, M)."""
        return hat_weights(data.t, self.knots(data))[:, 1:]

    def names(self, data) -> list[str]:
        m = self.knots(data).size
        return [f"attitude_walk_{self.AXES[i]}[{k}]" for i in self._sel() for k in range(1, m)]

    def _walk(self, data) -> np.ndarray:
        """The walk at the data's linearization point, (N, 3) rotation vectors, rad."""
        w = at_point(data).walk
        return np.zeros((data.n, 3)) if w is None else w

    def direct_columns(self, data) -> np.ndarray:
        """Navigation-frame rotation of each sample's attitude per unit parameter, (N, 3, q), rad."""
        _check_strapdown(data, "AttitudeWalk")
        W = self._weights(data)
        m = W.shape[1]
        J = left_jacobian(self._walk(data))
        sel = self._sel()
        out = np.empty((data.n, 3, len(sel) * m))
        for a, i in enumerate(sel):
            out[:, :, a * m:(a + 1) * m] = J[:, :, i, None] * W[:, None, :]
        return out

    def columns(self, data) -> np.ndarray:
        return acceleration_columns(data, self.direct_columns(data))

    def rate_change(self, data, d: np.ndarray) -> np.ndarray:
        return np.zeros((data.n, 3))

    def direct_change(self, data, d: np.ndarray) -> np.ndarray:
        W = self._weights(data)
        m = W.shape[1]
        v = np.zeros((data.n, 3))
        for a, i in enumerate(self._sel()):
            v[:, i] = W @ d[a * m:(a + 1) * m]
        return np.einsum("nij,nj->ni", left_jacobian(self._walk(data)), v)

    def apply(self, values, parts, data) -> None:
        W = self._weights(data)
        m = W.shape[1]
        for a, i in enumerate(self._sel()):
            parts["walk"][:, i] += W @ values[a * m:(a + 1) * m]

    def step_scale(self, data) -> np.ndarray:
        r"""The walk's prior standard deviation at each knot, :math:`n_g\sqrt{\tau_m - \tau_0}`, rad
        (``default_step_scale`` without ``arw``)."""
        k = self.knots(data)
        if self.arw is None:
            return np.full(len(self._sel()) * (k.size - 1), self.default_step_scale)
        return np.tile(self.arw * np.sqrt(k[1:] - k[0]), len(self._sel()))

    def extra_prior_cost(self, data) -> float:
        if self.arw is None:
            return 0.0
        return random_walk_cost(self.base(data), self.knots(data), self.arw, anchored=True)

    def extra_terms(self, model) -> list:
        if self.arw is None:
            return []
        data = model.data
        return [random_walk_term(model, self.names(data), self.knots(data), self.arw, self.units,
                                 "random walk AttitudeWalk", base=self.base(data), anchored=True)]

    @classmethod
    def example(cls) -> AttitudeWalk:
        return cls(arw=1e-3, interval=5.0)
