"""The coarse FEM mesh (``segment=``): the samples between nodes condensed exactly (issue 42).

The key property: with items at mesh nodes, the condensed problem's answer equals the
answer on every sample, at the nodes and (recovered) at every sample, to rounding; for
several non-uniform step patterns, per-sample sigma_a and constant error models.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.sparse as sp

import bvpnav
from bvpnav import fem
from bvpnav.constraints import Position, PositionBound, Symmetry, Velocity, ZeroVelocity
from bvpnav.error_models import Bias, ScaleFactor
from bvpnav.errors import InputError
from bvpnav.grid import MeshGrid, TimeGrid, mesh_nodes
from bvpnav.mesh import MeshModel
from bvpnav.solve.attitude import CHEAP_ERROR, CHEAP_FIRST, CHEAP_GAP

#: The simulated items are few and the noise small: the misfit check speaks (the same words
#: for both solves, asserted below); not the subject here.
pytestmark = pytest.mark.filterwarnings("ignore:misfit")


def _steps(kind: str, n: int, rng) -> np.ndarray:
    """Sample times (s) of ``n`` samples with a step pattern."""
    if kind == "uniform":
        h = np.full(n - 1, 0.01)
    elif kind == "random":
        h = rng.uniform(0.0026, 0.02, n - 1)          # KITTI's range of steps
    elif kind == "gap":
        h = np.full(n - 1, 0.01)
        h[n // 3] = 0.7                                 # one step longer than the segment
        h[2 * n // 3: 2 * n // 3 + 40] = 0.0026
    else:                                               # "alternating": 2 ms / 18 ms
        h = np.where(np.arange(n - 1) % 2, 0.002, 0.018)
    return np.concatenate([[0.0], np.cumsum(h)])


def _truth(t: np.ndarray, d: int):
    """Position (m), velocity (m/s) and acceleration (m/s^2) of a smooth motion at ``t``."""
    k = 1.0 + np.arange(d)
    w = 0.9 / k
    s, c = np.sin(w * t[:, None]), np.cos(w * t[:, None])
    return -k * s / w**2 + 0.3 * t[:, None], -k * c / w + 0.3, k * s


def _data(kind: str, n: int = 1500, d: int = 2, seed: int = 0):
    rng = np.random.default_rng(seed)
    t = _steps(kind, n, rng) + 3.0
    acc = _truth(t, d)[2] + 0.03 * rng.standard_normal((n, d)) + 0.02   # noise and a bias
    axes = ("x", "y", "z")[:d]
    return bvpnav.ImuData(t=t, acc=acc, axes=axes), rng


def _problem(data, rng, segment, sigma_a, error_model=None, between: bool = True):
    t, d = data.t, data.ndim
    n = t.size
    fix_t = t[::137]
    tv = np.array([t[0], t[n // 2 + 11]])
    noisy = _truth(fix_t, d)[0] + 0.2 * rng.standard_normal((fix_t.size, d))
    items = [Position(t=fix_t, value=noisy, sigma=0.2),
             Velocity(t=tv, value=_truth(tv, d)[1] + 0.1 * rng.standard_normal((2, d)), sigma=0.1)]
    if between:   # times between two samples: both become nodes
        tm, tp = 0.5 * (t[n // 2 + 90] + t[n // 2 + 91]), 0.3 * t[4 * n // 5] + 0.7 * t[4 * n // 5 + 1]
        items.append(Velocity(t=tm, value=_truth(np.array([tm]), d)[1], sigma=0.3, name="vmid"))
        items.append(Position(t=tp, value=_truth(np.array([tp]), d)[0], sigma=0.5, name="pmid"))
    return bvpnav.NavigationProblem(data, sigma_a=sigma_a, error_model=error_model, items=items,
                                    segment=segment)


def _rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# --------------------------------------------------------------- kernels
@pytest.mark.parametrize("kind", ["uniform", "random", "gap", "alternating"])
def test_condensation_is_phi_transpose_of_the_fine_matrices(kind):
    rng = np.random.default_rng(1)
    grid = TimeGrid(_steps(kind, 300, rng))
    nodes = mesh_nodes(grid, 0.4, times=[grid.t[17], 0.5 * (grid.t[200] + grid.t[201])])
    c = fem.condensation(grid, nodes)
    t = grid.t
    Phi = np.zeros((grid.n, nodes.size))
    for k in range(nodes.size - 1):
        p, q = nodes[k], nodes[k + 1]
        th = (t[p:q + 1] - t[p]) / (t[q] - t[p])
        Phi[p:q + 1, k] = 1.0 - th
        Phi[p:q + 1, k + 1] = th
    Phi[nodes] = np.eye(nodes.size)
    M, K = fem.mass(grid).toarray(), fem.stiffness(grid).toarray()
    assert np.abs(c.load.toarray() - Phi.T @ M).max() <= 1e-15 * np.abs(M).max()
    Kc = fem.stiffness(TimeGrid(t[nodes])).toarray()
    assert np.abs(Phi.T @ K @ Phi - Kc).max() <= 1e-11 * np.abs(Kc).max()
    # an element's two rows integrate 1 to its length; Cq of a one-step element is h/6 (1, 2)
    np.testing.assert_allclose((c.Cp + c.Cq).sum(axis=1).A.ravel(), np.diff(t[nodes]), rtol=1e-13)
    e = int(np.flatnonzero(nodes == 200)[0])
    h = t[201] - t[200]
    np.testing.assert_allclose(c.Cq[e].toarray().ravel()[[200, 201]], [h / 6, h / 3], rtol=1e-13)
    assert c.Cq[e].nnz == 2
    # written as canonical CSR: an element's row holds exactly its samples, a node's load row the
    # samples of its two elements, each once and in order (what a sum of duplicates would give)
    k = np.arange(nodes.size)
    elements = (nodes[:-1], nodes[1:])
    for A, (first, last) in ((c.Cp, elements), (c.Cq, elements),
                             (c.load, (nodes[np.maximum(k - 1, 0)], nodes[np.minimum(k + 1, k[-1])]))):
        assert A.shape[0] == first.size
        for r, (p, q) in enumerate(zip(first, last, strict=True)):
            np.testing.assert_array_equal(A.indices[A.indptr[r]:A.indptr[r + 1]], np.arange(p, q + 1))
        B = sp.csr_matrix((A.data.copy(), A.indices.copy(), A.indptr.copy()), shape=A.shape)
        B.has_canonical_format = False
        B.sum_duplicates()
        assert B.nnz == A.nnz and np.array_equal(B.data, A.data)


def test_mesh_nodes_rules():
    rng = np.random.default_rng(2)
    grid = TimeGrid(_steps("gap", 2000, rng))
    want = [grid.t[5], 0.25 * grid.t[700] + 0.75 * grid.t[701]]
    nodes = mesh_nodes(grid, 0.5, want)
    t = grid.t
    assert nodes[0] == 0 and nodes[-1] == grid.n - 1 and np.all(np.diff(nodes) > 0)
    long = np.diff(t[nodes]) > 0.5 * (1 + 1e-9)
    assert np.all(np.diff(nodes)[long] == 1)          # only a single step may exceed the segment
    assert {5, 700, 701} <= set(nodes.tolist())
    assert not np.any(np.diff(nodes) == 2)              # never one sample alone inside an element
    assert nodes.size < grid.n / 10                     # it is coarse
    assert mesh_nodes(grid, 1e-9).size == grid.n        # a tiny segment keeps every sample


# ------------------------------------------------------- the key property
@pytest.mark.parametrize("kind", ["uniform", "random", "gap", "alternating"])
@pytest.mark.parametrize("per_sample", [False, True])
def test_mesh_answer_equals_the_per_sample_answer(kind, per_sample):
    data, rng = _data(kind, d=2, seed=3)
    sigma = (rng.uniform(0.02, 0.2, (data.n, 2)) if per_sample else [0.05, 0.08])
    em = Bias() + ScaleFactor()
    fine = _problem(data, np.random.default_rng(7), None, sigma, em).solve(solver="direct", lam=1.0)
    prob = _problem(data, np.random.default_rng(7), 1.0, sigma, em)
    coarse = prob.solve(solver="direct", lam=1.0)
    model = prob.formulation.model
    assert isinstance(model, MeshModel) and model.N < data.n / 10
    for ax in data.axes:
        assert _rel(coarse.position(ax), fine.position(ax)) <= 1e-9
        assert _rel(coarse.velocity(ax), fine.velocity(ax)) <= 1e-9
        assert _rel(coarse.residuals[f"w_{ax}"], fine.residuals[f"w_{ax}"]) <= 1e-8
    assert _rel(coarse.error_params.to_numpy(), fine.error_params.to_numpy()) <= 1e-8
    assert coarse.warnings == fine.warnings     # the misfit's variance factor and degrees of freedom too
    # the nodal unknowns are the fine answer at the node samples
    nodes = model.grid.nodes
    assert _rel(coarse.x[model.r_index(0)], fine.position("x")[nodes]) <= 1e-9


def test_constant_acceleration_between_two_positions_is_exact_everywhere():
    """a = 0.5 m/s^2, hard positions 0 at the start and 3 m at the end of 2 s: r = t + t^2/4."""
    rng = np.random.default_rng(4)
    t = _steps("random", 800, rng)
    t = t * (2.0 / t[-1])
    data = bvpnav.ImuData(t=t, acc=np.full(t.size, 0.5))
    prob = bvpnav.NavigationProblem(data, segment=0.3)
    prob.add(Position(t=[0.0, 2.0], value=[0.0, 3.0]))
    sol = prob.solve(solver="direct")
    assert prob.formulation.model.N < 20
    np.testing.assert_allclose(sol.position("x"), t + t**2 / 4, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.velocity("x"), 1.0 + t / 2, rtol=0, atol=1e-11)


def test_direct_and_clarabel_agree_on_the_mesh():
    pytest.importorskip("clarabel")
    data, rng = _data("random", n=600, d=1, seed=5)
    prob = _problem(data, rng, 0.8, 0.05, Bias())
    a = prob.solve(solver="direct", lam=1.0)
    b = prob.solve(solver="clarabel", lam=1.0)
    assert _rel(b.position("x"), a.position("x")) <= 1e-7
    assert _rel(b.velocity("x"), a.velocity("x")) <= 1e-7


def test_interval_items_get_every_sample_of_their_interval():
    data, rng = _data("random", n=900, d=1, seed=6)
    t = data.t
    items = [Position(t=[t[0], t[-1]], value=[0.0, 1.0]), ZeroVelocity(t0=t[300], t1=t[340])]
    fine = bvpnav.NavigationProblem(data, sigma_a=0.1, items=items).solve(solver="direct")
    prob = bvpnav.NavigationProblem(data, sigma_a=0.1, items=items, segment=1.0)
    coarse = prob.solve(solver="direct")
    assert set(range(300, 341)) <= set(prob.formulation.model.grid.nodes.tolist())
    assert _rel(coarse.position("x"), fine.position("x")) <= 1e-9
    assert np.abs(coarse.velocity("x")[300:341]).max() <= 1e-9


# ------------------------------------------------------------ refusals
@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf"), "1 s", True])
def test_segment_must_be_a_positive_number_of_seconds(bad):
    data, _ = _data("uniform", n=50, d=1)
    with pytest.raises(InputError, match="segment="):
        bvpnav.NavigationProblem(data, segment=bad)


def test_refusals_name_the_problem():
    data, _ = _data("uniform", n=400, d=1)
    t = data.t
    with pytest.raises(InputError, match="residual='acceleration'"):
        bvpnav.NavigationProblem(data, residual="load", segment=1.0)
    prob = bvpnav.NavigationProblem(data, segment=1.0, items=[Position(t=[t[0], t[-1]], value=[0.0, 1.0]),
                                                              Symmetry(about=t[200])])
    with pytest.raises(InputError, match="Symmetry.*segment=None"):
        prob.solve(solver="direct")
    prob = bvpnav.NavigationProblem(data, segment=1.0, items=[Position(t=[t[0], t[-1]], value=[0.0, 1.0])])
    model = prob.formulation.model
    with pytest.raises(InputError, match=r"probe item: time .* inside the mesh element"):
        model.position([t[151]], what="probe item")
    with pytest.raises(InputError, match="not mesh nodes"):
        PositionBound(lower=-1.0, t0=t[10], t1=t[300]).compile(model)
    late_fix = Position(t=[t[0], t[-1] + 5.0], value=[0.0, 1.0], name="late fix")
    late = bvpnav.NavigationProblem(data, segment=1.0, items=[late_fix])
    with pytest.raises(InputError, match="late fix.*outside the recording window"):
        late.solve(solver="direct")


def test_mesh_grid_keeps_the_fine_rows_inside_one_step_elements():
    grid = TimeGrid(np.linspace(0.0, 1.0, 11))
    mesh = MeshGrid(grid.t[[0, 4, 5, 10]], fine=grid, nodes=np.array([0, 4, 5, 10]))
    P = mesh.interpolation_matrix([0.4, 0.43, 0.5, 1.0])
    np.testing.assert_allclose(P.toarray()[1], [0.0, 0.7, 0.3, 0.0])
    with pytest.raises(InputError, match="x: time 0.2"):
        mesh.interpolation_matrix([0.2], "x")


# ------------------------------------------------- node states on the mesh (stage B)
def _drive(T=20.0, rate=20.0, noise=False, seed=5):
    """The node-state tests' simulated strapdown drive (constant biases), noisy if asked."""
    from error_models.test_error_states import BA, BG, GRAV, const, simulate

    d = simulate(const(BG), const(BA), T=T, rate=rate, turn=8.0 if noise else 5.0)
    if noise:
        rng = np.random.default_rng(seed)
        n, data = d["t"].size, d["data"]
        d["data"] = bvpnav.ImuData.from_gyro(d["t"], data.specific_force + 2e-2 * rng.standard_normal((n, 3)),
                                             data.gyro + 2e-3 * rng.standard_normal((n, 3)),
                                             initial_attitude=d["C"][0], gravity=GRAV)
        d["fix"] = d["r"] + 0.3 * rng.standard_normal((n, 3))
    else:
        d["fix"] = d["r"]
    return d


