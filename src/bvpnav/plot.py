"""Figures: the L-curve with every rule's choice, trajectories and errors, solver comparisons.

Every function returns the ``Figure``; those that draw one panel take an optional
matplotlib ``Axes``. Nothing is shown or saved (use :func:`bvpnav.io.atomic_savefig` to
write a file atomically). matplotlib is imported only when a figure is drawn.

A solution solved with ``uncertainty=True`` or ``"scaled"`` (its trajectory has
``<axis>_std`` and ``v<axis>_std`` columns) is drawn by :func:`trajectory` and
:func:`solution` with a light band of +/- 2 standard deviations (labelled ``"±2σ"``)
around its positions and velocities.
"""

from __future__ import annotations

import re

import numpy as np

__all__ = ["lcurve", "solution", "trajectory", "errors", "comparison", "stationary"]

_MARKERS = {"lcurve": ("o", "C3"), "gcv": ("s", "C0"), "discrepancy": ("^", "C2"), "quasi": ("D", "C1")}


#: Opacity of the +/- 2 sigma bands.
BAND_ALPHA = 0.2
#: Label of the +/- 2 sigma bands.
BAND_LABEL = "±2σ"


def _std(sol, column: str) -> np.ndarray | None:
    """The standard deviations in ``column`` of the solution's trajectory, or None."""
    traj = getattr(sol, "trajectory", None)
    if traj is None or column not in traj.columns:
        return None
    return traj[column].to_numpy(dtype=float)


def _band(ax, t, centre, std, color, label: str = BAND_LABEL) -> None:
    """Shade ``centre`` +/- 2 ``std`` (a PolyCollection behind the lines)."""
    centre = np.asarray(centre, dtype=float)
    ax.fill_between(t, centre - 2 * std, centre + 2 * std, color=color, alpha=BAND_ALPHA, lw=0,
                    zorder=0.5, label=label)


def _axes(ax, **kw):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(**kw)
        return fig, ax
    return ax.figure, ax


def lcurve(curve, ax=None, annotate: bool = True):
    """Log-log L-curve (data residual norm vs information norm) with the chosen lambdas.

    Parameters
    ----------
    curve : bvpnav.lam.sweep.LambdaCurve
    ax : matplotlib Axes, optional

    Notes
    -----
    The curve is drawn through every lambda the sweep solved (its samples and the rules'
    refinements, :attr:`~bvpnav.lam.sweep.LambdaCurve.evaluated`); each rule's choice is
    marked at its (refined) lambda, interpolated on that curve in log-log coordinates
    (exactly on it when the choice was evaluated).
    """
    fig, ax = _axes(ax, figsize=(6, 5))
    lam_all, rho, eta = curve.lam, curve.residual_norm, curve.info_norm
    ev = getattr(curve, "evaluated", None)
    if ev is not None and len(ev) >= len(lam_all):   # the refinements too: the corner drawn densely
        lam_all, rho, eta = ev[:, 0], ev[:, 1], ev[:, 2]
    ax.loglog(rho, eta, ".-", color="0.4", lw=1, label="sweep")
    s = np.log(lam_all)
    for rule, lam in curve.chosen.items():
        m, c = _MARKERS.get(rule, ("x", "k"))
        u = np.log(lam)
        x = np.exp(np.interp(u, s, np.log(rho)))
        y = np.exp(np.interp(u, s, np.log(eta)))
        ax.loglog([x], [y], m, color=c, ms=9, mfc="none", mew=2,
                  label=f"{rule}: lambda = {lam:.3g}" + (" (used)" if rule == curve.rule else ""))
    ax.set_xlabel("residual norm  rho(lambda) (1)")
    ax.set_ylabel("information norm  eta(lambda) (1)")
    ax.set_title("L-curve")
    if annotate:
        ax.legend(fontsize=8)
    return fig


