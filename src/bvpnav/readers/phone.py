"""Phone sensor-logger exports: the "Sensor Logger" app's per-sensor CSV files.

Supported layout (Sensor Logger for Android/iOS, "CSV" export; a folder, or the ``.zip``
the app shares, with the files at its top or in one subfolder):

=========================  ==============================================  =====
file                       columns                                         units
=========================  ==============================================  =====
``TotalAcceleration.csv``  ``time, seconds_elapsed, z, y, x``              m/s^2
``Accelerometer.csv``      same (user acceleration: gravity removed)       m/s^2
``Gravity.csv``            same (the gravity part of the total)            m/s^2
``Gyroscope.csv``          same                                            rad/s
``Orientation.csv``        ``time, seconds_elapsed, qz, qy, qx, qw, ...``  --
=========================  ==============================================  =====

``time`` is integer ns since the Unix epoch (each sensor on its own sample instants,
one phone clock); ``seconds_elapsed`` is not used. Other files (Metadata.csv,
Magnetometer.csv, Location.csv, ...) are ignored.

Specific force: an accelerometer at rest reads +g upwards (Android convention, which
Sensor Logger uses on both platforms), so ``TotalAcceleration.csv`` *is* the specific
force; ``Accelerometer.csv`` alone is not (gravity removed) and is refused, but
``Accelerometer.csv + Gravity.csv`` (Gravity resampled onto the Accelerometer's times) is
used when there is no TotalAcceleration file (option ``acceleration``). The file used is
stated in the notes, and a specific force whose mean is far from gravity (< 5 m/s^2,
i.e. gravity removed or of the opposite sign) is refused.

Times: the specific-force file's samples are the recording's; the gyro rates are
resampled onto them by linear interpolation and the orientation by slerp (scipy), each
stated in the notes with its offset and rate ratio. A sensor that does not cover the
accelerometer's window is refused naming the file (no extrapolation), unless
``crop = true`` (the window is then cut to the common span, stated in the notes).

Orientation: Android's rotation vector is the device-to-ENU rotation (x east, y north,
z up), so the attitude's reference is ``attitude_frame = "enu"``. (On iOS the reference
frame depends on the app's setting; override with ``[input] attitude_frame`` or use
``orientation = false`` to integrate the gyro rates instead.)

Not supported (yet): phyphox exports (one ``Raw Data.csv`` per experiment).
"""

from __future__ import annotations

import io
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError
from . import Reader, Recording, register_reader

if TYPE_CHECKING:  # pragma: no cover
    from ..simulate import Simulation

__all__ = ["PhoneReader", "SENSOR_FILES", "write_export", "write_example_export", "zip_export",
           "ExampleExport"]

#: The files read, by role.
SENSOR_FILES = {"total": "TotalAcceleration.csv", "user": "Accelerometer.csv", "gravity": "Gravity.csv",
                "gyro": "Gyroscope.csv", "orientation": "Orientation.csv"}
_VECTOR = ("x", "y", "z")
_QUAT = ("qx", "qy", "qz", "qw")
_ZIP_MAGIC = b"PK\x03\x04"


