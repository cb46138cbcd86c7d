"""Sensor-grade presets: noise densities, bias sigmas and bias random walks.

One :class:`SensorGrade` holds the numbers that set ``sigma_a`` and every default
prior of the attitude error models for a class of inertial sensor. Three presets,
:data:`GRADES`, cover the usual classes (the numbers are typical orders of magnitude,
not one product's datasheet):

==============  =========  =========  =========  =========  =========  =========  =====  =======
grade           acc noise  acc bias   acc walk   gyro       gyro bias  gyro walk  tilt   heading
                m/s^2/     m/s^2      m/s^2/     noise      rad/s      rad/s/     rad    rad
                sqrt(Hz)              sqrt(s)    rad/s/                sqrt(s)
                                                 sqrt(Hz)
==============  =========  =========  =========  =========  =========  =========  =====  =======
``consumer``    2e-3       5e-2       1e-4       1e-4       5e-3       2e-5       0.02   unknown
``tactical``    5e-4       5e-3       1e-5       2e-5       5e-5       1e-6       0.005  unknown
``navigation``  5e-5       5e-4       1e-6       1e-6       5e-8       1e-8       0.001  unknown
==============  =========  =========  =========  =========  =========  =========  =====  =======

Noise densities are continuous-time white-noise intensities (the Kalibr / GTSAM
convention): the standard deviation of one sample at ``rate_hz`` is
``density * sqrt(rate_hz)`` (see :meth:`SensorGrade.sigma_a`). bvpnav neglects the Earth's
rotation (7.29e-5 rad/s), which a gyro measures like a bias: against the navigation
grade's gyro bias sigma (5e-8 rad/s) it is large, so remove it from the rates first or
widen that prior. Use
:func:`from_datasheet` for a particular sensor::

    from bvpnav.sensors import grade, from_datasheet
    g = grade("tactical")
    prob = NavigationProblem(data, error_model=g.error_model(), sigma_a=g.sigma_a(100.0))
    mine = from_datasheet(acc_noise="150 ug/sqrt(Hz)", acc_bias="40 mg", gyro_noise="0.2 deg/sqrt(h)",
                          gyro_bias="10 deg/h", base="consumer")

Examples
--------
>>> from bvpnav.sensors import GRADES, grade
>>> sorted(GRADES)
['consumer', 'navigation', 'tactical']
>>> g = grade("tactical")
>>> print(f"sigma_a at 100 Hz: {g.sigma_a(100.0):.4f} m/s^2")
sigma_a at 100 Hz: 0.0050 m/s^2
>>> g.error_model()
Bias(sigma=0.005, interval=30.0, drift=1e-05) + GyroBias(sigma=5e-05, interval=30.0, drift=1e-06) + ...
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from typing import Any

from .errors import InputError
from .imu import STANDARD_GRAVITY

__all__ = ["SensorGrade", "GRADES", "DEFAULT_GRADE", "grade", "resolve_grade", "from_datasheet", "UNITS"]

_DEG = math.pi / 180.0

#: Accepted datasheet units per :class:`SensorGrade` field: unit -> factor to SI.
#: Densities are converted to the same kind of density (a one-sided density is turned
#: into the continuous-time intensity by :func:`from_datasheet` with ``one_sided=True``).
UNITS: dict[str, dict[str, float]] = {
    "acc_noise": {  # SI: m/s^2/sqrt(Hz) (= m/s/sqrt(s))
        "m/s^2/sqrt(Hz)": 1.0,
        "m/s/sqrt(s)": 1.0,
        "ug/sqrt(Hz)": 1e-6 * STANDARD_GRAVITY,
        "mg/sqrt(Hz)": 1e-3 * STANDARD_GRAVITY,
        "m/s/sqrt(h)": 1.0 / 60.0,  # velocity random walk
        "ft/s/sqrt(h)": 0.3048 / 60.0,
    },
    "acc_bias": {  # SI: m/s^2
        "m/s^2": 1.0,
        "g": STANDARD_GRAVITY,
        "mg": 1e-3 * STANDARD_GRAVITY,
        "ug": 1e-6 * STANDARD_GRAVITY,
    },
    "acc_bias_walk": {  # SI: m/s^2/sqrt(s) (= m/s^3/sqrt(Hz))
        "m/s^2/sqrt(s)": 1.0,
        "m/s^3/sqrt(Hz)": 1.0,
        "ug/sqrt(s)": 1e-6 * STANDARD_GRAVITY,
        "mg/sqrt(s)": 1e-3 * STANDARD_GRAVITY,
        "ug/sqrt(h)": 1e-6 * STANDARD_GRAVITY / 60.0,
        "mg/sqrt(h)": 1e-3 * STANDARD_GRAVITY / 60.0,
    },
    "gyro_noise": {  # SI: rad/s/sqrt(Hz) (= rad/sqrt(s))
        "rad/s/sqrt(Hz)": 1.0,
        "rad/sqrt(s)": 1.0,
        "deg/s/sqrt(Hz)": _DEG,
        "deg/sqrt(s)": _DEG,
        "deg/h/sqrt(Hz)": _DEG / 3600.0,
        "deg/sqrt(h)": _DEG / 60.0,  # angle random walk
        "rad/sqrt(h)": 1.0 / 60.0,
    },
    "gyro_bias": {  # SI: rad/s
        "rad/s": 1.0,
        "deg/s": _DEG,
        "deg/h": _DEG / 3600.0,
        "mrad/s": 1e-3,
    },
    "gyro_bias_walk": {  # SI: rad/s/sqrt(s) (= rad/s^2/sqrt(Hz))
        "rad/s/sqrt(s)": 1.0,
        "rad/s^2/sqrt(Hz)": 1.0,
        "deg/s/sqrt(s)": _DEG,
        "deg/h/sqrt(h)": _DEG / 3600.0 / 60.0,  # rate random walk
        "deg/h/sqrt(s)": _DEG / 3600.0,
    },
    "tilt": {"rad": 1.0, "mrad": 1e-3, "deg": _DEG},
    "heading": {"rad": 1.0, "mrad": 1e-3, "deg": _DEG},
}

#: The SI unit of each numeric field (the first entry of :data:`UNITS`).
_SI = {k: next(iter(v)) for k, v in UNITS.items()}

_NUMERIC = ("acc_noise", "acc_bias", "acc_bias_walk", "gyro_noise", "gyro_bias", "gyro_bias_walk", "tilt")


def _positive(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{what}={value!r}: give a positive number in {_SI.get(what.split('.')[-1], 'SI')}")
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise InputError(f"{what}={value!r}: must be finite and > 0 ({_SI.get(what.split('.')[-1], 'SI')})")
    return v


def _rate(rate_hz: Any) -> float:
    if isinstance(rate_hz, bool) or not isinstance(rate_hz, (int, float)):
        raise InputError(f"rate_hz={rate_hz!r}: give the sample rate in Hz (e.g. 100.0)")
    r = float(rate_hz)
    if not (math.isfinite(r) and r > 0):
        raise InputError(f"rate_hz={rate_hz!r}: the sample rate must be finite and > 0 Hz")
    return r


def _with_bridge(density: float, drift: float, interval: float | None) -> float:
    """A white-noise density with what bias knots ``interval`` s apart leave out of a bias
    random walk of density ``drift`` added in quadrature (none when ``interval`` is None)."""
    if interval is None:
        return density
    from .error_models import bridge_intensity  # error models load numpy/pandas

    return math.sqrt(density**2 + bridge_intensity(drift, _positive(interval, "interval")))


@dataclass(frozen=True)
class SensorGrade:
    """Noise and bias figures of an IMU, in SI units.

    Parameters
    ----------
    acc_noise : float
        Accelerometer white-noise density, m/s^2/sqrt(Hz) (continuous-time intensity;
        per-sample sigma ``acc_noise * sqrt(rate_hz)``).
    acc_bias : float
        Accelerometer bias standard deviation (turn-on bias), m/s^2.
    acc_bias_walk : float
        Accelerometer bias random walk, m/s^2/sqrt(s): the bias changes by
        ``acc_bias_walk * sqrt(dt)`` (one sigma) over ``dt`` seconds.
    gyro_noise : float
        Gyro white-noise density (angle random walk), rad/s/sqrt(Hz) = rad/sqrt(s): the
        attitude it integrates to is modelled by
        :class:`~bvpnav.error_models.AttitudeWalk` (``error_model(walk=True)``).
    gyro_bias : float
        Gyro bias standard deviation, rad/s.
    gyro_bias_walk : float
        Gyro bias random walk, rad/s/sqrt(s).
    tilt : float
        Standard deviation of the initial roll and pitch, rad (what a stationary
        alignment achieves: about ``acc_bias / g``).
    heading : float or None
        Standard deviation of the initial heading, rad; ``None`` when the heading is
        unknown (no prior: the positions must determine it).
    name : str
        Short name (the key in :data:`GRADES` for a preset).
    description : str
        One line saying what sensors the grade stands for.

    Examples
    --------
    >>> from bvpnav.sensors import grade
    >>> g = grade("consumer")
    >>> g.acc_noise, g.gyro_bias, g.tilt  # m/s^2/sqrt(Hz), rad/s, rad
    (0.002, 0.005, 0.02)
    >>> print(f"{g.sigma_a(100.0):.3f} m/s^2")  # one sample's noise at 100 Hz: 2e-3 * sqrt(100)
    0.020 m/s^2
    """

    acc_noise: float
    acc_bias: float
    acc_bias_walk: float
    gyro_noise: float
    gyro_bias: float
    gyro_bias_walk: float
    tilt: float
    heading: float | None = None
    name: str = "custom"
    description: str = ""

    def __post_init__(self):
        for f in _NUMERIC:
            object.__setattr__(self, f, _positive(getattr(self, f), f))
        if self.heading is not None:
            unknown = isinstance(self.heading, float) and self.heading == math.inf
            # inf = no prior, kept as None so that there is one spelling of "unknown"
            object.__setattr__(self, "heading", None if unknown else _positive(self.heading, "heading"))
        if not isinstance(self.name, str) or not isinstance(self.description, str):
            raise InputError("SensorGrade: name and description must be strings")

    def sigma_a(self, rate_hz: float, interval: float | None = None) -> float:
        r"""Per-sample accelerometer noise standard deviation, m/s^2: NavigationProblem's ``sigma_a``.

        Parameters
        ----------
        rate_hz : float
            Sample rate of the recording, Hz.
        interval : float, optional
            Knot spacing of a random-walk ``Bias(interval=..., drift=acc_bias_walk)`` in
            the error model, s: the part of the bias walk its knots leave out is added to
            the white noise (:func:`bvpnav.error_models.bridge_intensity`). None (default):
            the sensor's white noise alone.

        Returns
        -------
        float
            :math:`\sigma_a = n_a \sqrt{f_s}`, m/s^2, with :math:`n_a` = ``acc_noise``
            (with ``interval``: :math:`n_a^2 + q_a^2 \Delta^2 / 12` in place of
            :math:`n_a^2`, :math:`q_a` = ``acc_bias_walk``).

        Notes
        -----
        bvpnav's acceleration residual :math:`w_i` is one value per sample and axis, and
        the objective :math:`\sum_i \|w_i\|^2/\sigma_a^2` is the maximum-a-posteriori
        estimate for independent per-sample noise of standard deviation
        :math:`\sigma_a`. A white noise of continuous-time intensity :math:`n_a`
        (autocorrelation :math:`n_a^2 \delta(\tau)`, units m/s^2/sqrt(Hz)) averaged over
        one sample period :math:`\Delta t = 1/f_s` has variance :math:`n_a^2/\Delta t`,
        hence

        .. math:: \sigma_a = n_a \sqrt{f_s}.

        From a datasheet:

        - a density in ug/sqrt(Hz): :math:`n_a = 10^{-6}\, g_0 \times` value
          (:math:`g_0` = 9.80665 m/s^2); 150 ug/sqrt(Hz) at 100 Hz gives
          :math:`1.471\times 10^{-3} \times 10 = 0.0147` m/s^2;
        - a velocity random walk in m/s/sqrt(h): :math:`n_a` = value / 60
          (1 m/s/sqrt(h) = 1 m/s / sqrt(3600 s));
        - datasheets usually quote the *one-sided* spectral density
          :math:`S_1 = 2 n_a^2`, i.e. a figure :math:`\sqrt 2` larger than the
          intensity; with an ideal anti-alias filter at the Nyquist frequency the
          per-sample sigma is then :math:`\sqrt{S_1 f_s / 2}` = figure
          :math:`\times\sqrt{f_s/2}`, a factor :math:`\sqrt 2` below figure
          :math:`\times\sqrt{f_s}` (``from_datasheet(..., one_sided=True)`` divides by
          :math:`\sqrt 2`). A sensor whose internal filter is narrower than
          :math:`f_s/2` has a smaller per-sample sigma (use its noise bandwidth in
          place of :math:`f_s/2`). The best number is measured: the standard
          deviation of a stationary recording after removing its mean.

        Vibration, not the sensor, usually dominates on a vehicle; ``sigma_a`` is then
        better set from the residual's RMS of a first solve.
        """
        return _with_bridge(self.acc_noise, self.acc_bias_walk, interval) * math.sqrt(_rate(rate_hz))

    def arw(self, interval: float | None = None) -> float:
        r"""Angle random walk for :class:`~bvpnav.error_models.AttitudeWalk`, rad/sqrt(s).

        Parameters
        ----------
        interval : float, optional
            Knot spacing of a random-walk ``GyroBias(interval=..., drift=gyro_bias_walk)``
            in the error model, s; None: the gyro's white noise alone.

        Returns
        -------
        float
            :math:`\sqrt{n_g^2 + q_g^2 \Delta^2 / 12}` (``gyro_noise``, ``gyro_bias_walk``).

        Notes
        -----
        The gyro bias between knots is a Brownian bridge the knots leave out; its
        integral, an attitude error, grows like an angle random walk of intensity
        :math:`q_g^2 \Delta^2/12` (:func:`bvpnav.error_models.bridge_intensity`), which
        adds to the white noise's :math:`n_g^2`. On the simulated 10-minute car drive
        (``examples/benchmarks/car_drive.py``) this and the accelerometer's counterpart
        (:meth:`sigma_a` with ``interval``) took the 10 s gap from 0.8173 to 0.8164 m.
        """
        return _with_bridge(self.gyro_noise, self.gyro_bias_walk, interval)

    def gyro_sigma(self, rate_hz: float) -> float:
        r"""Per-sample gyro noise standard deviation, rad/s: ``gyro_noise * sqrt(rate_hz)``.

        Parameters
        ----------
        rate_hz : float
            Sample rate, Hz.

        Notes
        -----
        The same relation as :meth:`sigma_a`: :math:`\sigma_\omega = n_\omega\sqrt{f_s}`.
        The angle random walk after ``T`` seconds of integration is
        :math:`n_\omega \sqrt T` rad.
        """
        return self.gyro_noise * math.sqrt(_rate(rate_hz))

    def error_model(self, interval: float | None = 30.0, heading_sigma: float | None = None,
                    time_varying: bool = True, walk: bool = False):
        """The error model with this grade's priors: accelerometer and gyro biases and the initial attitude.

        Parameters
        ----------
        interval : float, optional
            Knot spacing of the time-varying biases, s (default 30). Ignored when
            ``time_varying`` is false.
        heading_sigma : float, optional
            Prior standard deviation of the initial heading, rad; default the grade's
            ``heading`` (None for the presets: no prior, the heading comes from the
            positions). ``math.inf`` also means no prior.
        time_varying : bool
            True (default): biases as random walks with knots every ``interval`` s and
            increments of sigma ``*_bias_walk * sqrt(interval)``; false: constant biases
            with the prior ``acc_bias`` / ``gyro_bias``.
        walk : bool
            True: also the attitude error the gyro's white noise integrates to,
            ``AttitudeWalk(arw=arw(interval), interval=walk_interval(acc_noise, arw(interval)))``
            (:meth:`arw`: the white noise plus what the gyro-bias knots leave out; knots
            every 4.05 s for the tactical grade with 30 s bias knots). Pair it with
            ``sigma_a(rate_hz, interval)``. Default False: it adds three
            unknowns per knot (on the 10-minute car drive of
            ``examples/benchmarks/car_drive.py``: 444 more, 573 in all, each a column of
            the banded factor's border; 2 to 5 minutes per solve there) for about 1 % in
            position at 10 s between fixes, where it ties GTSAM's smoother.

        Returns
        -------
        bvpnav.error_models.CompositeErrorModel
            ``Bias(sigma=acc_bias, interval=..., drift=acc_bias_walk)
            + GyroBias(sigma=gyro_bias, interval=..., drift=gyro_bias_walk)
            + AttitudeError(sigma=(tilt, tilt, heading_sigma))``, and with ``walk``
            ``+ AttitudeWalk(arw=arw(interval), interval=walk_interval(acc_noise, arw(interval)))``.
        """
        from .error_models import (  # error models load numpy/pandas
            AttitudeError,
            AttitudeWalk,
            Bias,
            GyroBias,
            walk_interval,
        )

        if not isinstance(walk, bool):
            raise InputError(f"walk={walk!r}: give True (model the gyro's angle random walk, AttitudeWalk) "
                             "or False")
        if not isinstance(time_varying, bool):
            raise InputError(f"time_varying={time_varying!r}: give True (random-walk biases) or False "
                             "(constant biases)")
        if time_varying:
            interval = _positive(interval, "interval") if interval is not None else None
            if interval is None:
                raise InputError("interval=None with time_varying=True: give the knot spacing in s "
                                 "(e.g. 30.0), or time_varying=False for constant biases")
            tv_acc: dict[str, Any] = {"interval": interval, "drift": self.acc_bias_walk}
            tv_gyro: dict[str, Any] = {"interval": interval, "drift": self.gyro_bias_walk}
        else:
            tv_acc, tv_gyro = {}, {}
        heading_sigma = self._heading(heading_sigma)
        em = (Bias(sigma=self.acc_bias, **tv_acc)
              + GyroBias(sigma=self.gyro_bias, **tv_gyro)
              + AttitudeError(sigma=(self.tilt, self.tilt, heading_sigma)))
        if walk:
            arw = self.arw(interval if time_varying else None)
            em = em + AttitudeWalk(arw=arw, interval=walk_interval(self.acc_noise, arw))
        return em

    def _heading(self, heading_sigma: float | None) -> float | None:
        """The initial heading's prior sigma, rad: ``heading_sigma``, else the grade's; None for none."""
        if heading_sigma is None:
            return self.heading
        if isinstance(heading_sigma, (int, float)) and math.isinf(heading_sigma):
            return None
        return _positive(heading_sigma, "heading_sigma")

    def error_states(self, heading_sigma: float | None = None):
        r"""Node states with this grade's figures: the error model of the documented drive path.

        Parameters
        ----------
        heading_sigma : float, optional
            Prior standard deviation of the initial heading, rad; default the grade's ``heading``
            (None for the presets: no prior, the positions determine it). ``math.inf`` also means
            no prior.

        Returns
        -------
        bvpnav.error_models.ErrorStates
            ``ErrorStates(arw=gyro_noise, gyro_drift=gyro_bias_walk, acc_drift=acc_bias_walk,
            attitude_sigma=(tilt, tilt, heading_sigma), gyro_sigma=gyro_bias, acc_sigma=acc_bias)``.

        Notes
        -----
        The attitude error :math:`\delta\theta`, the gyro bias :math:`b_g` and the accelerometer
        bias :math:`b_a` are states at every node (every sample, or every mesh node with
        ``NavigationProblem(..., segment=...)``), tied to their neighbours by the process noise of
        the continuous-time model a factor graph discretizes:

        .. math:: \dot{\delta\theta} = -b_g + n_g, \quad \dot b_g = q_g, \quad \dot b_a = q_a,

        with intensities ``gyro_noise``, ``gyro_bias_walk`` and ``acc_bias_walk``; the first node
        has the priors ``tilt`` (roll, pitch), ``heading_sigma``, ``gyro_bias`` and ``acc_bias``.
        Pair it with :meth:`sigma_a` without an ``interval`` (no knots leave a bridge out).

        Examples
        --------
        >>> from bvpnav.sensors import grade
        >>> m = grade("tactical").error_states()
        >>> m.arw == grade("tactical").gyro_noise, bool(m.attitude_sigma[2] == float("inf"))
        (True, True)
        """
        from .error_models import ErrorStates  # error models load numpy/pandas

        heading_sigma = self._heading(heading_sigma)
        return ErrorStates(arw=self.gyro_noise, gyro_drift=self.gyro_bias_walk, acc_drift=self.acc_bias_walk,
                           attitude_sigma=(self.tilt, self.tilt, math.inf if heading_sigma is None
                                           else heading_sigma),
                           gyro_sigma=self.gyro_bias, acc_sigma=self.acc_bias)

    def complete(self, error_model) -> tuple[Any, list[str]]:
        r"""``error_model`` with this grade's figures as the priors it does not state.

        Parameters
        ----------
        error_model : ErrorModel
            One model or a sum of them.

        Returns
        -------
        (ErrorModel, list of str)
            The completed model (``error_model`` itself when nothing was missing) and one
            line per prior filled in, with its value and units.

        Notes
        -----
        Filled where absent: ``Bias`` ``sigma`` = ``acc_bias`` (m/s^2) and, with
        ``interval``, ``drift`` = ``acc_bias_walk`` (m/s^2/sqrt(s)); ``GyroBias`` ``sigma`` =
        ``gyro_bias`` (rad/s) and, with ``interval``, ``drift`` = ``gyro_bias_walk``
        (rad/s/sqrt(s)); ``AttitudeError`` ``sigma`` = (``tilt``, ``tilt``, ``heading``)
        rad (no heading prior when the grade's heading is unknown). A prior the model
        states is kept, and other models (scale factors, misalignment, ``AttitudeWalk``)
        are left as they are. Each prior is a Gaussian :math:`p \sim N(0, \sigma^2)`, the
        random walks :math:`p_{m+1} - p_m \sim N(0, q^2 \Delta t_m)`: the maximum a
        posteriori estimate for a sensor of this grade.
        """
        import dataclasses

        from .error_models import AttitudeError, Bias, GyroBias

        parts = list(getattr(error_model, "components", (error_model,)))
        filled: list[str] = []
        out = []
        for c in parts:
            change: dict[str, Any] = {}
            kind = type(c).__name__
            if isinstance(c, (Bias, GyroBias)):
                acc = isinstance(c, Bias)
                sig, walk = ((self.acc_bias, self.acc_bias_walk) if acc
                             else (self.gyro_bias, self.gyro_bias_walk))
                units = "m/s^2" if acc else "rad/s"
                if c.sigma is None and c.prior is None:
                    change["sigma"] = sig
                    filled.append(f"{kind}: sigma {sig:g} {units}")
                if c.interval is not None and c.drift is None:
                    change["drift"] = walk
                    filled.append(f"{kind}: drift {walk:g} {units}/sqrt(s)")
            elif isinstance(c, AttitudeError) and c.sigma is None:
                sel = list(c._sel())
                full = [self.tilt, self.tilt, self.heading]
                change["sigma"] = tuple(full[i] for i in sel)
                head = "none (unknown)" if self.heading is None else f"{self.heading:g} rad"
                filled.append(f"AttitudeError: sigma tilt {self.tilt:g} rad, heading {head}")
            out.append(dataclasses.replace(c, **change) if change else c)
        if not filled:
            return error_model, []
        model = out[0]
        for c in out[1:]:
            model = model + c
        return model, filled

    def table(self) -> dict[str, str]:
        """The figures with their SI units, for printing (``{"acc_noise": "0.0005 m/s^2/sqrt(Hz)", ...}``)."""
        out = {f: f"{getattr(self, f):g} {_SI[f]}" for f in _NUMERIC}
        out["heading"] = "unknown" if self.heading is None else f"{self.heading:g} rad"
        return out


#: The presets by name (see the module's table).
GRADES: dict[str, SensorGrade] = {
    "consumer": SensorGrade(
        acc_noise=2e-3, acc_bias=5e-2, acc_bias_walk=1e-4, gyro_noise=1e-4, gyro_bias=5e-3,
        gyro_bias_walk=2e-5, tilt=0.02, heading=None, name="consumer",
        description="consumer MEMS (phones, wearables, hobby IMUs)"),
    "tactical": SensorGrade(
        acc_noise=5e-4, acc_bias=5e-3, acc_bias_walk=1e-5, gyro_noise=2e-5, gyro_bias=5e-5,
        gyro_bias_walk=1e-6, tilt=0.005, heading=None, name="tactical",
        description="tactical grade (industrial MEMS and FOG, automotive GNSS/INS units)"),
    "navigation": SensorGrade(
        acc_noise=5e-5, acc_bias=5e-4, acc_bias_walk=1e-6, gyro_noise=1e-6, gyro_bias=5e-8,
        gyro_bias_walk=1e-8, tilt=0.001, heading=None, name="navigation",
        description="navigation grade (ring-laser and high-end fibre-optic gyro systems)"),
}


def grade(name: str) -> SensorGrade:
    """The preset sensor grade called ``name``.

    Parameters
    ----------
    name : {"consumer", "tactical", "navigation"}
        Case-insensitive.

    Returns
    -------
    SensorGrade

    Raises
    ------
    InputError
        For an unknown name, listing the valid ones.

    Examples
    --------
    >>> import bvpnav
    >>> from bvpnav.sensors import grade
    >>> grade("navigation").gyro_bias  # rad/s
    5e-08
    >>> try:
    ...     grade("military")
    ... except bvpnav.InputError as exc:
    ...     print(exc)
    grade 'military': unknown sensor grade; valid grades: consumer, tactical, navigation ...
    """
    key = name.strip().lower() if isinstance(name, str) else None
    if key not in GRADES:
        raise InputError(f"grade {name!r}: unknown sensor grade; valid grades: {', '.join(GRADES)} "
                         "(or build your own with bvpnav.sensors.from_datasheet)")
    return GRADES[key]


#: The grade whose priors a strapdown problem with gyro error models gets when it states none.
DEFAULT_GRADE = "consumer"


def resolve_grade(value: Any) -> SensorGrade | None:
    """A :class:`SensorGrade` from a preset name, a grade, or None (no grade).

    Raises
    ------
    InputError
        For anything else, naming the valid forms.

    Examples
    --------
    >>> from bvpnav.sensors import resolve_grade
    >>> resolve_grade("consumer").name, resolve_grade(None)
    ('consumer', None)
    """
    if value is None or isinstance(value, SensorGrade):
        return value
    if isinstance(value, str):
        return grade(value)
    raise InputError(f"grade={value!r}: give a preset name ({', '.join(GRADES)}), a SensorGrade "
                     "(bvpnav.sensors.from_datasheet(...)), or None for no assumed priors")


def _norm_unit(unit: str) -> str:
    u = unit.strip().replace(" ", "").replace("µ", "u").replace("μ", "u").replace("°", "deg")
    u = u.replace("²", "^2").replace("³", "^3").replace("**", "^")
    u = re.sub(r"√\(?(Hz|s|h)\)?", r"sqrt(\1)", u)
    u = re.sub(r"rt(Hz|s|h)\b", r"sqrt(\1)", u)
    u = re.sub(r"sqrt(Hz|s|h)\b", r"sqrt(\1)", u)
    u = u.replace("/hr", "/h").replace("(hr)", "(h)").replace("hz", "Hz").replace("(hz)", "(Hz)")
    u = u.replace("m/s2", "m/s^2").replace("m/s3", "m/s^3")
    return u


def _quantity(value: Any, field_name: str) -> float:
    """One datasheet figure in SI: a number (already SI), ``(value, unit)`` or ``"value unit"``."""
    units = UNITS[field_name]
    if isinstance(value, str):
        m = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.+?)\s*", value)
        if not m:
            raise InputError(f"{field_name}={value!r}: write a number and a unit, e.g. "
                             f"'{1.0} {list(units)[-1]}'; units: {', '.join(units)}")
        value = (float(m.group(1)), m.group(2))
    if isinstance(value, tuple):
        if len(value) != 2 or not isinstance(value[1], str):
            raise InputError(f"{field_name}={value!r}: give (number, unit), e.g. (1.0, {list(units)[-1]!r})")
        number, unit = value
        key = _norm_unit(unit)
        table = {_norm_unit(k): f for k, f in units.items()}
        if key not in table:
            raise InputError(f"{field_name}: unit {unit!r} is not known here; units for {field_name}: "
                             f"{', '.join(units)}")
        return _positive(number, field_name) * table[key]
    return _positive(value, field_name)


def from_datasheet(*, acc_noise: Any = None, acc_bias: Any = None, acc_bias_walk: Any = None,
                   gyro_noise: Any = None, gyro_bias: Any = None, gyro_bias_walk: Any = None,
                   tilt: Any = None, heading: Any = None, base: str | SensorGrade | None = None,
                   one_sided: bool = False, name: str = "custom", description: str = "") -> SensorGrade:
    r"""A :class:`SensorGrade` from datasheet figures in their usual units.

    Parameters
    ----------
    acc_noise, acc_bias, acc_bias_walk, gyro_noise, gyro_bias, gyro_bias_walk, tilt, heading
        Each a number in SI units (as in :class:`SensorGrade`), a pair ``(value, unit)``
        or a string ``"value unit"``, with the units of :data:`UNITS`, e.g.
        ``acc_noise="150 ug/sqrt(Hz)"`` or ``"0.05 m/s/sqrt(h)"`` (velocity random walk),
        ``acc_bias="40 mg"``, ``gyro_noise="0.005 deg/s/sqrt(Hz)"`` or
        ``"0.2 deg/sqrt(h)"`` (angle random walk), ``gyro_bias="10 deg/h"``,
        ``gyro_bias_walk="30 deg/h/sqrt(h)"`` (rate random walk), ``tilt="1 deg"``.
        ``µ``, ``°``, ``√Hz`` and ``rtHz`` are understood. A figure not given is taken from
        ``base``; ``heading`` not given is unknown (None) unless ``base`` has one.
    base : str or SensorGrade, optional
        A preset name or grade supplying the figures not given; without it every figure
        but ``heading`` is required.
    one_sided : bool
        True when the two noise densities are one-sided spectral densities (as most MEMS
        datasheets quote them): they are divided by :math:`\sqrt 2` to give the
        continuous-time intensity (see :meth:`SensorGrade.sigma_a`). Default False (the
        figure is used as the intensity, the conservative choice).
    name, description : str
        Labels of the result.

    Returns
    -------
    SensorGrade

    Notes
    -----
    Conversions (:math:`g_0` = 9.80665 m/s^2): 1 ug = :math:`10^{-6} g_0` m/s^2;
    1 mg = :math:`10^{-3} g_0` m/s^2; 1 m/s/sqrt(h) = 1/60 m/s^2/sqrt(Hz);
    1 deg/sqrt(h) = :math:`\pi/180/60` rad/s/sqrt(Hz); 1 deg/h = :math:`\pi/180/3600`
    rad/s; 1 deg/h/sqrt(h) = :math:`\pi/180/3600/60` rad/s/sqrt(s). A datasheet's *bias
    instability* (the Allan-deviation floor) is not a random walk; taking
    ``gyro_bias_walk`` = instability / sqrt(interval) for the error model's knot interval
    is a common and rough substitute when no rate random walk is given.

    Examples
    --------
    A datasheet's numbers in its own units; what it does not give comes from ``base``:

    >>> from bvpnav.sensors import from_datasheet
    >>> mine = from_datasheet(acc_noise="150 ug/sqrt(Hz)", acc_bias="40 mg", base="consumer")
    >>> print(f"{mine.acc_noise:.3e} m/s^2/sqrt(Hz), {mine.acc_bias:.4f} m/s^2")
    1.471e-03 m/s^2/sqrt(Hz), 0.3923 m/s^2
    >>> mine.gyro_noise == from_datasheet(base="consumer").gyro_noise
    True
    """
    if not isinstance(one_sided, bool):
        raise InputError(f"one_sided={one_sided!r}: give True (one-sided densities) or False")
    given = {"acc_noise": acc_noise, "acc_bias": acc_bias, "acc_bias_walk": acc_bias_walk,
             "gyro_noise": gyro_noise, "gyro_bias": gyro_bias, "gyro_bias_walk": gyro_bias_walk,
             "tilt": tilt, "heading": heading}
    ref = grade(base) if isinstance(base, str) else base
    if ref is not None and not isinstance(ref, SensorGrade):
        raise InputError(f"base={base!r}: give a preset name ({', '.join(GRADES)}) or a SensorGrade")
    values: dict[str, Any] = {}
    for f, v in given.items():
        if v is None:
            continue
        if f == "heading" and isinstance(v, float) and v == math.inf:
            values[f] = v  # unknown heading, also over a base that has one
            continue
        values[f] = _quantity(v, f)
        if one_sided and f in ("acc_noise", "gyro_noise"):
            values[f] /= math.sqrt(2.0)
    missing = [f for f in _NUMERIC if f not in values and ref is None]
    if missing:
        raise InputError(f"from_datasheet: {', '.join(missing)} not given; give them (with units), or "
                         f"base='consumer' / 'tactical' / 'navigation' to take the rest from a preset")
    if ref is not None:
        return replace(ref, **values, name=name, description=description)
    return SensorGrade(**values, name=name, description=description)
