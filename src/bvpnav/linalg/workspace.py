"""The solve's workspace: what one solve of one formulation computes once and reuses.

A :class:`~bvpnav.formulation.Formulation` is immutable and holds no solve-time state.
Whatever a solve wants to keep between its steps (the FEM rows by diagonals, the band
plan, the lambda sweep's band along lambda and its last factors for the solve at the
chosen lambda) lives in a :class:`Workspace` that the solve owns (the rule stage for a
sweep and the solve at its choice, the fixed-lambda stage otherwise) and hands
explicitly to the kernels of :mod:`bvpnav.linalg.lsq` and to the back ends that declare
they use it (:attr:`bvpnav.backends.Backend.uses_workspace`). A workspace belongs to one
formulation: a stage that makes a new formulation (demotion, linearization) solves it
with a new workspace.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model import NavModel
from .banded import AffineBand, BandPlan, DiagonalRows, KeptFactors

__all__ = ["Workspace"]


@dataclass(eq=False)
class Workspace:
    """Solve-time state of one formulation (every field None until a step fills it).

    Attributes
    ----------
    fem_diagonals : DiagonalRows or None
        The FEM rows by diagonals of :attr:`model` (:func:`bvpnav.linalg.lsq.fem_rows_by_diagonals`).
    model : NavModel or None
        The model :attr:`fem_diagonals` describe.
    fem_fixed : tuple or None
        The FEM rows' blocks that do not move with a Gauss-Newton point (the stiffness, the
        mass, the end velocities' and element residuals' columns: objects the node-state loop's
        models share), their placement by :func:`bvpnav.linalg.lsq.fem_rows_by_diagonals` and
        (node states) the entries off the diagonals as CSR rows to which the states' columns are
        appended, reused while the blocks are the same objects.
    band_plan : BandPlan or None
        The symbolic analysis of the banded factorization (:func:`bvpnav.linalg.lsq.banded_plan`),
        for the sparsity pattern :attr:`band_pattern`.
    band_pattern : tuple of ndarray or None
        ``(D.indptr, D.indices, E.indptr, E.indices, lam_rows)`` of the form the plan was made for.
    affine_band : AffineBand or None
        A lambda sweep's band along lambda, made with the plan :attr:`band_plan`: the solve at
        the chosen lambda copies its band at that lambda instead of assembling it.
    kept_factors : KeptFactors or None
        A lambda sweep's last factor and its spare buffers, handed to the solve at the chosen
        lambda (:meth:`bvpnav.lam.sweep.DirectSweep.hand_off`).
    band_buffer : ndarray or None
        Memory for the band of the next banded factor, given by a loop whose every factor is
        dead before the next one is assembled (the node-state loop of
        :mod:`bvpnav.solve.attitude`); the factor then lives in it. None: fresh memory.
    active_hint : ActiveHint or None
        The band and inequality rows at their bounds in the last answer
        (:mod:`bvpnav.linalg.active_set`): a loop that solves the same items again (the
        attitude loop) hands them to the next solve's workspace, whose active set starts there.
    """

    fem_diagonals: DiagonalRows | None = None
    model: NavModel | None = None
    fem_fixed: tuple | None = None
    band_plan: BandPlan | None = None
    band_pattern: tuple[np.ndarray, ...] | None = None
    affine_band: AffineBand | None = None
    kept_factors: KeptFactors | None = None
    band_buffer: np.ndarray | None = None
    active_hint: object | None = None

    def drop_model(self) -> None:
        """Forget :attr:`fem_diagonals` and the model they describe (which holds its data): a
        loop whose next step is a new model (the node-state loop's full passes) calls this so
        that the last step's model and data are freed before the next step's are made."""
        self.fem_diagonals = None
        self.model = None

    def drop_sweep_bands(self) -> None:
        """Forget a sweep's bands (the band along lambda and the kept factors) once the
        chosen lambda is solved: bands of the whole problem are not kept alive longer."""
        self.affine_band = None
        self.kept_factors = None
