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
   iterations is below ``tol`` (m) or after ``max_iter`` solves.
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


def _sub_problem(problem, items, error_model: bool = True):
    from .problem import NavigationProblem

    sub = NavigationProblem(problem.data, residual=problem.residual,
                            sigma_a=problem.sigma_a if problem._sigma_a_given else None,
                            error_model=problem.error_model if error_model else None, items=items)
    if error_model:
        sub._model = problem.model  # the same unknowns and FEM matrices
    return sub


def _initial_trajectory(problem, initial, nonlin, solve_kw) -> tuple[pd.DataFrame, str, Solution | None]:
    t = problem.model.grid.t
    axes = list(problem.model.axes)
    if initial is None:
        rest = [it for it in problem._items if not needs_linearization(it)]
        sub = _sub_problem(problem, rest)
        missing = sub.unobservable()
        note = ""
        if missing and problem.error_model is not None:
            # the error-model parameters may need the nonlinear items: start with them at zero
            sub = _sub_problem(problem, rest, error_model=False)
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


def solve_sequential(problem, solver: str = "clarabel", lam: float | str = 1.0, accuracy: str = "default",
                     verify: bool = True, options: dict | None = None, verbose: bool = False,
                     fallback="auto", *, tol: float = 1e-4, max_iter: int = 30, initial: Any = None,
                     lam_each: bool = False) -> Solution:
    """Solve a problem with items that need linearization by sequential convex solves.

    Parameters
    ----------
    problem : NavigationProblem
    solver, accuracy, verify, options, verbose, fallback
        Passed to :meth:`NavigationProblem.solve` for every convex solve.
    lam : float or str
        A number, or a rule name (``"lcurve"``, ...). A rule is evaluated on the first
        linearization and the chosen value kept for the later iterations (so the
        iteration converges to a fixed point of one problem), unless ``lam_each``.
    tol : float
        Convergence tolerance in m on the largest change of any nodal position between
        two successive iterations (default 1e-4 m).
    max_iter : int
        Maximum number of linearize-and-solve iterations (default 30).
    initial : Solution, DataFrame or array_like (N, d), optional
        Initial trajectory estimate (positions in m at the samples, all axes). Default:
        solve the problem without the items that need linearization.
    lam_each : bool
        Re-evaluate a lambda rule at every iteration (default False).

    Returns
    -------
    Solution
        The last iteration's solution. ``solution.stats["sequential"]`` holds
        ``iterations``, ``max_change`` and ``rms_change`` (m, one per iteration),
        ``converged``, ``tol``, ``max_iter``, ``initial`` (what it came from),
        ``lam`` per iteration, per-item row ``status`` counts of the last
        linearization and ``seconds``. When the loop did not converge, a warning is
        issued and added to ``solution.warnings``.

    Notes
    -----
    Iteration :math:`k` solves the convex problem with every nonlinear item
    :math:`g(r) = 0` replaced by its linearization about the previous estimate
    :math:`r^{(k-1)}`, and stops when :math:`\\max_{j,a} |r^{(k)}_{a,j} - r^{(k-1)}_{a,j}|
    < \\mathrm{tol}`. For a track this is a Gauss-Newton step on the distance to the
    path: the error of the linearization is second order in the distance of the estimate
    from the path, so the change shrinks quickly once the estimate is near the path.
    """
    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tol={tol!r}: the convergence tolerance must be a positive distance in m")
    if int(max_iter) < 1:
        raise InputError(f"max_iter={max_iter!r}: need at least one iteration")
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
    max_change, rms_change, lams = [], [], []
    sol, curve, counts = None, None, {}
    converged = False
    for _k in range(int(max_iter)):
        items = []
        for it in problem._items:
            if needs_linearization(it):
                lin = it.linearized(t, traj)
                if hasattr(lin, "projection"):
                    counts[it.label] = lin.projection().counts()
                items.append(lin)
            else:
                items.append(it)
        sub = _sub_problem(problem, items)
        sol = sub.solve(**{**solve_kw, "lam": lam_now})
        if rule is not None and curve is None:
            curve = sol.curve
        lams.append(float(sol.lam))
        if rule is not None and not lam_each:
            lam_now = float(sol.lam)
        pos = sol.position()
        pos = pos.reshape(prev.shape)
        diff = pos - prev
        max_change.append(float(np.max(np.abs(diff))))
        rms_change.append(float(np.sqrt(np.mean(diff**2))))
        prev = pos
        traj = sol.trajectory[axes]
        if max_change[-1] < tol:
            converged = True
            break
    assert sol is not None
    report = {"iterations": len(max_change), "max_change": max_change, "rms_change": rms_change,
              "converged": converged, "tol": float(tol), "max_iter": int(max_iter), "initial": origin,
              "lam": lams, "status": counts, "seconds": time.perf_counter() - t_start}
    sol.stats["sequential"] = report
    if rule is not None:
        sol.lam_rule = rule if lam_each else f"{rule} (first linearization)"
        sol.curve = curve
    if not converged:
        msg = (f"sequential loop did not converge: after {len(max_change)} iteration(s) the largest "
               f"position change is {max_change[-1]:.3g} m > tol={tol:g} m (changes: "
               + ", ".join(f"{c:.3g}" for c in max_change)
               + "). Raise max_iter, give a better initial estimate, or loosen tol")
        sol.warnings.append(msg)
        warnings.warn(msg, RuntimeWarning, stacklevel=3)
    return sol
