"""The sequential convex loop (bvpnav.solve.sequential) on TrackLine: convergence from a poor
start, hard/band/robust modes, conflicts and demotion, dispatch from solve()."""

from __future__ import annotations

import numpy as np
import pytest

import bvpnav
from bvpnav.constraints import Position, TrackLine
from bvpnav.constraints.track_line import project_onto_polyline
from bvpnav.simulate import Motion, sample_times
from bvpnav.solve import solve_sequential


# ------------------------------------------------------------ the loop
def planar_track(T: float = 20.0, rate: float = 50.0):
    """A noise-free planar motion that moves forward along a wavy path, at rest at both ends."""
    tw = np.arange(0.0, T + 1.0, 1.0)
    u = tw / T
    s = 3 * u**2 - 2 * u**3
    motion = Motion.from_waypoints(tw, np.column_stack([60 * s, 8 * np.sin(np.pi * s) ** 2
                                                        + 3 * np.sin(3 * np.pi * s)]))
    t = sample_times(0.0, T, rate)
    truth = motion.pos(t)
    path = motion.pos(np.linspace(0.0, T, 1001))
    data = bvpnav.ImuData(t, acc=motion.acc(t), axes=("x", "z"))
    return t, truth, path, data


@pytest.mark.parametrize("solver", ["direct", "clarabel"])
def test_loop_recovers_a_noise_free_track_from_a_poor_start(solver):
    t, truth, path, data = planar_track()
    track = TrackLine(x=path[:, 0], y=path[:, 1], axes=("x", "z"), sigma=0.01)
    prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 20.0], value=[truth[0], truth[-1]]), track)
    # start 2 m (x) and 1.5 m (z) off the truth
    start = truth + np.column_stack([2 * np.sin(np.pi * t / 20), 1.5 * np.sin(2 * np.pi * t / 20)])
    sol = solve_sequential(prob, solver=solver, initial=start, tol=1e-4)
    rep = sol.stats["sequential"]
    assert rep["converged"] and rep["max_change"][-1] < 1e-4
    assert rep["iterations"] <= 5  # measured: 4 (changes 1.40, 0.572, 0.032, <1e-9 m)
    assert rep["max_change"][0] > 1.0  # it really started far away
    assert sol.rms_error(truth) < 1e-6  # measured 7.7e-12 m (direct)
    assert sol.stats["verified"]


def test_loop_checks_observability_again_only_when_the_rows_change(monkeypatch):
    """Each iteration's formulation has the same items and error model, linearized elsewhere:
    what determines the unknowns (an SVD, as long as a solve) is checked again only when an item
    keeps other rows at the new point (TrackLine drops the samples that do not project onto the
    track: 49, 9, then 0 of them here); a linearization with the checked rows is not checked."""
    import bvpnav.solve.sequential as seq
    from bvpnav.formulation import Formulation

    calls, kept = [], []
    real, real_form = Formulation.unobservable, seq._Loop.linearized_form

    def counted(self):
        calls.append(1)
        return real(self)

    def noted(self, *args, **kwargs):
        out = real_form(self, *args, **kwargs)
        kept.append(self.kept)
        return out

    monkeypatch.setattr(Formulation, "unobservable", counted)
    monkeypatch.setattr(seq._Loop, "linearized_form", noted)
    t, truth, path, data = planar_track()
    track = TrackLine(x=path[:, 0], y=path[:, 1], axes=("x", "z"), sigma=0.01)
    prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 20.0], value=[truth[0], truth[-1]]), track)
    start = truth + np.column_stack([2 * np.sin(np.pi * t / 20), 1.5 * np.sin(2 * np.pi * t / 20)])
    sol = solve_sequential(prob, solver="direct", initial=start, tol=1e-4)
    solved = kept[:sol.stats["sequential"]["iterations"]]      # the last linearization only tests the change
    changes = 1 + sum(a != b for a, b in zip(solved[:-1], solved[1:], strict=True))
    assert [k["TrackLine"]["out_of_range"] for k in solved[:3]] == [49, 9, 0]
    assert len(calls) == changes < len(solved)
    assert sol.rms_error(truth) < 1e-6


HARD_LIKE = [({"mode": "hard"}, "direct"), ({"mode": "hard"}, "clarabel"),
             ({"mode": "band", "tol": 0.05}, "clarabel"),
             ({"mode": "robust", "sigma": 0.01, "huber": 0.02}, "clarabel")]


@pytest.mark.parametrize(("kw", "solver"), HARD_LIKE, ids=["hard-direct", "hard-clarabel", "band-clarabel",
                                                          "robust-clarabel"])
