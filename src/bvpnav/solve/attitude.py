r"""The damped outer loop for attitude error models (gyro errors, initial attitude).

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
   :math:`\mu \sum_p (\delta_p / s_p)^2`;
3. evaluate the nonlinear objective :math:`J(x + \delta)`: re-integrate at the new totals
   and solve the convex problem with the attitude *fixed* there (every other unknown
   free), adding the attitude priors;
4. accept the step only if :math:`J` falls (then :math:`\mu` shrinks tenfold), else
   raise :math:`\mu` tenfold and try again from ``x``;
5. stop when the largest attitude change over the window that an undamped step makes,
   :math:`\max_k \|\psi_k(\delta)\|`, is below ``tol`` (rad), or when an accepted step
   lowers :math:`J` by less than ``ftol`` relative.

Linear convergence. Gauss-Newton leaves out the curvature of the acceleration times the
residual; where the residual is large (fast motion the linear-acceleration model does not
follow, a foot's swing at 6 rad/s) the steps then shrink by a steady ratio ``r`` (the
foot-walk benchmark's docstring gives it) instead of quadratically. When an accepted step is more
than 0.3 of the previous one, the loop also evaluates the point ``1/(1 - r)`` steps along
the same direction and keeps it if it lowers :math:`J` further.

A global start, for an unknown heading: when ``AttitudeError`` estimates the heading
without a prior on it, the loop first evaluates :math:`J` at ``candidates`` headings
equally spaced over the circle (the attitude otherwise as given) and starts from the
best. With position information that makes the heading observable, this brings the start
within half a spacing (15 degrees for 12 candidates) of the answer, from where the damped
loop converges; without such information the heading stays what the priors make it.

The candidates are scored without the items whose rows turn with the attitude (body-frame
items such as :class:`~bvpnav.constraints.NonHolonomic`): with the attitude held fixed, such an
item scores a heading a few degrees off nearly as badly as one far off (with them a search can
pick a heading far off, from where the loop does not come back), while the position information
it leaves alone is what tells the headings apart. The loop then starts from the best candidate
with every item.

An unobservable heading is detected, not rounded: when nothing constrains the horizontal
direction (position fixes at one place only, or a walk with stances only) every candidate
scores the same, and picking the smallest would pick by rounding. The candidates are
evaluated in a spread order (the given heading first); for an equality-constrained
least-squares problem the objective is a trigonometric polynomial of degree 2 in the
heading (the accelerations are affine in its cosine and sine), so five equal values make
it constant and the search stops there. Equal means within :data:`HEADING_RTOL` of the
objective. The given heading is then kept, a warning says why, and the loop's report
says ``heading="unobservable"``.

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

from ..declare import ATTITUDE, check_option, defaults
from ..error_models._attitude import (
    at_point,
    attitude_components,
    propagate,
    reintegrate,
    with_damping,
)
from ..errors import InputError
from ..formulation import Formulation
from ..items import Linearizable
from ..log import progress, warn
from ..model import Cone, LinearizationPoint
from ..result import AttitudeLoopReport, Solution

__all__ = ["with_attitude", "check_attitude", "ATTITUDE_DEFAULTS", "objective_value", "hold_yaw_rate",
           "stance_turn", "stance_turn_warnings", "TURN_CONFIRM_SIGMAS", "TURN_NEGLIGIBLE",
           "parts_warnings"]

log = logging.getLogger(__name__)

Stage = Callable[..., Solution]

#: Options of the attitude loop and their defaults (``solve(attitude={...})``).
ATTITUDE_DEFAULTS: dict = defaults(ATTITUDE)

#: Weight of the violation of hard and band rows that act on the attitude models alone
#: (:meth:`_Loop.item_cost`), per (item unit)^2: a violation of 1e-8 rad/s weighs as much as
#: a unit of the objective.
MERIT_WEIGHT = 1e16

#: Candidate headings whose objectives differ by at most this fraction of the largest
#: (and of 1) cannot be told apart: the heading is unobservable. An unobservable heading
#: leaves differences of rounding; position information that makes it observable changes the
#: objective between headings by orders of magnitude more than this.
HEADING_RTOL = 1e-8

#: Equal objectives at this many distinct headings prove an equality-constrained
#: least-squares objective constant (a trigonometric polynomial of degree 2).
HEADING_PROOF = 5

#: Largest damping weight tried before the loop stops at a point no step improves.
MAX_DAMPING = 1e12

#: A part of the objective (the motion's, or the gyro-only items') that rises from the start
#: to the answer by more than the chi-square quantile of this probability (degrees of
#: freedom: the attitude parameters) is a conflict between the two, with a warning: where the
#: model holds, an attitude correction lowers both or moves either by about its parameter
#: count.
PARTS_CONFIDENCE = 0.999

#: The heading change the gyro-bias correction makes over the recording is confirmed by the
#: still intervals when it exceeds this many of its standard errors under what they state
#: (see :func:`stance_turn_warnings`; 2: about 95 %).
TURN_CONFIRM_SIGMAS = 2.0

#: A heading change below this, deg, is not reported unconfirmed: half a degree is below the
#: heading any pedestrian reference resolves (a magnetometer's 1-2 degrees, the scatter of a
#: walker's stride headings), so it cannot make an answer noticeably worse.
TURN_NEGLIGIBLE = 0.5


def check_attitude(options: dict | None) -> dict:
    """The loop's options with defaults, or :class:`InputError` naming a wrong one (the
    declared table :data:`bvpnav.declare.ATTITUDE`)."""
    return {**ATTITUDE_DEFAULTS, **(check_option("attitude", options) or {})}


# ------------------------------------------------------------- objective
def _penalty(term, x: np.ndarray) -> float:
    """The value of one penalty term at ``x`` (without ``lam``)."""
    sig = term.sigma
    if isinstance(term.residual, Cone):
        k = term.residual.size
        e = np.maximum(term.residual.excess(x), 0.0) / sig[::k]
        return float(np.sum(e**2) if term.mode == "soft" else np.sum(e))
    if term.soft_edges:
        return float(np.sum((term.excess(x) / sig) ** 2))
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


def objective_value(form: Formulation, x: np.ndarray, lam: float) -> float:
    r"""The convex problem's objective at the stacked solution ``x`` (dimensionless).

    Notes
    -----
    :math:`J = \|D_0 x + c_0\|^2 + \sum_{\text{items}} \lambda\,P_i(x) + \sum_{\text{priors}} P_j(x)`
    with the data rows :math:`D_0 x + c_0` of :meth:`bvpnav.formulation.Formulation.data_rows`
    and each penalty :math:`P` as cvxpy is given it (squares, Huber, L1, positive parts).
    """
    j = float(np.sum(form.data_rows().value(x) ** 2))
    for term in form.terms():
        if term.is_penalty:
            j += term.weight(lam) * _penalty(term, x)
    return j


# ------------------------------------------------------------- the loop
def _bilinear(item) -> bool:
    """Whether the item's rows are bilinear in a parameter and the velocity (an estimated
    mounting or side slip of a vehicle item)."""
    return bool(getattr(item, "mounting", None)) or getattr(item, "slip", None) == "estimated"


def _turns_with_attitude(items) -> bool:
    """Whether some item's rows turn with the attitude and so take the loop's linearization
    point: body-frame items (``body_frame``) and fixes of an antenna off the IMU
    (``turns_with_attitude``)."""
    return any(getattr(it, "body_frame", False) or getattr(it, "turns_with_attitude", False) for it in items)


class _Loop:
    def __init__(self, form: Formulation, inner: Stage, opts, lam, o: dict):
        self.form, self.inner, self.opts, self.o = form, inner, opts, o
        self.comps = attitude_components(form.error_model)
        rest = [c for c in getattr(form.error_model, "components", (form.error_model,))
                if c not in self.comps]
        self.rest_model = None if not rest else (rest[0] if len(rest) == 1 else sum(rest[1:], rest[0]))
        self.raw = form.data
        self.names = [n for c in self.comps for n in c.names(self.raw)]
        self.lam = lam
        self.rule = lam if isinstance(lam, str) else None
        self.solves = 0
        self.checked: dict = {}
        self.curve = None
        self._data: dict = {}
        self.parts: dict = {}
        #: The last evaluation, about whose velocity the next one linearizes rows bilinear in a
        #: parameter and the velocity (None until the first; see :meth:`evaluate`).
        self.velocity_point: Solution | None = None
        self.active_hints: dict = {}

    def data_at(self, values: dict):
        """The data re-integrated at the totals ``values`` (undamped), kept for the few most
        recent points: an evaluation at a point and the step from it share one integration."""
        key = tuple(float(values[n]) for n in self.names)
        if key not in self._data:
            if len(self._data) >= 4:
                self._data.pop(next(iter(self._data)))
            self._data[key] = reintegrate(self.raw, self.form.error_model, values)
        return self._data[key]

    def _form(self, data, error_model, search: bool = False, items: list | None = None) -> Formulation:
        """The fixed-attitude formulation of ``data`` with ``error_model`` and the loop's items
        (``items``: others in their place, whose observability is checked afresh)."""
        f = self.form
        own = items is None
        items = f.items if own else items
        if search:  # the heading search scores candidates without the items that turn with the attitude
            items = [it for it in items if not getattr(it, "body_frame", False)]
        if error_model is not f.error_model:  # attitude fixed: items on the gyro model alone drop out
            items = [it for it in items if not it.needs_error_model]
        out = Formulation(data, f.residual, f.sigma_a if f.sigma_a_given else None, error_model, items,
                          grade=None)  # the priors were filled in (or not) on the first formulation
        out.grade_report = f.grade_report
        # the same items and error model at every point: what determines the unknowns was
        # checked on the first formulation of each kind (an SVD, a fifth of a solve)
        out._observable = own and self.checked.get(id(error_model), False)
        return out

    def _solve(self, form: Formulation) -> Solution:
        # the band and inequality rows at their bounds in the last answer start the next
        # solve's active set (bvpnav.linalg.active_set); nothing else of a workspace is shared
        from ..linalg.workspace import Workspace

        key = id(form.error_model)   # the evaluations' and the steps' problems differ: one hint each
        workspace = Workspace(active_hint=self.active_hints.get(key))
        sol = self.inner(form, self.lam, self.opts, workspace=workspace)
        self.active_hints[key] = workspace.active_hint
        self.solves += 1
        self.checked[id(form.error_model)] = True
        note = str(sol.stats.get("factorization", ""))
        if sol.stats.get("solver") == "direct" and note.startswith("lu (ldl"):
            # every solve of the loop has the same sparse block (the attitude changes only the
            # dense columns and the data): where the regularized LDL^T failed once it fails
            # again, so the later solves go straight to the LU instead of factorising twice
            from dataclasses import replace

            chain = [(be, {**o, "method": "lu"}) if be.name == "direct" else (be, o)
                     for be, o in self.opts.chain]
            self.opts = replace(self.opts, chain=chain)
        if self.rule is not None and not isinstance(self.lam, float):
            self.curve = sol.curve
            self.lam = float(sol.lam)
        return sol

    def evaluate(self, values: dict, search: bool = False) -> tuple[float, Solution]:
        """``J(values)``: the convex problem with the attitude fixed at these totals (``search``:
        without body-frame items, for the heading search)."""
        data = self.data_at(values)
        if not search and self.velocity_point is None and self.mounted:
            self.velocity_point = self._unmounted(data)
        if not search and self.velocity_point is not None:
            # rows bilinear in a parameter and the velocity (NonHolonomic(mounting="estimated")):
            # about the last evaluation's velocity, as a step's are about its evaluation's
            import copy

            data = copy.copy(data)
            m = self.velocity_point.formulation.model
            vel = m.point_velocities(self.velocity_point.x)
            data.body_point = LinearizationPoint(velocity=vel, names=(), psi=np.zeros((data.n, 3, 0)))
        sol = self._solve(self._form(data, self.rest_model, search))
        if not search and self.mounted:
            self.velocity_point = sol
        used = sol.formulation
        motion = objective_value(used, sol.x, float(sol.lam))
        priors = sum(c.prior_cost(data) for c in self.comps)
        gyro_items = self.item_cost(data, float(sol.lam))
        self.parts[tuple(float(values[n]) for n in self.names)] = {
            "motion": motion, "gyro_items": gyro_items, "priors": priors}
        return motion + priors + gyro_items, sol

    @property
    def mounted(self) -> bool:
        """Whether an item's rows are bilinear in a parameter and the velocity
        (``NonHolonomic(mounting="estimated")``, ``NonHolonomic(slip="estimated")``)."""
        return any(_bilinear(it) for it in self.form.items)

    def _unmounted(self, data) -> Solution:
        """The first velocity point of mounted items: the fixed-attitude solve with the vehicle
        axes taken as the body's (the items without ``mounting`` and soft, the error model
        without the component that provides it)."""
        from dataclasses import replace

        rest = [c for c in getattr(self.rest_model, "components", (self.rest_model,))
                if c is not None and getattr(type(c), "provides", None) not in ("mounting", "side_slip")]
        model = None if not rest else (rest[0] if len(rest) == 1 else sum(rest[1:], rest[0]))
        # soft (0.1 m/s where the item gives no sigma): hard rows about the body's axes could
        # conflict with the other hard information, which holds about the vehicle's
        items = [replace(it, mounting=None, mode="soft", tol=None, huber=None,
                         sigma=0.1 if it.sigma is None else it.sigma,
                         **({"slip": None} if getattr(it, "slip", None) == "estimated" else {}))
                 if _bilinear(it) else it
                 for it in self.form.items if not it.needs_error_model]
        form = self._form(data, model, items=items)
        sol = self.inner(form, self.lam if isinstance(self.lam, float) else 1.0, self.opts)
        self.solves += 1
        return sol

    def parts_at(self, values: dict) -> dict | None:
        """The objective's parts at an evaluated point: ``motion`` (the data rows and the items
        the fixed-attitude solve fits), ``gyro_items`` (items on the attitude models alone, e.g.
        ZeroAngularRate) and ``priors``; None for a point not evaluated."""
        return self.parts.get(tuple(float(values[n]) for n in self.names))

    def item_cost(self, data, lam: float) -> float:
        r"""The cost, at zero increments, of the items that act on the attitude error models
        alone (:attr:`bvpnav.Item.needs_error_model`, e.g. a gyro stance): they are left out of
        the fixed-attitude solve and counted here, as the priors are.

        Notes
        -----
        Soft and robust items add their penalties. Hard and band rows, which each linearized
        step meets, add the quadratic merit :math:`\mu \sum_k v_k^2` of their violation
        :math:`v_k = \max(|\rho_k| - tol_k, 0)` (``tol`` 0 when hard) with
        :math:`\mu` = :data:`MERIT_WEIGHT`, so that a point that breaks them never wins
        against one that keeps them.
        """
        items = [it for it in self.form.items if it.needs_error_model]
        if not items:
            return 0.0
        f = self.form
        form = Formulation(data, f.residual, f.sigma_a if f.sigma_a_given else None, f.error_model, items,
                           grade=None)
        x = np.zeros(form.model.size)
        cost = 0.0
        for term in form.terms():
            if term.item is None:
                continue
            if term.is_penalty:
                cost += term.weight(lam) * _penalty(term, x)
            else:
                tol = 0.0 if term.tol is None else term.tol
                v = np.maximum(np.abs(term.residual.value(x)) - tol, 0.0)
                cost += MERIT_WEIGHT * float(v @ v)
        return cost

    def step(self, values: dict, damping: float, at_values: Solution | None = None
             ) -> tuple[dict, float, Solution]:
        """One damped linearized solve at ``values``: new totals, attitude change (rad), solution.
        ``at_values``, the evaluation at ``values``, gives the velocity about which body-frame
        items linearize their attitude terms (``data.body_point``, see
        :meth:`bvpnav.NavModel.body_velocity`)."""
        data = self.data_at(values)
        if damping:
            data = with_damping(data, damping)
        if at_values is not None and _turns_with_attitude(self.form.items):
            data = self.body_point(data, at_values)
        form = self._form(data, self.form.error_model)
        sol = self._solve(form)
        model = form.model
        parts = model.split(sol.x)
        names = list(model.param_names)
        delta = {n: float(v) for n, v in zip(names, parts["l"], strict=True) if n in self.names}
        new = {n: values.get(n, 0.0) + delta.get(n, 0.0) for n in self.names}
        rate = np.zeros((data.n, 3))
        init = np.zeros(3)
        direct = np.zeros((data.n, 3))
        for c in self.comps:
            d = np.array([delta[n] for n in c.names(data)])
            rate = rate + c.rate_change(data, d)
            init = init + c.initial_columns(data) @ d
            direct = direct + c.direct_change(data, d)
        psi = propagate(data, rate[:, :, None], init[:, None])[:, :, 0] + direct
        change = float(np.max(np.linalg.norm(psi, axis=1)))
        return new, change, sol

    def body_point(self, data, at_values: Solution):
        """A shallow copy of ``data`` carrying the :class:`~bvpnav.model.LinearizationPoint` of
        body-frame items: the velocity of the evaluation ``at_values`` and every attitude
        parameter's navigation-frame attitude change per unit (its propagated rate and initial
        columns, plus its direct columns for a walk)."""
        import copy

        m = at_values.formulation.model
        vel = m.point_velocities(at_values.x)
        names, cols = [], []
        for c in self.comps:
            psi = propagate(data, np.asarray(c.rate_columns(data), dtype=float),
                            np.asarray(c.initial_columns(data), dtype=float))
            if hasattr(c, "direct_columns"):
                psi = psi + c.direct_columns(data)
            names += list(c.names(data))
            cols.append(psi)
        out = copy.copy(data)
        ep = at_values.error_params
        lever = tuple(float(ep[f"lever_{a}"]) for a in "xyz") if "lever_x" in ep.index else None
        out.body_point = LinearizationPoint(velocity=vel, names=tuple(names),
                                            psi=np.concatenate(cols, axis=2), lever=lever)
        return out

    def heading_start(self, values: dict) -> tuple[dict, list, tuple | None, str | None]:
        """The start: ``values`` with the best candidate heading, the candidates' objectives,
        ``(J, solution)`` of the best (None without a search) and what the search found
        (None without a search, ``"searched"`` or ``"unobservable"``: the candidates
        cannot differ and ``values`` keeps the given heading)."""
        from ..error_models.attitude_error import AttitudeError

        att = next((c for c in self.comps if isinstance(c, AttitudeError)), None)
        o = self.o
        if att is None or "attitude_z" not in att.names(self.raw):
            return values, [], None, None
        free = not np.isfinite(att.prior_sigma(self.raw)[att.names(self.raw).index("attitude_z")])
        if o["heading"] == "given" or (o["heading"] == "auto" and not free):
            return values, [], None, None
        n = int(o["candidates"])
        golden = 0.5 * (np.sqrt(5.0) - 1.0)
        order = sorted(range(n), key=lambda k: (k * golden) % 1.0)  # 0 (the given heading) first
        # the degree-2 argument holds when every row is a least-squares row of the solve
        # (no linearized items, no items costed beside it at the point)
        exact = (not self.form.nonlinear_items
                 and not any(getattr(it, "needs_error_model", False) for it in self.form.items)
                 and all(t.least_squares_role() is not None for t in self.form.terms()))
        found, sols = [], []
        for m, k in enumerate(order):
            yaw = float(np.angle(np.exp(1j * 2.0 * np.pi * k / n)))
            trial = {**values, "attitude_z": yaw}
            j, sol = self.evaluate(trial, search=True)
            found.append({"heading": yaw, "objective": j})
            sols.append((j, trial, sol))
            log.info("attitude loop: heading %.1f deg -> objective %.6g", np.degrees(yaw), j)
            if exact and m + 1 == HEADING_PROOF and m + 1 < n and _indistinct(found):
                break
        if _indistinct(found):
            return values, found, (sols[0][0], sols[0][2]), "unobservable"
        best = min(sols, key=lambda b: b[0])
        return best[1], found, (best[0], best[2]), "searched"


def _indistinct(found: list) -> bool:
    """Whether the candidates' objectives agree within :data:`HEADING_RTOL`."""
    j = np.array([c["objective"] for c in found])
    return bool(np.ptp(j) <= HEADING_RTOL * max(1.0, float(np.max(np.abs(j)))))


