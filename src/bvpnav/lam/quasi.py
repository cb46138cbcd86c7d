"""Quasi-optimality: the smallest interior minimum of ||lambda dr/dlambda||."""

from __future__ import annotations

import math

import numpy as np

from . import WIDEN, LambdaRule, refine_extremum, register_rule

__all__ = ["Quasi"]


class Quasi(LambdaRule):
    r"""Minimise :math:`\|\lambda\, dr/d\lambda\|` (m, RMS over the nodal positions).

    Notes
    -----
    The function tends to 0 at both ends of any range, so the smallest *interior* local
    minimum is taken. Exact derivatives with the direct sweep (refined by
    :func:`bvpnav.lam.refine_extremum`);
    finite differences in :math:`\log\lambda` between samples with the cvxpy sweep.
    """

    name = "quasi"

    def scores(self, sweep, pts, s):
        if sweep.engine == "direct":
            return np.array([p["quasi"] for p in pts])
        model = sweep.model
        xs = np.array([p["x"] for p in pts])
        pos = np.concatenate([model.r_index(a) for a in range(model.d)])
        dxs = np.gradient(xs[:, pos], s, axis=0)
        return np.linalg.norm(dxs, axis=1) / math.sqrt(pos.size)

    def refine(self, sweep, pts, s, scores, curve):
        q = scores
        loc = [k for k in range(1, len(s) - 1) if q[k] < q[k - 1] and q[k] <= q[k + 1]]
        if not loc:
            curve.warnings.append(f"quasi: no interior local minimum in lam_range=({curve.lam_range[0]:g}, "
                                  f"{curve.lam_range[1]:g}); {WIDEN}")
            loc = [int(np.argmin(q[1:-1])) + 1]
        k = min(loc, key=lambda j: q[j])
        if sweep.engine != "direct":
            return float(curve.lam[k])
        return float(math.exp(refine_extremum(lambda u: sweep.point(math.exp(u))["quasi"], s, q, k,
                                              best="min")))


register_rule(Quasi())
