"""Benchmark: the 2011 paper's Table 2 scaling, every back end side by side.

The Table 1 problem (quintic, s = 0.05, mu = -0.5, unit noise) sampled ever faster:
N from 500 to 128,000 (``--max-n 1000000`` extends it), M = N/25 prior rows (the cubic
on the first and last N/50 samples), both end positions hard, lambda = 1 fixed. For
each N and objective form (``load``: the paper's ``||K r - f||^2``; ``acceleration``:
bvpnav's weighted residual form):

- ``bare LU``: scipy's SuperLU on the same augmented KKT system, one solve (the floor the
  issue names); ``bare LDL``: QDLDL on the same system regularized to be quasi-definite,
  one unrefined solve (acceleration form only; the load form needs pivoting);
- ``direct``, ``csne``: bvpnav's back ends (verified solves; ``direct`` uses the LDL^T
  with refinement on the acceleration form and the pivoted LU on the load form);
- ``clarabel``: through cvxpy (compile + solve, then a re-solve for a new lambda); for
  the load form only up to 20,000 samples (beyond, it is inaccurate and fails verification);
- ``osqp``: through cvxpy up to 4,000 samples (at 4,000 it already stops at its iteration
  limit, 15 s, far from the answer).

Accuracy is the relative max-norm difference of the trajectory from a reference (the
pivoted-LU direct solve with 6 refinement steps). Times in s (wall clock, this machine), with the
ratio to the fastest direct solve of the same row. The paper's CSNE times (ms, Matlab
7.9, 2 GHz 32-bit machine) are printed for orientation. With ``--memory`` the
largest N is re-run once per back end, each in its own process, and the table of peak
resident memory (``ru_maxrss`` of that process: the data, the problem and the solve)
and time is printed; that is also how Clarabel is run at N = 1,000,000. Timings belong
here, never in tests.

Run ``python examples/benchmarks/table2_scaling.py [--max-n 1000000] [--memory]``.
"""

from __future__ import annotations

import argparse
import json
import resource
import time
import warnings

import numpy as np
import scipy.sparse.linalg as spla
from _memory import own_peak_mb, run_case

import bvpnav
from bvpnav.constraints import Position
from bvpnav.linalg.lsq import _LDL, least_squares_form
from bvpnav.scenarios import cubic_prior, quintic_trajectory

PAPER_CSNE_MS = {500: 1, 1000: 2, 2000: 4, 4000: 8, 8000: 16, 16000: 34, 32000: 103, 64000: 212,
                 128000: 1106}


def problem(n: int, residual: str, seed: int = 1):
    _, _, a = quintic_trajectory()
    t = np.linspace(0.0, 10.0, n)
    rng = np.random.default_rng(seed)
    acc = 1.05 * a(t) + rng.normal(-0.5, 1.0, n)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), residual=residual)
    k = max(n // 50, 1)
    tp = np.concatenate([t[:k], t[-k:]])
    prior = cubic_prior(0.0, 10.0, 0.0, 10.0, 0.0, 0.0)
    prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0]), Position(t=tp, value=prior(tp), sigma=1.0))
    return prob


def timed(f):
    t0 = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t0


