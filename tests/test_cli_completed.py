"""Issue 41 item 5, the command line completed: a spec's [align] (a strapdown recording from file
to trajectory without Python), a 2-D --truth for a 3-axis solution, `bvpnav lcurve` without
--plot, and --help texts about strapdown inputs and the samples."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

import bvpnav
from bvpnav import detect
from bvpnav.align import align
from bvpnav.cli import main
from bvpnav.constraints import Position, ZeroVelocity
from bvpnav.error_models import AttitudeError, Bias
from bvpnav.scenarios import car_drive
from bvpnav.spec import dumps_spec, problem_to_spec

REST = 4.5  # s: the drive stands still for 5 s, the rest interval stops short of the start
INPUT = {"time": "t", "time_unit": "s", "specific_force": ["f_x", "f_y", "f_z"],
         "gyro": ["w_x", "w_y", "w_z"], "gyro_unit": "rad/s", "unit": "m/s^2", "frame": "enu"}
SOLVE = {"solver": "direct", "lam": 1.0}


@pytest.fixture(scope="module")
def drive():
    """A 60 s car drive at 10 Hz (tactical IMU with biases and noise): 5 s at rest, then driving;
    GNSS fixes every 5 s from t = 5 s."""
    d = car_drive(duration=60.0, rate=10.0, seed=1)
    return d, d.fix_t[5::5], d.fix_position[5::5]


def _recording(tmp_path, d):
    path = tmp_path / "drive.csv"
    cols = {"t": d.t, **{f"f_{a}": d.specific_force[:, k] for k, a in enumerate("xyz")},
            **{f"w_{a}": d.gyro[:, k] for k, a in enumerate("xyz")}}
    pd.DataFrame(cols).to_csv(path, index=False, float_format="%.17g")
    return path


def _python_path(d, c0, model, items, **solve):
    """The Python path of docs/guide/strapdown.md: from_gyro from the aligned attitude, then solve."""
    data = bvpnav.ImuData.from_gyro(d.t, d.specific_force, d.gyro, initial_attitude=c0)
    prob = bvpnav.NavigationProblem(data, error_model=model, sigma_a=0.05).add(*items)
    return prob, prob.solve(**{**SOLVE, **solve})


def _spec_file(tmp_path, prob, align_table, solve=None):
    spec = problem_to_spec(prob, solve={**SOLVE, **(solve or {})}, input=INPUT)
    spec.align = dict(align_table)
    path = tmp_path / "spec.toml"
    path.write_text(dumps_spec(spec))
    return path


def _solve_cli(tmp_path, rec, spec, capsys, *extra):
    out = tmp_path / "traj.csv"
    assert main(["solve", str(rec), "--spec", str(spec), "--out", str(out), *extra]) == 0
    return pd.read_csv(out), json.loads(out.with_suffix(".json").read_text()), capsys.readouterr().out


def _items(fix_t, fix_p):
    return [ZeroVelocity(t0=0.0, t1=REST, sigma=0.01, name="waiting"),
            Position(t=fix_t, value=fix_p, sigma=1.0, name="gnss")]


def test_align_rest_and_fixes_matches_the_python_path(tmp_path, drive, capsys):
    """[align] rest = [0, 4.5], heading = "fixes": `bvpnav solve` with the spec alone gives the
    Python path's trajectory (align, ImuData.from_gyro, solve) to 1e-9 m."""
    d, fix_t, fix_p = drive
    c0 = align(d.t, d.specific_force, stationary=(0.0, REST), positions=fix_p, position_times=fix_t,
               gyro=d.gyro)
    prob, sol = _python_path(d, c0, Bias(), _items(fix_t, fix_p))
    spec = _spec_file(tmp_path, prob, {"rest": [0.0, REST], "heading": "fixes"})
    traj, summary, printed = _solve_cli(tmp_path, _recording(tmp_path, d), spec, capsys)
    gap = np.max(np.abs(traj[["x", "y", "z"]].to_numpy() - sol.position()))
    assert gap < 1e-9, gap
    rec = summary["data_checks"]["align"]
    assert rec["rest"] == [0.0, REST] and rec["heading_source"] == "fixes"
    yaw, pitch, roll = c0.as_euler("ZYX", degrees=True)
    assert rec["yaw_deg"] == pytest.approx(yaw, abs=1e-9) and rec["roll_deg"] == pytest.approx(roll, abs=1e-9)
    # the alignment is a real one: roll and pitch within 0.05 deg of the truth (the true start)
    true_yaw, true_pitch, true_roll = d.attitude[0].as_euler("ZYX", degrees=True)
    assert abs(rec["roll_deg"] - true_roll) < 0.05 and abs(rec["pitch_deg"] - true_pitch) < 0.05
    assert "aligned at t[0]: roll" in printed and "(from the position fixes)" in printed
    assert rec["warning"] is None and rec["rest_mean_rate"] < 1e-3  # the stand does not turn
    # and it matters: from the identity the same spec (no [align]) is metres away
    plain = bvpnav.ImuData.from_gyro(d.t, d.specific_force, d.gyro)
    off = bvpnav.NavigationProblem(plain, error_model=Bias(), sigma_a=0.05).add(*prob.items).solve(**SOLVE)
    assert np.max(np.abs(off.position() - sol.position())) > 1.0