def _states_solve(d, model, segment, every, sigma, sigma_a):
    from bvpnav.constraints import Position

    k = np.arange(0, d["t"].size, every)
    prob = bvpnav.NavigationProblem(d["data"], error_model=model, sigma_a=sigma_a, segment=segment)
    prob.add(Position(t=d["t"][k], value=d["fix"][k], sigma=sigma))
    return prob, prob.solve(solver="direct", attitude={"progress": False})


@pytest.mark.parametrize("drift", [(0.0, 0.0), (1e-4, 1e-3)], ids=["constant", "walk"])
@pytest.mark.parametrize("segment", [1.0, 3.0])
def test_mesh_states_recover_constant_biases_to_rounding(drift, segment):
    """Noise-free: the biases held linear and the attitude re-integrated between nodes make the
    truth zero every row on the mesh too, so the estimate is the truth to rounding, in the few
    Gauss-Newton steps of exact Jacobians."""
    from bvpnav.error_models import ErrorStates

    d = _drive()
    model = ErrorStates(arw=1e-5, gyro_drift=drift[0], acc_drift=drift[1])
    before = dict(vars(d["data"]))
    prob, sol = _states_solve(d, model, segment, every=20, sigma=1e-4, sigma_a=1e-4)
    assert vars(d["data"]).keys() == before.keys()       # the user's data is not written to
    assert prob.data is d["data"] and not hasattr(d["data"], "state_mesh")
    assert prob.formulation.model.N <= 31 < d["t"].size / 10
    es = sol.error_states
    assert np.abs(es.filter(like="gyro_bias").to_numpy() - d["bg"]).max() < 1e-11
    assert np.abs(es.filter(like="acc_bias").to_numpy() - d["ba"]).max() < 1e-10
    assert np.abs((sol.attitude * d["C"].inv()).as_rotvec()).max() < 1e-10
    assert np.abs(sol.position() - d["r"]).max() < 1e-9
    rep = sol.records.attitude
    assert rep.converged and len(rep.iterations) <= 4 and sol.stats["verified"]


