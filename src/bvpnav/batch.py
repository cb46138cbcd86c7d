"""Solving recordings from files: one at a time, or many on Dask.

:func:`solve_recording` is the one code path from a file and a spec to a trajectory, a
JSON summary and a summary row; the ``solve`` command and :func:`run_batch` both call
it, so a batch gives bit-identical results to solving the recordings one by one.

Every finished recording's JSON summary carries a ``run`` record: the fingerprint of what
produced it (bvpnav version, SHA-256 of the spec text, the options that change results --
solver, lam, uncertainty, format -- and the recording's size, mtime and SHA-256) and the size and
SHA-256 of the trajectory written. ``run_batch(..., resume=True)`` skips a recording only
when that fingerprint matches and the trajectory is there, unchanged and readable;
otherwise it solves it again and the summary row's ``resume`` column says why.

With ``uncertainty`` (the spec's ``[solve]`` key or the override) each trajectory also
has the standard deviations ``<axis>_std`` (m) and ``v<axis>_std`` (m/s), after the
positions and velocities, and the JSON summary an ``uncertainty`` record
(:func:`uncertainty_summary`) and a ``std`` beside each error-model estimate.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import signal
import time
import traceback
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd

from . import __version__
from .declare import SOLVE_OPTIONS
from .errors import BvpnavError, InputError
from .io import (
    check_implicit_outputs,
    check_outputs,
    check_table_path,
    file_fingerprint,
    output_lock,
    parquet_frame,
    path_stamp,
    plain_json,
    remove_stale_temporaries,
    summary,
    write_json,
    write_table,
    write_trajectory,
)
from .log import once, signal_handled
from .log import progress as progress_bar
from .readers import align, read, reader_for
from .spec import parse_spec, read_spec_text

log = logging.getLogger(__name__)

__all__ = ["solve_kwargs", "overrides_of", "solve_recording", "run_batch", "fingerprint", "resume_reason",
           "uncertainty_option", "uncertainty_summary", "RECORDING_SUFFIXES", "SUMMARY_COLUMNS"]

#: File types a batch picks up.
RECORDING_SUFFIXES = (".csv", ".parquet", ".pq")
#: Columns of the batch summary table (``resume``: why a recording was skipped or solved
#: again by ``resume=True``; empty otherwise).
SUMMARY_COLUMNS = ["recording", "ok", "error", "samples", "lam", "lam_rule", "solver", "status",
                   "verified", "seconds", "output", "resume"]
#: The batch summary table's name in the output folder.
SUMMARY_NAME = "summary.csv"
#: Seconds to wait for a ``--scheduler`` address to answer as a dask scheduler.
CONNECT_TIMEOUT = 10.0


def display_path(path) -> str:
    r"""A path as text that can always be written (summary.csv, JSON, the terminal): a file
    name that is not valid UTF-8 keeps its bytes as ``\xNN`` escapes instead of failing."""
    return os.fsencode(path).decode("utf-8", "backslashreplace")


def uncertainty_option(value, option: str = "uncertainty") -> bool | str | None:
    """An ``uncertainty`` override checked: None (the spec decides), False, True or
    ``"scaled"``; :class:`InputError` (the declared message) otherwise."""
    return None if value is None else SOLVE_OPTIONS["uncertainty"].check(value)


def overrides_of(solver=None, lam=None, uncertainty=None, **more) -> dict:
    """The overrides of a run (None: not given, the spec decides), each checked by its
    declaration (:data:`bvpnav.declare.SOLVE_OPTIONS`: the message names the option and the
    value); an unknown name is refused listing the declared ones."""
    given = {"solver": solver, "lam": lam, "uncertainty": uncertainty, **more}
    unknown = [k for k in given if k not in SOLVE_OPTIONS]
    if unknown:
        raise InputError(f"unknown solve option(s) {unknown}; valid: {list(SOLVE_OPTIONS)}")
    return {k: SOLVE_OPTIONS[k].check(v) for k, v in given.items() if v is not None}


def solve_kwargs(spec, solver: str | None = None, lam=None, uncertainty=None, **more) -> dict:
    """Keyword arguments of ``solve()`` from the spec's ``[solve]`` table and overrides
    (each None keeps the spec's; any declared solve option may be overridden)."""
    return {**spec.solve, **{k: v for k, v in dict(solver=solver, lam=lam, uncertainty=uncertainty,
                                                     **more).items() if v is not None}}


def _sha256(text: str) -> str:
    import hashlib

    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _recording_fingerprint(path) -> dict:
    try:
        return file_fingerprint(path)
    except OSError as exc:
        raise InputError(f"recording {str(path)!r}: cannot read it ({exc.strerror}); it was removed or "
                         "changed during the run: restore it and run again") from None


def fingerprint(path, spec_text: str | None, solver=None, lam=None, fmt: str | None = None,
                recording: dict | None = None, uncertainty=None, **more) -> dict:
    """What a result depends on: bvpnav's version, the spec text's SHA-256, the options that
    change results (``solver``, ``lam``, ``format``, ``uncertainty``) and the recording's
    size, mtime (ns) and SHA-256 (``recording``, computed from ``path`` when not given).

    The spec's own ``[solve]`` keys (``uncertainty`` among them) are covered by the spec
    text's hash; the options are the overrides (None: not overridden). ``uncertainty`` is
    recorded only when it is overridden, so the fingerprints of runs without it are those
    bvpnav wrote before the option existed (a missing key reads as None in
    :func:`resume_reason`); so is every other overridden solve option (``more``: e.g.
    ``time_limit``)."""
    opts = {"solver": solver, "lam": lam, "format": fmt}
    opts.update({k: v for k, v in dict(uncertainty=uncertainty, **more).items() if v is not None})
    opts = json.loads(json.dumps(opts))
    return {"bvpnav": __version__, "spec_sha256": None if spec_text is None else _sha256(spec_text),
            "options": opts, "recording": recording or _recording_fingerprint(path)}


def uncertainty_summary(sol) -> dict | None:
    """The ``uncertainty`` record of a JSON summary, or None for a solve without it.

    Parameters
    ----------
    sol : Solution
        Solved with ``uncertainty=True`` or ``"scaled"``.

    Returns
    -------
    dict or None
        ``sol.stats["uncertainty"]`` (``scale``: ``"stated"`` or ``"scaled"``,
        ``variance_factor``, ``dof``, ``model``, ``method``, ``border``, ``block``,
        ``hard_rows_in_border``, ``border_condition``, ``pivot_condition``, ``time``) as plain
        JSON values, with ``columns`` (the trajectory's standard-deviation columns) and
        ``std``: the median and largest standard deviation of each (m or m/s).
    """
    rec = sol.stats.get("uncertainty")
    if not rec:
        return None
    out = plain_json(dict(rec))
    cols = [c for c in sol.trajectory.columns if c.endswith("_std")]
    out["columns"] = cols
    out["std"] = {c[: -len("_std")]: {"median": plain_json(float(np.median(sol.trajectory[c]))),
                                      "max": plain_json(float(np.max(sol.trajectory[c])))}
                  for c in cols if len(sol.trajectory)}
    return out


def _add_uncertainty(summ: dict, sol) -> None:
    """Put the uncertainty record and each error-model estimate's std into a summary."""
    rec = uncertainty_summary(sol)
    if rec is None:
        return
    std = getattr(sol, "error_params_std", None)
    for k, entry in summ.get("error_model", {}).items():
        if std is not None and k in std.index:
            entry["std"] = plain_json(float(std[k]))
    summ["uncertainty"] = rec


def solve_recording(path, spec, out, solver: str | None = None, lam=None, summary_path=None,
                    spec_text: str | None = None, uncertainty=None, information=(),
                    clock_offset: float | None = None, same_clock: bool = False, origin=None,
                    info_options=None, **more):
    """Solve one recording file with a spec; write the trajectory and its JSON summary.

    Parameters
    ----------
    path : path-like
        Recording (any reader's format: CSV, Parquet, a bag ...), read-only.
    spec : bvpnav.spec.Spec
    out : path-like
        Trajectory output (``.csv`` or ``.parquet``), written atomically.
    solver, lam : optional
        Overrides of the spec's ``[solve]`` table.
    uncertainty : bool or "scaled", optional
        Override of the spec's ``[solve]`` ``uncertainty`` (None: the spec's). With
        standard deviations the trajectory has ``<axis>_std`` (m) and ``v<axis>_std`` (m/s)
        after the velocities (``sol.trajectory`` is put in that column order too), and the
        summary an ``uncertainty`` record (:func:`uncertainty_summary`) and each
        error-model estimate a ``std``.
    summary_path : path-like, optional
        JSON summary (default: ``out`` with suffix ``.json``; at that default path an
        existing file is replaced only if it is a bvpnav JSON summary, see
        :func:`bvpnav.io.check_implicit_outputs`).
    spec_text : str, optional
        The spec's text, for the fingerprint in the summary's ``run`` record (see
        :func:`fingerprint`); None records no spec hash, so ``resume`` re-solves.
    information : sequence of path-like
        Files holding more information (an NMEA log: GNSS fixes), read by their suffix's
        reader and put on the recording's clock by :func:`bvpnav.readers.align`.
    clock_offset, same_clock : optional
        How those files' clocks relate to the recording's (see :func:`bvpnav.readers.align`).
    info_options : dict, optional
        Reader options for the information files (e.g. ``{"speed_as": "odometer"}`` for an
        NMEA log's speed over ground as an Odometer item), each given to the files whose
        reader takes it; a key no information file's reader takes is refused.
    **more
        Overrides of any other declared solve option (:data:`bvpnav.declare.SOLVE_OPTIONS`,
        e.g. ``time_limit``; None keeps the spec's), recorded in the fingerprint.
    origin : (float, float, float), optional
        Geodetic origin (latitude, longitude in degrees, height in m, WGS-84) of the local
        frame, for the information files that convert geodetic fixes; default the
        recording's own (a bag's first fix), else each file's first fix. The origin used
        is the row's ``geodetic_origin`` and the summary's ``run.geodetic_origin``.

    Returns
    -------
    (Solution, dict)
        The solution and its summary row (see :data:`SUMMARY_COLUMNS`).

    Raises
    ------
    InputError
        Before any work if an output is the recording or the other output, or cannot be
        written (:func:`bvpnav.io.check_outputs`), or has an unknown suffix; and if the
        recording changes while it is being solved (nothing is written then).
    """
    t0 = time.perf_counter()
    over = overrides_of(solver=solver, lam=lam, uncertainty=uncertainty, **more)
    out = Path(out)
    implicit = summary_path is None
    summary_path = Path(summary_path) if summary_path is not None else out.with_suffix(".json")
    fmt = check_table_path(out, "out")
    check_outputs({"recording": path, **{f"information {k + 1}": p for k, p in enumerate(information)}},
                  {"out": out, "summary_path": summary_path})
    if implicit:
        check_implicit_outputs({"summary_path (default: out with .json)": (summary_path, "summary")},
                               "move it away or give summary_path (--summary) another path")
    # size and mtime before reading: a recording still being written is caught below (None:
    # missing, a FIFO ...: the reader says so, naming the fix)
    before = path_stamp(path)
    # the reader first: it looks at the file's head before reading it whole, so a file that is
    # no recording (a 40 GB preallocated log, a zip) is refused at once, before it is hashed
    rec = read(path, spec.input)
    rec_fp = _recording_fingerprint(path)
    if before is not None and before != (rec_fp["size"], rec_fp["mtime_ns"]):
        raise InputError(f"recording {str(path)!r} changed while it was being solved; nothing was written: "
                         "wait until it is complete and run again")
    frame = spec.input.get("frame", "enu")
    info = list(rec.items_in(frame))
    notes = list(rec.notes)
    own = rec.meta.get("geodetic_origin")
    if origin is not None and own is not None and not np.allclose(origin, own, rtol=0, atol=1e-9):
        raise InputError(f"--origin {list(origin)}: the recording's own fixes are in the local frame about "
                         f"{list(own)} (its first fix or its [input] origin); give that origin in the spec's "
                         "[input] origin = [lat, lon, h] instead, so that every item and the geodetic output "
                         "share one frame")
    geo = list(origin) if origin is not None else own
    info_options = dict(info_options or {})
    takes_any = set().union(*(reader_for(p).options for p in information)) if information else set()
    unknown = sorted(set(info_options) - takes_any)
    if unknown:
        raise InputError(f"information option(s) {unknown} (--info-option): no information file's reader "
                         f"takes them; the readers of {[display_path(p) for p in information]} take "
                         f"{sorted(takes_any)}")
    for extra in information:  # fixes in the recording's local frame: its frame, one origin
        takes = reader_for(extra).options
        opts = {k: v for k, v in info_options.items() if k in takes}
        opts.update({"local_frame": frame} if "local_frame" in takes else {})
        if geo is not None and "origin" in takes:
            opts["origin"] = [float(v) for v in geo]
        more = read(extra, opts)
        geo = geo if geo is not None else more.meta.get("geodetic_origin")
        items, said = align(more, rec, clock_offset=clock_offset, same_clock=same_clock)
        info += items
        notes += list(more.notes) + said
    for note in notes:
        log.info("%s: %s", display_path(path), note)
    data = spec.imu_data(rec, info)  # after the information files: [align] may take its heading from them
    prob = spec.build(data, info=info)
    sol = prob.solve(**solve_kwargs(spec, **over))
    now = _recording_fingerprint(path)
    if (now["size"], now["sha256"]) != (rec_fp["size"], rec_fp["sha256"]):
        raise InputError(f"recording {str(path)!r} changed while it was being solved; nothing was written: "
                         "wait until it is complete and run again")
    write_trajectory(sol, out)
    written = file_fingerprint(out)
    summ = summary(sol, prob)
    _add_uncertainty(summ, sol)
    summ["run"] = {"recording": display_path(path), "samples": int(data.grid.n), "notes": notes,
                   "geodetic_origin": geo,
                   "information": [display_path(p) for p in information],
                   "information_options": info_options,
                   "fingerprint": fingerprint(path, spec_text, fmt=fmt, recording=rec_fp,
                                              **{"solver": solver, "lam": lam, **over}),
                   "trajectory": {"path": display_path(out), "size": written["size"],
                                  "sha256": written["sha256"]}}
    write_json(summ, summary_path)
    row = {"recording": display_path(path), "ok": True, "error": "", "samples": data.grid.n, "lam": sol.lam,
           "lam_rule": sol.lam_rule, "solver": sol.stats.get("solver"), "status": sol.stats.get("status"),
           "verified": bool(sol.stats.get("verified")), "seconds": time.perf_counter() - t0,
           "output": display_path(out), "resume": "", "geodetic_origin": geo, "items": list(prob.items)}
    return sol, row


def _task(path: str, spec_text: str, spec_source: str, out: str, over: dict, note: str = "") -> dict:
    """One batch task (runs on a worker): never raises an ``Exception``, returns a summary row."""
    t0 = time.perf_counter()
    try:
        spec = parse_spec(spec_text, spec_source)
        row = solve_recording(path, spec, out, spec_text=spec_text, **over)[1]
        row.pop("items", None)  # the problem's items stay on the worker
        row["resume"] = note
        return row
    except BvpnavError as exc:
        msg = f"{type(exc).__name__}: {exc}"
    except MemoryError:
        msg = ("MemoryError: out of memory solving this recording; solve it in shorter windows "
               "(fewer samples each) or on a machine with more memory")
    except Exception as exc:  # a bug: keep the other recordings going, report it in full
        msg = (f"internal error (a bug in bvpnav, please report it): {type(exc).__name__}: {exc} | "
               + traceback.format_exc(limit=3).replace("\n", " "))
    # the columns not given are empty in the summary table
    return {"recording": display_path(path), "ok": False, "error": msg, "verified": False,
            "seconds": time.perf_counter() - t0, "output": "", "resume": note}


def resume_reason(recording, out, summary_path, current: dict) -> tuple[str | None, dict]:
    """Why a finished-looking recording must be solved again (None: it may be skipped).

    Parameters
    ----------
    recording : path-like
    out, summary_path : path-like
        Its trajectory and JSON summary.
    current : dict
        The fingerprint of this run (:func:`fingerprint`).

    Returns
    -------
    (str or None, dict)
        The reason (e.g. ``"spec changed"``) or None, and the summary read (empty if none).
    """
    out, summary_path = Path(out), Path(summary_path)
    if not summary_path.is_file():
        return f"no summary {summary_path.name}", {}
    try:
        js = json.loads(summary_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return f"summary {summary_path.name} unreadable", {}
    run = js.get("run") if isinstance(js, dict) else None
    if not isinstance(run, dict) or not isinstance(run.get("fingerprint"), dict):
        return f"summary {summary_path.name} has no fingerprint (written by an older bvpnav)", {}
    old = run["fingerprint"]
    if old.get("bvpnav") != current["bvpnav"]:
        return f"bvpnav version changed ({old.get('bvpnav')} -> {current['bvpnav']})", js
    if old.get("spec_sha256") is None or old.get("spec_sha256") != current["spec_sha256"]:
        return "spec changed", js
    oo, co = old.get("options") or {}, current["options"]
    keys = list(co) + [k for k in oo if k not in co]  # an override given before and not now counts
    changed = [f"{k}: {oo.get(k)!r} -> {co.get(k)!r}" for k in keys if oo.get(k) != co.get(k)]
    if changed:
        return "options changed (" + ", ".join(changed) + ")", js
    orec, crec = old.get("recording") or {}, current["recording"]
    if (orec.get("size"), orec.get("sha256")) != (crec["size"], crec["sha256"]):
        return "recording changed", js
    traj = run.get("trajectory") or {}
    if not out.is_file():
        return f"trajectory {out.name} missing", js
    try:
        got = file_fingerprint(out)
    except OSError:
        return f"trajectory {out.name} unreadable", js
    if got["size"] == 0:
        return f"trajectory {out.name} empty", js
    if (got["size"], got["sha256"]) != (traj.get("size"), traj.get("sha256")):
        return f"trajectory {out.name} changed since it was written", js
    try:
        df = pd.read_csv(out) if out.suffix.lower() == ".csv" else parquet_frame(out)
    except Exception:  # any parser failure means: solve again
        return f"trajectory {out.name} unreadable", js
    if "t" not in df.columns or len(df) != run.get("samples"):
        return f"trajectory {out.name} incomplete", js
    return None, js


def _plan_outputs(files: list[Path], out_dir: Path, suffix: str) -> list[Path]:
    """Trajectory path of each recording; refuses two recordings that would write the same
    output and a recording whose output would be the batch summary table."""
    seen: dict[str, Path] = {}
    outs = []
    for p in files:
        key = p.stem.casefold()  # case-insensitive file systems: A.csv and a.csv collide too
        if key in seen:
            raise InputError(f"recordings {str(seen[key])!r} and {str(p)!r} would both write "
                             f"{str(out_dir / (p.stem + suffix))!r} and {p.stem}.json (outputs are named "
                             "after the recording's name without its suffix): rename one of them or move "
                             "it to another folder")
        seen[key] = p
        out = out_dir / (p.stem + suffix)
        if out.name.casefold() == SUMMARY_NAME:
            raise InputError(f"recording {str(p)!r} would write its trajectory onto the batch summary table "
                             f"{str(out_dir / SUMMARY_NAME)!r}: rename the recording (any name but "
                             "'summary') or use --format parquet")
        outs.append(out)
    return outs


def run_batch(directory, spec_path, out_dir, scheduler: str | None = None, workers: int = 2,
              solver: str | None = None, lam=None, resume: bool = False, progress: bool | None = None,
              suffix: str = ".csv", uncertainty=None, **more) -> pd.DataFrame:
    """Solve every recording in a folder with one spec, on Dask.

    Parameters
    ----------
    directory : path-like
        Folder of recordings (``*.csv``, ``*.parquet``); sorted by name.
    spec_path : path-like
        The spec file.
    out_dir : path-like
        Output folder: ``<stem><suffix>`` and ``<stem>.json`` per recording and
        ``summary.csv`` (one row per recording, failures included). It must not be
        ``directory``; two recordings with the same stem (``a.csv``, ``a.parquet``) and a
        recording whose trajectory would be ``summary.csv`` are refused before any work.
        While the batch runs it holds a lock on the folder (``.bvpnav.lock``): a second
        run into the same folder is refused.
    scheduler : str, optional
        A ``dask.distributed`` scheduler address, connected to (within
        :data:`CONNECT_TIMEOUT` seconds) before any output is written; default an
        in-process LocalCluster of ``workers`` single-threaded worker processes on the
        loopback interface; its workers ignore SIGINT (Ctrl-C is for this process alone),
        also one restarted after a death, and while they start SIGINT is ignored here too
        (they inherit it), so a Ctrl-C before they are up is lost. ``"serial"`` (any
        case) solves the recordings one after the other in this process, without Dask
        (for debugging and tests; an exception that is not an ``Exception``, such as
        ``KeyboardInterrupt``, stops the run, leaving the finished outputs).
    workers : int
        Workers of the local cluster (>= 1).
    solver, lam : optional
        Overrides of the spec's ``[solve]`` table.
    resume : bool
        Skip a recording only when its JSON summary's fingerprint matches this run (spec
        text, solver, lam, uncertainty, format, the recording's content, bvpnav's version) and its
        trajectory exists unchanged and readable; every other recording is solved again,
        and the ``resume`` column of its row says why (e.g. ``re-solved: spec changed``).
    progress : bool, optional
        A progress bar of the recordings done (tqdm): True always, False never, None
        (default) when stderr is a terminal. Each finished recording is also logged at
        INFO on ``bvpnav.batch``.
    suffix : {".csv", ".parquet"}
        Trajectory file type.
    uncertainty : bool or "scaled", optional
        Override of the spec's ``[solve]`` ``uncertainty`` (None: the spec's); see
        :func:`solve_recording` for the columns and the summary record.
    **more
        Overrides of any other declared solve option (e.g. ``time_limit``), checked
        before any work and part of each fingerprint.

    Returns
    -------
    pandas.DataFrame
        The summary table (also written to ``out_dir/summary.csv``).

    Raises
    ------
    InputError
        Bad folder or spec, output collisions (see ``out_dir``), an output that is an input
        (symlink, hard link), a file in ``out_dir`` at an output's path that is not
        bvpnav's own output (a JSON summary, a trajectory named by the summary beside it,
        a batch summary table), an output folder that cannot be written or is in use by
        another run, ``workers`` < 1, a scheduler that cannot be reached; all before any
        recording is solved.
    """
    directory, out_dir = Path(directory), Path(out_dir)
    if not directory.is_dir():
        raise InputError(f"{str(directory)!r} is not a folder of recordings; give the folder that holds "
                         "the *.csv / *.parquet files")
    if suffix not in (".csv", ".parquet"):
        raise InputError(f"suffix={suffix!r}: the trajectory format is '.csv' or '.parquet'")
    over = overrides_of(solver=solver, lam=lam, uncertainty=uncertainty, **more)
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"--workers {workers!r}: the number of local workers must be an integer >= 1, "
                         "e.g. --workers 2")
    if scheduler is not None:
        scheduler = str(scheduler).strip()
        if scheduler.casefold() == "serial":
            scheduler = "serial"
        elif not scheduler:
            raise InputError("--scheduler '': give a dask scheduler address (e.g. tcp://host:8786) or "
                             "'serial'; leave it out for a local cluster")
    spec_text = read_spec_text(spec_path)  # the workers parse this same text
    parse_spec(spec_text, str(spec_path))  # fail early, in the client, on a bad spec
    if os.path.realpath(out_dir) == os.path.realpath(directory) or (
            out_dir.is_dir() and os.path.samefile(out_dir, directory)):
        raise InputError(f"the output folder (--out) {str(out_dir)!r} is the folder of the recordings "
                         f"{str(directory)!r}: the outputs would mix with the recordings (and a later batch "
                         "would read them as recordings); give --out another folder")
    files = sorted(p for p in directory.iterdir() if p.suffix.lower() in RECORDING_SUFFIXES)
    if not files:
        raise InputError(f"{str(directory)!r}: no recordings (*.csv, *.parquet) in it")
    outs = _plan_outputs(files, out_dir, suffix)
    inputs = {"--spec": spec_path, **{f"recording {p.name}": p for p in files}}
    outputs = {"--out": out_dir / SUMMARY_NAME}
    for o in outs:
        outputs[f"--out (output of {o.stem})"] = o
        outputs[f"--out (summary of {o.stem})"] = o.with_suffix(".json")
    check_outputs(inputs, outputs)
    implicit = {"--out (batch summary)": (out_dir / SUMMARY_NAME, tuple(SUMMARY_COLUMNS))}
    for o in outs:
        implicit[f"--out (output of {o.stem})"] = (o, "trajectory")
        implicit[f"--out (summary of {o.stem})"] = (o.with_suffix(".json"), "summary")
    check_implicit_outputs(implicit, "move it out of the --out folder or give --out another folder")
    client = _connect(scheduler) if scheduler not in (None, "serial") else None
    try:
        return _batch_into(files, outs, out_dir, spec_text, str(spec_path), scheduler, workers, over,
                           resume, progress, suffix, client)
    finally:
        if client is not None:
            client.close()


async def _probe(address: str) -> None:
    """Ask the peer at ``address`` who it is; raise unless it says it is a dask scheduler."""
    from distributed.comm import connect

    comm = await connect(address, timeout=CONNECT_TIMEOUT)
    try:
        await comm.write({"op": "identity"})
        reply = await comm.read()
    finally:
        comm.abort()
    if not (isinstance(reply, dict) and reply.get("type") == "Scheduler"):
        raise ValueError("the peer is not a dask scheduler")


def _connect(scheduler: str):
    """A dask Client of the scheduler at this address, or InputError naming it (quickly)."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise InputError("batch needs dask.distributed: pip install 'bvpnav[batch]'") from None
    try:  # dask's own timeout does not bound the handshake with a peer that never answers
        asyncio.run(asyncio.wait_for(_probe(scheduler), CONNECT_TIMEOUT))
        return Client(scheduler, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (Exception, MemoryError) as exc:  # refused, timed out, garbage from a peer that is not dask
        why = str(exc).splitlines()[0][:200] if str(exc) else ""
        raise InputError(f"--scheduler {scheduler!r}: no dask scheduler answered at this address within "
                         f"{CONNECT_TIMEOUT:g} s ({type(exc).__name__}{': ' + why if why else ''}): nothing "
                         "is listening there or it is not a dask scheduler; start one (`dask scheduler`) and "
                         "give its address, e.g. --scheduler tcp://host:8786, or use 'serial' or leave "
                         "--scheduler out for a local cluster") from None


def _batch_into(files, outs, out_dir, spec_text, spec_source, scheduler, workers, over: dict, resume,
                progress, suffix, client) -> pd.DataFrame:
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"--out {str(out_dir)!r}: cannot create the folder ({exc.strerror}); give --out "
                         "a folder you can write to") from None
    with output_lock(out_dir, "--out"):
        try:
            rows = _run(files, outs, spec_text, spec_source, scheduler, workers, over, resume,
                        progress, suffix, client)
            df = pd.DataFrame(rows, columns=SUMMARY_COLUMNS)
            df = df.sort_values("recording", kind="stable").reset_index(drop=True)
            write_table(df, out_dir / SUMMARY_NAME)
        finally:  # temporaries of workers that were stopped mid-write (their processes are gone)
            remove_stale_temporaries(out_dir)
    return df


def _run(files, outs, spec_text, spec_source, scheduler, workers, over: dict, resume, progress,
         suffix, client=None) -> list[dict]:
    jobs, rows = [], []
    for p, out in zip(files, outs, strict=True):
        note = ""
        if resume:
            current = fingerprint(p, spec_text, fmt=suffix, **{"solver": None, "lam": None, **over})
            reason, js = resume_reason(p, out, out.with_suffix(".json"), current)
            if reason is None:
                run = js["run"]
                rows.append({"recording": display_path(p), "ok": True, "error": "",
                             "samples": run.get("samples"),
                             "lam": js.get("lam"), "lam_rule": js.get("lam_rule"),
                             "solver": (js.get("solver") or {}).get("solver"), "status": "skipped (resume)",
                             "verified": bool((js.get("solver") or {}).get("verified")),
                             "output": display_path(out), "resume": "skipped: fingerprint matches"})
                continue
            note = f"re-solved: {reason}"
        jobs.append((str(p), spec_text, spec_source, str(out), over, note))
    if jobs and scheduler == "serial":
        # once(): a warning shared by many recordings is issued once (each summary records it)
        with once(), progress_bar(total=len(jobs), desc="recordings", unit="rec", enabled=progress) as bar, \
                _interrupts_noted() as interrupts:
            for job in jobs:
                rows.append(_task(*job))
                if interrupts:  # a library swallowed the interrupt (e.g. into a parser error)
                    raise interrupts[0]
                _done(rows[-1], len(rows), len(jobs))
                bar.update(1)
    elif jobs:
        rows += _run_on_dask(jobs, scheduler, workers, progress, client)
    return rows


@contextlib.contextmanager
def _interrupts_noted():
    """Note every SIGINT (Ctrl-C) and SIGTERM that interrupts before its exception is raised as
    usual; yields the list of those exceptions. A library can catch the exception inside a task
    and report something else (pandas' C parser, interrupted in its read of the in-memory text,
    raised "Calling read(nbytes) on source failed"): the serial loop then raises the first again
    instead of solving the other recordings and calling the interrupted one a bad file.

    Either signal is chained only when its handler is a Python function (Python's own SIGINT
    handler, :func:`signal.default_int_handler`, which raises KeyboardInterrupt, or the CLI's
    SIGTERM handler, which raises ``_Terminated``): the caller's handler still decides what a
    signal does. Any other handler is left as it is: :data:`signal.SIG_DFL` ends the process
    and :data:`signal.SIG_IGN` ignores the signal, with nothing raised to swallow, and a
    handler installed outside Python (:func:`signal.getsignal` gives None) could not be put
    back afterwards.
    """
    noted: list[BaseException] = []
    with contextlib.ExitStack() as handlers:
        for signum in (signal.SIGINT, signal.SIGTERM):
            old = signal.getsignal(signum)
            if callable(old):
                handlers.enter_context(signal_handled(signum, _noting(old, noted)))
        yield noted


def _noting(old: Callable, noted: list[BaseException]):
    """A handler that calls the Python handler ``old`` and appends to ``noted`` what it raises."""

    def handler(signum, frame):
        try:
            old(signum, frame)     # the caller's handler decides; noted only if it interrupts
        except BaseException as exc:
            noted.append(exc)
            raise

    return handler


@contextlib.contextmanager
def _workers_ignore_ctrl_c():
    """Start the local workers with SIGINT ignored (inherited through spawn's exec): Ctrl-C in
    a terminal reaches the whole process group, and only this process should handle it (by
    closing the cluster), not each worker with its own traceback. A worker that a nanny starts
    again later does not inherit it: :class:`bvpnav._dask.IgnoreCtrlC` covers those."""
    with signal_handled(signal.SIGINT, signal.SIG_IGN):
        yield


def _local_cluster(workers: int):
    """The batch's LocalCluster of ``workers`` single-threaded worker processes, each ignoring
    Ctrl-C from its start (also one restarted by its nanny after the first died).

    SIGINT is ignored in this process while the cluster starts (the workers inherit it), so
    a Ctrl-C before the workers are up is lost: the batch stops at a Ctrl-C given after that.
    """
    from dask.distributed import LocalCluster

    from ._dask import IgnoreCtrlC

    # silence_logs: the workers' warnings and errors (tasks cancelled by Ctrl-C, a heartbeat
    # that finds the scheduler already closed while the cluster shuts down) are not for
    # users; a task's own failure is a row of the summary, a dead worker too.
    # dashboard_address: the scheduler's HTTP server on a free loopback port (None still
    # binds 8787 on every interface, and warns when another cluster has it).
    # plugins: passed on to each worker, and again to one its nanny starts after a death
    with _workers_ignore_ctrl_c():
        return LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True,
                            host="127.0.0.1", dashboard_address="127.0.0.1:0",
                            silence_logs=logging.CRITICAL, plugins=(IgnoreCtrlC(),))


def _done(row: dict, k: int, n: int) -> None:
    if row.get("ok"):
        log.info("recording %d/%d done: %s (lam=%s, solver %s, %.3g s)", k, n, row["recording"],
                 row.get("lam"), row.get("solver"), row.get("seconds") or 0.0)
    else:
        log.info("recording %d/%d failed: %s: %s", k, n, row["recording"], row.get("error"))


def _run_on_dask(jobs, scheduler, workers, progress, client=None) -> list[dict]:
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise InputError("batch needs dask.distributed: pip install 'bvpnav[batch]'") from None
    cluster, own = None, client is None
    if scheduler is None:
        cluster = _local_cluster(workers)
        client = Client(cluster)
    elif client is None:
        client = _connect(scheduler)
    try:
        futures = {client.submit(_task, *job, pure=False): job for job in jobs}
        bar = progress_bar(total=len(futures), desc="recordings", unit="rec", enabled=progress)
        rows = []
        for fut in as_completed(list(futures)):
            try:
                rows.append(fut.result())
            except Exception as exc:  # _task never raises: the worker itself died (e.g. KilledWorker)
                path, note = futures[fut][0], futures[fut][-1]
                rows.append({"recording": display_path(path), "ok": False, "verified": False, "output": "",
                             "resume": note,
                             "error": f"{type(exc).__name__}: the worker process solving it died ({exc}), "
                                      "often from lack of memory: solve it alone with `bvpnav solve`, in "
                                      "shorter windows, or with fewer --workers"})
            _done(rows[-1], len(rows), len(futures))
            bar.update(1)
        bar.close()
        return rows
    finally:
        if own:
            client.close()
        if cluster is not None:
            cluster.close()
