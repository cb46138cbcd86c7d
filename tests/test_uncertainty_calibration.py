"""Calibration and reference tests of ``solve(uncertainty=True)``.

Two kinds of evidence that the standard deviations are right:

- **Monte Carlo calibration.** The truth is generated from the very model bvpnav
  estimates (nodal residuals ``w* ~ N(0, sigma_a^2)``, parameters ``l*`` fixed or drawn
  from the stated prior, the exact FEM recurrence, soft item values = truth +
  N(0, sigma^2) noise, hard values = truth), so the error ``x_hat - x*`` is exactly
  N(0, Cov) and the fractions of errors within 1 and 2 standard deviations must be 0.683
  and 0.954. Configurations: 1-D hard items only, soft only, mixed (``Bias()``), 3-D mixed
  (``Bias() + ScaleFactor()``). 200 realisations per configuration go through the public
  ``solve(solver="direct", uncertainty=True)``; 3000 (the first 200 of them the same)
  through a fast path that solves the same equality-constrained least squares for all
  right-hand sides with one factorization. The fast path is checked to be the public
  estimator (to 1e-9 against an LU solve, and to the default solve's own accuracy on all
  200 public realisations), and the public standard deviations are data independent, so
  the 3000-realisation fractions are those of the public output.
- **RTS reference.** For the same information and noise a Kalman filter plus
  Rauch-Tung-Striebel smoother (written here, covariance form) is the same estimator;
  its smoothed means and standard deviations must equal bvpnav's.

Tolerances (the issue's, never looser) and why the asserted ones are not knife-edge
(binomial standard errors for ``n`` independent samples):

- 1 sigma, +/- 0.03: ``sqrt(0.683 * 0.317 / n)`` = 0.033 at n = 200, 0.0085 at n = 3000,
  i.e. the tolerance is 0.9 resp. 3.5 standard errors;
- 2 sigma, +/- 0.015: ``sqrt(0.954 * 0.046 / n)`` = 0.0148 at n = 200, 0.0038 at n = 3000,
  i.e. 1.0 resp. 3.9 standard errors.

So the fractions are asserted on 3000 realisations (the issue asks for "at least 200"): at
200 a correct implementation fails them by chance for a sizeable share of seeds (about
37 % per parameter at 1 sigma). Pooled positions and velocities have fewer effectively
independent samples than their count (errors along one trajectory are correlated); their
standard error is estimated from the spread of the per-realisation fractions, and the
test asserts that each tolerance is at least 3 of them. On the 200 public realisations
the mean squared standardized error is asserted instead (1 within 3.5 standard errors).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pytest
import scipy.linalg as sla
from _helpers import load_benchmark_module

import bvpnav as bv
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import Bias
from bvpnav.linalg.covariance import posterior
from bvpnav.linalg.lsq import least_squares_form
from bvpnav.log import BvpnavWarning
from bvpnav.solve.uncertainty import param_jacobian

pytestmark = pytest.mark.slow  # Monte Carlo runs

P1, P2 = 0.6826894921370859, 0.9544997361036416  # P(|Z| <= 1), P(|Z| <= 2)
TOL1, TOL2 = 0.03, 0.015  # the tolerances, never looser
PUBLIC_RUNS = 200
FAST_RUNS = 3000

# The Monte Carlo model (configurations, exact FEM recurrence, truth, problem, public solve,
# reported parameters, hard nodes) is defined once, in examples/benchmarks/_calibration.py, which the
# benchmark examples/benchmarks/uncertainty_calibration.py uses too.
_model = load_benchmark_module("_calibration")
Config, Truth = _model.Config, _model.Truth
configs, model_of, integrate, simulate = _model.configs, _model.model_of, _model.integrate, _model.simulate
problem, solve_public, reported = _model.problem, _model.solve_public, _model.reported
hard_nodes = _model.hard_nodes


# ------------------------------------------------------------------------------ fast path
class FastEstimator:
    """The same estimator as ``solve(solver="direct", lam=1)``, for many realisations.

    The problem is ``min ||D x + c||^2 s.t. E x + e = 0`` (:func:`bvpnav.linalg.lsq.least_squares_form`)
    with ``D``, ``E`` independent of the item values and ``c``, ``e`` affine in them; their
    derivative is taken from forms built at unit values (exact for affine maps). The
    augmented system ``[[-I, D, 0], [D^T, 0, E^T], [0, E, 0]]`` is factorized once (dense
    LU) and solved for all right-hand sides.
    """

    def __init__(self, cfg: Config):
        self.cfg = cfg
        shapes = [(len(it.t), cfg.d if it.axes is None else len(it.axes)) for it in cfg.items]
        sizes = [a * b for a, b in shapes]
        zero = [np.zeros(s) for s in shapes]
        p0 = problem(cfg, zero)
        self.model = p0.formulation.model
        ls0 = least_squares_form(p0.formulation, 1.0)
        D, E = ls0.D.A.toarray(), ls0.E.A.toarray()
        self.D, self.c0, self.e0 = D, ls0.D.c, ls0.E.c
        dc, de = [], []
        for i, size in enumerate(sizes):
            for k in range(size):
                vals = [z.copy() for z in zero]
                vals[i].reshape(-1)[k] = 1.0
                ls = least_squares_form(problem(cfg, vals).formulation, 1.0)
                assert np.array_equal(ls.D.A.toarray(), D) and np.array_equal(ls.E.A.toarray(), E)
                dc.append(ls.D.c - self.c0)
                de.append(ls.E.c - self.e0)
        self.dc, self.de = np.column_stack(dc), np.column_stack(de)
        m, n = D.shape
        p = E.shape[0]
        self.m, self.n, self.p = m, n, p
        K = np.block([[-np.eye(m), D, np.zeros((m, p))],
                      [D.T, np.zeros((n, n)), E.T],
                      [np.zeros((p, m)), E, np.zeros((p, p))]])
        self.lu = sla.lu_factor(K)
        self.dof = m - n + p

    def solve(self, values: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """Estimates for stacked values (each (R, len(t), d_item)).

        Returns
        -------
        x : ndarray, shape (R, n)
        vf : ndarray, shape (R,)
            Variance factors ``||D x + c||^2 / dof``.
        """
        y = np.hstack([v.reshape(v.shape[0], -1) for v in values])  # (R, k)
        c = self.c0[:, None] + self.dc @ y.T
        e = self.e0[:, None] + self.de @ y.T
        rhs = np.vstack([-c, np.zeros((self.n, y.shape[0])), -e])
        sol = sla.lu_solve(self.lu, rhs)
        x = sol[self.m:self.m + self.n].T
        rho = x @ self.D.T + c.T
        return x, np.einsum("ri,ri->r", rho, rho) / self.dof

    def state(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nodal positions and velocities of estimates ``x`` (R, n), each (R, N, d)."""
        m = self.model
        r = np.stack([x[:, m.r_index(a)] for a in range(m.d)], axis=2)
        v = np.stack([(m.node_velocity(a).A @ x.T).T + m.node_velocity(a).c for a in range(m.d)], axis=2)
        return r, v


