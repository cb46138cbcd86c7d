"""NavigationProblem: the user's face of a problem: add information, look at it, solve it.

The problem holds the data, the objective form, the error model and the items the user
adds. What the problem *is* lives below it (:class:`~bvpnav.formulation.Formulation`:
items compiled to terms; :mod:`bvpnav.cvx`: the DPP cvxpy problem); how it is *solved*
lives in :mod:`bvpnav.solve`; this class hands off to them (imported on first use, so that
``import bvpnav`` loads no factorization, lambda rule or their scipy subpackages).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from .cvx import CvxProblem, compiled
from .declare import solve_parameters_doc, solve_signature
from .formulation import Formulation, label_items, original
from .imu import ImuData
from .items import Item
from .model import Affine, NavModel
from .result import Solution, Verification
from .sensors import DEFAULT_GRADE
from .terms import Term

if TYPE_CHECKING:
    from .describe import Matrices

__all__ = ["NavigationProblem"]


class NavigationProblem:
    r"""Accelerations plus additional information, posed as one convex problem.

    Parameters
    ----------
    data : ImuData
        Sample times and accelerations.
    residual : {"acceleration", "load"}
        Objective form. ``"acceleration"`` (default) penalises the acceleration
        residual, :math:`\sum_i \|w_i\|^2 / \sigma_a^2` (the MAP estimate for white
        accelerometer noise of standard deviation ``sigma_a``); ``"load"`` penalises the
        FEM load residual :math:`\|K r - f(\hat a) - F l\|^2`, the 2011 paper's
        Tikhonov form.
    sigma_a : float or array_like, optional
        Accelerometer noise standard deviation in m/s^2, for the acceleration form: a
        scalar, one per axis (d,), one per sample (N,) or one per sample and axis (N, d)
        (e.g. a large value at samples clipped at the sensor's range or hit by an impact).
        Default 1 m/s^2 (then ``lam`` absorbs the scale).
    error_model : ErrorModel, optional
        Sensor error model contributing unknown parameters (see
        :mod:`bvpnav.error_models`).
    items : iterable of Item, optional
        Initial items; more can be added with :meth:`add`.
    grade : str or SensorGrade or None
        The sensor's grade (:mod:`bvpnav.sensors`: ``"consumer"``, ``"tactical"``,
        ``"navigation"`` or :func:`~bvpnav.sensors.from_datasheet`). On strapdown data
        whose error model has gyro parameters (``GyroBias``, ``AttitudeError``) and
        states no prior at all (no ``sigma``, ``prior``, ``drift`` or ``bounds`` on any
        part), the priors of ``Bias``, ``GyroBias`` and ``AttitudeError`` are this
        grade's figures (:meth:`~bvpnav.sensors.SensorGrade.complete`); the solution
        says so (``sol.stats["grade"]`` and its summary). Default ``"consumer"``, the
        loosest preset; None assumes nothing (a model without priors may then be
        refused as undetermined when the fixes are sparse).
    segment : float, optional
        Solve on a coarse FEM mesh (:mod:`bvpnav.mesh`), s: the positions are unknowns at the
        items' instants and at enough samples that no element is longer than ``segment``
        seconds; the samples between nodes (their accelerations, error-model columns and
        acceleration residuals) are condensed onto the nodes exactly, the analogue of a factor
        graph's preintegration. The answer at the nodes is that of the problem on every
        sample, and the solution still has every sample (recovered from the nodes). Needs
        ``residual="acceleration"``; items that evaluate every sample of an interval get those
        samples as nodes; items whose instants are known only when compiled and the knot
        attitude loop's error models are refused on a mesh. Body-frame items
        (``NonHolonomic``, ``ForwardMotion``, lever arms) work with ``ErrorStates``: their soft
        rows stay at their samples inside the elements, rows held as constraints (bands, hard,
        inequalities) get nodes at their instants. None (default): every sample is a node.

    Notes
    -----
    The problem solved is

    .. math::

        \min_{r, w, v_0, v_1, l}\; J_0(w) + \lambda \sum_{k \in soft} \|(D_k x - e_k)/\sigma_k\|^2
        \quad\text{s.t.}\quad K r + B v + M(\hat a + G l + w) = 0,\; D_h x = e_h,

    with :math:`J_0 = \|w / \sigma_a\|^2` or :math:`\|M w\|^2` (= :math:`\|K r + Bv - f\|^2`).
    Robust items use the Huber function or L1 in place of the square; band items add
    :math:`|D x - e| \le tol`; inequality items add :math:`g(x) \le 0`.

    Examples
    --------
    Constant acceleration 0.5 m/s^2 for 2 s between two known positions (0 m and 3 m): the
    initial velocity is :math:`(3 - 0.25 \cdot 2^2) / 2 = 1` m/s.

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> t = np.linspace(0.0, 2.0, 21)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.full(21, 0.5)))
    >>> prob.add(Position(t=[0.0, 2.0], value=[0.0, 3.0]))
    NavigationProblem(...)
    >>> sol = prob.solve(solver="direct")
    >>> print(f"v(0) = {sol.velocity('x')[0]:.3f} m/s, v(2) = {sol.velocity('x')[-1]:.3f} m/s")
    v(0) = 1.000 m/s, v(2) = 2.000 m/s
    """

    def __init__(
        self,
        data: ImuData,
        residual: str = "acceleration",
        sigma_a=None,
        error_model=None,
        items: Iterable[Item] = (),
        grade: Any = DEFAULT_GRADE,
        segment: float | None = None,
    ):
        self.data = data
        self._base = Formulation(data, residual=residual, sigma_a=sigma_a, error_model=error_model,
                                 grade=grade, segment=segment)
        self._items: list[Item] = []
        self._form: Formulation | None = None
        self._model: NavModel | None = None
        for it in items:
            self.add(it)

    def _redefine(self, **change) -> None:
        """The definition with ``change`` (checked by :class:`Formulation`); caches dropped."""
        kw = dict(residual=self.residual, sigma_a=self.sigma_a if self.sigma_a_given else None,
                  error_model=self._base.error_model_given, grade=self._base.grade,
                  segment=self._base.segment)
        self._base = Formulation(self.data, **{**kw, **change})
        self._form, self._model = None, None

    residual = property(lambda self: self._base.residual, lambda self, v: self._redefine(residual=v),
                        doc="The objective form; setting it (checked) starts a new formulation.")
    sigma_a = property(lambda self: self._base.sigma_a, lambda self, v: self._redefine(sigma_a=v),
                       doc="Accelerometer noise per axis, m/s^2; setting it (checked) starts a new "
                           "formulation.")
    error_model = property(lambda self: self._base.error_model,
                           lambda self, v: self._redefine(error_model=v),
                           doc="The sensor error model (None for none); setting it starts a new formulation.")
    grade = property(lambda self: self._base.grade, lambda self, v: self._redefine(grade=v),
                     doc="The sensor grade whose figures fill in missing error-model priors (None: none).")
    segment = property(lambda self: self._base.segment, lambda self, v: self._redefine(segment=v),
                       doc="The longest coarse-mesh element, s (None: every sample a node); setting it "
                           "(checked) starts a new formulation.")
    grade_report = property(lambda self: self._base.grade_report,
                            doc="The grade and the priors it filled in, or None when nothing was.")
    sigma_a_given = property(lambda self: self._base.sigma_a_given,
                             doc="Whether ``sigma_a`` was stated (else 1 m/s^2; ``lam`` absorbs the scale).")

    def __getstate__(self) -> dict:
        """The problem's definition without its caches (cvxpy's compiled problem holds
        solver objects that cannot be pickled; the rest is cheap to rebuild)."""
        state = dict(self.__dict__)
        state.update(_form=None, _model=None)
        return state

    def add(self, *items: Item) -> NavigationProblem:
        """Add one or more items; returns the problem for chaining.

        An unnamed item whose class label is taken is labelled ``Class#k`` (the item
        itself is not changed); a second item with the same explicit ``name`` is refused.

        Examples
        --------
        Items are added in place, and the problem is returned, so calls chain:

        >>> import numpy as np
        >>> import bvpnav
        >>> t = np.linspace(0.0, 2.0, 21)
        >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
        >>> from bvpnav.constraints import Position, Velocity
        >>> prob = bvpnav.NavigationProblem(data)
        >>> prob.add(Position(t=0.0, value=0.0)).add(Velocity(t=0.0, value=0.0)) is prob
        True
        >>> prob.item_labels
        ['Position', 'Velocity']
        """
        self._items.extend(label_items(items, self.item_labels))
        self._form = None
        return self

    def with_items(self, items: Iterable[Item], error_model: bool = True) -> NavigationProblem:
        """The same data, objective form and sigma_a with other items (their labels kept).

        With ``error_model=True`` the copy also keeps the error model and shares this
        problem's :class:`NavModel` (the same unknowns and FEM matrices); without it the
        copy has no error-model parameters.
        """
        new = NavigationProblem(self.data, residual=self.residual,
                                sigma_a=self.sigma_a if self.sigma_a_given else None,
                                error_model=self.error_model if error_model else None, items=items,
                                grade=self._base.grade, segment=self._base.segment)
        if error_model and self._base.segment is None:
            new._model = self._model
        return new

    @property
    def formulation(self) -> Formulation:
        """What the problem is now: an immutable :class:`Formulation` of its items."""
        if self._form is None:
            self._form = Formulation(self.data, self.residual, self.sigma_a if self.sigma_a_given else None,
                                     self._base.error_model_given, self._items,
                                     model=self._model if self._base.segment is None else None,
                                     grade=self._base.grade, segment=self._base.segment)
        if self._model is None:
            self._model = self._form.model
        return self._form

    @property
    def items(self) -> list[Item]:
        """The items in the order they were added."""
        return [original(i) for i in self._items]

    @property
    def item_labels(self) -> list[str]:
        """Unique labels of the items (``Class`` or ``Class#k``)."""
        return [i.label for i in self._items]

    @property
    def model(self) -> NavModel:
        """The :class:`NavModel` (unknowns and their maps), built on first use."""
        return self.formulation.model

    def terms(self) -> list[Term]:
        """Every item compiled (once) into :class:`~bvpnav.terms.Term` objects."""
        return self.formulation.terms()

    def data_rows(self) -> Affine:
        """Rows whose sum of squares is the data term ``J_0`` (see class Notes)."""
        return self.formulation.data_rows()

    def build(self) -> CvxProblem:
        """The cvxpy problem (built once; see :class:`bvpnav.cvx.CvxProblem`): ``problem``,
        ``lam`` (the Parameter), ``x``, ``fem``, ``fem_rows``, ``cons``, ``penalties``."""
        return compiled(self.formulation)

    @property
    def has_soft_terms(self) -> bool:
        """True when ``lam`` multiplies at least one term."""
        return self.formulation.has_soft_terms

    # ------------------------------------------------------ teaching
    def describe(self, format: str = "text", lam: float | None = None, conditioning: bool = True) -> str:
        """The assembled problem in readable mathematics, as plain text or LaTeX lines, with
        ``lam`` (default: the current value) and a KKT condition estimate (see
        :func:`bvpnav.describe.describe` for the parameters).

        Examples
        --------
        >>> import numpy as np
        >>> import bvpnav
        >>> t = np.linspace(0.0, 2.0, 21)
        >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
        >>> from bvpnav.constraints import Position
        >>> prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 2.0], value=[0.0, 3.0]))
        >>> print(prob.describe())
        bvpnav problem: N = 21 samples on [0, 2] s (h = 0.1 s); axes: x; residual form: acceleration
        unknowns x (44 entries):
          r_x  (21)  nodal positions, m
          w_x  (21)  acceleration residuals, m/s^2
          v0_x, v1_x  end velocities, m/s
        hard constraints:
          FEM (21 rows): K r + e_1 v_0 - e_N v_1 + M (a_hat + w) = 0
          Position [hard, 2 rows]: r(t_k) - p_k = 0 at 2 instant(s)  (= 0)
        ...
        """
        from .describe import describe

        return describe(self.formulation, format=format, lam=lam, conditioning=conditioning)

    def matrices(self) -> Matrices:
        """The assembled matrices for a solve by hand (see :func:`bvpnav.describe.matrices`)."""
        from .describe import matrices

        return matrices(self.formulation)

    def unobservable(self) -> list[str]:
        """Names of unknown directions that no item pins down (empty when all are; see
        :meth:`Formulation.unobservable`).

        Examples
        --------
        >>> import numpy as np
        >>> import bvpnav
        >>> t = np.linspace(0.0, 2.0, 21)
        >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
        >>> from bvpnav.constraints import Position
        >>> prob = bvpnav.NavigationProblem(data)
        >>> prob.unobservable()  # nothing known yet: a double integral's two constants
        ['axis x: position offset', 'axis x: velocity offset']
        >>> prob.add(Position(t=[0.0, 2.0], value=[0.0, 3.0])).unobservable()
        []
        """
        return self.formulation.unobservable()

    # ------------------------------------------------------------ solving
    def solve(self, *args, **options) -> Solution:
        """Solve and verify, falling back to other back ends when an answer fails.

        Every option is checked before any work (a wrong one is named with the valid
        values) and reaches every stage of the pipeline (:mod:`bvpnav.solve.pipeline`).
        The options are declared once, in :data:`bvpnav.declare.SOLVE_OPTIONS` (the same
        checks and messages as the spec's ``[solve]`` and the command line): ``solver``
        and ``lam`` may be given by position, the rest by keyword.

        {parameters}

        Returns
        -------
        Solution

        Raises
        ------
        InputError
            Before solving: a wrong or unknown option, a weight double precision cannot
            resolve, information that leaves unknowns free, or a memory estimate beyond
            the available memory (naming what would fit).
        SolveError
            (``Infeasible``, ``Unbounded``, ``Inaccurate``) when every attempt failed;
            ``error.attempts`` lists each. A back end's own exception (``LinAlgError``,
            ``MemoryError``, ...) is a failed attempt, then the next back end runs.
        """
        from .solve import pipeline

        if len(args) > 2:
            raise TypeError(f"solve() takes solver and lam by position, the rest by keyword; got {len(args)} "
                            "positional arguments")
        for name, value in zip(("solver", "lam"), args, strict=False):
            if name in options:
                raise TypeError(f"solve() got {name} both by position and by keyword")
            options[name] = value
        return pipeline.solve(self.formulation, **options)

    solve.__signature__ = solve_signature()  # type: ignore[attr-defined]
    solve.__doc__ = solve.__doc__.replace("{parameters}", solve_parameters_doc().lstrip())

    def verify(self, xval: np.ndarray, lam: float, accuracy: str = "default", duals: dict | None = None,
               factored: tuple | None = None) -> Verification:
        """Judge a stacked solution by recomputed residuals: a :class:`~bvpnav.result.Verification`
        (see :func:`bvpnav.solve.verify.verify`)."""
        from .solve.verify import verify

        return verify(self.formulation, xval, lam, accuracy, duals, factored)

    def __repr__(self) -> str:
        return (f"NavigationProblem(N={self.data.n}, axes={list(self.data.axes)}, "
                f"residual={self.residual!r}, items={self.item_labels}, error_model={self.error_model!r})")


