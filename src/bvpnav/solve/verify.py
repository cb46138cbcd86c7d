"""bvpnav's own judgement of an answer: recomputed residuals, never a status word.

:func:`verify` recomputes, from the stacked solution alone, the FEM residual, the
violation of every hard, band and inequality item, the stationarity of the Lagrangian
(when the duals are known and the objective is smooth), a forward-error estimate (least
squares problems: one refinement step on the augmented system, or the direct back end's
own last step when it already meets the preset) and the conditioning of
the error-model parameters, and says whether the answer passes the accuracy preset's
tolerances.
"""

from __future__ import annotations

import numpy as np

from ..backends import VERIFY_RTOL
from ..formulation import Formulation
from ..linalg.lsq import FORWARD_RTOL, Factored, check_factor, forward_error, least_squares_form
from ..linalg.workspace import Workspace
from ..result import Verification
from ..sparse import abs_max
from ..terms import transposed_product
from .conditioning import assess_conditioning

__all__ = ["verify", "stationarity"]


def _worst_violation(form: Formulation, xval: np.ndarray) -> tuple[float, str | None]:
    """Largest relative violation over the constraint terms, and its item."""
    worst, worst_item = 0.0, None
    for term in form.terms():
        v = term.violation(xval)
        if v is None:
            continue
        sc = max(float(np.max(term.residual.row_scale(xval))), 1.0)
        rel = float(np.max(v) / sc)
        if rel > worst:
            worst, worst_item = rel, term.label
    return worst, worst_item


def _nonfinite(form: Formulation, xval: np.ndarray) -> list[str]:
    """What is NaN or infinite in the solution vector or the reported parameters."""
    out = []
    if not np.all(np.isfinite(xval)):
        out.append(f"{int(np.count_nonzero(~np.isfinite(xval)))} entries of the solution vector")
    model = form.model
    if form.error_model is not None and model.q:
        with np.errstate(all="ignore"):
            rep = form.error_model.report(model.split(xval)["l"], model)
        vals = np.asarray(rep, dtype=float)
        out += [f"error parameter {n} = {v}" for n, v in zip(rep.index, vals, strict=True)
                if not np.isfinite(v)]
    return out


def _forward(form: Formulation, xval, lam, duals, factored: Factored | None, bound: float,
             workspace: Workspace | None) -> tuple[float | None, Factored | None]:
    """The forward-error estimate, factoring once (shared with the conditioning); the back
    end's last refinement step on this very ``xval`` when its correction meets ``bound``
    (:class:`bvpnav.linalg.lsq.Factored`: an upper estimate; one more step otherwise)."""
    last = None if factored is None else factored.refined
    if last is not None and last[0] is xval and np.isfinite(last[1]) and last[1] <= bound:
        return float(last[1]), factored
    if factored is None and form.model.q:
        ls = least_squares_form(form, lam)
        if ls is not None:
            try:
                factored = Factored(ls, check_factor(ls, form, workspace))
            except (RuntimeError, np.linalg.LinAlgError):  # forward_error's verdict too
                return float("inf"), None
    return forward_error(form, xval, lam, duals, factored, workspace), factored


def verify(form: Formulation, xval: np.ndarray, lam: float, accuracy: str = "default",
           duals: dict | None = None, factored: Factored | None = None,
           workspace: Workspace | None = None, trajectory: dict | None = None) -> Verification:
    r"""Judge a stacked solution by recomputed residuals.

    Parameters
    ----------
    form : Formulation
    xval : ndarray
        The stacked solution.
    lam : float
    accuracy : {"low", "default", "high"}
        Selects the tolerances (:data:`bvpnav.backends.VERIFY_RTOL`,
        :data:`bvpnav.linalg.lsq.FORWARD_RTOL`).
    duals : dict, optional
        cvxpy-convention duals (for stationarity and the forward error).
    factored : (LeastSquaresForm, factorization), optional
        The direct back end's factorization at this ``lam``, reused (with
        :class:`bvpnav.linalg.lsq.Factored`'s record of the last refinement step, its correction
        is the forward-error estimate when it meets the preset's bound).
    workspace : Workspace, optional
        The solve's workspace (a band plan to reuse when a factor is made here).
    trajectory : dict, optional
        ``form.model.trajectory(xval)``, when the caller has it (the solution is made of it):
        its velocities at the nodes (m/s) give the stationarity's floor its velocity scale
        instead of the nodes' velocity rows evaluated again (:func:`stationarity`).

    Returns
    -------
    Verification

    Notes
    -----
    The answer passes when the relative FEM residual is at most ``rtol``, the worst
    constraint violation at most ``10 rtol``, the stationarity (if known) at most
    :math:`\sqrt{rtol}`, the forward error (if known) within the preset's bound, and
    nothing is NaN or infinite except the parameters of a sensor axis the information
    leaves undetermined (named in the warnings instead).
    """
    rtol = VERIFY_RTOL[accuracy]
    model = form.model
    fem = model.fem_rows()
    fem_rel = abs_max(fem.value(xval)) / max(float(np.max(fem.row_scale(xval))), 1e-300)
    worst, worst_item = _worst_violation(form, xval)
    stat = None if duals is None else stationarity(form, xval, lam, duals, _node_velocities(form, trajectory))
    nonfinite = _nonfinite(form, xval)
    fwd, factored = _forward(form, xval, lam, duals, factored, FORWARD_RTOL[accuracy], workspace)
    conditioning = None
    if model.q and not np.any(~np.isfinite(xval)):
        conditioning = assess_conditioning(form, xval, lam, factored)
        if nonfinite:
            nonfinite += [dg["message"] for dg in conditioning["degenerate_axes"]]
    # the parameters of a sensor axis whose kept fraction is zero are undetermined (inf,
    # NaN) by the information itself; named in warnings, they do not fail the answer.
    # Anything else not finite does, whatever rounding decided (issue 14).
    undetermined = sorted({n for dg in (conditioning or {}).get("degenerate_axes", [])
                           if dg.get("undetermined") for n in dg["parameters"]})
    unexplained = [s for s in nonfinite if not s.startswith("sensor axis ")
                   and not any(s.startswith(f"error parameter {n} = ") for n in undetermined)]
    ok = (fem_rel <= rtol and worst <= rtol * 10 and (stat is None or stat <= np.sqrt(rtol))
          and (fwd is None or fwd <= FORWARD_RTOL[accuracy]) and not unexplained)
    return Verification(fem_residual=fem_rel, max_violation=worst, worst_item=worst_item,
                        stationarity=stat, forward_error=fwd, rtol=rtol, nonfinite=nonfinite,
                        undetermined=undetermined, conditioning=conditioning, verified=bool(ok))


