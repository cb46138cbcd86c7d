"""Hostile matrix of inputs: times, numbers, items, recordings and specs (issue 14).

Each case is a realistic mistake. API cases assert the exception class, the culprit and
the fix in the message, and that the caller's arrays are unchanged and still writeable;
file cases run through the reader and through the command line in a subprocess, and
assert that every input and earlier output is byte-identical afterwards (see
``tests/_hostile.py``). The classes of the report: data loss, misread input, traceback,
hang, vague message (the ``kind`` column below).
"""

from __future__ import annotations

import io
import os
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from _hostile import (
    EXIT_INPUT,
    assert_clean_failure,
    assert_unchanged,
    main_cli,
    raises_named,
    run_cli,
    snapshot,
)
from hypothesis import given, settings
from hypothesis import strategies as st

import bvpnav
from bvpnav.constraints import AverageVelocity, Position, Velocity
from bvpnav.errors import Infeasible, InputError
from bvpnav.grid import TimeGrid
from bvpnav.items import registry
from bvpnav.readers import read_recording
from bvpnav.samples import write_sample
from bvpnav.spec import load_spec, parse_spec, to_spec
from bvpnav.timebase import to_seconds

N = 11
T = np.linspace(0.0, 10.0, N)  # s
ACC1 = np.sin(T)  # m/s^2, one axis
ACC2 = np.column_stack([np.sin(T), np.cos(T)])  # m/s^2, two axes
STAMPS = pd.date_range("2026-01-31 12:00", periods=N, freq="1s")
NS_EPOCH = np.int64(1_769_860_800_000_000_000) + np.arange(N, dtype=np.int64) * 1_000_000_000


# --------------------------------------------------------------------- API
def _caller_arrays():
    """Fresh caller-owned arrays for one API case (checked unchanged and writeable after)."""
    return {
        "t": T.copy(), "acc1": ACC1.copy(), "acc2": ACC2.copy(),
        "t_dt": STAMPS.copy(), "t_series": pd.Series(STAMPS), "t_list": list(STAMPS),
        "t_td": (STAMPS - STAMPS[0]).to_numpy().copy(), "t_ns": NS_EPOCH.copy(),
        "acc_bool": ACC1 > 0, "acc_complex": ACC1 + 1j * ACC1,
        "acc_object": np.array([*ACC1[:3], None, *ACC1[4:]], dtype=object),
        "acc_text": ACC1.astype(str), "value2": np.array([0.0, 10.0]),
    }


def _imu(a, **kw):
    return bvpnav.ImuData(a["t"], a["acc2"], **kw)


def _solve(data, *items):
    return bvpnav.NavigationProblem(data).add(*items).solve(solver="direct")


