"""Start-up: what ``import bvpnav`` and ``bvpnav --help`` load (no timings here; those are
in examples/benchmarks/startup.py). Each check runs in a fresh interpreter, since this
test process may already have imported cvxpy."""

from __future__ import annotations

import subprocess
import sys

import pytest
from _helpers import run_python

#: Packages bvpnav imports only where they are used.
HEAVY = ("cvxpy", "matplotlib")


def loaded(after: str) -> dict:
    """Which of :data:`HEAVY` are imported after running ``after``."""
    return run_python(f"""
        import json, sys
        {after}
        print(json.dumps({{m: m in sys.modules for m in {HEAVY!r}}}))
    """)


@pytest.mark.parametrize("statement", ["import bvpnav", "import bvpnav.constraints",
                                       "import bvpnav.error_models", "import bvpnav.backends"])
def test_import_loads_neither_cvxpy_nor_matplotlib(statement):
    assert loaded(statement) == {m: False for m in HEAVY}


def test_help_works_without_cvxpy():
    out = run_python("""
        import contextlib, io, json, sys
        from bvpnav.cli import main
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            try:
                code = main(["--help"])
            except SystemExit as exc:  # argparse exits after printing the help
                code = exc.code
        print(json.dumps({"code": code, "usage": buf.getvalue().startswith("usage: bvpnav"),
                          "cvxpy": "cvxpy" in sys.modules,
                          "matplotlib": "matplotlib" in sys.modules}))
    """)
    assert out == {"code": 0, "usage": True, "cvxpy": False, "matplotlib": False}


def test_help_entry_point_exits_0():
    proc = subprocess.run([sys.executable, "-m", "bvpnav.cli", "--help"], capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("usage: bvpnav")


PROBLEM = """
    import json, sys
    import numpy as np
    import bvpnav
    from bvpnav.constraints import Position, Velocity
    t = np.linspace(0.0, 2.0, 201)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.sin(t)))
    prob.add(Position(t=[0.0, 2.0], value=[0.0, 1.0]))
    prob.add(Velocity(t=[1.0], value=[0.5], sigma=0.1))
"""


def test_direct_solve_needs_no_cvxpy_then_clarabel_loads_it():
    out = run_python(PROBLEM + """
    text = prob.describe()
    direct = prob.solve(solver="direct", fallback=None)
    before = "cvxpy" in sys.modules
    clarabel = prob.solve(solver="clarabel")
    print(json.dumps({"before": before, "after": "cvxpy" in sys.modules,
                      "verified": [direct.stats["verified"], clarabel.stats["verified"]],
                      "solvers": [direct.stats["solver"], clarabel.stats["solver"]],
                      "diff": float(np.max(np.abs(direct.trajectory.to_numpy()
                                                  - clarabel.trajectory.to_numpy())))}))
    """)
    assert out["before"] is False and out["after"] is True
    assert out["verified"] == [True, True]
    assert out["solvers"] == ["direct", "clarabel"]
    assert out["diff"] < 1e-6


def test_lazy_names_resolve():
    import bvpnav

    for name in ("attitude", "baselines", "simulate", "solve", "lam", "lambda_curve",
                 "compare_solvers"):
        assert name in dir(bvpnav)
        assert getattr(bvpnav, name) is not None
    from bvpnav import lambda_curve, simulate
    from bvpnav.solve import lambda_curve as original

    assert lambda_curve is original and simulate.__name__ == "bvpnav.simulate"
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        bvpnav.nonexistent  # noqa: B018


def test_help_and_version_load_neither_numpy_nor_pandas():
    """``bvpnav --help`` builds its parser (the sample names and descriptions included)
    from the package's version and exceptions alone: what makes it start in well under
    a second (timed in examples/benchmarks/startup.py)."""
    out = run_python("""
        import contextlib, io, json, sys
        from bvpnav.cli import main
        for argv in (["--help"], ["simulate", "--help"], ["--version"]):
            with contextlib.redirect_stdout(io.StringIO()):
                try:
                    main(argv)
                except SystemExit:
                    pass
        print(json.dumps({m: m in sys.modules for m in ("numpy", "pandas", "scipy")}))
    """)
    assert out == {"numpy": False, "pandas": False, "scipy": False}