def test_mesh_states_at_sample_spacing_are_the_per_sample_states():
    from bvpnav.error_models import ErrorStates

    d = _drive(T=10.0, noise=True)
    model = ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-4, acc_drift=1e-3, attitude_sigma=0.1)
    _, fine = _states_solve(d, model, None, every=20, sigma=0.3, sigma_a=2e-2)
    prob, mesh = _states_solve(d, model, 1e-6, every=20, sigma=0.3, sigma_a=2e-2)
    assert isinstance(prob.formulation.model, MeshModel) and prob.formulation.model.N == d["t"].size
    assert _rel(mesh.position(), fine.position()) <= 1e-9
    assert _rel(mesh.error_states.to_numpy(), fine.error_states.to_numpy()) <= 1e-7
    assert len(mesh.records.attitude.iterations) == len(fine.records.attitude.iterations)


def test_mesh_states_on_a_noisy_drive_match_the_per_sample_accuracy():
    from bvpnav.error_models import ErrorStates

    d = _drive(T=30.0, rate=50.0, noise=True)
    model = ErrorStates(arw=2e-3 / np.sqrt(50.0), gyro_drift=1e-4, acc_drift=1e-3)
    out = {}
    for seg in (None, 1.0, 2.0):
        prob, sol = _states_solve(d, model, seg, every=250, sigma=0.3, sigma_a=2e-2)
        es = sol.error_states
        out[seg] = (np.sqrt(np.mean((sol.position() - d["r"]) ** 2)),
                    np.abs(es.filter(like="gyro_bias").to_numpy() - d["bg"]).max(),
                    np.abs(es.filter(like="acc_bias").to_numpy() - d["ba"]).max())
        assert sol.records.attitude.converged and sol.stats["verified"]
    ref = np.array(out[None])
    assert ref[0] < 0.3                                   # the smoother beats the 0.3 m fixes
    for seg in (1.0, 2.0):                                # measured: equal to 3 digits
        assert np.all(np.abs(np.array(out[seg]) - ref) <= 0.03 * ref), (seg, out[seg], ref)


def test_lambda_rules_matrices_and_what_a_mesh_refuses():
    data, rng = _data("random", n=900, d=2, seed=8)
    fine = _problem(data, np.random.default_rng(9), None, 0.05, Bias())
    prob = _problem(data, np.random.default_rng(9), 1.0, 0.05, Bias())
    a, b = fine.solve(solver="direct", lam="lcurve"), prob.solve(solver="direct", lam="lcurve")
    assert b.lam == a.lam and _rel(b.position("x"), a.position("x")) <= 1e-9
    mats, model = prob.matrices(), prob.formulation.model
    assert mats.A_eq.shape[1] == model.size and mats.f.size == model.N * 2 and "u_x" in mats.layout
    with pytest.raises(InputError, match="GCV.*segment="):
        prob.solve(solver="direct", lam="gcv")
    with pytest.raises(InputError, match="uncertainty=.*segment=None"):
        prob.solve(solver="direct", lam=1.0, uncertainty=True)


