"""Car-drive benchmark (issue 16): withheld-fix RMS per GNSS outage length, and the gyro bias.

A simulated 10-minute car drive at 100 Hz (:func:`bvpnav.scenarios.car_drive`: turns,
stops, hills; a strapdown IMU of the chosen grade with drifting gyro and accelerometer
biases; a 5 degree heading and 0.5 degree tilt error in the initial attitude) with
noisy 1 Hz GNSS fixes. For every outage length G the fixes every G s are kept and the
others withheld; each method sees the kept fixes only and is scored by the 3-D RMS
error (m) against the TRUE position at the withheld fix instants:

(a) ``spline``: a cubic spline through the kept fixes (scipy);
(b) ``Bias()``: bvpnav with a constant accelerometer bias, the attitude integrated from
    the gyro from the guess (what bvpnav could do before issue 16), with the grade's
    ``sigma_a`` and (``Bias() sigma_a=1``) with bvpnav's default ``sigma_a``;
(c) ``+GyroBias+AttitudeError+Walk``: bvpnav with ``Bias(sigma, interval, drift) +
    GyroBias(interval, drift, sigma) + AttitudeError(sigma=(tilt, tilt, None)) +
    AttitudeWalk(arw, interval=walk_interval(acc_noise, arw))``, the grade's numbers as
    priors, ``arw`` the gyro noise plus what the 30 s gyro-bias knots leave out of the bias
    walk and ``sigma_a`` likewise for the accelerometer bias
    (:func:`bvpnav.error_models.bridge_intensity`), solved by the damped outer loop (``--no-walk``: without
    ``AttitudeWalk``, the gyro's angle random walk unmodelled, column
    ``+GyroBias+AttitudeError``);
(d) ``GTSAM``: GTSAM's batch smoother (IMU preintegration, bias random walk, GPS
    factors, Levenberg-Marquardt) from ``_gtsam_peer.py`` beside this script
    (``pip install bvpnav[peers]``); skipped with a note when unavailable.

Then, per outage length, the gyro bias of (c) per knot against the truth averaged over
the knot's support (hat weights), with its standard deviation from
``solve(uncertainty=True)``, and whether it is within 3 standard deviations or 20 %.

With several ``--seeds`` (noise realizations of the same drive) the table averaged over
them follows, with the number of drives on which each method beat (c): a comparison at
the 1e-4 level between two smoothers of nearly the same model is decided by one
realization's noise, the mean over several is the benchmark's figure.

Run: ``python examples/benchmarks/car_drive.py [--grade tactical consumer] [--quick] [--no-walk]
[--seeds 0 1 2]``.

Measured (2026-12-03, ``--seeds 0 1 2 3 4``, about 12 minutes per drive on the 2-core
machine), withheld-fix RMS averaged over the five drives, m; in brackets the drives on
which the method beat (c)::

    gap s   spline        Bias() sigma_a=1  Bias()          +GyroBias+AttitudeError+Walk  GTSAM
    10      5.3148 (0/5)  1.8201 (0/5)      193.3985 (0/5)  0.7856                        0.7858 (1/5)
    30     39.3794 (0/5)  3.9144 (0/5)      318.8087 (0/5)  1.2647                        1.2654 (1/5)
    60     85.6562 (0/5)  8.4018 (0/5)      404.5066 (0/5)  1.6159                        1.6168 (2/5)

GTSAM/bvpnav per drive between 0.9997 and 1.0026; every gyro-bias knot within 3 std or
20 % of the truth (63/63 per gap and drive).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from bvpnav import NavigationProblem
from bvpnav.constraints import Position
from bvpnav.error_models import Bias
from bvpnav.error_models._attitude import hat_weights
from bvpnav.scenarios import SENSOR_GRADES, CarDrive, car_drive
from bvpnav.sensors import grade as sensor_grade

sys.path.insert(0, str(Path(__file__).resolve().parent))  # _gtsam_peer.py lives beside this script

#: Method (c) with and without the angle random walk (``--no-walk``).
WALK, NO_WALK = "+GyroBias+AttitudeError+Walk", "+GyroBias+AttitudeError"
METHODS = ("spline", "Bias() sigma_a=1", "Bias()", NO_WALK, WALK, "GTSAM")


def load_peer():
    """``(gtsam_smoother, None)`` or ``(None, reason)`` when GTSAM or the peer module is missing."""
    try:
        from _gtsam_peer import gtsam_smoother
    except ImportError as exc:  # gtsam not installed, or the module not there
        return None, f"GTSAM column skipped: {exc}"
    return gtsam_smoother, None


def split_fixes(drive: CarDrive, gap: float) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the kept fixes (every ``gap`` s, the first and last included) and the withheld."""
    step = max(1, int(round(gap * drive.params["gnss_rate"])))
    kept = np.arange(0, drive.fix_t.size, step)
    if kept[-1] != drive.fix_t.size - 1:
        kept = np.append(kept, drive.fix_t.size - 1)
    return kept, np.setdiff1d(np.arange(drive.fix_t.size), kept)


