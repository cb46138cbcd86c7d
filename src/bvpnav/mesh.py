r"""A coarse FEM mesh with the samples between its nodes condensed: :class:`MeshModel`.

With ``NavigationProblem(..., segment=1.0)`` the unknowns are the positions at a mesh of
some of the samples (every item time, and enough samples that no element is longer than
``segment`` seconds), not at every sample; the measured accelerations, the error models'
columns and the acceleration residuals of the samples between nodes reach the nodes through
the exact condensation of the linear elements (:func:`bvpnav.fem.condensation`). It is the
FEM analogue of a factor graph's preintegration, and it is exact: with items at the nodes
only, the nodal positions and velocities are those of the problem on every sample, and the
trajectory at every sample is recovered from them (:meth:`MeshModel.trajectory`).

Notes
-----
**Unknowns.** Per axis the block of ``x`` is

    [ r (n nodal positions, m) | w (n residuals at the nodes, m/s^2) | v0, v1 (m/s) |
      u (2 per element with samples inside it, whitened, dimensionless) ]

**Rows.** With :math:`L_f = \Phi^T M_f` (:attr:`bvpnav.fem.Condensation.load`) the fine FEM
rows condense to (per axis)

.. math:: K_c r + B v + L_f (\hat a + G l) + L_f P_n w_n + \sum_e P_e L_e u_e = 0 ,

where :math:`P_n` puts the node residuals at their samples, and the residuals
:math:`w_e` of the samples strictly inside element :math:`e = [t_p, t_q]` reach the rows
only as the 2-vector :math:`\epsilon_e = B_e w_e` (its loads on nodes p and q, rows of
``Cp`` and ``Cq`` at those samples), placed by :math:`P_e` at rows p and q.

**Weights (the elimination of the samples inside an element).** The data term of the
acceleration form is :math:`\sum_i w_i^2 / \sigma_i^2` over every sample. Given
:math:`\epsilon_e`, the smallest :math:`\sum_{i \in e} w_i^2/\sigma_i^2` with
:math:`B_e w_e = \epsilon_e` is :math:`\epsilon_e^T C_e^{-1} \epsilon_e` with

.. math:: C_e = B_e \,\mathrm{diag}(\sigma_i^2)\, B_e^T
        = \sum_{i \in e} \sigma_i^2 \begin{bmatrix} c_{p,i}^2 & c_{p,i} c_{q,i} \\
          c_{p,i} c_{q,i} & c_{q,i}^2 \end{bmatrix},

(the 2x2 covariance of the load residual for white noise; regular with two or more
samples inside, :func:`bvpnav.grid.mesh_nodes` sees to it), attained at
:math:`w_e = \mathrm{diag}(\sigma_i^2) B_e^T C_e^{-1} \epsilon_e`, the conditional mean of
the residuals given :math:`\epsilon_e`. With :math:`C_e = L_e L_e^T` (Cholesky) and
:math:`\epsilon_e = L_e u_e` the term is :math:`\|u_e\|^2`: the data rows are
:math:`w_n / \sigma` at the nodes and :math:`u_e` itself. Since the items see :math:`w`
only through the condensed rows and the nodal velocities (below), minimizing over the
inside residuals first changes nothing: the condensed problem has the same minimizer at
the nodes, exactly (it is a partial minimization of a convex quadratic).

**Velocities.** At node q the velocity is :math:`(r_q - r_p)/H + C_q (\hat a + G l + w)`
over the element on its left (:func:`bvpnav.fem.condensation`), :math:`C_q w = c_{q,p}
w_p + c_{q,q} w_q + \epsilon_{e,2}`; ``v0`` and ``v1`` at the ends. A time inside an
element of one sample step uses the fine formula between its two nodes.

**Node states** (:class:`~bvpnav.error_models.ErrorStates`) sit at the nodes; their columns are
made at every sample (exact derivatives with the attitude re-integrated from the node) and
condensed as the other loads; see :mod:`bvpnav.error_models.error_states`.

**Recovery.** The residuals inside an element are the conditional mean above; the
positions there solve the element's fine FEM rows with the nodal positions as Dirichlet
conditions (one tridiagonal solve for all elements); the velocities at every sample come
from the fine formula (:meth:`bvpnav.NavModel.node_velocity_values`), which at the nodes
equals the coarse one.

**Body-frame rows** (``NonHolonomic``, ``ForwardMotion``, ``Odometer``, a lever arm) read the
attitude and the rates at the samples (:attr:`MeshModel.sample_grid`) and the velocity at a
sample inside an element from that element alone (:meth:`MeshModel.sample_velocity`: the
recovered trajectory's velocity there, exactly). Soft rows stay inside the elements; rows held
as constraints get nodes (:func:`rows_inside_elements`).
"""

from __future__ import annotations

import functools

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from . import fem
from .errors import InputError
from .grid import MeshGrid, TimeGrid, as_times, mesh_nodes
from .imu import ImuData
from .model import Affine, NavModel, TimeLabels, _body_axes, canonical_csr, columns_csr, state_component
from .sparse import as_csr

__all__ = ["MeshModel", "item_times", "check_segment", "rows_inside_elements"]

#: Item fields holding the instants the mesh must have nodes at (s).
TIME_FIELDS = ("t", "t0", "t1", "about_t", "lower_t", "upper_t")


def check_segment(segment) -> float | None:
    """``segment`` as a float (s), or None; :class:`InputError` for anything but a finite
    positive number of seconds."""
    if segment is None:
        return None
    try:
        val = float(segment)
    except (TypeError, ValueError):
        val = float("nan")
    if isinstance(segment, bool) or not np.isfinite(val) or val <= 0:
        raise InputError(f"segment={segment!r}: give the longest mesh element in seconds (a finite number "
                         "> 0, e.g. segment=1.0), or None (no segment key in a spec) to solve on every "
                         "sample")
    return val


