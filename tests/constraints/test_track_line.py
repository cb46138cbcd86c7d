"""TrackLine (a known planar path, timing unknown): projection, rows, spec, bad input, the
roller-coaster example (the sequential loop itself: tests/solve/test_sequential.py)."""

from __future__ import annotations

import pathlib
import warnings

import numpy as np
import pytest
from _helpers import load_example

import bvpnav
from bvpnav.constraints import TrackLine
from bvpnav.constraints.track_line import (
    AMBIGUOUS,
    CONTINUITY,
    OUT_OF_RANGE,
    SEGMENT,
    VERTEX,
    project_onto_polyline,
)
from bvpnav.spec import dumps_spec, parse_spec, to_spec

EX = pathlib.Path(__file__).resolve().parents[2] / "examples"


# ------------------------------------------------------------ geometry
L_SHAPE = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)]
HAIRPIN = [(0.0, 0.0), (10.0, 0.0), (10.0, 1.0), (0.0, 1.0)]


def one(vertices, p, **kw):
    return project_onto_polyline(vertices, [0.0], [p], **kw)


def test_inside_a_segment_gives_the_segment_line():
    pr = one(L_SHAPE, (5.0, 1.0))
    assert pr.status[0] == SEGMENT and pr.segment[0] == 0
    assert np.allclose(pr.point[0], (5.0, 0.0)) and pr.distance[0] == pytest.approx(1.0)
    assert np.allclose(np.abs(pr.normal[0]), (0.0, 1.0))


def test_outside_a_corner_uses_the_direction_to_the_vertex():
    pr = one(L_SHAPE, (11.0, -1.0))
    assert pr.status[0] == VERTEX
    assert np.allclose(pr.point[0], (10.0, 0.0)) and pr.distance[0] == pytest.approx(np.sqrt(2.0))
    assert np.allclose(pr.normal[0], np.array([1.0, -1.0]) / np.sqrt(2.0))
    on = one(L_SHAPE, (10.0, 0.0))  # on the vertex itself: the bisector of the two normals
    assert on.status[0] == VERTEX
    assert np.allclose(np.abs(on.normal[0]), np.array([1.0, 1.0]) / np.sqrt(2.0))


def test_beyond_the_ends_is_dropped_or_clamped():
    pr = one(L_SHAPE, (-2.0, 0.5))
    assert pr.status[0] == OUT_OF_RANGE and not pr.kept[0] and np.all(np.isnan(pr.normal[0]))
    cl = one(L_SHAPE, (-2.0, 0.0), beyond_ends="clamp")
    assert cl.status[0] == VERTEX and np.allclose(cl.point[0], (0.0, 0.0))
    assert np.allclose(np.abs(cl.normal[0]), (1.0, 0.0))
    end = one(L_SHAPE, (10.0, 12.0))  # beyond the last vertex
    assert end.status[0] == OUT_OF_RANGE


def test_ambiguous_samples_follow_arc_length_continuity():
    # (5, 0.5) is equidistant (0.5 m) from both legs of the hairpin: arc lengths 5 and 16 m
    alone = one(HAIRPIN, (5.0, 0.5))
    assert alone.status[0] == AMBIGUOUS and not alone.kept[0]
    fwd = project_onto_polyline(HAIRPIN, [0.0, 1.0, 2.0], [(4.0, 0.1), (5.0, 0.5), (6.0, 0.45)])
    assert list(fwd.status) == [SEGMENT, CONTINUITY, CONTINUITY]
    assert list(fwd.segment) == [0, 0, 0] and fwd.arc[1] == pytest.approx(5.0)
    back = project_onto_polyline(HAIRPIN, [0.0, 1.0, 2.0], [(5.0, 0.5), (5.0, 0.55), (6.0, 0.9)])
    assert list(back.status) == [CONTINUITY, CONTINUITY, SEGMENT]
    assert list(back.segment) == [2, 2, 2] and back.arc[0] == pytest.approx(16.0)
    assert np.allclose(back.point[0], (5.0, 1.0))


# ------------------------------------------------------------ the item
def test_compile_needs_a_linearization_point_and_rows_are_distances():
    item = TrackLine(x=[0.0, 10.0, 10.0], y=[0.0, 0.0, 10.0], axes=("x", "y"), name="rail")
    t = np.linspace(0.0, 10.0, 101)
    model = bvpnav.NavModel(bvpnav.ImuData(t=t, acc=np.zeros((t.size, 2))))
    with pytest.raises(bvpnav.InputError, match="rail.*linearization point"):
        item.compile(model)
    est = np.column_stack([t, np.full(t.size, 0.3)])  # 0.3 m above the first leg
    lin = item.linearized(t, est)
    res = lin.compile(model)
    x = np.zeros(model.size)
    x[model.r_index(0)], x[model.r_index(1)] = est[:, 0], est[:, 1]
    d = res.value(x)
    # every row is the signed distance (m) of the estimate from its nearest segment's line:
    # 0.3 m from the first leg, then (x > 9.7 m) nearer the second leg, at 10 - x
    assert res.m == t.size
    assert np.allclose(np.abs(d), np.minimum(0.3, 10.0 - t))


def test_spec_round_trip():
    item = TrackLine(x=[0.0, 5.0, 9.0], y=[0.0, 1.0, 0.0], axes=("x", "z"), t0=1.0, t1=8.0, sigma=0.5,
                     name="coaster")
    t = np.linspace(0.0, 10.0, 11)
    data = bvpnav.ImuData(t=t, acc=np.zeros((t.size, 2)), axes=("x", "z"))
    prob = bvpnav.NavigationProblem(data).add(item)
    text = to_spec(prob)
    back = parse_spec(text).items[0]
    assert isinstance(back, TrackLine) and back.label == "coaster"
    assert np.array_equal(back.x, item.x) and np.array_equal(back.y, item.y)
    assert back.axes == ("x", "z") and (back.t0, back.t1) == (1.0, 8.0)
    assert back.mode == "soft" and float(back.sigma) == 0.5 and back.about is None
    assert dumps_spec(parse_spec(text)) == text


def test_bad_input_names_the_item():
    with pytest.raises(bvpnav.InputError, match="rail.*vertices 1 and 2 coincide"):
        TrackLine(x=[0.0, 1.0, 1.0], y=[0.0, 0.0, 0.0], name="rail")
    with pytest.raises(bvpnav.InputError, match="rail.*two axis names"):
        TrackLine(x=[0.0, 1.0], y=[0.0, 0.0], axes=("x",), name="rail")


# ------------------------------------------------------------ the example
def test_roller_coaster_small():
    mod = load_example("roller_coaster")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        df = mod.run(small=True, quiet=True)
    assert len(df) == 3 and df.converged.all()
    # acceptance: TrackLine's RMS position error at least 5x smaller than the ends alone
    assert (df.a_pos_rms >= 5 * df.b_pos_rms).all(), df[["a_pos_rms", "b_pos_rms"]]
    assert (df.b_path_rms < 0.5).all() and (df.a_path_rms > 3.0).all()
