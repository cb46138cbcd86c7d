r"""The error-model contract, composition with ``+``, and the exact sensor-correction map.

Contract (what :class:`bvpnav.model.NavModel` and :class:`bvpnav.NavigationProblem`
call):

- ``names(data) -> list[str]``: one name per internal parameter (``q`` names);
- ``columns(data) -> ndarray (N, d, q)``: change of the navigation-frame acceleration
  (m/s^2) per unit of each internal parameter, so ``a_c = a_hat + G l + w``;
- ``report(l, model) -> pandas.Series``: the physical, unit-bearing estimates indexed
  by name (``Series.attrs["units"]`` maps name to units);
- ``terms(model) -> list[Term]``: priors (soft, not scaled by ``lam``) and bounds
  (hard inequalities) on the parameters.

The built-in sensor models share one exact linear reparametrisation. The measurement
model

.. math:: \hat f = D f + b, \qquad D = (I + \mathrm{diag}(s))(I + \Theta),

is inverted exactly by a correction that is *linear* in the internal unknowns
``E`` (a matrix) and ``beta`` (a vector):

.. math:: f = (I + E) \hat f + \beta, \qquad I + E = D^{-1}, \quad \beta = -D^{-1} b.

``ScaleFactor`` owns the diagonal of ``E``, ``Misalignment`` its off-diagonal entries,
``Bias`` owns ``beta`` and ``UnknownGravity`` an additive correction ``dg`` of the
nominal gravity. The reported physical values follow from ``D = (I + E)^{-1}``:
``s_i = D_ii - 1``, ``Theta_ij = D_ij / D_ii``, ``b = -D beta``, ``g = g_nominal + dg``.
A noise-free measurement of this form is therefore corrected exactly, not to first
order (Misalignment modelled without ScaleFactor is exact to first order only,
because ``E`` then has no diagonal).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np
import pandas as pd

from ..errors import InputError
from ..model import Affine
from ..terms import Term

__all__ = [
    "ErrorModel",
    "SensorErrorModel",
    "CompositeErrorModel",
    "Param",
    "SensorCorrection",
    "sensor_axes",
    "sensor_frame",
    "sensor_signal",
    "as_error_model",
]

# ------------------------------------------------------------------ data views
def sensor_axes(data) -> tuple[str, ...]:
    """Names of the sensor axes: body ``x, y, z`` (strapdown) or the navigation axes.

    Examples
    --------
    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.error_models import sensor_axes
    >>> sensor_axes(bvpnav.ImuData(t=[0.0, 0.5, 1.0], acc=np.zeros((3, 2)), axes=("e", "n")))
    ('e', 'n')
    >>> f, w = np.tile([0.0, 0.0, 9.80665], (3, 1)), np.zeros((3, 3))
    >>> sensor_axes(bvpnav.ImuData.from_gyro([0.0, 0.5, 1.0], f, w))  # strapdown: the body axes
    ('x', 'y', 'z')
    """
    return ("x", "y", "z") if data.is_strapdown else tuple(data.axes)


def sensor_frame(data) -> np.ndarray:
    """Sensor-to-navigation rotation per sample, shape (N, d, n_sensor), dimensionless.

    The body-to-navigation matrices ``C_i`` for strapdown data; identity matrices for
    navigation-frame data (the sensor axes are the navigation axes).

    Examples
    --------
    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> f = np.tile([0.0, 0.0, 9.80665], (11, 1))  # at rest, z up (m/s^2)
    >>> w = np.tile([0.0, 0.0, 0.1], (11, 1))      # turning about z at 0.1 rad/s
    >>> data = bvpnav.ImuData.from_gyro(t, f, w)
    >>> from bvpnav.error_models import sensor_frame
    >>> C = sensor_frame(data)  # body to navigation, one matrix per sample
    >>> C.shape, (np.round(C[-1], 3) + 0.0).tolist()[0]  # after 1 s at 0.1 rad/s about z
    ((11, 3, 3), [0.995, -0.1, 0.0])
    """
    if data.is_strapdown:
        return data.attitude.as_matrix()
    d = data.ndim
    return np.broadcast_to(np.eye(d), (data.n, d, d))


def sensor_signal(data) -> np.ndarray:
    """The measured sensor output per sample, shape (N, n_sensor), m/s^2.

    Body-frame specific force for strapdown data, else the navigation-frame ``acc``.

    Examples
    --------
    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> f = np.tile([0.0, 0.0, 9.80665], (11, 1))  # at rest, z up (m/s^2)
    >>> w = np.tile([0.0, 0.0, 0.1], (11, 1))      # turning about z at 0.1 rad/s
    >>> data = bvpnav.ImuData.from_gyro(t, f, w)
    >>> from bvpnav.error_models import sensor_signal
    >>> sensor_signal(data)[0].tolist()  # the body-frame specific force (m/s^2)
    [0.0, 0.0, 9.80665]
    """
    return data.specific_force if data.is_strapdown else data.acc


def _nominal_gravity(data) -> np.ndarray:
    """Gravity already added to ``data.acc`` (m/s^2, per navigation axis); zero for nav data."""
    if data.is_strapdown:
        return np.asarray(data.gravity, dtype=float)
    return np.zeros(data.ndim)


# ------------------------------------------------------------- small helpers
def _finite(value, what: str) -> np.ndarray:
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{what}: {value!r} is not numeric") from None
    if np.isnan(v).any():
        raise InputError(f"{what}: contains NaN; give numbers")
    return v


def _per_param(value, q: int, what: str) -> np.ndarray:
    """Broadcast a scalar or a q-vector to q entries."""
    v = np.asarray(value, dtype=float).ravel()
    if v.size == 1:
        return np.full(q, float(v[0]))
    if v.size != q:
        raise InputError(f"{what}: {v.size} values for {q} parameters; give one value or {q}")
    return v.copy()


class Param(NamedTuple):
    """One internal parameter of a built-in sensor model.

    Attributes
    ----------
    name : str
    role : {"scale", "misalignment", "bias", "gravity"}
    i : int
        Sensor axis (scale, bias, misalignment row) or navigation axis (gravity).
    j : int
        Sensor axis picked up (misalignment column); equal to ``i`` for scale, -1 else.

    Examples
    --------
    >>> from bvpnav.error_models import Param
    >>> Param("bias_x", "bias", 0)
    Param(name='bias_x', role='bias', i=0, j=-1)
    """

    name: str
    role: str
    i: int
    j: int = -1


class _Combinable:
    """``+`` composition shared by single and composite models."""

    @property
    def components(self) -> tuple:
        return (self,)

    def __add__(self, other):
        if not isinstance(other, _Combinable):
            return NotImplemented
        return CompositeErrorModel(*self.components, *other.components)

    def __radd__(self, other):
        if isinstance(other, (int, float)) and other == 0:  # sum([...]) support
            return self
        return NotImplemented


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class ErrorModel(_Combinable):
    r"""Base class of error models (the plug-in contract).

    Parameters
    ----------
    axes : str or sequence of str, optional
        Sensor axes (or navigation axes, for gravity) the model applies to; default all.
    prior : float or array_like, optional
        Prior value of each parameter in the model's units (default: the model's
        ``default_prior``, e.g. zero bias, nominal gravity). Used only with ``sigma``.
    sigma : float or array_like, optional
        Prior standard deviation in the model's units: adds the soft term
        :math:`\sum_k ((p_k - p_k^0)/\sigma_k)^2` to the objective (not scaled by ``lam``).
    bounds : (float, float) or (array_like, array_like), optional
        Lower and upper bounds in the model's units (``-inf``/``inf`` allowed): hard
        inequalities :math:`lo \le p \le hi`.

    Notes
    -----
    A subclass implements ``names(data)`` and ``columns(data)`` (shape (N, d, q): the
    change of the navigation-frame acceleration in m/s^2 per unit parameter). Then the
    corrected acceleration is :math:`a_c = \hat a + G l + w`. By default the internal
    parameter is the reported one (``report`` returns ``l``) and priors and bounds act
    on ``l`` directly; the built-in sensor models override this with an exact
    nonlinear reparametrisation (see :mod:`bvpnav.error_models._base`).

    Examples
    --------
    A custom model, a bias that grows linearly in time (the sensor reads high by
    :math:`d\,(t - t_0)`, d in m/s^3), estimated from three known positions and the initial
    velocity of the motion :math:`r = 0.5 \sin t` m:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, Velocity
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> tk = [0.0, 5.0, 10.0]
    >>> known = [Position(t=tk, value=0.5 * np.sin(tk)), Velocity(t=0.0, value=0.5)]  # r = 0.5 sin t (m)
    >>> from dataclasses import dataclass
    >>> from bvpnav.error_models import ErrorModel, sensor_axes, sensor_frame
    >>> @dataclass(frozen=True, kw_only=True, eq=False)
    ... class BiasDrift(ErrorModel):
    ...     units = "m/s^3"
    ...     def names(self, data):
    ...         return [f"drift_{a}" for a in sensor_axes(data)]
    ...     def columns(self, data):  # acceleration change per unit d: -C (t - t0)
    ...         return -sensor_frame(data) * (data.t - data.t[0])[:, None, None]
    >>> data = bvpnav.ImuData(t=t, acc=-0.5 * np.sin(t) + 0.01 * t)
    >>> sol = bvpnav.NavigationProblem(data, error_model=BiasDrift(), items=known).solve(solver="direct")
    >>> print(f"drift {sol.error_params['drift_x']:.4f} m/s^3")
    drift 0.0100 m/s^3
    """

    axes: Any = None
    prior: Any = None
    sigma: Any = None
    bounds: Any = None

    #: Units of the reported parameters.
    units: ClassVar[str] = ""

    def __post_init__(self):
        label = type(self).__name__
        if isinstance(self.axes, str):
            object.__setattr__(self, "axes", (self.axes,))
        elif self.axes is not None:
            object.__setattr__(self, "axes", tuple(str(a) for a in self.axes))
            if not self.axes:
                raise InputError(f"{label}: axes=() selects nothing; omit axes for all axes")
        if self.sigma is not None:
            s = _finite(self.sigma, f"{label}: sigma")
            if not np.all(np.isfinite(s) & (s > 0)):
                raise InputError(f"{label}: sigma={self.sigma!r} must be finite and > 0 ({self.units})")
            object.__setattr__(self, "sigma", s)
        if self.prior is not None:
            if self.sigma is None:
                raise InputError(
                    f"{label}: prior={self.prior!r} without sigma; give sigma (in {self.units}) "
                    "for a soft prior, or bounds=(lo, hi) for hard limits"
                )
            p = _finite(self.prior, f"{label}: prior")
            if not np.all(np.isfinite(p)):
                raise InputError(f"{label}: prior must be finite")
            object.__setattr__(self, "prior", p)
        if self.bounds is not None:
            try:
                lo, hi = self.bounds
            except (TypeError, ValueError):
                raise InputError(f"{label}: bounds={self.bounds!r}; give a pair (lo, hi)") from None
            lo = _finite(lo, f"{label}: lower bound")
            hi = _finite(hi, f"{label}: upper bound")
            try:
                ok = np.all(np.broadcast_to(lo, np.broadcast_shapes(lo.shape, hi.shape))
                            < np.broadcast_to(hi, np.broadcast_shapes(lo.shape, hi.shape)))
            except ValueError:
                raise InputError(f"{label}: bounds have shapes {lo.shape} and {hi.shape}") from None
            if not ok:
                raise InputError(f"{label}: bounds={self.bounds!r} need lo < hi")
            object.__setattr__(self, "bounds", (lo, hi))
        self.validate()

    # ------------------------------------------------------------ contract
    def validate(self) -> None:
        """Check the model's own arguments; raise :class:`InputError` naming the model."""

    def _check_counts(self, sizes: tuple[int, ...], give: str) -> None:
        """For a model of a fixed number of parameters: ``sigma`` and ``prior`` have one of
        ``sizes`` values, else an error naming the model and saying to give ``give``."""
        for what, v in (("sigma", self.sigma), ("prior", self.prior)):
            if v is not None and np.size(v) not in sizes:
                raise InputError(f"{type(self).__name__}: {what} has {np.size(v)} values; give {give}")

    def names(self, data) -> list[str]:
        """Parameter names, one per column."""
        raise NotImplementedError

    def columns(self, data) -> np.ndarray:
        """Acceleration change per unit parameter, shape (N, d, q), m/s^2 per unit."""
        raise NotImplementedError

    def report(self, l, model) -> pd.Series:
        """Physical estimates by name (default: the internal values themselves)."""
        names = self.names(model.data)
        return _series(np.asarray(l, dtype=float), names, self.units)

    def physical_rows(self, model, value) -> Affine:
        """Rows ``w_k (p_k - v_k)`` (model units, ``w_k > 0``) of each parameter against ``value``.

        Priors and bounds are built from these rows; the default ``w_k = 1`` with
        ``p = l``.
        """
        names = self.names(model.data)
        return model.params(names) - _per_param(value, len(names), f"{type(self).__name__}: value")

    def default_prior(self, model) -> np.ndarray:
        """Prior value when ``sigma`` is given without ``prior`` (default 0)."""
        return np.zeros(len(self.names(model.data)))

    def terms(self, model) -> list:
        """Soft prior and hard bound terms for :class:`bvpnav.NavigationProblem`."""
        names = self.names(model.data)
        q = len(names)
        tag = type(self).__name__ + "[" + ", ".join(names) + "]"
        out = []
        if self.sigma is not None:
            p0 = self.default_prior(model) if self.prior is None else _per_param(
                self.prior, q, f"{tag}: prior")
            rows = self.physical_rows(model, p0)
            out.append(Term(label=f"prior {tag}", item=None, residual=_relabel(rows, names, "prior"),
                            mode="soft", kind="equality", sigma=_per_param(self.sigma, q, f"{tag}: sigma"),
                            scaled_by_lam=False, units=self.units))
        if self.bounds is not None:
            lo = _per_param(self.bounds[0], q, f"{tag}: lower bound")
            hi = _per_param(self.bounds[1], q, f"{tag}: upper bound")
            parts = []
            ku = np.flatnonzero(np.isfinite(hi))
            kl = np.flatnonzero(np.isfinite(lo))
            if ku.size:
                parts.append(_relabel(self.physical_rows(model, np.where(np.isfinite(hi), hi, 0.0)).rows(ku),
                                      [names[k] for k in ku], "upper"))
            if kl.size:
                parts.append(_relabel(-self.physical_rows(model, np.where(np.isfinite(lo), lo, 0.0)).rows(kl),
                                      [names[k] for k in kl], "lower"))
            if parts:
                out.append(Term(label=f"bounds {tag}", item=None, residual=Affine.vstack(parts),
                                mode="hard", kind="inequality", scaled_by_lam=False, units=self.units))
        return out

    def __repr__(self) -> str:
        args = []
        for k, v in self.__dict__.items():
            if v is None or k.startswith("_"):
                continue
            if isinstance(v, np.ndarray):
                v = v.tolist()
            elif isinstance(v, tuple) and any(isinstance(x, np.ndarray) for x in v):
                v = tuple(x.tolist() if isinstance(x, np.ndarray) else x for x in v)
            args.append(f"{k}={v!r}")
        return f"{type(self).__name__}({', '.join(args)})"

    # -------------------------------------------------------------- helpers
    def _select_axes(self, available: tuple[str, ...], what: str) -> tuple[int, ...]:
        """Indices of ``self.axes`` in ``available`` (all when ``axes`` is None)."""
        if self.axes is None:
            return tuple(range(len(available)))
        out = []
        for a in self.axes:
            if a not in available:
                raise InputError(
                    f"{type(self).__name__}: unknown {what} axis {a!r}; this data has {what} axes "
                    f"{list(available)}"
                )
            if available.index(a) in out:
                raise InputError(f"{type(self).__name__}: axis {a!r} given twice")
            out.append(available.index(a))
        return tuple(out)


