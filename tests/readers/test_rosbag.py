"""The ROS bag reader: contract, exact times, topics, NavSatFix/Odometry items, damage, a solve."""

from __future__ import annotations

import sys

import numpy as np
import pytest

pytest.importorskip("rosbags")

import bvpnav  # noqa: E402
from bvpnav.constraints import Position, Velocity  # noqa: E402
from bvpnav.errors import InputError  # noqa: E402
from bvpnav.readers import get_reader, read, reader_for  # noqa: E402
from bvpnav.readers.rosbag import (  # noqa: E402
    IMU_TYPE,
    ODOMETRY_TYPE,
    _enu_to_geodetic,
    _geodetic_to_enu,
    _typestore,
    write_example_bag,
)
from bvpnav.testing import check_reader  # noqa: E402

START = 1_700_000_000_123_456_789


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    """A 4 s, 50 Hz bag with orientation and GNSS (sigma 0.05 m), noise-free IMU."""
    return write_example_bag(tmp_path_factory.mktemp("bag") / "b", duration=4.0, rate=50.0, seed=1)


def _imu_msg(types, ns: int, f=(0.0, 0.0, 9.80665), w=(0.0, 0.0, 0.0), cov0=-1.0):
    from bvpnav.readers.rosbag import _msg_header

    vec, quat = types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Quaternion"]
    return types[IMU_TYPE](header=_msg_header(types, ns, "imu"), orientation=quat(0.0, 0.0, 0.0, 1.0),
                           orientation_covariance=np.r_[cov0, np.zeros(8)], angular_velocity=vec(*w),
                           angular_velocity_covariance=np.zeros(9), linear_acceleration=vec(*f),
                           linear_acceleration_covariance=np.zeros(9))


def _write_bag(path, topics: dict[str, list[tuple[int, object, str]]]):
    """A ROS 2 bag from {topic: [(receive ns, message, msgtype), ...]}."""
    from rosbags.rosbag2 import Writer

    store = _typestore()
    with Writer(path, version=9) as writer:
        conns = {t: writer.add_connection(t, msgs[0][2], typestore=store) for t, msgs in topics.items()}
        rows = sorted((r, t, m, typ) for t, msgs in topics.items() for r, m, typ in msgs)
        for recv, topic, msg, typ in rows:
            writer.write(conns[topic], recv, store.serialize_cdr(msg, typ))
    return path


def _imu_topic(types, ns_list, **kw):
    return [(START + 1000 + k, _imu_msg(types, ns, **kw), IMU_TYPE) for k, ns in enumerate(ns_list)]


def test_contract(tmp_path):
    rec = check_reader(get_reader("rosbag"), tmp_path)
    assert rec.is_strapdown and rec.attitude is not None and rec.attitude_frame == "enu"
    assert [type(i) for i in rec.items] == [Position]


def test_times_exact_units_and_channels(bag):
    rec = read(bag.storage_file, {"format": "rosbag"})
    sim = bag.simulation
    ns = START + 20_000_000 * np.arange(sim.t.size, dtype=np.int64)
    assert rec.time_origin == f"{START} ns"
    assert np.array_equal(rec.t, (ns - START).astype(float) * 1e-9)  # integer ns difference first: exact
    assert np.array_equal(rec.specific_force, sim.specific_force)  # m/s^2, float64 round trip
    assert np.array_equal(rec.gyro, sim.gyro)  # rad/s
    assert (rec.attitude * sim.attitude.inv()).magnitude().max() < 1e-12
    # the receive clock: the bag's record times (header + 1.0/1.1/1.2 ms in the example)
    recv = read(bag.path, {"format": "rosbag", "stamp": "receive"})
    assert recv.time_origin == f"{START + 1_000_000} ns"
    lat = 1_000_000 + (np.arange(sim.t.size) % 3) * 100_000
    assert np.array_equal(recv.t, (ns + lat - START - 1_000_000).astype(float) * 1e-9)


