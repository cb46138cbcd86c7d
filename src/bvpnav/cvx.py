"""Terms -> one DPP cvxpy problem with the ``lam`` Parameter, and its culprit checks.

:func:`build` lowers a :class:`~bvpnav.formulation.Formulation` once: the FEM rows and the
hard items become constraints, the data term and the soft and robust items the objective
(the latter times ``lam``, one ``cp.Parameter``), each term through its row of the mode x
kind table (:mod:`bvpnav.terms`). The framework, not the plug-in, checks that the result
is DCP and DPP and names the culprit item. :func:`conflicting_items` finds which hard
items cannot hold together (a deletion filter over feasibility problems built from the
very same constraints). cvxpy is imported by :func:`build` and the feasibility checks on
first use, not with this module.

A solver's "infeasible" is a claim, not a proof: :func:`certificate` checks the Farkas
certificate the solver left in the constraints' duals against bvpnav's own rows, and a
verdict counts only when that certificate rules out every answer of a plausible size
(:class:`Certificate`); the deletion filter accepts only verdicts confirmed this way.
"""

from __future__ import annotations

import warnings
import weakref
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import ConvexityError
from .formulation import Formulation
from .model import Affine

if TYPE_CHECKING:
    import cvxpy as cp

__all__ = ["CvxProblem", "lower", "build", "compiled", "current_lam", "conflicting_items", "Certificate",
           "certificate", "CERTIFICATE_FACTOR"]

#: The value of the ``lam`` Parameter when :func:`build` creates it.
INITIAL_LAM = 1.0


def lower(rows: Affine, x: cp.Expression) -> cp.Expression:
    """The cvxpy expression ``A @ x + c`` of an affine map."""
    if not rows.c.any():
        return rows.A @ x
    return rows.A @ x + rows.c


@dataclass(eq=False)
class CvxProblem(Mapping):
    """The compiled cvxpy problem and its parts.

    Attributes
    ----------
    problem : cvxpy.Problem
    lam : cvxpy.Parameter
        The regularization weight (dimensionless, non-negative).
    x : cvxpy.Variable
        The stacked unknowns (see :class:`bvpnav.model.NavModel`).
    fem : cvxpy.Constraint
        The FEM equations.
    fem_rows : Affine
    cons : dict of str to list
        Item label -> its constraints (empty for penalty terms).
    penalties : list of (Term, cvxpy.Expression)
        Each penalty term with its penalty before ``lam``.
    equality_qp : bool
        Whether every term is a hard or soft equality (an equality-constrained least
        squares problem: no inequalities, bands, robust items or cones). Then the data
        term is a quadratic form of ``x`` itself (see :func:`data_term`) and the Clarabel
        back end solves without equilibration (see :mod:`bvpnav.backends.cvxpy_solvers`).
    """

    problem: cp.Problem
    lam: cp.Parameter
    x: cp.Variable
    fem: Any
    fem_rows: Affine
    cons: dict = field(default_factory=dict)
    penalties: list = field(default_factory=list)
    equality_qp: bool = False

    def __getitem__(self, key: str) -> Any:
        """Dictionary-style access (``build()["problem"]``), as in earlier releases."""
        if key not in self._names():
            raise KeyError(key)
        return getattr(self, key)

    def _names(self) -> list[str]:
        return [f.name for f in fields(self)]

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())

    def __len__(self) -> int:
        return len(self._names())

    def duals(self) -> dict:
        """``{"fem": y, label: [y per constraint]}`` after a solve (cvxpy's sign convention)."""
        out = {"fem": self.fem.dual_value}
        for label, lst in self.cons.items():
            out[label] = [c.dual_value for c in lst]
        return out


def data_term(rows: Affine, x: cp.Variable, quadratic_form: bool) -> cp.Expression:
    """The data term ``||A x + c||^2``.

    With ``quadratic_form`` and ``c = 0`` (the acceleration form: ``A`` picks and scales
    the residuals ``w``) it is ``quad_form(x, A^T A)`` of the variable itself, which cvxpy
    hands to the solver as the quadratic objective ``P`` directly; ``sum_squares`` of the
    expression ``A x`` instead makes cvxpy add one auxiliary variable and one equality row
    per residual (N per axis: the solver's KKT system was 5N instead of 3N rows per axis).
    Only for equality-constrained problems: with Clarabel's equilibration on (problems
    with inequalities), a DPP re-solve of this form through Clarabel's in-place update came
    back ``optimal_inaccurate`` (measured, N = 1e5, clarabel 0.11.1).
    """
    import cvxpy as cp

    if quadratic_form and not rows.c.any():
        return cp.quad_form(x, (rows.A.T @ rows.A).tocsr(), assume_PSD=True)
    return cp.sum_squares(lower(rows, x))


