"""FEM assembly and the core formulation: exactness, convergence, velocity recovery."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from _helpers import exact_piecewise_linear, quintic

import bvpnav
from bvpnav import fem
from bvpnav.constraints import Position, Velocity
from bvpnav.grid import TimeGrid


def grids():
    rng = np.random.default_rng(7)
    uniform = np.linspace(0.0, 4.0, 201)
    steps = rng.uniform(0.005, 0.04, 300)
    nonuniform = np.concatenate([[0.0], np.cumsum(steps)])
    return {"uniform": uniform, "nonuniform": nonuniform}


def test_stiffness_and_mass_match_element_integrals():
    t = np.array([0.0, 0.1, 0.3, 0.35, 1.0])
    g = TimeGrid(t)
    K = fem.stiffness(g).toarray()
    M = fem.mass(g).toarray()
    Kref = np.zeros((5, 5))
    Mref = np.zeros((5, 5))
    for j, h in enumerate(np.diff(t)):
        Kref[j:j + 2, j:j + 2] += np.array([[1, -1], [-1, 1]]) / h
        Mref[j:j + 2, j:j + 2] += np.array([[2, 1], [1, 2]]) * h / 6
    np.testing.assert_allclose(K, Kref, rtol=1e-14)
    np.testing.assert_allclose(M, Mref, rtol=1e-14)
    assert np.allclose(K @ np.ones(5), 0.0)  # constants are in the null space
    assert np.all(np.linalg.eigvalsh(M) > 0)


def test_load_vector_integrates_linear_acceleration():
    g = TimeGrid(np.array([0.0, 0.5, 1.25, 2.0]))
    a = np.array([1.0, -2.0, 0.5, 3.0])
    f = fem.load(g, a)
    # f_j = -integral(a phi_j), checked by fine quadrature of the interpolants
    tt = np.linspace(0.0, 2.0, 200001)
    aa = np.interp(tt, g.t, a)
    for j in range(4):
        phi = np.interp(tt, g.t, np.eye(4)[j])
        ref = -np.trapezoid(aa * phi, tt)
        assert f[j] == pytest.approx(ref, rel=1e-8, abs=1e-10)


def test_interpolation_rows_reproduce_linear_functions():
    g = TimeGrid(grids()["nonuniform"])
    times = np.linspace(g.t0, g.t1, 77)
    P = g.interpolation_matrix(times)
    assert isinstance(P, sp.csr_matrix)
    np.testing.assert_allclose(P @ (3.0 * g.t - 1.0), 3.0 * times - 1.0, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("kind", ["uniform", "nonuniform"])
def test_exact_for_piecewise_linear_acceleration(kind):
    t = grids()[kind]
    rng = np.random.default_rng(3)
    acc = rng.normal(0.0, 2.0, t.size)
    r, v = exact_piecewise_linear(t, acc, r0=1.5, v0=-0.7)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc))
    prob.add(Position(t=[t[0], t[-1]], value=[r[0], r[-1]]))
    sol = prob.solve()
    scale = np.max(np.abs(r))
    assert np.max(np.abs(sol.position("x") - r)) / scale < 1e-8
    # the velocity recovery is exact too when the nodal positions are
    assert np.max(np.abs(sol.velocity("x") - v)) / np.max(np.abs(v)) < 1e-8
    # and the acceleration residual is zero: nothing had to be corrected
    assert np.max(np.abs(sol.residuals["w_x"])) < 1e-8


def _quintic_errors(rate):
    p, v, a = quintic()
    t = np.linspace(0.0, 10.0, int(10 * rate) + 1)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=a(t)))
    prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0]))
    sol = prob.solve()
    ep = np.sqrt(np.mean((sol.position("x") - p(t)) ** 2))
    ev = np.sqrt(np.mean((sol.velocity("x") - v(t)) ** 2))
    return ep, ev, sol


def test_position_converges_second_order():
    errs = [_quintic_errors(rate)[0] for rate in (25, 50, 100, 200)]
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all(ratios >= 3.5), ratios


def test_velocity_converges_at_least_first_order():
    errs = [_quintic_errors(rate)[1] for rate in (25, 50, 100, 200)]
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all(ratios >= 1.9), ratios  # O(h); measured ~4 (second order)


def test_end_velocity_items_are_exact():
    p, v, a = quintic()
    t = np.linspace(0.0, 10.0, 301)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=a(t) + 0.3))  # biased
    prob.add(Position(t=0.0, value=0.0), Velocity(t=[0.0, 10.0], value=[0.25, -0.5]))
    sol = prob.solve()
    assert sol.velocity("x")[0] == pytest.approx(0.25, abs=1e-9)
    assert sol.velocity("x")[-1] == pytest.approx(-0.5, abs=1e-9)
    # velocity between nodes and at a node agree with the nodal formula
    mid = prob.model.velocity([t[100]]).value(sol.x)[0]
    assert mid == pytest.approx(sol.velocity("x")[100], abs=1e-12)


def test_momentum_balance_of_fem_rows():
    # summing the FEM rows: v1 - v0 = integral of the (corrected) acceleration
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.01, 0.05, 100))
    acc = rng.normal(size=t.size)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc))
    prob.add(Position(t=[t[0], t[-1]], value=[0.0, 1.0]))
    sol = prob.solve()
    integral = np.trapezoid(acc + sol.residuals["w_x"].to_numpy(), t)
    assert sol.velocity("x")[-1] - sol.velocity("x")[0] == pytest.approx(integral, abs=1e-9)


@pytest.mark.parametrize("kind", ["uniform", "nonuniform"])
def test_node_velocity_values_equal_the_rows_of_node_velocity(kind):
    """The solution's velocity column and the stationarity floor evaluate the nodal
    velocity without assembling its rows; the result is the rows' value (scale factor and
    bias columns included), and the operators hold the formula
    v_j = (r_j - r_{j-1})/h_{j-1} + h_{j-1} (a_{j-1} + 2 a_j)/6 at interior nodes."""
    from bvpnav.error_models import Bias, ScaleFactor
    from bvpnav.model import NavModel

    t = grids()[kind]
    rng = np.random.default_rng(3)
    data = bvpnav.ImuData(t, rng.normal(size=(t.size, 3)))
    model = NavModel(data, ScaleFactor() + Bias())
    x = rng.normal(size=model.size)
    for a in range(3):
        want = model.node_velocity(a).value(x)
        got = model.node_velocity_values(a, x)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.max(np.abs(want)))
    Vr, Va, Vb = fem.node_velocity_operators(TimeGrid(t))
    r, acc, h = rng.normal(size=t.size), rng.normal(size=t.size), np.diff(t)
    j = np.arange(1, t.size - 1)
    v = Vr @ r + Va @ acc
    np.testing.assert_allclose(v[j], (r[j] - r[j - 1]) / h[j - 1] + h[j - 1] * (acc[j - 1] + 2 * acc[j]) / 6,
                               rtol=1e-13, atol=1e-13)
    assert v[0] == 0 and v[-1] == 0 and (Vb @ [2.0, 5.0])[[0, -1]].tolist() == [2.0, 5.0]


@pytest.mark.parametrize("kind", ["uniform", "nonuniform"])
def test_velocity_rows_at_nodes_are_the_node_operators_rows(kind):
    """velocity_operators builds only the rows it needs: at node times (the ends, interior
    nodes, a node twice) its rows equal those of node_velocity_operators exactly, and
    between nodes Vr and Vb are those of the element's left node."""
    t = grids()[kind]
    grid = TimeGrid(t)
    NVr, NVa, NVb = fem.node_velocity_operators(grid)
    j = np.array([0, t.size - 1, 1, 5, 5, t.size - 2, 17])
    Vr, Va, Vb = fem.velocity_operators(grid, t[j])
    for got, full in ((Vr, NVr), (Va, NVa), (Vb, NVb)):
        assert got.shape == (j.size, full.shape[1])
        np.testing.assert_array_equal(got.toarray(), full[j].toarray())
    mid = 0.5 * (t[j[2:]] + t[j[2:] + 1])   # inside the element right of each interior node
    Vr, Va, Vb = fem.velocity_operators(grid, mid)
    np.testing.assert_array_equal(Vr.toarray(), NVr[j[2:]].toarray())
    np.testing.assert_array_equal(Vb.toarray(), NVb[j[2:]].toarray())
    assert np.all(Va.getnnz(axis=1) == 3)   # v_j's two entries and the element's second node


