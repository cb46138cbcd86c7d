"""Additional information, one kind per file; installed as ``bvpnav.constraints``.

Every module in this package is imported here, so defining an :class:`bvpnav.items.Item`
subclass in a new file is all it takes to register it by name (for spec files and the
CLI) and to put it through the shared contract test.
"""

from __future__ import annotations

import importlib
import pkgutil

from bvpnav.items import Item, registry

__all__ = ["Item", "registry"]

for _info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
    if _info.name.startswith("_"):
        continue
    _mod = importlib.import_module(f"{__name__}.{_info.name}")
    for _name in getattr(_mod, "__all__", ()):
        globals()[_name] = getattr(_mod, _name)
        __all__.append(_name)

del _info, _mod, _name
