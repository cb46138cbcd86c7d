r"""A known straight-line distance between the places at two instants (a measured walkway)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bvpnav.errors import InputError
from bvpnav.items import Item, Linearizable

from ._common import finite
from .same_position import _pairs

__all__ = ["KnownDistance"]


@dataclass(frozen=True, kw_only=True, eq=False)
class KnownDistance(Linearizable, Item):
    r"""The straight-line distance between the positions at ``t = (ta, tb)`` is ``distance``.

    A walkway of measured length walked from end to end, two survey marks, a lap of known
    length on a straight. The distance is not linear in the positions; the item is
    linearized along the direction of the estimated displacement and re-linearized by the
    sequential loop (:mod:`bvpnav.solve.sequential`), or along a ``direction`` you give.

    Parameters
    ----------
    t : (float, float)
        The two instants in s, inside the window.
    distance : float
        The distance, m (> 0).
    direction : array_like, optional
        Unit vector (one entry per axis of ``axes``) along which the distance is measured;
        default: linearized about the estimate.
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` and ``tol`` in m. ``axes=("x", "y")`` for
        a horizontal distance.

    Notes
    -----
    Linearized about a displacement :math:`d_0 = r(t_b) - r(t_a)` of the estimate, with
    :math:`u = d_0 / \lVert d_0 \rVert`: :math:`\rho = u^T (r(t_b) - r(t_a)) - D`. At the
    converged point :math:`u^T d = \lVert d \rVert`, so the residual is the distance error
    itself, with an error of second order in the angle between :math:`d` and :math:`u`.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.constraints import KnownDistance
    >>> KnownDistance(t=(2.0, 12.0), distance=10.0, direction=(1.0, 0.0), axes=("x", "y")).math()
    'u^T (r(t_b) - r(t_a)) - 10 m = 0'
    """

    t: Any
    distance: float
    direction: Any = None
    units = "m"

    def validate(self) -> None:
        label = self.label
        pairs = _pairs(self.t, label)
        if pairs.shape[0] != 1:
            raise InputError(f"{label}: t={self.t!r}; give one pair of instants t=(ta, tb) in s")
        object.__setattr__(self, "t", pairs[0])
        d = finite(self.distance, label, "distance")
        if d.size != 1 or not float(d.ravel()[0]) > 0:
            raise InputError(f"{label}: distance={self.distance!r}; give one distance > 0 in m")
        object.__setattr__(self, "distance", float(d.ravel()[0]))
        if self.direction is not None:
            u = finite(self.direction, label, "direction").ravel()
            n = float(np.linalg.norm(u))
            if not n > 0:
                raise InputError(f"{label}: direction={self.direction!r} has length 0; give a unit vector")
            if abs(n - 1.0) > 1e-6:
                raise InputError(f"{label}: direction={self.direction!r} has length {n:.6g}, not 1; give a "
                                 "unit vector (or leave it out: it is then taken from the estimate)")
            object.__setattr__(self, "direction", u / n)

    @property
    def needs_linearization(self) -> bool:
        """True while the item has no direction (the sequential loop supplies one)."""
        return self.direction is None

    @classmethod
    def example(cls) -> KnownDistance:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(t=(1.0, 9.0), distance=3.0)

    def linearized(self, t, positions) -> KnownDistance:
        """A copy linearized along the estimated displacement between the two instants.

        Parameters
        ----------
        t : array_like (K,)
            Times, s (e.g. a solution's sample times).
        positions : array_like (K, n_axes) or pandas.DataFrame
            Estimated positions, m, on ``axes`` (a DataFrame by column name, e.g.
            ``solution.trajectory``).
        """
        t = np.asarray(t, dtype=float)
        if isinstance(positions, pd.DataFrame):
            cols = list(self.axes) if self.axes is not None else [c for c in positions.columns
                                                                  if c in ("x", "y", "z")]
            missing = [a for a in cols if a not in positions.columns]
            if missing:
                raise InputError(f"{self.label}: the estimate has no column(s) {missing}")
            positions = positions[cols].to_numpy()
        p = np.asarray(positions, dtype=float).reshape(t.size, -1)
        ends = np.array([[np.interp(tk, t, p[:, j]) for j in range(p.shape[1])] for tk in self.t])
        d = ends[1] - ends[0]
        n = float(np.linalg.norm(d))
        if not n > 1e-9 * max(1.0, self.distance):
            raise InputError(f"{self.label}: the estimate puts both instants at one place, so the distance "
                             "has no direction yet; give direction= (a unit vector)")
        return dataclasses.replace(self, direction=d / n)

    def compile(self, model):
        what = f"{self.identify()}(t=...)"
        if self.direction is None:
            raise InputError(f"{self.identify()}: not linearized yet; solve it (the sequential loop "
                             "linearizes it) or give direction=")
        ax = model.axes_of(self.axes, self.identify())
        if self.direction.size != len(ax):
            raise InputError(f"{self.identify()}: direction has {self.direction.size} entries for "
                             f"{len(ax)} axes; give one per axis of axes=")
        d = model.position([self.t[1]], self.axes, what) - model.position([self.t[0]], self.axes, what)
        import scipy.sparse as sp

        from bvpnav.model import Affine

        u = sp.csr_matrix(self.direction.reshape(1, -1))
        return Affine(u @ d.A, u @ d.c - self.distance, (f"distance(t={self.t[0]:.6g}..{self.t[1]:.6g})",))

    def continuation_sigma(self) -> float | None:
        """None: iterate in its own mode (a distance does not need a soft start)."""
        return None

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        return r"u^T (r(t_b) - r(t_a)) - D = 0"

    def math(self) -> str:
        return f"u^T (r(t_b) - r(t_a)) - {self.distance:g} m = 0"
