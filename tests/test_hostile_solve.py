"""Hostile matrix of the solve path (issue 14): wrong option types, extreme but legal
values, failing back ends, memory, accessors, comparisons.

Every case asserts the exact exception class, the culprit named in the message (the
value, option, item or axis), the fix hinted, and that the caller's input arrays (and,
for the command line, every input file) are byte-identical afterwards. Where the
fallback chain ran, ``exc.attempts`` must record each back end with its reason.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from _hostile import (
    EXIT_INPUT,
    assert_clean_failure,
    assert_unchanged,
    main_cli,
    raises_named,
    snapshot,
)

import bvpnav
from bvpnav import backends as S
from bvpnav.backends.cvxpy_solvers import CvxpyBackend
from bvpnav.constraints import Position, Velocity
from bvpnav.errors import InputError, SolveError, SolverNotFound
from bvpnav.problem import NavigationProblem
from bvpnav.solve import chain as _chain
from bvpnav.solve import lambda_curve, solve_sequential

N = 101


class Inputs:
    """The caller's arrays (time, acceleration, fix positions), with copies to compare."""

    def __init__(self, epoch: float = 0.0):
        self.t = epoch + np.linspace(0.0, 10.0, N)
        self.acc = np.sin(self.t - epoch)
        self.fix_t = np.array([self.t[0], self.t[-1]])
        self.fix_v = np.array([0.0, 1.0])
        self._copies = [a.copy() for a in self.arrays]

    @property
    def arrays(self):
        return [self.t, self.acc, self.fix_t, self.fix_v]

    def problem(self, sigma=0.1, sigma_a=None, acc=None, error_model=None) -> NavigationProblem:
        data = bvpnav.ImuData(t=self.t, acc=self.acc if acc is None else acc)
        prob = NavigationProblem(data, sigma_a=sigma_a, error_model=error_model)
        prob.add(Position(t=self.fix_t, value=self.fix_v, name="ends"),
                 Position(t=self.t[50], value=0.3, sigma=sigma, name="fix"))
        return prob

    def assert_unchanged(self):
        for a, b in zip(self.arrays, self._copies, strict=True):
            assert a.tobytes() == b.tobytes() and a.dtype == b.dtype and a.shape == b.shape


@pytest.fixture
def inp():
    x = Inputs()
    yield x
    x.assert_unchanged()


def test_the_callers_arrays_stay_writeable():
    """ImuData and TimeGrid copy the caller's arrays (bvpnav.timebase): they stay writeable."""
    x = Inputs()
    x.problem()
    assert x.t.flags.writeable and x.acc.flags.writeable


