"""The trajectory is mirror-symmetric in time about an instant."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bvpnav.errors import InputError
from bvpnav.items import Item

from ._common import finite, times

__all__ = ["Symmetry"]


@dataclass(frozen=True, kw_only=True, eq=False)
class Symmetry(Item):
    r"""Positions mirrored about the instant ``about`` are equal (or opposite).

    Parameters
    ----------
    about : float
        The instant ``c`` in s about which the motion is mirrored.
    halfwidth : float, optional
        Use offsets ``0 < tau <= halfwidth`` (s); default: as far as the window allows.
    offsets : array_like of float, optional
        Explicit offsets ``tau`` in s; default: the sample times after ``c`` (so every
        node to the right of ``c`` is paired with its mirror image).
    parity : {"even", "odd"}
        ``even``: :math:`r(c + \tau) = r(c - \tau)` (the 2011 paper's symmetry, e.g. a
        there-and-back motion); ``odd``: :math:`r(c + \tau) - r(c) = -(r(c - \tau) - r(c))`.
    axes, sigma, mode, huber, tol, name
        See :class:`bvpnav.items.Item`; ``sigma`` in m.

    Notes
    -----
    Even residual :math:`\rho_k = r(c + \tau_k) - r(c - \tau_k)`; odd residual
    :math:`\rho_k = r(c + \tau_k) + r(c - \tau_k) - 2 r(c)`. Positions between nodes
    are interpolated linearly (the FEM's own representation).

    Examples
    --------
    A there-and-back motion :math:`r = (t - 1)^2` m (acceleration 2 m/s^2), mirrored about
    t = 1 s: the symmetry and the start position give the initial velocity, -2 m/s:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, Symmetry
    >>> data = bvpnav.ImuData(t=np.linspace(0.0, 2.0, 21), acc=np.full(21, 2.0))
    >>> prob = bvpnav.NavigationProblem(data).add(Position(t=0.0, value=1.0), Symmetry(about=1.0))
    >>> sol = prob.solve(solver="direct")
    >>> print(f"v(0) = {sol.velocity('x')[0]:.3f} m/s, r(1) = {abs(sol.position('x')[10]):.3f} m")
    v(0) = -2.000 m/s, r(1) = 0.000 m
    """

    about: Any
    halfwidth: float | None = None
    offsets: Any = None
    parity: str = "even"
    units = "m"
    #: Its instants mirror the samples about ``about`` (times between samples): a coarse mesh
    #: (``segment=``) cannot give them nodes in advance, so it refuses the item.
    on_mesh = False

    def validate(self) -> None:
        c = times(self.about, self.label, "about")
        if c.size != 1:
            raise InputError(f"{self.label}: about must be one instant in s")
        object.__setattr__(self, "about", float(c[0]))
        if self.parity not in ("even", "odd"):
            raise InputError(f"{self.label}: parity={self.parity!r}; choose 'even' or 'odd'")
        if self.halfwidth is not None:
            hw = float(finite(self.halfwidth, self.label, "halfwidth"))
            if hw <= 0:
                raise InputError(f"{self.label}: halfwidth={hw!r} s must be positive")
            object.__setattr__(self, "halfwidth", hw)
        if self.offsets is not None:
            off = times(self.offsets, self.label, "offsets")
            if np.any(off <= 0):
                raise InputError(f"{self.label}: offsets must be positive (s)")
            object.__setattr__(self, "offsets", off)

    def taus(self, grid) -> np.ndarray:
        """The offsets used on a grid (s)."""
        c = self.about
        if not grid.t0 <= c <= grid.t1:
            raise InputError(
                f"{self.label}: about={c!r} s is outside the window [{grid.t0!r}, {grid.t1!r}] s; "
                "use a time inside the window"
            )
        reach = min(c - grid.t0, grid.t1 - c)
        if self.halfwidth is not None:
            if self.halfwidth > reach * (1 + 1e-12):
                raise InputError(
                    f"{self.label}: halfwidth={self.halfwidth!r} s reaches outside the window "
                    f"(at most {reach!r} s around about={c!r} s)"
                )
            reach = self.halfwidth
        if self.offsets is not None:
            tau = self.offsets
            if np.any(tau > reach * (1 + 1e-12)):
                raise InputError(f"{self.label}: an offset reaches outside the window ({reach!r} s)")
            return np.minimum(tau, reach)
        tau = grid.t[(grid.t > c) & (grid.t <= c + reach * (1 + 1e-12))] - c
        if tau.size == 0:
            raise InputError(f"{self.label}: no sample lies within the mirrored range around {c!r} s")
        return np.minimum(tau, reach)

    @classmethod
    def example(cls) -> Symmetry:
        """A valid instance for a window of [0, 10] s with axes x, y, z (contract tests)."""
        return cls(about=5.0, halfwidth=4.0)

    def compile(self, model):
        tau = self.taus(model.grid)
        what = f"{self.identify()}(about={self.about:g})"
        right = model.position(self.about + tau, self.axes, what)
        left = model.position(self.about - tau, self.axes, what)
        if self.parity == "even":
            return right - left
        centre = model.position(np.full(tau.size, self.about), self.axes, what)
        return right + left - centre * 2.0

    def latex(self) -> str:
        """The residual's equation for ``describe(format="latex")`` (mathtext)."""
        if self.parity == "even":
            return r"r(c + \tau_k) - r(c - \tau_k) = 0"
        return r"r(c + \tau_k) + r(c - \tau_k) - 2 r(c) = 0"

    def math(self) -> str:
        if self.parity == "even":
            return f"r(c + tau_k) - r(c - tau_k) = 0, c = {self.about:g} s"
        return f"r(c + tau_k) + r(c - tau_k) - 2 r(c) = 0, c = {self.about:g} s"
