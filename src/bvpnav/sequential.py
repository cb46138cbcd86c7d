"""The sequential convex loop for items that must be linearized (e.g. a known track).

An item that is nonlinear in the positions (``TrackLine``: the distance to a polyline)
exposes ``needs_linearization`` (True while it has no linearization point) and
``linearized(t, trajectory) -> Item`` (a copy linearized about a trajectory estimate).
:meth:`bvpnav.NavigationProblem.solve` hands problems with such items to
:func:`solve_sequential`, which

1. solves a first phase without those items (every other item kept) for the initial
   estimate, unless ``initial`` is given;
2. repeatedly linearizes every such item about the current estimate, solves the
   resulting convex problem, and stops when the largest position change between two
   iterations is below ``tol`` (m) or after ``max_iter`` solves;
3. with a continuation for hard and band items: they are first iterated in soft mode,
   with a sigma that follows the estimate's distance to the path (down to a floor),
   until the change is below a looser ``soft_tol``, and only then in the requested mode.

Why the continuation. Measured on the noise-free test track of
``tests/test_track_line.py`` from a start 2 m off: a hard track without it stalls at
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

import time
import warnings
from typing import Any

import numpy as np
import pandas as pd

from .errors import InputError
from .result import Solution

__all__ = ["solve_sequential", "needs_linearization"]


def needs_linearization(item) -> bool:
    """True for an item that must be linearized before it can compile."""
    return bool(getattr(item, "needs_linearization", False))


def _initial_trajectory(problem, initial, nonlin, solve_kw) -> tuple[pd.DataFrame, str, Solution | None]:
    t = problem.model.grid.t
    axes = list(problem.model.axes)
    if initial is None:
        rest = [it for it in problem._items if not needs_linearization(it)]
        sub = problem.with_items(rest)
        missing = sub.unobservable()
        note = ""
        if missing and problem.error_model is not None:
            # the error-model parameters may need the nonlinear items: start with them at zero
            sub = problem.with_items(rest, error_model=False)
            missing = sub.unobservable()
            note = " (without the error model, which needs them)"
        if missing:
            raise InputError(
                f"sequential loop: the first phase (every item except {[i.label for i in nonlin]}) "
                f"leaves {'; '.join(missing)} undetermined, so there is no initial estimate. Add "
                "items that fix them (e.g. Position at both ends) or pass initial=<Solution or "
                "positions (N, d) in m> to bvpnav.sequential.solve_sequential")
        lam = solve_kw["lam"]
        if isinstance(lam, str) and not sub.has_soft_terms:
            lam = 1.0
        sol0 = sub.solve(**{**solve_kw, "lam": lam})
        return (sol0.trajectory[axes], "first phase: every item except the ones to linearize" + note,
                sol0)
    if isinstance(initial, Solution):
        return initial.trajectory[axes], "given Solution", None
    if isinstance(initial, pd.DataFrame):
        return initial[axes], "given DataFrame", None
    p = np.asarray(initial, dtype=float)
    if p.shape != (t.size, len(axes)) or not np.all(np.isfinite(p)):
        raise InputError(f"initial: expected finite positions of shape ({t.size}, {len(axes)}) in m "
                         f"(one row per sample, columns {axes}), got shape {p.shape}")
    return pd.DataFrame(p, index=pd.Index(t, name="t"), columns=axes), "given array", None


def _continued(lin, lam_soft: float):
    """Soft copy of a linearized hard/band item for the continuation phase; (item, sigma in m)."""
    sigma = float(lin.continuation_sigma())
    return lin.with_mode("soft", sigma=sigma * np.sqrt(lam_soft)), sigma


def solve_sequential(problem, solver: str = "clarabel", lam: float | str = 1.0, accuracy: str = "default",
                     verify: bool = True, options: dict | None = None, verbose: bool = False,
                     fallback="auto", *, tol: float = 1e-4, max_iter: int = 30, initial: Any = None,
                     lam_each: bool = False, continuation: bool = True,
                     soft_tol: float | None = None) -> Solution:
    """Solve a problem with items that need linearization by sequential convex solves.

    Parameters
    ----------
    problem : NavigationProblem
    solver, accuracy, verify, options, verbose, fallback
        Passed to :meth:`NavigationProblem.solve` for every convex solve.
    lam : float or str
        A number, or a rule name (``"lcurve"``, ...). A rule is evaluated on the first
        linearization of the final phase and the chosen value kept for the later
        iterations (so the iteration converges to a fixed point of one problem), unless
        ``lam_each``.
    tol : float
        Convergence tolerance in m on the largest change of any nodal position between
        two successive iterations (default 1e-4 m).
    max_iter : int
        Maximum number of linearize-and-solve iterations per phase (default 30).
    initial : Solution, DataFrame or array_like (N, d), optional
        Initial trajectory estimate (positions in m at the samples, all axes). Default:
        solve the problem without the items that need linearization.
    lam_each : bool
        Re-evaluate a lambda rule at every iteration (default False).
    continuation : bool
        Start hard and band items that support it (``continuation_sigma``/``with_mode``,
        e.g. ``TrackLine``) in soft mode (default True; see Notes).
    soft_tol : float, optional
        Tolerance in m on the largest position change that ends the soft phase; default
        ``max(tol, 0.01 m)``.

    Returns
    -------
    Solution
        The last iteration's solution. ``solution.stats["sequential"]`` holds
        ``iterations`` (all phases), ``max_change`` and ``rms_change`` (m, one per
        iteration), ``mode`` (per iteration: ``"soft"`` for a continuation iteration,
        else ``"final"``), ``sigma`` (per iteration: item label -> continuation sigma in
        m, empty in the final phase), ``phases`` (one record per phase: ``mode``,
        ``iterations``, ``tol``, ``converged``), ``converged`` (the final phase),
        ``tol``, ``soft_tol``, ``max_iter``, ``initial`` (what it came from), ``lam`` per
        iteration, per-item row ``status`` counts of the last linearization and
        ``seconds``. When the loop did not converge, a warning is issued and added to
        ``solution.warnings``.

    Raises
    ------
    Infeasible
        From the convex solve of an iteration: the message names the conflicting hard
        items (the linearized item keeps its label).

    Notes
    -----
    Iteration :math:`k` solves the convex problem with every nonlinear item
    :math:`g(r) = 0` replaced by its linearization about the previous estimate
    :math:`r^{(k-1)}`, and stops when :math:`\\max_{j,a} |r^{(k)}_{a,j} - r^{(k-1)}_{a,j}|
    < \\mathrm{tol}`. For a soft track this is a Gauss-Newton step on
    :math:`\\|w\\|^2 + \\lambda \\sum_k (d_k/\\sigma)^2`, a zero-residual problem for
    noise-free data, so the change shrinks quadratically once the estimate is near the
    path.

    Continuation. A hard (or band) track is first iterated in soft mode with

    .. math:: \\sigma^{(k)} = \\max\\big(d_\\mathrm{rms}(r^{(k-1)}),\\ \\sigma_\\min\\big),
              \\qquad \\lambda\\,(d/\\sigma_\\mathrm{eff})^2 = (d/\\sigma^{(k)})^2,

    where :math:`d_\\mathrm{rms}` is the RMS distance (m) of the current estimate to the
    path and :math:`\\sigma_\\min` the item's floor (``TrackLine``: the band half-width,
    or 1e-3 of the path length for a hard track): the track is only as stiff as the
    estimate is near it, so the data term can correct the timing along the path, and it
    stiffens as the estimate approaches. The copy's sigma is scaled by
    :math:`\\sqrt{\\lambda}` so that its weight does not depend on ``lam`` (a rule name
    or ``lam = 0`` uses :math:`\\lambda = 1` in this phase). When the change falls below
    ``soft_tol`` the requested mode is switched on and iterated to ``tol``.

    Why a hard track needs it (a slow, not a wrong, fixed point): see the module docstring.
    """
    def real(v) -> float:
        try:
            return float(v) if not isinstance(v, bool | str) else float("nan")
        except (TypeError, ValueError):
            return float("nan")

    if not (np.isfinite(real(tol)) and real(tol) > 0):
        raise InputError(f"tol={tol!r}: the convergence tolerance must be a positive distance in m")
    if isinstance(max_iter, bool) or not isinstance(max_iter, int | np.integer) or max_iter < 1:
        raise InputError(f"max_iter={max_iter!r}: need an integer of at least one iteration")
    soft_tol = max(float(tol), 0.01) if soft_tol is None else real(soft_tol)
    if not (np.isfinite(soft_tol) and soft_tol > 0):
        raise InputError(f"soft_tol={soft_tol!r}: must be a positive distance in m")
    t_start = time.perf_counter()
    nonlin = [it for it in problem._items if needs_linearization(it)]
    if not nonlin:
        return problem.solve(solver=solver, lam=lam, accuracy=accuracy, verify=verify, options=options,
                             verbose=verbose, fallback=fallback)
    for it in nonlin:
        if not callable(getattr(it, "linearized", None)):
            raise InputError(f"{it.label}: needs a linearization point but has no linearized() method")
    solve_kw = dict(solver=solver, lam=lam, accuracy=accuracy, verify=verify, options=options,
                    verbose=verbose, fallback=fallback)
    traj, origin, _ = _initial_trajectory(problem, initial, nonlin, solve_kw)
    t = problem.model.grid.t
    axes = list(problem.model.axes)
    prev = traj[axes].to_numpy()
    rule = lam if isinstance(lam, str) else None
    lam_now: float | str = lam
    lam_soft = float(lam) if rule is None and float(lam) > 0 else 1.0
    cont = {it.label for it in nonlin if continuation and it.mode in ("hard", "band")
            and callable(getattr(it, "continuation_sigma", None))
            and callable(getattr(it, "with_mode", None))}
    max_change, rms_change, lams, modes, sigmas, phases = [], [], [], [], [], []
    sol, curve, counts = None, None, {}
    converged = False
    soft = bool(cont)
    n_phase = 0
    while True:
        items, sig = [], {}
        for it in problem._items:
            if needs_linearization(it):
                lin = it.linearized(t, traj)
                if hasattr(lin, "projection"):
                    counts[it.label] = lin.projection().counts()
                if soft and it.label in cont:
                    lin, sig[it.label] = _continued(lin, lam_soft)
                items.append(lin)
            else:
                items.append(it)
        sub = problem.with_items(items)
        sol = sub.solve(**{**solve_kw, "lam": lam_soft if soft else lam_now})
        if not soft:
            if rule is not None and curve is None:
                curve = sol.curve
            if rule is not None and not lam_each:
                lam_now = float(sol.lam)
        lams.append(float(sol.lam))
        modes.append("soft" if soft else "final")
        sigmas.append(sig)
        pos = sol.position().reshape(prev.shape)
        diff = pos - prev
        max_change.append(float(np.max(np.abs(diff))))
        rms_change.append(float(np.sqrt(np.mean(diff**2))))
        prev = pos
        traj = sol.trajectory[axes]
        n_phase += 1
        limit = soft_tol if soft else tol
        done = max_change[-1] < limit
        if done or n_phase >= int(max_iter):
            phases.append({"mode": "soft" if soft else "final", "iterations": n_phase, "tol": limit,
                           "converged": bool(done)})
            if not soft:
                converged = done
                break
            soft, n_phase = False, 0
    assert sol is not None
    report = {"iterations": len(max_change), "max_change": max_change, "rms_change": rms_change,
              "mode": modes, "sigma": sigmas, "phases": phases, "continued": sorted(cont),
              "converged": converged, "tol": float(tol), "soft_tol": soft_tol, "max_iter": int(max_iter),
              "initial": origin, "lam": lams, "status": counts, "seconds": time.perf_counter() - t_start}
    sol.stats["sequential"] = report
    if rule is not None:
        sol.lam_rule = rule if lam_each else f"{rule} (first linearization)"
        sol.curve = curve
    if not converged:
        final = [m for m in modes if m == "final"]
        msg = (f"sequential loop did not converge: after {len(final)} iteration(s) of the final phase "
               + (f"(and {len(max_change) - len(final)} soft continuation iteration(s)) " if cont else "")
               + f"the largest position change is {max_change[-1]:.3g} m > tol={tol:g} m (changes: "
               + ", ".join(f"{c:.3g}" for c in max_change)
               + "). Raise max_iter, give a better initial estimate, or loosen tol")
        sol.warnings.append(msg)
        warnings.warn(msg, RuntimeWarning, stacklevel=3)
    return sol
