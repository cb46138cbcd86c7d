"""The damped outer loop for attitude error models (gyro errors, initial attitude).

An error model with attitude components (:class:`~bvpnav.error_models.AttitudeError`,
:class:`~bvpnav.error_models.GyroBias`, :class:`~bvpnav.error_models.GyroScaleFactor`)
changes the attitude the accelerations are computed with, and the acceleration is not
linear in it. The stage :func:`with_attitude` solves such a problem as a sequence of
convex problems, Levenberg-Marquardt style:

1. at the current totals ``x`` of the attitude parameters, re-integrate the attitude from
   the raw gyro rates (:func:`~bvpnav.error_models._attitude.reintegrate`), rebuild the
   navigation-frame accelerations and the error-model columns;
2. solve the convex problem whose attitude unknowns are the *increments* ``delta`` about
   ``x`` (priors on the totals ``x + delta``), with a damping term
   :math:`\\mu \\sum_p (\\delta_p / s_p)^2`;
3. evaluate the nonlinear objective :math:`J(x + \\delta)`: re-integrate at the new totals
   and solve the convex problem with the attitude *fixed* there (every other unknown
   free), adding the attitude priors;
4. accept the step only if :math:`J` falls (then :math:`\\mu` shrinks tenfold), else
   raise :math:`\\mu` tenfold and try again from ``x``;
5. stop when the largest attitude change over the window that the step makes,
   :math:`\\max_k \\|\\psi_k(\\delta)\\|`, is below ``tol`` (rad).

A global start, for an unknown heading: when ``AttitudeError`` estimates the heading
without a prior on it, the loop first evaluates :math:`J` at ``candidates`` headings
equally spaced over the circle (the attitude otherwise as given) and starts from the
best. With position information that makes the heading observable, this brings the start
within half a spacing (15 degrees for 12 candidates) of the answer, from where the damped
loop converges; without such information the heading stays what the priors make it.

Why damped and why priors on totals. An undamped Gauss-Newton loop on a car drive let
the start heading and the vertical gyro bias slide together until the model had removed
the car's turning; a prior on the increment (re-centred every iteration) cannot stop
that, a prior on the total can, and a step is only taken when it lowers the objective.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np

from ..error_models._attitude import (
    at_point,
    attitude_components,
    propagate,
    reintegrate,
)
from ..errors import InputError
from ..formulation import Formulation
from ..log import progress, warn
from ..model import Cone
from ..result import AttitudeLoopReport, Solution

__all__ = ["with_attitude", "check_attitude", "ATTITUDE_DEFAULTS", "objective_value"]

log = logging.getLogger(__name__)

Stage = Callable[..., Solution]

#: Options of the attitude loop and their defaults (``solve(attitude={...})``).
ATTITUDE_DEFAULTS: dict = {"tol": 1e-7, "max_iter": 30, "heading": "auto", "candidates": 12,
                           "loop": True, "progress": None}
ATTITUDE_KEYS = tuple(ATTITUDE_DEFAULTS)

#: Largest damping weight tried before the loop stops at a point no step improves.
MAX_DAMPING = 1e12


def check_attitude(options: dict | None) -> dict:
    """The loop's options with defaults, or :class:`InputError` naming a wrong one."""
    options = {} if options is None else dict(options)
    unknown = sorted(str(k) for k in set(options) - set(ATTITUDE_DEFAULTS))
    if unknown:
        raise InputError(f"attitude options {unknown} are not known; valid: {list(ATTITUDE_DEFAULTS)}")
    o = {**ATTITUDE_DEFAULTS, **options}
    tol = o["tol"]
    if isinstance(tol, bool) or not isinstance(tol, int | float) or not (np.isfinite(tol) and tol > 0):
        raise InputError(f"attitude tol={tol!r}: the tolerance is a positive angle in rad")
    mi = o["max_iter"]
    if isinstance(mi, bool) or not isinstance(mi, int | np.integer) or mi < 1:
        raise InputError(f"attitude max_iter={mi!r}: need an integer of at least one iteration")
    if o["heading"] not in ("auto", "search", "given"):
        raise InputError(f"attitude heading={o['heading']!r}: choose 'auto' (search when the heading has "
                         "no prior), 'search' or 'given' (start from the data's heading)")
    c = o["candidates"]
    if isinstance(c, bool) or not isinstance(c, int | np.integer) or c < 2:
        raise InputError(f"attitude candidates={c!r}: need an integer of at least 2 headings")
    if not isinstance(o["loop"], bool | np.bool_):
        raise InputError(f"attitude loop={o['loop']!r}: True (the damped loop) or False (one linearized "
                         "solve about the data as given)")
    return o


