r"""A car's start for the node-state loop: the attitude the position fixes imply.

``solve(..., attitude={"start": "course"})`` with :class:`~bvpnav.error_models.ErrorStates`:
the loop's first linearization point is not the attitude in the data (integrated from the raw
gyro, which a consumer gyro's bias turns by radians in minutes) but the attitude a car has
along the fixes: its heading is the heading of the velocity of the positions interpolated
linearly between the fixes, and its roll and pitch are those of the data's attitude at the
first sample (the initial alignment). The start is given as initial totals of the
attitude-error states, so the loop, its process rows (the raw gyro rates) and its answer are
otherwise those of the default start.
"""

from __future__ import annotations

import numpy as np

from ..align import initial_attitude
from ..errors import InputError

__all__ = ["COURSE_MIN_SPEED", "course_heading", "course_totals"]

#: Below this horizontal speed of the fix-interpolated velocity, m/s, the course heading is
#: held (the last heading of faster motion; before the first such motion, the first one):
#: a car at rest does not turn, and the direction of a fix noise's drift is no heading.
COURSE_MIN_SPEED = 1.0

_OPTION = "attitude={'start': 'course'}"


def _fixes(items, data) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and horizontal positions (M, 2) m of the ``Position`` items giving both
    horizontal axes, sorted by time."""
    from ..constraints import Position
    from ..items import as_values

    ts, ps = [], []
    for it in items:
        if not isinstance(it, Position):
            continue
        ax = data.axis_index(it.axes, f"{it.label}: axes")
        if 0 not in ax or 1 not in ax:
            continue
        v = as_values(it.value, it.t.size, len(ax), f"{it.label}: value").reshape(it.t.size, len(ax))
        ts.append(np.asarray(it.t, dtype=float))
        ps.append(v[:, [ax.index(0), ax.index(1)]])
    if not ts:
        raise InputError(f"{_OPTION}: the problem has no Position item on both horizontal axes "
                         f"({data.axes[0]!r}, {data.axes[1]!r}); the course start reads the heading from "
                         "the position fixes: add them (constraints.Position) or leave the start as in the "
                         "data (the default, 'data')")
    t = np.concatenate(ts)
    order = np.argsort(t, kind="stable")
    return t[order], np.concatenate(ps)[order]


def course_heading(t: np.ndarray, fix_t: np.ndarray, fix_xy: np.ndarray,
                   min_speed: float = COURSE_MIN_SPEED) -> np.ndarray:
    r"""The heading (rad, from the first horizontal axis towards the second) at the times ``t``
    (s) of the velocity of the fixes ``fix_xy`` (M, 2) m at ``fix_t`` (s) interpolated
    linearly, held below ``min_speed`` (m/s).

    Notes
    -----
    With :math:`p(t)` the piecewise-linear interpolation of the fixes sampled at ``t`` and
    :math:`v_i` its finite-difference velocity (:func:`numpy.gradient`),

    .. math:: \psi_i = \operatorname{atan2}(v_{i,2}, v_{i,1}) \quad \text{where }
        \|v_i\| \ge v_{min},

    else :math:`\psi_{i-1}` (before the first sample moving that fast, its heading).

    Raises
    ------
    InputError
        Fewer than 2 fixes at distinct times, or no sample whose speed reaches ``min_speed``.
    """
    fix_t = np.asarray(fix_t, dtype=float)
    if np.unique(fix_t).size < 2:
        raise InputError(f"{_OPTION}: {np.unique(fix_t).size} position fix time(s) on the horizontal axes; "
                         "the course heading needs at least 2 fixes at distinct times (a displacement)")
    pos = np.column_stack([np.interp(t, fix_t, fix_xy[:, k]) for k in range(2)])
    vel = np.gradient(pos, t, axis=0)
    speed = np.hypot(vel[:, 0], vel[:, 1])
    moving = np.flatnonzero(speed >= min_speed)
    if moving.size == 0:
        raise InputError(f"{_OPTION}: the fixes never move faster than {min_speed:g} m/s (largest "
                         f"{float(speed.max()):.3g} m/s between fixes), so they imply no heading; leave the "
                         "start as in the data (the default, 'data') or give fixes of the motion")
    yaw = np.arctan2(vel[:, 1], vel[:, 0])
    # index of the last moving sample at or before each sample (the first moving one before it)
    last = np.maximum.accumulate(np.where(speed >= min_speed, np.arange(t.size), -1))
    return yaw[np.where(last < 0, moving[0], last)]


def course_totals(form) -> np.ndarray:
    r"""The attitude-error totals (N, 3) rad that turn the data's attitude into the course
    attitude: :math:`\psi_i = \mathrm{Log}(C^c_i \hat C_i^T)`, where :math:`C^c_i` has the
    course heading (:func:`course_heading` of the problem's ``Position`` items) and the roll
    and pitch of the data's attitude at the first sample (Z-Y-X Euler angles; the body x axis
    is the car's forward axis), so that ``states_at(data, {"attitude_error": psi})`` carries
    :math:`C^c`.

    Raises
    ------
    InputError
        Naming the option: no node states, data without 3 axes and an attitude, no
        ``Position`` item, fewer than 2 fixes, no motion.
    """
    if not form.model.ns:
        raise InputError(f"{_OPTION}: the course start sets the node states' first linearization point; "
                         "this problem has none: use error_model=ErrorStates(...)")
    data = form.data
    if data.ndim != 3 or getattr(data, "attitude", None) is None:
        raise InputError(f"{_OPTION}: needs 3-axis data with an attitude (strapdown); this data has "
                         f"{data.ndim} axis(es)")
    fix_t, fix_xy = _fixes(form.items, data)
    t = np.asarray(data.t, dtype=float)
    yaw = course_heading(t, fix_t, fix_xy)
    _, pitch0, roll0 = data.attitude[0].as_euler("ZYX")
    course = initial_attitude(roll0, pitch0, yaw)
    return (course * data.attitude.inv()).as_rotvec()
