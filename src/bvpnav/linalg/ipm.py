r"""Bands and inequalities for the direct back end: a primal-dual interior-point method whose
every Newton step is one banded factorization.

A problem whose items are hard or soft equalities, bands (``|r| <= tol``) and hard or
band inequalities (``g <= 0``, ``g <= tol``) is the convex quadratic program (soft
inequalities and bands with soft edges: "Penalty rows" below)

.. math::

    \min_x \|A x + c\|^2 \quad \text{s.t.} \quad E x + e = 0, \quad G x + g \le 0,

``A`` the weighted objective rows and ``E`` the equality rows of
:func:`bvpnav.linalg.lsq.least_squares_form`, ``G`` the inequality rows (a band is two:
:math:`r - tol \le 0` and :math:`-r - tol \le 0`), each scaled to a largest coefficient
of 1. With slacks :math:`s = -(G x + g) \ge 0`, multipliers :math:`y` (cvxpy's
convention: Lagrangian :math:`f + y^T (E x + e) + z^T (G x + g)`) and :math:`z \ge 0`,
Mehrotra's predictor-corrector method takes Newton steps on

.. math::

    r_d = 2 A^T (A x + c) + E^T y + G^T z = 0, \quad r_e = E x + e = 0, \quad
    r_g = G x + g + s = 0, \quad s \circ z = \sigma \mu.

Eliminating :math:`ds` leaves the least-squares augmented system of
:mod:`bvpnav.linalg.banded` with the inequality rows as equality rows below ``E`` whose
multipliers :math:`\nu = dz/2` carry the diagonal :math:`-\Delta`,
:math:`\Delta_i = 2 s_i / z_i` (:class:`_Newton`): rows local in time sit in the band like
hard point rows, and a band's two sides share one multiplier. The plan (ordering,
bandwidth, border) is made once; each step changes only that diagonal and the scaling of
those rows (:class:`MultiplierBand`), then ``dgbtrf`` factors the band. Steps are refined
against the full linearized system.

**Penalty rows.** A soft inequality (:math:`\lambda \max(g_i, 0)^2/\sigma_i^2`) and a band with
soft edges (its two sides, :math:`\pm r - tol`) are rows of the same system: with
:math:`\max(g, 0)^2 = \min_{t \ge g} t^2` the row becomes :math:`G_i x + g_i - t_i \le 0` with
:math:`p_i t_i^2` in the objective (:math:`p_i = \lambda/\sigma_i^2` in the scaled row's units),
and the slack's stationarity gives :math:`t_i = z_i/(2 p_i)`. Eliminated, :math:`t_i` adds the
constant :math:`1/p_i` (:attr:`QuadraticForm.soft`) to the multiplier's diagonal,
:math:`\Delta_i = 2 s_i/z_i + 1/p_i`, and :math:`-z_i/(2 p_i)` to the row's residual; a hard
row has 0. The answer is the penalty's optimum, with :math:`z_i = 2 p_i \max(g_i, 0)`.

The direct back end tries :mod:`bvpnav.linalg.active_set` first (the same factorizations
with the diagonal 0 or huge) and comes here where it gives way (:func:`interior_point`
then reuses its plan). The first factorization leaves the inequality rows out (their
diagonal huge): the least-squares answer. When it already satisfies them it is the
optimum, with :math:`z = 0`, and the method stops there.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import SolveError
from ..formulation import Formulation
from ..model import Affine
from ..sparse import abs_max, canonical
from .banded import BandedKKT, BandPlan, NotBanded, _scales, _Stride
from .lsq import BorderedLU, LeastSquaresForm, column_nodes, fem_rows_by_diagonals, least_squares_form
from .workspace import Workspace

__all__ = ["QuadraticForm", "quadratic_form", "unsupported_term", "MultiplierBand", "solve_qp",
           "interior_point", "IPM_TOL"]

#: Relative tolerance of the interior-point method's residuals and gap per accuracy preset.
IPM_TOL = {"low": 1e-7, "default": 1e-9, "high": 1e-10}

#: The multipliers' diagonal of decoupled inequality rows (the first solve: without them).
_DECOUPLED = 1e30

#: The starting complementarity per row, in units of the least-squares objective per row:
#: large, since an under-estimate stalls Mehrotra's steps (the multipliers must grow by
#: orders of magnitude at a centering pace) while an over-estimate costs a few steps.
MU0 = 1e6


def unsupported_term(form: Formulation):
    """The first term the interior-point path cannot take (robust penalties, cones), or None."""
    for term in form.terms():
        if term.least_squares_role() is not None:
            continue
        if term.kind == "inequality" and term.mode in ("hard", "band", "soft"):
            continue   # soft: a row whose slack carries the penalty (QuadraticForm.soft)
        if term.kind == "equality" and term.mode == "band":
            continue
        return term
    return None


@dataclass(eq=False)
class QuadraticForm:
    r"""``min ||A x + c||^2 s.t. E x + e = 0, G x + g <= 0`` with row bookkeeping.

    Attributes
    ----------
    ls : LeastSquaresForm
        The objective and equality rows (:func:`bvpnav.linalg.lsq.least_squares_form`'s).
    G : Affine
        The inequality rows ``G x + g``, each scaled to a largest coefficient of 1.
    scale : ndarray
        The factor each row of ``G`` was divided by (its item's units per unit of ``G``).
    base : scipy.sparse.csr_matrix
        The distinct rows of ``G`` up to sign (a band's two sides are one row).
    base_of : ndarray of int
        The row of :attr:`base` each row of ``G`` is (``G_i = sign_i base_{base_of[i]}``).
    sign : ndarray
        +1 or -1 per row of ``G``.
    ineq_blocks : list of (label, list of slice)
        For each band or inequality term, its rows of ``G``: one slice (``r - tol``, or
        ``g - tol``) or two (a band's upper ``r - tol`` and lower ``-r - tol`` sides).
    before, after : ndarray of int
        Per row of ``G``, the row of the same term, side and axis at the item's previous
        and next instant (:meth:`bvpnav.items.Item.row_layout`: rows time-major), -1 at
        the ends; every row its own instant when the term has no item.
    soft : ndarray
        Per row of :attr:`base`, :math:`1/p_k` for the rows of a soft inequality or a band
        with soft edges (penalty :math:`p_k \max(G_k x + g_k, 0)^2` in the scaled row's
        units), 0 for the rows that hold hard (see the module Notes).
    """

    ls: LeastSquaresForm
    G: Affine
    scale: np.ndarray
    base: sp.csr_matrix
    base_of: np.ndarray
    sign: np.ndarray
    ineq_blocks: list
    before: np.ndarray
    after: np.ndarray
    soft: np.ndarray

    @property
    def soft_rows(self) -> np.ndarray:
        """:attr:`soft` per row of :attr:`G`."""
        return self.soft[self.base_of]

    def base_weights(self, w: np.ndarray) -> np.ndarray:
        r"""``w`` (one value per row of ``G``) summed onto :attr:`base`'s rows
        (:math:`\sum_{i \to k} w_i`: a band's two sides onto their one row)."""
        return np.bincount(self.base_of, weights=w, minlength=self.base.shape[0])


def quadratic_form(form: Formulation, lam: float) -> QuadraticForm:
    """The problem as a quadratic program (see the module Notes).

    Raises
    ------
    ValueError
        When a term is a robust penalty or a cone (:func:`unsupported_term`).
    """
    bad = unsupported_term(form)
    if bad is not None:
        raise ValueError(f"item {bad.label!r} (kind {bad.kind!r}, mode {bad.mode!r}) is not a "
                         "quadratic-program row")
    ls = least_squares_form(form, lam, surrogate=True)
    bases, consts, signs, of, blocks, strides, softs = [], [], [], [], [], [], []
    start = nbase = 0
    for term in form.terms():
        if term.least_squares_role() is not None:
            continue
        if term.is_penalty and term.weight(lam) == 0:
            continue   # a penalty at lam = 0 is not in the problem (its 1 / p would be infinite)
        res = term.residual
        item = getattr(term, "item", None)
        axes = item.row_layout(res.m)[1] if item is not None else 1
        A = canonical(res.A)
        bases.append(A)
        tol = np.zeros(res.m) if term.tol is None else np.broadcast_to(term.tol, (res.m,))
        # a penalty row's 1 / p_i, p_i its weight lam / sigma_i^2 (scaled below with its row)
        softs.append(np.broadcast_to(term.sigma, (res.m,)) ** 2 / term.weight(lam) if term.is_penalty
                     else np.zeros(res.m))
        pieces = []
        for sign in ([1.0] if term.kind == "inequality" else [1.0, -1.0]):
            consts.append(sign * res.c - tol)
            signs.append(np.full(res.m, sign))
            of.append(nbase + np.arange(res.m))
            pieces.append(slice(start, start + res.m))
            strides.append((start, res.m, axes))
            start += res.m
        nbase += res.m
        blocks.append((term.label, pieces))
    n = form.model.size
    B = canonical(sp.vstack(bases, format="csr")) if bases else sp.csr_matrix((0, n))
    big = abs(B).max(axis=1).toarray().ravel() if B.shape[0] else np.zeros(0)
    big[~(big > 0)] = 1.0
    B = sp.csr_matrix((B.data / np.repeat(big, np.diff(B.indptr)), B.indices, B.indptr), shape=B.shape)
    base_of = np.concatenate(of) if of else np.zeros(0, dtype=np.int64)
    sign = np.concatenate(signs) if signs else np.zeros(0)
    G = B[base_of]
    G = sp.csr_matrix((G.data * np.repeat(sign, np.diff(G.indptr)), G.indices, G.indptr), shape=G.shape)
    scale = big[base_of]
    c = np.concatenate(consts) / scale if consts else np.zeros(0)
    before, after = np.full(start, -1, dtype=np.int64), np.full(start, -1, dtype=np.int64)
    for first, m, axes in strides:
        i = np.arange(first, first + m)
        before[i[axes:]], after[i[:-axes]] = i[:-axes], i[axes:]
    soft = np.concatenate(softs) / big**2 if softs else np.zeros(0)
    return QuadraticForm(ls, Affine(G, c), scale, B, base_of, sign, blocks, before, after, soft)


class MultiplierBand:
    r"""The reduced banded system of the Newton steps from one plan: the inequality rows
    (:attr:`QuadraticForm.base`) are equality rows below ``E`` whose multipliers carry a
    diagonal :math:`-\Delta` that changes at every step.

    Parameters
    ----------
    plan : BandPlan
        Made for the objective rows ``A`` and the equality rows ``[E; base]``.
    first : tuple
        The plan's first assembly ``(ab, B, C, h, sU)`` (the band scaled by ``sU``).
    rows : ndarray of int
        The reduced unknowns of the ``base`` rows' multipliers.
    buffer : ndarray, optional
        Memory of at least the band's size for the band of each step (and its factor); None:
        fresh memory.

    Notes
    -----
    Only the multipliers' diagonal depends on :math:`\Delta`. The symmetric scaling of
    :func:`bvpnav.linalg.banded.scale_band` is kept from :math:`\Delta = 0` (each
    multiplier's scale from its largest entry then, the diagonal :math:`d_k` or the largest
    off it): each step copies that scaled band and writes the diagonal
    :math:`(d_k - \Delta_k) s_k^2`, one copy and a scatter of one value per row. A
    :math:`\Delta_k` large against the row's entries makes the row diagonally dominant
    (the LU pivots on it), a small one leaves a hard row; rescaling those rows at every step
    (what a fresh :func:`~bvpnav.linalg.banded.scale_band` would do) changed neither the steps
    nor the answers on the tests' problems and cost a pass over the band per step. A
    multiplier in the border (a row reaching far) has its diagonal in the border block.
    """

    def __init__(self, plan: BandPlan, first: tuple, rows: np.ndarray, buffer: np.ndarray | None = None):
        self.plan = plan
        ab, B, C, h, sU = first
        kl = plan.kl
        pos, bpos = plan.pos[rows].astype(np.int64), plan.bpos[rows].astype(np.int64)
        self.in_band = pos >= 0
        k = pos[self.in_band]
        self.k = k
        # back to unscaled values for the multipliers' own diagonal and off-diagonal maxima
        raw = ab[k] / (sU[k][:, None] * _window(sU, k, kl))
        self.d0 = raw[:, 2 * kl].copy()
        raw[:, 2 * kl] = 0.0
        off = np.max(np.abs(raw[:, kl:]), axis=1)
        # the band at Delta = 0 with the multipliers' scales from their entries at Delta = 0
        s0 = sU.copy()
        s0[k] = _scales(np.maximum(np.abs(self.d0), off))
        _rescale(ab, k, s0[k] / sU[k], kl)
        self.scaled0, self.s0, self.sk2 = ab, s0, s0[k] ** 2
        self.B, self.C0, self.h = B, C, h
        self.border_at = bpos[~self.in_band]
        self._buffer = (np.empty_like(ab) if buffer is None
                        else buffer.reshape(-1)[:ab.size].reshape(ab.shape))

    def parts(self, delta: np.ndarray) -> tuple:
        """``(ab, B, C, h, sU)`` at ``delta`` (one per ``base`` row), the band written into one
        buffer reused by every call (the factor of an earlier call is dead once this one is
        made)."""
        ab = self._buffer
        np.copyto(ab, self.scaled0)
        ab[self.k, 2 * self.plan.kl] = (self.d0 - delta[self.in_band]) * self.sk2
        C = self.C0
        if self.border_at.size:
            C = C.copy()
            C[self.border_at, self.border_at] -= delta[~self.in_band]
        return ab, self.B, C, self.h, self.s0


def _rescale(ab: np.ndarray, k: np.ndarray, ratio: np.ndarray, kl: int) -> None:
    """:func:`~bvpnav.linalg.banded._scale_rows` with the factor ``ratio`` on the band rows
    ``k`` (distinct) and 1 elsewhere, in place: only the entries in those rows and columns
    are touched (the multipliers' rows, a few per sample against the whole band)."""
    if not k.size:
        return
    nb = ab.shape[0]
    full = np.ones(nb)
    full[k] = ratio
    # columns k of the matrix (rows k of ab): entry ab[k, kl + s] is A[k + s - kl, k]
    pad = np.concatenate([np.zeros(kl), full, np.zeros(kl)])   # (0 outside the matrix, as there)
    ab[k, kl:] *= ratio[:, None] * pad[k[:, None] + np.arange(2 * kl + 1)[None, :]]
    # rows k of the matrix in the other columns j = k + t: ab[k + t, 2 kl - t]
    t = np.arange(-kl, kl + 1)
    J = k[:, None] + t[None, :]
    mine = np.zeros(nb, dtype=bool)
    mine[k] = True
    ok = (J >= 0) & (J < nb)
    ok[ok] = ~mine[J[ok]]
    rows, cols = np.nonzero(ok)
    ab[J[rows, cols], 2 * kl - t[cols]] *= ratio[rows]


def _window(sU: np.ndarray, k: np.ndarray, kl: int) -> np.ndarray:
    """``sU`` of the rows ``k + s - 2 kl`` met by band row ``k``'s entries ``ab[k, s]``
    (1 outside the band)."""
    pad = np.concatenate([np.ones(2 * kl), sU, np.ones(kl)])
    return pad[k[:, None] + np.arange(3 * kl + 1)[None, :]]


class _Steps:
    r"""Factorizations of the Newton system for a diagonal :math:`\Delta` of the inequality
    rows' multipliers: the banded one of a :class:`MultiplierBand` when the rows allow,
    else a pivoted sparse LU of the augmented matrix per step."""

    def __init__(self, qp: QuadraticForm, form: Formulation, workspace: Workspace | None, banded: bool,
                 reuse: tuple | None = None):
        self.qp, self.form = qp, form
        ls = qp.ls
        self.A = ls.D.A
        self.E = canonical(sp.vstack([ls.E.A, qp.base], format="csr"))
        self.m, self.n = self.A.shape
        self.pE = ls.E.m
        self.band: MultiplierBand | None = None
        self.notes: list[str] = []
        #: ``(pattern, plan, colnode)`` of the banded plan, for a later solve of the same pattern
        #: (:meth:`_plan`'s ``reuse``); None when not banded
        self.plan_key: tuple | None = None
        if banded:
            try:
                self.band = self._multiplier_band(workspace, reuse)
            except (NotBanded, ValueError, np.linalg.LinAlgError) as exc:
                self.notes.append(f"not banded: {exc}")

    def _multiplier_band(self, workspace, reuse: tuple | None) -> MultiplierBand:
        diagonal = fem_rows_by_diagonals(self.form, workspace)
        plan, first = self._plan(diagonal, reuse, workspace)
        rows = self.n + plan.unfolded.size + self.pE + np.arange(self.qp.base.shape[0])
        return MultiplierBand(plan, first, rows, _loop_buffers(workspace, plan)[1])

    def _plan(self, diagonal, reuse: tuple | None, workspace: Workspace | None = None
              ) -> tuple[BandPlan, tuple]:
        """The plan and its assembly at these values: ``reuse``'s plan (an earlier solve's
        :attr:`plan_key`) when the pattern is its own, or one it admits (node states: a
        Gauss-Newton step's objective rows filling exact zeros, :meth:`BandPlan.admitting`),
        else a new analysis."""
        ls, model = self.qp.ls, self.form.model
        lam_rows = np.asarray(ls.lam_rows, dtype=bool)
        colnode = column_nodes(model)
        pattern = (self.A.indptr, self.A.indices, self.E.indptr, self.E.indices, lam_rows, colnode)
        if reuse is not None:
            old, plan, cols = reuse
            band_out = _loop_buffers(workspace, plan)[0]
            same = [a is b or np.array_equal(a, b) for a, b in zip(old, pattern, strict=True)]
            if all(same):
                self.plan_key = (pattern, plan, cols)
                return plan, plan.assemble(self.A, self.E, diagonal, out=band_out)
            if all(same[4:]):
                fitted = _refit(plan, self.A, self.E, cols, lam_rows, diagonal, band_out)
                if fitted is not None:
                    self.plan_key = (pattern, fitted[0], cols)
                    return fitted
        cols = colnode
        try:
            if model.ns:   # node states couple the axes at every node: interleaved from the start
                raise NotBanded("node states")
            plan = BandPlan.build(self.A, self.E, cols, lam_rows=ls.lam_rows, diagonal=diagonal)
        except NotBanded:
            if model.d == 1 and not model.ns:
                raise
            cols = column_nodes(model, interleave=True)
            plan = BandPlan.build(self.A, self.E, cols, lam_rows=ls.lam_rows, diagonal=diagonal)
        first, plan._first = plan._first[2], None
        self.plan_key = (pattern, plan, cols)
        return plan, first

    def describe(self) -> str:
        return self.band.plan.describe() if self.band is not None else "lu"

    def factor(self, delta: np.ndarray):
        """The factorization of the augmented matrix with ``-delta`` on the ``base`` rows'
        multipliers."""
        if self.band is not None:
            fac = BandedKKT.numeric(self.band.plan, self.band.parts(delta))
            fac.params = self.form.model.l_index
            fac._bind(self.A, self.E)
            return fac
        m, n = self.m, self.n
        reg = np.concatenate([np.zeros(self.pE), delta])
        S = sp.bmat([[-sp.identity(m), self.A, None], [self.A.T, None, self.E.T],
                     [None, self.E, -sp.diags(reg)]], format="csc")
        return BorderedLU(S, m + self.form.model.l_index, np.arange(m + n, m + n + self.pE))


def _refit(plan: BandPlan, D: sp.csr_matrix, E: sp.csr_matrix, colnode: np.ndarray, lam_rows: np.ndarray,
           diagonal, out: np.ndarray | None = None) -> tuple[BandPlan, tuple] | None:
    """``plan`` for rows ``D``, ``E`` of another pattern with its assembly, or None when it
    does not serve them.

    An outer loop's next linearization has the same unknowns and rows, but entries that
    were exact zeros may fill and others vanish (a velocity of exactly 0 at a standstill in
    a body-frame row). The plan serves them when ``D``'s rows fold and eliminate as in the
    plan (:meth:`BandPlan.admitting`) and every entry of the assembly lands within its
    bandwidth (what :meth:`BandPlan.build` measured to choose it); plans that split the band
    into runs (``segments``) are not refitted.
    """
    if getattr(plan, "segments", 1) != 1:
        return None
    base = copy.copy(plan)
    base.nnz_E = E.nnz
    fitted = base.admitting(D, E, colnode, lam_rows)
    if fitted is None:
        return None
    entries = fitted._entries(D, E, diagonal)
    for e in entries[0]:
        if isinstance(e, _Stride):
            off = abs(e.off)
        elif e[0].size:
            off = int(np.max(np.abs(e[0].astype(np.int64) - e[1])))
        else:
            continue
        if off > fitted.kl:
            return None
    return fitted, fitted._scatter(entries, scaled=True, out=out)


def _loop_buffers(workspace: Workspace | None, plan: BandPlan) -> tuple:
    """Memory for the assembled band and for each step's copy of it (its factor), from the
    :attr:`~bvpnav.linalg.workspace.Workspace.band_buffer` of a loop whose every factor is
    dead before its next solve assembles (the node-state loop): halves of one buffer of twice
    the band, which the loop's solves then reuse instead of faulting in fresh pages for each
    (about 0.2 s of CPU per 300 MB band); ``(None, None)`` without one."""
    buf = getattr(workspace, "band_buffer", None)
    if buf is None:
        return None, None
    need = plan.pos_order.size * plan.ldab
    if buf.size // 2 < need:
        buf = workspace.band_buffer = np.empty(2 * need)
    half = buf.size // 2   # fixed halves: a band of another plan in the first never meets the second
    return buf[:half], buf[half:2 * half]


class _Newton:
    r"""Newton steps of the interior-point method: one factorization of the augmented system
    with the inequality rows' multipliers, then refinement against the full linearized
    system.

    Notes
    -----
    The full system, for right-hand sides :math:`b_1 .. b_4`:

    .. math::

        2 A^T A\, dx + E^T dy + G^T dz = b_1, \quad E\, dx = b_2, \quad
        G\, dx + ds = b_3, \quad z \circ ds + s \circ dz = b_4.

    Eliminating :math:`ds = (b_4 - s\, dz)/z` leaves :math:`G_i dx - \Delta_i \nu_i = b_{3i}
    - b_{4i}/z_i` with :math:`\nu = dz/2`, :math:`\Delta_i = 2 s_i / z_i` (plus a penalty row's
    :math:`1/p_i`, whose third equation is :math:`G_i dx + ds_i - dz_i/(2 p_i) = b_{3i}`). A band's two sides
    ``+B_k`` and ``-B_k`` share one multiplier :math:`\nu_k = \nu_+ - \nu_-` with
    :math:`\Delta_k = (1/\Delta_+ + 1/\Delta_-)^{-1}`; each side's multiplier follows from
    :math:`\nu_k` and the two rows' sum, in which :math:`dx` cancels (no product of a
    large :math:`1/\Delta` with the error of :math:`dx`).
    """

    def __init__(self, qp: QuadraticForm, steps: _Steps):
        self.qp, self.steps = qp, steps
        self.A, self.E, self.G = qp.ls.D.A, qp.ls.E.A, qp.G.A
        self.At, self.Et, self.Gt = self.A.T.tocsr(), self.E.T.tocsr(), self.G.T.tocsr()
        self.n, self.m = self.A.shape[1], self.A.shape[0]
        self.pE = self.E.shape[0]
        self.absE, self.absG = abs(self.E), abs(self.G)
        # each row of G and the other side of its band (-1: none)
        of = qp.base_of
        first = np.full(qp.base.shape[0], -1, dtype=np.int64)
        order = np.arange(of.size)
        partner = np.full(of.size, -1, dtype=np.int64)
        first[of[::-1]] = order[::-1]
        second = np.full(qp.base.shape[0], -1, dtype=np.int64)
        later = order != first[of]
        second[of[later]] = order[later]
        has = second[of] >= 0
        partner[has] = np.where(first[of[has]] == order[has], second[of[has]], first[of[has]])
        self.two = np.flatnonzero(partner >= 0)          # rows with another side, and that side
        self.other = partner[self.two]
        self.two_sign = qp.sign[self.two]
        self.two_base = qp.base_of[self.two]
        self.soft = qp.soft_rows
        self.fac = None

    def factor(self, s: np.ndarray, z: np.ndarray) -> None:
        self.s, self.z = s, z
        self.delta = 2.0 * s / z + self.soft
        self.fac = self.steps.factor(self._base_delta(self.delta))

    def _base_delta(self, delta: np.ndarray) -> np.ndarray:
        inv = self.qp.base_weights(1.0 / delta)
        return 1.0 / inv

    def _condensed(self, b1, b2, b3, b4):
        qp, s, z, dl, n, m = self.qp, self.s, self.z, self.delta, self.n, self.m
        rhs = b3 - b4 / z
        dk = self._base_delta(dl)
        rk = dk * qp.base_weights(qp.sign * rhs / dl)
        sol = self.fac.solve(np.concatenate([np.zeros(m), 0.5 * b1, b2, rk]))
        dx, dy, nu_k = sol[m:m + n], 2.0 * sol[m + n:m + n + self.pE], sol[m + n + self.pE:]
        nu = qp.sign * nu_k[qp.base_of]          # one side alone: its multiplier is the row's
        if self.two.size:
            i, j = self.two, self.other
            # sum of the two rows (their G parts cancel): dl_i nu_i + dl_j nu_j = -(rhs_i + rhs_j),
            # and nu_i - nu_j = sign_i nu_k
            nu[i] = (dl[j] * self.two_sign * nu_k[self.two_base] - (rhs[i] + rhs[j])) / (dl[i] + dl[j])
        dz = 2.0 * nu
        ds = (b4 - s * dz) / z
        return [dx, dy, dz, ds]

    def solve(self, b1, b2, b3, b4, refine: int = 2, rtol: float = 1e-13):
        """``(dx, dy, dz, ds)``, refined while the full system's residual is above ``rtol``
        relative to its terms (at most ``refine`` steps)."""
        d = self._condensed(b1, b2, b3, b4)
        for _ in range(refine):
            dx, dy, dz, ds = d
            g1 = 2.0 * (self.At @ (self.A @ dx))
            e1, f1 = self.Et @ dy, self.Gt @ dz
            R1 = b1 - g1 - e1 - f1
            R2 = b2 - self.E @ dx
            Gdx = self.G @ dx
            R3 = b3 - Gdx - ds + 0.5 * self.soft * dz
            R4 = b4 - self.z * ds - self.s * dz
            big = max(abs_max(R1) / max(abs_max(b1), abs_max(g1), abs_max(e1), abs_max(f1), 1e-300),
                      abs_max(R3) / max(abs_max(b3), abs_max(Gdx), abs_max(ds), 1e-300))
            if big <= rtol:
                break
            c = self._condensed(R1, R2, R3, R4)
            d = [a + b for a, b in zip(d, c, strict=True)]
        return d


@dataclass
class _Point:
    """An iterate and its residuals."""

    x: np.ndarray
    y: np.ndarray
    s: np.ndarray
    z: np.ndarray
    measures: tuple = ()

    @property
    def worst(self) -> float:
        return max(self.measures) if self.measures else np.inf


def _start(newton: _Newton, qp: QuadraticForm):
    """The least-squares answer without the inequality rows (their multipliers' diagonal
    huge: the rows decoupled), or, when that is singular (the inequality rows determine
    some unknown), with each inequality row as an objective row ``G_i x + g_i`` of weight 1
    (rows scaled to a largest coefficient of 1). Returns ``(x, y, weighted)``."""
    ls, mi, nb = qp.ls, qp.G.m, qp.base.shape[0]
    m, n, pE = newton.m, newton.n, newton.pE
    for delta in (_DECOUPLED, 2.0):
        try:
            newton.fac = newton.steps.factor(np.full(nb, delta))
            break
        except np.linalg.LinAlgError:
            if delta != _DECOUPLED:
                raise
    # G_i x + g_i = delta nu_i for every side: its base row holds B_k x - delta_k nu_k = r_k with
    # the sides' harmonic delta and r_k = delta_k sum_i sign_i (-g_i) / delta (as _condensed)
    dk = 1.0 / qp.base_weights(np.full(mi, 1.0 / delta))
    rk = dk * qp.base_weights(-qp.sign * qp.G.c / delta)
    z0 = newton.fac.solve(np.concatenate([-ls.D.c, np.zeros(n), -ls.E.c, rk]))
    return z0[m:m + n], 2.0 * z0[m + n:m + n + pE], delta != _DECOUPLED


def _measures(qp: QuadraticForm, pt: _Point, newton: _Newton, fscale: float):
    """``(equality, inequality violation, stationarity, gap)`` relative measures and the
    residuals ``(r_d, r_e, r_g)``."""
    A, E, G = qp.ls.D, qp.ls.E, qp.G
    res = A.value(pt.x)
    grad = 2.0 * (newton.At @ res)
    Ey, Gz = newton.Et @ pt.y, newton.Gt @ pt.z
    rd = grad + Ey + Gz
    re = E.value(pt.x)
    gx = G.value(pt.x) - 0.5 * newton.soft * pt.z    # a soft row's excess t = z / (2 p) moves its bound
    rg = gx + pt.s
    f = _dot(res, res)
    dscale = max(abs_max(grad), abs_max(Ey), abs_max(Gz), 1e-300)
    ax = np.abs(pt.x)
    escale = max(abs_max(newton.absE @ ax) + abs_max(E.c), 1e-300)
    gscale = max(abs_max(newton.absG @ ax) + abs_max(G.c), 1e-300)
    gap = _dot(pt.s, pt.z) / max(f, fscale, 1e-300)
    pt.measures = (abs_max(re) / escale, abs_max(np.maximum(gx, 0.0)) / gscale, abs_max(rd) / dscale, gap)
    return rd, re, rg


def solve_qp(form: Formulation, lam: float, tol: float = IPM_TOL["default"], max_iter: int = 80,
             workspace: Workspace | None = None, method: str = "auto"):
    r"""Solve a problem with band and inequality rows by Mehrotra's predictor-corrector method.

    Parameters
    ----------
    form : Formulation
    lam : float
    tol : float
        Relative tolerance on the equality residual, the inequality violation, the
        stationarity and the complementarity gap (relative to the objective).
    max_iter : int
    workspace : Workspace, optional
    method : {"auto", "banded", "lu"}
        ``"auto"``: banded for the acceleration form when the rows are local, else the
        pivoted sparse LU at every step.

    Returns
    -------
    x : ndarray
    info : dict
        ``duals`` (cvxpy's convention), ``iterations``, ``factorization``, ``gap``,
        ``residuals`` (the measures of every iterate), ``status`` (``optimal``, or
        ``inaccurate`` for the best iterate when progress stopped short of ``tol``).

    Raises
    ------
    SolveError
        When the method stalls far from an answer (the usual sign of inequality rows that
        cannot hold together with the hard rows: a conic solver then proves it and names
        the items).

    Examples
    --------
    A straight line from 0 m that wants to reach 10 m at 10 s (soft, sigma 1 m) under a
    ceiling of 8 m over its last second: it ends at the ceiling, with multiplier
    2 (10 - 8) = 4 on the last row:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, PositionBound
    >>> from bvpnav.linalg.ipm import solve_qp
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.zeros_like(t)))
    >>> _ = prob.add(Position(t=0.0, value=0.0), Position(t=10.0, value=10.0, sigma=1.0),
    ...              PositionBound(upper=8.0, t0=9.0, t1=10.0, name="ceiling"))
    >>> x, info = solve_qp(prob.formulation, lam=1.0)
    >>> print(f"end {x[100]:.6f} m, multiplier {info['duals']['ceiling'][0][-1]:.6f}, {info['status']}")
    end 8.000000 m, multiplier 4.000000, optimal

    Notes
    -----
    See the module Notes. Start: the least-squares answer, slacks and multipliers shifted
    and balanced as in Mehrotra's heuristic. One step length for the primal and dual
    variables (fraction to the boundary 0.99, 0.999 near the end); centering
    :math:`\sigma = (\mu_{aff}/\mu)^3`.
    """
    qp = quadratic_form(form, lam)
    banded = method == "banded" or (method == "auto" and form.residual == "acceleration")
    steps = _Steps(qp, form, workspace, banded)
    return interior_point(qp, steps, _Newton(qp, steps), tol, max_iter)


def interior_point(qp: QuadraticForm, steps: _Steps, newton: _Newton, tol: float, max_iter: int):
    """:func:`solve_qp`'s method on a quadratic program whose Newton systems ``steps``
    factorize (made once: a caller that tried another method first passes its own)."""
    mi = qp.G.m
    x, y, weighted = _start(newton, qp)
    r = qp.G.value(x)
    if mi == 0 or (not weighted and np.all(r <= 0.0)):
        return x, _info(qp, y, np.zeros(mi), 0, steps, 0.0, [], "optimal")
    f0 = float(np.sum(qp.ls.D.value(x) ** 2))
    fscale = 1e-12 * max(f0, 1.0)
    pt = _Point(x, y, *_initial_slacks(r, f0, mi))
    best, history, stalls = None, [], 0
    for it in range(max_iter + 1):
        rd, re, rg = _measures(qp, pt, newton, fscale)
        history.append(pt.measures)
        if best is None or pt.worst < best.worst:
            best = pt
        if pt.worst <= tol or it == max_iter or stalls >= 3:
            break
        s, z = pt.s, pt.z
        mu = _dot(s, z) / mi
        try:
            newton.factor(s, z)
        except np.linalg.LinAlgError:
            if best is pt and it == 0:
                raise
            break   # the weights have spread beyond what the factorization resolves: the best so far
        # predictor (affine scaling), then the corrector with Mehrotra's centering
        # the directions refined to a thousandth of the progress still to make
        rtol = min(max(1e-3 * pt.worst, 1e-14), 1e-6)
        dx, dy, dz, ds = newton.solve(-rd, -re, -rg, -s * z, rtol=rtol)
        a_aff = _step(s, ds, z, dz, 1.0)
        mu_aff = _dot(s + a_aff * ds, z + a_aff * dz) / mi
        sigma = min((mu_aff / mu) ** 3, 1.0)
        dx, dy, dz, ds = newton.solve(-rd, -re, -rg, -s * z + sigma * mu - ds * dz, rtol=rtol)
        alpha = _step(s, ds, z, dz, 0.99 if pt.measures[3] > 1e-6 else 0.999)
        stalls = stalls + 1 if alpha < 1e-6 else 0
        pt = _Point(pt.x + alpha * dx, pt.y + alpha * dy, s + alpha * ds, z + alpha * dz)
    status = "optimal" if best.worst <= tol else "inaccurate"
    if best.worst > max(1e3 * tol, 1e-6):
        last = best.measures
        raise SolveError(
            f"direct: the interior-point method stopped after {len(history) - 1} steps short of an answer "
            f"(best relative equality residual {last[0]:.1e}, inequality violation {last[1]:.1e}, "
            f"stationarity {last[2]:.1e}, gap {last[3]:.1e}); the band and inequality rows may not hold "
            "together with the hard rows. A conic solver (solver='clarabel') proves infeasibility and "
            "names the items that conflict.",
            attempts=[{"solver": "direct", "status": "not converged",
                       "reason": f"interior point: no answer in {len(history) - 1} steps"}])
    return best.x, _info(qp, best.y, best.z, len(history) - 1, steps, best.measures[3], history, status)


def _initial_slacks(r: np.ndarray, f0: float, mi: int) -> tuple[np.ndarray, np.ndarray]:
    """Slacks and multipliers to start from at rows ``r = G x + g`` of the least-squares
    answer: each violated row's slack 1.5 times its violation, each satisfied row's its
    margin plus a tenth of the largest violation; the multipliers at complementarity
    :data:`MU0` times ``max(f0, 1) / mi`` (``f0`` the least-squares objective)."""
    viol = np.maximum(r, 0.0)
    floor = 0.1 * max(float(np.max(viol)), 1e-300)
    s = np.maximum(-r, 0.0) + np.maximum(1.5 * viol, floor)
    z = (MU0 * max(f0, 1.0) / mi) / s
    return s, z


def _dot(a: np.ndarray, b: np.ndarray) -> float:
    """``a . b`` by ``einsum``: no threaded BLAS call (on a machine whose cores are busy, a
    threaded ``ddot``'s threads wait for them at every call of the loop)."""
    return float(np.einsum("i,i->", a, b))


def _step(s, ds, z, dz, frac: float) -> float:
    """The largest step in (0, 1] keeping ``s`` and ``z`` positive, times ``frac`` when it
    meets the boundary."""
    a = 1.0
    for v, dv in ((s, ds), (z, dz)):
        neg = dv < 0
        if neg.any():
            a = min(a, frac * float(np.min(-v[neg] / dv[neg])))
    return a


def _info(qp: QuadraticForm, y: np.ndarray, z: np.ndarray, iterations: int, steps: _Steps, gap: float,
          history: list, status: str, method: str = "interior point") -> dict:
    """The duals in cvxpy's convention per term, and the run's record."""
    duals = {}
    for label, sl in qp.ls.eq_blocks:
        duals[label] = y[sl] if label == "fem" else [y[sl]]
    zs = z / qp.scale if z.size else z   # back to the items' units
    for label, pieces in qp.ineq_blocks:
        duals[label] = [zs[sl] for sl in pieces]
    name = steps.describe()
    note = f"{method} on {name}" + (f" ({'; '.join(steps.notes)})" if steps.notes else "")
    return {"duals": duals, "iterations": iterations, "factorization": note, "gap": gap,
            "residuals": history, "status": status, "qp_method": method}
