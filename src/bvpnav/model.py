"""The unknowns of a navigation problem and the linear maps items are built from.

All unknowns live in one stacked vector ``x`` (numpy here; one cvxpy Variable in :mod:`bvpnav.cvx`). Per axis
``a`` (in the order of ``data.axes``) the block is

    [ r_a (N nodal positions, m) | w_a (N acceleration residuals, m/s^2) | v0_a, v1_a (m/s) ]

followed by the error-model parameters ``l`` (q entries, units per parameter) and, when an
error model declares them, its *node states* ``s`` (a few per time node: e.g. the attitude
error and the random-walk biases of :class:`~bvpnav.error_models.ErrorStates`), whose
acceleration columns are local in time (sparse ``G_s``).
Everything an item needs is an :class:`Affine` map ``A x + c`` built from sparse
matrices, so the same rows feed cvxpy, the direct back ends, ``describe()`` and
``matrices()``.
"""

from __future__ import annotations

import copy
import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from . import fem
from .errors import InputError
from .grid import as_times
from .imu import ImuData
from .sparse import as_csr, row_scaled

__all__ = ["Affine", "Cone", "LinearizationPoint", "NavModel", "RowLabels", "state_component"]


def state_component(error_model):
    """The one component of ``error_model`` that declares node states (``state_size``), or
    None; :class:`InputError` when several do (one node-state model per problem)."""
    if error_model is None:
        return None
    comps = [c for c in getattr(error_model, "components", (error_model,)) if hasattr(c, "state_size")]
    if len(comps) > 1:
        raise InputError(f"error model: {len(comps)} components with node states ({comps}); give one "
                         "ErrorStates(...) with every state it should carry")
    return comps[0] if comps else None


def canonical_csr(A) -> sp.csr_matrix:
    """``A`` as canonical CSR (sorted indices, duplicates summed, explicit zeros dropped)."""
    A = sp.csr_matrix(A)
    A.sum_duplicates()
    A.eliminate_zeros()
    A.sort_indices()
    return A


def _block_csr(blk) -> sp.csr_matrix:
    """A block as CSR; a dense one whose nonzero columns hold no zero (the error-model
    columns ``M G`` of one axis: the other axes' columns all zero) directly from those
    columns, without scanning every entry for nonzeros (three axes with six parameters at
    N = 1e6: 18 million entries, 12 million of them zero)."""
    if sp.issparse(blk) or np.ndim(blk) != 2:
        return sp.csr_matrix(blk)
    blk = np.asarray(blk, dtype=float)
    cols = np.flatnonzero(np.any(blk != 0, axis=0))
    return columns_csr(cols, blk[:, cols], blk.shape[1])


def columns_csr(cols: np.ndarray, vals: np.ndarray, ncols: int) -> sp.csr_matrix:
    """The (m, ncols) CSR matrix whose columns ``cols`` (increasing) hold ``vals`` (m,
    cols.size) and whose other columns are zero, canonical; made directly from ``vals``
    when it holds no zero (every row then has ``cols.size`` entries), else through scipy's
    conversion, which drops the zeros."""
    vals = np.asarray(vals, dtype=float)
    m, k = vals.shape
    if not k or not np.all(vals):
        dense = np.zeros((m, ncols))
        dense[:, cols] = vals
        return sp.csr_matrix(dense)
    itype = np.int32 if max(m * k, ncols) < 2**31 else np.int64
    indptr = np.arange(0, m * k + 1, k, dtype=itype)
    out = sp.csr_matrix((vals.ravel(), np.tile(np.asarray(cols).astype(itype), m), indptr), shape=(m, ncols))
    out.has_canonical_format = True
    return out


#: Stored entries whose absolute values :func:`abs_product` takes at a time (8 MB).
ABS_BLOCK = 1 << 20


def abs_product(A: sp.csr_matrix, v: np.ndarray) -> np.ndarray:
    """``|A| v`` for a CSR ``A``, a block of rows at a time: the absolute values of about
    :data:`ABS_BLOCK` stored entries at once, on ``A``'s own index arrays, instead of an
    absolute-value copy of every entry (three axes' FEM rows at N = 1e6: 24 million
    entries, 192 MB of fresh memory per call)."""
    m = A.shape[0]
    out = np.zeros(m)
    if not A.nnz:
        return out
    cuts = np.unique(np.r_[0, np.searchsorted(A.indptr, np.arange(ABS_BLOCK, A.nnz, ABS_BLOCK)), m])
    for r0, r1 in zip(cuts[:-1], cuts[1:], strict=True):
        s, e = int(A.indptr[r0]), int(A.indptr[r1])
        if e > s:
            blk = sp.csr_matrix((np.abs(A.data[s:e]), A.indices[s:e], A.indptr[r0:r1 + 1] - s),
                                shape=(r1 - r0, A.shape[1]))
            out[r0:r1] = blk @ v
    return out


def rows_side_by_side(row_blocks: list, ncols: int) -> sp.csr_matrix:
    """One CSR matrix from groups of row blocks: group ``g`` is a list of ``(block,
    column)`` (sparse or dense blocks of the same rows, placed from ``column`` on, in
    increasing column order without overlap), the groups stacked one below the other.

    Notes
    -----
    Every entry is written once into the result's arrays, at its row's offset plus the
    entries the blocks before it hold in that row: no per-group matrix, empty filler
    blocks or stacked copy (three axes' FEM rows at N = 1e6: about 0.5 GB of temporaries
    fewer than placing each axis with scipy's ``hstack`` and stacking the axes). Where
    every block holds the same number of entries in each row of a stretch (the FEM rows
    but their first and last), the stretch is written as 2-D slices (rows by entries),
    the other rows by index arrays (three axes with six parameters at N = 1e6: 24 million
    entries, 0.7 s by index arrays alone). Blocks with sorted column indices and no
    duplicates give a canonical result.
    """
    groups = [[(_block_csr(blk), int(col)) for blk, col in group] for group in row_blocks]
    counts = [sum(np.diff(blk.indptr) for blk, _ in group) for group in groups]
    indptr = np.zeros(sum(len(c) for c in counts) + 1, dtype=np.int64)
    np.cumsum(np.concatenate(counts), out=indptr[1:])
    nnz = int(indptr[-1])
    itype = np.int32 if max(nnz, ncols) < 2**31 else np.int64
    indices = np.empty(nnz, dtype=itype)
    data = np.empty(nnz)
    row0 = 0
    for group, cnt in zip(groups, counts, strict=True):
        R = cnt.size
        per = [np.diff(blk.indptr) for blk, _ in group]
        lo, hi = _uniform_rows(per)
        if hi > lo:   # rows lo .. hi - 1: cnt[lo] entries each, one 2-D slice of the arrays
            s, C = int(indptr[row0 + lo]), int(cnt[lo])
            I2 = indices[s:s + (hi - lo) * C].reshape(hi - lo, C)
            D2 = data[s:s + (hi - lo) * C].reshape(hi - lo, C)
        edge = np.r_[0:lo, hi:R]
        filled = indptr[row0 + edge]   # next free place in each edge row (a copy)
        at = 0
        for (blk, col), pr in zip(group, per, strict=True):
            if hi > lo and (c := int(pr[lo])):
                a, b = int(blk.indptr[lo]), int(blk.indptr[hi])
                np.add(blk.indices[a:b].reshape(-1, c), col, out=I2[:, at:at + c], casting="unsafe")
                D2[:, at:at + c] = blk.data[a:b].reshape(-1, c)
                at += c
            if not edge.size:
                continue
            ends = blk.indptr
            src = np.r_[ends[0]:ends[lo], ends[hi]:ends[R]].astype(np.int64)
            dest = np.repeat(filled - ends[edge], pr[edge])
            dest += src
            indices[dest] = blk.indices[src]
            indices[dest] += col
            data[dest] = blk.data[src]
            filled += pr[edge]
        row0 += R
    return sp.csr_matrix((data, indices, indptr.astype(itype, copy=False)), shape=(row0, ncols))


