"""GTSAM batch smoother: the peer bvpnav is compared against in the benchmarks.

Used only by the benchmark scripts (``pip install gtsam``, the ``peers`` extra);
never imported by :mod:`bvpnav`.

The graph is the standard loosely coupled GNSS/INS smoother: a navigation state
(pose ``X``, velocity ``V``, IMU bias ``B``) at every node, one
``CombinedImuFactor`` (IMU preintegration with a bias random walk) between
consecutive nodes, a ``GPSFactor`` at every fix, priors at the first node, solved
in batch by Levenberg-Marquardt.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from typing import Any

import gtsam
import numpy as np
from gtsam.symbol_shorthand import B, V, X
from scipy.spatial.transform import Rotation

__all__ = ["gtsam_smoother"]

STANDARD_GRAVITY = 9.80665
GRADE_KEYS = ("acc_noise", "acc_bias", "acc_bias_walk", "gyro_noise", "gyro_bias", "gyro_bias_walk",
              "tilt")


def _grade(grade: Any) -> dict[str, float]:
    """The grade as a dict of floats (accepts a dict or a ``SensorGrade`` dataclass)."""
    if dataclasses.is_dataclass(grade) and not isinstance(grade, type):
        grade = dataclasses.asdict(grade)
    if not isinstance(grade, Mapping):
        raise TypeError("grade: pass a dict (or SensorGrade) with keys " + ", ".join(GRADE_KEYS))
    missing = [k for k in GRADE_KEYS if k not in grade]
    if missing:
        raise KeyError(f"grade: missing {missing}")
    out = {k: float(grade[k]) for k in GRADE_KEYS}
    h = grade.get("heading")
    out["heading"] = np.pi if h is None or not np.isfinite(float(h)) else float(h)
    return out


def _node_times(t: np.ndarray, extra: list[np.ndarray], node_interval: float) -> np.ndarray:
    """Sorted union of the regular grid and the extra times, near-duplicates merged (s)."""
    t0, t1 = float(t[0]), float(t[-1])
    span = t1 - t0
    n = max(1, int(np.ceil(span / node_interval - 1e-9)))
    grid = np.linspace(t0, t1, n + 1)
    allt = np.sort(np.concatenate([grid, *extra]))
    tol = 1e-9 * max(1.0, abs(t0), abs(t1))
    keep = np.concatenate([[True], np.diff(allt) > tol])
    return allt[keep]


def _substeps(t: np.ndarray, f: np.ndarray, w: np.ndarray, nodes: np.ndarray):
    """IMU steps split at the node times.

    Returns the step lengths (s), the specific force (m/s^2) and rate (rad/s) to feed
    GTSAM for each step, and the index of the node interval each step belongs to.
    """
    tol = 1e-9 * max(1.0, abs(t[0]), abs(t[-1]))
    inner = nodes[(nodes > t[0] + tol) & (nodes < t[-1] - tol)]
    # node times that are not (close to) sample times split a step
    j = np.searchsorted(t, inner)
    near = np.minimum(np.abs(t[np.clip(j, 0, t.size - 1)] - inner),
                      np.abs(t[np.clip(j - 1, 0, t.size - 1)] - inner)) <= tol
    tt = np.union1d(t, inner[~near])
    ff = np.column_stack([np.interp(tt, t, f[:, k]) for k in range(3)])
    ww = np.column_stack([np.interp(tt, t, w[:, k]) for k in range(3)])
    dt = np.diff(tt)
    fm = 0.5 * (ff[:-1] + ff[1:])
    wm = 0.5 * (ww[:-1] + ww[1:])
    # GTSAM applies the start-of-step rotation to the whole step's specific force; rotating
    # the mid-step force back by half the step's rotation makes the scheme second order.
    fm = Rotation.from_rotvec(0.5 * wm * dt[:, None]).apply(fm)
    mid = 0.5 * (tt[:-1] + tt[1:])
    seg = np.searchsorted(nodes, mid) - 1
    return dt, fm, wm, seg


def _imu_factors(params, zero_bias, nn, dt, fm, wm, seg):
    """CombinedImuFactors between consecutive nodes and the preintegrated rotations."""
    bounds = np.append(np.searchsorted(seg, np.arange(nn)), seg.size)  # first step per interval
    imu, drot = [], []
    for i in range(nn - 1):
        pim = gtsam.PreintegratedCombinedMeasurements(params, zero_bias)
        for s in range(bounds[i], bounds[i + 1]):
            pim.integrateMeasurement(fm[s], wm[s], dt[s])
        imu.append(gtsam.CombinedImuFactor(X(i), V(i), X(i + 1), V(i + 1), B(i), B(i + 1), pim))
        drot.append(pim.deltaRij())
    return imu, drot


def _params(gravity_z: float, gr: dict[str, float], scale: float = 1.0):
    """Preintegration parameters, the IMU white-noise sigmas multiplied by ``scale``."""
    params = gtsam.PreintegrationCombinedParams.MakeSharedU(gravity_z)
    eye = np.eye(3)
    params.setAccelerometerCovariance((scale * gr["acc_noise"]) ** 2 * eye)
    params.setGyroscopeCovariance((scale * gr["gyro_noise"]) ** 2 * eye)
    params.setIntegrationCovariance(1e-8 * eye)
    params.setBiasAccCovariance(max(gr["acc_bias_walk"], 1e-12) ** 2 * eye)
    params.setBiasOmegaCovariance(max(gr["gyro_bias_walk"], 1e-12) ** 2 * eye)
    return params


def _priors(r0, pos0, vel0, gr, velocity_prior):
    """Prior factors at the first node: attitude (tilt, heading), velocity, bias."""
    cov_nav = np.diag([gr["tilt"] ** 2, gr["tilt"] ** 2, gr["heading"] ** 2])
    # Pose3 tangent is body-frame (R exp(xi)): rotate the nav-frame covariance into the body.
    # A Pose3 prior (a Rot3 prior cannot sit on a Pose3 key) with the translation left free
    # (1e4 m): the fixes, each at its own node, anchor the position.
    cov6 = np.zeros((6, 6))
    cov6[:3, :3] = r0.T @ cov_nav @ r0
    cov6[3:, 3:] = 1e8 * np.eye(3)
    out = [gtsam.PriorFactorPose3(X(0), gtsam.Pose3(gtsam.Rot3(r0), pos0),
                                  gtsam.noiseModel.Gaussian.Covariance(cov6))]
    if velocity_prior is None:
        v_val, v_sig = vel0, np.full(3, 10.0)
    else:
        v_val = np.asarray(velocity_prior[0], dtype=float).reshape(3)
        v_sig = np.broadcast_to(np.asarray(velocity_prior[1], dtype=float), (3,)).copy()
    out.append(gtsam.PriorFactorVector(V(0), v_val, gtsam.noiseModel.Diagonal.Sigmas(v_sig)))
    b_sig = np.array([gr["acc_bias"]] * 3 + [gr["gyro_bias"]] * 3)
    zero = gtsam.imuBias.ConstantBias(np.zeros(3), np.zeros(3))
    out.append(gtsam.PriorFactorConstantBias(B(0), zero, gtsam.noiseModel.Diagonal.Sigmas(b_sig)))
    return out


def gtsam_smoother(
    t,
    specific_force,
    gyro,
    gravity,
    fix_t,
    fix_position,
    fix_sigma,
    initial_attitude: Rotation,
    grade: Mapping[str, Any] | Any,
    eval_t,
    *,
    node_interval: float = 1.0,
    velocity_prior: tuple[Any, Any] | None = None,
    max_iterations: int = 300,
    relative_tol: float = 1e-8,
    heading_starts: int = 1,
    anneal: tuple[float, ...] = (),
) -> dict[str, Any]:
    """Batch factor-graph smoother (GTSAM IMU preintegration + GNSS fixes, LM).

    Parameters
    ----------
    t : array_like, shape (N,)
        IMU sample times, s (increasing).
    specific_force : array_like, shape (N, 3)
        Accelerometer output, body frame, m/s^2 (``f = C^T (a - g)``).
    gyro : array_like, shape (N, 3)
        Body angular rates relative to the navigation frame, rad/s (Earth rate neglected).
    gravity : array_like, shape (3,)
        Gravity in the navigation frame, m/s^2; must be ``(0, 0, -g)`` (ENU, z up).
    fix_t : array_like, shape (M,)
        GNSS fix times, s, inside ``[t[0], t[-1]]``.
    fix_position : array_like, shape (M, 3)
        Fix positions in the navigation frame, m.
    fix_sigma : array_like, shape (3,) or float
        Standard deviation of a fix per navigation axis, m.
    initial_attitude : scipy.spatial.transform.Rotation
        Rough body-to-navigation attitude at ``t[0]`` (the guess bvpnav gets too).
    grade : dict or SensorGrade
        ``acc_noise`` (m/s^2/sqrt(Hz)), ``acc_bias`` (m/s^2), ``acc_bias_walk``
        (m/s^2/sqrt(s)), ``gyro_noise`` (rad/s/sqrt(Hz)), ``gyro_bias`` (rad/s),
        ``gyro_bias_walk`` (rad/s/sqrt(s)), ``tilt`` (rad), optional ``heading``
        (rad; None or absent = unknown, a prior of pi).
    eval_t : array_like, shape (K,)
        Times where the result is wanted, s, inside ``[t[0], t[-1]]``; each becomes a node.
    node_interval : float
        Largest spacing of the nodes, s (nodes also at every fix and every ``eval_t``).
    velocity_prior : (value, sigma), optional
        Prior on the velocity at ``t[0]``: value (3,) m/s and sigma (float or (3,)) m/s.
        Default: the first fixes' finite difference with sigma 10 m/s.
    max_iterations : int
        Levenberg-Marquardt iteration limit (per solve). With 60 s between fixes LM
        from the fix-interpolated start can reach it before converging: compare the
        returned ``iterations`` with it, and raise it (about 300) or use ``anneal``.
    relative_tol : float
        Levenberg-Marquardt relative decrease of the error at which to stop.
    heading_starts : int
        Number of initial headings tried (multi-start for an unknown heading): the
        given one and the given one rotated about the navigation z by ``2 pi k / n``;
        the solution with the lowest final graph error is returned. Default 1 (only
        the given start; LM then converges from heading errors up to about 1 rad).
    anneal : sequence of float
        Continuation for long gaps between fixes: solve first with the IMU noise
        sigmas multiplied by each factor in turn (e.g. ``(100, 10)``), each solution the
        start of the next, then with the stated noise. Default none: one solve from the
        fix-interpolated start (which can need many LM iterations at 60 s gaps).

    Returns
    -------
    dict
        ``position`` (K, 3) m and ``velocity`` (K, 3) m/s in the navigation frame,
        ``gyro_bias`` (K, 3) rad/s and ``acc_bias`` (K, 3) m/s^2 (body), ``attitude``
        (scipy Rotation of length K, body to navigation), ``seconds`` (wall time of
        building and solving, s), ``iterations`` (LM iterations), ``error`` (final
        graph error, 0.5 * sum of squared whitened residuals), ``initial_error``,
        ``nodes`` (number of nodes), ``start_attitude`` (the initial attitude of the
        winning start). ``iterations`` sums the LM iterations of the winning start's
        solves (all annealing stages); ``seconds`` covers all starts.

    Notes
    -----
    GTSAM's conventions: bias ``ConstantBias(acc, gyro)`` (measured = true + bias);
    ``Pose3``/``Rot3`` tangent perturbations are in the body frame, so the nav-frame
    attitude prior (tilt, tilt, heading) is rotated into the body frame,
    ``Sigma_b = R0^T Sigma_n R0``; a ``GPSFactor`` constrains the pose's translation
    in the navigation frame. Noise densities enter as continuous covariances
    (``density^2 I``, GTSAM divides by the step), bias random walks likewise
    (``walk^2 I`` per second). Preintegration is linearised at zero bias (the initial
    estimate); GTSAM corrects the bias to first order.

    Each IMU step is fed with the mean of its two samples (the force rotated back by
    half the step's rotation), so the scheme is second order; a node that falls between
    samples splits the step, with the samples interpolated linearly.

    Initial values: positions interpolated linearly between the fixes (held constant
    beyond them), velocities from their differences, attitudes by integrating the gyro
    from ``initial_attitude`` (the preintegrated rotations chained node to node, the
    same scheme as ``bvpnav.attitude.integrate_gyro`` to second order), biases zero.
    """
    start = time.perf_counter()
    t = np.asarray(t, dtype=float)
    f = np.asarray(specific_force, dtype=float)
    w = np.asarray(gyro, dtype=float)
    g = np.asarray(gravity, dtype=float)
    fix_t = np.asarray(fix_t, dtype=float)
    fix_p = np.asarray(fix_position, dtype=float).reshape(-1, 3)
    sig = np.broadcast_to(np.asarray(fix_sigma, dtype=float), (3,)).copy()
    eval_t = np.atleast_1d(np.asarray(eval_t, dtype=float))
    gr = _grade(grade)
    _check(t, f, w, g, fix_t, fix_p, eval_t)
    order = np.argsort(fix_t)
    fix_t, fix_p = fix_t[order], fix_p[order]

    nodes = _node_times(t, [np.clip(fix_t, t[0], t[-1]), np.clip(eval_t, t[0], t[-1])], node_interval)
    nn = nodes.size

    def node_of(times: np.ndarray) -> np.ndarray:
        k = np.clip(np.searchsorted(nodes, times), 1, nn - 1)
        return np.where(np.abs(nodes[k - 1] - times) < np.abs(nodes[k] - times), k - 1, k)

    zero_bias = gtsam.imuBias.ConstantBias(np.zeros(3), np.zeros(3))
    steps = _substeps(t, f, w, nodes)
    gps_noise = gtsam.noiseModel.Diagonal.Sigmas(sig)
    fixed = gtsam.NonlinearFactorGraph()  # everything but the IMU factors
    for k, p in zip(node_of(fix_t), fix_p, strict=True):
        fixed.add(gtsam.GPSFactor(X(int(k)), p, gps_noise))

    # initial positions and velocities from the fixes
    pos0 = np.column_stack([np.interp(nodes, fix_t, fix_p[:, k]) for k in range(3)])
    slope = np.diff(fix_p, axis=0) / np.maximum(np.diff(fix_t), 1e-9)[:, None]
    vel0 = slope[np.clip(np.searchsorted(fix_t, nodes, side="right") - 1, 0, fix_t.size - 2)]
    for fac in _priors(initial_attitude.as_matrix(), pos0[0], vel0[0], gr, velocity_prior):
        fixed.add(fac)

    graphs = []  # (graph) per annealing stage, the stated noise last
    drot = None
    for scale in [*anneal, 1.0]:
        imu, drot = _imu_factors(_params(float(-g[2]), gr, scale), zero_bias, nn, *steps)
        graph = gtsam.NonlinearFactorGraph(fixed)
        for fac in imu:
            graph.add(fac)
        graphs.append(graph)
    att = [gtsam.Rot3(initial_attitude.as_matrix())]  # gyro-integrated attitude per node
    for r in drot:
        att.append(att[-1].compose(r))
    att_nodes = Rotation.from_matrix(np.array([r.matrix() for r in att]))

    lm = gtsam.LevenbergMarquardtParams()
    lm.setMaxIterations(int(max_iterations))
    lm.setRelativeErrorTol(float(relative_tol))
    lm.setAbsoluteErrorTol(0.0)
    n_starts = max(1, int(heading_starts))
    best = None
    for k in range(n_starts):
        turn = Rotation.from_rotvec([0.0, 0.0, 2 * np.pi * k / n_starts])
        q = (turn * att_nodes).as_quat()  # x, y, z, w; a heading change rotates the whole path
        values = gtsam.Values()
        for i in range(nn):
            rot = gtsam.Rot3.Quaternion(q[i, 3], q[i, 0], q[i, 1], q[i, 2])
            values.insert(X(i), gtsam.Pose3(rot, pos0[i]))
            values.insert(V(i), vel0[i])
            values.insert(B(i), zero_bias)
        initial_error = float(graphs[-1].error(values))
        iterations = 0
        for graph in graphs:
            opt = gtsam.LevenbergMarquardtOptimizer(graph, values, lm)
            values = opt.optimize()
            iterations += int(opt.iterations())
        err = float(graphs[-1].error(values))
        if best is None or err < best[0]:
            best = (err, values, iterations, initial_error, turn * initial_attitude)
    final_error, result, iterations, initial_error, start_attitude = best

    ke = node_of(eval_t)
    pose = [result.atPose3(X(int(k))) for k in ke]
    bias = [result.atConstantBias(B(int(k))) for k in ke]
    return {
        "position": np.array([p.translation() for p in pose]).reshape(-1, 3),
        "velocity": np.array([result.atVector(V(int(k))) for k in ke]).reshape(-1, 3),
        "gyro_bias": np.array([b.gyroscope() for b in bias]).reshape(-1, 3),
        "acc_bias": np.array([b.accelerometer() for b in bias]).reshape(-1, 3),
        "attitude": Rotation.from_matrix(np.array([p.rotation().matrix() for p in pose])),
        "iterations": iterations,
        "error": final_error,
        "initial_error": initial_error,
        "nodes": int(nn),
        "start_attitude": start_attitude,
        "seconds": time.perf_counter() - start,
    }


def _check(t, f, w, g, fix_t, fix_p, eval_t) -> None:
    """Shapes and ranges of the inputs (raises ValueError)."""
    if f.shape != (t.size, 3) or w.shape != (t.size, 3):
        raise ValueError("specific_force and gyro: expected shape (N, 3)")
    if g.shape != (3,) or abs(g[0]) + abs(g[1]) > 1e-9 * abs(g[2]) or g[2] >= 0:
        raise ValueError("gravity: GTSAM's MakeSharedU needs (0, 0, -g) (z up)")
    if fix_p.shape[0] != fix_t.size or fix_t.size < 2:
        raise ValueError("fix_t / fix_position: need at least 2 fixes, one position per time")
    tol = 1e-9 * max(1.0, abs(t[0]), abs(t[-1]))
    for name, tt in (("fix_t", fix_t), ("eval_t", eval_t)):
        if tt.min() < t[0] - tol or tt.max() > t[-1] + tol:
            raise ValueError(f"{name}: times outside the IMU record [{t[0]}, {t[-1]}] s")
