"""2011 Tikhonov paper, Section 5: a roller coaster whose track shape is known, not its timing.

A simulated planar track of about 250 m (station, lift hill, first drop, a vertical loop,
a camel-back hump, brake run) in the x-z plane. The car rotates freely in the plane: its
attitude is the track's tangent angle, so the accelerometer triad measures body-frame
specific force and the gyro measures the pitch rate. 1000 Hz, consumer-grade errors
(accelerometer bias 0.05 m/s^2 and white noise 0.02 m/s^2 per axis; gyro bias 5e-4 rad/s
and white noise 1e-3 rad/s). As in the paper the initial and final attitude are known to
be the same (up to the loop's full turn), which fixes the gyro bias; the attitude is then
integrated from the corrected gyro (``ImuData.from_gyro``) and the navigation-frame x and z
accelerations drive a 2-D problem.

Three runs at different speeds (lift speed and friction differ), known start and end
positions. Per run:

(a) FEM with the end positions only;
(b) the same plus ``TrackLine`` (soft, sigma = 1 m, the paper's unit variance), solved by
    the sequential convex loop (first phase: (a)); lambda chosen by the L-curve on run 1
    and re-used for runs 2 and 3, as in the paper.

Printed: RMS distance of the estimate to the true path and RMS position error against the
simulated truth (m), the loop's iterations and last change per iteration, and timings.

Run ``python examples/roller_coaster.py`` (full size, 1000 Hz) or ``--small`` (100 Hz,
the test size; also ``BVPNAV_SMALL=1``). With ``BVPNAV_FIGURES`` set (a directory, as for every
example; or ``--figures DIR``) ``roller_coaster.png`` is written there.
"""

from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.interpolate import CubicSpline

import bvpnav
from bvpnav.constraints import Position, TrackLine
from bvpnav.constraints.track_line import project_onto_polyline
from bvpnav.simulate import Motion, SensorErrors, simulate_imu
from bvpnav.solve import lambda_curve, solve_sequential

G = 9.80665
#: (lift speed m/s, rolling-friction deceleration m/s^2) of the three runs
RUNS = {1: (2.5, 0.25), 2: (3.2, 0.15), 3: (2.0, 0.40)}
ACCEL = SensorErrors(bias=0.05, noise=0.02)
GYRO = SensorErrors(bias=(0.0, 5e-4, 0.0), noise=1e-3)
WAYPOINT_STEP = 0.05  # s, on the sampling grid of every rate used


def _smoothstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def track(ds: float = 0.05) -> CubicSpline:
    """The track as a C2 spline of arc length: ``P(s) -> (x, z)`` in m."""
    pieces = []
    x = np.linspace(0.0, 10.0, 201)
    pieces.append(np.column_stack([x, 0.0 * x]))  # station
    x = np.linspace(10.0, 60.0, 1001)
    pieces.append(np.column_stack([x, 30.0 * _smoothstep((x - 10.0) / 50.0)]))  # lift hill
    x = np.linspace(60.0, 100.0, 801)
    pieces.append(np.column_stack([x, 30.0 - 28.0 * _smoothstep((x - 60.0) / 40.0)]))  # drop
    x = np.linspace(100.0, 108.0, 161)
    pieces.append(np.column_stack([x, np.full_like(x, 2.0)]))
    u = np.linspace(0.0, 2.0 * np.pi, 2001)  # vertical loop (a curtate trochoid, 16 m high)
    a, b = 2.0, 8.0
    pieces.append(np.column_stack([108.0 + a * u + b * np.sin(u), 2.0 + b * (1.0 - np.cos(u))]))
    x0 = 108.0 + 2.0 * np.pi * a
    x = np.linspace(x0, x0 + 8.0, 161)
    pieces.append(np.column_stack([x, np.full_like(x, 2.0)]))
    x = np.linspace(x0 + 8.0, x0 + 48.0, 801)  # camel-back hump
    pieces.append(np.column_stack([x, 2.0 + 9.0 * np.sin(np.pi * (x - x0 - 8.0) / 40.0) ** 2]))
    x = np.linspace(x0 + 48.0, x0 + 58.0, 201)
    pieces.append(np.column_stack([x, 2.0 - 2.0 * _smoothstep((x - x0 - 48.0) / 10.0)]))
    x = np.linspace(x0 + 58.0, x0 + 80.0, 441)
    pieces.append(np.column_stack([x, 0.0 * x]))  # brake run and station
    pts = np.vstack([pieces[0]] + [p[1:] for p in pieces[1:]])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    raw = CubicSpline(s, pts)
    s2 = np.arange(0.0, s[-1], ds)  # re-parametrise on a regular arc-length grid
    return CubicSpline(s2, raw(s2))


