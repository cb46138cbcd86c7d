r"""One generic lambda sweep: sample the curve, then let every rule score and refine.

The objective of a formulation splits as

.. math:: J(\lambda) = \hat\rho(x) + \lambda\, \hat\eta(x),

where :math:`\hat\rho` is the sum of squares of every term *not* multiplied by lambda
(the data term, error-model priors) and :math:`\hat\eta` the sum of squares of the
lambda-weighted items. Every rule looks at the curve :math:`\lambda \mapsto
(\rho, \eta) = (\hat\rho^{1/2}, \hat\eta^{1/2})`.

Two sweeps:

- :class:`DirectSweep` (problems that are equality-constrained least squares): one sparse
  factorization per lambda (:class:`bvpnav.linalg.lsq.BorderedLU`), the derivative
  :math:`dx/d\lambda` from the same factorization, hence the L-curve curvature and the
  quasi-optimality function *exactly* at every lambda; GCV's trace by exact columns for
  small problems and Hutchinson's randomized estimator (seeded Rademacher probes, one
  multi-right-hand-side solve) for large ones.
- :class:`CvxpySweep` (robust, band or inequality items): the solve stage it is given
  (the pipeline's fixed-lambda chain: back ends, fallback, verification) is run for each
  lambda; the compiled DPP problem is re-used.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..cvx import compiled
from ..errors import InputError
from ..formulation import LAM_RANGE, Formulation
from ..linalg.banded import AffineBand, BandedKKT, Factorization, KeptFactors, NotBanded
from ..linalg.condensed import CondensedBand, CondensedKKT
from ..linalg.lsq import (
    banded_factor,
    banded_plan,
    factor_form,
    fem_rows_by_diagonals,
    least_squares_form,
    non_least_squares_term,
)
from ..linalg.workspace import Workspace
from ..log import once, progress_enabled, sweeping
from ..log import progress as progress_bar
from ..log import warn as _warn
from ..plot import lcurve
from ..sparse import canonical
from . import get_rule, rule_names

__all__ = ["LambdaCurve", "DirectSweep", "CvxpySweep", "sweep_curve", "check_range", "DIRECT_POINTS",
           "SLOPE_POINTS", "CVXPY_POINTS"]

#: Default coarse sweep of the direct engine (exact curve at each point, then refined).
DIRECT_POINTS = 13

#: Default coarse sweep of the direct engine when every rule asked samples coarsely
#: (:attr:`bvpnav.lam.LambdaRule.coarse`: the L-curve, whose exact slopes locate an
#: extremum between samples, :func:`bvpnav.lam.refine_with_slopes`, and GCV; both
#: evaluate the half-way points beside their best sample, :func:`bvpnav.lam.half_way_points`):
#: one sample every two decades of the default range.
SLOPE_POINTS = 7

#: Default coarse sweep of the cvxpy engine (spline through the samples).
CVXPY_POINTS = 25

#: Most lambda-weighted rows for which a sweep without a band factors its sparse LU once (at
#: lambda = 1) and reaches every lambda by a low-rank update (:class:`_LamUpdate`) instead of
#: factoring again at each lambda.
UPDATE_ROWS = 64

#: The imaginary step of a complex-step point, relative to lambda (no difference is
#: taken, so it can be far below the square root of the machine epsilon).
COMPLEX_STEP = 1e-20

log = logging.getLogger(__name__)


class _LamUpdate(Factorization):
    r"""The augmented matrix :math:`S(\lambda)` of a sweep without a band, solved through one
    factorization of :math:`S(1)` and a low-rank update.

    Parameters
    ----------
    S : sparse matrix, shape (T, T)
        The augmented matrix at ``lam`` (:meth:`bvpnav.linalg.lsq.LeastSquaresForm.augmented`):
        what :meth:`refined` iterates against.
    base : Factorization
        The factorization of the augmented matrix at lambda = 1.
    rows : ndarray of int, shape (k,)
        The lambda-weighted rows (residual rows: the first block of ``S``).
    cap : ndarray, shape (k, k)
        :math:`G = P^T S(1)^{-1} P`, ``P`` the columns of the identity at ``rows``.
    lam : float
        Lambda (> 0).

    Notes
    -----
    The rows of :math:`\lambda` are scaled by :math:`\sqrt\lambda`, so with :math:`T` the
    identity but :math:`s = 1/\sqrt\lambda` at those rows, :math:`T S(\lambda) T = S(1) +
    \delta P P^T` with :math:`\delta = 1 - s^2` (the ``-I`` block's entries there become
    :math:`-s^2`). By the Woodbury identity

    .. math:: S(\lambda)^{-1} b = T (y - \delta Z (I + \delta G)^{-1} P^T y), \qquad
              y = S(1)^{-1} T b, \quad Z = S(1)^{-1} P.

    :math:`G` is minus the complement of the hat matrix at those rows (eigenvalues in
    :math:`[-1, 0]`), so :math:`I + \delta G` has eigenvalues of at least 1 for
    :math:`\lambda \le 1` and at least :math:`1/\lambda` above; :meth:`refined` iterates
    against :math:`S(\lambda)` itself.
    """

    def __init__(self, S, base: Factorization, rows: np.ndarray, cap: np.ndarray, lam: float):
        self.S = S
        self._base, self._rows = base, rows
        self._s = 1.0 / math.sqrt(lam)
        self._delta = 1.0 - self._s**2
        self._cap = np.linalg.inv(np.eye(rows.size) + self._delta * cap)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``S z = rhs`` for one (T,) or several (T, k) right-hand sides."""
        rows, s = self._rows, self._s
        c = np.array(rhs, dtype=float)
        c[rows] *= s
        y = self._base.solve(c)
        w = np.zeros_like(y)
        w[rows] = self._cap @ (self._delta * y[rows])
        y -= self._base.solve(w)
        y[rows] *= s
        return y


