"""Spec files: a problem's information, error model, form, solver and lambda rule in TOML.

A spec lists items by their registered names (``bvpnav.items.registry()``) and error
models by theirs (:func:`error_model_registry`), with their parameters; the input
section maps a recording's columns and units. It is parsed with :mod:`tomllib` only
(``tomli``, the same parser, on Python 3.10) and can never import or execute code: every
name is looked up in the registries, every field checked against the class, and anything
unknown is an error that names the line and lists the valid choices.

Example::

    [input]                       # how to read a recording (CSV or Parquet)
    time = "t"                    # time column
    time_unit = "s"               # s, ms, us or ns; "iso8601" for timestamps (seconds from
                                  # the first sample, kept in data.time_origin)
    time_origin = "first"         # optional: count numeric times from the first sample
                                  # (exact for integer epochs, e.g. int64 ns)
    columns = { x = "acc_x" }     # axis name -> acceleration column
    unit = "m/s^2"                # m/s^2, g, mg or ft/s^2

    [align]                       # optional, strapdown from gyro rates: the attitude at t[0]
    rest = [0.0, 4.5]             # s at rest: roll and pitch (or "first": the detector's)
    heading = "fixes"             # from the position fixes; a yaw in degrees; or "search"

    [problem]
    residual = "acceleration"     # or "load" (the 2011 paper's form)
    sigma_a = 1.0                 # m/s^2
    segment = 1.0                 # optional: a coarse mesh, no element longer than this (s)

    [solve]
    solver = "direct"
    accuracy = "default"
    lam = "lcurve"                # a number or a rule: lcurve, gcv, discrepancy, quasi
    uncertainty = true            # optional: standard deviations too (true: the stated
                                  # noise; "scaled": by the a-posteriori variance factor)
    time_limit = 60               # optional: seconds per solver attempt

    [[error_model]]
    type = "bias"

    [[item]]
    type = "position"
    name = "ends"
    t = [0.0, 10.0]
    value = [0.0, 10.0]
"""

from __future__ import annotations

import dataclasses
import math
import re
import sys
from typing import Any

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, packaged as tomli (a dependency there)
    import tomli as tomllib

from . import error_models as em
from .declare import SOLVE_OPTIONS
from .errors import InputError
from .formulation import RESIDUAL_FORMS
from .imu import ACC_UNITS as _ACC_UNITS
from .io import read_regular_file
from .items import _snake, positive_array, registry
from .mesh import check_segment
from .problem import NavigationProblem
from .timebase import TIME_UNITS as _TIME_UNITS

__all__ = ["Spec", "load_spec", "read_spec_text", "parse_spec", "dumps_spec", "problem_to_spec", "to_spec",
           "problem_from_spec", "error_model_registry", "TIME_UNITS", "ACC_UNITS"]

#: Seconds per unit of the time column (``time_unit = "iso8601"`` reads timestamps instead).
TIME_UNITS = _TIME_UNITS
#: m/s^2 per unit of the acceleration columns.
ACC_UNITS = _ACC_UNITS

_SECTIONS = {
    "input": None,  # the readers' options and the frame options: see _input_keys()
    "problem": {"residual", "sigma_a", "segment"},
    "solve": None,  # the declared solve options the spec takes: see _solve_keys()
    "stationary": None,  # detector options and the items' fields: see _STATIONARY_KEYS
    "align": None,  # the initial attitude of a strapdown recording: see _ALIGN_KEYS
    "error_model": None,  # array of tables, checked per model
    "item": None,  # array of tables, checked per item
}


#: ``[stationary]``: the options of :func:`bvpnav.detect.stationary`, then the fields of the
#: :class:`ZeroVelocity` items made from the intervals (``name`` gets a number appended).
_STATIONARY_KEYS = {"method", "window", "threshold", "sigma_a", "sigma_w", "acc_threshold", "gyro_threshold",
                    "gravity", "min_duration"}
_STATIONARY_ITEM_KEYS = {"sigma", "mode", "name"}

#: ``[align]``: the attitude at the first sample of a recording whose attitude is integrated
#: from gyro rates (:func:`bvpnav.align.align_recording`): roll and pitch from the interval at
#: rest, the heading given (degrees), from the fixes, or searched by the solve.
_ALIGN_KEYS = {"rest", "heading", "fixes", "min_distance", "min_rest"}


def error_model_registry() -> dict[str, type]:
    """Concrete error-model classes by registered name (snake case of the class name)."""
    out: dict[str, type] = {}
    abstract = {"ErrorModel", "SensorErrorModel", "CompositeErrorModel", "AttitudeErrorModel"}

    def walk(cls):
        for sub in cls.__subclasses__():
            if sub.__name__ not in abstract and not sub.__name__.startswith("_") \
                    and dataclasses.is_dataclass(sub):
                out[_snake(sub.__name__)] = sub
            walk(sub)

    walk(em.ErrorModel)
    return dict(sorted(out.items()))


