"""bvpnav.evaluate: ATE/RPE against analytic values, evo's numbers on the same files, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from bvpnav import InputError
from bvpnav.cli import main
from bvpnav.evaluate import (
    Trajectory,
    align,
    ape,
    associate,
    evaluate,
    read_trajectory,
    rpe,
    write_tum,
)


def _planar_case(n=60, eps=0.05, seed=3):
    """A planar reference (z = 0) and a vertical perturbation d_i = eps c_i (0, 0, 1) with c orthogonal
    to 1, x and y: the least-squares rigid fit of q + d onto q is then the identity (sum d = 0 and
    sum q x d = 0), so the rigid-fit errors are exactly d."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 30.0, n)
    q = np.column_stack([10 * np.cos(0.2 * t) + 0.3 * t, 6 * np.sin(0.3 * t), np.zeros(n)])
    c = rng.standard_normal(n)
    basis = np.column_stack([np.ones(n), q[:, 0], q[:, 1]])
    c -= basis @ np.linalg.lstsq(basis, c, rcond=None)[0]
    d = np.column_stack([np.zeros(n), np.zeros(n), eps * c])
    return t, q, d


def _transform(y, s, rot, tr):
    return s * y @ rot.T + tr


ROT = Rotation.from_euler("zyx", [37.0, 4.0, -3.0], degrees=True).as_matrix()
TR = np.array([120.0, -45.0, 7.5])


def test_rigid_alignment_errors_are_the_perturbation_exactly():
    t, q, d = _planar_case()
    est = Trajectory(t, _transform(q + d, 1.0, ROT, TR), name="est")
    ref = Trajectory(t, q, name="ref")
    res = ape(est, ref, align="rigid")
    np.testing.assert_allclose(res.error, np.abs(d[:, 2]), rtol=0, atol=1e-9)
    s = res.stats()
    assert s["rmse"] == pytest.approx(np.sqrt(np.mean(d[:, 2] ** 2)), abs=1e-9)
    assert s["median"] == pytest.approx(np.median(np.abs(d[:, 2])), abs=1e-9)
    assert s["rms_horizontal"] < 1e-9 and s["rms_vertical"] == pytest.approx(s["rmse"], abs=1e-12)
    np.testing.assert_allclose(res.alignment.rotation, ROT.T, atol=1e-9)
    # RPE every 5 samples, no orientation: the displacement error d_j - d_i in the aligned frame
    r = rpe(est, ref, delta=5, unit="frames", align="rigid")
    i, j = r.pairs[:, 0], r.pairs[:, 1]
    np.testing.assert_array_equal(i, np.arange(0, 55, 5))
    np.testing.assert_allclose(r.error, np.abs(d[j, 2] - d[i, 2]), atol=1e-9)


def test_similarity_and_scale_alignments_analytic():
    t, q, d = _planar_case()
    qc = q - q.mean(axis=0)
    a, b = np.sum(qc ** 2), np.sum(d ** 2)
    s_star = a / (a + b)  # the fitted relative scale: d is orthogonal to every centred q_i
    est = Trajectory(t, _transform(q + d, 2.5, ROT, TR))
    ref = Trajectory(t, q)
    res = ape(est, ref, align="similarity")
    expect = s_star * (qc + d) - qc
    np.testing.assert_allclose(res.vector, expect, atol=1e-9)
    assert res.rmse == pytest.approx(np.sqrt(a * b / (a + b) / len(t)), abs=1e-9)
    assert res.alignment.scale == pytest.approx(s_star / 2.5, rel=1e-12)
    # scale only (evo's --correct_scale alone): about the origin, no rotation or translation
    est2 = Trajectory(t, 2.5 * (q + d))
    res2 = ape(est2, ref, align="scale")
    np.testing.assert_allclose(res2.vector, s_star * (q + d) - q, atol=1e-9)