def speed_profile(P: CubicSpline, v_lift: float, friction: float):
    """Speed (m/s) along the track: ramp-up, chain lift, gravity minus friction, brakes."""
    L = P.x[-1]
    s = np.linspace(0.0, L, 200_001)
    z = P(s)[:, 1]
    k_top = int(np.argmax(z))
    v2 = np.full(s.size, v_lift**2)
    ramp = s < 5.0
    v2[ramp] = v_lift**2 * s[ramp] / 5.0
    free = s > s[k_top]
    v2[free] = v_lift**2 + 2.0 * G * (z[k_top] - z[free]) - 2.0 * friction * (s[free] - s[k_top])
    brake = s > L - 15.0
    kb = int(np.argmax(brake))
    v2[brake] = v2[kb] * (L - s[brake]) / 15.0
    if np.any(v2[free & ~brake] <= 0):
        raise ValueError("the car stops on the track: lower the friction")
    return s, np.sqrt(np.maximum(v2, 0.0))


def simulate_run(P: CubicSpline, run: int, rate: float, seed: int):
    """Strapdown simulation of one run; returns the Simulation and its 2-D ImuData (x, z)."""
    v_lift, friction = RUNS[run]
    s, v = speed_profile(P, v_lift, friction)
    mid = 0.5 * (v[1:] + v[:-1])
    tt = np.concatenate([[0.0], np.cumsum(np.diff(s) / mid)])
    T = np.ceil(tt[-1] / WAYPOINT_STEP) * WAYPOINT_STEP
    tw = np.arange(0.0, T + WAYPOINT_STEP / 2, WAYPOINT_STEP)
    sw = np.interp(tw * tt[-1] / T, tt, s)
    xz = P(sw)
    d = P(sw, 1)
    ang = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    pos = np.column_stack([xz[:, 0], np.zeros(tw.size), xz[:, 1]])
    euler = np.column_stack([np.zeros(tw.size), -ang, np.zeros(tw.size)])  # pitch = -track angle
    motion = Motion.from_waypoints(tw, pos, euler)
    sim = simulate_imu(motion, rate, accel=ACCEL, gyro=GYRO, seed=seed)
    # the final attitude equals the initial one (after the loop's full turn): fix the gyro bias
    raw = bvpnav.ImuData.from_gyro(sim.t, sim.specific_force, sim.gyro, initial_attitude=sim.attitude[0])
    err = (raw.attitude[-1].inv() * sim.attitude[-1]).as_rotvec()
    gyro = sim.gyro + err / (sim.t[-1] - sim.t[0])
    data3 = bvpnav.ImuData.from_gyro(sim.t, sim.specific_force, gyro, initial_attitude=sim.attitude[0])
    data = bvpnav.ImuData(sim.t, acc=data3.acc[:, [0, 2]], axes=("x", "z"))
    att_err = np.abs((data3.attitude.inv() * sim.attitude).magnitude()).max()
    return sim, data, float(att_err)


def path_distance(vertices: np.ndarray, t: np.ndarray, pos: np.ndarray) -> float:
    """RMS distance (m) of estimated positions to the polyline (continuity-resolved)."""
    pr = project_onto_polyline(vertices, t, pos, ambiguity=0.5, beyond_ends="clamp")
    return float(np.sqrt(np.mean(pr.distance**2)))