# ------------------------------------------------------------- objective
def _penalty(term, x: np.ndarray) -> float:
    """The value of one penalty term at ``x`` (without ``lam``)."""
    sig = term.sigma
    if isinstance(term.residual, Cone):
        k = term.residual.size
        e = np.maximum(term.residual.excess(x), 0.0) / sig[::k]
        return float(np.sum(e**2) if term.mode == "soft" else np.sum(e))
    r = term.residual.value(x)
    if term.kind == "inequality":
        g = np.maximum(r, 0.0) / sig
        return float(np.sum(g**2) if term.mode == "soft" else np.sum(g))
    if term.mode == "soft":
        return float(np.sum((r / sig) ** 2))
    if term.huber is None:
        return float(np.sum(np.abs(r) / sig))
    m = term.huber
    a = np.abs(r)
    return float(np.sum(np.where(a <= m, a**2, 2.0 * m * a - m**2) / sig**2))


def objective_value(form, x: np.ndarray, lam: float) -> float:
    """The convex problem's objective at the stacked solution ``x`` (dimensionless).

    Notes
    -----
    :math:`J = \\|D_0 x + c_0\\|^2 + \\sum_{\\text{items}} \\lambda\\,P_i(x) + \\sum_{\\text{priors}} P_j(x)`
    with the data rows :math:`D_0 x + c_0` of :meth:`bvpnav.formulation.Formulation.data_rows`
    and each penalty :math:`P` as cvxpy is given it (squares, Huber, L1, positive parts).
    """
    j = float(np.sum(form.data_rows().value(x) ** 2))
    for term in form.terms():
        if term.is_penalty:
            j += term.weight(lam) * _penalty(term, x)
    return j


