"""bvpnav.geodesy: WGS-84 local frames (against pymap3d), normal gravity (published values),
fixes as Position items, trajectories back to geodetic coordinates."""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pytest

import bvpnav
from bvpnav.constraints import Position
from bvpnav.geodesy import (
    WGS84,
    geodetic_to_local,
    local_to_geodetic,
    normal_gravity,
    position_items,
    trajectory_to_geodetic,
)

pymap3d = pytest.importorskip("pymap3d")

ORIGIN = (48.1173, 11.5167, 520.0)


def _points(n=50, seed=3, spread=0.4):
    rng = np.random.default_rng(seed)
    lat = ORIGIN[0] + rng.uniform(-spread, spread, n)
    lon = ORIGIN[1] + rng.uniform(-spread, spread, n)
    h = ORIGIN[2] + rng.uniform(-300.0, 3000.0, n)
    return lat, lon, h


# ------------------------------------------------------------------ normal gravity
def _somigliana_original(lat_deg, a, b, gamma_e, gamma_p):
    """Somigliana's formula in its original form (independent of the k, e^2 form used)."""
    c2, s2 = np.cos(np.radians(lat_deg)) ** 2, np.sin(np.radians(lat_deg)) ** 2
    return (a * gamma_e * c2 + b * gamma_p * s2) / np.sqrt(a**2 * c2 + b**2 * s2)


def test_normal_gravity_published_values():
    assert abs(normal_gravity(0.0) - 9.7803253359) < 1e-9  # TR8350.2 gamma_e
    assert abs(normal_gravity(90.0) - 9.8321849378) < 1e-9  # gamma_p
    assert abs(normal_gravity(-90.0) - 9.8321849378) < 1e-9
    # 45 deg: WGS-84 gives 9.8061977694; the often quoted 9.806199203 is GRS80's value (its gamma_e is
    # 1.4e-6 larger); both from Somigliana's original form with each system's constants.
    assert abs(normal_gravity(45.0) - 9.8061977694) < 1e-9
    grs80 = _somigliana_original(45.0, 6378137.0, 6356752.31414, 9.7803267715, 9.8321863685)
    assert abs(grs80 - 9.806199203) < 1e-9
    assert isinstance(normal_gravity(45.0), float)


def test_normal_gravity_matches_the_original_somigliana_form_at_every_latitude():
    lat = np.linspace(-90.0, 90.0, 37)
    ref = _somigliana_original(lat, WGS84["a"], WGS84["b"], WGS84["gamma_e"], WGS84["gamma_p"])
    np.testing.assert_allclose(normal_gravity(lat), ref, rtol=0, atol=1e-9)


def test_normal_gravity_height_gradient():
    grad45 = (normal_gravity(45.0, 100.0) - normal_gravity(45.0, 0.0)) / 100.0
    assert abs(grad45 - (-3.086e-6)) < 2e-9
    grad0 = normal_gravity(0.0, 1.0) - normal_gravity(0.0, 0.0)
    assert abs(grad0 - (-2 * WGS84["gamma_e"] / WGS84["a"] * (1 + WGS84["f"] + WGS84["m"]))) < 1e-11
    # the second-order term: at 10 km the linear decrease 3.0855e-2 m/s^2 is reduced by 3 g h^2 / a^2 = 7.2e-5
    drop = normal_gravity(45.0, 0.0) - normal_gravity(45.0, 10_000.0)
    second = 3 * normal_gravity(45.0) * 1e8 / WGS84["a"] ** 2
    linear = 2 / WGS84["a"] * (1 + WGS84["f"] + WGS84["m"] - WGS84["f"]) * normal_gravity(45.0) * 1e4
    assert drop == pytest.approx(linear - second, abs=1e-12)
    assert 0.03078 < drop < 0.03079
    np.testing.assert_allclose(normal_gravity([0.0, 45.0], [0.0, 100.0]),
                               [normal_gravity(0.0), normal_gravity(45.0, 100.0)], rtol=0, atol=0)


