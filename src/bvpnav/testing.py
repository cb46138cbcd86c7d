"""Contract checks for plug-ins: run them on your own items and error models.

In the spirit of scikit-learn's ``check_estimator``: :func:`check_item` puts an item
(a subclass of :class:`bvpnav.Item`) through every rule the framework relies on, and
:func:`check_error_model` does the same for an error model (a subclass of
:class:`bvpnav.error_models.ErrorModel`). The library runs both over every registered
plug-in in its own test suite (``tests/test_testing.py``); a plug-in author calls them
from a test of their own::

    from bvpnav.testing import check_item

    def test_my_item():
        check_item(MyItem)            # the class: its example() is checked
        check_item(MyItem(t=3.0))     # or one instance

Each check returns ``None`` when every rule holds and raises :class:`AssertionError`
otherwise, with a message naming the plug-in and the broken rule, e.g.
``item LoopClosure: rule 'frozen' broken: ...``. An exception raised by the plug-in
itself while a rule is checked is reported the same way (chained as the cause). The
checks never use ``assert`` statements, so they also work under ``python -O``.
"""

from __future__ import annotations

import dataclasses
import pickle
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import pandas as pd

from .backends import ACCURACIES, check_options, resolve_solver, solver_options
from .constraints import Position, Velocity
from .error_models import CompositeErrorModel, ErrorModel
from .error_models._base import as_error_model
from .errors import InputError
from .formulation import Formulation
from .grid import TimeGrid
from .imu import ImuData
from .items import MODES, Item, item_class
from .lam import NEEDS
from .lam.sweep import SLOPE_POINTS, CvxpySweep, DirectSweep, LambdaCurve
from .model import Affine, Cone, NavModel
from .problem import NavigationProblem
from .solve.chain import solve_fixed
from .solve.options import prepare
from .solve.verify import verify

__all__ = ["check_item", "check_error_model", "check_backend", "check_rule", "check_reader"]

#: Kinds an item may declare (``Item.kind``).
KINDS = ("equality", "inequality", "cone")


# ------------------------------------------------------------------ plumbing
def _fail(who: str, rule: str, detail: str) -> None:
    raise AssertionError(f"{who}: rule '{rule}' broken: {detail}")


def _require(ok: Any, who: str, rule: str, detail: str) -> None:
    if not ok:
        _fail(who, rule, detail)


@contextmanager
def _rule(who: str, rule: str) -> Iterator[None]:
    """Report an exception raised by the plug-in while ``rule`` is checked as a failure."""
    try:
        yield
    except AssertionError:
        raise
    except Exception as exc:  # the plug-in's own code failed: that breaks the rule
        raise AssertionError(f"{who}: rule '{rule}' broken: raised {type(exc).__name__}: {exc}") from exc


def _default_data() -> ImuData:
    """Three axes x, y, z on [0, 10] s (101 samples), accelerations that excite every axis."""
    t = np.linspace(0.0, 10.0, 101)
    acc = np.column_stack([np.sin(t), np.cos(t), 0.1 * t])
    return ImuData(t=t, acc=acc)


def _cvxpy_objects(value: Any) -> bool:
    """True if ``value`` is, or directly holds, a cvxpy expression or constraint (none can
    exist before cvxpy is imported, so this does not import it)."""
    cp = sys.modules.get("cvxpy")
    if cp is None:
        return False
    kinds = (cp.Expression, cp.Constraint)
    if isinstance(value, kinds):
        return True
    if isinstance(value, dict):
        value = list(value.values())
    if isinstance(value, list | tuple | set | frozenset):
        return any(isinstance(v, kinds) for v in value)
    return False


def _same_rows(a: Affine, b: Affine) -> bool:
    if a.A.shape != b.A.shape or a.c.shape != b.c.shape:
        return False
    if (a.A != b.A).nnz or not np.array_equal(a.c, b.c):
        return False
    if isinstance(a, Cone) or isinstance(b, Cone):
        return isinstance(a, Cone) and isinstance(b, Cone) and a.size == b.size
    return True


# ---------------------------------------------------------------------- items
#: The end-to-end solve of a band with soft edges (``mode="band"`` with a ``sigma``), beside
#: :data:`bvpnav.items.MODES`'.
SOFT_EDGES = "band with soft edges"


def _switch(item: Item, mode: str, sigma: float = 0.5) -> Item:
    """``item`` in another mode, with the weights that mode needs (and no others)."""
    if mode == SOFT_EDGES:   # a band with soft edges: the band's tol and a sigma
        return dataclasses.replace(item, mode="band", sigma=sigma, tol=0.1, huber=None)
    kw: dict[str, Any] = {"mode": mode, "sigma": None, "tol": None, "huber": None}
    if mode in ("soft", "robust"):
        kw["sigma"] = sigma
    if mode == "robust":
        kw["huber"] = 1.0
    if mode == "band":
        kw["tol"] = 0.1
    return dataclasses.replace(item, **kw)


def _check_residual(res: Any, item: Item, model: NavModel, who: str) -> None:
    """The compiled residual: type, shape, labels, finiteness (Cone groups for cones)."""
    name = type(item).__name__
    if item.kind == "cone":
        _require(isinstance(res, Cone), who, "compile returns a Cone",
                 f"{name}.kind is 'cone' but compile returned {type(res).__name__}; return "
                 "bvpnav.model.Cone(A, c, labels, size=k) (first row of each group the bound)")
    else:
        _require(isinstance(res, Affine) and not isinstance(res, Cone), who, "compile returns an Affine",
                 f"compile returned {type(res).__name__} for kind {item.kind!r}; return a "
                 "bvpnav.model.Affine (D x - e in the item's units; Cone only with kind = 'cone')")
    _require(res.m > 0, who, "residual shape", "compile returned no rows")
    _require(res.A.shape == (res.m, model.size), who, "residual shape",
             f"A has shape {res.A.shape}, expected ({res.m}, {model.size}): one column per unknown "
             "of the model (build the rows from model.position(), model.velocity(), ...)")
    _require(res.c.shape == (res.m,), who, "residual shape",
             f"c has shape {res.c.shape}, expected ({res.m},)")
    if res.labels is not None:
        _require(len(res.labels) == res.m and all(isinstance(s, str) for s in res.labels), who,
                 "residual labels", f"{len(res.labels)} labels for {res.m} rows; give one string per row "
                 "or labels=None")
    _require(np.all(np.isfinite(res.A.data)) and np.all(np.isfinite(res.c)), who, "finite residual",
             "A or c holds NaN or inf")
    if isinstance(res, Cone):
        _require(res.size >= 2 and res.groups >= 1 and res.m == res.groups * res.size, who, "cone groups",
                 f"{res.m} rows in {res.groups} group(s) of {res.size}")
        with _rule(who, "cone groups"):
            ex = res.excess(np.zeros(model.size))
        _require(ex.shape == (res.groups,) and np.all(np.isfinite(ex)), who, "cone groups",
                 f"excess() at x = 0 has shape {np.shape(ex)} (expected ({res.groups},)) or is not finite")