#: (id, kind, call(arrays), exception, culprit, fix)
API_CASES = [
    ("t-DatetimeIndex", "misread input", lambda a: bvpnav.ImuData(a["t_dt"], a["acc1"]),
     InputError, r"time: datetime values", r"to_seconds\(t\).*time_origin=origin"),
    ("t-Series-of-datetimes", "misread input", lambda a: bvpnav.ImuData(a["t_series"], a["acc1"]),
     InputError, r"time: datetime values", r"to_seconds\(t\)"),
    ("t-list-of-Timestamps", "misread input", lambda a: bvpnav.ImuData(a["t_list"], a["acc1"]),
     InputError, r"time: datetime values", r"to_seconds\(t\)"),
    ("t-timedelta64", "misread input", lambda a: bvpnav.ImuData(a["t_td"], a["acc1"]),
     InputError, r"time: duration \(timedelta\) values", r"to_seconds\(t\)"),
    ("t-int64-ns-epoch", "misread input", lambda a: bvpnav.ImuData(a["t_ns"], a["acc1"]),
     InputError, r"time: value at index 0 is 1\.76986e\+18 s.*epoch", r'to_seconds\(t, unit="ns"\)'),
    ("TimeGrid-datetime64", "misread input", lambda a: TimeGrid(a["t_dt"].to_numpy()),
     InputError, r"time: datetime values", r"to_seconds"),
    ("acc-bool", "misread input", lambda a: bvpnav.ImuData(a["t"], a["acc_bool"]),
     InputError, r"acc: bool values", r"numbers in m/s\^2"),
    ("acc-complex", "data loss", lambda a: bvpnav.ImuData(a["t"], a["acc_complex"]),
     InputError, r"acc: complex values \(the imaginary part would be lost\)", r"real numbers in m/s\^2"),
    ("acc-object-with-None", "traceback", lambda a: bvpnav.ImuData(a["t"], a["acc_object"]),
     InputError, r"acc: an object array \(entry 3 is None", r"plain numbers in m/s\^2"),
    ("acc-text", "misread input", lambda a: bvpnav.ImuData(a["t"], a["acc_text"]),
     InputError, r"acc: cannot be read as numbers: text values", r"pass numbers in m/s\^2"),
    ("axes-vx-beside-x", "data loss", lambda a: _imu(a, axes=("x", "vx")),
     InputError, r"axis 'vx' would write the column 'vx'.*axis 'x'", r"rename that axis"),
    ("axes-t", "data loss", lambda a: bvpnav.ImuData(a["t"], a["acc1"], axes=("t",)),
     InputError, r"axis 't' would write the column 't', which is already the time column",
     r"rename that axis"),
    ("axes-empty-name", "data loss", lambda a: _imu(a, axes=("x", "")),
     InputError, r"axis name '' is empty", r"rename that axis"),
    ("item-axes-empty-list", "misread input", lambda a: Position(t=0.0, value=0.0, axes=[]),
     InputError, r"Position: axes=\[\] names no axis", r"omit axes= for every axis"),
    ("value-per-instant-or-per-axis", "misread input",
     lambda a: _solve(_imu(a), Position(t=[0.0, 10.0], value=a["value2"])),
     InputError, r"Position \(t=\[0, 10\] s, value=\[0, 10\] m\): value: .*one per instant or one per axis",
     r"\[\[0\.0, 0\.0\], \[10\.0, 10\.0\]\] for one value per instant.*\[\[0\.0, 10\.0\], \[0\.0, 10\.0\]\] "
     r"for one value per axis"),
    ("sigma-shorter-than-rows", "misread input",
     lambda a: _solve(bvpnav.ImuData(a["t"], a["acc1"]),
                      Position(t=[0.0, 5.0, 10.0], value=0.0, sigma=[0.1, 0.2])),
     InputError, r"Position \(t=\[0, 5, 10\] s.*\): sigma: shape \(2,\) does not fit 3 instant\(s\) x 1 axis",
     r"3 value\(s\) \(one per instant\).*nothing is repeated"),
    ("sigma-per-instant-or-per-axis", "misread input",
     lambda a: _solve(_imu(a), Velocity(t=[0.0, 10.0], value=0.0, sigma=[0.1, 0.2], name="v ends")),
     InputError, r"v ends: sigma: \[0\.1, 0\.2\] has 2 entries for 2 instants on 2 axes",
     r"\[\[0\.1, 0\.1\], \[0\.2, 0\.2\]\] for one value per instant"),
    ("tol-wrong-length", "misread input",
     lambda a: _solve(_imu(a), Position(t=[0.0, 10.0], value=0.0, name="ends"),
                      AverageVelocity(t0=[1.0, 4.0, 6.0], t1=[2.0, 5.0, 7.0], value=0.0, mode="band",
                                      tol=[0.1, 0.2, 0.3, 0.4, 0.5], name="stopwatch")),
     InputError, r"stopwatch: tol: shape \(5,\) does not fit 3 instant\(s\) x 2 axis", r"shape \(3, 2\)"),
    ("item-value-bool", "misread input", lambda a: Position(t=0.0, value=True, name="p"),
     InputError, r"p: value: bool values", r"give numbers"),
    ("item-value-complex", "data loss", lambda a: Velocity(t=0.0, value=1 + 2j, name="v"),
     InputError, r"v: value: complex values", r"real numbers"),
    ("item-t-datetime", "misread input", lambda a: Position(t=a["t_dt"][:2], value=0.0, name="p"),
     InputError, r"p: t: datetime values", r"to_seconds"),
    ("sigma-bool", "misread input", lambda a: Position(t=0.0, value=0.0, sigma=True, name="p"),
     InputError, r"p: sigma: bool values", r"give numbers"),
    # round 2 (issue 14 "Trust"), F4-F6, F8
    ("F4-acc-DataFrame-by-position", "misread input",
     lambda a: bvpnav.ImuData(a["t"], pd.DataFrame({"acc_y": a["acc1"], "acc_x": 2 * a["acc1"]})),
     InputError, r"acc: a DataFrame with columns \['acc_y', 'acc_x'\].*taken by position",
     r"ImuData\.from_dataframe.*to_numpy\(\) with axes="),
    ("F4-acc-named-Series", "misread input",
     lambda a: bvpnav.ImuData(a["t"], pd.Series(a["acc1"], name="acc_y")),
     InputError, r"acc: a Series named 'acc_y'", r"ImuData\.from_dataframe"),
    ("F5-acc-masked-entry", "misread input",
     lambda a: bvpnav.ImuData(a["t"], np.ma.masked_array(a["acc1"], mask=np.arange(N) == 4)),
     InputError, r"acc: a masked array with 1 masked entry \(first: index 4\)",
     r"never fills gaps: remove those samples"),
    ("F5-t-masked-entry", "misread input",
     lambda a: bvpnav.ImuData(np.ma.masked_array(a["t"], mask=np.arange(N) >= 9), a["acc1"]),
     InputError, r"time: a masked array with 2 masked entries \(first: index 9\)", r"remove those samples"),
    ("F5-item-value-masked", "misread input",
     lambda a: Position(t=[0.0, 10.0], value=np.ma.masked_array([0.0, 1.0], mask=[False, True]), name="p"),
     InputError, r"p: value: a masked array with 1 masked entry \(first: index 1\)", r"remove those samples"),
    ("F6-t-float32-quantised", "misread input",
     lambda a: bvpnav.ImuData((50000.0 + 0.01 * np.arange(N)).astype(np.float32), a["acc1"]),
     InputError, r"time: times stored as float32 resolve only 0\.0039\d* at 50000",
     r"store the times as float64, or as integers with time_unit"),
    ("F8-axis-trailing-space", "misread input", lambda a: _imu(a, axes=("x ", "y")),
     InputError, r"axis name 'x ' has leading/trailing whitespace", r"rename that axis"),
    ("F8-axis-control-char", "misread input", lambda a: _imu(a, axes=("x", "y\t")),
     InputError, r"axis name 'y\\t' has leading/trailing whitespace or control characters",
     r"rename that axis"),
    ("F24-add-two-items-one-name", "vague message",
     lambda a: bvpnav.NavigationProblem(_imu(a)).add(Position(t=0.0, value=0.0, name="ends"),
                                                     Velocity(t=0.0, value=0.0, name="ends")),
     InputError, r"add\(\): an item named 'ends' is already in the problem", r"rename one of them"),
    ("conflict-names-unnamed-items", "vague message",
     lambda a: _solve(bvpnav.ImuData(a["t"], a["acc1"]), Position(t=[0.0, 10.0], value=0.0),
                      Position(t=[0.0], value=[3.0])),
     Infeasible, r"These hard items conflict: \[.*'Position#2 \(t=\[0\] s, value=\[3\] m\)'",
     r"Soften one of them"),
]


