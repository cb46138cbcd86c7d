"""Command line and files: simulate -> solve as a subprocess, specs round-trip, bad files.

``run`` starts ``python -m bvpnav.cli`` (the entry point as a user runs it); ``here`` calls
``bvpnav.cli.main`` in this process with the same exit code and output (``_hostile.main_cli``),
for checks of what a command does and says, where a new process adds only its start-up.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from _hostile import main_cli

import bvpnav
from bvpnav.error_models import Bias, Misalignment, ScaleFactor, UnknownGravity
from bvpnav.items import registry
from bvpnav.readers import read_recording
from bvpnav.spec import error_model_registry, load_spec, parse_spec, to_spec


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "bvpnav.cli", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=300)


def here(*args, cwd=None):
    return main_cli(list(args), cwd=cwd)


@pytest.fixture(scope="module")
def sample(tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    proc = here("simulate", "tikhonov2011", "--out", d / "rec")
    assert proc.returncode == 0, proc.stderr
    return d / "rec"


def test_simulate_then_solve_reproduces_the_python_api_exactly(sample, tmp_path):
    out = tmp_path / "traj.csv"
    proc = run("solve", sample / "recording.csv", "--spec", sample / "spec.toml", "--out", out,
               "--plot", tmp_path / "traj.png")
    assert proc.returncode == 0, proc.stderr
    spec = load_spec(sample / "spec.toml")
    prob = spec.build(read_recording(sample / "recording.csv", spec.input))
    sol = prob.solve(**spec.solve)
    got = pd.read_csv(out)
    assert list(got.columns) == ["t", "x", "vx"]
    np.testing.assert_array_equal(got["x"].to_numpy(), sol.trajectory["x"].to_numpy())
    np.testing.assert_array_equal(got["vx"].to_numpy(), sol.trajectory["vx"].to_numpy())
    summary = json.loads(out.with_suffix(".json").read_text())
    assert summary["lam_rule"] == "lcurve" and summary["lam"] == sol.lam
    truth = pd.read_csv(sample / "truth.csv")
    assert np.sqrt(np.mean((got["x"] - truth["x"]) ** 2)) < 1.5  # Table 1 row: ~0.8 m
    assert (tmp_path / "traj.png").stat().st_size > 5000


def test_parquet_in_and_out_match_csv(sample, tmp_path):
    rec = pd.read_csv(sample / "recording.csv")
    rec.to_parquet(tmp_path / "rec.parquet")
    a = read_recording(sample / "recording.csv", load_spec(sample / "spec.toml").input)
    b = read_recording(tmp_path / "rec.parquet", load_spec(sample / "spec.toml").input)
    np.testing.assert_array_equal(a.acc, b.acc)
    proc = here("solve", tmp_path / "rec.parquet", "--spec", sample / "spec.toml", "--out",
                tmp_path / "t.parquet", "--quiet")
    assert proc.returncode == 0 and proc.stdout == "", proc.stderr
    assert list(pd.read_parquet(tmp_path / "t.parquet").columns) == ["t", "x", "vx"]


@pytest.mark.parametrize("name,cls", sorted(registry().items()))
def test_every_item_round_trips_through_toml(name, cls):
    t = np.linspace(0.0, 10.0, 101)
    data = bvpnav.ImuData(t=t, acc=np.column_stack([np.sin(t), np.cos(t), 0.1 * t]))
    item = cls.example()
    prob = bvpnav.NavigationProblem(data).add(item)
    back = parse_spec(to_spec(prob)).build(data)
    (it2,) = back.items
    assert type(it2) is cls
    for f in ("mode", "sigma", "tol", "huber", "axes", "name"):
        a, b = getattr(item, f), getattr(it2, f)
        assert (a is None and b is None) or np.array_equal(np.asarray(a), np.asarray(b)), f
    # the rows, compiled for the model each example is written for (a gyro stance needs strapdown
    # data with a gyro model) and, for an item linearized by the solve, about one trajectory
    model = cls.example_model() or bvpnav.NavModel(data)
    if getattr(item, "needs_linearization", False):
        path = np.column_stack([t, 0.5 * t, 0.1 * t])
        item, it2 = item.linearized(t, path), it2.linearized(t, path)
    A, B = item.compile(model), it2.compile(model)
    assert (A.A != B.A).nnz == 0 and np.array_equal(A.c, B.c)


@pytest.mark.parametrize("model", [Bias(), ScaleFactor(axes=["x", "y"]), Misalignment(),
                                   UnknownGravity(prior=[0.0, 0.0, -9.81], sigma=0.01),
                                   Bias(bounds=(-1.0, 1.0)) + ScaleFactor(axes="z")],
                         ids=["bias", "scale", "misalignment", "gravity-prior", "composite-bounds"])
def test_every_error_model_round_trips_through_toml(model):
    t = np.linspace(0.0, 10.0, 101)
    data = bvpnav.ImuData(t=t, acc=np.column_stack([np.sin(t), np.cos(t), 0.1 * t]))
    prob = bvpnav.NavigationProblem(data, error_model=model, sigma_a=0.5)
    text = to_spec(prob, solve={"solver": "direct", "lam": 2.0})
    spec = parse_spec(text)
    back = spec.build(data)
    assert back.model.param_names == prob.model.param_names
    assert back.sigma_a.tolist() == prob.sigma_a.tolist() and spec.solve == {"solver": "direct", "lam": 2.0}
    assert to_spec(back) == to_spec(prob)


def test_error_model_registry_lists_the_builtins():
    assert set(error_model_registry()) >= {"bias", "scale_factor", "misalignment", "unknown_gravity"}


@pytest.mark.parametrize("text,needle", [
    ('[[item]]\ntype = "positon"\nt = 1.0\n', "line 2: unknown item 'positon'; valid types"),
    ('[[item]]\ntype = "position"\nt = 1.0\nvalu = 2\n', "line 4: item 'position' has no field 'valu'"),
    ('[problem]\nresidual = "acceleration"\nsigma = 1\n', "line 3: unknown key 'sigma' in [problem]"),
    ('[inputs]\ntime = "t"\n', "line 1: unknown section 'inputs'"),
    ('[input]\nunit = "furlong/s^2"\n', "line 2: unit='furlong/s^2'; valid acceleration units"),
    ('[[item]]\ntype = "position"\nt = 1.0\nsigma = -1\n', "line 1: Position: sigma"),
    ('[[error_model]]\ntype = "__import__"\n', "unknown error model '__import__'"),
    ("[[item]\n", "not valid TOML"),
])
def test_bad_specs_name_the_line_and_the_choices(text, needle):
    with pytest.raises(bvpnav.InputError) as exc:
        parse_spec(text, "spec.toml")
    assert needle in str(exc.value)


@pytest.mark.parametrize("body,needle", [
    ("t,acc_x\n0,1\n0.1,nan\n0.2,3\n0.3,1\n", "row 1 (line 3), column 'acc_x' is empty or NaN"),
    ("t,acc_x\n0,1\n0.2,2\n0.1,3\n0.3,1\n", "row 2 (line 4): time 0.1 goes back from"),
    ("t,acc_x\n0,1\n0.1,2\n0.1,3\n0.3,1\n", "row 2 (line 4): time 0.1 repeats"),
    ("t,acc_y\n0,1\n0.1,2\n0.2,3\n",
     "column 'acc_x' (axis x) not found; columns in the file: ['t', 'acc_y']"),
    ("t,acc_x\n0,1\n0.1,abc\n0.2,3\n", "row 1 (line 3), column 'acc_x' is not a number ('abc')"),
])
def test_bad_recordings_exit_2_with_one_line_naming_row_or_column(sample, tmp_path, body, needle):
    rec = tmp_path / "bad.csv"
    rec.write_text(body)
    before = rec.read_bytes()
    proc = here("solve", rec, "--spec", sample / "spec.toml", "--out", tmp_path / "o.csv")
    assert proc.returncode == 2
    assert needle in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert rec.read_bytes() == before and not (tmp_path / "o.csv").exists()


def test_wrong_unit_name_exits_2(sample, tmp_path):
    spec = (sample / "spec.toml").read_text().replace('unit = "m/s^2"', 'unit = "m/s2"')
    (tmp_path / "spec.toml").write_text(spec)
    proc = here("solve", sample / "recording.csv", "--spec", tmp_path / "spec.toml", "--out",
                tmp_path / "o.csv")
    assert proc.returncode == 2 and "unit='m/s2'; valid acceleration units" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_unit_conversions_g_and_ms(tmp_path):
    t = np.linspace(0.0, 2.0, 21)
    pd.DataFrame({"time_ms": t * 1000, "ax": np.full(21, 0.5)}).to_csv(tmp_path / "r.csv", index=False)
    data = read_recording(tmp_path / "r.csv", {"time": "time_ms", "time_unit": "ms", "unit": "g",
                                               "columns": {"x": "ax"}})
    np.testing.assert_allclose(data.grid.t, t, rtol=0, atol=1e-15)
    np.testing.assert_allclose(data.acc[:, 0], 0.5 * 9.80665, rtol=1e-15)


@pytest.mark.slow
def test_batch_on_a_local_cluster_matches_serial_and_reports_a_bad_recording(tmp_path):
    recs = tmp_path / "recs"
    recs.mkdir()
    from bvpnav.cli import main

    for seed in range(8):  # the recordings (in this process: the batch below is the subject)
        assert main(["simulate", "shuttle", "--out", str(tmp_path / f"s{seed}"), "--seed", str(seed),
                     "--quiet"]) == 0
        (tmp_path / f"s{seed}" / "recording.csv").rename(recs / f"run{seed}.csv")
    (recs / "broken.csv").write_text("t,acc_x\n0,1\n0.1,nan\n0.2,3\n0.3,1\n")
    spec_path = tmp_path / "s0" / "spec.toml"
    proc = run("batch", recs, "--spec", spec_path, "--out", tmp_path / "out", "--workers", 2, "--quiet")
    assert proc.returncode == 3, proc.stderr  # one recording failed
    summary = pd.read_csv(tmp_path / "out" / "summary.csv")
    assert len(summary) == 9 and summary.ok.sum() == 8
    bad = summary[~summary.ok].iloc[0]
    assert bad.recording.endswith("broken.csv") and "column 'acc_x' is empty or NaN" in bad.error
    spec = load_spec(spec_path)
    for seed in range(8):
        prob = spec.build(read_recording(recs / f"run{seed}.csv", spec.input))
        serial = prob.solve(**spec.solve).trajectory
        got = pd.read_csv(tmp_path / "out" / f"run{seed}.csv")
        np.testing.assert_array_equal(got["x"].to_numpy(), serial["x"].to_numpy())
    # resume: nothing is solved again, finished outputs are kept
    stamp = (tmp_path / "out" / "run0.csv").stat().st_mtime_ns
    proc = run("batch", recs, "--spec", spec_path, "--out", tmp_path / "out", "--resume", "--quiet")
    assert (tmp_path / "out" / "run0.csv").stat().st_mtime_ns == stamp


def test_example_specs_parse_and_match_the_simulated_ones(tmp_path):
    import pathlib

    specs = sorted((pathlib.Path(__file__).resolve().parents[1] / "examples" / "specs").glob("*.toml"))
    assert {p.stem for p in specs} >= {"shuttle", "tikhonov2011"}
    for p in specs:
        spec = load_spec(p)
        assert here("simulate", p.stem, "--out", tmp_path / p.stem, "--quiet").returncode == 0
        sim = load_spec(tmp_path / p.stem / "spec.toml")
        assert [type(i).__name__ for i in spec.items] == [type(i).__name__ for i in sim.items]
        assert spec.solve == sim.solve and spec.input == sim.input


def test_spec_on_conflict_demote_records_the_demoted_item(tmp_path):
    # two hard fixes disagree at t = 5 s; the spec trusts "fix A" more, so "fix B" is
    # demoted to soft (sigma 0.1 m), the run succeeds and the summary says so
    t = np.linspace(0.0, 10.0, 101)
    pd.DataFrame({"t": t, "acc_x": np.zeros_like(t)}).to_csv(tmp_path / "rec.csv", index=False)
    spec_text = """
