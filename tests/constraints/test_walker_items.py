"""Information a walk carries: ZeroAngularRate, SamePosition, KnownDistance, FloorHeight.

Exactness on noise-free simulations (each quantity recovered where it is observable), the
contract check, and the errors that name the item.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bvpnav import ImuData, InputError, NavigationProblem, detect, error_models
from bvpnav.constraints import (
    FloorHeight,
    KnownDistance,
    Position,
    SamePosition,
    Velocity,
    ZeroAngularRate,
    ZeroVelocity,
)
from bvpnav.scenarios import walking
from bvpnav.testing import check_item


@pytest.mark.parametrize("cls", [ZeroAngularRate, SamePosition, KnownDistance, FloorHeight])
def test_contract(cls):
    assert check_item(cls) is None


def test_gyro_bias_recovered_exactly_from_noise_free_stances():
    """A simulated walk whose gyros read a constant bias and nothing else in the stances:
    angular-rate rows in the stances (sigma 1e-5 rad/s beside the default grade's gyro-bias prior;
    soft zero velocity, the start position) give the bias to 1e-6 rad/s."""
    sc = walking(rate=100.0, n_strides=3, accel_noise=0.0, gyro_noise=0.0, accel_bias=0.0, gyro_bias=0.004,
                 seed=2)
    stance = sc.params["stance"]
    true_bias = sc.data.gyro[stance].mean(axis=0)
    assert np.ptp(sc.data.gyro[stance], axis=0).max() < 1e-12  # the stances read the bias alone
    assert np.linalg.norm(true_bias) == pytest.approx(0.004, rel=1e-9)
    prob = NavigationProblem(sc.data, error_model=error_models.GyroBias())
    prob.add(*detect.zero_velocity_items(sc.params["stance_intervals"], angular_rate=1e-5, sigma=0.01))
    prob.add(Position(t=[sc.t[0]], value=sc.position[0]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the loop's notes on a 3-stride walk are not what is tested here
        sol = prob.solve(solver="direct")
    est = sol.error_params[["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]].to_numpy()
    np.testing.assert_allclose(est, true_bias, rtol=0, atol=1e-6)
    assert sol.stats["verified"]
    # without the angular-rate rows the loop leaves a bias error orders of magnitude larger
    prob2 = NavigationProblem(sc.data, error_model=error_models.GyroBias())
    prob2.add(*detect.zero_velocity_items(sc.params["stance_intervals"], sigma=0.01))
    prob2.add(Position(t=[sc.t[0]], value=sc.position[0]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est2 = prob2.solve(solver="direct").error_params.to_numpy()
    assert np.max(np.abs(est2 - true_bias)) > 100 * np.max(np.abs(est - true_bias))


def test_zero_velocity_items_emit_both_kinds():
    items = detect.zero_velocity_items([(0.0, 1.0), (2.0, 3.0)], angular_rate=0.01, sigma=0.02, name="stance")
    kinds = [type(it).__name__ for it in items]
    assert kinds == ["ZeroVelocity", "ZeroVelocity", "ZeroAngularRate", "ZeroAngularRate"]
    assert items[2].t == (0.0, 1.0) and items[3].sigma == 0.01 and items[3].name == "stance 1 rate"
    assert [type(i).__name__ for i in detect.zero_velocity_items([(0.0, 1.0)])] == ["ZeroVelocity"]


def test_zero_angular_rate_sigma_per_body_axis():
    """sigma per body axis (3 values) or per instant and axis: one row per sample and axis, time-major."""
    model = ZeroAngularRate.example_model()
    prob = NavigationProblem(model.data, error_model=error_models.GyroBias())
    prob.add(ZeroAngularRate(t=(0.0, 2.0), sigma=(1e-3, 2e-3, 3e-3), name="still"))
    rows = [term for term in prob.formulation.terms() if term.item is not None and term.item.name == "still"]
    k = int(np.count_nonzero(model.data.t <= 2.0 + 1e-9))
    np.testing.assert_array_equal(rows[0].sigma, np.tile([1e-3, 2e-3, 3e-3], k))
    two = ZeroAngularRate(t=(0.0, 2.0), axes=("x", "z"), sigma=np.tile([1e-3, 3e-3], (k, 1)))
    assert two.weight_rows(2 * k).tolist() == np.tile([1e-3, 3e-3], k).tolist()


def _rolling_walk():
    """A noise-free simulated walk with a constant gyro bias whose every other stance rolls
    about body x at 0.1 rad/s in the gyro's reading (a foot that rolls while it stands)."""
    sc = walking(rate=100.0, n_strides=6, accel_noise=0.0, gyro_noise=0.0, accel_bias=0.0, gyro_bias=0.004,
                 seed=2)
    intervals = sc.params["stance_intervals"]
    w = sc.data.gyro.copy()
    for k, (a, b) in enumerate(intervals):
        if k % 2 == 1:
            w[(sc.t >= a - 1e-9) & (sc.t <= b + 1e-9), 0] += 0.1
    data = ImuData.from_gyro(sc.t, sc.data.specific_force, w, initial_attitude=sc.data.attitude[0],
                             gravity=sc.data.gravity)
    return sc, data, intervals, sc.data.gyro[sc.params["stance"]].mean(axis=0)


