"""Fuzzing the readers: only bvpnav's InputError may escape, never a raw traceback.

Hypothesis feeds the spec reader (mutations of the bundled specs, structured TOML with
values of the wrong types, arbitrary text) and the recording reader (CSV text with
random headers, cells, rows, BOMs and delimiters; Parquet files with random column
types). Every example must give a valid result or :class:`bvpnav.errors.InputError`
(the library's bad-input error, a ``ValueError`` and a ``BvpnavError``); any other
exception fails the test. Valid results are checked for what the readers promise:
finite, strictly increasing times and finite accelerations.
"""

from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import bvpnav
from bvpnav.errors import InputError
from bvpnav.items import registry
from bvpnav.readers import read_recording
from bvpnav.spec import Spec, _toml_value, dumps_spec, error_model_registry, parse_spec

pytestmark = pytest.mark.slow  # hundreds of examples per reader

ROOT = Path(__file__).resolve().parents[1]
SPEC_TEXTS = [p.read_text() for p in sorted((ROOT / "examples" / "specs").glob("*.toml"))]
ITEMS = registry()
MODELS = error_model_registry()
DATA = bvpnav.ImuData(np.linspace(0.0, 20.0, 41), np.zeros(41))  # axis x, window [0, 20] s

FUZZ = dict(deadline=None, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                   HealthCheck.filter_too_much])


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory(prefix="bvpnav-fuzz-") as d:
        yield Path(d)


def check_spec(text: str) -> None:
    """parse_spec then build on a small recording: a Spec/problem, or InputError."""
    try:
        spec = parse_spec(text, "fuzz.toml")
    except InputError:
        return
    assert isinstance(spec, Spec)
    try:
        spec.build(DATA).terms()  # items compiled against a 1-axis recording on [0, 20] s
    except InputError:
        pass


def check_recording(path: Path, inp) -> None:
    try:
        data = read_recording(path, inp)
    except InputError:
        return
    assert isinstance(data, bvpnav.ImuData)
    assert np.all(np.isfinite(data.t)) and np.all(np.diff(data.t) > 0) and data.n >= 3
    assert np.all(np.isfinite(data.acc)) and data.acc.shape == (data.n, data.ndim)


# ------------------------------------------------------------------ values
finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
scalars = st.one_of(
    st.integers(-10**30, 10**30), finite, st.floats(), st.booleans(),
    st.text(st.characters(blacklist_categories=("Cs", "Cc")), max_size=8),
    st.sampled_from(["hard", "soft", "robust", "band", "x", "y", "z", "lcurve", "even", "odd", "position",
                     "velocity", "acc_x", "t"]),
    st.sampled_from([0, -1, 0.0, -0.0, 1e308, -1e308, 20, 20.5, -0.5]),
)
toml_values = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(st.sampled_from(["x", "y", "z", "a", "t"]), inner, max_size=3)),
    max_leaves=8,
)


def line(key: str, value) -> str:
    return f"{key} = {_toml_value(value)}"


@st.composite
def structured_specs(draw) -> str:
    """Sections, keys, items and error models with mostly-right names and random values."""
    keys = {"input": ["time", "time_unit", "columns", "unit"], "problem": ["residual", "sigma_a"],
            "solve": ["solver", "accuracy", "lam", "fallback"]}
    lines = []
    for sec, names in keys.items():
        if draw(st.booleans()):
            lines.append(f"[{sec}]")
            for k in draw(st.lists(st.sampled_from(names), max_size=4, unique=True)):
                lines.append(line(k, draw(toml_values)))
            if draw(st.integers(0, 9)) == 9:
                lines.append(line("bogus", 1))
    for sec, reg in (("item", ITEMS), ("error_model", MODELS)):
        for _ in range(draw(st.integers(0, 2))):
            lines.append(f"[[{sec}]]")
            name = draw(st.one_of(st.sampled_from(sorted(reg)), toml_values))
            if draw(st.integers(0, 9)) < 9:
                lines.append(line("type", name))
            cls = reg.get(name) if isinstance(name, str) else None
            fields = [f.name for f in dataclasses.fields(cls) if f.init] if cls else ["t", "value"]
            for k in draw(st.lists(st.sampled_from(fields), max_size=5, unique=True)):
                lines.append(line(k, draw(toml_values)))
            if draw(st.integers(0, 9)) == 9:
                lines.append(line("bogus", 1))
    return "\n".join(lines) + "\n"


