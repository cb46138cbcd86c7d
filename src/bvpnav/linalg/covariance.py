r"""The covariance of an answer: positions, velocities and error-model parameters, in O(N).

The acceleration form is a maximum a-posteriori estimate under a stated Gaussian noise
model: the data rows are the nodal acceleration residuals :math:`w_j/\sigma_a`, the soft
rows the items' misfits over their sigmas, the hard rows hold exactly. Written as
least squares with equality constraints,

.. math:: \min_x \|D x + c\|^2 \quad \text{s.t.} \quad E x + e = 0,

the estimate is linear in the noise, and when the rows of ``D x + c`` at the truth are
independent with unit variance its covariance is the ``x`` block of the inverse of the
KKT matrix

.. math::

    K = \begin{bmatrix} D^T D & E^T \\ E & 0 \end{bmatrix}, \qquad
    \operatorname{Cov}(\hat x) = (K^{-1})_{xx} = N (N^T D^T D N)^{-1} N^T,

with ``N`` a basis of the null space of ``E``: the covariance on the manifold of the hard
constraints (zero in every direction a hard item fixes).

How it is computed: the unknowns and rows are grouped by time node (positions,
residuals and FEM multipliers of node ``j``, and the rows of local items next to them),
which makes ``K`` block tridiagonal except for a border: the end velocities, the first
position, the error-model parameters and the rows of non-local items (average
velocities, symmetry). The block-tridiagonal part is factorised by cyclic reduction
(:mod:`bvpnav.linalg.selinv`), which also gives its inverse on its own pattern; the border enters
through its Schur complement (a few right-hand sides). Everything is O(N) in time and
memory and vectorized.

For problems that are not least squares (robust, band and inequality items) the same is
done for the quadratic model at the solution (:meth:`bvpnav.terms.Term.quadratic_rows`:
active inequalities and band edges held as equalities, Huber rows by their curvature);
that is an approximation. For items that are linearized (``TrackLine``) it is the
covariance of the last linearization.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import InputError, SolveError
from ..formulation import Formulation
from ..model import Affine
from ..sparse import canonical
from .banded import row_span
from .lsq import LeastSquaresForm, least_squares_form
from .selinv import CyclicReduction, equilibrated_inverse, symmetric_scale

__all__ = ["Covariance", "posterior", "quadratic_model", "redundancy", "MAX_BORDER_ROWS", "BORDER_COND_WARN"]

#: Most hard-item rows the fallback layout takes into the border (each one costs a
#: right-hand side of N blocks); beyond it such problems are refused with the fix.
MAX_BORDER_ROWS = 2000

#: Equilibrated condition number (of the border's Schur complement, or of a block pivot)
#: above which the standard deviations are flagged as possibly inaccurate: their error
#: grows like the condition number times the rounding unit (measured: 2e-7 at 6e12, 0.2
#: at 1e14, below 1e-9 under 1e10), as with nearly repeated hard rows.
BORDER_COND_WARN = 1e10


def quadratic_model(form: Formulation, x: np.ndarray, lam: float) -> tuple[LeastSquaresForm, bool]:
    """The least-squares form of the problem, or of its quadratic model at ``x``.

    Returns
    -------
    ls : LeastSquaresForm
    exact : bool
        True when the problem is least squares (``ls`` is the problem itself).
    """
    ls = least_squares_form(form, lam)
    if ls is not None:
        return ls, True
    model = form.model
    obj, eq = [form.data_rows()], [model.fem_rows()]
    blocks = [("fem", slice(0, eq[0].m))]
    start = eq[0].m
    for term in form.terms():
        held, squared = term.quadratic_rows(x)
        if held.size:
            eq.append(term.residual.rows(held))
            blocks.append((term.label, slice(start, start + held.size)))
            start += held.size
        if squared.size:
            sig = np.broadcast_to(np.asarray(term.sigma, dtype=float), (term.residual.m,))[squared]
            rows = term.residual.rows(squared)
            if term.soft_edges:   # the excess beyond the band: its row shifted by the band's edge
                tol = np.broadcast_to(np.asarray(term.tol, dtype=float), (term.residual.m,))[squared]
                side = 1.0 if term.kind == "inequality" else np.sign(rows.value(x))
                rows = Affine(rows.A, rows.c - side * tol, rows.labels)
            obj.append(rows * (np.sqrt(term.weight(lam)) / sig))
    return LeastSquaresForm(Affine.vstack(obj), Affine.vstack(eq), blocks), False


@dataclass(eq=False)
class Covariance:
    r"""Covariance of a solution (see the module Notes for what it is).

    Attributes
    ----------
    state : ndarray, shape (N, 2 d, 2 d)
        Per sample, the covariance of ``(r_1..r_d, v_1..v_d)`` (m^2, m^2/s, m^2/s^2), in
        the order of the data's axes.
    params : ndarray, shape (q, q)
        Covariance of the error-model parameters in their internal parametrization.
    variance_factor : float
        A-posteriori variance factor :math:`\hat\sigma_0^2 = \|D \hat x + c\|^2 / f`.
    dof : int
        Degrees of freedom ``f``: objective rows minus unknowns plus independent hard rows.
    exact : bool
        False when this is the covariance of the quadratic model at the solution.
    border : int
        Unknowns handled by the Schur complement (error-model parameters, end
        velocities, first positions, non-local rows).
    block : int
        Size of the node blocks of the block-tridiagonal part.
    hard_rows_in_border : int
        0, or how many hard-item rows were moved into the border because some run of
        nodes was singular on its own with them (a hard zero-velocity interval): the
        covariance is exact either way.
    border_condition : float
        Equilibrated condition number of the border's Schur complement (of its
        non-null part when hard rows repeat each other).
    pivot_condition : float
        The largest equilibrated condition number of the block pivots.
    states : dict of str to ndarray (N, 3), or None
        With node states (:class:`~bvpnav.error_models.ErrorStates`): the variance of each
        state kind per node and axis, in its units squared.
    """

    state: np.ndarray
    params: np.ndarray
    variance_factor: float
    dof: int
    exact: bool
    border: int
    block: int
    hard_rows_in_border: int = 0
    border_condition: float = 1.0
    pivot_condition: float = 1.0
    states: dict | None = None

    def std(self) -> tuple[np.ndarray, np.ndarray]:
        """Standard deviations of positions (m) and velocities (m/s), each (N, d)."""
        d = self.state.shape[1] // 2
        var = np.clip(np.diagonal(self.state, axis1=1, axis2=2), 0.0, None)
        return np.sqrt(var[:, :d]), np.sqrt(var[:, d:])


class _Layout:
    """Where every unknown and row of the KKT matrix sits: a node block and slot, or the border."""

    def __init__(self, node: np.ndarray, extra: np.ndarray, nodes: int, d: int):
        T = node.size
        local = np.flatnonzero(node >= 0)
        # base unknowns (r, w, FEM multiplier) first in each node, then item rows
        order = local[np.lexsort((local, extra[local], node[local]))]
        nd = node[order]
        starts = np.searchsorted(nd, np.arange(nodes))
        slot = np.arange(order.size) - starts[nd]
        counts = np.bincount(nd, minlength=nodes)
        base = 3 * d
        cap = self._cap(counts, base, nodes)
        over = order[slot >= cap]
        node = node.copy()
        node[over] = -1
        keep = slot < cap
        self.node = node
        self.slot = np.full(T, -1)
        self.slot[order[keep]] = slot[keep]
        self.b = int(min(max(counts.max(initial=1), 1), cap))
        self.nodes = nodes
        self.border = np.flatnonzero(node < 0)
        self.bpos = np.full(T, -1)
        self.bpos[self.border] = np.arange(self.border.size)

    @staticmethod
    def _cap(counts: np.ndarray, base: int, nodes: int) -> int:
        """Block size that minimizes the work: n b^3 for the blocks plus n b^2 per row moved
        to the border."""
        top = int(counts.max(initial=base))
        best, cost_best = top, np.inf
        for b in range(min(base, top), top + 1):
            moved = int(np.clip(counts - b, 0, None).sum())
            cost = nodes * b**3 + 2.0 * moved * nodes * b**2
            if cost < cost_best:
                best, cost_best = b, cost
        return best

    def flat(self, idx: np.ndarray) -> np.ndarray:
        return self.node[idx] * self.b + self.slot[idx]


def _equilibrate(K: sp.csr_matrix, sweeps: int = 4) -> tuple[np.ndarray, np.ndarray]:
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


class _Posterior:
    """The factorised, bordered KKT matrix and its selected inverse.

    When no row couples two axes at a node (the usual case: items per axis, error-model
    parameters in the border), each axis is its own chain of nodes and the chains are
    laid end to end (blocks of 3 unknowns instead of 3 d): cyclic reduction costs b^3 per
    block, so that is d^2 times cheaper. A row that couples axes (``TrackLine``, a
    ``HalfSpace`` with an oblique normal) makes one chain with all axes per node.
    """

    def __init__(self, ls: LeastSquaresForm, model, hard_to_border: bool = False):
        N, d = model.N, model.d
        n = model.size
        # an explicit zero must not tie a row to a node (a cleaned copy, never the form's own)
        D, E = canonical(ls.D.A), canonical(ls.E.A)
        colaxis = np.full(n, -1, dtype=np.int64)
        for a in range(d):
            colaxis[model.r_index(a)[1:]] = a
            colaxis[model.w_index(a)] = a
            colaxis[model.element_index(a)] = a
        coupled = d > 1 and (model.ns > 0 or any(bool(np.any((hi >= 0) & (hi != lo)))  # a row on two axes
                                                 for lo, hi in (row_span(D, colaxis), row_span(E, colaxis))))
        self.chain = None if coupled or d == 1 else N   # nodes per independent chain
        colnode = np.full(n, -1, dtype=np.int64)
        for a in range(d):
            off = 0 if coupled else a * N
            colnode[model.r_index(a)[1:]] = off + np.arange(1, N)
            colnode[model.w_index(a)] = off + np.arange(N)
            colnode[model.element_index(a)] = off + model.element_nodes()   # a coarse mesh's (bvpnav.mesh)
        if model.ns:   # node states at their node (all axes of a node together: coupled)
            colnode[model.s_index] = model.state_nodes()
        lo, hi = row_span(D, colnode)
        span = hi - lo
        fold = (span <= 1) | (hi < 0)          # into D^T D: couples two neighbouring nodes at most
        rho = np.flatnonzero(~fold)
        Df, Dr = D[np.flatnonzero(fold)], D[rho]
        elo, ehi = row_span(E, colnode)
        # a row on one or two nodes sits at the first (a velocity row at node j restricted
        # to node j is parallel to the FEM row there), a row on three at the middle one
        espan = ehi - elo
        enode = np.where(ehi < 0, -1, np.where(espan <= 1, elo, np.where(espan == 2, elo + 1, -1)))
        fem = ls.eq_blocks[0][1]
        if hard_to_border:  # the fallback: every hard-item row through the Schur complement
            enode[fem.stop:] = -1
        per_axis = np.arange(N)
        enode[fem] = (np.tile(per_axis, d) if coupled
                      else np.concatenate([a * N + per_axis for a in range(d)]))  # FEM row j at node j
        rnode = np.where(span[rho] == 2, lo[rho] + 1, -1)
        nr, p = rho.size, E.shape[0]
        T = n + nr + p
        node = np.concatenate([colnode, rnode, enode])
        extra = np.zeros(T, dtype=np.int64)
        extra[n:] = 2
        extra[n + nr + np.arange(fem.start, fem.stop)] = 1
        self.layout = _Layout(node, extra, N if coupled else d * N, d if coupled else 1)
        H = (Df.T @ Df).tocsr()
        del Df, D
        K = sp.bmat([[H, Dr.T, E.T], [Dr, -sp.identity(nr), None], [E, None, None]], format="csr")
        del H, Dr, E
        self.n = n
        self.first_multiplier = n + nr   # global indices from here on are multipliers
        self.s, rows = _equilibrate(K)
        s = self.s
        i, j, v = rows, K.indices, K.data * s[rows] * s[K.indices]
        del K
        self._assemble(i, j, v)

    def _assemble(self, i: np.ndarray, j: np.ndarray, v: np.ndarray) -> None:
        """Scatter the scaled KKT entries ``(i, j, v)`` into node blocks, border coupling and
        border block; factorise; selected inverse; the border's Schur complement."""
        lay = self.layout
        b, nb, k = lay.b, lay.nodes, lay.border.size
        ni, nj = lay.node[i], lay.node[j]
        Dg = np.zeros((nb, b, b))
        Ub = np.zeros((max(nb - 1, 0), b, b))
        Bk = np.zeros((nb, b, k))
        C = np.zeros((k, k))
        ll = (ni >= 0) & (nj >= 0)
        if np.any(ll & (np.abs(ni - nj) > 1)):
            raise SolveError("uncertainty: internal error, a coupling between distant nodes")
        same = ll & (ni == nj)
        Dg[ni[same], lay.slot[i[same]], lay.slot[j[same]]] = v[same]
        up = ll & (nj == ni + 1)
        Ub[ni[up], lay.slot[i[up]], lay.slot[j[up]]] = v[up]
        lb = (ni >= 0) & (nj < 0)
        Bk[ni[lb], lay.slot[i[lb]], lay.bpos[j[lb]]] = v[lb]
        bb = (ni < 0) & (nj < 0)
        C[lay.bpos[i[bb]], lay.bpos[j[bb]]] = v[bb]
        used = np.zeros((nb, b), dtype=bool)
        loc = np.flatnonzero(lay.node >= 0)
        used[lay.node[loc], lay.slot[loc]] = True
        pn, ps = np.nonzero(~used)
        Dg[pn, ps, ps] = 1.0  # padding: decoupled unit unknowns
        del i, j, v, ni, nj
        c = 1 if self.chain is None else nb // self.chain   # independent chains, factorised together
        m = nb // c
        Ufull = np.concatenate([Ub, np.zeros((1, b, b))])   # boundary blocks between chains are 0
        self.cr = CyclicReduction(Dg.reshape(c, m, b, b), Ufull.reshape(c, m, b, b)[:, :m - 1])
        del Dg, Ub, Ufull
        Zd, Zu = self.cr.selected_inverse()
        self.Zd = Zd.reshape(nb, b, b)
        self.Zu = np.concatenate([Zu, np.zeros((c, 1, b, b))], axis=1).reshape(nb, b, b)[:nb - 1]
        del Zd, Zu
        self.Y = self.cr.solve(Bk.reshape(c, m, b, k)).reshape(nb, b, k) if k else np.zeros((nb, b, 0))
        S = C - np.einsum("nbk,nbl->kl", Bk, self.Y)
        self.redundant = 0
        self.border_cond = 1.0
        if k:
            try:
                Sinv = equilibrated_inverse(S[None])[0]
                scale = symmetric_scale(S)
                self.border_cond = float(np.linalg.cond(S * scale[:, None] * scale[None, :]))
            except np.linalg.LinAlgError:
                Sinv = self._generalized_inverse(S)
        else:
            Sinv = np.zeros((0, 0))
        self.Sinv = 0.5 * (Sinv + Sinv.T)

    def _generalized_inverse(self, S: np.ndarray) -> np.ndarray:
        """A generalized inverse of a singular border block whose null space holds only
        multipliers: hard rows that repeat each other (two average velocities whose sum
        is the end positions). Any generalized inverse gives the same ``x`` block of the
        KKT inverse, so the covariance is exact; a null direction that moves an unknown
        (information that does not determine it) is refused."""
        scale = symmetric_scale(S)
        Ss = S * scale[:, None] * scale[None, :]
        lam, V = np.linalg.eigh(0.5 * (Ss + Ss.T))
        # exactly repeated rows leave eigenvalues at rounding (2e-17 relative on the shuttle
        # sample); nearly repeated ones (an interval ending 1e-4 s from a sample) leave
        # 1e-14: those are kept, and the condition number they give is warned about
        null = np.abs(lam) <= 1e-15 * np.abs(lam).max()
        primal = self.layout.border < self.first_multiplier
        moved = np.abs(V[primal][:, null]).max(initial=0.0) if primal.any() else 0.0
        if moved > 1e-6 or null.all():
            raise np.linalg.LinAlgError("singular border Schur complement: an unknown is not determined")
        self.redundant = int(null.sum())
        kept = np.abs(lam[~null])
        self.border_cond = float(kept.max() / kept.min())
        inv = (V[:, ~null] / lam[~null]) @ V[:, ~null].T
        return inv * scale[:, None] * scale[None, :]

    # ------------------------------------------------------------ queries
    def _split(self, Q: sp.csr_matrix):
        """Scaled query rows as padded local (node, slot, value) arrays, the local rows as a
        sparse matrix over the flat block index, and the border part (dense)."""
        lay = self.layout
        Q = sp.csr_matrix(Q @ sp.diags(self.s[:self.n]))
        Q.eliminate_zeros()
        m = Q.shape[0]
        cols, vals = Q.indices, Q.data
        rows = np.repeat(np.arange(m), np.diff(Q.indptr))
        loc = lay.node[cols] >= 0
        L = sp.csr_matrix((vals[loc], (rows[loc], lay.flat(cols[loc]))), shape=(m, lay.nodes * lay.b))
        Bq = np.zeros((m, lay.border.size))
        Bq[rows[~loc], lay.bpos[cols[~loc]]] = vals[~loc]
        width = int(np.diff(L.indptr).max(initial=0))
        pos = np.arange(L.nnz) - np.repeat(L.indptr[:-1], np.diff(L.indptr))
        lrows = np.repeat(np.arange(m), np.diff(L.indptr))
        nodes = np.zeros((m, width), dtype=np.int64)
        slots = np.zeros((m, width), dtype=np.int64)
        pv = np.zeros((m, width))
        nodes[lrows, pos] = L.indices // lay.b
        slots[lrows, pos] = L.indices % lay.b
        pv[lrows, pos] = L.data
        return (nodes, slots, pv), L, Bq

    def query(self, Q: sp.csr_matrix) -> tuple:
        """Prepare query rows over ``x`` for :meth:`cross` (each row local to two adjacent
        nodes plus any border columns)."""
        padded, L, Bq = self._split(Q)
        u = L @ self.Y.reshape(self.layout.nodes * self.layout.b, -1) - Bq
        return padded, u, u @ self.Sinv

    def cross(self, q1: tuple, q2: tuple) -> np.ndarray:
        """``diag(Q1 Cov Q2^T)`` for two prepared queries (:meth:`query`)."""
        (n1, s1, v1), _, uS1 = q1
        (n2, s2, v2), u2, _ = q2
        a_n, b_n = n1[:, :, None], n2[:, None, :]
        a_s, b_s = s1[:, :, None], s2[:, None, :]
        real = (v1[:, :, None] != 0) & (v2[:, None, :] != 0)
        if self.chain is not None:  # independent chains: no local coupling between them
            real &= (a_n // self.chain) == (b_n // self.chain)
        dn = np.where(real, b_n - a_n, 0)
        if np.any(np.abs(dn) > 1):
            raise SolveError("uncertainty: a query row spans more than two nodes")
        nb = self.layout.nodes
        z = np.where(real & (dn == 0), self.Zd[a_n, a_s, b_s], 0.0)
        if nb > 1:
            top = nb - 2
            z = np.where(dn == 1, self.Zu[np.clip(a_n, 0, top), a_s, b_s], z)
            z = np.where(dn == -1, self.Zu[np.clip(b_n, 0, top), b_s, a_s], z)
        local = np.einsum("mi,mij,mj->m", v1, z, v2)
        return local + np.einsum("mk,mk->m", uS1, u2)

    def params(self, l_index: np.ndarray) -> np.ndarray:
        """Covariance of unknowns that are all in the border (the error-model parameters)."""
        pos = self.layout.bpos[l_index]
        if np.any(pos < 0):
            raise SolveError("uncertainty: internal error, a parameter is not in the border")
        s = self.s[l_index]
        return s[:, None] * self.Sinv[np.ix_(pos, pos)] * s[None, :]


def _factored(ls: LeastSquaresForm, model, what: str) -> tuple[_Posterior, int]:
    """The :class:`_Posterior` of ``ls`` and the hard-item rows it moved into the border (0, or
    all of them when a run of nodes is singular without them); ``what`` names the caller in the
    errors.

    Raises
    ------
    InputError
        When the hard rows are too many for the border, or the KKT matrix is singular."""
    hard_rows = int(ls.E.m - ls.eq_blocks[0][1].stop)
    try:
        try:
            return _Posterior(ls, model), 0
        except np.linalg.LinAlgError:
            # hard items that fix a stretch of the trajectory on their own (a hard
            # zero-velocity interval) can make a run of nodes singular by itself: their rows
            # then go through the border's Schur complement, which stays exact
            if hard_rows > MAX_BORDER_ROWS:
                raise InputError(
                    f"{what}: {hard_rows} hard-item rows fix stretches of the trajectory on "
                    f"their own, more than the {MAX_BORDER_ROWS} the O(N) covariance can take "
                    "through its border: give the long hard items (zero-velocity intervals) "
                    "mode='soft' with a small sigma (e.g. sigma=1e-3 m/s), or solve without "
                    f"{what}") from None
            return _Posterior(ls, model, hard_to_border=True), hard_rows
    except np.linalg.LinAlgError as exc:
        raise InputError(f"{what}: the covariance does not exist ({exc}): the information "
                         "does not determine every unknown. Add position or velocity "
                         f"information, or solve without {what}") from exc


def posterior(form: Formulation, x: np.ndarray, lam: float) -> Covariance:
    """The covariance of the estimate ``x`` of ``form`` at ``lam`` (see the module Notes).

    Parameters
    ----------
    form : Formulation
    x : ndarray
        The solution (stacked unknowns); it chooses the active rows of a quadratic model.
    lam : float
        The weight the soft items had.

    Returns
    -------
    Covariance

    Raises
    ------
    InputError
        When the information does not determine every unknown (the KKT matrix is
        singular), naming what to add.
    """
    model = form.model
    ls, exact = quadratic_model(form, x, lam)
    post, moved = _factored(ls, model, "uncertainty")
    d = model.d
    queries = [post.query(model.node_position(a).A) for a in range(d)]
    queries += [post.query(model.node_velocity(a).A) for a in range(d)]
    state = np.empty((model.N, 2 * d, 2 * d))
    for i in range(2 * d):
        for k in range(i, 2 * d):
            c = post.cross(queries[i], queries[k])
            state[:, i, k] = c
            state[:, k, i] = c
    params = post.params(model.l_index) if model.q else np.zeros((0, 0))
    states = None
    if model.ns:
        states = {}
        for kind in model.state_model.state_kinds(model.data):
            cols = []
            for ax in ("x", "y", "z"):
                q = post.query(model.states(kind, axes=ax).A)
                cols.append(post.cross(q, q))
            states[kind] = np.column_stack(cols)
    resid = ls.D.value(x)
    dof = int(ls.D.m - model.size + ls.E.m - post.redundant)  # independent hard rows only
    vf = float(resid @ resid / dof) if dof > 0 else float("nan")
    return Covariance(state=state, params=params, variance_factor=vf, dof=dof, exact=exact,
                      border=int(post.layout.border.size), block=int(post.layout.b),
                      hard_rows_in_border=moved, border_condition=post.border_cond,
                      pivot_condition=post.cr.pivot_condition, states=states)


#: The group of the data rows (the acceleration residuals over ``sigma_a``) in :func:`redundancy`.
DATA_GROUP = "acceleration residual"


def redundancy(form: Formulation, x: np.ndarray, lam: float) -> dict[str, tuple[int, float, float]]:
    r"""Each group of objective rows' redundancy and weighted square sum at the estimate ``x``.

    Parameters
    ----------
    form : Formulation
        An equality-constrained least-squares problem (no band, inequality or robust item).
    x : ndarray
        The solution (stacked unknowns).
    lam : float
        The weight the soft items had.

    Returns
    -------
    dict of str to (int, float, float)
        Per group, the rows :math:`m_g`, the redundancy :math:`r_g` (dimensionless) and the
        weighted residual square sum :math:`\Omega_g = \|D_g \hat x + c_g\|^2`; the groups are
        :data:`DATA_GROUP` (the acceleration residuals) and each soft item's and prior's label
        (items of one label summed). The redundancies add up to the degrees of freedom.

    Raises
    ------
    InputError
        When the problem is not least squares.

    Notes
    -----
    With the whitened rows :math:`D` and the covariance :math:`C = (K^{-1})_{xx}` of the module
    Notes, the hat matrix of the rows is :math:`H = D C D^T` and a group's redundancy is

    .. math:: r_g = m_g - \operatorname{tr}(D_g C D_g^T),

    the diagonal of :math:`D_g C D_g^T` from the selected inverse in O(N). Variance component
    estimation (Helmert; Foerstner's iteration) rescales each group's variances by
    :math:`\Omega_g / r_g` and solves again until every ratio is 1: the noise of each group
    estimated from its own residuals. For linearized items it is the last linearization's.
    :math:`\Omega_g` is dimensionless (whitened rows); a soft item's rows carry the weight
    ``lam``, so the iteration on them estimates :math:`\sigma^2/\lambda`: hold ``lam`` fixed (a
    number, not a rule) or rescale by it. Rows that reach more than two neighbouring nodes (an
    average over an interval, a velocity between samples) are refused; like :func:`posterior`,
    a run of nodes fixed by hard items alone goes through the border.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav import ImuData, NavigationProblem
    >>> from bvpnav.constraints import Position
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> rng = np.random.default_rng(0)
    >>> prob = NavigationProblem(ImuData(t, rng.normal(0.0, 0.01, (101, 1)), axes=("x",)), sigma_a=0.01)
    >>> p = [[0.0], [0.1], [0.0], [-0.1], [0.0]]
    >>> fixes = Position(t=[0.0, 2.5, 5.0, 7.5, 10.0], value=p, sigma=0.1, name="fixes")
    >>> _ = prob.add(fixes)
    >>> sol = prob.solve(solver="direct")
    >>> red = redundancy(sol.formulation, sol.x, sol.lam)
    >>> {k: round(r, 2) for k, (m, r, _) in red.items()}
    {'acceleration residual': 0.02, 'fixes': 2.98}
    """
    ls = least_squares_form(form, lam)
    if ls is None:
        raise InputError("redundancy: the problem is not least squares (a band, inequality or robust item); "
                         "the redundancies exist for soft and hard equality items only")
    groups = [(DATA_GROUP, form.data_rows().m)]
    groups += [(t.label, t.residual.m) for t in form.terms() if t.least_squares_role() == "D"]
    post, _ = _factored(ls, form.model, "redundancy")
    res = ls.D.value(np.asarray(x, dtype=float))
    out: dict[str, tuple[int, float, float]] = {}
    start = 0
    for label, m in groups:
        try:
            h = post.cross(*[post.query(ls.D.A[start:start + m])] * 2) if m else np.zeros(0)
        except SolveError as exc:   # a row over more than two neighbouring nodes
            raise InputError(f"redundancy: the rows of {label!r} reach more than two neighbouring "
                             "nodes (an average or a velocity between samples over a longer "
                             "span), whose redundancy the O(N) selected inverse does not give; "
                             "place them at samples, make them hard, or leave the item out") from exc
        r = res[start:start + m]
        m0, r0, o0 = out.get(label, (0, 0.0, 0.0))
        out[label] = (m0 + m, r0 + m - float(h.sum()), o0 + float(r @ r))
        start += m
    return out