@dataclasses.dataclass
class Spec:
    """A parsed spec: plain data, not yet bound to a recording.

    Attributes
    ----------
    input : dict
        ``time``, ``time_unit`` (or ``"iso8601"``), ``time_origin`` (``"first"``),
        ``columns`` (axis -> column), ``unit``.
    problem : dict
        Keyword arguments of :class:`bvpnav.NavigationProblem` (``residual``, ``sigma_a``,
        ``segment``).
    solve : dict
        Keyword arguments of :meth:`bvpnav.NavigationProblem.solve`: the declared options
        with ``spec=True`` (:data:`bvpnav.declare.SOLVE_OPTIONS`: ``solver``, ``accuracy``,
        ``lam``, ``fallback``, ``on_conflict``, ``priority``, ``demote_sigma``,
        ``uncertainty``, ``attitude``, ``time_limit``, and any option registered there).
    items : list
        Item instances.
    error_models : list
        Error-model instances (combined with ``+``).
    """

    input: dict
    problem: dict
    solve: dict
    items: list
    error_models: list
    #: Where each ``[problem]``/``[solve]`` key was written (``"spec.toml, line 12"``), for
    #: errors found only once the data is known (empty when built in code).
    where: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)
    #: ``[stationary]``: detect the stationary intervals in the recording and add a
    #: :class:`ZeroVelocity` item for each (empty: no detection). See :meth:`stationary_items`.
    stationary: dict = dataclasses.field(default_factory=dict)
    #: ``[align]``: roll and pitch from the interval at rest, the heading given, from the fixes
    #: or searched (empty: the attitude starts at ``[input] initial_attitude``). See :meth:`imu_data`.
    align: dict = dataclasses.field(default_factory=dict)

    def imu_data(self, rec, info=()):
        """The recording's :class:`bvpnav.ImuData` under ``[input]``, aligned by ``[align]``.

        Parameters
        ----------
        rec : bvpnav.readers.Recording
        info : sequence of Item, optional
            Items the recording and its information files hold (GNSS fixes): with the spec's
            own, the fixes of ``heading = "fixes"``.

        Notes
        -----
        With ``[align]``, the attitude at ``t[0]`` is :func:`bvpnav.align.align_recording`'s
        (the detector of ``rest = "first"`` takes ``[stationary]``'s options) and the record
        of it is ``data.checks["align"]`` (in the solution's ``stats["data_checks"]`` and the
        JSON summary): the same numbers as ``bvpnav.align.align`` then
        ``ImuData.from_gyro(..., initial_attitude=C0)`` in Python.
        """
        if not self.align:
            return rec.imu_data(self.input)
        from .align import align_recording
        from .strapdown import imu_data

        at = self.where.get("align", "[align]")
        al = self.align
        fixes = _fixes(list(self.items) + list(info), al.get("fixes"), at) if al.get("heading") == "fixes" \
            else None
        detector = {k: v for k, v in self.stationary.items() if k in _STATIONARY_KEYS - {"min_duration"}}
        try:
            c0, record = align_recording(rec, self.input, rest=al.get("rest", "first"),
                                         heading=al.get("heading", "search"), fixes=fixes,
                                         min_distance=al.get("min_distance", 10.0),
                                         min_rest=al.get("min_rest", 1.0), detector=detector)
        except InputError as exc:
            raise InputError(f"{at}: {exc}") from None
        data = imu_data(rec, self.input, initial_attitude=c0)
        data.checks["align"] = record
        return data

    def stationary_options(self, data) -> dict:
        """The keyword arguments of :func:`bvpnav.detect.stationary` that ``[stationary]`` gives
        for ``data``: its detector keys, with ``gravity`` defaulting to the recording's gravity
        magnitude (m/s^2)."""
        opts = {k: v for k, v in self.stationary.items() if k in _STATIONARY_KEYS}
        if "gravity" not in opts and getattr(data, "gravity", None) is not None:
            opts["gravity"] = float(np.linalg.norm(data.gravity))
        return opts

    def stationary_items(self, data) -> list:
        """The :class:`ZeroVelocity` items of ``[stationary]`` for ``data`` (strapdown), or [].

        The detector (:func:`bvpnav.detect.stationary`) takes the ``[stationary]`` options
        (``method`` default ``"shoe"``; ``gravity`` default the recording's gravity
        magnitude); ``sigma``/``mode`` make the items soft or hard (hard by default) and
        ``name`` (default ``"stationary"``) is numbered per interval.
        """
        if not self.stationary:
            return []
        from . import detect

        opts = self.stationary_options(data)
        item_kw = {k: v for k, v in self.stationary.items() if k in _STATIONARY_ITEM_KEYS}
        item_kw.setdefault("name", "stationary")
        at = self.where.get("stationary", "[stationary]")
        try:
            intervals = detect.stationary(data, **opts)
        except InputError as exc:
            raise InputError(f"{at}: {exc}") from None
        if not intervals:
            raise InputError(f"{at}: the {opts.get('method', 'shoe')} detector found no stationary "
                             "interval in the recording; check the threshold with `bvpnav stationary INPUT "
                             "--spec SPEC --plot PNG` (or bvpnav.plot.stationary), or drop [stationary]")
        return detect.zero_velocity_items(intervals, **item_kw)

    def error_model(self):
        """The combined error model, or None."""
        if not self.error_models:
            return None
        out = self.error_models[0]
        for m in self.error_models[1:]:
            out = out + m
        return out

    def build(self, data, info=()):
        """A :class:`bvpnav.NavigationProblem` for ``data`` (ImuData) from this spec.

        Parameters
        ----------
        data : ImuData
        info : sequence of Item, optional
            Information the recording itself holds (a reader's ``Recording.items``: GNSS
            fixes, odometry), added after the spec's items; a name used by both is refused.
        """

        try:
            prob = NavigationProblem(data, error_model=self.error_model(), **self.problem)
        except InputError as exc:
            key = next((k for k in self.problem if k in str(exc) and k in self.where), None)
            if key is None:
                raise
            raise InputError(f"{self.where[key]}: {exc}") from None
        prob.add(*self.items)
        if info:
            prob.add(*info)
        stationary = self.stationary_items(data)
        if stationary:
            prob.add(*stationary)
        labels = prob.item_labels
        for key in ("priority", "demote_sigma"):
            table = self.solve.get(key)
            unknown = sorted(set(table) - set(labels)) if isinstance(table, dict) else []
            if unknown:
                at = self.where.get(key, "spec")
                raise InputError(f"{at}: {key} names unknown item(s) {unknown}; the problem's items are "
                                 f"{labels}: use one of these names (or give the item name = \"...\")")
        return prob


