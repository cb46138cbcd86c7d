r"""How good is a trajectory against a reference: absolute and relative trajectory error.

The figures robotics and navigation papers report, computed the way ``evo`` computes them
(``evo_ape`` / ``evo_rpe``, translation part), so that a bvpnav trajectory and any other
estimator's can be scored side by side, and with the alignment a foot-mounted or vehicle
study usually states (a rigid fit about the vertical axis).

- :func:`read_trajectory` reads a TUM file (``t x y z qx qy qz qw``), bvpnav's trajectory
  table (``t, x, y[, z], ...``) or a truth table (``t, x, y[, z]``: 2-D motion-capture
  truth is common), CSV or Parquet; :func:`write_tum` writes one (from a
  :class:`Trajectory` or a :class:`~bvpnav.Solution`).
- :func:`associate` pairs the two trajectories' samples in time (nearest within a
  tolerance, as ``evo``; or the estimate interpolated at the reference's times).
- :func:`align` fits the estimate onto the reference: ``"none"``, ``"translation"``,
  ``"yaw"`` (rotation about the vertical axis and a translation: the rigid 2-D fit),
  ``"rigid"`` (SE(3), Umeyama), ``"similarity"`` (Sim(3), Umeyama with scale) or
  ``"scale"`` (scale only, about the origin, as ``evo --correct_scale`` alone).
- :func:`ape` and :func:`rpe` give an :class:`ErrorResult` with ``evo``'s statistics
  (rmse, mean, median, std, min, max, sse) and the per-axis, horizontal and vertical RMS.

Examples
--------
>>> import numpy as np
>>> from bvpnav.evaluate import Trajectory, ape
>>> t = np.arange(5.0)
>>> ref = Trajectory(t, np.column_stack([t, 0 * t, 0 * t]))
>>> est = Trajectory(t, ref.xyz + [1.0, 2.0, 0.0])
>>> round(ape(est, ref, align="none").rmse, 6), round(ape(est, ref, align="translation").rmse, 6)
(2.236068, 0.0)
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InputError

__all__ = ["Trajectory", "ErrorResult", "Alignment", "ALIGNMENTS", "read_trajectory", "write_tum",
           "associate", "align", "ape", "rpe", "plot", "evaluate", "format_result"]

#: Alignments :func:`align` knows, with what each fits.
ALIGNMENTS = {
    "none": "no alignment",
    "translation": "a translation (least squares: the mean offset)",
    "yaw": "a rotation about the vertical (z) axis and a translation (the rigid 2-D fit)",
    "rigid": "a rotation and a translation, SE(3) (Umeyama)",
    "similarity": "a rotation, a translation and a scale, Sim(3) (Umeyama)",
    "scale": "a scale about the origin only (evo's --correct_scale without --align)",
}

#: First line :func:`write_tum` writes when the orientation was not estimated: the
#: quaternions below it are identity placeholders, and :func:`read_trajectory` ignores them.
NO_ORIENTATION = "# bvpnav: orientation not estimated (identity quaternions)"


@dataclass(frozen=True)
class Trajectory:
    r"""Positions over time, with orientations where known.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times, s, strictly increasing.
    xyz : array_like, shape (n, d)
        Positions, m; d = 2 (x, y) or 3 (x, y, z).
    orientation : scipy.spatial.transform.Rotation, optional
        Body-to-world rotation per sample (n rotations), or None.
    name : str
        What the trajectory is called in tables and plots.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory
    >>> Trajectory([0.0, 1.0], [[0.0, 0.0], [1.0, 0.5]]).dims
    2
    """

    t: np.ndarray
    xyz: np.ndarray
    orientation: Any = None
    name: str = "trajectory"

    def __post_init__(self) -> None:
        t = np.array(self.t, dtype=float).reshape(-1)
        xyz = np.array(self.xyz, dtype=float)
        if xyz.ndim == 1:
            xyz = xyz[:, None]
        where = f"trajectory {self.name!r}"
        if xyz.shape[0] != t.size or xyz.shape[1] not in (2, 3):
            raise InputError(f"{where}: positions of shape {xyz.shape} for {t.size} times; give (n, 2) or "
                             "(n, 3) positions, one row per time")
        if t.size < 2:
            raise InputError(f"{where}: {t.size} sample(s); an evaluation needs at least 2")
        bad = ~(np.isfinite(t) & np.all(np.isfinite(xyz), axis=1))
        if bad.any():
            raise InputError(f"{where}: sample {int(np.argmax(bad))} (t = {t[np.argmax(bad)]!r}) is not "
                             f"finite ({int(bad.sum())} such rows); remove or fill them first")
        if np.any(np.diff(t) <= 0):
            k = int(np.argmax(np.diff(t) <= 0))
            raise InputError(f"{where}: times must increase; sample {k + 1} (t = {t[k + 1]:.9g} s) does not "
                             f"come after sample {k} (t = {t[k]:.9g} s)")
        if self.orientation is not None and len(self.orientation) != t.size:
            raise InputError(f"{where}: {len(self.orientation)} orientations for {t.size} times")
        t.flags.writeable = False
        xyz.flags.writeable = False
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "xyz", xyz)

    @property
    def dims(self) -> int:
        """Number of position axes (2 or 3)."""
        return int(self.xyz.shape[1])

    def __len__(self) -> int:
        return int(self.t.size)

    def take(self, idx) -> Trajectory:
        """The samples at the indices ``idx`` (a new trajectory)."""
        ori = None if self.orientation is None else self.orientation[np.asarray(idx)]
        return Trajectory(self.t[idx], self.xyz[idx], ori, self.name)

    @classmethod
    def from_solution(cls, solution, name: str = "bvpnav") -> Trajectory:
        """The positions (and attitude, for strapdown data) of a :class:`~bvpnav.Solution`."""
        pos = solution.position()
        if pos.ndim == 1 or pos.shape[1] == 1:
            raise InputError("a trajectory evaluation needs 2 or 3 position axes; this solution has 1. "
                             "Compare 1-axis solutions with Solution.rms_error(truth)")
        return cls(solution.t, pos, getattr(solution, "attitude", None), name)


@dataclass(frozen=True)
class Alignment:
    r"""The fitted map from the estimate onto the reference: :math:`p' = s R p + t`.

    Attributes
    ----------
    method : str
        One of :data:`ALIGNMENTS`.
    rotation : ndarray, shape (d, d)
        R (orthogonal, det +1).
    translation : ndarray, shape (d,)
        t, m.
    scale : float
        s (1 unless fitted).

    Examples
    --------
    An estimate turned by -90 degrees about z and moved 5 m along x:

    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory
    >>> t = np.arange(0.0, 6.0)
    >>> ref = Trajectory(t, np.column_stack([t, 0 * t, 0 * t]))  # 1 m/s along x
    >>> from bvpnav.evaluate import align
    >>> turn = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    >>> est = Trajectory(t, ref.xyz @ turn.T + [5.0, 0.0, 0.0])
    >>> fit = align(est, ref, "yaw")
    >>> round(fit.yaw_deg, 6), fit.scale
    (90.0, 1.0)
    >>> bool(np.abs(fit.apply(est).xyz - ref.xyz).max() < 1e-12)
    True
    """

    method: str
    rotation: np.ndarray
    translation: np.ndarray
    scale: float = 1.0

    def apply(self, traj: Trajectory) -> Trajectory:
        """``traj`` mapped by this alignment (positions and orientations)."""
        xyz = self.scale * traj.xyz @ self.rotation.T + self.translation
        ori = traj.orientation
        if ori is not None and traj.dims == 3:
            from scipy.spatial.transform import Rotation

            ori = Rotation.from_matrix(self.rotation) * ori
        return Trajectory(traj.t, xyz, ori, traj.name)

    @property
    def yaw_deg(self) -> float:
        """The rotation's angle about the vertical axis, degrees."""
        return float(np.degrees(np.arctan2(self.rotation[1, 0], self.rotation[0, 0])))


