"""Odometer readings from the readers (issue 39 item 7): ROS Odometry / TwistStamped topics and
NMEA speed over ground, on small synthetic files written here."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from bvpnav.constraints import Odometer, Position, Velocity
from bvpnav.errors import InputError

START = 1_700_000_000_123_456_789


# ------------------------------------------------------------------ ROS bags
@pytest.fixture(scope="module")
def ros():
    pytest.importorskip("rosbags")
    from bvpnav.readers.rosbag import _typestore

    return _typestore().types


def _header(types, ns: int, frame: str):
    from bvpnav.readers.rosbag import _msg_header

    return _msg_header(types, ns, frame)


def _write(path, topics):
    from rosbags.rosbag2 import Writer

    from bvpnav.readers.rosbag import _typestore

    store = _typestore()
    with Writer(path, version=9) as writer:
        conns = {t: writer.add_connection(t, msgs[0][2], typestore=store) for t, msgs in topics.items()}
        rows = sorted((r, t, m, typ) for t, msgs in topics.items() for r, m, typ in msgs)
        for recv, topic, msg, typ in rows:
            writer.write(conns[topic], recv, store.serialize_cdr(msg, typ))
    return path


def _imu(types, n: int = 11):
    from bvpnav.readers.rosbag import IMU_TYPE

    vec, quat = types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Quaternion"]
    out = []
    for k in range(n):
        ns = START + k * 10_000_000
        msg = types[IMU_TYPE](header=_header(types, ns, "imu"), orientation=quat(0.0, 0.0, 0.0, 1.0),
                              orientation_covariance=np.r_[-1.0, np.zeros(8)], angular_velocity=vec(0, 0, 0),
                              angular_velocity_covariance=np.zeros(9), linear_acceleration=vec(0, 0, 9.80665),
                              linear_acceleration_covariance=np.zeros(9))
        out.append((ns + 1000, msg, IMU_TYPE))
    return out


def _odometry(types, speeds, cov0: float = 0.01):
    from scipy.spatial.transform import Rotation

    from bvpnav.readers.rosbag import ODOMETRY_TYPE

    qx, qy, qz, qw = Rotation.from_euler("z", 90, degrees=True).as_quat()
    v3 = types["geometry_msgs/msg/Vector3"]
    cov = np.zeros(36)
    cov[[0, 7, 14]] = [cov0, 0.04, 0.09]
    out = []
    for k, (t, s) in enumerate(zip([START - 5_000_000, START + 20_000_000, START + 60_000_000], speeds,
                                   strict=True)):
        msg = types[ODOMETRY_TYPE](
            header=_header(types, t, "odom"), child_frame_id="base_link",
            pose=types["geometry_msgs/msg/PoseWithCovariance"](
                pose=types["geometry_msgs/msg/Pose"](position=types["geometry_msgs/msg/Point"](0.0, 0.0, 0.0),
                                                     orientation=types["geometry_msgs/msg/Quaternion"](
                                                         qx, qy, qz, qw)),
                covariance=np.zeros(36)),
            twist=types["geometry_msgs/msg/TwistWithCovariance"](
                twist=types["geometry_msgs/msg/Twist"](linear=v3(s, 0.3 * k, 0), angular=v3(0, 0, 0)),
                covariance=cov))
        out.append((t + 2000, msg, ODOMETRY_TYPE))
    return out


def _twist_stamped(types, speeds):
    from bvpnav.readers.rosbag import TWIST_STAMPED_TYPE

    v3 = types["geometry_msgs/msg/Vector3"]
    out = []
    for k, s in enumerate(speeds):
        ns = START + 15_000_000 + k * 20_000_000
        msg = types[TWIST_STAMPED_TYPE](header=_header(types, ns, "base_link"),
                                        twist=types["geometry_msgs/msg/Twist"](linear=v3(s, 0, 0),
                                                                               angular=v3(0, 0, 0)))
        out.append((ns + 500, msg, TWIST_STAMPED_TYPE))
    return out


def test_odometry_topic_as_an_odometer(tmp_path, ros):
    from bvpnav.readers import read

    path = _write(tmp_path / "odom", {"/imu": _imu(ros), "/odom": _odometry(ros, [1.0, 2.0, 3.0])})
    # default: the twist rotated into the odometry frame, a Velocity item (unchanged)
    (vel,) = read(path, {"format": "rosbag", "odometry_topic": "/odom"}).items
    assert isinstance(vel, Velocity)
    rec = read(path, {"format": "rosbag", "odometry_topic": "/odom", "odometry_as": "odometer",
                      "odometer_lever": [-1.0, 0.0, -0.3]})
    (odo,) = rec.items
    assert isinstance(odo, Odometer) and odo.label == "Odometry /odom"
    np.testing.assert_allclose(odo.t, [0.02, 0.06], atol=1e-15)   # the one before the IMU dropped
    np.testing.assert_allclose(odo.speed, [2.0, 3.0])             # twist.linear.x, not rotated
    np.testing.assert_allclose(odo.sigma, [0.1, 0.1])             # sqrt(covariance[0])
    np.testing.assert_allclose(odo.lever, [-1.0, 0.0, -0.3])
    assert odo.axis == "x" and odo.mode == "soft"
    assert any("Odometer item along body x" in n and "odometer_scale" in n for n in rec.notes)
    # a stated sigma wins over the covariance
    (odo,) = read(path, {"format": "rosbag", "odometry_topic": "/odom", "odometry_as": "odometer",
                         "odometry_sigma": 0.05}).items
    np.testing.assert_allclose(odo.sigma, [0.05, 0.05])


def test_wheel_speed_topic(tmp_path, ros):
    from bvpnav.readers import read

    path = _write(tmp_path / "ws", {"/imu": _imu(ros), "/wheel_speed": _twist_stamped(ros, [4.0, 4.5, 5.0])})
    with pytest.raises(InputError, match=r"/wheel_speed .*no covariance; set \[input\] speed_sigma"):
        read(path, {"format": "rosbag", "speed_topic": "/wheel_speed"})
    rec = read(path, {"format": "rosbag", "speed_topic": "/wheel_speed", "speed_sigma": 0.02})
    (odo,) = rec.items
    assert odo.label == "wheel speed /wheel_speed"
    np.testing.assert_allclose(odo.t, [0.015, 0.035, 0.055], atol=1e-15)
    np.testing.assert_allclose(odo.speed, [4.0, 4.5, 5.0])
    np.testing.assert_allclose(odo.sigma, 0.02)
    assert rec.meta["speed_topic"] == "/wheel_speed"


def test_odometer_topics_refuse_bad_data_naming_topic_and_message(tmp_path, ros):
    from bvpnav.readers import read

    path = _write(tmp_path / "nan", {"/imu": _imu(ros), "/odom": _odometry(ros, [1.0, np.nan, 3.0])})
    with pytest.raises(InputError, match=r"topic /odom: message 1 has a non-finite forward speed"):
        read(path, {"format": "rosbag", "odometry_topic": "/odom", "odometry_as": "odometer"})
    path = _write(tmp_path / "cov", {"/imu": _imu(ros), "/odom": _odometry(ros, [1.0, 2.0, 3.0], cov0=0.0)})
    with pytest.raises(InputError, match=r"/odom: message 1 has twist covariance\[0\] = 0.0.*odometry_sigma"):
        read(path, {"format": "rosbag", "odometry_topic": "/odom", "odometry_as": "odometer"})
    with pytest.raises(InputError, match=r"odometry_as = 'wheel'"):
        read(path, {"format": "rosbag", "odometry_topic": "/odom", "odometry_as": "wheel"})
    with pytest.raises(InputError, match=r"odometer_lever = \[1.0, 2.0\]"):
        read(path, {"format": "rosbag", "odometry_topic": "/odom", "odometry_as": "odometer",
                    "odometer_lever": [1.0, 2.0]})
    with pytest.raises(InputError, match=r"'/odom' is nav_msgs/msg/Odometry, not geometry_msgs/msg/Twist"):
        read(path, {"format": "rosbag", "speed_topic": "/odom"})


# ------------------------------------------------------------------ NMEA
def _nmea_log(tmp_path, vtg_speed: str = "036.0", name: str = "drive.nmea"):
    """Five 1 Hz epochs: GGA + RMC (10 m/s) at 0-1 s, GGA + VTG at 2-4 s (at 2 s with mode N,
    not valid; at 3 s in km/h; at 4 s in knots only), and a VTG after the RMC of 1 s (a
    repeated time)."""
    from bvpnav.readers.nmea import KNOT, format_gga, format_rmc, sentence

    date = dt.date(2026, 5, 1)
    t0 = 12 * 3600.0
    lines = []
    for k in range(5):
        lat, lon = 48.1 + 1e-5 * k, 11.5
        lines.append(format_gga(t0 + k, lat, lon, 520.0))
        if k < 2:
            lines.append(format_rmc(t0 + k, date, lat, lon, 10.0, 0.0))
        if k == 1:
            lines.append(sentence("GPVTG,000.0,T,,M,019.4,N,036.0,K,A"))   # same time as the RMC
        if k == 2:
            lines.append(sentence("GPVTG,000.0,T,,M,019.4,N,036.0,K,N"))
        if k == 3:
            lines.append(sentence(f"GPVTG,000.0,T,,M,019.4,N,{vtg_speed},K,A"))
        if k == 4:
            lines.append(sentence(f"GPVTG,000.0,T,,M,{10.5 / KNOT:.4f},N,,K,D"))
    path = tmp_path / name
    path.write_text("".join(line + "\r\n" for line in lines))
    return path


def test_nmea_speed_over_ground_as_an_odometer(tmp_path):
    pytest.importorskip("pynmea2")
    pytest.importorskip("pymap3d")
    from bvpnav.readers import read

    path = _nmea_log(tmp_path)
    rec = read(path, {"format": "nmea", "speed_as": "odometer", "velocity_sigma": 0.1,
                      "odometer_lever": [0.5, 0.0, 1.2]})
    pos, odo = rec.items
    assert isinstance(pos, Position) and isinstance(odo, Odometer)
    assert odo.label == "drive.nmea speed over ground" and odo.scaled is False
    np.testing.assert_allclose(odo.t, [0.0, 1.0, 3.0, 4.0])
    np.testing.assert_allclose(odo.speed, [10.0, 10.0, 10.0, 10.5], rtol=1e-5)  # 4 decimals of knots
    np.testing.assert_allclose(odo.sigma, 0.1)
    np.testing.assert_allclose(odo.lever, [0.5, 0.0, 1.2])
    assert any("4 RMC/VTG speeds over ground as a soft Odometer item" in n for n in rec.notes)
    assert any("Dropped RMC/VTG speeds: 1 repeated time, 1 status void" in n for n in rec.notes)
    # the default reads RMC speed and course as a Velocity item and ignores VTG, saying so
    rec = read(path, {"format": "nmea"})
    assert isinstance(rec.items[1], Velocity) and rec.items[1].t.size == 2
    assert any("Ignored sentences (only GGA, RMC and GST are read): 4 VTG" in n for n in rec.notes)


def test_nmea_bad_speed_is_refused_naming_the_line(tmp_path):
    pytest.importorskip("pynmea2")
    from bvpnav.readers import read

    path = _nmea_log(tmp_path, vtg_speed="-3.0")
    with pytest.raises(InputError, match=r"line 9: the VTG speed over ground '-3.0' is not a speed"):
        read(path, {"format": "nmea", "speed_as": "odometer"})
    from bvpnav.readers.nmea import format_gga

    bare = tmp_path / "bare.nmea"
    bare.write_text("".join(format_gga(43200.0 + k, 48.1, 11.5, 520.0) + "\r\n" for k in range(3)))
    with pytest.raises(InputError, match=r"bare.nmea: \[input\] speed_as = \"odometer\", but the log has no "
                       r"usable speed over ground in RMC or VTG sentences .*\(no RMC or VTG sentence\)"):
        read(bare, {"format": "nmea", "speed_as": "odometer"})
    with pytest.raises(InputError, match=r"speed_as = 'wheel'"):
        read(path, {"format": "nmea", "speed_as": "wheel"})
    with pytest.raises(InputError, match=r"odometer_lever = \[1, 2\]"):
        read(path, {"format": "nmea", "speed_as": "odometer", "odometer_lever": [1, 2]})


# ------------------------------------------------------------------ command line
def test_cli_states_an_nmea_speed_over_ground_as_an_odometer(tmp_path):
    """`bvpnav solve imu.csv --spec spec.toml --info log.nmea --info-option speed_as=odometer`: the
    log's VTG speeds become an Odometer item beside its fixes; a key no reader takes is refused."""
    pytest.importorskip("pynmea2")
    pymap3d = pytest.importorskip("pymap3d")
    import json

    import pandas as pd
    from _hostile import EXIT_INPUT, EXIT_OK, assert_clean_failure, main_cli

    from bvpnav.readers.nmea import format_gga, sentence
    from bvpnav.scenarios import car_drive

    origin, start = (48.1173, 11.5167, 520.0), dt.datetime(2026, 5, 1, 10, 0, 0, tzinfo=dt.timezone.utc)
    d = car_drive(duration=60.0, rate=10.0, seed=2, heading_error=0.0, tilt_error=0.0)
    stamps = [(start + dt.timedelta(seconds=float(s))).isoformat().replace("+00:00", "Z") for s in d.t]
    q = d.attitude.as_quat()
    pd.DataFrame({"time": stamps, **{f"f_{a}": d.specific_force_true[:, k] for k, a in enumerate("xyz")},
                  **{f"q{a}": q[:, k] for k, a in enumerate("xyzw")}}).to_csv(
        tmp_path / "imu.csv", index=False, float_format="%.17g")
    lat, lon, h = pymap3d.enu2geodetic(d.position[::10, 0], d.position[::10, 1], d.position[::10, 2], *origin)
    ground = np.linalg.norm(d.velocity[::10, :2], axis=1)   # horizontal speed, m/s
    lines = []
    for k, s in enumerate(d.t[::10]):
        lines.append(format_gga(36000.0 + s, lat[k], lon[k], h[k], hdop=0.2))
        lines.append(sentence(f"GPVTG,0.0,T,,M,,N,{ground[k] * 3.6:.4f},K,A"))
    (tmp_path / "log.nmea").write_text("".join(ln + "\r\n" for ln in lines))
    (tmp_path / "spec.toml").write_text("""\
[input]
time = "time"
time_unit = "iso8601"
specific_force = ["f_x", "f_y", "f_z"]
attitude = { quaternion = ["qx", "qy", "qz", "qw"], scalar = "last" }
attitude_frame = "enu"

[problem]
sigma_a = 0.01

[solve]
solver = "direct"
lam = 1.0
""")
    out = tmp_path / "traj.csv"
    base = ["solve", tmp_path / "imu.csv", "--spec", tmp_path / "spec.toml", "--info", tmp_path / "log.nmea",
            "--origin", *origin, "--out", out]
    proc = main_cli([*base, "--info-option", "speed_as=odometer", "--info-option", "velocity_sigma=0.05",
                     "--info-option", "date=2026-05-01"])   # no RMC: the date puts the log on UTC
    assert proc.returncode == EXIT_OK, proc.stderr
    summ = json.loads(out.with_suffix(".json").read_text())
    assert summ["run"]["information_options"] == {"speed_as": "odometer", "velocity_sigma": 0.05,
                                                  "date": "2026-05-01"}
    (odo,) = [row for row in summ["items"] if row["item"] == "log.nmea speed over ground"]
    assert odo["class"] == "Odometer" and odo["rows"] == 61 and odo["rms"] < 0.05   # m/s
    traj = pd.read_csv(out)
    err = traj[["x", "y", "z"]].to_numpy() - d.truth_at(traj.t.to_numpy())
    assert float(np.sqrt(np.mean(np.sum(err**2, axis=1)))) < 0.05   # m: exact fixes, noise-free IMU
    proc = main_cli([*base, "--info-option", "speed_as=odometer", "--info-option", "odometry_as=odometer",
                     "--info-option", "date=2026-05-01", "--out", tmp_path / "t2.csv"])
    assert_clean_failure(proc, EXIT_INPUT, r"information option\(s\) \['odometry_as'\]", r"speed_as")
    proc = main_cli([*base, "--info-option", "speed_as"])
    assert_clean_failure(proc, EXIT_INPUT, r"--info-option 'speed_as': give KEY=VALUE")


