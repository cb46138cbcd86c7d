"""From the files users have to a trajectory in one `bvpnav solve` call."""

from __future__ import annotations

import datetime as dt
import json

import numpy as np
import pandas as pd
import pytest
from _hostile import EXIT_INPUT, EXIT_OK, assert_clean_failure, main_cli

pytest.importorskip("pynmea2")
pymap3d = pytest.importorskip("pymap3d")

from bvpnav import simulate  # noqa: E402
from bvpnav.readers.nmea import format_gga, format_rmc  # noqa: E402

ORIGIN = (48.1173, 11.5167, 520.0)
START = dt.datetime(2026, 5, 1, 10, 0, 0, tzinfo=dt.timezone.utc)


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    """An IMU table with ISO timestamps and an NMEA log of the same motion, its clock 0.5 s later."""
    d = tmp_path_factory.mktemp("drive")
    sim = simulate.strapdown_3d_2010(rate=20.0, duration=20.0, noise=0.02, seed=3)
    t = sim.t
    q = sim.attitude.as_quat()
    stamps = [(START + dt.timedelta(seconds=float(s))).isoformat().replace("+00:00", "Z") for s in t]
    rec = pd.DataFrame({"time": stamps, **{f"f_{a}": sim.specific_force[:, k] for k, a in enumerate("xyz")},
                        **{f"q{a}": q[:, k] for k, a in enumerate("xyzw")}})
    rec.to_csv(d / "imu.csv", index=False, float_format="%.17g")
    tf = np.arange(0.5, 20.0, 1.0)  # fixes at 0.5, 1.5, ... s on the IMU's clock
    enu = sim.position(tf)
    lat, lon, h = pymap3d.enu2geodetic(enu[:, 0], enu[:, 1], enu[:, 2], *ORIGIN)
    lines = []
    for k, s in enumerate(tf):
        tod = 36000.0 + s
        lines.append(format_gga(tod, lat[k], lon[k], h[k], hdop=0.2))
        lines.append(format_rmc(tod, START.date(), lat[k], lon[k], 0.0, 0.0, status="V"))
    (d / "fixes.nmea").write_text("".join(ln + "\r\n" for ln in lines))
    (d / "spec.toml").write_text("""\
[input]
time = "time"
time_unit = "iso8601"
specific_force = ["f_x", "f_y", "f_z"]
attitude = { quaternion = ["qx", "qy", "qz", "qw"], scalar = "last" }
attitude_frame = "enu"

[problem]
sigma_a = 0.02

[solve]
solver = "direct"
lam = 1.0

[[error_model]]
type = "bias"
""")
    return d, sim


def test_an_imu_table_and_an_nmea_log_give_a_trajectory_and_its_geodetic_coordinates(drive, tmp_path):
    d, sim = drive
    out, geo = tmp_path / "traj.csv", tmp_path / "geo.csv"
    proc = main_cli(["solve", d / "imu.csv", "--spec", d / "spec.toml", "--info", d / "fixes.nmea",
                     "--origin", *ORIGIN, "--out", out, "--geodetic", geo, "-v"])
    assert proc.returncode == EXIT_OK, proc.stderr
    # both clocks are UTC: the log's t = 0 is its first fix, 0.5 s after the IMU's first sample
    assert "fixes.nmea: times shifted by +0.500000000 s" in proc.stderr, proc.stderr
    traj = pd.read_csv(out)
    err = traj[["x", "y", "z"]].to_numpy() - sim.position(traj.t.to_numpy())
    rms = float(np.sqrt(np.mean(np.sum(err**2, axis=1))))
    assert rms < 0.5, rms  # fixes every 1 s (HDOP 0.2, sigma 0.7 m per axis), bias estimated
    g = pd.read_csv(geo)
    assert list(g.columns) == ["t", "lat", "lon", "height"]
    e, n, u = pymap3d.geodetic2enu(g.lat, g.lon, g.height, *ORIGIN)
    np.testing.assert_allclose(np.column_stack([e, n, u]), traj[["x", "y", "z"]], rtol=0, atol=1e-3)