def test_hard_band_and_robust_tracks_converge_from_the_same_poor_start(kw, solver):
    t, truth, path, data = planar_track()
    track = TrackLine(x=path[:, 0], y=path[:, 1], axes=("x", "z"), name="rail", **kw)
    prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 20.0], value=[truth[0], truth[-1]]), track)
    start = truth + np.column_stack([2 * np.sin(np.pi * t / 20), 1.5 * np.sin(2 * np.pi * t / 20)])
    sol = solve_sequential(prob, solver=solver, initial=start, tol=1e-4)
    rep = sol.stats["sequential"]
    assert rep["converged"] and sol.stats["verified"]
    assert rep["max_change"][0] > 1.0
    if kw["mode"] == "robust":  # a penalty like soft: no continuation needed (measured 4 iterations)
        assert rep["mode"] == ["final"] * rep["iterations"] and rep["iterations"] <= 5
    else:
        # soft continuation first (measured 3 iterations: sigma 0.82 m = the RMS distance of the
        # start, then the floor: 0.063 m = 1e-3 of the path length, or the band's 0.05 m),
        # then the requested mode (measured 1 iteration)
        soft = [p for p in rep["phases"] if p["mode"] == "soft"]
        assert rep["mode"][0] == "soft" and rep["mode"][-1] == "final" and rep["continued"] == ["rail"]
        assert len(soft) == 1 and soft[0]["converged"] and soft[0]["iterations"] <= 4
        assert rep["phases"][-1] == {"mode": "final", "iterations": 1, "tol": 1e-4, "converged": True}
        sig = [s["rail"] for s in rep["sigma"] if s]
        floor = 0.05 if kw["mode"] == "band" else 1e-3 * track.length
        assert sig[0] > 0.5 and sig[-1] == pytest.approx(floor)
    # noise-free data and known ends: the truth is the only trajectory with a zero data term, and
    # it satisfies every mode (in the band too), so each mode recovers it
    assert sol.rms_error(truth) < 1e-6  # measured 7e-12 (direct), 8e-10 (hard clarabel), 3e-11 (band)
    d = project_onto_polyline(path, t, sol.position()).distance
    assert d.max() <= (kw.get("tol", 0.0) + 1e-6)


def test_an_outer_loops_capped_call_stays_in_the_continuations_soft_phase():
    """``steps=`` (the node-state loop's intermediate step): at most that many linearizations,
    no warning, and a hard track's continuation is not cut short by the requested mode (its
    soft phase goes on at the next call); called again without ``steps`` from that answer, the
    stage finishes soft, then hard, at the truth."""
    import warnings

    from bvpnav.solve import prepare
    from bvpnav.solve.chain import solve_fixed
    from bvpnav.solve.sequential import with_sequential

    t, truth, path, data = planar_track()
    track = TrackLine(x=path[:, 0], y=path[:, 1], axes=("x", "z"), name="rail", mode="hard")
    prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 20.0], value=[truth[0], truth[-1]]), track)
    start = truth + np.column_stack([2 * np.sin(np.pi * t / 20), 1.5 * np.sin(2 * np.pi * t / 20)])
    opts, lam = prepare(1.0, solver="direct", sequential={"initial": start})
    stage = with_sequential(solve_fixed)
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # a capped call that has not converged warns nothing
        first = stage(prob.formulation, lam, opts, steps=1)
    rep = first.stats["sequential"]
    assert rep["mode"] == ["soft"] and not rep["converged"] and rep["max_change"][0] > 1.0
    assert not [w for w in first.warnings if "did not converge" in w]
    opts, lam = prepare(1.0, solver="direct", sequential={"initial": first})
    sol = stage(prob.formulation, lam, opts)
    rep = sol.stats["sequential"]
    assert rep["converged"] and rep["mode"][0] == "soft" and rep["mode"][-1] == "final"
    assert sol.rms_error(truth) < 1e-6


