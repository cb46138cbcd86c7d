"""Generalized cross-validation: minimise rho^2 / tr(I - A_lambda)^2."""

from __future__ import annotations

import math

import numpy as np

from . import LambdaRule, edge_warning, refine_extremum, register_rule

__all__ = ["GCV", "gcv"]


def gcv(pt: dict) -> float:
    """The GCV function at one point: :math:`\\hat\\rho / \\mathrm{tr}(I - A_\\lambda)^2`."""
    dof = abs(pt["trace"])
    return pt["rho2"] / dof**2 if dof > 0 else np.inf


class GCV(LambdaRule):
    """Minimise :math:`G = \\hat\\rho / \\mathrm{tr}(I - A_\\lambda)^2`.

    Notes
    -----
    :math:`\\mathrm{tr}(I - A_\\lambda) = -\\mathrm{tr}(\\partial w / \\partial \\hat a)`, by exact
    columns for small problems and Hutchinson's randomized estimator for large ones (see
    :class:`bvpnav.lam.sweep.DirectSweep`). GCV treats the data residual as independent
    observations; in the load form the data term :math:`\\|M w\\|^2` is mass-matrix
    weighted (correlated), and on the 2011 example the function decreases to the edge of
    the range (a warning says so).
    """

    name = "gcv"
    uses_derivative = False
    needs = frozenset({"least_squares", "trace"})

    def scores(self, sweep, pts, s):
        return np.array([gcv(p) for p in pts])

    def refine(self, sweep, pts, s, scores, curve):
        k = int(np.argmin(scores))
        edge_warning(curve, self.name, k, 0, scores, best="min")
        return float(math.exp(refine_extremum(lambda u: gcv(sweep.point(math.exp(u))), s, scores, k,
                                              best="min")))


register_rule(GCV())