def test_align_first_rest_and_heading_in_degrees(tmp_path, capsys):
    """A foot-mounted walk: rest = "first" (the detector's first interval of >= 1 s, the 1.5 s
    stand) and heading = 30 (degrees), against the Python path (detect.stationary, align with
    yaw=radians(30), from_gyro) to 1e-9 m."""
    from bvpnav.scenarios import walking

    sc = walking(rate=100.0, n_strides=4, seed=0)
    d = sc.data
    probe = bvpnav.ImuData.from_gyro(d.t, d.specific_force, d.gyro, checks=False)
    t0, t1 = next((a, b) for a, b in detect.stationary(probe, gravity=9.80665) if b - a >= 1.0)
    assert (t0, t1) == (0.0, 1.5)  # the stand, as simulated
    c0 = align(d.t, d.specific_force, stationary=(t0, t1), yaw=math.radians(30.0), gyro=d.gyro)
    data = bvpnav.ImuData.from_gyro(d.t, d.specific_force, d.gyro, initial_attitude=c0)
    items = [Position(t=[0.0], value=[0.0, 0.0, 0.0], name="start"),
             *(ZeroVelocity(t0=a, t1=b, sigma=0.01, name=f"stance {k}")
               for k, (a, b) in enumerate(sc.params["stance_intervals"]))]
    prob = bvpnav.NavigationProblem(data, sigma_a=0.05).add(*items)
    sol = prob.solve(**SOLVE)
    spec = _spec_file(tmp_path, prob, {"rest": "first", "heading": 30.0})
    rec = tmp_path / "walk.csv"
    pd.DataFrame({"t": d.t, **{f"f_{a}": d.specific_force[:, k] for k, a in enumerate("xyz")},
                  **{f"w_{a}": d.gyro[:, k] for k, a in enumerate("xyz")}}).to_csv(rec, index=False,
                                                                                    float_format="%.17g")
    traj, summary, printed = _solve_cli(tmp_path, rec, spec, capsys)
    assert np.max(np.abs(traj[["x", "y", "z"]].to_numpy() - sol.position())) < 1e-9
    got = summary["data_checks"]["align"]
    assert got["rest"] == [0.0, 1.5] and got["yaw_deg"] == pytest.approx(30.0, abs=1e-9)
    assert "rest 0 .. 1.5 s; yaw 30 deg (given)" in printed
    # the walk starts heading east (yaw 0): given 30 deg, its end bearing turns by 30 deg (to 0.1 deg)
    end, true_end = traj[["x", "y"]].to_numpy()[-1], sc.position[-1]
    turned = math.degrees(math.atan2(end[1], end[0]) - math.atan2(true_end[1], true_end[0]))
    assert abs(turned - 30.0) < 0.1 and abs(np.hypot(*end) - np.hypot(*true_end[:2])) < 0.05


def test_align_warns_when_the_rest_interval_turns(tmp_path, drive, capsys):
    """rest = [20, 30] s is a gentle curve (0.019 rad/s): accepted (|f| is within 5 % of g) but warned,
    in the output and the summary, naming the interval, the rate and the fix; roll 1.3 deg off."""
    d, fix_t, fix_p = drive
    c0 = align(d.t, d.specific_force, stationary=(20.0, 30.0), positions=fix_p, position_times=fix_t,
               gyro=d.gyro)
    prob, _ = _python_path(d, c0, Bias(), _items(fix_t, fix_p))
    spec = _spec_file(tmp_path, prob, {"rest": [20.0, 30.0], "heading": "fixes"})
    _, summary, printed = _solve_cli(tmp_path, _recording(tmp_path, d), spec, capsys)
    rec = summary["data_checks"]["align"]
    assert 0.015 < rec["rest_mean_rate"] < 0.025 and "not at rest" in rec["warning"]
    assert "warning: [align] rest 20 .. 30 s: the gyro's mean rate there is 0.0186 rad/s" in printed
    assert "bvpnav stationary" in printed
    true_roll = d.attitude[0].as_euler("ZYX", degrees=True)[2]
    assert abs(rec["roll_deg"] - true_roll) > 1.0  # what the warning is about


