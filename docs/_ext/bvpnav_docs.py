"""Helpers of the documentation build (not part of the bvpnav package)."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import jupytext
from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

KERNELSPEC = {"name": "python3", "display_name": "Python 3", "language": "python"}
LANGUAGE_INFO = {"name": "python", "pygments_lexer": "ipython3"}


def read_percent_script(text: str):
    """Read a jupytext "percent" script as a notebook that says it is Python.

    The tutorial scripts carry no kernel metadata; without it myst-nb cannot choose a
    lexer for the code cells of a page that is not executed.
    """
    nb = jupytext.reads(text, fmt="py:percent")
    nb.metadata.setdefault("kernelspec", dict(KERNELSPEC))
    nb.metadata.setdefault("language_info", dict(LANGUAGE_INFO))
    return nb


def public_modules() -> list[str]:
    """Every public module of the installed package (``bvpnav`` and ``bvpnav.constraints``)."""
    import bvpnav
    import bvpnav.constraints

    names = {"bvpnav", "bvpnav.constraints"}
    for pkg in (bvpnav, bvpnav.constraints):
        for info in pkgutil.walk_packages(pkg.__path__, prefix=pkg.__name__ + "."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                names.add(info.name)
    return sorted(names)


def _members(name: str, mod) -> list[str]:
    """What a module's page documents: its ``__all__``, else the public names it defines."""
    members = getattr(mod, "__all__", None)
    if members is None:
        members = [k for k, v in vars(mod).items()
                   if not k.startswith("_") and getattr(v, "__module__", None) == name]
    return list(members)


def documented_elsewhere() -> dict[str, list[str]]:
    """Per module, the members the API reference documents on another page.

    Every object is described once, under its shortest public name: ``bvpnav.InputError``
    rather than ``bvpnav.errors.InputError``, ``bvpnav.constraints.Position`` rather
    than ``bvpnav.constraints.position.Position``. A module therefore leaves out what a
    parent package exports, and a sub-package leaves out what it merely re-exports from
    outside itself (``bvpnav.constraints`` re-exports ``Item`` from ``bvpnav.items``).
    The top-level ``bvpnav`` keeps all its exports: it is the public namespace. Two full
    descriptions of one object would make cross-references ambiguous (a Sphinx warning).
    """
    out: dict[str, list[str]] = {}
    modules = {name: importlib.import_module(name) for name in public_modules()}
    for name, mod in modules.items():
        members = _members(name, mod)
        parents = [modules[p] for p in modules if name.startswith(p + ".")]
        # (name, object) pairs, so that equal small constants of unrelated names never match
        exported = {(k, id(getattr(p, k))) for p in parents for k in getattr(p, "__all__", ())
                    if hasattr(p, k)}
        skip = []
        for k in members:
            obj = getattr(mod, k, None)
            home = getattr(obj, "__module__", None)
            foreign = (name != "bvpnav" and hasattr(mod, "__path__") and isinstance(home, str)
                       and home != name and not home.startswith(name + "."))
            if (k, id(obj)) in exported or foreign:
                skip.append(k)
        if skip:
            out[name] = sorted(skip)
    return out


def _summarised(obj) -> bool:
    """Classes and functions are listed (constants are described where they are, with their comment)."""
    return (inspect.isclass(obj) or inspect.isroutine(obj)) and bool(obj.__doc__)  # undocumented: no page


def module_objects() -> dict[str, list[str]]:
    """Per module, each object its page lists, as the full name it is described under.

    A module page's "Summary" links every class and function the module exports (or
    defines, without an ``__all__``) to its one description: on the page itself, or under
    the shortest public name given by :func:`documented_elsewhere`
    (``bvpnav.constraints.position`` lists ``bvpnav.constraints.Position``). The module
    template writes them as cross-references (``:py:obj:`~name```), so the page shows each
    object's own name.
    """
    elsewhere = documented_elsewhere()
    modules = {name: importlib.import_module(name) for name in public_modules()}

    def home(name: str, k: str, depth: int = 0) -> str:
        obj = getattr(modules[name], k)
        if k not in elsewhere.get(name, ()) or depth > 5:
            return f"{name}.{k}"
        # Exported by a parent package: described there (the shortest such name).
        for parent in sorted((p for p in modules if name.startswith(p + ".")), key=len):
            if k in getattr(modules[parent], "__all__", ()) and getattr(modules[parent], k, None) is obj:
                return home(parent, k, depth + 1)
        # Re-exported from outside a sub-package: described where it is defined.
        where = getattr(obj, "__module__", None)
        if where in modules and hasattr(modules[where], k):
            return home(where, k, depth + 1)
        return f"{name}.{k}"

    out: dict[str, list[str]] = {}
    for name, mod in modules.items():
        rows = [home(name, k) for k in _members(name, mod) if _summarised(getattr(mod, k, None))]
        if rows:
            out[name] = rows
    return out


def _add_mathjax_offline(app):
    """sphinx-mathjax-offline's hook (MathJax copied into ``_static``), declared parallel-safe:
    it only sets ``mathjax_path`` and copies files when the build has finished."""
    importlib.import_module("sphinx-mathjax-offline").setup(app)


class ModuleIndex(SphinxDirective):
    """``.. bvpnav-modules::``: a table of every public module, one per package.

    The list is walked from the installed package (:func:`public_modules`) at build time,
    so a module added later gets its row without editing the page. Each row links the
    module's page (generated by the recursive autosummary above it) with its first line.
    """

    has_content = False

    def run(self):
        names = public_modules()
        packages = [n for n in names if hasattr(importlib.import_module(n), "__path__")]
        groups: dict[str, list[str]] = {n: [n] for n in packages}
        for name in names:
            parent = name.rpartition(".")[0]
            if parent in groups:
                groups[parent].append(name)
        lines: list[str] = []
        for pkg, members in groups.items():
            lines += [f".. rubric:: {pkg}", "", ".. autosummary::", ""] + [f"   {m}" for m in members] + [""]
        node = nodes.container()
        self.state.nested_parse(StringList(lines, source="bvpnav-modules"), self.content_offset, node)
        return node.children


def setup(app):
    app.add_directive("bvpnav-modules", ModuleIndex)
    _add_mathjax_offline(app)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
