"""The innermost stage: one formulation at one fixed ``lam``, over a chain of back ends.

:func:`solve_fixed` tries the primary back end, then each fallback, until one answer
passes verification. Every try is a typed :class:`~bvpnav.result.Attempt` with its status
and reason: a back end that cannot take the problem or would not fit in memory is
skipped with the reason; any exception a back end raises (``LinAlgError``, SCS's
``ValueError``, ``MemoryError``, ...) is a failed attempt, then the next back end runs.
Infeasibility is a property of the information, not of a back end: it is raised at once,
naming the conflicting items.
"""

from __future__ import annotations

import logging
import time

from ..backends import Backend, memory_shortfall
from ..errors import BvpnavError, Infeasible, InputError, SolveError
from ..formulation import Formulation
from ..linalg.workspace import Workspace
from ..log import in_sweep
from ..result import Attempt, Solution
from .assemble import finish
from .options import SolveOptions

__all__ = ["solve_fixed", "attempt"]

log = logging.getLogger(__name__)


def attempt(form: Formulation, backend: Backend, options: dict, lam: float, opts: SolveOptions,
            workspace: Workspace | None = None) -> Solution:
    """One back end's verified answer at ``lam`` (or an exception); ``workspace`` goes to a
    back end that declares it uses one (:attr:`~bvpnav.backends.Backend.uses_workspace`)
    and to verification."""
    workspace = Workspace() if workspace is None else workspace
    why = backend.accepts(form)  # before solving: e.g. a cone item given to a QP solver
    if why is not None:
        raise InputError(why)
    limit = opts.time_limit
    native = getattr(backend, "time_limit_option", None)
    if limit is not None and native and native not in options:  # the user's own option wins
        options = {**options, native: limit}
    log.debug("%s at lam=%g: options in force %s (accuracy %r)", backend.name, lam, options, opts.accuracy)
    t_start = time.perf_counter()
    if getattr(backend, "uses_workspace", False):   # False for a back end written before it existed
        raw = backend.run(form, lam, options, opts.verbose, workspace=workspace)
    else:
        raw = backend.run(form, lam, options, opts.verbose)
    run = dict(raw.info)
    run["wall_time"] = time.perf_counter() - t_start
    if limit is not None and not native and run["wall_time"] > limit:
        # no option of its own stops it: run to the end, the answer discarded
        reason = f"time limit reached ({limit:g} s)"
        raise SolveError(f"{backend.name}: {reason}: it took {run['wall_time']:.3g} s and has no time "
                         "limit of its own, so its answer was discarded; give a larger time_limit",
                         attempts=[{"solver": backend.name, "status": "time limit", "reason": reason}])
    run.update(solver=backend.name, accuracy=opts.accuracy, options=options,
               preset_applied=opts.accuracy in backend.presets)
    sol = finish(form, raw.x, lam, run, raw.duals, opts.accuracy, opts.verify, raw.factored, workspace)
    if log.isEnabledFor(logging.DEBUG):
        log.debug("%s at lam=%g: verification %s", backend.name, lam, sol.stats.get("verification"))
    return sol


def _next(opts: SolveOptions, k: int) -> str:
    return f"trying {opts.chain[k + 1][0].name}" if k + 1 < len(opts.chain) else "no back end left"


def _fell_back(opts: SolveOptions, k: int, be: Backend, status: str, reason: str) -> None:
    log.info("%s at attempt %d: %s (%s); %s", be.name, k + 1, status, reason, _next(opts, k))


def _answered(sol: Solution, be: Backend, lam: float, k: int) -> None:
    st = sol.stats
    times = ", ".join(f"{key} {st[key]:.3g} s" for key in ("wall_time", "solve_time", "setup_time",
                                                          "compile_time") if isinstance(st.get(key), float))
    log.log(logging.DEBUG if in_sweep() else logging.INFO,
            "%s answered at lam=%g (attempt %d, %s, %s): %s", be.name, lam, k + 1, st.get("status"),
            "verified" if st.get("verified") else "not verified", times)


def _failed(backend: Backend, exc: Exception) -> SolveError:
    reason = f"{type(exc).__name__}: {exc}"
    err = SolveError(f"{backend.name} failed: {reason}",
                     attempts=[Attempt(solver=backend.name, status="error", reason=reason)])
    err.__cause__ = exc
    return err


def solve_fixed(form: Formulation, lam: float, opts: SolveOptions, workspace: Workspace | None = None
                ) -> Solution:
    """Solve ``form`` at a fixed ``lam``, falling back over ``opts.chain``, with one
    :class:`~bvpnav.linalg.workspace.Workspace` for every attempt (``workspace``: the rule
    stage's, holding its sweep's band and factors; else a new one).

    Raises
    ------
    InputError
        From the checks before solving (weights, observability) or when the primary back
        end cannot take the problem.
    Infeasible
        Naming the conflicting hard items.
    SolveError
        When every attempt failed; ``error.attempts`` lists them.
    """
    form.check_scales(lam)
    form.check_observability()
    workspace = Workspace() if workspace is None else workspace
    attempts: list[Attempt] = []
    last_exc: SolveError | None = None
    for k, (be, op) in enumerate(opts.chain):
        short = memory_shortfall(be, form) if k else None
        if short is not None:
            attempts.append(Attempt(solver=be.name, status="not applicable", reason=short))
            _fell_back(opts, k, be, "not applicable", short)
            continue
        try:
            sol = attempt(form, be, op, lam, opts, workspace)
        except Infeasible as exc:  # a property of the information
            exc.attempts = Attempt.plain(attempts + list(exc.attempts))
            raise
        except InputError as exc:
            if k == 0:
                raise
            # a fallback that cannot take this problem (e.g. direct with inequalities)
            attempts.append(Attempt(solver=be.name, status="not applicable", reason=str(exc)))
            _fell_back(opts, k, be, "not applicable", str(exc))
            continue
        except SolveError as exc:
            attempts.extend(Attempt.of(a) for a in (exc.attempts or [{"solver": be.name, "status": "error",
                                                                      "reason": str(exc)}]))
            last_exc = exc
            if not opts.verify and k == 0:
                exc.attempts = Attempt.plain(exc.attempts)
                raise
            _fell_back(opts, k, be, "failed", str(exc))
            continue
        except (BvpnavError, KeyboardInterrupt, SystemExit):
            raise
        except Exception as exc:  # a back end's own failure: recorded, then the next one
            err = _failed(be, exc)
            attempts.extend(err.attempts)
            last_exc = err
            if not opts.verify and k == 0:
                err.attempts = Attempt.plain(err.attempts)
                raise err from exc
            _fell_back(opts, k, be, "error", err.attempts[0]["reason"])
            continue
        _answered(sol, be, lam, k)
        sol.record(attempts=attempts + sol.records.attempts)
        if attempts:
            sol.warnings.append(f"{opts.backend.name} failed ({attempts[0]['reason']}); the answer "
                                f"comes from {be.name} with options {op}")
        return sol
    assert last_exc is not None
    summary = "; ".join(f"{a['solver']}: {a['status']} ({a['reason']})" for a in attempts)
    raise type(last_exc)(f"every attempt failed: {summary}. Last error: {last_exc}",
                         attempts=Attempt.plain(attempts)) from last_exc.__cause__
