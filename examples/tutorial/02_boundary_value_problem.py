# ---
# jupyter:
#   jupytext:
#     text_representation:
#       format_name: percent
# ---

# %% [markdown]
# # 02 · The same data as a boundary value problem
#
# Post-processing knows more than the start: here, where the motion *ended* too. Posed
# as a boundary value problem $r''(t) = a(t)$, $r(0) = r_0$, $r(T) = r_1$, the same
# biased data no longer drift. With a constant bias $b$ the error $e = r - p$ solves
# $e'' = b$, $e(0) = e(T) = 0$, so
#
# $$ e(t) = -\tfrac12\, b\, t\,(T - t), \qquad \max |e| = \frac{b T^2}{8} , $$
#
# four times smaller than the initial-value drift at the end (tutorial 01), and zero at
# both ends. Linear finite elements reproduce this parabola exactly at the nodes.

# %%
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import bvpnav
from bvpnav import baselines
from bvpnav.constraints import Position
from bvpnav.scenarios import quintic_trajectory

SMALL = os.environ.get("BVPNAV_SMALL") == "1"
FIGURES = Path(os.environ.get("BVPNAV_FIGURES", "figures"))
FIGURES.mkdir(parents=True, exist_ok=True)

p, v, a = quintic_trajectory()
rate = 20.0 if SMALL else 50.0
t = np.linspace(0.0, 10.0, int(10 * rate) + 1)
bias = 0.05  # m/s^2
acc = a(t) + bias

# %% [markdown]
# The problem: the data, and one item, the positions at both ends (hard: Dirichlet
# conditions). Every unknown's equation is shown by `describe()`.

# %%
prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc))
prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends"))
print(prob.describe(conditioning=False))
sol = prob.solve()
err_bvp = sol.position()[:, 0] - p(t)

_, r_ivp = baselines.trapezoid(t, acc)
err_ivp = r_ivp - p(t)
print(f"max |error|: initial-value {np.max(np.abs(err_ivp)):.4f} m, boundary-value "
      f"{np.max(np.abs(err_bvp)):.4f} m (b T^2 / 8 = {bias * 100 / 8:.4f} m)")

# %% [markdown]
# **The number this tutorial teaches:** the error the bias causes is the parabola
# $-\tfrac12 b t (T-t)$, at most $bT^2/8$ = 0.625 m. The problem is linear in the data,
# so that part is the difference between the solutions from biased and from exact
# samples, and linear elements reproduce it exactly at the nodes (the rest of
# `err_bvp` is the FEM's O(h²) error on the quintic itself, below 1 cm here).

# %%
parabola = -0.5 * bias * t * (10.0 - t)
clean = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=a(t))).add(
    Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends")).solve()
from_bias = sol.position()[:, 0] - clean.position()[:, 0]
print(f"error caused by the bias: max {np.max(np.abs(from_bias)):.6f} m; "
      f"differs from the parabola by {np.max(np.abs(from_bias - parabola)):.1e} m")
assert abs(np.max(np.abs(from_bias)) - bias * 100 / 8) < 1e-9
assert np.max(np.abs(from_bias - parabola)) < 1e-9
assert np.max(np.abs(err_bvp - parabola)) < 1e-2

fig, ax = plt.subplots(figsize=(6, 3.5))
ax.plot(t, err_ivp, label="initial value (trapezoid)")
ax.plot(t, err_bvp, label="boundary value (FEM, both ends fixed)")
ax.plot(t, parabola, "k:", label=r"$-\frac{1}{2} b t (T-t)$")
ax.set(xlabel="t (s)", ylabel="position error (m)", title="Fixing both ends stops the drift")
ax.legend()
fig.tight_layout()
fig.savefig(FIGURES / "02_bvp.png", dpi=100)
