"""The demotion stage: conflicting hard items made soft by priority until the rest holds.

With ``on_conflict="demote"`` each round runs the inner stage; on
:class:`~bvpnav.errors.Infeasible` it takes the conflicting set the back end found (an
irreducible infeasible subset, :func:`bvpnav.cvx.conflicting_items`), demotes its
lowest-priority *item* (error-model priors are never demoted) and runs the inner stage on
the modified formulation. Every round removes one hard item, so the loop ends.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable

from ..cvx import conflicting_items
from ..errors import Infeasible, InputError
from ..formulation import original
from ..result import Demotion, Solution
from .options import SolveOptions

__all__ = ["with_demotion", "conflicting_items", "check_demotion"]

Stage = Callable[..., Solution]

log = logging.getLogger(__name__)


def _demoted(form, label: str, sigma: float):
    """A copy of ``form`` with the item ``label`` made soft (sigma in its units)."""
    items = []
    for it in form.items:
        if it.label == label:
            it = dataclasses.replace(original(it), mode="soft", sigma=sigma, tol=None, huber=None,
                                     name=label)
        items.append(it)
    return form.with_items(items)


def check_demotion(form, priority, demote_sigma) -> tuple[dict, dict, float]:
    """``(priority, per-label sigma, default sigma)``, or :class:`InputError` naming an
    unknown item label."""
    labels = form.labels
    priority = dict(priority or {})
    sig_map = demote_sigma if isinstance(demote_sigma, dict) else {}
    sig_default = 1.0 if demote_sigma is None or isinstance(demote_sigma, dict) else float(demote_sigma)
    for what, keys in (("priority", priority), ("demote_sigma", sig_map)):
        unknown = sorted(set(keys) - set(labels))
        if unknown:
            raise InputError(f"{what} names unknown item(s) {unknown}; the problem's items are {labels}")
    return priority, sig_map, sig_default


def _victim(exc: Infeasible, current, demoted, priority, order) -> tuple[str, list]:
    conflict = next((a["conflicts"] for a in reversed(exc.attempts or []) if a.get("conflicts")), [])
    # from the items, not terms(): an item awaiting linearization (TrackLine) cannot compile
    hard_items = {it.label for it in current.items if it.is_constraint}
    candidates = [c for c in conflict if c in hard_items]
    if not candidates:
        done = f"; already demoted {[d.item for d in demoted]}" if demoted else ""
        raise Infeasible(f"{exc}{done}. No demotable item was identified in the conflict.",
                         attempts=exc.attempts) from exc
    return min(candidates, key=lambda c: (priority.get(c, 0.0), -order[c])), list(conflict)


def with_demotion(inner: Stage) -> Stage:
    """The stage that applies ``opts.on_conflict`` around ``inner``.

    ``opts.priority`` maps item labels to priorities (higher is kept hard longer; default
    0, ties broken by demoting the item added last); ``opts.demote_sigma`` is the sigma
    (item units) of a demoted item, one number or per label (default 1.0). The solution
    carries ``records.demoted`` (also ``stats["demoted"]``: ``item``, ``sigma``,
    ``priority``, ``conflict``) and one warning per demotion.
    """

    def stage(form, lam, opts: SolveOptions) -> Solution:
        if opts.on_conflict != "demote":
            return inner(form, lam, opts)
        priority, sig_map, sig_default = check_demotion(form, opts.priority, opts.demote_sigma)
        order = {label: k for k, label in enumerate(form.labels)}
        demoted: list[Demotion] = []
        current = form
        while True:
            try:
                sol = inner(current, lam, opts)
                break
            except Infeasible as exc:
                victim, conflict = _victim(exc, current, demoted, priority, order)
                sigma = float(sig_map.get(victim, sig_default))
                demoted.append(Demotion(item=victim, sigma=sigma, priority=priority.get(victim, 0.0),
                                        conflict=conflict))
                log.info("conflicting hard items %s: demoting %r to soft with sigma=%g (round %d)",
                         list(conflict), victim, sigma, len(demoted))
                current = _demoted(current, victim, sigma)
        sol.record(demoted=demoted)
        ident = {it.label: it.identify() for it in form.items}  # unnamed items: what they hold
        for d in demoted:
            others = [ident.get(c, c) for c in d.conflict if c != d.item]
            shown = ident.get(d.item, d.item)
            shown = repr(shown) if shown == d.item else shown
            sol.warnings.append(f"hard item {shown} (priority {d.priority:g}) conflicted with {others} "
                                f"and was demoted to soft with sigma={d.sigma:g}")
        return sol

    return stage
