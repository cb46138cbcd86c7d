"""Information a Kalman/RTS smoother cannot use: symmetry and average velocities.

A shuttle run: out 10 m and back on [0, 20] s (the 2011 paper's quintic, mirrored about
t = 10 s), 50 Hz accelerometer with scale error, bias and white noise. Known: start and
end at rest at the origin (the four boundary values). An RTS smoother with state
(position, velocity, bias) uses exactly those four measurements. bvpnav also knows,
as people on the ground typically do:

- **symmetry**: the way back mirrors the way out, r(10 + tau) = r(10 - tau)
  (``Symmetry(about=10, sigma=0.01)``: one row per mirrored pair, good to 1 cm; as a
  hard item its pair tau = 10 s would repeat the end positions, and a repeated hard row
  makes the KKT matrix singular);
- **average velocities**: 1 m/s out over [0, 10] s and -1 m/s back over [10, 20] s
  (``AverageVelocity``: from a tape measure and a stopwatch).

Neither is a measurement of the state at one instant, so a smoother cannot take it
without augmenting its state with lagged copies; bvpnav takes it as one more item.
Printed: mean RMS position error (m) over seeded realisations.

Run ``python examples/information_smoothers_cannot_use.py`` (20 realisations).
"""

from __future__ import annotations

import argparse

import numpy as np

import bvpnav
from bvpnav.baselines import rts_smoother
from bvpnav.constraints import AverageVelocity, Position, Symmetry, Velocity
from bvpnav.error_models import Bias
from bvpnav.scenarios import quintic_trajectory

RATE, SCALE, BIAS, NOISE = 50.0, 0.02, 0.3, 1.0


def shuttle(seed: int, rate: float = RATE):
    """Sample times (s), measured acceleration (m/s^2) and true position (m)."""
    p, _, a = quintic_trajectory()
    t = np.linspace(0.0, 20.0, int(round(20 * rate)) + 1)
    mirror = np.where(t <= 10.0, t, 20.0 - t)
    rng = np.random.default_rng(seed)
    acc = (1 + SCALE) * a(mirror) + rng.normal(BIAS, NOISE, t.size)
    return t, acc, p(mirror)


def realisation(seed: int) -> dict:
    t, acc, truth = shuttle(seed)
    data = bvpnav.ImuData(t=t, acc=acc)
    ends = [Position(t=[0.0, 20.0], value=[0.0, 0.0], name="ends"),
            Velocity(t=[0.0, 20.0], value=[0.0, 0.0], name="end velocities")]
    out = {}
    meas = [(0.0, "position", 0.0, 1e-6), (0.0, "velocity", 0.0, 1e-6),
            (20.0, "position", 0.0, 1e-6), (20.0, "velocity", 0.0, 1e-6)]
    rts = rts_smoother(t, acc, meas, sigma_a=NOISE)
    out["RTS smoother (4 boundary values)"] = np.sqrt(np.mean((rts.position.to_numpy() - truth) ** 2))

    def run(*extra):
        prob = bvpnav.NavigationProblem(data, sigma_a=NOISE, error_model=Bias()).add(*ends, *extra)
        return prob.solve(solver="direct").rms_error(truth)

    out["bvpnav, 4 boundary values"] = run()
    out["bvpnav + symmetry"] = run(Symmetry(about=10.0, sigma=0.01, name="mirror"))
    out["bvpnav + average velocities"] = run(AverageVelocity(t0=[0.0, 10.0], t1=[10.0, 20.0],
                                                             value=[1.0, -1.0], name="stopwatch"))
    out["bvpnav + both"] = run(Symmetry(about=10.0, sigma=0.01, name="mirror"),
                               AverageVelocity(t0=[0.0, 10.0], t1=[10.0, 20.0], value=[1.0, -1.0],
                                               name="stopwatch"))
    return out


def run(seeds: int = 20, quiet: bool = False) -> dict:
    res = [realisation(s) for s in range(seeds)]
    mean = {k: float(np.mean([r[k] for r in res])) for k in res[0]}
    if not quiet:
        print(f"shuttle run, 20 s at {RATE:g} Hz, scale {SCALE:+g}, bias {BIAS:+g} m/s^2, noise {NOISE:g} "
              f"m/s^2; mean RMS position error over {seeds} realisations")
        for k, v in mean.items():
            print(f"{k:<36} {v:8.3f} m")
    return mean


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    return run(ap.parse_args(argv).seeds)


if __name__ == "__main__":
    main()
