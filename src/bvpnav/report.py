r"""A quality report of a solution: one self-contained HTML file a person opens in a browser.

:func:`write_report` (``Solution.report(path)``, ``bvpnav solve ... --report r.html``)
writes one HTML file with every figure embedded as a base64 PNG and no external
resource (no script, stylesheet, font or image from elsewhere): it can be mailed,
archived and opened offline. Its sections:

1. **Summary**: samples, window, axes, lambda and its rule, solver, status, bvpnav's
   verification numbers (FEM residual, worst hard-item violation, stationarity,
   forward error against the preset's tolerance).
2. **Trajectory**: the map view (the first two axes, equal scales) with the +/- 2 sigma
   ellipses of the horizontal position where the solution has standard deviations,
   the position fixes (down-weighted ones marked) and the truth when given; then position
   and velocity per axis with their bands (:func:`bvpnav.plot.solution`).
3. **Residuals**: each item's normalized residuals :math:`\rho_i/\sigma_i` over time
   (and the acceleration residuals :math:`w/\sigma_a` of the acceleration form), the
   down-weighted rows of robust items marked; a table of the worst ones (time, item,
   row, residual, sigma, normalized residual) and the items' table.
4. **Sensor errors**: the error-model estimates over time (knots of time-varying models
   at their times, constant ones as lines) with +/- 2 sigma, and their table.
5. **Attitude**: for strapdown data, the correction applied to the data's attitude
   (rotation vector of :math:`C C_0^T`, degrees) over time.
6. **Solve record**: lambda's curve when a rule chose it, the outer loop's iterations
   (sequential or attitude loop), the attempts, demotions, and every warning.

:func:`figures` returns the report's figures by name (for a gallery or a notebook);
:func:`normalized_residuals` the table behind section 3.

Notes
-----
A row is *down-weighted* when its robust penalty is in its linear part: Huber rows with
:math:`|\rho_i| > M` (weight :math:`M/|\rho_i|` relative to least squares), L1 rows with
:math:`|\rho_i| > \sigma_i`. The normalized residual is :math:`\rho_i/\sigma_i` whatever
lambda is (the items' weights are :math:`\lambda/\sigma_i^2`; the report states lambda).
"""

from __future__ import annotations

import base64
import html
import io as _io
import os
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["figures", "normalized_residuals", "render_html", "write_report", "WORST_ROWS", "FIGURES",
           "map_view", "residual_figure", "sensor_error_figure", "attitude_figure", "loop_figure"]

#: The report's figures, in the order of the page (those that apply to a solution).
FIGURES = ("map", "solution", "residuals", "sensor_errors", "attitude", "lcurve", "loop")

#: Rows of the worst-normalized-residual table.
WORST_ROWS = 20
#: Ellipses drawn on the map view (at most).
ELLIPSES = 25
#: Normalized residual beyond which a fix is marked on the map view.
OUTLIER = 3.0
#: Resolution of the embedded PNGs, dots per inch.
DPI = 80


# --------------------------------------------------------------------------- tables
def _down_weighted(rows, r: np.ndarray) -> np.ndarray:
    """Rows of a robust item in the linear part of their penalty (see the module Notes)."""
    if rows.mode != "robust":
        return np.zeros(r.size, bool)
    if rows.huber is not None:
        return np.abs(r) > rows.huber
    if rows.sigma is None:
        return np.zeros(r.size, bool)
    return np.abs(r) > rows.sigma


