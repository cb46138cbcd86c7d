"""The public contract checks (bvpnav.testing) over every plug-in, and on broken ones.

Every registered item and error model must pass; each deliberately broken plug-in below
must fail, with the broken rule in the message. The broken items' class names start
with ``_`` so that they are not registered (the registry would otherwise hand them to
the spec files, the CLI and other tests).
"""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys
from dataclasses import dataclass
from typing import Any, ClassVar

import cvxpy as cp
import numpy as np
import pytest
import scipy.sparse as sp

import bvpnav
from bvpnav import error_models
from bvpnav.constraints import TrackLine
from bvpnav.cvx import lower
from bvpnav.error_models import ErrorModel, SensorErrorModel
from bvpnav.items import MODES, registry
from bvpnav.model import Affine, Cone
from bvpnav.testing import check_backend, check_error_model, check_item, check_rule

ITEMS = sorted(registry())
ERROR_MODELS = sorted(
    name for name in error_models.__all__
    if isinstance(getattr(error_models, name), type)
    and issubclass(getattr(error_models, name), ErrorModel)
    and getattr(error_models, name) not in (ErrorModel, SensorErrorModel)
)


def test_every_kind_of_plug_in_is_listed():
    assert {"position", "velocity", "speed_limit", "track_line"} <= set(ITEMS)
    assert any(registry()[n].kind == "cone" for n in ITEMS)  # the cone path is exercised
    assert {"Bias", "ScaleFactor", "Misalignment", "UnknownGravity"} <= set(ERROR_MODELS)


@pytest.mark.parametrize("name", ITEMS)
def test_registered_item_passes(name):
    assert check_item(registry()[name]) is None


@pytest.mark.parametrize("name", ERROR_MODELS)
def test_registered_error_model_passes(name):
    assert check_error_model(getattr(error_models, name)) is None


def test_instances_and_composites_pass():
    check_item(bvpnav.constraints.Position(t=[2.0, 4.0], value=[[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]],
                                           name="two fixes"))
    check_error_model(error_models.ScaleFactor(sigma=0.1) + error_models.Misalignment()
                      + error_models.Bias(bounds=(-1.0, 1.0)))


def test_strapdown_data():
    sim = bvpnav.simulate.strapdown_3d_2010(rate=10.0)
    model = error_models.ScaleFactor() + error_models.Misalignment() + error_models.Bias()
    check_error_model(model, data=sim.imu_data())


def test_item_that_needs_linearization_is_checked_through_its_linearized_copy():
    track = dataclasses.replace(TrackLine.example(), about=None, about_t=None)
    assert track.needs_linearization
    check_item(track)


def test_an_item_against_a_model_with_an_error_model():
    """The rows span the parameters too; the tiny solves do without the error model."""
    t = np.linspace(0.0, 10.0, 101)
    data = bvpnav.ImuData(t, np.column_stack([np.sin(t), np.cos(t), 0.1 * t]))
    check_item(bvpnav.constraints.Velocity, bvpnav.NavModel(data, error_models.ScaleFactor()))


def test_an_item_on_a_one_axis_model():
    t = np.linspace(0.0, 10.0, 51)
    check_item(bvpnav.constraints.Velocity.example(), bvpnav.NavModel(bvpnav.ImuData(t, np.sin(t))))


# ------------------------------------------------------------------ broken items
@dataclass(frozen=True, kw_only=True, eq=False)
class _Loop(bvpnav.Item):
    """A correct item (the tutorial's loop closure): the broken ones below derive from it."""

    t0: float = 2.0
    t1: float = 8.0

    def compile(self, model):
        return model.position(self.t1, self.axes) - model.position(self.t0, self.axes)

    def math(self):
        return f"r({self.t1:g}) - r({self.t0:g}) = 0"

    @classmethod
    def example(cls):
        return cls()


def test_a_correct_private_item_passes():
    check_item(_Loop)
    check_item(_Loop(t0=1.0, t1=3.0, axes="z", sigma=0.2))


class _NotFrozen(_Loop):
    def __setattr__(self, key, value):
        object.__setattr__(self, key, value)


@dataclass(frozen=True, kw_only=True, eq=False)
class _NotAffine(_Loop):
    def compile(self, model):
        return model.position(self.t1, self.axes).value(np.zeros(model.size))


@dataclass(frozen=True, kw_only=True, eq=False)
class _Random(_Loop):
    def compile(self, model):
        return super().compile(model) + np.random.default_rng().normal(size=3)


@dataclass(frozen=True, kw_only=True, eq=False)
class _HoldsVariable(_Loop):
    var: Any = None


@dataclass(frozen=True, kw_only=True, eq=False)
class _TwoLines(_Loop):
    def math(self):
        return "r(8) - r(2) = 0\n(a loop closure)"


