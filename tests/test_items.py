"""Each item corrects a known error by the expected amount, hard and soft, 1D and 3D."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import quintic

import bvpnav
from bvpnav.constraints import (
    AverageVelocity,
    Linear,
    Position,
    Symmetry,
    Velocity,
    ZeroVelocity,
)

T = np.linspace(0.0, 10.0, 401)


def truth_1d():
    """A trajectory with a non-zero initial velocity (what the items must recover)."""
    p, v, a = quintic()
    drift = 0.8  # m/s, unknown to the solver unless an item supplies it
    return (lambda t: p(t) + drift * t), (lambda t: v(t) + drift), a


def truth_3d():
    p, v, a = quintic()
    pos = lambda t: np.column_stack([p(t) + 0.8 * t, 0.5 * p(t) - 0.3 * t, np.sin(t) + 0.2 * t])  # noqa: E731
    vel = lambda t: np.column_stack([v(t) + 0.8, 0.5 * v(t) - 0.3, np.cos(t) + 0.2])  # noqa: E731
    acc = lambda t: np.column_stack([a(t), 0.5 * a(t), -np.sin(t)])  # noqa: E731
    return pos, vel, acc


def fem_reference(pos, acc, ndim):
    """FEM with both end positions fixed: the discrete answer the items should reach.

    Returns the solution and functions giving its position and velocity at any time,
    so that item values are consistent with the discretisation (the continuous truth
    differs from it by O(h^2))."""
    data = bvpnav.ImuData(t=T, acc=acc(T))
    prob = bvpnav.NavigationProblem(data)
    prob.add(Position(t=[T[0], T[-1]], value=np.vstack([pos(T[:1]), pos(T[-1:])]).reshape(2, ndim)))
    sol = prob.solve()
    P = lambda t: prob.model.position(np.atleast_1d(t)).value(sol.x).reshape(-1, ndim)  # noqa: E731
    V = lambda t: prob.model.velocity(np.atleast_1d(t)).value(sol.x).reshape(-1, ndim)  # noqa: E731
    return sol, P, V


def information(kind, P, V, ndim, sigma):
    """The item that supplies the missing velocity offset, from the discrete reference."""
    kw = {} if sigma is None else {"sigma": sigma}
    if kind == "velocity":
        return Velocity(t=3.0, value=V(3.0)[0], **kw)
    if kind == "position":
        return Position(t=7.5, value=P(7.5)[0], **kw)
    if kind == "average_velocity":
        return AverageVelocity(t0=2.0, t1=6.0, value=(P(6.0)[0] - P(2.0)[0]) / 4.0, **kw)
    if kind == "linear":  # r(7.5) - r(2.5) as a user row per axis
        coef = np.zeros((ndim, 2, ndim))
        for k in range(ndim):
            coef[k, 0, k], coef[k, 1, k] = -1.0, 1.0
        return Linear(t=[2.5, 7.5], coef=coef, value=P(7.5)[0] - P(2.5)[0], **kw)
    raise AssertionError(kind)


@pytest.mark.parametrize("ndim", [1, 3])
@pytest.mark.parametrize("sigma", [None, 0.05])
@pytest.mark.parametrize("kind", ["velocity", "position", "average_velocity", "linear"])
def test_item_supplies_the_missing_condition(kind, sigma, ndim):
    pos, vel, acc = truth_1d() if ndim == 1 else truth_3d()
    accn = lambda t: np.asarray(acc(t)).reshape(t.size, ndim)  # noqa: E731
    data = bvpnav.ImuData(t=T, acc=accn(T))
    start = np.asarray(pos(T[:1])).reshape(ndim)
    prob = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=start))
    # without the item the velocity offset is undetermined: reported by name
    with pytest.raises(bvpnav.InputError, match="velocity offset"):
        prob.solve()
    ref, P, V = fem_reference(pos, accn, ndim)
    prob.add(information(kind, P, V, ndim, sigma))
    sol = prob.solve()
    # consistent information: hard and soft both reach the reference to solver precision
    assert np.max(np.abs(sol.position() - ref.position())) < 1e-6
    assert np.max(np.abs(sol.velocity() - ref.velocity())) < 1e-6
    true = np.asarray(pos(T)).reshape(T.size, ndim)
    assert np.sqrt(np.mean((sol.position() - true) ** 2)) < 2e-3  # O(h^2) discretisation


@pytest.mark.parametrize("sigma", [None, 0.01])
def test_symmetry_fixes_velocity_offset(sigma):
    c = 5.0
    pos = lambda t: 3.0 * np.cos(2 * np.pi * (t - c) / 10.0) + 0.5 * (t - c) ** 2  # noqa: E731
    acc = lambda t: -3.0 * (2 * np.pi / 10.0) ** 2 * np.cos(2 * np.pi * (t - c) / 10.0) + 1.0  # noqa: E731
    data = bvpnav.ImuData(t=T, acc=acc(T))
    prob = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=pos(0.0)))
    prob.add(Symmetry(about=c, sigma=sigma))
    sol = prob.solve()
    assert np.sqrt(np.mean((sol.position("x") - pos(T)) ** 2)) < 1e-3


@pytest.mark.parametrize("sigma", [None, 0.01])
def test_odd_symmetry_removes_even_bias_error(sigma):
    """A linear drift is itself odd about c, so odd symmetry cannot fix a velocity
    offset (reported as unobservable); what it removes is an even error such as the
    bias parabola mu/2 (t - T0)(t - T1) left by fixing both ends."""
    c, mu = 5.0, 0.4
    odd = lambda t: 2.0 * np.sin(2 * np.pi * (t - c) / 10.0) + 0.3 * (t - c)  # noqa: E731
    acco = lambda t: -2.0 * (2 * np.pi / 10.0) ** 2 * np.sin(2 * np.pi * (t - c) / 10.0)  # noqa: E731
    data = bvpnav.ImuData(t=T, acc=acco(T) + mu)
    bare = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=odd(0.0)),
                                             Symmetry(about=c, parity="odd", sigma=sigma))
    with pytest.raises(bvpnav.InputError, match="velocity offset"):
        bare.solve()
    ends = Position(t=[0.0, 10.0], value=[odd(0.0), odd(10.0)])
    err_ii = bvpnav.NavigationProblem(data).add(ends).solve().position("x") - odd(T)
    sol = bvpnav.NavigationProblem(data).add(ends, Symmetry(about=c, parity="odd", sigma=sigma)).solve()
    err = sol.position("x") - odd(T)
    rms = lambda e: np.sqrt(np.mean(e**2))  # noqa: E731
    assert rms(err_ii) > 0.9  # the parabola: mu T^2 / sqrt(120) = 1.22 m
    assert rms(err) < 0.02 * rms(err_ii)


@pytest.mark.parametrize("sigma", [None, 0.01])
@pytest.mark.parametrize("ndim", [1, 3])
def test_zero_velocity_interval(sigma, ndim):
    # at rest for 2 s, then r = 0.01 (t - 2)^3: the acceleration is continuous and linear
    # between samples (t = 2 s is a sample), so the FEM is exact and so must be the result
    bump = lambda t: np.where(t > 2.0, 0.01 * (t - 2.0) ** 3, 0.0)  # noqa: E731
    accb = lambda t: np.where(t > 2.0, 0.06 * (t - 2.0), 0.0)  # noqa: E731
    acc = np.column_stack([accb(T) * (k + 1) for k in range(ndim)])
    true = np.column_stack([bump(T) * (k + 1) for k in range(ndim)])
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=T, acc=acc))
    prob.add(Position(t=0.0, value=0.0), ZeroVelocity(t0=0.0, t1=2.0, sigma=sigma))
    sol = prob.solve()
    assert np.max(np.abs(sol.position() - true)) < 1e-7
    assert np.max(np.abs(sol.velocity()[T <= 2.0])) < 1e-8


def test_bias_removed_by_end_velocities():
    """A constant bias with positions fixed at both ends leaves the parabola error
    mu/2 (t - T0)(t - T1); the two end velocities let the residual absorb it."""
    p, v, a = quintic()
    mu = 0.5
    data = bvpnav.ImuData(t=T, acc=a(T) + mu)
    ends = Position(t=[0.0, 10.0], value=[0.0, 10.0])
    prob = bvpnav.NavigationProblem(data).add(ends)
    err_ii = prob.solve().position("x") - p(T)
    parabola = mu / 2.0 * T * (T - 10.0)
    assert np.max(np.abs(err_ii - parabola)) < 2e-3  # the predicted error, to O(h^2)
    for vel in (Velocity(t=[0.0, 10.0], value=0.0), Velocity(t=[0.0, 10.0], value=0.0, sigma=1e-4)):
        prob = bvpnav.NavigationProblem(data).add(ends, vel)
        sol = prob.solve()
        err = sol.position("x") - p(T)
        # min-norm residual lies in span{M 1, M t}: the bias is removed up to the two end
        # samples' half-weight, an O(h) effect
        assert np.sqrt(np.mean(err**2)) < 0.01 * np.sqrt(np.mean(parabola**2))
        assert np.median(sol.residuals["w_x"]) == pytest.approx(-mu, rel=1e-2)


def test_soft_tends_to_hard():
    p, v, a = quintic()
    rng = np.random.default_rng(11)
    data = bvpnav.ImuData(t=T, acc=a(T) + rng.normal(0.0, 0.5, T.size))
    ends = Position(t=[0.0, 10.0], value=[0.0, 10.0])
    hard = bvpnav.NavigationProblem(data).add(ends, Velocity(t=[0.0, 10.0], value=0.0)).solve()
    gaps = []
    for sigma in (1e-1, 1e-2, 1e-3):
        soft = bvpnav.NavigationProblem(data).add(ends, Velocity(t=[0.0, 10.0], value=0.0, sigma=sigma))
        gaps.append(np.max(np.abs(soft.solve().position("x") - hard.position("x"))))
    gaps = np.array(gaps)
    assert gaps[-1] < 1e-4
    # the gap shrinks like sigma^2 once sigma is small (factor ~100 per decade)
    assert gaps[1] / gaps[2] > 50
    # and lam -> infinity does the same as sigma -> 0
    soft = bvpnav.NavigationProblem(data).add(ends, Velocity(t=[0.0, 10.0], value=0.0, sigma=0.1))
    big = soft.solve(lam=1e6)
    assert np.max(np.abs(big.position("x") - hard.position("x"))) < 1e-4


# ------------------------------------------------------------ broadcasting rule
@pytest.mark.parametrize("given, k, a, rows", [
    (2.0, 3, 2, [2.0] * 6),                                       # scalar
    ([1.0, 2.0, 3.0], 3, 2, [1.0, 1.0, 2.0, 2.0, 3.0, 3.0]),      # one per instant
    ([1.0, 2.0], 3, 2, [1.0, 2.0, 1.0, 2.0, 1.0, 2.0]),           # one per axis
    ([1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 3, 2, [1, 2, 3, 4, 5, 6]),   # one per row, time-major
    ([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]], 3, 2, [1, 2, 3, 4, 5, 6]),  # (instants, axes)
    ([[1.0, 2.0], [3.0, 4.0]], 2, 2, [1, 2, 3, 4]),               # (instants, axes), square
    ([1.0, 2.0], 2, 1, [1.0, 2.0]),                               # one axis: per instant = per row
])
def test_broadcast_rows_time_major(given, k, a, rows):
    """Row i * a + j is instant i, axis j, whatever form the quantity is given in."""
    from bvpnav.items import broadcast_rows

    assert broadcast_rows(given, k, a, "q").tolist() == [float(r) for r in rows]


@pytest.mark.parametrize("given, k, a, pattern", [
    ([1.0, 2.0], 2, 2, r"one per instant or one per axis\? Write it as shape \(2, 2\)"),
    ([1.0, 2.0, 3.0], 3, 3, r"one per instant or one per axis"),
    ([1.0, 2.0], 3, 1, r"shape \(2,\) does not fit 3 instant\(s\) x 1 axis"),
    ([1.0, 2.0, 3.0, 4.0], 3, 2, r"accepted flat lengths: \[1, 2, 3, 6\]"),
    ([[1.0, 2.0]], 3, 2, r"shape \(1, 2\) does not fit"),
])
def test_broadcast_rows_refuses_ambiguous_and_short(given, k, a, pattern):
    from bvpnav.errors import InputError
    from bvpnav.items import broadcast_rows

    with pytest.raises(InputError, match=pattern):
        broadcast_rows(given, k, a, "q")


def test_per_axis_sigma_weights_each_axis():
    """On main a per-axis sigma was repeated axis-major onto time-major rows (the second
    axis's sigma weighted the first axis's later instants); now each axis gets its own."""
    item = Position(t=[0.0, 5.0, 10.0], value=0.0, sigma=[0.1, 1.0])
    assert item.weight_rows(6).tolist() == [0.1, 1.0, 0.1, 1.0, 0.1, 1.0]
    band = Velocity(t=[0.0, 5.0, 10.0], value=0.0, mode="band", tol=[[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]])
    assert band.tol_rows(6).tolist() == [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]


def test_identify_shows_what_an_unnamed_item_holds():
    assert Position(t=[0.0, 10.0], value=[0.0, 10.0]).identify() == "Position (t=[0, 10] s, value=[0, 10] m)"
    assert Velocity(t=np.arange(11.0), value=0.0).identify() == (
        "Velocity (t=[0, 1, 2, ..., 10] (11 values) s, value=0 m/s)")
    assert Position(t=0.0, value=1.0, name="fix A").identify() == "fix A"
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(T, np.zeros(T.size)))
    prob.add(Position(t=0.0, value=0.0), Position(t=[0.0, 10.0], value=[0.0, 10.0], axes="x"))
    assert [i.identify() for i in prob._items] == [
        "Position (t=[0] s, value=0 m)", "Position#2 (t=[0, 10] s, value=[0, 10] m, axes=['x'])"]


def test_linear_row_units_are_its_units():
    """Linear's rows are in row_units (its docstring said units=, a field it never had, and
    the report showed every Linear item in m): they reach solution.items["units"]."""
    assert Linear(t=[2.0], coef=[1.0]).units == "m"
    drift = Linear(t=[5.0], coef=[1.0], value=0.8, quantity="velocity", row_units="m/s", name="drift")
    assert drift.units == "m/s"
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(T, np.zeros(T.size)))
    sol = prob.add(Position(t=0.0, value=0.0, name="start"), drift).solve()
    units = dict(zip(sol.items["item"], sol.items["units"], strict=True))
    assert units["drift"] == "m/s"
    assert units["start"] == "m"
    with pytest.raises(bvpnav.InputError, match="row_units=5; give the rows' units as a string"):
        Linear(t=[2.0], coef=[1.0], row_units=5)


def test_item_reprs_are_short_whatever_the_data():
    """An item with 1000 instants prints in one short line: mode, name, the fields that are
    set, more than 4 numbers as count and range (the dataclass repr printed every field,
    None ones and whole arrays)."""
    t = np.linspace(0.0, 10.0, 1000)
    item = Position(t=t, value=np.zeros(1000), sigma=0.5, name="prior")
    assert repr(item) == ("Position(mode='soft', name='prior', sigma=0.5, t=<1000 values, 0 .. 10>, "
                          "value=<1000 values, 0 .. 0>)")
    ends = Position(t=[0.0, 10.0], value=[0.0, 1.0])
    assert repr(ends) == "Position(mode='hard', t=[0.0, 10.0], value=[0.0, 1.0])"
    for name, cls in bvpnav.items.registry().items():
        assert len(repr(cls.example())) < 300, name