def _heading_warning(found: list, exact: bool) -> str:
    j = np.array([c["objective"] for c in found])
    spread = float(np.ptp(j) / max(1.0, float(np.max(np.abs(j)))))
    proof = (f"; the objective is a degree-2 trigonometric polynomial of the heading, so {len(found)} "
             "equal values make it constant and the search stopped there") if exact else ""
    return (f"attitude loop: the heading is not observable: {len(found)} candidate headings score the "
            f"same (objectives within {spread:.1g} relative{proof}). No information fixes the "
            "horizontal direction (e.g. position fixes at one place only, or stances only), so the "
            "given heading is kept (the data's initial attitude). To determine it, add a position fix "
            "away from the start, a velocity or heading item, or a prior (AttitudeError(sigma=...))")


def _at_point(loop: _Loop, values: dict, at_values: Solution) -> Solution:
    """The answer at the accepted totals ``values``, as a solution of the undamped
    linearized problem there with zero increments.

    The evaluation ``at_values`` (attitude fixed at ``values``) is the optimum of that
    problem restricted to zero increments, so its stacked vector with zeros inserted for
    the increments is a point of it: the trajectory is the evaluation's, ``error_params``
    report the totals, and the uncertainty stage gets the formulation with the attitude
    parameters (their standard deviations included).
    """
    from .assemble import make_solution

    data = loop.data_at(values)
    if _turns_with_attitude(loop.form.items):  # their attitude terms too
        data = loop.body_point(data, at_values)
    form = loop._form(data, loop.form.error_model)
    used = at_values.formulation
    # items the sequential loop linearized (a delayed fix, a track) at their last linearization
    lin = {it.label: it for it in used.items}
    waiting = [isinstance(it, Linearizable) and it.needs_linearization for it in form.items]
    if any(waiting):
        form = form.with_items([lin.get(it.label, it) if w else it for it, w in zip(form.items, waiting,
                                                                                  strict=True)])
    small, full = used.model, form.model
    x = np.zeros(full.size)
    head = full.d * full.block
    x[:head] = at_values.x[:head]
    have = dict(zip(small.param_names, at_values.x[head:], strict=True))
    x[head:] = [have.get(n, 0.0) for n in full.param_names]
    sol = make_solution(form, x, at_values.lam, at_values.lam_rule, at_values.records)
    sol.attitude_data = loop.raw.attitude  # the data's own, before the loop's corrections
    sol.warnings = list(dict.fromkeys(at_values.warnings + sol.warnings))
    sol.curve = at_values.curve
    return sol