def _series(values: np.ndarray, names, units: str | dict) -> pd.Series:
    s = pd.Series(np.asarray(values, dtype=float), index=pd.Index(list(names), name="parameter"),
                  name="estimate")
    s.attrs["units"] = dict(units) if isinstance(units, dict) else {n: units for n in names}
    return s


def _relabel(a: Affine, names, what: str) -> Affine:
    return Affine(a.A, a.c, tuple(f"{what}({n})" for n in names))


# ----------------------------------------------------- exact sensor correction
#: A kept fraction ``1 + E_ii`` within this (relative to ``|E_ii|``) of zero is zero: the
#: estimate ``E_ii ~ -1`` carries rounding of order ``cond * eps`` (measured 0 on one BLAS
#: kernel and 3e-13 on another for the same problem), so nothing smaller is resolved and
#: the verdict must not depend on which side of zero the rounding fell.
KEPT_ZERO = 1e-9

@dataclass(frozen=True)
class SensorCorrection:
    r"""Internal sensor correction ``f = (I + E) f_hat + beta`` and gravity correction ``dg``.

    Attributes
    ----------
    E : ndarray (n_sensor, n_sensor), dimensionless
    beta : ndarray (n_sensor,), m/s^2
    dg : ndarray (d,), m/s^2
    g_nominal : ndarray (d,), m/s^2

    Examples
    --------
    A sensor that reads 2 % high and 0.1 m/s^2 high, in the internal form
    :math:`f = (1 + E)\hat f + \beta`:

    >>> import numpy as np
    >>> from bvpnav.error_models import Param, SensorCorrection
    >>> corr = SensorCorrection(E=np.array([[1 / 1.02 - 1]]), beta=np.array([-0.1 / 1.02]),
    ...                         dg=np.zeros(1), g_nominal=np.zeros(1))
    >>> scale, bias = Param("scale_x", "scale", 0, 0), Param("bias_x", "bias", 0)
    >>> print(f"{corr.value(scale):.4f} {corr.value(bias):.4f} m/s^2")
    0.0200 0.1000 m/s^2
    """

    E: np.ndarray
    beta: np.ndarray
    dg: np.ndarray
    g_nominal: np.ndarray

    @property
    def kept(self) -> np.ndarray:
        """Kept fraction ``1 + E_ii`` of each sensor axis's own signal (dimensionless), with
        the values within :data:`KEPT_ZERO` (relative to ``|E_ii|``) of zero snapped to 0."""
        e = np.diag(self.E).astype(float)
        k = 1.0 + e
        with np.errstate(invalid="ignore"):
            zero = np.abs(k) <= KEPT_ZERO * np.maximum(1.0, np.abs(e))
        return np.where(zero, 0.0, k)

    @property
    def zero_axes(self) -> np.ndarray:
        """Indices of the sensor axes whose kept fraction is zero (see :attr:`kept`): the
        correction removes their signal and their gain, scale factor and bias are
        undetermined."""
        return np.flatnonzero(self.kept == 0.0)

    @property
    def D(self) -> np.ndarray:
        """Sensor matrix ``D = (I + E)^{-1} = (I + diag(s))(I + Theta)``.

        An axis whose kept fraction is zero (see :attr:`kept`) has ``D_ii = inf`` and
        the rest of its row and column 0 when no misalignment couples it to another axis
        (the other axes keep their finite values); coupled, or when ``I + E`` is singular
        otherwise, every entry is NaN.
        """
        n = self.E.shape[0]
        A = np.eye(n) + self.E
        zero = self.zero_axes
        if zero.size == 0:
            try:
                with np.errstate(all="ignore"):
                    return np.linalg.inv(A)
            except np.linalg.LinAlgError:
                return np.full((n, n), np.nan)
        off = A.copy()
        off[zero, zero] = 0.0
        if np.any(off[zero, :] != 0.0) or np.any(off[:, zero] != 0.0):
            return np.full((n, n), np.nan)  # a misalignment couples a removed axis to another
        rest = np.setdiff1d(np.arange(n), zero)
        D = np.zeros((n, n))
        D[zero, zero] = np.inf
        if rest.size:
            try:
                D[np.ix_(rest, rest)] = np.linalg.inv(A[np.ix_(rest, rest)])
            except np.linalg.LinAlgError:
                return np.full((n, n), np.nan)
        return D

    def value(self, p: Param) -> float:
        """Physical value of one parameter (see module notes).

        On an axis whose kept fraction is zero the scale factor is ``inf`` (the gain
        ``1 / (1 + E_ii)`` is infinite) and its bias and misalignments are NaN
        (undetermined), whatever rounding left in the internal values.
        """
        return float(self.values([p])[0])

    def values(self, params: list[Param]) -> np.ndarray:
        """Physical values of several parameters, each as :meth:`value` gives it, with
        :attr:`D` and the zero axes found once for all of them."""
        D, zero = self.D, set(self.zero_axes.tolist())
        out = np.empty(len(params))
        for k, p in enumerate(params):
            if p.role in ("scale", "misalignment", "bias") and p.i in zero:
                out[k] = np.inf if p.role == "scale" else np.nan
            elif p.role == "scale":
                out[k] = D[p.i, p.i] - 1.0
            elif p.role == "misalignment":
                out[k] = D[p.i, p.j] / D[p.i, p.i]
            elif p.role == "bias":
                out[k] = -(D[p.i] @ self.beta)
            else:
                out[k] = self.g_nominal[p.i] + self.dg[p.i]
        return out

    @classmethod
    def from_values(cls, params: list[Param], values: np.ndarray, data) -> SensorCorrection:
        ns = len(sensor_axes(data))
        E = np.zeros((ns, ns))
        beta = np.zeros(ns)
        dg = np.zeros(data.ndim)
        for p, v in zip(params, values, strict=True):
            if p.role in ("scale", "misalignment"):
                E[p.i, p.j] = v
            elif p.role == "bias":
                beta[p.i] = v
            elif p.role == "gravity":
                dg[p.i] = v
        return cls(E, beta, dg, _nominal_gravity(data))


