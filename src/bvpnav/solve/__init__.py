"""How a formulation is solved: checked options, stages that compose, verified answers.

See :mod:`bvpnav.solve.pipeline` for the order of the stages.
"""

from __future__ import annotations

from .options import DEFAULT_FALLBACK, SolveOptions, check_lam, prepare
from .pipeline import run, solve, solve_sequential
from .rule import choose_lambda, lambda_curve

__all__ = ["DEFAULT_FALLBACK", "SolveOptions", "check_lam", "prepare", "run", "solve", "solve_sequential",
           "lambda_curve", "choose_lambda"]
