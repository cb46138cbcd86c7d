"""CSV and Parquet tables, one row per sample: the default reader.

A table holds either navigation-frame acceleration (``acc_<axis>`` columns, or the
``columns`` map) or strapdown channels: specific force and gyro rates in the sensor's
axes, and perhaps an orientation (quaternion or Euler-angle columns), named in the spec's
``[input]``::

    [input]
    time = "t"
    specific_force = ["f_x", "f_y", "f_z"]   # m/s^2 (or unit = "g")
    gyro = ["w_x", "w_y", "w_z"]             # gyro_unit = "rad/s" (default) or "deg/s"
    attitude = { quaternion = ["qw", "qx", "qy", "qz"], scalar = "first" }   # optional
    attitude_frame = "enu"                   # what the orientation is relative to
    frame = "enu"                            # the navigation frame (or "ned")
    odometer = "speed"                       # optional: a forward-speed column (m/s) ...
    odometer_sigma = 0.05                    # ... its noise (m/s): an Odometer item
    odometer_lever = [-1.2, 0.8, -0.4]       # ... measured at this point (body axes, m)

Every check of the classic table is kept (see :meth:`TableReader.read`).
"""

from __future__ import annotations

import os
import re as _re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..imu import ACC_UNITS, axis_name_clash
from ..io import parquet_frame, read_regular_file
from ..timebase import TIME_UNITS, check_time_resolution, to_seconds
from . import Reader, Recording, register_reader

__all__ = ["TableReader", "GYRO_UNITS", "read_table"]

#: rad/s per unit of gyro columns.
GYRO_UNITS = {"rad/s": 1.0, "deg/s": 3.141592653589793 / 180.0}

#: The strapdown keys of a table's ``[input]``.
STRAPDOWN_KEYS = ("specific_force", "gyro", "gyro_unit", "attitude")

#: The keys of an odometer column (strapdown tables only).
ODOMETER_KEYS = ("odometer", "odometer_sigma", "odometer_lever")

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
    # parsed in UTC first (mixed offsets, e.g. a daylight-saving switch, cannot be parsed otherwise):
    # only to name the first cell that is no timestamp at all
    stamps = pd.to_datetime(col, format="ISO8601", errors="coerce", utc=True)
    nat = np.flatnonzero(stamps.isna().to_numpy())
    if nat.size:
        k = int(nat[0])
        raise InputError(f"{name}: {row_ref(k)}, column {tcol!r} is {cells[k]!r}, not an ISO 8601 "
                         "timestamp (e.g. 2026-01-31T12:00:00.125Z); fix or remove that row")
    # a zone is an offset after a time of day ("...T12:00:00+02:00", "...T120000Z"), not a date's day
    zone = _re.compile(r"[T ]\d{2}(:?\d{2}){0,2}([.,]\d+)?(Z|[+-]\d{2}(:?\d{2})?)$")
    zoned = np.array([bool(zone.search(v.strip())) for v in cells])
    if zoned.any() and not zoned.all():
        k = int(np.flatnonzero(zoned != zoned[0])[0])
        raise InputError(f"{name}: {row_ref(k)}, column {tcol!r} is {cells[k]!r}, "
                         f"{'with' if zoned[k] else 'without'} a time zone, unlike row 0 ({cells[0]!r}); a "
                         "naive timestamp's zone is not guessed: give every timestamp its offset (or none)")
    if not zoned.all():  # all naive: kept naive (their zone is not guessed to be UTC)
        stamps = pd.to_datetime(col, format="ISO8601", errors="coerce")
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


def _check_columns_present(df, tcol: str, roles: dict, name: str) -> None:
    """Refuse a column that feeds two roles, and a time or role column missing from ``df``.

    ``roles`` maps what a column is for (``"axis 'x'"``, ``"specific force y"``) to its name."""
    owner: dict[str, str] = {tcol: "the time column"}
    for role, c in roles.items():
        if c in owner:
            fix = ("map each axis to its own column in the spec's [input] columns = { x = \"...\", y = "
                   "\"...\" }" if role.startswith("axis") else
                   "give each strapdown channel its own column in the spec's [input]")
            raise InputError(f"{name}: column {c!r} is mapped to {role} but is already {owner[c]}; one "
                             f"column can feed one {role.split()[0]} only: {fix}")
        owner[c] = role
    for what, col in [("time", tcol)] + [(role.replace("'", ""), c) for role, c in roles.items()]:
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
                            f"{'speeds' if unit == 'm/s' else 'accelerations'} as numbers in {unit}")
                         + " in that column")
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


