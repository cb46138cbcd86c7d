"""Body-frame vehicle rows on the coarse mesh (issue 39 on ``segment=``): NonHolonomic and
ForwardMotion rows at samples inside the mesh's elements, through the condensed element."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import bvpnav
from bvpnav.attitude import step_rotation_vectors
from bvpnav.constraints import ForwardMotion, NonHolonomic, Position
from bvpnav.error_models import Bias, ErrorStates, Mounting
from bvpnav.errors import InputError
from bvpnav.mesh import MeshModel
from bvpnav.model import Affine
from bvpnav.scenarios import car_drive
from bvpnav.sensors import grade
from bvpnav.testing import check_item

GRAV = np.array([0.0, 0.0, -9.80665])
BG = np.array([1e-3, -5e-4, 2e-4])
BA = np.array([0.05, -0.03, 0.02])


def _mesh_problem(data, em=None, every=20, value=None, sigma=1.0, sigma_a=0.05, segment=1.0):
    k = np.arange(0, data.t.size, every)
    val = np.zeros((k.size, 3)) if value is None else value[k]
    prob = bvpnav.NavigationProblem(data, error_model=em, sigma_a=sigma_a, segment=segment)
    return prob.add(Position(t=data.t[k], value=val, sigma=sigma, name="fixes"))


@pytest.mark.parametrize("kind", ["bias", "states"])
def test_sample_velocity_is_the_recovered_trajectorys(kind):
    """At every sample, inside the elements as at the nodes, the rows are the velocity of the
    trajectory the mesh recovers (:meth:`MeshModel.trajectory`, the fine FEM between the nodes)
    for any unknowns; the body-frame rows are it rotated, plus omega x lever."""
    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    data = drive.data()
    em = Bias() if kind == "bias" else ErrorStates(arw=1e-3, gyro_drift=1e-4, acc_drift=1e-3)
    model = _mesh_problem(data, em).formulation.model
    assert isinstance(model, MeshModel) and model.N < data.t.size / 15
    x = np.random.default_rng(0).standard_normal(model.size)
    v = model.trajectory(x)["v"]
    got = model.sample_velocity(data.t).value(x).reshape(-1, 3)
    assert np.abs(got - v).max() <= 1e-12 * np.abs(v).max()
    if kind == "bias":      # the states' gyro bias would enter omega; the rotation is the same
        lever = np.array([-1.2, 0.3, -0.4])
        rows = model.body_velocity(data.t[::7], None, lever).value(x).reshape(-1, 3)
        expect = data.attitude[::7].inv().apply(v[::7]) + np.cross(data.gyro[::7], lever)
        assert np.abs(rows - expect).max() <= 1e-12 * np.abs(expect).max()
    # the rows of a sample inside an element touch only its two nodes' unknowns (the band)
    inside = np.flatnonzero(model.cond.element >= 0)[5]
    row = model.sample_velocity(data.t[[inside]], "x").A
    e = model.cond.element[inside]
    r_cols = np.intersect1d(row.indices, model.r_index(0))
    np.testing.assert_array_equal(r_cols, model.r_index(0)[[e, e + 1]])


def _rows_at_nodes(segment):
    from bvpnav.constraints import Odometer
    from bvpnav.error_models import OdometerScale

    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    data = drive.data()
    truth = drive.truth_at(data.t)
    k = np.arange(0, data.t.size, 20)
    prob = bvpnav.NavigationProblem(data, error_model=OdometerScale(), sigma_a=0.05, segment=segment)
    # a fix antenna off the IMU, an odometer and the rows at 1 Hz: the samples of the fixes (nodes)
    prob.add(Position(t=data.t[k], value=truth[k], sigma=0.5, lever=(1.0, 0.2, -0.3), name="fixes"),
             Odometer(t=data.t[k[1::2]], speed=np.linalg.norm(drive.velocity[k[1::2]], axis=1), sigma=0.05,
                      lever=(-1.2, 0.5, -0.4), name="odo"),
             NonHolonomic(mode="soft", sigma=0.1, rate=1.0, lever=(-1.0, 0.0, -0.3), name="nhc"),
             ForwardMotion(min_speed=0.5, rate=1.0, name="fwd"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return prob, prob.solve(solver="direct")


def test_rows_at_node_instants_give_the_per_sample_answer():
    """With the rows at node instants only the condensation is exact: the mesh's answer is the
    answer on every sample, at the nodes and (recovered) between them (a fix antenna's lever
    arm, an odometer with its scale, the non-holonomic rows and forward motion)."""
    fprob, fine = _rows_at_nodes(None)
    mprob, mesh = _rows_at_nodes(1.0)
    assert isinstance(mprob.formulation.model, MeshModel)
    assert fine.stats["verified"] and mesh.stats["verified"]
    scale = np.abs(fine.position()).max()
    assert np.abs(mesh.position() - fine.position()).max() <= 1e-8 * scale
    for name in ("nhc", "fwd", "odo", "fixes"):
        np.testing.assert_allclose(mesh.item_residuals[name], fine.item_residuals[name], rtol=0, atol=1e-8)
    assert abs(mesh.error_params["odometer_scale"] - fine.error_params["odometer_scale"]) < 1e-10


def _car(T=40.0, rate=20.0, bg=BG, ba=BA):
    """A noise-free drive in the model's own discretization whose body x is along the velocity at
    every sample: the attitude integrated from the rates, the velocity ``speed * C e_x``, the
    acceleration linear between samples with these velocities' trapezoid steps and the
    positions its exact integral (so every FEM row, and every non-holonomic row, is zero at the
    truth), biased sensors."""
    n = int(T * rate) + 1
    t = np.linspace(0.0, T, n)
    h = np.diff(t)
    w = np.column_stack([0.02 * np.sin(0.9 * t), 0.01 * np.cos(0.5 * t), 0.15 * np.sin(0.2 * t) + 0.03])
    raw_w = w + bg
    phi = step_rotation_vectors(t, raw_w) - h[:, None] * bg
    C = [Rotation.from_euler("ZYX", [0.4, 0.02, -0.01])]
    for k in range(n - 1):
        C.append(C[-1] * Rotation.from_rotvec(phi[k]))
    C = Rotation.concatenate(C)
    speed = 10.0 + 3.0 * np.sin(0.15 * t)
    v = speed[:, None] * C.as_matrix()[:, :, 0]
    a = np.empty((n, 3))
    a[0] = (v[1] - v[0]) / h[0]
    for k in range(n - 1):          # v[k+1] = v[k] + h (a[k] + a[k+1]) / 2
        a[k + 1] = 2.0 * (v[k + 1] - v[k]) / h[k] - a[k]
    r = np.zeros((n, 3))
    for k in range(n - 1):
        r[k + 1] = r[k] + h[k] * v[k] + h[k] ** 2 * (2 * a[k] + a[k + 1]) / 6
    f = C.inv().apply(a - GRAV) + ba
    data = bvpnav.ImuData.from_gyro(t, f, raw_w, initial_attitude=C[0], gravity=GRAV)
    return {"t": t, "data": data, "C": C, "r": r, "v": v}


def test_noise_free_car_is_recovered_with_rows_inside_the_elements():
    """Node states on a 2 s mesh, fixes every 10 s, the rows at 10 Hz (inside the elements): the
    truth zeroes every row, so the answer is the truth (positions to 1e-6 m, biases to 1e-9),
    and the rows' velocity at their instants is the truth's body velocity (speed, 0, 0)."""
    d = _car()
    em = ErrorStates(arw=1e-5, gyro_drift=0.0, acc_drift=0.0)
    nhc = NonHolonomic(mode="soft", sigma=0.01, name="nhc")
    prob = _mesh_problem(d["data"], em, every=200, value=d["r"], sigma=1e-3, sigma_a=1e-4, segment=2.0)
    prob.add(nhc)
    sol = prob.solve(solver="direct", attitude={"progress": False})
    model = sol.formulation.model
    assert isinstance(model, MeshModel) and model.N <= 25
    t_rows = nhc.instants(model)
    assert np.isin(t_rows, d["t"]).all() and not np.isin(t_rows, model.grid.t).all()
    assert sol.stats["verified"] and sol.records.attitude.converged
    assert np.abs(sol.position() - d["r"]).max() < 1e-6
    es = sol.error_states
    assert np.abs(es.filter(like="gyro_bias").to_numpy() - BG).max() < 1e-9
    assert np.abs(es.filter(like="acc_bias").to_numpy() - BA).max() < 1e-8
    assert np.abs(sol.item_residuals["nhc"]).max() < 1e-7
    k = np.searchsorted(d["t"], t_rows)
    forward = model.body_velocity(t_rows, "x").value(sol.x)
    np.testing.assert_allclose(forward, np.linalg.norm(d["v"][k], axis=1), rtol=0, atol=1e-6)


def test_noisy_drive_on_the_mesh_matches_the_per_sample_rows():
    """A tactical car drive (60 s at 10 Hz, fixes every 20 s), node states: with the rows (soft,
    inside the 1 s elements, alone and with the mounting estimated; and the default band with
    forward motion, by direct, whose rows get nodes: every sample at this rate) the mesh's answer
    is the per-sample one (measured: RMS 1.09274471 against 1.09274475 m soft, mounting yaw to
    3e-7 relative). The rows inside an element linearize about their own sample's velocity: about
    one interpolated between the nodes the mesh was 1.0933 m and the yaw 0.7 % off."""
    drive = car_drive(duration=60.0, rate=10.0, grade="tactical", seed=1)
    g = grade("tactical")
    keep = np.arange(0, drive.fix_t.size, 20)
    out = {}
    for seg in (None, 1.0):
        for name, extra in (("soft", [NonHolonomic(mode="soft", sigma=0.1)]),
                            ("mount", [NonHolonomic(mode="soft", sigma=0.1, mounting="estimated")]),
                            ("band", [NonHolonomic(), ForwardMotion()])):
            em = ErrorStates(arw=g.gyro_noise, gyro_drift=g.gyro_bias_walk, acc_drift=g.acc_bias_walk,
                             attitude_sigma=[0.02, 0.02, 0.2], gyro_sigma=g.gyro_bias, acc_sigma=g.acc_bias)
            if name == "mount":
                em = em + Mounting(sigma=0.02)
            prob = bvpnav.NavigationProblem(drive.data(), error_model=em, sigma_a=g.acc_noise * np.sqrt(10.0),
                                            segment=seg)
            prob.add(Position(t=drive.fix_t[keep], value=drive.fix_position[keep],
                              sigma=np.tile(drive.fix_sigma, (keep.size, 1))), *extra)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sol = prob.solve(solver="direct", attitude={"progress": False})
            assert sol.stats["verified"] and sol.records.attitude.converged
            out[seg, name] = float(np.sqrt(np.mean(np.sum((sol.position() - drive.position) ** 2, axis=1))))
            if name == "mount":
                out[seg, "yaw"] = float(sol.error_params["mounting_yaw"])
    for name in ("soft", "mount", "band", "yaw"):
        assert abs(out[1.0, name] - out[None, name]) <= 1e-5 * abs(out[None, name]), out
    assert out[None, "soft"] < 1.3       # the rows help (1.85 m without them)


def test_held_rows_get_nodes_and_penalty_rows_stay_inside():
    """Rows held as constraints (a hard-edged band, hard, forward motion's inequality) get mesh
    nodes at their instants; penalty rows (soft, robust, the default band's soft edges) stay at
    their samples inside the elements."""
    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    data = drive.data()
    for item, nodes in ((NonHolonomic(tol=0.1), True), (NonHolonomic(mode="hard"), True),
                        (ForwardMotion(), True), (NonHolonomic(), False),
                        (NonHolonomic(sigma=0.1), False), (ForwardMotion(sigma=0.1, mode="soft"), False),
                        (NonHolonomic(mode="robust", sigma=0.1, huber=1.0), False)):
        model = _mesh_problem(data).add(item).formulation.model
        rows = item.instants(model)
        assert rows.size == 601
        assert np.isin(rows, model.grid.t).all() == nodes, item
        assert (model.N > 600) == nodes


def test_contract_on_a_mesh_model():
    data = NonHolonomic.example_model().data
    model = MeshModel(data, segment=1.0, times=[0.0, 10.0])
    assert model.N < data.t.size
    check_item(NonHolonomic, model)
    check_item(ForwardMotion, model)
    check_item(NonHolonomic(sigma=0.05, axes=("x", "y", "z"), rate=None, lever=(0.4, -0.2, 0.1)), model)
    check_item(NonHolonomic(rate="nodes", lever=(-0.5, 0.0, -0.3), t=[(0.0, 4.0), (6.0, 10.0)]), model)
    check_item(NonHolonomic(rate="nodes", sigma=0.05, lever=(0.4, -0.2, 0.1)), model)
    check_item(ForwardMotion(rate="nodes", min_speed=0.5, max_speed=30.0, lever=(-0.5, 0.0, 0.0)), model)


def test_contract_on_a_node_state_mesh():
    """The rows at the nodes on the documented path's model (node states on a 1 s mesh, which a
    problem makes): the coarser model of the checks is a problem's mesh too, with nodes at the
    item's interval ends, so an interval between two fixes' nodes has its node rows there."""
    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    data = drive.data()
    k = np.arange(0, data.t.size, 20)
    em = ErrorStates(arw=1e-3, gyro_drift=1e-4, acc_drift=1e-3)
    item = NonHolonomic(rate="nodes", t=[(2.3, 2.6), (10.0, 30.0)])
    prob = bvpnav.NavigationProblem(data, error_model=em, sigma_a=0.05, segment=1.0)
    prob.add(Position(t=data.t[k], value=drive.position[k], sigma=1.0), item)
    model = prob.formulation.model
    assert isinstance(model, MeshModel) and model.ns and {2.3, 2.6} <= set(np.round(model.grid.t, 9))
    check_item(item, model)
    check_item(NonHolonomic(rate="nodes", sigma=0.1, lever=(-1.0, 0.0, -0.3)), model)
    check_item(ForwardMotion(rate="nodes"), model)
    check_item(NonHolonomic(), model)


def test_what_the_mesh_still_refuses():
    """Rows between two samples inside an element, and the attitude loop's parameter models."""
    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    data = drive.data()
    model = _mesh_problem(data).formulation.model
    t = 0.5 * (data.t[31] + data.t[32])
    with pytest.raises(InputError, match=r"probe: time .* inside the mesh element"):
        model.body_velocity([t], what="probe")
    from bvpnav.error_models import GyroBias

    with pytest.raises(InputError, match="GyroBias.*not carried.*segment=None"):
        _ = _mesh_problem(data, GyroBias(interval=20.0)).formulation.model


def test_rows_at_the_nodes_follow_the_mesh_and_ask_it_for_none():
    """``rate="nodes"``: one row per node (inside the intervals) of the mesh the other items and
    ``segment`` make, held or soft; the mesh is the one without the rows, and a problem without a
    mesh refuses it, naming the fix."""
    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    data = drive.data()
    plain = _mesh_problem(data).formulation.model
    for item in (NonHolonomic(rate="nodes"), NonHolonomic(rate="Nodes", sigma=0.1),
                 ForwardMotion(rate="nodes"), NonHolonomic(rate="nodes", mode="hard")):
        assert item.rate == "nodes" and item.rows_at_nodes
        model = _mesh_problem(data).add(item).formulation.model
        np.testing.assert_array_equal(model.grid.t, plain.grid.t)
        np.testing.assert_array_equal(item.instants(model), plain.grid.t)
    spans = NonHolonomic(rate="nodes", t=[(5.0, 20.0), (30.0, 41.3)])
    model = _mesh_problem(data).add(spans).formulation.model
    t = model.grid.t
    expect = t[((t >= 5.0) & (t <= 20.0)) | ((t >= 30.0) & (t <= 41.3))]
    np.testing.assert_array_equal(spans.instants(model), expect)
    assert expect.size == 16 + 12 + 1 and 41.3 in expect     # the interval ends are nodes (its t)
    assert not NonHolonomic(rate=1.0).rows_at_nodes and not ForwardMotion(rate=None).rows_at_nodes
    with pytest.raises(InputError, match=r"NonHolonomic.*rate='nodes'.*no mesh.*segment=1.0.*rate=1.0"):
        _mesh_problem(data, segment=None).add(NonHolonomic(rate="nodes")).formulation.terms()
    with pytest.raises(InputError, match=r"rate='node'.*'nodes'"):
        NonHolonomic(rate="node")
    with pytest.raises(InputError, match=r"ForwardMotion.*rate=-1.*'nodes'"):
        ForwardMotion(rate=-1)


def test_node_time_fast_paths_are_the_general_rows(monkeypatch):
    """At node times the velocity rows are the model's node rows (made once) and the attitude error
    is the node states' own columns and totals (no columns of every sample): the same A and c as
    the general paths (the attitude error read with a time inside an element among them, the
    velocity at each time alone), at a node-state loop's point with nonzero totals."""
    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    g = grade("tactical")
    em = ErrorStates(arw=g.gyro_noise, gyro_drift=g.gyro_bias_walk, acc_drift=g.acc_bias_walk,
                     attitude_sigma=[0.02, 0.02, 0.2], gyro_sigma=g.gyro_bias, acc_sigma=g.acc_bias)
    keep = np.arange(0, drive.fix_t.size, 20)
    prob = bvpnav.NavigationProblem(drive.data(), error_model=em, sigma_a=g.acc_noise * np.sqrt(20.0),
                                    segment=1.0)
    prob.add(Position(t=drive.fix_t[keep], value=drive.fix_position[keep],
                      sigma=np.tile(drive.fix_sigma, (keep.size, 1))), NonHolonomic(sigma=0.1, rate="nodes"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = prob.solve(solver="direct", attitude={"progress": False})
    model = sol.formulation.model
    assert isinstance(model, MeshModel) and model.ns and sol.stats["verified"]
    tot = model.state_model.state_total(model.data, "attitude_error")
    assert np.abs(tot).max() > 1e-3               # a point away from the data as measured
    nodes = model.grid.t[3:-2:2]
    inside = model.fine.t[np.flatnonzero(model.cond.element >= 0)[::37]]
    mixed = np.sort(np.r_[nodes, inside])
    at = np.searchsorted(mixed, nodes)

    def same(fast, general):
        assert fast.A.shape == general.A.shape and fast.A.shape[0] > 0
        assert abs(fast.A - general.A).max() <= 1e-12 * max(abs(general.A).max(), 1.0)
        assert np.abs(fast.c - general.c).max() <= 1e-12 * max(np.abs(general.c).max(), 1.0)

    for axes in (None, ("y", "z"), "x"):
        na = 3 if axes is None else len(axes)
        rows = (at[:, None] * na + np.arange(na)).ravel()
        fast = model.states("attitude_error", nodes, axes)
        assert list(fast.labels) == list(model.states("attitude_error", mixed, axes).rows(rows).labels)
        same(fast, model.states("attitude_error", mixed, axes).rows(rows))
        names = None if axes is None else list(np.atleast_1d(axes))
        one = Affine.vstack([model.velocity([t], names) for t in nodes])   # each time alone
        same(model.sample_velocity(nodes, names), one)
        same(model.sample_velocity(mixed, names).rows(rows), one)
    # the node rows of the attitude error: the node's own state, its total the node's
    k = np.searchsorted(model.grid.t, nodes)
    idx = model.state_model.state_index(model.data, "attitude_error")[k] + model.s_index[0]
    fast = model.states("attitude_error", nodes)
    np.testing.assert_array_equal(fast.A.indices, idx.ravel())
    np.testing.assert_array_equal(fast.A.data, 1.0)
    np.testing.assert_array_equal(fast.c, tot[k].ravel())
    # the body rows at the nodes: every axis made once per model, the axes asked for taken from them
    for axes, lever in ((("y", "z"), (0.0, 0.0, 0.0)), ("x", (0.0, 0.0, 0.0)), (None, (-1.2, 0.3, -0.4))):
        got = model.body_velocity(nodes, axes, lever)
        assert np.array_equal(got.c, bvpnav.NavModel.body_velocity(model, nodes, axes, lever).c)
        same(got, bvpnav.NavModel.body_velocity(model, nodes, axes, lever))
        assert list(got.labels) == list(bvpnav.NavModel.body_velocity(model, nodes, axes, lever).labels)
        on = np.flatnonzero(np.repeat(np.isin(mixed, nodes), got.m // nodes.size))
        same(model.body_velocity(mixed, axes, lever).rows(on), got)
    # made without the columns of every sample
    model.__dict__.pop("_att_cols", None)

    def every_sample(*args):
        raise AssertionError("the attitude columns of every sample were made")

    monkeypatch.setattr(type(model.state_model), "attitude_columns", every_sample)
    same(model.states("attitude_error", nodes), fast)
    with pytest.raises(AssertionError, match="every sample were made"):
        model.states("attitude_error", mixed)


def test_rows_at_the_nodes_linearize_about_the_node_velocities(monkeypatch):
    """With every body-frame row at the nodes the node-state loop's velocity point is the node
    velocities (linear between them, which no row reads): at the nodes the recovered trajectory's
    own to rounding, and the answer the one linearized about every sample's velocity (the same
    steps, positions to 1e-9 m)."""
    import bvpnav.solve.attitude as attitude

    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    g = grade("tactical")
    keep = np.arange(0, drive.fix_t.size, 20)

    def solve():
        em = ErrorStates(arw=g.gyro_noise, gyro_drift=g.gyro_bias_walk, acc_drift=g.acc_bias_walk,
                         attitude_sigma=[0.02, 0.02, 0.2], gyro_sigma=g.gyro_bias, acc_sigma=g.acc_bias)
        prob = bvpnav.NavigationProblem(drive.data(), error_model=em, sigma_a=g.acc_noise * np.sqrt(20.0),
                                        segment=1.0)
        prob.add(Position(t=drive.fix_t[keep], value=drive.fix_position[keep],
                          sigma=np.tile(drive.fix_sigma, (keep.size, 1))),
                 NonHolonomic(rate="nodes"), ForwardMotion(rate="nodes"))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return prob.solve(solver="direct", attitude={"progress": False})

    calls = []
    node_point = MeshModel.node_point_velocities
    monkeypatch.setattr(MeshModel, "node_point_velocities",
                        lambda self, x: calls.append(1) or node_point(self, x))
    fast = solve()
    model = fast.formulation.model
    assert calls and fast.stats["verified"] and fast.records.attitude.converged
    v_nodes = model.node_point_velocities(fast.x)
    v_all = model.point_velocities(fast.x)
    nodes = model.grid.nodes
    np.testing.assert_allclose(v_nodes[nodes], v_all[nodes], rtol=0, atol=1e-9 * np.abs(v_all).max())
    inside = np.flatnonzero(model.cond.element >= 0)
    assert np.abs(v_nodes[inside] - v_all[inside]).max() > 1e-4     # between the nodes they differ
    made = len(calls)
    monkeypatch.setattr(attitude, "_rows_at_nodes", lambda items, m: False)
    general = solve()
    assert general.stats["verified"] and len(calls) == made
    assert fast.stats["sequential"]["solves"] == general.stats["sequential"]["solves"]
    np.testing.assert_allclose(fast.position(), general.position(), rtol=0, atol=1e-9)


def test_rows_at_the_nodes_alone_take_the_node_point():
    """The node velocities are the loop's point only when every body-frame item has its rows at
    the nodes: with soft rows inside the elements beside them (10 Hz), or none, the samples'."""
    from bvpnav.solve.attitude import _rows_at_nodes

    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    model = _mesh_problem(drive.data()).formulation.model
    fixes = Position(t=[0.0], value=np.zeros((1, 3)), sigma=1.0)
    assert _rows_at_nodes([fixes, NonHolonomic(rate="nodes"), ForwardMotion(rate="nodes")], model)
    assert not _rows_at_nodes([fixes, NonHolonomic(rate="nodes"), NonHolonomic(sigma=0.1, name="b")], model)
    assert not _rows_at_nodes([fixes, ForwardMotion(rate="nodes"), NonHolonomic()], model)
    assert not _rows_at_nodes([fixes], model)
    assert not _rows_at_nodes([NonHolonomic(rate=1.0)], model)


def test_with_acc_drops_the_rows_that_hold_the_accelerations():
    """A mesh model for other accelerations does not keep the node velocities or the body rows at
    the nodes made with the first ones: its rows are a fresh model's."""
    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    model = _mesh_problem(drive.data()).formulation.model
    item = NonHolonomic(rate="nodes", lever=(-1.0, 0.2, -0.3))
    first = item.compile(model)
    assert "_node_velocities" in model.__dict__ and "_node_body_rows" in model.__dict__
    acc = np.zeros_like(model.data.acc)
    other = model.with_acc(acc)
    fresh = MeshModel(other.data, None, segment=model.segment, nodes=model.grid.nodes)
    np.testing.assert_allclose(item.compile(other).c, item.compile(fresh).c, rtol=0, atol=1e-12)
    np.testing.assert_allclose(other.sample_velocity(model.grid.t).c, fresh.sample_velocity(model.grid.t).c,
                               rtol=0, atol=1e-12)
    assert np.abs(first.c - item.compile(other).c).max() > 0.1


def test_rounding_noise_of_exact_zeros_is_dropped_from_rows_at_the_nodes():
    """Entries below 1e-14 of their row's largest (the off-diagonal rounding of C^T C = I) are
    dropped, so the rows' pattern does not move between linearization points; the others and the
    constants stay as they are."""
    import scipy.sparse as sp

    from bvpnav.constraints.non_holonomic import without_rounding_noise

    A = sp.csr_matrix(np.array([[1.0, 3e-21, -2e-8, 0.0], [0.0, 5e-3, -4e-17, 1e-16], [0.0, 0.0, 0.0, 0.0]]))
    rows = without_rounding_noise(Affine(A, np.array([1.0, 2.0, 3.0]), ("a", "b", "c")))
    np.testing.assert_array_equal(rows.A.toarray(), [[1.0, 0.0, -2e-8, 0.0], [0.0, 5e-3, 0.0, 1e-16],
                                                     [0.0, 0.0, 0.0, 0.0]])
    assert rows.A.nnz == 4 and list(rows.c) == [1.0, 2.0, 3.0] and tuple(rows.labels) == ("a", "b", "c")
    assert np.array_equal(A.toarray()[0], [1.0, 3e-21, -2e-8, 0.0])      # the input is not changed
    drive = car_drive(duration=60.0, rate=20.0, grade="tactical", seed=1)
    model = _mesh_problem(drive.data()).formulation.model
    for item in (NonHolonomic(rate="nodes"), ForwardMotion(rate="nodes")):
        got = item.compile(model).A
        full = (bvpnav.NavModel.body_velocity(model, model.grid.t, item.axes or "x")).A
        big = np.repeat(abs(full).max(axis=1).toarray().ravel(), np.diff(got.indptr))
        assert np.all(np.abs(got.data) >= 1e-14 * big) and got.nnz <= full.nnz
