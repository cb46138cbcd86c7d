"""cvxpy's installed solvers as back ends: presets, option checks, status mapping.

Every solver cvxpy reports installed (``cvxpy.installed_solvers()``) is a back end under
its lowercase name. Clarabel (the default), OSQP and SCS have measured accuracy presets;
another installed solver runs with its own defaults, and the result records that no
preset was applied (``stats["options"]`` is then the user's options alone).

cvxpy itself is imported when a cvxpy back end is first looked up (the factory asks
``cvxpy.installed_solvers()``) or run, not with this module: ``import bvpnav`` and the
direct back ends do not load it.

Presets
-------
``low``, ``default`` and ``high`` map to each solver's own options (below) and to the
relative tolerance of bvpnav's verification (:data:`bvpnav.backends.VERIFY_RTOL`).
Clarabel's static regularization is switched off in every preset: with it on, the FEM
problems at N >= 1e5 fail to converge (measured; see docs/guide/solvers.md). On an
equality-constrained least-squares problem (hard and soft equalities only) Clarabel also
runs without equilibration (:func:`adapt_options`, recorded in
``sol.stats["adapted_options"]``): 0-3 iterations instead of 3-50, verified at N = 1e6.
"""

from __future__ import annotations

import contextlib
import inspect
import numbers
import os
import time
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from ..cvx import certificate, compiled, conflicting_items
from ..errors import Infeasible, SolveError, Unbounded
from . import Backend, RawSolve, register_factory

if TYPE_CHECKING:
    import cvxpy as cp

__all__ = ["PRESETS", "CANON_BACKEND", "CvxpyBackend", "conic_solvers", "use_conic"]

#: Solver options per preset, by cvxpy's (upper-case) solver name.
PRESETS: dict[str, dict[str, dict[str, Any]]] = {
    "CLARABEL": {
        "low": dict(tol_gap_abs=1e-6, tol_gap_rel=1e-6, tol_feas=1e-6, tol_ktratio=1e-5,
                    static_regularization_enable=False),
        "default": dict(tol_gap_abs=1e-9, tol_gap_rel=1e-9, tol_feas=1e-9,
                        static_regularization_enable=False, max_iter=300),
        "high": dict(tol_gap_abs=1e-11, tol_gap_rel=1e-11, tol_feas=1e-11, tol_ktratio=1e-9,
                     static_regularization_enable=False, max_iter=500,
                     iterative_refinement_reltol=1e-15, iterative_refinement_abstol=1e-15,
                     iterative_refinement_max_iter=50),
    },
    # OSQP (ADMM) cannot reach eps 1e-8 on these problems: at N = 2,000 (1D, soft priors) it
    # stops at 100,000 iterations with status user_limit (measured). ``high`` is therefore the
    # tightest setting it reaches there; polishing then solves the active set's KKT system.
    "OSQP": {
        "low": dict(eps_abs=1e-5, eps_rel=1e-5, max_iter=20000),
        "default": dict(eps_abs=1e-6, eps_rel=1e-6, max_iter=100000, polishing=True),
        "high": dict(eps_abs=1e-7, eps_rel=1e-7, max_iter=50000, polishing=True,
                     polish_refine_iter=50),
    },
    "SCS": {
        "low": dict(eps_abs=1e-5, eps_rel=1e-5, max_iters=20000),
        "default": dict(eps_abs=1e-8, eps_rel=1e-8, max_iters=100000),
        "high": dict(eps_abs=1e-10, eps_rel=1e-10, max_iters=400000),
    },
}

#: Peak resident bytes per sample and axis, measured at N = 1,000,000 (one axis, Table 2
#: shape, each run in its own process, data and problem included; docs/results.md and the
#: README's memory line): Clarabel 4.81 GB in the acceleration form since its data term is
#: a quadratic form of x (5.75 GB before, with an auxiliary copy of w). The load form was
#: not run: its entry keeps the earlier 5.75 GB as a bound. Other cvxpy solvers (not
#: measured) are taken as Clarabel: cvxpy's compiled problem dominates.
CVXPY_MEMORY = {"acceleration": 4815.0, "load": 5750.0}