def _column_list(value: Any, key: str, k: int, name: str) -> list[str]:
    if not (isinstance(value, list) and len(value) == k and all(isinstance(c, str) and c for c in value)):
        raise InputError(f"{name}: [input] {key} = {value!r}; give the {k} column names in axis order, e.g. "
                         f"{key} = {[f'{key[0]}_{a}' for a in 'xyzw'[:k]]}")
    return list(value)


def _attitude_columns(value: Any, name: str) -> tuple[str, list[str], dict]:
    """(kind, columns, convention) of ``[input] attitude``: quaternion or Euler-angle columns."""
    form = ('give attitude = { quaternion = ["qw", "qx", "qy", "qz"], scalar = "first" } (or scalar = '
            '"last" with [x, y, z, w] columns), or attitude = { euler = ["yaw", "pitch", "roll"], '
            'sequence = "ZYX", degrees = true } (the angles in the order of the sequence)')
    if not isinstance(value, Mapping) or len({"quaternion", "euler"} & set(value)) != 1:
        raise InputError(f"{name}: [input] attitude = {value!r}; {form}")
    if "quaternion" in value:
        extra = sorted(set(value) - {"quaternion", "scalar"})
        if extra or value.get("scalar") not in ("first", "last"):
            unknown = f"; unknown keys {extra}" if extra else ""
            raise InputError(f"{name}: [input] attitude: quaternion columns need scalar = \"first\" or "
                             f"\"last\" (stated, never guessed){unknown}; {form}")
        return "quaternion", _column_list(value["quaternion"], "attitude.quaternion", 4, name), \
            {"scalar": value["scalar"]}
    extra = sorted(set(value) - {"euler", "sequence", "degrees"})
    from ..strapdown import _valid_sequence

    if extra or not _valid_sequence(value.get("sequence")) or not isinstance(value.get("degrees"), bool):
        raise InputError(f"{name}: [input] attitude: Euler-angle columns need sequence (three axes from "
                         "x, y, z: lower case extrinsic, upper case intrinsic, e.g. \"ZYX\" for yaw, pitch, "
                         "roll) and degrees = true or false, both stated"
                         f"{'; unknown keys ' + str(extra) if extra else ''}; {form}")
    return "euler", _column_list(value["euler"], "attitude.euler", 3, name), \
        {"sequence": value["sequence"], "degrees": value["degrees"]}


def _strapdown_roles(inp: Mapping[str, Any], name: str) -> tuple[dict, dict]:
    """(role -> column, parsed strapdown options) of a strapdown table's ``[input]``."""
    if "columns" in inp:
        raise InputError(f"{name}: [input] has both columns (navigation-frame acceleration) and "
                         "specific_force (body frame); a table holds one or the other: drop one")
    roles: dict[str, str] = {}
    sf = _column_list(inp["specific_force"], "specific_force", 3, name)
    roles.update({f"specific force {a}": c for a, c in zip("xyz", sf, strict=True)})
    parsed: dict[str, Any] = {"sf": sf}
    if "gyro" in inp:
        gy = _column_list(inp["gyro"], "gyro", 3, name)
        roles.update({f"gyro {a}": c for a, c in zip("xyz", gy, strict=True)})
        parsed["gyro"] = gy
    gu = inp.get("gyro_unit", "rad/s")
    if not isinstance(gu, str) or gu not in GYRO_UNITS:
        raise InputError(f"{name}: [input] gyro_unit = {gu!r}; valid gyro units: {list(GYRO_UNITS)}")
    if "gyro_unit" in inp and "gyro" not in inp:
        raise InputError(f"{name}: [input] gyro_unit without gyro columns; add gyro = [...] or drop it")
    parsed["gyro_unit"] = gu
    if "attitude" in inp:
        kind, cols, conv = _attitude_columns(inp["attitude"], name)
        labels = ("qw qx qy qz" if conv.get("scalar") == "first" else "qx qy qz qw").split() \
            if kind == "quaternion" else [f"angle {i + 1}" for i in range(3)]
        roles.update({f"attitude {lab}": c for lab, c in zip(labels, cols, strict=True)})
        parsed["attitude"] = (kind, cols, conv)
    if "gyro" not in inp and "attitude" not in inp:
        raise InputError(f"{name}: [input] specific_force needs gyro = [...] columns (the attitude is "
                         "integrated from them) or attitude = {...} columns (the device's orientation)")
    return roles, parsed


