"""Symmetric block-tridiagonal systems: solves and the selected inverse by cyclic reduction.

A symmetric matrix whose unknowns are grouped into ``n`` blocks of ``b`` with couplings
only between neighbouring blocks is stored as its diagonal blocks ``D`` (n, b, b) and its
upper blocks ``U`` (n - 1, b, b), ``U[i] = A[i, i+1]``. Cyclic (odd-even) reduction
eliminates the odd blocks, which couple only to even ones, leaving a block-tridiagonal
Schur complement on the even blocks with half as many blocks; after ``log2 n`` levels
one block remains. Every level is a handful of batched small dense operations, so the
whole factorization is vectorized: O(n b^3) work with no Python loop over blocks.

The same levels, run backwards, give

- :meth:`CyclicReduction.solve`: ``A X = R`` for several right-hand sides, and
- :meth:`CyclicReduction.selected_inverse`: the blocks of ``A^{-1}`` on the pattern of
  ``A`` (its diagonal and first off-diagonal blocks), without forming the dense inverse.

The pivots are the diagonal blocks of the odd unknowns at each level: Schur complements
of contiguous runs of blocks. They are inverted by LU with partial pivoting inside the
block; no pivoting happens between blocks, so a pivot that is singular (a contiguous run
of blocks whose own submatrix is singular) stops the factorization with
:class:`numpy.linalg.LinAlgError`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CyclicReduction", "block_tridiagonal_dense", "equilibrated_inverse", "symmetric_scale",
           "PIVOT_COND"]

#: Largest infinity-norm condition number accepted for a pivot block.
PIVOT_COND = 1e13


def symmetric_scale(blocks: np.ndarray) -> np.ndarray:
    """Per-row factors ``s`` (..., b) with which ``s_i A_ij s_j`` has rows of max-norm about
    1 (one Ruiz step); rows of zeros get 1."""
    diag = np.sqrt(np.abs(blocks).max(axis=-1))
    diag[diag == 0] = 1.0
    return 1.0 / diag


def equilibrated_inverse(blocks: np.ndarray, return_condition: bool = False):
    """Inverses of a stack of square blocks (k, b, b), refusing singular ones.

    Each block is scaled symmetrically to unit row maxima (:func:`symmetric_scale`) before
    LU with partial pivoting, and refused (:class:`numpy.linalg.LinAlgError`) when the
    scaled block's infinity-norm condition number exceeds :data:`PIVOT_COND`: a block whose
    unknowns merely have different units is not refused, a singular one is. With
    ``return_condition``, also the largest of those condition numbers.
    """
    scale = symmetric_scale(blocks)
    Bs = blocks * scale[..., :, None] * scale[..., None, :]
    try:
        inv_s = np.linalg.inv(Bs)
    except np.linalg.LinAlgError as exc:
        raise np.linalg.LinAlgError("singular pivot block") from exc
    cond = np.abs(Bs).sum(axis=-1).max(axis=-1) * np.abs(inv_s).sum(axis=-1).max(axis=-1)
    bad = ~np.isfinite(cond) | (cond > PIVOT_COND)
    if np.any(bad):
        raise np.linalg.LinAlgError(f"singular pivot block (condition number {np.nanmax(cond):.1e})")
    inv = inv_s * scale[..., :, None] * scale[..., None, :]
    return (inv, float(cond.max(initial=1.0))) if return_condition else inv


def _t(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


@dataclass
class _Level:
    n: int                 # blocks at this level
    U: np.ndarray          # (n-1, b, b) upper blocks at this level
    Dinv: np.ndarray       # (no, b, b) inverses of the odd pivots
    F1: np.ndarray         # (no, b, b) D_o^{-1} A[o, o-1]
    F2: np.ndarray         # (no2, b, b) D_o^{-1} A[o, o+1] (odd blocks with a right neighbour)


class CyclicReduction:
    r"""Cyclic-reduction factorization of a symmetric block-tridiagonal matrix.

    Parameters
    ----------
    D : ndarray, shape (n, b, b) or (c, n, b, b)
        Diagonal blocks (each symmetric); with a leading axis, ``c`` independent chains
        of the same length factorised together.
    U : ndarray, shape (n - 1, b, b) or (c, n - 1, b, b)
        Upper blocks, ``U[i] = A[i, i+1]`` (the lower ones are their transposes).

    Raises
    ------
    numpy.linalg.LinAlgError
        When a pivot block is singular or has a condition number above
        :data:`PIVOT_COND`.

    Notes
    -----
    One level, with ``o`` odd and its even neighbours ``o - 1``, ``o + 1``:

    .. math::

        D'_e = D_e - A_{e,e-1} D_{e-1}^{-1} A_{e-1,e} - A_{e,e+1} D_{e+1}^{-1} A_{e+1,e},
        \qquad U'_e = -A_{e,e+1} D_{e+1}^{-1} A_{e+1,e+2}.

    The selected inverse ``Z`` runs the levels back: with
    :math:`F_1 = D_o^{-1} A_{o,o-1}` and :math:`F_2 = D_o^{-1} A_{o,o+1}`,

    .. math::

        Z_{o,e} = -F_1 Z_{o-1,e} - F_2 Z_{o+1,e}, \qquad
        Z_{o,o} = D_o^{-1} - F_1 Z_{o-1,o} - F_2 Z_{o+1,o},

    which needs only the blocks of the even system's inverse on its own pattern
    (Takahashi's observation for tridiagonal patterns).
    """

    def __init__(self, D: np.ndarray, U: np.ndarray):
        D = np.asarray(D, dtype=float)
        U = np.asarray(U, dtype=float)
        self.batched = D.ndim == 4
        if not self.batched:
            D, U = D[None], U[None]
        c, n, b, _ = D.shape
        if U.shape != (c, max(n - 1, 0), b, b):
            raise ValueError(f"upper blocks of shape {U.shape}; expected {(c, max(n - 1, 0), b, b)}")
        self.n, self.b = n, b
        self.levels: list[_Level] = []
        self.pivot_condition = 1.0  # the largest equilibrated condition number of a pivot
        while n > 1:
            odd = np.arange(1, n, 2)
            no = odd.size
            no2 = int((odd + 1 < n).sum())  # odd blocks with a right neighbour come first
            Dinv, worst = equilibrated_inverse(D[:, odd], return_condition=True)
            self.pivot_condition = max(self.pivot_condition, worst)
            F1 = Dinv @ _t(U[:, odd - 1])             # D_o^{-1} A[o, o-1]
            F2 = Dinv[:, :no2] @ U[:, odd[:no2]]      # D_o^{-1} A[o, o+1]
            Dn = D[:, 0::2].copy()
            # right odd neighbour o = e + 1 of even e (e = o - 1): A[e,o] D_o^-1 A[o,e]
            Dn[:, :no] -= U[:, odd - 1] @ F1
            # left odd neighbour o = e - 1 of even e (e = o + 1): A[e,o] D_o^-1 A[o,e]
            Dn[:, 1:no2 + 1] -= _t(U[:, odd[:no2]]) @ F2
            Un = -(U[:, odd[:no2] - 1] @ F2)          # between e = o - 1 and e + 2 = o + 1
            self.levels.append(_Level(n, U, Dinv, F1, F2))
            D, U, n = 0.5 * (Dn + _t(Dn)), Un, Dn.shape[1]
        self._top, worst = equilibrated_inverse(D, return_condition=True)
        self.pivot_condition = max(self.pivot_condition, worst)

    def solve(self, R: np.ndarray) -> np.ndarray:
        """Solve ``A X = R`` for ``R`` of shape (n, b) or (n, b, k) (with a leading chain
        axis when the matrix has one)."""
        R = np.asarray(R, dtype=float)
        if not self.batched:
            R = R[None]
        vec = R.ndim == 3
        r = R[..., None] if vec else R.copy()
        stack = []
        for lv in self.levels:
            odd = np.arange(1, lv.n, 2)
            no2 = lv.F2.shape[1]
            g = lv.Dinv @ r[:, odd]                   # D_o^{-1} r_o
            rn = r[:, 0::2].copy()
            rn[:, :odd.size] -= lv.U[:, odd - 1] @ g
            rn[:, 1:no2 + 1] -= _t(lv.U[:, odd[:no2]]) @ g[:, :no2]
            stack.append(g)
            r = rn
        x = self._top @ r
        for lv, g in zip(reversed(self.levels), reversed(stack), strict=True):
            odd = np.arange(1, lv.n, 2)
            no2 = lv.F2.shape[1]
            xo = g - lv.F1 @ x[:, :odd.size]
            xo[:, :no2] -= lv.F2 @ x[:, 1:no2 + 1]
            full = np.empty((x.shape[0], lv.n) + x.shape[2:])
            full[:, 0::2] = x
            full[:, odd] = xo
            x = full
        x = x[..., 0] if vec else x
        return x if self.batched else x[0]

    def selected_inverse(self) -> tuple[np.ndarray, np.ndarray]:
        """The blocks of ``A^{-1}`` on the pattern of ``A``.

        Returns
        -------
        Zd : ndarray, shape (n, b, b)
            ``Z[i, i]``.
        Zu : ndarray, shape (n - 1, b, b)
            ``Z[i, i+1]``.

        With a leading chain axis when the matrix has one.
        """
        Zd = self._top.copy()
        c = Zd.shape[0]
        Zu = np.empty((c, 0, self.b, self.b))
        for lv in reversed(self.levels):
            odd = np.arange(1, lv.n, 2)
            no, no2 = odd.size, lv.F2.shape[1]
            # Z[o, o-1] and Z[o, o+1] from the even system's blocks
            Zo_l = -(lv.F1 @ Zd[:, :no])
            Zo_l[:, :no2] -= lv.F2 @ _t(Zu[:, :no2])
            Zo_r = -(lv.F1[:, :no2] @ Zu[:, :no2]) - lv.F2 @ Zd[:, 1:no2 + 1]
            Zoo = lv.Dinv - lv.F1 @ _t(Zo_l)
            Zoo[:, :no2] -= lv.F2 @ _t(Zo_r)
            Zd_new = np.empty((c, lv.n, self.b, self.b))
            Zd_new[:, 0::2] = Zd
            Zd_new[:, odd] = 0.5 * (Zoo + _t(Zoo))
            Zu_new = np.empty((c, lv.n - 1, self.b, self.b))
            Zu_new[:, odd - 1] = _t(Zo_l)              # Z[o-1, o]
            Zu_new[:, odd[:no2]] = Zo_r                # Z[o, o+1]
            Zd, Zu = Zd_new, Zu_new
        return (Zd, Zu) if self.batched else (Zd[0], Zu[0])


def block_tridiagonal_dense(D: np.ndarray, U: np.ndarray) -> np.ndarray:
    """The dense matrix of blocks ``D``, ``U`` (for tests and small cases)."""
    n, b, _ = D.shape
    A = np.zeros((n * b, n * b))
    for i in range(n):
        A[i * b:(i + 1) * b, i * b:(i + 1) * b] = D[i]
        if i + 1 < n:
            A[i * b:(i + 1) * b, (i + 1) * b:(i + 2) * b] = U[i]
            A[(i + 1) * b:(i + 2) * b, i * b:(i + 1) * b] = U[i].T
    return A
