r"""Stances seen by the gyro: the body does not turn, so the gyro reads its own error."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bvpnav.errors import InputError
from bvpnav.items import Item

from ._common import interval

__all__ = ["ZeroAngularRate"]

_BODY = ("x", "y", "z")


@dataclass(frozen=True, kw_only=True, eq=False)
class ZeroAngularRate(Item):
    r"""The body does not rotate during ``t = (t0, t1)``: the corrected gyro rate is zero.

    During a stance of a foot (or a stop of a vehicle) the gyro reads its bias plus noise;
    this item says so, which is what makes a gyro bias observable on foot-mounted data. It
    acts on the gyro error models' parameters (:class:`~bvpnav.error_models.GyroBias`,
    :class:`~bvpnav.error_models.GyroScaleFactor`) through
    :meth:`bvpnav.NavModel.body_rate`, and needs strapdown data with gyro rates
    (:meth:`bvpnav.ImuData.from_gyro`) and such a model.

    Parameters
    ----------
    t : (float, float)
        The interval ``(t0, t1)`` in s, ``t0 < t1``, inside the window.
    axes : sequence of str, optional
        Body axes among ``"x", "y", "z"`` (default all three).
    sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` and ``tol`` in rad/s, one value or one
        per body axis: the gyro's white noise per sample (its noise density times the
        square root of the rate) is the natural ``sigma`` where the body is truly still
        (a foot's stance rolls: see :func:`bvpnav.detect.zero_velocity_items`'
        ``angular_rate="spread"``). Prefer it to hard rows: for a constant bias every sample of a
        stance gives the same row, and hundreds of identical hard rows make the system's
        conditioning estimate (and so the verification) fail where soft rows do not.

    Notes
    -----
    One row per sample inside the interval (ends included when they are samples), per body axis:
    :math:`\rho_k = \omega(t_k) = \hat\omega(t_k) - b(t_k)` with the rates corrected by the
    current totals of the gyro error models and linear in their increments (the attitude
    loop re-linearizes). Noise-free stances recover a constant gyro bias exactly.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav import ImuData, NavigationProblem, error_models
    >>> from bvpnav.constraints import Position, ZeroAngularRate
    >>> t = np.linspace(0.0, 4.0, 401)
    >>> bias = np.array([0.01, -0.02, 0.005])                  # rad/s: the gyro reads only this
    >>> f = np.tile([0.0, 0.0, 9.80665], (t.size, 1))          # at rest, z up
    >>> data = ImuData.from_gyro(t, f, np.tile(bias, (t.size, 1)))
    >>> prob = NavigationProblem(data, error_model=error_models.GyroBias())
    >>> _ = prob.add(ZeroAngularRate(t=(0.0, 4.0), sigma=1e-5), Position(t=[0.0, 4.0], value=0.0))
    >>> sol = prob.solve(solver="direct")
    >>> np.round(sol.error_params.to_numpy(), 9).tolist()
    [0.01, -0.02, 0.005]
    """

    t: Any
    units = "rad/s"
    needs_error_model = True
    #: The body does not turn in ``t``: the solve's plausibility check compares a gyro bias
    #: estimate with the mean gyro reading there.
    zero_rate = True

    def validate(self) -> None:
        label = self.label
        try:
            t0, t1 = self.t
        except (TypeError, ValueError):
            raise InputError(f"{label}: t={self.t!r}; give the interval as t=(t0, t1) in s") from None
        object.__setattr__(self, "t", interval(t0, t1, label))
        if self.axes is not None:
            axes = (self.axes,) if isinstance(self.axes, str) else tuple(self.axes)
            bad = [a for a in axes if a not in _BODY]
            if bad or not axes:
                raise InputError(f"{label}: axes={self.axes!r}; give body axes among {list(_BODY)}")
            object.__setattr__(self, "axes", axes)

    def instants(self, grid) -> np.ndarray:
        """Instants (s): the samples inside ``[t0, t1]`` (the gyro measures at its samples; a rate
        interpolated at an end between samples would mix in the motion outside)."""
        t0, t1 = self.t
        tol = 1e-9 * max(1.0, abs(t0), abs(t1))
        inside = grid.t[(grid.t >= t0 - tol) & (grid.t <= t1 + tol)]
        if inside.size == 0:
            raise InputError(f"{self.identify()}: no sample lies in [{t0:g}, {t1:g}] s; widen the interval "
                             "or drop the item")
        return inside

    def row_layout(self, m: int) -> tuple[int, int]:
        """``(instants, body axes)`` of the ``m`` rows (time-major, then body axis), so that
        ``sigma`` may be given per body axis (3 values) or per instant and axis."""
        a = len(_BODY) if self.axes is None else len(self.axes)
        return (m // a, a) if m % a == 0 else (m, 1)

    @classmethod
    def example(cls) -> ZeroAngularRate:
        """A valid instance for the window of :meth:`example_model`."""
        return cls(t=(0.0, 2.0))

    @classmethod
    def example_model(cls):
        """Strapdown data on [0, 10] s (101 samples) at rest for the first 2 s with a constant
        gyro bias, turning afterwards, and a :class:`~bvpnav.error_models.GyroBias`: the model
        the contract check (:func:`bvpnav.testing.check_item`) compiles :meth:`example` for."""
        from bvpnav import error_models
        from bvpnav.imu import ImuData
        from bvpnav.model import NavModel

        t = np.linspace(0.0, 10.0, 101)
        moving = t > 2.0
        turn = np.column_stack([0.2 * np.sin(t), 0.1 * np.cos(t), 0.3 * np.sin(0.5 * t)])
        w = np.where(moving[:, None], turn, 0.0) + [0.002, -0.001, 0.003]
        f = np.column_stack([0.5 * np.sin(t) * moving, 0.2 * np.cos(t) * moving, np.full(t.size, 9.80665)])
        return NavModel(ImuData.from_gyro(t, f, w), error_models.GyroBias())

    def compile(self, model):
        comps = getattr(model.error_model, "components", (model.error_model,))
        if not any(c is not None and hasattr(c, "rate_columns") for c in comps):
            raise InputError(f"{self.identify()}: no gyro error model to act on (the rows would be "
                             "constants); add error_models.GyroBias() (or GyroScaleFactor) to the problem")
        return model.body_rate(self.instants(model.grid), self.axes, f"{self.identify()}(t=...)")

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"\hat\omega(t_k) - b(t_k) = 0"

    def math(self) -> str:
        return f"omega_hat(t_k) - b_gyro(t_k) = 0 for t_k in [{self.t[0]:g}, {self.t[1]:g}] s"
