"""describe() and matrices(): the formulation made visible, and a solve by hand."""

from __future__ import annotations

import io

import numpy as np
import pytest

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.describe import describe, matrices
from bvpnav.scenarios import tikhonov2011


def table1_problem():
    sc = tikhonov2011()
    t = sc.t
    tp = np.concatenate([t[:10], t[-10:]])
    prob = bvpnav.NavigationProblem(sc.data, residual="load")
    prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends"),
             Position(t=tp, value=sc.prior(tp), sigma=1.0, name="prior"))
    return prob


def test_describe_text_for_the_table1_problem():
    prob = table1_problem()
    text = prob.describe(lam=3.611)
    assert text == describe(prob, lam=3.611)
    lines = text.splitlines()
    assert lines[0] == ("bvpnav problem: N = 501 samples on [0, 10] s (h = 0.02 s); axes: x; "
                        "residual form: load")
    assert "unknowns x (1004 entries):" in lines
    assert "  FEM (501 rows): K r + e_1 v_0 - e_N v_1 + M (a_hat + w) = 0" in lines
    assert "  ends [hard, 2 rows]: r(t_k) - p_k = 0 at 2 instant(s)  (= 0)" in lines
    assert "  minimize  ||K r + B v - f - F l||^2  (= ||M w||^2, the 2011 paper's load form)" in lines
    assert ("  + lam * sum (.)^2 of (r(t_k) - p_k at 20 instant(s)) / sigma   [prior, soft, "
            "sigma = 1 m, 20 rows]") in lines
    assert "  lam = 3.611" in lines
    assert "size: 1004 unknowns, 503 equality rows, 521 objective rows, 4549 non-zeros" in lines
    cond = [ln for ln in lines if ln.startswith("condition estimate")]
    assert cond and float(cond[0].split(":")[1]) > 1e5  # the load form is ill-conditioned


def test_describe_latex_renders_with_mathtext():
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import mathtext

    tex = table1_problem().describe(format="latex", lam=3.611)
    formulas = [ln for ln in tex.splitlines() if ln.startswith("$")]
    assert r"$\lambda = 3.611$" in formulas
    assert r"$r(t_k) - p_k = 0\quad \mathrm{[ends,\ hard,\ 2\ rows]}$" in formulas
    assert any(r"\frac{r(t_k) - p_k }{\sigma_k}" in f for f in formulas)
    assert any(r"\|M w\|^2" in f for f in formulas)
    for f in formulas:  # every formula parses and renders
        mathtext.math_to_image(f, io.BytesIO(), format="png")
    assert all(ln.startswith(("$", "%")) for ln in tex.splitlines())
    with pytest.raises(bvpnav.InputError, match="format"):
        describe(table1_problem(), format="html")


@pytest.mark.parametrize("residual", ["acceleration", "load"])
def test_solve_by_hand_from_matrices(residual):
    """A student's numpy solve from matrices() reproduces solve() to 1e-8 relative."""
    sc = tikhonov2011(rate=20)
    t = sc.t
    prob = bvpnav.NavigationProblem(sc.data, residual=residual)
    prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends"),
             Position(t=t[:5], value=sc.prior(t[:5]), sigma=0.5, name="prior"),
             Velocity(t=5.0, value=0.0, sigma=0.2))
    lam = 2.5
    mats = prob.matrices()
    assert mats.A_eq.shape == matrices(prob).A_eq.shape
    # min ||J x||^2 + lam ||(D x - e)/sigma||^2  s.t.  A_eq x = b_eq   (dense KKT by hand)
    J = mats.J.toarray()
    W = mats.D.toarray() / mats.sigma[:, None]
    ew = mats.e / mats.sigma
    H = J.T @ J + lam * W.T @ W
    g = lam * W.T @ ew
    A = mats.A_eq.toarray()
    n, p = H.shape[0], A.shape[0]
    kkt = np.block([[H, A.T], [A, np.zeros((p, p))]])
    x = np.linalg.solve(kkt, np.concatenate([g, mats.b_eq]))[:n]
    sol = prob.solve(lam=lam, solver="clarabel", accuracy="high")
    r = x[mats.layout["r_x"]]
    assert np.max(np.abs(r - sol.position("x"))) / np.max(np.abs(r)) < 1e-8
    # the legend accounts for every row
    eq_rows = sum(s.stop - s.start for _, _, m, s in mats.legend if m == "A_eq")
    d_rows = sum(s.stop - s.start for _, _, m, s in mats.legend if m == "D")
    assert eq_rows == mats.A_eq.shape[0] and d_rows == mats.D.shape[0]
    # K, M, f are the papers' matrices: K r + B v = f + F l + ... with f = -M a_hat
    np.testing.assert_allclose(mats.f, -(mats.M @ sc.data.acc[:, 0]))
    assert mats.K.shape == (t.size, t.size)
