"""Helpers of the documentation build (not part of the bvpnav package)."""

from __future__ import annotations

import importlib
import pkgutil

import jupytext

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
        members = getattr(mod, "__all__", None)
        if members is None:
            members = [k for k, v in vars(mod).items()
                       if not k.startswith("_") and getattr(v, "__module__", None) == name]
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


def _add_mathjax_offline(app):
    """sphinx-mathjax-offline's hook (MathJax copied into ``_static``), declared parallel-safe:
    it only sets ``mathjax_path`` and copies files when the build has finished."""
    importlib.import_module("sphinx-mathjax-offline").setup(app)


def setup(app):
    _add_mathjax_offline(app)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
