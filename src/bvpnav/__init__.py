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
"""

from __future__ import annotations

from . import attitude, baselines, error_models, lam, scenarios, simulate, solve
from ._version import __version__
from .backends import available_solvers
from .compare import compare_solvers
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
    "attitude",
    "available_solvers",
    "baselines",
    "compare_solvers",
    "error_models",
    "lam",
    "lambda_curve",
    "solve",
    "scenarios",
    "simulate",
]
