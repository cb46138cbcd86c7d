"""Strapdown tables through the spec: specific force, gyro and orientation columns, frames."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from _hostile import EXIT_INPUT, EXIT_OK, assert_clean_failure, main_cli
from scipy.spatial.transform import Rotation

from bvpnav import readers, simulate
from bvpnav.errors import InputError
from bvpnav.spec import dumps_spec, parse_spec
from bvpnav.strapdown import frame_change
from bvpnav.testing import check_reader

FORCE = ["f_x", "f_y", "f_z"]
GYRO = ["w_x", "w_y", "w_z"]


@pytest.fixture(scope="module")
def sim():
    return simulate.strapdown_3d_2010(rate=20.0, duration=6.0, noise=0.0, seed=1)


def _write(path, t, **cols):
    df = pd.DataFrame({"t": t})
    for prefix, arr in cols.items():
        for k in range(arr.shape[1]):
            df[f"{prefix}{k}"] = arr[:, k]
    df.to_csv(path, index=False, float_format="%.17g")
    return path


def _read(path, **inp):
    rec = readers.read(path, inp)
    return rec, rec.imu_data(inp)


def test_the_table_reader_keeps_the_contract(tmp_path):
    rec = check_reader(readers.get_reader("table"), tmp_path)
    assert rec.axes == ("x",) and rec.n == 11


def test_quaternion_columns_scalar_first_or_last_give_the_true_acceleration(sim, tmp_path):
    ref = sim.imu_data(attitude="true")  # C f + g, the simulation's own navigation-frame acceleration
    q = sim.attitude.as_quat()  # scalar last
    first = _write(tmp_path / "first.csv", sim.t, f_=sim.specific_force, q_=q[:, [3, 0, 1, 2]])
    last = _write(tmp_path / "last.csv", sim.t, f_=sim.specific_force, q_=q)
    for path, scalar in ((first, "first"), (last, "last")):
        rec, data = _read(path, specific_force=["f_0", "f_1", "f_2"],
                          attitude={"quaternion": ["q_0", "q_1", "q_2", "q_3"], "scalar": scalar},
                          attitude_frame="enu")
        assert rec.is_strapdown and rec.gyro is None
        np.testing.assert_allclose(data.acc, ref.acc, rtol=0, atol=1e-12)
        assert data.axes == ("x", "y", "z")


def test_euler_columns_equal_the_quaternion(sim, tmp_path):
    ypr = sim.attitude.as_euler("ZYX", degrees=True)
    path = _write(tmp_path / "euler.csv", sim.t, f_=sim.specific_force, e_=ypr)
    _, data = _read(path, specific_force=["f_0", "f_1", "f_2"], attitude_frame="enu",
                    attitude={"euler": ["e_0", "e_1", "e_2"], "sequence": "ZYX", "degrees": True})
    np.testing.assert_allclose(data.acc, sim.imu_data(attitude="true").acc, rtol=0, atol=1e-10)


def test_gyro_in_degrees_per_second_and_g_units_integrate_like_from_gyro(sim, tmp_path):
    path = _write(tmp_path / "deg.csv", sim.t, f_=sim.specific_force / 9.80665, w_=np.rad2deg(sim.gyro))
    c0 = sim.attitude[0]
    init = {"quaternion": c0.as_quat().tolist(), "scalar": "last"}
    _, data = _read(path, specific_force=["f_0", "f_1", "f_2"], unit="g", gyro=["w_0", "w_1", "w_2"],
                    gyro_unit="deg/s", initial_attitude=init)
    ref = sim.imu_data(attitude="gyro")
    np.testing.assert_allclose(data.gyro, sim.gyro, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(data.acc, ref.acc, rtol=0, atol=1e-9)


def test_ned_is_the_enu_result_with_axes_swapped_and_up_negated(sim, tmp_path):
    q = sim.attitude.as_quat()
    path = _write(tmp_path / "q.csv", sim.t, f_=sim.specific_force, q_=q)
    inp = {"specific_force": ["f_0", "f_1", "f_2"], "attitude_frame": "enu",
           "attitude": {"quaternion": ["q_0", "q_1", "q_2", "q_3"], "scalar": "last"}}
    _, enu = _read(path, **inp)
    _, ned = _read(path, **inp, frame="ned")
    np.testing.assert_allclose(ned.acc, enu.acc @ frame_change("enu", "ned").T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ned.gravity, [0.0, 0.0, 9.80665])


def test_body_to_sensor_undoes_the_mounting(sim, tmp_path):
    mount = Rotation.from_euler("xyz", [10.0, -20.0, 90.0], degrees=True)  # v_sensor = R v_body
    f_s, w_s = mount.apply(sim.specific_force), mount.apply(sim.gyro)
    path = _write(tmp_path / "m.csv", sim.t, f_=f_s, w_=w_s)
    init = {"quaternion": sim.attitude[0].as_quat().tolist(), "scalar": "last"}
    _, data = _read(path, specific_force=["f_0", "f_1", "f_2"], gyro=["w_0", "w_1", "w_2"],
                    initial_attitude=init,
                    body_to_sensor={"euler": [10.0, -20.0, 90.0], "sequence": "xyz", "degrees": True})
    np.testing.assert_allclose(data.specific_force, sim.specific_force, rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.acc, sim.imu_data(attitude="gyro").acc, rtol=0, atol=1e-9)
    _, wrong = _read(path, specific_force=["f_0", "f_1", "f_2"], gyro=["w_0", "w_1", "w_2"],
                     initial_attitude=init)
    assert np.abs(wrong.acc - data.acc).max() > 1.0  # the mounting matters: not a test that cannot fail


@pytest.mark.parametrize("inp, pattern", [
    ({"specific_force": FORCE}, r"needs gyro = \[\.\.\.\] columns .* or attitude"),
    ({"specific_force": FORCE, "gyro": GYRO, "columns": {"x": "f_x"}}, r"both columns .* and specific_force"),
    ({"specific_force": ["f_x", "f_y", "f_x"], "gyro": GYRO},
     r"column 'f_x' is mapped to specific force z but is already specific force x"),
    ({"specific_force": FORCE, "gyro": ["w_x", "w_y", "t"]}, r"column 't' is mapped to gyro z but is already "
                                                             r"the time column"),
    ({"specific_force": FORCE, "gyro": GYRO, "gyro_unit": "rpm"}, r"gyro_unit = 'rpm'; valid gyro units"),
    ({"gyro": GYRO}, r"without specific_force"),
    ({"specific_force": FORCE, "attitude": {"quaternion": ["q0", "q1", "q2", "q3"]}},
     r"scalar = \"first\" or \"last\" \(stated, never guessed\)"),
    ({"specific_force": FORCE, "attitude": {"euler": ["a", "b", "c"], "degrees": True}}, r"need sequence"),
    ({"specific_force": FORCE, "gyro": GYRO, "attitude": {"quaternion": ["q0", "q1", "q2", "q3"],
                                                           "scalar": "first"}, "attitude_frame": "enu"},
     r"row 2 \(line 4\): the quaternion in columns .* has norm 1\.1"),
    ({"specific_force": FORCE, "attitude": {"quaternion": ["p0", "p1", "p2", "p3"], "scalar": "first"}},
     r"reference frame is None; set \[input\] attitude_frame"),
])
def test_strapdown_mistakes_name_the_column_and_the_fix(tmp_path, inp, pattern):
    n = 6
    t = np.arange(n) * 0.1
    q = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    q[2] *= 1.1
    df = pd.DataFrame({"t": t, **{c: np.zeros(n) for c in FORCE + GYRO},
                       **{f"q{k}": q[:, k] for k in range(4)}, "a": 0.0, "b": 0.0, "c": 0.0,
                       "p0": 1.0, "p1": 0.0, "p2": 0.0, "p3": 0.0})
    path = tmp_path / "rec.csv"
    df.to_csv(path, index=False)
    with pytest.raises(InputError, match=pattern):
        rec = readers.read(path, inp)
        rec.imu_data(inp)


SPEC = """\
[input]
specific_force = ["f_x", "f_y", "f_z"]
gyro = ["w_x", "w_y", "w_z"]
gyro_unit = "deg/s"
frame = "ned"
gravity = "wgs84"
latitude = 47.5
height = 400.0
body_to_sensor = { euler = [0.0, 0.0, 90.0], sequence = "xyz", degrees = true }
initial_attitude = { quaternion = [1.0, 0.0, 0.0, 0.0], scalar = "first" }