def item_times(items, grid=None) -> np.ndarray:
    """Every instant (s) the items name in their time fields (:data:`TIME_FIELDS`) and, with
    the samples' ``grid``, the instants of items that list them (``instants(grid)``, e.g.
    :class:`~bvpnav.constraints.ZeroVelocity`: every sample of its interval), except the rows
    that stay inside elements (:func:`rows_inside_elements`) and the rows that sit at the mesh's
    own nodes (an item whose ``rows_at_nodes`` is true, e.g. ``NonHolonomic(rate="nodes")``:
    they follow the mesh, so they ask it for no node).

    Raises
    ------
    InputError
        For an item that declares ``on_mesh = False`` (its instants cannot be known in advance).
    """
    out = []
    for it in items:
        if getattr(it, "on_mesh", True) is False:
            raise InputError(f"{it.identify()}: its instants are not known before it is compiled, so a "
                             "coarse "
                             "mesh (segment=) cannot give them nodes; solve on every sample (segment=None)")
        inst = getattr(it, "instants", None)
        if (grid is not None and callable(inst) and not rows_inside_elements(it)
                and getattr(it, "rows_at_nodes", False) is not True):
            try:
                out.append(np.asarray(inst(grid), dtype=float).ravel())
            except (TypeError, AttributeError, ValueError):   # instants of a model, not of a grid
                pass
        for name in TIME_FIELDS:
            v = getattr(it, name, None)
            if v is None or isinstance(v, str | bool):
                continue
            try:
                arr = np.asarray(v, dtype=float).ravel()
            except (TypeError, ValueError):
                continue
            out.append(arr[np.isfinite(arr)])
    return np.concatenate(out) if out else np.zeros(0)


def rows_inside_elements(item) -> bool:
    """Whether ``item``'s rows stay at their samples inside the mesh's elements instead of
    getting nodes: the penalty rows (soft, robust) of a body-frame item
    (:meth:`MeshModel.sample_velocity`; a band with soft edges is a penalty too). Its rows held
    as constraints (hard, band, inequality)
    get nodes: inside an element the residuals are their conditional mean given the element's
    loads (two per axis), which cannot follow a row profile the data contradict at a cost the
    samples' problem would pay (``examples/benchmarks/kitti_drive.py``: a band inside 1 s
    elements made the node-state loop diverge; with nodes at its rows it gives the samples'
    answer)."""
    return bool(getattr(item, "body_frame", False)) and not item.is_constraint


def _condensation(data: ImuData, fine, nodes: np.ndarray) -> fem.Condensation:
    """:func:`bvpnav.fem.condensation` of these nodes, kept on the formulation's copy of the
    measured data when it has one (node states: ``state_mesh``; the loop's steps share the grid
    and the mesh through ``data.state_point.raw``); the user's data is never written to."""
    raw = getattr(getattr(data, "state_point", None), "raw", data)
    if getattr(raw, "state_mesh", None) is None:   # the user's own data: never written to
        return fem.condensation(fine, nodes)
    kept = raw.__dict__.get("_mesh_condensation")
    if kept is not None and np.array_equal(kept.nodes, nodes) and np.array_equal(raw.t, fine.t):
        return kept
    out = fem.condensation(fine, nodes)
    raw.__dict__["_mesh_condensation"] = out
    return out


def _kept_constants(data: ImuData, cond: fem.Condensation, sigma: np.ndarray) -> tuple | None:
    """``(sigma, values)``: the mesh's matrices and element weights a step before made with this
    condensation and these ``sigma`` (kept on the formulation's copy of the measured data, as
    :func:`_condensation`, with the ``sigma`` array they were made with), or None."""
    raw = getattr(getattr(data, "state_point", None), "raw", data)
    kept = raw.__dict__.get("_mesh_constants")
    if kept is not None and kept[0] is cond and np.array_equal(kept[1], sigma):
        return kept[1], kept[2]
    return None


def _keep_constants(data: ImuData, cond: fem.Condensation, sigma: np.ndarray, values: tuple) -> None:
    raw = getattr(getattr(data, "state_point", None), "raw", data)
    if getattr(raw, "state_mesh", None) is not None:   # the user's own data: never written to
        raw.__dict__["_mesh_constants"] = (cond, sigma, values)


