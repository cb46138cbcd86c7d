"""Which hard items cannot hold together: a deletion filter over feasibility checks."""

from __future__ import annotations

import cvxpy as cp

__all__ = ["conflicting_items"]


def _feasible(problem, terms) -> bool:
    """Whether the FEM equations and ``terms`` (hard, band or inequality) can all hold."""
    model = problem.model
    x = cp.Variable(model.size)
    fem = model.fem_rows()
    cons = [fem.A @ x + fem.c == 0]
    for t in terms:
        r = t.residual.A @ x + t.residual.c
        if t.kind == "inequality":
            cons.append(r <= 0)
        elif t.mode == "band":
            cons.append(cp.abs(r) <= t.tol)
        else:
            cons.append(r == 0)
    prob = cp.Problem(cp.Minimize(0), cons)
    try:
        prob.solve(solver="CLARABEL")
    except cp.SolverError:
        return True  # cannot tell: do not accuse
    return prob.status not in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE)


def conflicting_items(problem) -> list[str]:
    """Labels of a smallest-by-deletion set of hard items that cannot hold together.

    Parameters
    ----------
    problem : NavigationProblem

    Returns
    -------
    list of str
        Empty when the hard information is consistent. Otherwise an irreducible
        infeasible subset: these items conflict, and dropping (or softening) any one of
        them removes this conflict (others may remain).

    Notes
    -----
    Deletion filter (Chinneck): start from every hard, band and inequality item (the FEM
    equations always stay); for each item, if the rest is still infeasible without it,
    drop it for good. One feasibility solve per item, so this runs only after a solve
    has failed.
    """
    terms = [t for t in problem.terms() if t.mode in ("hard", "band") or t.kind == "inequality"]
    if _feasible(problem, terms):
        return []
    keep = list(terms)
    for t in terms:
        trial = [s for s in keep if s is not t]
        if not _feasible(problem, trial):
            keep = trial
    return [t.label for t in keep]
