"""The O(N) reference of ``speed_memory.py``: bvpnav's KKT system, banded, solved by LAPACK.

The problem (per axis ``a``, unknowns ``r`` (N), ``w`` (N), end velocities ``v = (v0, v1)``,
error-model parameters ``l`` (q) shared by the axes)::

    min  sum_a ||w_a||^2 / sigma_a^2 + sum_k c_k (p_k^T z - d_k)^2
    s.t. K r_a + B v_a + M (a_hat_a + G_a l + w_a) = 0     (FEM rows, all axes)
         H z = h                                            (hard items)

with ``c_k = lam / sigma_k^2`` for the soft items (bvpnav weighs their rows by
``sqrt(lam) / sigma``) and ``z = (r, v, l)``. With the Lagrangian
``f + 2 mu^T (FEM) + 2 nu^T (H z - h)`` (``mu = y / 2``, bvpnav's convention) stationarity in
``w`` gives ``w_a = -sigma_a^2 M mu_a``: the acceleration residual is eliminated (valid as long
as no item touches ``w``; the benchmark's items do not: positions, end velocities). What is
left is the symmetric system

.. math::

    \\begin{bmatrix} P & F^T & H^T \\\\ F & -\\sigma_a^2 M^2 & 0 \\\\ H & 0 & 0 \\end{bmatrix}
    \\begin{bmatrix} z \\\\ \\mu \\\\ \\nu \\end{bmatrix} =
    \\begin{bmatrix} \\sum_k c_k d_k p_k \\\\ -M \\hat a \\\\ h \\end{bmatrix},
    \\qquad F = [K \\;\\; B \\;\\; M G],\\quad P = \\sum_k c_k p_k p_k^T.

Per axis the unknowns ``(r_j, mu_j)`` are interleaved (``r_j`` at ``2j``, ``mu_j`` at ``2j + 1``):
``K`` (tridiagonal) sits at offsets -3..+3, ``M^2`` (pentadiagonal) at 0, +-2, +-4, position
rows interpolated between two nodes at 0, +-2; so the matrix is banded with ``kl = ku = 4``.
Everything else (``v0, v1`` per axis, one multiplier per hard row, the q parameters) is a
*border*: one ``dgbtrf`` (the banded block is the same for every axis here: one grid, one
``sigma_a``, the fixes at the same times on every axis), then per axis one ``dgbtrs`` with
``1 + (border columns touching that axis)`` right-hand sides (``[b_a | C_a]``), the Schur
complement ``S_bb - sum_a C_a^T A^{-1} C_a`` of the border (dense, ``2d + d k_hard + q``
square) and ``z_band = y - X z_border``. Cost and memory are O(N).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack

KL = KU = 4


@dataclass
class Spec:
    """One benchmark problem in plain arrays (what both bvpnav and the reference consume).

    Attributes
    ----------
    t : ndarray (N,)
        Sample times, s.
    acc : ndarray (N, d)
        Measured acceleration, m/s^2.
    sigma_a : float
        Accelerometer noise, m/s^2.
    pos_t, pos_val, pos_sigma
        Soft position fixes: times (m,) s, values (m, d) m, standard deviation m (lam-weighted).
    hard_t, hard_val
        Hard positions: times (k,) s and values (k, d) m.
    vel_val, vel_sigma
        Soft velocities at the two ends of the window: values (2, d) m/s, standard deviation m/s.
    error_model : bool
        ``ScaleFactor() + Bias()`` per axis (``G``: the measured acceleration and ones).
    truth : ndarray (N, d)
        True positions, m (for orientation only).
    """

    t: np.ndarray
    acc: np.ndarray
    sigma_a: float
    pos_t: np.ndarray
    pos_val: np.ndarray
    pos_sigma: float
    hard_t: np.ndarray
    hard_val: np.ndarray
    vel_val: np.ndarray
    vel_sigma: float
    error_model: bool = False
    truth: np.ndarray = field(default=None, repr=False)

    @property
    def n(self) -> int:
        return self.t.size

    @property
    def d(self) -> int:
        return self.acc.shape[1]

    def columns(self) -> np.ndarray:
        """Error-model columns ``G`` (N, d, q): per axis a scale factor (column ``acc``) and a bias."""
        n, d = self.acc.shape
        if not self.error_model:
            return np.zeros((n, d, 0))
        G = np.zeros((n, d, 2 * d))
        for a in range(d):
            G[:, a, 2 * a] = self.acc[:, a]
            G[:, a, 2 * a + 1] = 1.0
        return G


def _interp(t: np.ndarray, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Element index ``j`` and weight ``theta`` of ``r(t) = (1-theta) r_j + theta r_{j+1}``."""
    j = np.clip(np.searchsorted(t, times, side="right") - 1, 0, t.size - 2)
    return j, (times - t[j]) / (t[j + 1] - t[j])


