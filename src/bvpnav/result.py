"""The solution object: tidy, time-indexed results with their provenance."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
import pandas as pd

from .errors import InputError

__all__ = ["Solution", "Attempt", "Verification", "SequentialReport", "Demotion", "Timings", "Run",
           "SolveRecords", "Uncertainty", "AttitudeLoopReport", "ItemRows"]


class _Record(Mapping):
    """A typed record that also reads like the dict it replaces (``rec["status"]``,
    ``rec.get("conflicts")``); optional fields that are None are not keys."""

    _optional: tuple[str, ...] = ()

    def _keys(self) -> list[str]:
        return [f.name for f in fields(self)  # type: ignore[arg-type]
                if not (f.name in self._optional and getattr(self, f.name) is None)]

    def __getitem__(self, key: str) -> Any:
        if key in self._keys():
            return getattr(self, key)
        raise KeyError(key)

    def __iter__(self) -> Iterator[str]:
        return iter(self._keys())

    def __len__(self) -> int:
        return len(self._keys())

    def as_dict(self) -> dict[str, Any]:
        """A plain dict (what ``Solution.stats`` holds)."""
        return {k: getattr(self, k) for k in self._keys()}

    copy = as_dict


@dataclass(eq=False)
class Attempt(_Record):
    """One back end's try at one lambda.

    Attributes
    ----------
    solver : str
    status : str
        The back end's status word (``optimal``, ``infeasible``, ...), ``error`` for an
        exception, ``not applicable`` for a back end skipped (memory, problem kind),
        ``time limit`` for one stopped by ``solve(time_limit=...)``.
    reason : str
        ``verified``, ``failed verification`` or why it failed or was skipped
        (``time limit reached (X s)``).
    conflicts : list of str, optional
        The conflicting hard items, for an infeasible attempt.
    output : str, optional
        What the solver itself printed (captured when ``verbose`` is off), for a failed
        attempt that printed something.
    """

    solver: str
    status: Any
    reason: str
    conflicts: list | None = None
    output: str | None = None
    _optional = ("conflicts", "output")

    @staticmethod
    def plain(records) -> list[dict]:
        """Attempts as plain dicts (what exceptions carry: JSON-ready)."""
        return [Attempt.of(r).as_dict() for r in records]

    @classmethod
    def of(cls, rec) -> Attempt:
        """An :class:`Attempt` from a back end's dict (or an Attempt itself)."""
        if isinstance(rec, Attempt):
            return rec
        return cls(solver=rec["solver"], status=rec.get("status"), reason=rec.get("reason", ""),
                   conflicts=rec.get("conflicts"), output=rec.get("output"))


@dataclass(eq=False)
class Verification(_Record):
    """bvpnav's own judgement of an answer (see :func:`bvpnav.solve.verify.verify`).

    Attributes
    ----------
    fem_residual : float
        Largest FEM residual relative to the size of the terms that cancel in it.
    max_violation : float
        Largest relative violation over hard, band and inequality items.
    worst_item : str or None
    stationarity : float or None
        Relative norm of the Lagrangian gradient (None: non-smooth or no duals).
    forward_error : float or None
        Estimated relative forward error (least-squares problems): one refinement step on
        the augmented system, or, for the direct back ends, the size of their own last
        refinement step when it meets the preset (an upper estimate of the answer's).
    rtol : float
        The tolerance of the accuracy preset.
    nonfinite : list of str
        What is NaN or infinite in the answer.
    undetermined : list of str
        Error-model parameters the information leaves undetermined (named in warnings).
    conditioning : dict or None
        See :func:`bvpnav.solve.conditioning.assess_conditioning`.
    verified : bool
    """

    fem_residual: float
    max_violation: float
    worst_item: str | None
    stationarity: float | None
    forward_error: float | None
    rtol: float
    nonfinite: list
    undetermined: list
    conditioning: dict | None
    verified: bool


