"""Named, seeded scenarios from the papers: data, truth and the information known.

Each scenario function returns a :class:`Scenario`; :data:`SCENARIOS` maps the names
used by the command line (``bvpnav demo NAME``, ``bvpnav simulate NAME``) to them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .imu import ImuData

__all__ = ["Scenario", "tikhonov2011", "walking", "quintic_trajectory", "cubic_prior", "SCENARIOS"]


@dataclass(eq=False)
class Scenario:
    """A simulated recording with its truth.

    Attributes
    ----------
    name : str
    data : ImuData
        The erroneous measurements.
    position, velocity : ndarray, shape (N,) or (N, d)
        True positions (m) and velocities (m/s) at the sample times.
    boundary : dict
        Known boundary values: ``r0``, ``r1`` (m), ``v0``, ``v1`` (m/s) at ``t0``, ``t1`` (s).
    params : dict
        The simulation's parameters (scale, bias, noise, seed, ...).
    prior : callable, optional
        A rough prior trajectory ``t -> position`` (m), where the scenario has one.
    """

    name: str
    data: ImuData
    position: np.ndarray
    velocity: np.ndarray
    boundary: dict
    params: dict = field(default_factory=dict)
    prior: Callable | None = None

    @property
    def t(self) -> np.ndarray:
        """Sample times, s."""
        return self.data.t


def quintic_trajectory():
    """The 2011 paper's reference trajectory on [0, 10] s.

    Returns
    -------
    p, v, a : numpy.polynomial.Polynomial
        Position (m), velocity (m/s) and acceleration (m/s^2) as functions of t (s).

    Notes
    -----
    The fifth-order polynomial with :math:`p(0) = 0`, :math:`p(5) = -10`, :math:`p(10) = 10` m
    and zero velocity at 0, 5 and 10 s.
    """
    knots = (0.0, 5.0, 10.0)
    A = np.array([[t**k for k in range(6)] for t in knots]
                 + [[k * t ** (k - 1) if k else 0.0 for k in range(6)] for t in knots])
    p = np.polynomial.Polynomial(np.linalg.solve(A, [0.0, -10.0, 10.0, 0.0, 0.0, 0.0]))
    return p, p.deriv(), p.deriv(2)


def cubic_prior(t0: float, t1: float, r0: float, r1: float, v0: float, v1: float):
    """The lowest-order polynomial through four boundary values (the 2011 paper's prior).

    Returns
    -------
    numpy.polynomial.Polynomial
        ``t -> position`` in m, with the given positions (m) and velocities (m/s) at
        ``t0`` and ``t1`` (s).
    """
    B = np.array([[1.0, t0, t0**2, t0**3], [0.0, 1.0, 2 * t0, 3 * t0**2],
                  [1.0, t1, t1**2, t1**3], [0.0, 1.0, 2 * t1, 3 * t1**2]])
    return np.polynomial.Polynomial(np.linalg.solve(B, [r0, v0, r1, v1]))


def tikhonov2011(rate: float = 50.0, scale: float = 0.05, bias: float = -0.5,
                 noise: float = 1.0, seed: int = 0) -> Scenario:
    """The 2011 paper's Example 1: a quintic trajectory and an erroneous accelerometer.

    Parameters
    ----------
    rate : float
        Sampling rate in Hz (the paper: 50 Hz, N = 501).
    scale : float
        Scale-factor error s (dimensionless).
    bias : float
        Bias mu in m/s^2.
    noise : float
        White-noise standard deviation in m/s^2 (the paper: variance 1).
    seed : int
        Seed of numpy's default generator.

    Notes
    -----
    The measurement is :math:`\\hat a(t) = (1 + s) a(t) + \\mathcal N(\\mu, \\sigma^2)`.
    """
    p, v, a = quintic_trajectory()
    n = int(round(10.0 * rate)) + 1
    t = np.linspace(0.0, 10.0, n)
    rng = np.random.default_rng(seed)
    acc = (1.0 + scale) * a(t) + rng.normal(bias, noise, n)
    boundary = {"t0": 0.0, "t1": 10.0, "r0": 0.0, "r1": 10.0, "v0": 0.0, "v1": 0.0}
    return Scenario(
        name="tikhonov2011", data=ImuData(t=t, acc=acc), position=p(t), velocity=v(t),
        boundary=boundary,
        params={"rate": rate, "scale": scale, "bias": bias, "noise": noise, "seed": seed},
        prior=cubic_prior(0.0, 10.0, 0.0, 10.0, 0.0, 0.0),
    )


SCENARIOS: dict[str, Callable[..., Scenario]] = {"tikhonov2011": tikhonov2011}


def walking(rate: float = 100.0, n_strides: int = 10, *, stride_time: float = 1.0,
            stance_fraction: float = 0.4, stride_length: float = 1.4, lift: float = 0.12,
            pitch: float = 0.6, stand: float = 1.5, accel_noise: float = 0.03, gyro_noise: float = 0.008,
            accel_bias: float = 0.02, gyro_bias: float = 0.001, seed: int = 0) -> Scenario:
    """A foot-mounted strapdown IMU of a person walking, with the true stance phases.

    The foot stands still for ``stand`` s, takes ``n_strides`` strides (a swing, then a
    stance in which the foot is exactly still) and stands still for ``stand`` s again.
    Each swing moves the foot ``stride_length`` forward along the current heading on a
    minimum-jerk profile, lifts it by ``lift`` and pitches it toe-down (push-off) then
    toe-up (before heel strike); heading and roll change a little from stride to stride.
    Stride times, lengths, lifts and turns vary by a few per cent (drawn from ``seed``).

    Parameters
    ----------
    rate : float
        Sampling rate, Hz.
    n_strides : int
        Number of strides (swings), >= 1.
    stride_time : float
        Mean stride duration (one swing plus one stance), s; about 1 s for walking.
    stance_fraction : float
        Share of each stride in which the foot is still (0 < share < 1).
    stride_length : float
        Mean forward displacement of the foot per stride, m.
    lift : float
        Mean foot clearance at mid-swing, m.
    pitch : float
        Peak toe-down pitch of the foot in the swing, rad (the toe-up peak before heel
        strike follows from the profile, about a third of it).
    stand : float
        Time standing still before the first and after the last stride, s.
    accel_noise, gyro_noise : float
        White-noise standard deviation per sample of the accelerometers (m/s^2) and the
        gyros (rad/s).
    accel_bias, gyro_bias : float
        Magnitude of a constant bias vector of the accelerometer triad (m/s^2) and of the
        gyro triad (rad/s) (fixed directions).
    seed : int
        Seed of the stride variations and of the sensor noise.

    Returns
    -------
    Scenario
        ``data`` is strapdown :class:`~bvpnav.imu.ImuData` built with
        :meth:`~bvpnav.imu.ImuData.from_gyro` from the measured specific force and gyro
        rates (so ``data.gyro`` is set; the attitude is integrated from the true initial
        attitude). ``position`` and ``velocity`` (N, 3) are the truth (m, m/s, navigation
        frame z up); ``boundary`` has the positions and (zero) velocities at both ends.
        ``params`` has the arguments plus ``"stance"``, the true per-sample boolean mask
        (True where the foot is still, ends included), ``"stance_intervals"``, the true
        still intervals ``[(t0, t1), ...]`` in s, and ``"simulation"``, the
        :class:`bvpnav.simulate.Simulation` (true specific force, body rates, attitude).

    Notes
    -----
    In a swing of duration :math:`T` with :math:`\\tau = (t - t_s)/T`, the forward
    displacement is :math:`L(10\\tau^3 - 15\\tau^4 + 6\\tau^5)`, the height
    :math:`64 h \\tau^3 (1 - \\tau)^3` and the pitch proportional to
    :math:`\\tau^3 (1 - \\tau)^3 (1 - \\tau/0.6)`: position, velocity, acceleration,
    attitude and body rate are continuous, and exactly constant (zero rates) in the
    stances. With the defaults the foot reaches about 4.5 m/s and 25 m/s^2 and the gyros
    about 6 rad/s, as foot-mounted IMUs measure in walking. The sensors read
    :math:`\\hat u = u + b + n` (see :class:`bvpnav.simulate.SensorErrors`).
    """
    from scipy.interpolate import PPoly

    from .errors import InputError
    from .simulate import Motion, SensorErrors, simulate_imu

    if not (isinstance(n_strides, (int, np.integer)) and n_strides >= 1):
        raise InputError(f"n_strides={n_strides!r}: give a whole number of strides >= 1")
    if not 0.0 < stance_fraction < 1.0:
        raise InputError(f"stance_fraction={stance_fraction!r}: the still share of a stride must be in "
                         "(0, 1)")
    for name, val in (("rate", rate), ("stride_time", stride_time), ("stand", stand)):
        if not (np.isfinite(val) and val > 0):
            raise InputError(f"{name}={val!r}: must be a positive number")
    rng = np.random.default_rng(seed)
    # (start, duration, kind) of each phase; kind 0 = still, 1 = swing
    strides = stride_time * (1.0 + 0.03 * rng.standard_normal(n_strides))
    lengths = stride_length * (1.0 + 0.05 * rng.standard_normal(n_strides))
    lifts = lift * (1.0 + 0.1 * rng.standard_normal(n_strides))
    turns = 0.05 * rng.standard_normal(n_strides)
    rolls = 0.05 * rng.standard_normal(n_strides)
    durations, kinds = [stand], [0]
    for k in range(n_strides):
        durations += [(1.0 - stance_fraction) * strides[k], stance_fraction * strides[k]]
        kinds += [1, 0]
    durations[-1] = stand  # the last stance is the final stand
    breaks = np.concatenate([[0.0], np.cumsum(durations)])
    t_end = np.ceil(breaks[-1] * rate - 1e-9) / rate  # a whole number of samples
    breaks[-1] = t_end

    tau = np.polynomial.Polynomial([0.0, 1.0])
    minjerk = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    bump = 64 * tau**3 * (1 - tau) ** 3
    tilt = tau**3 * (1 - tau) ** 3 * (1 - tau / 0.6)
    grid = np.linspace(0.0, 1.0, 2001)
    tilt = tilt / tilt(grid).max()

    order = 7
    cpos = np.zeros((order + 1, len(durations), 3))
    ceul = np.zeros((order + 1, len(durations), 3))
    pos = np.zeros(3)
    yaw = 0.0
    swing = 0
    for i, (dur, kind) in enumerate(zip(durations, kinds, strict=True)):
        if kind == 1:
            head = yaw + 0.5 * turns[swing]
            step = lengths[swing] * np.array([np.cos(head), np.sin(head), 0.0])
            comps = [pos[0] + step[0] * minjerk, pos[1] + step[1] * minjerk, pos[2] + lifts[swing] * bump]
            angles = [yaw + turns[swing] * minjerk, pitch * tilt, rolls[swing] * bump]
            for arr, polys in ((cpos, comps), (ceul, angles)):
                for j, p in enumerate(polys):
                    coef = np.zeros(order + 1)
                    coef[:p.coef.size] = p.coef / dur ** np.arange(p.coef.size)  # in powers of t - t_s
                    arr[:, i, j] = coef[::-1]
            pos = pos + step
            yaw += turns[swing]
            swing += 1
        else:
            cpos[-1, i] = pos
            ceul[-1, i] = (yaw, 0.0, 0.0)
    motion = Motion(position=PPoly(cpos, breaks), euler=PPoly(ceul, breaks))
    accel = SensorErrors(bias=accel_bias * np.array([0.6, -0.48, 0.64]), noise=accel_noise)
    gyro = SensorErrors(bias=gyro_bias * np.array([-0.48, 0.64, 0.6]), noise=gyro_noise)
    sim = simulate_imu(motion, rate, t0=0.0, t1=t_end, accel=accel, gyro=gyro, seed=seed)
    t = sim.t
    still = [(float(breaks[i]), float(breaks[i + 1])) for i, kind in enumerate(kinds) if kind == 0]
    stance = np.zeros(t.size, dtype=bool)
    for a, b in still:
        stance |= (t >= a - 1e-9) & (t <= b + 1e-9)
    data = ImuData.from_gyro(t, sim.specific_force, sim.gyro, initial_attitude=sim.attitude[0])
    position, velocity = sim.position(t), sim.velocity(t)
    boundary = {"t0": float(t[0]), "t1": float(t[-1]), "r0": position[0], "r1": position[-1],
                "v0": np.zeros(3), "v1": np.zeros(3)}
    params = {"rate": rate, "n_strides": int(n_strides), "stride_time": stride_time,
              "stance_fraction": stance_fraction, "stride_length": stride_length, "lift": lift,
              "pitch": pitch, "stand": stand, "accel_noise": accel_noise, "gyro_noise": gyro_noise,
              "accel_bias": accel_bias, "gyro_bias": gyro_bias, "seed": seed, "stance": stance,
              "stance_intervals": still, "simulation": sim}
    return Scenario(name="walking", data=data, position=position, velocity=velocity, boundary=boundary,
                    params=params)
