"""Input container: sample times and accelerations (navigation frame or strapdown)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from .errors import InputError
from .geodesy import STANDARD_GRAVITY
from .grid import TimeGrid
from .timebase import as_float_array

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

__all__ = ["ImuData", "STANDARD_GRAVITY", "ACC_UNITS", "DEFAULT_AXES", "RESERVED_NAMES",
           "axis_name_clash"]

#: m/s^2 per unit of an acceleration value (``[input] unit`` of a spec).
ACC_UNITS = {"m/s^2": 1.0, "g": STANDARD_GRAVITY, "mg": STANDARD_GRAVITY * 1e-3, "ft/s^2": 0.3048}
#: Default axis names by number of axes.
DEFAULT_AXES = {1: ("x",), 2: ("x", "y"), 3: ("x", "y", "z")}


#: Output column names besides the per-axis ones: the time column of a trajectory.
RESERVED_NAMES = ("t",)


def _outputs(axis: str) -> tuple[str, ...]:
    """Trajectory columns of one axis: position, velocity and their uncertainties."""
    return (axis, f"v{axis}", f"{axis}_std", f"v{axis}_std")


def axis_name_clash(axes: Sequence[str]) -> str | None:
    """Why these axis names cannot name trajectory columns, or None when they can.

    A trajectory has the columns ``t``, ``<axis>``, ``v<axis>``, ``<axis>_std`` and
    ``v<axis>_std`` per axis; every one must be distinct, so an axis may not be empty,
    be ``t``, or produce another axis's column (``vx`` beside ``x``: the velocity of
    ``x`` is ``vx``; ``x_std`` beside ``x``).
    """
    owner: dict[str, str] = {r: "the time column" for r in RESERVED_NAMES}
    for a in axes:
        if not a.strip():
            return f"axis name {a!r} is empty"
        if a != a.strip() or not a.isprintable():
            return (f"axis name {a!r} has leading/trailing whitespace or control characters (it would "
                    "name trajectory columns as it is)")
        for col in _outputs(a):
            if col in owner:
                return (f"axis {a!r} would write the column {col!r}, which is already {owner[col]}")
            owner[col] = f"a column of axis {a!r}" if col != a else f"the position of axis {a!r}"
    return None


def _finite_2d(arr, name: str, columns: Sequence[str] | None = None) -> np.ndarray:
    if isinstance(arr, pd.DataFrame) or (isinstance(arr, pd.Series) and arr.name is not None):
        what = (f"a DataFrame with columns {[str(c) for c in arr.columns]}" if isinstance(arr, pd.DataFrame)
                else f"a Series named {arr.name!r}")
        raise InputError(f"{name}: {what}; its column names would be ignored and the axes taken by "
                         "position. Use ImuData.from_dataframe(df, time=..., columns=[...]) (axes from the "
                         "column names), or pass values.to_numpy() with axes=(...) in the column order")
    a = as_float_array(arr, name, "m/s^2")  # a copy: the caller's array is never kept
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise InputError(f"{name}: expected shape (N,) or (N, d), got {a.shape}")
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        i, k = (int(v) for v in bad[0])
        col = columns[k] if columns is not None and k < len(columns) else f"column {k}"
        raise InputError(
            f"{name}: sample {i}, {col} is {float(a[i, k])!r}; every sample must be a finite number. "
            "Remove or repair that sample (bvpnav never fills gaps silently)."
        )
    return a


def _axis_names(axes: Sequence[str] | str | None, d: int) -> tuple[str, ...]:
    """The axis names of ``d`` acceleration columns (default x, y, z), checked: strings, one
    per column, distinct, and naming trajectory columns that do not collide."""
    if d not in (1, 2, 3):
        raise InputError(f"acc: {d} axes given; bvpnav handles 1, 2 or 3 axes")
    if axes is None:
        axes = DEFAULT_AXES[d]
    if not isinstance(axes, str) and any(not isinstance(s, str) for s in axes):
        raise InputError(f"axes: {list(axes)!r}; give axis names as strings, e.g. axes=('x', 'y')")
    axes = tuple([axes] if isinstance(axes, str) else axes)
    if len(axes) != d:
        raise InputError(f"axes: {len(axes)} names {axes} for {d} acceleration columns; give one name "
                         "per acceleration column")
    if len(set(axes)) != d:
        raise InputError(f"axes: names must be distinct, got {axes}; rename the repeated axis")
    clash = axis_name_clash(axes)
    if clash is not None:
        raise InputError(f"axes {axes}: {clash}; trajectory columns are t, <axis>, v<axis>, "
                         "<axis>_std and v<axis>_std, so rename that axis (e.g. 'x', 'y', 'z')")
    return axes


def _gravity_and_frame(gravity, frame: str | None) -> tuple[np.ndarray, str | None]:
    """The navigation-frame gravity vector (m/s^2) and the frame (stated, or implied by a
    gravity along -z (ENU) or +z (NED), else None), checked against each other."""
    if frame is not None and frame not in ("enu", "ned"):
        raise InputError(f"frame={frame!r}: valid navigation frames: 'enu' (x east, y north, z up) or 'ned' "
                         "(x north, y east, z down)")
    if gravity is None:
        g = np.array([0.0, 0.0, STANDARD_GRAVITY if frame == "ned" else -STANDARD_GRAVITY])
    else:
        g = as_float_array(gravity, "gravity", "m/s^2")
    if g.shape != (3,) or not np.all(np.isfinite(g)) or not np.any(g):
        raise InputError(f"gravity: expected 3 finite numbers in m/s^2 (not all zero), got {gravity!r}")
    up = g[2] < 0  # gravity along -z: z points up
    if frame is not None and gravity is not None and up != (frame == "enu"):
        raise InputError(f"gravity={g.tolist()} points along {'-' if up else '+'}z, but frame={frame!r} "
                         f"has z {'up' if frame == 'enu' else 'down'}: give gravity along "
                         f"{'-' if frame == 'enu' else '+'}z (or leave gravity out), or the other frame")
    if frame is None:
        u = g / np.linalg.norm(g)
        frame = "enu" if u[2] < -0.999 else "ned" if u[2] > 0.999 else None
    return g, frame


def _other(frame: str | None) -> str:
    return "enu" if frame == "ned" else "ned"


def _z(frame: str | None) -> str:
    return "z-down (forward-right-down, NED)" if _other(frame) == "ned" else "z-up (ENU, forward-left-up)"


#: The fixes of the frame check's verdicts, in Python terms, by constructor and frame.
_PYTHON_FIXES = {
    "gyro": lambda frame: {
        "gravity twice": (f"If the sensor's axes are {_z(frame)}, say so: ImuData.from_gyro(t, "
                          f"specific_force, gyro, frame='{_other(frame)}'); otherwise give the attitude at "
                          "the first sample, initial_attitude= (bvpnav.align.roll_pitch_from_stationary, "
                          "bvpnav.align.initial_attitude)."),
        "gravity horizontal": ("Give the attitude at the first sample, initial_attitude= (bvpnav.align."
                               "roll_pitch_from_stationary, bvpnav.align.initial_attitude), and check the "
                               "order of the specific_force and gyro columns (x, y, z)."),
        "gravity missing": ("Give the accelerometer's specific force with gravity in it (what the sensor "
                            "measures: +9.8 m/s^2 on the axis that points up at rest)."),
    },
    "attitude": lambda frame: {
        "gravity twice": (f"If the attitude is relative to {_other(frame).upper()}, say so: ImuData(t, "
                          f"specific_force=f, attitude=C, frame='{_other(frame)}'); otherwise the attitude "
                          "or the sensor's z axis is flipped."),
        "gravity horizontal": ("Check that the attitude maps body to navigation vectors (not its inverse) "
                               "and the quaternion order (scipy's is scalar-last (x, y, z, w))."),
        "gravity missing": ("Give the accelerometer's specific force with gravity in it (what the sensor "
                            "measures: +9.8 m/s^2 on the axis that points up at rest)."),
    },
}


#: A sample within this fraction of ``acc_range`` of it is taken as clipped.
ACC_RANGE_MARGIN = 0.005


class ImuData:
    """Sample times with the accelerations that drive r''(t) = a(t).

    Give either navigation-frame accelerations ``acc`` or a strapdown triple
    (``specific_force``, ``attitude``, ``gravity``).

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times in s, finite and strictly increasing (non-uniform allowed).
    acc : array_like, shape (N,) or (N, d), optional
        Navigation-frame acceleration in m/s^2, ``d`` = 1, 2 or 3 axes.
    specific_force : array_like, shape (N, 3), optional
        Body-frame specific force in m/s^2 (what an accelerometer triad measures).
    attitude : scipy.spatial.transform.Rotation or array_like, optional
        Body-to-navigation rotation per sample: a ``Rotation`` of length N, quaternions
        (N, 4) in scipy's scalar-last order ``(x, y, z, w)``, or matrices (N, 3, 3).
    gravity : array_like, shape (3,), optional
        Gravity vector in the navigation frame, m/s^2. Default ``(0, 0, -g0)`` with
        ``g0 = 9.80665`` (z up), or ``(0, 0, +g0)`` with ``frame="ned"``.
    frame : {"enu", "ned"}, optional
        The navigation frame of a strapdown triple (the frame ``attitude`` maps body
        vectors into): ``"enu"`` (x east, y north, z up; the default) or ``"ned"`` (x
        north, y east, z down). It sets the default gravity; a ``gravity`` whose z
        component points the other way is refused.
    checks : bool
        Run the input checks on strapdown data (default True): the frame and gravity
        sanity check (:func:`bvpnav.detect.frame_check`: a :class:`bvpnav.log.FrameWarning`
        when the acceleration at rest is far from zero, e.g. gravity counted twice), and in
        :meth:`from_gyro` the gyro saturation count. Their numbers are kept in
        ``data.checks``.
    acc_range : float, optional
        The accelerometer's full-scale range, m/s^2 (e.g. 156.9 for 16 g), strapdown data
        only: the samples at it (clipped, e.g. heel strikes) are marked and the solve
        weighs them with the noise ``max(sigma_a, acc_range)`` (:meth:`mark_acc_range`;
        the count is ``data.checks["acc_range"]["samples"]``).
    axes : sequence of str, optional
        Axis names; default ``x``, ``x, y`` or ``x, y, z`` by the number of axes. They
        name the trajectory's columns (``<axis>``, ``v<axis>``, ``<axis>_std``,
        ``v<axis>_std`` beside ``t``), so names whose columns would collide (``t``, an
        empty name, ``vx`` beside ``x``) are refused.
    time_origin : str, optional
        What ``t = 0`` is when the times were converted to seconds (see
        :func:`bvpnav.timebase.to_seconds`); kept in ``data.time_origin``.

    Notes
    -----
    Every array is copied (the copies are frozen): the caller's arrays stay writeable and
    a later edit of them changes nothing here. Times go through
    :func:`bvpnav.timebase.as_seconds`, numbers through
    :func:`bvpnav.timebase.as_float_array` (bool, complex, object, text, datetime values
    refused by name).

    In strapdown mode the navigation-frame acceleration is

    .. math:: a(t_i) = C_i f_i + g,

    with ``C_i`` the body-to-navigation rotation matrix of sample i
    (``v_nav = C_i v_body``). Frames: the navigation frame is whatever frame the
    positions are wanted in (z up with the default gravity); the body frame is the
    accelerometer triad's. To integrate the attitude from gyro rates use
    :meth:`from_gyro`.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav import ImuData
    >>> data = ImuData(t=[0.0, 0.1, 0.2, 0.3], acc=[[0.0, 1.0], [0.1, 1.0], [0.2, 1.0], [0.3, 1.0]],
    ...                axes=("x", "y"))
    >>> data
    ImuData(N=4, axes=('x', 'y'), navigation-frame, t=[0, 0.3] s)
    >>> data.n, data.ndim
    (4, 2)
    """

    def __init__(
        self,
        t,
        acc=None,
        *,
        specific_force=None,
        attitude=None,
        gravity=None,
        axes: Sequence[str] | None = None,
        time_origin: str | None = None,
        frame: str | None = None,
        checks: bool = True,
        acc_range: float | None = None,
    ):
        self.grid = TimeGrid(t)
        if time_origin is not None and not isinstance(time_origin, str):
            raise InputError(f"time_origin={time_origin!r}; give a string saying what t = 0 is (e.g. the "
                             "origin returned by bvpnav.timebase.to_seconds) or omit it")
        #: What ``t = 0`` is when the times were converted (e.g. an ISO 8601 timestamp or
        #: ``"1700000000000000000 ns"``); None when the times were given in s as they are.
        self.time_origin: str | None = time_origin
        n = self.grid.n
        self.specific_force: np.ndarray | None = None
        self.attitude: Rotation | None = None
        self.gravity: np.ndarray | None = None
        #: Body rates (N, 3) in rad/s when the attitude came from :meth:`from_gyro`.
        self.gyro: np.ndarray | None = None
        #: Linearization point of attitude error models (set by :mod:`bvpnav.solve.attitude`;
        #: see :class:`bvpnav.error_models._attitude.AttitudePoint`); None for data as given.
        self.attitude_point = None
        #: The navigation frame of strapdown data: ``"enu"``, ``"ned"`` (stated, or implied by
        #: a gravity along -z / +z), or None (navigation-frame data, or another gravity).
        self.frame: str | None = None
        #: The input checks run on these data (``"frame"``: :func:`bvpnav.detect.frame_check`,
        #: ``"saturation"``: :func:`bvpnav.detect.saturation`) as plain numbers, each with its
        #: ``"warning"`` (str or None); a solve copies the warnings into ``solution.warnings``.
        self.checks: dict = {}
        if acc is not None and specific_force is not None:
            raise InputError("give either acc (navigation frame) or specific_force, not both")
        if acc is None and specific_force is None:
            raise InputError("no accelerations: give acc=(N, d) in m/s^2 or specific_force=(N, 3)")
        if acc is not None:
            if attitude is not None or gravity is not None or frame is not None:
                raise InputError(
                    "attitude/gravity/frame go with specific_force (body frame); acc is already in "
                    "the navigation frame"
                )
            a = _finite_2d(acc, "acc", axes)
        else:
            a = self._strapdown(specific_force, attitude, gravity, n, frame)
        if a.shape[0] != n:
            raise InputError(f"acc has {a.shape[0]} samples but t has {n}; lengths must match: give one "
                             "acceleration row per time")
        axes = _axis_names(axes, a.shape[1])
        a.setflags(write=False)
        self.acc: np.ndarray = a
        self.axes: tuple[str, ...] = axes
        #: The accelerometer's full-scale range (m/s^2) when stated, and the samples at it
        #: (N,) bool: the solve gives them the noise ``max(sigma_a, acc_range)``.
        self.acc_range: float | None = None
        self.acc_clipped: np.ndarray | None = None
        if acc_range is not None:
            self.mark_acc_range(acc_range)
        if checks and self.is_strapdown:
            self.check_frame(_PYTHON_FIXES["attitude"](self.frame))

    def mark_acc_range(self, acc_range: float, source: str | None = None) -> dict:
        r"""Mark the samples at the accelerometer's range (clipped, e.g. at heel strike).

        Parameters
        ----------
        acc_range : float
            The accelerometer's full-scale range, m/s^2 (e.g. 156.9 for 16 g).
        source : str, optional
            The file, for the message.

        Returns
        -------
        dict
            ``samples`` (clipped samples), ``of`` (N), ``acc_range`` (m/s^2), ``margin``
            (m/s^2), ``first`` (the first 20 clipped sample indices) and ``warning``; also
            kept in ``checks["acc_range"]`` (a solve copies it into
            ``sol.stats["data_checks"]`` and the warning into ``sol.warnings``).

        Notes
        -----
        A sample is clipped when :math:`|f_{k,j}| \ge r - m` on any body axis :math:`j`,
        :math:`r` = ``acc_range``, :math:`m` = :data:`ACC_RANGE_MARGIN` :math:`\cdot r`
        (a clipped channel reads at or just under its nominal range). Its true value is
        beyond the range by an unknown amount, so the acceleration form weighs it with
        the noise :math:`\max(\sigma_a, r)` on every axis instead of :math:`\sigma_a`
        (:class:`bvpnav.NavigationProblem`); the load form has no per-sample noise and
        uses the samples as they are.

        Examples
        --------
        >>> import numpy as np
        >>> from bvpnav import ImuData
        >>> t = np.arange(100) * 0.01
        >>> f = np.tile([0.0, 0.0, 9.80665], (100, 1))
        >>> f[50:53, 2] = 156.9  # an impact clipped at 16 g
        >>> data = ImuData.from_gyro(t, f, np.zeros((100, 3)), acc_range=156.9, checks=False)
        >>> data.checks["acc_range"]["samples"], np.flatnonzero(data.acc_clipped).tolist()
        (3, [50, 51, 52])
        """
        from .detect import _positive
        from .log import SaturationWarning
        from .log import warn as _warn

        r = _positive("acc_range", acc_range, "m/s^2")
        if self.specific_force is None:
            raise InputError("acc_range is the accelerometer's range on its own axes: it needs the "
                             "body-frame specific force (ImuData(t, specific_force=..., attitude=...) or "
                             "ImuData.from_gyro), not navigation-frame acc")
        margin = ACC_RANGE_MARGIN * r
        clipped = np.any(np.abs(self.specific_force) >= r - margin, axis=1)
        clipped.setflags(write=False)
        self.acc_range, self.acc_clipped = r, clipped
        count = int(np.count_nonzero(clipped))
        msg = None
        if count:
            where = f" of {source}" if source else ""
            k = np.flatnonzero(clipped)
            msg = (f"accelerometer range{where}: {count} of {self.n} samples ({100 * count / self.n:.3g} %) "
                   f"are at the stated acc_range = {r:g} m/s^2 (within {margin:.3g}), the first at t = "
                   f"{self.t[k[0]]:.6g} s: clipped, so the solve weighs them with sigma = "
                   f"max(sigma_a, {r:g}) m/s^2 (their true value is beyond the range by an unknown amount)")
            _warn(msg, SaturationWarning)
        rep = {"samples": count, "of": int(self.n), "acc_range": r, "margin": float(margin),
               "first": [int(i) for i in np.flatnonzero(clipped)[:20]], "warning": msg}
        self.checks["acc_range"] = rep
        return rep

    def check_frame(self, fixes: dict | None = None, source: str | None = None):
        """Run the frame and gravity sanity check (:func:`bvpnav.detect.frame_check`) and keep
        its numbers in ``checks["frame"]``; a :class:`bvpnav.log.FrameWarning` when the
        acceleration at rest is far from zero. Returns the
        :class:`~bvpnav.detect.FrameCheck`."""
        from .detect import frame_check

        res = frame_check(self, fixes=fixes, source=source)
        self.checks["frame"] = res.as_dict()
        return res

    def check_saturation(self, gyro_range: float | None = None, source: str | None = None) -> dict:
        """Count the gyro samples at the sensor's range (:func:`bvpnav.detect.saturation`),
        keep the report in ``checks["saturation"]`` and warn
        (:class:`bvpnav.log.SaturationWarning`) when there are any."""
        from .detect import saturation

        if self.gyro is None:
            raise InputError("no gyro rates to check (data.gyro is None)")
        rep = saturation(self.t, self.gyro, gyro_range=gyro_range, source=source)
        self.checks["saturation"] = rep
        return rep

    def _strapdown(self, specific_force, attitude, gravity, n: int, frame: str | None) -> np.ndarray:
        """Check and keep the strapdown triple; return the navigation-frame acceleration C f + g."""
        f = _finite_2d(specific_force, "specific_force", ("f_x", "f_y", "f_z"))
        if f.shape[1] != 3:
            raise InputError(f"specific_force: expected shape (N, 3), got {f.shape}")
        if attitude is None:
            raise InputError("specific_force needs attitude (body to navigation) per sample")
        rot = self._as_rotation(attitude, n)
        g, self.frame = _gravity_and_frame(gravity, frame)
        if f.shape[0] != n:
            raise InputError(
                f"specific_force has {f.shape[0]} samples but t has {n}; lengths must match: give "
                "one specific-force row per time"
            )
        self.specific_force, self.attitude, self.gravity = f, rot, g
        return self._navigation_force(rot, f) + g

    def _navigation_force(self, rot: Rotation, f: np.ndarray) -> np.ndarray:
        """The specific force in the navigation frame, ``rot.apply(f)`` (N, 3), m/s^2, of which
        :meth:`_strapdown` makes the acceleration (a subclass may keep it)."""
        return rot.apply(f)

    @classmethod
    def from_gyro(
        cls,
        t,
        specific_force,
        gyro,
        *,
        initial_attitude: Rotation | None = None,
        gravity=None,
        frame: str | None = None,
        gyro_range: float | None = None,
        checks: bool = True,
        acc_range: float | None = None,
    ) -> ImuData:
        r"""Strapdown data whose attitude is integrated from gyro rates.

        Parameters
        ----------
        t : array_like, shape (N,)
            Sample times in s.
        specific_force : array_like, shape (N, 3)
            Body-frame specific force in m/s^2.
        gyro : array_like, shape (N, 3)
            Body angular rates relative to the navigation frame, rad/s (body axes).
        initial_attitude : scipy.spatial.transform.Rotation, optional
            Body-to-navigation attitude at ``t[0]``; default identity.
        gravity : array_like, shape (3,), optional
            Navigation-frame gravity in m/s^2 (default ``(0, 0, -9.80665)``, or
            ``(0, 0, +9.80665)`` with ``frame="ned"``).
        frame : {"enu", "ned"}, optional
            The navigation frame (default ``"enu"``): ``"ned"`` for a z-down sensor
            (forward-right-down body axes) whose attitude starts at identity in NED.
        gyro_range : float, optional
            The gyro's full-scale range, rad/s: samples at it are counted and reported
            (:func:`bvpnav.detect.saturation`, a :class:`bvpnav.log.SaturationWarning`);
            without it, runs of samples flat at an axis's largest rate are. The report
            is ``data.checks["saturation"]``.
        checks : bool
            Run the frame and gravity sanity check and the saturation count (see
            :class:`ImuData`); default True.
        acc_range : float, optional
            The accelerometer's full-scale range, m/s^2 (156.9 for 16 g): samples at it
            are marked clipped and weighted with the noise ``max(sigma_a, acc_range)``
            (:meth:`ImuData.mark_acc_range`).

        Notes
        -----
        :math:`C_{k+1} = C_k \exp([\phi_k\times])` with the step rotation vector
        :math:`\phi_k = \tfrac{h_k}{2}(\omega_k + \omega_{k+1}) + \tfrac{h_k^2}{12}\,
        \omega_k \times \omega_{k+1}` (see :func:`bvpnav.attitude.integrate_gyro`);
        then :math:`a_i = C_i f_i + g`. The rates are kept in ``data.gyro``.

        Frames. The navigation frame is the one the positions are wanted in: ENU (x east,
        y north, z up) with the default gravity ``(0, 0, -9.80665)``; for NED (z down)
        pass ``gravity=(0, 0, +9.80665)`` (or read the file with ``[input] frame = "ned"``,
        :mod:`bvpnav.strapdown`). The body frame is the sensor triad's x, y, z (for a
        vehicle usually forward-left-up in ENU, forward-right-down in NED). The
        accelerometer measures specific force, so at rest it reads :math:`-C^T g`:
        +9.81 m/s^2 on the axis that points up. The attitude ``C`` maps body to navigation
        vectors (scipy ``Rotation.apply``), quaternions are scalar-last ``(x, y, z, w)``,
        and Earth's rotation is neglected (the rates are relative to the navigation frame).
        Initial attitudes from a stationary interval and from the first fixes:
        :mod:`bvpnav.align`. When the gyro's bias or the initial attitude is uncertain,
        estimate them: :class:`~bvpnav.error_models.GyroBias`,
        :class:`~bvpnav.error_models.AttitudeError` (solved by the damped loop of
        :mod:`bvpnav.solve.attitude`).

        Examples
        --------
        A level triad at rest (specific force +g on its z axis, up) turning about z at
        0.1 rad/s: no navigation-frame acceleration:

        >>> import numpy as np
        >>> from bvpnav import ImuData
        >>> t = np.linspace(0.0, 1.0, 11)
        >>> f, w = np.tile([0.0, 0.0, 9.80665], (11, 1)), np.tile([0.0, 0.0, 0.1], (11, 1))
        >>> data = ImuData.from_gyro(t, f, w)
        >>> data
        ImuData(N=11, axes=('x', 'y', 'z'), strapdown, t=[0, 1] s)
        >>> bool(np.abs(data.acc).max() < 1e-12)
        True
        """
        from .attitude import integrate_gyro  # scipy.spatial: loaded for strapdown data only

        grid = TimeGrid(t)
        rot = integrate_gyro(grid.t, gyro, initial_attitude)
        out = cls(grid.t, specific_force=specific_force, attitude=rot, gravity=gravity, frame=frame,
                  checks=False, acc_range=acc_range)
        w = as_float_array(gyro, "gyro", "rad/s")
        w.setflags(write=False)
        out.gyro = w
        if checks:
            out.check_saturation(gyro_range)
            out.check_frame(_PYTHON_FIXES["gyro"](out.frame))
        elif gyro_range is not None:
            raise InputError("gyro_range is for the saturation count, which checks=False skips; drop one")
        return out

    @staticmethod
    def _as_rotation(attitude, n: int) -> Rotation:
        from scipy.spatial.transform import Rotation  # loaded for strapdown data only

        if isinstance(attitude, Rotation):
            rot = attitude
            if rot.single or len(rot) != n:
                size = 1 if rot.single else len(rot)
                raise InputError(f"attitude: Rotation of length {size}, expected one per sample ({n})")
            return rot
        arr = as_float_array(attitude, "attitude", f"a Rotation of length {n}, quaternions ({n}, 4) "
                             f"scalar-last, or matrices ({n}, 3, 3)")
        kind = {(n, 4): "quaternion", (n, 3, 3): "matrix"}.get(arr.shape)
        if kind is not None:
            nonfinite = np.flatnonzero(~np.all(np.isfinite(arr.reshape(n, -1)), axis=1))
            if nonfinite.size:
                i = int(nonfinite[0])
                raise InputError(
                    f"attitude: {kind} {i} has a non-finite entry ({arr[i].ravel().tolist()}); every "
                    "sample's attitude must be finite. Remove or repair that sample."
                )
        if kind == "quaternion":
            # No silent normalisation: a quaternion far from unit length is a units or
            # column-order mistake, not rounding.
            norms = np.linalg.norm(arr, axis=1)
            bad = np.flatnonzero(np.abs(norms - 1.0) > 1e-6)
            if bad.size:
                raise InputError(
                    f"attitude: quaternion {bad[0]} has norm {norms[bad[0]]:.6g}, not 1; pass unit "
                    "quaternions (x, y, z, w), scalar last (normalize them with q / |q| if they are "
                    "rotations)"
                )
            return Rotation.from_quat(arr)
        if kind == "matrix":
            err = np.abs(np.einsum("nij,nkj->nik", arr, arr) - np.eye(3)).max(axis=(1, 2))
            det = np.linalg.det(arr)
            bad = np.flatnonzero((err > 1e-6) | (det < 0))
            if bad.size:
                i = int(bad[0])
                raise InputError(
                    f"attitude: matrix {i} is not a rotation (max |C C^T - I| = {err[i]:.3g}, det = "
                    f"{det[i]:.6g}); pass orthonormal body-to-navigation matrices with det = +1"
                )
            return Rotation.from_matrix(arr)
        raise InputError(
            f"attitude: shape {arr.shape}; expected a Rotation of length {n}, quaternions ({n}, 4) "
            f"scalar-last, or matrices ({n}, 3, 3)"
        )

    # ---------------------------------------------------------------- helpers
    @property
    def t(self) -> np.ndarray:
        """Sample times, s."""
        return self.grid.t

    @property
    def n(self) -> int:
        """Number of samples N."""
        return self.grid.n

    @property
    def ndim(self) -> int:
        """Number of navigation axes d."""
        return len(self.axes)

    @property
    def is_strapdown(self) -> bool:
        """True when built from body-frame specific force and attitude."""
        return self.specific_force is not None

    def axis_index(self, names, what: str = "axes") -> tuple[int, ...]:
        """Indices of the named axes; ``None`` means all axes.

        Raises
        ------
        InputError
            For an unknown axis name, listing the valid ones.
        """
        if names is None:
            return tuple(range(self.ndim))
        if isinstance(names, str):
            names = (names,)
        out = []
        for s in names:
            if s not in self.axes:
                raise InputError(f"{what}: unknown axis {s!r}; this data has axes {list(self.axes)}")
            out.append(self.axes.index(s))
        return tuple(out)

    @classmethod
    def from_dataframe(
        cls, df: pd.DataFrame, time: str = "t", columns: Sequence[str] | None = None,
        axes: Sequence[str] | None = None,
    ) -> ImuData:
        """Build from a DataFrame with a time column and one column per axis (m/s^2).

        Parameters
        ----------
        df : pandas.DataFrame
        time : str
            Name of the time column (s). If absent, the index is used when it is named
            ``time``.
        columns : sequence of str, optional
            Acceleration columns in order; default: every other numeric column.
        axes : sequence of str, optional
            Axis names; default derived from the column names (``ax`` -> ``x``).
        """
        if time in df.columns:
            t = df[time].to_numpy()
        elif df.index.name == time:
            t = df.index.to_numpy()
        else:
            raise InputError(
                f"time column {time!r} not found; columns are {list(df.columns)}. "
                "Pass time=<name of the time column>."
            )
        if columns is None:
            columns = [c for c in df.columns if c != time]
        missing = [c for c in columns if c not in df.columns]
        if missing:
            raise InputError(f"acceleration column(s) {missing} not found; columns are {list(df.columns)}")
        if axes is None and all(str(c).startswith("a") and len(str(c)) > 1 for c in columns):
            axes = [str(c)[1:].lstrip("_") for c in columns]
        acc = as_float_array(df[list(columns)], f"columns {list(columns)}", "m/s^2")
        return cls(t, acc, axes=axes)

    def to_dataframe(self) -> pd.DataFrame:
        """Navigation-frame accelerations as a DataFrame indexed by time ``t`` (s).

        Examples
        --------
        >>> from bvpnav import ImuData
        >>> data = ImuData(t=[0.0, 0.1, 0.2], acc=[0.5, 0.5, 0.5])
        >>> df = data.to_dataframe()
        >>> df.columns.tolist(), df.index.name
        (['ax'], 't')
        >>> ImuData.from_dataframe(df)
        ImuData(N=3, axes=('x',), navigation-frame, t=[0, 0.2] s)
        """
        cols = {f"a{s}": self.acc[:, k] for k, s in enumerate(self.axes)}
        return pd.DataFrame(cols, index=pd.Index(self.t, name="t"))

    def __repr__(self) -> str:
        mode = "strapdown" if self.is_strapdown else "navigation-frame"
        return f"ImuData(N={self.n}, axes={self.axes}, {mode}, t=[{self.grid.t0:g}, {self.grid.t1:g}] s)"