@st.composite
def mutated_specs(draw) -> str:
    """A bundled (or re-written) spec with a few random line-level mutations."""
    text = draw(st.sampled_from(SPEC_TEXTS + [dumps_spec(parse_spec(SPEC_TEXTS[0]))]))
    lines = text.splitlines()
    for _ in range(draw(st.integers(1, 4))):
        if not lines:
            break
        k = draw(st.integers(0, len(lines) - 1))
        op = draw(st.sampled_from(["drop", "dup", "value", "key", "junk", "truncate", "swap"]))
        if op == "drop":
            del lines[k]
        elif op == "dup":
            lines.insert(k, lines[k])
        elif op == "value" and "=" in lines[k]:
            lines[k] = lines[k].split("=", 1)[0] + "= " + _toml_value(draw(toml_values))
        elif op == "key" and "=" in lines[k]:
            lines[k] = draw(st.sampled_from(["t", "t0", "t1", "value", "sigma", "mode", "axes", "type",
                                             "about", "tol", "huber", "name", "columns", "unit"])) \
                + " =" + lines[k].split("=", 1)[1]
        elif op == "junk":
            lines.insert(k, draw(st.text(max_size=20)))
        elif op == "truncate":
            lines[k] = lines[k][: draw(st.integers(0, max(len(lines[k]) - 1, 0)))]
        elif op == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[k], lines[j] = lines[j], lines[k]
    return "\n".join(lines) + "\n"


@settings(max_examples=500, **FUZZ)
@given(text=mutated_specs())
def test_fuzz_spec_mutations(text):
    check_spec(text)


@settings(max_examples=500, **FUZZ)
@given(text=structured_specs())
def test_fuzz_spec_wrong_types(text):
    check_spec(text)


@settings(max_examples=500, **FUZZ)
@given(text=st.one_of(st.text(max_size=200),
                      st.text(alphabet="[]{}=\"'#.,\n xyz012345aeptu_-", max_size=120)))
def test_fuzz_spec_arbitrary_text(text):
    check_spec(text)


# ------------------------------------------------------------------- CSV
cells = st.one_of(
    finite.map(repr), st.integers(-10**6, 10**6).map(str),
    st.sampled_from(["", "nan", "NaN", "inf", "-inf", "1e999", "-1e999", "1e308", "abc", "0x10", " 1 ",
                     "1,5", "\"2\"", "None", "null", "TRUE", "1e-320", "+0.5", "1_000"]),
    st.text(alphabet="0123456789.-+eE,;\"' \tnaif", max_size=6),
)
headers = st.lists(st.sampled_from(["t", "acc_x", "acc_y", "acc_z", "time", "ax", "", "acc_", "t", "x",
                                    "acc_x", "\"acc_y\""]), min_size=1, max_size=5)
inputs = st.one_of(
    st.none(), st.none(), st.none(),
    st.just({"time": "t", "columns": {"x": "acc_x"}}),
    st.fixed_dictionaries({}, optional={
        "time": st.sampled_from(["t", "time", "x", 5]),
        "time_unit": st.sampled_from(["s", "ms", "min", None]),
        "unit": st.sampled_from(["m/s^2", "g", "G", 1.0]),
        "columns": st.one_of(st.dictionaries(st.sampled_from(["x", "y", "z", "w"]),
                                             st.sampled_from(["acc_x", "acc_y", "ax", "t", "nope"]),
                                             max_size=3),
                             st.sampled_from([["acc_x"], "acc_x", 3, {"x": 1}]))}),
)


