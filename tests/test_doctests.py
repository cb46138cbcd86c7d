"""The docstrings' Examples run, and every public name has one (issue 43, "Examples that run").

Every module of the installed package (``bvpnav``, its sub-packages and the plug-in folder
``bvpnav.constraints``) is imported by its dotted name and its docstrings are collected with
:class:`doctest.DocTestFinder`; each docstring with examples is one test here, so README's
``pytest -q`` runs them with the rest. This is done here rather than with ``--doctest-modules``
on ``src/`` and ``constraints/``: the plug-in folder ``constraints/`` is installed as
``bvpnav.constraints``, and collecting it from its path would import it a second time under
another name; importing by dotted name also tests the installed package, not the files.
"""

from __future__ import annotations

import ast
import doctest
import importlib
import inspect
import pkgutil
import re
from types import ModuleType

import pytest

import bvpnav

#: ELLIPSIS for digits that depend on the BLAS kernel or the solver's last iteration; printed
#: numbers are rounded in the examples themselves.
OPTIONS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE

#: Plug-in families' base classes (issue 43: "each plug-in family's base class").
PLUGIN_BASES = [
    ("bvpnav.items", "Item"),
    ("bvpnav.error_models._base", "ErrorModel"),
    ("bvpnav.error_models._base", "SensorErrorModel"),
    ("bvpnav.backends", "Backend"),
    ("bvpnav.lam", "LambdaRule"),
    ("bvpnav.readers", "Reader"),
]


def _walk(package: str) -> list[str]:
    mod = importlib.import_module(package)
    names = [package]
    for info in pkgutil.iter_modules(mod.__path__, package + "."):
        names += _walk(info.name) if info.ispkg else [info.name]
    return names


def _module_names() -> list[str]:
    # the plug-in families discover their folders first, so that their registries keep the
    # order they document (built-ins first), not the alphabetical order of the walk below
    bvpnav.lam.rule_names()
    bvpnav.readers.registry()
    names = _walk("bvpnav")
    if "bvpnav.constraints" not in names:  # an editable install maps it from constraints/
        names += _walk("bvpnav.constraints")
    return sorted(set(names))


def _collect() -> tuple[dict[str, doctest.DocTest], dict[str, str]]:
    """Every docstring with examples, by qualified name; and modules that could not be imported."""
    finder = doctest.DocTestFinder()
    tests: dict[str, doctest.DocTest] = {}
    failed: dict[str, str] = {}
    for name in _module_names():
        try:
            mod = importlib.import_module(name)
        except ImportError as exc:  # an optional dependency: reported as a skip, never silently
            failed[name] = f"{name} not importable: {exc}"
            continue
        for test in finder.find(mod, name):
            if test.examples:
                tests[test.name] = test
    return tests, failed


TESTS, UNIMPORTABLE = _collect()


def _params():
    out = [pytest.param(name, id=name) for name in sorted(TESTS)]
    out += [pytest.param(name, id=name, marks=pytest.mark.skip(reason=why))
            for name, why in UNIMPORTABLE.items()]
    return out


@pytest.mark.parametrize("name", _params())
def test_docstring_examples_run(name):
    test = TESTS[name]
    lines: list[str] = []
    runner = doctest.DocTestRunner(optionflags=OPTIONS)
    # a fresh copy of the module's globals, as doctest gives each docstring
    test.globs = dict(test.globs)
    # examples that register a plug-in remove it again; a failing one must not leave it behind
    registries = [bvpnav.lam._RULES, bvpnav.readers._READERS]
    saved = [dict(r) for r in registries]
    try:
        result = runner.run(test, out=lines.append, clear_globs=True)
    finally:
        for reg, before in zip(registries, saved, strict=True):
            reg.clear()
            reg.update(before)
    assert result.failed == 0, "".join(lines)
    assert result.attempted > 0


