"""Solving recordings from files: one at a time, or many on Dask.

:func:`solve_recording` is the one code path from a file and a spec to a trajectory, a
JSON summary and a summary row; the ``solve`` command and :func:`run_batch` both call
it, so a batch gives bit-identical results to solving the recordings one by one.
"""

from __future__ import annotations

import time
import traceback
from pathlib import Path

import pandas as pd

from .errors import BvpnavError, InputError
from .io import read_recording, summary, write_json, write_table, write_trajectory

__all__ = ["solve_kwargs", "solve_recording", "run_batch", "RECORDING_SUFFIXES", "SUMMARY_COLUMNS"]

#: File types a batch picks up.
RECORDING_SUFFIXES = (".csv", ".parquet", ".pq")
#: Columns of the batch summary table.
SUMMARY_COLUMNS = ["recording", "ok", "error", "samples", "lam", "lam_rule", "solver", "status",
                   "verified", "seconds", "output"]


def solve_kwargs(spec, solver: str | None = None, lam=None) -> dict:
    """Keyword arguments of ``solve()`` from the spec's ``[solve]`` table and overrides."""
    kw = dict(spec.solve)
    if solver is not None:
        kw["solver"] = solver
    if lam is not None:
        kw["lam"] = lam
    if "fallback" in kw and kw["fallback"] in ("none", False):
        kw["fallback"] = None
    return kw


def solve_recording(path, spec, out, solver: str | None = None, lam=None, summary_path=None):
    """Solve one recording file with a spec; write the trajectory and its JSON summary.

    Parameters
    ----------
    path : path-like
        Recording (CSV or Parquet), read-only.
    spec : bvpnav.spec.Spec
    out : path-like
        Trajectory output (``.csv`` or ``.parquet``), written atomically.
    solver, lam : optional
        Overrides of the spec's ``[solve]`` table.
    summary_path : path-like, optional
        JSON summary (default: ``out`` with suffix ``.json``).

    Returns
    -------
    (Solution, dict)
        The solution and its summary row (see :data:`SUMMARY_COLUMNS`).
    """
    t0 = time.perf_counter()
    data = read_recording(path, spec.input)
    prob = spec.build(data)
    sol = prob.solve(**solve_kwargs(spec, solver, lam))
    out = Path(out)
    write_trajectory(sol, out)
    write_json(summary(sol, prob), summary_path or out.with_suffix(".json"))
    row = {"recording": str(path), "ok": True, "error": "", "samples": data.grid.n, "lam": sol.lam,
           "lam_rule": sol.lam_rule, "solver": sol.stats.get("solver"), "status": sol.stats.get("status"),
           "verified": bool(sol.stats.get("verified")), "seconds": time.perf_counter() - t0,
           "output": str(out)}
    return sol, row


def _task(path: str, spec_text: str, spec_source: str, out: str, solver, lam) -> dict:
    """One batch task (runs on a worker): never raises, returns a summary row."""
    from .spec import parse_spec

    t0 = time.perf_counter()
    try:
        spec = parse_spec(spec_text, spec_source)
        return solve_recording(path, spec, out, solver, lam)[1]
    except BvpnavError as exc:
        msg = f"{type(exc).__name__}: {exc}"
    except Exception as exc:  # a bug: keep the other recordings going, report it in full
        msg = f"{type(exc).__name__}: {exc} | " + traceback.format_exc(limit=3).replace("\n", " ")
    # the columns not given are empty in the summary table
    return {"recording": path, "ok": False, "error": msg, "verified": False,
            "seconds": time.perf_counter() - t0, "output": ""}


def run_batch(directory, spec_path, out_dir, scheduler: str | None = None, workers: int = 2,
              solver: str | None = None, lam=None, resume: bool = False, progress: bool = True,
              suffix: str = ".csv") -> pd.DataFrame:
    """Solve every recording in a folder with one spec, on Dask.

    Parameters
    ----------
    directory : path-like
        Folder of recordings (``*.csv``, ``*.parquet``); sorted by name.
    spec_path : path-like
        The spec file.
    out_dir : path-like
        Output folder: ``<stem><suffix>`` and ``<stem>.json`` per recording and
        ``summary.csv`` (one row per recording, failures included).
    scheduler : str, optional
        A ``dask.distributed`` scheduler address; default an in-process LocalCluster of
        ``workers`` single-threaded worker processes on the loopback interface.
        ``"serial"`` solves the recordings one after the other in this process, without
        Dask (for debugging and tests; an exception that is not an ``Exception``, such
        as ``KeyboardInterrupt``, stops the run, leaving the finished outputs).
    workers : int
        Workers of the local cluster.
    solver, lam : optional
        Overrides of the spec's ``[solve]`` table.
    resume : bool
        Skip recordings whose trajectory and summary already exist (an interrupted run
        leaves completed outputs intact: every file is written atomically).
    progress : bool
        Show a progress bar (tqdm).
    suffix : {".csv", ".parquet"}
        Trajectory file type.

    Returns
    -------
    pandas.DataFrame
        The summary table (also written to ``out_dir/summary.csv``).
    """
    from .spec import parse_spec, read_spec_text

    directory, out_dir = Path(directory), Path(out_dir)
    if not directory.is_dir():
        raise InputError(f"{str(directory)!r} is not a folder of recordings; give the folder that holds "
                         "the *.csv / *.parquet files")
    spec_text = read_spec_text(spec_path)  # the workers parse this same text
    parse_spec(spec_text, str(spec_path))  # fail early, in the client, on a bad spec
    files = sorted(p for p in directory.iterdir() if p.suffix.lower() in RECORDING_SUFFIXES)
    if not files:
        raise InputError(f"{str(directory)!r}: no recordings (*.csv, *.parquet) in it")
    out_dir.mkdir(parents=True, exist_ok=True)
    jobs, rows = [], []
    for p in files:
        out = out_dir / (p.stem + suffix)
        if resume and out.exists() and out.with_suffix(".json").exists():
            rows.append({"recording": str(p), "ok": True, "error": "", "status": "skipped (resume)",
                         "output": str(out)})
            continue
        jobs.append((str(p), spec_text, str(spec_path), str(out), solver, lam))
    if jobs and scheduler == "serial":
        rows += [_task(*job) for job in jobs]
    elif jobs:
        rows += _run_on_dask(jobs, scheduler, workers, progress)
    df = pd.DataFrame(rows, columns=SUMMARY_COLUMNS)
    df = df.sort_values("recording", kind="stable").reset_index(drop=True)
    write_table(df, out_dir / "summary.csv")
    return df


def _run_on_dask(jobs, scheduler, workers, progress) -> list[dict]:
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise InputError("batch needs dask.distributed: pip install 'bvpnav[batch]'") from None
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=max(int(workers), 1), threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address=None)
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        futures = [client.submit(_task, *job, pure=False) for job in jobs]
        bar = None
        if progress:
            from tqdm.auto import tqdm

            bar = tqdm(total=len(futures), desc="recordings", unit="rec")
        rows = []
        for fut in as_completed(futures):
            rows.append(fut.result())
            if bar is not None:
                bar.update(1)
        if bar is not None:
            bar.close()
        return rows
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
