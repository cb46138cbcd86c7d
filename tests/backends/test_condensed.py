"""The lambda sweep's condensed band (bvpnav.linalg.condensed.CondensedBand, CondensedKKT): the
unknowns lambda does not touch factored once, a small system per lambda. Its curve points
must be the whole band's, its selection of the kept unknowns must leave a nonsingular
interior with every kind of item, and it must step aside where it does not apply."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import bvpnav
from bvpnav.constraints import Position, Velocity, ZeroVelocity
from bvpnav.error_models import Bias
from bvpnav.lam.sweep import DirectSweep
from bvpnav.linalg.banded import BandedKKT, NotBanded
from bvpnav.linalg.condensed import CondensedBand, CondensedKKT


def fixes(extra=(), n: int = 4001, every: int = 80, seed: int = 0,
          error_model=None) -> bvpnav.NavigationProblem:
    """One axis over 40 s with non-uniform steps, hard end positions and a soft position
    fix every ``every`` samples (the lambda-weighted rows), plus ``extra`` items."""
    rng = np.random.default_rng(seed)
    t = np.sort(np.r_[0.0, 40.0, rng.uniform(0.0, 40.0, n - 2)])
    acc = -0.2 * np.sin(0.2 * t) + 0.05 * rng.standard_normal(n)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=0.05, error_model=error_model)
    fix = t[every // 2::every]
    prob.add(Position(t=[0.0, 40.0], value=[0.0, 5.0 * np.sin(8.0)], name="ends"),
             Position(t=fix, value=5.0 * np.sin(0.2 * fix) + 0.3 * rng.standard_normal(fix.size),
                      sigma=0.3, name="fixes"))
    for item in extra:
        prob.add(item)
    return prob


EXTRAS = {
    "fixes only": (),
    "a hard position inside": (Position(t=[17.3], value=[5.0 * np.sin(3.46)], name="mid"),),
    "soft velocities inside elements": (Velocity(t=[9.51, 30.07], value=[0.9, 0.96], sigma=0.05),),
    "a hard zero-velocity interval": (ZeroVelocity(t0=20.0, t1=21.5),),
    "a soft zero-velocity interval": (ZeroVelocity(t0=10.0, t1=11.0, sigma=0.01),),
}
KEYS = ("rho2", "eta2", "deta2", "d2eta2", "quasi")


class _Refined(BandedKKT):
    """A whole-band factor whose curve-point solves are refined three times (the
    reference the two unrefined paths are measured against)."""

    def _x(self, rhs):
        m, n = self.plan.m, self.plan.n
        return self.refined(np.asarray(rhs, dtype=float), 3, 0.0)[0][m:m + n]

    def solve_x(self, rhs):
        return self._x(rhs)

    def solve_x_real(self, rhs, eliminated=True, interior=True):
        return self._x(rhs)


def _reference(prob):
    ref = DirectSweep(prob.formulation, condense=False)
    plain = ref._factor

    def refined(form, lam=None, **kw):
        fac = copy.copy(plain(form, lam))
        fac.__class__ = _Refined
        return fac

    ref._factor = refined
    return ref


@pytest.mark.parametrize("extra", list(EXTRAS), ids=list(EXTRAS))
def test_condensed_points_are_as_accurate_as_the_whole_bands(extra):
    """Over lambda = 1e-4 .. 1e4, the worst relative error of a curve point's quantities
    from a small factorization per lambda, against a thrice-refined answer, is within 10
    times the worst of the whole band's unrefined factorization (or 1e-8), with hard rows,
    velocities inside elements and zero-velocity intervals among the fixes: the kept set
    leaves a nonsingular interior. Both sit at the problem's rounding floor (worst errors
    measured, condensed / whole: 1.5e-8 / 8.9e-9 with fixes only, 6.5e-6 / 3.7e-6 with a
    hard zero-velocity interval, 6.0e-6 / 9.6e-5 with a soft one); at one lambda either
    may be the worse by more (the soft interval's rho2 at 1e4: 3.4e-6 against 1.6e-7)."""
    prob = fixes(EXTRAS[extra])
    cond = DirectSweep(prob.formulation)
    whole = DirectSweep(prob.formulation, condense=False)
    ref = _reference(prob)
    worst_c = worst_w = 0.0
    for lam in (1e-4, 1e-2, 1.0, 1e2, 1e4):
        p, q, r = cond.point(lam), whole.point(lam), ref.point(lam)
        for k in KEYS:
            worst_c = max(worst_c, abs(p[k] - r[k]) / abs(r[k]))
            worst_w = max(worst_w, abs(q[k] - r[k]) / abs(r[k]))
    assert worst_c <= max(10.0 * worst_w, 1e-8), (worst_c, worst_w)
    assert isinstance(cond._cond, CondensedBand)
    assert cond._cond.T.size < 0.25 * cond._plan.size   # a small system per lambda


def test_without_the_interior_only_the_kept_unknowns_are_solved():
    """``interior=False`` solves the kept unknowns alone (the lambda rows read no other):
    the same values there as the whole solve, NaN elsewhere."""
    prob = fixes()
    sweep = DirectSweep(prob.formulation)
    form = sweep._ls.at_lam(0.3)
    fac = sweep._factor(form, 0.3, condensed=True)
    assert isinstance(fac, CondensedKKT)
    rhs = np.random.default_rng(1).standard_normal(fac.S.shape[0])
    full = fac.solve_x_real(rhs)
    part = fac.solve_x_real(rhs, interior=False)
    known = ~np.isnan(part)
    assert 0 < known.sum() < 0.25 * part.size and np.all(np.isfinite(full))
    np.testing.assert_allclose(part[known], full[known], rtol=1e-12, atol=0)
    lam_cols = np.unique(np.concatenate([t.residual.A.indices for t in sweep.lam_terms]))
    assert np.all(known[lam_cols])


@pytest.mark.filterwarnings("ignore::bvpnav.log.BvpnavWarning")  # the rules' lambdas misfit sigma_a
@pytest.mark.parametrize("rule", ["lcurve", "quasi", "gcv"])
def test_a_rule_chooses_the_same_lambda_with_and_without_condensation(monkeypatch, rule):
    """The rule's lambda from condensed points is the whole band's to 1e-4 in log lambda,
    and the solve there (the whole band's, verified) agrees to 1e-9."""
    sol = fixes().solve(solver="direct", lam=rule)

    def refuse(self, *a, **k):
        raise NotBanded("off for this test")

    monkeypatch.setattr(CondensedBand, "__init__", refuse)
    ref = fixes().solve(solver="direct", lam=rule)
    assert sol.stats["verified"] and ref.stats["verified"]
    assert abs(np.log(sol.lam / ref.lam)) < 1e-4, (sol.lam, ref.lam)
    np.testing.assert_allclose(sol.x, ref.x, rtol=0, atol=1e-9 * np.max(np.abs(ref.x)) + 1e-6)


@pytest.mark.parametrize("extra", ["fixes only", "a hard position inside"])
def test_gcvs_trace_from_the_condensed_log_determinant_is_the_whole_bands(extra):
    """GCV's trace by the log-determinant: the small system's complex step (the interior's
    determinant does not move with lambda) equals the whole band's complex step to 1e-8."""
    prob = fixes(EXTRAS[extra])
    cond = DirectSweep(prob.formulation, need_trace=True, need_derivative=False)
    whole = DirectSweep(prob.formulation, need_trace=True, need_derivative=False, condense=False)
    for lam in (1e-4, 1e-1, 10.0, 1e4):
        p, q = cond.point(lam), whole.point(lam)
        assert p["trace"] == pytest.approx(q["trace"], rel=1e-8), (lam, p["trace"], q["trace"])
        assert p["rho2"] == pytest.approx(q["rho2"], rel=1e-6)
    assert cond.logdet_derivative == "complex step (condensed)" and whole.logdet_derivative == "complex step"
    assert isinstance(cond._cond, CondensedBand)


def test_a_long_hard_zero_velocity_interval_is_kept_whole_not_condensed_into_a_singular_interior():
    """Most nodes holding a hard row's multiplier (a zero-velocity interval over 3/4 of the
    window, the review's case): those nodes are kept, since their segments would not be FEM
    equations alone (they factored with condition numbers of 1e17, unnoticed by dgbtrf,
    and the L-curve chose 1.0 against the whole band's 0.0999 when the most common node
    was taken for the plain one); so many are kept that the sweep keeps the whole band."""
    rng = np.random.default_rng(0)
    t = np.sort(np.r_[0.0, 40.0, rng.uniform(0.0, 40.0, 3999)])
    acc = -0.2 * np.sin(0.2 * t) + 0.05 * rng.standard_normal(t.size)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=0.05)
    fix = t[200::400]
    prob.add(Position(t=[0.0, 40.0], value=0.0, name="ends"),
             Position(t=fix, value=5.0 * np.sin(0.2 * fix) + 0.3 * rng.standard_normal(fix.size), sigma=0.3,
                      name="fixes"),
             ZeroVelocity(t0=5.0, t1=35.0))
    sweep = DirectSweep(prob.formulation)
    with pytest.raises(NotBanded, match="would be kept"):
        CondensedBand(sweep._plan, sweep._affine_parts(), sweep._plain_unknowns())
    whole = DirectSweep(prob.formulation, condense=False)
    for lam in (0.1, 1.0):
        p, q = sweep.point(lam), whole.point(lam)
        assert all(p[k] == q[k] for k in KEYS)
    assert sweep._cond is False


@pytest.mark.parametrize("make, why", [
    (lambda: fixes(every=1), "would be kept|no node holds"),    # a fix at every sample
    (lambda: fixes(error_model=Bias()), "no border"),          # an error-model parameter
])
def test_condensation_steps_aside_where_it_does_not_apply(make, why):
    """Lambda rows at every sample (nothing to condense) or a border (error-model
    parameters): the sweep keeps the whole band's factorization, with the same points."""
    prob = make()
    sweep = DirectSweep(prob.formulation)
    with pytest.raises(NotBanded, match=why):
        CondensedBand(sweep._plan, sweep._affine_parts(), sweep._plain_unknowns())
    p = sweep.point(0.5)
    assert sweep._cond is False
    q = DirectSweep(prob.formulation, condense=False).point(0.5)
    for k in KEYS:
        assert p[k] == pytest.approx(q[k], rel=1e-12)
