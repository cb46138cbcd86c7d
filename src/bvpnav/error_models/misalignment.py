"""Small misalignment (non-orthogonality) angles between sensor axes."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..errors import InputError
from ._base import Param, SensorErrorModel, sensor_axes

__all__ = ["Misalignment"]


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class Misalignment(SensorErrorModel):
    r"""Small angles by which each sensor axis leans towards the others, rad.

    Parameters
    ----------
    axes : str or sequence of str, optional
        Sensor axes; every ordered pair ``(i, j)``, ``i != j``, among them gets a
        parameter (six for a triad). Default all.
    pairs : sequence, optional
        Explicit pairs instead, e.g. ``["xy", "zx"]`` or ``[("x", "y")]``.
    prior, sigma, bounds
        Optional soft prior and hard bounds in rad (first order, see Notes).

    Notes
    -----
    Reported as ``misalignment_<i><j>`` = :math:`\Theta_{ij}`: sensor ``i`` reads
    :math:`(1+s_i)(f_i + \sum_{j \ne i} \Theta_{ij} f_j) + b_i`, i.e. its sensing axis
    is :math:`e_i + \sum_j \Theta_{ij} e_j` (small angles). Internally the off-diagonal
    :math:`E_{ij}` multiplies the measured output of axis ``j`` into axis ``i`` (column
    :math:`C e_i \hat f_j`), and :math:`\Theta_{ij} = D_{ij}/D_{ii}` with
    :math:`D = (I+E)^{-1}`. Together with :class:`ScaleFactor` this is exact; without it
    the correction is exact to first order in :math:`\Theta`. Priors and bounds use the
    first-order relation :math:`\Theta_{ij} \approx -E_{ij}`.

    Examples
    --------
    Six small angles for a triad, or the pairs named:

    >>> import numpy as np
    >>> import bvpnav
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> f = np.tile([0.0, 0.0, 9.80665], (11, 1))  # at rest, z up (m/s^2)
    >>> w = np.tile([0.0, 0.0, 0.1], (11, 1))      # turning about z at 0.1 rad/s
    >>> data = bvpnav.ImuData.from_gyro(t, f, w)
    >>> from bvpnav.error_models import Misalignment
    >>> [name[-2:] for name in Misalignment().names(data)]
    ['xy', 'xz', 'yx', 'yz', 'zx', 'zy']
    >>> Misalignment(pairs=["xy"]).columns(data).shape  # (samples, navigation axes, parameters)
    (11, 3, 1)
    """

    #: What the solve's plausibility check judges its estimates as (the limits are in
    #: :mod:`bvpnav.solve.plausibility`).
    plausibility_kind = "misalignment"

    pairs: Any = None
    units = "rad"

    def validate(self) -> None:
        if self.pairs is not None:
            if self.axes is not None:
                raise InputError("Misalignment: give axes= or pairs=, not both")
            out = []
            for p in self.pairs:
                pr = tuple(p)
                if len(pr) != 2 or pr[0] == pr[1]:
                    raise InputError(f"Misalignment: pair {p!r}; give two different axes like 'xy'")
                out.append((str(pr[0]), str(pr[1])))
            if not out:
                raise InputError("Misalignment: pairs=() selects nothing")
            object.__setattr__(self, "pairs", tuple(out))

    def params(self, data) -> list[Param]:
        ax = sensor_axes(data)
        sep = "" if all(len(a) == 1 for a in ax) else "_"
        if self.pairs is not None:
            idx = []
            for a, b in self.pairs:
                for s in (a, b):
                    if s not in ax:
                        raise InputError(
                            f"Misalignment: unknown sensor axis {s!r}; sensor axes are {list(ax)}"
                        )
                idx.append((ax.index(a), ax.index(b)))
        else:
            sel = self._select_axes(ax, "sensor")
            if len(sel) < 2:
                raise InputError(
                    f"Misalignment: needs at least two sensor axes, got {[ax[i] for i in sel]}"
                )
            idx = [(i, j) for i in sel for j in sel if i != j]
        if len(set(idx)) != len(idx):
            raise InputError("Misalignment: a pair is given twice")
        return [Param(f"misalignment_{ax[i]}{sep}{ax[j]}", "misalignment", i, j) for i, j in idx]
