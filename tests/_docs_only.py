"""Run the documentation as a fresh ``pip install -e ".[docs]"`` would: nothing else importable.

The test environment has every extra installed (``[test]``), which once hid that the site
needed ``rosbags`` while ``[docs]`` did not install it. :func:`environment` returns the
variables that make a Python process (the Sphinx build and the notebook kernels it starts,
which inherit its environment) refuse to import any top-level module whose distribution is
not in the dependency closure of ``bvpnav[docs]``: a ``sitecustomize`` puts a finder first
on ``sys.meta_path`` that raises ``ModuleNotFoundError`` for those names (and
``importlib.util.find_spec`` answers None), so an optional import (pandas trying pyarrow)
degrades as it would in that venv and a needed one fails.

The closure is read from ``pyproject.toml`` (bvpnav's own extras, followed through
self-references such as ``bvpnav[ros]``) and from the installed metadata of every other
distribution (their requirements, evaluated for this Python and the requested extras).
``.ci/run`` also builds the site in a real fresh venv from ``[docs]`` alone.
"""

from __future__ import annotations

import json
import sys
from importlib import metadata
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]

SITECUSTOMIZE = '''\
import json as _json
import os as _os
import sys as _sys

_BLOCKED = frozenset(_json.loads(open(_os.environ["BVPNAV_DOCS_ONLY_BLOCKED"]).read()))


class _NotInDocsExtra:
    """Top-level modules that a venv with only bvpnav[docs] installed would not have."""

    @staticmethod
    def find_spec(name, path=None, target=None):
        if "." not in name and name in _BLOCKED:
            raise ModuleNotFoundError(
                f"No module named {name!r}: its distribution is not installed by bvpnav[docs] "
                "(tests/_docs_only.py builds the site as a fresh `pip install -e .[docs]` would; "
                "add what the pages need to the [docs] extra in pyproject.toml)", name=name)
        return None


_sys.meta_path.insert(0, _NotInDocsExtra)

# A probe for an optional package (IPython asks importlib.util.find_spec("argcomplete")) gets the
# answer it would get in that venv: not there.
import importlib.util as _util  # noqa: E402

_find_spec = _util.find_spec


def _probe(name, package=None):
    if name.partition(".")[0] in _BLOCKED:
        return None
    return _find_spec(name, package)


_util.find_spec = _probe
'''


def _requirements(name: str, extras: frozenset[str], project: dict) -> list[Requirement]:
    """The requirements of one distribution with the given extras, markers evaluated."""
    if canonicalize_name(name) == "bvpnav":
        reqs = [Requirement(r) for r in project["dependencies"]]
        for extra in extras:
            reqs += [Requirement(r) for r in project["optional-dependencies"].get(extra, [])]
        return [r for r in reqs if r.marker is None or r.marker.evaluate({"extra": ""})]
    try:
        dist = metadata.distribution(name)
    except metadata.PackageNotFoundError:
        return []  # not installed here: nothing of it can be imported anyway
    out = []
    for text in dist.requires or []:
        req = Requirement(text)
        if req.marker is None or any(req.marker.evaluate({"extra": e}) for e in ("", *extras)):
            out.append(req)
    return out


def docs_closure(extra: str = "docs") -> set[str]:
    """Canonical names of every distribution that ``pip install .[extra]`` brings in."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    seen: set[tuple[str, frozenset[str]]] = set()
    stack = [("bvpnav", frozenset({extra}))]
    while stack:
        name, extras = stack.pop()
        key = (canonicalize_name(name), extras)
        if key in seen:
            continue
        seen.add(key)
        for req in _requirements(name, extras, project):
            stack.append((req.name, frozenset(req.extras)))
    return {name for name, _ in seen}


def blocked_modules(extra: str = "docs") -> list[str]:
    """Top-level import names provided only by distributions outside the closure."""
    keep = docs_closure(extra)
    blocked = []
    for module, dists in metadata.packages_distributions().items():
        if module in sys.stdlib_module_names or module in ("bvpnav", "constraints"):
            continue
        if not any(canonicalize_name(d) in keep for d in dists):
            blocked.append(module)
    return sorted(blocked)


def environment(folder: Path, extra: str = "docs") -> dict[str, str]:
    """Environment variables under which a Python process sees only ``bvpnav[extra]``."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "sitecustomize.py").write_text(SITECUSTOMIZE)
    blocked = folder / "blocked.json"
    blocked.write_text(json.dumps(blocked_modules(extra)))
    return {"PYTHONPATH": str(folder), "BVPNAV_DOCS_ONLY_BLOCKED": str(blocked)}