# ---------------------------------------------------------------------- file access
class _Export:
    """The export's CSV files by base name, from a folder or a zip archive."""

    def __init__(self, path: Path):
        self.path = path
        self.names: dict[str, str] = {}
        self._zip: zipfile.ZipFile | None = None
        if path.is_dir():
            self._from_folder(path)
        else:
            try:
                self._zip = zipfile.ZipFile(path)
                entries = [n for n in self._zip.namelist() if not n.endswith("/")]
            except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
                raise InputError(f"{str(path)!r}: not a readable zip archive ({exc}); give the Sensor Logger "
                                 "export folder or its complete .zip") from None
            groups: dict[str, dict[str, str]] = {}
            for n in entries:
                folder, _, base = n.rpartition("/")
                if base in SENSOR_FILES.values():
                    groups.setdefault(folder, {})[base] = n
            self._pick(groups)

    def _from_folder(self, path: Path) -> None:
        here = {p.name: str(p) for p in path.iterdir() if p.is_file() and p.name in SENSOR_FILES.values()}
        if here:
            self._pick({"": here})
            return
        groups = {}
        for sub in sorted(p for p in path.iterdir() if p.is_dir()):
            files = {p.name: str(p) for p in sub.iterdir() if p.is_file() and p.name in SENSOR_FILES.values()}
            if files:
                groups[sub.name] = files
        self._pick(groups)

    def _pick(self, groups: Mapping[str, Mapping[str, str]]) -> None:
        """The sensor files of the one export among ``groups`` (folder -> base name -> entry);
        several exports are refused, naming each (their files would be mixed one by one)."""
        if len(groups) > 1:
            listing = "; ".join(f"{(k + '/') if k else '(top level)'!r}: {', '.join(sorted(v))}"
                                for k, v in sorted(groups.items()))
            raise InputError(f"{str(self.path)!r} holds {len(groups)} exports ({listing}): read together "
                             "they would be mixed file by file (one phone's accelerometer with another's "
                             "orientation). Give one export: its folder, or a .zip of that folder alone")
        self.names = dict(next(iter(groups.values()))) if groups else {}

    def has(self, name: str) -> bool:
        return name in self.names

    def where(self, name: str) -> str:
        return f"{self.path / name}" if self._zip is None else f"{self.path}!{self.names[name]}"

    def read(self, name: str, columns: tuple[str, ...]):
        """(time ns int64 (N,), values (N, len(columns)) float) of one file, checked."""
        import pandas as pd

        where = self.where(name)
        try:
            if self._zip is not None:
                raw = io.BytesIO(self._zip.read(self.names[name]))
            else:
                raw = self.names[name]
            df = pd.read_csv(raw)
        except Exception as exc:  # noqa: BLE001 - any parse failure names the file
            raise InputError(f"{where!r}: cannot read the CSV ({type(exc).__name__}: "
                             f"{str(exc).strip().splitlines()[0] if str(exc).strip() else ''})") from None
        missing = [c for c in ("time", *columns) if c not in df.columns]
        if missing:
            raise InputError(f"{where!r}: no column(s) {missing}; Sensor Logger files have 'time' (ns since "
                             f"the epoch) and {list(columns)}; found {list(df.columns)}")
        return _checked(df, columns, where)