#: cvxpy's canonicalization back end for every cvxpy solve, unless the options name one
#: (``canon_backend=...``). cvxpy's default (``"CPP"``) grows faster than linearly with the
#: problem's size here; its ``"SCIPY"`` back end builds the same parametrized problem data
#: (DPP in ``lam``) in less time: the compile of one axis at N = 1e6 took 2.4-2.6 s against
#: 3.6-4.8 s, Clarabel's first solve with verification 7.9-8.1 s against 9.1-12.2 s (three
#: fresh processes each, interleaved; the same peak memory, 3.19 GB, and the same
#: re-solve, 2.8 s); 0.79-0.88 against 0.91-1.25 s for three axes at 1e5; no slower at
#: 2e3 and 1e4 (cvxpy 1.9.3, 2026-12-04).
CANON_BACKEND = "SCIPY"


#: Each cvxpy solver's own time-limit option (seconds), for ``solve(time_limit=...)``: Clarabel
#: ``time_limit`` (default inf), OSQP ``time_limit`` (0: none), SCS ``time_limit_secs`` (0:
#: none), HiGHS ``time_limit`` (read from clarabel 0.11, osqp 1.1 and scs 3.3 installed, and
#: HiGHS's option list). A solver not listed (ECOS has only ``max_iters``) gets none: the
#: chain discards its answer when it took longer (:func:`bvpnav.solve.chain.attempt`).
TIME_LIMIT_OPTIONS = {"CLARABEL": "time_limit", "OSQP": "time_limit", "SCS": "time_limit_secs",
                      "HIGHS": "time_limit"}

#: Words of a solver's own status that mean it stopped at its time limit: SCS "solved
#: (inaccurate - reached time_limit_secs)", OSQP "run time limit reached", Clarabel "MaxTime".
_TIME_WORDS = ("time_limit", "time limit", "maxtime", "max_time", "time limit reached")


@contextlib.contextmanager
def captured_output(enabled: bool = True):
    """Capture what a solver prints to the process's stdout and stderr (file descriptors 1
    and 2: C code prints there, not to :data:`sys.stdout`); yields a list that holds the
    text afterwards. SCS prints "ERROR: could not determine problem status." there, HiGHS
    its banner, whatever ``verbose`` is."""
    out: list[str] = []
    if not enabled:
        yield out
        return
    import sys
    import tempfile

    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    try:
        saved = [os.dup(1), os.dup(2)]
    except OSError:  # no such descriptors (an embedded interpreter): nothing to capture
        yield out
        return
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        try:
            os.dup2(tmp.fileno(), 1)
            os.dup2(tmp.fileno(), 2)
            yield out
        finally:
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(Exception):
                    stream.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            tmp.seek(0)
            out.append(tmp.read(64_000).decode("utf-8", "replace").strip())


def _stopped_by_time(prob, limit: float | None, seconds: float) -> bool:
    """Whether a solve stopped at its time limit: the solver's own status says so, or it
    failed (no status, user_limit, solver_error) after at least the limit."""
    if limit is None or not limit > 0 or not np.isfinite(limit):
        return False
    extra = getattr(getattr(prob, "solver_stats", None), "extra_stats", None)
    words = []
    if isinstance(extra, dict):
        words.append(str((extra.get("info") or {}).get("status", "")))
    else:
        words.append(str(getattr(getattr(extra, "info", None), "status", "")))
        words.append(str(getattr(extra, "status", "")))
    if any(w in " ".join(words).lower() for w in _TIME_WORDS):
        return True
    return getattr(prob, "status", None) in (None, "user_limit", "solver_error") and seconds >= limit


#: Clarabel's settings for equality-constrained least squares (see :func:`adapt_options`).
EQUALITY_QP_CLARABEL = {"equilibrate_enable": False, "iterative_refinement_reltol": 1e-15,
                        "iterative_refinement_abstol": 1e-15, "iterative_refinement_stop_ratio": 1.1,
                        "iterative_refinement_max_iter": 50}


