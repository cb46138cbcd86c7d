"""Terms -> one DPP cvxpy problem with the ``lam`` Parameter, and its culprit checks.

:func:`build` lowers a :class:`~bvpnav.formulation.Formulation` once: the FEM rows and the
hard items become constraints, the data term and the soft and robust items the objective
(the latter times ``lam``, one ``cp.Parameter``), each term through its row of the mode x
kind table (:mod:`bvpnav.terms`). The framework, not the plug-in, checks that the result
is DCP and DPP and names the culprit item. :func:`conflicting_items` finds which hard
items cannot hold together (a deletion filter over feasibility problems built from the
very same constraints). cvxpy is imported by :func:`build` and the feasibility checks on
first use, not with this module.
"""

from __future__ import annotations

import warnings
import weakref
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

from .errors import ConvexityError
from .formulation import Formulation
from .model import Affine

if TYPE_CHECKING:
    import cvxpy as cp

__all__ = ["CvxProblem", "lower", "build", "compiled", "current_lam", "conflicting_items"]

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


def _feasible(cvx: CvxProblem, labels) -> bool:
    """Whether the FEM equations and the constraints of the items ``labels`` can all hold
    (the very constraints :func:`build` compiled, modes included)."""
    import cvxpy as cp

    cons = [cvx.fem] + [c for label in labels for c in cvx.cons[label]]
    prob = cp.Problem(cp.Minimize(0), cons)
    try:
        with warnings.catch_warnings():  # an inaccurate feasibility verdict is judged below,
            warnings.simplefilter("ignore")  # not passed on as a stray cvxpy warning
            prob.solve(solver="CLARABEL")
    except cp.SolverError:
        return True  # cannot tell: do not accuse
    return prob.status not in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE)


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
    One feasibility solve per item, so this runs only after a solve has failed.
    """
    cvx = compiled(form)
    labels = [label for label, cons in cvx.cons.items() if cons]
    if _feasible(cvx, labels):
        return []
    keep = list(labels)
    for label in labels:
        trial = [k for k in keep if k != label]
        if not _feasible(cvx, trial):
            keep = trial
    return keep
