r"""The gating stage: fixes whose residual is too large for their sigma are rejected.

An item with a ``gate`` (:class:`~bvpnav.constraints.Position` and
:class:`~bvpnav.constraints.Velocity`: GNSS fixes) is judged after the inner solve, one
instant (fix) at a time, by its normalized residual

.. math:: z_k = \Big(\sum_a (\rho_{k,a} / \sigma_{k,a})^2\Big)^{1/2},

:math:`\rho_{k,a}` the fix's residual on axis :math:`a` at the estimate and
:math:`\sigma_{k,a}` its stated standard deviation: for a good fix and an estimate whose
own uncertainty at the fix is small next to :math:`\sigma` (fixes every second or more
often, an IMU that bridges them), :math:`z_k^2` is about chi-squared with one degree of
freedom per axis (a gate of 5 on three axes rejects a good fix with probability 1.4e-5).

The passes (each a full solve by the inner stages):

1. solve with every fix;
2. among the kept fixes with :math:`z_k` above the gate, reject those within a factor
   :data:`WORST_FRACTION` of the largest (so that a gross outlier, which drags the estimate
   and with it its neighbours' residuals, is removed before its neighbours are judged);
   solve again;
3. when a pass rejects nothing new, a rejected fix whose :math:`z_k` against the estimate
   made without it is within :data:`READMIT` times the gate is taken back; solve again;
4. stop when nothing changes, or after :data:`MAX_PASSES` solves (with a warning).

Nothing is dropped silently: ``Solution.rejected`` lists every rejected fix (item, time,
value, normalized residual, gate, the pass that rejected it), ``Solution.stats["gating"]``
counts them, and one warning names them.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np
import pandas as pd

from ..items import Linearizable
from ..log import warn
from ..result import Solution
from .options import SolveOptions

__all__ = ["with_gating", "normalized_residuals", "MAX_PASSES", "WORST_FRACTION", "READMIT"]

Stage = Callable[..., Solution]

log = logging.getLogger(__name__)

#: Most solves the stage makes (the first included).
MAX_PASSES = 8
#: A pass rejects the fixes above the gate whose normalized residual is at least this
#: fraction of the largest one.
WORST_FRACTION = 0.5
#: A rejected fix is taken back when its normalized residual falls to this fraction of the
#: gate (below 1: a fix on the edge does not go back and forth).
READMIT = 0.8


def normalized_residuals(item, sol: Solution, form) -> tuple[np.ndarray, np.ndarray]:
    """``(z, rho)``: the normalized residual per instant (K,) and the residual rows (K, n_axes)
    in the item's units of every instant of ``item`` at the solution ``sol`` (the instants
    left out of the solve included), on the model of the formulation the solution solves."""
    used = sol.formulation if sol.formulation is not None else form
    model = used.model
    it = item
    if isinstance(it, Linearizable) and it.needs_linearization:
        it = it.linearized_from(sol, model.grid.t, sol.trajectory[list(model.axes)])
    rows = it.compile(model)
    rho = rows.value(sol.x)
    sig = it.weight_rows(rho.size)
    k = it.n_instants()
    z = np.sqrt(np.sum(((rho / sig).reshape(k, -1)) ** 2, axis=1))
    return z, rho.reshape(k, -1)


def _form_with(form, gated: dict, kept: dict):
    items = []
    for it in form.items:
        if it.label not in gated:
            items.append(it)
            continue
        keep = np.flatnonzero(kept[it.label])
        if keep.size == it.n_instants():
            items.append(it)
        elif keep.size:
            items.append(it.with_instants(keep, gated[it.label]))
    return form.with_items(items)


def with_gating(inner: Stage) -> Stage:
    """The stage that gates the fixes of items with ``gate`` (see the module docstring).

    The solution carries ``rejected`` (a DataFrame, empty when every fix was kept),
    ``stats["gating"]`` (passes, fixes judged and rejected, whether the passes settled)
    and one warning listing the rejected fixes.
    """

    def stage(form, lam, opts: SolveOptions) -> Solution:
        gated_items = [it for it in form.items if getattr(it, "gate", None) is not None]
        if not gated_items:
            return inner(form, lam, opts)
        n_axes = {it.label: len(form.model.axes_of(it.axes, it.identify())) for it in gated_items}
        kept = {it.label: np.ones(it.n_instants(), dtype=bool) for it in gated_items}
        when = {it.label: np.zeros(it.n_instants(), dtype=int) for it in gated_items}
        current = form
        sol = inner(current, lam, opts)
        passes, settled = 1, False
        while True:
            z = {it.label: normalized_residuals(it, sol, current) for it in gated_items}
            over = {it.label: kept[it.label] & (z[it.label][0] > it.gate) for it in gated_items}
            worst = max((float(z[k][0][m].max()) for k, m in over.items() if m.any()), default=0.0)
            changed = False
            for it in gated_items:
                new = over[it.label] & (z[it.label][0] >= WORST_FRACTION * worst)
                if new.any():
                    kept[it.label][new] = False
                    when[it.label][new] = passes
                    changed = True
            if not changed:   # settled: take back what the estimate without it now fits
                for it in gated_items:
                    back = ~kept[it.label] & (z[it.label][0] <= READMIT * it.gate)
                    if back.any():
                        kept[it.label][back] = True
                        when[it.label][back] = 0
                        changed = True
            if not changed:
                settled = True
                break
            if passes >= MAX_PASSES:
                break
            current = _form_with(form, n_axes, kept)
            log.info("gating pass %d: %d fix(es) rejected", passes,
                     sum(int((~m).sum()) for m in kept.values()))
            sol = inner(current, lam, opts)
            passes += 1
        return _attach(sol, gated_items, kept, when, z, passes, settled, form)

    return stage


def _attach(sol: Solution, gated_items, kept, when, z, passes: int, settled: bool, form) -> Solution:
    rows = []
    axes = list(form.model.axes)
    for it in gated_items:
        zz, rho = z[it.label]
        k = it.n_instants()
        ax = [axes[a] for a in form.model.axes_of(it.axes, it.identify())]
        from ..items import as_values

        vals = as_values(it.value, k, len(ax), it.identify()).reshape(k, len(ax))
        for j in np.flatnonzero(~kept[it.label]):
            row = {"item": it.label, "t": float(it.t[j])}
            row.update({f"value_{a}": float(vals[j, i]) for i, a in enumerate(ax)})
            row.update({f"residual_{a}": float(rho[j, i]) for i, a in enumerate(ax)})
            row.update({"normalized": float(zz[j]), "gate": float(it.gate), "pass": int(when[it.label][j]),
                        "units": it.units})
            rows.append(row)
    table = pd.DataFrame(rows)
    n_judged = sum(it.n_instants() for it in gated_items)
    sol.rejected = table
    info = {"passes": passes, "settled": settled, "judged": n_judged, "rejected": len(rows),
            "items": [it.label for it in gated_items]}
    sol.record(gating=info)
    if rows:
        shown = ", ".join(f"{r['item']} t={r['t']:g} s (z={r['normalized']:.3g})" for r in rows[:20])
        more = f", ... {len(rows) - 20} more" if len(rows) > 20 else ""
        msg = (f"gating rejected {len(rows)} of {n_judged} fix(es) whose normalized residual exceeds the "
               f"gate: {shown}{more}; see Solution.rejected")
        sol.warnings.append(msg)
        warn(msg)
    if not settled:
        msg = (f"gating did not settle in {passes} solves (MAX_PASSES): the rejected list is that of the "
               "last pass; check the fixes' sigma and the gate")
        sol.warnings.append(msg)
        warn(msg)
    return sol