def _informs_yaw_rate(item, axis: str) -> bool:
    """Whether ``item`` carries information on the heading or on the gyro along body ``axis``:
    a ZeroAngularRate on that axis, or any item that does not declare
    ``heading_information`` False (unknown items count as informing)."""
    if getattr(item, "zero_rate", False):
        return item.axes is None or axis in item.axes
    return bool(getattr(item, "heading_information", True))


def hold_yaw_rate(form: Formulation) -> tuple[Formulation, list, str]:
    """The formulation with the yaw-rate gyro bias held at its prior when nothing informs it.

    Returns ``(formulation, held parameter names, warning)``; the formulation unchanged (and
    ``[]``, ``""``) when there is no ``GyroBias`` on the vertical body axis or an item informs it.

    Notes
    -----
    The vertical body axis is the one along the mean specific force of the recording (the
    up direction of a body that is, on average, not accelerating). A bias about it turns
    the horizontal acceleration of the motion only: stances (zero velocity, the same in every
    direction), a floor height and a start position cannot tell it from the swing's own
    errors, and an estimate there absorbs them (2.1 deg/s on a real walk whose gyro read
    under 0.01 deg/s in every stance). Held by a hard row on the total at the prior
    (:class:`~bvpnav.error_models.GyroBias` ``hold``), it stays there exactly.
    """
    from ..error_models.gyro_bias import GyroBias

    comps = list(getattr(form.error_model, "components", (form.error_model,)))
    sf = getattr(form.data, "specific_force", None)
    if sf is None or not any(isinstance(c, GyroBias) for c in comps):
        return form, [], ""
    axis = "xyz"[int(np.argmax(np.abs(np.mean(np.asarray(sf, dtype=float), axis=0))))]
    targets = [i for i, c in enumerate(comps) if isinstance(c, GyroBias)
               and axis in [c.AXES[j] for j in c._sel()] and axis not in (c.hold or ())]
    if not targets or any(_informs_yaw_rate(it, axis) for it in form.items):
        return form, [], ""
    from dataclasses import replace

    for i in targets:
        comps[i] = replace(comps[i], hold=tuple(comps[i].hold or ()) + (axis,))
    em = comps[0] if len(comps) == 1 else sum(comps[1:], comps[0])
    out = Formulation(form.data, form.residual, form.sigma_a if form.sigma_a_given else None, em, form.items,
                      grade=None)
    out.grade_report = form.grade_report
    held = [n for i in targets for n in (comps[i].names(form.data)[k] for k in comps[i].held(form.data))
            if n.startswith(f"gyro_bias_{axis}")]
    kinds = sorted({type(it).__name__ for it in form.items}) or ["none"]
    prior = sorted({float(v) for i in targets
                    for v in comps[i].prior_values(form.data)[comps[i].held(form.data)]})
    msg = (f"attitude loop: nothing carries heading information (items: {', '.join(kinds)}), so the "
           f"yaw-rate gyro bias (body axis {axis}, along the mean specific force) cannot be told from the "
           f"motion's own errors: {len(held)} parameter(s) gyro_bias_{axis} held at the prior "
           f"({', '.join(f'{p:g}' for p in prior)} rad/s) instead of estimated. To estimate it, add heading "
           f"information (positions at other instants, a SamePosition of a loop, a KnownDistance) or a "
           f"ZeroAngularRate on axis {axis}")
    return out, held, msg