@dataclass(repr=False)
class LambdaCurve:
    r"""A lambda sweep and the rules' choices.

    Attributes
    ----------
    lam : ndarray
        Sampled lambda values (dimensionless), increasing.
    residual_norm : ndarray
        :math:`\rho(\lambda)`, square root of the terms not weighted by lambda
        (data term in its own units, e.g. dimensionless for the acceleration form
        with ``sigma_a``, m/s for the load form).
    info_norm : ndarray
        :math:`\eta(\lambda)`, square root of the lambda-weighted item terms.
    scores : dict of str -> ndarray
        Per rule, its score at each sampled lambda (curvature for ``lcurve``, the GCV
        function, the discrepancy ``rho^2 - tau * dof`` and the quasi-optimality
        function ``||lambda dr/dlambda||`` in m); NaN where not computed.
    chosen : dict of str -> float
        Per rule, the chosen lambda (after refinement).
    rule : str
        The rule whose choice was used.
    engine : str
        ``"direct"`` or ``"cvxpy"``.
    warnings : list of str
        E.g. a corner at the edge of the range.
    evaluations : int
        Number of distinct lambdas solved.
    seconds : float
        Wall time of the sweep, s.
    lam_range : tuple
        The search interval as given.
    trace_method : str or None
        How GCV's trace was computed (``"exact columns"``, ``"log-determinant"`` or
        ``"Hutchinson (k probes)"``), None when no rule needed it.
    factorization : str or None
        The direct sweep's factorization (e.g. ``"banded (kl=4, ...)"``).
    evaluated : ndarray or None
        Every lambda the sweep solved (the samples and the rules' refinements), shape
        (k, 3): lambda, residual norm and information norm, by increasing lambda (what
        :meth:`plot` draws).
    """

    lam: np.ndarray
    residual_norm: np.ndarray
    info_norm: np.ndarray
    scores: dict = field(default_factory=dict)
    chosen: dict = field(default_factory=dict)
    rule: str = "lcurve"
    engine: str = "direct"
    warnings: list = field(default_factory=list)
    evaluations: int = 0
    seconds: float = 0.0
    lam_range: tuple = (1e-6, 1e6)
    trace_method: str | None = None
    factorization: str | None = None
    evaluated: np.ndarray | None = None

    def __repr__(self) -> str:
        """One line: how many lambdas over which range, each rule's choice, the rule used,
        the engine, the evaluations and time, and how many warnings (no arrays)."""
        lo, hi = self.lam_range
        chosen = ", ".join(f"{r} {v:.4g}" for r, v in self.chosen.items()) or "none"
        text = (f"LambdaCurve({len(self.lam)} lambdas over {lo:g} .. {hi:g}; chosen: {chosen}; "
                f"used: {self.rule}; {self.engine} engine, {self.evaluations} evaluations, "
                f"{self.seconds:.3g} s")
        if self.warnings:
            text += f"; {len(self.warnings)} warning(s), see .warnings"
        return text + ")"

    @property
    def lam_chosen(self) -> float:
        """The lambda of :attr:`rule`."""
        return self.chosen[self.rule]

    def to_frame(self) -> pd.DataFrame:
        """One row per sampled lambda: lam, residual_norm, info_norm and one column per score."""
        df = pd.DataFrame({"lam": self.lam, "residual_norm": self.residual_norm,
                           "info_norm": self.info_norm})
        for k, v in self.scores.items():
            df[k] = v
        return df

    def plot(self, ax=None):
        """L-curve with every rule's choice marked (see :func:`bvpnav.plot.lcurve`)."""
        return lcurve(self, ax=ax)


class _Grid:
    """A rule's view of a curve whose samples it reads every ``step``-th of: ``lam`` is
    its own samples; ``warnings`` and every other attribute are the curve's."""

    def __init__(self, curve: LambdaCurve, step: int):
        self._curve, self.lam = curve, curve.lam[::step]

    def __getattr__(self, name):
        return getattr(self._curve, name)


# ----------------------------------------------------------------- sweeps
class _NoLogdet(Exception):
    """A neighbouring lambda's factor has no log-determinant (the banded factor failed and
    the sparse LU took over): GCV's trace falls back to the probes."""


