"""One input normalisation: times as float seconds, numbers as float arrays.

Every entry point (``ImuData``, ``TimeGrid``, items, the CSV/Parquet readers and spec
values) turns what it was given into a fresh float array through this module, so the
same input is read the same way everywhere:

- the result is always a **copy** (the caller's array is never frozen, kept or changed);
- ``bool``, ``complex``, ``object`` and string data are refused by name (a complex value
  would lose its imaginary part, a bool is a flag and not a measurement, strings would be
  parsed silently);
- datetimes (``numpy.datetime64``, pandas ``Timestamp``/``DatetimeIndex``/datetime
  ``Series``, ``datetime.datetime``) and durations (``timedelta64``, ``Timedelta``) are
  refused by the Python API with the one-line conversion :func:`to_seconds`, which
  returns seconds from a stated origin;
- times beyond :data:`MAX_SECONDS` in magnitude are refused: they are epochs in ms, us or
  ns read as seconds, and :func:`to_seconds` with ``unit=`` converts them, subtracting
  the origin in integer arithmetic so that nanosecond epochs keep their precision.
"""

from __future__ import annotations

import datetime as _dt
from typing import Any

import numpy as np

from .errors import InputError

__all__ = ["MAX_SECONDS", "TIME_UNITS", "as_float_array", "as_seconds", "check_time_resolution",
           "to_seconds"]

#: Largest time magnitude accepted as seconds (about 3,170 years). Unix epoch seconds
#: are ~1.7e9; epochs in ms, us or ns (~1.7e12, 1.7e15, 1.7e18) are far beyond it.
MAX_SECONDS = 1e11
#: Seconds per unit of an integer or float time value.
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
#: Integer nanoseconds per unit (exact integer arithmetic).
_NS_PER_UNIT = {"s": 10**9, "ms": 10**6, "us": 10**3, "ns": 1}

_CONVERT = ("convert with `t, origin = bvpnav.timebase.to_seconds(t)` (float seconds from the first "
            "sample; keep the origin, e.g. ImuData(t, acc, time_origin=origin))")


def _is_time_scalar(v) -> bool:
    return isinstance(v, (_dt.datetime, _dt.date, _dt.time, _dt.timedelta, np.datetime64,
                          np.timedelta64))


def _pandas_array(x):
    """``x`` as a numpy array if it is a pandas object, else None."""
    import pandas as pd

    if isinstance(x, (pd.Timestamp, pd.Timedelta)):
        return np.asarray(x, dtype=object)
    if not isinstance(x, (pd.Series, pd.Index, pd.DataFrame, pd.api.extensions.ExtensionArray)):
        return None
    dtypes = list(x.dtypes) if isinstance(x, pd.DataFrame) else [x.dtype]
    if any(pd.api.types.is_bool_dtype(d) for d in dtypes):
        return np.zeros(np.shape(x), dtype=bool)  # refused by kind; the values do not matter
    if dtypes and all(pd.api.types.is_numeric_dtype(d) and not pd.api.types.is_complex_dtype(d)
                      for d in dtypes):
        return x.to_numpy(dtype=float, na_value=np.nan)  # nullable Int64/Float64 too
    return np.asarray(x.to_numpy())


def _refuse_kind(arr: np.ndarray, what: str, units: str, time: bool) -> None:
    """Raise for bool, complex, object, string, datetime and duration arrays."""
    kind = arr.dtype.kind
    if kind in "iuf":
        return
    if kind == "O":
        flat = arr.ravel()
        stamp = next((v for v in flat if _is_time_scalar(v)), None)
        if stamp is not None:
            kind = "m" if isinstance(stamp, (_dt.timedelta, np.timedelta64)) else "M"
        else:
            odd = [(k, v) for k, v in enumerate(flat)
                   if not (isinstance(v, (int, float, np.integer, np.floating))
                           and not isinstance(v, (bool, np.bool_)))][:1]
            shown = "" if not odd else (f" (entry {odd[0][0]} is {odd[0][1]!r}, of type "
                                        f"{type(odd[0][1]).__name__})")
            raise InputError(f"{what}: an object array{shown}; give plain numbers in {units} "
                             "(e.g. np.asarray(values, dtype=float) after fixing the odd entries)")
    if kind == "b":
        raise InputError(f"{what}: bool values (True/False) are not {'times' if time else 'measurements'}; "
                         f"give numbers in {units}")
    if kind == "c":
        raise InputError(f"{what}: complex values (the imaginary part would be lost); give real numbers "
                         f"in {units} (e.g. values.real if the imaginary part is zero)")
    if kind in "US":
        first = arr.ravel()[0] if arr.size else ""
        raise InputError(f"{what}: cannot be read as numbers: text values (first: {str(first)!r}) are "
                         f"never parsed silently; pass numbers in {units}")
    if kind in "Mm":
        which = "datetime" if kind == "M" else "duration (timedelta)"
        if time:
            raise InputError(f"{what}: {which} values are not read as seconds; {_CONVERT}")
        raise InputError(f"{what}: {which} values; give numbers in {units}")
    if kind not in "iuf":
        raise InputError(f"{what}: values of dtype {arr.dtype} are not numbers; give numbers in {units}")


