"""From a verified stacked vector to the user's :class:`~bvpnav.Solution`.

:func:`finish` verifies a back end's answer, records the attempt and refuses an answer
that fails (unless verification is off); :func:`make_solution` turns the vector into
tidy time-indexed tables (trajectory, acceleration residuals, one row per item), the
error-model estimates and the warnings a user must see.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from ..errors import Inaccurate, InputError
from ..formulation import Formulation
from ..linalg.lsq import Factored
from ..linalg.workspace import Workspace
from ..model import RowLabels, TimeLabels
from ..result import Attempt, ItemRows, Run, Solution, SolveRecords, Verification
from ..sparse import as_csr
from .verify import verify

__all__ = ["finish", "make_solution"]


def _dual_rms(duals: dict | None, label: str) -> float | None:
    if duals is None or not duals.get(label):
        return None
    ds = [np.concatenate([np.asarray(p, dtype=float).ravel() for p in d])
          if isinstance(d, list | tuple) else np.asarray(d, dtype=float).ravel()
          for d in duals[label] if d is not None]
    return float(np.sqrt(np.mean(np.concatenate(ds) ** 2))) if ds else None


_T_LABEL = re.compile(r"\(t=([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\)")


def _label_times(labels, m: int) -> np.ndarray | None:
    """Row times (s) read from row labels: exact from :class:`TimeLabels`, else parsed from
    ``"...(t=2.5)"``; None when the labels do not give every row one."""
    if labels is None or len(labels) != m:
        return None
    if isinstance(labels, TimeLabels):
        return np.repeat(labels.times, len(labels.axes))
    if isinstance(labels, RowLabels):
        parts = []
        for q in labels.parts:
            if isinstance(q, TimeLabels):
                parts.append(np.repeat(q.times, len(q.axes)))
            elif isinstance(q, tuple) and len(q) == 2 and isinstance(q[0], str) and isinstance(q[1], int):
                return None
            else:
                got = _label_times(q, len(q))
                if got is None:
                    return None
                parts.append(got)
        return np.concatenate(parts) if parts else None
    out = np.empty(m)
    for i, lab in enumerate(labels):
        hit = _T_LABEL.search(str(lab))
        if hit is None:
            return None
        out[i] = float(hit.group(1))
    return out


def _column_times(model, n: int) -> np.ndarray:
    """The time (s) of each of ``n`` columns that is a node's position, NaN for the others."""
    tcol = np.full(n, np.nan)
    for a in range(model.d):
        tcol[model.r_index(a)] = model.grid.t
    return tcol


def _row_times(term, model, m: int, tcol: np.ndarray | None = None) -> np.ndarray:
    """Time of each shown row (s): from the labels, else the mean time of the nodes the row
    touches weighted by its coefficients' sizes; NaN for rows on no node (priors, cones).
    ``tcol``: :func:`_column_times` of ``model`` when the caller has it."""
    res = term.residual
    got = _label_times(getattr(res, "labels", None), m)
    if got is not None:
        return got
    A = getattr(res, "A", None)
    if A is None or A.shape[0] != m:
        return np.full(m, np.nan)
    A = as_csr(A)
    if tcol is None or tcol.size != A.shape[1]:
        tcol = _column_times(model, A.shape[1])
    # |A| (1 on a node's position) and |A| t, summed over each row's stored entries in their order
    tj = tcol[A.indices]
    on = np.isfinite(tj)
    absA = np.abs(A.data)
    rows = np.repeat(np.arange(m), np.diff(A.indptr))
    den = np.bincount(rows, weights=absA * on, minlength=m)
    num = np.bincount(rows, weights=absA * np.where(on, tj, 0.0), minlength=m)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)


def _per_row(v, m: int) -> np.ndarray | None:
    return None if v is None or np.size(v) != m else np.asarray(v, float).ravel()


