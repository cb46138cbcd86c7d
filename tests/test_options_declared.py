"""Solve options declared once (bvpnav.declare) and time limits (issue 43 item 1, issue 40 item 3).

A new option added through the declaration alone reaches ``solve()``, the spec and the
command line, with the same text for the same bad value; ``time_limit`` stops a solver at
its own limit (SCS) or discards an answer that took longer (``direct``), as a clean
"time limit reached" attempt.
"""

from __future__ import annotations

import numpy as np
import pytest

import bvpnav
import bvpnav.solve.pipeline as pipeline
from bvpnav import ImuData, NavigationProblem
from bvpnav.cli import main
from bvpnav.compare import compare_solvers
from bvpnav.constraints import Position, Velocity
from bvpnav.declare import SOLVE_OPTIONS, Option, any_of, check_option, nothing, number
from bvpnav.samples import write_sample
from bvpnav.spec import parse_spec


def small_problem(n=201):
    t = np.linspace(0.0, 10.0, n)
    prob = NavigationProblem(ImuData(t, np.sin(t)), sigma_a=0.1)
    return prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0 - np.sin(10.0)]),
                    Velocity(t=[0.0], value=[1.0], sigma=0.1))


@pytest.fixture
def probe(monkeypatch):
    """A solve option declared in the test alone, and what the innermost stage saw of it."""
    opt = Option("probe_weight", None,
                 any_of(number(0, low_open=True), nothing(), want="a number > 0 (kg), or None"),
                 "float, optional", "A test's option.", unit="kg", cli="--probe-weight",
                 commands=("solve", "batch"), cli_help="a test's option")
    monkeypatch.setitem(SOLVE_OPTIONS, opt.name, opt)
    seen = []
    inner = pipeline.solve_fixed

    def recording(form, lam, opts, *args, **kwargs):
        seen.append(opts.probe_weight)
        return inner(form, lam, opts, *args, **kwargs)

    monkeypatch.setattr(pipeline, "solve_fixed", recording)
    return seen


def test_a_declared_option_reaches_solve_the_spec_and_the_cli(probe, tmp_path, capsys):
    # solve(): accepted, normalised, seen by the stage; absent: its default
    small_problem().solve(solver="direct", probe_weight=2)
    small_problem().solve(solver="direct")
    assert probe == [2.0, None]
    with pytest.raises(bvpnav.InputError) as api:
        small_problem().solve(solver="direct", probe_weight=-1)
    text = str(api.value)
    assert text == "probe_weight=-1: give a number > 0 (kg), or None"
    # the spec: the key is taken, a bad value gives the same text after its line
    spec = parse_spec('[solve]\nsolver = "direct"\nprobe_weight = 3.5\n', "s.toml")
    small_problem().solve(**spec.solve)
    assert probe[-1] == 3.5
    with pytest.raises(bvpnav.InputError) as sp:
        parse_spec('[solve]\nsolver = "direct"\nprobe_weight = -1\n', "s.toml")
    assert str(sp.value) == f"s.toml, line 3: {text}"
    # the command line: the flag exists, its value reaches the stage, a bad one the same text
    paths = write_sample("tikhonov2011", tmp_path / "rec")
    rec, spec_path = (str(p) for p in paths[:2])
    assert main(["solve", rec, "--spec", spec_path, "--out", str(tmp_path / "o.csv"), "--solver", "direct",
                 "--probe-weight", "0.25", "-q"]) == 0
    assert probe[-1] == 0.25
    capsys.readouterr()
    assert main(["solve", rec, "--spec", spec_path, "--out", str(tmp_path / "p.csv"),
                 "--probe-weight", "-1"]) == 2
    assert f"--probe-weight: {text}" in capsys.readouterr().err
    assert not (tmp_path / "p.csv").exists()
    # batch: an override of the declared option, checked before any work
    with pytest.raises(bvpnav.InputError, match=r"probe_weight=-1: give a number > 0 \(kg\), or None"):
        bvpnav.batch.run_batch(tmp_path / "rec", spec_path, tmp_path / "out", scheduler="serial",
                               probe_weight=-1)
    assert not (tmp_path / "out").exists()


def test_an_unknown_option_is_named_with_the_declared_ones():
    with pytest.raises(bvpnav.InputError, match=r"unknown option\(s\) \['time_limt'\] \(did you mean "
                                                r"'time_limit'\?\); valid: \[.*'time_limit'"):
        small_problem().solve(solver="direct", time_limt=3)


def test_the_same_bad_time_limit_gives_the_same_text_everywhere(tmp_path, capsys):
    text = "time_limit=-1: give a number of seconds > 0, or None for no limit"
    with pytest.raises(bvpnav.InputError) as api:
        small_problem().solve(solver="direct", time_limit=-1)
    assert str(api.value) == text
    with pytest.raises(bvpnav.InputError) as sp:
        parse_spec("[solve]\ntime_limit = -1\n", "s.toml")
    assert str(sp.value) == f"s.toml, line 2: {text}"
    paths = write_sample("tikhonov2011", tmp_path / "rec")
    for command in (["solve", "--out", str(tmp_path / "o.csv")], ["compare"]):
        assert main([command[0], str(paths[0]), "--spec", str(paths[1]), *command[1:],
                     "--time-limit", "-1"]) == 2
        assert f"--time-limit: {text}" in capsys.readouterr().err