class DirectSweep:
    """Exact per-lambda evaluation for least-squares problems.

    ``trace`` picks how GCV's trace is computed: ``"auto"`` (exact columns up to
    ``exact_trace_limit`` samples x axes, else the log-determinant where it applies, else
    Hutchinson), or ``"exact"``, ``"logdet"``, ``"hutchinson"`` to force one (the
    log-determinant falls back to Hutchinson where it does not apply).
    """

    engine = "direct"

    def __init__(self, form: Formulation, exact_trace_limit: int = 300, need_trace: bool = False,
                 probes: int = 24, seed: int = 0, tau: float = 1.5, trace: str = "auto",
                 need_derivative: bool = True, need_quasi: bool = True, condense: bool = True,
                 workspace: Workspace | None = None):
        self.form = form
        #: The solve's workspace: the band plan, the band along lambda and, after
        #: :meth:`hand_off`, the factors the solve at the chosen lambda takes.
        self.workspace = Workspace() if workspace is None else workspace
        self.exact_trace_limit = exact_trace_limit
        self.need_trace, self.probes, self.seed, self.tau = need_trace, probes, seed, tau
        self.need_derivative = need_derivative
        self.need_quasi = need_quasi
        self._cond = None if condense else False
        self.model = self.form.model
        self.terms = self.form.terms()
        self.lam_terms = [t for t in self.terms if t.mode == "soft" and t.scaled_by_lam]
        self.fixed_terms = [t for t in self.terms if t.mode == "soft" and not t.scaled_by_lam]
        self.data = self.form.data_rows()
        self.cache: dict[float, dict] = {}
        self._rhs_jac = None
        self._probe_rhs = None
        self._logdet_ok = None
        self.trace_method = None
        if trace not in ("auto", "exact", "logdet", "hutchinson"):
            raise InputError(f"trace={trace!r}: choose 'auto', 'exact', 'logdet' or 'hutchinson'")
        self.trace = trace
        self._ls = least_squares_form(self.form, 1.0)   # every lambda rescales its soft rows
        self._plan = None
        self._parts = None
        self._buffers: list = [None, None, None]
        self._kept: tuple | None = None   # (lambda, factor, buffer index) of the last real point
        self._update = None   # (factor at lambda = 1, rows, G) of _LamUpdate, or False
        self._reads_eliminated = None
        #: How the last log-determinant derivative was taken ("complex step" or
        #: "central difference"), None before GCV's first trace by the log-determinant.
        self.logdet_derivative = None
        self.factorization = "lu"
        if self.form.residual == "acceleration":  # the load form (condition ~N^4) keeps the pivoted LU
            try:
                self._plan = banded_plan(self._ls, self.form, self.workspace)
                self.factorization = self._plan.describe()
            except NotBanded as exc:
                self.factorization = f"lu (not banded: {exc})"
            except (RuntimeError, np.linalg.LinAlgError) as exc:
                self.factorization = f"lu (banded failed: {exc})"

    def _affine_parts(self):
        """The band along lambda (:class:`bvpnav.linalg.banded.AffineBand`): affine in lambda
        when every lambda-weighted row is folded (unknowns they touch are never
        eliminated), so a new lambda costs one copy of the scaled band, a few rows and one
        ``dgbtrf``, no assembly; False when a lambda row is not folded."""
        if self._parts is None:
            pl, ls = self._plan, self._ls
            D, E = canonical(ls.D.A), canonical(ls.E.A)
            lam_rows = np.asarray(ls.lam_rows, dtype=bool)
            if np.any(lam_rows & ~pl.fold):
                self._parts = False   # a far-reaching lambda row: assemble at every lambda
            else:
                diagonal = fem_rows_by_diagonals(self.form, self.workspace)
                self._parts = AffineBand(pl.assemble(D, E, diagonal),
                                         pl.objective_part(D[lam_rows]), pl.kl)
                # the solve at the chosen lambda takes its band from here too (lsq.banded_factor)
                self.workspace.affine_band = self._parts
        return self._parts

    def _combined(self, lam: float, buffer: int = 0, h: float = 0.0) -> tuple | None:
        """The scaled banded parts at ``lam`` (:meth:`bvpnav.linalg.banded.AffineBand.at`), or at
        ``lam + ih`` with ``h`` (:meth:`~bvpnav.linalg.banded.AffineBand.at_complex`), or None.

        The band is written into one of three arrays the sweep owns (``buffer`` 0: the
        factor of the current point, dead when the next point starts; 1: the log-
        determinant's neighbours, dead once their determinant is read; the complex one for
        ``h``, dead once the point's quantities are read), so that ``dgbtrf`` works in
        place of an array already mapped instead of a fresh one per lambda; after the
        sweep they serve the solve at the chosen lambda (:meth:`hand_off`)."""
        affine = self._affine_parts()
        if not affine:
            return None
        bufs = self._buffers
        buffer = 2 if h else buffer
        if bufs[buffer] is None:
            bufs[buffer] = np.empty(affine.scaled0.shape, dtype=complex if h else float)
        return affine.at_complex(lam, h, out=bufs[buffer]) if h else affine.at(lam, out=bufs[buffer])

    def _condensed(self):
        """The sweep's :class:`bvpnav.linalg.condensed.CondensedBand` (made at the first point), or
        False: no band affine in lambda, a border, several runs, GCV's trace by exact
        columns or probes (they take the whole factor; the log-determinant's derivative is
        the small system's, :meth:`bvpnav.linalg.condensed.CondensedBand.logdet_slope`), or lambda
        touching too much."""
        if self._cond is None:
            self._cond = False
            affine = self._affine_parts() if self._plan is not None else None
            if affine and (not self.need_trace or self._complex_applies()):
                try:
                    self._cond = CondensedBand(self._plan, affine, self._plain_unknowns())
                except (NotBanded, np.linalg.LinAlgError) as exc:
                    log.debug("lambda sweep: no condensation (%s)", exc)
        return self._cond

    def _plain_unknowns(self) -> np.ndarray:
        """Which reduced unknowns (``x``, the unfolded residuals, the multipliers) are
        positions or FEM multipliers (:class:`bvpnav.linalg.condensed.CondensedBand` keeps every
        node that holds another)."""
        pl, model = self._plan, self.model
        n, nu = pl.n, pl.unfolded.size
        plain = np.zeros(n + nu + pl.p, dtype=bool)
        plain[np.concatenate([model.r_index(a) for a in range(model.d)])] = True
        for label, rows in self._ls.eq_blocks:
            if label == "fem":
                plain[n + nu:][rows] = True
        return plain

    def _factor(self, ls, lam: float | None = None, condensed: bool = False):
        """The banded factor with the plan made once (the pattern is the same at every
        lambda), or the pivoted sparse LU when the problem is not banded. The last banded
        factor at a ``lam`` is kept for :meth:`hand_off`. With ``condensed``, a
        :class:`bvpnav.linalg.condensed.CondensedKKT` where the sweep has a condensed band."""
        cond = self._condensed() if condensed and lam is not None else False
        if cond:
            try:
                return CondensedKKT(ls.D.A, ls.E.A, cond, lam, params=self.model.l_index)
            except (NotBanded, RuntimeError, np.linalg.LinAlgError):
                pass   # the whole band's factor below
        if self._plan is not None:
            self._kept = None   # its buffer is about to be overwritten
            try:
                parts = None if lam is None else self._combined(lam)
                fac = banded_factor(ls, self.form, plan=self._plan, parts=parts)
            except (RuntimeError, np.linalg.LinAlgError):
                pass
            else:
                if lam is not None:
                    self._kept = (float(lam), fac, 0 if parts is not None else None)
                return fac
        elif lam is not None and self._updatable():
            base, rows, cap = self._update
            return _LamUpdate(ls.augmented(), base, rows, cap, float(lam) / self._ls.lam)
        return factor_form(ls, self.form)

    def _updatable(self) -> bool:
        """Whether points reach their lambda by :class:`_LamUpdate` (at most :data:`UPDATE_ROWS`
        lambda-weighted rows); its factor at lambda = 1 and :math:`G` are made at the first call."""
        if self._update is None:
            self._update = False
            rows = np.flatnonzero(np.asarray(self._ls.lam_rows, dtype=bool))
            if 0 < rows.size <= UPDATE_ROWS:
                base = factor_form(self._ls, self.form)   # raises, as a point's own would
                cap = np.empty((rows.size, rows.size))
                e = np.zeros(base.S.shape[0])
                for j, r in enumerate(rows):   # column by column: no (T, k) array
                    e[r] = 1.0
                    cap[:, j] = base.solve(e)[rows]
                    e[r] = 0.0
                self._update = (base, rows, cap)
        return bool(self._update)

    def hand_off(self) -> None:
        """Hand the last real point's factor and the buffers no factor uses to the solve at
        the chosen lambda (:attr:`bvpnav.linalg.workspace.Workspace.kept_factors`, read by
        :func:`bvpnav.linalg.lsq.banded_factor`): its band is written into memory the sweep has
        already touched instead of a fresh array, or, when it is the last point's lambda,
        not factored again. The sweep's buffers are then the solve's: the sweep evaluates
        no more points after this."""
        if self._plan is None:
            return
        kept = KeptFactors(self._plan)
        used = None
        if self._kept is not None:
            lam, fac, used = self._kept
            kept.keep(lam, fac, None if used is None else self._buffers[used])
        for b, buf in enumerate(self._buffers):
            if buf is not None and b != used:
                kept.spare(buf)
        if self._cond:
            kept.spare(self._cond.buffer())
            self._cond = None
        self._kept, self._buffers = None, [None] * len(self._buffers)
        self.workspace.kept_factors = kept

    def _logdet(self, lam: float) -> float:
        """:meth:`bvpnav.linalg.banded.BandedKKT.logdet` at ``lam``: from the combined parts by
        the numeric factorization alone where the band is affine in lambda."""
        try:
            parts = self._combined(lam, buffer=1)
            if parts is not None:
                return BandedKKT.numeric(self._plan, parts).logdet()
            fac = self._factor(self._ls.at_lam(lam), lam)
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            raise InputError(f"lambda={lam:g}: the KKT matrix is singular ({exc}); some unknown is "
                             "not determined by the information") from exc
        if not isinstance(fac, BandedKKT):   # the banded factor failed there: the sparse LU has none
            raise _NoLogdet(f"the banded factor failed at lambda={lam:g}")
        return fac.logdet()

    def point(self, lam: float, need_trace: bool | None = None, probes: int | None = None,
              seed: int | None = None) -> dict:
        """The curve at one lambda (cached): ``rho2``, ``eta2``, ``x``, with
        ``need_derivative`` (the default) ``deta2``, ``d2eta2`` and ``quasi``, and, when
        asked, ``trace``."""
        need_trace = self.need_trace if need_trace is None else need_trace
        probes = self.probes if probes is None else probes
        seed = self.seed if seed is None else seed
        key = float(lam)
        pt = self.cache.get(key)
        if (pt is not None and (not need_trace or "trace" in pt)
                and (not self.need_derivative or "deta2" in pt)):
            return pt
        ls = self._ls.at_lam(lam)
        m, n = ls.D.A.shape
        # GCV's trace by the log-determinant: on a condensed band, the small system's complex
        # step (_trace_logdet); else one complex factorization of the whole band at
        # lambda + ih gives the point, dx/dlambda and the determinant's derivative
        # (_complex_point)
        by_logdet = need_trace and self._complex_applies()
        condensed = not need_trace or (by_logdet and bool(self._condensed()))
        step = self._complex_point(ls, lam) if by_logdet and not condensed else None
        h = None
        if step is not None:
            fac, x, h = step
            banded = True
        else:
            try:
                fac = self._factor(ls, lam, condensed=condensed)
            except (RuntimeError, np.linalg.LinAlgError) as exc:
                raise InputError(f"lambda={lam:g}: the KKT matrix is singular ({exc}); some unknown "
                                 "is not determined by the information") from exc
            # the banded LU (pivoted, exact but for folding the local rows) answers a curve
            # point to about 1e-12 without refinement (the chosen lambda's own solve is refined
            # and verified); the sparse LU of the load form is refined twice
            banded = isinstance(fac, BandedKKT)
            if banded:
                x = fac.solve_x(ls.rhs())
            else:
                x = fac.refined(ls.rhs(), 2, 1e-14, window=slice(m, m + n))[0][m:m + n]
        scaled = [t.residual.value(x) / t.sigma for t in self.lam_terms]  # S (A x + c)
        rho2 = float(np.sum(self.data.value(x) ** 2))
        rho2 += sum(float(np.sum((t.residual.value(x) / t.sigma) ** 2)) for t in self.fixed_terms)
        eta2 = sum(float(np.sum(r**2)) for r in scaled)
        pt = {"lam": key, "rho2": rho2, "eta2": eta2, "x": x}
        if self.need_derivative:
            pt.update(self._derivative(ls, fac, banded, x, scaled, lam))
        if need_trace:
            pt["trace"] = self._trace(ls, fac, lam, probes, seed, h)
        self.cache[key] = pt
        return pt

    def _complex_applies(self) -> bool:
        """Whether a point with GCV's trace is one complex factorization: the trace by the
        log-determinant (``trace`` "auto" beyond the exact limit, or "logdet"), a band
        affine in lambda, and the measured accelerations entering as ``a_hat + w``."""
        N, d = self.model.N, self.model.d
        if self.trace not in ("auto", "logdet") or (self.trace == "auto" and N * d <= self.exact_trace_limit):
            return False
        return self._plan is not None and self._logdet_applies()

    def _complex_point(self, ls, lam: float):
        r"""``(factor, x, h)`` at ``lam`` from one complex factorization, or None (no affine
        band, or its factor failed: the real path takes over).

        Notes
        -----
        The folded system is affine in lambda, :math:`K(\lambda)`; factored at
        :math:`\lambda + ih` (:data:`COMPLEX_STEP` relative) its pivots give
        :math:`d\log|\det K|/d\lambda` (:meth:`bvpnav.linalg.banded.BandedKKT.logdet_step`,
        exact to rounding), and since :math:`K(\lambda + ih)^{-1} = K^{-1} - ih\,K^{-1}
        K' K^{-1} + O(h^2)` the real part of a solve with the real right-hand side is the
        point. One ``zgbtrf`` (about 1.7 times a ``dgbtrf``) and one ``zgbtrs`` replace the
        real factor and two more real factorizations at :math:`\lambda e^{\pm\delta}`;
        rules that use :math:`dx/d\lambda` take one more ``zgbtrs``
        (:meth:`_derivative`).
        """
        h = COMPLEX_STEP * lam
        parts = self._combined(lam, h=h)
        if parts is None:
            return None
        try:
            fac = banded_factor(ls, self.form, plan=self._plan, parts=parts)
        except (RuntimeError, np.linalg.LinAlgError):
            return None
        # a real right-hand side: the real part of the solve is x to O(h^2) (dx/dlambda is
        # then solved for with this factor, from the residuals, in _derivative: the
        # imaginary part of a solve with the right-hand side's derivative would carry
        # dx = K^-1 (b' - K' x) with b' and K' x cancelling inside the factorization,
        # accurate only to |x| eps / lambda; 14 % off at lambda = 1e6 on 2,000 samples)
        return fac, fac.solve_x_real(ls.rhs()), h

    def _derivative(self, ls, fac, banded: bool, x: np.ndarray, scaled: list, lam: float) -> dict:
        r"""``deta2``, ``d2eta2`` and ``quasi`` from :math:`dx/d\lambda`, one more solve with
        the factor (a complex-step factor's real part, see :meth:`_complex_point`).

        Notes
        -----
        With the hard rows as :math:`x = x_0 + Z y` (their right-hand side does not depend
        on lambda, so neither do :math:`x_0` and :math:`Z`) and the lambda-weighted residual
        :math:`r = S(Ax + c)`, the minimiser solves :math:`(H + \lambda G) y = \ldots`,
        :math:`G = Z^T A^T S^2 A Z`, so :math:`y' = -M^{-1} g` with :math:`M = H + \lambda G`
        and :math:`g = Z^T A^T S r`. Then :math:`\hat\eta' = 2 g^T y'`; differentiating
        :math:`M y' = -g` gives :math:`y'' = -2 M^{-1} G y'`, and since :math:`M` is
        symmetric :math:`g^T y'' = 2 y'^T G y'`, so

        .. math:: \hat\eta'' = 2\lVert S A x'\rVert^2 + 2 g^T y'' = 6\lVert S A x'\rVert^2,

        the second derivative for the price of a norm (:func:`bvpnav.lam.lcurve.curvature_slope`).
        """
        m, n = ls.D.A.shape
        # dx/dlam from the same factorization: H x' + E^T mu' = -sum A^T S^2 (A x + c)
        g = np.zeros(n)
        for t, r in zip(self.lam_terms, scaled, strict=True):
            g -= t.residual.A.T @ (r / t.sigma)
        rhs = np.concatenate([np.zeros(m), g, np.zeros(ls.E.m)])
        if banded:   # the eliminated unknowns (w) only where a lambda row reads them
            dx = fac.solve_x_real(rhs, eliminated=self._lam_rows_read_eliminated(fac),
                                  interior=self.need_quasi)
        else:
            dx = fac.refined(rhs, 1, window=slice(m, m + n))[0][m:m + n]
        deta2 = d2eta2 = 0.0
        for t, r in zip(self.lam_terms, scaled, strict=True):
            dr = (t.residual.A @ dx) / t.sigma   # S A x', the lambda rows' change
            deta2 += 2.0 * float(r @ dr)
            d2eta2 += 6.0 * float(dr @ dr)
        pos = np.concatenate([self.model.r_index(a) for a in range(self.model.d)])
        return {"deta2": deta2, "d2eta2": d2eta2,
                "quasi": float(np.linalg.norm(lam * dx[pos]) / math.sqrt(pos.size))}

    def _lam_rows_read_eliminated(self, fac) -> bool:
        r"""Whether a lambda-weighted row reads an unknown the banded factor eliminates (then
        :math:`dx/d\lambda` needs them back-substituted; the quasi-optimality value reads
        positions only). False by the plan's construction (a ``w`` that any soft row reads
        is not eliminated), checked once per sweep."""
        if self._reads_eliminated is None:
            el = fac.plan.elim
            self._reads_eliminated = bool(el.size) and any(
                t.residual.A.tocsc()[:, el].nnz for t in self.lam_terms)
        return self._reads_eliminated

    # --- GCV's trace: d w / d a_hat
    def _rhs_jacobian_apply(self, Z: np.ndarray) -> np.ndarray:
        """Change of the augmented right-hand side (at lambda = 1) when the measured
        accelerations change by ``Z`` (N, d); the form is affine in the data."""
        def rhs_for(acc):
            return least_squares_form(self.form.with_acceleration(acc), 1.0).rhs()

        if self._rhs_jac is None:
            self._rhs_jac = rhs_for(np.zeros_like(self.form.data.acc))
        return rhs_for(Z) - self._rhs_jac

    def _trace(self, ls, fac, lam, probes, seed, h=None) -> float:
        N, d = self.model.N, self.model.d
        if N != self.form.data.n:
            raise InputError("GCV's trace of the influence matrix is taken over every sample, which a "
                             "coarse mesh (segment=) does not keep; give lam= (a number) or a rule without "
                             "the trace (lam='lcurve'), or solve with segment=None")
        exact = self.trace == "exact" or (self.trace == "auto" and N * d <= self.exact_trace_limit)
        why = ""
        if (self.trace in ("auto", "logdet") and not exact and isinstance(fac, BandedKKT)
                and self._logdet_applies()):
            try:
                value = self._trace_logdet(ls, fac, lam, h)
                self.trace_method = "log-determinant"
                return value
            except _NoLogdet as exc:   # the probes below need no determinant
                why = f"; no log-determinant: {exc}"
        m, n = ls.D.A.shape
        widx = np.concatenate([self.model.w_index(a) for a in range(d)])  # axis-major like Z.T
        self.trace_method = ("exact columns" if exact else f"Hutchinson ({probes} probes)") + why
        if exact:
            Zs = [np.eye(N * d)[:, k].reshape(d, N).T for k in range(N * d)]
        else:
            rng = np.random.default_rng(seed)
            Zs = [rng.choice([-1.0, 1.0], size=(N, d)) for _ in range(probes)]
        if self._probe_rhs is None or self._probe_rhs[0] != (exact, probes, seed):
            self._probe_rhs = ((exact, probes, seed), Zs,
                               np.column_stack([self._rhs_jacobian_apply(Z) for Z in Zs]))
        Zs, R = self._probe_rhs[1], self._probe_rhs[2].copy()
        R[:m][ls.lam_rows] *= math.sqrt(lam)
        dW = fac.solve(R)[m:m + n][widx]
        vals = np.array([float(Z.T.ravel() @ dW[:, k]) for k, Z in enumerate(Zs)])
        return float(vals.sum()) if exact else float(vals.mean())

    def _logdet_applies(self) -> bool:
        """Whether the measured accelerations enter only as ``a_hat + w`` outside the data
        rows (the acceleration form with items of the corrected acceleration, positions and
        velocities): then the trace follows from the log-determinant (see
        :meth:`_trace_logdet`). Checked once with a random change of the data: every row's
        response must equal its ``w`` columns' (none for the data rows)."""
        if self._logdet_ok is None:
            ls, model = self._ls, self.model
            if self.form.residual != "acceleration":
                self._logdet_ok = False
                return False
            Z = np.random.default_rng(12345).standard_normal((model.N, model.d))
            R = self._rhs_jacobian_apply(Z)
            n = model.size
            zw = np.zeros(n)
            for a in range(model.d):
                zw[model.w_index(a)] = Z[:, a]
            m0 = model.N * model.d
            want_D = -(ls.D.A @ zw)
            want_D[:m0] = 0.0
            want = np.concatenate([want_D, np.zeros(n), -(ls.E.A @ zw)])
            scale = max(float(np.max(np.abs(want))), float(np.max(np.abs(R))), 1e-300)
            self._logdet_ok = bool(np.max(np.abs(R - want)) <= 1e-9 * scale)
        return self._logdet_ok

    def _trace_logdet(self, ls, fac, lam, h=None) -> float:
        r""":math:`\mathrm{tr}(\partial w / \partial \hat a)` from the log-determinant.

        Notes
        -----
        With ``u = a_hat + w`` as unknowns, the data rows are :math:`(u - \hat a)/\sigma_a`
        and nothing else depends on the data, so the influence matrix of the ``N d`` data
        rows is :math:`A = I + \partial w / \partial \hat a` and, with the hard rows' null
        space ``Z`` (dimension :math:`k_Z = n - p`), the fixed soft rows and priors
        :math:`D_p` and the lambda-weighted rows :math:`D_1`,

        .. math::

            \mathrm{tr} A = k_Z - \mathrm{tr}(D_p \Sigma D_p^T)
              - \lambda \frac{d}{d\lambda} \log\det(Z^T H Z),
            \qquad \Sigma = Z (Z^T H Z)^{-1} Z^T,

        since :math:`Z^T H Z = Z^T (D_0^T D_0 + D_p^T D_p + \lambda D_1^T D_1) Z`. With
        a factor at :math:`\lambda + ih` (``h`` given, :meth:`_complex_point`) the
        derivative is the complex step :meth:`bvpnav.linalg.banded.BandedKKT.logdet_step`, exact to
        rounding; otherwise (a band not affine in lambda) a central difference of
        :meth:`bvpnav.linalg.banded.BandedKKT.logdet` at :math:`\lambda e^{\pm\delta}` (two more
        factorizations, :math:`\delta = 10^{-3}`: truncation error about
        :math:`\delta^2/6` relative). :math:`\Sigma` on the few prior rows by solves with
        this factorization. Tests compare both with the trace by exact columns.
        """
        model = self.model
        m0 = model.N * model.d
        m, n = ls.D.A.shape
        fixed = np.flatnonzero(~ls.lam_rows)
        fixed = fixed[fixed >= m0]
        if isinstance(fac, CondensedKKT):   # the condensed system's: K does not move
            dlog = lam * fac.logdet_slope(COMPLEX_STEP * lam)
            self.logdet_derivative = "complex step (condensed)"
        elif h is not None:   # a complex factor at lambda + ih (_complex_point)
            dlog = lam * fac.logdet_step(h)
            self.logdet_derivative = "complex step"
        else:
            dlt = 1e-3
            up, down = self._logdet(lam * math.exp(dlt)), self._logdet(lam * math.exp(-dlt))
            dlog = (up - down) / (2.0 * dlt)   # lambda d/dlambda log det
            self.logdet_derivative = "central difference"
        prior = 0.0
        if fixed.size:
            Dp = ls.D.A[fixed]
            R = np.zeros((fac.S.shape[0], fixed.size))
            R[m:m + n] = Dp.T.toarray()
            X = fac.solve_x_real(R)
            # (S^-1)_xx = -Sigma in the augmented system's sign convention: its x block is the
            # inverse of [D^T D, E^T; E, 0] restricted, with -I on the residuals
            prior = float(np.sum(Dp.toarray().T * X))
        kz = n - ls.E.m
        tr_a = kz - abs(prior) - dlog
        return float(tr_a - m0)