def build(form: Formulation) -> CvxProblem:
    """Lower a formulation to one DPP cvxpy problem (see the module docstring).

    Raises
    ------
    ConvexityError
        Naming the item whose penalty is not DCP, or not DPP in ``lam``.
    """
    import cvxpy as cp

    model = form.model
    x = cp.Variable(model.size, name="x")
    lam = cp.Parameter(nonneg=True, value=INITIAL_LAM, name="lam")
    fem_rows = model.fem_rows()
    fem_con = lower(fem_rows, x) == 0
    equality_qp = all(t.least_squares_role() in ("E", "D") for t in form.terms())
    objective = data_term(form.data_rows(), x, equality_qp)
    cons: dict[str, list] = {}
    penalties = []
    for term in form.terms():
        r = lower(term.residual, x)
        cons[term.label] = term.constraints(r)
        pen = term.penalty(r)
        if pen is not None:
            penalties.append((term, pen))
    for term, pen in penalties:
        if not pen.is_convex():  # pragma: no cover - built from convex atoms
            raise ConvexityError(f"{term.label}: its penalty is not convex")
        objective = objective + (lam * pen if term.scaled_by_lam else pen)
    prob = cp.Problem(cp.Minimize(objective), [fem_con] + [c for lst in cons.values() for c in lst])
    if not prob.is_dcp():
        bad = [t.label for t, p in penalties if not p.is_dcp()]
        raise ConvexityError(f"the problem is not DCP; culprit item(s): {bad or 'unknown'}")
    if not prob.is_dpp():
        bad = [t.label for t, p in penalties if not (lam * p).is_dpp()]
        raise ConvexityError(f"the problem is not DPP in lam; culprit item(s): {bad or 'unknown'}")
    return CvxProblem(problem=prob, lam=lam, x=x, fem=fem_con, fem_rows=fem_rows, cons=cons,
                      penalties=penalties, equality_qp=equality_qp)


#: Each formulation's lowering, built on first use and kept as long as the formulation
#: lives (weakly keyed: nothing here keeps a formulation alive, and a pickled formulation
#: carries no cvxpy objects). Only this module reads and writes it.
_COMPILED: weakref.WeakKeyDictionary[Formulation, CvxProblem] = weakref.WeakKeyDictionary()


def compiled(form: Formulation) -> CvxProblem:
    """The formulation's cvxpy problem, built on first use and kept while the formulation
    lives (DPP: a new ``lam`` re-uses it)."""
    cvx = _COMPILED.get(form)
    if cvx is None:
        cvx = _COMPILED[form] = build(form)
    return cvx


def is_compiled(form: Formulation) -> bool:
    """Whether the formulation's cvxpy problem has been built."""
    return form in _COMPILED


def current_lam(form: Formulation) -> float:
    """The ``lam`` Parameter's current value (the last cvxpy solve's), without building the
    problem: :data:`INITIAL_LAM` while it is not built."""
    cvx = _COMPILED.get(form)
    return INITIAL_LAM if cvx is None else float(cvx.lam.value)


#: A certificate confirms infeasibility when the box it rules out is at least this many
#: times the problem's own scale (:attr:`Certificate.scale`).
CERTIFICATE_FACTOR = 10.0