@dataclass
class Public:
    """Per-realisation outputs of the public ``solve(uncertainty=True)``."""

    x: np.ndarray
    r: np.ndarray
    v: np.ndarray
    r_std: np.ndarray
    v_std: np.ndarray
    params: np.ndarray
    params_std: np.ndarray
    vf: np.ndarray
    dof: int
    names: list[str]


def run_public(cfg: Config, truth: Truth, runs: int) -> Public:
    """Solve the first ``runs`` realisations through the public API."""
    xs, rs, vs, rss, vss, ps, pss, vfs = ([] for _ in range(8))
    dof, names = -1, []
    for k in range(runs):
        sol = solve_public(cfg, [v[k] for v in truth.values])
        tr = sol.trajectory
        xs.append(sol.x)
        rs.append(tr[list(cfg.axes)].to_numpy())
        vs.append(tr[[f"v{a}" for a in cfg.axes]].to_numpy())
        rss.append(tr[[f"{a}_std" for a in cfg.axes]].to_numpy())
        vss.append(tr[[f"v{a}_std" for a in cfg.axes]].to_numpy())
        ps.append(sol.error_params.to_numpy(dtype=float))
        pss.append(sol.error_params_std.to_numpy(dtype=float))
        unc = sol.stats["uncertainty"]
        assert unc["scale"] == "stated" and unc["model"] == "exact"
        vfs.append(unc["variance_factor"])
        dof, names = unc["dof"], list(sol.error_params.index)
    return Public(np.array(xs), np.array(rs), np.array(vs), np.array(rss), np.array(vss),
                  np.array(ps), np.array(pss), np.array(vfs), dof, names)


