r"""A car's start for the node-state loop: the attitude the position fixes imply.

``solve(..., attitude={"start": "course"})`` with :class:`~bvpnav.error_models.ErrorStates`:
the loop's first linearization point is not the attitude in the data (integrated from the raw
gyro, which a consumer gyro's bias turns by radians in minutes) but the attitude a car has
along the fixes: its heading is the heading of the velocity of the positions interpolated
linearly between the fixes, and its roll and pitch are those of the data's attitude at the
first sample (the initial alignment). The start is given as initial totals of the
attitude-error states, so the loop, its process rows (the raw gyro rates) and its answer are
otherwise those of the default start.

Fixes of a ``Position`` item with a ``gate`` (the user expects outliers among them) are screened
before they give the course (:func:`screened`): a fix that its neighbours, joined by a straight
line, miss by more than a car's motion and the gate times the fixes' noise allow is left out of
the course (not out of the problem: the solve's gating judges it). One outlier of 30 m between
fixes 1 s apart would otherwise turn the course by tens of degrees for two seconds.
"""

from __future__ import annotations

import numpy as np

from ..align import initial_attitude
from ..errors import InputError

__all__ = ["COURSE_MIN_SPEED", "CAR_ACCELERATION", "course_heading", "course_totals", "screened"]

#: Below this horizontal speed of the fix-interpolated velocity, m/s, the course heading is
#: held (the last heading of faster motion; before the first such motion, the first one):
#: a car at rest does not turn, and the direction of a fix noise's drift is no heading.
COURSE_MIN_SPEED = 1.0

#: The largest horizontal acceleration of a road car, m/s^2 (1 g: more than its tyres' grip
#: allows): the fixes' screening (:func:`screened`) lets a path curve this much between them.
CAR_ACCELERATION = 9.80665

_OPTION = "attitude={'start': 'course'}"


def _misses(which: np.ndarray, keep: np.ndarray, fix_t, fix_xy, sigma, gate) -> np.ndarray:
    """:func:`screened`'s ratio of miss to allowance of the fixes ``which`` against the two
    nearest kept fixes other than themselves (both sides where there are; 0 where ``gate`` is
    infinite)."""
    kept = np.flatnonzero(keep)
    pos = np.searchsorted(kept, which)          # kept fixes before each one
    after = pos + keep[which].astype(int)        # skip the fix itself when it is kept
    lo, hi = pos - 1, after
    # both sides where possible; at an end the two nearest on the other side
    first, last = lo < 0, hi >= kept.size
    jn = np.where(first, hi, np.where(last, lo - 1, lo))
    kn = np.where(first, hi + 1, np.where(last, lo, hi))
    j, k = kept[np.clip(jn, 0, kept.size - 1)], kept[np.clip(kn, 0, kept.size - 1)]
    ti, tj, tk = fix_t[which], fix_t[j], fix_t[k]
    wj = (ti - tk) / (tj - tk)
    wk = 1.0 - wj
    miss = np.hypot(*(fix_xy[which] - wj[:, None] * fix_xy[j] - wk[:, None] * fix_xy[k]).T)
    s = np.sqrt(sigma[which] ** 2 + (wj * sigma[j]) ** 2 + (wk * sigma[k]) ** 2)
    with np.errstate(invalid="ignore"):   # an infinite gate: never screened
        allowed = 0.5 * CAR_ACCELERATION * np.abs((ti - tj) * (ti - tk)) + gate[which] * s
        return np.where(np.isfinite(gate[which]), miss / allowed, 0.0)