def rows_with_tail(head: sp.csr_matrix, tail: list, col: int, below: Sequence = ()) -> sp.csr_matrix:
    """The rows of ``head`` (CSR, its columns before ``col``) with the rows of the ``tail``
    blocks (CSR, stacked one below the other, as many rows as ``head``) placed from column
    ``col`` on after each row's entries, then the rows of the ``below`` matrices: the result of
    :func:`rows_side_by_side` for these blocks, written by index arithmetic on whole arrays (a
    ``head`` made once serves every Gauss-Newton step of the node-state loop). Canonical when
    the blocks are. The result's pattern is kept on ``head`` (up to :data:`TAIL_PLAN_KEPT`
    entries): a next call with blocks on the very same index arrays writes the values only."""
    R, ncols = head.shape
    tail = [as_csr(t) for t in tail]
    below = [as_csr(b) for b in below]
    # the blocks' index arrays: the same objects as the last call's with this head (the loop's steps'
    # node-state columns on a kept pattern) give the same result's pattern, which only takes the values
    arrays = [head.indptr, head.indices] + [a for t in (*tail, *below) for a in (t.indptr, t.indices)]
    plan = getattr(head, "_bvpnav_tail_plan", None)
    if (plan is not None and plan[0] == col and len(plan[1]) == len(arrays)
            and all(a is b for a, b in zip(plan[1], arrays, strict=True))):
        pattern, dest, tdest, at = plan[2:]
        data = np.empty(pattern.nnz)
        data[dest] = head.data
        if tail:
            data[tdest] = np.concatenate([t.data for t in tail])
        for b, a in zip(below, at, strict=True):
            data[a:a + b.nnz] = b.data
        out = copy.copy(pattern)   # sharing its index arrays, which no reader changes in place
        out.data = data
        return out
    hc = np.diff(head.indptr)
    tc = np.concatenate([np.diff(t.indptr) for t in tail]) if tail else np.zeros(R, np.int64)
    bc = [np.diff(b.indptr) for b in below]
    indptr = np.zeros(R + sum(c.size for c in bc) + 1, dtype=np.int64)
    np.cumsum(np.concatenate([hc + tc, *bc]), out=indptr[1:])
    nnz = int(indptr[-1])
    itype = np.int32 if max(nnz, ncols) < 2**31 else np.int64
    indices = np.empty(nnz, dtype=itype)
    data = np.empty(nnz)
    start = indptr[:R]
    dest = np.arange(head.nnz) + np.repeat(start - head.indptr[:-1], hc)    # the head's entries
    indices[dest] = head.indices
    data[dest] = head.data
    tdest = None
    if tail:   # the tail's entries, after the head's in each row
        tind = np.concatenate([t.indices for t in tail])
        tptr = np.r_[0, np.cumsum(tc)]
        tdest = np.arange(tind.size) + np.repeat(start + hc - tptr[:-1], tc)
        indices[tdest] = tind + col
        data[tdest] = np.concatenate([t.data for t in tail])
    at, starts = int(indptr[R]), []
    for b in below:
        starts.append(at)
        indices[at:at + b.nnz] = b.indices
        data[at:at + b.nnz] = b.data
        at += b.nnz
    out = sp.csr_matrix((data, indices, indptr.astype(itype, copy=False)),
                        shape=(R + sum(c.size for c in bc), ncols))
    if nnz <= TAIL_PLAN_KEPT:   # a bounded plan on the head, which lives as long as its model
        pattern = copy.copy(out)
        pattern.data = np.zeros(0)   # the pattern keeps no values (its nnz is the index arrays')
        head._bvpnav_tail_plan = (col, arrays, pattern, dest, tdest, starts)
    return out


def _uniform_rows(per: list) -> tuple[int, int]:
    """The longest stretch of rows ``[lo, hi)`` in which each block has one entry count
    (``per``: each block's entries per row); ``(0, 0)`` for fewer than three rows."""
    R = per[0].size if per else 0
    if R < 3:
        return 0, 0
    bad = np.zeros(R, dtype=bool)
    for pr in per:
        bad |= pr != pr[R // 2]
    idx = np.flatnonzero(bad)
    if not idx.size:
        return 0, R
    edges = np.concatenate([[-1], idx, [R]])
    g = int(np.argmax(np.diff(edges)))
    return int(edges[g]) + 1, int(edges[g + 1])


class _LabelsOnDemand(Sequence):
    """A sequence of row labels made when read: subclasses give ``__len__`` and
    ``_label(i)`` for ``0 <= i < len``; indexing (negative too) and slices come from here."""

    def _label(self, i: int) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        i = int(i)
        if i < 0:
            i += len(self)
        if not 0 <= i < len(self):
            raise IndexError(i)
        return self._label(i)


class RowLabels(_LabelsOnDemand):
    """Row labels made on demand (``"fem_x[12]"``): N strings are not built per solve.

    Parameters
    ----------
    parts : sequence
        Each either ``(prefix, count)`` (``count`` labels ``f"{prefix}[{i}]"``) or a
        sequence of label strings.
    """

    def __init__(self, parts: Sequence):
        self.parts = [(str(q[0]), int(q[1])) if _is_indexed(q)
                      else (q if isinstance(q, TimeLabels) else tuple(q)) for q in parts]
        self._ends = np.cumsum([q[1] if _is_indexed(q) else len(q) for q in self.parts])

    def __len__(self) -> int:
        return int(self._ends[-1]) if len(self._ends) else 0

    def __iter__(self):
        for q in self.parts:
            if _is_indexed(q):
                yield from (f"{q[0]}[{i}]" for i in range(q[1]))
            else:
                yield from q

    def _label(self, i: int) -> str:
        k = int(np.searchsorted(self._ends, i, side="right"))
        q = self.parts[k]
        j = i - (int(self._ends[k - 1]) if k else 0)
        return f"{q[0]}[{j}]" if _is_indexed(q) else q[j]


class TimeLabels(_LabelsOnDemand):
    """Labels of rows at times, made on demand (``"vx(t=2.5)"``): row ``k * len(axes) + a``
    is time ``k``, axis ``a`` (the 10,000 fixes of a long recording are not formatted per
    solve).

    Parameters
    ----------
    quantity : str
        The labels' prefix (``""`` for positions, ``"v"`` for velocities).
    axes : sequence of str
        Axis names, in row order within a time.
    times : ndarray
        Times, s.
    """

    def __init__(self, quantity: str, axes: Sequence[str], times: np.ndarray):
        self.quantity, self.axes, self.times = str(quantity), list(axes), np.asarray(times, dtype=float)

    def __len__(self) -> int:
        return self.times.size * len(self.axes)

    def _label(self, i: int) -> str:
        k, a = divmod(i, len(self.axes))
        return f"{self.quantity}{self.axes[a]}(t={self.times[k]:.6g})"


def _is_indexed(q) -> bool:
    """``(prefix, count)`` rather than a sequence of labels."""
    return (isinstance(q, tuple) and len(q) == 2 and isinstance(q[0], str)
            and isinstance(q[1], int | np.integer) and not isinstance(q[1], bool))


#: Largest stored entries of a matrix whose row-scaled copy :meth:`Affine.__mul__` keeps with it (a big
#: problem's rows are not kept twice).
ROW_SCALED_KEPT = 1 << 17

#: The most entries of a :func:`rows_with_tail` result whose plan (pattern and destinations,
#: about 20 bytes an entry) is kept on its head for the next call.
TAIL_PLAN_KEPT = 1 << 18


@dataclass(frozen=True, eq=False)
class Affine:
    """An affine map ``x -> A x + c`` of the stacked unknowns.

    Parameters
    ----------
    A : scipy.sparse.csr_matrix, shape (m, n)
    c : ndarray, shape (m,)
    labels : sequence of str, optional
        One label per row (e.g. ``"x(t=2.5)"``) for reports (a tuple, or
        :class:`RowLabels` made on demand).

    Examples
    --------
    Two rows, ``x0 + 1`` and ``2 x1``, of an unknown vector of length 2; affine maps add and scale:

    >>> import numpy as np
    >>> import scipy.sparse as sp
    >>> from bvpnav import Affine
    >>> f = Affine(sp.csr_matrix(np.diag([1.0, 2.0])), np.array([1.0, 0.0]), labels=("a", "b"))
    >>> g = 3 * f - f
    >>> g.m, g.A.toarray().tolist(), g.c.tolist()
    (2, [[2.0, 0.0], [0.0, 4.0]], [2.0, 0.0])
    """

    A: sp.csr_matrix
    c: np.ndarray
    labels: Sequence[str] | None = None

    def __post_init__(self):
        A = as_csr(self.A)
        c = np.asarray(self.c, dtype=float)
        # a copy (the caller's array is not kept), broadcast when not already one value a row
        c = c.copy() if c.shape == (A.shape[0],) else np.broadcast_to(c, (A.shape[0],)).copy()
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "c", c)

    @property
    def m(self) -> int:
        """Number of rows."""
        return self.A.shape[0]

    def __len__(self) -> int:
        return self.m

    def __add__(self, other) -> Affine:
        if isinstance(other, Affine):
            return Affine(self.A + other.A, self.c + other.c, self.labels)
        return Affine(self.A, self.c + np.asarray(other, dtype=float), self.labels)

    def __sub__(self, other) -> Affine:
        if isinstance(other, Affine):
            return Affine(self.A - other.A, self.c - other.c, self.labels)
        return Affine(self.A, self.c - np.asarray(other, dtype=float), self.labels)

    def __neg__(self) -> Affine:
        return Affine(-self.A, -self.c, self.labels)

    def __mul__(self, k) -> Affine:
        k = np.asarray(k, dtype=float)
        if k.ndim == 0:
            return Affine(self.A * float(k), self.c * float(k), self.labels)
        k = np.broadcast_to(k, (self.m,))
        A = self.A
        if sp.issparse(A) and A.format == "csr" and A.has_canonical_format and np.all(k):
            # row scaling on the stored values (no sparse product by diags(k)); the index
            # arrays are shared, which is safe for a canonical matrix (nothing sorts or merges
            # them again) and keeps the result canonical. The scaled matrix is kept with A for
            # the next product by the same k on the same values' array (a shallow copy of A
            # with new values is another matrix; values are never changed in place: the
            # node-state loop's steps scale the same data rows)
            kept = getattr(A, "_bvpnav_row_scaled", None)
            if kept is not None and kept[1] is A.data and np.array_equal(kept[0], k):
                return Affine(kept[2], self.c * k, self.labels)
            out = row_scaled(A, k)
            if A.nnz <= ROW_SCALED_KEPT:
                A._bvpnav_row_scaled = (np.array(k), A.data, out)
            return Affine(out, self.c * k, self.labels)
        return Affine(sp.diags(k) @ A, self.c * k, self.labels)

    __rmul__ = __mul__

    def __truediv__(self, k) -> Affine:
        return self * (1.0 / np.asarray(k, dtype=float))

    def rows(self, idx) -> Affine:
        """A subset of the rows."""
        idx = np.asarray(idx)
        labels = None if self.labels is None else tuple(np.asarray(self.labels, dtype=object)[idx])
        return Affine(self.A[idx], self.c[idx], labels)

    @staticmethod
    def stacked_labels(labels: Sequence) -> Sequence[str] | None:
        """Row-label sequences stacked (None unless every one is given); made on demand
        when any of them is."""
        if any(lab is None for lab in labels):
            return None
        if any(isinstance(lab, RowLabels | TimeLabels) for lab in labels):
            return RowLabels([q for lab in labels for q in (
                lab.parts if isinstance(lab, RowLabels) else [lab])])
        return tuple(s for lab in labels for s in lab)

    @staticmethod
    def vstack(parts: Sequence[Affine]) -> Affine:
        """Stack several maps row-wise."""
        parts = list(parts)
        labels = Affine.stacked_labels([p.labels for p in parts])
        if len(parts) == 1:   # one part: its arrays, not a copy (maps are never changed in place)
            A = parts[0].A
            return Affine(A if sp.issparse(A) and A.format == "csr" else sp.csr_matrix(A), parts[0].c, labels)
        return Affine(sp.vstack([p.A for p in parts], format="csr"),
                      np.concatenate([p.c for p in parts]), labels)

    def value(self, x: np.ndarray) -> np.ndarray:
        """Evaluate at a numeric ``x``."""
        return self.A @ x + self.c

    def row_scale(self, x: np.ndarray) -> np.ndarray:
        """``|A| |x| + |c|`` per row: the size of the terms that cancel in each row."""
        A = self.A if sp.issparse(self.A) and self.A.format == "csr" else sp.csr_matrix(self.A)
        out = abs_product(A, np.abs(x))
        out += np.abs(self.c)
        return out


