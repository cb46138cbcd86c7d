r"""Linear finite elements for r''(t) = a(t) on a non-uniform grid (pure scipy.sparse).

Weak form
---------
For every test function u,

.. math::

    \int_{T_0}^{T_1} \dot r \dot u \, dt
      = -\int_{T_0}^{T_1} a u \, dt + v(T_1) u(T_1) - v(T_0) u(T_0).

With hat functions for r, u and a (a interpolated linearly between samples) this is,
per axis, the N equations

.. math::

    K r + e_1 v_0 - e_N v_1 + M a = 0,

where ``K`` is the stiffness matrix (``1/h_{j-1} + 1/h_j`` on the diagonal, ``-1/h_j``
beside it, ``1/h`` at the two ends), ``M`` the consistent mass matrix
(``(h_{j-1} + h_j)/3`` on the diagonal, ``h_j/6`` beside it) and ``v_0``, ``v_1`` the
end velocities, which are unknowns of the system (natural boundary terms). The load
vector of the papers is ``f = -M a``. Summing all rows gives ``v_1 - v_0 = \int a``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .grid import TimeGrid, as_times

__all__ = [
    "stiffness",
    "mass",
    "load",
    "boundary_columns",
    "node_velocity_operators",
    "velocity_operators",
    "tridiagonal",
    "Condensation",
    "condensation",
]


def stiffness(grid: TimeGrid) -> sp.csr_matrix:
    """Stiffness matrix ``K[i, j] = integral(phi_i' phi_j')``, 1/s.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (N, N)
        Symmetric, tridiagonal, singular (constants are in its null space).
    """
    return tridiagonal(*_stiffness_diagonals(grid))


def _stiffness_diagonals(grid: TimeGrid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The diagonals ``(lower, diag, upper)`` (N - 1, N, N - 1) of :func:`stiffness`, 1/s,
    without the matrix."""
    inv = 1.0 / grid.h
    diag = np.zeros(grid.n)
    diag[:-1] += inv
    diag[1:] += inv
    return -inv, diag, -inv


def mass(grid: TimeGrid) -> sp.csr_matrix:
    """Consistent mass matrix ``M[i, j] = integral(phi_i phi_j)``, s.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (N, N)
        Symmetric positive definite, tridiagonal.
    """
    return tridiagonal(*_mass_diagonals(grid))


