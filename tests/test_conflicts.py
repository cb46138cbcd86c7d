"""Conflicting hard information is reported by name (a deletion filter, bvpnav.conflicts)."""

from __future__ import annotations

import numpy as np
import pytest

import bvpnav
from bvpnav.conflicts import conflicting_items
from bvpnav.constraints import Position, Velocity


def problem(*extra):
    t = np.linspace(0.0, 10.0, 201)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.zeros_like(t)))
    return prob.add(Position(t=[0.0, 10.0], value=[0.0, 0.0], name="ends"),
                    Velocity(t=2.0, value=0.0, name="v at 2 s"), *extra)


def test_two_contradictory_hard_positions_are_named_exactly():
    prob = problem(Position(t=5.0, value=1.0, name="fix A"), Position(t=5.0, value=2.0, name="fix B"))
    with pytest.raises(bvpnav.Infeasible) as exc:
        prob.solve()
    msg = str(exc.value)
    assert "These hard items conflict: ['fix A', 'fix B']" in msg
    assert any(a.get("conflicts") == ["fix A", "fix B"] for a in exc.value.attempts)
    assert conflicting_items(prob) == ["fix A", "fix B"]


def test_a_conflict_spread_over_three_items_is_irreducible():
    # r(0) = 0 (ends), r(5) = 1 (fix) and (r(5) - r(0)) / 5 s = 0 (stopwatch): no two of
    # them conflict, all three do
    from bvpnav.constraints import AverageVelocity

    prob = problem(Position(t=5.0, value=1.0, name="fix"),
                   AverageVelocity(t0=0.0, t1=5.0, value=0.0, name="stopwatch"))
    names = conflicting_items(prob)
    assert names == ["ends", "fix", "stopwatch"]  # dropping any one of them resolves it


def test_consistent_information_accuses_nobody_even_when_redundant():
    prob = problem(Position(t=10.0, value=0.0, name="end again"))  # repeats the ends, consistently
    assert conflicting_items(prob) == []
    assert prob.solve().stats["verified"]
