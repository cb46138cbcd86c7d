"""Classical baselines: initial-value integration and a Rauch-Tung-Striebel smoother.

- :func:`trapezoid`, :func:`simpson`, :func:`romberg`: integrate acceleration twice from
  known initial values (the initial-value view; errors grow without bound).
- :func:`rts_smoother`: a Kalman filter plus RTS backward pass with state (position,
  velocity, accelerometer bias) that uses position/velocity measurements at given times
  (e.g. the four boundary values). It cannot use information that is not a measurement
  of the state at one instant (average velocities, symmetry, track shapes), which is
  what the examples compare against bvpnav.

All functions work per axis on 1-D arrays (``acc`` of shape (N,)) or column-wise on
(N, d) arrays.

Examples
--------
Constant acceleration 0.5 m/s^2 for 2 s from rest: 1 m/s and 1 m at the end, by every
rule (exact for a constant):

>>> import numpy as np
>>> from bvpnav import baselines
>>> t = np.linspace(0.0, 2.0, 21)
>>> v, r = baselines.trapezoid(t, np.full(21, 0.5))
>>> print(f"{v[-1]:.3f} m/s, {r[-1]:.3f} m")
1.000 m/s, 1.000 m
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.integrate import cumulative_simpson, cumulative_trapezoid

from .errors import InputError
from .grid import TimeGrid

__all__ = ["trapezoid", "simpson", "romberg", "romberg_block", "rts_smoother"]


def _prep(t, acc):
    grid = TimeGrid(t)
    a = np.asarray(acc, dtype=float)
    if a.shape[0] != grid.t.size:
        raise InputError(f"acc has {a.shape[0]} samples but t has {grid.t.size}; lengths must match")
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        raise InputError(f"acc: non-finite value at sample {int(bad[0, 0])}; remove or repair it")
    return grid.t, a


def _twice(t, a, v0, r0, integrate):
    v = v0 + integrate(a, x=t, axis=0, initial=0.0)
    r = r0 + integrate(v, x=t, axis=0, initial=0.0)
    return v, r


def trapezoid(t, acc, v0=0.0, r0=0.0):
    r"""Velocity and position by the cumulative trapezoid rule, twice.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s (strictly increasing; non-uniform allowed).
    acc : array_like, shape (N,) or (N, d)
        Acceleration, m/s^2.
    v0, r0 : float or array_like
        Initial velocity (m/s) and position (m).

    Returns
    -------
    v, r : ndarray
        Velocity (m/s) and position (m) at every sample.

    Notes
    -----
    :math:`v_{k+1} = v_k + \tfrac{h_k}{2}(a_k + a_{k+1})`, the same for ``r`` from ``v``;
    the local error is :math:`O(h^3)`, the global error :math:`O(h^2)` plus the integrated
    measurement errors.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.baselines import trapezoid
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> v, r = trapezoid(t, np.full(21, 0.5), v0=1.0)  # 0.5 m/s^2 from 1 m/s
    >>> print(f"{v[-1]:.3f} m/s, {r[-1]:.3f} m")
    2.000 m/s, 3.000 m
    """
    t, a = _prep(t, acc)
    return _twice(t, a, v0, r0, cumulative_trapezoid)


def simpson(t, acc, v0=0.0, r0=0.0):
    """Velocity and position by scipy's cumulative Simpson rule, twice.

    Same parameters and returns as :func:`trapezoid`.

    Notes
    -----
    Composite Simpson on each pair of intervals (fourth order for smooth data;
    ``scipy.integrate.cumulative_simpson`` treats the odd last interval and
    non-uniform steps).

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.baselines import simpson
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> v, r = simpson(t, 2.0 * t)  # a = 2t: v = t^2, r = t^3/3
    >>> print(f"{v[-1]:.4f} m/s, {r[-1]:.4f} m")
    4.0000 m/s, 2.6667 m
    """
    t, a = _prep(t, acc)
    if t.size < 3:
        raise InputError("simpson needs at least 3 samples")
    return _twice(t, a, v0, r0, cumulative_simpson)


def romberg_block(y: np.ndarray, h: float) -> float:
    r"""Romberg's estimate of the integral of 2^k + 1 equally spaced samples ``y``.

    Notes
    -----
    Trapezoid sums :math:`T_j` with steps :math:`2^{k-j} h` are combined by Richardson
    extrapolation :math:`R_{j,m} = R_{j,m-1} + (R_{j,m-1} - R_{j-1,m-1})/(4^m - 1)`;
    with 9 samples (k = 3) the error is :math:`O(h^8)` for smooth integrands.

    Examples
    --------
    The integral of :math:`\sin` over :math:`[0, \pi]` (exactly 2) from nine samples:

    >>> import numpy as np
    >>> from bvpnav.baselines import romberg_block
    >>> print(f"{romberg_block(np.sin(np.linspace(0.0, np.pi, 9)), np.pi / 8):.5f}")
    2.00001
    """
    n = y.size - 1
    k = int(round(np.log2(n)))
    if n < 1 or 2**k != n:
        raise InputError(f"romberg_block needs 2^k + 1 samples, got {y.size}")
    R = []
    for j in range(k + 1):
        step = n // 2**j
        yy = y[::step]
        R.append([(step * h) * (yy.sum() - 0.5 * (yy[0] + yy[-1]))])
    for m in range(1, k + 1):
        for j in range(m, k + 1):
            R[j].append(R[j][m - 1] + (R[j][m - 1] - R[j - 1][m - 1]) / (4**m - 1))
    return float(R[k][k])


def romberg(t, acc, v0=0.0, r0=0.0, block: int = 8):
    """Velocity and position by Romberg integration over blocks of ``block`` intervals.

    The third paper's scheme: the integral over each block of 8 sample intervals is
    Romberg's extrapolation of the trapezoid sums with steps 8h, 4h, 2h, h; values at
    the samples inside a block (and in a last partial block) come from the cumulative
    Simpson rule anchored at the block start, so the error does not accumulate across
    blocks faster than Romberg's.

    Parameters
    ----------
    t : array_like, shape (N,)
        Equally spaced sample times, s.
    acc, v0, r0
        As :func:`trapezoid`.
    block : int
        Intervals per block, a power of two (default 8).

    Returns
    -------
    v, r : ndarray
        Velocity (m/s) and position (m) at every sample.

    Raises
    ------
    InputError
        For a non-uniform grid (naming the first step that differs) or a bad block.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.baselines import romberg
    >>> t = np.linspace(0.0, 2.0, 17)
    >>> v, r = romberg(t, 3.0 * t ** 2)  # v = t^3, r = t^4/4
    >>> print(f"{v[-1]:.4f} m/s, {r[-1]:.4f} m")
    8.0000 m/s, 4.0000 m
    """
    t, a = _prep(t, acc)
    h = np.diff(t)
    dev = np.nonzero(np.abs(h - h[0]) > 1e-9 * max(abs(h[0]), 1.0) + 1e-6 * h[0])[0]
    if dev.size:
        raise InputError(f"romberg needs equally spaced samples; step {int(dev[0])} "
                         f"(t={t[dev[0]]:g} s) is {h[dev[0]]:g} s, not {h[0]:g} s. "
                         "Use simpson() or trapezoid() for non-uniform data.")
    if block < 2 or block & (block - 1):
        raise InputError(f"block={block}: must be a power of two >= 2")
    if t.size < 3:
        raise InputError("romberg needs at least 3 samples")

    def integrate(y, start):
        y2 = y.reshape(y.shape[0], -1)
        out = np.empty_like(y2)
        for c in range(y2.shape[1]):
            col = y2[:, c]
            acc_val = np.asarray(start, dtype=float).ravel()
            base = acc_val[c] if acc_val.size > 1 else float(acc_val[0])
            out[0, c] = base
            i = 0
            while i < col.size - 1:
                j = min(i + block, col.size - 1)
                ws = max(0, j - block)  # a short last block borrows earlier samples
                win = col[ws:j + 1]
                if win.size >= 3:
                    cs = cumulative_simpson(win, dx=h[0], initial=0.0)
                else:
                    cs = cumulative_trapezoid(win, dx=h[0], initial=0.0)
                inner = cs[i - ws:] - cs[i - ws]
                if j - i == block:
                    inner[-1] = romberg_block(col[i:j + 1], h[0])
                out[i + 1:j + 1, c] = out[i, c] + inner[1:]
                i = j
        return out.reshape(y.shape)

    v = integrate(a, v0)
    r = integrate(v, r0)
    return v, r


def rts_smoother(t, acc, measurements, sigma_a: float = 1.0, sigma_bias: float = 0.0,
                 bias0_std: float = 10.0, initial=None, initial_std=(1e3, 1e3)) -> pd.DataFrame:
    r"""Kalman filter and Rauch-Tung-Striebel smoother with state (position, velocity, bias).

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s.
    acc : array_like, shape (N,)
        Measured acceleration (one axis), m/s^2; modelled as ``a_true + bias + noise``.
    measurements : sequence of (time, kind, value, std)
        ``kind`` is ``"position"`` (m) or ``"velocity"`` (m/s); ``time`` must be a sample
        time (the smoother does not interpolate); ``std`` > 0 in the measurement's units
        (use a small value such as 1e-6 for exact knowledge).
    sigma_a : float
        Accelerometer white-noise standard deviation per sample, m/s^2.
    sigma_bias : float
        Bias random-walk density, m/s^2/sqrt(s) (0: constant bias).
    bias0_std : float
        Prior standard deviation of the bias, m/s^2 (0 removes the bias state's freedom).
    initial : (p0, v0), optional
        Prior mean of position (m) and velocity (m/s) at the first sample (default 0).
    initial_std : (float, float)
        Prior standard deviations for ``initial`` (large: uninformative).

    Returns
    -------
    pandas.DataFrame
        Indexed by ``t``: ``position`` (m), ``velocity`` (m/s), ``bias`` (m/s^2) and their
        standard deviations ``position_std``, ``velocity_std``, ``bias_std``.

    Notes
    -----
    Between samples :math:`k, k+1` (step :math:`h`), with the mean measured acceleration
    :math:`u = (\hat a_k + \hat a_{k+1})/2`,

    .. math::
        x_{k+1} = F x_k + g\,u + g\,\epsilon, \quad
        F = \begin{bmatrix} 1 & h & -h^2/2 \\ 0 & 1 & -h \\ 0 & 0 & 1 \end{bmatrix},
        \quad g = (h^2/2, h, 0)^T,

    with :math:`\epsilon \sim N(0, \sigma_a^2)` and the bias random walk adding
    :math:`\sigma_b^2 h` to its variance. The smoother is the standard RTS recursion
    :math:`\hat x_k^s = \hat x_k + C_k (\hat x_{k+1}^s - \hat x_{k+1}^-)` with
    :math:`C_k = P_k F^T (P_{k+1}^-)^{-1}`.

    Examples
    --------
    An accelerometer reading 0.1 m/s^2 high, known to start at rest at 0 m and to end at 1 m
    after 2 s under a true 0.5 m/s^2: the smoother finds the bias:

    >>> import numpy as np
    >>> from bvpnav.baselines import rts_smoother
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> known = [(0.0, "position", 0.0, 1e-6), (0.0, "velocity", 0.0, 1e-6), (2.0, "position", 1.0, 1e-6)]
    >>> est = rts_smoother(t, np.full(21, 0.6), known, sigma_a=0.01)
    >>> print(est[["position", "velocity", "bias"]].iloc[-1].round(3).to_dict())
    {'position': 1.0, 'velocity': 1.0, 'bias': 0.1}
    """
    t, a = _prep(t, acc)
    if a.ndim != 1:
        raise InputError(f"rts_smoother works on one axis; acc has shape {a.shape}")
    n = t.size
    index = {}
    for i, m in enumerate(measurements):
        try:
            tm, kind, val, std = m
        except (TypeError, ValueError) as exc:
            raise InputError(f"measurement {i}: expected (time, kind, value, std), got {m!r}") from exc
        k = int(np.argmin(np.abs(t - tm)))
        if abs(t[k] - tm) > 1e-9 * max(1.0, abs(tm)):
            raise InputError(f"measurement {i}: t={tm!r} s is not a sample time; the smoother "
                             "needs measurements at samples")
        if kind not in ("position", "velocity"):
            raise InputError(f"measurement {i}: kind={kind!r}; use 'position' or 'velocity'")
        if not (np.isfinite(std) and std > 0):
            raise InputError(f"measurement {i}: std={std!r} must be > 0")
        index.setdefault(k, []).append((0 if kind == "position" else 1, float(val), float(std)))
    x = np.zeros(3)
    if initial is not None:
        x[:2] = initial
    P = np.diag([initial_std[0] ** 2, initial_std[1] ** 2, bias0_std**2])
    xs_f = np.empty((n, 3))
    Ps_f = np.empty((n, 3, 3))
    xs_p = np.empty((n, 3))
    Ps_p = np.empty((n, 3, 3))
    Fs = np.empty((n, 3, 3))

    def update(x, P, k):
        for comp, val, std in index.get(k, []):
            H = np.zeros(3)
            H[comp] = 1.0
            S = H @ P @ H + std**2
            K = P @ H / S
            x = x + K * (val - x[comp])
            IKH = np.eye(3) - np.outer(K, H)  # Joseph form: stays symmetric positive definite
            P = IKH @ P @ IKH.T + std**2 * np.outer(K, K)
            P = 0.5 * (P + P.T)
        return x, P

    xs_p[0], Ps_p[0] = x, P
    x, P = update(x, P, 0)
    xs_f[0], Ps_f[0] = x, P
    for k in range(n - 1):
        h = t[k + 1] - t[k]
        F = np.array([[1.0, h, -0.5 * h * h], [0.0, 1.0, -h], [0.0, 0.0, 1.0]])
        g = np.array([0.5 * h * h, h, 0.0])
        u = 0.5 * (a[k] + a[k + 1])
        Q = sigma_a**2 * np.outer(g, g)
        Q[2, 2] += sigma_bias**2 * h
        x = F @ x + g * u
        P = F @ P @ F.T + Q
        Fs[k] = F
        xs_p[k + 1], Ps_p[k + 1] = x, P
        x, P = update(x, P, k + 1)
        xs_f[k + 1], Ps_f[k + 1] = x, P
    xs = xs_f.copy()
    Ps = Ps_f.copy()
    for k in range(n - 2, -1, -1):
        # C = P_f F^T (P^-)^{-1} by a solve: a pseudo-inverse would truncate the small
        # eigenvalues that tiny process noise leaves in P^- (and lose the answer)
        try:
            C = np.linalg.solve(Ps_p[k + 1], Fs[k] @ Ps_f[k]).T
        except np.linalg.LinAlgError:  # exactly singular (no process noise at all)
            C = np.linalg.lstsq(Ps_p[k + 1], Fs[k] @ Ps_f[k], rcond=None)[0].T
        xs[k] = xs_f[k] + C @ (xs[k + 1] - xs_p[k + 1])
        Ps[k] = Ps_f[k] + C @ (Ps[k + 1] - Ps_p[k + 1]) @ C.T
    std = np.sqrt(np.maximum(np.einsum("kii->ki", Ps), 0.0))
    return pd.DataFrame({"position": xs[:, 0], "velocity": xs[:, 1], "bias": xs[:, 2],
                         "position_std": std[:, 0], "velocity_std": std[:, 1], "bias_std": std[:, 2]},
                        index=pd.Index(t, name="t"))
