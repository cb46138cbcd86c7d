"""Solvers side by side on one problem: a tidy table, failures included."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from .backends import ACCURACIES, available_solvers, check_options, resolve_solver
from .declare import check_option
from .errors import BvpnavError, InputError, SolveError
from .linalg.lsq import least_squares_form, non_least_squares_term
from .solve import check_lam, choose_lambda

__all__ = ["compare_solvers", "COLUMNS"]

#: Columns of :func:`compare_solvers`'s table.
COLUMNS = ["solver", "preset", "status", "verified", "compile_time", "solve_time", "wall_time",
           "iterations", "objective", "fem_residual", "max_violation", "forward_error", "rms_error",
           "max_error", "error"]


def _reference_positions(reference, problem):
    if reference is None:
        return None
    if hasattr(reference, "position") and callable(reference.position):
        ref = reference.position()
    else:
        ref = np.asarray(reference, dtype=float)
    ref = ref.reshape(problem.model.N, -1)
    if ref.shape[1] != problem.model.d:
        raise InputError(f"reference has {ref.shape[1]} axes, the problem {problem.model.d}; give "
                         "positions of shape (N,) or (N, d) in m at the sample times")
    return ref


def _listed(value, what: str) -> list:
    if isinstance(value, str) or not isinstance(value, Sequence):
        raise InputError(f"{what}={value!r}: give a list of names, e.g. {what}=['default']"
                         if what == "presets" else
                         f"{what}={value!r}: give a list of names, e.g. {what}=['clarabel', 'direct']")
    if len(value) == 0:
        raise InputError(f"{what}=[]: give at least one name")
    return list(value)


def _check_names(problem, solvers, presets, options) -> None:
    """InputError before any run for unknown solver or preset names (all of them named,
    with the valid ones) and for options keyed by a solver that is not compared."""
    solvers, presets = _listed(solvers, "solvers"), _listed(presets, "presets")
    have = available_solvers()
    bad = [s for s in solvers if not isinstance(s, str) or s.strip().lower() not in have]
    if bad:
        raise InputError(f"compare_solvers: unknown or not installed solver(s) {bad}; available: {have}")
    bad = [p for p in presets if p not in ACCURACIES]
    if bad:
        raise InputError(f"compare_solvers: unknown preset(s) {bad}; choose from {list(ACCURACIES)}")
    if options is not None:
        if not isinstance(options, Mapping):
            raise InputError(f"options={options!r}: give per-solver options, e.g. "
                             "options={'osqp': {'max_iter': 1000}}")
        names = {s.strip().lower() for s in solvers}
        stray = [k for k in options if k not in names]
        if stray:
            raise InputError(f"options: solver(s) {stray} are not among the compared solvers "
                             f"{list(solvers)}; key the options by one of them, e.g. "
                             "options={'osqp': {'max_iter': 1000}}")
        for name, opts in options.items():
            check_options(resolve_solver(name), opts, what=f"options[{name!r}]")


def compare_solvers(problem, solvers: Sequence[str] | None = None, presets: Sequence[str] = ("default",),
                    reference=None, lam: float | str = 1.0, options: dict | None = None,
                    time_limit: float | None = None) -> pd.DataFrame:
    """Solve one problem with several solvers and accuracy presets.

    Parameters
    ----------
    problem : NavigationProblem
    solvers : sequence of str, optional
        Solver names (default: Clarabel and OSQP, and the direct back ends ``direct`` and
        ``csne`` when the problem is least squares; SCS and others on request, e.g.
        ``solvers=["clarabel", "scs"]``: SCS needs about 10^5 iterations and tens of seconds
        for a 2,000-sample problem).
    presets : sequence of {"low", "default", "high"}
    reference : array_like or Solution, optional
        True (or reference) positions, m, shape (N,) or (N, d), for ``rms_error`` and
        ``max_error``.
    lam : float or str
        The same lambda for every run (a rule name is resolved once, before the runs, with
        the direct sweep when possible).
    options : dict, optional
        Per-solver extra options: ``{"osqp": {"max_iter": 1000}}``.
    time_limit : float, optional
        Seconds each run may take (``solve(time_limit=...)``; None: no limit). A run stopped
        by it is a row with status ``"time limit"`` and the reason in ``error``.

    Returns
    -------
    pandas.DataFrame
        One row per (solver, preset) with :data:`COLUMNS`: status as reported by the solver
        (or the error class), ``verified`` from bvpnav's residual checks, times in s,
        ``fem_residual``/``max_violation``/``forward_error`` relative, errors in m. A run
        that fails is a row with its status and message in ``error``; nothing is raised.

    Notes
    -----
    Runs use ``fallback=None`` and ``verify=False`` so each row shows that solver's own
    answer; ``verified`` then says whether bvpnav would have accepted it.

    Examples
    --------
    Two back ends on the same problem, each verified against bvpnav's own residual checks:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.full(21, 0.5)))
    >>> prob = prob.add(Position(t=[0.0, 2.0], value=[0.0, 3.0]))
    >>> table = bvpnav.compare_solvers(prob, solvers=["direct", "clarabel"])
    >>> print(table[["solver", "status", "verified"]].to_string(index=False))
      solver  status  verified
      direct optimal      True
    clarabel optimal      True
    """
    if solvers is None:
        have = set(available_solvers())
        solvers = [s for s in ("clarabel", "osqp") if s in have]
        if non_least_squares_term(problem.formulation) is None:
            solvers += ["direct", "csne"]
    _check_names(problem, solvers, presets, options)
    lam = check_lam(lam)
    time_limit = check_option("time_limit", time_limit)
    if isinstance(lam, str):
        lam = choose_lambda(problem, lam)
    ref = _reference_positions(reference, problem)
    ls = least_squares_form(problem.formulation, lam)
    rows = []
    for name in solvers:
        for preset in presets:
            row = dict.fromkeys(COLUMNS)
            row.update(solver=name, preset=preset, verified=False)
            t0 = time.perf_counter()
            try:
                sol = problem.solve(solver=name, lam=lam, accuracy=preset, verify=False, fallback=None,
                                    options=(options or {}).get(name), time_limit=time_limit)
            except (SolveError, BvpnavError) as exc:
                att = getattr(exc, "attempts", None) or []
                row.update(status=att[-1]["status"] if att else type(exc).__name__,
                           error=f"{type(exc).__name__}: {exc}", wall_time=time.perf_counter() - t0)
                rows.append(row)
                continue
            st = sol.stats
            ver = st.get("verification", {})
            row.update(status=st.get("status"), verified=bool(st.get("verified")),
                       compile_time=st.get("compile_time"), solve_time=st.get("solve_time"),
                       wall_time=st.get("wall_time"), iterations=st.get("iterations"),
                       objective=st.get("objective"), fem_residual=ver.get("fem_residual"),
                       max_violation=ver.get("max_violation"), forward_error=ver.get("forward_error"))
            if row["objective"] is None and ls is not None:
                row["objective"] = float(np.sum(ls.D.value(sol.x) ** 2))
            if ref is not None:
                e = sol.position().reshape(ref.shape) - ref
                row.update(rms_error=float(np.sqrt(np.mean(e**2))), max_error=float(np.max(np.abs(e))))
            rows.append(row)
    df = pd.DataFrame(rows, columns=COLUMNS)
    for c in ("compile_time", "solve_time", "wall_time", "objective", "fem_residual", "max_violation",
              "forward_error", "rms_error", "max_error"):
        df[c] = pd.to_numeric(df[c], errors="coerce")
    return df
