"""The lambda-rule stage: choose ``lam`` by a rule, then hand a fixed ``lam`` inward.

When ``lam`` is a rule name, the sweep (:func:`bvpnav.lam.sweep.sweep_curve`) runs with
the *inner* stage as its fixed-lambda solve (cvxpy engine) and the chosen lambda is then
solved by the inner stage with the same options; the :class:`~bvpnav.Solution` carries
``lam_rule`` and the whole :class:`~bvpnav.lam.sweep.LambdaCurve` in ``solution.curve``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from ..backends import check_memory, resolve_solver
from ..errors import InputError
from ..formulation import Formulation, as_formulation
from ..lam import rule_names
from ..lam.sweep import LambdaCurve, sweep_curve
from ..linalg.workspace import Workspace
from ..result import Solution
from .chain import solve_fixed
from .options import SolveOptions, prepare

__all__ = ["with_rule", "lambda_curve", "choose_lambda"]

Stage = Callable[..., Solution]

log = logging.getLogger(__name__)


def _curve(form: Formulation, rule: str, opts: SolveOptions, inner: Stage, workspace: Workspace,
           rules=None, **sweep) -> LambdaCurve:
    direct = resolve_solver("direct")
    return sweep_curve(form, rules=(rule,) if rules is None else rules, rule=rule,
                       solve_at=lambda lam: inner(form, lam, opts, workspace=workspace),
                       check_memory=lambda: check_memory(form, direct), workspace=workspace,
                       **{**opts.rule, **sweep})


def with_rule(inner: Stage) -> Stage:
    """The stage that resolves a rule name in ``lam`` before calling ``inner`` (the
    fixed-lambda stage, :func:`~bvpnav.solve.chain.solve_fixed`), with one workspace for
    the sweep and the solve at its choice (which takes the sweep's band or factor there)."""

    def stage(form: Formulation, lam, opts: SolveOptions, workspace: Workspace | None = None) -> Solution:
        if not isinstance(lam, str):
            kw = {} if workspace is None else {"workspace": workspace}
            return inner(form, lam, opts, **kw)
        workspace = Workspace() if workspace is None else workspace
        try:
            curve = _curve(form, lam, opts, inner, workspace)
            log.info("rule %s chose lam=%.6g (engine %s, %d evaluations, %.3g s); solving at it", lam,
                     curve.lam_chosen, curve.engine, curve.evaluations, curve.seconds)
            sol = inner(form, curve.lam_chosen, opts, workspace=workspace)
        finally:
            # the sweep's band along lambda served the solve at the chosen lambda
            workspace.drop_sweep_bands()
        sol.lam_rule = lam
        sol.curve = curve
        # already issued by the sweep (once); recorded here for the CLI and the JSON summary
        sol.warnings.extend(w for w in curve.warnings if w not in sol.warnings)
        return sol

    return stage


def lambda_curve(problem, rules=None, rule: str = "lcurve", lam_range=(1e-6, 1e6), points: int | None = None,
                 solver: str = "clarabel", accuracy: str = "default", options=None, tau: float = 1.5,
                 probes: int = 24, seed: int = 0, progress=None, engine: str = "auto",
                 solve_kw: dict | None = None) -> LambdaCurve:
    r"""Sweep lambda and apply the selection rules.

    Parameters
    ----------
    problem : NavigationProblem or Formulation
        Must have at least one soft item weighted by lambda.
    rules : sequence of str, optional
        Rules to evaluate (default every registered rule, :func:`bvpnav.lam.rule_names`);
        ``rule`` is always included.
    rule : str
        The rule whose choice is reported as :attr:`LambdaCurve.lam_chosen`.
    lam_range : (float, float)
        Search interval for lambda (dimensionless), log-spaced.
    points : int, optional
        Coarse sweep size; every rule is then refined inside its best bracket. Default: the
        sweep ``solve(lam=rule)`` runs (:func:`bvpnav.lam.sweep.sweep_curve`), so that both
        choose the same lambda; more points draw a denser curve.
    solver, accuracy, options
        For the ``cvxpy`` engine (non-least-squares problems).
    tau : float
        Discrepancy safety factor: choose lambda with :math:`\hat\rho = \tau\,
        \mathrm{tr}(I - A_\lambda)` (the data residual's expected size given the stated
        noise, only meaningful for ``residual="acceleration"`` with ``sigma_a`` given).
    probes : int
        Hutchinson probes for GCV's trace when the problem has more than 300 samples x axes
        (below that the trace is exact).
    seed : int
        Seed of the probes (results are reproducible).
    progress : bool, optional
        Show a tqdm bar (True always, False never); default: when stderr is a terminal (never
        in pipes, files or tests; see :func:`bvpnav.log.progress_enabled`).
    engine : {"auto", "direct", "cvxpy"}
    solve_kw : dict, optional
        Further options of :meth:`bvpnav.NavigationProblem.solve` (``verify``,
        ``fallback``, ``verbose``) for the ``cvxpy`` engine's solves.

    Returns
    -------
    LambdaCurve
        Its ``warnings`` (e.g. a rule's best value at the edge of ``lam_range``) are each
        issued once through :mod:`warnings` as :class:`bvpnav.log.BvpnavWarning`, reported
        at the caller's line.

    Notes
    -----
    Rules that cannot run on this problem are skipped (logged at INFO on
    ``bvpnav.lam.sweep``), e.g. ``gcv`` in the load form or ``discrepancy`` without
    ``sigma_a``; the chosen rule itself must run, or :class:`~bvpnav.InputError` says why.
    L-curve: maximise the curvature of :math:`(\log\rho, \log\eta)` (the 2011 paper's
    sign: the convex corner); with the direct sweep every sample may be chosen, the
    range's ends included (the curvature and its slope are exact there), and a best value
    at an end whose slope still rises out of the range is reported in ``warnings``; the
    cvxpy sweep's spline never chooses its two outermost samples on each side (end
    effects). GCV: minimise
    :math:`G = \hat\rho / \mathrm{tr}(I - A_\lambda)^2`, with
    :math:`\mathrm{tr}(I - A_\lambda) = -\mathrm{tr}(\partial w / \partial \hat a)`.
    Quasi-optimality: minimise :math:`\|\lambda\, dr/d\lambda\|`.

    Examples
    --------
    A noisy accelerometer (0.05 m/s^2) and ten soft position fixes (0.01 m) of the motion
    :math:`r = 0.5 \sin t` m; three rules on nine lambdas:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> rng = np.random.default_rng(0)
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> acc = -0.5 * np.sin(t) + 0.05 * rng.standard_normal(t.size)  # truth r = 0.5 sin t (m)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=0.05)
    >>> tk = t[::10]
    >>> fixes = Position(t=tk, value=0.5 * np.sin(tk) + 0.01 * rng.standard_normal(tk.size), sigma=0.01)
    >>> prob = prob.add(fixes)
    >>> curve = bvpnav.lambda_curve(prob, rules=["gcv", "discrepancy", "lcurve"], rule="gcv",
    ...                             lam_range=(1e-3, 1e3), points=9)
    >>> print(f"gcv chose lam = {curve.lam_chosen:.1f}")
    gcv chose lam = 1.3
    >>> sol = prob.solve(lam=curve.lam_chosen, solver="direct")
    >>> rms = np.sqrt(np.mean((sol.position("x") - 0.5 * np.sin(t)) ** 2))
    >>> print(f"position error {rms:.3f} m")
    position error 0.006 m
    """
    form = as_formulation(problem)
    extra = dict(solve_kw or {})
    ignored = sorted(set(extra) - {"verify", "fallback", "verbose", "solver", "accuracy", "options"})
    if ignored:
        raise InputError(f"solve_kw: {ignored} do not apply to the sweep's fixed-lambda solves; it "
                         "takes 'verify', 'fallback' and 'verbose' (and solver, accuracy, options)")
    extra.update(solver=solver, accuracy=accuracy, options=options)  # the explicit ones win
    opts, _ = prepare(1.0, **extra)
    return _curve(form, rule, opts, solve_fixed, Workspace(), rules=rule_names() if rules is None else rules,
                  lam_range=lam_range, points=points,
                  tau=tau, probes=probes, seed=seed, progress=progress, engine=engine)


def choose_lambda(problem, rule: str = "lcurve", **kwargs) -> float:
    """The lambda a rule chooses (see :func:`lambda_curve` for the options).

    Examples
    --------
    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> rng = np.random.default_rng(0)
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> acc = -0.5 * np.sin(t) + 0.05 * rng.standard_normal(t.size)  # truth r = 0.5 sin t (m)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=0.05)
    >>> tk = t[::10]
    >>> fixes = Position(t=tk, value=0.5 * np.sin(tk) + 0.01 * rng.standard_normal(tk.size), sigma=0.01)
    >>> prob = prob.add(fixes)
    >>> lam = bvpnav.solve.choose_lambda(prob, rule="gcv", lam_range=(1e-3, 1e3), points=9)
    >>> print(f"{lam:.1f}")
    1.3
    """
    return lambda_curve(problem, rules=(rule,), rule=rule, **kwargs).lam_chosen
