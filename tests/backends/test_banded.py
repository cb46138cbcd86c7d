"""The banded factorization of the direct back end (issue 18).

Agreement with the pivoted sparse LU on every least-squares item kind (hard and soft, with
and without error-model parameters in the border), the fallback when rows are not local,
the symbolic plan reused across lambda, and GCV's trace from the log-determinant against
the trace by exact columns.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp

import bvpnav
from bvpnav.constraints import AverageVelocity, Position, Symmetry, Velocity
from bvpnav.error_models import Bias, ScaleFactor
from bvpnav.items import registry
from bvpnav.lam.sweep import DirectSweep
from bvpnav.linalg.banded import MAX_BORDER, BandedKKT, BandPlan, NotBanded
from bvpnav.linalg.lsq import column_nodes, least_squares_form

#: Item kinds that are equality-constrained least squares in the hard and soft modes, whose
#: example is written for navigation-frame data (not for an example_model() of their own:
#: ZeroAngularRate needs strapdown data with a gyro model and acts on its parameters alone).
KINDS = sorted(k for k, cls in registry().items()
               if cls.example().kind == "equality" and cls.example_model() is None)


def problem(item=None, n: int = 801, error_model=None, seed: int = 3) -> bvpnav.NavigationProblem:
    """Three axes on [0, 10] s with non-uniform steps, soft end positions and a soft start
    velocity, plus ``item``."""
    rng = np.random.default_rng(seed)
    t = np.sort(np.r_[0.0, 10.0, rng.uniform(0.0, 10.0, n - 2)])

    def r(s):  # the true trajectory, m
        return np.column_stack([np.sin(s), np.cos(0.5 * s), 0.1 * s**2])

    acc = np.column_stack([-np.sin(t), -0.25 * np.cos(0.5 * t), np.full(n, 0.2)])
    acc += 0.05 * rng.standard_normal((n, 3))
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=0.05, error_model=error_model)
    prob.add(Position(t=[0.0, 10.0], value=r(np.array([0.0, 10.0])), sigma=0.1),
             Velocity(t=0.0, value=[1.0, 0.0, 0.0], sigma=0.1))
    if item is not None:
        prob.add(item)
    return prob


@pytest.mark.filterwarnings("ignore::bvpnav.log.BvpnavWarning")  # the examples' values misfit
@pytest.mark.parametrize("bias", [False, True], ids=["no-params", "bias"])
@pytest.mark.parametrize("mode", ["hard", "soft"])
@pytest.mark.parametrize("kind", KINDS)
def test_banded_agrees_with_the_pivoted_lu_on_every_item_kind(kind, mode, bias):
    """To 1e-10 of the trajectory's size, or to the conditioning floor where that is larger:
    three times the sum of the forward errors the verification estimates for the two
    answers (the banded one and the pivoted LU refined ten times; the difference of two
    answers is bounded by the sum of their errors). Measured: hard zero-velocity
    intervals 1e-9 to 3e-9 (each answer's estimate 0.8e-9 to 3.0e-9; a relative change
    of 1e-16 in the band, one ulp, moves the banded answer between those: the floor of
    the reference's estimate alone sat on that knife edge), hard symmetry 2.4e-8 (the LU
    fallback, both the same), everything else below 2e-10."""
    item = registry()[kind].example()
    if mode == "soft":
        item = dataclasses.replace(item, sigma=0.05, mode="soft")
    prob = problem(item, error_model=Bias() if bias else None)
    a = prob.solve(solver="direct", lam=1.3, options={"method": "banded"}, fallback=None)
    ref = prob.solve(solver="direct", lam=1.3, options={"method": "lu", "refine": 10}, fallback=None)
    assert a.stats["verified"] and ref.stats["verified"]
    floor = max(1e-10, 3.0 * (ref.stats["verification"]["forward_error"]
                              + a.stats["verification"]["forward_error"]))
    np.testing.assert_allclose(a.x, ref.x, rtol=0, atol=floor * np.max(np.abs(ref.x)))
    note = a.stats["factorization"]
    if kind == "symmetry":  # hundreds of rows pairing distant instants: a sparse factorization
        assert "not banded:" in note and "border" in note, note
    else:
        assert note.startswith("banded (kl="), note


def test_rows_that_reach_far_go_to_the_border_or_refuse_the_band():
    """A few far rows (two average velocities) sit in the border; a symmetry over the
    whole window pairs hundreds of distant instants: more than MAX_BORDER, so the plan
    refuses and names why (the solve then uses the sparse LDL^T)."""
    few = problem(registry()["average_velocity"].example(), n=401).formulation
    ls = least_squares_form(few, 1.0)
    plan = BandPlan.build(ls.D.A, ls.E.A, column_nodes(few.model), lam_rows=ls.lam_rows)
    assert 0 < plan.border <= 6 and plan.kl <= 6   # 2 instants x 3 axes at most, local band
    many = problem(Symmetry(about=5.0, halfwidth=4.9), n=401).formulation
    ls = least_squares_form(many, 1.0)
    with pytest.raises(NotBanded, match=rf"more than {MAX_BORDER}"):
        BandPlan.build(ls.D.A, ls.E.A, column_nodes(many.model), lam_rows=ls.lam_rows)


def test_local_rows_keep_one_axis_at_bandwidth_five_with_no_border():
    """Point fixes and the FEM rows of one axis: r_j and mu_j per node (w eliminated), the
    bandwidth set by the FEM multipliers' mass-matrix coupling (two nodes on)."""
    t = np.linspace(0.0, 20.0, 2001)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.sin(t)), sigma_a=0.05)
    prob.add(Position(t=t[::100], value=0.0, sigma=1.0), Position(t=0.0, value=0.0))
    ls = least_squares_form(prob.formulation, 1.0)
    fac = BandedKKT(ls.D.A, ls.E.A, column_nodes(prob.formulation.model), lam_rows=ls.lam_rows)
    assert fac.plan.border == 0 and fac.plan.kl <= 5
    assert fac.plan.size == 2 * t.size + 3   # r, mu per node; v0, v1; the hard position's mu
    z, steps, corr = fac.refined(ls.rhs(), 3, 1e-14)
    assert corr < 1e-10
    # the eliminated accelerations of one axis are one run: the solves index them by a slice
    assert isinstance(fac.plan.elim_index, slice)
    np.testing.assert_array_equal(np.arange(ls.D.A.shape[1])[fac.plan.elim_index], fac.plan.elim)
    # three axes interleave them with the positions: an index array, the same unknowns
    ls3 = least_squares_form(problem().formulation, 1.0)
    plan3 = BandedKKT(ls3.D.A, ls3.E.A, column_nodes(problem().formulation.model), lam_rows=ls3.lam_rows).plan
    assert not isinstance(plan3.elim_index, slice) and plan3.elim_index is plan3.elim


