"""The tutorial series runs at small size and asserts what it teaches."""

from __future__ import annotations

import json
import pathlib

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
def test_tutorial_runs_and_asserts_its_number(script, docs_build):
    """Each tutorial ran, at small size, in an interpreter of its own: the Jupyter kernel in which
    the documentation build (the session's ``docs_build``, once for test_docs and these tests)
    executed its page, as a reader opening it as a notebook would; a cell that raises (an assert
    of the number it teaches) fails that build. Every code cell ran, in order, none raised, it
    printed the number and saved its figures (``$BVPNAV_FIGURES``, here the build's folder)."""
    nb = json.loads((docs_build.notebooks / "tutorials" / f"{script.stem}.ipynb").read_text())
    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    lines = script.read_text().splitlines()
    cells = sum(line.startswith("# %%") and "[markdown]" not in line for line in lines)
    assert len(code) == cells, "the page's code cells are not the script's"
    assert [c.get("execution_count") for c in code] == list(range(1, len(code) + 1)), "not every cell ran"
    outputs = [o for c in code for o in c.get("outputs", [])]
    assert not [o for o in outputs if o["output_type"] == "error"]
    printed = "".join("".join(o["text"]) for o in outputs
                      if o["output_type"] == "stream" and o["name"] == "stdout")
    assert printed.strip()  # prints the number it teaches
    figures = sorted(docs_build.figures.glob(f"{script.stem[:2]}_*.png"))
    assert figures and all(f.stat().st_size > 5000 for f in figures)