@st.composite
def csv_files(draw) -> bytes:
    """Mostly nearly-valid recordings (so the row checks are reached) with random defects."""
    if draw(st.integers(0, 3)) < 3:  # (hypothesis favours small draws: keep the nominal case at 0)
        header = ["t", "acc_x"] + (["acc_y"] if draw(st.booleans()) else [])
        if draw(st.integers(0, 4)) == 4:
            header = draw(st.permutations(header))
    else:
        header = draw(headers)
    n_rows = draw(st.sampled_from([5, 3, 8, 4, 2, 0, 1]))
    times = sorted(draw(st.lists(finite, min_size=n_rows, max_size=n_rows)))
    if draw(st.integers(0, 3)) == 3:
        times = draw(st.permutations(times))
    weird = draw(st.sampled_from([0.0, 0.0, 0.05, 0.3]))  # share of defective cells
    ragged = draw(st.integers(0, 5)) == 5
    rows = []
    for k in range(n_rows):
        width = len(header) + (draw(st.sampled_from([-1, 0, 1])) if ragged else 0)
        row = [draw(cells) if draw(st.floats(0, 1)) < weird else repr(draw(finite))
               for _ in range(max(width, 0))]
        if "t" in header and header.index("t") < len(row) and draw(st.integers(0, 5)) < 5:
            row[header.index("t")] = repr(times[k])
        rows.append(row)
    sep = draw(st.sampled_from([",", ",", ",", ",", ",", ";", "\t"]))
    text = "\n".join(sep.join(r) for r in [header, *rows])
    if draw(st.booleans()):
        text += "\n"
    data = text.encode("utf-8")
    if draw(st.integers(0, 4)) == 4:
        data = b"\xef\xbb\xbf" + data
    if draw(st.integers(0, 19)) == 19:
        data = data.replace(b"0", b"\xff", 1)  # not UTF-8
    return data


@settings(max_examples=500, **FUZZ)
@given(body=csv_files(), inp=inputs)
def test_fuzz_csv_reader(folder, body, inp):
    path = folder / "rec.csv"
    path.write_bytes(body)
    check_recording(path, inp)


@settings(max_examples=500, **FUZZ)
@given(body=st.binary(max_size=200), inp=st.sampled_from([None, {"columns": {"x": "acc_x"}}]))
def test_fuzz_csv_reader_arbitrary_bytes(folder, body, inp):
    path = folder / "raw.csv"
    path.write_bytes(b"t,acc_x\n" + body if body[:1] == b"0" else body)
    check_recording(path, inp)


# --------------------------------------------------------------- Parquet
@st.composite
def column(draw, n: int):
    """A random Parquet column of length n: floats (most often), ints, nullable ints, bools,
    strings with nulls, float32, timedeltas."""
    special = st.sampled_from([np.nan, np.inf, -np.inf, 1e308])
    fl = st.one_of(finite, finite, finite, special) if draw(st.booleans()) else finite
    kind = draw(st.sampled_from(["float", "float", "float", "int", "Int64", "bool", "string", "float32",
                                 "timedelta"]))
    if kind == "float":
        return np.array(draw(st.lists(fl, min_size=n, max_size=n)), dtype=float)
    if kind == "int":
        return np.array(draw(st.lists(st.integers(-2**40, 2**40), min_size=n, max_size=n)), dtype=np.int64)
    if kind == "Int64":
        return pd.array(draw(st.lists(st.one_of(st.integers(-100, 100), st.none()), min_size=n, max_size=n)),
                        dtype="Int64")
    if kind == "bool":
        return np.array(draw(st.lists(st.booleans(), min_size=n, max_size=n)), dtype=bool)
    if kind == "string":
        cells = st.one_of(st.sampled_from(["1.5", "x", "", "nan", "inf", "2"]), st.none())
        return pd.array(draw(st.lists(cells, min_size=n, max_size=n)), dtype="string")
    if kind == "float32":
        return np.array(draw(st.lists(st.floats(width=32), min_size=n, max_size=n)), dtype=np.float32)
    secs = draw(st.lists(st.one_of(st.integers(0, 5), st.none()), min_size=n, max_size=n))
    return pd.Series([None if x is None else pd.Timedelta(seconds=x) for x in secs])