def normalized_residuals(sol, acceleration: bool = True) -> pd.DataFrame:
    r"""Every weighted residual row of a solution, normalized by its sigma.

    Parameters
    ----------
    sol : Solution
    acceleration : bool
        Also the acceleration residuals :math:`w/\sigma_a` (acceleration form), as item
        ``"acceleration w"``.

    Returns
    -------
    pandas.DataFrame
        Columns ``t`` (s; NaN for rows without a time, e.g. priors), ``item``, ``row``
        (the row's label), ``mode``, ``residual`` (item units), ``units``, ``sigma``
        (item units), ``normalized`` (residual / sigma, 1; for a band with soft edges the
        excess beyond the band over sigma, 0 inside it) and ``down_weighted`` (bool), sorted
        by ``|normalized|``, largest first. Hard rows and bands with hard edges have no sigma
        and are not listed.

    Examples
    --------
    A fix of 0.3 m (sigma 0.1 m) at a time the position is held at 0 m: its residual is
    -0.3 m, normalized -3:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> from bvpnav.report import normalized_residuals
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.zeros(21)), sigma_a=0.5)
    >>> prob = prob.add(Position(t=[0.0, 1.0], value=[0.0, 0.0], name="held"),
    ...                 Position(t=1.0, value=0.3, sigma=0.1, name="fix"))
    >>> row = normalized_residuals(prob.solve(solver="direct")).iloc[0]
    >>> row["item"], row["row"], float(row["t"]), round(float(row["normalized"]), 6)
    ('fix', 'x(t=1)', 1.0, -3.0)
    """
    parts = []
    for label, rows in sol.item_rows.items():
        r = np.asarray(sol.item_residuals.get(label, ()), float).ravel()
        if rows.sigma is None or r.size != rows.sigma.size or r.size == 0:
            continue
        idx = np.arange(r.size)
        parts.append(pd.DataFrame({
            "t": rows.t, "item": label, "row": [rows.label(i) for i in idx], "mode": rows.mode,
            "residual": r, "units": rows.units, "sigma": rows.sigma, "normalized": _normalized(rows, r),
            "down_weighted": _down_weighted(rows, r)}))
    if acceleration and sol.sigma_a is not None and len(sol.residuals):
        t = sol.residuals.index.to_numpy(float)
        for j, a in enumerate(sol._pos_cols):
            col = f"w_{a}"
            if col not in sol.residuals:
                continue
            w = sol.residuals[col].to_numpy(float)
            s = float(np.asarray(sol.sigma_a).ravel()[min(j, np.size(sol.sigma_a) - 1)])
            parts.append(pd.DataFrame({
                "t": t, "item": "acceleration w", "row": [f"w_{a}(t={v:.6g})" for v in t], "mode": "soft",
                "residual": w, "units": "m/s^2", "sigma": s, "normalized": w / s, "down_weighted": False}))
    cols = ["t", "item", "row", "mode", "residual", "units", "sigma", "normalized", "down_weighted"]
    if not parts:
        return pd.DataFrame(columns=cols)
    out = pd.concat(parts, ignore_index=True)[cols]
    order = np.argsort(-np.abs(out["normalized"].to_numpy(float)), kind="stable")
    return out.iloc[order].reset_index(drop=True)


def _normalized(rows, r: np.ndarray) -> np.ndarray:
    """Rows' residuals ``r`` over their sigma; a band with soft edges: the excess beyond the
    band over sigma (:meth:`bvpnav.terms.Term.excess`), 0 inside it."""
    from .terms import band_excess

    if rows.mode == "band" and rows.tol is not None:
        r = band_excess(r, rows.tol, rows.kind)
    return r / rows.sigma


# --------------------------------------------------------------------------- figures
def _fixes(sol, axes: list) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """Position fixes on the two map axes, recovered from the items' residuals
    (value = position at t - residual): (t, xy (K, 2), down-weighted (K,), beyond
    :data:`OUTLIER` sigma on some axis (K,)), or None."""
    from .model import TimeLabels

    ts, xy, bad, beyond = [], [], [], []
    classes = dict(zip(sol.items["item"], sol.items["class"], strict=False)) if len(sol.items) else {}
    for label, rows in sol.item_rows.items():
        labs = rows.labels
        if classes.get(label) != "Position" or not isinstance(labs, TimeLabels) or labs.quantity != "":
            continue
        if not all(a in labs.axes for a in axes):
            continue
        r = np.asarray(sol.item_residuals[label], float).reshape(labs.times.size, len(labs.axes))
        down = _down_weighted(rows, r.ravel()).reshape(r.shape).any(axis=1)
        if rows.sigma is not None:
            far = (np.abs(_normalized(rows, r.ravel())).reshape(r.shape) > OUTLIER).any(axis=1)
        else:
            far = np.zeros(len(r), bool)
        pts = []
        for a in axes:
            k = labs.axes.index(a)
            pts.append(np.interp(labs.times, sol.t, sol.position(a)) - r[:, k])
        ts.append(labs.times)
        xy.append(np.column_stack(pts))
        bad.append(down)
        beyond.append(far)
    if not ts:
        return None
    return np.concatenate(ts), np.vstack(xy), np.concatenate(bad), np.concatenate(beyond)