@pytest.mark.parametrize("call, exc, culprit, fix", [pytest.param(*c[2:], id=c[0]) for c in API_CASES])
def test_api_refuses_by_name(call, exc, culprit, fix):
    arrays = _caller_arrays()
    before = {k: (np.array(v, dtype=object, copy=True) if not isinstance(v, np.ndarray) else v.copy())
              for k, v in arrays.items()}
    raises_named(exc, lambda: call(arrays), culprit, fix)
    for k, v in arrays.items():
        arr = np.asarray(v)
        assert np.array_equal(np.asarray(before[k], dtype=arr.dtype), arr), f"{k} was modified"
        if isinstance(v, np.ndarray):
            assert v.flags.writeable, f"{k} was made read-only"


def test_api_arrays_are_copied_not_frozen_or_kept():
    """Data loss on main: ImuData/TimeGrid froze and kept the caller's own arrays."""
    t, acc, value = T.copy(), ACC2.copy(), np.array([[0.0, 0.0], [1.0, 2.0]])
    data = bvpnav.ImuData(t, acc)
    grid = TimeGrid(t)
    item = Position(t=np.array([0.0, 10.0]), value=value)
    assert t.flags.writeable and acc.flags.writeable and value.flags.writeable
    t[0], acc[0, 0], value[1, 1] = -1.0, 99.0, 99.0  # the caller edits its own arrays afterwards
    assert data.t[0] == 0.0 and grid.t[0] == 0.0 and data.acc[0, 0] == ACC2[0, 0]
    assert item.value[1, 1] == 2.0
    assert not data.acc.flags.writeable and not data.t.flags.writeable  # the copies are frozen


def test_to_seconds_is_the_stated_conversion():
    """The conversion the messages give: seconds from the first sample, origin stated, and
    integer nanoseconds subtracted before the float conversion (1 ns kept at 1.8e18 ns)."""
    t, origin = to_seconds(STAMPS)
    assert origin == "2026-01-31T12:00:00" and np.array_equal(t, np.arange(N, dtype=float))
    ns, origin = to_seconds(NS_EPOCH + 1, unit="ns")
    assert origin == "1769860800000000001 ns" and np.array_equal(ns, np.arange(N, dtype=float))
    fine, _ = to_seconds(np.array([NS_EPOCH[0], NS_EPOCH[0] + 1, NS_EPOCH[0] + 3]), unit="ns")
    assert np.max(np.abs(fine - [0.0, 1e-9, 3e-9])) < 1e-15  # float64 at 1.8e18 ns steps by 256 ns
    data = bvpnav.ImuData(t, ACC1, time_origin=origin)
    assert data.time_origin == origin


# -------------------------------------------------------------- files: helpers
@pytest.fixture()
def sample(tmp_path):
    d = tmp_path / "sample"
    write_sample("shuttle", d, rate=5.0)
    return d


def _plain_spec(sample: Path, folder: Path, extra_input: str = "") -> Path:
    """The shuttle spec without the explicit column map (axes from the acc_<axis> names)."""
    text = (sample / "spec.toml").read_text().replace('columns = { x = "acc_x" }\n', extra_input)
    p = folder / "plain.toml"
    p.write_text(text)
    return p


def _xlsx_bytes() -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("[Content_Types].xml", "<Types/>")
        z.writestr("xl/workbook.xml", "<workbook/>")
    return buf.getvalue()


def _parquet_bytes(df: pd.DataFrame, index: bool = False) -> bytes:
    buf = io.BytesIO()
    df.to_parquet(buf, index=index)
    return buf.getvalue()


def _csv_of(sample: Path) -> pd.DataFrame:
    return pd.read_csv(sample / "recording.csv")


def _rows(sample: Path, n: int = 6) -> str:
    return "\n".join((sample / "recording.csv").read_text().splitlines()[1:n + 1]) + "\n"


# Each builder writes the hostile recording into ``folder`` and returns (path, [input] table,
# spec path or None = the sample's spec). The [input] table is what the spec would give.
def _zip_as_csv(sample, folder):
    p = folder / "rec.csv"
    p.write_bytes(_xlsx_bytes())
    return p, {}, None


def _xls_as_csv(sample, folder):
    p = folder / "rec.csv"
    p.write_bytes(b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + b"\x00" * 504)
    return p, {}, None


