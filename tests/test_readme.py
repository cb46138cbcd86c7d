"""README's Python snippet runs as pasted, and its quickstart test command is CI's."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def test_the_python_snippet_runs_as_pasted():
    (code,) = re.findall(r"```python\n(.*?)```", README, re.S)
    ns: dict = {}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), ns)  # noqa: S102 (our own README)
    sol = ns["sol"]
    assert sol.stats["verified"]
    # the hard end positions hold; the soft end velocities are pulled towards 0 m/s
    assert sol.position("x")[[0, -1]] == pytest.approx([0.0, 10.0], abs=1e-9)
    assert np.all(np.abs(sol.velocity("x")[[0, -1]]) < 0.1)
    printed = out.getvalue().strip().splitlines()
    assert printed[-1] == f"True {sol.stats['verification']['forward_error']!r}"


def test_ci_runs_the_quickstart_test_command():
    cmds = re.findall(r"```bash\n(.*?)\n```", README, re.S)
    tests = [c for c in cmds if "pytest" in c]
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()[-1]
    assert tests == [ci]
