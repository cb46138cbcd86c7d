"""ROS bags (ROS 1 ``.bag``, ROS 2 folders and their ``.db3`` / ``.mcap`` files).

Read with the pure-Python `rosbags <https://gitlab.com/ternaris/rosbags>`_ package
(``pip install 'bvpnav[ros]'``; no ROS installation needed), through
``rosbags.highlevel.AnyReader`` and a ROS 2 Humble default typestore (used only when a
bag carries no message definitions of its own).

What is read:

- ``sensor_msgs/msg/Imu`` (option ``topic``; default: the only Imu topic, several are
  refused with the list): ``linear_acceleration`` is the specific force (m/s^2, sensor
  axes, header ``frame_id``), ``angular_velocity`` the gyro rates (rad/s). The
  ``orientation`` becomes the attitude (sensor to ENU, REP-103/REP-145) when no message
  has ``orientation_covariance[0] == -1`` (REP-145: "no orientation") and every
  quaternion is non-zero; otherwise the attitude is left to gyro integration, and the
  notes say why.
- ``sensor_msgs/msg/NavSatFix`` (option ``gnss_topic``; default: the only NavSatFix topic,
  none when there is none, several refused; ``gnss_topic = false`` ignores them): fixes
  with ``status.status >= 0`` become one :class:`~bvpnav.constraints.Position` item in
  local ENU (x east, y north, z up; m) about the first kept fix or the ``origin`` option,
  with ``sigma`` from the ``position_covariance`` diagonal (covariance type > 0) or the
  ``gnss_sigma`` option.
- ``nav_msgs/msg/Odometry`` (option ``odometry_topic``; default none): the twist's linear
  velocity, given in ``child_frame_id`` (nav_msgs documentation), is rotated by the
  message's pose orientation into ``header.frame_id``, which is *assumed* to be the
  navigation frame (ENU); one :class:`~bvpnav.constraints.Velocity` item, sigma from
  the rotated twist covariance or ``odometry_sigma``. With ``odometry_as = "odometer"``
  the twist's forward component ``twist.twist.linear.x`` (the child frame's x, the
  vehicle's forward axis by REP-103) becomes one :class:`~bvpnav.constraints.Odometer`
  item instead (no pose orientation needed), sigma from the twist covariance's first
  entry or ``odometry_sigma``: a wheel odometry whose scale
  :class:`~bvpnav.error_models.OdometerScale` can estimate.
- ``geometry_msgs/msg/TwistStamped`` (option ``speed_topic``; default none): a wheel-speed
  topic, ``twist.linear.x`` in m/s, one :class:`~bvpnav.constraints.Odometer` item with
  sigma ``speed_sigma`` (m/s; required: the message has no covariance).

Odometer items measure along body x at the point ``odometer_lever`` ([x, y, z] in m, body
axes, default the IMU itself): the reader does not read ``/tf``, so state the offset of the
odometry frame from the IMU there.

Time: ``stamp = "header"`` (default: ``header.stamp``, the sensor's clock) or
``"receive"`` (the bag's record time). Stamps are integer nanoseconds, converted by
:func:`bvpnav.timebase.to_seconds` exactly; ``t = 0`` is the first IMU stamp, stated as
``time_origin = "<ns> ns"`` since the Unix epoch (ROS time). GNSS and odometry item
times are on the same clock, relative to the same first IMU stamp; items outside the
IMU window are dropped and counted in the notes. Stamps of a topic that do not strictly
increase are refused, naming the topic and message index.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError
from . import Reader, Recording, register_reader

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from ..simulate import Simulation

__all__ = ["RosbagReader", "ExampleBag", "write_example_bag", "IMU_TYPE", "NAVSATFIX_TYPE", "ODOMETRY_TYPE",
           "TWIST_STAMPED_TYPE"]

IMU_TYPE = "sensor_msgs/msg/Imu"
NAVSATFIX_TYPE = "sensor_msgs/msg/NavSatFix"
ODOMETRY_TYPE = "nav_msgs/msg/Odometry"
TWIST_STAMPED_TYPE = "geometry_msgs/msg/TwistStamped"

_ROS1_MAGIC = b"#ROSBAG V2.0"
_MCAP_MAGIC = b"\x89MCAP0\r\n"
_SQLITE_MAGIC = b"SQLite format 3\x00"

# ------------------------------------------------------------------ geodesy
def _geodetic_to_enu(lat, lon, h, origin: tuple[float, float, float]) -> np.ndarray:
    """Local ENU (m, shape (K, 3)) of WGS-84 points about ``origin`` (lat deg, lon deg, h m),
    by :func:`bvpnav.geodesy.geodetic_to_local` (pymap3d)."""
    from ..geodesy import geodetic_to_local

    return geodetic_to_local(lat, lon, h, origin, "enu")


def _enu_to_geodetic(enu, origin: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of :func:`_geodetic_to_enu`: (lat deg, lon deg, h m)."""
    from ..geodesy import local_to_geodetic

    return local_to_geodetic(np.atleast_2d(enu), origin, "enu")


