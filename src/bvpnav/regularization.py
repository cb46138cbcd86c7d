"""Choosing the regularization weight lambda: L-curve, GCV, discrepancy, quasi-optimality.

The objective of a :class:`~bvpnav.NavigationProblem` splits as

.. math:: J(\\lambda) = \\hat\\rho(x) + \\lambda\\, \\hat\\eta(x),

where :math:`\\hat\\rho` is the sum of squares of every term *not* multiplied by lambda
(the data term, error-model priors) and :math:`\\hat\\eta` the sum of squares of the
lambda-weighted items. Every rule looks at the curve :math:`\\lambda \\mapsto
(\\rho, \\eta) = (\\hat\\rho^{1/2}, \\hat\\eta^{1/2})`.

Two sweep engines:

- ``"direct"`` (problems that are equality-constrained least squares): one sparse
  factorization per lambda (:class:`bvpnav.kkt.BorderedLU`), the derivative
  :math:`dx/d\\lambda` from the same factorization, hence the L-curve curvature and the
  quasi-optimality function *exactly* at every lambda, refined with Brent's method; GCV's
  trace by exact columns for small problems and Hutchinson's randomized estimator
  (seeded Rademacher probes, one multi-right-hand-side solve) for large ones.
- ``"cvxpy"`` (robust, band or inequality items): the compiled DPP problem is re-solved
  with the user's solver for each lambda (no recompilation); curvature comes from a
  spline through the sampled points and the corner is refined by sampling more densely
  around it.
"""

from __future__ import annotations

import copy
import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.interpolate import CubicSpline
from scipy.optimize import minimize_scalar

from .errors import InputError
from .kkt import factor_form, least_squares_form, non_least_squares_term

__all__ = ["RULES", "LambdaCurve", "lambda_curve", "choose_lambda", "solve_with_rule"]

RULES = ("lcurve", "gcv", "discrepancy", "quasi")


@dataclass
class LambdaCurve:
    """A lambda sweep and the rules' choices.

    Attributes
    ----------
    lam : ndarray
        Sampled lambda values (dimensionless), increasing.
    residual_norm : ndarray
        :math:`\\rho(\\lambda)`, square root of the terms not weighted by lambda
        (data term in its own units, e.g. dimensionless for the acceleration form
        with ``sigma_a``, m/s for the load form).
    info_norm : ndarray
        :math:`\\eta(\\lambda)`, square root of the lambda-weighted item terms.
    scores : dict of str -> ndarray
        Per rule, its score at each sampled lambda (curvature for ``lcurve``, the GCV
        function, the discrepancy ``rho^2 - tau * dof`` and the quasi-optimality
        function ``||lambda dr/dlambda||`` in m); NaN where not computed.
    chosen : dict of str -> float
        Per rule, the chosen lambda (after refinement).
    rule : str
        The rule whose choice was used.
    engine : str
        ``"direct"`` or ``"cvxpy"``.
    warnings : list of str
        E.g. a corner at the edge of the range.
    """

    lam: np.ndarray
    residual_norm: np.ndarray
    info_norm: np.ndarray
    scores: dict = field(default_factory=dict)
    chosen: dict = field(default_factory=dict)
    rule: str = "lcurve"
    engine: str = "direct"
    warnings: list = field(default_factory=list)
    evaluations: int = 0
    seconds: float = 0.0

    @property
    def lam_chosen(self) -> float:
        """The lambda of :attr:`rule`."""
        return self.chosen[self.rule]

    def to_frame(self) -> pd.DataFrame:
        """One row per sampled lambda: lam, residual_norm, info_norm and one column per score."""
        df = pd.DataFrame({"lam": self.lam, "residual_norm": self.residual_norm,
                           "info_norm": self.info_norm})
        for k, v in self.scores.items():
            df[k] = v
        return df

    def plot(self, ax=None):
        """L-curve with every rule's choice marked (see :func:`bvpnav.plot.lcurve`)."""
        from .plot import lcurve

        return lcurve(self, ax=ax)