def _utf16_csv(sample, folder):
    p = folder / "rec.csv"
    p.write_bytes((sample / "recording.csv").read_text().encode("utf-16"))
    return p, {}, None


def _parquet_as_csv(sample, folder):
    p = folder / "rec.csv"
    p.write_bytes(_parquet_bytes(_csv_of(sample)))
    return p, {}, None


def _csv_as_parquet(sample, folder):
    p = folder / "rec.parquet"
    p.write_bytes((sample / "recording.csv").read_bytes())
    return p, {}, None


def _preamble(mark):
    def build(sample, folder):
        p = folder / "rec.csv"
        p.write_text(f"{mark} logger v2, 2026-01-31\n{mark} units: s, m/s^2\n"
                     + (sample / "recording.csv").read_text())
        return p, {}, None
    return build


def _decimal_commas(sample, folder):
    df = _csv_of(sample)
    p = folder / "rec.csv"
    p.write_text(df.to_csv(sep=";", decimal=",", index=False))
    return p, {}, None


def _iso_without_unit(sample, folder):
    df = _csv_of(sample)
    df["t"] = (pd.Timestamp("2026-01-31T12:00:00Z") + pd.to_timedelta(df["t"], unit="s")).map(
        lambda s: s.isoformat())
    p = folder / "rec.csv"
    df.to_csv(p, index=False)
    return p, {}, None


def _iso_bad_cell(sample, folder):
    p, _, _ = _iso_without_unit(sample, folder)
    lines = p.read_text().splitlines()
    lines[3] = "noon," + lines[3].split(",", 1)[1]
    p.write_text("\n".join(lines) + "\n")
    spec = folder / "iso.toml"
    spec.write_text((sample / "spec.toml").read_text().replace('time_unit = "s"', 'time_unit = "iso8601"'))
    return p, {"time_unit": "iso8601"}, spec


def _ns_epoch(sample, folder):
    df = _csv_of(sample)
    df["t"] = NS_EPOCH[0] + np.round(df["t"].to_numpy() * 1e9).astype(np.int64)
    p = folder / "rec.csv"
    df.to_csv(p, index=False)
    spec = folder / "ns.toml"
    spec.write_text((sample / "spec.toml").read_text().replace('time_unit = "s"', 'time_unit = "ns"'))
    return p, {"time_unit": "ns"}, spec


def _parquet_index_other_name(sample, folder):
    df = _csv_of(sample).set_index("t")
    df.index.name = "time"
    p = folder / "rec.parquet"
    p.write_bytes(_parquet_bytes(df, index=True))
    return p, {}, None


def _parquet_datetime_column(sample, folder):
    df = _csv_of(sample)
    df["t"] = pd.Timestamp("2026-01-31T12:00:00") + pd.to_timedelta(df["t"], unit="s")
    p = folder / "rec.parquet"
    p.write_bytes(_parquet_bytes(df))
    return p, {}, None


def _header(new_header: str, plain: bool = True):
    def build(sample, folder):
        p = folder / "rec.csv"
        body = _rows(sample)
        ncol = len(new_header.split(","))
        body = "".join(",".join([ln.split(",")[0]] + [ln.split(",")[1]] * (ncol - 1)) + "\n"
                       for ln in body.splitlines())
        p.write_text(new_header + "\n" + body)
        return p, {}, (_plain_spec(sample, folder) if plain else None)
    return build


def _mapped_axis_t(sample, folder):
    spec = _plain_spec(sample, folder, 'columns = { t = "acc_x" }\n')
    p = folder / "rec.csv"
    p.write_bytes((sample / "recording.csv").read_bytes())
    return p, {"columns": {"t": "acc_x"}}, spec


def _mapped(columns: str, table: dict):
    def build(sample, folder):
        spec = _plain_spec(sample, folder, f"columns = {columns}\n")
        p = folder / "rec.csv"
        p.write_bytes((sample / "recording.csv").read_bytes())
        return p, {"columns": table}, spec
    return build


def _blank_line(sample, folder):
    lines = (sample / "recording.csv").read_text().splitlines()
    p = folder / "rec.csv"
    p.write_text("\n".join(lines[:3] + [""] + lines[3:8]) + "\n")  # blank line 4; data row 4 on line 5
    return p, {}, None


def _nan_after_blank_lines(sample, folder):
    p = folder / "rec.csv"
    p.write_text("t,acc_x\n0,1\n0.2,2\n0.4,nan\n0.6,1\n\n\n")  # trailing blank lines: accepted
    return p, {}, None


def _extra_field(sample, folder):
    lines = (sample / "recording.csv").read_text().splitlines()
    p = folder / "rec.csv"
    p.write_text("\n".join([lines[0]] + [ln + ",0.5" for ln in lines[1:8]]) + "\n")
    return p, {}, None


def _extra_field_one_row(sample, folder):
    lines = (sample / "recording.csv").read_text().splitlines()
    lines[4] += ",0.5"
    p = folder / "rec.csv"
    p.write_text("\n".join(lines[:8]) + "\n")
    return p, {}, None


def _parquet_float32_times(sample, folder):
    df = _csv_of(sample).iloc[:20]
    df = df.assign(t=(50000.0 + df["t"]).astype(np.float32))
    p = folder / "rec.parquet"
    p.write_bytes(_parquet_bytes(df))
    return p, {}, None