def test_without_a_stated_clock_relation_the_log_is_refused(drive, tmp_path):
    d, _ = drive
    rec = pd.read_csv(d / "imu.csv")
    rec["time"] = np.arange(len(rec)) * 0.05  # relative seconds: no absolute origin
    rec.to_csv(tmp_path / "rel.csv", index=False, float_format="%.17g")
    spec = (d / "spec.toml").read_text().replace('time_unit = "iso8601"', 'time_unit = "s"')
    spec = spec.replace('[[error_model]]\ntype = "bias"\n', '[[item]]\ntype = "position"\nt = [0.0, 19.95]\n'
                        'value = 0.0\n')
    (tmp_path / "spec.toml").write_text(spec)
    proc = main_cli(["solve", tmp_path / "rel.csv", "--spec", tmp_path / "spec.toml", "--info",
                     d / "fixes.nmea", "--out", tmp_path / "traj.csv"])
    assert_clean_failure(proc, EXIT_INPUT, r"not known to be one", r"--clock-offset SECONDS")
    assert not (tmp_path / "traj.csv").exists()
    proc = main_cli(["solve", tmp_path / "rel.csv", "--spec", tmp_path / "spec.toml", "--out",
                     tmp_path / "t2.csv", "--geodetic", tmp_path / "g.csv"])
    assert_clean_failure(proc, EXIT_INPUT, r"--geodetic: the local frame's geodetic origin is not known",
                         r"--origin LAT LON HEIGHT")


def test_a_ros2_bag_with_imu_and_navsatfix_to_a_trajectory_and_a_plot_in_one_call(tmp_path):
    pytest.importorskip("rosbags")
    from bvpnav.readers.rosbag import write_example_bag

    bag = write_example_bag(tmp_path / "drive", duration=8.0, rate=50.0, accel_noise=0.05, gyro_noise=0.002,
                            seed=4)
    spec = '[problem]\nsigma_a = 0.05\n\n[solve]\nsolver = "direct"\nlam = 1.0\n'
    (tmp_path / "spec.toml").write_text(spec)
    out, png, geo = tmp_path / "traj.csv", tmp_path / "traj.png", tmp_path / "geo.csv"
    proc = main_cli(["solve", bag.path, "--spec", tmp_path / "spec.toml", "--out", out, "--plot", png,
                     "--geodetic", geo, "-v"])
    assert proc.returncode == EXIT_OK, proc.stderr
    assert "t = 0 at the first Imu stamp" in proc.stderr  # the reader's notes are said
    traj = pd.read_csv(out).set_index("t")
    truth = bag.truth
    np.testing.assert_allclose(traj.index, truth.index, rtol=0, atol=1e-12)
    err = np.abs(traj[["x", "y", "z"]].to_numpy() - truth[["x", "y", "z"]].to_numpy()).max()
    assert err < 0.3, err  # 0.05 m fixes every 1 s, 0.05 m/s^2 accelerometer noise
    assert png.stat().st_size > 20_000
    g = pd.read_csv(geo)
    used = json.loads(out.with_suffix(".json").read_text())["run"]["geodetic_origin"]  # the first fix
    e, n, u = pymap3d.geodetic2enu(g.lat, g.lon, g.height, *used)
    np.testing.assert_allclose(np.column_stack([e, n, u]), traj[["x", "y", "z"]], rtol=0, atol=1e-3)
    e, n, u = pymap3d.geodetic2enu(g.lat, g.lon, g.height, *bag.origin)  # the truth's own frame
    assert np.abs(np.column_stack([e, n, u]) - truth[["x", "y", "z"]].to_numpy()).max() < 0.3
    ned = tmp_path / "ned.toml"
    ned.write_text('[input]\nframe = "ned"\n\n' + (tmp_path / "spec.toml").read_text())
    proc = main_cli(["solve", bag.path, "--spec", ned, "--out", tmp_path / "t3.csv"])
    assert_clean_failure(proc, EXIT_INPUT, r'set frame = "enu"',
                         r"are in the local ENU frame but the spec's \[input\] frame is 'ned'")
