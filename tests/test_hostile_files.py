"""Hostile matrix of outputs and the command line (issue 14): every way a run could destroy,
misread or hide something.

Each case asserts the exact exit code (or exception class), the culprit named in the message,
the fix, that every input and every earlier output is byte-identical (bytes and mode) and
that no temporary file is left. Cases that must be refused before any work also assert that
no file appeared.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import resource
import shutil
import signal
import socket
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from _hostile import (
    EXIT_INPUT,
    EXIT_INTERRUPT,
    EXIT_OK,
    EXIT_SOLVE,
    assert_clean_failure,
    assert_unchanged,
    raises_named,
    run_cli,
    snapshot,
    stray_temporaries,
)

import bvpnav.batch
import bvpnav.io
from bvpnav.cli import main
from bvpnav.errors import InputError
from bvpnav.readers import read_recording
from bvpnav.samples import write_sample
from bvpnav.spec import load_spec

EXIT_BUG, EXIT_TERM = 1, 143


# ------------------------------------------------------------------ fixtures and helpers
@pytest.fixture(scope="module")
def sample(tmp_path_factory):
    """The shuttle sample at 5 Hz (101 samples) and one earlier solve of it (traj.csv/.json)."""
    d = tmp_path_factory.mktemp("shuttle")
    write_sample("shuttle", d, rate=5.0)
    assert main(["solve", str(d / "recording.csv"), "--spec", str(d / "spec.toml"), "--out",
                 str(d / "traj.csv"), "--quiet"]) == 0
    return d


@pytest.fixture
def work(sample, tmp_path):
    """tmp_path with rec.csv, spec.toml and the earlier outputs traj.csv, traj.json."""
    for src, dst in (("recording.csv", "rec.csv"), ("spec.toml", "spec.toml"), ("traj.csv", "traj.csv"),
                     ("traj.json", "traj.json")):
        shutil.copyfile(sample / src, tmp_path / dst)
    return tmp_path


def files_in(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def cli(argv, capsys) -> tuple[int, str]:
    """Run ``main`` in this process; (exit code, stderr). Never a traceback."""
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    return code, err


def match_all(text: str, *patterns: str) -> None:
    for pat in patterns:
        assert re.search(pat, text, re.IGNORECASE | re.DOTALL), f"{pat!r} not in:\n{text}"


def solve_argv(t: Path, *extra) -> list:
    return ["solve", t / "rec.csv", "--spec", t / "spec.toml", "--quiet", *extra]


def recs_folder(t: Path, names=("run0.csv", "run1.csv")) -> Path:
    recs = t / "recs"
    recs.mkdir(exist_ok=True)
    for n in names:
        if n.endswith(".parquet"):
            pd.read_csv(t / "rec.csv").to_parquet(recs / n)
        else:
            shutil.copyfile(t / "rec.csv", recs / n)
    return recs


def batch_argv(t: Path, recs: Path, out: Path, *extra) -> list:
    return ["batch", recs, "--spec", t / "spec.toml", "--out", out, "--scheduler", "serial", "--quiet",
            *extra]


def _default_sigint():
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # a background test runner may have it ignored


def popen_cli(args, **kw) -> subprocess.Popen:
    """Start ``python -m bvpnav.cli ARGS`` in its own process group (as a terminal runs a
    command: Ctrl-C there is SIGINT to the whole group, see :func:`ctrl_c`)."""
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONWARNINGS="default")
    return subprocess.Popen([sys.executable, "-m", "bvpnav.cli", *map(str, args)], stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True, preexec_fn=_default_sigint, **kw)


def ctrl_c(proc: subprocess.Popen) -> None:
    """What Ctrl-C in a terminal does: SIGINT to every process of the command's group
    (the Dask workers included)."""
    os.killpg(proc.pid, signal.SIGINT)


def wait_for(cond, proc: subprocess.Popen, what: str, limit: float = 240.0) -> None:
    """Poll ``cond()`` until true (the process must still be running); a safety limit only."""
    end = time.monotonic() + limit
    while not cond():
        assert proc.poll() is None, f"process ended before {what}: {proc.communicate()}"
        assert time.monotonic() < end, f"never saw {what}"
        time.sleep(0.005)


def lock_holder(out: Path) -> str:
    """The process id written in ``out``'s lock file ('' while there is none)."""
    try:
        return (out / ".bvpnav.lock").read_text().strip()
    except OSError:
        return ""


def many_recordings(t: Path, n: int) -> Path:
    recs = t / "recs"
    recs.mkdir()
    for k in range(n):
        shutil.copyfile(t / "rec.csv", recs / f"run{k:02d}.csv")
    return recs


# ------------------------------------------------------------------ refused before any work
def _link(t, name, target):
    (t / name).symlink_to(t / target)
    return t / name


def _hard(t, name, target):
    os.link(t / target, t / name)
    return t / name


