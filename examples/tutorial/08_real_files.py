# ---
# jupyter:
#   jupytext:
#     text_representation:
#       format_name: percent
# ---

# %% [markdown]
# # 08 · From the files you have: a foot-mounted IMU and a ROS bag
#
# Real recordings come as files of what the sensor measured: specific force and gyro
# rates in the sensor's axes, on the logger's clock, perhaps with GNSS fixes beside them.
# A *reader* turns each into samples and information (see the guide page *Real inputs*),
# saying in `notes` everything it did to the data.
#
# The number of this lesson: a foot-mounted IMU walked 10 strides (13.7 m) is about
# 0.8 m off when it is only integrated from rest, and under 4 cm once the stances that
# `bvpnav.detect` finds in the data hold the velocity at zero (a zero-velocity update, a
# boundary condition at every step): twenty times better, from the data alone.

# %%
import os
from pathlib import Path

import numpy as np
import pandas as pd

import bvpnav
from bvpnav import detect, readers
from bvpnav.constraints import Position, Velocity
from bvpnav.samples import write_sample
from bvpnav.spec import load_spec

SMALL = os.environ.get("BVPNAV_SMALL") == "1"
FIGURES = Path(os.environ.get("BVPNAV_FIGURES", "figures"))
FIGURES.mkdir(parents=True, exist_ok=True)
WORK = Path(os.environ.get("BVPNAV_WORK", "tutorial-08"))

# %% [markdown]
# ## A strapdown table: what `bvpnav simulate walking` writes
#
# The recording holds `t, f_x, f_y, f_z, w_x, w_y, w_z`; the spec's `[input]` names the
# columns, their units and the navigation frame, and its `[stationary]` asks for the
# stances to be detected.

# %%
write_sample("walking", WORK, force=True)
spec = load_spec(WORK / "spec.toml")
rec = readers.read(WORK / "recording.csv", spec.input)
data = rec.imu_data(spec.input)
truth = pd.read_csv(WORK / "truth.csv")[["x", "y", "z"]].to_numpy()
print({k: spec.input[k] for k in ("specific_force", "gyro", "frame")})
print(f"{data.n} samples over {data.t[-1]:.2f} s")

# %% [markdown]
# ## Integrated from rest, then with the detected stances

# %%
start = Position(t=0.0, value=truth[0].tolist(), name="start")
rest = Velocity(t=0.0, value=[0.0, 0.0, 0.0], name="at rest")
drift = bvpnav.NavigationProblem(data).add(start, rest).solve(solver="direct")
found = detect.stationary(data, method="shoe", return_statistic=True)
zupt = bvpnav.NavigationProblem(data).add(start, *detect.zero_velocity_items(found, name="stance"))
sol = zupt.solve(solver="direct")
rms_drift, rms_zupt = drift.rms_error(truth), sol.rms_error(truth)
print(f"{len(found.intervals)} stances found (the walk has 11)")
print(f"RMS position error, integrated from rest: {rms_drift:.2f} m")
print(f"RMS position error, with the stances:     {rms_zupt:.3f} m")
assert len(found.intervals) == 11
assert rms_zupt < 0.1 and rms_drift > 10 * rms_zupt  # measured 0.037 m and 0.78 m

# %%
from bvpnav import plot  # noqa: E402

fig = plot.stationary(data, found)
fig.savefig(FIGURES / "08_stationary.png", dpi=80)

# %% [markdown]
# ## A ROS 2 bag with IMU and GNSS topics
#
# The `rosbag` reader (`pip install 'bvpnav[ros]'`) takes the `sensor_msgs/Imu` topic as
# the samples and the `NavSatFix` topic as a soft `Position` item in local ENU about the
# first fix, with the fixes' covariance as sigma; every stamp is an integer nanosecond.

# %%
from bvpnav.readers.rosbag import write_example_bag  # noqa: E402

bag = write_example_bag(WORK / "bag", duration=4.0 if SMALL else 10.0, rate=50.0, accel_noise=0.05, seed=1)
rec = readers.read(bag.path)
for note in rec.notes[:3]:
    print("-", note)
sol = bvpnav.NavigationProblem(rec.imu_data(), sigma_a=0.05).add(*rec.items).solve(solver="direct")
err = np.abs(sol.trajectory[["x", "y", "z"]].to_numpy() - bag.truth[["x", "y", "z"]].to_numpy()).max()
print(f"largest position error with 5 cm fixes once a second: {err:.3f} m")
assert err < 0.3
