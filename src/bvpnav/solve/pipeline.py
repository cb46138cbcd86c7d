"""The one place that knows the order of the solve stages.

A solve is ``demote(attitude(sequential(rule(chain))))``:

1. :func:`~bvpnav.solve.conflicts.with_demotion` — ``on_conflict="demote"``: conflicting
   hard items are made soft by priority until the rest holds;
1b. :func:`~bvpnav.solve.attitude.with_attitude` — error models acting on the attitude
   (gyro errors, initial attitude) are solved by a damped outer loop that re-integrates it;
2. :func:`~bvpnav.solve.sequential.with_sequential` — items that must be linearized
   (:class:`~bvpnav.items.Linearizable`) are iterated by sequential convex solves;
3. :func:`~bvpnav.solve.rule.with_rule` — a rule name in ``lam`` is resolved by a sweep;
4. :func:`~bvpnav.solve.chain.solve_fixed` — one formulation at one ``lam`` over the
   back ends, each answer verified by recomputed residuals;

and, with ``uncertainty``, :func:`~bvpnav.solve.uncertainty.attach_uncertainty` on the
answer, with the formulation it solves (the demoted or last linearized one).

Each stage takes the inner stage and calls it with a formulation, a ``lam`` and the one
:class:`~bvpnav.solve.options.SolveOptions` checked before any work; no stage calls back
up, so every option reaches every stage that needs it.

What a solve tells you, and where:

- ``solution.warnings``: everything worth a look (fallbacks, demotions, conditioning,
  rule and loop warnings); those about a choice you can change (a rule's best value at
  the edge of ``lam_range``, a sequential loop that did not converge) are also issued
  through :mod:`warnings` as :class:`bvpnav.log.BvpnavWarning`, once per call and
  attributed to your line;
- the ``bvpnav`` logger (:mod:`bvpnav.log`; silent unless logging is configured): at
  INFO each fallback attempt and its reason, the back end that answered with its
  timings, the chosen lambda and rule, each sequential iteration; at DEBUG the solver
  options in force and the verification measures;
- ``verbose=True``: the solver's own output (cvxpy's ``verbose``, printed to stdout by
  cvxpy and the solver);
- progress bars (tqdm) on lambda sweeps and sequential loops when stderr is a terminal.
"""

from __future__ import annotations

from ..backends import check_memory
from ..formulation import as_formulation
from ..log import once
from ..result import Solution
from .attitude import with_attitude
from .chain import solve_fixed
from .conflicts import with_demotion
from .options import SolveOptions, prepare
from .rule import with_rule
from .sequential import check_sequential, with_sequential
from .uncertainty import attach_uncertainty

__all__ = ["run", "solve", "solve_sequential", "STAGES"]

#: The stages from the outside in (each wraps the next); the last is the innermost.
STAGES = (with_demotion, with_attitude, with_sequential, with_rule)


def run(form, lam, opts: SolveOptions) -> Solution:
    """Run the pipeline on a formulation with checked options."""
    stage = solve_fixed
    for wrap in reversed(STAGES):
        stage = wrap(stage)
    with once():  # each warning once per call, however many stages and iterations raise it
        sol = stage(form, lam, opts)
    used = sol.__dict__.pop("_formulation", form)  # the formulation the answer solves
    if opts.uncertainty:
        sol = attach_uncertainty(sol, used, opts.uncertainty)
    return sol


def solve(form, lam=1.0, **options) -> Solution:
    """Check every option (see :func:`bvpnav.solve.options.prepare`), refuse a primary back
    end that cannot fit in memory, then run the pipeline.

    ``verbose=True`` passes the solver's own output through (cvxpy's ``verbose``: its
    compilation and the solver's iteration log, on stdout); bvpnav's own account of the
    solve is on the ``bvpnav`` logger at INFO and DEBUG (see the module docstring and
    :mod:`bvpnav.log`), whatever ``verbose`` is.
    """
    form = as_formulation(form)
    opts, lam = prepare(lam, **options)
    check_sequential(opts.sequential)
    check_memory(form, opts.backend)  # the primary; a fallback that does not fit is skipped
    return run(form, lam, opts)


def solve_sequential(problem, solver: str = "clarabel", lam: float | str = 1.0, accuracy: str = "default",
                     verify: bool = True, options: dict | None = None, verbose: bool = False,
                     fallback="auto", *, tol: float = 1e-4, max_iter: int = 30, initial=None,
                     lam_each: bool = False, continuation: bool = True,
                     soft_tol: float | None = None, progress: bool | None = None) -> Solution:
    """Solve a problem with items that need linearization by sequential convex solves.

    The same as ``problem.solve(...)`` with the loop's own options (see
    :func:`bvpnav.solve.sequential.with_sequential` for them, the report in
    ``solution.stats["sequential"]`` and the Notes); the other parameters are those of
    :meth:`bvpnav.NavigationProblem.solve`.

    Returns
    -------
    Solution
    """
    seq = dict(tol=tol, max_iter=max_iter, initial=initial, lam_each=lam_each, continuation=continuation,
               soft_tol=soft_tol, progress=progress)
    return solve(problem, lam, solver=solver, accuracy=accuracy, verify=verify, options=options,
                 verbose=verbose, fallback=fallback, sequential=seq)
