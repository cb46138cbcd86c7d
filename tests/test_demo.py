"""`bvpnav demo`: the README's main job prints its table and writes its PNG."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest


def _bvpnav_cmd() -> list[str]:
    exe = shutil.which("bvpnav") or str(Path(sys.executable).with_name("bvpnav"))
    if Path(exe).exists():
        return [exe]
    return [sys.executable, "-m", "bvpnav.cli"]  # pragma: no cover


def test_demo_prints_table_and_writes_png(tmp_path):
    png = tmp_path / "demo.png"
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([*_bvpnav_cmd(), "demo", "--plot", str(png)], capture_output=True,
                          text=True, timeout=300, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    rows = {}
    for line in out.splitlines():
        if line[:4].strip() in ("I", "II", "III", "IV"):
            rows[line[:4].strip()] = float(line.split()[-1])
    assert set(rows) == {"I", "II", "III", "IV"}, out
    # the ordering the papers teach: drifting IVP >> BVP with ends >> with more information
    assert rows["I"] > 2 * rows["II"]
    assert rows["II"] > 5 * rows["III"]
    assert rows["IV"] < rows["II"] / 5
    assert png.exists() and png.stat().st_size > 10_000
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_demo_rejects_unknown_scenario(tmp_path):
    proc = subprocess.run([*_bvpnav_cmd(), "demo", "no-such-scenario", "--plot", str(tmp_path / "x.png")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "tikhonov2011" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize("argv", [["--help"], ["demo", "--help"]])
def test_help_teaches(argv):
    proc = subprocess.run([*_bvpnav_cmd(), *argv], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0
    assert "boundary value problem" in proc.stdout or "trapezoid" in proc.stdout