@dataclass
class ErrorResult:
    r"""Errors of an estimate against a reference, with ``evo``'s statistics.

    Attributes
    ----------
    kind : str
        ``"ape"`` (absolute) or ``"rpe"`` (relative).
    t : ndarray, shape (m,)
        Time of each error, s (the reference's; for RPE the second of the pair).
    error : ndarray, shape (m,)
        Error norm per pose (APE) or per pair (RPE), m.
    vector : ndarray, shape (m, d)
        Error vectors (estimate minus reference), m.
    alignment : Alignment
        The alignment applied before the errors were taken.
    pairs : ndarray, shape (m, 2) or None
        Index pairs into the associated samples (RPE).
    settings : dict
        What was asked: alignment, association tolerance, delta and its unit, ...

    Examples
    --------
    An estimate that reads distances 10 % long: its relative error over every metre is 0.1 m:

    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory
    >>> t = np.arange(0.0, 6.0)
    >>> ref = Trajectory(t, np.column_stack([t, 0 * t, 0 * t]))  # 1 m/s along x
    >>> from bvpnav.evaluate import rpe
    >>> res = rpe(Trajectory(t, 1.1 * ref.xyz), ref, delta=1.0)
    >>> res.kind, len(res.error), round(res.rmse, 6)
    ('rpe', 5, 0.1)
    >>> stats = res.stats()
    >>> stats["count"], round(stats["rms_x"], 6), round(stats["rms_y"], 6)
    (5, 0.1, 0.0)
    """

    kind: str
    t: np.ndarray
    error: np.ndarray
    vector: np.ndarray
    alignment: Alignment
    pairs: np.ndarray | None = None
    settings: dict = field(default_factory=dict)
    estimate: Trajectory | None = None
    reference: Trajectory | None = None

    @property
    def rmse(self) -> float:
        """Root mean square of :attr:`error`, m."""
        return float(np.sqrt(np.mean(self.error ** 2)))

    def stats(self) -> dict[str, float]:
        """rmse, mean, median, std, min, max, sse (m; sse m^2), as ``evo`` reports them, and the
        RMS per axis (``rms_x`` ...), horizontal (``rms_horizontal``: x and y) and vertical
        (``rms_vertical``, 3-D only)."""
        e = self.error
        out = {"rmse": self.rmse, "mean": float(np.mean(e)), "median": float(np.median(e)),
               "std": float(np.std(e)), "min": float(np.min(e)), "max": float(np.max(e)),
               "sse": float(np.sum(e ** 2)), "count": int(e.size)}
        v = self.vector
        for j, ax in enumerate("xyz"[: v.shape[1]]):
            out[f"rms_{ax}"] = float(np.sqrt(np.mean(v[:, j] ** 2)))
        out["rms_horizontal"] = float(np.sqrt(np.mean(np.sum(v[:, :2] ** 2, axis=1))))
        if v.shape[1] == 3:
            out["rms_vertical"] = out["rms_z"]
        return out