# --------------------------------------------------------------------------- options
def _topic_option(value: Any, name: str) -> str | None | bool:
    """A topic option: a topic name, ``False`` (none) or None (automatic)."""
    if value is None or value is False or (isinstance(value, str) and value.startswith("/")):
        return value
    raise InputError(f'[input] {name} = {value!r}: give a topic name such as "/imu/data" (starting with /)'
                     + (", or false for none" if name != "topic" else ""))


def _sigma_option(value: Any, name: str) -> np.ndarray | None:
    if value is None:
        return None
    v = np.asarray(value, dtype=float) if not isinstance(value, (bool, str)) else np.array([np.nan])
    if v.ndim > 1 or v.size not in (1, 3) or not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise InputError(f"[input] {name} = {value!r}: a positive standard deviation (one number, or "
                         "[east, north, up]) in the item's units")
    return np.broadcast_to(v, (3,)).astype(float)


def _origin_option(value: Any) -> tuple[float, float, float] | None:
    if value is None:
        return None
    ok = (isinstance(value, (list, tuple)) and len(value) in (2, 3)
          and all(isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a)
                  for a in value))
    if not ok or not (-90 <= value[0] <= 90 and -180 <= value[1] <= 360):
        raise InputError(f"[input] origin = {value!r}: give [latitude_deg, longitude_deg] or "
                         "[latitude_deg, longitude_deg, height_m] (WGS-84) of the local ENU origin")
    return float(value[0]), float(value[1]), float(value[2]) if len(value) == 3 else 0.0


# ------------------------------------------------------------------------ bag access
def _bag_target(path: Path) -> Path:
    """What to open: the bag folder for a folder or a storage file beside metadata.yaml."""
    if path.is_dir():
        if not (path / "metadata.yaml").is_file():
            hint = (" (it looks like a phone export: set [input] format = \"phone\")"
                    if any(path.glob("*Acceleration.csv")) else "")
            raise InputError(f"{str(path)!r}: a ROS 2 bag folder holds metadata.yaml, this one does not"
                             f"{hint}; give the bag folder, a .db3/.mcap storage file or a ROS 1 .bag file")
        return path
    if path.suffix.lower() in (".db3", ".mcap") and (path.parent / "metadata.yaml").is_file():
        return path.parent
    return path


def _typestore():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def _topics(reader) -> dict[str, str]:
    out: dict[str, str] = {}
    for c in reader.connections:
        out.setdefault(c.topic, c.msgtype)
    return out


def _listing(topics: Mapping[str, str]) -> str:
    return ", ".join(f"{k} ({v})" for k, v in sorted(topics.items())) or "none"


def _pick(topics: Mapping[str, str], msgtype: str, value, option: str, path: Path, auto: bool) -> str | None:
    """The topic of ``msgtype`` to read: the option's, else the only one (when ``auto``)."""
    if value is False:
        return None
    if isinstance(value, str):
        if value not in topics:
            raise InputError(f"{str(path)!r}: [input] {option} = {value!r} is not in the bag; its topics: "
                             f"{_listing(topics)}")
        if topics[value] != msgtype:
            raise InputError(f"{str(path)!r}: topic {value!r} is {topics[value]}, not {msgtype}; its "
                             f"topics: {_listing(topics)}")
        return value
    found = sorted(k for k, v in topics.items() if v == msgtype)
    if not auto or not found:
        return None
    if len(found) > 1:
        raise InputError(f"{str(path)!r}: {len(found)} {msgtype} topics ({', '.join(found)}); choose one "
                         f"with [input] {option} = \"...\" (topics: {_listing(topics)})")
    return found[0]


def _read_messages(reader, wanted: Mapping[str, str], path: Path) -> dict[str, list[tuple[int, Any]]]:
    """Deserialized messages per topic: lists of (receive time ns, message), bag order."""
    out: dict[str, list[tuple[int, Any]]] = {t: [] for t in wanted}
    conns = [c for c in reader.connections if c.topic in wanted]
    topic, k = None, -1
    try:
        for conn, stamp, raw in reader.messages(connections=conns):
            topic, k = conn.topic, len(out[conn.topic])
            out[topic].append((int(stamp), reader.deserialize(raw, conn.msgtype)))
    except InputError:
        raise
    except Exception as exc:  # noqa: BLE001 - any failure of the storage or decoder names the file
        where = f" at message {k + 1} of topic {topic}" if topic is not None else ""
        raise InputError(f"{str(path)!r}: the bag is corrupt or truncated{where} ({type(exc).__name__}: "
                         f"{_first_line(exc)}); re-record or repair it (ros2 bag reindex)") from None
    return out