def test_hard_track_without_continuation_stalls_mistimed_on_the_path():
    # why the continuation exists: the hard rows put the estimate on the path at once, at the
    # start's (wrong) arc lengths, and the Gauss-Newton step corrects the timing only slowly
    t, truth, path, data = planar_track()
    track = TrackLine(x=path[:, 0], y=path[:, 1], axes=("x", "z"))
    prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 20.0], value=[truth[0], truth[-1]]), track)
    start = truth + np.column_stack([2 * np.sin(np.pi * t / 20), 1.5 * np.sin(2 * np.pi * t / 20)])
    with pytest.warns(RuntimeWarning, match="did not converge"):
        sol = solve_sequential(prob, solver="direct", initial=start, max_iter=5, continuation=False,
                               verify=False)
    rep = sol.stats["sequential"]
    assert rep["mode"] == ["final"] * 5 and not rep["converged"]
    assert sol.rms_error(truth) > 0.5  # measured 1.08 m after 5 iterations
    on = project_onto_polyline(path, t, sol.position())
    inside = on.kept  # on the path except where it overshoots the resting end (dropped samples)
    assert np.sqrt(np.mean(on.distance[inside] ** 2)) < 1e-3  # measured 1.6e-6 m: on the path, mistimed
    assert rep["status"]["TrackLine"]["out_of_range"] > 0  # measured 52 samples near the resting end


def test_a_fix_off_a_hard_track_is_named_and_can_be_demoted():
    t, truth, path, data = planar_track()
    k = 500  # t = 10 s: a fix 0.5 m above the track
    ends = Position(t=[0.0, 20.0], value=[truth[0], truth[-1]], name="ends")
    fix = Position(t=[t[k]], value=[truth[k] + [0.0, 0.5]], name="fix")
    rail = TrackLine(x=path[:, 0], y=path[:, 1], axes=("x", "z"), name="rail")
    prob = bvpnav.NavigationProblem(data).add(ends, fix, rail)
    with pytest.raises(bvpnav.errors.Infeasible, match=r"conflict: \['(rail|fix)', '(rail|fix)'\]"):
        prob.solve(solver="clarabel")
    with pytest.raises(bvpnav.InputError, match="on_conflict"):
        prob.solve(on_conflict="ignore")
    # the track is trusted more: the fix (added before it, so it would otherwise be kept) is demoted
    sol = prob.solve(solver="clarabel", on_conflict="demote", priority={"rail": 1.0}, demote_sigma=0.5)
    assert [(d["item"], d["sigma"], sorted(d["conflict"])) for d in sol.stats["demoted"]] == [
        ("fix", 0.5, ["fix", "rail"])]
    assert any("'fix'" in w and "demoted" in w for w in sol.warnings)
    assert sol.stats["sequential"]["converged"] and sol.stats["sequential"]["mode"][0] == "soft"
    # the solution stays on the path; the soft fix (0.5 m off it) only slides it a little along
    # the path against the noise-free data term
    assert project_onto_polyline(path, t, sol.position()).distance.max() < 1e-6
    assert sol.rms_error(truth) < 1e-3  # measured 9.6e-5 m (largest 2.4e-4 m)
    assert np.hypot(*(sol.position()[k] - (truth[k] + [0.0, 0.5]))) > 0.49


def test_solve_dispatches_to_the_loop_and_reports():
    t, truth, path, data = planar_track()
    track = TrackLine(x=path[:, 0], y=path[:, 1], axes=("x", "z"), sigma=0.01)
    biased = bvpnav.ImuData(t, acc=data.acc + np.array([0.02, -0.02]), axes=("x", "z"))
    ends = Position(t=[0.0, 20.0], value=[truth[0], truth[-1]])
    only_ends = bvpnav.NavigationProblem(biased).add(ends).solve(solver="direct")
    sol = bvpnav.NavigationProblem(biased).add(ends, track).solve(solver="direct")
    rep = sol.stats["sequential"]
    assert rep["converged"] and rep["iterations"] <= 6
    assert rep["initial"].startswith("first phase")
    # the track removes most of the bias drift of the end conditions alone
    assert sol.rms_error(truth) < only_ends.rms_error(truth) / 5
    # the solution lies on the path (within the polyline's chord error and the bias misfit)
    pr = project_onto_polyline(path, t, sol.position())
    assert np.sqrt(np.mean(pr.distance**2)) < 0.05


def test_loop_warns_when_not_converged():
    t, truth, path, data = planar_track()
    track = TrackLine(x=path[:, 0], y=path[:, 1], axes=("x", "z"), sigma=0.01)
    prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 20.0], value=[truth[0], truth[-1]]), track)
    start = truth + np.column_stack([2 * np.sin(np.pi * t / 20), 0.0 * t])
    with pytest.warns(RuntimeWarning, match="did not converge"):
        sol = solve_sequential(prob, solver="direct", initial=start, max_iter=1)
    assert not sol.stats["sequential"]["converged"] and sol.stats["sequential"]["iterations"] == 1
    assert any("did not converge" in w for w in sol.warnings)