def test_zero_angular_rate_spread_sigma_is_each_stance_rms():
    sc, data, intervals, bias = _rolling_walk()
    items = detect.zero_velocity_items(intervals, angular_rate="spread", data=data, sigma=0.01)
    rate = [it for it in items if isinstance(it, ZeroAngularRate)]
    assert len(rate) == len(intervals)
    for k, ((a, b), it) in enumerate(zip(intervals, rate, strict=True)):
        inside = (data.t >= a - 1e-9) & (data.t <= b + 1e-9)
        expect = np.sqrt(np.mean(data.gyro[inside] ** 2, axis=0))
        assert it.sigma.shape == (inside.sum(), 3)
        np.testing.assert_allclose(it.sigma, np.tile(expect, (inside.sum(), 1)), rtol=1e-12)
        # a rolling stance weighs by its roll, a still one by the bias it reads
        assert it.sigma[0, 0] == pytest.approx(abs(0.1 + bias[0]) if k % 2 else abs(bias[0]), rel=1e-6)
    with pytest.raises(InputError, match=r"data=.*from_gyro"):
        detect.zero_velocity_items(intervals, angular_rate="spread")
    with pytest.raises(InputError, match=r"angular_rate='noise'.*'spread'"):
        detect.zero_velocity_items(intervals, angular_rate="noise", data=data)
    with pytest.raises(InputError, match=r"interval 0 \(100, 101\) s holds no sample"):
        detect.zero_velocity_items([(100.0, 101.0)], angular_rate="spread", data=data)