# ----------------------------------------------------------------- engines
class _DirectSweep:
    """Exact per-lambda evaluation for least-squares problems."""

    engine = "direct"

    def __init__(self, problem, exact_trace_limit: int = 300):
        self.problem = problem
        self.exact_trace_limit = exact_trace_limit
        self.model = problem.model
        self.terms = problem.terms()
        self.lam_terms = [t for t in self.terms if t.mode == "soft" and t.scaled_by_lam]
        self.fixed_terms = [t for t in self.terms if t.mode == "soft" and not t.scaled_by_lam]
        self.data = problem.data_rows()
        self.cache: dict[float, dict] = {}
        self._rhs_jac = None
        self._probe_rhs = None

    def point(self, lam: float, need_trace: bool = False, probes: int = 24, seed: int = 0) -> dict:
        key = float(lam)
        pt = self.cache.get(key)
        if pt is not None and (not need_trace or "trace" in pt):
            return pt
        form = least_squares_form(self.problem, lam)
        m, n = form.D.A.shape
        try:
            fac = factor_form(form, self.problem)
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            raise InputError(f"lambda={lam:g}: the KKT matrix is singular ({exc}); some unknown is "
                             "not determined by the information") from exc
        z, _, _ = fac.refined(form.rhs(), 2, 1e-14, window=slice(m, m + n))
        x = z[m:m + n]
        scaled = [t.residual.value(x) / t.sigma for t in self.lam_terms]  # S (A x + c)
        rho2 = float(np.sum(self.data.value(x) ** 2))
        rho2 += sum(float(np.sum((t.residual.value(x) / t.sigma) ** 2)) for t in self.fixed_terms)
        eta2 = sum(float(np.sum(r**2)) for r in scaled)
        # dx/dlam from the same factorization: H x' + E^T mu' = -sum A^T S^2 (A x + c)
        g = np.zeros(n)
        for t, r in zip(self.lam_terms, scaled, strict=True):
            g -= t.residual.A.T @ (r / t.sigma)
        rhs = np.concatenate([np.zeros(m), g, np.zeros(form.E.m)])
        dz, _, _ = fac.refined(rhs, 1, window=slice(m, m + n))
        dx = dz[m:m + n]
        deta2 = sum(2.0 * float(np.sum(r * ((t.residual.A @ dx) / t.sigma)))
                    for t, r in zip(self.lam_terms, scaled, strict=True))
        pos = np.concatenate([self.model.r_index(a) for a in range(self.model.d)])
        pt = {"lam": key, "rho2": rho2, "eta2": eta2, "deta2": deta2, "x": x,
              "quasi": float(np.linalg.norm(lam * dx[pos]) / math.sqrt(pos.size))}
        if need_trace:
            pt["trace"] = self._trace(form, fac, lam, probes, seed)
        self.cache[key] = pt
        return pt

    # --- GCV's trace: d w / d a_hat
    def _rhs_jacobian_apply(self, Z: np.ndarray) -> np.ndarray:
        """Change of the augmented right-hand side (at lambda = 1) when the measured
        accelerations change by ``Z`` (N, d); the form is affine in the data."""
        def rhs_for(acc):
            p2 = copy.copy(self.problem)
            p2._model, p2._terms, p2._cvx = self.model.with_acc(acc), None, None
            return least_squares_form(p2, 1.0).rhs()

        if self._rhs_jac is None:
            self._rhs_jac = rhs_for(np.zeros_like(self.problem.data.acc))
        return rhs_for(Z) - self._rhs_jac

    def _trace(self, form, fac, lam, probes, seed) -> float:
        N, d = self.model.N, self.model.d
        m, n = form.D.A.shape
        widx = np.concatenate([self.model.w_index(a) for a in range(d)])  # axis-major like Z.T
        lam_rows = form.lam_rows
        exact = N * d <= self.exact_trace_limit
        if exact:
            Zs = [np.eye(N * d)[:, k].reshape(d, N).T for k in range(N * d)]
        else:
            rng = np.random.default_rng(seed)
            Zs = [rng.choice([-1.0, 1.0], size=(N, d)) for _ in range(probes)]
        if self._probe_rhs is None or self._probe_rhs[0] != (exact, probes, seed):
            self._probe_rhs = ((exact, probes, seed), Zs,
                               np.column_stack([self._rhs_jacobian_apply(Z) for Z in Zs]))
        Zs, R = self._probe_rhs[1], self._probe_rhs[2].copy()
        R[:m][lam_rows] *= math.sqrt(lam)
        dW = fac.solve(R)[m:m + n][widx]
        vals = np.array([float(Z.T.ravel() @ dW[:, k]) for k, Z in enumerate(Zs)])
        return float(vals.sum()) if exact else float(vals.mean())