def test_the_spec_file_keeps_the_segment_and_names_a_bad_one():
    from bvpnav.spec import parse_spec, to_spec

    data, rng = _data("random", n=600, d=1, seed=10)
    prob = _problem(data, rng, 0.75, 0.05, Bias(), between=False)
    text = to_spec(prob, solve={"solver": "direct", "lam": 1.0})
    assert "segment = 0.75" in text
    again = parse_spec(text).build(data)
    assert again.segment == 0.75
    a, b = prob.solve(solver="direct", lam=1.0), again.solve(solver="direct", lam=1.0)
    assert np.array_equal(a.position("x"), b.position("x"))
    bad = text.replace("segment = 0.75", "segment = -2")
    with pytest.raises(InputError, match=r"line \d+: segment=-2"):
        parse_spec(bad)


def test_a_formulation_with_other_items_keeps_its_states_mesh():
    """Demotion and linearization make formulations with other items (``with_items``): on a mesh
    with node states the copy shares the model only with its mesh, and solves."""
    from bvpnav.constraints import Position
    from bvpnav.error_models import ErrorStates
    from bvpnav.solve import pipeline

    d = _drive()
    t, k = d["t"], np.arange(0, d["t"].size, 20)
    extra = 0.5 * (t[101] + t[102])
    model = ErrorStates(arw=1e-5, gyro_drift=0.0, acc_drift=0.0)
    prob = bvpnav.NavigationProblem(d["data"], error_model=model, sigma_a=1e-4, segment=2.0)
    prob.add(Position(t=t[k], value=d["r"][k], sigma=1e-4, name="fixes"),
             Position(t=extra, value=d["r"][101], sigma=1.0, name="x"))   # a loose one between samples
    form = prob.formulation
    assert {101, 102} <= set(form.model.grid.nodes.tolist())
    fewer = form.with_items(form.items[:1])
    assert fewer.model is form.model and np.array_equal(fewer.data.state_mesh, form.model.grid.nodes)
    sol = pipeline.solve(fewer, solver="direct", attitude={"progress": False})
    assert sol.records.attitude.converged and sol.stats["verified"]
    assert np.abs(sol.position() - d["r"]).max() < 1e-8


# ------------------------------------------- cheap Gauss-Newton steps (issue 42)
def _cheap_rows(form, nodes0, nodes1):
    """The least-squares rows (D, E) of ``form`` at the node totals ``nodes1``: from every sample
    (a full pass), and cheaply from the per-element sums of a full pass at ``nodes0``; the
    columns of the gyro-bias states."""
    from bvpnav.error_models.error_states import cheap_at, states_at
    from bvpnav.formulation import Formulation
    from bvpnav.linalg.lsq import least_squares_form

    raw, sm = form.data, form.model.state_model

    def rows(data):
        f = Formulation(data, form.residual, form.sigma_a, form.error_model, form.items, grade=None,
                        segment=form.segment)
        f._observable = True
        return least_squares_form(f, 1.0), f

    _, ref = rows(states_at(raw, sm.expand(raw, nodes0)))
    full, _ = rows(states_at(raw, sm.expand(raw, nodes1)))
    cheap, fc = rows(cheap_at(ref.data, nodes1))
    gyro = fc.model.s_index[sm.state_index(fc.data, "gyro_bias").ravel()]
    return full, cheap, gyro



def _noisy_states_form():
    """A 20 s noisy drive's node states on a 1 s mesh with fixes every 20 samples: its formulation."""
    from bvpnav.error_models import ErrorStates

    d = _drive(T=20.0, noise=True)
    model = ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-4, acc_drift=1e-3)
    k = np.arange(0, d["t"].size, 20)
    prob = bvpnav.NavigationProblem(d["data"], error_model=model, sigma_a=2e-2, segment=1.0)
    prob.add(Position(t=d["t"][k], value=d["fix"][k], sigma=0.3))
    return prob.formulation


def test_a_cheap_point_has_the_full_pass_rows_in_the_node_attitudes_and_biases():
    """A cheap step's rows (made from a full pass's per-element sums, no pass over the samples)
    are the rows made from every sample when the nodes' attitudes and accelerometer biases
    move (exactly: the samples of an element turn with its left node), but for the gyro-bias
    columns, whose change with the accelerometer bias is left out; a gyro-bias change is
    taken to first order, so the rows' error is second order in it."""
    from scipy.spatial.transform import Rotation

    form = _noisy_states_form()
    n = form.model.N
    rng = np.random.default_rng(3)
    nodes0 = {kind: rng.normal(scale=s, size=(n, 3))
              for kind, s in (("attitude_error", 0.02), ("gyro_bias", 1e-3), ("acc_bias", 0.05))}
    moved = dict(nodes0)
    moved["attitude_error"] = (Rotation.from_rotvec(rng.normal(scale=0.1, size=(n, 3)))
                               * Rotation.from_rotvec(nodes0["attitude_error"])).as_rotvec()
    moved["acc_bias"] = nodes0["acc_bias"] + rng.normal(scale=0.05, size=(n, 3))
    full, cheap, gyro = _cheap_rows(form, nodes0, moved)
    assert full.D.A.shape == cheap.D.A.shape and full.E.A.shape == cheap.E.A.shape
    for a, b in ((full.D, cheap.D), (full.E, cheap.E)):
        assert np.abs(a.c - b.c).max() <= 1e-11 * np.abs(a.c).max()
    assert abs(full.D.A - cheap.D.A).max() <= 1e-11 * abs(full.D.A).max()
    other = np.setdiff1d(np.arange(full.E.A.shape[1]), gyro)
    dE = abs(full.E.A - cheap.E.A).tocsc()
    assert dE[:, other].max() <= 1e-11 * abs(full.E.A).max()
    # measured: 1e-16 relative elsewhere, 7e-4 in the gyro-bias columns (of the order of |db_a| / |f|)
    assert 0 < dE[:, gyro].max() <= 1e-2 * abs(full.E.A).max()
    # a gyro-bias change: the rows' error is second order in it (halving it quarters the error)
    errs = []
    for s in (2e-3, 1e-3):
        step = dict(nodes0)
        step["gyro_bias"] = nodes0["gyro_bias"] + s * np.linspace(-1.0, 1.0, 3 * n).reshape(n, 3)
        full, cheap, _ = _cheap_rows(form, nodes0, step)
        errs.append([np.abs(full.D.c - cheap.D.c).max(), np.abs(full.E.c - cheap.E.c).max()])
    ratio = np.array(errs[0]) / np.array(errs[1])   # measured: 4.00001, 3.99994
    assert np.all((3.5 < ratio) & (ratio < 4.5)), (errs, ratio)


