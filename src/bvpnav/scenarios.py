"""Named, seeded scenarios from the papers: data, truth and the information known.

Each scenario function returns a :class:`Scenario`; :data:`SCENARIOS` maps the names
used by the command line (``bvpnav demo NAME``, ``bvpnav simulate NAME``) to them.

Examples
--------
>>> from bvpnav import scenarios
>>> sorted(scenarios.SCENARIOS)  # the names the command line knows
['tikhonov2011']
>>> sc = scenarios.tikhonov2011(rate=10.0)
>>> sc.data, sc.boundary["r1"]
(ImuData(N=101, axes=('x',), navigation-frame, t=[0, 10] s), 10.0)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .imu import STANDARD_GRAVITY, ImuData

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

    Examples
    --------
    A scenario solved with its known boundary values and compared with its truth:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, Velocity
    >>> sc = bvpnav.scenarios.tikhonov2011(rate=10.0, noise=0.0, scale=0.0, bias=0.0)  # error-free
    >>> b = sc.boundary
    >>> prob = bvpnav.NavigationProblem(sc.data).add(
    ...     Position(t=[b["t0"], b["t1"]], value=[b["r0"], b["r1"]]), Velocity(t=b["t0"], value=b["v0"]))
    >>> err = np.abs(prob.solve(solver="direct").position("x") - sc.position).max()
    >>> print(f"largest error {err:.3f} m")  # the linear elements' discretisation at 10 Hz
    largest error 0.006 m
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

    Examples
    --------
    >>> from bvpnav.scenarios import quintic_trajectory
    >>> p, v, a = quintic_trajectory()
    >>> [round(float(p(t)), 6) + 0.0 for t in (0.0, 5.0, 10.0)]  # m
    [0.0, -10.0, 10.0]
    >>> [round(float(v(t)), 6) + 0.0 for t in (0.0, 5.0, 10.0)]  # m/s
    [0.0, 0.0, 0.0]
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

    Examples
    --------
    >>> from bvpnav.scenarios import cubic_prior
    >>> prior = cubic_prior(0.0, 10.0, 0.0, 10.0, 0.0, 0.0)  # from rest at 0 m to rest at 10 m
    >>> print(f"{prior(5.0):.3f} m")
    5.000 m
    """
    B = np.array([[1.0, t0, t0**2, t0**3], [0.0, 1.0, 2 * t0, 3 * t0**2],
                  [1.0, t1, t1**2, t1**3], [0.0, 1.0, 2 * t1, 3 * t1**2]])
    return np.polynomial.Polynomial(np.linalg.solve(B, [r0, v0, r1, v1]))


def tikhonov2011(rate: float = 50.0, scale: float = 0.05, bias: float = -0.5,
                 noise: float = 1.0, seed: int = 0) -> Scenario:
    r"""The 2011 paper's Example 1: a quintic trajectory and an erroneous accelerometer.

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
    The measurement is :math:`\hat a(t) = (1 + s) a(t) + \mathcal N(\mu, \sigma^2)`.

    Examples
    --------
    >>> from bvpnav.scenarios import tikhonov2011
    >>> sc = tikhonov2011(rate=50.0)
    >>> sc.data.n, sc.params["scale"], sc.params["bias"]  # 5 % scale error, -0.5 m/s^2 bias
    (501, 0.05, -0.5)
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
    r"""A foot-mounted strapdown IMU of a person walking, with the true stance phases.

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
    In a swing of duration :math:`T` with :math:`\tau = (t - t_s)/T`, the forward
    displacement is :math:`L(10\tau^3 - 15\tau^4 + 6\tau^5)`, the height
    :math:`64 h \tau^3 (1 - \tau)^3` and the pitch proportional to
    :math:`\tau^3 (1 - \tau)^3 (1 - \tau/0.6)`: position, velocity, acceleration,
    attitude and body rate are continuous, and exactly constant (zero rates) in the
    stances. With the defaults the foot reaches about 4.5 m/s and 25 m/s^2 and the gyros
    about 6 rad/s, as foot-mounted IMUs measure in walking. The sensors read
    :math:`\hat u = u + b + n` (see :class:`bvpnav.simulate.SensorErrors`).

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.scenarios import walking
    >>> walk = walking(rate=100.0, n_strides=2)
    >>> walk.data
    ImuData(N=462, axes=('x', 'y', 'z'), strapdown, t=[0, 4.61] s)
    >>> d = np.linalg.norm(walk.boundary["r1"] - walk.boundary["r0"])
    >>> print(f"{d:.2f} m")  # two strides of about 1.4 m (lengths vary by a few per cent)
    2.85 m
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


