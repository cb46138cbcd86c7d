"""The time grid: validation, steps and evaluation rows of the hat functions."""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .errors import InputError
from .timebase import as_seconds

__all__ = ["TimeGrid", "MeshGrid", "as_times", "mesh_nodes"]

#: Relative slack (in units of the window length) allowed when an item time sits
#: on the window's edge but is off by rounding, e.g. ``t = 0.1 * 100``.
EDGE_SLACK = 1e-9


def as_times(t, name: str = "t") -> np.ndarray:
    """Return ``t`` as a fresh 1-D float array in s, or raise :class:`InputError` naming ``name``.

    The one time normalisation of :mod:`bvpnav.timebase` (a copy; bool, complex, object,
    text, datetime and duration values refused by name with the conversion to use).
    """
    return as_seconds(t, name, limit=False)


@dataclass(frozen=True, eq=False)
class TimeGrid:
    r"""Strictly increasing sample times ``t_1 < ... < t_N`` in s.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times in s; finite and strictly increasing, ``N >= 3``, at most
        :data:`bvpnav.timebase.MAX_SECONDS` in magnitude. Non-uniform steps are allowed.
        The array is copied (then frozen); datetimes and epochs in ms/us/ns are refused
        with the conversion :func:`bvpnav.timebase.to_seconds`.

    Notes
    -----
    The steps are :math:`h_i = t_{i+1} - t_i`. The hat function of node ``j`` is

    .. math:: \phi_j(t) = \max(0, 1 - |t - t_j| / h), \quad h = h_{j-1} \text{ or } h_j,

    so any piecewise-linear function is :math:`r(t) = \sum_j r_j \phi_j(t)`.

    Examples
    --------
    >>> from bvpnav import TimeGrid
    >>> grid = TimeGrid([0.0, 0.5, 1.0, 2.0])
    >>> grid
    TimeGrid(N=4, t0=0 s, t1=2 s)
    >>> grid.duration, grid.h.tolist()
    (2.0, [0.5, 0.5, 1.0])
    """

    t: np.ndarray
    h: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        t = as_seconds(self.t, "time")  # a copy: the caller's array is never frozen or kept
        if t.size < 3:
            raise InputError(
                f"time: {t.size} samples given; the FEM needs at least 3 samples "
                "(two elements). Pass a longer recording."
            )
        dt = np.diff(t)
        bad = np.flatnonzero(dt <= 0)
        if bad.size:
            i = int(bad[0]) + 1
            kind = "duplicate" if dt[bad[0]] == 0 else "decreasing"
            raise InputError(
                f"time: sample {i} ({float(t[i])!r} s) is {kind} after sample {i - 1} "
                f"({float(t[i - 1])!r} s); "
                "times must be strictly increasing. Sort the samples and drop duplicates."
            )
        t.setflags(write=False)
        dt.setflags(write=False)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "h", dt)

    # ------------------------------------------------------------------ basics
    @property
    def n(self) -> int:
        """Number of samples (nodes) N."""
        return int(self.t.size)

    @property
    def t0(self) -> float:
        """Start of the window, s."""
        return float(self.t[0])

    @property
    def t1(self) -> float:
        """End of the window, s."""
        return float(self.t[-1])

    @property
    def duration(self) -> float:
        """Window length ``t_N - t_1``, s."""
        return self.t1 - self.t0

    def gaps(self, factor: float = 10.0) -> np.ndarray:
        """Indices ``i`` whose step ``h_i`` exceeds ``factor`` times the median step."""
        med = float(np.median(self.h))
        return np.flatnonzero(self.h > factor * med)

    # ------------------------------------------------------------ evaluation
    def check_inside(self, times: np.ndarray, what: str) -> np.ndarray:
        """Clip rounding-level excursions to the window; raise for real ones.

        Parameters
        ----------
        times : ndarray
            Times in s.
        what : str
            Name used in the error message (e.g. ``"Position(t=...)"``).
        """
        slack = EDGE_SLACK * max(self.duration, 1.0)
        lo, hi = self.t0, self.t1
        bad = np.flatnonzero((times < lo - slack) | (times > hi + slack))
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"{what}: time {float(times[k])!r} s (entry {k}) is outside the recording window "
                f"[{lo!r}, {hi!r}] s; bvpnav never extrapolates. Use a time inside the window."
            )
        return np.clip(times, lo, hi)

    def nearest(self, times: np.ndarray, tol: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The index of the time nearest each of ``times`` (s; the earlier of two equally near)
        and whether it lies within ``tol`` s of it (default: rounding of the window,
        ``EDGE_SLACK * max(duration, 1)``)."""
        tol = EDGE_SLACK * max(self.duration, 1.0) if tol is None else tol
        t = self.t
        k = np.clip(np.searchsorted(t, times), 0, self.n - 1)
        near = np.where((k > 0) & (np.abs(t[k - 1] - times) < np.abs(t[k] - times)), k - 1, k)
        return near, np.abs(t[near] - times) <= tol

    def locate(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Element index ``j`` and local coordinate ``s = t - t_j`` for each time.

        The element of a time equal to a node ``t_j`` (``j < N``) is ``j``; the last
        node belongs to the last element.
        """
        j = np.searchsorted(self.t, times, side="right") - 1
        j = np.clip(j, 0, self.n - 2)
        return j, times - self.t[j]

    def interpolation_matrix(self, times, what: str = "time") -> sp.csr_matrix:
        """Rows ``phi(t)`` evaluating the piecewise-linear nodal function at ``times``.

        Returns
        -------
        scipy.sparse.csr_matrix, shape (len(times), N)
            Row ``k`` has ``1 - s/h_j`` at column ``j`` and ``s/h_j`` at ``j + 1``.
        """
        times = self.check_inside(as_times(times, what), what)
        j, s = self.locate(times)
        theta = s / self.h[j]
        m = times.size
        rows = np.repeat(np.arange(m), 2)
        cols = np.column_stack([j, j + 1]).ravel()
        vals = np.column_stack([1.0 - theta, theta]).ravel()
        return sp.csr_matrix((vals, (rows, cols)), shape=(m, self.n))

    def nodes_in(self, t0: float, t1: float) -> np.ndarray:
        """Indices of the nodes with ``t0 <= t_j <= t1``."""
        return np.flatnonzero((self.t >= t0) & (self.t <= t1))

    def __len__(self) -> int:
        return self.n

    def __repr__(self) -> str:
        return f"TimeGrid(N={self.n}, t0={self.t0:g} s, t1={self.t1:g} s)"


def mesh_nodes(grid: TimeGrid, segment: float, times=()) -> np.ndarray:
    r"""The samples a coarse mesh keeps as nodes (increasing indices into ``grid``).

    Parameters
    ----------
    grid : TimeGrid
        Every sample, times in s.
    segment : float
        Longest element, s: between two nodes further apart, samples are added greedily (the
        last sample within ``segment`` of the previous node) until none is; one step longer
        than ``segment`` stays one element.
    times : array_like of float
        Times (s) that need nodes (the items' instants): a time on a sample makes it a node,
        a time between two samples makes both of them nodes (the element between them is
        then one step, where positions and velocities are those of the fine grid).

    Notes
    -----
    The first and last samples are nodes. An element with exactly one sample inside it
    gets that sample as a node too: the condensed load residual of an element is a
    2-vector whose covariance is regular only with two or more samples inside.

    Examples
    --------
    Ten seconds at 10 Hz, elements of at most 2 s, and a node wanted at 3.05 s (between two
    samples: both become nodes):

    >>> import numpy as np
    >>> from bvpnav.grid import TimeGrid, mesh_nodes
    >>> grid = TimeGrid(np.linspace(0.0, 10.0, 101))
    >>> mesh_nodes(grid, 2.0, times=[3.05]).tolist()
    [0, 20, 30, 31, 51, 71, 91, 100]
    """
    fixed = _needed_nodes(grid, times)
    out = [fixed[:1]]
    # the greedy walk on the times as Python floats (the same doubles: the same sums and
    # comparisons as on the array's scalars, and bisect_right is searchsorted's side="right"),
    # without a numpy call per node
    tl = np.asarray(grid.t, dtype=float).tolist()
    reach = segment * (1.0 + 1e-9)   # a sample at the segment's end up to rounding is within it
    for p, q in zip(fixed[:-1].tolist(), fixed[1:].tolist(), strict=True):
        cur, add = p, []
        while tl[q] - tl[cur] > reach:
            nxt = max(bisect.bisect_right(tl, tl[cur] + reach) - 1, cur + 1)
            if nxt >= q:
                break
            add.append(nxt)
            cur = nxt
        out.append(np.array(add + [q], dtype=np.int64))
    nodes = np.concatenate(out).astype(np.int64)
    lone = nodes[:-1][np.diff(nodes) == 2] + 1          # one sample inside: make it a node
    return np.union1d(nodes, lone).astype(np.int64)


def _needed_nodes(grid: TimeGrid, times=()) -> np.ndarray:
    """The samples :func:`mesh_nodes` keeps before its walk (increasing indices into ``grid``):
    the ends, a time's sample, both samples around a time between two."""
    t, N = grid.t, grid.n
    keep = np.zeros(N, dtype=bool)
    keep[[0, N - 1]] = True
    tt = np.asarray(times, dtype=float).ravel()
    tol = EDGE_SLACK * max(grid.duration, 1.0)
    # a time outside the window is left to the item that names it (its rows refuse it by name)
    tt = np.clip(tt[(tt >= grid.t0 - tol) & (tt <= grid.t1 + tol)], grid.t0, grid.t1)
    if tt.size:
        near, on = grid.nearest(tt, tol)
        keep[near[on]] = True
        j = np.clip(np.searchsorted(t, tt[~on], side="right") - 1, 0, N - 2)
        keep[j] = True
        keep[j + 1] = True
    return np.flatnonzero(keep)


@dataclass(frozen=True, eq=False)
class MeshGrid(TimeGrid):
    r"""The nodes of a coarse mesh over a fine grid of samples (``t`` the node times, s).

    Parameters
    ----------
    t : array_like, shape (n,)
        Node times, s: some of ``fine``'s sample times.
    fine : TimeGrid
        Every sample.
    nodes : ndarray of int, shape (n,)
        The sample index of each node.

    Notes
    -----
    Between two nodes the condensed problem keeps no position: a row evaluated at a time
    inside an element of more than one sample step (:meth:`interpolation_matrix`,
    :meth:`nodes_in`) raises :class:`~bvpnav.errors.InputError` naming what asked, instead of
    interpolating the nodes linearly (which is not the fine trajectory). Inside an element
    of one step the fine and the coarse hats agree.
    """

    fine: TimeGrid | None = field(default=None, repr=False)
    nodes: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        super().__post_init__()
        nodes = np.asarray(self.nodes, dtype=np.int64).copy()
        nodes.setflags(write=False)
        object.__setattr__(self, "nodes", nodes)

    def single_step(self, j: np.ndarray) -> np.ndarray:
        """Whether element ``j`` is one sample step of the fine grid."""
        return self.nodes[j + 1] == self.nodes[j] + 1

    def interpolation_matrix(self, times, what: str = "time") -> sp.csr_matrix:
        """As :meth:`TimeGrid.interpolation_matrix`, for times on a node or inside an element
        of one sample step; :class:`InputError` naming ``what`` for any other time."""
        times = self.check_inside(as_times(times, what), what)
        self.check_on_mesh(times, what)
        return super().interpolation_matrix(self.snapped(times), what)

    def snapped(self, times: np.ndarray) -> np.ndarray:
        """``times`` with those within rounding of a node moved onto it."""
        near, on = self.nearest(times)
        return np.where(on, self.t[near], times)

    def check_on_mesh(self, times: np.ndarray, what: str) -> None:
        """:class:`InputError` naming ``what`` for a time inside an element of several samples."""
        times = self.snapped(np.asarray(times, dtype=float))
        j, s = self.locate(times)
        bad = np.flatnonzero((s > 0) & (times != self.t[j + 1]) & ~self.single_step(j))
        if bad.size:
            k = int(bad[0])
            jj = int(j[k])
            raise InputError(
                f"{what}: time {float(times[k])!r} s lies inside the mesh element [{float(self.t[jj])!r}, "
                f"{float(self.t[jj + 1])!r}] s ({int(self.nodes[jj + 1] - self.nodes[jj])} sample steps), "
                "where "
                "the condensed problem keeps no position; the mesh gets nodes at the items' times `t`, "
                "`t0`, `t1` it finds: give this time to the item as one of those, or solve without "
                "segment=")

    def nodes_in(self, t0: float, t1: float) -> np.ndarray:
        """Indices of the nodes with ``t0 <= t_j <= t1``; :class:`InputError` when samples of the
        interval are not nodes (an item over every sample of an interval would silently see
        the nodes only)."""
        fine = self.fine.nodes_in(t0, t1)
        if fine.size and not np.all(np.isin(fine, self.nodes)):
            raise InputError(
                f"an item over every sample of [{t0!r}, {t1!r}] s: {int(np.sum(~np.isin(fine, self.nodes)))} "
                "of its samples are not mesh nodes (segment=); such items need every sample: solve "
                "without segment=")
        return super().nodes_in(t0, t1)

    def __repr__(self) -> str:
        return f"MeshGrid(n={self.n} nodes of N={self.fine.n} samples, t0={self.t0:g} s, t1={self.t1:g} s)"