def _ellipse_cov(sol, axes: list) -> np.ndarray | None:
    """Horizontal position covariance (N, 2, 2), m^2: the full one when the solve kept it,
    else diagonal from the standard deviations; None without them."""
    state = getattr(sol, "_cov", {}).get("state")
    cols = sol._pos_cols
    if state is not None:
        i, j = cols.index(axes[0]), cols.index(axes[1])
        return state[:, [i, j]][:, :, [i, j]]
    names = [f"{a}_std" for a in axes]
    if all(c in sol.trajectory.columns for c in names):
        s = sol.trajectory[names].to_numpy(float)
        out = np.zeros((s.shape[0], 2, 2))
        out[:, 0, 0], out[:, 1, 1] = s[:, 0] ** 2, s[:, 1] ** 2
        return out
    return None


def map_view(sol, truth=None, ax=None):
    """The path on the first two axes (equal scales) with +/- 2 sigma ellipses, fixes and truth.

    Parameters
    ----------
    sol : Solution
        With 2 or 3 axes.
    truth : array_like, optional
        True positions (N, d), m, at the sample times.
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.patches import Ellipse

    from .plot import _axes, _legend

    axes = sol._pos_cols[:2]
    fig, ax = _axes(ax, figsize=(7, 6), layout="constrained")
    p = sol.position()[:, :2]
    if truth is not None:
        tr = np.asarray(truth, float).reshape(len(sol.t), -1)
        ax.plot(tr[:, 0], tr[:, 1], color="k", lw=2.5, alpha=0.35, label="truth", zorder=1)
    ax.plot(p[:, 0], p[:, 1], color="C0", lw=1.5, label="estimate", zorder=3)
    ax.plot(p[:1, 0], p[:1, 1], "o", color="C0", ms=6, label="start", zorder=4)
    cov = _ellipse_cov(sol, axes)
    if cov is not None:
        for n, k in enumerate(np.unique(np.linspace(0, len(p) - 1, ELLIPSES).round().astype(int))):
            vals, vecs = np.linalg.eigh(cov[k])
            vals = np.maximum(vals, 0.0)
            ang = np.degrees(np.arctan2(vecs[1, 1], vecs[0, 1]))
            ax.add_patch(Ellipse(p[k], 4 * np.sqrt(vals[1]), 4 * np.sqrt(vals[0]), angle=ang, fill=False,
                                 color="C0", lw=0.8, alpha=0.7, label="±2σ ellipse" if n == 0 else None))
    fx = _fixes(sol, axes)
    if fx is not None:
        _, xy, bad, far = fx
        ax.plot(xy[~bad, 0], xy[~bad, 1], "o", color="C3", ms=4, mfc="none", label="position fixes", zorder=2)
        if far.any():
            ax.plot(xy[far, 0], xy[far, 1], "s", color="C1", ms=11, mfc="none", mew=2,
                    label=f"fixes beyond {OUTLIER:g}σ", zorder=5)
        if bad.any():
            ax.plot(xy[bad, 0], xy[bad, 1], "x", color="C3", ms=9, mew=2, label="down-weighted fixes",
                    zorder=5)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{axes[0]} (m)")
    ax.set_ylabel(f"{axes[1]} (m)")
    ax.set_title(f"map view {axes[0]}-{axes[1]}", fontsize=10)
    _legend(ax, fontsize=8)
    return fig


def residual_figure(sol, table: pd.DataFrame | None = None):
    """Normalized residuals over time: one panel per item kind of row (items with a time,
    the acceleration residuals), down-weighted rows marked; ``|.| = 3`` dashed.

    Returns
    -------
    matplotlib.figure.Figure or None
        None when no row has a sigma and a time.
    """
    import matplotlib.pyplot as plt

    table = normalized_residuals(sol) if table is None else table
    timed = table[np.isfinite(table["t"].to_numpy(float))].sort_values("t", kind="stable")
    if timed.empty:
        return None
    groups = [g for g in dict.fromkeys(timed["item"]) if g != "acceleration w"]
    accel = "acceleration w" in set(timed["item"])
    panels = (["items"] if groups else []) + (["acceleration w"] if accel else [])
    fig, axs = plt.subplots(len(panels), 1, figsize=(9, 2.6 * len(panels) + 0.5), sharex=True,
                            layout="constrained", squeeze=False)
    for ax, what in zip(axs[:, 0], panels, strict=True):
        if what == "items":
            for k, g in enumerate(groups):
                sub = timed[timed["item"] == g]
                ax.plot(sub["t"], sub["normalized"], ".", ms=3, color=f"C{k % 10}", label=g)
                bad = sub[sub["down_weighted"].astype(bool)]
                if len(bad):
                    ax.plot(bad["t"], bad["normalized"], "x", color="C3", ms=8, mew=2, label="down-weighted")
            ax.set_title("items: residual / sigma", fontsize=10)
        else:
            sub = timed[timed["item"] == what]
            for k, a in enumerate(sol._pos_cols):
                one = sub[sub["row"].str.startswith(f"w_{a}(")]
                ax.plot(one["t"], one["normalized"], lw=0.6, color=f"C{k}", label=f"w_{a}")
            sa = "stated" if sol.sigma_a_given else "default, not stated"
            ax.set_title(f"acceleration residuals w / sigma_a ({sa})", fontsize=10)
        for s in (3, -3):
            ax.axhline(s, color="0.3", ls="--", lw=0.8)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_ylabel("normalized residual (1)")
        from .plot import _legend

        _legend(ax, fontsize=7, loc="upper right")
    axs[-1, 0].set_xlabel("t (s)")
    return fig


def _unit_groups(sol) -> dict:
    ep = sol.error_params
    units = ep.attrs.get("units", {})
    groups: dict[str, list] = {}
    for name in ep.index:
        groups.setdefault(units.get(name, "") or "1", []).append(name)
    return groups


def sensor_error_figure(sol):
    """The error-model estimates over time, one panel per unit, with +/- 2 sigma.

    Knots of time-varying models (``name[k]``) are drawn at their times, joined (the
    models are linear between knots); constant parameters as lines over the window.

    Returns
    -------
    matplotlib.figure.Figure or None
        None without an error model.
    """
    import matplotlib.pyplot as plt

    ep = sol.error_params
    if not len(ep):
        return None
    std = sol.error_params_std
    times = ep.attrs.get("t", {})
    groups = _unit_groups(sol)
    t0, t1 = float(sol.t[0]), float(sol.t[-1])
    fig, axs = plt.subplots(len(groups), 1, figsize=(9, 2.5 * len(groups) + 0.5), sharex=True,
                            layout="constrained", squeeze=False)
    for ax, (unit, names) in zip(axs[:, 0], groups.items(), strict=True):
        series: dict[str, list] = {}
        for n in names:
            series.setdefault(n.split("[")[0] if n in times else n, []).append(n)
        for k, (base, members) in enumerate(series.items()):
            col = f"C{k % 10}"
            if members[0] in times:
                tt = np.array([times[m] for m in members])
            else:
                tt = np.array([t0, t1])
                members = members * 2
            v = ep[members].to_numpy(float)
            ax.plot(tt, v, "o-" if members[0] in times else "-", color=col, ms=3, lw=1.2, label=base)
            if len(std) and all(m in std.index for m in members):
                s = std[members].to_numpy(float)
                ax.fill_between(tt, v - 2 * s, v + 2 * s, color=col, alpha=0.15, lw=0)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_ylabel(f"estimate ({unit})")
        from .plot import _legend

        _legend(ax, fontsize=7, loc="upper right", ncol=3)
    axs[0, 0].set_title("sensor errors" + (" (±2σ shaded)" if len(std) else ""), fontsize=10)
    axs[-1, 0].set_xlabel("t (s)")
    return fig


def attitude_figure(sol):
    """The attitude correction (rotation vector of ``C C0^T``, degrees) over time, or None
    (navigation-frame data, or no correction)."""
    import matplotlib.pyplot as plt

    corr = sol.attitude_corrections
    if corr is None or not np.any(corr["angle"].to_numpy(float) > 0):
        return None
    fig, ax = plt.subplots(figsize=(9, 3), layout="constrained")
    t = corr.index.to_numpy(float)
    for k, a in enumerate(("x", "y", "z")):
        ax.plot(t, np.degrees(corr[a].to_numpy(float)), color=f"C{k}", lw=1.2, label=f"about {a}")
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("correction (deg)")
    ax.set_title("attitude correction: rotation vector of C C0^T (navigation frame)", fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    return fig


def loop_figure(sol):
    """The outer loop's progress: the attitude loop's objective per step or the sequential
    loop's largest position change per iteration (log scale), or None."""
    import matplotlib.pyplot as plt

    seq = sol.stats.get("sequential")
    if not seq:
        return None
    fig, ax = plt.subplots(figsize=(6, 3), layout="constrained")
    if seq.get("kind") == "attitude":
        it = seq.get("iterations") or []
        obj = [seq.get("objective_initial")] + [d.get("trial", d.get("objective")) for d in it]
        vals = np.array([np.nan if v is None else float(v) for v in obj])
        ax.semilogy(np.arange(vals.size), np.maximum(vals, np.finfo(float).tiny), "o-", color="C0")
        ax.set_ylabel("objective (1)")
        ax.set_title(f"attitude loop: {len(it)} step(s), {seq.get('reason')}", fontsize=10)
    else:
        ch = np.asarray(seq.get("max_change") or [], float)
        ax.semilogy(np.arange(1, ch.size + 1), np.maximum(ch, np.finfo(float).tiny), "o-", color="C0")
        ax.axhline(float(seq.get("tol", np.nan)), color="C3", ls="--", lw=1, label="tol")
        ax.set_ylabel("largest position change (m)")
        ax.set_title(f"sequential loop: {seq.get('iterations')} iteration(s)", fontsize=10)
        ax.legend(fontsize=7)
    ax.set_xlabel("iteration (1)")
    return fig


