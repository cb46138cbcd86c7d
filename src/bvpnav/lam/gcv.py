"""Generalized cross-validation: minimise rho^2 / tr(I - A_lambda)^2."""

from __future__ import annotations

import math

import numpy as np

from . import LambdaRule, edge_warning, half_way_points, refine_extremum, register_rule

__all__ = ["GCV", "gcv"]


def gcv(pt: dict) -> float:
    r"""The GCV function at one point: :math:`\hat\rho / \mathrm{tr}(I - A_\lambda)^2`."""
    dof = abs(pt["trace"])
    return pt["rho2"] / dof**2 if dof > 0 else np.inf


class GCV(LambdaRule):
    r"""Minimise :math:`G = \hat\rho / \mathrm{tr}(I - A_\lambda)^2`.

    Notes
    -----
    :math:`\mathrm{tr}(I - A_\lambda) = -\mathrm{tr}(\partial w / \partial \hat a)`, by exact
    columns for small problems and Hutchinson's randomized estimator for large ones (see
    :class:`bvpnav.lam.sweep.DirectSweep`). GCV treats the data residual as independent
    observations; in the load form the data term :math:`\|M w\|^2` is mass-matrix
    weighted (correlated), and on the 2011 example the function decreases to the edge of
    the range (a warning says so).

    On samples more than a decade apart (``solve(lam="gcv")`` samples every two decades
    on a range of 12 decades or more) the half-way points beside the best sample are
    evaluated first (:func:`bvpnav.lam.half_way_points`), so the minimum is refined from
    a bracket one decade wide on each side, as on a grid of one sample per decade. When
    the best is still an end of the range, every half-way point is evaluated (the whole
    one-decade grid) before the end is reported as an edge. A minimum narrower than about
    a decade, away from the best coarse sample, can still be missed where the one-decade
    grid would see it (see the guide's lambda page for measured rates).
    """

    name = "gcv"
    uses_derivative = False
    coarse = True
    needs = frozenset({"least_squares", "trace"})

    def scores(self, sweep, pts, s):
        return np.array([gcv(p) for p in pts])

    def refine(self, sweep, pts, s, scores, curve):
        def f(u):
            return gcv(sweep.point(math.exp(u)))

        k = int(np.argmin(scores))
        u, sc = list(s), list(scores)

        def look(mids):
            for mid in mids:
                if mid not in u:
                    i = int(np.searchsorted(u, mid))
                    u.insert(i, mid), sc.insert(i, f(mid))

        look(half_way_points(s, k))
        j = int(np.argmin(sc))
        if (j == 0 or j == len(u) - 1) and len(u) > len(s):
            # still an end on a coarse grid: before calling it an edge, every half-way point
            # (the one-decade grid's samples), so that a minimum inside the range that the
            # coarse samples straddle is not mistaken for one beyond it
            look([0.5 * (a + b) for a, b in zip(s[:-1], s[1:], strict=True)])
            j = int(np.argmin(sc))
        if j == 0 or j == len(u) - 1:   # an end of the range: the minimum may lie beyond it
            edge_warning(curve, self.name, k, 0, scores, best="min")
        return float(math.exp(refine_extremum(f, np.array(u), np.array(sc), j, best="min")))


register_rule(GCV())
