r"""The equality-constrained least-squares view of a problem, and a forward-error check.

Problems whose items are all hard or soft (no inequalities, bands or robust
penalties) are linear least squares with linear equality constraints:

.. math::

    \min_x \|D x + c\|^2 \quad \text{s.t.} \quad E x + e = 0,

where ``D`` stacks the data rows and the soft rows (weighted by
:math:`\sqrt{\lambda}/\sigma`, priors by :math:`1/\sigma`) and ``E`` stacks the FEM rows and
the hard items. Its optimality conditions, written with the residual
:math:`\rho = D x + c` and :math:`\mu = y/2` so that no normal matrix is formed, are the
augmented system

.. math::

    \begin{bmatrix} -I & D & 0 \\ D^T & 0 & E^T \\ 0 & E & 0 \end{bmatrix}
    \begin{bmatrix} \rho \\ x \\ \mu \end{bmatrix} =
    \begin{bmatrix} -c \\ 0 \\ -e \end{bmatrix}.

One step of iterative refinement on this system from a solver's answer estimates that
answer's forward error; bvpnav uses it to judge solvers' answers on problems where
small residuals do not imply an accurate trajectory (the load-residual form is
ill-conditioned roughly like :math:`N^4`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..formulation import Formulation
from ..model import Affine, rows_with_tail
from ..sparse import abs_max, canonical, row_scaled
from .banded import (
    AugmentedOperator,
    BandedKKT,
    BandPlan,
    DiagonalRows,
    Factorization,
    NotBanded,
    residual,
)
from .workspace import Workspace

__all__ = ["LeastSquaresForm", "least_squares_form", "non_least_squares_term", "forward_error",
           "check_factor", "BorderedLU", "banded_plan", "banded_factor", "fem_rows_by_diagonals",
           "factor_form", "solve_least_squares", "FORWARD_RTOL", "Factored"]

#: Largest relative forward error accepted per accuracy preset.
FORWARD_RTOL = {"low": 1e-4, "default": 1e-6, "high": 1e-8}


@dataclass(eq=False)
class LeastSquaresForm:
    r"""``min ||D x + c||^2 s.t. E x + e = 0`` with row bookkeeping.

    Attributes
    ----------
    D : Affine
        Objective rows (data, then soft items, then priors), already weighted.
    E : Affine
        Equality rows (FEM first, then hard items).
    eq_blocks : list of (label, slice)
        Which rows of ``E`` belong to the FEM (label ``"fem"``) and to each hard item.
    lam_rows : ndarray of bool
        Rows of ``D`` multiplied by :math:`\sqrt{\lambda}` (soft items).
    """

    D: Affine
    E: Affine
    eq_blocks: list
    lam_rows: np.ndarray | None = None
    lam: float | None = None

    @functools.cached_property
    def _entry_rows(self) -> np.ndarray:
        """The row of every stored entry of ``D`` (for :meth:`at_lam`'s row scaling)."""
        return np.repeat(np.arange(self.D.A.shape[0]), np.diff(self.D.A.indptr))

    def at_lam(self, lam: float) -> LeastSquaresForm:
        r"""The same form at another lambda: the rows of :attr:`lam_rows` rescaled by
        :math:`\sqrt{\lambda / \lambda_0}` (no item is compiled again)."""
        if self.lam is None or self.lam_rows is None:
            raise ValueError("at_lam needs a form made by least_squares_form")
        k = np.where(self.lam_rows, np.sqrt(lam / self.lam), 1.0)
        A = self.D.A
        scaled = row_scaled(A, k, self._entry_rows)
        return LeastSquaresForm(Affine(scaled, self.D.c * k, self.D.labels), self.E, self.eq_blocks,
                                self.lam_rows, float(lam))

    def augmented_upper(self, delta: float) -> sp.csc_matrix:
        """Upper triangle of the augmented matrix regularized by ``+delta`` on the unknowns
        and ``-delta`` on the multipliers (quasi-definite; assembled directly, for LDL^T)."""
        m, n = self.D.A.shape
        p = self.E.A.shape[0]
        return sp.bmat(
            [[-sp.identity(m), self.D.A, None],
             [None, delta * sp.identity(n), self.E.A.T],
             [None, None, -delta * sp.identity(p)]],
            format="csc",
        )

    def augmented(self) -> sp.csc_matrix:
        """The symmetric indefinite augmented matrix (see module Notes)."""
        m, n = self.D.A.shape
        p = self.E.A.shape[0]
        return sp.bmat(
            [[-sp.identity(m), self.D.A, None],
             [self.D.A.T, None, self.E.A.T],
             [None, self.E.A, sp.csr_matrix((p, p))]],
            format="csc",
        )

    def rhs(self) -> np.ndarray:
        """Right-hand side of the augmented system."""
        n = self.D.A.shape[1]
        return np.concatenate([-self.D.c, np.zeros(n), -self.E.c])


def non_least_squares_term(form: Formulation):
    """The first term that makes the problem not least squares (an inequality, a band or
    a robust penalty), or None when the problem is equality-constrained least squares."""
    for term in form.terms():
        if term.least_squares_role() is None:
            return term
    return None


def _weighted(res: Affine, k) -> Affine:
    """``res * k``, canonical (:func:`bvpnav.sparse.canonical`: a weighted value that is zero is
    not stored, the matrix marked); the weighted matrix kept with ``res.A`` (up to
    :data:`WEIGHTED_KEPT` entries) for the next call with the same ``k`` (the node-state loop's
    steps share the rows that do not move with the point: the items', the bias walks')."""
    A = res.A
    k = np.broadcast_to(np.asarray(k, dtype=float), (res.m,))
    kept = getattr(A, "_bvpnav_weighted", None)
    if kept is not None and kept[1] is getattr(A, "data", None) and np.array_equal(kept[0], k):
        return Affine(kept[2], res.c * k, res.labels)
    if sp.issparse(A) and A.format == "csr" and A.has_canonical_format and np.all(k):
        out = Affine(_scaled_canonical(A, k), res.c * k, res.labels)
    else:
        out = res * k
    if sp.issparse(A) and A.nnz <= WEIGHTED_KEPT:
        A._bvpnav_weighted = (np.array(k), A.data, out.A)   # a shallow copy with new values misses
    return out


def _scaled_canonical(A: sp.csr_matrix, k: np.ndarray) -> sp.csr_matrix:
    """``diag(k) A`` for a canonical CSR ``A`` and ``k`` without zeros, its zero values dropped
    as it is written (one matrix made: not a scaled copy, then a canonical copy of that), marked
    canonical."""
    m = A.shape[0]
    rows = np.repeat(np.arange(m), np.diff(A.indptr))
    v = A.data * k[rows]
    if v.size and not np.all(v):
        keep = v != 0
        indptr = np.zeros(m + 1, dtype=A.indptr.dtype)
        np.cumsum(np.bincount(rows[keep], minlength=m), out=indptr[1:])
        out = sp.csr_matrix((v[keep], A.indices[keep], indptr), shape=A.shape)
    else:
        out = sp.csr_matrix((v, A.indices, A.indptr), shape=A.shape)
    out.has_canonical_format = True
    out._bvpnav_canonical = out.data
    return out


#: Largest stored entries of a term's matrix whose weighted copy :func:`_weighted` keeps (a big
#: problem's rows are not kept twice).
WEIGHTED_KEPT = 1 << 17


def least_squares_form(form: Formulation, lam: float, surrogate: bool = False) -> LeastSquaresForm | None:
    r"""The problem as equality-constrained least squares, or None if it is not one.

    Parameters
    ----------
    form : Formulation
    lam : float
        Weight of the lambda-scaled soft rows (multiplied by :math:`\sqrt{\lambda}`).
    surrogate : bool
        Build the least-squares *part* of any problem instead (robust equalities as soft
        rows; inequalities, bands and cones left out): the view of the conditioning
        estimate, which can only err towards less information. Never None then.

    Returns
    -------
    LeastSquaresForm or None
        None when an item is an inequality, a band or a robust penalty (unless
        ``surrogate``).

    Notes
    -----
    Each term's place comes from :meth:`bvpnav.terms.Term.least_squares_role`: hard
    equalities are rows of ``E``, soft ones rows of ``D`` weighted by
    :math:`\sqrt{\lambda}/\sigma` (priors by :math:`1/\sigma`).
    """
    if not surrogate and non_least_squares_term(form) is not None:
        return None
    model = form.model
    obj = [form.data_rows()]
    eq = []   # the items' equality rows, below the FEM rows
    start = model.N * model.d
    blocks = [("fem", slice(0, start))]
    scaled = [np.zeros(obj[0].m, dtype=bool)]
    for term in form.terms():
        role = term.least_squares_role(surrogate)
        if role == "E":
            eq.append(term.residual)
            blocks.append((term.label, slice(start, start + term.residual.m)))
            start += term.residual.m
        elif role == "D":
            obj.append(_weighted(term.residual, np.sqrt(term.weight(lam)) / term.sigma))
            scaled.append(np.full(term.residual.m, bool(term.scaled_by_lam)))
    # canonical once (sorted, no duplicates or explicit zeros): every factorization and every
    # lambda of a sweep then shares these arrays instead of cleaning a copy of its own. Each
    # part is cleaned before stacking: a hard item's explicit zero would otherwise copy the
    # whole FEM block, and stacked canonical parts are canonical
    D = Affine.vstack([Affine(canonical(a.A), a.c, a.labels) for a in obj])
    # the FEM rows and the items' below them written once (not the FEM rows, then a copy)
    E = model.fem_rows_and([Affine(canonical(a.A), a.c, a.labels) for a in eq])
    E = Affine(canonical(E.A), E.c, E.labels)
    return LeastSquaresForm(D, E, blocks, np.concatenate(scaled), float(lam))


def forward_error(form: Formulation, xval: np.ndarray, lam: float, duals: dict | None,
                  factored: Factored | None = None, workspace: Workspace | None = None) -> float | None:
    r"""Relative forward error of ``xval`` estimated by one refinement step.

    Parameters
    ----------
    form : Formulation
    xval : ndarray
        The stacked solution to judge.
    lam : float
    duals : dict or None
        ``{"fem": y, label: [y_item]}`` in cvxpy's sign convention (Lagrangian
        ``f + y^T (E x + e)``). Missing duals are estimated as zero, which makes the
        estimate pessimistic, never optimistic.

    Returns
    -------
    float or None
        :math:`\|\delta x\|_\infty / \|x\|_\infty` for the correction :math:`\delta` of one
        refinement step, or None when the problem is not equality-constrained least
        squares.
    factored : Factored, optional
        A factorization of this problem's augmented matrix at this ``lam`` to reuse (the
        direct back end passes its own; the residual is still computed afresh).
    workspace : Workspace, optional
        The solve's workspace (a band plan to reuse when a factor is made here).
    """
    ls = factored.ls if factored is not None else least_squares_form(form, lam)
    if ls is None:
        return None
    p = ls.E.m
    y = np.zeros(p)
    if duals:
        for label, sl in ls.eq_blocks:
            d = duals.get(label)
            if label != "fem":
                d = d[0] if d else None
            if d is not None:
                y[sl] = np.asarray(d, dtype=float).ravel()
    rho = ls.D.value(xval)
    z = np.concatenate([rho, xval, y / 2.0])
    m = ls.D.m
    try:
        fac = factored.factor if factored is not None else check_factor(ls, form, workspace)
        resid = residual(fac.S, ls.rhs(), z)
        # the banded factor gives the correction's x part alone (no residuals formed)
        dx = fac.solve_x(resid) if isinstance(fac, BandedKKT) else fac.solve(resid)[m:m + xval.size]
    except (RuntimeError, np.linalg.LinAlgError):  # singular: the information does not determine x
        return float("inf")
    return float(np.max(np.abs(dx)) / max(np.max(np.abs(xval)), 1e-300))


class Factored(NamedTuple):
    r"""A factorization of the augmented system at one ``lam``, handed by a direct back end
    to verification (a ``(ls, factor)`` pair to code that unpacks two).

    Attributes
    ----------
    ls : LeastSquaresForm
    factor : Factorization
    refined : (ndarray, float) or None
        The answer ``x`` the back end refined with this factor and the relative size
        :math:`\|\delta x\|_\infty / \|x\|_\infty` of its one refinement step (None
        when it took none or several).

    Notes
    -----
    The step's correction is the one-step forward-error estimate (:func:`forward_error`)
    of the first solve; the answer includes the correction, so while refinement
    contracts (:math:`\|I - \tilde S^{-1} S\| < 1`) it estimates the answer's own error
    from above, down to the rounding floor. Verification uses it when it already meets
    the preset's bound and takes a fresh step on the answer otherwise (the bound can
    only be met, never missed, for want of that step). After several steps there is no
    such record: at the rounding floor the corrections are noise of the floor's size,
    and the one that stopped the loop was chosen for being small.
    """

    ls: LeastSquaresForm
    factor: Factorization
    refined: tuple | None = None


class _LDL:
    """QDLDL's LDL^T factorization (AMD ordering, no pivoting) of a quasi-definite matrix,
    with SuperLU's ``solve`` interface (one or several right-hand sides)."""

    def __init__(self, upper: sp.spmatrix):
        import qdldl  # a dependency of cvxpy

        self._f = qdldl.Solver(upper, upper=True)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.asarray(rhs, dtype=float)
        if rhs.ndim == 1:
            return self._f.solve(rhs)
        return np.column_stack([self._f.solve(np.ascontiguousarray(rhs[:, k]))
                                for k in range(rhs.shape[1])])


class BorderedLU(Factorization):
    r"""A factorization of ``S`` that eliminates a few dense unknowns through their Schur complement.

    Error-model parameters touch every FEM row, so their columns are dense; a sparse LU
    of the whole matrix then fills in roughly like N^2. Factorising the sparse part
    alone and handling the q dense unknowns by a q x q Schur complement keeps the cost
    linear in N. The factorization is reused by every :meth:`solve`.

    Parameters
    ----------
    S : sparse matrix, shape (T, T)
    dense : ndarray of int
        Indices of the unknowns (and matching equations) to eliminate last.
    shift_rows : ndarray of int, optional
        Rows (multipliers of hard items) that may be shifted by a tiny amount if the LU
        finds the matrix singular (redundant but consistent hard rows).
    upper : sparse matrix, optional
        The upper triangle of a statically regularized ``S`` (``S + diag(reg)`` with
        ``reg`` > 0 on the primal unknowns and < 0 on the multipliers: quasi-definite):
        factorise it with QDLDL's LDL^T (no pivoting) instead of ``S`` with SuperLU's LU;
        :meth:`refined` then iterates against ``S`` itself.

    Raises
    ------
    RuntimeError
        From SuperLU when the sparse block is singular.

    Notes
    -----
    With ``B`` the sparse block and ``L`` the dense indices,

    .. math:: (S_{LL} - S_{LB} S_{BB}^{-1} S_{BL})\, z_L = r_L - S_{LB} S_{BB}^{-1} r_B,
              \qquad z_B = S_{BB}^{-1} (r_B - S_{BL} z_L).
    """

    def __init__(self, S: sp.spmatrix, dense: np.ndarray, shift_rows: np.ndarray | None = None,
                 upper: sp.spmatrix | None = None):
        S = sp.csc_matrix(S)
        self.S = S
        self.shift = 0.0
        self.method = "lu" if upper is None else "ldl"
        if upper is not None:  # quasi-definite: no pivoting, no singular multiplier block
            self._factor(S, dense, upper)
            return
        try:
            self._factor(S, dense)
        except (RuntimeError, np.linalg.LinAlgError):
            if shift_rows is None or len(shift_rows) == 0:
                raise
            # redundant (but consistent) hard rows make the multiplier block singular: factor
            # S - delta I on those rows instead and let refinement against S recover x
            self.shift = 1e-10 * float(abs(S).max())
            d = np.zeros(S.shape[0])
            d[np.asarray(shift_rows, dtype=int)] = self.shift
            self._factor((S - sp.diags(d)).tocsc(), dense)

    def _sparse_factor(self, B):
        B = sp.csc_matrix(B)
        return spla.splu(B, permc_spec="COLAMD") if self.method == "lu" else _LDL(B)

    def _factor(self, S, dense, upper=None):
        """Factor the sparse block (of ``upper`` for LDL^T, else of ``S``) and form the
        Schur complement of the dense unknowns from ``S``."""
        F = S if upper is None else sp.csc_matrix(upper)
        self.dense = np.asarray(dense, dtype=int)
        if self.dense.size == 0:
            self.keep = None
            self.lu = self._sparse_factor(F)
            return
        mask = np.ones(S.shape[0], dtype=bool)
        mask[self.dense] = False
        self.keep = np.flatnonzero(mask)
        Sr, Sd = S[self.keep], S[self.dense]
        self.lu = self._sparse_factor(F[self.keep][:, self.keep])
        self.SBL = Sr[:, self.dense].toarray()
        self.SLB = Sd[:, self.keep].tocsr()
        self.X = self.lu.solve(self.SBL)
        self.schur = Sd[:, self.dense].toarray() - self.SLB @ self.X
        if not np.all(np.isfinite(self.schur)) or np.linalg.cond(self.schur) > 1e15:
            raise np.linalg.LinAlgError("singular Schur complement")

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``S z = rhs`` for one (T,) or several (T, k) right-hand sides."""
        rhs = np.asarray(rhs, dtype=float)
        if self.keep is None:
            return self.lu.solve(rhs)
        y0 = self.lu.solve(rhs[self.keep])
        zL = np.linalg.solve(self.schur, rhs[self.dense] - self.SLB @ y0)
        z = np.empty_like(rhs)
        z[self.keep] = y0 - self.X @ zL
        z[self.dense] = zL
        return z


def check_factor(ls: LeastSquaresForm, form: Formulation, workspace: Workspace | None = None
                 ) -> Factorization:
    """The factorization verification judges an answer with (any back end's): the banded
    one on the acceleration form (O(N), several times cheaper than a sparse LU), the
    pivoted LU where that is not banded or on the load form."""
    if form.residual == "acceleration":
        try:
            return banded_factor(ls, form, workspace=workspace)
        except (NotBanded, RuntimeError, np.linalg.LinAlgError, ValueError):
            pass
    return factor_form(ls, form, "lu")


def column_nodes(model, interleave: bool = False) -> np.ndarray:
    """Time node of every unknown of ``model`` (-1: the error-model parameters, which go to
    the border of a banded factorization).

    Positions and acceleration residuals of sample ``j`` sit at node ``j``, ``v0`` at the
    first node and ``v1`` at the last. Axes are laid end to end (axis ``a`` at nodes
    ``a N .. a N + N - 1``) unless ``interleave``: then every axis of sample ``j`` sits at
    node ``j`` (for rows that couple axes). Node states (an error model's per-node
    unknowns, :meth:`bvpnav.model.NavModel.state_nodes`) sit at their node, so they are in
    the band, not the border; they couple the axes, so they need ``interleave``.
    """
    N = model.N
    colnode = np.full(model.size, -1, dtype=np.int64)
    for a in range(model.d):
        off = 0 if interleave else a * N
        colnode[model.r_index(a)] = off + np.arange(N)
        colnode[model.w_index(a)] = off + np.arange(N)
        v0, v1 = model.v_end_index(a)
        colnode[v0], colnode[v1] = off, off + N - 1
        colnode[model.element_index(a)] = off + model.element_nodes()   # a coarse mesh's element residuals
    if model.ns:
        colnode[model.s_index] = model.state_nodes()
    return colnode


def fem_rows_by_diagonals(form: Formulation, workspace: Workspace | None = None) -> DiagonalRows:
    """The FEM rows (the first ``N d`` rows of a form's ``E``) of a formulation's model as
    :class:`~bvpnav.linalg.banded.DiagonalRows`: per axis the tridiagonal ``K`` on the positions
    and ``M`` on the acceleration residuals, the dense ``M G`` columns of the error-model
    parameters, and the end velocities' two entries. Kept in ``workspace`` (when given)
    with the model it describes."""
    model = form.model
    if workspace is not None and workspace.fem_diagonals is not None and workspace.model is model:
        return workspace.fem_diagonals
    N, d = model.N, model.d
    every = [model.fem_blocks(a) for a in range(d)]
    # the blocks that do not move with the linearization point (K, M, the end velocities' and
    # element residuals' columns: one object each for the node-state loop's models) placed once
    fixed = tuple(b[key] for b in every for key in ("r", "w", "vb", "u") if key in b)
    kept = None if workspace is None else workspace.fem_fixed
    if kept is not None and kept[1] == model.size and len(kept[0]) == len(fixed) and all(
            x is y for x, y in zip(kept[0], fixed, strict=True)):
        tri, rows, cols, vals = (list(v) for v in kept[2])
        if not model.q and model.ns and kept[3] is not None:
            # the other entries: the fixed ones' rows with the node states' columns after them
            # (the same matrix as through coordinates, without their sort)
            extra = rows_with_tail(kept[3], [model.ms_columns(a) for a in range(d)], int(model.s_index[0]))
            out = DiagonalRows(N * d, list(tri), [], extra)
            workspace.fem_diagonals, workspace.model = out, model
            return out
    else:
        tri, rows, cols, vals = [], [], [], []
        for a, blocks in enumerate(every):
            for key, c0 in (("r", model.r_index(a)[0]), ("w", model.w_index(a)[0])):
                A = blocks[key]   # K and M keep the diagonals they were made from (fem.tridiagonal)
                lo, dg, up = (getattr(A, "_bvpnav_diagonals", None)
                              or (A.diagonal(-1), A.diagonal(0), A.diagonal(1)))
                tri.append((a * N, int(c0), lo, dg, up))
            vb = blocks["vb"].tocoo()
            rows.append(a * N + vb.row)
            cols.append(np.asarray(model.v_end_index(a))[vb.col])
            vals.append(vb.data)
            if "u" in blocks:   # a coarse mesh's element residuals (bvpnav.mesh): two rows each
                u = blocks["u"].tocoo()
                rows.append(a * N + u.row)
                cols.append(model.element_index(a)[u.col])
                vals.append(u.data)
        if workspace is not None:
            head = (sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                  shape=(N * d, model.size)) if model.ns else None)
            placed = (tuple(tri), tuple(rows), tuple(cols), tuple(vals))
            workspace.fem_fixed = (fixed, model.size, placed, head)
    dense = []
    for a in range(d):
        if model.q:   # the columns copied: a view would keep all of the axis' M G alive
            mcols, mg = model.mg_columns(a)
            dense += [(a * N, int(model.l_index[k]), mg[:, i].copy()) for i, k in enumerate(mcols)
                      if mg[:, i].any()]
        if model.ns:   # the node states' local columns M G_s
            ms = model.ms_columns(a).tocoo()
            rows.append(a * N + ms.row)
            cols.append(model.s_index[ms.col])
            vals.append(ms.data)
    extra = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                          shape=(N * d, model.size))
    out = DiagonalRows(N * d, tri, dense, extra)
    if workspace is not None:
        workspace.fem_diagonals, workspace.model = out, model
    return out


def banded_plan(ls: LeastSquaresForm, form: Formulation, workspace: Workspace | None = None) -> BandPlan:
    """The symbolic analysis of a form's banded factorization (axes end to end, else
    interleaved when rows couple axes), with its first assembly kept for the first factor.

    With ``workspace``, the plan is kept there with the pattern it was made for, and
    handed out again for a form of the same pattern (the lambda sweep's points and the
    solve at the chosen lambda share one analysis).

    Raises
    ------
    bvpnav.linalg.banded.NotBanded
        When rows couple distant instants beyond the banded path's limits (the caller falls
        back to a sparse factorization).
    """
    model = form.model
    D, E = canonical(ls.D.A), canonical(ls.E.A)
    pattern = (D.indptr, D.indices, E.indptr, E.indices, np.asarray(ls.lam_rows, dtype=bool))
    if workspace is not None and workspace.band_plan is not None and all(
            a is b or np.array_equal(a, b) for a, b in zip(workspace.band_pattern, pattern, strict=True)):
        return workspace.band_plan   # the same pattern (another lambda, or the sweep's chosen one)
    if (workspace is not None and workspace.band_plan is not None and model.ns
            and all(a is b or np.array_equal(a, b) for a, b in zip(workspace.band_pattern[2:], pattern[2:],
                                                                   strict=True))):
        # node states (always interleaved): a Gauss-Newton step's objective rows may fill
        # exact zeros of the first step's; the plan serves them when they stay in its band
        plan = workspace.band_plan.admitting(D, E, column_nodes(model, interleave=True), ls.lam_rows)
        if plan is not None:
            workspace.band_plan, workspace.band_pattern = plan, pattern
            return plan
    diagonal = fem_rows_by_diagonals(form, workspace)
    try:
        if model.ns:   # node states couple the axes at every node: interleaved from the start
            raise NotBanded("node states")
        plan = BandPlan.build(D, E, column_nodes(model), lam_rows=ls.lam_rows, segments=model.d,
                              diagonal=diagonal)
    except NotBanded:
        if model.d == 1 and not model.ns:
            raise
        plan = BandPlan.build(D, E, column_nodes(model, interleave=True), lam_rows=ls.lam_rows,
                              diagonal=diagonal)
    if workspace is not None:
        workspace.band_plan, workspace.band_pattern = plan, pattern
    return plan


def banded_factor(ls: LeastSquaresForm, form: Formulation, plan: BandPlan | None = None, parts=None,
                  workspace: Workspace | None = None) -> BandedKKT:
    """:class:`bvpnav.linalg.banded.BandedKKT` of a form; ``plan`` (:func:`banded_plan`) from an
    earlier factor of the same pattern is reused, and ``parts`` assembled values with it
    (by default the lambda sweep's :class:`~bvpnav.linalg.banded.AffineBand` at the form's
    lambda when ``workspace`` has one, else an assembly).

    Raises
    ------
    bvpnav.linalg.banded.NotBanded
        As :func:`banded_plan`.
    """
    workspace = Workspace() if workspace is None else workspace   # the plan and the factor share diagonals
    plan = banded_plan(ls, form, workspace) if plan is None else plan
    if parts is None and ls.lam is not None:
        # after a lambda sweep of this formulation: its factor at this lambda when it kept
        # one (its last point's), else its scaled band at any lambda is one copy
        # (bvpnav.linalg.banded.AffineBand) into a buffer the sweep already touched: the solve at
        # the chosen lambda assembles nothing
        kept = workspace.kept_factors
        kept = kept if kept is not None and kept.plan is plan else None
        fac = None if kept is None else kept.take(ls.lam)
        if fac is not None:
            return fac.for_matrices(ls.D.A, ls.E.A)
        band = workspace.affine_band
        if band is not None and workspace.band_plan is plan:
            parts = band.at(ls.lam, out=None if kept is None else kept.buffer(band.scaled0.shape))
    out = None
    if parts is None and workspace.band_buffer is not None:   # a loop's band memory, reused
        need = plan.pos_order.size * plan.ldab
        if workspace.band_buffer.size < need:
            workspace.band_buffer = np.empty(need)
        out = workspace.band_buffer
    return BandedKKT(ls.D.A, ls.E.A, params=form.model.l_index, plan=plan, parts=parts,
                     diagonal=None if parts is not None else fem_rows_by_diagonals(form, workspace), out=out)


def factor_form(ls: LeastSquaresForm, form: Formulation, method: str = "lu", delta: float = 1e-12,
                workspace: Workspace | None = None) -> Factorization:
    """A factorization of a form's augmented matrix, error-model columns eliminated last.

    ``method="lu"``: SuperLU (COLAMD ordering, partial pivoting); redundant hard rows are
    handled by a tiny shift of the multiplier block. ``method="ldl"``: QDLDL on the
    quasi-definite matrix regularized by ``+delta`` on the unknowns and ``-delta`` on the
    multipliers (the augmented matrix already has ``-I`` on the residual rows); several
    times faster, but its answers need refinement against the exact matrix.
    ``method="banded"``: :func:`banded_factor` (raises
    :class:`~bvpnav.linalg.banded.NotBanded` for rows that are not local).
    """
    if method == "banded":
        return banded_factor(ls, form, workspace=workspace)
    m, n = ls.D.A.shape
    p = ls.E.m
    dense = m + form.model.l_index
    if method == "ldl":
        return BorderedLU(ls.augmented(), dense, upper=ls.augmented_upper(delta))
    if method != "lu":
        raise ValueError(f"method={method!r}; choose 'lu', 'ldl' or 'banded'")
    return BorderedLU(ls.augmented(), dense, np.arange(m + n, m + n + p))


#: Relative correction below which refinement of a banded answer stops, by accuracy
#: preset (the direct back end's ``refine_tol``): a hundredth of the preset's forward-error
#: bound (:data:`FORWARD_RTOL`). The correction measures the error of the answer before
#: the step, which the step itself removes, so the answer is better than this (one step
#: usually; a second one only shows the rounding floor).
BANDED_TOL = {name: 1e-2 * v for name, v in FORWARD_RTOL.items()}

#: Largest normwise backward error at which a refined LDL^T answer is accepted.
LDL_BACKWARD = 1e-12


def solve_least_squares(form: Formulation, lam: float, refine: int = 3, tol: float = 1e-14,
                        method: str = "auto", ldl_steps: int = 30, ldl_tol: float = 1e-12,
                        ldl_accept: float = 1e-7, banded_tol: float = BANDED_TOL["default"],
                        workspace: Workspace | None = None):
    r"""Solve the equality-constrained least-squares form directly.

    One sparse factorization of the augmented system (error-model parameters eliminated
    through their Schur complement) followed by iterative refinement in double precision.

    Parameters
    ----------
    form : Formulation
    lam : float
    refine : int
        Refinement steps after an LU factorization (stops early below ``tol``).
    tol : float
        Stop refining when the relative correction falls below this.
    method : {"auto", "lu", "ldl"}
        ``"lu"``: SuperLU with partial pivoting; robust for the ill-conditioned load form.
        ``"ldl"``: QDLDL on the regularized quasi-definite matrix, refined until the
        correction is below ``ldl_tol`` or stops shrinking (the rounding floor; at most
        ``ldl_steps``); if the last correction is then above ``ldl_accept``, the LU is
        used instead and the reason is recorded. ``"auto"``: ``"ldl"`` for the
        acceleration-residual form, ``"lu"`` for the load form (whose condition number,
        roughly N^4, defeats a regularized factorization).
    banded_tol : float
        Stop refining a banded answer when the relative correction falls below this
        (:data:`BANDED_TOL`).
    workspace : Workspace, optional
        The solve's workspace: the band plan, and a lambda sweep's band or factor at this
        ``lam``, to reuse.

    Returns
    -------
    x : ndarray
        The stacked solution.
    info : dict
        ``duals`` (cvxpy's sign convention, for verification), ``refinements``, ``correction``
        (relative size of the last correction, like the 2011 paper's Table 2),
        ``factorization`` (``"lu"`` or ``"ldl"``, with the reason for any switch),
        ``factor`` and ``form``.

    Raises
    ------
    ValueError
        When the problem is not least squares (inequalities, bands, robust items).

    Notes
    -----
    Refinement: :math:`z_{k+1} = z_k + \tilde S^{-1} (b - S z_k)`, where :math:`\tilde S`
    is the factorised (possibly regularized) matrix; it converges when
    :math:`\|I - \tilde S^{-1} S\| < 1`.
    """
    ls = least_squares_form(form, lam)
    if ls is None:
        raise ValueError("not an equality-constrained least-squares problem")
    if method == "auto":
        method = "lu" if form.residual == "load" else "banded"
    m, n = ls.D.A.shape
    window = slice(m, m + n)
    rhs = ls.rhs()
    notes = []
    fac = z = None
    k, corr = 0, np.inf
    if method == "banded":
        try:
            fac = banded_factor(ls, form, workspace=workspace)
            # a pivoted LU (exact but for folding the local rows): one refinement step whose
            # correction measures the first solve's error usually settles it
            z, k, corr = _accepted(fac, rhs, window, ldl_steps, banded_tol, ldl_accept, notes, "banded")
            if z is None:
                fac, method = None, "lu"
        except NotBanded as exc:
            notes.append(f"not banded: {exc}")
            method = "ldl"
        except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
            notes.append(f"banded failed: {exc}")
            method = "lu"
    if fac is None and method == "ldl":
        try:
            fac = factor_form(ls, form, "ldl")
            z, k, corr = _accepted(fac, rhs, window, ldl_steps, ldl_tol, ldl_accept, notes, "ldl")
            if z is None:
                fac = None
        except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
            notes.append(f"ldl failed: {exc}")
            fac = None
    if fac is None:
        fac = factor_form(ls, form, "lu")
        z, k, corr = fac.refined(rhs, refine + (3 if fac.shift else 0), tol, window=window)
    name = fac.plan.describe() if isinstance(fac, BandedKKT) else fac.method
    note = name + (f" ({'; '.join(notes)})" if notes else "")
    x = z[m:m + n]
    mu = z[m + n:]
    duals = {}
    for label, sl in ls.eq_blocks:
        y = 2.0 * mu[sl]
        duals[label] = y if label == "fem" else [y]
    return x, {"duals": duals, "refinements": k, "correction": corr, "factorization": note,
               "factor": fac, "form": ls, "refined": (x, corr) if k == 1 else None}


def _accepted(fac, rhs, window, steps, tol, accept, notes, name):
    """Refine a factorization that is not exact for ``S`` (regularized, or folded) and accept
    its answer only with a small correction and a normwise backward error near rounding;
    ``(None, k, corr)`` with the reason in ``notes`` otherwise."""
    S = fac.S
    operator = isinstance(S, AugmentedOperator)   # else an assembled sparse matrix
    scratch = np.empty_like(rhs) if operator and np.ndim(rhs) == 1 else None
    z, k, corr = fac.refined(rhs, steps, tol, window=window, stall=0.5, scratch=scratch)
    # a small correction alone can mislead (a wild first solve makes every later
    # correction small relative to z, and the correction is measured on x alone): also
    # require the answer's own normwise backward error |rhs - S z| / (|S| |z| + |rhs|)
    # (infinity norms of the vectors; for |S| its largest entry, which is at most the
    # infinity norm, so the measure is the stricter) to be near rounding. Judging the
    # iterate before the last step instead (its residual is already formed) would save
    # this product but not bound the answer's residuals and multipliers, which the step
    # may have moved (found in review)
    eta = np.inf
    if np.all(np.isfinite(z)):
        norm = S.max_abs() if operator else float(abs(S).max())
        den = norm * abs_max(z) + abs_max(rhs)
        res = residual(S, rhs, z, out=scratch)
        eta = abs_max(res) / max(den, 1e-300)
    if not (np.isfinite(corr) and corr <= accept):
        notes.append(f"{name} refinement stalled at correction {corr:.1e}")
        return None, k, corr
    if not eta <= LDL_BACKWARD:
        notes.append(f"{name} backward error {eta:.1e} after refinement")
        return None, k, corr
    return z, k, corr
