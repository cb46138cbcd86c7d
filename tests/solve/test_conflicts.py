"""Conflicting hard information is reported by name (a deletion filter, bvpnav.cvx)."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import conflict_problem

import bvpnav
from bvpnav.constraints import Position
from bvpnav.cvx import conflicting_items


def test_two_contradictory_hard_positions_are_named_exactly():
    prob = conflict_problem(Position(t=5.0, value=1.0, name="fix A"),
                            Position(t=5.0, value=2.0, name="fix B"))
    with pytest.raises(bvpnav.Infeasible) as exc:
        prob.solve()
    msg = str(exc.value)
    assert "These hard items conflict: ['fix A', 'fix B']" in msg
    assert any(a.get("conflicts") == ["fix A", "fix B"] for a in exc.value.attempts)
    assert conflicting_items(prob.formulation) == ["fix A", "fix B"]


def test_a_conflict_spread_over_three_items_is_irreducible():
    # r(0) = 0 (ends), r(5) = 1 (fix) and (r(5) - r(0)) / 5 s = 0 (stopwatch): no two of
    # them conflict, all three do
    from bvpnav.constraints import AverageVelocity

    prob = conflict_problem(Position(t=5.0, value=1.0, name="fix"),
                   AverageVelocity(t0=0.0, t1=5.0, value=0.0, name="stopwatch"))
    names = conflicting_items(prob.formulation)
    assert names == ["ends", "fix", "stopwatch"]  # dropping any one of them resolves it


def test_consistent_information_accuses_nobody_even_when_redundant():
    prob = conflict_problem(Position(t=10.0, value=0.0, name="end again"))  # repeats the ends, consistently
    assert conflicting_items(prob.formulation) == []
    assert prob.solve().stats["verified"]


def test_demote_by_priority_keeps_the_trusted_item_hard():
    a = Position(t=5.0, value=1.0, name="fix A")
    b = Position(t=5.0, value=2.0, name="fix B")
    sol = conflict_problem(a, b).solve(on_conflict="demote", priority={"fix A": 1.0}, demote_sigma=0.1)
    r5 = np.interp(5.0, sol.t, sol.position("x"))
    assert abs(r5 - 1.0) < 1e-9  # fix A stayed hard
    assert sol.stats["demoted"] == [{"item": "fix B", "sigma": 0.1, "priority": 0.0,
                                     "conflict": ["fix A", "fix B"]}]
    row = sol.items.set_index("item").loc["fix B"]
    assert row["mode"] == "soft" and abs(row["max_abs"] - 1.0) < 1e-9
    assert any("'fix B'" in w and "demoted to soft with sigma=0.1" in w for w in sol.warnings)
    # the other way round: B trusted more, A demoted
    sol = conflict_problem(a, b).solve(on_conflict="demote", priority={"fix B": 2.0})
    assert abs(np.interp(5.0, sol.t, sol.position("x")) - 2.0) < 1e-9
    assert [d["item"] for d in sol.stats["demoted"]] == ["fix A"]
    assert sol.stats["demoted"][0]["sigma"] == 1.0  # the documented default


def test_demote_ties_go_to_the_item_added_last_and_only_one_item_per_conflict():
    from bvpnav.constraints import AverageVelocity

    prob = conflict_problem(Position(t=5.0, value=1.0, name="fix"),
                   AverageVelocity(t0=0.0, t1=5.0, value=0.0, name="stopwatch"))
    sol = prob.solve(on_conflict="demote", priority={"ends": 10.0, "fix": 5.0})
    assert [d["item"] for d in sol.stats["demoted"]] == ["stopwatch"]
    assert abs(np.interp(5.0, sol.t, sol.position("x")) - 1.0) < 1e-9
    sol = prob.solve(on_conflict="demote")  # all priority 0: the last added goes
    assert [d["item"] for d in sol.stats["demoted"]] == ["stopwatch"]
    with pytest.raises(bvpnav.InputError, match=r"priority names unknown item\(s\) \['nope'\]"):
        prob.solve(on_conflict="demote", priority={"nope": 1.0})
    with pytest.raises(bvpnav.InputError, match="on_conflict='ignore'"):
        prob.solve(on_conflict="ignore")
