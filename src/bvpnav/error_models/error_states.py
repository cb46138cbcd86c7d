r"""Error states at every node: attitude error and random-walk biases in the band.

Design (issue 42, item 2)
-------------------------
The knot models (``GyroBias(interval=..., drift=...)``, ``AttitudeWalk``, ``Bias(interval=...)``)
put a time-varying quantity into the error-model parameters ``l``: a gyro-bias knot changes
the attitude from its time to the end, so its column of the FEM rows is dense and it sits in
the *border* of the banded factorization (:mod:`bvpnav.linalg.banded`), one dense right-hand
side each. This model instead declares **node states**: at every sample ``j``

* :math:`\psi_j` (3, rad): the navigation-frame attitude error,
  :math:`C_j = \exp([\psi_j\times])\,\hat C_j` with :math:`\hat C` the attitude of the data
  (integrated from the raw gyro rates);
* :math:`b_{g,j}` (3, rad/s, optional): the gyro bias, body axes;
* :math:`b_{a,j}` (3, m/s^2, optional): the accelerometer bias, body axes (the sensor reads
  :math:`\hat f = f + b_a`).

They enter the FEM rows only at their own sample (acceleration
:math:`a_j = C_j(\hat f_j - b_{a,j}) + g`), and they are tied to their neighbours by the
discrete process model a factor graph writes per epoch, as soft rows (not scaled by
``lam``):

.. math::

    e_j = \mathrm{Log}\!\left(C_{j+1}\,\exp([\phi_j - h_j b_{g,j}]\times)^T C_j^T\right)
          \sim N(0, n_g^2 h_j I), \qquad
    b_{j+1} - b_j \sim N(0, q^2 h_j I),

with :math:`\phi_j` the step rotation vector of the raw rates
(:func:`bvpnav.attitude.step_rotation_vectors`; the bias held constant over the step, as
GTSAM's preintegration holds it) and :math:`n_g` the gyro's angle random walk. Every unknown
is then local in time: ``bvpnav.linalg.lsq.column_nodes`` puts the states at their
node (axes interleaved) and the banded factorization has only the constant parameters of
other components (e.g. a constant ``ScaleFactor``) in its border. A drift of 0 makes a
bias constant by hard rows :math:`b_{j+1} = b_j` (still local); ``None`` leaves the state
out.

Linearization. The states are nonlinear (the attitude multiplies the specific force), so a
problem with them is solved by Gauss-Newton steps (:func:`bvpnav.solve.attitude.with_attitude`
runs them): at the current totals (a ``StatePoint`` carried by the data) the convex
problem's state unknowns are the increments, a left rotation :math:`\varepsilon_j` of the
attitude (:math:`C_j \to \exp([\varepsilon_j\times]) C_j`) and additive bias increments.
The linearized rows are the exact first derivatives:

.. math::

    e_j \approx e_j^0 + J_l(e_j^0)^{-1}\varepsilon_{j+1} - J_r(e_j^0)^{-1}\varepsilon_j
          + J_l(e_j^0)^{-1} C_{j+1} J_r(\phi_j - h_j b_{g,j})\, h_j\, \delta b_{g,j},

and the acceleration changes by :math:`\varepsilon_j \times C_j(\hat f_j - b_{a,j})
- C_j\,\delta b_{a,j}`. The fixed point is the nonlinear optimum; each step is one banded
factorization.

Why a new model rather than a switch on ``GyroBias``/``AttitudeWalk``: the states replace
*three* knot models at once (the gyro bias only enters through the attitude process rows,
which need the attitude states), and a model that owns all of them can keep their layout
(node-major, interleaved axes) and their process rows together. The knot models stay for
data without a gyro and for the published tables that use them.

On a coarse mesh (``NavigationProblem(..., segment=...)``, :mod:`bvpnav.mesh`) the states sit at
the mesh's nodes (``data.state_mesh``, the node samples, set by the formulation). Inside
element :math:`[t_p, t_q]` the biases are linear in time, :math:`b_i = (1 - \theta_i) b_p +
\theta_i b_q` with :math:`\theta_i = (t_i - t_p)/H`, and the attitude is the node's integrated
with the corrected rates, :math:`C_i = C_p P_i`, :math:`P_i = \prod_{j=p}^{i-1}\exp([a_j\times])`,
:math:`a_j = \phi_j - h_j b_{g,j}` (each sample's bias held over its step, as above; the loop
re-integrates it at every step, ``updated``). The acceleration columns of every sample are
the exact first derivatives, condensed onto the nodes with the rest of the load:
:math:`\varepsilon_p \times f_{n,i}` for the attitude, :math:`-C_i\,\delta b_{a,i}` for the
accelerometer bias, and for the gyro bias :math:`C_i \to \exp([-C_p Y_i\,\delta b\times])\,C_i`
with :math:`Y_i = \sum_{j=p}^{i-1} P_{j+1} J_r(a_j)\, h_j\, w_j` (:math:`w_j = 1 - \theta_j` for
node p, :math:`\theta_j` for node q). With constant biases the truth zeroes every row, on the
mesh as on the samples. The process rows tie neighbouring nodes over the element (the
continuous-time model with :math:`H` for :math:`h`): the attitude residual uses the element's
product :math:`\Delta R = P_q` for :math:`\exp([a_j\times])`, and its gyro-bias Jacobian sums
the steps' terms,

.. math::

    \frac{\partial e}{\partial b_{g,p|q}} = J_l(e)^{-1} C_q \sum_{i=p}^{q-1} w_i\, D_i^T
        J_r(a_i)\, h_i, \qquad D_i = \prod_{k=i+1}^{q-1}\exp([a_k\times]),

GTSAM's bias Jacobian of the preintegrated rotation. With one step per element all of it is
the per-sample model.

Items reach the states only through :class:`~bvpnav.model.NavModel` accessors
(``attitude_error(t)``, ``gyro_bias(t)``, ``acc_bias(t)``, and ``body_rate(t)``, which
subtracts the gyro-bias states), never by index.
"""

from __future__ import annotations

import contextlib
import copy
import functools
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
import scipy.sparse as sp
from scipy.spatial.transform import Rotation

from ..errors import InputError
from ..imu import ImuData
from ._attitude import _check_strapdown_gyro, _skew, right_jacobian
from ._base import ErrorModel

__all__ = ["ErrorStates"]

#: The node states in their order within a node, with units.
KINDS = {"attitude_error": "rad", "gyro_bias": "rad/s", "acc_bias": "m/s^2"}


@dataclass(frozen=True, eq=False)
class StatePoint:
    """Totals of the node states where the problem is linearized.

    Attributes
    ----------
    raw : ImuData
        The data as measured (its attitude integrated from the raw rates).
    totals : dict of str to ndarray (N, 3)
        The current total of each state kind (rad; rad/s; m/s^2).
    cheap : _Cheap or None
        A cheap Gauss-Newton step's point (:func:`cheap_at`): the rows are made from the sums
        of the last full pass, not from the samples; ``totals`` then hold the biases at every
        sample and the attitude error made from the nodes on first read (:class:`_Totals`).
    """

    raw: Any
    totals: dict = field(default_factory=dict)
    cheap: Any = None


class _Totals(dict):
    """Totals kind -> (N, 3) at every sample, some made on first read: a Gauss-Newton point of the
    node-state loop is read at the mesh's nodes only (:func:`_node_totals`) unless something asks
    for its samples (the last point's frame, a row that reads the attitude between nodes), so
    the pass over the samples that makes them is made only then. Every way of reading it (``[]``,
    ``get``, ``items``, ``values``, a copy, ``dict(t)``, ``{**t}``, pickling) gives the made
    arrays; a kind assigned, removed or popped drops its maker (it is a dict of its values).

    Parameters
    ----------
    values : dict
        The totals already made, kind -> (N, 3).
    lazy : dict
        kind -> a function of no arguments that makes that kind's (N, 3) totals (called once).
    nodes : dict
        kind -> (n, 3): the lazy kinds' totals at the mesh's node samples (equal to the samples'
        there, bit for bit).
    """

    def __init__(self, values: dict, lazy: dict, nodes: dict):
        super().__init__(values)
        for kind in lazy:
            dict.__setitem__(self, kind, None)
        self._lazy = dict(lazy)
        self._nodes = dict(nodes)

    def __getitem__(self, kind):
        make = self._lazy.get(kind)
        if make is not None:   # made, stored, and only then no longer lazy (a failed make stays lazy)
            dict.__setitem__(self, kind, make())
            del self._lazy[kind]
            self._nodes.pop(kind, None)
        return dict.__getitem__(self, kind)

    def _forget(self, kind) -> None:
        """A kind given a new value or removed: its lazy maker and node values no longer hold."""
        self._lazy.pop(kind, None)
        self._nodes.pop(kind, None)

    def __setitem__(self, kind, value) -> None:
        self._forget(kind)
        dict.__setitem__(self, kind, value)

    def __delitem__(self, kind) -> None:
        self._forget(kind)
        dict.__delitem__(self, kind)

    def pop(self, kind, *default):
        if kind not in self:
            return dict.pop(self, kind, *default)
        value = self[kind]
        del self[kind]
        return value

    def popitem(self) -> tuple:
        if not len(self):
            raise KeyError("popitem(): totals are empty")
        kind = list(dict.keys(self))[-1]
        return kind, self.pop(kind)

    def setdefault(self, kind, default=None):
        if kind in self:
            return self[kind]
        self[kind] = default
        return default

    def update(self, *args, **kwargs) -> None:
        for kind, value in dict(*args, **kwargs).items():
            self[kind] = value

    def __ior__(self, other):
        self.update(other)
        return self

    def clear(self) -> None:
        self._lazy.clear()
        self._nodes.clear()
        dict.clear(self)

    def __iter__(self):   # not dict's own: a copy (dict(t), {**t}) then reads every value through []
        return iter(list(dict.keys(self)))

    def get(self, kind, default=None):
        return self[kind] if kind in self else default

    def items(self) -> list:
        return [(kind, self[kind]) for kind in self]

    def values(self) -> list:
        return [self[kind] for kind in self]

    def copy(self) -> dict:
        return {kind: self[kind] for kind in self}

    def __reduce__(self):
        return dict, (self.copy(),)

    def at_nodes(self, kind: str, mesh: np.ndarray) -> np.ndarray:
        """``self[kind][mesh]`` (a new array), without making the samples of a lazy kind."""
        if kind in self._lazy:
            return self._nodes[kind].copy()
        return self[kind][mesh]


def _node_totals(data, kind: str) -> np.ndarray:
    """``_totals(data, kind)`` at the coarse mesh's node samples (n, 3), without the samples of a
    point whose totals are made on first read (:class:`_Totals`)."""
    mesh = _mesh(data)
    p = getattr(data, "state_point", None)
    if p is None or kind not in p.totals:
        return np.zeros((mesh.size, 3))
    if isinstance(p.totals, _Totals):
        return p.totals.at_nodes(kind, mesh)
    return p.totals[kind][mesh]


def _csr(data: np.ndarray, indices: np.ndarray, indptr: np.ndarray, shape: tuple) -> sp.csr_matrix:
    """A CSR matrix on its arrays (canonical ones: sorted, no duplicates; the loop's steps may
    share the index arrays, which no reader changes in place)."""
    return sp.csr_matrix((data, indices, indptr), shape=shape)


def _pattern(indices: np.ndarray, indptr: np.ndarray, shape: tuple) -> sp.csr_matrix:
    """A canonical CSR pattern (its values zeros) for :func:`_with_values`: kept, never handed out."""
    out = _csr(np.zeros(indices.size), indices, indptr, shape)
    out.has_canonical_format = True
    return out