@dataclass(frozen=True)
class Certificate:
    r"""A solver's infeasibility certificate, checked against bvpnav's own rows.

    Attributes
    ----------
    radius : float
        No stacked answer ``x`` with :math:`\|x\|_\infty <` ``radius`` satisfies the
        constraints (FEM equations and the hard, band and cone items checked): proved by
        the multipliers alone, in the units of the unknowns (m, m/s, m/s^2, ...).
    scale : float
        The problem's own scale: the largest of 1, the stated values and tolerances of
        the hard items ``C`` and the largest acceleration ``A`` (m/s^2) over the window
        ``T`` (s) as ``C/T``, ``C/T^2``, ``A``, ``A T``, ``A T^2``. A plausible answer has
        no unknown beyond it by orders of magnitude.
    support : tuple of str
        The items whose multipliers carry the certificate (largest first).

    Notes
    -----
    With multipliers ``y`` (equalities, free), ``nu >= 0`` (inequalities and bands,
    ``r <= tol``) and ``(mu, Y)`` in the second-order cone (cones, ``(s + tol, U)`` in
    the cone), every feasible ``x`` has

    .. math:: g^T x + \gamma \le 0, \quad g = \sum_k A_k^T u_k, \quad
              \gamma = \sum_k (c_k^T u_k - t_k)

    (``u = y``, ``nu``, ``nu_+ - nu_-`` or ``-(mu, Y)`` per row, ``t`` the multipliers
    times the tolerances), so :math:`\gamma > 0` proves
    :math:`\|x\|_\infty \ge \gamma / \|g\|_1`: the :attr:`radius`. The solver's
    duals are taken with either sign, projected onto their cones (which keeps the
    argument valid) and the better radius kept.
    """

    radius: float
    scale: float
    support: tuple = ()

    @property
    def confirmed(self) -> bool:
        """Whether the certificate rules out every answer up to ``CERTIFICATE_FACTOR`` times
        the problem's scale."""
        return bool(self.radius >= CERTIFICATE_FACTOR * self.scale)

    def describe(self) -> str:
        """One sentence: what the certificate proves and whether that is enough."""
        need = f"{CERTIFICATE_FACTOR:g} x the problem's scale {self.scale:.3g}"
        if np.isinf(self.radius):
            return f"rules out every answer (at least {need})"
        if self.confirmed:
            return f"rules out every answer with all unknowns within {self.radius:.3g} (at least {need})"
        return f"rules out only the answers with all unknowns within {self.radius:.3g}, less than {need}"