@pytest.mark.parametrize("lam", [1e-3, 0.7, 50.0])
def test_the_sweep_reuses_one_plan_and_matches_a_fresh_solve(lam):
    """Each lambda of the sweep combines two assembled parts (the band is affine in
    lambda) instead of assembling: the answer is the direct solve's at that lambda."""
    prob = problem(Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), n=601, error_model=Bias())
    sweep = DirectSweep(prob.formulation)
    assert sweep.factorization.startswith("banded")
    x = sweep.point(lam)["x"]
    assert sweep._parts  # the affine parts were used
    ref = prob.solve(solver="direct", lam=lam, options={"method": "lu"}, fallback=None)
    np.testing.assert_allclose(x, ref.x, rtol=0, atol=1e-10 * np.max(np.abs(ref.x)))


@pytest.mark.parametrize("bias", [False, True], ids=["no-params", "bias"])
@pytest.mark.parametrize("lam", [1e-2, 1.0, 1e2])
@pytest.mark.parametrize("item, complex_step, tol", [
    # folded lambda rows: the band is affine in lambda, one complex factor at lambda + ih
    # (exact to rounding: measured 2e-12 .. 1.7e-9 relative, the exact columns' own rounding)
    (Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), True, 1e-8),
    # a far-reaching lambda row in the border: a central difference of two more real
    # factors (truncation delta^2 / 6 = 1.7e-7 relative; measured 6e-9 .. 2.6e-7)
    (AverageVelocity(t0=[0.5], t1=[9.5], value=[0.1], sigma=0.05), False, 1e-6),
], ids=["complex-step", "central-difference"])
def test_gcv_trace_from_the_log_determinant_equals_the_trace_by_exact_columns(lam, bias, item, complex_step,
                                                                             tol):
    """On a small problem (the exact trace takes one solve per measured sample) the
    log-determinant formula, with the error-model priors' term, gives the same trace, by the
    complex step where the band is affine in lambda and by a central difference where not."""
    prob = problem(item, n=60, error_model=Bias() if bias else None)
    form = prob.formulation
    exact = DirectSweep(form, trace="exact")
    logdet = DirectSweep(form, trace="logdet")
    pa = exact.point(lam, need_trace=True)
    pb = logdet.point(lam, need_trace=True)
    a, b = pa["trace"], pb["trace"]
    assert exact.trace_method == "exact columns" and logdet.trace_method == "log-determinant"
    assert logdet.logdet_derivative == ("complex step" if complex_step else "central difference")
    assert abs(a - b) <= tol * abs(a), (a, b, abs(a - b) / abs(a))
    assert -3 * 60 < a < 0   # a trace of d w / d a_hat: between -N d and 0
    # the complex factor's solves (real parts) give the point and dx/dlambda: the curve's
    # quantities agree with the real factor's
    np.testing.assert_allclose(pb["x"], pa["x"], rtol=0, atol=1e-11 * np.max(np.abs(pa["x"])))
    assert abs(pb["deta2"] - pa["deta2"]) <= 1e-10 * abs(pa["deta2"])
    assert abs(pb["quasi"] - pa["quasi"]) <= 1e-6 * pa["quasi"]


@pytest.mark.parametrize("lam", [1.0, 1e3, 1e6])
def test_complex_step_points_keep_the_derivative_accurate_at_large_lambdas(lam):
    """dx/dlambda is solved for from the residuals with the complex factor (its real part),
    not read from the imaginary part of a solve with the right-hand side's derivative:
    there b' and K' x cancel inside the factorization, which lost 14 % of the
    quasi-optimality function at lambda = 1e6 on 2,000 samples and made a false minimum
    near 1e7. Every quantity of a GCV point equals the real path's. (Below lambda = 1e-3
    both paths' unrefined dx are noise next to a refined LU's: 2e-8 and 7e-8 against
    1.4e-9 at 1e-6, so they are not compared there.)"""
    form = problem(Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), n=2000, error_model=Bias()).formulation
    sweep = DirectSweep(form)   # the trace by the log-determinant (6,000 samples x axes)
    with_trace = sweep.point(lam, need_trace=True)
    assert sweep.logdet_derivative == "complex step"
    real = DirectSweep(form).point(lam)   # no trace: one real factor, two solves
    for key in ("rho2", "eta2", "deta2", "quasi"):
        assert abs(with_trace[key] - real[key]) <= 1e-6 * abs(real[key]), (key, with_trace[key], real[key])


def _affine_band(n: int):
    """``(formulation, plan, AffineBand)`` of three axes with a soft velocity item and a
    bias: the band along lambda as the sweep makes it."""
    from bvpnav.linalg.banded import AffineBand
    from bvpnav.linalg.lsq import banded_plan, least_squares_form
    from bvpnav.sparse import canonical

    form = problem(Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), n=n, error_model=Bias()).formulation
    ls = least_squares_form(form, 1.0)
    plan = banded_plan(ls, form)
    D, E = canonical(ls.D.A), canonical(ls.E.A)
    lam_rows = np.asarray(ls.lam_rows, dtype=bool)
    return form, plan, AffineBand(plan.assemble(D, E), plan.objective_part(D[lam_rows]), plan.kl)