# ------------------------------------------------------------------ reading
def _line_of(text: str, key: str, section: str | None = None, index: int = 0) -> int | None:
    """1-based line of ``key = ...`` inside the ``index``-th ``[section]``/``[[section]]``."""
    lines = text.splitlines()
    start, end = 0, len(lines)
    if section is not None:
        heads = [i for i, ln in enumerate(lines)
                 if re.match(rf"^\s*\[\[?\s*{re.escape(section)}\s*\]\]?\s*(#.*)?$", ln)]
        if index >= len(heads):
            return None
        start = heads[index]
        nxt = [i for i, ln in enumerate(lines) if i > start and re.match(r"^\s*\[", ln)]
        end = nxt[0] if nxt else len(lines)
        if key is None:
            return start + 1
    for i in range(start, end):
        if re.match(rf"^\s*{re.escape(key)}\s*=", lines[i]):
            return i + 1
    return start + 1 if section is not None else None


def _where(source: str, line: int | None) -> str:
    return f"{source}, line {line}" if line else source


def _has_datetime(v) -> bool:
    """Whether a TOML value is or holds a date, time or date-time."""
    import datetime

    if isinstance(v, (datetime.date, datetime.time)):  # datetime.datetime is a date
        return True
    if isinstance(v, list):
        return any(_has_datetime(x) for x in v)
    if isinstance(v, dict):
        return any(_has_datetime(x) for x in v.values())
    return False


def _instantiate(cls, kind: str, fields: dict, text: str, section: str, index: int, source: str):
    allowed = [f.name for f in dataclasses.fields(cls) if f.init]
    for key in fields:
        if key not in allowed:
            line = _line_of(text, key, section, index)
            raise InputError(f"{_where(source, line)}: {kind} {_snake(cls.__name__)!r} has no field "
                             f"{key!r}; valid fields: {allowed}")
    for key in ("name", "mode"):
        if key in fields and not isinstance(fields[key], str):
            line = _line_of(text, key, section, index)
            raise InputError(f"{_where(source, line)}: {kind} {_snake(cls.__name__)!r}: {key}="
                             f"{fields[key]!r}; give a string, e.g. {key} = \"...\"")
    for key, v in fields.items():
        if _has_datetime(v):
            line = _line_of(text, key, section, index)
            raise InputError(f"{_where(source, line)}: {kind} {_snake(cls.__name__)!r}: {key} holds a TOML "
                             "date/time; spec times are numbers in s on the recording's time axis (seconds "
                             'from the first sample when [input] has time_unit = "iso8601"): write e.g. '
                             f"{key} = 12.5")
    try:
        return cls(**fields)
    except InputError as exc:
        line = _line_of(text, None, section, index)
        raise InputError(f"{_where(source, line)}: {exc}") from None
    except (TypeError, ValueError, OverflowError) as exc:
        line = _line_of(text, None, section, index)
        raise InputError(f"{_where(source, line)}: {kind} {_snake(cls.__name__)!r}: {exc}; check the "
                         f"fields' types and values against the {kind}'s documentation") from None