def figures(sol, items=None, truth=None) -> dict[str, Any]:
    """The report's figures by name (each a matplotlib Figure), in the report's order.

    Parameters
    ----------
    sol : Solution
    items : sequence of Item, optional
        The problem's items, drawn on the position and velocity panels where they act.
    truth : array_like, optional
        True positions (N, d), m, at the sample times.

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        ``"map"`` (2-3 axes), ``"solution"`` (position and velocity per axis with bands),
        ``"residuals"``, ``"sensor_errors"``, ``"attitude"`` (attitude corrected), ``"lcurve"``
        (lambda chosen by a rule), ``"loop"`` (an outer loop ran): those that apply.
    """
    from . import plot

    tr = plot._truth_array(truth, sol)
    out: dict[str, Any] = {}
    if len(sol._pos_cols) >= 2:
        out["map"] = map_view(sol, truth=tr)
    out["solution"] = plot.solution(sol, items=items, truth=tr)
    for name, make in (("residuals", residual_figure), ("sensor_errors", sensor_error_figure),
                       ("attitude", attitude_figure)):
        fig = make(sol)
        if fig is not None:
            out[name] = fig
    if sol.curve is not None:
        out["lcurve"] = plot.lcurve(sol.curve)
    fig = loop_figure(sol)
    if fig is not None:
        out["loop"] = fig
    return out


