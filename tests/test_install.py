"""The installed package exposes every file of the top-level constraints/ folder."""

from __future__ import annotations

import importlib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FILES = sorted(p.name for p in (ROOT / "constraints").glob("*.py"))


def test_every_constraints_file_imports_from_the_installed_package():
    import bvpnav.constraints as pkg

    installed = Path(pkg.__file__).parent
    for name in FILES:
        if name == "__init__.py":
            continue
        mod = importlib.import_module(f"bvpnav.constraints.{name[:-3]}")
        assert Path(mod.__file__).name == name
        assert (installed / name).exists()


# pip builds in the source tree (build/, *.egg-info): one worker for every wheel build (pytest -n)
@pytest.mark.xdist_group("wheel-build")
@pytest.mark.slow
def test_wheel_contains_every_constraints_file(wheel_build):
    """What `pip install .` installs: build the wheel (conftest: pip wheel --no-deps of the
    source tree) and read its file list."""
    proc, folder = wheel_build
    if proc.returncode != 0:
        pytest.fail(f"building the wheel failed:\n{proc.stdout}\n{proc.stderr}")
    wheel = next(folder.glob("bvpnav-*.whl"))
    names = set(zipfile.ZipFile(wheel).namelist())
    for name in FILES:
        assert f"bvpnav/constraints/{name}" in names, name
    assert "bvpnav/__init__.py" in names and "bvpnav/problem.py" in names
    # and every module of the core, sub-packages included (a package missing from
    # pyproject's list is silently left out of the wheel; the editable install hides it)
    core = ROOT / "src" / "bvpnav"
    for path in sorted(core.rglob("*.py")):
        assert f"bvpnav/{path.relative_to(core).as_posix()}" in names, path
