r"""Seeded synthetic inertial data with known truth (the papers' scenarios and more).

A :class:`Motion` is a smooth position history (a cubic spline, m, navigation frame)
and an attitude history (cubic splines of yaw, pitch and roll, rad). From it
:func:`simulate_imu` samples body-frame specific force and gyro rates and corrupts
them with the sensor model of :mod:`bvpnav.error_models`:

.. math:: \hat u = (I + \mathrm{diag}(s))(I + \Theta)\, u + b + n, \qquad n \sim N(0, \sigma^2)

(``u`` the true specific force in m/s^2, or the true body rate in rad/s).

Exactness: the acceleration of a cubic spline is linear between its knots. When the
waypoint times are sample times (``Motion.from_waypoints`` with waypoints on the
sampling grid), the sampled acceleration interpolated linearly *is* the true
acceleration, so the FEM solution of noise-free data is exact to rounding: any
remaining error in a test is the estimator's, not the discretisation's.

Conventions: navigation frame z up, gravity ``(0, 0, -9.80665)`` m/s^2 by default;
attitude is body to navigation (``v_nav = C v_body``), Euler angles are scipy's
intrinsic ``"ZYX"`` (yaw, pitch, roll); gyro rates are body-frame, rad/s.

Examples
--------
Noise-free data of a motion whose waypoints lie on the sampling grid are solved exactly
(to rounding) from the two end positions and the initial velocity:

>>> import numpy as np
>>> from bvpnav import simulate
>>> motion = simulate.Motion.from_waypoints([0.0, 1.0, 2.0], [[0, 0, 0], [1, 0, 0], [2, 1, 0]])
>>> import bvpnav
>>> from bvpnav.constraints import Position, Velocity
>>> sim = simulate.simulate_imu(motion, rate=10.0)
>>> prob = bvpnav.NavigationProblem(sim.imu_data()).add(
...     Position(t=[0.0, 2.0], value=[[0, 0, 0], [2, 1, 0]]), Velocity(t=0.0, value=[0, 0, 0]))
>>> err = np.abs(prob.solve(solver="direct").position() - sim.position(sim.t)).max()
>>> bool(err < 1e-9)
True
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from .errors import InputError
from .imu import STANDARD_GRAVITY, ImuData

__all__ = [
    "SensorErrors",
    "Motion",
    "Simulation",
    "simulate_imu",
    "sample_times",
    "zyx_body_rate",
    "strapdown_3d_2010",
    "RateTable",
    "rate_table",
    "RATE_TABLE_RADIUS",
]

AXES = ("x", "y", "z")


# ----------------------------------------------------------------- sensor errors
@dataclass(frozen=True)
class SensorErrors:
    r"""Deterministic errors and white noise of a sensor triad (or a single sensor).

    Parameters
    ----------
    bias : float or array_like
        Constant bias per axis (m/s^2 for accelerometers, rad/s for gyros).
    scale : float or array_like
        Scale-factor error per axis, dimensionless (0.01 reads 1 % high).
    misalignment : float, array_like (n, n) or dict
        ``Theta_ij`` in rad (zero diagonal): how much of axis ``j`` sensor ``i`` picks
        up. A dict like ``{"xy": 1e-3}`` sets single entries; 0 means none.
    noise : float or array_like
        White-noise standard deviation per sample and axis (sensor units).

    Notes
    -----
    :math:`\hat u = (I + \mathrm{diag}(s))(I + \Theta) u + b + n`, the convention the
    error models in :mod:`bvpnav.error_models` invert.

    Examples
    --------
    An accelerometer triad reading 0.1 m/s^2 high on every axis:

    >>> import numpy as np
    >>> from bvpnav import simulate
    >>> motion = simulate.Motion.from_waypoints([0.0, 1.0, 2.0], [[0, 0, 0], [1, 0, 0], [2, 1, 0]])
    >>> sim = simulate.simulate_imu(motion, rate=10.0, accel=simulate.SensorErrors(bias=0.1))
    >>> (np.round(sim.specific_force - sim.specific_force_true, 9) + 0.0)[0].tolist()
    [0.1, 0.1, 0.1]
    """

    bias: Any = 0.0
    scale: Any = 0.0
    misalignment: Any = 0.0
    noise: Any = 0.0

    def _vec(self, v, n: int, what: str) -> np.ndarray:
        a = np.asarray(v, dtype=float).ravel()
        if a.size == 1:
            a = np.full(n, float(a[0]))
        if a.size != n or not np.all(np.isfinite(a)):
            raise InputError(f"SensorErrors.{what}: expected 1 or {n} finite values, got {v!r}")
        return a

    def theta(self, n: int) -> np.ndarray:
        """Misalignment matrix ``Theta`` (n, n), rad."""
        m = self.misalignment
        if isinstance(m, dict):
            out = np.zeros((n, n))
            for key, val in m.items():
                if len(key) != 2 or key[0] not in AXES[:n] or key[1] not in AXES[:n] or key[0] == key[1]:
                    raise InputError(
                        f"SensorErrors.misalignment: key {key!r}; use two different axes like 'xy'"
                    )
                out[AXES.index(key[0]), AXES.index(key[1])] = float(val)
            return out
        a = np.asarray(m, dtype=float)
        if a.ndim == 0:
            if float(a) != 0.0:
                raise InputError("SensorErrors.misalignment: give a (n, n) matrix or a dict, not a scalar")
            return np.zeros((n, n))
        if a.shape != (n, n) or np.any(np.diag(a) != 0) or not np.all(np.isfinite(a)):
            raise InputError(f"SensorErrors.misalignment: expected ({n}, {n}) finite with zero diagonal")
        return a

    def matrix(self, n: int) -> np.ndarray:
        """``D = (I + diag(s))(I + Theta)``, dimensionless."""
        return np.diag(1.0 + self._vec(self.scale, n, "scale")) @ (np.eye(n) + self.theta(n))

    def apply(self, true, rng: np.random.Generator) -> np.ndarray:
        """Corrupt true values (N, n) with these errors; draws ``N x n`` normals from ``rng``."""
        u = np.asarray(true, dtype=float)
        n = u.shape[1]
        noise = self._vec(self.noise, n, "noise")
        if np.any(noise < 0):
            raise InputError("SensorErrors.noise: standard deviations must be >= 0")
        out = u @ self.matrix(n).T + self._vec(self.bias, n, "bias")
        z = rng.standard_normal(u.shape)
        return out + z * noise


# ------------------------------------------------------------------------ motion
def sample_times(t0: float, t1: float, rate: float) -> np.ndarray:
    """Uniform sample times ``t0 + k / rate`` (s) covering ``[t0, t1]``.

    ``(t1 - t0) * rate`` must be (close to) an integer so that ``t1`` is a sample.

    Examples
    --------
    >>> from bvpnav.simulate import sample_times
    >>> sample_times(0.0, 1.0, 4.0).tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    if not (np.isfinite(rate) and rate > 0):
        raise InputError(f"rate={rate!r}: must be a positive number of samples per s")
    steps = (t1 - t0) * rate
    k = int(round(steps))
    if k < 2 or abs(steps - k) > 1e-6 * max(1.0, steps):
        raise InputError(
            f"window [{t0}, {t1}] s at {rate} Hz is {steps:g} steps; choose a rate that gives a "
            "whole number (>= 2) of steps"
        )
    return t0 + np.arange(k + 1) / rate