def _with_values(pattern: sp.csr_matrix, data: np.ndarray) -> sp.csr_matrix:
    """The matrix of ``pattern`` (:func:`_pattern`) with the values ``data``: a shallow copy
    sharing its index arrays (scipy's checks of them, made once for the pattern, are not run
    again at every Gauss-Newton step)."""
    out = copy.copy(pattern)
    out.data = data
    return out


def _raw(data):
    p = getattr(data, "state_point", None)
    return data if p is None else p.raw


#: The rows' patterns :meth:`ErrorStates.terms` keeps for the node-state loops running now whose
#: measured data is the user's own (no mesh: it is never written to), by ``id`` of that data:
#: ``(data, kept)``, for the loop's lifetime (:func:`kept_rows`).
_LOOP_ROWS: dict[int, tuple[Any, dict]] = {}


@contextlib.contextmanager
def kept_rows(raw) -> Iterator[None]:
    """Keep :meth:`ErrorStates.terms`' patterns of the rows made on the measured data ``raw``
    (and the points made from it) while the ``with`` block runs, then drop them: the node-state
    loop's steps share them. On a coarse mesh they are kept on the formulation's copy of the
    data (``state_mesh``) instead; the user's own data is never written to."""
    if getattr(raw, "state_mesh", None) is not None or id(raw) in _LOOP_ROWS:
        yield
        return
    _LOOP_ROWS[id(raw)] = (raw, {})
    try:
        yield
    finally:
        _LOOP_ROWS.pop(id(raw), None)


def _kept_rows(raw) -> dict:
    """Where :meth:`ErrorStates.terms` keeps its rows' patterns for ``raw``: on the formulation's
    copy of the data (a mesh), a running loop's (:func:`kept_rows`), else a new dict (kept
    nowhere)."""
    if getattr(raw, "state_mesh", None) is not None:
        return raw.__dict__.setdefault("_state_rows", {})
    kept = _LOOP_ROWS.get(id(raw))
    return kept[1] if kept is not None and kept[0] is raw else {}


def _totals(data, kind: str) -> np.ndarray:
    p = getattr(data, "state_point", None)
    if p is None or kind not in p.totals:
        return np.zeros((data.n, 3))
    return p.totals[kind]


def _compose(p: Rotation, q: Rotation) -> Rotation:
    """``p * q`` for equal-length rotations by the quaternion product written out (scipy's
    ``__mul__`` takes several times longer at these lengths; the same product to rounding)."""
    return Rotation.from_quat(_quat_product(p.as_quat(), q.as_quat()))


def _rotvec(q: np.ndarray) -> np.ndarray:
    r"""The rotation vectors (M, 3), rad, of quaternions ``q`` (M, 4, scalar last, of any norm):
    :math:`\theta\,\hat v` with :math:`\theta = 2\,\mathrm{atan2}(|v|, w)` on the hemisphere
    :math:`w \ge 0` (scipy's ``Rotation.from_quat(q).as_rotvec()`` without the rotation object;
    the scale :math:`\theta / \sin(\theta/2)` by its series below 1e-3 rad)."""
    return _rotvec_components(np.asarray(q, dtype=float).T)


def _rotvec_components(q: np.ndarray) -> np.ndarray:
    """:func:`_rotvec` of quaternions stored components first, (4, M) (x, y, z, w): the rotation
    vectors (M, 3), rad, each component computed on contiguous arrays."""
    q = q / np.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    q *= np.where(q[3] < 0.0, -1.0, 1.0)
    v = q[:3]
    angle = 2.0 * np.arctan2(np.sqrt(v[0] ** 2 + v[1] ** 2 + v[2] ** 2), q[3])
    small = angle <= 1e-3
    a2 = angle**2
    scale = np.where(small, 2.0 + a2 / 12.0 + 7.0 * a2**2 / 2880.0,
                     angle / np.sin(0.5 * np.where(small, 1.0, angle)))
    return np.ascontiguousarray((scale * v).T)


def _inverse_jacobian(phi: np.ndarray, sign: float) -> np.ndarray:
    r"""Inverse SO(3) Jacobian, (..., 3, 3): :math:`J_l^{-1}` (``sign`` +1) or :math:`J_r^{-1}`
    (-1) in closed form, :math:`I - \tfrac{s}{2}[\phi\times] + c\,[\phi\times]^2` with
    :math:`c = 1/\theta^2 - (1 + \cos\theta)/(2\theta\sin\theta)` (its series
    :math:`1/12 + \theta^2/720 + \theta^4/30240` below 1e-2 rad, where the difference loses
    digits); singular at :math:`\theta = \pi`, as the Jacobian."""
    S, Q = _inverse_jacobian_parts(phi)
    return np.eye(3) - 0.5 * sign * S + Q


