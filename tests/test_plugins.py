"""A lambda rule and a back end are one file each: both are added here, from the tests.

Each is registered through the public API only (``bvpnav.lam.register_rule``,
``bvpnav.backends.register_backend``), then used by name through ``solve()`` exactly like
the built-in ones, and judged against an independent answer.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import bvpnav
from bvpnav.backends import Backend, RawSolve, register_backend, unregister_backend
from bvpnav.constraints import Position
from bvpnav.lam import LambdaRule, register_rule, unregister_rule
from bvpnav.linalg.lsq import least_squares_form, non_least_squares_term

T = np.linspace(0.0, 10.0, 101)
ACC = np.sin(T) + np.random.default_rng(3).normal(0.0, 0.2, T.size)  # m/s^2


def problem(mode="soft"):
    kw = {"huber": 0.5} if mode == "robust" else {}
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=ACC), sigma_a=0.2, items=[
        Position(t=[0.0, 10.0], value=[0.0, 1.0], name="ends"),
        Position(t=[3.0, 5.0, 7.0], value=[0.3, 0.5, 0.7], sigma=0.05, mode=mode, name="fixes", **kw)])


# ------------------------------------------------------------------ a rule in one class
class Balance(LambdaRule):
    """Choose lambda where the two parts of the objective are equal: rho^2 = lam eta^2."""

    name = "balance"

    def scores(self, sweep, pts, s):
        return np.array([math.log(p["rho2"]) - math.log(p["lam"] * p["eta2"]) for p in pts])

    def refine(self, sweep, pts, s, scores, curve):
        k = int(np.nonzero(np.sign(scores[:-1]) != np.sign(scores[1:]))[0][0])

        def f(u):
            p = sweep.point(math.exp(u))
            return math.log(p["rho2"]) - math.log(p["lam"] * p["eta2"])

        return float(math.exp(brentq(f, s[k], s[k + 1], xtol=1e-10)))


# ------------------------------------------------------------- a back end in one class
class DenseKKT(Backend):
    """Equality-constrained least squares by one dense solve of the normal KKT system."""

    name = "dense-kkt"
    least_squares_only = True
    presets = {"low": {}, "default": {}, "high": {}}
    memory_per_sample = {"acceleration": 2e4, "load": 2e4}

    def accepts(self, form):
        term = non_least_squares_term(form)
        return None if term is None else f"dense-kkt takes least squares only, not {term.label!r}"

    def run(self, form, lam, options, verbose=False):
        ls = least_squares_form(form, lam)
        D, E = ls.D.A.toarray(), ls.E.A.toarray()
        n, p = D.shape[1], E.shape[0]
        K = np.block([[2.0 * D.T @ D, E.T], [E, np.zeros((p, p))]])
        z = np.linalg.solve(K, np.concatenate([-2.0 * D.T @ ls.D.c, -ls.E.c]))
        y = z[n:]
        duals = {label: (y[sl] if label == "fem" else [y[sl]]) for label, sl in ls.eq_blocks}
        return RawSolve(z[:n], {"status": "optimal", "iterations": 1}, duals)


@pytest.fixture
def plugins():
    register_rule(Balance())
    register_backend(DenseKKT())
    yield
    unregister_rule("balance")
    unregister_backend("dense-kkt")


def test_a_rule_added_from_the_tests_is_used_by_name(plugins):
    prob = problem()
    sol = prob.solve(lam="balance", solver="direct")
    assert sol.lam_rule == "balance" and "balance" in bvpnav.lam.rule_names()
    # at the chosen lambda the two parts of the objective are equal (to the root's tolerance)
    x = sol.x
    rho2 = float(np.sum(prob.data_rows().value(x) ** 2))
    eta2 = sum(float(np.sum((t.residual.value(x) / t.sigma) ** 2)) for t in prob.terms() if t.mode == "soft")
    assert rho2 == pytest.approx(sol.lam * eta2, rel=1e-6)
    # the built-in rules still choose what they chose, and the new one shows in the curve
    curve = bvpnav.lambda_curve(prob, rules=("lcurve", "balance"))
    assert set(curve.chosen) == {"lcurve", "balance"}
    assert curve.chosen["balance"] == pytest.approx(sol.lam, rel=1e-6)


def test_a_rule_added_from_the_tests_runs_on_the_cvxpy_sweep(plugins):
    sol = problem("robust").solve(lam="balance", rule={"points": 9})
    assert sol.curve.engine == "cvxpy" and sol.lam_rule == "balance" and sol.stats["verified"]


def test_a_back_end_added_from_the_tests_solves_like_direct(plugins):
    prob = problem()
    ref = prob.solve(solver="direct", lam=3.0)
    sol = prob.solve(solver="dense-kkt", lam=3.0)
    assert sol.stats["solver"] == "dense-kkt" and sol.stats["verified"]
    assert "dense-kkt" in bvpnav.available_solvers()
    np.testing.assert_allclose(sol.position(), ref.position(), rtol=0, atol=1e-9)
    # it refuses what it cannot take, naming the item, and the chain goes on
    robust = problem("robust")
    with pytest.raises(bvpnav.InputError, match="dense-kkt takes least squares only, not 'fixes'"):
        robust.solve(solver="dense-kkt")
    fb = robust.solve(solver="scs", options={"max_iters": 2}, fallback=["dense-kkt", "clarabel"])
    reasons = {a["solver"]: a for a in fb.stats["attempts"]}
    assert reasons["dense-kkt"]["status"] == "not applicable" and "'fixes'" in reasons["dense-kkt"]["reason"]
    assert fb.stats["solver"] == "clarabel" and fb.stats["verified"]


def test_unknown_names_are_refused_once_the_plugins_are_gone(plugins):
    unregister_rule("balance")
    unregister_backend("dense-kkt")
    with pytest.raises(bvpnav.InputError, match="balance"):
        problem().solve(lam="balance")
    with pytest.raises(bvpnav.SolverNotFound, match="dense-kkt"):
        problem().solve(solver="dense-kkt")