def fractions(err: np.ndarray, std: np.ndarray) -> tuple[float, float, float, float]:
    """Fractions within 1 and 2 std, pooled over all but the first axis, and their
    standard errors from the spread over the first axis (realisations, independent).

    Parameters
    ----------
    err, std : ndarray, shape (R, ...)
    """
    z = np.abs(err) / std
    R = z.shape[0]
    f1 = (z <= 1).reshape(R, -1).mean(axis=1)
    f2 = (z <= 2).reshape(R, -1).mean(axis=1)
    se = np.sqrt(R)
    return float(f1.mean()), float(f2.mean()), float(f1.std(ddof=1) / se), float(f2.std(ddof=1) / se)


# ---------------------------------------------------------------------- shared MC results
@dataclass
class MC:
    """Everything the calibration tests look at, for one configuration."""

    cfg: Config
    truth: Truth
    pub: Public
    fast: FastEstimator
    fx: np.ndarray
    fvf: np.ndarray


@pytest.fixture(scope="module", params=list(configs()))
def mc(request) -> MC:
    cfg = configs()[request.param]
    rng = np.random.default_rng([20261201, list(configs()).index(request.param)])
    truth = simulate(cfg, rng, FAST_RUNS)
    pub = run_public(cfg, truth, PUBLIC_RUNS)
    fast = FastEstimator(cfg)
    fx, fvf = fast.solve(truth.values)
    return MC(cfg, truth, pub, fast, fx, fvf)


# --------------------------------------------------------------------------------- tests
def test_truth_satisfies_the_fem_equations():
    """The recurrence truth is a point of bvpnav's model: FEM rows vanish, node
    velocities equal the recurrence's, for every configuration."""
    for cfg in configs().values():
        model = model_of(cfg)
        truth = simulate(cfg, np.random.default_rng(3), 4)
        fem = model.fem_rows()
        for k in range(4):
            assert np.abs(fem.value(truth.x[k])).max() < 1e-12
            for a in range(cfg.d):
                nv = model.node_velocity(a).value(truth.x[k])
                np.testing.assert_allclose(nv, truth.v[k, :, a], rtol=0, atol=1e-12)


def test_fast_path_is_the_public_estimator(mc: MC):
    """The fast path is bvpnav's estimator: equal to ``solve(solver="direct",
    options={"method": "lu"})`` to 1e-9 of the solution's scale (the exact solution of the
    same least squares), and to the default public solve to within the default's own
    accuracy (its LDL refinement accepts corrections up to 1e-7; measured up to ~1e-8
    relative) and to 1e-5 of every standard deviation, which is what the fractions see;
    the analytic reported parameters / Jacobian are bvpnav's."""
    m = mc.fast.model
    for k in range(5):
        p = problem(mc.cfg, [v[k] for v in mc.truth.values])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", BvpnavWarning)
            sol = p.solve(solver="direct", lam=1.0, options={"method": "lu"})
        assert sol.stats["factorization"] == "lu"
        assert np.abs(mc.fx[k] - sol.x).max() < 1e-9 * np.abs(sol.x).max()
        pr, _ = reported(mc.cfg, mc.fx[k:k + 1, m.l_index])
        np.testing.assert_allclose(pr[0], sol.error_params.to_numpy(dtype=float), rtol=0,
                                   atol=1e-9 * np.abs(sol.error_params.to_numpy(dtype=float)).max())
    n = PUBLIC_RUNS
    scale = np.abs(mc.pub.x).max()
    assert np.abs(mc.fx[:n] - mc.pub.x).max() < 1e-7 * scale
    fr, fv = mc.fast.state(mc.fx[:n])
    keep_r, keep_v = ~hard_nodes(mc.cfg, "position"), ~hard_nodes(mc.cfg, "velocity")
    assert (np.abs(fr - mc.pub.r)[:, keep_r] / mc.pub.r_std[:, keep_r]).max() < 1e-5
    assert (np.abs(fv - mc.pub.v)[:, keep_v] / mc.pub.v_std[:, keep_v]).max() < 1e-5
    pr, J = reported(mc.cfg, mc.fx[:n][:, m.l_index])
    assert (np.abs(pr - mc.pub.params) / mc.pub.params_std).max() < 1e-5
    # the variance factor of the fast path is bvpnav's
    np.testing.assert_allclose(mc.fvf[:n], mc.pub.vf, rtol=1e-6)
    form = problem(mc.cfg, [v[0] for v in mc.truth.values]).formulation
    l0 = mc.pub.x[0][m.l_index]
    np.testing.assert_allclose(form.error_model.report(l0, form.model).to_numpy(dtype=float), pr[0],
                               atol=1e-15)
    np.testing.assert_allclose(param_jacobian(form, l0), J[0], atol=1e-8)