def _item_rows(term, model, m: int, tcol: np.ndarray | None = None) -> ItemRows:
    """The :class:`ItemRows` of a term's ``m`` shown rows (``tcol``: see :func:`_row_times`)."""
    labels = getattr(term.residual, "labels", None)
    return ItemRows(t=_row_times(term, model, m, tcol),
                    labels=labels if labels is not None and len(labels) == m else None, mode=term.mode,
                    kind=term.kind, units=term.units,
                    sigma=_per_row(term.sigma, m), huber=term.huber, tol=_per_row(term.tol, m))


def _items_table(form: Formulation, xval: np.ndarray, duals: dict | None) -> tuple[pd.DataFrame, dict, dict]:
    rows, item_res, item_rows = [], {}, {}
    model = form.model
    tcol = _column_times(model, model.size)
    for term in form.terms():
        r, shown = term.shown(xval)
        item_res[term.label] = r
        item_rows[term.label] = _item_rows(term, model, np.size(shown), tcol)
        rows.append({
            "item": term.label,
            "class": type(term.item).__name__ if term.item is not None else "prior",
            "mode": term.mode, "kind": term.kind, "rows": term.residual.m, "units": term.units,
            "rms": float(np.sqrt(np.mean(shown**2))), "max_abs": float(np.max(np.abs(shown))),
            "dual_rms": _dual_rms(duals, term.label),
        })
    cols = ["item", "class", "mode", "kind", "rows", "units", "rms", "max_abs", "dual_rms"]
    return pd.DataFrame(rows, columns=cols), item_res, item_rows


def _knot_times(form) -> dict:
    """Time (s) of each time-varying error-model parameter ``name[k]`` (knot ``k``)."""
    out = {}
    em, data = form.error_model, form.model.data
    for c in getattr(em, "components", (em,)) if em is not None else ():
        knots = getattr(c, "knots", None)
        kt = knots(data) if callable(knots) else None
        if kt is None:
            continue
        for name in c.names(data):
            hit = re.search(r"\[(\d+)\]$", name)
            if hit is not None and int(hit.group(1)) < len(kt):
                out[name] = float(kt[int(hit.group(1))])
    return out


def _warnings(form: Formulation, run: Run | None, check: Verification | None) -> list[str]:
    warn = [] if run is None else [f"{run.solver}: {w}" for w in run.solver_warnings]
    if run is not None and not run.preset_applied:
        warn.append(f"{run.solver}: bvpnav has no accuracy presets for this solver; it ran with "
                    f"its own default tolerances (accuracy={run.accuracy!r} set only bvpnav's "
                    "verification tolerance); pass options=... to tighten them")
    cond = check.conditioning if check is not None else None
    if cond is not None:
        warn += cond["warnings"]
    if run is not None and str(run.status).endswith("inaccurate"):
        warn.append(f"{run.solver} reported status {run.status!r}; the answer passed "
                    "bvpnav's verification (see stats['verification'])")
    grid = getattr(form.model, "fine", form.model.grid)   # the samples, also under a coarse mesh
    gaps = grid.gaps()
    if gaps.size:
        h, med, t = grid.h, float(np.median(grid.h)), grid.t
        warn.append(f"{gaps.size} gap(s) longer than 10x the median step {med:g} s: the first, from "
                    f"sample {gaps[0]} to {gaps[0] + 1} (t={t[gaps[0]]:g} s), is {h[gaps[0]]:g} s "
                    f"long; results across gaps rely on the linear-acceleration assumption")
    return warn