def parts_warnings(parts: dict | None, q: int) -> list[str]:
    r"""Warnings when the attitude models' answer trades one part of the objective for the other.

    Parameters
    ----------
    parts : dict
        ``{"initial": {...}, "answer": {...}}`` of :meth:`_Loop.parts_at` (``motion``,
        ``gyro_items``, ``priors``).
    q : int
        Number of attitude parameters.

    Returns
    -------
    list of str

    Notes
    -----
    A rise :math:`\Delta` of a part (in the stated sigmas' chi-square units) beyond
    :math:`\chi^2_{q}(p)`, :math:`p` = :data:`PARTS_CONFIDENCE`, is more than estimating
    :math:`q` parameters from consistent information costs it. The motion's part rising: the
    gyro-only items (stances read by the gyro) turned the attitude against what the
    accelerations and stances say, e.g. a foot that rolls in its detected stances. The gyro
    items' part rising while the motion's falls: the gyro bias was set by the motion's misfit
    (errors the model does not have, e.g. a foot's swing against a white ``sigma_a``), away
    from what the gyro reads where the body is still; the heading follows it. On 12 real foot
    trials with ``GyroBias`` and ``ZeroAngularRate``, either made turn and heading worse than
    ``Bias()`` alone.

    Examples
    --------
    >>> from bvpnav.solve.attitude import parts_warnings
    >>> walk = {"initial": {"motion": 5679.5, "gyro_items": 985674.1, "priors": 0.0},
    ...         "answer": {"motion": 28855.9, "gyro_items": 917816.0, "priors": 5.3}}
    >>> print(parts_warnings(walk, 3)[0][:101])
    attitude models: the answer fits the gyro-only items (e.g. ZeroAngularRate) better (985674 -> 917816)
    >>> walk["answer"]["motion"] = 10.0      # both parts fall: the model holds, nothing to say
    >>> parts_warnings(walk, 3)
    []
    """
    if not parts or parts.get("initial") is None or parts.get("answer") is None:
        return []
    from scipy.stats import chi2

    a, b = parts["initial"], parts["answer"]
    limit = float(chi2.ppf(PARTS_CONFIDENCE, max(int(q), 1)))
    out = []
    rise_m = b["motion"] - a["motion"]
    rise_g = b["gyro_items"] - a["gyro_items"]
    if rise_m > limit:
        out.append(
            f"attitude models: the answer fits the gyro-only items (e.g. ZeroAngularRate) better "
            f"({a['gyro_items']:.6g} -> {b['gyro_items']:.6g}) by fitting the motion worse "
            f"({a['motion']:.6g} -> {b['motion']:.6g}, a rise beyond {limit:.3g} for {q} parameters): "
            "what the gyro reads in the intervals said to be still contradicts the accelerations (a foot "
            "still rolls in a detected stance). Compare with the answer without the attitude models, and "
            "give ZeroAngularRate a sigma that covers the stances' own rates "
            "(zero_velocity_items(..., angular_rate='spread', data=data))")
    elif rise_g > limit and rise_m < 0:
        out.append(
            f"attitude models: the answer fits the motion better ({a['motion']:.6g} -> {b['motion']:.6g}) "
            f"with a gyro correction the gyro-only items (e.g. ZeroAngularRate) contradict "
            f"({a['gyro_items']:.6g} -> {b['gyro_items']:.6g}, a rise beyond {limit:.3g} for {q} "
            "parameters): the gyro bias absorbs errors of the motion the model does not have (sigma_a's "
            "white noise against a swing's), away from what the gyro reads where the body is still, and "
            "the heading follows it. Compare with the answer without the attitude models; hold the bias "
            "at the stances' reading (GyroBias(prior=..., sigma=...)) or leave GyroBias out")
    return out


def stance_turn(form: Formulation, sol: Solution) -> tuple[float, float, int, str] | None:
    r"""The heading change the gyro bias makes and its uncertainty under what the stances state.

    Parameters
    ----------
    form : Formulation
        The formulation the attitude loop solved (its items, data and error model).
    sol : Solution
        Its answer, with ``attitude`` (the attitude used) and the gyro bias totals.

    Returns
    -------
    (float, float, int, str) or None
        The turn :math:`\Delta\psi` and its standard error :math:`\sigma_\psi` (deg), the number
        of still intervals and the yaw-rate body axis; None without a ``GyroBias``, without
        ``ZeroAngularRate`` items on every body axis, or when another item carries heading
        information (:func:`hold_yaw_rate`'s rule).

    Notes
    -----
    The correction turns the heading, against the gyro bias at its prior, by

    .. math:: \Delta\psi = \sum_k u^T C_k\,(b_k - b^0_k)\,\Delta t_k,

    :math:`u` the vertical (along gravity), :math:`C_k` the attitude, :math:`b_k` the bias.
    Where the still intervals (``ZeroAngularRate``) are the only items that carry heading
    information (:func:`hold_yaw_rate`'s rule), they state the bias per body axis with a
    standard error :math:`s_j` (:func:`bvpnav.solve.plausibility._stance_rates`: the readings
    weighted by the items' own :math:`1/\sigma^2`, scaled by their scatter), so the turn with
    :math:`\sigma_\psi = \sqrt{\sum_j (g_j s_j)^2}`, :math:`g = \sum_k C_k^T u\,\Delta t_k`.
    When :math:`|\Delta\psi| \le` :data:`TURN_CONFIRM_SIGMAS` :math:`\sigma_\psi` (and above
    :data:`TURN_NEGLIGIBLE`), the stances cannot tell the correction from none: it was set by
    the motion, which cannot tell a yaw-rate bias from its own unmodelled errors (a foot's
    swing against a white ``sigma_a``), and the heading may be worse than without the model.
    """
    from .plausibility import _kind, _stance_rates

    data = form.data
    att = getattr(sol, "attitude", None)
    gyros = [c for c in getattr(form.error_model, "components", (form.error_model,))
             if _kind(c) == "gyro_bias" and callable(getattr(c, "bias", None))]
    if att is None or not gyros or getattr(data, "gravity", None) is None or data.n < 2:
        return None
    axis = "xyz"[int(np.argmax(np.abs(np.mean(np.asarray(data.specific_force, dtype=float), axis=0))))]
    if any(_informs_yaw_rate(it, axis) and not getattr(it, "zero_rate", False) for it in form.items):
        return None  # other heading information: the motion's correction is not on its own
    stated = _stance_rates(form.items, data)
    if stated is None or any(ax not in stated for ax in "xyz"):
        return None
    se = np.array([stated[ax][1] for ax in "xyz"])
    up = np.asarray(data.gravity, dtype=float).ravel()[:3]
    up = up / np.linalg.norm(up)
    dt = np.gradient(np.asarray(data.t, dtype=float))
    rows = np.einsum("nij,i->nj", att.as_matrix(), up) * dt[:, None]  # u^T C_k dt_k, per sample
    db = np.zeros((data.n, 3))
    for c in gyros:
        names = c.names(data)
        db += c.bias(sol, data) - c.bias(dict(zip(names, c.prior_values(data), strict=True)), data)
    turn = float(np.degrees(np.sum(rows * db)))
    sigma = float(np.degrees(np.linalg.norm(rows.sum(axis=0) * se)))
    return turn, sigma, stated[axis][2], axis


def stance_turn_warnings(form: Formulation, sol: Solution) -> list[str]:
    """A warning when the heading change the gyro bias makes rests on the motion alone: the
    turn of :func:`stance_turn` above :data:`TURN_NEGLIGIBLE` deg and within
    :data:`TURN_CONFIRM_SIGMAS` of its standard error. Returns the messages (empty or one)."""
    found = stance_turn(form, sol)
    if found is None:
        return []
    turn, sigma, k, axis = found
    if abs(turn) <= TURN_NEGLIGIBLE or abs(turn) > TURN_CONFIRM_SIGMAS * sigma:
        return []
    data = form.data
    span = float(data.t[-1] - data.t[0])
    return [f"attitude models: the still intervals do not confirm the heading the gyro bias gives: it turns "
            f"the heading by {turn:+.3g} deg over the {span:.4g} s against the bias at its prior, and what "
            f"the {k} still interval(s) state (ZeroAngularRate, their readings weighted by "
            f"1/sigma^2) fixes that turn only to +-{sigma:.3g} deg ({abs(turn) / sigma:.2g} "
            f"standard errors, at most {TURN_CONFIRM_SIGMAS:g} is no evidence). With no other heading "
            f"information nothing confirms the correction: the motion cannot tell a yaw-rate bias from its "
            f"own unmodelled errors (a foot's swing against a white sigma_a), so the heading may be worse "
            f"than without GyroBias by as much. Compare with the answer without the attitude models; hold "
            f"the yaw-rate bias (GyroBias(hold='{axis}')) or add heading information (a SamePosition of a "
            f"loop, positions at other instants)"]


def _warn(sol: Solution, msg: str) -> None:
    sol.warnings.append(msg)
    warn(msg)


