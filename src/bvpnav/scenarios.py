"""Named, seeded scenarios from the papers: data, truth and the information known.

Each scenario function returns a :class:`Scenario`; :data:`SCENARIOS` maps the names
used by the command line (``bvpnav demo NAME``, ``bvpnav simulate NAME``) to them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .imu import ImuData

__all__ = ["Scenario", "tikhonov2011", "quintic_trajectory", "cubic_prior", "SCENARIOS"]


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
