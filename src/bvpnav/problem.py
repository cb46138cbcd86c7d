"""NavigationProblem: data + items + objective -> a verified trajectory.

The FEM equations are hard constraints of a cvxpy problem; the measurement error is
the explicit acceleration residual ``w`` (m/s^2); error-model parameters ``l`` are
unknowns too; every item compiles to an affine residual that the problem turns into a
hard, soft, robust or band term. The regularization weight ``lam`` is one cvxpy
Parameter, so the problem is DPP and a new ``lam`` re-uses the compiled problem.
"""

from __future__ import annotations

import numbers
import time
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import cvxpy as cp
import numpy as np
import pandas as pd

from .errors import (
    BvpnavError,
    ConvexityError,
    Inaccurate,
    Infeasible,
    InputError,
    SolveError,
    Unbounded,
)
from .imu import ImuData
from .items import Item
from .model import Affine, NavModel
from .result import Solution
from .solvers import VERIFY_RTOL, check_memory, memory_shortfall, resolve_solver, solver_options

#: Lambda values other than 0 that double precision can weigh against the data term: a
#: weight beyond 1e12 (or below 1e-12) leaves one side of the objective below rounding of
#: the other (the answer is that of hard items, or of no soft items).
LAM_RANGE = (1e-12, 1e12)

#: Bounds of the squared weight of a term relative to the data term (dimensionless, see
#: :meth:`NavigationProblem.check_scales`): 30 orders of magnitude either way, far from
#: the overflow of a square (1e308) and wider than any physical choice of sigma.
WEIGHT_RANGE = (1e-30, 1e30)

#: Accelerometer noise standard deviations (m/s^2) double precision handles in the
#: acceleration form's weights 1/sigma_a^2.
SIGMA_A_RANGE = (1e-12, 1e12)

#: Largest acceleration magnitude (m/s^2) accepted: 1e9 m/s^2 is 1e8 g, beyond any
#: accelerometer; larger values are a unit mistake and overflow the squared residuals.
ACC_MAX = 1e9


def check_lam(lam):
    """``lam`` as a float (or a rule name), or :class:`InputError` naming the value and
    the valid ones."""
    from .regularization import RULES

    if isinstance(lam, str):
        if lam not in RULES:
            raise InputError(f"lam={lam!r} is not a known rule; choose one of {list(RULES)} or a "
                             f"number >= 0")
        return lam
    if isinstance(lam, bool | np.bool_) or not isinstance(lam, numbers.Real):
        raise InputError(f"lam={lam!r} ({type(lam).__name__}): give a finite number >= 0 (e.g. "
                         f"lam=1.0) or a rule name from {list(RULES)}")
    lam = float(lam)
    if not np.isfinite(lam) or lam < 0:
        raise InputError(f"lam={lam!r}: must be a finite number >= 0")
    if lam != 0 and not LAM_RANGE[0] <= lam <= LAM_RANGE[1]:
        raise InputError(
            f"lam={lam:g} is outside {LAM_RANGE[0]:g}..{LAM_RANGE[1]:g} (or 0), the range in which "
            "double precision still weighs the soft items against the data term. For items that "
            "must hold exactly make them hard (sigma=None); to ignore them use lam=0; otherwise "
            "choose a lam in that range (or a rule, e.g. lam='lcurve')")
    return lam

__all__ = ["NavigationProblem", "Term", "RESIDUAL_FORMS", "DEFAULT_FALLBACK", "LAM_RANGE", "check_lam"]

RESIDUAL_FORMS = ("acceleration", "load")

#: The automatic fallback chain (``fallback="auto"``) after a primary Clarabel attempt:
#: Clarabel again with static regularization, the direct sparse back end (equality-
#: constrained least squares only; skipped with a recorded reason otherwise), then SCS.
#: After another primary solver the first entry is plain Clarabel.
DEFAULT_FALLBACK: tuple = (("clarabel", {"static_regularization_enable": True}), "direct", "scs")


@dataclass(eq=False)
class Term:
    """One compiled piece of information.

    Attributes
    ----------
    label : str
    item : Item or None
        ``None`` for terms the problem itself adds (error-model priors).
    residual : Affine
        ``D x - e`` in the item's units (for inequalities: ``g`` with ``g <= 0``).
    mode : str
        ``hard``, ``soft``, ``robust`` or ``band``.
    kind : str
        ``equality``, ``inequality`` (``g <= 0``) or ``cone`` (``residual`` is a
        :class:`~bvpnav.model.Cone`: per group ``||u_k|| <= s_k``).
    sigma, tol : ndarray or None
        Per-row standard deviation and band half-width, item units.
    huber : float or None
        Huber threshold in item units (robust mode); ``None`` means L1.
    scaled_by_lam : bool
        Whether the term is multiplied by ``lam`` (items: yes; priors: no).
    """

    label: str
    item: Item | None
    residual: Affine
    mode: str
    kind: str = "equality"
    sigma: np.ndarray | None = None
    tol: np.ndarray | None = None
    huber: float | None = None
    scaled_by_lam: bool = True
    units: str = ""