def _node_velocities(form: Formulation, trajectory: dict | None) -> np.ndarray | None:
    """The velocities at the nodes (n, d), m/s, of a trajectory at every sample
    (:meth:`bvpnav.model.NavModel.trajectory`), or None without one."""
    if trajectory is None:
        return None
    return np.asarray(trajectory["v"])[form.model.node_samples]


def _gradient_floor(form: Formulation, xval: np.ndarray, lam: float, data,
                    velocities: np.ndarray | None = None) -> float:
    """The size the gradient would have if the residuals were as large as the terms that
    cancel in them (see :func:`stationarity`); ``velocities`` at the nodes (n, d), m/s, when
    known (else evaluated from ``xval``)."""
    model = form.model
    probe = np.zeros(model.size)
    T = model.grid.duration
    for a in range(model.d):
        r_a = xval[model.r_index(a)]
        v_a = model.node_velocity_values(a, xval) if velocities is None else velocities[:, a]
        a_scale = max(float(np.max(np.abs(r_a))) / T**2, float(np.max(np.abs(v_a))) / T)
        probe[model.w_index(a)] = np.maximum(np.abs(model.data.acc[model.node_samples, a]), a_scale)
    floor = 2.0 * abs_max(data.A.T @ data.value(probe))
    for term in form.terms():
        floor = max(floor, term.gradient_floor(xval, lam))
    return floor


def stationarity(form: Formulation, xval: np.ndarray, lam: float, duals: dict,
                 velocities: np.ndarray | None = None) -> float | None:
    r"""Relative norm of the Lagrangian gradient (None for non-smooth objectives);
    ``velocities`` at the nodes (n, d), m/s, of ``xval`` when the caller has them (the floor's
    velocity scale; else evaluated from ``xval``).

    Notes
    -----
    The gradient :math:`2 J^T J x + A_{fem}^T y + \sum_k g_k` (each term's part from the
    mode x kind table, :meth:`bvpnav.terms.Term.gradient`) is measured against the
    largest of its parts and a floor: the data-term gradient if the residual were as
    large as the measurement (at least the acceleration scale the trajectory itself sets,
    :math:`|r|/T^2` and :math:`|v|/T`), and each weighted term's gradient if its residual
    were as large as the terms that cancel in it (:math:`|A| |x| + |c|`); so exactly
    consistent data is not judged against round-off alone.
    """
    data = form.data_rows()
    y = duals.get("fem")
    if y is None:
        return None
    # the gradients added into one vector as they come, each one's size kept for the scale;
    # an item's on the columns it touches (transposed_product)
    total = data.A.T @ data.value(xval)
    total *= 2.0
    scale = abs_max(total)
    g = form.model.fem_rows().A.T @ np.asarray(y, dtype=float).ravel()
    scale = max(scale, abs_max(g))
    total += g
    del g
    for term in form.terms():
        u = term.gradient_rows(xval, lam, duals.get(term.label))
        if u is None:
            return None
        cols, g = transposed_product(term.residual.A, u)
        scale = max(scale, abs_max(g))
        total[cols] += g
    floor = _gradient_floor(form, xval, lam, data, velocities)
    scale = max(scale, floor, 1e-300)
    return abs_max(total) / scale