def _first_line(exc: BaseException) -> str:
    s = str(exc).strip()
    return s.splitlines()[0] if s else "no message"


def _stamp_ns(recv: int, msg, stamp: str) -> int:
    if stamp == "receive":
        return recv
    st = msg.header.stamp
    return int(st.sec) * 1_000_000_000 + int(st.nanosec)


def _check_increasing(ns: np.ndarray, topic: str, path: Path, stamp: str, index=None) -> None:
    """Refuse stamps that do not strictly increase, naming the message (its index in the topic)."""
    d = np.diff(ns)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        j = int(bad[0]) + 1
        k, k0 = (j, j - 1) if index is None else (int(index[j]), int(index[j - 1]))
        how = "repeats" if d[j - 1] == 0 else "is before"
        alt = "receive" if stamp == "header" else "header"
        raise InputError(f"{str(path)!r}: topic {topic}: message {k} has {stamp} stamp {int(ns[j])} ns, "
                         f"which {how} message {k0}'s {int(ns[j - 1])} ns ({bad.size} such message(s)); the "
                         f"stamps of a topic must strictly increase (try [input] stamp = \"{alt}\")")


# ---------------------------------------------------------------------------- topics
def _imu_channels(msgs, topic: str, path: Path, stamp: str):
    """(ns, specific force, gyro, attitude or None, notes) of the Imu messages."""
    from scipy.spatial.transform import Rotation

    if len(msgs) < 3:
        raise InputError(f"{str(path)!r}: topic {topic} has {len(msgs)} message(s); at least 3 are needed")
    ns = np.array([_stamp_ns(r, m, stamp) for r, m in msgs], dtype=np.int64)
    _check_increasing(ns, topic, path, stamp)
    f = np.array([[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
                  for _, m in msgs])
    w = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z] for _, m in msgs])
    q = np.array([[m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w] for _, m in msgs])
    c0 = np.array([m.orientation_covariance[0] for _, m in msgs])
    for what, arr in (("linear_acceleration", f), ("angular_velocity", w)):
        bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        if bad.size:
            raise InputError(f"{str(path)!r}: topic {topic}: message {int(bad[0])} has a non-finite {what} "
                             f"({bad.size} message(s)); every sample needs finite values")
    notes = [f"Imu topic {topic}: linear_acceleration read as specific force (m/s^2) and angular_velocity "
             f"as gyro rates (rad/s), sensor axes of frame_id {msgs[0][1].header.frame_id!r}."]
    none = int(np.count_nonzero(c0 == -1))
    norm = np.linalg.norm(q, axis=1)
    if none:
        notes.append(f"{none} of {len(msgs)} Imu messages have orientation_covariance[0] = -1 (REP-145: no "
                     "orientation); the orientation is not used (attitude from gyro integration).")
        return ns, f, w, None, notes
    if not np.all(np.isfinite(norm) & (norm > 0.5)):
        notes.append("Some Imu orientations are zero or non-finite quaternions; the orientation is not used "
                     "(attitude from gyro integration).")
        return ns, f, w, None, notes
    notes.append("Imu orientation (x, y, z, w) used as the sensor-to-ENU attitude (REP-103/REP-145; "
                 "attitude_frame = \"enu\").")
    frame_id = str(msgs[0][1].header.frame_id)
    if frame_id.lower().endswith(("_ned", "_frd")):
        notes.append(f"frame_id {frame_id!r} names NED/FRD (z-down) axes by its REP-103 suffix, but the "
                     "orientation is read as ENU (REP-145); if it is relative to NED, set [input] "
                     "attitude_frame = \"ned\" (the frame check of the acceleration at rest tells).")
    return ns, f, w, Rotation.from_quat(q), notes


def _window(ns: np.ndarray, lo: int, hi: int, what: str, notes: list[str]) -> np.ndarray:
    inside = (ns >= lo) & (ns <= hi)
    out = int(ns.size - np.count_nonzero(inside))
    if out:
        notes.append(f"{out} of {ns.size} {what} outside the IMU window were dropped.")
    return inside


def _rel_seconds(ns: np.ndarray, ns0: int) -> np.ndarray:
    return (ns - np.int64(ns0)).astype(float) * 1e-9  # integer difference first: exact to the ns


