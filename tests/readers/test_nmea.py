"""The nmea reader: the Reader contract, fixes in a local frame (against pymap3d), sigmas
from HDOP and GST, UTC times (dates, midnight), corrupt lines by number, the missing-extra
message, and an end-to-end problem with NMEA fixes and a simulated IMU."""

from __future__ import annotations

import datetime as dt
import math
import sys

import numpy as np
import pytest

import bvpnav
from bvpnav import readers
from bvpnav.constraints import Position, Velocity
from bvpnav.readers import get_reader
from bvpnav.testing import check_reader

pynmea2 = pytest.importorskip("pynmea2")
pymap3d = pytest.importorskip("pymap3d")

from bvpnav.geodesy import geodetic_to_local, local_to_geodetic  # noqa: E402
from bvpnav.readers.nmea import (  # noqa: E402
    EXAMPLE,
    example_lines,
    format_gga,
    format_gst,
    format_rmc,
    sentence,
)

DATE = dt.date(2026, 5, 1)


def _write(tmp_path, lines, name="log.nmea"):
    path = tmp_path / name
    path.write_text("".join(line + "\r\n" for line in lines))
    return path


def _items(rec):
    pos = [i for i in rec.items if isinstance(i, Position)]
    vel = [i for i in rec.items if isinstance(i, Velocity)]
    return pos[0], (vel[0] if vel else None)


def test_reader_contract(tmp_path):
    reader = get_reader("nmea")
    rec = check_reader(reader, tmp_path)
    assert rec.is_information and rec.acc is None and rec.specific_force is None
    assert rec.time_origin == "2026-05-01T10:00:00.000000000Z"
    np.testing.assert_array_equal(rec.t, np.arange(11.0))
    pos, vel = _items(rec)
    assert pos.mode == "soft" and tuple(pos.axes) == ("x", "y", "z")
    assert tuple(vel.axes) == ("x", "y")
    np.testing.assert_allclose(np.reshape(vel.value, (-1, 2)), np.tile(EXAMPLE["velocity"], (11, 1)),
                               atol=1e-3)
    assert rec.meta["geodetic_origin"] == pytest.approx(list(EXAMPLE["origin"]), abs=1e-8)
    assert any("Ignored sentences" in n and "GSV" in n for n in rec.notes)
    assert readers.reader_for(tmp_path / "x.nmea") is reader


def test_sniff_is_strict():
    reader = get_reader("nmea")
    good = "".join(s + "\r\n" for s in example_lines())[:4096].encode()
    assert reader.sniff(good)
    assert not reader.sniff(b"t,acc_x\n0.0,1.0\n0.1,1.1\n")
    assert not reader.sniff(b"$GPGSV,1,1,04*70\r\n")  # no fix sentence
    assert not reader.sniff(b"some text\nmore text\n" + good[:200])  # mostly not NMEA
    assert ".txt" not in reader.suffixes and ".csv" not in reader.suffixes


def test_fix_matches_pymap3d_and_the_truth(tmp_path):
    origin = (48.11, 11.50, 500.0)  # a stated origin, not the first fix
    path = _write(tmp_path, example_lines())
    rec = readers.read(path, {"format": "nmea", "origin": list(origin)})
    pos, _ = _items(rec)
    xyz = np.reshape(pos.value, (-1, 3))
    ggas = [pynmea2.parse(s) for s in example_lines() if "GGA" in s]
    lat = np.array([m.latitude for m in ggas])
    lon = np.array([m.longitude for m in ggas])
    h = np.array([m.altitude + float(m.geo_sep) for m in ggas])
    ref = np.column_stack(pymap3d.geodetic2enu(lat, lon, h, *origin, deg=True))
    np.testing.assert_allclose(xyz, ref, rtol=0, atol=1e-3)
    # the file was written from known local positions about EXAMPLE's origin (0.2 mm, 1 mm in the text)
    k = np.arange(11.0)
    truth = np.column_stack([8.0 * k, 6.0 * k, np.zeros(11)])
    la, lo, hh = local_to_geodetic(truth, EXAMPLE["origin"])
    np.testing.assert_allclose(xyz, geodetic_to_local(la, lo, hh, origin), rtol=0, atol=1.5e-3)
    # round trip of the reader's output back to the fixes' geodetic coordinates
    back = local_to_geodetic(xyz, rec.meta["geodetic_origin"])
    np.testing.assert_allclose(geodetic_to_local(*back, origin), xyz, rtol=0, atol=1e-6)
    assert rec.meta["geodetic_origin"] == list(origin)
    assert any("[input] origin" in n for n in rec.notes)


