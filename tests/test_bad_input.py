"""The bad-input matrix: every entry point refuses bad data with bvpnav's InputError.

One table of cases over the Python API (ImuData, items, NavigationProblem and its
solve), spec files (parse_spec, load_spec), the CSV and Parquet readers and the
command line (``bvpnav.cli.main``, exit code 2). Each case gives two regular
expressions: one for the culprit (sample index, row, column, item label, spec line)
and one for the hint of the fix. A wrong unit that is only wrong in magnitude (an
accelerometer in g declared as m/s^2) cannot be detected from the numbers and is not
faked here; an unknown unit *name* is.

Long gaps between samples are not an error on the non-uniform grid, but the solution
reports them (:func:`test_a_long_gap_is_solved_and_reported`).
"""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

import bvpnav
from bvpnav.cli import main
from bvpnav.constraints import AverageVelocity, Position, Symmetry, Velocity, ZeroVelocity
from bvpnav.errors import InputError
from bvpnav.readers import read_recording
from bvpnav.samples import write_sample
from bvpnav.spec import load_spec, parse_spec

T = np.linspace(0.0, 10.0, 11)  # s
ACC = np.column_stack([np.sin(T), np.cos(T), 0.1 * T])  # m/s^2
XYZ = ("x", "y", "z")
QUAT = Rotation.from_rotvec(np.column_stack([0 * T, 0 * T, 0.1 * T])).as_quat()  # (11, 4), scalar last
F_BODY = np.column_stack([np.zeros(11), np.zeros(11), np.full(11, 9.80665)])  # m/s^2
GOOD_CSV = "t,acc_x,acc_y\n0,1,0\n0.1,2,0\n0.2,3,0\n0.3,1,0\n"
XY_INPUT = {"columns": {"x": "acc_x", "y": "acc_y"}}


def with_bad(arr, index, value):
    out = np.array(arr, dtype=float)
    out[index] = value
    return out


def problem(*items, **kw):
    return bvpnav.NavigationProblem(bvpnav.ImuData(T, ACC, axes=XYZ), **kw).add(*items)


def solved(*items, **kw):
    """Build and solve (direct back end): items are checked against the data here."""
    return lambda: problem(Position(t=[0.0, 10.0], value=0.0, name="ends"), *items, **kw).solve(
        solver="direct")


# ------------------------------------------------------------ entry points
def api(fn):
    return ("raise", lambda tmp, sample: fn())


def spec_text(text):
    return ("raise", lambda tmp, sample: parse_spec(text, "bad.toml"))


def spec_file(text):
    def run(tmp, sample):
        p = tmp / "bad.toml"
        p.write_text(text)
        load_spec(p)
    return ("raise", run)


def csv(body, inp=None, bom=False):
    def run(tmp, sample):
        p = tmp / "rec.csv"
        p.write_bytes(("\ufeff" if bom else "").encode() + body.encode())
        read_recording(p, inp)
    return ("raise", run)


def parquet(columns, inp=None):
    def run(tmp, sample):
        p = tmp / "rec.parquet"
        pd.DataFrame(columns).to_parquet(p)
        read_recording(p, inp)
    return ("raise", run)


def cli(build):
    """``build(tmp, sample)`` returns the argv of ``bvpnav``; the case expects exit code 2."""
    return ("cli", build)


def solve_argv(recording=None, spec=None, extra=()):
    def build(tmp, sample):
        rec, sp = sample / "recording.csv", sample / "spec.toml"
        if recording is not None:
            rec = tmp / "rec.csv"
            rec.write_text(recording)
        if spec is not None:
            sp = tmp / "spec.toml"
            sp.write_text(spec((sample / "spec.toml").read_text()))
        return ["solve", str(rec), "--spec", str(sp), "--out", str(tmp / "out.csv"), *extra]
    return build


def add_item(block):
    return lambda text: text + "\n[[item]]\n" + block + "\n"


Q_NAN = with_bad(QUAT, (4, 2), np.nan)
M_BAD = Rotation.from_quat(QUAT).as_matrix()
M_BAD[6] *= 2.0
M_INF = Rotation.from_quat(QUAT).as_matrix()
M_INF[3, 1, 1] = np.inf
PQ_T = [0.0, 0.1, 0.2, 0.3]