def adapt_options(cvxpy_name: str, cvx, options: dict) -> dict:
    """Options the problem's shape adds to the preset's and the user's (recorded in
    ``sol.stats["adapted_options"]``); a key the user (or the preset) gave is left alone.

    Clarabel on an equality-constrained least-squares problem (``cvx.equality_qp``: hard
    and soft equalities only) runs with ``equilibrate_enable=False``. Its only cone is
    then the zero cone, so its initial point, one solve of the KKT system, is already the
    answer; with the Ruiz equilibration (bounded to 1e-4..1e4 per row and column) the FEM
    rows (stiffness entries 1/h beside mass entries h) stay badly scaled, that point
    missed the tolerances and 3-6 interior-point iterations followed, ending at a forward
    error of 2e-9..2e-7 (and ``optimal_inaccurate`` at N = 1e6 with h = 1e-5 s). Without
    equilibration: 0-3 iterations, forward error 1e-10..1e-8 (measured, N = 1e5..1e6,
    clarabel 0.11.1). Unequilibrated, a nearly degenerate error-model block (a sensor axis
    without specific force, scaled condition 2e9) leaves pivots that Clarabel's dynamic
    regularization bumps, and its refinement, stopped once a step gains less than 5x,
    ended at a forward error of 4e-5; refinement to 1e-15 while a step gains 10 % (up to
    50 steps) reaches 1.3e-9 there (and the degenerate combination 1 + k_y 2e-8). With equilibration
    switched back on by the user, the DPP re-solve does not reuse Clarabel's solver in
    place (``warm_start=False``): its in-place update of the quadratic-form data term came
    back inaccurate (see :func:`bvpnav.cvx.data_term`).
    """
    if cvxpy_name != "CLARABEL" or not getattr(cvx, "equality_qp", False):
        return {}
    if options.get("equilibrate_enable", False):
        return {} if "warm_start" in options else {"warm_start": False}
    out = {k: v for k, v in EQUALITY_QP_CLARABEL.items() if k not in options}
    return out


def _cvxpy_keywords() -> set[str]:
    """cvxpy's own keywords of ``Problem.solve`` (accepted with every cvxpy solver)."""
    import cvxpy as cp

    params = inspect.signature(cp.Problem._solve).parameters
    return {k for k, p in params.items() if k not in ("self", "solver")
            and p.kind is not inspect.Parameter.VAR_KEYWORD}


def _clarabel_settings() -> dict[str, Any] | None:
    try:
        import clarabel
    except ImportError:  # pragma: no cover - clarabel is a dependency of cvxpy
        return None
    settings = clarabel.DefaultSettings()
    return {a: getattr(settings, a) for a in dir(settings)
            if not a.startswith("_") and not callable(getattr(settings, a))}


def _osqp_settings() -> dict[str, Any] | None:
    try:
        from osqp.ext_builtin import OSQPSettings
    except ImportError:  # pragma: no cover - another OSQP build: it judges its options itself
        return None
    settings = OSQPSettings()
    return {a: getattr(settings, a) for a in dir(settings) if not a.startswith("_")}


#: Earlier spellings of settings, per solver, translated before the solve (OSQP 1.x renamed
#: ``polish`` to ``polishing`` and silently ignores the old name: a user's polish=False did
#: nothing).
ALIASES: dict[str, dict[str, str]] = {"osqp": {"polish": "polishing"}}

#: Solvers whose settings bvpnav can list (names checked before any work; Clarabel's values
#: are type-checked too); others judge their options themselves (a refusal is a recorded
#: failed attempt, see :func:`bvpnav.solve.chain.solve_fixed`).
_SETTINGS = {"clarabel": _clarabel_settings, "osqp": _osqp_settings}


def _type_of(default) -> tuple[str, Any] | None:
    """(description, check) for a setting's default value's type."""
    if isinstance(default, bool):
        return "True or False", lambda v: isinstance(v, bool | np.bool_)
    if isinstance(default, numbers.Integral):
        return "an integer", lambda v: isinstance(v, numbers.Integral) and not isinstance(v, bool | np.bool_)
    if isinstance(default, numbers.Real):
        return "a number", lambda v: isinstance(v, numbers.Real) and not isinstance(v, bool | np.bool_)
    return None