def test_std_does_not_depend_on_the_data(mc: MC):
    """Least squares: the covariance of positions and velocities is the same for every
    realisation (it depends on the weights only)."""
    for s in (mc.pub.r_std, mc.pub.v_std):
        assert np.abs(s - s[0]).max() <= 1e-9 * s.max()
    if not mc.cfg.scale:  # linear report: parameter std is data independent too
        assert np.abs(mc.pub.params_std - mc.pub.params_std[0]).max() <= 1e-9 * mc.pub.params_std.max()


def test_hard_items_give_zero_std_and_zero_error(mc: MC):
    """Where a hard item fixes the value: std ~0 (variance below 1e-12 of the typical
    variance, i.e. std below 1e-6 of the typical std: the variance comes out of a
    difference of O(1) terms, so ~1e-16 relative is its floor) and the error ~0;
    everywhere else the std is clearly positive."""
    for kind, est, std, true in (("position", mc.pub.r, mc.pub.r_std, mc.truth.r),
                                 ("velocity", mc.pub.v, mc.pub.v_std, mc.truth.v)):
        mask = hard_nodes(mc.cfg, kind)
        typical = np.median(std[0][~mask])
        if mask.any():
            assert std[0][mask].max() < 1e-6 * typical, (kind, std[0][mask].max() / typical)
            err = (est - true[:PUBLIC_RUNS])[:, mask]
            assert np.abs(err).max() < 1e-9 * max(1.0, np.abs(true).max())
        assert std[0][~mask].min() > 1e-3 * typical


def _check(label: str, f1: float, f2: float) -> None:
    assert abs(f1 - P1) <= TOL1, f"{label}: fraction within 1 sigma {f1:.4f}, target {P1:.3f} +/- {TOL1}"
    assert abs(f2 - P2) <= TOL2, f"{label}: fraction within 2 sigma {f2:.4f}, target {P2:.3f} +/- {TOL2}"


def _chi2(label: str, z: np.ndarray) -> None:
    """Mean of z^2 over realisations (first axis; pooled over the rest per realisation)
    is 1 within 3.5 standard errors estimated from its spread over the realisations."""
    R = z.shape[0]
    per = (z**2).reshape(R, -1).mean(axis=1)
    se = per.std(ddof=1) / np.sqrt(R)
    assert abs(per.mean() - 1.0) <= 3.5 * se, f"{label}: mean z^2 {per.mean():.4f} +/- {se:.4f}"


