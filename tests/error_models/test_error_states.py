"""ErrorStates: attitude error and random-walk biases as node states in the band (issue 42 item 2).

The drives are simulated with the model's own discretization (the attitude by
:math:`C_{j+1} = C_j \\exp([\\phi_j(\\hat\\omega) - h_j b_{g,j}]\\times)`, positions by exact
integration of an acceleration linear between samples), so that with constant biases the
truth has zero residual in every row and must be recovered to rounding.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.spatial.transform import Rotation

import bvpnav
from bvpnav.attitude import step_rotation_vectors
from bvpnav.constraints import Position
from bvpnav.error_models import ErrorStates, GyroBias
from bvpnav.errors import InputError
from bvpnav.log import BvpnavWarning

GRAV = np.array([0.0, 0.0, -9.80665])


def simulate(bg, ba, T=20.0, rate=20.0, seed=0, turn=5.0):
    """A noise-free strapdown drive on an irregular grid: true biases ``bg(t)`` (rad/s) and
    ``ba(t)`` (m/s^2), body rates up to ``turn`` x (0.05, 0.04, 0.2) rad/s."""
    rng = np.random.default_rng(seed)
    n = int(T * rate) + 1
    t = np.linspace(0.0, T, n) + np.r_[0.0, rng.uniform(-0.2, 0.2, n - 2) / rate, 0.0]
    h = np.diff(t)
    a = np.column_stack([0.8 * np.sin(0.3 * t), 0.6 * np.cos(0.2 * t), 0.2 * np.sin(0.5 * t)])
    w = turn * np.column_stack([0.05 * np.sin(0.7 * t), 0.04 * np.cos(0.5 * t),
                                0.15 * np.sin(0.2 * t) + 0.05])
    Bg, Ba = bg(t), ba(t)
    raw_w = w + Bg
    phi = step_rotation_vectors(t, raw_w) - h[:, None] * Bg[:-1]
    C = [Rotation.from_euler("ZYX", [0.4, 0.02, -0.01])]
    for k in range(n - 1):
        C.append(C[-1] * Rotation.from_rotvec(phi[k]))
    C = Rotation.concatenate(C)
    f = C.inv().apply(a - GRAV) + Ba
    v = np.zeros((n, 3))
    r = np.zeros((n, 3))
    v[0] = [10.0, 1.0, 0.0]
    for k in range(n - 1):
        v[k + 1] = v[k] + h[k] * (a[k] + a[k + 1]) / 2
        r[k + 1] = r[k] + h[k] * v[k] + h[k] ** 2 * (2 * a[k] + a[k + 1]) / 6
    data = bvpnav.ImuData.from_gyro(t, f, raw_w, initial_attitude=C[0], gravity=GRAV)
    return {"t": t, "data": data, "C": C, "r": r, "bg": Bg, "ba": Ba}


def const(v):
    return lambda t: np.tile(v, (t.size, 1))


BG = [1e-3, -5e-4, 2e-4]
BA = [0.05, -0.03, 0.02]


def problem(d, model, every=4, fix_sigma=1e-4, sigma_a=1e-4):
    k = np.arange(0, d["t"].size, every)
    prob = bvpnav.NavigationProblem(d["data"], error_model=model, sigma_a=sigma_a)
    return prob.add(Position(t=d["t"][k], value=d["r"][k], sigma=fix_sigma))


def errors(sol, d):
    es = sol.error_states
    return {"bg": np.abs(es.filter(like="gyro_bias").to_numpy() - d["bg"]).max(),
            "ba": np.abs(es.filter(like="acc_bias").to_numpy() - d["ba"]).max(),
            "att": np.abs((sol.attitude * d["C"].inv()).as_rotvec()).max(),
            "r": np.abs(sol.position() - d["r"]).max()}


@pytest.mark.parametrize("drift", [(0.0, 0.0), (1e-4, 1e-3)], ids=["constant", "walk"])
def test_constant_biases_and_attitude_recovered_to_rounding(drift):
    # the truth zeroes every row (process rows included), so the optimum is the truth
    d = simulate(const(BG), const(BA))
    model = ErrorStates(arw=1e-5, gyro_drift=drift[0], acc_drift=drift[1])
    sol = problem(d, model).solve(solver="direct", attitude={"progress": False})
    e = errors(sol, d)
    assert e["bg"] < 1e-10 and e["ba"] < 1e-9 and e["att"] < 1e-9 and e["r"] < 1e-9, e
    rep = sol.records.attitude
    assert rep.kind == "states" and rep.converged and len(rep.iterations) <= 6
    # the heading was 0.4 rad and the gyro bias 1e-3 rad/s: the first step is large, the last tiny
    assert rep.iterations[0]["step"] > 1e-3 > 1e-7 > rep.iterations[-1]["step"]
    assert sol.stats["verified"]
    assert sol.stats["factorization"].startswith("banded") and "border 0" in sol.stats["factorization"]


def test_drifting_biases_recovered_within_their_posterior():
    # biases that are random walks of the stated densities (seeded); noise-free otherwise, so the
    # estimate's error is the posterior's: within a few standard deviations everywhere
    rng = np.random.default_rng(3)
    qg, qa = 2e-5, 2e-3
    n = 401
    wg = np.cumsum(rng.standard_normal((n, 3)), axis=0) * qg * np.sqrt(0.05)
    wa = np.cumsum(rng.standard_normal((n, 3)), axis=0) * qa * np.sqrt(0.05)
    d = simulate(lambda t: np.asarray(BG) + wg[:t.size], lambda t: np.asarray(BA) + wa[:t.size])
    model = ErrorStates(arw=1e-5, gyro_drift=qg, acc_drift=qa)
    sol = problem(d, model, every=2, fix_sigma=1e-3).solve(solver="direct", attitude={"progress": False},
                                                            uncertainty=True)
    es, sd = sol.error_states, sol.error_states_std
    assert list(sd.columns) == list(es.columns)
    zg = (es.filter(like="gyro_bias").to_numpy() - d["bg"]) / sd.filter(like="gyro_bias").to_numpy()
    za = (es.filter(like="acc_bias").to_numpy() - d["ba"]) / sd.filter(like="acc_bias").to_numpy()
    # measured: max |z| 2.0 and 2.7, RMS z 0.89 and 1.06 (one realization: its errors are correlated)
    assert np.abs(zg).max() < 5.0 and np.abs(za).max() < 5.0, (np.abs(zg).max(), np.abs(za).max())
    for z in (zg, za):
        assert 0.3 < np.sqrt(np.mean(z**2)) < 2.5
    assert sol.records.attitude.converged


def test_quick_intermediate_steps_give_the_staged_answer():
    # noisy rates, forces and fixes (residuals left at the optimum): Gauss-Newton converges
    # linearly over several steps, the middle ones one banded solve each (no refinement, no
    # verification); every step through the stage gives the same answer to rounding, verified
    rng = np.random.default_rng(5)
    d = simulate(const(BG), const(BA), T=20.0, turn=8.0)
    n, data = d["t"].size, d["data"]
    noisy = bvpnav.ImuData.from_gyro(d["t"], data.specific_force + 2e-2 * rng.standard_normal((n, 3)),
                                     data.gyro + 2e-3 * rng.standard_normal((n, 3)),
                                     initial_attitude=d["C"][0], gravity=GRAV)
    drive = {**d, "data": noisy, "r": d["r"] + 1e-2 * rng.standard_normal((n, 3))}
    model = ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-4, acc_drift=1e-3)
    sols = {}
    for quick in (True, False):
        prob = problem(drive, model, every=20, fix_sigma=1e-2, sigma_a=2e-2)
        sols[quick] = prob.solve(solver="direct", attitude={"progress": False, "quick": quick})
    fast, slow = sols[True].records.attitude, sols[False].records.attitude
    kinds = [it["solve"] for it in fast.iterations]
    # a fixed lambda: the first step is one banded solve too (the problem is checked before
    # it); the answer goes through the stage
    assert kinds[0] == "banded" and kinds[-1] == "stage", kinds
    assert {it["solve"] for it in slow.iterations} == {"stage"}
    assert fast.converged and slow.converged and len(fast.iterations) == len(slow.iterations) >= 4
    x, y = sols[True].x, sols[False].x
    assert np.abs(x - y).max() <= 1e-9 * np.abs(y).max(), np.abs(x - y).max() / np.abs(y).max()
    assert sols[True].stats["verified"] and sols[False].stats["verified"]


def test_an_undetermined_problem_is_refused_before_the_first_banded_step():
    # one fix leaves the velocity free: the loop whose first step is one banded solve refuses it
    # with the stage's words, before any step
    d = simulate(const(BG), const(BA), T=2.0)
    messages = []
    for quick in (True, False):
        prob = bvpnav.NavigationProblem(d["data"], error_model=ErrorStates(arw=1e-5, gyro_drift=1e-4,
                                                                           acc_drift=1e-3), sigma_a=1e-3)
        prob.add(Position(t=[0.0], value=[d["r"][0]], sigma=1e-2))
        with pytest.raises(InputError, match="nothing determines axis x: velocity offset") as err:
            prob.solve(solver="direct", attitude={"progress": False, "quick": quick})
        messages.append(str(err.value))
    assert messages[0] == messages[1]


def test_a_plan_made_where_rows_had_exact_zeros_serves_the_filled_rows():
    # the first Gauss-Newton step's process rows have exact zeros (zero residual: identity
    # Jacobians) that later steps fill: the first plan serves them (same answer as a fresh
    # plan), and refuses rows that reach beyond its band or change what is eliminated
    from bvpnav.linalg.banded import BandedKKT, BandPlan
    from bvpnav.linalg.lsq import column_nodes, least_squares_form

    d = simulate(const(BG), const(BA), T=2.0)
    model = ErrorStates(arw=1e-4, gyro_drift=1e-4, acc_drift=1e-3, attitude_sigma=0.1)
    form = problem(d, model, every=5).formulation
    ls = least_squares_form(form, 1.0)
    D, E = ls.D.A.tocsr(), ls.E.A.tocsr()
    colnode = column_nodes(form.model, interleave=True)
    process = np.flatnonzero(np.diff(D.indptr) == 9)   # the attitude process rows: 3 x 3 blocks
    rows = process[15:27]                                  # nodes 5 to 8
    s0 = form.model.s_index[0]
    D0 = D.copy()
    for r in rows:   # each block's diagonal alone: the rows as at a zero residual (identity Jacobians)
        seg = np.arange(D0.indptr[r], D0.indptr[r + 1])
        D0.data[seg[(D0.indices[seg] - s0) % 3 != (r - process[0]) % 3]] = 0.0
    D0.eliminate_zeros()
    assert D0.nnz == D.nnz - 12 * 6
    plan = BandPlan.build(D0, E, colnode, lam_rows=ls.lam_rows)
    served = plan.admitting(D, E, colnode, ls.lam_rows)
    assert served is not None and served.nnz_D == D.nnz and plan.nnz_D == D0.nnz
    rhs = ls.rhs()
    m, n = D.shape
    x = BandedKKT(D, E, params=form.model.l_index, plan=served).refined(rhs, 3)[0][m:m + n]
    ref = BandedKKT(D, E, colnode, params=form.model.l_index).refined(rhs, 3)[0][m:m + n]
    dense = np.linalg.solve(ls.augmented().toarray(), rhs)[m:m + n]
    for y in (x, ref):
        assert np.abs(y - dense).max() <= 1e-9 * np.abs(dense).max(), np.abs(y - dense).max()
    # a row coupling states three nodes apart: still folded, but beyond the plan's band
    far = D.tolil()
    r = int(rows[0])
    far[r, form.model.s_index[9 * 3 + 1]] = 1.0
    assert plan.admitting(far.tocsr(), E, colnode, ls.lam_rows) is None
    # a second entry in a row alone on an eliminated unknown: the unknown is kept
    lone = np.flatnonzero(np.diff(D.indptr) == 1)
    el = int(D.indices[D.indptr[lone[0]]])
    assert el in set(plan.elim)
    other = D.tolil()
    other[int(lone[0]), int(form.model.s_index[0])] = 1.0
    assert plan.admitting(other.tocsr(), E, colnode, ls.lam_rows) is None


def test_linearized_solve_equals_dense_reference():
    from bvpnav.linalg.lsq import banded_plan, least_squares_form

    d = simulate(const(BG), const(BA), T=3.0)
    model = ErrorStates(arw=1e-4, gyro_drift=1e-4, acc_drift=1e-3, attitude_sigma=[0.1, 0.1, np.inf],
                        gyro_sigma=1e-3, acc_sigma=0.1)
    sol = problem(d, model, every=5, fix_sigma=1e-2, sigma_a=1e-2).solve(solver="direct",
                                                                         attitude={"loop": False})
    form = sol.formulation
    assert form.model.ns == 9 * d["t"].size
    ls = least_squares_form(form, float(sol.lam))
    plan = banded_plan(ls, form)
    assert plan.border == 0 and plan.kl <= 60
    S = ls.augmented().toarray()
    z = np.linalg.solve(S, ls.rhs())
    m, n = ls.D.A.shape
    x = z[m:m + n]
    rel = np.abs(sol.x - x).max() / np.abs(x).max()
    assert rel < 1e-8, rel
    assert np.abs(sol.x[form.model.s_index]).max() > 1e-3   # the states did move
    # the cvxpy path (Clarabel) on the same rows
    other = problem(d, model, every=5, fix_sigma=1e-2, sigma_a=1e-2).solve(
        solver="clarabel", accuracy="high", attitude={"loop": False})
    assert np.abs(other.x - x).max() / np.abs(x).max() < 1e-8
    # the problem's description and matrices name the state block
    prob = problem(d, model, every=5, fix_sigma=1e-2, sigma_a=1e-2)
    assert "node states at every sample: attitude_error, gyro_bias, acc_bias" in str(prob.describe())
    assert prob.matrices().layout["s"] == slice(form.model.s_index[0], form.model.size)


def test_uncertainty_matches_dense_inverse():
    from bvpnav.linalg.lsq import least_squares_form

    d = simulate(const(BG), const(BA), T=2.0)
    model = ErrorStates(arw=1e-4, gyro_drift=1e-4, acc_drift=1e-3, attitude_sigma=0.1, gyro_sigma=1e-3,
                        acc_sigma=0.1)
    sol = problem(d, model, every=5, fix_sigma=1e-2, sigma_a=1e-2).solve(
        solver="direct", attitude={"loop": False}, uncertainty=True)
    form = sol.formulation
    ls = least_squares_form(form, float(sol.lam))
    # covariance of x: the x block of the inverse of the augmented matrix (eliminating the
    # residuals leaves [[D^T D, E^T], [E, 0]], whose inverse's x block it is)
    S = ls.augmented().toarray()
    m, n = ls.D.A.shape
    cov = np.linalg.inv(S)[m:m + n, m:m + n]
    mod = form.model
    sm = mod.state_model
    for kind in ("attitude_error", "gyro_bias", "acc_bias"):
        idx = mod.s_index[sm.state_index(mod.data, kind)]
        ref = np.sqrt(np.diag(cov)[idx])
        got = sol.error_states_std.filter(like=kind).to_numpy()
        np.testing.assert_allclose(got, ref, rtol=1e-6)
    ref_x = np.sqrt(np.diag(cov)[mod.r_index(0)])
    np.testing.assert_allclose(sol.trajectory["x_std"].to_numpy(), ref_x, rtol=1e-6, atol=1e-12)


def test_accessors_read_the_states():
    d = simulate(const(BG), const(BA), T=1.0)
    model = ErrorStates(arw=1e-4, gyro_drift=1e-4, acc_drift=1e-3)
    nav = bvpnav.NavModel(d["data"], model)
    x = np.zeros(nav.size)
    sm = nav.state_model
    x[nav.s_index[sm.state_index(nav.data, "gyro_bias")]] = np.arange(3 * nav.N).reshape(nav.N, 3) * 1e-3
    t = [0.0, 0.5 * (nav.grid.t[3] + nav.grid.t[4])]
    gb = nav.gyro_bias(t).value(x).reshape(2, 3)
    np.testing.assert_allclose(gb[0], [0.0, 1e-3, 2e-3])
    np.testing.assert_allclose(gb[1], 0.5 * (np.array([9, 10, 11]) + np.array([12, 13, 14])) * 1e-3,
                               rtol=0.3)   # linear between the nodes at the midpoint's time
    w = nav.body_rate([0.0], "z").value(x)
    assert w[0] == pytest.approx(d["data"].gyro[0, 2] - 2e-3)
    with pytest.raises(InputError, match="no 'acc_bias' node state"):
        bvpnav.NavModel(d["data"], ErrorStates(arw=1e-4)).acc_bias()


def test_body_rate_takes_the_gyro_bias_totals_and_the_increments():
    # at a linearization point whose gyro-bias totals are b0, the rate is the measured one less
    # b0 less the step's increment: omega = omega_hat - (b0 + delta b)
    from bvpnav.error_models.error_states import states_at

    d = simulate(const(BG), const(BA), T=1.0)
    model = ErrorStates(arw=1e-4, gyro_drift=1e-4, acc_drift=1e-3)
    raw = d["data"]
    b0 = np.array([1e-3, -2e-3, 4e-3])
    totals = {k: np.zeros((raw.n, 3)) for k in model.state_kinds(raw)}
    totals["gyro_bias"] = np.tile(b0, (raw.n, 1))
    nav = bvpnav.NavModel(states_at(raw, totals), model)
    x = np.zeros(nav.size)
    x[nav.s_index[nav.state_model.state_index(nav.data, "gyro_bias")]] = 5e-4
    w = nav.body_rate([0.0, 0.5]).value(x).reshape(2, 3)
    ref = np.array([[np.interp(tk, raw.t, raw.gyro[:, a]) for a in range(3)] for tk in (0.0, 0.5)])
    np.testing.assert_allclose(w, ref - b0 - 5e-4, rtol=0, atol=1e-12)


def test_bad_options_are_named():
    with pytest.raises(InputError, match="arw"):
        ErrorStates()
    with pytest.raises(InputError, match="gyro_drift"):
        ErrorStates(arw=1e-4, gyro_drift=-1.0)
    with pytest.raises(InputError, match="attitude_sigma"):
        ErrorStates(arw=1e-4, attitude_sigma=[1.0, 2.0])
    d = simulate(const(BG), const(BA), T=1.0)
    prob = problem(d, ErrorStates(arw=1e-4) + GyroBias())
    with pytest.raises(InputError, match="leave those models out"):
        prob.solve(solver="direct")


def test_contract_check_catches_a_state_column_away_from_its_node():
    from dataclasses import dataclass

    import scipy.sparse as sp

    from bvpnav.testing import check_error_model

    @dataclass(frozen=True, kw_only=True, eq=False, repr=False)
    class Shifted(ErrorStates):
        def state_columns(self, data):   # every column one sample late: not local
            return [sp.csr_matrix(sp.vstack([sp.csr_matrix((1, g.shape[1])), g[:-1]]))
                    for g in super().state_columns(data)]

    check_error_model(ErrorStates)
    with pytest.raises(AssertionError, match="rule 'state columns' broken"):
        check_error_model(Shifted(arw=1e-3, gyro_drift=1e-4))


def test_lambda_rule_on_the_state_layout():
    # the rule's sweep runs on the banded state layout at the first linearization; the later steps
    # keep its lambda. Noise-free constant biases: whatever lambda, the truth zeroes every row
    d = simulate(const(BG), const(BA), T=2.0)
    prob = problem(d, ErrorStates(arw=1e-5, gyro_drift=1e-4, acc_drift=1e-3), fix_sigma=1e-2, sigma_a=1e-3)
    sol = prob.solve(lam="gcv", solver="direct", attitude={"progress": False})
    assert sol.lam_rule == "gcv (first evaluation)" and 0 < sol.lam < np.inf
    assert sol.curve is not None and sol.records.attitude.converged
    assert np.abs(sol.position() - d["r"]).max() < 1e-9


def test_anderson_mixing_finds_the_limit_of_a_linear_iteration_with_two_modes():
    from bvpnav.solve.attitude import _anderson

    # g(x) = x* + R (x - x*) with R of two modes (ratios 0.6 and -0.5) on two kinds of state
    # of different units: after three steps the mixed point is the limit x* (to rounding),
    # where the last plain step is still 0.36 of the first error off
    rng = np.random.default_rng(2)
    n = 5
    U = np.linalg.qr(rng.standard_normal((6 * n, 2)))[0]
    R = U @ np.diag([0.6, -0.5]) @ U.T
    scale = np.r_[np.full(3 * n, 1e-3), np.full(3 * n, 1.0)]   # rad and m/s^2
    xs = rng.standard_normal(6 * n) * scale
    x = xs + (U @ [1.0, 1.0]) * scale
    history = []
    for _ in range(3):
        g = xs + scale * (R @ ((x - xs) / scale))
        history.append((x, g))
        x = g
    mixed, gam = _anderson(history, n)
    assert np.abs((mixed - xs) / scale).max() < 1e-12
    assert np.abs((history[-1][1] - xs) / scale).max() > 0.1
    assert _anderson(history[:1], n) is None


def test_a_misfit_loop_is_accelerated_to_the_same_answer_in_fewer_steps(monkeypatch):
    # rates and forces 10 times noisier than sigma_a says (a misfit, as on the KITTI drive):
    # Gauss-Newton alternates along one line, shrinking by about 0.54 a step; Anderson mixing of
    # the last steps reaches the answer of the plain loop (both stop below tol) in fewer steps
    import bvpnav.solve.attitude as stage

    rng = np.random.default_rng(5)
    d = simulate(const(BG), const(BA), T=60.0, turn=15.0)
    n, data = d["t"].size, d["data"]
    noisy = bvpnav.ImuData.from_gyro(d["t"], data.specific_force + 0.3 * rng.standard_normal((n, 3)),
                                     data.gyro + 0.03 * rng.standard_normal((n, 3)),
                                     initial_attitude=d["C"][0], gravity=GRAV)
    drive = {**d, "data": noisy, "r": d["r"] + 1e-2 * rng.standard_normal((n, 3))}
    model = ErrorStates(arw=0.03 / np.sqrt(20.0), gyro_drift=1e-4, acc_drift=1e-3)
    sols = {}
    for mixed in (True, False):
        if not mixed:
            monkeypatch.setattr(stage, "_anderson", lambda history, n: None)
        with pytest.warns(BvpnavWarning, match="misfit"):
            sols[mixed] = problem(drive, model, every=100, fix_sigma=1e-2, sigma_a=0.03).solve(
                solver="direct", attitude={"progress": False})
    fast, slow = sols[True], sols[False]
    it_fast, it_slow = fast.records.attitude.iterations, slow.records.attitude.iterations
    assert fast.records.attitude.converged and slow.records.attitude.converged
    # measured: 11 steps against 22
    assert len(it_fast) <= 0.6 * len(it_slow), (len(it_fast), len(it_slow))
    assert any("accelerated" in it for it in it_fast) and not any("accelerated" in it for it in it_slow)
    # the answer is a Gauss-Newton step below tol in both: the same to the loop's tolerance
    # (measured: 3e-10 relative, 2e-7 m, 2e-8 (rad, rad/s, m/s^2))
    assert np.abs(fast.x - slow.x).max() <= 1e-8 * np.abs(slow.x).max()
    assert np.abs(fast.position() - slow.position()).max() < 1e-5
    assert np.abs(fast.error_states.to_numpy() - slow.error_states.to_numpy()).max() < 1e-6
    assert fast.stats["verified"] and slow.stats["verified"]


@pytest.mark.parametrize("lengths", [[7, 8, 8, 6, 8], [1, 30, 2, 2, 5], [12]])
def test_segment_products_are_the_element_products(lengths):
    """The mesh's per-step products ``R_s ... R_i`` from each element's first step: equal to the
    product taken one step at a time, whether the elements are of similar lengths (the padded
    scan) or not (the indexed scan)."""
    from bvpnav.error_models.error_states import _segment_products

    rng = np.random.default_rng(3)
    m = sum(lengths)
    steps = Rotation.from_rotvec(0.3 * rng.standard_normal((m, 3)))
    first = np.cumsum([0] + lengths[:-1])
    start = np.repeat(first, lengths)
    got = Rotation.from_quat(_segment_products(steps.as_quat(), start).T)
    for i in range(m):
        want = steps[start[i]]
        for j in range(start[i] + 1, i + 1):
            want = want * steps[j]
        assert (got[i] * want.inv()).magnitude() < 1e-13


def test_quaternion_components_are_scipys_bit_for_bit():
    """The unit quaternions and rotation matrices the coarse mesh's elements write out on
    component arrays (no rotation objects) are scipy's ``Rotation.from_quat`` / ``as_matrix``,
    bit for bit: near the identity, at any norm, and with a negative scalar part."""
    from bvpnav.error_models.error_states import _matrix_components, _unit_components

    rng = np.random.default_rng(5)
    q = rng.standard_normal((500, 4)) * rng.uniform(0.5, 2.0, (500, 1))
    q[:100] = [0.0, 0.0, 0.0, 1.0] + 1e-9 * rng.standard_normal((100, 4))
    want = Rotation.from_quat(q)
    unit = _unit_components(np.ascontiguousarray(q.T))
    assert np.array_equal(unit, want.as_quat().T)
    assert np.array_equal(_matrix_components(unit), want.as_matrix().transpose(1, 2, 0))


def test_right_jacobian_components_are_the_right_jacobian():
    """The steps' right Jacobians written entry by entry (components first) are
    ``right_jacobian``'s (N, 3, 3) blocks, below and above its series' 1e-4 rad."""
    from bvpnav.error_models._attitude import right_jacobian
    from bvpnav.error_models.error_states import _right_jacobian_components

    rng = np.random.default_rng(4)
    phi = rng.standard_normal((40, 3)) * np.repeat([1e-6, 1e-4, 1e-2, 1.0], 10)[:, None]
    got = _right_jacobian_components(phi)
    assert got.shape == (3, 3, 40)
    assert np.abs(np.moveaxis(got, -1, 0) - right_jacobian(phi)).max() < 1e-15


@pytest.mark.parametrize("m", [5, 17, 40])
def test_the_steps_columns_are_the_same_numbers_block_by_block(monkeypatch, m):
    r"""The mesh's per-step columns :math:`S_j J_r(a_j) h_j`, made block by block of steps, are the
    products of the whole pass's rotation matrices and right Jacobians, bit for bit, at block
    sizes that divide the steps or leave a remainder; the weighted halves the running sums start
    from are :math:`(1 - \theta) Z` and :math:`\theta Z` of those numbers, whether written in
    their own memory or from the columns already made."""
    from bvpnav.error_models import error_states as es

    rng = np.random.default_rng(6)
    a = rng.standard_normal((m, 3)) * 10.0 ** rng.uniform(-7, -1, (m, 1))
    Sc = np.ascontiguousarray(Rotation.from_rotvec(rng.standard_normal((m, 3))).as_quat().T)
    h = rng.uniform(0.005, 0.02, m)
    theta = rng.uniform(0.0, 1.0, m + 1)
    J, S = es._right_jacobian_components(a), es._matrix_components(Sc)
    want = np.empty((3, 3, m))
    for k in range(3):
        for c in range(3):
            want[k, c] = S[k, 0] * J[0, c]
            want[k, c] += S[k, 1] * J[1, c]
            want[k, c] += S[k, 2] * J[2, c]
            want[k, c] *= h
    want = want.reshape(9, m)
    for block in (1, 4, m, 10 * m):
        monkeypatch.setattr(es, "STEP_BLOCK", block)
        el = es._Elements(np.zeros(m + 1, dtype=int), theta, a, Sc, h)
        w = el.weighted   # the columns written in its own memory
        assert np.array_equal(w[0, :, 1:], want * (1.0 - theta[:-1])) and not w[:, :, 0].any()
        assert np.array_equal(w[1, :, 1:], want * theta[:-1])
        assert "Zc" not in el.__dict__
        el = es._Elements(np.zeros(m + 1, dtype=int), theta, a, Sc, h)
        assert np.array_equal(el.Zc, want)
        assert np.array_equal(el.weighted[0, :, 1:], want * (1.0 - theta[:-1]))   # from Zc


def test_rotation_vectors_of_quaternions_are_scipys():
    """The re-integrated attitude's rotation vectors (no rotation objects): scipy's to rounding,
    on both hemispheres, below and above the series' 1e-3 rad, near pi and unnormalized."""
    from bvpnav.error_models.error_states import _rotvec

    rng = np.random.default_rng(5)
    axes = rng.standard_normal((6, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    angles = np.array([0.0, 1e-9, 9e-4, 1.1e-3, 1.0, np.pi - 1e-6])
    q = Rotation.from_rotvec(axes * angles[:, None]).as_quat()
    q = np.concatenate([q, -q, 3.0 * q])          # the other hemisphere; another norm
    want = Rotation.from_quat(q).as_rotvec()
    assert np.max(np.abs(_rotvec(q) - want)) < 1e-14
    assert np.allclose(np.linalg.norm(_rotvec(q[:6]), axis=1), angles, rtol=1e-12, atol=0)


def test_the_kept_index_arrays_are_int32_only_when_every_index_fits():
    """The attitude process rows' pointers reach ``3 m w`` (``w = 12`` entries per row on a
    mesh with gyro-bias states: 36 per element), the bias walks' ``6 m``, the columns the
    model's size: int32 only when all are below 2**31 (a wrapped int32 pointer is silent)."""
    from bvpnav.error_models.error_states import _index_type

    edge = 2**31 // 36   # 36 m: the largest stored index with w = 12
    assert _index_type(10**6, edge, 12) is np.int32
    assert _index_type(10**6, edge + 1, 12) is np.int64   # 24 (m + 1) < 2**31: beyond the old bound's reach
    assert _index_type(2**31, 10, 12) is np.int64   # the columns
    assert _index_type(2**31 - 1, 10, 12) is np.int32


def test_a_solve_without_a_mesh_leaves_the_users_data_as_it_was():
    """The node-state loop keeps the rows' patterns for its steps, but not on the user's own
    data (inputs are never modified): its attributes and its pickled size are as before."""
    import pickle

    d = simulate(const(BG), const(BA), T=20.0, rate=20.0, turn=5.0)
    data = d["data"]
    before, size = dict(data.__dict__), len(pickle.dumps(data))
    k = np.arange(0, d["t"].size, 20)
    prob = bvpnav.NavigationProblem(data, error_model=ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-4,
                                                                  acc_drift=1e-3), sigma_a=2e-2)
    prob.add(Position(t=d["t"][k], value=d["r"][k], sigma=0.3))
    sol = prob.solve(solver="direct", attitude={"progress": False})
    assert sol.records.attitude.converged and len(sol.records.attitude.iterations) >= 2
    assert sorted(data.__dict__) == sorted(before)
    assert all(data.__dict__[key] is v for key, v in before.items())
    assert len(pickle.dumps(data)) == size


@pytest.mark.parametrize("segment", [None, 1.0], ids=["samples", "mesh"])
def test_a_patterns_stencil_writes_the_placed_band_bit_for_bit_at_other_values(segment):
    # a Gauss-Newton step's assembly of a pattern seen before goes through the plan's stencil
    # (gathers and sums over the values): the band, h and the scales must be exactly those the
    # blocks placed one by one give, at the first values and at other values of the same
    # pattern (the next step's), and the factor must solve the system
    from bvpnav.linalg.banded import BandedKKT, _Stencil
    from bvpnav.linalg.lsq import banded_plan, fem_rows_by_diagonals, least_squares_form
    from bvpnav.linalg.workspace import Workspace

    d = simulate(const(BG), const(BA), T=4.0)
    model = ErrorStates(arw=1e-4, gyro_drift=1e-4, acc_drift=1e-3, attitude_sigma=0.1)
    k = np.arange(0, d["t"].size, 8)
    prob = bvpnav.NavigationProblem(d["data"], error_model=model, sigma_a=1e-3, segment=segment)
    prob.add(Position(t=d["t"][k], value=d["r"][k], sigma=1e-2))
    form = prob.add(Position(t=d["t"][[3, 40]], value=d["r"][[3, 40]], mode="hard")).formulation
    ls = least_squares_form(form, 1.0)
    ws = Workspace()
    plan = banded_plan(ls, form, ws)
    diagonal = fem_rows_by_diagonals(form, ws)
    D, E = ls.D.A, ls.E.A
    assert plan.border == 0 and plan.segments == 1 and plan.elim.size and E.shape[0] > diagonal.rows
    by_diagonals = plan._pairs_by_diagonals(E, diagonal)
    assert by_diagonals == (segment is None)   # the mesh's element residuals: pairs by products
    rng = np.random.default_rng(1)
    for step in range(3):   # the plan's first values, then two other steps' of the same pattern
        if step:
            D = D.copy()
            E = E.copy()
            D.data *= rng.uniform(0.5, 2.0, D.nnz)
            # the FEM rows are the model's (the diagonals describe them), the items' rows below
            below = slice(E.indptr[diagonal.rows], E.nnz)
            E.data[below] *= rng.uniform(0.5, 2.0, E.nnz - E.indptr[diagonal.rows])
        stencil = plan._stencil(D, E, diagonal)
        assert isinstance(stencil, _Stencil) and stencil.by_diagonals == by_diagonals
        placed = plan._scatter(plan._entries(D, E, diagonal), scaled=True)
        ab, B, C, h, sU = stencil.parts(D, E, plan.ldab)
        assert B is None and placed[1] is None and C.shape == placed[2].shape == (0, 0)
        for new, old in ((ab, placed[0]), (h, placed[3]), (sU, placed[4])):
            assert new.shape == old.shape and np.array_equal(new, old)
        assert plan._stencil(D, E, diagonal) is stencil   # kept for the pattern
        Ez = E[:, plan.elim_index]   # the eliminated columns by gathers: scipy's matrices exactly
        for got, want in zip(stencil.eliminated(plan, E), (Ez, Ez.T.tocsr()), strict=True):
            for a in ("data", "indices", "indptr"):
                assert np.array_equal(getattr(got, a), getattr(want, a))
        fac = BandedKKT(D, E, plan=plan, diagonal=diagonal)
        assert fac.plan._stencil_kept is stencil
        aug = sp.bmat([[-sp.identity(D.shape[0]), D, None], [D.T, None, E.T], [None, E, None]]).toarray()
        rhs = rng.standard_normal(aug.shape[0])
        z = fac.refined(rhs, 3)[0]
        assert np.abs(aug @ z - rhs).max() <= 1e-9 * np.abs(rhs).max()
    # another pattern: a new stencil for it (a value made zero drops its entry)
    D2 = D.copy()
    D2.data[D2.indptr[np.flatnonzero(np.diff(D2.indptr) > 2)[0]]] = 0.0   # a process row's first entry
    D2.eliminate_zeros()
    other = plan._stencil(D2, E, diagonal)
    assert other is not stencil and other is not None
    placed = plan._scatter(plan._entries(D2, E, diagonal), scaled=True)
    assert np.array_equal(other.parts(D2, E, plan.ldab)[0], placed[0])


def test_a_pattern_beyond_the_stencils_size_is_placed_as_before(monkeypatch):
    # no stencil is kept for a pattern of more entries than STENCIL_ENTRIES (its index arrays
    # would be as large as the band): the assembly places the blocks, with the same band
    from bvpnav.linalg import banded
    from bvpnav.linalg.lsq import banded_plan, fem_rows_by_diagonals, least_squares_form
    from bvpnav.linalg.workspace import Workspace

    d = simulate(const(BG), const(BA), T=2.0)
    form = problem(d, ErrorStates(arw=1e-4, gyro_drift=1e-4, acc_drift=1e-3)).formulation
    ls = least_squares_form(form, 1.0)
    ws = Workspace()
    plan = banded_plan(ls, form, ws)
    diagonal = fem_rows_by_diagonals(form, ws)
    D, E = ls.D.A, ls.E.A
    monkeypatch.setattr(banded, "STENCIL_ENTRIES", D.nnz + E.nnz - 1)
    assert plan._stencil(D, E, diagonal) is None
    placed = plan.assemble(D.copy(), E.copy(), diagonal)   # not the plan's first arrays
    monkeypatch.setattr(banded, "STENCIL_ENTRIES", D.nnz + E.nnz)
    stencil = plan._stencil(D, E, diagonal)
    assert stencil is not None
    assert np.array_equal(stencil.parts(D, E, plan.ldab)[0], placed[0])


def test_state_index_is_the_node_major_layout_and_read_only():
    """``state_index``: kind ``k`` of node ``j`` at ``3 kinds j + 3 k + axis``, for each set of
    kinds and number of nodes (a kept array serves only its own layout), and read only (a kept
    array is shared by every caller)."""
    from bvpnav.error_models.error_states import STATE_INDEX_KEPT, _state_index

    for n in (5, 7, STATE_INDEX_KEPT + 1):
        for kinds in (1, 2, 3):
            for k in range(kinds):
                idx = _state_index(n, 3 * kinds, k)
                want = 3 * kinds * np.arange(n)[:, None] + 3 * k + np.arange(3)
                assert idx.shape == (n, 3) and np.array_equal(idx, want)
                with pytest.raises(ValueError):
                    idx[0, 0] = -1