def _sensor_layout(model) -> dict[tuple[str, int, int], str]:
    """(role, i, j) -> parameter name over every built-in sensor model in the problem."""
    em = model.error_model
    comps = getattr(em, "components", (em,)) if em is not None else ()
    out = {}
    for c in comps:
        if isinstance(c, SensorErrorModel):
            for p in c.params(model.data):
                if p.role != "bias_knot":
                    out[(p.role, p.i, p.j)] = p.name
    return out


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class _Installed(ErrorModel):
    """Base of the models of a fixed set of parameters that do not act on the accelerations
    (an antenna's or a vehicle point's offset, a mounting, a delay): the items read them
    through :class:`~bvpnav.NavModel` accessors, and their columns are zero.

    Subclasses state their parameter names (``NAMES``), why ``axes=`` does not apply
    (``NO_AXES``, the rest of the message) and the sigma/prior counts they take
    (``COUNTS``: the sizes and what to give, as :meth:`ErrorModel._check_counts`).
    """

    NAMES: ClassVar[tuple[str, ...]] = ()
    NO_AXES: ClassVar[str] = ""
    COUNTS: ClassVar[tuple[tuple[int, ...], str]] = ((), "")

    def validate(self) -> None:
        if self.axes is not None:
            raise InputError(f"{type(self).__name__}: axes= is not supported; {self.NO_AXES}")
        self._check_counts(*self.COUNTS)

    def names(self, data) -> list[str]:
        return list(self.NAMES)

    def columns(self, data) -> np.ndarray:
        """Zero: the parameters do not act on the accelerations, shape (N, d, q)."""
        return np.zeros((data.n, data.ndim, len(self.NAMES)))


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class SensorErrorModel(ErrorModel):
    r"""Base of the built-in sensor models (scale, misalignment, bias, gravity).

    Subclasses list their internal parameters with :meth:`params`; the columns, the
    physical report and the exact prior/bound rows follow from the roles.

    Notes
    -----
    With ``C_i`` the sensor-to-navigation matrix and ``f_i`` the measured sensor output
    of sample i, the columns are

    .. math::

        G[:, :, E_{kj}] = C_i[:, k] \hat f_{i,j}, \quad
        G[:, :, \beta_k] = C_i[:, k], \quad G[:, :, dg_a] = e_a

    (the 2010 paper's eq. 31-34 with ``F = -M G``).

    Examples
    --------
    The built-in accelerometer models list their parameters with roles; columns follow from
    the roles:

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> f = np.tile([0.0, 0.0, 9.80665], (11, 1))  # at rest, z up (m/s^2)
    >>> w = np.tile([0.0, 0.0, 0.1], (11, 1))      # turning about z at 0.1 rad/s
    >>> data = bvpnav.ImuData.from_gyro(t, f, w)
    >>> from bvpnav.error_models import Bias, ScaleFactor
    >>> Bias(axes="z").params(data)
    [Param(name='bias_z', role='bias', i=2, j=-1)]
    >>> ScaleFactor(axes="z").params(data)
    [Param(name='scale_z', role='scale', i=2, j=2)]
    >>> Bias(axes="z").columns(data)[0].tolist()  # sensor z is navigation z at the start
    [[0.0], [0.0], [1.0]]
    """

    def params(self, data) -> list[Param]:
        """The internal parameters with their roles."""
        raise NotImplementedError

    def names(self, data) -> list[str]:
        return [p.name for p in self.params(data)]

    def columns(self, data) -> np.ndarray:
        C = sensor_frame(data)
        f = sensor_signal(data)
        n, d = data.n, data.ndim
        cols = []
        for p in self.params(data):
            if p.role in ("scale", "misalignment"):
                cols.append(C[:, :, p.i] * f[:, p.j, None])
            elif p.role == "bias":
                cols.append(np.array(C[:, :, p.i]))
            else:
                g = np.zeros((n, d))
                g[:, p.i] = 1.0
                cols.append(g)
        return np.stack(cols, axis=2)

    def physical(self, corr: SensorCorrection, data) -> np.ndarray:
        """Physical values of this model's parameters given the full correction."""
        return corr.values(self.params(data))

    def report(self, l, model) -> pd.Series:
        ps = self.params(model.data)
        corr = SensorCorrection.from_values(ps, np.asarray(l, dtype=float), model.data)
        return _series(self.physical(corr, model.data), [p.name for p in ps], self.units)

    def physical_rows(self, model, value) -> Affine:
        r"""Rows linear in the internal unknowns, equal to ``w (p - v)`` with ``w > 0``.

        Notes
        -----
        With ``k_i = E_ii`` (zero when scale is not modelled):

        - scale: :math:`-k_i - v(1 + k_i) = (s_i - v)(1 + k_i)`;
        - bias: :math:`-\beta_i - v(1 + k_i) = (b_i - v)(1 + k_i)`;
        - gravity: :math:`g_a + dg_a - v`;
        - misalignment: :math:`-E_{ij} - v \approx \Theta_{ij} - v` (first order).

        The first three are exact without misalignment, so bounds on them are exact
        linear inequalities; with misalignment they hold to first order in Theta.
        """
        ps = self.params(model.data)
        v = _per_param(value, len(ps), f"{type(self).__name__}: value")
        layout = _sensor_layout(model)
        g0 = _nominal_gravity(model.data)
        rows = []
        for p, vk in zip(ps, v, strict=True):
            P = model.params([p.name])
            if p.role == "scale":
                rows.append(P * (-(1.0 + vk)) - vk)
            elif p.role == "misalignment":
                rows.append(-P - vk)
            elif p.role in ("bias", "bias_knot"):  # a knot's bias: the same row on its value
                r = -P - vk
                kname = layout.get(("scale", p.i, p.i))
                if kname is not None:
                    r = r + model.params([kname]) * (-vk)
                rows.append(r)
            else:
                rows.append(P + (g0[p.i] - vk))
        return Affine.vstack(rows)