def _public_objects() -> list[tuple[str, object]]:
    """Every name in ``bvpnav.__all__``, the functions and classes each public submodule exports
    in its own ``__all__``, and the plug-in families' base classes."""
    objs: list[tuple[str, object]] = []
    for name in bvpnav.__all__:
        if name == "__version__":  # a string: nothing to document with an example
            continue
        obj = getattr(bvpnav, name)
        objs.append((f"bvpnav.{name}", obj))
        if isinstance(obj, ModuleType):
            for sub in getattr(obj, "__all__", ()):
                member = getattr(obj, sub)
                if inspect.isclass(member) or inspect.isfunction(member):
                    objs.append((f"bvpnav.{name}.{sub}", member))
    for module, name in PLUGIN_BASES:
        objs.append((f"{module}.{name}", getattr(importlib.import_module(module), name)))
    seen: set[int] = set()  # a base exported by its package is listed once
    return [(p, o) for p, o in objs if not (id(o) in seen or seen.add(id(o)))]


def _qualified(obj) -> str:
    if isinstance(obj, ModuleType):
        return obj.__name__
    return f"{obj.__module__}.{obj.__qualname__}"


_EXAMPLES = re.compile(r"^\s*Examples\n\s*-{8,}\n", re.MULTILINE)


@pytest.mark.parametrize("public,obj", [pytest.param(p, o, id=p) for p, o in _public_objects()])
def test_public_name_has_a_running_example(public, obj):
    doc = inspect.getdoc(obj) or ""
    match = _EXAMPLES.search(doc)
    assert match, f"{public}: its docstring has no numpydoc 'Examples' section"
    section = doc[match.end():]
    nxt = re.search(r"^\S.*\n-{3,}\n", section, re.MULTILINE)  # the next numpydoc section, if any
    examples = section[: nxt.start() if nxt else None]
    assert ">>>" in examples, f"{public}: its Examples section has no '>>>' line"
    qual = _qualified(obj)
    assert qual in TESTS, f"{public} ({qual}): doctest did not collect its examples"
    assert TESTS[qual].examples, f"{public}: doctest found no examples"


def test_examples_section_count_matches_the_collected_doctests():
    """A docstring with an Examples section whose ``>>>`` lines doctest does not see (for example
    one indented as a literal block after ``::``) would never run: each must be collected."""
    missing = []
    for name in _module_names():
        if name in UNIMPORTABLE:
            continue
        mod = importlib.import_module(name)
        for obj in [mod, *vars(mod).values()]:
            if not (isinstance(obj, ModuleType) and obj is mod) and getattr(obj, "__module__", None) != name:
                continue
            if not (inspect.isclass(obj) or inspect.isfunction(obj) or obj is mod):
                continue
            if _EXAMPLES.search(inspect.getdoc(obj) or "") and _qualified(obj) not in TESTS:
                missing.append(_qualified(obj))
    assert not missing, f"Examples sections doctest does not collect: {missing}"


def _docstring_sources(path: str) -> list[tuple[int, str]]:
    """(line, source text) of every docstring in a file, prefix and quotes included."""
    src = open(path, encoding="utf-8").read()
    if "\\" not in src:
        return []
    lines = src.splitlines()
    out = []
    for n in ast.walk(ast.parse(src)):
        if (isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and n.body
                and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)
                and isinstance(n.body[0].value.value, str)):
            c = n.body[0].value
            text = "\n".join(lines[c.lineno - 1:c.end_lineno])[c.col_offset:]
            out.append((c.lineno, text))
    return out


def test_docstrings_with_a_backslash_are_raw():
    r"""Math is written in docstrings as in LaTeX, ``:math:`\sigma```: a docstring holding a
    backslash is a raw string (prefix ``r``), so no backslash is doubled and none is an escape."""
    offenders = []
    for name in _module_names():
        if name in UNIMPORTABLE:
            continue
        path = importlib.import_module(name).__file__
        for line, text in _docstring_sources(path):
            prefix = re.match(r"[A-Za-z]*", text).group(0)
            if "\\" in text and "r" not in prefix.lower():
                offenders.append(f"{path}:{line}")
    assert not offenders, ("docstrings with a backslash that are not raw strings; write r\"\"\" and single "
                           f"backslashes: {offenders}")