# ------------------------------------------------------------------ option types
# (call on a problem, class, culprit, fix)
OPTION_CASES = [
    pytest.param(lambda p: p.solve(fallback=5), InputError, r"fallback=5 \(int\)",
                 r"list of solver names or \(name, options\) pairs", id="fallback-int"),
    pytest.param(lambda p: p.solve(fallback=["direct", 7]), InputError, r"fallback entry 1 = 7",
                 r"\(name, options\) pairs", id="fallback-entry-int"),
    pytest.param(lambda p: p.solve(fallback=[("scs", "fast")]), InputError,
                 r"fallback entry 0 = \('scs', 'fast'\)", r"\(name, options\) pairs",
                 id="fallback-entry-options-str"),
    pytest.param(lambda p: p.solve(fallback="always"), InputError, r"fallback='always'",
                 r"use 'auto', None", id="fallback-word"),
    pytest.param(lambda p: p.solve(fallback=["gurobix"]), SolverNotFound, r"'gurobix'",
                 r"available: .*clarabel", id="fallback-unknown-solver"),
    pytest.param(lambda p: p.solve(accuracy="ultra"), InputError, r"accuracy='ultra'",
                 r"choose one of \['low', 'default', 'high'\]", id="accuracy-word"),
    pytest.param(lambda p: p.solve(accuracy=3), InputError, r"accuracy=3",
                 r"choose one of \['low', 'default', 'high'\]", id="accuracy-int"),
    pytest.param(lambda p: p.solve(lam=-1), InputError, r"lam=-1\.0", r"finite number >= 0",
                 id="lam-negative"),
    pytest.param(lambda p: p.solve(lam="nonsense"), InputError, r"lam='nonsense'",
                 r"choose one of \['lcurve', 'gcv', 'discrepancy', 'quasi'\]", id="lam-word"),
    pytest.param(lambda p: p.solve(lam=[1.0, 2.0]), InputError, r"lam=\[1\.0, 2\.0\] \(list\)",
                 r"finite number >= 0", id="lam-list"),
    pytest.param(lambda p: p.solve(lam=True), InputError, r"lam=True \(bool\)",
                 r"finite number >= 0", id="lam-bool"),
    pytest.param(lambda p: p.solve(lam=float("nan")), InputError, r"lam=nan",
                 r"finite number >= 0", id="lam-nan"),
    pytest.param(lambda p: p.solve(options={"typo": 1}), InputError,
                 r"solver 'clarabel' has no option 'typo'", r"valid options: \[.*'max_iter'",
                 id="clarabel-option-typo"),
    pytest.param(lambda p: p.solve(options={"max_iters": 5}), InputError,
                 r"no option 'max_iters'", r"did you mean 'max_iter'\?", id="clarabel-option-near"),
    pytest.param(lambda p: p.solve(options="fast"), InputError, r"options='fast'",
                 r"give a dict of solver options", id="options-str"),
    pytest.param(lambda p: p.solve(solver="direct", options={"method": "qrr"}), InputError,
                 r"'direct' option method='qrr'", r"one of \['auto', 'banded', 'lu', 'ldl'\]",
                 id="direct-method-typo"),
    pytest.param(lambda p: p.solve(solver="direct", options={"refine": -1}), InputError,
                 r"'direct' option refine=-1", r"an integer from 0 to 100", id="direct-refine"),
    pytest.param(lambda p: p.solve(solver="direct", options={"pivot": True}), InputError,
                 r"'direct' has no option 'pivot'", r"valid options: \['ipm_max_iter', 'ipm_tol', "
                 r"'ldl_accept', 'method', 'qp', 'refine', 'refine_tol'\]", id="direct-unknown-option"),
    pytest.param(lambda p: p.solve(solver="direct", options={"refine_tol": 1.0}), InputError,
                 r"'direct' option refine_tol=1\.0", r"between 0 and 1", id="direct-refine-tol"),
    pytest.param(lambda p: p.solve(solver="csne", options={"tol": 0.0}), InputError,
                 r"'csne' option tol=0\.0", r"between 0 and 1", id="csne-tol"),
    pytest.param(lambda p: p.solve(verify="yes"), InputError, r"verify='yes'",
                 r"True or False", id="verify-str"),
    pytest.param(lambda p: p.solve(solver=3), SolverNotFound, r"got 3",
                 r"must be a name \(str\)", id="solver-int"),
    pytest.param(lambda p: p.solve(solver=None), SolverNotFound, r"got None",
                 r"must be a name \(str\)", id="solver-none"),
    # the rule path checks every option before its sweep
    pytest.param(lambda p: p.solve(lam="gcv", fallback=5), InputError, r"fallback=5",
                 r"list of solver names", id="rule-fallback-int"),
    pytest.param(lambda p: p.solve(lam="lcurve", options={"typo": 1}), InputError,
                 r"no option 'typo'", r"valid options", id="rule-options-typo"),
    pytest.param(lambda p: solve_sequential(p, tol="tight"), InputError, r"tol='tight'",
                 r"positive distance in m", id="sequential-tol-str"),
    pytest.param(lambda p: solve_sequential(p, max_iter=2.5), InputError, r"max_iter=2\.5",
                 r"an integer of at least one", id="sequential-max-iter-float"),
    pytest.param(lambda p: p.solve(on_conflict="demote", accuracy="ultra"), InputError,
                 r"accuracy='ultra'", r"choose one of", id="demote-accuracy"),
]


def test_a_bad_solver_name_is_an_input_error(inp):
    """Found by the independent hostile review: ``except InputError`` missed SolverNotFound."""
    prob = inp.problem()
    for bad in (None, "no-such-solver"):
        exc = raises_named(InputError, lambda b=bad: prob.solve(solver=b), repr(bad), r"available|a name")
        assert isinstance(exc, SolverNotFound)


