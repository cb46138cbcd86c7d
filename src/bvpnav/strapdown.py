"""From a recording's strapdown channels to navigation-frame acceleration.

A reader gives what the sensor measured, in the sensor's axes: specific force, gyro
rates, perhaps an orientation from the device. This module applies what the spec's
``[input]`` says about frames and turns it into :class:`bvpnav.ImuData`:

- ``frame``: the navigation frame, ``"enu"`` (default; axes x = east, y = north,
  z = up) or ``"ned"`` (x = north, y = east, z = down);
- ``gravity``: a magnitude in m/s^2 (default 9.80665, along "down"), a vector of three
  numbers in the navigation frame, or ``"wgs84"`` (normal gravity at ``latitude``,
  degrees, and ``height``, m above the ellipsoid: :func:`bvpnav.geodesy.normal_gravity`);
- ``body_to_sensor``: the rotation ``R`` with ``v_sensor = R v_body`` (default identity),
  as ``{ euler = [a, b, c], sequence = "xyz", degrees = true }`` or
  ``{ quaternion = [x, y, z, w], scalar = "last" }``;
- ``initial_attitude``: body-to-navigation attitude at the first sample, when the
  attitude is integrated from gyro rates (same two forms; default identity);
- ``attitude_frame``: the reference frame of an orientation given in the file
  (``"enu"`` or ``"ned"``), when the reader cannot know it;
- ``gyro_range``: the gyro's full-scale range in rad/s; samples at it are counted and
  reported (:func:`bvpnav.detect.saturation`; without it, runs flat at an axis's largest
  rate are).

Every recording's navigation-frame acceleration is checked against zero at rest
(:func:`bvpnav.detect.frame_check`): gravity counted twice, or an up axis turned
horizontal, is a :class:`bvpnav.log.FrameWarning` naming the option to set.

Conventions are those of :mod:`bvpnav.attitude`: ``C`` rotates body vectors into the
navigation frame, ``v_nav = C v_body``; rates are body rates relative to the navigation
frame (Earth rotation neglected).

Examples
--------
The navigation frame and gravity from the spec's ``[input]`` options:

>>> from bvpnav.strapdown import frame_change, gravity_vector
>>> gravity_vector({}, "enu").tolist()
[0.0, 0.0, -9.80665]
>>> gravity_vector({"gravity": 9.81}, "ned").tolist()
[0.0, 0.0, 9.81]
>>> frame_change("enu", "ned").tolist()
[[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import InputError
from .imu import STANDARD_GRAVITY, ImuData

if TYPE_CHECKING:  # pragma: no cover
    from scipy.spatial.transform import Rotation

__all__ = ["FRAME_OPTIONS", "FRAMES", "imu_data", "rotation_option", "gravity_vector", "frame_change"]

#: The ``[input]`` keys about frames and the strapdown channels (read here, not by the readers).
FRAME_OPTIONS = frozenset({"frame", "gravity", "latitude", "height", "body_to_sensor", "initial_attitude",
                           "attitude_frame", "gyro_range"})

#: Navigation frames: name -> what its axes are.
FRAMES = {"enu": "x = east, y = north, z = up", "ned": "x = north, y = east, z = down"}

#: Rotation taking ENU vectors to NED: (e, n, u) -> (n, e, -u).
_ENU_TO_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def frame_change(src: str, dst: str) -> np.ndarray:
    """The 3x3 matrix taking vectors in frame ``src`` to frame ``dst`` (``enu``/``ned``).

    Examples
    --------
    ENU to NED swaps east and north and turns up into down:

    >>> import numpy as np
    >>> from bvpnav.strapdown import frame_change
    >>> T = frame_change("enu", "ned")
    >>> (T @ [1.0, 2.0, 3.0]).tolist()  # east 1, north 2, up 3 -> north 2, east 1, down -3
    [2.0, 1.0, -3.0]
    """
    for f in (src, dst):
        if f not in FRAMES:
            raise InputError(f"frame {f!r}: valid navigation frames: {sorted(FRAMES)}")
    return np.eye(3) if src == dst else _ENU_TO_NED.copy()  # the map is its own inverse


def rotation_option(value: Any, what: str) -> Rotation:
    """A constant rotation from a spec table.

    Parameters
    ----------
    value : mapping
        ``{ euler = [a, b, c], sequence = "xyz", degrees = true }`` (scipy's
        :meth:`Rotation.from_euler`: lower-case sequence extrinsic, upper-case intrinsic;
        ``degrees`` default true) or ``{ quaternion = [x, y, z, w], scalar = "last" }``
        (``scalar = "first"`` for ``[w, x, y, z]``; unit norm to 1e-6).
    what : str
        The option's name for messages.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.strapdown import rotation_option
    >>> R = rotation_option({"euler": [0, 0, 90], "sequence": "xyz", "degrees": True}, "body_to_sensor")
    >>> (np.round(R.as_rotvec(), 6) + 0.0).tolist()
    [0.0, 0.0, 1.570796]
    >>> R2 = rotation_option({"quaternion": [0, 0, 0.7071068, 0.7071068], "scalar": "last"}, "body_to_sensor")
    >>> print(f"{np.degrees(R2.magnitude()):.3f}")
    90.000
    """
    from scipy.spatial.transform import Rotation

    form = 'give { euler = [a, b, c], sequence = "xyz", degrees = true } or { quaternion = [x, y, z, w], ' \
           'scalar = "last" }'
    if not isinstance(value, Mapping) or not ({"euler", "quaternion"} & set(value)):
        raise InputError(f"[input] {what} = {value!r}: {form}")
    if "euler" in value:
        extra = sorted(set(value) - {"euler", "sequence", "degrees"})
        angles, seq, deg = value["euler"], value.get("sequence", "xyz"), value.get("degrees", True)
        ok = (isinstance(angles, (list, tuple)) and len(angles) == 3
              and all(isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a)
                      for a in angles))
        if extra or not ok or not isinstance(deg, bool) or not _valid_sequence(seq):
            raise InputError(f"[input] {what} = {dict(value)!r}: {form} (three finite angles; sequence of "
                             "three axes from x, y, z, all lower case (extrinsic) or all upper case "
                             "(intrinsic); degrees = true or false)")
        return Rotation.from_euler(seq, [float(a) for a in angles], degrees=deg)
    extra = sorted(set(value) - {"quaternion", "scalar"})
    q, scalar = value["quaternion"], value.get("scalar", "last")
    ok = (isinstance(q, (list, tuple)) and len(q) == 4
          and all(isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a) for a in q))
    if extra or not ok or scalar not in ("first", "last"):
        raise InputError(f"[input] {what} = {dict(value)!r}: {form} (four finite numbers; scalar = \"first\" "
                         "or \"last\")")
    q = np.asarray(q, dtype=float)
    if scalar == "first":
        q = np.roll(q, -1)
    if abs(np.linalg.norm(q) - 1.0) > 1e-6:
        raise InputError(f"[input] {what}: quaternion {value['quaternion']} has norm "
                         f"{np.linalg.norm(q):.6g}, not 1; give a unit quaternion")
    return Rotation.from_quat(q)


def _valid_sequence(seq: Any) -> bool:
    return (isinstance(seq, str) and len(seq) == 3 and (seq.islower() or seq.isupper())
            and set(seq.lower()) <= set("xyz") and seq[0].lower() != seq[1].lower()
            and seq[1].lower() != seq[2].lower())


def gravity_vector(options: Mapping[str, Any], frame: str) -> np.ndarray:
    """Gravity in the navigation frame, m/s^2, from ``gravity`` (and ``latitude``, ``height``).

    Notes
    -----
    A magnitude ``g`` points down: :math:`(0, 0, -g)` in ENU, :math:`(0, 0, g)` in NED.
    ``"wgs84"`` is the normal gravity of the WGS-84 ellipsoid at the given latitude and
    height (:func:`bvpnav.geodesy.normal_gravity`).

    Examples
    --------
    >>> from bvpnav.strapdown import gravity_vector
    >>> gravity_vector({"gravity": "wgs84", "latitude": 45.0, "height": 0.0}, "enu").round(5).tolist()
    [0.0, 0.0, -9.8062]
    >>> gravity_vector({"gravity": [0.0, 0.01, -9.8]}, "enu").tolist()
    [0.0, 0.01, -9.8]
    """
    g = options.get("gravity", STANDARD_GRAVITY)
    lat, h = options.get("latitude"), options.get("height")
    if g == "wgs84":
        if not isinstance(lat, (int, float)) or isinstance(lat, bool) or not -90 <= lat <= 90:
            raise InputError(f'[input] gravity = "wgs84" needs latitude (degrees, -90..90), got {lat!r}: add '
                             "latitude = <deg> (and height = <m>)")
        if h is None:
            h = 0.0
        if not isinstance(h, (int, float)) or isinstance(h, bool) or not math.isfinite(h):
            raise InputError(f"[input] height = {h!r}: give the height above the WGS-84 ellipsoid in m")
        from .geodesy import normal_gravity

        g = normal_gravity(float(lat), float(h))
    elif lat is not None or h is not None:
        raise InputError('[input] latitude/height only go with gravity = "wgs84" (normal gravity there); '
                         "drop them or set gravity = \"wgs84\"")
    if isinstance(g, (int, float)) and not isinstance(g, bool):
        if not (math.isfinite(g) and 9.7 <= g <= 9.9):
            raise InputError(f"[input] gravity = {g!r}: a magnitude in m/s^2 near the Earth's (9.78..9.84); "
                             "give e.g. 9.80665, a vector [gx, gy, gz], or \"wgs84\"")
        return np.array([0.0, 0.0, -float(g) if frame == "enu" else float(g)])
    ok = (isinstance(g, (list, tuple)) and len(g) == 3
          and all(isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a) for a in g))
    if not ok:
        raise InputError(f"[input] gravity = {g!r}: give a magnitude in m/s^2 (e.g. 9.80665), a vector "
                         "[gx, gy, gz] in the navigation frame, or \"wgs84\" with latitude and height")
    return np.asarray(g, dtype=float)


def imu_data(rec: Any, options: Mapping[str, Any], initial_attitude: Rotation | None = None) -> ImuData:
    r""":class:`bvpnav.ImuData` from a :class:`~bvpnav.readers.Recording` and the frame options.

    Parameters
    ----------
    rec : bvpnav.readers.Recording
        The reader's output (this module sits below the readers, so the type is not
        imported here).
    options : mapping
        The ``[input]`` keys of :data:`FRAME_OPTIONS`; others are ignored.
    initial_attitude : scipy.spatial.transform.Rotation, optional
        Body-to-navigation attitude at the first sample for an attitude integrated from
        gyro rates, instead of ``options["initial_attitude"]`` (the spec's ``[align]``
        computes it: :func:`bvpnav.align.align_recording`); refused beside that option.

    Returns
    -------
    ImuData

    Notes
    -----
    With ``R`` the body-to-sensor rotation (:math:`v_s = R v_b`), the body-frame specific
    force and rates are :math:`f_b = R^T f_s`, :math:`\omega_b = R^T \omega_s`. With an
    orientation :math:`C_{rs}` from the file (sensor to its reference frame r) the
    body-to-navigation attitude is :math:`C_{nb} = T_{nr} C_{rs} R` (:math:`T_{nr}` the
    fixed ENU/NED change); otherwise it is integrated from :math:`\omega_b` starting at
    ``initial_attitude``. Then :math:`a = C_{nb} f_b + g`.

    Examples
    --------
    A level triad at rest (specific force +g on z, up) in the default ENU frame:

    >>> import numpy as np
    >>> from bvpnav.readers import Recording
    >>> from bvpnav.strapdown import imu_data
    >>> rec = Recording(t=np.linspace(0.0, 1.0, 11), source="example",
    ...                 specific_force=np.tile([0.0, 0.0, 9.80665], (11, 1)), gyro=np.zeros((11, 3)))
    >>> data = imu_data(rec, {})
    >>> data
    ImuData(N=11, axes=('x', 'y', 'z'), strapdown, t=[0, 1] s)
    >>> (np.round(data.acc[0], 9) + 0.0).tolist()  # at rest: no acceleration
    [0.0, 0.0, 0.0]
    """
    from scipy.spatial.transform import Rotation

    used = {k: v for k, v in options.items() if k in FRAME_OPTIONS}
    if rec.acc is None and rec.specific_force is None:
        kinds = ", ".join(sorted({type(i).__name__ for i in rec.items})) or "nothing"
        raise InputError(f"{rec.source} holds information only ({kinds}), no IMU samples: solve a "
                         "recording of IMU samples and give this file beside it (bvpnav solve RECORDING "
                         "--info FILE; in Python: bvpnav.readers.align(info, recording))")
    if not rec.is_strapdown:
        if used:
            raise InputError(f"{rec.source}: [input] {sorted(used)} describe strapdown data (specific force "
                             "and gyro/attitude), but the recording is navigation-frame acceleration; drop "
                             "them, or name the specific-force columns")
        return ImuData(t=rec.t, acc=rec.acc, axes=rec.axes, time_origin=rec.time_origin)
    frame = used.get("frame", "enu")
    if not isinstance(frame, str) or frame not in FRAMES:
        raise InputError(f"[input] frame = {frame!r}: valid navigation frames: "
                         + ", ".join(f"{k!r} ({v})" for k, v in FRAMES.items()))
    g = gravity_vector(used, frame)
    mount = (rotation_option(used["body_to_sensor"], "body_to_sensor") if "body_to_sensor" in used
             else Rotation.identity())
    f_b = mount.inv().apply(rec.specific_force)
    if rec.attitude is not None:
        ref = used.get("attitude_frame", rec.attitude_frame)
        if not isinstance(ref, str) or ref not in FRAMES:
            raise InputError(f"{rec.source}: the orientation's reference frame is {ref!r}; set [input] "
                             "attitude_frame = \"enu\" or \"ned\" (what the device's orientation is "
                             "relative to)")
        if "initial_attitude" in used:
            raise InputError(f"{rec.source}: the file gives the orientation; initial_attitude is for "
                             "attitudes integrated from gyro rates: drop it")
        change = Rotation.from_matrix(frame_change(ref, frame))
        c_nb = change * rec.attitude * mount
        data = ImuData(t=rec.t, specific_force=f_b, attitude=c_nb, gravity=g, time_origin=rec.time_origin,
                       checks=False)
        if rec.gyro is not None:
            w = mount.inv().apply(rec.gyro)
            w.setflags(write=False)
            data.gyro = w
        return _checked(data, rec, used, _orientation_fixes(ref, "attitude_frame" in used))
    if "attitude_frame" in used:
        raise InputError(f"{rec.source}: [input] attitude_frame says what a file's orientation is "
                         "relative to, but this recording has no orientation (the attitude is integrated "
                         "from the gyro rates, starting at initial_attitude in the navigation frame): drop "
                         "attitude_frame")
    if rec.gyro is None:
        raise InputError(f"{rec.source}: specific force without an attitude or gyro rates; give the gyro "
                         "columns ([input] gyro = [...]) or the orientation ([input] attitude = {...})")
    if initial_attitude is not None and "initial_attitude" in used:
        raise InputError("[input] initial_attitude and [align] both give the attitude at the first sample: "
                         "keep one (drop initial_attitude to align from the rest interval, or drop [align])")
    c0 = (rotation_option(used["initial_attitude"], "initial_attitude") if "initial_attitude" in used
          else initial_attitude)
    data = ImuData.from_gyro(rec.t, f_b, mount.inv().apply(rec.gyro), initial_attitude=c0, gravity=g,
                             checks=False)
    data.time_origin = rec.time_origin
    return _checked(data, rec, used, _integration_fixes(frame))


def _checked(data: ImuData, rec: Any, used: Mapping[str, Any], fixes: dict) -> ImuData:
    """``data`` after the frame check and, with gyro rates, the saturation count (both kept in
    ``data.checks``, each warning once)."""
    if "gyro_range" in used:
        r = used["gyro_range"]
        if isinstance(r, bool) or not isinstance(r, (int, float)) or not (math.isfinite(r) and r > 0):
            raise InputError(f"[input] gyro_range = {r!r}: the gyro's full-scale range in rad/s (e.g. 34.9 "
                             "for 2000 deg/s)")
        if data.gyro is None:
            raise InputError(f"{rec.source}: [input] gyro_range is given but the recording has no gyro "
                             "rates; drop it")
    if data.gyro is not None:
        data.check_saturation(used.get("gyro_range"), source=rec.source)
    data.check_frame(fixes, source=rec.source)
    return data


def _orientation_fixes(ref: str, stated: bool) -> dict:
    other = "enu" if ref == "ned" else "ned"
    said = "as given by attitude_frame" if stated else "the reader's convention"
    return {
        "gravity twice": (f"The file's orientation was read as relative to {ref.upper()} ({said}); if it is "
                          f"relative to {other.upper()} (e.g. forward-right-down body axes with a NED "
                          f"orientation, or the reverse), set [input] attitude_frame = \"{other}\"."),
        "gravity horizontal": ("Check [input] attitude (its column order, scalar = \"first\" or \"last\") "
                               "and body_to_sensor."),
        "gravity missing": ("Give the accelerometer's specific force with gravity in it (what the sensor "
                            "measures), not a linear or user acceleration."),
    }


def _integration_fixes(frame: str) -> dict:
    other = "enu" if frame == "ned" else "ned"
    axes = "z-down (forward-right-down)" if other == "ned" else "z-up (forward-left-up)"
    return {
        "gravity twice": (f"If the sensor's axes are {axes}, set [input] frame = \"{other}\"; otherwise "
                          "give the attitude at the first sample, [input] initial_attitude."),
        "gravity horizontal": ("Give the attitude at the first sample ([input] initial_attitude) and check "
                               "the gyro and specific_force column order and body_to_sensor."),
        "gravity missing": ("Give the accelerometer's specific force with gravity in it (what the sensor "
                            "measures), not a linear or user acceleration."),
    }