def test_public_calibration_200(mc: MC):
    """The public output over 200 realisations: mean squared standardized error is 1
    for positions, velocities (pooled, hard-fixed samples excluded) and each parameter.

    The issue's fraction tolerances are asserted on 3000 realisations
    (:func:`test_calibration_3000`, "at least 200" in the issue): at 200 they are about one
    binomial standard error wide for a single parameter (see the module docstring), so a
    correct implementation fails them by chance for a sizeable share of seeds (with this
    seed, 3 of the 9 parameters have 1-sigma fractions of 0.73-0.77 in the first 200
    realisations and 0.68-0.69 over 3000)."""
    n = PUBLIC_RUNS
    for kind, est, std, true in (("position", mc.pub.r, mc.pub.r_std, mc.truth.r[:n]),
                                 ("velocity", mc.pub.v, mc.pub.v_std, mc.truth.v[:n])):
        keep = ~hard_nodes(mc.cfg, kind)
        _chi2(f"{mc.cfg.name} {kind}", (est - true)[:, keep] / std[:, keep])
    true, _ = reported(mc.cfg, mc.truth.l[:n])
    for i, name in enumerate(mc.pub.names):
        _chi2(f"{mc.cfg.name} {name}", (mc.pub.params[:, i] - true[:, i]) / mc.pub.params_std[:, i])