@dataclass(eq=False)
class SequentialReport(_Record):
    """What the sequential convex loop did (see :func:`bvpnav.solve.sequential.with_sequential`).

    Attributes
    ----------
    iterations : int
        All phases.
    max_change, rms_change : list of float
        Largest and RMS nodal position change per iteration, m.
    mode : list of str
        Per iteration ``"soft"`` (continuation) or ``"final"``.
    sigma : list of dict
        Per iteration: item label -> continuation sigma, m.
    phases : list of dict
        ``mode``, ``iterations``, ``tol``, ``converged`` per phase.
    continued : list of str
        Items iterated soft first.
    converged : bool
        Of the final phase.
    tol, soft_tol : float
        Tolerances, m.
    max_iter : int
    initial : str
        Where the initial estimate came from.
    lam : list of float
        Per iteration.
    status : dict
        Per item, row status counts of the last linearization.
    seconds : float
    """

    iterations: int
    max_change: list
    rms_change: list
    mode: list
    sigma: list
    phases: list
    continued: list
    converged: bool
    tol: float
    soft_tol: float
    max_iter: int
    initial: str
    lam: list
    status: dict
    seconds: float


@dataclass(eq=False)
class AttitudeLoopReport(_Record):
    """What the damped attitude loop did (see :func:`bvpnav.solve.attitude.with_attitude`).

    Attributes
    ----------
    kind : str
        ``"attitude"``.
    iterations : list of dict
        Per linearized step: ``objective`` (before), ``trial`` (the objective at the new
        totals), ``step`` (the largest attitude change it makes over the window, rad),
        ``accepted`` and ``damping``; the last entry has ``converged=True`` when its step
        was below ``tol``.
    converged : bool
    reason : str
        Why the loop stopped: ``"step"`` (an undamped step below ``tol``; the answer is
        that step's solve), ``"objective"`` (an accepted step lowered the objective by less
        than ``ftol`` relative), ``"no descent"`` (the undamped step raised the objective
        and so did the damped ones down to ``tol``: a minimum to rounding) or
        ``"max_iter"`` (not converged). In all but ``"step"`` the answer is the last
        accepted point itself (zero increments about it).
    tol : float
        rad.
    max_iter : int
    objective_initial, objective : float
        The nonlinear objective at the start (after the heading search) and at the answer.
    heading_search : list of dict
        ``heading`` (rad) and ``objective`` of each candidate of the global start.
    solves : int
        Convex solves the loop made (evaluations and steps).
    seconds : float
    inner : SequentialReport or None
        The report of the last inner sequential loop (items that need linearization).
    heading : str or None
        What the heading search found: ``"searched"`` (the best candidate is the start) or
        ``"unobservable"`` (the candidates cannot differ: the given heading is kept, with
        a warning); None (not a key) without a search.
    held : list of str or None
        Gyro-bias parameters the loop held at their prior because nothing carried heading
        information (the yaw-rate bias; with a warning); None (not a key) when none.
    objective_parts : dict or None
        ``initial`` (the start: the attitude as the data give it, after the heading search)
        and ``answer``: the objective's parts there, ``motion`` (the data rows and the items
        the fixed-attitude solve fits), ``gyro_items`` (items on the attitude models alone,
        e.g. ZeroAngularRate) and ``priors``.
    full_passes, cheap_steps : int or None
        Node states (``kind="states"``): the steps made from every sample (full passes) and the
        cheap ones made from a full pass's per-element sums
        (:func:`bvpnav.error_models.error_states.cheap_at`); None (not keys) otherwise.
    """

    kind: str
    iterations: list
    converged: bool
    reason: str
    tol: float
    max_iter: int
    objective_initial: float
    objective: float
    heading_search: list
    solves: int
    seconds: float
    inner: Any = None
    heading: str | None = None
    held: list | None = None
    objective_parts: dict | None = None
    full_passes: int | None = None
    cheap_steps: int | None = None

    _optional = ("inner", "heading", "held", "objective_parts", "full_passes", "cheap_steps")

    def as_dict(self) -> dict[str, Any]:
        out = super().as_dict()
        if self.inner is not None:
            out["inner"] = self.inner.as_dict()
        return out


