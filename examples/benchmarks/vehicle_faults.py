"""Vehicle faults (issue 39 items 3-6): lever arm, fix delay, outliers and odometer scale on a simulated car.

A simulated car drive (:func:`bvpnav.scenarios.car_drive`: turns, stops, hills; a strapdown
IMU of the chosen grade with drifting biases and a 5 degree initial heading error) with 1 Hz
GNSS fixes that carry the faults of a real receiver (:func:`bvpnav.scenarios.faulty_fixes`):
the antenna 1 m ahead of the IMU, the fixes stamped 50 ms late, 5 % of them 20-50 m off; and
a 10 Hz odometer (the forward speed at the IMU, 0.05 m/s noise) reading 2 % high. Three solves
per drive, the same IMU error model in each (the node states from the grade's figures, see
below; ``--knots``: the grade's knot model, biases at knots 30 s apart and the initial attitude):

(a) ``clean``: the run without the faults and without their unknowns: the same fix stamps
    and fix noise with the antenna at the IMU and no delay or outliers, soft positions, and
    the odometer without its scale error (calibrated), nothing estimated but the IMU's errors:
    the calibrated view, "B" in the tables;
(b) ``faults``: the faulty fixes as ``Position(..., lever="estimated", delay="estimated",
    gate=5)`` and the odometer with ``LeverArm(sigma=(1, 1, 0.02), prior=(0, 0, tape)) +
    TimeOffset(sigma=0.2) + OdometerScale(sigma=0.05)`` added to the error model: the
    horizontal lever arm unknown (1 m prior sigma about zero), the vertical one from a tape
    measure with a 2 cm error drawn per seed (a car barely rolls or pitches, so GNSS cannot see
    it: its error passes into the height one to one), the delay and the scale unknown;
(c) ``reference``: the estimator of (b) (lever arm, delay and scale estimated with the same
    priors, the gate on) on the fault-free data of (a): the antenna at the IMU (the tape reads
    its own error), no delay, no outliers, the odometer calibrated. "A" in the tables: what
    the faults cost the method, on which issue 39's "RMS within 10 % of a run without the
    faults" is judged; (a) stays as the stricter view (what not knowing the calibration costs).

With ``--explain`` two more solves split the cost of (b): ``known`` (the faulty fixes and
readings with the lever arm, delay and scale given: what the outliers alone cost) and
``calibration`` (lever arm, delay and scale estimated, no outliers, no gate: what the
calibration alone costs).

Printed per drive (grade, fix quality, seed): the lever arm, delay and scale errors with their
standard deviations (``solve(uncertainty=True)``), the outliers caught, missed and the good
fixes rejected, the RMS position error (3-D) of (a), (c) and (b) against the truth at the samples,
the ratios (b)/(c) and (b)/(a), 3-D and horizontal, the reference run's own delay estimate (truth
0) and the wall times; then per grade, fix quality and duration the mean and worst over the seeds
(with the errors in units of their reported standard deviations: an honest estimator is mostly
under 2), and the acceptance of issue 39: lever arm within 5 cm, scale within 0.2 %, delay within
5 ms, every bad fix rejected and no good one, RMS within 10 % of (c).

Measured (2026-12-05, on a shared machine under heavy load, so the wall times say little; the
summary over seeds is in ``docs/guide/strapdown.md``, section "Vehicles"), ``--knots``, 300
s, the drives that finished this session, on the commit before the rebase onto main's merges of
2026-12-05 (B: the calibrated run (a), A: the reference run (c); "(A) ms" is run (c)'s own
delay estimate, truth 0):

tactical::

    seed  lever x, y cm (std)      delay ms (std)  scale % (std)   RMS B, A, faults cm  /A    /B    (A) ms
       0  -2.3 (2.0), 1.5 (1.4)   -1.04 (1.10)    -0.011 (0.008)  2.70 5.36 5.47     1.02  2.03  -0.72 (1.07)
       1  -2.3 (2.1), -1.2 (1.5)  -0.38 (1.10)    +0.008 (0.008)  2.95 4.43 4.12     0.93  1.40  -0.77 (1.07)
       2  2.3 (2.1), -1.9 (1.5)   +2.99 (1.09)    +0.004 (0.008)  2.44 4.17 4.07     0.98  1.67  +3.03 (1.07)
       3  -4.0 (2.0), 2.2 (1.4)   -3.06 (1.09)    +0.019 (0.008)  3.04 4.53 4.67     1.03  1.53  -2.79 (1.07)
       4  4.5 (2.0), -3.7 (1.5)   +0.29 (1.09)    +0.018 (0.008)  2.96 6.22 6.03     0.97  2.03  +0.33 (1.07)

consumer::

    seed  lever x, y cm (std)      delay ms (std)  scale % (std)   RMS B, A, faults cm  /A    /B    (A) ms
       1  5.2 (3.5), 0.3 (1.8)    +1.36 (1.46)    +0.008 (0.009)  4.18 6.13 6.06     0.99  1.45  +0.99 (1.44)
       2  -0.6 (3.4), 0.9 (1.8)   +5.54 (1.46)    +0.007 (0.009)  3.46 8.48 8.00     0.94  2.31  +5.40 (1.44)
       3  -11.4 (3.4), 2.7 (1.8)  -3.48 (1.46)    +0.019 (0.009)  3.83 9.83 9.87     1.00  2.58  -3.24 (1.44)
       4  9.4 (3.5), -3.7 (1.8)   +2.15 (1.46)    +0.020 (0.009)  3.95 8.68 8.93     1.03  2.26  +2.23 (1.44)

Every outlier rejected and no good fix in every drive; the RMS within 10 % of the reference run
(A) in every drive. The calibration errors are the same with and without the faults (the last
column against the delay's): they are the drive's noise, not the faults. On a noise-free drive
(the IMU's turn-on biases and initial attitude error only; consumer, seed 2) the delay comes
out within 0.02 ms and the horizontal lever arm within 0.4 mm, so the method has no bias there.
The errors beyond 2 standard deviations (the delay of tactical seeds 2 and 3 and of consumer
seed 2, +5.54 ms or 3.8 of them; the consumer's forward lever arm on seeds 3 and 4) say that
the reported standard deviations are optimistic on this drive. Traced on consumer seed 2, run
(A) (+5.40 ms, std 1.44), with one noise source switched off at a time in the simulation:
without the gyro's white noise +3.43 ms, without the fix noise +4.36, without the odometer's
+4.35; the gyro's share is the attitude walk that the grade's error model (``walk=False``)
leaves out, so the reported std cannot hold it. With the walk modelled in all three runs
(``--walk``), tactical seeds 2 and 3 give the delay +2.98 (std 1.26) and -2.65 ms (1.26), 2.4
and 2.1 standard deviations (run (A): 2.4 and 1.9), and RMS B, A, faults of 2.25, 3.33, 3.22
and 2.78, 3.94, 4.04 cm (/A 0.97 and 1.03, /B 1.43 and 1.45): part of the excess, not all; the
rows above are without it. Consumer seed 0 was stopped after 7 CPU minutes with this model (it
did not finish in the previous session either; not run again with it since the fix below).

Why consumer seed 0 was slow (profiled 2026-12-05, 670 CPU s of its faults run (b) without
finishing): its raw attitude drifts by radians over the 300 s (the consumer gyro's turn-on bias,
0.005 rad/s; the first attitude step is 5.2 rad and the objective 6.5e8), and in the first gating
pass the outliers are still in. With residuals that large the estimated delay's Gauss-Newton
linearization (the rows take the previous answer's velocity) converges linearly, the position
changes shrinking by 0.82 per iteration, so the sequential loop inside every attitude step and
every evaluation ran into its ``max_iter`` (30); and half of the CPU (324 of 670 s) was an
observability check (an SVD as long as the solve) repeated on every linearized copy. The check is
now made once per loop (the copies have the same items and error model); the linear convergence
stays (an Aitken extrapolation of the linearization point was tried: 0.82 became about 0.63 per
iteration on this drive, but on a simulated delay with 5 m outliers it broke a loop that converges
plainly in 36 iterations, so it was not kept). Smaller, on the 120 s consumer seed 0 drive: the
attitude loop of the first gating pass stalls at steps of 1e-7-1e-4 rad that its objective
(2.5e6, the outliers in) cannot tell apart, rejected and accepted in turn until a damped step
falls below ``tol`` (17-27 iterations, without any delay estimated as well). The faults run of
that 120 s drive took 77 CPU s before the check was made once, 21 after. With the node states
the loop diverged outright: each node-state step iterated the delay's linearization to its
``tol`` (30 iterations, not reached) about an attitude the next step moved, and the steps grew
(objective 6.6e7, 5.8e7, 7.5e7, 3.3e9, 4.6e10; steps 0.85-4.5 rad; stopped after 10 CPU minutes).
The fix (2026-12-05, in the library): the node-state loop's intermediate steps linearize the
delayed fixes once (one Gauss-Newton step on the states and the delay together), and the step
expected to be the last iterates them to ``tol``; the fixed point is the same (a 60 s consumer
drive: the delay to 1e-12 s, ``tests/solve/test_state_loop_linearized_items.py``). Seed 0's
faults run now converges in 14, 10 and 9 steps over its three gating passes (17 CPU s); every
other drive's rows are unchanged to every printed digit.

The node states (the default; ``--knots`` for the knot model): every run's error model is
``grade.error_states()``, i.e. ``ErrorStates(arw=gyro_noise, gyro_drift=gyro_bias_walk,
acc_drift=acc_bias_walk, attitude_sigma=[tilt, tilt, inf], gyro_sigma=gyro_bias,
acc_sigma=acc_bias)`` from the grade's
figures (the model the simulation draws its IMU from: white noise and bias random walks), with
``sigma_a = acc_noise * sqrt(rate)``, per sample (the odometer's and the delayed fixes' rows
fall between the nodes of a 1 s mesh). Measured (2026-12-05, load average 15-16 on 2 cores, on
the commit before the rebase onto main of 03:40 UTC), tactical, 300 s::

    seed  lever x, y cm (std)      delay ms (std)  scale % (std)   RMS B, A, faults cm  /A    /B    (A) ms
       0  0.7 (2.5), 0.6 (1.6)    -0.12 (1.25)    -0.013 (0.009)  2.51 5.59 5.47     0.98  2.18  +0.08 (1.23)
       1  -1.1 (2.5), 1.0 (1.6)   +0.72 (1.25)    +0.008 (0.009)  2.56 3.56 3.72     1.04  1.46  +0.37 (1.23)
       2  2.8 (2.5), -0.8 (1.6)   +3.03 (1.25)    +0.005 (0.009)  2.25 3.38 3.26     0.96  1.45  +2.98 (1.23)
       3  -3.3 (2.5), 1.3 (1.6)   -2.66 (1.25)    +0.020 (0.009)  2.78 3.93 4.04     1.03  1.45  -2.36 (1.23)
       4  3.0 (2.5), -2.3 (1.6)   +0.19 (1.25)    +0.018 (0.009)  2.51 4.39 4.17     0.95  1.66  +0.29 (1.23)

Every criterion met on every seed (against the knot model's rows above: the lever arm 3.5 / 4.1 cm
3-D mean / worst against 4.4 / 5.8, its worst horizontal err/std 1.4 against 2.5, the delay 1.35 /
3.03 ms against 1.55 / 3.06, 2.4 standard deviations at worst against 2.8; RMS faults / (A) 0.95-
1.04 3-D, 0.88-1.12 horizontal; RMS A 13-29 % lower on seeds 1-4, 4 % higher on seed 0); the
delay of seeds 2 and 3 is what ``--walk`` gave, so the node states take up the gyro noise's
attitude walk as that does.
Consumer, 300 s, seeds 0-4 (seed 0 since the fix above; before, it was stopped unfinished after
9.8 CPU minutes, and with the knot model after 11.8; seeds 1-4 as before it, to every digit;
load average 15-16)::

    seed  lever x, y cm (std)      delay ms (std)  scale % (std)   RMS B, A, faults cm  /A    /B    (A) ms
       0  3.4 (4.7), 1.4 (1.8)    +0.92 (1.62)    -0.013 (0.009)  3.41 6.92 6.68     0.97  1.96  +0.92 (1.60)
       1  1.5 (4.7), 0.8 (1.9)    +1.99 (1.62)    +0.007 (0.009)  3.26 3.86 3.99     1.03  1.22  +1.65 (1.60)
       2  -0.9 (4.7), 0.1 (1.8)   +2.89 (1.61)    +0.008 (0.009)  2.81 6.24 5.42     0.87  1.93  +2.83 (1.60)
       3  -4.7 (4.6), 0.4 (1.8)   -2.15 (1.62)    +0.019 (0.009)  3.46 5.28 5.27     1.00  1.53  -1.77 (1.60)
       4  -4.9 (4.7), -2.0 (1.8)  -0.24 (1.62)    +0.018 (0.009)  3.13 6.29 6.11     0.97  1.95  -0.01 (1.60)

Every outlier rejected and no good fix, the scale and the delay within 0.2 % and 5 ms on every
seed (the delay 2.89 ms at worst, 1.8 standard deviations, against the knot model's 5.54 ms and
3.8), RMS faults / (A) 0.87-1.03; the lever arm within 5 cm 3-D on seeds 1 and 2, 5.4, 5.2 and 5.3 cm
on seeds 0, 3 and 4 (horizontal 3.7, 4.7 and 5.3 cm, 0.7, 1.0 and 1.1 of their standard deviations;
seed 0's vertical is the tape's 4.0 cm, a 2-sigma draw; the knot model: 11.4 and 9.4 cm forward on
seeds 3 and 4, 3.4 and 2.7 of its). The forward lever arm's standard deviation, 4.6-4.7
cm after 300 s (the knot model reported 3.4-3.5, too small for its errors), is what limits it: the
drive's information, not the method. Being better on both grades and honest (every error within
2.4 of its standard deviation), the node states are the benchmark's default since 2026-12-05;
``--knots`` gives the grade's knot model of the tables above.

The 600 s drive (2026-12-05, ``--duration 600``; the consumer drives with ``--course``, the course
start whose heading no longer reads the gated fixes' outliers: from the raw-gyro attitude, radians off
after 600 s, consumer seed 2 stopped at a wrong optimum, lever arm 4 m off and RMS 73 m; one run per
drive, load average 2-4; B: the calibrated run (a), A: the reference run (c)):

tactical::

    seed  lever x, y, z cm (std)               delay ms (std)  scale % (std)   RMS B, A, faults cm  /A    /B
       0  -0.2 (1.7), 1.3 (1.1), 4.3 (2.0)     +0.08 (0.86)    +0.001 (0.006)  2.42 4.41 4.62       1.05  1.91
       1  -0.6 (1.7), 0.6 (1.1), -1.4 (2.0)    +0.09 (0.86)    +0.005 (0.006)  2.39 2.78 2.72       0.98  1.14
       2  -1.8 (1.7), -1.1 (1.1), -1.6 (2.0)   -0.70 (0.87)    +0.010 (0.006)  2.50 3.73 3.62       0.97  1.45
       3  -2.8 (1.7), -0.3 (1.1), 1.9 (2.0)    -1.19 (0.86)    +0.018 (0.006)  2.05 2.52 2.77       1.10  1.35
       4  -0.9 (1.7), 1.3 (1.1), -0.1 (2.0)    +0.77 (0.86)    +0.016 (0.006)  2.63 3.35 3.18       0.95  1.21

consumer::

    seed  lever x, y, z cm (std)               delay ms (std)  scale % (std)   RMS B, A, faults cm  /A    /B
       0  -0.1 (3.1), 2.0 (1.2), 4.1 (2.0)     +0.71 (1.14)    -0.001 (0.006)  3.26 4.90 5.22       1.06  1.60
       1  -3.3 (3.1), -0.4 (1.2), -1.5 (2.0)   +0.03 (1.14)    +0.004 (0.006)  3.05 4.78 4.62       0.97  1.51
       2  -1.8 (3.1), -0.7 (1.2), -1.6 (2.0)   -0.79 (1.15)    +0.010 (0.006)  3.46 4.28 4.24       0.99  1.22
       3  -4.0 (3.1), -0.1 (1.2), 1.9 (2.0)    -1.42 (1.15)    +0.018 (0.006)  2.82 3.57 3.91       1.10  1.39
       4  -0.0 (3.1), 2.3 (1.2), 0.0 (2.0)     -0.00 (1.14)    +0.016 (0.006)  3.38 4.02 4.07       1.01  1.20

Every criterion holds on every seed of both grades (the lever arm 4.5 cm at worst, 3-D, of which
the tape's vertical 4.1-4.3 cm; the forward lever arm's standard deviation 1.7 cm tactical, 3.1 cm
consumer). At 300 s the course start gives the default start's answers (consumer seeds 0 and 1,
every printed digit).

Run: ``python examples/benchmarks/vehicle_faults.py [--grade tactical consumer] [--quality ...]
[--duration 300] [--rate 10] [--seeds 0 1 2 3 4] [--explain] [--no-odometer] [--walk] [--knots] [--course]
[--quick] [--json FILE]``; each drive in its own process with ``--json`` and then ``--table FILE ...``
for the tables of them all.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from bvpnav import NavigationProblem
from bvpnav.constraints import Odometer, Position
from bvpnav.error_models import LeverArm, OdometerScale, TimeOffset
from bvpnav.scenarios import CarDrive, FaultyFixes, car_drive, faulty_fixes
from bvpnav.sensors import grade as sensor_grade

#: Fix qualities: name -> (horizontal, vertical) standard deviation, m.
QUALITIES = {"RTK 0.05/0.1 m": (0.05, 0.1), "code 1/2 m": (1.0, 2.0)}
LEVER = (1.0, 0.0, 0.0)      # m, body frame: 1 m ahead of the IMU
DELAY = 0.05                 # s
OUTLIERS = 0.05              # fraction of the fixes
GATE = 5.0                   # normalized residual
INTERVAL = 30.0              # s between bias knots
SCALE = 0.02                 # odometer scale error (reads 2 % high)
ODO_RATE = 10.0              # Hz
ODO_SIGMA = 0.05             # m/s, odometer noise
TAPE = 0.02                  # m, standard deviation of the vertical lever arm's tape measurement
#: Whether both runs have the odometer (``--no-odometer``: neither, and no scale to estimate).
ODOMETER = True
#: Whether every run's error model also has the gyro noise's attitude walk (``--walk``:
#: ``grade.error_model(walk=True)``, the AttitudeWalk the simulated gyro's white noise makes).
WALK = False
#: Whether every run's error model is the node states (``--states``: ``ErrorStates`` from the grade's
#: figures, the attitude error and both bias random walks as states at every sample, the model the
#: simulation draws from) instead of the grade's knot model (``grade.error_model(INTERVAL)``).
STATES = True
#: Whether every run's attitude loop starts from the course (``--course``: ``solve(attitude={"start":
#: "course"})``, the heading the fixes imply, the gated fixes' outliers screened out of it: the start
#: README recommends for a gyro that drifts by more than a few degrees over the drive).
COURSE = False
#: The solves: (a), (b), (c) and the two of ``--explain``.
RUNS = ("clean", "faults", "reference", "known", "calibration")


@dataclass(frozen=True)
class Drive:
    """One simulated drive with everything both runs are given."""

    drive: CarDrive
    fixes: FaultyFixes
    clean_fix: np.ndarray      # (M, 3) m: the fault-free fixes at the same stamps
    odo_t: np.ndarray          # s
    odo_speed: np.ndarray      # m/s: the true forward speed plus the odometer's noise
    tape_z: float              # m: the measured vertical lever arm


def make_drive(grade: str, quality: str, duration: float, rate: float, seed: int) -> Drive:
    """The drive of ``seed``: IMU and fix noise (``seed``), faults (``seed + 1``), odometer noise
    (``seed + 2``) and the tape measurement (``seed + 3``)."""
    drive = car_drive(duration=duration, rate=rate, grade=grade, seed=seed, gnss_sigma=QUALITIES[quality])
    fixes = faulty_fixes(drive, lever=LEVER, delay=DELAY, outliers=OUTLIERS, seed=seed + 1)
    clean_fix = drive.fix_position[np.isin(drive.fix_t, fixes.t)]
    k = np.arange(0, drive.t.size, max(1, int(round(rate / ODO_RATE))))
    forward = np.einsum("kij,ki->kj", drive.attitude.as_matrix()[k], drive.velocity[k])[:, 0]
    noise = ODO_SIGMA * np.random.default_rng(seed + 2).standard_normal(k.size)
    tape = LEVER[2] + TAPE * float(np.random.default_rng(seed + 3).standard_normal())
    return Drive(drive, fixes, clean_fix, drive.t[k], forward + noise, tape)


def extra_information(d: Drive, faults: bool, estimated: bool | None = None) -> tuple[list, list]:
    """Items and error-model components the vehicle adds: ``(items, components)``.

    The odometer: calibrated in the clean run; in the faults run it reads ``1 + SCALE`` times
    the speed and ``OdometerScale(sigma=0.05)`` estimates that (``estimated``, default
    ``faults``: the scale is estimated; the reference run estimates it on the calibrated
    odometer). None with ``ODOMETER`` false.
    """
    if not ODOMETER:
        return [], []
    speed = (1.0 + SCALE) * d.odo_speed if faults else d.odo_speed
    models = [OdometerScale(sigma=0.05)] if (faults if estimated is None else estimated) else []
    return [Odometer(t=d.odo_t, speed=speed, sigma=ODO_SIGMA, name="odometer")], models


def error_model(g, rate: float):
    """The IMU's error model of every run and its ``sigma_a`` (m/s^2): the grade's knot model
    (biases at knots :data:`INTERVAL` s apart, the initial attitude; with :data:`WALK` the
    gyro noise's attitude walk too), or with :data:`STATES` the node states from the same
    figures (the process noise the gyro's angle random walk and both bias walks, the first
    node's priors the turn-on biases and the tilt, the heading open)."""
    if STATES:   # ErrorStates(arw=gyro_noise, ..., attitude_sigma=(tilt, tilt, inf), ...), no knots
        return g.error_states(), g.sigma_a(rate)
    return g.error_model(INTERVAL, walk=WALK), g.sigma_a(rate, INTERVAL)


def solve(d: Drive, which: str = "faults", uncertainty: bool = False):
    """One of :data:`RUNS` (see the module docstring); returns the solution and its wall time, s."""
    drive, fx = d.drive, d.fixes
    g = sensor_grade(drive.params["grade"])
    em, sigma_a = error_model(g, drive.rate)
    sigma = np.tile(drive.fix_sigma, (fx.t.size, 1))
    if which == "clean":
        items, models = extra_information(d, faults=False)
        items.append(Position(t=fx.t, value=d.clean_fix, sigma=sigma, name="gnss"))
    elif which == "known":       # the faulty data, the calibration given
        items, models = extra_information(d, faults=False)
        items.append(Position(t=fx.t, value=fx.position, sigma=sigma, lever=LEVER, delay=DELAY, gate=GATE,
                              name="gnss"))
    elif which in ("faults", "calibration", "reference"):
        items, models = extra_information(d, faults=which != "reference", estimated=True)
        value, gate = {"faults": (fx.position, GATE), "calibration": (fx.clean, None),
                       "reference": (d.clean_fix, GATE)}[which]
        items.append(Position(t=fx.t, value=value, sigma=sigma, lever="estimated", delay="estimated",
                              gate=gate, name="gnss"))
        # the tape measures the antenna's height with the drive's tape error (reference: at the IMU)
        tape = d.tape_z - LEVER[2] if which == "reference" else d.tape_z
        models += [LeverArm(sigma=(1.0, 1.0, TAPE), prior=(0.0, 0.0, tape)), TimeOffset(sigma=0.2)]
    else:
        raise ValueError(f"which={which!r}: one of {RUNS}")
    for m in models:
        em = em + m
    prob = NavigationProblem(drive.data(), error_model=em, sigma_a=sigma_a)
    prob.add(*items)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the gating warning is read from the solution below
        start = {"start": "course"} if COURSE else {}
        sol = prob.solve(solver="direct", attitude={"progress": False, "heading": "given", **start},
                         uncertainty=uncertainty)
    return sol, time.perf_counter() - t0


def rms3(sol, drive: CarDrive, axes: int = 3) -> float:
    """RMS position error at the samples over the first ``axes`` axes (3: 3-D; 2: horizontal), m."""
    e = (sol.position() - drive.position)[:, :axes]
    return float(np.sqrt(np.mean(np.sum(e ** 2, axis=1))))


def run(grade: str, quality: str, duration: float, rate: float, seed: int = 0, explain: bool = False,
        reference: bool = True) -> dict:
    """One drive: the solves and the measures (see the module docstring); ``reference=False``
    leaves out the reference run (c) and what is measured against it (NaN)."""
    d = make_drive(grade, quality, duration, rate, seed)
    drive, fixes = d.drive, d.fixes
    sols, secs = {}, {}
    for which in RUNS if explain else RUNS[:3]:
        if which == "reference" and not reference:
            continue
        sols[which], secs[which] = solve(d, which, uncertainty=which in ("faults", "reference"))
    faults = sols["faults"]
    ep, sd = faults.error_params, faults.error_params_std
    rej = faults.rejected
    got = set() if rej is None or not len(rej) else set(
        np.searchsorted(fixes.t, rej["t"].to_numpy()).tolist())
    bad = set(fixes.bad.tolist())
    out = {"grade": grade, "quality": quality, "duration": duration, "rate": rate, "seed": seed, "walk": WALK,
           "model": "states" if STATES else "knots",
           "fixes": int(fixes.t.size), "bad": len(bad), "caught": len(bad & got),
           "false": sorted(got - bad), "missed": sorted(bad - got), "gating": faults.stats.get("gating", {}),
           "lever": [float(ep[f"lever_{a}"]) for a in "xyz"],
           "lever_std": [float(sd.get(f"lever_{a}", np.nan)) for a in "xyz"], "tape_z": d.tape_z,
           "delay": float(ep["time_offset"]), "delay_std": float(sd.get("time_offset", np.nan)),
           "scale": float(ep.get("odometer_scale", SCALE if ODOMETER else np.nan)),
           "scale_std": float(sd.get("odometer_scale", np.nan)),
           "rms": {k: rms3(s, drive) for k, s in sols.items()},
           "rms_h": {k: rms3(s, drive, 2) for k, s in sols.items()}, "seconds": secs}
    out["rms_clean"], out["rms_faults"] = out["rms"]["clean"], out["rms"]["faults"]
    out["lever_err"] = [e - t for e, t in zip(out["lever"], LEVER, strict=True)]
    out["lever_err_norm"] = float(np.linalg.norm(out["lever_err"]))
    out["delay_err"] = out["delay"] - DELAY
    out["scale_err"] = out["scale"] - SCALE
    # the error the calibration's own errors make at every sample, taken out with the truth's attitude and
    # velocity: r - r_true = v d_delay - C d_lever (the fixes are fitted at t - delay by r + C lever)
    e = faults.position() - drive.position
    e += drive.attitude.apply(np.asarray(out["lever_err"])) - drive.velocity * out["delay_err"]
    out["rms_taken_out"] = float(np.sqrt(np.mean(np.sum(e ** 2, axis=1))))
    out["ratio"] = out["rms_faults"] / out["rms_clean"]
    out["ratio_h"] = out["rms_h"]["faults"] / out["rms_h"]["clean"]
    out["rms_reference"] = out["rms"].get("reference", np.nan)
    out["ratio_ref"] = out["rms_faults"] / out["rms_reference"]
    out["ratio_ref_h"] = out["rms_h"]["faults"] / out["rms_h"].get("reference", np.nan)
    # the estimates' errors in standard deviations (an honest estimator: mostly under 2)
    out["lever_z"] = [e / s for e, s in zip(out["lever_err"], out["lever_std"], strict=True)]
    out["delay_z"] = out["delay_err"] / out["delay_std"]
    out["scale_z"] = out["scale_err"] / out["scale_std"]
    # the reference run's own calibration (the truth there: no lever arm, no delay, a calibrated odometer)
    ref = sols.get("reference")
    rp, rs = (ref.error_params, ref.error_params_std) if ref is not None else (pd.Series(dtype=float), {})
    out["reference_est"] = {"lever_err": [float(rp.get(f"lever_{a}", np.nan)) for a in "xyz"],
                            "lever_std": [float(rs.get(f"lever_{a}", np.nan)) for a in "xyz"],
                            "delay_err": float(rp.get("time_offset", np.nan)),
                            "delay_std": float(rs.get("time_offset", np.nan)),
                            "scale_err": float(rp.get("odometer_scale", np.nan)),
                            "rejected": int(ref.stats.get("gating", {}).get("rejected", 0)) if ref else 0}
    out["pass"] = {"lever 5 cm": out["lever_err_norm"] <= 0.05,
                   "scale 0.2 %": bool(abs(out["scale_err"]) <= 0.002),
                   "delay 5 ms": abs(out["delay_err"]) <= 0.005,
                   "outliers": not out["false"] and not out["missed"],
                   "RMS 10 % (ref.)": bool(out["ratio_ref"] <= 1.10)}
    return out


def print_header() -> None:
    print(f"{'grade':>9} {'fixes':>15} {'seed':>4} {'lever error x, y, z (std) cm':>38} "
          f"{'delay ms (std)':>14} {'scale % (std)':>14} {'caught':>6} {'false':>5} {'RMS clean':>9} "
          f"{'RMS ref.':>9} {'RMS faults':>10} {'/ref.':>6} {'horiz.':>6} {'/clean':>6} {'horiz.':>6} "
          f"{'calib. out':>10} {'ref. delay ms (std)':>19} {'explain: known, calib.':>22} {'time s':>17}")


def print_row(r: dict) -> None:
    """One drive's row of the table (printed as soon as it is measured)."""
    lev = ", ".join(f"{1e2 * v:.1f} ({1e2 * s:.1f})"
                    for v, s in zip(r["lever_err"], r["lever_std"], strict=True))
    delay = f"{1e3 * r['delay_err']:+.2f} ({1e3 * r['delay_std']:.2f})"
    scale = f"{1e2 * r['scale_err']:+.3f} ({1e2 * r['scale_std']:.3f})"
    ref = r["reference_est"]
    ref_delay = f"{1e3 * ref['delay_err']:+.2f} ({1e3 * ref['delay_std']:.2f})"
    rc = r["rms"]["clean"]
    explain = (f"{r['rms']['known'] / rc:.2f}, {r['rms']['calibration'] / rc:.2f}" if "known" in r["rms"]
               else "")
    secs = r["seconds"]
    print(f"{r['grade']:>9} {r['quality']:>15} {r['seed']:>4} {lev:>38} {delay:>14} {scale:>14} "
          f"{r['caught']:>3}/{r['bad']:<2} {len(r['false']):>5} {rc:9.4f} {r['rms_reference']:9.4f} "
          f"{r['rms_faults']:10.4f} {r['ratio_ref']:6.2f} {r['ratio_ref_h']:6.2f} {r['ratio']:6.2f} "
          f"{r['ratio_h']:6.2f} {r['rms_taken_out'] / rc:10.2f} {ref_delay:>19} {explain:>22} "
          f"{secs['clean']:4.0f} +{secs['faults']:5.0f} +{secs.get('reference', np.nan):5.0f}", flush=True)


def summary(results: list[dict]) -> list[dict]:
    """Per grade and fix quality: the mean and worst over the seeds of each measure."""
    out = []
    def key_of(r):
        return r["grade"], r["quality"], r["duration"], r.get("model", "knots")

    for key in dict.fromkeys(key_of(r) for r in results):
        rs = [r for r in results if key_of(r) == key]
        cols = {"lever_cm": [1e2 * r["lever_err_norm"] for r in rs],
                "lever_h_cm": [1e2 * float(np.hypot(*r["lever_err"][:2])) for r in rs],
                "lever_h_std_cm": [1e2 * max(r["lever_std"][:2]) for r in rs],
                "lever_h_z": [max(abs(z) for z in r["lever_z"][:2]) for r in rs],
                "scale_pct": [1e2 * abs(r["scale_err"]) for r in rs],
                "scale_z": [abs(r["scale_z"]) for r in rs],
                "delay_ms": [1e3 * abs(r["delay_err"]) for r in rs],
                "delay_std_ms": [1e3 * r["delay_std"] for r in rs],
                "delay_z": [abs(r["delay_z"]) for r in rs],
                "ref_delay_z": [abs(r["reference_est"]["delay_err"] / r["reference_est"]["delay_std"])
                                for r in rs],
                "ratio_ref": [r["ratio_ref"] for r in rs], "ratio_ref_h": [r["ratio_ref_h"] for r in rs],
                "ratio": [r["ratio"] for r in rs], "ratio_h": [r["ratio_h"] for r in rs]}
        row = {"grade": key[0], "quality": key[1], "model": key[3], "seeds": [r["seed"] for r in rs],
               "caught": sum(r["caught"] for r in rs), "bad": sum(r["bad"] for r in rs),
               "missed": sum(len(r["missed"]) for r in rs), "false": sum(len(r["false"]) for r in rs),
               "duration": rs[0]["duration"], "rate": rs[0]["rate"]}
        for name, v in cols.items():
            row[name] = (float(np.mean(v)), float(np.max(v)))
        out.append(row)
    return out


def print_summary(rows: list[dict]) -> None:
    """The mean and worst over seeds, as a Markdown table (the one in README and the guide)."""
    print("| drive | grade | seeds | lever arm error 3-D, cm | horizontal (std), cm | horizontal, err/std "
          "| scale error, % | delay error (std), ms | delay, err/std | (A)'s delay, err/std "
          "| outliers caught / missed / good rejected | RMS faults / reference (A), 3-D | horizontal "
          "| RMS faults / calibrated (B), 3-D | horizontal |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")

    def mw(s, name, fmt):
        return f"{s[name][0]:{fmt}} / {s[name][1]:{fmt}}"

    for s in rows:
        grade = s["grade"] + (", node states" if s.get("model") == "states" else "")
        print(f"| {s['duration']:g} s | {grade} | {len(s['seeds'])} "
              f"| {mw(s, 'lever_cm', '.1f')} | {mw(s, 'lever_h_cm', '.1f')} ({s['lever_h_std_cm'][0]:.1f}) "
              f"| {mw(s, 'lever_h_z', '.1f')} | {mw(s, 'scale_pct', '.3f')} "
              f"| {mw(s, 'delay_ms', '.2f')} ({s['delay_std_ms'][0]:.2f}) | {mw(s, 'delay_z', '.1f')} "
              f"| {mw(s, 'ref_delay_z', '.1f')} "
              f"| {s['caught']}/{s['bad']} / {s['missed']} / {s['false']} "
              f"| {mw(s, 'ratio_ref', '.2f')} | {mw(s, 'ratio_ref_h', '.2f')} "
              f"| {mw(s, 'ratio', '.2f')} | {mw(s, 'ratio_h', '.2f')} |")
    print("(each cell: mean / worst over the seeds; errors in absolute value, the lever arm's as the "
          "length of its error vector, err/std the larger horizontal component's; std: the mean reported "
          "one)")


def print_table(results: list[dict]) -> None:
    """The table of every drive, the summary over seeds, then the acceptance checks."""
    print_header()
    for r in results:
        print_row(r)
    print()
    print_summary(summary(results))
    print("\nacceptance (issue 39): lever within 5 cm, scale within 0.2 %, delay within 5 ms, every outlier "
          "rejected and no good fix, RMS within 10 % of the reference run (A)")
    for r in results:
        marks = ", ".join(f"{k}: {'yes' if v else 'NO'}" for k, v in r["pass"].items())
        print(f"  {r['grade']:>9} {r['quality']:>15} seed {r['seed']}: {marks}")


def main(argv=None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grade", nargs="+", default=["tactical", "consumer"])
    ap.add_argument("--quality", nargs="+", default=["RTK 0.05/0.1 m"], choices=list(QUALITIES))
    ap.add_argument("--duration", type=float, default=300.0, help="s (default 300: one cycle of the drive)")
    ap.add_argument("--rate", type=float, default=10.0, help="IMU rate, Hz (default 10)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    ap.add_argument("--explain", action="store_true", help="also the 'known' and 'calibration' solves")
    ap.add_argument("--quick", action="store_true", help="120 s at 10 Hz, seed 0")
    ap.add_argument("--no-odometer", action="store_true", help="neither run has the odometer")
    ap.add_argument("--walk", action="store_true",
                    help="the error models also have the gyro noise's attitude walk (AttitudeWalk)")
    ap.add_argument("--knots", action="store_true",
                    help="the grade's knot model (biases at knots INTERVAL s apart) instead of the node "
                         "states (ErrorStates from the grade's figures, the default)")
    ap.add_argument("--course", action="store_true",
                    help="start every run's attitude loop from the course the fixes imply (node states)")
    ap.add_argument("--json", help="also write each drive's measures to this file (JSON lines, appended)")
    ap.add_argument("--table", nargs="+", metavar="JSON",
                    help="print the tables of drives measured earlier (--json files) and solve nothing")
    a = ap.parse_args(argv)
    if a.table:
        results = [json.loads(line) for f in a.table for line in open(f) if line.strip()]
        print_table(results)
        return results
    global ODOMETER, WALK, STATES, COURSE
    ODOMETER = not a.no_odometer
    WALK = a.walk
    STATES = not a.knots
    COURSE = a.course
    if a.quick:
        a.duration, a.rate, a.seeds = 120.0, 10.0, [0]
    print(f"car drive {a.duration:g} s at {a.rate:g} Hz, seeds {a.seeds}; lever {LEVER} m (vertical from "
          f"a tape, sigma {100 * TAPE:g} cm), delay {1e3 * DELAY:g} ms, {100 * OUTLIERS:g} % outliers of "
          f"20-50 m, gate {GATE:g}; odometer {ODO_RATE:g} Hz, {100 * SCALE:g} % scale, noise "
          f"{ODO_SIGMA:g} m/s" + ("; the gyro noise's attitude walk modelled (--walk)" if WALK else "")
          + ("; node states" if STATES else "; the grade's knot model (--knots)"))
    results = []
    print_header()
    for grade in a.grade:
        for quality in a.quality:
            for seed in a.seeds:
                r = run(grade, quality, a.duration, a.rate, seed, explain=a.explain)
                results.append(r)
                print_row(r)
                if a.json:
                    with open(a.json, "a") as f:
                        f.write(json.dumps(r, default=float) + "\n")
    print()
    print_table(results)   # again, with the summary and the acceptance checks
    return results


if __name__ == "__main__":
    main()
