"""Issue 5's examples at small size: outlying position fixes and the ski jump."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import load_example

load = load_example


# ------------------------------------------------------------------------ outliers
@pytest.fixture(scope="module")
def outliers():
    mod = load("outliers")
    # the --small configuration: 20 Hz, seeds 0-4
    return mod, mod.run(rate=20.0, seeds=5, quiet=True)


def test_outliers_robust_is_not_pulled(outliers):
    """Acceptance: robust mode's RMS position error is >= 5x smaller than soft mode's.

    Measured (20 Hz, seeds 0-4): soft 2.18 m, Huber 0.257 m, L1 0.283 m, oracle 0.184 m;
    ratio of the means 7.7, per realisation 6.5 ... 9.3. Over 20 realisations at 50 Hz
    the ratio of the means is 6.9 and single realisations range from 4.2 to 11.8, hence
    the per-realisation bound of 4.
    """
    mod, df = outliers
    assert df.attrs["ratio"] >= 5.0, df
    assert np.all(df.attrs["ratios"] >= 4.0), df.attrs["ratios"]
    sigma = mod.SIGMA_FIX
    soft, hub, l1, oracle = (df.loc[k] for k in (mod.SOFT, mod.HUB, mod.L1, mod.ORACLE))
    # against the noise level: the outliers dominate soft mode's error ...
    assert soft.rms_error > 2 * sigma and soft.pull > 5 * sigma
    # ... while both robust penalties end up better than one fix, near the oracle
    for r in (hub, l1):
        assert r.rms_error < sigma and r.pull < sigma
        assert r.rms_error < 2 * oracle.rms_error
    # the oracle (18 good fixes, soft): averaging beats a single fix by more than 2x
    assert oracle.rms_error < sigma / 2


def test_outliers_known_numbers(outliers):
    """Regression guard for the seeded small run (simulator + solver)."""
    mod, df = outliers
    assert df.loc[mod.SOFT, "rms_error"] == pytest.approx(2.184, abs=0.01)
    assert df.loc[mod.HUB, "rms_error"] == pytest.approx(0.257, abs=0.01)
    assert df.loc[mod.L1, "rms_error"] == pytest.approx(0.283, abs=0.01)
    assert df.loc[mod.ORACLE, "rms_error"] == pytest.approx(0.184, abs=0.01)


def test_outliers_prints_table_and_writes_figure_when_asked(tmp_path, capsys):
    mod = load("outliers")
    mod.run(rate=20.0, seeds=1, figures=str(tmp_path))
    out = capsys.readouterr().out
    assert "robust, Huber 1.5 m" in out and "robust, L1" in out and "soft / worse robust" in out
    png = tmp_path / "outliers.png"
    assert png.exists() and png.read_bytes()[:4] == b"\x89PNG"
    # without the request no file is written
    mod.run(rate=20.0, seeds=1, quiet=True)
    assert [p.name for p in tmp_path.iterdir()] == ["outliers.png"]


# ------------------------------------------------------------------------ ski jump
@pytest.fixture(scope="module")
def ski_jump():
    import bvpnav.constraints

    if not hasattr(bvpnav.constraints, "TrackLine"):
        pytest.skip("bvpnav.constraints.TrackLine is not available")
    mod = load("ski_jump")
    # the --small configuration: 50 Hz, seeds 0-3
    return mod, mod.run(rate=50.0, seeds=4, quiet=True)


@pytest.mark.slow
def test_ski_jump_simulation_is_the_stated_jump(ski_jump):
    mod, res = ski_jump
    sc = res["first"]["scenario"]
    sim = sc["sim"]
    # take-off after 6.09 s at 26.2 m/s, 3.67 s in the air, landing at x = 95.1 m
    assert sc["t_takeoff"] == pytest.approx(6.094, abs=0.01)
    assert sc["v_takeoff"] == pytest.approx(26.23, abs=0.05)
    assert sc["t_landing"] - sc["t_takeoff"] == pytest.approx(3.66, abs=0.02)
    assert sc["x_landing"] == pytest.approx(95.06, abs=0.1)
    # the boot is on the hill after landing (the spline smooths the impact: < 5 cm),
    # and stays in the plane y = 0
    after = sim.t >= sc["t_landing"]
    hill = sc["hill"]
    gap = sim.truth["z"].to_numpy()[after] - np.interp(sim.truth["x"].to_numpy()[after], hill["x"], hill["z"])
    assert np.abs(gap).max() < 0.05
    assert np.abs(sim.truth["y"].to_numpy()).max() == 0.0
    # the five inrun points: from the gate (t = 0) to the take-off edge (the origin)
    info = res["first"]["information"]
    assert info["t_points"][0] == 0.0
    assert info["t_points"][-1] == pytest.approx(sc["t_takeoff"], abs=1 / 50)
    assert np.allclose(info["points"][-1], 0.0, atol=0.6)  # one sample at 26 m/s


@pytest.mark.slow
def test_ski_jump_landing_hill_line_shrinks_the_landing_error(ski_jump):
    """The landing-hill line makes the landing-point error clearly smaller.

    Measured at 50 Hz, seeds 0-3: mean landing-point error 0.504 m without the line,
    0.053 m with it (ratio of the means 9.6; per realisation 3.3 to 27). At 200 Hz with
    8 realisations: 0.567 m and 0.028 m (20.5x; per realisation 7.2 to 96). The bound
    of 5 on the means leaves a factor 1.9 below the smallest measured value; the bound
    of 3 per realisation sits 10 % under the smallest single ratio seen (3.3).
    """
    mod, res = ski_jump
    t = res["table"]
    assert res["ratio"] >= 5.0, t
    assert np.all(res["ratios"] >= 3.0), res["ratios"]
    wide = res["per_seed"].pivot(index="seed", columns="solution", values="landing_error")
    # without the line the landing point is an extrapolation from the inrun: tens of cm
    assert np.all(wide[mod.WITHOUT] > 0.15), wide
    # with it the landing point is within 10 cm (the line's sigma is 5 cm)
    assert np.all(wide[mod.WITH] < 0.1), wide
    # the flight as a whole is better too; after landing the along-track error remains,
    # but the line still halves it
    assert t.loc[mod.WITH, "rms_flight"] < t.loc[mod.WITHOUT, "rms_flight"] / 3
    assert t.loc[mod.WITH, "rms_after"] < t.loc[mod.WITHOUT, "rms_after"] / 2


@pytest.mark.slow
def test_ski_jump_known_numbers(ski_jump):
    """Regression guard for the seeded small run (simulator + TrackLine loop + solver)."""
    mod, res = ski_jump
    t = res["table"]
    assert t.loc[mod.WITHOUT, "landing_error"] == pytest.approx(0.504, abs=0.01)
    assert t.loc[mod.WITH, "landing_error"] == pytest.approx(0.053, abs=0.01)


@pytest.mark.slow
def test_ski_jump_sequential_loop_converges_and_honours_the_information(ski_jump):
    mod, res = ski_jump
    for rep in res["sequential"]:
        assert rep["converged"] and rep["iterations"] <= 10, rep
        assert rep["max_change"][-1] < rep["tol"]
        # the first re-linearization moves the trajectory by up to a few m, then it settles
        assert rep["max_change"][0] > 100 * rep["max_change"][-1]
    first = res["first"]
    sc, info = first["scenario"], first["information"]
    for sol in first["solutions"].values():
        # the inrun points are hard
        got = np.column_stack([np.interp(info["t_points"], sol.t, sol.position(a)) for a in "xyz"])
        assert np.abs(got - info["points"]).max() < 1e-5
    # with the line the estimate follows the hill after landing (well inside 3 sigma)
    sol = first["solutions"][mod.WITH]
    after = sol.t >= sc["t_landing"]
    hill = sc["hill"]
    gap = sol.position("z")[after] - np.interp(sol.position("x")[after], hill["x"], hill["z"])
    assert np.abs(gap).max() < 3 * mod.SIGMA_HILL / np.cos(np.radians(35.0))


@pytest.mark.slow
def test_ski_jump_prints_table_and_writes_figure_when_asked(ski_jump, tmp_path, capsys, monkeypatch):
    mod, _ = ski_jump
    monkeypatch.setenv("BVPNAV_FIGURES", str(tmp_path))
    mod.main(["--rate", "25", "--seeds", "1"])
    out = capsys.readouterr().out
    assert "landing-point error without / with the landing-hill line" in out
    assert mod.WITHOUT in out and mod.WITH in out and "sequential loop" in out
    assert (tmp_path / "ski_jump.png").read_bytes()[:4] == b"\x89PNG"
