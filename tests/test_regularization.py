"""Lambda rules: exact curvature, known answers, engines, errors."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import bvpnav
from bvpnav.constraints import Position
from bvpnav.lam.lcurve import curvature as _curvature
from bvpnav.lam.lcurve import spline_curvature as _spline_curvature
from bvpnav.lam.sweep import DirectSweep as _DirectSweep
from bvpnav.scenarios import tikhonov2011
from bvpnav.solve import lambda_curve


def table1(seed=0, scale=0.05, bias=-0.5):
    sc = tikhonov2011(scale=scale, bias=bias, seed=seed)
    t = sc.t
    tp = np.concatenate([t[:10], t[-10:]])
    prob = bvpnav.NavigationProblem(sc.data, residual="load").add(
        Position(t=[0.0, 10.0], value=[0.0, 10.0]),
        Position(t=tp, value=sc.prior(tp), sigma=1.0, name="prior"))
    return prob, sc


def known_noise(seed, n=1001, sa=0.3, sp=0.01):
    """Accelerometer noise sa and position noise sp stated correctly: lambda = 1 is the
    maximum-likelihood weight (2011 paper, Section 2.2)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 10.0, n)
    acc = -np.sin(t) + rng.normal(0, sa, n)
    z = np.sin(t) + rng.normal(0, sp, n)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=sa)
    prob.add(Position(t=t, value=z, sigma=sp))
    return prob, np.sin(t)


def test_exact_curvature_matches_spline_of_dense_sweep():
    prob, _ = table1()
    eng = _DirectSweep(prob)
    lams = np.geomspace(1e-2, 1e2, 81)
    pts = [eng.point(v) for v in lams]
    exact = np.array([_curvature(p) for p in pts])
    spline = _spline_curvature(np.log(lams), [p["rho2"] for p in pts], [p["eta2"] for p in pts],
                               np.log(lams))
    inner = slice(5, -5)
    np.testing.assert_allclose(exact[inner], spline[inner], atol=0.02 * np.max(np.abs(exact)))


def test_derivative_identity_rho_prime_equals_minus_lam_eta_prime():
    prob, _ = table1()
    eng = _DirectSweep(prob)
    lam, eps = 2.0, 1e-5
    a, b, c = eng.point(lam * (1 - eps)), eng.point(lam), eng.point(lam * (1 + eps))
    d_rho = (c["rho2"] - a["rho2"]) / (2 * lam * eps)
    d_eta = (c["eta2"] - a["eta2"]) / (2 * lam * eps)
    assert abs(d_eta - b["deta2"]) < 1e-5 * abs(b["deta2"])
    assert abs(d_rho + lam * b["deta2"]) < 1e-5 * abs(d_rho)


def test_lcurve_refines_beyond_the_grid_and_lands_near_the_paper():
    prob, _ = table1()
    curve = lambda_curve(prob, rules=("lcurve",))
    lam = curve.lam_chosen
    assert lam not in curve.lam  # refined, not a grid point
    k = np.argmax(curve.scores["lcurve"][2:-2]) + 2
    assert curve.lam[k - 1] <= lam <= curve.lam[k + 1]
    # the paper reports lambda_L = 3.611 for this row (mean over its realisations)
    assert 3.611 / 2 < lam < 3.611 * 2
    assert set(curve.to_frame().columns) >= {"lam", "residual_norm", "info_norm", "lcurve"}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gcv_and_discrepancy_find_the_ml_weight_with_known_noise(seed):
    prob, truth = known_noise(seed)
    curve = lambda_curve(prob, rules=("gcv", "discrepancy", "quasi"), rule="gcv")
    assert 0.4 < curve.chosen["gcv"] < 2.5
    # discrepancy with tau = 1.5 over-smooths by design, but stays within a decade
    assert 1.0 < curve.chosen["discrepancy"] < 10.0
    # at the chosen lambda the defining equation holds
    p = _DirectSweep(prob).point(curve.chosen["discrepancy"], need_trace=True)
    assert abs(p["rho2"] - 1.5 * abs(p["trace"])) < 1e-3 * p["rho2"]
    sol = prob.solve(lam="gcv", solver="direct")
    assert sol.lam_rule == "gcv" and sol.lam == pytest.approx(sol.curve.chosen["gcv"])
    assert sol.rms_error(truth) < 1.2 * prob.solve(lam=1.0, solver="direct").rms_error(truth)


def test_quasi_optimality_picks_an_interior_minimum():
    prob, _ = table1(seed=3, scale=0.0, bias=0.5)
    curve = lambda_curve(prob, rules=("quasi",), rule="quasi")
    q = curve.scores["quasi"]
    lam = curve.lam_chosen
    k = int(np.argmin(np.abs(np.log(curve.lam / lam))))
    assert 0 < k < len(q) - 1
    assert 0.1 < lam < 100


def test_hutchinson_trace_agrees_with_exact_trace():
    prob, _ = known_noise(0, n=251)
    exact = _DirectSweep(prob).point(1.0, need_trace=True)["trace"]  # N <= 300: exact columns
    est = [_DirectSweep(prob, exact_trace_limit=0).point(1.0, need_trace=True, probes=100,
                                                          seed=s)["trace"] for s in range(4)]
    # Rademacher probes: standard error sqrt(2 ||B||_F^2 / P) <= sqrt(2 |tr B| / P) per estimate
    se = np.sqrt(2 * abs(exact) / 100 / 4)
    assert abs(np.mean(est) - exact) < 4 * se