def test_navsatfix_positions_close_to_truth(bag):
    rec = read(bag.path, {"format": "rosbag", "origin": list(bag.origin)})
    (fix,) = rec.items
    inside = (bag.gnss_t >= 0) & (bag.gnss_t <= 4.0) & (bag.gnss_status >= 0)
    assert np.allclose(fix.t, bag.gnss_t[inside], atol=1e-12)  # same clock as the Imu's t
    truth = bag.simulation.motion.pos(fix.t)
    assert np.abs(fix.value - truth).max() < 4 * 0.05  # the GNSS noise, sigma 0.05 m per axis
    assert np.allclose(fix.sigma, 0.05)
    notes = " ".join(rec.notes)
    assert "1 of 7 NavSatFix messages" in notes and "status < 0" in notes  # the no-fix one, counted
    assert "2 of 6 valid NavSatFix fixes" in notes and "outside the IMU window" in notes
    # default origin: the first kept fix is (0, 0, 0)
    rec0 = read(bag.path, {"format": "rosbag"})
    assert np.abs(rec0.items[0].value[0]).max() < 1e-9
    assert any("origin: the first kept fix" in n for n in rec0.notes)
    assert np.allclose(rec0.items[0].value - rec0.items[0].value[0], fix.value - fix.value[0], atol=1e-6)
    assert read(bag.path, {"format": "rosbag", "gnss_topic": False}).items == ()
    overridden = read(bag.path, {"format": "rosbag", "gnss_sigma": 2.0}).items[0]
    assert np.allclose(overridden.sigma, 2.0)


def test_geodesy_exact():
    a = 6378137.0
    enu = _geodetic_to_enu([0.0], [0.001], [0.0], (0.0, 0.0, 0.0))
    assert np.allclose(enu, [[a * np.sin(np.radians(0.001)), 0.0, a * (np.cos(np.radians(0.001)) - 1)]],
                       atol=1e-9)
    pts = np.array([[100.0, -50.0, 3.0], [-2500.0, 1200.0, -40.0]])
    origin = (48.1, 11.5, 520.0)
    assert np.abs(_geodetic_to_enu(*_enu_to_geodetic(pts, origin), origin) - pts).max() < 1e-6


def test_orientation_present_vs_covariance_minus_one(tmp_path):
    off = write_example_bag(tmp_path / "no_ori", duration=2.0, rate=50.0, with_gnss=False,
                            with_orientation=False)
    rec = read(off.path, {"format": "rosbag"})
    assert rec.attitude is None and rec.attitude_frame is None and rec.items == ()
    assert any("orientation_covariance[0] = -1" in n for n in rec.notes)
    data = rec.imu_data({"initial_attitude": {"quaternion": list(off.simulation.attitude[0].as_quat())}})
    acc = off.simulation.truth[["ax", "ay", "az"]].to_numpy()
    assert np.abs(data.acc - acc).max() < 0.05  # gyro-integrated attitude, 50 Hz
    on = read(write_example_bag(tmp_path / "ori", duration=2.0, rate=50.0, with_gnss=False).path,
              {"format": "rosbag"})
    assert on.attitude is not None and on.attitude_frame == "enu"
    assert np.abs(on.imu_data().acc - acc).max() < 1e-9


def test_two_imu_topics_refused_listing_both(tmp_path):
    types = _typestore().types
    ns = [START + k * 10_000_000 for k in range(5)]
    path = _write_bag(tmp_path / "two", {"/imu/a": _imu_topic(types, ns), "/imu/b": _imu_topic(types, ns)})
    with pytest.raises(InputError, match="2 sensor_msgs/msg/Imu topics") as err:
        read(path, {"format": "rosbag"})
    assert "/imu/a" in str(err.value) and "/imu/b" in str(err.value) and "topic =" in str(err.value)
    assert read(path, {"format": "rosbag", "topic": "/imu/b"}).meta["imu_topic"] == "/imu/b"
    with pytest.raises(InputError, match="'/imu/c' is not in the bag.*/imu/a"):
        read(path, {"format": "rosbag", "topic": "/imu/c"})


