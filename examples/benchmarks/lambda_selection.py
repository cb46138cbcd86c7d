"""Benchmark: choosing lambda at N = 100,000 with 40 items.

The Table 1 problem at 10 kHz (N = 100,001 samples), both end positions hard, and 40 soft
items: the cubic prior split into 15 blocks at each end of the window and 10 rough
velocity fixes along the way. Reports
a single direct solve, then for each rule the number of lambda evaluations, the time per
evaluation and the total. GCV uses 24 Hutchinson probes (one multi-right-hand-side solve
per lambda). Timings belong here, never in tests.

Run ``python examples/benchmarks/lambda_selection.py [--n 100001]``.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.scenarios import cubic_prior, quintic_trajectory
from bvpnav.solve import lambda_curve


def problem(n: int, seed: int = 1):
    p, v, a = quintic_trajectory()
    t = np.linspace(0.0, 10.0, n)
    rng = np.random.default_rng(seed)
    acc = 1.05 * a(t) + rng.normal(-0.5, 1.0, n)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=1.0)
    prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends"))
    prior = cubic_prior(0.0, 10.0, 0.0, 10.0, 0.0, 0.0)
    k = max(n // 50, 20)
    for j, blk in enumerate(np.array_split(np.arange(k), 15)):
        for side, idx in (("start", blk), ("end", n - 1 - blk)):
            tp = t[idx]
            prob.add(Position(t=tp, value=prior(tp), sigma=1.0, name=f"prior {side} {j}"))
    # 10 rough velocity fixes along the way (e.g. from a wheel), 1 m/s accuracy
    tv = np.linspace(1.0, 9.0, 10)
    for j, tj in enumerate(tv):
        prob.add(Velocity(t=[tj], value=[v(tj) + rng.normal(0, 0.3)], sigma=1.0, name=f"speed {j}"))
    return prob


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100001)
    args = ap.parse_args(argv)
    prob = problem(args.n)
    t0 = time.perf_counter()
    prob.terms()
    print(f"N = {args.n}, items = {len(prob.items)}, compile of the items {time.perf_counter() - t0:.2f} s")
    t0 = time.perf_counter()
    sol = prob.solve(solver="direct", lam=1.0)
    single = time.perf_counter() - t0
    print(f"single verified direct solve: {single:.2f} s")
    print(f"{'rule':<12} {'lambda':>10} {'evaluations':>12} {'s / evaluation':>15} {'total (s)':>10} "
          f"{'x single':>9}")
    for rule in ("lcurve", "gcv", "discrepancy", "quasi"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = time.perf_counter()
            c = lambda_curve(prob, rules=(rule,), rule=rule, progress=False)
            dt = time.perf_counter() - t0
        print(f"{rule:<12} {c.lam_chosen:>10.4g} {c.evaluations:>12d} {dt / c.evaluations:>15.3f} "
              f"{dt:>10.2f} {dt / single:>9.1f}", flush=True)
    del sol


if __name__ == "__main__":
    main()