def test_strapdown_wgs84_gravity_uses_normal_gravity():
    from bvpnav.strapdown import gravity_vector

    g = gravity_vector({"gravity": "wgs84", "latitude": 45.0, "height": 100.0}, "ned")
    assert g[2] == pytest.approx(normal_gravity(45.0, 100.0), abs=1e-12)


@pytest.mark.parametrize("lat,h,needle", [([0.0, 10.0, 91.0], 0.0, "entry 2"),
                                          ([0.0, np.nan], 0.0, "entry 1"),
                                          (10.0, [0.0, np.inf], "entry 1")])
def test_normal_gravity_refuses_bad_values_by_index(lat, h, needle):
    with pytest.raises(bvpnav.InputError, match=needle):
        normal_gravity(lat, h)


# ------------------------------------------------------------------ local frames
def test_enu_agrees_with_pymap3d_and_round_trips():
    lat, lon, h = _points()
    enu = geodetic_to_local(lat, lon, h, ORIGIN)
    ref = np.column_stack(pymap3d.geodetic2enu(lat, lon, h, *ORIGIN, deg=True))
    np.testing.assert_allclose(enu, ref, rtol=0, atol=1e-3)
    assert np.abs(enu[:, :2]).max() > 20_000  # tens of km: the curvature matters
    back = geodetic_to_local(*local_to_geodetic(enu, ORIGIN), ORIGIN)
    np.testing.assert_allclose(back, enu, rtol=0, atol=1e-6)
    la, lo, hh = local_to_geodetic(enu, ORIGIN)
    np.testing.assert_allclose(la, lat, rtol=0, atol=1e-10)
    np.testing.assert_allclose(lo, lon, rtol=0, atol=1e-10)
    np.testing.assert_allclose(hh, h, rtol=0, atol=1e-6)


def test_ned_is_north_east_down_of_enu():
    lat, lon, h = _points(20)
    enu = geodetic_to_local(lat, lon, h, ORIGIN, frame="enu")
    ned = geodetic_to_local(lat, lon, h, ORIGIN, frame="ned")
    np.testing.assert_allclose(ned, np.column_stack([enu[:, 1], enu[:, 0], -enu[:, 2]]), rtol=0, atol=1e-6)
    back = local_to_geodetic(ned, ORIGIN, frame="ned")
    np.testing.assert_allclose(back[0], lat, rtol=0, atol=1e-10)
    # a point due north is +y in ENU, +x in NED; a point above is +z in ENU, -z in NED
    p = geodetic_to_local([ORIGIN[0] + 0.001, ORIGIN[0]], [ORIGIN[1], ORIGIN[1]], [ORIGIN[2], ORIGIN[2] + 10],
                          ORIGIN, frame="ned")
    assert p[0, 0] > 100 and abs(p[0, 1]) < 1e-6 and p[1, 2] == pytest.approx(-10.0)


def test_scalars_broadcast():
    out = geodetic_to_local(ORIGIN[0], [ORIGIN[1], ORIGIN[1] + 0.01], ORIGIN[2], ORIGIN)
    assert out.shape == (2, 3) and np.allclose(out[0], 0.0)
    assert local_to_geodetic([0.0, 0.0, 0.0], ORIGIN)[0].shape == (1,)


@pytest.mark.parametrize("call,needle", [
    (lambda: geodetic_to_local([10.0, 95.0], [0.0, 0.0], [0.0, 0.0], ORIGIN), r"lat: entry 1 is 95\.0"),
    (lambda: geodetic_to_local([10.0, 11.0], [0.0, np.nan], 0.0, ORIGIN), "lon: entry 1"),
    (lambda: geodetic_to_local([10.0, 11.0], [0.0, 1.0, 2.0], 0.0, ORIGIN), "one value per fix"),
    (lambda: geodetic_to_local(10.0, 0.0, 0.0, (95.0, 0.0, 0.0)), "origin"),
    (lambda: geodetic_to_local(10.0, 0.0, 0.0, (10.0, 0.0)), "origin"),
    (lambda: geodetic_to_local(10.0, 0.0, 0.0, ORIGIN, frame="nwu"), "enu"),
    (lambda: local_to_geodetic(np.zeros((4, 2)), ORIGIN), r"shape \(4, 2\)"),
    (lambda: local_to_geodetic([[0.0, 0.0, 0.0], [1.0, np.inf, 0.0]], ORIGIN), r"xyz\[1, 1\]"),
])
def test_conversions_refuse_bad_input_by_name(call, needle):
    with pytest.raises(bvpnav.InputError, match=needle):
        call()