def test_zero_angular_rate_spread_keeps_a_rolling_stance_out_of_the_bias():
    """At the gyro's noise sigma the stances that roll (0.1 rad/s, half of the inner ones) pull
    the x bias by 2.4e-2 rad/s; with each stance's own spread as its sigma by under 1e-3."""
    sc, data, intervals, bias = _rolling_walk()
    errors = {}
    for rate in (1e-3, "spread"):
        prob = NavigationProblem(data, error_model=error_models.GyroBias())
        prob.add(*detect.zero_velocity_items(intervals, angular_rate=rate, data=data, sigma=0.01))
        prob.add(Position(t=[sc.t[0]], value=sc.position[0]))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the plausibility notes are not what is tested here
            sol = prob.solve(solver="direct")
        errors[rate] = sol.error_params[["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]].to_numpy() - bias
    assert abs(errors[1e-3][0]) > 0.01
    assert abs(errors["spread"][0]) < 1e-3
    assert np.max(np.abs(errors["spread"][1:])) < 1e-4


def test_zero_angular_rate_needs_a_gyro_model_and_gyro_rates():
    t = np.linspace(0.0, 2.0, 21)
    f = np.tile([0.0, 0.0, 9.80665], (t.size, 1))
    data = ImuData.from_gyro(t, f, np.zeros((t.size, 3)))
    prob = NavigationProblem(data, error_model=error_models.Bias())
    prob.add(ZeroAngularRate(t=(0.0, 1.0)), ZeroVelocity(t0=0.0, t1=2.0), Position(t=[0.0], value=0.0))
    with pytest.raises(InputError, match=r"ZeroAngularRate.*no gyro error model.*GyroBias"):
        prob.solve(solver="direct")
    with pytest.raises(InputError, match="body axes"):
        ZeroAngularRate(t=(0.0, 1.0), axes=("east",))
    with pytest.raises(InputError, match=r"t=\(t0, t1\)"):
        ZeroAngularRate(t=0.5)


def _circle(n=2001, T=20.0, bias=(0.02, -0.01)):
    """One lap of a circle of radius 5 m in T s (ends where it starts, at rest speed)."""
    t = np.linspace(0.0, T, n)
    w = 2 * np.pi / T
    pos = 5.0 * np.column_stack([np.cos(w * t) - 1.0, np.sin(w * t)])
    acc = -5.0 * w**2 * np.column_stack([np.cos(w * t), np.sin(w * t)])
    vel0 = np.array([0.0, 5.0 * w])
    return t, pos, acc + np.asarray(bias), vel0


def test_same_position_determines_a_bias_exactly():
    t, pos, acc, v0 = _circle()
    data = ImuData(t, acc, axes=("x", "y"))
    prob = NavigationProblem(data, error_model=error_models.Bias())
    prob.add(Position(t=[0.0], value=0.0), Velocity(t=[0.0], value=v0), SamePosition(t=(0.0, t[-1])))
    sol = prob.solve(solver="direct")
    np.testing.assert_allclose(sol.error_params.to_numpy(), [0.02, -0.01], atol=1e-4)
    # the FEM's own error is O(h^2): halving h quarters the bias error
    t2, _, acc2, _ = _circle(n=4001)
    prob2 = NavigationProblem(ImuData(t2, acc2, axes=("x", "y")), error_model=error_models.Bias())
    prob2.add(Position(t=[0.0], value=0.0), Velocity(t=[0.0], value=v0), SamePosition(t=(0.0, t2[-1])))
    e1 = np.abs(sol.error_params.to_numpy() - [0.02, -0.01]).max()
    e2 = np.abs(prob2.solve(solver="direct").error_params.to_numpy() - [0.02, -0.01]).max()
    assert 3.0 < e1 / e2 < 5.0
    # with a linear acceleration the FEM is exact: the bias to rounding
    tl = np.linspace(0.0, 10.0, 101)
    accl = np.column_stack([0.3 - 0.09 * tl, -0.2 + 0.06 * tl]) + [0.05, 0.01]  # closes: r(10) = r(0)
    prob3 = NavigationProblem(ImuData(tl, accl, axes=("x", "y")), error_model=error_models.Bias())
    prob3.add(Position(t=[0.0], value=0.0), Velocity(t=[0.0], value=0.0), SamePosition(t=(0.0, 10.0)))
    np.testing.assert_allclose(prob3.solve(solver="direct").error_params.to_numpy(), [0.05, 0.01], atol=1e-9)


def test_same_position_pairs_and_bad_pairs():
    item = SamePosition(t=[(0.0, 10.0), (2.0, 7.5)])
    assert item.t.shape == (2, 2)
    with pytest.raises(InputError, match="one instant twice"):
        SamePosition(t=(3.0, 3.0))
    with pytest.raises(InputError, match="two instants"):
        SamePosition(t=(1.0, 2.0, 3.0))


def test_floor_height_exact_and_band():
    """z reads a 2 mm/s^2 bias; ends fixed at 0 and a flat floor at one more instant give the
    bias exactly (the linear acceleration makes the FEM exact)."""
    t = np.linspace(0.0, 10.0, 101)
    acc = np.column_stack([0.1 - 0.02 * t, 0.002 + 0 * t])
    data = ImuData(t, acc, axes=("x", "z"))
    prob = NavigationProblem(data, error_model=error_models.Bias(axes=("z",)))
    prob.add(Position(t=[0.0], value=0.0), Velocity(t=[0.0], value=0.0),
             FloorHeight(t=[0.0, 4.0, 10.0], value=[0.0, 0.0, 0.0], axis="z"))
    sol = prob.solve(solver="direct")
    assert sol.error_params.iloc[0] == pytest.approx(0.002, abs=1e-12)
    np.testing.assert_allclose(sol.position("z"), 0.0, atol=1e-10)
    # a ramp: heights 0, 0.05, 0.2 m are followed exactly when the data says so
    ramp = FloorHeight(t=[1.0, 5.0, 9.0], value=[0.0, 0.05, 0.2], axis="z")
    rows = ramp.compile(_model(data))
    assert rows.c.tolist() == pytest.approx([-0.05, -0.2])
    # a band keeps every height difference within tol
    band = NavigationProblem(data)
    band.add(Position(t=[0.0, 10.0], value=0.0),
             FloorHeight(t=[2.0, 5.0, 8.0], axis="z", mode="band", tol=0.001))
    z = band.solve(solver="clarabel").position("z")
    zk = np.interp([2.0, 5.0, 8.0], t, z)
    assert np.max(np.abs(zk[1:] - zk[0])) <= 0.001 + 1e-7
    assert np.max(np.abs(zk[1:] - zk[0])) > 0.0009  # the band is active: the bias pulls z away


def _model(data):
    from bvpnav import NavModel

    return NavModel(data)


def test_floor_height_bad_input():
    with pytest.raises(InputError, match="at least two"):
        FloorHeight(t=[1.0])
    with pytest.raises(InputError, match="3 heights for 2 instants"):
        FloorHeight(t=[1.0, 2.0], value=[0.0, 1.0, 2.0])
    with pytest.raises(InputError, match="one axis"):
        FloorHeight(t=[1.0, 2.0], axes=("x", "z"))


def test_known_distance_determines_a_scale_factor():
    """A straight walk of 6.67 m along a heading of 30 deg, the x accelerometer 3 % high: the start
    at rest and the known distance give the scale factor exactly (linear acceleration: the FEM
    is exact; the linearization converges to the true direction)."""
    t = np.linspace(0.0, 10.0, 201)
    a_true = 0.4 - 0.08 * t                       # s(t) = 0.2 t^2 - 0.08 t^3 / 6, at rest at 10 s
    d = 0.2 * 100 - 0.08 * 1000 / 6
    u = np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    acc = a_true[:, None] * u[None, :] * [1.03, 1.0]
    data = ImuData(t, acc, axes=("x", "y"))
    prob = NavigationProblem(data, error_model=error_models.ScaleFactor(axes=("x",)))
    prob.add(Position(t=[0.0], value=0.0), Velocity(t=[0.0], value=0.0),
             KnownDistance(t=(0.0, 10.0), distance=d))
    sol = prob.solve(solver="direct")
    assert np.linalg.norm(sol.position()[-1]) == pytest.approx(d, abs=1e-9)
    np.testing.assert_allclose(sol.position()[-1], d * u, atol=1e-8)
    assert sol.error_params.iloc[0] == pytest.approx(0.03, abs=1e-9)
    with pytest.raises(InputError, match="length 1.41421, not 1"):
        KnownDistance(t=(0.0, 1.0), distance=1.0, direction=(1.0, 1.0, 0.0))
    with pytest.raises(InputError, match="distance > 0"):
        KnownDistance(t=(0.0, 1.0), distance=0.0)


def test_yaw_rate_gyro_bias_held_at_its_prior_without_heading_information():
    """A noise-free simulated walk (constant gyro bias, exact stances) with stances and the start
    only: nothing tells the yaw-rate bias from the swings' own errors, so the loop holds it at its
    prior (here 0, then 1e-3 rad/s) to 1e-9 and says so, while x and y (tilt, seen by the stances)
    are recovered to 15 %; with a ZeroAngularRate on z it is estimated again (no hold)."""
    sc = walking(rate=100.0, n_strides=8, accel_noise=0.0, gyro_noise=0.0, accel_bias=0.0, gyro_bias=0.004,
                 seed=2)
    bias = sc.data.gyro[sc.params["stance"]].mean(axis=0)
    intervals = sc.params["stance_intervals"]
    names = ["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]
    for prior in (0.0, 1e-3):
        model = error_models.GyroBias(sigma=0.05, prior=[0.0, 0.0, prior])
        prob = NavigationProblem(sc.data, error_model=model)
        prob.add(*detect.zero_velocity_items(intervals, sigma=0.01))
        prob.add(Position(t=[sc.t[0]], value=sc.position[0]))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sol = prob.solve(solver="direct", attitude={"tol": 1e-9})
        est = sol.error_params[names].to_numpy()
        assert abs(est[2] - prior) < 1e-9
        np.testing.assert_allclose(est[:2], bias[:2], rtol=0.15)
        held = [str(w.message) for w in caught if "heading information" in str(w.message)]
        assert len(held) == 1 and "gyro_bias_z held at the prior" in held[0]
        assert "ZeroAngularRate on axis z" in held[0]
        assert held[0] in sol.warnings
        assert sol.stats["sequential"]["held"] == ["gyro_bias_z"]
    prob = NavigationProblem(sc.data, error_model=error_models.GyroBias())
    prob.add(*detect.zero_velocity_items(intervals, angular_rate=1e-5, sigma=0.01))
    prob.add(Position(t=[sc.t[0]], value=sc.position[0]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = prob.solve(solver="direct")
    assert "held" not in sol.stats["sequential"]
    assert abs(sol.error_params["gyro_bias_z"] - bias[2]) < 1e-6


def test_gyro_bias_hold_names_the_axes():
    assert error_models.GyroBias(hold="z").hold == ("z",)
    with pytest.raises(InputError, match=r"hold='q'.*estimated body axes"):
        error_models.GyroBias(hold="q")
    with pytest.raises(InputError, match=r"hold=\('z',\).*\['x', 'y'\]"):
        error_models.GyroBias(axes=("x", "y"), hold=("z",))


def test_parts_warnings_name_which_part_the_attitude_models_traded():
    """The chi-square limit for 3 parameters at 0.999 is 16.27: a rise of the motion's part
    beyond it names the stances' gyro readings; a rise of the gyro items' part while the motion's
    falls names the motion's misfit; both falling (or rises within the limit) say nothing."""
    from bvpnav.solve.attitude import parts_warnings

    def parts(m0, g0, m1, g1):
        return {"initial": {"motion": m0, "gyro_items": g0, "priors": 0.0},
                "answer": {"motion": m1, "gyro_items": g1, "priors": 1.0}}

    (a,) = parts_warnings(parts(5679.5, 985674.1, 28855.9, 917816.0), 3)  # measured on a real walk
    assert "fitting the motion worse (5679.5 -> 28855.9" in a and "beyond 16.3 for 3 parameters" in a
    assert "angular_rate='spread'" in a
    (b,) = parts_warnings(parts(5679.5, 7584.0, 3650.6, 7721.4), 3)  # the same walk, 'spread'
    assert "contradict (7584 -> 7721.4" in b and "leave GyroBias out" in b
    assert parts_warnings(parts(19.33, 7984.0, 0.38, 0.0), 3) == []  # a consistent walk: both fall
    assert parts_warnings(parts(100.0, 50.0, 116.0, 10.0), 3) == []  # a rise within the limit
    assert parts_warnings(parts(100.0, 50.0, 116.5, 10.0), 3) != []
    assert parts_warnings(parts(100.0, 50.0, 90.0, 66.0), 3) == []
    assert parts_warnings(None, 3) == [] and parts_warnings({"initial": None, "answer": None}, 3) == []


def test_a_consistent_walk_gives_no_attitude_parts_warning():
    """Noise-free stances reading the bias alone: the gyro items and the motion both fall."""
    sc = walking(rate=100.0, n_strides=3, accel_noise=0.0, gyro_noise=0.0, accel_bias=0.0, gyro_bias=0.004,
                 seed=2)
    prob = NavigationProblem(sc.data, error_model=error_models.GyroBias())
    prob.add(*detect.zero_velocity_items(sc.params["stance_intervals"], angular_rate="spread", data=sc.data,
                                         sigma=0.01))
    prob.add(Position(t=[sc.t[0]], value=sc.position[0]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = prob.solve(solver="direct")
    parts = sol.stats["sequential"]["objective_parts"]
    assert parts["answer"]["motion"] < parts["initial"]["motion"]
    assert parts["answer"]["gyro_items"] < parts["initial"]["gyro_items"]
    assert not [w for w in sol.warnings if w.startswith("attitude models:")]
