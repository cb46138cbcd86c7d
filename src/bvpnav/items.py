"""The contract every piece of additional information follows.

An item is a small frozen dataclass. Its constructor stores and validates data and
creates no cvxpy objects; its one method :meth:`Item.compile` receives the typed
:class:`~bvpnav.model.NavModel` and returns the item's residual as an
:class:`~bvpnav.model.Affine` map (``D x - e`` in the item's units). The framework,
not the item, turns the residual into a hard equality, a weighted soft term, a robust
penalty or a tolerance band, checks convexity, and names the item in every error.

Subclasses register themselves by name on definition, so the spec files, the CLI and
the shared contract test find every item without a list to maintain.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import numpy as np

from .errors import InputError
from .timebase import as_float_array

__all__ = ["Item", "Linearizable", "MODES", "registry", "register", "item_class", "broadcast_rows",
           "as_values"]

MODES = ("hard", "soft", "robust", "band")

_REGISTRY: dict[str, type[Item]] = {}


def registry() -> dict[str, type[Item]]:
    """Registered item classes by name (imports ``bvpnav.constraints`` first)."""
    import bvpnav.constraints  # noqa: F401  (discovers every file of the plug-in package)

    return dict(_REGISTRY)


def register(cls: type[Item]) -> type[Item]:
    """Register an item class under its ``registered_name`` (idempotent)."""
    name = cls.registered_name()
    old = _REGISTRY.get(name)
    if old is not None and old is not cls and old.__qualname__ != cls.__qualname__:
        raise InputError(f"item name {name!r} is registered twice ({old!r} and {cls!r})")
    _REGISTRY[name] = cls
    return cls


def item_class(name: str) -> type[Item]:
    """Look up an item class by registered name; unknown names list the valid ones."""
    reg = registry()
    key = str(name).lower()
    if key not in reg:
        raise InputError(f"unknown item {name!r}; registered items: {sorted(reg)}")
    return reg[key]


def _snake(name: str) -> str:
    return re.sub(r"(?<!^)(?=[A-Z])", "_", name).lower()


def positive_array(value, what: str, allow_none: bool = True):
    """Validate a positive scalar or array (sigma, tol, huber); return a float array or None."""
    if value is None:
        if allow_none:
            return None
        raise InputError(f"{what} is required")
    arr = as_float_array(value, what, "the item's units")
    bad = np.flatnonzero(~(np.isfinite(arr) & (arr > 0)).ravel())
    if bad.size:
        v = float(arr.ravel()[bad[0]])
        raise InputError(
            f"{what} = {v!r}: must be a finite positive number (for a hard condition omit sigma "
            "or use mode='hard')"
        )
    return arr


@dataclass(frozen=True, kw_only=True, eq=False)
class Item:
    r"""Base class of additional information.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Axes the item applies to; default all axes of the data.
    sigma : float or array_like, optional
        Standard deviation of the information in the item's units (``units``).
        ``None`` with no ``mode`` means hard; a number alone means soft.
    mode : {"hard", "soft", "robust", "band"}, optional
        How the residual enters the problem (see Notes).
    huber : float, optional
        Huber threshold in the item's units for ``mode="robust"``; ``None`` means the
        L1 penalty.
    tol : float or array_like, optional
        Half-width of the band in the item's units for ``mode="band"``. With ``sigma`` as
        well the band has soft edges (see Notes).
    name : str, optional
        Label used in reports and error messages; default ``Class#k``.

    Notes
    -----
    With residual :math:`\rho = D x - e` (item units) the modes are

    - hard: :math:`\rho = 0`;
    - soft: :math:`\lambda \sum_i (\rho_i/\sigma_i)^2` added to the objective;
    - robust: :math:`\lambda \sum_i \mathrm{huber}(\rho_i/\sigma_i, M/\sigma_i)`, or
      :math:`\lambda \sum_i |\rho_i|/\sigma_i` without a threshold;
    - band: :math:`|\rho_i| \le \mathrm{tol}_i`;
    - band with ``sigma`` (soft edges): :math:`\lambda \sum_i (\max(|\rho_i| - \mathrm{tol}_i,
      0)/\sigma_i)^2`, nothing within the band and the excess beyond it a soft penalty (an
      inequality :math:`g \le 0`: :math:`\max(g_i - \mathrm{tol}_i, 0)`). The information
      "within tol, and rarely beyond by more than sigma": convex, once differentiable, and
      solved by ``direct`` as well as by the conic solvers. Not for cone items.

    **Broadcasting rule** (one function, :func:`broadcast_rows`, for ``value``, ``sigma``
    and ``tol`` of every item). An item with K instants on A axes has K * A residual rows,
    time-major (instant 0 axes 0..A-1, instant 1, ...). A per-row quantity may be

    - a scalar: the same for every row;
    - K values: one per instant (the same on every axis);
    - A values: one per axis (the same at every instant);
    - K * A values: one per row, time-major;
    - shape (K, A): one per instant and axis.

    When K == A > 1 a flat list of K values could mean per instant or per axis: it is
    refused, with both spellings (shape (K, A) says either unambiguously, e.g.
    ``value=[[0, 0], [10, 10]]`` for "0 m at the first instant, 10 m at the second" on
    two axes). Anything else is refused naming the item and the accepted lengths; nothing
    is repeated to fit. Items whose instants are the grid nodes (intervals, symmetry,
    bounds, cones, tracks) take a scalar or one value per row. ``axes=[]`` (no axis) is
    refused at construction.

    Examples
    --------
    The mode follows from the arguments (no ``sigma``: hard; ``sigma`` alone: soft):

    >>> from bvpnav.constraints import Position
    >>> Position(t=1.0, value=0.5).mode
    'hard'
    >>> soft = Position(t=1.0, value=0.5, sigma=0.1)
    >>> soft.mode, soft.units, soft.kind
    ('soft', 'm', 'equality')
    >>> Position.registered_name()
    'position'
    >>> from bvpnav.items import item_class
    >>> item_class("position") is Position
    True
    """

    axes: Any = None
    sigma: Any = None
    mode: str | None = None
    huber: float | None = None
    tol: Any = None
    name: str | None = None

    #: Units of the residual, used in messages and ``describe()``.
    units: ClassVar[str] = "m"
    #: ``"equality"`` (residual should be zero) or ``"inequality"`` (residual <= 0).
    kind: ClassVar[str] = "equality"
    #: True for an item that cannot compile before it is linearized about a trajectory
    #: (only :class:`Linearizable` items ever say so).
    needs_linearization: ClassVar[bool] = False
    #: True for an item whose rows act only on error-model parameters (a gyro stance acts on
    #: the gyro bias): the contract check then solves it with its :meth:`example_model`'s
    #: error model.
    needs_error_model: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "__repr__" not in cls.__dict__:  # before @dataclass, which keeps a __repr__ it finds
            cls.__repr__ = Item.__repr__
        if not cls.__name__.startswith("_"):
            register(cls)

    @classmethod
    def registered_name(cls) -> str:
        """Name used in spec files and the CLI (snake case of the class name)."""
        return _snake(cls.__name__)

    def __post_init__(self):
        if self.name is not None and not (isinstance(self.name, str) and self.name.strip()):
            raise InputError(f"{type(self).__name__}: name={self.name!r}; give a non-empty string "
                             "(it labels the item in reports and errors)")
        label = self.label
        mode = self.mode
        if mode is None:
            mode = "hard" if self.sigma is None else "soft"
        mode = str(mode).lower()
        if mode not in MODES:
            raise InputError(f"{label}: mode={self.mode!r}; choose one of {list(MODES)}")
        object.__setattr__(self, "mode", mode)
        sigma = positive_array(self.sigma, f"{label}: sigma")
        if mode == "soft" and sigma is None:
            raise InputError(f"{label}: mode='soft' needs sigma (in {self.units})")
        if mode == "hard" and sigma is not None:
            raise InputError(
                f"{label}: sigma={self.sigma!r} with mode='hard'; drop sigma or use mode='soft'"
            )
        object.__setattr__(self, "sigma", sigma)
        huber = positive_array(self.huber, f"{label}: huber")
        if huber is not None and mode != "robust":
            raise InputError(f"{label}: huber= goes with mode='robust'")
        object.__setattr__(self, "huber", None if huber is None else float(huber))
        if mode == "band" and sigma is not None and self.kind == "cone":
            raise InputError(f"{label}: sigma={self.sigma!r} with mode='band' (a band with soft edges) is "
                             "not available for a cone item; drop sigma (a hard band) or use mode='soft'")
        tol = positive_array(self.tol, f"{label}: tol")
        if mode == "band" and tol is None:
            raise InputError(f"{label}: mode='band' needs tol (half-width in {self.units})")
        if tol is not None and mode != "band":
            raise InputError(f"{label}: tol= goes with mode='band'")
        object.__setattr__(self, "tol", tol)
        if isinstance(self.axes, str):
            object.__setattr__(self, "axes", (self.axes,))
        elif self.axes is not None:
            try:
                axes = tuple(self.axes)
            except TypeError:
                raise InputError(f"{label}: axes={self.axes!r}; give an axis name or a list of them, e.g. "
                                 "axes=('x', 'y')") from None
            if not axes:
                raise InputError(f"{label}: axes={self.axes!r} names no axis; omit axes= for every axis "
                                 "of the data, or name some, e.g. axes=('x',)")
            if not all(isinstance(a, str) for a in axes):
                raise InputError(f"{label}: axes={self.axes!r}; give axis names as strings, e.g. "
                                 "axes=('x', 'y')")
            object.__setattr__(self, "axes", axes)
        self.validate()

    # ----------------------------------------------------------- contract
    def validate(self) -> None:
        """Check the item's own data; raise :class:`InputError` naming the item."""

    def compile(self, model) -> Any:
        """Return the residual ``D x - e`` as an :class:`~bvpnav.model.Affine` (item units).

        Inequality items return ``g`` with the meaning ``g(x) <= 0``.
        """
        raise NotImplementedError

    @classmethod
    def example(cls) -> Item:
        """A valid instance for a window of [0, 10] s with axes x, y, z.

        Every registered item provides one, so the shared contract test
        (``tests/test_contract.py``) can exercise it without a list to maintain.
        """
        raise NotImplementedError(f"{cls.__name__} must implement example() for the contract test")

    @classmethod
    def example_model(cls):
        """The :class:`~bvpnav.NavModel` that :meth:`example` is written for, or None for the
        default (three axes x, y, z on [0, 10] s, navigation-frame accelerations). An item
        that needs strapdown data or an error model returns one."""
        return None

    def math(self) -> str:
        """One line of plain-text mathematics for ``describe()``."""
        return f"{type(self).__name__}"

    def latex(self) -> str | None:
        """The residual's equation as mathtext-compatible LaTeX (None: use ``math()``)."""
        return None

    # ------------------------------------------------------------ helpers
    @property
    def label(self) -> str:
        """The item's name for messages."""
        return self.name or type(self).__name__

    def row_layout(self, m: int) -> tuple[int, int]:
        """``(instants, axes)`` of the item's ``m`` residual rows (time-major).

        The default uses :meth:`n_instants` when the item knows them; otherwise every row
        is its own instant (``(m, 1)``: a scalar or one value per row).
        """
        k = self.n_instants()
        if k and m % k == 0:
            return k, m // k
        return m, 1

    def n_instants(self) -> int | None:
        """Number of instants (or intervals) the item constrains, if known before compiling."""
        return None

    @property
    def is_constraint(self) -> bool:
        """Whether the rows are held as constraints (hard, or a band without ``sigma``: hard
        edges) rather than penalized (soft, robust, a band with soft edges)."""
        return self.mode == "hard" or (self.mode == "band" and self.sigma is None)

    def weight_rows(self, m: int) -> np.ndarray | None:
        """``sigma`` per residual row (None for hard/band), by :func:`broadcast_rows`."""
        if self.sigma is None:
            return None
        k, a = self.row_layout(m)
        return broadcast_rows(self.sigma, k, a, f"{self.identify()}: sigma", self.units)

    def tol_rows(self, m: int) -> np.ndarray | None:
        """``tol`` per residual row, by :func:`broadcast_rows`."""
        if self.tol is None:
            return None
        k, a = self.row_layout(m)
        return broadcast_rows(self.tol, k, a, f"{self.identify()}: tol", self.units)

    def identify(self) -> str:
        """The item's label, and for an unnamed item what it holds, for messages.

        A named item is its name; an unnamed one (``Position``, ``Position#3``) is
        followed by its own fields, shortened, with units, e.g.
        ``Position#3 (t=[0, 10] s, value=[0, 10] m)``, so a message naming it can be
        acted on.
        """
        original = self.__dict__.get("_original", self)
        if original.name is not None:
            return self.label
        base = {f.name for f in fields(Item)}
        parts = []
        for f in fields(self):
            if f.name in base or not f.init:
                continue
            v = getattr(self, f.name)
            if v is None:
                continue
            unit = ""
            if f.name in ("t", "t0", "t1", "about") or f.name.endswith("_t"):
                unit = " s"
            elif f.name == "value":
                unit = f" {self.units}"
            parts.append(f"{f.name}={_short(v)}{unit}")
        if self.axes is not None:
            parts.append(f"axes={list(self.axes)}")
        return f"{self.label} ({', '.join(parts)})" if parts else self.label

    def params(self) -> dict[str, Any]:
        """Constructor arguments as plain Python values (for specs and repr)."""
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if v is None:
                continue
            if isinstance(v, np.ndarray):
                v = v.tolist()
            elif isinstance(v, tuple):
                v = list(v)
            out[f.name] = v
        return out

    def __repr__(self) -> str:
        """``Position(mode='hard', name='ends', t=[0.0, 10.0], value=[0.0, 10.0])``: the mode,
        the name and the other fields that are set; more than 4 numbers by count and range."""
        parts = [f"mode={self.mode!r}"] + ([f"name={self.name!r}"] if self.name else [])
        parts += [f"{k}={_repr_value(v)}" for k, v in self.params().items() if k not in ("mode", "name")]
        return f"{type(self).__name__}({', '.join(parts)})"