@pytest.mark.parametrize("axes, error_model", [(1, None), (3, None), (3, "SF+B")])
def test_fem_rows_are_each_axis_blocks_placed_in_its_columns(axes, error_model):
    """The FEM rows, written entry by entry into one CSR matrix, equal each axis' blocks
    (K on r, M on w, the end velocities' columns, M G on the error-model parameters)
    moved to their columns by a COO assembly and stacked, exactly, in canonical form;
    ``_place`` (one axis) gives that axis' rows."""
    from bvpnav.error_models import Bias, ScaleFactor
    from bvpnav.model import rows_side_by_side

    rng = np.random.default_rng(4)
    t = np.sort(np.r_[0.0, 5.0, rng.uniform(0.0, 5.0, 148)])
    acc = rng.standard_normal((t.size, axes))
    em = ScaleFactor() + Bias() if error_model else None
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc if axes > 1 else acc[:, 0]), error_model=em)
    model = prob.formulation.model
    fem_rows = model.fem_rows()
    # the reference: each block's entries moved to its columns by COO, summed, stacked
    parts = []
    for a in range(axes):
        blocks, o = model.fem_blocks(a), a * model.block
        starts = {"r": o, "w": o + t.size, "vb": o + 2 * t.size, "l": axes * model.block}
        coo = [(sp.coo_matrix(blocks[key]), starts[key]) for key in starts if key in blocks]
        parts.append(sp.csr_matrix((np.concatenate([c.data for c, _ in coo]),
                                    (np.concatenate([c.row for c, _ in coo]),
                                     np.concatenate([c.col + col for c, col in coo]))),
                                   shape=(t.size, model.size)))
    want = sp.vstack(parts, format="csr")
    want.sort_indices()
    A = fem_rows.A
    assert A.shape == want.shape == (axes * t.size, model.size)
    assert A.has_canonical_format and A.nnz == want.nnz
    np.testing.assert_array_equal(A.indptr, want.indptr)
    np.testing.assert_array_equal(A.indices, want.indices)
    np.testing.assert_array_equal(A.data, want.data)
    for a in range(axes):
        one = model._place(model.fem_blocks(a), a)
        np.testing.assert_array_equal(one.toarray(), want[a * t.size:(a + 1) * t.size].toarray())
    np.testing.assert_array_equal(fem_rows.c, np.concatenate([model.M @ acc.reshape(t.size, -1)[:, a]
                                                              for a in range(axes)]))
    # dense blocks, and groups of other sizes
    B = rows_side_by_side([[(np.eye(2), 1)], [(sp.csr_matrix([[0.0, 3.0]]), 0), (np.array([[5.0]]), 3)]], 4)
    np.testing.assert_array_equal(B.toarray(), [[0, 1, 0, 0], [0, 0, 1, 0], [0, 3, 0, 5]])