class CvxpyBackend(Backend):
    """One cvxpy solver (``cvxpy_name`` as cvxpy spells it)."""

    memory_per_sample = CVXPY_MEMORY

    def __init__(self, cvxpy_name: str):
        self.cvxpy_name = cvxpy_name
        self.name = cvxpy_name.lower()
        self.presets = PRESETS.get(cvxpy_name, {})
        self.time_limit_option = TIME_LIMIT_OPTIONS.get(cvxpy_name)

    # ------------------------------------------------------------ options
    def valid_options(self) -> list[str] | None:
        listed = _SETTINGS.get(self.name)
        settings = listed() if listed is not None else None
        if settings is None:
            return None
        return sorted(set(settings) | _cvxpy_keywords() | set(ALIASES.get(self.name, {})))

    def check_value(self, key: str, value) -> str | None:
        if self.name != "clarabel":
            return None
        default = (_clarabel_settings() or {}).get(key)
        kind = _type_of(default) if default is not None else None
        if kind is None or kind[1](value):
            return None
        return f"{kind[0]} (Clarabel's setting {key}, default {default!r})"

    # ------------------------------------------------------------ support
    def takes_cones(self) -> bool:
        """Whether the solver accepts second-order cones (asks cvxpy's solver table)."""
        from cvxpy.constraints import SOC
        from cvxpy.reductions.solvers.defines import SOLVER_MAP_CONIC

        solver = SOLVER_MAP_CONIC.get(self.cvxpy_name)
        return solver is not None and SOC in getattr(solver, "SUPPORTED_CONSTRAINTS", ())

    def takes_quadratics(self) -> bool:
        """Whether the solver takes the quadratic data term (a QP solver, or a conic solver
        with second-order cones); LP/MILP-only solvers (cvxpy's SCIPY) do not."""
        from cvxpy.reductions.solvers.defines import SOLVER_MAP_QP

        return self.cvxpy_name in SOLVER_MAP_QP or self.takes_cones()

    def accepts(self, form) -> str | None:
        if not self.takes_quadratics():
            return (f"solver {self.name!r} solves linear programs only: it takes no quadratic "
                    "objective, and every bvpnav problem has one (the data term). Use "
                    "solver='clarabel' (or 'osqp', 'scs')")
        if self.takes_cones():
            return None
        for term in form.terms():
            if term.kind == "cone":
                return (f"solver {self.name!r} cannot take item {term.label!r} (kind {term.kind!r}, "
                        f"mode {term.mode!r}): it is a QP solver and this item is a second-order "
                        f"cone. {use_conic()}.")
        return None

    # ---------------------------------------------------------------- run
    def run(self, form, lam: float, options: dict, verbose: bool = False) -> RawSolve:
        import cvxpy as cp

        cvx = compiled(form)
        prob: cp.Problem = cvx.problem
        cvx.lam.value = lam
        alias = ALIASES.get(self.name, {})
        options = {alias.get(k, k): v for k, v in options.items()}
        adapted = adapt_options(self.cvxpy_name, cvx, options)
        canon = {} if "canon_backend" in options else {"canon_backend": CANON_BACKEND}
        limit = options.get(self.time_limit_option) if self.time_limit_option else None
        t0 = time.perf_counter()
        printed: list[str] = []
        try:
            with captured_output(not verbose) as printed, warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                prob.solve(solver=self.cvxpy_name, verbose=verbose, **options, **adapted, **canon)
            if adapted.get("equilibrate_enable") is False and prob.status != cp.OPTIMAL:
                # without its equilibration Clarabel can call consistent but redundant hard
                # rows (a hard zero-velocity interval beside a hard position) infeasible: its
                # own scaling is the safer default then
                first = prob.status
                adapted = {"equilibrate_enable": True, "warm_start": False,
                           "retried": f"equilibration on after status {first}"}
                prob.solve(solver=self.cvxpy_name, verbose=verbose, **options, **canon,
                           **{k: v for k, v in adapted.items() if k != "retried" and k not in options})
        except cp.error.SolverError as exc:
            said = (printed or [""])[0] or None
            if _stopped_by_time(prob, limit, time.perf_counter() - t0):
                raise self._timed_out(limit, said) from exc
            raise SolveError(
                f"{self.name} failed: {exc}" + (f" (it printed: {said[-300:]})" if said else ""),
                attempts=[{"solver": self.name, "status": "solver_error", "reason": str(exc),
                           **({"output": said} if said else {})}],
            ) from exc
        said = (printed or [""])[0] or None
        if _stopped_by_time(prob, limit, time.perf_counter() - t0):
            raise self._timed_out(limit, said)
        status = prob.status
        st = prob.solver_stats
        info = {
            "status": status,
            "iterations": getattr(st, "num_iters", None),
            "solve_time": getattr(st, "solve_time", None),
            "setup_time": getattr(st, "setup_time", None),
            "compile_time": getattr(prob, "compilation_time", None),
            "cvxpy_time": time.perf_counter() - t0,
            "objective": prob.value,
            "solver_warnings": [str(w.message) for w in caught],
            "adapted_options": adapted,
            "canon_backend": options.get("canon_backend", CANON_BACKEND),
        }
        if said:
            info["solver_output"] = said
        self._raise_for(status, form, cvx)
        return RawSolve(np.array(cvx.x.value, dtype=float), info, cvx.duals())

    def _timed_out(self, limit: float, said: str | None) -> SolveError:
        reason = f"time limit reached ({limit:g} s)"
        return SolveError(f"{self.name}: {reason}; give a larger time_limit, or another solver",
                          attempts=[{"solver": self.name, "status": "time limit", "reason": reason,
                                     **({"output": said} if said else {})}])

    def _raise_for(self, status: str, form, cvx) -> None:
        """Raise for an infeasible (naming the conflicting items), unbounded or empty answer."""
        import cvxpy as cp

        if status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
            raise self._infeasible(status, form, cvx)
        if status in (cp.UNBOUNDED, cp.UNBOUNDED_INACCURATE):
            raise Unbounded(
                f"{self.name}: the problem is unbounded (status {status}); some unknown is not "
                "determined by any information",
                attempts=[{"solver": self.name, "status": status, "reason": "unbounded"}],
            )
        if cvx.x.value is None:
            raise SolveError(
                f"{self.name} returned no solution (status {status})",
                attempts=[{"solver": self.name, "status": status, "reason": "no solution"}],
            )

    def _infeasible(self, status: str, form, cvx) -> SolveError:
        """The error of an "infeasible" verdict: :class:`Infeasible` naming a conflicting
        subset when the solver's certificate is confirmed (:func:`bvpnav.cvx.certificate`),
        else a plain :class:`SolveError` (a failed attempt: the fallback chain moves on).

        The certificate is checked against bvpnav's own rows; the conflicting subset comes
        from the deletion filter (:func:`bvpnav.cvx.conflicting_items`), whose every
        verdict is confirmed the same way, else from the certificate's own support.
        """
        try:
            cert = certificate(form, cvx)
        except Exception as exc:  # a malformed certificate is no proof
            cert, why = None, f"its certificate could not be checked ({type(exc).__name__}: {exc})"
        else:
            why = "it left no certificate" if cert is None else f"its certificate {cert.describe()}"
        if cert is None or not cert.confirmed:
            reason = f"its '{status}' verdict was not confirmed: {why}"
            return SolveError(f"{self.name}: {reason}",
                              attempts=[{"solver": self.name, "status": status, "reason": reason}])
        try:
            culprits = conflicting_items(form)
        except Exception:  # the finder must never hide the confirmed verdict
            culprits = []
        ident = {it.label: it.identify() for it in form.items}  # unnamed items: what they hold
        if culprits:
            which = (f"These hard items conflict: {[ident.get(c, c) for c in culprits]}. Soften one of "
                     "them (give sigma=...).")
        else:
            culprits = list(cert.support)
            which = (f"No smaller conflicting subset was found; the certificate rests on the hard items "
                     f"{[ident.get(c, c) for c in culprits]}: soften one of them (give sigma=...).")
        return Infeasible(
            f"{self.name}: the hard information cannot hold together (status {status}; {why}). {which}",
            attempts=[{"solver": self.name, "status": status, "reason": "infeasible (certificate confirmed)",
                       "conflicts": culprits}],
        )