def zyx_body_rate(angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
    r"""Body angular rate (N, 3), rad/s, from yaw, pitch, roll (N, 3) in rad (scipy ``"ZYX"``)
    and their rates (N, 3) in rad/s.

    Notes
    -----
    .. math::

        \omega_b = \begin{bmatrix} \dot\phi - \dot\psi\sin\theta \\
            \dot\theta\cos\phi + \dot\psi\cos\theta\sin\phi \\
            -\dot\theta\sin\phi + \dot\psi\cos\theta\cos\phi \end{bmatrix}

    with yaw :math:`\psi`, pitch :math:`\theta` and roll :math:`\phi`.

    Examples
    --------
    A yaw rate of 0.5 rad/s, level: 0.5 rad/s about the body z axis; at a pitch of +90
    degrees: -0.5 rad/s about the body x axis:

    >>> import numpy as np
    >>> from bvpnav.simulate import zyx_body_rate
    >>> zyx_body_rate(np.array([[0.0, 0.0, 0.0]]), np.array([[0.5, 0.0, 0.0]])).tolist()
    [[0.0, 0.0, 0.5]]
    >>> pitched = zyx_body_rate(np.array([[0.0, np.pi / 2, 0.0]]), np.array([[0.5, 0.0, 0.0]]))
    >>> (np.round(pitched, 9) + 0.0).tolist()
    [[-0.5, 0.0, 0.0]]
    """
    _, th, ph = np.asarray(angles, dtype=float).T
    dps, dth, dph = np.asarray(rates, dtype=float).T
    return np.column_stack([
        dph - dps * np.sin(th),
        dth * np.cos(ph) + dps * np.cos(th) * np.sin(ph),
        -dth * np.sin(ph) + dps * np.cos(th) * np.cos(ph),
    ])

@dataclass(frozen=True, eq=False)
class Motion:
    """A smooth position and attitude history.

    Parameters
    ----------
    position : scipy.interpolate.CubicSpline (or PPoly)
        Position in m, navigation frame, vector-valued (d components, usually 3).
    euler : scipy.interpolate.CubicSpline, optional
        Yaw, pitch, roll in rad (scipy ``"ZYX"`` intrinsic); default level, heading 0.

    Notes
    -----
    The body rate follows from the Euler rates (:func:`zyx_body_rate`).

    Examples
    --------
    Cubic splines through waypoints (put on the sampling grid) and level, heading 0:

    >>> import numpy as np
    >>> from bvpnav import simulate
    >>> motion = simulate.Motion.from_waypoints([0.0, 1.0, 2.0], [[0, 0, 0], [1, 0, 0], [2, 1, 0]])
    >>> (np.round(motion.pos([1.0]), 9) + 0.0).tolist()  # m
    [[1.0, 0.0, 0.0]]
    """

    position: Any
    euler: Any = None

    @classmethod
    def from_waypoints(cls, t, position, euler=None, bc_type="clamped") -> Motion:
        """Cubic splines through waypoints.

        Parameters
        ----------
        t : array_like, shape (K,)
            Waypoint times, s (put them on the sampling grid for exact FEM data).
        position : array_like, shape (K, d)
            Positions, m.
        euler : array_like, shape (K, 3), optional
            Yaw, pitch, roll, rad.
        bc_type : str
            Spline end conditions; ``"clamped"`` starts and ends at rest.
        """
        t = np.asarray(t, dtype=float)
        pos = np.asarray(position, dtype=float)
        if pos.ndim == 1:
            pos = pos[:, None]
        if pos.shape[0] != t.size:
            raise InputError(f"position: {pos.shape[0]} waypoints for {t.size} times")
        eul = None
        if euler is not None:
            e = np.asarray(euler, dtype=float)
            if e.shape != (t.size, 3):
                raise InputError(
                    f"euler: expected shape ({t.size}, 3) (yaw, pitch, roll in rad), got {e.shape}"
                )
            eul = CubicSpline(t, e, bc_type=bc_type)
        return cls(CubicSpline(t, pos, bc_type=bc_type), eul)

    @property
    def t0(self) -> float:
        """Start of the motion, s."""
        return float(self.position.x[0])

    @property
    def t1(self) -> float:
        """End of the motion, s."""
        return float(self.position.x[-1])

    def pos(self, t) -> np.ndarray:
        """Position (N, d), m."""
        return np.atleast_2d(self.position(t, 0))

    def vel(self, t) -> np.ndarray:
        """Velocity (N, d), m/s."""
        return np.atleast_2d(self.position(t, 1))

    def acc(self, t) -> np.ndarray:
        """Acceleration (N, d), m/s^2."""
        return np.atleast_2d(self.position(t, 2))

    def angles(self, t) -> np.ndarray:
        """Yaw, pitch, roll (N, 3), rad."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if self.euler is None:
            return np.zeros((t.size, 3))
        return np.atleast_2d(self.euler(t))

    def attitude(self, t) -> Rotation:
        """Body-to-navigation attitude per time."""
        return Rotation.from_euler("ZYX", self.angles(t))

    def body_rate(self, t) -> np.ndarray:
        """Body angular rate (N, 3), rad/s (see class Notes)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if self.euler is None:
            return np.zeros((t.size, 3))
        return zyx_body_rate(np.atleast_2d(self.euler(t)), np.atleast_2d(self.euler(t, 1)))


# -------------------------------------------------------------------- simulation
@dataclass(eq=False)
class Simulation:
    """Simulated strapdown IMU output with its truth.

    Attributes
    ----------
    t : ndarray (N,)
        Sample times, s.
    specific_force : ndarray (N, 3)
        Measured body-frame specific force, m/s^2.
    gyro : ndarray (N, 3)
        Measured body rates, rad/s.
    attitude : Rotation
        True body-to-navigation attitude per sample.
    gravity : ndarray (3,)
        True gravity vector, m/s^2 (navigation frame).
    truth : pandas.DataFrame
        Index ``t``; true ``x, y, z`` (m), ``vx, vy, vz`` (m/s), ``ax, ay, az`` (m/s^2).
    specific_force_true, body_rate_true : ndarray (N, 3)
        Error-free sensor inputs.
    accel, gyro_errors : SensorErrors
        The errors applied.
    motion : Motion
    seed : int or None

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav import simulate
    >>> motion = simulate.Motion.from_waypoints([0.0, 1.0, 2.0], [[0, 0, 0], [1, 0, 0], [2, 1, 0]])
    >>> sim = simulate.simulate_imu(motion, rate=10.0)
    >>> sim.imu_data()
    ImuData(N=21, axes=('x', 'y', 'z'), strapdown, t=[0, 2] s)
    >>> sim.truth.loc[1.0, ["x", "vx", "vy", "ay"]].round(3).tolist()  # m, m/s, m/s, m/s^2
    [1.0, 1.5, 0.75, 3.0]
    """

    t: np.ndarray
    specific_force: np.ndarray
    gyro: np.ndarray
    attitude: Rotation
    gravity: np.ndarray
    truth: pd.DataFrame
    specific_force_true: np.ndarray
    body_rate_true: np.ndarray
    accel: SensorErrors
    gyro_errors: SensorErrors
    motion: Motion
    seed: Any = None
    info: dict = field(default_factory=dict)

    def imu_data(self, attitude: str = "true", gravity=None, initial=None) -> ImuData:
        """The measurements as :class:`bvpnav.ImuData` (strapdown).

        Parameters
        ----------
        attitude : {"true", "gyro"}
            Use the true attitude, or integrate the measured gyro rates from
            ``initial`` (default: the true initial attitude).
        gravity : array_like (3,), optional
            Nominal gravity given to the data (m/s^2); default ``(0, 0, -9.80665)``.
            The truth may differ (``self.gravity``): that is what ``UnknownGravity``
            estimates.
        """
        g = np.array([0.0, 0.0, -STANDARD_GRAVITY]) if gravity is None else gravity
        if attitude == "true":
            return ImuData(self.t, specific_force=self.specific_force, attitude=self.attitude, gravity=g)
        if attitude == "gyro":
            init = self.attitude[0] if initial is None else initial
            return ImuData.from_gyro(self.t, self.specific_force, self.gyro, initial_attitude=init, gravity=g)
        raise InputError(f"attitude={attitude!r}; choose 'true' or 'gyro'")

    def position(self, t) -> np.ndarray:
        """True position at any times (N, 3), m."""
        return self.motion.pos(t)

    def velocity(self, t) -> np.ndarray:
        """True velocity at any times (N, 3), m/s."""
        return self.motion.vel(t)


def simulate_imu(
    motion: Motion,
    rate: float,
    *,
    t0: float | None = None,
    t1: float | None = None,
    accel: SensorErrors | None = None,
    gyro: SensorErrors | None = None,
    gravity=None,
    seed: int | None = None,
) -> Simulation:
    r"""Sample a motion as a strapdown IMU would see it.

    Parameters
    ----------
    motion : Motion
        3-D position (m) and attitude history.
    rate : float
        Sampling rate, Hz.
    t0, t1 : float, optional
        Window, s; default the motion's.
    accel, gyro : SensorErrors, optional
        Accelerometer (m/s^2) and gyro (rad/s) errors; default none.
    gravity : array_like (3,), optional
        True gravity, m/s^2; default ``(0, 0, -9.80665)``.
    seed : int, optional
        Seed of ``numpy.random.default_rng``; accelerometer noise is drawn first,
        then gyro noise, so a seed fixes both.

    Returns
    -------
    Simulation

    Notes
    -----
    :math:`f = C^T (\ddot r - g)` (specific force, body frame) and
    :math:`\omega = \omega_b` from the Euler rates; then the sensor model of
    :class:`SensorErrors` is applied.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav import simulate
    >>> motion = simulate.Motion.from_waypoints([0.0, 1.0, 2.0], [[0, 0, 0], [1, 0, 0], [2, 1, 0]])
    >>> sim = simulate.simulate_imu(motion, rate=10.0, gyro=simulate.SensorErrors(noise=1e-3), seed=0)
    >>> sim.t.size, sim.gyro.shape
    (21, (21, 3))
    >>> bool(np.abs(sim.gyro - sim.body_rate_true).max() < 5e-3)  # the noise, 1e-3 rad/s per sample
    True
    """
    t0 = motion.t0 if t0 is None else float(t0)
    t1 = motion.t1 if t1 is None else float(t1)
    t = sample_times(t0, t1, rate)
    g = np.array([0.0, 0.0, -STANDARD_GRAVITY]) if gravity is None else np.asarray(gravity, float)
    if g.shape != (3,):
        raise InputError("gravity: expected 3 components in m/s^2")
    pos, vel, acc = motion.pos(t), motion.vel(t), motion.acc(t)
    if pos.shape[1] != 3:
        raise InputError(f"motion: strapdown simulation needs a 3-D position, got {pos.shape[1]} axes")
    att = motion.attitude(t)
    f_true = att.inv().apply(acc - g)
    w_true = motion.body_rate(t)
    accel = SensorErrors() if accel is None else accel
    gyro_e = SensorErrors() if gyro is None else gyro
    rng = np.random.default_rng(seed)
    f_meas = accel.apply(f_true, rng)
    w_meas = gyro_e.apply(w_true, rng)
    idx = pd.Index(t, name="t")
    cols = {}
    for k, a in enumerate(AXES):
        cols[a] = pos[:, k]
    for k, a in enumerate(AXES):
        cols["v" + a] = vel[:, k]
    for k, a in enumerate(AXES):
        cols["a" + a] = acc[:, k]
    return Simulation(t=t, specific_force=f_meas, gyro=w_meas, attitude=att, gravity=g,
                      truth=pd.DataFrame(cols, index=idx), specific_force_true=f_true,
                      body_rate_true=w_true, accel=accel, gyro_errors=gyro_e, motion=motion, seed=seed,
                      info={"rate": float(rate)})


# ----------------------------------------------------------- 2010, Section 5.3
def strapdown_3d_2010(
    rate: float = 100.0,
    duration: float = 20.0,
    *,
    accel: SensorErrors | None = None,
    gravity=(0.03, -0.02, -9.815),
    noise: float = 0.0,
    seed: int | None = 0,
) -> Simulation:
    """A 3-D motion with attitude changes for the nine-parameter model (2010, Sec. 5.3).

    Parameters
    ----------
    rate : float
        Sampling rate, Hz (``rate`` must be a whole number so waypoints are samples).
    duration : float
        Length of the recording, s (a whole number; waypoints every 1 s).
    accel : SensorErrors, optional
        Accelerometer errors; default consumer grade: bias ``(0.12, -0.15, 0.2)`` m/s^2,
        scale ``(0.01, -0.02, 0.015)``, white noise ``noise``.
    gravity : array_like (3,)
        True gravity, m/s^2. It differs from the nominal ``(0, 0, -9.80665)`` by a
        local-g error and a tilt-like horizontal part (the paper's unknown gravity).
    noise : float
        Accelerometer white-noise standard deviation per sample, m/s^2 (used when
        ``accel`` is not given).
    seed : int, optional
        Noise seed. The trajectory itself is fixed (its own seed), so different seeds
        give the same motion with different noise.

    Returns
    -------
    Simulation
        Starts and ends at rest; positions wander a few metres, yaw turns through
        about one revolution and pitch/roll swing by up to ~35 degrees, so body-frame
        biases and the navigation-frame gravity are distinguishable.

    Examples
    --------
    >>> from bvpnav.simulate import strapdown_3d_2010
    >>> sim = strapdown_3d_2010(rate=20.0, duration=4.0)
    >>> sim.imu_data()
    ImuData(N=81, axes=('x', 'y', 'z'), strapdown, t=[0, 4] s)
    >>> sim.gravity.tolist()  # the paper's slightly tilted gravity, m/s^2
    [0.03, -0.02, -9.815]
    """
    duration = float(duration)
    if duration < 4 or abs(duration - round(duration)) > 1e-9:
        raise InputError(f"duration={duration!r}: give a whole number of seconds >= 4")
    if abs(rate - round(rate)) > 1e-9:
        raise InputError(f"rate={rate!r}: give a whole number of Hz so that waypoints are samples")
    shape_rng = np.random.default_rng(2010)
    tw = np.arange(int(round(duration)) + 1, dtype=float)
    steps = shape_rng.normal(0.0, 1.5, size=(tw.size, 3))
    steps[:, 2] *= 0.3
    steps[0] = 0.0
    pos = np.cumsum(steps, axis=0)
    pos[-1] = pos[-2]  # come to rest
    yaw = 2.0 * np.pi * tw / duration + 0.4 * np.sin(1.3 * tw)
    pitch = 0.6 * np.sin(2.0 * np.pi * tw / 7.0) * np.sin(np.pi * tw / duration)
    roll = 0.6 * np.sin(2.0 * np.pi * tw / 5.0 + 0.5) * np.sin(np.pi * tw / duration)
    motion = Motion.from_waypoints(tw, pos, np.column_stack([yaw, pitch, roll]))
    if accel is None:
        accel = SensorErrors(bias=(0.12, -0.15, 0.2), scale=(0.01, -0.02, 0.015), noise=noise)
    sim = simulate_imu(motion, rate, accel=accel, gravity=gravity, seed=seed)
    sim.info.update(scenario="strapdown_3d_2010", duration=duration)
    return sim


# ------------------------------------------------------ 2010, Example 1 (Sec. 6)
#: Rate-table radius (m): the paper's test 1 covers 7 revolutions = 10.4 m.
RATE_TABLE_RADIUS = 10.4 / (7 * 2.0 * np.pi)

_RATE_TABLE_TESTS = {1: {"repeats": 10, "revolutions": 7.0, "duration": 20.0, "paper_distance": 10.4},
                     2: {"repeats": 50, "revolutions": 62.0, "duration": 100.0, "paper_distance": 92.3}}


@dataclass(eq=False)
class RateTable:
    r"""A tangential accelerometer on a rotating table (2010 paper, Example 1).

    Attributes
    ----------
    t : ndarray (N,)
        Sample times of the motion, s (``0 .. T``).
    acc : ndarray (N,)
        Measured tangential acceleration, m/s^2.
    rest_acc : ndarray
        Measurements while at rest before the motion, m/s^2 (for bias removal).
    position, velocity, acceleration : ndarray (N,)
        True arc length (m), speed (m/s) and tangential acceleration (m/s^2).
    centripetal : ndarray (N,)
        True centripetal acceleration :math:`R\omega^2`, m/s^2.
    radius : float
        m.
    period : float
        Length of one repeat of the angular-velocity profile, s.
    omega_max : float
        Peak angular velocity, rad/s.
    errors : dict
        The bias (m/s^2), scale (1), mounting angle (rad) and noise std (m/s^2) used.
    test : int

    Examples
    --------
    >>> from bvpnav.simulate import rate_table
    >>> table = rate_table(rate=100.0)
    >>> table.data
    ImuData(N=2001, axes=('x',), navigation-frame, t=[0, 20] s)
    >>> print(f"radius {table.radius:.4f} m, arc length {table.position[-1]:.1f} m, at rest again")
    radius 0.2365 m, arc length 10.4 m, at rest again
    >>> float(table.velocity[-1])
    0.0
    """

    t: np.ndarray
    acc: np.ndarray
    rest_acc: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    centripetal: np.ndarray
    radius: float
    period: float
    omega_max: float
    errors: dict
    test: int
    seed: Any = None

    @property
    def data(self) -> ImuData:
        """Navigation-frame (1-axis, along the arc) :class:`bvpnav.ImuData`."""
        return ImuData(self.t, self.acc)

    @property
    def effective_bias(self) -> float:
        """Bias plus the mean centripetal leak, m/s^2: the constant a bias model can absorb."""
        e = self.errors
        return float(e["bias"] + (1.0 + e["scale"]) * np.sin(e["mounting"]) * np.mean(self.centripetal))

    @property
    def duration(self) -> float:
        """T, s."""
        return float(self.t[-1] - self.t[0])

    def truth_at(self, t) -> tuple[np.ndarray, np.ndarray]:
        """True arc length (m) and speed (m/s) at times ``t`` (s)."""
        th, om, _ = _table_profile(np.atleast_1d(np.asarray(t, float)), self.period, self.omega_max)
        return self.radius * th, self.radius * om


def _table_profile(t: np.ndarray, period: float, omega_max: float):
    """Angle (rad), rate (rad/s) and angular acceleration (rad/s^2) of the sin^2 profile."""
    k = np.floor(t / period)
    tau = t - k * period
    x = 2.0 * np.pi * tau / period
    per_rep = omega_max * period / 2.0
    theta = k * per_rep + omega_max * (tau / 2.0 - period / (4.0 * np.pi) * np.sin(x))
    omega = omega_max * np.sin(np.pi * tau / period) ** 2
    alpha = omega_max * np.pi / period * np.sin(x)
    return theta, omega, alpha


def rate_table(
    test: int = 1,
    rate: float = 1000.0,
    *,
    bias: float = 0.2,
    scale: float = 0.01,
    mounting: float = 0.005,
    noise_density: float = 0.002,
    rest: float = 2.0,
    radius: float = RATE_TABLE_RADIUS,
    seed: int | None = 0,
) -> RateTable:
    r"""Simulate the 2010 paper's rate-table tests.

    Parameters
    ----------
    test : {1, 2}
        Test 1: the angular-velocity profile repeated 10 times in 20 s, 7 revolutions.
        Test 2: 50 repeats in 100 s, scaled to 62 revolutions.
    rate : float
        Sampling rate, Hz (the paper: 1000).
    bias : float
        Accelerometer bias, m/s^2.
    scale : float
        Scale-factor error, dimensionless.
    mounting : float
        Angle (rad) by which the sensing axis leans from the tangent towards the axis
        of rotation, so the sensor also sees a share of the centripetal acceleration
        (the paper's sensor was only "approximately" tangential). Its mean acts like
        an extra bias that at-rest averaging cannot see; the rest is not modelled.
    noise_density : float
        White-noise density, m/s^2/sqrt(Hz); the per-sample standard deviation is
        ``noise_density * sqrt(rate / 2)``.
    rest : float
        Seconds of at-rest data recorded before the motion (for methods I and II).
    radius : float
        Distance of the sensor from the axis, m; default ``10.4 / (7 * 2 pi)`` from
        test 1 (test 2 then covers 62 x 1.486 = 92.1 m; the paper quotes 92.3 m).
    seed : int, optional

    Returns
    -------
    RateTable

    Notes
    -----
    The paper shows the profile only as a plot; we use one smooth pulse per repeat,
    :math:`\omega(\tau) = \omega_{max} \sin^2(\pi\tau/P)`, :math:`P = T/\text{repeats} = 2` s,
    which starts and ends each repeat at rest and turns by :math:`\omega_{max} P/2`.
    The sensor reads

    .. math:: \hat a = (1 + s)(R\dot\omega\cos\mu + R\omega^2\sin\mu) + b + n.

    Examples
    --------
    >>> from bvpnav.simulate import rate_table
    >>> table = rate_table(test=1, rate=100.0)
    >>> table.errors["bias"], table.errors["scale"]  # m/s^2, dimensionless
    (0.2, 0.01)
    >>> table.rest_acc.shape  # 2 s at rest before the motion, for the bias
    (200,)
    """
    if test not in _RATE_TABLE_TESTS:
        raise InputError(f"test={test!r}; the paper has tests 1 and 2")
    spec = _RATE_TABLE_TESTS[test]
    T = spec["duration"]
    period = T / spec["repeats"]
    omega_max = spec["revolutions"] * 2.0 * np.pi / spec["repeats"] * 2.0 / period
    t = sample_times(0.0, T, rate)
    theta, omega, alpha = _table_profile(t, period, omega_max)
    theta[-1] = spec["revolutions"] * 2.0 * np.pi  # exact end (the profile restarts at T)
    omega[-1] = 0.0
    alpha[-1] = 0.0
    a_t = radius * alpha
    a_r = radius * omega**2
    sigma = noise_density * np.sqrt(rate / 2.0)
    rng = np.random.default_rng(seed)
    n_rest = int(round(rest * rate))
    rest_meas = bias + sigma * rng.standard_normal(n_rest)
    meas = (1.0 + scale) * (a_t * np.cos(mounting) + a_r * np.sin(mounting)) + bias
    meas = meas + sigma * rng.standard_normal(t.size)
    return RateTable(t=t, acc=meas, rest_acc=rest_meas, position=radius * theta, velocity=radius * omega,
                     acceleration=a_t, centripetal=a_r, radius=radius, period=period, omega_max=omega_max,
                     errors={"bias": bias, "scale": scale, "mounting": mounting, "noise_std": sigma},
                     test=test, seed=seed)
