"""The simulated car-drive benchmark (examples/benchmarks/car_drive.py) at its quick size.

Measured on seed 0, tactical, 120 s at 50 Hz (the full 600 s / 100 Hz table over seeds is in
README and the script's docstring): at 10 / 30 s between kept fixes node states (``ErrorStates``)
reach 0.655 / 2.128 m, with NonHolonomic 0.430 / 1.754 m, a spline 6.98 / 48.8 m; GTSAM's example
graph 0.663 / 2.110 m, the peer smoother 0.655 / 2.123 m. Every bvpnav answer verified. The
comparison with GTSAM (a peer, not a test dependency) is the benchmark's: its table prints the ratios.
"""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest
from _helpers import load_benchmark_module

pytestmark = pytest.mark.slow  # the benchmark's quick run

@pytest.fixture(scope="module")
def quick():
    bench = load_benchmark_module("car_drive")
    methods = ["bvpnav states", "bvpnav states NHC soft", "spline"]
    with contextlib.redirect_stdout(io.StringIO()) as out:
        rows = bench.main(["--quick", "--grade", "tactical", "--methods", *methods, "--ref", "spline"])
    return {(r["method"], r["gap"]): r for r in rows}, out.getvalue()


def test_node_states_fit_and_beat_the_spline(quick):
    by, printed = quick
    for gap, limit in {10.0: 0.8, 30.0: 2.5}.items():  # m; measured 0.655 and 2.128
        states, nhc, spline = (by[(m, gap)] for m in ("bvpnav states", "bvpnav states NHC soft", "spline"))
        assert states["rms"] < limit, states
        assert states["verified"] and nhc["verified"], (states, nhc)
        assert states["iterations"] <= 10, states  # measured 5
        assert not any(w.startswith("misfit") for w in states["warnings"]), states  # the model fits
        assert nhc["rms"] < 0.9 * states["rms"], (nhc, states)  # measured 0.66x and 0.82x
        assert spline["rms"] > 5.0 * states["rms"], (spline, states)
        assert states["samples"] == 6001 and 0.0 < states["peak_mb"] < 4096.0
    assert "over seeds [0]" in printed and "verified" in printed


def test_summary_mean_worst_ratios_and_counts():
    """Per grade, gap and method over the seeds: mean and worst RMS, the worst ratios to the
    reference on the same drive, the drives where the method is no worse, verified answers."""
    bench = load_benchmark_module("car_drive")

    def row(method, seed, rms, seconds, verified=None, **kw):
        return {"grade": "tactical", "gap": 10.0, "method": method, "seed": seed, "rms": rms,
                "seconds": seconds, "cpu_seconds": seconds / 2, "verified": verified, "peak_mb": 1.0,
                "samples": 2**10, **kw}

    rows = [row("GTSAM", 0, 1.0, 1.0), row("GTSAM", 1, 2.0, 2.0), row("GTSAM", 2, 1.0, 1.0),
            row("bvpnav states", 0, 0.9, 3.0, True), row("bvpnav states", 1, 2.2, 10.0, True),
            row("bvpnav states", 2, 1.0, 2.0, False),
            row("bvpnav README", 0, np.nan, 5.0, refused="InputError: nothing determines 3 combinations")]
    got = {s["method"]: s for s in bench.summary(rows, "GTSAM")}
    s = got["bvpnav states"]
    assert s["rms_mean"] == pytest.approx(4.1 / 3) and s["rms_worst"] == pytest.approx(2.2)
    assert s["x_rms_worst"] == pytest.approx(1.1) and s["x_seconds_worst"] == pytest.approx(5.0)
    assert s["seconds"] == pytest.approx(5.0) and s["cpu_seconds"] == pytest.approx(2.5)
    assert s["x_cpu_worst"] == pytest.approx(5.0)  # CPU is half the wall time for both here
    assert (s["wins"], s["runs"], s["verified"], s["failed"]) == (2, 3, 2, 0)  # ties count as no worse
    assert s["peak_b"] == pytest.approx(2**20 / 2**10)
    r = got["bvpnav README"]
    assert (r["runs"], r["failed"]) == (0, 1) and np.isnan(r["rms_mean"])
    with contextlib.redirect_stdout(io.StringIO()) as out:
        bench.print_summary(rows, "GTSAM", [0, 1, 2])
    assert "1 failed" in out.getvalue() and "2/3" in out.getvalue()
