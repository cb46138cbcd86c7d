"""The quasi-optimality rule (bvpnav.lam.quasi)."""

from __future__ import annotations

import numpy as np
from _helpers import table1

from bvpnav.solve import lambda_curve


def test_quasi_optimality_picks_an_interior_minimum():
    prob, _ = table1(seed=3, scale=0.0, bias=0.5)
    curve = lambda_curve(prob, rules=("quasi",), rule="quasi")
    q = curve.scores["quasi"]
    lam = curve.lam_chosen
    k = int(np.argmin(np.abs(np.log(curve.lam / lam))))
    assert 0 < k < len(q) - 1
    assert 0.1 < lam < 100
