r"""Stationary intervals from the IMU itself: where the sensor is still (zero-velocity detection).

:func:`stationary` finds the intervals in which a strapdown IMU (body-frame specific
force and gyro rates) is at rest, as ``(t0, t1)`` pairs in s that go straight into
:class:`bvpnav.constraints.ZeroVelocity` (see :func:`zero_velocity_items`). Two detectors:

- ``"shoe"``: the stance hypothesis optimal detector (SHOE), the generalized likelihood
  ratio test of Skog, Händel, Nilsson and Rantakokko, "Zero-velocity detection -- an
  algorithm evaluation", IEEE Trans. Biomed. Eng. 57(11), 2657-2666, 2010 (the
  detector of OpenShoe and, with differences listed in :func:`shoe_statistic`, of
  gaitmap's ``ShoeZuptDetector``);
- ``"magnitude"``: moving-window means of :math:`|\,\|f\| - g\,|` and, where there are
  gyro rates, of :math:`\|\omega\|` below two thresholds.

Windows are counted in samples (``window``), not seconds: the published statistic is a
sum over W consecutive samples, and so it stays that on non-uniform time steps. Every
statistic is computed with sliding-window views of the samples (no Python loop over
samples); the per-window work is done in blocks to bound the memory.

Example::

    from bvpnav import detect
    intervals = detect.stationary(data)               # [(t0, t1), ...] in s
    prob.add(*detect.zero_velocity_items(intervals, sigma=0.01))

Examples
--------
A simulated foot: standing, two strides, standing; the stance phases are found from the
IMU alone:

>>> from bvpnav import detect, scenarios
>>> walk = scenarios.walking(rate=100.0, n_strides=2)  # stands 1.5 s, two strides, stands
>>> detect.stationary(walk.data)
[(0.0, 1.5), (2.1, 2.51), (3.1, 4.61)]
>>> [(round(a, 2), round(b, 2)) for a, b in walk.params["stance_intervals"]]  # the truth
[(0.0, 1.5), (2.1, 2.5), (3.1, 4.61)]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from .errors import InputError
from .geodesy import STANDARD_GRAVITY


class ImuLike(Protocol):
    """What the detectors and checks read of a :class:`bvpnav.ImuData` (not imported: it
    sits above this module and runs :func:`frame_check` and :func:`saturation` itself)."""

    t: np.ndarray
    n: int
    acc: np.ndarray
    specific_force: np.ndarray | None
    gyro: np.ndarray | None
    gravity: np.ndarray | None

__all__ = [
    "Detection",
    "METHODS",
    "SHOE_SIGMA_A",
    "SHOE_SIGMA_W",
    "SHOE_THRESHOLD",
    "MAGNITUDE_ACC_THRESHOLD",
    "MAGNITUDE_GYRO_THRESHOLD",
    "DEFAULT_WINDOW",
    "ADAPTIVE_SPAN",
    "ADAPTIVE_ABOVE_MIN",
    "ADAPTIVE_BELOW_MAX",
    "adaptive_threshold",
    "stationary",
    "stationary_mask",
    "shoe_statistic",
    "magnitude_statistic",
    "intervals_from_mask",
    "zero_velocity_items",
    "FrameCheck",
    "frame_check",
    "frame_name",
    "saturation",
    "FRAME_CHECK_LIMIT",
    "GRAVITY_TWICE",
    "FRAME_CHECK_WINDOW",
    "FRAME_CHECK_GYRO",
    "SATURATION_RUN",
    "SATURATION_MIN_RATE",
]

#: The detectors :func:`stationary` knows.
METHODS = ("shoe", "magnitude")
#: SHOE's default accelerometer noise standard deviation, m/s^2 (OpenShoe's setting).
SHOE_SIGMA_A = 0.01
#: SHOE's default gyro noise standard deviation, rad/s (OpenShoe's 0.1 deg/s).
SHOE_SIGMA_W = float(np.deg2rad(0.1))
#: SHOE's default threshold gamma (dimensionless; OpenShoe's 0.3e5 with the sigmas above).
SHOE_THRESHOLD = 3.0e4
#: The magnitude detector's default threshold on the window mean of ``| |f| - g |``, m/s^2.
MAGNITUDE_ACC_THRESHOLD = 0.5
#: The magnitude detector's default threshold on the window mean of ``|omega|``, rad/s.
MAGNITUDE_GYRO_THRESHOLD = 0.5
#: Default window length W, samples (OpenShoe's setting).
DEFAULT_WINDOW = 3

#: Adaptive SHOE threshold (``threshold="adaptive"``): the span of the running minimum
#: and maximum of the statistic around each sample, s (about one to two strides, so that
#: every stride's stance and swing lie in it at any sampling rate).
ADAPTIVE_SPAN = 1.5
#: Adaptive threshold: decades above the running minimum of the statistic (the stance of
#: the stride at hand) that still count as stance.
ADAPTIVE_ABOVE_MIN = 1.0
#: Adaptive threshold: decades below the running maximum (the swing peak) that the
#: threshold never exceeds.
ADAPTIVE_BELOW_MAX = 2.0

#: Window rows computed at once (bounds the temporaries to about 8 MB).
_BLOCK_VALUES = 1 << 20


@dataclass(frozen=True, eq=False)
class Detection:
    """What :func:`stationary` found, with the statistic it decided on.

    Attributes
    ----------
    intervals : list of (float, float)
        Stationary intervals ``(t0, t1)`` in s, sorted, non-overlapping, ``t0 < t1``.
    mask : ndarray of bool, shape (N,)
        Per-sample decision before ``min_duration`` (True: stationary).
    statistic : ndarray, shape (N,)
        Per-sample statistic: the smallest statistic of the windows holding the sample
        (SHOE: dimensionless :math:`T`; magnitude: the larger of the two ratios
        statistic / threshold). ``mask == (statistic < threshold)``.
    threshold : float or ndarray, shape (N,)
        The threshold the statistic was compared with (1 for ``"magnitude"``; one per
        sample with ``threshold="adaptive"``).
    method : str
    window : int
        Window length W in samples.
    params : dict
        The detector's settings (noise levels, thresholds, gravity, min_duration).

    Examples
    --------
    >>> from bvpnav import detect, scenarios
    >>> walk = scenarios.walking(rate=100.0, n_strides=2)  # stands 1.5 s, two strides, stands
    >>> det = detect.stationary(walk.data, return_statistic=True)
    >>> det.method, det.window, det.threshold
    ('shoe', 3, 30000.0)
    >>> bool((det.mask == (det.statistic < det.threshold)).all())
    True
    """

    intervals: list
    mask: np.ndarray
    statistic: np.ndarray
    threshold: Any
    method: str
    window: int
    params: dict

    def report(self, t=None) -> dict:
        """What was found, in plain numbers: the intervals, their durations and the share still.

        Parameters
        ----------
        t : array_like, shape (N,), optional
            The sample times, s (for the share of the recording's duration); without
            them the share is of the samples.

        Returns
        -------
        dict
            ``intervals`` (count), ``still_samples``, ``samples``, ``still_share``
            (0..1), ``duration_s`` (``min``, ``median``, ``max`` of the intervals, s),
            ``gap_s`` (longest time between consecutive intervals, s), ``threshold``
            (``min``, ``median``, ``max`` of the threshold used), ``method``, ``window``,
            and ``text``: one line saying it.

        Examples
        --------
        >>> from bvpnav import detect, scenarios
        >>> walk = scenarios.walking(rate=100.0, n_strides=2)
        >>> rep = detect.stationary(walk.data, return_statistic=True).report()
        >>> rep["intervals"], rep["still_samples"], rep["samples"], round(rep["gap_s"], 2)
        (3, 345, 462, 0.6)
        >>> rep["text"][:62]
        'shoe (W = 3): 3 stationary intervals, 345 of 462 samples (74.7'
        """
        d = np.array([b - a for a, b in self.intervals]) if self.intervals else np.zeros(0)
        gaps = np.array([b[0] - a[1] for a, b in zip(self.intervals[:-1], self.intervals[1:], strict=True)])
        thr = np.atleast_1d(np.asarray(self.threshold, dtype=float))
        n, still = int(self.mask.size), int(np.count_nonzero(self.mask))
        share = still / max(n, 1)
        if t is not None:
            tt = np.asarray(t, dtype=float)
            share = float(np.sum(np.diff(tt)[self.mask[:-1] & self.mask[1:]]) / max(tt[-1] - tt[0], 1e-300))
        def q(x):
            if not x.size:
                return {"min": np.nan, "median": np.nan, "max": np.nan}
            return {"min": float(x.min()), "median": float(np.median(x)), "max": float(x.max())}

        out = {"intervals": len(self.intervals), "still_samples": still, "samples": n,
               "still_share": float(share),
               "duration_s": q(d), "gap_s": float(gaps.max()) if gaps.size else 0.0, "threshold": q(thr),
               "method": self.method, "window": self.window}
        tq = out["threshold"]
        ttxt = (f"{tq['min']:.3g}" if tq["min"] == tq["max"] else
                f"{tq['min']:.3g}..{tq['max']:.3g} (median {tq['median']:.3g}, adaptive)")
        dq = out["duration_s"]
        out["text"] = (f"{self.method} (W = {self.window}): {len(self.intervals)} stationary intervals, "
                       f"{still} of {n} samples ({100 * still / max(n, 1):.1f} %); "
                       f"durations {dq['min']:.2g}..{dq['max']:.3g} s "
                       f"(median {dq['median']:.2g} s); longest gap {out['gap_s']:.2g} s; threshold {ttxt}")
        return out


# ----------------------------------------------------------------- statistics
def _window_blocks(n_windows: int, width: int):
    """Slices of window indices, each small enough for the temporaries of one block."""
    step = max(1, _BLOCK_VALUES // max(1, width))
    return (slice(s, min(s + step, n_windows)) for s in range(0, n_windows, step))


def _window_sum(x: np.ndarray, window: int) -> np.ndarray:
    """Sum of ``x`` (N,) over each window of ``window`` consecutive samples: (N - W + 1,)."""
    views = sliding_window_view(x, window)
    out = np.empty(views.shape[0])
    for sl in _window_blocks(views.shape[0], window):
        out[sl] = views[sl].sum(axis=1)
    return out


def shoe_statistic(specific_force, gyro, window: int, *, sigma_a: float = SHOE_SIGMA_A,
                   sigma_w: float = SHOE_SIGMA_W, gravity: float = STANDARD_GRAVITY) -> np.ndarray:
    r"""The SHOE test statistic of every window of ``window`` consecutive samples.

    Parameters
    ----------
    specific_force : array_like, shape (N, 3)
        Body-frame specific force, m/s^2.
    gyro : array_like, shape (N, 3)
        Body rates, rad/s.
    window : int
        Window length W, samples (1 <= W <= N).
    sigma_a : float
        Accelerometer white-noise standard deviation, m/s^2.
    sigma_w : float
        Gyro white-noise standard deviation, rad/s.
    gravity : float
        Magnitude of gravity g, m/s^2.

    Returns
    -------
    ndarray, shape (N - W + 1,)
        :math:`T_n` (dimensionless) of the window of samples ``n .. n + W - 1``.

    Notes
    -----
    Skog et al. (2010), eq. (12):

    .. math::

        T_n = \frac{1}{W} \sum_{l=n}^{n+W-1} \left( \frac{1}{\sigma_a^2}
            \left\| f_l - g \frac{\bar f_n}{\|\bar f_n\|} \right\|^2
            + \frac{1}{\sigma_\omega^2} \|\omega_l\|^2 \right),
        \qquad \bar f_n = \frac{1}{W} \sum_{l=n}^{n+W-1} f_l,

    the generalized likelihood ratio of "still" (specific force of magnitude g along an
    unknown direction, zero rates, white noise) against "moving"; the sensor is still
    where :math:`T_n < \gamma`. This is the published definition and OpenShoe's. gaitmap's
    ``find_static_samples_shoe`` differs: it takes the gravity direction from the mean of
    the *whole* recording instead of each window's :math:`\bar f_n`, uses g = 9.81 m/s^2,
    gyro rates in deg/s, windows that advance by half their length, and calls a window
    still when its statistic is ``<=`` the threshold (its defaults:
    0.15 s windows, variances 3.5e-9 (m/s^2)^2 and 1.3e-7 (deg/s)^2, threshold 2.31e9,
    i.e. :math:`\gamma\sigma_a^2` = 8.1 (m/s^2)^2 and :math:`\gamma\sigma_\omega^2` =
    0.091 (rad/s)^2; OpenShoe's defaults used here give 3 (m/s^2)^2 and the same
    0.091 (rad/s)^2). Only the products :math:`\gamma\sigma_a^2` and
    :math:`\gamma\sigma_\omega^2` matter for the decision.

    Examples
    --------
    A triad at rest reads gravity on its up axis and no rate: the statistic is zero:

    >>> import numpy as np
    >>> from bvpnav.detect import shoe_statistic
    >>> f, w = np.tile([0.0, 0.0, 9.80665], (10, 1)), np.zeros((10, 3))
    >>> shoe_statistic(f, w, window=3).tolist()
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    """
    f = np.asarray(specific_force, dtype=float)
    w = np.asarray(gyro, dtype=float)
    views = sliding_window_view(f, window, axis=0)  # (N - W + 1, 3, W), no copy
    out = np.empty(views.shape[0])
    for sl in _window_blocks(views.shape[0], 3 * window):
        fw = views[sl]
        mean = fw.mean(axis=2)
        u = mean / np.linalg.norm(mean, axis=1, keepdims=True)
        out[sl] = np.square(fw - gravity * u[:, :, None]).sum(axis=(1, 2))
    gyro_energy = _window_sum(np.einsum("ij,ij->i", w, w), window)
    return (out / sigma_a**2 + gyro_energy / sigma_w**2) / window


def magnitude_statistic(specific_force, gyro, window: int, *,
                        acc_threshold: float = MAGNITUDE_ACC_THRESHOLD,
                        gyro_threshold: float | None = MAGNITUDE_GYRO_THRESHOLD,
                        gravity: float = STANDARD_GRAVITY) -> np.ndarray:
    r"""The magnitude detector's statistic of every window of ``window`` samples.

    Parameters
    ----------
    specific_force : array_like, shape (N, 3)
        Body-frame specific force, m/s^2.
    gyro : array_like, shape (N, 3), or None
        Body rates, rad/s; None (or ``gyro_threshold=None``): acceleration only.
    window : int
        Window length W, samples.
    acc_threshold : float
        Threshold on the window mean of :math:`|\|f_l\| - g|`, m/s^2.
    gyro_threshold : float or None
        Threshold on the window mean of :math:`\|\omega_l\|`, rad/s.
    gravity : float
        g, m/s^2.

    Returns
    -------
    ndarray, shape (N - W + 1,)
        Dimensionless; the window is still where it is below 1.

    Notes
    -----
    .. math::

        S_n = \max\left( \frac{1}{W a_{th}} \sum_{l=n}^{n+W-1} \bigl|\|f_l\| - g\bigr|,\;
            \frac{1}{W \omega_{th}} \sum_{l=n}^{n+W-1} \|\omega_l\| \right)

    (the second term only with gyro rates), so :math:`S_n < 1` exactly when both window
    means are below their thresholds.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.detect import magnitude_statistic
    >>> f, w = np.tile([0.0, 0.0, 9.80665], (10, 1)), np.zeros((10, 3))
    >>> f[5:, 0] = 3.0  # moving from sample 5 on: 3 m/s^2 along x
    >>> np.round(magnitude_statistic(f, w, window=3), 3).tolist()  # per window, over its threshold
    [0.0, 0.0, 0.0, 0.299, 0.598, 0.897, 0.897, 0.897]
    """
    f = np.asarray(specific_force, dtype=float)
    acc = _window_sum(np.abs(np.linalg.norm(f, axis=1) - gravity), window) / (window * acc_threshold)
    if gyro is None or gyro_threshold is None:
        return acc
    rate = _window_sum(np.linalg.norm(np.asarray(gyro, dtype=float), axis=1), window)
    return np.maximum(acc, rate / (window * gyro_threshold))


def _per_sample_min(stat: np.ndarray, window: int) -> np.ndarray:
    """Per sample, the smallest statistic of the windows that hold it: (N,) from (N - W + 1,)."""
    pad = np.full(window - 1, np.inf)
    return sliding_window_view(np.concatenate([pad, stat, pad]), window).min(axis=1)


# --------------------------------------------------------------------- checks
def _positive(name: str, value, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name}={value!r}: give a positive number in {unit}") from None
    if isinstance(value, bool) or not (np.isfinite(v) and v > 0):
        raise InputError(f"{name}={value!r}: must be a finite number > 0 ({unit})")
    return v


def _channels(data, method: str) -> tuple[np.ndarray, np.ndarray | None]:
    """The specific force (N, 3) and gyro rates (N, 3) or None of ``data``, checked."""
    if not (hasattr(data, "specific_force") and hasattr(data, "grid")):  # an ImuData (not imported: it
        # sits above this module, whose frame check it runs)
        raise InputError(f"data: got {type(data).__name__}; give a bvpnav.ImuData with body-frame "
                         "specific force and gyro rates, e.g. ImuData.from_gyro(t, specific_force, gyro)")
    if data.specific_force is None:
        raise InputError(
            f"method={method!r} needs the body-frame specific force, but data has navigation-frame "
            "accelerations only (ImuData(t, acc=...), gravity removed); build the data from the raw "
            "sensor channels: ImuData.from_gyro(t, specific_force, gyro) (m/s^2, rad/s)")
    w = data.gyro
    if w is not None:
        w = np.asarray(w, dtype=float)
        if w.shape != (data.n, 3) or not np.all(np.isfinite(w)):
            raise InputError(f"data.gyro: expected {data.n} finite rows of 3 rates (rad/s), got shape "
                             f"{w.shape}; build the data with ImuData.from_gyro(t, specific_force, gyro)")
    if method == "shoe" and w is None:
        raise InputError(
            "method='shoe' needs gyro rates, but data.gyro is None (ImuData built with an attitude, "
            "not from gyro rates); build it with ImuData.from_gyro(t, specific_force, gyro), or use "
            "method='magnitude', which can run on the acceleration alone")
    return data.specific_force, w


def _window(window, n: int) -> int:
    if window is None:
        window = DEFAULT_WINDOW
    if isinstance(window, (bool, float)) or not isinstance(window, (int, np.integer)):
        raise InputError(f"window={window!r}: give the window length as a whole number of samples "
                         f"(the default is {DEFAULT_WINDOW}; at r Hz, s seconds are about round(s * r) + 1 "
                         "samples)")
    if window < 2:
        raise InputError(f"window={window}: a window needs at least 2 samples (so that every "
                         "stationary interval has t0 < t1); give window >= 2")
    if window > n:
        raise InputError(f"window={window} samples is longer than the data ({n} samples); give a "
                         f"window of at most {n} samples (the default is {DEFAULT_WINDOW})")
    return int(window)


def _settings(method: str, threshold, sigma_a, sigma_w, acc_threshold, gyro_threshold,
              has_gyro: bool) -> dict:
    """The detector's settings with the defaults filled in, or InputError for a misplaced one."""
    if method not in METHODS:
        raise InputError(f"method={method!r}; choose one of {list(METHODS)}")
    if method == "shoe":
        misplaced = {"acc_threshold": acc_threshold,
                     "gyro_threshold": None if gyro_threshold == "auto" else gyro_threshold}
        given = [k for k, v in misplaced.items() if v is not None]
        if given:
            raise InputError(f"{', '.join(given)}: settings of method='magnitude'; SHOE takes threshold= "
                             "(gamma), sigma_a= (m/s^2) and sigma_w= (rad/s)")
        if isinstance(threshold, str):
            if threshold != "adaptive":
                raise InputError(f"threshold={threshold!r}: give gamma as a number > 0 (dimensionless), "
                                 "or 'adaptive' (a threshold from the recording's own statistic)")
            thr: Any = "adaptive"
        else:
            thr = _positive("threshold", SHOE_THRESHOLD if threshold is None else threshold, "1")
        return {"threshold": thr,
                "sigma_a": _positive("sigma_a", SHOE_SIGMA_A if sigma_a is None else sigma_a, "m/s^2"),
                "sigma_w": _positive("sigma_w", SHOE_SIGMA_W if sigma_w is None else sigma_w, "rad/s")}
    given = [k for k, v in {"threshold": threshold, "sigma_a": sigma_a, "sigma_w": sigma_w}.items()
             if v is not None]
    if given:
        raise InputError(f"{', '.join(given)}: settings of method='shoe'; the magnitude detector takes "
                         "acc_threshold= (m/s^2) and gyro_threshold= (rad/s, or None for acceleration "
                         "only)")
    acc = _positive("acc_threshold", MAGNITUDE_ACC_THRESHOLD if acc_threshold is None else acc_threshold,
                    "m/s^2")
    if isinstance(gyro_threshold, str):
        if gyro_threshold != "auto":
            raise InputError(f"gyro_threshold={gyro_threshold!r}: give a number in rad/s, None "
                             "(acceleration only) or 'auto'")
        gyr = MAGNITUDE_GYRO_THRESHOLD if has_gyro else None
    elif gyro_threshold is None:
        gyr = None
    else:
        gyr = _positive("gyro_threshold", gyro_threshold, "rad/s")
        if not has_gyro:
            raise InputError(f"gyro_threshold={gyro_threshold!r}, but data.gyro is None; build the data "
                             "with ImuData.from_gyro(t, specific_force, gyro), or give gyro_threshold=None "
                             "for the acceleration-only test")
    return {"acc_threshold": acc, "gyro_threshold": gyr, "threshold": 1.0}


def adaptive_threshold(t, statistic, *, span: float = ADAPTIVE_SPAN, above_min: float = ADAPTIVE_ABOVE_MIN,
                       below_max: float = ADAPTIVE_BELOW_MAX, floor: float = SHOE_THRESHOLD) -> np.ndarray:
    r"""A per-sample SHOE threshold from the recording's own statistic (walking and running).

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s.
    statistic : array_like, shape (N,)
        The per-sample SHOE statistic (:attr:`Detection.statistic`), dimensionless, > 0.
    span : float
        Length of the running minimum and maximum around each sample, s.
    above_min : float
        Decades above the running minimum that count as stance.
    below_max : float
        Decades below the running maximum that the threshold never exceeds.
    floor : float
        A statistic below this is stationary anywhere (the fixed threshold).

    Returns
    -------
    ndarray, shape (N,)
        The threshold :math:`\gamma_k` of every sample (dimensionless).

    Notes
    -----
    With :math:`s_k = \log_{10} T_k`, its running minimum :math:`m_k` and maximum
    :math:`M_k` over ``span`` seconds centred on sample :math:`k`,

    .. math:: \log_{10}\gamma_k = \maxigl(\min(m_k + a,\; M_k - b),\; \log_{10}\gamma_0igr),

    :math:`a` = ``above_min``, :math:`b` = ``below_max``, :math:`\gamma_0` = ``floor``.
    Each stride's stance is the valley of the statistic between two swings, whose depth
    depends on the gait: walking stances reach :math:`10^{2}..10^{4.5}` with OpenShoe's
    noise settings, running stances only :math:`10^{5}..10^{5.6}` (heel strike, a short
    stance), the swings :math:`10^{7}..10^{8}`. A fixed :math:`\gamma` that suits one gait
    misses the other's stances; relative to the stride at hand (its valley, bounded by its
    swing peaks) one setting holds for both, and at any rate, since the span is in
    seconds. Where the foot stands for longer than the span, :math:`\gamma_0` decides.

    Examples
    --------
    A valley of :math:`10^{5}` between swings of :math:`10^{7.5}`, above the fixed
    threshold 3e4, is a stance here:

    >>> import numpy as np
    >>> from bvpnav.detect import adaptive_threshold
    >>> t = np.arange(300) * 0.01
    >>> s = np.full(300, 10**7.5)
    >>> s[140:160] = 1e5
    >>> gamma = adaptive_threshold(t, s)
    >>> int(np.count_nonzero(s < gamma)), float(np.log10(gamma[150]))
    (20, 5.5)
    """
    t = np.asarray(t, dtype=float)
    stat = np.asarray(statistic, dtype=float)
    span = _positive("span", span, "s")
    floor = _positive("floor", floor, "1")
    if t.size < 2:
        return np.full(stat.shape, floor)
    step = float(np.median(np.diff(t)))
    n = max(1, int(round(span / step)))
    s = np.log10(np.maximum(stat, np.finfo(float).tiny))
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    # centred running extremes over n samples, shorter at the ends
    lo = minimum_filter1d(s, n, mode="constant", cval=np.inf)
    hi = maximum_filter1d(s, n, mode="constant", cval=-np.inf)
    return 10.0 ** np.maximum(np.minimum(lo + above_min, hi - below_max), np.log10(floor))


# ------------------------------------------------------------------ detection
def stationary_mask(data: ImuLike, method: str = "shoe", *, window: int | None = None,
                    threshold: float | None = None, sigma_a: float | None = None,
                    sigma_w: float | None = None, acc_threshold: float | None = None,
                    gyro_threshold: float | str | None = "auto",
                    gravity: float = STANDARD_GRAVITY) -> tuple[np.ndarray, np.ndarray]:
    """Per-sample stationary decision and the statistic it was made on.

    Parameters are those of :func:`stationary` (without ``min_duration``).

    Returns
    -------
    mask : ndarray of bool, shape (N,)
        True where the sample lies in at least one window whose statistic is below the
        threshold.
    statistic : ndarray, shape (N,)
        Per sample, the smallest window statistic over the W windows that hold it
        (dimensionless), so that ``mask == (statistic < threshold)``.

    Examples
    --------
    >>> from bvpnav import detect, scenarios
    >>> walk = scenarios.walking(rate=100.0, n_strides=2)  # stands 1.5 s, two strides, stands
    >>> mask, statistic = detect.stationary_mask(walk.data)
    >>> mask.shape, int(mask.sum())  # stationary samples of 462
    ((462,), 345)
    """
    mask, stat, _, _ = _detect(data, method, window, threshold, sigma_a, sigma_w, acc_threshold,
                               gyro_threshold, gravity)
    return mask, stat


def _detect(data, method, window, threshold, sigma_a, sigma_w, acc_threshold, gyro_threshold, gravity):
    """(mask, per-sample statistic, window, settings) of one detector run."""
    f, w = _channels(data, method)
    g = _positive("gravity", gravity, "m/s^2")
    cfg = _settings(method, threshold, sigma_a, sigma_w, acc_threshold, gyro_threshold, w is not None)
    W = _window(window, data.n)
    if method == "shoe":
        stat = shoe_statistic(f, w, W, sigma_a=cfg["sigma_a"], sigma_w=cfg["sigma_w"], gravity=g)
    else:
        stat = magnitude_statistic(f, w, W, acc_threshold=cfg["acc_threshold"],
                                   gyro_threshold=cfg["gyro_threshold"], gravity=g)
    per_sample = _per_sample_min(stat, W)
    cfg["gravity"] = g
    thr = cfg["threshold"]
    if isinstance(thr, str):
        thr = adaptive_threshold(data.t, per_sample)
        cfg.update(span=ADAPTIVE_SPAN, above_min=ADAPTIVE_ABOVE_MIN, below_max=ADAPTIVE_BELOW_MAX,
                   floor=SHOE_THRESHOLD)
        cfg["threshold_array"] = thr
    return per_sample < thr, per_sample, W, cfg


def stationary(data: ImuLike, method: str = "shoe", *, window: int | None = None,
               threshold: float | None = None, sigma_a: float | None = None, sigma_w: float | None = None,
               acc_threshold: float | None = None, gyro_threshold: float | str | None = "auto",
               gravity: float = STANDARD_GRAVITY, min_duration: float = 0.0,
               return_statistic: bool = False) -> list[tuple[float, float]] | Detection:
    r"""Intervals in which the IMU is stationary, detected from its own samples.

    Parameters
    ----------
    data : ImuData
        Strapdown data with the body-frame specific force ``data.specific_force``
        (N, 3, m/s^2) and, for SHOE, the gyro rates ``data.gyro`` (N, 3, rad/s), as
        :meth:`bvpnav.ImuData.from_gyro` builds it. Times may be non-uniform.
    method : {"shoe", "magnitude"}
        The SHOE likelihood-ratio test (needs gyro rates) or the magnitude test (see the
        module docstring).
    window : int, optional
        Window length W in **samples** (2 <= W <= N), default :data:`DEFAULT_WINDOW`
        (3, OpenShoe's). In seconds a window spans W - 1 sample steps, so at r Hz a window
        of s seconds is about ``round(s * r) + 1`` samples.
    threshold : float or "adaptive", optional
        SHOE: the threshold :math:`\gamma` (dimensionless), default
        :data:`SHOE_THRESHOLD`; ``"adaptive"``: a threshold per sample from the
        recording's own statistic, relative to each stride's stance valley and swing
        peaks (:func:`adaptive_threshold`), which suits walking and running alike with no
        tuning (with the default ``sigma_a``, ``sigma_w``: its floor is
        :data:`SHOE_THRESHOLD`). Not for ``"magnitude"``.
    sigma_a, sigma_w : float, optional
        SHOE: accelerometer (m/s^2) and gyro (rad/s) noise standard deviations, default
        :data:`SHOE_SIGMA_A`, :data:`SHOE_SIGMA_W`. Only the products with the threshold
        matter (:math:`\gamma\sigma_a^2` in (m/s^2)^2, :math:`\gamma\sigma_\omega^2` in
        (rad/s)^2).
    acc_threshold : float, optional
        Magnitude test: threshold on the window mean of :math:`|\|f\| - g|`, m/s^2,
        default :data:`MAGNITUDE_ACC_THRESHOLD`.
    gyro_threshold : float, None or "auto"
        Magnitude test: threshold on the window mean of :math:`\|\omega\|`, rad/s.
        ``"auto"`` (default): :data:`MAGNITUDE_GYRO_THRESHOLD` when ``data.gyro`` is
        set, else the acceleration alone; None: the acceleration alone.
    gravity : float
        Magnitude of gravity g, m/s^2.
    min_duration : float
        Intervals shorter than this (``t1 - t0 < min_duration``, s) are **dropped** from
        the result (they stay in ``Detection.mask``). Default 0: every detected run is
        kept.
    return_statistic : bool
        Return a :class:`Detection` (intervals, per-sample mask and statistic,
        threshold, window) instead of the list of intervals.

    Returns
    -------
    list of (float, float) or Detection
        Intervals ``(t0, t1)`` in s: the first and last sample time of each run of
        stationary samples; sorted, non-overlapping, ``t0 < t1`` (a run has at least W
        >= 2 samples), each valid as ``ZeroVelocity(t0=t0, t1=t1)``.

    Raises
    ------
    InputError
        Data without specific force (navigation-frame only) or, for SHOE, without gyro
        rates; a window that is not a whole number in [2, N]; a threshold, noise level or
        gravity that is not a positive number; a setting of the other method.

    Notes
    -----
    With the window statistic :math:`T_n` of the samples :math:`n .. n+W-1` (SHOE:
    :func:`shoe_statistic`; magnitude: :func:`magnitude_statistic` with threshold 1),
    sample :math:`k` is stationary when some window holding it is below the threshold,

    .. math:: \min_{n:\, n \le k \le n+W-1} T_n < \gamma,

    which is OpenShoe's rule (a window below :math:`\gamma` marks all its W samples) and
    gaitmap's with windows overlapping by W - 1 samples.

    Examples
    --------
    >>> from bvpnav import detect, scenarios
    >>> walk = scenarios.walking(rate=100.0, n_strides=2)  # stands 1.5 s, two strides, stands
    >>> intervals = detect.stationary(walk.data)
    >>> intervals
    [(0.0, 1.5), (2.1, 2.51), (3.1, 4.61)]
    >>> detect.stationary(walk.data, min_duration=1.0)  # the two long stands only
    [(0.0, 1.5), (3.1, 4.61)]
    """
    if isinstance(min_duration, bool) or not np.isfinite(min_duration) or min_duration < 0:
        raise InputError(f"min_duration={min_duration!r}: give a duration >= 0 in s (0 keeps every "
                         "interval)")
    mask, stat, W, cfg = _detect(data, method, window, threshold, sigma_a, sigma_w, acc_threshold,
                                 gyro_threshold, gravity)
    intervals = intervals_from_mask(data.t, mask, min_duration=min_duration)
    if not return_statistic:
        return intervals
    cfg["min_duration"] = float(min_duration)
    mask.setflags(write=False)
    stat.setflags(write=False)
    thr = cfg.pop("threshold_array", cfg["threshold"])
    if isinstance(thr, np.ndarray):
        thr.setflags(write=False)
    return Detection(intervals=intervals, mask=mask, statistic=stat, threshold=thr,
                     method=method, window=W, params=cfg)


def intervals_from_mask(t, mask, *, min_duration: float = 0.0) -> list[tuple[float, float]]:
    """The runs of True in a per-sample mask as ``(t0, t1)`` intervals in s.

    Parameters
    ----------
    t : array_like, shape (N,)
        Increasing sample times, s.
    mask : array_like of bool, shape (N,)
    min_duration : float
        Runs with ``t1 - t0 < min_duration`` (s) are dropped. A run of a single sample
        has ``t0 == t1`` and cannot be a ``ZeroVelocity`` interval: it is always dropped
        (:func:`stationary` never makes one; its runs have at least W >= 2 samples).

    Returns
    -------
    list of (float, float)
        First and last sample time of each run, sorted and non-overlapping.

    Examples
    --------
    >>> from bvpnav.detect import intervals_from_mask
    >>> t = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5]
    >>> intervals_from_mask(t, [True, True, False, False, True, True])
    [(0.0, 0.1), (0.4, 0.5)]
    """
    t = np.asarray(t, dtype=float)
    m = np.asarray(mask, dtype=bool)
    if m.shape != t.shape or t.ndim != 1:
        raise InputError(f"mask of shape {m.shape} for times of shape {t.shape}; give one boolean per "
                         "sample time")
    starts, ends = _runs(m)
    t0, t1 = t[starts], t[ends]
    keep = (t1 > t0) & (t1 - t0 >= min_duration)
    return [(float(a), float(b)) for a, b in zip(t0[keep], t1[keep], strict=True)]


def zero_velocity_items(intervals, angular_rate: float | bool | str | None = None, *, data=None,
                        **item_kw: Any) -> list:
    r"""One :class:`bvpnav.constraints.ZeroVelocity` per interval (and, on request, one
    :class:`bvpnav.constraints.ZeroAngularRate`).

    Parameters
    ----------
    intervals : list of (float, float) or Detection
        ``(t0, t1)`` in s, e.g. from :func:`stationary`.
    angular_rate : float, True or "spread", optional
        Also say that the body does not turn in each interval: a ``ZeroAngularRate`` with
        this ``sigma`` (rad/s: the gyro's white noise per sample), or hard with ``True``,
        or with ``"spread"`` a sigma per interval and body axis from the interval's own
        gyro readings (needs ``data``; see Notes). It makes a gyro bias observable (it
        needs a gyro error model such as :class:`bvpnav.error_models.GyroBias`). Default:
        velocity only.
    data : ImuData, optional
        The strapdown data with gyro rates (:meth:`bvpnav.ImuData.from_gyro`), for
        ``angular_rate="spread"``.
    **item_kw
        Passed to every ZeroVelocity (``sigma`` in m/s, ``mode``, ``axes``, ``huber``, ...);
        ``name`` gets the interval's number appended (``"stance 0"``, ...; the angular-rate
        items ``"stance 0 rate"``, ...).

    Returns
    -------
    list of ZeroVelocity (and ZeroAngularRate)
        The velocity items first, then the angular-rate items, in interval order.

    Notes
    -----
    ``"spread"``: a detected stance is still enough for the velocity but a foot still rolls
    in it (0.07-0.2 rad/s measured on real walks, ten times a MEMS gyro's noise), and
    saying "zero rate" at the noise sigma there turns that roll into a gyro bias. The
    sigma of interval :math:`k` on body axis :math:`j` is instead the RMS of the measured
    rate over its samples, :math:`\sigma_{kj} = \max(\sqrt{\overline{\hat\omega_j^2}},
    \sigma_{min})` with :math:`\sigma_{min}` = :data:`SPREAD_FLOOR`: it bounds what the
    body turns plus the gyro's own error, so a rolling stance weighs little and a still
    one weighs by its noise (and bias: conservative for a gyro whose bias exceeds its
    noise, the estimate stays unbiased, its standard deviation larger).

    Examples
    --------
    >>> from bvpnav.detect import zero_velocity_items
    >>> zero_velocity_items([(0.0, 1.5), (3.1, 4.6)])
    [ZeroVelocity(mode='hard', t0=0.0, t1=1.5), ZeroVelocity(mode='hard', t0=3.1, t1=4.6)]
    >>> zero_velocity_items([(0.0, 1.5)], sigma=0.01)  # soft, 0.01 m/s
    [ZeroVelocity(mode='soft', sigma=0.01, t0=0.0, t1=1.5)]
    """
    from bvpnav.constraints import ZeroAngularRate, ZeroVelocity

    if isinstance(intervals, Detection):
        intervals = intervals.intervals
    name = item_kw.pop("name", None)
    out = []
    for k, (t0, t1) in enumerate(intervals):
        kw = dict(item_kw)
        if name is not None:
            kw["name"] = f"{name} {k}"
        out.append(ZeroVelocity(t0=float(t0), t1=float(t1), **kw))
    if angular_rate is None or angular_rate is False:
        return out
    spread = isinstance(angular_rate, str)
    if spread and angular_rate != "spread":
        raise InputError(f"zero_velocity_items: angular_rate={angular_rate!r}; give a sigma in rad/s, True "
                         "(hard) or 'spread' (a sigma per stance from its own gyro readings)")
    gyro = _spread_gyro(data) if spread else None
    sigma = None if angular_rate is True else angular_rate
    for k, (t0, t1) in enumerate(intervals):
        kw = {} if name is None else {"name": f"{name} {k} rate"}
        if spread:
            sigma = _spread_sigma(data.t, gyro, float(t0), float(t1), k)
        out.append(ZeroAngularRate(t=(float(t0), float(t1)), sigma=sigma, **kw))
    return out


#: Smallest sigma of ``angular_rate="spread"``, rad/s: a noise-free recording's stance
#: reads the bias alone, which may be zero on an axis.
SPREAD_FLOOR = 1e-6


def _spread_gyro(data) -> np.ndarray:
    gyro = getattr(data, "gyro", None)
    if gyro is None:
        raise InputError("zero_velocity_items(angular_rate='spread'): give data= with gyro rates (an "
                         "ImuData built by ImuData.from_gyro); the sigma of each stance is its own gyro "
                         "readings' RMS")
    return np.asarray(gyro, dtype=float)


def _spread_sigma(t: np.ndarray, gyro: np.ndarray, t0: float, t1: float, k: int) -> np.ndarray:
    """Per sample in ``[t0, t1]`` and body axis, the interval's RMS rate (rad/s), shape (m, 3)."""
    tol = 1e-9 * max(1.0, abs(t0), abs(t1))
    inside = (t >= t0 - tol) & (t <= t1 + tol)
    if not inside.any():
        raise InputError(f"zero_velocity_items: interval {k} ({t0:g}, {t1:g}) s holds no sample of the data; "
                         "give the intervals detected on this data")
    rms = np.maximum(np.sqrt(np.mean(gyro[inside] ** 2, axis=0)), SPREAD_FLOOR)
    return np.tile(rms, (int(inside.sum()), 1))


# ------------------------------------------------------- frame and gravity sanity
#: A mean navigation-frame acceleration at rest larger than this fraction of g is reported.
FRAME_CHECK_LIMIT = 0.5
#: A mean component along gravity above this fraction of g is gravity counted twice.
GRAVITY_TWICE = 1.5
#: The magnitude detector's window (samples) used to find rest for the frame check.
FRAME_CHECK_WINDOW = 5
#: The magnitude detector's gyro threshold (rad/s) for the frame check's rest: still, not
#: merely turning slowly (the detector's default, 0.5 rad/s, accepts a slow turn).
FRAME_CHECK_GYRO = 0.1


@dataclass(frozen=True, eq=False)
class FrameCheck:
    r"""What :func:`frame_check` measured.

    Attributes
    ----------
    over : {"rest", "all"}
        Whether the means are over the samples detected at rest or over the whole
        recording (no rest detected).
    samples : int
        Number of samples averaged.
    mean_acc : ndarray, shape (3,)
        Mean navigation-frame acceleration :math:`\\bar a` over them, m/s^2.
    mean_specific_force : ndarray, shape (3,)
        Mean body-frame specific force over them, m/s^2 (the sensor's own axes).
    gravity : ndarray, shape (3,)
        The navigation-frame gravity vector used, m/s^2.
    along_gravity : float
        :math:`\bar a \cdot \hat g`, m/s^2 (positive: along gravity, i.e. downwards).
    horizontal : float
        :math:`\|\bar a - (\bar a\cdot\hat g)\hat g\|`, m/s^2.
    verdict : str or None
        None (plausible), ``"gravity twice"``, ``"gravity horizontal"``,
        ``"gravity missing"`` or ``"not zero"``.
    message : str or None
        The warning (None when plausible).

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav import ImuData, detect
    >>> t = np.arange(0.0, 10.0, 0.01)
    >>> f = np.tile([0.0, 0.0, 9.80665], (t.size, 1))  # a level z-up sensor at rest
    >>> res = detect.frame_check(ImuData.from_gyro(t, f, np.zeros((t.size, 3))), warn=False)
    >>> res.over, res.samples, res.verdict, res.as_dict()["mean_acc"]
    ('rest', 1000, None, [0.0, 0.0, 0.0])
    """

    over: str
    samples: int
    mean_acc: np.ndarray
    mean_specific_force: np.ndarray
    gravity: np.ndarray
    along_gravity: float
    horizontal: float
    verdict: str | None
    message: str | None

    def as_dict(self) -> dict:
        """Plain numbers (JSON-ready) of the check."""
        return {"over": self.over, "samples": self.samples, "mean_acc": self.mean_acc.tolist(),
                "mean_specific_force": self.mean_specific_force.tolist(), "gravity": self.gravity.tolist(),
                "along_gravity": self.along_gravity, "horizontal": self.horizontal, "verdict": self.verdict,
                "warning": self.message}


def _vec(v, digits: int = 3) -> str:
    return "(" + ", ".join(f"{float(x):.{digits}g}" for x in v) + ")"


def frame_name(gravity) -> str:
    """The navigation frame a gravity vector implies, in words (``"ENU (z up)"``, ...).

    Examples
    --------
    >>> from bvpnav.detect import frame_name
    >>> frame_name([0.0, 0.0, -9.80665])
    'ENU (x east, y north, z up)'
    >>> frame_name([0.0, 0.0, 9.80665])
    'NED (x north, y east, z down)'
    """
    g = np.asarray(gravity, dtype=float)
    u = g / np.linalg.norm(g)
    if u[2] < -0.999:
        return "ENU (x east, y north, z up)"
    if u[2] > 0.999:
        return "NED (x north, y east, z down)"
    return f"a frame with gravity along {_vec(u)}"


def _axis_convention(f_mean: np.ndarray, over: str) -> str:
    """Which sensor axis points up, from the mean specific force at rest (it points up)."""
    k = int(np.argmax(np.abs(f_mean)))
    up = f_mean[k] > 0
    axis = "xyz"[k]
    reads = "at rest" if over == "rest" else "on average"
    conv = ("" if k != 2 else " (z-up body axes, e.g. FLU/ENU)" if up else
            " (z-down body axes, e.g. FRD/NED)")
    return (f"{reads} the sensor reads a specific force of {_vec(f_mean)} m/s^2 in its own axes, so its "
            f"{axis} axis points {'up' if up else 'down'}{conv}")


def _verdict(along: float, horizontal: float, norm: float, g0: float) -> tuple[str | None, str]:
    if norm <= FRAME_CHECK_LIMIT * g0:
        return None, ""
    if along >= GRAVITY_TWICE * g0:
        return "gravity twice", (f"{along:.3g} m/s^2 ({along / g0:.2f} g) along gravity: gravity is counted "
                                 "twice (the attitude turns the specific force, which points up at rest, "
                                 "to point down: the sensor's axes and the navigation frame disagree on "
                                 "which way z points)")
    if horizontal >= FRAME_CHECK_LIMIT * g0:
        return "gravity horizontal", (f"{horizontal:.3g} m/s^2 ({horizontal / g0:.2f} g) horizontal: the "
                                      "attitude turns the sensor's up axis towards the horizontal (axis "
                                      "order, quaternion order or the initial attitude)")
    if along >= FRAME_CHECK_LIMIT * g0:
        return "gravity missing", (f"{along:.3g} m/s^2 ({along / g0:.2f} g) along gravity: the specific "
                                   "force lacks gravity (gravity removed, e.g. a linear or user "
                                   "acceleration given as specific force)")
    return "not zero", f"|mean| = {norm:.3g} m/s^2 ({norm / g0:.2f} g)"


def frame_check(data: ImuLike, *, fixes: dict | None = None, source: str | None = None,
                warn: bool = True) -> FrameCheck:
    r"""Frame and gravity sanity: the mean navigation-frame acceleration at rest against zero.

    Parameters
    ----------
    data : ImuData
        Strapdown data (``specific_force``, ``attitude``, ``gravity``; ``acc = C f + g``).
    fixes : dict, optional
        The fix to name per verdict (``"gravity twice"``, ``"gravity horizontal"``,
        ``"gravity missing"``, ``"not zero"``), in the caller's terms (a Python argument,
        a spec option); a generic one otherwise.
    source : str, optional
        The file the data came from, for the message.
    warn : bool
        Issue the message as a :class:`bvpnav.log.FrameWarning`.

    Returns
    -------
    FrameCheck

    Notes
    -----
    Rest is found by the magnitude detector of :func:`stationary` (window
    :data:`FRAME_CHECK_WINDOW` samples; with gyro rates when there are any, below
    :data:`FRAME_CHECK_GYRO`); with no sample at rest the whole recording is averaged. The
    detector cannot tell rest from steady motion (a car cruising straight), and need not: both
    have a navigation-frame acceleration of about zero, which is all the check uses; the
    message says so.
    With :math:`\hat g = g/\|g\|`,

    .. math:: \bar a = \frac{1}{|R|}\sum_{i \in R} (C_i f_i + g), \quad
              a_\parallel = \bar a\cdot\hat g, \quad
              a_\perp = \|\bar a - a_\parallel \hat g\|,

    which is about zero at rest when the frames are right. A mean larger than
    :data:`FRAME_CHECK_LIMIT` g is reported: :math:`a_\parallel \ge` :data:`GRAVITY_TWICE`
    g is gravity counted twice (a z-down sensor or attitude read as z-up, or the
    reverse), :math:`a_\perp \ge` :data:`FRAME_CHECK_LIMIT` g an up axis turned
    horizontal, :math:`a_\parallel \ge` :data:`FRAME_CHECK_LIMIT` g a specific force
    without gravity.

    Examples
    --------
    A level z-down sensor (forward-right-down axes) at rest, read as ENU, then as NED:

    >>> import numpy as np
    >>> from bvpnav import ImuData, detect
    >>> t = np.arange(0.0, 10.0, 0.01)
    >>> f = np.tile([0.0, 0.0, -9.80665], (t.size, 1))  # +g on the axis that points up: -z
    >>> enu = ImuData.from_gyro(t, f, np.zeros((t.size, 3)), checks=False)
    >>> res = detect.frame_check(enu, warn=False)
    >>> res.verdict, round(res.along_gravity / 9.80665, 2)
    ('gravity twice', 2.0)
    >>> ned = ImuData.from_gyro(t, f, np.zeros((t.size, 3)), frame="ned", checks=False)
    >>> detect.frame_check(ned, warn=False).verdict is None
    True
    """
    from .log import FrameWarning
    from .log import warn as _warn

    f = np.asarray(data.specific_force, dtype=float)
    acc = np.asarray(data.acc, dtype=float)
    g = np.asarray(data.gravity, dtype=float)
    g0 = float(np.linalg.norm(g))
    w = None if data.gyro is None else np.asarray(data.gyro, dtype=float)
    rest = np.zeros(f.shape[0], dtype=bool)
    if f.shape[0] >= FRAME_CHECK_WINDOW:
        stat = magnitude_statistic(f, w, FRAME_CHECK_WINDOW, gyro_threshold=FRAME_CHECK_GYRO, gravity=g0)
        rest = _per_sample_min(stat, FRAME_CHECK_WINDOW) < 1.0
    over = "rest" if np.count_nonzero(rest) >= FRAME_CHECK_WINDOW else "all"
    sel = rest if over == "rest" else slice(None)
    m, fm = acc[sel].mean(axis=0), f[sel].mean(axis=0)
    u = g / g0
    along = float(m @ u)
    horizontal = float(np.linalg.norm(m - along * u))
    verdict, diag = _verdict(along, horizontal, float(np.linalg.norm(m)), g0)
    msg = None
    if verdict is not None:
        n = int(np.count_nonzero(rest)) if over == "rest" else f.shape[0]
        what = (f"the {n} samples the magnitude test finds unaccelerated (at rest, or moving steadily: "
                "bvpnav.detect.stationary)" if over == "rest"
                else f"the whole recording ({n} samples; no rest detected)")
        fix = (fixes or {}).get(verdict) or ("State the navigation frame and the sensor's axes correctly "
                                             "(frame, gravity, attitude, initial attitude).")
        where = f" of {source}" if source else ""
        msg = (f"frame check{where}: the mean navigation-frame acceleration over {what} is {_vec(m)} m/s^2, "
               f"not about zero: {diag}. Navigation frame {frame_name(g)}, gravity {_vec(g, 6)} m/s^2; "
               f"{_axis_convention(fm, over)}. {fix}")
        if warn:
            _warn(msg, FrameWarning)
    n_used = int(np.count_nonzero(rest)) if over == "rest" else f.shape[0]
    return FrameCheck(over=over, samples=n_used, mean_acc=m, mean_specific_force=fm, gravity=g.copy(),
                      along_gravity=along, horizontal=horizontal, verdict=verdict, message=msg)


#: Consecutive samples at an axis's largest absolute rate taken as clipped when no range is stated.
SATURATION_RUN = 3
#: The smallest largest absolute rate (rad/s) taken for a gyro's range when none is stated.
SATURATION_MIN_RATE = 0.5


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and last index of each run of True."""
    edges = np.diff(np.concatenate([[0], mask.view(np.int8), [0]]))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1


def saturation(t, gyro, *, gyro_range: float | None = None, source: str | None = None,
               warn: bool = True) -> dict:
    r"""Gyro samples at the sensor's range: counted, located and reported.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s.
    gyro : array_like, shape (N, 3)
        Body rates, rad/s.
    gyro_range : float, optional
        The gyro's full-scale range, rad/s (> 0): a sample with :math:`|\omega_k| \ge`
        the range (to 1e-6 relative) on an axis is saturated. Without it, an axis is
        saturated where its largest :math:`|\omega_k|` (at least
        :data:`SATURATION_MIN_RATE` rad/s) repeats in runs of at least
        :data:`SATURATION_RUN` consecutive samples (a clipped signal is flat at its
        limit; a measured peak is not).
    source : str, optional
        The file, for the message.
    warn : bool
        Issue the message as a :class:`bvpnav.log.SaturationWarning`.

    Returns
    -------
    dict
        ``samples`` (samples saturated on some axis), ``of`` (N), ``gyro_range`` (rad/s or
        None), ``axes`` (axis -> ``samples``, ``level`` rad/s, ``runs``, ``intervals``: the
        first 20 ``(t0, t1)`` in s) and ``warning`` (str or None).

    Examples
    --------
    A rate of amplitude 6 rad/s on z clipped by a 250 deg/s (4.363 rad/s) gyro:

    >>> import numpy as np
    >>> from bvpnav import detect
    >>> t = np.arange(200) * 0.01
    >>> w = np.zeros((200, 3))
    >>> w[:, 2] = np.clip(6.0 * np.sin(2 * np.pi * t), -4.363, 4.363)
    >>> rep = detect.saturation(t, w, warn=False)
    >>> rep["samples"], rep["axes"]["z"]["runs"], rep["axes"]["z"]["intervals"][0]
    (100, 4, (0.13, 0.37))
    >>> detect.saturation(t, w, gyro_range=4.363, warn=False)["samples"]
    100
    """
    from .log import SaturationWarning
    from .log import warn as _warn

    t = np.asarray(t, dtype=float)
    w = np.asarray(gyro, dtype=float)
    if gyro_range is not None:
        gyro_range = _positive("gyro_range", gyro_range, "rad/s")
    any_axis = np.zeros(w.shape[0], dtype=bool)
    axes: dict[str, dict] = {}
    for k, name in enumerate("xyz"):
        a = np.abs(w[:, k])
        if gyro_range is not None:
            level, at = gyro_range, a >= gyro_range * (1.0 - 1e-6)
            first, last = _runs(at)
        else:
            level = float(a.max()) if a.size else 0.0
            if level < SATURATION_MIN_RATE:
                continue
            first, last = _runs(a >= level * (1.0 - 1e-9))
            long = last - first + 1 >= SATURATION_RUN
            first, last = first[long], last[long]
            at = np.zeros(a.size, dtype=bool)
            for i0, i1 in zip(first, last, strict=True):
                at[i0:i1 + 1] = True
        if first.size:
            any_axis |= at
            spans = [(float(t[i0]), float(t[i1])) for i0, i1 in zip(first[:20], last[:20], strict=True)]
            axes[name] = {"samples": int(np.count_nonzero(at)), "level": float(level),
                          "runs": int(first.size), "intervals": spans}
    count = int(np.count_nonzero(any_axis))
    msg = None
    if count:
        parts = [f"axis {k} {v['samples']} samples at |rate| {v['level']:.4g} rad/s "
                 f"({np.rad2deg(v['level']):.4g} deg/s) in {v['runs']} run(s), the first at t = "
                 f"{v['intervals'][0][0]:.6g}..{v['intervals'][0][1]:.6g} s" for k, v in axes.items()]
        how = (f"at or beyond the stated gyro_range = {gyro_range:.4g} rad/s" if gyro_range is not None
               else f"flat at the axis's largest |rate| for {SATURATION_RUN} or more consecutive samples")
        where = f" of {source}" if source else ""
        share = 100.0 * count / w.shape[0]
        msg = (f"gyro saturation{where}: {count} of {w.shape[0]} samples ({share:.3g} %) are {how}: "
               f"{'; '.join(parts)}. The rates were clipped at the sensor's range there, so the "
               "attitude integrated through them is wrong (its error grows with every clipped run); record "
               "with a larger gyro range, or leave those intervals out")
        if warn:
            _warn(msg, SaturationWarning)
    return {"samples": count, "of": int(w.shape[0]), "gyro_range": gyro_range, "axes": axes, "warning": msg}