def _iterate(loop: _Loop, values: dict, j: float, at_values: Solution, o: dict):
    """The damped iterations from ``values``: (values, J, the solution at them, the last step's
    solution, the iterations' records, why the loop stopped or None)."""
    damping = 0.0
    iters: list[dict] = []
    reason = None
    sol = None
    last_full = None  # the last accepted undamped step (rad), to detect linear convergence
    with progress(desc="attitude loop", unit="iter", enabled=o["progress"]) as bar:
        for _ in range(int(o["max_iter"])):
            new, change, sol = loop.step(values, damping, at_values)
            if change < o["tol"]:
                # undamped: the Gauss-Newton step itself is below tol (converged); damped:
                # the undamped step raised J and so do the damped ones down to tol, so no
                # step the data can tell apart lowers it (a minimum to rounding)
                reason = "step" if damping == 0.0 else "no descent"
                iters.append({"objective": j, "trial": j, "step": change, "accepted": False,
                              "damping": damping, "converged": True})
                break
            j_new, at_new = loop.evaluate(new)
            accepted = bool(j_new < j)
            entry = {"objective": j, "trial": j_new, "step": change, "accepted": accepted,
                     "damping": damping}
            if accepted and damping == 0.0 and last_full is not None and change > 0.3 * last_full:
                # linear convergence (steps shrinking by a steady ratio r): the remaining
                # distance is about r / (1 - r) steps along the same direction; try the
                # extrapolated point and keep it only if it lowers J further
                r = min(change / last_full, 0.9)
                alpha = 1.0 / (1.0 - r)
                far = {n: values[n] + alpha * (new[n] - values[n]) for n in new}
                j_far, at_far = loop.evaluate(far)
                entry.update(extrapolated=alpha, extrapolated_objective=j_far)
                if j_far < j_new:
                    new, j_new, at_new = far, j_far, at_far
                    entry["trial"] = j_far
            iters.append(entry)
            log.info("attitude iteration %d: objective %.9g -> %.9g, step %.3g rad, damping %.3g, %s",
                     len(iters), j, j_new, change, damping, "accepted" if accepted else "rejected")
            bar.update(1)
            if accepted:
                small = j - j_new <= o["ftol"] * max(abs(j), 1e-300)
                values, j, at_values = new, j_new, at_new
                if abs(values.get("attitude_z", 0.0)) > np.pi:  # R_z is periodic: keep it in (-pi, pi]
                    values["attitude_z"] = float(np.angle(np.exp(1j * values["attitude_z"])))
                if damping == 0.0:
                    last_full = change
                damping = 0.0 if damping < 1e-6 else damping / 10.0
                if small:
                    reason = "objective"
                    break
            else:
                damping = 1.0 if damping == 0.0 else damping * 10.0
                if damping > MAX_DAMPING:
                    reason = "no descent"  # no step lowers J: a minimum to rounding
                    break
    return values, j, at_values, sol, iters, reason


def _direct_first(opts) -> bool:
    """Whether the solve's first back end is ``direct`` (the one whose banded factor an
    intermediate node-state step uses alone)."""
    chain = getattr(opts, "chain", None)
    return bool(chain) and getattr(chain[0][0], "name", None) == "direct"


def _expected(iters: list) -> float:
    """The next step's size (rad) expected from the last two (Gauss-Newton converges
    linearly here: the ratio of successive steps carries on), or the last one's."""
    last = iters[-1]["step"]
    if len(iters) < 2 or not iters[-2]["step"] > 0:
        return last
    return last * min(1.0, last / iters[-2]["step"])


#: The node-state loop's Anderson acceleration (:func:`_anderson`) mixes this many past steps...
ANDERSON_DEPTH = 2

#: ... once the last step is below this largest attitude change, rad (Gauss-Newton's linear
#: regime; the first steps from a heading far off are taken as they come)...
ANDERSON_START = 0.1

#: ... and keeps the mixed point only when it moves the attitude at most this many times as far
#: as the plain step would (else the plain step).
ANDERSON_REACH = 10.0


def _flat_totals(sm, data, totals: dict) -> np.ndarray:
    """The node-state totals of every kind as one vector (kind after kind, (n, 3) each at the nodes)."""
    return np.concatenate([np.asarray(totals[k], dtype=float).ravel() for k in sm.state_kinds(data)])