@dataclass(eq=False)
class Demotion(_Record):
    """A hard item made soft because it conflicted with others.

    Attributes
    ----------
    item : str
    sigma : float
        Its new standard deviation, item units.
    priority : float
    conflict : list of str
        The conflicting set it was taken from.
    """

    item: str
    sigma: float
    priority: float
    conflict: list


@dataclass(eq=False)
class Timings(_Record):
    """Where the time of the winning attempt went, s (None where a back end does not say).

    Attributes
    ----------
    compile_time : float or None
        cvxpy's compilation of the problem (0 for the direct back ends).
    setup_time, solve_time : float or None
        The solver's own setup and solve.
    cvxpy_time : float or None
        The whole ``Problem.solve`` call (cvxpy back ends).
    wall_time : float
        The whole attempt, back-end call to answer.
    """

    compile_time: float | None = None
    setup_time: float | None = None
    solve_time: float | None = None
    cvxpy_time: float | None = None
    wall_time: float | None = None
    _optional = ("cvxpy_time",)


#: Keys of a back end's measurements that are timings.
_TIMING_KEYS = ("compile_time", "setup_time", "solve_time", "cvxpy_time", "wall_time")


@dataclass(eq=False)
class Run(_Record):
    """The winning back end's run.

    Attributes
    ----------
    solver : str
    status : str
        The back end's own status word.
    accuracy : str
    options : dict
        The options in force (preset plus the user's).
    preset_applied : bool
        Whether bvpnav had a preset for this back end and accuracy.
    iterations : int or None
    objective : float or None
    timings : Timings
    solver_warnings : list of str
    details : dict
        Back-end specific measurements (e.g. ``refinements``, ``correction``,
        ``factorization`` of the direct back end).
    """

    solver: str
    status: Any
    accuracy: str = "default"
    options: dict = field(default_factory=dict)
    preset_applied: bool = True
    iterations: Any = None
    objective: Any = None
    timings: Timings = field(default_factory=Timings)
    solver_warnings: list = field(default_factory=list)
    details: dict = field(default_factory=dict)

    @classmethod
    def of(cls, info: dict) -> Run:
        """A :class:`Run` from a back end's measurements (``RawSolve.info``) plus ``solver``,
        ``accuracy``, ``options``, ``preset_applied`` and ``wall_time``."""
        known = {"solver", "status", "accuracy", "options", "preset_applied", "iterations", "objective",
                 "solver_warnings", *_TIMING_KEYS}
        return cls(solver=info["solver"], status=info.get("status"), accuracy=info.get("accuracy", "default"),
                   options=dict(info.get("options") or {}), preset_applied=info.get("preset_applied", True),
                   iterations=info.get("iterations"), objective=info.get("objective"),
                   timings=Timings(**{k: info[k] for k in _TIMING_KEYS if k in info}),
                   solver_warnings=list(info.get("solver_warnings", [])),
                   details={k: v for k, v in info.items() if k not in known})

    def flat(self) -> dict[str, Any]:
        """The run as the flat keys of ``Solution.stats`` (timings and details inline)."""
        out = {k: getattr(self, k) for k in ("solver", "status", "accuracy", "options", "preset_applied",
                                             "iterations", "objective", "solver_warnings")}
        out.update(self.timings.as_dict())
        out.update(self.details)
        return out


