"""The one place that knows the order of the solve stages.

A solve is ``gate(demote(attitude(sequential(rule(chain)))))``:

0. :func:`~bvpnav.solve.gating.with_gating` — fixes with a ``gate`` whose normalized
   residual exceeds it are rejected (listed in ``Solution.rejected``) and the rest solved again;
1. :func:`~bvpnav.solve.conflicts.with_demotion` — ``on_conflict="demote"``: conflicting
   hard items are made soft by priority until the rest holds;
2. :func:`~bvpnav.solve.attitude.with_attitude` — error models acting on the attitude
   (gyro errors, initial attitude) are solved by a damped outer loop that re-integrates it;
3. :func:`~bvpnav.solve.sequential.with_sequential` — items that must be linearized
   (:class:`~bvpnav.items.Linearizable`) are iterated by sequential convex solves;
4. :func:`~bvpnav.solve.rule.with_rule` — a rule name in ``lam`` is resolved by a sweep;
5. :func:`~bvpnav.solve.chain.solve_fixed` — one formulation at one ``lam`` over the
   back ends, each answer verified by recomputed residuals;

then :func:`~bvpnav.solve.plausibility.attach` (misfit against the stated noise and
implausible error-model estimates, always) and, with ``uncertainty``,
:func:`~bvpnav.solve.uncertainty.attach_uncertainty` on the answer, with the formulation
it solves (the demoted or last linearized one).

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
from ..formulation import Formulation, as_formulation
from ..log import once
from ..result import Solution
from .attitude import with_attitude
from .chain import solve_fixed
from .conflicts import with_demotion
from .gating import with_gating
from .options import SolveOptions, prepare
from .plausibility import attach as attach_plausibility
from .rule import with_rule
from .sequential import check_sequential, with_sequential
from .uncertainty import attach_uncertainty

__all__ = ["run", "solve", "solve_sequential", "STAGES"]

#: The stages from the outside in (each wraps the next); the last is the innermost.
STAGES = (with_gating, with_demotion, with_attitude, with_sequential, with_rule)


def run(form: Formulation, lam, opts: SolveOptions) -> Solution:
    """Run the pipeline on a formulation with checked options.

    Examples
    --------
    Options checked once by :func:`~bvpnav.solve.options.prepare`, then the pipeline:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.full(21, 0.5)))
    >>> prob = prob.add(Position(t=[0.0, 2.0], value=[0.0, 3.0]))
    >>> from bvpnav.solve import prepare, run
    >>> opts, lam = prepare(1.0, solver="direct")
    >>> sol = run(prob.formulation, lam, opts)
    >>> print(f"v(0) = {sol.velocity('x')[0]:.3f} m/s")
    v(0) = 1.000 m/s
    """
    stage = solve_fixed
    for wrap in reversed(STAGES):
        stage = wrap(stage)
    with once():  # each warning once per call, however many stages and iterations raise it
        sol = stage(form, lam, opts)
    used = form if sol.formulation is None else sol.formulation  # the formulation the answer solves
    sol = attach_plausibility(sol, used, form.data)  # misfit and implausible estimates, always
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

    Examples
    --------
    The function behind :meth:`bvpnav.NavigationProblem.solve`:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.full(21, 0.5)))
    >>> prob = prob.add(Position(t=[0.0, 2.0], value=[0.0, 3.0]))
    >>> sol = bvpnav.solve.solve(prob, solver="direct")
    >>> print(f"v(0) = {sol.velocity('x')[0]:.3f} m/s, v(2) = {sol.velocity('x')[-1]:.3f} m/s")
    v(0) = 1.000 m/s, v(2) = 2.000 m/s
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

    Examples
    --------
    A vehicle drives 10 m along the x axis in 10 s; a small bias on the y accelerometer
    (0.02 sin t m/s^2) would bend its path, but it is known to stay on the line y = 0
    (:class:`~bvpnav.constraints.TrackLine`, an item solved by linearization):

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, TrackLine
    >>> t = np.linspace(0.0, 10.0, 51)
    >>> acc = np.zeros((51, 2))
    >>> acc[:, 1] = 0.02 * np.sin(t)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc, axes=("x", "y")))
    >>> prob = prob.add(Position(t=[0.0, 10.0], value=[[0.0, 0.0], [10.0, 0.0]]),
    ...                 TrackLine(x=[0.0, 5.0, 10.0], y=[0.0, 0.0, 0.0], axes=("x", "y"), sigma=0.01))
    >>> sol = bvpnav.solve.solve_sequential(prob, solver="direct")
    >>> sol.stats["sequential"]["converged"]
    True
    >>> print(f"largest |y| {np.abs(sol.position('y')).max():.3f} m")
    largest |y| 0.000 m
    """
    seq = dict(tol=tol, max_iter=max_iter, initial=initial, lam_each=lam_each, continuation=continuation,
               soft_tol=soft_tol, progress=progress)
    return solve(problem, lam, solver=solver, accuracy=accuracy, verify=verify, options=options,
                 verbose=verbose, fallback=fallback, sequential=seq)
