"""Silent mixes (issue 40, case 7): two phones in one zip, a clipped gyro.

A zip or folder with two phones' exports was merged file by file (one phone's accelerometer
with the other's orientation); now it is refused, naming both. A gyro clipped at its range
(a walk 47 times worse) said nothing; now the saturated samples are counted, located and
reported (a :class:`bvpnav.log.SaturationWarning`, ``data.checks``, ``solution.warnings``).
(A NED/FRD bag read as ENU: ``tests/test_frame_check.py``.)
"""

from __future__ import annotations

import warnings
import zipfile

import numpy as np
import pandas as pd
import pytest

from bvpnav import ImuData, NavigationProblem, readers, scenarios
from bvpnav.constraints import Position, ZeroVelocity
from bvpnav.detect import SATURATION_RUN, saturation
from bvpnav.errors import InputError
from bvpnav.log import SaturationWarning
from bvpnav.readers.phone import write_example_export

START_B = 1_718_040_000_000_000_000  # phone B's clock: another recording, hours later


# --------------------------------------------------------------- two phones, one archive
@pytest.fixture()
def two_phones(tmp_path):
    a = write_example_export(tmp_path / "phoneA", duration=2.0)
    b = write_example_export(tmp_path / "phoneB", duration=3.0, start_ns=START_B)
    return a.path, b.path


def _zip(archive, entries):
    with zipfile.ZipFile(archive, "w") as z:
        for name, path in entries:
            z.write(path, name)
    return archive


def test_a_zip_of_two_phones_is_refused_naming_both(two_phones, tmp_path):
    a, b = two_phones
    # interleaved so that file-by-file picking took A's accelerometer and B's orientation
    entries = [("phoneA/TotalAcceleration.csv", a / "TotalAcceleration.csv"),
               ("phoneB/TotalAcceleration.csv", b / "TotalAcceleration.csv"),
               ("phoneB/Gyroscope.csv", b / "Gyroscope.csv"),
               ("phoneB/Orientation.csv", b / "Orientation.csv"),
               ("phoneA/Gyroscope.csv", a / "Gyroscope.csv")]
    archive = _zip(tmp_path / "both.zip", entries)
    with pytest.raises(InputError) as err:
        readers.read(archive, {"format": "phone"})
    msg = str(err.value)
    assert "holds 2 exports" in msg
    assert "'phoneA/': Gyroscope.csv, TotalAcceleration.csv" in msg
    assert "'phoneB/': Gyroscope.csv, Orientation.csv, TotalAcceleration.csv" in msg
    assert "mixed file by file" in msg and "Give one export" in msg
    # files at the top level beside a nested export: two exports too
    top = _zip(tmp_path / "top.zip", [("TotalAcceleration.csv", a / "TotalAcceleration.csv"),
                                      ("Gyroscope.csv", a / "Gyroscope.csv"),
                                      ("old/Orientation.csv", b / "Orientation.csv")])
    with pytest.raises(InputError, match=r"holds 2 exports \('\(top level\)': Gyroscope.csv, "
                       r"TotalAcceleration.csv; 'old/': Orientation.csv\)"):
        readers.read(top, {"format": "phone"})
    # one phone's export alone reads, all its files from its folder
    one = _zip(tmp_path / "one.zip", [(f"phoneB/{p.name}", p) for p in sorted(b.iterdir())])
    rec = readers.read(one, {"format": "phone"})
    assert rec.source == f"{one}!phoneB/TotalAcceleration.csv"
    assert rec.n == readers.read(b, {"format": "phone"}).n == 301


def test_a_folder_of_two_phone_exports_is_refused_naming_both(two_phones, tmp_path):
    with pytest.raises(InputError, match=r"holds 2 exports \('phoneA/': Gyroscope.csv, Orientation.csv, "
                       r"TotalAcceleration.csv; 'phoneB/': .*mixed file by file"):
        readers.read(tmp_path, {"format": "phone"})


# ---------------------------------------------------------------------- clipped gyro
@pytest.fixture(scope="module")
def walk():
    return scenarios.walking(rate=100.0, n_strides=6, seed=2)


def _solve(data, sc):
    prob = NavigationProblem(data, sigma_a=0.05)
    prob.add(Position(t=0.0, value=sc.position[0]),
             *[ZeroVelocity(t0=a, t1=b, sigma=0.01, mode="soft") for a, b in sc.params["stance_intervals"]])
    return prob.solve(solver="direct")


