"""SensorGrade.error_states: the node-state model of the documented drive path from a grade's figures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bvpnav import InputError, NavigationProblem
from bvpnav.constraints import Position
from bvpnav.log import BvpnavWarning
from bvpnav.sensors import from_datasheet, grade


def test_figures_map_to_the_states_process_and_priors():
    g = grade("tactical")
    m = g.error_states()
    assert (m.arw, m.gyro_drift, m.acc_drift) == (g.gyro_noise, g.gyro_bias_walk, g.acc_bias_walk)
    np.testing.assert_array_equal(m.attitude_sigma, [g.tilt, g.tilt, np.inf])
    np.testing.assert_array_equal(m.gyro_sigma, [g.gyro_bias] * 3)
    np.testing.assert_array_equal(m.acc_sigma, [g.acc_bias] * 3)
    assert g.error_states(heading_sigma=0.05).attitude_sigma[2] == 0.05
    assert g.error_states(heading_sigma=math.inf).attitude_sigma[2] == np.inf
    # the same heading rule as error_model(): the grade's own heading when given
    fig = dict(acc_noise=1e-3, acc_bias=0.01, acc_bias_walk=1e-4, gyro_noise=1e-4, gyro_bias=1e-3,
               gyro_bias_walk=1e-5, tilt=0.01)
    assert from_datasheet(**fig, heading=0.2).error_states().attitude_sigma[2] == pytest.approx(0.2)


def test_bad_heading_names_the_option():
    with pytest.raises(InputError, match="heading_sigma"):
        grade("consumer").error_states(heading_sigma=-1.0)


def test_noise_free_drive_recovered_with_the_grade_states():
    """Noise-free drive with zero sensor errors (the grade's priors centred on the truth): the grade's
    node states on a 1 s mesh, the documented path, return the truth to 1e-6 m and 1e-8 rad."""
    from error_models.test_error_states import const, simulate

    d = simulate(const([0.0, 0.0, 0.0]), const([0.0, 0.0, 0.0]), T=20.0, rate=20.0)
    g = grade("tactical")
    prob = NavigationProblem(d["data"], error_model=g.error_states(), sigma_a=g.sigma_a(20.0), segment=1.0)
    k = np.arange(0, d["t"].size, 20)
    prob.add(Position(t=d["t"][k], value=d["r"][k], sigma=0.01))
    with pytest.warns(BvpnavWarning, match="misfit: .* only"):   # noise-free: residuals far below the sigmas
        sol = prob.solve(solver="direct", attitude={"progress": False})
    assert prob.formulation.model.N < d["t"].size / 10          # solved on the mesh
    assert np.abs(sol.position() - d["r"]).max() < 1e-6
    assert np.abs((sol.attitude * d["C"].inv()).as_rotvec()).max() < 1e-8
    assert sol.stats["verified"]