# --------------------------------------------------------------------------- HTML
_CSS = """
body { font-family: sans-serif; max-width: 1100px; margin: 1em auto; color: #222; }
h1 { font-size: 1.5em; } h2 { border-bottom: 1px solid #ccc; margin-top: 1.6em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 2px 8px; text-align: right; }
th { background: #f0f0f0; } td.l, th.l { text-align: left; }
img { max-width: 100%; display: block; margin: 0.5em 0; }
.warn { background: #fff4e0; border-left: 4px solid #e69500; padding: 4px 8px; margin: 4px 0; }
.ok { color: #176117; } .bad { color: #a40000; font-weight: bold; }
"""


def _png(fig) -> str:
    import matplotlib.pyplot as plt

    buf = _io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _img(name: str, fig, caption: str) -> str:
    return (f'<figure id="fig-{name}"><img alt="{html.escape(caption)}" src="data:image/png;base64,'
            f'{_png(fig)}"><figcaption>{html.escape(caption)}</figcaption></figure>')


def _fmt(v) -> str:
    if v is None:
        return "—"
    if isinstance(v, bool | np.bool_):
        return "yes" if v else "no"
    if isinstance(v, int | np.integer):
        return str(int(v))
    if isinstance(v, float | np.floating):
        return "—" if not np.isfinite(v) else f"{float(v):.4g}"
    return str(v)