# ------------------------------------------------------------------ a column of the recording
def test_a_speed_column_of_a_strapdown_table_to_the_scale_on_the_command_line(tmp_path):
    """A strapdown CSV with a forward-speed column reading 2 % high (`[input] odometer`), fixes
    every 10 s in the spec and `[[error_model]] type = "odometer_scale"`: `bvpnav solve` reports
    the scale, exactly on noise-free data consistent with the FEM."""
    import json
    import sys

    import pandas as pd
    from _hostile import EXIT_INPUT, EXIT_OK, assert_clean_failure, main_cli

    from bvpnav import ImuData
    from bvpnav.readers import read
    from bvpnav.scenarios import car_drive

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parents[1] / "constraints"))
    from test_odometer import _integrate

    d = car_drive(duration=60.0, rate=10.0, seed=5)
    data = ImuData(d.t, specific_force=d.specific_force_true, attitude=d.attitude, gravity=d.gravity,
                   frame="enu")
    r, v = _integrate(data.t, data.acc, d.position[0], d.velocity[0])
    forward = np.einsum("kij,ki->kj", data.attitude.as_matrix(), v)[:, 0]
    q = d.attitude.as_quat()
    pd.DataFrame({"t": d.t, **{f"f_{a}": d.specific_force_true[:, k] for k, a in enumerate("xyz")},
                  **{f"q{a}": q[:, k] for k, a in enumerate("xyzw")}, "speed": 1.02 * forward}).to_csv(
        tmp_path / "drive.csv", index=False, float_format="%.17g")
    k = np.arange(0, d.t.size, 100)
    fixes = "\n".join(f"[[item]]\ntype = \"position\"\nname = \"fix {j}\"\nt = {float(d.t[j])!r}\nvalue = "
                      f"{[float(x) for x in r[j]]!r}\nsigma = 1.0\n" for j in k)
    spec = f"""\
[input]
time = "t"
specific_force = ["f_x", "f_y", "f_z"]
attitude = {{ quaternion = ["qx", "qy", "qz", "qw"], scalar = "last" }}
attitude_frame = "enu"
odometer = "speed"
odometer_sigma = 0.05

[solve]
solver = "direct"
lam = 1.0

[[error_model]]
type = "odometer_scale"

{fixes}"""
    (tmp_path / "spec.toml").write_text(spec)
    quat = {"quaternion": ["qx", "qy", "qz", "qw"], "scalar": "last"}
    rec = read(tmp_path / "drive.csv", {"time": "t", "specific_force": ["f_x", "f_y", "f_z"],
                                        "attitude": quat, "attitude_frame": "enu", "odometer": "speed",
                                        "odometer_sigma": 0.05})
    (odo,) = rec.items
    assert odo.label == "drive.csv column speed" and odo.t.size == d.t.size
    np.testing.assert_allclose(odo.sigma, 0.05)
    out = tmp_path / "traj.csv"
    proc = main_cli(["solve", tmp_path / "drive.csv", "--spec", tmp_path / "spec.toml", "--out", out])
    assert proc.returncode == EXIT_OK, proc.stderr
    summ = json.loads(out.with_suffix(".json").read_text())
    scale = summ["error_model"]["odometer_scale"]
    assert scale["units"] == "1" and abs(scale["estimate"] - 0.02) <= 1e-6 * 0.02, scale
    # the column must be there, and needs its sigma
    (tmp_path / "nosig.toml").write_text(spec.replace("odometer_sigma = 0.05\n", ""))
    proc = main_cli(["solve", tmp_path / "drive.csv", "--spec", tmp_path / "nosig.toml", "--out",
                     tmp_path / "t2.csv"])
    assert_clean_failure(proc, EXIT_INPUT, r"odometer_sigma = None; give the speed's noise")
    (tmp_path / "nocol.toml").write_text(spec.replace('odometer = "speed"', 'odometer = "wheel"'))
    proc = main_cli(["solve", tmp_path / "drive.csv", "--spec", tmp_path / "nocol.toml", "--out",
                     tmp_path / "t3.csv"])
    assert_clean_failure(proc, EXIT_INPUT, r"wheel")