@pytest.mark.parametrize("lam", [1e-3, 2.0])
def test_affine_band_at_a_complex_lambda_is_the_real_band_plus_the_step(lam):
    """The complex parts at lambda + ih are the real parts at lambda, scaled with the real
    lambda's scales, plus ih times the lambda part so scaled (the band is affine in lambda)."""
    from bvpnav.linalg.banded import _scale_rows

    form, plan, affine = _affine_band(n=301)
    h = 1e-3 * lam   # large enough to see the imaginary part next to the real one
    ab, B, C, hh, sU = affine.at(lam)
    abc, Bc, Cc, hc, sUc = affine.at_complex(lam, h)
    np.testing.assert_array_equal(abc.real, ab)
    np.testing.assert_array_equal(sUc, sU)
    np.testing.assert_array_equal(hc, hh)
    # the step by a difference of the real parts at lambda + h, scaled as at lambda
    ab2, *_ = affine.at(lam + h)
    want = ab2.copy()
    one = ab.shape[0]   # equal axes: the band is one run's, its scales the first run's
    _scale_rows(want, 1.0 / affine.at(lam + h)[4][:one], plan.kl)
    _scale_rows(want, sU[:one], plan.kl)
    np.testing.assert_allclose(abc.real + abc.imag, want, rtol=0, atol=1e-12 * np.max(np.abs(want)))
    np.testing.assert_allclose(Cc.imag, (affine.at(lam + h)[2] - C).real, rtol=1e-9,
                               atol=1e-12 * np.max(np.abs(C)))
    np.testing.assert_allclose(Bc.toarray().imag, (affine.at(lam + h)[1] - B).toarray(), rtol=1e-9,
                               atol=1e-12 * abs(B).max())


@pytest.mark.parametrize("lam", [1e-2, 3.0])
def test_a_far_reaching_lambda_row_assembles_at_every_lambda(lam):
    """A soft average velocity over most of the window sits in the border with a sqrt(lam)
    weight: the band is not affine in lambda there, so the sweep assembles each lambda (the
    plan's own assembly at lambda = 1 must not be taken for another lambda)."""
    prob = problem(AverageVelocity(t0=[0.5], t1=[9.5], value=[0.1], sigma=0.05), n=601)
    sweep = DirectSweep(prob.formulation)
    x = sweep.point(lam)["x"]
    assert sweep._parts is False
    ref = prob.solve(solver="direct", lam=lam, options={"method": "lu"}, fallback=None)
    np.testing.assert_allclose(x, ref.x, rtol=0, atol=1e-10 * np.max(np.abs(ref.x)))


@pytest.mark.parametrize("lam", [1e-4, 0.3, 1.0, 7e3])
def test_affine_band_at_a_lambda_is_the_scaled_assembly_there(lam):
    """AffineBand recomputes only the rows a lambda-weighted row touches (and their
    neighbours' scaling): the scaled band and scale equal assembling and scaling afresh, to
    the rounding of the combination A(1) + (lam - 1) A_1 (an entry made of lambda rows
    alone carries an absolute error of about eps times its size at lambda = 1, a relative
    one of eps / lam: hence the tolerance's 1 / lam below 1)."""
    from bvpnav.linalg.lsq import least_squares_form
    from bvpnav.sparse import canonical

    form, plan, affine = _affine_band(n=601)
    assert 0 < affine.rows.size < plan.size   # a few rows, not the whole band
    ab, B, C, h, sU = affine.at(lam)
    at = least_squares_form(form, lam)
    ref_ab, ref_B, ref_C, ref_h, ref_sU = plan.assemble(canonical(at.D.A), canonical(at.E.A))
    tol = 1e-14 * max(1.0, 1.0 / lam)
    np.testing.assert_allclose(sU, ref_sU, rtol=tol)
    np.testing.assert_allclose(ab, ref_ab, rtol=0, atol=tol * np.max(np.abs(ref_ab)))
    np.testing.assert_allclose(C, ref_C, rtol=1e-12, atol=1e-12 * np.max(np.abs(ref_C)))
    np.testing.assert_allclose(B.toarray(), ref_B.toarray(), rtol=1e-12, atol=1e-12 * abs(ref_B).max())
    np.testing.assert_array_equal(h, ref_h)


def test_gcv_trace_falls_back_to_probes_when_a_neighbour_factor_is_not_banded(monkeypatch):
    """The log-determinant needs banded factors at lambda e^(+-delta); where the banded
    factor fails there and the sparse LU takes over (it has no log-determinant), the trace
    comes from Hutchinson's probes instead, named in ``trace_method``, and agrees with the
    exact trace within the probes' standard error."""
    from bvpnav.linalg.lsq import factor_form

    prob = problem(Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), n=60)
    form = prob.formulation
    exact = DirectSweep(form, trace="exact").point(1.0, need_trace=True)["trace"]
    sweep = DirectSweep(form, trace="logdet", probes=200)
    real = sweep._factor
    monkeypatch.setattr(sweep, "_combined", lambda lam, buffer=0, h=0.0: None)
    monkeypatch.setattr(sweep, "_factor", lambda f, lam=None, **kw: real(f, lam) if lam == 1.0
                        else factor_form(f, form))
    est = sweep.point(1.0, need_trace=True)["trace"]
    assert sweep.trace_method.startswith("Hutchinson (200 probes); no log-determinant: the banded "
                                         "factor failed at lambda=1.001"), sweep.trace_method
    se = np.sqrt(2 * abs(exact) / 200)   # Rademacher probes: sd <= sqrt(2 |tr B| / P)
    assert abs(est - exact) < 4 * se, (est, exact, se)