def _table(df: pd.DataFrame, cls: str, left=()) -> str:
    head = "".join(f'<th class="{"l" if c in left else ""}">{html.escape(str(c))}</th>' for c in df.columns)
    body = []
    for row in df.itertuples(index=False):
        cells = "".join(f'<td class="{"l" if c in left else ""}">{html.escape(_fmt(v))}</td>'
                        for c, v in zip(df.columns, row, strict=True))
        body.append(f"<tr>{cells}</tr>")
    return f'<table class="{cls}"><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table>'


def _kv(pairs: list, cls: str) -> str:
    return _table(pd.DataFrame(pairs, columns=["what", "value"]), cls, left=("what", "value"))


def _summary(sol) -> str:
    s, t = sol.stats, sol.t
    ver = s.get("verification") or {}
    verified = s.get("verified")
    pairs = [("samples", len(t)), ("window (s)", f"{t[0]:g} .. {t[-1]:g}" if len(t) else "—"),
             ("axes", ", ".join(sol._pos_cols)), ("lambda", f"{sol.lam:.6g} ({sol.lam_rule})"),
             ("solver", s.get("solver")), ("status", s.get("status")), ("accuracy", s.get("accuracy")),
             ("verified", verified)]
    for k, unit in (("fem_residual", "relative"), ("max_violation", "relative"), ("worst_item", ""),
                    ("stationarity", "relative"), ("forward_error", "relative"), ("rtol", "tolerance")):
        if k in ver:
            pairs.append((f"{k.replace('_', ' ')}" + (f" ({unit})" if unit else ""), ver[k]))
    if sol.sigma_a is not None:
        pairs.append(("sigma_a (m/s^2)", ", ".join(f"{v:.4g}" for v in np.ravel(sol.sigma_a))
                      + ("" if sol.sigma_a_given else " (default, not stated)")))
    unc = s.get("uncertainty")
    if unc:
        vf = _fmt(unc.get("variance_factor"))
        pairs.append(("uncertainty", f"{unc.get('scale')}; variance factor {vf} on {unc.get('dof')} degrees "
                                     f"of freedom ({unc.get('model')})"))
    cls = "ok" if verified else "bad"
    head = (f'{"Verified" if verified else "NOT verified"}: {s.get("solver")} ({s.get("status")}); '
            f"{len(sol.warnings)} warning(s).")
    return f'<p class="{cls}">{html.escape(head)}</p>' + _kv(pairs, "summary")


def _with_units(values, units) -> list[str]:
    return [f"{v:.4g} {u}" for v, u in zip(values, units, strict=True)]


