"""One sweep, one answer (issue 40, case 2): ``bvpnav solve`` with ``lam = "lcurve"`` and
``bvpnav lcurve`` choose the same lambda at every size, and it is the corner of an
independent dense reference of the same curve; a corner beside the range's end is refined.
"""

from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pandas as pd
import pytest
from scipy.linalg import solve_banded

from bvpnav.cli import main
from bvpnav.lam import REFINE_XATOL
from bvpnav.scenarios import tikhonov2011

#: Samples per decade of the reference sweep: its corner is bracketed to +-0.01 decade (2.3 %).
REFERENCE_PER_DECADE = 100


def _reference(rate: float):
    r"""The L-curve of the problem ``bvpnav simulate tikhonov2011 --rate RATE`` writes,
    solved here without bvpnav: ``lam -> (rho, eta, r)``.

    Notes
    -----
    The spec: the load form, both end positions hard (0 and 10 m), a soft cubic prior
    (sigma 1 m) on samples 1-10 and N-11..N-2, nothing else. The load residual's rows are
    :math:`-M w = K r + B v - f`; the end velocities are free and enter the two end rows
    only, so at the minimum those rows vanish and the data term is the interior rows',
    :math:`g_i = (r_{i-1} - 2 r_i + r_{i+1})/h - (M\hat a)_i`. With :math:`L` that
    tridiagonal operator on the interior (end positions moved to the right-hand side),
    :math:`r = r_0 + L^{-1} g` (:math:`r_0` the data-only solution), and with :math:`S`
    picking the prior's samples, :math:`C = S L^{-1}` (20 rows) and
    :math:`d = S r_0 - p`, the problem :math:`\min \lVert g\rVert^2 + \lambda\lVert d +
    C g\rVert^2` has :math:`g = -\lambda C^T (I + \lambda C C^T)^{-1} d`: a 20 x 20 solve
    per lambda, so a dense sweep costs nothing. :math:`\rho = \lVert g \rVert`,
    :math:`\eta = \lVert d + C g \rVert` (bvpnav's :math:`\rho = \lVert M w\rVert` over all
    rows, the end rows zero). With the thin SVD :math:`C^T = U \Sigma V^T` and
    :math:`z = V^T d`, :math:`V^T y = z / (1 + \lambda \sigma^2)`, so every sample of the curve
    is a sum over the 20 singular values: :math:`\rho = \lambda \lVert \sigma z / (1 +
    \lambda\sigma^2)\rVert`, :math:`\eta = \lVert z / (1 + \lambda\sigma^2)\rVert`.

    Returns
    -------
    curve : callable
        ``lams (L,) -> (rho (L,), eta (L,))``, vectorized over lambda.
    at : callable
        ``lam -> (rho, eta)`` or, with ``trajectory=True``, ``(rho, eta, r)``: the 20 x 20
        solve and the trajectory at one lambda.
    """
    sc = tikhonov2011(rate=rate, seed=0)
    t, a = sc.t, sc.data.acc[:, 0]
    n, h = t.size, t[1] - t[0]
    idx = np.r_[1:11, n - 11:n - 1]
    m = n - 2
    band = np.zeros((3, m))
    band[0, 1:], band[1], band[2, :-1] = 1.0 / h, -2.0 / h, 1.0 / h
    rhs = h / 6.0 * (a[:-2] + 4.0 * a[1:-1] + a[2:])
    rhs[-1] -= 10.0 / h   # r(10 s) = 10 m; r(0) = 0
    r0 = solve_banded((1, 1), band, rhs)
    pick = np.zeros((m, idx.size))
    pick[idx - 1, np.arange(idx.size)] = 1.0
    C = solve_banded((1, 1), band, pick).T   # L is symmetric
    d = r0[idx - 1] - sc.prior(t[idx])
    G = C @ C.T

    def at(lam: float, trajectory: bool = False):
        y = np.linalg.solve(np.eye(idx.size) + lam * G, d)
        g = -lam * (C.T @ y)
        rho, eta = float(np.linalg.norm(g)), float(np.linalg.norm(d + C @ g))
        if not trajectory:
            return rho, eta
        return rho, eta, np.concatenate([[0.0], r0 + solve_banded((1, 1), band, g), [10.0]])

    _, s, vt = np.linalg.svd(C.T, full_matrices=False)
    z = vt @ d

    def curve(lams: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q = 1.0 / (1.0 + np.multiply.outer(lams, s**2))   # (L, 20)
        return lams * np.linalg.norm(s * z * q, axis=1), np.linalg.norm(z * q, axis=1)

    return curve, at


def _reference_corner(curve, lo: float = 1e-6, hi: float = 1e6) -> tuple[float, float, float]:
    """The maximiser of the reference's curvature of ``(log rho, log eta)`` (second-order
    differences on :data:`REFERENCE_PER_DECADE` samples per decade) and its two neighbours."""
    lams = np.geomspace(lo, hi, int(round(np.log10(hi / lo) * REFERENCE_PER_DECADE)) + 1)
    u = np.log(lams)
    z, e = np.log(curve(lams))
    z1, e1 = np.gradient(z, u, edge_order=2), np.gradient(e, u, edge_order=2)
    z2, e2 = np.gradient(z1, u, edge_order=2), np.gradient(e1, u, edge_order=2)
    kappa = (z1 * e2 - z2 * e1) / (z1**2 + e1**2) ** 1.5
    j = int(np.argmax(kappa))
    assert 0 < j < lams.size - 1, "the reference's corner lies at the end of the range"
    return float(lams[j]), float(lams[j - 1]), float(lams[j + 1])


@pytest.mark.filterwarnings("ignore::bvpnav.log.BvpnavWarning")   # quasi's, beside the L-curve
@pytest.mark.parametrize("rate", [50, 1000, pytest.param(20000, marks=pytest.mark.slow)],
                         ids=["501", "10001", "200001"])
def test_solve_and_lcurve_choose_the_same_lambda_at_the_reference_corner(tmp_path, capsys, rate):
    """Issue 40's case: at 200,001 samples ``solve`` chose 1e-4 (4.10 m) and ``lcurve`` 1e5,
    from sweeps of 7 and 25 samples with guard samples at the ends. Now both commands sweep
    the same samples and choose, to 1 %, the maximiser of the reference's curvature within
    its bracket of +-0.01 decade: about 3.89, 2.09e3 and 8.51e5 (the paper's convex corner;
    at 1e4 and 2e5 samples the curve's sharpest bend is concave, not a corner by the
    paper's sign, and at 2e5 the convex one is too faint to see: a warning says so). The
    trajectory solved at that lambda is the reference's own (the same problem)."""
    rec = tmp_path / "rec"
    assert main(["simulate", "tikhonov2011", "--rate", str(rate), "--out", str(rec), "-q"]) == 0
    files = [str(rec / "recording.csv"), "--spec", str(rec / "spec.toml")]
    assert main(["solve", *files, "--out", str(tmp_path / "sol.csv"), "-q"]) == 0
    summary = json.loads((tmp_path / "sol.json").read_text())
    lam_solve = summary["lam"]
    capsys.readouterr()
    assert main(["lcurve", *files, "--plot", str(tmp_path / "lc.png")]) == 0
    out = capsys.readouterr().out
    lam_lcurve = float(re.search(r"^lcurve\s+lam = (\S+)", out, re.M).group(1))   # 6 digits
    assert abs(np.log(lam_lcurve / lam_solve)) < 0.01, (lam_solve, lam_lcurve)
    assert "edge" not in out and "no convex corner" not in out, out
    # at 2e5 the convex corner is faint (curvature 0.0067: a radius of about 150 in log units
    # on a curve about 19 across), and both commands say so; at 501 and 1e4 it is not (2.3
    # and 0.13 on curves about 16 across)
    faint = rate == 20000
    assert ("lcurve: the corner chosen" in out) == faint, out
    assert any(w.startswith("lcurve: the corner chosen") for w in summary["warnings"]) == faint

    curve, at = _reference(rate)
    best, low, high = _reference_corner(curve)
    assert low <= lam_solve <= high, (lam_solve, best, low, high)
    # the reference is the problem the CLI solved: its trajectory at the chosen lambda, where
    # the 20 x 20 solve and the SVD form of the curve agree
    rho, eta, r = at(lam_solve, trajectory=True)
    np.testing.assert_allclose(np.ravel(curve(np.array([lam_solve]))), [rho, eta], rtol=1e-8)
    x = pd.read_csv(tmp_path / "sol.csv")["x"].to_numpy()
    assert np.max(np.abs(x - r)) < 1e-6 * np.max(np.abs(r))


def _table2(n: int):
    """The 2011 paper's Table 2 shape: quintic, both end positions hard, a cubic prior
    (sigma 1 m) on the first and last 2 % of the samples, the acceleration form."""
    import bvpnav
    from bvpnav.constraints import Position
    from bvpnav.scenarios import cubic_prior, quintic_trajectory

    _, _, a = quintic_trajectory()
    t = np.linspace(0.0, 10.0, n)
    acc = 1.05 * a(t) + np.random.default_rng(1).normal(-0.5, 1.0, n)
    k = max(n // 50, 1)
    tp = np.concatenate([t[:k], t[-k:]])
    prior = cubic_prior(0.0, 10.0, 0.0, 10.0, 0.0, 0.0)
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc)).add(
        Position(t=[0.0, 10.0], value=[0.0, 10.0]), Position(t=tp, value=prior(tp), sigma=1.0))


@pytest.mark.parametrize("n", [5000, pytest.param(100_000, marks=pytest.mark.slow)])
def test_a_corner_between_the_last_allowed_sample_and_the_end_is_refined(n):
    """Issue 40's guard-sample case: the corner (about 1.16e4; curvature 2.38 at the sample
    1e4 and -0.13 at 1e6) lay between the last sample the rule could choose and the range's
    end sample, and ``lam="lcurve"`` returned 1e4 unrefined with a high-edge warning. Now it
    is refined there, to the lambda a range reaching past it (1e9) gives, with no warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # no warning at all
        curve = _table2(n).solve(solver="direct", lam="lcurve").curve
    wide = _table2(n).solve(solver="direct", lam="lcurve", rule={"lam_range": (1e-6, 1e9)}).curve
    assert len(curve.lam) == 7 and curve.lam[5] == pytest.approx(1e4) and curve.lam[6] == pytest.approx(1e6)
    assert curve.scores["lcurve"][5] > 2.0 and curve.scores["lcurve"][6] < 0   # the case itself
    assert 1.1e4 < curve.lam_chosen < 1.25e4
    assert abs(np.log(curve.lam_chosen / wide.lam_chosen)) < REFINE_XATOL
    assert not curve.warnings and not wide.warnings