def _soc_project(mu: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Projection of the columns ``(mu_j, Y[:, j])`` onto the second-order cone."""
    ny = np.linalg.norm(Y, axis=0)
    inside, below = ny <= mu, ny <= -mu
    a = np.where(inside, mu, np.where(below, 0.0, 0.5 * (mu + ny)))
    unit = np.divide(Y, ny, out=np.zeros_like(Y), where=ny > 0)
    Yp = np.where(inside, Y, np.where(below, 0.0, a * unit))
    return a, Yp


def _term_multipliers(term, duals: list, sign: float) -> tuple[np.ndarray, float] | None:
    """``(u, t)`` of one constraint term (see :class:`Certificate`), or None without duals."""
    if any(d is None for d in duals):
        return None
    m = term.residual.m
    tol = np.zeros(m) if term.tol is None else np.broadcast_to(np.asarray(term.tol, float), (m,))
    if term.kind == "cone":
        k = term.residual.size
        mu, Y = duals[0]
        mu, Y = _soc_project(sign * np.asarray(mu, float).ravel(),
                             sign * np.asarray(Y, float).reshape(k - 1, -1))
        u = -np.column_stack([mu, Y.T]).ravel()
        return u, float(mu @ tol[::k]) if term.mode == "band" else 0.0
    d = [np.broadcast_to(np.asarray(v, float).ravel() * sign, (m,)) for v in duals]
    if term.kind == "equality" and term.mode == "hard":
        return d[0], 0.0
    nu = [np.maximum(v, 0.0) for v in d]
    if term.kind == "equality":  # band: r <= tol and -r <= tol
        return nu[0] - nu[1], float(tol @ (nu[0] + nu[1]))
    return nu[0], float(tol @ nu[0]) if term.mode == "band" else 0.0


def _scale(form, terms) -> float:
    """:attr:`Certificate.scale` of a formulation."""
    data = form.data
    T = max(float(data.t[-1] - data.t[0]), 1e-300)
    A = float(np.max(np.abs(data.acc))) if data.acc.size else 0.0
    C = 0.0
    for term in terms:
        C = max(C, float(np.max(np.abs(term.residual.c), initial=0.0)))
        if term.tol is not None:
            C = max(C, float(np.max(np.abs(term.tol), initial=0.0)))
    return float(max(1.0, C, C / T, C / T**2, A, A * T, A * T * T))


def certificate(form: Formulation, cvx: CvxProblem | None = None,
                labels: Sequence[str] | None = None) -> Certificate | None:
    """The infeasibility certificate the last solve left in the duals, checked.

    Parameters
    ----------
    form : Formulation or NavigationProblem
    cvx : CvxProblem, optional
        The compiled problem whose constraints hold the duals (default: the formulation's).
    labels : sequence of str, optional
        The items whose constraints took part in that solve (default: every constraint
        item); the FEM equations always do.

    Returns
    -------
    Certificate or None
        None when a constraint has no dual (the solver left no certificate).
    """
    cvx = compiled(form) if cvx is None else cvx
    by_label = {t.label: t for t in form.terms()}
    labels = [lb for lb, cons in cvx.cons.items() if cons] if labels is None else list(labels)
    terms = [by_label[lb] for lb in labels]
    y = cvx.fem.dual_value
    if y is None:
        return None
    best = None
    for sign in (1.0, -1.0):
        u = sign * np.asarray(y, float).ravel()
        g = cvx.fem_rows.A.T @ u
        gamma = float(cvx.fem_rows.c @ u)
        mass = {}
        for term in terms:
            got = _term_multipliers(term, [c.dual_value for c in cvx.cons[term.label]], sign)
            if got is None:
                return None
            u, t = got
            g = g + term.residual.A.T @ u
            gamma += float(term.residual.c @ u) - t
            mass[term.label] = float(np.max(np.abs(u), initial=0.0))
        norm = float(np.abs(g).sum())
        radius = 0.0 if gamma <= 0 else (np.inf if norm == 0 else gamma / norm)
        if best is None or radius > best[0]:
            top = max(mass.values(), default=0.0)
            support = tuple(sorted((lb for lb, v in mass.items() if v > 1e-6 * top),
                                   key=lambda lb: -mass[lb]))
            best = (radius, support)
    return Certificate(radius=float(best[0]), scale=_scale(form, terms), support=best[1])


def _feasible(cvx: CvxProblem, labels, form=None) -> bool:
    """Whether the FEM equations and the constraints of the items ``labels`` can all hold
    (the very constraints :func:`build` compiled, modes included): False only when
    Clarabel says infeasible and its certificate confirms it (:func:`certificate`; with
    ``form`` None, on Clarabel's word)."""
    import cvxpy as cp

    cons = [cvx.fem] + [c for label in labels for c in cvx.cons[label]]
    prob = cp.Problem(cp.Minimize(0), cons)
    try:
        with warnings.catch_warnings():  # an inaccurate feasibility verdict is judged below,
            warnings.simplefilter("ignore")  # not passed on as a stray cvxpy warning
            prob.solve(solver="CLARABEL")
    except cp.SolverError:
        return True  # cannot tell: do not accuse
    if prob.status not in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
        return True
    if form is None:
        return False
    cert = certificate(form, cvx, labels)
    return cert is None or not cert.confirmed  # an unconfirmed verdict accuses nobody


def conflicting_items(form: Formulation) -> list[str]:
    """Labels of a smallest-by-deletion set of hard items that cannot hold together.

    Parameters
    ----------
    form : Formulation

    Returns
    -------
    list of str
        Empty when the hard information is consistent. Otherwise an irreducible
        infeasible subset: these items conflict, and dropping (or softening) any one of
        them removes this conflict (others may remain).

    Notes
    -----
    Deletion filter (Chinneck): start from every item that compiles to constraints (hard
    and band items, hard inequalities and second-order cones; the FEM equations always
    stay); for each item, if the rest is still infeasible without it, drop it for good.
    One feasibility solve per item, so this runs only after a solve has failed. A
    feasibility verdict counts only when its certificate is confirmed
    (:func:`certificate`), so every set the filter keeps was proved infeasible.
    """
    cvx = compiled(form)
    labels = [label for label, cons in cvx.cons.items() if cons]
    if _feasible(cvx, labels, form):
        return []
    keep = list(labels)
    for label in labels:
        trial = [k for k in keep if k != label]
        if not _feasible(cvx, trial, form):
            keep = trial
    return keep