def _checked(df, columns: tuple[str, ...], where: str):
    import pandas as pd

    if len(df) < 2:
        raise InputError(f"{where!r}: {len(df)} sample(s); at least 2 are needed")
    if not pd.api.types.is_integer_dtype(df["time"]):
        raise InputError(f"{where!r}: column 'time' is not integer nanoseconds since the epoch (dtype "
                         f"{df['time'].dtype}, first value {df['time'].iloc[0]!r})")
    ns = df["time"].to_numpy(dtype=np.int64)
    d = np.diff(ns)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise InputError(f"{where!r}: data row {k + 1} has time {int(ns[k])} ns, "
                         f"{'the same as' if d[k - 1] == 0 else 'before'} row {k}'s {int(ns[k - 1])} ns "
                         f"({bad.size} such row(s)); times must strictly increase")
    try:
        vals = df[list(columns)].to_numpy(dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{where!r}: columns {list(columns)} are not all numbers") from None
    rows = np.flatnonzero(~np.all(np.isfinite(vals), axis=1))
    if rows.size:
        raise InputError(f"{where!r}: data row {int(rows[0]) + 1} has a missing or non-finite value in "
                         f"{list(columns)} ({rows.size} such row(s))")
    return ns, vals


# ----------------------------------------------------------------------- resampling
def _rel(ns: np.ndarray, ns0: int) -> np.ndarray:
    return (ns - np.int64(ns0)).astype(float) * 1e-9


def _clock_note(name: str, ns: np.ndarray, master: np.ndarray, master_name: str, how: str) -> str:
    off = (int(ns[0]) - int(master[0])) * 1e-9
    ratio = float(np.median(np.diff(master))) / float(np.median(np.diff(ns)))
    return (f"{name} ({ns.size} samples, {1e9 / float(np.median(np.diff(ns))):.4g} Hz) resampled onto "
            f"{master_name}'s {master.size} times by {how}; its first sample is {off:+.6f} s from "
            f"{master_name}'s, its median rate {ratio:.6g} x {master_name}'s.")


def _cover(ns: np.ndarray, lo: int, hi: int, where: str, crop: bool) -> tuple[int, int]:
    """The part of [lo, hi] (ns) a sensor covers; refused when it does not all (unless crop)."""
    if ns[0] <= lo and ns[-1] >= hi:
        return lo, hi
    if not crop:
        gap = [f"starts {(int(ns[0]) - lo) * 1e-9:.6f} s after" if ns[0] > lo else "",
               f"ends {(hi - int(ns[-1])) * 1e-9:.6f} s before" if ns[-1] < hi else ""]
        raise InputError(f"{where!r} {' and '.join(g for g in gap if g)} the accelerometer's samples; it is "
                         "not extrapolated: set [input] crop = true to keep only the time every sensor "
                         "covers")
    return max(lo, int(ns[0])), min(hi, int(ns[-1]))


def _interp(ns: np.ndarray, vals: np.ndarray, at: np.ndarray) -> np.ndarray:
    ns0 = int(at[0])
    x, xi = _rel(ns, ns0), _rel(at, ns0)
    return np.column_stack([np.interp(xi, x, vals[:, j]) for j in range(vals.shape[1])])


def _slerp(ns: np.ndarray, quat: np.ndarray, at: np.ndarray, where: str):
    from scipy.spatial.transform import Rotation, Slerp

    norm = np.linalg.norm(quat, axis=1)
    bad = np.flatnonzero(norm < 0.5)
    if bad.size:
        raise InputError(f"{where!r}: data row {int(bad[0]) + 1} has a zero quaternion (qx, qy, qz, qw)")
    ns0 = int(at[0])
    return Slerp(_rel(ns, ns0), Rotation.from_quat(quat))(_rel(at, ns0))


# --------------------------------------------------------------------------- reader
class PhoneReader(Reader):
    """Sensor Logger exports (folder or .zip): specific force, gyro rates, orientation.

    Options: ``acceleration`` (``"auto"``, ``"total"`` or ``"user+gravity"``),
    ``orientation`` (true: use Orientation.csv when present; false: integrate the gyro),
    ``crop`` (cut the window to the span every sensor covers instead of refusing).
    """

    name = "phone"
    suffixes = ("/", ".zip")
    options = frozenset({"acceleration", "orientation", "crop"})
    description = "Sensor Logger phone export (folder or .zip of TotalAcceleration/Gyroscope/Orientation.csv)"

    def sniff(self, head: bytes) -> bool:
        """A zip whose head names a Sensor Logger file, or a folder listing naming one."""
        names = [n.encode() for n in (SENSOR_FILES["total"], SENSOR_FILES["gyro"], SENSOR_FILES["user"])]
        if head.startswith(_ZIP_MAGIC):
            return any(n in head for n in names)
        return any(n in head.split(b"\n") for n in names)

    def read(self, path: Path, options: Mapping[str, Any]) -> Recording:
        path = Path(path)
        mode = options.get("acceleration", "auto")
        use_att, crop = options.get("orientation", True), options.get("crop", False)
        if mode not in ("auto", "total", "user+gravity"):
            raise InputError(f"[input] acceleration = {mode!r}: \"auto\", \"total\" (TotalAcceleration.csv) "
                             "or \"user+gravity\" (Accelerometer.csv + Gravity.csv)")
        for key, v in (("orientation", use_att), ("crop", crop)):
            if not isinstance(v, bool):
                raise InputError(f"[input] {key} = {v!r}: true or false")
        if path.is_dir() and (path / "metadata.yaml").is_file():
            raise InputError(f"{str(path)!r} holds metadata.yaml: a ROS 2 bag folder, not a phone export; "
                             "set [input] format = \"rosbag\"")
        export = _Export(path)
        notes: list[str] = []
        ns, f, master = self._specific_force(export, mode, crop, notes)
        lo, hi = int(ns[0]), int(ns[-1])
        gyro_d = export.read(SENSOR_FILES["gyro"], _VECTOR) if export.has(SENSOR_FILES["gyro"]) else None
        ori_d = (export.read(SENSOR_FILES["orientation"], _QUAT)
                 if use_att and export.has(SENSOR_FILES["orientation"]) else None)
        for name, d in ((SENSOR_FILES["gyro"], gyro_d), (SENSOR_FILES["orientation"], ori_d)):
            if d is not None:
                lo, hi = _cover(d[0], lo, hi, export.where(name), crop)
        ns, f = self._crop(ns, f, lo, hi, master, notes)
        gyro = att = None
        if gyro_d is not None:
            gyro = _interp(gyro_d[0], gyro_d[1], ns)
            notes.append(_clock_note(SENSOR_FILES["gyro"], gyro_d[0], ns, master, "linear interpolation"))
        if ori_d is not None:
            att = _slerp(ori_d[0], ori_d[1], ns, export.where(SENSOR_FILES["orientation"]))
            notes.append(_clock_note(SENSOR_FILES["orientation"], ori_d[0], ns, master, "slerp"))
            notes.append("Orientation (qx, qy, qz, qw) used as the device-to-ENU attitude (Android rotation "
                         "vector: x east, y north, z up; attitude_frame = \"enu\").")
        elif gyro is None:
            raise InputError(f"{str(path)!r}: neither {SENSOR_FILES['gyro']} nor "
                             f"{SENSOR_FILES['orientation']} (with orientation = true): the attitude cannot "
                             "be known")
        _check_gravity(f, att, export.where(master))
        from ..timebase import to_seconds

        t, origin = to_seconds(ns, "ns")
        notes.insert(0, f"Times: {master} 'time' (integer ns since the Unix epoch); t = 0 at its first "
                        f"sample ({origin}).")
        return Recording(t=t, source=export.where(master), time_origin=origin, specific_force=f, gyro=gyro,
                         attitude=att, attitude_frame="enu" if att is not None else None, notes=tuple(notes),
                         meta={"files": sorted(export.names), "accelerometer": master})

    def _specific_force(self, export: _Export, mode: str, crop: bool, notes: list[str]):
        total, user, grav = SENSOR_FILES["total"], SENSOR_FILES["user"], SENSOR_FILES["gravity"]
        if mode == "total" or (mode == "auto" and export.has(total)):
            if not export.has(total):
                raise InputError(f"{str(export.path)!r}: no {total} (acceleration = \"total\")")
            ns, f = export.read(total, _VECTOR)
            notes.append(f"Specific force: {total} (x, y, z in m/s^2, gravity included), device axes.")
            return ns, f, total
        if not (export.has(user) and export.has(grav)):
            have = sorted(export.names) or "no Sensor Logger file"
            raise InputError(f"{str(export.path)!r}: no specific force: needs {total}, or {user} (gravity "
                             f"removed) together with {grav}; found {have}")
        ns, a = export.read(user, _VECTOR)
        gns, g = export.read(grav, _VECTOR)
        lo, hi = _cover(gns, int(ns[0]), int(ns[-1]), export.where(grav), crop)
        keep = (ns >= lo) & (ns <= hi)
        ns, a = ns[keep], a[keep]
        f = a + _interp(gns, g, ns)
        notes.append(f"Specific force: {user} (user acceleration) + {grav}, m/s^2, device axes.")
        notes.append(_clock_note(grav, gns, ns, user, "linear interpolation"))
        return ns, f, user

    @staticmethod
    def _crop(ns, f, lo: int, hi: int, master: str, notes: list[str]):
        keep = (ns >= lo) & (ns <= hi)
        if not np.all(keep):
            if np.count_nonzero(keep) < 3:
                raise InputError(f"{master}: fewer than 3 samples inside the span every sensor covers")
            notes.append(f"crop = true: {int(np.count_nonzero(~keep))} {master} samples outside the span "
                         f"every sensor covers were dropped ({int(np.count_nonzero(keep))} kept).")
        return ns[keep], f[keep]

    def example(self, folder: Path) -> Path:
        """A 2 s export as the app shares it: a .zip of TotalAcceleration, Gyroscope and
        Orientation.csv on their own clocks (a .zip, which only this reader claims; a
        folder is claimed by the rosbag reader too)."""
        ex = write_example_export(Path(folder) / "sensorlogger", duration=2.0)
        return zip_export(ex.path, Path(folder) / "sensorlogger.zip")


def _check_gravity(f: np.ndarray, att, where: str) -> None:
    """Refuse a "specific force" that is not one (gravity removed, or opposite sign)."""
    up = float(np.mean(att.apply(f)[:, 2])) if att is not None else float(np.mean(np.linalg.norm(f, axis=1)))
    if up < 5.0:
        what = "upward component (ENU z)" if att is not None else "magnitude"
        raise InputError(f"{where!r}: the mean {what} of the specific force is {up:.3g} m/s^2, not about "
                         "+9.8: this is not a specific force (gravity removed, or iOS sign convention); use "
                         "TotalAcceleration.csv, or Accelerometer.csv with Gravity.csv")


# -------------------------------------------------------------------------- writing
def _write_csv(path: Path, ns: np.ndarray, cols: Mapping[str, np.ndarray], start: int) -> None:
    names = list(cols)
    rows = ["time,seconds_elapsed," + ",".join(names)]
    for k in range(ns.size):
        vals = ",".join(repr(float(cols[c][k])) for c in names)
        rows.append(f"{int(ns[k])},{(int(ns[k]) - start) * 1e-9!r},{vals}")
    path.write_text("\n".join(rows) + "\n")


def write_export(folder, *, acc_ns, acc, gyro_ns=None, gyro=None, orientation_ns=None, quat=None,
                 total: bool = True, gravity=None) -> Path:
    """Write a Sensor Logger-style export folder from arrays.

    Parameters
    ----------
    folder : path-like
        Folder to create (parents too).
    acc_ns : array_like of int, shape (N,)
        Accelerometer times, ns since the Unix epoch.
    acc : array_like, shape (N, 3)
        Specific force (``total=True``, TotalAcceleration.csv) or user acceleration
        (``total=False``, Accelerometer.csv), m/s^2, device x, y, z.
    gyro_ns, gyro : array_like, optional
        Gyroscope times (ns) and rates (M, 3), rad/s.
    orientation_ns, quat : array_like, optional
        Orientation times (ns) and device-to-ENU quaternions (K, 4) as (x, y, z, w).
    total : bool
        Which accelerometer file ``acc`` goes to.
    gravity : tuple (ns, (L, 3) array), optional
        Gravity.csv times and values (m/s^2).

    Returns
    -------
    Path
        The folder. Columns are in Sensor Logger's order (``z, y, x``; ``qz, qy, qx, qw``).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    acc_ns = np.asarray(acc_ns, dtype=np.int64)
    firsts = [int(acc_ns[0])] + [int(np.asarray(x)[0]) for x in (gyro_ns, orientation_ns) if x is not None]
    start = min(firsts)
    acc = np.asarray(acc, float)
    vec = lambda v: {"z": v[:, 2], "y": v[:, 1], "x": v[:, 0]}  # noqa: E731
    _write_csv(folder / SENSOR_FILES["total" if total else "user"], acc_ns, vec(acc), start)
    if gravity is not None:
        _write_csv(folder / SENSOR_FILES["gravity"], np.asarray(gravity[0], np.int64),
                   vec(np.asarray(gravity[1], float)), start)
    if gyro_ns is not None:
        _write_csv(folder / SENSOR_FILES["gyro"], np.asarray(gyro_ns, np.int64), vec(np.asarray(gyro, float)),
                   start)
    if orientation_ns is not None:
        q = np.asarray(quat, float)
        _write_csv(folder / SENSOR_FILES["orientation"], np.asarray(orientation_ns, np.int64),
                   {"qz": q[:, 2], "qy": q[:, 1], "qx": q[:, 0], "qw": q[:, 3]}, start)
    (folder / "Metadata.csv").write_text("version,device name,platform\n1,bvpnav example,android\n")
    return folder


def zip_export(folder, archive) -> Path:
    """Zip an export folder as the app shares it (files under one folder, the specific-force
    file first so that :meth:`PhoneReader.sniff` sees its name); the archive's path."""
    folder, archive = Path(folder), Path(archive)
    first = (SENSOR_FILES["total"], SENSOR_FILES["user"])
    files = sorted((p for p in folder.iterdir() if p.is_file()), key=lambda p: (p.name not in first, p.name))
    with zipfile.ZipFile(archive, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for p in files:
            z.write(p, f"{folder.name}/{p.name}")
    return archive


@dataclass(frozen=True, eq=False)
class ExampleExport:
    """An export written by :func:`write_example_export` and its truth.

    Attributes
    ----------
    path : Path
        The export folder.
    acc_ns, gyro_ns, orientation_ns : ndarray of int64
        Each sensor's sample times, ns since the Unix epoch.
    simulation : bvpnav.simulate.Simulation
        The motion sampled on the accelerometer's times (true attitude, specific force).
    """

    path: Path
    acc_ns: np.ndarray
    gyro_ns: np.ndarray
    orientation_ns: np.ndarray
    simulation: Simulation


def write_example_export(folder, duration: float = 2.0, rate: float = 100.0,
                         start_ns: int = 1_718_030_736_872_695_300) -> ExampleExport:
    """A Sensor Logger export of a known motion, each sensor on its own clock.

    The accelerometer samples at ``rate`` Hz; the gyroscope at 0.3 % slower with its
    first sample 4 ms earlier; the orientation at ``rate / 2`` starting 10 ms earlier and
    ending 10 ms later (so both cover the accelerometer's window).

    Parameters
    ----------
    folder : path-like
        Folder to create.
    duration : float
        Accelerometer span, s (whole number >= 2).
    rate : float
        Accelerometer rate, Hz (``1e9 / rate`` whole ns).
    start_ns : int
        First accelerometer time, ns since the Unix epoch.
    """
    from ..simulate import Motion, simulate_imu

    tw = np.arange(int(round(duration)) + 1, dtype=float)
    rng = np.random.default_rng(7)
    pos = np.cumsum(rng.normal(0, 0.3, size=(tw.size, 3)), axis=0)
    pos[0] = 0.0
    eul = np.column_stack([0.5 * np.sin(tw), 0.2 * np.sin(1.3 * tw), 0.15 * np.cos(0.9 * tw)])
    motion = Motion.from_waypoints(tw, pos, eul)
    sim = simulate_imu(motion, rate)
    dt = int(round(1e9 / rate))
    acc_ns = start_ns + dt * np.arange(sim.t.size, dtype=np.int64)
    # the other sensors: the same motion at their own instants (the splines extend smoothly beyond it)
    g_dt = int(round(dt * 1.003))
    gyro_ns = start_ns - 4_000_000 + g_dt * np.arange(int((acc_ns[-1] - start_ns + 8_000_000) // g_dt) + 2)
    o_dt = 2 * dt
    ori_ns = start_ns - 10_000_000 + o_dt * np.arange(int((acc_ns[-1] - start_ns + 20_000_000) // o_dt) + 1)
    gyro = motion.body_rate(_rel(gyro_ns, start_ns))
    quat = motion.attitude(_rel(ori_ns, start_ns)).as_quat()
    path = write_export(folder, acc_ns=acc_ns, acc=sim.specific_force, gyro_ns=gyro_ns, gyro=gyro,
                        orientation_ns=ori_ns, quat=quat)
    return ExampleExport(path=path, acc_ns=acc_ns, gyro_ns=gyro_ns, orientation_ns=ori_ns, simulation=sim)


register_reader(PhoneReader())