class Linearizable:
    """The declared contract of an item that is nonlinear in the unknowns.

    Mix it in before :class:`Item` (``class TrackLine(Linearizable, Item)``: then an item that
    forgets :attr:`needs_linearization` fails loudly instead of reading Item's False). The
    sequential
    convex loop (:mod:`bvpnav.solve.sequential`) handles exactly the items that are
    instances of this class and whose :attr:`needs_linearization` is True; it calls the
    methods below and nothing else.

    Methods to provide: :attr:`needs_linearization` (True while there is no linearization
    point) and :meth:`linearized`. Optional: :meth:`continuation_sigma` and
    :meth:`with_mode` (overriding them makes a hard or band item iterate soft first) and
    :meth:`linearization_counts` (reported per iteration).
    """

    @property
    def needs_linearization(self) -> bool:  # type: ignore[override]
        raise NotImplementedError

    def linearized(self, t, positions) -> Item:
        """A copy linearized about an estimate (``t`` in s, ``positions`` (N, d) in m or a
        trajectory DataFrame), which compiles to an affine residual."""
        raise NotImplementedError

    def continuation_sigma(self) -> float | None:
        """Sigma (item units) of a soft stand-in for a hard or band linearized copy.

        Override it (and :meth:`with_mode`) to take a continuation: the loop iterates such
        an item soft first with this sigma. The base method means "no continuation"; an
        override returning None means none for this linearization (the item is iterated
        in its own mode)."""
        return None

    def with_mode(self, mode: str, sigma=None, tol=None, huber=None) -> Item:
        """A copy in another mode (needed when :meth:`continuation_sigma` is not None)."""
        raise NotImplementedError

    def linearization_counts(self) -> dict[str, int] | None:
        """Per-row status counts of the linearization (e.g. rows kept or dropped), or None."""
        return None

    def linearized_from(self, solution, t, trajectory) -> Item:
        """A copy linearized about a solution (the previous iterate; None when the loop
        starts from a given trajectory): by default :meth:`linearized` about its
        positions. Override it to read more of the estimate (error-model parameters,
        velocities)."""
        return self.linearized(t, trajectory)

    def linearization_change(self, previous) -> float | None:
        """How far this linearization moved from ``previous`` (the same item's previous
        linearization), in the item's units: when every linearized item of the loop says less
        than ``tol``, the last solve already answers the new linearization and the loop stops
        without another solve. None (default): not measured (the loop judges by the change of
        the positions)."""
        return None

    def first_phase(self) -> Item | None:
        """The stand-in of this item in the loop's first phase (the solve that makes the
        initial estimate), or None (default) to leave it out of that phase."""
        return None


