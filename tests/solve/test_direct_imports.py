"""A solve the ``direct`` back end answers never imports cvxpy (issue 42: the import alone
costs a quarter of a second against a 0.1 s solve): the automatic fallback chain is looked
up on first use. Each import check runs in a fresh interpreter (this test process may
already have imported cvxpy)."""

from __future__ import annotations

import pytest
from _helpers import run_python

import bvpnav
from bvpnav.solve import prepare


def test_a_direct_solve_does_not_import_cvxpy():
    out = run_python("""
        import json, sys
        import numpy as np
        import bvpnav
        from bvpnav.constraints import Position
        t = np.arange(0.0, 10.0, 0.01)
        data = bvpnav.ImuData(t=t, acc=np.full((t.size, 1), 0.2), axes=("x",))
        fix = t[::100]
        prob = bvpnav.NavigationProblem(data, sigma_a=0.1, items=[
            Position(t=fix, value=0.1 * (fix - fix[0])[:, None] ** 2, sigma=0.01)])
        sol = prob.solve(solver="direct")
        x = sol.trajectory["x"].to_numpy()
        print(json.dumps({"solver": sol.stats["solver"], "cvxpy": "cvxpy" in sys.modules,
                          "end": float(x[-1] - x[0]), "span": float(t[-1] - t[0])}))
    """)
    assert out["solver"] == "direct" and out["cvxpy"] is False
    # x = 0.1 (t - t0)^2 is the exact answer to a = 0.2 with these fixes
    assert out["end"] == pytest.approx(0.1 * out["span"] ** 2, rel=1e-3)


def test_the_automatic_fallbacks_are_found_when_read():
    opts, _ = prepare(solver="direct")
    assert opts.chain[0][0].name == "direct" and not opts.chain.resolved
    names = [be.name for be, _ in opts.chain]
    installed = bvpnav.available_solvers()
    assert opts.chain.resolved
    assert names == ["direct"] + [n for n in ("clarabel", "scs") if n in installed]


def test_an_explicit_fallback_is_checked_up_front():
    with pytest.raises(bvpnav.SolverNotFound, match="no_such_solver"):
        prepare(solver="direct", fallback=["no_such_solver"])
    opts, _ = prepare(solver="direct", fallback=["scs"])
    assert opts.chain.resolved and [be.name for be, _ in opts.chain] == ["direct", "scs"]