REFUSED = [
    # --- data loss: an output that is an input or another output
    pytest.param(lambda t: solve_argv(t, "--out", t / "rec.csv"),
                 r"--out '[^']*rec\.csv' is the same file as the input INPUT", r"give --out another path",
                 id="solve-out-is-the-recording"),
    pytest.param(lambda t: solve_argv(t, "--out", t / "nowhere" / ".." / "rec.csv"),
                 r"--out '[^']*nowhere/\.\./rec\.csv' is the same file as the input INPUT",
                 r"give --out another path", id="solve-out-is-the-recording-spelt-otherwise"),
    pytest.param(lambda t: solve_argv(t, "--out", _link(t, "link.csv", "rec.csv")),
                 r"--out '[^']*link\.csv' is the same file as the input INPUT '[^']*rec\.csv'",
                 r"give --out another path", id="solve-out-symlink-to-the-recording"),
    pytest.param(lambda t: solve_argv(t, "--out", _hard(t, "hard.csv", "rec.csv")),
                 r"--out '[^']*hard\.csv' is a hard link to the input INPUT '[^']*rec\.csv'",
                 r"give --out another path", id="solve-out-hard-link-to-the-recording"),
    pytest.param(lambda t: ["solve", t / "rec.csv", "--spec", _hard(t, "s.json", "spec.toml"), "--out",
                            t / "new.csv", "--summary", t / "s.json", "--quiet"],
                 r"--summary '[^']*s\.json' is the same file as the input --spec", r"give --summary another",
                 id="solve-summary-is-the-spec"),
    pytest.param(lambda t: ["solve", t / "rec.csv", "--spec", _hard(t, "new.json", "spec.toml"), "--out",
                            t / "new.csv", "--quiet"],
                 r"--summary \(default: --out with \.json\) '[^']*new\.json' is the same file as the input "
                 r"--spec", r"give --summary", id="solve-default-summary-is-the-spec"),
    pytest.param(lambda t: solve_argv(t, "--out", t / "traj.csv", "--plot", _link(t, "fig.png", "spec.toml")),
                 r"--plot '[^']*fig\.png' is the same file as the input --spec '[^']*spec\.toml'",
                 r"give --plot another path", id="solve-plot-symlink-to-the-spec"),
    pytest.param(lambda t: solve_argv(t, "--out", t / "traj.csv", "--summary",
                                      _link(t, "s.json", "traj.csv")),
                 r"--summary '[^']*s\.json' is the same file as the output --out '[^']*traj\.csv'",
                 r"give --summary another path", id="solve-summary-symlink-to-the-trajectory"),
    pytest.param(lambda t: ["lcurve", t / "rec.csv", "--spec", t / "spec.toml", "--plot", t / "l.png",
                            "--out", t / "rec.csv", "--quiet"],
                 r"--out '[^']*rec\.csv' is the same file as the input INPUT", r"give --out another path",
                 id="lcurve-out-is-the-recording"),
    pytest.param(lambda t: ["compare", t / "rec.csv", "--spec", t / "spec.toml", "--out",
                            _link(t, "table.csv", "rec.csv"), "--quiet"],
                 r"--out '[^']*table\.csv' is the same file as the input INPUT", r"give --out another path",
                 id="compare-out-symlink-to-the-recording"),
    pytest.param(lambda t: batch_argv(t, recs_folder(t), t / "recs"),
                 r"output folder \(--out\) '[^']*recs' is the folder of the recordings",
                 r"give --out another folder", id="batch-out-is-the-recordings-folder"),
    pytest.param(lambda t: batch_argv(t, recs_folder(t), _link(t, "results", "recs")),
                 r"output folder \(--out\) '[^']*results' is the folder of the recordings",
                 r"give --out another folder", id="batch-out-symlink-to-the-recordings-folder"),
    pytest.param(lambda t: batch_argv(t, recs_folder(t, ("a.csv", "a.parquet")), t / "out"),
                 r"recordings '[^']*a\.csv' and '[^']*a\.parquet' would both write '[^']*out/a\.csv'",
                 r"rename one of them", id="batch-two-recordings-one-stem"),
    pytest.param(lambda t: batch_argv(t, recs_folder(t, ("run.csv", "summary.csv")), t / "out"),
                 r"recording '[^']*summary\.csv' would write its trajectory onto the batch summary table",
                 r"rename the recording|--format parquet", id="batch-recording-named-summary"),
    pytest.param(lambda t: (recs_folder(t), (t / "out").mkdir(),
                            (t / "out" / "run0.csv").symlink_to(t / "recs" / "run0.csv"),
                            batch_argv(t, t / "recs", t / "out"))[-1],
                 r"--out \(output of run0\) '[^']*out/run0\.csv' is the same file as the input recording "
                 r"run0\.csv", r"give --out", id="batch-output-symlink-to-a-recording"),
    pytest.param(lambda t: (recs_folder(t), (t / "out").mkdir(),
                            os.link(t / "spec.toml", t / "out" / "run1.json"),
                            batch_argv(t, t / "recs", t / "out"))[-1],
                 r"--out \(summary of run1\) '[^']*out/run1\.json' is a hard link to the input --spec",
                 r"give --out", id="batch-summary-hard-link-to-the-spec"),
    pytest.param(lambda t: ["simulate", "shuttle", "--out", t, "--rate", "5", "--quiet"],
                 r"--out '[^']*' already holds spec\.toml", r"--force",
                 id="simulate-into-a-folder-with-a-spec"),
    pytest.param(lambda t: (t.joinpath("mine").mkdir(),
                            shutil.copyfile(t / "rec.csv", t / "mine" / "truth.csv"),
                            ["simulate", "shuttle", "--out", t / "mine", "--quiet"])[-1],
                 r"already holds truth\.csv", r"new or empty folder, or add --force",
                 id="simulate-over-a-users-truth-file"),
    # --- data loss: outputs that are not plain replaceable files
    pytest.param(lambda t: (t.joinpath("traj.csv").chmod(0o444), solve_argv(t, "--out", t / "traj.csv"))[-1],
                 r"--out '[^']*traj\.csv' is read-only \(mode 0444\)", r"chmod u\+w|another path",
                 id="solve-over-a-read-only-output"),
    pytest.param(lambda t: (t.joinpath("dir.csv").mkdir(), solve_argv(t, "--out", t / "dir.csv"))[-1],
                 r"--out '[^']*dir\.csv' is a folder", r"path of a regular file", id="solve-out-is-a-folder"),
    pytest.param(lambda t: solve_argv(t, "--out", t / "rec.csv" / "traj.csv"),
                 r"'[^']*rec\.csv' is a file, not a folder", r"give --out a path in a folder",
                 id="solve-out-inside-a-file"),
    pytest.param(lambda t: ["simulate", "shuttle", "--out", t / "rec.csv", "--quiet"],
                 r"'[^']*rec\.csv' is a file, not a folder", r"in a folder", id="simulate-out-is-a-file"),
    pytest.param(lambda t: ((t / "null.csv").symlink_to("/dev/null"),
                            solve_argv(t, "--out", t / "null.csv"))[-1],
                 r"--out '[^']*null\.csv' is a character device", r"path of a regular file",
                 id="solve-out-symlink-to-dev-null"),
    # --- hang: outputs that a writer would block on
    pytest.param(lambda t: (os.mkfifo(t / "pipe.csv"), solve_argv(t, "--out", t / "pipe.csv"))[-1],
                 r"--out '[^']*pipe\.csv' is a FIFO \(named pipe\)", r"path of a regular file",
                 id="solve-out-is-a-fifo"),
    pytest.param(lambda t: (os.mkfifo(t / "fig.png"), solve_argv(t, "--out", t / "o.csv", "--plot",
                                                                 t / "fig.png"))[-1],
                 r"--plot '[^']*fig\.png' is a FIFO \(named pipe\)", r"regular file",
                 id="solve-plot-is-a-fifo"),
    # --- misread input: suffixes and option lists checked up front, not after the work
    pytest.param(lambda t: solve_argv(t, "--out", t / "o.csv", "--plot", t / "out.txt"),
                 r"--plot '[^']*out\.txt': suffix '\.txt' is not a figure format", r"\.png",
                 id="solve-plot-txt"),
    pytest.param(lambda t: solve_argv(t, "--out", t / "o.csv", "--plot", t / "figure"),
                 r"--plot '[^']*figure': no suffix", r"\.png", id="solve-plot-no-suffix"),
    pytest.param(lambda t: solve_argv(t, "--out", t / "traj.txt"),
                 r"--out '[^']*traj\.txt': unknown output type '\.txt'", r"\.csv or \.parquet",
                 id="solve-out-txt"),
    pytest.param(lambda t: solve_argv(t, "--out", t / "o.csv", "--summary", t / "s.txt"),
                 r"--summary '[^']*s\.txt'", r"end its name with \.json", id="solve-summary-not-json"),
    pytest.param(lambda t: ["lcurve", t / "rec.csv", "--spec", t / "spec.toml", "--plot", t / "l.png",
                            "--rules", ",", "--quiet"],
                 r"--rules ',': no rule named", r"lcurve, gcv", id="lcurve-rules-comma"),
    pytest.param(lambda t: ["lcurve", t / "rec.csv", "--spec", t / "spec.toml", "--plot", t / "l.png",
                            "--rules", "lcurve,,gcv", "--quiet"],
                 r"--rules 'lcurve,,gcv': entry 2 is empty", r"separated by commas", id="lcurve-rules-hole"),
    pytest.param(lambda t: ["lcurve", t / "rec.csv", "--spec", t / "spec.toml", "--plot", t / "l.docx",
                            "--quiet"],
                 r"--plot '[^']*l\.docx': suffix '\.docx'", r"\.png", id="lcurve-plot-docx"),
    pytest.param(lambda t: ["compare", t / "rec.csv", "--spec", t / "spec.toml", "--solvers", "direct,",
                            "--quiet"],
                 r"--solvers 'direct,': an entry is empty", r"direct,clarabel", id="compare-solvers-hole"),
    pytest.param(lambda t: ["demo", "--plot", t / "demo.txt", "--quiet"],
                 r"--plot '[^']*demo\.txt'", r"\.png", id="demo-plot-txt"),
]