def test_a_clipped_gyro_is_counted_located_and_reported(walk):
    sim = walk.params["simulation"]
    limit = np.deg2rad(250.0)  # a 250 deg/s gyro; the walk reaches about 6 rad/s
    assert np.abs(sim.gyro).max() > 1.2 * limit
    clipped = np.clip(sim.gyro, -limit, limit)
    over = np.abs(sim.gyro) > limit
    expected = int(np.count_nonzero(over.any(axis=1)))
    c0 = sim.attitude[0]
    with pytest.warns(SaturationWarning) as got:
        data = ImuData.from_gyro(sim.t, sim.specific_force, clipped, initial_attitude=c0)
    msg = str(got[0].message)
    rep = data.checks["saturation"]
    assert rep["samples"] == expected and rep["of"] == sim.t.size
    for k, axis in enumerate("xyz"):
        if over[:, k].any():
            first = int(np.flatnonzero(over[:, k])[0])
            assert rep["axes"][axis]["samples"] == int(np.count_nonzero(over[:, k]))
            assert rep["axes"][axis]["level"] == pytest.approx(limit, rel=1e-12)
            assert rep["axes"][axis]["intervals"][0][0] == sim.t[first]
            n_axis = rep["axes"][axis]["samples"]
            assert f"axis {axis} {n_axis} samples at |rate| 4.363 rad/s (250 deg/s)" in msg
    assert msg.startswith(f"gyro saturation: {expected} of {sim.t.size} samples")
    assert "clipped at the sensor's range" in msg
    # the stated range finds the same samples
    with pytest.warns(SaturationWarning, match="at or beyond the stated gyro_range = 4.363 rad/s"):
        stated = ImuData.from_gyro(sim.t, sim.specific_force, clipped, initial_attitude=c0, gyro_range=limit)
    assert stated.checks["saturation"]["samples"] == expected
    # and the solve says so: the clipped walk is far worse, and not silently
    sol = _solve(data, walk)
    good = _solve(ImuData.from_gyro(sim.t, sim.specific_force, sim.gyro, initial_attitude=c0), walk)
    assert sol.rms_error(walk.position) > 5 * good.rms_error(walk.position)
    assert any(w.startswith("gyro saturation: ") for w in sol.warnings)
    assert sol.stats["data_checks"]["saturation"]["samples"] == expected


def test_unclipped_and_quantized_rates_are_not_saturation(walk):
    sim = walk.params["simulation"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", SaturationWarning)
        data = ImuData.from_gyro(sim.t, sim.specific_force, sim.gyro, initial_attitude=sim.attitude[0])
    assert data.checks["saturation"]["samples"] == 0
    # a 16-bit gyro at rest: its largest |value| (a few LSB) repeats in runs, far below any range
    lsb = np.deg2rad(2000.0) / 32768
    rest = np.round(np.random.default_rng(0).normal(0.0, 0.01, size=(3000, 3)) / lsb) * lsb
    t = np.arange(3000) * 0.01
    rep = saturation(t, rest, warn=False)
    assert rep["samples"] == 0
    # the same values as a rate table held at its largest rate for 2 samples: a peak, not clipping
    w = np.zeros((50, 3))
    w[20:20 + SATURATION_RUN - 1, 1] = 3.0
    assert saturation(np.arange(50.0), w, warn=False)["samples"] == 0
    w[20:20 + SATURATION_RUN, 1] = 3.0
    assert saturation(np.arange(50.0), w, warn=False)["samples"] == SATURATION_RUN


def test_gyro_range_through_the_spec_and_bad_values(walk, tmp_path):
    sim = walk.params["simulation"]
    limit = np.deg2rad(250.0)
    df = pd.DataFrame({"t": sim.t, **{f"f{k}": sim.specific_force[:, k] for k in range(3)},
                       **{f"w{k}": np.clip(sim.gyro[:, k], -limit, limit) for k in range(3)}})
    df.to_csv(tmp_path / "clip.csv", index=False, float_format="%.17g")
    q = sim.attitude[0].as_quat().tolist()
    inp = {"specific_force": ["f0", "f1", "f2"], "gyro": ["w0", "w1", "w2"], "gyro_range": float(limit),
           "initial_attitude": {"quaternion": q}}
    rec = readers.read(tmp_path / "clip.csv", inp)
    with pytest.warns(SaturationWarning, match=r"gyro saturation of .*clip\.csv: \d+ of "):
        data = rec.imu_data(inp)
    assert data.checks["saturation"]["gyro_range"] == limit
    with pytest.raises(InputError, match=r"gyro_range = -1: the gyro's full-scale range in rad/s"):
        rec.imu_data({**inp, "gyro_range": -1})
    with pytest.raises(InputError, match="gyro_range must be > 0|gyro_range=0"):
        saturation(sim.t, sim.gyro, gyro_range=0)
