r"""A land vehicle does not slide sideways or jump: its body-frame lateral and vertical velocity is ~0."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from bvpnav.errors import InputError
from bvpnav.items import Item

from ._common import finite, interval

__all__ = ["NonHolonomic"]

#: Largest known cornering compliance :math:`K` accepted by ``slip=K``, s^2/m (0.05: a side-slip
#: angle of 28 degrees per g of lateral specific force, several times any road tyre's; see
#: :class:`NonHolonomic`'s Notes for the physics and :class:`~bvpnav.error_models.SideSlip` for the
#: published figures, 0.004-0.009 s^2/m). Wider than the limits an *estimated* compliance is
#: warned beyond (:data:`bvpnav.solve.plausibility.SIDE_SLIP_LIMITS`, road tyres on a paved
#: road): a stated value is the user's knowledge of the vehicle (loose ground, worn tyres), an
#: estimate outside a road tyre's range more likely absorbs another error.
SLIP_MAX = 0.05

#: Default half-width of the band, m/s: what a car's wheels allow sideways and vertically
#: (tyre slip in ordinary driving, suspension travel, a residual mounting misalignment of a few
#: tenths of a degree at 15 m/s) without being tuned to any recording.
DEFAULT_TOL = 0.1

#: Default sigma of the band's soft edges, m/s: beyond the band the excess is a soft penalty of
#: this sigma (a skid of another 0.1 m/s costs what one standard deviation does), the same scale
#: as the band itself, so the default states one figure of the vehicle's sideways freedom.
DEFAULT_EDGE_SIGMA = 0.1

_BODY = ("x", "y", "z")


def intervals(t, label: str) -> tuple[tuple[float, float], ...] | None:
    """``None`` (the whole window), one ``(t0, t1)`` or a list of them, validated (s)."""
    if t is None:
        return None
    arr = finite(t, label, "t")
    if arr.ndim == 1 and arr.size == 2:
        arr = arr.reshape(1, 2)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] == 0:
        raise InputError(f"{label}: t={t!r}; give an interval t=(t0, t1) in s, a list of them "
                         "[(t0, t1), ...], or omit t for the whole recording")
    out = tuple(interval(a, b, label) for a, b in arr)
    order = sorted(out)
    for (a0, a1), (b0, b1) in zip(order[:-1], order[1:], strict=True):
        if b0 < a1:
            raise InputError(f"{label}: intervals ({a0:g}, {a1:g}) and ({b0:g}, {b1:g}) s overlap; give "
                             "disjoint intervals (the rows would be counted twice)")
    return tuple(order)


def lever_arm(lever, label: str) -> tuple[float, float, float] | str:
    """The lever as three body-frame coordinates, m, or ``"estimated"`` (the
    :class:`~bvpnav.error_models.NhcLever` parameters)."""
    if isinstance(lever, str):
        if lever != "estimated":
            raise InputError(f"{label}: lever={lever!r}; give 'estimated' (the point is the error model's "
                             "NhcLever) or three body-frame coordinates in m, e.g. lever=(-1.4, 0, -0.3)")
        return lever
    v = finite(lever, label, "lever").ravel()
    if v.size != 3:
        raise InputError(f"{label}: lever={lever!r} has {v.size} component(s); give the point as three "
                         "body-frame coordinates in m (x forward, y left, z up), e.g. lever=(-1.4, 0, -0.3)")
    return tuple(float(a) for a in v)


#: ``rate=NODES``: the rows at the coarse mesh's nodes (:func:`body_instants`).
NODES = "nodes"


def positive_rate(rate, label: str) -> float | str | None:
    """``None`` (every sample), ``"nodes"`` (the coarse mesh's nodes) or a rate in Hz > 0."""
    if rate is None:
        return None
    if isinstance(rate, str):
        if rate.strip().lower() != NODES:
            raise InputError(f"{label}: rate={rate!r}; give the rows' rate in Hz (> 0), 'nodes' (at the "
                             "coarse mesh's nodes, segment=), or None for every sample")
        return NODES
    r = finite(rate, label, "rate")
    if r.size != 1 or not float(r.ravel()[0]) > 0:
        raise InputError(f"{label}: rate={rate!r}; give the rows' rate in Hz (> 0), 'nodes' (at the coarse "
                         "mesh's nodes, segment=), or None for every sample")
    return float(r.ravel()[0])


def slip_value(slip, label: str) -> float | str | None:
    """``None`` (no slip), ``"estimated"`` or a known cornering compliance :math:`K` in s^2/m,
    validated (finite, ``0 <= K <= SLIP_MAX``)."""
    if slip is None or (isinstance(slip, str) and slip == "estimated"):
        return slip
    fix = ("give the rear axle's cornering compliance K in s^2/m (the side-slip angle, rad, per m/s^2 of "
           f"lateral specific force; 0 <= K <= {SLIP_MAX:g}, a car's 0.004-0.009), 'estimated' (the "
           "error model's SideSlip), or None")
    if isinstance(slip, str | bool):
        raise InputError(f"{label}: slip={slip!r}; {fix}")
    try:
        k = float(slip)
    except (TypeError, ValueError):
        raise InputError(f"{label}: slip={slip!r}; {fix}") from None
    if not (np.isfinite(k) and 0.0 <= k <= SLIP_MAX):
        raise InputError(f"{label}: slip={slip!r} s^2/m is outside [0, {SLIP_MAX:g}] (negative: the rear "
                         f"axle sliding into the turn, which a tyre's lateral force cannot do; above: a slip "
                         f"angle of {np.degrees(SLIP_MAX * 9.80665):.0f} deg per g and more); {fix}")
    return k


def lateral_force(model, t: np.ndarray) -> np.ndarray:
    """The measured body-frame lateral specific force :math:`f_y` at ``t`` (m/s^2; linear
    between samples)."""
    f = np.asarray(model.data.specific_force, dtype=float)[:, 1]
    return model.sample_grid.interpolation_matrix(t, "lateral specific force") @ f


def slip_rows(model, t, axes, lever, slip, who: str):
    r"""The side-slip term of the lateral rows (zero on the other axes), to be added to
    :func:`point_rows`: :math:`K f_y(t_k)\, v_x(t_k)` with a known ``slip`` :math:`K` (linear
    in the point's forward velocity), or with ``slip="estimated"`` the rows of
    :meth:`bvpnav.NavModel.side_slip_velocity` (the error model's
    :class:`~bvpnav.error_models.SideSlip`)."""
    import scipy.sparse as sp

    from bvpnav.model import Affine

    if isinstance(slip, str):
        return model.side_slip_velocity(t, axes, lever=None if isinstance(lever, str) else lever, what=who)
    t = np.asarray(t, dtype=float)
    nb, iy = len(axes), list(axes).index("y")
    fwd = point_rows(model, t, ("x",), lever, who)                  # one row per instant
    S = sp.csr_matrix((slip * lateral_force(model, t), (np.arange(t.size) * nb + iy, np.arange(t.size))),
                      shape=(t.size * nb, t.size))
    return Affine(S @ fwd.A, S @ fwd.c)


def point_rows(model, t, axes, lever, who: str):
    """The body-frame velocity rows of the point ``lever`` (:meth:`bvpnav.NavModel.body_velocity`),
    or with ``lever="estimated"`` those of the IMU plus :meth:`bvpnav.NavModel.vehicle_point_velocity`
    (the point the error model's :class:`~bvpnav.error_models.NhcLever` gives)."""
    if isinstance(lever, str):
        rows = model.body_velocity(t, axes, (0.0, 0.0, 0.0), what=who)
        point = model.vehicle_point_velocity(t, axes, what=who)
        return rows + point       # the point's rows have no constant: the labels and c are the IMU's
    return model.body_velocity(t, axes, lever, what=who)


#: Entries of a row smaller than this times the row's largest are rounding noise of exact zeros
#: (:func:`without_rounding_noise`).
ROUNDING_NOISE = 1e-14


def without_rounding_noise(rows):
    r"""``rows`` without the entries below :data:`ROUNDING_NOISE` times their row's largest.

    A body-frame row at a sample :math:`q` holds :math:`C_q^T` times the velocity's columns; where
    those hold :math:`C_q` itself (the accelerometer bias's columns of the sample's own state, in
    an element of one sample step) the product is :math:`C_q^T C_q = I`, whose off-diagonal
    entries come out of the sums as rounding noise (about 1e-20) or as exact zeros, differently
    from one linearization point to the next. Sparse rows drop exact zeros, so the rows' pattern
    would change between Gauss-Newton steps, and with it the banded plan's analysis
    (:class:`bvpnav.linalg.banded.BandPlan`), made again every step. Dropped, the pattern is
    the structure's; the values change by about the rounding of the row's own sums (1e-14 of
    the row's largest entry is some fifty machine epsilons).
    """
    import scipy.sparse as sp

    from bvpnav.model import Affine

    A = sp.csr_matrix(rows.A, copy=True)
    if A.nnz == 0:
        return rows
    big = np.maximum.reduceat(np.abs(A.data), A.indptr[:-1][np.diff(A.indptr) > 0])
    scale = np.zeros(A.shape[0])
    scale[np.diff(A.indptr) > 0] = big
    small = np.abs(A.data) < ROUNDING_NOISE * np.repeat(scale, np.diff(A.indptr))
    if not small.any():
        return rows
    A.data[small] = 0.0
    A.eliminate_zeros()
    return Affine(A, rows.c, rows.labels)


def lever_text(lever) -> str:
    """The lever for ``math()``: its coordinates, or the estimated point."""
    if isinstance(lever, str):
        return "l (estimated, NhcLever)"
    return "(" + ", ".join(f"{v:g}" for v in lever) + ") m"


def check_body_data(model, who: str) -> None:
    """Refuse, naming the item, data that have no body frame (navigation-frame accelerations)."""
    data = model.data
    if not getattr(data, "is_strapdown", False) or getattr(data, "attitude", None) is None:
        raise InputError(f"{who}: acts on the body-frame velocity, but these data are navigation-frame "
                         f"accelerations on axes {list(model.axes)} with no attitude; build the data with "
                         "bvpnav.ImuData.from_gyro(t, specific_force, gyro) (body-frame specific force and "
                         "gyro rates)")


def body_instants(model, spans, rate: float | str | None, who: str) -> np.ndarray:
    """The samples inside ``spans`` (the whole window when None), thinned to at most ``rate`` Hz:
    per interval, the first sample at or after each of ``t0, t0 + 1/rate, ...`` (s); with
    ``rate="nodes"`` the coarse mesh's nodes inside ``spans`` (a model without a mesh is refused:
    its nodes are every sample)."""
    if isinstance(rate, str):
        t, word = _mesh_node_times(model, who), "mesh node"
    else:
        t, word = getattr(model, "sample_grid", model).t, "sample"   # a coarse mesh's nodes are some samples
    eps = 1e-9 * max(1.0, abs(float(t[0])), abs(float(t[-1])))
    spans = ((float(t[0]), float(t[-1])),) if spans is None else spans
    out = []
    for a, b in spans:
        if a < t[0] - eps or b > t[-1] + eps:
            raise InputError(f"{who}: interval ({a:g}, {b:g}) s reaches outside the recording window "
                             f"[{t[0]:g}, {t[-1]:g}] s; give intervals inside it (or omit t for all of it)")
        inside = np.flatnonzero((t >= a - eps) & (t <= b + eps))
        if inside.size == 0:
            raise InputError(f"{who}: no {word} lies in ({a:g}, {b:g}) s; widen the interval or drop it")
        if rate is not None and not isinstance(rate, str):
            ts = t[inside]
            marks = ts[0] + np.arange(int(np.floor((ts[-1] - ts[0]) * rate + 1e-9)) + 1) / rate
            pick = np.unique(np.clip(np.searchsorted(ts, marks - eps), 0, ts.size - 1))
            inside = inside[pick]
        out.append(inside)
    return t[np.unique(np.concatenate(out))]


def _mesh_node_times(model, who: str) -> np.ndarray:
    """``rate="nodes"``: the times of the model's coarse mesh nodes (s), or :class:`InputError`
    for a model without a mesh."""
    sample_grid = getattr(model, "sample_grid", None)
    grid = getattr(model, "grid", None)
    if sample_grid is None or grid is None or grid is sample_grid:
        raise InputError(f"{who}: rate='nodes' puts the rows at a coarse mesh's nodes, but this problem has "
                         "no mesh (every sample is a node: the rows would be as dense as the samples); give "
                         "NavigationProblem(..., segment=1.0) or the rows' rate in Hz, e.g. rate=1.0")
    return np.asarray(grid.t, dtype=float)


@dataclass(frozen=True, kw_only=True, eq=False)
class NonHolonomic(Item):
    r"""The body-frame lateral and vertical velocity of a point of a land vehicle is ~0.

    A car's wheels roll: the point above the rear axle moves along the car's own forward axis,
    neither sideways nor up. Between GNSS fixes this is what keeps a strapdown solution from
    drifting sideways. The rows are the body-frame velocity of the point ``lever``
    (:meth:`bvpnav.NavModel.body_velocity`): linear in the navigation velocity for the
    current attitude, and re-linearized with it by the attitude loop when the problem
    estimates attitude errors (:class:`~bvpnav.error_models.GyroBias`,
    :class:`~bvpnav.error_models.AttitudeError`, ...), so the constraint turns with the
    corrected heading instead of dragging the path along a wrong one.

    Parameters
    ----------
    axes : sequence of str
        Body axes whose velocity is ~0, among ``"x", "y", "z"`` (default ``("y", "z")``:
        lateral and vertical). The body frame is the IMU's (x forward, y left, z up on a car).
    lever : array_like (3,) or ``"estimated"``
        The point, m, in body axes from the IMU; default ``(0, 0, 0)`` (the IMU itself).
        Ideally the middle of the rear axle (the point of a car that does not slide when it
        turns; a point ``d`` m ahead of it moves sideways at ``d`` times the yaw rate).
        ``"estimated"``: the point is unknown, the parameters of
        :class:`~bvpnav.error_models.NhcLever` (add it to the error model, with a prior).
    t : (float, float) or list of them, optional
        Interval(s) in s where the vehicle rolls on the ground; default the whole recording.
    mounting : {None, "estimated"}
        ``"estimated"``: the IMU is not aligned with the vehicle, and the rows constrain the
        velocity across the *vehicle's* forward axis, whose yaw and pitch in the body frame are
        the parameters of :class:`~bvpnav.error_models.Mounting` (add it to the error model,
        with a prior). Default None: the body axes are the vehicle's.
    slip : None, float or ``"estimated"``
        The tyres' side slip in turns (see Notes): ``None`` (default) holds the lateral
        velocity at zero; a cornering compliance :math:`K` in s^2/m (the rear axle's side-slip
        angle, rad, per m/s^2 of lateral specific force, e.g. 0.007: about 3.9 degrees per g)
        makes the lateral rows :math:`v_y + K f_y v_x`; ``"estimated"``: :math:`K` is the
        parameter of :class:`~bvpnav.error_models.SideSlip` (add it to the error model, with
        its prior). Needs ``"y"`` in ``axes``.
    rate : float, ``"nodes"`` or None
        Rate of the rows, Hz (default 10): the samples nearest at or after ``t0 + k / rate``
        per interval; ``None`` for every sample. The errors of this information (tyre slip,
        misalignment) are correlated over many samples, so rows much denser than they
        decorrelate add weight, not information. ``"nodes"``: the rows at the nodes of the
        coarse mesh (``NavigationProblem(..., segment=)``) inside the intervals, and nowhere
        else (see Notes); refused without a mesh (there every sample is a node: rows as dense
        as the samples, the overcount above at its worst).
    tol : float or array_like, optional
        Half-width of the band, m/s (per axis allowed). Default :data:`DEFAULT_TOL` = 0.1
        m/s in ``mode="band"`` (the default mode): the velocity may be anywhere within
        ``tol``, so a car that skids a little does not drag the solution.
    sigma, mode, huber, name
        See :class:`bvpnav.items.Item`. With nothing given the band has soft edges of sigma
        :data:`DEFAULT_EDGE_SIGMA` = 0.1 m/s (see Notes): where the car skids more than
        ``tol`` the excess is a soft penalty, reported by :meth:`active`. ``tol`` alone (or
        ``mode="band"`` without ``sigma``) makes the band's edges hard; ``sigma`` alone
        (m/s) makes the rows soft; ``mode="hard"`` makes them exact.

    Notes
    -----
    Rows at the chosen samples :math:`t_k`, per body axis :math:`j` (time-major):

    .. math:: \rho_{k,j} = e_j^T \left( C_k^T v_n(t_k) + \omega_k \times \ell \right)

    with :math:`C_k` the body-to-navigation attitude (the attitude loop's current point),
    :math:`v_n` the FEM velocity, :math:`\omega_k` the corrected body rate and :math:`\ell`
    the lever; band: :math:`|\rho_{k,j}| \le tol_j`. With attitude error models the rows
    also carry the first-order change :math:`C_k^T [v^0\times] \psi_k` of the attitude
    increments (see :meth:`bvpnav.NavModel.body_velocity`). With ``mounting="estimated"``
    the rows are :math:`\rho_{k,y} - s_y v^0_{x,k}` and :math:`\rho_{k,z} + s_z v^0_{x,k}`
    (:meth:`bvpnav.NavModel.mounting_velocity`): zero when the point moves along the
    vehicle's forward axis :math:`(1, s_y, -s_z)` in body axes. With ``lever="estimated"``
    :math:`\ell` is the unknown of :class:`~bvpnav.error_models.NhcLever` and
    :math:`\omega_k \times \ell = [\omega_k\times]\,\ell` is linear in it
    (:meth:`bvpnav.NavModel.vehicle_point_velocity`).

    **The band's edges.** A hard band says the point never moves sideways faster than
    ``tol``. A car does, in a sharp turn or on a loose surface, and where the fixes are dense
    enough to show it a hard edge pulls the path against them. The default band's edges are
    soft: the penalty :math:`\lambda \sum (\max(|\rho| - tol, 0)/\sigma)^2` is zero
    within the band and grows beyond it as a soft row of sigma :math:`\sigma` would from the
    edge (:class:`bvpnav.items.Item`, "band with sigma"), so the band costs nothing where the
    car rolls and still holds a drifting solution where nothing else does.

    **Rows at the mesh's nodes** (``rate="nodes"``). On a coarse mesh the unknowns are the
    nodes' positions, velocities and states; between nodes the velocity is not an unknown but
    the conditional mean of the samples' residuals given the element's loads
    (:func:`bvpnav.mesh.rows_inside_elements`, :meth:`bvpnav.mesh.MeshModel.sample_velocity`),
    which a row profile inside an element can only pull through those two loads per axis.
    At the nodes the rows read the model's velocity and attitude error where it has them,
    and need no nodes of their own (the mesh is built first, from the other items and
    ``segment``; the rows follow it). It is also the honest weight: what this information
    gets wrong (tyre slip, a mounting misalignment, suspension travel) is correlated over
    about a second, so rows at 10 Hz with independent sigmas count each error about ten
    times; one row per node of a 1 s mesh counts it about once. Where other items give the
    mesh denser nodes (fixes at 10 Hz, a zero-velocity interval's samples) the rows follow
    them and are as dense there.

    **Side slip** (``slip=``). A car is not non-holonomic in a turn: a tyre carries a lateral
    force by rolling at a slip angle :math:`\alpha` to its heading, and in the linear range
    (below about 0.4 g) the force is proportional to it, :math:`F_y = -C_\alpha \alpha`
    with :math:`\alpha = \arctan(v_y / v_x) \approx v_y / v_x` of the wheel's velocity
    and :math:`C_\alpha` the axle's cornering stiffness (N/rad): the force opposes the
    sideways sliding. In a steady turn the rear axle carries the share of the lateral force
    its load :math:`W_r` carries of the weight, :math:`F_{y,r} = W_r\, a_y / g` (moments
    about the centre of gravity: the steady-state cornering of the bicycle model, Gillespie,
    *Fundamentals of Vehicle Dynamics*, SAE 1992, ch. 6; Rajamani, *Vehicle Dynamics and
    Control*, 2nd ed., Springer 2012, ch. 2-3).
    The lateral force the tyres carry per unit mass is what the accelerometer measures, the
    lateral specific force :math:`f_y` (gravity's component on a banked road included, so
    no bank angle is needed). So the middle of the rear axle slides outwards at

    .. math:: v_y = -\frac{W_r}{g\, C_{\alpha r}}\, f_y\, v_x = -K f_y v_x ,

    :math:`K = D_r / g` with :math:`D_r = W_r / C_{\alpha r}` the rear axle's cornering
    compliance (rad per g; Gillespie's understeer gradient is :math:`D_f - D_r`): the side-slip
    angle :math:`\beta = v_y / v_x = -K f_y`, outwards (right, :math:`-y`) in a left turn
    (:math:`f_y > 0`). The lateral row becomes :math:`\rho_{k,y} + K f_y(t_k)\,
    \rho_{k,x}` with :math:`\rho_{k,x}` the point's forward velocity; with ``slip=
    "estimated"`` :math:`K f_y v^0_x` with :math:`v^0_x` the loop's linearization point
    (:meth:`bvpnav.NavModel.side_slip_velocity`; exact at the loop's answer). For a car
    driving forward (:math:`v_x > 0`); the published figures for :math:`K` are under
    :class:`~bvpnav.error_models.SideSlip`. The point should be the rear axle's middle
    (``lever``): a point :math:`d` m ahead of it moves sideways at :math:`d` times the yaw
    rate besides.

    Examples
    --------
    >>> from bvpnav.constraints import NonHolonomic
    >>> item = NonHolonomic()
    >>> item.mode, item.axes, float(item.tol), float(item.sigma), item.units
    ('band', ('y', 'z'), 0.1, 0.1, 'm/s')
    >>> NonHolonomic(tol=0.1).sigma is None          # a band with hard edges
    True
    >>> NonHolonomic(sigma=0.05, rate=2.0, t=[(0.0, 50.0), (70.0, 120.0)]).mode
    'soft'
    """

    lever: Any = (0.0, 0.0, 0.0)
    t: Any = None
    rate: Any = 10.0
    mounting: Any = None
    slip: Any = None
    units = "m/s"
    #: The item's axes are body axes (the contract check compares one body axis's rows with
    #: the rows of all of them instead of looking for navigation axes).
    body_frame: ClassVar[bool] = True

    def __post_init__(self):
        if self.mode is None and self.sigma is None and self.tol is None:
            object.__setattr__(self, "mode", "band")
            object.__setattr__(self, "tol", DEFAULT_TOL)
            object.__setattr__(self, "sigma", DEFAULT_EDGE_SIGMA)
        elif self.mode is None and self.tol is not None and self.sigma is None:
            object.__setattr__(self, "mode", "band")
        elif str(self.mode).lower() == "band" and self.tol is None:
            object.__setattr__(self, "tol", DEFAULT_TOL)
        super().__post_init__()

    def validate(self) -> None:
        label = self.label
        axes = ("y", "z") if self.axes is None else self.axes
        bad = [a for a in axes if a not in _BODY]
        if bad:
            raise InputError(f"{label}: axes={list(axes)}; give body axes among {list(_BODY)} (x forward, "
                             "y left, z up), e.g. axes=('y', 'z')")
        if len(set(axes)) != len(axes):
            raise InputError(f"{label}: axes={list(axes)} names an axis twice")
        object.__setattr__(self, "axes", tuple(axes))
        if self.mounting not in (None, "estimated"):
            raise InputError(f"{label}: mounting={self.mounting!r}; give 'estimated' (the yaw and pitch of "
                             "the error model's Mounting) or None (the body axes are the vehicle's)")
        if self.mounting is not None and "x" in axes:
            raise InputError(f"{label}: mounting='estimated' with axes={list(axes)}; the mounting turns the "
                             "lateral and vertical rows: give axes among ('y', 'z')")
        object.__setattr__(self, "lever", lever_arm(self.lever, label))
        object.__setattr__(self, "slip", slip_value(self.slip, label))
        if self.slip is not None and "y" not in axes:
            raise InputError(f"{label}: slip={self.slip!r} with axes={list(axes)}; the side slip acts on the "
                             "lateral rows: give axes with 'y' (e.g. axes=('y', 'z')) or drop slip")
        object.__setattr__(self, "t", intervals(self.t, label))
        object.__setattr__(self, "rate", positive_rate(self.rate, label))

    @property
    def reads_error_model(self) -> bool:
        """Whether the rows read a parameter of the error model (the :class:`~bvpnav.error_models.
        Mounting` with ``mounting="estimated"``, the :class:`~bvpnav.error_models.NhcLever` with
        ``lever="estimated"``, the :class:`~bvpnav.error_models.SideSlip` with ``slip=
        "estimated"``): the contract check then solves with it."""
        return self.mounting is not None or isinstance(self.lever, str) or isinstance(self.slip, str)

    @property
    def rows_at_nodes(self) -> bool:
        """``rate="nodes"``: the rows sit at the coarse mesh's nodes and ask it for none
        (:func:`bvpnav.mesh.item_times`)."""
        return self.rate == NODES

    def row_layout(self, m: int) -> tuple[int, int]:
        """``(instants, body axes)``: sigma and tol may be given per axis."""
        a = len(self.axes)
        return (m // a, a) if m % a == 0 else (m, 1)

    def instants(self, model) -> np.ndarray:
        """The rows' times (s): the samples in the intervals at :attr:`rate` (with ``"nodes"``
        the mesh's nodes in them)."""
        return body_instants(model, self.t, self.rate, self.identify())

    @classmethod
    def example(cls) -> NonHolonomic:
        """A valid instance for :meth:`example_model` (band, the default)."""
        return cls(lever=(-0.5, 0.0, -0.3), t=[(0.0, 4.0), (6.0, 10.0)], rate=5.0)

    @classmethod
    def example_model(cls):
        """Strapdown data on [0, 10] s (101 samples) of a car-like motion: forward acceleration,
        a turn, pitch and roll changing (the contract check compiles :meth:`example` for it)."""
        return vehicle_example_model()

    def compile(self, model):
        who = self.identify()
        check_body_data(model, who)
        t = self.instants(model)
        rows = point_rows(model, t, self.axes, self.lever, who)
        if self.slip is not None:
            rows = rows + slip_rows(model, t, self.axes, self.lever, self.slip, who)
        if self.mounting is not None:
            lever = None if isinstance(self.lever, str) else self.lever
            # no constant: the rows' labels and c
            rows = rows + model.mounting_velocity(t, self.axes, lever=lever, what=who)
        return without_rounding_noise(rows) if self.rows_at_nodes else rows

    def active(self, solution, rtol: float = 1e-3):
        """The rows at or beyond the band's edge in a solution: where the vehicle slid by at
        least ``tol`` (beyond it only with the default soft edges).

        Parameters
        ----------
        solution : Solution
            A solution of a problem holding this item (found by its label).
        rtol : float
            A row is at the edge when ``|rho| >= tol (1 - rtol)``.

        Returns
        -------
        pandas.DataFrame
            Columns ``t`` (s), ``axis`` (body axis) and ``velocity`` (m/s), one row per active
            row, in time order; empty for an item that is not a band.
        """
        import pandas as pd

        r = solution.item_residuals.get(self.label)
        if r is None:
            raise InputError(f"{self.identify()}: not in this solution (its items: "
                             f"{sorted(solution.item_residuals)})")
        if self.mode != "band" or self.tol is None:
            return pd.DataFrame({"t": [], "axis": [], "velocity": []})
        r = np.asarray(r, dtype=float)
        tol = self.tol_rows(r.size)
        a = len(self.axes)
        k = np.flatnonzero(np.abs(r) >= tol * (1.0 - rtol))
        times = np.asarray(solution.item_rows[self.label].t, dtype=float) if self.label in getattr(
            solution, "item_rows", {}) else np.full(r.size, np.nan)
        return pd.DataFrame({"t": times[k], "axis": [self.axes[i % a] for i in k], "velocity": r[k]})

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"e_j^T (C_k^T v_n(t_k) + \omega_k \times \ell) = 0"

    def math(self) -> str:
        out = f"e_j^T (C^T v_n(t_k) + omega x {lever_text(self.lever)}) = 0 for body axes {list(self.axes)}"
        if self.slip is None:
            return out
        k = "estimated (SideSlip)" if isinstance(self.slip, str) else f"= {self.slip:g} s^2/m"
        return out + f", the lateral one plus K f_y v_x with K {k}"


def vehicle_example_model():
    """Strapdown data on [0, 10] s (101 samples): a car-like motion (speeding up, turning, pitch
    and roll changing), the attitude integrated from the rates."""
    from scipy.spatial.transform import Rotation

    from bvpnav.imu import ImuData
    from bvpnav.model import NavModel

    t = np.linspace(0.0, 10.0, 101)
    w = np.column_stack([0.02 * np.sin(t), 0.03 * np.cos(0.7 * t), 0.2 * np.sin(0.4 * t)])
    f = np.column_stack([0.8 + 0.3 * np.sin(t), 0.5 * np.sin(0.4 * t), np.full(t.size, 9.80665)])
    data = ImuData.from_gyro(t, f, w, initial_attitude=Rotation.from_euler("ZYX", [0.4, 0.02, -0.01]),
                             checks=False)
    return NavModel(data)