def _truth_array(truth, sol) -> np.ndarray | None:
    """True positions as shape (N, d) at the solution's samples, or InputError."""
    if truth is None:
        return None
    from .errors import InputError

    if hasattr(truth, "columns"):  # a table with one column per axis (t as column or index)
        cols = list(sol._pos_cols)
        if cols == ["x", "y", "z"] and {"x", "y"} <= set(truth.columns) and "z" not in truth.columns:
            cols = ["x", "y"]  # a 2-D truth: drawn on the map and the x, y panels
        missing = [a for a in cols if a not in truth.columns]
        if missing:
            raise InputError(f"truth: no column for axis/axes {missing}; it has {list(truth.columns)} "
                             f"(give one column per axis {sol._pos_cols}, positions in m)")
        truth = truth[cols].to_numpy(dtype=float)
    arr = np.asarray(truth, dtype=float)
    n, d = len(sol.t), len(sol._pos_cols)
    if d == 3 and arr.shape == (n, 2):  # a 2-D truth (x, y) of a 3-axis solution: no z to draw
        arr = np.column_stack([arr, np.full(n, np.nan)])
    if arr.size != n * d:
        raise InputError(f"truth of shape {arr.shape} does not match the solution's {n} samples x "
                         f"{d} axes {sol._pos_cols}; give true positions in m at the sample times")
    return arr.reshape(n, d)


def trajectory(solutions: dict, truth=None, axis: str | None = None, ax=None):
    """Position against time for several solutions (``{label: Solution}``), with the truth (m).

    With several axes (``axis=None``) each line is labelled ``"<label> <axis>"`` and the
    truth of an axis is drawn in that axis' colour, dashed. A solution with standard
    deviations (``solve(uncertainty=...)``) gets a band of +/- 2 std in its line's colour,
    labelled ``"<line label> ±2σ"``.
    """
    fig, ax = _axes(ax, figsize=(8, 4))
    t = None
    colours = {}
    for k, (label, sol) in enumerate(solutions.items()):
        t = sol.t
        axes = sol._pos_cols if axis is None else [sol._axis(axis, "position")]
        for j, a in enumerate(axes):
            name = label if len(axes) == 1 else f"{label} {a}"
            (line,) = ax.plot(t, sol.position(a), label=name, color=f"C{(k * len(axes) + j) % 10}")
            colours.setdefault(a, line.get_color())
            std = _std(sol, f"{a}_std")
            if std is not None:
                _band(ax, t, sol.position(a), std, line.get_color(), label=f"{name} {BAND_LABEL}")
    if truth is not None and t is not None:
        tr = np.asarray(truth, dtype=float)
        tr = tr.reshape(len(t), -1)
        names = list(colours) if tr.shape[1] == len(colours) else [None] * tr.shape[1]
        for j, a in enumerate(names):
            one = tr.shape[1] == 1
            ax.plot(t, tr[:, j], "k" if one else "--", color="k" if one else colours.get(a, "k"),
                    lw=2, alpha=0.6, label="truth" if one else f"truth {a}")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("position (m)" if axis is None else f"position {axis} (m)")
    ax.legend(fontsize=8)
    return fig


#: How each built-in item is drawn by :func:`solution`: the panel it acts on.
_ITEM_STYLE = {"position": ("o", "C3"), "velocity": ("s", "C2"), "average_velocity": ("-", "C1"),
               "zero_velocity": ("", "C4"), "symmetry": ("", "C5"), "speed_limit": ("", "C6"),
               "position_bound": ("", "C7"), "track_line": ("-", "C8")}


def _item_axes(item, axes: list) -> list:
    return [a for a in (item.axes if item.axes is not None else axes) if a in axes]


def _item_values(item, value, k: int, axes_of_item: list) -> np.ndarray:
    from .items import as_values

    return np.asarray(as_values(value, k, len(axes_of_item), f"{item.label}: value"), float).reshape(
        k, len(axes_of_item))


#: A numbered item name (``"stance 3"``, ``"fix_12"``, ``"Position#2"``): its stem and number.
_NUMBERED = re.compile(r"^(.*?)[\s_#-]*\d+$")


