"""The foot-mounted walk benchmark (examples/benchmarks/foot_walk.py) at its quick size.

0.6 lap of the rectangle (51 s) at 100 Hz with consumer MEMS errors, the stances
detected, the start known and a 1 m fix at 15 and 30 s, none in the last 21 s. Measured
first (seed 0): final position error 6.27 m with ``Bias()`` alone against 0.49 m with
``GyroBias + AttitudeError`` (a factor 12.8; RMS 5.44 against 0.42 m); heading at the
end +22.9 against -0.4 degrees; the z gyro bias 4.78e-3 rad/s against a true mean of
5.05e-3 (std 5.7e-4, 5 %). Other seeds vary with the two fixes' noise (seed 1: a factor
4.6 on the final error), so the seed is fixed and the margins are against seed 0.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("scipy")

pytestmark = pytest.mark.slow  # the benchmark's quick run

SCRIPT = Path(__file__).resolve().parents[1] / "examples" / "benchmarks" / "foot_walk.py"


def _load():
    spec = importlib.util.spec_from_file_location("foot_walk_benchmark", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def bench():
    mod = _load()
    return mod, mod.main(["--quick", "--no-gtsam"])


def test_attitude_models_cut_the_final_error(bench):
    mod, rows = bench
    a, b = rows[mod.A], rows[mod.B_]
    assert b["converged"]
    # measured 6.27 m against 0.49 m (12.8x) and RMS 5.44 against 0.42 m (13x)
    assert a["final"] > 5.0 * b["final"], (a["final"], b["final"])
    assert a["rms"] > 5.0 * b["rms"], (a["rms"], b["rms"])
    assert b["rms"] < 1.0
    # the heading at the end: 22.9 degrees off without the models, -0.4 with them
    assert abs(a["heading"]) > 15.0 and abs(b["heading"]) < 3.0, (a["heading"], b["heading"])
    # and better than a spline through the same fixes
    assert rows[mod.C]["final"] > 5.0 * b["final"]


def test_z_gyro_bias_within_three_sigma_or_twenty_percent(bench):
    mod, rows = bench
    walk, b = rows["_walk"], rows[mod.B_]
    est = b["gyro_bias"][:, 2]
    std = b["gyro_bias_std"][:, 2]
    truth = walk.gyro_bias[:, 2]
    # compare at the knots' mean level: the walk's mean bias against the estimate's mean
    err = abs(est.mean() - truth.mean())
    assert std.mean() < 0.2 * abs(truth.mean())  # determined by the data, not by its prior (5e-3)
    assert err < max(3.0 * std.mean(), 0.2 * abs(truth.mean())), (est.mean(), truth.mean(), std.mean())
    # the horizontal axes are seen by the ZUPTs (tilt): much tighter
    for k in (0, 1):
        assert abs(b["gyro_bias"][:, k].mean() - walk.gyro_bias[:, k].mean()) < 0.05 * abs(
            walk.gyro_bias[:, k].mean())


def test_helpers():
    mod = _load()
    t = np.linspace(0.0, 10.0, 11)
    assert mod.stance_times(t, [(1.0, 3.0), (7.0, 7.5)]).tolist() == [1.0, 2.0, 3.0, 7.0]
    assert mod.heading_error(mod.Rotation.from_euler("z", 179, degrees=True),
                             mod.Rotation.from_euler("z", -179, degrees=True)) == pytest.approx(-2.0)
    plan = mod.stride_plan(1.0)
    assert len(plan) == 70 and sum(plan) == pytest.approx(2 * np.pi)  # one lap turns once around
    assert mod.stride_plan(2.0).count(None) == 1  # a pause between the laps
