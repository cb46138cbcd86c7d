"""Files in and out: recordings (CSV, Parquet), trajectories, JSON summaries.

Atomic output: every file bvpnav writes appears whole or not at all.

Outputs are written to a temporary file in the destination's folder and moved into
place with :func:`os.replace` (atomic on POSIX and Windows), so an interrupted run never
leaves a half-written result, and inputs are only ever opened for reading.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .errors import InputError

__all__ = ["atomic_path", "atomic_write_text", "atomic_write_bytes", "atomic_savefig", "read_recording",
           "write_table", "write_trajectory", "summary", "write_json"]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success move it onto ``path``.

    On an exception the temporary file is removed and ``path`` is left untouched.
    """
    dest = Path(path)
    dest.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=dest.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.replace(tmp_path, dest)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write text (UTF-8) atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write bytes atomically."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def atomic_savefig(fig, path: str | os.PathLike, **kwargs) -> None:
    """Save a matplotlib figure atomically (format from the path's suffix)."""
    fmt = Path(path).suffix.lstrip(".") or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, **kwargs)


# ------------------------------------------------------------------ recordings
def _read_table(path: Path):
    import pandas as pd

    suffix = path.suffix.lower()
    if not path.exists():
        raise InputError(f"{str(path)!r}: no such file; check the path")
    if not path.is_file():
        raise InputError(f"{str(path)!r}: not a file; give the path of a recording (.csv or .parquet)")
    if suffix == ".csv":
        try:
            return pd.read_csv(path)
        except pd.errors.EmptyDataError:
            raise InputError(f"{str(path)!r}: not a readable CSV file (it is empty); a recording needs a "
                             "header line (t, acc_<axis>) and at least 3 rows") from None
        except pd.errors.ParserError as exc:
            raise InputError(f"{str(path)!r}: not a readable CSV file ({str(exc).splitlines()[0]}); every "
                             "row needs the same number of fields as the header line") from None
        except UnicodeDecodeError:
            raise InputError(f"{str(path)!r}: not a readable CSV file (not UTF-8 text); save it as UTF-8 "
                             "comma-separated values") from None
        except (ValueError, OverflowError) as exc:  # e.g. unbalanced quotes, absurd field sizes
            raise InputError(f"{str(path)!r}: not a readable CSV file ({str(exc).splitlines()[0]}); check "
                             "the file is comma-separated text with one header line") from None
        except OSError as exc:
            raise InputError(f"{str(path)!r}: cannot read it ({exc.strerror}); check the path and "
                             "permissions") from None
    if suffix in (".parquet", ".pq"):
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise InputError(f"{str(path)!r}: reading Parquet needs pyarrow "
                             "(pip install 'bvpnav[parquet]')") from None
        try:
            return pd.read_parquet(path)
        except Exception as exc:  # pyarrow raises its own error types for corrupt files
            raise InputError(f"{str(path)!r}: not a readable Parquet file ({exc})") from None
    raise InputError(f"{str(path)!r}: unknown file type {suffix!r}; give a .csv or .parquet file")


