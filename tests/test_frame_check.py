"""Frame and gravity sanity (issue 40, case 4): the mean navigation-frame acceleration at rest.

A z-down sensor (forward-right-down body axes, attitude relative to NED) read as ENU counts
gravity twice: at rest C f + g is about (0, 0, -2 g). Every path that turns specific force
and an attitude into navigation-frame acceleration runs :func:`bvpnav.detect.frame_check`
and warns, naming the frame, gravity, the sensor's axes and the fix; correctly stated
frames never warn (the whole suite runs with ``error::bvpnav.log.FrameWarning``).
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from bvpnav import ImuData, NavigationProblem, readers, scenarios, simulate
from bvpnav.constraints import Position, ZeroVelocity
from bvpnav.detect import frame_check
from bvpnav.errors import InputError
from bvpnav.log import FrameWarning
from bvpnav.strapdown import frame_change

G0 = 9.80665
FLU_TO_FRD = Rotation.from_euler("x", 180, degrees=True)  # v_frd = R v_flu: (x, y, z) -> (x, -y, -z)
ENU_TO_NED = Rotation.from_matrix(frame_change("enu", "ned"))


@pytest.fixture(scope="module")
def walk():
    """A simulated foot walk (z-up sensor, ENU), and the same recording from a z-down sensor:
    forward-right-down body axes, its attitude relative to NED."""
    sc = scenarios.walking(rate=100.0, n_strides=4, seed=3)
    sim = sc.params["simulation"]
    frd = {"f": FLU_TO_FRD.apply(sim.specific_force), "w": FLU_TO_FRD.apply(sim.gyro),
           "C": ENU_TO_NED * sim.attitude * FLU_TO_FRD.inv()}  # C_ned<-frd = T C_enu<-flu R^T
    return sc, sim, frd


def _no_frame_warning(fn):
    with warnings.catch_warnings():
        warnings.simplefilter("error", FrameWarning)
        return fn()


def test_z_down_sensor_read_as_enu_warns_gravity_counted_twice(walk):
    sc, sim, frd = walk
    with pytest.warns(FrameWarning) as rec:
        data = ImuData.from_gyro(sim.t, frd["f"], frd["w"])  # ENU by default, identity start
    msg = str(rec[0].message)
    chk = data.checks["frame"]
    assert chk["verdict"] == "gravity twice" and chk["over"] == "rest"
    # at rest C f + g = (0, 0, -g) + (0, 0, -g) for a level z-down sensor read as z-up
    assert chk["along_gravity"] == pytest.approx(2 * G0, rel=0.01)
    assert chk["horizontal"] < 0.05 * G0
    assert chk["samples"] >= int(0.8 * np.count_nonzero(sc.params["stance"]))
    for part in ("gravity is counted twice", "Navigation frame ENU (x east, y north, z up)",
                 "gravity (0, 0, -9.80665) m/s^2", "its z axis points down (z-down body axes, e.g. FRD/NED)",
                 "ImuData.from_gyro(t, specific_force, gyro, frame='ned')", "(2.00 g) along gravity"):
        assert part in msg, (part, msg)


def test_the_same_sensor_stated_as_ned_is_quiet_and_gives_the_ned_acceleration(walk):
    sc, sim, frd = walk
    data = _no_frame_warning(lambda: ImuData.from_gyro(sim.t, frd["f"], frd["w"], frame="ned",
                                                       initial_attitude=frd["C"][0]))
    assert data.frame == "ned" and np.array_equal(data.gravity, [0.0, 0.0, G0])
    assert data.checks["frame"]["verdict"] is None and data.checks["frame"]["warning"] is None
    np.testing.assert_allclose(data.acc, ENU_TO_NED.apply(np.array(sc.data.acc)), rtol=0, atol=1e-9)
    # the frame is one decision: with an identity start (heading north) the check is quiet too
    level = _no_frame_warning(lambda: ImuData.from_gyro(sim.t, frd["f"], frd["w"], frame="ned"))
    assert np.linalg.norm(level.checks["frame"]["mean_acc"]) < 0.05 * G0


def test_given_attitude_relative_to_ned_read_as_enu_warns_with_the_frame_argument(walk):
    _, sim, frd = walk
    with pytest.warns(FrameWarning, match=r"If the attitude is relative to NED, say so: ImuData\(t, "
                      r"specific_force=f, attitude=C, frame='ned'\)"):
        ImuData(sim.t, specific_force=frd["f"], attitude=frd["C"])
    ok = _no_frame_warning(lambda: ImuData(sim.t, specific_force=frd["f"], attitude=frd["C"], frame="ned"))
    assert ok.checks["frame"]["verdict"] is None


def test_frame_and_gravity_must_agree():
    t = np.arange(5.0)
    f = np.tile([0.0, 0.0, G0], (5, 1))
    with pytest.raises(InputError, match=r"gravity=\[0.0, 0.0, -9.8\] points along -z, but frame='ned' has z "
                       "down"):
        ImuData(t, specific_force=f, attitude=Rotation.identity(5), gravity=[0, 0, -9.8], frame="ned")
    with pytest.raises(InputError, match="frame='xyz': valid navigation frames"):
        ImuData.from_gyro(t, f, np.zeros((5, 3)), frame="xyz")
    with pytest.raises(InputError, match="attitude/gravity/frame go with specific_force"):
        ImuData(t, f, frame="enu")


def test_up_axis_turned_horizontal_and_gravity_missing_are_named(walk):
    _, sim, _ = walk
    g_enu = np.array([0.0, 0.0, -G0])
    swapped = sim.specific_force[:, [2, 0, 1]]  # columns z, x, y given as x, y, z
    with pytest.warns(FrameWarning, match=r"horizontal: the attitude turns the sensor's up axis"):
        d = ImuData.from_gyro(sim.t, swapped, sim.gyro[:, [2, 0, 1]], initial_attitude=sim.attitude[0])
    assert d.checks["frame"]["verdict"] == "gravity horizontal"
    assert d.checks["frame"]["horizontal"] > 0.5 * G0
    user = sim.specific_force + sim.attitude.inv().apply(g_enu)  # gravity removed ("linear acceleration")
    with pytest.warns(FrameWarning, match=r"the specific force lacks gravity"):
        d = ImuData(sim.t, specific_force=user, attitude=sim.attitude)
    chk = d.checks["frame"]
    assert chk["verdict"] == "gravity missing" and chk["over"] == "all"  # |f| is never near g: no rest
    assert chk["along_gravity"] == pytest.approx(G0, rel=0.02)


def test_the_solve_reports_it_in_warnings_and_stats(walk):
    sc, sim, frd = walk
    with pytest.warns(FrameWarning):
        data = ImuData.from_gyro(sim.t, frd["f"], frd["w"])
    prob = NavigationProblem(data)
    prob.add(Position(t=0.0, value=[0.0, 0.0, 0.0]),
             *[ZeroVelocity(t0=a, t1=b, mode="soft", sigma=0.01) for a, b in sc.params["stance_intervals"]])
    sol = prob.solve(solver="direct")
    assert any(w.startswith("frame check: ") and "counted twice" in w for w in sol.warnings)
    assert sol.stats["data_checks"]["frame"]["verdict"] == "gravity twice"


def test_frame_check_numbers_on_a_known_case():
    """Level sensor at rest, then a constant 1 m/s^2 push: the rest mean is exactly C f + g there."""
    t = np.arange(0.0, 10.0, 0.01)
    f = np.tile([0.0, 0.0, G0], (t.size, 1))
    f[t > 6.0] = [1.0, 0.0, G0 + 3.0]  # moving: |f| far from g, left out of "rest"
    data = ImuData(t, specific_force=f, attitude=Rotation.identity(t.size), checks=False)
    res = frame_check(data, warn=False)
    assert res.over == "rest" and res.verdict is None
    assert res.samples == np.count_nonzero(t <= 6.0)
    np.testing.assert_allclose(res.mean_acc, 0.0, atol=1e-12)


# ----------------------------------------------------------------------- readers
def _table(path, t, **cols):
    df = pd.DataFrame({"t": t})
    for prefix, arr in cols.items():
        for k in range(arr.shape[1]):
            df[f"{prefix}{k}"] = arr[:, k]
    df.to_csv(path, index=False, float_format="%.17g")
    return path


def test_table_reader_names_frame_or_attitude_frame(walk, tmp_path):
    _, sim, frd = walk
    force = ["f0", "f1", "f2"]
    gyro_csv = _table(tmp_path / "gyro.csv", sim.t, f=frd["f"], w=frd["w"])
    inp = {"specific_force": force, "gyro": ["w0", "w1", "w2"]}
    rec = readers.read(gyro_csv, inp)
    with pytest.warns(FrameWarning, match=r"frame check of .*gyro\.csv.*set \[input\] frame = \"ned\""):
        rec.imu_data(inp)
    _no_frame_warning(lambda: rec.imu_data({**inp, "frame": "ned"}))
    q = frd["C"].as_quat()
    ori_csv = _table(tmp_path / "ori.csv", sim.t, f=frd["f"], q=q)
    inp = {"specific_force": force, "attitude": {"quaternion": ["q0", "q1", "q2", "q3"], "scalar": "last"},
           "attitude_frame": "enu"}
    rec = readers.read(ori_csv, inp)
    with pytest.warns(FrameWarning, match=r"read as relative to ENU \(as given by attitude_frame\); if it is "
                      r"relative to NED .* set \[input\] attitude_frame = \"ned\""):
        rec.imu_data(inp)
    data = _no_frame_warning(lambda: rec.imu_data({**inp, "attitude_frame": "ned"}))
    np.testing.assert_allclose(data.acc, simulate_acc(sim), rtol=0, atol=1e-8)  # ENU, the truth


def simulate_acc(sim):
    return sim.attitude.apply(sim.specific_force) + [0.0, 0.0, -G0]


def test_ned_frd_bag_read_as_enu_warns_naming_attitude_frame(walk, tmp_path):
    """A bag whose Imu orientation is relative to NED with FRD body axes (frame_id imu_frd)."""
    pytest.importorskip("rosbags")
    from rosbags.rosbag2 import Writer

    from bvpnav.readers.rosbag import IMU_TYPE, _msg_header, _typestore

    _, sim, frd = walk
    store = _typestore()
    types = store.types
    vec, quat = types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Quaternion"]
    q = frd["C"].as_quat()
    start = 1_700_000_000_000_000_000
    with Writer(tmp_path / "ned_bag", version=9) as writer:
        conn = writer.add_connection("/imu/data", IMU_TYPE, typestore=store)
        for k in range(sim.t.size):
            ns = start + 10_000_000 * k
            msg = types[IMU_TYPE](header=_msg_header(types, ns, "imu_frd"), orientation=quat(*q[k]),
                                  orientation_covariance=np.diag([1e-4] * 3).ravel(),
                                  angular_velocity=vec(*frd["w"][k]), angular_velocity_covariance=np.zeros(9),
                                  linear_acceleration=vec(*frd["f"][k]),
                                  linear_acceleration_covariance=np.zeros(9))
            writer.write(conn, ns + 1_000_000, store.serialize_cdr(msg, IMU_TYPE))
    rec = readers.read(tmp_path / "ned_bag", {"format": "rosbag"})
    assert any("imu_frd" in n and "NED" in n for n in rec.notes)  # the frame_id's suffix is stated
    with pytest.warns(FrameWarning) as got:
        data = rec.imu_data({})
    msg = str(got[0].message)
    assert "gravity is counted twice" in msg
    assert "read as relative to ENU (the reader's convention)" in msg
    assert 'set [input] attitude_frame = "ned"' in msg
    assert data.checks["frame"]["along_gravity"] == pytest.approx(2 * G0, rel=0.01)
    fixed = _no_frame_warning(lambda: rec.imu_data({"attitude_frame": "ned"}))
    np.testing.assert_allclose(fixed.acc, simulate_acc(sim), rtol=0, atol=1e-6)  # float64 quaternions


# ------------------------------------------------ correctly stated frames: never a warning
@pytest.mark.parametrize("make", [
    lambda: scenarios.walking(rate=100.0, n_strides=3, seed=1).data,
    lambda: simulate.strapdown_3d_2010(rate=20.0, duration=6.0, noise=0.0, seed=1).imu_data("true"),
    lambda: simulate.strapdown_3d_2010(rate=20.0, duration=6.0, noise=0.0, seed=1).imu_data("gyro"),
    lambda: scenarios.car_drive(duration=60.0, rate=50.0).data(),
], ids=["walking", "strapdown2010-true", "strapdown2010-gyro", "car"])
def test_correct_frames_are_quiet(make):
    data = _no_frame_warning(make)
    chk = data.checks["frame"]
    assert chk["verdict"] is None and np.linalg.norm(chk["mean_acc"]) < 0.5 * G0


def test_the_command_line_prints_the_frame_warning_with_the_spec_option(walk, tmp_path, capsys):
    from bvpnav.cli import main

    _, sim, frd = walk
    _table(tmp_path / "zdown.csv", sim.t, f=frd["f"], w=frd["w"])
    spec = """\