@pytest.mark.parametrize("call, cls, culprit, fix", OPTION_CASES)
def test_wrong_options_are_named_before_any_work(inp, monkeypatch, call, cls, culprit, fix):
    prob = inp.problem()

    def no_solve(*a, **k):  # "before work": no back end may run
        raise AssertionError("a back end ran before the options were checked")

    monkeypatch.setattr(_chain, "attempt", no_solve)
    monkeypatch.setattr(bvpnav.lam.sweep.DirectSweep, "point", no_solve)
    exc = raises_named(cls, lambda: call(prob), culprit, fix)
    assert type(exc) is cls


def test_unknown_options_of_an_unlisted_solver_are_a_recorded_attempt(inp):
    """SCS's option names are not listed by bvpnav: SCS itself refuses the unknown one,
    and that is a failed attempt with its reason (then the next back end)."""
    sol = inp.problem().solve(solver="scs", options={"max_iterz": 5}, fallback=["direct"])
    att = sol.stats["attempts"]
    assert [a["solver"] for a in att] == ["scs", "direct"]
    assert att[0]["status"] in ("error", "solver_error") and "max_iterz" in att[0]["reason"]
    assert att[1]["reason"] == "verified" and sol.stats["verified"]


# ------------------------------------------------------------- numerical extremes
EXTREME_CASES = [
    pytest.param(lambda x: x.problem(sigma=1e-300).solve(), r"fix: sigma = 1e-300 m",
                 r"Give sigma between 1e-15 and 1e\+15 m", id="sigma-1e-300"),
    pytest.param(lambda x: x.problem(sigma=1e300).solve(), r"fix: sigma = 1e\+300 m",
                 r"Give sigma between", id="sigma-1e300"),
    pytest.param(lambda x: x.problem().solve(lam=1e300), r"lam=1e\+300",
                 r"make them hard \(sigma=None\).*lam=0", id="lam-1e300"),
    pytest.param(lambda x: x.problem().solve(lam=1e-300), r"lam=1e-300",
                 r"outside 1e-12\.\.1e\+12 \(or 0\)", id="lam-1e-300"),
    pytest.param(lambda x: x.problem().solve(solver="direct", lam=1e300), r"lam=1e\+300",
                 r"make them hard", id="lam-1e300-direct"),
    pytest.param(lambda x: x.problem(sigma=1e-10).solve(lam=1e12), r"fix: sigma = 1e-10 m .*lam=1e\+12",
                 r"Give sigma between", id="sigma-and-lam-together"),
    pytest.param(lambda x: x.problem(sigma_a=1e-300), r"sigma_a = 1e-300 m/s\^2 \(axis x\)",
                 r"accelerometer noise in m/s\^2", id="sigma-a-1e-300"),
    pytest.param(lambda x: x.problem(sigma_a=1e300), r"sigma_a = 1e\+300 m/s\^2",
                 r"outside 1e-12\.\.1e\+12 m/s\^2", id="sigma-a-1e300"),
    pytest.param(lambda x: x.problem(acc=np.full(N, 1e200)), r"acceleration at sample 0 \(t=0 s\), "
                 r"axis x, is 1e\+200 m/s\^2", r"Check the unit", id="acc-1e200"),
    pytest.param(lambda x: x.problem(acc=np.where(np.arange(N) == 7, -3e12, 0.5)),
                 r"sample 7 \(t=0\.7 s\).*-3e\+12.*1 sample\(s\)", r"remove the corrupt samples",
                 id="acc-one-spike"),
    pytest.param(lambda x: lambda_curve(x.problem(), lam_range=(1e-300, 1e300)),
                 r"lam_range=\(1e-300, 1e\+300\)", r"sweep inside it", id="lcurve-range-1e300"),
    pytest.param(lambda x: lambda_curve(x.problem(), lam_range=(1e300, 1e301)),
                 r"lam_range=\(1e\+300, 1e\+301\)", r"sweep inside it", id="lcurve-range-high"),
    pytest.param(lambda x: lambda_curve(x.problem(sigma=1e-13), lam_range=(1e-6, 1e6)),
                 r"fix: sigma = 1e-13 m .*lam=1e\+06", r"Give sigma between",
                 id="lcurve-sweep-end-overflows"),
    pytest.param(lambda x: lambda_curve(x.problem(), points=10**6), r"points=1000000",
                 r"at most 1000", id="lcurve-points"),
    pytest.param(lambda x: lambda_curve(x.problem(), lam_range="wide"), r"lam_range='wide'",
                 r"two numbers \(low, high\)", id="lcurve-range-str"),
]