def test_a_points_totals_at_the_nodes_are_its_samples_there_made_without_them():
    """The node-state loop reads a point's totals at the mesh's nodes: a full pass's (``expand``)
    and a cheap point's (``cheap_at``) are there before their samples are made (on first read),
    and equal the samples' at the nodes bit for bit; at every sample they are the attitude of
    ``states_at`` (to rounding), the biases linear between the nodes, and a cheap point's
    attitude error the reference's but at the nodes; a copy holds every kind's samples."""
    import pickle

    from scipy.spatial.transform import Rotation

    from bvpnav.error_models.error_states import _hats, _node_totals, attitude_at, cheap_at, states_at

    form = _noisy_states_form()
    raw, sm, n = form.data, form.model.state_model, form.model.N
    mesh = form.model.grid.nodes
    rng = np.random.default_rng(11)
    nodes = {kind: rng.normal(scale=s, size=(n, 3))
             for kind, s in (("attitude_error", 0.05), ("gyro_bias", 2e-3), ("acc_bias", 0.05))}
    tot = sm.expand(raw, nodes)
    data = states_at(raw, tot)
    at = {k: _node_totals(data, k) for k in nodes}
    assert dict.__getitem__(tot, "attitude_error") is None   # not made by the reads at the nodes
    np.testing.assert_array_equal(sm.state_total(data, "attitude_error"), at["attitude_error"])
    for k in nodes:
        np.testing.assert_array_equal(tot[k][mesh], at[k])
    psi = (data.attitude * raw.attitude.inv()).as_rotvec()
    assert np.abs(tot["attitude_error"] - psi).max() <= 1e-12
    for k in ("gyro_bias", "acc_bias"):
        np.testing.assert_array_equal(tot[k], _hats(raw) @ nodes[k])
    # a cheap point from that pass: its nodes as given, the reference's attitude between them
    moved = {k: v + rng.normal(scale=1e-3, size=(n, 3)) for k, v in nodes.items()}
    moved["attitude_error"] = (Rotation.from_rotvec(rng.normal(scale=0.01, size=(n, 3)))
                               * Rotation.from_rotvec(nodes["attitude_error"])).as_rotvec()
    cheap = cheap_at(data, moved)
    ct = cheap.state_point.totals
    at = {k: _node_totals(cheap, k) for k in moved}
    assert all(dict.__getitem__(ct, k) is None for k in moved)
    np.testing.assert_array_equal(at["attitude_error"], moved["attitude_error"])
    for k in moved:
        np.testing.assert_array_equal(ct[k][mesh], at[k])
    inside = np.setdiff1d(np.arange(raw.n), mesh)
    np.testing.assert_array_equal(ct["attitude_error"][inside], tot["attitude_error"][inside])
    for k in ("gyro_bias", "acc_bias"):
        np.testing.assert_array_equal(ct[k], _hats(raw) @ moved[k])
    # the attitude alone (the loop's answer) is states_at's
    for given in (tot, {k: np.array(v) for k, v in tot.items()}):
        want = states_at(raw, given).attitude.as_quat()
        np.testing.assert_array_equal(attitude_at(raw, given).as_quat(), want)
    # copies (and a pickle) read the samples
    again = sm.expand(raw, nodes)
    for copied in (dict(again), {**sm.expand(raw, nodes)}, pickle.loads(pickle.dumps(sm.expand(raw, nodes)))):
        assert type(copied) is dict and set(copied) == set(nodes)
        for k in nodes:
            np.testing.assert_array_equal(copied[k], tot[k])


def test_totals_made_on_first_read_behave_as_a_dict_of_their_values():
    """The totals whose samples are made on first read (``_Totals``) are a dict of their values
    whatever is done to them: an assigned kind keeps its value (its maker and node values
    dropped), pop / setdefault / popitem / update give and take the made arrays, a maker that
    fails leaves the kind to be made on the next read (not a placeholder), and the node values
    handed out are copies."""
    from bvpnav.error_models.error_states import _Totals

    calls = []

    def make():
        calls.append(1)
        if len(calls) == 1:
            raise MemoryError("first make fails")
        return np.full((4, 3), 2.0)

    def fresh():
        return _Totals({"acc_bias": np.zeros((4, 3))}, {"attitude_error": lambda: np.ones((4, 3))},
                       {"attitude_error": np.ones((2, 3))})

    t = _Totals({}, {"attitude_error": make}, {"attitude_error": np.full((2, 3), 2.0)})
    with pytest.raises(MemoryError):
        t["attitude_error"]
    np.testing.assert_array_equal(t["attitude_error"], 2.0)   # made on the next read
    t = fresh()
    t["attitude_error"] = np.full((4, 3), 5.0)
    np.testing.assert_array_equal(t["attitude_error"], 5.0)
    np.testing.assert_array_equal(t.at_nodes("attitude_error", np.array([0, 3])), 5.0)
    t = fresh()
    np.testing.assert_array_equal(t.pop("attitude_error"), 1.0)
    assert "attitude_error" not in t and t.pop("attitude_error", None) is None
    t = fresh()
    np.testing.assert_array_equal(t.setdefault("attitude_error", None), 1.0)
    t = fresh()
    kind, value = t.popitem()
    assert kind == "attitude_error"
    np.testing.assert_array_equal(value, 1.0)
    t = fresh()
    t.update(attitude_error=np.zeros((4, 3)))
    t |= {"acc_bias": np.ones((4, 3))}
    np.testing.assert_array_equal(t["attitude_error"], 0.0)
    np.testing.assert_array_equal(t["acc_bias"], 1.0)
    t = fresh()
    handed = t.at_nodes("attitude_error", np.array([0, 3]))
    handed += 1.0
    np.testing.assert_array_equal(t.at_nodes("attitude_error", np.array([0, 3])), 1.0)
    del t["attitude_error"]
    assert set(t) == {"acc_bias"}
    t.clear()
    assert len(t) == 0 and dict(t) == {}


def _moved_point(seed: int):
    """``_noisy_states_form()``'s formulation with its data at a point where every node state is
    moved (attitude errors 0.05 rad, gyro biases 2e-3 rad/s, accelerometer biases 0.05 m/s^2,
    drawn with ``seed``): ``(form, raw, state model, node totals, data there, rng)``."""
    from bvpnav.error_models.error_states import states_at

    form = _noisy_states_form()
    raw, sm, n = form.data, form.model.state_model, form.model.N
    rng = np.random.default_rng(seed)
    nodes = {kind: rng.normal(scale=s, size=(n, 3))
             for kind, s in (("attitude_error", 0.05), ("gyro_bias", 2e-3), ("acc_bias", 0.05))}
    return form, raw, sm, nodes, states_at(raw, sm.expand(raw, nodes)), rng