def test_yaw_and_translation_alignments():
    t, q, d = _planar_case()
    rz = Rotation.from_euler("z", 73.0, degrees=True).as_matrix()
    est = Trajectory(t, _transform(q + d, 1.0, rz, TR))
    res = ape(est, Trajectory(t, q), align="yaw")
    np.testing.assert_allclose(res.vector, d, atol=1e-9)
    assert res.alignment.yaw_deg == pytest.approx(-73.0, abs=1e-9)
    res_t = ape(Trajectory(t, q + d + TR), Trajectory(t, q), align="translation")
    np.testing.assert_allclose(res_t.vector, d, atol=1e-9)
    res_n = ape(Trajectory(t, q + TR), Trajectory(t, q), align="none")
    np.testing.assert_allclose(res_n.error, np.linalg.norm(TR), rtol=1e-12)
    # fitted on the first 20 samples only (evo's --n_to_align): exact there, the same map here
    est = Trajectory(t, _transform(q, 1.0, rz, TR))
    first = align(est, Trajectory(t, q), "rigid", first=20)
    np.testing.assert_allclose(first.apply(est).xyz, q, atol=1e-9)
    with pytest.raises(InputError, match="first=1"):
        align(est, Trajectory(t, q), "rigid", first=1)


def test_rpe_with_orientations_is_frame_local():
    """With orientations, evo's RPE expresses each displacement in the pair's first body frame: a rigid
    misplacement of the whole estimate (positions and orientations) does not change it."""
    t, q, d = _planar_case()
    yaw, roll = (0.3 * t)[:, None], (0.05 * np.sin(t))[:, None]
    ori_q = Rotation.from_euler("z", yaw) * Rotation.from_euler("x", roll)
    big = Rotation.from_matrix(ROT)
    est = Trajectory(t, _transform(q + d, 1.0, ROT, TR), big * ori_q)
    ref = Trajectory(t, q, ori_q)
    r = rpe(est, ref, delta=3, unit="frames", align="none", all_pairs=True)
    i, j = r.pairs[:, 0], r.pairs[:, 1]
    np.testing.assert_allclose(r.error, np.abs(d[j, 2] - d[i, 2]), atol=1e-9)


def test_rpe_by_time_and_path():
    t = np.linspace(0.0, 20.0, 201)
    q = np.column_stack([t, np.sin(t), 0 * t])
    drift = np.column_stack([0.01 * t, 0 * t, 0 * t])
    est, ref = Trajectory(t, q + drift), Trajectory(t, q)
    r = rpe(est, ref, delta=2.0, unit="s")
    np.testing.assert_array_equal(np.diff(r.pairs[:, 0]), 20)
    np.testing.assert_allclose(r.error, 0.02, rtol=1e-9)
    rp = rpe(est, ref, delta=3.0, unit="m", pairs_from="reference")
    steps = np.linalg.norm(np.diff(q, axis=0), axis=1)
    for i, j in rp.pairs:
        assert steps[i:j].sum() >= 3.0 > steps[i:j - 1].sum()


def test_association_nearest_and_interpolate():
    t_ref = np.arange(0.0, 10.0, 0.1)
    ref = Trajectory(t_ref, np.column_stack([t_ref, 2 * t_ref, 0 * t_ref]))
    t_est = np.arange(0.0, 10.0, 0.0333) + 0.004
    est = Trajectory(t_est, np.column_stack([t_est, 2 * t_est, 0 * t_est]))
    e, r = associate(est, ref, max_diff=0.01)
    assert len(e) == len(r) > 50
    assert np.max(np.abs(e.t - r.t)) <= 0.01
    e2, r2 = associate(est, ref, method="interpolate")
    np.testing.assert_allclose(e2.xyz, r2.xyz, atol=1e-12)
    with pytest.raises(InputError, match="within 0.01 s"):
        associate(Trajectory(t_est + 100, est.xyz), ref)


def test_two_d_truth_scores_horizontal_only(tmp_path):
    t, q, d = _planar_case()
    truth = tmp_path / "truth.csv"
    rows = zip(t, q[:, 0], q[:, 1], strict=True)
    truth.write_text("t,x,y\n" + "\n".join(f"{a:.17g},{b:.17g},{c:.17g}" for a, b, c in rows))
    est = Trajectory(t, q + d + [1.0, 2.0, 3.0])
    res = evaluate(est, truth, align="translation")["ape"]
    assert res.vector.shape[1] == 2 and res.rmse < 1e-9


