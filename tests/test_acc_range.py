"""ImuData(..., acc_range=): clipped impacts get a large sigma, and the count is reported (issue 38)."""

from __future__ import annotations

import numpy as np
import pytest

from bvpnav import ImuData, NavigationProblem
from bvpnav.constraints import Position, Velocity
from bvpnav.errors import InputError
from bvpnav.log import SaturationWarning

pytestmark = pytest.mark.filterwarnings("ignore:misfit")

G = 9.80665
RANGE = 156.9  # 16 g
T = np.arange(301) * 0.005


def at_rest_with_impact():
    """A level z-up sensor at rest; a heel strike of 300 m/s^2 on z clipped at 16 g (4 samples)."""
    f = np.tile([0.0, 0.0, G], (T.size, 1))
    f[150:154, 2] = min(300.0, RANGE)
    f[150:154, 0] = 40.0  # the impact also rings x (not clipped)
    return f


def solve(data):
    prob = NavigationProblem(data, sigma_a=0.05)
    prob.add(Position(t=[T[0], T[-1]], value=0.0), Velocity(t=[T[0], T[-1]], value=0.0))
    return prob.solve(solver="direct")


def test_clipped_impact_is_weighted_down_and_counted():
    f = at_rest_with_impact()
    plain = solve(ImuData.from_gyro(T, f, np.zeros((T.size, 3)), checks=False))
    bent = np.abs(plain.position()).max()
    assert bent > 1e-2  # the impact bends the path of a sensor at rest
    with pytest.warns(SaturationWarning, match=r"4 of 301 samples .* acc_range = 156.9"):
        data = ImuData.from_gyro(T, f, np.zeros((T.size, 3)), checks=False, acc_range=RANGE)
    assert np.flatnonzero(data.acc_clipped).tolist() == [150, 151, 152, 153]
    sol = solve(data)
    # sigma 156.9 against 0.05 at the clipped samples: the bend shrinks by about (0.05/156.9)^2
    # times the number of unclipped samples that would share it (measured 4.2e-6 m)
    assert np.abs(sol.position()).max() < 1e-3 * bent
    assert sol.stats["data_checks"]["acc_range"]["samples"] == 4
    assert any("acc_range = 156.9" in w for w in sol.warnings)
    # the residual takes the clipped excess there (all but a 2e-5 share, spread over the rest)
    assert sol.residuals["w_z"].to_numpy()[150] == pytest.approx(-(RANGE - G), rel=1e-4)


def test_no_clipping_no_change_and_margin():
    f = at_rest_with_impact()
    f[150:154, 2] = RANGE * (1 - 0.01)  # 1 % under the range: a measured peak, not clipped
    data = ImuData.from_gyro(T, f, np.zeros((T.size, 3)), checks=False, acc_range=RANGE)
    assert data.checks["acc_range"]["samples"] == 0 and data.checks["acc_range"]["warning"] is None
    ref = ImuData.from_gyro(T, f, np.zeros((T.size, 3)), checks=False)
    np.testing.assert_array_equal(solve(data).position(), solve(ref).position())
    f[150, 1] = -RANGE * (1 - 0.004)  # within the 0.5 % margin on another axis, negative
    with pytest.warns(SaturationWarning):
        data = ImuData.from_gyro(T, f, np.zeros((T.size, 3)), checks=False, acc_range=RANGE)
    assert np.flatnonzero(data.acc_clipped).tolist() == [150]


def test_acc_range_bad_input():
    with pytest.raises(InputError, match="acc_range"):
        ImuData(T, acc=np.zeros((T.size, 2)), acc_range=RANGE)
    with pytest.raises(InputError, match="acc_range"):
        ImuData.from_gyro(T, at_rest_with_impact(), np.zeros((T.size, 3)), checks=False, acc_range=-1.0)