def _worst(sol, table: pd.DataFrame) -> str:
    if table.empty:
        return ('<p>No residual has a sigma (every item is hard or a band, and the load form has no '
                'sigma_a): nothing to normalize. The items\' residuals are in the table below.</p>')
    top = table.head(WORST_ROWS)
    df = pd.DataFrame({"rank": np.arange(1, len(top) + 1), "t (s)": top["t"].to_numpy(float),
                       "item": top["item"], "row": top["row"], "mode": top["mode"],
                       "residual": _with_units(top["residual"], top["units"]),
                       "sigma": _with_units(top["sigma"], top["units"]),
                       "normalized": top["normalized"].to_numpy(float),
                       "down-weighted": top["down_weighted"].astype(bool).to_numpy()})
    n3 = int((np.abs(table["normalized"].to_numpy(float)) > 3).sum())
    return (f"<p>{len(table)} weighted residual rows; {n3} beyond 3 sigma; the {len(top)} largest "
            f"|residual / sigma|:</p>" + _table(df, "worst", left=("item", "row", "mode")))


def _error_table(sol) -> str:
    ep = sol.error_params
    if not len(ep):
        return "<p>No error model.</p>"
    units = ep.attrs.get("units", {})
    times = ep.attrs.get("t", {})
    std = sol.error_params_std
    df = pd.DataFrame({"parameter": list(ep.index), "t (s)": [times.get(n) for n in ep.index],
                       "estimate": ep.to_numpy(float),
                       "std": [float(std[n]) if n in std.index else None for n in ep.index],
                       "units": [units.get(n, "") for n in ep.index]})
    return _table(df, "error-params", left=("parameter", "units"))


def _rejected(sol) -> str:
    """The fixes gating rejected (:attr:`Solution.rejected`), one row each, or ''."""
    rej = getattr(sol, "rejected", None)
    if rej is None:
        return ""
    g = sol.stats.get("gating") or {}
    if not len(rej):
        return (f"<h3>Rejected fixes</h3><p>Gating kept every one of the {g.get('judged', '?')} fixes "
                "judged.</p>")
    head = (f"<p>Gating rejected {len(rej)} of {g.get('judged', '?')} fixes (normalized residual above the "
            f"gate; {g.get('passes', '?')} solves{'' if g.get('settled', True) else ', NOT settled'}); "
            "they are left out of the answer:</p>")
    return "<h3>Rejected fixes</h3>" + head + _table(rej.rename(columns={"t": "t (s)"}), "rejected",
                                                     left=("item", "units"))


def _record(sol) -> str:
    s = sol.stats
    out = []
    if sol.curve is not None:
        c = sol.curve
        chosen = ", ".join(f"{k}: {v:.4g}" for k, v in c.chosen.items())
        out.append(f"<p>lambda chosen by <b>{html.escape(str(c.rule))}</b> from a sweep of {len(c.lam)} "
                   f"points ({html.escape(chosen)}).</p>")
    seq = s.get("sequential")
    if seq:
        if seq.get("kind") == "attitude":
            it = seq.get("iterations") or []
            df = pd.DataFrame([{"step": k + 1, "objective": d.get("objective"), "trial": d.get("trial"),
                                "step (rad)": d.get("step"), "accepted": d.get("accepted"),
                                "damping": d.get("damping")} for k, d in enumerate(it)])
            out.append(f"<p>Attitude loop: {len(it)} step(s), converged {_fmt(seq.get('converged'))} "
                       f"({html.escape(str(seq.get('reason')))}), {seq.get('solves')} solves.</p>")
        else:
            n = int(seq.get("iterations") or 0)
            df = pd.DataFrame({"iteration": np.arange(1, n + 1), "mode": (seq.get("mode") or [None] * n)[:n],
                               "max change (m)": (seq.get("max_change") or [None] * n)[:n],
                               "rms change (m)": (seq.get("rms_change") or [None] * n)[:n]})
            out.append(f"<p>Sequential loop: {n} iteration(s), converged {_fmt(seq.get('converged'))}.</p>")
        if len(df):
            out.append(_table(df, "loop", left=("mode",)))
    att = s.get("attempts") or []
    if att:
        df = pd.DataFrame([{"solver": a.get("solver"), "status": a.get("status"), "reason": a.get("reason")}
                           for a in att])
        out.append("<h3>Attempts</h3>" + _table(df, "attempts", left=("solver", "status", "reason")))
    dem = s.get("demoted")
    if dem:
        df = pd.DataFrame([{"item": d.get("item"), "sigma": d.get("sigma"),
                            "conflict": ", ".join(d.get("conflict") or [])} for d in dem])
        out.append("<h3>Hard items made soft (conflicts)</h3>"
                   + _table(df, "demoted", left=("item", "conflict")))
    out.append("<h3>Warnings</h3>")
    if sol.warnings:
        out += [f'<div class="warn">{html.escape(str(w))}</div>' for w in sol.warnings]
    else:
        out.append("<p>None.</p>")
    return "\n".join(out)


