"""The least-squares KKT system as a banded matrix with a border: O(N) factorizations.

The augmented system of :mod:`bvpnav.lsq`,

.. math::

    S = \\begin{bmatrix} -I & D & 0 \\\\ D^T & 0 & E^T \\\\ 0 & E & 0 \\end{bmatrix},
    \\qquad S z = b, \\quad z = (\\rho, x, \\mu),

is never assembled here. Objective rows of ``D`` that touch only a few neighbouring time
nodes are *folded*: their residual :math:`\\rho_f = D_f x - b_f` is eliminated exactly,
which leaves the reduced symmetric system

.. math::

    \\begin{bmatrix} D_f^T D_f & D_u^T & E^T \\\\ D_u & -I & 0 \\\\ E & 0 & 0 \\end{bmatrix}
    \\begin{bmatrix} x \\\\ \\rho_u \\\\ \\mu \\end{bmatrix} =
    \\begin{bmatrix} b_x + D_f^T b_f \\\\ b_u \\\\ b_\\mu \\end{bmatrix}

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

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack

__all__ = ["BandedKKT", "BandPlan", "NotBanded", "Factorization", "AugmentedOperator", "ruiz_scale",
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


def row_span(A: sp.csr_matrix, colnode: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest node of each row's columns with a node >= 0 (``hi = -1`` for a
    row with none)."""
    A = sp.csr_matrix(A)
    m = A.shape[0]
    nn = colnode[A.indices]
    rows = np.repeat(np.arange(m), np.diff(A.indptr))
    big = np.iinfo(np.int64).max
    lo = np.full(m, big, dtype=np.int64)
    hi = np.full(m, -1, dtype=np.int64)
    loc = nn >= 0
    np.minimum.at(lo, rows[loc], nn[loc])
    np.maximum.at(hi, rows[loc], nn[loc])
    return lo, hi