@pytest.mark.parametrize("item, runs", [
    (Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), 3),                  # the same on every axis
    (Position(t=[3.0], value=[0.5], axes=("x",), sigma=0.05), 1),        # a local row on x only
], ids=["equal-axes", "one-axis-item"])
@pytest.mark.parametrize("bias", [False, True], ids=["no-params", "bias"])
def test_equal_axes_factor_one_band_and_solve_the_others_as_right_hand_sides(item, runs, bias):
    """Three axes laid end to end whose band rows are equal (one grid, one sigma_a, the
    same local items) factor one axis' band; a local item on one axis makes them differ
    and the whole band is factored. Either way the answer is the pivoted LU's to 1e-10,
    and the log-determinant is the whole band's."""
    prob = problem(item, error_model=Bias() if bias else None)
    form = prob.formulation
    ls = least_squares_form(form, 1.0)
    fac = BandedKKT(ls.D.A, ls.E.A, column_nodes(form.model), params=form.model.l_index,
                    plan=BandPlan.build(ls.D.A, ls.E.A, column_nodes(form.model), segments=3))
    whole = BandedKKT(ls.D.A, ls.E.A, column_nodes(form.model), params=form.model.l_index)
    assert fac.plan.segments == 3 and fac._runs == runs and whole._runs == 1
    assert fac._lu.shape[1] == fac.plan.size // runs
    rhs = ls.rhs()
    ref = prob.solve(solver="direct", options={"method": "lu"}, fallback=None).x
    m, n = ls.D.A.shape
    x = fac.refined(rhs, 2)[0][m:m + n]
    np.testing.assert_allclose(x, ref, rtol=0, atol=1e-10 * np.max(np.abs(ref)))
    assert abs(fac.logdet() - whole.logdet()) <= 1e-9 * abs(whole.logdet())
    if bias:   # the border's Schur complement (the parameters' information) is the same too
        np.testing.assert_allclose(fac.schur, whole.schur, rtol=1e-9)
        # A^{-1} B is kept by runs: a parameter of one axis has a column on that axis alone
        kept = sum(Xa.size for _, _, Xa in fac._xruns)
        assert kept == fac.plan.size // runs * (form.model.q if runs > 1 else fac.k)


@pytest.mark.parametrize("by_diagonals", [True, False], ids=["strided", "entry-by-entry"])
@pytest.mark.parametrize("item, equal", [
    (Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), True),             # the same on every axis
    (Position(t=[3.0], value=[0.5], axes=("x",), sigma=0.05), False),   # a local row on x only
], ids=["equal-axes", "one-axis-item"])
def test_equal_axes_are_assembled_as_one_run_of_the_whole_band(item, equal, by_diagonals, monkeypatch):
    """When every axis' entries are the first axis' moved by a run (compared as they are
    held: strided diagonals and sorted cells), the assembly writes the first run alone; the
    whole band, written entry by entry, is that run repeated. Otherwise the whole band; and
    with too many cells to sort (a large problem's FEM rows entry by entry) the whole band
    too, whose equal runs the factorization then finds itself."""
    from bvpnav.linalg import banded
    from bvpnav.linalg.banded import _Stride
    from bvpnav.linalg.lsq import fem_rows_by_diagonals
    from bvpnav.sparse import canonical

    prob = problem(item, error_model=Bias())
    form = prob.formulation
    ls = least_squares_form(form, 1.0)
    D, E = canonical(ls.D.A), canonical(ls.E.A)
    diagonal = fem_rows_by_diagonals(form) if by_diagonals else None
    plan = BandPlan.build(D, E, column_nodes(form.model), segments=3, diagonal=diagonal)
    ab = plan._scatter(plan._entries(D, E, diagonal))[0]
    entries = plan._entries(D, E, diagonal)[0]
    assert any(isinstance(e, _Stride) for e in entries) == by_diagonals
    whole = plan._write_band([e for e in entries if isinstance(e, _Stride)],
                             [e for e in entries if not isinstance(e, _Stride)])
    assert whole.shape[0] == plan.size
    if equal:
        assert ab.shape[0] == plan.size // 3
        np.testing.assert_array_equal(np.tile(ab, (3, 1)), whole)
    else:
        np.testing.assert_array_equal(ab, whole)
    monkeypatch.setattr(banded, "MIN_SORTED_CELLS", 0)
    monkeypatch.setattr(banded, "MANY_CELLS", 10**9)   # no cell may be sorted
    parts = plan._scatter(plan._entries(D, E, diagonal), scaled=True)
    assert any(not isinstance(e, _Stride) and e[0].size for e in entries)   # cells to sort
    assert parts[0].shape[0] == plan.size
    fac = BandedKKT(ls.D.A, ls.E.A, params=form.model.l_index, plan=plan, parts=parts)
    assert fac._runs == (3 if equal else 1)


