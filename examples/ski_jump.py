"""2010 paper, Section 7: a ski jump from five inrun points and the landing-hill line.

The paper navigates a ski jumper's boot with consumer-grade sensors and two pieces of
information: the boot's position at five points spread along the inrun, and the fact
that after landing the boot moves along the (linearized) landing hill. It has no
reference trajectory, so it cannot give errors. Here the jump is simulated, so the
landing-point error can be measured with and without the landing-hill item.

The simulated jump (2-D in the vertical x-z plane, x downhill, z up; the take-off edge
at the origin):

- inrun: a 45 m straight at 35 degrees, a circular transition (radius 100 m) to the
  11 degree table, 6 m of table; the jumper starts at rest and slides with snow
  friction (mu = 0.03) and air drag (take-off speed 26.2 m/s after 6.1 s);
- take-off: a push of 2.5 m/s normal to the table at the edge;
- flight: gravity plus a simple aerodynamic model (drag and lift proportional to the
  speed squared, about 1 and 2 m/s^2 at take-off speed), skis pitched up to 25 degrees
  against the flight path in the air; 3.7 s in the air;
- landing (at x = 95 m) on a hill whose slope grows from 5 to 35 degrees over the first
  40 m (the knoll), stays at 35 degrees to x = 100 m and flattens into the outrun by
  x = 150 m; the normal velocity is lost at touch-down, then the jumper slides on and
  brakes (5 m/s^2) beyond x = 150 m; the recording ends 4 s after landing.

The boot's track is a cubic spline through the simulated states every 0.08 s (so the
take-off push and the landing impact, about 10 g, are smoothed over about 0.2 s).

Sensors: a strapdown triad (body x along the ski, z normal to it) with consumer-grade
accelerometer errors, bias (0.15, -0.10, 0.20) m/s^2 and scale error (+1.0, -0.5,
-1.5) %, and white noise of 0.05 m/s^2/sqrt(Hz) (0.71 m/s^2 per sample at 200 Hz,
0.35 at 50 Hz) that stands for the sensor noise plus the skis' vibration on the
track. The attitude (pitch, and roll and yaw errors) is integrated from gyro rates
with the bias left after a calibration at rest at the start gate, (0.3, 0.5, -0.3)
mrad/s, and white noise of 2e-4 rad/s/sqrt(Hz) (``--true-attitude`` uses the true
attitude instead). Each realisation is the same jump with other sensor noise; the
table gives means over realisations, because one realisation's landing-point error
depends much on its noise (per realisation the ratio below ranges from 3 to 100).

Information used:

- the five inrun points: positions at arc lengths 0, 1/4, 1/2, 3/4 and 1 of the inrun
  (start gate to take-off edge), at the true instants rounded to a sample (photo
  cells), as hard ``Position`` items on x, y and z (the boot stays in the plane y = 0);
- the landing-hill line: ``TrackLine(x=..., y=..., axes=("x", "z"), t0=t_landing,
  mode="soft", sigma=0.05)``, the hill as a polyline with 1 m vertices, from the
  instant of landing (visible as the impact in the accelerometer) to the end; sigma
  is the 5 cm allowed for the snow surface and the boot above it;
- error model ``Bias() + ScaleFactor(axes=("x", "z"))``: five unknowns besides the
  trajectory (the body y axis feels no specific force in a planar jump, so its scale
  factor cannot be told from its bias).

Choice of lambda: the data term is the acceleration residual weighted by the stated
noise level (``sigma_a``), so ``lam = 1`` weighs the landing-hill rows by the Gaussian
likelihood of their 5 cm (the MAP estimate); the inrun points are hard. The TrackLine
is nonlinear (the nearest hill segment depends on the estimate):
``NavigationProblem.solve`` runs the sequential loop from the solution without the
line, and its iterations and changes per iteration are printed.

What the line can and cannot do: it measures the distance to the hill, i.e. the
position *normal* to the hill. At the landing point that, together with the
trajectory's continuity back to the inrun, removes most of the error (about 20x at
200 Hz). Along the hill it says nothing to first order, so on the flat outrun the
along-track (x) error still grows (RMS after landing about 0.5 m with the line against
1.1 m without).

Printed: the landing-point error (m, x-z distance between the estimated and the true
position at the instant of landing) with and without the landing-hill line, the RMS
x-z position error over the flight, after landing and overall (means over
realisations), the ratio per realisation, the loop's report and the error-model
estimates of the first realisation. Run ``python examples/ski_jump.py`` (200 Hz,
8 realisations, about a minute) or ``--small`` (50 Hz, 4 realisations). With
``BVPNAV_FIGURES`` set (a directory; or ``--figures DIR``) ``ski_jump.png`` (first
realisation) is written there.

Notes
-----
Motion equations of the simulation (m, s): on a profile with slope angle
:math:`\\alpha` (positive downhill) and arc length :math:`s`,
:math:`\\ddot s = g \\sin\\alpha - \\mu g \\cos\\alpha - k_d \\dot s^2 - b` (b the braking, m/s^2); in the air
:math:`\\ddot r = g + |v| (-k_d v + k_l v^\\perp)` with :math:`v^\\perp` the velocity
turned by +90 degrees. The accelerometer reads :math:`\\hat f = (I + S) C^T (\\ddot r -
g) + b_a + n`. The landing-hill row at each sample after landing is the linearized
distance to the hill, :math:`n_k \\cdot r(t_k) - n_k \\cdot q_k` (m), with
:math:`q_k` the nearest point of the polyline to the current estimate.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

import bvpnav
from bvpnav.constraints import Position
from bvpnav.error_models import Bias, ScaleFactor
from bvpnav.simulate import Motion, SensorErrors, simulate_imu

G = 9.80665  #: m/s^2
MU = 0.03  #: snow friction, dimensionless
KD = 0.0015  #: air drag coefficient, 1/m (deceleration k_d v^2)
KL = 0.003  #: lift coefficient in flight, 1/m
PUSH = 2.5  #: take-off push normal to the table, m/s
ATTACK = np.radians(25.0)  #: ski pitch above the flight path in the air, rad
BRAKE = 5.0  #: braking on the flat outrun, m/s^2
KNOT = 0.08  #: spacing of the spline knots, s
AFTER_LANDING = 4.0  #: recording after landing, s
ACCEL = SensorErrors(bias=(0.15, -0.10, 0.20), scale=(0.010, -0.005, -0.015), noise=0.0)
NOISE_DENSITY = 0.05  #: accelerometer white noise incl. ski vibration, m/s^2/sqrt(Hz)
GYRO_BIAS = (0.0003, 0.0005, -0.0003)  #: gyro bias left after calibration at the gate, rad/s
GYRO_DENSITY = 2e-4  #: gyro white noise, rad/s/sqrt(Hz)
SIGMA_HILL = 0.05  #: landing-hill line sigma, m


# ------------------------------------------------------------------ the hill
def _profile(angle_of_s, length: float, ds: float = 0.01) -> tuple[np.ndarray, ...]:
    """Arc length (m), x, z (m) and slope angle (rad, positive downhill) of a profile."""
    s = np.arange(0.0, length + ds / 2, ds)
    a = angle_of_s(s)
    # trapezoid rule on the unit tangent (cos a, -sin a)
    dx = np.concatenate([[0.0], np.cumsum(0.5 * (np.cos(a[1:]) + np.cos(a[:-1])) * ds)])
    dz = np.concatenate([[0.0], np.cumsum(-0.5 * (np.sin(a[1:]) + np.sin(a[:-1])) * ds)])
    return s, dx, dz, a


def inrun_profile() -> dict:
    """The inrun from the start gate (s = 0) to the take-off edge at the origin.

    Returns
    -------
    dict
        ``s`` arc length (m), ``x``, ``z`` (m), ``angle`` (rad, positive downhill),
        ``length`` (m).
    """
    a0, a1, radius, l1, l3 = np.radians(35.0), np.radians(11.0), 100.0, 45.0, 6.0
    l2 = radius * (a0 - a1)

    def angle(s):
        return np.clip(a0 - (s - l1) / radius, a1, a0)

    s, x, z, a = _profile(angle, l1 + l2 + l3)
    return {"s": s, "x": x - x[-1], "z": z - z[-1], "angle": a, "length": float(s[-1])}


def landing_profile() -> dict:
    """The landing hill from below the edge (x = 0, z = -3 m) to the end of the outrun.

    Returns
    -------
    dict
        ``s`` arc length (m), ``x``, ``z`` (m), ``angle`` (rad, positive downhill).
    """

    def slope_of_x(x):
        up = 0.5 - 0.5 * np.cos(np.pi * np.clip(x / 40.0, 0.0, 1.0))  # knoll: 5 -> 35 deg
        down = 0.5 + 0.5 * np.cos(np.pi * np.clip((x - 100.0) / 50.0, 0.0, 1.0))  # 35 -> 0 deg
        return np.where(x < 100.0, np.radians(5.0 + 30.0 * up), np.radians(35.0) * down)

    x = np.arange(0.0, 300.0 + 0.005, 0.01)
    a = slope_of_x(x)
    z = -3.0 - np.concatenate([[0.0], np.cumsum(0.5 * (np.tan(a[1:]) + np.tan(a[:-1])) * 0.01)])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(z)))])
    return {"s": s, "x": x, "z": z, "angle": a}


def _slide(prof: dict, s0: float, v0: float, t_span: tuple[float, float], brake_from_x: float | None = None,
           events=None):
    """Slide along a profile from arc length s0 (m) with speed v0 (m/s); dense solution."""

    def rhs(_t, y):
        s, v = y
        a = np.interp(s, prof["s"], prof["angle"])
        acc = G * np.sin(a) - MU * G * np.cos(a) - KD * v * v
        if brake_from_x is not None and np.interp(s, prof["s"], prof["x"]) > brake_from_x and v > 0:
            acc -= BRAKE
        return [v, acc]

    return solve_ivp(rhs, t_span, [s0, v0], events=events, dense_output=True, rtol=1e-10, atol=1e-10,
                     max_step=0.01)


def _on(prof: dict, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """x, z (m) and angle (rad) at arc lengths s of a profile."""
    return (np.interp(s, prof["s"], prof["x"]), np.interp(s, prof["s"], prof["z"]),
            np.interp(s, prof["s"], prof["angle"]))


def simulate_jump(rate: float = 200.0, seed: int = 0) -> dict:
    """Simulate the jump and the strapdown accelerometer and gyro triads.

    Parameters
    ----------
    rate : float
        Sampling rate, Hz (a multiple of 12.5 Hz, so the knots every 0.08 s are samples).
    seed : int
        Seed of the accelerometer and gyro noise (the jump itself is deterministic).

    Returns
    -------
    dict
        ``sim`` (:class:`bvpnav.simulate.Simulation`), ``t_takeoff``, ``t_landing`` (s),
        ``inrun`` and ``hill`` (profiles, see :func:`inrun_profile`,
        :func:`landing_profile`), ``sigma_a`` (m/s^2).
    """
    inrun, hill = inrun_profile(), landing_profile()
    # inrun: from rest at the gate until the edge
    edge = inrun["length"]

    def at_edge(_t, y):
        return y[0] - edge

    at_edge.terminal = True
    ph1 = _slide(inrun, 0.0, 0.0, (0.0, 30.0), events=at_edge)
    t_to = float(ph1.t_events[0][0])
    v_edge = float(ph1.y_events[0][0][1])
    a_tab = inrun["angle"][-1]
    along, normal = np.array([np.cos(a_tab), -np.sin(a_tab)]), np.array([np.sin(a_tab), np.cos(a_tab)])
    vel0 = v_edge * along + PUSH * normal

    def flight(_t, y):
        v = y[2:]
        sp = np.hypot(*v)
        perp = np.array([-v[1], v[0]])
        acc = np.array([0.0, -G]) + sp * (-KD * v + KL * perp)
        return [v[0], v[1], acc[0], acc[1]]

    def touch(_t, y):
        return y[1] - np.interp(y[0], hill["x"], hill["z"])

    touch.terminal = True
    touch.direction = -1
    ph2 = solve_ivp(flight, (t_to, t_to + 10.0), [0.0, 0.0, *vel0], events=touch, dense_output=True,
                    rtol=1e-10, atol=1e-10, max_step=0.01)
    t_land = float(ph2.t_events[0][0])
    xl, _, vxl, vzl = ph2.y_events[0][0]
    s_land = float(np.interp(xl, hill["x"], hill["s"]))
    b = np.interp(s_land, hill["s"], hill["angle"])
    v_tan = vxl * np.cos(b) - vzl * np.sin(b)  # the normal part is lost at touch-down
    t_end = KNOT * np.ceil((t_land + AFTER_LANDING) / KNOT)
    ph3 = _slide(hill, s_land, v_tan, (t_land, t_end + 1e-9), brake_from_x=150.0)

    # the boot's states on the knots, then one spline through them
    tk = np.round(np.arange(0.0, t_end + KNOT / 2, KNOT), 10)
    pos = np.zeros((tk.size, 3))
    pitch = np.zeros(tk.size)
    m1, m2, m3 = tk <= t_to, (tk > t_to) & (tk < t_land), tk >= t_land
    s1 = ph1.sol(tk[m1])[0]
    pos[m1, 0], pos[m1, 2], pitch[m1] = _on(inrun, s1)
    y2 = ph2.sol(tk[m2])
    pos[m2, 0], pos[m2, 2] = y2[0], y2[1]
    path = -np.arctan2(y2[3], y2[2])  # pitch of the flight path (positive nose down)
    pitch[m2] = path - ATTACK * np.sin(np.pi * (tk[m2] - t_to) / (t_land - t_to)) ** 0.5
    s3 = ph3.sol(tk[m3])[0]
    pos[m3, 0], pos[m3, 2], pitch[m3] = _on(hill, s3)
    euler = np.column_stack([np.zeros(tk.size), pitch, np.zeros(tk.size)])
    motion = Motion.from_waypoints(tk, pos, euler=euler, bc_type="not-a-knot")
    sigma_a = NOISE_DENSITY * np.sqrt(rate)
    accel = SensorErrors(bias=ACCEL.bias, scale=ACCEL.scale, noise=sigma_a)
    gyro = SensorErrors(bias=GYRO_BIAS, noise=GYRO_DENSITY * np.sqrt(rate))
    sim = simulate_imu(motion, rate, accel=accel, gyro=gyro, seed=seed)
    return {"sim": sim, "t_takeoff": t_to, "t_landing": t_land, "inrun": inrun, "hill": hill,
            "sigma_a": sigma_a, "v_takeoff": float(np.hypot(*vel0)), "x_landing": float(xl)}


# ------------------------------------------------------------------ navigation
def information(sc: dict) -> dict:
    """The five inrun points and the landing-hill polyline.

    Returns
    -------
    dict
        ``t_points`` (5,) s, ``points`` (5, 3) m, ``hill_x``, ``hill_z`` (m, vertices
        every 1 m from x = 0 to the end of the outrun).
    """
    sim, inrun = sc["sim"], sc["inrun"]
    truth = sim.truth
    # arc length travelled at each sample (the boot is on the inrun until take-off)
    on_inrun = sim.t <= sc["t_takeoff"]
    xs = truth["x"].to_numpy()[on_inrun]
    s_at = np.interp(xs, inrun["x"], inrun["s"])
    targets = np.linspace(0.0, inrun["length"], 5)
    idx = [int(np.argmin(np.abs(s_at - s))) for s in targets]  # the photo cell's sample
    t_points = sim.t[idx]
    hill = sc["hill"]
    step = 100  # profile samples are 1 cm apart: vertices every 1 m
    return {"t_points": t_points, "points": sim.position(t_points), "hill_x": hill["x"][::step],
            "hill_z": hill["z"][::step]}


def problems(sc: dict, info: dict, attitude: str = "gyro", model=None):
    """Both problems: inrun points only, and inrun points plus the landing-hill line.

    ``attitude``: ``"gyro"`` (integrated from the simulated gyro rates, the default) or
    ``"true"``. The default error model is ``Bias() + ScaleFactor(axes=("x", "z"))``: the
    body y axis sees no specific force in a planar jump, so its scale factor cannot be
    told from its bias.
    """
    from bvpnav.constraints import TrackLine

    data = sc["sim"].imu_data(attitude=attitude)
    model = Bias() + ScaleFactor(axes=("x", "z")) if model is None else model
    inrun = Position(t=info["t_points"], value=info["points"], name="inrun points")
    line = TrackLine(x=info["hill_x"], y=info["hill_z"], axes=("x", "z"), t0=sc["t_landing"], t1=None,
                     mode="soft", sigma=SIGMA_HILL, name="landing hill")
    without = bvpnav.NavigationProblem(data, sigma_a=sc["sigma_a"], error_model=model, items=[inrun])
    with_line = bvpnav.NavigationProblem(data, sigma_a=sc["sigma_a"], error_model=model,
                                         items=[inrun, line])
    return without, with_line


def scores(sc: dict, sol) -> dict:
    """Errors of one solution against the simulated truth, m.

    ``landing_error`` is the x-z distance between estimate and truth at the instant of
    landing (``landing_dx``, ``landing_dz`` its parts); ``rms_flight``, ``rms_after``
    and ``rms_all`` are RMS x-z distances over the flight, after landing and overall.
    """
    sim = sc["sim"]
    t = sim.t
    truth = sim.truth[["x", "z"]].to_numpy()
    est = sol.trajectory[["x", "z"]].to_numpy()
    est_land = np.array([np.interp(sc["t_landing"], t, est[:, k]) for k in range(2)])
    true_land = sim.position(sc["t_landing"])[0, [0, 2]]
    dist2 = np.sum((est - truth) ** 2, axis=1)
    flight = (t >= sc["t_takeoff"]) & (t <= sc["t_landing"])
    after = t >= sc["t_landing"]
    return {"landing_error": float(np.hypot(*(est_land - true_land))),
            "landing_dx": float(est_land[0] - true_land[0]), "landing_dz": float(est_land[1] - true_land[1]),
            "rms_flight": float(np.sqrt(np.mean(dist2[flight]))),
            "rms_after": float(np.sqrt(np.mean(dist2[after]))), "rms_all": float(np.sqrt(np.mean(dist2)))}


WITHOUT, WITH = "inrun points only", "inrun points + landing hill"


def realisation(rate: float, seed: int, solver: str = "clarabel", attitude: str = "gyro") -> dict:
    """One seeded jump solved with and without the landing-hill line.

    Returns
    -------
    dict
        ``scores`` ({label: :func:`scores`}), ``sequential`` (the loop's report),
        ``error_params`` (DataFrame: truth beside both estimates), ``scenario``,
        ``information``, ``solutions``.
    """
    sc = simulate_jump(rate, seed)
    info = information(sc)
    without, with_line = problems(sc, info, attitude)
    sols = {WITHOUT: without.solve(solver=solver, lam=1.0), WITH: with_line.solve(solver=solver, lam=1.0)}
    e = sc["sim"].accel
    scale = np.asarray(e.scale)[[0, 2]]
    truth_params = {**{f"bias_{a}": float(b) for a, b in zip("xyz", e.bias, strict=True)},
                    **{f"scale_{a}": float(v) for a, v in zip("xz", scale, strict=True)}}
    params = pd.DataFrame({"truth": pd.Series(truth_params), **{k: s.error_params for k, s in sols.items()}})
    return {"scores": {k: scores(sc, s) for k, s in sols.items()},
            "sequential": sols[WITH].stats.get("sequential", {}), "error_params": params, "scenario": sc,
            "information": info, "solutions": sols}


def run(rate: float = 200.0, seeds: int = 8, quiet: bool = False, figures: str | None = None,
        solver: str = "clarabel", attitude: str = "gyro") -> dict:
    """Simulate ``seeds`` jumps (the same jump, different sensor noise) and score both solutions.

    Returns
    -------
    dict
        ``table`` (DataFrame, one row per solution: means over realisations, m),
        ``per_seed`` (long DataFrame), ``ratio`` (mean landing-point error without over
        with the line), ``ratios`` (per realisation), ``sequential`` (one loop report
        per realisation), ``first`` (the first realisation, see :func:`realisation`).
    """
    recs, seq, first = [], [], None
    for seed in range(seeds):
        res = realisation(rate, seed, solver, attitude)
        first = res if first is None else first
        recs += [{"seed": seed, "solution": k, **v} for k, v in res["scores"].items()]
        seq.append(res["sequential"])
    long = pd.DataFrame(recs)
    cols = ["landing_error", "rms_flight", "rms_after", "rms_all"]
    table = long.groupby("solution", sort=False)[cols].mean()
    wide = long.pivot(index="seed", columns="solution", values="landing_error")[[WITHOUT, WITH]]
    ratios = (wide[WITHOUT] / wide[WITH]).to_numpy()
    ratio = float(table.loc[WITHOUT, "landing_error"] / table.loc[WITH, "landing_error"])
    if not quiet:
        sc = first["scenario"]
        print(f"ski jump: {sc['sim'].t.size} samples at {rate:g} Hz ({sc['sim'].t[-1]:.2f} s), take-off "
              f"{sc['t_takeoff']:.2f} s at {sc['v_takeoff']:.1f} m/s, landing {sc['t_landing']:.2f} s at "
              f"x = {sc['x_landing']:.1f} m; sigma_a = {sc['sigma_a']:.3g} m/s^2, lam = 1, attitude from "
              f"{attitude}; means over {seeds} noise realisations")
        print("errors (m): landing point (x-z distance at the instant of landing), RMS over the flight, "
              "after landing and overall")
        print(table.to_string(float_format="{:9.3f}".format))
        print(f"landing-point error without / with the landing-hill line: {ratio:.1f}x (means); per "
              "realisation: " + " ".join(f"{r:.1f}" for r in ratios))
        print("landing-point error per realisation (m):")
        print(wide.to_string(float_format="{:7.3f}".format))
        for k, rep in enumerate(seq):
            print(f"seed {k}: sequential loop {rep['iterations']} iteration(s), converged "
                  f"{rep['converged']}, largest change per iteration (m): "
                  + ", ".join(f"{c:.2g}" for c in rep["max_change"]))
        print("error-model estimates, first realisation (bias m/s^2, scale dimensionless):")
        with pd.option_context("display.float_format", "{:.4g}".format):
            print(first["error_params"].to_string())
    if figures:
        _figure(first["scenario"], first["information"], first["solutions"], Path(figures))
    return {"table": table, "per_seed": long, "ratio": ratio, "ratios": ratios, "sequential": seq,
            "first": first}


def _figure(sc: dict, info: dict, sols: dict, folder: Path) -> None:
    """Hill, true and estimated trajectories and the error against time (``ski_jump.png``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bvpnav.io import atomic_savefig

    folder.mkdir(parents=True, exist_ok=True)
    sim = sc["sim"]
    fig, axes = plt.subplots(2, 1, figsize=(9, 8))
    ax = axes[0]
    ax.plot(sc["inrun"]["x"], sc["inrun"]["z"], "k", lw=3, alpha=0.4, label="inrun")
    ax.plot(info["hill_x"], info["hill_z"], color="0.3", lw=3, alpha=0.4, label="landing hill")
    ax.plot(sim.truth["x"], sim.truth["z"], "k", lw=1, label="truth")
    for label, sol in sols.items():
        ax.plot(sol.position("x"), sol.position("z"), lw=1, label=label)
    ax.plot(info["points"][:, 0], info["points"][:, 2], "o", mfc="none", color="C3", label="inrun points")
    ax.set(xlabel="x (m)", ylabel="z (m)", aspect="equal")
    ax.legend(fontsize=7)
    ax = axes[1]
    truth = sim.truth[["x", "z"]].to_numpy()
    for label, sol in sols.items():
        ax.plot(sol.t, np.linalg.norm(sol.trajectory[["x", "z"]].to_numpy() - truth, axis=1), label=label)
    for tt, what in ((sc["t_takeoff"], "take-off"), (sc["t_landing"], "landing")):
        ax.axvline(tt, color="0.5", lw=0.5)
        ax.text(tt, 0.0, what, fontsize=7, rotation=90, va="bottom")
    ax.set(xlabel="t (s)", ylabel="position error in x-z (m)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    atomic_savefig(fig, folder / "ski_jump.png", dpi=100)
    plt.close(fig)


def main(argv=None) -> dict:
    """Command line: ``--small`` (50 Hz, 4 realisations), ``--rate``, ``--seeds``, ``--solver``,
    ``--true-attitude``, ``--figures DIR`` (default ``$BVPNAV_FIGURES``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--small", action="store_true", help="50 Hz, 4 realisations (quick)")
    ap.add_argument("--rate", type=float, default=200.0, help="sampling rate, Hz (a multiple of 25)")
    ap.add_argument("--seeds", type=int, default=8, help="noise realisations")
    ap.add_argument("--solver", default="clarabel")
    ap.add_argument("--true-attitude", action="store_true", help="use the true attitude, not the gyro's")
    ap.add_argument("--figures", metavar="DIR", default=os.environ.get("BVPNAV_FIGURES"),
                    help="write PNG figures here (default: $BVPNAV_FIGURES, if set)")
    args = ap.parse_args(argv)
    rate, seeds = (50.0, 4) if args.small else (args.rate, args.seeds)
    return run(rate, seeds, figures=args.figures, solver=args.solver,
               attitude="true" if args.true_attitude else "gyro")


if __name__ == "__main__":
    main()