def _item_names(items) -> dict[int, str]:
    """One legend label per kind of item and mode (``id(item)`` -> label).

    A kind with one item in a mode keeps its own name (``"start (hard)"``); several share
    one entry, named after their common stem when their names are numbered (``"stance
    (hard, 11 items)"`` for ``stance 0`` ... ``stance 10``), else after the kind
    (``"zero velocity (soft, 3 items)"``).
    """
    groups: dict[tuple[str, str], list] = {}
    for item in items:
        groups.setdefault((type(item).registered_name(), item.mode), []).append(item)
    out = {}
    for (kind, mode), its in groups.items():
        if len(its) == 1:
            out[id(its[0])] = f"{its[0].label} ({mode})"
            continue
        stems = set()
        for it in its:
            hit = _NUMBERED.match(it.label)
            stems.add(hit.group(1).strip() if hit and hit.group(1).strip() else it.label)
        stem = stems.pop() if len(stems) == 1 else kind.replace("_", " ")
        for it in its:
            out[id(it)] = f"{stem} ({mode}, {len(its)} items)"
    return out


def _span(item, t_range) -> tuple[float, float]:
    t0, t1 = getattr(item, "t0", None), getattr(item, "t1", None)
    return (t_range[0] if t0 is None else float(t0)), (t_range[1] if t1 is None else float(t1))


def _draw_known(item, kind, on, p, name, mk, col, hollow):
    tk = np.atleast_1d(np.asarray(item.t, float))
    vals = _item_values(item, item.value, tk.size, on)
    panels = p["pos"] if kind == "position" else p["vel"]
    for j, a in enumerate(on):
        panels[a].plot(tk, vals[:, j], mk, color=col, mfc=hollow, ms=7, mew=1.5, zorder=5, label=name)
    path = p["path"]
    if kind == "position" and path is not None and all(a in on for a in path._bvpnav_axes):
        i, j = (on.index(a) for a in path._bvpnav_axes)
        path.plot(vals[:, i], vals[:, j], mk, color=col, mfc=hollow, ms=5, mew=1.2, zorder=5, label=name)


def _draw_average_velocity(item, kind, on, p, name, mk, col, hollow):
    t0 = np.atleast_1d(np.asarray(item.t0, float))
    t1 = np.atleast_1d(np.asarray(item.t1, float))
    vals = _item_values(item, item.value, t0.size, on)
    for j, a in enumerate(on):
        for i in range(t0.size):
            p["vel"][a].plot([t0[i], t1[i]], [vals[i, j]] * 2, "-", color=col, lw=3, alpha=0.8,
                             solid_capstyle="butt", zorder=5, label=name)


def _draw_zero_velocity(item, kind, on, p, name, mk, col, hollow):
    t0 = np.atleast_1d(np.asarray(item.t0, float))
    t1 = np.atleast_1d(np.asarray(item.t1, float))
    for a in on:
        for i in range(t0.size):
            p["vel"][a].axvspan(t0[i], t1[i], color=col, alpha=0.15, lw=0, label=name)


def _draw_symmetry(item, kind, on, p, name, mk, col, hollow):
    for a in on:
        for c in np.atleast_1d(np.asarray(item.about, float)):
            p["pos"][a].axvline(c, color=col, ls=":", lw=1.5, label=name)


def _draw_speed_limit(item, kind, on, p, name, mk, col, hollow):
    lo, hi = _span(item, p["t_range"])
    for a in on:
        for sgn in (1, -1):
            p["vel"][a].plot([lo, hi], [sgn * item.v_max] * 2, "--", color=col, lw=1, label=name)


def _draw_position_bound(item, kind, on, p, name, mk, col, hollow):
    for which, tt in (("lower", item.lower_t), ("upper", item.upper_t)):
        v = getattr(item, which)
        if v is None:
            continue
        v = np.atleast_1d(np.asarray(v, float))
        if tt is None:  # a constant bound over the item's interval
            if v.size != 1:
                continue  # one bound per axis: not drawn
            tt, v = np.array(_span(item, p["t_range"])), np.repeat(v, 2)
        tt = np.atleast_1d(np.asarray(tt, float))
        if v.size == tt.size:
            for a in on:
                p["pos"][a].plot(tt, v, "--", color=col, lw=1, label=name)