#: (id, kind, build, culprit, fix); the culprit is matched in the reader's message and the
#: CLI's stderr alike.
FILE_CASES = [
    ("xlsx-renamed-csv", "misread input", _zip_as_csv, r"rec\.csv'?: this \.csv file is a ZIP archive",
     r"export the sheet as CSV"),
    ("xls-renamed-csv", "misread input", _xls_as_csv, r"rec\.csv'?: this \.csv file is a legacy Excel \.xls",
     r"export the sheet as CSV"),
    ("utf16-csv", "vague message", _utf16_csv, r"rec\.csv'?: this \.csv file is UTF-16 text",
     r"save it as UTF-8"),
    ("parquet-renamed-csv", "vague message", _parquet_as_csv,
     r"rec\.csv'?: this \.csv file is a Parquet file", r"rename it to \.parquet"),
    ("csv-renamed-parquet", "vague message", _csv_as_parquet,
     r"rec\.parquet'?: this \.parquet file is text \('t,acc_x", r"rename it to \.csv"),
    ("comment-preamble-hash", "vague message", _preamble("#"),
     r"rec\.csv'?: lines 1-2 are a comment preamble \('# logger v2", r"delete those lines"),
    ("comment-preamble-percent", "vague message", _preamble("%"),
     r"rec\.csv'?: lines 1-2 are a comment preamble \('% logger", r"header \(e\.g\. t,acc_x\) is line 1"),
    ("decimal-commas", "vague message", _decimal_commas,
     r"rec\.csv'?: fields separated by ';' with decimal commas \(line 2: '0,0;-1,41",
     r"',' between fields and '\.' decimals"),
    ("iso-timestamps-without-unit", "vague message", _iso_without_unit,
     r"row 0 \(line 2\), column 't' is the timestamp '2026-01-31T12:00:00\+00:00'",
     r'time_unit = "iso8601".*data\.time_origin'),
    ("iso-timestamp-bad-cell", "vague message", _iso_bad_cell,
     r"row 2 \(line 4\), column 't' is 'noon', not an ISO 8601 timestamp", r"fix or remove that row"),
    ("int-ns-epoch", "data loss", _ns_epoch,
     r"column 't' holds integer times up to 1769860820000000000 ns \(an epoch\?\)",
     r'add time_origin = "first"'),
    ("parquet-time-index-other-name", "misread input", _parquet_index_other_name,
     r"time column 't' not found; the file's index is named 'time'", r'set time = "time"'),
    ("parquet-datetime-column", "misread input", _parquet_datetime_column,
     r"column 't' holds datetime64\[\w+\] values, not numbers in s", r'time_unit = "iso8601"'),
    ("empty-header-cell", "misread input", _header("t,acc_x,"),
     r"rec\.csv'?: header cell 3 \(line 1\) is empty", r"name every column"),
    ("duplicate-header", "data loss", _header("t,acc_x,acc_x"),
     r"rec\.csv'?: header line 1 names column 'acc_x' twice \(columns 2 and 3\)",
     r"give every column its own name"),
    ("acc_vx-beside-acc_x", "data loss", _header("t,acc_x,acc_vx"),
     r"axis 'vx' would write the column 'vx'.*axis 'x'", r"rename the column"),
    ("acc_t", "data loss", _header("t,acc_t"),
     r"axis 't' would write the column 't', which is already the time column", r"rename the column"),
    ("acc_-empty-axis", "data loss", _header("t,acc_"), r"axis name '' is empty", r"rename the column"),
    ("columns-map-axis-t", "data loss", _mapped_axis_t,
     r"columns = \{'t': 'acc_x'\}: axis 't' would write the column 't'", r"choose other axis names"),
    # round 2 (issue 14 "Trust"), F6-F10
    ("F6-parquet-float32-times", "misread input", _parquet_float32_times,
     r"rec\.parquet: column 't': times stored as float32 resolve only 0\.0039",
     r"store the times as float64, or as integers with time_unit"),
    ("F7-one-column-two-axes", "misread input",
     _mapped('{ x = "acc_x", y = "acc_x" }', {"x": "acc_x", "y": "acc_x"}),
     r"column 'acc_x' is mapped to axis 'y' but is already axis 'x'", r"map each axis to its own column"),
    ("F7-time-column-as-axis", "misread input", _mapped('{ x = "t" }', {"x": "t"}),
     r"column 't' is mapped to axis 'x' but is already the time column", r"map each axis to its own column"),
    ("F8-header-trailing-space", "misread input", _header("t,acc_x "),
     r"rec\.csv'?: header cell 2 \(line 1\) is 'acc_x ', with leading/trailing whitespace",
     r"Remove the spaces around the header names"),
    ("F8-padded-beside-plain", "misread input", _header("t,acc_x,acc_x "),
     r"header cell 3 \(line 1\) is 'acc_x '", r"Remove the spaces"),
    ("F8-header-leading-space", "misread input", _header("t, acc_x"),
     r"header cell 2 \(line 1\) is ' acc_x'", r"Remove the spaces"),
    ("F9-blank-line-between-rows", "misread input", _blank_line,
     r"rec\.csv'?: line 4 is blank, between data rows", r"delete the blank line\(s\)"),
    ("F9-line-number-after-trailing-blanks", "misread input", _nan_after_blank_lines,
     r"rec\.csv: row 2 \(line 4\), column 'acc_x' is empty or NaN", r"fix or remove those rows"),
    ("F10-every-row-one-field-more", "misread input", _extra_field,
     r"rec\.csv'?: row 0 \(line 2\) has 3 fields but the header \(line 1\) has 2",
     r"remove the extra field\(s\)"),
    ("F10-one-row-one-field-more", "misread input", _extra_field_one_row,
     r"rec\.csv'?: row 3 \(line 5\) has 3 fields but the header \(line 1\) has 2", r"remove the extra"),
]