def reference_solve(spec: Spec, lam: float = 1.0) -> np.ndarray:
    """Trajectory ``r`` (N, d) of the benchmark problem: banded LU + bordering (see module).

    Parameters
    ----------
    spec : Spec
    lam : float
        Weight of the soft items (dimensionless).

    Returns
    -------
    ndarray, shape (N, d)
        Nodal positions, m.
    """
    t, n, d = spec.t, spec.n, spec.d
    h = np.diff(t)
    kd = np.zeros(n)
    kd[:-1] += 1.0 / h
    kd[1:] += 1.0 / h
    md = np.zeros(n)
    md[:-1] += h / 3.0
    md[1:] += h / 3.0
    M = sp.diags([h / 6.0, md, h / 6.0], [-1, 0, 1], format="csr")
    M2 = M @ M
    m2 = [M2.diagonal(k) for k in range(3)]
    G = spec.columns()
    q = G.shape[2]
    jp, tp = _interp(t, spec.pos_t)
    jh, th = _interp(t, spec.hard_t)
    nh, cp = jh.size, lam / spec.pos_sigma**2
    nb = 2 * d + nh * d + q  # border: (v0, v1) per axis, hard multipliers per axis, parameters
    S = np.zeros((nb, nb))
    rb = np.zeros(nb)
    cv = lam / spec.vel_sigma**2
    for a in range(d):
        S[2 * a, 2 * a] = S[2 * a + 1, 2 * a + 1] = cv
        rb[2 * a:2 * a + 2] = cv * spec.vel_val[:, a]
        rb[2 * d + a * nh:2 * d + (a + 1) * nh] = spec.hard_val[:, a]
    # the banded block of one axis (the same for every axis but its right-hand side)
    n2 = 2 * n
    prr0 = np.zeros(n)
    np.add.at(prr0, jp, cp * (1 - tp) ** 2)
    np.add.at(prr0, jp + 1, cp * tp**2)
    prr1 = np.zeros(n - 1)
    np.add.at(prr1, jp, cp * (1 - tp) * tp)
    diag = [np.zeros(n2) for _ in range(KU + 1)]
    diag[0][0::2], diag[0][1::2] = prr0, -spec.sigma_a**2 * m2[0]
    diag[1][0::2], diag[1][1:-1:2] = kd, -1.0 / h
    diag[2][0:-2:2], diag[2][1:-2:2] = prr1, -spec.sigma_a**2 * m2[1]
    diag[3][0:-2:2] = -1.0 / h
    diag[4][1:-4:2] = -spec.sigma_a**2 * m2[2]
    ab = np.zeros((2 * KL + KU + 1, n2), order="F")
    for k, dk in enumerate(diag):
        ab[KL + KU - k, k:] = dk[:n2 - k]
        ab[KL + KU + k, :n2 - k] = dk[:n2 - k]
    lu, piv, info = lapack.dgbtrf(ab, KL, KU, overwrite_ab=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"banded factor: dgbtrf info {info}")
    del ab
    pieces = []
    for a in range(d):
        cols = np.r_[2 * a, 2 * a + 1, 2 * d + a * nh + np.arange(nh), 2 * d + nh * d + np.arange(q)]
        B = np.zeros((n2, cols.size + 1), order="F")  # [rhs | border columns touching axis a]
        np.add.at(B[:, 0], 2 * jp, cp * (1 - tp) * spec.pos_val[:, a])
        np.add.at(B[:, 0], 2 * jp + 2, cp * tp * spec.pos_val[:, a])
        B[1::2, 0] = -(M @ spec.acc[:, a])
        B[1, 1], B[n2 - 1, 2] = 1.0, -1.0
        B[2 * jh, 3 + np.arange(nh)] = 1 - th
        B[2 * jh + 2, 3 + np.arange(nh)] += th
        if q:
            B[1::2, 3 + nh:] = M @ G[:, a, :]
        Y, info = lapack.dgbtrs(lu, KL, KU, B, piv)
        if info != 0:
            raise np.linalg.LinAlgError(f"banded solve: dgbtrs info {info}")
        C = B[:, 1:]
        S[np.ix_(cols, cols)] -= C.T @ Y[:, 1:]
        rb[cols] -= C.T @ Y[:, 0]
        pieces.append((cols, Y))
        del B
    zb = np.linalg.solve(S, rb)
    r = np.empty((n, d))
    for a, (cols, Y) in enumerate(pieces):
        r[:, a] = Y[0::2, 0] - Y[0::2, 1:] @ zb[cols]
    return r
