r"""Dead reckoning's error per stride: an unknown displacement of each swing between two stances, m."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ._base import ErrorModel

__all__ = ["StrideDrift", "stride_sigma"]

#: Standard gravity, m/s^2 (the specific force a tilt error turns into a horizontal
#: acceleration in a stance).
_G0 = 9.80665
#: :math:`1/\Phi^{-1}(3/4)`: the median absolute value of a zero-mean Gaussian times this is its sigma.
MAD_TO_SIGMA = 1.482602218505602
#: Smallest stride sigma of :func:`stride_sigma`, m (a stride of no length still gets a prior).
STRIDE_SIGMA_FLOOR = 1e-4


def _stances(intervals, label: str) -> np.ndarray:
    """Stance intervals ``(t0, t1)`` in s as an array (k, 2), sorted and disjoint."""
    iv = getattr(intervals, "intervals", intervals)  # a bvpnav.detect.Detection
    try:
        arr = np.asarray(iv, dtype=float).reshape(-1, 2)
    except (TypeError, ValueError):
        raise InputError(f"{label}: intervals={intervals!r}; give the stance intervals as (t0, t1) pairs "
                         "in s (e.g. bvpnav.detect.stationary(data))") from None
    if arr.shape[0] < 2:
        raise InputError(f"{label}: {arr.shape[0]} stance interval(s); a stride lies between two stances, "
                         "give at least two")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{label}: the stance intervals must be finite times in s")
    if np.any(arr[:, 1] <= arr[:, 0]) or np.any(arr[1:, 0] <= arr[:-1, 1]):
        raise InputError(f"{label}: the stance intervals must be (t0, t1) with t0 < t1, sorted and apart "
                         "(as bvpnav.detect.stationary returns them)")
    return arr


def _swing_length(t: np.ndarray, acc: np.ndarray) -> float:
    """Horizontal length (m) of one swing by plain integration, de-drifted to end at rest."""
    if t.size < 2:
        return 0.0
    h = np.diff(t)
    v = np.vstack([np.zeros(acc.shape[1]), np.cumsum(0.5 * h[:, None] * (acc[:-1] + acc[1:]), axis=0)])
    v = v - ((t - t[0]) / (t[-1] - t[0]))[:, None] * v[-1]  # zero velocity at both stances
    return float(np.linalg.norm(np.sum(0.5 * h[:, None] * (v[:-1] + v[1:]), axis=0)))


def stride_sigma(data, intervals, axes=("x", "y")) -> tuple[np.ndarray, dict]:
    r"""Each stride's displacement sigma (m) from the recording: the attitude error a stride
    adds, as the stances' gravity shows it, times the stride's length.

    Parameters
    ----------
    data : ImuData
        The data (navigation-frame accelerations ``data.acc``, m/s^2, gravity removed; for
        strapdown data those of the integrated attitude).
    intervals : list of (float, float) or bvpnav.detect.Detection
        The stance intervals, s (at least three: two strides give one attitude increment
        per axis too few to judge).
    axes : sequence of str
        The horizontal navigation axes (default ``("x", "y")``).

    Returns
    -------
    sigma : ndarray, shape (n,)
        Per stride, :math:`\sigma_k = \max(\sigma_\psi L_k, \sigma_{min})`, m.
    info : dict
        ``sigma_psi`` (rad), ``tilt_increments`` ((n, 2) rad), ``lengths`` ((n,) m),
        ``text`` (one line).

    Notes
    -----
    In stance :math:`k` the foot is still, so the mean horizontal acceleration of the
    integrated attitude is gravity through its tilt error: :math:`	heta_k = ar a_{h,k}/g`
    (rad, per horizontal axis; a constant accelerometer bias adds a constant). The change
    :math:`\Delta	heta_k = 	heta_{k+1} - 	heta_k` is the attitude error stride :math:`k`
    added (the gyro's errors under the swing's rates); its spread, robustly
    :math:`\sigma_\psi = 1.4826\,\mathrm{median}|\Delta	heta|` over both axes (a few
    stances with a rolling foot do not set it), is taken for the heading too, which no stance
    shows. A heading error :math:`\psi` turns the stride's displacement :math:`L_k` (plain
    integration of the swing de-drifted to end at rest) by :math:`\psi L_k` across it.

    Examples
    --------
    >>> from bvpnav import detect, scenarios
    >>> from bvpnav.error_models.stride_drift import stride_sigma
    >>> walk = scenarios.walking(rate=100.0, n_strides=4)  # 1.4 m strides, no attitude error
    >>> sigma, info = stride_sigma(walk.data, detect.stationary(walk.data))
    >>> [round(float(x), 1) for x in info["lengths"]], bool(info["sigma_psi"] < 0.01)  # m; rad (noise only)
    ([1.4, 1.4, 1.5, 1.5], True)
    """
    iv = _stances(intervals, "stride_sigma")
    if iv.shape[0] < 3:
        raise InputError(f"stride_sigma: {iv.shape[0]} stances; give at least three (two strides) to judge "
                         "the attitude error a stride adds")
    names = tuple(data.axes)
    missing = [a for a in axes if a not in names]
    if missing:
        raise InputError(f"stride_sigma: axes {missing} are not the data's axes {names}; give its horizontal "
                         "axes")
    cols = [names.index(a) for a in axes]
    t = np.asarray(data.t, dtype=float)
    acc = np.asarray(data.acc, dtype=float)[:, cols]
    g = _G0 if getattr(data, "gravity", None) is None else float(np.linalg.norm(data.gravity)) or _G0
    tol = 1e-9 * max(1.0, float(np.abs(t).max()))
    tilt, lengths = [], []
    for k, (a, b) in enumerate(iv):
        inside = (t >= a - tol) & (t <= b + tol)
        if not inside.any():
            raise InputError(f"stride_sigma: stance {k} ({a:g}, {b:g}) s holds no sample; give the stances "
                             "detected on this data")
        tilt.append(acc[inside].mean(axis=0) / g)
        if k + 1 < iv.shape[0]:
            sw = (t >= b - tol) & (t <= iv[k + 1, 0] + tol)
            lengths.append(_swing_length(t[sw], acc[sw]))
    inc = np.diff(np.array(tilt), axis=0)
    spsi = float(MAD_TO_SIGMA * np.median(np.abs(inc)))
    lengths = np.array(lengths)
    sigma = np.maximum(spsi * lengths, STRIDE_SIGMA_FLOOR)
    text = (f"stride_sigma: {lengths.size} strides, attitude error per stride {np.degrees(spsi):.2g} deg "
            f"(from the tilt at the stances), strides {np.median(lengths):.2g} m (median), sigma "
            f"{np.median(sigma):.2g} m per stride (median), {np.sqrt(np.sum(sigma**2)):.2g} m over the walk")
    return sigma, {"sigma_psi": spsi, "tilt_increments": inc, "lengths": lengths, "text": text}


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class StrideDrift(ErrorModel):
    r"""An unknown displacement of each stride (the swing between two stances), m.

    A foot-mounted walk is dead reckoning from stance to stance: what its white noise
    model (``sigma_a``, the stances' sigma) claims for the path's end is far less than the
    real drift, which comes from each stride's systematic errors (its heading, the foot's
    roll in the stance, the detector's edges) that no stance row sees. This model states
    that drift: each stride's displacement is uncertain by ``sigma`` per axis. The stances
    do not see it (zero in every stance, no velocity change over the swing): the estimate
    moves only by what the acceleration residuals share with its step (nothing on a
    noise-free walk), and the standard deviations grow by :math:`\sigma\sqrt{n}` after
    :math:`n` strides. Information on the position, such as
    :class:`~bvpnav.constraints.SamePosition` of a walk's ends, then spreads its
    correction over the strides in proportion to their variance.

    Parameters
    ----------
    intervals : list of (float, float) or bvpnav.detect.Detection
        The stance intervals ``(t0, t1)`` in s, sorted and apart; stride ``k`` is the
        swing from the end of stance ``k`` to the start of stance ``k + 1``.
    sigma : float or array_like
        Prior standard deviation of each stride's displacement per axis, m (one value,
        or one per parameter). Without it the strides are free (determined only by
        position information, e.g. a fix at every stance).
    axes : str or sequence of str, optional
        Navigation axes the displacements act on; default ``("x", "y")`` (horizontal:
        a floor's height is stated by the stances and a flat-floor item).
    prior, bounds
        See :class:`~bvpnav.error_models.ErrorModel` (m).

    Notes
    -----
    Parameters ``stride_<axis>[k]``, axis-major. Stride ``k`` over :math:`[a_k, b_k]`,
    :math:`T_k = b_k - a_k`, :math:`\tau = (t - a_k)/T_k`, moves the position along axis
    :math:`e` by :math:`d_k S(\tau)` with the minimum-jerk step
    :math:`S = 10\tau^3 - 15\tau^4 + 6\tau^5` (:math:`S(0) = 0`, :math:`S(1) = 1`, zero
    velocity and acceleration at both ends), so its column is the acceleration

    .. math:: G_k(t) = \frac{S''(\tau)}{T_k^2}\, e = \frac{60\tau - 180\tau^2 + 120\tau^3}{T_k^2}\, e,
              \quad 0 \le \tau \le 1,

    zero outside the swing: zero in every stance (a stance row does not see it) and of
    zero integral (the velocity after the swing is unchanged). The prior
    :math:`d_k \sim N(0, \sigma^2)` per axis makes the end of :math:`n` strides uncertain
    by :math:`\sigma\sqrt n` more than the white noise says. On the FEM's sampled
    acceleration the displacement is :math:`d_k` to the quadrature error of :math:`S''`
    (a few 1e-4 relative with 100 samples per swing).

    Examples
    --------
    Two stances around a 1 m stride: with the stances alone the stride's displacement
    keeps its prior, 0.02 m per axis:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, ZeroVelocity
    >>> from bvpnav.error_models import StrideDrift
    >>> t = np.linspace(0.0, 2.0, 201)
    >>> tau = np.clip(t - 0.5, 0.0, 1.0)
    >>> acc = np.where((t > 0.5) & (t < 1.5), 60 * tau - 180 * tau**2 + 120 * tau**3, 0.0)
    >>> noise = 0.01 * np.random.default_rng(0).standard_normal((t.size, 2))  # m/s^2
    >>> data = bvpnav.ImuData(t=t, acc=np.column_stack([acc, 0 * t]) + noise, axes=("x", "y"))
    >>> prob = bvpnav.NavigationProblem(data, error_model=StrideDrift(intervals=[(0, 0.5), (1.5, 2)],
    ...                                                                sigma=0.02), sigma_a=0.01)
    >>> _ = prob.add(Position(t=0.0, value=0.0), ZeroVelocity(t0=0.0, t1=0.5), ZeroVelocity(t0=1.5, t1=2.0))
    >>> sol = prob.solve(solver="direct", uncertainty=True)
    >>> print(f"{sol.position()[-1, 0]:.2f} m +- {sol.trajectory['x_std'].iloc[-1]:.3f} m")
    1.00 m +- 0.020 m
    """

    intervals: Any = None
    units = "m"

    def __post_init__(self):
        if self.axes is None:
            object.__setattr__(self, "axes", ("x", "y"))
        super().__post_init__()

    def validate(self) -> None:
        object.__setattr__(self, "intervals", _stances(self.intervals, "StrideDrift"))

    @classmethod
    def from_stances(cls, data, intervals, axes=("x", "y")) -> StrideDrift:
        """The model with each stride's sigma from the recording (:func:`stride_sigma`).

        Parameters
        ----------
        data : ImuData
        intervals : list of (float, float) or bvpnav.detect.Detection
            The stance intervals, s.
        axes : sequence of str
            Horizontal navigation axes (default ``("x", "y")``).

        Returns
        -------
        StrideDrift
            ``sigma`` per parameter (the stride's sigma on every axis).
        """
        sigma, _ = stride_sigma(data, intervals, axes)
        return cls(intervals=intervals, sigma=np.tile(sigma, len(axes)), axes=tuple(axes))

    @classmethod
    def example(cls) -> StrideDrift:
        """A valid instance for a window of [0, 10] s (contract tests): three stances, two strides."""
        return cls(intervals=[(0.0, 1.0), (4.0, 5.0), (8.0, 10.0)], sigma=0.05)

    def swings(self) -> np.ndarray:
        """The strides ``(a_k, b_k)`` in s: from each stance's end to the next one's start, (n, 2)."""
        return np.column_stack([self.intervals[:-1, 1], self.intervals[1:, 0]])

    def _axis_index(self, data) -> list[int]:
        return list(self._select_axes(tuple(data.axes), "navigation"))

    def names(self, data) -> list[str]:
        ax = tuple(data.axes)
        n = self.swings().shape[0]
        return [f"stride_{ax[i]}[{k}]" for i in self._axis_index(data) for k in range(n)]

    def columns(self, data) -> np.ndarray:
        t = np.asarray(data.t, dtype=float)
        sw = self.swings()
        if sw[0, 0] < t[0] or sw[-1, 1] > t[-1]:
            raise InputError(f"StrideDrift: strides from {sw[0, 0]:g} to {sw[-1, 1]:g} s are not inside the "
                             f"data's window [{t[0]:g}, {t[-1]:g}] s; give the stances detected on this data")
        T = sw[:, 1] - sw[:, 0]
        tau = (t[:, None] - sw[None, :, 0]) / T[None, :]
        inside = (tau > 0.0) & (tau < 1.0)
        prof = np.where(inside, (60 * tau - 180 * tau**2 + 120 * tau**3) / T[None, :] ** 2, 0.0)  # (N, n)
        axes = self._axis_index(data)
        G = np.zeros((t.size, len(data.axes), len(axes) * sw.shape[0]))
        for j, i in enumerate(axes):
            G[:, i, j * sw.shape[0]:(j + 1) * sw.shape[0]] = prof
        return G
