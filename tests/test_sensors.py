"""Sensor-grade presets, sigma_a from noise densities, datasheet unit conversion (issue 16)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bvpnav import ImuData
from bvpnav.error_models import AttitudeError, Bias, GyroBias
from bvpnav.errors import InputError
from bvpnav.sensors import GRADES, UNITS, SensorGrade, from_datasheet, grade

G0 = 9.80665
FIELDS = ("acc_noise", "acc_bias", "acc_bias_walk", "gyro_noise", "gyro_bias", "gyro_bias_walk", "tilt",
          "heading")
#: The shared contract's table, typed in again here (not read from the module).
TABLE = {
    "consumer": (2e-3, 5e-2, 1e-4, 1e-4, 5e-3, 2e-5, 0.02, None),
    "tactical": (5e-4, 5e-3, 1e-5, 2e-5, 5e-5, 1e-6, 0.005, None),
    "navigation": (5e-5, 5e-4, 1e-6, 1e-6, 5e-8, 1e-8, 0.001, None),
}


@pytest.mark.parametrize("name", sorted(TABLE))
def test_presets_are_the_contract_table(name):
    g = grade(name)
    assert tuple(getattr(g, f) for f in FIELDS) == TABLE[name]
    assert g.name == name and g.description
    assert GRADES[name] is g


def test_grades_are_frozen_and_ordered_from_worst_to_best():
    with pytest.raises(AttributeError):
        grade("tactical").acc_noise = 1.0
    for f in FIELDS[:-1]:
        vals = [getattr(grade(n), f) for n in ("consumer", "tactical", "navigation")]
        assert vals[0] > vals[1] > vals[2], f


def test_grade_names_are_case_insensitive_and_unknown_ones_listed():
    assert grade(" Tactical ") is GRADES["tactical"]
    with pytest.raises(InputError, match="consumer, tactical, navigation") as exc:
        grade("automotive")
    assert "'automotive'" in str(exc.value)
    with pytest.raises(InputError, match="unknown sensor grade"):
        grade(3)


def test_sigma_a_is_density_times_root_rate():
    assert grade("tactical").sigma_a(100.0) == pytest.approx(5e-3, rel=1e-15)
    assert grade("consumer").sigma_a(200) == pytest.approx(2e-3 * 14.142135623730951, rel=1e-15)
    assert grade("navigation").sigma_a(400.0) == pytest.approx(1e-3, rel=1e-15)
    assert grade("consumer").gyro_sigma(100.0) == pytest.approx(1e-3, rel=1e-15)
    for bad in (0.0, -100.0, math.nan, math.inf, "100", True):
        with pytest.raises(InputError, match="rate_hz"):
            grade("tactical").sigma_a(bad)


def test_sigma_a_matches_the_std_of_averaged_white_noise():
    """The convention itself: white noise of intensity n averaged over 1/rate has std n sqrt(rate)."""
    n, rate, fine = 2e-3, 50.0, 100
    rng = np.random.default_rng(0)
    dt = 1.0 / (rate * fine)
    continuous = rng.normal(scale=n / math.sqrt(dt), size=(20000, fine))  # intensity n on a fine grid
    per_sample = continuous.mean(axis=1)
    g = SensorGrade(acc_noise=n, acc_bias=1e-2, acc_bias_walk=1e-4, gyro_noise=1e-4, gyro_bias=1e-3,
                    gyro_bias_walk=1e-5, tilt=0.01)
    assert per_sample.std() == pytest.approx(g.sigma_a(rate), rel=0.02)


@pytest.mark.parametrize(("field", "figure", "si"), [
    ("acc_noise", "150 ug/sqrt(Hz)", 150e-6 * 9.80665),
    ("acc_noise", "150 µg/√Hz", 1.4709975e-3),
    ("acc_noise", (60.0, "ug/rtHz"), 60e-6 * 9.80665),
    ("acc_noise", "0.06 m/s/sqrt(h)", 0.001),                    # VRW: / 60
    ("acc_noise", "3e-3 m/s^2/sqrt(Hz)", 3e-3),
    ("acc_bias", "40 mg", 0.392266),
    ("acc_bias", "2 ug", 1.96133e-5),
    ("acc_bias", (0.05, "m/s^2"), 0.05),
    ("acc_bias_walk", "60 ug/sqrt(h)", 60e-6 * 9.80665 / 60),
    ("gyro_noise", "0.005 deg/s/sqrt(Hz)", 8.726646259971648e-05),
    ("gyro_noise", "0.6 deg/sqrt(h)", 1.7453292519943296e-4),    # ARW: deg -> rad, / 60
    ("gyro_noise", "0.6 °/√h", 1.7453292519943296e-4),
    ("gyro_bias", "10 deg/h", 4.84813681109536e-05),
    ("gyro_bias", "36 deg/hr", 1.7453292519943296e-4),
    ("gyro_bias", "0.1 deg/s", 1.7453292519943296e-3),
    ("gyro_bias_walk", "36 deg/h/sqrt(h)", 36 * math.pi / 180 / 3600 / 60),
    ("tilt", "1 deg", 0.017453292519943295),
    ("tilt", "5 mrad", 5e-3),
])
def test_datasheet_units_against_hand_computed_values(field, figure, si):
    got = from_datasheet(base="consumer", **{field: figure})
    assert getattr(got, field) == pytest.approx(si, rel=1e-12)
    others = [f for f in FIELDS if f != field]
    assert all(getattr(got, f) == getattr(grade("consumer"), f) for f in others)


def test_a_full_datasheet_and_its_sigma_a():
    g = from_datasheet(acc_noise="100 ug/sqrt(Hz)", acc_bias="20 mg", acc_bias_walk=1e-4,
                       gyro_noise="0.3 deg/sqrt(h)", gyro_bias="5 deg/h", gyro_bias_walk=1e-6,
                       tilt="0.5 deg", heading="10 deg", name="mine", description="a datasheet")
    assert g.name == "mine" and g.heading == pytest.approx(math.radians(10.0), rel=1e-15)
    # 100 ug/sqrt(Hz) = 9.80665e-4 m/s^2/sqrt(Hz); at 100 Hz: 9.80665e-3 m/s^2
    assert g.sigma_a(100.0) == pytest.approx(9.80665e-3, rel=1e-12)


def test_one_sided_densities_lose_root_two():
    """A one-sided figure S: per-sample sigma = S sqrt(rate / 2)."""
    g = from_datasheet(acc_noise="100 ug/sqrt(Hz)", gyro_noise="0.005 deg/s/sqrt(Hz)", base="tactical",
                       one_sided=True)
    assert g.sigma_a(100.0) == pytest.approx(100e-6 * G0 * math.sqrt(50.0), rel=1e-12)
    assert g.gyro_sigma(100.0) == pytest.approx(math.radians(0.005) * math.sqrt(50.0), rel=1e-12)
    assert g.acc_bias == grade("tactical").acc_bias  # only densities change


def test_datasheet_mistakes_are_refused_by_name():
    with pytest.raises(InputError, match="acc_bias_walk, gyro_noise, gyro_bias, gyro_bias_walk, tilt "
                                         "not given"):
        from_datasheet(acc_noise=1e-3, acc_bias=1e-2)
    with pytest.raises(InputError, match="unit 'furlongs' is not known.*deg/h"):
        from_datasheet(gyro_bias=(3.0, "furlongs"), base="consumer")
    with pytest.raises(InputError, match="acc_bias.*ug/sqrt"):  # a density unit where a bias goes
        from_datasheet(acc_bias="40 ug/sqrt(Hz)", base="consumer")
    with pytest.raises(InputError, match="acc_noise.*> 0"):
        from_datasheet(acc_noise="-150 ug/sqrt(Hz)", base="consumer")
    with pytest.raises(InputError, match="number and a unit"):
        from_datasheet(tilt="one degree", base="consumer")
    with pytest.raises(InputError, match="unknown sensor grade"):
        from_datasheet(tilt=0.01, base="phone")
    with pytest.raises(InputError, match="tilt"):
        SensorGrade(acc_noise=1e-3, acc_bias=1e-2, acc_bias_walk=1e-4, gyro_noise=1e-4, gyro_bias=1e-3,
                    gyro_bias_walk=1e-5, tilt=0.0)
    assert set(UNITS) == set(FIELDS)


def test_infinite_heading_means_unknown():
    g = from_datasheet(heading=math.inf, base="consumer")
    assert g.heading is None


def _strapdown(n=301, rate=10.0):
    t = np.arange(n) / rate
    f = np.tile([0.0, 0.0, G0], (n, 1))
    return ImuData.from_gyro(t, f, np.zeros((n, 3)))


def test_error_model_carries_the_grade_priors():
    g = grade("tactical")
    em = g.error_model()
    acc, gyro, att = em.components
    assert isinstance(acc, Bias) and isinstance(gyro, GyroBias) and isinstance(att, AttitudeError)
    assert float(acc.sigma) == 5e-3 and acc.interval == 30.0 and acc.drift == 1e-5
    assert float(gyro.sigma) == 5e-5 and gyro.interval == 30.0 and gyro.drift == 1e-6
    np.testing.assert_array_equal(np.asarray(att.sigma, dtype=float), [0.005, 0.005, np.inf])
    data = _strapdown()  # 30 s: one knot interval
    names = em.names(data)
    assert {"bias_x[0]", "bias_x[1]", "gyro_bias_z[0]", "gyro_bias_z[1]", "attitude_x", "attitude_y",
            "attitude_z"} <= set(names)


def test_error_model_options():
    g = grade("consumer")
    const = g.error_model(time_varying=False)
    acc, gyro, att = const.components
    assert acc.interval is None and acc.drift is None and gyro.interval is None and gyro.drift is None
    assert {"bias_x", "gyro_bias_z", "attitude_z"} <= set(const.names(_strapdown()))
    _, gyro10, att10 = g.error_model(interval=10.0, heading_sigma=0.1).components
    assert gyro10.interval == 10.0
    np.testing.assert_allclose(np.asarray(att10.sigma, dtype=float), [0.02, 0.02, 0.1])
    known = from_datasheet(heading="2 deg", base="consumer").error_model()
    assert np.asarray(known.components[2].sigma, dtype=float)[2] == pytest.approx(math.radians(2.0))
    unknown = from_datasheet(heading="2 deg", base="consumer").error_model(heading_sigma=math.inf)
    assert np.isinf(np.asarray(unknown.components[2].sigma, dtype=float)[2])
    for bad in ({"interval": 0.0}, {"interval": None}, {"heading_sigma": -1.0}, {"time_varying": "yes"},
                {"walk": 1}):
        with pytest.raises(InputError):
            g.error_model(**bad)


def test_error_model_with_the_angle_random_walk():
    """walk=True adds AttitudeWalk with the grade's ARW plus what the 30 s gyro-bias knots
    leave out, sqrt(2e-5^2 + 1e-6^2 * 30^2 / 12) = 2.17945e-5 rad/sqrt(s), and the spacing
    of walk_interval: sqrt(3) * 5e-4 / (9.80665 * 2.17945e-5) = 4.0519 s (tactical grade);
    with constant biases the ARW is the gyro noise alone (4.4155 s)."""
    from bvpnav.error_models import AttitudeWalk

    em = grade("tactical").error_model(walk=True)
    walk = em.components[-1]
    assert isinstance(walk, AttitudeWalk)
    assert walk.arw == pytest.approx(2.17945e-5, rel=1e-5)
    assert walk.interval == pytest.approx(4.0519, abs=1e-4)
    const = grade("tactical").error_model(walk=True, time_varying=False).components[-1]
    assert const.arw == 2e-5 and const.interval == pytest.approx(4.4155, abs=1e-4)
    names = em.names(_strapdown())  # 30 s: round(30 / 4.05) = 7 walk intervals, knots 1..7 per axis
    walk_z = [n for n in names if n.startswith("attitude_walk_z")]
    assert walk_z == [f"attitude_walk_z[{m}]" for m in range(1, 8)]
    assert not any(isinstance(c, AttitudeWalk) for c in grade("tactical").error_model().components)


def test_bridge_terms_of_sigma_a_and_arw():
    """sigma_a(rate, interval) and arw(interval) add q^2 D^2 / 12 of the bias walks to the
    white-noise densities: tactical, 100 Hz, 30 s knots: sqrt((5e-4^2 + 1e-5^2 * 75) * 100)
    = 5.07445e-3 m/s^2 against 5e-3 without."""
    from bvpnav.error_models import bridge_intensity

    g = grade("tactical")
    assert g.sigma_a(100.0) == pytest.approx(5e-3, rel=1e-12)
    assert g.sigma_a(100.0, interval=30.0) == pytest.approx(5.074446e-3, rel=1e-6)
    assert g.arw() == 2e-5
    assert g.arw(30.0) ** 2 == pytest.approx(4e-10 + 7.5e-11, rel=1e-12)
    assert bridge_intensity(1e-6, 30.0) == pytest.approx(7.5e-11, rel=1e-12)
    for bad in ({"drift": 0.0, "interval": 30.0}, {"drift": 1e-6, "interval": -1.0},
                {"drift": None, "interval": 30.0}):
        with pytest.raises(InputError):
            bridge_intensity(**bad)
    with pytest.raises(InputError):
        g.sigma_a(100.0, interval=0.0)


def test_bridge_intensity_is_the_variance_of_the_left_out_integral():
    """Monte Carlo: a random walk of density q sampled at knots D apart and interpolated
    linearly leaves out a bridge whose integral over one interval has variance q^2 D^3 / 12
    (bridge_intensity * D); 4000 paths, the estimate within 4 standard errors."""
    from bvpnav.error_models import bridge_intensity

    rng = np.random.default_rng(5)
    q, D, steps, paths = 2.0, 3.0, 600, 4000
    dt = D / steps
    walk = np.concatenate([np.zeros((paths, 1)),
                           np.cumsum(q * np.sqrt(dt) * rng.standard_normal((paths, steps)), axis=1)], axis=1)
    s = np.linspace(0.0, D, steps + 1)
    bridge = walk - np.outer(walk[:, -1], s / D)     # what the linear interpolation leaves out
    integral = np.sum(0.5 * (bridge[:, 1:] + bridge[:, :-1]), axis=1) * dt
    expected = bridge_intensity(q, D) * D
    se = expected * np.sqrt(2.0 / paths)
    assert abs(np.var(integral) - expected) < 4 * se