def _odometer_option(inp: Mapping[str, Any], name: str, strap: bool):
    """(column, sigma m/s, lever m) of an odometer column, or None when none is named."""
    import math

    given = [k for k in ODOMETER_KEYS if k in inp]
    if not given:
        return None
    if "odometer" not in inp:
        raise InputError(f"{name}: [input] {given} without odometer = \"<column>\"; name the forward-speed "
                         "column (m/s) or drop them")
    if not strap:
        raise InputError(f"{name}: [input] odometer needs strapdown columns (specific_force with gyro or "
                         "attitude): an odometer measures along the body axis, which navigation-frame "
                         "accelerations do not know")
    col, sigma = inp["odometer"], inp.get("odometer_sigma")
    if not isinstance(col, str) or not col:
        raise InputError(f"{name}: [input] odometer = {col!r}; give the forward-speed column's name")
    if isinstance(sigma, bool) or not isinstance(sigma, int | float) or not (
            math.isfinite(sigma) and sigma > 0):
        raise InputError(f"{name}: [input] odometer_sigma = {sigma!r}; give the speed's noise, a positive "
                         "number in m/s (the odometer column needs it)")
    lever = inp.get("odometer_lever", [0.0, 0.0, 0.0])
    if not (isinstance(lever, list | tuple) and len(lever) == 3 and all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in lever)):
        raise InputError(f"{name}: [input] odometer_lever = {lever!r}; give [x, y, z], the measured point "
                         "relative to the IMU in body axes, m")
    return col, float(sigma), tuple(float(v) for v in lever)


def _odometer_item(odo, t, speed, path: Path):
    from ..constraints import Odometer

    col, sigma, lever = odo
    return Odometer(t=t, speed=speed, sigma=sigma, lever=lever, name=f"{path.name} column {col}")


