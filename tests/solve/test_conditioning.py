"""Nearly unobservable error-model parameters are reported, and NaN is never verified (issue 8.3).

The synthetic recording: navigation-frame data on two axes, T = 10 s, N = 101 samples,
hard positions and velocities at both ends, exact (noise-free, linear-in-time
accelerations, which the FEM integrates exactly).

- axis x: true acceleration ``t/T`` m/s^2, measured with scale error +1 % and bias
  0.1 m/s^2;
- axis y: (almost) no true acceleration, ``nu (t/T - 1/2)`` with ``nu`` = 0 or 2e-8
  m/s^2, and a sensor output ``b + mu (t/T - 1/2)``, bias ``b`` = 0.2 m/s^2 plus a small
  drift ``mu`` = 2e-5 m/s^2 (the "little noise" that makes the scale column differ from
  the bias column).

With both ends fixed, the information sees the acceleration only through its integrals
against 1 and t, so (in the continuum limit) the parameter directions are compared in
L2(0, T) on span{1, t}. For the y pair the columns are ``1`` and ``b + mu psi``
(``psi = t/T - 1/2``, orthogonal to 1, ``||psi||^2 = ||1||^2 / 12``):

    cos(theta_y) = b / sqrt(b^2 + mu^2/12),
    relative singular value sqrt(1 - cos theta_y) ~= mu / (|b| sqrt(24)) = 2.0412e-5

(measured 2.0516e-5: the trapezoidal ends move it by 0.5 % at N = 101). For the x pair
the columns are ``1`` and ``c1 t/T + c0`` (``c1`` = 1.01, ``c0`` = 0.1):

    cos(theta_x) = (c1/2 + c0) / sqrt(c1^2/3 + c1 c0 + c0^2) = 0.90085,
    relative singular values sqrt(1 -+ cos theta_x) = 0.31489 and 1.37871

(measured 0.31625 and 1.37840). The two axes do not couple, so a parameter alone on its
axis (bias_y without scale_y) has relative singular value 1.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import scipy.linalg as sla
from _helpers import load_example

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import Bias, ErrorModel, ScaleFactor
from bvpnav.errors import Inaccurate, InputError
from bvpnav.linalg.lsq import least_squares_form
from bvpnav.solve.assemble import finish
from bvpnav.solve.conditioning import (
    GAIN_LIMIT,
    RELATIVE_SV_WARN,
    information_matrix,
    relative_singular_values,
)

T, N = 10.0, 101
B_Y = 0.2  #: bias of the y sensor, m/s^2
MU = 2e-5  #: drift of the y sensor output, m/s^2
C1, C0 = 1.01, 0.1  #: x sensor output = C1 t/T + C0, m/s^2

SV_Y = MU / (B_Y * np.sqrt(24.0))  # 2.0412e-5 (continuum limit)
COS_X = (C1 / 2 + C0) / np.sqrt(C1**2 / 3 + C1 * C0 + C0**2)
SV_X = (np.sqrt(1 - COS_X), np.sqrt(1 + COS_X))  # 0.31489, 1.37871 (continuum limit)
DISCRETE = 0.01  # relative distance of the N = 101 values from the continuum limit (measured 0.5 %)


def _from_rest(c1: float, c0: float, t) -> tuple[np.ndarray, np.ndarray]:
    """Position (m) and velocity (m/s) for the acceleration ``c1 t/T + c0`` from rest at 0."""
    t = np.asarray(t, dtype=float)
    return c1 * t**3 / (6 * T) + c0 * t**2 / 2, c1 * t**2 / (2 * T) + c0 * t


def recording(nu: float = 0.0, mu: float = MU, error_model=None, sigma_a: float = 0.1):
    """The synthetic two-axis problem described in the module docstring."""
    t = np.linspace(0.0, T, N)
    u = t / T
    acc = np.column_stack([C1 * u + C0, B_Y + mu * (u - 0.5)])
    px, vx = _from_rest(1.0, 0.0, [0.0, T])
    py, vy = _from_rest(nu, -nu / 2, [0.0, T])
    data = bvpnav.ImuData(t, acc, axes=("x", "y"))
    em = Bias() + ScaleFactor() if error_model is None else error_model
    prob = bvpnav.NavigationProblem(data, sigma_a=sigma_a, error_model=em)
    prob.add(Position(t=[0.0, T], value=np.column_stack([px, py])),
             Velocity(t=[0.0, T], value=np.column_stack([vx, vy])))
    return prob


def dense_reference_sv(prob) -> np.ndarray:
    """Relative singular values from the definitions with dense linear algebra (no Schur
    complement): covariance ``Z (Z^T D^T D Z)^{-1} Z^T`` on the null space ``Z`` of the
    equality rows, its parameter block inverted, scaled to unit diagonal."""
    m = prob.model
    E = bvpnav.Affine.vstack([m.fem_rows()] + [t.residual for t in prob.terms() if t.mode == "hard"])
    D = prob.data_rows().A.toarray()
    Z = sla.null_space(E.A.toarray())
    DZ = D @ Z
    cov = Z @ np.linalg.solve(DZ.T @ DZ, Z.T)
    H = np.linalg.inv(cov[np.ix_(m.l_index, m.l_index)])
    d = 1.0 / np.sqrt(np.diag(H))
    return np.sqrt(np.linalg.eigvalsh(H * np.outer(d, d)))


def _by_name(warnings: list[str], *names: str) -> list[str]:
    return [w for w in warnings if all(n in w for n in names)]


# ---------------------------------------------------------------- the issue
@pytest.mark.parametrize("solver", ["clarabel", "direct"])
def test_axis_without_specific_force_warns_naming_scale_and_bias(solver):
    """Issue 8.3: y feels no specific force, Bias() + ScaleFactor() on all axes.

    The solve succeeds (the internal correction is determined: it removes the y signal,
    1 + k_y = 0), but scale_y and bias_y are meaningless: both warnings name them.
    """
    sol = recording(nu=0.0).solve(solver=solver, fallback=None)
    assert sol.stats["verified"] and sol.stats["solver"] == solver
    cond = sol.stats["conditioning"]
    sv = np.array(cond["relative_singular_values"])
    # ascending: the y pair's small one, the x pair, the y pair's large one (sqrt 2)
    assert sv[0] == pytest.approx(SV_Y, rel=DISCRETE)
    assert sv[1] == pytest.approx(SV_X[0], rel=DISCRETE)
    assert sv[2] == pytest.approx(SV_X[1], rel=DISCRETE)
    assert sv[3] == pytest.approx(np.sqrt(2.0), rel=1e-9)
    assert cond["min_relative_sv"] == sv[0] < RELATIVE_SV_WARN
    assert cond["weak"] == [{"parameters": ["bias_y", "scale_y"], "relative_sv": sv[0]}]
    (near,) = _by_name(sol.warnings, "bias_y and scale_y are nearly indistinguishable")
    assert f"relative singular value {sv[0]:.1e}" in near and "2.1e-05" in near
    assert "ScaleFactor(axes=" in near
    # the estimate removes the y signal: 1 + k_y at the rounding level of a problem
    # whose scaled condition number is 1 / sv^2 = 2.4e9 (measured 3e-13)
    (axis,) = cond["degenerate_axes"]
    assert axis["axis"] == "y" and axis["parameters"] == ["bias_y", "scale_y"]
    assert abs(axis["kept"]) < 1e-6 and abs(axis["gain"]) > 1e6
    (deg,) = _by_name(sol.warnings, "sensor axis y", "bias_y and scale_y are", "not determined")
    assert "ScaleFactor(axes=(...)) without 'y'" in deg
    # the x parameters are exact, the y ones are reported but flagged
    assert sol.error_params["scale_x"] == pytest.approx(0.01, rel=1e-8)
    assert sol.error_params["bias_x"] == pytest.approx(0.1, rel=1e-8)
    assert abs(sol.error_params["scale_y"]) > 1e6


def test_tiny_true_signal_gives_a_finite_but_flagged_scale():
    """nu = mu / 1000: the exact fit is 1 + k_y = nu / mu, so the reported gain is exactly
    mu / nu = 1000 (scale_y = 999) and the bias is b; gain > GAIN_LIMIT: flagged."""
    sol = recording(nu=MU / 1000).solve(solver="direct", fallback=None)
    assert sol.error_params["scale_y"] == pytest.approx(999.0, rel=1e-6)  # measured 2e-10
    assert sol.error_params["bias_y"] == pytest.approx(B_Y, rel=1e-9)
    (axis,) = sol.stats["conditioning"]["degenerate_axes"]
    assert axis["gain"] == pytest.approx(1000.0, rel=1e-6) and axis["gain"] > GAIN_LIMIT
    assert axis["kept"] == pytest.approx(1e-3, rel=1e-6)
    assert len(_by_name(sol.warnings, "bias_y and scale_y")) == 2


def test_well_posed_variant_has_no_warning():
    """ScaleFactor on the excited axis only: no warning; bias_y alone has relative
    singular value 1 and is estimated exactly (the drift mu psi is orthogonal to 1)."""
    sol = recording(nu=0.0, error_model=Bias() + ScaleFactor(axes=("x",))).solve()
    assert sol.warnings == []
    cond = sol.stats["conditioning"]
    sv = np.array(cond["relative_singular_values"])
    assert sv[0] == pytest.approx(SV_X[0], rel=DISCRETE)
    assert sv[1] == pytest.approx(1.0, rel=1e-9)
    assert sv[2] == pytest.approx(SV_X[1], rel=DISCRETE)
    assert cond["weak"] == [] and cond["degenerate_axes"] == []
    assert sol.error_params["bias_y"] == pytest.approx(B_Y, rel=1e-9)
    assert sol.error_params["scale_x"] == pytest.approx(0.01, rel=1e-8)


def test_exactly_unobservable_still_raises_before_solving():
    """mu = 0: the scale column is b times the bias column; refused before any solve."""
    prob = recording(nu=0.0, mu=0.0)
    with pytest.raises(InputError, match=r"1 combination\(s\) of: parameter bias_y, parameter scale_y"):
        prob.solve()


def test_schur_complement_matches_a_dense_reference():
    """The Schur complement (reused factorization and the verifier's own LU) gives the
    relative singular values of the dense definition, and both agree with the analytic
    values (module docstring) to the discretization error."""
    prob = recording(nu=0.0)
    ref = dense_reference_sv(prob)
    for solver in ("direct", "clarabel"):
        sv = np.array(prob.solve(solver=solver, fallback=None).stats["conditioning"]
                      ["relative_singular_values"])
        assert np.allclose(sv, ref, rtol=1e-4, atol=0), (solver, sv, ref)
    own = relative_singular_values(information_matrix(prob.formulation, 1.0))[0]
    assert np.allclose(own, ref, rtol=1e-4, atol=0)
    assert ref[0] == pytest.approx(SV_Y, rel=DISCRETE)


def test_problem_with_an_inequality_uses_its_least_squares_part():
    """An (inactive) position bound keeps the problem out of least squares: the estimate
    uses the equality information, the same numbers as without the bound."""
    from bvpnav.constraints import PositionBound

    prob = recording(nu=0.0)
    prob.add(PositionBound(upper=100.0, axes=("x",)))
    sol = prob.solve(solver="clarabel", fallback=None)
    sv = np.array(sol.stats["conditioning"]["relative_singular_values"])
    assert np.allclose(sv, dense_reference_sv(recording(nu=0.0)), rtol=1e-4, atol=0)
    assert _by_name(sol.warnings, "bias_y and scale_y are nearly indistinguishable")


def test_least_squares_part_of_a_band_problem_by_the_banded_factorization():
    """With band or inequality rows no back end hands a factorization of the least-squares
    part: the acceleration form's is the banded one (not a sparse LU), the same reduced
    Hessian as the sparse LU's to rounding, and the same singular values as the dense
    definition on the problem without the bound."""
    from bvpnav.constraints import PositionBound
    from bvpnav.solve.conditioning import _banded_schur, _schur

    prob = recording(nu=0.0)
    prob.add(PositionBound(upper=100.0, axes=("x",)))
    form = prob.formulation
    assert form.residual == "acceleration"
    ls = least_squares_form(form, 1.0, surrogate=True)
    banded = _banded_schur(ls, form)
    assert banded is not None and banded.shape == (form.model.q, form.model.q)
    m, n = ls.D.A.shape
    lu = _schur(ls.augmented(), m + form.model.l_index, np.arange(m + n, m + n + ls.E.m))
    np.testing.assert_allclose(banded, lu, rtol=1e-8, atol=1e-8 * np.abs(lu).max())
    own = relative_singular_values(information_matrix(form, 1.0))[0]
    assert np.allclose(own, dense_reference_sv(recording(nu=0.0)), rtol=1e-4, atol=0)


# ------------------------------------------------------- NaN is never verified
class NanReport(ErrorModel):
    """A bias-like parameter on axis x whose report is NaN (a broken plug-in)."""

    units = "m/s^2"

    def names(self, data):
        return ["broken"]

    def columns(self, data):
        g = np.zeros((data.n, data.ndim, 1))
        g[:, 0, 0] = 1.0
        return g

    def report(self, l, model):
        return pd.Series([np.nan], index=pd.Index(["broken"], name="parameter"), name="estimate")


def test_verify_refuses_nan_in_x_and_in_the_reported_parameters():
    prob = recording(nu=MU / 1000)
    sol = prob.solve(solver="direct", fallback=None)
    good = prob.verify(sol.x, 1.0)
    assert good["verified"] and good["nonfinite"] == []
    x = sol.x.copy()
    x[prob.model.r_index(0)[50]] = np.nan
    bad = prob.verify(x, 1.0)
    assert not bad["verified"] and bad["nonfinite"] == ["1 entries of the solution vector"]
    # 1 + k_y = 0 exactly: I + E is singular; axis y's parameters are undetermined (scale
    # inf, bias NaN) and the x axis keeps its finite values (issue 14: before, every sensor
    # parameter's report was NaN, and the same exact zero from a solver on one BLAS kernel
    # failed a solve that verified on another). This x is not a solution (forward error).
    x = sol.x.copy()
    x[prob.model.l_index[list(prob.model.param_names).index("scale_y")]] = -1.0
    bad = prob.verify(x, 1.0)
    assert not bad["verified"] and bad["forward_error"] > 1e-6
    assert [s for s in bad["nonfinite"] if s.startswith("error parameter")] == [
        "error parameter bias_y = nan", "error parameter scale_y = inf"]
    assert bad["undetermined"] == ["bias_y", "scale_y"]
    assert any(s.startswith("sensor axis y") for s in bad["nonfinite"])  # the reason


def test_nan_report_fails_every_attempt():
    """A NaN estimate is never returned: each solver's answer fails verification and the
    error says what was not finite."""
    t = np.linspace(0.0, T, N)
    data = bvpnav.ImuData(t, 0.3 * np.ones(N))
    prob = bvpnav.NavigationProblem(data, error_model=NanReport(),
                                    items=[Position(t=[0.0, T], value=[0.0, 0.0]),
                                           Velocity(t=0.0, value=0.0)])
    with pytest.raises(Inaccurate, match=r"not finite: error parameter broken = nan") as info:
        prob.solve(solver="direct", fallback=["clarabel"])
    assert [a["solver"] for a in info.value.attempts] == ["direct", "clarabel"]
    assert all(a["reason"] == "failed verification" for a in info.value.attempts)


# --------------------------------------------------------- the reported case
def test_ski_jump_with_scale_factor_on_all_axes_is_flagged():
    """examples/ski_jump.py at 50 Hz, gyro attitude: with ScaleFactor() on all axes the
    internal parameters are well separated (smallest relative singular value 0.15) but
    the correction nearly removes the body y axis (1 + k_y = -0.0196: a reversed gain of
    -51); the warning names scale_y and bias_y. The example's own model has no warning."""
    sj = load_example("ski_jump")
    sc = sj.simulate_jump(50.0, 0)
    info = sj.information(sc)
    bad, _ = sj.problems(sc, info, "gyro", Bias() + ScaleFactor())
    sol = bad.solve(lam=1.0)
    cond = sol.stats["conditioning"]
    assert cond["min_relative_sv"] > 0.1 and cond["weak"] == []
    (axis,) = cond["degenerate_axes"]
    assert axis["axis"] == "y" and abs(axis["kept"]) < 1.0 / GAIN_LIMIT
    assert _by_name(sol.warnings, "sensor axis y", "bias_y and scale_y")
    good, _ = sj.problems(sc, info, "gyro")
    sol = good.solve(lam=1.0)
    assert sol.warnings == [] and sol.stats["conditioning"]["degenerate_axes"] == []


def test_a_degenerate_axis_with_a_non_finite_report_is_an_input_error_not_a_fallback():
    """1 + k_y = 0 exactly makes every physical sensor parameter NaN. That is the
    information's fault (no specific force along y), so the answer is refused at once with
    the fix, instead of sending the chain through every solver."""
    prob = recording(nu=MU / 1000)
    sol = prob.solve(solver="direct", fallback=None)
    x = sol.x.copy()
    x[prob.model.l_index[list(prob.model.param_names).index("scale_y")]] = -1.0
    info = {"solver": "direct", "status": "optimal"}
    with pytest.raises(bvpnav.InputError, match=r"direct: the error-model estimate is not finite "
                       r"because sensor axis y.*without 'y'"):
        finish(prob.formulation, x, 1.0, info, None, "default", True)


@pytest.mark.parametrize("kept", [0.0, 3e-13, -3e-13, 2e-10, -5e-10])
def test_the_verdict_on_a_removed_axis_does_not_depend_on_rounding(kept):
    """Issue 14: the same problem gave 1 + k_y = 0 exactly on one BLAS kernel (then NaN
    everywhere and an InputError) and 3e-13 on another (verified, gain 3e12). Any kept
    fraction within KEPT_ZERO = 1e-9 of zero is zero: one verdict, the same finiteness,
    the same message, whichever side of zero the rounding fell (a margin of 2x and more
    from the threshold on both sides)."""
    from bvpnav.error_models._base import KEPT_ZERO

    assert abs(kept) <= KEPT_ZERO / 2
    prob = recording(nu=0.0)
    sol = prob.solve(solver="direct", fallback=None)
    x = sol.x.copy()
    x[prob.model.l_index[list(prob.model.param_names).index("scale_y")]] = -1.0 + kept
    check = prob.verify(x, 1.0)
    assert check["verified"] and check["undetermined"] == ["bias_y", "scale_y"]
    (axis,) = check["conditioning"]["degenerate_axes"]
    assert axis["kept"] == 0.0 and axis["gain"] == np.inf and axis["undetermined"]
    assert "keeps a fraction 0 (within 1e-09 of zero)" in axis["message"]
    rep = prob.error_model.report(prob.model.split(x)["l"], prob.model)
    assert rep["scale_y"] == np.inf and np.isnan(rep["bias_y"])
    assert rep["scale_x"] == pytest.approx(0.01, rel=1e-8) and rep["bias_x"] == pytest.approx(0.1, rel=1e-8)


def test_a_kept_fraction_beyond_the_threshold_is_a_finite_flagged_gain():
    """2e-9 (twice KEPT_ZERO) is resolved: a finite gain of 5e8, flagged, verified."""
    prob = recording(nu=0.0)
    sol = prob.solve(solver="direct", fallback=None)
    x = sol.x.copy()
    x[prob.model.l_index[list(prob.model.param_names).index("scale_y")]] = -1.0 + 2e-9
    check = prob.verify(x, 1.0)
    (axis,) = check["conditioning"]["degenerate_axes"]
    assert not axis["undetermined"] and axis["gain"] == pytest.approx(5e8, rel=1e-6)
    assert check["undetermined"] == [] and check["nonfinite"] == []