_CACHE: dict[str, CvxpyBackend] = {}


def conic_solvers() -> list[str]:
    """The installed cvxpy solvers that take every bvpnav item (second-order cones
    included), of Clarabel and SCS: the solvers error messages suggest."""
    import cvxpy as cp

    return [n for n in ("clarabel", "scs") if n.upper() in cp.installed_solvers()]


def use_conic() -> str:
    """The suggestion of a refusal: ``Use solver='clarabel' or solver='scs'`` (the installed
    ones of :func:`conic_solvers`; Clarabel when none is)."""
    conic = conic_solvers()
    return (f"Use solver={conic[0] if conic else 'clarabel'!r}"
            + (f" or solver={conic[1]!r}" if len(conic) > 1 else ""))


def _installed() -> list[CvxpyBackend]:
    """One back end per installed cvxpy solver that takes a quadratic objective (objects
    kept, so patches and state stick). LP/MILP-only solvers (cvxpy's SCIPY) are not offered:
    every bvpnav problem has a quadratic data term."""
    import cvxpy as cp

    out = []
    for s in cp.installed_solvers():
        if s not in _CACHE:
            _CACHE[s] = CvxpyBackend(s)
        if _CACHE[s].takes_quadratics():
            out.append(_CACHE[s])
    return out


register_factory(_installed)
