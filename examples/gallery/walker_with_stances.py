# ---
# jupyter:
#   jupytext:
#     text_representation:
#       format_name: percent
# ---

# %% [markdown]
# # A walker with stances
#
# A simulated foot-mounted IMU ({func}`bvpnav.scenarios.walking`: strapdown specific
# force and gyro rates, a small accelerometer and gyro bias) walks a few strides. The
# foot is still at every stance; {func}`bvpnav.detect.stationary` finds those intervals
# in the IMU data alone (the SHOE detector) and
# {func}`bvpnav.detect.zero_velocity_items` turns them into
# {class}`~bvpnav.constraints.ZeroVelocity` items. The start position is the only other
# thing known.
#
# Runs as a script (`python examples/gallery/walker_with_stances.py`); `BVPNAV_SMALL=1`
# walks 5 strides at 50 Hz (the site's build), otherwise 10 at 100 Hz.

# %%
import os

import numpy as np

import bvpnav
from bvpnav import detect, evaluate, plot, report
from bvpnav.constraints import Position
from bvpnav.scenarios import walking

SMALL = os.environ.get("BVPNAV_SMALL") == "1"
sc = walking(rate=50.0 if SMALL else 100.0, n_strides=5 if SMALL else 10, seed=0)
data = sc.data

found = detect.stationary(data, method="shoe", return_statistic=True)
stances = detect.zero_velocity_items(found, name="stance")
print(f"{len(found.intervals)} stationary intervals found in {data.t[-1]:.1f} s")

# %% [markdown]
# What the detector saw: its statistic against the threshold, and the signals with the
# intervals shaded (check the threshold here before trusting a solve).

# %%
fig = plot.stationary(data, found)

# %% [markdown]
# The walk with every stance, against the same walk with only the first and the last
# stance (the still ends: a plain boundary value problem):

# %%
start = Position(t=[0.0], value=sc.position[0], name="start")
sol = bvpnav.NavigationProblem(data).add(start, *stances).solve(solver="direct", lam=1.0)
ends = bvpnav.NavigationProblem(data).add(start, stances[0], stances[-1]).solve(solver="direct", lam=1.0)
rms = {name: float(np.sqrt(np.mean(np.sum((s.position().reshape(-1, 3) - sc.position) ** 2, axis=1))))
       for name, s in (("stances", sol), ("ends only", ends))}
walked = float(np.sum(np.linalg.norm(np.diff(sc.position, axis=0), axis=1)))
print(f"{walked:.1f} m walked; RMS position error {rms['stances']:.3f} m with the stances, "
      f"{rms['ends only']:.2f} m with the still ends alone")
assert rms["stances"] < 0.1 and rms["stances"] < rms["ends only"] / 1.5

# %% [markdown]
# The main figures of its quality report ({func}`bvpnav.report.figures`): the map, the
# solution with one legend entry for all the stances, and each item's normalized
# residuals.

# %%
figures = report.figures(sol, items=[start, *stances], truth=sc.position)
print("report figures:", ", ".join(figures))
assert {"map", "solution", "residuals"} <= set(figures)

# %% [markdown]
# The absolute trajectory error after a rigid alignment (as a motion-capture truth would
# be compared):

# %%
truth = evaluate.Trajectory(data.t, sc.position, name="truth")
ape = evaluate.ape(evaluate.Trajectory.from_solution(sol), truth, align="rigid")
print(evaluate.format_result(ape))
fig = evaluate.plot(ape)