def rms3(est: np.ndarray, truth: np.ndarray) -> float:
    """3-D RMS error, m."""
    return float(np.sqrt(np.mean(np.sum((est - truth) ** 2, axis=1))))


def at_times(t: np.ndarray, nodal: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Nodal values (N, 3) linearly interpolated at ``times`` (exact at sample times)."""
    return np.column_stack([np.interp(times, t, nodal[:, k]) for k in range(nodal.shape[1])])


def attitude_model(grade: str, interval: float, walk: bool = True):
    """The error model of method (c): the preset grade's
    :meth:`~bvpnav.sensors.SensorGrade.error_model` (its numbers as priors, biases with knots
    every ``interval`` s); ``walk``: with the gyro's angle random walk (``AttitudeWalk``, its
    density the gyro noise plus what the gyro-bias knots leave out, :meth:`SensorGrade.arw`)."""
    return sensor_grade(grade).error_model(interval, walk=walk)


def bvpnav_solve(drive: CarDrive, kept: np.ndarray, error_model, uncertainty: bool, heading: str = "given",
                 grade_sigma_a: bool = True, interval: float | None = None):
    """bvpnav with the kept fixes as soft positions; returns the solution and its wall time (s).

    ``sigma_a`` is the grade's per-sample accelerometer noise (``grade_sigma_a``; with the
    bias knots' ``interval`` for a random-walk ``Bias``, :meth:`SensorGrade.sigma_a`) or
    left unstated (bvpnav's default 1 m/s^2, what a new user gets).
    ``heading`` is the attitude loop's global start ("given": from the guess, as the GTSAM
    peer starts; "auto": the coarse heading search, 12 more solves).
    """
    # per-sample noise of the accelerometers
    sigma_a = sensor_grade(drive.params["grade"]).sigma_a(drive.rate, interval) if grade_sigma_a else None
    prob = NavigationProblem(drive.data(), error_model=error_model, sigma_a=sigma_a)
    prob.add(Position(t=drive.fix_t[kept], value=drive.fix_position[kept],
                      sigma=np.tile(drive.fix_sigma, (kept.size, 1))))
    t0 = time.perf_counter()
    sol = prob.solve(solver="direct", lam=1.0, uncertainty=uncertainty,
                     attitude={"progress": False, "heading": heading})
    return sol, time.perf_counter() - t0


def gyro_bias_rows(drive: CarDrive, sol, interval: float) -> list[dict]:
    """Per knot and axis: estimate, std, truth (hat-weighted mean over the knot's support) (rad/s)."""
    names = [n for n in sol.error_params.index if n.startswith("gyro_bias_x[")]
    m = len(names)
    knots = np.linspace(drive.t[0], drive.t[-1], m)
    W = hat_weights(drive.t, knots)
    truth = (W.T @ drive.gyro_bias) / W.sum(axis=0)[:, None]
    rows = []
    for j in range(m):
        for a, ax in enumerate("xyz"):
            name = f"gyro_bias_{ax}[{j}]"
            est = float(sol.error_params[name])
            std = float(sol.error_params_std[name]) if name in sol.error_params_std else float("nan")
            err = abs(est - truth[j, a])
            ok = bool(err <= 3 * std or err <= 0.2 * abs(truth[j, a]))
            rows.append({"knot": j, "t": knots[j], "axis": ax, "estimate": est, "std": std,
                         "truth": truth[j, a], "ok": ok})
    return rows


def run_gap(drive: CarDrive, gap: float, peer, interval: float, heading: str = "given",
            walk: bool = True) -> dict:
    """All methods at one outage length; RMS (m) and wall time (s) per method."""
    kept, withheld = split_fixes(drive, gap)
    t_w = drive.fix_t[withheld]
    truth = drive.truth_at(t_w)
    out: dict = {"gap": gap, "kept": kept.size, "withheld": withheld.size, "rms": {}, "seconds": {}}
    t0 = time.perf_counter()
    spline = CubicSpline(drive.fix_t[kept], drive.fix_position[kept])(t_w)
    out["rms"]["spline"], out["seconds"]["spline"] = rms3(spline, truth), time.perf_counter() - t0

    sol, sec = bvpnav_solve(drive, kept, Bias(), uncertainty=False, grade_sigma_a=False)
    key = "Bias() sigma_a=1"
    out["rms"][key], out["seconds"][key] = rms3(at_times(drive.t, sol.position(), t_w), truth), sec
    sol, sec = bvpnav_solve(drive, kept, Bias(), uncertainty=False)
    out["rms"]["Bias()"], out["seconds"]["Bias()"] = rms3(at_times(drive.t, sol.position(), t_w), truth), sec

    sol, sec = bvpnav_solve(drive, kept, attitude_model(drive.params["grade"], interval, walk),
                            uncertainty=True, heading=heading, interval=interval)
    key = WALK if walk else NO_WALK
    out["key"] = key
    out["rms"][key], out["seconds"][key] = rms3(at_times(drive.t, sol.position(), t_w), truth), sec
    out["gyro_bias"] = gyro_bias_rows(drive, sol, interval)
    out["attitude"] = {a: float(sol.error_params[f"attitude_{a}"]) for a in "xyz"}
    seq = sol.stats.get("sequential", {}) if isinstance(sol.stats, dict) else {}
    out["loop"] = {"iterations": len(seq.get("iterations", [])), "converged": seq.get("converged")}
    out["warnings"] = list(sol.warnings)
    W = hat_weights(t_w, np.linspace(drive.t[0], drive.t[-1], len(out["gyro_bias"]) // 3))
    est = np.array([[r["estimate"] for r in out["gyro_bias"] if r["axis"] == ax] for ax in "xyz"]).T
    true_w = np.column_stack([np.interp(t_w, drive.t, drive.gyro_bias[:, k]) for k in range(3)])
    out["bias_rms"] = {key: float(np.sqrt(np.mean((W @ est - true_w) ** 2)))}

    if peer is not None:
        g = peer(drive.t, drive.specific_force, drive.gyro, drive.gravity, drive.fix_t[kept],
                 drive.fix_position[kept], drive.fix_sigma, drive.initial_attitude_guess,
                 dict(drive.params["sensor"]), t_w)
        out["rms"]["GTSAM"], out["seconds"]["GTSAM"] = rms3(np.asarray(g["position"]), truth), g["seconds"]
        out["bias_rms"]["GTSAM"] = float(np.sqrt(np.mean((np.asarray(g["gyro_bias"]) - true_w) ** 2)))
    return out


def print_table(grade: str, drive: CarDrive, results: list[dict], note: str | None) -> None:
    """The withheld-fix RMS table (m) with wall times (s), and the acceptance checks."""
    cols = [m for m in METHODS if all(m in r["rms"] for r in results)]
    print(f"\n== {grade}: {drive.params['duration']:g} s at {drive.rate:g} Hz, fixes "
          f"{drive.params['gnss_rate']:g} Hz sigma {drive.fix_sigma.tolist()} m, seed {drive.params['seed']}")
    print("withheld-fix RMS, m (3-D, against the truth); wall time in s in brackets")
    print(f"{'gap s':>6} {'kept':>5} {'held':>5} " + " ".join(f"{c:>29}" for c in cols))
    for r in results:
        cells = [f"{r['rms'][c]:10.4f} ({r['seconds'][c]:7.1f} s)" for c in cols]
        print(f"{r['gap']:6g} {r['kept']:5d} {r['withheld']:5d} " + " ".join(f"{c:>29}" for c in cells))
    if note:
        print(note)
    for r in results:
        key = r["key"]
        ratio = r["rms"]["Bias()"] / r["rms"][key]
        vs = (f"; GTSAM/bvpnav {r['rms']['GTSAM'] / r['rms'][key]:.4f}" if "GTSAM" in r["rms"] else "")
        brms = "  ".join(f"{k} {v:.2e}" for k, v in r["bias_rms"].items())
        print(f"gap {r['gap']:g} s: Bias()/attitude-models {ratio:.1f}x{vs}; gyro-bias RMS error at the "
              f"withheld instants (rad/s): {brms}; loop {r['loop']['iterations']} iterations, converged "
              f"{r['loop']['converged']}; attitude correction est "
              f"({r['attitude']['x']:+.5f}, {r['attitude']['y']:+.5f}, {r['attitude']['z']:+.5f}) rad, "
              f"true {tuple(round(float(v), 5) for v in drive.attitude_correction)}")
        for w in r["warnings"]:
            print(f"    warning: {w[:200]}")


def print_bias(results: list[dict]) -> None:
    """Estimated vs true gyro bias per knot (rad/s) for method (c)."""
    for r in results:
        rows = r["gyro_bias"]
        n_ok = sum(row["ok"] for row in rows)
        print(f"\ngyro bias of {r['key']}, gap {r['gap']:g} s: {n_ok}/{len(rows)} within "
              "3 std or 20 % of the truth (rad/s; truth = hat-weighted mean over the knot's support)")
        print(f"{'knot':>4} {'t s':>6} " + " ".join(f"{'est ' + a:>10} {'std':>8} {'true':>10} ok"
                                                   for a in "xyz"))
        for j in sorted({row["knot"] for row in rows}):
            cells = [row for row in rows if row["knot"] == j]
            print(f"{j:4d} {cells[0]['t']:6.0f} " + " ".join(
                f"{c['estimate']:10.2e} {c['std']:8.1e} {c['truth']:10.2e} {'y' if c['ok'] else 'N':>2}"
                for c in cells))


def main(argv: list[str] | None = None) -> list[dict]:
    """Run the benchmark; returns the results per grade and gap."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grade", nargs="+", default=["tactical"], choices=sorted(SENSOR_GRADES))
    ap.add_argument("--duration", type=float, default=600.0, help="s (default 600)")
    ap.add_argument("--rate", type=float, default=100.0, help="IMU rate, Hz (default 100)")
    ap.add_argument("--gaps", type=float, nargs="+", default=[10.0, 30.0, 60.0],
                    help="kept-fix spacings, s (default 10 30 60)")
    ap.add_argument("--interval", type=float, default=30.0, help="bias knot spacing of (c), s (default 30)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0],
                    help="drives to run (noise realizations); with several, also the mean table")
    ap.add_argument("--seed", type=int, default=None, help="one drive (same as --seeds SEED)")
    ap.add_argument("--heading", default="given", choices=["given", "auto"],
                    help="start of the attitude loop of (c): the guess (like GTSAM) or the search")
    ap.add_argument("--no-gtsam", action="store_true", help="skip the GTSAM column")
    ap.add_argument("--no-walk", action="store_true",
                    help="method (c) without AttitudeWalk (the gyro's angle random walk unmodelled)")
    ap.add_argument("--quick", action="store_true", help="120 s at 50 Hz, gaps 10 30 (a smoke test)")
    args = ap.parse_args(argv)
    if args.quick:
        args.duration, args.rate, args.gaps = 120.0, 50.0, [10.0, 30.0]
    peer, note = (None, "GTSAM column skipped (--no-gtsam)") if args.no_gtsam else load_peer()
    seeds = [args.seed] if args.seed is not None else args.seeds
    everything = []
    for grade in args.grade:
        per_seed = []
        for seed in seeds:
            drive = car_drive(args.duration, args.rate, grade, seed=seed)
            results = [run_gap(drive, gap, peer, args.interval, args.heading, not args.no_walk)
                       for gap in args.gaps]
            print_table(grade, drive, results, note)
            print_bias(results)
            everything.append({"grade": grade, "seed": seed, "results": results})
            per_seed.append(results)
            sys.stdout.flush()
        if len(seeds) > 1:
            print_mean(grade, seeds, per_seed)
    return everything


def mean_rms(per_seed: list[list[dict]]) -> list[dict]:
    """Per outage length, each method's withheld-fix RMS averaged over the drives (m)."""
    out = []
    for i, first in enumerate(per_seed[0]):
        rows = [results[i] for results in per_seed]
        methods = [m for m in first["rms"] if all(m in r["rms"] for r in rows)]
        out.append({"gap": first["gap"], "key": first["key"],
                    "rms": {m: float(np.mean([r["rms"][m] for r in rows])) for m in methods},
                    "beats": {m: sum(r["rms"][first["key"]] > r["rms"][m] for r in rows) for m in methods}})
    return out


def print_mean(grade: str, seeds: list[int], per_seed: list[list[dict]]) -> None:
    """The RMS table averaged over the drives, and how many drives each method beat (c) on."""
    print(f"\n== {grade}: withheld-fix RMS averaged over seeds {seeds} (m); in brackets the number of "
          "drives where the method is better than (c)")
    rows = mean_rms(per_seed)
    cols = [m for m in METHODS if all(m in r["rms"] for r in rows)]
    print(f"{'gap s':>6} " + " ".join(f"{c:>29}" for c in cols))
    for r in rows:
        cells = [f"{r['rms'][c]:22.4f} ({r['beats'][c]}/{len(seeds)})" for c in cols]
        print(f"{r['gap']:6g} " + " ".join(cells))
    for r in rows:
        key = r["key"]
        vs = f"; GTSAM/bvpnav {r['rms']['GTSAM'] / r['rms'][key]:.4f}" if "GTSAM" in r["rms"] else ""
        default, graded = r["rms"]["Bias() sigma_a=1"], r["rms"]["Bias()"]
        print(f"gap {r['gap']:g} s (mean): Bias()/attitude-models {default / r['rms'][key]:.1f}x "
              f"(bvpnav's default sigma_a), {graded / r['rms'][key]:.1f}x (the grade's){vs}")


if __name__ == "__main__":
    main()