@dataclass(frozen=True, eq=False)
class Cone(Affine):
    r"""Affine rows grouped into second-order cones: ``||u_k||_2 <= s_k``.

    The rows come in consecutive groups of ``size``; in group ``k`` the first row is the
    bound ``s_k`` and the remaining ``size - 1`` rows are the vector ``u_k`` (both affine
    in ``x``, same units). Items of ``kind = "cone"`` return one from ``compile``.

    Parameters
    ----------
    A, c, labels
        As for :class:`Affine` (``m`` a multiple of ``size``).
    size : int
        Rows per group (1 + length of the vector), at least 2.

    Notes
    -----
    The constraint is :math:`\|A_{u,k} x + c_{u,k}\|_2 \le A_{s,k} x + c_{s,k}` per group.
    """

    size: int = 2

    def __post_init__(self):
        super().__post_init__()
        if int(self.size) < 2 or self.A.shape[0] % int(self.size):
            raise InputError(f"Cone: {self.A.shape[0]} rows do not split into groups of {self.size}")
        object.__setattr__(self, "size", int(self.size))

    @property
    def groups(self) -> int:
        """Number of cones."""
        return self.m // self.size

    def excess(self, x: np.ndarray) -> np.ndarray:
        """``||u_k|| - s_k`` per group at a numeric ``x`` (<= 0 where the cone holds)."""
        v = self.value(x).reshape(self.groups, self.size)
        return np.linalg.norm(v[:, 1:], axis=1) - v[:, 0]


@dataclass(frozen=True, eq=False)
class LinearizationPoint:
    r"""Where body-frame rows linearize the attitude (``data.body_point``).

    The attitude loop (:mod:`bvpnav.solve.attitude`) sets it on the data of each linearized
    step; :meth:`NavModel.body_velocity` reads it.

    Attributes
    ----------
    velocity : ndarray (N, 3)
        Navigation-frame velocity at every sample, m/s: the loop's evaluation at the current
        attitude.
    names : tuple of str
        The attitude parameters whose columns ``psi`` holds.
    psi : ndarray (N, 3, len(names))
        Navigation-frame attitude change per unit of each parameter, rad per unit
        (:math:`C \to \exp([\psi\times]) C`).
    """

    velocity: np.ndarray
    names: tuple
    psi: np.ndarray
    #: The GNSS antenna's estimated lever arm at the evaluation, m, body axes (None: not
    #: estimated): the point :meth:`NavModel.antenna_offset` linearizes :math:`C l` about.
    lever: tuple | None = None


