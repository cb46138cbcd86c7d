"""The speed/memory benchmark of issue 18 at small size: its banded reference solves the very
problem bvpnav solves (numbers, never timings).

Measured: the reference agrees with ``direct`` (LDL^T and LU) to about 2e-12 relative at
N = 3,000 and 1e5, on one axis and on three axes with ``ScaleFactor() + Bias()``.
"""

from __future__ import annotations

import contextlib
import io
import warnings

import numpy as np
import pytest
from _helpers import load_benchmark_module


@pytest.fixture(scope="module")
def bench():
    return load_benchmark_module("speed_memory")


def _direct(bench, spec, lam, method=None):
    prob = bench.make_problem(spec)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = prob.solve(solver="direct", lam=lam, fallback=None,
                         options=None if method is None else {"method": method})
    assert sol.stats["verified"]
    return bench.trajectory(prob, sol.x), sol


@pytest.mark.parametrize("axes", [1, 3])
@pytest.mark.parametrize("lam", [1.0, 0.05])
def test_reference_agrees_with_direct_ldl_and_lu(bench, axes, lam):
    from _banded_reference import reference_solve

    spec = bench.make_spec(3000, axes, error_model=axes > 1, seed=2)
    ref = reference_solve(spec, lam)
    assert ref.shape == (3000, axes)
    for method in (None, "lu"):
        r, sol = _direct(bench, spec, lam, method)
        if method == "lu":
            assert sol.stats["factorization"] == "lu"
        assert bench.rel_diff(r, ref) < 1e-8, (axes, lam, method, bench.rel_diff(r, ref))
    # the problem is the one described: the answer is near the truth (1 m fixes, 30 s)
    assert np.max(np.abs(ref - spec.truth)) < 2.0


def test_error_model_columns_match_bvpnav(bench):
    from bvpnav.error_models import Bias, ScaleFactor

    spec = bench.make_spec(500, 3, error_model=True)
    prob = bench.make_problem(spec)
    G = (ScaleFactor() + Bias()).columns(prob.formulation.data)
    mine = spec.columns()
    # same columns up to their order (scale factors: the measured acceleration; biases: ones)
    for k in range(mine.shape[2]):
        assert min(np.max(np.abs(G[:, :, j] - mine[:, :, k])) for j in range(G.shape[2])) == 0.0


@pytest.mark.slow
def test_quick_run_prints_its_tables(bench):
    # one repetition: the repeats only time the same deterministic solves again (a median of
    # ratios), and the test reads the numbers, never the timings
    with contextlib.redirect_stdout(io.StringIO()) as out:
        bench.main(["--quick", "--repeat", "1"])
    text = out.getvalue()
    for head in ("speed: ratios to the reference", "lambda rules, N = 10000", "peers (1 axis"):
        assert head in text, text
    rows = [ln.split() for ln in text.splitlines() if ln.startswith(("1 ax", "3 ax"))]
    direct = [r[r.index("direct"):] for r in rows if "direct" in r and "backend" not in r]
    assert len(direct) == 4  # 1 and 3 axes at N = 2e3 and 1e4
    for r in direct:  # direct, time, x ref, runs, vs ref, verified
        assert float(r[4]) < 1e-8 and r[5] == "True", r
    for rule in ("lcurve", "gcv", "quasi"):
        line = next(ln for ln in text.splitlines() if ln.startswith(rule))
        lam, evals = float(line.split()[1]), int(line.split()[2])
        assert 1e-6 <= lam <= 1e6 and evals >= 1, line