def _draw_track_line(item, kind, on, p, name, mk, col, hollow):
    path = p["path"]
    if path is not None and list(item.axes or ()) == path._bvpnav_axes:
        path.plot(np.asarray(item.x, float), np.asarray(item.y, float), "-", color=col, lw=4, alpha=0.3,
                  label=name)


_DRAW = {"position": _draw_known, "velocity": _draw_known, "average_velocity": _draw_average_velocity,
         "zero_velocity": _draw_zero_velocity, "symmetry": _draw_symmetry, "speed_limit": _draw_speed_limit,
         "position_bound": _draw_position_bound, "track_line": _draw_track_line}


def _draw_items(items, axes: list, pos_ax: dict, vel_ax: dict, path_ax, t_range) -> None:
    """Draw each item where it acts: positions and velocities as markers at their times,
    average velocities as segments over their intervals, stationary intervals and
    symmetry centres as shading and lines, speed limits and position bounds as limits,
    a track on the path panel. Other items (half-spaces, linear rows, plug-ins) are not
    drawn; they are in the summary's item table."""
    panels = {"pos": pos_ax, "vel": vel_ax, "path": path_ax, "t_range": t_range}
    drawn = [it for it in items or () if getattr(type(it), "registered_name", None) is not None
             and type(it).registered_name() in _DRAW]
    names = _item_names(drawn)
    for item in drawn:
        kind = type(item).registered_name()
        mk, col = _ITEM_STYLE[kind]
        _DRAW[kind](item, kind, _item_axes(item, axes), panels, names[id(item)], mk, col,
                    "none" if item.mode != "hard" else col)


def _draw_rejected(sol, axes: list, pos_ax: dict, vel_ax: dict, path_ax) -> None:
    """The fixes gating rejected (``sol.rejected``) as red crosses where their values are:
    on the position (m) or velocity (m/s) panels, and on the path when both of its axes are
    given."""
    rej = getattr(sol, "rejected", None)
    if rej is None or not len(rej):
        return
    label = f"rejected by gating ({len(rej)})"
    for a in axes:
        col = f"value_{a}"
        if col not in rej:
            continue
        for units, panels in (("m", pos_ax), ("m/s", vel_ax)):
            sel = (rej["units"] == units).to_numpy() & np.isfinite(rej[col].to_numpy(dtype=float))
            if sel.any():
                panels[a].plot(rej["t"].to_numpy()[sel], rej[col].to_numpy(dtype=float)[sel], "x",
                               color="red", ms=7, mew=1.5, label=label, zorder=5)
    if path_ax is not None:
        h = getattr(path_ax, "_bvpnav_axes", axes[:2])
        cols = [f"value_{a}" for a in h]
        if all(c in rej for c in cols):
            sel = (rej["units"] == "m").to_numpy()
            xy = rej[cols].to_numpy(dtype=float)[sel]
            ok = np.all(np.isfinite(xy), axis=1)
            if ok.any():
                path_ax.plot(xy[ok, 0], xy[ok, 1], "x", color="red", ms=7, mew=1.5, label=label, zorder=5)


def _legend(ax, **kw) -> None:
    """A legend with one entry per label (items draw one artist per instant or axis)."""
    handles, labels = ax.get_legend_handles_labels()
    seen = {}
    for h, lab in zip(handles, labels, strict=True):
        seen.setdefault(lab, h)
    if seen:
        ax.legend(list(seen.values()), list(seen), **kw)


