"""Figures: the L-curve with every rule's choice, trajectories and errors, solver comparisons.

Every function takes an optional matplotlib ``Axes`` and returns the ``Figure``; nothing
is shown or saved (use :func:`bvpnav.io.atomic_savefig` to write a file atomically).
"""

from __future__ import annotations

import numpy as np

__all__ = ["lcurve", "trajectory", "errors", "comparison"]

_MARKERS = {"lcurve": ("o", "C3"), "gcv": ("s", "C0"), "discrepancy": ("^", "C2"), "quasi": ("D", "C1")}


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
    Each rule's choice is marked at its (refined) lambda, interpolated on the sampled
    curve in log-log coordinates.
    """
    fig, ax = _axes(ax, figsize=(6, 5))
    ax.loglog(curve.residual_norm, curve.info_norm, ".-", color="0.4", lw=1, label="sweep")
    s = np.log(curve.lam)
    for rule, lam in curve.chosen.items():
        m, c = _MARKERS.get(rule, ("x", "k"))
        u = np.log(lam)
        x = np.exp(np.interp(u, s, np.log(curve.residual_norm)))
        y = np.exp(np.interp(u, s, np.log(curve.info_norm)))
        ax.loglog([x], [y], m, color=c, ms=9, mfc="none", mew=2,
                  label=f"{rule}: lambda = {lam:.3g}" + (" (used)" if rule == curve.rule else ""))
    ax.set_xlabel("residual norm  rho(lambda)")
    ax.set_ylabel("information norm  eta(lambda)")
    ax.set_title("L-curve")
    if annotate:
        ax.legend(fontsize=8)
    return fig


def trajectory(solutions: dict, truth=None, axis: str | None = None, ax=None):
    """Position against time for several solutions (``{label: Solution}``), with the truth (m)."""
    fig, ax = _axes(ax, figsize=(8, 4))
    t = None
    for label, sol in solutions.items():
        t = sol.t
        ax.plot(t, sol.position(axis), label=label)
    if truth is not None and t is not None:
        ax.plot(t, np.asarray(truth), "k", lw=2, alpha=0.6, label="truth")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("position (m)")
    ax.legend(fontsize=8)
    return fig


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


def comparison(table, ax=None):
    """Solve time (s, log scale) against accuracy for a :func:`bvpnav.compare_solvers` table.

    Failed or unverified runs are drawn hollow, so they are visible, not hidden.
    """
    fig, ax = _axes(ax, figsize=(7, 5))
    ycol = "rms_error" if "rms_error" in table and table["rms_error"].notna().any() else "fem_residual"
    for k, row in enumerate(table.itertuples(index=False)):
        d = row._asdict()
        x, y = d.get("solve_time"), d.get(ycol)
        if x is None or y is None or not np.isfinite(x) or not np.isfinite(y):
            continue
        ok = d.get("verified", False)
        ax.loglog([max(x, 1e-6)], [max(y, 1e-16)], "o", color=f"C{k % 10}",
                  mfc=None if ok else "none", ms=8, label=f"{d['solver']}/{d['preset']} ({d['status']})")
    ax.set_xlabel("solve time (s)")
    ax.set_ylabel(ycol.replace("_", " "))
    ax.legend(fontsize=7)
    return fig
