"""Every solve option declared once: name, type, default, allowed values, unit, help.

In the spirit of scikit-learn's ``_parameter_constraints``: :data:`SOLVE_OPTIONS` holds one
:class:`Option` per keyword of :meth:`bvpnav.NavigationProblem.solve`, and everything that
takes a solve option is generated from it or checks through it:

- ``NavigationProblem.solve``: its signature and its Parameters section;
- :func:`bvpnav.solve.options.prepare`: each value checked (and normalised) by its
  option's rule before any work, then the checks that need several options or the
  installed solvers;
- the spec's ``[solve]`` table (:mod:`bvpnav.spec`): which keys it takes (``spec=True``)
  and each value's check, the message prefixed with the file and line;
- the command line (:mod:`bvpnav.cli`): one flag per option with a ``cli`` entry, on the
  commands it names, its text read by the option's ``from_text`` and then checked here;
- ``bvpnav.batch``: the overrides of a run and their fingerprint.

So a bad value gives the same text from ``solve()``, the spec and the command line
(``time_limit=-1: give a number of seconds > 0, or None for no limit``), and a new solve
option is one :func:`register_option` call (or one entry below) plus its use in a stage.

The rules are the small composable checks of :mod:`bvpnav.checks` (:func:`boolean`,
:func:`number`, :func:`one_of`, :func:`table`, ...). This module imports neither numpy nor
the formulation (the registries it consults are imported when a value is checked), so the
command line's parser is built from it in a fresh process without them.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from .checks import (
    ANY,
    Invalid,
    Rule,
    any_of,
    boolean,
    is_bool,
    is_real,
    mapping_of,
    nothing,
    number,
    one_of,
    table,
    text,
)
from .errors import InputError, SolverNotFound

__all__ = ["Rule", "Invalid", "Option", "SOLVE_OPTIONS", "register_option", "unregister_option",
           "check_option", "check_options", "boolean", "number", "one_of", "text", "table", "mapping_of",
           "any_of", "nothing", "UNCERTAINTY", "SEQUENTIAL", "ATTITUDE", "RULE", "solve_signature",
           "solve_parameters_doc", "defaults", "cli_options", "value_from_text"]


@dataclass(frozen=True)
class Option:
    """One solve option, declared once.

    Attributes
    ----------
    name : str
        The keyword of ``solve()`` and the key of the spec's ``[solve]``.
    default : Any
        The value when not given.
    rule : Rule
        Checks a value and returns it normalised (see :func:`check_option`).
    type : str
        The numpydoc type of ``solve()``'s Parameters section.
    help : str
        Its description there (reStructuredText).
    unit : str
        Physical unit, named in messages through the rule.
    spec : bool
        Whether the spec's ``[solve]`` table takes it.
    cli : str, optional
        Its command-line flag (e.g. ``"--time-limit"``); None for none.
    commands : tuple of str
        The commands that have the flag.
    cli_help : str
        The flag's help (plain text).
    from_text : callable, optional
        The flag's text to a value (default :func:`value_from_text`: a number when it reads
        as one, else the text); raises :class:`InputError` for text it cannot read.
    cli_kwargs : dict
        More :meth:`argparse.ArgumentParser.add_argument` keywords (``nargs``, ``const``,
        ``metavar``).
    error : type
        The :class:`InputError` subclass raised (``SolverNotFound`` for ``solver``).
    """

    name: str
    default: Any
    rule: Rule
    type: str
    help: str
    unit: str = ""
    spec: bool = True
    cli: str | None = None
    commands: tuple = ("solve", "batch")
    cli_help: str = ""
    from_text: Callable[[str], Any] | None = None
    cli_kwargs: dict = field(default_factory=dict)
    error: type = InputError

    def check(self, value, where: str | None = None):
        """``value`` checked and normalised, or :class:`InputError` naming the option, the
        value and what a valid one is (prefixed with ``where``: a spec's line, a flag)."""
        try:
            return self.rule(value)
        except Invalid as exc:
            shown = exc.shown if exc.shown is not None else repr(value)
            typed = f" ({type(value).__name__})" if exc.typed else ""
            head = f"{self.name}{exc.sep}" if exc.nested else f"{self.name}={shown}{typed}: "
            raise self.error((f"{where}: " if where else "") + head + exc.reason) from None


# ------------------------------------------------------------------ the options
#: :data:`bvpnav.backends.ACCURACIES` and :data:`bvpnav.formulation.LAM_RANGE` as written here, so
#: that this module (and the command line's parser made from it) imports neither numpy nor the
#: formulation; ``tests/test_options_declared.py`` checks that they agree.
ACCURACIES = ("low", "default", "high")
_LAMS = "1e-12..1e12"


def _solver_test(v):
    if not isinstance(v, str):
        raise Invalid(f"must be a name (str), got {v!r}; e.g. solver='direct' (installed: "
                      "bvpnav.available_solvers())")
    return v


def _lam_test(v):
    from .formulation import LAM_RANGE
    from .lam import rule_names

    rules = list(rule_names())
    if isinstance(v, str):
        if v not in rules:
            raise Invalid(f"not a known rule; choose one of {rules} or a number >= 0")
        return v
    if not is_real(v):
        raise Invalid(f"give a finite number >= 0 (e.g. lam=1.0) or a rule name from {rules}", typed=True)
    lam = float(v)
    if not math.isfinite(lam) or lam < 0:
        raise Invalid(f"must be a finite number >= 0 or a rule name from {rules}", shown=repr(lam))
    if lam != 0 and not LAM_RANGE[0] <= lam <= LAM_RANGE[1]:
        raise Invalid(
            f"outside {LAM_RANGE[0]:g}..{LAM_RANGE[1]:g} (or 0), the range in which double precision "
            "still weighs the soft items against the data term. For items that must hold exactly make "
            "them hard (sigma=None); to ignore them use lam=0; otherwise choose a lam in that range (or "
            "a rule, e.g. lam='lcurve')", shown=f"{lam:g}")
    return lam


#: Values of ``solve(uncertainty=...)`` other than True and False.
UNCERTAINTY = ("scaled",)


def _uncertainty_test(v):
    if is_bool(v):
        return bool(v)
    if isinstance(v, str) and v in UNCERTAINTY:
        return v
    low = v.strip().lower() if isinstance(v, str) else None
    hint = ""
    if low in ("true", "false", "stated", "yes", "no", "on", "off"):
        hint = " (a TOML boolean has no quotes: uncertainty = true or false; True or False in Python)"
    elif low in UNCERTAINTY:
        hint = f' (in lower case: uncertainty = "{low}")'
    raise Invalid('give True (standard deviations under the stated noise), "scaled" (scaled by the '
                  f"a-posteriori variance factor) or False; in a spec true, \"scaled\" or false{hint}")


def _fallback_test(v):
    how = ("use 'auto', None, or a list of solver names or (name, options) pairs, e.g. "
           "fallback=['direct', ('scs', {'max_iters': 20000})]")
    if v is None or v is False or v == "none":  # TOML has no None: "none" or false in a spec
        return None
    if isinstance(v, str):
        if v != "auto":
            raise Invalid(how)
        return v
    if not isinstance(v, list | tuple):
        raise Invalid(how, typed=True)
    for k, e in enumerate(v):
        if not (isinstance(e, str) or (isinstance(e, list | tuple) and len(e) == 2
                                       and isinstance(e[0], str) and isinstance(e[1], Mapping))):
            raise Invalid(f"entry {k} = {e!r}: {how}", nested=True)
    return v


def _options_test(v):
    if v is None:
        return None
    if not isinstance(v, Mapping):
        raise Invalid("give a dict of solver options, e.g. options={'max_iter': 500}, or None")
    return dict(v)


_TIME_LIMIT = any_of(number(0, low_open=True, unit="s"), nothing(),
                     want="a number of seconds > 0, or None for no limit")
_PROGRESS = any_of(boolean(), nothing(), want="True, False or None (a bar when stderr is a terminal)")
#: Checked where they are used: the sweep's range and engine, an initial trajectory.
_ANY = ANY
_POSITIVE_M = number(0, low_open=True, want="a positive distance in m")
_ITERATIONS = number(1, integer=True, want="an integer of at least one iteration")

#: The sequential loop's options (``solve(sequential={...})``) and their defaults.
SEQUENTIAL: dict[str, tuple[Any, Rule]] = {
    "tol": (1e-4, _POSITIVE_M), "max_iter": (30, _ITERATIONS), "initial": (None, _ANY),
    "lam_each": (False, boolean()), "continuation": (True, boolean()),
    "soft_tol": (None, any_of(_POSITIVE_M, nothing())), "progress": (None, _PROGRESS)}
#: The damped attitude loop's options (``solve(attitude={...})``) and their defaults.
ATTITUDE: dict[str, tuple[Any, Rule]] = {
    "tol": (1e-7, number(0, low_open=True, want="a positive angle in rad")), "ftol": (1e-12, number(0)),
    "max_iter": (30, _ITERATIONS),
    "heading": ("auto", one_of("auto", "search", "given", want="'auto' (search when the heading has no "
                                                             "prior), 'search' or 'given' (start from "
                                                             "the data's heading)")),
    "candidates": (12, number(2, integer=True, want="an integer of at least 2 headings")),
    "loop": (True, boolean()), "progress": (None, _PROGRESS), "quick": (True, boolean()),
    "cheap": (True, boolean()),
    "start": ("data", one_of("data", "course", want="'data' (the node states' first linearization point is "
                                                    "the data's attitude) or 'course' (a car's: the heading "
                                                    "of the fixes' velocity, bvpnav.solve.course)"))}
#: The lambda sweep's options (``solve(rule={...})``; checked as a whole by the sweep).
RULE: dict[str, tuple[Any, Rule]] = {
    "lam_range": ((1e-6, 1e6), _ANY), "points": (25, _ANY), "tau": (None, _ANY), "probes": (None, _ANY),
    "seed": (None, _ANY), "progress": (None, _PROGRESS), "engine": (None, _ANY)}


def defaults(keys: Mapping[str, tuple[Any, Rule]]) -> dict:
    """The defaults of a nested option table (:data:`SEQUENTIAL`, :data:`ATTITUDE`, :data:`RULE`)."""
    return {k: d for k, (d, _) in keys.items()}


def _nested(keys, what, example):
    return any_of(nothing(), table({k: r for k, (_, r) in keys.items()}, what, example),
                  want=f"a dict of {what} options, e.g. {example}, with keys from {list(keys)}")


def value_from_text(text: str):
    """A flag's text as a value: an int or a float when it reads as one, ``none`` as None,
    else the text itself (checked by the option's rule afterwards)."""
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    return None if text.strip().lower() == "none" else text


#: ``--uncertainty`` values and what they mean to ``solve(uncertainty=...)``.
UNCERTAINTY_FLAG = {"stated": True, "scaled": "scaled", "off": False}


def _uncertainty_from_text(value: str):
    import os

    if value in UNCERTAINTY_FLAG:
        return UNCERTAINTY_FLAG[value]
    hint = ""
    if os.path.splitext(str(value))[1].lower() in (".csv", ".parquet", ".pq", ".toml"):
        hint = ("; it took the file name that followed it: put --uncertainty after the input, or "
                "write --uncertainty=stated")
    raise InputError(f"--uncertainty {value!r}: choose stated (the default when no value is "
                     "given: standard deviations under the stated noise), scaled (scaled by the "
                     f"a-posteriori variance factor) or off (none, whatever the spec says){hint}")


def _options() -> list[Option]:
    lams = _LAMS
    return [
        Option("solver", "clarabel", Rule(_solver_test, "a solver name (str)"), "str",
               "Case-insensitive solver name (``bvpnav.available_solvers()``).",
               cli="--solver", cli_help="override the spec's solver (e.g. clarabel, osqp, direct, csne)",
               from_text=str, error=SolverNotFound),
        Option("lam", 1.0, Rule(_lam_test, f"0, a number in {lams} or a rule"),
               "float or str",
               "Weight of the item terms relative to the data term (dimensionless): 0 or "
               f"{lams} (:data:`bvpnav.formulation.LAM_RANGE`), or a rule that chooses it "
               "(``\"lcurve\"``, ``\"gcv\"``, ``\"discrepancy\"``, ``\"quasi\"``, or a registered "
               "one). Its value depends on the objective form: the acceleration form's data term is "
               "normalised by ``sigma_a``, the load form's carries the mass matrix (about one step h per "
               "row), so a lam chosen for one form (or, in the load form, one rate) is not one for the "
               "other: choose it again with a rule.",
               cli="--lam", commands=("solve", "batch", "compare"),
               cli_help="lambda: a number or a rule (lcurve, gcv, discrepancy, quasi); default from the spec",
               from_text=lambda s: float(s) if _reads_float(s) else s, cli_kwargs={"metavar": "LAM"}),
        Option("accuracy", "default", one_of(*ACCURACIES), '{"low", "default", "high"}',
               "Preset mapped to the solver's options and to the verification tolerance."),
        Option("verify", True, boolean(), "bool",
               "Refuse answers that fail bvpnav's recomputed residuals (default True; off only to "
               "inspect a failure: the result then says ``verified=False``).", spec=False),
        Option("options", None, Rule(_options_test, "a dict of solver options, or None"), "dict, optional",
               "Extra solver options on top of the preset. Clarabel's, OSQP's and the direct back ends' "
               "are checked before solving; other solvers judge theirs (a refusal is a failed attempt).",
               spec=False),
        Option("verbose", False, boolean(), "bool",
               "Pass the solver's own output through (cvxpy's ``verbose=True``; the direct back ends "
               "print nothing). Without it a solver's own printing is captured and kept in its attempt "
               "record. bvpnav's own account of the solve (attempts, the chosen lambda, sequential "
               "iterations, timings) is on the ``bvpnav`` logger at INFO and DEBUG whatever ``verbose`` "
               "is (see :mod:`bvpnav.log`).", spec=False),
        Option("fallback", "auto", Rule(_fallback_test, "'auto', None or a list of solvers"),
               '"auto", sequence or None',
               "Solver names or ``(name, options)`` pairs to try when an answer fails or the solver errs "
               "(the primary's ``options`` are not passed on). ``\"auto\"`` is "
               ":data:`bvpnav.solve.DEFAULT_FALLBACK`: Clarabel with static regularization, ``direct`` "
               "(skipped with the reason when not least squares), then SCS. ``None`` (in a spec "
               "``\"none\"`` or ``false``) disables it. Every attempt is in ``stats[\"attempts\"]`` with "
               "its reason."),
        Option("on_conflict", "raise", one_of("raise", "demote", want="'raise' or 'demote'"),
               '{"raise", "demote"}',
               "Hard information that cannot hold together raises :class:`~bvpnav.errors.Infeasible` "
               "naming the conflicting items, or with ``\"demote\"`` the lowest-priority item of each "
               "conflict becomes soft until the rest holds (``stats[\"demoted\"]`` and ``warnings`` say "
               "which, with what sigma)."),
        Option("priority", None,
               any_of(nothing(), mapping_of(number(), "item", "priority={'survey point': 10}"),
                      want="a dict of item name -> number, e.g. priority={'survey point': 10}"),
               "mapping of str to float, optional",
               "Item label -> priority for demotion (higher is kept hard longer; default 0, among equals "
               "the item added last goes first)."),
        Option("demote_sigma", None,
               any_of(nothing(), number(0, low_open=True),
                      mapping_of(number(0, low_open=True), "item", "demote_sigma={'ends': 0.5}"),
                      want="a number > 0 (item units) or a dict of item name -> number > 0"),
               "float or mapping of str to float, optional",
               "Sigma (item units) of a demoted item, one for all or per label; default 1.0."),
        Option("sequential", None, _nested(SEQUENTIAL, "sequential loop", "sequential={'max_iter': 50}"),
               "dict, optional",
               "Options of the loop for items that must be linearized (``tol``, ``soft_tol`` in m, "
               "``max_iter``, ...; :func:`bvpnav.solve.sequential.with_sequential`).", spec=False),
        Option("rule", None, _nested(RULE, "lambda sweep", "rule={'lam_range': (1e-4, 1e4)}"),
               "dict, optional",
               "Options of the lambda sweep (``lam_range``, ``points``, ...; "
               ":func:`bvpnav.solve.lambda_curve`).", spec=False),
        Option("uncertainty", False, Rule(_uncertainty_test, "True, False or 'scaled'"), 'bool or "scaled"',
               "Add standard deviations: ``<axis>_std`` (m) and ``v<axis>_std`` (m/s) columns to "
               "``trajectory``, ``error_params_std``, ``covariance(...)`` and ``stats[\"uncertainty\"]`` "
               "(see :mod:`bvpnav.solve.uncertainty`). True: the covariance of the weights as stated (the "
               "posterior covariance when ``lam = 1`` and the sigmas are the true noise); ``\"scaled\"``: "
               "multiplied by the a-posteriori variance factor (for sigmas that are only relative, or a "
               "``lam`` chosen by a rule). O(N) time and memory.",
               cli="--uncertainty", from_text=_uncertainty_from_text,
               cli_kwargs={"nargs": "?", "const": "stated", "metavar": "HOW"},
               cli_help="also the standard deviations: <axis>_std (m) and v<axis>_std (m/s) columns in the "
                        "trajectory, and the summary's uncertainty record and error-model std. HOW: stated "
                        "(the default: under sigma_a and the items' sigma as given), scaled (times the "
                        "a-posteriori variance factor: for sigmas that are only relative) or off; overrides "
                        "the spec's [solve] uncertainty"),
        Option("attitude", None, _nested(ATTITUDE, "attitude loop", "attitude={'max_iter': 50}"),
               "dict, optional",
               "Options of the damped outer loop that error models acting on the attitude "
               "(``AttitudeError``, ``GyroBias``, ``GyroScaleFactor``) are solved by: ``tol`` (rad), "
               "``max_iter``, ``heading`` (``\"auto\"``, ``\"search\"``, ``\"given\"``), ``candidates``, "
               "``loop``, ``progress``, and for ``ErrorStates`` ``quick``, ``cheap`` and ``start`` "
               "(``\"data\"``, or "
               "``\"course\"``: a car's heading from the position fixes, :mod:`bvpnav.solve.course`) "
               "(:func:`bvpnav.solve.attitude.with_attitude`)."),
        Option("time_limit", None, _TIME_LIMIT, "float or None",
               "Seconds each back-end attempt may take (None: no limit). A cvxpy solver gets it as its "
               "own option (Clarabel and OSQP ``time_limit``, SCS ``time_limit_secs``, HiGHS "
               "``time_limit``; an option of the same name in ``options`` wins); a back end without one "
               "(``direct``, ``csne``, other cvxpy solvers) runs to the end and its answer is discarded "
               "when it took longer. An attempt stopped by the limit is recorded as \"time limit "
               "reached (X s)\" and the fallback chain moves on.", unit="s",
               cli="--time-limit", commands=("solve", "batch", "compare"), cli_kwargs={"metavar": "SECONDS"},
               cli_help="seconds each solver attempt may take (none: no limit); overrides the spec's [solve] "
                        "time_limit"),
    ]


def _g(x: float) -> str:
    """``1e+12`` as ``1e12``."""
    return f"{x:g}".replace("e+", "e")


def _reads_float(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


#: Every solve option by name, in the order of ``solve()``'s signature.
SOLVE_OPTIONS: dict[str, Option] = {o.name: o for o in _options()}


def register_option(option: Option) -> Option:
    """Add (or replace) a solve option: ``solve()``, the spec and the CLI take it at once
    (a stage reads it as ``opts.<name>``)."""
    if not (isinstance(option.name, str) and option.name.isidentifier()):
        raise InputError(f"register_option: {option.name!r} is not a keyword name")
    SOLVE_OPTIONS[option.name] = option
    return option


def unregister_option(name: str) -> None:
    """Remove a solve option (one a test added)."""
    SOLVE_OPTIONS.pop(name, None)


def check_option(name: str, value, where: str | None = None):
    """``value`` of option ``name`` checked and normalised (see :meth:`Option.check`)."""
    return SOLVE_OPTIONS[name].check(value, where)


def check_options(given: Mapping[str, Any], what: str = "solve") -> dict:
    """Every declared option's value (given, else its default), checked; an unknown name is
    an :class:`InputError` listing the valid ones."""
    unknown = [k for k in given if k not in SOLVE_OPTIONS]
    if unknown:
        import difflib

        close = difflib.get_close_matches(str(unknown[0]), list(SOLVE_OPTIONS), n=1)
        raise InputError(f"{what}: unknown option(s) {unknown}" + (f" (did you mean {close[0]!r}?)" if close
                                                                    else "")
                         + f"; valid: {list(SOLVE_OPTIONS)}")
    return {name: opt.check(given[name]) if name in given else opt.default
            for name, opt in SOLVE_OPTIONS.items()}


def solve_signature(with_self: bool = True) -> inspect.Signature:
    """The signature of ``solve()`` made from the declaration (``solver`` and ``lam`` may be
    given by position, the rest by keyword, as before)."""
    P = inspect.Parameter
    params = [P("self", P.POSITIONAL_OR_KEYWORD)] if with_self else []
    for k, o in enumerate(SOLVE_OPTIONS.values()):
        kind = P.POSITIONAL_OR_KEYWORD if k < 2 else P.KEYWORD_ONLY
        params.append(P(o.name, kind, default=o.default))
    return inspect.Signature(params)


def solve_parameters_doc(indent: str = "        ") -> str:
    """The numpydoc Parameters section of ``solve()``, from the declaration."""
    import textwrap

    lines = ["Parameters", "----------"]
    for o in SOLVE_OPTIONS.values():
        lines.append(f"{o.name} : {o.type}")
        lines += textwrap.wrap(o.help, 88, initial_indent="    ", subsequent_indent="    ")
    return "\n".join(indent + ln if ln else ln for ln in lines)


def cli_options(command: str) -> list[Option]:
    """The options with a flag on ``command``."""
    return [o for o in SOLVE_OPTIONS.values() if o.cli and command in o.commands]


def from_flag(option: Option, text_value: str):
    """A flag's text checked as the option's value: read by ``from_text``, then the rule
    (the same message as ``solve()``'s, after the flag)."""
    conv = option.from_text or value_from_text
    value = conv(text_value)
    return option.check(value, where=option.cli)