def _allowed_columns(model: NavModel, axes: tuple[str, ...]) -> set[int]:
    cols: set[int] = set()
    for a, ax in enumerate(model.axes):
        if ax in axes:
            cols |= set(range(a * model.block, (a + 1) * model.block))
    return cols | set(model.l_index.tolist())


def _segment(model: NavModel, item: Item) -> float | None:
    """The coarse mesh's ``segment`` (s) of a :class:`bvpnav.mesh.MeshModel` the checks solve on:
    a mesh without node states, or any mesh for an item whose rows are at its nodes
    (``rows_at_nodes``, which only a mesh has); else None (the solves, without the error model,
    are on every sample)."""
    from .mesh import MeshModel

    if not isinstance(model, MeshModel):
        return None
    if model.state_model is None or getattr(item, "rows_at_nodes", False) is True:
        return model.segment
    return None


def _other_mesh(item: Item, coarse: ImuData, model: NavModel, segment: float) -> NavModel:
    """The coarser data's mesh of the same ``segment``, with nodes at the item's own instants
    (as a problem gives them, :func:`bvpnav.mesh.item_times`) and, with node states, made by a
    problem (which gives the states their mesh)."""
    from .mesh import MeshModel, item_times
    from .problem import NavigationProblem

    t2 = coarse.t
    times = item_times([item], TimeGrid(t2))
    times = np.r_[t2[0], t2[-1], times[(times >= t2[0]) & (times <= t2[-1])]]
    if getattr(model, "state_model", None) is None:
        return MeshModel(coarse, model.error_model, segment=segment, times=times)
    prob = NavigationProblem(coarse, error_model=model.error_model, segment=segment)
    prob.add(Position(t=times, value=np.zeros((times.size, 3)), sigma=1.0, name="nodes"))
    return prob.formulation.model