def test_tum_round_trip_and_bad_lines(tmp_path):
    t, q, _ = _planar_case(n=10)
    ori = Rotation.from_euler("z", t[:, None])
    p = tmp_path / "a.tum"
    write_tum(Trajectory(t, q, ori), p)
    back = read_trajectory(p)
    np.testing.assert_array_equal(back.t, t)
    np.testing.assert_array_equal(back.xyz, q)
    assert np.max((back.orientation.inv() * ori).magnitude()) < 1e-12
    p2 = tmp_path / "b.tum"
    write_tum(Trajectory(t, q), p2)
    assert read_trajectory(p2).orientation is None
    bad = tmp_path / "bad.tum"
    bad.write_text("0 0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n")
    with pytest.raises(InputError, match="line 2: 7 entries"):
        read_trajectory(bad)
    nonunit = tmp_path / "nonunit.tum"
    nonunit.write_text("0 0 0 0 0 0 0 2\n1 1 0 0 0 0 0 1\n")
    with pytest.raises(InputError, match="norm 2"):
        read_trajectory(nonunit)


def _realistic(tmp_path, seed=11):
    """A car-like drive at 10 Hz with heading along the motion, and a drifting, noisy estimate at
    about 100 Hz on another clock grid (jittered), both written as TUM files."""
    rng = np.random.default_rng(seed)
    t_ref = np.arange(0.0, 60.0, 0.1)
    heading = 0.4 * np.sin(0.07 * t_ref) + 0.02 * t_ref
    speed = 8.0 + np.sin(0.3 * t_ref)
    dt = np.diff(t_ref, prepend=t_ref[0])
    x = np.cumsum(speed * np.cos(heading) * dt)
    y = np.cumsum(speed * np.sin(heading) * dt)
    z = 0.5 * np.sin(0.05 * t_ref)
    angles = np.column_stack([heading, 0.01 * np.sin(t_ref), 0.02 * np.cos(t_ref)])
    ori_ref = Rotation.from_euler("zyx", angles)
    t_est = np.sort(np.arange(0.0, 60.0, 0.01) + rng.uniform(-0.002, 0.002, 6000))
    t_est = t_est[(t_est > 0) & (t_est < 59.9)]
    xe = np.interp(t_est, t_ref, x) + 0.002 * t_est ** 1.5 + 0.05 * rng.standard_normal(t_est.size)
    ye = np.interp(t_est, t_ref, y) - 0.01 * t_est + 0.05 * rng.standard_normal(t_est.size)
    ze = np.interp(t_est, t_ref, z) + 0.03 * rng.standard_normal(t_est.size)
    est_xyz = _transform(np.column_stack([xe, ye, ze]), 1.02, ROT, TR)
    from scipy.spatial.transform import Slerp

    ori_est = Rotation.from_matrix(ROT) * Slerp(t_ref, ori_ref)(t_est) * Rotation.from_rotvec(
        0.01 * rng.standard_normal((t_est.size, 3)))
    pe, pr = tmp_path / "est.tum", tmp_path / "ref.tum"
    write_tum(Trajectory(t_est, est_xyz, ori_est), pe)
    write_tum(Trajectory(t_ref, np.column_stack([x, y, z]), ori_ref), pr)
    return pe, pr


EVO_CASES = [  # (our align, evo align, evo correct_scale)
    ("none", False, False),
    ("rigid", True, False),
    ("similarity", True, True),
    ("scale", False, True),
]