def solution(sol, items=None, truth=None, label: str | None = None):
    """The whole solution on one figure: a panel per quantity.

    One row per axis with its position (m) and velocity (m/s) against time; then the
    acceleration residuals ``w`` (m/s^2, the correction the estimate implies at each
    sample, one line per axis), and for 2 or 3 axes the path in the horizontal plane
    (the first two axes, equal scales). For 1 axis with a truth, that panel is the
    position error instead.

    A solution with standard deviations (``solve(uncertainty=...)``: ``<axis>_std`` and
    ``v<axis>_std`` columns) has a light band of +/- 2 std around each position and
    velocity (and around zero on the position error panel), labelled ``"±2σ"``; the title
    says whether they are under the stated noise or scaled.

    Parameters
    ----------
    sol : Solution
    items : sequence of Item, optional
        The problem's items (``problem.items`` or ``spec.items``), drawn where they act:
        known positions and velocities as markers at their times (filled: hard; hollow:
        soft, robust or band; one legend entry per kind of item and mode, e.g. one for
        eleven stances ``stance 0`` ... ``stance 10``), average velocities as segments over their intervals,
        stationary intervals shaded, symmetry centres as dotted lines, speed limits and
        position bounds as dashed limits, a :class:`~bvpnav.constraints.TrackLine` and the
        positions given on both of its axes (fixes) on the path panel. Fixes rejected by
        gating (``sol.rejected``) are red crosses at their values, whether or not
        ``items`` is given.
    truth : array_like or DataFrame, optional
        True positions (m) at the sample times, shape (N,) or (N, d), or a table with one
        column per axis (e.g. ``truth.csv`` written by ``bvpnav simulate``). For an x, y, z
        solution a 2-D truth (shape (N, 2) or a table with x and y: motion capture) is drawn
        on the path and the x and y panels.
    label : str, optional
        Legend label of the estimate (default ``"bvpnav (<solver>)"``).

    Returns
    -------
    matplotlib.figure.Figure
        Its axes titled ``"position <axis>"``, ``"velocity <axis>"``, ``"residuals"``,
        ``"path <a>-<b>"`` or ``"position error"``.
    """
    import matplotlib.pyplot as plt

    axes = list(sol._pos_cols)
    d = len(axes)
    tru = _truth_array(truth, sol)
    label = label or f"bvpnav ({sol.stats.get('solver')})"
    extra = d >= 2 or tru is not None
    rows = d + 1
    fig = plt.figure(figsize=(9, 2.1 * rows + 0.6), layout="constrained")
    grid = fig.add_gridspec(rows, 2)
    t = sol.t
    pos_ax, vel_ax = {}, {}
    first = None
    for i, a in enumerate(axes):
        pa = fig.add_subplot(grid[i, 0], sharex=first)
        first = first or pa
        va = fig.add_subplot(grid[i, 1], sharex=first)
        pa.plot(t, sol.position(a), color="C0", lw=1.5, label=label)
        va.plot(t, sol.velocity(a), color="C0", lw=1.5, label=label)
        for panel, centre, col in ((pa, sol.position(a), f"{a}_std"), (va, sol.velocity(a), f"v{a}_std")):
            std = _std(sol, col)
            if std is not None:
                _band(panel, t, centre, std, "C0")
        if tru is not None and np.isfinite(tru[:, i]).any():  # a 2-D truth has no z
            pa.plot(t, tru[:, i], color="k", lw=2.5, alpha=0.35, label="truth", zorder=1)
        pa.set_title(f"position {a}", fontsize=10)
        va.set_title(f"velocity {a}", fontsize=10)
        pa.set_ylabel(f"{a} (m)")
        va.set_ylabel(f"v{a} (m/s)")
        pos_ax[a], vel_ax[a] = pa, va
    res = fig.add_subplot(grid[d, 0] if extra else grid[d, :], sharex=first)
    for j, a in enumerate(axes):
        col = f"w_{a}"
        if col in sol.residuals:
            res.plot(sol.residuals.index.to_numpy(), sol.residuals[col].to_numpy(), lw=0.8,
                     color=f"C{j}", label=f"w {a}")
    res.axhline(0, color="k", lw=0.5)
    res.set_title("residuals", fontsize=10)
    res.set_ylabel("w (m/s$^2$)")
    res.set_xlabel("t (s)")
    if d > 1:
        res.legend(fontsize=7, ncol=d)
    path = None
    if d >= 2:
        path = fig.add_subplot(grid[d, 1])
        h = axes[:2]
        path._bvpnav_axes = h
        p = sol.position()
        path.plot(p[:, 0], p[:, 1], color="C0", lw=1.5, label=label)
        path.plot(p[:1, 0], p[:1, 1], "o", color="C0", ms=5, label="start")
        if tru is not None:
            flat = d == 3 and not np.isfinite(tru[:, 2]).any()
            path.plot(tru[:, 0], tru[:, 1], color="k", lw=2.5, alpha=0.35,
                      label="truth (x, y only)" if flat else "truth", zorder=1)
        path.set_title(f"path {h[0]}-{h[1]}", fontsize=10)
        path.set_xlabel(f"{h[0]} (m)")
        path.set_ylabel(f"{h[1]} (m)")
        path.set_aspect("equal", adjustable="datalim")
    elif tru is not None:
        err = fig.add_subplot(grid[d, 1], sharex=first)
        e = sol.position(axes[0]) - tru[:, 0]
        err.plot(t, e, color="C0", lw=1, label=f"RMS {np.sqrt(np.mean(e ** 2)):.3g} m")
        std = _std(sol, f"{axes[0]}_std")
        if std is not None:
            _band(err, t, np.zeros_like(e), std, "C0")
        err.axhline(0, color="k", lw=0.5)
        err.set_title("position error", fontsize=10)
        err.set_ylabel(f"{axes[0]} - truth (m)")
        err.set_xlabel("t (s)")
        err.legend(fontsize=7)
    _draw_items(items, axes, pos_ax, vel_ax, path, (float(t[0]), float(t[-1])))
    _draw_rejected(sol, axes, pos_ax, vel_ax, path)
    for a in axes:
        _legend(pos_ax[a], fontsize=7)
        if len(vel_ax[a].get_legend_handles_labels()[1]) > 1:
            _legend(vel_ax[a], fontsize=7)
    if path is not None:
        _legend(path, fontsize=7)
    fig.suptitle(f"lambda = {sol.lam:.3g} ({sol.lam_rule}); {sol.stats.get('solver')} "
                 f"{sol.stats.get('status')}" + (", verified" if sol.stats.get("verified") else "")
                 + _band_note(sol), fontsize=10)
    return fig