@pytest.mark.parametrize("call, culprit, fix", EXTREME_CASES)
def test_extremes_double_precision_cannot_resolve_are_refused(inp, call, culprit, fix):
    exc = raises_named(InputError, lambda: call(inp), culprit, fix)
    assert type(exc) is InputError


@pytest.mark.parametrize("make, lam", [
    pytest.param(lambda x: x.problem(acc=np.full(N, 1e-200)), 1.0, id="acc-1e-200"),
    pytest.param(lambda x: x.problem(), 1e12, id="lam-at-upper-bound"),
    pytest.param(lambda x: x.problem(), 1e-12, id="lam-at-lower-bound"),
    pytest.param(lambda x: x.problem(), 0.0, id="lam-zero"),
])
def test_legal_extremes_inside_the_ranges_verify(inp, make, lam):
    for solver in ("clarabel", "direct"):
        sol = make(inp).solve(solver=solver, lam=lam)
        assert sol.stats["verified"] and np.all(np.isfinite(sol.x))


def test_times_in_a_1e9_s_epoch_solve_like_times_from_zero():
    a, b = Inputs(), Inputs(epoch=1e9)
    for solver in ("clarabel", "direct"):
        sa, sb = a.problem().solve(solver=solver), b.problem().solve(solver=solver)
        assert sb.stats["verified"]
        # the epoch's rounding of the steps (ulp(1e9) = 1.2e-7 s on 0.1 s) moves the answer
        # by ~1e-6 relative at most; a misread time grid would be off by O(1)
        assert np.max(np.abs(sa.position() - sb.position())) < 1e-4
    a.assert_unchanged()
    b.assert_unchanged()


# -------------------------------------------------- failing back ends in the chain
def _raise(exc):
    def run(*args, **kwargs):
        raise exc
    return run


def _patch_backend(monkeypatch, name, exc):
    """Make back end ``name`` raise ``exc`` from inside its run."""
    if name in ("direct", "csne"):
        monkeypatch.setattr(S._BACKENDS[name], "run", _raise(exc))
    else:
        orig = CvxpyBackend.run

        def run(self, *a, **k):
            if self.name == name:
                raise exc
            return orig(self, *a, **k)
        monkeypatch.setattr(CvxpyBackend, "run", run)


CHAIN_CASES = [
    # (patched back ends -> exception, solve kwargs, expected attempts [(solver, reason regex)])
    pytest.param({"direct": np.linalg.LinAlgError("Singular matrix")},
                 dict(solver="direct", fallback=None),
                 [("direct", r"LinAlgError: Singular matrix")], id="direct-linalg-no-fallback"),
    pytest.param({"scs": ValueError("ScsWork allocation error!")},
                 dict(solver="scs", fallback=None),
                 [("scs", r"ValueError: ScsWork allocation error!")], id="scs-valueerror-no-fallback"),
    pytest.param({"clarabel": MemoryError("cannot allocate"), "direct": np.linalg.LinAlgError("x"),
                  "scs": ValueError("ScsWork allocation error!")},
                 dict(),
                 [("clarabel", r"MemoryError: cannot allocate"), ("clarabel", r"MemoryError"),
                  ("direct", r"LinAlgError"), ("scs", r"ValueError: ScsWork")],
                 id="auto-chain-every-link-raises"),
    pytest.param({"csne": ArithmeticError("overflow"), "osqp": TypeError("bad setting")},
                 dict(solver="csne", fallback=["osqp"]),
                 [("csne", r"ArithmeticError: overflow"), ("osqp", r"TypeError: bad setting")],
                 id="csne-then-osqp-raise"),
]


@pytest.mark.parametrize("broken, kw, expected", CHAIN_CASES)
def test_back_end_exceptions_are_recorded_attempts_then_a_solve_error(inp, monkeypatch, broken, kw,
                                                                      expected):
    for name, exc in broken.items():
        _patch_backend(monkeypatch, name, exc)
    prob = inp.problem()
    err = raises_named(SolveError, lambda: prob.solve(**kw), expected[-1][0] + r".*failed",
                       re.escape(type(broken[expected[-1][0]]).__name__))
    assert type(err) is SolveError
    assert [a["solver"] for a in err.attempts] == [s for s, _ in expected]
    for a, (_, reason) in zip(err.attempts, expected, strict=True):
        assert a["status"] == "error" and re.search(reason, a["reason"]), a
    if len(expected) > 1:
        assert str(err).startswith("every attempt failed")
        for s, _ in expected:
            assert f"{s}: error" in str(err)