def test_table_odometer_options_are_checked(tmp_path):
    from bvpnav.readers import read

    t = [0.0, 0.1, 0.2, 0.3, 0.4]
    path = tmp_path / "nav.csv"
    path.write_text("t,acc_x,speed\n" + "".join(f"{a!r},0.0,1.0\n" for a in t))
    with pytest.raises(InputError, match=r"odometer needs strapdown columns"):
        read(path, {"odometer": "speed", "odometer_sigma": 0.1})
    strap = {"specific_force": ["acc_x", "acc_x", "acc_x"], "gyro": ["acc_x", "acc_x", "acc_x"]}
    with pytest.raises(InputError, match=r"\['odometer_sigma'\] without odometer = \"<column>\""):
        read(path, {**strap, "odometer_sigma": 0.1})
    with pytest.raises(InputError, match=r"odometer_lever = \[1, 2\]; give \[x, y, z\]"):
        read(path, {**strap, "odometer": "speed", "odometer_sigma": 0.1, "odometer_lever": [1, 2]})
    path.write_text("t,f_x,f_y,f_z,w_x,w_y,w_z,speed\n" + "".join(
        f"{a!r},0.0,0.0,9.80665,0.0,0.0,0.0,{'x' if k == 3 else '1.0'}\n" for k, a in enumerate(t)))
    strap = {"specific_force": ["f_x", "f_y", "f_z"], "gyro": ["w_x", "w_y", "w_z"]}
    with pytest.raises(InputError, match=r"row 3 \(line 5\), column 'speed' is not a number \('x'\)"):
        read(path, {**strap, "odometer": "speed", "odometer_sigma": 0.1})


