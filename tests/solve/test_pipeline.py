"""The solve pipeline: every user option reaches every stage, and no stage calls back up.

A spy on the innermost step (one back end's attempt, ``bvpnav.solve.chain.attempt``)
records what each attempt was given. Every path through the pipeline (fixed lambda, a
lambda rule with the direct and the cvxpy sweep, the sequential loop, demotion, and their
combinations) must hand every attempt the user's solver, accuracy preset, extra options,
verify flag and fallback chain: before the redesign, ``solve(lam="gcv", fallback=None,
verify=False)`` ran its final solve with ``fallback="auto", verify=True``.
"""

from __future__ import annotations

import numpy as np
import pytest

import bvpnav
from bvpnav.constraints import Position, TrackLine
from bvpnav.solve import chain, pipeline

T = np.linspace(0.0, 10.0, 101)
RNG = np.random.default_rng(7)
ACC = np.sin(T) + RNG.normal(0.0, 0.05, T.size)  # m/s^2


def ls_problem():
    """Least squares: hard ends, three soft fixes (a rule uses the direct sweep)."""
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=ACC), items=[
        Position(t=[0.0, 10.0], value=[0.0, 1.0], name="ends"),
        Position(t=[3.0, 5.0, 7.0], value=[0.3, 0.5, 0.7], sigma=0.1, name="fixes")])


def robust_problem():
    """A robust item: not least squares (a rule uses the cvxpy sweep)."""
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=ACC), items=[
        Position(t=[0.0, 10.0], value=[0.0, 1.0], name="ends"),
        Position(t=[3.0, 5.0, 7.0], value=[0.3, 0.5, 0.7], sigma=0.1, mode="robust", huber=0.2,
                 name="fixes")])


def conflict_problem():
    """Two hard positions at t = 5 s that disagree (demotion makes one soft)."""
    prob = ls_problem()
    return prob.add(Position(t=5.0, value=0.5, name="a"), Position(t=5.0, value=0.6, name="b"))


def track_problem():
    """A straight rail along x in 2-D: the sequential loop (soft track)."""
    acc = np.column_stack([np.zeros_like(T), RNG.normal(0.0, 0.05, T.size)])
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=acc, axes=("x", "y")), items=[
        Position(t=[0.0, 10.0], value=[[0.0, 0.0], [10.0, 0.0]], name="ends"),
        Position(t=[2.0, 8.0], value=[[2.0, 0.0], [8.0, 0.0]], sigma=0.5, name="fixes"),
        TrackLine(x=[-1.0, 11.0], y=[0.0, 0.0], axes=("x", "y"), sigma=0.05, name="rail")])


@pytest.fixture
def spy(monkeypatch):
    calls: list[dict] = []
    real = chain.attempt

    def spying(form, backend, options, lam, opts):
        calls.append({"solver": backend.name, "options": dict(options), "verify": opts.verify,
                      "accuracy": opts.accuracy, "chain": [b.name for b, _ in opts.chain],
                      "on_conflict": opts.on_conflict, "lam": lam})
        return real(form, backend, options, lam, opts)

    monkeypatch.setattr(chain, "attempt", spying)
    return calls


# (problem, lam, extra solve options, stages the path goes through)
PATHS = [
    pytest.param(ls_problem, 1.0, {}, "chain", id="fixed"),
    pytest.param(ls_problem, "gcv", {}, "rule(direct sweep) > chain", id="gcv-direct-sweep"),
    pytest.param(robust_problem, "lcurve", {"rule": {"points": 9}}, "rule(cvxpy sweep) > chain",
                 id="lcurve-cvxpy-sweep"),
    pytest.param(track_problem, 1.0, {}, "sequential > chain", id="sequential"),
    pytest.param(track_problem, "quasi", {"rule": {"points": 9}}, "sequential > rule > chain",
                 id="sequential-rule"),
    pytest.param(conflict_problem, 1.0, {"on_conflict": "demote"}, "demote > chain", id="demote"),
    pytest.param(conflict_problem, "gcv", {"on_conflict": "demote"}, "demote > rule > chain",
                 id="demote-rule"),
]


@pytest.mark.parametrize("make, lam, extra, stages", PATHS)
def test_every_option_reaches_every_attempt(spy, make, lam, extra, stages):
    prob = make()
    cone_free = "robust" not in make.__name__
    solver = "clarabel"
    user = {"max_iter": 321}
    sol = prob.solve(solver=solver, lam=lam, accuracy="high", verify=False, options=user,
                     fallback=None, **extra)
    assert spy, f"{stages}: no attempt ran"
    for call in spy:
        assert call["solver"] == solver, (stages, call)
        assert call["options"]["max_iter"] == 321, (stages, call)  # the user's option
        assert call["options"]["tol_gap_abs"] == 1e-11, (stages, call)  # the 'high' preset
        assert call["accuracy"] == "high" and call["verify"] is False, (stages, call)
        assert call["chain"] == ["clarabel"], (stages, call)  # fallback=None: nothing else
        assert call["on_conflict"] == extra.get("on_conflict", "raise"), (stages, call)
    assert sol.stats["solver"] == solver and sol.stats["accuracy"] == "high"
    assert sol.stats["options"]["max_iter"] == 321
    if isinstance(lam, str):
        assert sol.curve is not None and sol.lam_rule.startswith(lam)
        assert sol.lam == pytest.approx(sol.curve.chosen[lam], rel=1e-12)
    if "sequential" in stages:
        assert sol.stats["sequential"]["converged"] and sol.records.sequential.iterations >= 2
    if "demote" in stages:
        assert [d.item for d in sol.records.demoted] == ["b"]  # added last, equal priority
    assert cone_free or sol.curve.engine == "cvxpy"


@pytest.mark.parametrize("fallback, expected", [(None, ["direct"]), (["scs"], ["direct", "scs"]),
                                                ("auto", ["direct", "clarabel", "scs"])])
def test_the_fallback_chain_of_a_rule_is_the_users(spy, fallback, expected):
    """The final solve of a rule uses the user's fallback (the bug of the recursion)."""
    sol = ls_problem().solve(solver="direct", lam="gcv", fallback=fallback, verify=False)
    assert [c["chain"] for c in spy] == [expected]
    assert sol.lam_rule == "gcv" and sol.stats["solver"] == "direct"


def test_the_stages_compose_in_one_place():
    """pipeline.run builds demote(sequential(rule(chain))); no stage imports the problem."""
    assert [s.__name__ for s in pipeline.STAGES] == ["with_demotion", "with_sequential", "with_rule"]
    import bvpnav.solve.conflicts as c
    import bvpnav.solve.rule as r
    import bvpnav.solve.sequential as s

    for mod in (c, r, s, chain):
        assert "NavigationProblem" not in vars(mod), mod.__name__


def test_typed_records_build_the_stats():
    sol = conflict_problem().solve(on_conflict="demote")
    rec = sol.records
    assert isinstance(rec.verification, bvpnav.result.Verification) and rec.verification.verified
    assert all(isinstance(a, bvpnav.result.Attempt) for a in rec.attempts)
    assert sol.stats["verification"] == rec.verification.as_dict()
    assert sol.stats["attempts"] == [a.as_dict() for a in rec.attempts]
    assert sol.stats["demoted"] == [d.as_dict() for d in rec.demoted]
    # records read like the dicts they replace
    assert rec.attempts[-1]["reason"] == "verified" and rec.attempts[-1].get("conflicts") is None