def test_condensed_state_columns_are_the_load_times_the_per_sample_columns():
    r"""The node states' condensed columns (per-element sums: the gyro-bias block as
    :math:`C_p \sum_i W_{ri} [g_i\times] Y_i` from running sums restarted at the nodes) are the
    load times the columns made at every sample (``state_columns``: the blocks written per
    sample), at a point with every state moved, to rounding; the same sparsity."""
    form, raw, sm, _, data, rng = _moved_point(5)
    W = form.model.cond.load
    got = sm.condensed_columns(data, W)
    want = [(W @ g).tocsr() for g in sm.state_columns(data)]
    gyro = sm.state_index(data, "gyro_bias").ravel()
    for a, b in zip(got, want, strict=True):
        assert a.shape == b.shape
        scale = abs(b).max()
        assert abs(a - b).max() <= 1e-12 * scale
        assert abs(b[:, gyro]).max() > 1e-3 * scale   # the gyro-bias block is there to compare
        b.eliminate_zeros()
        assert a.nnz == b.nnz


def test_condensed_columns_read_a_points_strapdown_only_at_its_own_attitude():
    """A point's data (``states_at``) keeps the attitude's matrices and the navigation-frame
    specific force its strapdown made: the condensed columns read them (the columns made from
    the attitude, bit for bit), once; given another attitude, the data's columns are that
    attitude's, not the kept ones."""
    import copy

    from bvpnav.error_models.error_states import states_at

    form, raw, sm, nodes, data, rng = _moved_point(7)
    W = form.model.cond.load

    def made_here(d):   # the same data without what its strapdown kept
        out = copy.copy(d)
        out.__dict__ = {k: v for k, v in d.__dict__.items() if k != "_kept_navigation_force"}
        return out

    want = sm.condensed_columns(made_here(data), W)
    assert "_kept_navigation_force" in data.__dict__
    got = sm.condensed_columns(data, W)
    assert "_kept_navigation_force" not in data.__dict__   # read once
    for a, b in zip(got, want, strict=True):
        assert a.shape == b.shape and (a != b).nnz == 0
    # a point whose attitude is then replaced by another point's: that attitude's columns
    turned = nodes["attitude_error"] + rng.normal(scale=0.05, size=(form.model.N, 3))
    other = dict(nodes, attitude_error=turned)
    moved = states_at(raw, sm.expand(raw, nodes))
    moved.attitude = states_at(raw, sm.expand(raw, other)).attitude
    want = sm.condensed_columns(made_here(moved), W)
    got = sm.condensed_columns(moved, W)
    for a, b, c in zip(got, want, sm.condensed_columns(made_here(data), W), strict=True):
        assert (a != b).nnz == 0
        assert abs(a - c).max() > 1e-3 * abs(c).max()   # another attitude: other columns


def test_mesh_nodes_walk_is_the_searchsorted_walk():
    """The mesh's greedy walk between the nodes the items need (on the times as Python floats)
    gives the nodes of the walk by ``searchsorted`` on the array, on uneven steps, at segments
    a whole number of steps long (ties with the reach) and not."""
    from bvpnav.grid import TimeGrid, _needed_nodes, mesh_nodes

    def walked(grid, segment, times):   # the walk on the array's scalars
        t = grid.t
        fixed = _needed_nodes(grid, times)
        out = [fixed[:1]]
        for p, q in zip(fixed[:-1], fixed[1:], strict=True):
            cur, add = int(p), []
            reach = segment * (1.0 + 1e-9)
            while t[q] - t[cur] > reach:
                nxt = max(int(np.searchsorted(t, t[cur] + reach, side="right")) - 1, cur + 1)
                if nxt >= q:
                    break
                add.append(nxt)
                cur = nxt
            out.append(np.array(add + [int(q)], dtype=np.int64))
        nodes = np.concatenate(out)
        return np.union1d(nodes, nodes[:-1][np.diff(nodes) == 2] + 1)

    rng = np.random.default_rng(3)
    for t in (np.arange(2001) * 0.01, np.cumsum(rng.uniform(0.005, 0.02, 3000))):
        grid = TimeGrid(t)
        times = rng.uniform(t[0] - 1.0, t[-1] + 1.0, 17)
        for segment in (0.05, 0.1, 0.37, 1.0, 3.0):
            got = mesh_nodes(grid, segment, times)
            assert got.dtype == np.int64
            assert np.array_equal(got, walked(grid, segment, times))
            assert got.size > 2


def test_state_acceleration_is_the_per_sample_columns_times_the_states():
    """The acceleration the node states' increments make at every sample (the trajectory's
    recovery inside elements reads it), taken without the columns, is the columns made at
    every sample (``state_columns``) times the increments, at a point with every state moved,
    for every kind of state; and a change of the increments or of the point changes it."""
    from bvpnav.error_models.error_states import states_at

    form, raw, sm, nodes, data, rng = _moved_point(7)
    cols = sm.state_columns(data)
    s = rng.normal(size=cols[0].shape[1])
    got = sm.state_acceleration(data, s)
    want = np.column_stack([g @ s for g in cols])
    assert got.shape == (raw.n, 3)
    assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()
    for kind in ("attitude_error", "gyro_bias", "acc_bias"):   # each kind on its own
        only = np.zeros_like(s)
        idx = sm.state_index(data, kind).ravel()
        only[idx] = s[idx]
        part = np.column_stack([g @ only for g in cols])
        assert np.abs(part).max() > 1e-3 * np.abs(want).max()
        assert np.abs(sm.state_acceleration(data, only) - part).max() <= 1e-12 * np.abs(part).max()
    other = states_at(raw, sm.expand(raw, {**nodes, "gyro_bias": 2.0 * nodes["gyro_bias"]}))
    assert np.abs(sm.state_acceleration(other, s) - got).max() > 1e-6 * np.abs(got).max()


@pytest.mark.parametrize("block", [1, 13, 500])
def test_state_acceleration_block_by_block_is_the_whole_pass_bit_for_bit(monkeypatch, block):
    """The states' acceleration made block by block of samples (every term is per sample) is the
    same numbers, bit for bit, as made on every sample at once, at blocks that divide the samples
    or leave a remainder, and at blocks that split elements."""
    from bvpnav.error_models import error_states as es

    form, raw, sm, nodes, data, rng = _moved_point(7)
    s = rng.normal(size=sm.state_size(data))
    monkeypatch.setattr(es, "STEP_BLOCK", 10 * raw.n)
    whole = sm.state_acceleration(data, s).copy()
    monkeypatch.setattr(es, "STEP_BLOCK", block)
    assert np.array_equal(sm.state_acceleration(data, s), whole)