@pytest.mark.parametrize("case", ["1-axis", "3-axes-bias", "hard-zero-velocity", "scale-factor"])
def test_fem_rows_placed_by_diagonals_equal_the_entry_by_entry_assembly(case):
    """The FEM rows described by their diagonals (lsq.fem_rows_by_diagonals) give the same
    plan, and assemble the same band, border coupling and border as the entry-by-entry
    path, to rounding in the
    summed -E_z h^-1 E_z^T; hard zero-velocity rows on the acceleration residuals make
    that block come from the generic product, and a description that does not match E
    (an entry missing) is not used."""
    from bvpnav.constraints import ZeroVelocity
    from bvpnav.linalg.lsq import fem_rows_by_diagonals
    if case == "1-axis":
        prob = problem(n=301)
        t, acc = prob.data.t, prob.data.acc[:, 0]
        prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=0.05)
        prob.add(Position(t=[0.0, 10.0], value=[0.0, 1.0]),
                 Position(t=[2.5, 6.1], value=[0.3, 0.7], sigma=0.1))
    else:
        em = {"3-axes-bias": Bias(), "scale-factor": ScaleFactor() + Bias()}.get(case)
        prob = problem(ZeroVelocity(t0=4.0, t1=5.0) if case == "hard-zero-velocity" else None, n=301,
                       error_model=em)
    form = prob.formulation
    ls = least_squares_form(form, 1.0)
    D, E = ls.D.A, ls.E.A
    plan = BandPlan.build(D, E, column_nodes(form.model), lam_rows=ls.lam_rows)
    diagonal = fem_rows_by_diagonals(form)
    assert diagonal.matches(E)
    # the symbolic analysis from the diagonals (spans, reach) orders every unknown the same
    by_diagonals = BandPlan.build(D, E, column_nodes(form.model), lam_rows=ls.lam_rows, diagonal=diagonal)
    for name in ("pos", "bpos", "elim", "fold"):
        np.testing.assert_array_equal(getattr(by_diagonals, name), getattr(plan, name))
    assert by_diagonals.kl == plan.kl
    ab, B, C, h = plan._scatter(plan._entries(D, E, diagonal))
    ab0, B0, C0, h0 = plan._scatter(plan._entries(D, E))
    np.testing.assert_allclose(ab, ab0, rtol=0, atol=1e-14 * np.max(np.abs(ab0)))
    np.testing.assert_array_equal(h, h0)
    np.testing.assert_array_equal(C, C0)
    if B0 is not None:
        np.testing.assert_array_equal(B.toarray(), B0.toarray())
    if diagonal.dense:   # one parameter column left out: the description no longer matches E
        broken = dataclasses.replace(diagonal, dense=diagonal.dense[1:])
        assert not broken.matches(E)


@pytest.mark.parametrize("case", ["points", "bias", "zero-velocity", "average-velocity"])
def test_the_band_scaled_as_it_is_placed_equals_scaling_the_placed_band(case):
    """The assembly scales the band from its entries' column maxima as it places them;
    that is scale_band on the placed band (column maxima of the whole band), entry for
    entry, with the border parts untouched."""
    from bvpnav.constraints import ZeroVelocity
    from bvpnav.linalg.banded import scale_band

    item = {"points": None, "bias": None, "zero-velocity": ZeroVelocity(t0=4.0, t1=5.0),
            "average-velocity": AverageVelocity(t0=[0.5], t1=[9.5], value=[0.1], sigma=0.05)}[case]
    prob = problem(item, n=301, error_model=Bias() if case == "bias" else None)
    form = prob.formulation
    ls = least_squares_form(form, 1.0)
    D, E = ls.D.A, ls.E.A
    plan = BandPlan.build(D, E, column_nodes(form.model), lam_rows=ls.lam_rows)
    ab, B, C, h, sU = plan._scatter(plan._entries(D, E), scaled=True)
    ref, B0, C0, h0 = plan._scatter(plan._entries(D, E))
    ref_sU = scale_band(ref, plan.kl)
    np.testing.assert_allclose(sU, ref_sU, rtol=1e-15)
    np.testing.assert_allclose(ab, ref, rtol=0, atol=1e-15 * np.max(np.abs(ref)))
    np.testing.assert_array_equal(C, C0)
    if B0 is not None:
        np.testing.assert_array_equal(B.toarray(), B0.toarray())


def test_augmented_operator_residual_and_largest_entry_equal_the_dense_matrix():
    """``residual`` is ``rhs - S z`` (into a given buffer too) and ``max_abs`` the largest
    absolute entry of the dense augmented matrix, a lower bound of its infinity norm; random
    shapes with empty rows and columns."""
    import scipy.sparse as sp

    from bvpnav.linalg.banded import AugmentedOperator

    rng = np.random.default_rng(0)
    for trial in range(20):
        m, n, p = (int(v) for v in rng.integers(1, 30, 3))
        D = sp.random(m, n, density=0.2, random_state=trial, format="csr")
        E = sp.random(p, n, density=0.15, random_state=trial + 100, format="csr")
        D.data -= 0.5
        E.data -= 0.5
        S = sp.bmat([[-sp.identity(m), D, None], [D.T, None, E.T], [None, E, None]]).toarray()
        op = AugmentedOperator(D, E)
        assert op.max_abs() == np.abs(S).max() <= np.abs(S).sum(axis=1).max()
        z, rhs = rng.normal(size=(2, m + n + p))
        want = rhs - S @ z
        np.testing.assert_allclose(op.residual(rhs, z), want, rtol=1e-13, atol=1e-14)
        buf = np.full_like(rhs, np.nan)
        assert op.residual(rhs, z, out=buf) is buf
        np.testing.assert_allclose(buf, want, rtol=1e-13, atol=1e-14)


@pytest.mark.parametrize("slice_rows", [7, 64, 1000])
def test_the_band_written_a_slice_at_a_time_equals_writing_each_block_whole(slice_rows, monkeypatch):
    """Long sorted writes go into the band a slice of rows at a time (all blocks' parts in
    one slice together); with slices of a few rows (many cuts, blocks ending mid-slice) the
    band is the same as writing every block at once."""
    import bvpnav.linalg.banded as banded
    from bvpnav.constraints import ZeroVelocity
    from bvpnav.linalg.lsq import fem_rows_by_diagonals

    prob = problem(ZeroVelocity(t0=4.0, t1=5.0), n=801, error_model=Bias())
    form = prob.formulation
    ls = least_squares_form(form, 1.0)
    D, E = ls.D.A, ls.E.A
    plan = BandPlan.build(D, E, column_nodes(form.model), lam_rows=ls.lam_rows)
    diagonal = fem_rows_by_diagonals(form)
    monkeypatch.setattr(banded, "SCATTER_SLICE", 10**9)   # every block written whole
    whole = plan._scatter(plan._entries(D, E, diagonal), scaled=True)
    monkeypatch.setattr(banded, "SCATTER_SLICE", slice_rows)
    sliced = plan._scatter(plan._entries(D, E, diagonal), scaled=True)
    np.testing.assert_array_equal(sliced[0], whole[0])
    np.testing.assert_array_equal(sliced[4], whole[4])


