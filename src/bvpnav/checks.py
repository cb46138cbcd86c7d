"""Small composable checks of one value, each naming what a valid value is.

A :class:`Rule` returns the value normalised or raises :class:`Invalid` with the reason;
:class:`bvpnav.declare.Option` turns that into an :class:`~bvpnav.errors.InputError` naming
the option and the value. The rules: :func:`boolean`, :func:`number` (integers, ranges,
units), :func:`one_of`, :func:`text`, :func:`nothing`, :func:`any_of`, :func:`table` (a
dict of known keys, each with its own rule) and :func:`mapping_of`. They import nothing
beyond the standard library, so the command line's parser can be built from them without
numpy (numpy's scalars are recognised by their type).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

__all__ = ["Invalid", "Rule", "ANY", "is_bool", "is_real", "boolean", "number", "one_of", "text", "nothing",
           "any_of", "table", "mapping_of"]


def is_bool(v) -> bool:
    """A Python or numpy boolean."""
    return isinstance(v, bool) or (type(v).__module__ == "numpy" and type(v).__name__ in ("bool_", "bool"))


def is_real(v) -> bool:
    """A real number that is not a boolean (numpy's scalars are :class:`numbers.Real`)."""
    return isinstance(v, numbers.Real) and not is_bool(v)


class Invalid(ValueError):
    """A value a :class:`Rule` refuses: ``reason`` says what a valid one is; ``nested`` when
    the reason already names a key inside the value (a table's entry); ``shown``: the value
    as the message shows it (default its repr); ``typed``: name the value's type too."""

    def __init__(self, reason: str, nested: bool = False, shown: str | None = None, typed: bool = False,
                 sep: str = " "):
        super().__init__(reason)
        self.reason, self.nested, self.shown, self.typed, self.sep = reason, nested, shown, typed, sep


@dataclass(frozen=True)
class Rule:
    """A check of one value: ``test(value)`` returns the value normalised, or raises
    :class:`Invalid`; ``want`` describes a valid value (``"a number > 0 (s)"``)."""

    test: Callable[[Any], Any]
    want: str

    def __call__(self, value):
        return self.test(value)


def _refuse(want: str):
    raise Invalid(f"give {want}")


def boolean() -> Rule:
    """True or False (numpy booleans too), as a Python bool."""
    def test(v):
        if is_bool(v):
            return bool(v)
        hint = ""
        if isinstance(v, str) and v.strip().lower() in ("true", "false", "yes", "no", "on", "off"):
            hint = " (a boolean, not a string: True or False; in a spec true or false without quotes)"
        raise Invalid(f"give True or False{hint}")
    return Rule(test, "True or False")


def number(low: float | None = None, high: float | None = None, *, low_open: bool = False,
           high_open: bool = False, integer: bool = False, unit: str = "", want: str | None = None) -> Rule:
    """A finite number (an integer with ``integer=True``) in ``low..high`` (open ends with
    ``low_open``/``high_open``), as a float (int for integers); ``unit`` is named."""
    kind = "an integer" if integer else "a number"
    parts = []
    if low is not None and high is not None:
        parts.append(f"{'>' if low_open else '>='} {low:g} and {'<' if high_open else '<='} {high:g}")
    elif low is not None:
        parts.append(f"{'>' if low_open else '>='} {low:g}")
    elif high is not None:
        parts.append(f"{'<' if high_open else '<='} {high:g}")
    want = want or " ".join([kind, *parts]) + (f" ({unit})" if unit else "")

    def test(v):
        ok = is_real(v) and (isinstance(v, numbers.Integral) or not integer)
        if not ok or not math.isfinite(float(v)):
            _refuse(want)
        x = float(v)
        if low is not None and (x <= low if low_open else x < low):
            _refuse(want)
        if high is not None and (x >= high if high_open else x > high):
            _refuse(want)
        return int(v) if integer else x
    return Rule(test, want)


def one_of(*values, want: str | None = None) -> Rule:
    """One of ``values`` (compared with ``==``; a bool never stands for 0 or 1)."""
    shown = want or f"one of {list(values)}"

    def test(v):
        for c in values:
            if type(v) is type(c) and v == c or (isinstance(c, str) and isinstance(v, str) and v == c):
                return c
        hint = ""
        if isinstance(v, str) and v.strip().lower() in [str(c).lower() for c in values] and v not in values:
            hint = f" (in lower case: {v.strip().lower()!r})"
        raise Invalid(f"choose {shown}{hint}")
    return Rule(test, shown)


def text(want: str = "a string") -> Rule:
    """Any string."""
    def test(v):
        if not isinstance(v, str):
            _refuse(want)
        return v
    return Rule(test, want)


def nothing() -> Rule:
    """None only."""
    def test(v):
        if v is not None:
            _refuse("None")
        return None
    return Rule(test, "None")


def any_of(*rules: Rule, want: str | None = None) -> Rule:
    """The first rule that takes the value; else ``want`` (default: the rules' wants joined)."""
    shown = want or " or ".join(r.want for r in rules)

    def test(v):
        for r in rules:
            try:
                return r(v)
            except Invalid as exc:
                if exc.nested:  # a table that took the value's shape: its reason is the precise one
                    raise
        _refuse(shown)
    return Rule(test, shown)


def table(keys: Mapping[str, Rule], what: str, example: str) -> Rule:
    """A dict of options: every key known, every value checked by its rule; returns a new
    dict of the given keys (defaults are the consumer's: :func:`defaults`)."""
    want = f"a dict of {what} options, e.g. {example}, with keys from {list(keys)}"

    def test(v):
        if not isinstance(v, Mapping):
            _refuse(want)
        unknown = sorted(str(k) for k in v if k not in keys)
        if unknown:
            raise Invalid(f"unknown option(s) {unknown}; valid: {list(keys)}", nested=True, sep=": ")
        out = {}
        for k, x in v.items():
            try:
                out[k] = keys[k](x)
            except Invalid as exc:
                raise Invalid(f"{k}={x!r}: {exc.reason}", nested=True) from None
        return out
    return Rule(test, want)


def mapping_of(rule: Rule, what: str, example: str) -> Rule:
    """A dict of item name -> value checked by ``rule``."""
    want = f"a dict of item name -> {rule.want}, e.g. {example}"

    def test(v):
        if not isinstance(v, Mapping):
            _refuse(want)
        out = {}
        for k, x in v.items():
            if not isinstance(k, str):
                raise Invalid(f"{what} name {k!r} is not a string; give {want}")
            try:
                out[k] = rule(x)
            except Invalid as exc:
                raise Invalid(f"entry {k!r} = {x!r}: {exc.reason}") from None
        return out
    return Rule(test, want)




#: Any value (checked where it is used).
ANY = Rule(lambda v: v, "any value")