def _check_values(plain: dict, text: str, source: str) -> None:
    """Check the values of ``[problem]``, ``[solve]`` and ``[input]`` (not only their keys)."""
    def at(sec: str):
        return lambda key: _where(source, _line_of(text, key, sec))

    _check_problem_values(plain["problem"], at("problem"))
    _check_solve_values(plain["solve"], at("solve"))
    _check_input_values(plain["input"], at("input"))
    _check_stationary_values(plain["stationary"], at("stationary"))
    _check_align_values(plain["align"], plain["input"], at("align"), at("input"))


def _check_stationary_values(tab: dict, where) -> None:
    """Check ``[stationary]``: the detector's name and the items' name and mode (the rest is
    checked by the detector and the item, with the section's line)."""
    if not tab:
        return
    from .detect import METHODS

    if tab.get("method", "shoe") not in METHODS:
        raise InputError(f"{where('method')}: method = {tab['method']!r}; stationary detectors: "
                         f"{list(METHODS)}")
    for key in ("name", "mode"):
        if key in tab and not isinstance(tab[key], str):
            raise InputError(f"{where(key)}: {key} = {tab[key]!r}; give a string, e.g. {key} = \"...\"")


def _align_number(v, positive: bool) -> bool:
    """Whether ``v`` is a finite real number (not a boolean), and > 0 if ``positive``."""
    from .checks import is_real

    return is_real(v) and math.isfinite(v) and (v > 0 if positive else True)


def _check_align_values(tab: dict, inp: dict, where, where_input) -> None:
    """Check ``[align]``'s values, and that ``[input]`` does not give the attitude too."""
    if not tab:
        return
    from .align import HEADINGS

    for key in ("initial_attitude", "attitude"):
        if key in inp:
            what = ("gives the attitude at the first sample" if key == "initial_attitude" else
                    "reads the orientation from the file")
            raise InputError(f"{where_input(key)}: [input] {key} {what}, and [align] computes it from the "
                             f"interval at rest: keep one (drop {key}, or drop [align])")
    rest = tab.get("rest", "first")
    ok = rest == "first" or (isinstance(rest, list) and len(rest) == 2 and all(_align_number(v, False)
                                                                                for v in rest)
                             and rest[0] < rest[1])
    if not ok:
        raise InputError(f"{where('rest')}: rest = {rest!r}; give the interval at rest in s, rest = [t0, t1] "
                         'with t0 < t1 (e.g. rest = [0.0, 4.5]), or rest = "first" (the first interval the '
                         "stationary detector finds)")
    heading = tab.get("heading", "search")
    if not (_align_number(heading, False) or heading in HEADINGS):
        raise InputError(f"{where('heading')}: heading = {heading!r}; give the yaw at the first sample in "
                         "degrees (counterclockwise from east in ENU, clockwise from north in NED; e.g. "
                         'heading = 30.0), "fixes" (from the position fixes) or "search" (the solve searches '
                         "it)")
    if "fixes" in tab and (heading != "fixes" or not isinstance(tab["fixes"], str)):
        raise InputError(f"{where('fixes')}: fixes = {tab['fixes']!r} names the position item the heading "
                         'comes from; it goes with heading = "fixes" and is a name, e.g. fixes = "gnss"')
    for key, default in (("min_distance", 10.0), ("min_rest", 1.0)):
        if key in tab and not _align_number(tab[key], True):
            unit = "m between the fixes" if key == "min_distance" else "s, the shortest interval at rest"
            raise InputError(f"{where(key)}: {key} = {tab[key]!r}; give a positive number ({unit}; default "
                             f"{default:g})")


def _check_align_models(plain: dict, models: list, text: str, source: str) -> None:
    """``heading = "search"`` needs a solve that searches: an ``attitude_error`` model estimating
    the heading, free (no sigma on z) or with ``[solve] attitude = {heading = "search"}``."""
    if plain["align"].get("heading", "search") != "search":
        return
    from .error_models.attitude_error import AttitudeError

    line = _where(source, _line_of(text, "heading", "align"))
    asked = (plain["solve"].get("attitude") or {}).get("heading", "auto")
    att = next((m for m in models if isinstance(m, AttitudeError) and "attitude_z" in m.names(None)), None)
    if att is None:
        raise InputError(f"{line}: heading = \"search\" (the default) starts from yaw 0 for the solve to "
                         "search the heading, but no [[error_model]] estimates it: add [[error_model]] "
                         'type = "attitude_error" (sigma = [tilt, tilt, inf]), or give the heading in '
                         'degrees or heading = "fixes"')
    free = not np.isfinite(att.prior_sigma(None)[att.names(None).index("attitude_z")])
    if asked == "given" or (asked == "auto" and not free):
        why = ("[solve] attitude has heading = \"given\"" if asked == "given" else
               "the attitude_error model has a sigma on the heading, so the solve keeps it")
        raise InputError(f"{line}: heading = \"search\" starts from yaw 0 for the solve to search, but "
                         f"{why}: " 'set [solve] attitude = { heading = "search" }, or give the heading in '
                         "degrees")


