"""The L-curve rule: the corner of maximum curvature of (log rho, log eta)."""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import CubicSpline

from . import (
    WIDEN,
    LambdaRule,
    bracket,
    edge_warning,
    half_way_points,
    refine_with_slopes,
    register_rule,
)

__all__ = ["LCurve", "curvature", "curvature_slope", "spline_curvature"]


def curvature(pt: dict) -> float:
    r"""Signed curvature of :math:`(\log\rho, \log\eta)` at one lambda from exact derivatives.

    Notes
    -----
    With :math:`\hat\rho = \rho^2`, :math:`\hat\eta = \eta^2`, the stationarity of
    :math:`J = \hat\rho + \lambda\hat\eta` along the solution path gives
    :math:`\hat\rho' = -\lambda\hat\eta'`, and the second derivatives cancel from the
    curvature :math:`(\zeta'\eta'' - \zeta''\eta')/(\zeta'^2 + \eta'^2)^{3/2}` of
    :math:`(\zeta, \eta) = (\tfrac12\log\hat\rho, \tfrac12\log\hat\eta)`:

    .. math:: \kappa = \frac{2}{\hat\rho\hat\eta\,|\hat\eta'|}
        \frac{1 + \lambda\hat\eta'/\hat\eta + \lambda^2\hat\eta'/\hat\rho}
             {(\lambda^2/\hat\rho^2 + 1/\hat\eta^2)^{3/2}}.

    Positive where the curve, traversed with increasing lambda, turns counter-clockwise
    (the 2011 paper's sign convention, its equation 17).
    """
    lam, r, e, de = pt["lam"], pt["rho2"], pt["eta2"], pt["deta2"]
    if de == 0 or r <= 0 or e <= 0:
        return 0.0
    return float(_kappa(lam, r, e, de))


def _kappa(lam, r, e, de):
    """:func:`curvature`'s formula, for real or complex arguments (``|de|`` taken by the
    sign of its real part, so that a complex step passes through it)."""
    mag = de if de.real > 0 else -de
    return (2.0 / (r * e * mag) * (1.0 + lam * de / e + lam**2 * de / r)
            / (lam**2 / r**2 + 1.0 / e**2) ** 1.5)


def curvature_slope(pt: dict) -> float:
    r""":math:`d\kappa / d\log\lambda` of :func:`curvature`, exact (needs ``d2eta2``).

    Notes
    -----
    Along the solution path :math:`\hat\rho' = -\lambda\hat\eta'` and
    :math:`\hat\rho'' = -\hat\eta' - \lambda\hat\eta''`, and the second derivative of the
    lambda-weighted terms is :math:`\hat\eta'' = 6\,\lVert S A x'\rVert^2` (the point's
    ``d2eta2``: the minimiser's sensitivity is symmetric, so no second solve is needed, see
    :meth:`bvpnav.lam.sweep.DirectSweep.point`). :math:`\kappa` is a closed form in
    :math:`(\lambda, \hat\rho, \hat\eta, \hat\eta')`; its total derivative is taken by a
    complex step, every argument moved by :math:`ih` times its own derivative,

    .. math:: \frac{d\kappa}{d\log\lambda} = \frac{\lambda}{h}\,
        \operatorname{Im}\kappa(\lambda + ih,\ \hat\rho - ih\lambda\hat\eta',\
        \hat\eta + ih\hat\eta',\ \hat\eta' + ih\hat\eta''),

    exact to rounding for :math:`h = 10^{-20}\lambda` (no difference is formed).
    """
    lam, r, e, de, dde = pt["lam"], pt["rho2"], pt["eta2"], pt["deta2"], pt["d2eta2"]
    if de == 0 or r <= 0 or e <= 0:
        return 0.0
    h = 1e-20 * lam
    k = _kappa(complex(lam, h), complex(r, -h * lam * de), complex(e, h * de), complex(de, h * dde))
    return float(lam * k.imag / h)


def spline_curvature(s: np.ndarray, rho2, eta2, s_eval: np.ndarray) -> np.ndarray:
    """Curvature of (log rho, log eta) from cubic splines in s = log lambda."""
    zeta = CubicSpline(s, 0.5 * np.log(rho2))
    eta = CubicSpline(s, 0.5 * np.log(eta2))
    z1, z2 = zeta(s_eval, 1), zeta(s_eval, 2)
    e1, e2 = eta(s_eval, 1), eta(s_eval, 2)
    # sign: positive at the corner of an L traversed with rho increasing
    return (z1 * e2 - z2 * e1) / np.maximum((z1**2 + e1**2) ** 1.5, 1e-300)