CASES = [
    # ---------------------------------------------------------------- ImuData
    pytest.param(api(lambda: bvpnav.ImuData(with_bad(T, 4, np.nan), ACC)),
                 r"time: value at index 4 is nan", r"remove or repair", id="api-t-nan"),
    pytest.param(api(lambda: bvpnav.ImuData(with_bad(T, 10, np.inf), ACC)),
                 r"time: value at index 10 is inf", r"remove or repair", id="api-t-inf"),
    pytest.param(api(lambda: bvpnav.ImuData(T, with_bad(ACC, (3, 0), np.nan), axes=XYZ)),
                 r"acc: sample 3, x is nan", r"remove or repair", id="api-acc-x-nan"),
    pytest.param(api(lambda: bvpnav.ImuData(T, with_bad(ACC, (7, 1), -np.inf), axes=XYZ)),
                 r"acc: sample 7, y is -inf", r"remove or repair", id="api-acc-y-inf"),
    pytest.param(api(lambda: bvpnav.ImuData(T, with_bad(ACC, (0, 2), np.nan))),
                 r"acc: sample 0, column 2 is nan", r"remove or repair", id="api-acc-z-nan"),
    pytest.param(api(lambda: bvpnav.ImuData(T, specific_force=with_bad(F_BODY, (5, 2), np.inf),
                                            attitude=QUAT)),
                 r"specific_force: sample 5, f_z is inf", r"remove or repair", id="api-force-inf"),
    pytest.param(api(lambda: bvpnav.ImuData(T, specific_force=F_BODY, attitude=Q_NAN)),
                 r"attitude: quaternion 4 .*nan", r"remove or repair", id="api-quat-nan"),
    pytest.param(api(lambda: bvpnav.ImuData(T, specific_force=F_BODY, attitude=M_INF)),
                 r"attitude: matrix 3 .*inf", r"remove or repair", id="api-matrix-inf"),
    pytest.param(api(lambda: bvpnav.ImuData(T, specific_force=F_BODY, attitude=2.0 * QUAT)),
                 r"attitude: quaternion 0 has norm 2", r"normali[sz]e", id="api-quat-not-unit"),
    pytest.param(api(lambda: bvpnav.ImuData(T, specific_force=F_BODY, attitude=M_BAD)),
                 r"attitude: matrix 6 is not a rotation", r"orthonormal", id="api-matrix-not-rotation"),
    pytest.param(api(lambda: bvpnav.ImuData(T, specific_force=F_BODY, attitude=QUAT[:, :3])),
                 r"attitude: shape \(11, 3\)", r"quaternions \(11, 4\) scalar-last", id="api-att-shape"),
    pytest.param(api(lambda: bvpnav.ImuData(T, specific_force=F_BODY, attitude=QUAT[:-1])),
                 r"attitude: shape \(10, 4\)", r"one per sample|\(11, 4\)", id="api-att-vs-t"),
    pytest.param(api(lambda: bvpnav.ImuData(T, specific_force=F_BODY,
                                            attitude=Rotation.from_quat(QUAT[:5]))),
                 r"attitude: Rotation of length 5", r"one per sample \(11\)", id="api-rotation-length"),
    pytest.param(api(lambda: bvpnav.ImuData.from_gyro(T, F_BODY, with_bad(np.zeros((11, 3)), (8, 1),
                                                                          np.nan))),
                 r"gyro: sample 8, axis y is nan", r"remove or repair", id="api-gyro-nan"),
    pytest.param(api(lambda: bvpnav.ImuData.from_gyro(T, F_BODY, np.zeros((11, 2)))),
                 r"gyro: expected shape \(11, 3\)", r"one body rate per sample", id="api-gyro-shape"),
    pytest.param(api(lambda: bvpnav.ImuData(T[[0, 1, 2, 5, 4, 6, 7, 8, 9, 10]], ACC[:10])),
                 r"sample 4 \(4\.0 s\) is decreasing after sample 3", r"sort the samples",
                 id="api-t-unsorted"),
    pytest.param(api(lambda: bvpnav.ImuData(T[[0, 1, 2, 2, 3, 4, 5, 6, 7, 8, 9]], ACC)),
                 r"sample 3 \(2\.0 s\) is duplicate", r"drop duplicates", id="api-t-duplicate"),
    pytest.param(api(lambda: bvpnav.ImuData(T[:2], ACC[:2])),
                 r"time: 2 samples", r"at least 3 samples", id="api-two-samples"),
    pytest.param(api(lambda: bvpnav.ImuData(T, ACC[:9])),
                 r"acc has 9 samples but t has 11", r"one acceleration row per time", id="api-t-vs-acc"),
    pytest.param(api(lambda: bvpnav.ImuData(T, np.ones((11, 4)))),
                 r"acc: 4 axes given", r"1, 2 or 3 axes", id="api-four-axes"),
    pytest.param(api(lambda: bvpnav.ImuData(T, ACC, axes=("x", "y"))),
                 r"axes: 2 names \('x', 'y'\) for 3", r"one name per acceleration column",
                 id="api-axes-count"),
    # ------------------------------------------------------------------ items
    pytest.param(api(solved(Position(t=[2.0, 12.5], value=1.0, name="fix"))),
                 r"fix\(t=\.\.\.\): time 12\.5 s \(entry 1\) is outside .* \[0\.0, 10\.0\]",
                 r"use a time inside the window", id="item-position-outside"),
    pytest.param(api(solved(Velocity(t=-0.5, value=0.0, name="v0"))),
                 r"v0\(t=\.\.\.\): time -0\.5 s", r"use a time inside the window",
                 id="item-velocity-outside"),
    pytest.param(api(lambda: ZeroVelocity(t0=5.0, t1=3.0, name="stop")),
                 r"stop: interval t0=5\.0 s, t1=3\.0 s has t1 <= t0", r"give t0 < t1",
                 id="item-zupt-reversed"),
    pytest.param(api(lambda: ZeroVelocity(t0=4.0, t1=4.0, name="stop")),
                 r"stop: interval t0=4\.0 s, t1=4\.0 s", r"give t0 < t1", id="item-zupt-empty"),
    pytest.param(api(lambda: AverageVelocity(t0=[1.0, 6.0], t1=[2.0, 6.0], value=0.0, name="sw")),
                 r"sw: interval 1 has t1=6\.0 s <= t0=6\.0 s", r"give t0 < t1", id="item-avgvel-reversed"),
    pytest.param(api(lambda: Position(t=1.0, value=0.0, sigma=-0.1, name="p")),
                 r"p: sigma = -0\.1", r"finite positive number", id="item-sigma-negative"),
    pytest.param(api(lambda: Velocity(t=1.0, value=0.0, sigma=[0.1, 0.0], name="v")),
                 r"v: sigma = 0\.0", r"finite positive number.*omit sigma", id="item-sigma-zero"),
    pytest.param(api(lambda: Position(t=1.0, mode="band", tol=-1.0, name="p")),
                 r"p: tol = -1\.0", r"finite positive number", id="item-tol-negative"),
    pytest.param(api(lambda: Position(t=1.0, mode="robust", sigma=1.0, huber=0.0, name="p")),
                 r"p: huber = 0\.0", r"finite positive number", id="item-huber-zero"),
    pytest.param(api(lambda: Position(t=1.0, mode="sfot", name="p")),
                 r"p: mode='sfot'", r"choose one of \['hard', 'soft', 'robust', 'band'\]",
                 id="item-bad-mode"),
    pytest.param(api(lambda: Position(t=1.0, name=[0])),
                 r"Position: name=\[0\]", r"give a non-empty string", id="item-name-not-a-string"),
    pytest.param(api(lambda: bvpnav.NavigationProblem(bvpnav.ImuData(T, ACC[:, 0]))
                     .solve(on_conflict="ignore")),
                 r"on_conflict='ignore'", r"choose 'raise' or 'demote'", id="solve-bad-on-conflict"),
    pytest.param(api(lambda: Position(t=[1.0, np.nan], name="p")),
                 r"p: t: value at index 1 is nan", r"remove or repair", id="item-t-nan"),
    pytest.param(api(lambda: Velocity(t=1.0, value=[0.0, np.inf], name="v")),
                 r"v: value entry 1 is inf", r"must be finite", id="item-value-inf"),
    pytest.param(api(solved(Position(t=5.0, value=0.0, axes="w", name="pw"))),
                 r"pw: unknown axis 'w'", r"this data has axes \['x', 'y', 'z'\]", id="item-unknown-axis"),
    pytest.param(api(solved(Symmetry(about=11.0, name="mirror"))),
                 r"mirror: about=11\.0 s is outside the window", r"inside the window",
                 id="item-symmetry-outside"),
    pytest.param(api(lambda: Symmetry(about=5.0, parity="odd-ish", name="mirror")),
                 r"mirror: parity='odd-ish'", r"choose 'even' or 'odd'", id="item-symmetry-parity"),
    # ------------------------------------------------------------ problem/solve
    pytest.param(api(lambda: problem(residual="accel")),
                 r"residual='accel'", r"choose one of \['acceleration', 'load'\]", id="problem-residual"),
    pytest.param(api(lambda: problem(sigma_a=[1.0, -2.0, 1.0])),
                 r"sigma_a \(m/s\^2\) = -2\.0", r"finite positive number", id="problem-sigma-a"),
    pytest.param(api(lambda: problem(Position(t=[0.0, 10.0], value=0.0)).solve(solver="direct", lam=-1.0)),
                 r"lam=-1\.0", r"finite number >= 0", id="solve-lam-negative"),
    pytest.param(api(lambda: problem(Position(t=[0.0, 10.0], value=0.0)).solve(accuracy="extreme")),
                 r"accuracy='extreme'", r"choose one of \['low', 'default', 'high'\]", id="solve-accuracy"),
    pytest.param(api(lambda: problem(Position(t=[0.0, 10.0], value=0.0)).solve(lam="corner")),
                 r"'corner'", r"lcurve", id="solve-lam-rule"),
    # ------------------------------------------------------------------- specs
    pytest.param(spec_file('[input]\ntime_unit = "min"\n'),
                 r"bad\.toml, line 2: time_unit='min'", r"valid units: \['s', 'ms', 'us', 'ns'\]",
                 id="spec-time-unit"),
    pytest.param(spec_text('[input]\ncolumns = { x = 1 }\n'),
                 r"line 2: columns", r'columns = \{ x = "acc_x" \}', id="spec-columns-type"),
    pytest.param(spec_text('[problem]\nresidual = "accel"\n'),
                 r"line 2: residual='accel'", r"choose one of \['acceleration', 'load'\]",
                 id="spec-residual"),
    pytest.param(spec_text('[problem]\nsigma_a = 0.0\n'),
                 r"line 2: sigma_a", r"finite positive number", id="spec-sigma-a"),
    pytest.param(spec_text('[solve]\nsolver = "direct"\naccuracy = "best"\n'),
                 r"line 3: accuracy='best'", r"choose one of \['low', 'default', 'high'\]",
                 id="spec-accuracy"),
    pytest.param(spec_text('[solve]\nlam = "corner"\n'),
                 r"line 2: lam='corner'", r"choose one of \[.*'lcurve'", id="spec-lam"),
    pytest.param(spec_file('[[item]]\ntype = "zero_velocty"\nt0 = 0.0\nt1 = 1.0\n'),
                 r"bad\.toml, line 2: unknown item 'zero_velocty'", r"valid types: .*'zero_velocity'",
                 id="spec-unknown-item"),
    pytest.param(spec_text('[[item]]\ntype = "velocity"\nname = "v0"\nt = 0.0\nmode = "hard"\nsigma = 0\n'),
                 r"line 1: v0: sigma = 0", r"finite positive number", id="spec-item-sigma-zero"),
    pytest.param(spec_text('[[item]]\ntype = "position"\nname = "p"\nt = "ten"\n'),
                 r"line 1: p: t: cannot be read as numbers", r"pass numbers in s", id="spec-item-t-text"),
    pytest.param(spec_text('[[item]]\ntype = "zero_velocity"\nname = "zv"\nt0 = 3\nt1 = 2\n'),
                 r"line 1: zv: interval t0=3\.0 s, t1=2\.0 s", r"give t0 < t1", id="spec-item-reversed"),
    pytest.param(spec_text('item = 5\n'),
                 r"line 1: item", r"\[\[item\]\] tables", id="spec-item-not-table"),
    # ------------------------------------------------------------- CSV reader
    pytest.param(csv("t,acc_x,acc_y\n0,1,0\nnan,2,0\n0.2,3,0\n0.3,1,0\n", XY_INPUT),
                 r"row 1 \(line 3\), column 't' is empty or NaN", r"fix or remove those rows",
                 id="csv-t-nan"),
    pytest.param(csv("t,acc_x,acc_y\n0,1,0\n0.1,2,0\n0.2,3,inf\n0.3,1,0\n", XY_INPUT),
                 r"row 2 \(line 4\), column 'acc_y' is infinite", r"fix or remove those rows",
                 id="csv-acc-y-inf"),
    pytest.param(csv("t,acc_x,acc_y\n0,1,0\n0.1,,0\n0.2,3,0\n0.3,1,0\n", XY_INPUT),
                 r"row 1 \(line 3\), column 'acc_x' is empty or NaN", r"fix or remove", id="csv-acc-x-empty"),
    pytest.param(csv("t,acc_x,acc_y\n0,1,0\n0.1,2,0\n0.2,1e999,0\n", XY_INPUT),
                 r"row 2 \(line 4\), column 'acc_x' is infinite", r"fix or remove", id="csv-huge-number"),
    pytest.param(csv("t,acc_x\n0,1\n0.1,2\n"),
                 r"rec\.csv: 2 rows", r"at least 3 samples", id="csv-two-rows"),
    pytest.param(csv("t,acc_x\n0,1\n0.1,2,7\n0.2,3\n"),
                 r"rec\.csv'?: .*line 3", r"same number of fields", id="csv-ragged-row"),
    pytest.param(csv("t;acc_x\n0;1\n0.1;2\n0.2;3\n"),
                 r"rec\.csv: one column 't;acc_x'", r"comma-separated", id="csv-semicolons"),
    pytest.param(csv(GOOD_CSV, {"columns": {"x": "acc_x", "w": "acc_w"}}),
                 r"column 'acc_w' \(axis w\) not found", r"columns in the file: \['t', 'acc_x', 'acc_y'\]",
                 id="csv-unknown-axis-column"),
    pytest.param(csv(GOOD_CSV, {"unit": "m/s/s"}),
                 r"rec\.csv: unit='m/s/s'", r"valid acceleration units: \['m/s\^2', 'g', 'mg', 'ft/s\^2'\]",
                 id="csv-unknown-unit"),
    pytest.param(csv(GOOD_CSV, {"time_unit": "h"}),
                 r"rec\.csv: time_unit='h'", r"valid units", id="csv-unknown-time-unit"),
    pytest.param(csv(GOOD_CSV, {"time": "time"}),
                 r"column 'time' \(time\) not found", r"columns in the file", id="csv-no-time-column"),
    pytest.param(csv("t,acc_x\n0,1\n0.1,x1\n0.2,3\n", bom=True),
                 r"row 1 \(line 3\), column 'acc_x' is not a number \('x1'\)", r"fix or remove",
                 id="csv-bom-text-cell"),
    pytest.param(csv(""),
                 r"rec\.csv'?: not a readable CSV file \(it is empty\)", r"header line", id="csv-empty-file"),
    # --------------------------------------------------------- Parquet reader
    pytest.param(parquet({"t": [0.0, 0.2, 0.1, 0.3], "acc_x": [1.0, 2.0, 3.0, 4.0]}),
                 r"rec\.parquet: row 2: time 0\.1 goes back from", r"sort the file by time",
                 id="pq-t-unsorted"),
    pytest.param(parquet({"t": [0.0, 0.1, 0.1, 0.3], "acc_x": [1.0, 2.0, 3.0, 4.0]}),
                 r"rec\.parquet: row 2: time 0\.1 repeats", r"drop duplicate samples", id="pq-t-duplicate"),
    pytest.param(parquet({"t": PQ_T, "acc_x": pd.array([1, None, 3, 4], dtype="Int64")}),
                 r"rec\.parquet: row 1, column 'acc_x' is empty or NaN", r"fix or remove", id="pq-null-int"),
    pytest.param(parquet({"t": PQ_T, "acc_x": [True, False, True, True]}),
                 r"rec\.parquet: column 'acc_x' holds bool", r"numbers in m/s\^2", id="pq-bool-column"),
    pytest.param(parquet({"t": ["0", "0.1", "zero", "0.3"], "acc_x": [1.0, 2.0, 3.0, 4.0]}),
                 r"rec\.parquet: row 2, column 't' is not a number \('zero'\)", r"fix or remove",
                 id="pq-string-time"),
    # -------------------------------------------------------- command line
    pytest.param(cli(solve_argv(recording="t,acc_x\n0,1\n0.1,2\ninf,3\n0.3,1\n")),
                 r"row 2 \(line 4\), column 't' is infinite", r"fix or remove", id="cli-t-inf"),
    pytest.param(cli(solve_argv(spec=add_item('type = "position"\nname = "late"\nt = 25.0\nvalue = 0.0'))),
                 r"late\(t=\.\.\.\): time 25\.0 s", r"use a time inside the window", id="cli-item-outside"),
    pytest.param(cli(solve_argv(spec=add_item('type = "velocity"\nname = "vz"\nt = 1.0\naxes = "z"'))),
                 r"vz: unknown axis 'z'", r"this data has axes \['x'\]", id="cli-item-unknown-axis"),
    pytest.param(cli(solve_argv(spec=lambda s: s.replace('unit = "m/s^2"', 'unit = "G"'))),
                 r"line \d+: unit='G'", r"valid acceleration units", id="cli-unit-name"),
    pytest.param(cli(solve_argv(extra=["--solver", "gurobi-ish"])),
                 r"gurobi-ish", r"installed", id="cli-unknown-solver"),
    pytest.param(cli(solve_argv(extra=["--lam", "-3"])),
                 r"lam=-3\.0", r"finite number >= 0", id="cli-lam-negative"),
    pytest.param(cli(lambda tmp, sample: ["solve", str(tmp / "missing.csv"), "--spec",
                                          str(sample / "spec.toml"), "--out", str(tmp / "o.csv")]),
                 r"missing\.csv': no such file", r"check the path", id="cli-missing-recording"),
    pytest.param(cli(lambda tmp, sample: ["batch", str(sample / "recording.csv"), "--spec",
                                          str(sample / "spec.toml"), "--out", str(tmp / "o")]),
                 r"recording\.csv' is not a folder", r"give the folder", id="cli-batch-not-a-folder"),
]