def _gnss_item(msgs, topic: str, path: Path, stamp: str, window: tuple[int, int], opts: Mapping[str, Any],
               notes: list[str], meta: dict):
    """One Position item (local ENU, m) of the fixes, or None."""
    from bvpnav.constraints import Position

    ns = np.array([_stamp_ns(r, m, stamp) for r, m in msgs], dtype=np.int64)
    status = np.array([int(m.status.status) for _, m in msgs])
    lla = np.array([[m.latitude, m.longitude, m.altitude] for _, m in msgs], dtype=float).reshape(-1, 3)
    cov = np.array([np.asarray(m.position_covariance, float)[[0, 4, 8]] for _, m in msgs]).reshape(-1, 3)
    ctype = np.array([int(m.position_covariance_type) for _, m in msgs])
    ok = status >= 0
    if np.count_nonzero(~ok):
        notes.append(f"{int(np.count_nonzero(~ok))} of {len(msgs)} NavSatFix messages of {topic} have "
                     "status < 0 (no fix) and were dropped.")
    finite = np.all(np.isfinite(lla), axis=1)
    if np.count_nonzero(ok & ~finite):
        notes.append(f"{int(np.count_nonzero(ok & ~finite))} NavSatFix messages with non-finite coordinates "
                     "were dropped.")
    keep = ok & finite
    inside = (ns >= window[0]) & (ns <= window[1])
    if np.count_nonzero(keep & ~inside):
        notes.append(f"{int(np.count_nonzero(keep & ~inside))} of {int(np.count_nonzero(keep))} valid "
                     f"NavSatFix fixes of {topic} are outside the IMU window and were dropped.")
    keep &= inside
    if not np.any(keep):
        notes.append(f"NavSatFix topic {topic}: no fix inside the IMU window; no Position item.")
        return None
    k = np.flatnonzero(keep)
    _check_increasing(ns[k], topic, path, stamp, index=k)
    origin = _origin_option(opts.get("origin"))
    if origin is None:
        origin = (float(lla[k[0], 0]), float(lla[k[0], 1]), float(lla[k[0], 2]))
        notes.append(f"Local ENU origin: the first kept fix, lat {origin[0]:.9f} deg, lon {origin[1]:.9f} "
                     f"deg, h {origin[2]:.3f} m (set [input] origin to choose another).")
    enu = _geodetic_to_enu(lla[k, 0], lla[k, 1], lla[k, 2], origin)
    meta["geodetic_origin"] = origin
    sigma = _sigma_option(opts.get("gnss_sigma"), "gnss_sigma")
    if sigma is not None:
        sig = np.tile(sigma, (k.size, 1))
        notes.append(f"GNSS sigma from [input] gnss_sigma = {sigma.tolist()} m (the bag's covariances "
                     "ignored).")
    else:
        bad = k[(ctype[k] <= 0) | ~np.all(np.isfinite(cov[k]) & (cov[k] > 0), axis=1)]
        if bad.size:
            raise InputError(f"{str(path)!r}: topic {topic}: fix {int(bad[0])} has no usable "
                             f"position_covariance (type {int(ctype[bad[0]])}, diagonal "
                             f"{cov[bad[0]].tolist()}; "
                             f"{bad.size} such fix(es)); set [input] gnss_sigma = <m> (or [east, north, up])")
        sig = np.sqrt(cov[k])
        notes.append("GNSS sigma per fix from the position_covariance diagonal (east, north, up).")
    notes.append(f"NavSatFix topic {topic}: {k.size} fixes as a Position item in local ENU (x east, y north, "
                 "z up, m); use frame = \"enu\" with these items.")
    return Position(t=_rel_seconds(ns[k], window[0]), value=enu, axes=("x", "y", "z"), sigma=sig,
                    name=f"NavSatFix {topic}")


def _inside_window(msgs, topic: str, path: Path, stamp: str, window: tuple[int, int], notes: list[str],
                   kind: str, item: str):
    """``(ns, k, messages)``: every message's stamp (ns), the indices of those inside the IMU
    window (checked increasing) and those messages; None, with a note that no ``item`` is made,
    when none is inside."""
    ns = np.array([_stamp_ns(r, m, stamp) for r, m in msgs], dtype=np.int64)
    k = np.flatnonzero(_window(ns, window[0], window[1], f"{kind} messages of {topic}", notes))
    if not k.size:
        notes.append(f"{kind} topic {topic}: no message inside the IMU window; no {item} item.")
        return None
    _check_increasing(ns[k], topic, path, stamp, index=k)
    return ns, k, [msgs[i][1] for i in k]