# ----------------------------------------------------------------- car drive (issue 16)
def _grade_table() -> dict[str, dict[str, float | None]]:
    from .sensors import GRADES

    keys = ("acc_noise", "acc_bias", "acc_bias_walk", "gyro_noise", "gyro_bias", "gyro_bias_walk", "tilt",
            "heading")
    return {name: {k: getattr(g, k) for k in keys} for name, g in GRADES.items()}


#: Sensor-grade error numbers as plain dicts, from :data:`bvpnav.sensors.GRADES` (one table).
#: Continuous-time white-noise densities: the per-sample standard deviation is
#: ``density * sqrt(rate_hz)``. Units: acc_noise m/s^2/sqrt(Hz), acc_bias m/s^2, acc_bias_walk
#: m/s^2/sqrt(s), gyro_noise rad/s/sqrt(Hz), gyro_bias rad/s, gyro_bias_walk rad/s/sqrt(s),
#: tilt rad, heading rad (None: unknown).
SENSOR_GRADES: dict[str, dict[str, float | None]] = _grade_table()
__all__ += ["CarDrive", "car_drive", "SENSOR_GRADES"]

# 630 tau^4 (1 - tau)^4 on [0, 1]: a bump of unit area whose value and first three derivatives
# vanish at both ends; its integral is the smooth step of every channel of the drive.
_BUMP = np.polynomial.Polynomial([0.0, 0.0, 0.0, 0.0, 630.0, -2520.0, 3780.0, -2520.0, 630.0])
_STEP = _BUMP.integ()
_ROLL_PER_LATERAL = 0.01  # rad of roll (outward lean) per m/s^2 of lateral acceleration
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(6)


@dataclass(frozen=True)
class _Channel:
    """A scalar ``base + sum_i delta_i S((t - t_i) / T_i)`` with the smooth step S (C^4)."""

    events: tuple[tuple[float, float, float], ...]  # (start s, duration s, change)
    base: float = 0.0

    def __call__(self, t: np.ndarray, nu: int = 0) -> np.ndarray:
        """Value (nu=0) or nu-th time derivative (nu <= 2) at times ``t`` (s)."""
        out = np.full(t.shape, self.base if nu == 0 else 0.0)
        poly = (_STEP, _BUMP, _BUMP.deriv())[nu]
        for t0, dur, delta in self.events:
            tau = (t - t0) / dur
            inside = (tau > 0.0) & (tau < 1.0)
            out[inside] += delta * poly(tau[inside]) / dur**nu
            if nu == 0:
                out[tau >= 1.0] += delta
        return out