def as_float_array(x: Any, what: str, units: str = "SI units", time: bool = False) -> np.ndarray:
    """A fresh float64 copy of ``x``, refusing non-numeric data by name.

    Parameters
    ----------
    x : array_like
        Numbers (lists, numpy arrays, numeric pandas objects).
    what : str
        The culprit's name for messages (e.g. ``"acc"``, ``"Position#2: value"``).
    units : str
        Units the numbers are expected in, for messages.
    time : bool
        Whether ``x`` holds times (datetime messages then give the conversion).

    Returns
    -------
    numpy.ndarray
        A new float64 array (never a view of ``x``), any shape.

    Raises
    ------
    InputError
        For bool, complex, object, string, datetime and duration data, and masked arrays
        with a masked entry (an all-unmasked masked array is read as its data).
    """
    if isinstance(x, np.ma.MaskedArray):
        mask = np.ma.getmaskarray(x)
        if mask.any():
            first = tuple(int(v) for v in np.argwhere(mask)[0])
            where = first[0] if len(first) == 1 else first
            raise InputError(f"{what}: a masked array with {int(mask.sum())} masked entr"
                             f"{'y' if mask.sum() == 1 else 'ies'} (first: index {where}); bvpnav never "
                             "fills gaps: remove those samples (e.g. keep = ~mask.any(axis=1) on t and "
                             "the values) or repair them, then pass plain numbers")
        x = np.ma.getdata(x)
    arr = _pandas_array(x)
    if arr is None and isinstance(x, (list, tuple)):
        # np.asarray([1.0, True]) would be [1.0, 1.0]: find a bool mixed into numbers first
        try:
            obj = np.asarray(x, dtype=object).ravel()
        except (TypeError, ValueError):
            obj = np.array([], dtype=object)
        flag = next((k for k, v in enumerate(obj) if isinstance(v, (bool, np.bool_))), None)
        if flag is not None:
            raise InputError(f"{what}: entry {flag} is {obj[flag]!r}, a bool (True/False), not a "
                             f"{'time' if time else 'measurement'}; give numbers in {units}")
    if arr is None:
        try:
            arr = np.asarray(x)
        except (TypeError, ValueError) as exc:  # ragged nested lists
            raise InputError(f"{what}: cannot be read as an array of numbers ({exc}); give a scalar or "
                             f"a rectangular array of numbers in {units}") from None
    _refuse_kind(arr, what, units, time)
    try:
        return np.array(arr, dtype=float, copy=True)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"{what}: cannot be read as numbers ({exc}); give numbers in {units}") from None


def as_seconds(t: Any, what: str = "t", limit: bool = True) -> np.ndarray:
    """Times as a fresh 1-D float array in s (a scalar becomes length 1).

    Parameters
    ----------
    t : array_like
        Times in s.
    what : str
        Name for messages.
    limit : bool
        Refuse magnitudes above :data:`MAX_SECONDS` (epochs in ms/us/ns).

    Raises
    ------
    InputError
        For non-numeric data (see :func:`as_float_array`), datetimes and durations (with
        the conversion to use), more than one dimension, non-finite values, and (with
        ``limit``) epoch-sized values.
    """
    dtype = getattr(t, "dtype", None)
    arr = as_float_array(t, what, "s", time=True)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise InputError(f"{what}: expected a scalar or a 1-D array of times in s, got shape {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise InputError(
            f"{what}: value at index {bad[0]} is {float(arr[bad[0]])!r} ({bad.size} non-finite "
            "value(s)); times must be finite numbers in s. Remove or repair that entry."
        )
    if isinstance(dtype, np.dtype):
        check_time_resolution(arr, dtype, what)
    if limit:
        big = np.flatnonzero(np.abs(arr) > MAX_SECONDS)
        if big.size:
            k = int(big[0])
            raise InputError(
                f"{what}: value at index {k} is {float(arr[k]):.6g} s, beyond {MAX_SECONDS:g} s (~3,000 "
                "years): an epoch in ms, us or ns read as seconds? Convert it with "
                "`t, origin = bvpnav.timebase.to_seconds(t, unit=\"ns\")` (or \"ms\", \"us\"): seconds "
                "from the first sample, integer arithmetic first"
            )
    return arr


#: Coarsest time resolution accepted from a low-precision float, as a fraction of the
#: median sample step.
RESOLUTION_FRACTION = 1e-3