class CvxpySweep:
    """Runs a fixed-lambda solve stage for each lambda (the compiled DPP problem is re-used).

    Parameters
    ----------
    form : Formulation
    solve_at : callable
        ``solve_at(lam) -> Solution``: the pipeline's fixed-lambda stage.
    """

    engine = "cvxpy"

    def __init__(self, form: Formulation, solve_at: Callable, tau: float = 1.5):
        self.form = form
        self.model = self.form.model
        self.solve_at = solve_at
        self.tau = tau
        self.cache: dict[float, dict] = {}

    def point(self, lam: float, **_) -> dict:
        """The curve at one lambda (cached): ``rho2``, ``eta2`` and ``x``."""
        key = float(lam)
        if key in self.cache:
            return self.cache[key]
        x = self.solve_at(key).x
        rho2 = float(np.sum(self.form.data_rows().value(x) ** 2))
        eta2 = 0.0
        cvx = compiled(self.form)
        # the penalties at this answer: a back end that is not cvxpy's (direct's interior
        # point) leaves the variable as it was, so it is set to the answer first
        cvx.x.value = x
        for term, pen in cvx.penalties:
            v = float(pen.value) if pen.value is not None else np.nan
            if term.scaled_by_lam:
                eta2 += v
            else:
                rho2 += v
        pt = {"lam": key, "rho2": rho2, "eta2": eta2, "x": x}
        self.cache[key] = pt
        return pt


