"""Additional information, one kind per file; installed as ``bvpnav.constraints``.

Every module in this package is imported here, so defining an :class:`bvpnav.items.Item`
subclass in a new file is all it takes to register it by name (for spec files and the
CLI) and to put it through the shared contract test.

Examples
--------
Every item here is registered by its snake-case name (the spec files' and CLI's):

>>> import bvpnav.constraints as items
>>> items.registry()["zero_velocity"] is items.ZeroVelocity
True
>>> "position" in items.registry() and "track_line" in items.registry()
True
"""

from __future__ import annotations

from bvpnav.items import Item, registry
from bvpnav.plugins import discover, export

__all__ = ["Item", "registry"]

__all__ += export(globals(), discover(__name__, __path__))
