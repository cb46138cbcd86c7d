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
from .imu import ACC_UNITS, ImuData, axis_name_clash
from .timebase import TIME_UNITS, check_time_resolution, to_seconds

__all__ = ["atomic_path", "atomic_write_text", "atomic_write_bytes", "atomic_savefig", "read_recording",
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
            "file_fingerprint", "output_lock", "TABLE_SUFFIXES",
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
#: Leading bytes of file types that are sometimes renamed to .csv / .parquet.
_MAGIC = (
    (b"PK\x03\x04", "a ZIP archive (an .xlsx/.ods workbook, or a zipped file)",
     "open it in its program and export the sheet as CSV (comma-separated, '.' decimals), or unzip it"),
    (b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1", "a legacy Excel .xls workbook (OLE2)",
     "open it in a spreadsheet program and export the sheet as CSV (comma-separated, '.' decimals)"),
    (b"PAR1", "a Parquet file", "rename it to .parquet"),
    (b"\x1f\x8b", "gzip-compressed data", "decompress it first (gunzip)"),
    (b"BZh", "bzip2-compressed data", "decompress it first (bunzip2)"),
    (b"\xfd7zXZ\x00", "xz-compressed data", "decompress it first (unxz)"),
    (b"%PDF", "a PDF document", "export the data itself as CSV"),
    (b"\x89HDF", "an HDF5 file", "export the datasets as CSV or Parquet"),
    (b"\xff\xfe", "UTF-16 text (little-endian byte-order mark)", "save it as UTF-8"),
    (b"\xfe\xff", "UTF-16 text (big-endian byte-order mark)", "save it as UTF-8"),
)


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


def _sniff(raw: bytes) -> tuple[str, str] | None:
    """(what the bytes are, the fix) for known binary formats, else None."""
    for magic, what, fix in _MAGIC:
        if raw.startswith(magic):
            return what, fix
    if b"\x00" in raw[:4096]:
        return "binary data (NUL bytes)", "give a CSV text file or a Parquet file"
    return None


def _csv_text(raw: bytes, name: str) -> str:
    """Decode a CSV file and refuse what it would be misread as (with the fix)."""
    import csv
    import io as _io
    import re

    found = _sniff(raw)
    if found is not None:
        what, fix = found
        raise InputError(f"{name!r}: this .csv file is {what}, not CSV text; {fix}")
    try:
        # A UTF-8 byte-order mark is an encoding marker, not data: accepted and dropped.
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise InputError(f"{name!r}: not a readable CSV file (byte {exc.start}, line {line}, is not UTF-8 "
                         "text); save it as UTF-8 comma-separated values") from None
    lines = text[: 1 << 16].splitlines()  # the head is enough for the checks below
    k = 0
    while k < len(lines) and (lines[k].lstrip().startswith(("#", "%")) or not lines[k].strip()):
        k += 1
    if k and any(ln.strip() for ln in lines[:k]):
        first = next(ln for ln in lines[:k] if ln.strip())
        raise InputError(f"{name!r}: lines 1-{k} are a comment preamble ({first.strip()[:40]!r}) before the "
                         "header; bvpnav reads the header from line 1 and skips nothing: delete those lines "
                         "(or move the notes to a separate file) so the header (e.g. t,acc_x) is line 1")
    if not lines:
        return text
    header = text.split("\n", 1)[0].rstrip("\r")
    if ";" in header and "," not in header:
        sample = next((ln for ln in lines[1:] if ln.strip()), "")
        if re.search(r"\d,\d", sample):
            raise InputError(f"{name!r}: fields separated by ';' with decimal commas (line 2: "
                             f"{sample[:40]!r}); bvpnav reads comma-separated CSV with '.' as the decimal "
                             "point: export it with ',' between fields and '.' decimals "
                             "(pandas: df.to_csv(path, index=False))")
    try:
        cells = next(csv.reader(_io.StringIO(header)))
    except (csv.Error, StopIteration):
        return text  # the table reader reports it
    if len(cells) > 1:
        empty = [j for j, c in enumerate(cells) if not c.strip()]
        if empty:
            j = empty[0]
            raise InputError(f"{name!r}: header cell {j + 1} (line 1) is empty; name every column (t, "
                             f"acc_<axis>, ...) so no column is read under an invented name; header: {cells}")
        padded = [j for j, c in enumerate(cells) if c != c.strip()]
        if padded:
            j = padded[0]
            raise InputError(f"{name!r}: header cell {j + 1} (line 1) is {cells[j]!r}, with leading/trailing "
                             "whitespace; it would name a column (and an axis) with the spaces in it. Remove "
                             "the spaces around the header names (e.g. t,acc_x)")
        seen: dict[str, int] = {}
        for j, c in enumerate(cells):
            if c in seen:
                raise InputError(f"{name!r}: header line 1 names column {c!r} twice (columns "
                                 f"{seen[c] + 1} and {j + 1}); give every column its own name (the second "
                                 "one would be renamed silently otherwise)")
            seen[c] = j
    blank = _re.search(r"\n[ \t\r]*\n", text.rstrip())
    if blank is not None:
        line = text[: blank.start()].count("\n") + 2
        raise InputError(f"{name!r}: line {line} is blank, between data rows; bvpnav skips nothing (a blank "
                         "line may be a lost sample, and it would shift every reported line number): "
                         "delete the blank line(s), or repair the missing row")
    return text


def _check_table_head(path: Path, suffix: str, head: bytes) -> None:
    """Refuse a recording by its suffix and first bytes, before a huge file is read whole."""
    if suffix not in (".csv", ".parquet", ".pq"):
        raise InputError(f"{str(path)!r}: unknown file type {suffix!r}; give a .csv or .parquet file")
    found = _sniff(head)
    if suffix == ".csv" and found is not None:
        raise InputError(f"{str(path)!r}: this .csv file is {found[0]}, not CSV text; {found[1]}")
    if suffix != ".csv" and not head.startswith(b"PAR1") and found is not None:
        raise InputError(f"{str(path)!r}: this {suffix} file is {found[0]}, not Parquet (no PAR1 magic "
                         f"bytes); {found[1]}")


def _read_table(path: Path):
    """The recording at ``path`` as a DataFrame, read as CSV or Parquet by its suffix."""
    suffix = path.suffix.lower()
    raw = read_regular_file(path, "recording",  # a FIFO or device named first
                            check_head=lambda head: _check_table_head(path, suffix, head))
    if suffix == ".csv":
        return _read_csv(raw, path)
    return _read_parquet(raw, path, suffix)


def _read_csv(raw: bytes, path: Path):
    """A CSV recording's bytes as a DataFrame; every parser failure becomes an InputError."""
    import io as _io

    import pandas as pd

    text = _csv_text(raw, str(path))
    _check_field_counts(text, str(path))
    try:
        df = pd.read_csv(_io.StringIO(text), index_col=False)
    except pd.errors.EmptyDataError:
        raise InputError(f"{str(path)!r}: not a readable CSV file (it is empty); a recording needs a "
                         "header line (t, acc_<axis>) and at least 3 rows") from None
    except pd.errors.ParserError as exc:
        raise InputError(f"{str(path)!r}: not a readable CSV file ({str(exc).splitlines()[0]}); every "
                         "row needs the same number of fields as the header line") from None
    except (ValueError, OverflowError) as exc:  # e.g. unbalanced quotes, absurd field sizes
        raise InputError(f"{str(path)!r}: not a readable CSV file ({str(exc).splitlines()[0]}); check "
                         "the file is comma-separated text with one header line") from None
    return df


def parquet_frame(source: bytes | str | os.PathLike):
    """A Parquet file (its bytes or its path) as a DataFrame, read on the calling thread.

    ``pandas.read_parquet`` on a Python file object lets pyarrow's thread pool outlive the
    interpreter's teardown: about one process in three then aborts at exit ("terminate called
    without an active exception", exit -6) after its work is done (apache/arrow#34314, #50482).
    Reading from an Arrow buffer with ``use_threads=False`` measured 0 aborts in 150 runs
    (48 in 150 before); a recording is small enough that one thread costs nothing.
    """
    import pandas as pd
    import pyarrow as pa

    raw = source if isinstance(source, (bytes, bytearray, memoryview)) else Path(source).read_bytes()
    return pd.read_parquet(pa.BufferReader(raw), use_threads=False)


def _read_parquet(raw: bytes, path: Path, suffix: str):
    """A Parquet recording's bytes as a DataFrame (pyarrow needed, PAR1 magic checked)."""
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise InputError(f"{str(path)!r}: reading Parquet needs pyarrow "
                         "(pip install 'bvpnav[parquet]')") from None
    if not raw.startswith(b"PAR1"):
        found = _sniff(raw)
        if found is None:
            head = raw[:30].decode("utf-8", "replace")
            what, fix = f"text ({head!r}...)", "if it is CSV, rename it to .csv"
        else:
            what, fix = found
        raise InputError(f"{str(path)!r}: this {suffix} file is {what}, not Parquet (no PAR1 magic bytes); "
                         f"{fix}")
    try:
        df = parquet_frame(raw)
    except Exception as exc:  # pyarrow raises its own error types for corrupt files
        raise InputError(f"{str(path)!r}: not a readable Parquet file ({exc})") from None
    _check_parquet_names(df, path)
    return df


def _check_parquet_names(df, path: Path) -> None:
    """Refuse duplicate, empty or space-padded column names of a Parquet table."""
    names = [str(c) for c in df.columns]
    dup = sorted({c for c in names if names.count(c) > 1})
    if dup:
        raise InputError(f"{str(path)!r}: column {dup[0]!r} appears {names.count(dup[0])} times; give every "
                         "column its own name")
    if any(not c.strip() for c in names):
        j = next(j for j, c in enumerate(names) if not c.strip())
        raise InputError(f"{str(path)!r}: column {j + 1} has an empty name; name every column (t, "
                         "acc_<axis>, ...)")
    padded = [c for c in names if c != c.strip()]
    if padded:
        raise InputError(f"{str(path)!r}: column name {padded[0]!r} has leading/trailing whitespace; it "
                         "would name an axis with the spaces in it. Rename the column without them")


def _check_field_counts(text: str, name: str) -> None:
    """Refuse rows with more fields than the header (pandas would shift the columns)."""
    import csv
    import io as _io

    rows = csv.reader(_io.StringIO(text))
    try:
        header = next(rows, None)
        if header is None:
            return
        for k, row in enumerate(rows):
            _more_fields(name, k, rows.line_num, row, header)
    except csv.Error:
        return  # the table reader reports it


def _more_fields(name: str, k: int, line: int, row: list, header: list) -> None:
    if len(row) > len(header):
        raise InputError(f"{name!r}: row {k} (line {line}) has {len(row)} fields but the header "
                         f"(line 1) has {len(header)}; every row needs the same number of fields as "
                         "the header: remove the extra field(s) (a trailing comma?) or name the extra "
                         "column in the header")


_ISO_HINT = ("set time_unit = \"iso8601\" in the spec's [input] (times become seconds from the first "
             "sample, recorded in data.time_origin) or store the times as numbers in s")


def _time_seconds(df, tcol: str, tunit: str, origin: str | None, name: str, row_ref):
    """The time column in s and what t = 0 is (None: the times as given)."""
    import pandas as pd

    col = df[tcol]
    dtype = col.dtype
    if tunit == "iso8601":
        return _iso_seconds(col, tcol, name, row_ref)
    _check_time_dtype(dtype, tcol, tunit, name)
    if pd.api.types.is_object_dtype(dtype) or pd.api.types.is_string_dtype(dtype):
        _refuse_timestamp_cells(col, tcol, tunit, name, row_ref)
    if pd.api.types.is_integer_dtype(dtype) and len(col):
        return _integer_seconds(col, tcol, tunit, origin, name)
    return None, None


def _iso_seconds(col, tcol: str, name: str, row_ref):
    """Seconds from the first sample and the origin of a column of ISO 8601 timestamps."""
    import pandas as pd

    dtype = col.dtype
    if pd.api.types.is_datetime64_any_dtype(dtype):
        stamps = col
    elif pd.api.types.is_object_dtype(dtype) or pd.api.types.is_string_dtype(dtype):
        stamps = _parse_iso_cells(col, tcol, name, row_ref)
    else:
        raise InputError(f"{name}: column {tcol!r} holds {dtype} values but time_unit = \"iso8601\"; "
                         "store ISO 8601 timestamps there, or give time_unit = \"s\" (ms, us, ns) for "
                         "numbers")
    try:
        t, zero = to_seconds(stamps)
    except InputError as exc:
        raise InputError(f"{name}: column {tcol!r}: {exc}") from None
    return t, zero


def _parse_iso_cells(col, tcol: str, name: str, row_ref):
    """The text cells of a time column as datetimes, naming the first cell that is not one."""
    import numpy as np
    import pandas as pd

    cells = col.to_numpy()
    bad = [k for k, v in enumerate(cells) if not isinstance(v, str)]
    if bad:
        k = bad[0]
        raise InputError(f"{name}: {row_ref(k)}, column {tcol!r} is {cells[k]!r}, not an ISO 8601 "
                         "timestamp (time_unit = \"iso8601\"); fix or remove that row")
    stamps = pd.to_datetime(col, format="ISO8601", errors="coerce")
    nat = np.flatnonzero(stamps.isna().to_numpy())
    if nat.size:
        k = int(nat[0])
        raise InputError(f"{name}: {row_ref(k)}, column {tcol!r} is {cells[k]!r}, not an ISO 8601 "
                         "timestamp (e.g. 2026-01-31T12:00:00.125Z); fix or remove that row")
    return stamps


def _check_time_dtype(dtype, tcol: str, tunit: str, name: str) -> None:
    """Refuse a numeric time column of date, duration, bool or other non-number type."""
    import pandas as pd

    if pd.api.types.is_datetime64_any_dtype(dtype) or pd.api.types.is_timedelta64_dtype(dtype):
        raise InputError(f"{name}: column {tcol!r} holds {dtype} values, not numbers in {tunit}; "
                         + (_ISO_HINT if pd.api.types.is_datetime64_any_dtype(dtype) else
                            "store the durations as numbers in s"))
    if pd.api.types.is_bool_dtype(dtype) or not (pd.api.types.is_numeric_dtype(dtype)
                                                 or pd.api.types.is_object_dtype(dtype)
                                                 or pd.api.types.is_string_dtype(dtype)):
        raise InputError(f"{name}: column {tcol!r} holds {dtype} values; store times as numbers in {tunit} "
                         "in that column")


def _refuse_timestamp_cells(col, tcol: str, tunit: str, name: str, row_ref) -> None:
    """Refuse an ISO timestamp in a numeric time column (time_unit is not "iso8601")."""
    import numpy as np
    import pandas as pd

    v = pd.to_numeric(col, errors="coerce").to_numpy(dtype=float, na_value=np.nan)
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size and isinstance(col.iloc[int(bad[0])], str):
        cell = col.iloc[int(bad[0])]
        if not pd.isna(pd.to_datetime(pd.Series([cell]), format="ISO8601", errors="coerce").iloc[0]):
            raise InputError(f"{name}: {row_ref(int(bad[0]))}, column {tcol!r} is the timestamp "
                             f"{cell!r}, not a number in {tunit}; {_ISO_HINT}")


def _integer_seconds(col, tcol: str, tunit: str, origin: str | None, name: str):
    """Exact seconds of increasing integer times with time_origin = "first" (else (None, None));
    refuses integer epochs that float seconds cannot resolve to one unit."""
    import numpy as np

    ints = col.to_numpy()
    dt = np.diff(ints.astype(np.int64)) if ints.dtype.kind == "i" else None
    if dt is not None and np.all(dt > 0):
        if origin == "first":
            return to_seconds(ints, tunit)
        big = float(np.max(np.abs(ints.astype(float)))) * TIME_UNITS[tunit]
        if np.spacing(big) > 0.5 * TIME_UNITS[tunit]:
            raise InputError(
                f"{name}: column {tcol!r} holds integer times up to {int(np.max(np.abs(ints)))} {tunit} "
                f"(an epoch?) that float seconds cannot resolve to 1 {tunit}; add time_origin = "
                "\"first\" to the spec's [input] (times then count from the first sample, exactly, "
                "and the origin is recorded in data.time_origin)")
    return None, None


def _input_options(inp: dict, name: str):
    """The checked ``[input]`` options: (time column, time unit, acceleration unit, time origin,
    axis -> column map or None)."""
    tcol = inp.get("time", "t")
    tunit = inp.get("time_unit", "s")
    unit = inp.get("unit", "m/s^2")
    origin = inp.get("time_origin")
    if not isinstance(tcol, str):
        raise InputError(f"{name}: time={tcol!r}; give the name of the time column as a string")
    if not isinstance(tunit, str) or (tunit not in TIME_UNITS and tunit != "iso8601"):
        raise InputError(f"{name}: time_unit={tunit!r}; valid units: {list(TIME_UNITS)} for numbers, or "
                         "'iso8601' for timestamps")
    if origin is not None and origin != "first":
        raise InputError(f"{name}: time_origin={origin!r}; the only choice is \"first\" (count the times "
                         "from the first sample), or omit it")
    if not isinstance(unit, str) or unit not in ACC_UNITS:
        raise InputError(f"{name}: unit={unit!r}; valid acceleration units: {list(ACC_UNITS)}")
    cols = inp.get("columns")
    if cols is not None and not (isinstance(cols, dict) and cols
                                 and all(isinstance(v, str) for v in cols.values())):
        raise InputError(f"{name}: columns={cols!r}; map axis names to column names, e.g. "
                         'columns = { x = "acc_x" }')
    return tcol, tunit, unit, origin, cols


def _time_as_column(df, tcol: str, name: str):
    """``df`` with the time column as a column: a Parquet index named ``tcol`` is moved into
    the columns; a differently named or unnamed index holding the time is refused."""
    import pandas as pd

    if tcol not in df.columns and df.index.name is not None:
        if df.index.name == tcol:  # the time column stored as the Parquet index: unambiguous
            df = df.reset_index()
        else:
            raise InputError(f"{name}: time column {tcol!r} not found; the file's index is named "
                             f"{df.index.name!r} (the time stored as the Parquet index?): set time = "
                             f"\"{df.index.name}\" in the spec's [input] if it is the time; columns in the "
                             f"file: {list(df.columns)}")
    if tcol not in df.columns and not isinstance(df.index, pd.RangeIndex):
        raise InputError(f"{name}: time column {tcol!r} not found; the file has an unnamed {df.index.dtype} "
                         "index (the time stored as the Parquet index without a name?): write the file with "
                         f"the time as a column named {tcol!r} (df.reset_index(names={tcol!r})); columns "
                         f"in the file: {list(df.columns)}")
    return df


def _check_separator(df, name: str) -> None:
    """Refuse a one-column table whose header shows another field separator than ','."""
    if len(df.columns) == 1:
        head = str(df.columns[0])
        for sep, what in ((";", "';'"), ("\t", "tabs"), ("|", "'|'"), (" ", "spaces")):
            if sep in head.strip():
                raise InputError(f"{name}: one column {head!r}: the fields seem to be separated by {what}; "
                                 "bvpnav reads comma-separated CSV, save the file with ',' between fields")


def _axis_columns(df, cols: dict | None, name: str) -> dict:
    """The axis -> column map: ``cols`` as given, or every ``acc_<axis>`` column; refused when
    the axis names would collide in the trajectory's columns."""
    if cols is None:
        cols = {str(c)[4:]: c for c in df.columns if str(c).startswith("acc_")}
        if not cols:
            raise InputError(f"{name}: no acceleration columns: name them acc_<axis> or map them with "
                             f"columns = {{ x = \"...\" }} in the spec's [input]; columns in the file: "
                             f"{list(df.columns)}")
        clash = axis_name_clash(list(cols))
        if clash is not None:
            raise InputError(f"{name}: the columns {list(cols.values())} give the axes {list(cols)}: {clash} "
                             "(trajectory columns are t, <axis>, v<axis>, <axis>_std, v<axis>_std); rename "
                             "the column(s) (e.g. acc_x, acc_y, acc_z) or map them with columns = { x = "
                             "\"...\" } in the spec's [input]")
    else:
        clash = axis_name_clash([str(a) for a in cols])
        if clash is not None:
            raise InputError(f"{name}: [input] columns = {cols}: {clash} (trajectory columns are t, <axis>, "
                             "v<axis>, <axis>_std, v<axis>_std); choose other axis names, e.g. "
                             "columns = { x = \"...\", y = \"...\" }")
    return cols


def _check_columns_present(df, tcol: str, cols: dict, name: str) -> None:
    """Refuse a column that feeds two roles, and a time or axis column missing from ``df``."""
    owner: dict[str, str] = {tcol: "the time column"}
    for a, c in cols.items():
        if c in owner:
            raise InputError(f"{name}: column {c!r} is mapped to axis {a!r} but is already {owner[c]}; one "
                             "column can feed one axis only: map each axis to its own column in the spec's "
                             "[input] columns = { x = \"...\", y = \"...\" }")
        owner[c] = f"axis {a!r}"
    for what, col in [("time", tcol)] + [(f"axis {a}", c) for a, c in cols.items()]:
        if col not in df.columns:
            raise InputError(f"{name}: column {col!r} ({what}) not found; columns in the file: "
                             f"{list(df.columns)}")


def _row_ref(line0: int | None):
    """How messages name row ``k``: ``row k``, with its file line when rows start at line ``line0``."""
    def row_ref(k: int) -> str:
        return f"row {k}" + (f" (line {k + line0})" if line0 else "")

    return row_ref


def _numeric_column(df, col: str, tcol: str, tunit: str, unit: str, name: str, row_ref):
    """Column ``col`` as finite floats (its own units), naming the first cell that is not one."""
    import numpy as np
    import pandas as pd

    dtype = df[col].dtype
    if pd.api.types.is_bool_dtype(dtype) or not (pd.api.types.is_numeric_dtype(dtype)
                                                 or pd.api.types.is_object_dtype(dtype)
                                                 or pd.api.types.is_string_dtype(dtype)):
        raise InputError(f"{name}: column {col!r} holds {dtype} values; store "
                         + ("times as numbers in " + tunit if col == tcol else
                            f"accelerations as numbers in {unit}") + " in that column")
    if pd.api.types.is_complex_dtype(dtype):
        raise InputError(f"{name}: column {col!r} holds complex values; store real accelerations in "
                         f"{unit} in that column")
    try:
        v = pd.to_numeric(df[col], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
    except (TypeError, ValueError):  # cells holding lists, dicts, bytes ... (Parquet)
        raise InputError(f"{name}: column {col!r} holds values that are not numbers "
                         f"(first: {df[col].iloc[0]!r}); store plain numbers in it") from None
    raw = df[col].to_numpy()
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size:
        k = int(bad[0])
        if pd.isna(raw[k]) or str(raw[k]).strip().lower() == "nan":
            what = "empty or NaN"
        elif np.isinf(v[k]):
            what = "infinite"
        else:
            what = f"not a number ({raw[k]!r})"
        raise InputError(f"{name}: {row_ref(k)}, column {col!r} is {what} ({bad.size} bad row(s) in "
                         "this column); fix or remove those rows")
    return v


def _numeric_seconds(df, tcol: str, tunit: str, origin: str | None, shown, name: str):
    """(times in s, what t = 0 is) of the numeric time column ``shown`` (in ``tunit``)."""
    import numpy as np

    zero = None
    if origin == "first":
        t, zero = to_seconds(shown, tunit)
    else:
        t = shown * TIME_UNITS[tunit]
    if isinstance(df[tcol].dtype, np.dtype):
        check_time_resolution(shown, df[tcol].dtype, f"{name}: column {tcol!r}")
    return t, zero


def _check_increasing(t, shown, numeric: bool, tcol: str, name: str, row_ref) -> None:
    """Refuse times that repeat or go back, naming the row and both times as the file has them."""
    import numpy as np

    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        kind = "repeats" if dt[k - 1] == 0 else "goes back from"
        prev, cur = shown[k - 1], shown[k]
        fmt = (lambda x: repr(float(x))) if numeric else (lambda x: repr(str(x)))
        raise InputError(f"{name}: {row_ref(k)}: time {fmt(cur)} {kind} the previous "
                         f"row's {fmt(prev)} ({tcol!r} must increase strictly); "
                         "sort the file by time and drop duplicate samples")


def read_recording(path: str | os.PathLike, input: dict | None = None):
    """Read a recording (CSV or Parquet) into :class:`bvpnav.ImuData`.

    Parameters
    ----------
    path : str or path-like
        The file; must be a regular file (a FIFO, device or folder is refused before
        it is opened), opened read-only, never modified.
    input : dict, optional
        The spec's ``[input]`` table: ``time`` (column, default ``"t"``), ``time_unit``
        (``s``, ``ms``, ``us``, ``ns``; default ``s``; or ``iso8601`` for ISO 8601
        timestamps or a datetime column, converted to seconds from the first sample),
        ``time_origin`` (``"first"``: count the times from the first sample, subtracted
        exactly in integer arithmetic for integer columns), ``columns`` (axis -> column;
        default every ``acc_<axis>`` column) and ``unit`` (``m/s^2``, ``g``, ``mg``,
        ``ft/s^2``; default ``m/s^2``).

    Returns
    -------
    ImuData
        Times in s, accelerations in m/s^2; ``data.time_origin`` says what ``t = 0`` is
        when the times were converted (ISO timestamp or ``"<value> <unit>"``), else None.

    Raises
    ------
    InputError
        Naming the file and the column or row, with the fix: missing columns (with the
        ones present), columns of bool, date or duration type, non-numeric, NaN or
        infinite cells, unsorted or duplicate times, fewer than 3 rows, unknown units,
        unreadable or empty files, ragged rows and fields separated by something other
        than commas; files that are something else (a ZIP/xlsx/xls/Parquet renamed .csv,
        text renamed .parquet), comment preambles, decimal commas, empty or duplicate
        header cells, ISO timestamps without ``time_unit = "iso8601"``, integer epochs that
        float seconds cannot resolve, axis names whose trajectory columns would collide
        (``acc_vx`` beside ``acc_x``, ``acc_t``, ``acc_``). A UTF-8 byte-order mark is
        accepted (an encoding marker, not data). Time stored as the Parquet index is used
        when the index carries the time column's name. No raw parser exception escapes.
    """
    import numpy as np

    p = Path(path)
    name = str(p)
    tcol, tunit, unit, origin, cols = _input_options(dict(input or {}), name)
    df = _time_as_column(_read_table(p), tcol, name)
    _check_separator(df, name)
    cols = _axis_columns(df, cols, name)
    _check_columns_present(df, tcol, cols, name)
    if len(df) < 3:
        raise InputError(f"{name}: {len(df)} rows; at least 3 samples are needed")
    row_ref = _row_ref(2 if p.suffix.lower() == ".csv" else None)  # header is line 1
    t_conv, zero = _time_seconds(df, tcol, tunit, origin, name, row_ref)
    arrays = {col: _numeric_column(df, col, tcol, tunit, unit, name, row_ref)
              for col in ([] if t_conv is not None else [tcol]) + list(cols.values())}
    if t_conv is not None:
        t, shown = t_conv, df[tcol].to_numpy()
    else:
        shown = arrays[tcol]
        t, zero = _numeric_seconds(df, tcol, tunit, origin, shown, name)
    _check_increasing(t, shown, t_conv is None, tcol, name, row_ref)
    acc = np.column_stack([arrays[c] for c in cols.values()]) * ACC_UNITS[unit]
    return ImuData(t=t, acc=acc, axes=list(cols), time_origin=zero)


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
    """A JSON-ready summary: lambda and rule, error-model estimates with units, solver
    statistics and item residuals."""


    units = {}
    em = problem.error_model
    for comp in ([] if em is None else getattr(em, "components", (em,))):
        for n in comp.names(problem.data):
            units[n] = getattr(comp, "units", "")
    st = solution.stats
    keep = ("solver", "status", "verified", "accuracy", "iterations", "compile_time", "solve_time",
            "wall_time", "factorization", "verification", "attempts", "demoted", "sequential")
    return plain_json({
        "lam": solution.lam, "lam_rule": solution.lam_rule,
        "error_model": {k: {"estimate": float(v), "units": units.get(k, "")}
                        for k, v in solution.error_params.items()},
        "solver": {k: st.get(k) for k in keep if k in st},
        "items": solution.items.to_dict(orient="records"),
        "warnings": list(solution.warnings),
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


def _input_identities(inputs: dict) -> tuple[dict, dict]:
    """The given inputs by resolved path and by (device, inode): -> (name, path, True)."""
    by_real: dict[str, tuple[str, object, bool]] = {}  # resolved path -> (name, path, is an input)
    by_key: dict[tuple[int, int], tuple[str, object, bool]] = {}  # (device, inode) -> the same
    for k, p in inputs.items():
        if p is not None:
            real, key = _ident(p)
            by_real.setdefault(real, (k, p, True))
            if key is not None:
                by_key.setdefault(key, (k, p, True))
    return by_real, by_key


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
        (None: not given). Inputs are only read.
    outputs : dict
        How the caller names each output (e.g. ``"--out"``, ``"--plot"``) -> its path
        (None: not given).

    Raises
    ------
    InputError
        Naming both paths and the option to change, when an output is an input or another
        output of the same run (same path after resolving symlinks, or the same file
        through a hard link); when an output exists but is a folder, a FIFO, a device or a
        read-only file; when a part of its folder is a file; or when its folder cannot be
        written (permission, read-only file system), checked by creating and removing a
        temporary file there.
    """
    by_real, by_key = _input_identities(inputs)
    outs = [(k, p, *_ident(p)) for k, p in outputs.items() if p is not None]
    for opt, p, real, key in outs:
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
    """Size (bytes), modification time (ns) and SHA-256 of a regular file's content.

    Raises
    ------
    OSError
        If it cannot be read, or is not a regular file (a FIFO is never opened: that
        would block).
    """
    import hashlib

    if not _stat.S_ISREG(os.stat(path).st_mode):
        raise OSError(_errno.EINVAL, "not a regular file", str(path))
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        st = os.fstat(fh.fileno())
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return {"size": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": h.hexdigest()}


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
