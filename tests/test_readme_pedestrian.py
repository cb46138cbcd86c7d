"""README's foot-mounted snippet runs as pasted on a simulated foot IMU file (issue 38)."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import matplotlib
import numpy as np

from bvpnav.evaluate import Trajectory, ape
from bvpnav.scenarios import walking

matplotlib.use("Agg")
README = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")


def test_the_pedestrian_snippet_runs(tmp_path, monkeypatch):
    (code,) = re.findall(r"```py\n(.*?)```", README, re.S)
    sc = walking(rate=100.0, n_strides=8, seed=3)
    flip = np.array([1.0, -1.0, -1.0])  # the scenario's z-up body axes as a z-down sensor's
    table = np.column_stack([sc.t, sc.data.specific_force * flip, sc.data.gyro * flip])
    np.savetxt(tmp_path / "foot.csv", table, delimiter=",")
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), ns)  # noqa: S102 (our own README)
    sol = ns["sol"]
    assert "stationary intervals" in out.getvalue()
    # NED north/east against the scenario's ENU east/north, after the 2-D rigid fit
    est = sol.position().reshape(-1, 3)[:, [1, 0]]
    err = ape(Trajectory(sc.t, est), Trajectory(sc.t, sc.position[:, :2]), align="yaw")
    assert err.rmse < 0.05, err.rmse
    assert np.all(np.isfinite(sol.trajectory["x_std"]))