def _odometry_item(msgs, topic: str, path: Path, stamp: str, window: tuple[int, int],
                   opts: Mapping[str, Any], notes: list[str]):
    """One Velocity item (m/s) of the odometry twists rotated into header.frame_id, or None."""
    from scipy.spatial.transform import Rotation

    from bvpnav.constraints import Velocity

    picked = _inside_window(msgs, topic, path, stamp, window, notes, "Odometry", "Velocity")
    if picked is None:
        return None
    ns, k, sel = picked
    q = np.array([[m.pose.pose.orientation.x, m.pose.pose.orientation.y, m.pose.pose.orientation.z,
                   m.pose.pose.orientation.w] for m in sel])
    norm = np.linalg.norm(q, axis=1)
    if not np.all(np.isfinite(norm) & (norm > 0.5)):
        bad = int(k[np.flatnonzero(~(np.isfinite(norm) & (norm > 0.5)))[0]])
        raise InputError(f"{str(path)!r}: topic {topic}: message {bad} has a zero or non-finite pose "
                         "orientation; the twist (child frame) cannot be rotated into the odometry frame")
    rot = Rotation.from_quat(q)
    v_child = np.array([[m.twist.twist.linear.x, m.twist.twist.linear.y, m.twist.twist.linear.z]
                        for m in sel])
    v = rot.apply(v_child)
    sigma = _sigma_option(opts.get("odometry_sigma"), "odometry_sigma")
    if sigma is not None:
        sig = np.tile(sigma, (k.size, 1))
    else:
        r = rot.as_matrix()
        c = np.array([np.asarray(m.twist.covariance, float).reshape(6, 6)[:3, :3] for m in sel])
        var = np.einsum("kij,kjl,kil->ki", r, c, r)  # diag(R C R^T)
        if not np.all(np.isfinite(var) & (var > 0)):
            raise InputError(f"{str(path)!r}: topic {topic}: the twist covariance is zero or unusable; set "
                             "[input] odometry_sigma = <m/s>")
        sig = np.sqrt(var)
    frame = sel[0].header.frame_id
    notes.append(f"Odometry topic {topic}: {k.size} twists (child_frame_id {sel[0].child_frame_id!r}) "
                 f"rotated by the pose orientation into {frame!r}, assumed to be the navigation frame (ENU), "
                 "as a Velocity item (m/s).")
    return Velocity(t=_rel_seconds(ns[k], window[0]), value=v, axes=("x", "y", "z"), sigma=sig,
                    name=f"Odometry {topic}")


def _lever_option(value: Any) -> np.ndarray:
    if value is None:
        return np.zeros(3)
    v = np.asarray(value, dtype=float) if isinstance(value, (list, tuple)) else np.array([np.nan])
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise InputError(f"[input] odometer_lever = {value!r}: give [x, y, z], the odometry point's position "
                         "relative to the IMU in body axes, m")
    return v


def _odometer_item(msgs, topic: str, path: Path, stamp: str, window: tuple[int, int],
                   opts: Mapping[str, Any], notes: list[str], twist_stamped: bool):
    """One Odometer item (m/s along body x) of an Odometry topic's forward twist or of a
    TwistStamped wheel-speed topic, or None."""
    from bvpnav.constraints import Odometer

    what = "TwistStamped" if twist_stamped else "Odometry"
    picked = _inside_window(msgs, topic, path, stamp, window, notes, what, "Odometer")
    if picked is None:
        return None
    ns, k, sel = picked
    tw = [m.twist if twist_stamped else m.twist.twist for m in sel]
    speed = np.array([float(w.linear.x) for w in tw])
    bad = np.flatnonzero(~np.isfinite(speed))
    if bad.size:
        raise InputError(f"{str(path)!r}: topic {topic}: message {int(k[bad[0]])} has a non-finite forward "
                         f"speed twist.linear.x = {speed[bad[0]]!r} ({bad.size} such message(s)); repair or "
                         "drop them")
    option = "speed_sigma" if twist_stamped else "odometry_sigma"
    given = _sigma_option(opts.get(option), option)
    if given is not None:
        sig = np.full(k.size, float(given[0]))
        src = f"[input] {option} = {float(given[0]):g} m/s"
    elif twist_stamped:
        raise InputError(f"{str(path)!r}: topic {topic} ({TWIST_STAMPED_TYPE}) carries no covariance; set "
                         "[input] speed_sigma = <m/s> (the wheel speed's noise)")
    else:
        var = np.array([float(np.asarray(m.twist.covariance, float)[0]) for m in sel])
        if not np.all(np.isfinite(var) & (var > 0)):
            i = int(k[np.flatnonzero(~(np.isfinite(var) & (var > 0)))[0]])
            cov0 = float(np.asarray(msgs[i][1].twist.covariance, float)[0])
            raise InputError(f"{str(path)!r}: topic {topic}: message {i} has twist covariance[0] = {cov0!r}, "
                             "no usable variance of the forward speed; set [input] odometry_sigma = <m/s>")
        sig = np.sqrt(var)
        src = "the twist covariance's first entry"
    lever = _lever_option(opts.get("odometer_lever"))
    notes.append(f"{what} topic {topic}: {k.size} forward speeds (twist.linear.x, m/s) as an Odometer item "
                 f"along body x at the lever {lever.tolist()} m, sigma from {src}; add "
                 "[[error_model]] type = \"odometer_scale\" to estimate its scale factor.")
    return Odometer(t=_rel_seconds(ns[k], window[0]), speed=speed, lever=lever, sigma=sig,
                    name=f"{'wheel speed' if twist_stamped else 'Odometry'} {topic}")