@pytest.mark.parametrize("build,culprit,fix", REFUSED)
def test_refused_before_any_work(build, culprit, fix, work, capsys):
    argv = build(work)
    before, names = snapshot(work), files_in(work)
    code, err = cli(argv, capsys)
    assert code == EXIT_INPUT, err
    assert err.startswith("bvpnav: error: ") and len(err.strip().splitlines()) == 1, err
    match_all(err, culprit, fix)
    assert_unchanged(before)
    assert files_in(work) == names  # nothing was written: the check came before the work
    assert stray_temporaries(work) == []


def test_simulate_force_replaces_its_own_files_only(work, capsys):
    """--force is the way to write into a folder that holds the three names; other files stay."""
    keep = snapshot(work / "rec.csv", work / "traj.csv", work / "traj.json")
    code, err = cli(["simulate", "shuttle", "--out", work, "--rate", "5", "--force", "--quiet"], capsys)
    assert code == EXIT_OK, err
    assert_unchanged(keep)
    assert load_spec(work / "spec.toml").solve["solver"] == "direct"
    assert len(pd.read_csv(work / "truth.csv")) == 101
    assert stray_temporaries(work) == []


# ------------------------------------------------------------------ modes of written files
def test_new_outputs_get_the_umask_mode_and_replaced_ones_keep_theirs(work, capsys):
    inputs = snapshot(work / "rec.csv", work / "spec.toml")
    old = os.umask(0o022)
    try:
        (work / "traj.csv").chmod(0o640)  # the earlier output: group-readable, not world
        code, err = cli(solve_argv(work, "--out", work / "traj.csv", "--plot", work / "new.png"), capsys)
    finally:
        os.umask(old)
    assert code == EXIT_OK, err
    assert stat.S_IMODE((work / "traj.csv").stat().st_mode) == 0o640  # kept, not made private
    for new in ("new.png",):
        assert stat.S_IMODE((work / new).stat().st_mode) == 0o644  # 0o666 & ~0o022, not mkstemp's 0o600
    assert stat.S_IMODE((work / "traj.json").stat().st_mode) == 0o644  # replaced a 0644 file
    assert_unchanged(inputs)
    assert stray_temporaries(work) == []


# ------------------------------------------------------------------ resume
def _bump(rec: Path) -> None:
    """Change one acceleration sample of a recording (same size class, other content)."""
    df = pd.read_csv(rec)
    df.loc[7, "acc_x"] += 0.5
    df.to_csv(rec, index=False)


RESUME = [
    pytest.param(lambda t, recs: (t / "spec.toml").write_text((t / "spec.toml").read_text().replace(
        "lam = 1.0", "lam = 2.0")), "all", r"re-solved: spec changed", id="spec-changed"),
    pytest.param(lambda t, recs: _bump(recs / "run0.csv"), "run0", r"re-solved: recording changed",
                 id="recording-changed"),
    pytest.param(lambda t, recs: (t / "out" / "run0.csv").write_bytes(b""), "run0",
                 r"re-solved: trajectory run0\.csv empty", id="zero-byte-trajectory"),
    pytest.param(lambda t, recs: (t / "out" / "run0.csv").write_bytes(
        (t / "out" / "run0.csv").read_bytes()[:300]), "run0",
        r"re-solved: trajectory run0\.csv changed since it was written", id="truncated-trajectory"),
    pytest.param(lambda t, recs: (t / "out" / "run0.json").write_text('{"lam": 1.0, "ru'), "run0",
                 r"re-solved: summary run0\.json unreadable", id="corrupt-summary"),
    pytest.param(lambda t, recs: (t / "out" / "run0.json").write_text(json.dumps({
        k: v for k, v in json.loads((t / "out" / "run0.json").read_text()).items() if k != "run"})),
        "run0", r"re-solved: summary run0\.json has no fingerprint", id="summary-of-an-older-bvpnav"),
    pytest.param(lambda t, recs: (t / "out" / "run0.csv").unlink(), "run0",
                 r"re-solved: trajectory run0\.csv missing", id="trajectory-deleted"),
    pytest.param("--solver", "all", r"re-solved: options changed \(solver: None -> 'clarabel'\)",
                 id="solver-changed"),
    pytest.param("--lam", "all", r"re-solved: options changed \(lam: None -> 3\.0\)", id="lam-changed"),
]