def test_missing_pymap3d_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "pymap3d", None)
    with pytest.raises(bvpnav.InputError, match=r"needs pymap3d \(pip install 'bvpnav\[gnss\]'\)"):
        geodetic_to_local(10.0, 0.0, 0.0, ORIGIN)
    assert normal_gravity(10.0) > 9.78  # needs nothing beyond numpy


# ------------------------------------------------------------------ items and trajectories
def test_position_items_sigma_forms():
    lat, lon, h = _points(4, spread=0.001)
    t = [0.0, 1.0, 2.0, 3.0]
    hard = position_items(t, lat, lon, h, ORIGIN)
    assert isinstance(hard, Position) and hard.mode == "hard" and hard.sigma is None
    np.testing.assert_allclose(np.reshape(hard.value, (4, 3)), geodetic_to_local(lat, lon, h, ORIGIN))
    hv = position_items(t, lat, lon, h, ORIGIN, frame="ned", sigma=np.tile([2.0, 5.0], (4, 1)), name="gps")
    assert hv.mode == "soft" and hv.name == "gps" and tuple(hv.axes) == ("x", "y", "z")
    np.testing.assert_array_equal(np.reshape(hv.sigma, (4, 3)), np.tile([2.0, 2.0, 5.0], (4, 1)))
    per_fix = position_items(t, lat, lon, h, ORIGIN, sigma=[1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(np.reshape(per_fix.sigma, (4, 3))[:, 2], [1.0, 2.0, 3.0, 4.0])
    with pytest.raises(bvpnav.InputError, match="sigma of fix 1, axis 2"):
        position_items(t, lat, lon, h, ORIGIN, sigma=[[1, 1, 1], [1, 1, 0], [1, 1, 1], [1, 1, 1]])
    with pytest.raises(bvpnav.InputError, match="one time per fix"):
        position_items(t[:3], lat, lon, h, ORIGIN)


def test_trajectory_to_geodetic_adds_columns_to_a_copy():
    lat, lon, h = _points(5, spread=0.01)
    enu = geodetic_to_local(lat, lon, h, ORIGIN)
    df = pd.DataFrame({"x": enu[:, 0], "y": enu[:, 1], "z": enu[:, 2], "vx": 1.0},
                      index=pd.Index(np.arange(5.0), name="t"))
    before = df.copy()
    out = trajectory_to_geodetic(df, ORIGIN)
    pd.testing.assert_frame_equal(df, before)
    assert list(out.columns) == ["x", "y", "z", "vx", "lat", "lon", "height"]
    np.testing.assert_allclose(out["lat"], lat, rtol=0, atol=1e-10)
    np.testing.assert_allclose(out["lon"], lon, rtol=0, atol=1e-10)
    np.testing.assert_allclose(out["height"], h, rtol=0, atol=1e-6)
    ned = df.rename(columns={"x": "n", "y": "e", "z": "d"})
    ned["n"], ned["e"], ned["d"] = enu[:, 1], enu[:, 0], -enu[:, 2]
    out2 = trajectory_to_geodetic(ned, ORIGIN, frame="ned", axes=("n", "e", "d"))
    np.testing.assert_allclose(out2["lat"], lat, rtol=0, atol=1e-10)
    with pytest.raises(bvpnav.InputError, match="already has columns"):
        trajectory_to_geodetic(out, ORIGIN)
    with pytest.raises(bvpnav.InputError, match="missing"):
        trajectory_to_geodetic(df, ORIGIN, axes=("x", "y", "up"))