# ---------------------------------------------------------------------------- reader
class RosbagReader(Reader):
    """ROS 1 / ROS 2 bags: an Imu topic, optional NavSatFix and Odometry topics.

    Options: ``topic``, ``gnss_topic``, ``odometry_topic``, ``odometry_as`` (``"velocity"`` or
    ``"odometer"``), ``speed_topic``, ``stamp`` (``"header"`` or ``"receive"``), ``origin``
    ([lat deg, lon deg, h m]), ``gnss_sigma`` (m), ``odometry_sigma`` and ``speed_sigma``
    (m/s), ``odometer_lever`` ([x, y, z] m). See the module documentation.
    """

    name = "rosbag"
    suffixes = (".bag", ".mcap", ".db3", "/")
    options = frozenset({"topic", "gnss_topic", "odometry_topic", "stamp", "origin", "gnss_sigma",
                         "odometry_sigma", "odometry_as", "speed_topic", "speed_sigma", "odometer_lever"})
    modules = ("rosbags", "pymap3d")
    extra = "ros"
    description = "ROS 1 .bag / ROS 2 bag (folder, .db3, .mcap): Imu, NavSatFix and Odometry topics"

    def sniff(self, head: bytes) -> bool:
        """ROS 1, MCAP or SQLite magic bytes (or a folder listing naming metadata.yaml)."""
        return (head.startswith((_ROS1_MAGIC, _MCAP_MAGIC, _SQLITE_MAGIC))
                or b"metadata.yaml" in head.split(b"\n"))

    def read(self, path: Path, options: Mapping[str, Any]) -> Recording:
        from rosbags.highlevel import AnyReader

        path = Path(path)
        stamp = options.get("stamp", "header")
        if stamp not in ("header", "receive"):
            raise InputError(f"[input] stamp = {stamp!r}: \"header\" (header.stamp, the sensor's clock) or "
                             "\"receive\" (the bag's record time)")
        opts = {k: _topic_option(options.get(k), k) for k in ("topic", "gnss_topic", "odometry_topic",
                                                              "speed_topic")}
        _origin_option(options.get("origin"))
        if options.get("odometry_as", "velocity") not in ("velocity", "odometer"):
            raise InputError(f"[input] odometry_as = {options.get('odometry_as')!r}: \"velocity\" (the twist "
                             "rotated into the navigation frame) or \"odometer\" (its forward speed, with a "
                             "scale factor to estimate)")
        _lever_option(options.get("odometer_lever"))
        target = _bag_target(path)
        try:
            with AnyReader([target], default_typestore=_typestore()) as reader:
                topics = _topics(reader)
                imu = _pick(topics, IMU_TYPE, opts["topic"], "topic", path, auto=True)
                if imu is None:
                    raise InputError(f"{str(path)!r}: no {IMU_TYPE} topic; its topics: {_listing(topics)}")
                gnss = _pick(topics, NAVSATFIX_TYPE, opts["gnss_topic"], "gnss_topic", path, auto=True)
                odom = _pick(topics, ODOMETRY_TYPE, opts["odometry_topic"], "odometry_topic", path,
                             auto=False)
                speed = _pick(topics, TWIST_STAMPED_TYPE, opts["speed_topic"], "speed_topic", path,
                              auto=False)
                wanted = {t: topics[t] for t in (imu, gnss, odom, speed) if t is not None}
                msgs = _read_messages(reader, wanted, path)
        except InputError:
            raise
        except Exception as exc:  # noqa: BLE001 - rosbags raises many types for damaged files
            raise InputError(f"{str(path)!r}: cannot open the bag ({type(exc).__name__}: "
                             f"{_first_line(exc)}); is it a complete ROS 1 .bag, ROS 2 bag folder, .db3 or "
                             ".mcap file?") from None
        return self._recording(path, msgs, imu, gnss, (odom, speed), stamp, options, topics)

    def _recording(self, path, msgs, imu, gnss, odometry, stamp, options, topics) -> Recording:
        from ..timebase import to_seconds

        ns, f, w, att, notes = _imu_channels(msgs[imu], imu, path, stamp)
        t, origin = to_seconds(ns, "ns")
        notes.insert(0, f"Times: {stamp} stamps in integer ns; t = 0 at the first Imu stamp ({origin} since "
                        "the Unix epoch, ROS time); every item is on this clock.")
        odom, speed = odometry
        meta: dict = {"topics": dict(topics), "imu_topic": imu, "gnss_topic": gnss, "odometry_topic": odom,
                      "speed_topic": speed,
                      "stamp": stamp, "frame_id": msgs[imu][0][1].header.frame_id,
                      "first_stamp_ns": int(ns[0]), "frame": "enu"}
        window = (int(ns[0]), int(ns[-1]))
        items = []
        if gnss is not None:
            item = _gnss_item(msgs[gnss], gnss, path, stamp, window, options, notes, meta)
            items += [item] if item is not None else []
        if odom is not None:
            if options.get("odometry_as", "velocity") == "odometer":
                item = _odometer_item(msgs[odom], odom, path, stamp, window, options, notes, False)
            else:
                item = _odometry_item(msgs[odom], odom, path, stamp, window, options, notes)
            items += [item] if item is not None else []
        if speed is not None:
            item = _odometer_item(msgs[speed], speed, path, stamp, window, options, notes, True)
            items += [item] if item is not None else []
        return Recording(t=t, source=f"{path} (topic {imu})", time_origin=origin, specific_force=f, gyro=w,
                         attitude=att, attitude_frame="enu" if att is not None else None, items=tuple(items),
                         notes=tuple(notes), meta=meta)

    def example(self, folder: Path) -> Path:
        """A 2 s ROS 2 bag (sqlite3) with Imu and NavSatFix topics; its ``.db3`` file."""
        bag = write_example_bag(Path(folder) / "example_bag", duration=2.0, rate=50.0, gnss_rate=2.0)
        return bag.storage_file


