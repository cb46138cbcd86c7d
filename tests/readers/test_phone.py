"""The phone (Sensor Logger) reader: contract, clocks, resampling accuracy, refusals, zip."""

from __future__ import annotations

import shutil
import zipfile

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from bvpnav.errors import InputError
from bvpnav.readers import get_reader, read, reader_for
from bvpnav.readers.phone import write_example_export, write_export, zip_export
from bvpnav.testing import check_reader

T0 = 1_718_030_736_872_695_300
G = np.array([0.0, 0.0, 9.80665])  # specific force at rest, device level: +g up


def _ns(start: int, step: int, n: int) -> np.ndarray:
    return start + step * np.arange(n, dtype=np.int64)


def _w(t):
    """Analytic gyro rates, rad/s; |w''| <= 9."""
    return np.column_stack([np.sin(3 * t), np.cos(2 * t), 0.1 * t])


def _rot(t):
    """Analytic attitude: a turn about a fixed axis by 0.8 sin(1.5 t) rad; |angle''| <= 1.8."""
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    return Rotation.from_rotvec(np.outer(0.8 * np.sin(1.5 * t), axis))


def test_contract(tmp_path):
    rec = check_reader(get_reader("phone"), tmp_path)  # its example is a .zip
    assert rec.attitude is not None and rec.attitude_frame == "enu" and rec.gyro is not None