@dataclass(frozen=True, kw_only=True, eq=False)
class _SkipsBase(_Loop):
    def __post_init__(self):  # forgets super().__post_init__(): nothing is validated
        pass


@dataclass(frozen=True, kw_only=True, eq=False)
class _ModeDependent(_Loop):
    def compile(self, model):
        rows = super().compile(model)
        return rows * 2.0 if self.mode == "soft" else rows


@dataclass(frozen=True, kw_only=True, eq=False)
class _AllAxes(_Loop):
    def compile(self, model):  # ignores self.axes
        return model.position(self.t1) - model.position(self.t0)


@dataclass(frozen=True, kw_only=True, eq=False)
class _Unpicklable(_Loop):
    scale: Any = lambda v: v  # noqa: E731  (a lambda does not pickle)


@dataclass(frozen=True, kw_only=True, eq=False)
class _ConeAsAffine(_Loop):
    kind: ClassVar[str] = "cone"


@dataclass(frozen=True, kw_only=True, eq=False)
class _WrongWidth(_Loop):
    def compile(self, model):
        rows = super().compile(model)
        return Affine(rows.A[:, :-1], rows.c)


@dataclass(frozen=True, kw_only=True, eq=False)
class _NaN(_Loop):
    def compile(self, model):
        return super().compile(model) + np.array([0.0, np.nan, 0.0])


@dataclass(frozen=True, kw_only=True, eq=False)
class _Contradiction(_Loop):
    def compile(self, model):  # r(t0) = 0 and r(t0) = 1: no hard solution
        r = model.position(self.t0, self.axes)
        return Affine.vstack([r, r - 1.0])


@dataclass(frozen=True, kw_only=True, eq=False)
class _BadConeValues(_Loop):
    kind: ClassVar[str] = "cone"

    def compile(self, model):
        rows = model.velocity([self.t0, self.t1], self.axes)
        k = model.d + 1
        c = np.full(2 * k, np.inf)
        return Cone(sp.vstack([sp.csr_matrix((1, model.size)), rows.A[:model.d],
                               sp.csr_matrix((1, model.size)), rows.A[model.d:]]), c, size=k)


@dataclass(frozen=True, kw_only=True, eq=False)
class _NeverLinear(_Loop):
    @property
    def needs_linearization(self):
        return True

    def linearized(self, t, positions):
        return self


@dataclass(frozen=True, kw_only=True, eq=False)
class _ForgivingMode(_Loop):
    def __post_init__(self):  # turns an unknown mode into the default instead of refusing it
        if self.mode not in (None, *MODES):
            object.__setattr__(self, "mode", None)
        super().__post_init__()


@dataclass(frozen=True, kw_only=True, eq=False)
class _BadLabels(_Loop):
    def compile(self, model):
        rows = super().compile(model)
        return Affine(rows.A, rows.c, labels=("loop",))


@dataclass(frozen=True, kw_only=True, eq=False)
class _NoExample(bvpnav.Item):
    def compile(self, model):
        return model.position(5.0, self.axes)


@dataclass(frozen=True, kw_only=True, eq=False)
class _Cached(_Loop):
    def compile(self, model):  # keeps the first model's rows
        if "_rows" not in self.__dict__:
            object.__setattr__(self, "_rows", super().compile(model))
        return self.__dict__["_rows"]


@dataclass(frozen=True, kw_only=True, eq=False)
class _KeepsExpression(_Loop):
    def compile(self, model):
        rows = super().compile(model)
        object.__setattr__(self, "_expr", lower(rows, cp.Variable(model.size)))
        return rows


@dataclass(frozen=True, kw_only=True, eq=False)
class _Crashes(_Loop):
    def compile(self, model):
        raise ZeroDivisionError("oops")


BROKEN_ITEMS = [
    (_NotFrozen, "frozen"),
    (_NotAffine, "compile returns an Affine"),
    (_Random, "deterministic"),
    (_HoldsVariable(var=cp.Variable(3)), "no cvxpy objects"),
    (_TwoLines, "math"),
    (_SkipsBase, "refuses bad sigma"),
    (_ForgivingMode, "refuses bad mode"),
    (_BadLabels, "residual labels"),
    (_NoExample, "example"),
    (_ModeDependent, "modes"),
    (_AllAxes, "axes"),
    (_Unpicklable, "pickles"),
    (_ConeAsAffine, "compile returns a Cone"),
    (_WrongWidth, "residual shape"),
    (_NaN, "finite residual"),
    (_Contradiction, "solves when hard"),
    (_BadConeValues, "finite residual"),
    (_NeverLinear, "linearized"),
    (_Cached, "no state across models"),
    (_KeepsExpression, "no cvxpy objects"),
    (_Crashes, "compile"),
]