@pytest.mark.parametrize("change,which,note", RESUME)
def test_resume_solves_again_what_no_longer_matches(change, which, note, work, capsys):
    recs = recs_folder(work)
    out = work / "out"
    code, err = cli(batch_argv(work, recs, out), capsys)
    assert code == EXIT_OK, err
    extra = []
    if isinstance(change, str):  # an option of the new run
        extra = [change, {"--solver": "clarabel", "--lam": "3.0"}[change]]
    else:
        change(work, recs)
    keep = {n for n in ("run0", "run1") if which != "all" and n != which}
    before = snapshot(recs, work / "spec.toml", *[out / f"{n}{s}" for n in keep for s in (".csv", ".json")])
    code, err = cli(batch_argv(work, recs, out, "--resume", *extra), capsys)
    assert code == EXIT_OK, err
    assert_unchanged(before)  # inputs, and the outputs still valid, untouched
    df = pd.read_csv(out / "summary.csv", keep_default_na=False)
    for n in ("run0", "run1"):
        row = df[df.recording.str.endswith(f"{n}.csv")].iloc[0]
        if n in keep:
            assert row.status == "skipped (resume)" and row.resume == "skipped: fingerprint matches"
        else:
            match_all(row.resume, note)
            assert row.ok and row.status != "skipped (resume)"
            spec = load_spec(work / "spec.toml")
            kw = bvpnav.batch.solve_kwargs(spec, *(["clarabel", None] if change == "--solver" else
                                                   [None, 3.0] if change == "--lam" else [None, None]))
            ref = spec.build(read_recording(recs / f"{n}.csv", spec.input)).solve(**kw).trajectory
            np.testing.assert_array_equal(pd.read_csv(out / f"{n}.csv")["x"].to_numpy(), ref["x"].to_numpy())
    assert stray_temporaries(work) == []


# ------------------------------------------------------------------ signals (real processes)
@pytest.mark.slow
@pytest.mark.parametrize("scheduler", ["serial", "dask"])
def test_ctrl_c_in_a_batch_exits_130_in_one_line_and_resume_finishes_it(work, scheduler):
    recs = many_recordings(work, 24)
    out = work / "out"
    inputs = snapshot(recs, work / "spec.toml")
    argv = batch_argv(work, recs, out)
    if scheduler == "dask":  # the default: a LocalCluster of two worker processes
        argv = [a for a in argv if a not in ("--scheduler", "serial")]
    proc = popen_cli(argv)
    wait_for(lambda: any(out.glob("*.json")), proc, "the first finished recording")
    ctrl_c(proc)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == EXIT_INTERRUPT, stderr
    assert stderr.strip() == "bvpnav: interrupted" and "Traceback" not in stderr
    assert_unchanged(inputs)
    assert stray_temporaries(work) == [] and not (out / "summary.csv").exists()
    finished = sorted(p.stem for p in out.glob("*.json"))
    assert 1 <= len(finished) < 24
    earlier = snapshot(*[out / f"{n}{s}" for n in finished for s in (".csv", ".json")])
    proc2 = run_cli([*argv, "--resume"])
    assert proc2.returncode == EXIT_OK, proc2.stderr
    assert_unchanged(inputs)
    assert_unchanged(earlier)  # finished recordings were skipped, not written again
    df = pd.read_csv(out / "summary.csv", keep_default_na=False)
    assert len(df) == 24 and df.ok.all()
    assert (df.status == "skipped (resume)").sum() == len(finished)
    assert set(df.resume) <= {"skipped: fingerprint matches"} | {
        f"re-solved: no summary {p.stem}.json" for p in recs.iterdir()}
    assert stray_temporaries(work) == []


def test_a_worker_restarted_by_its_nanny_ignores_ctrl_c_too():
    """The batch's local workers ignore SIGINT so that Ctrl-C is handled by the batch alone.
    They inherited SIG_IGN while the cluster was built, but a worker that died (as from lack of
    memory) was started again by its nanny with Python's handler, so Ctrl-C printed its
    traceback; every worker, the restarted one included, must ignore it."""
    pytest.importorskip("dask.distributed")
    from dask.distributed import Client

    def sigint_handler() -> str:  # a local function: sent by value, nothing to import there
        return repr(signal.getsignal(signal.SIGINT))  # asyncio's handler cannot be sent back

    ignored = repr(signal.SIG_IGN)
    cluster = bvpnav.batch._local_cluster(1)  # one worker: the cheapest cluster that shows it
    try:
        with Client(cluster) as client:
            client.wait_for_workers(1, timeout=120)
            assert set(client.run(sigint_handler).values()) == {ignored}
            ((address, pid),) = client.run(os.getpid).items()
            os.kill(pid, signal.SIGKILL)  # its nanny starts another worker, at another address
            deadline = time.monotonic() + 120
            while ((len(now := set(client.scheduler_info()["workers"])) != 1 or address in now)
                   and time.monotonic() < deadline):
                time.sleep(0.2)
            assert len(now) == 1 and address not in now, (
                f"the nanny did not restart the killed worker {address} within 120 s (workers now: {now})")
            handlers = client.run(sigint_handler)
            assert set(handlers) == now and set(handlers.values()) == {ignored}, handlers
    finally:
        cluster.close()


def swallowing_task(monkeypatch, signum: int) -> list:
    """Replace the batch's task by one that, on the second recording, raises ``signum`` in
    this process and catches whatever its handler raises, reporting a bad file as pandas' C
    parser did ("Calling read(nbytes) on source failed"); returns the recordings the tasks
    were given."""
    import bvpnav.batch as batch

    real, calls = batch._task, []

    def task(*job):
        calls.append(job[0])
        if len(calls) == 2:
            try:
                signal.raise_signal(signum)
            except BaseException:   # like the parser: anything raised inside its read
                return {"recording": job[0], "ok": False, "error": "ParserError: read failed"}
        return real(*job)

    monkeypatch.setattr(batch, "_task", task)
    return calls


def test_ctrl_c_swallowed_by_a_library_still_stops_a_serial_batch(work, monkeypatch):
    """Ctrl-C while pandas' C parser reads a recording came back as a ParserError ("Calling
    read(nbytes) on source failed"): the recording was called a bad file and the batch went on
    (exit 3 instead of 130, seen once in CI). The serial loop notes the signal and stops."""
    import bvpnav.batch as batch

    recs = many_recordings(work, 6)
    out = work / "out"
    calls = swallowing_task(monkeypatch, signal.SIGINT)  # Ctrl-C
    # the caller here is a plain Python process: Python's own handler, SIGINT not blocked (an
    # earlier test in the same test worker must not decide what this one sees)
    found = signal.signal(signal.SIGINT, signal.default_int_handler)
    mask = signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGINT])
    before = signal.getsignal(signal.SIGINT)
    try:
        with pytest.raises(KeyboardInterrupt):
            batch.run_batch(recs, work / "spec.toml", out, scheduler="serial", progress=False)
        after = signal.getsignal(signal.SIGINT)
    finally:
        signal.signal(signal.SIGINT, found)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    assert len(calls) == 2                              # no recording after the interrupt
    assert after is before                              # the caller's handler is back
    assert sorted(p.name for p in out.glob("*.json")) == ["run00.json"] and not (out / "summary.csv").exists()