[input]
specific_force = ["f0", "f1", "f2"]
gyro = ["w0", "w1", "w2"]
{frame}
[problem]
sigma_a = 0.1

[solve]
solver = "direct"
lam = 1.0

[[item]]
type = "position"
t = 0.0
value = [0.0, 0.0, 0.0]
mode = "hard"

[[item]]
type = "velocity"
t = 0.0
value = [0.0, 0.0, 0.0]
mode = "hard"
"""
    (tmp_path / "enu.toml").write_text(spec.format(frame=""))
    (tmp_path / "ned.toml").write_text(spec.format(frame='frame = "ned"'))
    assert main(["solve", str(tmp_path / "zdown.csv"), "--spec", str(tmp_path / "enu.toml"), "--out",
                 str(tmp_path / "a.csv")]) == 0
    out = capsys.readouterr()
    text = out.out + out.err
    assert "frame check of " in text and 'set [input] frame = "ned"' in text and "counted twice" in text
    import json

    js = json.loads((tmp_path / "a.json").read_text())
    assert js["data_checks"]["frame"]["verdict"] == "gravity twice"
    assert main(["solve", str(tmp_path / "zdown.csv"), "--spec", str(tmp_path / "ned.toml"), "--out",
                 str(tmp_path / "b.csv")]) == 0
    out = capsys.readouterr()
    assert "frame check" not in out.out + out.err
    assert json.loads((tmp_path / "b.json").read_text())["data_checks"]["frame"]["verdict"] is None
