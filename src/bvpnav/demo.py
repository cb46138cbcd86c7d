"""The bundled demonstration: one recording, four ways of navigating it.

``bvpnav demo`` runs the 2011 paper's quintic scenario with a biased, scaled, noisy
accelerometer (seeded) and compares

1. time-stepping: trapezoid double integration from the known initial state (the
   classical initial-value view);
2. FEM with both end positions fixed (the 2010 paper's boundary value problem);
3. FEM with all four boundary values as Tikhonov information: the 2011 paper's
   method I (load-residual form, positions at both ends hard, the cubic prior through
   the four boundary values on the first and last 10 samples, lambda by L-curve);
4. bvpnav's default: the acceleration-residual form with the four boundary values as
   hard items.

It prints a table of RMS position errors and writes a PNG figure.
"""

from __future__ import annotations

import numpy as np

from .baselines import trapezoid
from .constraints import Position, Velocity
from .io import atomic_savefig, check_figure_path, check_outputs
from .problem import NavigationProblem
from .samples import check_seed
from .scenarios import tikhonov2011

__all__ = ["run_demo"]


def run_demo(png: str | None = "bvpnav-demo.png", seed: int = 0, quiet: bool = False,
             lam: float | str = "lcurve") -> dict:
    """Run the demonstration.

    Parameters
    ----------
    png : str or None
        Where to write the figure (None: no figure); its suffix (a format matplotlib
        writes) and folder are checked before any work, and it is written atomically.
    seed : int
        Noise seed (>= 0).
    quiet : bool
        Print nothing.
    lam : float or str
        Lambda for method 3 (default: chosen by the L-curve).

    Raises
    ------
    InputError
        If ``seed`` is not an integer >= 0, or ``png`` has a suffix matplotlib does not
        write, or cannot be written.

    Returns
    -------
    dict
        RMS position errors (m) by method, the lambda used, and the figure path.
    """
    seed = check_seed(seed)
    if png:  # the output policy, before the work
        check_figure_path(png, "png")
        check_outputs({}, {"png": png})
    sc = tikhonov2011(seed=seed)
    t, acc = sc.t, sc.data.acc[:, 0]
    b = sc.boundary
    truth = sc.position
    rms = {}
    _, pos_ivp = trapezoid(t, acc, v0=b["v0"], r0=b["r0"])
    rms["I   time-stepping (trapezoid)"] = float(np.sqrt(np.mean((pos_ivp - truth) ** 2)))

    ends = Position(t=[b["t0"], b["t1"]], value=[b["r0"], b["r1"]], name="ends")
    fem = NavigationProblem(sc.data, residual="load").add(ends).solve()
    rms["II  FEM, both ends fixed"] = fem.rms_error(truth)

    prior_t = np.concatenate([t[:10], t[-10:]])
    tik = NavigationProblem(sc.data, residual="load").add(
        ends, Position(t=prior_t, value=sc.prior(prior_t), sigma=1.0, name="prior"))
    # the load form is ill-conditioned: the direct back end is its accurate path
    sol3 = tik.solve(lam=lam, solver="direct")
    rms["III FEM + Tikhonov (2011 paper, L-curve)"] = sol3.rms_error(truth)

    full = NavigationProblem(sc.data).add(
        ends, Velocity(t=[b["t0"], b["t1"]], value=[b["v0"], b["v1"]], name="end velocities"))
    sol4 = full.solve()
    rms["IV  FEM, four boundary values (bvpnav default)"] = sol4.rms_error(truth)

    if not quiet:
        p = sc.params
        print(f"bvpnav demo: the 2011 paper's quintic, N = {t.size} samples at {p['rate']:g} Hz, "
              f"scale {p['scale']:+g}, bias {p['bias']:+g} m/s^2, noise {p['noise']:g} m/s^2, "
              f"seed {seed}")
        print(f"{'method':<48} {'RMS position error (m)':>24}")
        for k, v in rms.items():
            print(f"{k:<48} {v:>24.3f}")
        print(f"lambda for III: {sol3.lam:.4g} ({sol3.lam_rule})")
    out = {"rms": rms, "lam": sol3.lam, "png": None}
    if png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
        ax1.plot(t, truth, "k", lw=2.5, label="truth")
        ax1.plot(t, pos_ivp, color="C0", label="I trapezoid")
        ax1.plot(t, fem.position("x"), color="C1", label="II FEM, ends fixed")
        ax1.plot(t, sol3.position("x"), color="C2", label="III FEM + Tikhonov")
        ax1.plot(t, sol4.position("x"), "--", color="C3", label="IV four boundary values")
        ax1.set_ylabel("position x (m)")
        ax1.set_ylim(truth.min() - 8, truth.max() + 8)
        ax1.legend(fontsize=8)
        for lab, pos, col in (("II", fem.position("x"), "C1"), ("III", sol3.position("x"), "C2"),
                              ("IV", sol4.position("x"), "C3")):
            ax2.plot(t, pos - truth, color=col, label=lab)
        ax2.set_ylabel("position error (m)")
        ax2.set_xlabel("t (s)")
        ax2.legend(fontsize=8)
        fig.tight_layout()
        atomic_savefig(fig, png)
        plt.close(fig)
        out["png"] = str(png)
        if not quiet:
            print(f"figure written to {png}")
    return out
