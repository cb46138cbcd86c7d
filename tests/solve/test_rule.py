"""The lambda-rule stage (bvpnav.solve.rule): every user option reaches the final fixed-lambda solve."""

from __future__ import annotations

import pytest
from _helpers import known_noise


# ------------------------------------- every user option reaches the final solve (issue 14)
def _final_solve_kwargs(monkeypatch, prob, **kw):
    """Solve with a rule; return the options the final fixed-lambda solve ran with (what
    every back-end attempt of it was handed by the pipeline)."""
    from bvpnav.solve import chain

    calls = []
    orig = chain.attempt

    def spy(form, backend, options, lam, opts, *workspace):
        calls.append({"lam": lam, "fallback": opts.fallback, "verify": opts.verify,
                      "accuracy": opts.accuracy, "options": opts.options, "solver": opts.solver})
        return orig(form, backend, options, lam, opts, *workspace)

    monkeypatch.setattr(chain, "attempt", spy)
    sol = prob.solve(**kw)
    final = [c for c in calls if not isinstance(c.get("lam"), str)]
    assert len({c["lam"] for c in final}) == 1, calls  # the direct sweep runs no back end
    assert final[0]["lam"] == sol.lam == sol.curve.lam_chosen and sol.lam_rule == kw["lam"]
    return final[0], sol


@pytest.mark.parametrize("option, value, check", [
    ("fallback", None, lambda s: [a["solver"] for a in s.stats["attempts"]] == ["clarabel"]),
    ("verify", False, lambda s: s.stats["verified"] in (True, False)),
    ("accuracy", "high", lambda s: s.stats["accuracy"] == "high"),
    ("options", {"max_iter": 77}, lambda s: s.stats["options"]["max_iter"] == 77),
    ("solver", "direct", lambda s: s.stats["solver"] == "direct"),
])
def test_rule_passes_each_option_to_the_final_solve(monkeypatch, option, value, check):
    """Before: lam='gcv' with fallback=None, verify=False ran its final solve with
    fallback='auto', verify=True (the options were dropped in solve_with_rule)."""
    prob, _ = known_noise(0, n=201)
    final, sol = _final_solve_kwargs(monkeypatch, prob, lam="gcv", **{option: value})
    assert final[option] == value
    assert check(sol)


def test_rule_with_verify_false_returns_an_unverified_answer_instead_of_falling_back(monkeypatch):
    """verify=False and fallback=None reach the final solve: an OSQP stopped after five
    iterations is returned as it is (verified False), not replaced by the chain's next link
    (before the fix the final solve verified, fell back and returned Clarabel's answer)."""
    prob, _ = known_noise(0, n=201)
    final, sol = _final_solve_kwargs(monkeypatch, prob, lam="gcv", fallback=None, verify=False,
                                     solver="osqp", options={"max_iter": 5})
    assert final["verify"] is False and final["fallback"] is None
    assert sol.stats["solver"] == "osqp" and sol.stats["status"] == "user_limit"
    assert not sol.stats["verified"]
    assert sol.stats["attempts"] == [{"solver": "osqp", "status": "user_limit",
                                      "reason": "failed verification"}]