def check_range(lam_range, points) -> tuple[float, float]:
    """``(low, high)`` of a sweep, or :class:`InputError` naming a bad range or point count."""
    return _check_range(lam_range, points)


def _check_range(lam_range, points) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in lam_range)
    except (TypeError, ValueError):
        raise InputError(f"lam_range={lam_range!r}: give two numbers (low, high), e.g. "
                         "lam_range=(1e-6, 1e6)") from None
    if not (0 < lo < hi and np.isfinite(hi)):
        raise InputError(f"lam_range={lam_range!r}: need 0 < low < high")
    if lo < LAM_RANGE[0] or hi > LAM_RANGE[1]:
        raise InputError(
            f"lam_range={lam_range!r} reaches beyond {LAM_RANGE[0]:g}..{LAM_RANGE[1]:g}, the lambdas "
            "double precision can weigh against the data term; sweep inside it (the default "
            "is (1e-6, 1e6))")
    if isinstance(points, bool) or not isinstance(points, int | np.integer) or points < 7:
        raise InputError(f"points={points!r}: the sweep needs an integer of at least 7 points")
    if points > 1000:
        raise InputError(f"points={points}: at most 1000 sweep points (each is one solve); the "
                         "corner is refined between the samples anyway, 25 is the default")
    return lo, hi