def _attitude_from_columns(arrays: dict, spec: tuple, name: str, row_ref):
    """scipy Rotation per row from quaternion or Euler-angle columns, unit norms checked."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    kind, cols, conv = spec
    a = np.column_stack([arrays[c] for c in cols])
    if kind == "euler":
        return Rotation.from_euler(conv["sequence"], a, degrees=conv["degrees"])
    q = a if conv["scalar"] == "last" else a[:, [1, 2, 3, 0]]
    norms = np.linalg.norm(q, axis=1)
    bad = np.flatnonzero(np.abs(norms - 1.0) > 1e-6)
    if bad.size:
        k = int(bad[0])
        raise InputError(f"{name}: {row_ref(k)}: the quaternion in columns {cols} has norm {norms[k]:.6g}, "
                         f"not 1 ({bad.size} such row(s)); check the column order and scalar = "
                         f"\"{conv['scalar']}\" (a wrong order or a scaled quaternion is a mistake bvpnav "
                         "does not repair)")
    return Rotation.from_quat(q)


def read_table(path: str | os.PathLike, input: Mapping[str, Any] | None = None) -> Recording:
    """Read a CSV or Parquet recording into a :class:`~bvpnav.readers.Recording`.

    Parameters
    ----------
    path : str or path-like
        The file; must be a regular file (a FIFO, device or folder is refused before
        it is opened), opened read-only, never modified.
    input : mapping, optional
        The reader's part of the spec's ``[input]``: ``time`` (column, default ``"t"``),
        ``time_unit`` (``s``, ``ms``, ``us``, ``ns``; default ``s``; or ``iso8601`` for ISO
        8601 timestamps or a datetime column, converted to seconds from the first sample),
        ``time_origin`` (``"first"``: count the times from the first sample, subtracted
        exactly in integer arithmetic for integer columns), ``unit`` (``m/s^2``, ``g``,
        ``mg``, ``ft/s^2``; default ``m/s^2``), and either ``columns`` (axis -> column of
        navigation-frame acceleration; default every ``acc_<axis>`` column) or the strapdown
        columns ``specific_force`` (three columns, ``unit``), ``gyro`` (three columns,
        ``gyro_unit`` ``rad/s`` or ``deg/s``) and ``attitude`` (quaternion or Euler-angle
        columns with their convention stated, see the module docstring); with strapdown
        columns, ``odometer`` names a forward-speed column (m/s, every row) that becomes an
        :class:`~bvpnav.constraints.Odometer` item with ``odometer_sigma`` (m/s, required)
        and ``odometer_lever`` ([x, y, z] m, body axes; default the IMU).

    Returns
    -------
    Recording
        Times in s, accelerations in m/s^2, rates in rad/s; ``time_origin`` says what
        ``t = 0`` is when the times were converted (ISO timestamp or ``"<value> <unit>"``).

    Raises
    ------
    InputError
        Naming the file and the column or row, with the fix: missing columns (with the
        ones present), a column given two roles, columns of bool, date or duration type,
        non-numeric, NaN or infinite cells, unsorted or duplicate times, fewer than 3 rows,
        unknown units, unreadable or empty files, ragged rows and fields separated by
        something other than commas; files that are something else (a ZIP/xlsx/xls/Parquet
        renamed .csv, text renamed .parquet), comment preambles, decimal commas, empty or
        duplicate header cells, ISO timestamps without ``time_unit = "iso8601"``, integer
        epochs that float seconds cannot resolve, axis names whose trajectory columns would
        collide (``acc_vx`` beside ``acc_x``, ``acc_t``, ``acc_``), quaternions that are not
        unit length, conventions not stated. A UTF-8 byte-order mark is accepted (an
        encoding marker, not data). Time stored as the Parquet index is used when the index
        carries the time column's name. No raw parser exception escapes.
    """
    import numpy as np

    p = Path(path)
    name = str(p)
    inp = dict(input or {})
    tcol, tunit, unit, origin, cols = _input_options(inp, name)
    strap = "specific_force" in inp
    if not strap and any(k in inp for k in STRAPDOWN_KEYS):
        given = [k for k in STRAPDOWN_KEYS if k in inp]
        raise InputError(f"{name}: [input] {given} without specific_force; strapdown tables name the "
                         "specific-force columns: add specific_force = [\"f_x\", \"f_y\", \"f_z\"]")
    if strap:
        roles, parsed = _strapdown_roles(inp, name)
    odo = _odometer_option(inp, name, strap)
    if odo is not None:
        roles["odometer"] = odo[0]
    df = _time_as_column(_read_table(p), tcol, name)
    _check_separator(df, name)
    if not strap:
        cols = _axis_columns(df, cols, name)
        roles = {f"axis {a!r}": c for a, c in cols.items()}
    _check_columns_present(df, tcol, roles, name)
    if len(df) < 3:
        raise InputError(f"{name}: {len(df)} rows; at least 3 samples are needed")
    row_ref = _row_ref(2 if p.suffix.lower() == ".csv" else None)  # header is line 1
    t_conv, zero = _time_seconds(df, tcol, tunit, origin, name, row_ref)
    units = {c: unit for c in roles.values()}
    if odo is not None:
        units[odo[0]] = "m/s"
    if strap:
        units.update({c: parsed["gyro_unit"] for c in parsed.get("gyro", ())})
        units.update({c: "(attitude)" for c in parsed.get("attitude", (None, ()))[1]})
    arrays = {col: _numeric_column(df, col, tcol, tunit, units.get(col, unit), name, row_ref)
              for col in ([] if t_conv is not None else [tcol]) + list(roles.values())}
    if t_conv is not None:
        t, shown = t_conv, df[tcol].to_numpy()
    else:
        shown = arrays[tcol]
        t, zero = _numeric_seconds(df, tcol, tunit, origin, shown, name)
    _check_increasing(t, shown, t_conv is None, tcol, name, row_ref)
    if not strap:
        acc = np.column_stack([arrays[c] for c in cols.values()]) * ACC_UNITS[unit]
        return Recording(t=t, source=name, time_origin=zero, acc=acc, axes=tuple(cols))
    f = np.column_stack([arrays[c] for c in parsed["sf"]]) * ACC_UNITS[unit]
    w = (np.column_stack([arrays[c] for c in parsed["gyro"]]) * GYRO_UNITS[parsed["gyro_unit"]]
         if "gyro" in parsed else None)
    att = (_attitude_from_columns(arrays, parsed["attitude"], name, row_ref) if "attitude" in parsed
           else None)
    items, notes = (), ()
    if odo is not None:
        items = (_odometer_item(odo, t, arrays[odo[0]], p),)
        notes = (f"Column {odo[0]!r}: {t.size} forward speeds (m/s) as an Odometer item along body x at the "
                 f"lever {list(odo[2])} m, sigma {odo[1]:g} m/s; add [[error_model]] type = "
                 "\"odometer_scale\" to estimate its scale factor.",)
    return Recording(t=t, source=name, time_origin=zero, specific_force=f, gyro=w, attitude=att, items=items,
                     notes=notes)


class TableReader(Reader):
    """CSV (comma-separated, header row) or Parquet, one row per sample (see :func:`read_table`)."""

    name = "table"
    suffixes = (".csv", ".parquet", ".pq")
    options = frozenset({"time", "time_unit", "time_origin", "columns", "unit", *STRAPDOWN_KEYS,
                         *ODOMETER_KEYS})
    description = "CSV or Parquet, one row per sample (time, acceleration or strapdown columns)"

    def sniff(self, head: bytes) -> bool:
        return True  # the default: every .csv / .parquet file is offered to it

    def read(self, path: Path, options: Mapping[str, Any]) -> Recording:
        return read_table(path, options)

    def example(self, folder: Path) -> Path:
        import numpy as np

        path = Path(folder) / "recording.csv"
        t = np.arange(11) * 0.1
        rows = (f"{float(a)!r},{float(b)!r}\n" for a, b in zip(t, np.sin(t), strict=True))
        path.write_text("t,acc_x\n" + "".join(rows))
        return path


register_reader(TableReader())
