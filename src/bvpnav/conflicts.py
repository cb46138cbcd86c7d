"""Which hard items cannot hold together: a deletion filter over feasibility checks."""

from __future__ import annotations

import dataclasses
import warnings

import cvxpy as cp

__all__ = ["conflicting_items", "solve_demoting"]


def _feasible(cvx: dict, labels) -> bool:
    """Whether the FEM equations and the constraints of the items ``labels`` can all hold
    (the very constraints :meth:`NavigationProblem.build` compiled, modes included)."""
    cons = [cvx["fem"]] + [c for label in labels for c in cvx["cons"][label]]
    prob = cp.Problem(cp.Minimize(0), cons)
    try:
        with warnings.catch_warnings():  # an inaccurate feasibility verdict is judged below,
            warnings.simplefilter("ignore")  # not passed on as a stray cvxpy warning
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
    and band items, hard inequalities and second-order cones; the FEM equations always
    stay); for each item, if the rest is still infeasible without it, drop it for good.
    One feasibility solve per item, so this runs only after a solve has failed.
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


def _demoted_problem(problem, label: str, sigma: float):
    """A copy of ``problem`` with the item ``label`` made soft (sigma in its units)."""
    from .problem import _Renamed

    items = []
    for it in problem._items:
        if it.label == label:
            base = _Renamed.unwrap(it)
            it = dataclasses.replace(base, mode="soft", sigma=sigma, tol=None, huber=None, name=label)
        items.append(it)
    return problem.with_items(items)


def solve_demoting(problem, solve_kwargs: dict, priority=None, demote_sigma=None):
    """Solve, demoting conflicting hard items to soft by priority until the rest holds.

    Parameters
    ----------
    problem : NavigationProblem
    solve_kwargs : dict
        Arguments for :meth:`NavigationProblem.solve` (solver, lam, accuracy, ...).
    priority : mapping of str to float, optional
        Item label -> priority (higher is kept hard longer); default 0 for every item,
        ties broken by demoting the item added last.
    demote_sigma : float or mapping of str to float, optional
        Sigma (item units) of a demoted item; default 1.0.

    Returns
    -------
    Solution
        With ``stats["demoted"]``: one record per demoted item (``item``, ``sigma``,
        ``priority``, ``conflict`` — the conflicting set it was taken from), and one
        warning per demotion.

    Notes
    -----
    Each round solves; on :class:`~bvpnav.errors.Infeasible` it takes the conflicting set
    that :func:`conflicting_items` found (an irreducible infeasible subset), demotes its
    lowest-priority *item* (error-model priors are never demoted) and solves the modified
    problem again. Every round removes one hard item, so the loop ends.
    """
    from .errors import Infeasible, InputError

    labels = problem.item_labels
    priority = dict(priority or {})
    sig_map = demote_sigma if isinstance(demote_sigma, dict) else {}
    sig_default = 1.0 if demote_sigma is None or isinstance(demote_sigma, dict) else float(demote_sigma)
    for what, keys in (("priority", priority), ("demote_sigma", sig_map)):
        unknown = sorted(set(keys) - set(labels))
        if unknown:
            raise InputError(f"{what} names unknown item(s) {unknown}; the problem's items are {labels}")
    order = {label: k for k, label in enumerate(labels)}
    demoted: list[dict] = []
    current = problem
    while True:
        try:
            sol = current.solve(**solve_kwargs, on_conflict="raise")
            break
        except Infeasible as exc:
            conflict = next((a["conflicts"] for a in reversed(exc.attempts or [])
                             if a.get("conflicts")), [])
            # from the items, not terms(): an item awaiting linearization (TrackLine) cannot compile
            hard_items = {it.label for it in current._items if it.mode in ("hard", "band")}
            candidates = [c for c in conflict if c in hard_items]
            if not candidates:
                done = f"; already demoted {[d['item'] for d in demoted]}" if demoted else ""
                raise Infeasible(f"{exc}{done}. No demotable item was identified in the conflict.",
                                 attempts=exc.attempts) from exc
            victim = min(candidates, key=lambda c: (priority.get(c, 0.0), -order[c]))
            sigma = float(sig_map.get(victim, sig_default))
            demoted.append({"item": victim, "sigma": sigma, "priority": priority.get(victim, 0.0),
                            "conflict": list(conflict)})
            current = _demoted_problem(current, victim, sigma)
    sol.stats["demoted"] = demoted
    ident = {it.label: it.identify() for it in problem._items}  # unnamed items: what they hold
    for d in demoted:
        others = [ident.get(c, c) for c in d["conflict"] if c != d["item"]]
        shown = ident.get(d["item"], d["item"])
        shown = repr(shown) if shown == d["item"] else shown
        sol.warnings.append(
            f"hard item {shown} (priority {d['priority']:g}) conflicted "
            f"with {others} and was "
            f"demoted to soft with sigma={d['sigma']:g}"
        )
    return sol