def screened(fix_t: np.ndarray, fix_xy: np.ndarray, sigma: np.ndarray, gate: np.ndarray) -> np.ndarray:
    r"""Which fixes (bool, M) to keep for the course: those that the straight line through two
    neighbouring kept fixes misses by no more than a car's curving and the gate allow.

    Parameters
    ----------
    fix_t : ndarray (M,)
        Times, s, increasing.
    fix_xy : ndarray (M, 2)
        Horizontal positions, m.
    sigma : ndarray (M,)
        Each fix's horizontal standard deviation, m.
    gate : ndarray (M,)
        Each fix's gate (normalized residual), ``inf`` for a fix that is never screened.

    Notes
    -----
    For fix :math:`i` and its kept neighbours :math:`j < i < k` (at the ends the two nearest
    kept fixes on one side), the line through them predicts :math:`\hat p_i = w_j p_j + w_k
    p_k` with the Lagrange weights :math:`w_j = (t_i - t_k)/(t_j - t_k)`, :math:`w_k = 1 -
    w_j`. A path of acceleration at most :math:`a` departs from that line by at most
    :math:`\tfrac{a}{2} |(t_i - t_j)(t_i - t_k)|`, and the fixes' noise by a standard
    deviation :math:`s_i = \sqrt{\sigma_i^2 + w_j^2 \sigma_j^2 + w_k^2 \sigma_k^2}`. The fix
    whose miss :math:`\|p_i - \hat p_i\|` exceeds :math:`\tfrac{a}{2}|(t_i - t_j)(t_i -
    t_k)| + g_i s_i` by the largest ratio is left out, and the test is repeated until every
    kept fix passes (:data:`CAR_ACCELERATION` for :math:`a`); a fix left out that then passes
    against its kept neighbours is let back (an outlier next to it had made it miss). At
    least three fixes are kept; with fewer than three nothing is screened.

    Examples
    --------
    Fixes 1 s apart along a straight road at 10 m/s, one of them 30 m off:

    >>> import numpy as np
    >>> from bvpnav.solve.course import screened
    >>> t = np.arange(6.0)
    >>> xy = np.column_stack([10.0 * t, np.zeros(6)])
    >>> xy[3, 1] = 30.0
    >>> screened(t, xy, np.full(6, 0.5), np.full(6, 5.0)).tolist()
    [True, True, True, False, True, True]
    """
    m = fix_t.size
    keep = np.ones(m, dtype=bool)
    if m < 3:
        return keep
    for _ in range(2 * m):   # each fix is left out, and let back, at most once or so
        ratio = _misses(np.flatnonzero(keep), keep, fix_t, fix_xy, sigma, gate)
        if np.any(ratio > 1.0) and keep.sum() > 3:
            keep[np.flatnonzero(keep)[int(np.argmax(ratio))]] = False
            continue
        out = np.flatnonzero(~keep)   # a fix left out because of a neighbour that is now out
        back = _misses(out, keep, fix_t, fix_xy, sigma, gate) if out.size else out
        if not np.any(back <= 1.0):
            break
        keep[out[int(np.argmin(back))]] = True
    return keep


def _fixes(items, data) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and horizontal positions (M, 2) m of the ``Position`` items giving both
    horizontal axes, sorted by time, without the fixes :func:`screened` leaves out (those of
    items with a ``gate``)."""
    from ..constraints import Position
    from ..items import as_values

    ts, ps, sig, gates = [], [], [], []
    for it in items:
        if not isinstance(it, Position):
            continue
        ax = data.axis_index(it.axes, f"{it.label}: axes")
        if 0 not in ax or 1 not in ax:
            continue
        v = as_values(it.value, it.t.size, len(ax), f"{it.label}: value").reshape(it.t.size, len(ax))
        ts.append(np.asarray(it.t, dtype=float))
        ps.append(v[:, [ax.index(0), ax.index(1)]])
        gate = getattr(it, "gate", None)
        gates.append(np.full(it.t.size, np.inf if gate is None else float(gate)))
        if gate is None or it.sigma is None:
            sig.append(np.zeros(it.t.size))
        else:   # the larger horizontal sigma of each fix (gated items have a sigma)
            s = it.weight_rows(it.t.size * len(ax)).reshape(it.t.size, len(ax))
            sig.append(np.max(s[:, [ax.index(0), ax.index(1)]], axis=1))
    if not ts:
        raise InputError(f"{_OPTION}: the problem has no Position item on both horizontal axes "
                         f"({data.axes[0]!r}, {data.axes[1]!r}); the course start reads the heading from "
                         "the position fixes: add them (constraints.Position) or leave the start as in the "
                         "data (the default, 'data')")
    t = np.concatenate(ts)
    order = np.argsort(t, kind="stable")
    t, xy = t[order], np.concatenate(ps)[order]
    keep = screened(t, xy, np.concatenate(sig)[order], np.concatenate(gates)[order])
    return t[keep], xy[keep]


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