def test_folder_is_read_and_a_bag_folder_is_refused(tmp_path):
    ex = write_example_export(tmp_path / "e", duration=2.0)
    rec = read(ex.path, {"format": "phone"})
    assert rec.n == ex.acc_ns.size and rec.source.endswith("TotalAcceleration.csv")
    (tmp_path / "bag").mkdir()
    (tmp_path / "bag" / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    with pytest.raises(InputError, match='ROS 2 bag folder.*format = "rosbag"'):
        read(tmp_path / "bag", {"format": "phone"})


def test_times_exact_units_and_truth(tmp_path):
    ex = write_example_export(tmp_path / "e", duration=2.0)
    rec = read(ex.path, {"format": "phone"})
    assert rec.time_origin == f"{ex.acc_ns[0]} ns"
    assert np.array_equal(rec.t, (ex.acc_ns - ex.acc_ns[0]).astype(float) * 1e-9)
    assert np.array_equal(rec.specific_force, ex.simulation.specific_force)  # columns z, y, x reordered
    acc = ex.simulation.truth[["ax", "ay", "az"]].to_numpy()
    assert np.abs(rec.imu_data().acc - acc).max() < 2e-3  # attitude slerped from 50 Hz
    notes = " ".join(rec.notes)
    assert "TotalAcceleration.csv" in notes and "linear interpolation" in notes and "slerp" in notes
    assert "-0.004000 s" in notes and "0.997" in notes  # the gyro clock's offset and rate ratio, stated


def test_resampling_matches_analytic_signals(tmp_path):
    """Linear interpolation of the rates and slerp of the attitude, against the exact values.

    Bounds: linear interpolation errs by at most h^2/8 max|f''| (h the sensor's step):
    gyro h = 10.03 ms, |w''| <= 9 -> 1.13e-4 rad/s; for a turn about a fixed axis slerp is
    linear interpolation of the angle: h = 20 ms, |angle''| <= 1.8 -> 9e-5 rad.
    """
    acc_ns = _ns(T0, 10_000_000, 301)
    gyro_ns = _ns(T0 - 3_000_000, 10_030_000, 302)
    ori_ns = _ns(T0 - 10_000_000, 20_000_000, 152)
    tg, to = (gyro_ns - T0) * 1e-9, (ori_ns - T0) * 1e-9
    f = np.tile(G, (acc_ns.size, 1))
    write_export(tmp_path / "a", acc_ns=acc_ns, acc=f, gyro_ns=gyro_ns, gyro=_w(tg), orientation_ns=ori_ns,
                 quat=_rot(to).as_quat())
    rec = read(tmp_path / "a", {"format": "phone"})
    t = rec.t
    assert np.abs(rec.gyro - _w(t)).max() <= 0.010030**2 / 8 * 9 * 1.001
    assert (rec.attitude * _rot(t).inv()).magnitude().max() <= 0.020**2 / 8 * 1.8 * 1.001
    # samples that coincide are reproduced exactly (to rounding)
    same = np.isin(acc_ns, ori_ns)
    assert same.sum() > 10
    assert (rec.attitude[same] * _rot(t[same]).inv()).magnitude().max() < 1e-12


def test_sensor_not_covering_refused_or_cropped(tmp_path):
    acc_ns = _ns(T0, 10_000_000, 101)
    gyro_ns = _ns(T0 + 50_000_000, 10_000_000, 96)  # starts 50 ms late
    f = np.tile(G, (acc_ns.size, 1))
    write_export(tmp_path / "late", acc_ns=acc_ns, acc=f, gyro_ns=gyro_ns, gyro=_w((gyro_ns - T0) * 1e-9))
    with pytest.raises(InputError, match=r"Gyroscope\.csv' starts 0\.050000 s after .* crop = true"):
        read(tmp_path / "late", {"format": "phone"})
    rec = read(tmp_path / "late", {"format": "phone", "crop": True})
    assert rec.n == 96 and rec.time_origin == f"{T0 + 50_000_000} ns"
    assert any("crop = true: 5 TotalAcceleration.csv samples" in n for n in rec.notes)
    assert np.allclose(rec.gyro, _w((gyro_ns - T0) * 1e-9), atol=1e-12)  # coinciding samples


def test_user_acceleration_needs_gravity(tmp_path):
    acc_ns = _ns(T0, 10_000_000, 51)
    user = np.column_stack([0.1 * np.sin(np.arange(51)), np.zeros(51), np.zeros(51)])
    g_ns = _ns(T0 - 5_000_000, 10_000_000, 52)
    kw = dict(acc_ns=acc_ns, acc=user, gyro_ns=acc_ns, gyro=np.zeros((51, 3)), total=False)
    write_export(tmp_path / "user", **kw)
    with pytest.raises(InputError, match="Accelerometer.csv .gravity removed. together with Gravity.csv"):
        read(tmp_path / "user", {"format": "phone"})
    write_export(tmp_path / "both", **kw, gravity=(g_ns, np.tile(G, (52, 1))))
    rec = read(tmp_path / "both", {"format": "phone"})
    assert np.allclose(rec.specific_force, user + G, atol=1e-12)
    assert any("Accelerometer.csv (user acceleration) + Gravity.csv" in n for n in rec.notes)


def test_not_a_specific_force_refused(tmp_path):
    acc_ns = _ns(T0, 10_000_000, 51)
    write_export(tmp_path / "flip", acc_ns=acc_ns, acc=np.tile(-G, (51, 1)), orientation_ns=acc_ns,
                 quat=np.tile([0.0, 0.0, 0.0, 1.0], (51, 1)))
    with pytest.raises(InputError, match=r"upward component .* -9\.81 m/s\^2.*not a specific force"):
        read(tmp_path / "flip", {"format": "phone"})


def test_bad_times_and_columns_named(tmp_path):
    acc_ns = _ns(T0, 10_000_000, 21)
    acc_ns[7] = acc_ns[6]
    write_export(tmp_path / "dup", acc_ns=acc_ns, acc=np.tile(G, (21, 1)), gyro_ns=_ns(T0, 10_000_000, 21),
                 gyro=np.zeros((21, 3)))
    with pytest.raises(InputError, match=r"Acceleration\.csv': data row 8 has time .* the same as row 7"):
        read(tmp_path / "dup", {"format": "phone"})
    folder = tmp_path / "cols"
    shutil.copytree(tmp_path / "dup", folder)
    (folder / "Gyroscope.csv").write_text("time,seconds_elapsed,a,b\n1,0.0,1,2\n2,0.1,1,2\n")
    (folder / "TotalAcceleration.csv").unlink()
    (folder / "TotalAcceleration.csv").write_text((tmp_path / "dup" / "Gyroscope.csv").read_text())
    with pytest.raises(InputError, match=r"Gyroscope\.csv': no column\(s\) \['x', 'y', 'z'\]"):
        read(folder, {"format": "phone"})


def test_orientation_option_and_gyro_integration(tmp_path):
    ex = write_example_export(tmp_path / "e", duration=2.0)
    rec = read(ex.path, {"format": "phone", "orientation": False})
    assert rec.attitude is None and rec.gyro is not None
    sim = ex.simulation
    data = rec.imu_data({"initial_attitude": {"quaternion": list(sim.attitude[0].as_quat())}})
    assert np.abs(data.acc - sim.truth[["ax", "ay", "az"]].to_numpy()).max() < 0.02


def test_zip_export(tmp_path):
    ex = write_example_export(tmp_path / "e", duration=2.0)
    archive = zip_export(ex.path, tmp_path / "export.zip")
    assert zipfile.ZipFile(archive).namelist()[0] == "e/TotalAcceleration.csv"
    reader = get_reader("phone")
    assert reader_for(archive) is reader and reader.sniff(archive.read_bytes()[:4096])
    a, b = read(archive), read(ex.path, {"format": "phone"})
    assert np.array_equal(a.t, b.t) and np.array_equal(a.gyro, b.gyro)
    assert "export.zip!" in a.source
    cut = tmp_path / "cut.zip"
    cut.write_bytes(archive.read_bytes()[:300])
    with pytest.raises(InputError, match="cut.zip"):
        read(cut)
    assert not reader.sniff(b"PK\x03\x04" + b"\x00" * 26 + b"other.txt")