def run(small: bool = False, figures: str | None = None, quiet: bool = False) -> pd.DataFrame:
    """All three runs; one row per run with the RMS numbers (m) of (a) and (b)."""
    rate = 100.0 if small else 1000.0
    P = track()
    sv = np.arange(0.0, P.x[-1], 0.5)
    vertices = P(np.append(sv, P.x[-1]))
    item = TrackLine(x=vertices[:, 0], y=vertices[:, 1], axes=("x", "z"), sigma=1.0, name="track")
    lam = None
    rows, keep = [], {}
    for r in RUNS:
        t0 = time.perf_counter()
        sim, data, att_err = simulate_run(P, r, rate, seed=100 + r)
        truth = sim.truth[["x", "z"]].to_numpy()
        ends = Position(t=[data.t[0], data.t[-1]], value=[truth[0], truth[-1]], name="ends")
        pa = bvpnav.NavigationProblem(data, sigma_a=ACCEL.noise).add(ends)
        sol_a = pa.solve(solver="direct")
        pb = bvpnav.NavigationProblem(data, sigma_a=ACCEL.noise).add(ends, item)
        t_l = time.perf_counter()
        if lam is None:  # the L-curve on run 1, on the linearization about (a), as the paper
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                lin = item.linearized(data.t, sol_a.trajectory)
                curve = lambda_curve(bvpnav.NavigationProblem(data, sigma_a=ACCEL.noise).add(ends, lin),
                                     rules=("lcurve",), lam_range=(1e-4, 1e6),
                                     points=9 if small else 25)  # refined in its bracket
            lam = curve.lam_chosen
        t_l = time.perf_counter() - t_l
        t_s = time.perf_counter()
        sol_b = solve_sequential(pb, solver="direct", lam=lam, initial=sol_a, tol=1e-4, max_iter=40)
        t_s = time.perf_counter() - t_s
        sq = sol_b.stats["sequential"]
        rows.append({
            "run": r, "v_lift": RUNS[r][0], "friction": RUNS[r][1], "duration": data.t[-1],
            "samples": data.n, "attitude_err_deg": np.degrees(att_err),
            "a_path_rms": path_distance(vertices, data.t, sol_a.position()),
            "a_pos_rms": sol_a.rms_error(truth),
            "b_path_rms": path_distance(vertices, data.t, sol_b.position()),
            "b_pos_rms": sol_b.rms_error(truth),
            "lam": lam, "iterations": sq["iterations"], "last_change": sq["max_change"][-1],
            "converged": sq["converged"], "changes": sq["max_change"],
            "lcurve_s": t_l, "loop_s": t_s, "total_s": time.perf_counter() - t0,
        })
        keep[r] = (truth, sol_a.position(), sol_b.position())
    df = pd.DataFrame(rows)
    df["ratio"] = df.a_pos_rms / df.b_pos_rms
    if not quiet:
        print(f"Roller coaster (2011 paper, Sec. 5): track {P.x[-1]:.1f} m, {rate:g} Hz, accelerometer "
              f"bias {ACCEL.bias} m/s^2, noise {ACCEL.noise} m/s^2; gyro bias 5e-4 rad/s, noise 1e-3 rad/s")
        print(f"lambda by L-curve on run 1: {lam:.4g} (re-used for runs 2 and 3)")
        print(f"{'run':>3} {'T (s)':>6} | {'(a) ends only':>21} | {'(b) + TrackLine':>21} | "
              f"{'ratio':>6} | {'iter':>4} {'last change':>11} | {'time (s)':>8}")
        print(f"{'':>3} {'':>6} | {'path RMS':>10} {'pos RMS':>10} | {'path RMS':>10} {'pos RMS':>10} | "
              f"{'':>6} | {'':>4} {'(m)':>11} |")
        for d in df.to_dict("records"):
            print(f"{d['run']:>3} {d['duration']:6.1f} | {d['a_path_rms']:10.3f} {d['a_pos_rms']:10.3f} | "
                  f"{d['b_path_rms']:10.4f} {d['b_pos_rms']:10.4f} | {d['ratio']:6.1f} | "
                  f"{d['iterations']:>4} {d['last_change']:11.2e} | {d['total_s']:8.1f}")
        for d in df.to_dict("records"):
            print(f"run {d['run']}: change per iteration (m): " + ", ".join(f"{c:.3g}" for c in d["changes"]))
    if figures:
        _figure(vertices, keep, Path(figures))
    return df


def _figure(vertices, keep, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(10, 4))
    ax.plot(vertices[:, 0], vertices[:, 1], "k-", lw=2.5, label="track")
    for r, (_, a, b) in keep.items():
        ax.plot(a[:, 0], a[:, 1], ":", lw=1, label=f"run {r}: (a) ends only")
        ax.plot(b[:, 0], b[:, 1], "--", lw=1, label=f"run {r}: (b) + TrackLine")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_aspect("equal")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(out / "roller_coaster.png", dpi=100)
    plt.close(fig)


def main(argv=None) -> pd.DataFrame:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--small", action="store_true", help="100 Hz instead of 1000 Hz (test size)")
    ap.add_argument("--figures", metavar="DIR", default=os.environ.get("BVPNAV_FIGURES"),
                    help="write PNG figures here (default: $BVPNAV_FIGURES, if set)")
    args = ap.parse_args(argv)
    return run(small=args.small or os.environ.get("BVPNAV_SMALL") == "1", figures=args.figures)


if __name__ == "__main__":
    main()
