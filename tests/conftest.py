"""Shared fixtures. Plain helper functions live in ``_helpers.py`` (import them from there).

The suite runs in parallel (``pytest -n auto``: pytest-xdist; ``--dist loadgroup`` in pyproject's
addopts). A module- or class-scoped fixture is made once per worker that runs a test using it, so
the tests of a file that share such a fixture (one value of it, when it is parametrized) are one
unit of work, sent whole to one worker: the fixture is made once, as in a serial run. Tests with
the same ``xdist_group`` mark are one unit too, and so are the tests using one of the expensive
session fixtures of :data:`SHARED_SESSION` (the documentation build). Every other test is its own
unit, given to whichever worker is free. Units holding a test marked ``slow`` are handed out first,
the documentation build's unit (the longest) before them, so that the longest work does not start
last and finish on one worker while the other idles.

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
from dataclasses import dataclass
from pathlib import Path

import pytest
from _docs_only import environment as docs_only_environment
from _helpers import quintic
from _hostile import assert_unchanged, snapshot
from _kernel_fork import start_server, stop_server

#: Fixture scopes made once per module (or class) of a worker; "session" fixtures are made once
#: per worker whatever the grouping, so grouping by them would only cost parallelism.
SHARED_SCOPES = {"module", "class", "package"}
#: Session fixtures whose tests are one unit all the same: too expensive to make once per worker.
SHARED_SESSION = {"docs_build"}
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


ROOT = Path(__file__).resolve().parents[1]
#: Where a fetch would go: the discard port on loopback, closed (connection refused).
NO_NETWORK = "http://127.0.0.1:9"


@dataclass(frozen=True)
class DocsBuild:
    """The documentation site built as a reader would (see :func:`docs_build`).

    Attributes
    ----------
    html : Path
        The HTML folder.
    figures : Path
        The folder the executed pages (the tutorials) saved their figure files into
        (``$BVPNAV_FIGURES`` of the build, named by ``BVPNAV_DOCS_FIGURES``).
    notebooks : Path
        myst-nb's copies of the executed pages (``jupyter_execute``: ``tutorials/01_....ipynb``).
    """

    html: Path
    figures: Path
    notebooks: Path


def _sources(*roots: Path) -> dict:
    """:func:`snapshot` of the files under ``roots`` but bytecode caches, which tests running
    beside the build (pytest -n) write when they import an example."""
    return {p: v for p, v in snapshot(*roots).items() if "__pycache__" not in p.parts}


def _files(root: Path) -> set[Path]:
    return {p for p in root.rglob("*") if p.is_file() and "__pycache__" not in p.parts}


@pytest.fixture(scope="session")
def docs_build(tmp_path_factory) -> DocsBuild:
    """The site built once for the session (test_docs reads its pages, test_tutorial the
    tutorials' runs: myst-nb executes each tutorial, the gallery and the executed guides in a
    kernel of its own and fails the build on any exception; their tests are one unit of work,
    :data:`SHARED_SESSION`).

    ``sphinx-build -W --keep-going -b html`` on a copy of ``docs/`` in a temporary folder, so
    the generated API stubs never land in the work tree; every proxy points at a closed loopback
    port, so any attempt to fetch something during the build (intersphinx inventories, remote
    images) fails it; only what ``bvpnav[docs]`` installs is importable, in the build and in its
    kernels. The pages are executed at small size (``BVPNAV_SMALL=1``). Each page's kernel is a
    process of its own, forked from one that has made the kernel's and the pages' imports
    (``_kernel_fork.py``): the imports are paid once, not once per page."""
    base = tmp_path_factory.mktemp("docs")
    src = base / "source"
    docs, examples = ROOT / "docs", ROOT / "examples"
    # Symbolic links (the tutorials) are copied as the files they point to.
    shutil.copytree(docs, src, ignore=shutil.ignore_patterns(
        "_build", "generated", "jupyter_execute", ".jupyter_cache"))
    before = _sources(examples, docs)
    files_before = _files(examples) | _files(docs)
    figures = base / "figures"
    env = dict(os.environ, BVPNAV_SMALL="1", MPLBACKEND="Agg", BVPNAV_DOCS_FIGURES=str(figures))
    env.pop("BVPNAV_DOCS_EXECUTE", None)
    env.pop("BVPNAV_FIGURES", None)
    env.update(docs_only_environment(base / "docs-only"))
    for var in ("http_proxy", "https_proxy", "HTTP_PROXY", "HTTPS_PROXY", "all_proxy", "ALL_PROXY"):
        env[var] = NO_NETWORK
    env.pop("no_proxy", None)
    env.pop("NO_PROXY", None)
    out = base / "html"
    # In a pytest-xdist worker the other workers keep the cores busy: Sphinx's parallel read
    # (forked readers, pickled doctrees merged back) would only add CPU; run serially it reads
    # and executes the pages one after another, with the same warnings-as-errors build.
    jobs = "1" if os.environ.get("PYTEST_XDIST_WORKER") else "2"
    # The pages' kernels are forks of one process that has made their imports (_kernel_fork.py).
    kernels, kernel_env = start_server(base / "kernels")
    env.update(kernel_env)
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-j", jobs, "-b", "html", str(src),
             str(out)],
            cwd=base, env=env, capture_output=True, text=True, timeout=900, stdin=subprocess.DEVNULL,
        )
    finally:
        stop_server(kernels, base / "kernels")
    assert proc.returncode == 0, f"sphinx-build failed:\n{proc.stderr[-6000:]}\n{proc.stdout[-2000:]}"
    # The build read the examples and the docs and wrote nothing beside them.
    assert_unchanged(before)
    assert _files(examples) | _files(docs) == files_before
    return DocsBuild(html=out, figures=figures, notebooks=base / "jupyter_execute")


def _shared(item: pytest.Item) -> list[str]:
    """Keys of what ``item`` shares with other tests: this suite's module/class-scoped fixture
    instances it uses (``file::name`` or ``file::name[param index]``), the :data:`SHARED_SESSION`
    fixtures it uses and its xdist_group marks."""
    module = item.nodeid.split("::", 1)[0]
    keys = [f"group:{m.args[0] if m.args else m.kwargs.get('name', 'default')}"
            for m in item.iter_markers("xdist_group")]
    info = getattr(item, "_fixtureinfo", None)
    callspec = getattr(item, "callspec", None)
    for name in info.names_closure if info is not None else ():
        defs = info.name2fixturedefs.get(name)
        if defs and defs[-1].scope == "session" and name in SHARED_SESSION:
            keys.append(f"session::{name}")
            continue
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
    """In an xdist worker: the :data:`SHARED_SESSION` unit, then units holding a slow test
    first (the order within kept), and the units written for the controller's scheduler."""
    workerinput = getattr(config, "workerinput", None)
    if workerinput is None or UNITS_DIR not in workerinput:
        return
    units = _units(items)
    slow = {units[item.nodeid] for item in items if item.get_closest_marker("slow")}
    # the unit of the shared session fixtures (the documentation build: the longest unit) first
    longest = {units[item.nodeid] for item in items
               if any(k.startswith("session::") for k in _shared(item))}
    # stable; every worker sorts alike
    items.sort(key=lambda item: (units[item.nodeid] not in longest, units[item.nodeid] not in slow))
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