[input]
time = "t"
columns = { x = "acc_x" }

[solve]
solver = "clarabel"
lam = 1.0
on_conflict = "demote"
priority = { "fix A" = 1.0 }
demote_sigma = 0.1

[[item]]
type = "position"
name = "ends"
t = [0.0, 10.0]
value = [0.0, 0.0]

[[item]]
type = "position"
name = "fix A"
t = 5.0
value = 1.0

[[item]]
type = "position"
name = "fix B"
t = 5.0
value = 2.0
"""
    (tmp_path / "spec.toml").write_text(spec_text)
    out = tmp_path / "traj.csv"
    proc = here("solve", tmp_path / "rec.csv", "--spec", tmp_path / "spec.toml", "--out", out)
    assert proc.returncode == 0, proc.stderr
    assert "'fix B'" in proc.stderr + proc.stdout and "demoted" in proc.stderr + proc.stdout
    got = pd.read_csv(out)
    assert abs(np.interp(5.0, got["t"], got["x"]) - 1.0) < 1e-9
    summary = json.loads(out.with_suffix(".json").read_text())
    assert [d["item"] for d in summary["solver"]["demoted"]] == ["fix B"]
    # without the option the same spec is an error naming both fixes (exit code 3)
    (tmp_path / "raise.toml").write_text(spec_text.replace('on_conflict = "demote"', ""))
    proc = here("solve", tmp_path / "rec.csv", "--spec", tmp_path / "raise.toml", "--out",
                tmp_path / "t2.csv")
    assert proc.returncode == 3 and "['fix A', 'fix B']" in proc.stderr
    with pytest.raises(bvpnav.InputError, match=r"line 9: on_conflict='ignore'"):
        parse_spec(spec_text.replace('"demote"', '"ignore"'))
    with pytest.raises(bvpnav.InputError, match=r"line 10: priority="):
        parse_spec(spec_text.replace("1.0 }", '"high" }'))
