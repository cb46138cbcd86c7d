r"""Initial alignment: roll and pitch from a stationary interval, heading from the motion.

Frames (the conventions of :mod:`bvpnav.attitude` and :mod:`bvpnav.strapdown`):

- navigation frame ``"enu"`` (default; x = east, y = north, z = up, gravity
  :math:`g = (0, 0, -g_0)`) or ``"ned"`` (x = north, y = east, z = down,
  :math:`g = (0, 0, +g_0)`);
- body frame: the axes x, y, z of the accelerometer and gyro triad (usually x forward;
  y left and z up for ENU users, y right and z down for NED users);
- the attitude ``C`` rotates body vectors into the navigation frame,
  :math:`v_n = C v_b` (scipy ``Rotation.apply``), with Euler angles

  .. math:: C = R_z(\psi)\, R_y(\theta)\, R_x(\phi)

  (scipy ``Rotation.from_euler("ZYX", [yaw, pitch, roll])``): roll :math:`\phi` about
  body x, pitch :math:`\theta` about the once-rotated y, yaw :math:`\psi` about the
  navigation z axis. In ENU the yaw is counterclockwise from east about up (0 = body x
  pointing east, +90 deg = north); in NED it is the aerospace heading, clockwise from
  north about down (0 = north, +90 deg = east). The formula is the same in both
  frames, only the axes differ;
- gravity sign: an accelerometer at rest measures the specific force
  :math:`f_b = C^T (a - g) = -C^T g`, i.e. :math:`+g_0` on the axis that points up
  (a level triad reads (0, 0, +9.81) with z up and (0, 0, -9.81) with z down).

One physical attitude in both frames: with body axes x forward, y left, z up (FLU) for
ENU and x forward, y right, z down (FRD) for NED,
:math:`C_{ned} = T\, C_{enu}\, B` with :math:`T` the ENU-to-NED change
:math:`(e, n, u) \to (n, e, -u)` and :math:`B = \mathrm{diag}(1, -1, -1)`, and the
angles are related by :math:`\phi_{ned} = \phi_{enu}`,
:math:`\theta_{ned} = -\theta_{enu}`, :math:`\psi_{ned} = \pi/2 - \psi_{enu}`
(positive pitch is nose *down* about the left axis, nose *up* about the right axis).
For the *same* body triad in both frames, :math:`C_{ned} = T\, C_{enu}`.

Examples
--------
A triad at rest, rolled by -0.01 rad, pitched by 0.02 rad, heading 0.3 rad counterclockwise
from east (ENU); the accelerometer gives roll and pitch, a known heading completes it:

>>> import numpy as np
>>> from scipy.spatial.transform import Rotation
>>> C = Rotation.from_euler("ZYX", [0.3, 0.02, -0.01])  # yaw, pitch, roll (rad)
>>> f = np.tile(C.inv().apply([0.0, 0.0, 9.80665]), (21, 1))  # at rest: -C^T g (m/s^2)
>>> from bvpnav.align import align
>>> C0 = align(np.linspace(0.0, 2.0, 21), f, stationary=(0.0, 2.0), yaw=0.3)
>>> (np.round(C0.as_euler("ZYX"), 6) + 0.0).tolist()
[0.3, 0.02, -0.01]
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from .errors import InputError
from .imu import STANDARD_GRAVITY
from .strapdown import FRAMES

if TYPE_CHECKING:  # pragma: no cover
    from scipy.spatial.transform import Rotation

__all__ = ["roll_pitch_from_stationary", "heading_from_positions", "heading_from_velocity",
           "initial_attitude", "attitude_angles", "align", "align_recording", "HEADINGS"]

#: The heading sources of :func:`align_recording` (and the spec's ``[align] heading``)
#: besides a number in degrees.
HEADINGS = {"fixes": "the direction of travel between the first position fixes min_distance apart",
            "search": "0 to start from; the solve searches it (needs an attitude_error model)"}

#: Relative departure of the mean specific force's magnitude from g accepted as "at rest".
GRAVITY_TOLERANCE = 0.05
#: Mean gyro rate over a rest interval above which :func:`align_recording` warns that the
#: sensor turns there, rad/s (0.57 deg/s: above consumer gyro biases, 5e-3 rad/s; a car's
#: gentle curve at 15 m/s turning this fast pulls about 0.9 deg into the roll).
REST_RATE = 0.01


def _frame(frame: Any) -> str:
    if not isinstance(frame, str) or frame.lower() not in FRAMES:
        raise InputError(f"frame={frame!r}: valid navigation frames: "
                         + ", ".join(f"{k!r} ({v})" for k, v in FRAMES.items()))
    return frame.lower()


def _up_sign(frame: str) -> float:
    """+1 when the navigation z axis points up (ENU), -1 when it points down (NED)."""
    return 1.0 if frame == "enu" else -1.0


def _array(value: Any, what: str, unit: str) -> np.ndarray:
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{what}: cannot be read as numbers; give an array in {unit}") from None
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        raise InputError(f"{what}: entry {tuple(int(i) for i in bad[0])} is {float(a[tuple(bad[0])])!r}; "
                         "every value must be finite. Remove or repair that sample.")
    return a


def roll_pitch_from_stationary(specific_force, frame: str = "enu", *, gravity: float = STANDARD_GRAVITY,
                               tolerance: float = GRAVITY_TOLERANCE) -> tuple[float, float]:
    r"""Roll and pitch of a triad at rest from its mean specific force.

    Parameters
    ----------
    specific_force : array_like, shape (N, 3) or (3,)
        Body-frame specific force in m/s^2 during a stationary interval (averaged over
        the rows), or its mean.
    frame : {"enu", "ned"}
        Navigation frame the angles refer to (see the module's conventions).
    gravity : float
        Magnitude of gravity, m/s^2 (default 9.80665), for the plausibility check only.
    tolerance : float
        Accepted relative departure of :math:`|\bar f|` from ``gravity`` (default 0.05).

    Returns
    -------
    (roll, pitch) : tuple of float
        rad, with :math:`C = R_z(\psi) R_y(\theta) R_x(\phi)`; roll in
        :math:`(-\pi, \pi]`, pitch in :math:`[-\pi/2, \pi/2]`.

    Raises
    ------
    InputError
        When the mean specific force is not about ``gravity`` in magnitude (the interval
        is not at rest, or the values are not in m/s^2).

    Notes
    -----
    At rest :math:`f = -C^T g = s\, g_0\, C^T e_z` with :math:`s = +1` in ENU (z up)
    and :math:`s = -1` in NED (z down); with :math:`C = R_z R_y R_x`,

    .. math:: s\, \bar f / g_0 = (-\sin\theta,\ \sin\phi\cos\theta,\ \cos\phi\cos\theta),

    so :math:`\phi = \operatorname{atan2}(s \bar f_y, s \bar f_z)` and
    :math:`\theta = \operatorname{atan2}(-s \bar f_x, \sqrt{\bar f_y^2 + \bar f_z^2})`.
    The yaw does not enter (gravity is along the yaw axis). Exact for a noise-free
    triad at rest; an accelerometer bias :math:`b` tilts the answer by about
    :math:`|b_{xy}|/g_0` rad.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> C = Rotation.from_euler("ZYX", [0.3, 0.02, -0.01])  # yaw, pitch, roll (rad)
    >>> f = np.tile(C.inv().apply([0.0, 0.0, 9.80665]), (21, 1))  # at rest: -C^T g (m/s^2)
    >>> from bvpnav.align import roll_pitch_from_stationary
    >>> roll, pitch = roll_pitch_from_stationary(f)
    >>> print(f"roll {roll:.4f} rad, pitch {pitch:.4f} rad")
    roll -0.0100 rad, pitch 0.0200 rad
    """
    fr = _frame(frame)
    f = _array(specific_force, "specific_force", "m/s^2")
    if f.ndim == 2 and f.shape[1] == 3 and f.shape[0] >= 1:
        f = f.mean(axis=0)
    if f.shape != (3,):
        raise InputError(f"specific_force: shape {f.shape}; give the stationary samples (N, 3) or their "
                         "mean (3,), body x, y, z in m/s^2")
    if not (isinstance(gravity, (int, float)) and math.isfinite(gravity) and gravity > 0):
        raise InputError(f"gravity={gravity!r}: give the magnitude of gravity in m/s^2 (e.g. 9.80665)")
    if not (isinstance(tolerance, (int, float)) and 0 < tolerance < 1):
        raise InputError(f"tolerance={tolerance!r}: a relative tolerance between 0 and 1 (e.g. 0.05)")
    norm = float(np.linalg.norm(f))
    if abs(norm - gravity) > tolerance * gravity:
        hint = (" (it looks like units of g: multiply by 9.80665)" if abs(norm - 1.0) < 0.1 else
                " (it looks like units of mg: multiply by 0.00980665)" if abs(norm - 1000.0) < 100 else "")
        raise InputError(f"specific_force: the mean specific force has magnitude {norm:.4g} m/s^2, not "
                         f"about g = {gravity:.6g} (tolerance {100 * tolerance:g} %){hint}; roll and pitch "
                         "need an interval at rest: choose samples where the sensor does not move, in m/s^2")
    s = _up_sign(fr)
    fx, fy, fz = s * f
    roll = math.atan2(fy, fz)
    pitch = math.atan2(-fx, math.hypot(fy, fz))
    return roll, pitch


def _horizontal(values: np.ndarray, what: str) -> np.ndarray:
    if values.ndim != 2 or values.shape[1] not in (2, 3):
        raise InputError(f"{what}: shape {values.shape}; give (N, 2) or (N, 3) navigation-frame values "
                         "(x, y[, z]) in the frame's axes")
    return values[:, :2]


def heading_from_positions(t, positions, frame: str = "enu", min_distance: float = 10.0) -> float:
    r"""Yaw of the direction of travel between the first position fixes far enough apart.

    Parameters
    ----------
    t : array_like, shape (M,)
        Fix times, s, strictly increasing.
    positions : array_like, shape (M, 2) or (M, 3)
        Navigation-frame positions in m (x, y[, z] of the frame: east, north[, up] in
        ENU, north, east[, down] in NED).
    frame : {"enu", "ned"}
        Navigation frame.
    min_distance : float
        Horizontal distance, m, the second fix must be from the first (default 10).
        Choose it well above the fixes' noise: the heading's error is about
        :math:`\sqrt 2\, \sigma_p / d` rad for a horizontal noise :math:`\sigma_p`.

    Returns
    -------
    float
        Yaw in rad, in :math:`(-\pi, \pi]`: counterclockwise from east in ENU,
        clockwise from north in NED (the yaw of :func:`initial_attitude`).

    Raises
    ------
    InputError
        When no fix is ``min_distance`` from the first one (the fixes do not move
        enough to define a heading), or for malformed input.

    Notes
    -----
    With :math:`p_0` the first fix and :math:`p_k` the first later fix with
    :math:`\|p_k - p_0\|_{xy} \ge d_{min}`,

    .. math:: \psi = \operatorname{atan2}(y_k - y_0,\ x_k - x_0)

    in both frames (in NED, x = north and y = east make this the clockwise angle from
    north). This is the body's yaw when body x points along the travel direction (a
    car or a walker moving forward, no side slip) and the path is straight between the
    two fixes; on a curve it is the chord's direction.

    Examples
    --------
    Ten metres travelled at 0.3 rad north of east (ENU):

    >>> import numpy as np
    >>> from bvpnav.align import heading_from_positions
    >>> t = np.linspace(0.0, 10.0, 11)
    >>> xy = np.column_stack([t * np.cos(0.3), t * np.sin(0.3)])
    >>> print(f"{heading_from_positions(t, xy):.4f} rad")
    0.3000 rad
    """
    _frame(frame)  # the formula is the same in both frames (see Notes)
    tt = _array(t, "t", "s").ravel()
    p = _horizontal(_array(positions, "positions", "m"), "positions")
    if tt.size != p.shape[0]:
        raise InputError(f"t has {tt.size} times but positions has {p.shape[0]} rows; give one time per fix")
    if tt.size >= 2 and np.any(np.diff(tt) <= 0):
        k = int(np.flatnonzero(np.diff(tt) <= 0)[0])
        raise InputError(f"t: fix times must be strictly increasing (t[{k}] = {tt[k]:g} s, t[{k + 1}] = "
                         f"{tt[k + 1]:g} s); sort the fixes and drop repeated ones")
    if not (isinstance(min_distance, (int, float)) and math.isfinite(min_distance) and min_distance > 0):
        raise InputError(f"min_distance={min_distance!r}: give a horizontal distance in m (> 0)")
    d = np.hypot(*(p - p[0]).T) if tt.size else np.zeros(0)
    far = np.flatnonzero(d >= min_distance)
    if far.size == 0:
        most = float(d.max()) if d.size else 0.0
        raise InputError(f"positions: the {tt.size} fixes stay within {most:.3g} m of the first one, less "
                         f"than min_distance = {min_distance:g} m, so they do not define a direction of "
                         "travel; give fixes over a longer stretch of motion, a velocity "
                         "(heading_from_velocity), or the heading itself")
    k = int(far[0])
    dx, dy = p[k] - p[0]
    return math.atan2(dy, dx)


def heading_from_velocity(velocity, frame: str = "enu", min_speed: float = 0.5):
    r"""Yaw of the horizontal velocity.

    Parameters
    ----------
    velocity : array_like, shape (2,), (3,), (N, 2) or (N, 3)
        Navigation-frame velocity in m/s (x, y[, z] of the frame).
    frame : {"enu", "ned"}
        Navigation frame.
    min_speed : float
        Horizontal speed, m/s, below which the direction is refused as undefined
        (default 0.5).

    Returns
    -------
    float or ndarray of shape (N,)
        Yaw in rad: :math:`\psi = \operatorname{atan2}(v_y, v_x)`, counterclockwise
        from east in ENU, clockwise from north in NED.

    Raises
    ------
    InputError
        When a horizontal speed is below ``min_speed`` (naming the first such row).

    Notes
    -----
    The body's yaw when body x points along the velocity (no side slip). A noise
    :math:`\sigma_v` on each horizontal component gives a heading error of about
    :math:`\sigma_v / |v_{xy}|` rad.

    Examples
    --------
    >>> import math
    >>> from bvpnav.align import heading_from_velocity
    >>> print(f"{heading_from_velocity([1.0, 1.0]):.4f} rad")  # north-east in ENU
    0.7854 rad
    >>> print(f"{heading_from_velocity([1.0, 1.0], frame='ned'):.4f} rad")  # north = east in NED
    0.7854 rad
    """
    _frame(frame)
    v = _array(velocity, "velocity", "m/s")
    single = v.ndim == 1
    h = _horizontal(v[None, :] if single else v, "velocity")
    if not (isinstance(min_speed, (int, float)) and math.isfinite(min_speed) and min_speed > 0):
        raise InputError(f"min_speed={min_speed!r}: give a horizontal speed in m/s (> 0)")
    speed = np.hypot(h[:, 0], h[:, 1])
    slow = np.flatnonzero(speed < min_speed)
    if slow.size:
        i = int(slow[0])
        where = "" if single else f" row {i}:"
        raise InputError(f"velocity:{where} horizontal speed {speed[i]:.3g} m/s is below min_speed = "
                         f"{min_speed:g} m/s, too slow to define a direction of travel; use a velocity "
                         "while moving, or the heading itself")
    yaw = np.arctan2(h[:, 1], h[:, 0])
    return float(yaw[0]) if single else yaw


def initial_attitude(roll, pitch, yaw, frame: str = "enu") -> Rotation:
    r"""Body-to-navigation attitude from roll, pitch and yaw.

    Parameters
    ----------
    roll, pitch, yaw : float or array_like of shape (N,)
        Angles in rad (broadcast together).
    frame : {"enu", "ned"}
        Navigation frame: in ENU the yaw is counterclockwise from east about up, in NED
        clockwise from north about down (see the module's conventions).

    Returns
    -------
    scipy.spatial.transform.Rotation
        One rotation for scalar angles, else N: :math:`C = R_z(\psi) R_y(\theta)
        R_x(\phi)` with :math:`v_n = C v_b`, ready for
        ``ImuData.from_gyro(..., initial_attitude=C)``.

    Notes
    -----
    The same formula in both frames (scipy ``Rotation.from_euler("ZYX", [yaw, pitch,
    roll])``); the frame states what the angles mean. Body x points at
    :math:`C e_x = (\cos\psi\cos\theta,\ \sin\psi\cos\theta,\ -\sin\theta)`.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.align import initial_attitude
    >>> C = initial_attitude(-0.01, 0.02, 0.3)  # roll, pitch, yaw (rad)
    >>> (np.round(C.as_euler("ZYX"), 6) + 0.0).tolist()
    [0.3, 0.02, -0.01]
    """
    from scipy.spatial.transform import Rotation

    _frame(frame)
    r, p, y = (_array(a, name, "rad") for a, name in ((roll, "roll"), (pitch, "pitch"), (yaw, "yaw")))
    try:
        r, p, y = np.broadcast_arrays(r, p, y)
    except ValueError:
        raise InputError(f"roll, pitch, yaw: shapes {r.shape}, {p.shape}, {y.shape} do not broadcast; give "
                         "three scalars or three arrays of one length") from None
    if r.ndim > 1:
        raise InputError(f"roll, pitch, yaw: shape {r.shape}; give scalars or 1-D arrays (one per sample)")
    return Rotation.from_euler("ZYX", np.stack([y, p, r], axis=-1))


def attitude_angles(rotation: Rotation, frame: str = "enu", *, t=None, unwrap: bool = False) -> pd.DataFrame:
    r"""Roll, pitch and yaw in degrees per sample: the inverse of :func:`initial_attitude`.

    Parameters
    ----------
    rotation : scipy.spatial.transform.Rotation
        Body-to-navigation attitude, one or many.
    frame : {"enu", "ned"}
        Navigation frame (what the yaw means; see the module's conventions).
    t : array_like, optional
        Times, s, for the index (named ``t``); default 0, 1, ...
    unwrap : bool
        Remove the 360-degree jumps of the yaw between samples (default False: yaw in
        (-180, 180]).

    Returns
    -------
    pandas.DataFrame
        Columns ``roll_deg``, ``pitch_deg`` (in [-90, 90]), ``yaw_deg``.

    Notes
    -----
    scipy ``as_euler("ZYX")`` gives :math:`(\psi, \theta, \phi)` of
    :math:`C = R_z(\psi) R_y(\theta) R_x(\phi)`. At :math:`\theta = \pm 90`
    degrees (body x vertical) roll and yaw are not separable (gimbal lock; scipy warns
    and sets roll to zero).

    Examples
    --------
    >>> from bvpnav.align import attitude_angles, initial_attitude
    >>> print(attitude_angles(initial_attitude(-0.01, 0.02, 0.3)).round(3).to_string())
       roll_deg  pitch_deg  yaw_deg
    0    -0.573      1.146   17.189
    """
    from scipy.spatial.transform import Rotation

    _frame(frame)
    if not isinstance(rotation, Rotation):
        raise InputError(f"rotation: {type(rotation).__name__}; give a scipy Rotation (body to navigation)")
    eul = np.atleast_2d(rotation.as_euler("ZYX"))
    yaw = np.unwrap(eul[:, 0]) if unwrap else eul[:, 0]
    index = None
    if t is not None:
        tt = _array(t, "t", "s").ravel()
        if tt.size != eul.shape[0]:
            raise InputError(f"t has {tt.size} times for {eul.shape[0]} rotations; give one time per "
                             "rotation")
        index = pd.Index(tt, name="t")
    return pd.DataFrame({"roll_deg": np.degrees(eul[:, 2]), "pitch_deg": np.degrees(eul[:, 1]),
                         "yaw_deg": np.degrees(yaw)}, index=index)


def _stationary_rows(stationary: Any, t: np.ndarray) -> np.ndarray:
    n = t.size
    form = ("give a slice of sample indices (slice(0, 500)), a boolean mask of shape (N,), or a time "
            "interval (t0, t1) in s")
    if isinstance(stationary, slice):
        rows = np.arange(n)[stationary]
    elif isinstance(stationary, tuple) and len(stationary) == 2:
        try:
            t0, t1 = float(stationary[0]), float(stationary[1])
        except (TypeError, ValueError):
            raise InputError(f"stationary={stationary!r}: {form}") from None
        if not t0 < t1:
            raise InputError(f"stationary=({t0:g}, {t1:g}) s: the interval must have t0 < t1")
        rows = np.flatnonzero((t >= t0) & (t <= t1))
    else:
        mask = np.asarray(stationary)
        if mask.dtype != bool or mask.shape != (n,):
            raise InputError(f"stationary: {form} (got {type(stationary).__name__} "
                             f"{getattr(mask, 'shape', '')} {getattr(mask, 'dtype', '')})")
        rows = np.flatnonzero(mask)
    if rows.size == 0:
        raise InputError(f"stationary={stationary!r} selects no sample of the {n}; {form} that covers "
                         "samples at rest")
    return rows


def align(t, specific_force, *, stationary, positions=None, position_times=None, velocity=None,
          yaw: float | None = None, gyro=None, frame: str = "enu", min_distance: float = 10.0,
          gravity: float = STANDARD_GRAVITY, tolerance: float = GRAVITY_TOLERANCE) -> Rotation:
    r"""The body-to-navigation attitude at ``t[0]`` from a stationary interval and the motion.

    Parameters
    ----------
    t : array_like, shape (N,)
        IMU sample times, s.
    specific_force : array_like, shape (N, 3)
        Body-frame specific force, m/s^2.
    stationary : slice, boolean array of shape (N,), or (t0, t1)
        The samples at rest (indices, a mask, or a time interval in s): roll and pitch
        from :func:`roll_pitch_from_stationary` over them.
    positions : array_like, shape (M, 2) or (M, 3), optional
        Position fixes (m, navigation frame) at ``position_times``: the heading from
        :func:`heading_from_positions`.
    position_times : array_like, shape (M,), optional
        Times of the fixes, s (required with ``positions``).
    velocity : array_like, shape (2,) or (3,), optional
        A navigation-frame velocity while moving, m/s: the heading from
        :func:`heading_from_velocity`.
    yaw : float, optional
        The heading itself, rad. Give ``yaw=0.0`` when it is unknown and let the
        solver's heading search and ``AttitudeError`` find it.
    gyro : array_like, shape (N, 3), optional
        Body rates, rad/s: needed only when the stationary interval starts after
        ``t[0]``, to carry its roll and pitch back to ``t[0]``.
    frame : {"enu", "ned"}
        Navigation frame.
    min_distance : float
        See :func:`heading_from_positions`, m.
    gravity, tolerance
        See :func:`roll_pitch_from_stationary`.

    Returns
    -------
    scipy.spatial.transform.Rotation
        :math:`C_0 = R_z(\psi) R_y(\theta_0) R_x(\phi_0)`, for
        ``ImuData.from_gyro(t, specific_force, gyro, initial_attitude=C_0, gravity=...)``.

    Raises
    ------
    InputError
        Naming the argument: no heading source or more than one, a non-stationary
        interval, fixes that do not move, an interval after ``t[0]`` without ``gyro``.

    Notes
    -----
    Exactly one of ``positions``, ``velocity`` and ``yaw`` gives the heading. The
    heading from positions or a velocity is the direction of travel some time after
    ``t[0]``; it is taken as the yaw at ``t[0]`` (the vehicle starts moving forward
    along body x, without turning first). When the stationary interval starts at sample
    :math:`k > 0`, its attitude :math:`C_k = R_z(\psi_k) R_y(\theta) R_x(\phi)` is
    carried back with the gyro, :math:`C_0 = C_k \Delta_k^{-1}` with :math:`\Delta_k`
    the attitude integrated from identity at ``t[0]``
    (:func:`bvpnav.attitude.integrate_gyro`); a rotation about the navigation z axis
    does not change roll or pitch, so :math:`\psi_k` does not matter.

    Examples
    --------
    Roll and pitch from 2 s at rest, the heading given (ENU, counterclockwise from east):

    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> C = Rotation.from_euler("ZYX", [0.3, 0.02, -0.01])  # yaw, pitch, roll (rad)
    >>> f = np.tile(C.inv().apply([0.0, 0.0, 9.80665]), (21, 1))  # at rest: -C^T g (m/s^2)
    >>> from bvpnav.align import align, attitude_angles
    >>> C0 = align(np.linspace(0.0, 2.0, 21), f, stationary=(0.0, 2.0), yaw=0.3)
    >>> print(attitude_angles(C0).round(3).to_string())
       roll_deg  pitch_deg  yaw_deg
    0    -0.573      1.146   17.189
    """
    from .grid import TimeGrid

    fr = _frame(frame)
    grid = TimeGrid(t)
    tt = grid.t
    f = _array(specific_force, "specific_force", "m/s^2")
    if f.shape != (tt.size, 3):
        raise InputError(f"specific_force: shape {f.shape}; expected ({tt.size}, 3), one body-frame row "
                         "(x, y, z, m/s^2) per sample of t")
    sources = [name for name, v in (("positions", positions), ("velocity", velocity), ("yaw", yaw))
               if v is not None]
    if len(sources) != 1:
        said = f"{' and '.join(sources)} given" if sources else "none given"
        raise InputError(f"align: give exactly one heading source, positions= (with position_times=), "
                         f"velocity= or yaw= ({said}); with the heading unknown give yaw=0.0 and let the "
                         "solver's heading search find it")
    rows = _stationary_rows(stationary, tt)
    try:
        roll, pitch = roll_pitch_from_stationary(f[rows], fr, gravity=gravity, tolerance=tolerance)
    except InputError as exc:
        raise InputError(f"stationary: samples {int(rows[0])}..{int(rows[-1])} "
                         f"(t = {tt[rows[0]]:g}..{tt[rows[-1]]:g} s): {exc}") from None
    if rows[0] > 0:
        if gyro is None:
            raise InputError(f"stationary: the interval starts at sample {int(rows[0])} (t = {tt[rows[0]]:g} "
                             f"s), after t[0] = {tt[0]:g} s, and the attitude is wanted at t[0]; pass gyro= "
                             "(N, 3) rad/s to carry it back, or start the recording at the interval "
                             f"(t[{int(rows[0])}:])")
        from scipy.spatial.transform import Rotation

        from .attitude import integrate_gyro

        k = int(rows[0])
        rates = _array(gyro, "gyro", "rad/s")
        if rates.shape != (tt.size, 3):
            raise InputError(f"gyro: shape {rates.shape}; expected ({tt.size}, 3), one body rate (x, y, z, "
                             "rad/s) per sample of t")
        delta = integrate_gyro(tt[: k + 1], rates[: k + 1])[-1]
        back = Rotation.from_euler("YX", [pitch, roll]) * delta.inv()
        _, pitch, roll = back.as_euler("ZYX")
    elif gyro is not None:
        _array(gyro, "gyro", "rad/s")  # checked, not needed: the interval starts at t[0]
    if yaw is not None:
        if isinstance(yaw, bool) or not isinstance(yaw, (int, float)) or not math.isfinite(yaw):
            raise InputError(f"yaw={yaw!r}: give the heading in rad (a finite number)")
        heading = float(yaw)
    elif velocity is not None:
        heading = heading_from_velocity(velocity, fr)
        if not isinstance(heading, float):
            raise InputError("velocity: give one velocity (shape (2,) or (3,)) while moving, m/s")
    else:
        if position_times is None:
            raise InputError("positions given without position_times: give the fix times in s "
                             "(position_times=...)")
        heading = heading_from_positions(position_times, positions, fr, min_distance=min_distance)
    return initial_attitude(roll, pitch, heading, fr)


def align_recording(rec, frame_options: Any = None, *, rest: Any = "first", heading: Any = "search",
                    fixes=None, min_distance: float = 10.0, min_rest: float = 1.0,
                    detector: dict | None = None) -> tuple[Rotation, dict]:
    r"""The initial attitude of a recording's strapdown channels: the spec's ``[align]``.

    Parameters
    ----------
    rec : bvpnav.readers.Recording
        Specific force (m/s^2) and gyro rates (rad/s) in the sensor's axes, no orientation.
    frame_options : mapping, optional
        The spec's ``[input]`` frame options (``frame``, ``gravity``, ``body_to_sensor``:
        :mod:`bvpnav.strapdown`).
    rest : "first" or (t0, t1)
        The interval at rest, s; ``"first"``: the first interval of at least ``min_rest`` s
        that :func:`bvpnav.detect.stationary` finds (with ``detector``'s options).
    heading : float, "fixes" or "search"
        The yaw at ``t[0]`` in **degrees** (the frame's convention: counterclockwise from
        east in ENU, clockwise from north in NED); ``"fixes"``: from ``fixes``
        (:func:`heading_from_positions`); ``"search"``: 0, for the solve's heading search.
    fixes : (t, positions), optional
        Fix times (s) and navigation-frame positions (M, 2 or 3; m), for ``"fixes"``.
    min_distance : float
        See :func:`heading_from_positions`, m.
    min_rest : float
        Shortest detected interval taken by ``rest="first"``, s.
    detector : dict, optional
        Keyword arguments of :func:`bvpnav.detect.stationary` (``gravity`` defaults to the
        frame options' gravity magnitude).

    Returns
    -------
    (Rotation, dict)
        :math:`C_0` for :func:`bvpnav.strapdown.imu_data` (``initial_attitude=``), and a record:
        ``rest`` [t0, t1] (s), ``heading_source``, ``roll_deg``, ``pitch_deg``, ``yaw_deg``,
        ``rest_mean_rate`` (the norm of the mean gyro rate over the interval, rad/s) and
        ``warning`` (None, or the message issued when that rate exceeds :data:`REST_RATE`:
        an interval that turns is not at rest).

    Notes
    -----
    The same numbers as the Python path, bit for bit: with :math:`f_b = R^T f_s`,
    :math:`\omega_b = R^T \omega_s` (``body_to_sensor`` R),
    ``align(t, f_b, stationary=(t0, t1), gyro=w_b, yaw=radians(heading) | positions=...,
    frame=frame, gravity=|g|)``.

    Examples
    --------
    A triad rolled by -0.01 rad and pitched by 0.02 rad, at rest for 2 s, the heading given
    as 30 degrees:

    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> from bvpnav.readers import Recording
    >>> C = Rotation.from_euler("ZYX", [0.3, 0.02, -0.01])  # yaw, pitch, roll (rad)
    >>> f = np.tile(C.inv().apply([0.0, 0.0, 9.80665]), (21, 1))  # at rest: -C^T g (m/s^2)
    >>> rec = Recording(t=np.linspace(0.0, 2.0, 21), source="example", specific_force=f,
    ...                 gyro=np.zeros((21, 3)))
    >>> from bvpnav.align import align_recording
    >>> c0, record = align_recording(rec, rest=(0.0, 2.0), heading=30.0)
    >>> print({k: round(v, 4) for k, v in record.items() if k.endswith("_deg")}, record["warning"])
    {'roll_deg': -0.573, 'pitch_deg': 1.1459, 'yaw_deg': 30.0} None
    """
    import math as _m

    from scipy.spatial.transform import Rotation

    from .strapdown import gravity_vector, rotation_option

    opts = dict(frame_options or {})
    if getattr(rec, "attitude", None) is not None:
        raise InputError(f"{rec.source}: the file gives the orientation, so there is nothing to align: drop "
                         "[align] (it is for attitudes integrated from gyro rates)")
    if getattr(rec, "specific_force", None) is None or getattr(rec, "gyro", None) is None:
        raise InputError(f"{rec.source}: [align] needs the strapdown channels, specific force and gyro rates "
                         "([input] specific_force = [...] and gyro = [...]); drop [align] for "
                         "navigation-frame accelerations")
    fr = _frame(opts.get("frame", "enu"))
    g = gravity_vector(opts, fr)
    mount = (rotation_option(opts["body_to_sensor"], "body_to_sensor") if "body_to_sensor" in opts
             else Rotation.identity())
    t = np.asarray(rec.t, dtype=float)
    f_b, w_b = mount.inv().apply(rec.specific_force), mount.inv().apply(rec.gyro)
    if isinstance(rest, str):
        if rest != "first":
            raise InputError(f'rest = {rest!r}: give "first" (the first interval the detector finds) or '
                             "[t0, t1] in s")
        t0, t1 = _first_rest(t, f_b, w_b, g, min_rest, detector or {}, rec.source)
    else:
        t0, t1 = (float(v) for v in rest)
    kw: dict[str, Any] = {}
    if isinstance(heading, str):
        if heading == "fixes":
            if fixes is None:
                raise InputError('heading = "fixes" needs position fixes; none given')
            kw = {"positions": fixes[1], "position_times": fixes[0], "min_distance": min_distance}
        elif heading == "search":
            kw = {"yaw": 0.0}
        else:
            raise InputError(f"heading = {heading!r}: give a yaw in degrees or one of {sorted(HEADINGS)}")
    else:
        kw = {"yaw": _m.radians(float(heading))}
    c0 = align(t, f_b, stationary=(t0, t1), gyro=w_b, frame=fr, gravity=float(np.linalg.norm(g)), **kw)
    angles = attitude_angles(c0, fr).iloc[0]
    rows = (t >= t0) & (t <= t1)
    turning = float(np.linalg.norm(w_b[rows].mean(axis=0)))
    warning = None
    if turning > REST_RATE:
        warning = (f"[align] rest {t0:g} .. {t1:g} s: the gyro's mean rate there is {turning:.3g} rad/s, "
                   f"more than {REST_RATE:g} rad/s (a gyro bias is smaller): the sensor turns, so it is not "
                   "at rest and the roll and pitch taken from it hold the motion's acceleration; give an "
                   "interval where it stands still (`bvpnav stationary INPUT --spec SPEC` lists them)")
        from .log import warn

        warn(warning)
    record = {"rest": [t0, t1], "heading_source": heading if isinstance(heading, str) else "given",
              "roll_deg": float(angles["roll_deg"]), "pitch_deg": float(angles["pitch_deg"]),
              "yaw_deg": float(angles["yaw_deg"]), "rest_mean_rate": turning, "warning": warning}
    return c0, record


def _first_rest(t, f_b, w_b, g, min_rest: float, detector: dict, source: str) -> tuple[float, float]:
    """The first interval at rest of at least ``min_rest`` s (:func:`bvpnav.detect.stationary`)."""
    from . import detect
    from .imu import ImuData

    data = ImuData.from_gyro(t, f_b, w_b, gravity=g, checks=False)  # the detector needs no attitude
    opts = {"gravity": float(np.linalg.norm(g)), **detector}
    found = detect.stationary(data, **opts)
    long = [(a, b) for a, b in found if b - a >= min_rest]
    if not long:
        seen = ", ".join(f"{a:g}..{b:g} s" for a, b in found[:5]) or "none"
        raise InputError(f"{source}: rest = \"first\": the {opts.get('method', 'shoe')} detector found no "
                         f"interval at rest of at least min_rest = {min_rest:g} s (found: {seen}); give the "
                         "interval yourself, rest = [t0, t1] in s, or lower min_rest (check with `bvpnav "
                         "stationary INPUT --spec SPEC --plot PNG`)")
    return float(long[0][0]), float(long[0][1])