[stationary]
method = "magnitude"
sigma = 0.01
name = "still"

[[item]]
type = "position"
t = 0.0
value = [0.0, 0.0, 0.0]
"""


def test_a_strapdown_spec_round_trips(tmp_path):
    spec = parse_spec(SPEC, "s.toml")
    again = parse_spec(dumps_spec(spec), "again.toml")
    assert again.input == spec.input and again.stationary == spec.stationary
    assert again.input["body_to_sensor"] == {"euler": [0.0, 0.0, 90.0], "sequence": "xyz", "degrees": True}
    assert dumps_spec(again) == dumps_spec(spec)


@pytest.mark.parametrize("edit, pattern", [
    (("frame = \"ned\"", "frame = \"xyz\""), r"s\.toml, line 5: frame = 'xyz'; valid navigation frames"),
    (("gravity = \"wgs84\"\nlatitude = 47.5\nheight = 400.0", "gravity = 98.1"),
     r"s\.toml, line 6: .*gravity = 98\.1: a magnitude"),
    (("latitude = 47.5", "latitude = 147.5"), r"s\.toml, line 6: .*needs latitude \(degrees, -90\.\.90\)"),
    (("gyro_unit = \"deg/s\"", "gyro_units = \"deg/s\""), r"s\.toml, line 4: unknown key 'gyro_units' in "
                                                        r"\[input\]"),
    (("sequence = \"xyz\"", "sequence = \"xxy\""), r"line 9: .*body_to_sensor"),
    (("method = \"magnitude\"", "method = \"mean\""),
     r"line 13: method = 'mean'; stationary detectors"),
    (("[input]", "[input]\nformat = \"tables\""),
     r"line 2: \[input\] format = 'tables' is not a known reader \(did you mean 'table'\?\)"),
])
def test_spec_mistakes_in_frames_name_the_line(edit, pattern):
    with pytest.raises(InputError, match=pattern):
        parse_spec(SPEC.replace(*edit), "s.toml")


@pytest.mark.slow
@pytest.mark.parametrize("scenario, limit", [("walking", 0.1), ("strapdown3d", 0.3)])
def test_simulated_strapdown_recordings_solve_from_the_command_line(tmp_path, scenario, limit):
    # measured: 0.037 m (walking: start position and the detected stances), 0.11 m (strapdown3d:
    # nine-parameter model, ends and three velocities, 0.02 m/s^2 noise)
    folder = tmp_path / scenario
    proc = main_cli(["simulate", scenario, "--out", folder])
    assert proc.returncode == EXIT_OK, proc.stderr
    head = (folder / "recording.csv").read_text().splitlines()[0]
    assert head.startswith("t,f_x,f_y,f_z,")
    proc = main_cli(["solve", folder / "recording.csv", "--spec", folder / "spec.toml", "--out",
                     tmp_path / "traj.csv", "--truth", folder / "truth.csv", "--plot", tmp_path / "traj.png"])
    assert proc.returncode == EXIT_OK, proc.stderr
    rms = float(proc.stdout.split("truth.csv): ")[1].split(" m")[0])
    assert rms < limit, proc.stdout
    traj = pd.read_csv(tmp_path / "traj.csv")
    assert list(traj.columns) == ["t", "x", "y", "z", "vx", "vy", "vz"]


def test_the_stationary_command_finds_the_walks_stances_and_draws_them(tmp_path):
    folder = tmp_path / "walk"
    assert main_cli(["simulate", "walking", "--out", folder]).returncode == EXIT_OK
    proc = main_cli(["stationary", folder / "recording.csv", "--spec", folder / "spec.toml", "--out",
                     tmp_path / "still.csv", "--plot", tmp_path / "still.png"])
    assert proc.returncode == EXIT_OK, proc.stderr
    assert proc.stdout.startswith("11 stationary interval(s)"), proc.stdout  # 10 strides: 9 + both ends
    got = pd.read_csv(tmp_path / "still.csv")
    assert list(got.columns) == ["t0", "t1"] and len(got) == 11 and (got.t1 > got.t0).all()
    assert (tmp_path / "still.png").stat().st_size > 10_000
    proc = main_cli(["stationary", folder / "truth.csv", "--spec", folder / "spec.toml"])
    assert_clean_failure(proc, EXIT_INPUT, r"column 'f_x' \(specific force x\) not found")


def test_the_readers_command_lists_every_reader():
    proc = main_cli(["readers"])
    assert proc.returncode == EXIT_OK, proc.stderr
    for name in readers.registry():
        assert any(line.startswith(name) for line in proc.stdout.splitlines()), proc.stdout


# --------------------------------------------------------------- found by an independent review
def test_a_float_epoch_origin_is_stated_as_its_number_and_aligns_with_same_clock(tmp_path):
    from bvpnav.readers import _origin_ns, align

    t = 1777629600.5 + np.arange(101) * 0.01
    pd.DataFrame({"t": t, "acc_x": 0.0}).to_csv(tmp_path / "f.csv", index=False, float_format="%.17g")
    rec = readers.read(tmp_path / "f.csv", {"time_origin": "first"})
    assert rec.time_origin == "1777629600.5 s"
    assert _origin_ns(rec.time_origin) == ("epoch", 1777629600_500000000)
    from bvpnav.constraints import Position

    info = readers.Recording(t=np.array([0.0]), source="i", time_origin="1777629600000000000 ns",
                             items=(Position(t=1.0, value=0.0),))
    items, _ = align(info, rec, same_clock=True)
    assert items[0].t.tolist() == [0.5]


def test_iso_times_across_a_daylight_saving_switch_are_read_in_utc(tmp_path):
    import datetime as dt

    zone = [dt.timezone(dt.timedelta(hours=1))] * 3 + [dt.timezone(dt.timedelta(hours=2))] * 3
    base = dt.datetime(2026, 3, 29, 0, 59, 59, 980000, tzinfo=dt.timezone.utc)
    stamps = [(base + dt.timedelta(seconds=0.01 * k)).astimezone(z).isoformat() for k, z in enumerate(zone)]
    assert stamps[2].endswith("+01:00") and stamps[3].endswith("+02:00")  # 01:59:59.99 -> 03:00:00.00
    pd.DataFrame({"t": stamps, "acc_x": 0.0}).to_csv(tmp_path / "dst.csv", index=False)
    rec = readers.read(tmp_path / "dst.csv", {"time_unit": "iso8601"})
    np.testing.assert_allclose(np.diff(rec.t), 0.01, rtol=0, atol=1e-9)
    mixed = stamps[:3] + [s[:-6] for s in stamps[3:]]
    pd.DataFrame({"t": mixed, "acc_x": 0.0}).to_csv(tmp_path / "mixed.csv", index=False)
    with pytest.raises(InputError, match=r"row 3 .* without a time zone, unlike row 0"):
        readers.read(tmp_path / "mixed.csv", {"time_unit": "iso8601"})


@pytest.mark.parametrize("key", ["frame", "attitude_frame"])
def test_a_list_where_a_frame_name_goes_names_the_line(key):
    with pytest.raises(InputError, match=rf"s\.toml, line 2: {key} = \['enu'\]"):
        parse_spec(f'[input]\n{key} = ["enu"]\n', "s.toml")


def test_attitude_frame_without_an_orientation_and_clock_options_without_info_are_refused(sim, tmp_path):
    path = _write(tmp_path / "g.csv", sim.t, f_=sim.specific_force, w_=sim.gyro)
    with pytest.raises(InputError, match="has no orientation .* drop attitude_frame"):
        _read(path, specific_force=["f_0", "f_1", "f_2"], gyro=["w_0", "w_1", "w_2"], attitude_frame="enu")
    with pytest.raises(InputError, match=r'euler = \["yaw", "pitch", "roll"\], sequence = "ZYX"'):
        _read(path, specific_force=["f_0", "f_1", "f_2"], attitude={"euler": ["f_0", "f_1", "f_2"]})
    (tmp_path / "s.toml").write_text("[solve]\nsolver = \"direct\"\n")
    proc = main_cli(["solve", path, "--spec", tmp_path / "s.toml", "--out", tmp_path / "o.csv",
                     "--clock-offset", "5"])
    assert_clean_failure(proc, EXIT_INPUT, r"--clock-offset relates the clock of an --info file",
                         r"add --info FILE or drop the option")