def test_a_raising_primary_falls_back_to_a_verified_answer(inp, monkeypatch):
    _patch_backend(monkeypatch, "direct", np.linalg.LinAlgError("Singular matrix"))
    sol = inp.problem().solve(solver="direct", fallback=["clarabel"])
    att = sol.stats["attempts"]
    assert [(a["solver"], a["status"]) for a in att] == [("direct", "error"), ("clarabel", "optimal")]
    assert "LinAlgError: Singular matrix" in att[0]["reason"] and att[1]["reason"] == "verified"
    assert any("direct failed (LinAlgError" in w for w in sol.warnings)


# --------------------------------------------------------------------- memory
GB = 10**9


def test_memory_estimate_refuses_before_work_and_names_what_fits(inp, monkeypatch):
    prob = inp.problem()
    need = S.memory_estimate(S.resolve_solver("clarabel"), prob)
    assert need == pytest.approx(N * 4815.0)  # measured bytes per sample (CVXPY_MEMORY)
    # room for direct (1,300 B per sample) but not for Clarabel (4,815 B)
    monkeypatch.setattr(S, "available_memory", lambda: int(N * 4000 / S.MEMORY_SHARE))
    monkeypatch.setattr(_chain, "attempt", _raise(AssertionError("solved anyway")))
    exc = raises_named(InputError, prob.solve,
                       r"solver 'clarabel' needs about 0\.000486 GB for N = 101 samples x 1 axes",
                       r"limit 0\.000404 GB", r"solver='direct' \(about", r"at most 83 samples")
    assert type(exc) is InputError


@pytest.mark.slow
def test_memory_refusal_on_ten_million_samples_without_allocating(monkeypatch):
    """The estimate needs N only: a 10-million-sample problem is refused in a moment."""
    t = np.arange(10_000_000, dtype=float) * 1e-3
    t_copy = t.copy()
    data = bvpnav.ImuData(t=t, acc=np.zeros_like(t))
    prob = NavigationProblem(data, items=[Position(t=[0.0, t[-1]], value=0.0, name="ends"),
                                          Velocity(t=0.0, value=0.0, name="v0")])
    monkeypatch.setattr(S, "available_memory", lambda: 32 * GB)
    monkeypatch.setattr(bvpnav.formulation.Formulation, "check_observability",
                        _raise(AssertionError("work before the memory check")))
    raises_named(InputError, prob.solve, r"N = 10000000 samples", r"about 48\.1 GB",
                 r"limit 28\.8 GB", r"solver='direct' \(about 13 GB\)",
                 r"shorter window of at most 5981308 samples \(about 5981 s\)")
    monkeypatch.setattr(S, "available_memory", lambda: 12 * GB)
    exc = raises_named(InputError, lambda: prob.solve(solver="direct"),
                       r"'direct' needs about 13 GB", r"limit 10\.8 GB",
                       r"at most 8307692 samples")
    assert "solver='csne'" not in str(exc)  # csne (27.7 GB) does not fit either
    assert t.tobytes() == t_copy.tobytes()


def test_a_fallback_that_does_not_fit_is_skipped_with_its_reason(inp, monkeypatch):
    prob = inp.problem()
    monkeypatch.setattr(S, "available_memory", lambda: int(N * 2500 / S.MEMORY_SHARE))
    _patch_backend(monkeypatch, "direct", np.linalg.LinAlgError("Singular matrix"))
    err = raises_named(SolveError, lambda: prob.solve(solver="direct", fallback=["clarabel"]),
                       r"direct: error \(LinAlgError", r"clarabel: not applicable \(solver "
                       r"'clarabel' needs about")
    assert [(a["solver"], a["status"]) for a in err.attempts] == [("direct", "error"),
                                                                  ("clarabel", "not applicable")]