class _CvxpySweep:
    """Re-solves the compiled DPP problem for each lambda."""

    engine = "cvxpy"

    def __init__(self, problem, solver, accuracy, options, solve_kw=None):
        self.problem = problem
        self.solve_kw = dict(solve_kw or {}, solver=solver, accuracy=accuracy, options=options)
        self.cache: dict[float, dict] = {}

    def point(self, lam: float, need_trace: bool = False, **_) -> dict:
        key = float(lam)
        if key in self.cache:
            return self.cache[key]
        sol = self.problem.solve(lam=key, **self.solve_kw)
        cvx = self.problem.build()
        x = sol.x
        rho2 = float(np.sum(self.problem.data_rows().value(x) ** 2))
        eta2 = 0.0
        for term, pen in cvx["penalties"]:
            v = float(pen.value) if pen.value is not None else np.nan
            if term.scaled_by_lam:
                eta2 += v
            else:
                rho2 += v
        pt = {"lam": key, "rho2": rho2, "eta2": eta2, "x": x}
        self.cache[key] = pt
        return pt


# ------------------------------------------------------------------- rules
def _curvature(pt: dict) -> float:
    """Signed curvature of :math:`(\\log\\rho, \\log\\eta)` at one lambda from exact derivatives.

    Notes
    -----
    With :math:`\\hat\\rho = \\rho^2`, :math:`\\hat\\eta = \\eta^2`, the stationarity of
    :math:`J = \\hat\\rho + \\lambda\\hat\\eta` along the solution path gives
    :math:`\\hat\\rho' = -\\lambda\\hat\\eta'`, and the second derivatives cancel from the
    curvature :math:`(\\zeta'\\eta'' - \\zeta''\\eta')/(\\zeta'^2 + \\eta'^2)^{3/2}` of
    :math:`(\\zeta, \\eta) = (\\tfrac12\\log\\hat\\rho, \\tfrac12\\log\\hat\\eta)`:

    .. math:: \\kappa = \\frac{2}{\\hat\\rho\\hat\\eta\\,|\\hat\\eta'|}
        \\frac{1 + \\lambda\\hat\\eta'/\\hat\\eta + \\lambda^2\\hat\\eta'/\\hat\\rho}
             {(\\lambda^2/\\hat\\rho^2 + 1/\\hat\\eta^2)^{3/2}}.

    Positive where the curve, traversed with increasing lambda, turns counter-clockwise
    (the 2011 paper's sign convention, its equation 17).
    """
    lam, r, e, de = pt["lam"], pt["rho2"], pt["eta2"], pt["deta2"]
    if de == 0 or r <= 0 or e <= 0:
        return 0.0
    return float(2.0 / (r * e * abs(de)) * (1.0 + lam * de / e + lam**2 * de / r)
                 / (lam**2 / r**2 + 1.0 / e**2) ** 1.5)


def _spline_curvature(s: np.ndarray, rho2: np.ndarray, eta2: np.ndarray, s_eval: np.ndarray):
    """Curvature of (log rho, log eta) from cubic splines in s = log lambda."""
    zeta = CubicSpline(s, 0.5 * np.log(rho2))
    eta = CubicSpline(s, 0.5 * np.log(eta2))
    z1, z2 = zeta(s_eval, 1), zeta(s_eval, 2)
    e1, e2 = eta(s_eval, 1), eta(s_eval, 2)
    # sign: positive at the corner of an L traversed with rho increasing
    return (z1 * e2 - z2 * e1) / np.maximum((z1**2 + e1**2) ** 1.5, 1e-300)


def _gcv(pt: dict) -> float:
    dof = abs(pt["trace"])
    return pt["rho2"] / dof**2 if dof > 0 else np.inf


