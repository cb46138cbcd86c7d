"""Standard deviations through spec files, the command line, figures and batch runs.

The numbers are the Python API's (``NavigationProblem.solve(uncertainty=...)``): every
test compares what a file holds with ``sol.trajectory`` / ``sol.stats["uncertainty"]``
of the same spec solved in Python.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from _hostile import main_cli

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

import bvpnav
from bvpnav import plot
from bvpnav.batch import run_batch, solve_recording
from bvpnav.cli import main
from bvpnav.readers import read_recording
from bvpnav.spec import load_spec, parse_spec, to_spec

SIGMA_A = 0.05
BIAS = (0.2, -0.1)

SPEC = """\
[input]
time = "t"
columns = {{ x = "acc_x", y = "acc_y" }}
unit = "m/s^2"

[problem]
residual = "acceleration"
sigma_a = {sigma_a}

[solve]
solver = "direct"
lam = 1.0
{extra}
[[error_model]]
type = "bias"

[[item]]
type = "position"
mode = "hard"
name = "start"
t = [0.0]
value = [[0.0, 0.0]]

[[item]]
type = "position"
mode = "soft"
sigma = 0.1
name = "end"
t = [10.0]
value = [{end}]

[[item]]
type = "velocity"
mode = "soft"
sigma = 0.05
name = "ends moving"
t = [0.0, 10.0]
value = [[0.0, 0.0], {vend}]
"""


def _truth(t):
    """acc = (sin t, cos t) from rest at the origin: positions and velocities."""
    return (np.column_stack([t - np.sin(t), 1 - np.cos(t)]),
            np.column_stack([1 - np.cos(t), np.sin(t)]))


def spec_text(uncertainty: str | None = "true") -> str:
    p, v = _truth(np.array([10.0]))
    extra = "" if uncertainty is None else f"uncertainty = {uncertainty}\n"
    p, v = p.tolist(), v.tolist()
    return SPEC.format(sigma_a=SIGMA_A, extra=extra, end=f"[{p[0][0]!r}, {p[0][1]!r}]",
                       vend=f"[{v[0][0]!r}, {v[0][1]!r}]")


def write_recording(path, seed: int = 0, n: int = 201) -> None:
    t = np.linspace(0.0, 10.0, n)
    rng = np.random.default_rng(seed)
    acc = np.column_stack([np.sin(t), np.cos(t)]) + BIAS + rng.normal(0.0, SIGMA_A, (n, 2))
    pd.DataFrame({"t": t, "acc_x": acc[:, 0], "acc_y": acc[:, 1]}).to_csv(path, index=False)


@pytest.fixture(scope="module")
def rec(tmp_path_factory):
    """A 2-axis recording, its spec with ``uncertainty = true`` and one without the key."""
    d = tmp_path_factory.mktemp("unc")
    write_recording(d / "recording.csv")
    (d / "spec.toml").write_text(spec_text("true"))
    (d / "plain.toml").write_text(spec_text(None))
    return d


def api_solution(rec, spec_name="spec.toml", **kw):
    spec = load_spec(rec / spec_name)
    prob = spec.build(read_recording(rec / "recording.csv", spec.input))
    return prob.solve(**{**spec.solve, **kw}), prob


STD_COLUMNS = ["x_std", "y_std", "vx_std", "vy_std"]


# ------------------------------------------------------------------ spec
@pytest.mark.parametrize("value,parsed", [("true", True), ("false", False), ('"scaled"', "scaled")])
def test_spec_uncertainty_values_are_read(value, parsed):
    spec = parse_spec(f'[solve]\nlam = 1.0\nuncertainty = {value}\n', "spec.toml")
    assert spec.solve == {"lam": 1.0, "uncertainty": parsed}


@pytest.mark.parametrize("value,hint", [
    ('"yes"', "a TOML boolean has no quotes"),
    ('"true"', "a TOML boolean has no quotes"),
    ('"Scaled"', 'in lower case: uncertainty = "scaled"'),
    ("1", ""),
    ("[true]", ""),
])
def test_a_bad_spec_uncertainty_names_the_line_the_value_and_the_choices(value, hint):
    text = f'[solve]\nsolver = "direct"\nlam = 1.0\nuncertainty = {value}\n'
    with pytest.raises(bvpnav.InputError) as exc:
        parse_spec(text, "spec.toml")
    msg = str(exc.value)
    shown = repr(tomllib.loads(f"v = {value}")["v"])
    assert msg.startswith(f"spec.toml, line 4: uncertainty={shown}: give True")
    assert '"scaled"' in msg and "or false" in msg and hint in msg
    with pytest.raises(bvpnav.InputError) as same:  # the same text from solve() (one declaration)
        bvpnav.declare.check_option("uncertainty", tomllib.loads(f"v = {value}")["v"])
    assert msg == f"spec.toml, line 4: {same.value}"


def test_to_spec_round_trips_the_uncertainty_key(rec):
    _, prob = api_solution(rec, "plain.toml")
    for value in (True, "scaled", False):
        text = to_spec(prob, solve={"solver": "direct", "lam": 1.0, "uncertainty": value})
        back = parse_spec(text, "again.toml")
        assert back.solve["uncertainty"] == value and type(back.solve["uncertainty"]) is type(value)


# ------------------------------------------------------------------ solve
def test_solve_writes_the_std_columns_and_the_uncertainty_record(rec, tmp_path, capsys):
    out = tmp_path / "traj.csv"
    argv = ["solve", str(rec / "recording.csv"), "--spec", str(rec / "spec.toml"), "--out", str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    sol, _ = api_solution(rec)
    got = pd.read_csv(out)
    assert list(got.columns) == ["t", "x", "y", "vx", "vy", *STD_COLUMNS]
    for c in ["x", "y", "vx", "vy", *STD_COLUMNS]:
        np.testing.assert_allclose(got[c].to_numpy(), sol.trajectory[c].to_numpy(), rtol=0, atol=1e-12)
    assert got["x_std"].iloc[0] == 0.0 and got["x_std"].iloc[-1] > 0  # a hard start, a soft end
    js = json.loads(out.with_suffix(".json").read_text())
    u, ref = js["uncertainty"], sol.stats["uncertainty"]
    assert u["scale"] == "stated" and u["dof"] == ref["dof"] and u["model"] == "exact"
    assert u["variance_factor"] == pytest.approx(ref["variance_factor"], rel=1e-12)
    assert u["columns"] == STD_COLUMNS
    assert u["std"]["x"]["median"] == pytest.approx(float(np.median(sol.trajectory["x_std"])), rel=1e-12)
    assert u["std"]["vy"]["max"] == pytest.approx(float(sol.trajectory["vy_std"].max()), rel=1e-12)
    for k in ("bias_x", "bias_y"):
        assert js["error_model"][k]["std"] == pytest.approx(sol.error_params_std[k], rel=1e-12)
        assert js["error_model"][k]["estimate"] == pytest.approx(sol.error_params[k], rel=1e-12)
    # the estimated biases are within a few of their standard deviations of the truth
    for k, b in zip(("bias_x", "bias_y"), BIAS, strict=True):
        assert abs(sol.error_params[k] - b) < 4 * sol.error_params_std[k]
    assert "assume the stated noise" in printed
    assert f"variance factor is {ref['variance_factor']:.4g} on {ref['dof']} degrees" in printed
    assert f"median std: position x {np.median(sol.trajectory['x_std']):.3g} m" in printed
    ep, ep_std = sol.error_params, sol.error_params_std
    assert f"bias_x = {ep['bias_x']:.4g} +/- {ep_std['bias_x']:.2g} m/s^2" in printed


def test_the_flag_overrides_the_spec_scaled_and_off(rec, tmp_path, capsys):
    stated, _ = api_solution(rec, "plain.toml", uncertainty=True)
    vf = stated.stats["uncertainty"]["variance_factor"]
    out = tmp_path / "scaled.parquet"
    assert main(["solve", str(rec / "recording.csv"), "--spec", str(rec / "plain.toml"), "--out", str(out),
                 "--uncertainty", "scaled"]) == 0
    assert "scaled by the a-posteriori variance factor" in capsys.readouterr().out
    got = pd.read_parquet(out)
    assert list(got.columns) == ["t", "x", "y", "vx", "vy", *STD_COLUMNS]
    for c in STD_COLUMNS:  # scaled: the stated numbers times the square root of the variance factor
        np.testing.assert_allclose(got[c].to_numpy(), np.sqrt(vf) * stated.trajectory[c].to_numpy(),
                                   rtol=1e-9, atol=1e-15)
    js = json.loads(out.with_suffix(".json").read_text())
    assert js["uncertainty"]["scale"] == "scaled"
    # a bare --uncertainty is the stated noise
    out2 = tmp_path / "stated.csv"
    assert main(["solve", str(rec / "recording.csv"), "--spec", str(rec / "plain.toml"), "--out", str(out2),
                 "--uncertainty", "-q"]) == 0
    np.testing.assert_allclose(pd.read_csv(out2)["x_std"], stated.trajectory["x_std"], rtol=0, atol=1e-12)
    # off: none, whatever the spec says
    out3 = tmp_path / "off.csv"
    assert main(["solve", str(rec / "recording.csv"), "--spec", str(rec / "spec.toml"), "--out", str(out3),
                 "--uncertainty", "off", "-q"]) == 0
    assert list(pd.read_csv(out3).columns) == ["t", "x", "y", "vx", "vy"]
    js = json.loads(out3.with_suffix(".json").read_text())
    assert "uncertainty" not in js and "std" not in js["error_model"]["bias_x"]


def test_a_bad_flag_value_exits_2_before_any_work(rec, tmp_path):
    out = tmp_path / "o.csv"
    proc = main_cli(["solve", rec / "recording.csv", "--spec", rec / "plain.toml", "--out", out,
                     "--uncertainty", "maybe"])
    assert proc.returncode == 2
    assert proc.stderr.startswith("bvpnav: error: --uncertainty 'maybe': choose stated")
    assert "scaled" in proc.stderr and "off" in proc.stderr and "Traceback" not in proc.stderr
    assert not out.exists() and not out.with_suffix(".json").exists()


def test_solve_plot_draws_the_band_from_the_cli(rec, tmp_path):
    proc = main_cli(["solve", rec / "recording.csv", "--spec", rec / "spec.toml", "--out", tmp_path / "t.csv",
                     "--plot", tmp_path / "t.png"])
    assert proc.returncode == 0, proc.stderr
    assert "uncertainty (exact covariance): the standard deviations assume the stated noise" in proc.stdout
    assert (tmp_path / "t.png").stat().st_size > 5000


# ------------------------------------------------------------------ figures
def _bands(ax, label):
    from matplotlib.collections import PolyCollection

    return [c for c in ax.collections if isinstance(c, PolyCollection) and c.get_label() == label]


def _extent_at(band, t0: float) -> tuple[float, float]:
    """Lowest and highest vertex of a fill_between band at time ``t0``."""
    v = band.get_paths()[0].vertices
    y = v[np.isclose(v[:, 0], t0, rtol=0, atol=1e-12), 1]
    return float(y.min()), float(y.max())


def test_solution_figure_draws_a_2_sigma_band_around_position_and_velocity(rec):
    import matplotlib.pyplot as plt

    sol, prob = api_solution(rec)
    fig = plot.solution(sol, items=prob.items)
    try:
        panels = {a.get_title(): a for a in fig.axes}
        k = 57
        tk = sol.t[k]
        for title, col in (("position x", "x"), ("position y", "y"), ("velocity x", "vx"),
                           ("velocity y", "vy")):
            (band,) = _bands(panels[title], "±2σ")
            val, std = sol.trajectory[col].iloc[k], sol.trajectory[f"{col}_std"].iloc[k]
            lo, hi = _extent_at(band, tk)
            assert lo == pytest.approx(val - 2 * std, rel=1e-12, abs=1e-12)
            assert hi == pytest.approx(val + 2 * std, rel=1e-12, abs=1e-12)
            assert 0 < band.get_alpha() <= 0.3
            assert "±2σ" in [t.get_text() for t in panels[title].get_legend().get_texts()]
        assert not _bands(panels["residuals"], "±2σ") and not _bands(panels["path x-y"], "±2σ")
        assert "±2σ under the stated noise" in fig._suptitle.get_text()
    finally:
        plt.close(fig)
    plain, _ = api_solution(rec, "plain.toml")
    fig = plot.solution(plain, items=prob.items)
    try:
        assert all(not _bands(a, "±2σ") for a in fig.axes)
        assert "±2σ" not in fig._suptitle.get_text()
    finally:
        plt.close(fig)


def test_one_axis_error_panel_has_the_band_around_zero(rec):
    import matplotlib.pyplot as plt

    from bvpnav.constraints import Position, Velocity
    from bvpnav.imu import ImuData

    t = np.linspace(0.0, 10.0, 101)
    p, v = _truth(t)
    acc = np.sin(t)[:, None] + np.random.default_rng(3).normal(0, SIGMA_A, (t.size, 1))
    prob = bvpnav.NavigationProblem(ImuData(t=t, acc=acc), sigma_a=SIGMA_A)
    # a fix at the end gives the residuals a degree of freedom: without it the variance
    # factor is undefined and "scaled" falls back to the stated deviations (issue 40)
    prob.add(Position(t=[0.0], value=[0.0], name="start"), Velocity(t=[0.0], value=[0.0], name="rest"),
             Position(t=[10.0], value=[float(p[-1, 0])], sigma=0.5, name="fix"))
    sol = prob.solve(lam=1.0, solver="direct", uncertainty="scaled")
    assert sol.stats["uncertainty"]["dof"] == 1 and np.isfinite(sol.stats["uncertainty"]["variance_factor"])
    fig = plot.solution(sol, truth=p[:, 0])
    try:
        err = next(a for a in fig.axes if a.get_title() == "position error")
        (band,) = _bands(err, "±2σ")
        lo, hi = _extent_at(band, t[40])
        assert hi == pytest.approx(2 * sol.trajectory["x_std"].iloc[40], rel=1e-12)
        assert lo == pytest.approx(-hi, rel=1e-12)
        assert "scaled by the variance factor" in fig._suptitle.get_text()
    finally:
        plt.close(fig)


def test_trajectory_figure_draws_a_band_per_line_only_with_std(rec):
    import matplotlib.pyplot as plt
    from matplotlib.colors import to_rgb

    sol, _ = api_solution(rec)
    plain, _ = api_solution(rec, "plain.toml")
    fig = plot.trajectory({"with": sol, "without": plain})
    try:
        ax = fig.axes[0]
        k = 120
        for a in ("x", "y"):
            (band,) = _bands(ax, f"with {a} ±2σ")
            val, std = sol.trajectory[a].iloc[k], sol.trajectory[f"{a}_std"].iloc[k]
            lo, hi = _extent_at(band, sol.t[k])
            assert (lo, hi) == pytest.approx((val - 2 * std, val + 2 * std), rel=1e-12)
            line = next(ln for ln in ax.get_lines() if ln.get_label() == f"with {a}")
            np.testing.assert_allclose(band.get_facecolor()[0][:3], to_rgb(line.get_color()))
        assert not any("without" in c.get_label() and "±2σ" in c.get_label() for c in ax.collections)
        assert len([c for c in ax.collections if "±2σ" in c.get_label()]) == 2
    finally:
        plt.close(fig)
    fig = plot.trajectory({"without": plain}, axis="x")
    try:
        assert not fig.axes[0].collections
    finally:
        plt.close(fig)


# ------------------------------------------------------------------ batch
def test_batch_writes_std_columns_and_records_and_resume_keys_on_uncertainty(rec, tmp_path):
    recs = tmp_path / "recs"
    recs.mkdir()
    for seed in (1, 2):
        write_recording(recs / f"run{seed}.csv", seed=seed)
    out = tmp_path / "out"
    df = run_batch(recs, rec / "spec.toml", out, scheduler="serial", progress=False)
    assert df.ok.all()
    spec = load_spec(rec / "spec.toml")
    for seed in (1, 2):
        sol = spec.build(read_recording(recs / f"run{seed}.csv", spec.input)).solve(**spec.solve)
        got = pd.read_csv(out / f"run{seed}.csv")
        assert list(got.columns) == ["t", "x", "y", "vx", "vy", *STD_COLUMNS]
        for c in STD_COLUMNS:
            np.testing.assert_allclose(got[c].to_numpy(), sol.trajectory[c].to_numpy(), rtol=0, atol=1e-12)
        js = json.loads((out / f"run{seed}.json").read_text())
        assert js["uncertainty"]["scale"] == "stated"
        vf = sol.stats["uncertainty"]["variance_factor"]
        assert js["uncertainty"]["variance_factor"] == pytest.approx(vf, rel=1e-12)
        assert js["error_model"]["bias_y"]["std"] == pytest.approx(sol.error_params_std["bias_y"], rel=1e-12)
        assert "uncertainty" not in js["run"]["fingerprint"]["options"]  # not overridden
    # the same run again: skipped
    df = run_batch(recs, rec / "spec.toml", out, scheduler="serial", progress=False, resume=True)
    assert (df.resume == "skipped: fingerprint matches").all()
    # the override changes the result: solved again, and the files say so
    df = run_batch(recs, rec / "spec.toml", out, scheduler="serial", progress=False, resume=True,
                   uncertainty="scaled")
    assert (df.resume == "re-solved: options changed (uncertainty: None -> 'scaled')").all()
    js = json.loads((out / "run2.json").read_text())
    assert js["uncertainty"]["scale"] == "scaled"
    assert js["run"]["fingerprint"]["options"]["uncertainty"] == "scaled"
    # and dropping the override again (the spec's true) too
    df = run_batch(recs, rec / "spec.toml", out, scheduler="serial", progress=False, resume=True)
    assert (df.resume == "re-solved: options changed (uncertainty: 'scaled' -> None)").all()
    assert json.loads((out / "run2.json").read_text())["uncertainty"]["scale"] == "stated"
    # the spec without the key is another spec: solved again, without the columns
    df = run_batch(recs, rec / "plain.toml", out, scheduler="serial", progress=False, resume=True)
    assert (df.resume == "re-solved: spec changed").all()
    assert list(pd.read_csv(out / "run1.csv").columns) == ["t", "x", "y", "vx", "vy"]
    assert "uncertainty" not in json.loads((out / "run1.json").read_text())


def test_batch_refuses_a_bad_uncertainty_override_before_any_work(rec, tmp_path):
    recs = tmp_path / "recs"
    recs.mkdir()
    write_recording(recs / "a.csv")
    with pytest.raises(bvpnav.InputError, match=r"uncertainty='stated': give True"):
        run_batch(recs, rec / "plain.toml", tmp_path / "out", scheduler="serial", progress=False,
                  uncertainty="stated")
    assert not (tmp_path / "out").exists()


def test_solve_recording_puts_the_std_columns_after_the_velocities(rec, tmp_path):
    sol, _ = solve_recording(rec / "recording.csv", load_spec(rec / "spec.toml"), tmp_path / "a.csv")
    assert list(sol.trajectory.columns) == ["x", "y", "vx", "vy", *STD_COLUMNS]
    assert list(pd.read_csv(tmp_path / "a.csv").columns) == ["t", *sol.trajectory.columns]


@pytest.mark.parametrize("header, ours", [
    ("t,x,vx", True), ("t,x,vx,x_std,vx_std", True),
    ("t,x,y,vx,vy,x_std,y_std,vx_std,vy_std", True),
    ("t,x,vx,vx_std,x_std", False), ("t,x,vx,x_std", False), ("t,x,vx,y_std,vy_std", False)])
def test_a_trajectory_with_std_columns_is_recognised_as_bvpnavs(tmp_path, header, ours):
    """An interrupted batch run leaves a trajectory without its JSON; the next run into that
    folder may replace it only if it is recognisably bvpnav's own output, std columns too."""
    from bvpnav.io import _trajectory_columns

    path = tmp_path / "rec.csv"
    path.write_text(header + "\n" + ",".join(["0"] * len(header.split(","))) + "\n")
    assert _trajectory_columns(path) is ours