# --------------------------------------------------------------------------- example
@dataclass(frozen=True, eq=False)
class ExampleBag:
    """A bag written by :func:`write_example_bag` and the truth it was generated from.

    Attributes
    ----------
    path : Path
        The ROS 2 bag folder (holds ``metadata.yaml``).
    storage_file : Path
        Its storage file (``.db3`` or ``.mcap``).
    truth : pandas.DataFrame
        Index ``t`` (s from the first Imu header stamp): true ``x, y, z`` (m, local ENU about
        ``origin``), ``vx, vy, vz`` (m/s), ``ax, ay, az`` (m/s^2) at the Imu samples.
    origin : tuple of float
        Geodetic origin of the local ENU frame: latitude (deg), longitude (deg), height (m).
    start_ns : int
        The first Imu header stamp, ns since the Unix epoch.
    gnss_t : ndarray
        Header times of the NavSatFix messages, s from ``start_ns`` (some outside the window).
    gnss_status : ndarray
        Their ``status.status`` (-1 for the one no-fix message).
    simulation : bvpnav.simulate.Simulation
        The strapdown simulation (true attitude, error-free sensor values).
    """

    path: Path
    storage_file: Path
    truth: pd.DataFrame
    origin: tuple[float, float, float]
    start_ns: int
    gnss_t: np.ndarray
    gnss_status: np.ndarray
    simulation: Simulation


def _example_motion(duration: float):
    from ..simulate import Motion

    shape = np.random.default_rng(145)
    tw = np.arange(int(round(duration)) + 1, dtype=float)
    steps = shape.normal(0.0, 1.0, size=(tw.size, 3)) * [1.0, 1.0, 0.2]
    steps[0] = 0.0
    pos = np.cumsum(steps, axis=0)
    pos[-1] = pos[-2]
    yaw = 0.8 * np.sin(2 * np.pi * tw / max(duration, 1.0)) + 0.3
    pitch = 0.2 * np.sin(1.7 * tw)
    roll = 0.25 * np.sin(1.1 * tw + 0.4)
    return Motion.from_waypoints(tw, pos, np.column_stack([yaw, pitch, roll]))


def _msg_header(types, ns: int, frame: str):
    return types["std_msgs/msg/Header"](stamp=types["builtin_interfaces/msg/Time"](sec=ns // 10**9,
                                                                                  nanosec=ns % 10**9),
                                        frame_id=frame)


