"""The gyro-bias plausibility check against what the stances show (issue 38)."""

from __future__ import annotations

import numpy as np
import pytest

from bvpnav import NavigationProblem, detect, error_models
from bvpnav.constraints import Position
from bvpnav.error_models import Bias, GyroBias
from bvpnav.scenarios import walking
from bvpnav.solve.plausibility import _kind


def walk_problem(em):
    sc = walking(rate=100.0, n_strides=3, accel_noise=0.0, gyro_noise=0.0, accel_bias=0.0, gyro_bias=0.004,
                 seed=2)
    prob = NavigationProblem(sc.data, error_model=em)
    prob.add(*detect.zero_velocity_items(sc.params["stance_intervals"], angular_rate=True, sigma=0.01))
    prob.add(Position(t=[sc.t[0]], value=sc.position[0]))
    return sc, prob


def gyro_warnings(sol):
    return [w for w in sol.warnings if "gyro bias" in w]


def test_a_bias_equal_to_the_stance_reading_is_not_called_implausible():
    sc, prob = walk_problem(GyroBias())
    sol = prob.solve(solver="direct")
    est = sol.error_params[["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"]].to_numpy()
    np.testing.assert_allclose(est, sc.data.gyro[sc.params["stance"]].mean(axis=0), rtol=0, atol=1e-6)
    assert gyro_warnings(sol) == []  # before: "removes 102 % of the axis's mean measured rate"


@pytest.mark.filterwarnings("ignore:implausible estimate")
def test_a_bias_far_from_the_stance_reading_is_named():
    # a prior of 0.02 rad/s held at 1e-7 beats the stances' rows: the estimate is the prior
    sc, _ = walk_problem(GyroBias())
    prob = NavigationProblem(sc.data, error_model=GyroBias(prior=0.02, sigma=1e-7))
    prob.add(*detect.zero_velocity_items(sc.params["stance_intervals"], angular_rate=0.01, sigma=0.01))
    prob.add(Position(t=[sc.t[0]], value=sc.position[0]))
    sol = prob.solve(solver="direct")
    msgs = gyro_warnings(sol)
    assert msgs and all("still interval" in m for m in msgs)
    assert len(msgs) == 3  # every axis: 0.02 against the stance readings (|.| <= 0.004)


def test_error_models_declare_their_kind():
    assert [_kind(m) for m in (Bias(), GyroBias(), error_models.AttitudeError(), error_models.ScaleFactor(),
                               error_models.Misalignment(), error_models.UnknownGravity(),
                               error_models.GyroScaleFactor())] == [
        "acc_bias", "gyro_bias", "attitude", "scale", "misalignment", "gravity", "gyro_scale"]