def test_rows_side_by_side_writes_uniform_stretches_by_slices_and_the_rest_by_index():
    """Blocks whose entry counts per row are constant on a stretch (written as 2-D slices)
    and vary elsewhere (rows before, after and between, written by index arrays), with
    empty rows and a block empty on the stretch: the same matrix as scipy's ``hstack`` of
    the blocks moved to their columns by COO and stacked, canonical."""
    from bvpnav.model import _uniform_rows, rows_side_by_side

    rng = np.random.default_rng(7)

    def block(rows: int, width: int, counts: np.ndarray) -> sp.csr_matrix:
        cols = [np.sort(rng.choice(width, size=c, replace=False)) for c in counts]
        indptr = np.r_[0, np.cumsum(counts)]
        return sp.csr_matrix((rng.normal(size=indptr[-1]) + 3.0, np.concatenate(cols), indptr),
                             shape=(rows, width))

    for trial in range(20):
        groups, want = [], []
        for _ in range(rng.integers(1, 4)):
            R = int(rng.integers(1, 40))
            col, group = 0, []
            for _ in range(rng.integers(1, 4)):
                width = int(rng.integers(1, 6))
                counts = np.full(R, rng.integers(0, width + 1))
                odd = rng.random(R) < (0.0 if trial % 4 == 0 else 0.2)   # rows off the stretch
                counts[odd] = rng.integers(0, width + 1, size=int(odd.sum()))
                blk = block(R, width, counts)
                col += int(rng.integers(0, 3))
                group.append((blk, col))
                col += width
            groups.append(group)
            coo = [(blk.tocoo(), c) for blk, c in group]
            want.append(sp.csr_matrix((np.concatenate([m.data for m, _ in coo]),
                                       (np.concatenate([m.row for m, _ in coo]),
                                        np.concatenate([m.col + c for m, c in coo]))), shape=(R, 30)))
        got = rows_side_by_side(groups, 30)
        ref = sp.vstack(want, format="csr")
        ref.sort_indices()
        assert got.has_canonical_format
        np.testing.assert_array_equal(got.indptr, ref.indptr)
        np.testing.assert_array_equal(got.indices, ref.indices)
        np.testing.assert_array_equal(got.data, ref.data)
    # the stretch found: the longest run of rows with the middle row's counts in every block
    assert _uniform_rows([np.array([1, 3, 3, 3, 2, 3, 3, 3, 3, 1]), np.full(10, 2)]) == (5, 9)
    assert _uniform_rows([np.array([2, 2, 2])]) == (0, 3)
    assert _uniform_rows([np.array([2, 2])]) == (0, 0)