# ------------------------------------------------------------------ files
def _read_tum(path: Path) -> Trajectory:
    from scipy.spatial.transform import Rotation

    text = path.read_text(encoding="utf-8", errors="replace")
    lines = text.splitlines()
    no_orientation = bool(lines) and lines[0].strip() == NO_ORIENTATION
    rows = []
    for k, line in enumerate(lines, start=1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        parts = s.split()
        if len(parts) != 8:
            raise InputError(f"{str(path)!r} line {k}: {len(parts)} entries; a TUM trajectory line is "
                             "'timestamp tx ty tz qx qy qz qw' (8 numbers separated by spaces)")
        try:
            rows.append([float(p) for p in parts])
        except ValueError:
            raise InputError(f"{str(path)!r} line {k}: not a number in {s!r}; a TUM line holds 8 "
                             "numbers") from None
    if not rows:
        raise InputError(f"{str(path)!r}: no trajectory lines (a TUM file holds 'timestamp tx ty tz qx qy "
                         "qz qw' lines)")
    m = np.array(rows)
    ori = None
    if not no_orientation:
        q = m[:, 4:8]
        norms = np.linalg.norm(q, axis=1)
        if np.any(~np.isfinite(norms)) or np.any(np.abs(norms - 1.0) > 1e-3):
            k = int(np.argmax(~np.isfinite(norms) | (np.abs(norms - 1.0) > 1e-3)))
            raise InputError(f"{str(path)!r}: the quaternion of pose {k} (t = {m[k, 0]:.9g} s) has norm "
                             f"{norms[k]:.6g}, not 1; a TUM file holds unit quaternions qx qy qz qw")
        ori = Rotation.from_quat(q)  # scalar last, as TUM
    return Trajectory(m[:, 0], m[:, 1:4], ori, path.stem)


def _read_table(path: Path, name: str) -> Trajectory:
    import pandas as pd

    if path.suffix.lower() in (".parquet", ".pq"):
        from .io import parquet_frame

        df = parquet_frame(path)
    else:
        df = pd.read_csv(path)
    if "t" not in df.columns:
        raise InputError(f"{str(path)!r}: no column 't' (s); it has {list(df.columns)}. A trajectory table "
                         "has t and positions x, y[, z] (m), like bvpnav's --out or a truth.csv")
    axes = [a for a in ("x", "y", "z") if a in df.columns]
    if axes not in (["x", "y"], ["x", "y", "z"]):
        raise InputError(f"{str(path)!r}: position columns {axes}; a trajectory table has x, y (2-D) or "
                         f"x, y, z (m). It has {list(df.columns)}")
    try:
        t = df["t"].to_numpy(dtype=float)
        xyz = df[axes].to_numpy(dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{str(path)!r}: t or a position column holds text; give numbers (s, m)") from None
    ori = None
    quat = ["qx", "qy", "qz", "qw"]
    if all(c in df.columns for c in quat):
        from scipy.spatial.transform import Rotation

        ori = Rotation.from_quat(df[quat].to_numpy(dtype=float))
    return Trajectory(t, xyz, ori, name)


def read_trajectory(path: str | os.PathLike, name: str | None = None) -> Trajectory:
    r"""Read a trajectory: TUM (``.tum``, or ``.txt`` with 8 numbers a line) or a table.

    Parameters
    ----------
    path : str or path-like
        A TUM file (``timestamp tx ty tz qx qy qz qw``; times s, positions m) or a CSV /
        Parquet table with ``t`` (s) and ``x, y`` or ``x, y, z`` (m), optionally ``qx, qy,
        qz, qw`` (body to world): bvpnav's trajectory output and ``truth.csv`` are such tables.
    name : str, optional
        The trajectory's name (default: the file's stem).

    Returns
    -------
    Trajectory

    Raises
    ------
    InputError
        Naming the file, the line or column, and the fix.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from bvpnav.evaluate import read_trajectory
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "walk.tum"
    >>> _ = p.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n")
    >>> read_trajectory(p).xyz[-1].tolist()
    [1.0, 0.0, 0.0]
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{str(p)!r}: no such file; give a TUM file or a table with t, x, y[, z]")
    suffix = p.suffix.lower()
    if suffix in (".csv", ".parquet", ".pq"):
        traj = _read_table(p, name or p.stem)
    elif suffix in (".tum", ".txt", ""):
        traj = _read_tum(p)
    else:
        raise InputError(f"{str(p)!r}: unknown trajectory format {suffix!r}; give .tum/.txt (TUM) or "
                         ".csv/.parquet (a table with t, x, y[, z])")
    return replace(traj, name=name or p.stem)


def write_tum(traj, path: str | os.PathLike) -> None:
    r"""Write a trajectory in the TUM format, atomically.

    Parameters
    ----------
    traj : Trajectory or bvpnav.Solution
        A 3-D trajectory (a 2-D one is written with z = 0). A solution of strapdown data
        writes its attitude; otherwise the quaternions are identity placeholders, marked by a
        first comment line that :func:`read_trajectory` reads back as "no orientation".
    path : str or path-like
        Destination (never one of the inputs; replaced whole or not at all).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from bvpnav.evaluate import Trajectory, write_tum, read_trajectory
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "out.tum"
    >>> write_tum(Trajectory([0.0, 0.5], [[0, 0, 0], [1, 2, 3]]), p)
    >>> read_trajectory(p).orientation is None
    True
    """
    from .io import atomic_write_text

    if not isinstance(traj, Trajectory):
        traj = Trajectory.from_solution(traj)
    xyz = traj.xyz if traj.dims == 3 else np.column_stack([traj.xyz, np.zeros(len(traj))])
    lines = []
    if traj.orientation is None:
        lines.append(NO_ORIENTATION)
        q = np.tile([0.0, 0.0, 0.0, 1.0], (len(traj), 1))
    else:
        q = traj.orientation.as_quat()
    lines.append("# timestamp tx ty tz qx qy qz qw")
    for ti, p, qi in zip(traj.t, xyz, q, strict=True):
        lines.append(" ".join(repr(float(v)) for v in (ti, *p, *qi)))
    atomic_write_text(path, "\n".join(lines) + "\n")


# ------------------------------------------------------------------ association
def associate(est: Trajectory, ref: Trajectory, max_diff: float = 0.01, method: str = "nearest",
              offset: float = 0.0) -> tuple[Trajectory, Trajectory]:
    r"""Pair the samples of two trajectories in time.

    Parameters
    ----------
    est, ref : Trajectory
        Estimate and reference.
    max_diff : float
        Largest time difference of a pair, s (``evo``'s ``--t_max_diff``, default 0.01 s).
    method : {"nearest", "interpolate"}
        ``"nearest"``: as ``evo``: every sample of the trajectory with fewer samples is paired
        with the nearest sample of the other within ``max_diff`` (on a tie, the earlier);
        unpaired samples are dropped. ``"interpolate"``: the estimate is interpolated
        linearly (orientations by slerp) at each reference time inside its span.
    offset : float
        Added to the estimate's times before pairing, s.

    Returns
    -------
    (Trajectory, Trajectory)
        Estimate and reference with the same number of samples, in time order.

    Raises
    ------
    InputError
        When no pair is found, naming both spans and the tolerance.

    Examples
    --------
    An estimate at 2 Hz against a reference at 1 Hz: the pairs are the common instants:

    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory
    >>> t = np.arange(0.0, 6.0)
    >>> ref = Trajectory(t, np.column_stack([t, 0 * t, 0 * t]))  # 1 m/s along x
    >>> from bvpnav.evaluate import associate
    >>> t2 = np.arange(0.0, 5.5, 0.5)
    >>> est = Trajectory(t2, np.column_stack([t2, 0 * t2, 0 * t2]))
    >>> e, r = associate(est, ref)
    >>> e.t.tolist(), r.t.tolist()
    ([0.0, 1.0, 2.0, 3.0, 4.0, 5.0], [0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    """
    if not (np.isfinite(max_diff) and max_diff >= 0):
        raise InputError(f"max_diff={max_diff!r}: give a time tolerance >= 0 s")
    te = est.t + offset
    if method == "interpolate":
        idx = np.flatnonzero((ref.t >= te[0]) & (ref.t <= te[-1]))  # interpolation never extrapolates
        if idx.size < 2:
            raise _no_pairs(est, ref, max_diff, offset)
        tq = ref.t[idx]
        xyz = np.column_stack([np.interp(tq, te, est.xyz[:, j]) for j in range(est.dims)])
        ori = None
        if est.orientation is not None:
            from scipy.spatial.transform import Slerp

            ori = Slerp(te, est.orientation)(tq)
        return Trajectory(tq - offset, xyz, ori, est.name), ref.take(idx)
    if method != "nearest":
        raise InputError(f"method={method!r}: give 'nearest' or 'interpolate'")
    est_longer = len(est) > len(ref)
    short_t, long_t = (ref.t, te) if est_longer else (te, ref.t)
    i_short, i_long = _nearest(short_t, long_t, max_diff)
    if i_short.size < 2:
        raise _no_pairs(est, ref, max_diff, offset)
    ie, ir = (i_long, i_short) if est_longer else (i_short, i_long)
    return est.take(ie), ref.take(ir)


def _nearest(a: np.ndarray, b: np.ndarray, max_diff: float) -> tuple[np.ndarray, np.ndarray]:
    """For each a (sorted), the nearest b (sorted) within max_diff: evo's rule, vectorized."""
    inside = (a >= b[0] - max_diff) & (a <= b[-1] + max_diff)
    ia = np.flatnonzero(inside)
    j = np.minimum(np.searchsorted(b, a[ia], side="right"), b.size - 1)
    ub = b[j] - a[ia]
    lb = np.where(j > 0, a[ia] - b[np.maximum(j - 1, 0)], np.inf)
    take_ub = (ub <= max_diff) & (ub < lb)
    take_lb = ~take_ub & (lb <= max_diff) & (lb <= ub)
    ok = take_ub | take_lb
    jj = np.where(take_ub, j, j - 1)
    return ia[ok], jj[ok]


def _no_pairs(est, ref, max_diff, offset) -> InputError:
    return InputError(f"no two samples of {est.name!r} ({est.t[0]:.9g} .. {est.t[-1]:.9g} s, offset "
                      f"{offset:g} s) and {ref.name!r} ({ref.t[0]:.9g} .. {ref.t[-1]:.9g} s) lie within "
                      f"{max_diff:g} s of each other; check that both use the same clock, give the offset, "
                      "or raise max_diff")


# ------------------------------------------------------------------ alignment
def _umeyama(x: np.ndarray, y: np.ndarray, with_scale: bool) -> tuple[np.ndarray, np.ndarray, float]:
    """R, t, s minimising sum |s R x_i + t - y_i|^2 (Umeyama 1991; x, y of shape (n, m))."""
    n, m = x.shape
    mx, my = x.mean(axis=0), y.mean(axis=0)
    xc, yc = x - mx, y - my
    var_x = np.sum(xc ** 2) / n
    cov = yc.T @ xc / n
    u, d, vt = np.linalg.svd(cov)
    if np.count_nonzero(d > np.finfo(float).eps * max(1.0, d[0])) < m - 1:
        raise InputError("the trajectory is degenerate (all samples on a line or at one point): a rotation "
                         "cannot be fitted; use align='translation' or 'none'")
    s_mat = np.eye(m)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        s_mat[-1, -1] = -1.0
    r = u @ s_mat @ vt
    c = float(np.trace(np.diag(d) @ s_mat) / var_x) if with_scale else 1.0
    t = my - c * r @ mx
    return r, t, c


def align(est: Trajectory, ref: Trajectory, method: str = "rigid", first: int | None = None) -> Alignment:
    r"""The least-squares map of the estimate's positions onto the reference's.

    Parameters
    ----------
    est, ref : Trajectory
        Associated trajectories (same length, same dimension).
    method : str
        One of :data:`ALIGNMENTS`.
    first : int, optional
        Fit on the first ``first`` samples only (``evo``'s ``--n_to_align``).

    Returns
    -------
    Alignment

    Notes
    -----
    Minimises :math:`\sum_i \lVert s R p_i + t - q_i \rVert^2` over the parameters the method
    frees (Umeyama 1991). ``"yaw"`` decouples: the horizontal part is the 2-D Umeyama fit, the
    vertical translation the mean height offset. ``"scale"`` keeps the Sim(3) scale only and
    applies it about the origin, as ``evo`` does.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory
    >>> t = np.arange(0.0, 6.0)
    >>> ref = Trajectory(t, np.column_stack([t, 0 * t, 0 * t]))  # 1 m/s along x
    >>> from bvpnav.evaluate import align
    >>> est = Trajectory(t, ref.xyz + [1.0, 2.0, 0.0])
    >>> fit = align(est, ref, "translation")
    >>> (fit.translation + 0.0).tolist()
    [-1.0, -2.0, 0.0]
    """
    if method not in ALIGNMENTS:
        raise InputError(f"align={method!r}: give one of {sorted(ALIGNMENTS)}")
    if len(est) != len(ref) or est.dims != ref.dims:
        raise InputError(f"align: {len(est)} x {est.dims} estimate against {len(ref)} x {ref.dims} "
                         "reference; associate them first")
    d = est.dims
    n = len(est) if first is None else int(first)
    if not 2 <= n <= len(est):
        raise InputError(f"first={first!r}: give 2 .. {len(est)} samples to fit on")
    p, q = est.xyz[:n], ref.xyz[:n]
    eye, zero = np.eye(d), np.zeros(d)
    if method == "none":
        return Alignment(method, eye, zero)
    if method == "translation":
        return Alignment(method, eye, q.mean(axis=0) - p.mean(axis=0))
    if method == "yaw":
        r2, t2, _ = _umeyama(p[:, :2], q[:, :2], False)
        rot, tr = eye.copy(), zero.copy()
        rot[:2, :2], tr[:2] = r2, t2
        if d == 3:
            tr[2] = float(np.mean(q[:, 2] - p[:, 2]))
        return Alignment(method, rot, tr)
    r, t, s = _umeyama(p, q, method in ("similarity", "scale"))
    if method == "scale":
        return Alignment(method, eye, zero, s)
    return Alignment(method, r, t, s)


# ------------------------------------------------------------------ metrics
def _prepare(est, ref, align_method, max_diff, method, first, offset):
    if est.dims != ref.dims:
        if ref.dims == 2 and est.dims == 3:
            est = Trajectory(est.t, est.xyz[:, :2], None, est.name)
        elif ref.dims == 3 and est.dims == 2:
            ref = Trajectory(ref.t, ref.xyz[:, :2], None, ref.name)
    if est.dims == 2:  # orientations only enter a 3-D evaluation
        est, ref = replace(est, orientation=None), replace(ref, orientation=None)
    e, r = associate(est, ref, max_diff=max_diff, method=method, offset=offset)
    al = align(e, r, align_method, first)
    return al.apply(e), r, al


def ape(est: Trajectory, ref: Trajectory, align: str = "rigid", max_diff: float = 0.01,
        method: str = "nearest", first: int | None = None, offset: float = 0.0) -> ErrorResult:
    r"""Absolute trajectory error: the position error per associated sample after alignment.

    Parameters
    ----------
    est, ref : Trajectory
        Estimate and reference. A 2-D reference evaluates the estimate's x and y only.
    align : str
        One of :data:`ALIGNMENTS` (default ``"rigid"``, evo's ``--align``).
    max_diff, method, offset :
        The time association (see :func:`associate`).
    first : int, optional
        Fit the alignment on the first ``first`` associated samples.

    Returns
    -------
    ErrorResult
        ``error`` = :math:`\lVert s R p_i + t - q_i \rVert` (m) per sample; ``stats()`` gives
        ``evo_ape``'s figures for the translation part.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory, ape
    >>> t = np.linspace(0, 10, 11)
    >>> ref = Trajectory(t, np.column_stack([np.cos(t), np.sin(t), 0 * t]))
    >>> est = Trajectory(t, ref.xyz @ [[0, -1, 0], [1, 0, 0], [0, 0, 1]] + 5.0)  # turned, moved
    >>> ape(est, ref, align="rigid").rmse < 1e-12
    True
    """
    e, r, al = _prepare(est, ref, align, max_diff, method, first, offset)
    vec = e.xyz - r.xyz
    settings = {"align": align, "max_diff": max_diff, "method": method, "offset": offset, "first": first}
    return ErrorResult("ape", r.t.copy(), np.linalg.norm(vec, axis=1), vec, al, None, settings, e, r)


def _pairs(traj: Trajectory, delta: float, unit: str, all_pairs: bool, rel_tol: float) -> np.ndarray:
    n = len(traj)
    if unit == "frames":
        k = int(delta)
        if k != delta or k < 1:
            raise InputError(f"delta={delta!r} frames: give a whole number >= 1")
        if all_pairs:
            i = np.arange(n - k)
            return np.column_stack([i, i + k])
        ids = np.arange(0, n, k)
        return np.column_stack([ids[:-1], ids[1:]])
    if unit == "m":
        steps = np.linalg.norm(np.diff(traj.xyz, axis=0), axis=1)
        along = np.concatenate([[0.0], np.cumsum(steps)])
    else:
        along = traj.t - traj.t[0]
    if all_pairs:
        out = []
        for i in range(n - 1):
            rest = along[i + 1:] - along[i]
            c = int(np.argmin(np.abs(rest - delta)))
            if abs(rest[c] - delta) <= delta * rel_tol:
                out.append((i, c + i + 1))
        return np.array(out, dtype=int).reshape(-1, 2)
    ids = [0]
    if unit == "m":  # evo's consecutive rule: a new pose once the path since the last reaches delta
        run = 0.0
        for i in range(1, n):
            run += steps[i - 1]
            if run >= delta:
                ids.append(i)
                run = 0.0
    else:
        for i in range(1, n):
            if along[i] - along[ids[-1]] >= delta - 1e-9 * max(1.0, abs(delta)):
                ids.append(i)
    ids = np.array(ids)
    return np.column_stack([ids[:-1], ids[1:]])


def rpe(est: Trajectory, ref: Trajectory, delta: float = 1.0, unit: str = "m", align: str = "none",
        all_pairs: bool = False, rel_tol: float = 0.1, pairs_from: str = "estimate", max_diff: float = 0.01,
        method: str = "nearest", offset: float = 0.0) -> ErrorResult:
    r"""Relative error: how wrong the estimate's motion is over a distance, a time or a number of samples.

    Parameters
    ----------
    est, ref : Trajectory
        Estimate and reference.
    delta : float
        The pair spacing, in ``unit``.
    unit : {"m", "s", "frames"}
        Path length travelled (``evo``'s ``--delta_unit m``), elapsed time, or samples.
    align : str
        One of :data:`ALIGNMENTS` applied first (default ``"none"``, as ``evo_rpe``; only the
        scale matters when orientations are known).
    all_pairs : bool
        Every pair at the spacing (within ``rel_tol * delta`` for m and s), not consecutive ones.
    pairs_from : {"estimate", "reference"}
        Which trajectory's path chooses the pairs (``evo``'s default: the estimate).
    max_diff, method, offset :
        The time association (see :func:`associate`).

    Returns
    -------
    ErrorResult
        One error per pair (i, j), m.

    Notes
    -----
    With orientations on both sides (3-D), the error is ``evo``'s translation part of
    :math:`E_{ij} = (Q_i^{-1} Q_j)^{-1} (P_i^{-1} P_j)`, i.e.
    :math:`\lVert R_{P_i}^T (p_j - p_i) - R_{Q_i}^T (q_j - q_i) \rVert`, expressed in the body
    frame at the pair's start (Q reference, P estimate). Without orientations it is the error of
    the displacement, :math:`\lVert (p_j - p_i) - (q_j - q_i) \rVert`, in the aligned frame.

    Examples
    --------
    An estimate that reads distances 10 % long:

    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory
    >>> t = np.arange(0.0, 6.0)
    >>> ref = Trajectory(t, np.column_stack([t, 0 * t, 0 * t]))  # 1 m/s along x
    >>> from bvpnav.evaluate import rpe
    >>> res = rpe(Trajectory(t, 1.1 * ref.xyz), ref, delta=1.0, unit="m")
    >>> np.round(res.error, 6).tolist()
    [0.1, 0.1, 0.1, 0.1, 0.1]
    """
    if unit not in ("m", "s", "frames"):
        raise InputError(f"unit={unit!r}: give 'm' (path length), 's' (time) or 'frames' (samples)")
    if not (np.isfinite(delta) and delta > 0):
        raise InputError(f"delta={delta!r}: give a spacing > 0 ({unit})")
    if pairs_from not in ("estimate", "reference"):
        raise InputError(f"pairs_from={pairs_from!r}: give 'estimate' or 'reference'")
    e, r, al = _prepare(est, ref, align, max_diff, method, None, offset)
    pr = _pairs(e if pairs_from == "estimate" else r, delta, unit, all_pairs, rel_tol)
    if pr.shape[0] == 0:
        raise InputError(f"delta = {delta:g} {unit} gives no pair over these {len(e)} samples; give a "
                         "smaller spacing" + (" or a larger rel_tol" if all_pairs else ""))
    i, j = pr[:, 0], pr[:, 1]
    dp, dq = e.xyz[j] - e.xyz[i], r.xyz[j] - r.xyz[i]
    if e.orientation is not None and r.orientation is not None and e.dims == 3:
        dp = e.orientation[i].inv().apply(dp)
        dq = r.orientation[i].inv().apply(dq)
    vec = dp - dq
    settings = {"align": align, "delta": delta, "unit": unit, "all_pairs": all_pairs, "rel_tol": rel_tol,
                "pairs_from": pairs_from, "max_diff": max_diff, "method": method, "offset": offset}
    return ErrorResult("rpe", r.t[j].copy(), np.linalg.norm(vec, axis=1), vec, al, pr, settings, e, r)


# ------------------------------------------------------------------ report
def format_result(res: ErrorResult) -> str:
    """A few lines of text: what was compared and the statistics (m).

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory
    >>> t = np.arange(0.0, 6.0)
    >>> ref = Trajectory(t, np.column_stack([t, 0 * t, 0 * t]))  # 1 m/s along x
    >>> from bvpnav.evaluate import format_result, rpe
    >>> print(format_result(rpe(Trajectory(t, 1.1 * ref.xyz), ref, delta=1.0)))
    RPE over 1 m, 5 pairs, aligned by no alignment
      rmse 0.1  mean 0.1  median 0.1  std ...  min 0.1  max 0.1 m
      RMS x 0.1  y 0  z 0  horizontal 0.1  vertical 0 m
    """
    s = res.stats()
    head = "APE" if res.kind == "ape" else (f"RPE over {res.settings['delta']:g} {res.settings['unit']}"
                                            + (" (all pairs)" if res.settings.get("all_pairs") else ""))
    al = res.alignment
    how = ALIGNMENTS[al.method]
    if al.method in ("yaw", "rigid", "similarity") and al.rotation.shape[0] >= 2:
        how += f"; yaw {al.yaw_deg:+.3f} deg"
    if al.method in ("similarity", "scale"):
        how += f"; scale {al.scale:.6f}"
    lines = [f"{head}, {s['count']} {'poses' if res.kind == 'ape' else 'pairs'}, aligned by {how}",
             "  " + "  ".join(f"{k} {s[k]:.6g}" for k in ("rmse", "mean", "median", "std", "min", "max"))
             + " m",
             "  RMS " + "  ".join(f"{k[4:]} {v:.6g}" for k, v in s.items() if k.startswith("rms_")) + " m"]
    return "\n".join(lines)


def plot(results: list[ErrorResult] | ErrorResult, path: str | os.PathLike | None = None):
    """Map view (equal axes) of the aligned estimate over the reference, and each error over time.

    Returns the matplotlib figure; writes it atomically to ``path`` when given.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory
    >>> t = np.arange(0.0, 6.0)
    >>> ref = Trajectory(t, np.column_stack([t, 0 * t, 0 * t]))  # 1 m/s along x
    >>> import tempfile
    >>> from pathlib import Path
    >>> from bvpnav.evaluate import ape, plot
    >>> tmp = tempfile.TemporaryDirectory()
    >>> res = ape(Trajectory(t, ref.xyz + [0.0, 0.5, 0.0]), ref, align="none")  # 0.5 m off in y
    >>> fig = plot(res, Path(tmp.name) / "ape.png")
    >>> (Path(tmp.name) / "ape.png").exists()
    True
    >>> tmp.cleanup()
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    results = [results] if isinstance(results, ErrorResult) else list(results)
    first = results[0]
    fig, axes = plt.subplots(1 + len(results), 1, figsize=(7, 4 + 2.2 * len(results)),
                             gridspec_kw={"height_ratios": [2.2] + [1] * len(results)})
    ax = axes[0]
    ax.plot(first.reference.xyz[:, 0], first.reference.xyz[:, 1], "k-", lw=1.2,
            label=f"{first.reference.name} (reference)")
    ax.plot(first.estimate.xyz[:, 0], first.estimate.xyz[:, 1], "-", color="tab:blue", lw=1.0,
            label=f"{first.estimate.name} (aligned: {first.alignment.method})")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="best", fontsize=8)
    ax.set_title("trajectory, map view")
    for a, res in zip(axes[1:], results, strict=True):
        label = "APE" if res.kind == "ape" else f"RPE ({res.settings['delta']:g} {res.settings['unit']})"
        a.plot(res.t, res.error, ".-" if res.error.size < 200 else "-", ms=3, lw=0.8, color="tab:red")
        a.axhline(res.rmse, color="k", lw=0.8, ls="--", label=f"rmse {res.rmse:.4g} m")
        a.set_xlabel("t (s)")
        a.set_ylabel(f"{label} (m)")
        a.legend(loc="best", fontsize=8)
    fig.tight_layout()
    if path is not None:
        from .io import atomic_savefig

        atomic_savefig(fig, path, "--plot")
        plt.close(fig)
    return fig


def evaluate(est, ref, align: str = "rigid", rpe_delta: float | None = None, rpe_unit: str = "m",
             all_pairs: bool = False, **kw) -> dict[str, ErrorResult]:
    r"""APE and, when ``rpe_delta`` is given, RPE of an estimate against a reference.

    Parameters
    ----------
    est : Trajectory, bvpnav.Solution, str or path-like
        The estimate (a file is read with :func:`read_trajectory`).
    ref : Trajectory, str or path-like
        The reference (truth).
    align : str
        One of :data:`ALIGNMENTS`, for both figures (with orientations on both sides the RPE
        depends on the alignment's scale only).
    rpe_delta, rpe_unit :
        The RPE's spacing and its unit ("m", "s" or "frames").
    all_pairs : bool
        The RPE over every pair at that spacing, not consecutive ones (see :func:`rpe`).
    **kw :
        ``max_diff``, ``method``, ``offset``: the time association (:func:`associate`).

    Returns
    -------
    dict
        ``{"ape": ErrorResult, "rpe": ErrorResult}`` (``"rpe"`` only with ``rpe_delta``).

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.evaluate import Trajectory, evaluate
    >>> t = np.linspace(0.0, 20.0, 201)
    >>> ref = Trajectory(t, np.column_stack([t, np.sin(t), 0 * t]), name="truth")
    >>> est = Trajectory(t, ref.xyz + [[0.01 * ti, 0, 0] for ti in t], name="est")  # 1 cm/s drift
    >>> out = evaluate(est, ref, align="translation", rpe_delta=1.0, rpe_unit="s")
    >>> round(out["ape"].stats()["max"], 3), round(out["rpe"].rmse, 4)
    (0.1, 0.01)
    """
    if not isinstance(est, Trajectory):
        est = read_trajectory(est) if isinstance(est, (str, os.PathLike)) else Trajectory.from_solution(est)
    if not isinstance(ref, Trajectory):
        ref = read_trajectory(ref)
    out = {"ape": ape(est, ref, align=align, **kw)}
    if rpe_delta is not None:
        out["rpe"] = rpe(est, ref, delta=rpe_delta, unit=rpe_unit, align=align, all_pairs=all_pairs, **kw)
    return out