def _inverse_jacobian_parts(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""``([phi x], c [phi x]^2)`` of :func:`_inverse_jacobian`."""
    phi = np.asarray(phi, dtype=float)
    th2 = np.sum(phi**2, axis=-1)
    th = np.sqrt(th2)
    small = th < 1e-2
    safe = np.where(small, 1.0, th)
    c = np.where(small, 1.0 / 12.0 + th2 / 720.0 + th2**2 / 30240.0,
                 1.0 / safe**2 - (1.0 + np.cos(safe)) / (2.0 * safe * np.sin(safe)))
    S = _skew(phi)
    return S, c[..., None, None] * (S @ S)


def _inverse_jacobians(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r""":math:`(J_l^{-1}, J_r^{-1})` of :func:`_inverse_jacobian` (the same values) from one
    :math:`[\phi\times]` and its square."""
    S, Q = _inverse_jacobian_parts(phi)
    A = 0.5 * S
    eye = np.eye(3)
    return eye - A + Q, eye + A + Q


def _mesh(data) -> np.ndarray | None:
    """The node samples carrying the states on a coarse mesh (``state_mesh`` of the data as
    measured, set by :class:`~bvpnav.formulation.Formulation` for ``segment=``), or None: every
    sample is a node."""
    return getattr(_raw(data), "state_mesh", None)


def _hats(data, nodes_only: bool = False) -> sp.csr_matrix:
    """The mesh's hat functions at the samples, (N, n): biases linear between nodes; with
    ``nodes_only`` their rows at the node samples (n, n: a product with them gives the samples'
    values there, bit for bit)."""
    from ..grid import TimeGrid

    raw = _raw(data)
    mesh = _mesh(data)
    kept = raw.__dict__.get("_mesh_hats")
    if kept is None or kept[0] is not mesh:
        t = np.asarray(data.t, dtype=float)
        out = TimeGrid(t[mesh]).interpolation_matrix(t)
        kept = raw.__dict__["_mesh_hats"] = (mesh, out, out[mesh])
    return kept[2] if nodes_only else kept[1]


#: Steps per block of :meth:`_Elements._write_steps`: its per-step arrays (the rotation matrices,
#: the right Jacobians and their intermediates) are made for this many steps at a time.
STEP_BLOCK = 8192


@dataclass(eq=False)
class _Elements:
    """A coarse mesh's elements at a point: per sample its element's left node ``left`` and
    ``theta`` (0 at nodes); per step ``a`` (the corrected step rotations, rad), ``Sc`` (the
    product of the element's steps up to and including this one, as unit quaternions stored
    components first, (4, N - 1): x, y, z, w) and ``h`` (the step, s). ``spare``: the largest
    arrays of the elements this one replaced (:func:`_elements`), memory for its own
    (:attr:`weighted`, :attr:`Zc`): a Gauss-Newton pass then writes them into pages it already
    has instead of fresh ones the process must fault in."""

    left: np.ndarray
    theta: np.ndarray
    a: np.ndarray
    Sc: np.ndarray

    h: np.ndarray
    spare: dict = field(default_factory=dict)

    def _memory(self, name: str, shape: tuple) -> np.ndarray:
        """The spare array ``name`` when it has ``shape`` (taken: used once), else a new one."""
        out = self.spare.pop(name, None)
        return out if out is not None and out.shape == shape else np.empty(shape)

    @functools.cached_property
    def Zc(self) -> np.ndarray:
        """:math:`S_j J_r(a_j) h_j` of every step, component-major (9, N - 1) (s; row-major 3 x 3,
        each entry contiguous over the steps): :meth:`_write_steps` (:attr:`weighted` writes it
        into its own memory instead; this is for :attr:`Z`)."""
        m = self.a.shape[0]
        out = self._memory("Zc", (9, m))
        self._write_steps(out.reshape(3, 3, m))
        return out

    def _write_steps(self, out: np.ndarray) -> None:
        """:attr:`Zc` written into ``out`` (3, 3, N - 1), a view allowed: entry by entry on the
        steps' arrays (:func:`_right_jacobian_components`, :func:`_matrix_components`), block by
        block of :data:`STEP_BLOCK` steps (every operation is per step: the same numbers as on all
        steps at once, with the blocks' arrays in place of the whole pass's), as the running sums
        and the process rows read it."""
        m = out.shape[2]
        tmp = np.empty(min(m, STEP_BLOCK))
        for lo in range(0, m, STEP_BLOCK):
            hi = min(lo + STEP_BLOCK, m)
            J = _right_jacobian_components(self.a[lo:hi])
            S = _matrix_components(self.Sc[:, lo:hi])
            h, t = self.h[lo:hi], tmp[:hi - lo]
            for k in range(3):
                for c in range(3):
                    o = out[k, c, lo:hi]
                    np.multiply(S[k, 0], J[0, c], out=o)
                    np.multiply(S[k, 1], J[1, c], out=t)
                    o += t
                    np.multiply(S[k, 2], J[2, c], out=t)
                    o += t
                    o *= h

    @functools.cached_property
    def weighted(self) -> np.ndarray:
        r""":attr:`Zc` weighted for the element's left and right node, :math:`(1 - \theta_j) Z_j` and
        :math:`\theta_j Z_j`, (2, 9, N) (s): step ``j`` in column ``j + 1``, column 0 zero (the
        layout of :func:`_gyro_sums`' running sums, which are taken in this memory, in place, and
        drop it). :attr:`Zc` is written into the left node's half and weighted there in place
        (the same products) unless it was made already."""
        th = self.theta[:-1]
        m = self.a.shape[0]
        out = self._memory("weighted", (2, 9, m + 1))
        out[:, :, 0] = 0.0
        Z = self.__dict__.get("Zc")
        if Z is None:
            Z = out[0, :, 1:]
            self._write_steps(out.reshape(2, 3, 3, m + 1)[0, :, :, 1:])
            np.multiply(Z, th, out=out[1, :, 1:])
            Z *= 1.0 - th
        else:
            np.multiply(Z, 1.0 - th, out=out[0, :, 1:])
            np.multiply(Z, th, out=out[1, :, 1:])
        return out

    @functools.cached_property
    def element_sums(self) -> tuple[np.ndarray, np.ndarray]:
        r"""The sums of :attr:`weighted` over every element's steps, (9, n - 1) each (s): the process
        rows' bias terms (:func:`_mesh_process`), and what restarts :func:`_gyro_sums` at the nodes."""
        start = np.flatnonzero(np.r_[True, self.left[1:-1] != self.left[:-2]])
        return tuple(np.add.reduceat(z[:, 1:], start, axis=1) for z in self.weighted)

    @property
    def Z(self) -> np.ndarray:
        """:math:`S_j J_r(a_j) h_j` of every step, (N - 1, 3, 3) (s): :attr:`Zc` sample-major (a view)."""
        return self.Zc.T.reshape(-1, 3, 3)


def _block_acceleration(out: np.ndarray, tmp: np.ndarray, left: np.ndarray, th: np.ndarray, rot: Rotation,
                        f: np.ndarray, att: np.ndarray, node: dict, Y2: np.ndarray | None,
                        Cn: np.ndarray | None) -> None:
    r""":meth:`ErrorStates.state_acceleration` on a coarse mesh at a block of ``b`` samples, written
    into ``out`` (3, b): the samples' element's left nodes ``left`` and ``theta``, their attitude
    ``rot`` and specific force ``f`` (3, b); the node values ``att`` (the attitude increments, 3 x
    n) and ``node`` (kind and (kind, 1): a bias's increments at the left and the right node, 3 x
    n), the running sums ``Y2`` (2, 3, 3, b) and the nodes' matrices ``Cn`` (9, n) with gyro-bias
    states. ``tmp``: scratch of b. The products on component arrays, summed in the order
    ``Rotation.apply`` and ``numpy.einsum`` sum them."""
    b = out.shape[1]

    def rotated(M, v: np.ndarray, order: tuple = (0, 2, 1)) -> np.ndarray:
        """``M v`` per sample: ``M(k)`` the row-major 3 x 3 entry ``k`` at every sample (b,),
        ``v`` (3, b), the products summed in ``order`` (``Rotation.apply``'s:
        ``(m0 v0 + m2 v2) + m1 v1``)."""
        r = np.empty((3, b))
        p, q, w = order
        for i in range(3):
            np.multiply(M(3 * i + p), v[p], out=r[i])
            np.multiply(M(3 * i + q), v[q], out=tmp)
            r[i] += tmp
            np.multiply(M(3 * i + w), v[w], out=tmp)
            r[i] += tmp
        return r

    def crossed(a: np.ndarray, c: np.ndarray, into: np.ndarray | None = None) -> np.ndarray:
        """``a x c`` per sample, ``a``, ``c`` (3, b) (``numpy.cross``'s products), or ``into``
        plus it."""
        x = np.empty((3, b))
        for i in range(3):
            j, k = (i + 1) % 3, (i + 2) % 3
            np.multiply(a[j], c[k], out=x[i])
            np.multiply(a[k], c[j], out=tmp)
            x[i] -= tmp
        if into is not None:
            into += x
        return x if into is None else into

    def carried(Y: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``Y v`` per sample, ``Y`` (3, 3, b), ``v`` (3, b): einsum ``"jcn,nc->nj"``'s sums."""
        part = np.empty((3, b))
        for j in range(3):
            np.multiply(Y[j, 0], v[0], out=part[j])
            for c in (1, 2):
                np.multiply(Y[j, c], v[c], out=tmp)
                part[j] += tmp
        return part

    def spread(V: np.ndarray) -> np.ndarray:
        """Node values ``V`` (..., n nodes) at the block's samples (their element's), (..., b)."""
        return np.take(V, left, axis=-1)

    C = rot.as_matrix().reshape(b, 9).T   # C_i, (9, b)
    fn = rotated(C.__getitem__, f)        # C_i f_i
    out[...] = crossed(spread(att), fn)
    if "acc_bias" in node:   # C_i ((1 - theta) B_p + theta B_q)
        v = spread(node["acc_bias"])
        v *= 1.0 - th
        w = spread(node[("acc_bias", 1)])
        w *= th
        v += w
        out -= rotated(C.__getitem__, v)
    if Y2 is not None:
        u = carried(Y2[0], spread(node["gyro_bias"]))
        u += carried(Y2[1], spread(node[("gyro_bias", 1)]))
        # C_p (the element's left node's, an entry at a time) u, summed in the order of the
        # products' columns
        crossed(fn, rotated(lambda k: spread(Cn[k]), u, (0, 1, 2)), out)


def _right_jacobian_components(phi: np.ndarray) -> np.ndarray:
    r""":func:`~bvpnav.error_models._attitude.right_jacobian` of the rotation vectors ``phi`` (M, 3),
    component-major (3, 3, M): :math:`I - a\,[\phi\times] + b\,[\phi\times]^2` with the same
    coefficients and series (below 1e-4 rad), each entry computed on contiguous arrays of the M
    vectors (no per-vector 3 x 3 blocks)."""
    p = np.ascontiguousarray(np.asarray(phi, dtype=float).T)
    m = p.shape[1]
    th2 = p[0] ** 2 + p[1] ** 2 + p[2] ** 2
    th = np.sqrt(th2)
    small = th < 1e-4
    safe = np.where(small, 1.0, th)
    a = np.where(small, 0.5 - th2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    b = np.where(small, 1.0 / 6.0 - th2 / 120.0, (safe - np.sin(safe)) / safe**3)
    d = 1.0 - b * th2
    out = np.empty((3, 3, m))
    for k in range(3):
        bk = b * p[k]
        for c in range(3):
            np.multiply(bk, p[c], out=out[k, c])
        out[k, k] += d
    # - a [phi x]: [phi x] = [[0, -z, y], [z, 0, -x], [-y, x, 0]]
    for k, c, comp, sgn in ((0, 1, 2, 1.0), (0, 2, 1, -1.0), (1, 0, 2, -1.0), (1, 2, 0, 1.0),
                            (2, 0, 1, 1.0), (2, 1, 0, -1.0)):
        out[k, c] += sgn * (a * p[comp])
    return out


def _unit_components(q: np.ndarray) -> np.ndarray:
    """Quaternions stored components first, (4, M), divided by their norms in place: the
    quaternions scipy's ``Rotation.from_quat`` keeps (its norm and division, so ``as_quat``
    of that rotation is this, bit for bit), without the rotation object."""
    q /= np.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return q


def _matrix_components(q: np.ndarray) -> np.ndarray:
    r"""The rotation matrices of unit quaternions stored components first, ``q`` (4, M),
    component-major (3, 3, M): scipy's ``Rotation.as_matrix`` written out entry by entry on
    the components' arrays (its products and sums in its order: the same matrices, bit for
    bit), with no (M, 3, 3) array to transpose."""
    x, y, z, w = q
    x2, y2, z2, w2 = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    out = np.empty((3, 3, q.shape[1]))
    out[0, 0] = x2 - y2 - z2 + w2
    out[1, 0] = 2 * (xy + zw)
    out[2, 0] = 2 * (xz - yw)
    out[0, 1] = 2 * (xy - zw)
    out[1, 1] = - x2 + y2 - z2 + w2
    out[2, 1] = 2 * (yz + xw)
    out[0, 2] = 2 * (xz + yw)
    out[1, 2] = 2 * (yz - xw)
    out[2, 2] = - x2 - y2 + z2 + w2
    return out


def _index_type(size: int, m: int, w: int) -> type:
    """The integer type of the kept index arrays of :meth:`ErrorStates.terms`' process rows:
    int32 when every stored index fits (the columns, below ``size``; the attitude rows' pointers,
    up to their ``3 m w`` entries, ``m`` elements of ``w`` entries per row; the bias walks' up to
    ``6 m``), else int64."""
    return np.int32 if max(int(size), 3 * int(m) * int(w), 6 * int(m)) < 2**31 else np.int64


def _block_order(kinds: list) -> list:
    """The order of a mesh element's state blocks, ``(kind, right node?)``: every kind at the left
    node, then the biases at the right node (the attitude error is carried from the left node)."""
    return [(kind, 0) for kind in kinds] + [(kind, 1) for kind in kinds if kind != "attitude_error"]


def _elements(data, mesh: np.ndarray, bg: np.ndarray) -> _Elements:
    """:class:`_Elements` with the gyro-bias totals ``bg`` (N, 3) at the samples; the last one kept
    on the measured data (it depends on nothing else): the state columns and process rows of a
    point share it, and so does the next step's point with the one :meth:`ErrorStates.updated`
    made."""
    raw = _raw(data)
    kept = raw.__dict__.get("_mesh_elements")
    if kept is not None and kept[0] is mesh and (kept[1] is bg or np.array_equal(kept[1], bg)):
        return kept[2]
    el = _make_elements(data, mesh, bg)
    if kept is not None:   # the replaced elements' largest arrays (read only while it was kept): el's memory
        old = kept[2].__dict__
        for name, key in (("Zc", "Zc"), ("weighted", "_gyro_sums")):
            if key in old:
                el.spare[name] = old.pop(key)
    raw.__dict__["_mesh_elements"] = (mesh, np.array(bg), el)
    return el


def _make_elements(data, mesh: np.ndarray, bg: np.ndarray) -> _Elements:
    from ..attitude import step_rotation_vectors

    raw = _raw(data)
    t = np.asarray(raw.t, dtype=float)
    n = t.size
    kept = raw.__dict__.get("_mesh_left")          # of the mesh only: the same at every point
    if kept is not None and kept[0] is mesh:
        left, theta, h, start, layout = kept[1]
    else:
        left = np.minimum(np.searchsorted(mesh, np.arange(n), side="right") - 1, mesh.size - 1)
        theta = np.zeros(n)
        inner = left < mesh.size - 1
        theta[inner] = (t[inner] - t[mesh[left[inner]]]) / np.diff(t[mesh])[left[inner]]
        h, start = np.diff(t), mesh[left[:-1]]
        layout = _scan_layout(start)
        raw.__dict__["_mesh_left"] = (mesh, (left, theta, h, start, layout))
    phi = raw.__dict__.get("_step_rotations")      # of the measured rates: the same at every point
    if phi is None:
        phi = raw.__dict__["_step_rotations"] = step_rotation_vectors(t, np.asarray(raw.gyro, dtype=float))
    a = phi - h[:, None] * bg[:-1]
    return _Elements(left, theta, a, _segment_products(Rotation.from_rotvec(a).as_quat(), start, layout), h)


def _gyro_sums(el: _Elements, mesh: np.ndarray) -> np.ndarray:
    r"""The running sums :math:`Y_i` of the gyro-bias columns (module Notes) for the left and
    the right node of every sample's element, component-major (2, 9, N) (s; row-major 3 x 3
    per sample): :math:`\sum_{p \le j < i} w_j P_{j+1} J_r(a_j) h_j` with :math:`w_j = 1 -
    \theta_j` and :math:`\theta_j` (contiguous cumulative sums, restarted at every node); kept
    on the elements (the condensed columns and the trajectory of one point share them)."""
    kept = el.__dict__.get("_gyro_sums")
    if kept is not None:
        return kept
    n = el.left.size
    if mesh[0] != 0 or mesh[-1] != n - 1:   # pragma: no cover - mesh_nodes keeps both ends
        raise ValueError("node states: a coarse mesh must have nodes at the first and the last sample")
    sums = el.element_sums
    Y2 = el.weighted                       # step j in column j + 1, column 0 zero: summed in place
    for Y, total in zip(Y2, sums, strict=True):
        Y[:, mesh[1:]] -= total            # each element's sum taken off at its last step: the
        np.cumsum(Y, axis=1, out=Y)        # running sums restart at every node
    Y2[:, :, mesh] = 0.0                   # exactly (not to rounding) at the nodes
    del el.weighted                        # summed in place
    el.__dict__["_gyro_sums"] = Y2
    return Y2


def _scan_layout(start: np.ndarray) -> tuple | None:
    """Where :func:`_segment_products`' padded scan puts every step (elements whose first steps are
    ``start``, ascending): ``(ne, nb, B, flat)``, ``flat`` the step's place in a (B, nb, ne) array
    (position in the block, block, element: the elements vary fastest, so every composition of
    the scan runs on contiguous runs of them), or None when the elements' lengths differ too much
    for the padding (the indexed scan then). Of the mesh alone: kept with it."""
    m = start.shape[0]
    if not m:
        return None
    first = np.flatnonzero(np.r_[True, start[1:] != start[:-1]])
    lens = np.diff(np.r_[first, m])
    if first.size * int(lens.max()) > 1.5 * m:
        return None
    ne, L = first.size, int(lens.max())
    B = max(1, int(np.ceil(np.sqrt(L))))
    nb = -(-L // B)
    row, pos = np.repeat(np.arange(ne), lens), np.arange(m) - np.repeat(first, lens)
    return ne, nb, B, ((pos % B) * nb + pos // B) * ne + row


def _segment_products(steps: np.ndarray, start: np.ndarray, layout: tuple | None | bool = False
                      ) -> np.ndarray:
    """``R_s ... R_i`` for every step ``i`` (quaternions ``steps``, (M, 4)) from the first step
    ``start[i]`` of its element, as unit quaternions stored components first, (4, M)
    (:func:`_unit_components`): a segmented parallel prefix scan (log2 of the longest element
    vectorised compositions). The steps of an element are contiguous (``start`` ascends): when
    the elements are of similar lengths the products run on a (B, elements, blocks) array per
    component padded with identities (blocks of B, about the square root of the longest element,
    :func:`_scan_layout`; ``layout`` its answer when kept, else made here): running products
    within every block, then of the blocks' totals, then each block's from the totals before it
    (about two compositions per step in all, in vectorised slices; the same products grouped
    otherwise, equal to rounding)."""
    if layout is False:
        layout = _scan_layout(start)
    if layout is not None:
        ne, nb, B, flat = layout
        Q = np.zeros((4, B, nb, ne))               # components first; position in the block next
        Q[3] = 1.0
        Qf = Q.reshape(4, -1)
        Qf[:, flat] = steps.T
        for j in range(1, B):                      # within the blocks
            Q[:, j] = _quat_components_product(Q[:, j - 1], Q[:, j])
        T = Q[:, B - 1].copy()                     # the blocks' totals, then their running products
        for b in range(1, nb):
            T[:, b] = _quat_components_product(T[:, b - 1], T[:, b])
        if nb > 1:
            Q[:, :, 1:] = _quat_components_product(T[:, None, :-1], Q[:, :, 1:])
        return _unit_components(np.take(Qf, flat, axis=1))   # C order (an index on axis 1 is not)
    q = steps.copy()
    idx = np.arange(q.shape[0])
    off = 1
    while True:
        take = np.flatnonzero(idx - off >= start)
        if not take.size:
            break
        q[take] = _quat_product(q[take - off], q[take])
        off *= 2
    return _unit_components(np.ascontiguousarray(q.T))


def _quat_components_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`_quat_product` on quaternions stored components first, ``(4, ...)`` (x, y, z, w):
    each component written into the result in place (the sums in the order
    ``(aw bx + bw ax) + (ay bz - az by)``)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    tmp = np.empty(out.shape[1:])
    for o, (p, q, u, v, w, z) in zip(out[:3], ((bx, ax, ay, bz, az, by), (by, ay, az, bx, ax, bz),
                                              (bz, az, ax, by, ay, bx)), strict=True):
        np.multiply(aw, p, out=o)
        np.multiply(bw, q, out=tmp)
        o += tmp
        np.multiply(u, v, out=tmp)
        tmp -= w * z
        o += tmp
    np.multiply(ax, bx, out=tmp)
    tmp += ay * by
    tmp += az * bz
    np.multiply(aw, bw, out=out[3])
    out[3] -= tmp
    return out


def _quat_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The quaternion products ``a b`` (scalar last, (M, 4)) of :func:`_compose`, on the arrays
    (no rotation objects made and normalized between the steps of a scan)."""
    return _quat_components_product(a.T, b.T).T


def _point_attitude(raw, totals: dict) -> tuple:
    """``(totals, attitude)`` of :func:`states_at`: the totals as (N, 3) arrays (``totals`` itself
    when the last :meth:`ErrorStates.expand` made it) and the attitude at them (that expand's, or
    the data's composed with the attitude error)."""
    made = raw.__dict__.get("_expanded_attitude")   # (totals, their attitude) of the last expand
    if made is not None and totals is made[0]:   # (N, 3) arrays, the attitude error made on first read
        # C_i as expand re-integrated it (to rounding the same), normalized as Rotation.from_quat
        # normalizes (_unit_components: the same quaternions) on the components' contiguous arrays
        q = np.ascontiguousarray(_unit_components(np.array(made[1].T)).T)
        return totals, Rotation(q, normalize=False)
    n = raw.n
    tot = {k: np.asarray(v, dtype=float).reshape(n, 3) for k, v in totals.items()}
    att = raw.attitude
    if "attitude_error" in tot:
        att = _compose(Rotation.from_rotvec(tot["attitude_error"]), att)
    return tot, att


def attitude_at(data, totals: dict) -> Rotation:
    """The attitude of :func:`states_at` ``(data, totals).attitude``, without the data made at it."""
    return _point_attitude(_raw(data), totals)[1]


class _PointData(ImuData):
    """The data of a node-state linearization point (:func:`states_at`): its strapdown keeps the
    specific force in the navigation frame it made the accelerations of, for
    :meth:`ErrorStates.condensed_columns` (:func:`_rotated_force`) to read instead of making it
    again (until then only: it is read once)."""

    def _navigation_force(self, rot: Rotation, f: np.ndarray) -> np.ndarray:
        fn = rot.apply(f)
        # one list for this data and its shallow copies (a formulation's): emptied when read
        self.__dict__["_kept_navigation_force"] = [rot, f, fn]
        return fn


def _rotated_force(data) -> tuple[np.ndarray, np.ndarray]:
    """``(C, C f)`` at the data's point: the attitude's matrices (N, 3, 3) and the specific force
    in the navigation frame (N, 3), m/s^2, the latter the one the strapdown of a
    :class:`_PointData` kept when it is of its attitude and specific force (taken: read once;
    ``Rotation.apply`` is the product of these matrices, the same sums), else made here."""
    kept = data.__dict__.pop("_kept_navigation_force", None)
    C = data.attitude.as_matrix()
    if kept:
        rot, f, fn = kept
        kept.clear()
        if rot is data.attitude and f is data.specific_force:
            return C, fn
    return C, np.einsum("nij,nj->ni", C, data.specific_force)


def states_at(data, totals: dict):
    r"""The measured data re-linearized at the node-state ``totals`` (kind -> (N, 3)): attitude
    :math:`\exp([\psi\times])\hat C`, specific force :math:`\hat f - b_a`, ``state_point`` set."""
    raw = _raw(data)
    tot, att = _point_attitude(raw, totals)
    f = raw.specific_force - tot["acc_bias"] if "acc_bias" in tot else raw.specific_force
    # on a coarse mesh the condensed columns read the strapdown's C f (_PointData); without one
    # nothing would, and the data would carry it for its lifetime
    kind = ImuData if _mesh(raw) is None else _PointData
    out = kind(raw.t, specific_force=f, attitude=att, gravity=raw.gravity, axes=raw.axes,
               time_origin=raw.time_origin, checks=False)
    out.checks = dict(raw.checks)
    out.gyro = raw.gyro
    out.state_point = StatePoint(raw=raw, totals=tot)
    return out


@dataclass(eq=False)
class _Cheap:
    r"""A cheap step's point relative to ``ref``, the data of the last full pass (whose per-element
    sums it reads): per mesh node the rotation ``rot`` (n, 3, 3) that takes the reference's node
    attitude to this point's, :math:`R_p = C_p \bar C_p^T`, and the bias changes ``dbg``, ``dba``
    (n, 3; rad/s, m/s^2)."""

    ref: Any
    rot: np.ndarray
    dbg: np.ndarray
    dba: np.ndarray


def _cheap(data) -> _Cheap | None:
    return getattr(getattr(data, "state_point", None), "cheap", None)


def cheap_error(data, nodes: dict) -> float:
    r"""The relative size, rad, of what a cheap step (:func:`cheap_at`) from ``data``'s point (a
    full pass) to the node totals ``nodes`` (kind -> (n, 3) at a coarse mesh's nodes) leaves
    out: :math:`\rho_g (\rho_g / 2 + \rho_a)` with :math:`\rho_g = \max_e H_e \max(|\Delta
    b_{g,p}|, |\Delta b_{g,q}|)` the largest rotation the gyro-bias change makes over an
    element (taken to first order: its second-order term) and :math:`\rho_a = \max_p |\Delta
    b_{a,p}| / |g|` the tilt an accelerometer-bias change is equivalent to (its product with the
    gyro-bias change is left out of the sums). 0 without gyro-bias states (the cheap step is
    then exact); inf without a mesh."""
    mesh = _mesh(data)
    if mesh is None:
        return float("inf")
    if "gyro_bias" not in nodes:
        return 0.0
    raw = _raw(data)
    db = np.linalg.norm(np.asarray(nodes["gyro_bias"]) - _node_totals(data, "gyro_bias"), axis=1)
    H = np.diff(np.asarray(raw.t, dtype=float)[mesh])
    rho_g = float(np.max(H * np.maximum(db[:-1], db[1:]))) if H.size else 0.0
    rho_a = 0.0
    if "acc_bias" in nodes:
        g = float(np.linalg.norm(raw.gravity)) if getattr(raw, "gravity", None) is not None else 0.0
        da = float(np.max(np.linalg.norm(np.asarray(nodes["acc_bias"]) - _node_totals(data, "acc_bias"),
                                         axis=1)))
        rho_a = da / g if g > 0 else float("inf")
    return rho_g * (0.5 * rho_g + rho_a)


def cheap_at(ref, nodes: dict):
    r"""A cheap Gauss-Newton point: the data of the last full pass ``ref`` (its samples, and the
    per-element sums its rows were made of) moved to the node totals ``nodes`` (kind -> (n, 3)
    at the mesh's nodes) without a pass over the samples.

    Notes
    -----
    Inside element :math:`[t_p, t_q]` the attitude is the left node's carried by the corrected
    rates, :math:`C_i = C_p P_i` (module Notes), so a change of the node attitudes alone rotates
    every sample of the element by the same :math:`R_p = C_p \bar C_p^T` (bars: the reference):
    the element's load sums :math:`\sum_i W_{ri} C_i (\hat f_i - b_{a,i})` become
    :math:`R_p` times the reference's, exactly, and so do the condensed columns and the process
    rows (:math:`e = \mathrm{Log}(R_q \bar C_q \Delta R^T \bar C_p^T R_p^T)`). The
    accelerometer bias enters the sums linearly (exact too). The gyro-bias change
    :math:`\Delta b_g` is taken to first order, through the reference's own columns
    (:math:`\sum_i W_{ri} [f_{n,i}\times] C_p Y_i`, and the process rows' bias Jacobians);
    the terms left out (the second order of :math:`\Delta b_g`, its product with the
    accelerometer-bias change, and the columns' change with the biases) are measured by
    :func:`cheap_error`. The loop (:func:`bvpnav.solve.attitude._state_loop`) takes a cheap
    step only while that is small and always ends with a full pass, so its answer is
    the exact fixed point.
    """
    raw, mesh = _raw(ref), _mesh(ref)
    if mesh is None or _cheap(ref) is not None:
        raise ValueError("cheap_at: the reference must be a full pass on a coarse mesh")
    nn = mesh.size
    was = {k: _node_totals(ref, k) for k in nodes}
    rot = _compose(Rotation.from_rotvec(nodes["attitude_error"]),
                   Rotation.from_rotvec(was["attitude_error"]).inv()).as_matrix()
    zero = np.zeros((nn, 3))
    dbg = nodes["gyro_bias"] - was["gyro_bias"] if "gyro_bias" in nodes else zero
    dba = nodes["acc_bias"] - was["acc_bias"] if "acc_bias" in nodes else zero
    # the totals at every sample (the biases linear between the nodes, the attitude error the
    # reference's but at the nodes) when read; at the nodes now
    hats, at_nodes = _hats(ref), _hats(ref, nodes_only=True)
    lazy, known = {}, {}
    for k, v in nodes.items():
        v = np.array(v, dtype=float)
        if k == "attitude_error":
            def make(v=v):
                att = np.array(_totals(ref, "attitude_error"))
                att[mesh] = v
                return att
            lazy[k], known[k] = make, v
        else:
            lazy[k], known[k] = (lambda v=v: hats @ v), at_nodes @ v
    tot = _Totals({}, lazy, known)
    out = copy.copy(ref)
    for key in ("_cheap_sums", "_cheap_process"):   # the reference's, read through cheap.ref
        out.__dict__.pop(key, None)
    out.state_point = StatePoint(raw=raw, totals=tot, cheap=_Cheap(ref, rot, dbg, dba))
    return out


def _cheap_sums(data, W, groups: dict) -> tuple:
    """A cheap point's condensed sums for the rows ``W``: the load sums (G, 3) of every group
    (row, element) of :meth:`ErrorStates._groups`, their change from the reference's, and the
    blocks of :meth:`ErrorStates.condensed_columns` (key -> (G, 3, 3)); kept on ``data``."""
    cheap = _cheap(data)
    mine = data.__dict__.setdefault("_cheap_loads", {})
    kept = mine.get(id(W))
    if kept is not None and kept[0] is W:
        return kept[1]
    ref = cheap.ref.__dict__.get("_cheap_sums", {}).get(id(W))
    if ref is None or ref[0] is not W:
        raise RuntimeError("cheap step: the reference pass kept no sums for these rows")
    L0, Y0 = ref[1], ref[2]
    left = groups["left"]
    nn = cheap.rot.shape[0]
    d = L0.copy()
    for (kind, right), blk in Y0.items():
        if kind == "attitude_error":
            continue
        node = left + right
        change = cheap.dba if kind == "acc_bias" else cheap.dbg
        ok = node < nn
        if ok.all():   # every group's node (the left ones): no copies of the blocks
            d += np.einsum("gij,gj->gi", blk, change[node])
        else:
            d[ok] += np.einsum("gij,gj->gi", blk[ok], change[node[ok]])
    R = cheap.rot[left]
    L = np.einsum("gij,gj->gi", R, d)
    Y = {key: (-_skew(L) if key[0] == "attitude_error" else R @ blk) for key, blk in Y0.items()}
    out = (L, L - L0, Y)
    mine[id(W)] = (W, out)
    return out


def process_residuals(data) -> tuple[np.ndarray, np.ndarray]:
    r"""The attitude process residuals :math:`e_j` (N - 1, 3), rad, at the data's point, and
    the step rotations :math:`a_j = \phi_j - h_j b_{g,j}` (N - 1, 3), rad."""
    from ..attitude import step_rotation_vectors

    raw = _raw(data)
    phi = step_rotation_vectors(raw.t, np.asarray(raw.gyro, dtype=float))
    a = phi - data.grid.h[:, None] * _totals(data, "gyro_bias")[:-1]
    C = data.attitude
    R = _compose(_compose(C[1:], Rotation.from_rotvec(-a)), C[:-1].inv())
    return R.as_rotvec(), a


def _mesh_process(data, mesh: np.ndarray, gyro: bool):
    r"""The attitude process rows of a coarse mesh's elements (module Notes): the residuals
    :math:`e_k` (n - 1, 3, rad), :math:`J_l(e_k)^{-1}`, :math:`J_r(e_k)^{-1}` and the gyro-bias
    Jacobians of the element's left and right nodes (n - 1, 3, 3; s, or None without gyro-bias
    states)."""
    cheap = _cheap(data)
    if cheap is not None:
        return _cheap_process(data, cheap, gyro)
    el = _elements(data, mesh, _totals(data, "gyro_bias"))
    # each element's product of steps (the unit quaternions as they are: the rotation scipy keeps)
    dR = Rotation(el.Sc[:, mesh[1:] - 1].T, normalize=False)
    C = data.attitude
    Cp, Cq = C[mesh[:-1]], C[mesh[1:]]
    M = _compose(_compose(Cq, dR.inv()), Cp.inv())
    e0 = M.as_rotvec()
    Jli, Jri = _inverse_jacobians(e0)
    if not gyro:
        data.__dict__["_cheap_process"] = (M.as_quat(), None, None)
        return e0, Jli, Jri, None, None
    # D_i^T = dR^T (R_s ... R_i), dR the element's: dR^T out of the sums over its steps
    lead = Cq.as_matrix() @ np.swapaxes(dR.as_matrix(), 1, 2)
    ne = mesh.size - 1
    Vp, Vq = (lead @ z.T.reshape(ne, 3, 3) for z in el.element_sums)
    data.__dict__["_cheap_process"] = (M.as_quat(), Vp, Vq)   # a cheap step's reference
    return e0, Jli, Jri, Jli @ Vp, Jli @ Vq


def _from_rotation_matrices(m: np.ndarray) -> Rotation:
    """``Rotation.from_matrix(m)`` of matrices that ``Rotation.as_matrix`` made (orthogonal with a
    positive determinant to rounding): the same rotations, without scipy's checks of the
    determinant and the Gram matrices where scipy can skip them (``assume_valid``, recent scipy):
    such matrices pass them, and the conversion after them is the same."""
    try:
        return Rotation.from_matrix(m, assume_valid=True)
    except TypeError:   # an older scipy: no assume_valid
        return Rotation.from_matrix(m)


def _cheap_process(data, cheap: _Cheap, gyro: bool):
    r""":func:`_mesh_process` at a cheap point (:func:`cheap_at`): with the reference's
    :math:`\bar M = \bar C_q \Delta R^T \bar C_p^T` and bias sums :math:`V_{p|q}` (the bias
    Jacobians without :math:`J_l^{-1}`), :math:`e = \mathrm{Log}(R_q \exp([V_p \Delta b_p +
    V_q \Delta b_q]\times) \bar M R_p^T)` and the Jacobians :math:`J_l(e)^{-1} R_q V_{p|q}`."""
    kept = cheap.ref.__dict__.get("_cheap_process")
    if kept is None or (gyro and kept[1] is None):
        raise RuntimeError("cheap step: the reference pass kept no process rows")
    Mq, Vp, Vq = kept
    # the compositions of _compose on the quaternions' components (each product normalized as
    # Rotation.from_quat normalizes it): the same rotations, without a rotation object each
    M = _unit_components(np.array(Mq.T))
    if gyro:
        v = np.einsum("eij,ej->ei", Vp, cheap.dbg[:-1]) + np.einsum("eij,ej->ei", Vq, cheap.dbg[1:])
        M = _unit_components(_quat_components_product(Rotation.from_rotvec(v).as_quat().T, M))
    R = np.ascontiguousarray(_from_rotation_matrices(cheap.rot).as_quat().T)
    Rp_inv = R[:, :-1].copy()
    Rp_inv[:3] *= -1.0                    # the inverse: the vector part negated (Rotation.inv's)
    RqM = _unit_components(_quat_components_product(R[:, 1:], M))
    e0 = Rotation.from_quat(_quat_components_product(RqM, Rp_inv).T).as_rotvec()
    Jli, Jri = _inverse_jacobians(e0)
    if not gyro:
        return e0, Jli, Jri, None, None
    lead = Jli @ cheap.rot[1:]
    return e0, Jli, Jri, lead @ Vp, lead @ Vq


#: Most nodes whose :meth:`ErrorStates.state_index` arrays are kept (a coarse mesh's: the loop
#: reads them many times per step); more are made at every call.
STATE_INDEX_KEPT = 1 << 16


def _made_state_index(n: int, per_node: int, k: int) -> np.ndarray:
    """:meth:`ErrorStates.state_index` of kind number ``k`` on ``n`` nodes of ``per_node`` states
    (read only)."""
    out = np.arange(n)[:, None] * per_node + 3 * k + np.arange(3)[None, :]
    out.setflags(write=False)
    return out


_kept_state_index = functools.lru_cache(maxsize=16)(_made_state_index)


def _state_index(n: int, per_node: int, k: int) -> np.ndarray:
    """:func:`_made_state_index`, kept for the last few layouts of at most
    :data:`STATE_INDEX_KEPT` nodes."""
    return (_kept_state_index if n <= STATE_INDEX_KEPT else _made_state_index)(n, per_node, k)


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class ErrorStates(ErrorModel):
    r"""Attitude error and random-walk biases as states at every node (in the band).

    Parameters
    ----------
    arw : float
        Angle random walk of the gyro, rad/sqrt(s) (its white-noise density): the sigma
        :math:`n_g\sqrt{h_j}` of the attitude process rows.
    gyro_drift : float, optional
        Gyro-bias random walk, rad/s/sqrt(s). None (default): no gyro-bias states; 0: a
        constant gyro bias (hard rows :math:`b_{j+1} = b_j`).
    acc_drift : float, optional
        Accelerometer-bias random walk, m/s^2/sqrt(s); None: no accelerometer-bias states;
        0: constant.
    attitude_sigma : float or array_like, optional
        Prior sigma of the initial attitude error per navigation axis, rad (None: free; inf
        on an axis: free on that axis, e.g. ``[0.1, 0.1, inf]`` for an open heading).
    gyro_sigma, acc_sigma : float or array_like, optional
        Prior sigma of the first node's gyro bias (rad/s) and accelerometer bias (m/s^2),
        per body axis, about zero (None: free).

    Notes
    -----
    The model, its rows and their linearization are in the module docstring
    (:mod:`bvpnav.error_models.error_states`). It declares no parameters in ``l``; its
    unknowns are the node states :math:`s` of :class:`~bvpnav.model.NavModel`. Estimates
    are in ``sol.error_states`` (a DataFrame per sample).

    Examples
    --------
    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.error_models import ErrorStates
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> data = bvpnav.ImuData.from_gyro(t, np.tile([0.0, 0.0, 9.80665], (11, 1)), np.zeros((11, 3)))
    >>> m = ErrorStates(arw=1e-3, gyro_drift=1e-4, acc_drift=1e-3)
    >>> m.state_kinds(data), m.state_size(data)
    (['attitude_error', 'gyro_bias', 'acc_bias'], 99)
    """

    arw: Any = None
    gyro_drift: Any = None
    acc_drift: Any = None
    attitude_sigma: Any = None
    gyro_sigma: Any = None
    acc_sigma: Any = None
    units = "rad"

    def validate(self) -> None:
        from ._attitude import positive_option

        if any(v is not None for v in (self.axes, self.sigma, self.prior, self.bounds)):
            raise InputError("ErrorStates: axes, sigma, prior and bounds are not options; give "
                             "attitude_sigma=, gyro_sigma=, acc_sigma= (priors of the first node) and arw=, "
                             "gyro_drift=, "
                             "acc_drift= (the process noise)")
        object.__setattr__(self, "arw", positive_option(self.arw, "ErrorStates: arw (rad/sqrt(s))"))
        if self.arw is None:
            raise InputError("ErrorStates: give arw= (the gyro's angle random walk, rad/sqrt(s)): it ties "
                             "the attitude of each node to the next")
        for name, unit in (("gyro_drift", "rad/s/sqrt(s)"), ("acc_drift", "m/s^2/sqrt(s)")):
            v = getattr(self, name)
            if v is None:
                continue
            try:
                v = float(v)
            except (TypeError, ValueError):
                raise InputError(f"ErrorStates: {name}={v!r}; give a number >= 0 ({unit}) or None") from None
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"ErrorStates: {name}={v!r} must be finite and >= 0 ({unit}; 0: constant)")
            object.__setattr__(self, name, v)
        for name in ("attitude_sigma", "gyro_sigma", "acc_sigma"):
            v = getattr(self, name)
            if v is None:
                continue
            s = np.broadcast_to(np.asarray(v, dtype=float), (3,)).copy() if np.size(v) in (1, 3) else None
            if s is None or not np.all(~np.isnan(s) & (s > 0)):
                raise InputError(f"ErrorStates: {name}={v!r}; give one positive number or three (per axis; "
                                 "inf: no prior on that axis)")
            object.__setattr__(self, name, s)

    # ------------------------------------------------------------ layout
    def names(self, data) -> list[str]:
        return []

    def columns(self, data) -> np.ndarray:
        return np.zeros((data.n, data.ndim, 0))

    def report(self, l, model) -> pd.Series:
        s = pd.Series([], dtype=float, name="estimate", index=pd.Index([], name="parameter"))
        s.attrs["units"] = {}
        return s

    def state_kinds(self, data) -> list[str]:
        """The node states this model carries, in their order within a node."""
        out = ["attitude_error"]
        if self.gyro_drift is not None:
            out.append("gyro_bias")
        if self.acc_drift is not None:
            out.append("acc_bias")
        return out

    def _per_node(self, data) -> int:
        return 3 * len(self.state_kinds(data))

    @staticmethod
    def _nodes(data) -> int:
        """Number of state nodes: the samples, or the nodes of a coarse mesh."""
        mesh = _mesh(data)
        return data.n if mesh is None else int(np.size(mesh))

    def state_size(self, data) -> int:
        """Number of node states, ``3 * kinds * N`` (n nodes on a coarse mesh)."""
        _check_strapdown_gyro(data, "ErrorStates")
        if data.ndim != 3:
            raise InputError("ErrorStates: needs three navigation axes")
        return self._per_node(data) * self._nodes(data)

    def state_nodes(self, data) -> np.ndarray:
        """Node of every state: node-major, ``3 * kinds`` per node."""
        return np.repeat(np.arange(self._nodes(data)), self._per_node(data))

    def state_index(self, data, kind: str) -> np.ndarray:
        """Position in the state block of ``kind`` at every node and axis, (N, 3) int (the
        samples, or the nodes of a coarse mesh; read only)."""
        kinds = self.state_kinds(data)
        return _state_index(self._nodes(data), 3 * len(kinds), kinds.index(kind))

    def state_total(self, data, kind: str) -> np.ndarray:
        """The current total of ``kind`` at every node, (N, 3) (zero at the data as measured;
        at the node samples on a coarse mesh)."""
        return _totals(data, kind) if _mesh(data) is None else _node_totals(data, kind)

    def state_columns(self, data) -> list:
        r"""Acceleration change per unit state, one sparse (N, ns) matrix per navigation
        axis, m/s^2 per unit: :math:`\varepsilon_j\times f_{n,j}` and :math:`-C_j\,\delta b_{a,j}`."""
        n = data.n
        K = self._per_node(data)
        kinds = self.state_kinds(data)
        fn = data.attitude.apply(data.specific_force)
        S = -_skew(fn)                       # (N, 3, 3): column c = e_c x fn
        C = data.attitude.as_matrix()
        mesh = _mesh(data)
        if mesh is not None:
            return self._mesh_columns(data, mesh, S, C)
        out = []
        for a in range(3):
            blocks = [(self.state_index(data, "attitude_error"), S[:, a, :])]
            if "acc_bias" in kinds:
                blocks.append((self.state_index(data, "acc_bias"), -C[:, a, :]))
            cols = np.concatenate([b[0] for b in blocks], axis=1)
            vals = np.concatenate([b[1] for b in blocks], axis=1)
            rows = np.repeat(np.arange(n), cols.shape[1])
            out.append(sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(n, K * n)))
        return out

    def _mesh_blocks(self, data, mesh: np.ndarray, S: np.ndarray, C: np.ndarray) -> tuple:
        """The per-sample blocks of :meth:`state_columns` on a coarse mesh (module Notes): the
        elements :class:`_Elements`, the blocks' order ``(kind, right node?)`` and
        ``{key: (weight per sample or None, (N, 3, 3))}`` (row: navigation axis, column: state
        component; the block of sample i acts on the states of node ``left[i] + right``)."""
        n = data.n
        kinds = self.state_kinds(data)
        el = _elements(data, mesh, _totals(data, "gyro_bias"))
        k, th = el.left, el.theta
        blocks = {("attitude_error", 0): (None, S)}
        if "acc_bias" in kinds:
            blocks[("acc_bias", 0)] = (1.0 - th, -C)
            blocks[("acc_bias", 1)] = (th, -C)
        if "gyro_bias" in kinds:
            # Y_i = sum_{p <= j < i} P_{j+1} J_r(a_j) h_j w_j: running sums, restarted per element
            # (w_j = theta_j for the right node, 1 - theta_j for the left one)
            Z = el.Z
            cum = np.zeros((2, n, 3, 3))
            np.cumsum(Z, axis=0, out=cum[0, 1:])
            np.cumsum(th[:-1, None, None] * Z, axis=0, out=cum[1, 1:])
            cum -= cum[:, mesh[k]]
            SCp = -(S @ C[mesh[k]])
            blocks[("gyro_bias", 0)] = (None, SCp @ (cum[0] - cum[1]))
            blocks[("gyro_bias", 1)] = (None, SCp @ cum[1])
        order = _block_order(kinds)
        return el, order, blocks

    def _mesh_columns(self, data, mesh: np.ndarray, S: np.ndarray, C: np.ndarray) -> list:
        """:meth:`state_columns` on a coarse mesh (module Notes): (N, ns) per axis, every sample
        on the states of its element's two nodes."""
        n, nn = data.n, mesh.size
        kinds = self.state_kinds(data)
        el, _, blocks = self._mesh_blocks(data, mesh, S, C)
        cols, indptr, r0, order = self._mesh_layout(data, mesh, kinds, el.left)
        # every sample's row holds 3 entries per block: the CSR arrays directly, in canonical
        # form (blocks ordered by node, then kind: increasing columns); at the samples of the
        # last node the right node is the left one, and its blocks (weight 0) are left out
        nb, no = len(order), sum(1 for _, right in order if not right)
        V = np.empty((3, r0 * 3 * nb + (n - r0) * 3 * no))
        main = V[:, :r0 * 3 * nb].reshape(3, r0, nb, 3)
        tail = V[:, r0 * 3 * nb:].reshape(3, n - r0, no, 3)
        for j, key in enumerate(order):
            w, B = blocks[key]
            B = B if w is None else w[:, None, None] * B
            main[:, :, j, :] = B[:r0].transpose(1, 0, 2)
            if not key[1]:
                tail[:, :, j, :] = B[r0:].transpose(1, 0, 2)   # the left node's blocks come first
        ns = self._per_node(data) * nn
        out = []
        for a in range(3):
            G = sp.csr_matrix((V[a], cols.copy(), indptr.copy()), shape=(n, ns))
            G.has_canonical_format = True
            out.append(G)
        return out

    def condensed_columns(self, data, W) -> list:
        r"""``W @ state_columns(data)[a]`` for every navigation axis, without the columns of
        every sample: on a coarse mesh, sums over the samples that ``W`` (sparse (m, N), e.g.
        the condensation's load :math:`\Phi^T M_f`) weighs of the per-sample blocks, grouped
        by the row and the sample's element (one sparse product per kind of block; the same
        products as ``W @ state_columns``, summed in another order). Canonical CSR (m, ns)
        per axis (explicit zeros dropped, as :func:`bvpnav.model.canonical_csr`).

        Notes
        -----
        Per group (row r, element of left node p) the sums are :math:`\sum_i W_{ri} f_{n,i}`
        (the attitude block :math:`-[\cdot\times]` of it), :math:`-\sum_i W_{ri} w_i C_i`
        (accelerometer bias, :math:`w = 1 - \theta, \theta`) and :math:`\sum_i W_{ri}
        [f_{n,i}\times] C_p Y_i` (gyro bias, module Notes); the weights :math:`W_{ri} w_i` are
        the same at every point. The gyro-bias sums are taken as :math:`C_p \sum_i W_{ri}
        [g_i\times] Y_i` with :math:`g_i = C_p^T f_{n,i}` (:math:`[f\times] C = C [(C^T f)\times]`
        for a rotation :math:`C`; :math:`C_p` is one per group).
        """
        mesh = _mesh(data)
        if mesh is None:
            return [sp.csr_matrix(W @ g) for g in self.state_columns(data)]
        kinds = self.state_kinds(data)
        n = data.n
        cheap = _cheap(data)
        if cheap is not None:   # from the last full pass's sums (cheap_at)
            g = self._groups(cheap.ref, mesh, W, None)
            return self._placed(g, _cheap_sums(data, W, g)[2])
        el = _elements(data, mesh, _totals(data, "gyro_bias"))
        g = self._groups(data, mesh, W, el.left)
        P = g["P"]
        C, fn = _rotated_force(data)                             # f_n = C f
        L = P @ fn
        Y = {("attitude_error", 0): -_skew(L)}
        if "acc_bias" in kinds:
            C9 = C.reshape(n, 9)
            Y[("acc_bias", 0)] = -(g["P1"] @ C9).reshape(-1, 3, 3)
            Y[("acc_bias", 1)] = -(g["P2"] @ C9).reshape(-1, 3, 3)
        if "gyro_bias" in kinds:
            # [f_n x] C_p Y_i = C_p [g_i x] Y_i with g_i = C_p^T f_n,i (C_p the sample's element's left
            # node's, the same for every sample of a group): the sums of [g_i x] Y_i, then C_p
            Y4 = _gyro_sums(el, mesh).reshape(2, 3, 3, n)
            Cn = C.reshape(n, 9)[mesh]                                   # (n nodes, 9)
            CnT = np.ascontiguousarray(Cn.T)                             # C_p[k, l] at 3 k + l
            f = np.ascontiguousarray(fn.T)
            gb = np.empty((3, n))
            x, tmp, cp = np.empty(n), np.empty(n), np.empty(n)
            for c in range(3):   # g_c = sum_k C_p[k, c] f_k, C_p[k, c] at every sample (its element's)
                np.take(CnT[c], el.left, out=cp)
                np.multiply(cp, f[0], out=gb[c])
                np.take(CnT[3 + c], el.left, out=cp)
                np.multiply(cp, f[1], out=tmp)
                gb[c] += tmp
                np.take(CnT[6 + c], el.left, out=cp)
                np.multiply(cp, f[2], out=tmp)
                gb[c] += tmp
            Sg = np.empty((P.shape[0], 2, 3, 3))
            for w in range(2):
                for r in range(3):
                    a, b = (r + 1) % 3, (r + 2) % 3          # ([g x] Y)_r = g_a Y_b - g_b Y_a
                    for c in range(3):
                        np.multiply(gb[a], Y4[w, b, c], out=x)
                        np.multiply(gb[b], Y4[w, a, c], out=tmp)
                        x -= tmp
                        Sg[:, w, r, c] = P @ x
            Yg = np.einsum("gij,gwjc->gwic", Cn.reshape(-1, 3, 3)[g["left"]], Sg)
            Y[("gyro_bias", 0)], Y[("gyro_bias", 1)] = Yg[:, 0], Yg[:, 1]
        # the sums and their derivatives, for the cheap steps that follow (cheap_at)
        data.__dict__.setdefault("_cheap_sums", {})[id(W)] = (W, L, Y)
        return self._placed(g, Y)

    def condensed_change(self, data, W) -> np.ndarray | None:
        """At a cheap point (:func:`cheap_at`): the change of ``W @ (C_i (f_i - b_{a,i}))`` from the
        reference's, (m, 3) m/s^2 per row of ``W`` (the condensed load of the samples'
        accelerations moves by it); None at any other point (the load is made from the samples)."""
        cheap = _cheap(data)
        mesh = _mesh(data)
        if cheap is None or mesh is None:
            return None
        g = self._groups(cheap.ref, mesh, W, None)
        dL = _cheap_sums(data, W, g)[1]
        return np.column_stack([np.bincount(g["row"], dL[:, a], minlength=W.shape[0]) for a in range(3)])

    def _placed(self, g: dict, Y: dict) -> list:
        """The blocks ``Y`` (key -> (G, 3, 3), one per group of ``g``) as the canonical CSR
        matrices of :meth:`condensed_columns`, one per navigation axis."""
        order, nnz = g["order"], g["nnz"]
        blocks = np.stack([Y[key] for key in order])   # (kinds, G, 3, 3)
        G = blocks.shape[1]
        gather = g.get("gather")
        if gather is None or gather[0] != G:
            # every axis' entries of the kept groups' blocks, in the slots' order (block by block,
            # group, column), the axes one after the other: one gather and one sum for all
            idx = [np.concatenate([(((k * G + g["keep"][key]) * 3 + a) * 3)[:, None] + np.arange(3)
                                   for k, key in enumerate(order)]).ravel() for a in range(3)]
            slots = np.concatenate([g["slot"] + a * nnz for a in range(3)])
            gather = g["gather"] = (G, np.concatenate(idx), slots)
        # per slot the same sums in the same order as one axis at a time
        every = np.bincount(gather[2], blocks.reshape(-1)[gather[1]], minlength=3 * nnz)
        kept = g.setdefault("patterns", {})   # per axis: the layout's entries not zero, and their pattern
        out = []
        for a in range(3):
            v = every[a * nnz:(a + 1) * nnz]
            nz = v != 0
            if a in kept and np.array_equal(kept[a][0], nz):   # zeros where the last point had them
                out.append(_with_values(kept[a][1], v[nz]))
                continue
            A = sp.csr_matrix((v.copy(), g["indices"].copy(), g["indptr"].copy()), shape=g["shape"])
            A.has_canonical_format = True   # the kept layout is not pruned
            A.eliminate_zeros()
            kept[a] = (nz, _pattern(A.indices, A.indptr, A.shape))
            out.append(A)
        return out

    def _groups(self, data, mesh: np.ndarray, W, left: np.ndarray) -> dict:
        """How :meth:`condensed_columns` groups the entries of ``W``: by row, then the element
        (left node) of the sample; the placement of the groups' blocks in the (m, ns) result.
        The same for every point: kept on the measured data for the last few ``W`` (the load)."""
        raw = _raw(data)
        kinds = tuple(self.state_kinds(data))
        cache = raw.__dict__.setdefault("_mesh_groups", {})
        kept = cache.get(id(W))
        if kept is not None and kept[0] is W and kept[1] is mesh and kept[2] == kinds:
            return kept[3]
        if left is None:
            raise RuntimeError("cheap step: the reference pass grouped no such rows")
        Wc = sp.coo_matrix(W)
        nn, K = mesh.size, self._per_node(data)
        key = Wc.row.astype(np.int64) * nn + left[Wc.col]
        perm = np.argsort(key, kind="stable")
        key = key[perm]
        starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
        R, L = key[starts] // nn, key[starts] % nn
        order = _block_order(kinds)
        rows, cols, keep = [], [], {}
        for kind, right in order:
            node = L + right
            ok = np.flatnonzero(node < nn)
            keep[(kind, right)] = ok
            c = self.state_index(data, kind)[node[ok]]                    # (G, 3)
            rows.append(np.repeat(R[ok], 3))
            cols.append(c.ravel())
        rows, cols = np.concatenate(rows), np.concatenate(cols)
        shape = (W.shape[0], K * nn)
        lin = rows * shape[1] + cols
        uniq, slot = np.unique(lin, return_inverse=True)
        ur, uc = uniq // shape[1], uniq % shape[1]
        indptr = np.r_[0, np.cumsum(np.bincount(ur, minlength=shape[0]))]
        group = np.cumsum(np.r_[False, key[1:] != key[:-1]])        # group of every entry of W
        vals, cols_w = np.asarray(Wc.data, dtype=float)[perm], Wc.col[perm]
        th = _elements(data, mesh, _totals(data, "gyro_bias")).theta

        if sp.issparse(W) and W.format == "csr" and W.has_canonical_format:
            # W's entries grouped (stable sort: by column within a group): the groups' CSR arrays
            ptr = np.r_[starts, key.size].astype(cols_w.dtype)

            def summing(w):
                return sp.csr_matrix((w, cols_w, ptr), shape=(starts.size, W.shape[1]))
        else:
            def summing(w):
                return sp.csr_matrix((w, (group, cols_w)), shape=(starts.size, W.shape[1]))

        out = {"P": summing(vals), "P1": summing(vals * (1.0 - th[cols_w])), "P2": summing(vals * th[cols_w]),
               "row": R, "left": L, "order": order, "keep": keep, "slot": slot, "nnz": uniq.size,
               "indices": uc.astype(np.int32),
               "indptr": indptr.astype(np.int32), "shape": shape}
        if len(cache) >= 8:   # the load's, and a few others (velocity rows)
            cache.pop(next(iter(cache)))
        cache[id(W)] = (W, mesh, kinds, out)
        return out

    def state_acceleration(self, data, s: np.ndarray) -> np.ndarray:
        r"""``state_columns(data)[a] @ s`` for every axis, (N, 3), m/s^2: the acceleration the
        state increments ``s`` make at every sample (on a coarse mesh without the columns:
        :math:`\varepsilon_p \times f_{n,i} - C_i \delta b_{a,i} + f_{n,i} \times C_p (Y_{p,i}
        \delta b_{g,p} + Y_{q,i} \delta b_{g,q})`, module Notes). On a mesh the products are
        taken on component arrays over blocks of :data:`STEP_BLOCK` samples
        (:func:`_block_acceleration`; the rotations' matrices component-major), the products
        summed in the order ``Rotation.apply`` and ``numpy.einsum`` summed them (the same numbers
        to rounding; bit for bit with the numpy and scipy this was written against); the answer
        is a (N, 3) view of a (3, N) array."""
        mesh = _mesh(data)
        s = np.asarray(s, dtype=float)
        if mesh is None:
            return np.column_stack([g @ s for g in self.state_columns(data)])
        kinds = self.state_kinds(data)
        n, nn = data.n, mesh.size
        el = _elements(data, mesh, _totals(data, "gyro_bias"))
        nxt = np.minimum(np.arange(1, nn + 1), nn - 1)   # the right node (the last node's weight is 0)
        # the node values: attitude increments, the biases' at the left and the right node
        att = np.ascontiguousarray(s[self.state_index(data, "attitude_error")].T)
        node = {kind: np.ascontiguousarray(s[self.state_index(data, kind)].T) for kind in kinds[1:]}
        node.update({(kind, 1): np.ascontiguousarray(v[:, nxt]) for kind, v in list(node.items())})
        Y2 = _gyro_sums(el, mesh).reshape(2, 3, 3, n) if "gyro_bias" in kinds else None
        Cn = (np.ascontiguousarray(data.attitude[mesh].as_matrix().reshape(nn, 9).T)
              if "gyro_bias" in kinds else None)
        f = np.asarray(data.specific_force, dtype=float)
        out = np.empty((3, n))
        tmp = np.empty(min(n, STEP_BLOCK))
        # every term is per sample: made block by block of STEP_BLOCK samples (the same numbers as
        # on every sample at once, each block's arrays in place of the whole pass's)
        for lo in range(0, n, STEP_BLOCK):
            hi = min(lo + STEP_BLOCK, n)
            _block_acceleration(out[:, lo:hi], tmp[:hi - lo], el.left[lo:hi], el.theta[lo:hi],
                                data.attitude[lo:hi], f[lo:hi].T, att, node,
                                None if Y2 is None else Y2[..., lo:hi], Cn)
        return out.T

    def _mesh_layout(self, data, mesh: np.ndarray, kinds: list, k: np.ndarray) -> tuple:
        """The column indices and row pointers of :meth:`_mesh_columns` (the same at every point:
        kept on the measured data), the first sample ``r0`` of the last node and the blocks'
        order ``(kind, right node?)``."""
        raw = _raw(data)
        kept = raw.__dict__.get("_mesh_layout")
        if kept is not None and kept[0] is mesh and kept[1] == tuple(kinds):
            return kept[2]
        nn, n, K = mesh.size, k.size, self._per_node(data)
        order = _block_order(kinds)
        nxt = np.minimum(k + 1, nn - 1)
        cols = np.concatenate([self.state_index(data, kind)[nxt if right else k]
                               for kind, right in order], axis=1)
        itype = np.int32 if K * nn < 2**31 and cols.size < 2**31 else np.int64
        r0 = int(np.searchsorted(k, nn - 1))       # the first sample of the last node (k ascends)
        no = sum(1 for _, right in order if not right)
        width = 3 * len(order)
        cols = np.concatenate([cols[:r0].ravel(), cols[r0:, :3 * no].ravel()]).astype(itype)
        indptr = np.concatenate([np.arange(0, r0 * width + 1, width),
                                 r0 * width + 3 * no * np.arange(1, n - r0 + 1)]).astype(itype)
        out = (cols, indptr, r0, order)
        raw.__dict__["_mesh_layout"] = (mesh, tuple(kinds), out)
        return out

    # ------------------------------------------------------------ rows
    def terms(self, model) -> list:
        from ..model import Affine, RowLabels
        from ..terms import Term

        data = model.data
        mesh = _mesh(data)
        n = self._nodes(data)
        h = data.grid.h if mesh is None else np.diff(np.asarray(data.t, dtype=float)[mesh])
        s0 = int(model.s_index[0])
        kinds = self.state_kinds(data)
        out = []

        # the rows' patterns (and the walks' matrices) depend on the layout alone: made once for
        # the loop's steps (_kept_rows: never on the user's own data)
        fixed = _kept_rows(_raw(data))
        if fixed.get("key") != (id(mesh), n, s0, model.size, tuple(kinds)):
            fixed.clear()
            fixed["key"] = (id(mesh), n, s0, model.size, tuple(kinds))
            fixed["mesh"] = mesh   # keeps the mesh alive while its id is the key

        # the attitude process rows
        P = self.state_index(data, "attitude_error")
        if mesh is None:
            e0, a = process_residuals(data)
            Jli, Jri = _inverse_jacobians(e0)
            blocks = [(P[:-1], -Jri), (P[1:], Jli)]
            if "gyro_bias" in kinds:
                C1 = data.attitude.as_matrix()[1:]
                Bg = Jli @ C1 @ right_jacobian(a) * h[:, None, None]
                blocks.insert(1, (self.state_index(data, "gyro_bias")[:-1], Bg))
        else:
            e0, Jli, Jri, Bp, Bq = _mesh_process(data, mesh, "gyro_bias" in kinds)
            blocks = [(P[:-1], -Jri), (P[1:], Jli)]
            if "gyro_bias" in kinds:
                B = self.state_index(data, "gyro_bias")
                blocks = [blocks[0], (B[:-1], Bp), blocks[1], (B[1:], Bq)]
        m = n - 1
        # row (j, i): sum_c J[j, i, c] * state cols[j, c]; the blocks in increasing columns (node j's
        # states, then node j + 1's), so the CSR arrays are written directly, in canonical order
        w = 3 * len(blocks)
        itype = _index_type(model.size, m, w)
        vals = np.empty((m, 3, w))
        for b, (_, J) in enumerate(blocks):
            vals[:, :, 3 * b:3 * b + 3] = J
        if "process" not in fixed:
            cols = np.empty((m, 3, w), dtype=np.int64)
            for b, (c, _) in enumerate(blocks):
                cols[:, :, 3 * b:3 * b + 3] = s0 + c[:, None, :]
            fixed["process"] = _pattern(cols.ravel().astype(itype),
                                        np.arange(0, 3 * m * w + 1, w, dtype=itype), (3 * m, model.size))
        A = _with_values(fixed["process"], vals.ravel())
        res = Affine(A, e0.ravel(), RowLabels([("process_attitude", 3 * m)]))
        out.append(Term(label="process ErrorStates[attitude]", item=None, residual=res, mode="soft",
                        kind="equality", sigma=np.repeat(self.arw * np.sqrt(h), 3), scaled_by_lam=False,
                        units="rad"))
        # the bias walks (hard rows when constant)
        for kind, q in (("gyro_bias", self.gyro_drift), ("acc_bias", self.acc_drift)):
            if kind not in kinds:
                continue
            tot = self.state_total(data, kind)
            if kind not in fixed:   # row (j, c): b_{j+1,c} - b_{j,c}, its two columns in increasing order
                B = self.state_index(data, kind)
                cols = (s0 + np.stack([B[:-1], B[1:]], axis=-1)).ravel()
                fixed[kind] = _csr(np.tile([-1.0, 1.0], 3 * m), cols.astype(itype),
                                   np.arange(0, 6 * m + 1, 2, dtype=itype), (3 * m, model.size))
            A = fixed[kind]
            res = Affine(A, (tot[1:] - tot[:-1]).ravel(), RowLabels([(f"process_{kind}", 3 * m)]))
            if q > 0:
                out.append(Term(label=f"process ErrorStates[{kind}]", item=None, residual=res, mode="soft",
                                kind="equality", sigma=np.repeat(q * np.sqrt(h), 3), scaled_by_lam=False,
                                units=KINDS[kind]))
            else:
                out.append(Term(label=f"constant ErrorStates[{kind}]", item=None, residual=res, mode="hard",
                                kind="equality", scaled_by_lam=False, units=KINDS[kind]))
        return out + self._prior_terms(data, model, fixed)

    def _prior_terms(self, data, model, fixed: dict) -> list:
        """The priors on the first node's states (:meth:`terms`); their rows' patterns, and a bias
        prior's rows whole (the identity's), kept in ``fixed`` with the process rows'."""
        from ..model import Affine
        from ..terms import Term

        s0 = int(model.s_index[0])
        kinds = self.state_kinds(data)
        out = []
        for kind, sig in (("attitude_error", self.attitude_sigma), ("gyro_bias", self.gyro_sigma),
                          ("acc_bias", self.acc_sigma)):
            if sig is None or kind not in kinds:
                continue
            tot = self.state_total(data, kind)[0]
            keep = np.flatnonzero(np.isfinite(sig))
            if keep.size:   # the kept rows of J on the first node's three states (increasing columns)
                key = ("prior", kind, tuple(keep))
                if key not in fixed:   # the pattern; a bias prior's rows (J = I) whole
                    k, cols = keep.size, self.state_index(data, kind)[0]
                    fixed[key] = _pattern(np.tile(s0 + cols, k), np.arange(0, 3 * k + 1, 3), (k, model.size))
                    if kind != "attitude_error":
                        fixed[key] = _with_values(fixed[key], np.eye(3)[keep].ravel())
                A = (_with_values(fixed[key], _inverse_jacobian(tot, 1.0)[keep].ravel())
                     if kind == "attitude_error" else fixed[key])
                res = Affine(A, tot[keep], tuple(f"prior_{kind}[{i}]" for i in keep))
                out.append(Term(label=f"prior ErrorStates[{kind}]", item=None, residual=res,
                                mode="soft", kind="equality", sigma=np.asarray(sig, dtype=float)[keep],
                                scaled_by_lam=False, units=KINDS[kind]))
        return out

    # ------------------------------------------------------------ totals
    def updated(self, data, s: np.ndarray) -> dict:
        r"""The totals at every sample after the increments ``s`` (the state block of a solution):
        attitude by composition, :math:`\exp([\psi'\times]) = \exp([\varepsilon\times])\exp([\psi\times])`,
        biases by addition; on a coarse mesh at the nodes, and the samples follow
        (:meth:`node_totals`, :meth:`expand`)."""
        return self.expand(data, self.node_totals(data, s))

    def node_totals(self, data, s: np.ndarray) -> dict:
        r"""The totals at the nodes after the increments ``s``, kind -> (n, 3) (attitude by
        composition, biases by addition; the nodes of a coarse mesh, else every sample)."""
        out = {}
        for kind in self.state_kinds(data):
            d = np.asarray(s, dtype=float)[self.state_index(data, kind)]
            tot = self.state_total(data, kind)
            if kind == "attitude_error":
                out[kind] = _compose(Rotation.from_rotvec(d), Rotation.from_rotvec(tot)).as_rotvec()
            else:
                out[kind] = tot + d
        return out

    def expand(self, data, nodes: dict) -> dict:
        r"""The totals at every sample, kind -> (N, 3), from those at the nodes of a coarse mesh
        (``nodes``, kind -> (n, 3)): the biases linear between nodes, the attitude
        re-integrated from its element's left node with the corrected rates, :math:`C_i = C_p
        P_i` (module Notes), as the attitude error :math:`\mathrm{Log}(C_i \hat C_i^T)` of every
        sample. Without a mesh the nodes are the samples: ``nodes`` itself. On a mesh the
        attitude error's samples are made on first read (a dict whose every read gives the made
        arrays, :class:`_Totals`)."""
        mesh = _mesh(data)
        if mesh is None:
            return dict(nodes)
        hats = _hats(data)
        out = {kind: hats @ np.asarray(v, dtype=float) for kind, v in nodes.items()
               if kind != "attitude_error"}
        raw = _raw(data)
        n = raw.n
        el = _elements(data, mesh, out.get("gyro_bias", np.zeros((n, 3))))
        Chat = raw.attitude
        Cnode = _compose(Rotation.from_rotvec(nodes["attitude_error"]), Chat[mesh]).as_quat()   # C_p
        # C_i = C_p P_i (components first): P_i the product of the element's steps before sample i,
        # the identity at the nodes (a product with it gives C_p's components exactly)
        P = np.empty((4, n))
        P[:, 1:] = el.Sc
        P[:, mesh] = ((0.0,), (0.0,), (0.0,), (1.0,))
        C = _quat_components_product(np.take(np.ascontiguousarray(Cnode.T), el.left, axis=1), P)
        inv = raw.__dict__.get("_attitude_inverse_components")
        if inv is None:
            inv = raw.__dict__["_attitude_inverse_components"] = np.ascontiguousarray(Chat.inv().as_quat().T)

        def attitude_error(C=C, inv=inv):   # Log(C_i hat C_i^T) of every sample, when read
            return _rotvec_components(_quat_components_product(C, inv))

        # at the nodes now (the loop's next step reads them): the same products there
        at_nodes = _rotvec_components(_quat_components_product(np.ascontiguousarray(C[:, mesh]),
                                                               np.ascontiguousarray(inv[:, mesh])))
        out = _Totals(out, {"attitude_error": attitude_error}, {"attitude_error": at_nodes})
        raw.__dict__["_expanded_attitude"] = (out, C.T)
        return out

    def release(self, data) -> None:
        """Drop the memory the loop's full passes hand each other (the kept elements' spare
        arrays, :func:`_elements`): called when the node-state loop ends, so that a solution
        does not keep arrays no pass will write again, nor the last expand's totals and attitude
        (:func:`_point_attitude` reads them; call this after the answer's attitude is made)."""
        raw = _raw(data)
        kept = raw.__dict__.get("_mesh_elements")
        if kept is not None:
            kept[2].spare.clear()
        raw.__dict__.pop("_expanded_attitude", None)

    def frame(self, data, totals: dict) -> pd.DataFrame:
        """The states per sample as a DataFrame (index ``t (s)``; columns ``<kind>_<axis> (<unit>)``)."""
        cols = {}
        for kind in self.state_kinds(data):
            for c, ax in enumerate("xyz"):
                cols[f"{kind}_{ax} ({KINDS[kind]})"] = totals[kind][:, c]
        return pd.DataFrame(cols, index=pd.Index(np.asarray(data.t, dtype=float), name="t (s)"))

    def attitude_columns(self, data) -> list:
        r"""Navigation-frame attitude change per unit state at every sample, one sparse (N, ns)
        matrix per navigation axis, rad per unit: the :math:`\psi_i` of
        :math:`C_i \to \exp([\psi_i\times])\,C_i` that the body-frame rows linearize.

        Notes
        -----
        At every sample its own node's :math:`\varepsilon_i`. On a coarse mesh (module Notes) the
        attitude inside element :math:`[t_p, t_q]` is the left node's integrated,
        :math:`\psi_i = \varepsilon_p - C_p Y_i\,\delta b`: the columns of :meth:`state_columns`
        with the identity for :math:`-[f_{n,i}\times]` and the accelerometer bias left out.
        """
        mesh = _mesh(data)
        kinds = self.state_kinds(data)
        n, ns = data.n, self.state_size(data)
        if mesh is None:
            cols = self.state_index(data, "attitude_error")
            return [sp.csr_matrix((np.ones(n), (np.arange(n), cols[:, a])), shape=(n, ns)) for a in range(3)]
        eye = np.broadcast_to(np.eye(3), (n, 3, 3))
        out = self._mesh_columns(data, mesh, eye, data.attitude.as_matrix())
        if "acc_bias" not in kinds:
            return out
        keep = np.ones(ns)
        keep[self.state_index(data, "acc_bias").ravel()] = 0.0
        return [sp.csr_matrix(g @ sp.diags(keep)) for g in out]

    @staticmethod
    def example_data():
        """Strapdown data with gyro rates (that of the attitude models' contract checks)."""
        from ._attitude import AttitudeErrorModel

        return AttitudeErrorModel.example_data()

    @classmethod
    def example(cls) -> ErrorStates:
        return cls(arw=1e-3, gyro_drift=1e-4, acc_drift=1e-3)
