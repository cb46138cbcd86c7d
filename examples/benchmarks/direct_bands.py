"""Benchmark: band rows at every sample, solved by ``direct``'s interior-point path.

The 2011 paper's biased quintic (N samples over 10 s, both end positions hard, the cubic
prior on the first and last N/50 samples) with a velocity band of +-0.05 m/s around the true
velocity at every sample (a stand-in for a vehicle's non-holonomic band: the unmodelled
accelerometer bias drives the path against it at many samples). Side by side, in one run:

- ``plain``: the same problem without the band, ``direct`` (one banded factorization);
- ``soft``: the band's rows as soft rows (sigma = 0.05 m/s), ``direct``: the least-squares
  problem of the same size and bandwidth;
- ``band direct``: the band, ``direct``'s default: the active set (:mod:`bvpnav.linalg.active_set`,
  updates of the rows held at their bounds, each one banded factorization), the interior point
  where it gives way (the ``qp`` column says which answered, ``steps`` its updates or steps);
- ``band ipm``: the band, ``direct`` with ``qp="interior point"`` (Mehrotra steps, each one
  banded factorization);
- ``band clarabel``: the band, Clarabel through cvxpy (up to ``--clarabel-up-to`` samples);
- ``wide band``: a band of +-10 m/s that the least-squares answer already satisfies,
  ``direct``: the interior-point path's cost when no row presses (one factorization).

Every time is the wall and CPU time of ``problem.solve`` on a fresh problem (after one small
warm-up solve of each kind, so that imports and first calls are not counted): the items'
compilation, the solve and bvpnav's verification. The ratios are CPU-time ratios to
``plain`` and ``soft`` of the same N and run (on a shared machine the wall time measures the
neighbours too). Timings belong here, never in tests.

Run ``python examples/benchmarks/direct_bands.py [--n 10000 100000] [--clarabel-up-to 100000]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.scenarios import cubic_prior, quintic_trajectory

TOL = 0.05   # m/s


def problem(n: int, band: str | None, seed: int = 1) -> bvpnav.NavigationProblem:
    """The Table 1 problem at N = ``n`` with the velocity rows as ``band``, ``soft`` or absent."""
    p, v, a = quintic_trajectory()
    t = np.linspace(0.0, 10.0, n)
    rng = np.random.default_rng(seed)
    acc = 1.05 * a(t) + rng.normal(-0.5, 1.0, n)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=1.0)
    k = max(n // 50, 1)
    tp = np.concatenate([t[:k], t[-k:]])
    prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends"),
             Position(t=tp, value=cubic_prior(0.0, 10.0, 0.0, 10.0, 0.0, 0.0)(tp), sigma=1.0, name="prior"))
    if band in ("band", "wide"):
        tol = TOL if band == "band" else 10.0
        prob.add(Velocity(t=t, value=v(t), mode="band", tol=tol, name="velocity band"))
    elif band == "soft":
        prob.add(Velocity(t=t, value=v(t), sigma=TOL, name="velocity band"))
    return prob


def timed(n: int, band: str | None, solver: str,
          qp: str | None = None) -> tuple[float, float, bvpnav.Solution]:
    prob = problem(n, band)
    opts = {} if qp is None else {"options": {"qp": qp}}
    w0, c0 = time.perf_counter(), time.process_time()
    sol = prob.solve(solver=solver, lam=1.0, fallback=None, **opts)
    return time.perf_counter() - w0, time.process_time() - c0, sol


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[10000, 100000])
    ap.add_argument("--clarabel-up-to", type=int, default=100000)
    args = ap.parse_args(argv)
    for band, solver in ((None, "direct"), ("band", "direct"), ("band", "clarabel")):
        timed(200, band, solver)   # warm-up: imports and first calls
    timed(200, "band", "direct", "interior point")
    print(f"velocity band +-{TOL} m/s at every sample; times of problem.solve (compile, solve, verify)")
    head = (f"{'N':>8} {'case':<14} {'wall (s)':>9} {'CPU (s)':>8} {'x plain':>8} {'x soft':>7} "
            f"{'steps':>6} {'active':>7} {'verified':>9}  qp")
    print(head)
    print("-" * len(head))
    for n in args.n:
        rows = [("plain", None, "direct"), ("soft", "soft", "direct"), ("wide band", "wide", "direct"),
                ("band direct", "band", "direct"), ("band ipm", "band", "direct")]
        if n <= args.clarabel_up_to:
            rows.append(("band clarabel", "band", "clarabel"))
        base = {}
        ref = None
        for name, band, solver in rows:
            wall, cpu, sol = timed(n, band, solver, "interior point" if name == "band ipm" else None)
            base.setdefault(name, cpu)
            active = ""
            if band == "band":
                vel = sol.velocity()[:, 0]
                true = quintic_trajectory()[1](sol.trajectory.index.to_numpy(dtype=float))
                active = str(int(np.sum(np.abs(vel - true) > TOL * (1.0 - 1e-6))))
                ref = sol.x if ref is None else ref
            steps = sol.stats.get("iterations") if band in ("band", "wide") else ""
            ok = sol.stats["verified"]
            print(f"{n:>8} {name:<14} {wall:>9.2f} {cpu:>8.2f} {cpu / base['plain']:>8.1f} "
                  f"{cpu / base.get('soft', cpu):>7.1f} {steps!s:>6} {active:>7} {ok!s:>9}  "
                  f"{sol.stats.get('qp_method', '')}")
            if name == "band clarabel":
                print(f"{'':>8} {'':<14} band: largest |x_direct - x_clarabel| / |x| = "
                      f"{np.max(np.abs(ref - sol.x)) / np.max(np.abs(sol.x)):.1e}")


if __name__ == "__main__":
    main()