def _fixes(items: list, name, at: str):
    """(t, xy) of the position fixes for ``[align] heading = "fixes"``: the position item named
    ``name``, or the only one with x and y."""
    from .items import broadcast_rows

    cands = []
    for it in items:
        if type(it).registered_name() != "position":
            continue
        axes = list(it.axes) if it.axes is not None else ["x", "y", "z"]
        if "x" in axes and "y" in axes and (name is None or it.label == name):
            cands.append((it, axes))
    names = [it.label for it in items if type(it).registered_name() == "position"]
    if len(cands) != 1:
        if not cands:
            why = (f"no position item named {name!r} with x and y" if name is not None else
                   "no position item with x and y")
            fix = (f"the position items are {names}" if names else "add a [[item]] type = \"position\" "
                   "(or --info FILE with GNSS fixes)")
        else:
            why = f"{len(cands)} position items {[c[0].label for c in cands]}"
            fix = 'name one: fixes = "..."'
        raise InputError(f'{at}: heading = "fixes": {why}; {fix}, or give the heading in degrees or '
                         'heading = "search"')
    it, axes = cands[0]
    k = it.n_instants()
    vals = broadcast_rows(it.value, k, len(axes), f"{it.label}: value", "m").reshape(k, len(axes))
    return np.asarray(it.t, dtype=float), vals[:, [axes.index("x"), axes.index("y")]]


def _check_problem_values(prob: dict, where) -> None:
    """Check ``[problem]``: the residual form, ``sigma_a`` and ``segment`` (``where(key)`` names
    the line)."""

    if "residual" in prob and not (isinstance(prob["residual"], str) and prob["residual"] in RESIDUAL_FORMS):
        raise InputError(f"{where('residual')}: residual={prob['residual']!r}; choose one of "
                         f"{list(RESIDUAL_FORMS)}")
    if "sigma_a" in prob:
        sa = prob["sigma_a"]
        if isinstance(sa, bool) or (isinstance(sa, list) and any(isinstance(v, bool) for v in sa)):
            raise InputError(f"{where('sigma_a')}: sigma_a={sa!r}; give a number in m/s^2")
        try:
            arr = positive_array(sa, "sigma_a (m/s^2)", allow_none=False)
        except (InputError, OverflowError) as exc:
            raise InputError(f"{where('sigma_a')}: {exc}") from None
        if arr.ndim > 1 or arr.size not in (1, 2, 3):
            raise InputError(f"{where('sigma_a')}: sigma_a={sa!r}; give one number in m/s^2 or "
                             "one per axis")
    if "segment" in prob:
        try:
            check_segment(prob["segment"])
        except InputError as exc:
            raise InputError(f"{where('segment')}: {exc}") from None


def _solve_keys() -> set[str]:
    """The keys ``[solve]`` takes: the declared solve options with ``spec=True``
    (:data:`bvpnav.declare.SOLVE_OPTIONS`)."""
    return {name for name, opt in SOLVE_OPTIONS.items() if opt.spec}


def _check_solve_values(solve: dict, where) -> None:
    """Check every ``[solve]`` value by its declaration (the same check and message as
    ``solve()``'s, after the line), and ``priority``/``demote_sigma`` beside an explicit
    ``on_conflict = "raise"``."""
    for key, value in solve.items():
        SOLVE_OPTIONS[key].check(value, where(key))
    # an explicit on_conflict = "raise" beside them contradicts them; without on_conflict they
    # are kept for a later "demote" (tests/test_cli.py switches a spec between the two)
    for key in ("priority", "demote_sigma"):
        if key in solve and solve.get("on_conflict") == "raise":
            raise InputError(f"{where(key)}: {key} is set but on_conflict is 'raise', so it "
                             "would be ignored; "
                             f'add on_conflict = "demote" to [solve] (or remove {key})')


