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

Measured (2026-12-05, 2-core machine shared with other jobs, load average 15-22: wall times
inflated 5-10x, read the CPU ratios; the README path as two runs side by side, gaps 10 and 30
in one, 60 in the other, and the node-state path in a third; every answer verified)::

    gap s  case                 RMS m    CPU s  x ref  solves  band solves: updates of each
    10     README               1.760     49.0   1.00      40
    10     NHC+FM band          1.710     91.7   1.87      30  active set (18): 11, 13, 11, 3, 2, 1, 0...
    30     README              15.534     48.5   1.00      45
    30     NHC+FM band          3.078    107.7   2.22      32  active set (20): 13, 12, 11, 11, 9, 3...
    60     README              55.400     38.7   1.00      32
    60     NHC+FM band          5.714    163.3   4.22      50  active set (38): 13, 18, 9, 10, 6, 1...
    10     states               1.472      9.7   1.00      11
    10     states NHC+FM band   1.817     18.9   1.94       7  active set (2): 12, 0; 5 quick steps
    30     states              15.529      9.3   1.00      11
    30     states NHC+FM band   3.744     23.6   2.54      10  active set (2): 13, 0; 8 quick steps
    60     states              55.389      8.1   1.00       9
    60     states NHC+FM band   5.906     25.4   3.13       9  active set (2): 20, 0; 7 quick steps

Before (without the quick steps, the kept plan and the banded conditioning): README path
2.40x at 10 s (this session, load about 7), 3.01x at 30 s and 5.47x at 60 s (the day before,
load 18-22); node states 3.2x at 30 s (28.7 s against 9.0 s on a quiet machine, every step
solved in full, 18 pattern analyses). Where the rest goes: the first solve of each kind
starts with no rows at their bounds (12-20 updates: about half of the node-state path's extra
CPU), and at 60 s the README path's attitude loop makes 50 solves with the bands against 32
without (the rows at their bounds unchanged after the seventh band solve); a band solve with
0 updates costs about 2 s (steps: the attitude parameters in the border) and 0.8 s
(evaluations). Starting a kind's first solve from the other kind's rows was tried: 13 -> 10
updates, 87.3 s against 91.7 s at 10 s (within the load's noise), not kept.
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