def _fast_std(mc: MC) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position and velocity std (N, d) from the public solve (data independent), and
    the reported parameters' std per fast realisation through the public covariance's
    internal block and the reported Jacobian at each estimate."""
    form = problem(mc.cfg, [v[0] for v in mc.truth.values]).formulation
    P = posterior(form, mc.pub.x[0], 1.0).params
    _, J = reported(mc.cfg, mc.fx[:, mc.fast.model.l_index])
    pstd = np.sqrt(np.einsum("rij,jk,rik->ri", J, P, J))
    np.testing.assert_allclose(pstd[:PUBLIC_RUNS], mc.pub.params_std, rtol=1e-7)
    return mc.pub.r_std[0], mc.pub.v_std[0], pstd


def test_calibration_3000(mc: MC):
    """The issue's acceptance: 3000 realisations of bvpnav's estimator (the fast path, equal
    to the public solve) against the public standard deviations; every parameter and the
    pooled positions and velocities within the issue's tolerances, which are >= 3
    standard errors here (asserted)."""
    r_std, v_std, pstd = _fast_std(mc)
    fr, fv = mc.fast.state(mc.fx)
    for kind, est, std, true in (("position", fr, r_std, mc.truth.r), ("velocity", fv, v_std, mc.truth.v)):
        keep = ~hard_nodes(mc.cfg, kind)
        f1, f2, s1, s2 = fractions((est - true)[:, keep], np.broadcast_to(std, est.shape)[:, keep])
        assert TOL1 >= 3 * s1 and TOL2 >= 3 * s2, (kind, s1, s2)  # the test is not a knife edge
        _check(f"{mc.cfg.name} {kind} (fast, {FAST_RUNS})", f1, f2)
    est, _ = reported(mc.cfg, mc.fx[:, mc.fast.model.l_index])
    true, _ = reported(mc.cfg, mc.truth.l)
    for i, name in enumerate(mc.pub.names):
        f1, f2, s1, s2 = fractions(est[:, i] - true[:, i], pstd[:, i])
        assert TOL1 >= 3 * s1 and TOL2 >= 3 * s2, (name, s1, s2)
        _check(f"{mc.cfg.name} {name} (fast, {FAST_RUNS})", f1, f2)


def test_variance_factor_mean_is_one(mc: MC):
    """The a-posteriori variance factor is chi^2_f / f: its mean over R realisations is 1
    with standard error sqrt(2 / (f R)); asserted within 3.5 standard errors, for the
    200 public and the 3000 fast realisations."""
    f = mc.pub.dof
    assert f == mc.fast.dof and f >= 1
    for vf in (mc.pub.vf, mc.fvf):
        se = np.sqrt(2.0 / (f * vf.size))
        assert abs(vf.mean() - 1.0) <= 3.5 * se, (mc.cfg.name, vf.size, vf.mean(), se)


# -------------------------------------------------------------------------- RTS reference
def rts_smoother(t: np.ndarray, a_hat: np.ndarray, sigma_a: float, prior_mean: np.ndarray,
                 prior_cov: np.ndarray, meas_idx: np.ndarray, meas: np.ndarray, sigma_p: float,
                 bias: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Kalman filter and Rauch-Tung-Striebel smoother (covariance form) for bvpnav's model.

    State ``s_j = (r_j, v_j, w_j[, beta])`` with the corrected acceleration
    ``a_j = a_hat_j + w_j [+ beta]``; the exact recurrence
    ``r_{j+1} = r_j + h v_j + h^2 (2 a_j + a_{j+1}) / 6``, ``v_{j+1} = v_j + h (a_j + a_{j+1}) / 2``
    is ``s_{j+1} = F s_j + u_j + g_w w_{j+1}`` with ``F = [[1, h, h^2/3, h^2/2], [0, 1, h/2, h],
    [0, 0, 0, 0], [0, 0, 0, 1]]`` (the last row and column only with ``bias``),
    ``u_j = (h^2 (2 a_hat_j + a_hat_{j+1}) / 6, h (a_hat_j + a_hat_{j+1}) / 2, 0[, 0])``,
    ``g_w = (h^2/6, h/2, 1[, 0])`` and ``w_{j+1} ~ N(0, sigma_a^2)``.

    Parameters
    ----------
    t, a_hat : ndarray, shape (N,)
    sigma_a : float
    prior_mean : ndarray, shape (ns,)
        Mean of ``s_0`` (its ``w_0`` entry 0).
    prior_cov : ndarray, shape (ns, ns)
        Covariance of ``s_0`` (its ``w_0`` entry ``sigma_a^2``).
    meas_idx : ndarray of int
        Nodes with a position measurement (increasing).
    meas : ndarray
        The measured positions (m), std ``sigma_p``.
    bias : bool
        Whether the state carries a constant acceleration offset ``beta``.

    Returns
    -------
    mean : ndarray, shape (N, ns)
    cov : ndarray, shape (N, ns, ns)
        Smoothed means and covariances.
    """
    N, ns = t.size, prior_mean.size
    H = np.zeros(ns)
    H[0] = 1.0
    z = dict(zip(meas_idx.tolist(), meas, strict=True))
    mf, Pf = np.empty((N, ns)), np.empty((N, ns, ns))
    mp, Pp = np.empty((N, ns)), np.empty((N, ns, ns))
    Fs = np.empty((N, ns, ns))
    m, P = prior_mean.astype(float), prior_cov.astype(float)
    for j in range(N):
        if j:
            h = t[j] - t[j - 1]
            F = np.zeros((ns, ns))
            F[0, :3] = (1.0, h, h**2 / 3)
            F[1, 1:3] = (1.0, h / 2)
            g = np.zeros(ns)
            g[:3] = (h**2 / 6, h / 2, 1.0)
            u = np.zeros(ns)
            u[:2] = (h**2 * (2 * a_hat[j - 1] + a_hat[j]) / 6, h * (a_hat[j - 1] + a_hat[j]) / 2)
            if bias:
                F[0, 3], F[1, 3], F[3, 3] = h**2 / 2, h, 1.0
            Fs[j - 1] = F
            m = F @ m + u
            P = F @ P @ F.T + sigma_a**2 * np.outer(g, g)
        mp[j], Pp[j] = m, P
        if j in z:  # Joseph-form update
            S = H @ P @ H + sigma_p**2
            K = P @ H / S
            m = m + K * (z[j] - H @ m)
            IKH = np.eye(ns) - np.outer(K, H)
            P = IKH @ P @ IKH.T + sigma_p**2 * np.outer(K, K)
        mf[j], Pf[j] = m, P
    ms, Ps = mf.copy(), Pf.copy()
    for j in range(N - 2, -1, -1):
        C = np.linalg.solve(Pp[j + 1].T, (Pf[j] @ Fs[j].T).T).T  # Pf F^T Pp^-1
        ms[j] = mf[j] + C @ (ms[j + 1] - mp[j + 1])
        Ps[j] = Pf[j] + C @ (Ps[j + 1] - Pp[j + 1]) @ C.T
    return ms, Ps