def _other_model(model: NavModel, item: Item) -> NavModel:
    """The same axes and window on a coarser grid (navigation-frame accelerations; strapdown
    data with gyro rates stay strapdown, with the same error model)."""
    t = np.asarray(model.data.t, dtype=float)     # every sample (a coarse mesh's grid is its nodes)
    t2 = np.linspace(float(t[0]), float(t[-1]), max(t.size // 2 + 1, 3))
    data = model.data
    if getattr(data, "gyro", None) is not None:
        def on(v):
            return np.column_stack([np.interp(t2, t, v[:, a]) for a in range(v.shape[1])])

        coarse = ImuData.from_gyro(t2, on(data.specific_force), on(data.gyro),
                                   initial_attitude=data.attitude[0], gravity=data.gravity)
        from .mesh import MeshModel

        if isinstance(model, MeshModel):   # a coarse mesh stays a mesh (items may read its nodes)
            return _other_mesh(item, coarse, model, model.segment)
        return NavModel(coarse, model.error_model)
    acc = np.column_stack([np.interp(t2, t, data.acc[:, a]) for a in range(model.d)])
    return NavModel(ImuData(t2, acc, axes=model.axes))


def _check_other_model(item: Item, model: NavModel, res: Affine, who: str) -> None:
    """Rows follow the model they are compiled for: the item keeps nothing from one compile."""
    rule = "no state across models"
    with _rule(who, rule):
        other = _other_model(model, item)
        rows = item.compile(other)
        back = item.compile(model)
    _require(isinstance(rows, Affine) and rows.A.shape[1] == other.size, who, rule,
             f"compiled for a model of {other.size} unknowns the rows have "
             f"{getattr(getattr(rows, 'A', None), 'shape', ('?', '?'))[1]} columns: build them from the "
             "model passed to compile(), cache nothing")
    _require(isinstance(back, Affine) and _same_rows(res, back), who, rule,
             "after compiling for another model the rows for the first one changed")


def _check_body_axes(item: Item, model: NavModel, who: str) -> None:
    """An item on body axes (``body_frame``): restricted to one of its axes, its rows are those
    of that axis among the rows of all of them (a body axis mixes every navigation axis)."""
    axes = tuple(item.axes or ())
    if len(axes) < 2:
        return
    with _rule(who, "axes"):
        full = item.compile(model)
        one = dataclasses.replace(item, axes=(axes[1],))
        rows = one.compile(model)
    a = len(axes)
    _require(full.m % a == 0 and rows.m * a == full.m, who, "axes",
             f"with axes={[axes[1]]} the item has {rows.m} rows, with axes={list(axes)} {full.m}")
    pick = np.arange(1, full.m, a)
    _require(_same_rows(full.rows(pick), Affine(rows.A, rows.c)), who, "axes",
             f"with axes={[axes[1]]} the rows differ from that axis's rows with axes={list(axes)}")


def _check_axes(item: Item, model: NavModel, who: str) -> None:
    """Restricted to one axis, the rows touch that axis's unknowns (and ``l``) only."""
    if getattr(type(item), "body_frame", False):
        _check_body_axes(item, model, who)
        return
    candidates = [item]
    if item.axes is None and not type(item).__name__.startswith("_"):
        with _rule(who, "example"):
            candidates.append(type(item).example())
    for cand in candidates:
        if cand.axes is not None:
            one = cand
            with _rule(who, "axes"):
                rows = one.compile(model)
        elif model.d > 1:
            try:  # refused: values given per axis, or the item needs several axes
                one = dataclasses.replace(cand, axes=(model.axes[1],))
                rows = one.compile(model)
            except InputError:
                continue
        else:
            return
        cols = set(np.unique(rows.A.nonzero()[1]).tolist())
        outside = sorted(cols - _allowed_columns(model, tuple(one.axes)))
        _require(not outside, who, "axes",
                 f"with axes={list(one.axes)} the rows touch {len(outside)} unknown(s) of other axes "
                 "(use model.axes_of(self.axes) and pass self.axes to model.position(), ...)")
        return


def _solve_with(item: Item, model: NavModel, mode: str, who: str) -> None:
    """A tiny end-to-end solve with the item in ``mode``.

    Hard and band items stand beside soft end positions (a hard item may fix the ends
    itself), soft and robust ones beside hard end positions (so the problem is
    determined without them).
    """
    rule = f"solves when {mode}"
    t = model.grid.t
    ends = [float(t[0]), float(t[-1])]
    with _rule(who, rule):
        if mode in ("hard", "band"):
            base = Position(t=ends, value=0.0, sigma=1.0, name="check_item ends (soft)")
        else:
            base = Position(t=ends, value=0.0, name="check_item ends (hard)")
        checked = _switch(item, mode, sigma=1.0)
        # no error model (its parameters would need more items) unless the item acts on it alone
        # or reads a parameter of it (``reads_error_model``: NonHolonomic(mounting="estimated"))
        reads = item.needs_error_model or getattr(item, "reads_error_model", False)
        em = model.error_model if reads else None
        prob = NavigationProblem(model.data, error_model=em, segment=_segment(model, item))
        prob.add(base, checked)
        sol = prob.solve(lam=1.0)
    _require(sol.stats.get("verified"), who, rule, f"the solve was not verified ({sol.stats.get('status')})")
    _require(np.all(np.isfinite(sol.x)), who, rule, "the solution is not finite")
    _require(checked.label in set(sol.items["item"]), who, rule,
             f"the item's label {checked.label!r} is missing from Solution.items")
    resid = sol.item_residuals.get(checked.label)
    _require(resid is not None and np.all(np.isfinite(resid)), who, rule,
             "Solution.item_residuals holds no finite residual for the item")


def _base_trajectory(model: NavModel, who: str) -> pd.DataFrame:
    """The estimate a sequential loop would start from: positions 0 at both ends."""
    t = model.grid.t
    with _rule(who, "linearized"):
        prob = NavigationProblem(model.data)
        prob.add(Position(t=[float(t[0]), float(t[-1])], value=0.0))
        return prob.solve().trajectory


def check_item(item_or_class: Item | type[Item], model: NavModel | None = None) -> None:
    """Check that an item honours the contract of :class:`bvpnav.Item`.

    Parameters
    ----------
    item_or_class : Item or type
        An item instance, or an item class (its ``example()`` is checked).
    model : NavModel, optional
        The model to compile against. Default: the class's ``example_model()`` when it gives
        one (an item that needs strapdown data or an error model), else three axes
        ``x, y, z`` on [0, 10] s (101 samples), the window every other ``example()`` is
        written for.

    Returns
    -------
    None
        When every rule holds.

    Raises
    ------
    AssertionError
        On the first broken rule, naming the item's class and the rule, e.g.
        ``item MyItem: rule 'deterministic' broken: ...``.

    Notes
    -----
    The rules (the name in quotes is the one a failure reports):

    - 'is an Item': an instance of :class:`bvpnav.Item`; ``kind`` is one of
      ``"equality"``, ``"inequality"``, ``"cone"``; ``units`` is a string;
    - 'registered': a public class (name not starting with ``_``) is found by
      :func:`bvpnav.items.item_class` under its snake-case name, case-insensitively;
    - 'example': the class's ``example()`` returns an instance of the class;
    - 'frozen': every field refuses assignment (``dataclasses.FrozenInstanceError``);
    - 'no cvxpy objects': the constructor stores data only;
    - 'pickles': a pickled copy compiles to the same rows (batch runs ship items to
      worker processes);
    - 'math': ``math()`` is one non-empty line of text (for ``describe()``) and
      ``latex()`` a non-empty string or None; 'repr': ``repr()`` and ``identify()``
      give text (they name the item in messages);
    - 'compile returns an Affine' / 'compile returns a Cone' (``kind = "cone"``),
      'residual shape' (``m > 0`` rows over all ``model.size`` unknowns), 'residual
      labels' (one per row, if any), 'finite residual', and for cones 'cone groups'
      (``m`` a multiple of the group size, ``excess()`` finite);
    - 'deterministic': compiling twice gives identical rows; 'no state across models':
      compiled for a coarser grid of the same window the rows span that model's unknowns,
      and the first model's rows are unchanged afterwards ('no cvxpy objects' is checked
      again after compiling);
    - 'modes': every mode of :data:`bvpnav.items.MODES` is a switch on the same
      object: the copy reports the mode and compiles to the same rows;
    - 'refuses bad sigma' / 'refuses bad mode': ``sigma=-1`` and ``mode="sometimes"``
      raise :class:`bvpnav.InputError` naming the class (and the field);
    - 'axes': restricted to one axis (the second of the model's; the item's own
      ``axes`` when it has some), the rows touch only that axis's unknowns and the
      error-model parameters. An instance whose values name every axis (so it refuses
      one axis) is checked through its class's ``example()``;
    - 'solves when hard': hard, beside soft positions 0 at both ends, the item gives a
      verified finite solution in which it is reported; 'solves when band': the same
      with ``tol=0.1``; 'solves when soft' and 'solves when robust': the same with
      ``sigma=1`` (robust: ``huber=1``) beside hard end positions, and 'solves when band
      with soft edges' (not for cones) with ``tol=0.1, sigma=1`` beside them (all on
      ``model.data`` without the error model, whose parameters these items alone need
      not determine). On a coarse mesh's model (:class:`bvpnav.mesh.MeshModel`) the
      coarser model is a mesh of the same ``segment`` with nodes at the item's instants
      (made by a problem when the model has node states), and the solves are on a mesh
      when the model has no node states or the item's rows are at its nodes
      (``NonHolonomic(rate="nodes")``);
    - 'linearized': an item with ``needs_linearization`` True is not compiled or solved
      itself; its ``linearized(t, trajectory)`` about the solution with positions 0 at
      both ends must no longer need linearization and is put through every rule above.
    """
    if isinstance(item_or_class, type):
        cls = item_or_class
        who = f"item {cls.__name__}"
        _require(issubclass(cls, Item), who, "is an Item", f"{cls!r} is not a subclass of bvpnav.Item")
        with _rule(who, "example"):
            item = cls.example()
        _require(isinstance(item, cls), who, "example", f"example() returned {type(item).__name__}, "
                 f"not a {cls.__name__}")
    else:
        item = item_or_class
        cls = type(item)
        who = f"item {cls.__name__}"
    if model is None:
        model = cls.example_model() if hasattr(cls, "example_model") else None
        model = NavModel(_default_data()) if model is None else model
    _check_item(item, model, who)


def _check_item(item: Item, model: NavModel, who: str) -> None:
    cls = type(item)
    name = cls.__name__
    _require(isinstance(item, Item), who, "is an Item", f"{item!r} is not an instance of bvpnav.Item")
    _require(cls.kind in KINDS, who, "is an Item", f"kind = {cls.kind!r}; choose one of {list(KINDS)}")
    _require(isinstance(item.units, str), who, "is an Item", f"units = {item.units!r} must be a string")
    if not name.startswith("_"):
        reg = cls.registered_name()
        with _rule(who, "registered"):
            found, upper = item_class(reg), item_class(reg.upper())
        _require(found is cls and upper is cls, who, "registered",
                 f"item_class({reg!r}) gives {found!r}, item_class({reg.upper()!r}) gives {upper!r}")
        with _rule(who, "example"):
            ex = cls.example()
        _require(isinstance(ex, cls), who, "example",
                 f"example() returned {type(ex).__name__}, not a {name}")

    # ---------------------------------------------------- data only, frozen
    for key, value in vars(item).items():
        _require(not _cvxpy_objects(value), who, "no cvxpy objects",
                 f"attribute {key!r} holds a cvxpy object; store data and build rows in compile()")
    _require(dataclasses.is_dataclass(item), who, "frozen", "the item is not a dataclass")
    for f in dataclasses.fields(item):
        try:
            setattr(item, f.name, getattr(item, f.name, None))
        except dataclasses.FrozenInstanceError:
            continue
        except Exception as exc:
            _fail(who, "frozen", f"assigning field {f.name!r} raised {type(exc).__name__}, not "
                  "dataclasses.FrozenInstanceError; declare @dataclass(frozen=True, kw_only=True, eq=False)")
        _fail(who, "frozen", f"field {f.name!r} can be assigned; declare "
              "@dataclass(frozen=True, kw_only=True, eq=False)")
    with _rule(who, "math"):
        text = item.math()
    _require(isinstance(text, str) and text.strip() and "\n" not in text.strip(), who, "math",
             f"math() returned {text!r}; give one non-empty line of plain-text mathematics")
    with _rule(who, "math"):
        tex = item.latex()
    _require(tex is None or (isinstance(tex, str) and tex.strip()), who, "math",
             f"latex() returned {tex!r}; give a non-empty mathtext string or None (use math())")
    with _rule(who, "repr"):
        shown = (repr(item), item.identify())
    _require(all(isinstance(v, str) and v for v in shown), who, "repr",
             "repr() or identify() gave no text (both name the item in messages)")
    with _rule(who, "pickles"):
        copy = pickle.loads(pickle.dumps(item))
    _require(type(copy) is cls, who, "pickles", f"unpickled as {type(copy).__name__}")

    # ------------------------------------------------- bad weights refused
    with _rule(who, "refuses bad sigma"):  # unnamed, so that messages name the class
        plain = dataclasses.replace(item, name=None) if item.name is not None else item
    for field, value, word in (("sigma", -1.0, "sigma"), ("mode", "sometimes", "mode")):
        rule = f"refuses bad {field}"
        kw = {"sigma": -1.0, "mode": None} if field == "sigma" else {"mode": "sometimes"}
        try:
            dataclasses.replace(plain, **kw)
        except InputError as exc:
            msg = str(exc)
            _require(name in msg and word in msg, who, rule,
                     f"{field}={value!r} was refused, but the message {msg!r} does not name {name!r} "
                     f"and {word!r}")
        except Exception as exc:
            _fail(who, rule, f"{field}={value!r} raised {type(exc).__name__} ({exc}), not bvpnav.InputError")
        else:
            _fail(who, rule, f"{field}={value!r} was accepted; call Item.__post_init__ (super()) "
                  "from your own __post_init__, or validate in validate()")

    # --------------------------------------- linearization: check the copy
    if getattr(item, "needs_linearization", False):
        traj = _base_trajectory(model, who)
        with _rule(who, "linearized"):
            lin = item.linearized(traj.index.to_numpy(), traj[list(model.axes)])
        _require(isinstance(lin, Item), who, "linearized",
                 f"linearized() returned {type(lin).__name__}, not an item")
        _require(not getattr(lin, "needs_linearization", False), who, "linearized",
                 "the linearized copy still needs linearization")
        _check_item(lin, model, f"{who} linearized(t, trajectory)")
        return

    # ------------------------------------------------------------ compile
    with _rule(who, "compile"):
        res = item.compile(model)
    _check_residual(res, item, model, who)
    with _rule(who, "deterministic"):
        again = item.compile(model)
    _require(isinstance(again, Affine) and _same_rows(res, again), who, "deterministic",
             "compiling the same item twice gave different rows")
    with _rule(who, "pickles"):
        shipped = copy.compile(model)
    _require(isinstance(shipped, Affine) and _same_rows(res, shipped), who, "pickles",
             "a pickled copy compiles to different rows")
    for key, value in vars(item).items():
        _require(not _cvxpy_objects(value), who, "no cvxpy objects",
                 f"compile() left a cvxpy object in attribute {key!r}; return rows, keep no expressions")
    _check_other_model(item, model, res, who)

    # -------------------------------------------------- every mode a switch
    for mode in MODES:
        with _rule(who, "modes"):
            other = _switch(item, mode)
            rows = other.compile(model)
        _require(other.mode == mode, who, "modes", f"the copy with mode={mode!r} reports mode {other.mode!r}")
        _require(isinstance(rows, Affine) and _same_rows(res, rows), who, "modes",
                 f"in mode {mode!r} compile gives other rows; the residual must not depend on the "
                 "mode (the framework applies it)")

    # --------------------------------------------------------- axis choice
    _check_axes(item, model, who)

    # ----------------------------------------------------------- end to end
    for mode in MODES:
        _solve_with(item, model, mode, who)
    if item.kind != "cone":   # cones refuse soft edges
        _solve_with(item, model, SOFT_EDGES, who)


# --------------------------------------------------------------- error models
def _with_acc(data: ImuData, acc: np.ndarray) -> ImuData:
    """``data`` with other navigation-frame accelerations (strapdown: the specific force)."""
    if data.is_strapdown:
        f = data.attitude.inv().apply(acc - data.gravity)
        out = ImuData(data.t, specific_force=f, attitude=data.attitude, gravity=data.gravity,
                      axes=data.axes, checks=False)
        out.gyro = data.gyro  # the attitude error models' columns need the rates
        return out
    return ImuData(data.t, acc, axes=data.axes)


def _truth_values(q: int) -> np.ndarray:
    """Small internal parameter values of both signs, all different."""
    k = np.arange(q)
    return 0.01 * (1.0 + 0.5 * k / max(q, 1)) * np.where(k % 2, -1.0, 1.0)


def _without_priors(em: ErrorModel | CompositeErrorModel) -> ErrorModel | CompositeErrorModel:
    """``em`` without soft priors, random-walk priors (``drift``, ``arw``) and bounds (a prior
    pulls the estimate off the simulated value)."""
    if isinstance(em, CompositeErrorModel):
        return CompositeErrorModel(*[_without_priors(c) for c in em.components])
    if dataclasses.is_dataclass(em):
        names = {f.name for f in dataclasses.fields(em)}
        kw = {k: None for k in ("prior", "sigma", "bounds", "drift", "arw")
              if k in names and getattr(em, k) is not None}
        if kw:
            return dataclasses.replace(em, **kw)
    return em


def _check_recovery(em: ErrorModel | CompositeErrorModel, data: ImuData, q: int, who: str) -> None:
    """Simulate a sensor with known internal parameters and solve for them."""
    rule = "recovers its parameters"
    l_true = _truth_values(q)
    with _rule(who, rule):
        em = _without_priors(em)
        a_true = np.asarray(data.acc, dtype=float)
        meas, step = data, np.inf
        scale = max(1.0, float(np.max(np.abs(a_true))))
        for _ in range(50):  # a_hat = a_true - G(a_hat) l: columns may depend on the measurement
            acc = a_true - np.einsum("nap,p->na", np.asarray(em.columns(meas), dtype=float), l_true)
            step = float(np.max(np.abs(acc - meas.acc)))
            meas = _with_acc(meas, acc)
            if step <= 1e-14 * scale:
                break
    _require(step <= 1e-14 * scale, who, rule,
             f"simulating a_hat = a_true - G(a_hat) l by fixed-point iteration did not converge (last "
             f"change {step:.3g} m/s^2): the columns change too fast with the measurement for "
             f"parameters of about 0.01")
    with _rule(who, rule):
        # the truth: the FEM's own double integration of the true accelerations
        t = data.t
        free = NavigationProblem(data).add(Position(t=float(t[0]), value=0.0),
                                           Velocity(t=float(t[0]), value=0.0))
        integrated = free.solve(accuracy="high")
        pos, vel = integrated.position(), integrated.velocity()
        k = np.unique(np.linspace(0, t.size - 1, 11).round().astype(int))
        prob = NavigationProblem(meas, error_model=em, grade=None)  # the check states no prior: assume none
        prob.add(Position(t=t[k], value=pos[k], name="check positions"),
                 Velocity(t=t[k], value=vel[k], name="check velocities"))
        # a model whose parameters act on other information than the accelerations (an
        # odometer's scale) names the items that observe them
        values = dict(zip(em.names(meas), l_true, strict=True))
        for comp in getattr(em, "components", (em,)):
            if hasattr(comp, "check_items"):
                prob.add(*comp.check_items(NavModel(meas, em), values, t[k], vel[k]))
        missing = prob.unobservable()
    _require(not missing, who, rule, f"on the check data the parameters are not determined by positions "
             f"and velocities at 11 instants ({'; '.join(missing)}); pass data= on which they are")
    with _rule(who, rule):
        model = NavModel(meas, em)
        # attitude models: one linearized solve (the linear model the simulation used)
        sol = prob.solve(accuracy="high", attitude={"loop": False})
        expect = em.report(l_true, model)
        zero = em.report(np.zeros(q), model)
    names = list(expect.index)
    simulated = dict(zip(names, np.round(l_true, 6).tolist(), strict=True))
    _require(sol.stats.get("verified"), who, rule, "the solve was not verified")
    # the solver's internal values first (a report could hide a wrong estimate) ...
    l_est = sol.x[model.l_index]
    bad = np.flatnonzero(~(np.abs(l_est - l_true) <= 1e-6 * np.abs(l_true)))
    wrong = ", ".join(f"{names[j]}: {l_est[j]:.9g}" for j in bad)
    _require(not bad.size, who, rule, f"simulated with internal parameters {simulated}; the solve found "
             f"internal values {wrong}")
    # ... then what the user sees: report(l) of the estimate against report(l) of the truth
    est = sol.error_params
    _require(list(est.index) == names, who, rule,
             f"the solution reports {list(est.index)}, the model's report() {names}")
    e, x = est.to_numpy(dtype=float), expect.to_numpy(dtype=float)
    bad = np.flatnonzero(~(np.abs(e - x) <= 1e-6 * np.maximum(np.abs(x), 0.01)))
    wrong = ", ".join(f"{names[j]} = {e[j]:.9g} (expected {x[j]:.9g})" for j in bad)
    _require(not bad.size, who, rule, f"simulated with internal parameters {simulated}; reported {wrong}")
    same = np.flatnonzero(expect.to_numpy(dtype=float) == zero.to_numpy(dtype=float))
    _require(not same.size, who, "report", "report() ignores the parameter(s) "
             f"{[names[j] for j in same]}: the same value at l = 0 and at l = {simulated}")


def check_error_model(model_or_class: ErrorModel | CompositeErrorModel | type[ErrorModel],
                      data: ImuData | None = None) -> None:
    """Check that an error model honours the contract of :class:`bvpnav.error_models.ErrorModel`.

    Parameters
    ----------
    model_or_class : ErrorModel or CompositeErrorModel or type
        An error model, or an error-model class (its ``example()`` if it has one, else an
        instance built with no arguments).
    data : ImuData, optional
        Data to build columns and to simulate on. Default: navigation-frame
        accelerations on three axes ``x, y, z`` over [0, 10] s (101 samples).

    Returns
    -------
    None
        When every rule holds.

    Raises
    ------
    AssertionError
        On the first broken rule, naming the model's class and the rule, e.g.
        ``error model Offset: rule 'unique names' broken: ...``.

    Notes
    -----
    The rules (the name in quotes is the one a failure reports):

    - 'is an error model': accepted by ``NavigationProblem(error_model=...)``;
    - 'names': ``names(data)`` is a non-empty list of non-empty strings;
      'unique names': no name twice;
    - 'columns': ``columns(data)`` has shape (N, d, q) with q the number of names, and
      is finite;
    - 'deterministic': names and columns are the same when asked twice;
    - 'pickles': a pickled copy has the same names and columns;
    - 'report': ``report(l, model)`` at ``l = 0`` is a :class:`pandas.Series` indexed
      by the names, with finite values and ``attrs["units"]`` naming the units of each;
    - 'terms': ``terms(model)`` is a list of terms whose rows span the model's unknowns;
    - 'recovers its parameters': accelerations are simulated with known internal
      parameters ``l`` (about 0.01, both signs) by solving
      ``a_hat = a_true - G(a_hat) l`` by fixed-point iteration (the columns may depend
      on the measurement), positions and velocities at 11 instants are taken from the
      FEM's integration of ``a_true`` (with the items a component's
      ``check_items(model, values, t, velocities)`` returns, for parameters that act on
      other information, e.g. an odometer's scale), and the solve (priors and bounds dropped) must
      find ``l`` to 1e-6 relative and report ``report(l)`` (1e-6 relative, absolute
      1e-8 below 0.01); ``report()`` must change with every parameter (rule
      'report'). Parameters that these measurements cannot determine fail the rule;
      pass ``data=`` on which they can.

    A model of node states only (no names, a ``state_size``, e.g.
    :class:`~bvpnav.error_models.ErrorStates`) is checked by other rules: 'state layout'
    (``state_index`` of its kinds cover ``0 .. state_size - 1`` once, at the nodes
    ``state_nodes`` says), 'state columns' (one finite sparse (N, ns) matrix per axis whose
    state columns are nonzero at their own node only: local, so they go in the band),
    'pickles' and 'terms' (rows over the model's unknowns, each touching states of at most
    two neighbouring nodes).
    """
    if isinstance(model_or_class, type):
        cls = model_or_class
        who = f"error model {cls.__name__}"
        with _rule(who, "is an error model"):
            em = cls.example() if hasattr(cls, "example") else cls()
    else:
        em = model_or_class
        who = f"error model {type(em).__name__}"
    with _rule(who, "is an error model"):
        as_error_model(em)
    if data is None:
        comps = getattr(em, "components", (em,))
        own = [c for c in comps if hasattr(c, "example_data")]
        data = own[0].example_data() if own else _default_data()

    with _rule(who, "names"):
        names = em.names(data)
    if not names and hasattr(em, "state_size"):   # a model of node states only
        _check_node_states(em, data, who)
        return
    _require(isinstance(names, list | tuple) and len(names) > 0, who, "names",
             f"names(data) returned {names!r}; give a non-empty list of parameter names")
    _require(all(isinstance(n, str) and n.strip() for n in names), who, "names",
             f"names(data) = {list(names)!r}; every name must be a non-empty string")
    dup = sorted({n for n in names if list(names).count(n) > 1})
    _require(not dup, who, "unique names", f"names(data) gives {dup} more than once")
    q = len(names)
    with _rule(who, "columns"):
        G = np.asarray(em.columns(data), dtype=float)
    shape = (data.n, data.ndim, q)
    _require(G.shape == shape, who, "columns", f"columns(data) has shape {G.shape}, expected {shape} "
             "(samples, navigation axes, parameters)")
    _require(np.all(np.isfinite(G)), who, "columns", "columns(data) holds NaN or inf")
    with _rule(who, "deterministic"):
        same = list(em.names(data)) == list(names) and np.array_equal(np.asarray(em.columns(data)), G)
    _require(same, who, "deterministic", "names or columns differ when asked twice")
    with _rule(who, "pickles"):
        copy = pickle.loads(pickle.dumps(em))
        same = list(copy.names(data)) == list(names) and np.array_equal(np.asarray(copy.columns(data)), G)
    _require(same, who, "pickles", "a pickled copy has other names or columns")

    with _rule(who, "report"):
        model = NavModel(data, em)
        rep = em.report(np.zeros(q), model)
    _require(isinstance(rep, pd.Series), who, "report",
             f"report(l, model) returned {type(rep).__name__}, not a pandas.Series")
    _require(list(rep.index) == list(names), who, "report",
             f"report() is indexed by {list(rep.index)}, not by the names {list(names)}")
    with _rule(who, "report"):
        vals = rep.to_numpy(dtype=float)
    _require(np.all(np.isfinite(vals)), who, "report", f"report() at zero parameters is not finite: "
             f"{dict(zip(names, vals, strict=True))}")
    units = rep.attrs.get("units")
    _require(isinstance(units, dict) and all(n in units for n in names), who, "report",
             f"report().attrs['units'] = {units!r}; map every parameter name to its units")

    with _rule(who, "terms"):
        terms = em.terms(model) if hasattr(em, "terms") else []
    _require(isinstance(terms, list), who, "terms",
             f"terms(model) returned {type(terms).__name__}, not a list")
    for term in terms:
        res = getattr(term, "residual", None)
        _require(isinstance(res, Affine) and res.A.shape[1] == model.size, who, "terms",
                 f"term {getattr(term, 'label', term)!r} has no residual rows over the {model.size} unknowns")

    comps = getattr(em, "components", (em,))
    through_items = [c for c in comps if getattr(type(c), "provides", None)]
    for c in through_items:
        _check_item_recovery(c, f"{who} ({type(c).__name__})" if len(comps) > 1 else who)
    rest = [c for c in comps if c not in through_items]
    if rest:
        em_rest = rest[0] if len(rest) == 1 else CompositeErrorModel(*rest)
        _check_recovery(em_rest, data, len(em_rest.names(data)), who)


def _check_item_recovery(em: ErrorModel, who: str) -> None:
    """A model whose parameters act through items (``provides``: the lever arm, the fixes'
    delay; zero columns) is checked on its own ``example_recovery()``: a noise-free problem
    and the true values, found to 1e-6 relative (absolute below 0.01)."""
    rule = "recovers its parameters"
    _require(hasattr(type(em), "example_recovery"), who, rule,
             "a model whose parameters act through items (provides=...) needs a classmethod "
             "example_recovery(problem) -> (problem, {name: true value}, solve options), given the "
             "problem class")
    with _rule(who, rule):
        from .problem import NavigationProblem

        prob, truth, opts = type(em).example_recovery(NavigationProblem)
        sol = prob.solve(**opts)
    _require(sol.stats.get("verified"), who, rule, "the solve was not verified")
    bad = {n: float(sol.error_params[n]) for n, v in truth.items()
           if not abs(float(sol.error_params[n]) - v) <= 1e-6 * max(abs(v), 0.01)}
    _require(not bad, who, rule, f"simulated with {truth}; found {bad}")


def _check_node_states(em, data, who: str) -> None:
    """The rules of a node-state model (see :func:`check_error_model`)."""
    import scipy.sparse as sp

    with _rule(who, "state layout"):
        ns = int(em.state_size(data))
        nodes = np.asarray(em.state_nodes(data))
        idx = np.concatenate([np.asarray(em.state_index(data, k)).ravel() for k in em.state_kinds(data)])
        at = np.concatenate([np.repeat(np.arange(data.n), np.asarray(em.state_index(data, k)).shape[1])
                             for k in em.state_kinds(data)])
    _require(nodes.shape == (ns,) and np.array_equal(np.sort(idx), np.arange(ns)), who, "state layout",
             f"state_index of the kinds {em.state_kinds(data)} does not cover 0 .. {ns - 1} once")
    _require(np.array_equal(nodes[idx], at), who, "state layout",
             "state_nodes disagrees with the node of state_index")
    with _rule(who, "state columns"):
        cols = [sp.csr_matrix(g) for g in em.state_columns(data)]
    _require(len(cols) == data.ndim and all(g.shape == (data.n, ns) for g in cols), who, "state columns",
             f"state_columns(data) must be {data.ndim} sparse matrices of shape ({data.n}, {ns})")
    for g in cols:
        coo = g.tocoo()
        _require(np.all(np.isfinite(coo.data)), who, "state columns", "state columns hold NaN or inf")
        _require(np.array_equal(nodes[coo.col], coo.row), who, "state columns",
                 "a state's column is nonzero away from its own node (not local)")
    with _rule(who, "pickles"):
        copy = pickle.loads(pickle.dumps(em))
        same = copy.state_size(data) == ns and all(
            (sp.csr_matrix(a) != b).nnz == 0 for a, b in zip(copy.state_columns(data), cols, strict=True))
    _require(same, who, "pickles", "a pickled copy has other state columns")
    with _rule(who, "terms"):
        model = NavModel(data, em)
        terms = em.terms(model)
    s0 = model.size - ns
    for term in terms:
        res = getattr(term, "residual", None)
        _require(isinstance(res, Affine) and res.A.shape[1] == model.size, who, "terms",
                 f"term {getattr(term, 'label', term)!r} has no residual rows over the {model.size} unknowns")
        A = res.A.tocoo()
        st = A.col >= s0
        node = nodes[A.col[st] - s0]
        lo = np.full(res.m, np.iinfo(np.int64).max)
        hi = np.full(res.m, -1)
        np.minimum.at(lo, A.row[st], node)
        np.maximum.at(hi, A.row[st], node)
        _require(np.all((hi < 0) | (hi - lo <= 1)), who, "terms",
                 f"term {term.label!r} ties states of nodes more than one apart (not local)")


# ------------------------------------------------------------------ back ends
def _ls_formulation(sigma_a: float | None = None):
    """A small least-squares problem (hard ends, soft fixes) and a robust copy of it."""
    t = np.linspace(0.0, 10.0, 41)
    acc = np.sin(t) + 0.05 * np.cos(7.0 * t)
    data = ImuData(t=t, acc=acc)
    ends = Position(t=[0.0, 10.0], value=[0.0, 1.0], name="ends")
    fixes = dict(t=[3.0, 5.0, 7.0], value=[0.3, 0.5, 0.7], sigma=0.1, name="fixes")
    ls = Formulation(data, sigma_a=sigma_a, items=[ends, Position(**fixes)])
    robust = Formulation(data, sigma_a=sigma_a, items=[ends, Position(**fixes, mode="robust", huber=0.2)])
    return ls, robust


def check_backend(backend) -> None:
    r"""Check that a back end keeps the :class:`bvpnav.backends.Backend` contract.

    Parameters
    ----------
    backend : Backend
        An instance (registered or not).

    Raises
    ------
    AssertionError
        Naming the back end and the broken rule: a lowercase non-empty ``name``; presets
        only for ``low``/``default``/``high`` whose options its own option check accepts;
        an unknown option refused naming it (when it lists its options); a positive
        ``memory_per_sample`` for both objective forms; ``accepts`` returning None or a
        reason that names the item it cannot take (or the back end itself); and, on a
        small least-squares problem (which every back end must accept), a finite stacked
        solution that bvpnav's
        verification passes at the ``default`` preset and that agrees with the ``direct``
        back end to 1e-6 m.

    Notes
    -----
    The reference is the exact solution of
    :math:`\min \|D x + c\|^2` s.t. :math:`E x + e = 0` from one sparse factorization
    (:class:`bvpnav.backends.direct.DirectBackend`).
    """
    name = getattr(backend, "name", None)
    who = f"back end {name!r}"
    _require(isinstance(name, str) and name and name == name.lower(), who, "name",
             "the name must be a non-empty lowercase string")
    with _rule(who, "presets"):
        presets = backend.presets
        _require(isinstance(presets, dict) and set(presets) <= set(ACCURACIES), who, "presets",
                 f"presets must be a dict keyed by {list(ACCURACIES)}, got {presets!r}")
        for acc, opts in presets.items():
            try:
                check_options(backend, opts, what=f"presets[{acc!r}]")
            except InputError as exc:
                _fail(who, "presets", f"its own preset {acc!r} is refused by its option check: {exc}")
    with _rule(who, "options"):
        valid = backend.valid_options()
        if valid is not None:
            try:
                check_options(backend, {"no_such_option_xyz": 1})
            except InputError as exc:
                _require("no_such_option_xyz" in str(exc), who, "options",
                         f"the refusal of an unknown option does not name it: {exc}")
            else:
                _fail(who, "options", "an unknown option was accepted although valid_options() lists them")
    with _rule(who, "memory"):
        per = backend.memory_per_sample
        ok = all(isinstance(per.get(f), int | float) and np.isfinite(per.get(f)) and per.get(f) > 0
                 for f in ("acceleration", "load"))
        _require(ok, who, "memory", f"memory_per_sample needs positive bytes per sample for "
                 f"'acceleration' and 'load', got {per!r}")
    ls, robust = _ls_formulation()
    with _rule(who, "accepts"):
        for form in (ls, robust):
            why = backend.accepts(form)
            named = isinstance(why, str) and (name in why or any(lab in why for lab in form.labels))
            _require(why is None or named, who, "accepts",
                     f"accepts() must return None or a reason naming the item (or the back end), got {why!r}")
    with _rule(who, "run"):
        why = backend.accepts(ls)
        _require(why is None, who, "run", f"it refuses plain equality-constrained least squares: {why}")
        raw = backend.run(ls, 2.0, solver_options(backend, "default"), False)
        x = np.asarray(raw.x, dtype=float)
        _require(x.shape == (ls.model.size,) and np.all(np.isfinite(x)), who, "run",
                 f"run() must return a finite stacked vector of {ls.model.size} entries, got shape {x.shape}")
        _require(isinstance(raw.info, dict) and "status" in raw.info, who, "run",
                 "run() must report its status in RawSolve.info['status']")
        check = verify(ls, x, 2.0, "default", raw.duals, raw.factored)
        _require(check.verified, who, "run", f"its answer fails bvpnav's verification: {check.as_dict()}")
        ref = resolve_solver("direct").run(ls, 2.0, solver_options(resolve_solver("direct"), "default"))
        pos = np.concatenate([ls.model.r_index(a) for a in range(ls.model.d)])
        err = float(np.max(np.abs(x[pos] - ref.x[pos])))
        _require(err <= 1e-6, who, "run", f"positions differ from the direct back end by {err:.3g} m")


# ------------------------------------------------------------------ lambda rules
def check_rule(rule) -> None:
    """Check that a lambda rule keeps the :class:`bvpnav.lam.LambdaRule` contract.

    Parameters
    ----------
    rule : LambdaRule
        An instance (registered or not).

    Raises
    ------
    AssertionError
        Naming the rule and the broken rule of the contract: a non-empty ``name``;
        ``needs`` a subset of :data:`bvpnav.lam.NEEDS`; ``slopes`` and ``coarse`` bools,
        ``slopes`` True only with ``uses_derivative``; on a small least-squares problem
        (direct sweep, sampled every two decades for a rule that samples coarsely, as
        ``sweep_curve`` samples it) ``scores`` one number per sampled
        lambda and ``refine`` a lambda inside the sweep's range, the same on a second run;
        and, unless the rule needs least squares, the same on the cvxpy sweep of a problem
        with a robust item.
    """
    name = getattr(rule, "name", None)
    who = f"lambda rule {name!r}"
    _require(isinstance(name, str) and name, who, "name", "the name must be a non-empty string")
    needs = getattr(rule, "needs", None)
    _require(isinstance(needs, set | frozenset) and needs <= set(NEEDS), who, "needs",
             f"needs must be a (frozen)set, a subset of {list(NEEDS)}, got {needs!r}")
    _require("trace" not in needs or "least_squares" in needs, who, "needs",
             "a rule that needs 'trace' needs 'least_squares' too (only the direct sweep has it)")
    slopes = getattr(rule, "slopes", False)
    _require(isinstance(slopes, bool), who, "slopes", f"slopes must be True or False, got {slopes!r}")
    _require(not slopes or getattr(rule, "uses_derivative", True), who, "slopes",
             "a rule that reads slopes (d2eta2) needs the derivative solve: uses_derivative = True")
    coarse = getattr(rule, "coarse", False)
    _require(isinstance(coarse, bool), who, "coarse", f"coarse must be True or False, got {coarse!r}")
    ls, robust = _ls_formulation(sigma_a=0.05)
    # as sweep_curve samples for this rule alone: every two decades on the direct sweep
    # when it samples coarsely
    grids = {"direct": np.geomspace(1e-6, 1e6, SLOPE_POINTS) if coarse else np.geomspace(1e-3, 1e3, 13),
             "cvxpy": np.geomspace(1e-3, 1e3, 13)}
    opts, _ = prepare(1.0, fallback=None)
    # as sweep_curve builds it for this rule alone: without dx/dlam when the rule says it
    # does not read deta2 or quasi (so a rule that reads them anyway fails here, not later)
    sweeps = [("direct", lambda: DirectSweep(ls, need_trace="trace" in rule.needs,
                                             need_derivative=getattr(rule, "uses_derivative", True)))]
    if "least_squares" not in rule.needs:
        sweeps.append(("cvxpy", lambda: CvxpySweep(robust, lambda lam: solve_fixed(robust, lam, opts))))
    for engine, make in sweeps:
        lams = grids[engine]
        s = np.log(lams)
        chosen = []
        for _ in range(2):
            sweep = make()
            pts = [sweep.point(lam) for lam in lams]
            curve = LambdaCurve(lam=lams, residual_norm=np.sqrt([p["rho2"] for p in pts]),
                                info_norm=np.sqrt([p["eta2"] for p in pts]), rule=name,
                                engine=engine, lam_range=(lams[0], lams[-1]))
            with _rule(who, f"scores ({engine} sweep)"):
                sc = np.asarray(rule.scores(sweep, pts, s), dtype=float)
                _require(sc.shape == lams.shape, who, f"scores ({engine} sweep)",
                         f"one score per sampled lambda expected ({lams.size}), got shape {sc.shape}")
            with _rule(who, f"refine ({engine} sweep)"):
                lam = float(rule.refine(sweep, pts, s, sc, curve))
                _require(np.isfinite(lam) and lams[0] <= lam <= lams[-1], who, f"refine ({engine} sweep)",
                         f"the chosen lambda {lam!r} is not inside the sweep's range "
                         f"{lams[0]:g}..{lams[-1]:g}")
            chosen.append(lam)
        _require(chosen[0] == chosen[1], who, f"deterministic ({engine} sweep)",
                 f"two runs chose {chosen[0]!r} and {chosen[1]!r}")


def check_reader(reader, folder) -> Any:
    """Check that a reader keeps the :class:`bvpnav.readers.Reader` contract.

    Parameters
    ----------
    reader : Reader
        A registered reader.
    folder : path-like
        An empty folder for its example file (e.g. pytest's ``tmp_path``).

    Returns
    -------
    Recording
        What the reader read from its own example (for further checks by its test).

    Raises
    ------
    AssertionError
        Naming the reader and the broken rule: a lowercase registered ``name``, lowercase
        ``suffixes`` (``".ext"`` or ``"/"`` for folders), string ``options`` that do not
        shadow the frame options, an ``extra`` when it has ``modules``, a description;
        ``example`` writes a file that ``reader_for`` picks and ``sniff`` recognises;
        ``read`` leaves it byte-identical and returns a :class:`Recording` with finite,
        strictly increasing times, either navigation-frame ``acc`` (N, d), or
        ``specific_force`` (N, 3) with gyro (N, 3) and/or an attitude of length N, or
        neither with at least one item (information only); items that are
        :class:`bvpnav.Item` instances, notes that are strings; ``imu_data`` gives an
        :class:`ImuData` of N samples (unless information only); and a truncated copy
        either reads or raises :class:`bvpnav.InputError` naming the file (never another
        exception).
    """
    from pathlib import Path

    from . import readers
    from .strapdown import FRAME_OPTIONS

    name = getattr(reader, "name", None)
    who = f"reader {name!r}"
    _require(isinstance(name, str) and name and name == name.lower(), who, "name",
             "the name must be a non-empty lowercase string")
    _require(readers.registry().get(name) is reader, who, "registered", "register_reader(reader) on import")
    _require(reader.suffixes and all(isinstance(s, str) and s == s.lower() and (s == "/" or s.startswith("."))
                                     for s in reader.suffixes), who, "suffixes",
             f"lowercase '.ext' (or '/' for a folder), got {reader.suffixes!r}")
    _require(all(isinstance(o, str) for o in reader.options) and not (set(reader.options) & FRAME_OPTIONS),
             who, "options", f"strings, none of the frame options {sorted(FRAME_OPTIONS)}")
    _require(not reader.modules or isinstance(reader.extra, str), who, "extra",
             "a reader with optional modules names the extra that installs them")
    _require(isinstance(reader.description, str) and reader.description, who, "description", "one line")
    folder = Path(folder)
    with _rule(who, "example"):
        path = Path(reader.example(folder))
    _require(path.exists(), who, "example", f"example() returned {path}, which does not exist")
    picked = readers.reader_for(path)
    _require(picked is reader, who, "reader_for", f"its example {path.name} is picked by {picked!r}")
    if not path.is_dir():
        with open(path, "rb") as fh:
            head = fh.read(readers.HEAD_BYTES)
        _require(reader.sniff(head), who, "sniff", f"sniff() does not recognise its own example {path.name}")
    files = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
    before = {p: p.read_bytes() for p in files}
    with _rule(who, "read"):
        rec = readers.read(path, {"format": name})
    _require(all(p.read_bytes() == b for p, b in before.items()), who, "read-only", "read() changed the file")
    _require(isinstance(rec, readers.Recording), who, "read", f"returned {type(rec).__name__}, not Recording")
    t = np.asarray(rec.t)
    _require(t.ndim == 1 and t.size >= 3 and np.all(np.isfinite(t)) and np.all(np.diff(t) > 0), who, "times",
             "t: at least 3 finite, strictly increasing times in s")
    n = t.size
    if rec.acc is not None:
        _require(rec.specific_force is None and np.shape(rec.acc)[0] == n, who, "channels",
                 "acc (N, d) and no specific_force")
    elif rec.is_information:
        _require(len(rec.items) > 0, who, "channels",
                 "an information-only recording (no acc, no specific_force) has items")
    else:
        _require(rec.specific_force is not None and np.shape(rec.specific_force) == (n, 3), who, "channels",
                 "specific_force (N, 3) when there is no acc")
        _require(rec.gyro is not None or rec.attitude is not None, who, "channels",
                 "specific force comes with gyro rates or an attitude")
        _require(rec.gyro is None or np.shape(rec.gyro) == (n, 3), who, "channels", "gyro (N, 3) in rad/s")
        _require(rec.attitude is None or len(rec.attitude) == n, who, "channels", "one attitude per sample")
    _require(all(isinstance(i, Item) for i in rec.items), who, "items", "items are bvpnav Item instances")
    _require(all(isinstance(s, str) for s in rec.notes), who, "notes", "notes are sentences (str)")
    if not rec.is_information:
        with _rule(who, "imu_data"):
            data = rec.imu_data()
        _require(isinstance(data, ImuData) and data.n == n, who, "imu_data",
                 "an ImuData of the same N samples")
    if path.is_file():
        cut = folder / f"truncated{path.suffix}"
        cut.write_bytes(before[path][: max(1, len(before[path]) // 2)])
        try:
            readers.read(cut, {"format": name})
        except InputError as exc:
            _require(cut.name in str(exc), who, "corrupt file", f"the message does not name the file: {exc}")
        except Exception as exc:  # noqa: BLE001 - the rule is: no other exception type
            _fail(who, "corrupt file", f"a truncated file raised {type(exc).__name__}: {exc}")
    return rec