def check_time_resolution(t: np.ndarray, dtype: np.dtype, what: str) -> None:
    """Refuse times stored in a float type too coarse for their sample steps.

    Parameters
    ----------
    t : numpy.ndarray
        The times as read (float64), in s or the column's unit.
    dtype : numpy.dtype
        The type they were stored in; only floats narrower than float64 are checked.
    what : str
        The culprit (argument or column) for the message.

    Raises
    ------
    InputError
        When the spacing of ``dtype`` at ``max|t|`` exceeds :data:`RESOLUTION_FRACTION`
        of the median sample step: the stored times are already quantised.
    """
    if dtype.kind != "f" or dtype.itemsize >= 8 or t.size < 2:
        return
    steps = np.abs(np.diff(t))
    step = float(np.median(steps))
    if not np.isfinite(step) or step <= 0:
        return  # the ordering check reports it
    top = float(np.max(np.abs(t)))
    res = float(np.spacing(dtype.type(top)))
    if res > RESOLUTION_FRACTION * step:
        raise InputError(f"{what}: times stored as {dtype} resolve only {res:.3g} at {top:.6g}, "
                         f"{res / step:.3g} of the median step {step:.3g} (the times are quantised); store "
                         "the times as float64, or as integers with time_unit (e.g. ms), or count them "
                         "from the first sample")


def to_seconds(values: Any, unit: str | None = None) -> tuple[np.ndarray, str]:
    """Convert times to float seconds from the first sample, and say from what.

    Parameters
    ----------
    values : array_like, shape (N,)
        Datetimes (``numpy.datetime64``, pandas ``DatetimeIndex``/``Series``/``Timestamp``
        list, ``datetime.datetime`` list, ISO 8601 strings), durations (``timedelta64``,
        ``Timedelta``), or numbers in ``unit``.
    unit : {"s", "ms", "us", "ns"}, optional
        Required for numbers (e.g. ``"ns"`` for int64 nanosecond epochs); not allowed for
        datetimes and durations, which carry their own unit.

    Returns
    -------
    seconds : numpy.ndarray, shape (N,)
        ``values - values[0]`` in s (float64). The subtraction is done in integer
        nanoseconds (datetimes, durations) or integers (integer input) before the
        conversion to float, so nanosecond epochs keep their precision.
    origin : str
        What ``seconds == 0`` is: an ISO 8601 timestamp, a duration, or ``"<value> <unit>"``.

    Raises
    ------
    InputError
        For an empty or non-1-D input, an unknown unit, a missing unit for numbers, NaT or
        non-finite values, mixed time zones, or unparseable strings.
    """
    import pandas as pd

    arr = _pandas_array(values)
    if arr is None:
        arr = np.asarray(values)
    if arr.ndim != 1 or arr.size == 0:
        raise InputError(f"to_seconds: expected a 1-D array of times, got shape {arr.shape}")
    kind = arr.dtype.kind
    flat = arr.ravel()
    if kind == "O" and any(_is_time_scalar(v) for v in flat):
        kind = "m" if any(isinstance(v, (_dt.timedelta, np.timedelta64)) for v in flat) else "M"
    if kind in "US" or (kind == "O" and all(isinstance(v, str) for v in flat)):
        kind = "M"
    if kind in "Mm":
        if unit is not None:
            raise InputError(f"to_seconds: unit={unit!r} given for datetime/duration values, which carry "
                             "their own unit; drop unit=")
        try:
            if kind == "M":
                idx = pd.DatetimeIndex(pd.to_datetime(values if not isinstance(values, np.ndarray) else arr,
                                                      format="ISO8601" if arr.dtype.kind in "USO" else None))
            else:
                idx = pd.TimedeltaIndex(values if not isinstance(values, np.ndarray) else arr)
        except (TypeError, ValueError, OverflowError) as exc:
            raise InputError(f"to_seconds: cannot read the values as times ({str(exc).splitlines()[0]}); "
                             "give datetimes of one time zone (or all naive) or durations") from None
        nat = np.flatnonzero(idx.isna())
        if nat.size:
            raise InputError(f"to_seconds: entry {int(nat[0])} is NaT (missing); every sample needs a time. "
                             "Remove or repair that entry.")
        ns = idx.as_unit("ns").asi8.astype(np.int64)  # integer nanoseconds (whatever the resolution)
        origin = idx[0].isoformat() if kind == "M" else str(idx[0])
        return (ns - ns[0]).astype(float) * 1e-9, origin
    if unit is None:
        raise InputError("to_seconds: numbers need unit= (\"s\", \"ms\", \"us\" or \"ns\"), e.g. "
                         "to_seconds(t, unit=\"ns\") for int64 nanosecond epochs")
    if unit not in TIME_UNITS:
        raise InputError(f"to_seconds: unit={unit!r}; valid units: {list(TIME_UNITS)}")
    _refuse_kind(arr, "to_seconds", unit, time=True)
    if kind in "iu":
        first = int(flat[0])
        if kind == "i" or int(flat.max()) < 2**63:
            d = arr.astype(np.int64) - np.int64(first)  # integer arithmetic: exact
        else:  # uint64 beyond int64: Python integers
            d = np.array([int(v) - first for v in flat], dtype=np.int64)
        return d.astype(float) * TIME_UNITS[unit], f"{first} {unit}"
    f = np.array(arr, dtype=float)
    bad = np.flatnonzero(~np.isfinite(f))
    if bad.size:
        raise InputError(f"to_seconds: entry {int(bad[0])} is {f[bad[0]]!r}; times must be finite")
    return (f - f[0]) * TIME_UNITS[unit], f"{float(f[0])!r} {unit}"