@pytest.mark.parametrize("build, culprit, fix", [pytest.param(*c[2:], id=c[0]) for c in FILE_CASES])
def test_reader_says_what_the_file_is(sample, tmp_path, build, culprit, fix):
    folder = tmp_path / "in"
    folder.mkdir()
    path, inp, spec = build(sample, folder)
    before = snapshot(folder, sample)
    raises_named(InputError, lambda: read_recording(path, inp), culprit, fix)
    assert_unchanged(before)


#: The cases also run through ``bvpnav solve`` (``bvpnav.cli.main`` in this process: exit 2, no
#: traceback, no output written).
CLI_IDS = ["xlsx-renamed-csv", "comment-preamble-hash", "decimal-commas", "iso-timestamps-without-unit",
           "int-ns-epoch", "parquet-time-index-other-name", "duplicate-header", "acc_vx-beside-acc_x",
           "F7-one-column-two-axes", "F8-header-trailing-space", "F9-blank-line-between-rows",
           "F10-every-row-one-field-more"]


@pytest.mark.parametrize("build, culprit, fix", [pytest.param(*c[2:], id=c[0]) for c in FILE_CASES
                                                 if c[0] in CLI_IDS])
def test_cli_says_what_the_file_is(sample, tmp_path, build, culprit, fix):
    folder = tmp_path / "in"
    folder.mkdir()
    path, _, spec = build(sample, folder)
    out = tmp_path / "out"
    out.mkdir()
    (out / "earlier.csv").write_text("t,x\n0,0\n")  # an earlier output
    before = snapshot(folder, sample, out)
    proc = main_cli(["solve", path, "--spec", spec or sample / "spec.toml", "--out", out / "traj.csv"])
    assert_clean_failure(proc, EXIT_INPUT, culprit, fix)
    assert_unchanged(before)
    assert sorted(p.name for p in out.iterdir()) == ["earlier.csv"]


# ---------------------------------------------------------------- hangs
def _fifo(folder: Path, name: str) -> Path:
    p = folder / name
    os.mkfifo(p)
    return p


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs (POSIX)")
@pytest.mark.parametrize("which", ["recording", "spec"])
def test_fifo_is_refused_without_hanging(sample, tmp_path, which):
    """A FIFO nobody writes to blocks open() forever: the run must end (timeout 60 s, it
    takes a few seconds) with exit 2 naming the path, and leave the FIFO in place."""
    rec, spec = sample / "recording.csv", sample / "spec.toml"
    if which == "recording":
        rec = _fifo(tmp_path, "rec.csv")
        culprit = r"recording '[^']*rec\.csv' is a FIFO \(named pipe\), not a regular file"
    else:
        spec = _fifo(tmp_path, "spec.toml")
        culprit = r"spec '[^']*spec\.toml' is a FIFO \(named pipe\), not a regular file"
    before = snapshot(sample)
    proc = run_cli(["solve", rec, "--spec", spec, "--out", tmp_path / "traj.csv"], timeout=60)
    assert_clean_failure(proc, EXIT_INPUT, culprit, r"save it to a file and give that path")
    assert_unchanged(before)
    fifo = rec if which == "recording" else spec
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and not (tmp_path / "traj.csv").exists()


@pytest.mark.parametrize("which", ["folder-as-spec", "dev-stdin-as-recording", "dev-stdin-as-spec"])
def test_non_regular_paths_are_refused(sample, tmp_path, which):
    rec, spec = sample / "recording.csv", sample / "spec.toml"
    if which == "folder-as-spec":
        spec = tmp_path / "specs"
        spec.mkdir()
        culprit = r"spec '[^']*specs' is a folder, not a regular file"
    elif which == "dev-stdin-as-recording":
        rec = Path("/dev/stdin")  # run_cli gives the subprocess /dev/null as stdin: a character device
        culprit = r"recording '/dev/stdin' is a character device"
    else:
        spec = Path("/dev/stdin")
        culprit = r"spec '/dev/stdin' is a character device"
    before = snapshot(sample)
    proc = run_cli(["solve", rec, "--spec", spec, "--out", tmp_path / "traj.csv"], timeout=60)
    assert_clean_failure(proc, EXIT_INPUT, culprit, r"regular file")
    assert_unchanged(before)


def test_fifo_reader_api_returns_at_once(tmp_path):
    """The same through the Python API: InputError, not a blocked open()."""
    if not hasattr(os, "mkfifo"):
        pytest.skip("needs FIFOs (POSIX)")
    rec = _fifo(tmp_path, "rec.csv")
    raises_named(InputError, lambda: read_recording(rec), r"rec\.csv' is a FIFO", r"save it to a file")
    raises_named(InputError, lambda: load_spec(_fifo(tmp_path, "s.toml")), r"s\.toml' is a FIFO",
                 r"regular file")


