"""The discrepancy principle: the data residual as large as the stated noise."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from . import WIDEN, LambdaRule, register_rule

__all__ = ["Discrepancy"]


class Discrepancy(LambdaRule):
    r"""Choose lambda with :math:`\hat\rho = \tau\, \mathrm{tr}(I - A_\lambda)`.

    Notes
    -----
    Meaningful only for ``residual="acceleration"`` with ``sigma_a`` given (the residual
    is then in units of the noise); ``tau`` (the sweep's safety factor, default 1.5).
    The largest crossing is refined by Brent's root finder; without a crossing the closest
    sample is taken, with a warning.
    """

    name = "discrepancy"
    uses_derivative = False
    needs = frozenset({"least_squares", "trace", "noise"})

    def scores(self, sweep, pts, s):
        return np.array([p["rho2"] - sweep.tau * abs(p["trace"]) for p in pts])

    def refine(self, sweep, pts, s, scores, curve):
        sign = np.sign(scores)
        cross = np.nonzero(sign[:-1] * sign[1:] < 0)[0]
        if cross.size == 0:
            curve.warnings.append("discrepancy: the residual never matches the stated noise in the "
                                  "range; taking the closest point: check sigma_a= (the accelerometer noise, "
                                  f"m/s^2), adjust tau= (default 1.5), or {WIDEN}")
            return float(curve.lam[int(np.argmin(np.abs(scores)))])
        k = int(cross[-1])

        def f(u):
            p = sweep.point(math.exp(u))
            return p["rho2"] - sweep.tau * abs(p["trace"])

        return float(math.exp(brentq(f, s[k], s[k + 1], xtol=1e-4)))


register_rule(Discrepancy())
