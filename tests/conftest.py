"""Shared fixtures. Plain helper functions live in ``_helpers.py`` (import them from there).

The suite runs in parallel (``pytest -n auto``: pytest-xdist; ``--dist loadgroup`` in pyproject's
addopts). A module- or class-scoped fixture is made once per worker that runs a test using it, so
the tests of a file that share such a fixture (one value of it, when it is parametrized) are one
unit of work, sent whole to one worker: the fixture is made once, as in a serial run. Tests with
the same ``xdist_group`` mark are one unit too. Every other test is its own unit, given to
whichever worker is free. Units holding a test marked ``slow`` are handed out first, so that the
longest work does not start last and finish on one worker while the other idles.

xdist's own ``loadgroup`` passes a test's group to the controller by appending it to the test's
node id, which pytest 9.2's structured node ids ignore (pytest-dev/pytest-xdist#1386: the groups
are silently dropped). Here each worker writes the units it collected (test id -> unit) to a file
named by the controller, and the controller's scheduler (:class:`_Units`) reads them.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from _helpers import quintic

#: Fixture scopes made once per module (or class) of a worker; "session" fixtures are made once
#: per worker whatever the grouping, so grouping by them would only cost parallelism.
SHARED_SCOPES = {"module", "class", "package"}
#: workerinput key: the folder where the workers write their units
UNITS_DIR = "bvpnav_units_dir"
_UNITS_KEY = pytest.StashKey[str]()


@pytest.fixture
def quintic_traj():
    return quintic()


@pytest.fixture(scope="session")
def wheel_build(tmp_path_factory) -> tuple[subprocess.CompletedProcess, Path]:
    """``pip wheel --no-deps`` of the source tree, built once for the tests that read the wheel
    (test_docs, test_install: their ``wheel-build`` xdist group puts them on one worker, which
    makes a session fixture once): pip's finished process and the folder it wrote the wheel to.
    Each test checks pip's exit status itself."""
    out = tmp_path_factory.mktemp("wheel")
    root = Path(__file__).resolve().parents[1]
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out), str(root)],
        capture_output=True, text=True, timeout=300,
    )
    return proc, out


def _shared(item: pytest.Item) -> list[str]:
    """Keys of what ``item`` shares with other tests: this suite's module/class-scoped fixture
    instances it uses (``file::name`` or ``file::name[param index]``) and its xdist_group marks."""
    module = item.nodeid.split("::", 1)[0]
    keys = [f"group:{m.args[0] if m.args else m.kwargs.get('name', 'default')}"
            for m in item.iter_markers("xdist_group")]
    info = getattr(item, "_fixtureinfo", None)
    callspec = getattr(item, "callspec", None)
    for name in info.names_closure if info is not None else ():
        defs = info.name2fixturedefs.get(name)
        if not defs or defs[-1].scope not in SHARED_SCOPES or not defs[-1].baseid:
            continue  # baseid "": a plugin's fixture (pytest's own)
        index = f"[{callspec.indices[name]}]" if callspec is not None and name in callspec.indices else ""
        keys.append(f"{module}::{name}{index}")
    return keys


def _units(items: list[pytest.Item]) -> dict[str, str]:
    """Test id -> unit: tests sharing a key are one unit (joined transitively)."""
    parent: dict[str, str] = {}

    def find(x: str) -> str:
        while parent.setdefault(x, x) != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    keyed = [(item.nodeid, _shared(item)) for item in items]
    for _, keys in keyed:
        for key in keys[1:]:
            parent[find(key)] = find(keys[0])
    return {nodeid: find(keys[0]) if keys else nodeid for nodeid, keys in keyed}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """In an xdist worker: units holding a slow test first (the order within kept), and the
    units written for the controller's scheduler."""
    workerinput = getattr(config, "workerinput", None)
    if workerinput is None or UNITS_DIR not in workerinput:
        return
    units = _units(items)
    slow = {units[item.nodeid] for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: units[item.nodeid] not in slow)  # stable; every worker sorts alike
    folder = Path(workerinput[UNITS_DIR])
    tmp = folder / f".{workerinput['workerid']}.tmp"
    tmp.write_text(json.dumps({item.nodeid: units[item.nodeid] for item in items}))
    os.replace(tmp, folder / f"{workerinput['workerid']}.json")


def pytest_configure(config: pytest.Config) -> None:
    """The controller of a parallel run (-n with --dist loadgroup) makes the units' folder."""
    if config.pluginmanager.hasplugin("xdist") and config.getoption("dist", "no") == "loadgroup" \
            and not hasattr(config, "workerinput"):
        folder = tempfile.mkdtemp(prefix="bvpnav-units-")
        config.stash[_UNITS_KEY] = folder
        config.add_cleanup(lambda: shutil.rmtree(folder, ignore_errors=True))


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node) -> None:
    """Tell each worker where to write its units."""
    folder = node.config.stash.get(_UNITS_KEY, None)
    if folder is not None:
        node.workerinput[UNITS_DIR] = folder


@pytest.hookimpl(optionalhook=True, tryfirst=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log):
    """For --dist loadgroup: scope scheduling by the workers' units."""
    folder = config.stash.get(_UNITS_KEY, None)
    if folder is None:
        return None
    from xdist.scheduler import LoadScopeScheduling

    class _Units(LoadScopeScheduling):
        """xdist's scope scheduling with this suite's units as the scopes, in the workers'
        order (units with a slow test first)."""

        units: dict[str, str] | None = None

        def _split_scope(self, nodeid: str) -> str:
            if self.units is None:
                found = sorted(Path(folder).glob("*.json"))
                self.units = json.loads(found[0].read_text()) if found else {}
            return self.units.get(nodeid, nodeid)

    config.option.loadscopereorder = False
    return _Units(config, log)
