"""Stationary-interval detection (bvpnav.detect) on the simulated foot-mounted walk."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

import bvpnav  # noqa: E402
from bvpnav import detect, plot, scenarios  # noqa: E402
from bvpnav.constraints import Position, ZeroVelocity  # noqa: E402
from bvpnav.errors import InputError  # noqa: E402


def precision_recall(mask, truth) -> tuple[float, float]:
    tp = np.count_nonzero(mask & truth)
    return tp / max(np.count_nonzero(mask), 1), tp / np.count_nonzero(truth)


def shoe_literal(f, w, W, sigma_a, sigma_w, g):
    """Skog et al. (2010), eq. (12), transcribed term by term with loops."""
    N = len(f)
    T = np.zeros(N - W + 1)
    for n in range(N - W + 1):
        mean = [sum(f[l][i] for l in range(n, n + W)) / W for i in range(3)]
        norm = sum(c * c for c in mean) ** 0.5
        total = 0.0
        for l in range(n, n + W):
            acc = sum((f[l][i] - g * mean[i] / norm) ** 2 for i in range(3))
            rate = sum(w[l][i] ** 2 for i in range(3))
            total += acc / sigma_a**2 + rate / sigma_w**2
        T[n] = total / W
    return T


@pytest.fixture(scope="module")
def walk():
    return scenarios.walking(seed=1)


@pytest.fixture(scope="module")
def short_walk():
    return scenarios.walking(n_strides=4, seed=2)


# ---------------------------------------------------------------- the statistics
@pytest.mark.parametrize("W", [2, 3, 7])
def test_shoe_statistic_is_the_published_formula(W, monkeypatch):
    rng = np.random.default_rng(W)
    f = rng.normal(0.0, 1.5, (120, 3)) + [0.4, -0.3, 9.7]
    w = rng.normal(0.0, 0.4, (120, 3))
    ref = shoe_literal(f.tolist(), w.tolist(), W, 0.02, 0.003, 9.81)
    got = detect.shoe_statistic(f, w, W, sigma_a=0.02, sigma_w=0.003, gravity=9.81)
    assert got.shape == (120 - W + 1,)
    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-12
    # computed block by block (a few windows at a time): the same numbers
    monkeypatch.setattr(detect, "_BLOCK_VALUES", 10)
    blocked = detect.shoe_statistic(f, w, W, sigma_a=0.02, sigma_w=0.003, gravity=9.81)
    assert np.max(np.abs(blocked - ref) / np.abs(ref)) < 1e-12


def test_magnitude_statistic_is_its_formula():
    rng = np.random.default_rng(7)
    f = rng.normal(0.0, 0.5, (60, 3)) + [0.0, 0.0, 9.8]
    w = rng.normal(0.0, 0.3, (60, 3))
    W, a_th, w_th = 4, 0.3, 0.4
    ref = [max(sum(abs(np.linalg.norm(f[l]) - 9.80665) for l in range(n, n + W)) / (W * a_th),
               sum(np.linalg.norm(w[l]) for l in range(n, n + W)) / (W * w_th)) for n in range(60 - W + 1)]
    got = detect.magnitude_statistic(f, w, W, acc_threshold=a_th, gyro_threshold=w_th)
    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-12
    acc_only = detect.magnitude_statistic(f, None, W, acc_threshold=a_th)
    assert np.all(acc_only <= got + 1e-15) and np.any(acc_only < got)


def test_per_sample_decision_is_openshoes_fill_rule(walk):
    """A window below the threshold marks all its W samples; the per-sample statistic is the
    smallest of the windows holding the sample."""
    d = walk.data
    W, gamma = 5, 150.0  # a threshold inside the stance statistics, so the rule is exercised
    T = detect.shoe_statistic(d.specific_force, d.gyro, W)
    fill = np.zeros(d.n, dtype=bool)
    for k in np.flatnonzero(T < gamma):
        fill[k:k + W] = True
    mask, stat = detect.stationary_mask(d, window=W, threshold=gamma)
    assert np.array_equal(mask, fill) and 0.2 < mask.mean() < 0.6
    assert np.array_equal(mask, stat < gamma)
    k = 700
    assert stat[k] == min(T[max(0, k - W + 1):k + 1])


# ------------------------------------------------------------- the simulated walk
def test_walking_scenario_truth(walk):
    """The foot is exactly still in the stances and moves like a walking foot in between."""
    sim = walk.params["simulation"]
    stance = walk.params["stance"]
    assert len(walk.params["stance_intervals"]) == 11 and 0.45 < stance.mean() < 0.6
    speed = np.linalg.norm(walk.velocity, axis=1)
    rate = np.linalg.norm(sim.body_rate_true, axis=1)
    assert speed[stance].max() < 1e-12 and rate[stance].max() < 1e-12
    assert 3.5 < speed.max() < 6.0 and 4.0 < rate.max() < 10.0
    acc = np.linalg.norm(sim.truth[["ax", "ay", "az"]].to_numpy(), axis=1)
    assert 15.0 < acc.max() < 40.0
    # at rest the sensors read gravity and zero rates, plus the MEMS noise and bias
    f_still = walk.data.specific_force[stance]
    assert abs(np.linalg.norm(f_still, axis=1).mean() - 9.80665) < 0.05
    assert 0.006 < np.std(walk.data.gyro[stance][:, 0]) < 0.010
    assert walk.data.gyro is not None and walk.data.is_strapdown
    # the stride moves the foot ~1.4 m forward: 10 strides, ~14 m
    assert 12.0 < np.linalg.norm(walk.position[-1, :2] - walk.position[0, :2]) < 16.0


@pytest.mark.parametrize("method", ["shoe", "magnitude"])
def test_stance_samples_are_found(walk, method):
    """Precision and recall of the stance samples; measured 0.975 / 1.000 (SHOE) and 0.979 /
    1.000 (magnitude) for seed 1 (0.973-0.985 / 1.000 over seeds 0-7): the only misses are
    the one or two samples at each end of a swing where the foot has barely started moving."""
    stance = walk.params["stance"]
    mask, _ = detect.stationary_mask(walk.data, method)
    precision, recall = precision_recall(mask, stance)
    assert precision >= 0.96 and recall >= 0.995, (precision, recall)


@pytest.mark.parametrize("method", ["shoe", "magnitude"])
def test_intervals_match_the_stance_phases(walk, method):
    truth = np.array(walk.params["stance_intervals"])
    found = detect.stationary(walk.data, method)
    assert len(found) == len(truth)
    iv = np.array(found)
    # within a sample step (0.01 s) or two of the true ends; sorted and disjoint
    assert np.abs(iv - truth).max() < 0.021
    assert np.all(iv[:, 0] < iv[:, 1]) and np.all(iv[1:, 0] > iv[:-1, 1])
    assert all(isinstance(v, float) for pair in found for v in pair)
    assert set(iv.ravel()) <= set(walk.t)


def test_min_duration_drops_short_intervals(walk):
    det = detect.stationary(walk.data, min_duration=1.0, return_statistic=True)
    (a0, a1), (b0, b1) = det.intervals  # the two stands of 1.5 s only
    assert a0 == 0.0 and b1 == walk.t[-1] and 1.49 < a1 - a0 < 1.52 and 1.49 < b1 - b0 < 1.52
    assert len(detect.intervals_from_mask(walk.t, det.mask)) == 11  # the mask keeps the stances
    assert det.window == detect.DEFAULT_WINDOW and det.threshold == detect.SHOE_THRESHOLD
    assert np.array_equal(det.mask, det.statistic < det.threshold)


def test_magnitude_runs_without_gyro(walk):
    sim = walk.params["simulation"]
    data = bvpnav.ImuData(walk.t, specific_force=walk.data.specific_force, attitude=sim.attitude)
    assert data.gyro is None
    mask, _ = detect.stationary_mask(data, "magnitude")
    precision, recall = precision_recall(mask, walk.params["stance"])
    assert precision >= 0.96 and recall >= 0.995
    det = detect.stationary(data, "magnitude", return_statistic=True)
    assert det.params["gyro_threshold"] is None


def test_intervals_from_mask_drops_single_samples():
    t = np.array([0.0, 0.1, 0.3, 0.4, 0.5, 0.9, 1.0])
    mask = np.array([1, 1, 0, 1, 0, 1, 1], dtype=bool)
    assert detect.intervals_from_mask(t, mask) == [(0.0, 0.1), (0.9, 1.0)]
    assert detect.intervals_from_mask(t, mask, min_duration=0.11) == []


# ------------------------------------------------ non-uniform times and a solve
def test_non_uniform_times_feed_zero_velocity_and_a_solve(short_walk):
    """30 % of the samples dropped at random (steps 0.01-0.09 s): the stances are still found,
    and as ZeroVelocity items they pin the drift of a strapdown solve."""
    sim = short_walk.params["simulation"]
    rng = np.random.default_rng(5)
    n = sim.t.size
    keep = np.sort(np.concatenate([[0, n - 1], rng.choice(np.arange(1, n - 1), int(0.7 * n), replace=False)]))
    t = sim.t[keep]
    assert np.ptp(np.diff(t)) > 0.05
    data = bvpnav.ImuData.from_gyro(t, sim.specific_force[keep], sim.gyro[keep],
                                    initial_attitude=sim.attitude[0])
    stance = short_walk.params["stance"][keep]
    for method in ("shoe", "magnitude"):
        precision, recall = precision_recall(detect.stationary_mask(data, method)[0], stance)
        assert precision >= 0.95 and recall >= 0.99, (method, precision, recall)
    intervals = detect.stationary(data)
    assert len(intervals) == 5
    items = detect.zero_velocity_items(intervals, sigma=0.01, name="stance")
    assert all(isinstance(z, ZeroVelocity) for z in items) and items[2].name == "stance 2"
    assert [(z.t0, z.t1) for z in items] == intervals
    truth = sim.position(t)
    start = Position(t=0.0, value=truth[0])

    prob = bvpnav.NavigationProblem(data, sigma_a=0.03).add(start, *items)
    sol = prob.solve()
    assert sol.stats["verified"]
    err = np.abs(sol.position() - truth).max()
    free = bvpnav.NavigationProblem(data, sigma_a=0.03).add(start, bvpnav.constraints.Velocity(
        t=0.0, value=[0.0, 0.0, 0.0])).solve()
    err_free = np.abs(free.position() - truth).max()
    # measured 0.009 m with the detected stances, 0.5 m without
    assert err < 0.03 and err < 0.1 * err_free, (err, err_free)
    speed = np.linalg.norm(sol.velocity(), axis=1)
    inside = np.zeros(t.size, dtype=bool)
    for t0, t1 in intervals:
        inside |= (t >= t0) & (t <= t1)
    assert speed[inside].max() < 0.05 and speed.max() > 3.0


def test_zero_velocity_items_take_a_detection(short_walk):
    det = detect.stationary(short_walk.data, return_statistic=True)
    items = detect.zero_velocity_items(det, mode="soft", sigma=0.02)
    assert len(items) == len(det.intervals) == 5
    assert all(z.mode == "soft" and z.sigma == 0.02 and z.name is None for z in items)


# ------------------------------------------------------------------------ errors
def _data(walk, **kw):
    return bvpnav.ImuData.from_gyro(walk.t[:50], walk.data.specific_force[:50], walk.data.gyro[:50], **kw)


BAD = {
    "no gyro for shoe": (lambda w: (bvpnav.ImuData(w.t[:50], specific_force=w.data.specific_force[:50],
                                                   attitude=Rotation.identity(50)), {}),
                         ["data.gyro is None", "ImuData.from_gyro", "method='magnitude'"]),
    "navigation frame only": (lambda w: (bvpnav.ImuData(w.t[:50], np.zeros((50, 3))), {}),
                              ["navigation-frame accelerations only", "specific force", "from_gyro"]),
    "navigation frame magnitude": (lambda w: (bvpnav.ImuData(w.t[:50], np.zeros((50, 3))),
                                              {"method": "magnitude"}), ["method='magnitude' needs"]),
    "not ImuData": (lambda w: (w.data.specific_force, {}), ["got ndarray", "bvpnav.ImuData"]),
    "window > N": (lambda w: (_data(w), {"window": 51}), ["window=51", "longer than the data (50",
                                                          "at most 50"]),
    "window 1": (lambda w: (_data(w), {"window": 1}), ["at least 2 samples"]),
    "window in s": (lambda w: (_data(w), {"window": 0.1}), ["whole number of samples"]),
    "threshold 0": (lambda w: (_data(w), {"threshold": 0.0}), ["threshold=0.0", "> 0"]),
    "threshold negative": (lambda w: (_data(w), {"threshold": -3.0}), ["threshold=-3.0", "> 0"]),
    "threshold nan": (lambda w: (_data(w), {"threshold": float("nan")}), ["threshold=nan"]),
    "sigma_a 0": (lambda w: (_data(w), {"sigma_a": 0}), ["sigma_a=0", "m/s^2"]),
    "sigma_w text": (lambda w: (_data(w), {"sigma_w": "small"}), ["sigma_w='small'", "rad/s"]),
    "acc_threshold negative": (lambda w: (_data(w), {"method": "magnitude", "acc_threshold": -1}),
                               ["acc_threshold=-1"]),
    "gyro_threshold 0": (lambda w: (_data(w), {"method": "magnitude", "gyro_threshold": 0.0}),
                         ["gyro_threshold=0.0"]),
    "gravity 0": (lambda w: (_data(w), {"gravity": 0.0}), ["gravity=0.0"]),
    "shoe with acc_threshold": (lambda w: (_data(w), {"acc_threshold": 0.3}),
                                ["acc_threshold", "method='magnitude'", "threshold="]),
    "magnitude with threshold": (lambda w: (_data(w), {"method": "magnitude", "threshold": 3e4}),
                                 ["threshold", "method='shoe'", "acc_threshold="]),
    "gyro_threshold without gyro": (
        lambda w: (bvpnav.ImuData(w.t[:50], specific_force=w.data.specific_force[:50],
                                  attitude=Rotation.identity(50)),
                   {"method": "magnitude", "gyro_threshold": 0.5}),
        ["data.gyro is None", "gyro_threshold=None"]),
    "unknown method": (lambda w: (_data(w), {"method": "zupt"}), ["method='zupt'", "'shoe'", "'magnitude'"]),
    "min_duration negative": (lambda w: (_data(w), {"min_duration": -0.1}), ["min_duration=-0.1", ">= 0"]),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_input_names_the_problem_and_the_fix(walk, case):
    build, words = BAD[case]
    data, kw = build(walk)
    method = kw.pop("method", "shoe")
    with pytest.raises(InputError) as err:
        detect.stationary(data, method, **kw)
    for word in words:
        assert word in str(err.value), (word, str(err.value))


# ---------------------------------------------------------------------- figure
def test_plot_shows_statistic_threshold_and_intervals(short_walk, tmp_path):
    det = detect.stationary(short_walk.data, return_statistic=True)
    path = tmp_path / "stationary.png"
    fig = plot.stationary(short_walk.data, det, path=path)
    assert path.stat().st_size > 10_000
    stat_ax, force_ax, rate_ax = fig.axes
    assert [a.get_title() for a in fig.axes] == ["statistic", "specific force", "angular rate"]
    assert stat_ax.get_yscale() == "log" and rate_ax.get_yscale() == "log"
    threshold = [ln for ln in stat_ax.get_lines() if ln.get_linestyle() == "--"]
    assert len(threshold) == 1 and threshold[0].get_ydata()[0] == detect.SHOE_THRESHOLD
    assert len(stat_ax.patches) == len(det.intervals) == 5  # one shaded span per interval
    assert np.allclose(stat_ax.get_lines()[0].get_ydata(), det.statistic)
    plt.close(fig)
    # from intervals only: the statistic is computed with the given method and settings
    fig = plot.stationary(short_walk.data, det.intervals[:2], method="magnitude", window=4)
    assert len(fig.axes[0].patches) == 2 and "window 4" in fig._suptitle.get_text()
    assert [ln.get_ydata()[0] for ln in fig.axes[0].get_lines() if ln.get_linestyle() == "--"] == [1.0]
    plt.close(fig)
    no_gyro = bvpnav.ImuData(short_walk.t, specific_force=short_walk.data.specific_force,
                             attitude=short_walk.params["simulation"].attitude)
    fig = plot.stationary(no_gyro, detect.stationary(no_gyro, "magnitude", return_statistic=True))
    assert [a.get_title() for a in fig.axes] == ["statistic", "specific force"]
    plt.close(fig)
