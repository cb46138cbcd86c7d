# ---
# jupyter:
#   jupytext:
#     text_representation:
#       format_name: percent
# ---

# %% [markdown]
# # A solver comparison
#
# {func}`bvpnav.compare_solvers` runs one problem through every back end asked for and
# returns a tidy table: status, wall time, bvpnav's own verification of each answer
# (FEM residual, hard-item violation, forward error) and the error against a reference.
# The problem here is a walk with detected stances (as in the walker page), in three
# axes with several hundred samples.
#
# Runs as a script (`python examples/gallery/solver_comparison.py`); `BVPNAV_SMALL=1`
# walks 3 strides at 50 Hz (the site's build), otherwise 10 at 100 Hz. Wall times depend
# on the machine and its load: read them as orders of magnitude.

# %%
import os

import numpy as np

import bvpnav
from bvpnav import detect, plot, report
from bvpnav.constraints import Position
from bvpnav.scenarios import walking

SMALL = os.environ.get("BVPNAV_SMALL") == "1"
sc = walking(rate=50.0 if SMALL else 100.0, n_strides=3 if SMALL else 10, seed=1)
stances = detect.zero_velocity_items(detect.stationary(sc.data, method="shoe"), name="stance")
prob = bvpnav.NavigationProblem(sc.data).add(Position(t=[0.0], value=sc.position[0], name="start"), *stances)

# OSQP capped at 4,000 iterations (it would otherwise run long for a first-order method's accuracy)
table = bvpnav.compare_solvers(prob, solvers=["direct", "csne", "clarabel", "osqp"], lam=1.0,
                               reference=sc.position, options={"osqp": {"max_iter": 4000}})
cols = ["solver", "status", "verified", "wall_time", "forward_error", "rms_error"]
print(f"N = {sc.data.t.size} samples x 3 axes")
print(table[cols].to_string(index=False, float_format="{:.3g}".format))
ok = table[table.verified]
assert {"direct", "csne", "clarabel"} <= set(ok.solver)
assert np.ptp(ok.rms_error) < 1e-3

# %% [markdown]
# The table as a figure: time and accuracy per solver, the verified answers filled.

# %%
fig = plot.comparison(table)

# %% [markdown]
# The direct back end's answer, in the main figures of its quality report
# ({func}`bvpnav.report.figures`): the map, the solution and the normalized residuals.

# %%
figures = report.figures(prob.solve(solver="direct", lam=1.0), items=prob.items, truth=sc.position)
print("report figures:", ", ".join(figures))