def make_solution(form: Formulation, xval: np.ndarray, lam: float, lam_rule: str, records: SolveRecords,
                  duals: dict | None = None, trajectory: dict | None = None) -> Solution:
    """The :class:`~bvpnav.Solution` of a stacked vector with its records (``trajectory``:
    ``form.model.trajectory(xval)`` when the caller has made it)."""
    model = form.model
    # every sample (a coarse mesh recovers them from its nodes)
    traj = model.trajectory(xval) if trajectory is None else trajectory
    idx = pd.Index(traj["t"], name="t")
    cols = {ax: traj["r"][:, a] for a, ax in enumerate(model.axes)}
    cols.update({"v" + ax: traj["v"][:, a] for a, ax in enumerate(model.axes)})
    parts = model.split(xval)
    resid = pd.DataFrame({f"w_{ax}": traj["w"][:, a] for a, ax in enumerate(model.axes)}, index=idx)
    items_df, item_res, item_rows = _items_table(form, xval, duals)
    if form.error_model is not None and model.q:
        params = form.error_model.report(parts["l"], model)
        params.attrs["t"] = _knot_times(form)
    else:
        params = pd.Series(dtype=float, name="estimate")
    if getattr(form, "grade_report", None) is not None:
        records.grade = form.grade_report
    sol = Solution(trajectory=pd.DataFrame(cols, index=idx), residuals=resid, items=items_df,
                   item_residuals=item_res, lam=float(lam), lam_rule=lam_rule, error_params=params,
                   stats={}, x=xval, warnings=_warnings(form, records.run, records.verification),
                   records=records, _formulation=form, item_rows=item_rows,
                   sigma_a=np.array(form.sigma_a, float) if form.residual == "acceleration" else None,
                   sigma_a_given=bool(form.sigma_a_given))
    if form.data.is_strapdown:
        sol.attitude = form.data.attitude
        sol.attitude_data = form.data.attitude
    return sol.record()


def finish(form: Formulation, xval: np.ndarray, lam: float, run: dict, duals, accuracy: str,
           verify_answer: bool, factored: Factored | None = None, workspace: Workspace | None = None
           ) -> Solution:
    """Verify a back end's answer and make the solution, or raise.

    Parameters
    ----------
    run : dict
        The back end's measurements with ``solver``, ``status``, ``accuracy``, ``options``.
    verify_answer : bool
        Refuse an answer that fails verification (:class:`~bvpnav.errors.Inaccurate`).

    Raises
    ------
    InputError
        When the error-model estimate is not finite because of the information itself (a
        degenerate sensor axis): no other back end can help.
    Inaccurate
        When the answer fails verification and ``verify_answer`` is True.
    """
    # the answer at every sample, made once for the solution and the verification's velocity
    # scale (a coarse mesh recovers it from its nodes); not of an answer with NaN or inf, which
    # the verification names
    traj = form.model.trajectory(xval) if np.all(np.isfinite(xval)) else None
    check = verify(form, xval, lam, accuracy, duals, factored, workspace, traj)
    attempt = Attempt(solver=run["solver"], status=run.get("status"),
                      reason="verified" if check.verified else "failed verification")
    cond = check.conditioning or {}
    degenerate = [dg["message"] for dg in cond.get("degenerate_axes", [])]
    if degenerate and check.nonfinite and not check.verified:
        raise InputError(f"{run['solver']}: the error-model estimate is not finite because "
                         + "; ".join(degenerate))
    if verify_answer and not check.verified:
        raise Inaccurate(
            f"{run['solver']} (status {run.get('status')}, accuracy={accuracy!r}) returned an "
            f"answer that fails verification: FEM residual {check.fem_residual:.2e}, "
            f"worst hard-item violation {check.max_violation:.2e} "
            f"({check.worst_item}), stationarity {check.stationarity}, "
            f"estimated forward error {check.forward_error}, "
            + (f"not finite: {'; '.join(check.nonfinite)}, " if check.nonfinite else "")
            + f"tolerance {check.rtol:.0e}. Try accuracy='high', another solver "
            "(e.g. solver='direct' for problems without inequalities), or residual="
            "'acceleration'.",
            attempts=[attempt.as_dict()],
        )
    records = SolveRecords(run=Run.of(run), attempts=[attempt], verification=check)
    return make_solution(form, xval, lam, "fixed", records, duals, traj)