def test_unknown_available_memory_skips_the_check(inp, monkeypatch):
    monkeypatch.setattr(S, "available_memory", lambda: None)
    assert inp.problem().solve().stats["verified"]


# ----------------------------------------------------------------- accessors
@pytest.fixture(scope="module")
def solved():
    x = Inputs()
    sol = x.problem().solve(solver="direct")
    return x, sol


@pytest.mark.parametrize("call, culprit, fix", [
    pytest.param(lambda s: s.position("q"), r"position\('q'\): the solution has no axis 'q'",
                 r"its axes are \['x'\]", id="position-axis"),
    pytest.param(lambda s: s.velocity("z"), r"velocity\('z'\).*no axis 'z'", r"axes are \['x'\]",
                 id="velocity-axis"),
    pytest.param(lambda s: s.position(0), r"position\(0\)", r"its axes are \['x'\]",
                 id="position-index"),
    pytest.param(lambda s: s.rms_error(np.zeros(7)), r"truth of shape \(7,\)",
                 r"true positions in m at the sample times", id="rms-error-shape"),
])
def test_solution_accessors_name_the_axes(solved, call, culprit, fix):
    x, sol = solved
    before = sol.trajectory.copy()
    exc = raises_named(InputError, lambda: call(sol), culprit, fix)
    assert type(exc) is InputError
    assert sol.trajectory.equals(before)
    x.assert_unchanged()


# ----------------------------------------------------------------- comparing
@pytest.mark.parametrize("kw, culprit, fix", [
    pytest.param(dict(presets=["ultra"]), r"unknown preset\(s\) \['ultra'\]",
                 r"choose from \['low', 'default', 'high'\]", id="compare-preset"),
    pytest.param(dict(presets="default"), r"presets='default'", r"list of names",
                 id="compare-presets-str"),
    pytest.param(dict(solvers=["clarabel", "gurobix", "cplexx"]),
                 r"solver\(s\) \['gurobix', 'cplexx'\]", r"available: \[.*'direct'",
                 id="compare-solvers"),
    pytest.param(dict(solvers=["direct"], options={"osqp": {"max_iter": 5}}),
                 r"solver\(s\) \['osqp'\] are not among the compared solvers \['direct'\]",
                 r"key the options by one of them", id="compare-stray-options"),
    pytest.param(dict(solvers=["direct"], options={"direct": {"method": "qrr"}}),
                 r"options\['direct'\]: solver 'direct' option method='qrr'",
                 r"'auto', 'banded', 'lu', 'ldl'",
                 id="compare-direct-options"),
    pytest.param(dict(solvers=["direct"], lam=1e300), r"lam=1e\+300", r"make them hard",
                 id="compare-lam"),
])
def test_compare_solvers_refuses_unknown_names_up_front(inp, monkeypatch, kw, culprit, fix):
    monkeypatch.setattr(_chain, "attempt", _raise(AssertionError("ran a solver")))
    exc = raises_named(InputError, lambda: bvpnav.compare_solvers(inp.problem(), **kw), culprit, fix)
    assert type(exc) is InputError


# ------------------------------------------------------------- command line
@pytest.fixture(scope="module")
def shuttle(tmp_path_factory):
    d = tmp_path_factory.mktemp("shuttle")
    from bvpnav.samples import write_sample

    write_sample("shuttle", d, rate=5.0)
    return d


@pytest.mark.parametrize("extra, culprit, fix", [
    pytest.param(["--lam", "1e300"], r"lam=1e\+300", r"make them hard", id="cli-lam-1e300"),
    pytest.param(["--lam", "1e-300"], r"lam=1e-300", r"outside 1e-12\.\.1e\+12", id="cli-lam-1e-300"),
])
def test_cli_extremes_exit_2_and_touch_nothing(shuttle, tmp_path, extra, culprit, fix):
    out = tmp_path / "out"
    out.mkdir()
    (out / "earlier.csv").write_text("t,x\n0,0\n")
    before = snapshot(shuttle, out)
    proc = main_cli(["solve", shuttle / "recording.csv", "--spec", shuttle / "spec.toml",
                     "--out", out / "traj.csv", *extra])
    assert_clean_failure(proc, EXIT_INPUT, culprit, fix)
    assert_unchanged(before)
    assert sorted(p.name for p in out.iterdir()) == ["earlier.csv"]
