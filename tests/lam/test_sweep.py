"""The lambda sweep (bvpnav.lam.sweep) and its rules together: derivatives, traces, known
answers, the cvxpy engine, errors, plots. Per rule: test_lcurve.py, test_quasi.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _helpers import known_noise, table1

import bvpnav
from bvpnav.constraints import Position
from bvpnav.lam.sweep import DirectSweep as _DirectSweep
from bvpnav.solve import lambda_curve


def test_derivative_identity_rho_prime_equals_minus_lam_eta_prime():
    prob, _ = table1()
    eng = _DirectSweep(prob.formulation)
    lam, eps = 2.0, 1e-5
    a, b, c = eng.point(lam * (1 - eps)), eng.point(lam), eng.point(lam * (1 + eps))
    d_rho = (c["rho2"] - a["rho2"]) / (2 * lam * eps)
    d_eta = (c["eta2"] - a["eta2"]) / (2 * lam * eps)
    assert abs(d_eta - b["deta2"]) < 1e-5 * abs(b["deta2"])
    assert abs(d_rho + lam * b["deta2"]) < 1e-5 * abs(d_rho)


@pytest.mark.parametrize("error_model", [None, "scale+bias"])
def test_load_form_points_by_one_factor_and_an_update_equal_a_factor_per_lambda(error_model):
    """The load form has no band: a sweep factors its sparse LU once (lambda = 1) and reaches
    every lambda through a rank-20 update of the prior's rows (sweep._LamUpdate). Every
    quantity of a point equals the one from a fresh LU at that lambda (the previous path),
    across the range and beyond it, with the error model's dense columns too."""
    from bvpnav.error_models import Bias, ScaleFactor
    from bvpnav.lam.sweep import _LamUpdate

    prob, _ = table1()
    if error_model:
        prob = bvpnav.NavigationProblem(prob.data, residual="load", error_model=ScaleFactor() + Bias(),
                                        grade=None).add(*prob.items)
    updated, fresh = _DirectSweep(prob.formulation), _DirectSweep(prob.formulation)
    fresh._update = False   # a sparse LU at every lambda
    assert updated._plan is None
    assert isinstance(updated._factor(updated._ls.at_lam(3.0), 3.0), _LamUpdate)
    assert len(prob.formulation.model.l_index) == (2 if error_model else 0)
    for lam in (1e-6, 1e-2, 1.0, 37.0, 1e4, 1e6, 1e9):
        a, b = fresh.point(lam), updated.point(lam)
        np.testing.assert_allclose(b["x"], a["x"], rtol=0, atol=1e-10 * np.abs(a["x"]).max())
        for key in ("rho2", "eta2", "deta2", "d2eta2", "quasi"):
            assert b[key] == pytest.approx(a[key], rel=1e-9), (lam, key)


def _with_bias():
    """Three axes with a bias per axis (the banded factor's border) and soft velocities."""
    from bvpnav.constraints import Velocity
    from bvpnav.error_models import Bias

    rng = np.random.default_rng(4)
    t = np.linspace(0.0, 10.0, 801)
    acc = np.column_stack([-np.sin(t), -0.25 * np.cos(0.5 * t), np.full(t.size, 0.2)])
    acc += 0.05 * rng.standard_normal(acc.shape) + [0.03, -0.02, 0.01]
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=0.05, error_model=Bias())
    r = np.column_stack([np.sin(t), np.cos(0.5 * t), 0.1 * t**2])
    return prob.add(Position(t=t[::50], value=r[::50], sigma=0.1), Position(t=0.0, value=r[0]),
                    Velocity(t=[0.0, 10.0], value=[[1.0, 0.0, 0.0], [np.cos(10.0), -0.5 * np.sin(5.0), 2.0]],
                             sigma=0.05))


def _velocity_rows():
    """Known noise plus soft velocities inside elements (rows that read w there)."""
    from bvpnav.constraints import Velocity

    prob, _ = known_noise(0, n=2001)
    return prob.add(Velocity(t=[2.5, 7.52], value=[np.cos(2.5), np.cos(7.52)], sigma=0.02))


@pytest.mark.parametrize("make", [lambda: known_noise(0, n=2001)[0], _velocity_rows],
                         ids=["position rows", "velocity rows inside elements"])