def test_the_spec_and_solve_share_one_lam_range():
    """The spec took any lam >= 0 while solve() refused 1e13: one declared range now."""
    for bad in (1e13, 1e-13):
        with pytest.raises(bvpnav.InputError) as api:
            check_option("lam", bad)
        with pytest.raises(bvpnav.InputError) as sp:
            parse_spec(f"[solve]\nlam = {bad!r}\n", "s.toml")
        assert str(sp.value) == f"s.toml, line 2: {api.value}"
        assert "outside 1e-12..1e+12 (or 0)" in str(api.value)
    for good in (0, 1e-12, 1e12):
        assert parse_spec(f"[solve]\nlam = {good!r}\n", "s.toml").solve["lam"] == good


def test_the_declaration_makes_the_signature_and_the_docs():
    import inspect

    sig = inspect.signature(NavigationProblem.solve)
    assert list(sig.parameters)[1:] == list(SOLVE_OPTIONS)
    assert all(sig.parameters[n].default == o.default for n, o in SOLVE_OPTIONS.items())
    doc = NavigationProblem.solve.__doc__
    assert all(f"        {n} : {o.type}\n" in doc for n, o in SOLVE_OPTIONS.items())


# ------------------------------------------------------------------ time limits
def slow_problem():
    """5,000 samples: SCS at its default preset (eps 1e-8) needs far more than 0.05 s."""
    return small_problem(5000)


def test_scs_stops_at_its_time_limit_as_a_clean_attempt(capfd):
    prob = slow_problem()
    with pytest.raises(bvpnav.SolveError) as exc:
        prob.solve(solver="scs", time_limit=0.05, fallback=None)
    (att,) = exc.value.attempts
    assert att["solver"] == "scs" and att["status"] == "time limit"
    assert att["reason"] == "time limit reached (0.05 s)"
    # the chain moves on; the answer comes from the next back end, the stop recorded (SCS's own
    # option given directly: it is the limit then, and direct runs without one whatever the load)
    sol = prob.solve(solver="scs", options={"time_limit_secs": 0.05}, fallback=["direct"])
    assert sol.stats["solver"] == "direct" and sol.stats["verified"]
    assert [(a["solver"], a["status"]) for a in sol.stats["attempts"]] == [("scs", "time limit"),
                                                                           ("direct", "optimal")]
    out, err = capfd.readouterr()
    assert "ERROR" not in out + err  # the solver's own printing is captured, not passed through


def test_the_solver_option_in_force_is_the_solvers_own():
    """time_limit maps to each cvxpy solver's own option; the user's own option wins."""
    prob = small_problem()
    for name, key in (("clarabel", "time_limit"), ("osqp", "time_limit"), ("scs", "time_limit_secs")):
        sol = prob.solve(solver=name, time_limit=30.0, fallback=None, verify=False)
        assert sol.stats["options"][key] == 30.0
    sol = prob.solve(solver="scs", time_limit=30.0, options={"time_limit_secs": 40.0}, fallback=None,
                     verify=False)
    assert sol.stats["options"]["time_limit_secs"] == 40.0


def test_direct_has_no_limit_of_its_own_so_a_late_answer_is_discarded():
    prob = small_problem()
    with pytest.raises(bvpnav.SolveError, match=r"direct: time limit reached \(1e-09 s\): it took .* s and "
                                                r"has no time limit of its own, so its answer was discarded"):
        prob.solve(solver="direct", time_limit=1e-9, fallback=None)
    assert prob.solve(solver="direct", time_limit=None).stats["verified"]


def test_compare_shows_each_solvers_outcome_under_a_time_limit():
    table = compare_solvers(slow_problem(), solvers=["scs", "direct"], time_limit=0.05)
    assert list(table.solver) == ["scs", "direct"]
    scs = table.iloc[0]
    assert scs.status == "time limit" and not scs.verified
    assert "time limit reached (0.05 s)" in scs.error
    assert isinstance(table.iloc[1].status, str) and table.iloc[1].status


def test_compare_help_states_the_default_time_limit(capsys):
    with pytest.raises(SystemExit):
        main(["compare", "--help"])
    assert "default 60 s per solver run" in " ".join(capsys.readouterr().out.split())


def test_what_a_solver_prints_is_captured_and_kept(capfd):
    """C code prints to file descriptors 1 and 2 (SCS's "ERROR: could not determine problem
    status."): captured and handed back, nothing reaches the terminal; verbose passes it through."""
    import os

    from bvpnav.backends.cvxpy_solvers import captured_output

    with captured_output() as said:
        os.write(1, b"ERROR: could not determine problem status.\n")
        os.write(2, b"solver warning\n")
    assert said == ["ERROR: could not determine problem status.\nsolver warning"]
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    with captured_output(enabled=False) as said:
        os.write(1, b"shown\n")
    assert said == [] and capfd.readouterr().out == "shown\n"


def test_the_constants_the_declaration_writes_out_agree_with_their_sources():
    """bvpnav.declare spells out the presets and the lam range (so that the command line's
    parser needs neither numpy nor the formulation): they must be the real ones."""
    import bvpnav.declare as declare
    from bvpnav.backends import ACCURACIES
    from bvpnav.formulation import LAM_RANGE

    assert declare.ACCURACIES == ACCURACIES
    assert declare._LAMS == f"{LAM_RANGE[0]:g}..{LAM_RANGE[1]:g}".replace("e+", "e")