def test_ned_frame_swaps_axes(tmp_path):
    path = _write(tmp_path, example_lines())
    enu = readers.read(path, {"format": "nmea"})
    ned = readers.read(path, {"format": "nmea", "local_frame": "ned"})
    pe, ve = _items(enu)
    pn, vn = _items(ned)
    e, n = np.reshape(pe.value, (-1, 3)), np.reshape(pn.value, (-1, 3))
    np.testing.assert_allclose(n, np.column_stack([e[:, 1], e[:, 0], -e[:, 2]]), rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.reshape(vn.value, (-1, 2)), np.reshape(ve.value, (-1, 2))[:, ::-1])
    assert ned.meta["frame"] == "ned"


def test_hdop_to_sigma_and_gst(tmp_path):
    o = EXAMPLE["origin"]
    lines = [format_gga(100.0 + i, o[0] + 1e-5 * i, o[1], o[2], hdop=1.2) for i in range(4)]
    lines.insert(3, format_gst(102.0, 0.8, 0.5, 1.7))  # GST for the third fix
    path = _write(tmp_path, lines)
    rec = readers.read(path, {"format": "nmea", "uere": 3.0, "vertical_factor": 2.0, "date": "2026-05-01"})
    sig = np.reshape(_items(rec)[0].sigma, (-1, 3))
    sh = 1.2 * 3.0
    np.testing.assert_allclose(sig[0], [sh / math.sqrt(2), sh / math.sqrt(2), 2.0 * sh])
    np.testing.assert_allclose(sig[2], [0.5, 0.8, 1.7])  # ENU: x east (lon sigma), y north (lat sigma)
    assert any("3 from HDOP" in n and "1 from GST" in n for n in rec.notes)
    rec2 = readers.read(path, {"format": "nmea", "sigma_source": "hdop", "date": "2026-05-01"})
    np.testing.assert_allclose(np.reshape(_items(rec2)[0].sigma, (-1, 3))[2],
                               [5 * 1.2 / math.sqrt(2)] * 2 + [1.5 * 5 * 1.2])  # the defaults
    with pytest.raises(bvpnav.InputError, match="uere"):
        readers.read(path, {"format": "nmea", "uere": -1.0})


def test_midnight_rollover(tmp_path):
    path = _write(tmp_path, example_lines(start=86395.0))  # 23:59:55 .. 00:00:05 next day
    rec = readers.read(path, {"format": "nmea"})
    np.testing.assert_allclose(rec.t, np.arange(11.0), rtol=0, atol=1e-9)
    assert rec.time_origin == "2026-05-01T23:59:55.000000000Z"
    assert any("midnight" in n for n in rec.notes)
    # GGA only: the date from the option, the rollover from the times
    gga = [s for s in example_lines(start=86395.0) if "GGA" in s]
    rec2 = readers.read(_write(tmp_path, gga, "gga.nmea"), {"format": "nmea", "date": "2026-05-01"})
    np.testing.assert_allclose(rec2.t, np.arange(11.0), rtol=0, atol=1e-9)
    assert rec2.time_origin == "2026-05-01T23:59:55.000000000Z"
    with pytest.raises(bvpnav.InputError, match="disagrees"):
        readers.read(path, {"format": "nmea", "date": "2026-05-02"})


def test_without_a_date_t_is_time_of_day_from_the_first_fix(tmp_path):
    gga = [s for s in example_lines() if "GGA" in s]
    rec = readers.read(_write(tmp_path, gga), {"format": "nmea"})
    assert rec.time_origin is None
    assert any("10:00:00.000 UTC on an unknown date" in n and 'date = "YYYY-MM-DD"' in n for n in rec.notes)
    with pytest.raises(bvpnav.InputError, match="YYYY-MM-DD"):
        readers.read(_write(tmp_path, gga), {"format": "nmea", "date": "1 May"})


