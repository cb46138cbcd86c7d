# ---
# jupyter:
#   jupytext:
#     text_representation:
#       format_name: percent
# ---

# %% [markdown]
# # A lambda study
#
# How much to trust the accelerometer against the other information is the weight
# $\lambda$ of the regularisation term. The 2011 paper's problem
# ({func}`bvpnav.scenarios.tikhonov2011`: a 10 m shuttle in 10 s with a scale error, a
# -0.5 m/s² bias and noise; the ends known; a rough cubic prior at the first and last
# samples) is solved over a sweep of $\lambda$ with {func}`bvpnav.lambda_curve`; the
# rules (L-curve, GCV, quasi-optimality, discrepancy) each pick one, and the truth says
# which pick was good.
#
# Runs as a script (`python examples/gallery/lambda_study.py`); `BVPNAV_SMALL=1` sweeps
# 15 values (the site's build), otherwise 30.

# %%
import os

import numpy as np
import pandas as pd

import bvpnav
from bvpnav import plot, report
from bvpnav.constraints import Position
from bvpnav.scenarios import tikhonov2011

SMALL = os.environ.get("BVPNAV_SMALL") == "1"
sc = tikhonov2011(rate=50.0, seed=3)
t = sc.t
tp = np.concatenate([t[1:11], t[-11:-1]])
prob = bvpnav.NavigationProblem(sc.data, sigma_a=1.0)
prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends"),
         Position(t=tp, value=sc.prior(tp), sigma=1.0, name="cubic prior"))

curve = bvpnav.lambda_curve(prob, rules=("lcurve", "gcv", "quasi", "discrepancy"), points=15 if SMALL else 30)
solutions = {rule: prob.solve(lam=lam) for rule, lam in curve.chosen.items()}
table = pd.DataFrame([{"rule": rule, "lambda": curve.chosen[rule], "RMS error (m)": s.rms_error(sc.position)}
                      for rule, s in solutions.items()])
print(table.to_string(index=False, float_format="{:.4g}".format))
best = table.set_index("rule")["RMS error (m)"]
assert best["lcurve"] < 0.5 and best["lcurve"] < best["discrepancy"]

# %% [markdown]
# A solve that lets the L-curve choose (`lam="lcurve"`) keeps its curve; the main figures
# of its quality report ({func}`bvpnav.report.figures`) are the solution with the truth,
# the normalized residuals and the L-curve with the chosen $\lambda$:

# %%
sol = prob.solve(lam="lcurve")
figures = report.figures(sol, items=prob.items, truth=sc.position)
print("report figures:", ", ".join(figures))
assert "lcurve" in figures

# %% [markdown]
# The error of each rule's choice against time:

# %%
fig = plot.errors({f"{rule} (λ = {curve.chosen[rule]:.3g})": s for rule, s in solutions.items()},
                  truth=sc.position)
