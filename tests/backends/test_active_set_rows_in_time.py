"""The active set adds, of the violated rows, those that peak among their neighbours in time:
for an item with several axes (rows time-major, the axes interleaved) the neighbours are the
same axis's rows at the instants before and after, not the next row of ``G``. Checked on the
quadratic program's row bookkeeping and against Clarabel on a two-axis velocity band."""

from __future__ import annotations

import numpy as np
from _helpers import quintic

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.linalg import active_set as AS
from bvpnav.linalg.ipm import quadratic_form


def plane_band(n=401, tol=0.1, noise=0.05, seed=5):
    """The quintic on x and its mirror image on y (biased, noisy accelerometers), both ends
    fixed, the cubic prior as soft positions, and a velocity band on both axes at every sample
    around the true velocity plus noise: the bias presses the path against the band at many
    samples of both axes."""
    p, v, a = quintic()
    t = np.linspace(0.0, 10.0, n)
    rng = np.random.default_rng(seed)
    acc = np.column_stack([1.05 * a(t) + rng.normal(-0.5, 1.0, n), -0.95 * a(t) + rng.normal(0.4, 1.0, n)])
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc, axes=("x", "y")))
    ends = np.array([[0.0, 0.0], [10.0, -10.0]])
    vm = np.column_stack([v(t), -v(t)]) + rng.normal(0.0, noise, (n, 2))
    return prob.add(Position(t=[0.0, 10.0], value=ends, name="ends"),
                    Position(t=[0.1, 9.9], value=[[p(0.1), -p(0.1)], [p(9.9), -p(9.9)]], sigma=1.0,
                             name="prior"),
                    Velocity(t=t, value=vm, mode="band", tol=tol, name="vel"))


def test_rows_know_their_neighbours_in_time():
    """A band of 2 axes at 401 instants: 802 rows per side, upper side first; row 2k + a is
    axis a at instant k, its neighbours 2(k -+ 1) + a, none across the ends or the sides."""
    prob = plane_band()
    qp = quadratic_form(prob.formulation, 1.0)
    (label, (up, low)), = qp.ineq_blocks
    assert label == "vel" and (up.start, up.stop, low.start, low.stop) == (0, 802, 802, 1604)
    i = np.arange(1604)
    k, a = (i % 802) // 2, i % 2
    np.testing.assert_array_equal(qp.before, np.where(k > 0, i - 2, -1))
    np.testing.assert_array_equal(qp.after, np.where(k < 400, i + 2, -1))
    # the rows of one side, one axis: the same base row's sign flips between the sides
    np.testing.assert_array_equal(qp.base_of[:802], qp.base_of[802:])
    assert np.all(a[qp.before[qp.before >= 0]] == a[qp.before >= 0])


def test_peaks_compare_each_axis_with_itself():
    """Values alternating between two axes (axis 0 rising to a peak at instant 5, axis 1 ten
    times larger and flat): the peaks are axis 0's instant 5 and every instant of axis 1
    (equal neighbours count), never a row for being above the other axis's row."""
    prob = plane_band(n=11)
    qp = quadratic_form(prob.formulation, 1.0)
    k = np.arange(11)
    side = np.empty(22)
    side[0::2] = -np.abs(k - 5.0)
    side[1::2] = 10.0
    r = np.concatenate([side, side])
    peaks = AS._peaks(qp, r)
    expect = np.zeros(22, dtype=bool)
    expect[10] = True
    expect[1::2] = True
    np.testing.assert_array_equal(peaks, np.concatenate([expect, expect]))


def test_two_axis_band_matches_clarabel():
    """The active set's answer on the two-axis band equals Clarabel's to 1e-8 of the largest
    unknown, verified, with rows of both axes at their bounds; and the KKT multipliers are
    nonnegative."""
    prob = plane_band()
    d = prob.solve(solver="direct", lam=1.0, accuracy="high", fallback=None, options={"qp": "active set"})
    c = prob.solve(solver="clarabel", lam=1.0, accuracy="high", fallback=None)
    assert d.stats["verified"] and d.stats["qp_method"] == "active set"
    np.testing.assert_allclose(d.x, c.x, rtol=0, atol=1e-8 * np.max(np.abs(c.x)))
    x, info = AS.solve_bands(prob.formulation, 1.0, tol=1e-10, qp_method="active set")
    np.testing.assert_array_equal(x, d.x)
    up, low = info["duals"]["vel"]
    assert min(up.min(), low.min()) >= 0.0
    pressed = (up > 0) | (low > 0)
    assert pressed[0::2].sum() >= 5 and pressed[1::2].sum() >= 5, (pressed[0::2].sum(), pressed[1::2].sum())


def test_loop_band_memory_reused_with_the_same_answers():
    """A loop's ``band_buffer`` (the node-state loop gives one): the assembled band and each
    pass's copy live in its two halves, solve after solve, and the answers are bitwise those
    of solves in fresh memory (one solve, then the next from its rows and plan)."""
    from bvpnav.linalg import ipm
    from bvpnav.linalg.workspace import Workspace

    prob = plane_band()
    form = prob.formulation
    fresh, loop = Workspace(), Workspace(band_buffer=np.empty(0))
    seen = []
    made = ipm.MultiplierBand.__init__

    def spy(self, *a, **k):
        made(self, *a, **k)
        seen.append((self.scaled0, self._buffer))

    ipm.MultiplierBand.__init__ = spy
    try:
        answers = []
        for ws in (fresh, fresh, loop, loop):
            x, info = AS.solve_bands(form, 1.0, tol=1e-10, workspace=ws, qp_method="active set")
            answers.append((x, info["active_set"]))
    finally:
        ipm.MultiplierBand.__init__ = made
    assert answers[0][1] == answers[2][1] and answers[1][1] == answers[3][1] == "0 updates from the last " \
                                                                              "solve's rows"
    np.testing.assert_array_equal(answers[0][0], answers[2][0])
    np.testing.assert_array_equal(answers[1][0], answers[3][0])
    buf = loop.band_buffer
    half = buf.size // 2
    for _band, copy in seen[2:]:
        assert np.shares_memory(copy, buf[half:]) and not np.shares_memory(copy, buf[:half])
    # the second solve reuses the plan: its assembly is in the first half too
    assert np.shares_memory(seen[3][0], buf[:half])
    for band, copy in seen[:2]:
        assert not np.shares_memory(copy, buf) and not np.shares_memory(band, buf)
