"""Benchmark (issue 39 item 8): what band and inequality rows cost ``direct`` on the KITTI drive.

The development split of ``kitti_drive.py`` (first 240 s; the rest is never read) with fixes
every G s, on both documented paths, each case in its own child process:

``README``
    the README path (``from_datasheet``, ``g.error_model(30)``, ``solver="direct"``, the
    attitude loop) without vehicle rows: the reference of the next two.
``NHC+FM band``
    plus ``NonHolonomic`` (lateral and vertical, a band of 0.1 m/s, 10 Hz) and ``ForwardMotion``
    (forward speed >= 0, an inequality), ``direct``'s default ``qp="auto"``: the active set
    (:mod:`bvpnav.linalg.active_set`), warm-started across the loop, the interior point
    where it gives way.
``NHC+FM band (ipm)``
    the same with ``options={"qp": "interior point"}``.
``states``
    the node-state path (``kitti_drive``'s ``bvpnav states``: ``ErrorStates``, the node-state
    loop) without vehicle rows: the reference of the next.
``states NHC+FM band``
    plus the same ``NonHolonomic`` band and ``ForwardMotion``; the loop's intermediate steps
    are quick active-set passes (:func:`bvpnav.linalg.active_set.quick_step`).

Printed per gap: the horizontal RMS at the withheld fixes, wall and CPU seconds, the CPU ratio
to the case's reference of the same gap and run (the issue's acceptance: at most 3x), the
loop's solves, and how the solves through the back end answered their band rows
(``qp_method`` counts; the JSON lines list each such solve: method, updates, rows at their
bounds, CPU s). On a shared machine read the CPU ratios.

Run: ``python examples/benchmarks/kitti_bands.py [--gaps 10 30 60] [--methods ...]``.

Measured (2026-12-05, 03:31-03:56 UTC, 2-core machine shared with other jobs, load average
15-20: wall times inflated 5-10x, read the CPU ratios; three runs side by side: the README
path at gaps 10 and 30, at 60, and the node-state path at all three; every answer verified;
on branch ``bands2`` based on main ``b88ecc4``, before its rebase)::

    gap s  case                 RMS m    CPU s  x ref  solves  band solves: updates of each
    10     README               1.760     47.1   1.00      40
    10     NHC+FM band          1.710     83.7   1.78      30  active set (18): 8, 10, 7, 2, 2, 0, 1, 0...
    30     README              15.534     48.3   1.00      45
    30     NHC+FM band          3.078    105.1   2.17      32  active set (20): 9, 10, 9, 10, 8, 3, 1...
    60     README              55.400     37.2   1.00      32
    60     NHC+FM band          5.714    145.2   3.90      46  active set (34): 13, 17, 8, 8, 5, 1, 2, 0...
    10     states               1.472      6.9   1.00       8
    10     states NHC+FM band   1.817     13.8   1.99       8  active set (3): 9, 0, 0; 5 quick steps
    30     states              15.529      8.1   1.00       9
    30     states NHC+FM band   3.744     16.7   2.06       9  active set (2): 11, 0; 7 quick steps
    60     states              55.389      6.0   1.00       7
    60     states NHC+FM band   5.906     17.1   2.83       8  active set (2): 16, 0; 6 quick steps

The node-state path again after the rebase onto main ``508d049`` (04:00 UTC, load 9-11, one
run per gap pair): 13.2 / 15.8 / 15.8 s against 6.6 / 7.1 / 7.2 s, 2.00 / 2.22 / 2.18x, the
same RMS and solves.

What changed since the run before (node states 1.94 / 2.54 / 3.13x, README path 1.87 / 2.22 /
4.22x): the violated rows an update adds are those that peak among their neighbours in time
(``QuadraticForm.before``/``after``: the same item's row of the same axis and side at the
instants before and after; they were the next rows of ``G``, which for ``NonHolonomic``'s
interleaved y/z rows compared one axis with the other: 3573 of the first solve's 4650
violated rows at 60 s counted as peaks, 688 now), 20 -> 16 updates in the node-state path's
first solve at 60 s and its loop 10 -> 8 outer steps; the node-state loop's assembled band
and each pass's copy reuse the loop's ``band_buffer`` (a fresh 294 MB band cost about 0.2 s
of page faults twice per outer step); an update checks the unrefined solve and refines only
once the guess holds (the first solve at 60 s 8.2 -> 6.5 s). Tried and not kept: adding
every violated row (23 updates at 60 s against 20 with the peaks by ``G`` order), dropping
only the rows whose multiplier pulls most among their neighbours (17 against 16), the node-state
loop's first step as a quick step too (12 outer steps instead of 10, 22.2 against 21.3 s);
low-rank (Woodbury) updates of the band factor do not pay here: a banded solve costs a
quarter of a factorization (``dgbtrs`` reads the factor once per right-hand side), and the
updates that change few rows are the last few.

Where the rest goes. Node states at 60 s (17.1 s): the first solve 6.6 s (16 updates of
about 0.4 s: factorization 0.19 s, two banded solves, the checks), the quick steps about 7 s
(a one-pass step 0.75 s against about 0.5 s for a plain step), the last solve 0.7 s. The
README path at 60 s: 46 solves against 32 (12 heading candidates in both; with the bands one
more evaluation at the start, 17 iterations against 10), a band solve of 0 updates about 2.2 s
(steps) and 0.8-0.9 s (evaluations) against about 1.1 s per solve without the rows. Its loop
takes more steps because of the damping: from the fifth iteration the undamped and lightly
damped steps (1e-5 rad) raise the objective and steps at damping 100 lower it by 2e-9
relative, the damping alternating 10 / 100 for a dozen iterations; the rows at their bounds no
longer change then (0 updates from the 8th band solve on). The linearized step holds the
body-frame rows (bilinear in the velocity and the attitude) at their bounds to first order, the
evaluation at the new attitude holds them exactly: the Maratos effect of SQP with nonlinear
constraints, which a second-order correction of the step or a non-monotone acceptance would
address (attitude.py ``_iterate``, not changed here).
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import kitti_drive as K  # noqa: E402
from _memory import own_peak_mb, run_case  # noqa: E402

METHODS = {"README": ("bvpnav README", None), "NHC+FM band": ("bvpnav NHC+FM band", "auto"),
           "NHC+FM band (ipm)": ("bvpnav NHC+FM band", "interior point"),
           "states": ("bvpnav states", None), "states NHC+FM band": ("bvpnav states", "auto")}

#: The reference of each case: the same problem without the vehicle rows.
REFERENCE = {"README": "README", "NHC+FM band": "README", "NHC+FM band (ipm)": "README",
             "states": "states", "states NHC+FM band": "states"}


def vehicle_rows(prob) -> None:
    """``NonHolonomic`` (lateral and vertical, a band of 0.1 m/s, 10 Hz) and ``ForwardMotion``
    (forward speed >= 0), as ``kitti_drive``'s ``NHC+FM band`` adds them."""
    from bvpnav.constraints import ForwardMotion, NonHolonomic

    prob.add(NonHolonomic(axes=("y", "z"), lever=(0.0, 0.0, 0.0), rate=K.NHC_RATE, mode="band",
                          tol=K.NHC_WIDTH, name="non-holonomic"))
    prob.add(ForwardMotion(min_speed=0.0, rate=K.NHC_RATE, name="forward"))