def _usable_rules(form: Formulation, names: list[str], rule: str, engine: str) -> list[str]:
    """The rules that can run here; the chosen ``rule`` itself must, or InputError."""
    out = []
    for name in names:
        needs = get_rule(name).needs
        if engine == "cvxpy" and "least_squares" in needs:
            if name == rule:
                ok = [n for n in rule_names() if "least_squares" not in get_rule(n).needs]
                raise InputError(f"lam={name!r} needs a linear least-squares problem (hard and soft "
                                 "items only); this one has robust, band or inequality items. "
                                 f"Use lam={ok[0]!r}" + "".join(f" or {n!r}" for n in ok[1:]) + ".")
            continue
        if "noise" in needs and (form.residual != "acceleration" or not form.sigma_a_given):
            if name == rule:
                raise InputError(f"lam={name!r} needs the noise level: use residual='acceleration' "
                                 "with sigma_a=<accelerometer noise, m/s^2>")
            log.info("rule %s skipped: it needs residual='acceleration' with sigma_a", name)
            continue
        if "acceleration" in needs and form.residual != "acceleration":
            if name == rule:
                raise InputError(f"lam={name!r} needs the acceleration residual (it treats the measured "
                                 "accelerations as independent observations): use residual='acceleration' "
                                 "(sigma_a optional), or another rule, e.g. lam='lcurve'")
            log.info("rule %s skipped: it needs residual='acceleration' (this problem has %r)", name,
                     form.residual)
            continue
        out.append(name)
    return out