def test_align_heading_searched_by_the_solve(tmp_path, drive, capsys):
    """heading = "search": yaw 0 at the start and the solve's heading search (a free heading in
    attitude_error), as in Python with align(..., yaw=0.0); the heading found is the truth's."""
    d, fix_t, fix_p = drive
    c0 = align(d.t, d.specific_force, stationary=(0.0, REST), yaw=0.0, gyro=d.gyro)
    model = Bias() + AttitudeError(sigma=(0.01, 0.01, None))
    prob, sol = _python_path(d, c0, model, _items(fix_t, fix_p))
    spec = _spec_file(tmp_path, prob, {"rest": [0.0, REST], "heading": "search"})
    assert "inf" in spec.read_text()  # the free heading, written and read back
    traj, summary, printed = _solve_cli(tmp_path, _recording(tmp_path, d), spec, capsys)
    assert np.max(np.abs(traj[["x", "y", "z"]].to_numpy() - sol.position())) < 1e-9
    assert sol.stats["sequential"]["heading"] == "searched"
    true_yaw = d.attitude[0].as_euler("ZYX")[0]
    found = sol.error_params["attitude_z"]
    assert abs(math.remainder(found - true_yaw, 2 * math.pi)) < math.radians(2.0)
    assert "(0, searched by the solve)" in printed


@pytest.mark.parametrize("table, extra, says", [
    ('rest = [4.5, 0.0]', "", ["line 2", "rest = [4.5, 0.0]", "t0 < t1"]),
    ('heading = "north"', "", ["line 2", "heading = 'north'", "degrees", '"fixes"']),
    ('heading = "search"', "", ["line 2", 'type = "attitude_error"']),
    ('heading = 10.0\nfixes = "gnss"', "", ["line 3", 'heading = "fixes"']),
    ('min_rest = 0', 'heading = 1.0', ["min_rest = 0", "positive"]),
    ('wobble = 1', "", ["unknown key 'wobble' in [align]", "heading", "rest"]),
])
def test_align_errors_name_the_line_and_the_fix(tmp_path, table, extra, says):
    text = f"[align]\n{table}\n{extra}\n[input]\ntime = \"t\"\nspecific_force = [\"a\", \"b\", \"c\"]\n" \
           "gyro = [\"d\", \"e\", \"f\"]\n"
    spec = tmp_path / "spec.toml"
    spec.write_text(text)
    with pytest.raises(bvpnav.InputError) as err:
        bvpnav.spec.load_spec(spec)
    for s in says:
        assert s in str(err.value), (s, str(err.value))


