"""The tutorial series runs as scripts at small size and asserts what it teaches."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import pytest

TUTORIAL = pathlib.Path(__file__).resolve().parents[1] / "examples" / "tutorial"
SCRIPTS = sorted(TUTORIAL.glob("[0-9][0-9]_*.py"))


def test_the_series_is_complete_and_in_percent_format():
    assert [p.name[:2] for p in SCRIPTS] == [f"{k:02d}" for k in range(1, 9)]
    for p in SCRIPTS:
        text = p.read_text()
        assert "format_name: percent" in text and text.count("# %%") >= 3, p.name


@pytest.mark.slow
@pytest.mark.parametrize("script", SCRIPTS, ids=[p.stem for p in SCRIPTS])
def test_tutorial_runs_and_asserts_its_number(script, tmp_path):
    """Each tutorial is run in its own interpreter (as a reader would run it), so its
    home-made items and figures cannot leak into other tests."""
    env = dict(os.environ, BVPNAV_SMALL="1", BVPNAV_FIGURES=str(tmp_path), MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    figures = list(tmp_path.glob("*.png"))
    assert figures and all(f.stat().st_size > 5000 for f in figures)
    assert proc.stdout.strip()  # prints the number it teaches