def write_example_bag(
    path,
    duration: float = 10.0,
    rate: float = 100.0,
    with_gnss: bool = True,
    seed: int | None = 0,
    *,
    gnss_rate: float = 1.0,
    gnss_sigma: float = 0.05,
    accel_noise: float = 0.0,
    gyro_noise: float = 0.0,
    with_orientation: bool = True,
    storage: str = "sqlite3",
    origin: tuple[float, float, float] = (48.137154, 11.576124, 520.0),
    start_ns: int = 1_700_000_000_123_456_789,
) -> ExampleBag:
    """Write a ROS 2 bag of a known strapdown motion: ``/imu/data`` (and ``/gnss/fix``).

    Parameters
    ----------
    path : path-like
        The bag folder to create (must not exist).
    duration : float
        Length in s (a whole number >= 2; waypoints every 1 s).
    rate : float
        Imu rate in Hz; ``1e9 / rate`` must be a whole number of ns.
    with_gnss : bool
        Write NavSatFix messages: one per ``1 / gnss_rate`` s from 1 s before the first
        Imu sample to 1 s after the last (the vehicle rests there), one of them
        ``status = -1`` (no fix), with white ENU noise of ``gnss_sigma`` m and a diagonal
        known covariance.
    seed : int, optional
        Seed of the sensor and GNSS noise (the motion is fixed).
    gnss_rate : float
        Fixes per s.
    gnss_sigma : float
        GNSS noise standard deviation per ENU axis, m (> 0; written as the covariance).
    accel_noise, gyro_noise : float
        White noise of the specific force (m/s^2) and gyro rates (rad/s).
    with_orientation : bool
        Write the true orientation (sensor to ENU) in the Imu messages; if False, the
        quaternion is zero and ``orientation_covariance[0] = -1`` (REP-145).
    storage : {"sqlite3", "mcap"}
        The rosbag2 storage plugin.
    origin : tuple of float
        Geodetic origin of the motion's local ENU frame (lat deg, lon deg, h m).
    start_ns : int
        The first Imu header stamp, ns since the Unix epoch. Receive (record) times are the
        header stamps plus 1 to 1.2 ms (Imu) or 40 ms (GNSS).

    Returns
    -------
    ExampleBag
        The paths and the truth.

    Notes
    -----
    The motion (:mod:`bvpnav.simulate`) is a clamped cubic spline through waypoints on the
    sampling grid, so noise-free data solved by the FEM reproduce it to rounding. The
    navigation frame is ENU with gravity ``(0, 0, -9.80665)`` m/s^2.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer

    from ..simulate import SensorErrors, simulate_imu

    path = Path(path)
    dt_ns = 1e9 / rate
    if abs(dt_ns - round(dt_ns)) > 1e-6 or rate <= 0:
        raise InputError(f"rate={rate!r}: 1e9 / rate must be a whole number of ns (e.g. 50, 100, 200 Hz)")
    if gnss_sigma <= 0 or storage not in ("sqlite3", "mcap"):
        raise InputError("gnss_sigma must be > 0 m and storage 'sqlite3' or 'mcap'")
    dt_ns = int(round(dt_ns))
    motion = _example_motion(float(duration))
    sim = simulate_imu(motion, rate, accel=SensorErrors(noise=accel_noise),
                       gyro=SensorErrors(noise=gyro_noise), seed=seed)
    rng = np.random.default_rng(None if seed is None else seed + 1)
    store = _typestore()
    types = store.types
    vec, quat = types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Quaternion"]
    imu_ns = start_ns + dt_ns * np.arange(sim.t.size, dtype=np.int64)
    q = sim.attitude.as_quat()
    cov_q = np.diag([1e-4] * 3).ravel() if with_orientation else np.r_[-1.0, np.zeros(8)]
    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    T = float(sim.t[-1])
    gnss_t = np.arange(-1.0, T + 1.0 + 1e-9, 1.0 / gnss_rate) if with_gnss else np.zeros(0)
    gnss_status = np.zeros(gnss_t.size, dtype=int)
    if gnss_t.size > 3:
        gnss_status[gnss_t.size // 2] = -1
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        c_imu = writer.add_connection("/imu/data", IMU_TYPE, typestore=store)
        c_fix = writer.add_connection("/gnss/fix", NAVSATFIX_TYPE, typestore=store) if with_gnss else None
        records = []
        for k in range(sim.t.size):
            msg = types[IMU_TYPE](
                header=_msg_header(types, int(imu_ns[k]), "imu_link"),
                orientation=quat(*(q[k] if with_orientation else np.zeros(4))),
                orientation_covariance=cov_q.copy(),
                angular_velocity=vec(*sim.gyro[k]), angular_velocity_covariance=np.zeros(9),
                linear_acceleration=vec(*sim.specific_force[k]), linear_acceleration_covariance=np.zeros(9))
            records.append((int(imu_ns[k]) + 1_000_000 + (k % 3) * 100_000, c_imu, msg, IMU_TYPE))
        if with_gnss:
            enu = motion.pos(np.clip(gnss_t, 0.0, T)) + rng.normal(0.0, gnss_sigma, size=(gnss_t.size, 3))
            lat, lon, h = _enu_to_geodetic(enu, origin)
            status_t = types["sensor_msgs/msg/NavSatStatus"]
            for k, tg in enumerate(gnss_t):
                ns = start_ns + int(round(tg * 1e9))
                msg = types[NAVSATFIX_TYPE](
                    header=_msg_header(types, ns, "gnss"),
                    status=status_t(status=int(gnss_status[k]), service=1),
                    latitude=float(lat[k]), longitude=float(lon[k]), altitude=float(h[k]),
                    position_covariance=np.diag([gnss_sigma**2] * 3).ravel(), position_covariance_type=2)
                records.append((ns + 40_000_000, c_fix, msg, NAVSATFIX_TYPE))
        for recv, conn, msg, typ in sorted(records, key=lambda r: r[0]):
            writer.write(conn, recv, store.serialize_cdr(msg, typ))
    files = sorted(p for p in path.iterdir() if p.suffix in (".db3", ".mcap"))
    truth = sim.truth.copy()
    truth.index = truth.index - truth.index[0]
    return ExampleBag(path=path, storage_file=files[0], truth=truth, origin=tuple(float(o) for o in origin),
                      start_ns=int(start_ns), gnss_t=gnss_t, gnss_status=gnss_status, simulation=sim)


register_reader(RosbagReader())