@dataclass(eq=False)
class Uncertainty(_Record):
    """How the standard deviations of a solution were obtained and what they mean.

    Attributes
    ----------
    scale : str
        ``"stated"``: the covariance of the weights as given (the posterior covariance
        when ``lam = 1`` and every sigma is the true noise); ``"scaled"``: multiplied by
        ``variance_factor``.
    variance_factor : float
        A-posteriori variance factor: the weighted residual sum of squares over ``dof``
        (about 1 when the stated sigmas are right).
    dof : int
        Degrees of freedom: objective rows minus unknowns plus hard rows.
    model : str
        ``"exact"`` (least squares), ``"quadratic model"`` (robust, band or inequality
        items: the quadratic model at the solution, an approximation) or ``"last
        linearization"`` (items linearized by the sequential loop).
    method : str
        How the covariance was computed.
    border : int
        Unknowns handled through the Schur complement.
    block : int
        Size of the node blocks.
    hard_rows_in_border : int
        Hard-item rows taken through the Schur complement because a run of nodes was
        singular with them (0 normally; the covariance is exact either way).
    border_condition, pivot_condition : float
        Equilibrated condition numbers of the border's Schur complement and the worst
        block pivot (above :data:`bvpnav.linalg.covariance.BORDER_COND_WARN` the solution warns).
    time : float
        Seconds spent.
    unscalable : str, optional
        Why a scaled uncertainty could not be scaled meaningfully: ``"0 degrees of
        freedom"`` (the variance factor is undefined; the standard deviations are the
        stated ones, ``scale`` says ``"stated"``) or ``"exact fit"`` (the variance factor
        is about 0, so are the scaled standard deviations). Not a key otherwise.
    """

    scale: str
    variance_factor: float
    dof: int
    model: str
    method: str
    border: int
    block: int
    hard_rows_in_border: int
    border_condition: float
    pivot_condition: float
    time: float
    unscalable: str | None = None
    _optional = ("unscalable",)


@dataclass(eq=False)
class SolveRecords:
    """The typed records the solve stages return; ``Solution.stats`` is built from them.

    Attributes
    ----------
    run : Run or None
        The winning back end's run (status, iterations, timings, options in force).
    attempts : list of Attempt
    verification : Verification or None
    sequential : SequentialReport or None
    demoted : list of Demotion or None
    uncertainty : Uncertainty or None
    plausibility : dict or None
        The misfit numbers and limits of :func:`bvpnav.solve.plausibility.assess`.
    data_checks : dict or None
        The input checks of the data solved (``ImuData.checks``: the frame and gravity
        check, the gyro saturation count), each with its ``warning``.
    grade : dict or None
        The sensor grade whose figures filled in missing error-model priors: ``name``,
        ``filled`` (one line per prior) and ``figures``
        (:attr:`bvpnav.formulation.Formulation.grade_report`); None when none were.
    gating : dict or None
        The gating stage's counts (passes, fixes judged and rejected, settled); None when
        no item has a gate.
    """

    run: Run | None = None
    attempts: list = field(default_factory=list)
    verification: Verification | None = None
    sequential: SequentialReport | None = None
    demoted: list | None = None
    uncertainty: Uncertainty | None = None
    attitude: AttitudeLoopReport | None = None
    plausibility: dict | None = None
    data_checks: dict | None = None
    grade: dict | None = None
    gating: dict | None = None

    def stats(self) -> dict[str, Any]:
        """The ``Solution.stats`` dict (plain values: it is written to JSON by batch runs)."""
        out = self.run.flat() if self.run is not None else {}
        if self.verification is not None:
            out["verification"] = self.verification.as_dict()
            out["verified"] = self.verification.verified
            if self.verification.conditioning is not None:
                out["conditioning"] = self.verification.conditioning
        out["attempts"] = [a.as_dict() for a in self.attempts]
        if self.attitude is not None:
            out["sequential"] = self.attitude.as_dict()
        elif self.sequential is not None:
            out["sequential"] = self.sequential.as_dict()
        if self.demoted is not None:
            out["demoted"] = [d.as_dict() for d in self.demoted]
        if self.uncertainty is not None:
            out["uncertainty"] = self.uncertainty.as_dict()
        if self.plausibility is not None:
            out["plausibility"] = dict(self.plausibility)
        if self.data_checks:
            out["data_checks"] = dict(self.data_checks)
        if self.gating is not None:
            out["gating"] = dict(self.gating)
        if self.grade is not None:
            out["grade"] = {"name": self.grade["name"], "filled": list(self.grade["filled"]),
                            "figures": dict(self.grade["figures"])}
        return out