def _repr_value(v) -> str:
    """A field for a repr: up to 4 numbers as they are, more as ``<N values, lo .. hi>``."""
    if isinstance(v, list):
        try:
            a = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            return repr(v)
        if a.size > 4:
            return f"<{a.size} values, {np.nanmin(a):.4g} .. {np.nanmax(a):.4g}>"
    return repr(v)


def _short(v, n: int = 4) -> str:
    """A value shortened for a message: numbers with ``%g``, long arrays elided."""
    if isinstance(v, str):
        return repr(v)
    if isinstance(v, bool | np.bool_):
        return repr(bool(v))
    try:
        arr = np.asarray(v, dtype=float)
    except Exception:  # anything not numeric (it is only shown)
        text = repr(v)
        return text if len(text) <= 40 else text[:37] + "..."
    if arr.ndim == 0:
        return f"{float(arr):g}"
    if arr.ndim > 1:
        return f"<array of shape {arr.shape}>"
    vals = [f"{x:g}" for x in arr]
    if len(vals) > n:
        vals = vals[: n - 1] + ["...", vals[-1]]
        return "[" + ", ".join(vals) + f"] ({arr.size} values)"
    return "[" + ", ".join(vals) + "]"


def broadcast_rows(v, k: int, a: int, what: str, units: str = "") -> np.ndarray:
    """Spread a per-row quantity over ``k`` instants x ``a`` axes, time-major (the rule).

    Parameters
    ----------
    v : float or array_like
        A scalar, ``k`` values (per instant), ``a`` values (per axis), ``k * a`` values
        (per row, time-major) or shape ``(k, a)``.
    k, a : int
        Instants and axes of the item's rows.
    what : str
        The item and the field, for messages (e.g. ``"Position#2 (t=[0, 10] s): value"``).
    units : str
        The field's units, for messages.

    Returns
    -------
    numpy.ndarray, shape (k * a,)
        Row ``i * a + j`` is instant ``i``, axis ``j``.

    Raises
    ------
    InputError
        For a flat list of ``k == a > 1`` values (per instant or per axis? both spellings
        are given), and for any other shape, naming the accepted lengths.
    """
    arr = as_float_array(v, what, units or "the item's units")
    bad = np.flatnonzero(~np.isfinite(arr.ravel()))
    if bad.size:
        j = int(bad[0])
        raise InputError(f"{what}: entry {j} is {float(arr.ravel()[j])!r}; values must be finite")
    m = k * a
    if arr.size == 1:
        return np.full(m, float(arr.ravel()[0]))
    if arr.shape == (k, a):
        return arr.ravel()
    if arr.ndim == 1:
        if arr.size == k and k == a:
            per_inst = np.repeat(arr[:, None], a, axis=1).tolist()
            per_axis = np.repeat(arr[None, :], k, axis=0).tolist()
            raise InputError(
                f"{what}: {arr.tolist()} has {k} entries for {k} instants on {a} axes: one per instant "
                f"or one per axis? Write it as shape ({k}, {a}), one row per instant and one column per "
                f"axis: {per_inst} for one value per instant (the same on every axis), or {per_axis} "
                "for one value per axis (the same at every instant)"
            )
        if arr.size == m:
            return arr.copy()
        if arr.size == k:
            return np.repeat(arr, a)
        if arr.size == a:
            return np.tile(arr, k)
    accepted = sorted({1, k, a, m})
    raise InputError(
        f"{what}: shape {arr.shape} does not fit {k} instant(s) x {a} axis(es) = {m} row(s); give a "
        f"scalar, {k} value(s) (one per instant), {a} (one per axis), {m} (one per row, time-major) or "
        f"shape ({k}, {a}) (accepted flat lengths: {accepted}); nothing is repeated to fit"
    )


def as_values(value, m_times: int, nax: int, what: str) -> np.ndarray:
    """An item's value per residual row: :func:`broadcast_rows` with ``m_times`` instants.

    Accepts a scalar, ``m_times`` values (one per instant), ``nax`` values (one per axis),
    ``m_times * nax`` values (one per row) or shape ``(m_times, nax)``; a flat list that
    could be either (``m_times == nax > 1``) is refused with both spellings.
    """
    return broadcast_rows(value, m_times, nax, what)