def _mass_diagonals(grid: TimeGrid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The diagonals ``(lower, diag, upper)`` (N - 1, N, N - 1) of :func:`mass`, s, without the
    matrix."""
    h = grid.h
    diag = np.zeros(grid.n)
    diag[:-1] += h / 3.0
    diag[1:] += h / 3.0
    return h / 6.0, diag, h / 6.0


def tridiagonal(lower: np.ndarray, diag: np.ndarray, upper: np.ndarray) -> sp.csr_matrix:
    """The (N, N) tridiagonal matrix (N >= 2) with these diagonals (N - 1, N, N - 1), made directly
    in CSR form with the index type scipy would choose (``scipy.sparse.diags`` goes through a
    DIA-to-CSR conversion, about five times slower at N = 1e6; 64-bit index arrays would be
    converted by the constructor, a third of the time). The diagonals are kept on the
    matrix as ``_bvpnav_diagonals`` (``(lower, diag, upper)``, read by
    :func:`bvpnav.linalg.lsq.fem_rows_by_diagonals` instead of extracting them again)."""
    n = diag.size
    itype = np.int32 if 3 * n < 2**31 else np.int64
    data = np.empty(3 * n - 2)
    cols = np.empty(3 * n - 2, dtype=itype)
    data[:2] = diag[0], upper[0]
    data[-2:] = lower[-1], diag[-1]
    cols[:2] = 0, 1
    cols[-2:] = n - 2, n - 1
    mid, mcols = data[2:-2].reshape(n - 2, 3), cols[2:-2].reshape(n - 2, 3)   # rows 1 .. n - 2
    mid[:, 0], mid[:, 1], mid[:, 2] = lower[:-1], diag[1:-1], upper[1:]
    mcols[:, 0] = np.arange(n - 2, dtype=itype)
    mcols[:, 1] = mcols[:, 0] + 1
    mcols[:, 2] = mcols[:, 0] + 2
    indptr = np.empty(n + 1, dtype=itype)
    indptr[:2] = 0, 2
    indptr[2:n] = np.arange(5, 3 * n - 3, 3, dtype=itype)
    indptr[n] = 3 * n - 2
    out = sp.csr_matrix((data, cols, indptr), shape=(n, n))
    out.has_canonical_format = True
    out._bvpnav_diagonals = (np.asarray(lower, dtype=float), np.asarray(diag, dtype=float),
                             np.asarray(upper, dtype=float))
    return out


def load(grid: TimeGrid, acc: np.ndarray) -> np.ndarray:
    r"""Load vector ``f = -M a`` of linearly interpolated samples, m/s.

    Parameters
    ----------
    grid : TimeGrid
    acc : ndarray, shape (N,) or (N, d)
        Acceleration samples in m/s^2.

    Notes
    -----
    .. math:: f_j = -\tfrac{h_{j-1}}{6}(a_{j-1} + 2a_j) - \tfrac{h_j}{6}(2a_j + a_{j+1})
    """
    return -(mass(grid) @ np.asarray(acc, dtype=float))


def boundary_columns(grid: TimeGrid) -> sp.csr_matrix:
    """Columns multiplying the end velocities ``(v_0, v_1)`` in the FEM rows.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (N, 2)
        ``+1`` at row 1 for ``v_0`` and ``-1`` at row N for ``v_1``.
    """
    n = grid.n
    return sp.csr_matrix(([1.0, -1.0], ([0, n - 1], [0, 1])), shape=(n, 2))


def node_velocity_operators(grid: TimeGrid) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
    r"""Operators giving nodal velocities ``v = Vr r + Va a + Vb [v0, v1]``.

    Returns
    -------
    Vr : csr_matrix, shape (N, N), 1/s
    Va : csr_matrix, shape (N, N), s
    Vb : csr_matrix, shape (N, 2), dimensionless

    Notes
    -----
    Interior node j uses the natural boundary term of the sub-domain ``[T_0, t_j]``:

    .. math:: v_j = \frac{r_j - r_{j-1}}{h_{j-1}} + \frac{h_{j-1}}{6}(a_{j-1} + 2a_j),

    which equals the same formula from the right (``[t_j, T_1]``) whenever FEM row j
    holds. It is exact when r is a cubic (a linear in t) and the nodal positions
    are exact, so it converges as O(h^2) with the FEM's nodal values. The end nodes
    return the unknowns ``v_0`` and ``v_1`` themselves, so a velocity condition at
    an end is exact.
    """
    return _node_velocity_rows(grid, np.arange(grid.n))


def velocity_operators(
    grid: TimeGrid, times, what: str = "time"
) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
    r"""Operators for the velocity at arbitrary times inside the window.

    Returns ``(Vr, Va, Vb)`` with ``len(times)`` rows, as in
    :func:`node_velocity_operators`.

    Notes
    -----
    For ``t = t_j + s`` inside element j the acceleration is linear, so

    .. math:: v(t) = v_j + a_j s + (a_{j+1} - a_j) \frac{s^2}{2 h_j}.

    Times on a node use the nodal rows directly (exact at the ends).
    """
    times = grid.check_inside(as_times(times, what), what)
    j, s = grid.locate(times)
    at_end = times >= grid.t1
    j = np.where(at_end, grid.n - 1, j)
    s = np.where(at_end, 0.0, s)
    m = times.size
    Vr, NVa, Vb = _node_velocity_rows(grid, j)
    inner = s > 0
    k = np.flatnonzero(inner)
    jj = j[k]
    hh = grid.h[np.minimum(jj, grid.n - 2)]
    ss = s[k]
    c1 = ss - ss**2 / (2.0 * hh)
    c2 = ss**2 / (2.0 * hh)
    extra = sp.csr_matrix(
        (np.concatenate([c1, c2]), (np.concatenate([k, k]), np.concatenate([jj, jj + 1]))),
        shape=(m, grid.n),
    )
    Va = NVa + extra
    return Vr.tocsr(), Va.tocsr(), Vb.tocsr()


def _node_velocity_rows(grid: TimeGrid, j: np.ndarray) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
    """Rows ``j`` of :func:`node_velocity_operators` (``len(j)`` rows, any nodes in any
    order), made from those nodes' elements alone: a few velocities cost O(len(j)), not
    O(N). Made directly in CSR form: two entries (columns j-1, j) per interior node's row
    (the element on its left), none at the ends, whose rows of ``Vb`` pick ``v0``, ``v1``."""
    n, m = grid.n, j.size
    interior = (j > 0) & (j < n - 1)
    jj = j[interior]
    h = grid.h[jj - 1]
    cols = np.column_stack([jj - 1, jj]).ravel()
    indptr = np.concatenate([[0], np.cumsum(2 * interior)])
    Vr = sp.csr_matrix((np.column_stack([-1.0 / h, 1.0 / h]).ravel(), cols, indptr), shape=(m, n))
    Va = sp.csr_matrix((np.column_stack([h / 6.0, h / 3.0]).ravel(), cols, indptr), shape=(m, n))
    e = np.flatnonzero(~interior)   # the ends: v0 and v1 themselves
    Vb = sp.csr_matrix((np.ones(e.size), (e, np.where(j[e] == 0, 0, 1))), shape=(m, 2))
    return Vr, Va, Vb


@dataclass(frozen=True, eq=False)
class Condensation:
    r"""The samples of a fine grid condensed onto a mesh of some of them (:func:`condensation`).

    Attributes
    ----------
    nodes : ndarray of int, shape (n,)
        Sample index of every mesh node (increasing, first and last sample included).
    Cp, Cq : scipy.sparse.csr_matrix, shape (n - 1, N), s
        Row ``e`` holds :math:`\int_{E_e} \phi_p \phi_i\,dt` (``Cp``) and
        :math:`\int_{E_e} \phi_q \phi_i\,dt` (``Cq``) over the samples ``i`` of element
        :math:`E_e = [t_p, t_q]` (``p = nodes[e]``, ``q = nodes[e + 1]``), with
        :math:`\phi_p, \phi_q` the coarse hats and :math:`\phi_i` the fine ones: ``Cp @ a``
        and ``Cq @ a`` are the element's loads on its two nodes for samples ``a``.
    load : scipy.sparse.csr_matrix, shape (n, N), s
        :math:`\Phi^T M_f`: node ``k`` gets ``Cp`` of the element on its right plus ``Cq``
        of the element on its left.
    interior : ndarray of int
        The samples strictly inside an element (no node).
    element : ndarray of int, shape (N,)
        The element of every sample (-1 at nodes).
    """

    nodes: np.ndarray
    Cp: sp.csr_matrix
    Cq: sp.csr_matrix
    load: sp.csr_matrix
    interior: np.ndarray
    element: np.ndarray


def condensation(grid: TimeGrid, nodes: np.ndarray) -> Condensation:
    r"""The condensation of the linear elements of ``grid`` onto the mesh of samples ``nodes``.

    Parameters
    ----------
    grid : TimeGrid
        The fine grid (every sample), times in s.
    nodes : ndarray of int
        Increasing sample indices, the first (0) and the last (N - 1) included.

    Returns
    -------
    Condensation

    Notes
    -----
    Write the fine nodal positions as :math:`r_f = \Phi r_c + z`, with :math:`\Phi` (N, n)
    the coarse hats at the samples (linear interpolation between nodes) and :math:`z` zero at
    the nodes. In 1-D, :math:`\Phi^T K_f \Phi = K_c` and :math:`\Phi^T K_f z = 0` (the coarse
    hats have a constant slope on each element and :math:`z` vanishes at its ends), and the
    boundary columns are the same, so :math:`\Phi^T` times the fine FEM rows is

    .. math:: K_c r_c + B v + \Phi^T M_f a = 0,

    exact for the nodal values whatever the samples between nodes are; the rows at the
    samples between nodes determine :math:`z` (one Dirichlet problem per element). The
    velocity at node :math:`q` from the element :math:`[t_p, t_q]` on its left is, by the
    weak form with the test function :math:`\phi_q` restricted to the element,

    .. math:: v_q = \frac{r_q - r_p}{H} + \int_{t_p}^{t_q} \phi_q a \, dt
              = \frac{r_q - r_p}{H} + (C_q a)_e ,

    the fine formula :math:`(r_q - r_{q-1})/h + h (a_{q-1} + 2 a_q)/6` when the fine rows
    between the nodes hold. Per fine step ``i`` (samples ``i``, ``i + 1``) of element ``e``
    with :math:`\theta = (t - t_p)/H` linear, the products of two linear functions integrate
    to :math:`\int \phi_q a = \tfrac{h_i}{6}\,[\theta_i (2 a_i + a_{i+1}) + \theta_{i+1}(a_i +
    2 a_{i+1})]` (``Cp`` with :math:`1 - \theta`).

    Examples
    --------
    Eleven samples, nodes at 0, 0.5 and 1 s: a constant acceleration of 1 m/s^2 loads each node
    with the integral of its hat function (0.25, 0.5, 0.25 m/s), as one coarse element would:

    >>> import numpy as np
    >>> from bvpnav.fem import condensation
    >>> from bvpnav.grid import TimeGrid
    >>> c = condensation(TimeGrid(np.linspace(0.0, 1.0, 11)), np.array([0, 5, 10]))
    >>> np.round(c.load @ np.ones(11), 12).tolist()
    [0.25, 0.5, 0.25]
    """
    t, h = grid.t, grid.h
    nodes = np.asarray(nodes, dtype=np.int64)
    N, n = grid.n, nodes.size
    step_elem = np.repeat(np.arange(n - 1), np.diff(nodes))          # element of fine step i
    tp, H = t[nodes[:-1]][step_elem], (t[nodes[1:]] - t[nodes[:-1]])[step_elem]
    th0 = (t[:-1] - tp) / H
    th1 = (t[1:] - tp) / H
    th1[nodes[1:] - 1] = 1.0            # the last step of an element ends on its right node
    th0[nodes[:-1]] = 0.0
    k6 = h / 6.0
    # written straight into canonical CSR arrays (no duplicates summed, no indices sorted): element
    # e's row holds its samples nodes[e] .. nodes[e + 1], sample j at entry j + e, so step i's two
    # samples at i + e and i + 1 + e, a sample inside the element getting its two steps' sum
    size = N + n - 2
    itype = np.int32 if size < 2**31 else np.int64
    elem = np.repeat(np.arange(n - 1), np.diff(nodes) + 1)      # the element (row) of every entry
    indices = (np.arange(size) - elem).astype(itype)
    indptr = (nodes + np.arange(n)).astype(itype)
    indptr[0] = 0
    at = np.arange(N - 1) + step_elem

    def element_rows(first: np.ndarray, second: np.ndarray) -> sp.csr_matrix:
        """The (n - 1, N) rows with step i's entries ``first[i]`` (at its first sample) and
        ``second[i]`` (at its second)."""
        vals = np.zeros(size)
        vals[at] = first
        vals[at + 1] += second
        out = sp.csr_matrix((vals, indices.copy(), indptr.copy()), shape=(n - 1, N))
        out.has_canonical_format = True
        return out

    Cq = element_rows(k6 * (2.0 * th0 + th1), k6 * (th0 + 2.0 * th1))
    Cp = element_rows(k6 * (2.0 * (1.0 - th0) + (1.0 - th1)), k6 * ((1.0 - th0) + 2.0 * (1.0 - th1)))
    # node k's row: the samples nodes[k - 1] .. nodes[k + 1], Cq of the element on its left and
    # Cp of the one on its right, node k's own sample the sum of the two
    lo = nodes[np.maximum(np.arange(n) - 1, 0)]
    width = nodes[np.minimum(np.arange(n) + 1, n - 1)] - lo + 1
    lptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(width, out=lptr[1:])
    m = int(lptr[-1])
    vals = np.zeros(m)
    vals[lptr[elem] + indices - lo[elem]] = Cp.data             # element e -> its left node e
    vals[lptr[elem + 1] + indices - nodes[elem]] += Cq.data     # element e -> its right node e + 1
    ltype = np.int32 if max(m, N) < 2**31 else np.int64
    lcols = (np.arange(m) + np.repeat(lo - lptr[:-1], width)).astype(ltype)
    load = sp.csr_matrix((vals, lcols, lptr.astype(ltype)), shape=(n, N))
    load.has_canonical_format = True
    element = np.full(N, -1, dtype=np.int64)
    is_node = np.zeros(N, dtype=bool)
    is_node[nodes] = True
    interior = np.flatnonzero(~is_node)
    element[interior] = step_elem[interior]   # sample i (not a node) is inside the element of step i
    return Condensation(nodes=nodes, Cp=Cp, Cq=Cq, load=load, interior=interior, element=element)
