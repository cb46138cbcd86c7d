"""How a formulation is solved: checked options, stages that compose, verified answers.

See :mod:`bvpnav.solve.pipeline` for the order of the stages.

Examples
--------
Constant acceleration 0.5 m/s^2 for 2 s between known positions 0 m and 3 m:

>>> import numpy as np
>>> import bvpnav
>>> from bvpnav.constraints import Position
>>> t = np.linspace(0.0, 2.0, 21)
>>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.full(21, 0.5)))
>>> prob = prob.add(Position(t=[0.0, 2.0], value=[0.0, 3.0]))
>>> sol = bvpnav.solve.solve(prob.formulation, solver="direct")
>>> print(f"v(0) = {sol.velocity('x')[0]:.3f} m/s")
v(0) = 1.000 m/s
"""

from __future__ import annotations

from .options import DEFAULT_FALLBACK, SolveOptions, check_lam, prepare
from .pipeline import run, solve, solve_sequential
from .rule import choose_lambda, lambda_curve

__all__ = ["DEFAULT_FALLBACK", "SolveOptions", "check_lam", "prepare", "run", "solve", "solve_sequential",
           "lambda_curve", "choose_lambda"]