@pytest.mark.parametrize("plugin, rule", BROKEN_ITEMS,
                         ids=[(p if isinstance(p, type) else type(p)).__name__ for p, _ in BROKEN_ITEMS])
def test_broken_item_fails_naming_the_rule(plugin, rule):
    name = (plugin if isinstance(plugin, type) else type(plugin)).__name__
    with pytest.raises(AssertionError, match=rf"^item {name}: rule '{re.escape(rule)}' broken: "):
        check_item(plugin)


def test_an_exception_of_the_plug_in_is_reported_as_the_broken_rule():
    with pytest.raises(AssertionError, match="raised ZeroDivisionError: oops") as info:
        check_item(_Crashes)
    assert isinstance(info.value.__cause__, ZeroDivisionError)


def test_not_an_item_and_not_registered(monkeypatch):
    with pytest.raises(AssertionError, match="item int: rule 'is an Item' broken"):
        check_item(int)
    import bvpnav.testing

    monkeypatch.setattr(bvpnav.testing, "item_class", lambda name: bvpnav.constraints.Position)
    with pytest.raises(AssertionError, match="item Velocity: rule 'registered' broken"):
        check_item(bvpnav.constraints.Velocity)


def test_a_renamed_item_is_still_refused_by_class_name():
    """The sigma/mode rules look at the class's message, not the instance's label."""
    check_item(_Loop(name="door"))


