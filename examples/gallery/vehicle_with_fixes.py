# ---
# jupyter:
#   jupytext:
#     text_representation:
#       format_name: percent
# ---

# %% [markdown]
# # A vehicle with GNSS fixes
#
# A simulated car drive ({func}`bvpnav.scenarios.car_drive`: a tactical-grade strapdown
# IMU, fixes once a second with 1 m horizontal and 2 m vertical noise). The fixes are
# soft {class}`~bvpnav.constraints.Position` items; twenty seconds of them are withheld
# (an outage: a tunnel) and the accelerometer bias is estimated with the path. The solve
# returns standard deviations (`uncertainty=True`), drawn as bands that widen in the
# outage; {mod}`bvpnav.evaluate` gives the error against the truth.
#
# Runs as a script (`python examples/gallery/vehicle_with_fixes.py`); `BVPNAV_SMALL=1`
# runs a 60 s drive at 20 Hz (the site's build), otherwise 180 s at 100 Hz.

# %%
import os

import numpy as np

import bvpnav
from bvpnav import evaluate, report
from bvpnav.constraints import Position
from bvpnav.error_models import Bias
from bvpnav.scenarios import car_drive

SMALL = os.environ.get("BVPNAV_SMALL") == "1"
drive = car_drive(duration=60.0 if SMALL else 180.0, rate=20.0 if SMALL else 100.0, grade="tactical")
outage = (drive.fix_t > 25.0) & (drive.fix_t < 45.0)      # s: no fixes in the tunnel
kept = ~outage

prob = bvpnav.NavigationProblem(drive.data(), error_model=Bias())
prob.add(Position(t=drive.fix_t[kept], value=drive.fix_position[kept],
                  sigma=np.tile(drive.fix_sigma, (int(kept.sum()), 1)), name="gnss"))
sol = prob.solve(solver="direct", lam=1.0, uncertainty=True)
print(sol)
print(f"{kept.sum()} fixes used, {outage.sum()} withheld from {drive.fix_t[outage][0]:.0f} s "
      f"to {drive.fix_t[outage][-1]:.0f} s")

# %% [markdown]
# The main figures of the solution's quality report ({func}`bvpnav.report.figures`, the
# figures `sol.report("report.html")` embeds): the map with the fixes and the truth, the
# position and velocity with their ±2σ bands (wider in the outage), each fix's normalized
# residual, and the estimated sensor errors with their standard deviations.

# %%
figures = report.figures(sol, items=prob.items, truth=drive.position)
print("report figures:", ", ".join(figures))
assert {"map", "solution", "residuals"} <= set(figures)
sol.report("vehicle_report.html", items=prob.items, truth=drive.position)   # the whole report, one file

# %% [markdown]
# The absolute trajectory error with no alignment (the fixes fix the frame), over the
# whole drive and in the outage alone:

# %%
truth = evaluate.Trajectory(drive.t, drive.position, name="truth")
ape = evaluate.ape(evaluate.Trajectory.from_solution(sol), truth, align="none")
print(evaluate.format_result(ape))
err = np.linalg.norm(sol.position().reshape(-1, 3) - drive.position, axis=1)
gap = (drive.t > 25.0) & (drive.t < 45.0)
print(f"RMS position error: {np.sqrt(np.mean(err[~gap] ** 2)):.2f} m with fixes, "
      f"{np.sqrt(np.mean(err[gap] ** 2)):.2f} m in the outage")
assert np.sqrt(np.mean(err ** 2)) < 5.0
fig = evaluate.plot(ape)
