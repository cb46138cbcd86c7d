"""Small shared helpers for the item files (not an item kind)."""

from __future__ import annotations

import numpy as np

from bvpnav.errors import InputError
from bvpnav.grid import as_times
from bvpnav.timebase import as_float_array


def times(value, label: str, what: str = "t") -> np.ndarray:
    """Validated 1-D array of times (s) for an item, naming the item on error."""
    return as_times(value, f"{label}: {what}")


def interval(t0, t1, label: str) -> tuple[float, float]:
    """Validated interval ``t0 < t1`` in s."""
    a = as_times(t0, f"{label}: t0")
    b = as_times(t1, f"{label}: t1")
    if a.size != 1 or b.size != 1:
        raise InputError(f"{label}: t0 and t1 must be single times in s")
    if not b[0] > a[0]:
        raise InputError(f"{label}: interval t0={float(a[0])!r} s, t1={float(b[0])!r} s has t1 <= t0; "
                         "give t0 < t1")
    return float(a[0]), float(b[0])


def finite(value, label: str, what: str = "value") -> np.ndarray:
    """Finite float array (any shape, a fresh copy), naming the item on error."""
    v = as_float_array(value, f"{label}: {what}", "the item's units")  # a copy, never the caller's
    bad = np.flatnonzero(~np.isfinite(v.ravel()))
    if bad.size:
        raise InputError(f"{label}: {what} entry {bad[0]} is {float(v.ravel()[bad[0]])!r}; must be finite "
                         "(give a number)")
    return v
