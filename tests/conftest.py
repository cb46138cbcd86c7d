"""Shared fixtures. Plain helper functions live in ``_helpers.py`` (import them from there).

The suite runs in parallel (``pytest -n auto``, pytest-xdist, with ``--dist loadgroup`` from
pyproject's addopts). A module- or class-scoped fixture is made once per worker that runs a test
using it, so :func:`pytest_collection_modifyitems` puts the tests of a file that share such a
fixture (one value of it, when it is parametrized) into one ``xdist_group``: the fixture is made
once, and every other test of the suite is spread over the workers one by one. In a worker, the
units (groups and single tests) holding a test marked ``slow`` are moved to the front, so that
the longest work starts first instead of finishing last on one worker while the other idles.
"""

from __future__ import annotations

import pytest
from _helpers import quintic

#: Fixture scopes made once per module (or class) of a worker; "session" fixtures are made once
#: per worker whatever the grouping, so grouping by them would only cost parallelism.
SHARED_SCOPES = {"module", "class", "package"}


@pytest.fixture
def quintic_traj():
    return quintic()


def _shared_fixtures(item: pytest.Item) -> list[str]:
    """The instances of this suite's module/class-scoped fixtures that ``item`` uses, each as
    ``name`` or ``name[param index]``."""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return []
    callspec = getattr(item, "callspec", None)
    out = []
    for name in info.names_closure:
        defs = info.name2fixturedefs.get(name)
        if not defs:
            continue
        fdef = defs[-1]
        if fdef.scope not in SHARED_SCOPES or not fdef.baseid:  # "": a plugin's (pytest's own)
            continue
        if callspec is not None and name in callspec.indices:
            name = f"{name}[{callspec.indices[name]}]"
        out.append(name)
    return out


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Group the tests that share a module/class-scoped fixture instance (within one file) into
    one ``xdist_group`` (joined transitively: two tests sharing any instance are in one group)."""
    parent: dict[str, str] = {}

    def find(x: str) -> str:
        while parent.setdefault(x, x) != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    keyed = []
    for item in items:
        module = item.nodeid.split("::", 1)[0]
        keys = [f"{module}::{name}" for name in _shared_fixtures(item)]
        for key in keys[1:]:
            parent[find(key)] = find(keys[0])
        keyed.append((item, keys))
    for item, keys in keyed:
        if keys:
            item.add_marker(pytest.mark.xdist_group(find(keys[0])))
    if hasattr(config, "workerinput"):  # a pytest-xdist worker: every worker sorts alike
        unit = {id(item): find(keys[0]) if keys else item.nodeid for item, keys in keyed}
        slow = {unit[id(item)] for item in items if item.get_closest_marker("slow")}
        items.sort(key=lambda item: unit[id(item)] not in slow)  # stable: the order within stays
