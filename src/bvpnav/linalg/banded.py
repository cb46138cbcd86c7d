r"""The least-squares KKT system as a banded matrix with a border: O(N) factorizations.

The augmented system of :mod:`bvpnav.linalg.lsq`,

.. math::

    S = \begin{bmatrix} -I & D & 0 \\ D^T & 0 & E^T \\ 0 & E & 0 \end{bmatrix},
    \qquad S z = b, \quad z = (\rho, x, \mu),

is never assembled here. Objective rows of ``D`` that touch only a few neighbouring time
nodes are *folded*: their residual :math:`\rho_f = D_f x - b_f` is eliminated exactly,
which leaves the reduced symmetric system

.. math::

    \begin{bmatrix} D_f^T D_f & D_u^T & E^T \\ D_u & -I & 0 \\ E & 0 & 0 \end{bmatrix}
    \begin{bmatrix} x \\ \rho_u \\ \mu \end{bmatrix} =
    \begin{bmatrix} b_x + D_f^T b_f \\ b_u \\ b_\mu \end{bmatrix}

(``u``: the unfolded rows, those that reach far in time). Every unknown and multiplier
gets a time node (positions, residuals and FEM multipliers of node ``j`` at ``j``; a
hard item's multiplier at the middle node of the row; end velocities at the first and
last node) or goes to the *border*: the error-model parameters (dense columns), the
residuals of unfolded rows and the multipliers of hard rows that reach far (average
velocities, symmetry). Ordered by node, the local part is banded with a small
bandwidth (5/5 for one axis with point fixes: ``r_j, w_j, mu_j`` per node); axes that no
row couples are laid end to end. The banded part is factorised once by LAPACK's
``dgbtrf`` (partial pivoting within the band) after a symmetric Ruiz equilibration, and
the border enters through its Schur complement (one solve with ``k`` right-hand sides).

Why this is accurate: the folded block is :math:`D_f^T D_f`, which squares only the
conditioning of the folded rows (the acceleration form's residual rows ``w / sigma_a``
and local items); iterative refinement against the exact, unassembled ``S``
(:meth:`Factorization.refined`) recovers what squaring loses, as the corrected
semi-normal equations do. Problems whose rows are not local (a bandwidth or border
beyond the limits below) raise :class:`NotBanded`, and the caller falls back to a sparse
factorization.
"""

from __future__ import annotations

import copy
import functools
import itertools
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack

from ..sparse import abs_max, as_csr, canonical

__all__ = ["BandedKKT", "BandPlan", "DiagonalRows", "NotBanded", "Factorization", "AugmentedOperator",
           "KeptFactors",
           "row_span", "MAX_BAND", "MAX_BORDER", "FOLD_SPAN"]

#: Largest lower (and upper) bandwidth of the local part accepted for a banded factor;
#: the work is N b^2, so beyond this a sparse LDL^T with a fill-reducing ordering wins.
MAX_BAND = 60

#: Most unknowns in the border (error-model parameters, far-reaching rows); each costs a
#: right-hand side of the banded solve and N doubles of memory.
MAX_BORDER = 600

#: Widest node span of a row that is still local (folded or placed in the band).
FOLD_SPAN = 4


class NotBanded(ValueError):
    """The problem's rows are not local enough for the banded factorization (says why)."""


def _eliminated(D: sp.csr_matrix, fold: np.ndarray, colnode: np.ndarray,
                lam_rows: np.ndarray | None) -> np.ndarray:
    """The unknowns eliminated before the banded factorization: those with a node whose every
    objective entry is alone in a folded row that lambda does not weight (indices, sorted)."""
    Drow = np.repeat(np.arange(D.shape[0]), np.diff(D.indptr))
    Dcol = D.indices.astype(np.int64)
    alone = fold[Drow] & (np.diff(D.indptr)[Drow] == 1)
    if lam_rows is not None:
        alone &= ~np.asarray(lam_rows, dtype=bool)[Drow]
    # columns with an entry, none of them shared (boolean marks: a byte per unknown
    # where two integer counts of the unknowns' length took sixteen)
    single = np.zeros(D.shape[1], dtype=bool)
    single[Dcol] = True
    single[Dcol[~alone]] = False
    single &= colnode >= 0
    return np.flatnonzero(single)

def row_span(A: sp.csr_matrix, colnode: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest node of each row's columns with a node >= 0 (``hi = -1`` for a
    row with none)."""
    A = as_csr(A)
    m = A.shape[0]
    big = np.iinfo(np.int64).max
    lo = np.full(m, big, dtype=np.int64)
    hi = np.full(m, -1, dtype=np.int64)
    counts = np.diff(A.indptr)
    rows = np.flatnonzero(counts)
    if rows.size:
        nn = colnode[A.indices]
        starts = A.indptr[:-1][rows]
        hi[rows] = np.maximum.reduceat(nn, starts)
        np.putmask(nn, nn < 0, big)
        lo[rows] = np.minimum.reduceat(nn, starts)
    return lo, hi


def column_squares(A: sp.csr_matrix, cols: np.ndarray) -> np.ndarray:
    """Sum of squares of the entries of each of ``A``'s columns ``cols``."""
    if cols.size == 0:
        return np.zeros(0)
    return np.bincount(A.indices, weights=A.data ** 2, minlength=A.shape[1])[cols]




