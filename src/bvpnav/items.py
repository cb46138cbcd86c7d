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

__all__ = ["Item", "MODES", "registry", "register", "item_class"]

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
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{what}: {value!r} is not a number") from None
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
    """Base class of additional information.

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
        Half-width of the band in the item's units for ``mode="band"``.
    name : str, optional
        Label used in reports and error messages; default ``Class#k``.

    Notes
    -----
    With residual :math:`\\rho = D x - e` (item units) the modes are

    - hard: :math:`\\rho = 0`;
    - soft: :math:`\\lambda \\sum_i (\\rho_i/\\sigma_i)^2` added to the objective;
    - robust: :math:`\\lambda \\sum_i \\mathrm{huber}(\\rho_i/\\sigma_i, M/\\sigma_i)`, or
      :math:`\\lambda \\sum_i |\\rho_i|/\\sigma_i` without a threshold;
    - band: :math:`|\\rho_i| \\le \\mathrm{tol}_i`.
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

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
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
        tol = positive_array(self.tol, f"{label}: tol")
        if mode == "band" and tol is None:
            raise InputError(f"{label}: mode='band' needs tol (half-width in {self.units})")
        if tol is not None and mode != "band":
            raise InputError(f"{label}: tol= goes with mode='band'")
        object.__setattr__(self, "tol", tol)
        if isinstance(self.axes, str):
            object.__setattr__(self, "axes", (self.axes,))
        elif self.axes is not None:
            object.__setattr__(self, "axes", tuple(str(a) for a in self.axes))
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

    def weight_rows(self, m: int) -> np.ndarray | None:
        """``sigma`` broadcast to the item's m residual rows (None for hard/band)."""
        if self.sigma is None:
            return None
        return self._broadcast(self.sigma, m, "sigma")

    def tol_rows(self, m: int) -> np.ndarray | None:
        """``tol`` broadcast to the item's m residual rows."""
        if self.tol is None:
            return None
        return self._broadcast(self.tol, m, "tol")

    def _broadcast(self, v: np.ndarray, m: int, what: str) -> np.ndarray:
        v = np.asarray(v, dtype=float)
        if v.size == 1:
            return np.full(m, float(v.ravel()[0]))
        if v.size == m:
            return v.ravel().astype(float)
        # per-time or per-axis arrays: repeat to rows (time-major, then axis)
        if m % v.size == 0:
            return np.repeat(v.ravel(), m // v.size)
        raise InputError(f"{self.label}: {what} has {v.size} entries for {m} residual rows")

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
        args = ", ".join(f"{k}={v!r}" for k, v in self.params().items())
        return f"{type(self).__name__}({args})"


def as_values(value, m_times: int, nax: int, what: str) -> np.ndarray:
    """Broadcast an item's value to shape (m_times, nax) then flatten time-major.

    Accepts a scalar, an array of length ``nax`` (one value per axis for every time),
    an array of length ``m_times`` (one value per time, single axis or the same for
    every axis), or an array of shape (m_times, nax).
    """
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{what}: {value!r} is not numeric") from None
    if not np.all(np.isfinite(v)):
        k = int(np.flatnonzero(~np.isfinite(v.ravel()))[0])
        raise InputError(f"{what}: entry {k} is {float(v.ravel()[k])!r}; values must be finite")
    if v.ndim == 0:
        out = np.full((m_times, nax), float(v))
    elif v.shape == (m_times, nax):
        out = v
    elif v.ndim == 1 and v.size == m_times and (nax == 1 or m_times != nax):
        out = np.repeat(v[:, None], nax, axis=1)
    elif v.ndim == 1 and v.size == nax:
        out = np.repeat(v[None, :], m_times, axis=0)
    else:
        raise InputError(
            f"{what}: shape {v.shape} does not fit {m_times} time(s) x {nax} axis(es); give a "
            f"scalar, {nax} per-axis values, {m_times} per-time values or shape ({m_times}, {nax})"
        )
    return out.ravel()
