r"""A land vehicle drives forward: its body-frame forward speed is at least a bound (an inequality)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from bvpnav.errors import InputError
from bvpnav.items import Item
from bvpnav.model import Affine

from ._common import finite
from .non_holonomic import (
    NODES,
    body_instants,
    check_body_data,
    intervals,
    lever_arm,
    point_rows,
    positive_rate,
    vehicle_example_model,
    without_rounding_noise,
)

__all__ = ["ForwardMotion"]

_BODY = ("x", "y", "z")


@dataclass(frozen=True, kw_only=True, eq=False)
class ForwardMotion(Item):
    r"""The body-frame forward speed of a point of the vehicle is at least ``min_speed``
    (and at most ``max_speed`` when given).

    A car does not reverse on an ordinary drive: its speed along its own forward axis is
    never below zero (or below a known minimum while it is known to move). The convex form
    takes this as it is, an inequality, where a Kalman smoother can only take a tuned
    pseudo-measurement. With ``max_speed`` too the speed stays in a band.

    Parameters
    ----------
    min_speed : float
        Lower bound on the forward speed, m/s (default 0).
    max_speed : float, optional
        Upper bound, m/s (> ``min_speed``); default none.
    axis : {"x", "y", "z"}
        The body axis that points forward (default ``"x"``).
    lever : array_like (3,) or ``"estimated"``
        The point, m, in body axes from the IMU; default the IMU itself. ``"estimated"``:
        the point of :class:`~bvpnav.error_models.NhcLever` in the error model (as for
        :class:`~bvpnav.constraints.NonHolonomic`).
    t : (float, float) or list of them, optional
        Interval(s) in s where it holds; default the whole recording.
    rate : float, ``"nodes"`` or None
        Rate of the rows, Hz (default 10; ``None`` for every sample; ``"nodes"``: at the coarse
        mesh's nodes, refused without one, as :class:`~bvpnav.constraints.NonHolonomic`'s).
    sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; in m/s. The default is hard (the bound holds); with
        ``sigma`` a violation is penalized (``lam sum (pos(g)/sigma)^2``); ``tol`` loosens the
        bounds by ``tol``.

    Notes
    -----
    Inequality rows at the chosen samples :math:`t_k`, with the forward speed
    :math:`s_k = e_x^T (C_k^T v_n(t_k) + \omega_k \times \ell)`
    (:meth:`bvpnav.NavModel.body_velocity`):

    .. math:: g_k = u_{min} - s_k \le 0, \qquad g'_k = s_k - u_{max} \le 0 \text{ (with a maximum)},

    first every lower-bound row, then every upper-bound row.

    Examples
    --------
    >>> from bvpnav.constraints import ForwardMotion
    >>> fm = ForwardMotion()
    >>> fm.mode, fm.kind, fm.min_speed
    ('hard', 'inequality', 0.0)
    >>> ForwardMotion(min_speed=2.0, max_speed=40.0, t=(10.0, 50.0)).math()
    '2 m/s <= e_x^T (C^T v_n(t_k) + omega x lever) <= 40 m/s'
    """

    min_speed: Any = 0.0
    max_speed: Any = None
    axis: str = "x"
    lever: Any = (0.0, 0.0, 0.0)
    t: Any = None
    rate: Any = 10.0
    units = "m/s"
    kind = "inequality"
    #: Body-frame rows (see :attr:`bvpnav.constraints.NonHolonomic.body_frame`).
    body_frame: ClassVar[bool] = True

    def validate(self) -> None:
        label = self.label
        if self.axes is not None:
            raise InputError(f"{label}: axes={list(self.axes)}; the forward axis is given by axis= (one body "
                             "axis, default 'x')")
        if self.axis not in _BODY:
            raise InputError(f"{label}: axis={self.axis!r}; give the body axis that points forward, one of "
                             f"{list(_BODY)}")
        lo = finite(self.min_speed, label, "min_speed")
        if lo.size != 1:
            raise InputError(f"{label}: min_speed={self.min_speed!r}; give one speed in m/s")
        object.__setattr__(self, "min_speed", float(lo.ravel()[0]))
        if self.max_speed is not None:
            hi = finite(self.max_speed, label, "max_speed")
            if hi.size != 1 or not float(hi.ravel()[0]) > self.min_speed:
                raise InputError(f"{label}: max_speed={self.max_speed!r}; give one speed in m/s above "
                                 f"min_speed={self.min_speed:g} m/s")
            object.__setattr__(self, "max_speed", float(hi.ravel()[0]))
        object.__setattr__(self, "lever", lever_arm(self.lever, label))
        object.__setattr__(self, "t", intervals(self.t, label))
        object.__setattr__(self, "rate", positive_rate(self.rate, label))

    @property
    def reads_error_model(self) -> bool:
        """With ``lever="estimated"`` the rows read the :class:`~bvpnav.error_models.NhcLever`:
        the contract check then solves with it."""
        return isinstance(self.lever, str)

    @property
    def rows_at_nodes(self) -> bool:
        """``rate="nodes"``: the rows sit at the coarse mesh's nodes and ask it for none
        (:func:`bvpnav.mesh.item_times`)."""
        return self.rate == NODES

    def instants(self, model) -> np.ndarray:
        """The rows' times (s): the samples in the intervals at :attr:`rate` (with ``"nodes"``
        the mesh's nodes in them)."""
        return body_instants(model, self.t, self.rate, self.identify())

    def row_layout(self, m: int) -> tuple[int, int]:
        """Every row its own instant (a scalar sigma or tol, or one per row)."""
        return m, 1

    @classmethod
    def example(cls) -> ForwardMotion:
        """A valid instance for :meth:`example_model`."""
        return cls(min_speed=0.5, max_speed=30.0, lever=(-0.5, 0.0, 0.0), t=(1.0, 9.0), rate=5.0)

    @classmethod
    def example_model(cls):
        """The car-like strapdown data of :meth:`bvpnav.constraints.NonHolonomic.example_model`."""
        return vehicle_example_model()

    def compile(self, model):
        who = self.identify()
        check_body_data(model, who)
        s = point_rows(model, self.instants(model), self.axis, self.lever, who)
        if self.rows_at_nodes:
            s = without_rounding_noise(s)
        low = Affine(-s.A, self.min_speed - s.c, tuple(f"{lab} >= {self.min_speed:g}" for lab in s.labels))
        if self.max_speed is None:
            return low
        high = Affine(s.A, s.c - self.max_speed, tuple(f"{lab} <= {self.max_speed:g}" for lab in s.labels))
        return Affine.vstack([low, high])

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"u_{min} - e_x^T (C_k^T v_n(t_k) + \omega_k \times \ell) \leq 0"

    def math(self) -> str:
        hi = "" if self.max_speed is None else f" <= {self.max_speed:g} m/s"
        return f"{self.min_speed:g} m/s <= e_{self.axis}^T (C^T v_n(t_k) + omega x lever){hi}"