def _prior_cost(comps, data) -> float:
    """The attitude priors at zero increments: their share of the nonlinear objective."""
    j = 0.0
    for c in comps:
        names = c.names(data)
        base = c.base(data)
        sig = c.prior_sigma(data)
        p0 = np.zeros(len(names)) if c.prior is None else np.broadcast_to(
            np.asarray(c.prior, dtype=float).ravel() if np.size(c.prior) in (1, len(names)) else c.prior,
            (len(names),))
        ok = np.isfinite(sig)
        j += float(np.sum(((base[ok] - p0[ok]) / sig[ok]) ** 2))
        drift = getattr(c, "drift", None)
        if drift is not None:
            k = c.knots(data)
            m = k.size
            for a in range(len(names) // m):
                b = base[a * m:(a + 1) * m]
                j += float(np.sum((np.diff(b) / (drift * np.sqrt(np.diff(k)))) ** 2))
    return j


# ------------------------------------------------------------- the loop
class _Loop:
    def __init__(self, form, inner: Stage, opts, lam, o: dict):
        self.form, self.inner, self.opts, self.o = form, inner, opts, o
        self.comps = attitude_components(form.error_model)
        rest = [c for c in getattr(form.error_model, "components", (form.error_model,))
                if c not in self.comps]
        self.rest_model = None if not rest else (rest[0] if len(rest) == 1 else sum(rest[1:], rest[0]))
        self.raw = form.data
        self.names = [n for c in self.comps for n in c.names(self.raw)]
        self.lam = lam
        self.rule = lam if isinstance(lam, str) else None
        self.evaluations = 0
        self.solves = 0
        self.curve = None

    def _form(self, data, error_model) -> Formulation:
        f = self.form
        return Formulation(data, f.residual, f.sigma_a if f.sigma_a_given else None, error_model, f.items)

    def _solve(self, form) -> Solution:
        sol = self.inner(form, self.lam, self.opts)
        self.solves += 1
        if self.rule is not None and not isinstance(self.lam, float):
            self.curve = sol.curve
            self.lam = float(sol.lam)
        return sol

    def evaluate(self, values: dict) -> tuple[float, Solution]:
        """``J(values)``: the convex problem with the attitude fixed at these totals."""
        data = reintegrate(self.raw, self.form.error_model, values)
        sol = self._solve(self._form(data, self.rest_model))
        self.evaluations += 1
        used = sol.__dict__.get("_formulation")
        j = objective_value(used, sol.x, float(sol.lam)) + _prior_cost(self.comps, data)
        return j, sol

    def step(self, values: dict, damping: float) -> tuple[dict, float, Solution]:
        """One damped linearized solve at ``values``: new totals, attitude change (rad), solution."""
        data = reintegrate(self.raw, self.form.error_model, values, damping=damping)
        form = self._form(data, self.form.error_model)
        sol = self._solve(form)
        model = form.model
        parts = model.split(sol.x)
        names = list(model.param_names)
        delta = {n: float(v) for n, v in zip(names, parts["l"], strict=True) if n in self.names}
        new = {n: values.get(n, 0.0) + delta.get(n, 0.0) for n in self.names}
        rate = np.zeros((data.n, 3))
        init = np.zeros(3)
        for c in self.comps:
            d = np.array([delta[n] for n in c.names(data)])
            rate = rate + c.rate_columns(data) @ d
            init = init + c.initial_columns(data) @ d
        psi = propagate(data, rate[:, :, None], init[:, None])
        change = float(np.max(np.linalg.norm(psi[:, :, 0], axis=1)))
        return new, change, sol

    def heading_start(self, values: dict) -> tuple[dict, list]:
        from ..error_models.attitude_error import AttitudeError

        att = next((c for c in self.comps if isinstance(c, AttitudeError)), None)
        o = self.o
        if att is None or "attitude_z" not in att.names(self.raw):
            return values, []
        free = not np.isfinite(att.prior_sigma(self.raw)[att.names(self.raw).index("attitude_z")])
        if o["heading"] == "given" or (o["heading"] == "auto" and not free):
            return values, []
        n = int(o["candidates"])
        found = []
        best = None
        for k in range(n):
            yaw = float(np.angle(np.exp(1j * 2.0 * np.pi * k / n)))
            trial = {**values, "attitude_z": yaw}
            j, _ = self.evaluate(trial)
            found.append({"heading": yaw, "objective": j})
            log.info("attitude loop: heading %.1f deg -> objective %.6g", np.degrees(yaw), j)
            if best is None or j < best[0]:
                best = (j, trial)
        return best[1], found


def _warn(sol: Solution, msg: str) -> None:
    sol.warnings.append(msg)
    warn(msg)


def with_attitude(inner: Stage) -> Stage:
    """The stage that solves formulations with attitude error models by the damped outer
    loop (see the module docstring); others pass straight to ``inner``.

    The stage reads ``opts.attitude`` (:data:`ATTITUDE_DEFAULTS`):

    tol : float
        Stop when the largest attitude change a step makes over the window is below
        this, rad (default 1e-7 rad).
    max_iter : int
        Largest number of linearized steps (accepted or not), default 30.
    heading : {"auto", "search", "given"}
        The global start for the heading (``"auto"``: search when ``AttitudeError``
        estimates the heading without a prior).
    candidates : int
        Headings tried by the search (default 12, every 30 degrees).
    loop : bool
        False: one linearized solve about the data as given (no re-integration; the
        linear model of the columns, e.g. for contract checks and teaching).
    progress : bool, optional
        A tqdm bar of the iterations (None: when stderr is a terminal).

    The answer is the last linearized solve at the accepted totals (its increments are
    below ``tol``), so ``error_params`` holds the totals and ``solve(uncertainty=...)``
    their standard deviations. ``stats["sequential"]`` holds the loop's report
    (:class:`~bvpnav.result.AttitudeLoopReport`): per iteration the objective before and
    after, the step (rad), whether it was accepted, the damping.
    """

    def stage(form, lam, opts) -> Solution:
        comps = attitude_components(form.error_model)
        if not comps:
            return inner(form, lam, opts)
        o = check_attitude(getattr(opts, "attitude", None))
        if at_point(form.data).values:
            raise InputError("attitude loop: this data already carries a linearization point; give the "
                             "data as measured")
        t0 = time.perf_counter()
        loop = _Loop(form, inner, opts, lam, o)
        values = {n: 0.0 for n in loop.names}
        if not o["loop"]:
            sol = inner(form, lam, opts)
            sol.attitude = reintegrate(form.data, form.error_model, {
                n: float(sol.error_params[n]) for n in loop.names}).attitude
            return sol
        values, search = loop.heading_start(values)
        j, _ = loop.evaluate(values)
        j0 = j
        damping = 0.0
        iters: list[dict] = []
        converged = False
        sol = None
        with progress(desc="attitude loop", unit="iter", enabled=o["progress"]) as bar:
            for _ in range(int(o["max_iter"])):
                new, change, sol = loop.step(values, damping)
                if change < o["tol"]:
                    converged = True
                    iters.append({"objective": j, "trial": j, "step": change, "accepted": False,
                                  "damping": damping, "converged": True})
                    break
                j_new, _ = loop.evaluate(new)
                accepted = bool(j_new < j)
                iters.append({"objective": j, "trial": j_new, "step": change, "accepted": accepted,
                              "damping": damping})
                log.info("attitude iteration %d: objective %.9g -> %.9g, step %.3g rad, damping %.3g, %s",
                         len(iters), j, j_new, change, damping, "accepted" if accepted else "rejected")
                bar.update(1)
                if accepted:
                    values, j = new, j_new
                    if "attitude_z" in values:  # R_z is periodic: keep the heading in (-pi, pi]
                        values["attitude_z"] = float(np.angle(np.exp(1j * values["attitude_z"])))
                    damping = 0.0 if damping < 1e-6 else damping / 10.0
                else:
                    damping = 1e-3 if damping == 0.0 else damping * 10.0
                    if damping > MAX_DAMPING:
                        converged = True  # no step lowers J: a minimum to rounding
                        break
            if converged and (sol is None or damping > 0.0 or not iters[-1].get("converged")):
                _, _, sol = loop.step(values, 0.0)
        if sol is None:  # pragma: no cover - max_iter >= 1
            raise InputError("attitude loop: no iteration ran")
        if not converged:
            _, _, sol = loop.step(values, 0.0)
            msg = (f"attitude loop did not converge in {o['max_iter']} iterations: the last step changed the "
                   f"attitude by {iters[-1]['step']:.3g} rad > tol={o['tol']:g} rad. Raise max_iter "
                   f"(solve(..., attitude={{'max_iter': {2 * int(o['max_iter'])}}})), give better priors "
                   "(sigma= on GyroBias/AttitudeError, e.g. from bvpnav.sensors.grade), or a better initial "
                   "attitude (bvpnav.align)")
            _warn(sol, msg)
        totals = {n: float(sol.error_params[n]) for n in loop.names}
        sol.attitude = reintegrate(form.data, form.error_model, totals).attitude
        report = AttitudeLoopReport(
            kind="attitude", iterations=iters, converged=converged, tol=float(o["tol"]),
            max_iter=int(o["max_iter"]), objective_initial=j0, objective=j, heading_search=search,
            solves=loop.solves, seconds=time.perf_counter() - t0, inner=sol.records.sequential)
        sol.records.attitude = report
        sol.record()
        if loop.rule is not None:
            sol.lam_rule = f"{loop.rule} (first evaluation)"
            sol.curve = loop.curve
        return sol

    return stage