def test_the_plans_memos_answer_for_their_own_arrays_and_free_the_ones_they_drop():
    """BandPlan remembers the band positions of large blocks by their index content
    (_placed) and the flat band indices of those position arrays by identity (_flat_index):
    a position array dropped from the first memo is freed (the memos keep no other
    reference), and a new array that takes its memory and id gets its own flat index, not
    the dropped one's."""
    import gc
    import weakref

    from bvpnav.linalg.banded import MEMO_ENTRIES, MEMO_PER_KEY

    prob = problem(n=801)
    ls = least_squares_form(prob.formulation, 1.0)
    plan = BandPlan.build(ls.D.A, ls.E.A, column_nodes(prob.formulation.model), lam_rows=ls.lam_rows)
    assert plan.border == 0
    band = np.flatnonzero(plan.pos >= 0)
    rng = np.random.default_rng(5)

    def flat(j, i):
        return j.astype(np.int64) * (plan.ldab - 1) + i + 2 * plan.kl

    dropped, reused = [], 0
    for _ in range(10):   # MEMO_PER_KEY + 1 patterns of one key (size and ends): the oldest dropped
        for _ in range(MEMO_PER_KEY + 1):
            r = band[:MEMO_ENTRIES + 10].copy()
            r[1:-1] = np.sort(rng.choice(band[1:MEMO_ENTRIES + 9], r.size - 2))
            c = band[:r.size]
            keep, pi, pj = plan._placed(r, c)
            assert keep is None
            np.testing.assert_array_equal(plan._flat_index(pi, pj), flat(plan.pos[r], plan.pos[c]))
            dropped.append((weakref.ref(pi), weakref.ref(pj), id(pi), id(pj)))
            del pi, pj
        gc.collect()
        gone = {k for wi, wj, *ids in dropped if wi() is None and wj() is None for k in ids}
        for _ in range(8):   # new position arrays, some in the memory of dropped ones
            a, b = plan.pos[rng.choice(band, 7)], plan.pos[rng.choice(band, 7)]
            reused += id(a) in gone or id(b) in gone
            np.testing.assert_array_equal(plan._flat_index(a, b), flat(a, b))
    assert sum(wi() is None and wj() is None for wi, wj, *_ in dropped) == len(dropped) - MEMO_PER_KEY
    assert reused > 0   # ids were reused: the check above met that case
    assert len(plan._flat_memo) <= len(plan._memo_owned)   # two orientations per kept block at most


def test_evenly_spaced_positions_are_found_as_runs_and_the_rest_goes_entry_by_entry():
    """_affine_runs splits a block's band positions into stretches written as strided
    slices (step > 0), stretches of unknowns in neither band nor border (step 0: their
    entries dropped) and the rest (None: placed entry by entry): the run boundaries fall
    where the step changes, short stretches join the irregular ones."""
    from bvpnav.linalg.banded import MIN_STRIDE_RUN, _affine_runs

    k = 3 * MIN_STRIDE_RUN
    a = 2 * np.arange(k)                              # one axis: r_j, mu_j interleaved
    b = np.array([2 * k + 3, 2 * k + 4, 2 * k + 8])   # a node holding extra unknowns
    c = 2 * k + 11 + 3 * np.arange(k)                 # step 3
    p = np.concatenate([a, b, c, np.full(k, -1)])
    absent = np.r_[np.zeros(2 * k + 3, bool), np.ones(k, bool)]
    # a run ends where the next difference starts (its last point begins the next run):
    # b's last point continues c's step, c's last point is alone before the -1s
    assert _affine_runs(p, absent) == [(0, k - 1, 0, 2), (k - 1, k + 2, None, None),
                                       (k + 2, 2 * k + 2, 2 * k + 8, 3), (2 * k + 2, 2 * k + 3, None, None),
                                       (2 * k + 3, 3 * k + 3, -1, 0)]
    # the -1 stretch in the border is not dropped: it joins the irregular point before it
    assert _affine_runs(p, ~absent)[-1] == (2 * k + 2, 3 * k + 3, None, None)
    for u0, u1, p0, s in _affine_runs(p, absent):
        if s is not None:
            np.testing.assert_array_equal(p[u0:u1], p0 + s * np.arange(u1 - u0))
    # a block shorter than a run, or too fragmented, is one irregular stretch
    assert _affine_runs(a[:MIN_STRIDE_RUN - 1], None) == [(0, MIN_STRIDE_RUN - 1, None, None)]
    zigzag = np.arange(4 * MIN_STRIDE_RUN) ^ 1
    assert _affine_runs(zigzag, None) == [(0, zigzag.size, None, None)]


@pytest.mark.parametrize("item", ["points", "zero-velocity", "bias"])
def test_the_strided_band_writes_equal_the_entry_by_entry_writes(item, monkeypatch):
    """The FEM diagonals written as strided slices of the band (_Stride) give the band, its
    scale, the border coupling and the border bit for bit as placing every entry by index
    (MIN_STRIDE_RUN beyond any block: no run qualifies)."""
    import bvpnav.linalg.banded as banded
    from bvpnav.constraints import ZeroVelocity
    from bvpnav.linalg.lsq import fem_rows_by_diagonals

    prob = problem(ZeroVelocity(t0=4.0, t1=5.0) if item == "zero-velocity" else None, n=801,
                   error_model=Bias() if item == "bias" else None)
    form = prob.formulation
    ls = least_squares_form(form, 1.0)
    D, E = ls.D.A, ls.E.A
    diagonal = fem_rows_by_diagonals(form)
    plan = BandPlan.build(D, E, column_nodes(form.model), lam_rows=ls.lam_rows, diagonal=diagonal)
    entries = plan._entries(D, E, diagonal)
    assert sum(isinstance(e, banded._Stride) for e in entries[0]) >= 3
    strided = plan._scatter(entries, scaled=True)
    monkeypatch.setattr(banded, "MIN_STRIDE_RUN", 10**9)
    entries = plan._entries(D, E, diagonal)
    assert not any(isinstance(e, banded._Stride) for e in entries[0])
    indexed = plan._scatter(entries, scaled=True)
    for a, b in zip(strided, indexed, strict=True):
        if b is None:
            assert a is None
        else:
            dense = [x.toarray() if hasattr(x, "toarray") else x for x in (a, b)]
            np.testing.assert_array_equal(*dense)


