"""2010 paper, Example 1: a tangential accelerometer on a rotating table (Table 1).

Three ways to get velocity and position along the arc from one accelerometer:

- I   time stepping: trapezoid rule twice from rest, bias removed by averaging the
      at-rest output beforehand;
- II  FEM with both end positions fixed (Dirichlet), same bias removal;
- III FEM with both end positions fixed plus the two end velocities (rest) used to
      estimate a scale factor and a bias (``ScaleFactor() + Bias()``), raw data.

Errors (computed minus true) at T/3, T/2 and 2T/3 are printed beside the paper's
Table 1. The data are simulated (``bvpnav.simulate.rate_table``): the paper's rate
table, sensor and profile are not available, so only the pattern is comparable
(I grows with time, II stays bounded, III is smallest), not the digits.

Run ``python examples/rate_table_2010.py`` (1000 Hz, as the paper) or ``--small``.
"""

from __future__ import annotations

import argparse

import numpy as np

import bvpnav
from bvpnav import simulate
from bvpnav.baselines import trapezoid
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import Bias, ScaleFactor

#: The paper's Table 1: errors at t1 = T/3, t2 = T/2, t3 = 2T/3 (velocity m/s, position m).
PAPER_TABLE1 = {
    1: {"vel": {"I": (0.07, 0.10, 0.12), "II": (0.01, 0.04, 0.06), "III": (0.04, 0.05, 0.04)},
        "pos": {"I": (0.10, 0.49, 1.00), "II": (-0.31, -0.29, -0.15), "III": (-0.10, -0.07, -0.05)}},
    2: {"vel": {"I": (33.24, 65.47, 97.17), "II": (-0.67, 0.50, 1.15), "III": (0.33, 0.54, 0.44)},
        "pos": {"I": (510.96, 1992.99, 4434.70), "II": (-42.34, -43.42, -16.59),
                "III": (-6.78, -4.72, -0.61)}},
}
METHODS = ("I", "II", "III")


def run_test(test: int, rate: float, seed: int = 0, solver: str = "clarabel", **errors) -> dict:
    """Simulate one test and return the errors of methods I-III at T/3, T/2, 2T/3.

    Returns
    -------
    dict
        ``vel`` and ``pos``: method -> three errors (m/s, m); ``params``: method III's
        estimates and the truth; ``times`` (s); ``rest_bias`` (m/s^2).
    """
    sim = simulate.rate_table(test, rate, seed=seed, **errors)
    t = sim.t
    T = sim.duration
    tq = np.array([T / 3.0, T / 2.0, 2.0 * T / 3.0])
    r_true, v_true = sim.truth_at(tq)
    length = float(sim.position[-1])
    rest_bias = float(np.mean(sim.rest_acc))
    a0 = sim.acc - rest_bias

    vel, pos = {}, {}
    v1, r1 = trapezoid(t, a0)
    vel["I"] = np.interp(tq, t, v1) - v_true
    pos["I"] = np.interp(tq, t, r1) - r_true

    ends = Position(t=[0.0, T], value=[0.0, length])
    p2 = bvpnav.NavigationProblem(bvpnav.ImuData(t, a0)).add(ends)
    s2 = p2.solve(solver=solver)
    vel["II"] = p2.model.velocity(tq).value(s2.x) - v_true
    pos["II"] = p2.model.position(tq).value(s2.x) - r_true

    p3 = bvpnav.NavigationProblem(sim.data, error_model=ScaleFactor() + Bias())
    p3.add(ends, Velocity(t=[0.0, T], value=0.0))
    s3 = p3.solve(solver=solver)
    vel["III"] = p3.model.velocity(tq).value(s3.x) - v_true
    pos["III"] = p3.model.position(tq).value(s3.x) - r_true

    # the constant part of the centripetal leak is indistinguishable from a bias
    params = {"estimate": s3.error_params.to_dict(),
              "truth": {"scale_x": sim.errors["scale"], "bias_x": sim.effective_bias},
              "sensor_bias": sim.errors["bias"]}
    return {"vel": vel, "pos": pos, "params": params, "times": tq, "rest_bias": rest_bias,
            "length": length, "N": t.size}


def format_table(results: dict) -> str:
    """Our errors beside the paper's Table 1."""
    lines = []
    for test, res in results.items():
        paper = PAPER_TABLE1[test]
        lines.append(f"Test {test}: N = {res['N']}, arc length {res['length']:.2f} m, "
                     f"t1..t3 = {', '.join(f'{x:.2f}' for x in res['times'])} s")
        for key, unit in (("vel", "m/s"), ("pos", "m")):
            name = "Vel. error" if key == "vel" else "Pos. error"
            lines.append(f"  {name} [{unit}]  {'ours t1':>10} {'t2':>9} {'t3':>9}   |  "
                         f"{'paper t1':>9} {'t2':>9} {'t3':>9}")
            for m in METHODS:
                ours = " ".join(f"{x:9.3f}" for x in res[key][m])
                theirs = " ".join(f"{x:9.2f}" for x in paper[key][m])
                lines.append(f"  {m:<16} {ours}    |  {theirs}")
        est = res["params"]["estimate"]
        tru = res["params"]["truth"]
        lines.append("  III estimates: " + ", ".join(f"{k} = {est[k]:.5g} (true {tru[k]:.5g})" for k in tru))
        lines.append(f"  (true bias_x = sensor bias {res['params']['sensor_bias']:.5g} + mean centripetal "
                     "leak of the tilted mounting)")
        lines.append(f"  at-rest bias estimate for I/II: {res['rest_bias']:.5g} m/s^2")
    return "\n".join(lines)


def main(argv=None) -> dict:
    """Run both tests; return ``{test: run_test(...)}`` and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rate", type=float, default=1000.0, help="sampling rate, Hz (paper: 1000)")
    ap.add_argument("--small", action="store_true", help="100 Hz instead of 1000 Hz (quick)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--tests", type=int, nargs="+", default=[1, 2], choices=[1, 2])
    ap.add_argument("--solver", default="clarabel")
    args = ap.parse_args(argv)
    rate = 100.0 if args.small else args.rate
    results = {k: run_test(k, rate, args.seed, args.solver) for k in args.tests}
    print(format_table(results))
    return results


if __name__ == "__main__":
    main()