@dataclass(frozen=True)
class _CarPath:
    """Speed, heading and climb-angle channels of the drive, and what follows from them."""

    speed: _Channel  # m/s along body x
    yaw: _Channel  # heading, rad from nav x (east) towards y (north)
    climb: _Channel  # flight-path angle, rad, positive nose up

    def velocity(self, t: np.ndarray) -> np.ndarray:
        """Navigation-frame velocity (N, 3), m/s."""
        v, psi, gam = self.speed(t), self.yaw(t), self.climb(t)
        return v[:, None] * np.column_stack([np.cos(psi) * np.cos(gam), np.sin(psi) * np.cos(gam),
                                             np.sin(gam)])

    def acceleration(self, t: np.ndarray) -> np.ndarray:
        """Navigation-frame acceleration (N, 3), m/s^2: the exact derivative of :meth:`velocity`."""
        v, dv = self.speed(t), self.speed(t, 1)
        psi, dpsi = self.yaw(t), self.yaw(t, 1)
        gam, dgam = self.climb(t), self.climb(t, 1)
        cp, sp, cg, sg = np.cos(psi), np.sin(psi), np.cos(gam), np.sin(gam)
        u = np.column_stack([cp * cg, sp * cg, sg])
        du = (dpsi[:, None] * np.column_stack([-sp * cg, cp * cg, np.zeros_like(cg)])
              + dgam[:, None] * np.column_stack([-cp * sg, -sp * sg, cg]))
        return dv[:, None] * u + v[:, None] * du

    def euler(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Yaw, pitch, roll (N, 3) in rad (scipy ``"ZYX"``) and their rates (N, 3) in rad/s."""
        v, dv = self.speed(t), self.speed(t, 1)
        dpsi, ddpsi = self.yaw(t, 1), self.yaw(t, 2)
        roll = _ROLL_PER_LATERAL * v * dpsi
        droll = _ROLL_PER_LATERAL * (dv * dpsi + v * ddpsi)
        # body x along the velocity: ZYX pitch is minus the climb angle (y left, z up)
        ang = np.column_stack([self.yaw(t), -self.climb(t), roll])
        rate = np.column_stack([dpsi, -self.climb(t, 1), droll])
        return ang, rate

    def body_rate(self, t: np.ndarray) -> np.ndarray:
        """Body angular rate relative to the navigation frame (N, 3), rad/s, body axes."""
        from .simulate import zyx_body_rate

        return zyx_body_rate(*self.euler(t))

    def displacement(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """``integral_a^b velocity dt`` per pair (N, 3), m (6-point Gauss-Legendre)."""
        half = 0.5 * (b - a)
        mid = 0.5 * (b + a)
        tt = (mid[:, None] + half[:, None] * _GL_NODES[None, :]).ravel()
        vel = self.velocity(tt).reshape(a.size, _GL_NODES.size, 3)
        return half[:, None] * np.einsum("j,njk->nk", _GL_WEIGHTS, vel)


def _car_schedule(duration: float) -> _CarPath:
    """The drive's manoeuvres laid end to end, cut to fill ``duration`` s (>= 60).

    A stand of 5 s and an acceleration to 12 m/s, then a cycle of manoeuvres (a left turn,
    a stop, a hill, a right turn, an S-curve, a speed-up, a downhill curve, a slow-down, a
    half-circle, a stop) repeated mirrored (the second cycle turns the other way, with lower
    hills) until the next one would not fit; then a cruise, a stop and a stand of 5 s.
    """
    speed: list[tuple[float, float, float]] = []
    yaw: list[tuple[float, float, float]] = []
    climb: list[tuple[float, float, float]] = []
    state = {"t": 5.0, "v": 12.0}
    speed.append((5.0, 12.0, 12.0))
    state["t"] = 17.0
    end_block = 15.0  # final deceleration (10 s) and stand (5 s)

    def cycle(sign: float, hill: float) -> list[tuple[float, list]]:
        deg = np.pi / 180.0
        return [
            (8.0, []),
            (16.0, [("yaw", 0.0, 16.0, sign * 90 * deg)]),
            (28.0, [("stop", 10.0, 6.0, 12.0, 12.0)]),
            (35.0, [("climb", 0.0, 10.0, 0.05 * hill), ("climb", 25.0, 10.0, -0.05 * hill)]),
            (16.0, [("yaw", 0.0, 16.0, -sign * 90 * deg)]),
            (20.0, [("yaw", 0.0, 10.0, sign * 30 * deg), ("yaw", 10.0, 10.0, -sign * 30 * deg)]),
            (10.0, [("speed", 0.0, 10.0, 16.0)]),
            (35.0, [("climb", 0.0, 10.0, -0.06 * hill), ("climb", 25.0, 10.0, 0.06 * hill),
                    ("yaw", 2.5, 30.0, sign * 45 * deg)]),
            (10.0, [("speed", 0.0, 10.0, 10.0)]),
            (40.0, [("yaw", 0.0, 40.0, -sign * 180 * deg)]),
            (8.0, [("speed", 0.0, 8.0, 12.0)]),
            (30.0, [("stop", 10.0, 8.0, 12.0, 12.0)]),
        ]

    def place(length: float, parts: list) -> None:
        t0 = state["t"]
        for kind, *args in parts:
            if kind == "yaw":
                yaw.append((t0 + args[0], args[1], args[2]))
            elif kind == "climb":
                climb.append((t0 + args[0], args[1], args[2]))
            elif kind == "speed":
                speed.append((t0 + args[0], args[1], args[2] - state["v"]))
                state["v"] = args[2]
            else:  # stop: decelerate, stand, accelerate
                dec, hold, acc, v_after = args
                speed.append((t0, dec, -state["v"]))
                speed.append((t0 + dec + hold, acc, v_after))
                state["v"] = v_after
        state["t"] = t0 + length

    k = 0
    done = False
    while not done:
        for length, parts in cycle(1.0 if k % 2 == 0 else -1.0, 1.0 if k % 2 == 0 else 0.7):
            if state["t"] + length > duration - end_block:
                done = True
                break
            place(length, parts)
        k += 1
    state["t"] = duration - end_block
    speed.append((state["t"], 10.0, -state["v"]))
    return _CarPath(_Channel(tuple(speed)), _Channel(tuple(yaw)), _Channel(tuple(climb)))


@dataclass(frozen=True, eq=False)
class CarDrive:
    """A simulated car drive: strapdown IMU output, GNSS fixes and the truth.

    Frames: navigation frame ENU (x east, y north, z up), gravity ``(0, 0, -9.80665)``
    m/s^2; body x forward, y left, z up; attitude ``C`` body to navigation
    (``v_nav = C v_body``); gyro rates are the body's rate relative to the navigation
    frame in body axes (Earth rotation neglected, as bvpnav assumes). The attributes cannot be
    reassigned (the arrays stay writeable: scipy's ``Rotation.apply`` refuses read-only input).

    Attributes
    ----------
    t : ndarray (N,)
        Sample times, s (from 0).
    specific_force : ndarray (N, 3)
        Measured body-frame specific force, m/s^2 (true + accelerometer bias + white noise).
    gyro : ndarray (N, 3)
        Measured body rates, rad/s (true + gyro bias + white noise).
    gravity : ndarray (3,)
        Gravity, m/s^2 (navigation frame).
    position, velocity, acceleration : ndarray (N, 3)
        True position (m, starting at the origin), velocity (m/s) and acceleration (m/s^2).
    attitude : scipy.spatial.transform.Rotation
        True body-to-navigation attitude per sample.
    specific_force_true, body_rate_true : ndarray (N, 3)
        Error-free specific force (m/s^2) and body rate (rad/s).
    accel_bias, gyro_bias : ndarray (N, 3)
        True sensor biases per sample (turn-on value plus random walk), m/s^2 and rad/s;
        the sensors read ``u + b + n``.
    initial_attitude_guess : Rotation
        The attitude at ``t[0]`` a user would start from: the truth with the stated tilt
        and heading errors, ``C0_guess = Rz(heading_error) exp([(tx, ty, 0)x]) C0_true``.
    attitude_correction : ndarray (3,)
        The correction that turns the guess into the truth in the sense of
        ``AttitudeError`` (``C0_true = exp([(ax, ay, 0)x]) Rz(az) C0_guess``), rad:
        ``(-tx, -ty, -heading_error)``.
    fix_t : ndarray (M,)
        GNSS fix times, s (``gnss_rate`` Hz, on the sample grid when the rates divide).
    fix_position : ndarray (M, 3)
        Noisy GNSS positions, m (navigation frame).
    fix_sigma : ndarray (3,)
        Standard deviation of the fix noise per axis, m (horizontal, horizontal, vertical).
    grade : str
        Sensor grade name (a key of :data:`SENSOR_GRADES`).
    params : dict
        The arguments, the grade's numbers (``"sensor"``) and the per-sample noise standard
        deviations (``"acc_noise_std"`` m/s^2, ``"gyro_noise_std"`` rad/s).

    Examples
    --------
    >>> from bvpnav.scenarios import car_drive
    >>> drive = car_drive(duration=60.0, rate=10.0)
    >>> drive.t.size, drive.fix_t.size, drive.fix_sigma.tolist()  # samples, GNSS fixes, sigma (m)
    (601, 61, [1.0, 1.0, 2.0])
    """

    t: np.ndarray
    specific_force: np.ndarray
    gyro: np.ndarray
    gravity: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    attitude: object
    specific_force_true: np.ndarray
    body_rate_true: np.ndarray
    accel_bias: np.ndarray
    gyro_bias: np.ndarray
    initial_attitude_guess: object
    attitude_correction: np.ndarray
    fix_t: np.ndarray
    fix_position: np.ndarray
    fix_sigma: np.ndarray
    grade: str
    params: dict = field(default_factory=dict)
    _path: _CarPath | None = field(default=None, repr=False)

    @property
    def rate(self) -> float:
        """Sampling rate, Hz."""
        return float(self.params["rate"])

    def data(self) -> ImuData:
        """The measurements as strapdown :class:`~bvpnav.imu.ImuData`.

        The attitude is integrated from the measured (biased) gyro rates, starting from
        :attr:`initial_attitude_guess`, with :meth:`ImuData.from_gyro`.
        """
        return ImuData.from_gyro(self.t, self.specific_force, self.gyro,
                                 initial_attitude=self.initial_attitude_guess, gravity=self.gravity)

    def truth_at(self, times) -> np.ndarray:
        """True position (len(times), 3) in m at any times (s) inside ``[t[0], t[-1]]``.

        Exact to rounding: the velocity is integrated from the nearest earlier sample with
        6-point Gauss-Legendre quadrature.
        """
        from .errors import InputError

        tt = np.atleast_1d(np.asarray(times, dtype=float))
        if tt.ndim != 1 or not np.all(np.isfinite(tt)):
            raise InputError("times: expected finite times in s (a 1-D array)")
        if tt.size and (tt.min() < self.t[0] - 1e-9 or tt.max() > self.t[-1] + 1e-9):
            raise InputError(f"times: outside the drive [{self.t[0]}, {self.t[-1]}] s")
        k = np.clip(np.searchsorted(self.t, tt, side="right") - 1, 0, self.t.size - 1)
        return self.position[k] + self._path.displacement(self.t[k], tt)

    def velocity_at(self, times) -> np.ndarray:
        """True velocity (len(times), 3) in m/s at any times (s)."""
        return self._path.velocity(np.atleast_1d(np.asarray(times, dtype=float)))


def car_drive(duration: float = 600.0, rate: float = 100.0, grade: str = "tactical", *,
              gnss_rate: float = 1.0, gnss_sigma=(1.0, 2.0), seed: int = 0,
              heading_error: float = 5.0 * np.pi / 180.0,
              tilt_error: float | tuple[float, float] = 0.5 * np.pi / 180.0) -> CarDrive:
    r"""A car drive of ``duration`` s with a strapdown IMU of a given grade and GNSS fixes.

    The drive (the same for every seed and grade; a shorter ``duration`` is the start of
    the same drive plus a stop): a 5 s stand, then straights, 90 degree left and right
    turns (16 s each), an S-curve, a 180 degree curve, stops of 6-8 s, hills of 10-25 m
    (climb angle up to 0.06 rad, the pitch following the slope), speeds of 10-16 m/s,
    an outward roll of 0.01 rad per m/s^2 of lateral acceleration, and a final stop and
    5 s stand. With the default 600 s: 5 stops (ends included), about 6 km.

    Parameters
    ----------
    duration : float
        Length of the drive, s (>= 60; ``duration * rate`` a whole number).
    rate : float
        IMU sampling rate, Hz.
    grade : {"consumer", "tactical", "navigation"}
        Sensor grade: the noise densities, turn-on bias sigmas and bias random walks of
        :data:`SENSOR_GRADES`.
    gnss_rate : float
        GNSS fix rate, Hz.
    gnss_sigma : (float, float)
        Standard deviation of the fix noise, horizontal and vertical, m.
    seed : int
        Seed of ``numpy.random.default_rng``: draws, in this order, the accelerometer
        turn-on bias (3), its random walk (N-1, 3) and noise (N, 3), the same three for
        the gyro, and the fix noise (M, 3). The same seed gives the same normals at
        every grade (scaled by the grade's numbers).
    heading_error : float
        Error of the initial heading guess about nav z, rad (default 5 degrees).
    tilt_error : float or (float, float)
        Error of the initial tilt guess, rad: rotations about nav x and y, or one number
        for a tilt of that size about the horizontal axis (1, 1, 0)/sqrt(2) (default
        0.5 degrees).

    Returns
    -------
    CarDrive

    Notes
    -----
    The path is given by three C^4 channels of time, each a sum of smooth steps
    :math:`\Delta\, S((t - t_i)/T_i)` with :math:`S' = 630\tau^4(1-\tau)^4`: the speed
    :math:`v`, the heading :math:`\psi` and the climb angle :math:`\gamma`. The velocity is
    :math:`v\,u` with :math:`u = (\cos\psi\cos\gamma, \sin\psi\cos\gamma, \sin\gamma)`,
    the acceleration its analytic derivative, the position its integral (Gauss-Legendre,
    exact to rounding). The attitude is ``Rz(psi) Ry(-gamma) Rx(phi)`` (body x along the
    velocity) with the roll :math:`\phi = 0.01\, v\dot\psi`; the body rate follows
    analytically from the Euler rates (see :class:`bvpnav.simulate.Motion`), the true
    specific force is :math:`f = C^T(a - g)`. The sensors read

    .. math:: \hat f = f + b_a(t) + n_a, \quad \hat\omega = \omega + b_g(t) + n_g,

    with :math:`b(t_0) \sim N(0, \sigma_b^2)` per axis, :math:`b_{k+1} = b_k + q\sqrt{h}\,\xi_k`
    (random walk ``q``) and white noise of standard deviation ``density * sqrt(rate)``.

    Examples
    --------
    >>> from bvpnav.scenarios import car_drive
    >>> drive = car_drive(duration=60.0, rate=10.0, grade="tactical")
    >>> drive.grade, drive.params["sensor"]["acc_noise"]
    ('tactical', 0.0005)
    """
    from scipy.spatial.transform import Rotation  # scipy.spatial: loaded for strapdown data only

    from .errors import InputError
    from .simulate import sample_times

    if grade not in SENSOR_GRADES:
        raise InputError(f"grade={grade!r}: choose one of {sorted(SENSOR_GRADES)}")
    if not (np.isfinite(duration) and duration >= 60.0):
        raise InputError(f"duration={duration!r}: the drive needs at least 60 s")
    if not (np.isfinite(gnss_rate) and 0 < gnss_rate <= rate):
        raise InputError(f"gnss_rate={gnss_rate!r}: must be positive and at most the IMU rate {rate} Hz")
    sig = np.asarray(gnss_sigma, dtype=float).ravel()
    if sig.shape != (2,) or not np.all(np.isfinite(sig)) or np.any(sig < 0):
        raise InputError(f"gnss_sigma={gnss_sigma!r}: give (horizontal, vertical) standard deviations in m")
    tilt = np.asarray(tilt_error, dtype=float).ravel()
    if tilt.size == 1:
        tilt = np.full(2, float(tilt[0]) / np.sqrt(2.0))
    if tilt.shape != (2,) or not np.all(np.isfinite(tilt)) or not np.isfinite(heading_error):
        raise InputError("tilt_error: one angle or (about x, about y) in rad; heading_error: rad")
    t = sample_times(0.0, float(duration), rate)
    n = t.size
    path = _car_schedule(float(duration))
    g = np.array([0.0, 0.0, -STANDARD_GRAVITY])

    vel = path.velocity(t)
    acc = path.acceleration(t)
    pos = np.zeros((n, 3))
    pos[1:] = np.cumsum(path.displacement(t[:-1], t[1:]), axis=0)
    ang, _ = path.euler(t)
    att = Rotation.from_euler("ZYX", ang)
    f_true = att.inv().apply(acc - g)
    w_true = path.body_rate(t)

    sensor = SENSOR_GRADES[grade]
    rng = np.random.default_rng(seed)
    h = np.diff(t)[:, None]

    def drifting(sigma: float, walk: float) -> np.ndarray:
        b = np.empty((n, 3))
        b[0] = sigma * rng.standard_normal(3)
        b[1:] = b[0] + np.cumsum(walk * np.sqrt(h) * rng.standard_normal((n - 1, 3)), axis=0)
        return b

    acc_std = sensor["acc_noise"] * np.sqrt(rate)
    gyro_std = sensor["gyro_noise"] * np.sqrt(rate)
    b_a = drifting(sensor["acc_bias"], sensor["acc_bias_walk"])
    f_meas = f_true + b_a + acc_std * rng.standard_normal((n, 3))
    b_g = drifting(sensor["gyro_bias"], sensor["gyro_bias_walk"])
    w_meas = w_true + b_g + gyro_std * rng.standard_normal((n, 3))

    m = int(np.floor(duration * gnss_rate + 1e-9)) + 1
    fix_t = np.arange(m) / gnss_rate
    k = np.clip(np.searchsorted(t, fix_t, side="right") - 1, 0, n - 1)
    fix_true = pos[k] + path.displacement(t[k], fix_t)
    fix_sigma = np.array([sig[0], sig[0], sig[1]])
    fix_pos = fix_true + fix_sigma * rng.standard_normal((m, 3))

    guess = (Rotation.from_rotvec([0.0, 0.0, float(heading_error)])
             * Rotation.from_rotvec([tilt[0], tilt[1], 0.0]) * att[0])
    correction = np.array([-tilt[0], -tilt[1], -float(heading_error)])
    params = {"duration": float(duration), "rate": float(rate), "grade": grade,
              "gnss_rate": float(gnss_rate), "gnss_sigma": tuple(float(s) for s in sig), "seed": seed,
              "heading_error": float(heading_error), "tilt_error": tuple(float(x) for x in tilt),
              "sensor": dict(sensor), "acc_noise_std": float(acc_std), "gyro_noise_std": float(gyro_std)}
    return CarDrive(t=t, specific_force=f_meas, gyro=w_meas, gravity=g, position=pos, velocity=vel,
                    acceleration=acc, attitude=att, specific_force_true=f_true, body_rate_true=w_true,
                    accel_bias=b_a, gyro_bias=b_g, initial_attitude_guess=guess,
                    attitude_correction=correction, fix_t=fix_t, fix_position=fix_pos,
                    fix_sigma=fix_sigma, grade=grade, params=params, _path=path)


@dataclass(frozen=True, eq=False)
class FaultyFixes:
    """GNSS fixes of a :class:`CarDrive` with the faults of a real receiver (see
    :func:`faulty_fixes`).

    Attributes
    ----------
    t : ndarray (M,)
        Fix stamps, s: the drive's fix times whose ``t - delay`` is inside the drive
        (with a positive delay the fix at the start is left out).
    position : ndarray (M, 3)
        Antenna positions, m: the truth at ``t - delay`` moved by the lever arm, noise and
        the outliers' offsets.
    clean : ndarray (M, 3)
        The same without the outliers' offsets, m.
    bad : ndarray of int
        Indices of the outlier fixes (sorted).
    offset : ndarray (len(bad), 3)
        The outliers' offsets, m.
    lever : ndarray (3,)
        Antenna position in the body frame, m.
    delay : float
        Delay of the stamps against the IMU clock, s (a fix stamped ``t`` is the antenna at
        ``t - delay``).

    Examples
    --------
    Outliers are the fixes whose value differs from the clean one, by 20-50 m:

    >>> import numpy as np
    >>> from bvpnav.scenarios import car_drive, faulty_fixes
    >>> fx = faulty_fixes(car_drive(duration=60.0, rate=10.0))
    >>> off = np.linalg.norm(fx.position - fx.clean, axis=1)
    >>> np.flatnonzero(off > 0).tolist() == fx.bad.tolist()
    True
    >>> bool(np.all((off[fx.bad] >= 20) & (off[fx.bad] <= 50)))
    True
    """

    t: np.ndarray
    position: np.ndarray
    clean: np.ndarray
    bad: np.ndarray
    offset: np.ndarray
    lever: np.ndarray
    delay: float


def faulty_fixes(drive: CarDrive, lever=(1.0, 0.0, 0.0), delay: float = 0.05, outliers: float = 0.05,
                 outlier_range=(20.0, 50.0), seed: int = 0) -> FaultyFixes:
    r"""The drive's GNSS fixes as a receiver with an offset antenna, latency and outliers gives them.

    Parameters
    ----------
    drive : CarDrive
    lever : array_like (3,)
        Antenna position relative to the IMU, body frame (x forward, y left, z up), m.
    delay : float
        Latency, s: the fix stamped :math:`t_k` is the antenna at :math:`t_k - \delta`
        (with the drive's fix noise). Fixes whose :math:`t_k - \delta` is outside the
        drive are left out.
    outliers : float
        Fraction of the fixes moved by 20-50 m (at least one when positive), drawn among
        all but the first and last fix.
    outlier_range : (float, float)
        Size of the outliers' offsets, m (uniform; direction uniform on the sphere).
    seed : int
        Seed of the outliers' draw (the fix noise is the drive's own).

    Returns
    -------
    FaultyFixes

    Notes
    -----
    :math:`p_k = r(t_k - \delta) + C(t_k - \delta)\, l + n_k + o_k`, with the drive's
    fix noise :math:`n_k` and the outlier offset :math:`o_k` (zero for good fixes). The
    truth at a time between samples is :meth:`CarDrive.truth_at` and the attitude is
    interpolated on the great circle.

    Examples
    --------
    >>> from bvpnav.scenarios import car_drive, faulty_fixes
    >>> fx = faulty_fixes(car_drive(duration=60.0, rate=10.0), delay=0.1)
    >>> fx.bad.size, fx.lever.tolist(), fx.delay
    (3, [1.0, 0.0, 0.0], 0.1)
    >>> fx.t[:2].tolist()  # the fix at 0 s would hold the antenna before the drive
    [1.0, 2.0]
    """
    from scipy.spatial.transform import Slerp

    from .errors import InputError

    lv = np.asarray(lever, dtype=float).ravel()
    if lv.shape != (3,) or not np.all(np.isfinite(lv)):
        raise InputError(f"lever={lever!r}: give (x, y, z) in m, body frame")
    shifted = drive.fix_t - float(delay)
    inside = (shifted >= drive.t[0] - 1e-12) & (shifted <= drive.t[-1] + 1e-12)
    t = np.asarray(drive.fix_t, dtype=float)[inside]
    if t.size < 3:
        raise InputError(f"delay={delay!r} s leaves {t.size} fix(es) inside the drive; give a smaller delay")
    if not 0.0 <= outliers < 1.0:
        raise InputError(f"outliers={outliers!r}: a fraction in [0, 1)")
    at = np.clip(t - float(delay), drive.t[0], drive.t[-1])
    truth = drive.truth_at(at)
    rot = Slerp(drive.t, drive.attitude)(at)
    noise = drive.fix_position[inside] - drive.truth_at(t)   # the drive's own fix noise
    clean = truth + rot.apply(lv) + noise
    rng = np.random.default_rng(seed)
    m = t.size
    n_bad = 0 if outliers == 0 else max(1, int(round(outliers * m)))
    bad = np.sort(rng.choice(np.arange(1, m - 1), size=n_bad, replace=False)) if n_bad else np.zeros(0, int)
    dirs = rng.standard_normal((n_bad, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    offset = dirs * rng.uniform(*outlier_range, n_bad)[:, None]
    pos = clean.copy()
    pos[bad] += offset
    return FaultyFixes(t=t.copy(), position=pos, clean=clean, bad=bad, offset=offset, lever=lv.copy(),
                       delay=float(delay))


__all__ += ["FaultyFixes", "faulty_fixes"]
