# ---
# jupyter:
#   jupytext:
#     text_representation:
#       format_name: percent
# ---

# %% [markdown]
# # 05 · Information a filter cannot use: average velocity and symmetry
#
# A Kalman filter and its RTS smoother take measurements of the *state at one instant*.
# People on the ground often know other things:
#
# - **average velocity**: a tape measure and a stopwatch say the run out took 10 s for
#   10 m, $\frac{1}{t_1 - t_0}\int_{t_0}^{t_1} v\,dt = \frac{r(t_1) - r(t_0)}{t_1 - t_0} = \bar v$;
# - **symmetry**: a shuttle run comes back the way it went, $r(10 + \tau) = r(10 - \tau)$.
#
# Neither is a state at one instant; in bvpnav each is one more item (one linear row
# per constraint). A shuttle run out to 10 m and back in 20 s, 50 Hz, with a 2 % scale
# error, a 0.3 m/s² bias and unit noise; known: at rest at the origin at both ends.

# %%
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import bvpnav
from bvpnav.baselines import rts_smoother
from bvpnav.constraints import AverageVelocity, Position, Symmetry, Velocity
from bvpnav.error_models import Bias
from bvpnav.scenarios import quintic_trajectory

SMALL = os.environ.get("BVPNAV_SMALL") == "1"
FIGURES = Path(os.environ.get("BVPNAV_FIGURES", "figures"))
FIGURES.mkdir(parents=True, exist_ok=True)

p, _, a = quintic_trajectory()
t = np.linspace(0.0, 20.0, 1001)
mirror = np.where(t <= 10.0, t, 20.0 - t)  # out along the quintic, back mirrored
truth = p(mirror)
seeds = range(3) if SMALL else range(10)

ends = [Position(t=[0.0, 20.0], value=[0.0, 0.0], name="ends"),
        Velocity(t=[0.0, 20.0], value=[0.0, 0.0], name="at rest")]
mirror_item = Symmetry(about=10.0, sigma=0.01, name="mirror")
stopwatch = AverageVelocity(t0=[0.0, 10.0], t1=[10.0, 20.0], value=[1.0, -1.0], name="stopwatch")
cases = {"RTS smoother (4 boundary values)": None, "bvpnav, same 4 values": [],
         "bvpnav + symmetry": [mirror_item], "bvpnav + average velocities": [stopwatch],
         "bvpnav + both": [mirror_item, stopwatch]}

# %%
errors = {k: [] for k in cases}
for seed in seeds:
    rng = np.random.default_rng(seed)
    acc = 1.02 * a(mirror) + rng.normal(0.3, 1.0, t.size)
    for name, extra in cases.items():
        if extra is None:  # the smoother: state (position, velocity, bias), exact boundary values
            meas = [(0.0, "position", 0.0, 1e-6), (0.0, "velocity", 0.0, 1e-6),
                    (20.0, "position", 0.0, 1e-6), (20.0, "velocity", 0.0, 1e-6)]
            est = rts_smoother(t, acc, meas, sigma_a=1.0).position.to_numpy()
        else:
            prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=1.0, error_model=Bias())
            est = prob.add(*ends, *extra).solve(solver="direct").position()[:, 0]
        errors[name].append(np.sqrt(np.mean((est - truth) ** 2)))
mean = {k: float(np.mean(v)) for k, v in errors.items()}
for k, v in mean.items():
    print(f"{k:<34} {v:.3f} m RMS")

# %% [markdown]
# **The number this tutorial teaches:** with the same four boundary values bvpnav and
# the smoother are the same estimator (equal errors); the two pieces of information a
# smoother cannot take reduce the error by more than a factor of two.

# %%
assert abs(mean["bvpnav, same 4 values"] / mean["RTS smoother (4 boundary values)"] - 1) < 0.02
assert mean["bvpnav + both"] < mean["bvpnav, same 4 values"] / 2

fig, ax = plt.subplots(figsize=(6, 3.5))
ax.bar(range(len(mean)), list(mean.values()))
ax.set_xticks(range(len(mean)), [k.replace("bvpnav ", "").replace(" (4 boundary values)", "") for k in mean],
              rotation=20, ha="right")
ax.set(ylabel="mean RMS position error (m)", title="Information beyond the state")
fig.tight_layout()
fig.savefig(FIGURES / "05_information.png", dpi=100)