def test_sigterm_swallowed_by_a_library_still_stops_a_serial_batch(work, monkeypatch, capsys):
    """The CLI's SIGTERM handler raises an exception like Ctrl-C does, which a library can
    catch inside a task the same way (pandas' C parser turned it into a ParserError): the
    serial loop notes SIGTERM too, so the batch stops with exit 143 instead of calling the
    recording a bad file and solving the others."""
    recs = many_recordings(work, 6)
    out = work / "out"
    calls = swallowing_task(monkeypatch, signal.SIGTERM)
    before = signal.getsignal(signal.SIGTERM)
    code = main([str(a) for a in batch_argv(work, recs, out)])
    assert (code, capsys.readouterr().err.strip()) == (EXIT_TERM, "bvpnav: terminated")
    assert len(calls) == 2                              # no recording after the signal
    assert signal.getsignal(signal.SIGTERM) is before   # the caller's handler is back
    assert sorted(p.name for p in out.glob("*.json")) == ["run00.json"] and not (out / "summary.csv").exists()
    assert stray_temporaries(work) == [] and not (out / ".bvpnav.lock").exists()


def test_a_serial_batch_leaves_the_callers_sig_dfl_for_ctrl_c_as_it_is(work, monkeypatch):
    """A caller that set SIGINT to SIG_DFL wants Ctrl-C to end the process at once: the serial
    loop chains only Python handlers, so it neither replaces SIG_DFL during the recordings
    (before, its noting handler raised KeyboardInterrupt instead) nor afterwards."""
    import bvpnav.batch as batch

    recs = many_recordings(work, 2)
    out = work / "out"
    real, seen = batch._task, []

    def task(*job):
        seen.append(signal.getsignal(signal.SIGINT))
        return real(*job)

    monkeypatch.setattr(batch, "_task", task)
    before = signal.signal(signal.SIGINT, signal.SIG_DFL)
    try:
        df = batch.run_batch(recs, work / "spec.toml", out, scheduler="serial", progress=False)
        after = signal.getsignal(signal.SIGINT)
    finally:
        signal.signal(signal.SIGINT, before)
    assert df.ok.all() and len(df) == 2
    assert seen == [signal.SIG_DFL, signal.SIG_DFL] and after is signal.SIG_DFL


def test_sigterm_in_a_batch_exits_143_and_cleans_up(work):
    # 96 recordings: the signal must arrive while the batch still runs. With 24 the batch
    # ended about 0.8 s after the first summary appeared, and once in a fresh-clone CI run
    # on a noisy VM it had finished (exit 0) before the signal was sent
    recs = many_recordings(work, 96)
    out = work / "out"
    inputs = snapshot(recs, work / "spec.toml")
    proc = popen_cli(batch_argv(work, recs, out))
    wait_for(lambda: (out / "run00.json").exists(), proc, "the first finished recording")
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == EXIT_TERM, stderr
    assert stderr.strip() == "bvpnav: terminated"
    assert_unchanged(inputs)
    assert stray_temporaries(work) == [] and not (out / ".bvpnav.lock").exists()


def test_sigkill_mid_write_leaves_no_partial_output_and_the_next_run_removes_the_temporary(work):
    """simulate at 5 kHz writes 3.5 MB CSV files (each takes a while): killed while the first
    temporary exists, nothing partial is visible under a real name; the next bvpnav write into
    the folder removes the dead process's temporary."""
    d = work / "sim"
    others = snapshot(work)  # files beside the killed run's folder
    proc = popen_cli(["simulate", "shuttle", "--out", d, "--rate", "5000", "--quiet"])
    wait_for(lambda: d.is_dir() and stray_temporaries(d) != [], proc, "a temporary file")
    proc.kill()
    proc.wait()
    left = stray_temporaries(d)
    assert left and all(f".bvpnav-{_host()}-{proc.pid}-" in n for n in left), left
    visible = sorted(p.name for p in d.iterdir() if not p.name.startswith("."))
    for name in visible:  # only whole files under real names
        assert len(pd.read_csv(d / name)) == 100001
    code = run_cli(["simulate", "shuttle", "--out", d, "--rate", "5", "--force", "--quiet"])
    assert code.returncode == EXIT_OK, code.stderr
    assert stray_temporaries(d) == [] and len(pd.read_csv(d / "recording.csv")) == 101
    assert_unchanged(others)


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9_]", "_", socket.gethostname())[:40]


def test_stale_temporaries_of_dead_processes_are_removed_and_nothing_else(work, capsys):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True, check=True)
    pid = int(dead.stdout)
    stale = work / f".traj.csv.bvpnav-{_host()}-{pid}-0123abcd.tmp"
    alive = work / f".traj.csv.bvpnav-{_host()}-{os.getpid()}-89abcdef.tmp"  # this process: running
    other_host = work / f".traj.csv.bvpnav-elsewhere-{pid}-0123abcd.tmp"  # maybe running elsewhere
    users = work / ".notes.tmp"
    for p in (stale, alive, other_host, users):
        p.write_text("partial")
    keep = snapshot(work / "rec.csv", work / "spec.toml", alive, other_host, users)
    code, err = cli(solve_argv(work, "--out", work / "traj.csv"), capsys)
    assert code == EXIT_OK, err
    assert not stale.exists()
    assert_unchanged(keep)
    assert stray_temporaries(work) == sorted(p.name for p in (alive, other_host, users))


# ------------------------------------------------------------------ write failures
def _fsize_limit(nbytes: int):
    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, nbytes))
    return limit


def test_file_too_large_names_the_destination_not_the_temporary(work):
    """ulimit -f: the trajectory (~6 kB) exceeds 2 kB; Python ignores SIGXFSZ, write() gets EFBIG."""
    before = snapshot(work)
    proc = run_cli(solve_argv(work, "--out", work / "traj.csv"), preexec_fn=_fsize_limit(2000))
    assert_clean_failure(proc, EXIT_INPUT, r"cannot write '[^']*traj\.csv': the file is too large",
                         r"raise the limit or write to another disk", r"it was left as it was")
    assert ".tmp" not in proc.stderr and "Errno" not in proc.stderr
    assert_unchanged(before)
    assert stray_temporaries(work) == []


@contextlib.contextmanager
def tmpfs(where: Path, options: str):
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("needs root and mount(8) for a small tmpfs")
    where.mkdir()
    res = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(where)], capture_output=True)
    if res.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {res.stderr!r}")
    try:
        yield where
    finally:
        subprocess.run(["umount", str(where)], check=True)