def _skew(v: np.ndarray) -> np.ndarray:
    """``[v x]`` for an array of vectors (K, 3) -> (K, 3, 3)."""
    z = np.zeros(v.shape[0])
    x, y, w = v[:, 0], v[:, 1], v[:, 2]
    return np.stack([np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2)


def _body_axes(axes, what: str, word: str = "body axes") -> tuple[tuple[str, ...], list[int]]:
    """Names and indices of body axes given as a name, a sequence of names or ``None`` (all
    three), or :class:`InputError` naming ``what`` and the valid names."""
    body = ("x", "y", "z")
    names = (axes,) if isinstance(axes, str) else (body if axes is None else tuple(axes))
    bad = [a for a in names if a not in body]
    if bad or not names:
        raise InputError(f"{what}: {word} {list(names)}; give some of {list(body)}")
    return names, [body.index(a) for a in names]


class NavModel:
    r"""Typed context handed to every item's ``compile``: the unknowns and their maps.

    Parameters
    ----------
    data : ImuData
    error_model : ErrorModel, optional
        Contributes the parameter columns ``G`` (acceleration per unit parameter).

    Notes
    -----
    Per axis ``a`` the hard FEM constraint is

    .. math:: K r_a + e_1 v_{0,a} - e_N v_{1,a} + M (\hat a_a + G_a l + w_a) = 0,

    i.e. the 2010 paper's ``K r = f(\hat a) + F l + f(w)`` with ``f(a) = -M a`` and
    ``F = -M G``. The corrected acceleration is ``a_c = \hat a + G l + w``.

    Examples
    --------
    Five samples on one axis: the unknowns are five positions, five acceleration residuals and
    the two end velocities; the position at 0.5 s is the middle node's unknown:

    >>> import numpy as np
    >>> import bvpnav
    >>> model = bvpnav.NavModel(bvpnav.ImuData(t=np.linspace(0.0, 1.0, 5), acc=np.zeros(5)))
    >>> model.N, model.d, model.size
    (5, 1, 12)
    >>> row = model.position([0.5])
    >>> row.A.toarray().nonzero()[1].tolist(), row.c.tolist()
    ([2], [0.0])
    """

    def __init__(self, data: ImuData, error_model=None):
        self.data = data
        self.grid = data.grid
        self.axes = data.axes
        self.error_model = error_model
        n, d = self.grid.n, data.ndim
        self.N = n
        self.d = d
        self.block = 2 * n + 2
        if error_model is not None:
            G = np.asarray(error_model.columns(data), dtype=float)
            if G.shape[:2] != (n, d):
                raise InputError(
                    f"error model {error_model!r}: columns of shape {G.shape}, expected ({n}, {d}, q)"
                )
            self.param_names = tuple(error_model.names(data))
        else:
            G = np.zeros((n, d, 0))
            self.param_names = ()
        self.G = G
        self.q = G.shape[2]
        self.state_model = state_component(error_model)
        if self.state_model is not None:
            self.ns = int(self.state_model.state_size(data))
            Gs = [as_csr(g) for g in self.state_model.state_columns(data)]
            if len(Gs) != d or any(g.shape != (n, self.ns) for g in Gs):
                raise InputError(f"error model {self.state_model!r}: state columns must be {d} sparse "
                                 f"matrices of shape ({n}, {self.ns}), one per axis")
            self.Gs = Gs
        else:
            self.ns, self.Gs = 0, []
        self.size = d * self.block + self.q + self.ns
        self.K = fem.stiffness(self.grid)
        self.M = fem.mass(self.grid)

    @functools.cached_property
    def _node_vel(self) -> tuple:
        """:func:`bvpnav.fem.node_velocity_operators` of the grid, made on first use."""
        return fem.node_velocity_operators(self.grid)

    # --------------------------------------------------------------- layout
    def _offset(self, axis: int) -> int:
        return axis * self.block

    def r_index(self, axis: int) -> np.ndarray:
        """Indices of the nodal positions of axis ``axis`` in ``x``."""
        o = self._offset(axis)
        return np.arange(o, o + self.N)

    def w_index(self, axis: int) -> np.ndarray:
        """Indices of the acceleration residuals of axis ``axis`` in ``x``."""
        o = self._offset(axis) + self.N
        return np.arange(o, o + self.N)

    def v_end_index(self, axis: int) -> tuple[int, int]:
        """Indices of ``v0`` and ``v1`` of axis ``axis`` in ``x``."""
        o = self._offset(axis) + 2 * self.N
        return o, o + 1

    @property
    def l_index(self) -> np.ndarray:
        """Indices of the error-model parameters in ``x``."""
        return np.arange(self.d * self.block, self.d * self.block + self.q)

    @property
    def s_index(self) -> np.ndarray:
        """Indices of the error model's node states in ``x`` (empty without them)."""
        return np.arange(self.d * self.block + self.q, self.size)

    @property
    def node_samples(self) -> np.ndarray:
        """The sample index of every node (all samples; a coarse mesh keeps some,
        :class:`bvpnav.mesh.MeshModel`)."""
        return np.arange(self.N)

    def element_index(self, axis: int) -> np.ndarray:
        """Indices in ``x`` of the condensed element residuals of one axis (none here; see
        :class:`bvpnav.mesh.MeshModel`), after ``v0, v1`` in the axis' block."""
        return np.zeros(0, dtype=np.int64)

    def element_nodes(self) -> np.ndarray:
        """The node each element residual of an axis sits at (for banded orderings)."""
        return np.zeros(0, dtype=np.int64)

    def residual_sigma(self, sigma_a: np.ndarray) -> np.ndarray:
        """The standard deviation of every row of :meth:`residual_rows` (m/s^2), from
        ``sigma_a`` per axis (d,) or per sample and axis (N, d): axis-major."""
        sa = np.asarray(sigma_a, dtype=float)
        return sa.T.ravel() if sa.ndim == 2 else np.repeat(sa, self.N)

    def state_nodes(self) -> np.ndarray:
        """Time node (sample index) of every node state, (ns,) int."""
        if not self.ns:
            return np.zeros(0, dtype=np.int64)
        return np.asarray(self.state_model.state_nodes(self.data), dtype=np.int64)

    def states(self, kind: str, t=None, axes=None, what: str | None = None) -> Affine:
        r"""The error model's node state ``kind`` (e.g. ``"attitude_error"``, rad;
        ``"gyro_bias"``, rad/s; ``"acc_bias"``, m/s^2) at times ``t`` as rows affine in
        the unknowns: its current total plus the state increment, linear between nodes.
        Rows ordered time-major, then axis (``axes`` among ``x, y, z``; default all).

        Raises :class:`InputError` naming the fix when the error model has no such state.
        """
        what = what or kind.replace("_", " ")
        sm = self.state_model
        kinds = [] if sm is None else sm.state_kinds(self.data)
        if kind not in kinds:
            raise InputError(f"{what}: the error model has no {kind!r} node state (it has {kinds}); "
                             "add bvpnav.error_models.ErrorStates(...) with that state to the error model")
        names, ax = _body_axes(axes, what, "axes")
        times = self.grid.t if t is None else as_times(t, what)
        P = sp.identity(self.N, format="csr") if t is None else self.grid.interpolation_matrix(times, what)
        cols = np.asarray(sm.state_index(self.data, kind), dtype=np.int64)   # (N, 3)
        total = np.asarray(sm.state_total(self.data, kind), dtype=float)     # (N, 3)
        parts = []
        for a in ax:
            S = sp.csr_matrix((np.ones(self.N), (np.arange(self.N), self.s_index[cols[:, a]])),
                              shape=(self.N, self.size))
            parts.append(Affine(P @ S, P @ total[:, a]))
        out = self._interleave(parts, times.size)
        return Affine(out.A, out.c, TimeLabels(f"{kind}_", list(names), times))

    def attitude_error(self, t=None, axes=None) -> Affine:
        """The navigation-frame attitude error (rad) at times ``t`` (see :meth:`states`)."""
        return self.states("attitude_error", t, axes, "attitude error")

    def acc_bias(self, t=None, axes=None) -> Affine:
        """The accelerometer bias (body axes, m/s^2) at times ``t`` (see :meth:`states`)."""
        return self.states("acc_bias", t, axes, "accelerometer bias")

    def gyro_bias(self, t=None, axes=None) -> Affine:
        """The gyro bias (body axes, rad/s) at times ``t`` (see :meth:`states`)."""
        return self.states("gyro_bias", t, axes, "gyro bias")

    def _placed(self, blocks: dict[str, sp.spmatrix], axis: int) -> list:
        """Per-axis blocks (keys r, w, vb, l) with the first column of ``x`` each multiplies:
        ``[(block, column)]`` in increasing column order (:func:`rows_side_by_side`)."""
        o = self._offset(axis)
        starts = (("r", o), ("w", o + self.N), ("vb", o + 2 * self.N), ("u", o + 2 * self.N + 2),
                  ("l", self.d * self.block), ("s", self.d * self.block + self.q))
        return [(blocks[key], start) for key, start in starts
                if key in blocks and (key != "l" or self.q) and (key != "s" or self.ns)]

    def _place(self, blocks: dict[str, sp.spmatrix], axis: int) -> sp.csr_matrix:
        """Assemble per-axis blocks (keys r, w, vb, l) into rows over the whole ``x``, each
        entry written once into the result (:func:`rows_side_by_side`)."""
        return rows_side_by_side([self._placed(blocks, axis)], self.size)

    def axes_of(self, axes, what: str = "axes") -> tuple[int, ...]:
        """Axis indices for a name, a sequence of names, or ``None`` (all)."""
        return self.data.axis_index(axes, what)

    # ----------------------------------------------------------- FEM rows
    def fem_rows(self) -> Affine:
        """The hard FEM equations ``K r + B v + M (a_hat + G l + w) = 0`` for all axes (m/s)."""
        if getattr(self, "_fem_cache", None) is None:
            self._fem_cache = self._fem_rows()
        return self._fem_cache

    def with_acc(self, acc: np.ndarray) -> NavModel:
        """The same model (grid, K, M, error-model columns) for other measured
        accelerations ``acc`` (N, d), m/s^2; used to differentiate with respect to the data."""
        import copy

        other = copy.copy(self)
        other.data = copy.copy(self.data)
        other.data.acc = np.asarray(acc, dtype=float)
        other._fem_cache = None
        return other

    def fem_blocks(self, axis: int) -> dict:
        """The blocks of one axis' FEM rows by the unknowns they multiply: ``r`` (K, 1/s),
        ``w`` (M, s), ``vb`` (the end velocities' columns) and, with error-model
        parameters, ``l`` (``M G``, dense (N, q), s); :meth:`fem_rows` places them."""
        blocks = {"r": self.K, "w": self.M, "vb": self._boundary_columns()}
        if self.q:
            blocks["l"] = columns_csr(*self.mg_columns(axis), self.q)
        if self.ns:
            blocks["s"] = self.ms_columns(axis)
        return blocks

    def _boundary_columns(self) -> sp.csr_matrix:
        """The end velocities' columns of one axis' FEM rows (:func:`bvpnav.fem.boundary_columns`)."""
        return fem.boundary_columns(self.grid)

    def ms_columns(self, axis: int) -> sp.csr_matrix:
        """``M G_s`` of one axis (s): the node states' columns of the FEM rows, sparse and
        local (a state of node ``j`` reaches rows ``j - 1 .. j + 1``); made once per axis."""
        cache = self.__dict__.setdefault("_ms_cache", {})
        if axis not in cache:
            cache[axis] = canonical_csr(self.M @ self.Gs[axis])
        return cache[axis]

    def mg_columns(self, axis: int) -> tuple[np.ndarray, np.ndarray]:
        """``M G`` of one axis (s) by the parameters acting on it: ``(cols, vals)``, the
        columns of ``G`` not all zero and their products (N, cols.size).

        Notes
        -----
        It depends on the grid and the error model only (not on the accelerations, so
        :meth:`with_acc`'s copies share it): made once per axis, read by :meth:`fem_blocks`,
        :func:`bvpnav.linalg.lsq.fem_rows_by_diagonals` and the observability check. The other
        columns, zero, are neither multiplied nor stored (three axes with six parameters at
        N = 1e6: a dense (N, q) product per axis was 48 MB, two thirds of it zeros).
        """
        cache = self.__dict__.setdefault("_mg_cache", {})
        if axis not in cache:
            cache[axis] = self._times_g(self.M, axis)
        return cache[axis]

    def _times_g(self, V: sp.spmatrix, axis: int) -> tuple[np.ndarray, np.ndarray]:
        """``V G`` of one axis by the columns of ``G`` not all zero: ``(cols, vals)``."""
        G = self.G[:, axis, :]
        cols = np.flatnonzero(np.any(G != 0, axis=0))
        return cols, np.asarray(V @ np.ascontiguousarray(G[:, cols]))

    def _fem_rows(self, below: Sequence[Affine] = ()) -> Affine:
        # every axis' rows written into one matrix (no per-axis matrix and stacked copy),
        # and the rows ``below`` after them
        if self.ns and not self.q:
            # node states: their columns come last; the other blocks (the same at every
            # Gauss-Newton point) are placed once and the states' columns appended to their rows
            A = rows_with_tail(self._fem_fixed_rows(), [self.ms_columns(a) for a in range(self.d)],
                               int(self.s_index[0]), [p.A for p in below])
        else:
            groups = [self._placed(self.fem_blocks(a), a) for a in range(self.d)]
            A = rows_side_by_side(groups + [[(p.A, 0)] for p in below], self.size)
        c = np.concatenate([self._acc_load(a) for a in range(self.d)] + [p.c for p in below])
        return Affine(A, c, Affine.stacked_labels([self._fem_labels(), *(p.labels for p in below)]))

    def _kept_constants(self) -> dict:
        """Rows that depend on the grid alone, made once (a coarse mesh shares them between the
        node-state loop's models)."""
        return self.__dict__.setdefault("_grid_constants", {})

    def _fem_fixed_rows(self) -> sp.csr_matrix:
        """The FEM rows of every axis without the node states' columns (they depend on the grid
        and the mesh alone: made once, :meth:`_kept_constants`)."""
        kept = self._kept_constants()
        key = ("fem_fixed", self.size)
        if key not in kept:
            groups = [[(b, c) for b, c in self._placed(self.fem_blocks(a), a) if c < int(self.s_index[0])]
                      for a in range(self.d)]
            kept[key] = rows_side_by_side(groups, self.size)
        return kept[key]

    def _acc_load(self, axis: int) -> np.ndarray:
        """``M a_hat`` of one axis (m/s): the measured accelerations' part of the FEM rows."""
        return self.M @ self.data.acc[:, axis]

    def _fem_labels(self) -> RowLabels:
        """The FEM rows' labels, ``fem_x[j]`` axis by axis."""
        return RowLabels([(f"fem_{self.axes[a]}", self.N) for a in range(self.d)])

    def fem_rows_and(self, below: Sequence[Affine]) -> Affine:
        """:meth:`fem_rows` with the rows ``below`` (maps of the stacked unknowns, canonical)
        after them, as one map whose matrix is written once; :meth:`fem_rows` is then a view
        of its first rows (its arrays' prefixes), not a second copy.

        Notes
        -----
        The equality rows of :func:`bvpnav.linalg.lsq.least_squares_form`: stacking the FEM rows
        and a few items' rows copied every FEM entry (three axes with six parameters at
        N = 1e6: 288 MB of fresh memory). With the FEM rows already made, they are stacked.
        """
        below = list(below)
        if getattr(self, "_fem_cache", None) is not None or not below:
            return Affine.vstack([self.fem_rows(), *below])
        out = self._fem_rows(below)
        p = self.N * self.d
        A, end = out.A, int(out.A.indptr[p])
        fem = sp.csr_matrix((A.data[:end], A.indices[:end], A.indptr[:p + 1]), shape=(p, A.shape[1]))
        fem.has_canonical_format = A.has_canonical_format
        self._fem_cache = Affine(fem, out.c[:p], self._fem_labels())
        return out

    def residual_rows(self, axes=None) -> Affine:
        """The acceleration residuals ``w`` (m/s^2), axis-major."""
        parts = []
        for a in self.axes_of(axes):
            # one entry per row: the CSR arrays directly (no COO conversion and its sort)
            cols = np.asarray(self.w_index(a), dtype=np.int32 if self.size < 2**31 else np.int64)
            A = sp.csr_matrix((np.ones(self.N), cols, np.arange(self.N + 1, dtype=cols.dtype)),
                              shape=(self.N, self.size))
            A.has_canonical_format = True
            parts.append(Affine(A, np.zeros(self.N)))
        return Affine.vstack(parts)

    def load_residual_rows(self, axes=None) -> Affine:
        """The load residuals ``K r + B v - f(a_hat) - F l = -M w`` (m/s), axis-major."""
        parts = []
        for a in self.axes_of(axes):
            A = self._place({"w": -self.M}, a)
            parts.append(Affine(A, np.zeros(self.N)))
        return Affine.vstack(parts)

    # ------------------------------------------------- evaluation at times
    def _labels(self, quantity: str, times: np.ndarray, axes: tuple[int, ...]) -> TimeLabels:
        return TimeLabels(quantity, [self.axes[a] for a in axes], times)

    def _interleave(self, per_axis: list[Affine], m: int) -> Affine:
        """Stack per-axis blocks of m rows so that row ``k * nax + a`` is time k, axis a."""
        stacked = Affine.vstack(per_axis)
        nax = len(per_axis)
        if nax == 1:   # already in that order
            return stacked
        order = (np.arange(nax)[None, :] * m + np.arange(m)[:, None]).ravel()
        return Affine(stacked.A[order], stacked.c[order])

    def position(self, t, axes=None, what: str = "position") -> Affine:
        r"""Positions at times ``t`` (m): rows ordered time-major, then axis.

        Notes
        -----
        The FEM position is piecewise linear: :math:`r(t) = \sum_j r_j \phi_j(t)`.
        """
        times = as_times(t, what)
        ax = self.axes_of(axes, what)
        P = self.grid.interpolation_matrix(times, what)
        parts = [Affine(self._place({"r": P}, a), np.zeros(times.size)) for a in ax]
        out = self._interleave(parts, times.size)
        return Affine(out.A, out.c, self._labels("", times, ax))

    def velocity(self, t, axes=None, what: str = "velocity") -> Affine:
        """Velocities at times ``t`` (m/s): rows ordered time-major, then axis.

        Notes
        -----
        At a node, :math:`v_j = (r_j - r_{j-1})/h_{j-1} + h_{j-1}(a_{j-1} + 2 a_j)/6` with
        the corrected acceleration ``a = a_hat + G l + w``; ``v_0``/``v_1`` at the ends;
        between nodes the linear acceleration is integrated exactly (see
        :func:`bvpnav.fem.velocity_operators`). Second order in h.
        """
        times = as_times(t, what)
        ax = self.axes_of(axes, what)
        Vr, Va, Vb = fem.velocity_operators(self.grid, times, what)
        parts = []
        for a in ax:
            blocks = {"r": Vr, "w": Va, "vb": Vb}
            if self.q:
                blocks["l"] = columns_csr(*self._times_g(Va, a), self.q)
            if self.ns:
                blocks["s"] = canonical_csr(Va @ self.Gs[a])
            parts.append(Affine(self._place(blocks, a), Va @ self.data.acc[:, a]))
        out = self._interleave(parts, times.size)
        return Affine(out.A, out.c, self._labels("v", times, ax))

    @property
    def sample_grid(self):
        """The grid of every sample (the data's): the unknowns' own grid here; a coarse mesh
        (:class:`bvpnav.mesh.MeshModel`) keeps its nodes in :attr:`grid` and the samples here.
        Per-sample arrays (attitude, rates) are interpolated on it."""
        return self.grid

    def sample_velocity(self, t, axes=None, what: str = "velocity") -> Affine:
        """Velocities at times ``t`` (m/s) for the body-frame rows: :meth:`velocity` here; on a
        coarse mesh also at the samples inside its elements
        (:meth:`bvpnav.mesh.MeshModel.sample_velocity`)."""
        return self.velocity(t, axes, what)

    def _point_velocity(self, times: np.ndarray, point: LinearizationPoint, what: str) -> np.ndarray:
        """The linearization point's navigation velocity at ``times`` (K, 3), m/s: given at every
        sample (:meth:`point_velocities`), linear in between."""
        return self.sample_grid.interpolation_matrix(times, what) @ point.velocity

    @functools.cached_property
    def _rate_columns(self) -> np.ndarray:
        """Change of the corrected body rates per unit parameter on all of the model's
        parameters, (N, 3, q), rad/s per unit (zero for parameters without rate columns); made
        once per model, for every stance item that asks."""
        W = np.zeros((self.data.n, 3, self.q))
        for comp in getattr(self.error_model, "components", (self.error_model,)):
            if comp is None or not hasattr(comp, "rate_columns"):
                continue
            idx = [self.param_names.index(n) for n in comp.names(self.data)]
            W[:, :, idx] += np.asarray(comp.rate_columns(self.data), dtype=float)
        return W

    def body_rate(self, t, axes=None, what: str = "body rate") -> Affine:
        r"""The corrected gyro rates in the body frame at times ``t`` (rad/s), affine in the
        gyro error models' parameters: rows ordered time-major, then body axis.

        Parameters
        ----------
        t : array_like of float
            Times, s, inside the window (between samples the rates are linear).
        axes : str or sequence of str, optional
            Body axes among ``"x", "y", "z"`` (default all three).
        what : str
            What asks (for error messages).

        Notes
        -----
        :math:`\omega(t) = \sum_i \phi_i(t) \left(\omega_i + \sum_p \partial\omega_i/\partial
        l_p \; \delta l_p \right)`, with :math:`\omega_i` the rates corrected by the current
        totals of the attitude error models (the measured rates when there are none) and
        :math:`\partial\omega_i/\partial l_p` their ``rate_columns``: the gyro bias enters as
        :math:`\omega = \hat\omega - b`. An error model without rate columns contributes
        nothing, so without a gyro error model the rows are constant. With a node-state gyro
        bias (:class:`~bvpnav.error_models.ErrorStates`) its rows :meth:`gyro_bias` are
        subtracted.
        """
        times = as_times(t, what)
        point = getattr(self.data, "attitude_point", None)
        rates = point.rates if point is not None else getattr(self.data, "gyro", None)
        if rates is None:
            raise InputError(f"{what}: needs the gyro rates; build the data with bvpnav.ImuData.from_gyro "
                             "(or a reader given a gyro column)")
        names, ax = _body_axes(axes, what)
        P = self.sample_grid.interpolation_matrix(times, what)
        W = self._rate_columns
        L = self.params().A
        empty = sp.csr_matrix((times.size, self.size))
        parts = [Affine(sp.csr_matrix(P @ W[:, a, :]) @ L if self.q else empty,
                        P @ np.asarray(rates, dtype=float)[:, a]) for a in ax]
        out = self._interleave(parts, times.size)
        if self.ns and "gyro_bias" in self.state_model.state_kinds(self.data):
            out = out - self.gyro_bias(times, names)   # node states: omega = omega_hat - b_g(t)
        return Affine(out.A, out.c, TimeLabels("omega_", list(names), times))

    def _attitude_columns(self) -> np.ndarray | None:
        """Navigation-frame attitude change per unit parameter on the model's parameters, (n, 3,
        q) at every sample (:attr:`sample_grid`), rad per unit, from the data's
        :class:`LinearizationPoint` (None without one)."""
        point = getattr(self.data, "body_point", None)
        if point is None or not self.q:
            return None
        Psi = np.zeros((self.data.n, 3, self.q))
        for k, name in enumerate(point.names):
            if name in self.param_names:
                Psi[:, :, self.param_names.index(name)] = point.psi[:, :, k]
        return Psi

    def body_velocity(self, t, axes=None, lever=(0.0, 0.0, 0.0), what: str = "body velocity") -> Affine:
        r"""The velocity of a point of the body in body axes at times ``t`` (m/s), affine in the
        unknowns: rows ordered time-major, then body axis.

        Parameters
        ----------
        t : array_like of float
            Times, s, inside the window.
        axes : str or sequence of str, optional
            Body axes among ``"x", "y", "z"`` (default all three).
        lever : array_like (3,)
            The point, m, in body axes from the IMU (the origin of the navigation solution).
        what : str
            What asks (for error messages).

        Notes
        -----
        .. math:: v_b(t) = C(t)^T v_n(t) + \omega(t) \times \ell
                  + C(t)^T [v_n^0(t)\times]\,\psi(t) - [\ell\times]\,\delta\omega(t),

        with :math:`C` the body-to-navigation attitude of the data (the current attitude
        point of the attitude loop; between samples by spherical interpolation),
        :math:`v_n` the FEM velocity (:meth:`velocity`), :math:`\omega` the corrected body
        rates (:meth:`body_rate`, needed when :math:`\ell \ne 0`) and :math:`\ell` the lever.
        The last two terms are the first-order effect of the increments of the attitude
        error models: a navigation-frame attitude change :math:`\psi = \Psi\,\delta l`
        (:math:`C \to \exp([\psi\times]) C`, so :math:`C^T v \to C^T v - C^T(\psi\times v)`)
        taken about the velocity :math:`v_n^0` of the loop's last evaluation, both from the
        data's :class:`LinearizationPoint` (``data.body_point``, set by
        :mod:`bvpnav.solve.attitude`, which knows the attitude error models; without one the
        term is left out, and the rows are exact at zero increments either way), and the rate
        change :math:`\delta\omega` of the gyro models. With node states
        (:class:`~bvpnav.error_models.ErrorStates`) the attitude change is the state increment
        of :meth:`attitude_error` at the instants, about the velocity of the node-state loop's
        last step. The outer loop re-integrates and re-linearizes, so at its answer the rows
        are exact.
        """
        data = self.data
        if not getattr(data, "is_strapdown", False) or getattr(data, "attitude", None) is None:
            raise InputError(f"{what}: needs strapdown data with an attitude (body-frame velocities); build "
                             "the data with bvpnav.ImuData.from_gyro (specific force and gyro rates)")
        if self.d != 3:
            raise InputError(f"{what}: needs the three navigation axes; the data has {list(self.axes)}")
        names, jb = _body_axes(axes, what)
        try:
            ell = np.asarray(lever, dtype=float).reshape(3)
        except (TypeError, ValueError):
            raise InputError(f"{what}: lever={lever!r}; give the point as three body-frame coordinates in m, "
                             "e.g. lever=(-1.4, 0.0, -0.3)") from None
        if not np.all(np.isfinite(ell)):
            raise InputError(f"{what}: lever={lever!r} must be finite (m)")
        times = as_times(t, what)
        jb = np.array(jb)
        K, nb = times.size, jb.size
        C = self._attitude_at(times, what)                       # (K, 3, 3) body to navigation
        V = self.sample_velocity(times, None, what)              # rows k * 3 + a
        Ct = np.swapaxes(C, 1, 2)[:, jb, :]                      # (K, nb, 3): rows of C^T
        rows = np.repeat(np.arange(K * nb), 3)
        cols = (np.arange(K)[:, None, None] * 3 + np.arange(3)[None, None, :]).repeat(nb, axis=1).ravel()
        R = sp.csr_matrix((Ct.ravel(), (rows, cols)), shape=(K * nb, 3 * K))
        A, c = R @ V.A, R @ V.c
        if np.any(ell):
            point = getattr(data, "attitude_point", None)
            rates = point.rates if point is not None else getattr(data, "gyro", None)
            if rates is None:
                raise InputError(f"{what}: a lever of {ell.tolist()} m needs the gyro rates (omega x lever); "
                                 "build the data with bvpnav.ImuData.from_gyro")
            # omega x l = -[l x] omega, with the corrected rates of body_rate (affine in the gyro
            # models' parameters or node states)
            Lx = -np.array([[0.0, -ell[2], ell[1]], [ell[2], 0.0, -ell[0]], [-ell[1], ell[0], 0.0]])[jb]
            Wl = sp.kron(sp.identity(K), sp.csr_matrix(Lx), format="csr")
            rate = self.body_rate(times, None, what)
            A, c = A + Wl @ rate.A, c + Wl @ rate.c
        point = getattr(data, "body_point", None)
        if point is not None:   # the attitude increments at the instants: C^T [v0 x] psi(t)
            v0 = self._point_velocity(times, point, what)
            turn = self._attitude_rows(times, np.einsum("kbn,knm->kbm", Ct, _skew(v0)), what)
            if turn is not None:
                A = A + turn
        return Affine(A, c, TimeLabels("vb_", list(names), times))

    def _attitude_rows(self, times: np.ndarray, M: np.ndarray, what: str) -> sp.csr_matrix | None:
        r"""The rows :math:`M_k\,\psi(t_k)` ((K * r, size)) of per-time maps ``M`` (K, r, 3) of the
        attitude increments :math:`\psi` about the loop's :class:`LinearizationPoint`: the
        attitude parameters' columns (:meth:`_attitude_columns`) and the node states' attitude
        error (:meth:`attitude_error`), or None when the model has neither."""
        K, r = M.shape[0], M.shape[1]
        out = None
        Psi = self._attitude_columns()
        if Psi is not None and np.any(Psi):
            P = self.sample_grid.interpolation_matrix(times, what)
            psi = np.stack([P @ Psi[:, a, :] for a in range(3)], axis=1)           # (K, 3, q)
            L = np.einsum("kbn,knq->kbq", M, psi)
            if np.any(L):
                out = sp.csr_matrix(L.reshape(K * r, self.q)) @ self.params().A
        if self.ns and "attitude_error" in self.state_model.state_kinds(self.data):
            cols = (np.arange(K)[:, None, None] * 3 + np.arange(3)[None, None, :]).repeat(r, axis=1).ravel()
            B = sp.csr_matrix((M.ravel(), (np.repeat(np.arange(K * r), 3), cols)), shape=(K * r, 3 * K))
            term = B @ self.attitude_error(times).A
            out = term if out is None else out + term
        return None if out is None else sp.csr_matrix(out)

    def _attitude_at(self, times: np.ndarray, what: str) -> np.ndarray:
        """The data's body-to-navigation attitude matrices at ``times`` (K, 3, 3): the samples'
        where a time is a sample, spherical interpolation between them."""
        from scipy.spatial.transform import Slerp

        att = self.data.attitude
        grid = self.sample_grid
        times = grid.check_inside(times, what)
        t = grid.t
        k = np.clip(np.searchsorted(t, times), 0, t.size - 1)
        on = np.isclose(t[k], times, rtol=0.0, atol=1e-12 * max(1.0, float(np.max(np.abs(t)))))
        out = np.empty((times.size, 3, 3))
        if np.any(on):
            out[on] = att[k[on]].as_matrix()
        if not np.all(on):
            out[~on] = Slerp(t, att)(times[~on]).as_matrix()
        return out

    def speed_gain(self, what: str = "speed gain") -> Affine:
        r"""The factor that turns a measured speed into a true one, one row (dimensionless).

        The :class:`~bvpnav.error_models.OdometerScale` component of the error model gives
        :math:`1 + e` with its internal parameter :math:`e = 1/(1 + k) - 1` (``k`` the
        odometer's scale-factor error); without one the factor is the constant 1 (a
        calibrated odometer).
        """
        comps = [c for c in getattr(self.error_model, "components", (self.error_model,))
                 if c is not None and hasattr(c, "speed_gain")]
        if len(comps) > 1:
            raise InputError(f"{what}: the error model has {len(comps)} odometer scale models; give one")
        if not comps:
            return Affine(sp.csr_matrix((1, self.size)), np.ones(1), ("gain",))
        return comps[0].speed_gain(self)

    # ------------------------------------------------ GNSS antenna and clock
    def _provided(self, role: str, what: str, fix: str) -> list[str]:
        """Names of the parameters of the error-model component that declares ``provides ==
        role`` (:class:`~bvpnav.error_models.LeverArm`, :class:`~bvpnav.error_models.TimeOffset`),
        or :class:`InputError` naming ``what`` and the fix."""
        for comp in getattr(self.error_model, "components", (self.error_model,)):
            if comp is not None and getattr(type(comp), "provides", None) == role:
                return list(comp.names(self.data))
        raise InputError(f"{what}: needs the error model {fix} (it holds the unknown); add it, e.g. "
                         f"NavigationProblem(data, error_model=... + {fix}), or give the value as known")

    def antenna_offset(self, t, lever, axes=None, *, rate: bool = False, what: str = "lever arm") -> Affine:
        r"""Where the antenna is relative to the IMU, in the navigation frame: :math:`C(t)\,l`
        (m) or, with ``rate``, its velocity :math:`C(t)\,(\omega(t) \times l)` (m/s); rows
        time-major, then axis.

        Parameters
        ----------
        t : array_like of float
            Times, s, inside the window.
        lever : array_like of 3 floats or ``"estimated"``
            The lever arm in the body frame, m (known), or ``"estimated"``: the parameters
            of the :class:`~bvpnav.error_models.LeverArm` error model (affine in them).
        axes : str or sequence of str, optional
            Navigation axes (default all).
        rate : bool
            The antenna's velocity relative to the IMU instead of its offset.
        what : str
            What asks (for error messages).

        Notes
        -----
        :math:`C(t)` is the current attitude (the data's, or the attitude loop's estimate:
        the rows are linear in :math:`l` for a given attitude and re-made at every step of
        the loop); :math:`\omega(t)` the current corrected body rates, linear between samples.
        With the attitude loop's :class:`LinearizationPoint` (``data.body_point``) the rows
        also carry the first-order effect of the attitude increments :math:`\psi`
        (:math:`C \to \exp([\psi\times]) C`):

        .. math:: C\,\ell \to C\,\ell - [(C\,\hat\ell)\times]\,\psi ,

        with :math:`\ell = l` or :math:`\omega \times l` and :math:`\hat\ell` at the known
        lever arm or the point's estimate (``body_point.lever``), :math:`\psi` the attitude
        parameters' columns or the node states' attitude error, as in :meth:`body_velocity`;
        so the loop sees that a heading change moves the antenna. (The change of
        :math:`\omega` by the gyro models is left out of the velocity rows.)
        """
        times = as_times(t, what)
        ax = self.axes_of(axes, what)
        if not self.data.is_strapdown or self.d != 3:
            raise InputError(f"{what}: a lever arm is in the body frame and needs the attitude; this data is "
                             f"navigation-frame with axes {list(self.axes)} (no attitude). Build the data "
                             "with bvpnav.ImuData.from_gyro (or with attitude=), or drop lever=")
        R = self._attitude_at(times, what)
        if rate:
            point = getattr(self.data, "attitude_point", None)
            rates = point.rates if point is not None else getattr(self.data, "gyro", None)
            if rates is None:
                raise InputError(f"{what}: the antenna's velocity needs the gyro rates; build the data with "
                                 "bvpnav.ImuData.from_gyro")
            P = self.sample_grid.interpolation_matrix(times, what)
            w = P @ np.asarray(rates, dtype=float)
            skew = np.zeros((times.size, 3, 3))
            skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
            skew[:, 1, 0], skew[:, 2, 0], skew[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
            R = R @ skew
        turn = self._antenna_turn(times, R, lever, ax, what)     # the attitude increments' term
        R = R[:, list(ax), :]                                   # (K, nax, 3): rows per time and axis
        labels = TimeLabels("lever_" if not rate else "lever_v", [self.axes[a] for a in ax], times)
        if isinstance(lever, str):
            idx = self.l_index[[self.param_names.index(n) for n in self._provided("lever_arm", what,
                                                                                   "LeverArm(sigma=...)")]]
            A = sp.csr_matrix((R.ravel(), (np.repeat(np.arange(R.shape[0] * R.shape[1]), 3),
                                           np.tile(idx, R.shape[0] * R.shape[1]))),
                              shape=(R.shape[0] * R.shape[1], self.size))
            return Affine(A if turn is None else A + turn, np.zeros(A.shape[0]), labels)
        lv = np.asarray(lever, dtype=float).reshape(3)
        A = sp.csr_matrix((R.shape[0] * R.shape[1], self.size)) if turn is None else turn
        return Affine(A, (R @ lv).ravel(), labels)

    def _antenna_turn(self, times: np.ndarray, R: np.ndarray, lever, ax, what: str) -> sp.csr_matrix | None:
        r"""The rows :math:`-[(R\hat l)\times]\,\psi(t)` of :meth:`antenna_offset` on the navigation
        axes ``ax`` ((K * len(ax), size)), or None without a linearization point or a lever arm
        to linearize about."""
        point = getattr(self.data, "body_point", None)
        if point is None:
            return None
        if isinstance(lever, str):
            if point.lever is None:
                return None
            lv = np.asarray(point.lever, dtype=float).reshape(3)
        else:
            lv = np.asarray(lever, dtype=float).reshape(3)
        if not np.any(lv):
            return None
        return self._attitude_rows(times, -_skew(np.einsum("kij,j->ki", R, lv))[:, list(ax), :], what)

    def time_offset(self, what: str = "time offset") -> Affine:
        """The delay of the GNSS fixes against the IMU clock as one row (s): the parameter of
        the :class:`~bvpnav.error_models.TimeOffset` error model, or :class:`InputError`
        naming ``what`` when the problem has none."""
        return self.params(self._provided("time_offset", what, "TimeOffset(sigma=...)"))

    def _looped(self) -> bool:
        """Whether an outer loop re-linearizes the body-frame rows (attitude error models, node
        states with an attitude error, or the loop's data)."""
        comps = [c for c in getattr(self.error_model, "components", (self.error_model,)) if c is not None]
        return (any(hasattr(c, "rate_columns") or hasattr(c, "initial_columns") for c in comps)
                or getattr(self.data, "attitude_point", None) is not None        # the loop's data
                or getattr(self.data, "body_point", None) is not None
                or (self.ns and "attitude_error" in self.state_model.state_kinds(self.data)))

    def mounting_velocity(self, t, axes, lever=(0.0, 0.0, 0.0), what: str = "mounting") -> Affine:
        r"""The change of the lateral and vertical body velocity rows of a vehicle item made by
        the IMU's mounting (:class:`~bvpnav.error_models.Mounting`), m/s; rows time-major, then
        axis, to be added to :meth:`body_velocity`'s rows of the same ``t`` and ``axes``.

        Parameters
        ----------
        t : array_like of float
            Times, s, inside the window.
        axes : str or sequence of str
            Body axes among ``"y"`` and ``"z"`` (the forward axis carries no mounting term).
        lever : array_like (3,) or None
            The point where the rows hold, m, body axes from the IMU; ``None`` for a point the
            error model estimates (:class:`~bvpnav.error_models.NhcLever`), whose forward speed
            is then taken as the IMU's (see Notes).
        what : str
            What asks (for error messages).

        Notes
        -----
        With the slopes :math:`(s_y, s_z)` of the mounting the rows are
        :math:`-s_y\, v^0_x(t)` (axis y) and :math:`+s_z\, v^0_x(t)` (axis z), so that
        :math:`v_y - s_y v_x = 0` and :math:`v_z + s_z v_x = 0` say the point moves along the
        vehicle's forward axis :math:`(1, s_y, -s_z)`. :math:`v^0_x = e_x^T (C^T v^0 + \omega
        \times \ell)` is the forward body velocity of the point :math:`\ell` at the loop's
        linearization point (``data.body_point``, set by the attitude loop, as for
        :meth:`body_velocity`'s attitude terms; the rates :math:`\omega` as in
        :meth:`vehicle_point_velocity`), so the rows are exact at the loop's answer. With the
        point estimated, :math:`(\omega \times \ell)_x = \omega_y \ell_z - \omega_z \ell_y` is
        left out: the rows are then exact only for a point on the body's x axis. Without a
        point (a loop's first solve) the rows are zero and the slopes stay at their prior for
        that solve; without an attitude loop at all (no attitude error model, no node states)
        nothing would iterate them, and this refuses.
        """
        names, jb = _body_axes(axes, what)
        if 0 in jb:
            raise InputError(f"{what}: mounting='estimated' acts on the lateral and vertical rows (axes 'y', "
                             f"'z'), not on {list(names)}; the forward speed changes by the misalignment's "
                             "cosine only (4e-5 at 0.5 deg)")
        idx = self.l_index[[self.param_names.index(n) for n in self._provided("mounting", what,
                                                                               "Mounting(sigma=...)")]]
        times, point = self._loop_point(t, what, "mounting", "give the data in vehicle axes (rotate the "
                                                             "IMU samples by the known mounting)")
        K, nb = times.size, len(jb)
        if point is None:
            return Affine(sp.csr_matrix((K * nb, self.size)), np.zeros(K * nb),
                          TimeLabels("mount_", list(names), times))
        vx = self._forward_speed(times, point, lever, what)
        sign = np.array([{1: -1.0, 2: 1.0}[j] for j in jb])
        col = np.array([idx[j - 1] for j in jb])
        A = sp.csr_matrix(((vx[:, None] * sign[None, :]).ravel(), (np.arange(K * nb), np.tile(col, K))),
                          shape=(K * nb, self.size))
        return Affine(A, np.zeros(K * nb), TimeLabels("mount_", list(names), times))

    def _loop_point(self, t, what: str, option: str, fix: str):
        """``(times, data.body_point)`` for rows linearized about the attitude loop's velocity
        (``option="estimated"``); refused, with ``fix``, when the problem has no loop."""
        if not self._looped():
            raise InputError(f"{what}: {option}='estimated' is linearized about the velocity of the attitude "
                             "loop, and this problem has none (no attitude error model, no node states); add "
                             f"one (e.g. AttitudeError(sigma=...) or GyroBias), or {fix}")
        return as_times(t, what), getattr(self.data, "body_point", None)

    def side_slip_velocity(self, t, axes, lever=(0.0, 0.0, 0.0), what: str = "side slip") -> Affine:
        r"""The side slip :math:`K f_y(t)\, v^0_x(t)` of the lateral rows of a vehicle item, m/s,
        with :math:`K` the parameter of the error model's :class:`~bvpnav.error_models.SideSlip`;
        rows time-major, then axis (zero but on ``"y"``), to be added to :meth:`body_velocity`'s
        rows of the same ``t`` and ``axes``.

        Parameters
        ----------
        t : array_like of float
            Times, s, inside the window.
        axes : str or sequence of str
            Body axes among ``"x", "y", "z"``.
        lever : array_like (3,) or None
            The point where the rows hold, m, body axes from the IMU; ``None`` for a point the
            error model estimates (:class:`~bvpnav.error_models.NhcLever`), whose forward speed
            is then taken as the IMU's (see Notes).
        what : str
            What asks (for error messages).

        Notes
        -----
        :math:`f_y` is the measured lateral specific force (linear between samples) and
        :math:`v^0_x = e_x^T (C^T v^0 + \omega \times \ell)` the forward body velocity of the
        point :math:`\ell` at the loop's linearization point (``data.body_point``; the rates
        :math:`\omega` as in :meth:`vehicle_point_velocity`), as in :meth:`mounting_velocity`:
        without a point (a loop's first solve) the rows are zero, so :math:`K` stays at its
        prior for that solve, and at the loop's answer the rows are exact. With the point
        estimated, :math:`(\omega \times \ell)_x = \omega_y \ell_z - \omega_z \ell_y` is left
        out: the rows are then exact only for a point on the body's x axis. The rows freeze
        :math:`v^0_x` and leave out :math:`K_0 f_y\, \delta v_x`: with hard rows the fixed
        point is exact; with soft rows it is the fixed point of the linearized rows, within
        about :math:`K f_y` (a few per cent) of the lateral residual of the bilinear least
        squares. Refused without an attitude loop (nothing would iterate them).
        """
        names, jb = _body_axes(axes, what)
        (col,) = self.l_index[[self.param_names.index(n) for n in self._provided("side_slip", what,
                                                                                  "SideSlip(sigma=...)")]]
        times, point = self._loop_point(t, what, "slip", "give the compliance as known (slip=K in s^2/m)")
        K, nb = times.size, len(jb)
        labels = TimeLabels("slip_", list(names), times)
        if point is None or 1 not in jb:
            return Affine(sp.csr_matrix((K * nb, self.size)), np.zeros(K * nb), labels)
        P = self.sample_grid.interpolation_matrix(times, what)
        vx = self._forward_speed(times, point, lever, what, P)
        fy = P @ np.asarray(self.data.specific_force)[:, 1]
        A = sp.csr_matrix((fy * vx, (np.arange(K) * nb + jb.index(1), np.full(K, col))),
                          shape=(K * nb, self.size))
        return Affine(A, np.zeros(K * nb), labels)

    def _forward_speed(self, times: np.ndarray, point, lever, what: str, P=None) -> np.ndarray:
        r"""The forward body speed (m/s) of the point ``lever`` (m, body axes; ``None``: the
        IMU's) at ``times`` about the loop's ``point``, :math:`e_x^T (C^T v^0 + \omega \times
        \ell)`. ``P``: the samples' interpolation matrix at ``times`` when the caller has it
        (made here for a point off the IMU otherwise)."""
        C = self._attitude_at(times, what)
        vx = np.einsum("kn,kn->k", C[:, :, 0], self._point_velocity(times, point, what))
        ell = np.zeros(3) if lever is None else np.asarray(lever, dtype=float).reshape(3)
        if np.any(ell):     # (omega x l)_x = w_y l_z - w_z l_y
            P = self.sample_grid.interpolation_matrix(times, what) if P is None else P
            w = P @ self._point_rates(what)
            vx = vx + w[:, 1] * ell[2] - w[:, 2] * ell[1]
        return vx

    def _point_rates(self, what: str) -> np.ndarray:
        """The body rates at every sample (N, 3), rad/s, at the loop's current point: corrected by
        the attitude loop's totals (``data.attitude_point``), less the node states' gyro-bias
        totals (``data.state_point``), else the measured rates."""
        point = getattr(self.data, "attitude_point", None)
        rates = point.rates if point is not None else getattr(self.data, "gyro", None)
        if rates is None:
            raise InputError(f"{what}: lever='estimated' needs the gyro rates (the point's velocity is "
                             "omega x lever); these data have an attitude but no rates: build them with "
                             "bvpnav.ImuData.from_gyro (or give a gyro column to the reader), or give the "
                             "lever as known")
        rates = np.asarray(rates, dtype=float)
        states = getattr(self.data, "state_point", None)
        if states is not None and "gyro_bias" in states.totals:
            rates = rates - states.totals["gyro_bias"]
        return rates

    def vehicle_point_velocity(self, t, axes, what: str = "vehicle point") -> Affine:
        r"""The velocity :math:`\omega \times \ell` of the vehicle's no-slip point relative to the
        IMU, in body axes (m/s), with the point :math:`\ell` the parameters of the error model's
        :class:`~bvpnav.error_models.NhcLever`; rows time-major, then axis, to be added to
        :meth:`body_velocity`'s rows (lever zero) of the same ``t`` and ``axes``.

        Parameters
        ----------
        t : array_like of float
            Times, s, inside the window.
        axes : str or sequence of str
            Body axes among ``"x", "y", "z"``.
        what : str
            What asks (for error messages).

        Notes
        -----
        .. math:: \omega \times \ell = [\omega\times]\,\ell ,

        linear in :math:`\ell` for the body rates :math:`\omega` at the current point: the
        rates corrected by the attitude loop's totals (``data.attitude_point``), less the node
        states' gyro-bias totals (``data.state_point``), else the measured rates; between
        samples linear. No attitude enters (the columns are :math:`C^T`-free). The product of
        the rates' increments in the same step and the offset is left out: at the loop's answer
        the increments are zero and the rows exact (0.1 mm/s for 1e-4 rad/s and 1 m on the way).
        """
        names, jb = _body_axes(axes, what)
        idx = self.l_index[[self.param_names.index(n) for n in self._provided("nhc_lever", what,
                                                                               "NhcLever(sigma=...)")]]
        rates = self._point_rates(what)
        times = as_times(t, what)
        K, nb = times.size, len(jb)
        w = self.sample_grid.interpolation_matrix(times, what) @ rates      # (K, 3)
        W = _skew(w)[:, jb, :]                                         # (K, nb, 3): rows of [omega x]
        A = sp.csr_matrix((W.ravel(), (np.repeat(np.arange(K * nb), 3), np.tile(idx, K * nb))),
                          shape=(K * nb, self.size))
        return Affine(A, np.zeros(K * nb), TimeLabels("point_", list(names), times))

    def node_velocity(self, axis: int) -> Affine:
        """Velocity at every node of one axis (m/s)."""
        Vr, Va, Vb = self._node_vel
        blocks = {"r": Vr, "w": Va, "vb": Vb}
        if self.q:
            blocks["l"] = columns_csr(*self._times_g(Va, axis), self.q)
        if self.ns:
            blocks["s"] = canonical_csr(Va @ self.Gs[axis])
        return Affine(self._place(blocks, axis), Va @ self.data.acc[:, axis])

    def point_velocities(self, xval: np.ndarray) -> np.ndarray:
        """The velocity of the stacked solution ``xval`` at every sample (n, d), m/s: the point about
        which the next step linearizes body-frame rows (here the nodes are the samples; a coarse
        mesh recovers its samples, :meth:`bvpnav.mesh.MeshModel.point_velocities`)."""
        return np.column_stack([self.node_velocity_values(a, xval) for a in range(self.d)])

    def node_velocity_values(self, axis: int, xval: np.ndarray) -> np.ndarray:
        r""":meth:`node_velocity` of one axis evaluated at the stacked solution ``xval``
        (m/s), without assembling its rows.

        Notes
        -----
        :math:`v = V_r r + V_a (\hat a + G l + w) + V_b (v_0, v_1)`
        (:func:`bvpnav.fem.node_velocity_operators`), evaluated by slices: at an interior
        node :math:`v_j = (r_j - r_{j-1}) / h_{j-1} + h_{j-1} (a_{j-1} + 2 a_j) / 6`, and
        :math:`v_0`, :math:`v_1` at the ends.
        """
        o, N = self._offset(axis), self.N
        acc = self.data.acc[:, axis] + xval[o + N:o + 2 * N]   # slices of x: views, not copies
        if self.q:
            acc += self.G[:, axis, :] @ xval[self.l_index]
        if self.ns:
            acc += self.Gs[axis] @ xval[self.s_index]
        r, hl = xval[o:o + N], self.grid.h[:N - 2]
        v = np.empty(N)
        v[0], v[-1] = xval[o + 2 * N], xval[o + 2 * N + 1]
        inner = v[1:-1]
        np.subtract(r[1:-1], r[:-2], out=inner)
        inner /= hl
        a2 = acc[1:-1] * 2.0
        a2 += acc[:-2]
        a2 *= hl
        a2 /= 6.0
        inner += a2
        return v

    def node_position(self, axis: int) -> Affine:
        """Position at every node of one axis (m)."""
        I = sp.identity(self.N, format="csr")
        return Affine(self._place({"r": I}, axis), np.zeros(self.N))

    def params(self, names=None) -> Affine:
        """Error-model parameters (internal, linear parametrisation) as rows."""
        idx = np.arange(self.q) if names is None else np.array(
            [self.param_names.index(n) for n in names], dtype=int
        )
        A = sp.csr_matrix((np.ones(idx.size), (np.arange(idx.size), self.l_index[idx])),
                          shape=(idx.size, self.size))
        return Affine(A, np.zeros(idx.size), tuple(self.param_names[i] for i in idx))

    # --------------------------------------------------------- extraction
    def trajectory(self, xval: np.ndarray) -> dict[str, np.ndarray]:
        """The answer at every sample: ``t`` (N,, s), ``r`` (N, d, m), ``v`` (N, d, m/s) and the
        acceleration residuals ``w`` (N, d, m/s^2) of the stacked solution ``xval``."""
        parts = self.split(xval)
        return {"t": self.grid.t, "r": parts["r"], "w": parts["w"],
                "v": np.column_stack([self.node_velocity_values(a, xval) for a in range(self.d)])}

    def split(self, xval: np.ndarray) -> dict[str, np.ndarray]:
        """Numeric pieces of a solution vector: r, w (N, d), v_end (2, d), l (q,), s (ns,)."""
        r = np.column_stack([xval[self.r_index(a)] for a in range(self.d)])
        w = np.column_stack([xval[self.w_index(a)] for a in range(self.d)])
        vend = np.array([[xval[i] for i in self.v_end_index(a)] for a in range(self.d)]).T
        return {"r": r, "w": w, "v_end": vend, "l": xval[self.l_index], "s": xval[self.s_index]}

    def __repr__(self) -> str:
        return f"NavModel(N={self.N}, axes={self.axes}, q={self.q}, unknowns={self.size})"
