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

    def spying(form, backend, options, lam, opts, *workspace):
        calls.append({"solver": backend.name, "options": dict(options), "verify": opts.verify,
                      "accuracy": opts.accuracy, "chain": [b.name for b, _ in opts.chain],
                      "on_conflict": opts.on_conflict, "lam": lam})
        return real(form, backend, options, lam, opts, *workspace)

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
    """pipeline.run builds gate(demote(attitude(sequential(rule(chain))))); no stage imports the
    problem."""
    assert [s.__name__ for s in pipeline.STAGES] == ["with_gating", "with_demotion", "with_attitude",
                                                     "with_sequential", "with_rule"]
    import bvpnav.solve.attitude as a
    import bvpnav.solve.conflicts as c
    import bvpnav.solve.gating as g
    import bvpnav.solve.rule as r
    import bvpnav.solve.sequential as s

    for mod in (a, c, g, r, s, chain):
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


def test_the_run_and_its_timings_are_typed_and_flattened_into_the_stats():
    sol = ls_problem().solve(solver="direct")
    run = sol.records.run
    assert isinstance(run, bvpnav.result.Run) and isinstance(run.timings, bvpnav.result.Timings)
    assert run.solver == "direct" and run.preset_applied and run.options == sol.stats["options"]
    assert run.timings.wall_time >= run.timings.solve_time > 0
    for key in ("solve_time", "setup_time", "compile_time", "wall_time"):
        assert sol.stats[key] == getattr(run.timings, key)
    assert sol.stats["factorization"] == run.details["factorization"]  # back-end specific
    cv = ls_problem().solve(solver="clarabel").records.run
    # the options the problem's shape added (an equality-constrained least-squares problem)
    assert cv.timings.cvxpy_time >= cv.timings.solve_time > 0
    from bvpnav.backends.cvxpy_solvers import CANON_BACKEND, EQUALITY_QP_CLARABEL

    assert cv.details == {"adapted_options": EQUALITY_QP_CLARABEL, "canon_backend": CANON_BACKEND}


# ------------------------------------------- found by the independent review of the redesign
def test_lambda_curve_evaluates_every_registered_rule_by_default():
    prob = ls_problem()
    prob.sigma_a = 0.05  # the discrepancy rule needs the noise level
    curve = bvpnav.lambda_curve(prob)
    assert set(curve.chosen) == set(bvpnav.lam.rule_names()) == {"lcurve", "gcv", "discrepancy", "quasi"}


def test_setting_sigma_a_after_construction_changes_the_solution():
    prob = ls_problem()
    before = prob.solve(solver="direct").position()
    prob.sigma_a = 0.01
    assert prob.sigma_a_given and prob.formulation.sigma_a[0] == 0.01
    after = prob.solve(solver="direct").position()
    assert np.max(np.abs(after - before)) > 1e-3  # the data term weighs 10^4 times more
    with pytest.raises(bvpnav.InputError, match="sigma_a"):
        prob.sigma_a = -1.0


def test_a_formulation_gives_unnamed_items_unique_labels():
    from bvpnav.formulation import Formulation

    data = bvpnav.ImuData(t=T, acc=ACC)
    form = Formulation(data, items=[Position(t=0.0, value=0.0), Position(t=10.0, value=1.0),
                                    Position(t=5.0, value=0.5, sigma=0.1)])
    assert form.labels == ["Position", "Position#2", "Position#3"]
    sol = bvpnav.solve.solve(form, solver="direct")
    assert abs(sol.position()[-1] - 1.0) < 1e-9 and sol.stats["verified"]


@pytest.mark.parametrize("kw, culprit", [
    (dict(lam="gcv", rule={"bogus": 1}), r"rule: unknown option\(s\) \['bogus'\]; valid: \['lam_range'"),
    (dict(lam="gcv", rule="points"), r"rule='points': give a dict"),
    (dict(lam="gcv", rule={"lam_range": (1.0, 0.5)}), r"lam_range=\(1.0, 0.5\): need 0 < low < high"),
    (dict(sequential={"max_iters": 3}), r"sequential: unknown option\(s\) \['max_iters'\]; valid: \['tol'"),
    (dict(sequential="x"), r"sequential='x': give a dict"),
])
def test_rule_and_sequential_options_are_checked_before_any_work(monkeypatch, kw, culprit):
    monkeypatch.setattr(chain, "attempt", lambda *a, **k: pytest.fail("a back end ran"))
    with pytest.raises(bvpnav.InputError, match=culprit):
        track_problem().solve(**kw)


def test_lambda_curve_solve_kw_keeps_the_explicit_arguments_and_refuses_what_it_ignores(spy):
    curve = bvpnav.lambda_curve(robust_problem(), rules=("lcurve",), points=9, solver="clarabel",
                                solve_kw=dict(solver="scs", verify=False, fallback=None))
    assert curve.engine == "cvxpy" and {c["solver"] for c in spy} == {"clarabel"}
    assert all(c["verify"] is False and c["chain"] == ["clarabel"] for c in spy)
    with pytest.raises(bvpnav.InputError, match=r"solve_kw: \['on_conflict'\] do not apply"):
        bvpnav.lambda_curve(robust_problem(), solve_kw={"on_conflict": "demote"})


def test_a_rule_needing_the_trace_must_need_least_squares():
    class Traced(bvpnav.lam.LambdaRule):
        name = "traced"
        needs = frozenset({"trace"})

    with pytest.raises(bvpnav.InputError, match="needs 'trace' but not 'least_squares'"):
        bvpnav.lam.register_rule(Traced())
    assert "traced" not in bvpnav.lam.rule_names()


def test_build_is_a_mapping_and_failed_attempts_are_plain_dicts():
    import json

    cvx = ls_problem().build()
    assert "lam" in cvx and set(dict(cvx)) >= {"problem", "lam", "x", "fem", "cons", "penalties"}
    with pytest.raises(bvpnav.Infeasible) as err:
        conflict_problem().solve()
    json.dumps(err.value.attempts)  # JSON-ready, as before the typed records
    assert err.value.attempts[-1]["conflicts"] == ["a", "b"]


def test_a_solution_names_the_formulation_it_solves():
    """``Solution.formulation`` (read-only) is the problem's own formulation for a plain
    solve and the demoted one after a conflict: the item the demotion made soft is soft
    there, hard in the problem; and no formulation holds a cache of the solve."""
    prob = ls_problem()
    sol = prob.solve(solver="direct")
    assert sol.formulation is prob.formulation
    with pytest.raises(AttributeError):
        sol.formulation = None
    prob = conflict_problem()
    sol = prob.solve(solver="clarabel", on_conflict="demote")
    modes = {it.label: it.mode for it in sol.formulation.items}
    assert sol.formulation is not prob.formulation
    assert sorted(modes.values()).count("soft") == 2   # 'fixes' and the demoted one
    demoted = [label for label in ("a", "b") if modes[label] == "soft"]
    assert len(demoted) == 1 and {it.label: it.mode for it in prob.formulation.items}[demoted[0]] == "hard"
    assert not hasattr(sol.formulation, "cache") and not hasattr(prob.formulation, "cache")