def _check_input_values(inp: dict, where) -> None:
    """Check ``[input]``: reader, time column, time unit and origin, acceleration unit, columns,
    strapdown columns and frames."""
    if "format" in inp:
        from .readers import get_reader

        try:
            get_reader(inp["format"])
        except InputError as exc:
            raise InputError(f"{where('format')}: {exc}") from None
    _check_frame_values(inp, where)
    for key, k in (("specific_force", 3), ("gyro", 3)):
        v = inp.get(key)
        if v is not None and not (isinstance(v, list) and len(v) == k and all(isinstance(c, str) and c
                                                                             for c in v)):
            raise InputError(f"{where(key)}: {key} = {v!r}; give the {k} column names in axis order, e.g. "
                             f"{key} = {[f'{key[0]}_{a}' for a in 'xyz']}")
    if "time" in inp and not isinstance(inp["time"], str):
        raise InputError(f"{where('time')}: time={inp['time']!r}; give the "
                         'name of the time column as a string, e.g. time = "t"')
    if "time_unit" in inp and not (isinstance(inp["time_unit"], str)
                                   and (inp["time_unit"] in TIME_UNITS or inp["time_unit"] == "iso8601")):
        raise InputError(f"{where('time_unit')}: time_unit="
                         f"{inp['time_unit']!r}; valid units: {list(TIME_UNITS)} for numbers, or \"iso8601\" "
                         "for timestamps")
    if "time_origin" in inp and inp["time_origin"] != "first":
        raise InputError(f"{where('time_origin')}: time_origin={inp['time_origin']!r}; the only "
                         'choice is "first" (count the times from the first sample), or omit the key')
    if "unit" in inp and not (isinstance(inp["unit"], str) and inp["unit"] in ACC_UNITS):
        raise InputError(f"{where('unit')}: unit={inp['unit']!r}; "
                         f"valid acceleration units: {list(ACC_UNITS)}")
    if "columns" in inp and not (isinstance(inp["columns"], dict) and inp["columns"]
                                 and all(isinstance(v, str) for v in inp["columns"].values())):
        raise InputError(f"{where('columns')}: columns must map "
                         'axis names to column names, e.g. columns = { x = "acc_x" }')


def _check_frame_values(inp: dict, where) -> None:
    """Check the frame options of ``[input]`` (navigation frame, gravity, rotations), naming the line."""
    from . import strapdown

    frame = inp.get("frame", "enu")
    if not isinstance(frame, str) or frame not in strapdown.FRAMES:
        raise InputError(f"{where('frame')}: frame = {frame!r}; valid navigation frames: "
                         + ", ".join(f"{k!r} ({v})" for k, v in strapdown.FRAMES.items()))
    if "attitude_frame" in inp and not (isinstance(inp["attitude_frame"], str)
                                        and inp["attitude_frame"] in strapdown.FRAMES):
        raise InputError(f"{where('attitude_frame')}: attitude_frame = {inp['attitude_frame']!r}; the "
                         f"orientation's reference frame is one of {sorted(strapdown.FRAMES)}")
    keys = [k for k in ("gravity", "latitude", "height") if k in inp]
    try:
        strapdown.gravity_vector(inp, frame)
    except InputError as exc:
        raise InputError(f"{where(keys[0] if keys else 'gravity')}: {exc}") from None
    r = inp.get("gyro_range", 1.0)
    if isinstance(r, bool) or not isinstance(r, (int, float)) or not (math.isfinite(r) and r > 0):
        raise InputError(f"{where('gyro_range')}: gyro_range = {r!r}; the gyro's full-scale range in rad/s "
                         "(e.g. 34.9 for 2000 deg/s)")
    for key in ("body_to_sensor", "initial_attitude"):
        if key in inp:
            try:
                strapdown.rotation_option(inp[key], key)
            except InputError as exc:
                raise InputError(f"{where(key)}: {exc}") from None


#: Largest spec file read, bytes (a spec is a small text file).
MAX_SPEC_BYTES = 10 * 1024 * 1024


def parse_spec(text: str, source: str = "spec") -> Spec:
    """Parse TOML text into a :class:`Spec`.

    Raises
    ------
    InputError
        For TOML syntax errors, unknown sections, keys, item or error-model names, and
        invalid values (of ``[input]``, ``[problem]`` and ``[solve]`` too: residual form,
        ``sigma_a`` > 0, and every ``[solve]`` value by its declaration in
        :data:`bvpnav.declare.SOLVE_OPTIONS`, with ``solve()``'s message; and values
        of the wrong TOML type anywhere), naming the line and listing the valid choices;
        for values nested too deeply to read, and for two items with the same name.
    """
    try:
        return _parse_spec(text, source)
    except RecursionError:
        raise InputError(f"{source}: values nested too deeply to read (arrays or tables inside one "
                         "another hundreds of levels deep); a spec needs at most a few levels: fix that "
                         "value") from None