def _sweep(engine, lams, need_trace, progress, probes, seed):
    from tqdm.auto import tqdm

    pts = []
    for lam in tqdm(lams, desc="lambda sweep", disable=not progress, leave=False):
        pts.append(engine.point(lam, need_trace=need_trace, probes=probes, seed=seed))
    return pts


def lambda_curve(problem, rules=RULES, rule: str = "lcurve", lam_range=(1e-6, 1e6), points: int = 25,
                 solver: str = "clarabel", accuracy: str = "default", options=None,
                 tau: float = 1.5, probes: int = 24, seed: int = 0, progress=None,
                 engine: str = "auto", solve_kw: dict | None = None) -> LambdaCurve:
    """Sweep lambda and apply the selection rules.

    Parameters
    ----------
    problem : NavigationProblem
        Must have at least one soft item weighted by lambda.
    rules : sequence of str
        Rules to evaluate (subset of :data:`RULES`); ``rule`` is always included.
    rule : str
        The rule whose choice is reported as :attr:`LambdaCurve.lam_chosen`.
    lam_range : (float, float)
        Search interval for lambda (dimensionless), log-spaced.
    points : int
        Coarse sweep size; every rule is then refined inside its best bracket.
    solver, accuracy, options
        For the ``cvxpy`` engine (non-least-squares problems).
    tau : float
        Discrepancy safety factor: choose lambda with :math:`\\hat\\rho = \\tau\\,
        \\mathrm{tr}(I - A_\\lambda)` (the data residual's expected size given the stated
        noise, only meaningful for ``residual="acceleration"`` with ``sigma_a`` given).
    probes : int
        Hutchinson probes for GCV's trace when the problem has more than 300 samples x axes
        (below that the trace is exact).
    seed : int
        Seed of the probes (results are reproducible).
    progress : bool, optional
        Show a tqdm bar; default: when the problem is large (more than 50,000 unknowns).
    engine : {"auto", "direct", "cvxpy"}
    solve_kw : dict, optional
        Further options of :meth:`bvpnav.NavigationProblem.solve` (``verify``,
        ``fallback``, ``verbose``) for the ``cvxpy`` engine's solves.

    Returns
    -------
    LambdaCurve

    Notes
    -----
    L-curve: maximise the curvature of :math:`(\\log\\rho, \\log\\eta)`; the two
    outermost sweep points on each side are never chosen (a "corner" there is the range
    ending, and is reported in ``warnings``). GCV: minimise
    :math:`G = \\hat\\rho / \\mathrm{tr}(I - A_\\lambda)^2`, with
    :math:`\\mathrm{tr}(I - A_\\lambda) = -\\mathrm{tr}(\\partial w / \\partial \\hat a)`.
    Quasi-optimality: minimise :math:`\\|\\lambda\\, dr/d\\lambda\\|`.
    """
    import time

    t0 = time.perf_counter()
    rules = list(dict.fromkeys([rule, *rules]))
    for r in rules:
        if r not in RULES:
            raise InputError(f"lam rule {r!r} is not known; choose one of {list(RULES)} or a number")
    if not problem.has_soft_terms:
        raise InputError("choosing lambda needs at least one soft (or robust) item weighted by lambda; "
                         "every item is hard, so lambda has no effect: pass a number (e.g. lam=1)")
    from .problem import LAM_RANGE

    try:
        lo, hi = (float(v) for v in lam_range)
    except (TypeError, ValueError):
        raise InputError(f"lam_range={lam_range!r}: give two numbers (low, high), e.g. "
                         "lam_range=(1e-6, 1e6)") from None
    if not (0 < lo < hi and np.isfinite(hi)):
        raise InputError(f"lam_range={lam_range!r}: need 0 < low < high")
    if lo < LAM_RANGE[0] or hi > LAM_RANGE[1]:
        raise InputError(
            f"lam_range={lam_range!r} reaches beyond {LAM_RANGE[0]:g}..{LAM_RANGE[1]:g}, the lambdas "
            "double precision can weigh against the data term; sweep inside it (the default "
            "is (1e-6, 1e6))")
    if isinstance(points, bool) or not isinstance(points, int | np.integer) or points < 7:
        raise InputError(f"points={points!r}: the sweep needs an integer of at least 7 points")
    if points > 1000:
        raise InputError(f"points={points}: at most 1000 sweep points (each is one solve); the "
                         "corner is refined by Brent's method anyway, 25 is the default")
    ls = non_least_squares_term(problem) is None
    if engine == "auto":
        engine = "direct" if ls else "cvxpy"
    if engine == "direct" and not ls:
        raise InputError("engine='direct' needs a least-squares problem (no band, robust or "
                         "inequality items); use engine='cvxpy'")
    if engine == "cvxpy":
        for r in ("gcv", "discrepancy"):
            if r in rules:
                if r == rule:
                    raise InputError(f"lam={r!r} needs a linear least-squares problem (hard and soft "
                                     "items only); this one has robust, band or inequality items. "
                                     "Use lam='lcurve' or 'quasi'.")
                rules.remove(r)
    if "discrepancy" in rules and (problem.residual != "acceleration" or not problem._sigma_a_given):
        if rule == "discrepancy":
            raise InputError("lam='discrepancy' needs the noise level: use residual='acceleration' "
                             "with sigma_a=<accelerometer noise, m/s^2>")
        rules.remove("discrepancy")
    problem.check_scales(lo)  # the sweep's extremes: every weight stays resolvable
    problem.check_scales(hi)
    problem.check_observability()
    if engine == "direct":
        from .solvers import check_memory, resolve_solver

        check_memory(problem, resolve_solver("direct"))
    if progress is None:
        progress = problem.model.size > 50_000
    eng = _DirectSweep(problem) if engine == "direct" else _CvxpySweep(problem, solver, accuracy,
                                                                        options, solve_kw)
    need_trace = any(r in rules for r in ("gcv", "discrepancy"))
    lams = np.geomspace(lo, hi, points)
    pts = _sweep(eng, lams, need_trace, progress, probes, seed)
    curve = LambdaCurve(lam=lams, residual_norm=np.sqrt([p["rho2"] for p in pts]),
                        info_norm=np.sqrt([p["eta2"] for p in pts]), rule=rule, engine=eng.engine)
    s = np.log(lams)

    def point(lam_):
        return eng.point(float(lam_), need_trace=need_trace, probes=probes, seed=seed)

    def bracket(k):
        return s[max(k - 1, 0)], s[min(k + 1, len(s) - 1)]

    def edge_warn(name, k, guard):
        if k <= guard or k >= len(s) - 1 - guard:
            curve.warnings.append(
                f"{name}: the best value lies at the edge of lam_range={lam_range} "
                f"(lam={lams[k]:.3g}); widen the range")

    if "lcurve" in rules:
        if eng.engine == "direct":
            kap = np.array([_curvature(p) for p in pts])
        else:
            kap = _spline_curvature(s, [p["rho2"] for p in pts], [p["eta2"] for p in pts], s)
        curve.scores["lcurve"] = kap
        inner = np.arange(2, len(s) - 2)
        k = int(inner[np.argmax(kap[inner])])
        edge_warn("lcurve", k, 2)
        if kap[k] <= 0:
            curve.warnings.append("lcurve: the curve has no convex corner in the range")
        a, b = bracket(k)
        if eng.engine == "direct":
            res = minimize_scalar(lambda u: -_curvature(point(math.exp(u))), bounds=(a, b),
                                  method="bounded", options={"xatol": 1e-3})
            curve.chosen["lcurve"] = float(math.exp(res.x))
        else:
            fine = np.linspace(a, b, 9)[1:-1]
            for u in fine[np.abs(fine - s[k]) > 1e-6]:
                point(math.exp(u))
            keys = np.array(sorted(eng.cache))
            keys = keys[np.concatenate([[True], np.diff(np.log(keys)) > 1e-9])]
            ss = np.log(keys)
            dense = np.linspace(a, b, 401)
            kd = _spline_curvature(ss, [eng.cache[q]["rho2"] for q in keys],
                                   [eng.cache[q]["eta2"] for q in keys], dense)
            curve.chosen["lcurve"] = float(math.exp(dense[np.argmax(kd)]))
    if "gcv" in rules:
        g = np.array([_gcv(p) for p in pts])
        curve.scores["gcv"] = g
        k = int(np.argmin(g))
        edge_warn("gcv", k, 0)
        a, b = bracket(k)
        res = minimize_scalar(lambda u: _gcv(point(math.exp(u))), bounds=(a, b), method="bounded",
                              options={"xatol": 1e-3})
        curve.chosen["gcv"] = float(math.exp(res.x))
    if "discrepancy" in rules:
        disc = np.array([p["rho2"] - tau * abs(p["trace"]) for p in pts])
        curve.scores["discrepancy"] = disc
        sign = np.sign(disc)
        cross = np.nonzero(sign[:-1] * sign[1:] < 0)[0]
        if cross.size == 0:
            curve.warnings.append("discrepancy: the residual never matches the stated noise in the "
                                  "range (is sigma_a right?); taking the closest point")
            k = int(np.argmin(np.abs(disc)))
            curve.chosen["discrepancy"] = float(lams[k])
        else:
            k = int(cross[-1])
            from scipy.optimize import brentq

            def f(u):
                p = point(math.exp(u))
                return p["rho2"] - tau * abs(p["trace"])

            curve.chosen["discrepancy"] = float(math.exp(brentq(f, s[k], s[k + 1], xtol=1e-4)))
    if "quasi" in rules:
        if eng.engine == "direct":
            q = np.array([p["quasi"] for p in pts])
        else:
            xs = np.array([p["x"] for p in pts])
            pos = np.concatenate([problem.model.r_index(a) for a in range(problem.model.d)])
            dxs = np.gradient(xs[:, pos], s, axis=0)
            q = np.linalg.norm(dxs, axis=1) / math.sqrt(pos.size)
        curve.scores["quasi"] = q
        # the smallest interior local minimum (q -> 0 at both ends of any range)
        loc = [k for k in range(1, len(s) - 1) if q[k] < q[k - 1] and q[k] <= q[k + 1]]
        if not loc:
            curve.warnings.append("quasi: no interior local minimum in lam_range; widen the range")
            loc = [int(np.argmin(q[1:-1])) + 1]
        k = min(loc, key=lambda j: q[j])
        if eng.engine == "direct":
            a, b = bracket(k)
            res = minimize_scalar(lambda u: point(math.exp(u))["quasi"], bounds=(a, b),
                                  method="bounded", options={"xatol": 1e-3})
            curve.chosen["quasi"] = float(math.exp(res.x))
        else:
            curve.chosen["quasi"] = float(lams[k])
    curve.evaluations = len(eng.cache)
    curve.seconds = time.perf_counter() - t0
    for w in curve.warnings:
        warnings.warn(w, RuntimeWarning, stacklevel=2)
    return curve