@pytest.mark.parametrize("error_model", [Bias(), ScaleFactor() + Bias()], ids=["B", "SF+B"])
def test_border_coupling_by_columns_equals_the_summed_coo_assembly(error_model):
    """The error-model parameters' coupling is laid out column by column from its blocks
    (each a dense FEM column of one parameter); it equals the COO assembly, which sums
    duplicates, and a column reached by two blocks, or rows out of order, take that
    assembly instead (None)."""
    from bvpnav.linalg.banded import _coupling_by_columns
    from bvpnav.linalg.lsq import banded_plan, fem_rows_by_diagonals, least_squares_form

    prob = problem(n=201, error_model=error_model)
    form = prob.formulation
    ls = least_squares_form(form, 1.0)
    plan = banded_plan(ls, form)
    entries = plan._entries(ls.D.A, ls.E.A, fem_rows_by_diagonals(form))
    cpl = entries[1]
    nb, k = plan.pos_order.size, plan.border_order.size
    fast = _coupling_by_columns(cpl, nb, k)
    assert fast is not None and k == form.model.q
    rows, cols, vals = (np.concatenate([c[t] for c in cpl]) for t in range(3))
    coo = sp.csc_matrix((vals, (rows, cols)), shape=(nb, k))
    assert fast.nnz == coo.nnz > 0
    np.testing.assert_array_equal(fast.toarray(), coo.toarray())
    # canonical as declared (checked afresh on the arrays, not taken from the flag)
    assert sp.csc_matrix((fast.data, fast.indices, fast.indptr), shape=fast.shape).has_canonical_format
    # a second block in a column: the conversion must sum them
    r0, c0, v0 = next(c for c in cpl if c[0].size)
    assert _coupling_by_columns([*cpl, (r0[:3], c0[:3], v0[:3])], nb, k) is None
    # rows out of order in a block
    assert _coupling_by_columns([(r0[::-1], c0, v0)], nb, k) is None
    # a block over two columns
    two = np.where(np.arange(r0.size) % 2 == 0, c0, (c0 + 1) % k)
    assert _coupling_by_columns([(r0, two, v0)], nb, k) is None


def _one_axis():
    t = np.linspace(0.0, 10.0, 301)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.sin(t)), sigma_a=0.05)
    # end velocities (interior ones would keep the accelerations they touch out of the
    # eliminated run: a lambda row touches them)
    return prob.add(Position(t=t[::30], value=0.0, sigma=1.0), Position(t=0.0, value=0.0),
                    Velocity(t=[0.0, 10.0], value=0.3, sigma=0.05))


@pytest.mark.parametrize("make", [
    lambda: problem(Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), n=301),
    lambda: problem(Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), n=301, error_model=Bias()),
    _one_axis], ids=["no-border", "border", "one-axis"])
def test_the_real_part_of_a_complex_factors_solve_is_taken_after_the_real_maps(make):
    """``solve_x_real`` keeps the eliminations, scalings, gathers and scatters real and
    takes the real part after the band's (and the border's) complex solve: equal to the
    real part of the all-complex ``solve_x``, for one and for several right-hand sides, and
    the same as ``solve_x`` for a real factor; with three axes the eliminated unknowns are
    an index array, with one a slice (``BandPlan.elim_index``)."""
    from bvpnav.linalg.banded import AffineBand
    from bvpnav.linalg.lsq import banded_plan
    from bvpnav.sparse import canonical

    form = make().formulation
    ls = least_squares_form(form, 1.0)
    plan = banded_plan(ls, form)
    D, E = canonical(ls.D.A), canonical(ls.E.A)
    lam_rows = np.asarray(ls.lam_rows, dtype=bool)
    affine = AffineBand(plan.assemble(D, E), plan.objective_part(D[lam_rows]), plan.kl)
    lam = 3.0
    at = ls.at_lam(lam)
    cplx = BandedKKT(at.D.A, at.E.A, plan=plan, parts=affine.at_complex(lam, 1e-3 * lam))
    assert (cplx.k > 0) == (form.model.q > 0)
    assert isinstance(plan.elim_index, slice) == (form.model.d == 1)
    rng = np.random.default_rng(0)
    for rhs in (at.rhs(), rng.standard_normal((at.rhs().size, 3))):
        want = cplx.solve_x(rhs).real
        np.testing.assert_allclose(cplx.solve_x_real(rhs), want, rtol=0, atol=1e-13 * np.max(np.abs(want)))
    real = BandedKKT(at.D.A, at.E.A, plan=plan, parts=affine.at(lam))
    np.testing.assert_array_equal(real.solve_x_real(at.rhs()), real.solve_x(at.rhs()))
    with pytest.raises(TypeError, match="real right-hand side"):
        cplx.solve_x_real(at.rhs() * 1j)


def test_row_scaling_keeps_a_canonical_matrix_marked_and_a_zero_scale_is_scanned_again():
    """``row_scaled`` (a lambda's rows) keeps the canonical mark of its source when no scale
    is zero, so ``canonical`` returns it as it is; a zero scale makes explicit zeros, which
    ``canonical`` then removes (an explicit zero must not tie a row to a node)."""
    from bvpnav.sparse import canonical, row_scaled

    A = canonical(sp.csr_matrix(np.array([[1.0, 0.0, 2.0], [0.0, 3.0, 0.0]])))
    B = row_scaled(A, np.array([2.0, 0.5]))
    assert canonical(B) is B
    np.testing.assert_array_equal(B.toarray(), [[2.0, 0.0, 4.0], [0.0, 1.5, 0.0]])
    C = row_scaled(A, np.array([1.0, 0.0]))
    assert C.nnz == 3 and canonical(C).nnz == 2
    np.testing.assert_array_equal(canonical(C).toarray(), [[1.0, 0.0, 2.0], [0.0, 0.0, 0.0]])