def _anderson(history: list, n: int) -> tuple[np.ndarray, np.ndarray] | None:
    r"""The Anderson-mixed point from ``history`` (``(x_k, g_k)``: totals before a step and
    after it, as :func:`_flat_totals` vectors of blocks of ``3 n``, one per kind of state),
    and the mixing coefficients; None with too little history or non-finite coefficients.

    Notes
    -----
    Gauss-Newton as a fixed-point map :math:`x \mapsto g(x)` with :math:`f_k = g_k - x_k`
    (the step): with the differences :math:`\Delta f_i = f_{i+1} - f_i`,
    :math:`\Delta g_i = g_{i+1} - g_i` of the last :data:`ANDERSON_DEPTH` + 1 steps,

    .. math:: \gamma = \arg\min_\gamma \|W (f_k - \Delta F \gamma)\|_2, \qquad
              x_{k+1} = g_k - \Delta G\, \gamma,

    ``W`` scaling each kind of state by the RMS of its step (rad, rad/s and m/s^2 weigh
    alike). Where the steps shrink by steady ratios along a few directions (the linear
    convergence of Gauss-Newton where the data misfit their sigmas) this is the secant
    estimate of the limit along them; the fixed point, hence the answer, is the same.
    """
    if len(history) < 2:
        return None
    H = history[-(ANDERSON_DEPTH + 1):]
    f = [g - x for x, g in H]
    fk = f[-1]
    w = np.empty_like(fk)
    for a in range(fk.size // (3 * n)):
        seg = slice(3 * n * a, 3 * n * (a + 1))
        rms = float(np.sqrt(np.mean(fk[seg] ** 2)))
        w[seg] = 1.0 / rms if rms > 0 else 0.0
    dF = np.column_stack([f[i + 1] - f[i] for i in range(len(H) - 1)])
    dG = np.column_stack([H[i + 1][1] - H[i][1] for i in range(len(H) - 1)])
    gam, *_ = np.linalg.lstsq(dF * w[:, None], fk * w, rcond=1e-10)
    if not np.all(np.isfinite(gam)):
        return None
    return H[-1][1] - dG @ gam, gam


def _next_totals(sm, data, s: np.ndarray, iters: list, prev_att: np.ndarray | None, o: dict,
                 history: list) -> tuple[dict, np.ndarray]:
    """The totals at the nodes after the step ``s`` (Anderson-mixed with the past steps,
    :func:`_anderson`, in the linear regime) and this attitude step. ``iters[-1]`` records
    ``turn``, the cosine between this attitude step and the last, and ``accelerated``, the
    mixing coefficients;
    ``history`` keeps ``(x, g)`` of the last steps below :data:`ANDERSON_START` (a step above
    it, or one larger than the step before, clears it: a pair from the nonlinear regime or from
    steps that grow, where Gauss-Newton overshoots, would mislead the secant; so would the grown
    step's own pair as the oldest of the next mixing, which on a simulated consumer car with a
    course start threw the attitude far off and cost steps).

    On a coarse mesh (``sm.node_totals``) the unknowns are the nodes' totals: they are the
    ones mixed, and the samples' totals are made from the point taken when a full pass needs
    them (``sm.expand``, the attitude re-integrated)."""
    att = s[sm.state_index(data, "attitude_error")].ravel()
    if prev_att is not None:
        den = max(float(np.linalg.norm(att) * np.linalg.norm(prev_att)), 1e-300)
        iters[-1]["turn"] = float(att @ prev_att) / den
    plain = sm.node_totals(data, s)     # at the nodes: a coarse mesh's, else every sample
    grew = len(iters) > 1 and iters[-1]["step"] >= iters[-2]["step"]
    if not o["loop"] or iters[-1]["step"] >= ANDERSON_START or grew:
        history.clear()   # mixed only with steps of the linear regime, where they shrink
        return plain, att
    kinds = sm.state_kinds(data)
    before = _flat_totals(sm, data, {k: sm.state_total(data, k) for k in kinds})   # at the nodes
    history.append((before, _flat_totals(sm, data, plain)))
    del history[:-(ANDERSON_DEPTH + 1)]
    if iters[-1]["step"] < o["tol"]:
        return plain, att   # the answer's totals, as Gauss-Newton gives them
    m = before.size // (3 * len(kinds))   # samples, or nodes
    mixed = _anderson(history, m)
    if mixed is None:
        return plain, att
    xn, gam = mixed
    x, g = history[-1]
    na = 3 * m   # the attitude block comes first
    reach = float(np.max(np.abs(g[:na] - x[:na])))
    if np.max(np.abs(xn[:na] - x[:na])) > ANDERSON_REACH * max(reach, 1e-300):
        return plain, att
    iters[-1]["accelerated"] = [float(v) for v in gam]
    return {k: xn[na * i:na * (i + 1)].reshape(m, 3) for i, k in enumerate(kinds)}, att


#: A Gauss-Newton step on a coarse mesh may be cheap while what it leaves out
#: (:func:`~bvpnav.error_models.error_states.cheap_error`, rad: the second-order term of the
#: gyro-bias change since the last full pass) is at most this: the change turns no element by
#: more than about 4.5e-3 rad (0.26 degrees). Cheap steps only move the linearization point (the
#: answer is a full pass's), so this sets how far one full pass carries, not the accuracy (the
#: KITTI benchmark's docstring has the counts it gave against the loop's ``tol`` as the limit).
CHEAP_ERROR = 1e-5

#: Cheap steps are taken where Gauss-Newton converges linearly (:func:`_slow`): the last step at
#: least this fraction of the one before: a real drive whose data misfit their sigmas converges
#: linearly well above it, a noise-free simulated drive quadratically well below it (the rates
#: are in the KITTI benchmark's docstring and the commit that set it).
CHEAP_RATE = 0.02

#: A low estimate of the step of the first full pass after cheap ones, relative to the gyro-bias
#: rotation :math:`\rho_g \le \sqrt{2 e}` of the last (``e``:
#: :func:`~bvpnav.error_models.error_states.cheap_error`): the cheap steps' fixed point is off by
#: about this much or more (their columns' change with the gyro bias is left out). A run of cheap
#: steps ends when its next step is expected below it (converging the cheap model further is
#: wasted), and when it is below ``tol`` that full pass goes through the stage at once. A low
#: estimate: the measured ratios (in the commits that set it) are mostly above it.
CHEAP_GAP = 0.01

#: A first step of at least this, rad, starts far from the answer: the second may be cheap before
#: the rate of convergence is known (:func:`_slow` needs two steps), since several steps follow at
#: any rate (from 0.1 rad quadratic convergence takes three more to 1e-7). The cheap step is
#: still taken only when what it leaves out is within :data:`CHEAP_ERROR`; a start closer than
#: this converges quadratically, where a cheap second step would cost a full pass more.
CHEAP_FIRST = 0.1

#: Items whose rows read the nodal positions alone (no attitude, velocity or acceleration of the
#: point): with only these (and :class:`~bvpnav.error_models.ErrorStates` as the whole error
#: model) a coarse mesh's Gauss-Newton steps may be cheap (:func:`_cheap_eligible`).
POINT_FREE_ITEMS = ("Position",)


def _cheap_eligible(form: Formulation) -> bool:
    """Whether the node-state loop of ``form`` may take cheap steps
    (:func:`bvpnav.error_models.error_states.cheap_at`): node states on a coarse mesh, no
    other error-model parameters, and items of :data:`POINT_FREE_ITEMS` without a lever arm
    or a delay (their rows do not move with the linearization point) whose terms are least
    squares (soft or hard: a band's or a robust penalty's steps are the active set's, which
    a cheap point does not pay off)."""
    from ..error_models.error_states import _mesh

    m = form.model
    if _mesh(form.data) is None or m.q or not hasattr(m.state_model, "condensed_change"):
        return False
    if not all(type(it).__name__ in POINT_FREE_ITEMS and getattr(it, "lever", None) is None
               and getattr(it, "delay", None) is None for it in form.items):
        return False
    return all(t.least_squares_role() is not None for t in form.terms() if t.item is not None)


def _rows_at_nodes(items, model) -> bool:
    """Whether every body-frame item reads the loop's linearization velocity at a coarse mesh's
    nodes only (``rows_at_nodes``, e.g. ``NonHolonomic(rate="nodes")``): the point is then
    :meth:`~bvpnav.mesh.MeshModel.node_point_velocities`, not the samples' recovered velocity."""
    body = [it for it in items if getattr(it, "body_frame", False)]
    return (bool(body) and hasattr(model, "node_point_velocities")
            and all(getattr(it, "rows_at_nodes", False) is True for it in body))


def _quick_next(o: dict, k: int, iters: list, lam) -> bool:
    """Whether step ``k`` of the node-state loop (options ``o``) may be one banded solve: the
    loop goes on, it is not the last allowed step, and either it is the first at a fixed
    ``lam`` (a lambda rule is resolved by the stage) or the next step is expected at least
    ``tol`` (:func:`_expected`)."""
    if not o["loop"] or k + 1 >= int(o["max_iter"]):
        return False
    return _expected(iters) >= o["tol"] if iters else not isinstance(lam, str)


def _may_cheap(o: dict, k: int, iters: list, lam, started: bool = False) -> bool:
    """Whether step ``k`` may be cheap: Gauss-Newton converges linearly (:func:`_slow`) or the
    one step taken was large (:func:`_far`; not when the loop ``started`` off the data), the
    step is an intermediate one (:func:`_quick_next`), and a run of cheap steps has not yet
    converged to within what it leaves out (its next step expected above :data:`CHEAP_GAP`
    times the gyro-bias rotation: a full pass is then due)."""
    if not ((_slow(iters) or (_far(iters) and not started)) and _quick_next(o, k, iters, lam)):
        return False
    last = iters[-1]
    return last["solve"] != "cheap" or _expected(iters) >= _left_out(last)


def _far(iters: list) -> bool:
    """Whether the node-state loop has taken one step and it was at least :data:`CHEAP_FIRST`:
    the next may be cheap before the rate of convergence is known. Only from the data as
    measured: a cheap step rotates its reference pass's samples element by element, which is a
    full pass's point only when the samples' attitude between the nodes is the gyro's from the
    left node (the data's, integrated from its rates; a start off the data, ``start="course"``,
    sets every sample's attitude, and cheap steps from it converge away from the full passes'
    point)."""
    return len(iters) == 1 and iters[0]["step"] >= CHEAP_FIRST


def _left_out(it: dict) -> float:
    """The step (rad) a cheap step ``it`` is expected to leave to the next full pass:
    :data:`CHEAP_GAP` times the gyro-bias rotation ``sqrt(2 cheap_error)``."""
    return CHEAP_GAP * float(np.sqrt(2.0 * it["cheap_error"]))


def _slow(iters: list) -> bool:
    """Whether the node-state loop converges linearly (the last step at least :data:`CHEAP_RATE`
    of the one before), where cheap steps pay; where it converges quadratically (the data fit
    their sigmas) full passes are the faster way."""
    return len(iters) >= 2 and iters[-1]["step"] >= CHEAP_RATE * iters[-2]["step"]


def _banded_next(o: dict, k: int, iters: list, lam) -> bool:
    """Whether a full pass at step ``k`` may be one banded solve: :func:`_quick_next`, or it is the
    first after cheap steps and its step (what they left out, :data:`CHEAP_GAP`) is expected at
    least ``tol``."""
    if (iters and iters[-1]["solve"] == "cheap" and k + 1 < int(o["max_iter"])
            and _left_out(iters[-1]) >= o["tol"]):
        return True
    return _quick_next(o, k, iters, lam)


def _checked_first(form: Formulation, quick: bool, o: dict, lam) -> bool:
    """Check ``form`` (the stage's refusal, :meth:`~bvpnav.formulation.Formulation.check_observability`)
    when the loop's first step will be one banded solve, which checks nothing; whether it did."""
    if quick and _quick_next(o, 0, [], lam):
        form.check_observability()
        return True
    return False


def _quick_step(f: Formulation, lam: float, workspace) -> np.ndarray | None:
    """The unknowns ``x`` of one banded solve of ``f`` at ``lam``, without refinement or
    verification (an intermediate Gauss-Newton step, whose answer only moves the
    linearization point), or None when ``f`` is not banded equality-constrained least
    squares or the solve fails (the stage then solves it). Band and inequality rows: one
    pass of the active set from the last answer's rows
    (:func:`bvpnav.linalg.active_set.quick_step`)."""
    from ..linalg.banded import NotBanded
    from ..linalg.lsq import banded_factor, least_squares_form

    if f.residual != "acceleration":
        return None
    try:   # building the rows may fail too (then the stage, or a full pass for a cheap point)
        ls = least_squares_form(f, lam)
        if ls is None:   # band or inequality rows (imported only then: the module is large)
            from ..linalg.active_set import quick_step

            x = quick_step(f, lam, workspace)
        else:
            x = banded_factor(ls, f, workspace=workspace).solve_x(ls.rhs())
        if x is None:
            return None
    except (NotBanded, RuntimeError, np.linalg.LinAlgError, ValueError):
        return None
    return x if np.all(np.isfinite(x)) else None


def _start_totals(form: Formulation, o: dict) -> tuple[dict, bool]:
    """The node states' totals (kind -> (N, 3)) at the loop's first point, and whether they
    move it off the data: zero, or with ``start="course"`` the attitude error to a car's
    course attitude (:func:`bvpnav.solve.course.course_totals`)."""
    raw = form.data
    totals = {k: np.zeros((raw.n, 3)) for k in form.model.state_model.state_kinds(raw)}
    if o["start"] != "course":
        return totals, False
    from .course import course_totals

    totals["attitude_error"] = course_totals(form)
    return totals, True


def _banded_step(f: Formulation, cheap: bool, banded: bool, lam, workspace, full: Callable) -> tuple:
    """``(f, x, cheap)`` of a node-state step: ``x`` of one banded solve of ``f``
    (:func:`_quick_step`) when the point is ``cheap`` or ``banded``, else None (the stage
    solves it). A cheap point the banded path does not solve is made again as a full pass
    (``full()``, a formulation)."""
    x = _quick_step(f, float(lam), workspace) if cheap or banded else None
    if cheap and x is None:
        f, cheap = full(), False
        x = _quick_step(f, float(lam), workspace) if banded else None
    return f, x, cheap


def _cheap_point(ref, nodes: dict | None, may_cheap: bool) -> tuple | None:
    """``(data, err)`` of the node-state loop's next point when it is cheap
    (:func:`~bvpnav.error_models.error_states.cheap_at` from the last full pass's data ``ref``,
    no pass over the samples; ``err`` the size of what it leaves out): when ``may_cheap`` and
    that is at most :data:`CHEAP_ERROR`; else None (the next point is a full pass,
    :func:`_full_point`)."""
    from ..error_models.error_states import cheap_at, cheap_error

    if may_cheap and ref is not None and nodes is not None:
        err = cheap_error(ref, nodes)
        if err <= CHEAP_ERROR:
            return cheap_at(ref, nodes), err
    return None


def _full_point(form: Formulation, iters: list, nodes: dict | None, totals: dict | None,
                started: bool, workspace) -> tuple:
    """The data of a full pass of the node-state loop and the totals at every sample (made
    from ``nodes``, the node totals, when given; else ``totals``): the data as measured at an
    unmoved start. The loop's ``workspace`` (when it has one) first forgets the last step's
    model (:meth:`~bvpnav.linalg.workspace.Workspace.drop_model`: it holds that step's data)."""
    from ..error_models.error_states import states_at

    if workspace is not None:
        workspace.drop_model()
    raw = form.data
    if nodes is not None:
        totals = form.model.state_model.expand(raw, nodes)
    return (raw if not (iters or started) else states_at(raw, totals)), totals


def _body_velocity(form: Formulation, iters: list, f: Formulation | None, x) -> np.ndarray | None:
    """With body-frame items, after a first step: the velocity (N, 3), m/s, of the last step's
    answer ``x`` of ``f`` at every sample (at the nodes, linear between them, when the items'
    rows are at the nodes), their attitude term's linearization point; else None."""
    if not (iters and any(getattr(it, "body_frame", False) for it in form.items)):
        return None
    m = f.model
    return m.node_point_velocities(x) if _rows_at_nodes(form.items, m) else m.point_velocities(x)


def _set_body_point(data, vel: np.ndarray | None) -> None:
    """The body-frame items' linearization point ``vel`` (:func:`_body_velocity`) on the
    next point's ``data``, when there is one."""
    if vel is not None:
        data.body_point = LinearizationPoint(velocity=vel, names=(), psi=np.zeros((data.n, 3, 0)))


def _step_form(form: Formulation, data, checked: bool, item_terms: list | None) -> Formulation:
    """The formulation of a node-state step: ``form`` at the point ``data``, checked when
    ``checked``; ``item_terms`` (the items' terms of ``form``, or None) stand for its items' when
    its model has ``form``'s layout."""
    out = Formulation(data, form.residual, form.sigma_a if form.sigma_a_given else None,
                      form.error_model, form.items, grade=None, segment=form.segment)
    out.grade_report = form.grade_report
    out._observable = checked
    if item_terms is not None and out.model.size == form.model.size:
        out._terms = [*item_terms, *out.error_model.terms(out.model)]
    return out


def _state_loop(form: Formulation, inner: Stage, lam, opts, comps: list) -> Solution:
    r"""Gauss-Newton on the node states of :class:`~bvpnav.error_models.ErrorStates`.

    At the current totals (attitude errors, biases per node) the data is re-linearized
    (``bvpnav.error_models.error_states.states_at``: the attitude rotated, the
    accelerometer bias removed, the process rows' residuals evaluated there), the convex
    problem gives the increments, and the totals take them. Each step is one banded
    factorization (the states are in the band; the band plan is made once and reused). The
    loop stops when the step's largest attitude change :math:`\max_j \|\varepsilon_j\|` is
    below ``tol`` rad (the gyro-bias steps act on the attitude only through the process rows,
    so they are in it; the accelerometer bias is linear given the attitude); the answer is
    that step's solve (its increments below ``tol``). ``stats["sequential"]`` holds the
    report (``kind="states"``).

    With ``direct`` as the first back end (and ``quick``, the default), the steps before
    the one expected to converge (the ratio of the last two steps carried on below ``tol``)
    are one banded solve each (:func:`bvpnav.linalg.lsq.banded_factor`, no refinement, no
    verification): they only move the linearization point, which the next step
    re-linearizes about (``iterations[k]["solve"]``: ``"banded"``; ``"stage"`` otherwise).
    The problem is checked (:meth:`~bvpnav.formulation.Formulation.check_observability`,
    the stage's refusal) before the first step; a first step that resolves a lambda rule,
    and the answer, go through the stage (refined and verified); a quick step whose change
    is below ``tol`` is solved again by the stage, and so is a form the banded path does
    not take. Gauss-Newton converges linearly where the data misfit their sigmas: once the
    steps are below :data:`ANDERSON_START` and shrinking, each new point mixes the last steps
    (Anderson acceleration, :func:`_anderson`, ``iterations[k]["accelerated"]``); the loop still stops
    at a Gauss-Newton step below ``tol``, and that step's totals are not mixed.

    With items the sequential stage linearizes (a fix's estimated delay or lever arm's
    turning rows, :func:`bvpnav.solve.sequential.with_sequential`), the same steps linearize
    them once from the last answer (``iterations[k]["solve"]``: ``"linearized once"``): one
    Gauss-Newton step on the states and the items' unknowns together, rather than the items
    iterated to their ``tol`` about an attitude the next step moves (their loop converges
    linearly where the attitude is far off); a step below ``tol`` made so is solved again by
    the stage, the items iterated to their ``tol``, and is the answer only if its attitude
    step is still below ``tol``.

    On a coarse mesh (``segment=``, items of :data:`POINT_FREE_ITEMS`, :func:`_cheap_eligible`)
    an intermediate step where Gauss-Newton converges linearly (:data:`CHEAP_RATE`), or the second
    after a first step of at least :data:`CHEAP_FIRST`, is *cheap*
    (``iterations[k]["solve"]``: ``"cheap"``) while what it
    leaves out is small (:data:`CHEAP_ERROR`,
    :func:`bvpnav.error_models.error_states.cheap_error`: the second-order term of the
    gyro-bias change since the last full pass): it is made from the last full pass's
    per-element sums and their derivatives (:func:`bvpnav.error_models.error_states.cheap_at`,
    exact in the nodes' attitude and the accelerometer bias), with no pass over the samples,
    as a factor graph's preintegration is corrected to first order in the bias. The first step
    after cheap ones is a full pass (one banded solve: its step is what they left out), and so
    is the answer's, so the answer is the exact fixed point. ``stats["sequential"]`` counts
    ``full_passes`` and ``cheap_steps``.
    """
    from ..error_models.error_states import attitude_at, states_at

    if comps:
        names = ", ".join(type(c).__name__ for c in comps)
        raise InputError(f"ErrorStates with attitude parameters ({names}): "
                         "the node states already carry the initial attitude (attitude_sigma=) and the gyro "
                         "bias (gyro_drift=; 0 for a constant bias); leave those models out")
    o = check_attitude(getattr(opts, "attitude", None))
    raw = form.data
    if getattr(raw, "state_point", None) is not None:
        raise InputError("node states: this data already carries a linearization point; give the data as "
                         "measured")
    sm = form.model.state_model
    t0 = time.perf_counter()
    totals, started = _start_totals(form, o)
    nodes = None   # the next point's totals at the nodes (None: ``totals`` is it)
    ref = None     # the last full pass's data: the reference of the cheap steps
    iters: list[dict] = []
    reason = None
    lam_now, rule, curve = lam, (lam if isinstance(lam, str) else None), None
    sol = data = f = x = prev_att = None
    history: list = []   # (totals before, after) of the last steps, for _next_totals
    # every step's formulation has the same sparsity pattern: one workspace keeps the band
    # plan (reused when the pattern matches, bvpnav.linalg.lsq.banded_plan)
    from ..linalg.workspace import Workspace

    workspace = Workspace() if not form.nonlinear_items else None
    if workspace is not None:   # each step's factor is dead before the next: one band's memory
        workspace.band_buffer = np.empty(0)
    quick = bool(o["quick"]) and workspace is not None and _direct_first(opts)
    # items the sequential stage linearizes (a fix's estimated delay): an intermediate step
    # linearizes them once (Gauss-Newton on the states and their unknowns together) instead of
    # iterating them to convergence about a linearization point that the next step moves
    joint = bool(o["quick"]) and bool(form.nonlinear_items)
    cheap_ok = quick and bool(o["cheap"]) and _cheap_eligible(form)
    checked = _checked_first(form, quick, o, lam_now)

    # the items' terms of every step are the first form's when their rows do not read the point
    # (the items a cheap loop admits, on the same mesh): compiled once
    item_terms = form.terms()[:len(form.items)] if cheap_ok else None

    def step_form(data) -> Formulation:
        return _step_form(form, data, checked, item_terms)

    kw = {} if workspace is None else {"workspace": workspace}   # the stage's solves share it

    with progress(desc="state loop", unit="iter", enabled=o["progress"]) as bar:
        for k in range(int(o["max_iter"])):
            vel = _body_velocity(form, iters, f, x)
            point = _cheap_point(ref, nodes, cheap_ok and _may_cheap(o, k, iters, lam_now, started))
            cheap = point is not None
            if cheap:
                data, err = point
            else:
                # a full pass: the last point (its data, formulation and answer, the cheap steps'
                # reference, the samples' totals a new one replaces) is read no more, and its
                # memory is free before the new point's is taken
                point = ref = data = f = x = err = used = s = None
                totals = totals if nodes is None else None
                data, totals = _full_point(form, iters, nodes, totals, started, workspace)
            _set_body_point(data, vel)
            f = step_form(data) if iters or started else form
            # an intermediate step only moves the linearization point: one banded solve, no
            # refinement or verification; the step expected to be the last (and the first
            # when it resolves a lambda rule) goes through the stage
            f, x, cheap = _banded_step(f, cheap, quick and _banded_next(o, k, iters, lam_now),
                                       lam_now, workspace,
                                       lambda at=nodes: step_form(states_at(raw, sm.expand(raw, at))))
            staged, once = x is None, False
            if staged:
                once = joint and _quick_next(o, k, iters, lam_now)
                sol = inner(f, lam_now, opts, **kw, **({"steps": 1} if once else {}))
                x = sol.x
                checked = True
                if rule is not None and not isinstance(lam_now, float):
                    curve, lam_now = sol.curve, float(sol.lam)
            s = f.model.split(x)["s"]
            step = float(np.max(np.linalg.norm(s[sm.state_index(raw, "attitude_error")], axis=1)))
            if (once or (not staged and not cheap)) and step < o["tol"]:
                # a quick step (or one linearization) that converged: the answer is this step's solve
                # by the stage (the linearized items iterated to their tol)
                sol = inner(f, lam_now, opts, **kw)
                x, staged, once = sol.x, True, False
                s = f.model.split(x)["s"]
                step = float(np.max(np.linalg.norm(s[sm.state_index(raw, "attitude_error")], axis=1)))
            # the objective of the formulation the step solved (items the sequential stage linearizes,
            # e.g. a fix's estimated delay, at their linearization)
            used = sol.formulation if staged and sol.formulation is not None else f
            j = objective_value(used, x, float(sol.lam if staged else lam_now))
            iters.append({"objective": j, "trial": j, "step": step, "accepted": True, "damping": 0.0,
                          "solve": ("linearized once" if once else "stage") if staged
                          else ("cheap" if cheap else "banded"),
                          **({"cheap_error": err} if cheap else {})})
            if cheap_ok and not cheap:
                ref = f.data
            nodes, prev_att = _next_totals(sm, f.data, s, iters, prev_att, o, history)
            log.info("state iteration %d: objective %.9g, step %.3g rad (%s)", len(iters), j, step,
                     iters[-1]["solve"])
            bar.update(1)
            if not o["loop"]:   # one linearized solve about the data as given
                reason = "loop off"
                break
            if step < o["tol"] and not cheap:   # a cheap step's point is checked by a full pass
                reason = "step"
                iters[-1]["converged"] = True
                break
    # the loop's band memory and plan, the last point's data and formulation (the answer keeps
    # its own), are not read again: freed before the samples' totals and attitude are made
    workspace = kw = ref = data = f = x = used = s = None
    totals = sm.expand(raw, nodes)
    if reason is None:
        _warn(sol, f"node-state loop did not converge in {o['max_iter']} iterations: the last step changed "
                   f"the attitude by {iters[-1]['step']:.3g} rad > tol={o['tol']:g} rad. Raise max_iter "
                   f"(solve(..., attitude={{'max_iter': {2 * int(o['max_iter'])}}})) or give priors on the "
                   "first node (ErrorStates(attitude_sigma=..., gyro_sigma=..., acc_sigma=...))")
    sol.error_states = sm.frame(raw, totals)
    sol.attitude = attitude_at(raw, totals)
    sm.release(raw)
    sol.attitude_data = raw.attitude
    sol.records.attitude = AttitudeLoopReport(
        kind="states", iterations=iters, converged=reason is not None, reason=reason or "max_iter",
        tol=float(o["tol"]), max_iter=int(o["max_iter"]), objective_initial=iters[0]["objective"],
        objective=iters[-1]["objective"], heading_search=[], solves=len(iters),
        seconds=time.perf_counter() - t0, inner=sol.records.sequential,
        full_passes=sum(it["solve"] != "cheap" for it in iters),
        cheap_steps=sum(it["solve"] == "cheap" for it in iters))
    sol.record()
    if rule is not None:
        sol.lam_rule = f"{rule} (first evaluation)"
        sol.curve = curve
    return sol


def with_attitude(inner: Stage) -> Stage:
    """The stage that solves formulations with attitude error models by the damped outer
    loop (see the module docstring); others pass straight to ``inner``.

    The stage reads ``opts.attitude`` (:data:`ATTITUDE_DEFAULTS`):

    tol : float
        Stop when the largest attitude change an undamped step makes over the window is
        below this, rad (default 1e-7 rad).
    ftol : float
        Also stop when an accepted step lowers the objective by less than this fraction
        of it (default 1e-12; such a step changes nothing the data can see).
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
    quick : bool
        Node states (:class:`~bvpnav.error_models.ErrorStates`) with ``direct``: the
        intermediate Gauss-Newton steps are one banded solve each, without refinement or
        verification (default True); False: every step through the stage.
    cheap : bool
        Node states on a coarse mesh with ``quick``: intermediate steps made from the last
        full pass's per-element sums while the gyro bias stays near its value there (default
        True; :func:`_state_loop`); False: every step from the samples.
    start : {"data", "course"}
        Node states: the first linearization point. ``"data"`` (default): the data's
        attitude; ``"course"``: a car's attitude from the ``Position`` items (the heading of
        the fix-interpolated velocity, held below
        :data:`~bvpnav.solve.course.COURSE_MIN_SPEED`; the roll and pitch of the data's
        first sample), as initial attitude-error totals (:mod:`bvpnav.solve.course`); the
        process rows keep the raw gyro rates.

    The answer is the last linearized solve at the accepted totals (its increments are
    below ``tol``), so ``error_params`` holds the totals and ``solve(uncertainty=...)``
    their standard deviations. ``stats["sequential"]`` holds the loop's report
    (:class:`~bvpnav.result.AttitudeLoopReport`): per iteration the objective before and
    after, the step (rad), whether it was accepted, the damping.
    """

    def stage(form: Formulation, lam, opts) -> Solution:
        comps = attitude_components(form.error_model)
        if form.model.ns:
            from ..error_models.error_states import kept_rows

            with kept_rows(form.data):   # the steps' shared row patterns, for the loop's lifetime
                return _state_loop(form, inner, lam, opts, comps)
        if check_attitude(getattr(opts, "attitude", None))["start"] == "course":
            from .course import course_totals

            course_totals(form)   # refuses: no node states to start
        if not comps:
            return inner(form, lam, opts)
        o = check_attitude(getattr(opts, "attitude", None))
        if at_point(form.data).values:
            raise InputError("attitude loop: this data already carries a linearization point; give the "
                             "data as measured")
        t0 = time.perf_counter()
        form, held, held_why = hold_yaw_rate(form)
        loop = _Loop(form, inner, opts, lam, o)
        values = {n: 0.0 for n in loop.names}
        if not o["loop"]:
            sol = inner(form, lam, opts)
            sol.attitude = reintegrate(form.data, form.error_model, {
                n: float(sol.error_params[n]) for n in loop.names}).attitude
            return sol
        values, search, best, heading = loop.heading_start(values)
        body = any(getattr(it, "body_frame", False) for it in form.items)
        j, at_values = best if best is not None and not body else loop.evaluate(values)
        j0 = j
        start = dict(values)
        values, j, at_values, sol, iters, reason = _iterate(loop, values, j, at_values, o)
        converged = reason is not None
        if reason != "step":  # the accepted point itself, not an increment never tested
            sol = _at_point(loop, values, at_values)
        if not converged:
            msg = (f"attitude loop did not converge in {o['max_iter']} iterations: the last step changed the "
                   f"attitude by {iters[-1]['step']:.3g} rad > tol={o['tol']:g} rad; the answer is the "
                   f"last accepted point. Raise max_iter (solve(..., attitude={{'max_iter': "
                   f"{2 * int(o['max_iter'])}}})), loosen tol, give better priors (sigma= on GyroBias/"
                   "AttitudeError, e.g. from bvpnav.sensors.grade), or a better initial attitude "
                   "(bvpnav.align)")
            _warn(sol, msg)
        if heading == "unobservable":
            _warn(sol, _heading_warning(search, len(search) < int(o["candidates"])))
        if held:
            _warn(sol, held_why)
        parts = {"initial": loop.parts_at(start), "answer": loop.parts_at(values)}
        for msg in parts_warnings(parts, len(loop.names)):
            _warn(sol, msg)
        totals = {n: float(sol.error_params[n]) for n in loop.names}
        sol.attitude = reintegrate(form.data, form.error_model, totals).attitude
        for msg in stance_turn_warnings(form, sol):
            _warn(sol, msg)
        report = AttitudeLoopReport(
            kind="attitude", iterations=iters, converged=converged, reason=reason or "max_iter",
            tol=float(o["tol"]),
            max_iter=int(o["max_iter"]), objective_initial=j0, objective=j, heading_search=search,
            solves=loop.solves, seconds=time.perf_counter() - t0, inner=sol.records.sequential,
            heading=heading, held=held or None,
            objective_parts=parts)
        sol.records.attitude = report
        sol.record()
        if loop.rule is not None:
            sol.lam_rule = f"{loop.rule} (first evaluation)"
            sol.curve = loop.curve
        return sol

    return stage