def test_the_derivative_solve_skips_the_eliminated_accelerations(make):
    """dx/dlambda skips the eliminated accelerations' back-substitution: no lambda-weighted
    row reads one (a w that any soft row reads, as a velocity inside an element does, is
    not eliminated). deta2 equals the central difference of eta2, and equals the one with
    the back-substitution; the skipped entries are NaN, the others the full solve's."""
    eng = _DirectSweep(make())
    lam, eps = 0.8, 1e-5
    a, b, c = eng.point(lam * (1 - eps)), eng.point(lam), eng.point(lam * (1 + eps))
    fac = eng._factor(eng._ls.at_lam(lam), lam)
    assert eng._lam_rows_read_eliminated(fac) is False
    d_eta = (c["eta2"] - a["eta2"]) / (2 * lam * eps)
    assert abs(d_eta - b["deta2"]) < 1e-5 * abs(b["deta2"])
    full = _DirectSweep(make())
    full._reads_eliminated = True   # as if a lambda row read w: back-substituted
    assert full.point(lam)["deta2"] == pytest.approx(b["deta2"], rel=1e-12)
    rhs = np.random.default_rng(0).standard_normal(fac.S.shape[0])
    x_all, x_part = fac.solve_x_real(rhs), fac.solve_x_real(rhs, eliminated=False)
    el = fac.plan.elim
    assert el.size and np.all(np.isnan(x_part[el]))
    keep = np.setdiff1d(np.arange(x_all.size), el)
    np.testing.assert_array_equal(x_part[keep], x_all[keep])


@pytest.mark.parametrize("make", [lambda: table1()[0], lambda: known_noise(0, n=2001)[0], _with_bias],
                         ids=["load form, LU", "acceleration form, banded", "three axes, bias border"])
def test_second_derivative_of_eta2_is_six_times_the_squared_change_of_the_lambda_rows(make):
    """d2eta2 = 6 ||S A x'||^2 (no second solve) equals the central difference of the
    exact first derivative, from lambda = 0.01 to 300, in both forms and factorizations,
    with error-model parameters in the banded factor's border too."""
    eng = _DirectSweep(make())
    eps = 1e-3
    for lam in (0.01, 2.0, 300.0):
        a, b, c = eng.point(lam * (1 - eps)), eng.point(lam), eng.point(lam * (1 + eps))
        fd = (c["deta2"] - a["deta2"]) / (2 * lam * eps)
        assert b["d2eta2"] > 0
        assert abs(b["d2eta2"] - fd) < 1e-4 * abs(fd), (lam, b["d2eta2"], fd)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gcv_and_discrepancy_find_the_ml_weight_with_known_noise(seed):
    prob, truth = known_noise(seed)
    curve = lambda_curve(prob, rules=("gcv", "discrepancy", "quasi"), rule="gcv")
    assert 0.4 < curve.chosen["gcv"] < 2.5
    # discrepancy with tau = 1.5 over-smooths by design, but stays within a decade
    assert 1.0 < curve.chosen["discrepancy"] < 10.0
    # at the chosen lambda the defining equation holds
    p = _DirectSweep(prob.formulation).point(curve.chosen["discrepancy"], need_trace=True)
    assert abs(p["rho2"] - 1.5 * abs(p["trace"])) < 1e-3 * p["rho2"]
    sol = prob.solve(lam="gcv", solver="direct")
    assert sol.lam_rule == "gcv" and sol.lam == pytest.approx(sol.curve.chosen["gcv"])
    assert sol.rms_error(truth) < 1.2 * prob.solve(lam=1.0, solver="direct").rms_error(truth)


