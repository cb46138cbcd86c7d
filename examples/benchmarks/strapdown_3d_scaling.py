"""Benchmark: 3-D strapdown navigation with the nine-parameter error model, at scale.

The 2010 paper's Section 5.3 setting (a strapdown triad with scale factor, bias and an
unknown gravity vector: nine parameters), simulated for minutes at 100 Hz to 1 kHz:
positions at both ends and velocities at t = 0, T/2, T hard (the paper's constraints),
plus GNSS-like position fixes every 10 s (soft, sigma = 1 m) and 0.05 m/s^2 white
accelerometer noise; the acceleration-residual form with sigma_a = 0.05 m/s^2 and
lambda = 1. Each row is one verified solve:

- ``direct``: bvpnav's default direct back end (QDLDL LDL^T + refinement here);
- ``direct lu``: the same with SuperLU's pivoted LU (``options={"method": "lu"}``);
- ``csne``: the 2011 paper's corrected semi-normal equations;
- ``clarabel``: through cvxpy (compile + solve).

Columns: unknowns (3 N positions + 3 N residuals + velocities + 9 parameters), time in s
and the ratio to the fastest direct solve of the same row, the relative max difference
from the reference (``direct lu`` at the high preset), the worst relative error of the
nine parameters against the simulation's truth, and the RMS position error (m). With
``--memory`` the largest case is re-run once per back end in its own process and its
peak resident memory printed. Timings belong here, never in tests.

Run ``python examples/benchmarks/strapdown_3d_scaling.py [--rates 100,200,500,1000]
[--duration 120] [--memory]``.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from _memory import own_peak_mb, run_case

import bvpnav
from bvpnav import simulate
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import Bias, ScaleFactor, UnknownGravity

BACKENDS = {"direct": ("direct", {}), "direct lu": ("direct", {"method": "lu"}),
            "csne": ("csne", {}), "clarabel": ("clarabel", {})}


def problem(rate: float, duration: float, seed: int = 0):
    """The benchmark problem and its simulation (truth)."""
    sim = simulate.strapdown_3d_2010(rate=rate, duration=duration, noise=0.05, seed=seed)
    T = float(sim.t[-1])
    tv = [0.0, T / 2.0, T]
    tfix = np.arange(10.0, T - 1.0, 10.0)
    rng = np.random.default_rng(seed + 1)
    fixes = sim.position(tfix) + rng.normal(0.0, 1.0, (tfix.size, 3))
    prob = bvpnav.NavigationProblem(sim.imu_data(), error_model=ScaleFactor() + Bias() + UnknownGravity(),
                                    sigma_a=0.05)
    prob.add(Position(t=[0.0, T], value=sim.position([0.0, T]), name="ends"),
             Velocity(t=tv, value=sim.velocity(tv), name="velocities"),
             Position(t=tfix, value=fixes, sigma=1.0, name="gnss"))
    return prob, sim


def truth_params(sim) -> dict:
    e = sim.accel
    s = np.broadcast_to(np.asarray(e.scale, float), (3,))
    b = np.broadcast_to(np.asarray(e.bias, float), (3,))
    return {**{f"scale_{a}": s[k] for k, a in enumerate("xyz")},
            **{f"bias_{a}": b[k] for k, a in enumerate("xyz")},
            **{f"gravity_{a}": sim.gravity[k] for k, a in enumerate("xyz")}}


def score(sol, sim) -> tuple[float, float]:
    truth = truth_params(sim)
    est = sol.error_params
    par = max(abs(est[k] - v) / abs(v) for k, v in truth.items())
    pos = sim.truth[["x", "y", "z"]].to_numpy()
    return float(par), float(np.sqrt(np.mean((sol.position() - pos) ** 2)))


def solve(prob, name: str, accuracy: str = "default", verify: bool = True):
    solver, opts = BACKENDS[name]
    t0 = time.perf_counter()
    sol = prob.solve(solver=solver, accuracy=accuracy, options=opts or None, fallback=None, verify=verify)
    return sol, time.perf_counter() - t0


def bench(rate: float, duration: float, backends: list[str]) -> list[dict]:
    prob, sim = problem(rate, duration)
    prob.terms()
    ref, _ = solve(prob, "direct lu", "high", verify=False)
    scale = float(np.max(np.abs(ref.position())))
    rows = []
    for name in backends:
        try:
            sol, dt = solve(prob, name)
            par, rms = score(sol, sim)
            err = float(np.max(np.abs(sol.position() - ref.position())) / scale)
            note = "verified" + (f", {sol.stats['factorization']}" if "factorization" in sol.stats else "")
            rows.append({"backend": name, "time": dt, "error": err, "param": par, "rms": rms, "note": note})
        except bvpnav.BvpnavError as exc:
            rows.append({"backend": name, "time": np.nan, "error": np.nan, "param": np.nan, "rms": np.nan,
                         "note": f"{type(exc).__name__}: {str(exc)[:80]}"})
    fastest = min((r["time"] for r in rows if r["backend"].startswith(("direct", "csne"))
                   and np.isfinite(r["time"])), default=np.nan)
    for r in rows:
        r.update(rate=rate, n=sim.t.size, unknowns=prob.model.size, ratio=r["time"] / fastest)
    return rows


def case(rate: float, duration: float, name: str) -> dict:
    t0 = time.perf_counter()
    prob, sim = problem(rate, duration)
    build = time.perf_counter() - t0
    sol, dt = solve(prob, name, verify=False)
    return {"backend": name, "build": build, "time": dt, "verified": bool(sol.stats["verified"]),
            "status": sol.stats["status"], "rms": score(sol, sim)[1], "peak_mb": own_peak_mb()}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rates", default="100,200,500,1000", help="sampling rates, Hz (comma separated)")
    ap.add_argument("--duration", type=float, default=120.0, help="recording length, s (whole number)")
    ap.add_argument("--backends", default=",".join(BACKENDS))
    ap.add_argument("--memory", action="store_true",
                    help="re-run the largest case once per back end in its own process (peak memory)")
    ap.add_argument("--case", nargs=3, metavar=("RATE", "DURATION", "BACKEND"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.case:
        print(json.dumps(case(float(args.case[0]), float(args.case[1]), args.case[2])))
        return
    rates = [float(r) for r in args.rates.split(",")]
    backends = args.backends.split(",")
    print(f"3-D, nine-parameter model, {args.duration:g} s per recording")
    print(f"{'rate (Hz)':>9}{'N':>9}{'unknowns':>10}  {'backend':<10}{'time (s)':>9}{'x fastest':>10}"
          f"{'rel. diff':>11}{'param err':>11}{'RMS pos (m)':>12}  note")
    for rate in rates:
        for r in bench(rate, args.duration, backends):
            print(f"{r['rate']:>9g}{r['n']:>9}{r['unknowns']:>10}  {r['backend']:<10}{r['time']:>9.3f}"
                  f"{r['ratio']:>10.2f}{r['error']:>11.1e}{r['param']:>11.1e}{r['rms']:>12.4f}  {r['note']}",
                  flush=True)
    if args.memory:
        print(f"\npeak resident memory at {rates[-1]:g} Hz x {args.duration:g} s (each row its own process)")
        print(f"{'backend':<10}{'time (s)':>9}{'x fastest':>10}{'peak (MB)':>11}  note")
        largest = [str(rates[-1]), str(args.duration)]
        rows = [run_case(__file__, [*largest, b]) | {"backend": b} for b in backends]
        fastest = min(r.get("time", np.inf) for r in rows if r["backend"].startswith(("direct", "csne")))
        for r in rows:
            t = r.get("time", np.nan)
            note = r.get("error") or f"{r['status']}, verified={r['verified']}, RMS {r['rms']:.4f} m"
            print(f"{r['backend']:<10}{t:>9.2f}{t / fastest:>10.2f}{r['peak_mb']:>11.0f}  {note}", flush=True)


if __name__ == "__main__":
    main()
