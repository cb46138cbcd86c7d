"""The solution object: tidy, time-indexed results with their provenance."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from .errors import InputError

__all__ = ["Solution"]


@dataclass(eq=False)
class Solution:
    """A verified trajectory and everything needed to judge it.

    Attributes
    ----------
    trajectory : pandas.DataFrame
        Index ``t`` (s). Columns ``x``, ``y``, ``z`` (positions, m) and ``vx``, ``vy``,
        ``vz`` (velocities, m/s) for the axes present (named after the data's axes).
    residuals : pandas.DataFrame
        Index ``t`` (s). Columns ``w_<axis>``: the acceleration correction
        ``a_c - a_hat - G l`` in m/s^2 that the estimate implies at each sample.
    items : pandas.DataFrame
        One row per item: name, class, mode, rows, units, rms and max absolute
        residual (item units; for inequalities the violation ``max(g, 0)``), and the
        rms of the dual (hard, band and inequality items).
    item_residuals : dict of str to ndarray
        Residual of every item row, in the item's units.
    lam : float
        The regularization weight used.
    lam_rule : str
        ``"fixed"`` or the name of the rule that chose it.
    error_params : pandas.Series
        Error-model estimates by parameter name (units in the error model's docs);
        empty without an error model.
    stats : dict
        Solver, status, iterations, compile/setup/solve times (s), options in force,
        accuracy preset, verification measures and the attempts made.
    x : ndarray
        The stacked solution vector (see :class:`bvpnav.model.NavModel`).
    """

    trajectory: pd.DataFrame
    residuals: pd.DataFrame
    items: pd.DataFrame
    item_residuals: dict[str, np.ndarray]
    lam: float
    lam_rule: str
    error_params: pd.Series
    stats: dict[str, Any]
    x: np.ndarray
    warnings: list[str] = field(default_factory=list)
    curve: Any = None

    def _axis(self, axis, what: str) -> str | None:
        """``axis`` itself when it is one of the solution's axes (or None), else
        :class:`~bvpnav.errors.InputError` listing them."""
        if axis is None or (isinstance(axis, str) and axis in self._pos_cols):
            return axis
        raise InputError(f"{what}({axis!r}): the solution has no axis {axis!r}; its axes are "
                         f"{self._pos_cols} (or call {what}() for all of them)")

    def position(self, axis: str | None = None) -> np.ndarray:
        """Nodal positions (m), shape (N,) for one axis or (N, d) for all.

        Raises
        ------
        InputError
            For an axis the solution does not have (the message lists its axes).
        """
        axis = self._axis(axis, "position")
        cols = self._pos_cols if axis is None else [axis]
        out = self.trajectory[cols].to_numpy()
        return out[:, 0] if axis is not None else out

    def velocity(self, axis: str | None = None) -> np.ndarray:
        """Nodal velocities (m/s), shape (N,) for one axis or (N, d) for all.

        Raises
        ------
        InputError
            For an axis the solution does not have (the message lists its axes).
        """
        axis = self._axis(axis, "velocity")
        cols = ["v" + c for c in self._pos_cols] if axis is None else ["v" + axis]
        out = self.trajectory[cols].to_numpy()
        return out[:, 0] if axis is not None else out

    @property
    def _pos_cols(self) -> list[str]:
        return [c for c in self.trajectory.columns if not c.startswith("v")]

    @property
    def t(self) -> np.ndarray:
        """Sample times, s."""
        return self.trajectory.index.to_numpy()

    def rms_error(self, truth: np.ndarray) -> float:
        """RMS position error (m) against true positions of shape (N,) or (N, d)."""
        shape = self.position().shape
        try:
            truth = np.asarray(truth, dtype=float).reshape(shape)
        except (TypeError, ValueError) as exc:
            raise InputError(f"rms_error(truth): truth of shape {np.shape(truth)} does not match the "
                             f"solution's positions {shape} (N samples x axes {self._pos_cols}); give "
                             "true positions in m at the sample times") from exc
        return float(np.sqrt(np.mean((self.position() - truth) ** 2)))

    def __repr__(self) -> str:
        s = self.stats
        return (
            f"Solution(N={len(self.trajectory)}, axes={self._pos_cols}, lam={self.lam:g} "
            f"({self.lam_rule}), solver={s.get('solver')}, status={s.get('status')}, "
            f"verified={s.get('verified')})"
        )