def _parse_spec(text: str, source: str = "spec") -> Spec:
    """Parse ``text`` (see :func:`parse_spec`)."""
    if text.startswith("\ufeff"):  # a UTF-8 byte-order mark: an encoding marker, not TOML
        text = text[1:]
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: not valid TOML: {exc}") from None
    for sec in doc:
        if sec not in _SECTIONS:
            line = _line_of(text, None, sec) or _line_of(text, sec)
            raise InputError(f"{_where(source, line)}: unknown section {sec!r}; valid sections: "
                             f"{sorted(_SECTIONS)}")
    plain = {sec: _plain_table(doc, sec, text, source)
             for sec in ("input", "problem", "solve", "stationary", "align")}
    _check_values(plain, text, source)
    reg_items = registry()
    reg_models = error_model_registry()
    objs = {sec: _instances(doc, sec, reg, kind, text, source)
            for sec, reg, kind in (("item", reg_items, "item"), ("error_model", reg_models, "error model"))}
    _check_item_names(doc, text, source)
    where = {k: _where(source, _line_of(text, k, sec)) for sec in ("problem", "solve") for k in plain[sec]}
    if plain["stationary"]:
        where["stationary"] = _where(source, _line_of(text, None, "stationary"))
    if plain["align"]:
        where["align"] = _where(source, _line_of(text, None, "align"))
        _check_align_models(plain, objs["error_model"], text, source)
    return Spec(plain["input"], plain["problem"], plain["solve"], objs["item"], objs["error_model"], where,
                stationary=plain["stationary"], align=plain["align"])


def _plain_table(doc: dict, sec: str, text: str, source: str) -> dict:
    """A copy of the ``[sec]`` table (``{}`` if absent), refused if it is not a table or has an
    unknown key."""
    tab = doc.get(sec, {})
    if not isinstance(tab, dict):
        raise InputError(f"{source}: [{sec}] must be a table")
    allowed = (_input_keys(tab.get("format")) if sec == "input" else
               _STATIONARY_KEYS | _STATIONARY_ITEM_KEYS if sec == "stationary" else
               _solve_keys() if sec == "solve" else _ALIGN_KEYS if sec == "align" else _SECTIONS[sec])
    for key in tab:
        if key not in allowed:
            line = _line_of(text, key, sec)
            whose = f" (of the {tab['format']!r} reader)" if sec == "input" and "format" in tab else ""
            raise InputError(f"{_where(source, line)}: unknown key {key!r} in [{sec}]{whose}; valid keys: "
                             f"{sorted(allowed)}")
    return dict(tab)


def _input_keys(fmt: Any = None) -> set[str]:
    """The keys ``[input]`` may hold: ``format``, the frame options, and the options of the
    reader ``fmt`` names (of every reader when it is not given: the file's suffix decides)."""
    from .readers import get_reader, registry
    from .strapdown import FRAME_OPTIONS

    keys = {"format", *FRAME_OPTIONS}
    if isinstance(fmt, str) and fmt.lower() in registry():  # an unknown format is named with its line later
        return keys | set(get_reader(fmt).options)
    for reader in registry().values():
        keys |= set(reader.options)
    return keys


def _instances(doc: dict, sec: str, reg: dict, kind: str, text: str, source: str) -> list:
    """The ``[[sec]]`` tables as instances of the registered classes ``reg`` (by ``type``)."""
    entries = doc.get(sec, [])
    if isinstance(entries, dict):
        entries = [entries]
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        line = _line_of(text, None, sec) or _line_of(text, sec)
        raise InputError(f"{_where(source, line)}: {sec} must be a list of [[{sec}]] tables, each "
                         f'with a type = "..." key; valid types: {sorted(reg)}')
    out = []
    for k, entry in enumerate(entries):
        fields = dict(entry)
        name = fields.pop("type", None)
        if name is None:
            raise InputError(f"{_where(source, _line_of(text, None, sec, k))}: [[{sec}]] number "
                             f"{k + 1} has no type; valid types: {sorted(reg)}")
        if str(name).lower() not in reg:
            raise InputError(f"{_where(source, _line_of(text, 'type', sec, k))}: unknown {kind} "
                             f"{name!r}; valid types: {sorted(reg)}")
        out.append(_instantiate(reg[str(name).lower()], kind, fields, text, sec, k, source))
    return out


def _check_item_names(doc: dict, text: str, source: str) -> None:
    """Refuse two ``[[item]]`` tables with the same name (names identify items)."""
    seen: dict[str, int] = {}
    for k, entry in enumerate(doc.get("item", []) if isinstance(doc.get("item"), list) else []):
        nm = entry.get("name")
        if isinstance(nm, str):
            if nm in seen:
                first, second = (_line_of(text, None, "item", j) for j in (seen[nm], k))
                raise InputError(f"{source}: the [[item]] tables at lines {first} and {second} are both "
                                 f"named {nm!r}; item names identify items (priority, demote_sigma, "
                                 "messages): rename one of them")
            seen[nm] = k


def read_spec_text(path) -> str:
    """A spec file's text, with errors naming the file.

    The path must be a regular file (checked with ``os.stat`` before opening: a FIFO or
    ``/dev/stdin`` would block forever); it is opened read-only. A UTF-8 byte-order mark
    is accepted and dropped (an encoding marker some editors write, not part of the TOML).
    """
    raw = read_regular_file(path, "spec", max_bytes=MAX_SPEC_BYTES)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise InputError(f"spec {str(path)!r}: not UTF-8 text (byte {exc.start}, line {line}); save it as "
                         "UTF-8") from None


