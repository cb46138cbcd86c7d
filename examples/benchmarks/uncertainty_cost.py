"""Benchmark: what ``solve(uncertainty=True)`` costs, as a multiple of ``solve()``.

One axis at N = 1e4, 1e5, 1e6 samples (100 Hz; a hard start, a soft end and nine soft
position fixes) and three axes at N = 1e5 with ``Bias() + ScaleFactor()`` (six error-model
parameters in the border), all with the ``direct`` back end, lambda = 1. For each case
the two solves are interleaved in the same process (``repeat`` times; the median is
printed), so the ratio does not depend on the machine's speed or its BLAS. With
``--memory`` each case is re-run once per variant in a fresh child process and its peak
resident memory (VmHWM) is printed with the ratio.

Columns: samples, axes, parameters; the median wall time of ``solve()`` and of
``solve(uncertainty=True)`` in s and their ratio (the issue's bound: at most 3); the
uncertainty stage alone (``stats["uncertainty"]["time"]``); the border size and node
block size of the block-tridiagonal factorization; peak memory of each variant (MB) and
their ratio (the bound: at most 1.5). Timings belong here, never in tests.

Run ``python examples/benchmarks/uncertainty_cost.py [--sizes 1e4,1e5,1e6] [--repeat 3]
[--memory]``; the full run takes about 10 minutes on a 2-core machine.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings

import numpy as np
from _memory import own_peak_mb, run_case

import bvpnav
from bvpnav.constraints import Position
from bvpnav.error_models import Bias, ScaleFactor


def problem(n: int, axes: int) -> bvpnav.NavigationProblem:
    """The benchmark problem: ``n`` samples at 100 Hz, ``axes`` axes."""
    t = np.arange(n) * 0.01
    rng = np.random.default_rng(0)
    acc = np.sin(t)[:, None] * np.arange(1, axes + 1) + 0.01 * rng.normal(size=(n, axes))
    data = bvpnav.ImuData(t, acc[:, 0] if axes == 1 else acc)
    em = Bias() + ScaleFactor() if axes > 1 else None
    p = bvpnav.NavigationProblem(data, sigma_a=0.01, error_model=em)
    zero = 0.0 if axes == 1 else [0.0] * axes
    T = float(t[-1])
    p.add(Position(t=0.0, value=zero), Position(t=T, value=zero, sigma=0.1))
    p.add(*[Position(t=float(tk), value=zero, sigma=0.1) for tk in np.linspace(0.0, T, 11)[1:-1]])
    return p


def _one(n: int, axes: int, uncertainty: bool) -> tuple[float, dict]:
    p = problem(n, axes)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = p.solve(solver="direct", uncertainty=uncertainty)
    return time.perf_counter() - t0, sol.stats.get("uncertainty", {})


def case(n: int, axes: int, repeat: int) -> dict:
    """Interleaved timings of both variants."""
    plain, unc, stage = [], [], []
    rec: dict = {}
    for _ in range(repeat):
        plain.append(_one(n, axes, False)[0])
        t, rec = _one(n, axes, True)
        unc.append(t)
        stage.append(rec["time"])
    return {"n": n, "axes": axes, "q": 6 if axes > 1 else 0, "solve": float(np.median(plain)),
            "uncertainty": float(np.median(unc)), "stage": float(np.median(stage)),
            "border": rec["border"], "block": rec["block"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1e4,1e5,1e6", help="1-axis sizes, comma separated")
    ap.add_argument("--three-axis", default="1e5", help="3-axis sizes (Bias + ScaleFactor)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--memory", action="store_true", help="peak memory per variant, fresh processes")
    ap.add_argument("--case", nargs=3, metavar=("N", "AXES", "UNCERTAINTY"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.case:  # child process of --memory: one solve, then its own peak
        n, axes, unc = int(float(args.case[0])), int(args.case[1]), args.case[2] == "1"
        wall, _ = _one(n, axes, unc)
        print(json.dumps({"wall": wall, "peak_mb": own_peak_mb()}))
        return
    cases = [(int(float(s)), 1) for s in args.sizes.split(",") if s]
    cases += [(int(float(s)), 3) for s in args.three_axis.split(",") if s]
    head = (f"{'N':>9} {'axes':>4} {'q':>2} {'solve s':>8} {'+unc s':>8} {'ratio':>6} {'stage s':>8} "
            f"{'border':>6} {'block':>5}")
    if args.memory:
        head += f" {'peak MB':>8} {'+unc MB':>8} {'ratio':>6}"
    print(head)
    _one(2000, 3, True)  # warm up: imports and first-call costs belong to neither variant
    for n, axes in cases:
        r = case(n, axes, args.repeat if n < 1_000_000 else max(1, args.repeat - 1))
        line = (f"{n:>9} {axes:>4} {r['q']:>2} {r['solve']:>8.2f} {r['uncertainty']:>8.2f} "
                f"{r['uncertainty'] / r['solve']:>6.2f} {r['stage']:>8.2f} {r['border']:>6} {r['block']:>5}")
        if args.memory:
            a = run_case(__file__, [str(n), str(axes), "0"])
            b = run_case(__file__, [str(n), str(axes), "1"])
            line += f" {a['peak_mb']:>8.0f} {b['peak_mb']:>8.0f} {b['peak_mb'] / a['peak_mb']:>6.2f}"
        print(line, flush=True)


if __name__ == "__main__":
    main()