def _sweep(eng, lams, progress):
    with progress_bar(lams, desc="lambda sweep", unit="lam", enabled=progress) as bar:
        return [eng.point(lam) for lam in bar]


def sweep_curve(form: Formulation, rules=None, rule: str = "lcurve", lam_range=(1e-6, 1e6),
                points: int | None = None, tau: float = 1.5, probes: int = 24, seed: int = 0, progress=None,
                engine: str = "auto", solve_at: Callable | None = None,
                check_memory: Callable | None = None, workspace: Workspace | None = None) -> LambdaCurve:
    """Sweep lambda over a formulation and apply the selection rules.

    Parameters
    ----------
    form : Formulation
        Must have at least one soft item weighted by lambda.
    rules : sequence of str, optional
        Rules to evaluate (default: every registered rule); ``rule`` is always included.
    rule : str
        The rule whose choice is reported as :attr:`LambdaCurve.lam_chosen`.
    lam_range : (float, float)
        Search interval for lambda (dimensionless), log-spaced.
    points : int, optional
        Coarse sweep size; every rule is then refined inside its best bracket (to 1 % in
        lambda, :func:`bvpnav.lam.refine_extremum`). Default: 13 (one per decade of the default range) with
        the ``direct`` engine, whose curve is exact at every point, of which a rule that
        samples coarsely (the L-curve or GCV, :attr:`bvpnav.lam.LambdaRule.coarse`) reads
        every other one (7, :data:`SLOPE_POINTS`, two decades apart) where the range spans
        12 decades or more; only those 7 are solved when every rule samples coarsely. A
        rule reads the same samples whichever rules run beside it, so ``solve(lam=rule)``
        and a sweep of several rules (``bvpnav lcurve``) choose the same lambda;
        25 with the ``cvxpy`` engine, whose curvature is a spline through the samples.
    tau : float
        Discrepancy safety factor.
    probes, seed : int
        Hutchinson probes of GCV's trace (problems of more than 300 samples x axes) and
        their seed (results are reproducible).
    progress : bool, optional
        Show a tqdm bar (True always, False never); default: when stderr is a terminal (see
        :func:`bvpnav.log.progress_enabled`).
    engine : {"auto", "direct", "cvxpy"}
    solve_at : callable, optional
        ``solve_at(lam) -> Solution``, the fixed-lambda solve of the ``cvxpy`` engine
        (required for it).
    check_memory : callable, optional
        Called before the ``direct`` engine runs (refuses a sweep that cannot fit).
    workspace : Workspace, optional
        The solve's workspace: the ``direct`` engine keeps its band plan, its band along
        lambda and its last factors there for the solve at the chosen lambda.

    Returns
    -------
    LambdaCurve

    Notes
    -----
    Each of ``curve.warnings`` is issued once through :mod:`warnings` (a
    :class:`bvpnav.log.BvpnavWarning`, attributed to the caller's line); the chosen lambdas
    are logged at INFO on ``bvpnav.lam.sweep``.
    """
    with once():
        return _sweep_curve(form, rules, rule, lam_range, points, tau, probes, seed, progress, engine,
                            solve_at, check_memory, workspace)