def test_affine_row_scaling_equals_the_diagonal_product_and_keeps_zero_scales_exact():
    """``Affine * k`` scales a canonical CSR matrix's stored values (sharing its index
    arrays) where every ``k`` is nonzero: the same matrix as ``diag(k) @ A``, canonical; a
    zero scale takes the product (no explicit zeros that would tie a row to a node)."""
    from bvpnav.model import Affine

    rng = np.random.default_rng(0)
    A = sp.random(300, 50, density=0.05, format="csr", random_state=1)
    A.sum_duplicates()
    c = rng.normal(size=300)
    k = rng.uniform(0.5, 2.0, 300)
    out = Affine(A, c) * k
    assert out.A.has_canonical_format and np.shares_memory(out.A.indices, A.indices)
    np.testing.assert_array_equal(out.A.toarray(), (sp.diags(k) @ A).toarray())
    np.testing.assert_array_equal(out.c, c * k)
    k[3] = 0.0
    zero = Affine(A, c) * k
    assert not np.shares_memory(zero.A.indices, A.indices)
    np.testing.assert_array_equal(zero.A.toarray(), (sp.diags(k) @ A).toarray())


def test_dense_blocks_become_csr_from_their_nonzero_columns_as_scipy_converts_them():
    """``rows_side_by_side`` takes a dense block (the error-model columns) from its nonzero
    columns when they hold no zero, else by scipy's conversion: the same matrix either way,
    for an all-zero block, a full one, zero columns, and a zero inside a nonzero column."""
    from bvpnav.model import _block_csr

    rng = np.random.default_rng(2)
    blocks = [np.zeros((5, 3)), rng.normal(size=(6, 4)), np.c_[np.zeros(7), rng.normal(size=7), np.zeros(7)],
              np.c_[rng.normal(size=4), [0.0, 1.0, 2.0, 0.0]], np.zeros((0, 3))]
    for blk in blocks:
        got, want = _block_csr(blk), sp.csr_matrix(blk)
        assert got.nnz == want.nnz and got.shape == want.shape
        np.testing.assert_array_equal(got.toarray(), blk)
        assert got.has_canonical_format