def ruiz_scale(K: sp.csr_matrix, sweeps: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric Ruiz scaling ``s`` so that ``diag(s) K diag(s)`` has rows of max-norm near 1;
    also the row index of every stored entry (``K`` is CSR)."""
    T = K.shape[0]
    rows = np.repeat(np.arange(T), np.diff(K.indptr))
    cols, vals = K.indices, np.abs(K.data)
    s = np.ones(T)
    nonempty = np.diff(K.indptr) > 0
    starts = K.indptr[:-1][nonempty]
    for _ in range(sweeps):
        r = np.zeros(T)
        if vals.size:
            r[nonempty] = np.maximum.reduceat(vals * s[rows] * s[cols], starts)
        r = np.sqrt(r)
        r[r == 0] = 1.0
        s /= r
    return s, rows


def column_squares(A: sp.csr_matrix, cols: np.ndarray) -> np.ndarray:
    """Sum of squares of the entries of each of ``A``'s columns ``cols``."""
    if cols.size == 0:
        return np.zeros(0)
    return np.asarray(A[:, cols].power(2).sum(axis=0)).ravel()


class AugmentedOperator:
    """The augmented matrix ``S`` of :mod:`bvpnav.lsq` as an operator (never assembled).

    Parameters
    ----------
    D, E : scipy.sparse.csr_matrix
        Objective rows (m, n) and equality rows (p, n).
    """

    def __init__(self, D: sp.csr_matrix, E: sp.csr_matrix):
        self.D, self.E = sp.csr_matrix(D), sp.csr_matrix(E)
        self.m, self.n = self.D.shape
        self.p = self.E.shape[0]
        self.shape = (self.m + self.n + self.p,) * 2

    def __matmul__(self, z: np.ndarray) -> np.ndarray:
        m, n = self.m, self.n
        rho, x, mu = z[:m], z[m:m + n], z[m + n:]
        return np.concatenate([self.D @ x - rho, self.D.T @ rho + self.E.T @ mu, self.E @ x])

    def norm_inf(self) -> float:
        """The infinity norm (largest absolute row sum) of ``S``."""
        aD, aE = abs(self.D), abs(self.E)
        one = np.ones
        parts = [aD @ one(self.n) + 1.0, aD.T @ one(self.m) + aE.T @ one(self.p), aE @ one(self.n)]
        return float(max((float(np.max(v)) for v in parts if v.size), default=0.0))


class Factorization:
    """What every factorization of the augmented system offers: ``S``, :meth:`solve` and
    :meth:`refined` (iterative refinement against ``S`` itself)."""

    S = None

    def solve(self, rhs: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def refined(self, rhs: np.ndarray, steps: int, tol: float = 0.0, window: slice | None = None,
                stall: float | None = None):
        """Solve with up to ``steps`` iterative-refinement steps in double precision.

        Returns ``(z, steps_taken, last_relative_correction)``; the correction is measured
        on ``window`` (default: all of ``z``) and refinement stops below ``tol``, or, with
        ``stall``, as soon as a correction is not at least ``stall`` times smaller than the
        one before (the rounding floor has been reached).

        Notes
        -----
        :math:`z_{k+1} = z_k + \\tilde S^{-1} (b - S z_k)` with the factorised
        :math:`\\tilde S`; it converges when :math:`\\|I - \\tilde S^{-1} S\\| < 1`.
        """
        window = window if window is not None else slice(None)
        z = self.solve(rhs)
        corr, k = np.inf, 0
        for _ in range(steps):
            k += 1
            dz = self.solve(rhs - self.S @ z)
            z += dz
            prev, corr = corr, float(np.max(np.abs(dz[window])) / max(np.max(np.abs(z[window])), 1e-300))
            if corr < tol or (stall is not None and corr > stall * prev):
                break
        return z, k, (0.0 if k == 0 else corr)


def canonical(A: sp.spmatrix) -> sp.csr_matrix:
    """``A`` as CSR without duplicates or explicit zeros (a copy when it had any: an explicit
    zero must not tie a row to a node)."""
    A = sp.csr_matrix(A)
    if not A.has_canonical_format or (A.data.size and not np.all(A.data)):
        A = A.copy()
        A.sum_duplicates()
        A.eliminate_zeros()
    return A


def _pairs(group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All ordered pairs ``(a, b)`` of positions with the same value of ``group`` (a sorted
    array), ``(a, a)`` included: the entries of a sum of outer products, one per group."""
    if group.size == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    starts = np.flatnonzero(np.r_[True, group[1:] != group[:-1]])
    counts = np.diff(np.r_[starts, group.size])
    c = np.repeat(counts, counts)                 # group size of every position
    st = np.repeat(starts, counts)                # group start of every position
    a = np.repeat(np.arange(group.size), c)
    first = np.repeat(np.cumsum(c) - c, c)        # where each position's run of pairs starts
    b = np.repeat(st, c) + (np.arange(a.size) - first)
    return a, b


@dataclass(eq=False)
class _Group:
    """One kind of contribution to the reduced matrix: where each value goes."""

    band: np.ndarray        # which values go to the banded part
    band_dest: np.ndarray   # their flat index in the (nb, ldab) row-major band array
    B: np.ndarray           # which values couple the band to the border
    B_row: np.ndarray
    B_col: np.ndarray
    C: np.ndarray           # which values lie in the border block
    C_dest: np.ndarray


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

    def describe(self) -> str:
        """E.g. ``"banded (kl=4, ku=4, 200001 unknowns, border 0)"``."""
        return f"banded (kl={self.kl}, ku={self.ku}, {self.size} unknowns, border {self.border})"

    @classmethod
    def build(cls, D: sp.csr_matrix, E: sp.csr_matrix, colnode: np.ndarray,
              max_band: int = MAX_BAND, max_border: int = MAX_BORDER, span: int = FOLD_SPAN) -> BandPlan:
        """Order the reduced system by node; raise :class:`NotBanded` when it is not local.

        Parameters
        ----------
        D, E : scipy.sparse.csr_matrix
            Objective rows (m, n) and equality rows (p, n), canonical (sorted indices, no
            duplicates).
        colnode : ndarray of int (n,)
            Node of each unknown, -1 for unknowns that go to the border.
        """
        m, n = D.shape
        p = E.shape[0]
        lo, hi = row_span(D, colnode)
        fold = (hi < 0) | (hi - lo <= span)
        unf = np.flatnonzero(~fold)
        Drow = np.repeat(np.arange(m), np.diff(D.indptr))
        Dcol = D.indices.astype(np.int64)
        nnz_row = np.diff(D.indptr)[Drow]
        # an unknown is eliminated when each of its objective entries is alone in a folded row
        alone = fold[Drow] & (nnz_row == 1)
        single = np.bincount(Dcol, weights=alone, minlength=n) == np.bincount(Dcol, minlength=n)
        single &= np.bincount(Dcol, minlength=n) > 0
        single &= colnode >= 0
        elim = np.flatnonzero(single)
        elo, ehi = row_span(E, colnode)
        enode = np.where((ehi >= 0) & (ehi - elo <= span), (elo + ehi) // 2, -1)
        node = np.concatenate([colnode, np.full(unf.size, -1, dtype=np.int64), enode])
        node[elim] = -2
        # within a node, unknowns that reach the next node last (a FEM multiplier reaches one
        # node on; one axis then has bandwidth 4 even where a node holds extra unknowns)
        reach = node.copy()
        reach[n + unf.size:] = np.where(enode >= 0, ehi, -1)
        local = np.flatnonzero(node >= 0)
        order = local[np.lexsort((reach[local], node[local]))]
        pos = np.full(node.size, -1, dtype=np.int64)
        pos[order] = np.arange(order.size)
        border = np.flatnonzero(node == -1)
        if border.size > max_border:
            raise NotBanded(f"{border.size} unknowns in the border (error-model parameters and rows "
                            f"that reach far in time), more than {max_border}")
        bpos = np.full(node.size, -1, dtype=np.int64)
        bpos[border] = np.arange(border.size)
        plan = cls(fold=fold, elim=elim, pos=pos, bpos=bpos, kl=0, n=n, m=m, p=p,
                   nnz_D=D.nnz, nnz_E=E.nnz)
        plan.pos_order, plan.border_order = order, border
        plan._analyse(D, E, Drow, Dcol, max_band)
        return plan

    def _analyse(self, D, E, Drow, Dcol, max_band) -> None:
        """Index arrays of every contribution (the symbolic factorization's input)."""
        n, nu = self.n, int(np.count_nonzero(~self.fold))
        off = n + nu
        keep = np.ones(n, dtype=bool)
        keep[self.elim] = False
        zslot = np.full(n, -1, dtype=np.int64)
        zslot[self.elim] = np.arange(self.elim.size)
        # H = D_f^T D_f over kept columns: pairs of entries in the same folded row
        fe = np.flatnonzero(self.fold[Drow] & keep[Dcol])
        a, b = _pairs(Drow[fe])
        self._H = (fe[a], fe[b])
        Hi, Hj = Dcol[fe[a]], Dcol[fe[b]]
        # h: the eliminated unknowns' diagonal
        ze = np.flatnonzero(self.fold[Drow] & ~keep[Dcol])
        self._h = (ze, zslot[Dcol[ze]])
        # E over kept columns (and its transpose)
        Erow = np.repeat(np.arange(self.p), np.diff(E.indptr))
        Ecol = E.indices.astype(np.int64)
        ke = np.flatnonzero(keep[Ecol])
        self._E = ke
        # Q = E_z h^-1 E_z^T: pairs of entries in the same eliminated column
        qe = np.flatnonzero(~keep[Ecol])
        qe = qe[np.argsort(Ecol[qe], kind="stable")]
        a, b = _pairs(Ecol[qe])
        self._Q = (qe[a], qe[b], zslot[Ecol[qe[a]]])
        Qi, Qj = off + Erow[qe[a]], off + Erow[qe[b]]
        # unfolded rows: their residual against their columns, and -1 on the diagonal
        ue = np.flatnonzero(~self.fold[Drow])
        urow = np.full(self.m, -1, dtype=np.int64)
        urow[~self.fold] = np.arange(nu)
        self._U = ue
        Ui = n + urow[Drow[ue]]
        groups = {"H": (Hi, Hj),
                  "E": (np.r_[off + Erow[ke], Ecol[ke]], np.r_[Ecol[ke], off + Erow[ke]]),
                  "Q": (Qi, Qj),
                  "U": (np.r_[Ui, Dcol[ue], n + np.arange(nu)], np.r_[Dcol[ue], Ui, n + np.arange(nu)])}
        kl = 0
        for i, j in groups.values():
            pi, pj = self.pos[i], self.pos[j]
            band = (pi >= 0) & (pj >= 0)
            kl = max(kl, int(np.abs(pi[band] - pj[band]).max(initial=0)))
        if kl > max_band:
            raise NotBanded(f"bandwidth {kl} after ordering by time node, more than {max_band}: some "
                            "rows couple distant instants")
        self.kl = kl
        self.ldab = 3 * kl + 1
        self.groups = {name: self._group(i, j) for name, (i, j) in groups.items()}

    def _group(self, i: np.ndarray, j: np.ndarray) -> _Group:
        pi, pj = self.pos[i], self.pos[j]
        bi, bj = self.bpos[i], self.bpos[j]
        band = np.flatnonzero((pi >= 0) & (pj >= 0))
        kl = self.kl
        # LAPACK's band storage: A[i, j] at ab[2 kl + i - j, j]; here row-major (nb, ldab)
        dest = pj[band] * self.ldab + (2 * kl + pi[band] - pj[band])
        B = np.flatnonzero((pi >= 0) & (bj >= 0))
        C = np.flatnonzero((bi >= 0) & (bj >= 0))
        return _Group(band, dest, B, pi[B], bj[B], C, bi[C] * self.border + bj[C])

    def same_pattern(self, D: sp.csr_matrix, E: sp.csr_matrix) -> bool:
        """Whether ``D`` and ``E`` have the shapes and entry counts this plan was made for."""
        return (D.shape == (self.m, self.n) and E.shape == (self.p, self.n)
                and D.nnz == self.nnz_D and E.nnz == self.nnz_E)

    def values(self, Dd: np.ndarray, Ed: np.ndarray) -> tuple[dict, np.ndarray]:
        """The value of every contribution for these entries of ``D`` and ``E`` (group name ->
        values), and the eliminated unknowns' diagonal ``h``."""
        ze, zs = self._h
        h = np.bincount(zs, weights=Dd[ze] ** 2, minlength=self.elim.size)
        a, b = self._H
        qa, qb, qz = self._Q
        ke, ue = self._E, self._U
        nu = int(np.count_nonzero(~self.fold))
        vals = {"H": Dd[a] * Dd[b], "E": np.r_[Ed[ke], Ed[ke]],
                "Q": -Ed[qa] * Ed[qb] / h[qz] if qa.size else np.zeros(0),
                "U": np.r_[Dd[ue], Dd[ue], -np.ones(nu)]}
        return vals, h


class BandedKKT(Factorization):
    """A banded-plus-border factorization of the augmented system (see the module Notes).

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
    :math:`-\\sigma_a^2 M^2`, pentadiagonal). One axis with point fixes then has the
    unknowns ``r_j, mu_j`` per node and bandwidth 4. The banded part is scaled
    symmetrically by the square roots of its column maxima before ``dgbtrf``.
    """

    method = "banded"
    shift = 0.0

    def __init__(self, D: sp.csr_matrix, E: sp.csr_matrix, colnode: np.ndarray | None = None,
                 params: np.ndarray | None = None, plan: BandPlan | None = None):
        D, E = canonical(D), canonical(E)
        if plan is None:
            plan = BandPlan.build(D, E, colnode)
        elif not plan.same_pattern(D, E):
            raise NotBanded("the sparsity pattern changed since the plan was made")
        self.plan = pl = plan
        self.S = AugmentedOperator(D, E)
        self.params = np.asarray(params if params is not None else [], dtype=int)
        self._unf = pl.unfolded
        self._Df = D[pl.fold] if self._unf.size else D
        el = pl.elim
        if el.size:
            self._Ez = E.tocsc()[:, el]
        vals, self._h = pl.values(D.data, E.data)
        nb, k, kl, ldab = pl.size, pl.border, pl.kl, pl.ldab
        self.k = k
        gs = [(pl.groups[name], v) for name, v in vals.items()]
        ab = np.bincount(np.concatenate([g.band_dest for g, _ in gs]),
                         weights=np.concatenate([v[g.band] for g, v in gs]),
                         minlength=nb * ldab).reshape(nb, ldab)
        # symmetric scaling by the square roots of the column maxima (row j of ab is column j)
        colmax = np.abs(ab).max(axis=1) if nb else np.zeros(0)
        sU = 1.0 / np.sqrt(np.where(colmax > 0, colmax, 1.0))
        pad = np.concatenate([np.zeros(2 * kl), sU, np.zeros(kl)])
        ab *= sU[:, None] * np.lib.stride_tricks.sliding_window_view(pad, ldab)[:nb]
        lu, piv, info = lapack.dgbtrf(ab.T, kl, kl, overwrite_ab=1)
        if info != 0:
            raise np.linalg.LinAlgError(f"the banded part is singular (zero pivot at {info})")
        self._lu, self._piv = lu, piv
        self._sU = sU
        if k:
            C = np.bincount(np.concatenate([g.C_dest for g, _ in gs]),
                            weights=np.concatenate([v[g.C] for g, v in gs]), minlength=k * k).reshape(k, k)
            dmax = np.abs(np.diag(C))
            sW = 1.0 / np.sqrt(np.where(dmax > 0, dmax, 1.0))
            Bi = np.concatenate([g.B_row for g, _ in gs])
            Bj = np.concatenate([g.B_col for g, _ in gs])
            Bv = np.concatenate([v[g.B] for g, v in gs]) * sU[Bi] * sW[Bj]
            self.B = sp.csc_matrix((Bv, (Bi, Bj)), shape=(nb, k))
            self._sW = sW
            self.X = self._band_solve(self.B.toarray())
            self.schur_border = C * sW[:, None] * sW[None, :] - self.B.T @ self.X
            if not np.all(np.isfinite(self.schur_border)) or np.linalg.cond(self.schur_border) > 1e15:
                raise np.linalg.LinAlgError("singular Schur complement of the border")

    # ------------------------------------------------------------------ solves
    def _band_solve(self, R: np.ndarray) -> np.ndarray:
        x, info = lapack.dgbtrs(self._lu, self.plan.kl, self.plan.kl, R, self._piv)
        if info != 0:  # pragma: no cover - argument error
            raise np.linalg.LinAlgError(f"dgbtrs failed (info {info})")
        return x

    def _reduced_solve(self, r: np.ndarray) -> np.ndarray:
        """Solve the reduced (unscaled, after eliminations) system for ``r`` (R,) or (R, c)."""
        pl = self.plan
        shape = r.shape
        r2 = r.reshape(shape[0], -1)
        y = self._band_solve(r2[pl.pos_order] * self._sU[:, None])
        out = np.zeros_like(r2)
        if self.k:
            rW = r2[pl.border_order] * self._sW[:, None]
            zW = np.linalg.solve(self.schur_border, rW - self.B.T @ y)
            y = y - self.X @ zW
            out[pl.border_order] = zW * self._sW[:, None]
        out[pl.pos_order] = y * self._sU[:, None]
        return out.reshape(shape)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``S z = rhs`` for one (T,) or several (T, c) right-hand sides."""
        rhs = np.asarray(rhs, dtype=float)
        pl = self.plan
        m, n, el = pl.m, pl.n, pl.elim
        nu = self._unf.size
        b1, bx, bmu = rhs[:m], rhs[m:m + n], rhs[m + n:]
        b1f = b1[pl.fold] if nu else b1
        r = np.concatenate([bx + self._Df.T @ b1f, b1[self._unf], bmu])
        if el.size:
            hcol = self._h.reshape((-1,) + (1,) * (r.ndim - 1))
            gz = r[el] / hcol
            r[n + nu:] -= self._Ez @ gz
        zr = self._reduced_solve(r)
        mu = zr[n + nu:]
        if el.size:
            zr[el] = gz - (self._Ez.T @ mu) / hcol
        x = zr[:n]
        z = np.empty_like(rhs)
        z[m:m + n] = x
        z[m + n:] = mu
        if nu:
            z[:m][pl.fold] = self._Df @ x - b1f
            z[:m][self._unf] = zr[n:n + nu]
        else:
            z[:m] = self._Df @ x - b1f
        return z

    # ---------------------------------------------------------- conditioning
    @property
    def keep(self):
        """Not None when there are error-model parameters (as :class:`bvpnav.lsq.BorderedLU`)."""
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