def load_spec(path) -> Spec:
    """Read and parse a spec file (opened read-only)."""
    return parse_spec(read_spec_text(path), source=str(path))


# ------------------------------------------------------------------ writing
_ESCAPES = {"\\": "\\\\", '"': '\\"', "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}


def _toml_string(v: str) -> str:
    r"""A TOML basic string for any Python string: quotes, backslashes and control
    characters escaped, everything outside printable ASCII as ``\uXXXX``/``\UXXXXXXXX``
    (the file stays ASCII whatever its encoding is read as)."""
    out = []
    for ch in v:
        code = ord(ch)
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif 0x20 <= code < 0x7F:
            out.append(ch)
        elif 0xD800 <= code <= 0xDFFF:
            raise InputError(f"cannot write {v!r} to a spec: it holds a lone surrogate (U+{code:04X}), which "
                             "is not a Unicode character; fix the string")
        elif code <= 0xFFFF:
            out.append(f"\\u{code:04X}")
        else:
            out.append(f"\\U{code:08X}")
    return '"' + "".join(out) + '"'


def _toml_key(k) -> str:
    """A TOML key: bare when it is ``A-Za-z0-9_-``, else a quoted basic string."""
    k = str(k)
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else _toml_string(k)


def _toml_value(v) -> str:
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)  # shortest round-trip representation
    if isinstance(v, str):
        return _toml_string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise InputError(f"cannot write {v!r} ({type(v).__name__}) to a spec")


def _fields_of(obj, skip=()) -> dict:
    out = {}
    for f in dataclasses.fields(obj):
        if not f.init or f.name in skip:
            continue
        v = getattr(obj, f.name)
        if v is None:
            continue
        if isinstance(v, tuple) and f.name == "bounds":
            v = [np.asarray(v[0]).tolist(), np.asarray(v[1]).tolist()]
        out[f.name] = v
    return out


def dumps_spec(spec: Spec) -> str:
    """TOML text for a :class:`Spec` (the inverse of :func:`parse_spec`)."""
    lines = ["# bvpnav spec (written by bvpnav)"]
    for sec in ("input", "problem", "solve", "stationary", "align"):
        tab = getattr(spec, sec)
        if tab:
            lines += ["", f"[{sec}]"] + [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in tab.items()]
    for m in spec.error_models:
        lines += ["", "[[error_model]]", f'type = "{_snake(type(m).__name__)}"']
        lines += [f"{k} = {_toml_value(v)}" for k, v in _fields_of(m).items()]
    for it in spec.items:
        lines += ["", "[[item]]", f'type = "{type(it).registered_name()}"']
        lines += [f"{k} = {_toml_value(v)}" for k, v in _fields_of(it).items()]
    return "\n".join(lines) + "\n"


def problem_to_spec(problem, solve: dict | None = None, input: dict | None = None) -> Spec:
    """The :class:`Spec` of a problem (its items, error model, form and sigma_a)."""
    prob_kw: dict[str, Any] = {"residual": problem.residual}
    if problem.sigma_a_given:
        sa = problem.sigma_a
        if sa.ndim == 2 and not np.all(sa == sa.flat[0]):
            raise InputError("sigma_a is given per sample, which a spec file cannot hold (one number "
                             "or one per axis); give sigma_a per axis to write the spec, or keep the "
                             "problem in Python")
        sa = sa.ravel()
        prob_kw["sigma_a"] = float(sa[0]) if np.all(sa == sa[0]) else sa.tolist()
    if getattr(problem, "segment", None) is not None:
        prob_kw["segment"] = float(problem.segment)
    em = problem.error_model
    models = [] if em is None else list(getattr(em, "components", (em,)))
    return Spec(dict(input or {}), prob_kw, dict(solve or {}), list(problem.items), models)


def problem_from_spec(spec: Spec, data):
    """Build the problem a spec describes for ``data`` (ImuData)."""
    return spec.build(data)


def to_spec(problem, solve: dict | None = None, input: dict | None = None) -> str:
    """A problem's information as spec-file TOML.

    Parameters
    ----------
    problem : NavigationProblem
    solve : dict, optional
        The ``[solve]`` table (solver, accuracy, lam, uncertainty, ...: keyword arguments
        of :meth:`~bvpnav.NavigationProblem.solve`).
    input : dict, optional
        The ``[input]`` table (time column and unit, axis columns, acceleration unit).

    Returns
    -------
    str
        TOML listing every item and error-model component with its parameters, the
        residual form and sigma_a; ``parse_spec(text).build(data)`` gives the same problem
        back.
    """
    return dumps_spec(problem_to_spec(problem, solve=solve, input=input))