def test_abs_product_by_blocks_of_rows_equals_the_whole_absolute_matrix(monkeypatch):
    """``|A| v`` taken a few stored entries at a time (blocks cut inside long rows, empty
    rows, an empty matrix) equals the product with the whole absolute matrix; ``row_scale``
    is ``|A| |x| + |c|``."""
    import bvpnav.model as md

    rng = np.random.default_rng(3)
    for block in (1, 7, 64, 1 << 20):
        monkeypatch.setattr(md, "ABS_BLOCK", block)
        for trial in range(5):
            A = sp.random(40, 25, density=0.2 * trial, format="csr", random_state=trial)
            A.data -= 0.5
            v = rng.normal(size=25)
            np.testing.assert_allclose(md.abs_product(A, v), abs(A) @ v, rtol=1e-14, atol=1e-15)
            c = rng.normal(size=40)
            np.testing.assert_allclose(md.Affine(A, c).row_scale(v), abs(A) @ np.abs(v) + np.abs(c),
                                       rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize("n", [2, 3, 4, 9, 1000])
def test_tridiagonal_equals_scipy_diags_in_canonical_csr_and_keeps_its_diagonals(n):
    """``fem.tridiagonal`` (written straight into CSR arrays) is scipy's ``diags`` matrix
    entry for entry, canonical, with 32-bit indices, and carries the diagonals it was made
    from (read by the FEM rows' diagonal description)."""
    rng = np.random.default_rng(n)
    lo, dg, up = rng.normal(size=n - 1), rng.normal(size=n), rng.normal(size=n - 1)
    A = fem.tridiagonal(lo, dg, up)
    want = sp.diags([lo, dg, up], [-1, 0, 1], format="csr")
    want.sort_indices()
    assert A.has_canonical_format and A.indices.dtype == np.int32 and A.indptr.dtype == np.int32
    np.testing.assert_array_equal(A.indptr, want.indptr)
    np.testing.assert_array_equal(A.indices, want.indices)
    np.testing.assert_array_equal(A.data, want.data)
    for k, v in zip((-1, 0, 1), A._bvpnav_diagonals, strict=True):
        np.testing.assert_array_equal(v, A.diagonal(k))


def test_time_labels_are_made_on_demand_and_read_as_the_formatted_strings():
    """Position and velocity rows are labelled ``f"{q}{axis}(t={t:.6g})"`` time-major, made
    on demand (``TimeLabels``), and stay lazy when stacked with other rows' labels; every
    way of reading them (index, negative index, slice, iteration, a stack's rows, a row
    selection) gives the strings."""
    from bvpnav.model import Affine, RowLabels, TimeLabels

    t = np.linspace(0.0, 10.0, 1001)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.zeros((t.size, 3))))
    m = prob.formulation.model
    times = np.array([1.0, 2.5, 7.123456789])
    P, V = m.position(times), m.velocity(times[:2], axes=["y", "z"])
    want_p = [f"{ax}(t={tk:.6g})" for tk in times for ax in "xyz"]
    want_v = [f"v{ax}(t={tk:.6g})" for tk in times[:2] for ax in "yz"]
    assert isinstance(P.labels, TimeLabels) and list(P.labels) == want_p
    assert list(V.labels) == want_v and V.labels[-1] == want_v[-1] and P.labels[2:5] == want_p[2:5]
    with pytest.raises(IndexError):
        P.labels[len(want_p)]
    both = Affine.vstack([P, m.fem_rows(), V])
    assert isinstance(both.labels, RowLabels) and len(both.labels) == both.m
    assert both.labels[len(want_p) - 1] == want_p[-1] and both.labels[-1] == want_v[-1]
    assert both.labels[len(want_p)] == "fem_x[0]"
    assert list(P.rows([0, 4]).labels) == [want_p[0], want_p[4]]
    one = m.position(times, axes=["x"])   # one axis: the rows as made, no reordering copy
    assert list(one.labels) == [f"x(t={tk:.6g})" for tk in times]
    np.testing.assert_array_equal(one.A.toarray(), P.A.toarray()[0::3])


