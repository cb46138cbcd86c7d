"""Figures, the CLI's -v/-q, --truth and --lam-range, and short reprs (issue 20, items 6-8).

Figures are checked through matplotlib's objects (panel titles, axis labels, line
labels), never pixels.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from bvpnav import NavigationProblem, plot  # noqa: E402
from bvpnav.cli import main  # noqa: E402
from bvpnav.constraints import AverageVelocity, Position, Velocity, ZeroVelocity  # noqa: E402
from bvpnav.imu import ImuData  # noqa: E402
from bvpnav.io import write_table  # noqa: E402
from bvpnav.samples import write_sample  # noqa: E402
from bvpnav.spec import to_spec  # noqa: E402


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _three_axes(n=121):
    t = np.linspace(0.0, 12.0, n)
    w = 2 * np.pi / 12
    pos = np.column_stack([5 * np.sin(w * t), 3 * (1 - np.cos(w * t)), 0.05 * t * (12 - t)])
    vel = np.column_stack([5 * w * np.cos(w * t), 3 * w * np.sin(w * t), 0.05 * (12 - 2 * t)])
    acc = np.column_stack([-5 * w**2 * np.sin(w * t), 3 * w**2 * np.cos(w * t), np.full(n, -0.1)])
    acc = acc + np.random.default_rng(1).normal(0.0, 0.02, acc.shape)
    prob = NavigationProblem(ImuData(t=t, acc=acc, axes=("x", "y", "z")), sigma_a=0.02)
    prob.add(Position(t=[0.0, 12.0], value=[pos[0], pos[-1]], name="ends"),
             Velocity(t=[0.0, 12.0], value=[vel[0], vel[-1]], name="end velocities"),
             Position(t=[6.0], value=[pos[60] + 0.1], sigma=0.3, name="fix"))
    return t, acc, pos, prob


@pytest.fixture(scope="module")
def rec3(tmp_path_factory):
    """A 3-axis recording with its spec and truth.csv, laid out as `bvpnav simulate` does."""
    d = tmp_path_factory.mktemp("rec3")
    t, acc, pos, prob = _three_axes()
    inp = {"time": "t", "time_unit": "s", "columns": {a: f"acc_{a}" for a in "xyz"}, "unit": "m/s^2"}
    write_table(pd.DataFrame({"t": t, **{f"acc_{a}": acc[:, k] for k, a in enumerate("xyz")}}),
                d / "recording.csv")
    (d / "spec.toml").write_text(to_spec(prob, solve={"solver": "direct", "lam": 1.0}, input=inp))
    write_table(pd.DataFrame({"t": t, **{a: pos[:, k] for k, a in enumerate("xyz")}}), d / "truth.csv")
    return d


@pytest.fixture(scope="module")
def shuttle(tmp_path_factory):
    d = tmp_path_factory.mktemp("shuttle")
    write_sample("shuttle", d, rate=5.0)
    return d


def _titles(fig):
    return [a.get_title() for a in fig.axes]


def _labels(ax):
    return [line.get_label() for line in ax.get_lines()]


def _by_title(fig, title):
    (ax,) = [a for a in fig.axes if a.get_title() == title]
    return ax


# ------------------------------------------------------------------ plot.solution
def test_solution_figure_has_a_panel_per_quantity_for_three_axes():
    t, _, pos, prob = _three_axes()
    sol = prob.solve(solver="direct")
    fig = plot.solution(sol, items=prob.items, truth=pos)
    titles = _titles(fig)
    for a in "xyz":
        assert f"position {a}" in titles and f"velocity {a}" in titles
        assert _by_title(fig, f"position {a}").get_ylabel() == f"{a} (m)"
        assert _by_title(fig, f"velocity {a}").get_ylabel() == f"v{a} (m/s)"
    assert "residuals" in titles and "path x-y" in titles
    path = _by_title(fig, "path x-y")
    assert (path.get_xlabel(), path.get_ylabel()) == ("x (m)", "y (m)")
    assert "truth" in _labels(path)
    # residuals: one line per axis, each labelled with its axis (not three identical labels)
    res = [lab for lab in _labels(_by_title(fig, "residuals")) if not lab.startswith("_")]
    assert res == ["w x", "w y", "w z"]
    # the items where they act: hard end positions filled, the soft fix hollow, at their times
    px = _by_title(fig, "position x")
    lines = {line.get_label(): line for line in px.get_lines()}
    assert {"bvpnav (direct)", "truth", "ends (hard)", "fix (soft)"} <= set(lines)
    np.testing.assert_allclose(lines["ends (hard)"].get_xdata(), [0.0, 12.0])
    np.testing.assert_allclose(lines["fix (soft)"].get_xdata(), [6.0])
    assert lines["fix (soft)"].get_markerfacecolor() == "none"
    assert "end velocities (hard)" in _labels(_by_title(fig, "velocity z"))
    assert "end velocities (hard)" not in lines


def test_solution_figure_one_axis_draws_velocity_items_and_the_error_against_the_truth():
    t = np.linspace(0.0, 10.0, 101)
    acc = np.zeros((t.size, 1))
    prob = NavigationProblem(ImuData(t=t, acc=acc), sigma_a=1.0).add(
        Position(t=[0.0], value=[0.0], name="start"),
        ZeroVelocity(t0=0.0, t1=1.0, name="still"),
        AverageVelocity(t0=[2.0], t1=[8.0], value=[0.0], sigma=0.1, name="stopwatch"))
    sol = prob.solve(solver="direct")
    fig = plot.solution(sol, items=prob.items, truth=np.zeros(t.size))
    assert _titles(fig) == ["position x", "velocity x", "residuals", "position error"]
    vel = _by_title(fig, "velocity x")
    assert "stopwatch (soft)" in _labels(vel)
    assert any(p.get_label() == "still (hard)" for p in vel.patches)  # the stationary interval, shaded
    assert _by_title(fig, "position error").get_lines()[0].get_label().startswith("RMS ")


def test_solution_figure_without_truth_or_items_and_bad_truth():
    t, _, _, prob = _three_axes()
    sol = prob.solve(solver="direct")
    fig = plot.solution(sol)
    assert "truth" not in _labels(_by_title(fig, "position x"))
    with pytest.raises(Exception, match="does not match"):
        plot.solution(sol, truth=np.zeros(5))


def test_trajectory_labels_each_axis():
    _, _, pos, prob = _three_axes()
    sol = prob.solve(solver="direct")
    fig = plot.trajectory({"bvpnav (direct)": sol}, truth=pos)
    labels = _labels(fig.axes[0])
    assert labels[:3] == ["bvpnav (direct) x", "bvpnav (direct) y", "bvpnav (direct) z"]
    assert labels[3:] == ["truth x", "truth y", "truth z"]


def test_comparison_plots_wall_time_with_solver_names_as_ticks():
    table = pd.DataFrame({
        "solver": ["clarabel", "direct", "csne"], "preset": ["default"] * 3,
        "status": ["optimal", "optimal", "singular"], "verified": [True, True, False],
        "solve_time": [0.001, 0.5, 0.2], "wall_time": [0.04, 0.011, 0.009],
        "forward_error": [1e-13, 3e-14, np.nan], "fem_residual": [1e-16, 1e-16, np.nan]})
    fig = plot.comparison(table)
    wall, acc = fig.axes
    assert wall.get_xlabel() == "wall time (s)" and wall.get_xscale() == "log"
    assert [tk.get_text() for tk in wall.get_yticklabels()] == ["clarabel/default", "direct/default",
                                                                 "csne/default"]
    widths = sorted(p.get_width() for p in wall.patches)
    np.testing.assert_allclose(widths, sorted([0.04, 0.011, 0.009]), rtol=1e-9)  # wall, not solve time
    assert acc.get_title() == "forward error"
    assert any("singular" in tx.get_text() for tx in acc.texts)  # a failed run is named, not hidden
    labels = [tk.get_text() for tk in wall.get_xticklabels(minor=True)]
    assert not any(labels)  # no crowded minor labels


# ------------------------------------------------------------------ the CLI
def test_solve_plot_draws_truth_beside_a_simulated_recording_and_from_truth(rec3, tmp_path, monkeypatch,
                                                                              capsys):
    figs = []
    monkeypatch.setattr("bvpnav.io.atomic_savefig", lambda fig, *a, **k: figs.append(fig))
    assert main(["solve", str(rec3 / "recording.csv"), "--spec", str(rec3 / "spec.toml"), "--out",
                 str(tmp_path / "a.csv"), "--plot", str(tmp_path / "a.png")]) == 0
    out = capsys.readouterr().out
    assert "RMS position error against the truth" in out
    assert "truth" in _labels(_by_title(figs[-1], "position y"))
    # --truth names the file explicitly (here a copy elsewhere, sampled at every other time)
    tr = pd.read_csv(rec3 / "truth.csv").iloc[::2]
    tr.to_csv(tmp_path / "elsewhere.csv", index=False)
    rec = tmp_path / "rec.csv"
    rec.write_bytes((rec3 / "recording.csv").read_bytes())
    assert main(["solve", str(rec), "--spec", str(rec3 / "spec.toml"), "--out", str(tmp_path / "b.csv"),
                 "--plot", str(tmp_path / "b.png"), "--truth", str(tmp_path / "elsewhere.csv")]) == 0
    assert "truth" in _labels(_by_title(figs[-1], "position z"))
    # no truth: none drawn
    assert main(["solve", str(rec), "--spec", str(rec3 / "spec.toml"), "--out", str(tmp_path / "c.csv"),
                 "--plot", str(tmp_path / "c.png")]) == 0
    assert "truth" not in _labels(_by_title(figs[-1], "position z"))


@pytest.mark.parametrize("body, needle", [
    ("t,a,b\n0,1,2\n", "no column(s) ['x', 'y', 'z']"),
    ("t,x,y,z\n5,0,0,0\n6,0,0,0\n", "do not cover"),
])
def test_bad_truth_exits_2_naming_the_fix(rec3, tmp_path, capsys, body, needle):
    (tmp_path / "truth_bad.csv").write_text(body)
    assert main(["solve", str(rec3 / "recording.csv"), "--spec", str(rec3 / "spec.toml"), "--out",
                 str(tmp_path / "a.csv"), "--truth", str(tmp_path / "truth_bad.csv")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("bvpnav: error: --truth") and needle in err
    assert main(["solve", str(rec3 / "recording.csv"), "--spec", str(rec3 / "spec.toml"), "--out",
                 str(tmp_path / "a.csv"), "--truth", str(tmp_path / "missing.csv")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_verbosity_changes_what_is_printed(shuttle, tmp_path, capsys):
    args = ["solve", str(shuttle / "recording.csv"), "--spec", str(shuttle / "spec.toml"), "--out"]
    assert main([*args, str(tmp_path / "a.csv")]) == 0
    plain = capsys.readouterr()
    assert "samples; lam = 1" in plain.out and "INFO" not in plain.err
    assert main([*args, str(tmp_path / "b.csv"), "-v"]) == 0
    verbose = capsys.readouterr()
    assert "samples; lam = 1" in verbose.out and "INFO" in verbose.err and "DEBUG" not in verbose.err
    assert main([*args, str(tmp_path / "c.csv"), "-vv"]) == 0
    assert "DEBUG" in capsys.readouterr().err
    assert main([*args, str(tmp_path / "d.csv"), "-q"]) == 0
    quiet = capsys.readouterr()
    assert quiet.out == "" and quiet.err == ""
    assert main([*args, str(tmp_path / "e.csv"), "-q", "-v"]) == 2
    assert "not both" in capsys.readouterr().err


@pytest.mark.parametrize("cmd", ["demo", "simulate", "solve", "lcurve", "compare", "batch"])
def test_every_subcommand_takes_v_and_q(cmd, capsys):
    with pytest.raises(SystemExit):
        main([cmd, "--help"])
    text = capsys.readouterr().out
    assert "-v, --verbose" in text and "-q, --quiet" in text


def test_lam_range_reaches_the_curve(shuttle, tmp_path, monkeypatch, capsys):
    import bvpnav.solve as solve_pkg

    seen = {}
    real = solve_pkg.lambda_curve

    def spy(*a, **k):
        seen.update(k)
        curve = real(*a, **k)
        seen["curve"] = curve
        return curve

    monkeypatch.setattr(solve_pkg, "lambda_curve", spy)
    args = ["lcurve", str(shuttle / "recording.csv"), "--spec", str(shuttle / "spec.toml"), "--plot",
            str(tmp_path / "lc.png"), "--rules", "lcurve", "--points", "9", "-q"]
    assert main([*args, "--lam-range", "1e-3", "1e3"]) == 0
    assert seen["lam_range"] == (1e-3, 1e3) and seen["curve"].lam_range == (1e-3, 1e3)
    assert seen["curve"].lam.min() == pytest.approx(1e-3) and seen["curve"].lam.max() == pytest.approx(1e3)
    for bad, needle in ((["1e3", "1e-3"], "0 < LOW < HIGH"), (["a", "1"], "two numbers"),
                        (["1e-20", "1"], "reaches beyond")):
        assert main([*args, "--lam-range", *bad]) == 2
        assert needle in capsys.readouterr().err


def test_demo_help_counts_the_methods_it_prints(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--help"])
    text = capsys.readouterr().out
    assert "four ways" in text and "three ways" not in text


def test_batch_summary_path_has_no_doubled_slash(tmp_path, capsys):
    recs = tmp_path / "recs"
    write_sample("shuttle", tmp_path / "s", rate=5.0)
    recs.mkdir()
    (recs / "a.csv").write_bytes((tmp_path / "s" / "recording.csv").read_bytes())
    assert main(["batch", str(recs), "--spec", str(tmp_path / "s" / "spec.toml"), "--out",
                 str(tmp_path / "results") + "/", "--scheduler", "serial"]) == 0
    out = capsys.readouterr().out
    assert "summary: " in out and "//" not in out


# ------------------------------------------------------------------ reprs
def test_solution_repr_is_short_and_informative():
    _, _, _, prob = _three_axes()
    sol = prob.solve(solver="direct")
    text = repr(sol)
    lines = text.splitlines()
    assert 2 <= len(lines) <= 6 and all(len(line) <= 120 for line in lines)
    assert "121 samples" in text and "axes x, y, z" in text
    assert "lam = 1 (fixed)" in text and "direct" in text and "verified" in text
    assert "fix soft" in text  # item residuals
    assert "array" not in text and "\n\n" not in text
