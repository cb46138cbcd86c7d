"""What the problem is: data, objective form, error model and items, compiled to terms.

A :class:`Formulation` is immutable: the same data, residual form, ``sigma_a``, error
model and items always compile to the same :class:`~bvpnav.terms.Term` list (cached).
Everything that *solves* (the least-squares view, the cvxpy problem, the back ends, the
lambda rules and the solve pipeline) takes a formulation and never the user's
:class:`~bvpnav.NavigationProblem`; a stage that changes the information (demotion,
linearization) makes a new formulation with :meth:`Formulation.with_items`.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable
from typing import Any

import numpy as np
import scipy.sparse as sp

from .errors import BvpnavError, ConvexityError, InputError
from .grid import mesh_nodes
from .imu import ImuData
from .items import Item, Linearizable, positive_array
from .mesh import MeshModel, check_segment, item_times
from .model import Affine, NavModel, state_component
from .sensors import DEFAULT_GRADE, resolve_grade
from .terms import Term

__all__ = ["Formulation", "as_formulation", "RESIDUAL_FORMS", "LAM_RANGE", "WEIGHT_RANGE",
           "SIGMA_A_RANGE", "ACC_MAX", "label_items", "original"]

RESIDUAL_FORMS = ("acceleration", "load")

#: Lambda values other than 0 that double precision can weigh against the data term: a
#: weight beyond 1e12 (or below 1e-12) leaves one side of the objective below rounding of
#: the other (the answer is that of hard items, or of no soft items).
LAM_RANGE = (1e-12, 1e12)

#: Bounds of the squared weight of a term relative to the data term (dimensionless, see
#: :meth:`Formulation.check_scales`): 30 orders of magnitude either way, far from the
#: overflow of a square (1e308) and wider than any physical choice of sigma.
WEIGHT_RANGE = (1e-30, 1e30)

#: Accelerometer noise standard deviations (m/s^2) double precision handles in the
#: acceleration form's weights 1/sigma_a^2.
SIGMA_A_RANGE = (1e-12, 1e12)

#: Largest acceleration magnitude (m/s^2) accepted: 1e9 m/s^2 is 1e8 g, beyond any
#: accelerometer; larger values are a unit mistake and overflow the squared residuals.
ACC_MAX = 1e9


def as_formulation(obj) -> Formulation:
    """``obj`` itself when it is a :class:`Formulation`, else its ``formulation``
    (a :class:`~bvpnav.NavigationProblem`)."""
    if isinstance(obj, Formulation):
        return obj
    form = getattr(obj, "formulation", None)
    if isinstance(form, Formulation):
        return form
    raise InputError(f"expected a bvpnav.NavigationProblem or Formulation, got {type(obj).__name__}")


class _Renamed:
    """Give a second unnamed item of the same class a unique label without mutating it."""

    @staticmethod
    def wrap(item: Item, label: str) -> Item:
        clone = object.__new__(type(item))
        clone.__dict__.update(item.__dict__)
        object.__setattr__(clone, "name", label)
        object.__setattr__(clone, "_original", item)
        return clone


def original(item: Item) -> Item:
    """The item as the user gave it (before a unique label was attached)."""
    return item.__dict__.get("_original", item)


def label_items(items: Iterable[Item], taken: Iterable[str] = ()) -> list[Item]:
    """Items with unique labels: an unnamed item whose class label is taken becomes
    ``Class#k`` (a relabelled copy; the user's item is not changed).

    Raises
    ------
    InputError
        For something that is not an item, or a second item with the same explicit name.
    """
    taken = set(taken)
    out = []
    for it in items:
        if not isinstance(it, Item):
            raise InputError(
                f"add(): {it!r} is not a bvpnav item; build one from bvpnav.constraints "
                "(e.g. Position(t=0.0, value=0.0))"
            )
        label = it.label
        if it.name is None and label in taken:
            k = 2
            while f"{label}#{k}" in taken:
                k += 1
            label = f"{label}#{k}"
            it = _Renamed.wrap(it, label)
        elif it.name is not None and label in taken:
            raise InputError(f"add(): an item named {label!r} is already in the problem; item names "
                             "identify items (priority, demote_sigma, messages): rename one of them "
                             "(name=...)")
        taken.add(label)
        out.append(it)
    return out


def _check_sigma_a(sigma_a, data: ImuData) -> np.ndarray:
    """``sigma_a`` as (d,) (one value or one per axis) or (N, d) (per sample), checked."""
    if sigma_a is None:
        return np.ones(data.ndim)
    sa = positive_array(sigma_a, "sigma_a (m/s^2)", False)
    n, d = data.n, data.ndim
    if sa.ndim <= 1 and sa.size in (1, d):
        sa = np.array(np.broadcast_to(sa.ravel(), (d,)), dtype=float)
    elif sa.ndim == 1 and sa.size == n:
        sa = np.repeat(sa[:, None], d, axis=1)
    elif sa.shape == (n, d) or (sa.ndim == 2 and sa.shape == (n, 1)):
        sa = np.array(np.broadcast_to(sa, (n, d)), dtype=float)
    else:
        raise InputError(f"sigma_a: shape {sa.shape} for {n} samples on the axes {list(data.axes)}; give "
                         f"one value in m/s^2, one per axis ({d}), one per sample ({n},) or one per sample "
                         f"and axis ({n}, {d})")
    flat = sa.reshape(-1, d)
    for i, k in zip(*np.nonzero((flat < SIGMA_A_RANGE[0]) | (flat > SIGMA_A_RANGE[1])), strict=True):
        where = f"axis {data.axes[k]}" + (f", sample {i}" if sa.ndim == 2 else "")
        raise InputError(
            f"sigma_a = {flat[i, k]:g} m/s^2 ({where}) is outside "
            f"{SIGMA_A_RANGE[0]:g}..{SIGMA_A_RANGE[1]:g} m/s^2, where the weights 1/sigma_a^2 "
            "stay resolvable in double precision; give the accelerometer noise in m/s^2 "
            "(typically 1e-4 to 1)")
    sa.setflags(write=False)
    return sa


def _clipped(sa: np.ndarray, data: ImuData) -> np.ndarray:
    """``sigma_a`` with ``max(sigma_a, data.acc_range)`` at the samples marked clipped."""
    clipped = getattr(data, "acc_clipped", None)
    if clipped is None or not clipped.any():
        return sa
    out = np.array(np.broadcast_to(sa, (data.n, data.ndim)) if sa.ndim == 1 else sa, dtype=float)
    out[clipped] = np.maximum(out[clipped], float(data.acc_range))
    out.setflags(write=False)
    return out


def _check_acc(data: ImuData) -> None:
    acc = np.asarray(data.acc, dtype=float)
    # the largest and smallest entries, NaN left out (fmax / fmin), no array of the whole size
    if not acc.size or not (np.fmax.reduce(acc, axis=None) > ACC_MAX
                            or np.fmin.reduce(acc, axis=None) < -ACC_MAX):
        return
    with np.errstate(invalid="ignore"):
        big = np.abs(acc) > ACC_MAX
    if not np.any(big):
        return
    i, a = np.unravel_index(int(np.argmax(big)), big.shape) if big.ndim > 1 else (int(np.argmax(big)), 0)
    val = acc.reshape(data.n, -1)[i, a]
    raise InputError(
        f"acceleration at sample {i} (t={data.t[i]:g} s), axis {data.axes[a]}, is {val:g} "
        f"m/s^2: beyond {ACC_MAX:g} m/s^2 (1e8 g), which no accelerometer measures and whose "
        f"squares overflow; {int(np.count_nonzero(big))} sample(s) exceed it. Check the "
        "unit of the acceleration column (m/s^2 expected) or remove the corrupt samples")


def _with_grade(error_model, grade, data) -> tuple[Any, dict[str, Any] | None]:
    """The error model with ``grade``'s priors when it has gyro parameters and states no prior at
    all, and the report (grade name, figures, the priors filled in); else the model as given and
    None. A model with any prior stated is the user's own statement and is left alone (priors of
    models of other sensors, ``other_sensor = True`` such as an odometer's scale, do not count)."""
    from .error_models._attitude import AttitudeErrorModel

    if error_model is None or grade is None or not data.is_strapdown:
        return error_model, None
    parts = getattr(error_model, "components", (error_model,))
    if not any(isinstance(c, AttitudeErrorModel) for c in parts):
        return error_model, None
    # a prior of a model of another sensor (an odometer's scale) says nothing about the IMU's
    imu = [c for c in parts if not getattr(c, "other_sensor", False)]
    if any(getattr(c, k, None) is not None for c in imu for k in ("sigma", "prior", "drift", "bounds")):
        return error_model, None
    model, filled = grade.complete(error_model)
    if not filled:
        return error_model, None
    return model, {"name": grade.name, "filled": filled, "figures": grade.table()}


