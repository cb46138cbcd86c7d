"""A known planar path without its timing (the 2011 paper's roller-coaster track).

The object is known to move along a polyline with vertices ``(x_i, y_i)`` on two chosen
axes, but not *when* it is where. The distance to a polyline is not affine in the
positions, so the item is linearized about a current estimate and re-linearized by the
sequential convex loop (:mod:`bvpnav.solve.sequential`), which :meth:`NavigationProblem.solve`
runs automatically for items that still need a linearization point.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
import scipy.sparse as sp

from bvpnav.errors import InputError
from bvpnav.items import Item, Linearizable
from bvpnav.model import Affine

from ._common import finite, interval, times

__all__ = ["TrackLine", "TrackProjection", "project_onto_polyline", "SEGMENT", "VERTEX", "CONTINUITY",
           "OUT_OF_RANGE", "AMBIGUOUS"]

#: Projection status codes (``TrackProjection.status``): rows kept ...
SEGMENT, VERTEX, CONTINUITY = 0, 1, 2
#: ... and rows dropped.
OUT_OF_RANGE, AMBIGUOUS = -1, -2

#: Floor of the continuation sigma of a hard track, as a fraction of the path length.
CONTINUATION_FLOOR = 1e-3
_CHUNK_ELEMENTS = 2_000_000  # samples x segments evaluated at once
#: Candidates nearer than ``d_min + ambiguity`` (radius rho) on one branch span at most about
#: 2 rho of arc length (a little more on the outside of a bend): more than 3 rho is two branches.
_BRANCH = 3.0


@dataclass(frozen=True, eq=False)
class TrackProjection:
    """Nearest points of samples on a polyline and the linearized rows they give.

    Attributes
    ----------
    t : ndarray (n,)
        Sample times, s.
    point : ndarray (n, 2)
        Nearest point on the polyline, m (NaN where dropped).
    normal : ndarray (n, 2)
        Unit row direction ``n`` (dimensionless): the segment's normal, or the direction
        from the sample to the nearest vertex (NaN where dropped).
    distance : ndarray (n,)
        Distance from the sample to the polyline, m.
    arc : ndarray (n,)
        Arc length of the nearest point from the first vertex, m.
    segment : ndarray of int (n,)
        Index of the chosen segment (vertex ``i`` to ``i + 1``).
    status : ndarray of int (n,)
        ``SEGMENT`` (0), ``VERTEX`` (1) or ``CONTINUITY`` (2: an ambiguous sample
        resolved by arc-length continuity) for kept rows; ``OUT_OF_RANGE`` (-1) or
        ``AMBIGUOUS`` (-2, nothing to resolve it by) for dropped rows.
    """

    t: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    distance: np.ndarray
    arc: np.ndarray
    segment: np.ndarray
    status: np.ndarray

    @property
    def kept(self) -> np.ndarray:
        """Boolean mask of the samples that give a row."""
        return self.status >= 0

    def counts(self) -> dict[str, int]:
        """Number of samples per status name."""
        names = {SEGMENT: "segment", VERTEX: "vertex", CONTINUITY: "continuity",
                 OUT_OF_RANGE: "out_of_range", AMBIGUOUS: "ambiguous"}
        return {v: int(np.sum(self.status == k)) for k, v in names.items()}


def _segments(V: np.ndarray):
    A = V[:-1]
    d = V[1:] - A
    L = np.hypot(d[:, 0], d[:, 1])
    S0 = np.concatenate([[0.0], np.cumsum(L)])
    return A, d, L, S0


def _to_segments(Q: np.ndarray, A, d, L, S0):
    """Clamped and raw segment parameters, distances and arc lengths for points Q (n, 2)."""
    rel = Q[:, None, :] - A[None, :, :]
    raw = (rel[..., 0] * d[None, :, 0] + rel[..., 1] * d[None, :, 1]) / (L * L)[None, :]
    u = np.clip(raw, 0.0, 1.0)
    px = A[None, :, 0] + u * d[None, :, 0]
    py = A[None, :, 1] + u * d[None, :, 1]
    dist = np.hypot(Q[:, None, 0] - px, Q[:, None, 1] - py)
    s = S0[None, :-1] + u * L[None, :]
    return raw, u, dist, s


def project_onto_polyline(vertices, t, positions, ambiguity: float = 0.5,
                          beyond_ends: str = "drop") -> TrackProjection:
    r"""Nearest segment of each sample, with the paper's ambiguous and out-of-range cases.

    Parameters
    ----------
    vertices : array_like (P, 2)
        Polyline vertices, m, in the order they are travelled.
    t : array_like (n,)
        Sample times, s, increasing (used for the continuity rule).
    positions : array_like (n, 2)
        Current estimate of the positions on the two axes, m.
    ambiguity : float
        m. Segments whose distance is within ``ambiguity`` of the smallest one are
        candidates; when the candidates lie on different branches of the track (their
        arc lengths differ by more than ``3 (d_min + ambiguity)``, more than one branch
        can span inside that radius), the sample is ambiguous.
    beyond_ends : {"drop", "clamp"}
        What a sample beyond an end of the polyline gives: no row (``"drop"``, the
        paper's choice), or the linearized distance to the end vertex (``"clamp"``:
        the object is known to be on the path, so it is pulled back to the end).

    Returns
    -------
    TrackProjection

    Notes
    -----
    Per sample ``p`` the nearest point ``q`` on the polyline is found. If ``q`` lies inside
    segment ``i`` the row is the segment's line, :math:`n_i \cdot r = n_i \cdot v_i` with
    the unit normal :math:`n_i` (the paper's equation 24 scaled to metres). If ``q`` is an
    interior vertex (``p`` in the wedge outside a corner) the row is the linearized
    distance to that vertex, :math:`u \cdot r = u \cdot q` with
    :math:`u = (p - q)/|p - q|` (the bisector normal when ``p`` is on the vertex).

    Out of range: a sample whose nearest point is an end of the polyline *and* that lies
    beyond it (its projection parameter is outside the end segment) gives no row, as in
    the paper ("the trajectory is not exploited" there); with ``beyond_ends="clamp"`` it
    is treated like a corner: the row is the linearized distance to the end vertex.

    Ambiguous: where several branches of the track are about equally near (a loop,
    a crossing), the branch whose arc length is nearest to that of the previous kept
    sample is taken (the estimate moves continuously along the track), then its nearest
    segment; the first ambiguous samples of a series use the next unambiguous sample
    instead. A sample with nothing to compare to gives no row.
    """
    V = np.asarray(vertices, dtype=float)
    t = np.asarray(t, dtype=float)
    Q = np.asarray(positions, dtype=float).reshape(-1, 2)
    A, d, L, S0 = _segments(V)
    nseg = A.shape[0]
    n = Q.shape[0]
    seg = np.zeros(n, dtype=int)
    uu = np.zeros(n)
    rawu = np.zeros(n)
    dmin = np.zeros(n)
    arc = np.zeros(n)
    amb = np.zeros(n, dtype=bool)
    lmax = float(L.max())
    chunk = max(1, _CHUNK_ELEMENTS // nseg)
    # candidate segments: within dv + ambiguity (dv, the distance to the nearest vertex, bounds the
    # distance to the polyline) of the sample, so their midpoints are within that + L_max / 2
    from scipy.spatial import cKDTree  # heavy; not loaded by `import bvpnav.constraints`

    dv = cKDTree(V).query(Q)[0]
    mtree = cKDTree(A + 0.5 * d)
    for k0 in range(0, n, chunk):
        sl = slice(k0, min(n, k0 + chunk))
        Qc = Q[sl]
        radius = (dv[sl] + ambiguity + 0.5 * lmax) * (1.0 + 1e-9) + 1e-12
        near = mtree.query_ball_point(Qc, radius)
        cnt = np.fromiter((len(c) for c in near), dtype=int, count=len(near))
        rows = np.repeat(np.arange(cnt.size), cnt)
        cols = np.concatenate([np.asarray(c, dtype=int) for c in near])
        order = np.lexsort((cols, rows))  # segments in index order: argmin's tie-breaking
        rows, cols = rows[order], cols[order]
        start = np.concatenate([[0], np.cumsum(cnt)[:-1]])
        rel = Qc[rows] - A[cols]
        raw = (rel[:, 0] * d[cols, 0] + rel[:, 1] * d[cols, 1]) / (L[cols] * L[cols])
        u = np.clip(raw, 0.0, 1.0)
        dist = np.hypot(Qc[rows, 0] - (A[cols, 0] + u * d[cols, 0]),
                        Qc[rows, 1] - (A[cols, 1] + u * d[cols, 1]))  # as _to_segments
        sarc = S0[cols] + u * L[cols]
        dm = np.minimum.reduceat(dist, start)
        first = np.flatnonzero(dist == dm[rows])
        _, at = np.unique(rows[first], return_index=True)
        pick = first[at]
        seg[sl], uu[sl], rawu[sl], dmin[sl], arc[sl] = cols[pick], u[pick], raw[pick], dm, sarc[pick]
        cand = dist <= (dm + ambiguity)[rows]
        hi = np.maximum.reduceat(np.where(cand, sarc, -np.inf), start)
        lo = np.minimum.reduceat(np.where(cand, sarc, np.inf), start)
        amb[sl] = (hi - lo) > _BRANCH * (dm + ambiguity)
    status = np.full(n, SEGMENT, dtype=int)
    # ambiguous samples: arc-length continuity with the neighbouring unambiguous ones
    idx = np.flatnonzero(amb)
    if idx.size:
        clear = np.flatnonzero(~amb)
        for k in idx:
            if k > 0 and status[k - 1] != AMBIGUOUS:
                ref = arc[k - 1]  # the previous sample (clear or already resolved)
            else:
                after = clear[clear > k]
                ref = arc[after[0]] if after.size else None
            if ref is None:
                status[k] = AMBIGUOUS
                continue
            raw, u, dist, s = _to_segments(Q[k:k + 1], A, d, L, S0)
            raw, u, dist, s = raw[0], u[0], dist[0], s[0]
            cand = np.flatnonzero(dist <= dmin[k] + ambiguity)
            near = cand[np.argmin(np.abs(s[cand] - ref))]
            branch = cand[np.abs(s[cand] - s[near]) <= _BRANCH * (dmin[k] + ambiguity)]
            j = branch[np.argmin(dist[branch])]
            seg[k], uu[k], rawu[k], dmin[k], arc[k] = j, u[j], raw[j], dist[j], s[j]
            status[k] = CONTINUITY
    point = A[seg] + uu[:, None] * d[seg]
    normal = np.column_stack([-d[seg, 1], d[seg, 0]]) / L[seg][:, None]
    eps = 1e-9 * max(1.0, float(np.abs(V).max())) / L[seg]  # rounding on the end vertex: in range
    at_start = (seg == 0) & (rawu < -eps)
    at_end = (seg == nseg - 1) & (rawu > 1.0 + eps)
    closed = bool(np.hypot(*(V[0] - V[-1])) <= 1e-9 * max(1.0, float(np.abs(V).max())))
    clamp = closed or beyond_ends == "clamp"
    out = (at_start | at_end) & (not clamp)
    corner = ((uu <= 0.0) & (seg > 0)) | ((uu >= 1.0) & (seg < nseg - 1)) | ((at_start | at_end) & clamp)
    corner &= ~out
    ck = np.flatnonzero(corner)
    if ck.size:
        vec = Q[ck] - point[ck]
        norm = np.hypot(vec[:, 0], vec[:, 1])
        tiny = norm <= 1e-12 * max(1.0, lmax)
        dirn = vec / np.where(tiny, 1.0, norm)[:, None]
        # on the vertex itself: the mean of the two adjacent unit normals
        other = np.clip(np.where(uu[ck] <= 0.0, seg[ck] - 1, seg[ck] + 1), 0, nseg - 1)
        n2 = np.column_stack([-d[other, 1], d[other, 0]]) / L[other][:, None]
        bis = normal[ck] + n2
        bn = np.hypot(bis[:, 0], bis[:, 1])
        bis = np.where((bn > 1e-9)[:, None], bis / np.where(bn > 1e-9, bn, 1.0)[:, None], normal[ck])
        normal[ck] = np.where(tiny[:, None], bis, dirn)
        status[ck[status[ck] == SEGMENT]] = VERTEX
    status[out] = OUT_OF_RANGE
    drop = status < 0
    point[drop] = np.nan
    normal[drop] = np.nan
    return TrackProjection(t=t, point=point, normal=normal, distance=dmin, arc=arc, segment=seg,
                           status=status)


@dataclass(frozen=True, kw_only=True, eq=False)
class TrackLine(Linearizable, Item):
    r"""The object moves along a known planar polyline (timing unknown).

    Parameters
    ----------
    x, y : array_like of float, shape (P,)
        Vertices of the path in m on the first and second of ``axes``, in the order
        travelled (P >= 2, no repeated consecutive vertices). Make the polyline fine
        enough that its segments follow the curvature of the path.
    axes : (str, str)
        The two axes of the plane, default ``("x", "y")``.
    t0, t1 : float, optional
        Interval in s during which the object is on the path; default the whole
        recording.
    about : array_like (K, 2), optional
        Linearization point: the current position estimate (m) on ``axes`` at the
        times ``about_t``. Normally left empty: :meth:`NavigationProblem.solve` then runs
        the sequential loop (:func:`bvpnav.solve.solve_sequential`), which fills it
        via :meth:`linearized`. An item with ``about`` is an ordinary linear item.
    about_t : array_like (K,), optional
        Times (s) of ``about``; the item gives one row per time inside ``[t0, t1]``.
    ambiguity : float
        m (default 0.5): how much farther than the nearest segment another branch may be
        and still make the sample ambiguous (see :func:`project_onto_polyline`).
    beyond_ends : {"drop", "clamp"}
        Samples of the estimate beyond an end of the path give no row (``"drop"``, the
        paper's choice, right when the ends are known otherwise or the object may leave
        the path there) or are pulled back to the end vertex (``"clamp"``).
    sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma``, ``huber`` and ``tol`` are distances to
        the path in m (scalars).

    Notes
    -----
    At each time :math:`t_k` the nearest point :math:`q_k` of the polyline to the
    current estimate :math:`p_k` gives the row

    .. math:: \rho_k = n_k \cdot r(t_k) - n_k \cdot q_k,

    the signed distance of :math:`r(t_k)` from the tangent line at :math:`q_k`, with
    :math:`n_k` the segment's unit normal (or the unit direction from :math:`q_k` to
    :math:`p_k` at a corner). Up to the normalisation this is the 2011 paper's equation
    (24), :math:`(Y_i - Y_{i-1}) r_x - (X_i - X_{i-1}) r_y = X_{i-1} Y_i - X_i Y_{i-1}`,
    with the segment chosen by distance instead of by the horizontal coordinate (so
    vertical parts and loops work). Samples beyond the ends of the path give no row;
    ambiguous samples are resolved by arc-length continuity (see
    :func:`project_onto_polyline`).

    In hard and band mode the sequential loop starts with a soft copy
    (:meth:`continuation_sigma`, :meth:`with_mode`): hard rows from a far start fix the
    estimate on the path at wrong arc lengths, from which the iteration recovers only
    slowly (see :mod:`bvpnav.solve.sequential`).

    With ``solve(uncertainty=...)`` the standard deviations are those of the last
    linearization (the tangent rows at the final estimate): an approximation that ignores
    the path's curvature and the choice of segment, good where the estimate is close to
    the path compared with its radius of curvature.

    Examples
    --------
    A vehicle that drives 10 m along x in 10 s and is known to stay on the line y = 0, while a
    small bias on its y accelerometer would bend the path (solved by sequential linearization):

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, TrackLine
    >>> t = np.linspace(0.0, 10.0, 51)
    >>> acc = np.column_stack([np.zeros(51), 0.02 * np.sin(t)])
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc, axes=("x", "y"))).add(
    ...     Position(t=[0.0, 10.0], value=[[0.0, 0.0], [10.0, 0.0]]),
    ...     TrackLine(x=[0.0, 5.0, 10.0], y=[0.0, 0.0, 0.0], axes=("x", "y"), sigma=0.01))
    >>> sol = prob.solve(solver="direct")
    >>> print(f"largest |y| {np.abs(sol.position('y')).max():.3f} m")
    largest |y| 0.000 m
    """

    x: Any
    y: Any
    axes: Any = ("x", "y")
    t0: float | None = None
    t1: float | None = None
    about: Any = None
    about_t: Any = None
    ambiguity: float = 0.5
    beyond_ends: str = "drop"
    units = "m"

    def validate(self) -> None:
        label = self.label
        x = finite(self.x, label, "x").ravel()
        y = finite(self.y, label, "y").ravel()
        if x.size != y.size:
            raise InputError(f"{label}: x has {x.size} vertices but y has {y.size}; give one y per x")
        if x.size < 2:
            raise InputError(f"{label}: the path needs at least 2 vertices (x, y in m), got {x.size}")
        seglen = np.hypot(np.diff(x), np.diff(y))
        bad = np.flatnonzero(seglen <= 0)
        if bad.size:
            raise InputError(f"{label}: vertices {bad[0]} and {bad[0] + 1} coincide at "
                             f"({x[bad[0]]:g}, {y[bad[0]]:g}) m; remove the repeated vertex")
        if self.axes is None or len(self.axes) != 2:
            raise InputError(f"{label}: axes={self.axes!r}; a track lies in a plane: give two axis "
                             "names, e.g. axes=('x', 'z')")
        if self.axes[0] == self.axes[1]:
            raise InputError(f"{label}: axes={self.axes!r} names the same axis twice")
        for what in ("sigma", "tol"):
            v = getattr(self, what)
            if v is not None and np.size(v) != 1:
                raise InputError(f"{label}: {what} must be one distance in m (the rows follow the "
                                 "estimate, so per-row values cannot be matched to them)")
        if (self.t0 is None) != (self.t1 is None):
            lo = float(times(self.t0, label, "t0")[0]) if self.t0 is not None else -np.inf
            hi = float(times(self.t1, label, "t1")[0]) if self.t1 is not None else np.inf
        elif self.t0 is not None:
            lo, hi = interval(self.t0, self.t1, label)
        else:
            lo, hi = None, None
        object.__setattr__(self, "t0", None if lo is None or not np.isfinite(lo) else lo)
        object.__setattr__(self, "t1", None if hi is None or not np.isfinite(hi) else hi)
        if not (np.isfinite(self.ambiguity) and self.ambiguity >= 0):
            raise InputError(f"{label}: ambiguity={self.ambiguity!r} must be a distance >= 0 in m")
        object.__setattr__(self, "ambiguity", float(self.ambiguity))
        if self.beyond_ends not in ("drop", "clamp"):
            raise InputError(f"{label}: beyond_ends={self.beyond_ends!r}; choose 'drop' or 'clamp'")
        if (self.about is None) != (self.about_t is None):
            raise InputError(f"{label}: give about (positions, m) and about_t (times, s) together")
        if self.about is not None:
            at = times(self.about_t, label, "about_t")
            ab = finite(self.about, label, "about")
            if ab.ndim != 2 or ab.shape != (at.size, 2):
                raise InputError(f"{label}: about has shape {ab.shape}; expected ({at.size}, 2): one "
                                 f"position on {list(self.axes)} per time in about_t")
            object.__setattr__(self, "about_t", at)
            object.__setattr__(self, "about", ab)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)

    # ------------------------------------------------------- linearization
    @property
    def vertices(self) -> np.ndarray:
        """The polyline, shape (P, 2), m."""
        return np.column_stack([self.x, self.y])

    @property
    def needs_linearization(self) -> bool:
        """True while the item has no linearization point (the sequential loop supplies it)."""
        return self.about is None

    def in_interval(self, t) -> np.ndarray:
        """Mask of the times (s) inside ``[t0, t1]``."""
        t = np.asarray(t, dtype=float)
        m = np.ones(t.shape, dtype=bool)
        if self.t0 is not None:
            m &= t >= self.t0 - 1e-12 * max(1.0, abs(self.t0))
        if self.t1 is not None:
            m &= t <= self.t1 + 1e-12 * max(1.0, abs(self.t1))
        return m

    def linearized(self, t, positions) -> TrackLine:
        """A copy linearized about an estimate.

        Parameters
        ----------
        t : array_like (K,)
            Times, s (e.g. the sample times of a solution).
        positions : array_like (K, 2) or pandas.DataFrame
            Estimated positions, m, on ``axes`` (a DataFrame is indexed by column name,
            e.g. ``solution.trajectory``).

        Returns
        -------
        TrackLine
            The same item with ``about``/``about_t`` set to the samples inside ``[t0, t1]``.
        """
        t = np.asarray(t, dtype=float)
        if isinstance(positions, pd.DataFrame):
            missing = [a for a in self.axes if a not in positions.columns]
            if missing:
                raise InputError(f"{self.label}: the estimate has no column(s) {missing} for axes "
                                 f"{list(self.axes)}")
            positions = positions[list(self.axes)].to_numpy()
        p = np.asarray(positions, dtype=float).reshape(t.size, 2)
        keep = self.in_interval(t)
        if not keep.any():
            raise InputError(f"{self.label}: no time of the estimate lies in [t0, t1] = "
                             f"[{self.t0}, {self.t1}] s")
        return dataclasses.replace(self, about=p[keep], about_t=t[keep])

    def projection(self) -> TrackProjection:
        """Nearest points and row directions at the linearization point (see
        :func:`project_onto_polyline`; computed once per linearized copy)."""
        if self.about is None:
            raise InputError(f"{self.label}: no linearization point yet; use linearized(t, positions)")
        cached = self.__dict__.get("_projection")
        if cached is None:
            keep = self.in_interval(self.about_t)
            cached = project_onto_polyline(self.vertices, self.about_t[keep], self.about[keep],
                                           self.ambiguity, self.beyond_ends)
            object.__setattr__(self, "_projection", cached)
        return cached

    def linearization_counts(self) -> dict[str, int]:
        """Row status counts of the linearization point's projection (see :class:`TrackProjection`)."""
        return self.projection().counts()

    @property
    def length(self) -> float:
        """Arc length of the polyline, m."""
        return float(np.sum(np.hypot(np.diff(self.x), np.diff(self.y))))

    def continuation_sigma(self) -> float:
        r"""Sigma (m) of the soft stand-in for a hard or band track in the sequential loop.

        Returns
        -------
        float
            ``max(d_rms, floor)``: the RMS distance (m) of the linearization point's kept
            samples to the path, but at least the band half-width ``tol`` (band mode) or
            1e-3 of the path length :attr:`length` (hard mode).

        Notes
        -----
        :math:`\sigma = \max(\sqrt{\overline{d_k^2}}, \sigma_\min)`; see
        :mod:`bvpnav.solve.sequential` for why the loop starts soft.
        """
        pr = self.projection()
        d = pr.distance[pr.kept]
        rms = float(np.sqrt(np.mean(d**2))) if d.size else 0.0
        floor = float(np.max(self.tol)) if self.mode == "band" else CONTINUATION_FLOOR * self.length
        return max(rms, floor)

    def with_mode(self, mode: str, sigma=None, tol=None, huber=None) -> TrackLine:
        """A copy in another mode (same path, interval and linearization point; m)."""
        new = dataclasses.replace(self, mode=mode, sigma=sigma, tol=tol, huber=huber)
        if "_projection" in self.__dict__:  # the rows do not depend on the mode
            object.__setattr__(new, "_projection", self.__dict__["_projection"])
        return new

    # ------------------------------------------------------------ contract
    @classmethod
    def example(cls) -> TrackLine:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        tk = np.linspace(1.0, 9.0, 9)
        about = np.column_stack([tk, 0.5 * np.sin(tk) + 0.1])
        return cls(x=[0.0, 4.0, 7.0, 10.0], y=[0.0, 1.0, 0.5, 0.0], axes=("x", "y"),
                   about=about.tolist(), about_t=tk.tolist())

    def compile(self, model):
        if self.about is None:
            raise InputError(
                f"{self.identify()}: a track is nonlinear and needs a linearization point. "
                "NavigationProblem.solve() supplies it (sequential loop, bvpnav.solve.sequential); to "
                "compile by hand use item.linearized(t, positions) first")
        model.axes_of(self.axes, self.identify())
        pr = self.projection()
        k = np.flatnonzero(pr.kept)
        if k.size == 0:
            raise InputError(
                f"{self.identify()}: every sample of the linearization point is beyond the ends of the "
                f"path or ambiguous ({pr.counts()}); check the path, axes={list(self.axes)} and "
                "the interval t0/t1")
        tk = pr.t[k]
        rows = model.position(tk, self.axes, what=f"{self.identify()}(t=...)")  # rows 2 i + a
        nrm = pr.normal[k]
        C = sp.csr_matrix((nrm.ravel(), (np.repeat(np.arange(k.size), 2), np.arange(2 * k.size))),
                          shape=(k.size, 2 * k.size))
        rhs = np.sum(nrm * pr.point[k], axis=1)
        labels = tuple(f"track(t={v:.6g})" for v in tk)
        return Affine(C @ rows.A, C @ rows.c - rhs, labels)

    def params(self) -> dict[str, Any]:
        out = super().params()
        if self.about is None:
            out.pop("about_t", None)
        return out

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"n_k \cdot r(t_k) - n_k \cdot q_k = 0"

    def math(self) -> str:
        ax = "".join(self.axes)
        lin = "not linearized" if self.about is None else f"{self.about_t.size} sample(s)"
        return (f"n_k . r_{ax}(t_k) - n_k . q_k = 0: nearest segment of a {self.x.size}-vertex path "
                f"({lin})")