def test_cvxpy_engine_for_robust_items_matches_direct_curve_shape():
    # acceleration form: Clarabel is accurate there (the load form limits it to ~1e-4)
    prob, _ = table1()
    prob.residual = "acceleration"
    robust, _ = table1()
    robust.residual = "acceleration"
    items = robust.items
    items[1] = Position(t=items[1].t, value=items[1].value, sigma=1.0, mode="robust", huber=1e3,
                        name="prior")
    robust = robust.with_items(items)
    a = lambda_curve(prob, rules=("lcurve",), lam_range=(1e1, 1e7), points=17)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = lambda_curve(robust, rules=("lcurve",), lam_range=(1e1, 1e7), points=17,
                         solver="clarabel", accuracy="high")
    assert b.engine == "cvxpy"
    # a Huber threshold far above the residuals is least squares: same curve
    np.testing.assert_allclose(b.residual_norm, a.residual_norm, rtol=1e-4)
    assert abs(np.log(b.lam_chosen / a.lam_chosen)) < np.log(1.3)


def test_rule_errors_name_the_fix():
    prob, _ = table1()
    with pytest.raises(bvpnav.InputError, match="sigma_a"):
        prob.solve(lam="discrepancy")
    with pytest.raises(bvpnav.InputError, match="choose one of"):
        prob.solve(lam="lcurvee")
    hard = bvpnav.NavigationProblem(prob.data).add(Position(t=[0.0, 10.0], value=[0.0, 10.0]))
    with pytest.raises(bvpnav.InputError, match="every item is hard"):
        hard.solve(lam="lcurve")


def test_plots_mark_every_rule_and_write_atomically(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from bvpnav import plot
    from bvpnav.io import atomic_savefig

    prob, sc = table1()
    # the load form: gcv needs the acceleration residual and is skipped (logged at INFO)
    curve = lambda_curve(prob, rules=("lcurve", "gcv", "quasi"), points=13, lam_range=(1e-3, 1e3))
    fig = curve.plot()
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert set(curve.chosen) == {"lcurve", "quasi"}
    assert sum(lab.split(":")[0] in curve.chosen for lab in labels) == 2
    assert any("(used)" in lab and lab.startswith("lcurve") for lab in labels)
    sol = prob.solve(solver="direct", lam=curve.lam_chosen)
    f2 = plot.errors({"I": sol}, sc.position)
    rms = float(f2.axes[0].get_legend().get_texts()[0].get_text().split("RMS ")[1].split(" m")[0])
    assert abs(rms - sol.rms_error(sc.position)) < 1e-3 * rms + 1e-12
    out = tmp_path / "lcurve.png"
    atomic_savefig(fig, out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# ------------------------------------- every user option reaches the final solve (issue 14)
def _final_solve_kwargs(monkeypatch, prob, **kw):
    """Solve with a rule; return the options the final fixed-lambda solve ran with (what
    every back-end attempt of it was handed by the pipeline)."""
    from bvpnav.solve import chain

    calls = []
    orig = chain.attempt

    def spy(form, backend, options, lam, opts):
        calls.append({"lam": lam, "fallback": opts.fallback, "verify": opts.verify,
                      "accuracy": opts.accuracy, "options": opts.options, "solver": opts.solver})
        return orig(form, backend, options, lam, opts)

    monkeypatch.setattr(chain, "attempt", spy)
    sol = prob.solve(**kw)
    final = [c for c in calls if not isinstance(c.get("lam"), str)]
    assert len({c["lam"] for c in final}) == 1, calls  # the direct sweep runs no back end
    assert final[0]["lam"] == sol.lam == sol.curve.lam_chosen and sol.lam_rule == kw["lam"]
    return final[0], sol


@pytest.mark.parametrize("option, value, check", [
    ("fallback", None, lambda s: [a["solver"] for a in s.stats["attempts"]] == ["clarabel"]),
    ("verify", False, lambda s: s.stats["verified"] in (True, False)),
    ("accuracy", "high", lambda s: s.stats["accuracy"] == "high"),
    ("options", {"max_iter": 77}, lambda s: s.stats["options"]["max_iter"] == 77),
    ("solver", "direct", lambda s: s.stats["solver"] == "direct"),
])
def test_rule_passes_each_option_to_the_final_solve(monkeypatch, option, value, check):
    """Before: lam='gcv' with fallback=None, verify=False ran its final solve with
    fallback='auto', verify=True (the options were dropped in solve_with_rule)."""
    prob, _ = known_noise(0, n=201)
    final, sol = _final_solve_kwargs(monkeypatch, prob, lam="gcv", **{option: value})
    assert final[option] == value
    assert check(sol)


def test_rule_with_verify_false_returns_an_unverified_answer_instead_of_falling_back(monkeypatch):
    """verify=False and fallback=None reach the final solve: an OSQP stopped after five
    iterations is returned as it is (verified False), not replaced by the chain's next link
    (before the fix the final solve verified, fell back and returned Clarabel's answer)."""
    prob, _ = known_noise(0, n=201)
    final, sol = _final_solve_kwargs(monkeypatch, prob, lam="gcv", fallback=None, verify=False,
                                     solver="osqp", options={"max_iter": 5})
    assert final["verify"] is False and final["fallback"] is None
    assert sol.stats["solver"] == "osqp" and sol.stats["status"] == "user_limit"
    assert not sol.stats["verified"]
    assert sol.stats["attempts"] == [{"solver": "osqp", "status": "user_limit",
                                      "reason": "failed verification"}]