def test_corrupt_line_is_named_with_its_number(tmp_path):
    lines = example_lines()
    bad = lines[4][:-2] + ("00" if not lines[4].endswith("00") else "11")
    lines[4] = bad  # line 5 of the file
    path = _write(tmp_path, lines)
    with pytest.raises(bvpnav.InputError, match=r"log\.nmea: line 5: bad checksum.*skip_bad_lines = true"):
        readers.read(path, {"format": "nmea"})
    rec = readers.read(path, {"format": "nmea", "skip_bad_lines": True})
    assert any("Skipped 1 bad lines" in n and "line 5" in n for n in rec.notes)
    assert rec.n == 11  # line 5 was an RMC: its epoch still has the GGA fix
    garbage = _write(tmp_path, example_lines()[:3] + ["$GPGGA,garbage"] + example_lines()[3:], "g.nmea")
    with pytest.raises(bvpnav.InputError, match=r"g\.nmea: line 4: "):
        readers.read(garbage, {"format": "nmea"})


def test_no_fix_and_bad_quality_are_dropped_and_counted(tmp_path):
    o = EXAMPLE["origin"]
    lines = [format_gga(100.0 + i, o[0] + 1e-5 * i, o[1], o[2], quality=q)
             for i, q in enumerate([1, 0, 4, 6, 2])]
    lines.insert(1, sentence("GPGGA,000140.50,,,,,0,00,99.99,,,,,,"))
    rec = readers.read(_write(tmp_path, lines), {"format": "nmea"})
    np.testing.assert_array_equal(rec.t, [0.0, 2.0, 4.0])
    note = next(n for n in rec.notes if n.startswith("Dropped GGA"))
    assert "2 quality 0 (no fix)" in note and "1 quality 6 (estimated)" in note
    with pytest.raises(bvpnav.InputError, match="no usable GGA fix"):
        readers.read(_write(tmp_path, [lines[1]], "none.nmea"), {"format": "nmea"})


def test_out_of_order_and_void_rmc(tmp_path):
    o = EXAMPLE["origin"]
    lines = [format_gga(t, o[0], o[1], o[2]) for t in (100.0, 102.0, 101.0)]
    with pytest.raises(bvpnav.InputError, match="line 3: .*out of order"):
        readers.read(_write(tmp_path, lines), {"format": "nmea"})
    lines = [format_gga(100.0 + i, o[0], o[1], o[2]) for i in range(3)]
    lines.append(format_rmc(102.0, DATE, o[0], o[1], 1.0, 90.0, status="V"))
    rec = readers.read(_write(tmp_path, lines, "v.nmea"), {"format": "nmea"})
    assert len(rec.items) == 1 and rec.time_origin.startswith("2026-05-01T00:01:40")
    assert any("status void" in n for n in rec.notes)
    repeated = example_lines()
    repeated.insert(3, repeated[2])  # the first RMC twice
    rec = readers.read(_write(tmp_path, repeated, "r.nmea"), {"format": "nmea"})
    assert _items(rec)[1].t.size == 11 and any("1 repeated time" in n for n in rec.notes)
    repeated.insert(2, repeated[1])  # the first GGA twice
    with pytest.raises(bvpnav.InputError, match=r"r2\.nmea: line 3: a second fix at 10:00:00"):
        readers.read(_write(tmp_path, repeated, "r2.nmea"), {"format": "nmea"})


def test_missing_pynmea2_names_the_extra(tmp_path, monkeypatch):
    path = get_reader("nmea").example(tmp_path)
    monkeypatch.setitem(sys.modules, "pynmea2", None)
    with pytest.raises(bvpnav.InputError, match=r"needs pynmea2 \(pip install 'bvpnav\[gnss\]'\)"):
        readers.read(path)


def test_unknown_option_is_refused(tmp_path):
    path = get_reader("nmea").example(tmp_path)
    with pytest.raises(bvpnav.InputError, match="not an option of the 'nmea' reader"):
        readers.read(path, {"orign": "first"})