def test_disk_full_on_a_small_tmpfs(work):
    with tmpfs(work / "small", "size=8k") as small:
        (small / "traj.csv").write_text("old trajectory\n")
        before = snapshot(work)
        proc = run_cli(solve_argv(work, "--out", small / "traj.csv"))
        assert_clean_failure(proc, EXIT_INPUT, r"cannot write '[^']*small/traj\.csv': the disk is full",
                             r"free some space or write to another disk", r"left as it was")
        assert ".tmp" not in proc.stderr
        assert_unchanged(before)
        assert stray_temporaries(work) == []


@contextlib.contextmanager
def read_only_folder(where: Path):
    """A folder nobody can write: chmod 0555 for a normal user; as root (who ignores modes) a
    read-only tmpfs."""
    if os.geteuid() != 0:
        where.mkdir()
        where.chmod(0o555)
        try:
            yield where
        finally:
            where.chmod(0o755)
        return
    with tmpfs(where, "ro,size=64k") as ro:
        yield ro


def test_outputs_in_a_read_only_folder_are_refused_before_the_solve(work):
    with read_only_folder(work / "ro") as ro:
        before = snapshot(work)
        proc = run_cli(solve_argv(work, "--out", ro / "traj.csv"))
        assert_clean_failure(proc, EXIT_INPUT, r"--out '[^']*ro/traj\.csv': cannot write in '[^']*ro'",
                             r"read-only|permission denied", r"a folder you can write to")
        proc = run_cli(batch_argv(work, recs_folder(work), ro / "out"))
        assert_clean_failure(proc, EXIT_INPUT, r"--out[^']*'[^']*ro/out/", r"read-only|permission denied",
                             r"folder you can write to")
        assert_unchanged(before)
        assert stray_temporaries(work) == []


def test_a_failed_write_reports_the_destination_in_the_api(work, monkeypatch):
    """The Python API raises InputError (not a raw OSError quoting '.traj.csv.<...>.tmp')."""
    import errno

    def full(self, path, *args, **kwargs):
        Path(path).write_text("t,x\n0,")
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    before = snapshot(work)
    monkeypatch.setattr(pd.DataFrame, "to_csv", full)
    err = raises_named(InputError,
                       lambda: bvpnav.io.write_table(pd.DataFrame({"t": [0.0]}), work / "traj.csv"),
                       r"cannot write '[^']*traj\.csv': the disk is full", r"free some space")
    assert ".tmp" not in str(err)
    assert_unchanged(before)
    assert stray_temporaries(work) == []


# ------------------------------------------------------------------ concurrent runs, vanishing inputs
def test_a_second_batch_into_the_same_folder_is_refused_at_once(work):
    recs = many_recordings(work, 24)
    out = work / "out"
    first = popen_cli(batch_argv(work, recs, out))
    # the lock file exists before it is locked and holds the pid: wait until it names the first run
    wait_for(lambda: lock_holder(out) == str(first.pid), first, "the first run's lock")
    first.send_signal(signal.SIGSTOP)  # hold it mid-run, deterministically
    try:
        before = snapshot(recs, work / "spec.toml", out)
        second = run_cli(batch_argv(work, recs, out))
        assert_clean_failure(second, EXIT_INPUT, rf"--out '[^']*out': another bvpnav run \(pid {first.pid}\)",
                             r"wait for it to finish or give --out another folder")
        assert_unchanged(before)
    finally:
        first.send_signal(signal.SIGCONT)
    _, stderr = first.communicate(timeout=300)
    assert first.returncode == EXIT_OK, stderr
    assert len(pd.read_csv(out / "summary.csv")) == 24 and stray_temporaries(work) == []


def test_a_recording_deleted_during_a_batch_is_a_failed_row(work, monkeypatch, capsys):
    recs = recs_folder(work, ("run0.csv", "run1.csv", "run2.csv"))
    real = bvpnav.batch.solve_recording

    def solve_then_delete(path, *args, **kwargs):
        res = real(path, *args, **kwargs)
        if path.endswith("run0.csv"):
            (recs / "run1.csv").unlink()
        return res

    monkeypatch.setattr(bvpnav.batch, "solve_recording", solve_then_delete)
    keep = snapshot(recs / "run0.csv", recs / "run2.csv", work / "spec.toml")
    code, err = cli(batch_argv(work, recs, work / "out"), capsys)
    out = capsys.readouterr()
    assert code == EXIT_SOLVE, err
    df = pd.read_csv(work / "out" / "summary.csv", keep_default_na=False)
    bad = df[~df.ok]
    assert len(bad) == 1 and bad.recording.iloc[0].endswith("run1.csv")
    match_all(bad.error.iloc[0], r"run1\.csv'?: no such file", r"check the path")
    assert df.ok.sum() == 2 and not out.err
    assert_unchanged(keep)
    assert stray_temporaries(work) == []


def test_a_recording_that_changes_during_its_solve_writes_nothing(work, monkeypatch, capsys):
    real = bvpnav.batch.read

    def read_then_append(path, *args, **kwargs):
        data = real(path, *args, **kwargs)
        with open(path, "a") as fh:  # another program is still writing the recording
            fh.write("20.2,0.5\n")
        return data

    monkeypatch.setattr(bvpnav.batch, "read", read_then_append)
    others = snapshot(work / "spec.toml", work / "traj.csv", work / "traj.json")
    code, err = cli(solve_argv(work, "--out", work / "new.csv"), capsys)
    assert code == EXIT_INPUT, err
    match_all(err, r"recording '[^']*rec\.csv' changed while it was being solved; nothing was written",
              r"run again")
    assert not (work / "new.csv").exists() and not (work / "new.json").exists()
    assert_unchanged(others)
    assert stray_temporaries(work) == []


# ------------------------------------------------------------------ tracebacks and vague endings
def test_an_internal_error_is_one_line_with_how_to_see_the_traceback(work, monkeypatch, capsys):
    def bug(*args, **kwargs):
        return {}["no such key"]

    monkeypatch.setattr(bvpnav.batch, "solve_recording", bug)
    before = snapshot(work)
    code, err = cli(solve_argv(work, "--out", work / "traj.csv"), capsys)
    assert code == EXIT_BUG
    assert len(err.strip().splitlines()) == 1
    match_all(err, r"bvpnav: internal error: KeyError: 'no such key'", r"BVPNAV_DEBUG=1")
    assert_unchanged(before)
    monkeypatch.setenv("BVPNAV_DEBUG", "1")
    assert main([str(a) for a in solve_argv(work, "--out", work / "traj.csv")]) == EXIT_BUG
    assert "Traceback" in capsys.readouterr().err  # asked for: shown
    assert_unchanged(before)
    assert stray_temporaries(work) == []


