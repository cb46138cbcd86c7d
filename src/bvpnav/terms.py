"""Compiled information: the :class:`Term` and the one table of what a mode means per kind.

An item compiles to a residual (an :class:`~bvpnav.model.Affine` map of the stacked
unknowns, or a :class:`~bvpnav.model.Cone`); the problem turns it into a :class:`Term`
with a *mode* (``hard``, ``soft``, ``robust``, ``band``) and a *kind* (``equality``
``D x - e = 0``, ``inequality`` ``g(x) <= 0``, ``cone`` ``||u_k|| <= s_k``). What the
4 x 3 combinations mean is written here once, in one class per kind, and every reader
asks the term:

=================  ======================  ==========================  ==========================
mode               equality ``r``          inequality ``g``            cone excess ``e_k``
=================  ======================  ==========================  ==========================
hard               ``r = 0``               ``g <= 0``                  ``||u_k|| <= s_k``
band               ``|r| <= tol``          ``g <= tol``                ``||u_k|| <= s_k + tol_k``
band with sigma    ``lam sum (pos(|r| -    ``lam sum (pos(g - tol)     (refused)
                   tol)/s)^2``             /s)^2``
soft               ``lam sum (r/s)^2``     ``lam sum (pos(g)/s)^2``    ``lam sum (pos(e)/s)^2``
robust             ``lam sum huber/|.|``   ``lam sum pos(g)/s``        ``lam sum pos(e)/s``
=================  ======================  ==========================  ==========================

(``lam`` multiplies items; error-model priors and bounds are not scaled by it.) A band with a
``sigma`` has soft edges: nothing inside it, the excess beyond it squared (:attr:`Term.soft_edges`),
so it is a penalty, not a constraint. Each kind
answers: its cvxpy constraints and penalty (:meth:`TermKind.constraints`,
:meth:`TermKind.penalty`), the violation that verification measures, the gradient of its
part of the Lagrangian (stationarity), the rows it shows in a solution, its role in the
least-squares view (:meth:`Term.least_squares_role`) and how :func:`bvpnav.describe.describe`
writes it. cvxpy is imported by the lowering methods only, on first use: the direct back
ends, verification and ``import bvpnav`` never load it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

from .model import Affine
from .sparse import abs_max, as_csr

if TYPE_CHECKING:
    import cvxpy as cp

__all__ = ["Term", "TermKind", "KINDS", "MODES", "CONSTRAINT_MODES", "PENALTY_MODES", "band_excess"]

MODES = ("hard", "soft", "robust", "band")
#: Modes that compile to constraints, and modes that compile to lambda-weighted penalties.
CONSTRAINT_MODES = ("hard", "band")
PENALTY_MODES = ("soft", "robust")


@dataclass(eq=False)
class Term:
    """One compiled piece of information.

    Attributes
    ----------
    label : str
    item : Item or None
        ``None`` for terms the problem itself adds (error-model priors and bounds).
    residual : Affine
        ``D x - e`` in the item's units (for inequalities: ``g`` with ``g <= 0``; for
        cones a :class:`~bvpnav.model.Cone`).
    mode : str
        ``hard``, ``soft``, ``robust`` or ``band``.
    kind : str
        ``equality``, ``inequality`` or ``cone``.
    sigma, tol : ndarray or None
        Per-row standard deviation and band half-width, item units.
    huber : float or None
        Huber threshold in item units (robust mode); ``None`` means L1.
    scaled_by_lam : bool
        Whether the term is multiplied by ``lam`` (items: yes; priors: no).
    units : str
        Units of the residual rows.
    """

    label: str
    item: Any
    residual: Affine
    mode: str
    kind: str = "equality"
    sigma: np.ndarray | None = None
    tol: np.ndarray | None = None
    huber: float | None = None
    scaled_by_lam: bool = True
    units: str = ""

    # ------------------------------------------------------------ the table
    @property
    def table(self) -> TermKind:
        """The kind's entry of the mode x kind table."""
        return KINDS[self.kind]

    @property
    def soft_edges(self) -> bool:
        """A band with a ``sigma``: free within ``tol``, the excess beyond it a soft penalty."""
        return self.mode == "band" and self.sigma is not None

    @property
    def is_constraint(self) -> bool:
        """Hard or band (without soft edges): compiled to constraints (verified as violations)."""
        return self.mode in CONSTRAINT_MODES and not self.soft_edges

    @property
    def is_penalty(self) -> bool:
        """Soft, robust or a band with soft edges: a penalty in the objective."""
        return self.mode in PENALTY_MODES or self.soft_edges

    def excess(self, x: np.ndarray) -> np.ndarray:
        r"""A band with soft edges: how far each row lies beyond the band at ``x``, signed
        (:math:`\operatorname{sign}(r) \max(|r| - tol, 0)` for an equality, :math:`\max(g - tol,
        0)` for an inequality), item units."""
        return band_excess(self.residual.value(x), self.tol, self.kind)

    def weight(self, lam: float) -> float:
        """The factor of this term's penalty: ``lam`` for items, 1 for priors."""
        return float(lam) if self.scaled_by_lam else 1.0

    def least_squares_role(self, surrogate: bool = False) -> str | None:
        """Where the term goes in the least-squares view: ``"E"`` (equality rows),
        ``"D"`` (objective rows) or None (not a least-squares row).

        Only equality terms are rows: hard ones equality rows, soft ones objective rows.
        With ``surrogate`` (the conditioning estimate, which may err towards less
        information) robust equalities count as soft and bands and other kinds are left
        out (``None``) instead of making the view impossible.
        """
        if self.kind != "equality":
            return None
        if self.mode == "hard":
            return "E"
        if self.mode == "soft" or (surrogate and self.mode == "robust"):
            return "D"
        return None

    def quadratic_rows(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r"""Rows of this term in its quadratic model at ``x`` (the view of the covariance).

        Returns
        -------
        held, squared : ndarray of int
            Rows held as equalities (hard equalities; active inequalities and band edges;
            an L1 penalty at its kink) and rows that enter squared with weight
            :math:`\sqrt{w}/\sigma` (soft rows; Huber rows inside the threshold; soft
            inequalities that are violated). Other rows have no curvature at ``x``.

        Notes
        -----
        A row counts as active when it is within ``1e-6 (|A| |x| + |c|)`` of its bound.
        Cones are left out (they can only add information).
        """
        return self.table.quadratic_rows(self, x)

    def constraints(self, r: cp.Expression) -> list:
        """cvxpy constraints of this term given its lowered residual ``r``."""
        return self.table.constraints(self, r) if self.is_constraint else []

    def penalty(self, r: cp.Expression) -> cp.Expression | None:
        """cvxpy penalty (without ``lam``) of this term, or None for constraints."""
        return self.table.penalty(self, r) if self.is_penalty else None

    def violation(self, x: np.ndarray) -> np.ndarray | None:
        """Non-negative violation per row of a constraint term at ``x`` (item units),
        None for penalty terms."""
        return self.table.violation(self, x) if self.is_constraint else None

    def gradient(self, x: np.ndarray, lam: float, duals) -> np.ndarray | None:
        """Gradient of this term's part of the Lagrangian at ``x``; None where it is not
        smooth or the duals it needs are missing (stationarity cannot be judged)."""
        return self.table.gradient(self, x, lam, duals)

    def gradient_rows(self, x: np.ndarray, lam: float, duals) -> np.ndarray | None:
        """The weights ``u`` on this term's rows whose product ``A^T u`` with its residual's
        matrix is :meth:`gradient` (None where that is None): the verification adds
        ``A^T u`` on ``A``'s columns alone (:func:`transposed_product`)."""
        return self.table.gradient_rows(self, x, lam, duals)

    def shown(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(raw, shown)``: the residual rows at ``x`` and what a solution reports of
        them (for inequalities and cones only the violation ``max(., 0)``)."""
        return self.table.shown(self, x)

    def gradient_floor(self, x: np.ndarray, lam: float) -> float:
        """The size this penalty's gradient would have if its residual were as large as
        the terms that cancel in it (``|A| |x| + |c|``); 0 for constraints."""
        if not self.is_penalty or self.sigma is None:
            return 0.0
        # |A| |x| + |c| per row (Affine.row_scale) and |A|^T w on the stored entries of A, summed
        # in their order as the CSR products do (no |A| matrix made)
        A = as_csr(self.residual.A)
        rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
        absA = np.abs(A.data)
        size = np.bincount(rows, weights=absA * np.abs(x[A.indices]), minlength=A.shape[0])
        size += np.abs(self.residual.c)
        if self.mode == "robust" and self.huber is not None:
            size = np.minimum(size, self.huber)
        w = size * (2.0 * self.weight(lam) / self.sigma**2)   # the weights on the rows
        absA *= w[rows]   # |A| weighted by rows, in place (one array of the stored entries)
        return abs_max(_column_sums(A.indices, absA, A.shape[1])[1])


def band_excess(r: np.ndarray, tol, kind: str) -> np.ndarray:
    r"""How far rows ``r`` lie beyond a band of half-width ``tol`` (item units): signed,
    :math:`\operatorname{sign}(r) \max(|r| - tol, 0)`, for an equality; :math:`\max(r - tol, 0)`
    for an inequality (``kind``); 0 inside the band.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.terms import band_excess
    >>> band_excess(np.array([-0.3, 0.05, 0.25]), 0.1, "equality").round(2).tolist()
    [-0.2, 0.0, 0.15]
    """
    if kind == "inequality":
        return np.maximum(r - tol, 0.0)
    return np.sign(r) * np.maximum(np.abs(r) - tol, 0.0)


def transposed_product(A: sp.spmatrix, u: np.ndarray) -> tuple[np.ndarray | slice, np.ndarray]:
    """``A^T u`` on the columns ``A`` touches: ``(cols, values)``, the product being
    ``values`` at ``cols`` and zero elsewhere.

    A few rows (an item's) touch a few columns: their sums are formed there alone instead
    of a vector of every unknown (48 MB each for three axes at N = 1e6). A matrix with
    entries in more than an eighth of its columns gives ``(slice(None), A^T u)``.
    """
    A = A.tocsr() if A.format != "csr" else A
    rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    return _column_sums(A.indices, A.data * u[rows], A.shape[1])


def _column_sums(cols: np.ndarray, values: np.ndarray, n: int) -> tuple[np.ndarray | slice, np.ndarray]:
    """The sums of ``values`` by column ``cols`` (a CSR matrix's stored entries, in their order: the
    sums of its transposed product, in the order it adds them) as :func:`transposed_product`
    returns them: on the columns that occur, or on all ``n`` when more than an eighth occur."""
    if cols.size * 8 > n:
        return slice(None), np.bincount(cols, weights=values, minlength=n).astype(float, copy=False)
    touched, at = np.unique(cols, return_inverse=True)
    return touched, np.bincount(at.ravel(), weights=values, minlength=touched.size)


class TermKind:
    """One kind's column of the mode x kind table (see the module docstring)."""

    name = ""

    def constraints(self, term: Term, r: cp.Expression) -> list:
        raise NotImplementedError

    def penalty(self, term: Term, r: cp.Expression) -> cp.Expression:
        raise NotImplementedError

    def violation(self, term: Term, x: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def gradient(self, term: Term, x: np.ndarray, lam: float, duals) -> np.ndarray | None:
        u = self.gradient_rows(term, x, lam, duals)
        return None if u is None else term.residual.A.T @ u

    def gradient_rows(self, term: Term, x: np.ndarray, lam: float, duals) -> np.ndarray | None:
        """See :meth:`Term.gradient_rows`."""
        raise NotImplementedError

    def shown(self, term: Term, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r = term.residual.value(x)
        return r, np.maximum(r, 0)

    def relation(self, term: Term, tol_text: str) -> str:
        """The constraint's relation as text, e.g. ``= 0`` or ``|.| <= 0.1 m``."""
        raise NotImplementedError

    def quadratic_rows(self, term: Term, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """See :meth:`Term.quadratic_rows`."""
        none = np.zeros(0, dtype=int)
        return none, none

    def penalty_symbol(self, term: Term) -> str:
        """The penalty's symbol in :func:`bvpnav.describe.describe`."""
        if term.soft_edges:
            return "pos(. - tol)^2"
        return "pos(.)" if term.mode == "robust" else "pos(.)^2"


def _active_tol(term: Term, x: np.ndarray) -> np.ndarray:
    """How close to its bound a row must be to count as active at ``x`` (item units)."""
    return 1e-6 * np.maximum(term.residual.row_scale(x), 1e-300)


def _constraint_rows(duals, band_pair: bool) -> np.ndarray | None:
    """A constraint's gradient weights on its rows: its duals (a band's pair subtracted)."""
    if not duals or any(d is None for d in duals):
        return None
    z = np.asarray(duals[0], dtype=float).ravel()
    if band_pair:
        z = z - np.asarray(duals[1], dtype=float).ravel()
    return z


class Equality(TermKind):
    """``r = D x - e``: hard ``r = 0``, band ``|r| <= tol``, soft squares, robust Huber/L1."""

    name = "equality"

    def constraints(self, term, r):
        return [r == 0] if term.mode == "hard" else [r <= term.tol, -r <= term.tol]

    def penalty(self, term, r):
        import cvxpy as cp

        if term.soft_edges:
            return cp.sum_squares(cp.multiply(1.0 / term.sigma, cp.pos(cp.abs(r) - term.tol)))
        if term.mode == "soft":
            return cp.sum_squares(cp.multiply(1.0 / term.sigma, r))
        if term.huber is None:
            return cp.norm1(cp.multiply(1.0 / term.sigma, r))
        return cp.sum(cp.multiply(1.0 / term.sigma**2, cp.huber(r, term.huber)))

    def violation(self, term, x):
        r = term.residual.value(x)
        return np.abs(r) if term.mode == "hard" else np.maximum(np.abs(r) - term.tol, 0)

    def gradient_rows(self, term, x, lam, duals):
        k = term.weight(lam)
        if term.soft_edges:
            return term.excess(x) * (2.0 * k / term.sigma**2)
        if term.mode == "soft":
            return term.residual.value(x) * (2.0 * k / term.sigma**2)
        if term.mode == "robust":
            if term.huber is None:
                return None
            r = term.residual.value(x)
            g = np.where(np.abs(r) <= term.huber, 2.0 * r, 2.0 * term.huber * np.sign(r))
            return g * (k / term.sigma**2)
        return _constraint_rows(duals, band_pair=term.mode == "band")

    def shown(self, term, x):
        r = term.residual.value(x)
        return r, r

    def relation(self, term, tol_text):
        return "= 0" if term.mode == "hard" else f"|.| <= {tol_text} {term.units}"

    def quadratic_rows(self, term, x):
        r, atol = term.residual.value(x), _active_tol(term, x)
        every = np.arange(r.size)
        if term.mode == "hard":
            return every, every[:0]
        if term.mode == "soft":
            return every[:0], every
        if term.soft_edges:
            return every[:0], np.flatnonzero(np.abs(r) > term.tol + atol)
        if term.mode == "band":
            return np.flatnonzero(np.abs(r) >= term.tol - atol), every[:0]
        if term.huber is None:  # L1: only its kink holds a row
            return np.flatnonzero(np.abs(r) <= atol), every[:0]
        return every[:0], np.flatnonzero(np.abs(r) <= term.huber)

    def penalty_symbol(self, term):
        if term.mode == "robust":
            return "huber" if term.huber else "|.|"
        if term.soft_edges:
            return "pos(|.| - tol)^2"
        return "(.)^2"


class Inequality(TermKind):
    """``g(x) <= 0``: hard, band ``g <= tol``, soft ``pos(g)^2``, robust ``pos(g)``."""

    name = "inequality"

    def constraints(self, term, r):
        return [r <= 0] if term.mode == "hard" else [r <= term.tol]

    def penalty(self, term, r):
        import cvxpy as cp

        if term.soft_edges:
            return cp.sum_squares(cp.multiply(1.0 / term.sigma, cp.pos(r - term.tol)))
        if term.mode == "soft":
            return cp.sum_squares(cp.multiply(1.0 / term.sigma, cp.pos(r)))
        return cp.sum(cp.multiply(1.0 / term.sigma, cp.pos(r)))

    def violation(self, term, x):
        r = term.residual.value(x)
        return np.maximum(r - (term.tol if term.mode == "band" else 0.0), 0)

    def gradient_rows(self, term, x, lam, duals):
        if term.soft_edges:
            return term.excess(x) * (2.0 * term.weight(lam) / term.sigma**2)
        if term.mode == "soft":
            return np.maximum(term.residual.value(x), 0) * (2.0 * term.weight(lam) / term.sigma**2)
        if term.mode == "robust":
            return None
        return _constraint_rows(duals, band_pair=False)

    def relation(self, term, tol_text):
        return "<= 0" if term.mode == "hard" else f"<= {tol_text} {term.units}"

    def quadratic_rows(self, term, x):
        g, atol = term.residual.value(x), _active_tol(term, x)
        none = np.zeros(0, dtype=int)
        if term.mode == "soft":
            return none, np.flatnonzero(g > atol)
        if term.soft_edges:
            return none, np.flatnonzero(g > term.tol + atol)
        bound = term.tol if term.mode == "band" else 0.0
        if term.mode == "robust":  # pos(g): its kink at g = 0
            return np.flatnonzero(np.abs(g) <= atol), none
        return np.flatnonzero(g >= bound - atol), none


class SecondOrderCone(TermKind):
    r"""Groups ``(s_k, u_k)`` with excess ``e_k = ||u_k|| - s_k``: hard ``e_k <= 0``, band
    ``e_k <= tol_k``, soft ``sum pos(e_k)^2 / sigma_k^2``, robust ``sum pos(e_k) / sigma_k``.

    Notes
    -----
    cvxpy's SOC duals ``(mu, Y)`` enter the Lagrangian as :math:`-(\mu s + \langle Y, U\rangle)`.
    """

    name = "cone"

    def _split(self, term, r):
        import cvxpy as cp

        k = term.residual.size
        R = cp.reshape(r, (k, term.residual.groups), order="F")
        return k, R[0, :], R[1:, :]

    def constraints(self, term, r):
        import cvxpy as cp

        k, s, U = self._split(term, r)
        if term.mode == "hard":
            return [cp.SOC(s, U, axis=0)]
        return [cp.SOC(s + term.tol[::k], U, axis=0)]

    def penalty(self, term, r):
        import cvxpy as cp

        k, s, U = self._split(term, r)
        excess = cp.pos(cp.norm(U, 2, axis=0) - s)
        w = 1.0 / term.sigma[::k]
        if term.mode == "soft":
            return cp.sum_squares(cp.multiply(w, excess))
        return cp.sum(cp.multiply(w, excess))

    def violation(self, term, x):
        k = term.residual.size
        return np.maximum(term.residual.excess(x) - (term.tol[::k] if term.mode == "band" else 0.0), 0)

    def shown(self, term, x):
        e = term.residual.excess(x)
        return e, np.maximum(e, 0)

    def gradient_rows(self, term, x, lam, duals):
        u = self._rows(term, x, duals)
        return None if u is None else (term.weight(lam) * u if term.is_penalty else u)

    def _rows(self, term, x, duals):
        res = term.residual
        k = res.size
        if term.mode in ("hard", "band"):
            if not duals or duals[0] is None:
                return None
            mu, Y = duals[0]
            z = np.column_stack([np.asarray(mu, dtype=float).ravel(),
                                 np.asarray(Y, dtype=float).reshape(k - 1, -1).T]).ravel()
            return -z
        if term.mode == "robust":
            return None
        v = res.value(x).reshape(res.groups, k)
        nu = np.linalg.norm(v[:, 1:], axis=1)
        e = np.maximum(nu - v[:, 0], 0.0)
        if np.any((e > 0) & (nu == 0)):
            return None
        coef = 2.0 * e / term.sigma[::k] ** 2
        dz = np.zeros_like(v)
        on = e > 0
        dz[on, 1:] = coef[on, None] * v[on, 1:] / nu[on, None]
        dz[on, 0] = -coef[on]
        return dz.ravel()

    def relation(self, term, tol_text):
        rel = "<= 0" if term.mode == "hard" else f"<= {tol_text} {term.units}"
        return rel + ", second-order cone per node"


#: The table: kind name -> its column.
KINDS: dict[str, TermKind] = {k.name: k for k in (Equality(), Inequality(), SecondOrderCone())}