def _band_note(sol) -> str:
    """What the bands hold, for the title (empty without standard deviations)."""
    rec = sol.stats.get("uncertainty") or {}
    if not rec or not any(str(c).endswith("_std") for c in sol.trajectory.columns):
        return ""
    if rec.get("scale") == "scaled":
        vf = rec.get("variance_factor")
        return f"; {BAND_LABEL} scaled by the variance factor" + (
            f" {vf:.3g}" if isinstance(vf, float) and np.isfinite(vf) else "")
    return f"; {BAND_LABEL} under the stated noise"


def errors(solutions: dict, truth, axis: str | None = None, ax=None):
    """Position error (m) against time for several solutions, with each RMS in the legend."""
    fig, ax = _axes(ax, figsize=(8, 4))
    truth = np.asarray(truth, dtype=float)
    for label, sol in solutions.items():
        pos = np.asarray(sol.position(axis), dtype=float)
        if pos.ndim == 2 and truth.ndim == 1:
            if pos.shape[1] != 1:
                raise ValueError(f"truth has one axis but the solution has {pos.shape[1]}; pass axis=")
            pos = pos[:, 0]
        e = pos - truth
        ax.plot(sol.t, e, label=f"{label} (RMS {np.sqrt(np.mean(e**2)):.3g} m)")
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("position error (m)")
    ax.legend(fontsize=8)
    return fig


