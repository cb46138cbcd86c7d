"""Benchmark: stance detection on real foot trials, precision and recall against the Vicon truth.

For every trial of the foot development set (issue 38; the folder's README), the SHOE
detector (:func:`bvpnav.detect.stationary`) with

- its fixed default threshold (3e4, window 3 samples),
- the fixed setting of the issue's table (1e5, window 5),
- ``threshold="adaptive"`` (:func:`bvpnav.detect.adaptive_threshold`: from the
  recording's own statistic, the same setting for walking and running),

is scored per sample against the truth "still": the Vicon foot speed (5-sample median)
below 0.1 m/s. Precision is the share of detected samples truly still, recall the share
of truly still samples detected; ``strides hit`` is the share of the true still runs
longer than 0.05 s that hold at least one detected sample (a stride without any stance
leaves a gap the solver must bridge). The Vicon track is resampled and has jumps, so
the truth itself is approximate; compare the methods, not the last digit.

Measured (precision / recall / strides hit)::

    trial               kind      fixed default (3e4, W 3)  issue's (1e5, W 5)   adaptive
    2017-11-22-11-26-05 walking   0.96 / 0.77 / 0.91   0.94 / 0.92 / 0.93   0.96 / 0.78 / 0.91
    2017-11-22-11-26-46 walking   0.98 / 0.67 / 0.91   0.97 / 0.89 / 1.00   0.98 / 0.78 / 0.94
    2017-11-22-11-28-39 walking   1.00 / 0.84 / 1.00   0.98 / 0.95 / 1.00   1.00 / 0.84 / 1.00
    2017-11-22-11-35-59 walking   0.96 / 0.68 / 0.75   0.94 / 0.92 / 0.97   0.92 / 0.93 / 0.97
    2017-11-22-11-50-42 walking   0.93 / 0.80 / 1.00   0.91 / 0.94 / 1.00   0.93 / 0.81 / 1.00
    2017-11-22-11-51-23 walking   0.96 / 0.70 / 0.97   0.96 / 0.92 / 1.00   0.96 / 0.73 / 0.97
    2017-11-22-11-52-02 walking   0.93 / 0.69 / 0.92   0.93 / 0.92 / 1.00   0.93 / 0.80 / 1.00
    2017-11-27-11-13-10 running   0.99 / 0.65 / 0.45   0.96 / 0.86 / 0.95   0.93 / 0.93 / 1.00
    2017-11-27-11-13-41 running   1.00 / 0.83 / 0.33   0.99 / 0.85 / 0.44   0.89 / 0.96 / 1.00
    2017-11-27-11-14-52 running   0.97 / 0.89 / 0.92   0.95 / 0.97 / 1.00   0.87 / 0.98 / 1.00
    2017-12-15-18-01-51 running   0.96 / 0.75 / 0.65   0.87 / 0.89 / 0.83   0.83 / 0.89 / 0.83
    2018-02-09-11-32-01 walking   0.88 / 0.39 / 0.52   0.84 / 0.77 / 0.93   0.84 / 0.84 / 0.98
    walking median                0.96 / 0.70 / 0.92   0.94 / 0.92 / 1.00   0.94 / 0.81 / 0.98
    running median                0.98 / 0.79 / 0.55   0.96 / 0.87 / 0.89   0.88 / 0.95 / 1.00

What decides the trajectory is *strides hit*: a stride with no detected stance leaves a
swing-plus-swing gap (the fixed default misses 45-67 % of the running strides and a
quarter of the strides of 11-35-59, whose RMS is then 0.38 m).

Run ``python examples/benchmarks/stationary_detection.py FOLDER``.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _foot_trials import load, trials  # noqa: E402

from bvpnav import detect  # noqa: E402

SETTINGS = {"fixed default (3e4, W 3)": {}, "issue's (1e5, W 5)": {"threshold": 1e5, "window": 5},
            "adaptive": {"threshold": "adaptive"}}


def scores(mask: np.ndarray, truth: np.ndarray, t: np.ndarray) -> tuple[float, float, float]:
    """Precision, recall, and the share of true still runs (> 0.05 s) with a detected sample."""
    tp = np.count_nonzero(mask & truth)
    edges = np.diff(np.concatenate([[0], truth.view(np.int8), [0]]))
    runs = [(a, b) for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True)
            if t[b - 1] - t[a] > 0.05]
    hit = np.mean([mask[a:b].any() for a, b in runs]) if runs else np.nan
    return tp / max(np.count_nonzero(mask), 1), tp / max(np.count_nonzero(truth), 1), float(hit)


def _fmt(x) -> str:
    return " / ".join(f"{v:.2f}" for v in x)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", help="the folder of the *_LLIO.mat foot trials")
    args = ap.parse_args(argv)
    res: dict = {}
    print(f"{'trial':<19} {'kind':<8} " + " ".join(f"{s:>28}" for s in SETTINGS))
    print(f"{'':<28} " + " ".join(f"{'prec / rec / strides hit':>28}" for _ in SETTINGS))
    for path in trials(args.folder):
        tr = load(path)
        truth = tr.still
        row = {}
        for label, kw in SETTINGS.items():
            det = detect.stationary(tr.data, return_statistic=True, **kw)
            row[label] = scores(det.mask, truth, tr.t)
        res[tr.name] = (tr.kind, row)
        print(f"{tr.name:<19} {tr.kind:<8} " + " ".join(
            f"{_fmt(row[s]):>28}" for s in SETTINGS), flush=True)
    for kind in ("walking", "running"):
        sel = [row for k, row in res.values() if k == kind]
        print(f"{kind + ' median':<28} " + " ".join(
            f"{_fmt(np.median([r[s] for r in sel], axis=0)):>28}" for s in SETTINGS))
    return res


if __name__ == "__main__":
    main()
