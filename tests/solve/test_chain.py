"""Solver failures trigger the fallback chain, which records every attempt and why."""

from __future__ import annotations

import numpy as np
import pytest

import bvpnav
from bvpnav.constraints import Position
from bvpnav.solve import DEFAULT_FALLBACK

T = np.linspace(0.0, 10.0, 201)


def _robust_problem():
    # Hard ends, three robust fixes (one an outlier): a cone program (Huber), so an
    # interior-point solver needs several iterations and max_iter=1 cannot finish.
    items = [Position(t=[0.0, 10.0], value=[0.0, 1.0], name="ends"),
             Position(t=[3.0, 5.0, 7.0], value=[0.3, 0.5, 9.0], mode="robust", sigma=0.1,
                      huber=0.2, name="fixes")]
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=np.sin(T)), items=items)


def _ls_problem():
    items = [Position(t=[0.0, 10.0], value=[0.0, 1.0], name="ends"),
             Position(t=5.0, value=0.3, sigma=0.1, name="fix")]
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=np.sin(T)), items=items)


def test_default_chain_is_clarabel_then_direct_then_scs():
    assert DEFAULT_FALLBACK[0][0] == "clarabel"
    assert [e if isinstance(e, str) else e[0] for e in DEFAULT_FALLBACK[1:]] == ["direct", "scs"]


def test_iteration_limit_on_the_primary_falls_back_to_a_verified_answer():
    prob = _robust_problem()
    ref = prob.solve(accuracy="high")  # unhindered Clarabel
    assert ref.stats["solver"] == "clarabel" and ref.stats["verified"]
    sol = prob.solve(options={"max_iter": 1})
    att = sol.stats["attempts"]
    # the primary stopped at its iteration limit and failed bvpnav's own check
    assert att[0]["solver"] == "clarabel" and att[0]["status"] == "user_limit"
    assert att[0]["reason"] == "failed verification"
    # direct cannot take a robust item: skipped, with the item named in the reason
    direct = [a for a in att if a["solver"] == "direct"]
    assert direct and direct[0]["status"] == "not applicable" and "'fixes'" in direct[0]["reason"]
    # the answer comes from the last link of the chain, verified, and says so
    assert sol.stats["solver"] == "scs" and sol.stats["verified"]
    assert att[-1] == {"solver": "scs", "status": sol.stats["status"], "reason": "verified"}
    assert any("clarabel failed (failed verification)" in w for w in sol.warnings)
    # and it is the same trajectory (SCS at eps 1e-8 on a 10 m window)
    assert np.max(np.abs(sol.position() - ref.position())) < 1e-4


def test_configured_chain_is_followed_in_order():
    prob = _ls_problem()
    ref = prob.solve(solver="direct")
    sol = prob.solve(solver="osqp", options={"max_iter": 1}, fallback=["direct"])
    att = sol.stats["attempts"]
    assert [a["solver"] for a in att] == ["osqp", "direct"]
    assert att[0]["reason"] != "verified" and att[1]["reason"] == "verified"
    assert sol.stats["solver"] == "direct"
    assert np.max(np.abs(sol.position() - ref.position())) < 1e-9


def test_every_attempt_failing_raises_with_each_status():
    prob = _robust_problem()
    with pytest.raises(bvpnav.SolveError) as exc:
        prob.solve(options={"max_iter": 1}, fallback=[("scs", {"max_iters": 2})])
    msg = str(exc.value)
    assert "every attempt failed" in msg
    assert [a["solver"] for a in exc.value.attempts] == ["clarabel", "scs"]
    assert "clarabel: user_limit" in msg and "scs:" in msg


def test_no_fallback_raises_the_primary_failure():
    with pytest.raises(bvpnav.Inaccurate, match="user_limit"):
        _robust_problem().solve(options={"max_iter": 1}, fallback=None)


def test_solver_warnings_reach_the_solution():
    # SCS stops at "optimal_inaccurate" here; cvxpy's warning and the status are reported
    # in Solution.warnings next to the fallback notice, not swallowed
    sol = _robust_problem().solve(options={"max_iter": 1})
    assert sol.stats["status"] == "optimal_inaccurate"
    assert any(w.startswith("scs: Solution may be inaccurate") for w in sol.warnings)
    assert any("'optimal_inaccurate'" in w and "passed" in w for w in sol.warnings)