@pytest.mark.parametrize("axes", [1, 3])
def test_band_rows_move_by_slices_and_give_the_index_arrays_own_answer(axes):
    """``BandPlan.moves`` gathers and scatters the band rows by a few strided slices (an
    axis interleaves ``r_j`` and ``mu_j``: period 2, two runs per axis) and an index array
    for the rest: the same arrays as numpy's fancy indexing with ``pos_order``, for one and
    several right-hand sides."""
    from bvpnav.linalg.lsq import banded_plan

    prob = problem(n=2001, error_model=Bias() if axes == 3 else None)
    if axes == 1:
        data = prob.data
        prob = bvpnav.NavigationProblem(bvpnav.ImuData(data.t, data.acc[:, 0]), sigma_a=0.05)
        prob.add(Position(t=[0.0, 10.0], value=0.0, name="ends"))
        prob.add(Position(t=np.arange(0.5, 10.0, 1.0), value=0.1, sigma=1.0, name="fixes"))
    form = prob.formulation
    ls = least_squares_form(form, 1.0)
    plan = banded_plan(ls, form)
    moves = plan.moves
    # a handful of slices and a few loose rows, not an index array for everything
    assert 0 < len(moves.pairs) <= 2 * axes and moves.band_rest.size < 64
    rng = np.random.default_rng(1)
    for r in (rng.standard_normal(plan.pos.size), rng.standard_normal((plan.pos.size, 3))):
        np.testing.assert_array_equal(moves.gather(r), r[plan.pos_order])
        y = rng.standard_normal((plan.size,) + r.shape[1:])
        out, want = np.zeros_like(r), np.zeros_like(r)
        moves.scatter(y, out)
        want[plan.pos_order] = y
        np.testing.assert_array_equal(out, want)


@pytest.mark.parametrize("seed", range(4))
def test_moves_of_an_arbitrary_order_equal_fancy_indexing(seed):
    """Orders that are not runs (a random permutation), runs with a remainder, and periods
    up to the limit: ``_Moves`` falls back to index arrays where slices do not cover."""
    from bvpnav.linalg.banded import _Moves

    rng = np.random.default_rng(seed)
    n = 3000
    orders = [rng.permutation(n),
              np.concatenate([[2999, 5], np.arange(1000, 2000), rng.permutation(np.arange(6, 1000))]),
              np.stack([np.arange(0, 1000), np.arange(1000, 2000), np.arange(2000, 3000)], 1).ravel(),
              np.arange(n)[::-1].copy()]
    for order in orders:
        moves = _Moves(order.astype(np.int32))
        r = rng.standard_normal(n)
        np.testing.assert_array_equal(moves.gather(r), r[order])
        y = rng.standard_normal(order.size)
        out, want = np.zeros(n), np.zeros(n)
        moves.scatter(y, out)
        want[order] = y
        np.testing.assert_array_equal(out, want)
    assert len(_Moves(orders[2]).pairs) == 3 and _Moves(orders[2]).band_rest.size == 0   # period 3
    assert _Moves(orders[0]).pairs == [] and _Moves(orders[0]).band_rest.size == n        # no runs


def test_an_answer_whose_last_step_moved_the_residuals_is_refused():
    """The backward error is the answer's own (after the last step), not that of the iterate
    before it: a factor exact on ``x`` but wrong elsewhere converges on the window (the
    correction 1e-12) while the off-window part grows; the answer is refused with the
    reason, where judging the previous iterate accepted it (found in review)."""
    from bvpnav.linalg.banded import Factorization
    from bvpnav.linalg.lsq import _accepted

    class Stub(Factorization):   # S = I; the factor is slightly off on x and far off elsewhere
        def __init__(self):
            self.S = sp.identity(2, format="csr")
            self.M = np.diag([1.0 - 1e-4, 1001.0])

        def solve(self, r):
            return self.M @ r

    notes: list = []
    z, k, corr = _accepted(Stub(), np.array([1.0, 1e-22]), slice(0, 1), 30, 1e-12, 1e-7, notes, "ldl")
    assert z is None and corr < 1e-11
    assert notes and "backward error" in notes[0]


@pytest.mark.parametrize("lam", [1e-4, 1.0])
def test_banded_refinement_stops_at_the_presets_tolerance_with_the_answer_at_the_rounding_floor(lam):
    """The banded answer's refinement stops once the correction is below the preset's
    ``refine_tol`` (a hundredth of its forward-error bound: 1e-8 by default). On this
    problem the rounding floor is about 2e-10: the default takes one step, ``high``
    (1e-10) refines until the corrections stall, and the answers agree with each other and
    with the pivoted sparse LU far inside 1e-8 (measured 1e-10 .. 4e-10)."""
    from bvpnav.linalg.lsq import BANDED_TOL, FORWARD_RTOL

    assert all(BANDED_TOL[k] == pytest.approx(1e-2 * FORWARD_RTOL[k]) for k in FORWARD_RTOL)
    prob = problem(Velocity(t=[2.0, 7.0], value=0.3, sigma=0.05), n=4001)
    default = prob.solve(solver="direct", lam=lam, fallback=None)
    high = prob.solve(solver="direct", lam=lam, accuracy="high", fallback=None)
    forced = prob.solve(solver="direct", lam=lam, options={"refine_tol": 1e-16}, fallback=None)
    lu = prob.solve(solver="direct", lam=lam, options={"method": "lu"}, fallback=None)
    assert default.stats["refinements"] == 1 and default.stats["correction"] <= 1e-8
    assert high.stats["refinements"] >= 2 and forced.stats["refinements"] >= 2
    assert default.stats["verified"] and high.stats["verified"]
    scale = np.max(np.abs(lu.x))
    for other in (high, lu):
        assert np.max(np.abs(default.x - other.x)) <= 1e-8 * scale