def test_a_full_pass_after_other_points_has_a_fresh_formulations_rows():
    """A coarse mesh's elements hand their largest arrays to the next point's as memory (not
    values): a full pass made after passes at two other points has, bit for bit, the rows of
    the same point made first in a fresh formulation; and the rows move with the point (the
    gyro bias, the attitude), nothing kept from the points before."""
    from bvpnav.error_models.error_states import states_at
    from bvpnav.formulation import Formulation
    from bvpnav.linalg.lsq import least_squares_form

    def rows(form, nodes):
        raw, sm = form.data, form.model.state_model
        f = Formulation(states_at(raw, sm.expand(raw, nodes)), form.residual, form.sigma_a, form.error_model,
                        form.items, grade=None, segment=form.segment)
        f._observable = True
        return least_squares_form(f, 1.0)

    form = _noisy_states_form()
    n = form.model.N
    rng = np.random.default_rng(7)
    points = [{kind: rng.normal(scale=s, size=(n, 3))
               for kind, s in (("attitude_error", 0.05), ("gyro_bias", 2e-3), ("acc_bias", 0.05))}
              for _ in range(3)]
    first = rows(_noisy_states_form(), points[2])
    seen = [rows(form, p) for p in points]
    for a, b in ((first.D, seen[2].D), (first.E, seen[2].E)):
        assert np.array_equal(a.c, b.c)
        assert np.array_equal(a.A.indptr, b.A.indptr) and np.array_equal(a.A.indices, b.A.indices)
        assert np.array_equal(a.A.data, b.A.data)
    for a, b in ((seen[0], seen[1]), (seen[1], seen[2])):   # each point's own rows
        assert np.abs(a.E.c - b.E.c).max() > 1e-3 * np.abs(a.E.c).max()
        assert abs(a.E.A - b.E.A).max() > 1e-3 * abs(a.E.A).max()
        assert np.abs(a.D.c - b.D.c).max() > 1e-3 * np.abs(a.D.c).max()


def test_cheap_steps_give_the_full_passes_answer():
    """With cheap intermediate steps (``attitude={"cheap": True}``, the default) the loop
    converges to the answer of full passes only: the last step is always a full pass (through
    the stage), and the first after cheap ones too; the counts are in the report."""
    from bvpnav.error_models import ErrorStates

    d = _drive(T=20.0, noise=True)
    model = ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-4, acc_drift=1e-3)
    sols = {}
    for cheap in (True, False):
        k = np.arange(0, d["t"].size, 20)
        prob = bvpnav.NavigationProblem(d["data"], error_model=model, sigma_a=2e-2, segment=1.0)
        prob.add(Position(t=d["t"][k], value=d["fix"][k], sigma=0.3))
        sols[cheap] = prob.solve(solver="direct", attitude={"progress": False, "cheap": cheap})
    fast, slow = sols[True].records.attitude, sols[False].records.attitude
    kinds = [it["solve"] for it in fast.iterations]
    assert fast.cheap_steps == kinds.count("cheap") >= 2
    assert slow.cheap_steps == 0 and "cheap" not in [it["solve"] for it in slow.iterations]
    assert kinds[-1] == "stage" and fast.converged and slow.converged
    # the first full pass after cheap steps is one banded solve while what they left out
    # (CHEAP_GAP times the gyro-bias rotation) is at least tol and it is not the last allowed step
    due = [i + 1 for i in range(len(kinds) - 1) if kinds[i] == "cheap" and kinds[i + 1] != "cheap"
           and CHEAP_GAP * np.sqrt(2.0 * fast.iterations[i]["cheap_error"]) >= fast.tol
           and i + 2 < fast.max_iter]
    assert due and all(kinds[i] == "banded" for i in due), kinds
    # measured: positions 1.1e-12 relative apart, states 3e-10 (both stop at a step below 1e-7 rad)
    a, b = sols[True], sols[False]
    assert np.abs(a.position() - b.position()).max() <= 1e-9 * np.abs(b.position()).max()
    assert np.abs(a.error_states.to_numpy() - b.error_states.to_numpy()).max() <= 1e-8
    assert a.stats["verified"] and b.stats["verified"]


def test_a_start_far_off_takes_a_cheap_second_step():
    """From a start whose first step is at least CHEAP_FIRST (a heading 0.3 rad off, the heading
    open) the second step is cheap when what it leaves out is within CHEAP_ERROR, before the
    rate of convergence is known (it needs two steps); the answer is the cheap-off loop's, in
    fewer full passes."""
    from error_models.test_error_states import GRAV
    from scipy.spatial.transform import Rotation

    from bvpnav.error_models import ErrorStates

    d = _drive(T=20.0, noise=True)
    data = bvpnav.ImuData.from_gyro(d["t"], d["data"].specific_force, d["data"].gyro,
                                    initial_attitude=Rotation.from_rotvec([0.0, 0.0, 0.3]) * d["C"][0],
                                    gravity=GRAV)
    model = ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-5, acc_drift=1e-3,
                        attitude_sigma=[0.1, 0.1, np.inf], gyro_sigma=1e-3, acc_sigma=1e-3)
    k = np.arange(0, d["t"].size, 20)
    sols = {}
    for cheap in (True, False):
        prob = bvpnav.NavigationProblem(data, error_model=model, sigma_a=2e-2, segment=1.0)
        prob.add(Position(t=d["t"][k], value=d["fix"][k], sigma=0.3))
        sols[cheap] = prob.solve(solver="direct", attitude={"progress": False, "cheap": cheap})
    fast, slow = sols[True].records.attitude, sols[False].records.attitude
    first, second = fast.iterations[:2]
    # measured: first step 0.39 rad, the second's cheap error 1.2e-6 rad
    assert first["step"] >= CHEAP_FIRST and first["solve"] == "banded"
    assert second["solve"] == "cheap" and second["cheap_error"] <= CHEAP_ERROR
    assert fast.converged and slow.converged and fast.full_passes < slow.full_passes
    # measured: positions 3e-13 relative apart
    a, b = sols[True], sols[False]
    assert np.abs(a.position() - b.position()).max() <= 1e-9 * np.abs(b.position()).max()
    assert np.abs(a.error_states.to_numpy() - b.error_states.to_numpy()).max() <= 1e-8
    assert a.stats["verified"] and b.stats["verified"]