def residual(S, rhs: np.ndarray, z: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``rhs - S z`` for the augmented matrix ``S`` of any factorization: formed in place
    (into ``out`` when given) by :meth:`AugmentedOperator.residual` for one right-hand
    side, else by the product."""
    if np.ndim(rhs) == 1 and isinstance(S, AugmentedOperator):
        return S.residual(rhs, z, out=out)
    return rhs - S @ z


class AugmentedOperator:
    """The augmented matrix ``S`` of :mod:`bvpnav.linalg.lsq` as an operator (never assembled).

    Parameters
    ----------
    D, E : scipy.sparse.csr_matrix
        Objective rows (m, n) and equality rows (p, n).
    """

    def __init__(self, D: sp.csr_matrix, E: sp.csr_matrix):
        self.D, self.E = as_csr(D), as_csr(E)
        self.m, self.n = self.D.shape
        self.p = self.E.shape[0]
        self.shape = (self.m + self.n + self.p,) * 2

    def __matmul__(self, z: np.ndarray) -> np.ndarray:
        m, n = self.m, self.n
        rho, x, mu = z[:m], z[m:m + n], z[m + n:]
        return np.concatenate([self.D @ x - rho, self.D.T @ rho + self.E.T @ mu, self.E @ x])

    def residual(self, rhs: np.ndarray, z: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """``rhs - S z`` (one right-hand side), into ``out`` when given: each block's product
        subtracted in its slice (no concatenated product and no second full-length array,
        each of which is fresh memory of the length of ``z``)."""
        m, n = self.m, self.n
        rho, x, mu = z[:m], z[m:m + n], z[m + n:]
        out = np.empty_like(rhs, dtype=np.result_type(rhs, z)) if out is None else out
        np.subtract(rhs[:m], self.D @ x, out=out[:m])
        out[:m] += rho
        g = self.D.T @ rho
        g += self.E.T @ mu
        np.subtract(rhs[m:m + n], g, out=out[m:m + n])
        del g
        np.subtract(rhs[m + n:], self.E @ x, out=out[m + n:])
        return out

    def max_abs(self) -> float:
        """The largest absolute entry of ``S`` (the ``-I`` block's 1 included): a lower bound
        of its infinity norm, larger than it by at most the most entries a row holds, read
        from the stored values without an absolute-value copy (the infinity norm needed a
        copy of ``|E|`` and four sparse products)."""
        return max(1.0 if self.m else 0.0, abs_max(self.D.data), abs_max(self.E.data))


class Factorization:
    """What every factorization of the augmented system offers: ``S``, :meth:`solve` and
    :meth:`refined` (iterative refinement against ``S`` itself)."""

    S = None

    def solve(self, rhs: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def refined(self, rhs: np.ndarray, steps: int, tol: float = 0.0, window: slice | None = None,
                stall: float | None = None, scratch: np.ndarray | None = None):
        r"""Solve with up to ``steps`` iterative-refinement steps in double precision.

        Returns ``(z, steps_taken, last_relative_correction)``; the correction is measured
        on ``window`` (default: all of ``z``) and refinement stops below ``tol``, or, with
        ``stall``, as soon as a correction is not at least ``stall`` times smaller than the
        one before (the rounding floor has been reached). ``scratch`` (an array like a
        one-dimensional ``rhs``) holds the residuals when ``S`` forms them in place.

        Notes
        -----
        :math:`z_{k+1} = z_k + \tilde S^{-1} (b - S z_k)` with the factorised
        :math:`\tilde S`; it converges when :math:`\|I - \tilde S^{-1} S\| < 1`.
        """
        window = window if window is not None else slice(None)
        z = self.solve(rhs)
        corr, k = np.inf, 0
        res = scratch
        for _ in range(steps):
            k += 1
            res = residual(self.S, rhs, z, out=res)   # into one buffer reused by every step
            dz = self.solve(res)
            z += dz
            prev, corr = corr, abs_max(dz[window]) / max(abs_max(z[window]), 1e-300)
            if corr < tol or (stall is not None and corr > stall * prev):
                break
        return z, k, (0.0 if k == 0 else corr)






def _row_maxima(ab: np.ndarray) -> np.ndarray:
    """``max_j |ab[i, j]|`` per row, by ``reduceat`` over the flat array (numpy's reduction
    over short rows is twice as slow), as the larger of the row's maximum and minus its
    minimum (no absolute-value copy of the band)."""
    nb, ldab = ab.shape
    if not nb:
        return np.zeros(0)
    flat, starts = ab.reshape(-1), np.arange(0, nb * ldab, ldab)
    out = np.maximum.reduceat(flat, starts)
    np.maximum(out, -np.minimum.reduceat(flat, starts), out=out)
    return out


def _mul(A: sp.spmatrix, v: np.ndarray) -> np.ndarray:
    """``A @ v`` for a real sparse ``A``; a complex ``v`` (the complex step) by its real and
    imaginary parts (scipy would make a complex copy of ``A`` at every product)."""
    if v.dtype.kind != "c":
        return A @ v
    if not v.size:
        return np.zeros((A.shape[0],) + v.shape[1:], dtype=complex)
    # the real and imaginary parts as two interleaved real columns: one pass over A
    v = np.ascontiguousarray(v)
    pairs = v.view(float).reshape(v.shape[0], -1)
    return np.ascontiguousarray(A @ pairs).view(complex).reshape((A.shape[0],) + v.shape[1:])


def _scale_rows(ab: np.ndarray, sU: np.ndarray, kl: int, rows: np.ndarray | None = None) -> None:
    """Multiply band entries by ``sU`` of their row and column of the matrix, in place
    (``rows``: only these rows of ``ab``, given as ``ab[rows]``)."""
    nb = sU.size
    pad = np.concatenate([np.zeros(kl), sU, np.zeros(kl)])
    # entry (j, kl + s) is A[j + s - kl, j]: scaled by sU[j] and sU[j + s - kl] = pad[j + s]
    win = np.lib.stride_tricks.sliding_window_view(pad, 2 * kl + 1)[:nb]
    own = sU
    if rows is not None:
        win, own = win[rows], sU[rows]
    factor = win * own[:, None]
    ab[:, kl:] *= factor


#: Band rows written at a time by :meth:`BandPlan._scatter`: the slice of the band stays
#: in a typical L2 cache while every diagonal's entries in it are written (smaller and
#: larger slices, and the whole band at once, were slower; see the benchmark
#: ``examples/benchmarks/speed_memory.py``).
SCATTER_SLICE = 1 << 13


def _equal_cells(cols: list, rows: list, vals: list, L: int, seg: int) -> bool:
    """Whether the band cells (column, row, value arrays) of every run of ``L`` band rows
    are those of the first run, moved by the run's length, none reaching another run."""
    if not cols:
        return True
    c = np.concatenate(cols).astype(np.int64)
    r = np.concatenate(rows).astype(np.int64)
    v = np.concatenate(vals)
    a = c // L
    if np.any(r // L != a):
        return False
    c -= a * L
    r -= a * L
    order = np.lexsort((r, c, a))
    a, c, r, v = a[order], c[order], r[order], v[order]
    counts = np.bincount(a, minlength=seg)
    if np.any(counts != counts[0]):
        return False
    k = int(counts[0])
    return all(np.array_equal(x[b * k:(b + 1) * k], x[:k]) for b in range(1, seg) for x in (c, r, v))


def _oriented(band: list):
    """The index entries ``(i, j, v, mirror)`` as written: ``(i, j, v)``, then ``(j, i, v)``
    for a mirrored one."""
    for pi, pj, v, mirror in band:
        yield pi, pj, v
        if mirror:
            yield pj, pi, v


def _cells_below(band: list, L: int) -> list:
    """The index entries ``(i, j, v, mirror)`` of band columns ``j < L`` (each orientation
    of a mirrored entry on its own, as written)."""
    out = []
    for i, j, v in _oriented(band):
        sel = j < L
        if sel.any():
            out.append((i[sel], j[sel], v[sel], False))
    return out


class _Stride(NamedTuple):
    """Band entries at evenly spaced positions: ``A[j0 + off + step t, j0 + step t] = v[t]``
    (and the transpose with ``mirror``), written as strided slices of the band instead of
    by index arrays (:meth:`BandPlan._place_diagonal`)."""

    j0: int
    off: int
    step: int
    v: np.ndarray
    mirror: bool

    def span(self, which: int, e0: int, e1: int) -> tuple[slice, slice]:
        """The band rows (``which`` 0: the columns ``j``, 1: the mirrored rows ``j + off``)
        in ``[e0, e1)`` as a slice of the band, and the matching slice of ``v``."""
        a, s, L = self.j0 + (self.off if which else 0), self.step, self.v.size
        t0 = min(max(-(-(e0 - a) // s), 0), L)
        t1 = min(max(-(-(e1 - a) // s), t0), L)
        return slice(a + s * t0, a + s * (t1 - 1) + 1 if t1 > t0 else a + s * t0, s), slice(t0, t1)

    def write(self, ab: np.ndarray, kl: int, e0: int, e1: int) -> None:
        """Write the entries in band rows ``[e0, e1)`` into ``ab`` (LAPACK's layout, C order
        (nb, 3 kl + 1): ``ab[j, 2 kl + i - j] = A[i, j]``)."""
        for which in (0, 1)[:1 + self.mirror]:
            rows, ts = self.span(which, e0, e1)
            ab[rows, 2 * kl + (-self.off if which else self.off)] = self.v[ts]


def _scale_entries(strided: list, band: list, nb: int) -> np.ndarray:
    """The symmetric scale ``sU`` of :func:`scale_band` from the entries' column maxima,
    taken before they are placed (no passes over the band), and the entries' values
    scaled by it: a stride's in place (its own copy, made by
    :meth:`BandPlan._place_diagonal`), an index entry's into a new array that replaces it
    in ``band`` (its values may be the caller's)."""
    colmax = np.zeros(nb)
    for e in strided:   # positions distinct within one: a strided maximum
        a = np.abs(e.v)
        for which in (0, 1)[:1 + e.mirror]:
            cm = colmax[e.span(which, 0, nb)[0]]
            np.maximum(cm, a, out=cm)
    for pi, pj, v, mirror in band:
        a = np.abs(v)
        np.maximum.at(colmax, pj, a)
        if mirror:
            np.maximum.at(colmax, pi, a)
    sU = _scales(colmax, overwrite=True)
    for e in strided:
        v = e.v
        v *= sU[e.span(1, 0, nb)[0]]   # the row's scale, then the column's, as below
        v *= sU[e.span(0, 0, nb)[0]]
    for k, (pi, pj, v, mirror) in enumerate(band):
        w = v * sU[pi]
        w *= sU[pj]
        band[k] = (pi, pj, w, mirror)
    return sU


#: :meth:`BandPlan._equal_run_entries` sorts at most ``L / MANY_CELLS`` cells (``L`` band
#: rows per axis), or ``MIN_SORTED_CELLS`` on small problems (a few ms); beyond, writing
#: the whole band and comparing its runs is cheaper.
MANY_CELLS = 4
MIN_SORTED_CELLS = 1 << 16

#: Blocks of at least this many entries are placed through :meth:`BandPlan._placed` (their
#: band positions remembered per plan); at most :data:`MEMO_PER_KEY` index patterns are
#: kept per block size and ends.
MEMO_ENTRIES = 1024
MEMO_PER_KEY = 2

#: Most stored entries of ``D`` and ``E`` together for which a plan keeps a :class:`_Stencil` (its
#: index arrays hold a few integers per entry and per product pair, about the band's own memory);
#: larger patterns are placed block by block at every assembly.
STENCIL_ENTRIES = 1 << 20

#: Shortest run of evenly spaced band positions placed as a :class:`_Stride` (shorter ones,
#: where extra unknowns sit at a node, go entry by entry).
MIN_STRIDE_RUN = 64


def _affine_runs(p: np.ndarray, absent: np.ndarray | None = None) -> list:
    """Runs ``(u0, u1, p0, s)`` covering ``u = 0 .. p.size - 1`` with ``p[u] = p0 + s (u - u0)``:
    ``s > 0`` and ``p0 >= 0`` for positions in the band, ``s = 0`` for a run of unknowns in
    neither the band nor the border (``absent``: per ``u``, not in the border), ``s = None``
    for anything else (short runs, decreasing or mixed positions)."""
    L = p.size
    if L < MIN_STRIDE_RUN:
        return [(0, L, None, None)] if L else []
    d = np.diff(p)
    starts = np.flatnonzero(d[1:] != d[:-1]) + 1
    if starts.size > L // MIN_STRIDE_RUN:
        return [(0, L, None, None)]
    bounds = [0, *starts.tolist(), L]
    out: list = []
    for u0, u1 in zip(bounds[:-1], bounds[1:], strict=True):
        s, p0 = int(d[min(u0, L - 2)]), int(p[u0])
        ok = u1 - u0 >= MIN_STRIDE_RUN and ((s > 0 and p0 >= 0) or (
            s == 0 and p0 < 0 and absent is not None and bool(absent[u0:u1].all())))
        if not ok:
            s = p0 = None
        if out and s is None and out[-1][3] is None:
            out[-1] = (out[-1][0], u1, None, None)
        else:
            out.append((u0, u1, p0, s))
    return out


#: Largest period tried by :class:`_Moves` (one axis interleaves two unknowns per node).
MAX_MOVE_PERIOD = 4

#: Most slices :class:`_Moves` uses before it keeps the index array instead.
MAX_MOVE_SLICES = 256


class _Moves:
    """The map ``R = r[order]`` between reduced unknowns and band rows (and back, ``out[order]
    = y``) as strided slices where ``order`` is made of a few interleaved arithmetic runs
    (one axis: ``r_j`` and ``mu_j`` alternate; three axes: the same per axis), an index
    array for the rest.

    Parameters
    ----------
    order : ndarray of int (nb,)
        Reduced unknown of each band row (:attr:`BandPlan.pos_order`), distinct.

    Notes
    -----
    Each phase ``c`` of a period ``P`` (band rows ``c, c + P, ...``) is split into runs
    where the reduced index grows by a constant step (:func:`_affine_runs`); a run of
    ``u1 - u0`` rows is the slice pair ``band[c + P u0 : c + P u1 : P]`` and
    ``reduced[p0 : p0 + s (u1 - u0) : s]``. A slice copy is about ten times faster than
    numpy's fancy indexing with the int32 positions (gather or scatter): two of each per
    solve.
    """

    def __init__(self, order: np.ndarray):
        order = np.asarray(order)
        self.nb = nb = order.size
        self.pairs: list = []
        rest, left_size = None, nb   # None: every band row (made only if no period does better)
        for P in range(1, MAX_MOVE_PERIOD + 1):
            pairs, loose = [], []
            for c in range(min(P, nb)):
                for u0, u1, p0, s in _affine_runs(order[c::P]):
                    if s is None or s <= 0:
                        loose.append(c + P * np.arange(u0, u1, dtype=np.int64))
                    else:
                        pairs.append((slice(c + P * u0, c + P * (u1 - 1) + 1, P),
                                      slice(p0, p0 + s * (u1 - u0 - 1) + 1, s)))
            left = np.concatenate(loose) if loose else np.zeros(0, dtype=np.int64)
            if len(pairs) <= MAX_MOVE_SLICES and left.size < left_size:
                self.pairs, rest, left_size = pairs, left, left.size
                if 2 * left.size < MIN_STRIDE_RUN:
                    break
        self.band_rest = np.sort(rest) if rest is not None else np.arange(nb, dtype=np.int64)
        self.red_rest = order[self.band_rest].astype(np.int64)

    def gather(self, r: np.ndarray) -> np.ndarray:
        """``r[order]`` (a new array; ``r`` (R,) or (R, c))."""
        if not self.pairs:
            return r[self.red_rest]
        R = np.empty((self.nb,) + r.shape[1:], dtype=r.dtype)
        for b, q in self.pairs:
            R[b] = r[q]
        if self.band_rest.size:
            R[self.band_rest] = r[self.red_rest]
        return R

    def scatter(self, y: np.ndarray, out: np.ndarray) -> None:
        """``out[order] = y``."""
        for b, q in self.pairs:
            out[q] = y[b]
        if self.band_rest.size:
            out[self.red_rest] = y[self.band_rest]


def _row_groups(diagonal: DiagonalRows) -> list:
    """The tridiagonal blocks of ``diagonal`` grouped by their first row:
    ``[(r0, [(c0, lower, diag, upper), ...]), ...]`` (the FEM rows of one axis: K and M)."""
    groups: dict[int, list] = {}
    for r0, c0, lo, dg, up in diagonal.tridiagonal:
        groups.setdefault(r0, []).append((c0, lo, dg, up))
    return list(groups.items())


def _ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """``concatenate([arange(s, s + c) for s, c in zip(starts, counts)])``, int64."""
    counts = counts.astype(np.int64)
    ends = np.cumsum(counts)
    out = np.arange(int(ends[-1]) if ends.size else 0, dtype=np.int64)
    out -= np.repeat(ends - counts - starts.astype(np.int64), counts)
    return out


def _pairs_in_columns(first: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For entries ``first`` (indices, in the order the pairs are wanted) of a matrix whose
    entries have columns ``cols``: ``(a, b)``, every entry ``a`` of ``first`` with every
    entry ``b`` of ``first`` in its column, ``b`` by increasing index."""
    if not first.size:
        return first, first
    by_col = first[np.argsort(cols[first], kind="stable")]
    ucols, start, count = np.unique(cols[by_col], return_index=True, return_counts=True)
    k = np.searchsorted(ucols, cols[first])
    reps = count[k]
    return np.repeat(first, reps), by_col[_ranges(start[k], reps)]


def _dense_ids(keys: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """``(unique, inverse)`` of integer ``keys`` in ``[0, size)`` (as :func:`numpy.unique`),
    by marks in an array of ``size`` instead of a sort."""
    mark = np.zeros(size, dtype=bool)
    mark[keys] = True
    uniq = np.flatnonzero(mark)
    ids = np.empty(size, dtype=np.int32 if uniq.size < 2**31 else np.int64)
    ids[uniq] = np.arange(uniq.size)
    return uniq, ids[keys]


class _Stencil:
    r"""Where every value of ``D`` and ``E`` of one sparsity pattern goes in the scaled band of
    :meth:`BandPlan.assemble`, found once: an assembly of that pattern (the node-state loop's
    Gauss-Newton steps) is then a few gathers, products and ``bincount`` sums over the values,
    no sparse matrix made and no block placed.

    Only for plans without a border and with one run (:attr:`BandPlan.segments`): the
    node-state loop's interleaved plans.

    Notes
    -----
    The band cells are *slots*, each one value of the reduced matrix written once (or, for a
    mirrored slot, at its transpose too): ``E``'s entries (a multiplier's row, an unknown's
    column, mirrored); :math:`D_f^T D_f` at ``(i, j)``, the sum over the rows ``k`` (ascending)
    of :math:`D_{ki} D_{kj}` (the same at ``(j, i)``: the products commute); :math:`-E_z h^{-1}
    E_z^T` at ``(r_1, r_2)``, the sum over the eliminated columns ``c`` (ascending) of
    :math:`(E_{r_1 c} / h_c) E_{r_2 c}`, or, where :meth:`BandPlan._entries` takes it by
    diagonals, of :math:`(E_{r_1 c} E_{r_2 c}) / h_c` at ``r_1 <= r_2``, mirrored. Those are the
    operations, in the order, of scipy's sparse products and of
    :meth:`BandPlan._diagonal_pairs`, and the scaling is :func:`_scale_entries`'s (a slot's
    value times the scale of its row, then of its column): the band is the one
    :meth:`BandPlan._entries` and :meth:`BandPlan._scatter` write, bit for bit.
    """

    def __init__(self, plan: BandPlan, D: sp.csr_matrix, E: sp.csr_matrix, by_diagonals: bool):
        n, m, p, kl, ldab = plan.n, plan.m, plan.p, plan.kl, plan.ldab
        nb = plan.pos_order.size
        pos = plan.pos.astype(np.int64)
        el = plan.elim
        self.pattern = tuple(np.array(a) for a in (D.indptr, D.indices, E.indptr, E.indices))
        self.by_diagonals = by_diagonals
        self.n, self.el, self.nb, self.kl = n, el, nb, kl
        self._ez: list | None = None   # the eliminated columns' matrices (eliminated)
        size = nb * ldab
        eliminated = np.zeros(n, dtype=bool)
        eliminated[el] = True
        slot = np.full(n, -1, dtype=np.int64)
        slot[el] = np.arange(el.size)
        Dcount, Ecount = np.diff(D.indptr), np.diff(E.indptr)
        Drow = np.repeat(np.arange(m, dtype=np.int64), Dcount)
        Dcol = D.indices.astype(np.int64)
        Erow = np.repeat(np.arange(p, dtype=np.int64), Ecount)
        Ecol = E.indices.astype(np.int64)

        def cell(i: np.ndarray, j: np.ndarray) -> np.ndarray:   # the flat band index of A[i, j]
            return j * (ldab - 1) + i + 2 * kl

        def banded(i: np.ndarray, j: np.ndarray) -> np.ndarray:
            ok = (i >= 0) & (j >= 0)
            if np.any(np.abs(i[ok] - j[ok]) > kl):
                raise NotBanded("the sparsity pattern changed since the plan was made")
            return ok

        # E's entries: a multiplier's row and an unknown's column, mirrored
        er, ec = pos[n + Erow], pos[Ecol]
        self.e_take = np.flatnonzero(banded(er, ec))
        parts = [(er[self.e_take], ec[self.e_take], np.ones(self.e_take.size, dtype=bool))]
        # D_f^T D_f (every row folded: no border), without the rows that are a lone entry on an
        # eliminated unknown: the pairs i <= j of scipy's product in its order (column i, row k
        # ascending, column j), each sum placed at (i, j) and (j, i)
        if el.size and D.nnz:
            first = Dcol[np.minimum(D.indptr[:-1], D.nnz - 1)]
            kept = ~((Dcount == 1) & eliminated[first])
        else:
            kept = np.ones(m, dtype=bool)
        ent = np.flatnonzero(kept[Drow])
        ent = ent[np.argsort(Dcol[ent], kind="stable")]
        k = Drow[ent]
        after = D.indptr[k + 1] - ent   # entries of row k from this one on (sorted columns)
        a = np.repeat(ent, after)
        b = _ranges(ent, after)
        i, j = pos[Dcol[a]], pos[Dcol[b]]
        ok = banded(i, j)
        self.d_a, self.d_b = a[ok], b[ok]
        del a, b   # (the pairs' arrays freed once read: the largest this analysis makes)
        key, self.d_inv = _dense_ids(cell(i[ok], j[ok]), size)
        del i, j, ok
        self.d_sums = key.size
        dj = key // ldab
        di = key % ldab + dj - 2 * kl
        off = np.flatnonzero(di != dj)
        self.d_map = np.concatenate([np.arange(key.size), off])
        parts.append((np.concatenate([di, dj[off]]), np.concatenate([dj, di[off]]),
                      np.zeros(self.d_map.size, dtype=bool)))
        del di, dj, off
        # -E_z h^-1 E_z^T: every pair of E's entries in an eliminated column, by the first
        # one's row, then the column, then the second one's row
        a, b = _pairs_in_columns(np.flatnonzero(eliminated[Ecol]), Ecol)
        if by_diagonals:
            ok = Erow[a] <= Erow[b]
            a, b = a[ok], b[ok]
        i, j = pos[n + Erow[a]], pos[n + Erow[b]]
        ok = banded(i, j)
        self.z_a, self.z_b, self.z_c = a[ok], b[ok], slot[Ecol[a[ok]]]
        key, self.z_inv = _dense_ids(cell(i[ok], j[ok]), size)
        zj = key // ldab
        zi = key % ldab + zj - 2 * kl
        parts.append((zi, zj, (zi != zj) if by_diagonals else np.zeros(key.size, dtype=bool)))
        self.sizes = [x[0].size for x in parts]
        self.pa = np.concatenate([x[0] for x in parts])   # the slot's row (scaled first) ...
        self.pb = np.concatenate([x[1] for x in parts])   # ... and column
        mirror = np.concatenate([x[2] for x in parts])
        del parts
        mslots = np.flatnonzero(mirror)
        del mirror
        cells = np.concatenate([cell(self.pa, self.pb), cell(self.pb[mslots], self.pa[mslots])])
        self.flat, where = _dense_ids(cells, size)   # the cells by band row (a column of A)
        if self.flat.size != cells.size:
            raise NotBanded("two values for one band cell")   # never for a plan's pattern
        order = np.empty(cells.size, dtype=np.int64)
        del cells
        order[where] = np.arange(order.size)
        del where
        self.cell_slot = np.concatenate([np.arange(self.pa.size), mslots])[order]
        del order
        cols = self.flat // ldab
        self.col_start = np.flatnonzero(np.r_[True, cols[1:] != cols[:-1]]) if cols.size else cols
        self.cols = cols[self.col_start]

    def matches(self, D: sp.csr_matrix, E: sp.csr_matrix, by_diagonals: bool) -> bool:
        """Whether ``D`` and ``E`` have this stencil's pattern (and pairs as it was made)."""
        return by_diagonals == self.by_diagonals and all(
            a is b or (a.size == b.size and np.array_equal(a, b))
            for a, b in zip(self.pattern, (D.indptr, D.indices, E.indptr, E.indices), strict=True))

    def matches_rows(self, E: sp.csr_matrix) -> bool:
        """Whether ``E`` has this stencil's pattern."""
        return all(a is b or (a.size == b.size and np.array_equal(a, b))
                   for a, b in zip(self.pattern[2:], (E.indptr, E.indices), strict=True))

    def eliminated(self, plan: BandPlan, E: sp.csr_matrix) -> tuple:
        """:meth:`BandPlan._eliminated` of ``E`` (this stencil's pattern): the matrices scipy's
        column indexing and transpose make, found once for the pattern (on the entries' numbers
        as values), then ``E``'s values gathered into copies of them."""
        if self._ez is None:
            numbers = sp.csr_matrix((np.arange(1.0, E.nnz + 1.0), E.indices, E.indptr), shape=E.shape)
            Ez = numbers[:, plan.elim_index]
            self._ez = [(M, M.data.astype(np.int64) - 1) for M in (Ez, Ez.T.tocsr())]
        out = []
        for M, take in self._ez:
            X = copy.copy(M)   # the pattern's index arrays, shared (never changed in place)
            X.data = E.data[take]
            out.append(X)
        return tuple(out)

    def parts(self, D: sp.csr_matrix, E: sp.csr_matrix, ldab: int, out: np.ndarray | None = None) -> tuple:
        """``(ab, None, C, h, sU)`` as :meth:`BandPlan.assemble` (``ab`` scaled; ``out``: memory
        for the band, :meth:`BandPlan._write_band`)."""
        Dd, Ed = D.data, E.data
        nE, nD, nZ = self.sizes
        S = np.empty(nE + nD + nZ)
        np.take(Ed, self.e_take, out=S[:nE])
        w = Dd[self.d_a]
        w *= Dd[self.d_b]
        np.take(np.bincount(self.d_inv, w, minlength=self.d_sums), self.d_map, out=S[nE:nE + nD])
        h = np.bincount(D.indices, weights=Dd ** 2, minlength=self.n)[self.el]   # column_squares
        if nZ:
            if self.by_diagonals:
                w = Ed[self.z_a] * Ed[self.z_b]
                w *= (1.0 / h)[self.z_c]
            else:
                w = Ed[self.z_a] / h[self.z_c]
                w *= Ed[self.z_b]
            np.negative(np.bincount(self.z_inv, w, minlength=nZ), out=S[nE + nD:])
        cells = S[self.cell_slot]
        colmax = np.zeros(self.nb)
        if self.cols.size:   # the largest magnitude in every band row (a column of A)
            colmax[self.cols] = np.maximum.reduceat(np.abs(cells), self.col_start)
        sU = _scales(colmax, overwrite=True)
        S *= sU[self.pa]
        S *= sU[self.pb]
        size = self.nb * ldab
        if out is not None and out.dtype == np.float64 and out.flags.c_contiguous and out.size >= size:
            ab = out.reshape(-1)[:size].reshape(self.nb, ldab)
            # the band's cells only: the first kl of every band row are the factor's fill-in rows,
            # which dgbtrf zeroes itself before it writes them (the last factor's values stay
            # there unread)
            ab[:, self.kl:].fill(0.0)
        else:
            ab = np.zeros((self.nb, ldab))
        np.take(S, self.cell_slot, out=cells)
        ab.reshape(-1)[self.flat] = cells
        return ab, None, np.zeros((0, 0)), h, sU


class _Run(NamedTuple):
    """Entries of ``E`` at rows ``r0 + t`` and columns ``c0 + step t``, ``t = 0 .. size - 1``
    (``step`` 1: a diagonal, 0: a dense column): a piece of :func:`_entry_pieces` that
    needs no index arrays."""

    r0: int
    c0: int
    size: int
    step: int

    def rows(self) -> slice:
        return slice(self.r0, self.r0 + self.size)

    def cols(self, values: np.ndarray) -> np.ndarray:
        """``values`` at the piece's columns (a slice, or one value repeated)."""
        if self.step:
            return values[self.c0:self.c0 + self.size]
        return np.full(self.size, values[self.c0])


def _entry_pieces(E: sp.csr_matrix, diagonal: DiagonalRows | None = None) -> list:
    """``E``'s entries as pieces: ``(rows, cols)`` index arrays for a CSR matrix's entries,
    or, with a matching :class:`DiagonalRows`, a :class:`_Run` per diagonal and dense
    column (no per-entry expansion of the FEM rows) and arrays for the other rows'."""
    def csr(A: sp.csr_matrix, r0: int = 0) -> tuple:
        return r0 + np.repeat(np.arange(A.shape[0]), np.diff(A.indptr)), A.indices

    if diagonal is None or not diagonal.matches(E):
        return [csr(E)]
    pieces: list = [csr(diagonal.extra), csr(E[diagonal.rows:], diagonal.rows)]
    for b0, c0, _, dg, _ in diagonal.tridiagonal:
        L = dg.size
        pieces += [_Run(b0, c0, L, 1), _Run(b0 + 1, c0, L - 1, 1), _Run(b0, c0 + 1, L - 1, 1)]
    pieces += [_Run(b0, col, v.size, 0) for b0, col, v in diagonal.dense]
    return pieces


def _spans(pieces: list, colnode: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`row_span` of a matrix of ``m`` rows given as :func:`_entry_pieces` (a
    :class:`_Run` has one entry per row: elementwise minima and maxima on a slice)."""
    big = np.iinfo(np.int64).max
    lo = np.full(m, big, dtype=np.int64)
    hi = np.full(m, -1, dtype=np.int64)
    for piece in pieces:
        if isinstance(piece, _Run):
            nn = piece.cols(colnode)
            rows = piece.rows()
            np.maximum(hi[rows], nn, out=hi[rows])
            np.minimum(lo[rows], np.where(nn >= 0, nn, big), out=lo[rows])
            continue
        rows, cols = piece
        nn = colnode[cols]
        np.minimum.at(lo, rows[nn >= 0], nn[nn >= 0])
        np.maximum.at(hi, rows, nn)
    return lo, hi


def _coupling_by_columns(cpl: list, nb: int, k: int) -> sp.csc_matrix | None:
    """The border coupling (nb, k) as CSC straight from its blocks ``(rows, cols, values)``
    when each block lies in one border column with increasing rows and no column has two
    blocks (the error-model parameters' dense FEM columns): the blocks laid end to end by
    column, no sort and no duplicates to sum (0.35 s for three axes with six parameters at
    N = 1e6 through COO); None otherwise."""
    by_col: dict[int, tuple] = {}
    for rows, cols, vals in cpl:
        if not rows.size:
            continue
        c = int(cols[0])
        if c in by_col or np.any(cols != c) or (rows.size > 1 and np.any(rows[1:] <= rows[:-1])):
            return None
        by_col[c] = (rows, vals)
    counts = np.zeros(k + 1, dtype=np.int64)
    for c, (rows, _) in by_col.items():
        counts[c + 1] = rows.size
    order = sorted(by_col)
    parts = [by_col[c] for c in order]
    indices = np.concatenate([r for r, _ in parts]) if parts else np.zeros(0, dtype=np.int32)
    data = np.concatenate([v for _, v in parts]) if parts else np.zeros(0)
    B = sp.csc_matrix((data, indices, np.cumsum(counts)), shape=(nb, k))
    B.has_canonical_format = True   # sorted rows in each column, each column from one block
    return B


def _equal_runs(ab: np.ndarray, runs: int) -> bool:
    """Whether the band (LAPACK layout, see :meth:`BandPlan._scatter`) is ``runs`` equal
    consecutive blocks; then no entry couples two of them (the first block has none above
    it, the last none below, and every block equals both)."""
    nb = ab.shape[0]
    if nb % runs:
        return False
    L = nb // runs
    return all(np.array_equal(ab[:L], ab[a * L:(a + 1) * L]) for a in range(1, runs))


def _scales(colmax: np.ndarray, overwrite: bool = False) -> np.ndarray:
    """The symmetric scale ``1 / sqrt(column maximum)`` (1 for an empty column); in place of
    ``colmax`` with ``overwrite`` (no three temporaries of the band's length)."""
    out = colmax if overwrite else colmax.copy()
    out[~(out > 0)] = 1.0
    np.sqrt(out, out=out)
    np.divide(1.0, out, out=out)
    return out


def scale_band(ab: np.ndarray, kl: int) -> np.ndarray:
    """Scale a symmetric banded matrix in LAPACK's layout (C order (nb, 3 kl + 1), see
    :meth:`BandPlan._scatter`) in place by the square roots of its column maxima; returns
    the scale ``sU`` (the scaled matrix is ``diag(sU) A diag(sU)``).

    Notes
    -----
    Column maxima, not 2-norms: the 2-norms, cheaper, cost an order of magnitude of
    accuracy on hard zero-velocity rows. Entries before ``ab[:, kl]`` are the LU's fill
    space (zero), so the maxima are those of whole rows.
    """
    sU = _scales(_row_maxima(ab), overwrite=True)
    _scale_rows(ab, sU, kl)
    return sU


class AffineBand:
    r"""The banded parts along a lambda sweep, scaled, for one copy per lambda.

    With every lambda-weighted row folded into the band (none eliminated, none in the
    border but through ``B1``, ``C1``), the reduced matrix is affine in lambda:
    :math:`A(\lambda) = A_0 + (\lambda - 1) A_1`, and :math:`A_1` touches the few band
    rows of the unknowns those rows weigh (positions at the fixes). The scaling of
    :func:`scale_band` changes only in those rows' columns, and the scaled entries only
    within ``kl`` rows of them: each lambda copies the scaled :math:`A_0` once and
    recomputes those rows, instead of combining, taking maxima and scaling the whole band.

    Parameters
    ----------
    parts0 : tuple
        ``(ab, B, C, h, sU)`` at lambda = 1, ``ab`` scaled by ``sU``
        (:meth:`BandPlan.assemble`).
    parts1 : tuple
        ``(ab1, B1, C1)`` per unit of lambda (:meth:`BandPlan.objective_part`).
    kl : int
    """

    def __init__(self, parts0: tuple, parts1: tuple, kl: int):
        ab0, self.B, self.C, self.h, sU0 = parts0
        ab1, self.B1, self.C1 = parts1
        whole = sU0.size
        if ab0.shape[0] != ab1.shape[0]:   # one part's runs are equal, the other's not
            ab0, ab1 = (np.tile(x, (whole // x.shape[0], 1)) for x in (ab0, ab1))
        nb = ab0.shape[0]
        self.runs = whole // nb   # > 1: one run's band (equal axes), its scales those of each
        self.sU0 = sU0[:nb]
        self.kl = kl
        flat = ab1.reshape(-1)
        touched = np.unique(np.flatnonzero(flat) // ab1.shape[1])
        near = (touched[:, None] + np.arange(-kl, kl + 1)).ravel()
        self.rows = np.unique(near[(near >= 0) & (near < nb)])       # entries that change
        self.own = np.searchsorted(self.rows, touched)                # maxima that change
        self.touched = touched
        self.ab1 = ab1[self.rows]
        self.scaled0 = ab0
        self.ab0 = ab0[self.rows]   # the rows that change, back to lambda's units
        _scale_rows(self.ab0, 1.0 / self.sU0, kl, self.rows)

    def at(self, lam: float, out: np.ndarray | None = None) -> tuple:
        """``(ab, B, C, h, sU)`` at ``lam``: ``ab`` scaled by ``sU`` (:func:`scale_band`),
        written into ``out`` (an array of the band's shape whose factor is no longer
        needed: no new allocation, no page faults) when given."""
        return self._parts(lam, 0.0, out)

    def at_complex(self, lam: float, h: float, out: np.ndarray | None = None) -> tuple:
        r"""The parts at the complex lambda :math:`\lambda + ih`, scaled by the real
        lambda's ``sU`` (the complex-step derivative, :meth:`BandedKKT.logdet_step`):
        :meth:`at` plus :math:`ih` times the lambda part, ``ab`` complex, written into
        ``out`` (a complex array of the band's shape) when given.

        Notes
        -----
        The parts are affine in lambda, so :math:`A(\lambda + ih) = A(\lambda) + ih A_1`
        exactly; only the rows of :attr:`rows` have an imaginary part.
        """
        return self._parts(lam, h, out)

    def _parts(self, lam: float, h: float, out: np.ndarray | None) -> tuple:
        """:meth:`at` (``h`` = 0) or :meth:`at_complex`."""
        g = lam - 1.0
        vals, sU = self._rows_at(lam)
        if h:
            step = self.ab1 * h
            _scale_rows(step, sU, self.kl, self.rows)
            vals = vals + 1j * step
            g = g + 1j * h
        if out is None:
            out = np.empty(self.scaled0.shape, dtype=vals.dtype)
        np.copyto(out, self.scaled0)
        out[self.rows] = vals
        B = None if self.B is None else self.B + g * self.B1
        if self.runs > 1:
            sU = np.tile(sU, self.runs)
        return out, B, self.C + g * self.C1, self.h, sU

    def _rows_at(self, lam: float) -> tuple[np.ndarray, np.ndarray]:
        """The changing rows at ``lam``, scaled, and the scales of one run."""
        vals = self.ab0 + (lam - 1.0) * self.ab1
        sU = self.scales_at(lam)
        _scale_rows(vals, sU, self.kl, self.rows)
        return vals, sU

    def scales_at(self, lam: float) -> np.ndarray:
        """The scales of one run at ``lam`` (:func:`scale_band`'s, of the band the rows
        that change make at ``lam``): only the touched rows' maxima are taken, no row is
        scaled."""
        sU = self.sU0.copy()
        sU[self.touched] = _scales(_row_maxima(self.ab0[self.own] + (lam - 1.0) * self.ab1[self.own]))
        return sU


class KeptFactors:
    """A lambda sweep's last factorizations, handed to the solve at the chosen lambda
    (:func:`bvpnav.linalg.lsq.banded_factor`), and the sweep's band buffers that no factor needs.

    Each is handed out once: a factor taken is the solve's own, and a buffer taken (for a
    new factor written in place) ends the factor that lived in it.

    Parameters
    ----------
    plan : BandPlan
        The plan every factor here was made with.
    """

    def __init__(self, plan: BandPlan):
        self.plan = plan
        self._factors: dict[float, tuple] = {}
        self._spare: list[np.ndarray] = []

    def keep(self, lam: float, factor: BandedKKT, buffer: np.ndarray | None) -> None:
        """Keep ``factor`` of the point at ``lam``, whose band lives in ``buffer`` (None:
        its own memory)."""
        self._factors[float(lam)] = (factor, buffer)

    def spare(self, buffer: np.ndarray) -> None:
        """A band buffer no factor uses (its values are dead)."""
        self._spare.append(buffer)

    def lams(self) -> list[float]:
        """The lambdas whose factors are kept."""
        return list(self._factors)

    def take(self, lam: float) -> BandedKKT | None:
        """The factor at exactly ``lam``, or None."""
        got = self._factors.pop(float(lam), None)
        return None if got is None else got[0]

    def buffer(self, shape: tuple) -> np.ndarray | None:
        """A real array of ``shape`` over memory the sweep has already touched (a spare
        buffer, else a kept factor's, which ends that factor), or None. Writing the chosen
        lambda's band there instead of into a fresh array saves the page faults of a first
        write, which grow with N."""
        size = int(np.prod(shape))
        pool = self._spare + [buf for _, buf in self._factors.values() if buf is not None]
        for buf in pool:
            if buf.nbytes >= 8 * size and buf.flags.c_contiguous:
                if any(b is buf for _, b in self._factors.values()):
                    self._factors = {k: v for k, v in self._factors.items() if v[1] is not buf}
                else:
                    self._spare = [b for b in self._spare if b is not buf]
                return np.frombuffer(buf, dtype=float, count=size).reshape(shape)
        return None


@dataclass(eq=False)
class DiagonalRows:
    """The first :attr:`rows` rows of ``E`` by their diagonals (the FEM rows, see
    :func:`bvpnav.linalg.lsq.fem_rows_by_diagonals`): the plan places them by formula, a few
    arrays of length N, instead of entry by entry.

    Attributes
    ----------
    rows : int
        ``E``'s rows ``0 .. rows - 1`` are described here, every entry of them.
    tridiagonal : list of (int, int, ndarray, ndarray, ndarray)
        ``(r0, c0, lower, diag, upper)``: the square block ``E[r0 + i, c0 + j]`` with
        ``diag[i]`` at ``j = i``, ``lower[i - 1]`` at ``j = i - 1`` and ``upper[i]`` at
        ``j = i + 1``. Blocks have disjoint columns; blocks that share rows start at the
        same row and have the same size (an axis' K and M).
    dense : list of (int, int, ndarray)
        ``(r0, col, values)``: a column, ``E[r0 + i, col] = values[i]``.
    extra : scipy.sparse.csr_matrix
        The other entries of those rows, shape ``(rows, n)``.
    """

    rows: int
    tridiagonal: list
    dense: list
    extra: sp.csr_matrix

    @functools.cached_property
    def nonzeros(self) -> int:
        """The description's nonzero values (counted once: every assembly checks them)."""
        nz = self.extra.nnz + sum(int(np.count_nonzero(v)) for b in self.tridiagonal for v in b[2:])
        return nz + sum(int(np.count_nonzero(v)) for _, _, v in self.dense)

    def matches(self, E: sp.csr_matrix) -> bool:
        """Whether ``E`` (canonical: no explicit zeros) holds as many entries in those rows
        as the description has nonzero values (a description of other rows does not)."""
        if E.shape[0] < self.rows or self.extra.shape != (self.rows, E.shape[1]):
            return False
        return int(E.indptr[self.rows]) == self.nonzeros


@dataclass(eq=False)
class BandPlan:
    """The symbolic analysis of the reduced system (see the module Notes): where every
    entry of the objective and equality rows goes. It depends on the sparsity pattern only
    and is reused by every factorization of the same problem at another lambda.

    The reduced unknowns are ``x`` (n), the residuals of the unfolded rows (``nu``) and the
    multipliers (p), in that order.

    Attributes
    ----------
    fold : ndarray of bool (m,)
        Objective rows eliminated into ``D_f^T D_f``.
    elim : ndarray of int
        Unknowns of ``x`` whose every objective entry is alone in its row (the
        acceleration residuals ``w``): eliminated by a diagonal pivot before the band.
    pos, bpos : ndarray of int (n + nu + p,)
        Position of each reduced unknown in the banded part and in the border (-1: not
        there).
    kl : int
        Lower (= upper) bandwidth of the banded part.
    segments : int
        Equal consecutive parts of the banded part that no entry couples, one per axis
        laid end to end (1 otherwise); a factorization whose parts are equal too factors
        one and solves the others as extra right-hand sides (:class:`BandedKKT`).
    """

    fold: np.ndarray
    elim: np.ndarray
    pos: np.ndarray
    bpos: np.ndarray
    kl: int
    n: int
    m: int
    p: int
    nnz_D: int = 0
    nnz_E: int = 0
    segments: int = 1

    @property
    def ku(self) -> int:
        """Upper bandwidth (the reduced matrix is symmetric)."""
        return self.kl

    @property
    def size(self) -> int:
        """Unknowns in the banded part."""
        return int(self.pos_order.size)

    @property
    def border(self) -> int:
        """Unknowns in the border."""
        return int(self.border_order.size)

    @property
    def unfolded(self) -> np.ndarray:
        """Indices of the objective rows kept as unknowns."""
        return np.flatnonzero(~self.fold)

    @functools.cached_property
    def moves(self) -> _Moves:
        """:attr:`pos_order` as slices (:class:`_Moves`), for the solves' gathers and
        scatters."""
        return _Moves(self.pos_order)

    @functools.cached_property
    def elim_index(self) -> slice | np.ndarray:
        """:attr:`elim` as a slice when it is one run of consecutive unknowns (the usual
        case: an axis' accelerations residuals, or all axes'), for the solves' gathers and
        scatters (a view and a block copy instead of an index array each time)."""
        el = self.elim
        if el.size and el[-1] - el[0] + 1 == el.size and np.all(np.diff(el) == 1):
            return slice(int(el[0]), int(el[-1]) + 1)
        return el

    def describe(self) -> str:
        """E.g. ``"banded (kl=4, ku=4, 200001 unknowns, border 0)"``."""
        return f"banded (kl={self.kl}, ku={self.ku}, {self.size} unknowns, border {self.border})"

    def _segment(self, node: np.ndarray, segments: int) -> int:
        """``segments`` when the ordered banded unknowns split into that many equal runs,
        run ``a`` holding the nodes ``a T .. (a + 1) T - 1`` (``T`` = nodes per segment),
        else 1. Whether an entry couples two runs is left to the factorization: runs whose
        band rows are equal, as it requires, have none (the first run's have none above it,
        the last run's none below)."""
        nb = self.pos_order.size
        if segments <= 1 or nb % segments or not nb:
            return 1
        L, ends = nb // segments, node[self.pos_order]
        T = (int(ends[-1]) + 1) // segments
        ok = all(ends[a * L] >= a * T and ends[(a + 1) * L - 1] < (a + 1) * T for a in range(segments))
        return segments if ok else 1

    @classmethod
    def build(cls, D: sp.csr_matrix, E: sp.csr_matrix, colnode: np.ndarray,
              max_band: int = MAX_BAND, max_border: int = MAX_BORDER, span: int = FOLD_SPAN,
              lam_rows: np.ndarray | None = None, segments: int = 1,
              diagonal: DiagonalRows | None = None) -> BandPlan:
        """Order the reduced system by node; raise :class:`NotBanded` when it is not local.

        Parameters
        ----------
        D, E : scipy.sparse.csr_matrix
            Objective rows (m, n) and equality rows (p, n), canonical (sorted indices, no
            duplicates).
        colnode : ndarray of int (n,)
            Node of each unknown, -1 for unknowns that go to the border.
        lam_rows : ndarray of bool (m,), optional
            Lambda-weighted objective rows: an unknown they touch is not eliminated, so the
            banded part stays affine in lambda (:meth:`objective_part`).
        segments : int
            The nodes are this many equal runs laid end to end (axes no row couples), see
            :attr:`segments`.
        diagonal : DiagonalRows, optional
            ``E``'s first rows by diagonals, for the first assembly (:meth:`assemble`).
        """
        m, n = D.shape
        p = E.shape[0]
        lo, hi = row_span(D, colnode)
        fold = (hi < 0) | (hi - lo <= span)
        unf = np.flatnonzero(~fold)
        elim = _eliminated(D, fold, colnode, lam_rows)
        pieces = _entry_pieces(E, diagonal)
        elo, ehi = _spans(pieces, colnode, p)
        enode = np.where((ehi >= 0) & (ehi - elo <= span), (elo + ehi) // 2, -1)
        # int32 nodes where they fit (half the fresh memory of these unknown-long arrays:
        # nine million entries for three axes at N = 1e6)
        small = np.int32 if n + unf.size + p < 2**31 else np.int64
        node = np.empty(n + unf.size + p, dtype=small)
        node[:n] = colnode
        node[n:n + unf.size] = -1
        node[n + unf.size:] = enode
        node[elim] = -2
        # within a node, unknowns that reach the next node last (a FEM multiplier reaches one
        # node on; one axis then has bandwidth 4 even where a node holds extra unknowns): a
        # multiplier reaches its row's last node, an unknown of x one node on when a row
        # whose multiplier sits at a later node holds it (r_j, not the end velocity v0)
        reach = node.copy()
        reach[n + unf.size:] = np.where(enode >= 0, ehi, -1)
        onward = np.zeros(n, dtype=small)
        for piece in pieces:
            if isinstance(piece, _Run):
                ahead = enode[piece.rows()] > piece.cols(colnode)
                if piece.step:
                    onward[piece.c0:piece.c0 + piece.size][ahead] = 1
                elif ahead.any():
                    onward[piece.c0] = 1
                continue
            rows, cols = piece
            onward[cols[enode[rows] > colnode[cols]]] = 1
        reach[:n] += np.where(node[:n] >= 0, onward, 0)
        del onward, pieces
        local = np.flatnonzero(node >= 0)
        # by node, then by reach: one stable sort of a combined key (reach - node is small;
        # the key's runs are already sorted: faster than lexsort)
        nl = node[local]
        ahead = reach[local] - nl
        ahead -= ahead.min(initial=0)
        width = int(ahead.max(initial=0)) + 1
        if (int(nl.max(initial=-1)) + 1) * width >= 2**31:   # the key needs 64 bits
            nl, ahead = nl.astype(np.int64), ahead.astype(np.int64)
        order = local[np.argsort(nl * width + ahead, kind="stable")]
        del nl, ahead
        # int32 positions where they fit: half the memory when every entry is placed
        pos = np.full(node.size, -1, dtype=small)
        pos[order] = np.arange(order.size)
        border = np.flatnonzero(node == -1)
        if border.size > max_border:
            raise NotBanded(f"{border.size} unknowns in the border (error-model parameters and rows "
                            f"that reach far in time), more than {max_border}")
        bpos = np.full(node.size, -1, dtype=small)
        bpos[border] = np.arange(border.size)
        plan = cls(fold=fold, elim=elim, pos=pos, bpos=bpos, kl=0, n=n, m=m, p=p,
                   nnz_D=D.nnz, nnz_E=E.nnz)
        plan.pos_order, plan.border_order = order, border
        plan.band_node = node[order]   # the node of each band position (CondensedKKT)
        plan.segments = plan._segment(node, segments)
        del lo, hi, elo, ehi, node, reach, local, order, border
        plan._analyse(D, E, max_band, diagonal)
        return plan

    def _analyse(self, D, E, max_band, diagonal: DiagonalRows | None = None) -> None:
        """The bandwidth of the banded part, from one assembly (kept for the first factor)."""
        entries = self._entries(D, E, diagonal)
        kl = 0
        for e in entries[0]:
            if isinstance(e, _Stride):
                kl = max(kl, abs(e.off))
                continue
            pi, pj = e[0], e[1]
            if pi.size:
                off = pi - pj
                kl = max(kl, int(off.max()), -int(off.min()))
        if kl > max_band:
            raise NotBanded(f"bandwidth {kl} after ordering by time node, more than {max_band}: some "
                            "rows couple distant instants")
        self.kl = kl
        self.ldab = 3 * kl + 1
        self._first = (D.data, E.data, self._scatter(entries, scaled=True))

    def _entries(self, D: sp.csr_matrix, E: sp.csr_matrix, diagonal: DiagonalRows | None = None) -> tuple:
        """The reduced matrix's entries, placed: ``(band, border_coupling, border, h)``.

        ``band`` is a list of ``(i, j, values, mirror)`` with positions in the banded part
        (``mirror``: the block's transpose is there too, at ``(j, i)``); the border
        coupling ``(i, k, values)`` holds the entries in band row ``i`` and border column
        ``k``, the border ``(k, l, values)`` those among border unknowns; ``h`` is the
        eliminated unknowns' diagonal. Entries of eliminated unknowns are dropped.

        Notes
        -----
        Blocks of the (symmetric) reduced matrix: :math:`D_f^T D_f` on ``x``; the unfolded
        rows :math:`[D_u, -I]` and their transpose; ``E`` and its transpose;
        :math:`-E_z h^{-1} E_z^T` on the multipliers. With ``diagonal`` (a
        :class:`DiagonalRows` that matches ``E``) its rows are placed by diagonals, and so
        is :math:`-E_z h^{-1} E_z^T` when no other row touches an eliminated unknown
        (:meth:`_diagonal_pairs`).
        """
        n = self.n
        unf = self.unfolded
        nu = unf.size
        el = self.elim
        Df = D[self.fold] if nu else D
        h = column_squares(Df, el)
        out = ([], [], [])

        def add_sparse(A: sp.spmatrix, r0: int, c0: int, mirror: bool, sign: float = 1.0) -> None:
            A = A.tocoo()
            self._place(A.row + r0, A.col + c0, A.data if sign == 1.0 else sign * A.data, mirror, out)

        eliminated = np.zeros(n, dtype=bool)
        eliminated[el] = True
        # a row on an eliminated unknown is alone there (its only entry): it adds h alone,
        # so the product runs over the other rows (the items' rows, not the N data rows)
        if el.size and Df.nnz:
            counts = np.diff(Df.indptr)
            first = Df.indices[np.minimum(Df.indptr[:-1], max(Df.nnz - 1, 0))]
            Df = Df[~((counts == 1) & eliminated[first])]
        add_sparse(Df.T @ Df, 0, 0, False)
        if nu:
            add_sparse(D[unf], n, 0, True)
            self._place(n + np.arange(nu), n + np.arange(nu), -np.ones(nu), False, out)
        r0 = n + nu
        if diagonal is not None and diagonal.matches(E):
            k = diagonal.rows
            runs: dict = {}
            for b0, c0, lo, dg, up in diagonal.tridiagonal:
                rr, cc = (r0 + b0, dg.size), (c0, dg.size)
                self._place_diagonal(rr, cc, 0, 0, dg, True, out, runs)
                self._place_diagonal(rr, cc, 1, 0, lo, True, out, runs)
                self._place_diagonal(rr, cc, 0, 1, up, True, out, runs)
            for b0, col, v in diagonal.dense:
                self._place(r0 + b0 + np.arange(v.size), np.full(v.size, col), v, True, out)
            add_sparse(diagonal.extra, r0, 0, True)
            add_sparse(E[k:], r0 + k, 0, True)
            if self._pairs_by_diagonals(E, diagonal):
                hinv = np.zeros(n)
                hinv[el] = 1.0 / h
                self._diagonal_pairs(diagonal, hinv, r0, out, runs)
                return (*out, h)
        else:
            add_sparse(E, r0, 0, True)
        if el.size:
            # (E_z scaled by 1/h) times the kept transpose of E_z: no diagonal product and no
            # second transpose (a third less time than (E_z h^-1/2)(E_z h^-1/2)^T)
            Ez, EzT = self._eliminated(E)
            Zh = sp.csr_matrix((Ez.data / h[Ez.indices], Ez.indices, Ez.indptr), shape=Ez.shape)
            add_sparse(Zh @ EzT, n + nu, n + nu, False, -1.0)
        return (*out, h)

    def _pairs_by_diagonals(self, E: sp.csr_matrix, diagonal: DiagonalRows | None) -> bool:
        """Whether :meth:`_entries` places :math:`-E_z h^{-1} E_z^T` by diagonals
        (:meth:`_diagonal_pairs`): ``diagonal`` matches ``E`` and no other row touches an
        eliminated unknown."""
        el = self.elim
        if diagonal is None or not el.size or not diagonal.matches(E):
            return False
        eliminated = np.zeros(self.n, dtype=bool)
        eliminated[el] = True
        dense = np.array([col for _, col, _ in diagonal.dense], dtype=np.int64)
        return not (eliminated[E.indices[E.indptr[diagonal.rows]:]].any()
                    or eliminated[diagonal.extra.indices].any() or eliminated[dense].any())

    def _diagonal_pairs(self, diagonal: DiagonalRows, hinv: np.ndarray, r0: int, out: tuple,
                        runs: dict | None = None) -> None:
        r"""Place :math:`-E_z h^{-1} E_z^T` for the tridiagonal blocks of ``diagonal``
        (``hinv``: :math:`1/h` on the eliminated unknowns, 0 elsewhere), the only rows on
        eliminated unknowns.

        Notes
        -----
        With the block's entries :math:`e_{i, i+s} = V_s[i]` (:math:`s = -1, 0, 1`), rows
        ``i`` and ``i + t`` share column ``c = i + s = i + t + s'``, so

        .. math:: (E_z h^{-1} E_z^T)_{i, i+t} = \sum_{s - s' = t} V_s[i]\, V_{s'}[i + t]\,
                  h^{-1}_{c_0 + i + s}, \qquad t = 0, 1, 2

        (pentadiagonal, symmetric), summed over the blocks that share the rows.
        """
        for b0, group in _row_groups(diagonal):
            N = group[0][2].size
            acc = {t: np.zeros(N - t) for t in (0, 1, 2)}
            for c0, lo, dg, up in group:
                g = np.concatenate([[0.0], hinv[c0:c0 + N], [0.0]])   # g[1 + j]: 1/h at column c0 + j
                if not g.any():
                    continue   # no eliminated unknown among this block's columns
                V = {-1: np.concatenate([[0.0], lo]), 0: dg, 1: np.concatenate([up, [0.0]])}
                for t in (0, 1, 2):
                    m = N - t
                    for s in (-1, 0, 1):
                        if s - t >= -1:
                            acc[t] += V[s][:m] * V[s - t][t:] * g[1 + s:1 + s + m]
            rr = (r0 + b0, N)
            for t in (0, 1, 2):
                self._place_diagonal(rr, rr, 0, t, -acc[t], t > 0, out, {} if runs is None else runs)

    def _place(self, r: np.ndarray, c: np.ndarray, v: np.ndarray, mirror: bool, out: tuple) -> None:
        """Append one block's entries (reduced indices ``r``, ``c``; ``mirror``: its
        transpose too) to ``out = (band, border_coupling, border)`` (see :meth:`_entries`).

        Without a border, a block of at least :data:`MEMO_ENTRIES` entries is placed from
        :meth:`_placed` (its band positions found once per plan and index pattern)."""
        band, cpl, brd = out
        if not self.border_order.size and r.size >= MEMO_ENTRIES:
            keep, pi, pj = self._placed(r, c)
            band.append((pi, pj, v if keep is None else v[keep], mirror))
            return
        pi, pj = self.pos[r], self.pos[c]
        keep = (pi >= 0) & (pj >= 0)
        band.append((pi[keep], pj[keep], v[keep], mirror))
        if not self.border_order.size:
            return
        bi, bj = self.bpos[r], self.bpos[c]
        for a, b, pa, pb in ((pi, bj, bi, bj), (pj, bi, bj, bi))[:1 + mirror]:
            sel = (a >= 0) & (b >= 0)
            cpl.append((a[sel], b[sel], v[sel]))
            sel = (pa >= 0) & (pb >= 0)
            brd.append((pa[sel], pb[sel], v[sel]))

    def _placed(self, r: np.ndarray, c: np.ndarray) -> tuple:
        """``(keep, pi, pj)`` for a block at reduced indices ``r``, ``c``: the entries in the
        band (``keep``: their indices, None for all) and their band positions, remembered
        per plan for the next assembly of the same index arrays (the Gauss-Newton steps of
        one pattern: the positions are found once, and :meth:`_flat_index` on these very
        ``pi``, ``pj`` is computed once). The indices are compared in full, so a block of
        another pattern is placed afresh."""
        memo = self.__dict__.setdefault("_place_memo", {})
        key = (r.size, int(r[0]), int(r[-1]), int(c[0]), int(c[-1]))
        for rec in memo.get(key, ()):
            if np.array_equal(rec[0], r) and np.array_equal(rec[1], c):
                return rec[2:]
        pi, pj = self.pos[r], self.pos[c]
        keep = (pi >= 0) & (pj >= 0)
        if keep.all():
            rec = (r.copy(), c.copy(), None, pi, pj)
        else:
            idx = np.flatnonzero(keep)
            rec = (r.copy(), c.copy(), idx, pi[idx], pj[idx])
        memo.setdefault(key, []).append(rec)
        owned = self.__dict__.setdefault("_memo_owned", set())
        owned.update((id(rec[3]), id(rec[4])))
        if len(memo[key]) > MEMO_PER_KEY:   # another pattern each time: keep the newest
            old = memo[key].pop(0)
            dead = {id(old[3]), id(old[4])}
            owned -= dead
            flat = getattr(self, "_flat_memo", {})
            for k in [k for k in flat if k[0] in dead or k[1] in dead]:
                del flat[k]
        return rec[2:]

    def _flat_index(self, j: np.ndarray, i: np.ndarray) -> np.ndarray:
        """The flat band index ``j (ldab - 1) + i + 2 kl`` of entries at band rows ``j`` and
        columns ``i`` (``ab[j, 2 kl + i - j]`` of the C-order band ``(nb, ldab)``), int64;
        remembered for position arrays of :meth:`_placed` (the same objects each assembly)."""
        memo = self.__dict__.setdefault("_flat_memo", {})
        rec = memo.get((id(j), id(i)))
        if rec is not None and rec[0] is j and rec[1] is i:
            return rec[2]
        idx = j.astype(np.int64)
        idx *= self.ldab - 1
        idx += i
        idx += 2 * self.kl
        owned = getattr(self, "_memo_owned", ())
        if id(j) in owned and id(i) in owned:   # arrays the place memo keeps alive
            memo[(id(j), id(i))] = (j, i, idx)
        return idx

    def _place_diagonal(self, rows: tuple, cols: tuple, dr: int, dc: int, v: np.ndarray, mirror: bool,
                        out: tuple, runs: dict) -> None:
        """:meth:`_place` for one diagonal of a block: entry ``t`` at reduced row
        ``rows[0] + dr + t`` and column ``cols[0] + dc + t`` (``rows``, ``cols``: the block's
        ``(first, size)``). Where both map to evenly spaced band positions with one step (one
        axis' nodes), the entries are one :class:`_Stride` each run (no index arrays, a
        strided write); unknowns in neither band nor border drop their entries; the rest
        goes through :meth:`_place`. ``runs`` caches :func:`_affine_runs` per block."""
        L = v.size
        pieces = []
        for (a, size), d in ((rows, dr), (cols, dc)):
            key = (a, size)
            if key not in runs:
                runs[key] = _affine_runs(self.pos[a:a + size], self.bpos[a:a + size] < 0)
            # the runs in piece coordinates t = u - d, clipped to [0, L)
            pieces.append([(max(u0 - d, 0), min(u1 - d, L), p0, s, u0 - d) for u0, u1, p0, s in runs[key]
                           if min(u1 - d, L) > max(u0 - d, 0)])
        R, C = pieces
        i = j = 0
        while i < len(R) and j < len(C):
            (ra, rb, rp, rs, rt), (ca, cb, cp, cs, ct) = R[i], C[j]
            t0, t1 = max(ra, ca), min(rb, cb)
            if t1 > t0:
                if rs == 0 or cs == 0:
                    pass   # eliminated (or otherwise placed) unknowns: no band or border entry
                elif rs is not None and rs == cs:
                    pi0, pj0 = rp + rs * (t0 - rt), cp + cs * (t0 - ct)
                    # a copy: the values are scaled in place later
                    out[0].append(_Stride(pj0, pi0 - pj0, rs, v[t0:t1].copy(), mirror))
                else:
                    t = np.arange(t0, t1)
                    self._place(rows[0] + dr + t, cols[0] + dc + t, v[t0:t1], mirror, out)
            if rb <= cb:
                i += 1
            if cb <= rb:
                j += 1

    def _scatter(self, entries: tuple, scaled: bool = False, out: np.ndarray | None = None) -> tuple:
        """``(ab, B, C, h)`` from :meth:`_entries`: the banded part in LAPACK's band layout
        (``ab[j, 2 kl + i - j] = A[i, j]``, C order (nb, 3 kl + 1), that is ``dgbtrf``'s
        column-major ``(ldab, nb)`` transposed), its coupling to the border (CSC, nb x k)
        and the border block (dense); each entry placed by index arithmetic (no permuted
        copy of the matrix). ``scaled``: ``(ab, B, C, h, sU)`` with ``ab`` scaled as
        :func:`scale_band` would, the column maxima taken from the entries before they are
        placed (no passes over the band for its maxima and its scaling); the band entries'
        values are scaled in place (``entries`` serve one call).

        Notes
        -----
        Every place of the band is taken by at most one entry (the blocks of
        :meth:`_entries` are disjoint and each holds summed values), so the maximum of
        column ``j`` is the largest ``|v|`` placed in it. ``out``: memory for the band (see
        :meth:`_write_band`).
        """
        band, cpl, brd, h = entries
        nb, k, kl = self.pos_order.size, self.border_order.size, self.kl
        strided = [e for e in band if isinstance(e, _Stride)]
        band = [e for e in band if not isinstance(e, _Stride)]
        for e in strided:
            if abs(e.off) > kl:
                raise NotBanded("the sparsity pattern changed since the plan was made")
        sU = _scale_entries(strided, band, nb) if scaled else None
        runs = self._equal_run_entries(strided, band)
        if runs > 1:   # equal axes: one run's band (the others are its copies, never formed)
            L = nb // runs
            ab = self._write_band(strided, _cells_below(band, L), L)
        else:
            ab = self._write_band(strided, band, out=out)
        B, C = None, np.zeros((k, k))
        if k:
            def cat(parts: list, t: int) -> np.ndarray:
                return np.concatenate([p[t] for p in parts]) if parts else np.zeros(0, int)

            B = _coupling_by_columns(cpl, nb, k)
            if B is None:   # entries of several blocks in one column: summed by the conversion
                B = sp.csc_matrix((cat(cpl, 2), (cat(cpl, 0), cat(cpl, 1))), shape=(nb, k))
            np.add.at(C, (cat(brd, 0), cat(brd, 1)), cat(brd, 2))
        return (ab, B, C, h) if sU is None else (ab, B, C, h, sU)

    def _equal_run_entries(self, strided: list, band: list) -> int:
        """:attr:`segments` when the entries of every run of the band are those of the first,
        moved by the run's length (positions and values exactly, none reaching another run),
        else 1.

        Notes
        -----
        A :class:`_Stride` with a counterpart in every run (the same first column within
        the run, offset, step and length) is compared by its values; the other entries as
        cells (column, row, value) sorted within each run, a stride without counterparts
        expanded to its cells (a stretch one axis holds strided and another entry by entry,
        short where it happens). Equal entries give equal runs, so the band of one run is
        all a factorization needs (:class:`BandedKKT` solves the others as right-hand
        sides). With more than ``L / MANY_CELLS`` cells to sort (at least
        ``MIN_SORTED_CELLS``; the FEM rows entry by
        entry, as with hard rows on the acceleration residuals: 1.0 s to sort 1e7 cells
        against 0.13 s to write the whole band and compare it, three axes at N = 3e5), the
        whole band is written as before (and :class:`BandedKKT` compares its runs).
        """
        seg, nb = self.segments, self.pos_order.size
        if seg <= 1 or nb % seg:
            return 1
        L = nb // seg
        by_run: list = [{} for _ in range(seg)]
        loose = []   # strides without a counterpart in every run: compared as cells
        for e in strided:
            a = e.j0 // L
            last = e.j0 + e.step * (e.v.size - 1)
            if min(e.j0, e.j0 + e.off) < a * L or max(last, last + e.off) >= (a + 1) * L:
                return 1
            key = (e.j0 - a * L, e.off, e.step, e.v.size, e.mirror)
            if key in by_run[a]:
                loose.append(e)
            else:
                by_run[a][key] = e
        common = set(by_run[0]).intersection(*by_run[1:])
        for key in common:
            if not all(np.array_equal(by_run[a][key].v, by_run[0][key].v) for a in range(1, seg)):
                return 1
        loose += [e for d in by_run for key, e in d.items() if key not in common]
        cells = list(band)
        for e in loose:   # as index entries: A[j + off, j] = v at j = j0 + step t
            j = e.j0 + e.step * np.arange(e.v.size, dtype=np.int64)
            cells.append((j + e.off, j, e.v, e.mirror))
        rows, cols, vals = [], [], []
        for i, j, v in _oriented(cells):
            rows.append(i)
            cols.append(j)
            vals.append(v)
        if sum(c.size for c in cols) > max(L // MANY_CELLS, MIN_SORTED_CELLS):
            return 1   # sorting them would cost more than writing the whole band and comparing
        return seg if _equal_cells(cols, rows, vals, L, seg) else 1

    def _write_band(self, strided: list, band: list, nb: int | None = None,
                    out: np.ndarray | None = None) -> np.ndarray:
        """The band ``ab[j, 2 kl + i - j] = A[i, j]`` from :class:`_Stride` and index
        entries (see :meth:`_scatter`); long writes go a slice of band rows at a time,
        every one's part in it together: one diagonal at a time would stream the whole band
        once per diagonal (3 kl + 1 values per row). With ``nb``,
        the first ``nb`` band rows alone (strided entries are clipped to them; the index
        entries must lie there). ``out``: a float array of at least the band's size whose
        memory the band takes (zeroed first), instead of fresh memory: a loop of
        factorizations of one pattern then touches its pages once (fresh pages cost the
        first write a page fault each: 0.6 s of CPU for 280 MB, against 0.04 s for the
        scatter itself)."""
        kl, ldab = self.kl, self.ldab
        nb = self.pos_order.size if nb is None else nb
        if out is not None and out.dtype == np.float64 and out.flags.c_contiguous and out.size >= nb * ldab:
            ab = out.reshape(-1)[:nb * ldab].reshape(nb, ldab)
            ab.fill(0.0)
        else:
            ab = np.zeros((nb, ldab))
        flat = ab.reshape(-1)
        runs = []   # long writes: strided entries, and index entries sorted by band row
        for e in strided:
            if e.v.size <= SCATTER_SLICE:
                e.write(ab, kl, 0, nb)
            else:
                runs.append(e)
        for pi, pj, v, mirror in band:
            off = pi - pj
            if off.size and (off.max() > kl or off.min() < -kl):
                raise NotBanded("the sparsity pattern changed since the plan was made")
            del off
            for j, i in ((pj, pi), (pi, pj))[:1 + mirror]:
                if j.size > SCATTER_SLICE and bool(np.all(j[1:] >= j[:-1])):
                    runs.append((j, self._flat_index(j, i), v))
                else:
                    flat[self._flat_index(j, i)] = v
        if runs:
            edges = np.minimum(np.arange(0, nb + SCATTER_SLICE, SCATTER_SLICE), nb)
            cuts = [None if isinstance(r, _Stride) else np.searchsorted(r[0], edges) for r in runs]
            for c in range(edges.size - 1):
                for r, cut in zip(runs, cuts, strict=True):
                    if cut is None:
                        r.write(ab, kl, edges[c], edges[c + 1])
                    elif cut[c + 1] > cut[c]:
                        a, b = cut[c], cut[c + 1]
                        flat[r[1][a:b]] = r[2][a:b]
        return ab

    def assemble(self, D: sp.csr_matrix, E: sp.csr_matrix, diagonal: DiagonalRows | None = None,
                 out: np.ndarray | None = None) -> tuple:
        """The reduced matrix's parts ``(ab, B, C, h, sU)``, the band scaled (see
        :meth:`_scatter`), for these values (``diagonal``: ``E``'s first rows by diagonals,
        :class:`DiagonalRows`); the first call with the very arrays the plan was made from
        returns that assembly. ``out``: memory for the band (:meth:`_write_band`)."""
        first, self._first = getattr(self, "_first", None), None
        if first is not None and first[0] is D.data and first[1] is E.data:
            return first[2]
        stencil = self._stencil(D, E, diagonal)
        if stencil is not None:
            return stencil.parts(D, E, self.ldab, out=out)
        return self._scatter(self._entries(D, E, diagonal), scaled=True, out=out)

    def _stencil(self, D: sp.csr_matrix, E: sp.csr_matrix, diagonal: DiagonalRows | None) -> _Stencil | None:
        """The :class:`_Stencil` of ``D`` and ``E``'s pattern, kept for the plan's last pattern
        (an assembly that is not the plan's first is a factorization of the pattern again: a
        Gauss-Newton step, a lambda or an interior-point iteration); None for a plan with a
        border or several runs, a pattern of more than :data:`STENCIL_ENTRIES` entries, or
        where it does not apply."""
        if self.border_order.size or self.segments > 1 or D.nnz + E.nnz > STENCIL_ENTRIES:
            return None
        by_diagonals = self._pairs_by_diagonals(E, diagonal)
        kept = self.__dict__.get("_stencil_kept")
        if kept is not None and kept.matches(D, E, by_diagonals):
            return kept
        try:
            self._stencil_kept = _Stencil(self, D, E, by_diagonals)
        except NotBanded:   # placed as before, which says why
            self._stencil_kept = None
            return None
        return self._stencil_kept

    def eliminated_columns(self, E: sp.csr_matrix) -> sp.csr_matrix:
        """``E`` restricted to the eliminated unknowns (kept for the last ``E`` seen: every
        lambda of a sweep has the same equality rows)."""
        return self._eliminated(E)[0]

    def _eliminated(self, E: sp.csr_matrix) -> tuple:
        """:meth:`eliminated_columns` and its transpose in CSR (a row-wise product is about
        twice as fast as scipy's column-wise one for ``E_z^T mu``), cached together."""
        cached = getattr(self, "_Ez", None)
        if cached is None or cached[0] is not E.data:   # the same arrays under a new wrapper
            stencil = self.__dict__.get("_stencil_kept")
            if stencil is not None and stencil.matches_rows(E):   # a pattern seen: gathers
                cached = (E.data, *stencil.eliminated(self, E))
            else:
                # scipy's column indexing (a slice for one run of unknowns): faster than the
                # product with a selection matrix
                Ez = E[:, self.elim_index]
                cached = (E.data, Ez, Ez.T.tocsr())
            self._Ez = cached
        return cached[1], cached[2]

    def objective_part(self, D1: sp.csr_matrix) -> tuple:
        """The parts of :math:`D_1^T D_1` alone (rows that are all folded and touch no
        eliminated unknown): what a lambda-weighted block adds, per unit of lambda."""
        H = (D1.T @ D1).tocoo()
        out = ([], [], [])
        self._place(H.row, H.col, H.data, False, out)
        ab, B, C, _ = self._scatter((*out, None))
        return ab, B, C

    def admitting(self, D: sp.csr_matrix, E: sp.csr_matrix, colnode: np.ndarray,
                  lam_rows: np.ndarray | None = None, span: int = FOLD_SPAN) -> BandPlan | None:
        """This plan for objective rows ``D`` of another pattern (``E``'s pattern the plan's,
        which the caller checks), or None when it does not serve them.

        It serves them when the rows fold and the unknowns are eliminated as in the plan
        and every folded row's banded unknowns lie within ``kl`` band positions of each
        other (their products :math:`D_f^T D_f` stay in the band): e.g. a Gauss-Newton
        step's rows whose first linearization had exact zeros that later ones fill. The
        answer is a copy with ``D``'s entry count (:meth:`same_pattern`), without the first
        assembly.
        """
        m, n = D.shape
        if (m, n) != (self.m, self.n) or E.shape != (self.p, self.n) or E.nnz != self.nnz_E:
            return None
        lo, hi = row_span(D, colnode)
        fold = (hi < 0) | (hi - lo <= span)
        if not np.array_equal(fold, self.fold):
            return None
        if not np.array_equal(_eliminated(D, fold, colnode, lam_rows), self.elim):
            return None
        Dcol = D.indices.astype(np.int64)
        rows = np.flatnonzero(np.diff(D.indptr))
        if rows.size:   # the band positions each row spans (rows with entries: whole segments)
            pc = self.pos[Dcol].astype(np.int64)
            banded = pc >= 0
            starts = D.indptr[:-1][rows]
            hi_p = np.maximum.reduceat(np.where(banded, pc, -1), starts)
            lo_p = np.minimum.reduceat(np.where(banded, pc, np.iinfo(np.int64).max), starts)
            if np.any(fold[rows] & (hi_p >= 0) & (hi_p - lo_p > self.kl)):
                return None
        out = copy.copy(self)
        out.nnz_D = D.nnz
        out._first = None
        for memo in ("_place_memo", "_flat_memo", "_memo_owned", "_stencil_kept"):   # the copy keeps its own
            out.__dict__.pop(memo, None)
        return out

    def same_pattern(self, D: sp.csr_matrix, E: sp.csr_matrix) -> bool:
        """Whether ``D`` and ``E`` have the shapes and entry counts this plan was made for."""
        return (D.shape == (self.m, self.n) and E.shape == (self.p, self.n)
                and D.nnz == self.nnz_D and E.nnz == self.nnz_E)


class BandedKKT(Factorization):
    r"""A banded-plus-border factorization of the augmented system (see the module Notes).

    Parameters
    ----------
    D, E : scipy.sparse.csr_matrix
        Objective rows (m, n) and equality rows (p, n).
    colnode : ndarray of int (n,)
        Node of each unknown (-1: border). Ignored when ``plan`` is given.
    params : ndarray of int, optional
        Indices (in ``x``) of the error-model parameters, for :attr:`schur`.
    plan : BandPlan, optional
        A plan of a problem with the same sparsity pattern, reused (only the values are
        scattered and factorised again).
    parts : tuple, optional
        The assembled ``(ab, B, C, h, sU)`` of :meth:`BandPlan.assemble` or
        :meth:`AffineBand.at` (the band scaled by ``sU``), instead of assembling from ``D``
        and ``E``.
    lam_rows : ndarray of bool, optional
        Passed to :meth:`BandPlan.build`.
    diagonal : DiagonalRows, optional
        ``E``'s first rows by diagonals (placed by formula, see :class:`DiagonalRows`).
    out : ndarray, optional
        Memory for the band (``BandPlan._write_band``); the factor then lives in it.

    Raises
    ------
    NotBanded
        When the rows are not local enough, or ``plan`` is for another pattern.
    numpy.linalg.LinAlgError
        When the banded part or the border's Schur complement is singular.

    Notes
    -----
    An unknown ``w`` whose only objective entries are ``h w^2`` (the acceleration residual
    over ``sigma_a``) is eliminated first: ``w = (b_w - E_w^T mu) / h``, which adds
    :math:`-E_w h^{-1} E_w^T` to the multipliers' block (for the FEM rows,
    :math:`-\sigma_a^2 M^2`, pentadiagonal). One axis with point fixes then has the
    unknowns ``r_j, mu_j`` per node and bandwidth 4. The banded part is scaled
    symmetrically by the square roots of its column maxima before ``dgbtrf``.
    """

    method = "banded"
    shift = 0.0

    def __init__(self, D: sp.csr_matrix, E: sp.csr_matrix, colnode: np.ndarray | None = None,
                 params: np.ndarray | None = None, plan: BandPlan | None = None, parts: tuple | None = None,
                 lam_rows: np.ndarray | None = None, diagonal: DiagonalRows | None = None,
                 out: np.ndarray | None = None):
        D, E = canonical(D), canonical(E)
        if plan is None:
            plan = BandPlan.build(D, E, colnode, lam_rows=lam_rows, diagonal=diagonal)
        self.plan = pl = plan
        D, E = self._bind(D, E)
        self.params = np.asarray(params if params is not None else [], dtype=int)
        self._factor_parts(pl.assemble(D, E, diagonal, out=out) if parts is None else parts)

    def _bind(self, D: sp.csr_matrix, E: sp.csr_matrix) -> tuple:
        """``S``, the folded rows and the eliminated columns from ``D`` and ``E``, which must
        have the pattern of :attr:`plan`; returns them canonical.

        Raises
        ------
        NotBanded
            When ``D`` and ``E`` have another pattern.
        """
        D, E = canonical(D), canonical(E)
        pl = self.plan
        if not pl.same_pattern(D, E):
            raise NotBanded("the sparsity pattern changed since the plan was made")
        self.S = AugmentedOperator(D, E)
        self._unf = pl.unfolded
        self._Df = D[pl.fold] if self._unf.size else D
        if pl.elim.size:
            self._Ez, self._EzT = pl._eliminated(E)
        return D, E

    def for_matrices(self, D: sp.csr_matrix, E: sp.csr_matrix) -> BandedKKT:
        """This factorization as that of ``S`` built from ``D`` and ``E``: the same pattern
        (:meth:`BandPlan.same_pattern`) with values equal to rounding, e.g. a lambda sweep's
        point handed to the solve at the same lambda. The factor is shared, ``S`` and the
        folded and eliminated rows are ``D``'s and ``E``'s, so refinement and the backward
        error are measured against the given matrices.

        Raises
        ------
        NotBanded
            When ``D`` and ``E`` have another pattern.
        """
        out = copy.copy(self)
        out._bind(D, E)
        return out

    @classmethod
    def numeric(cls, plan: BandPlan, parts: tuple) -> BandedKKT:
        """The factorization of assembled ``parts`` (:meth:`BandPlan.assemble`) alone, for
        :meth:`logdet`: no operator, so no solves of the full system (the lambda sweep's
        log-determinant at neighbouring lambdas)."""
        self = cls.__new__(cls)
        self.plan, self.params = plan, np.zeros(0, dtype=int)
        self._factor_parts(parts)
        return self

    def _factor_parts(self, parts: tuple) -> None:
        """Factor the banded part, then the border's Schur complement. ``parts`` is
        ``(ab, B, C, h, sU)`` with the band scaled by ``sU`` (:meth:`BandPlan.assemble`,
        :meth:`AffineBand.at`)."""
        pl = self.plan
        ab, Bs, C, self._h, sU = parts   # ab is this factor's own (dgbtrf overwrites it)
        del parts
        k, kl = pl.border, pl.kl
        self.k = k
        # axes with equal band rows (one grid, one sigma_a, the same items on each): one
        # run is factored, the others are its extra right-hand sides
        nb = pl.pos_order.size
        if ab.shape[0] < nb:   # one run's band (BandPlan._scatter found the runs equal)
            self._runs = runs = nb // ab.shape[0]
        else:
            self._runs = runs = pl.segments if pl.segments > 1 and _equal_runs(ab, pl.segments) else 1
        one = ab[:nb // runs]
        # complex parts (AffineBand.at_complex: a lambda with an imaginary step) take zgbtrf
        gbtrf, self._gbtrs = lapack.get_lapack_funcs(("gbtrf", "gbtrs"), (one,))
        lu, piv, info = gbtrf(one.T, kl, kl, overwrite_ab=1)
        del ab, one
        if info != 0:
            raise np.linalg.LinAlgError(f"the banded part is singular (zero pivot at {info})")
        self._lu, self._piv = lu, piv
        self._sU = sU
        if k:
            dmax = np.abs(np.diag(C))
            sW = 1.0 / np.sqrt(np.where(dmax > 0, dmax, 1.0))
            B = Bs.tocsc(copy=True)   # diag(sU) Bs diag(sW), entry by entry
            B.sum_duplicates()        # _border_solve places B's entries one by one
            B.data *= sU[B.indices] * np.repeat(sW, np.diff(B.indptr))
            self.B = B
            self._sW = sW
            self._xruns = self._border_solve(B)
            BtX = np.zeros((k, k), dtype=self._lu.dtype)
            L = B.shape[0] // runs
            Br = B.tocsr() if runs > 1 else None
            for a, cols, Xa in self._xruns:
                BtX[:, cols] += (B if Br is None else Br[a * L:(a + 1) * L]).T @ Xa
            self.schur_border = C * sW[:, None] * sW[None, :] - BtX
            if not np.all(np.isfinite(self.schur_border)) or np.linalg.cond(self.schur_border) > 1e15:
                raise np.linalg.LinAlgError("singular Schur complement of the border")

    def _border_solve(self, B: sp.csc_matrix) -> list:
        """``X = A^{-1} B`` for the border's columns ``B`` (nb, k), by runs:
        ``[(a, cols, X_a)]``, ``X_a`` (L, len(cols)) the rows of run ``a`` (the others are
        zero: with equal runs (:attr:`BandPlan.segments`) the banded part is block diagonal).

        Notes
        -----
        With one run this is the dense ``A^{-1} B``. With several, a border column (an
        error-model parameter of one axis) is nonzero in one run, and so is its solution:
        only those blocks are formed and kept, from ``B``'s own entries (no dense ``(nb,
        k)`` copy of ``B`` or of ``X``: each would be fresh memory of the whole band's
        length times the border that the process must fault in).
        """
        runs, k = self._runs, B.shape[1]
        if runs == 1:
            return [(0, np.arange(k), self._band_solve(B.toarray()))]
        L = B.shape[0] // runs
        blocks = []   # (run, column, rows within the run, values)
        for j in range(k):
            rows, vals = B.indices[B.indptr[j]:B.indptr[j + 1]], B.data[B.indptr[j]:B.indptr[j + 1]]
            run = rows // L
            for a in np.flatnonzero(np.bincount(run[vals != 0], minlength=runs)):   # O(nnz), no sort
                sel = run == a
                blocks.append((int(a), j, rows[sel] - a * L, vals[sel]))
        if not blocks:
            return []
        # by run (stable: by column within a run): each run's solutions are adjacent columns,
        # kept as views of the one solve (no copies: each would be fresh memory)
        blocks.sort(key=lambda blk: blk[0])
        Rs = np.zeros((L, len(blocks)), dtype=self._lu.dtype, order="F")
        for c, (_, _, r, v) in enumerate(blocks):
            Rs[r, c] = v
        x = self._trs(Rs, overwrite=True)
        out, start = [], 0
        for a, group in itertools.groupby(blocks, key=lambda blk: blk[0]):
            cols = np.array([blk[1] for blk in group])
            out.append((a, cols, x[:, start:start + cols.size]))
            start += cols.size
        return out

    # ------------------------------------------------------------------ solves
    def _trs(self, R: np.ndarray, overwrite: bool = False) -> np.ndarray:
        """``A^{-1} R`` for one run's banded factor (``dgbtrs``, or ``zgbtrs`` for complex
        parts), ``R`` (L,) or (L, c); in place of a Fortran-ordered ``R`` with
        ``overwrite``."""
        kl = self.plan.kl
        x, info = self._gbtrs(self._lu, kl, kl, R, self._piv, overwrite_b=overwrite)
        if info != 0:  # pragma: no cover - argument error
            raise np.linalg.LinAlgError(f"gbtrs failed (info {info})")
        return x

    def _band_solve(self, R: np.ndarray, overwrite: bool = False) -> np.ndarray:
        """``A^{-1} R`` for the scaled banded part ``A`` and ``R`` (nb, c); with equal runs
        (:attr:`BandPlan.segments`) each run's rows are right-hand sides of the one factor,
        those that are zero (a parameter of another axis) skipped."""
        runs = self._runs
        if runs == 1:
            return self._trs(R, overwrite)
        nb = R.shape[0]
        L = nb // runs
        if R.ndim == 1:
            if all(R[a * L:(a + 1) * L].any() for a in range(runs)):
                # the runs as the columns of one (L, runs) Fortran array: R's own memory
                return self._trs(R.reshape(runs, L).T, overwrite).T.reshape(nb)
            return self._band_solve(R[:, None])[:, 0]
        c = R.shape[1]
        blocks = [(a, j) for a in range(runs) for j in range(c) if R[a * L:(a + 1) * L, j].any()]
        out = np.zeros_like(R)
        if not blocks:
            return out
        Rs = np.empty((L, len(blocks)), dtype=R.dtype, order="F")
        for col, (a, j) in enumerate(blocks):
            Rs[:, col] = R[a * L:(a + 1) * L, j]
        x = self._trs(Rs, overwrite=True)
        for col, (a, j) in enumerate(blocks):
            out[a * L:(a + 1) * L, j] = x[:, col]
        return out

    def _reduced_solve(self, r: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Solve the reduced (unscaled, after eliminations) system for ``r`` (R,) or (R, c),
        into ``out`` when given (an array like ``r``, or ``r`` itself: it is gathered before
        anything is written). A real ``r`` with a factor of complex
        parts gives the real part of the solution (the scalings, the gathers and the
        scatters are real: only the band's and the border's solves are complex)."""
        pl = self.plan
        # one right-hand side stays one-dimensional (gathers and scatters of a vector are
        # about twice as fast as of an (R, 1) array's rows)
        sU = self._sU if r.ndim == 1 else self._sU[:, None]
        R = pl.moves.gather(r)
        R *= sU
        if R.dtype != self._lu.dtype:
            R = R.astype(self._lu.dtype)
        y = self._band_solve(R, overwrite=True)   # R is this solve's own gathered copy
        # every reduced unknown is banded, in the border or eliminated; solve() fills the
        # eliminated ones, so nothing needs zeroing here
        out = np.empty_like(r) if out is None else out
        if self.k:
            sW = self._sW if r.ndim == 1 else self._sW[:, None]
            rW = r[pl.border_order] * sW
            zW = np.linalg.solve(self.schur_border, rW - self.B.T @ y)
            L = y.shape[0] // self._runs
            for a, cols, Xa in self._xruns:   # y -= A^{-1} B zW, run by run
                y[a * L:(a + 1) * L] -= Xa @ zW[cols]
            out[pl.border_order] = (zW * sW).real if out.dtype.kind != "c" else zW * sW
        if out.dtype.kind != "c" and y.dtype.kind == "c":
            y = y.real * sU
        else:
            y *= sU
        pl.moves.scatter(y, out)
        return out

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``S z = rhs`` for one (T,) or several (T, c) right-hand sides."""
        return self._solve(self._as_rhs(rhs))

    def solve_x(self, rhs: np.ndarray) -> np.ndarray:
        """The ``x`` part of :meth:`solve` alone (the residuals are not formed), for a
        lambda sweep's points."""
        return self._solve(self._as_rhs(rhs), x_only=True)

    def solve_x_real(self, rhs: np.ndarray, eliminated: bool = True, interior: bool = True) -> np.ndarray:
        r"""The real part of :meth:`solve_x` for a real ``rhs`` (one or several columns).

        With a factor of :meth:`AffineBand.at_complex`'s parts at :math:`\lambda + ih` this
        is the solution at :math:`\lambda` to :math:`O(h^2)`: the eliminations, scalings,
        gathers and scatters stay real (they are real linear maps, so the real part may be
        taken after the band's solve), only ``zgbtrs`` and the border's solve are complex.
        The same as :meth:`solve_x` for a real factor. With ``eliminated=False`` the
        eliminated unknowns (:attr:`BandPlan.elim_index`, the acceleration corrections) are
        not back-substituted and come out NaN, for a caller that reads none of them (a
        lambda sweep's :math:`dx/d\lambda` where no lambda-weighted row touches them).
        ``interior`` is :class:`CondensedKKT`'s (ignored here).
        """
        return self._solve(self._as_rhs(rhs, real=True), x_only=True, eliminated=eliminated)

    def _as_rhs(self, rhs, real: bool = False) -> np.ndarray:
        """``rhs`` as a new or given array of the factor's type (float, or complex for a
        factor of :meth:`AffineBand.at_complex`'s parts), or a real one with ``real``
        (:meth:`solve_x_real`)."""
        if self._lu.dtype.kind == "c" and not real:
            return np.asarray(rhs, dtype=complex)
        rhs = np.asarray(rhs)
        if rhs.dtype.kind == "c":
            raise TypeError("solve_x_real takes a real right-hand side" if real else
                            "a complex right-hand side needs a factor of complex parts "
                            "(AffineBand.at_complex)")
        return rhs.astype(float, copy=False)

    def _solve(self, rhs: np.ndarray, x_only: bool = False, eliminated: bool = True) -> np.ndarray:
        pl = self.plan
        m, n, el = pl.m, pl.n, pl.elim
        nu = self._unf.size
        b1, bx, bmu = rhs[:m], rhs[m:m + n], rhs[m + n:]
        b1f = b1[pl.fold] if nu else b1
        # without unfolded rows the reduced unknowns (x, mu) are z's own tail: the reduced
        # right-hand side is formed there and solved in place (the gather copies it before
        # anything is written back: one array of the reduced unknowns' length fewer per solve)
        z = None if x_only or nu else np.empty_like(rhs)
        r = (np.empty((n + nu + bmu.shape[0],) + rhs.shape[1:], dtype=rhs.dtype) if z is None
             else z[m:])
        if b1f.any():
            np.add(bx, _mul(self._Df.T, b1f), out=r[:n])
        else:
            r[:n] = bx
        r[n:n + nu] = b1[self._unf]
        r[n + nu:] = bmu
        if el.size:
            ei = pl.elim_index
            hcol = self._h.reshape((-1,) + (1,) * (r.ndim - 1))
            gz = r[ei] / hcol
            if gz.any():   # (none for a sweep's dx/dlambda: no lambda row touches w)
                r[n + nu:] -= _mul(self._Ez, gz)
        zr = self._reduced_solve(r, out=None if z is None else r)
        mu = zr[n + nu:]
        if el.size and not (x_only and not eliminated):
            w = _mul(self._EzT, mu)
            w /= hcol
            np.subtract(gz, w, out=w)
            zr[ei] = w
        elif el.size:
            zr[ei] = np.nan   # not back-substituted (solve_x_real's eliminated=False)
        x = zr[:n]
        if x_only:
            return x
        if z is None:
            z = np.empty_like(rhs)
            z[m:m + n] = x
            z[m + n:] = mu
        if nu:
            z[:m][pl.fold] = _mul(self._Df, x) - b1f
            z[:m][self._unf] = zr[n:n + nu]
        else:
            z[:m] = _mul(self._Df, x) - b1f
        return z

    def logdet(self) -> float:
        r""":math:`\log|\det S|` up to a constant that depends on the pattern only (the
        folded rows' ``-I`` and signs): the eliminated pivots ``h``, the banded LU's
        diagonal and the border's Schur complement, each unscaled.

        Notes
        -----
        With the symmetric scaling ``s``, :math:`\log|\det A| = \sum_j \log|U_{jj}| -
        2 \sum_j \log s_j`; eliminating ``w`` by its pivot ``h`` and the border by its Schur
        complement ``W`` multiply the determinant by :math:`\prod h` and :math:`\det W`.
        """
        kl = self.plan.kl
        out = float(np.sum(np.log(self._h))) if self._h.size else 0.0
        out += (self._runs * float(np.sum(np.log(np.abs(self._lu[2 * kl]))))
                - 2.0 * float(np.sum(np.log(self._sU))))
        if self.k:
            out += float(np.linalg.slogdet(self.schur_border)[1]) - 2.0 * float(np.sum(np.log(self._sW)))
        return out

    def logdet_step(self, h: float) -> float:
        r"""The derivative of :meth:`logdet` along the imaginary step ``h`` of a factor of
        complex parts (:meth:`AffineBand.at_complex`): :math:`d\log|\det S| / d\lambda` at
        the step's real lambda.

        Notes
        -----
        The complex-step derivative: the parts at :math:`\lambda + ih` with the scales of
        the real lambda held fixed are :math:`\tilde A(\lambda) + ih\,\tilde A'(\lambda)
        + O(h^2)`, every pivot :math:`U_{jj}` becomes :math:`U_{jj} + ih\,U_{jj}'` (the
        pivoting is that of the real matrix, up to ties), and

        .. math:: \frac{d}{d\lambda}\log|\det S| = \frac{1}{h}\Big(\sum_j
            \frac{\operatorname{Im} U_{jj}}{\operatorname{Re} U_{jj}}
            + \operatorname{tr}\big((\operatorname{Re} W)^{-1} \operatorname{Im} W\big)\Big)
            + O(h^2),

        with :math:`W` the border's Schur complement (the fixed scales and the eliminated
        pivots, independent of lambda, contribute nothing). No difference is taken, so
        there is no cancellation: with :math:`h = 10^{-20}\lambda` the derivative is exact
        to rounding, from one complex factorization where a central difference takes two
        real ones and is accurate to :math:`\delta^2/6`.
        """
        if self._lu.dtype.kind != "c":
            raise TypeError("logdet_step needs a factor of complex parts (AffineBand.at_complex)")
        u = self._lu[2 * self.plan.kl]
        out = self._runs * float(np.sum(u.imag / u.real))
        if self.k:
            W = self.schur_border
            out += float(np.trace(np.linalg.solve(W.real, W.imag)))
        return out / h

    # ---------------------------------------------------------- conditioning
    @property
    def keep(self):
        """Not None when there are error-model parameters (as :class:`bvpnav.linalg.lsq.BorderedLU`)."""
        return True if self.params.size else None

    @property
    def schur(self) -> np.ndarray:
        """Schur complement of the error-model parameters in ``S`` (q, q): the information
        matrix :func:`bvpnav.solve.conditioning.information_matrix` reads."""
        pl = self.plan
        bp = pl.bpos[self.params]
        other = np.setdiff1d(np.arange(self.k), bp)
        sc = self._sW
        W = self.schur_border / sc[:, None] / sc[None, :]   # back to the unscaled unknowns
        H = W[np.ix_(bp, bp)]
        if other.size:
            H = H - W[np.ix_(bp, other)] @ np.linalg.solve(W[np.ix_(other, other)], W[np.ix_(other, bp)])
        return H