def _rts_case(t: np.ndarray, bias: bool, seed: int):
    """bvpnav solution and RTS smoother for the same information on grid ``t``."""
    rng = np.random.default_rng(seed)
    a_hat = 0.7 * np.sin(1.3 * t) + 0.1 * t
    sigma_a, sigma_p = 0.03, 0.05
    r0m, v0m, P0r, P0v = 0.4, -0.2, 0.02**2, 0.1**2
    b0, sb = 0.05, 0.02  # bias prior (reported, sensor sign): b ~ N(b0, sb^2), beta = -b
    # measurements of a truth drawn from the same model (the comparison holds for any
    # values; consistent ones keep the variance-factor check quiet)
    ac = a_hat + rng.normal(0, sigma_a, t.size) - (b0 + sb * rng.standard_normal() if bias else 0.0)
    r, _ = integrate(t, ac[None, :, None], r0m + np.sqrt(P0r) * rng.standard_normal(),
                     v0m + np.sqrt(P0v) * rng.standard_normal())
    meas_idx = np.arange(3, t.size, 6)
    meas = r[0, meas_idx, 0] + rng.normal(0, sigma_p, meas_idx.size)
    em = Bias(prior=b0, sigma=sb) if bias else None
    p = bv.NavigationProblem(bv.ImuData(t, a_hat), sigma_a=sigma_a, error_model=em)
    p.add(Position(t=0.0, value=r0m, sigma=np.sqrt(P0r)), Velocity(t=0.0, value=v0m, sigma=np.sqrt(P0v)),
          Position(t=t[meas_idx], value=meas, sigma=sigma_p))
    sol = p.solve(solver="direct", lam=1.0, uncertainty=True)
    ns = 4 if bias else 3
    m0 = np.zeros(ns)
    m0[:2] = r0m, v0m
    P0 = np.zeros((ns, ns))
    P0[0, 0], P0[1, 1], P0[2, 2] = P0r, P0v, sigma_a**2
    if bias:
        m0[3], P0[3, 3] = -b0, sb**2
    ms, Ps = rts_smoother(t, a_hat, sigma_a, m0, P0, meas_idx, meas, sigma_p, bias=bias)
    return sol, ms, Ps


@pytest.mark.parametrize("grid,bias", [("uniform", False), ("nonuniform", False), ("nonuniform", True)])
def test_rts_reference(grid: str, bias: bool):
    """bvpnav and an RTS smoother with the same information and noise are the same
    estimator: smoothed means equal bvpnav's positions and velocities to ~1e-9 (which
    checks the state-space derivation, signs and the h^2/3, h/2 entries), and the position
    and velocity std (and the bias std) agree to 1e-6 relative."""
    if grid == "uniform":
        t = np.linspace(0.0, 6.0, 61)
    else:
        t = np.concatenate([[0.0], np.cumsum(np.random.default_rng(11).uniform(0.04, 0.16, 60))])
    sol, ms, Ps = _rts_case(t, bias, seed=7)
    tr = sol.trajectory
    scale = np.abs(ms[:, 0]).max()
    np.testing.assert_allclose(tr["x"].to_numpy(), ms[:, 0], rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(tr["vx"].to_numpy(), ms[:, 1], rtol=0, atol=1e-9 * np.abs(ms[:, 1]).max())
    np.testing.assert_allclose(tr["x_std"].to_numpy(), np.sqrt(Ps[:, 0, 0]), rtol=1e-6)
    np.testing.assert_allclose(tr["vx_std"].to_numpy(), np.sqrt(Ps[:, 1, 1]), rtol=1e-6)
    # the full per-sample state covariance too
    S = sol.covariance("state")
    np.testing.assert_allclose(S[:, 0, 1], Ps[:, 0, 1], rtol=1e-6,
                               atol=1e-6 * np.sqrt(Ps[:, 0, 0] * Ps[:, 1, 1]).max())
    if bias:
        np.testing.assert_allclose(sol.error_params["bias_x"], -ms[0, 3], rtol=0, atol=1e-9 * abs(ms[0, 3]))
        np.testing.assert_allclose(sol.error_params_std["bias_x"], np.sqrt(Ps[0, 3, 3]), rtol=1e-6)
