# ---
# jupyter:
#   jupytext:
#     text_representation:
#       format_name: percent
# ---

# %% [markdown]
# # 01 · Double integration drifts
#
# The classical, *initial-value* view of inertial navigation: start from a known position
# and velocity and integrate the measured acceleration twice. Any error in the
# acceleration is integrated twice too. A constant bias $b$ (m/s²) grows into a position
# error of
#
# $$ e(t) = \tfrac12\, b\, t^2 , $$
#
# whatever the integration rule. A better rule (Romberg instead of the trapezoid) removes
# the *discretisation* error, not the *sensor* error.
#
# Run as a script (`python 01_double_integration.py`) or open it as a notebook with
# jupytext. `BVPNAV_SMALL=1` runs it at test size; figures go to `$BVPNAV_FIGURES`
# (default `./figures`).

# %%
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from bvpnav import baselines
from bvpnav.scenarios import quintic_trajectory

SMALL = os.environ.get("BVPNAV_SMALL") == "1"
FIGURES = Path(os.environ.get("BVPNAV_FIGURES", "figures"))
FIGURES.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# The 2011 paper's reference motion: a quintic from 0 m to 10 m in 10 s, at rest at both
# ends, passing -10 m at t = 5 s. We sample its exact acceleration at 50 Hz (20 Hz small).

# %%
p, v, a = quintic_trajectory()
rate = 20.0 if SMALL else 50.0
t = np.linspace(0.0, 10.0, int(10 * rate) + 1)

# %% [markdown]
# ## 1. Clean data: only the integration rule matters

# %%
v_trap, r_trap = baselines.trapezoid(t, a(t))
v_romb, r_romb = baselines.romberg(t, a(t))
err_trap = abs(v_trap[-1] - v(10.0))
err_romb = abs(v_romb[-1] - v(10.0))
print(f"velocity error at 10 s, exact samples: trapezoid {err_trap:.2e} m/s, Romberg {err_romb:.2e} m/s")
assert err_romb < err_trap

# %% [markdown]
# ## 2. A biased accelerometer: the error is the sensor's, and it grows like t²

# %%
bias = 0.05  # m/s^2
v_b, r_b = baselines.romberg(t, a(t) + bias)
drift = r_b - p(t)
print(f"position error at 10 s with a {bias} m/s^2 bias: {drift[-1]:.4f} m "
      f"(1/2 b T^2 = {0.5 * bias * 10.0**2:.4f} m)")

# %% [markdown]
# **The number this tutorial teaches:** the drift at the end is $\tfrac12 b T^2$ = 2.5 m,
# to the integration rule's accuracy.

# %%
assert abs(drift[-1] - 0.5 * bias * 10.0**2) < 1e-6

fig, ax = plt.subplots(figsize=(6, 3.5))
ax.plot(t, drift, label="Romberg, biased data")
ax.plot(t, 0.5 * bias * t**2, "--", label=r"$\frac{1}{2} b t^2$")
ax.set(xlabel="t (s)", ylabel="position error (m)", title="Double integration drifts")
ax.legend()
fig.tight_layout()
fig.savefig(FIGURES / "01_drift.png", dpi=100)
