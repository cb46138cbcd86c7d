"""The L-curve rule: the corner of maximum curvature of (log rho, log eta)."""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import CubicSpline

from . import WIDEN, LambdaRule, bracket, edge_warning, refine_extremum, register_rule

__all__ = ["LCurve", "curvature", "spline_curvature"]


def curvature(pt: dict) -> float:
    """Signed curvature of :math:`(\\log\\rho, \\log\\eta)` at one lambda from exact derivatives.

    Notes
    -----
    With :math:`\\hat\\rho = \\rho^2`, :math:`\\hat\\eta = \\eta^2`, the stationarity of
    :math:`J = \\hat\\rho + \\lambda\\hat\\eta` along the solution path gives
    :math:`\\hat\\rho' = -\\lambda\\hat\\eta'`, and the second derivatives cancel from the
    curvature :math:`(\\zeta'\\eta'' - \\zeta''\\eta')/(\\zeta'^2 + \\eta'^2)^{3/2}` of
    :math:`(\\zeta, \\eta) = (\\tfrac12\\log\\hat\\rho, \\tfrac12\\log\\hat\\eta)`:

    .. math:: \\kappa = \\frac{2}{\\hat\\rho\\hat\\eta\\,|\\hat\\eta'|}
        \\frac{1 + \\lambda\\hat\\eta'/\\hat\\eta + \\lambda^2\\hat\\eta'/\\hat\\rho}
             {(\\lambda^2/\\hat\\rho^2 + 1/\\hat\\eta^2)^{3/2}}.

    Positive where the curve, traversed with increasing lambda, turns counter-clockwise
    (the 2011 paper's sign convention, its equation 17).
    """
    lam, r, e, de = pt["lam"], pt["rho2"], pt["eta2"], pt["deta2"]
    if de == 0 or r <= 0 or e <= 0:
        return 0.0
    return float(2.0 / (r * e * abs(de)) * (1.0 + lam * de / e + lam**2 * de / r)
                 / (lam**2 / r**2 + 1.0 / e**2) ** 1.5)


def spline_curvature(s: np.ndarray, rho2, eta2, s_eval: np.ndarray) -> np.ndarray:
    """Curvature of (log rho, log eta) from cubic splines in s = log lambda."""
    zeta = CubicSpline(s, 0.5 * np.log(rho2))
    eta = CubicSpline(s, 0.5 * np.log(eta2))
    z1, z2 = zeta(s_eval, 1), zeta(s_eval, 2)
    e1, e2 = eta(s_eval, 1), eta(s_eval, 2)
    # sign: positive at the corner of an L traversed with rho increasing
    return (z1 * e2 - z2 * e1) / np.maximum((z1**2 + e1**2) ** 1.5, 1e-300)


class LCurve(LambdaRule):
    """Maximise the curvature of :math:`(\\log\\rho, \\log\\eta)`.

    Notes
    -----
    The two outermost sweep points on each side are never chosen (a "corner" there is the
    range ending, reported in the curve's warnings). Exact curvature (:func:`curvature`)
    with the direct sweep, refined by :func:`bvpnav.lam.refine_extremum`; a spline through the samples
    (:func:`spline_curvature`) with the cvxpy sweep, refined by sampling more densely.
    """

    name = "lcurve"

    def scores(self, sweep, pts, s):
        if sweep.engine == "direct":
            return np.array([curvature(p) for p in pts])
        return spline_curvature(s, [p["rho2"] for p in pts], [p["eta2"] for p in pts], s)

    def refine(self, sweep, pts, s, scores, curve):
        inner = np.arange(2, len(s) - 2)
        k = int(inner[np.argmax(scores[inner])])
        edge_warning(curve, self.name, k, 2, scores, best="max")
        if scores[k] <= 0:
            curve.warnings.append("lcurve: the curve has no convex corner in lam_range=("
                                  f"{curve.lam_range[0]:g}, {curve.lam_range[1]:g}); {WIDEN}, or "
                                  "choose another rule (e.g. lam='quasi')")
        if sweep.engine == "direct":
            return float(math.exp(refine_extremum(lambda u: curvature(sweep.point(math.exp(u))), s,
                                                  scores, k, best="max", bounds=(s[2], s[-3]))))
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


register_rule(LCurve())
