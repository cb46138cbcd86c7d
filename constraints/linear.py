"""Any linear combination of positions or velocities at given instants (escape hatch)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from bvpnav.errors import InputError
from bvpnav.items import Item
from bvpnav.model import Affine

from ._common import finite, times

__all__ = ["Linear"]


@dataclass(frozen=True, kw_only=True, eq=False)
class Linear(Item):
    r"""User rows ``sum_k sum_a C[i, k, a] q_a(t_k) = value_i``.

    Parameters
    ----------
    t : array_like of float, shape (K,)
        Instants in s that the rows refer to.
    coef : array_like, shape (m, K, n_axes), (m, K) or (K,)
        Coefficients ``C``; (m, K) or (K,) when the item has one axis. Units: value
        units per quantity unit.
    value : float or array_like, shape (m,)
        Right-hand sides ``e`` in ``row_units``.
    quantity : {"position", "velocity"}
        What ``q`` is: position (m) or velocity (m/s).
    row_units : str
        Units of the rows (of ``value``, ``sigma`` and ``tol``), default ``"m"``; give
        e.g. ``"m/s"`` for velocity rows. They are the item's :attr:`units`: the
        ``units`` column of ``solution.items`` and the units in messages.
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` and ``tol`` in ``row_units``.

    Notes
    -----
    The residual is :math:`\rho_i = \sum_{k,a} C_{ika}\, q_a(t_k) - e_i`, i.e. the
    2011 paper's general ``D r = e`` row by row.

    Examples
    --------
    The displacement between 0 s and 2 s, :math:`r(2) - r(0) = 3` m, as one user row:

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
    >>> from bvpnav.constraints import Linear, Position
    >>> prob = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=0.0),
    ...                                           Linear(t=[0.0, 2.0], coef=[[-1.0, 1.0]], value=3.0))
    >>> print(f"v(0) = {prob.solve(solver='direct').velocity('x')[0]:.3f} m/s")
    v(0) = 1.000 m/s
    """

    t: Any
    coef: Any
    value: Any = 0.0
    quantity: str = "position"
    row_units: str = "m"

    @property
    def units(self) -> str:
        """The rows' units (``row_units``), shown in ``solution.items["units"]`` and messages."""
        return self.row_units

    def validate(self) -> None:
        t = times(self.t, self.label)
        c = finite(self.coef, self.label, "coef")
        if c.ndim == 1:
            c = c[None, :, None]
        elif c.ndim == 2:
            c = c[:, :, None]
        if c.ndim != 3 or c.shape[1] != t.size:
            raise InputError(
                f"{self.label}: coef shape {np.shape(self.coef)} does not match {t.size} instant(s); "
                "expected (m, K, n_axes), (m, K) or (K,)"
            )
        if self.quantity not in ("position", "velocity"):
            raise InputError(f"{self.label}: quantity={self.quantity!r}; use 'position' or 'velocity'")
        if not isinstance(self.row_units, str):
            raise InputError(f"{self.label}: row_units={self.row_units!r}; give the rows' units as a "
                             'string, e.g. row_units = "m/s"')
        v = finite(self.value, self.label)
        if v.size not in (1, c.shape[0]):
            raise InputError(f"{self.label}: {v.size} values for {c.shape[0]} rows")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "coef", c)
        object.__setattr__(self, "value", v)

    @classmethod
    def example(cls) -> Linear:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(t=[2.0, 8.0], coef=[[1.0, -1.0]], value=0.5, axes="y")

    def compile(self, model):
        ax = model.axes_of(self.axes, self.identify())
        if self.coef.shape[2] != len(ax):
            raise InputError(
                f"{self.identify()}: coef has {self.coef.shape[2]} axis column(s) but the item applies "
                f"to {len(ax)} axis(es) {[model.axes[a] for a in ax]}; set axes= to match"
            )
        what = f"{self.identify()}(t=...)"
        q = model.position if self.quantity == "position" else model.velocity
        base = q(self.t, self.axes, what)  # rows k * nax + a
        C = sp.csr_matrix(self.coef.reshape(self.coef.shape[0], -1))
        rhs = np.broadcast_to(self.value.ravel(), (C.shape[0],))
        return Affine(C @ base.A, C @ base.c - rhs)

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"\sum_j C_{ij}\, q(t_j) - e_i = 0"

    def math(self) -> str:
        return f"sum_k C_ik {self.quantity}(t_k) - e_i = 0 ({self.coef.shape[0]} row(s))"