def bench(n: int, residual: str) -> list[dict]:
    prob = problem(n, residual)
    prob.terms()
    # the load form at N >= 512,000 is beyond double precision at the high preset: unverified
    ref = prob.solve(solver="direct", accuracy="high", fallback=None, verify=False,
                     options={"method": "lu"})
    scale = np.max(np.abs(ref.x))
    rows = []

    def acc(x):
        return float(np.max(np.abs(x - ref.x)) / scale)

    form = least_squares_form(prob, 1.0)
    S = form.augmented().tocsc()
    rhs = form.rhs()
    m, nx = form.D.A.shape
    z, dt = timed(lambda: spla.splu(S, permc_spec="COLAMD").solve(rhs))
    rows.append({"backend": "bare LU", "time": dt, "error": acc(z[m:m + nx]), "note": "one solve"})
    if residual == "acceleration":
        U = form.augmented_upper(1e-12)
        z, dt = timed(lambda: _LDL(U).solve(rhs))
        rows.append({"backend": "bare LDL", "time": dt, "error": acc(z[m:m + nx]),
                     "note": "one solve, unrefined"})
    for name in ("direct", "csne"):
        try:
            sol, dt = timed(lambda name=name: prob.solve(solver=name, fallback=None))
            fac = f", {sol.stats['factorization']}" if name == "direct" else ""
            rows.append({"backend": name, "time": dt, "error": acc(sol.x),
                         "note": f"it={sol.stats['iterations']}{fac}, verified"})
        except bvpnav.BvpnavError as exc:
            rows.append({"backend": name, "time": np.nan, "error": np.nan, "note": type(exc).__name__})
    if (residual == "acceleration" and n <= 128000) or n <= 20000:
        try:
            sol, dt = timed(lambda: prob.solve(solver="clarabel", fallback=None))
            _, dt2 = timed(lambda: prob.solve(solver="clarabel", lam=2.0, fallback=None))
            rows.append({"backend": "clarabel", "time": dt, "error": acc(sol.x),
                         "note": f"re-solve new lam {dt2:.3f} s"})
        except bvpnav.BvpnavError as exc:
            rows.append({"backend": "clarabel", "time": np.nan, "error": np.nan,
                         "note": f"{type(exc).__name__} (failed verification)"})
    if n <= 4000:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                sol, dt = timed(lambda: prob.solve(solver="osqp", fallback=None, verify=False))
                rows.append({"backend": "osqp", "time": dt, "error": acc(sol.x),
                             "note": f"{sol.stats['status']}, verified={sol.stats['verified']}"})
            except bvpnav.BvpnavError as exc:
                rows.append({"backend": "osqp", "time": np.nan, "error": np.nan, "note": type(exc).__name__})
    fastest = min(r["time"] for r in rows if r["backend"] in ("direct", "csne") and np.isfinite(r["time"]))
    for r in rows:
        r.update(n=n, m=n // 25, form=residual, ratio=r["time"] / fastest)
    return rows


def case(n: int, residual: str, backend: str) -> dict:
    """One solve, verification reported rather than enforced (for the memory table, run in
    a child process)."""
    prob, t_build = timed(lambda: problem(n, residual))
    sol, dt = timed(lambda: prob.solve(solver=backend, fallback=None, verify=False))
    return {"n": n, "form": residual, "backend": backend, "build": t_build, "time": dt,
            "status": sol.stats["status"], "verified": bool(sol.stats["verified"]),
            "forward_error": sol.stats["verification"]["forward_error"], "peak_mb": own_peak_mb()}


def memory_table(n: int, forms: list[str]) -> None:
    print(f"\npeak resident memory at N = {n} (each row its own process)")
    print(f"{'form':<13}{'backend':<10}{'time (s)':>10}{'x fastest':>10}{'peak (MB)':>11}  note")
    for form in forms:
        backends = ["direct", "csne"] + (["clarabel"] if form == "acceleration" else [])
        rows = [run_case(__file__, [str(n), form, b]) | {"backend": b} for b in backends]
        fastest = min(r.get("time", np.inf) for r in rows if r["backend"] in ("direct", "csne"))
        for r in rows:
            note = r.get("error") or (f"{r['status']}, verified={r['verified']}, "
                                      f"forward error {r['forward_error']:.1e}")
            t = r.get("time", np.nan)
            print(f"{form:<13}{r['backend']:<10}{t:>10.2f}{t / fastest:>10.2f}{r['peak_mb']:>11.0f}  {note}",
                  flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-n", type=int, default=128000)
    ap.add_argument("--forms", default="load,acceleration")
    ap.add_argument("--memory", action="store_true",
                    help="also run the largest N once per back end in its own process (peak memory)")
    ap.add_argument("--memory-only", action="store_true", help="only the peak-memory table")
    ap.add_argument("--case", nargs=3, metavar=("N", "FORM", "BACKEND"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.case:
        print(json.dumps(case(int(args.case[0]), args.case[1], args.case[2])))
        return
    ns = [n for n in (500, 1000, 2000, 4000, 8000, 16000, 32000, 64000, 128000, 256000, 512000, 1000000)
          if n <= args.max_n]
    forms = args.forms.split(",")
    if args.memory_only:
        memory_table(ns[-1], forms)
        return
    print(f"{'form':<13}{'N':>8}{'M':>7}  {'backend':<9}{'time (s)':>10}{'x fastest':>10}{'rel. error':>12}"
          f"  {'paper CSNE (ms)':>15}  note")
    for form in forms:
        for n in ns:
            for r in bench(n, form):
                paper = PAPER_CSNE_MS.get(n, "") if r["backend"] == "csne" else ""
                print(f"{r['form']:<13}{r['n']:>8}{r['m']:>7}  {r['backend']:<9}{r['time']:>10.4f}"
                      f"{r['ratio']:>10.2f}{r['error']:>12.1e}  {paper!s:>15}  {r['note']}", flush=True)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory of this process: {peak:.0f} MB")
    if args.memory:
        memory_table(ns[-1], forms)


if __name__ == "__main__":
    main()
