"""The ``bvpnav`` logger, progress bars and warnings that are issued once, at the user's line."""

from __future__ import annotations

import io
import logging
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import bvpnav
import bvpnav.log as blog
from bvpnav.constraints import Position, TrackLine
from bvpnav.lam.sweep import SLOPE_POINTS
from bvpnav.scenarios import tikhonov2011
from bvpnav.solve import lambda_curve

T = np.linspace(0.0, 10.0, 101)
ACC = np.sin(T) + np.random.default_rng(7).normal(0.0, 0.05, T.size)  # m/s^2


def ls_problem():
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=ACC), items=[
        Position(t=[0.0, 10.0], value=[0.0, 1.0], name="ends"),
        Position(t=[3.0, 5.0, 7.0], value=[0.3, 0.5, 0.7], sigma=0.1, name="fixes")])


def track_problem():
    """A straight rail along x in 2-D: the sequential loop (soft track)."""
    acc = np.column_stack([np.zeros_like(T), np.random.default_rng(3).normal(0.0, 0.05, T.size)])
    return bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=acc, axes=("x", "y")), items=[
        Position(t=[0.0, 10.0], value=[[0.0, 0.0], [10.0, 0.0]], name="ends"),
        Position(t=[2.0, 8.0], value=[[2.0, 0.0], [8.0, 0.0]], sigma=0.5, name="fixes"),
        TrackLine(x=[-1.0, 11.0], y=[0.0, 0.0], axes=("x", "y"), sigma=0.05, name="rail")])


def table1_load(seed=0):
    """The 2011 paper's Example 1 in the load form (the README's `bvpnav lcurve` example)."""
    sc = tikhonov2011(seed=seed)
    tp = np.concatenate([sc.t[1:11], sc.t[-11:-1]])
    return bvpnav.NavigationProblem(sc.data, residual="load").add(
        Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends"),
        Position(t=tp, value=sc.prior(tp), sigma=1.0, name="cubic prior"))


def messages(caplog, name, level=logging.INFO):
    return [r.getMessage() for r in caplog.records if r.name == name and r.levelno == level]


@pytest.fixture
def restore_logging():
    """Undo :func:`bvpnav.log.configure` (handler, level, progress switch)."""
    handlers, level = list(blog.logger.handlers), blog.logger.level
    yield
    blog.logger.handlers[:] = handlers
    blog.logger.setLevel(level)
    blog._PROGRESS_OFF = False


# ----------------------------------------------------------------- the logger
def test_the_package_logger_has_only_a_null_handler_and_modules_log_below_it():
    assert [type(h) for h in logging.getLogger("bvpnav").handlers] == [logging.NullHandler]
    import bvpnav.lam.sweep as sweep
    import bvpnav.solve.chain as chain
    import bvpnav.solve.sequential as seq

    assert {m.log.name for m in (chain, sweep, seq)} == {"bvpnav.solve.chain", "bvpnav.lam.sweep",
                                                          "bvpnav.solve.sequential"}
    assert all(m.log.parent is blog.logger or m.log.parent.name.startswith("bvpnav")
               for m in (chain, sweep, seq))