def test_hutchinson_trace_agrees_with_exact_trace():
    prob, _ = known_noise(0, n=251)
    exact = _DirectSweep(prob.formulation).point(1.0, need_trace=True)["trace"]  # N <= 300: exact columns
    est = [_DirectSweep(prob.formulation, trace="hutchinson").point(1.0, need_trace=True, probes=100,
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
    curve = lambda_curve(prob, rules=("lcurve", "gcv", "quasi"), points=13, lam_range=(1e-3, 1e3))
    fig = curve.plot()
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert sum(lab.split(":")[0] in curve.chosen for lab in labels) == 3
    assert any("(used)" in lab and lab.startswith("lcurve") for lab in labels)
    sol = prob.solve(solver="direct", lam=curve.lam_chosen)
    f2 = plot.errors({"I": sol}, sc.position)
    rms = float(f2.axes[0].get_legend().get_texts()[0].get_text().split("RMS ")[1].split(" m")[0])
    assert abs(rms - sol.rms_error(sc.position)) < 1e-3 * rms + 1e-12
    out = tmp_path / "lcurve.png"
    atomic_savefig(fig, out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


PEAKS = {
    # log-lambda functions with a known extremum: a Lorentzian (heavy tails), a narrow one
    # (narrower than the grid), a skewed cusp-like peak, and flat-topped ones (a parabola is
    # a poor model of their top: a search that trusts it early stops 0.1 off)
    "lorentz": (lambda u: 1.0 / (1.0 + ((u - 0.7) / 0.8) ** 2), 0.7),
    "narrow": (lambda u: 1.0 / (1.0 + ((u + 2.1) / 0.3) ** 2), -2.1),
    "asymmetric": (lambda u: -abs(u - 0.4) ** 1.5 - 0.5 * (u - 0.4), 0.4 - (1.0 / 3.0) ** 2),
    "flat4": (lambda u: 1.0 / (1.0 + ((u + 4.5) / 1.0) ** 4), -4.5),
    "flat4.66": (lambda u: 1.0 / (1.0 + abs((u + 4.4653) / 1.1177) ** 4.66), -4.4653),
    "flat5.4": (lambda u: 1.0 / (1.0 + abs((u - 0.16) / 0.62) ** 5.4), 0.16),
}


@pytest.mark.parametrize("decades", [1.0, 1.5])
def test_refine_extremum_reaches_the_tolerance_with_no_more_evaluations_than_a_cold_brent(decades):
    """Seeded with the sweep's own three samples around the best one, the parabolic search
    lands within xatol of the true maximiser of every peak, and over the set spends no more
    new evaluations than scipy's bounded Brent started cold on the same brackets (which
    re-discovers what the samples already say); a minimum is the same search negated."""
    from scipy.optimize import minimize_scalar

    from bvpnav.lam import REFINE_XATOL, refine_extremum

    s = np.arange(-6, 7) * decades * np.log(10.0)
    ours = cold = 0
    for name, (f, u_star) in PEAKS.items():
        scores = np.array([f(u) for u in s])
        k = int(np.argmax(scores))
        calls = []
        u = refine_extremum(lambda v, f=f, calls=calls: calls.append(v) or f(v), s, scores, k, best="max")
        assert abs(u - u_star) < REFINE_XATOL, name
        ours += len(calls)
        cold += minimize_scalar(lambda v, f=f: -f(v), bounds=(s[k - 1], s[k + 1]), method="bounded",
                                options={"xatol": REFINE_XATOL}).nfev
        v = refine_extremum(lambda w, f=f: -f(w), s, -scores, k, best="min")
        assert abs(v - u_star) < REFINE_XATOL, name
    assert ours <= cold, (ours, cold)


def test_refine_extremum_returns_the_bracket_end_when_the_best_is_there():
    """A monotone function on the bracket: the end is returned, no evaluation wasted inside."""
    from bvpnav.lam import refine_extremum

    s = np.log(np.geomspace(1e-3, 1e3, 7))
    scores = s.copy()  # increasing: the best allowed sample 5 still has a better neighbour 6
    assert refine_extremum(lambda v: v, s, scores, 5, best="max") == pytest.approx(s[6])


def test_sweep_and_chosen_lambda_share_one_band_plan(monkeypatch):
    """The sweep's banded plan is cached on the formulation; the solve at the chosen lambda
    reuses it (the symbolic analysis is done once per rule solve)."""
    from bvpnav.linalg.banded import BandPlan

    prob, _ = known_noise(0, n=2001)
    built = []
    original = BandPlan.build.__func__

    def counting(cls, *a, **kw):
        built.append(1)
        return original(cls, *a, **kw)

    monkeypatch.setattr(BandPlan, "build", classmethod(counting))
    sol = prob.solve(solver="direct", lam="lcurve")
    assert sol.stats["verified"] and sol.stats["factorization"].startswith("banded")
    assert len(built) == 1


def test_a_sweep_without_derivative_rules_skips_the_derivative_solve():
    """GCV alone reads rho2 and the trace: the points carry no deta2 (one solve fewer per
    lambda); asking a rule that needs it afterwards recomputes the point."""
    prob, _ = known_noise(0, n=2001)
    eng = _DirectSweep(prob.formulation, need_trace=True, need_derivative=False)
    p = eng.point(0.7)
    assert "deta2" not in p and "trace" in p
    eng.need_derivative = True
    q = eng.point(0.7)
    assert "deta2" in q and q["rho2"] == pytest.approx(p["rho2"], rel=1e-12)


def _holds_no_band(form) -> bool:
    """Whether nothing of a sweep's bands is kept with the formulation (it holds no cache:
    the bands live in the solve's workspace)."""
    from bvpnav.linalg.banded import AffineBand, KeptFactors
    from bvpnav.linalg.workspace import Workspace

    return not hasattr(form, "cache") and not any(
        isinstance(v, AffineBand | KeptFactors | Workspace) for v in vars(form).values())


@pytest.mark.filterwarnings("ignore::bvpnav.log.BvpnavWarning")  # the L-curve's lambda misfits sigma_a
def test_the_chosen_lambda_solved_from_the_sweeps_band_equals_a_fresh_solve():
    """The solve at the chosen lambda takes its band from the sweep (AffineBand, no
    assembly): verified, equal to a fresh problem solved at that lambda, and the band is not
    kept alive with the formulation afterwards."""
    prob, _ = known_noise(0, n=2001)
    sol = prob.solve(solver="direct", lam="lcurve")
    assert _holds_no_band(prob.formulation) and sol.stats["verified"]
    fresh, _ = known_noise(0, n=2001)
    ref = fresh.solve(solver="direct", lam=sol.lam)
    np.testing.assert_allclose(sol.x, ref.x, rtol=0, atol=1e-10 * np.max(np.abs(ref.x)))


@pytest.mark.filterwarnings("ignore::bvpnav.log.BvpnavWarning")  # the rules' lambdas misfit sigma_a
@pytest.mark.parametrize("rule", ["lcurve", "gcv", "quasi"])
def test_the_chosen_lambda_is_factored_in_a_buffer_of_the_sweep(monkeypatch, rule):
    """After the sweep, the solve at the chosen lambda writes its band into memory the sweep
    used (no fresh band-sized array): one factorization, verified, equal to a fresh solve
    at that lambda, and nothing is kept with the formulation afterwards."""
    from bvpnav.linalg.banded import BandedKKT, KeptFactors

    prob, _ = known_noise(0, n=2001)
    factored, buffers = [], []
    original = BandedKKT._factor_parts
    monkeypatch.setattr(BandedKKT, "_factor_parts", lambda self, parts: (factored.append(1),
                                                                        original(self, parts))[1])
    original_buffer = KeptFactors.buffer
    monkeypatch.setattr(KeptFactors, "buffer", lambda self, shape: (buffers.append(original_buffer(
        self, shape)), buffers[-1])[1])
    sol = prob.solve(solver="direct", lam=rule)
    assert sol.stats["verified"] and sol.stats["factorization"].startswith("banded")
    assert len(buffers) == 1 and buffers[0] is not None
    # the sweep's own factorizations (GCV's trace: each of its points is one complex one)
    assert len(factored) == sol.curve.evaluations + 1
    assert _holds_no_band(prob.formulation)
    fresh, _ = known_noise(0, n=2001)
    ref = fresh.solve(solver="direct", lam=sol.lam)
    np.testing.assert_allclose(sol.x, ref.x, rtol=0, atol=1e-10 * np.max(np.abs(ref.x)))


def test_the_last_points_factor_is_handed_to_a_solve_at_its_lambda(monkeypatch):
    """A solve at exactly the sweep's last lambda takes that point's factor (no
    factorization) and answers as a fresh solve; at another lambda it factors again."""
    from bvpnav.linalg.banded import BandedKKT
    from bvpnav.linalg.lsq import solve_least_squares

    prob, _ = known_noise(1, n=2001)
    form = prob.formulation
    eng = _DirectSweep(form)
    for lam in (0.3, 0.7):
        eng.point(lam)
    eng.hand_off()
    factored = []
    original = BandedKKT._factor_parts
    monkeypatch.setattr(BandedKKT, "_factor_parts", lambda self, parts: (factored.append(1),
                                                                        original(self, parts))[1])
    x_last = solve_least_squares(form, 0.7, workspace=eng.workspace)[0]
    assert factored == []
    # not kept (its buffer held the point at 0.7)
    x_other = solve_least_squares(form, 0.3, workspace=eng.workspace)[0]
    assert factored == [1]
    fresh, _ = known_noise(1, n=2001)
    for lam, x in ((0.7, x_last), (0.3, x_other)):
        ref = solve_least_squares(fresh.formulation, lam)[0]
        np.testing.assert_allclose(x, ref, rtol=0, atol=1e-10 * np.max(np.abs(ref)))


def test_a_kept_factor_and_its_buffer_are_handed_out_once():
    """KeptFactors: a factor is taken once; a buffer taken for a new band ends the factor
    that lived in it; spare buffers go first."""
    from bvpnav.linalg.banded import KeptFactors

    kept = KeptFactors(plan=None)
    a, b, spare = np.zeros((5, 3)), np.zeros((5, 3)), np.zeros((5, 3))
    kept.keep(1.0, "factor at 1", a)
    kept.keep(2.0, "factor at 2", b)
    kept.spare(spare)
    assert kept.take(1.0) == "factor at 1" and kept.take(1.0) is None and kept.take(3.0) is None
    out = kept.buffer((5, 3))
    out[:] = 7.0
    assert np.all(spare == 7.0) and np.all(b == 0.0) and kept.lams() == [2.0]
    out = kept.buffer((5, 3))   # no spare left: the kept factor's buffer, which ends it
    out[:] = 8.0
    assert np.all(b == 8.0) and kept.lams() == [] and kept.buffer((5, 3)) is None
    assert kept.take(2.0) is None


def test_a_factor_for_other_matrices_of_its_pattern_refines_against_them():
    """BandedKKT.for_matrices: the factor of one lambda's form answers the form of a lambda
    0.1 % away after refinement against that form's own matrices (the solve at the chosen
    lambda measures its residuals on its own form), and refuses another pattern."""
    from bvpnav.linalg.banded import NotBanded
    from bvpnav.linalg.lsq import banded_factor, least_squares_form

    prob, _ = known_noise(0, n=501)
    form = prob.formulation
    f1, f2 = least_squares_form(form, 0.5), least_squares_form(form, 0.5005)
    fac = banded_factor(f1, form).for_matrices(f2.D.A, f2.E.A)
    z, k, corr = fac.refined(f2.rhs(), 5, 1e-14)
    exact = banded_factor(f2, form).refined(f2.rhs(), 3, 1e-14)[0]
    assert k >= 2   # the first solve is off by about the change of lambda
    np.testing.assert_allclose(z, exact, rtol=0, atol=1e-11 * np.max(np.abs(exact)))
    with pytest.raises(NotBanded, match="pattern"):
        fac.for_matrices(f2.D.A[:-1], f2.E.A)


def test_refine_extremum_keeps_to_its_bounds():
    """A rule that never chooses its outermost samples (the L-curve's two on each side)
    gives bounds: a better neighbour beyond a bound, or a parabola whose vertex lies
    beyond it, returns the bound (the best allowed point), never the excluded sample."""
    from bvpnav.lam import refine_extremum

    s = np.log(np.geomspace(1e-3, 1e3, 9))
    inc = s.copy()   # increasing: the best allowed sample 6 has a better excluded neighbour 7
    assert refine_extremum(lambda v: v, s, inc, 6, best="max", bounds=(s[2], s[6])) == s[6]
    # a peak just beyond the upper bound: the parabola's vertex lies in the excluded range
    peak = s[6] + 0.3 * (s[7] - s[6])
    g = -(s - peak) ** 2
    assert refine_extremum(lambda v: -(v - peak) ** 2, s, g, 6, best="max", bounds=(s[2], s[6])) == s[6]
    # inside the bounds nothing changes: the peak itself, to the tolerance
    peak = s[5] + 0.3 * (s[6] - s[5])
    g = -(s - peak) ** 2
    u = refine_extremum(lambda v: -(v - peak) ** 2, s, g, 5, best="max", bounds=(s[2], s[6]))
    assert abs(u - peak) < 1e-3


def _slope(f, u, h=1e-6):
    return (f(u + h) - f(u - h)) / (2 * h)


@pytest.mark.parametrize("decades", [1.0, 2.0])
def test_refine_with_slopes_reaches_the_tolerance_in_fewer_evaluations_than_values_alone(decades):
    """Given each point's slope, the search lands within xatol of every peak (the flat tops
    included, where the slope has a zero of order three or more) and over the set spends
    fewer new evaluations than the value-only search from the same samples; a minimum is
    the same search negated."""
    from bvpnav.lam import REFINE_XATOL, refine_extremum, refine_with_slopes

    s = np.arange(-6, 7) * decades * np.log(10.0)
    ours = theirs = 0
    for name, (f, u_star) in PEAKS.items():
        scores = np.array([f(u) for u in s])
        slopes = np.array([_slope(f, u) for u in s])
        k = int(np.argmax(scores))
        calls = []
        u = refine_with_slopes(lambda v, f=f, calls=calls: calls.append(v) or (f(v), _slope(f, v)),
                               s, scores, slopes, k)
        assert abs(u - u_star) < REFINE_XATOL, (name, u, u_star)
        ours += len(calls)
        counted = []
        refine_extremum(lambda v, f=f, counted=counted: counted.append(v) or f(v), s, scores, k)
        theirs += len(counted)
        v = refine_with_slopes(lambda w, f=f: (-f(w), -_slope(f, w)), s, -scores, -slopes, k, best="min")
        assert abs(v - u_star) < REFINE_XATOL, name
    assert ours < theirs, (ours, theirs)


@pytest.mark.parametrize("decades", [1.0, 2.0])
def test_the_septic_step_model_saves_evaluations_over_the_bracket_cubic(monkeypatch, decades):
    """refine_with_slopes steps to the peak of the degree-7 Hermite polynomial through the
    bracket's ends and the two evaluated points nearest it: over the peaks, no more
    evaluations than with the bracket's cubic alone (hermite_fit_peak disabled), strictly
    fewer in all, and every answer within xatol."""
    import bvpnav.lam as lam_mod
    from bvpnav.lam import REFINE_XATOL, refine_with_slopes

    s = np.arange(-6, 7) * decades * np.log(10.0)

    def count() -> list[int]:
        out = []
        for f, u_star in PEAKS.values():
            scores = np.array([f(u) for u in s])
            slopes = np.array([_slope(f, u) for u in s])
            calls = []
            u = refine_with_slopes(lambda v, f=f, calls=calls: calls.append(v) or (f(v), _slope(f, v)),
                                   s, scores, slopes, int(np.argmax(scores)))
            assert abs(u - u_star) < REFINE_XATOL
            out.append(len(calls))
        return out

    septic = count()
    monkeypatch.setattr(lam_mod, "hermite_fit_peak", lambda *a, **k: None)
    cubic = count()
    print(f"{decades} decades apart: septic {septic}, cubic {cubic}")
    assert sum(septic) < sum(cubic), (septic, cubic)
    assert max(np.subtract(septic, cubic)) <= 1, (septic, cubic)


def test_hermite_fit_peak_is_exact_for_a_septic_and_none_without_a_maximum():
    """Values and slopes at four points determine a degree-7 polynomial: its maximiser in
    the bracket is found to rounding, from points inside and far outside it; a function
    rising across the bracket has none there."""
    from bvpnav.lam import hermite_fit_peak

    def g(u):   # a single maximum at u = 0.3 (the derivative's other roots are complex)
        return -(u - 0.3) ** 2 * (1.0 + 0.2 * u**2 + 0.01 * u**4) + 0.002 * (u - 0.3) ** 7

    def _poly_slope(u):
        w = u - 0.3
        return (-2 * w * (1.0 + 0.2 * u**2 + 0.01 * u**4) - w**2 * (0.4 * u + 0.04 * u**3)
                + 0.014 * w**6)

    for a, b, far in ((-1.0, 1.0, (2.5, -4.0)), (0.2, 0.5, (0.9, -0.6)), (0.29, 0.31, (1.5, -2.0))):
        pts = [(x, g(x), _poly_slope(x)) for x in (a, b, *far)]
        assert hermite_fit_peak(pts, a, b) == pytest.approx(0.3, abs=1e-9)
    rising = [(x, x + x**3, 1 + 3 * x**2) for x in (0.0, 1.0, 2.0, -1.0)]
    assert hermite_fit_peak(rising, 0.0, 1.0) is None


def test_hermite_peak_is_exact_for_a_cubic():
    """The cubic -u^3/3 + u has its maximum at u = 1; from its values and slopes at any
    bracket the maximiser is found to rounding (and the midpoint without a maximum)."""
    from bvpnav.lam import hermite_peak

    def g(u):
        return -u**3 / 3 + u

    def d(u):
        return 1 - u**2

    for a, b in ((0.0, 1.7), (-0.5, 3.0), (0.9, 1.05)):
        assert hermite_peak(a, b, g(a), g(b), d(a), d(b)) == pytest.approx(1.0, abs=1e-12)
    # both ends on the rising side and no maximum inside: the midpoint
    assert hermite_peak(-0.5, 0.5, g(-0.5), g(0.5), d(-0.5), d(0.5)) == pytest.approx(0.0)


def test_refine_with_slopes_keeps_to_bounds_and_falls_back_without_a_bracket():
    """A peak beyond a bound returns the bound; a slope of zero at the best sample (no
    bracket from the signs) is the value-only search's answer; a point where the slope is
    exactly zero is returned as it is."""
    from bvpnav.lam import REFINE_XATOL, refine_extremum, refine_with_slopes

    s = np.log(np.geomspace(1e-3, 1e3, 7))
    peak = s[5] + 0.4 * (s[6] - s[5])
    g, dg = -(s - peak) ** 2, -2 * (s - peak)
    assert refine_with_slopes(lambda v: (-(v - peak) ** 2, -2 * (v - peak)), s, g, dg, 5,
                              bounds=(s[1], s[5])) == s[5]
    peak = s[3]
    g, dg = -(s - peak) ** 4, -4 * (s - peak) ** 3
    assert dg[3] == 0
    f = lambda v: -(v - peak) ** 4   # noqa: E731
    assert refine_with_slopes(lambda v: (f(v), -4 * (v - peak) ** 3), s, g, dg, 3) == \
        refine_extremum(f, s, g, 3)
    peak = s[3] + 0.3
    g, dg = -(s - peak) ** 2, -2 * (s - peak)
    u = refine_with_slopes(lambda v: (-(v - peak) ** 2, 0.0), s, g, dg, 3)
    assert s[3] + REFINE_XATOL <= u <= s[4] - REFINE_XATOL


def test_guard_samples_cover_two_decades_at_each_end_of_the_default_grids():
    from bvpnav.lam import guard_samples

    assert guard_samples(np.log(np.geomspace(1e-6, 1e6, 13))) == 2
    assert guard_samples(np.log(np.geomspace(1e-6, 1e6, 7))) == 1
    assert guard_samples(np.log(np.geomspace(1e-6, 1e6, 5))) == 1
    assert guard_samples(np.log(np.geomspace(1e-3, 1e-1, 9))) == 2


def test_refine_with_slopes_bisects_when_it_creeps_on_a_flat_top():
    """-|u - c|^p with p = 6, 8, 10: the slope's zero is of order p - 1, where secants creep
    from one side; after five such steps the search bisects and ends inside the tolerance's
    bracket (2 xatol wide) in well under maxiter evaluations."""
    from bvpnav.lam import REFINE_XATOL, refine_with_slopes

    for decades in (1.0, 2.0):
        s = np.arange(-6, 7) * decades * np.log(10.0)
        for p in (6, 8, 10):
            for c in (0.77, 0.3):
                def f(u, p=p, c=c):
                    return -abs(u - c) ** p
                scores = np.array([f(u) for u in s])
                slopes = np.array([_slope(f, u) for u in s])
                calls = []
                u = refine_with_slopes(lambda v, f=f, calls=calls: calls.append(v) or (f(v), _slope(f, v)),
                                       s, scores, slopes, int(np.argmax(scores)))
                # ended by the bracket, not by running out of evaluations (maxiter = 30)
                assert abs(u - c) < 2 * REFINE_XATOL and len(calls) < 30, (decades, p, c, u, len(calls))


def test_refine_with_slopes_takes_a_zero_slope_only_at_a_best_point_and_stops_at_nan():
    """A degenerate point whose slope is exactly zero but whose score is below the bracket's
    ends does not end the search; a score that is not finite ends it inside the bracket."""
    from bvpnav.lam import REFINE_XATOL, refine_with_slopes

    s = np.log(np.geomspace(1e-3, 1e3, 7))
    peak = s[3] + 0.5

    def f(v):
        return -(v - peak) ** 2

    g, dg = f(s), -2 * (s - peak)
    calls = []

    def degenerate(v):   # the first evaluation looks like a point of no curve at all
        calls.append(v)
        if len(calls) == 1:
            return -1e3, 0.0
        return f(v), -2 * (v - peak)

    u = refine_with_slopes(degenerate, s, g, dg, 3)
    assert len(calls) > 1 and abs(u - peak) < 2 * REFINE_XATOL   # searched on past it
    u = refine_with_slopes(lambda v: (float("nan"), float("nan")), s, g, dg, 3)
    assert s[3] <= u <= s[4]


@pytest.mark.parametrize("make", [lambda: known_noise(0)[0], lambda: known_noise(4)[0],
                                  lambda: known_noise(6)[0], lambda: known_noise(1, n=2001)[0]],
                         ids=["noise0", "noise4", "noise6", "noise1-2001"])
def test_gcv_alone_samples_every_two_decades_and_chooses_the_one_decade_grids_minimum(make):
    """``solve(lam="gcv")`` samples every two decades (7 points) and evaluates the half-way
    points beside its best sample (the 13-point grid's own samples there) before refining:
    the same minimum to the refinement's tolerance (measured 1e-10 .. 1e-8 in log lambda),
    four evaluations fewer (measured 14-19 against 18-23)."""
    from bvpnav.lam import REFINE_XATOL
    from bvpnav.lam.sweep import DIRECT_POINTS, SLOPE_POINTS

    coarse = make().solve(solver="direct", lam="gcv").curve   # the default sweep
    fine = lambda_curve(make(), rules=("gcv",), rule="gcv", points=DIRECT_POINTS)
    assert len(coarse.lam) == SLOPE_POINTS and len(fine.lam) == DIRECT_POINTS
    assert abs(np.log(coarse.lam_chosen / fine.lam_chosen)) < REFINE_XATOL
    assert coarse.evaluations <= fine.evaluations - 3
    assert not coarse.warnings and not fine.warnings


@pytest.mark.filterwarnings("ignore::bvpnav.log.BvpnavWarning")  # seed 0's edge warning
def test_gcv_on_a_coarse_grid_looks_half_way_before_calling_the_best_sample_an_edge():
    """The 2011 example in the acceleration form, seed 3: on the 13-point grid GCV's minimum
    lies inside (about 4e4, between the samples 1e4 and 1e5); the 7-point grid's best
    sample is the end 1e6, but the half-way point 1e5 scores better, so the refinement
    finds the same interior minimum without an edge warning. Seed 0 decreases to the end:
    the half-way point does not help and the edge warning stays."""
    from _helpers import table1_problem

    from bvpnav.lam import REFINE_XATOL
    from bvpnav.lam.sweep import DIRECT_POINTS

    inner = table1_problem(2001, seed=3)[0].solve(solver="direct", lam="gcv").curve
    fine = lambda_curve(table1_problem(2001, seed=3)[0], rules=("gcv",), rule="gcv", points=DIRECT_POINTS)
    assert len(inner.lam) == 7 and inner.lam[-1] == pytest.approx(1e6)
    assert int(np.argmin(inner.scores["gcv"])) == 6   # the coarse grid's best sample is the end
    assert 1e4 < fine.lam_chosen < 1e5 and not fine.warnings
    assert abs(np.log(inner.lam_chosen / fine.lam_chosen)) < REFINE_XATOL and not inner.warnings
    edge = table1_problem(2001, seed=0)[0].solve(solver="direct", lam="gcv").curve
    assert edge.lam_chosen == pytest.approx(1e6) and any("high edge" in w for w in edge.warnings)


class _FakeSweep:
    """A GCV sweep of a given function of ``u = log lambda`` (trace 1): ``rho2 = g(u)``."""

    engine = "direct"

    def __init__(self, g):
        self.g, self.cache = g, {}

    def point(self, lam):
        key = float(lam)
        if key not in self.cache:
            self.cache[key] = {"rho2": float(self.g(np.log(key))), "trace": 1.0}
        return self.cache[key]


def _gcv_refine(g, n):
    from types import SimpleNamespace

    from bvpnav.lam.gcv import GCV

    lams = np.geomspace(1e-6, 1e6, n)
    sweep = _FakeSweep(g)
    pts = [sweep.point(lam) for lam in lams]
    curve = SimpleNamespace(lam=lams, lam_range=(1e-6, 1e6), warnings=[])
    rule = GCV()
    lam = rule.refine(sweep, pts, np.log(lams), rule.scores(sweep, pts, np.log(lams)), curve)
    return lam, len(sweep.cache), curve.warnings


def test_coarse_gcv_looks_at_every_half_way_point_before_calling_an_end_an_edge():
    """A dip 0.4 decade wide at lambda = 10 (an odd decade, between the coarse samples 1 and
    100) on a background falling to the low end: the best coarse sample is the end 1e-6 and
    its half-way point scores no better; every half-way point is then evaluated, the dip
    is found as on the one-decade grid, and nothing warns (found in review: without this
    the end was returned with a warning to widen the range)."""
    ln10 = np.log(10.0)

    def g(u):
        return np.exp(2 + 0.3 * np.tanh(u / ln10 / 3) - 2 * np.exp(-0.5 * ((u / ln10 - 1) / 0.4) ** 2))

    fine = _gcv_refine(g, 13)
    coarse = _gcv_refine(g, 7)
    assert 8.0 < fine[0] < 12.0 and not fine[2]
    assert abs(np.log(coarse[0] / fine[0])) < 1e-6 and not coarse[2]
    # a background that falls to the end without a dip keeps its edge warning
    lam, evals, warnings = _gcv_refine(lambda u: np.exp(u / ln10 / 3), 7)
    assert lam == pytest.approx(1e-6) and any("low edge" in w for w in warnings) and evals == 13