@st.composite
def parquet_frames(draw) -> pd.DataFrame:
    n = draw(st.sampled_from([5, 3, 7, 0, 1, 2]))
    names = ["t", "acc_x"] + (["acc_y"] if draw(st.booleans()) else [])
    if draw(st.integers(0, 3)) == 3:
        names = draw(st.lists(st.sampled_from(["t", "acc_x", "acc_y", "ax", "time", "acc_"]), min_size=1,
                              max_size=4, unique=True))
    cols = {c: draw(column(n)) for c in names}
    if "t" in cols and draw(st.integers(0, 3)) < 3:
        cols["t"] = np.sort(draw(st.lists(finite, min_size=n, max_size=n, unique=True))).astype(float)
    return pd.DataFrame(cols)


@settings(max_examples=500, **FUZZ)
@given(df=parquet_frames(), inp=inputs)
def test_fuzz_parquet_reader(folder, df, inp):
    path = folder / "rec.parquet"
    df.to_parquet(path)
    check_recording(path, inp)


# ------------------------------------------------- the one input normalisation
@st.composite
def api_arrays(draw):
    """Arrays of any dtype a caller may hold, as numpy arrays, lists or pandas objects."""
    n = 5
    kind = draw(st.sampled_from(["float", "int", "bool", "complex", "datetime", "timedelta", "object",
                                 "str", "list", "series", "nullable"]))
    if kind == "float":
        return np.array(draw(st.lists(st.floats(), min_size=n, max_size=n)))
    if kind == "int":
        return np.array(draw(st.lists(st.integers(-2**62, 2**62), min_size=n, max_size=n)), dtype=np.int64)
    if kind == "bool":
        return np.array(draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    if kind == "complex":
        return np.array(draw(st.lists(st.complex_numbers(allow_nan=False), min_size=n, max_size=n)),
                        dtype=complex)
    if kind == "datetime":
        freq = draw(st.sampled_from(["1ms", "1s"]))
        return pd.date_range("2026-01-01", periods=n, freq=freq).to_numpy().copy()
    if kind == "timedelta":
        return np.arange(n).astype("timedelta64[s]")
    if kind == "object":
        return np.array(draw(st.lists(st.one_of(st.floats(), st.none(), st.text(max_size=3)), min_size=n,
                                      max_size=n)), dtype=object)
    if kind == "str":
        return np.array([str(float(x)) for x in range(n)])
    if kind == "list":
        return draw(st.lists(st.one_of(st.floats(allow_nan=False), st.integers(-5, 5), st.booleans()),
                             min_size=n, max_size=n))
    if kind == "series":
        return pd.Series(np.arange(n, dtype=float) * draw(st.floats(0.1, 10.0)))
    return pd.array([1.0, None, 2.0, 3.0, 4.0] if draw(st.booleans()) else [0.0, 1.0, 2.0, 3.0, 4.0],
                    dtype="Float64")


@settings(max_examples=300, **FUZZ)
@given(t=api_arrays(), acc=api_arrays())
def test_fuzz_imudata_normalisation(t, acc):
    """ImuData takes any caller array: a valid result is exactly the float64 reading of
    plain numbers, anything else is InputError; the caller's arrays are never changed,
    frozen or kept."""
    keep = [x.copy() if isinstance(x, np.ndarray) else x for x in (t, acc)]
    try:
        data = bvpnav.ImuData(t, acc)
    except InputError:
        data = None
    for orig, now in zip(keep, (t, acc), strict=True):
        if isinstance(now, np.ndarray):
            assert now.flags.writeable
            if now.dtype.kind == "O":  # None and NaN entries: compare what each entry is
                assert [repr(x) for x in orig.ravel()] == [repr(x) for x in now.ravel()]
            else:
                assert np.array_equal(orig, now, equal_nan=now.dtype.kind == "f")
    if data is None:
        return
    for given_, got in ((t, data.t), (acc, data.acc[:, 0])):
        plain = np.asarray(given_.to_numpy() if hasattr(given_, "to_numpy") else given_)
        assert plain.dtype.kind in "iuf", plain.dtype  # only plain numbers are accepted
        assert np.array_equal(got, plain.astype(float))
        assert not np.shares_memory(got, plain)