# ---------------------------------------------------------------- specs
SPEC_CASES = [
    ("spec-time-origin-unknown", '[input]\ntime_origin = "last"\n',
     r"bad\.toml, line 2: time_origin='last'", r'the only choice is "first"'),
    ("spec-time-unit-unknown", '[input]\ntime_unit = "iso"\n',
     r"bad\.toml, line 2: time_unit='iso'", r'"iso8601" for timestamps'),
    ("spec-item-value-bool", '[[item]]\ntype = "position"\nname = "p"\nt = 0.0\nvalue = true\n',
     r"bad\.toml, line 1: p: value: bool values", r"give numbers"),
    ("spec-item-times-text", '[[item]]\ntype = "position"\nname = "p"\nt = ["0", "1"]\n',
     r"bad\.toml, line 1: p: t: cannot be read as numbers: text values", r"pass numbers in s"),
    ("spec-item-time-toml-datetime", '[[item]]\ntype = "position"\nname = "p"\nt = 2026-01-31T12:00:00Z\n',
     r"bad\.toml, line 4: item 'position': t holds a TOML date/time", r"write e\.g\. t = 12\.5"),
    ("spec-item-axes-empty", '[[item]]\ntype = "velocity"\nname = "v"\nt = 0.0\naxes = []\n',
     r"bad\.toml, line 1: v: axes=\[\] names no axis", r"omit axes="),
    # round 2 (issue 14 "Trust"), F12, F16, F24
    ("F12-priority-with-raise", '[solve]\non_conflict = "raise"\npriority = { ends = 2 }\n',
     r"bad\.toml, line 3: priority is set but on_conflict is 'raise'", r'add on_conflict = "demote"'),
    ("F16-nested-10000-deep", "[problem]\nsigma_a = " + "[" * 10000 + "]" * 10000 + "\n",
     r"bad\.toml: values nested too deeply to read", r"fix that value"),
    ("F24-two-items-one-name", '[[item]]\ntype = "position"\nname = "ends"\nt = 0.0\n\n'
     '[[item]]\ntype = "velocity"\nname = "ends"\nt = 1.0\n',
     r"bad\.toml: the \[\[item\]\] tables at lines 1 and 6 are both named 'ends'", r"rename one of them"),
]


@pytest.mark.parametrize("text, culprit, fix", [pytest.param(*c[1:], id=c[0]) for c in SPEC_CASES])
def test_spec_values_are_refused_by_line(tmp_path, text, culprit, fix):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    before = snapshot(p)
    raises_named(InputError, lambda: load_spec(p), culprit, fix)
    assert_unchanged(before)


# ------------------------------------------------- accepted on purpose (say why)
def test_utf8_bom_is_accepted_in_spec_and_csv(sample, tmp_path):
    """A UTF-8 byte-order mark is an encoding marker some editors write, not data: the spec
    and the recording read exactly as without it (main gave vague errors)."""
    spec_b, rec_b = tmp_path / "bom.toml", tmp_path / "bom.csv"
    spec_b.write_bytes(b"\xef\xbb\xbf" + (sample / "spec.toml").read_bytes())
    rec_b.write_bytes(b"\xef\xbb\xbf" + (sample / "recording.csv").read_bytes())
    before = snapshot(tmp_path)
    plain = load_spec(sample / "spec.toml")
    spec = load_spec(spec_b)
    assert spec.input == plain.input and [i.params() for i in spec.items] == [i.params() for i in plain.items]
    a, b = read_recording(sample / "recording.csv", plain.input), read_recording(rec_b, spec.input)
    assert np.array_equal(a.t, b.t) and np.array_equal(a.acc, b.acc) and a.axes == b.axes == ("x",)
    assert_unchanged(before)