def _sweep_curve(form: Formulation, rules, rule, lam_range, points, tau, probes, seed, progress, engine,
                 solve_at, check_memory, workspace) -> LambdaCurve:
    t0 = time.perf_counter()
    asked = set([rule, *(rule_names() if rules is None else rules)])
    for r in asked:
        get_rule(r)
    names = [r for r in rule_names() if r in asked]  # the registry's order, whatever was asked
    if not form.has_soft_terms:
        raise InputError("choosing lambda needs at least one soft (or robust) item weighted by lambda; "
                         "every item is hard, so lambda has no effect: pass a number (e.g. lam=1)")
    ls = non_least_squares_term(form) is None
    if engine == "auto":
        engine = "direct" if ls else "cvxpy"
    if engine == "direct" and not ls:
        raise InputError("engine='direct' needs a least-squares problem (no band, robust or "
                         "inequality items); use engine='cvxpy'")
    names = _usable_rules(form, names, rule, engine)
    lo, hi = _check_range(lam_range, DIRECT_POINTS if points is None else points)
    # one sample every two decades or more only where the range spans 12 decades or more
    # (every other sample of the 13-point grid); a rule that samples coarsely
    # (bvpnav.lam.LambdaRule.coarse) is given those samples whichever rules run beside it,
    # so that ``solve(lam=rule)`` and a sweep that scores more rules (``bvpnav lcurve``)
    # choose the same lambda from the same samples and refinements
    wide = math.log10(hi / lo) >= 2.0 * (SLOPE_POINTS - 1) - 1e-9
    coarse = points is None and engine == "direct" and wide
    if points is None:
        points = CVXPY_POINTS if engine != "direct" else DIRECT_POINTS
    form.check_scales(lo)  # the sweep's extremes: every weight stays resolvable
    form.check_scales(hi)
    form.check_observability()
    if engine == "direct" and check_memory is not None:
        check_memory()
    progress = progress_enabled(progress)
    need_trace = any("trace" in get_rule(r).needs for r in names)
    if engine == "direct":
        eng = DirectSweep(form, need_trace=need_trace, probes=probes, seed=seed, tau=tau, workspace=workspace,
                          need_derivative=any(get_rule(r).uses_derivative for r in names),
                          need_quasi=any(get_rule(r).uses_derivative
                                         and getattr(get_rule(r), "reads_quasi", True) for r in names))
    else:
        if solve_at is None:
            raise InputError("the cvxpy sweep needs a solve stage (solve_at); use "
                             "bvpnav.lambda_curve(problem, ...) or problem.solve(lam=<rule>)")
        eng = CvxpySweep(form, solve_at, tau=tau)
    lams = np.geomspace(lo, hi, points)
    every = 2 if coarse else 1   # DIRECT_POINTS = 2 (SLOPE_POINTS - 1) + 1
    if coarse and all(get_rule(r).coarse for r in names):
        lams = lams[::2]   # no rule reads the samples between
        every = 1
    with sweeping():
        pts = _sweep(eng, lams, progress)
        curve = LambdaCurve(lam=lams, residual_norm=np.sqrt([p["rho2"] for p in pts]),
                            info_norm=np.sqrt([p["eta2"] for p in pts]), rule=rule, engine=eng.engine,
                            lam_range=lam_range)
        s = np.log(lams)
        for name in names:
            r = get_rule(name)
            curve.scores[name] = r.scores(eng, pts, s)
            step = every if r.coarse else 1
            sub = curve.scores[name] if step == 1 else r.scores(eng, pts[::step], s[::step])
            curve.chosen[name] = float(r.refine(eng, pts[::step], s[::step], sub, _Grid(curve, step)))
        if isinstance(eng, DirectSweep):
            eng.hand_off()
    curve.evaluations = len(eng.cache)
    curve.evaluated = np.array([(q, math.sqrt(p["rho2"]), math.sqrt(p["eta2"]))
                                for q, p in sorted(eng.cache.items())]).reshape(-1, 3)
    curve.trace_method = getattr(eng, "trace_method", None)
    curve.factorization = getattr(eng, "factorization", None)
    curve.seconds = time.perf_counter() - t0
    curve.warnings[:] = list(dict.fromkeys(curve.warnings))  # each once
    log.info("lambda sweep: engine %s, %d points over lam_range=(%g, %g), %d evaluations, %.3g s; %s",
             eng.engine, len(lams), lo, hi, curve.evaluations, curve.seconds,
             ", ".join(f"{n} lam={v:.6g}" + (" (used)" if n == rule else "")
                       for n, v in curve.chosen.items()))
    for w in curve.warnings:
        _warn(w)
    return curve