def test_the_broken_rule_is_reported_under_python_O():
    """The checks raise AssertionError themselves: ``python -O`` strips no rule."""
    code = ("from bvpnav.testing import check_error_model\n"
            "try:\n    check_error_model('bias')\n"
            "except AssertionError as e:\n    print('refused:', e)\n")
    out = subprocess.run([sys.executable, "-O", "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "refused: error model str: rule 'is an error model' broken" in out.stdout


# ----------------------------------------------------------- broken error models
@dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class _Offset(ErrorModel):
    """A correct custom model: one constant acceleration offset per navigation axis."""

    units = "m/s^2"

    def names(self, data):
        return [f"offset_{a}" for a in data.axes]

    def columns(self, data):
        return np.broadcast_to(np.eye(data.ndim), (data.n, data.ndim, data.ndim)).copy()


def test_a_correct_custom_error_model_passes():
    check_error_model(_Offset)
    check_error_model(_Offset(sigma=1.0))


class _Duplicate(_Offset):
    def names(self, data):
        return ["offset"] * data.ndim


class _NoNames(_Offset):
    def names(self, data):
        return []


class _BlankName(_Offset):
    def names(self, data):
        return ["offset_x", " ", "offset_z"]


class _Thin(_Offset):
    def columns(self, data):
        return super().columns(data)[:, :, :1]


class _Infinite(_Offset):
    def columns(self, data):
        G = super().columns(data)
        G[3, 0, 0] = np.inf
        return G


class _Noisy(_Offset):
    def columns(self, data):
        return super().columns(data) * (1.0 + 1e-3 * np.random.default_rng().random())


class _ArrayReport(_Offset):
    def report(self, l, model):
        return np.asarray(l)


class _Misindexed(_Offset):
    def report(self, l, model):
        return super().report(l, model).reset_index(drop=True)


class _NoUnits(_Offset):
    def report(self, l, model):
        s = super().report(l, model)
        s.attrs.clear()
        return s


class _Constant(_Offset):
    def report(self, l, model):  # reports the prior instead of the estimate
        return super().report(np.zeros(len(l)), model)


class _Touchy(_Offset):
    def columns(self, data):  # 300 x the measurement per unit: a_hat = a - G(a_hat) l diverges
        return np.repeat(300.0 * np.asarray(data.acc)[:, :, None], data.ndim, axis=2) * np.eye(data.ndim)


class _Unobservable(_Offset):
    def columns(self, data):  # two parameters with the same column
        G = super().columns(data)
        G[:, :, 1] = G[:, :, 0]
        return G


class _Held(_Offset):
    def __reduce__(self):
        raise TypeError("cannot pickle this model")


BROKEN_MODELS = [
    (_Duplicate, "unique names"),
    (_NoNames, "names"),
    (_BlankName, "names"),
    (_Thin, "columns"),
    (_Infinite, "columns"),
    (_Noisy, "deterministic"),
    (_ArrayReport, "report"),
    (_Misindexed, "report"),
    (_NoUnits, "report"),
    (_Constant, "report"),
    (_Touchy, "recovers its parameters"),
    (_Unobservable, "recovers its parameters"),
    (_Held, "pickles"),
]


@pytest.mark.parametrize("plugin, rule", BROKEN_MODELS, ids=[p.__name__ for p, _ in BROKEN_MODELS])
def test_broken_error_model_fails_naming_the_rule(plugin, rule):
    with pytest.raises(AssertionError, match=rf"^error model {plugin.__name__}: rule '{rule}' broken: "):
        check_error_model(plugin)


def test_the_custom_error_model_example_passes(monkeypatch):
    """examples/custom_error_model.py's BiasDrift, alone and beside a built-in model."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "examples" / "custom_error_model.py"
    spec = importlib.util.spec_from_file_location("_custom_error_model_example", path)
    mod = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, mod)  # importable by name, as pickle needs
    spec.loader.exec_module(mod)
    check_error_model(mod.BiasDrift)
    data = bvpnav.simulate.strapdown_3d_2010(rate=10.0).imu_data()
    check_error_model(mod.BiasDrift() + error_models.Bias(), data)


def test_a_non_model_is_refused():
    with pytest.raises(AssertionError, match="rule 'is an error model'"):
        check_error_model("bias")


# backends and lambda rules: see check_backend / check_rule


@pytest.mark.parametrize("name", bvpnav.available_solvers())
def test_registered_back_end_passes(name):
    """Every back end (cvxpy's installed solvers and the direct ones) keeps the contract."""
    check_backend(bvpnav.backends.resolve_solver(name))


@pytest.mark.parametrize("name", bvpnav.lam.rule_names())
def test_registered_rule_passes(name):
    check_rule(bvpnav.lam.get_rule(name))


class _Sloppy(bvpnav.backends.Backend):
    """Returns the direct answer moved by 1 mm: fails verification."""

    name = "sloppy"
    presets = {"default": {}}
    least_squares_only = True

    def accepts(self, form):
        return bvpnav.backends.resolve_solver("direct").accepts(form)

    def run(self, form, lam, options, verbose=False):
        direct = bvpnav.backends.resolve_solver("direct")
        raw = direct.run(form, lam, bvpnav.backends.solver_options(direct, "default"))
        raw.x = raw.x + 1e-3
        return raw


class _BadPreset(_Sloppy):
    name = "bad-preset"
    presets = {"fast": {}}


class _Upper(_Sloppy):
    name = "Upper"


class _Vague(_Sloppy):
    name = "vague"

    def accepts(self, form):
        return "no"


class _OutsideRule(bvpnav.lam.LambdaRule):
    name = "outside"

    def scores(self, sweep, pts, s):
        return np.zeros(len(pts))

    def refine(self, sweep, pts, s, scores, curve):
        return 1e9


class _ShortRule(_OutsideRule):
    name = "short"

    def scores(self, sweep, pts, s):
        return np.zeros(3)


class _RandomRule(_OutsideRule):
    name = "random"

    def refine(self, sweep, pts, s, scores, curve):
        return float(np.exp(np.random.default_rng().uniform(s[0], s[-1])))


class _NeedyRule(_OutsideRule):
    name = "needy"
    needs = frozenset({"clairvoyance"})


class _DerivativeReader(_OutsideRule):
    """Says it does not read dx/dlam (so the sweep skips that solve) but reads deta2."""

    name = "derivative-reader"
    uses_derivative = False

    def scores(self, sweep, pts, s):
        return np.array([p["deta2"] for p in pts])


class _BlindSlopes(_OutsideRule):
    """Reads slopes (d2eta2) but lets the sweep skip the derivative solve that gives them."""

    name = "blind-slopes"
    slopes = True
    uses_derivative = False


class _MaybeSlopes(_OutsideRule):
    name = "maybe-slopes"
    slopes = "yes"


class _MaybeCoarse(_OutsideRule):
    name = "maybe-coarse"
    coarse = 1


@pytest.mark.parametrize("plugin, rule", [
    (_Sloppy(), "run"), (_BadPreset(), "presets"), (_Upper(), "name"), (_Vague(), "accepts"),
], ids=lambda p: getattr(p, "name", str(p)))
def test_broken_back_end_fails_naming_the_rule(plugin, rule):
    with pytest.raises(AssertionError, match=rf"^back end {plugin.name!r}: rule '{rule}' broken: "):
        check_backend(plugin)


@pytest.mark.parametrize("plugin, rule", [
    (_OutsideRule(), "refine (direct sweep)"), (_ShortRule(), "scores (direct sweep)"),
    (_RandomRule(), "deterministic (direct sweep)"), (_NeedyRule(), "needs"),
    (_DerivativeReader(), "scores (direct sweep)"), (_BlindSlopes(), "slopes"), (_MaybeSlopes(), "slopes"),
    (_MaybeCoarse(), "coarse"),
], ids=lambda p: getattr(p, "name", str(p)))
def test_broken_rule_fails_naming_the_rule(plugin, rule):
    pattern = rf"^lambda rule {plugin.name!r}: rule '{re.escape(rule)}' broken: "
    with pytest.raises(AssertionError, match=pattern):
        check_rule(plugin)
