r"""The last stage of a solve: standard deviations of the answer (``solve(uncertainty=...)``).

What the numbers are (:mod:`bvpnav.linalg.covariance` computes them, in O(N)):

- with ``uncertainty=True`` the covariance of the estimate under the weights as stated:
  the data rows weighted by ``1/sigma_a`` per sample, each soft item by
  ``sqrt(lam)/sigma``, error-model priors by ``1/sigma``. With ``lam = 1`` and sigmas that
  are the true noise this is the posterior covariance of the MAP estimate (and the
  covariance of its error over repeated noise);
- with ``uncertainty="scaled"`` the same multiplied by the a-posteriori variance factor
  :math:`\hat\sigma_0^2 = \|D\hat x + c\|^2 / f` (the weighted residual sum of squares
  over its degrees of freedom, as in geodetic adjustment): the answer for sigmas that
  are only relative, or a ``lam`` chosen by a rule. The load form has no noise model in
  its data term, so it is always scaled.

A scaled uncertainty that cannot be scaled says so (a warning, and
``stats["uncertainty"]["unscalable"]``): with no degrees of freedom the variance factor is
undefined and the stated standard deviations are returned (``scale`` then says
``"stated"``); on an exact fit (variance factor below :data:`EXACT_FIT`) the scaled
standard deviations are about zero, which says nothing about the accuracy.

Hard items give zero variance in what they fix. For robust, band and inequality items
it is the covariance of the quadratic model at the solution, for linearized items
(``TrackLine``) that of the last linearization: approximations, recorded in
``stats["uncertainty"]["model"]``.
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd
from scipy import stats as _stats

from ..errors import InputError
from ..formulation import Formulation
from ..linalg.covariance import BORDER_COND_WARN, posterior
from ..log import warn
from ..result import Solution, Uncertainty

__all__ = ["attach_uncertainty", "param_jacobian", "EXACT_FIT"]

#: A variance factor below this is an exact fit: the weighted residuals are under a
#: millionth of the stated sigmas.
EXACT_FIT = 1e-12


def param_jacobian(form: Formulation, l: np.ndarray) -> np.ndarray:
    """Jacobian of the reported error-model parameters with respect to the internal ones
    (central differences; exact for the linear ones), shape (q_reported, q)."""
    model = form.model
    l = np.asarray(l, dtype=float)
    cols = []
    for k in range(l.size):
        h = 1e-6 * max(1.0, abs(l[k]))
        lp, lm = l.copy(), l.copy()
        lp[k] += h
        lm[k] -= h
        cols.append((form.error_model.report(lp, model).to_numpy(dtype=float)
                     - form.error_model.report(lm, model).to_numpy(dtype=float)) / (2 * h))
    return np.column_stack(cols)


def _variance_warning(vf: float, dof: int, scale: str) -> str | None:
    """A warning when the variance factor rejects the stated noise at the 1 % level."""
    if scale != "stated" or dof < 1 or not np.isfinite(vf):
        return None
    lo, hi = _stats.chi2.ppf([0.005, 0.995], dof) / dof
    if lo <= vf <= hi:
        return None
    side = "larger" if vf > hi else "smaller"
    return (f"uncertainty: the a-posteriori variance factor is {vf:.3g} ({dof} degrees of freedom; "
            f"{lo:.3g}..{hi:.3g} expected if the stated sigmas were right): the residuals are "
            f"{side} than sigma_a and the items' sigmas say, by about a factor {np.sqrt(vf):.3g}. "
            "The standard deviations assume the stated noise; use uncertainty='scaled' to scale "
            "them by the residuals, or correct sigma_a / the items' sigma")


def _unscalable(vf: float, dof: int, why: str) -> tuple[str, str] | None:
    """``(what, warning)`` when a scaled uncertainty cannot be scaled meaningfully."""
    if dof < 1 or not np.isfinite(vf):
        return "0 degrees of freedom", (
            f"uncertainty: {why}, but the residuals have {dof} degrees of freedom (the information "
            "fixes the estimate exactly: as many conditions as the unknowns need, e.g. a position "
            "and a velocity at one instant), so the a-posteriori variance factor is undefined; the "
            "standard deviations returned are those of the stated noise (sigma_a and the items' "
            "sigma), not scaled. Add redundant information (more fixes) to scale them")
    if vf < EXACT_FIT:
        return "exact fit", (
            f"uncertainty: {why}, but the residuals are zero to within a millionth of the stated "
            f"sigmas (variance factor {vf:.3g} over {dof} degrees of freedom: an exact fit, e.g. "
            "noise-free data), so every scaled standard deviation is about 0; that says nothing "
            "about the accuracy. Use uncertainty=True with the true noise in sigma_a and the "
            "items' sigma")
    return None


def attach_uncertainty(sol: Solution, form: Formulation, how) -> Solution:
    """Add standard deviations and covariances to ``sol`` (see the module docstring)."""
    t0 = time.perf_counter()
    model = form.model
    if model.N != form.data.n:
        raise InputError("uncertainty=: the posterior of a coarse mesh (segment=) is not carried to every "
                         "sample yet; solve with segment=None for standard deviations")
    cov = posterior(form, sol.x, sol.lam)
    scale = "scaled" if how == "scaled" or form.residual == "load" else "stated"
    unscalable = None
    if scale == "scaled":
        why = ("uncertainty='scaled' was asked for" if how == "scaled" else
               "the load form's uncertainty is always scaled (its data term has no noise model)")
        unscalable = _unscalable(float(cov.variance_factor), int(cov.dof), why)
        if unscalable is not None:
            sol.warnings.append(unscalable[1])
            warn(unscalable[1])
            if unscalable[0] == "0 degrees of freedom":
                scale = "stated"
    k = cov.variance_factor if scale == "scaled" else 1.0
    state = cov.state * k
    rstd, vstd = (np.sqrt(k) * s for s in cov.std())
    for a, ax in enumerate(model.axes):  # x_std, y_std, ..., then vx_std, ...: as the values
        sol.trajectory[f"{ax}_std"] = rstd[:, a]
    for a, ax in enumerate(model.axes):
        sol.trajectory[f"v{ax}_std"] = vstd[:, a]
    sol._cov["state"] = state
    if model.q and form.error_model is not None:
        J = param_jacobian(form, sol.x[model.l_index])
        P = J @ (cov.params * k) @ J.T
        names = list(sol.error_params.index)
        sol._cov["error_params"] = pd.DataFrame(P, index=names, columns=names)
        std = pd.Series(np.sqrt(np.clip(np.diag(P), 0, None)), index=sol.error_params.index, name="std")
        std.attrs["units"] = dict(sol.error_params.attrs.get("units", {}))
        sol.error_params_std = std
    else:
        sol._cov["error_params"] = pd.DataFrame()
    if cov.states is not None and sol.error_states is not None:   # node states: std per sample
        std = {}
        for kind, var in cov.states.items():
            for c, ax in enumerate("xyz"):
                name = next(n for n in sol.error_states.columns if n.startswith(f"{kind}_{ax} "))
                std[name] = np.sqrt(np.clip(var[:, c] * k, 0.0, None))
        sol.error_states_std = pd.DataFrame(std, index=sol.error_states.index)
    linearized = sol.records.sequential is not None or bool(form.nonlinear_items)
    what = "last linearization" if linearized else "exact" if cov.exact else "quadratic model"
    msg = _variance_warning(cov.variance_factor, cov.dof, scale)
    if msg is not None:  # a choice the user can change: also through warnings
        sol.warnings.append(msg)
        warn(msg)
    worst = max(cov.border_condition, cov.pivot_condition)
    if worst > BORDER_COND_WARN:
        sol.warnings.append(
            f"uncertainty: the covariance computation is ill-conditioned (condition number "
            f"{worst:.1e}; errors grow like it times 1e-16): hard items that nearly repeat each other (two "
            "at almost the same instant, or an interval that ends a hair from a sample) leave "
            "the standard deviations inaccurate; merge such items or give one of them "
            "mode='soft'")
    if sol.lam_rule != "fixed" and scale == "stated":
        sol.warnings.append(
            f"uncertainty: lam = {sol.lam:.4g} was chosen by {sol.lam_rule!r}, so the stated "
            "covariance weighs each soft item as if its sigma were sigma/sqrt(lam); "
            "uncertainty='scaled' calibrates it by the residuals instead")
    rec = Uncertainty(scale=scale, variance_factor=float(cov.variance_factor), dof=int(cov.dof),
                      model=what, method="block-tridiagonal selected inversion (cyclic reduction) "
                      "with the border by its Schur complement", border=cov.border, block=cov.block,
                      hard_rows_in_border=int(cov.hard_rows_in_border),
                      border_condition=float(cov.border_condition),
                      pivot_condition=float(cov.pivot_condition), time=time.perf_counter() - t0,
                      unscalable=None if unscalable is None else unscalable[0])
    return sol.record(uncertainty=rec)
