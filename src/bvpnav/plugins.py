"""Discovery of plug-in folders: every public module of a folder, imported once.

The four plug-in families (``bvpnav.constraints``, ``bvpnav.error_models``,
``bvpnav.backends``, ``bvpnav.lam``) are folders whose modules register what they define
when imported; :func:`discover` imports them and :func:`export` lifts their public names
into the folder's namespace.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Iterable, MutableMapping
from types import ModuleType

__all__ = ["discover", "export"]

#: Folders already discovered: package name -> its modules (a folder is read once).
_DONE: dict[str, list[ModuleType]] = {}


def discover(package: str, path: Iterable[str], first: Iterable[str] = (),
             skip: Iterable[str] = ()) -> list[ModuleType]:
    """Import the public modules of a package folder: ``first`` in that order, then the
    others by name (modules whose name starts with ``_`` and those in ``skip`` are not
    plug-ins). A folder is read once; later calls return the same modules.

    Parameters
    ----------
    package : str
        The package's dotted name (its ``__name__``).
    path : iterable of str
        The package's ``__path__``.
    first : iterable of str
        Module names to import before the others (e.g. built-ins in their listed order).
    skip : iterable of str
        Module names that are not plug-ins.

    Returns
    -------
    list of module
    """
    if package in _DONE:
        return _DONE[package]
    first, skip = list(first), set(skip)
    rest = sorted(m.name for m in pkgutil.iter_modules(path)
                  if not m.name.startswith("_") and m.name not in skip and m.name not in first)
    mods = _DONE[package] = [importlib.import_module(f"{package}.{name}") for name in [*first, *rest]]
    return mods


def export(namespace: MutableMapping, modules: Iterable[ModuleType]) -> list[str]:
    """Copy each module's ``__all__`` names into ``namespace``; the names, in order."""
    names = []
    for mod in modules:
        for name in getattr(mod, "__all__", ()):
            namespace[name] = getattr(mod, name)
            names.append(name)
    return names