def _meshed(data: ImuData, segment: float, error_model, items, nodes=None) -> ImuData:
    """``data`` for a coarse mesh: with node states (:class:`~bvpnav.error_models.ErrorStates`) a
    shallow copy carrying the mesh's node samples as ``state_mesh`` (the states sit at the
    nodes); else ``data`` itself. The mesh is ``nodes`` (a shared model's), a node-state loop
    step's (its measured data's), or made from ``segment`` and the items. The user's data is
    never changed."""
    if state_component(error_model) is None:
        return data
    point = getattr(data, "state_point", None)
    if point is not None:   # a node-state loop's step: the mesh its measured data carries
        nodes = getattr(point.raw, "state_mesh", None)
        if nodes is None:
            raise InputError("segment=: this data carries a node-state linearization point made without a "
                             "mesh; give the data as measured")
    elif nodes is None:
        nodes = mesh_nodes(data.grid, segment, item_times(items, data.grid))
    if np.array_equal(getattr(data, "state_mesh", None), nodes):
        return data
    out = copy.copy(data)
    out.state_mesh = np.asarray(nodes)
    return out


class Formulation:
    r"""Data + objective form + error model + items, compiled (once) to terms.

    Parameters
    ----------
    data : ImuData
    residual : {"acceleration", "load"}
        Objective form (see :class:`bvpnav.NavigationProblem`).
    sigma_a : float or array_like, optional
        Accelerometer noise standard deviation, m/s^2 (acceleration form only): one
        value, one per axis (d,), one per sample (N,) or per sample and axis (N, d);
        stored as (d,) or (N, d).
    error_model : ErrorModel, optional
    items : iterable of Item
        Items with unique labels (see :func:`label_items`).
    model : NavModel, optional
        A model of the same data and error model to share (its FEM matrices).
    grade : str or SensorGrade or None
        The sensor grade whose figures become the priors of a strapdown error model with
        gyro parameters (``GyroBias``, ``AttitudeError``) that states no prior at all
        (:meth:`bvpnav.sensors.SensorGrade.complete`); default ``"consumer"``. None: no
        priors are assumed. What was filled in is ``grade_report`` (None when nothing was).
    segment : float, optional
        Solve on a coarse mesh of the samples (:class:`bvpnav.mesh.MeshModel`): nodes at the
        items' instants and no element longer than ``segment`` s, the samples between nodes
        condensed exactly. None (default): every sample is a node.

    Notes
    -----
    The data term :math:`J_0` is :math:`\sum_i \|w_i / \sigma_a\|^2` (acceleration form)
    or :math:`\|M w\|^2 = \|K r + B v - f - F l\|^2` (load form); see
    :meth:`data_rows`.
    """

    def __init__(self, data: ImuData, residual: str = "acceleration", sigma_a=None, error_model=None,
                 items: Iterable[Item] = (), model: NavModel | None = None, grade: Any = DEFAULT_GRADE,
                 segment: float | None = None):
        if not isinstance(data, ImuData):
            raise InputError(f"data must be a bvpnav.ImuData, got {type(data).__name__}")
        if residual not in RESIDUAL_FORMS:
            raise InputError(f"residual={residual!r}; choose one of {list(RESIDUAL_FORMS)}")
        if sigma_a is not None and residual == "load":
            raise InputError("sigma_a goes with residual='acceleration'; the load form has no sigma_a")
        self.segment = check_segment(segment)
        if self.segment is not None and residual != "acceleration":
            raise InputError("segment= goes with residual='acceleration' (the condensed residuals are "
                             "weighted "
                             "by sigma_a); solve the load form on every sample (segment=None)")
        items = tuple(label_items(items))
        if self.segment is not None:   # a shared model keeps its mesh
            data = _meshed(data, self.segment, error_model, items,
                           model.grid.nodes if isinstance(model, MeshModel) else None)
        self.data = data
        self.residual = residual
        self.sigma_a = _check_sigma_a(sigma_a, data)
        #: ``sigma_a`` as the data rows use it: with ``max(sigma_a, acc_range)`` at the
        #: samples the data mark clipped (:meth:`bvpnav.ImuData.mark_acc_range`), (d,) or (N, d).
        self.sigma_a_used = _clipped(self.sigma_a, data)
        self.sigma_a_given = sigma_a is not None
        _check_acc(data)
        self.grade = resolve_grade(grade)
        #: The error model as given (``error_model`` is it with the grade's priors filled in).
        self.error_model_given = error_model
        self.error_model, self.grade_report = _with_grade(error_model, self.grade, data)
        self.items: tuple[Item, ...] = items  # unique labels (a no-op when they are)
        self._model = model
        self._terms: list[Term] | None = None
        self._observable = False
        self._data_rows: Affine | None = None

    # ----------------------------------------------------------- copies
    def with_items(self, items: Iterable[Item], error_model: bool = True) -> Formulation:
        """The same data, objective form and sigma_a with other items (labels kept).

        With ``error_model=True`` the copy keeps the error model and shares this
        formulation's :class:`NavModel`; without it the copy has no error-model parameters.
        """
        items = list(items)
        share = error_model and (self.segment is None or self._on_mesh(items))
        return Formulation(self.data, self.residual, self.sigma_a if self.sigma_a_given else None,
                           self.error_model_given if error_model else None, items,
                           model=self._model if share else None, grade=self.grade, segment=self.segment)

    def _on_mesh(self, items) -> bool:
        """Whether this formulation's mesh (when made) has nodes at every instant of ``items``."""
        if self._model is None:
            return True
        try:
            grid = self._model.grid
            grid.check_on_mesh(grid.check_inside(item_times(items, self.data.grid), "t"), "t")
        except InputError:
            return False
        return True

    @property
    def labels(self) -> list[str]:
        """Unique labels of the items, in order."""
        return [i.label for i in self.items]

    @property
    def nonlinear_items(self) -> list[Item]:
        """Items that must be linearized before they compile (:class:`Linearizable`)."""
        return [it for it in self.items if isinstance(it, Linearizable) and it.needs_linearization]

    # -------------------------------------------------------- compiling
    @property
    def model(self) -> NavModel:
        """The :class:`NavModel` (unknowns and their maps), built on first use."""
        if self._model is None:
            if self.segment is None:
                self._model = NavModel(self.data, self.error_model)
            else:
                self._model = MeshModel(self.data, self.error_model, segment=self.segment,
                                        times=item_times(self.items, self.data.grid),
                                        sigma_a=self.sigma_a_used,
                                        nodes=getattr(self.data, "state_mesh", None))
        return self._model

    def terms(self) -> list[Term]:
        """Every item (and the error model's priors and bounds) compiled to terms, once."""
        if self._terms is not None:
            return self._terms
        model = self.model
        terms = [self._compile(it, model) for it in self.items]
        if self.error_model is not None:
            terms.extend(self.error_model.terms(model))
        self._terms = terms
        return terms

    @staticmethod
    def _compile(it: Item, model: NavModel) -> Term:
        label = it.label
        try:
            res = it.compile(model)
        except BvpnavError:
            raise
        except Exception as exc:  # a custom item's bug: name the item
            raise BvpnavError(f"{label}: compile() failed: {type(exc).__name__}: {exc}") from exc
        if not isinstance(res, Affine):
            raise ConvexityError(
                f"{label}: compile() returned {type(res).__name__}; items must return a "
                "bvpnav.model.Affine residual built from the model's maps"
            )
        if res.m == 0:
            raise InputError(f"{label}: produced no rows (nothing to constrain)")
        return Term(label=label, item=original(it), residual=res, mode=it.mode, kind=it.kind,
                    sigma=it.weight_rows(res.m), tol=it.tol_rows(res.m), huber=it.huber,
                    units=it.units)

    def data_rows(self) -> Affine:
        """Rows whose sum of squares is the data term ``J_0`` (see class Notes); made once
        (the least-squares form, the cvxpy problem and the verification all read them)."""
        if self._data_rows is None:
            m = self.model
            if self.residual == "acceleration":
                self._data_rows = m.residual_rows() / m.residual_sigma(self.sigma_a_used)
            else:
                self._data_rows = m.load_residual_rows()
        return self._data_rows

    def with_acceleration(self, acc: np.ndarray) -> Formulation:
        """The same formulation with the measured accelerations replaced by ``acc`` (shape
        ``(N, d)``, m/s^2), sharing everything else: the form is affine in the data, so
        the lambda sweep's GCV trace differences two of these. Nothing is checked again."""
        new = copy.copy(self)
        new._model, new._terms, new._data_rows = self.model.with_acc(acc), None, None
        return new

    @property
    def has_soft_terms(self) -> bool:
        """True when ``lam`` multiplies at least one term."""
        return any(t.is_penalty and t.scaled_by_lam for t in self.terms())

    def least_squares_items(self) -> bool:
        """Whether every item is a hard or soft equality and no error-model bound exists,
        judged from the items' declared kind and mode (no compilation: N may be huge)."""
        for it in self.items:
            if it.kind != "equality" or it.mode in ("band", "robust"):
                return False
        em = self.error_model
        comps = getattr(em, "components", (em,)) if em is not None else ()
        return all(getattr(c, "bounds", None) is None for c in comps)

    # ---------------------------------------------------- observability
    def null_directions(self) -> tuple[np.ndarray, list[str]]:
        """Directions of ``x`` the FEM equations leave free when ``w = 0``.

        Returns
        -------
        Z : ndarray, shape (n_unknowns, 2 d + q)
            Per axis a position offset (m) and a velocity offset (m/s), then one direction
            per error-model parameter (the trajectory change it causes, starting at rest).
        names : list of str
        """
        Z, names = self._null_columns()
        return Z.toarray(), names

    def _null_columns(self, at: np.ndarray | None = None) -> tuple[sp.csc_matrix, list[str]]:
        """:meth:`null_directions` as a sparse matrix (made from each direction's nonzero
        entries: a dense (n, 2 d + q) array costs memory and time of the whole problem's
        size for a product with a few item rows). With ``at`` (indices of unknowns), only
        those rows are filled, the others left empty: the product with rows that touch
        nothing else is the same, and a few items do not cost the whole (n, 2 d + q) matrix."""
        m = self.model
        t = m.grid.t
        keep = None
        if at is not None:
            keep = np.zeros(m.size, dtype=bool)
            keep[at] = True
        rows, vals, names = [], [], []

        def add(r: np.ndarray, v: np.ndarray) -> None:
            if keep is not None:
                sel = keep[r]
                r, v = r[sel], v[sel]
            rows.append(r)
            vals.append(v)

        for a, ax in enumerate(m.axes):
            v0, v1 = m.v_end_index(a)
            add(m.r_index(a), np.ones(m.N))
            add(np.concatenate([m.r_index(a), [v0, v1]]), np.concatenate([t - t[0], [1.0, 1.0]]))
            names += [f"axis {ax}: position offset", f"axis {ax}: velocity offset"]
        h = m.grid.h
        for k, pname in enumerate(m.param_names):
            r, v = [], []
            for a in range(m.d):
                mcols, mgs = m.mg_columns(a)   # M G, made once per axis with the model
                i = int(np.searchsorted(mcols, k))
                if i == mcols.size or mcols[i] != k or not mgs[:, i].any():
                    continue   # the parameter does not act on this axis
                mg = mgs[:, i]
                s = np.cumsum(mg)[:-1]  # element slopes with v0 = 0
                r += [m.r_index(a), [m.v_end_index(a)[1]]]
                v += [np.concatenate([[0.0], np.cumsum(s * h)]), [s[-1] + mg[-1]]]
            add(np.concatenate(r + [[m.l_index[k]]]).astype(np.int64), np.concatenate(v + [[1.0]]))
            names.append(f"parameter {pname}")
        indptr = np.concatenate([[0], np.cumsum([r.size for r in rows])])
        Z = sp.csc_matrix((np.concatenate(vals), np.concatenate(rows), indptr), shape=(m.size, len(names)))
        return Z, names

    def unobservable(self) -> list[str]:
        """Names of unknown directions that no item pins down (empty when all are)."""
        terms = [t for t in self.terms() if t.kind == "equality"]
        if not terms:
            return self._null_columns(at=np.zeros(0, dtype=np.int64))[1]
        A = Affine.vstack([t.residual for t in terms]).A
        Z, names = self._null_columns(at=np.unique(A.indices))
        DZ = (A @ Z).toarray()
        norms = np.linalg.norm(DZ, axis=0)
        scale = norms.max() if norms.size and norms.max() > 0 else 1.0
        out = [names[k] for k in np.flatnonzero(norms <= 1e-12 * scale)]
        ok = np.flatnonzero(norms > 1e-12 * scale)
        if ok.size:
            out += self._combinations(DZ[:, ok] / norms[ok], [names[j] for j in ok])
        return out

    @staticmethod
    def _combinations(Dn: np.ndarray, names: list[str]) -> list[str]:
        """The undetermined combinations of unit directions ``Dn`` (columns), by name."""
        # with fewer information rows than directions the null space has more vectors than
        # there are singular values: pad with zero rows (never a full U: M x M)
        if Dn.shape[0] < Dn.shape[1]:
            Dn = np.vstack([Dn, np.zeros((Dn.shape[1] - Dn.shape[0], Dn.shape[1]))])
        _, s, vt = np.linalg.svd(Dn, full_matrices=False)
        rank = int(np.sum(s > 1e-9 * s[0])) if s.size else 0
        null = vt[rank:]
        if not null.shape[0]:
            return []
        involved = sorted({int(j) for comb in null
                           for j in np.flatnonzero(np.abs(comb) > 0.1 * np.abs(comb).max())})
        return [f"{null.shape[0]} combination(s) of: " + ", ".join(names[j] for j in involved)]

    def check_observability(self) -> None:
        """Raise :class:`InputError` naming what the information leaves undetermined."""
        if self._observable:  # checked for these terms already
            return
        missing = self.unobservable()
        if missing:
            params = self.error_model is not None and any("parameter " in m for m in missing)
            hint = ""
            if params and self.data.is_strapdown:
                hint = (" Or give the error model priors (sigma=, drift= on Bias / GyroBias, sigma= on "
                        "AttitudeError), e.g. from a sensor grade: NavigationProblem(..., grade='consumer') "
                        "fills in the priors a gyro error model does not state"
                        + ("" if self.grade is None else f" (this problem's grade "
                           f"{self.grade.name!r} left these undetermined: give priors or more items)") + ".")
            # a model observed by its own kind of item says which (OdometerScale: Odometer items)
            comps = getattr(self.error_model, "components", (self.error_model,)) if params else ()
            for c in comps:
                own = getattr(c, "observability_hint", None)
                if own and any(f"parameter {n}" in m for n in c.names(self.data) for m in missing):
                    hint += " " + own
            raise InputError(
                "not enough information: nothing determines " + "; ".join(missing)
                + ". Add items (e.g. Position at an end for an offset, a second Position or a "
                "Velocity for a velocity offset, more velocities for error-model parameters) "
                "or remove error-model parameters." + hint
            )
        self._observable = True

    def check_scales(self, lam: float) -> None:
        """Raise :class:`InputError` naming a weight double precision cannot resolve.

        The squared weight of every soft (or robust) row relative to the data term,
        ``(lam if the term is lambda-weighted else 1) * (s / sigma)^2`` with ``s`` the
        smallest ``sigma_a`` (acceleration form) or 1 (load form), must lie within
        :data:`WEIGHT_RANGE`; beyond it one side of the objective is lost in rounding of
        the other, or its square overflows.
        """
        ref = float(np.min(self.sigma_a)) if self.residual == "acceleration" else 1.0
        lo, hi = WEIGHT_RANGE
        for term in self.terms():
            k = term.weight(lam)
            if not term.is_penalty or term.sigma is None or k == 0:
                continue
            sig = np.asarray(term.sigma, dtype=float)
            with np.errstate(all="ignore"):
                w2 = k * (ref / sig) ** 2
            bad = np.flatnonzero(~((w2 >= lo) & (w2 <= hi)))
            if bad.size == 0:
                continue
            j = int(bad[0])
            s_lo, s_hi = ref * np.sqrt(k / hi), ref * np.sqrt(k / lo)
            raise InputError(
                f"{term.label}: sigma = {sig[j]:g} {term.units} (row {j}) with lam={k:g} gives a "
                f"squared weight {w2[j]:.3g} relative to the data term, outside {lo:g}..{hi:g}, "
                "which double precision cannot resolve against it. Give sigma between "
                f"{s_lo:.3g} and {s_hi:.3g} {term.units} at this lam, or make the item hard "
                "(sigma=None) if it must hold exactly")

    def __getstate__(self) -> dict:
        """The definition without what is derived from it (rebuilt on first use)."""
        state = dict(self.__dict__)
        state.update(_model=None, _terms=None, _observable=False, _data_rows=None)
        return state