def test_align_refuses_a_given_initial_attitude_and_missing_fixes(tmp_path, drive, capsys):
    d, fix_t, fix_p = drive
    rec = _recording(tmp_path, d)
    spec = tmp_path / "spec.toml"
    head = '[input]\ntime = "t"\nspecific_force = ["f_x", "f_y", "f_z"]\ngyro = ["w_x", "w_y", "w_z"]\n'
    spec.write_text(head + 'initial_attitude = { euler = [0, 0, 10] }\n\n[align]\nheading = 10.0\n')
    with pytest.raises(bvpnav.InputError, match=r"line 5: \[input\] initial_attitude .* keep one"):
        bvpnav.spec.load_spec(spec)
    spec.write_text(head + '\n[align]\nheading = "fixes"\n\n[[item]]\ntype = "position"\nt = [0.0]\n'
                    'value = [0.0, 0, 0]\nname = "start"\n\n[[item]]\ntype = "position"\nt = [60.0]\n'
                    'value = [1.0, 0, 0]\nname = "end"\n')
    assert main(["solve", str(rec), "--spec", str(spec), "--out", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert "line 6" in err and "2 position items ['start', 'end']" in err and 'fixes = "..."' in err


def test_truth_2d_for_a_3_axis_solution(tmp_path, drive, capsys):
    """--truth with t, x, y only (motion capture): the printed RMS is the horizontal one, equal to
    bvpnav.evaluate's rms_horizontal; the plot draws it on the map and the x, y panels."""
    d, fix_t, fix_p = drive
    c0 = align(d.t, d.specific_force, stationary=(0.0, REST), positions=fix_p, position_times=fix_t,
               gyro=d.gyro)
    prob, sol = _python_path(d, c0, Bias(), _items(fix_t, fix_p))
    spec = _spec_file(tmp_path, prob, {"rest": [0.0, REST], "heading": "fixes"})
    truth = tmp_path / "mocap.csv"
    pd.DataFrame({"t": d.t, "x": d.position[:, 0], "y": d.position[:, 1]}).to_csv(truth, index=False,
                                                                                 float_format="%.17g")
    png = tmp_path / "traj.png"
    html = tmp_path / "report.html"
    _, _, printed = _solve_cli(tmp_path, _recording(tmp_path, d), spec, capsys, "--truth", str(truth),
                               "--plot", str(png), "--report", str(html))
    assert html.read_text().count("data:image/png;base64") >= 2  # the report draws with the 2-D truth too
    want = float(np.sqrt(np.mean(np.sum((sol.position()[:, :2] - d.position[:, :2]) ** 2, axis=1))))
    assert 0.1 < want < 20.0
    from bvpnav.evaluate import ape, read_trajectory

    scored = ape(read_trajectory(tmp_path / "traj.csv"), read_trajectory(truth), align="none")
    assert scored.stats()["rms_horizontal"] == pytest.approx(want, rel=1e-9)
    line = next(ln for ln in printed.splitlines() if "RMS" in ln)
    assert line.startswith("horizontal RMS position error against the 2-D truth")
    assert "z is not scored" in line
    assert f"{want:.4g} m" in line
    assert png.stat().st_size > 10_000
    import matplotlib.pyplot as plt

    from bvpnav import plot

    fig = plot.solution(sol, truth=pd.read_csv(truth).drop(columns="t"))
    labels = {ax.get_title(): [ln.get_label() for ln in ax.get_lines()] for ax in fig.axes}
    assert "truth" in labels["position x"] and "truth" in labels["position y"]
    assert "truth" not in labels["position z"]
    assert "truth (x, y only)" in labels["path x-y"]
    plt.close(fig)


def test_truth_missing_axes_still_refused(tmp_path, drive, capsys):
    """A truth with x only (not the horizontal pair) of a 3-axis solution is refused, naming it."""
    d, fix_t, fix_p = drive
    c0 = align(d.t, d.specific_force, stationary=(0.0, REST), yaw=0.0, gyro=d.gyro)
    prob, _ = _python_path(d, c0, Bias(), _items(fix_t, fix_p))
    spec = _spec_file(tmp_path, prob, {"rest": [0.0, REST], "heading": 0.0})
    truth = tmp_path / "x_only.csv"
    pd.DataFrame({"t": d.t, "x": d.position[:, 0]}).to_csv(truth, index=False)
    assert main(["solve", str(_recording(tmp_path, d)), "--spec", str(spec), "--out", str(tmp_path / "o.csv"),
                 "--truth", str(truth)]) == 2
    assert "no column(s) ['y', 'z']" in capsys.readouterr().err


def test_lcurve_prints_the_rules_without_plot(tmp_path, capsys):
    """`bvpnav lcurve` without --plot prints each rule's choice (the same as with --plot) and writes
    no figure."""
    assert main(["simulate", "tikhonov2011", "--out", str(tmp_path / "s")]) == 0
    args = ["lcurve", str(tmp_path / "s" / "recording.csv"), "--spec", str(tmp_path / "s" / "spec.toml"),
            "--points", "9"]
    capsys.readouterr()
    assert main(args) == 0
    bare = capsys.readouterr().out
    chosen = dict(ln.split(" lam = ") for ln in bare.splitlines() if " lam = " in ln)
    assert {k.strip() for k in chosen} == {"lcurve", "quasi"}  # the load form's default rules
    assert all(1e-3 < float(v) < 1e3 for v in chosen.values())  # interior choices (3.9 and 2.7)
    png = tmp_path / "l.png"
    assert main([*args, "--plot", str(png)]) == 0
    assert capsys.readouterr().out == bare and png.stat().st_size > 5_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["l.png", "s"]


def test_help_describes_strapdown_inputs_and_the_samples(capsys):
    from bvpnav.samples import SAMPLES

    for cmd in (["solve", "--help"], ["simulate", "--help"], ["--help"]):
        with pytest.raises(SystemExit):
            main(cmd)
    out = capsys.readouterr().out
    for words in ("specific_force = [", "gyro = [", 'gyro_unit = "rad/s"', "frame = \"enu\"", "ned (x north",
                  "body_to_sensor", "initial_attitude", "[align]", "rest = [0.0, 4.5]", 'heading = "fixes"',
                  "at rest +9.81 m/s^2 on the", "strapdown channels"):
        assert words in out, words
    start = out.index("Scenarios:")
    sim = " ".join(out[start:out.index("positional arguments", start)].split())
    for name in SAMPLES:  # each scenario: its line, then what it writes
        assert f" {name} " in sim and sim.index("writes recording.csv: t", sim.index(f" {name} ")) > 0
    assert sim.count("writes recording.csv: t") == len(SAMPLES)
    assert "f_x f_y f_z (specific force, m/s^2" in sim and "w_x w_y w_z (gyro, rad/s)" in sim
    assert "qw qx qy qz (the orientation" in sim and "acc_x (m/s^2, navigation frame" in sim
