"""A lambda sweep's band condensed onto the unknowns lambda changes.

On the speed benchmark's 1e5 samples with a position fix a second, lambda changes 12,016
of the band's 200,004 unknowns: :class:`CondensedBand` factors the others once for the
whole sweep and forms their Schur complement onto the kept ones, and each lambda factors
that small band (:class:`CondensedKKT`), instead of copying and factoring the whole band
(:class:`bvpnav.linalg.banded.AffineBand`) at every point.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack

from .banded import AffineBand, BandedKKT, BandPlan, NotBanded, scale_band

__all__ = ["CondensedBand", "CondensedKKT"]


def _band_of(rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, n: int, kl: int) -> np.ndarray:
    """Entries ``A[rows, cols] += vals`` of an (n, n) matrix of bandwidth ``kl`` in the
    LAPACK layout of :mod:`bvpnav.linalg.banded` (C order (n, 3 kl + 1), entry ``(j, kl + s)`` =
    ``A[j + s - kl, j]``)."""
    flat = cols * (3 * kl + 1) + (2 * kl + rows - cols)
    return np.bincount(flat, weights=vals, minlength=n * (3 * kl + 1)).reshape(n, 3 * kl + 1)


def _gbtrs(lu: np.ndarray, k: int, piv: np.ndarray, b: np.ndarray, overwrite: bool = False) -> np.ndarray:
    """``dgbtrs`` with ``k`` sub- and superdiagonals, its ``info`` checked (nonzero: an
    argument LAPACK refused)."""
    x, info = lapack.dgbtrs(lu, k, k, b, piv, overwrite_b=overwrite)
    if info != 0:  # pragma: no cover - argument error
        raise np.linalg.LinAlgError(f"dgbtrs failed (info {info})")
    return x


class CondensedBand:
    r"""A lambda sweep's band condensed onto the unknowns lambda changes: one banded
    factorization of the rest for the whole sweep, then a small one per lambda.

    Parameters
    ----------
    plan : BandPlan
    affine : AffineBand
        The band along lambda (one run, no border).
    plain : ndarray of bool (n + nu + p,)
        Which reduced unknowns are positions or FEM multipliers.
    max_share : float
        Refuse (:class:`NotBanded`) when the condensed unknowns exceed this share of the
        band (the small factorization would not be small).

    Raises
    ------
    NotBanded
        When the band has a border or several runs, or too many unknowns would be kept.
    numpy.linalg.LinAlgError
        When the interior is singular.

    Notes
    -----
    With the band at lambda = 1 scaled, :math:`M = A^{(1)}`, the band at lambda is
    :math:`A(\lambda) = \Delta (M + (\lambda - 1) \tilde A_1) \Delta`, where
    :math:`\tilde A_1` (the lambda-weighted rows' part, scaled like :math:`M`) and the
    change of scale :math:`\Delta` touch only the unknowns of the nodes those rows weigh.
    The kept set :math:`T` is every unknown of those nodes, of every node that holds
    anything but positions and FEM multipliers (``plain``: boundary velocities, hard rows'
    multipliers, accelerations a soft row reads), and of the whole nodes within
    :math:`k_l` band positions of them on each side: the other unknowns :math:`I` then
    fall into segments the band does not couple, each the FEM equations of its nodes
    alone with the neighbours fixed (a Dirichlet stiffness and its multipliers: as many
    as positions, nonsingular; the interior factor is refused if its pivots span more
    than 1e13 all the same). With :math:`K = M_{II}` factored once (``dgbtrf`` of the
    band with :math:`T`'s rows and columns made the identity),

    .. math:: S(\lambda) = M_{TT} - M_{TI} K^{-1} M_{IT} + (\lambda - 1)\tilde A_{1,TT},

    banded in :math:`T`'s order (equilibrated at each lambda before ``dgbtrf``), and
    :math:`M(\lambda)^{-1} b` is :math:`x_T = S^{-1}
    (b_T - M_{TI} K^{-1} b_I)`, :math:`x_I = K^{-1} (b_I - M_{IT} x_T)`. The columns of
    :math:`M_{IT}` at the same distance from the same side of their runs reach disjoint
    segments, so :math:`K^{-1} M_{IT}` is :math:`2 k_l` solves, not :math:`|T|`.

    Accuracy: this block elimination does not pivot across :math:`T` and :math:`I`, so a
    point may be less accurate than the whole band's unrefined factor at one lambda (21
    times on a soft zero-velocity interval's data residual at lambda = 1e4), though not
    over the sweep (tested: the worst over 1e-4 .. 1e4 within 10 times the whole band's).
    Only the rules read these points; the solve at the chosen lambda is the whole band's,
    refined and verified (on the speed benchmark at 1e6 the L-curve's lambda moved by
    2e-4 in log lambda, its tolerance being 1e-2).
    """

    def __init__(self, plan: BandPlan, affine: AffineBand, plain: np.ndarray, max_share: float = 0.25):
        if plan.border or affine.runs != 1 or affine.B is not None and affine.B.shape[1]:
            raise NotBanded("condensation needs one run and no border")
        ab0, kl = affine.scaled0, plan.kl
        nb = ab0.shape[0]
        node = np.asarray(plan.band_node)
        plain = np.asarray(plain, dtype=bool)[plan.pos_order]   # per band position
        # a node is kept with everything but positions and FEM multipliers (boundary
        # velocities, hard rows' multipliers, accelerations a soft row reads), and with
        # the unknowns the lambda rows weigh
        special = np.bincount(node, weights=~plain).astype(bool)
        special[node[affine.touched]] = True
        counts = np.bincount(node)
        if not np.any(~special & (counts > 0)):
            raise NotBanded("no node holds positions and FEM multipliers alone")
        # with each special node, the whole nodes within kl band positions of it on each side
        # (node is sorted along the band): runs of T at least 2 kl + 1 long, segments of
        # whole nodes between them
        last = np.cumsum(counts) - 1
        sp_nodes = np.flatnonzero(special & (counts > 0))
        lo = node[np.maximum(last[sp_nodes] - counts[sp_nodes] + 1 - kl, 0)]
        hi = node[np.minimum(last[sp_nodes] + kl, nb - 1)]
        mark = np.bincount(lo, minlength=counts.size + 1) - np.bincount(hi + 1, minlength=counts.size + 1)
        inT = (np.cumsum(mark)[:-1] > 0)[node]
        T = np.flatnonzero(inT)
        if not T.size or T.size > max_share * nb:
            raise NotBanded(f"{T.size} of {nb} unknowns would be kept")
        loc = np.full(nb, -1, dtype=np.int64)
        loc[T] = np.arange(T.size)
        cut = np.flatnonzero(np.diff(T) > 1)
        starts, ends = T[np.concatenate([[0], cut + 1])], T[np.concatenate([cut, [T.size - 1]])]
        inner = (starts > 0) & (ends < nb - 1)
        if np.any((ends - starts < 2 * kl) & inner):   # pragma: no cover - by construction
            raise NotBanded("a kept run shorter than 2 kl + 1")
        # K: the band with T's rows and columns the identity
        K = ab0.copy()
        K[T] = 0.0
        s = np.arange(2 * kl + 1)
        j = T[:, None] + kl - s[None, :]   # A[t, j] sits at (j, kl + s)
        ok = (j >= 0) & (j < nb)
        K[j[ok], np.broadcast_to(kl + s, j.shape)[ok]] = 0.0
        K[T, 2 * kl] = 1.0
        lu, piv, info = lapack.dgbtrf(K.T, kl, kl, overwrite_ab=1)
        pivots = np.abs(lu[2 * kl])
        if info != 0 or pivots.min() <= 1e-13 * pivots.max():   # a guard: never met by FEM segments
            raise np.linalg.LinAlgError(f"the condensed band's interior is singular or nearly "
                                        f"(pivots {pivots.min():.1e} .. {pivots.max():.1e})")
        self._K = K   # dgbtrf's storage (lu is its transposed view)
        self._lu, self._piv, self.kl, self.nb = lu, piv, kl, nb
        # M's entries in T's columns (M is symmetric: also its rows)
        r = T[:, None] + s[None, :] - kl
        v = ab0[T][:, kl:]
        ok = (r >= 0) & (r < nb) & (v != 0)
        c = np.broadcast_to(T[:, None], r.shape)[ok]
        r, v = r[ok], v[ok]
        out = ~inT[r]
        # by columns: a product with it visits T's few columns, not the band's rows
        self.M_IT = sp.csc_matrix((v[out], (r[out], loc[c[out]])), shape=(nb, T.size))
        self.M_TI = self.M_IT.T.tocsr()
        # K^-1 M_IT by groups of columns reaching disjoint segments (side and offset)
        cols = np.unique(c[out])
        q = np.searchsorted(starts, cols, side="right") - 1
        left = ((cols - starts[q] < kl) & (starts[q] > 0)) | (ends[q] == nb - 1)
        off = np.where(left, cols - starts[q], ends[q] - cols)
        group = np.where(left, 0, kl) + off
        seg = np.where(left, q, q + 1)   # segment q lies between runs q - 1 and q
        G = 2 * kl
        Mc = self.M_IT[:, loc[cols]].tocoo()
        P = np.empty((T.size, G))             # M_TI K^-1 M_IT by group: each T row reads one segment
        for side in (0, kl):   # kl groups at a time: an (nb, kl) array, not (nb, 2 kl)
            R = np.zeros((nb, kl), order="F")
            sel = (group[Mc.col] >= side) & (group[Mc.col] < side + kl)
            R[Mc.row[sel], group[Mc.col[sel]] - side] = Mc.data[sel]   # one column of a group per row
            R = _gbtrs(lu, kl, piv, R, overwrite=True)
            P[:, side:side + kl] = self.M_TI @ R
            del R
        owner = np.full((G, starts.size + 1), -1, dtype=np.int64)
        owner[group, seg] = loc[cols]
        rows_T = loc[cols]
        partner = owner[:, seg].T             # (len(cols), G): the column of each group there
        ok = partner >= 0
        tt = ~out
        Sr = np.concatenate([loc[r[tt]], np.broadcast_to(rows_T[:, None], partner.shape)[ok]])
        Sc = np.concatenate([loc[c[tt]], partner[ok]])
        Sv = np.concatenate([v[tt], -P[rows_T][ok]])
        # the lambda part, scaled like M, on the rows of affine.rows (all in T)
        s1 = affine.sU0
        ri = affine.rows[:, None] + s[None, :] - kl
        inside = (ri >= 0) & (ri < nb)
        v1 = affine.ab1[:, kl:] * s1[affine.rows][:, None] * s1[np.clip(ri, 0, nb - 1)]
        ok = inside & (v1 != 0)
        Ar, Ac = loc[ri[ok]], loc[np.broadcast_to(affine.rows[:, None], ri.shape)[ok]]
        self.kT = kT = int(max(np.max(np.abs(Sr - Sc)), np.max(np.abs(Ar - Ac), initial=0)))
        self._S1 = _band_of(Sr, Sc, Sv, T.size, kT)
        self._A1 = _band_of(Ar, Ac, v1[ok], T.size, kT)
        self.T, self.inT, self.plan, self.affine = T, inT, plan, affine
        self._interior_rhs = None   # (b_I, K^-1 b_I) of the last right-hand side

    def logdet_slope(self, lam: float, h: float) -> float:
        r""":math:`d\log|\det \hat A(\lambda)| / d\lambda` of the unscaled band, by a
        complex step ``h`` on the small system alone.

        Notes
        -----
        :math:`\hat A(\lambda) = \mathrm{diag}(s_1)^{-1} M(\lambda)\,\mathrm{diag}(s_1)^{-1}`
        with the fixed scales :math:`s_1`, and :math:`\det M = \det K \det S(\lambda)` with
        :math:`K` fixed, so the derivative is that of :math:`\log|\det S|`: the pivots of
        :math:`S(\lambda + ih) = S(\lambda) + ih\tilde A_{1,TT}` (``zgbtrf``) give
        :math:`\sum_j \operatorname{Im} U_{jj} / \operatorname{Re} U_{jj} / h`, exact to
        rounding as in :meth:`bvpnav.linalg.banded.BandedKKT.logdet_step`.
        """
        ab = self._S1 + complex(lam - 1.0, h) * self._A1
        lu, _, info = lapack.zgbtrf(ab.T, self.kT, self.kT, overwrite_ab=1)
        if info != 0:
            raise np.linalg.LinAlgError(f"the condensed system is singular at lambda={lam:g} (pivot {info})")
        u = lu[2 * self.kT]
        return float(np.sum(u.imag / u.real)) / h

    def buffer(self) -> np.ndarray:
        """The band-sized array of the interior's factor, dead once the sweep is done (for
        :class:`bvpnav.linalg.banded.KeptFactors`)."""
        return self._K

    def at(self, lam: float) -> tuple:
        """``(factor of S(lam), piv, Delta, sU, e)`` at ``lam`` (see the Notes; ``e`` the
        small band's own scale at ``lam``)."""
        ab = self._S1 + (lam - 1.0) * self._A1
        e = scale_band(ab, self.kT)   # equilibrated at lam, as the whole band is
        lu, piv, info = lapack.dgbtrf(ab.T, self.kT, self.kT, overwrite_ab=1)
        if info != 0:
            raise np.linalg.LinAlgError(f"the condensed system is singular at lambda={lam:g} (pivot {info})")
        sU = self.affine.scales_at(lam)
        return lu, piv, sU / self.affine.sU0, sU, e

    def solve(self, small: tuple, R: np.ndarray, interior: bool = True) -> np.ndarray:
        """``A(lam)^{-1} R`` for ``R`` (nb,) in the scaled band's order, ``small`` from
        :meth:`at`; the unknowns outside ``T`` are NaN without ``interior``."""
        lu, piv, d, _, e = small
        b = R / d
        bI = b.copy()
        bI[self.T] = 0.0
        kl, T = self.kl, self.T
        g = b[T]
        if bI.any():
            last = self._interior_rhs
            if last is not None and np.array_equal(last[0], bI):
                u = last[1]   # a sweep's points share the right-hand side off T
            else:
                u = _gbtrs(self._lu, kl, self._piv, bI)
                self._interior_rhs = (bI, u)
            g = g - self.M_TI @ u
        xT = _gbtrs(lu, self.kT, piv, g * e)
        xT *= e
        if interior:
            rhs = bI - self.M_IT @ xT   # (bI may be the cached interior right-hand side)
            rhs[T] = 0.0
            x = _gbtrs(self._lu, kl, self._piv, rhs, overwrite=True)   # 0 on T
        else:
            x = np.full(self.nb, np.nan)
        x[T] = xT
        x /= d
        return x


class CondensedKKT(BandedKKT):
    r""":class:`BandedKKT` at one lambda of a :class:`CondensedBand`: its band solves are
    the condensed ones (a small factorization per lambda), the rest (folding, eliminated
    accelerations, gathers, scales) as in :class:`BandedKKT`. Real, one run, no border;
    no log-determinant. :meth:`solve_x_real` with ``interior=False`` leaves the unknowns
    outside the condensed set NaN (a sweep's :math:`dx/d\lambda`, read on the lambda rows
    alone)."""

    def __init__(self, D: sp.csr_matrix, E: sp.csr_matrix, condensed: CondensedBand, lam: float,
                 params: np.ndarray | None = None):
        self.plan = condensed.plan
        self._bind(D, E)
        self.params = np.asarray(params if params is not None else [], dtype=int)
        self._h = condensed.affine.h
        self.k, self._runs = 0, 1
        self._condensed, self._lam = condensed, float(lam)
        self._small = condensed.at(lam)
        self._sU = self._small[3]
        self._lu = np.zeros((0, 0))   # the dtype of the solves (real)
        self._interior = True

    def _trs(self, R: np.ndarray, overwrite: bool = False) -> np.ndarray:
        if R.ndim == 1:
            return self._condensed.solve(self._small, R, self._interior)
        return np.column_stack([self._condensed.solve(self._small, R[:, i], self._interior)
                                for i in range(R.shape[1])])

    def solve_x_real(self, rhs: np.ndarray, eliminated: bool = True, interior: bool = True) -> np.ndarray:
        self._interior = interior
        try:
            return super().solve_x_real(rhs, eliminated)
        finally:
            self._interior = True

    def logdet(self) -> float:
        raise NotImplementedError("a condensed factor has no log-determinant (see logdet_slope)")

    def logdet_slope(self, h: float) -> float:
        """:meth:`CondensedBand.logdet_slope` at this factor's lambda."""
        return self._condensed.logdet_slope(self._lam, h)