@dataclass(eq=False)
class ItemRows:
    """What a solution knows about each residual row of one item (or prior), for reports.

    Attributes
    ----------
    t : ndarray
        Time of each row, s (NaN where the row has no single time, e.g. a prior on
        error-model parameters or a cone's group).
    labels : sequence of str or None
        Row labels (``"x(t=12)"``), made on demand.
    mode : str
        ``hard``, ``soft``, ``robust`` or ``band``.
    kind : str
        ``equality``, ``inequality`` or ``cone``.
    units : str
        Units of the residual rows.
    sigma : ndarray or None
        Standard deviation per row (soft and robust), item units.
    huber : float or None
        Huber threshold (robust), item units; None with an L1 penalty.
    tol : ndarray or None
        Band half-width per row (band), item units.
    """

    t: np.ndarray
    labels: Any
    mode: str
    kind: str
    units: str
    sigma: np.ndarray | None = None
    huber: float | None = None
    tol: np.ndarray | None = None

    def label(self, i: int) -> str:
        """The label of row ``i`` (``"row i"`` without labels)."""
        if self.labels is not None and len(self.labels) == len(self.t):
            return str(self.labels[i])
        return f"row {i}"


@dataclass(eq=False)
class Solution:
    """A verified trajectory and everything needed to judge it.

    Attributes
    ----------
    trajectory : pandas.DataFrame
        Index ``t`` (s). Columns ``x``, ``y``, ``z`` (positions, m) and ``vx``, ``vy``,
        ``vz`` (velocities, m/s) for the axes present (named after the data's axes);
        with ``solve(uncertainty=...)`` also ``x_std``, ... (m) and ``vx_std``, ... (m/s).
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
        accuracy preset, verification measures and the attempts made (built from
        :attr:`records`).
    x : ndarray
        The stacked solution vector (see :class:`bvpnav.model.NavModel`).
    warnings : list of str
    curve : LambdaCurve or None
        The lambda sweep, when a rule chose ``lam``.
    records : SolveRecords
        The typed records of the solve (attempts, verification, sequential report,
        demotions, the winning run's measurements, the uncertainty).
    error_params_std : pandas.Series
        Standard deviations of :attr:`error_params` (same units; first order in the
        reported parametrization), with ``solve(uncertainty=...)``; else empty.
    attitude : scipy.spatial.transform.Rotation or None
        For strapdown data, the body-to-navigation attitude per sample the answer uses:
        corrected by the attitude error models' estimates when there are any, else the
        data's. None for navigation-frame data. See :attr:`attitude_angles`.
    formulation : Formulation or None
        The :class:`~bvpnav.formulation.Formulation` the answer solves (read-only): the
        problem's own, or the one a solve stage made from it (conflicting items demoted,
        nonlinear items at their last linearization, the attitude at its estimate).
    error_states : pandas.DataFrame or None
        With node states (:class:`~bvpnav.error_models.ErrorStates`): their totals per
        sample (index ``t (s)``; columns ``attitude_error_x (rad)``, ``gyro_bias_x (rad/s)``,
        ``acc_bias_x (m/s^2)``, ...).
    error_states_std : pandas.DataFrame or None
        Their standard deviations (same columns), with ``solve(uncertainty=...)``.
    attitude_data : scipy.spatial.transform.Rotation or None
        For strapdown data, the data's own attitude before any correction (see
        :attr:`attitude_corrections`).
    item_rows : dict of str to ItemRows
        Per item (the keys of :attr:`item_residuals`): each row's time, label, mode and
        sigma (what :mod:`bvpnav.report` needs for normalized residuals).
    sigma_a : ndarray or None
        The accelerometer noise per axis, m/s^2, of the acceleration form (None for the
        load form); ``sigma_a_given`` says whether it was stated or is the default.
    rejected : pandas.DataFrame or None
        The fixes rejected by gating (items with ``gate``, :mod:`bvpnav.solve.gating`): one
        row per fix with the item, ``t`` (s), ``value_<axis>``, ``residual_<axis>`` (item
        units), ``normalized`` (the normalized residual), ``gate`` and ``pass``; empty when
        every fix was kept, None when no item has a gate.

    Examples
    --------
    A solution's trajectory is a table indexed by time (s), with positions (m) and
    velocities (m/s) per axis:

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position, Velocity
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.full(11, 2.0)))
    >>> sol = prob.add(Position(t=0.0, value=0.0), Velocity(t=0.0, value=0.0)).solve(solver="direct")
    >>> print(sol.trajectory.tail(2).round(3))
            x   vx
    t
    0.9  0.81  1.8
    1.0  1.00  2.0
    >>> sol.lam, sol.stats["solver"], sol.stats["status"]
    (1.0, 'direct', 'optimal')
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
    records: SolveRecords = field(default_factory=SolveRecords)
    error_params_std: pd.Series = field(default_factory=lambda: pd.Series(dtype=float, name="std"))
    attitude: Any = None
    attitude_data: Any = None
    error_states: Any = None
    error_states_std: Any = None
    item_rows: dict = field(default_factory=dict, repr=False)
    sigma_a: np.ndarray | None = None
    sigma_a_given: bool = False
    rejected: pd.DataFrame | None = None
    _cov: dict = field(default_factory=dict, repr=False)
    _formulation: Any = field(default=None, repr=False, compare=False)

    @property
    def formulation(self):
        """The :class:`~bvpnav.formulation.Formulation` the answer solves (see the class
        Attributes; None for a solution made without one)."""
        return self._formulation

    @property
    def attitude_corrections(self) -> pd.DataFrame | None:
        r"""The correction the solve applied to the data's attitude, per sample (None
        without strapdown data).

        Columns ``x``, ``y``, ``z``: the rotation vector of :math:`C\,C_0^T` (navigation
        frame, rad), :math:`C` the attitude used (:attr:`attitude`) and :math:`C_0` the
        data's (:attr:`attitude_data`); ``angle``: its size, rad. All zero when no attitude
        error model was estimated.
        """
        if self.attitude is None or self.attitude_data is None:
            return None
        rv = (self.attitude * self.attitude_data.inv()).as_rotvec()
        return pd.DataFrame({"x": rv[:, 0], "y": rv[:, 1], "z": rv[:, 2],
                             "angle": np.linalg.norm(rv, axis=1)}, index=self.trajectory.index.copy())

    def report(self, path, items=None, truth=None, title: str | None = None) -> None:
        """Write a self-contained HTML quality report of this solution (see
        :func:`bvpnav.report.write_report`)."""
        from .report import write_report

        write_report(self, path, items=items, truth=truth, title=title)

    @property
    def attitude_angles(self) -> pd.DataFrame | None:
        r"""Roll, pitch and yaw of :attr:`attitude` per sample, degrees (None without one).

        Notes
        -----
        :math:`C = R_z(\text{yaw})\, R_y(\text{pitch})\, R_x(\text{roll})` (body to
        navigation; scipy's ``as_euler("ZYX")``): in the ENU frame with body axes
        forward-left-up, yaw is the heading counterclockwise from east about up; in NED
        with forward-right-down, the aerospace angles (yaw clockwise from north).
        """
        if self.attitude is None:
            return None
        ypr = np.degrees(self.attitude.as_euler("ZYX"))
        return pd.DataFrame({"roll_deg": ypr[:, 2], "pitch_deg": ypr[:, 1], "yaw_deg": ypr[:, 0]},
                            index=self.trajectory.index.copy())

    def covariance(self, what: str = "error_params"):
        """A covariance computed by ``solve(uncertainty=...)``.

        Parameters
        ----------
        what : {"error_params", "state"}
            ``"error_params"``: a DataFrame over the reported error-model parameters
            (their units squared). ``"state"``: an ndarray of shape (N, 2 d, 2 d), per
            sample the covariance of the positions then the velocities in the order of
            the axes (m^2, m^2/s, m^2/s^2).

        Raises
        ------
        InputError
            Without ``uncertainty`` in the solve, or for another ``what``.
        """
        if not self._cov:
            raise InputError("covariance(): this solution has none; solve with uncertainty=True "
                             "(or 'scaled')")
        if what not in self._cov:
            raise InputError(f"covariance({what!r}): choose one of {sorted(self._cov)}")
        out = self._cov[what]
        return out.copy()

    def record(self, **records) -> Solution:
        """Set typed records (``attempts=``, ``sequential=``, ``demoted=``, ...) and
        rebuild :attr:`stats` from them; returns the solution."""
        for k, v in records.items():
            setattr(self.records, k, v)
        self.stats.clear()
        self.stats.update(self.records.stats())
        return self

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
        return [c for c in self.trajectory.columns if not c.startswith("v") and not c.endswith("_std")]

    @property
    def t(self) -> np.ndarray:
        """Sample times, s."""
        return self.trajectory.index.to_numpy()

    def rms_error(self, truth: np.ndarray) -> float:
        """RMS position error (m) against true positions of shape (N,) or (N, d).

        Examples
        --------
        >>> import numpy as np
        >>> import bvpnav
        >>> t = np.linspace(0.0, 2.0, 21)
        >>> data = bvpnav.ImuData(t=t, acc=np.full(21, 0.5))  # 0.5 m/s^2 for 2 s
        >>> from bvpnav.constraints import Position
        >>> prob = bvpnav.NavigationProblem(data).add(Position(t=[0.0, 2.0], value=[0.0, 3.0]))
        >>> sol = prob.solve(solver="direct")
        >>> bool(sol.rms_error(t + 0.25 * t**2) < 1e-9)  # the truth r = t + t^2/4 (m)
        True
        """
        shape = self.position().shape
        try:
            truth = np.asarray(truth, dtype=float).reshape(shape)
        except (TypeError, ValueError) as exc:
            raise InputError(f"rms_error(truth): truth of shape {np.shape(truth)} does not match the "
                             f"solution's positions {shape} (N samples x axes {self._pos_cols}); give "
                             "true positions in m at the sample times") from exc
        return float(np.sqrt(np.mean((self.position() - truth) ** 2)))

    def __repr__(self) -> str:
        """A few lines: samples and window, axes; lambda and its rule; solver, status and
        verification; the RMS residual of the first items (item units); the first error-model
        estimates; how many warnings."""
        s = self.stats
        t = self.t
        window = f" ({t[0]:g} .. {t[-1]:g} s)" if len(t) else ""
        verified = {True: "verified", False: "NOT verified"}.get(s.get("verified"), "verification unknown")
        lines = [f"Solution: {len(self.trajectory)} samples{window}, axes {', '.join(self._pos_cols)}",
                 f"  lam = {self.lam:.4g} ({self.lam_rule}); solver {s.get('solver')}: {s.get('status')}, "
                 f"{verified}"]
        if len(self.items):
            parts = []
            for r in self.items.head(4).itertuples(index=False):
                rms = getattr(r, "rms", float("nan"))
                parts.append(f"{r.item} {r.mode} {rms:.2g} {r.units}")
            more = f", ... {len(self.items) - 4} more" if len(self.items) > 4 else ""
            lines.append("  item residuals (rms): " + ", ".join(parts) + more)
        if s.get("grade"):
            lines.append(f"  sensor grade assumed: {s['grade']['name']} (priors filled in: "
                         + "; ".join(s["grade"]["filled"]) + ")")
        if len(self.error_params):
            ep = self.error_params
            more = f", ... {len(ep) - 4} more" if len(ep) > 4 else ""
            est = ", ".join(f"{k} = {v:.4g}" for k, v in ep.head(4).items())
            lines.append(f"  error model: {est}{more}")
        if self.rejected is not None and len(self.rejected):
            lines.append(f"  {len(self.rejected)} fix(es) rejected by gating: see .rejected")
        if self.warnings:
            lines.append(f"  {len(self.warnings)} warning(s): see .warnings")
        return "\n".join(lines)
