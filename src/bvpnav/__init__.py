"""bvpnav: post-processed inertial navigation as a boundary value problem.

Accelerometer samples plus additional information (positions, velocities, average
velocities, symmetry, stationary intervals, ...) are posed as one declarative convex
problem: the linear-FEM equations of r''(t) = a(t) are hard constraints, the
measurement error is an explicit residual, and every piece of information is a
pluggable item from :mod:`bvpnav.constraints`.

Quick start::

    import bvpnav
    from bvpnav.constraints import Position, Velocity

    data = bvpnav.ImuData(t=t, acc=acc)
    prob = bvpnav.NavigationProblem(data)
    prob.add(Position(t=[t[0], t[-1]], value=[0.0, 10.0]))
    sol = prob.solve()
    sol.trajectory  # index t (s); columns x (m), vx (m/s)

Examples
--------
A car starting at rest at the origin, under a constant 0.5 m/s^2 for 2 s:

>>> import numpy as np
>>> import bvpnav
>>> from bvpnav.constraints import Position, Velocity
>>> t = np.linspace(0.0, 2.0, 21)
>>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))
>>> prob = bvpnav.NavigationProblem(data)
>>> prob.add(Position(t=0.0, value=0.0), Velocity(t=0.0, value=0.0))
NavigationProblem(...)
>>> sol = prob.solve(solver="direct")
>>> print(f"{sol.position('x')[-1]:.3f} m, {sol.velocity('x')[-1]:.3f} m/s")
1.000 m, 1.000 m/s
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from ._version import __version__
from .errors import (
    BvpnavError,
    ConvexityError,
    Inaccurate,
    Infeasible,
    InputError,
    SolveError,
    SolverNotFound,
    Unbounded,
)

if TYPE_CHECKING:  # the lazy names below, for type checkers and IDEs
    from . import align, attitude, baselines, error_models, evaluate, lam, scenarios, sensors, simulate, solve
    from .backends import available_solvers
    from .compare import compare_solvers
    from .grid import TimeGrid
    from .imu import ImuData
    from .items import Item
    from .model import Affine, NavModel
    from .problem import NavigationProblem
    from .result import Solution
    from .solve import lambda_curve

__all__ = [
    "__version__",
    "Affine",
    "BvpnavError",
    "ConvexityError",
    "ImuData",
    "Inaccurate",
    "Infeasible",
    "InputError",
    "Item",
    "NavModel",
    "NavigationProblem",
    "Solution",
    "SolveError",
    "SolverNotFound",
    "TimeGrid",
    "Unbounded",
    "align",
    "attitude",
    "available_solvers",
    "baselines",
    "compare_solvers",
    "detect",
    "error_models",
    "evaluate",
    "lam",
    "lambda_curve",
    "readers",
    "solve",
    "scenarios",
    "sensors",
    "simulate",
    "strapdown",
]

#: Names imported on first attribute access (PEP 562), not by ``import bvpnav``: the package
#: itself imports only its version and exceptions (no numpy), so ``bvpnav --help`` and
#: ``bvpnav --version`` start in a fraction of a second. The problem's classes pull in numpy,
#: pandas and scipy.sparse on first use; ``solve``, ``lam`` and ``compare`` also
#: scipy.sparse.linalg and scipy.optimize, ``attitude`` scipy.spatial, ``baselines``
#: scipy.integrate, ``simulate`` scipy.interpolate. Name -> (submodule, attribute, or None for
#: the submodule itself). cvxpy and matplotlib are imported where they are used
#: (:mod:`bvpnav.cvx`, :mod:`bvpnav.terms`, the cvxpy back ends, :mod:`bvpnav.plot`).
_LAZY = {
    "Affine": ("model", "Affine"),
    "ImuData": ("imu", "ImuData"),
    "Item": ("items", "Item"),
    "NavModel": ("model", "NavModel"),
    "NavigationProblem": ("problem", "NavigationProblem"),
    "Solution": ("result", "Solution"),
    "TimeGrid": ("grid", "TimeGrid"),
    "available_solvers": ("backends", "available_solvers"),
    "error_models": ("error_models", None),
    "scenarios": ("scenarios", None),
    "attitude": ("attitude", None),
    "baselines": ("baselines", None),
    "compare_solvers": ("compare", "compare_solvers"),
    "lam": ("lam", None),
    "lambda_curve": ("solve", "lambda_curve"),
    "simulate": ("simulate", None),
    "solve": ("solve", None),
    "detect": ("detect", None),
    "readers": ("readers", None),
    "strapdown": ("strapdown", None),
    "sensors": ("sensors", None),
    "align": ("align", None),
    "evaluate": ("evaluate", None),
}


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module, attr = _LAZY[name]
    mod = importlib.import_module(f"{__name__}.{module}")  # binds the submodule here too
    value = mod if attr is None else getattr(mod, attr)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