def test_a_cheap_step_whose_rows_fail_is_made_again_as_a_full_pass(monkeypatch):
    """A cheap point whose least-squares rows cannot be built (here: made to fail) does not end
    the solve: the step is made again as a full pass, and the loop is the cheap-off loop."""
    import bvpnav.linalg.lsq as lsq
    from bvpnav.error_models import ErrorStates
    from bvpnav.error_models.error_states import _cheap

    d = _drive(T=20.0, noise=True)
    model = ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-4, acc_drift=1e-3)
    k = np.arange(0, d["t"].size, 20)
    built = lsq.least_squares_form
    tried = []

    def failing(form, lam, surrogate=False):
        if _cheap(form.data) is not None:
            tried.append(lam)
            raise RuntimeError("cheap rows refused (test)")
        return built(form, lam, surrogate)

    sols = {}
    for cheap in (True, False):
        prob = bvpnav.NavigationProblem(d["data"], error_model=model, sigma_a=2e-2, segment=1.0)
        prob.add(Position(t=d["t"][k], value=d["fix"][k], sigma=0.3))
        with monkeypatch.context() as mp:
            mp.setattr(lsq, "least_squares_form", failing)
            sols[cheap] = prob.solve(solver="direct", attitude={"progress": False, "cheap": cheap})
    assert len(tried) >= 2   # cheap points were made (and each made again as a full pass)
    a, b = sols[True], sols[False]
    kinds = [it["solve"] for it in a.records.attitude.iterations]
    assert "cheap" not in kinds and kinds == [it["solve"] for it in b.records.attitude.iterations]
    assert a.records.attitude.converged and a.stats["verified"]
    np.testing.assert_array_equal(a.position(), b.position())


def test_a_band_takes_no_cheap_step():
    """A band's steps are the active set's (not one banded solve): the loop takes no cheap step
    with it, and its answer is the cheap-off loop's."""
    from bvpnav.error_models import ErrorStates

    d = _drive(T=30.0, noise=True)
    model = ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-4, acc_drift=1e-3)
    k = np.arange(0, d["t"].size, 20)
    sols = {}
    for cheap in (True, False):
        prob = bvpnav.NavigationProblem(d["data"], error_model=model, sigma_a=2e-2, segment=1.0)
        prob.add(Position(t=d["t"][k], value=d["fix"][k], mode="band", tol=0.2))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sols[cheap] = prob.solve(solver="direct", attitude={"progress": False, "cheap": cheap})
    a, b = sols[True], sols[False]
    kinds = [it["solve"] for it in a.records.attitude.iterations]
    assert a.records.attitude.cheap_steps == 0 and "cheap" not in kinds
    assert kinds == [it["solve"] for it in b.records.attitude.iterations] and a.records.attitude.converged
    np.testing.assert_array_equal(a.position(), b.position())


def test_a_loop_with_linearized_items_on_a_mesh_takes_no_cheap_step():
    """Items the sequential stage linearizes (a fix's estimated delay) are linearized once per
    intermediate step; such a loop never takes cheap steps (their rows move with the point),
    though it runs on a coarse mesh (fixes at every sample keep every shifted time on it)."""
    from bvpnav.error_models import ErrorStates, TimeOffset

    d = _drive(T=20.0, noise=True)
    model = ErrorStates(arw=2e-3 / np.sqrt(20.0), gyro_drift=1e-4, acc_drift=1e-3) + TimeOffset()
    prob = bvpnav.NavigationProblem(d["data"], error_model=model, sigma_a=2e-2, segment=1.0)
    prob.add(Position(t=d["t"], value=d["fix"], sigma=0.3, delay="estimated"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = prob.solve(solver="direct", attitude={"progress": False})
    assert prob.formulation.data.state_mesh is not None   # the node states sit on a mesh
    rep = sol.records.attitude
    kinds = [it["solve"] for it in rep.iterations]
    assert "linearized once" in kinds and "cheap" not in kinds and rep.cheap_steps == 0
    assert rep.converged and kinds[-1] == "stage"


def test_a_linearized_item_on_a_mesh_reads_the_trajectory_at_its_own_times():
    """The sequential loop linearizes an item about the answer's trajectory, which on a mesh is
    at every sample, not at the nodes: ``KnownDistance`` on a 1 s mesh (it failed with a
    reshape error of 1203 values into 33 rows). Noise-free, sparse fixes, a hard known
    distance between two instants inside elements: the estimate is the truth to rounding and
    holds the distance, as the per-sample problem does."""
    from bvpnav.constraints import KnownDistance, Position
    from bvpnav.error_models import ErrorStates

    d = _drive(T=20.0)
    k = np.arange(0, d["t"].size, 20)
    ia, ib = 30, 250
    dist = float(np.linalg.norm(d["r"][ib] - d["r"][ia]))
    out = {}
    for segment in (None, 1.0):
        prob = bvpnav.NavigationProblem(d["data"], error_model=ErrorStates(arw=1e-4, gyro_drift=1e-4,
                                                                           acc_drift=1e-3),
                                        sigma_a=2e-2, segment=segment)
        prob.add(Position(t=d["t"][k], value=d["fix"][k], sigma=0.3),
                 KnownDistance(t=(d["t"][ia], d["t"][ib]), distance=dist, mode="hard"))
        sol = prob.solve(solver="direct", attitude={"progress": False})
        pos = sol.position()
        assert sol.stats["verified"]
        assert abs(np.linalg.norm(pos[ib] - pos[ia]) - dist) < 1e-6 * dist
        out[segment] = pos
    assert np.max(np.abs(out[1.0] - d["r"])) < 1e-5
    assert np.max(np.abs(out[None] - d["r"])) < 1e-5


def test_mesh_states_solution_keeps_no_spare_memory():
    """The full passes hand each other their largest arrays as memory (the kept elements'
    ``spare``); when the loop ends they are dropped, so a solution keeps none alive, nor the
    last expand's totals and attitude (read once, for the answer's attitude)."""
    import gc

    from bvpnav.error_models import ErrorStates
    from bvpnav.error_models.error_states import _Elements

    d = _drive(noise=True)
    model = ErrorStates(arw=1e-3, gyro_drift=1e-4, acc_drift=1e-3)
    _, sol = _states_solve(d, model, 1.0, every=20, sigma=0.3, sigma_a=2e-2)
    assert sol.stats["sequential"]["full_passes"] >= 2   # at least one hand-over took place
    alive = [o for o in gc.get_objects() if isinstance(o, _Elements)]
    assert alive and not any(o.spare for o in alive)
    assert "_expanded_attitude" not in sol.formulation.data.state_point.raw.__dict__
