"""Files in and out: recordings (CSV, Parquet), trajectories, JSON summaries.

Atomic output: every file bvpnav writes appears whole or not at all.

Outputs are written to a temporary file in the destination's folder and moved into
place with :func:`os.replace` (atomic on POSIX and Windows), so an interrupted run never
leaves a half-written result, and inputs are only ever opened for reading.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

from .errors import InputError

__all__ = ["atomic_path", "atomic_write_text", "atomic_write_bytes", "atomic_savefig",
           "write_table", "write_trajectory", "summary", "write_json"]


# ------------------------------------------------------------------ atomic output
# Write side (issue 14): the temporary file of a write is ``.<name>.bvpnav-<host>-<pid>-<hex>.tmp``
# beside its destination, created with the umask's mode (never mkstemp's 0600); a replaced
# file keeps its mode. Temporaries are removed on every exit path of the ``with`` block; those
# of a process that died without cleaning up (SIGKILL, power loss) are removed the next time
# this host's bvpnav writes into that folder. An OSError becomes an InputError that names the
# destination (never the temporary name), the reason and the fix.
import errno as _errno  # noqa: E402
import re as _re  # noqa: E402
import secrets as _secrets  # noqa: E402
import socket as _socket  # noqa: E402
import stat as _stat  # noqa: E402

__all__ += ["check_outputs", "check_figure_path", "check_table_path", "remove_stale_temporaries",
            "file_fingerprint", "path_stamp", "output_lock", "TABLE_SUFFIXES",
           "bvpnav_summary", "check_implicit_outputs", "SUMMARY_KEYS"]

#: Suffixes :func:`write_table` writes.
TABLE_SUFFIXES = (".csv", ".parquet", ".pq")

_HOST = _re.sub(r"[^A-Za-z0-9_]", "_", _socket.gethostname())[:40] or "host"
_TMP_RE = _re.compile(r"^\..*\.bvpnav-(?P<host>[A-Za-z0-9_]+)-(?P<pid>\d+)-[0-9a-f]{8}\.tmp$", _re.DOTALL)
_swept: set[str] = set()

#: errno -> (reason, fix) of a failed write.
_WRITE_ERRORS = {
    _errno.ENOSPC: ("the disk is full", "free some space or write to another disk"),
    _errno.EDQUOT: ("the disk quota is exhausted", "free some space or write to another disk"),
    _errno.EFBIG: ("the file is too large for this file system or for the process's file-size "
                   "limit (ulimit -f)", "raise the limit or write to another disk"),
    _errno.EACCES: ("permission denied", "choose a folder you can write to, or change its permissions"),
    _errno.EPERM: ("operation not permitted", "choose a folder you can write to, or change its permissions"),
    _errno.EROFS: ("the file system is read-only", "write to a folder on a writable disk"),
    _errno.ENOENT: ("its folder does not exist (or was removed during the run)",
                    "check the path and create the folder"),
    _errno.ENOTDIR: ("a part of the path is a file, not a folder", "choose another path"),
    _errno.EISDIR: ("it is a folder", "give the path of a file"),
    _errno.ENAMETOOLONG: ("the name is too long", "choose a shorter path"),
    _errno.EIO: ("an input/output error of the disk", "check the disk and write elsewhere"),
}


def _write_error(dest: Path, exc: OSError, tmp: Path | None = None) -> InputError:
    """An :class:`InputError` naming ``dest`` (not the temporary file) for an OSError."""
    reason, fix = _WRITE_ERRORS.get(exc.errno, (None, "check the path, the permissions and the free space"))
    if reason is None:
        reason = exc.strerror or str(exc)
        if tmp is not None:
            reason = reason.replace(str(tmp), str(dest)).replace(tmp.name, dest.name)
    kept = "it was left as it was" if dest.exists() else "nothing was written there"
    return InputError(f"cannot write {str(dest)!r}: {reason}; {fix} ({kept})")


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    if os.name != "posix":  # os.kill(pid, 0) would terminate the process on Windows
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # e.g. EPERM: it exists, owned by someone else
        return True
    return True


def remove_stale_temporaries(folder: str | os.PathLike) -> list[Path]:
    """Remove temporary files that a dead bvpnav process of this host left in ``folder``.

    Only names of bvpnav's atomic writer (``.<name>.bvpnav-<host>-<pid>-<hex>.tmp``) whose
    host is this one and whose process no longer exists are removed; any other file is left.

    Returns
    -------
    list of Path
        The files removed.
    """
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for e in entries:
        m = _TMP_RE.match(e.name)
        if m is None or m["host"] != _HOST or _pid_alive(int(m["pid"])):
            continue
        with contextlib.suppress(OSError):
            if e.is_file(follow_symlinks=False):
                os.unlink(e.path)
                removed.append(Path(e.path))
    return removed


def _temp_name(dest: Path) -> Path:
    """A fresh temporary name beside ``dest`` (host, pid and random hex: never another's)."""
    return dest.parent / f".{dest.name[:120]}.bvpnav-{_HOST}-{os.getpid()}-{_secrets.token_hex(4)}.tmp"


def _create_temp(dest: Path, holder: list) -> Path:
    """Create an empty temporary file beside ``dest`` (mode from the umask).

    Its name is put in ``holder`` *before* the file is created, so that a caller who
    removes ``holder``'s names on any exception (a signal may arrive between any two
    bytecodes) never leaves the file behind.
    """
    for _ in range(100):
        holder.append(_temp_name(dest))
        try:
            os.close(os.open(holder[-1], os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:  # not ours (practically impossible): never remove it
            holder.pop()
            continue
        return holder[-1]
    raise FileExistsError(_errno.EEXIST, "no free temporary name")  # pragma: no cover


def _discard(names: list) -> None:
    for name in names:
        with contextlib.suppress(OSError):
            os.unlink(name)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success move it onto ``path``.

    The file appears whole or not at all: on any exception (KeyboardInterrupt included) the
    temporary file is removed and ``path`` is left as it was. A new file gets the mode the
    umask gives; a replaced file keeps its mode. Stale temporaries of dead bvpnav processes
    in the folder are removed first (once per folder and process).

    Raises
    ------
    InputError
        On an OSError (disk full, permission, read-only file system, file too large ...),
        naming ``path``, the reason and the fix.
    """
    dest = Path(path)
    made: list[Path] = []  # the temporary's name, recorded before the file exists
    try:
        dest.parent.mkdir(parents=True, exist_ok=True)
        folder = os.path.realpath(dest.parent)
        if folder not in _swept:
            remove_stale_temporaries(folder)
            _swept.add(folder)
        tmp = _create_temp(dest, made)
        try:
            mode = _stat.S_IMODE(os.stat(dest).st_mode)  # a replaced file keeps its mode
        except OSError:
            mode = _stat.S_IMODE(os.stat(tmp).st_mode)  # 0o666 & ~umask
        yield tmp
        os.chmod(tmp, mode)
        os.replace(tmp, dest)
        made.clear()
    except OSError as exc:
        _discard(made)
        raise _write_error(dest, exc, made[0] if made else None) from None
    except BaseException:  # KeyboardInterrupt, SIGTERM (the CLI's handler), a caller's error
        _discard(made)
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write text (UTF-8) atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write bytes atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def atomic_savefig(fig, path: str | os.PathLike, option: str = "path", **kwargs) -> None:
    """Save a matplotlib figure atomically, in the format of the path's suffix.

    Raises
    ------
    InputError
        If the suffix is not a format matplotlib writes (checked before anything is
        written; see :func:`check_figure_path`), or on an OSError as :func:`atomic_path`.
    """
    fmt = check_figure_path(path, option)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, **kwargs)


# ------------------------------------------------------------------ recordings
def read_regular_file(path: str | os.PathLike, what: str = "recording", max_bytes: int | None = None,
                      check_head=None) -> bytes:
    """The bytes of a regular file, refusing anything else before it could block.

    ``os.stat`` is checked before opening (a FIFO, a terminal or ``/dev/stdin`` would
    block a reader forever, a folder cannot be read), and the descriptor is opened
    non-blocking and checked again with ``os.fstat`` (no race with a swapped file).

    Parameters
    ----------
    path : str or path-like
    what : str
        What the file is for, in messages (``"recording"``, ``"spec"``).
    max_bytes : int, optional
        Refuse files larger than this (by their size, before reading).
    check_head : callable, optional
        Called with the first 64 KiB before the rest is read; raises to refuse the file
        (e.g. binary data) without reading all of it.

    Raises
    ------
    InputError
        Naming the path: missing, not a regular file (saying what it is), unreadable.
    """
    name = str(path)

    def kind_of(mode: int) -> str | None:
        return None if _stat.S_ISREG(mode) else _kind(mode)

    def refuse(kind: str) -> InputError:
        return InputError(f"{what} {name!r} is {kind}, not a regular file; bvpnav reads a {what} only "
                          "from a regular file (a pipe or device could block forever): save it to a file "
                          "and give that path")

    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise InputError(f"{what} {name!r}: no such file; check the path") from None
    except OSError as exc:
        raise InputError(f"{what} {name!r}: cannot read it ({exc.strerror}); check the path and "
                         "permissions") from None
    kind = kind_of(st.st_mode)
    if kind is not None:
        raise refuse(kind)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except OSError as exc:
        raise InputError(f"{what} {name!r}: cannot read it ({exc.strerror}); check the path and "
                         "permissions") from None
    try:
        st = os.fstat(fd)
        kind = kind_of(st.st_mode)
        if kind is not None:
            raise refuse(kind)
        if max_bytes is not None and st.st_size > max_bytes:
            raise InputError(f"{what} {name!r} is {st.st_size:,} bytes, beyond the {max_bytes:,}-byte limit "
                             f"for a {what}; is it the right file? A {what} is a small text file")
        with os.fdopen(fd, "rb", closefd=False) as fh:
            head = fh.read(1 << 16)
            if check_head is not None:
                check_head(head)
            return head + fh.read()
    except OSError as exc:
        raise InputError(f"{what} {name!r}: cannot read it ({exc.strerror}); check the path and "
                         "permissions") from None
    finally:
        os.close(fd)


def parquet_frame(source: bytes | str | os.PathLike):
    """A Parquet file (its bytes or its path) as a DataFrame, read on the calling thread.

    ``pandas.read_parquet`` goes through Arrow's dataset scanner, which starts a thread of
    Arrow's pool even with ``use_threads=False``; a pool thread still alive at interpreter
    teardown can abort the process after its work is done ("terminate called without an
    active exception", exit -6; apache/arrow#34314, #50482). This reads the file with
    ``ParquetFile.read`` (no scanner, no pre-buffering) from an Arrow buffer and converts it
    on the calling thread, so no Arrow thread is ever started; the index and dtypes come
    back from the file's pandas metadata as ``pandas.read_parquet`` gives them.

    Parameters
    ----------
    source : bytes or path-like
        The file's bytes, or its path.

    Returns
    -------
    pandas.DataFrame
        The table, with the index stored in the file.

    Examples
    --------
    >>> import io, pandas as pd
    >>> buf = io.BytesIO()
    >>> pd.DataFrame({"acc_x": [0.0, 1.0]}, index=pd.Index([0.0, 0.1], name="time")).to_parquet(buf)
    >>> parquet_frame(buf.getvalue()).index.name
    'time'
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    raw = source if isinstance(source, (bytes, bytearray, memoryview)) else Path(source).read_bytes()
    with pq.ParquetFile(pa.BufferReader(raw), pre_buffer=False) as f:
        table = f.read(use_threads=False)
    return table.to_pandas(use_threads=False)


def write_table(df, path: str | os.PathLike, option: str = "path") -> None:
    """Write a DataFrame atomically as CSV (floats round-trip exactly) or Parquet.

    Raises
    ------
    InputError
        On an unknown suffix (before anything is written), a missing pyarrow, or an
        OSError as :func:`atomic_path`.
    """
    p = Path(path)
    suffix = check_table_path(p, option)
    if suffix in (".parquet", ".pq"):
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise InputError(f"{str(p)!r}: writing Parquet needs pyarrow "
                             "(pip install 'bvpnav[parquet]')") from None
    with atomic_path(p) as tmp:
        if suffix == ".csv":
            df.to_csv(tmp, index=False, float_format="%.17g")
        else:
            df.to_parquet(tmp, index=False)


def write_trajectory(solution, path: str | os.PathLike) -> None:
    """Write ``solution.trajectory`` with a ``t`` column (s), positions (m) and velocities
    (m/s) named as in the Python API, atomically."""
    write_table(solution.trajectory.reset_index(), path)


def plain_json(v):
    """A JSON-ready copy: dicts, lists, tuples and arrays recursively, numpy scalars as Python
    values, non-finite floats as None, anything else as its text."""
    import numpy as np

    if isinstance(v, dict):
        return {str(k): plain_json(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [plain_json(x) for x in v]
    if isinstance(v, np.ndarray):
        return plain_json(v.tolist())
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not np.isfinite(v):
        return None
    if isinstance(v, (str, int, float, bool)) or v is None:
        return v
    return str(v)


def summary(solution, problem) -> dict:
    """A JSON-ready summary: lambda and rule, error-model estimates with units (and standard
    deviations with ``uncertainty``), solver statistics, item residuals and, with gated fixes,
    the gating counts and every rejected fix."""


    units = {}
    em = problem.error_model
    for comp in ([] if em is None else getattr(em, "components", (em,))):
        for n in comp.names(problem.data):
            units[n] = getattr(comp, "units", "")
    st = solution.stats
    std = solution.error_params_std
    rejected = getattr(solution, "rejected", None)   # fixes gating rejected (Solution.rejected)
    keep = ("solver", "status", "verified", "accuracy", "iterations", "compile_time", "solve_time",
            "wall_time", "factorization", "verification", "attempts", "demoted", "sequential")
    return plain_json({
        "lam": solution.lam, "lam_rule": solution.lam_rule,
        "error_model": {k: {"estimate": float(v), "units": units.get(k, ""),
                            **({"std": float(std[k])} if k in std.index else {})}
                        for k, v in solution.error_params.items()},
        "solver": {k: st.get(k) for k in keep if k in st},
        "items": solution.items.to_dict(orient="records"),
        "warnings": list(solution.warnings),
        **({"data_checks": st["data_checks"]} if st.get("data_checks") else {}),
        **({"gating": st["gating"], "rejected": rejected.to_dict(orient="records")}
           if rejected is not None else {}),
    })


def write_json(obj, path: str | os.PathLike) -> None:
    """Write JSON atomically."""
    import json

    atomic_write_text(path, json.dumps(obj, indent=2) + "\n")


# ------------------------------------------------------------------ output policy
def _figure_formats() -> dict[str, str]:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    return FigureCanvasAgg.get_supported_filetypes()


def check_figure_path(path: str | os.PathLike, option: str = "path") -> str:
    """The matplotlib format of a figure path from its suffix, checked before any work.

    Parameters
    ----------
    path : path-like
        Figure file, e.g. ``traj.png``.
    option : str
        How the caller names the path in messages (e.g. ``"--plot"``).

    Returns
    -------
    str
        The format (the suffix without its dot, lower case).

    Raises
    ------
    InputError
        If the suffix is missing or not a format matplotlib writes; the message lists them.
    """
    fmt = Path(path).suffix.lstrip(".").lower()
    formats = _figure_formats()
    if fmt not in formats:
        what = f"suffix {Path(path).suffix!r}" if fmt else "no suffix"
        raise InputError(f"{option} {str(path)!r}: {what} is not a figure format matplotlib writes; end "
                         f"the name with one of {', '.join('.' + f for f in sorted(formats))} "
                         "(e.g. .png)")
    return fmt


def check_table_path(path: str | os.PathLike, option: str = "path") -> str:
    """The lower-case suffix of a table output (``.csv``, ``.parquet``, ``.pq``), checked
    before any work; :class:`InputError` naming ``option`` otherwise."""
    suffix = Path(path).suffix.lower()
    if suffix not in TABLE_SUFFIXES:
        what = f"unknown output type {Path(path).suffix!r}" if suffix else "no suffix"
        raise InputError(f"{option} {str(path)!r}: {what}; end the name with .csv or .parquet")
    return suffix


def _ident(path: str | os.PathLike) -> tuple[str, tuple[int, int] | None]:
    """(the path with symlinks resolved, (device, inode) if it exists)."""
    real = os.path.realpath(path)
    try:
        st = os.stat(path)
    except OSError:
        return real, None
    return real, (st.st_dev, st.st_ino)


def _kind(mode: int) -> str:
    for test, name in ((_stat.S_ISDIR, "a folder"), (_stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (_stat.S_ISCHR, "a character device"), (_stat.S_ISBLK, "a block device"),
                       (_stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


def _probe_folder(folder: Path) -> OSError | None:
    """Create and remove a temporary file in ``folder``: the OSError, if writing fails."""
    made: list[Path] = []
    try:
        _create_temp(folder / "probe", made)
    except OSError as exc:
        return exc
    finally:
        _discard(made)
    return None


def _input_identities(inputs: dict) -> tuple[dict, dict, dict]:
    """The given inputs by resolved path and by (device, inode): -> (name, path, True), and
    the input folders by resolved path -> (name, path).

    A folder input (a ROS 2 bag, a phone export) is the input as a whole: every file under
    it is entered too (by its resolved path, so a symlink's target, and by inode, so a hard
    link elsewhere), named as the input.
    """
    by_real: dict[str, tuple[str, object, bool]] = {}  # resolved path -> (name, path, is an input)
    by_key: dict[tuple[int, int], tuple[str, object, bool]] = {}  # (device, inode) -> the same
    folders: dict[str, tuple[str, object]] = {}
    for k, p in inputs.items():
        if p is None:
            continue
        real, key = _ident(p)
        by_real.setdefault(real, (k, p, True))
        if key is not None:
            by_key.setdefault(key, (k, p, True))
        if os.path.isdir(p):
            folders.setdefault(real, (k, p))
            for root, _dirs, names in os.walk(p):
                for name in names:
                    f = os.path.join(root, name)
                    f_real, f_key = _ident(f)
                    by_real.setdefault(f_real, (f"{k} (a file of the folder {str(p)!r})", f, True))
                    if f_key is not None:
                        by_key.setdefault(f_key, (f"{k} (a file of the folder {str(p)!r})", f, True))
    return by_real, by_key, folders


def _refuse_inside_input_folder(opt: str, p, real: str, folders: dict) -> None:
    """Refuse output ``opt`` whose resolved path lies inside an input folder."""
    for folder, (name, fp) in folders.items():
        if real != folder and os.path.commonpath([real, folder]) == folder:
            raise InputError(f"{opt} {str(p)!r} is inside the input {name} {str(fp)!r}, a folder read as "
                             f"one recording (every file in it is the input): bvpnav never writes into its "
                             f"inputs; give {opt} a path outside {str(fp)!r}")


def _refuse_same_file(opt: str, p, real: str, key, by_real: dict, by_key: dict) -> None:
    """Refuse output ``opt`` when it is an input or an earlier output (same path or hard link)."""
    hit, how = by_real.get(real), "the same file as"
    if hit is None and key is not None and key in by_key:
        hit, how = by_key[key], "a hard link to"
    if hit is not None:
        other, op, is_input = hit
        if is_input:
            raise InputError(f"{opt} {str(p)!r} is {how} the input {other} {str(op)!r}: bvpnav never "
                             f"writes over its inputs; give {opt} another path")
        raise InputError(f"{opt} {str(p)!r} is {how} the output {other} {str(op)!r}: one output would "
                         f"overwrite the other; give {opt} another path")


def _check_existing_output(opt: str, p: Path) -> None:
    """Refuse an existing output that is not a regular file, or is read-only."""
    st = os.stat(p)
    if not _stat.S_ISREG(st.st_mode):
        raise InputError(f"{opt} {str(p)!r} is {_kind(st.st_mode)}; bvpnav replaces its outputs "
                         f"whole, give {opt} the path of a regular file")
    if not st.st_mode & 0o222:
        raise InputError(f"{opt} {str(p)!r} is read-only (mode {_stat.S_IMODE(st.st_mode):04o}); "
                         f"bvpnav does not replace a read-only file: make it writable (chmod u+w) "
                         f"or give {opt} another path")


def _existing_folder(opt: str, p: Path) -> Path:
    """The nearest existing ancestor of ``p``; refused when it is a file, not a folder."""
    parent = p.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if parent.exists() and not parent.is_dir():
        raise InputError(f"{opt} {str(p)!r}: {str(parent)!r} is a file, not a folder; give {opt} a path "
                         "in a folder")
    return parent


def _check_writable(folders: dict) -> None:
    """Refuse the first folder (-> (option, path)) where a temporary file cannot be created."""
    for folder, (opt, p) in folders.items():
        exc = _probe_folder(Path(folder))
        if exc is not None:
            reason, fix = _WRITE_ERRORS.get(exc.errno, (exc.strerror or "it cannot be written", ""))
            raise InputError(f"{opt} {str(p)!r}: cannot write in {folder!r}: {reason}; give {opt} a path in "
                             "a folder you can write to" + (f" ({fix})" if fix else ""))


def check_outputs(inputs: dict, outputs: dict) -> None:
    """The output policy, checked by every command before any work.

    Parameters
    ----------
    inputs : dict
        How the caller names each input (e.g. ``"INPUT"``, ``"--spec"``) -> its path
        (None: not given). Inputs are only read. A folder (a ROS 2 bag, a phone export) is
        an input as a whole: nothing is written anywhere inside it.
    outputs : dict
        How the caller names each output (e.g. ``"--out"``, ``"--plot"``) -> its path
        (None: not given).

    Raises
    ------
    InputError
        Naming both paths and the option to change, when an output is an input or another
        output of the same run (same path after resolving symlinks, or the same file
        through a hard link), or lies inside an input folder, or is a file of one (through
        a symlink or hard link elsewhere); when an output exists but is a folder, a FIFO, a device or a
        read-only file; when a part of its folder is a file; or when its folder cannot be
        written (permission, read-only file system), checked by creating and removing a
        temporary file there.
    """
    by_real, by_key, input_folders = _input_identities(inputs)
    outs = [(k, p, *_ident(p)) for k, p in outputs.items() if p is not None]
    for opt, p, real, key in outs:
        _refuse_inside_input_folder(opt, p, real, input_folders)
        _refuse_same_file(opt, p, real, key, by_real, by_key)
        by_real[real] = (opt, p, False)
        if key is not None:
            by_key[key] = (opt, p, False)
    folders: dict[str, tuple[str, object]] = {}
    for opt, p, _real, key in outs:
        p = Path(p)
        if key is not None:
            _check_existing_output(opt, p)
        folders.setdefault(os.path.realpath(_existing_folder(opt, p)), (opt, p))
    _check_writable(folders)


#: Keys every JSON summary written by bvpnav holds (see :func:`summary`).
SUMMARY_KEYS = ("lam", "lam_rule", "error_model", "solver", "items")


def bvpnav_summary(path: str | os.PathLike) -> dict | None:
    """The JSON summary at ``path`` if it is recognisably bvpnav's (an object with the keys
    :data:`SUMMARY_KEYS`), else None (missing, unreadable, not JSON, or someone else's)."""
    import json

    try:
        if not _stat.S_ISREG(os.stat(path).st_mode) or os.stat(path).st_size > (64 << 20):
            return None
        with open(path, encoding="utf-8") as fh:
            js = json.load(fh)
    except (OSError, ValueError):
        return None
    return js if isinstance(js, dict) and all(k in js for k in SUMMARY_KEYS) else None


def _starts_like_summary(path: Path) -> bool:
    try:
        with open(path, "rb") as fh:
            head = fh.read(64)
    except OSError:
        return False
    return _re.match(rb'\s*\{\s*"lam"\s*:', head) is not None


def _trajectory_columns(path: Path) -> bool:
    """Whether the table's columns are a bvpnav trajectory's: ``t``, positions, ``v<axis>``,
    optionally followed by the standard deviation of each (``<column>_std``)."""
    try:
        if path.suffix.lower() == ".csv":
            with open(path, encoding="utf-8", errors="replace", newline="") as fh:
                cols = fh.readline().rstrip("\r\n").split(",")
        else:
            import pyarrow.parquet as pq

            cols = list(pq.read_schema(path).names)
    except Exception:  # unreadable: not recognisably ours
        return False
    std = [c for c in cols if c.endswith("_std")]
    base = cols[:len(cols) - len(std)]
    if std and std != [c + "_std" for c in base[1:]]:
        return False
    k = (len(base) - 1) // 2
    return (len(base) >= 3 and len(base) % 2 == 1 and base[0] == "t"
            and base[1 + k:] == ["v" + c for c in base[1:1 + k]])


def check_implicit_outputs(outputs: dict, fix: str) -> None:
    """Refuse to replace a file at an output path that bvpnav derived (not one typed by the
    user) unless that file is recognisably bvpnav's own output.

    Parameters
    ----------
    outputs : dict
        How the caller names each implicit output -> ``(path, kind)``; ``kind`` is
        ``"summary"`` (a JSON summary: replaceable if :func:`bvpnav_summary` recognises it),
        ``"trajectory"`` (replaceable if the JSON summary beside it, same name with
        ``.json``, is bvpnav's and, when it has a ``run`` record, names this file) or a
        tuple of column names (a CSV table: replaceable if its header is exactly those).
    fix : str
        How to avoid the collision (e.g. ``"give --summary PATH"``), appended to the message.

    Raises
    ------
    InputError
        Naming the first existing file that is not bvpnav's and the fix; nothing is written.
    """
    for opt, (p, kind) in outputs.items():
        p = Path(p)
        if not os.path.lexists(p):
            continue
        if kind == "summary":  # or bvpnav's summary cut short (its text starts with the key "lam")
            ok = bvpnav_summary(p) is not None or _starts_like_summary(p)
        elif kind == "trajectory":
            js = bvpnav_summary(p.with_suffix(".json"))
            run = js.get("run") if js is not None else None
            traj = run.get("trajectory") if isinstance(run, dict) else None
            ok = (js is not None and (not isinstance(traj, dict)
                                      or Path(str(traj.get("path", ""))).name == p.name)) or (
                js is None and _trajectory_columns(p))  # written just before a run was stopped
        else:
            try:
                with open(p, encoding="utf-8", errors="replace", newline="") as fh:
                    head = fh.readline().rstrip("\r\n")
            except OSError:
                head = None
            ok = head == ",".join(kind)
        if not ok:
            what = {"summary": "is not a bvpnav JSON summary",
                    "trajectory": "is not a bvpnav trajectory (no bvpnav JSON summary beside it names it)"
                    }.get(kind, "is not a table bvpnav wrote")
            raise InputError(f"{opt} {str(p)!r} already exists and {what}: bvpnav replaces a file at a path "
                             f"it chose itself only when that file is its own output; {fix}")


def file_fingerprint(path: str | os.PathLike) -> dict:
    """Size (bytes), modification time (ns) and SHA-256 of a regular file's content, or of a
    folder's regular files (a ROS 2 bag, a phone export): their relative paths and contents
    in name order, total size, latest mtime.

    Raises
    ------
    OSError
        If it cannot be read, or is not a regular file or folder (a FIFO is never opened:
        that would block).
    """
    import hashlib

    mode = os.stat(path).st_mode
    if _stat.S_ISDIR(mode):
        root = Path(path)
        files = sorted(p for p in root.rglob("*") if p.is_file())
        h = hashlib.sha256()
        size, mtime = 0, 0
        for p in files:
            fp = file_fingerprint(p)
            h.update(p.relative_to(root).as_posix().encode() + b"\0" + fp["sha256"].encode())
            size, mtime = size + fp["size"], max(mtime, fp["mtime_ns"])
        return {"size": size, "mtime_ns": mtime, "sha256": h.hexdigest()}
    if not _stat.S_ISREG(mode):
        raise OSError(_errno.EINVAL, "not a regular file", str(path))
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        st = os.fstat(fh.fileno())
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return {"size": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": h.hexdigest()}


def path_stamp(path: str | os.PathLike) -> tuple[int, int] | None:
    """(size, mtime in ns) of a file, or of a folder's files (as :func:`file_fingerprint`
    counts them), without reading them; None when it cannot be stat'ed or is neither."""
    try:
        st = os.stat(path)
        if _stat.S_ISDIR(st.st_mode):
            stats = [p.stat() for p in sorted(Path(path).rglob("*")) if p.is_file()]
            return sum(s.st_size for s in stats), max((s.st_mtime_ns for s in stats), default=0)
        return (st.st_size, st.st_mtime_ns) if _stat.S_ISREG(st.st_mode) else None
    except OSError:
        return None


@contextlib.contextmanager
def output_lock(folder: str | os.PathLike, option: str = "--out") -> Iterator[None]:
    """Hold an exclusive lock on an output folder (``.bvpnav.lock`` in it) while writing.

    A second bvpnav run that writes into the same folder at the same time is refused at
    once (no waiting) instead of interleaving its outputs with the first's. The lock is
    the kernel's (``flock``), so it is released when the process dies, even by SIGKILL;
    the file is removed on exit. Without ``fcntl`` (Windows) there is no lock.

    Raises
    ------
    InputError
        If another process holds the lock, naming the folder and its process id.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        yield
        return
    path = Path(folder) / ".bvpnav.lock"
    nofollow = getattr(os, "O_NOFOLLOW", 0)
    while True:
        created = True
        try:  # never follow a symlink, never truncate: a file we did not create is only read
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL | nofollow, 0o666)
        except FileExistsError:
            created = False
            try:
                fd = os.open(path, os.O_RDWR | nofollow | getattr(os, "O_NONBLOCK", 0))
            except FileNotFoundError:  # removed in between by the run that held it: try again
                continue
            except OSError as exc:
                if exc.errno == _errno.EISDIR:
                    raise InputError(f"{option} {str(folder)!r}: its lock file {str(path)!r} is a folder, "
                                     f"not bvpnav's lock: remove it or give {option} another folder"
                                     ) from None
                if exc.errno == _errno.ELOOP or os.path.islink(path):
                    raise InputError(f"{option} {str(folder)!r}: its lock file {str(path)!r} is a symbolic "
                                     "link; bvpnav writes its process id there and never through a link: "
                                     "remove the link (it is not bvpnav's) or give "
                                     f"{option} another folder") from None
                raise _write_error(path, exc) from None
        except OSError as exc:
            raise _write_error(path, exc) from None
        st = os.fstat(fd)
        if not _stat.S_ISREG(st.st_mode):
            os.close(fd)
            raise InputError(f"{option} {str(folder)!r}: its lock file {str(path)!r} is {_kind(st.st_mode)}, "
                             f"not bvpnav's lock: remove it or give {option} another folder")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            other = ""
            with contextlib.suppress(OSError):
                other = os.pread(fd, 32, 0).decode(errors="replace").strip()
            os.close(fd)
            raise InputError(f"{option} {str(folder)!r}: another bvpnav run (pid {other or '?'}) is writing "
                             f"into this folder now; wait for it to finish or give {option} another folder"
                             ) from None
        if not created:  # a lock left by a killed run holds a process id and nothing else
            old = os.pread(fd, 64, 0)
            if st.st_size > 32 or not _re.fullmatch(rb"\s*\d*\s*", old):
                os.close(fd)
                raise InputError(f"{option} {str(folder)!r}: {str(path)!r} exists and is not a bvpnav lock "
                                 "(bvpnav's holds only a process id); bvpnav does not overwrite it: move "
                                 f"it away or give {option} another folder")
        try:  # the holder before us may have removed the file: lock the one at the path
            same = os.path.samestat(os.fstat(fd), os.lstat(path))
        except OSError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)  # ours: created by this run, or a lock file holding a process id
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)
        os.close(fd)