def _decade_axis(a, vals) -> None:
    """Log x axis over whole decades with labels at the decades only (``0.01``, ``1e-10``):
    no crowded minor labels however narrow the range; room on the right for the values."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    v = np.asarray(vals, float)
    v = v[np.isfinite(v) & (v > 0)]
    lo, hi = (np.floor(np.log10(v.min())), np.ceil(np.log10(v.max()))) if v.size else (-3.0, 0.0)
    hi = max(hi, lo + 1) + 0.6  # the value labels
    a.set_xscale("log")
    a.set_xlim(10 ** lo, 10 ** hi)
    step = max(1, int(np.ceil((hi - lo) / 6)))
    a.xaxis.set_major_locator(LogLocator(base=10.0 ** step, numticks=12))
    a.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    a.xaxis.set_minor_formatter(NullFormatter())
    a.grid(axis="x", which="major", lw=0.4, alpha=0.5)


def comparison(table, ax=None):
    """Wall time and accuracy of each run of a :func:`bvpnav.compare_solvers` table.

    Two panels of horizontal bars, one bar per run (``solver/preset``, named on the
    vertical axis so long names stay readable): the wall time (s, log scale; the
    ``wall_time`` column, as ``bvpnav compare`` prints it) and the accuracy (the
    ``rms_error`` against the reference when the table has one, else the estimated
    ``forward_error``, else the ``fem_residual``). Failed or unverified runs are drawn
    hatched and hollow with their status, so they are visible, not hidden.

    Parameters
    ----------
    table : pandas.DataFrame
    ax : sequence of two matplotlib Axes, optional
    """
    import matplotlib.pyplot as plt

    def usable(col):
        return col in table and np.isfinite(table[col].to_numpy(dtype=float)).any()

    ycol = next((c for c in ("rms_error", "forward_error", "fem_residual") if usable(c)), "fem_residual")
    n = len(table)
    if ax is None:
        fig, (a_t, a_e) = plt.subplots(1, 2, figsize=(9, 1.2 + 0.45 * max(n, 1)), sharey=True,
                                       layout="constrained")
    else:
        a_t, a_e = ax
        fig = a_t.figure
    names = [f"{r.solver}/{r.preset}" for r in table.itertuples(index=False)]
    yk = np.arange(n)[::-1]
    for a, col, unit in ((a_t, "wall_time", "s"), (a_e, ycol, "")):
        vals = table[col].to_numpy(dtype=float) if col in table else np.full(n, np.nan)
        for k, row in enumerate(table.itertuples(index=False)):
            d = row._asdict()
            ok = bool(d.get("verified", False))
            v = vals[k]
            if not np.isfinite(v):
                a.text(0.02, yk[k], f"({d.get('status')})", transform=a.get_yaxis_transform(),
                       va="center", fontsize=8, color="0.4")
                continue
            a.barh(yk[k], max(v, 1e-300), height=0.6, left=1e-300, color=f"C{k % 10}" if ok else "none",
                   edgecolor=f"C{k % 10}", hatch=None if ok else "//", lw=1.5)
            a.text(v, yk[k], f" {v:.3g}{(' ' + unit) if unit else ''}"
                   + ("" if ok else f" ({d.get('status')}, not verified)"), va="center", fontsize=8)
        _decade_axis(a, vals)
    a_t.set_yticks(yk, names, fontsize=9)
    a_t.set_ylabel("run (solver/preset)")
    a_t.set_xlabel("wall time (s)")
    a_t.set_title("wall time", fontsize=10)
    a_e.set_xlabel(ycol.replace("_", " ") + (" (m)" if ycol == "rms_error" else " (relative)"))
    a_e.set_title(ycol.replace("_", " "), fontsize=10)
    return fig


def stationary(data, result, path=None, *, method: str = "shoe", **detector_kw):
    r"""Check a stationary detection: the statistic against its threshold, the signals, the intervals.

    Three panels against time (s), the stationary intervals shaded on each: the
    detector's per-sample statistic (log scale) with the threshold as a dashed line (a
    sample is stationary below it); the specific-force magnitude :math:`\|f\|` (m/s^2)
    with g; the gyro magnitude :math:`\|\omega\|` (rad/s, log scale) when the data has
    gyro rates. Where the statistic of the moving samples comes close to the line, the
    threshold is marginal.

    Parameters
    ----------
    data : ImuData
        The strapdown data the detection ran on.
    result : bvpnav.detect.Detection or list of (float, float)
        ``stationary(..., return_statistic=True)``, or intervals ``(t0, t1)`` in s (then
        the statistic is computed with ``method`` and ``detector_kw`` by
        :func:`bvpnav.detect.stationary`, and the given intervals are shaded).
    path : str or os.PathLike, optional
        Also write the figure there, atomically, in the format of its suffix
        (:func:`bvpnav.io.atomic_savefig`).
    method : str
        Detector of the statistic when ``result`` is a list of intervals.
    **detector_kw
        Its settings (``window``, ``threshold``, ``sigma_a``, ...), likewise.

    Returns
    -------
    matplotlib.figure.Figure
        Its axes titled ``"statistic"``, ``"specific force"`` and (with gyro rates)
        ``"angular rate"``.
    """
    import matplotlib.pyplot as plt

    from .detect import Detection
    from .detect import stationary as detect_stationary

    det = result if isinstance(result, Detection) else detect_stationary(
        data, method, return_statistic=True, **detector_kw)
    intervals = det.intervals if isinstance(result, Detection) else [tuple(map(float, iv)) for iv in result]
    t = data.t
    rows = 3 if data.gyro is not None else 2
    fig, axs = plt.subplots(rows, 1, figsize=(9, 1.9 * rows + 0.8), sharex=True, layout="constrained")
    stat = np.maximum(np.asarray(det.statistic, float), np.finfo(float).tiny)
    axs[0].semilogy(t, stat, color="C0", lw=1, label=f"{det.method} statistic")
    thr = np.asarray(det.threshold, dtype=float)
    thr_txt = f"{float(thr):.3g}" if thr.ndim == 0 else f"adaptive {thr.min():.3g}..{thr.max():.3g}"
    if thr.ndim == 0:
        axs[0].axhline(float(thr), color="C3", ls="--", lw=1.2, label=f"threshold {thr_txt}")
    else:
        axs[0].semilogy(t, thr, color="C3", ls="--", lw=1.2, label=f"threshold {thr_txt}")
    axs[0].set_ylabel("statistic (1)")
    axs[0].set_title("statistic", fontsize=10)
    fn = np.linalg.norm(data.specific_force, axis=1)
    g = det.params.get("gravity")
    axs[1].plot(t, fn, color="C0", lw=0.8, label="|f|")
    axs[1].axhline(g, color="k", lw=0.6, ls=":", label=f"g = {g:g} m/s$^2$")
    acc_thr = det.params.get("acc_threshold")
    if acc_thr is not None:
        axs[1].axhspan(g - acc_thr, g + acc_thr, color="C3", alpha=0.1, lw=0, label="g ± acc_threshold")
    axs[1].set_ylabel("|f| (m/s$^2$)")
    axs[1].set_title("specific force", fontsize=10)
    if data.gyro is not None:
        wn = np.maximum(np.linalg.norm(data.gyro, axis=1), np.finfo(float).tiny)
        axs[2].semilogy(t, wn, color="C0", lw=0.8, label="|ω|")
        if det.params.get("gyro_threshold") is not None:
            axs[2].axhline(det.params["gyro_threshold"], color="C3", ls="--", lw=1.2, label="gyro_threshold")
        axs[2].set_ylabel("|ω| (rad/s)")
        axs[2].set_title("angular rate", fontsize=10)
    for a in axs:
        for k, (t0, t1) in enumerate(intervals):
            a.axvspan(t0, t1, color="C2", alpha=0.15, lw=0, label="stationary" if k == 0 else None)
        _legend(a, fontsize=7, loc="upper right")
    axs[-1].set_xlabel("t (s)")
    share = sum(t1 - t0 for t0, t1 in intervals) / max(float(t[-1] - t[0]), np.finfo(float).tiny)
    fig.suptitle(f"{det.method}: window {det.window} samples, threshold {thr_txt}; "
                 f"{len(intervals)} intervals, {100 * share:.0f} % of the time stationary", fontsize=10)
    if path is not None:
        from .io import atomic_savefig

        atomic_savefig(fig, path)
    return fig