def test_nothing_is_printed_without_configuration():
    """A fresh interpreter: a solve that falls back and a rule print nothing at all."""
    code = textwrap.dedent("""
        import numpy as np, bvpnav
        from bvpnav.constraints import Position
        t = np.linspace(0.0, 10.0, 101)
        prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.sin(t)), items=[
            Position(t=[0.0, 10.0], value=[0.0, 1.0]), Position(t=5.0, value=0.3, sigma=0.1)])
        sol = prob.solve(solver="osqp", options={"max_iter": 1}, fallback=["direct"])
        assert sol.stats["solver"] == "direct", sol.stats["solver"]
        from bvpnav.scenarios import tikhonov2011
        sc = tikhonov2011(seed=0)
        tp = np.concatenate([sc.t[1:11], sc.t[-11:-1]])
        bvpnav.NavigationProblem(sc.data, residual="load").add(
            Position(t=[0.0, 10.0], value=[0.0, 10.0]),
            Position(t=tp, value=sc.prior(tp), sigma=1.0)).solve(lam="lcurve", solver="direct")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout == "" and out.stderr == ""


def test_a_fallback_attempt_and_the_answering_back_end_are_logged_at_info(caplog):
    caplog.set_level(logging.DEBUG, logger="bvpnav")
    sol = ls_problem().solve(solver="osqp", options={"max_iter": 1}, fallback=["direct"])
    assert sol.stats["solver"] == "direct"
    info = messages(caplog, "bvpnav.solve.chain")
    assert any(m.startswith("osqp at attempt 1: failed (") and "trying direct" in m for m in info), info
    assert any(m.startswith("direct answered at lam=1 (attempt 2,") and "wall_time" in m for m in info), info
    debug = messages(caplog, "bvpnav.solve.chain", logging.DEBUG)
    assert any("options in force" in m and "'max_iter': 1" in m for m in debug), debug
    assert any("verification {" in m and "forward_error" in m for m in debug), debug


def test_a_rule_choosing_lambda_is_logged_with_engine_evaluations_and_seconds(caplog):
    caplog.set_level(logging.INFO, logger="bvpnav")
    sol = table1_load().solve(lam="lcurve", solver="direct")
    (sweep,) = messages(caplog, "bvpnav.lam.sweep")
    assert sweep.startswith(f"lambda sweep: engine direct, {SLOPE_POINTS} points over "
                            "lam_range=(1e-06, 1e+06), ")
    assert f"lcurve lam={sol.lam:.6g} (used)" in sweep and " evaluations, " in sweep
    (rule,) = messages(caplog, "bvpnav.solve.rule")
    assert rule.startswith(f"rule lcurve chose lam={sol.lam:.6g} (engine direct, ")
    # the sweep's own solves are not INFO records (only the final solve's back end is)
    assert len([m for m in messages(caplog, "bvpnav.solve.chain") if "answered" in m]) == 1


def test_a_skipped_rule_says_why_at_info(caplog):
    caplog.set_level(logging.INFO, logger="bvpnav")
    curve = lambda_curve(table1_load(), rules=("lcurve", "discrepancy"), points=9)
    assert "discrepancy" not in curve.chosen
    assert any("rule discrepancy skipped: it needs residual='acceleration' with sigma_a" in m
               for m in messages(caplog, "bvpnav.lam.sweep"))


def test_sequential_iterations_are_logged(caplog):
    caplog.set_level(logging.INFO, logger="bvpnav")
    sol = track_problem().solve(solver="direct")
    rep = sol.stats["sequential"]
    its = [m for m in messages(caplog, "bvpnav.solve.sequential") if m.startswith("sequential iteration")]
    assert len(its) == rep["iterations"] >= 2
    assert f"max change {rep['max_change'][-1]:.3g} m" in its[-1] and "(final phase" in its[-1]
    assert any(m.startswith("sequential loop converged after") for m in messages(caplog,
                                                                                 "bvpnav.solve.sequential"))


# ------------------------------------------------------------------ configure
@pytest.mark.parametrize("verbosity, level", [(-1, logging.ERROR), (0, logging.WARNING), (1, logging.INFO),
                                              (2, logging.DEBUG), (3, logging.DEBUG)])
def test_configure_maps_verbosity_to_levels_with_one_stderr_handler(restore_logging, verbosity, level):
    blog.configure(verbosity, quiet_warnings=False)
    handler = blog.configure(verbosity, quiet_warnings=False)  # twice: still one handler
    ours = [h for h in blog.logger.handlers if getattr(h, blog._HANDLER_TAG, False)]
    assert ours == [handler] and handler.stream is sys.stderr
    assert blog.logger.level == level
    assert blog.progress_enabled() is False  # not a terminal here, whatever the verbosity


def test_configure_v_prints_info_to_stderr_in_a_short_format(restore_logging, capsys):
    handler = blog.configure(1, quiet_warnings=False)
    handler.setStream(sys.stderr)  # capsys's stream
    ls_problem().solve(solver="osqp", options={"max_iter": 1}, fallback=["direct"])
    err = capsys.readouterr().err.splitlines()
    assert any(line.startswith("bvpnav: INFO: osqp at attempt 1: failed") for line in err), err
    assert not any("DEBUG" in line for line in err)


# ------------------------------------------------------------------- warnings
def _edge_curve(**kw):
    """The L-curve's corner (~3.6) lies far above this range: edge warnings."""
    return lambda_curve(table1_load(), rules=("lcurve", "quasi"), lam_range=(1e-3, 1e-1), points=9, **kw)


def test_a_warning_is_issued_once_at_the_callers_line_and_says_how_to_widen():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        curve = _edge_curve()
    assert curve.warnings
    msgs = [str(w.message) for w in caught]
    assert sorted(msgs) == sorted(curve.warnings)  # each once
    for w in caught:
        assert issubclass(w.category, bvpnav.log.BvpnavWarning) and issubclass(w.category, RuntimeWarning)
        assert w.filename == __file__, w.filename  # this file, not bvpnav's
        assert "widen lam_range=(low, high) (CLI: --lam-range)" in str(w.message)
    assert any("e.g. lam_range=(" in m for m in msgs)


def test_a_rule_warning_copied_into_solution_warnings_is_issued_once():
    prob = table1_load()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sol = prob.solve(lam="lcurve", solver="direct", rule={"lam_range": (1e-3, 1e-1), "points": 9})
    issued = [str(w.message) for w in caught]
    assert issued and len(issued) == len(set(issued))
    assert set(issued) <= set(sol.warnings) and set(sol.curve.warnings) <= set(issued)
    assert {w.filename for w in caught} == {__file__}


def test_a_rule_warning_raised_on_every_sequential_iteration_is_issued_once():
    prob = track_problem()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sol = prob.solve(solver="direct", lam="quasi", rule={"lam_range": (1e-3, 1e-2), "points": 7},
                         sequential={"lam_each": True})
    issued = [str(w.message) for w in caught]
    assert sol.stats["sequential"]["iterations"] >= 2
    assert issued and len(issued) == len(set(issued)), issued
    assert {w.filename for w in caught} == {__file__}


def test_the_not_converged_warning_points_at_the_callers_line_and_says_how():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sol = track_problem().solve(solver="direct", sequential={"max_iter": 1, "continuation": False})
    (w,) = [w for w in caught if "did not converge" in str(w.message)]
    assert w.filename == __file__ and "sequential={'max_iter': 2}" in str(w.message)
    assert str(w.message) in sol.warnings


def test_configure_keeps_python_from_showing_them_a_second_time(restore_logging):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        blog.configure(0)  # the CLI prints curve.warnings itself
        curve = _edge_curve()
    assert curve.warnings and not caught


def test_tutorial_04_does_not_warn():
    """Tutorial 04 at 15 points warned 'at the edge' for an L-curve corner at 9e3 in
    (1e-6, 1e6). (The README's `bvpnav lcurve` example: see
    test_readme_lcurve_example_does_not_warn.)"""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        readme = lambda_curve(table1_load(), rules=("lcurve", "quasi"))
        sc = tikhonov2011(rate=50.0, seed=3)
        tp = np.concatenate([sc.t[1:11], sc.t[-11:-1]])
        for residual, sigma_a, rules in (("load", None, ("lcurve", "quasi")),
                                         ("acceleration", 1.0, ("lcurve", "gcv", "discrepancy", "quasi"))):
            prob = bvpnav.NavigationProblem(sc.data, residual=residual, sigma_a=sigma_a).add(
                Position(t=[0.0, 10.0], value=[0.0, 10.0]), Position(t=tp, value=sc.prior(tp), sigma=1.0))
            curve = lambda_curve(prob, rules=rules, points=15)
            assert curve.warnings == [], curve.warnings
    assert readme.warnings == [] and set(readme.chosen) == {"lcurve", "quasi"}


def test_an_interior_maximum_at_the_last_allowed_sample_is_not_an_edge():
    from bvpnav.lam import edge_warning
    from bvpnav.lam.sweep import LambdaCurve

    lam = np.geomspace(1e-6, 1e6, 15)
    curve = LambdaCurve(lam=lam, residual_norm=lam, info_norm=lam, lam_range=(1e-6, 1e6))
    peak = -((np.arange(15) - 12.2) ** 2)  # maximum at 12.2, between samples 12 and 13
    assert not edge_warning(curve, "lcurve", 12, 2, peak, best="max")
    rising = np.arange(15.0)  # still rising at the end of the range
    assert edge_warning(curve, "lcurve", 12, 2, rising, best="max")
    assert "high edge" in curve.warnings[0] and "lam_range=(1e-06, 1e+09)" in curve.warnings[0]


# ------------------------------------------------------------------- progress
def test_progress_bars_are_off_when_stderr_is_not_a_terminal(capfd, monkeypatch):
    assert blog.progress_enabled() is False
    table1_load().solve(lam="lcurve", solver="direct")
    track_problem().solve(solver="direct")
    err = capfd.readouterr().err
    assert "lambda sweep" not in err and "sequential loop" not in err and "it/s" not in err

    class TTY(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stderr", TTY())
    assert blog.progress_enabled() is True
    assert blog.progress_enabled(False) is False
    monkeypatch.setattr(blog, "_PROGRESS_OFF", True)  # configure(-1), the CLI's -q
    assert blog.progress_enabled() is False


def test_a_bar_is_shown_on_a_terminal_for_a_sweep_of_any_size(monkeypatch):
    class TTY(io.StringIO):
        def isatty(self):
            return True

    tty = TTY()
    monkeypatch.setattr(sys, "stderr", tty)
    monkeypatch.setattr(blog, "progress", _no_delay(blog.progress))
    import bvpnav.lam.sweep as sweep

    monkeypatch.setattr(sweep, "progress_bar", blog.progress)
    lambda_curve(table1_load(), rules=("quasi",), points=9)  # 501 samples: small
    assert "lambda sweep" in tty.getvalue()


def _no_delay(fn):
    def wrapped(*a, **kw):
        kw["delay"] = 0
        return fn(*a, **kw)

    return wrapped


def test_a_cli_run_from_python_leaves_no_handler_filter_or_level_behind(tmp_path, capsys):
    """``bvpnav.cli.main([...])`` configures logging for its run only: afterwards the
    package logger has its NullHandler alone, its level, and the warning filters as before
    (a run inside a test session used to leave a stderr handler for every later test)."""
    from bvpnav.cli import main

    logger = logging.getLogger("bvpnav")
    before = (list(logger.handlers), logger.level, list(warnings.filters))
    code = main(["solve", "-vv", str(tmp_path / "missing.csv"), "--spec", str(tmp_path / "x.toml"),
                 "--out", str(tmp_path / "out.csv")])
    assert code == 2 and "bvpnav: error:" in capsys.readouterr().err
    assert (list(logger.handlers), logger.level, list(warnings.filters)) == before


def test_readme_lcurve_example_does_not_warn(tmp_path, capsys):
    """The README's `bvpnav simulate tikhonov2011` + `bvpnav lcurve` lines: the load form's
    default rules leave GCV out (its independence assumption fails on the mass-matrix
    weighted residual, and its function falls to the edge of any range there), so the
    example prints its choices and no warning; GCV stays in the acceleration form's
    defaults and runs on the load form when asked for."""
    from bvpnav.cli import default_rules, main

    assert default_rules("load") == ("lcurve", "quasi")
    assert "gcv" in default_rules("acceleration")
    rec = tmp_path / "rec"
    assert main(["simulate", "tikhonov2011", "--out", str(rec), "-q"]) == 0
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["lcurve", str(rec / "recording.csv"), "--spec", str(rec / "spec.toml"),
                     "--plot", str(tmp_path / "l.png")]) == 0
    out = capsys.readouterr()
    assert "lcurve" in out.out and "quasi" in out.out and "gcv" not in out.out
    assert "warning" not in (out.out + out.err).lower()
    assert main(["lcurve", str(rec / "recording.csv"), "--spec", str(rec / "spec.toml"), "--rules", "gcv",
                 "--plot", str(tmp_path / "g.png")]) == 0
    assert "edge" in capsys.readouterr().out   # asked for, it runs and says where it landed


# ------------------------------------------------------------------------- signals
def test_signal_handled_installs_for_the_block_and_restores_the_handler_before():
    import signal

    calls = []

    def caller(signum, frame):
        calls.append(("caller", signum))

    def inner(signum, frame):
        calls.append(("inner", signum))

    before = signal.signal(signal.SIGTERM, caller)
    try:
        with blog.signal_handled(signal.SIGTERM, inner) as installed:
            assert installed and signal.getsignal(signal.SIGTERM) is inner
            signal.raise_signal(signal.SIGTERM)
        assert signal.getsignal(signal.SIGTERM) is caller
        with pytest.raises(RuntimeError), blog.signal_handled(signal.SIGTERM, signal.SIG_IGN):
            signal.raise_signal(signal.SIGTERM)  # ignored
            raise RuntimeError("the block failed")
        assert signal.getsignal(signal.SIGTERM) is caller  # restored on the way out of a failure too
        signal.raise_signal(signal.SIGTERM)
    finally:
        signal.signal(signal.SIGTERM, before)
    assert calls == [("inner", signal.SIGTERM), ("caller", signal.SIGTERM)]


def test_signal_handled_off_the_main_thread_runs_the_block_and_changes_nothing():
    import signal
    import threading

    before, seen = signal.getsignal(signal.SIGTERM), []

    def run():
        with blog.signal_handled(signal.SIGTERM, signal.SIG_IGN) as installed:
            seen.append((installed, signal.getsignal(signal.SIGTERM)))

    worker = threading.Thread(target=run)
    worker.start()
    worker.join()
    assert seen == [(False, before)] and signal.getsignal(signal.SIGTERM) is before


def test_signal_handled_off_the_main_thread_leaves_the_blocks_errors_unchained():
    """Off the main thread :func:`signal.signal` raises ValueError; the block must not run
    inside that except clause, or every error leaving it carries the ValueError ("signal only
    works in main thread") as its ``__context__`` in tracebacks."""
    import signal
    import sys
    import threading

    seen = []

    def run():
        try:
            with blog.signal_handled(signal.SIGTERM, signal.SIG_IGN) as installed:
                seen.append((installed, sys.exc_info()[1]))
                raise RuntimeError("the block failed")
        except RuntimeError as exc:
            seen.append((exc.__context__, exc.__cause__))

    worker = threading.Thread(target=run)
    worker.start()
    worker.join()
    assert seen == [(False, None), (None, None)]