def test_out_of_memory_exits_3_suggesting_a_shorter_window(work, monkeypatch, capsys):
    def oom(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(bvpnav.batch, "solve_recording", oom)
    before = snapshot(work)
    code, err = cli(solve_argv(work, "--out", work / "traj.csv"), capsys)
    assert code == EXIT_SOLVE and len(err.strip().splitlines()) == 1
    match_all(err, r"out of memory", r"shorter window")
    assert_unchanged(before)
    assert stray_temporaries(work) == []


def test_ctrl_c_while_writing_exits_130_and_keeps_the_old_output(work, monkeypatch, capsys):
    def interrupted(self, path, *args, **kwargs):
        Path(path).write_text("t,x\n0,")
        raise KeyboardInterrupt

    monkeypatch.setattr(pd.DataFrame, "to_csv", interrupted)
    before = snapshot(work)
    code, err = cli(solve_argv(work, "--out", work / "traj.csv"), capsys)
    assert code == EXIT_INTERRUPT and err.strip() == "bvpnav: interrupted"
    assert_unchanged(before)
    assert stray_temporaries(work) == []


CONFLICT_SPEC = """
[input]
time = "t"
columns = { x = "acc_x" }

[solve]
lam = 1.0

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


def test_compare_with_nothing_verified_exits_3(work, capsys):
    (work / "conflict.toml").write_text(CONFLICT_SPEC)
    before = snapshot(work)
    code, err = cli(["compare", work / "rec.csv", "--spec", work / "conflict.toml", "--solvers",
                     "clarabel,direct", "--out", work / "table.csv", "--quiet"], capsys)
    assert code == EXIT_SOLVE, err
    match_all(err, r"none of the 2 runs gave a verified answer",
              r"try another solver or preset|check the spec")
    assert_unchanged(before)
    table = pd.read_csv(work / "table.csv")  # the table is still written: it says what failed
    assert len(table) == 2 and not table.verified.any()
    assert stray_temporaries(work) == []


def test_a_lock_left_by_a_killed_batch_does_not_block_the_next(work, capsys):
    """The lock is the kernel's: a killed run leaves the file, not the lock."""
    recs = recs_folder(work)
    (work / "out").mkdir()
    (work / "out" / ".bvpnav.lock").write_text("4194304\n")  # a pid from a run that was SIGKILLed
    inputs = snapshot(recs, work / "spec.toml")
    code, err = cli(batch_argv(work, recs, work / "out"), capsys)
    assert code == EXIT_OK, err
    assert not (work / "out" / ".bvpnav.lock").exists()
    assert len(pd.read_csv(work / "out" / "summary.csv")) == 2
    assert_unchanged(inputs)
    assert stray_temporaries(work) == []


# ------------------------------------------------------------------ the Python API refuses the same
def _solve_rec(t: Path, out: Path, **kw):
    return bvpnav.batch.solve_recording(t / "rec.csv", load_spec(t / "spec.toml"), out, **kw)


API = [
    pytest.param(lambda t: _solve_rec(t, t / "rec.csv"),
                 r"out '[^']*rec\.csv' is the same file as the input recording", r"give out another path",
                 id="solve_recording-out-is-the-recording"),
    pytest.param(lambda t: _solve_rec(t, t / "traj.csv", summary_path=t / "traj.csv"),
                 r"summary_path '[^']*traj\.csv' is the same file as the output out '[^']*traj\.csv'",
                 r"give summary_path another path", id="solve_recording-summary-onto-the-trajectory"),
    pytest.param(lambda t: bvpnav.batch.run_batch(recs_folder(t), t / "spec.toml", t / "recs",
                                                  scheduler="serial", progress=False),
                 r"output folder \(--out\) '[^']*recs' is the folder of the recordings", r"another folder",
                 id="run_batch-into-the-recordings-folder"),
    pytest.param(lambda t: write_sample("shuttle", t, rate=5.0),
                 r"already holds spec\.toml", r"--force", id="write_sample-over-a-spec"),
    pytest.param(lambda t: bvpnav.io.write_table(pd.DataFrame({"t": [0.0]}), t / "table.xlsx", "out"),
                 r"out '[^']*table\.xlsx': unknown output type '\.xlsx'", r"\.csv or \.parquet",
                 id="write_table-unknown-suffix"),
]


@pytest.mark.parametrize("call,culprit,fix", API)
def test_the_api_refuses_before_any_work(call, culprit, fix, work):
    before, names = snapshot(work), files_in(work)
    raises_named(InputError, lambda: call(work), culprit, fix)
    assert_unchanged(before)
    assert files_in(work) - names <= {"recs", "recs/run0.csv", "recs/run1.csv"}  # the set-up only
    assert stray_temporaries(work) == []


# ------------------------------------------------------------------ round 2 (issue 14 "Trust")
def _users_json(p: Path) -> Path:
    p.parent.mkdir(exist_ok=True)
    p.write_text('{"logger": "X200"}\n')
    return p


def _lock_link(t: Path) -> list:
    (t / "keep.txt").write_text("precious\n")
    argv = _batch_with(t, "x.txt", "")
    (t / "out" / ".bvpnav.lock").symlink_to(t / "keep.txt")
    return argv


def _batch_with(t: Path, name: str, content: str) -> list:
    recs = recs_folder(t, ("run0.csv",))
    (t / "out").mkdir()
    (t / "out" / name).write_text(content)
    return batch_argv(t, recs, t / "out")


ROUND2_REFUSED = [
    # --- data loss: a file at a path bvpnav chose (not typed by the user) that is not bvpnav's
    pytest.param(lambda t: (shutil.copyfile(t / "rec.csv", t / "run1.csv"), _users_json(t / "run1.json"),
                            solve_argv(t, "--out", t / "run1.parquet"))[-1],
                 r"--summary \(default: --out with \.json\) '[^']*run1\.json' already exists and is not a "
                 r"bvpnav JSON summary", r"give --summary PATH", id="F1-solve-default-summary-is-users-json"),
    pytest.param(lambda t: _batch_with(t, "run0.json", '{"logger": "X200"}\n'),
                 r"--out \(summary of run0\) '[^']*out/run0\.json' already exists and is not a bvpnav JSON",
                 r"move it out of the --out folder or give --out another folder", id="F2-batch-users-json"),
    pytest.param(lambda t: _batch_with(t, "run0.csv", "a,b\n1,2\n"),
                 r"--out \(output of run0\) '[^']*out/run0\.csv' already exists and is not a bvpnav "
                 r"trajectory",
                 r"give --out another folder", id="F2-batch-users-csv"),
    pytest.param(lambda t: _batch_with(t, "summary.csv", "my,notes\n"),
                 r"--out \(batch summary\) '[^']*out/summary\.csv' already exists and is not a table bvpnav",
                 r"give --out another folder", id="F2-batch-users-summary-csv"),
    # --- data loss: the lock file is a link to, or is, someone else's file
    pytest.param(lambda t: _lock_link(t),
                 r"lock file '[^']*out/\.bvpnav\.lock' is a symbolic link", r"remove the link|another folder",
                 id="F3-lock-symlink-to-a-users-file"),
    pytest.param(lambda t: _batch_with(t, ".bvpnav.lock", "my notes, not a pid\n"),
                 r"'[^']*out/\.bvpnav\.lock' exists and is not a bvpnav lock", r"move it away|another folder",
                 id="F3-lock-is-a-users-file"),
    # --- traceback: bad numbers for options
    pytest.param(lambda t: ["simulate", "shuttle", "--out", t / "sim", "--seed", "-1", "--quiet"],
                 r"--seed -1", r"integer >= 0", id="F13-simulate-negative-seed"),
    pytest.param(lambda t: ["demo", "--plot", t / "demo.png", "--seed", "-1", "--quiet"],
                 r"--seed -1", r"integer >= 0", id="F13-demo-negative-seed"),
    pytest.param(lambda t: batch_argv(t, recs_folder(t), t / "out")[:-3] + ["--workers", "0", "--quiet"],
                 r"--workers 0", r">= 1", id="F26-workers-0"),
    pytest.param(lambda t: batch_argv(t, recs_folder(t), t / "out")[:-3] + ["--workers", "-2", "--quiet"],
                 r"--workers -2", r">= 1", id="F26-workers-negative"),
    # --- hang / vague: simulate rates
    pytest.param(lambda t: ["simulate", "shuttle", "--out", t / "sim", "--rate", "1e7", "--quiet"],
                 r"--rate 1e\+07: .*would have 2e\+08 samples",
                 r"1,000,000.*give --rate 49999\.\d+ Hz or less",
                 id="F20-simulate-huge-rate"),
    pytest.param(lambda t: ["simulate", "shuttle", "--out", t / "sim", "--rate", "1e-9", "--quiet"],
                 r"--rate 1e-09: .*would have 1 samples", r"give --rate 2 Hz or more",
                 id="F23-simulate-tiny-rate"),
]


@pytest.mark.parametrize("build,culprit,fix", ROUND2_REFUSED)
def test_round2_refused_before_any_work(build, culprit, fix, work, capsys):
    argv = build(work)
    before, names = snapshot(work), files_in(work)
    code, err = cli(argv, capsys)
    assert code == EXIT_INPUT, err
    match_all(err, culprit, fix)
    assert_unchanged(before)
    assert files_in(work) == names
    assert stray_temporaries(work) == []


def test_round2_implicit_outputs_of_bvpnav_are_still_replaced(work, capsys):
    """F1/F2 policy: bvpnav's own earlier outputs at implicit paths are replaced as before."""
    inputs = snapshot(work / "rec.csv", work / "spec.toml")
    code, err = cli(solve_argv(work, "--out", work / "traj.csv"), capsys)  # traj.json is bvpnav's
    assert code == EXIT_OK, err
    recs = recs_folder(work, ("run0.csv",))
    for _ in range(2):
        code, err = cli(batch_argv(work, recs, work / "out"), capsys)
        assert code == EXIT_OK, err
    run = json.loads((work / "out" / "run0.json").read_text())["run"]
    assert run["trajectory"]["path"].endswith("run0.csv")
    assert_unchanged(inputs)


def test_round2_scheduler_is_case_insensitive(work, capsys):
    """F14: 'Serial' is 'serial', not an address to connect to."""
    recs = recs_folder(work, ("run0.csv",))
    inputs = snapshot(recs, work / "spec.toml")
    argv = batch_argv(work, recs, work / "out")
    argv[argv.index("serial")] = "Serial"
    code, err = cli(argv, capsys)
    assert code == EXIT_OK, err
    assert bool(pd.read_csv(work / "out" / "summary.csv").ok.all())
    assert_unchanged(inputs)


def test_round2_recording_name_not_utf8_is_solved(work, capsys):
    """F15: a file name that is not UTF-8 is solved; summary.csv and the JSON name it escaped."""
    recs = work / "recs"
    recs.mkdir()
    name = os.fsdecode(b"run\xe9.csv")
    shutil.copyfile(work / "rec.csv", recs / name)
    inputs = snapshot(recs, work / "spec.toml")
    code, err = cli(batch_argv(work, recs, work / "out"), capsys)
    assert code == EXIT_OK, err
    table = pd.read_csv(work / "out" / "summary.csv")
    assert table.recording.tolist() == [str(recs / "run") + "\\xe9.csv"] and bool(table.ok.all())
    assert json.loads((work / "out" / os.fsdecode(b"run\xe9.json")).read_text())["run"]["samples"] == 101
    assert_unchanged(inputs)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def _garbage_peer():
    """A loopback server that answers every connection with bytes that are not dask's."""
    import threading

    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen()
    srv.settimeout(0.2)
    stop = threading.Event()

    def serve():
        while not stop.is_set():
            try:
                c, _ = srv.accept()
            except OSError:
                continue
            with contextlib.suppress(OSError):
                c.sendall(b"\xff" * 64)
            c.close()

    th = threading.Thread(target=serve, daemon=True)
    th.start()
    try:
        yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    finally:
        stop.set()
        th.join()
        srv.close()


@contextlib.contextmanager
def _http_server():
    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(500):
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", port)) == 0:
                    break
            time.sleep(0.02)
        yield f"tcp://127.0.0.1:{port}"
    finally:
        proc.kill()
        proc.wait()


@contextlib.contextmanager
def _nothing_listening():
    yield f"tcp://127.0.0.1:{_free_port()}"


@pytest.mark.parametrize("peer", [pytest.param(_garbage_peer, id="F18-peer-answers-garbage"),
                                  pytest.param(_http_server, id="F22-http-server"),
                                  pytest.param(_nothing_listening, id="F25-nothing-listening")])
def test_round2_scheduler_that_is_not_dask_is_refused(peer, work, capsys, monkeypatch):
    """A scheduler address is input: exit 2 naming --scheduler and the address, within the
    connect timeout (shortened here), and nothing written (not even the --out folder)."""
    monkeypatch.setattr(bvpnav.batch, "CONNECT_TIMEOUT", 2.0)
    recs = recs_folder(work, ("run0.csv",))
    before, names = snapshot(work), files_in(work)
    with peer() as address:
        argv = batch_argv(work, recs, work / "out")
        argv[argv.index("serial")] = address
        code, err = cli(argv, capsys)
    assert code == EXIT_INPUT, err
    match_all(err, rf"--scheduler '{re.escape(address)}'", r"nothing is listening there or it is not a dask "
              r"scheduler", r"give its address|leave --scheduler out")
    assert_unchanged(before)
    assert files_in(work) == names
