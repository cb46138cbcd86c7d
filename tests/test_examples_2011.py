"""The 2011 examples at small size: Table 1, trapezoid vs Romberg, solver comparison."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import load_example

import bvpnav

load = load_example


@pytest.fixture(scope="module")
def table1_small():
    mod = load("tikhonov_table1")
    rows = [(0.05, -0.5), (0.0, 0.5), (0.0, 0.0)]
    return mod, mod.run(seeds=4, rows=rows, quiet=True)


@pytest.mark.slow
def test_table1_lcurve_lambda_and_method_ii_match_the_paper(table1_small):
    mod, df = table1_small
    biased = df[df.mu != 0]
    # 4 realisations only (the full run uses 20): a factor 1.5 on lambda_L, 25% on sigma_II
    ratio = biased.lam_L / biased.paper_lam_L
    assert np.all((ratio > 1 / 1.5) & (ratio < 1.5)), ratio.tolist()
    rel = np.abs(biased.sigma_II / biased.paper_sigma_II - 1)
    assert np.all(rel < 0.25), rel.tolist()
    # Tikhonov with the L-curve beats method II by a wide margin on biased rows
    assert np.all(biased["sigma_I(lam_L)"] < biased.sigma_II / 4)


@pytest.mark.slow
def test_table1_beyond_the_paper(table1_small):
    _, df = table1_small
    # the weighted form with a bias model and GCV beats the paper's method I on average
    assert df.sigma_IV.mean() < df["sigma_I(lam_L)"].mean()
    # and is as good as the RTS smoother on the identical realisations (within 5%)
    assert df.sigma_IV.mean() <= 1.05 * df.sigma_RTS.mean()


def test_trapezoid_vs_romberg_ordering(capsys):
    res = load("trapezoid_vs_romberg").run()
    out = capsys.readouterr().out
    assert "1.23e-03" in out and "1.60e-04" in out
    lo = res["paper regime"]
    assert lo["romberg"] < lo["trapezoid"] / 10
    # beyond the paper: near the coarse levels' Nyquist rate Romberg loses
    hi = res["with 97/211 Hz vibration"]
    assert hi["romberg"] > hi["trapezoid"]


def test_compare_solvers_table_shows_failures_as_rows():
    sc = bvpnav.scenarios.tikhonov2011(rate=100.0, seed=2)
    from bvpnav.constraints import Position, Velocity

    prob = bvpnav.NavigationProblem(sc.data).add(Position(t=[0.0, 10.0], value=[0.0, 10.0]),
                                                  Velocity(t=[0.0, 10.0], value=[0.0, 0.0]))
    df = bvpnav.compare_solvers(prob, solvers=["clarabel", "direct", "osqp"],
                                presets=["default"], reference=sc.position,
                                options={"osqp": {"max_iter": 5}})
    assert list(df.solver) == ["clarabel", "direct", "osqp"]
    good = df.set_index("solver")
    assert good.loc["clarabel", "verified"] and good.loc["direct", "verified"]
    assert abs(good.loc["clarabel", "rms_error"] - good.loc["direct", "rms_error"]) < 1e-6
    # OSQP stopped after 5 iterations: a row that says so, not an exception
    assert not good.loc["osqp", "verified"]
    assert set(bvpnav.compare.COLUMNS) <= set(df.columns)
    # an unknown solver name is a typo, refused up front with the valid names (issue 14;
    # it used to be a row of the table after every other run)
    with pytest.raises(bvpnav.InputError, match=r"\['no-such-solver'\]; available: .*'clarabel'"):
        bvpnav.compare_solvers(prob, solvers=["clarabel", "direct", "osqp", "no-such-solver"])


@pytest.mark.slow
def test_information_a_smoother_cannot_use():
    res = load("information_smoothers_cannot_use").run(seeds=4, quiet=True)
    rts = res["RTS smoother (4 boundary values)"]
    # with the same information bvpnav and the RTS smoother agree (both are the same estimator)
    assert abs(res["bvpnav, 4 boundary values"] - rts) < 0.02 * rts
    # symmetry and average velocities are information the smoother cannot take
    assert res["bvpnav + symmetry"] < rts
    assert res["bvpnav + average velocities"] < 0.8 * rts
    assert res["bvpnav + both"] < 0.5 * rts