_CAPTIONS = {
    "map": "Map view (equal scales): the estimate, ±2σ ellipses of the horizontal position where the "
           "solution has standard deviations, position fixes (squares: beyond 3σ; x: down-weighted) and the "
           "truth when given.",
    "solution": "Position and velocity per axis (±2σ bands where known), the items where they act, the "
                "acceleration residuals.",
    "residuals": "Normalized residuals (residual / sigma) over time; dashed: ±3.",
    "sensor_errors": "Estimated sensor errors over time (knots of time-varying models at their times).",
    "attitude": "Correction applied to the data's attitude.",
    "lcurve": "The lambda sweep and each rule's choice.",
    "loop": "The outer loop's progress.",
}


def render_html(sol, items=None, truth=None, title: str | None = None) -> str:
    """The report as one HTML document (str); see the module docstring for its sections."""
    import matplotlib

    title = title or "bvpnav quality report"
    table = normalized_residuals(sol)
    with matplotlib.rc_context({"figure.max_open_warning": 0}):
        figs = figures(sol, items=items, truth=truth)
        imgs = {k: _img(k, f, _CAPTIONS.get(k, k)) for k, f in figs.items()}
    sec = [f"<h1>{html.escape(title)}</h1>", "<h2 id='summary'>Summary</h2>", _summary(sol),
           "<h2 id='trajectory'>Trajectory</h2>", imgs.get("map", ""), imgs["solution"],
           "<h2 id='residuals'>Residuals</h2>", imgs.get("residuals", ""),
           "<h3>Worst normalized residuals</h3>", _worst(sol, table), _rejected(sol),
           "<h3>Items</h3>", _table(sol.items.drop(columns=["dual_rms"], errors="ignore"), "items",
                                    left=("item", "class", "mode", "kind", "units")),
           "<h2 id='sensor-errors'>Sensor errors</h2>", imgs.get("sensor_errors", ""), _error_table(sol)]
    corr = sol.attitude_corrections
    if corr is not None:
        sec += ["<h2 id='attitude'>Attitude corrections</h2>", imgs.get("attitude", ""),
                f"<p>Largest correction {np.degrees(corr['angle'].max()):.4g} deg"
                + ("" if "attitude" in imgs else ": the data's attitude is used as it is (no attitude error "
                   "model)") + ".</p>"]
    sec += ["<h2 id='record'>Solve record</h2>", imgs.get("lcurve", ""), imgs.get("loop", ""), _record(sol)]
    body = "\n".join(x for x in sec if x)
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}'
            f"</title><style>{_CSS}</style></head><body>\n{body}\n</body></html>\n")


def write_report(sol, path: str | os.PathLike, items=None, truth=None, title: str | None = None) -> None:
    """Write the HTML quality report of ``sol`` to ``path``, atomically.

    Parameters
    ----------
    sol : Solution
    path : str or os.PathLike
        Ends in ``.html`` or ``.htm``.
    items : sequence of Item, optional
        The problem's items (``problem.items``), drawn where they act.
    truth : array_like or DataFrame, optional
        True positions, m, at the sample times (shape (N, d), or a table with a column per axis).
    title : str, optional

    Raises
    ------
    InputError
        For another suffix, or when the file cannot be written.
    """
    from .errors import InputError
    from .io import atomic_write_text

    if os.path.splitext(str(path))[1].lower() not in (".html", ".htm"):
        raise InputError(f"report {str(path)!r}: the report is HTML; end its name with .html")
    atomic_write_text(path, render_html(sol, items=items, truth=truth, title=title))