@pytest.fixture(scope="module")
def sample(tmp_path_factory):
    """The shuttle sample (x axis only) at 5 Hz: a valid recording and spec."""
    d = tmp_path_factory.mktemp("shuttle")
    write_sample("shuttle", d, rate=5.0)
    return d


@pytest.mark.parametrize("case,culprit,fix", CASES)
def test_bad_input_names_the_culprit_and_the_fix(case, culprit, fix, tmp_path, sample, capsys):
    kind, run = case
    if kind == "cli":
        code = main(run(tmp_path, sample))
        err = capsys.readouterr().err
        assert code == 2, err
        assert err.startswith("bvpnav: error: ") and "Traceback" not in err
        assert not (tmp_path / "out.csv").exists()
        msg = err
    else:
        with pytest.raises(InputError) as exc:
            run(tmp_path, sample)
        msg = str(exc.value)
    assert re.search(culprit, msg), msg
    assert re.search(fix, msg, flags=re.IGNORECASE), msg


def test_the_matrix_has_enough_cases():
    assert len(CASES) >= 35
    assert len({p.id for p in CASES}) == len(CASES)


def test_a_long_gap_is_solved_and_reported(sample, tmp_path, capsys):
    """A 3 s hole in a 0.2 s grid is allowed but named: sample index, length, median step."""
    t = np.concatenate([np.arange(0.0, 4.01, 0.2), np.arange(7.0, 10.01, 0.2)])  # gap 4 -> 7 s
    k = int(np.flatnonzero(np.isclose(t, 4.0))[0])  # sample 20
    sol = bvpnav.NavigationProblem(bvpnav.ImuData(t, np.ones(t.size))).add(
        Position(t=[0.0, 10.0], value=[0.0, 50.0])).solve(solver="direct")
    # 1 m/s^2 from rest between r(0) = 0 and r(10) = 50 m: r = t^2 / 2 at every node, gap or not
    np.testing.assert_allclose(sol.position("x"), t**2 / 2, rtol=0, atol=1e-9)
    (msg,) = [w for w in sol.warnings if "gap" in w]
    assert f"sample {k} to {k + 1}" in msg and "t=4 s" in msg
    assert "is 3 s long" in msg and "median step 0.2 s" in msg and "10x" in msg
    # the command line prints it and keeps it in the summary
    rec = tmp_path / "gap.csv"
    pd.DataFrame({"t": t, "acc_x": np.ones(t.size)}).to_csv(rec, index=False)
    spec = tmp_path / "spec.toml"
    spec.write_text('[input]\ncolumns = { x = "acc_x" }\n[solve]\nsolver = "direct"\n'
                    '[[item]]\ntype = "position"\nt = [0.0, 10.0]\nvalue = [0.0, 50.0]\n')
    assert main(["solve", str(rec), "--spec", str(spec), "--out", str(tmp_path / "o.csv")]) == 0
    out = capsys.readouterr().out
    assert "warning: 1 gap(s)" in out and f"sample {k} to {k + 1}" in out
    summ = json.loads((tmp_path / "o.json").read_text())
    assert summ["warnings"] == [msg]
