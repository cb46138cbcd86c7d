"""Safety of files: inputs opened read-only, outputs atomic, interrupted batches resumable."""

from __future__ import annotations

import builtins
import io
import os
import stat

import numpy as np
import pandas as pd
import pytest

import bvpnav.batch
import bvpnav.io
from bvpnav.batch import run_batch
from bvpnav.cli import main
from bvpnav.io import write_table
from bvpnav.readers import read_recording
from bvpnav.samples import write_sample
from bvpnav.spec import load_spec

WRITE_MODES = set("wax+")


@pytest.fixture(scope="module")
def sample(tmp_path_factory):
    """The shuttle sample at 5 Hz (101 samples): recording.csv and spec.toml."""
    d = tmp_path_factory.mktemp("shuttle")
    write_sample("shuttle", d, rate=5.0)
    return d


def leftovers(folder):
    """Temporary files of the atomic writer (``.<name>.<random>.tmp``) left in a folder."""
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def test_solve_opens_read_only_inputs_for_reading_only(sample, tmp_path, monkeypatch):
    """chmod 0o444 inputs solve fine and keep bytes and mtime; a spy on open() also checks the
    mode, since chmod alone proves nothing when the tests run as root."""
    rec, spec = tmp_path / "rec.csv", tmp_path / "spec.toml"
    rec.write_bytes((sample / "recording.csv").read_bytes())
    spec.write_bytes((sample / "spec.toml").read_bytes())
    for p in (rec, spec):
        p.chmod(0o444)
    before = {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in (rec, spec)}
    opened = []  # (input path, mode or flags) for every open of an input
    real_open, real_os_open = builtins.open, os.open
    inputs = {str(rec), str(spec)}

    def spy_open(file, mode="r", *args, **kwargs):
        if str(file) in inputs:
            opened.append((str(file), mode))
        return real_open(file, mode, *args, **kwargs)

    def spy_os_open(path, flags, *args, **kwargs):
        if str(path) in inputs:
            opened.append((str(path), "w" if flags & (os.O_WRONLY | os.O_RDWR | os.O_APPEND) else "r"))
        return real_os_open(path, flags, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", spy_open)
    monkeypatch.setattr(io, "open", spy_open)
    monkeypatch.setattr(os, "open", spy_os_open)
    out = tmp_path / "out" / "traj.csv"
    assert main(["solve", str(rec), "--spec", str(spec), "--out", str(out), "--quiet"]) == 0
    monkeypatch.undo()
    assert {p for p, _ in opened} == inputs  # the spy saw both inputs being read ...
    assert all(not (WRITE_MODES & set(str(m))) for _, m in opened), opened  # ... and only read
    for p, (data, mtime) in before.items():
        assert p.read_bytes() == data and p.stat().st_mtime_ns == mtime
        assert stat.S_IMODE(p.stat().st_mode) == 0o444
    got = pd.read_csv(out)
    sp = load_spec(spec)
    ref = sp.build(read_recording(rec, sp.input)).solve(**sp.solve).trajectory
    assert len(got) == 101 and list(got.columns) == ["t", "x", "vx"]
    np.testing.assert_array_equal(got["x"].to_numpy(), ref["x"].to_numpy())
    assert abs(got["x"].iloc[0]) < 1e-12 and abs(got["x"].iloc[-1]) < 1e-12  # hard ends at the origin, m
    assert out.with_suffix(".json").exists() and leftovers(out.parent) == []


def test_a_read_only_parquet_recording_is_left_untouched(sample, tmp_path):
    rec = tmp_path / "rec.parquet"
    pd.read_csv(sample / "recording.csv").to_parquet(rec)
    rec.chmod(0o444)
    data, mtime = rec.read_bytes(), rec.stat().st_mtime_ns
    out = tmp_path / "traj.parquet"
    assert main(["solve", str(rec), "--spec", str(sample / "spec.toml"), "--out", str(out), "--quiet"]) == 0
    assert rec.read_bytes() == data and rec.stat().st_mtime_ns == mtime
    assert len(pd.read_parquet(out)) == 101


class DiskFull(OSError):
    pass


def half_then_fail(method):
    """Replace a writer method by one that writes half of its output, then fails."""
    def broken(self, path, *args, **kwargs):
        buf = io.StringIO()
        method(self, buf, *args, **kwargs)
        text = buf.getvalue()
        with builtins.open(path, "w") as fh:
            fh.write(text[: len(text) // 2])
        raise DiskFull(28, "No space left on device")
    return broken


#: An earlier bvpnav summary (solve's default summary path replaces only bvpnav's own).
OLD_SUMMARY = '{"lam": 1.0, "lam_rule": "fixed", "error_model": {}, "solver": {}, "items": []}\n'


@pytest.mark.parametrize("fails", ["trajectory", "summary"])
def test_a_failed_write_leaves_the_old_output_whole_and_no_temporary_file(sample, tmp_path, monkeypatch,
                                                                          fails):
    out, summ = tmp_path / "traj.csv", tmp_path / "traj.json"
    out.write_text("old trajectory\n")
    summ.write_text(OLD_SUMMARY)
    if fails == "trajectory":
        monkeypatch.setattr(pd.DataFrame, "to_csv", half_then_fail(pd.DataFrame.to_csv))
    else:
        real = type(out).write_text

        def write_text(self, text, *args, **kwargs):
            real(self, text[: len(text) // 2], *args, **kwargs)
            raise DiskFull(28, "No space left on device")
        monkeypatch.setattr(type(out), "write_text", write_text)
    code = main(["solve", str(sample / "recording.csv"), "--spec", str(sample / "spec.toml"), "--out",
                 str(out), "--quiet"])
    monkeypatch.undo()
    assert code == 2  # an OSError: reported, not a traceback
    assert summ.read_text() == OLD_SUMMARY
    if fails == "trajectory":
        assert out.read_text() == "old trajectory\n"
    else:  # the trajectory was complete and replaced before the summary failed
        assert len(pd.read_csv(out)) == 101
    assert leftovers(tmp_path) == []


def test_an_interrupt_mid_write_leaves_the_old_file(tmp_path, monkeypatch):
    out = tmp_path / "t.csv"
    write_table(pd.DataFrame({"t": [0.0, 1.0]}), out)
    old = out.read_bytes()

    def interrupted(self, path, *args, **kwargs):
        with builtins.open(path, "w") as fh:
            fh.write("t\n0.0\n")
        raise KeyboardInterrupt
    monkeypatch.setattr(pd.DataFrame, "to_csv", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_table(pd.DataFrame({"t": np.arange(5.0)}), out)
    assert out.read_bytes() == old and leftovers(tmp_path) == []


def test_an_interrupted_batch_keeps_finished_outputs_and_resumes(sample, tmp_path, monkeypatch):
    recs = tmp_path / "recs"
    recs.mkdir()
    for seed in range(5):
        write_sample("shuttle", tmp_path / f"s{seed}", seed=seed, rate=5.0)
        (tmp_path / f"s{seed}" / "recording.csv").rename(recs / f"run{seed}.csv")
    spec = sample / "spec.toml"
    out = tmp_path / "out"
    solved = []
    real_solve, real_json = bvpnav.batch.solve_recording, bvpnav.batch.write_json

    def counting_solve(path, *args, **kwargs):
        solved.append(os.path.basename(path))
        return real_solve(path, *args, **kwargs)

    def json_then_interrupt(obj, path):
        if os.path.basename(path) == "run2.json":  # run2's trajectory is written, its summary not
            raise KeyboardInterrupt
        real_json(obj, path)

    monkeypatch.setattr(bvpnav.batch, "solve_recording", counting_solve)
    monkeypatch.setattr(bvpnav.batch, "write_json", json_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        run_batch(recs, spec, out, scheduler="serial", progress=False)
    assert solved == ["run0.csv", "run1.csv", "run2.csv"]
    assert sorted(p.name for p in out.iterdir()) == ["run0.csv", "run0.json", "run1.csv", "run1.json",
                                                     "run2.csv"]  # no summary, no temporary file
    stamps = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    finished = {p.name: p.read_bytes() for p in out.iterdir()}

    monkeypatch.setattr(bvpnav.batch, "write_json", real_json)
    solved.clear()
    df = run_batch(recs, spec, out, scheduler="serial", progress=False, resume=True)
    assert solved == ["run2.csv", "run3.csv", "run4.csv"]  # run2 had no summary: solved again
    assert df.ok.all() and len(df) == 5
    assert df.status.tolist()[:2] == ["skipped (resume)"] * 2
    for name in ("run0.csv", "run0.json", "run1.csv", "run1.json"):
        p = out / name
        assert p.stat().st_mtime_ns == stamps[name] and p.read_bytes() == finished[name]
    assert (out / "run2.json").exists() and (out / "summary.csv").exists() and leftovers(out) == []
    # the resumed outputs are those of an uninterrupted run
    sp = load_spec(spec)
    for seed in range(5):
        ref = sp.build(read_recording(recs / f"run{seed}.csv", sp.input)).solve(**sp.solve).trajectory
        got = pd.read_csv(out / f"run{seed}.csv")
        np.testing.assert_array_equal(got["x"].to_numpy(), ref["x"].to_numpy())
    # a second resume solves nothing
    solved.clear()
    df = run_batch(recs, spec, out, scheduler="serial", progress=False, resume=True)
    assert solved == [] and (df.status == "skipped (resume)").all()


def test_the_json_summary_records_what_the_result_depends_on(sample, tmp_path):
    """The run record that --resume compares: spec text hash, options, the recording's size
    and content hash, and the trajectory's size and hash as written."""
    import hashlib
    import json

    out = tmp_path / "traj.csv"
    assert main(["solve", str(sample / "recording.csv"), "--spec", str(sample / "spec.toml"), "--out",
                 str(out), "--solver", "direct", "--quiet"]) == 0
    run = json.loads(out.with_suffix(".json").read_text())["run"]
    fp = run["fingerprint"]
    rec = (sample / "recording.csv").read_bytes()
    assert fp["spec_sha256"] == hashlib.sha256((sample / "spec.toml").read_bytes()).hexdigest()
    assert fp["options"] == {"solver": "direct", "lam": None, "format": ".csv"}
    assert fp["recording"]["size"] == len(rec)
    assert fp["recording"]["sha256"] == hashlib.sha256(rec).hexdigest()
    assert fp["recording"]["mtime_ns"] == (sample / "recording.csv").stat().st_mtime_ns
    assert run["samples"] == 101 and run["trajectory"]["size"] == out.stat().st_size
    assert run["trajectory"]["sha256"] == hashlib.sha256(out.read_bytes()).hexdigest()


@pytest.mark.slow
def test_reading_parquet_leaves_no_thread_that_aborts_the_process_at_exit(tmp_path):
    # pandas.read_parquet on a file object aborted 48 of 150 processes at interpreter exit
    # (SIGABRT, "terminate called without an active exception"; apache/arrow#34314): the CLI
    # printed its message and then exited -6 instead of 2. 16 clean exits in a row would
    # happen with probability 2e-3 if the abort were still possible.
    import subprocess
    import sys

    path = tmp_path / "rec.parquet"
    pd.DataFrame({"acc_x": np.zeros(50)}, index=pd.Index(np.arange(50) * 0.1, name="time")).to_parquet(path)
    script = ("import sys; from bvpnav.io import parquet_frame; p = sys.argv[1]; "
              "a = parquet_frame(open(p, 'rb').read()); b = parquet_frame(p); "
              "sys.exit(2 if a.index.name == b.index.name == 'time' and len(a) == 50 else 1)")
    codes = []
    for _ in range(8):  # two at a time
        procs = [subprocess.Popen([sys.executable, "-c", script, str(path)], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL) for _ in range(2)]
        codes += [p.wait(timeout=120) for p in procs]
    assert codes == [2] * 16, codes


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="counts threads in /proc (Linux)")
def test_reading_parquet_starts_no_arrow_thread(tmp_path):
    # The abort above is a thread of Arrow's pool alive at teardown; the probabilistic test can
    # miss it on a quiet machine, this one cannot: pandas.read_parquet starts one such thread
    # even with use_threads=False, parquet_frame must start none.
    import subprocess
    import sys

    path = tmp_path / "rec.parquet"
    index = pd.Index(np.arange(50) * 0.1, name="time")
    pd.DataFrame({"acc_x": np.arange(50.0)}, index=index).to_parquet(path)
    script = ("import os, sys, pandas, pyarrow.parquet; from bvpnav.io import parquet_frame\n"
              "n = lambda: len(os.listdir('/proc/self/task'))\n"
              "before = n(); a = parquet_frame(sys.argv[1])\n"
              "b = parquet_frame(open(sys.argv[1], 'rb').read())\n"
              "print(before, n(), a.index.name, float(a['acc_x'].sum()), b.equals(a))")
    out = subprocess.run([sys.executable, "-c", script, str(path)], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    before, after, name, total, same = out.stdout.split()
    assert int(after) == int(before), f"{int(after) - int(before)} thread(s) started by reading Parquet"
    assert (name, float(total), same) == ("time", 1225.0, "True")


# ------------------------------------------------------------- a folder recording (issue 40, case 5)
_FOLDER_SPEC = """\
[problem]
sigma_a = 0.1

[solve]
solver = "direct"
lam = 1.0

[[item]]
type = "position"
t = 0.0
value = [0.0, 0.0, 0.0]
mode = "hard"

[[item]]
type = "velocity"
t = 0.0
value = [0.0, 0.0, 0.0]
mode = "hard"
"""


@pytest.fixture()
def export(tmp_path):
    """A generated phone export folder (TotalAcceleration, Gyroscope, Orientation, Metadata .csv)
    and a spec that solves it."""
    from bvpnav.readers.phone import write_example_export

    ex = write_example_export(tmp_path / "export", duration=2.0)
    (tmp_path / "spec.toml").write_text(_FOLDER_SPEC)
    return ex.path


def _tree(folder):
    """Every file under ``folder`` -> (SHA-256 of its bytes, mode)."""
    import hashlib

    return {p.relative_to(folder): (hashlib.sha256(p.read_bytes()).hexdigest(), p.stat().st_mode)
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("target", [
    ("--out", "TotalAcceleration.csv"),     # the raw sensor file itself: was replaced, exit 0
    ("--out", "trajectory.csv"),            # a new file in the recording's folder
    ("--summary", "Metadata.json"),
    ("--plot", "figure.png"),
    ("--geodetic", "Gyroscope.csv"),
])
def test_no_output_goes_into_a_folder_recording(export, tmp_path, capsys, target):
    opt, name = target
    before = _tree(export)
    args = ["solve", str(export), "--spec", str(tmp_path / "spec.toml"), "--out", str(tmp_path / "traj.csv")]
    if opt == "--out":
        args[-1] = str(export / name)
    else:
        args += [opt, str(export / name)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert f"{opt} '{export / name}' is inside the input INPUT '{export}'" in err
    assert "never writes into its inputs" in err and "give " + opt + " a path outside" in err
    assert _tree(export) == before  # every input byte (and mode) unchanged, nothing added
    assert not (tmp_path / "traj.csv").exists()
    # and the same run with every output outside the folder solves
    assert main(["solve", str(export), "--spec", str(tmp_path / "spec.toml"), "--out",
                 str(tmp_path / "traj.csv")]) == 0
    assert _tree(export) == before


def test_links_into_a_folder_recording_are_inputs_too(export, tmp_path, capsys):
    """A symlink or a hard link outside the folder to one of its files is that file."""
    (tmp_path / "sym.csv").symlink_to(export / "TotalAcceleration.csv")
    os.link(export / "Gyroscope.csv", tmp_path / "hard.csv")
    before = _tree(export)
    for path, how in ((tmp_path / "sym.csv", "is inside the input INPUT"),
                      (tmp_path / "hard.csv", "is a hard link to the input INPUT (a file of the folder")):
        assert main(["solve", str(export), "--spec", str(tmp_path / "spec.toml"), "--out", str(path)]) == 2
        assert how in capsys.readouterr().err
    assert _tree(export) == before


def test_check_outputs_protects_every_file_of_an_input_folder(export, tmp_path):
    from bvpnav.errors import InputError

    sub = export / "more"
    sub.mkdir()
    (sub / "x.csv").write_text("t\n0\n")
    for out in (export / "more" / "x.csv", export / "more" / "new.csv", export / "new.csv"):
        with pytest.raises(InputError, match="is inside the input recording"):
            bvpnav.io.check_outputs({"recording": export}, {"out": out})
    with pytest.raises(InputError, match="the same file as the input recording"):
        bvpnav.io.check_outputs({"recording": export}, {"out": export})
    bvpnav.io.check_outputs({"recording": export}, {"out": tmp_path / "elsewhere.csv"})  # outside: fine