def test_iso8601_and_epoch_times_convert_when_the_spec_says_so(sample, tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    ref = read_recording(sample / "recording.csv")
    iso, _, _ = _iso_without_unit(sample, folder)
    data = read_recording(iso, {"time_unit": "iso8601"})
    assert data.time_origin == "2026-01-31T12:00:00+00:00"
    assert np.max(np.abs(data.t - ref.t)) < 1e-6  # the timestamps carry microseconds
    ns, _, _ = _ns_epoch(sample, folder)
    data = read_recording(ns, {"time_unit": "ns", "time_origin": "first"})
    assert data.time_origin == f"{NS_EPOCH[0]} ns"
    assert np.max(np.abs(data.t - ref.t)) < 1e-9
    pq = folder / "indexed.parquet"
    pq.write_bytes(_parquet_bytes(_csv_of(sample).set_index("t"), index=True))
    data = read_recording(pq)  # the index carries the time column's name: used
    assert np.array_equal(data.t, ref.t) and np.array_equal(data.acc, ref.acc)


# --------------------------------------------------- spec writer round trip
names = st.text(min_size=1, max_size=12).filter(lambda s: s.strip())


@settings(max_examples=150, deadline=None, database=None)
@given(name=names, kind=st.sampled_from(sorted(registry())))
def test_to_spec_round_trips_any_name_and_every_item(name, kind):
    """bvpnav.spec.to_spec(problem) is valid TOML for any item name (spaces, quotes, backslashes,
    control characters, non-ASCII) and gives every registered item's example() back."""
    data = bvpnav.ImuData(T, np.column_stack([ACC1, ACC1, ACC1]), axes=("x", "y", "z"))
    item = registry()[kind].example()
    fields = {**item.params(), "name": name}
    named = type(item)(**fields)
    prob = bvpnav.NavigationProblem(data).add(named)
    text = to_spec(prob, solve={"on_conflict": "demote", "priority": {name: 2.0},
                                "demote_sigma": {name: 0.5}})
    spec = parse_spec(text, "written.toml")
    assert spec.solve["priority"] == {name: 2.0} and spec.solve["demote_sigma"] == {name: 0.5}
    (back,) = spec.items
    assert type(back) is type(named) and back.name == name
    for key, v in named.params().items():
        assert np.array_equal(np.asarray(back.params()[key], dtype=object), np.asarray(v, dtype=object)), key


# ------------------------------------------- round 2: huge files are refused unread
_LIMITED = """
import resource, sys
resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))  # a regression fails, not eats memory
from bvpnav.errors import InputError
from bvpnav.readers import read_recording
from bvpnav.spec import load_spec
try:
    load_spec(sys.argv[2]) if sys.argv[1] == "spec" else read_recording(sys.argv[2])
except InputError as exc:
    print(exc, file=sys.stderr)
    sys.exit(2)
sys.exit(0)
"""


@pytest.mark.parametrize("which, name, culprit, fix", [
    pytest.param("spec", "big.toml",
                 r"spec '.*big\.toml' is 42,949,672,960 bytes, beyond the 10,485,760-byte",
                 r"A spec is a small text file", id="F17-40GB-sparse-spec"),
    pytest.param("recording", "r.csv", r"r\.csv'?: this \.csv file is binary data \(NUL bytes\)",
                 r"give a CSV text file", id="F21-40GB-sparse-recording"),
])
def test_huge_sparse_file_is_refused_before_it_is_read(tmp_path, which, name, culprit, fix):
    """A 40 GB sparse file: refused from its size or its first bytes, in a process whose
    address space is capped at 3 GB (reading it whole would fail with MemoryError there).
    Byte-identity of 40 GB cannot be hashed in a test: its size and mtime are checked, and
    its first MiB is all NUL still."""
    big = tmp_path / name
    with open(big, "wb") as fh:
        fh.truncate(40 << 30)
    st = big.stat()
    proc = subprocess.run([sys.executable, "-c", _LIMITED, which, str(big)], capture_output=True,
                          text=True, timeout=120)
    assert_clean_failure(proc, EXIT_INPUT, culprit, fix)  # InputError, not MemoryError
    after = big.stat()
    assert (after.st_size, after.st_mtime_ns, after.st_mode) == (st.st_size, st.st_mtime_ns, st.st_mode)
    with open(big, "rb") as fh:
        assert fh.read(1 << 20) == bytes(1 << 20)


# ------------------------------------------- round 2: accepted on purpose (say why)
def test_unmasked_masked_array_and_fine_float32_times_are_accepted():
    """A masked array with nothing masked is plain data; float32 times whose resolution is
    far below the step (0..10 s at 1 s: spacing 1e-6 s) lose nothing."""
    data = bvpnav.ImuData(T.astype(np.float32), np.ma.masked_array(ACC1.copy()))
    assert np.array_equal(data.t, T) and np.array_equal(data.acc[:, 0], ACC1)


def test_from_dataframe_takes_axes_from_the_names():
    """The fix the DataFrame refusal points to: axes follow the column names, not positions."""
    df = pd.DataFrame({"t": T, "ay": ACC1, "ax": 2 * ACC1})
    data = bvpnav.ImuData.from_dataframe(df)
    assert data.axes == ("y", "x")
    assert np.array_equal(data.acc[:, 1], 2 * ACC1)


@pytest.mark.parametrize("edit, culprit, fix", [
    pytest.param(("sigma_a = 1.0", "sigma_a = [1.0, 2.0, 3.0]"),
                 r"bad\.toml, line 12: sigma_a: shape \(3,\) for 101 samples on the axes \['x'\]",
                 r"one per axis",
                 id="spec-sigma_a-per-axis-count"),
    pytest.param(("lam = 1.0", 'lam = 1.0\non_conflict = "demote"\npriority = { nosuch = 1 }'),
                 r"bad\.toml, line 19: priority names unknown item\(s\) \['nosuch'\]",
                 r"the problem's items are \['ends'.*use one of these names",
                 id="spec-priority-unknown-item"),
])
def test_spec_errors_found_with_the_data_name_the_line(sample, tmp_path, edit, culprit, fix):
    """Round 2: errors that need the data (axes, item labels) still name the spec line."""
    spec = tmp_path / "bad.toml"
    text = (sample / "spec.toml").read_text()
    assert edit[0] in text
    spec.write_text(text.replace(edit[0], edit[1], 1))
    out = tmp_path / "out"
    out.mkdir()
    (out / "earlier.csv").write_text("t,x\n0,0\n")
    before = snapshot(sample, spec, out)
    proc = main_cli(["solve", sample / "recording.csv", "--spec", spec, "--out", out / "traj.csv"])
    assert_clean_failure(proc, EXIT_INPUT, culprit, fix)
    assert_unchanged(before)
    assert sorted(p.name for p in out.iterdir()) == ["earlier.csv"]