def choose_lambda(problem, rule: str = "lcurve", **kwargs) -> float:
    """The lambda a rule chooses (see :func:`lambda_curve` for the options)."""
    return lambda_curve(problem, rules=(rule,), rule=rule, **kwargs).lam_chosen


def solve_with_rule(problem, rule: str, solver: str = "clarabel", accuracy: str = "default",
                    options=None, verify: bool = True, verbose: bool = False, fallback="auto",
                    **kwargs):
    """Choose lambda by ``rule``, then solve with ``solver`` at that lambda.

    Every solve option (``solver``, ``accuracy``, ``options``, ``verify``, ``verbose``,
    ``fallback``; see :meth:`bvpnav.NavigationProblem.solve`) reaches the final solve and
    the sweep's solves (``cvxpy`` engine). The returned :class:`~bvpnav.Solution` carries
    ``lam_rule`` and the whole :class:`LambdaCurve` in ``solution.curve``.
    """
    solve_kw = dict(solver=solver, accuracy=accuracy, options=options, verify=verify,
                    verbose=verbose, fallback=fallback)
    curve = lambda_curve(problem, rules=(rule,), rule=rule, solver=solver, accuracy=accuracy,
                         options=options, solve_kw=solve_kw, **kwargs)
    sol = problem.solve(lam=curve.lam_chosen, **solve_kw)
    sol.lam_rule = rule
    sol.curve = curve
    sol.warnings.extend(curve.warnings)
    return sol