class LCurve(LambdaRule):
    r"""Maximise the curvature of :math:`(\log\rho, \log\eta)`.

    Notes
    -----
    With the direct sweep the curvature (:func:`curvature`) and its slope
    (:func:`curvature_slope`) are exact at every point, the range's ends included: every
    sample may be chosen, the sweep samples every two decades by default and the corner is
    refined from values and slopes (:func:`bvpnav.lam.refine_with_slopes`) anywhere in the
    range. The best value is at an edge (a warning naming that end of the range) only when
    it is an end sample and the exact slope there still rises out of the range. With the
    cvxpy sweep the curvature is a spline through the samples (:func:`spline_curvature`),
    refined by sampling more densely; the spline's end effects keep its two outermost
    samples on each side from being chosen (a best value beside them warns).
    """

    name = "lcurve"
    slopes = True
    coarse = True
    reads_quasi = False

    def scores(self, sweep, pts, s):
        if sweep.engine == "direct":
            return np.array([curvature(p) for p in pts])
        return spline_curvature(s, [p["rho2"] for p in pts], [p["eta2"] for p in pts], s)

    def refine(self, sweep, pts, s, scores, curve):
        if sweep.engine == "direct":
            return self._refine_exact(sweep, pts, s, scores, curve)
        # a spline through the cvxpy sweep's samples keeps two away from its ends (end effects)
        g = 2
        inner = np.arange(g, len(s) - g)
        k = int(inner[np.argmax(scores[inner])])
        edge_warning(curve, self.name, k, g, scores, best="max")
        if scores[k] <= 0:
            _no_corner(curve)
        a, b = bracket(s, k)
        fine = np.linspace(a, b, 9)[1:-1]
        for u in fine[np.abs(fine - s[k]) > 1e-6]:
            sweep.point(math.exp(u))
        keys = np.array(sorted(sweep.cache))
        keys = keys[np.concatenate([[True], np.diff(np.log(keys)) > 1e-9])]
        dense = np.linspace(a, b, 401)
        kd = spline_curvature(np.log(keys), [sweep.cache[q]["rho2"] for q in keys],
                              [sweep.cache[q]["eta2"] for q in keys], dense)
        return float(math.exp(dense[np.argmax(kd)]))

    def _refine_exact(self, sweep, pts, s, scores, curve) -> float:
        """The direct sweep's choice: the curvature and its slope are exact at every point,
        so every sample may be chosen, the ends included; the corner is refined from values
        and slopes inside the whole range, and an end is an edge only when the curvature
        still rises out of the range there."""
        seen = [float(v) for v in scores]   # every curvature this rule evaluated

        def f(u):
            pt = sweep.point(math.exp(u))
            seen.append(curvature(pt))
            return seen[-1], curvature_slope(pt)

        n = len(s)
        k = int(np.argmax(scores))
        lo, hi = s[0], s[-1]
        u, sc = list(s[max(k - 1, 0):k + 2]), list(scores[max(k - 1, 0):k + 2])
        sl = [curvature_slope(p) for p in pts[max(k - 1, 0):k + 2]]
        # samples more than a decade apart: the half-way points beside the best one, so
        # that a corner between samples is not missed
        for mid in half_way_points(s, k, lo, hi):
            val, slope = f(mid)
            j = int(np.searchsorted(u, mid))
            u.insert(j, mid), sc.insert(j, val), sl.insert(j, slope)
        u, sc, sl = np.array(u), np.array(sc), np.array(sl)
        j = int(np.argmax(sc))
        if sc[j] <= 0:
            _no_corner(curve)
        # an end sample is an edge when the exact slope there points out of the range (the
        # curvature still rises beyond it); else the corner lies inside and is refined
        if (u[j] == lo and sl[j] < 0) or (u[j] == hi and sl[j] > 0):
            edge_warning(curve, self.name, 0 if u[j] == lo else n - 1, 0)
            return float(curve.lam[0] if u[j] == lo else curve.lam[-1])
        best = refine_with_slopes(f, u, sc, sl, j, best="max", bounds=(lo, hi))
        if best <= lo or best >= hi:   # the refinement found the curvature rising out of the range
            edge_warning(curve, self.name, 0 if best <= lo else n - 1, 0)
        _faint_corner(curve, pts, seen, math.exp(best))
        return float(math.exp(best))


def _faint_corner(curve, pts: list, kappas: list, lam: float) -> None:
    r"""Warn when the convex corner chosen is too faint to be seen on the plotted curve.

    Notes
    -----
    A corner of curvature :math:`\kappa` turns on a radius :math:`1/\kappa` in the
    plot's units (natural logarithms on both axes); when that radius exceeds the extent of
    the curve (the diagonal of the box its samples span in :math:`(\log\rho, \log\eta)`),
    the curve is straight there on any plot of it, and the criterion's answer rests on
    nothing the curve shows. Read from the rule's own samples and evaluations only (no new
    solve), so the same in every sweep that gives the rule the same samples.
    """
    kmax = max(kappas)
    if kmax <= 0:
        return   # no convex corner at all: warned already
    z = [0.5 * math.log(p["rho2"]) for p in pts if p["rho2"] > 0 and p["eta2"] > 0]
    e = [0.5 * math.log(p["eta2"]) for p in pts if p["rho2"] > 0 and p["eta2"] > 0]
    if len(z) < 2:
        return
    extent = math.hypot(max(z) - min(z), max(e) - min(e))
    if 1.0 / kmax <= extent:
        return
    other = (" and the curve bends more sharply the other way (concave, curvature "
             f"{min(kappas):.2g} at a sample)" if -min(kappas) > kmax else "")
    curve.warnings.append(
        f"lcurve: the corner chosen (lam={lam:.3g}) is faint: its curvature {kmax:.2g} turns on a "
        f"radius of {1.0 / kmax:.3g} (log units), more than the curve's extent ({extent:.3g}), so a "
        f"plot of the curve shows no corner there{other}; the L-curve's choice is not reliable here: "
        "judge it against solutions at other lambdas, or state the accelerometer noise "
        "(residual='acceleration' with sigma_a, where lam=1 needs no choosing)")


def _no_corner(curve) -> None:
    curve.warnings.append("lcurve: the curve has no convex corner in lam_range=("
                          f"{curve.lam_range[0]:g}, {curve.lam_range[1]:g}); {WIDEN}, or "
                          "choose another rule (e.g. lam='quasi')")


register_rule(LCurve())