# ------------------------------------------------------------------ composite
class CompositeErrorModel(_Combinable):
    """Several error models side by side (built with ``+``).

    Parameters
    ----------
    *components : ErrorModel
        Parameters are ordered as the components are.

    Notes
    -----
    The columns are concatenated, ``G = [G_1 | G_2 | ...]``. Reporting evaluates the
    built-in sensor models jointly (bias, scale and misalignment share one exact
    correction matrix) and every other model on its own slice of ``l``.

    Examples
    --------
    >>> from bvpnav.error_models import Bias, ScaleFactor, UnknownGravity
    >>> model = ScaleFactor() + Bias() + UnknownGravity()
    >>> model
    ScaleFactor() + Bias() + UnknownGravity()
    >>> [type(c).__name__ for c in model.components]
    ['ScaleFactor', 'Bias', 'UnknownGravity']
    """

    def __init__(self, *components):
        flat = []
        for c in components:
            if not isinstance(c, _Combinable):
                raise InputError(
                    f"error model: {c!r} is not an error model; use bvpnav.error_models.Bias(), "
                    "ScaleFactor(), ... or a subclass of ErrorModel"
                )
            flat.extend(c.components)
        if not flat:
            raise InputError("error model: no components")
        self._components = tuple(flat)

    @property
    def components(self) -> tuple:
        return self._components

    def _sizes(self, data) -> list[int]:
        return [len(c.names(data)) for c in self._components]

    def names(self, data) -> list[str]:
        out, owner = [], {}
        for c in self._components:
            for n in c.names(data):
                if n in owner:
                    raise InputError(
                        f"error model: parameter {n!r} comes from both {owner[n]} and "
                        f"{type(c).__name__}; each parameter may appear once (select axes=...)"
                    )
                owner[n] = type(c).__name__
                out.append(n)
        return out

    def columns(self, data) -> np.ndarray:
        self.names(data)  # duplicate check
        return np.concatenate([np.asarray(c.columns(data), dtype=float) for c in self._components],
                              axis=2)

    def report(self, l, model) -> pd.Series:
        data = model.data
        l = np.asarray(l, dtype=float)
        sizes = self._sizes(data)
        offs = np.concatenate([[0], np.cumsum(sizes)])
        sens_p, sens_v = [], []
        for c, o, q in zip(self._components, offs[:-1], sizes, strict=True):
            if isinstance(c, SensorErrorModel) and not getattr(c, "time_varying", False):
                sens_p.extend(c.params(data))
                sens_v.extend(l[o:o + q])
        corr = SensorCorrection.from_values(sens_p, np.array(sens_v), data)
        # (values, names, units) per component, one Series made at the end (not one per component
        # joined by pd.concat: param_jacobian calls this twice per parameter)
        parts = []
        for c, o, q in zip(self._components, offs[:-1], sizes, strict=True):
            if getattr(c, "time_varying", False) or isinstance(c, SensorErrorModel):
                names = c.names(data)
                values = c.knot_values(l[o:o + q], corr, data) if getattr(c, "time_varying", False) \
                    else c.physical(corr, data)
                parts.append((np.asarray(values, dtype=float), names,
                              dict(c.units) if isinstance(c.units, dict) else {n: c.units for n in names}))
            else:
                s = c.report(l[o:o + q], model)
                own = s.attrs.get("units", {n: getattr(c, "units", "") for n in s.index})
                parts.append((s, list(s.index), own))
        units = {}
        for _, _, u in parts:
            units.update(u)
        if all(isinstance(v, np.ndarray) or v.dtype == np.float64 for v, _, _ in parts):
            out = pd.Series(np.concatenate([np.asarray(v, dtype=float) for v, _, _ in parts]),
                            index=pd.Index([n for _, names, _ in parts for n in names]), name="estimate")
        else:   # a component reports something other than floats: pandas combines the types
            out = pd.concat([v if isinstance(v, pd.Series) else _series(v, n, u) for v, n, u in parts])
            out.name = "estimate"
        out.index.name = "parameter"
        out.attrs["units"] = units
        return out

    def terms(self, model) -> list:
        out = []
        for c in self._components:
            out.extend(c.terms(model))
        return out

    def __repr__(self) -> str:
        return " + ".join(repr(c) for c in self._components)


def as_error_model(obj):
    """Return ``obj`` if it is an error model (single or composite), else raise InputError."""
    if obj is None or isinstance(obj, _Combinable):
        return obj
    raise InputError(f"error_model={obj!r}: expected bvpnav.error_models.Bias() + ScaleFactor() etc.")
