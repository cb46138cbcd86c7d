"""The sequential convex loop for items that must be linearized (e.g. a known track).

An item that is nonlinear in the positions (``TrackLine``: the distance to a polyline)
declares the :class:`~bvpnav.items.Linearizable` contract: ``needs_linearization`` (True
while it has no linearization point) and ``linearized(t, trajectory) -> Item`` (a copy
linearized about a trajectory estimate). The pipeline's sequential stage
(:func:`with_sequential`) handles formulations with such items; it

1. solves a first phase without those items (every other item kept, or the stand-in an
   item offers with ``first_phase()``: a delayed fix at its stamp) for the initial
   estimate, unless ``initial`` is given; called again within one solve on the same items
   (by the attitude loop or the gating passes around it) it starts from its previous
   answer instead;
2. repeatedly linearizes every such item about the current estimate, solves the
   resulting convex problem, and stops when the largest position change between two
   iterations is below ``tol`` (m) or after ``max_iter`` solves;
3. with a continuation for hard and band items: they are first iterated in soft mode,
   with a sigma that follows the estimate's distance to the path (down to a floor),
   until the change is below a looser ``soft_tol``, and only then in the requested mode.

Why the continuation. Measured on the noise-free test track of
``tests/solve/test_sequential.py`` from a start 2 m off: a hard track without it stalls at
about 1.1 m RMS error (changes of 0.007-0.08 m per iteration, still 0.59 m after 80
iterations), with about 50 samples at the resting end dropped as beyond the path. The
dropped samples are a symptom, not the cause: with ``beyond_ends="clamp"`` nothing is
dropped and it stalls just the same. Nor is it another fixed point: the error keeps
shrinking, only very slowly. The first hard step puts the whole estimate on the path at
the *arc lengths of the start* (within 0.13 m of the path but 1.9 m ahead along it at
t = 14 s, running past the end and back to the end fix); a mistimed trajectory on the
path has a large data misfit and so large multipliers on the hard rows, and the
Gauss-Newton (SQP) step leaves out their product with the path's curvature, which is not
small next to the data term's weak stiffness along the path: linear convergence with a
rate near one. A soft row lets the data term fix the timing first (the estimate may
leave the path by about sigma); at the truth the multipliers vanish, so the hard phase
then converges in one or two steps (measured: 3 soft + 1 hard iteration, 7e-12 m).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np
import pandas as pd

from ..declare import check_option
from ..errors import InputError
from ..formulation import Formulation
from ..items import Linearizable
from ..log import progress, warn
from ..result import SequentialReport, Solution
from .options import SEQUENTIAL_DEFAULTS, SolveOptions

__all__ = ["with_sequential", "check_sequential", "SEQUENTIAL_DEFAULTS"]

Stage = Callable[..., Solution]

log = logging.getLogger(__name__)



def check_sequential(options: dict | None) -> dict:
    """The loop's options with defaults (``soft_tol`` resolved: ``max(tol, 0.01)`` m when not
    given), or :class:`InputError` naming a wrong one (the declared table
    :data:`bvpnav.declare.SEQUENTIAL`)."""
    o = {**SEQUENTIAL_DEFAULTS, **(check_option("sequential", options) or {})}
    o["soft_tol"] = max(float(o["tol"]), 0.01) if o["soft_tol"] is None else float(o["soft_tol"])
    return o


def _initial_trajectory(form: Formulation, initial, nonlin, inner: Stage, lam, opts
                        ) -> tuple[pd.DataFrame, str, Solution | None]:
    t = form.model.grid.t
    axes = list(form.model.axes)
    if initial is None:
        skip = {id(it) for it in nonlin}
        # an item may offer a stand-in for this phase (a delayed fix: the fix at its stamp)
        rest = [it if id(it) not in skip else it.first_phase() for it in form.items]
        rest = [it for it in rest if it is not None]
        sub = form.with_items(rest)
        missing = sub.unobservable()
        note = ""
        if missing and form.error_model is not None:
            # the error-model parameters may need the nonlinear items: start with them at zero
            sub = form.with_items(rest, error_model=False)
            missing = sub.unobservable()
            note = " (without the error model, which needs them)"
        if missing:
            raise InputError(
                f"sequential loop: the first phase (every item except {[i.label for i in nonlin]}) "
                f"leaves {'; '.join(missing)} undetermined, so there is no initial estimate. Add "
                "items that fix them (e.g. Position at both ends) or pass initial=<Solution or "
                "positions (N, d) in m> to bvpnav.solve.solve_sequential")
        if isinstance(lam, str) and not sub.has_soft_terms:
            lam = 1.0
        sol0 = inner(sub, lam, opts)
        return sol0.trajectory[axes], "first phase: every item except the ones to linearize" + note, sol0
    if isinstance(initial, Solution):
        return initial.trajectory[axes], "given Solution", initial
    if isinstance(initial, pd.DataFrame):
        return initial[axes], "given DataFrame", None
    p = np.asarray(initial, dtype=float)
    if p.shape != (t.size, len(axes)) or not np.all(np.isfinite(p)):
        raise InputError(f"initial: expected finite positions of shape ({t.size}, {len(axes)}) in m "
                         f"(one row per sample, columns {axes}), got shape {p.shape}")
    return pd.DataFrame(p, index=pd.Index(t, name="t"), columns=axes), "given array", None


def _continued(lin, lam_soft: float):
    """Soft copy of a linearized hard/band item for the continuation phase; (item, sigma in
    m), or (the item itself, None) when it declines a continuation this time."""
    sigma = lin.continuation_sigma()
    if sigma is None:
        return lin, None
    sigma = float(sigma)
    return lin.with_mode("soft", sigma=sigma * np.sqrt(lam_soft)), sigma


class _Loop:
    """State of one run of the loop (iterations, phases and what they measured)."""

    def __init__(self, form: Formulation, nonlin, o: dict, lam):
        self.form, self.o = form, o
        self.nonlin = {id(it) for it in nonlin}
        self.rule = lam if isinstance(lam, str) else None
        self.lam_now = lam
        self.lam_soft = float(lam) if self.rule is None and float(lam) > 0 else 1.0
        # a hard or band item that takes a continuation starts soft
        self.cont = {it.label for it in nonlin if o["continuation"] and it.is_constraint
                     and type(it).continuation_sigma is not Linearizable.continuation_sigma}
        self.max_change, self.rms_change, self.lams, self.modes, self.sigmas = [], [], [], [], []
        self.phases, self.counts, self.curve = [], {}, None
        self.soft = bool(self.cont)
        self.current: dict = {}   # the latest linearization of each item, by label
        #: whether the linearized formulations were checked for observability: they have the same
        #: items and error model, only the linearization point moves (a check is an SVD, about as
        #: long as a solve) -- unless an item keeps other rows at the new point (TrackLine drops
        #: the samples that do not project onto the track): the rows each item kept at the checked
        #: linearization (``linearization_counts``), so that a change is checked again
        self.observable = bool(form._observable)
        self.kept: dict = {}
        self.checked_kept: dict | None = {} if self.observable else None

    def linearized_form(self, t, traj, sol: Solution | None = None):
        items, sig, kept = [], {}, {}
        for it in self.form.items:
            if id(it) not in self.nonlin:
                items.append(it)
                continue
            lin = it.linearized_from(sol, t, traj)
            self.current[it.label] = lin
            counts = lin.linearization_counts() if isinstance(lin, Linearizable) else None
            if counts is not None:
                self.counts[it.label] = counts
                kept[it.label] = dict(counts)
            if self.soft and it.label in self.cont:
                lin, s = _continued(lin, self.lam_soft)
                if s is not None:
                    sig[it.label] = s
            items.append(lin)
        self.sigmas.append(sig)
        self.kept = kept
        if kept != self.checked_kept:   # other rows than at the checked point: check again
            self.observable = False
        out = self.form.with_items(items)
        out._observable = self.observable
        return out

    def checked(self, sub: Formulation) -> None:
        """Note that ``sub`` (the latest linearized formulation) passed the observability check."""
        if sub._observable and not self.observable:
            self.observable, self.checked_kept = True, self.kept

    def note(self, sol: Solution, prev: np.ndarray) -> np.ndarray:
        if not self.soft:
            if self.rule is not None and self.curve is None:
                self.curve = sol.curve
            if self.rule is not None and not self.o["lam_each"]:
                self.lam_now = float(sol.lam)
        self.lams.append(float(sol.lam))
        self.modes.append("soft" if self.soft else "final")
        pos = sol.position().reshape(prev.shape)
        diff = pos - prev
        self.max_change.append(float(np.max(np.abs(diff))))
        self.rms_change.append(float(np.sqrt(np.mean(diff**2))))
        return pos

    def report(self, converged: bool, origin: str, seconds: float) -> SequentialReport:
        o = self.o
        return SequentialReport(
            iterations=len(self.max_change), max_change=self.max_change, rms_change=self.rms_change,
            mode=self.modes, sigma=self.sigmas, phases=self.phases, continued=sorted(self.cont),
            converged=converged, tol=float(o["tol"]), soft_tol=o["soft_tol"], max_iter=int(o["max_iter"]),
            initial=origin, lam=self.lams, status=self.counts, seconds=seconds)


def _not_converged(loop: _Loop) -> str:
    final = [m for m in loop.modes if m == "final"]
    mc = loop.max_change
    return (f"sequential loop did not converge: after {len(final)} iteration(s) of the final phase "
            + (f"(and {len(mc) - len(final)} soft continuation iteration(s)) " if loop.cont else "")
            + f"the largest position change is {mc[-1]:.3g} m > tol={loop.o['tol']:g} m (changes: "
            + ", ".join(f"{c:.3g}" for c in mc)
            + f"). Raise max_iter (solve(..., sequential={{'max_iter': {2 * int(loop.o['max_iter'])}}}) or "
            "bvpnav.solve.solve_sequential(..., max_iter=...)), give a better initial estimate (initial=), "
            "or loosen tol (tol=, in m)")


def _settled(before: dict, now: dict, tol: float) -> bool:
    """Whether every item measures its linearization's move (``linearization_change``) and
    each moved by less than ``tol`` (item units)."""
    if set(before) != set(now):
        return False
    for label, lin in now.items():
        change = lin.linearization_change(before[label]) if isinstance(lin, Linearizable) else None
        if change is None or not change < tol:
            return False
    return True


def _iterate(loop: _Loop, inner: Stage, opts: SolveOptions, traj: pd.DataFrame,
             sol: Solution | None = None, capped: bool = False) -> tuple[Solution, bool]:
    """Linearize and solve until the final phase converges or runs out of iterations
    (``capped``: an outer loop's intermediate step, which ends with the phase it is in: a
    continuation's soft phase is not cut short by the requested modes)."""
    axes = list(loop.form.model.axes)
    prev = traj[axes].to_numpy()
    n_phase = 0
    with progress(desc="sequential loop", unit="iter", enabled=loop.o["progress"]) as bar:
        before: dict | None = None
        while True:
            # the trajectory's own times: on a mesh the answer is at every sample, not at the nodes
            sub = loop.linearized_form(traj.index.to_numpy(dtype=float), traj, sol)
            if before is not None and not loop.soft and _settled(before, loop.current, loop.o["tol"]):
                # every item's linearization moved by less than tol: the last solve answers it
                loop.phases.append({"mode": "final", "iterations": n_phase, "tol": loop.o["tol"],
                                    "converged": True, "by": "linearization change"})
                return sol, True
            before = dict(loop.current) if n_phase or not loop.soft else None
            sol = inner(sub, loop.lam_soft if loop.soft else loop.lam_now, opts)
            loop.checked(sub)
            prev = loop.note(sol, prev)
            traj = sol.trajectory[axes]
            n_phase += 1
            limit = loop.o["soft_tol"] if loop.soft else loop.o["tol"]
            done = loop.max_change[-1] < limit
            mode = "soft" if loop.soft else "final"
            log.info("sequential iteration %d (%s phase, %d): max change %.3g m (rms %.3g m, tol %g m), "
                     "lam=%g",
                     len(loop.max_change), mode, n_phase, loop.max_change[-1], loop.rms_change[-1], limit,
                     loop.lams[-1])
            bar.update(1)
            bar.set_postfix_str(f"{mode}, max change {loop.max_change[-1]:.2g} m", refresh=False)
            if done or n_phase >= int(loop.o["max_iter"]):
                loop.phases.append({"mode": mode, "iterations": n_phase, "tol": limit,
                                    "converged": bool(done)})
                if not loop.soft or capped:
                    return sol, bool(done) and not loop.soft
                log.info("sequential loop: soft continuation ended after %d iteration(s) (%s); now %s",
                         n_phase, "converged" if done else "max_iter reached", "the requested modes")
                # the requested modes make other terms: checked again
                loop.soft, n_phase, loop.observable = False, 0, False


def with_sequential(inner: Stage) -> Stage:
    r"""The stage that solves formulations with :class:`~bvpnav.items.Linearizable` items by
    sequential convex solves of ``inner`` (see the module docstring).

    The stage reads ``opts.sequential`` (:data:`SEQUENTIAL_DEFAULTS`):

    tol : float
        Convergence tolerance in m on the largest change of any nodal position between
        two successive iterations (default 1e-4 m).
    max_iter : int
        Maximum number of linearize-and-solve iterations per phase (default 30).
    initial : Solution, DataFrame or array_like (N, d), optional
        Initial trajectory estimate (positions in m at the samples, all axes). Default:
        solve the problem without the items that need linearization.
    lam_each : bool
        Re-evaluate a lambda rule at every iteration (default False: a rule is evaluated
        on the first linearization of the final phase and the chosen value kept).
    continuation : bool
        Start hard and band items that support it in soft mode (default True).
    soft_tol : float, optional
        Tolerance in m on the largest position change that ends the soft phase; default
        ``max(tol, 0.01 m)``.
    progress : bool, optional
        A tqdm bar of the iterations: True always, False never, None (default) when stderr
        is a terminal.

    The returned solution is the last iteration's, with ``records.sequential`` (a
    :class:`~bvpnav.result.SequentialReport`, also ``stats["sequential"]``); when the loop
    did not converge, a :class:`bvpnav.log.BvpnavWarning` is issued (once, at the caller's
    line) and added to ``solution.warnings``. Each iteration is logged at INFO on
    ``bvpnav.solve.sequential`` (largest and RMS position change, phase, lambda), and a
    progress bar counts the iterations when stderr is a terminal (``rule={"progress":
    False}`` turns it off).

    An outer loop that re-linearizes after every call (the node-state loop,
    :func:`bvpnav.solve.attitude.with_attitude`) may pass ``steps`` (int) to the stage: at most
    that many linearizations from the previous answer, without the warning (its intermediate
    steps are Gauss-Newton steps on the states and the linearized items' unknowns together; the
    step it expects to be its last calls the stage without ``steps``, iterated to ``tol``).

    Notes
    -----
    Iteration :math:`k` solves the convex problem with every nonlinear item
    :math:`g(r) = 0` replaced by its linearization about the previous estimate
    :math:`r^{(k-1)}`, and stops when :math:`\max_{j,a} |r^{(k)}_{a,j} - r^{(k-1)}_{a,j}|
    < \mathrm{tol}`. For a soft track this is a Gauss-Newton step on
    :math:`\|w\|^2 + \lambda \sum_k (d_k/\sigma)^2`, a zero-residual problem for
    noise-free data, so the change shrinks quadratically once the estimate is near the
    path.

    Continuation. A hard (or band) track is first iterated in soft mode with

    .. math:: \sigma^{(k)} = \max\big(d_\mathrm{rms}(r^{(k-1)}),\ \sigma_\min\big),
              \qquad \lambda\,(d/\sigma_\mathrm{eff})^2 = (d/\sigma^{(k)})^2,

    where :math:`d_\mathrm{rms}` is the RMS distance (m) of the current estimate to the
    path and :math:`\sigma_\min` the item's floor (``TrackLine``: the band half-width,
    or 1e-3 of the path length for a hard track): the track is only as stiff as the
    estimate is near it, so the data term can correct the timing along the path, and it
    stiffens as the estimate approaches. The copy's sigma is scaled by
    :math:`\sqrt{\lambda}` so that its weight does not depend on ``lam`` (a rule name
    or ``lam = 0`` uses :math:`\lambda = 1` in this phase). When the change falls below
    ``soft_tol`` the requested mode is switched on and iterated to ``tol``.
    """

    last: dict = {}   # the previous answer per set of items (the outer loops call this stage often)

    def stage(form: Formulation, lam, opts: SolveOptions, workspace=None, steps: int | None = None
              ) -> Solution:
        nonlin = form.nonlinear_items
        if not nonlin:   # a caller's workspace (a loop of same-pattern formulations) goes on down
            kw = {} if workspace is None else {"workspace": workspace}
            return inner(form, lam, opts, **kw)
        o = check_sequential(opts.sequential)
        if steps is not None:   # an outer loop's intermediate step: it re-linearizes anyway
            o = {**o, "max_iter": int(steps)}
        t_start = time.perf_counter()
        key = (form.model.N, tuple(it.label for it in nonlin))
        if o["initial"] is None and key in last:
            # called again by an outer loop (attitude steps, gating passes) on the same items:
            # start from the previous answer instead of a first phase
            sol0 = last[key]
            traj, origin = sol0.trajectory[list(form.model.axes)], "the previous answer of this stage"
        else:
            traj, origin, sol0 = _initial_trajectory(form, o["initial"], nonlin, inner, lam, opts)
        loop = _Loop(form, nonlin, o, lam)
        log.info("sequential loop over %s: initial estimate from %s; continuation for %s",
                 [it.label for it in nonlin], origin, sorted(loop.cont) or "none")
        sol, converged = _iterate(loop, inner, opts, traj, sol0, capped=steps is not None)
        seconds = time.perf_counter() - t_start
        sol.record(sequential=loop.report(converged, origin, seconds))
        last[key] = sol
        log.info("sequential loop %s after %d iteration(s), %.3g s", "converged" if converged else
                 "did not converge", len(loop.max_change), seconds)
        if loop.rule is not None:
            sol.lam_rule = loop.rule if o["lam_each"] else f"{loop.rule} (first linearization)"
            sol.curve = loop.curve
        if not converged and steps is None:
            msg = _not_converged(loop)
            sol.warnings.append(msg)
            warn(msg)
        return sol

    return stage