@pytest.mark.parametrize(("ours", "evo_align", "evo_scale"), EVO_CASES)
def test_agrees_with_evo_on_the_same_files(tmp_path, ours, evo_align, evo_scale):
    evo = pytest.importorskip("evo", reason="evo (pip install evo) is the reference for this comparison")
    from evo.core import metrics, sync
    from evo.main_ape import ape as evo_ape
    from evo.main_rpe import rpe as evo_rpe
    from evo.tools import file_interface

    del evo
    pe, pr = _realistic(tmp_path)
    ref_e, est_e = sync.associate_trajectories(file_interface.read_tum_trajectory_file(str(pr)),
                                               file_interface.read_tum_trajectory_file(str(pe)),
                                               max_diff=0.01)
    res_evo = evo_ape(ref_e, est_e, metrics.PoseRelation.translation_part, align=evo_align,
                      correct_scale=evo_scale)
    est, ref = read_trajectory(pe), read_trajectory(pr)
    ours_ape = ape(est, ref, align=ours, max_diff=0.01)
    assert ours_ape.error.size == res_evo.np_arrays["error_array"].size
    for k in ("rmse", "mean", "median", "std", "min", "max", "sse"):
        assert ours_ape.stats()[k] == pytest.approx(res_evo.stats[k], rel=1e-6, abs=1e-9), k
    for delta, unit, evo_unit, all_pairs in [(10.0, "m", metrics.Unit.meters, False),
                                             (20, "frames", metrics.Unit.frames, False),
                                             (5.0, "m", metrics.Unit.meters, True)]:
        ref_e, est_e = sync.associate_trajectories(file_interface.read_tum_trajectory_file(str(pr)),
                                                   file_interface.read_tum_trajectory_file(str(pe)),
                                                   max_diff=0.01)
        r_evo = evo_rpe(ref_e, est_e, metrics.PoseRelation.translation_part, delta=delta, delta_unit=evo_unit,
                        all_pairs=all_pairs, align=evo_align, correct_scale=evo_scale)
        r_ours = rpe(est, ref, delta=delta, unit=unit, align=ours, all_pairs=all_pairs)
        assert r_ours.error.size == r_evo.np_arrays["error_array"].size
        for k in ("rmse", "mean", "median", "std", "min", "max"):
            assert r_ours.stats()[k] == pytest.approx(r_evo.stats[k], rel=1e-6, abs=1e-9), (delta, unit, k)


def test_cli_evaluate(tmp_path, capsys):
    t, q, d = _planar_case()
    est = tmp_path / "est.csv"
    rows = _transform(q + d, 1.0, Rotation.from_euler("z", 30, degrees=True).as_matrix(), TR)
    est.write_text("t,x,y,z,vx,vy,vz\n" + "\n".join(",".join(repr(float(v)) for v in (ti, *p, 0, 0, 0))
                                                   for ti, p in zip(t, rows, strict=True)))
    truth = tmp_path / "truth.tum"
    write_tum(Trajectory(t, q), truth)
    out, fig = tmp_path / "scores.json", tmp_path / "scores.png"
    code = main(["evaluate", str(est), "--truth", str(truth), "--align", "yaw", "--delta", "5",
                 "--delta-unit", "frames", "--out", str(out), "--plot", str(fig)])
    assert code == 0
    text = capsys.readouterr().out
    assert "APE" in text and "RPE over 5 frames" in text and "yaw -30.000 deg" in text
    rec = json.loads(out.read_text())
    assert rec["ape"]["stats"]["rmse"] == pytest.approx(np.sqrt(np.mean(d[:, 2] ** 2)), abs=1e-9)
    assert fig.stat().st_size > 10_000
    # an output onto an input is refused, the input untouched
    before = truth.read_bytes()
    assert main(["evaluate", str(est), "--truth", str(truth), "--plot", str(truth)]) == 2
    assert truth.read_bytes() == before


def test_readme_evaluation_lines_run(tmp_path, monkeypatch, capsys):
    """README's evaluation block runs as written, and prints the figures it quotes."""
    import re
    import shlex
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    (block,) = [b for b in re.findall(r"```bash\n(.*?)\n```", readme, re.S) if "bvpnav evaluate" in b]
    monkeypatch.chdir(tmp_path)
    for line in block.splitlines():
        argv = shlex.split(line)
        assert argv[0] == "bvpnav"
        assert main(argv[1:]) == 0, line
    out = capsys.readouterr().out
    rec = json.loads((tmp_path / "scores.json").read_text())
    quoted = re.search(r"here ([0-9.]+) m RMS, ([0-9.]+) m horizontal", readme)
    assert f"{rec['ape']['stats']['rmse']:.3f}" == quoted.group(1)
    assert f"{rec['ape']['stats']['rms_horizontal']:.3f}" == quoted.group(2)
    assert "RPE over 5 m" in out