def test_duplicate_and_unsorted_stamps_named(tmp_path):
    types = _typestore().types
    ns = [START + k * 10_000_000 for k in range(6)]
    ns[3] = ns[2]
    path = _write_bag(tmp_path / "dup", {"/imu": _imu_topic(types, ns)})
    with pytest.raises(InputError, match=r"topic /imu: message 3 has header stamp .* repeats message 2"):
        read(path, {"format": "rosbag"})
    assert read(path, {"format": "rosbag", "stamp": "receive"}).n == 6  # the record times do increase
    ns = [START + k * 10_000_000 for k in range(6)]
    ns[4], ns[5] = ns[5], ns[4]
    path = _write_bag(tmp_path / "swap", {"/imu": _imu_topic(types, ns)})
    with pytest.raises(InputError, match=r"message 5 .* is before message 4"):
        read(path, {"format": "rosbag"})


def test_odometry_velocity_items(tmp_path):
    from scipy.spatial.transform import Rotation

    from bvpnav.readers.rosbag import _msg_header

    types = _typestore().types
    ns = [START + k * 10_000_000 for k in range(11)]
    yaw = Rotation.from_euler("z", 90, degrees=True)
    qx, qy, qz, qw = yaw.as_quat()
    cov = np.zeros(36)
    cov[[0, 7, 14]] = [0.01, 0.04, 0.09]
    v3 = types["geometry_msgs/msg/Vector3"]
    odom = []
    for k, t in enumerate([START - 5_000_000, START + 20_000_000, START + 60_000_000]):
        msg = types[ODOMETRY_TYPE](
            header=_msg_header(types, t, "odom"), child_frame_id="base_link",
            pose=types["geometry_msgs/msg/PoseWithCovariance"](
                pose=types["geometry_msgs/msg/Pose"](position=types["geometry_msgs/msg/Point"](0.0, 0.0, 0.0),
                                                     orientation=types["geometry_msgs/msg/Quaternion"](
                                                         qx, qy, qz, qw)),
                covariance=np.zeros(36)),
            twist=types["geometry_msgs/msg/TwistWithCovariance"](
                twist=types["geometry_msgs/msg/Twist"](linear=v3(1.0 + k, 0, 0), angular=v3(0, 0, 0)),
                covariance=cov))
        odom.append((t + 2000, msg, ODOMETRY_TYPE))
    path = _write_bag(tmp_path / "odom", {"/imu": _imu_topic(types, ns), "/odom": odom})
    assert read(path, {"format": "rosbag"}).items == ()  # odometry only when asked for
    rec = read(path, {"format": "rosbag", "odometry_topic": "/odom"})
    (vel,) = rec.items
    assert isinstance(vel, Velocity)
    assert np.allclose(vel.t, [0.02, 0.06], atol=1e-15)
    assert np.allclose(vel.value, [[0.0, 2.0, 0.0], [0.0, 3.0, 0.0]], atol=1e-12)  # body x -> ENU north
    assert np.allclose(vel.sigma, np.sqrt([0.04, 0.01, 0.09]))  # diag(R C R^T)
    assert any("1 of 3 Odometry messages" in n for n in rec.notes)
    assert any("assumed to be the navigation frame" in n for n in rec.notes)


def test_missing_rosbags_names_the_extra(bag, monkeypatch):
    monkeypatch.setitem(sys.modules, "rosbags", None)  # import rosbags now raises ImportError
    with pytest.raises(InputError, match=r"pip install 'bvpnav\[ros\]'"):
        read(bag.path, {"format": "rosbag"})


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_corrupt_bag_named(tmp_path, storage):
    ex = write_example_bag(tmp_path / "c", duration=2.0, rate=50.0, storage=storage)
    data = ex.storage_file.read_bytes()
    ex.storage_file.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match="corrupt|cannot open") as err:
        read(ex.storage_file, {"format": "rosbag"})
    assert ex.storage_file.name in str(err.value)
    junk = tmp_path / "junk.bag"
    junk.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 100)
    with pytest.raises(InputError, match="junk.bag"):
        read(junk)
    assert reader_for(junk).name == "rosbag"