class NavigationProblem:
    """Accelerations plus additional information, posed as one convex problem.

    Parameters
    ----------
    data : ImuData
        Sample times and accelerations.
    residual : {"acceleration", "load"}
        Objective form. ``"acceleration"`` (default) penalises the acceleration
        residual, :math:`\\sum_i \\|w_i\\|^2 / \\sigma_a^2` (the MAP estimate for white
        accelerometer noise of standard deviation ``sigma_a``); ``"load"`` penalises the
        FEM load residual :math:`\\|K r - f(\\hat a) - F l\\|^2`, the 2011 paper's
        Tikhonov form.
    sigma_a : float or array_like, optional
        Accelerometer noise standard deviation in m/s^2 (scalar or one per axis), for
        the acceleration form. Default 1 m/s^2 (then ``lam`` absorbs the scale).
    error_model : ErrorModel, optional
        Sensor error model contributing unknown parameters (see
        :mod:`bvpnav.error_models`).
    items : iterable of Item, optional
        Initial items; more can be added with :meth:`add`.

    Notes
    -----
    The problem solved is

    .. math::

        \\min_{r, w, v_0, v_1, l}\\; J_0(w) + \\lambda \\sum_{k \\in soft} \\|(D_k x - e_k)/\\sigma_k\\|^2
        \\quad\\text{s.t.}\\quad K r + B v + M(\\hat a + G l + w) = 0,\\; D_h x = e_h,

    with :math:`J_0 = \\|w / \\sigma_a\\|^2` or :math:`\\|M w\\|^2` (= :math:`\\|K r + Bv - f\\|^2`).
    Robust items use the Huber function or L1 in place of the square; band items add
    :math:`|D x - e| \\le tol`; inequality items add :math:`g(x) \\le 0`.
    """

    def __init__(
        self,
        data: ImuData,
        residual: str = "acceleration",
        sigma_a=None,
        error_model=None,
        items: Iterable[Item] = (),
    ):
        if not isinstance(data, ImuData):
            raise InputError(f"data must be a bvpnav.ImuData, got {type(data).__name__}")
        if residual not in RESIDUAL_FORMS:
            raise InputError(f"residual={residual!r}; choose one of {list(RESIDUAL_FORMS)}")
        if sigma_a is not None and residual == "load":
            raise InputError("sigma_a goes with residual='acceleration'; the load form has no sigma_a")
        self.data = data
        self.residual = residual
        if sigma_a is None:
            sa = np.ones(data.ndim)
        else:
            from .items import positive_array

            sa = positive_array(sigma_a, "sigma_a (m/s^2)", False).ravel()
            if sa.size not in (1, data.ndim):
                raise InputError(f"sigma_a: {sa.size} value(s) for the axes {list(data.axes)}; give one "
                                 "value in m/s^2 or one per axis")
            sa = np.broadcast_to(sa, (data.ndim,))
        self.sigma_a = np.array(sa, dtype=float)
        for k in np.flatnonzero((self.sigma_a < SIGMA_A_RANGE[0]) | (self.sigma_a > SIGMA_A_RANGE[1])):
            raise InputError(
                f"sigma_a = {self.sigma_a[k]:g} m/s^2 (axis {data.axes[k]}) is outside "
                f"{SIGMA_A_RANGE[0]:g}..{SIGMA_A_RANGE[1]:g} m/s^2, where the weights 1/sigma_a^2 "
                "stay resolvable in double precision; give the accelerometer noise in m/s^2 "
                "(typically 1e-4 to 1)")
        with np.errstate(invalid="ignore"):
            big = np.abs(np.asarray(data.acc, dtype=float)) > ACC_MAX
        if np.any(big):
            i, a = np.unravel_index(int(np.argmax(big)), big.shape) if big.ndim > 1 else (
                int(np.argmax(big)), 0)
            val = np.asarray(data.acc, dtype=float).reshape(data.n, -1)[i, a]
            raise InputError(
                f"acceleration at sample {i} (t={data.t[i]:g} s), axis {data.axes[a]}, is {val:g} "
                f"m/s^2: beyond {ACC_MAX:g} m/s^2 (1e8 g), which no accelerometer measures and whose "
                f"squares overflow; {int(np.count_nonzero(big))} sample(s) exceed it. Check the "
                "unit of the acceleration column (m/s^2 expected) or remove the corrupt samples")
        self._sigma_a_given = sigma_a is not None
        self.error_model = error_model
        self._items: list[Item] = []
        self._model: NavModel | None = None
        self._terms: list[Term] | None = None
        self._cvx: dict[str, Any] | None = None
        for it in items:
            self.add(it)

    # ------------------------------------------------------------ pickling
    #: Caches rebuilt lazily after unpickling (cvxpy's compiled problem holds solver
    #: objects that cannot be pickled; the rest is cheap to rebuild and may be large).
    _CACHES = ("_model", "_terms", "_cvx", "_observable_terms")

    def __getstate__(self) -> dict:
        """The problem's definition without its caches (see :attr:`_CACHES`)."""
        state = dict(self.__dict__)
        for k in self._CACHES:
            state.pop(k, None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._model, self._terms, self._cvx = None, None, None

    # ----------------------------------------------------------- building
    def add(self, *items: Item) -> NavigationProblem:
        """Add one or more items; returns the problem for chaining."""
        for it in items:
            if not isinstance(it, Item):
                raise InputError(
                    f"add(): {it!r} is not a bvpnav item; build one from bvpnav.constraints "
                    "(e.g. Position(t=0.0, value=0.0))"
                )
            label = it.label
            taken = {x.label for x in self._items}
            if it.name is None and label in taken:
                k = 2
                while f"{label}#{k}" in taken:
                    k += 1
                label = f"{label}#{k}"
                self._items.append(_Renamed.wrap(it, label))
            elif it.name is not None and label in taken:
                raise InputError(f"add(): an item named {label!r} is already in the problem; item names "
                                 "identify items (priority, demote_sigma, messages): rename one of them "
                                 "(name=...)")
            else:
                self._items.append(it)
        self._terms = None
        self._cvx = None
        return self

    def with_items(self, items: Iterable[Item], error_model: bool = True) -> NavigationProblem:
        """The same data, objective form and sigma_a with other items (their labels kept).

        With ``error_model=True`` the copy also keeps the error model and shares this
        problem's :class:`NavModel` (the same unknowns and FEM matrices); without it the
        copy has no error-model parameters.
        """
        new = NavigationProblem(self.data, residual=self.residual,
                                sigma_a=self.sigma_a if self._sigma_a_given else None,
                                error_model=self.error_model if error_model else None, items=items)
        if error_model:
            new._model = self._model
        return new

    @property
    def items(self) -> list[Item]:
        """The items in the order they were added."""
        return [_Renamed.unwrap(i) for i in self._items]

    @property
    def item_labels(self) -> list[str]:
        """Unique labels of the items (``Class`` or ``Class#k``)."""
        return [i.label for i in self._items]

    @property
    def model(self) -> NavModel:
        """The :class:`NavModel` (unknowns and their maps), built on first use."""
        if self._model is None:
            self._model = NavModel(self.data, self.error_model)
        return self._model

    def terms(self) -> list[Term]:
        """Compile every item (once) into :class:`Term` objects."""
        if self._terms is not None:
            return self._terms
        model = self.model
        terms = []
        for it in self._items:
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
            terms.append(
                Term(label=label, item=_Renamed.unwrap(it), residual=res, mode=it.mode,
                     kind=getattr(it, "kind", "equality"), sigma=it.weight_rows(res.m),
                     tol=it.tol_rows(res.m), huber=it.huber, units=getattr(it, "units", ""))
            )
        if self.error_model is not None and hasattr(self.error_model, "terms"):
            terms.extend(self.error_model.terms(model))
        self._terms = terms
        return terms

    def data_rows(self) -> Affine:
        """Rows whose sum of squares is the data term ``J_0`` (see class Notes)."""
        m = self.model
        if self.residual == "acceleration":
            return m.residual_rows() / np.repeat(self.sigma_a, m.N)
        return m.load_residual_rows()

    def build(self) -> dict[str, Any]:
        """Build (once) and return the cvxpy problem with its parts.

        Returns
        -------
        dict
            ``problem`` (cp.Problem), ``lam`` (cp.Parameter), ``x`` (cp.Variable),
            ``fem`` (the FEM constraint) and ``cons`` (label -> list of constraints).
        """
        if self._cvx is not None:
            return self._cvx
        model = self.model
        x = model.x
        lam = cp.Parameter(nonneg=True, value=1.0, name="lam")
        fem_rows = model.fem_rows()
        fem_con = fem_rows.expr(x) == 0
        objective = cp.sum_squares(self.data_rows().expr(x))
        cons: dict[str, list] = {}
        penalties = []
        for term in self.terms():
            r = term.residual.expr(x)
            mode = term.mode
            con_list = []
            if term.kind == "equality":
                if mode == "hard":
                    con_list.append(r == 0)
                elif mode == "band":
                    con_list += [r <= term.tol, -r <= term.tol]
                elif mode == "soft":
                    penalties.append((term, cp.sum_squares(cp.multiply(1.0 / term.sigma, r))))
                elif mode == "robust":
                    w2 = 1.0 / term.sigma**2
                    if term.huber is None:
                        penalties.append((term, cp.norm1(cp.multiply(1.0 / term.sigma, r))))
                    else:
                        penalties.append((term, cp.sum(cp.multiply(w2, cp.huber(r, term.huber)))))
            elif term.kind == "cone":  # groups (s_k, u_k) with ||u_k|| <= s_k
                con_list, pen = _cone_parts(term, r)
                if pen is not None:
                    penalties.append((term, pen))
            else:  # inequality g <= 0
                if mode == "hard":
                    con_list.append(r <= 0)
                elif mode == "band":
                    con_list.append(r <= term.tol)
                elif mode == "soft":
                    penalties.append((term, cp.sum_squares(cp.multiply(1.0 / term.sigma, cp.pos(r)))))
                else:
                    penalties.append((term, cp.sum(cp.multiply(1.0 / term.sigma, cp.pos(r)))))
            cons[term.label] = con_list
        for term, pen in penalties:
            if not pen.is_convex():  # pragma: no cover - built from convex atoms
                raise ConvexityError(f"{term.label}: its penalty is not convex")
            objective = objective + (lam * pen if term.scaled_by_lam else pen)
        all_cons = [fem_con] + [c for lst in cons.values() for c in lst]
        prob = cp.Problem(cp.Minimize(objective), all_cons)
        if not prob.is_dcp():
            bad = [t.label for t, p in penalties if not p.is_dcp()]
            raise ConvexityError(f"the problem is not DCP; culprit item(s): {bad or 'unknown'}")
        if not prob.is_dpp():
            bad = [t.label for t, p in penalties if not (lam * p).is_dpp()]
            raise ConvexityError(f"the problem is not DPP in lam; culprit item(s): {bad or 'unknown'}")
        self._cvx = {"problem": prob, "lam": lam, "x": x, "fem": fem_con, "fem_rows": fem_rows,
                     "cons": cons, "penalties": penalties}
        return self._cvx

    @property
    def has_soft_terms(self) -> bool:
        """True when ``lam`` multiplies at least one term."""
        return any(t.mode in ("soft", "robust") and t.scaled_by_lam for t in self.terms())

    # ------------------------------------------------------ teaching
    def describe(self, format: str = "text", lam: float | None = None, conditioning: bool = True) -> str:
        """The assembled problem in readable mathematics (see :func:`bvpnav.describe.describe`).

        Parameters
        ----------
        format : {"text", "latex"}
            Plain text, or LaTeX lines that render with matplotlib's mathtext.
        lam : float, optional
            The lambda to print (default: the problem's current value).
        conditioning : bool
            Include a condition estimate of the KKT matrix (one sparse LU).

        Returns
        -------
        str
            Variables with sizes and units, the FEM hard constraints, the error-model
            columns, each item's equation with its mode and weight, the objective with
            lambda, the size (rows, columns, non-zeros) and the conditioning estimate.
        """
        from .describe import describe

        return describe(self, format=format, lam=lam, conditioning=conditioning)

    def matrices(self):
        """The assembled matrices (K, M, f, F, A_eq, b_eq, J, D, e, sigma, legend, layout)
        for a solve by hand; see :class:`bvpnav.describe.Matrices`.

        Returns
        -------
        bvpnav.describe.Matrices

        Notes
        -----
        The problem is :math:`\\min_x \\|J x\\|^2 + \\lambda \\|(D x - e)/\\sigma\\|^2`
        subject to :math:`A_{eq} x = b_{eq}`, whose first rows are the FEM equations
        :math:`K r + B v - f - F l + M w = 0`.
        """
        from .describe import matrices

        return matrices(self)

    def to_spec(self, solve: dict | None = None, input: dict | None = None) -> str:
        """The problem's information as spec-file TOML (see :mod:`bvpnav.spec`).

        Parameters
        ----------
        solve : dict, optional
            The ``[solve]`` table (solver, accuracy, lam).
        input : dict, optional
            The ``[input]`` table (time column and unit, axis columns, acceleration unit).

        Returns
        -------
        str
            TOML listing every item and error-model component with its parameters, the
            residual form and sigma_a; ``bvpnav.spec.parse_spec(text).build(data)`` gives
            the same problem back.
        """
        from .spec import dumps_spec, problem_to_spec

        return dumps_spec(problem_to_spec(self, solve=solve, input=input))

    # ------------------------------------------------------ observability
    def null_directions(self) -> tuple[np.ndarray, list[str]]:
        """Directions of ``x`` the FEM equations leave free when ``w = 0``.

        Returns
        -------
        Z : ndarray, shape (n_unknowns, 2 d + q)
            Per axis a position offset and a velocity offset, then one direction per
            error-model parameter (the trajectory change it causes, starting at rest).
        names : list of str
        """
        m = self.model
        t = m.grid.t
        cols, names = [], []
        for a, ax in enumerate(m.axes):
            z = np.zeros(m.size)
            z[m.r_index(a)] = 1.0
            cols.append(z)
            names.append(f"axis {ax}: position offset")
            z = np.zeros(m.size)
            z[m.r_index(a)] = t - t[0]
            z[list(m.v_end_index(a))] = 1.0
            cols.append(z)
            names.append(f"axis {ax}: velocity offset")
        h = m.grid.h
        for k, pname in enumerate(m.param_names):
            z = np.zeros(m.size)
            z[m.l_index[k]] = 1.0
            for a in range(m.d):
                mg = m.M @ m.G[:, a, k]
                s = np.cumsum(mg)[:-1]  # element slopes with v0 = 0
                r = np.concatenate([[0.0], np.cumsum(s * h)])
                z[m.r_index(a)] = r
                i0, i1 = m.v_end_index(a)
                z[i0] = 0.0
                z[i1] = s[-1] + mg[-1]
            cols.append(z)
            names.append(f"parameter {pname}")
        return np.column_stack(cols), names

    def unobservable(self) -> list[str]:
        """Names of unknown directions that no item pins down (empty when all are)."""
        terms = [t for t in self.terms() if t.kind == "equality"]
        Z, names = self.null_directions()
        if not terms:
            return names
        D = Affine.vstack([t.residual for t in terms]).A
        DZ = D @ Z
        norms = np.linalg.norm(DZ, axis=0)
        scale = norms.max() if norms.size and norms.max() > 0 else 1.0
        out = [names[k] for k in np.flatnonzero(norms <= 1e-12 * scale)]
        ok = np.flatnonzero(norms > 1e-12 * scale)
        if ok.size:
            Dn = DZ[:, ok] / norms[ok]
            # with fewer information rows than directions the null space has more vectors
            # than there are singular values: pad with zero rows (never a full U: M x M)
            if Dn.shape[0] < Dn.shape[1]:
                Dn = np.vstack([Dn, np.zeros((Dn.shape[1] - Dn.shape[0], Dn.shape[1]))])
            _, s, vt = np.linalg.svd(Dn, full_matrices=False)
            rank = int(np.sum(s > 1e-9 * s[0])) if s.size else 0
            null = vt[rank:]
            if null.shape[0]:
                involved = sorted({int(j) for comb in null
                                   for j in np.flatnonzero(np.abs(comb) > 0.1 * np.abs(comb).max())})
                what = ", ".join(names[ok[j]] for j in involved)
                out.append(f"{null.shape[0]} combination(s) of: {what}")
        return out

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
            if term.mode not in ("soft", "robust") or term.sigma is None:
                continue
            k = lam if term.scaled_by_lam else 1.0
            if k == 0:
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

    def check_observability(self) -> None:
        """Raise :class:`InputError` naming what the information leaves undetermined."""
        terms = self.terms()
        if getattr(self, "_observable_terms", None) is terms:  # checked for these items already
            return
        missing = self.unobservable()
        if missing:
            raise InputError(
                "not enough information: nothing determines " + "; ".join(missing)
                + ". Add items (e.g. Position at an end for an offset, a second Position or a "
                "Velocity for a velocity offset, more velocities for error-model parameters) "
                "or remove error-model parameters."
            )
        self._observable_terms = terms

    # ------------------------------------------------------------ solving
    def solve(
        self,
        solver: str = "clarabel",
        lam: float | str = 1.0,
        accuracy: str = "default",
        verify: bool = True,
        options: dict | None = None,
        verbose: bool = False,
        fallback="auto",
        on_conflict: str = "raise",
        priority: Mapping[str, float] | None = None,
        demote_sigma: float | Mapping[str, float] | None = None,
    ) -> Solution:
        """Solve and verify, falling back to other back ends when an answer fails.

        Parameters
        ----------
        solver : str
            Case-insensitive solver name (``bvpnav.available_solvers()``).
        lam : float or str
            Regularization weight (dimensionless ratio of the item terms to the data
            term): 0 or within :data:`LAM_RANGE` (1e-12 to 1e12), or the name of a rule
            that chooses it (``"lcurve"``, ``"gcv"``, ``"discrepancy"``, ``"quasi"``).
        accuracy : {"low", "default", "high"}
            Preset mapped to the solver's options and to the verification tolerance.
        verify : bool
            Recompute residuals and refuse answers that fail (default True; switch off
            only to inspect a failure: the result then says ``verified=False``).
        options : dict, optional
            Extra solver options, on top of the preset. Names are checked before solving
            for Clarabel (its settings and cvxpy's own keywords) and the direct back ends
            (names and values); other solvers judge their options themselves (a refusal
            is a failed attempt).
        fallback : "auto", sequence or None
            What to try when the answer fails verification or the solver errs: a
            sequence of solver names or ``(name, options)`` pairs (the primary's
            ``options`` are not passed on). ``"auto"`` is :data:`DEFAULT_FALLBACK`:
            Clarabel with static regularization switched on (it helps small problems
            with many hard rows, hurts large ones; plain Clarabel after another primary
            solver), the direct back end (skipped, with the reason recorded, when the
            problem is not equality-constrained least squares), then SCS. ``None`` or
            ``()`` disables it. Every attempt is recorded in
            ``solution.stats["attempts"]`` with its status and reason.
        on_conflict : {"raise", "demote"}
            What to do when the hard information cannot hold together. ``"raise"``
            (default) raises :class:`~bvpnav.errors.Infeasible` naming the conflicting
            items. ``"demote"`` turns the lowest-priority item of each conflicting set
            into a soft item and solves again, until the rest is consistent; the
            result's ``stats["demoted"]`` and ``warnings`` say which items were
            demoted, with what sigma and which conflict they belonged to.
        priority : mapping of str to float, optional
            Item label -> priority for ``on_conflict="demote"``: higher means more
            trusted, kept hard longer. Unlisted items have priority 0; among equal
            priorities the item added last is demoted first.
        demote_sigma : float or mapping of str to float, optional
            Standard deviation (item units) given to a demoted item, one number for all
            or per label; default 1.0 (e.g. 1 m for a position, 1 m/s for a velocity).

        Returns
        -------
        Solution

        Raises
        ------
        InputError
            Before solving, for bad input or information that leaves unknowns free: an
            option of the wrong type or value (named, with the valid ones), a weight that
            double precision cannot resolve (:meth:`check_scales`), or a problem whose
            memory estimate exceeds the available memory
            (:func:`bvpnav.solvers.check_memory`, naming what would fit).
        SolveError
            (``Infeasible``, ``Unbounded``, ``Inaccurate``) when every attempt failed;
            ``error.attempts`` lists each attempt's status and reason. Any exception a
            back end raises (e.g. ``LinAlgError``, SCS's ``ValueError``, ``MemoryError``)
            is such a failed attempt (status ``"error"``), then the next back end runs;
            a fallback whose memory estimate does not fit is skipped with its reason.
        """
        if on_conflict not in ("raise", "demote"):
            raise InputError(f"on_conflict={on_conflict!r}; choose 'raise' or 'demote'")
        # every option is checked before any work (also on the rule, sequential and
        # demotion paths, which call solve() again with the same options)
        lam = check_lam(lam)
        for name, flag in (("verify", verify), ("verbose", verbose)):
            if not isinstance(flag, bool | np.bool_):
                raise InputError(f"{name}={flag!r}: must be True or False")
        backend = resolve_solver(solver)
        solver_options(backend, accuracy, options)
        self._fallback_chain(backend, accuracy, options, fallback)
        check_memory(self, backend)  # the primary; a fallback that does not fit is skipped
        if on_conflict == "demote":  # before the loop: each round calls solve() (and the loop) again
            from .conflicts import solve_demoting

            return solve_demoting(self, dict(solver=solver, lam=lam, accuracy=accuracy, verify=verify,
                                             options=options, verbose=verbose, fallback=fallback),
                                  priority=priority, demote_sigma=demote_sigma)
        if any(getattr(it, "needs_linearization", False) for it in self._items):
            from .sequential import solve_sequential  # nonlinear items: sequential convex loop

            return solve_sequential(self, solver=solver, lam=lam, accuracy=accuracy, verify=verify,
                                    options=options, verbose=verbose, fallback=fallback)
        if isinstance(lam, str):
            from . import regularization

            return regularization.solve_with_rule(self, lam, solver=solver, accuracy=accuracy,
                                                  options=options, verify=verify, verbose=verbose,
                                                  fallback=fallback)
        opts = solver_options(backend, accuracy, options)
        chain = [(backend, opts)] + self._fallback_chain(backend, accuracy, options, fallback)
        self.check_scales(lam)
        self.check_observability()
        attempts: list[dict] = []
        last_exc: SolveError | None = None
        for k, (be, op) in enumerate(chain):
            short = memory_shortfall(be, self) if k else None
            if short is not None:
                attempts.append({"solver": be.name, "status": "not applicable", "reason": short})
                continue
            try:
                sol = self._attempt(be, op, lam, accuracy, verify, verbose)
            except Infeasible as exc:  # infeasibility is a property of the information
                exc.attempts = attempts + exc.attempts
                raise
            except InputError as exc:
                if k == 0:
                    raise
                # a fallback that cannot take this problem (e.g. direct with inequalities)
                attempts.append({"solver": be.name, "status": "not applicable", "reason": str(exc)})
                continue
            except SolveError as exc:
                attempts.extend(exc.attempts or [{"solver": be.name, "status": "error",
                                                  "reason": str(exc)}])
                last_exc = exc
                if not verify and k == 0:
                    raise
                continue
            except (BvpnavError, KeyboardInterrupt, SystemExit):
                raise
            except Exception as exc:  # a back end's own failure (LinAlgError, SCS's ValueError,
                # MemoryError, ...): a recorded failed attempt, then the next back end
                reason = f"{type(exc).__name__}: {exc}"
                rec = {"solver": be.name, "status": "error", "reason": reason}
                attempts.append(rec)
                err = SolveError(f"{be.name} failed: {reason}", attempts=[rec])
                err.__cause__ = exc
                last_exc = err
                if not verify and k == 0:
                    raise err from exc
                continue
            sol.stats["attempts"] = attempts + sol.stats["attempts"]
            if attempts:
                sol.warnings.append(
                    f"{backend.name} failed ({attempts[0]['reason']}); the answer comes from "
                    f"{be.name} with options {op}"
                )
            return sol
        assert last_exc is not None
        summary = "; ".join(f"{a['solver']}: {a['status']} ({a['reason']})" for a in attempts)
        raise type(last_exc)(f"every attempt failed: {summary}. Last error: {last_exc}",
                             attempts=attempts) from last_exc.__cause__

    def _fallback_chain(self, backend, accuracy, options, fallback) -> list:
        from .solvers import Backend

        how = ("use 'auto', None, or a list of solver names or (name, options) pairs, e.g. "
               "fallback=['direct', ('scs', {'max_iters': 20000})]")
        if fallback is None:
            return []
        entries: list = []
        if isinstance(fallback, str):
            if fallback != "auto":
                raise InputError(f"fallback={fallback!r}; {how}")
            entries = list(DEFAULT_FALLBACK)
            if backend.name != "clarabel":
                entries[0] = "clarabel"
        elif isinstance(fallback, list | tuple):
            entries = list(fallback)
        else:
            raise InputError(f"fallback={fallback!r} ({type(fallback).__name__}); {how}")
        chain = []
        for k, e in enumerate(entries):
            if isinstance(e, str):
                name, extra = e, {}
            elif (isinstance(e, list | tuple) and len(e) == 2 and isinstance(e[0], str)
                  and isinstance(e[1], Mapping)):
                name, extra = e[0], dict(e[1])
            else:
                raise InputError(f"fallback entry {k} = {e!r}: {how}")
            try:
                be = resolve_solver(name)
            except BvpnavError:
                if fallback == "auto":
                    continue  # an optional back end that is not installed
                raise
            if isinstance(be, Backend) and be.name == backend.name and not extra:
                continue
            chain.append((be, solver_options(be, accuracy, {**(options or {}), **extra}
                                             if be.name == backend.name else extra)))
        return chain

    def _attempt(self, backend, opts, lam, accuracy, verify, verbose) -> Solution:
        from .solvers import check_support

        check_support(backend, self)  # before solving: e.g. a cone item given to a QP solver
        t_start = time.perf_counter()
        factored = None
        if backend.kind == "direct":
            xval, info = backend.run(self, lam, accuracy, opts)
            duals = info.pop("duals", None)
            factored = info.pop("factored", None)
        else:
            xval, info, duals = self._solve_cvxpy(backend, lam, opts, verbose)
        info["wall_time"] = time.perf_counter() - t_start
        info.update(solver=backend.name, accuracy=accuracy, options=opts)
        return self._finish(xval, lam, "fixed", info, duals, accuracy, verify, factored)

    def _solve_cvxpy(self, backend, lam: float, opts: dict, verbose: bool):
        cvx = self.build()
        prob: cp.Problem = cvx["problem"]
        cvx["lam"].value = lam
        t0 = time.perf_counter()
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                prob.solve(solver=backend.cvxpy_name, verbose=verbose, **opts)
        except cp.error.SolverError as exc:
            raise SolveError(
                f"{backend.name} failed: {exc}",
                attempts=[{"solver": backend.name, "status": "solver_error", "reason": str(exc)}],
            ) from exc
        wall = time.perf_counter() - t0
        status = prob.status
        st = prob.solver_stats
        info = {
            "status": status,
            "iterations": getattr(st, "num_iters", None),
            "solve_time": getattr(st, "solve_time", None),
            "setup_time": getattr(st, "setup_time", None),
            "compile_time": getattr(prob, "compilation_time", None),
            "cvxpy_time": wall,
            "objective": prob.value,
            "solver_warnings": [str(w.message) for w in caught],
        }
        if status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
            from .conflicts import conflicting_items

            try:
                culprits = conflicting_items(self)
            except Exception:  # the finder must never hide the solver's verdict
                culprits = []
            ident = {it.label: it.identify() for it in self._items}  # unnamed items: what they hold
            if culprits:
                which = (f"These hard items conflict: {[ident.get(c, c) for c in culprits]}. Soften one of "
                         "them (give sigma=...).")
            else:
                hard = [ident.get(t.label, t.label) for t in self.terms() if t.mode in ("hard", "band")]
                which = (f"No conflicting subset was confirmed (a numerical verdict?). Hard/band "
                         f"items: {hard}. Soften some of them (give sigma=...) or try another solver.")
            raise Infeasible(
                f"{backend.name}: the hard information cannot hold together (status {status}). {which}",
                attempts=[{"solver": backend.name, "status": status, "reason": "infeasible",
                           "conflicts": culprits}],
            )
        if status in (cp.UNBOUNDED, cp.UNBOUNDED_INACCURATE):
            raise Unbounded(
                f"{backend.name}: the problem is unbounded (status {status}); some unknown is not "
                "determined by any information",
                attempts=[{"solver": backend.name, "status": status, "reason": "unbounded"}],
            )
        if cvx["x"].value is None:
            raise SolveError(
                f"{backend.name} returned no solution (status {status})",
                attempts=[{"solver": backend.name, "status": status, "reason": "no solution"}],
            )
        duals = {"fem": cvx["fem"].dual_value}
        for label, lst in cvx["cons"].items():
            duals[label] = [c.dual_value for c in lst]
        return np.array(cvx["x"].value, dtype=float), info, duals

    # ------------------------------------------------------- verification
    def verify(self, xval: np.ndarray, lam: float, accuracy: str = "default",
               duals: dict | None = None, factored: tuple | None = None) -> dict[str, Any]:
        """Recompute the FEM residual, hard-item violations and (when duals are given
        and the objective is smooth) the stationarity residual.

        ``factored`` is an optional ``(LeastSquaresForm, BorderedLU)`` of this problem at
        this ``lam`` (the direct back end's own) reused by the forward-error estimate.

        Returns
        -------
        dict
            ``fem_residual`` (relative), ``max_violation`` (relative, over hard, band and
            inequality items), ``worst_item``, ``stationarity`` (relative or None),
            ``rtol``, ``nonfinite`` (what is NaN or infinite in the solution vector or in
            the reported error-model parameters: any makes the answer fail),
            ``conditioning`` (see :func:`bvpnav.conditioning.assess_conditioning`; None
            without error-model parameters) and ``verified`` (bool).
        """
        rtol = VERIFY_RTOL[accuracy]
        model = self.model
        fem = model.fem_rows()
        res = fem.value(xval)
        scale = fem.row_scale(xval)
        fem_rel = float(np.max(np.abs(res)) / max(np.max(scale), 1e-300))
        worst, worst_item = 0.0, None
        for term in self.terms():
            if term.mode not in ("hard", "band") and not (term.kind == "inequality"
                                                          and term.mode == "hard"):
                continue
            r = term.residual.value(xval)
            if term.kind == "equality":
                v = np.abs(r) if term.mode == "hard" else np.maximum(np.abs(r) - term.tol, 0)
            elif term.kind == "cone":
                k = term.residual.size
                v = np.maximum(term.residual.excess(xval)
                               - (term.tol[::k] if term.mode == "band" else 0.0), 0)
            else:
                v = np.maximum(r - (term.tol if term.mode == "band" else 0.0), 0)
            sc = max(float(np.max(term.residual.row_scale(xval))), 1.0)
            rel = float(np.max(v) / sc)
            if rel > worst:
                worst, worst_item = rel, term.label
        stat = None
        if duals is not None:
            stat = self._stationarity(xval, lam, duals)
        from .kkt import FORWARD_RTOL, factor_form, forward_error, least_squares_form

        # NaN/inf never pass: not in x (comparisons with NaN are False, but say so), nor in
        # the reported error-model parameters (a singular physical reparametrisation)
        nonfinite = []
        if not np.all(np.isfinite(xval)):
            nonfinite.append(f"{int(np.count_nonzero(~np.isfinite(xval)))} entries of the solution vector")
        if self.error_model is not None and model.q:
            with np.errstate(all="ignore"):
                rep = self.error_model.report(model.split(xval)["l"], model)
            vals = np.asarray(rep, dtype=float)
            nonfinite += [f"error parameter {n} = {v}" for n, v in zip(rep.index, vals, strict=True)
                          if not np.isfinite(v)]
        fwd_failed = False
        if factored is None and model.q:
            # factor once here: the forward-error estimate and the conditioning share it
            form = least_squares_form(self, lam)
            if form is not None:
                try:
                    factored = (form, factor_form(form, self, "lu"))
                except (RuntimeError, np.linalg.LinAlgError):  # forward_error's verdict too
                    fwd_failed = True
        fwd = float("inf") if fwd_failed else forward_error(self, xval, lam, duals, factored)
        conditioning = None
        if model.q and not np.any(~np.isfinite(xval)):
            from .conditioning import assess_conditioning

            conditioning = assess_conditioning(self, xval, lam, factored)
            if nonfinite:
                nonfinite += [dg["message"] for dg in conditioning["degenerate_axes"]]
        # the parameters of a sensor axis whose kept fraction is zero are undetermined (inf,
        # NaN) by the information itself; named in warnings, they do not fail the answer.
        # Anything else not finite does, whatever rounding decided (issue 14).
        undetermined = sorted({n for dg in (conditioning or {}).get("degenerate_axes", [])
                               if dg.get("undetermined") for n in dg["parameters"]})
        unexplained = [s for s in nonfinite if not s.startswith("sensor axis ")
                       and not any(s.startswith(f"error parameter {n} = ") for n in undetermined)]
        ok = (fem_rel <= rtol and worst <= rtol * 10 and (stat is None or stat <= np.sqrt(rtol))
              and (fwd is None or fwd <= FORWARD_RTOL[accuracy]) and not unexplained)
        return {"fem_residual": fem_rel, "max_violation": worst, "worst_item": worst_item,
                "stationarity": stat, "forward_error": fwd, "rtol": rtol, "nonfinite": nonfinite,
                "undetermined": undetermined, "conditioning": conditioning, "verified": bool(ok)}

    def _stationarity(self, xval: np.ndarray, lam: float, duals: dict) -> float | None:
        """Relative norm of the Lagrangian gradient (None for non-smooth objectives)."""
        grads = []
        data = self.data_rows()
        grads.append(2.0 * (data.A.T @ data.value(xval)))
        model = self.model
        fem = model.fem_rows()
        y = duals.get("fem")
        if y is None:
            return None
        grads.append(fem.A.T @ np.asarray(y, dtype=float).ravel())
        for term in self.terms():
            r = term.residual.value(xval)
            A = term.residual.A
            k = lam if term.scaled_by_lam else 1.0
            if term.kind == "cone":
                g = _cone_gradient(term, xval, duals.get(term.label))
                if g is None:
                    return None
                grads.append(k * g if term.mode in ("soft", "robust") else g)
            elif term.mode == "soft" and term.kind == "equality":
                grads.append(k * 2.0 * (A.T @ (r / term.sigma**2)))
            elif term.mode == "soft":
                grads.append(k * 2.0 * (A.T @ (np.maximum(r, 0) / term.sigma**2)))
            elif term.mode == "robust":
                if term.huber is None or term.kind != "equality":
                    return None
                g = np.where(np.abs(r) <= term.huber, 2.0 * r, 2.0 * term.huber * np.sign(r))
                grads.append(k * (A.T @ (g / term.sigma**2)))
            else:
                dl = duals.get(term.label)
                if dl is None or any(d is None for d in dl):
                    return None
                if term.kind == "equality" and term.mode == "band":
                    z = np.asarray(dl[0]).ravel() - np.asarray(dl[1]).ravel()
                else:
                    z = np.asarray(dl[0]).ravel()
                grads.append(A.T @ z)
        total = np.sum(grads, axis=0)
        # floor: the data-term gradient if the residual were as large as the measurement
        # (at least the acceleration scale the trajectory itself sets, |r|/T^2 and |v|/T,
        # so that exactly consistent data, e.g. zero acceleration with hard positions on
        # a straight line, is not judged against round-off alone)
        probe = np.zeros(model.size)
        T = model.grid.duration
        for a in range(model.d):
            r_a = model.node_position(a).value(xval)
            v_a = model.node_velocity(a).value(xval)
            a_scale = max(float(np.max(np.abs(r_a))) / T**2, float(np.max(np.abs(v_a))) / T)
            probe[model.w_index(a)] = np.maximum(np.abs(model.data.acc[:, a]), a_scale)
        floor = float(np.max(np.abs(2.0 * (data.A.T @ data.value(probe)))))
        # and each weighted term's gradient if its residual were as large as the terms that
        # cancel in it (|A| |x| + |c|): a consistent problem (every residual zero, e.g.
        # zero acceleration fitted exactly) otherwise has only round-off to compare with
        for term in self.terms():
            if term.mode in ("soft", "robust") and term.sigma is not None:
                k = lam if term.scaled_by_lam else 1.0
                size = term.residual.row_scale(xval)
                if term.mode == "robust" and term.huber is not None:
                    size = np.minimum(size, term.huber)
                w = 2.0 * size / term.sigma**2
                floor = max(floor, float(np.max(k * (abs(term.residual.A).T @ w))))
        scale = max(max(float(np.max(np.abs(g))) for g in grads), floor, 1e-300)
        return float(np.max(np.abs(total)) / scale)

    # -------------------------------------------------------------- result
    def _finish(self, xval, lam, lam_rule, info, duals, accuracy, verify, factored=None) -> Solution:
        check = self.verify(xval, lam, accuracy, duals, factored)
        info["verification"] = check
        info["verified"] = check["verified"]
        info.setdefault("attempts", []).append(
            {"solver": info["solver"], "status": info.get("status"),
             "reason": "verified" if check["verified"] else "failed verification"}
        )
        cond = check.get("conditioning") or {}
        degenerate = [dg["message"] for dg in cond.get("degenerate_axes", [])]
        if degenerate and check.get("nonfinite") and not check["verified"]:
            # the information's fault: no fallback can help
            raise InputError(f"{info['solver']}: the error-model estimate is not finite because "
                             + "; ".join(degenerate))
        if verify and not check["verified"]:
            raise Inaccurate(
                f"{info['solver']} (status {info.get('status')}, accuracy={accuracy!r}) returned an "
                f"answer that fails verification: FEM residual {check['fem_residual']:.2e}, "
                f"worst hard-item violation {check['max_violation']:.2e} "
                f"({check['worst_item']}), stationarity {check['stationarity']}, "
                f"estimated forward error {check['forward_error']}, "
                + (f"not finite: {'; '.join(check['nonfinite'])}, " if check.get("nonfinite") else "")
                + f"tolerance {check['rtol']:.0e}. Try accuracy='high', another solver "
                "(e.g. solver='direct' for problems without inequalities), or residual="
                "'acceleration'.",
                attempts=info["attempts"],
            )
        return self._make_solution(xval, lam, lam_rule, info, duals)

    def _make_solution(self, xval, lam, lam_rule, info, duals) -> Solution:
        model = self.model
        t = model.grid.t
        idx = pd.Index(t, name="t")
        cols = {}
        for a, ax in enumerate(model.axes):
            cols[ax] = model.node_position(a).value(xval)
        for a, ax in enumerate(model.axes):
            cols["v" + ax] = model.node_velocity(a).value(xval)
        traj = pd.DataFrame(cols, index=idx)
        parts = model.split(xval)
        resid = pd.DataFrame({f"w_{ax}": parts["w"][:, a] for a, ax in enumerate(model.axes)},
                             index=idx)
        rows, item_res = [], {}
        for term in self.terms():
            r = term.residual.excess(xval) if term.kind == "cone" else term.residual.value(xval)
            item_res[term.label] = r
            shown = np.maximum(r, 0) if term.kind in ("inequality", "cone") else r
            dual_rms = None
            if duals is not None and duals.get(term.label):
                ds = [np.concatenate([np.asarray(p, dtype=float).ravel() for p in d])
                      if isinstance(d, list | tuple) else np.asarray(d, dtype=float).ravel()
                      for d in duals[term.label] if d is not None]
                if ds:
                    dual_rms = float(np.sqrt(np.mean(np.concatenate(ds) ** 2)))
            rows.append({
                "item": term.label,
                "class": type(term.item).__name__ if term.item is not None else "prior",
                "mode": term.mode, "kind": term.kind, "rows": term.residual.m,
                "units": term.units,
                "rms": float(np.sqrt(np.mean(shown**2))), "max_abs": float(np.max(np.abs(shown))),
                "dual_rms": dual_rms,
            })
        items_df = pd.DataFrame(rows, columns=["item", "class", "mode", "kind", "rows", "units",
                                               "rms", "max_abs", "dual_rms"])
        if self.error_model is not None and model.q:
            params = self.error_model.report(parts["l"], model)
        else:
            params = pd.Series(dtype=float, name="estimate")
        warn = [f"{info.get('solver')}: {w}" for w in info.get("solver_warnings", [])]
        cond = (info.get("verification") or {}).get("conditioning")
        if cond is not None:
            info["conditioning"] = cond
            warn += cond["warnings"]
        if str(info.get("status", "")).endswith("inaccurate"):
            warn.append(f"{info.get('solver')} reported status {info['status']!r}; the answer passed "
                        "bvpnav's verification (see stats['verification'])")
        gaps = model.grid.gaps()
        if gaps.size:
            h, med = model.grid.h, float(np.median(model.grid.h))
            warn.append(f"{gaps.size} gap(s) longer than 10x the median step {med:g} s: the first, from "
                        f"sample {gaps[0]} to {gaps[0] + 1} (t={t[gaps[0]]:g} s), is {h[gaps[0]]:g} s "
                        f"long; results across gaps rely on the "
                        "linear-acceleration assumption")
        return Solution(trajectory=traj, residuals=resid, items=items_df, item_residuals=item_res,
                        lam=float(lam), lam_rule=lam_rule, error_params=params, stats=info,
                        x=xval, warnings=warn)


def _cone_parts(term: Term, r: cp.Expression) -> tuple[list, cp.Expression | None]:
    """Constraints and penalty of a cone term (see :class:`bvpnav.model.Cone`).

    Notes
    -----
    With the excess :math:`e_k = \\|u_k\\|_2 - s_k`: hard :math:`e_k \\le 0`; band
    :math:`e_k \\le tol_k`; soft :math:`\\sum_k \\max(e_k, 0)^2/\\sigma_k^2`; robust
    :math:`\\sum_k \\max(e_k, 0)/\\sigma_k` (the last two times ``lam``).
    """
    k = term.residual.size
    R = cp.reshape(r, (k, term.residual.groups), order="F")
    s, U = R[0, :], R[1:, :]
    if term.mode == "hard":
        return [cp.SOC(s, U, axis=0)], None
    if term.mode == "band":
        return [cp.SOC(s + term.tol[::k], U, axis=0)], None
    excess = cp.pos(cp.norm(U, 2, axis=0) - s)
    w = 1.0 / term.sigma[::k]
    if term.mode == "soft":
        return [], cp.sum_squares(cp.multiply(w, excess))
    return [], cp.sum(cp.multiply(w, excess))


def _cone_gradient(term: Term, xval: np.ndarray, duals) -> np.ndarray | None:
    """Gradient of a cone term's part of the Lagrangian (None where it is not smooth or
    the duals are missing). cvxpy's SOC duals ``(mu, Y)`` enter as ``-(mu s + <Y, U>)``."""
    res = term.residual
    k = res.size
    A = res.A
    if term.mode in ("hard", "band"):
        if not duals or duals[0] is None:
            return None
        mu, Y = duals[0]
        z = np.column_stack([np.asarray(mu, dtype=float).ravel(),
                             np.asarray(Y, dtype=float).reshape(k - 1, -1).T]).ravel()
        return -(A.T @ z)
    if term.mode == "robust":
        return None
    v = res.value(xval).reshape(res.groups, k)
    nu = np.linalg.norm(v[:, 1:], axis=1)
    e = np.maximum(nu - v[:, 0], 0.0)
    if np.any((e > 0) & (nu == 0)):
        return None
    coef = 2.0 * e / term.sigma[::k] ** 2
    dz = np.zeros_like(v)
    on = e > 0
    dz[on, 1:] = coef[on, None] * v[on, 1:] / nu[on, None]
    dz[on, 0] = -coef[on]
    return A.T @ dz.ravel()


class _Renamed:
    """Give a second unnamed item of the same class a unique label without mutating it."""

    @staticmethod
    def wrap(item: Item, label: str) -> Item:
        clone = object.__new__(type(item))
        clone.__dict__.update(item.__dict__)
        object.__setattr__(clone, "name", label)
        object.__setattr__(clone, "_original", item)
        return clone

    @staticmethod
    def unwrap(item: Item) -> Item:
        return item.__dict__.get("_original", item)