def read_recording(path: str | os.PathLike, input: dict | None = None):
    """Read a recording (CSV or Parquet) into :class:`bvpnav.ImuData`.

    Parameters
    ----------
    path : str or path-like
        The file; opened read-only, never modified.
    input : dict, optional
        The spec's ``[input]`` table: ``time`` (column, default ``"t"``), ``time_unit``
        (``s``, ``ms``, ``us``, ``ns``; default ``s``), ``columns`` (axis -> column;
        default every ``acc_<axis>`` column) and ``unit`` (``m/s^2``, ``g``, ``mg``,
        ``ft/s^2``; default ``m/s^2``).

    Returns
    -------
    ImuData
        Times in s, accelerations in m/s^2.

    Raises
    ------
    InputError
        Naming the file and the column or row, with the fix: missing columns (with the
        ones present), columns of bool, date or duration type, non-numeric, NaN or
        infinite cells, unsorted or duplicate times, fewer than 3 rows, unknown units,
        unreadable or empty files, ragged rows and fields separated by something other
        than commas. Any other failure of the CSV parser is reported the same way, so
        no raw parser exception escapes.
    """
    import numpy as np
    import pandas as pd

    from .imu import ImuData
    from .spec import ACC_UNITS, TIME_UNITS

    p = Path(path)
    inp = dict(input or {})
    name = str(p)
    tcol = inp.get("time", "t")
    tunit = inp.get("time_unit", "s")
    unit = inp.get("unit", "m/s^2")
    if not isinstance(tcol, str):
        raise InputError(f"{name}: time={tcol!r}; give the name of the time column as a string")
    if not isinstance(tunit, str) or tunit not in TIME_UNITS:
        raise InputError(f"{name}: time_unit={tunit!r}; valid units: {list(TIME_UNITS)}")
    if not isinstance(unit, str) or unit not in ACC_UNITS:
        raise InputError(f"{name}: unit={unit!r}; valid acceleration units: {list(ACC_UNITS)}")
    cols = inp.get("columns")
    if cols is not None and not (isinstance(cols, dict) and cols
                                 and all(isinstance(v, str) for v in cols.values())):
        raise InputError(f"{name}: columns={cols!r}; map axis names to column names, e.g. "
                         'columns = { x = "acc_x" }')
    df = _read_table(p)
    if len(df.columns) == 1:
        head = str(df.columns[0])
        for sep, what in ((";", "';'"), ("\t", "tabs"), ("|", "'|'"), (" ", "spaces")):
            if sep in head.strip():
                raise InputError(f"{name}: one column {head!r}: the fields seem to be separated by {what}; "
                                 "bvpnav reads comma-separated CSV, save the file with ',' between fields")
    if cols is None:
        cols = {str(c)[4:]: c for c in df.columns if str(c).startswith("acc_")}
        if not cols:
            raise InputError(f"{name}: no acceleration columns: name them acc_<axis> or map them with "
                             f"columns = {{ x = \"...\" }} in the spec's [input]; columns in the file: "
                             f"{list(df.columns)}")
    for what, col in [("time", tcol)] + [(f"axis {a}", c) for a, c in cols.items()]:
        if col not in df.columns:
            raise InputError(f"{name}: column {col!r} ({what}) not found; columns in the file: "
                             f"{list(df.columns)}")
    if len(df) < 3:
        raise InputError(f"{name}: {len(df)} rows; at least 3 samples are needed")
    line0 = 2 if p.suffix.lower() == ".csv" else None  # header is line 1

    def row_ref(k: int) -> str:
        return f"row {k}" + (f" (line {k + line0})" if line0 else "")

    arrays = {}
    for col in [tcol, *cols.values()]:
        dtype = df[col].dtype
        if pd.api.types.is_bool_dtype(dtype) or not (pd.api.types.is_numeric_dtype(dtype)
                                                     or pd.api.types.is_object_dtype(dtype)
                                                     or pd.api.types.is_string_dtype(dtype)):
            raise InputError(f"{name}: column {col!r} holds {dtype} values; store "
                             + ("times as numbers in " + tunit if col == tcol else
                                f"accelerations as numbers in {unit}") + " in that column")
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
        arrays[col] = v
    t = arrays[tcol] * TIME_UNITS[tunit]
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        kind = "repeats" if dt[k - 1] == 0 else "goes back from"
        raise InputError(f"{name}: {row_ref(k)}: time {float(arrays[tcol][k])!r} {kind} the previous "
                         f"row's {float(arrays[tcol][k - 1])!r} ({tcol!r} must increase strictly); "
                         "sort the file by time and drop duplicate samples")
    acc = np.column_stack([arrays[c] for c in cols.values()]) * ACC_UNITS[unit]
    return ImuData(t=t, acc=acc, axes=list(cols))


def write_table(df, path: str | os.PathLike) -> None:
    """Write a DataFrame atomically as CSV (floats round-trip exactly) or Parquet."""
    p = Path(path)
    suffix = p.suffix.lower()
    with atomic_path(p) as tmp:
        if suffix == ".csv":
            df.to_csv(tmp, index=False, float_format="%.17g")
        elif suffix in (".parquet", ".pq"):
            try:
                df.to_parquet(tmp, index=False)
            except ImportError:
                raise InputError(f"{str(p)!r}: writing Parquet needs pyarrow "
                                 "(pip install 'bvpnav[parquet]')") from None
        else:
            raise InputError(f"{str(p)!r}: unknown output type {suffix!r}; use .csv or .parquet")


def write_trajectory(solution, path: str | os.PathLike) -> None:
    """Write ``solution.trajectory`` with a ``t`` column (s), positions (m) and velocities
    (m/s) named as in the Python API, atomically."""
    write_table(solution.trajectory.reset_index(), path)


def summary(solution, problem) -> dict:
    """A JSON-ready summary: lambda and rule, error-model estimates with units, solver
    statistics and item residuals."""
    import numpy as np

    def clean(v):
        if isinstance(v, dict):
            return {str(k): clean(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [clean(x) for x in v]
        if isinstance(v, np.ndarray):
            return clean(v.tolist())
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, float) and not np.isfinite(v):
            return None
        if isinstance(v, (str, int, float, bool)) or v is None:
            return v
        return str(v)

    units = {}
    em = problem.error_model
    for comp in ([] if em is None else getattr(em, "components", (em,))):
        for n in comp.names(problem.data):
            units[n] = getattr(comp, "units", "")
    st = solution.stats
    keep = ("solver", "status", "verified", "accuracy", "iterations", "compile_time", "solve_time",
            "wall_time", "factorization", "verification", "attempts", "demoted", "sequential")
    return clean({
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
