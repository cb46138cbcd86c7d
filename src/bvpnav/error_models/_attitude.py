r"""Attitude error models: the shared linearized attitude-error propagation.

An attitude error model has parameters that change the *attitude* the navigation-frame
acceleration ``a_i = C_i f_i + g`` is computed with: the error of the initial attitude
(:class:`~bvpnav.error_models.AttitudeError`) and the gyro's own errors
(:class:`~bvpnav.error_models.GyroBias`, :class:`~bvpnav.error_models.GyroScaleFactor`).
The acceleration is not linear in them, so a problem with such a model is solved by the
damped outer loop of :mod:`bvpnav.solve.attitude`: it re-integrates the attitude with
the current totals, hands the convex problem the *increments* about them as unknowns,
and keeps a step only when the nonlinear objective falls.

The linearization point (the totals and the raw measurements) travels with the data as
an :class:`AttitudePoint` (``data.attitude_point``): the error models stay immutable and
read it from the data they are given, so every plug-in signature is unchanged.

Conventions: ``C`` maps body to navigation vectors; a perturbation of the attitude is a
small rotation :math:`\psi` in the navigation frame, :math:`C' = \exp([\psi\times]) C`.
The gyro reads :math:`\hat\omega = (1 + s)\,\omega + b` per body axis.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from dataclasses import replace as _replace
from typing import ClassVar

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import InputError
from ._base import ErrorModel, _per_param, _series

__all__ = ["AttitudeErrorModel", "AttitudePoint", "knot_times", "hat_weights", "right_jacobian",
           "left_jacobian", "propagate", "attitude_components", "reintegrate", "at_point"]


# ------------------------------------------------------------------ knots
def knot_times(t: np.ndarray, interval: float) -> np.ndarray:
    """Knots of a time-varying parameter: ``n + 1`` equally spaced times over the window.

    ``n = max(1, round((t_N - t_1) / interval))``, so the spacing is the ``interval`` (s)
    rounded to fit the window exactly; the first knot is ``t_1``, the last ``t_N``.
    """
    t0, t1 = float(t[0]), float(t[-1])
    n = max(1, int(round((t1 - t0) / float(interval))))
    return np.linspace(t0, t1, n + 1)


def hat_weights(t: np.ndarray, knots: np.ndarray) -> np.ndarray:
    """Linear (hat) interpolation weights, shape (N, M): ``p(t_i) = sum_m W[i, m] p_m``."""
    t = np.asarray(t, dtype=float)
    m = knots.size
    W = np.zeros((t.size, m))
    if m == 1:
        W[:, 0] = 1.0
        return W
    k = np.clip(np.searchsorted(knots, t, side="right") - 1, 0, m - 2)
    u = (t - knots[k]) / (knots[k + 1] - knots[k])
    rows = np.arange(t.size)
    W[rows, k] = 1.0 - u
    W[rows, k + 1] = u
    return W


# ----------------------------------------------------------- knot options and priors
def positive_option(value, what: str) -> float | None:
    """``value`` as a positive finite float (None stays None), or :class:`InputError` naming it."""
    if value is None:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{what}={value!r}: give a positive number") from None
    if not (np.isfinite(v) and v > 0):
        raise InputError(f"{what}={value!r}: must be finite and > 0")
    return v


def random_walk_term(model, names: list, knots: np.ndarray, drift: float, units: str, label: str,
                     sign: float = 1.0, base: np.ndarray | None = None, anchored: bool = False):
    r"""The soft prior of a random walk over knot values, per axis (axis-major ``names``).

    Rows :math:`\pm(p_{m+1} - p_m)` (plus the totals' own difference ``base``) with sigma
    :math:`\sigma_d \sqrt{t_{m+1} - t_m}`: the increments of a random walk of density
    ``drift`` (units per sqrt(s)) between the knots. ``anchored``: the walk is zero at
    the first knot, which is not a parameter (``names`` hold knots 1, 2, ... per axis), and
    the first row is :math:`p_1 - 0`.
    """
    from ..model import Affine
    from ..terms import Term
    from ._base import _relabel

    m = knots.size - 1 if anchored else knots.size
    n_ax = len(names) // m
    base = np.zeros(len(names)) if base is None else base
    rows, labels = [], []
    for a in range(n_ax):
        P = model.params(names[a * m:(a + 1) * m])
        b = base[a * m:(a + 1) * m]
        if anchored:
            rows.append(P.rows(np.arange(1)) * sign + b[:1])
            labels.append(f"0->{names[a * m]}")
        rows.append((P.rows(np.arange(1, m)) - P.rows(np.arange(m - 1))) * sign + (b[1:] - b[:-1]))
        labels += [f"{names[a * m + j]}->[{j + 1}]" for j in range(m - 1)]
    res = _relabel(Affine.vstack(rows), labels, "drift")
    sigma = np.tile(drift * np.sqrt(np.diff(knots)), n_ax)
    return Term(label=label, item=None, residual=res, mode="soft", kind="equality", sigma=sigma,
                scaled_by_lam=False, units=units)


def random_walk_cost(base: np.ndarray, knots: np.ndarray, drift: float, anchored: bool = False) -> float:
    """The sum of squares of :func:`random_walk_term`'s rows at the totals ``base``
    (axis-major knot values; without the first knot when ``anchored``): the prior's share
    of the damped loop's objective."""
    m = knots.size - 1 if anchored else knots.size
    b = np.asarray(base, dtype=float).reshape(-1, m)
    if anchored:
        b = np.concatenate([np.zeros((b.shape[0], 1)), b], axis=1)
    r = np.diff(b, axis=1) / (drift * np.sqrt(np.diff(knots)))
    return float(np.sum(r**2))


# ------------------------------------------------------------- SO(3) helpers
def _skew(v: np.ndarray) -> np.ndarray:
    """``[v x]`` for an array of vectors (..., 3) -> (..., 3, 3)."""
    v = np.asarray(v)
    out = np.zeros(v.shape + (3,), dtype=np.result_type(v.dtype, float))
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    out[..., 0, 1], out[..., 0, 2] = -w, y
    out[..., 1, 0], out[..., 1, 2] = w, -x
    out[..., 2, 0], out[..., 2, 1] = -y, x
    return out


def _jacobian(phi: np.ndarray, sign: float) -> np.ndarray:
    """SO(3) Jacobian ``I + sign a [phi x] + b [phi x]^2`` (right: sign -1, left: +1)."""
    phi = np.asarray(phi, dtype=float)
    th2 = np.sum(phi**2, axis=-1)
    th = np.sqrt(th2)
    small = th < 1e-4
    safe = np.where(small, 1.0, th)
    # a = (1 - cos th) / th^2, b = (th - sin th) / th^3, with their series below 1e-4 rad
    a = np.where(small, 0.5 - th2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    b = np.where(small, 1.0 / 6.0 - th2 / 120.0, (safe - np.sin(safe)) / safe**3)
    # [phi x]^2 = phi phi^T - th^2 I: the entries written directly (no matrix products)
    out = b[..., None, None] * phi[..., :, None] * phi[..., None, :]
    d = 1.0 - b * th2
    for i in range(3):
        out[..., i, i] += d
    out += (sign * a)[..., None, None] * _skew(phi)
    return out


def right_jacobian(phi: np.ndarray) -> np.ndarray:
    r"""Right Jacobian of SO(3): :math:`\exp(\phi + d) = \exp(\phi)\exp(J_r(\phi) d) + O(d^2)`."""
    return _jacobian(phi, -1.0)


def left_jacobian(phi: np.ndarray) -> np.ndarray:
    r"""Left Jacobian of SO(3): :math:`\exp(\phi + d) = \exp(J_l(\phi) d)\exp(\phi) + O(d^2)`."""
    return _jacobian(phi, 1.0)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` along axis 1 of (n, 3, q) arrays (either may broadcast a trailing 1);
    written out by component: several times faster than ``np.cross(..., axis=1)``."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)


# ----------------------------------------------------- linearization point
@dataclass(frozen=True, eq=False)
class AttitudePoint:
    r"""Where the attitude is linearized: raw measurements and the current totals.

    Attributes
    ----------
    raw_gyro : ndarray (N, 3) or None
        The gyro rates as measured, rad/s (None for data whose attitude was given).
    raw_attitude : Rotation
        The attitude as given or integrated from the raw rates and the given initial
        attitude (body to navigation), length N.
    values : dict of str to float
        Total value of every attitude parameter at this point (their units).
    rates : ndarray (N, 3) or None
        The corrected rates :math:`\omega = (\hat\omega - b)/(1 + s)`, rad/s.
    scale : ndarray (3,)
        Current gyro scale-factor errors (dimensionless; zero when not modelled).
    damping : float
        Levenberg-Marquardt weight of the increments (0: none); see
        :meth:`AttitudeErrorModel.step_scale`.
    walk : ndarray (N, 3) or None
        Navigation-frame rotation vectors :math:`\psi_w(t_i)`, rad, applied after the
        integration (:class:`~bvpnav.error_models.AttitudeWalk`):
        ``attitude = exp([psi_w x]) C_integrated``; None when zero.
    """

    raw_gyro: np.ndarray | None
    raw_attitude: Rotation
    values: dict = field(default_factory=dict)
    rates: np.ndarray | None = None
    scale: np.ndarray = field(default_factory=lambda: np.zeros(3))
    damping: float = 0.0
    walk: np.ndarray | None = None


def at_point(data):
    """The data's :class:`AttitudePoint` (the zero point of the data as given when none)."""
    p = getattr(data, "attitude_point", None)
    if p is not None:
        return p
    _check_strapdown(data, "attitude error models")
    gyro = None if data.gyro is None else np.asarray(data.gyro, dtype=float)
    return AttitudePoint(raw_gyro=gyro, raw_attitude=data.attitude, rates=gyro)


def attitude_components(error_model) -> list:
    """The attitude components of an error model (single or composite), in order."""
    if error_model is None:
        return []
    comps = getattr(error_model, "components", (error_model,))
    return [c for c in comps if isinstance(c, AttitudeErrorModel)]


# ------------------------------------------------------------ propagation
def propagate(data, rate_cols: np.ndarray, initial_cols: np.ndarray) -> np.ndarray:
    r"""Navigation-frame attitude perturbation per unit parameter, shape (N, 3, q), rad.

    Parameters
    ----------
    data : ImuData
        Strapdown data at the linearization point (its attitude and step rotations).
    rate_cols : ndarray (N, 3, q)
        Change of the corrected body rate per unit parameter, rad/s per unit.
    initial_cols : ndarray (3, q)
        Navigation-frame rotation of the initial attitude per unit parameter, rad per unit.

    Notes
    -----
    The attitude is integrated as :math:`C_{k+1} = C_k \exp([\phi_k\times])` with
    :math:`\phi_k = \tfrac{h_k}{2}(\omega_k + \omega_{k+1}) + \tfrac{h_k^2}{12}\,
    \omega_k \times \omega_{k+1}` (:func:`bvpnav.attitude.step_rotation_vectors`).
    Writing a perturbed attitude as :math:`\exp([\psi_k\times]) C_k`, the exact first
    variation of that recursion is

    .. math:: \psi_1 = \psi_0, \qquad \psi_{k+1} = \psi_k + C_{k+1} J_r(\phi_k)\, \delta\phi_k,

    .. math:: \delta\phi_k = \tfrac{h_k}{2}(\delta\omega_k + \delta\omega_{k+1})
              + \tfrac{h_k^2}{12}(\delta\omega_k \times \omega_{k+1}
              + \omega_k \times \delta\omega_{k+1}),

    with :math:`J_r` the right Jacobian of SO(3). It is the derivative of the discrete
    integration itself, so the re-integrated attitude differs from the linearized one
    by :math:`O(\delta^2)` in the increment :math:`\delta`, at every step size; the
    integration's own error against the continuous attitude is :math:`O(h^2)`.
    Continuous limit: :math:`\dot\psi = C\,\delta\omega` (a gyro bias ``b`` gives
    :math:`\delta\omega = -b`, so :math:`\psi(t) = \psi_0 - \int_0^t C b\,ds`).

    With an attitude walk at the point (:class:`~bvpnav.error_models.AttitudeWalk`,
    attitude :math:`\exp([\psi_{w,k}\times]) C_k`), the recursion runs on the integrated
    :math:`C_k` and its result is rotated into the walked frame:
    :math:`\exp([\psi_{w}\times])\exp([\psi\times]) C = \exp([R_w\psi\times])
    \exp([\psi_{w}\times]) C` with :math:`R_w = \exp([\psi_w\times])`, exactly.
    """
    from ..attitude import step_rotation_vectors

    point = at_point(data)
    C = data.attitude.as_matrix()
    Rw = None
    if point.walk is not None:
        Rw = Rotation.from_rotvec(point.walk).as_matrix()
        C = np.swapaxes(Rw, 1, 2) @ C  # the integrated attitude, before the walk
    n, q = C.shape[0], rate_cols.shape[2]
    psi = np.empty((n, 3, q))
    psi[:] = initial_cols[None]
    if n > 1 and q:
        w = point.rates
        if w is None:
            if np.any(rate_cols):
                raise InputError("gyro error models need the gyro rates: build the data with "
                                 "bvpnav.ImuData.from_gyro")
        else:
            h = data.grid.h[:, None, None]
            phi = step_rotation_vectors(data.t, w)
            dw0, dw1 = rate_cols[:-1], rate_cols[1:]
            w0, w1 = w[:-1, :, None], w[1:, :, None]
            dphi = 0.5 * h * (dw0 + dw1) + (h**2 / 12.0) * (_cross(dw0, w1) + _cross(w0, dw1))
            T = C[1:] @ right_jacobian(phi)
            psi[1:] += np.cumsum(np.matmul(T, dphi), axis=0)
    return psi if Rw is None else np.matmul(Rw, psi)


def acceleration_columns(data, psi: np.ndarray) -> np.ndarray:
    r"""Navigation-frame acceleration change per unit parameter, (N, 3, q), m/s^2 per unit.

    Notes
    -----
    :math:`a = C f + g` with :math:`C \to \exp([\psi\times]) C` changes by
    :math:`\psi \times (C f)` to first order.
    """
    fn = data.attitude.apply(data.specific_force)
    return _cross(psi, fn[:, :, None])


# ------------------------------------------------------------- the base class
@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class AttitudeErrorModel(ErrorModel):
    """Base of the error models that act through the attitude (see module docstring).

    A subclass implements ``names(data)``, ``rate_columns(data)`` (N, 3, q),
    ``initial_columns(data)`` (3, q) and ``apply(values, parts)`` (how its totals correct
    the rates and the initial attitude). The parameters the convex problem sees are the
    increments about the totals of ``data.attitude_point``; ``report`` returns totals and
    priors act on totals, so iterating cannot walk away from them.
    """

    #: Parameter scale for the Levenberg-Marquardt damping, in the model's units.
    default_step_scale: ClassVar[float] = 1.0
    #: The axes a model's ``axes=`` selects from, and what they are called in messages.
    AXES: ClassVar[tuple[str, ...]] = ("x", "y", "z")
    axis_kind: ClassVar[str] = "body"

    def _sel(self) -> tuple[int, ...]:
        """Indices of the selected axes in :attr:`AXES`."""
        return self._select_axes(self.AXES, self.axis_kind)

    def rate_columns(self, data) -> np.ndarray:
        """Change of the corrected body rates per unit parameter, (N, 3, q), rad/s per unit."""
        q = len(self.names(data))
        return np.zeros((data.n, 3, q))

    def initial_columns(self, data) -> np.ndarray:
        """Navigation-frame rotation of the initial attitude per unit parameter, (3, q)."""
        return np.zeros((3, len(self.names(data))))

    def apply(self, values: np.ndarray, parts: dict, data) -> None:
        """Fold this model's totals into ``parts`` (keys ``bias`` (N, 3) rad/s, ``scale`` (3,),
        ``initial`` Rotation, ``walk`` (N, 3) navigation-frame rotation vectors, rad, applied
        after the integration) used to re-integrate the attitude."""
        raise NotImplementedError

    def columns(self, data) -> np.ndarray:
        psi = propagate(data, self.rate_columns(data), self.initial_columns(data))
        return acceleration_columns(data, psi)

    def rate_change(self, data, d: np.ndarray) -> np.ndarray:
        """Change of the corrected body rates for the increments ``d``, (N, 3), rad/s."""
        return self.rate_columns(data) @ d

    def direct_change(self, data, d: np.ndarray) -> np.ndarray:
        """Navigation-frame attitude change for the increments ``d`` that does not go through
        the integration (:class:`~bvpnav.error_models.AttitudeWalk`), (N, 3), rad; zero here."""
        return np.zeros((data.n, 3))

    def base(self, data) -> np.ndarray:
        """Totals of this model's parameters at the data's linearization point (0 when none)."""
        vals = at_point(data).values
        return np.array([float(vals.get(n, 0.0)) for n in self.names(data)])

    def report(self, l, model):
        names = self.names(model.data)
        return _series(self.base(model.data) + np.asarray(l, dtype=float), names, self.units)

    def physical_rows(self, model, value):
        names = self.names(model.data)
        v = _per_param(value, len(names), f"{type(self).__name__}: value")
        return model.params(names) + (self.base(model.data) - v)

    def prior_sigma(self, data) -> np.ndarray:
        """Prior standard deviation per parameter (inf where there is none)."""
        q = len(self.names(data))
        return np.full(q, np.inf) if self.sigma is None else _per_param(self.sigma, q, type(self).__name__)

    def prior_values(self, data) -> np.ndarray:
        """Prior value of each total (the model's units; 0 unless ``prior=`` says)."""
        q = len(self.names(data))
        if self.prior is None:
            return np.zeros(q)
        return _per_param(self.prior, q, f"{type(self).__name__}: prior")

    def prior_cost(self, data) -> float:
        r"""This model's priors at zero increments (the totals of ``data``'s point): its share
        of the nonlinear objective, :math:`\sum_k ((x_k - p_k)/\sigma_k)^2` plus
        :meth:`extra_prior_cost`."""
        sig = self.prior_sigma(data)
        ok = np.isfinite(sig)
        r = (self.base(data) - self.prior_values(data))[ok] / sig[ok]
        return float(r @ r) + self.extra_prior_cost(data)

    def extra_prior_cost(self, data) -> float:
        """The :meth:`extra_terms` at zero increments; none by default."""
        return 0.0

    def step_scale(self, data) -> np.ndarray:
        """Scale of each parameter for the damping: its prior sigma, else the default."""
        s = self.prior_sigma(data)
        return np.where(np.isfinite(s), s, self.default_step_scale)

    def terms(self, model) -> list:
        from ..terms import Term
        from ._base import _relabel

        data = model.data
        names = self.names(data)
        tag = type(self).__name__ + "[" + ", ".join(names[:4]) + (", ..." if len(names) > 4 else "") + "]"
        out = []
        sig = self.prior_sigma(data)
        keep = np.flatnonzero(np.isfinite(sig))
        if keep.size:
            rows = self.physical_rows(model, self.prior_values(data)).rows(keep)
            out.append(Term(label=f"prior {tag}", item=None,
                            residual=_relabel(rows, [names[k] for k in keep], "prior"), mode="soft",
                            kind="equality", sigma=sig[keep], scaled_by_lam=False, units=self.units))
        if self.bounds is not None:
            raise InputError(f"{type(self).__name__}: bounds are not supported on attitude parameters; "
                             "give sigma= (a prior on the total value)")
        out.extend(self.extra_terms(model))
        damp = at_point(data).damping
        if damp > 0:
            rows = model.params(names)
            out.append(Term(label=f"damping {tag}", item=None, residual=_relabel(rows, names, "step"),
                            mode="soft", kind="equality", sigma=self.step_scale(data) / np.sqrt(damp),
                            scaled_by_lam=False, units=self.units))
        return out

    def extra_terms(self, model) -> list:
        """Further prior terms (e.g. a random walk's increments); none by default."""
        return []

    @staticmethod
    def example_data():
        """Strapdown data on which every attitude parameter is determined (contract checks).

        20 s at 10 Hz of a body turning about all three axes (rates up to 0.4 rad/s) with
        specific force varying on every axis; the attitude integrated from the rates.
        """
        from ..imu import ImuData

        t = np.linspace(0.0, 20.0, 201)
        w = np.column_stack([0.3 * np.sin(0.5 * t), 0.2 * np.cos(0.3 * t), 0.4 * np.sin(0.2 * t) + 0.1])
        f = np.column_stack([np.sin(t), 0.5 * np.cos(2.0 * t), 9.8 + 0.3 * np.sin(t)])
        # synthetic: the specific force does not follow the rotation (a mean acceleration of 0.7 g,
        # which the frame check would report); the contract needs only that it varies on every axis
        return ImuData.from_gyro(t, f, w, initial_attitude=Rotation.from_euler("ZYX", [0.3, 0.1, -0.2]),
                                 checks=False)


def _check_strapdown(data, who: str) -> None:
    if not getattr(data, "is_strapdown", False):
        raise InputError(f"{who}: needs strapdown data (specific force with an attitude, e.g. "
                         "bvpnav.ImuData.from_gyro); navigation-frame accelerations have no attitude")


def _check_strapdown_gyro(data, who: str) -> None:
    _check_strapdown(data, who)
    if at_point(data).raw_gyro is None:
        raise InputError(f"{who}: needs the gyro rates; build the data with bvpnav.ImuData.from_gyro "
                         "(this data's attitude was given, not integrated)")


def reintegrate(data, error_model, values: dict, damping: float = 0.0):
    r"""The data re-integrated with the attitude totals ``values`` (name -> total).

    Parameters
    ----------
    data : ImuData
        Strapdown data (its ``attitude_point`` if it has one, else itself, is the raw
        measurement).
    error_model : ErrorModel
        The error model whose attitude components interpret ``values``.
    values : dict of str to float
        Totals of the attitude parameters (their units).
    damping : float
        Damping weight recorded in the point (see :class:`AttitudePoint`).

    Returns
    -------
    ImuData
        With the corrected attitude, ``acc = C f + g`` and ``attitude_point`` set.

    Notes
    -----
    The corrected rates are :math:`\omega = (\hat\omega - b(t))/(1 + s)` and the
    initial attitude :math:`C_1 = R\,\hat C_1` with ``R`` from
    :class:`~bvpnav.error_models.AttitudeError`; then
    :math:`C_{k+1} = C_k\exp([\phi_k\times])` as in :func:`bvpnav.attitude.integrate_gyro`;
    last, an attitude walk (:class:`~bvpnav.error_models.AttitudeWalk`) rotates each
    :math:`C_k` by :math:`\exp([\psi_w(t_k)\times])`.
    For data whose attitude was given (no gyro), only the initial correction applies:
    :math:`C_k = R\,\hat C_k`.
    """
    from ..attitude import integrate_gyro
    from ..imu import ImuData

    point = at_point(data)
    comps = attitude_components(error_model)
    parts: dict = {"bias": np.zeros((data.n, 3)), "scale": np.zeros(3), "initial": Rotation.identity(),
                   "walk": np.zeros((data.n, 3))}
    for c in comps:
        names = c.names(data)
        c.apply(np.array([float(values.get(n, 0.0)) for n in names]), parts, data)
    raw0 = point.raw_attitude[0]
    start = parts["initial"] * raw0
    if point.raw_gyro is not None:
        rates = (point.raw_gyro - parts["bias"]) / (1.0 + parts["scale"])
        rot = integrate_gyro(data.t, rates, start)
    else:
        rates = None
        rot = parts["initial"] * point.raw_attitude
    walk = parts["walk"] if np.any(parts["walk"]) else None
    if walk is not None:
        rot = Rotation.from_rotvec(walk) * rot
    out = ImuData(data.t, specific_force=data.specific_force, attitude=rot, gravity=data.gravity,
                  axes=data.axes, time_origin=data.time_origin, checks=False)
    out.checks = dict(data.checks)  # the measured data's checks, not re-run at each iterate
    out.gyro = data.gyro
    out.attitude_point = AttitudePoint(raw_gyro=point.raw_gyro, raw_attitude=point.raw_attitude,
                                       values={k: float(v) for k, v in values.items()}, rates=rates,
                                       scale=np.array(parts["scale"], dtype=float), damping=float(damping),
                                       walk=walk)
    return out


def with_damping(data, damping: float):
    """A shallow copy of ``data`` whose point carries another damping weight (the same
    re-integrated attitude, accelerations and rates)."""
    import copy

    out = copy.copy(data)
    out.attitude_point = _replace(at_point(data), damping=float(damping))
    return out
