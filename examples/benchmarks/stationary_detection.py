"""Benchmark: stationary-interval detection (``bvpnav.detect``) on the simulated walk.

The foot-mounted walk of ``bvpnav.scenarios.walking`` (10 strides of about 1 s at
100 Hz, the foot still for 40 % of each stride, 1.5 s standing at both ends, white
sensor noise plus a small bias) is run through the two detectors with their default
settings (SHOE: W = 3 samples, sigma_a = 0.01 m/s^2, sigma_w = 0.1 deg/s, gamma = 3e4;
magnitude: W = 3, 0.5 m/s^2 and 0.5 rad/s). Per noise level (accelerometer m/s^2 /
gyro rad/s per sample) and detector, the table gives the precision, recall and F1 of the
stance samples against the simulation's truth (mean and worst over the seeds), and how
many detected intervals there are against the true stance phases (detected / true,
summed over the seeds). The last level is well beyond MEMS grade, to show where each
detector gives way. Then the time of one ``detect.stationary`` call per 1e5 samples
(a 1000 s walk; the best of several runs). Timings belong here, never in tests.

Run ``python examples/benchmarks/stationary_detection.py [--seeds 0,1,2] [--repeat 5]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from bvpnav import detect, scenarios

#: (accelerometer noise m/s^2, gyro noise rad/s) per sample.
NOISE = [(0.01, 0.005), (0.05, 0.01), (0.2, 0.05), (0.5, 0.1)]
METHODS = ("shoe", "magnitude")


def scores(mask: np.ndarray, truth: np.ndarray) -> tuple[float, float, float]:
    """Precision, recall and F1 of the stance samples."""
    tp = np.count_nonzero(mask & truth)
    precision = tp / max(np.count_nonzero(mask), 1)
    recall = tp / max(np.count_nonzero(truth), 1)
    f1 = 2 * precision * recall / max(precision + recall, 1e-300)
    return precision, recall, f1


def accuracy_table(seeds: list[int]) -> list[dict]:
    rows = []
    for acc_noise, gyro_noise in NOISE:
        walks = [scenarios.walking(accel_noise=acc_noise, gyro_noise=gyro_noise, seed=s) for s in seeds]
        for method in METHODS:
            s = np.array([scores(detect.stationary_mask(w.data, method)[0], w.params["stance"])
                          for w in walks])
            found = sum(len(detect.stationary(w.data, method)) for w in walks)
            true = sum(len(w.params["stance_intervals"]) for w in walks)
            rows.append({"noise": f"{acc_noise:g} / {gyro_noise:g}", "method": method,
                         "precision": s[:, 0].mean(), "precision_min": s[:, 0].min(),
                         "recall": s[:, 1].mean(), "recall_min": s[:, 1].min(),
                         "f1": s[:, 2].mean(), "f1_min": s[:, 2].min(), "intervals": f"{found} / {true}"})
    return rows


def timing(repeat: int) -> dict:
    """Seconds per 1e5 samples of one ``detect.stationary`` call, per method (best of ``repeat``)."""
    walk = scenarios.walking(n_strides=998, accel_noise=0.03, gyro_noise=0.008, seed=0)
    n = walk.data.n
    out = {"samples": n}
    for method in METHODS:
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            detect.stationary(walk.data, method)
            best = min(best, time.perf_counter() - t0)
        out[method] = best * 1e5 / n
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2", help="comma-separated seeds of the walk (default 0,1,2)")
    ap.add_argument("--repeat", type=int, default=5, help="timing runs per method; the best counts")
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    print(f"Stance samples on scenarios.walking (10 strides, 100 Hz), seeds {seeds}: mean (worst)")
    head = (f"{'noise acc/gyro':>15} {'method':>10} {'precision':>16} {'recall':>16} {'F1':>16} "
            f"{'intervals':>10}")
    print(head)
    print("-" * len(head))
    for r in accuracy_table(seeds):
        print(f"{r['noise']:>15} {r['method']:>10} {r['precision']:>8.4f} ({r['precision_min']:.4f}) "
              f"{r['recall']:>8.4f} ({r['recall_min']:.4f}) {r['f1']:>8.4f} ({r['f1_min']:.4f}) "
              f"{r['intervals']:>10}")
    tm = timing(args.repeat)
    print(f"\nTime per 1e5 samples (a {tm['samples']}-sample walk, best of {args.repeat}):")
    for method in METHODS:
        print(f"  {method:>10}: {1e3 * tm[method]:7.1f} ms")


if __name__ == "__main__":
    main()