def case(name: str, gap: float) -> dict:
    import bvpnav.linalg.active_set as AS
    import bvpnav.solve.pipeline  # noqa: F401  (imports before the clock starts)

    d = K.load_dev()
    kept, withheld = K.split_fixes(d["fix_t"], gap)
    fig = K.figures(d["meta"], 1.0 / float(np.mean(np.diff(d["t"]))))
    c0 = K.initial_attitude(d, kept)
    method, qp = METHODS[name]
    prob = K.problem(d, kept, method, fig, c0, 30.0)
    if method == "bvpnav states" and qp is not None:
        vehicle_rows(prob)
    methods: collections.Counter = collections.Counter()
    inner = AS.solve_bands
    record: list = []

    def counted(*a, **kw):
        c1 = time.process_time()
        x, info = inner(*a, **kw)
        methods[info["qp_method"]] += 1
        record.append([info["qp_method"], info.get("active_set", ""), info.get("iterations"),
                       info.get("active_rows"), round(time.process_time() - c1, 3)])
        return x, info

    AS.solve_bands = counted
    import bvpnav.backends.direct as D

    D.solve_bands = counted
    opts = {} if qp is None else {"options": {"qp": qp}}
    t0, c = time.perf_counter(), time.process_time()
    sol = prob.solve(solver="direct", attitude={"progress": False}, **opts)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c
    pos = sol.position()
    t_w = d["fix_t"][withheld]
    est = np.column_stack([np.interp(t_w, d["t"], pos[:, k]) for k in range(3)])
    att = sol.stats.get("sequential", {})
    return {"name": name, "gap": gap, "rms": K.hrms(est, d["fix_p"][withheld]), "seconds": wall,
            "cpu_seconds": cpu, "solves": att.get("solves"), "qp": dict(methods),
            "verified": sol.stats.get("verified"), "peak_mb": own_peak_mb(), "band_solves": record}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gaps", type=float, nargs="+", default=[10.0, 30.0, 60.0])
    ap.add_argument("--methods", nargs="+", default=list(METHODS), choices=list(METHODS))
    ap.add_argument("--case", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.case:
        print(json.dumps(case(args.case[0], float(args.case[1]))))
        return []
    rows = []
    for gap in args.gaps:
        for name in args.methods:
            r = run_case(__file__, [name, str(gap)])
            r.setdefault("name", name)
            r.setdefault("gap", gap)
            rows.append(r)
            print(json.dumps(r), flush=True)
    print(f"\n{'gap s':>6} {'case':<18} {'RMS m':>8} {'wall s':>8} {'CPU s':>8} {'x README':>9} "
          f"{'solves':>7}  qp")
    for gap in args.gaps:
        for r in (r for r in rows if r["gap"] == gap):
            ref = next((q for q in rows if q["gap"] == gap and q["name"] == REFERENCE[r["name"]]), {})
            ratio = r.get("cpu_seconds", np.nan) / ref.get("cpu_seconds", np.nan)
            print(f"{gap:6g} {r['name']:<18} {r.get('rms', np.nan):8.3f} {r.get('seconds', np.nan):8.1f} "
                  f"{r.get('cpu_seconds', np.nan):8.1f} {ratio:9.2f} {r.get('solves')!s:>7}  "
                  f"{r.get('qp') or r.get('error', '')}")
    return rows


if __name__ == "__main__":
    main()