def test_end_to_end_fixes_and_imu_recover_the_trajectory(tmp_path):
    """NMEA fixes (0.7 m horizontal, 1 m vertical noise, 1 Hz) and RMC velocities plus a noisy
    50 Hz accelerometer: the solved trajectory is much closer to the truth than the fixes."""
    rng = np.random.default_rng(7)
    T, w = 20.0, np.array([0.5, 0.3, 0.4])

    def pos(t):
        return np.column_stack([8 * t + 3 * np.sin(w[0] * t), 6 * t + 2 * np.cos(w[1] * t) - 2,
                                0.5 * np.sin(w[2] * t)])

    def vel(t):
        return np.column_stack([8 + 3 * w[0] * np.cos(w[0] * t), 6 - 2 * w[1] * np.sin(w[1] * t),
                                0.5 * w[2] * np.cos(w[2] * t)])

    def acc(t):
        return np.column_stack([-3 * w[0] ** 2 * np.sin(w[0] * t), -2 * w[1] ** 2 * np.cos(w[1] * t),
                                -0.5 * w[2] ** 2 * np.sin(w[2] * t)])

    tf = np.arange(0.0, T + 0.5, 1.0)
    noise = rng.normal(0.0, [0.7, 0.7, 1.0], (tf.size, 3))
    lat, lon, h = local_to_geodetic(pos(tf) + noise, EXAMPLE["origin"])
    lines = []
    for k, t in enumerate(tf):
        tod = 43200.0 + t
        v = vel(np.array([t]))[0]
        lines.append(format_gga(tod, lat[k], lon[k], h[k], geoid=47.0, hdop=1.0))
        lines.append(format_rmc(tod, DATE, lat[k], lon[k], math.hypot(v[0], v[1]),
                                math.degrees(math.atan2(v[0], v[1]))))
    rec = readers.read(_write(tmp_path, lines), {"format": "nmea", "uere": 1.0, "vertical_factor": 1.0,
                                                 "origin": list(EXAMPLE["origin"])})
    assert rec.time_origin == "2026-05-01T12:00:00.000000000Z"
    ti = np.linspace(0.0, T, 1001)
    a = acc(ti) + rng.normal(0.0, 0.05, (ti.size, 3))
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=ti, acc=a, time_origin=rec.time_origin), sigma_a=0.05)
    prob.add(*rec.items)
    traj = prob.solve().trajectory
    est = traj[["x", "y", "z"]].to_numpy()
    err = est - pos(ti)
    rms, fix_rms = np.sqrt(np.mean(err**2, axis=0)), np.sqrt(np.mean(noise**2, axis=0))
    assert np.all(rms < 0.7 * fix_rms), (rms, fix_rms)
    assert np.linalg.norm(err, axis=1).max() < 1.2
    verr = traj[["vx", "vy"]].to_numpy() - vel(ti)[:, :2]
    assert np.abs(verr).max() < 0.2


def test_damaged_logs_raise_only_input_errors_naming_the_file(tmp_path):
    """Random character changes, cuts and short sentences (valid checksums included): the
    log reads or raises InputError naming the file, never another exception."""
    rng = np.random.default_rng(11)
    text = "".join(s + "\r\n" for s in example_lines())
    o = EXAMPLE["origin"]
    fields = format_gga(100.0, o[0], o[1], o[2])[1:-3].split(",")
    cases = [sentence(",".join(fields[:k])) + "\r\n" for k in range(1, len(fields))]
    cases += [sentence(",".join(fields[:k] + ["x"] + fields[k + 1:])) + "\r\n" for k in range(1, len(fields))]
    for _ in range(80):
        chars = list(text)
        for i in rng.integers(0, len(chars), rng.integers(1, 4)):
            chars[i] = chr(int(rng.choice([ord(","), ord("."), ord("*"), 0, 200, *range(48, 91)])))
        cases.append("".join(chars))
    cases.append(text[: int(rng.integers(1, len(text)))])
    path = tmp_path / "damaged.nmea"
    for case in cases:
        path.write_text(case, encoding="latin-1")
        for opts in ({}, {"skip_bad_lines": True}):
            try:
                readers.read(path, {"format": "nmea", **opts})
            except bvpnav.InputError as exc:
                assert "damaged.nmea" in str(exc), exc