def test_end_to_end_solve_recovers_truth(tmp_path):
    """From a generated ROS 2 bag (Imu + NavSatFix) to the trajectory.

    The motion is a spline with waypoints on the 100 Hz grid, so the FEM is exact for the
    noise-free accelerations; the error is what the data leave undetermined. With IMU
    white noise (0.02 m/s^2, 0.002 rad/s, the attitude from the messages) and 9 fixes of
    sigma 0.05 m inside the 10 s window, the fitted start position and velocity have
    standard deviations about sigma * sqrt(4 / 9) = 0.033 m at the ends; measured max
    error 0.08 m (seed 3). Tolerance 0.15 m = 3 sigma. With (nearly) exact fixes, sigma
    1e-4 m, the whole chain (clock, frames, geodesy, gravity) must agree to 1e-3 m.
    """
    ex = write_example_bag(tmp_path / "run", duration=10.0, rate=100.0, accel_noise=0.02, gyro_noise=0.002,
                           seed=3)
    rec = read(ex.path, {"format": "rosbag", "origin": list(ex.origin)})
    prob = bvpnav.NavigationProblem(rec.imu_data({"frame": "enu"}))
    for item in rec.items:
        prob.add(item)
    sol = prob.solve()
    truth = ex.truth[["x", "y", "z"]].to_numpy()
    assert np.allclose(sol.trajectory.index.to_numpy(), ex.truth.index.to_numpy(), atol=1e-12)
    assert np.abs(sol.position() - truth).max() < 0.15
    exact = write_example_bag(tmp_path / "exact", duration=10.0, rate=100.0, gnss_sigma=1e-4, seed=3)
    rec = read(exact.path, {"format": "rosbag", "origin": list(exact.origin)})
    sol = bvpnav.NavigationProblem(rec.imu_data()).add(rec.items[0]).solve()
    assert np.abs(sol.position() - truth).max() < 1e-3


def test_ros1_bag(tmp_path):
    """A ROS 1 .bag (rosbags' ROS 1 writer, Noetic types): the same channels and exact times."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    types = store.types
    vec, quat = types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Quaternion"]
    path = tmp_path / "run.bag"
    ns = [START + k * 5_000_000 for k in range(8)]
    with Writer(path) as writer:
        conn = writer.add_connection("/imu", IMU_TYPE, typestore=store)
        for k, t in enumerate(ns):
            header = types["std_msgs/msg/Header"](seq=k, stamp=types["builtin_interfaces/msg/Time"](
                sec=t // 10**9, nanosec=t % 10**9), frame_id="imu")
            msg = types[IMU_TYPE](header=header, orientation=quat(0.0, 0.0, 0.0, 1.0),
                                  orientation_covariance=np.r_[-1.0, np.zeros(8)],
                                  angular_velocity=vec(0.01 * k, 0.0, 0.0),
                                  angular_velocity_covariance=np.zeros(9),
                                  linear_acceleration=vec(0.0, 0.0, 9.8),
                                  linear_acceleration_covariance=np.zeros(9))
            writer.write(conn, t + 1000, store.serialize_ros1(msg, IMU_TYPE))
    assert get_reader("rosbag").sniff(path.read_bytes()[:4096]) and reader_for(path).name == "rosbag"
    rec = read(path)
    assert rec.time_origin == f"{START} ns" and np.array_equal(rec.t, np.arange(8) * 5_000_000 * 1e-9)
    assert np.allclose(rec.gyro[:, 0], 0.01 * np.arange(8)) and rec.attitude is None