def test_a_bag_with_wheel_odometry_to_the_scale(tmp_path, ros):
    """A ROS 2 bag of a noise-free car: Imu (specific force, gyro, orientation), NavSatFix every
    5 s and nav_msgs/Odometry at 10 Hz whose forward twist reads 2 % high; read with
    odometry_as = "odometer", solved with OdometerScale: the scale within 1e-6 (the readings are the
    car's true speeds, not the FEM's own at 10 Hz; measured 8.7e-8)."""
    pytest.importorskip("pymap3d")
    from bvpnav import NavigationProblem
    from bvpnav.error_models import OdometerScale
    from bvpnav.readers import read
    from bvpnav.readers.rosbag import IMU_TYPE, NAVSATFIX_TYPE, ODOMETRY_TYPE, _enu_to_geodetic
    from bvpnav.scenarios import car_drive

    d = car_drive(duration=60.0, rate=10.0, seed=6)
    origin = (48.1, 11.5, 500.0)
    vec, quat = ros["geometry_msgs/msg/Vector3"], ros["geometry_msgs/msg/Quaternion"]
    q = d.attitude.as_quat()
    ns = START + np.round(d.t * 1e9).astype(np.int64)
    imu = [(int(n) + 1000, ros[IMU_TYPE](
        header=_header(ros, int(n), "imu"), orientation=quat(*q[k]), orientation_covariance=np.zeros(9),
        angular_velocity=vec(*d.body_rate_true[k]), angular_velocity_covariance=np.zeros(9),
        linear_acceleration=vec(*d.specific_force_true[k]), linear_acceleration_covariance=np.zeros(9)),
        IMU_TYPE) for k, n in enumerate(ns)]
    fk = np.arange(0, d.t.size, 50)
    lat, lon, h = _enu_to_geodetic(d.position[fk], origin)
    status = ros["sensor_msgs/msg/NavSatStatus"]
    fix = [(int(ns[k]) + 2000, ros[NAVSATFIX_TYPE](
        header=_header(ros, int(ns[k]), "gnss"), status=status(status=0, service=1), latitude=float(lat[j]),
        longitude=float(lon[j]), altitude=float(h[j]), position_covariance=np.diag([0.01] * 3).ravel(),
        position_covariance_type=2), NAVSATFIX_TYPE) for j, k in enumerate(fk)]
    forward = np.einsum("kij,ki->kj", d.attitude.as_matrix(), d.velocity)[:, 0]
    cov = np.zeros(36)
    cov[0] = 0.05**2
    odom = [(int(ns[k]) + 3000, ros[ODOMETRY_TYPE](
        header=_header(ros, int(ns[k]), "odom"), child_frame_id="base_link",
        pose=ros["geometry_msgs/msg/PoseWithCovariance"](
            pose=ros["geometry_msgs/msg/Pose"](position=ros["geometry_msgs/msg/Point"](0.0, 0.0, 0.0),
                                               orientation=quat(0.0, 0.0, 0.0, 1.0)),
            covariance=np.zeros(36)),
        twist=ros["geometry_msgs/msg/TwistWithCovariance"](
            twist=ros["geometry_msgs/msg/Twist"](linear=vec(1.02 * forward[k], 0.0, 0.0),
                                                 angular=vec(0, 0, 0)),
            covariance=cov)), ODOMETRY_TYPE) for k in range(d.t.size)]
    path = _write(tmp_path / "car", {"/imu": imu, "/fix": fix, "/odom": odom})
    rec = read(path, {"format": "rosbag", "odometry_topic": "/odom", "odometry_as": "odometer",
                      "origin": list(origin)})
    fixes, odo = rec.items
    assert isinstance(odo, Odometer) and odo.t.size == d.t.size
    np.testing.assert_allclose(odo.sigma, 0.05)
    prob = NavigationProblem(rec.imu_data(), error_model=OdometerScale(), items=rec.items)
    sol = prob.solve(solver="direct")
    assert abs(float(sol.error_params["odometer_scale"]) - 0.02) < 1e-6
