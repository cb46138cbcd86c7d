"""Which hard items cannot hold together: a deletion filter over feasibility checks."""

from __future__ import annotations

import cvxpy as cp

__all__ = ["conflicting_items"]


def _feasible(cvx: dict, labels) -> bool:
    """Whether the FEM equations and the constraints of the items ``labels`` can all hold
    (the very constraints :meth:`NavigationProblem.build` compiled, modes included)."""
    cons = [cvx["fem"]] + [c for label in labels for c in cvx["cons"][label]]
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
    Deletion filter (Chinneck): start from every item that compiles to constraints (hard
    and band items, hard inequalities; the FEM equations always stay); for each item, if
    the rest is still infeasible without it, drop it for good. One feasibility solve per
    item, so this runs only after a solve has failed.
    """
    cvx = problem.build()
    labels = [label for label, cons in cvx["cons"].items() if cons]
    if _feasible(cvx, labels):
        return []
    keep = list(labels)
    for label in labels:
        trial = [k for k in keep if k != label]
        if not _feasible(cvx, trial):
            keep = trial
    return keep