def _element_entries(C: sp.csr_matrix, e: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``C[e, idx]`` (one value per sample ``idx`` of element ``e``) of a condensation's ``Cp`` or
    ``Cq``: read from their layout (:func:`bvpnav.fem.condensation`: element ``e``'s row holds
    its samples in order, sample ``j`` at entry ``j + e``) when it holds, else by scipy's
    indexing."""
    if not idx.size:
        return np.zeros(0)
    at = idx + e
    if at[-1] < C.indices.size and np.array_equal(C.indices[at], idx) and np.all(
            (C.indptr[e] <= at) & (at < C.indptr[e + 1])):
        return C.data[at]
    return np.asarray(C[e, idx]).ravel()


class MeshModel(NavModel):
    r"""The unknowns of a problem on a coarse mesh of its samples (see the module Notes).

    Parameters
    ----------
    data : ImuData
        Every sample.
    error_model : ErrorModel, optional
        Its columns are made on every sample and condensed; node states
        (:class:`~bvpnav.error_models.ErrorStates`) sit at the nodes (``data.state_mesh``, which
        must be this mesh: :class:`~bvpnav.formulation.Formulation` sets it on a copy).
    segment : float
        Longest element, s (:func:`bvpnav.grid.mesh_nodes`).
    times : array_like of float
        Instants that need nodes (the items'), s.
    sigma_a : ndarray
        Accelerometer noise, m/s^2, (d,) or (N, d) (the formulation's, clipping applied): the
        weights of the condensed residuals depend on it.
    nodes : ndarray of int, optional
        The node samples, when already made (default: :func:`bvpnav.grid.mesh_nodes` of
        ``segment`` and ``times``).

    Attributes
    ----------
    fine : TimeGrid
        Every sample.
    grid : MeshGrid
        The nodes.
    cond : bvpnav.fem.Condensation
    """

    def __init__(self, data: ImuData, error_model=None, *, segment: float, times=(), sigma_a=None,
                 nodes: np.ndarray | None = None):
        comps = getattr(error_model, "components", (error_model,))
        gyro = [type(c).__name__ for c in comps if c is not None and hasattr(c, "rate_columns")]
        if gyro:
            raise InputError(f"segment=: the attitude loop's error models ({', '.join(gyro)}) are not "
                             "carried "
                             "on a coarse mesh yet; solve them on every sample (segment=None)")
        fine = data.grid
        nodes = mesh_nodes(fine, float(segment), times) if nodes is None else np.asarray(nodes, np.int64)
        self.data = data
        self.fine = fine
        self.segment = float(segment)
        self.cond = _condensation(data, fine, nodes)
        self.grid = MeshGrid(fine.t[nodes], fine=fine, nodes=nodes)
        self.axes = data.axes
        self.error_model = error_model
        n, d, Nf = nodes.size, data.ndim, fine.n
        self.N, self.d = n, d
        if error_model is not None:
            G = np.asarray(error_model.columns(data), dtype=float)
            if G.shape[:2] != (Nf, d):
                raise InputError(f"error model {error_model!r}: columns of shape {G.shape}, expected "
                                 f"({Nf}, {d}, q)")
            self.param_names = tuple(error_model.names(data))
        else:
            G = np.zeros((Nf, d, 0))
            self.param_names = ()
        self.G = G                      # on every sample; condensed by mg_columns
        self.q = G.shape[2]
        self.state_model, self.ns = state_component(error_model), 0
        if self.state_model is not None:   # node states at the mesh nodes (data.state_mesh)
            if not np.array_equal(getattr(data, "state_mesh", None), nodes):
                raise InputError("segment=: the node states' mesh (data.state_mesh) is not this mesh; build "
                                 "the problem with NavigationProblem(..., segment=...), which sets it")
            self.ns = int(self.state_model.state_size(data))
        sa = np.ones(d) if sigma_a is None else np.asarray(sigma_a, dtype=float)
        sigma_fine = np.broadcast_to(sa if sa.ndim == 2 else sa[None, :], (Nf, d))
        inside = np.diff(nodes) - 1
        self.elements = np.flatnonzero(inside >= 2)        # elements with residuals to condense
        self.me = self.elements.size
        self.block = 2 * n + 2 + 2 * self.me
        self.size = d * self.block + self.q + self.ns
        kept = _kept_constants(data, self.cond, sigma_fine)
        if kept is not None:   # the loop's steps share the mesh and sigma_a (and its (N, d) array)
            self.sigma_fine, values = kept
            self.K, self.M, self._cp, self._cq, self._slot, self.chol, self._constant = values
            return
        self.sigma_fine = np.array(sigma_fine)
        self.K = fem.stiffness(self.grid)
        W = self.cond.load[:, nodes].tocsr()
        self.M = fem.tridiagonal(W.diagonal(-1), W.diagonal(0), W.diagonal(1))   # the node residuals
        self._prepare_elements()
        #: Blocks of the rows that depend on the mesh and sigma_a alone, made once and shared by the
        #: loop's models (read-only): the element residuals' FEM columns, the end velocities' columns
        self._constant: dict = {}
        _keep_constants(data, self.cond, self.sigma_fine,
                        (self.K, self.M, self._cp, self._cq, self._slot, self.chol, self._constant))

    def _prepare_elements(self) -> None:
        """The load coefficients of the samples inside elements and the Cholesky factors of
        the elements' 2x2 covariances per axis (module Notes)."""
        c = self.cond
        idx = c.interior
        e = c.element[idx]
        self._cp, self._cq = _element_entries(c.Cp, e, idx), _element_entries(c.Cq, e, idx)
        self._slot = np.full(self.N - 1, -1, dtype=np.int64)
        self._slot[self.elements] = np.arange(self.me)
        nE = self.N - 1
        self.chol = []
        for a in range(self.d):
            s2 = self.sigma_fine[idx, a] ** 2
            Spp = np.bincount(e, self._cp**2 * s2, nE)[self.elements]
            Spq = np.bincount(e, self._cp * self._cq * s2, nE)[self.elements]
            Sqq = np.bincount(e, self._cq**2 * s2, nE)[self.elements]
            L00 = np.sqrt(Spp)
            L10 = Spq / L00
            L11 = np.sqrt(np.maximum(Sqq - L10**2, 0.0))
            self.chol.append(np.stack([L00, L10, L11], axis=1))

    # ------------------------------------------------------------ layout
    @property
    def node_samples(self) -> np.ndarray:
        """The sample index of every node."""
        return self.grid.nodes

    def element_index(self, axis: int) -> np.ndarray:
        """Indices in ``x`` of the whitened element residuals ``u`` of one axis (2 per element
        with samples inside it, in element order)."""
        o = self._offset(axis) + 2 * self.N + 2
        return np.arange(o, o + 2 * self.me)

    def element_nodes(self) -> np.ndarray:
        """The node of each element residual: the element's left node for the first, its
        right node for the second."""
        return np.column_stack([self.elements, self.elements + 1]).ravel()

    def _element_block(self, axis: int) -> sp.csr_matrix:
        r"""The columns of the ``u`` of one axis in its FEM rows, (n, 2 m):
        :math:`\epsilon_e = L_e u_e` at rows p (``L00 u0``) and q (``L10 u0 + L11 u1``)."""
        kept = self._constant.get(("u", axis))
        if kept is not None:
            return kept
        L = self.chol[axis]
        k = np.arange(self.me)
        rows = np.concatenate([self.elements, self.elements + 1, self.elements + 1])
        cols = np.concatenate([2 * k, 2 * k, 2 * k + 1])
        out = sp.csr_matrix((np.concatenate([L[:, 0], L[:, 1], L[:, 2]]), (rows, cols)),
                            shape=(self.N, 2 * self.me))
        out.sum_duplicates()
        out.sort_indices()
        self._constant[("u", axis)] = out
        return out

    # ----------------------------------------------------------- FEM rows
    def fem_blocks(self, axis: int) -> dict:
        """As :meth:`NavModel.fem_blocks`, with the element residuals' columns ``u``."""
        blocks = super().fem_blocks(axis)
        if self.me:
            blocks["u"] = self._element_block(axis)
        return blocks

    def _kept_constants(self) -> dict:
        return self._constant

    def _boundary_columns(self) -> sp.csr_matrix:
        """As :meth:`NavModel._boundary_columns`, made once for the loop's models (kept with the
        mesh's constants)."""
        if "vb" not in self._constant:
            self._constant["vb"] = super()._boundary_columns()
        return self._constant["vb"]

    @functools.cached_property
    def Gs(self) -> list:
        """The node states' columns at every sample, sparse (N, ns) per axis, m/s^2 per unit
        (made on first use: the rows read them condensed, :meth:`_state_times`)."""
        if self.state_model is None:
            return []
        return [as_csr(g) for g in self.state_model.state_columns(self.data)]

    def _state_times(self, W) -> list:
        """``W @ Gs[a]`` for every axis, canonical CSR (``W`` sparse (m, N)): by the state
        model's per-element sums when it has them (``condensed_columns``), without the columns
        of every sample."""
        by_sums = getattr(self.state_model, "condensed_columns", None)
        if by_sums is None:
            return [canonical_csr(W @ g) for g in self.Gs]
        return by_sums(self.data, W)

    @functools.cached_property
    def _left_element_state_columns(self) -> list:
        r"""``Cq @ Gs[a]`` of every axis ((n - 1, ns), s): the node states' loads of every element
        on its right node, made once per model (one pass over the samples); the velocities at
        the nodes (from the element on their left) are made of them."""
        return self._state_times(self.cond.Cq)

    @functools.cached_property
    def _load_change(self) -> np.ndarray | None:
        """The change of the nodes' loads (n, d), m/s^2 s, that the state model makes without the
        samples at a cheap Gauss-Newton point
        (:func:`bvpnav.error_models.error_states.cheap_at`: the data's accelerations are then the
        last full pass's), from its per-element sums of the load rows; None at any other point."""
        by_sums = getattr(self.state_model, "condensed_change", None)
        return None if by_sums is None else by_sums(self.data, self.cond.load)

    def ms_columns(self, axis: int) -> sp.csr_matrix:
        r""":math:`\Phi^T M_f G_s` of one axis (s): the node states' columns condensed (local: a
        state of node k reaches rows k - 1 .. k + 1): node k gets ``Cp G_s`` of the element on
        its right and ``Cq G_s`` of the one on its left (the rows of the condensation's load,
        made for every axis at once)."""
        cache = self.__dict__.setdefault("_ms_cache", {})
        if not cache:   # the condensation's load rows, Sp Cp + Sq Cq: every axis at once
            cache.update(enumerate(self._state_times(self.cond.load)))
        return cache[axis]

    def mg_columns(self, axis: int) -> tuple[np.ndarray, np.ndarray]:
        r""":math:`\Phi^T M_f G` of one axis (s): the error model's columns condensed."""
        cache = self.__dict__.setdefault("_mg_cache", {})
        if axis not in cache:
            cache[axis] = self._times_g(self.cond.load, axis)
        return cache[axis]

    def _check_full_point(self, what: str) -> None:
        """Refuse ``what`` at a cheap Gauss-Newton point (:attr:`_load_change`): its samples'
        accelerations are the last full pass's, so only the condensed loads are made there."""
        if self._load_change is not None:
            raise RuntimeError(f"{what} of a cheap Gauss-Newton point: made at full passes only (its "
                               "samples' accelerations are the last full pass's)")

    def _acc_load(self, axis: int) -> np.ndarray:
        out = self._acc_loads()[:, axis]
        change = self._load_change
        return out.copy() if change is None else out + change[:, axis]

    def _acc_loads(self) -> np.ndarray:
        """``cond.load @ data.acc`` (n, d), m/s^2 s: the samples' accelerations condensed, every axis
        in one product, kept with the load and the accelerations it was made of: on the data when
        bvpnav made it (node states: a cheap Gauss-Newton point, a copy of its full pass's data,
        reads that pass's), else on this model (the user's own data is never written to). Read
        only: the kept array is returned."""
        W, acc = self.cond.load, self.data.acc
        ours = getattr(self.data, "state_mesh", None) is not None
        store = self.data.__dict__ if ours else self.__dict__
        kept = store.get("_mesh_acc_loads")
        if kept is None or kept[0] is not W or kept[1] is not acc:
            kept = store["_mesh_acc_loads"] = (W, acc, np.asarray(W @ acc))
        return kept[2]

    def residual_rows(self, axes=None) -> Affine:
        """The node residuals ``w`` (m/s^2) and the whitened element residuals ``u``, axis by
        axis (:meth:`residual_sigma` gives their standard deviations)."""
        key = ("residual_rows", None if axes is None else tuple(np.atleast_1d(axes)), self.size)
        if key not in self._constant:
            self._constant[key] = self._residual_rows(axes)
        return self._constant[key]

    def _residual_rows(self, axes=None) -> Affine:
        parts = []
        for a in self.axes_of(axes):
            cols = np.concatenate([self.w_index(a), self.element_index(a)])
            m = cols.size
            parts.append(Affine(sp.csr_matrix((np.ones(m), (np.arange(m), cols)), shape=(m, self.size)),
                                np.zeros(m)))
        return Affine.vstack(parts)

    def residual_sigma(self, sigma_a: np.ndarray) -> np.ndarray:
        """``sigma_a`` at the node samples (m/s^2) and 1 for the whitened ``u``, axis by axis.
        The element weights are the model's own (made from the ``sigma_a`` it was given)."""
        return np.concatenate([np.r_[self.sigma_fine[self.grid.nodes, a], np.ones(2 * self.me)]
                               for a in range(self.d)])

    def load_residual_rows(self, axes=None) -> Affine:
        raise InputError("segment=: a coarse mesh weighs the acceleration residuals "
                         "(residual='acceleration'); "
                         "the load form is solved on every sample")

    # ------------------------------------------------------ velocities
    def velocity(self, t, axes=None, what: str = "velocity") -> Affine:
        r"""Velocities at times ``t`` (m/s), rows time-major then axis: at a node from the
        element on its left (module Notes), ``v0``/``v1`` at the ends; inside an element of
        one sample step the linear acceleration integrated from its left node, as
        :func:`bvpnav.fem.velocity_operators`. Other times raise :class:`InputError`."""
        self._check_full_point("velocities")
        times = self.grid.check_inside(as_times(t, what), what)
        self.grid.check_on_mesh(times, what)
        times = self.grid.snapped(times)
        ax = self.axes_of(axes, what)
        g, n, nodes = self.grid, self.N, self.grid.nodes
        j, s = g.locate(times)
        end = times >= g.t1
        j, s = np.where(end, n - 1, j), np.where(end, 0.0, s)
        m = times.size
        k = np.arange(m)
        inner = (j > 0) & (j < n - 1)
        ki, ji = k[inner], j[inner]
        H = g.h[ji - 1]
        Vr = sp.csr_matrix((np.r_[-1.0 / H, 1.0 / H], (np.r_[ki, ki], np.r_[ji - 1, ji])), shape=(m, n))
        ends = ~inner
        Vb = sp.csr_matrix((np.ones(int(ends.sum())), (k[ends], np.where(j[ends] == 0, 0, 1))), shape=(m, 2))
        # the left element's loads on node j, placed at the rows of the inner times
        place = sp.csr_matrix((np.ones(ki.size), (ki, np.arange(ki.size))), shape=(m, ki.size))
        F = place @ self.cond.Cq[ji - 1]
        # inside a one-step element: + a_i s - (a_i - a_{i+1}) s^2 / (2 h)
        mid = s > 0
        km, jm, sm = k[mid], j[mid], s[mid]
        hm = g.h[np.minimum(jm, n - 2)]
        c1, c2 = sm - sm**2 / (2.0 * hm), sm**2 / (2.0 * hm)
        F = F + sp.csr_matrix((np.r_[c1, c2], (np.r_[km, km], np.r_[nodes[jm], nodes[jm] + 1])),
                              shape=(m, self.fine.n))
        F = F.tocsr()
        Vw = F[:, nodes]                                    # the node residuals' share
        slot = np.full(m, -1, dtype=np.int64)
        slot[ki] = self._slot[ji - 1]
        has = slot >= 0
        FGs = None
        if self.ns:   # the left element's loads (Cq G_s), and the samples' columns inside one-step elements
            Fm = F - place @ self.cond.Cq[ji - 1]
            Fm.eliminate_zeros()
            FGs = [place @ CqG[ji - 1] for CqG in self._left_element_state_columns]
            if Fm.nnz:
                FGs = [canonical_csr(a + b) for a, b in zip(FGs, self._state_times(Fm), strict=True)]
            else:
                FGs = [canonical_csr(a) for a in FGs]
        parts = []
        for a in ax:
            blocks = {"r": Vr, "w": Vw, "vb": Vb}
            if self.me:
                L = self.chol[a][slot[has]]
                kk, ss = k[has], slot[has]
                blocks["u"] = sp.csr_matrix((np.r_[L[:, 1], L[:, 2]],
                                             (np.r_[kk, kk], np.r_[2 * ss, 2 * ss + 1])),
                                            shape=(m, 2 * self.me))
            if self.q:
                blocks["l"] = columns_csr(*self._times_g(F, a), self.q)
            if self.ns:
                blocks["s"] = FGs[a]
            parts.append(Affine(self._place(blocks, a), F @ self.data.acc[:, a]))
        out = self._interleave(parts, m)
        return Affine(out.A, out.c, self._labels("v", times, ax))

    @functools.cached_property
    def _node_velocities(self) -> Affine:
        """:meth:`velocity` at every node, every axis (time-major), made once."""
        return self.velocity(self.grid.t)

    def node_velocity(self, axis: int) -> Affine:
        """Velocity at every node of one axis (m/s): rows of :meth:`velocity` at the nodes for
        every axis, made once per model."""
        return self._node_velocities.rows(np.arange(axis, self.N * self.d, self.d))

    def node_velocity_values(self, axis: int, xval: np.ndarray) -> np.ndarray:
        """:meth:`node_velocity` of one axis evaluated at ``xval`` (m/s)."""
        V = self._node_velocities
        return (V.A @ xval + V.c)[axis::self.d]

    def with_acc(self, acc: np.ndarray) -> MeshModel:
        """As :meth:`bvpnav.NavModel.with_acc`, without the rows this model keeps that hold its
        accelerations (the node velocities and the body rows at the nodes)."""
        other = super().with_acc(acc)
        for key in ("_node_velocities", "_node_body_rows"):
            other.__dict__.pop(key, None)
        return other

    def node_point_velocities(self, xval: np.ndarray) -> np.ndarray:
        r"""The velocity of the nodal solution ``xval`` at the nodes, linear between them, at every
        sample (``fine.n``, d), m/s: the linearization point of body-frame rows that are read at the nodes
        only (``rate="nodes"``), without recovering the samples inside the elements.

        Notes
        -----
        At a node :math:`v_j` is :meth:`node_velocity` (inside the window the left element's,
        :math:`(r_j - r_{j-1})/H + (C_q a)_e`; at the ends the end velocities), which the recovered trajectory
        (:meth:`point_velocities`) equals there up to rounding: the fine velocity is continuous
        at the samples. Between the nodes the values are the linear interpolant, which no row at
        the nodes reads.
        """
        V = self._node_velocities
        vn = (V.A @ xval + V.c).reshape(self.N, self.d)
        return np.column_stack([np.interp(self.fine.t, self.grid.t, vn[:, a]) for a in range(self.d)])

    # ------------------------------------------------------- recovery
    def trajectory(self, xval: np.ndarray) -> dict[str, np.ndarray]:
        r"""The answer at every sample: ``t`` (N,), ``r``, ``v``, ``w`` (N, d) from the nodal
        solution ``xval`` (module Notes, Recovery).

        Notes
        -----
        Inside element e, :math:`w_i = \sigma_i^2 (c_{p,i} z_0 + c_{q,i} z_1)` with
        :math:`z = L_e^{-T} u_e`; the positions there solve the fine FEM rows
        :math:`K_f r + M_f a = 0` at those samples with the nodal positions given.
        """
        self._check_full_point("the trajectory")
        fine, nodes, idx = self.fine, self.grid.nodes, self.cond.interior
        Nf, d = fine.n, self.d
        # every axis at once, axis-major ((d, Nf): each axis contiguous), one banded solve with d
        # right-hand sides
        W = np.zeros((d, Nf))
        R = np.zeros((d, Nf))
        for a in range(d):
            W[a, nodes] = xval[self.w_index(a)]
            R[a, nodes] = xval[self.r_index(a)]
        if self.me:
            e = self.cond.element[idx]
            sl = self._slot[e]
            for a in range(d):
                u = xval[self.element_index(a)].reshape(self.me, 2)
                L = self.chol[a]
                z1 = u[:, 1] / L[:, 2]
                z0 = (u[:, 0] - L[:, 1] * z1) / L[:, 0]
                W[a, idx] = self.sigma_fine[idx, a] ** 2 * (self._cp * z0[sl] + self._cq * z1[sl])
        acc = self.data.acc[:, :d].T + W
        if self.q:
            lval = xval[self.l_index]
            for a in range(d):
                acc[a] += self.G[:, a, :] @ lval
        if self.ns:
            acc += self._state_acceleration(xval[self.s_index]).T
        tmp = np.empty((d, Nf - 2))   # the products of the rows below, one at a time
        if idx.size:
            # K_f r + M_f a = 0 at the samples inside elements, the nodal positions given (the
            # products' inner rows term by term, in the order a CSR product sums them), rows 1 .. Nf - 2
            # (each array freed once read: the recovery's memory is the answer's and a few rows)
            lo_m, dg_m, up_m = fem._mass_diagonals(fine)
            rhs = np.multiply(lo_m[:-1], acc[:, :-2])
            rhs += np.multiply(dg_m[1:-1], acc[:, 1:-1], out=tmp)
            rhs += np.multiply(up_m[1:], acc[:, 2:], out=tmp)
            del lo_m, dg_m, up_m
            np.negative(rhs, out=rhs)
            lo_k, dg_k, up_k = fem._stiffness_diagonals(fine)
            kr = np.multiply(lo_k[:-1], R[:, :-2])
            kr += np.multiply(dg_k[1:-1], R[:, 1:-1], out=tmp)
            kr += np.multiply(up_k[1:], R[:, 2:], out=tmp)
            rhs -= kr
            del kr
            band = self._interior_band((lo_k, dg_k, up_k))
            del lo_k, dg_k, up_k
            b = rhs.take(idx - 1, axis=1)
            del rhs
            # one solve for every axis: the (M, d) right-hand sides in Fortran order (no copy), the
            # band and the right-hand sides made here (overwritten)
            R[:, idx] = sla.solve_banded((1, 1), band, b.T, overwrite_ab=True, overwrite_b=True,
                                         check_finite=False).T
            del band, b
        V = np.empty((d, Nf))
        for a in range(d):
            v0, v1 = self.v_end_index(a)
            V[a, 0], V[a, -1] = xval[v0], xval[v1]
        hl = fine.h[:-1]
        # (R_i - R_{i-1}) / h + h (a_{i-1} + 2 a_i) / 6 at the samples inside
        inner = V[:, 1:-1]
        np.subtract(R[:, 1:-1], R[:, :-2], out=inner)
        inner /= hl
        np.multiply(acc[:, 1:-1], 2.0, out=tmp)
        tmp += acc[:, :-2]
        tmp *= hl
        tmp /= 6.0
        inner += tmp
        del acc, tmp, inner
        R, V, W = (np.ascontiguousarray(z.T) for z in (R, V, W))   # (Nf, d), as callers index them
        return {"t": fine.t, "r": R, "v": V, "w": W}

    def _state_acceleration(self, s: np.ndarray) -> np.ndarray:
        """``Gs[a] @ s`` for every axis, (N, d), m/s^2 (by the state model's
        ``state_acceleration`` when it has it, without the columns of every sample)."""
        by_blocks = getattr(self.state_model, "state_acceleration", None)
        if by_blocks is None:
            return np.column_stack([g @ s for g in self.Gs])
        return by_blocks(self.data, s)

    def _interior_band(self, diagonals: tuple) -> np.ndarray:
        """``K_f`` (its diagonals ``(lower, diag, upper)``) on the samples inside elements (nodes
        held), in :func:`scipy.linalg.solve_banded`'s (1, 1) layout: neighbours across a node are
        not coupled."""
        idx = self.cond.interior
        lo, dg, up = diagonals
        ab = np.zeros((3, idx.size))
        ab[1] = dg[idx]
        if idx.size > 1:
            adj = np.diff(idx) == 1
            ab[0, 1:] = np.where(adj, up[idx[:-1]], 0.0)
            ab[2, :-1] = np.where(adj, lo[idx[:-1]], 0.0)
        return ab

    def __repr__(self) -> str:
        return (f"MeshModel(n={self.N} nodes of N={self.fine.n} samples, segment={self.segment:g} s, "
                f"axes={self.axes}, q={self.q}, unknowns={self.size})")

    # ------------------------------------------- body-frame rows (issue 39)
    @property
    def sample_grid(self):
        """Every sample (:attr:`fine`): the attitude and the rates are per sample."""
        return self.fine

    def sample_velocity(self, t, axes=None, what: str = "velocity") -> Affine:
        r"""Velocities at times ``t`` (m/s), rows time-major then axis: :meth:`velocity` at the
        nodes (and inside elements of one sample step), and at a sample strictly inside element
        :math:`[t_p, t_q]` from the condensed element alone.

        Notes
        -----
        The fine velocity is continuous at the samples and its steps are the trapezoids of
        the linear acceleration, :math:`v_i = v_p^+ + \sum_{j=p}^{i-1} h_j (a_j + a_{j+1})/2`,
        with the velocity at node p from the element on its right
        :math:`v_p^+ = (r_q - r_p)/H - (C_p a)_e` (as :math:`v_q = (r_q - r_p)/H + (C_q a)_e`
        from the left, :func:`bvpnav.fem.condensation`). So

        .. math:: v_i = \frac{r_q - r_p}{H} + F_i\,(\hat a + G l + G_s s + w),
                  \qquad F_i = T_i - (C_p)_e ,

        :math:`T_i` the trapezoid weights over samples p..i: affine in the two nodes' unknowns,
        their residuals, the element's whitened residuals :math:`u_e` (the residuals inside are
        their conditional mean, :math:`w_j = \sigma_j^2 (c_{p,j} z_0 + c_{q,j} z_1)`,
        :math:`z = L_e^{-T} u_e`, as :meth:`trajectory` recovers them) and the load. It is the
        recovered trajectory's velocity (:meth:`trajectory`) at that sample, exactly. A row
        couples only the element's two nodes, so the band stays a band. Times between two
        samples inside an element raise :class:`InputError` (as :meth:`velocity`).
        """
        f = self.fine
        times = f.check_inside(as_times(t, what), what)
        ax = self.axes_of(axes, what)
        near, on = f.nearest(times, 1e-9 * max(f.duration, 1.0))
        inner = on & (self.cond.element[near] >= 0)
        rest = np.flatnonzero(~inner)
        ins = np.flatnonzero(inner)
        parts = []
        if rest.size:
            node = self._node_of(times[rest])
            if np.all(node >= 0):   # the nodes' own rows, made once per model (:meth:`velocity`'s)
                rows = (node[:, None] * self.d + np.asarray(ax)[None, :]).ravel()
                V = self._node_velocities
                parts.append(Affine(V.A[rows], V.c[rows]))   # labelled below
            else:
                parts.append(self.velocity(times[rest], [self.axes[a] for a in ax], what))
        if ins.size:
            parts.append(self._inner_velocity(near[ins], ax))
        out = Affine.vstack(parts)
        nax = len(ax)
        pos = np.empty(times.size, dtype=np.int64)
        pos[np.r_[rest, ins]] = np.arange(times.size)
        order = (pos[:, None] * nax + np.arange(nax)[None, :]).ravel()
        return Affine(out.A[order], out.c[order], self._labels("v", times, ax))

    def body_velocity(self, t, axes=None, lever=(0.0, 0.0, 0.0), what: str = "body velocity") -> Affine:
        """As :meth:`bvpnav.NavModel.body_velocity`; at node times the rows of every body axis are
        kept on the model for the last times and lever asked and the axes asked for taken from
        them (the non-holonomic rows and forward motion at the nodes, ``rate="nodes"``, with
        one lever read the same rows)."""
        try:
            times = as_times(t, what)
            key = (times.tobytes(), np.asarray(lever, dtype=float).reshape(3).tobytes())
        except (InputError, TypeError, ValueError):
            return super().body_velocity(t, axes, lever, what)   # which says what is wrong
        if times.size == 0 or np.any(self._node_of(times) < 0):
            return super().body_velocity(t, axes, lever, what)
        kept = self.__dict__.get("_node_body_rows")
        if kept is None or kept[0] != key:
            kept = self.__dict__["_node_body_rows"] = (key, super().body_velocity(times, None, lever, what))
        names, jb = _body_axes(axes, what)
        rows = (np.arange(times.size)[:, None] * 3 + np.asarray(jb)[None, :]).ravel()
        every = kept[1]
        return Affine(every.A[rows], every.c[rows], TimeLabels("vb_", list(names), times))

    def _inner_velocity(self, i: np.ndarray, ax) -> Affine:
        """:meth:`sample_velocity` at samples ``i`` strictly inside elements (see its Notes)."""
        self._check_full_point("velocities")
        f, nodes, c = self.fine, self.grid.nodes, self.cond
        m = i.size
        e = c.element[i]
        p = nodes[e]
        # the trapezoid weights over the samples p..i of each row
        lens = i - p + 1
        row = np.repeat(np.arange(m), lens)
        j = np.repeat(p, lens) + (np.arange(row.size) - np.repeat(np.cumsum(lens) - lens, lens))
        h = np.r_[f.h, 0.0]
        last = np.repeat(i, lens)
        wt = 0.5 * (np.where(j > np.repeat(p, lens), h[j - 1], 0.0) + np.where(j < last, h[j], 0.0))
        T = sp.csr_matrix((wt, (row, j)), shape=(m, f.n))
        F = (T - c.Cp[e]).tocsr()
        H = self.grid.h[e]
        k = np.arange(m)
        Vr = sp.csr_matrix((np.r_[-1.0 / H, 1.0 / H], (np.r_[k, k], np.r_[e, e + 1])), shape=(m, self.N))
        Vw = F[:, nodes]
        slot = self._slot[e]
        if np.any(slot < 0):   # pragma: no cover - mesh_nodes leaves no element with one sample inside
            raise InputError("segment=: an element with one sample inside has no condensed residuals")
        idx = c.interior
        parts = []
        for a in ax:
            s2 = self.sigma_fine[idx, a] ** 2
            gp, gq = np.zeros(f.n), np.zeros(f.n)
            gp[idx], gq[idx] = s2 * self._cp, s2 * self._cq
            al0, al1 = F @ gp, F @ gq
            L = self.chol[a][slot]
            c0 = al0 / L[:, 0]
            c1 = (al1 - c0 * L[:, 1]) / L[:, 2]
            blocks = {"r": Vr, "w": Vw,
                      "u": sp.csr_matrix((np.r_[c0, c1], (np.r_[k, k], np.r_[2 * slot, 2 * slot + 1])),
                                         shape=(m, 2 * self.me))}
            if self.q:
                blocks["l"] = columns_csr(*self._times_g(F, a), self.q)
            if self.ns:
                blocks["s"] = canonical_csr(F @ self.Gs[a])
            parts.append(Affine(self._place(blocks, a), F @ self.data.acc[:, a]))
        return self._interleave(parts, m)

    def point_velocities(self, xval: np.ndarray) -> np.ndarray:
        """The velocity of the nodal solution ``xval`` at every sample (n, d), m/s, as
        :meth:`trajectory` recovers it: body-frame rows inside an element linearize about their own
        sample's velocity, as on every sample (not about one interpolated between the nodes)."""
        return self.trajectory(xval)["v"]

    def states(self, kind: str, t=None, axes=None, what: str | None = None) -> Affine:
        r"""As :meth:`bvpnav.NavModel.states`, at any time: the biases linear between the nodes;
        the attitude error at a sample inside an element the left node's carried by the corrected
        rates (:meth:`bvpnav.error_models.ErrorStates.attitude_columns`: its total at the sample
        plus the exact first-order change), linear between samples. When every time is a node, the
        attitude error is the node states' own (their columns and totals, as the biases'): the
        same rows without the columns of every sample."""
        if t is None or kind not in getattr(self.state_model, "state_kinds", lambda d: [])(self.data):
            return super().states(kind, t, axes, what)
        what = what or kind.replace("_", " ")
        names, ax = _body_axes(axes, what, "axes")
        times = self.fine.check_inside(as_times(t, what), what)
        sm, n = self.state_model, self.N
        parts = []
        node = self._node_of(times)
        if kind == "attitude_error" and np.any(node < 0):
            point = getattr(self.data, "state_point", None)
            totals = None if point is None else point.totals.get(kind)
            P = self.fine.interpolation_matrix(times, what)
            cols = self._attitude_state_columns()
            total = np.zeros((self.fine.n, 3)) if totals is None else np.asarray(totals, dtype=float)
            for a in ax:
                parts.append(Affine(self._place({"s": canonical_csr(P @ cols[a])}, 0), P @ total[:, a]))
        else:
            # a bias linear between the nodes; the attitude error at the nodes only: the node state
            # itself (no columns of every sample), its total the node's
            if kind == "attitude_error":
                P = sp.csr_matrix((np.ones(times.size), (np.arange(times.size), node)), shape=(times.size, n))
            else:
                P = TimeGrid(self.grid.t).interpolation_matrix(times, what)
            idx = np.asarray(sm.state_index(self.data, kind), dtype=np.int64)
            total = np.asarray(sm.state_total(self.data, kind), dtype=float)
            for a in ax:
                S = sp.csr_matrix((np.ones(n), (np.arange(n), idx[:, a])), shape=(n, self.ns))
                parts.append(Affine(self._place({"s": canonical_csr(P @ S)}, 0), P @ total[:, a]))
        out = self._interleave(parts, times.size)
        return Affine(out.A, out.c, TimeLabels(f"{kind}_", list(names), times))

    def _node_of(self, times: np.ndarray) -> np.ndarray:
        """The node of each of ``times`` (s) within rounding of one (as :meth:`MeshGrid.snapped`),
        -1 for the others."""
        near, on = self.grid.nearest(times)
        return np.where(on, near, -1)

    def _attitude_state_columns(self) -> list:
        """:meth:`bvpnav.error_models.ErrorStates.attitude_columns` of this model's data, made once."""
        if "_att_cols" not in self.__dict__:
            self.__dict__["_att_cols"] = [as_csr(g) for g in self.state_model.attitude_columns(self.data)]
        return self.__dict__["_att_cols"]
