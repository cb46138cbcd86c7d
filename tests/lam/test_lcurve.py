"""The L-curve rule (bvpnav.lam.lcurve): exact curvature, refinement beyond the grid, the paper's lambda."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import known_noise, table1

from bvpnav.lam.lcurve import curvature as _curvature
from bvpnav.lam.lcurve import curvature_slope as _curvature_slope
from bvpnav.lam.lcurve import spline_curvature as _spline_curvature
from bvpnav.lam.sweep import DirectSweep as _DirectSweep
from bvpnav.solve import lambda_curve


def test_exact_curvature_matches_spline_of_dense_sweep():
    prob, _ = table1()
    eng = _DirectSweep(prob.formulation)
    lams = np.geomspace(1e-2, 1e2, 81)
    pts = [eng.point(v) for v in lams]
    exact = np.array([_curvature(p) for p in pts])
    spline = _spline_curvature(np.log(lams), [p["rho2"] for p in pts], [p["eta2"] for p in pts],
                               np.log(lams))
    inner = slice(5, -5)
    np.testing.assert_allclose(exact[inner], spline[inner], atol=0.02 * np.max(np.abs(exact)))


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


def test_curvature_slope_is_the_derivative_of_the_curvature():
    """The complex-step slope of the exact curvature equals its central difference in
    log lambda (to the difference's own error) across the corner and both flanks."""
    prob, _ = table1()
    eng = _DirectSweep(prob.formulation)
    eps = 1e-3
    slopes, diffs = [], []
    for lam in np.geomspace(1e-3, 1e3, 7):
        a, b, c = (eng.point(lam * np.exp(e)) for e in (-eps, 0.0, eps))
        slopes.append(_curvature_slope(b))
        diffs.append((_curvature(c) - _curvature(a)) / (2 * eps))
    np.testing.assert_allclose(slopes, diffs, rtol=1e-4, atol=1e-6 * np.max(np.abs(diffs)))
    assert np.ptp(np.sign(diffs)) == 2   # both signs: the corner lies inside


@pytest.mark.filterwarnings("ignore::bvpnav.log.BvpnavWarning")  # the L-curve's lambda misfits sigma_a
@pytest.mark.parametrize("make", [lambda: table1()[0], lambda: known_noise(0, n=2001)[0],
                                  lambda: known_noise(1, n=2001)[0]], ids=["table1", "noise0", "noise1"])
def test_lcurve_alone_samples_every_two_decades_and_chooses_the_one_decade_grids_corner(make):
    """With slopes the default sweep of ``solve(lam="lcurve")`` is 7 points, not 13: the same
    corner to the refinement's tolerance (1 % in lambda), in fewer evaluations."""
    from bvpnav.lam import REFINE_XATOL
    from bvpnav.lam.sweep import DIRECT_POINTS, SLOPE_POINTS

    coarse = make().solve(solver="direct", lam="lcurve").curve   # the default sweep
    fine = lambda_curve(make(), rules=("lcurve",), points=DIRECT_POINTS)
    assert len(coarse.lam) == SLOPE_POINTS == 7
    assert abs(np.log(coarse.lam_chosen / fine.lam_chosen)) < REFINE_XATOL
    assert coarse.evaluations < fine.evaluations


def test_a_range_narrower_than_twelve_decades_keeps_thirteen_samples():
    """Seven samples only where they lie two decades apart: on (1e-2, 1e2) the L-curve keeps
    13 and finds the corner inside (about 6, the paper's row), as a 13-point sweep does."""
    from bvpnav.lam import REFINE_XATOL
    from bvpnav.lam.sweep import DIRECT_POINTS

    curve = table1()[0].solve(solver="direct", lam="lcurve", rule={"lam_range": (1e-2, 1e2)}).curve
    assert len(curve.lam) == DIRECT_POINTS and not curve.warnings
    fine = lambda_curve(table1()[0], rules=("lcurve",), points=13, lam_range=(1e-2, 1e2))
    assert abs(np.log(curve.lam_chosen / fine.lam_chosen)) < REFINE_XATOL
    assert 3.611 / 2 < curve.lam_chosen < 3.611 * 2


def test_a_corner_in_the_first_sixth_of_the_range_is_refined_not_cut_off():
    """The corner (about 6, the paper's row) lies between the range's first sample and the
    second, which the rule once never chose (returning the second, 26.8, with an edge
    warning): the exact curvature needs no guard sample, so the corner is refined there,
    the lambda of a narrow range around it, with no warning."""
    import warnings

    from bvpnav.lam import REFINE_XATOL

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        curve = table1()[0].solve(solver="direct", lam="lcurve",
                                  rule={"lam_range": (0.26801, 2.6801e11)}).curve
    assert len(curve.lam) == 7 and curve.lam[0] < curve.lam_chosen < curve.lam[1]
    narrow = lambda_curve(table1()[0], rules=("lcurve",), lam_range=(1e-2, 1e2))
    assert abs(np.log(curve.lam_chosen / narrow.lam_chosen)) < REFINE_XATOL
    assert not curve.warnings


def test_a_corner_beyond_the_range_warns_naming_the_ranges_own_end():
    """The corner (about 6) lies below the range: the curvature still rises at the range's
    first sample, so that sample, the low edge itself, is returned and the warning names it."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        curve = table1()[0].solve(solver="direct", lam="lcurve", rule={"lam_range": (30.0, 3e13 / 1e2)}).curve
    assert curve.lam_chosen == pytest.approx(30.0, rel=1e-12)
    [w] = [w for w in curve.warnings if "edge" in w]
    assert "low edge lam=30 of lam_range=(30, 3e+11)" in w and "best chosen" not in w, w


def test_the_cvxpy_spline_keeps_two_samples_from_each_end_on_a_coarse_grid():
    """Only the direct sweep's exact values and slopes make one guard sample enough: the
    cvxpy sweep's spline (end effects) keeps two even with samples two decades apart."""
    from bvpnav.lam.lcurve import LCurve
    from bvpnav.lam.sweep import LambdaCurve

    class Spline:   # a cvxpy-like sweep on an analytic L-shaped curve
        engine = "cvxpy"

        def __init__(self):
            self.cache = {}

        def point(self, lam):
            p = {"lam": lam, "rho2": 1.0 + lam, "eta2": 1.0 + 1.0 / lam}
            self.cache[float(lam)] = p
            return p

    lams = np.geomspace(1e-6, 1e6, 7)
    s = np.log(lams)
    sweep = Spline()
    pts = [sweep.point(v) for v in lams]
    scores = np.array([0.0, 5.0, 1.0, 0.5, 0.2, 0.1, 0.0])   # best at the first allowed-by-one sample
    curve = LambdaCurve(lam=lams, residual_norm=np.ones(7), info_norm=np.ones(7), rule="lcurve",
                        engine="cvxpy", lam_range=(1e-6, 1e6))
    lam = LCurve().refine(sweep, pts, s, scores, curve)
    assert lams[1] < lam and np.log(lam) >= s[2] - np.log(100.0)   # chosen from k = 2's bracket
    assert any("low edge" in w for w in curve.warnings)