def test_rows_with_tail_reuses_its_pattern_only_for_the_same_index_arrays():
    """``rows_with_tail`` keeps the result's pattern with the head for tails (and rows below) on
    the very index arrays of the last call: another call on them takes the new values (the
    result equals scipy's ``hstack``/``vstack`` of the blocks), and tails on other index arrays,
    even equal ones, are placed again."""
    import copy

    from bvpnav.model import rows_with_tail

    rng = np.random.default_rng(11)
    left = sp.random(6, 4, density=0.5, format="csr", random_state=1)
    head = sp.hstack([left, sp.csr_matrix((6, 3))], format="csr")   # the full width, its columns before 4
    tail = [sp.random(6, 3, density=0.5, format="csr", random_state=2)]
    below = sp.random(2, 7, density=0.5, format="csr", random_state=3)

    def want(tl, bl):
        return sp.vstack([sp.hstack([left, tl[0]]), bl], format="csr").toarray()

    first = rows_with_tail(head, tail, 4, [below])
    np.testing.assert_array_equal(first.toarray(), want(tail, below))
    for _ in range(2):   # the same index arrays (shallow copies), new values: the kept pattern
        t2, b2 = copy.copy(tail[0]), copy.copy(below)
        t2.data, b2.data = rng.normal(size=t2.nnz), rng.normal(size=b2.nnz)
        got = rows_with_tail(head, [t2], 4, [b2])
        np.testing.assert_array_equal(got.toarray(), want([t2], b2))
        assert got.indices is first.indices and not np.array_equal(got.data, first.data)
    other = sp.random(6, 3, density=0.3, format="csr", random_state=4)   # another pattern
    np.testing.assert_array_equal(rows_with_tail(head, [other], 4, [below]).toarray(), want([other], below))
    np.testing.assert_array_equal(rows_with_tail(head, tail, 4, [below]).toarray(), want(tail, below))


def test_row_scaling_kept_only_for_the_same_values():
    """``Affine * k`` keeps the row-scaled matrix with ``A`` for the next product by the same
    ``k``; a shallow copy of ``A`` with new values (the loop's kept patterns) is another matrix:
    its product is ``diag(k) A`` of its own values, not the kept one."""
    import copy

    from bvpnav.model import Affine

    A = sp.csr_matrix(np.array([[1.0, 2.0], [0.0, 3.0]]))
    k = np.array([2.0, 5.0])
    first = (Affine(A, np.zeros(2)) * k).A
    np.testing.assert_array_equal(first.toarray(), [[2.0, 4.0], [0.0, 15.0]])
    assert (Affine(A, np.zeros(2)) * k).A is first   # kept: the same k on the same values
    B = copy.copy(A)
    B.data = np.array([7.0, 8.0, 9.0])
    np.testing.assert_array_equal((Affine(B, np.zeros(2)) * k).A.toarray(), [[14.0, 16.0], [0.0, 45.0]])
    np.testing.assert_array_equal((Affine(A, np.zeros(2)) * (2 * k)).A.toarray(), [[4.0, 8.0], [0.0, 30.0]])


def test_plain_mesh_solve_never_writes_to_the_users_data():
    """A coarse mesh without node states keeps what it condenses on its own model, not on the
    user's :class:`bvpnav.ImuData` (nothing added to it, nothing changed), and a second solve of
    the same data gives the first's answer."""
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 15.0, 1500)
    acc = np.column_stack([np.sin(t), np.cos(0.5 * t)]) + 0.02 * rng.standard_normal((t.size, 2))
    data = bvpnav.ImuData(t=t, acc=acc, axes=("x", "y"))
    before = dict(data.__dict__)
    acc0 = data.acc.copy()

    def solve():
        p = bvpnav.NavigationProblem(data, sigma_a=0.03, segment=1.0)
        k = np.arange(0, t.size, 100)
        p.add(Position(t=t[k], value=np.zeros((k.size, 2)), sigma=0.5))
        return p.solve(solver="direct")

    first = solve()
    assert set(data.__dict__) == set(before)
    np.testing.assert_array_equal(data.acc, acc0)
    np.testing.assert_array_equal(solve().position(), first.position())
