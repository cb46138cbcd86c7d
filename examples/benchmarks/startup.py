"""Benchmark: start-up time of ``import bvpnav`` and ``bvpnav --help``.

Each command runs as a fresh Python process, several times, the commands taking turns
(round 1: every command once, round 2: every command again, ...) so that a machine
that slows down or speeds up during the run affects them all alike. Reported: the median
wall and CPU (user + system) seconds per command, and the ratio of ``import bvpnav`` to
``import pandas`` taken round by round (then the median of those ratios), all measured
in this one run. ``import cvxpy`` and an empty interpreter are there for reference.
Also listed: which heavy packages ``import bvpnav`` loads (none should be).

The children inherit the environment: with ``PYTHONDONTWRITEBYTECODE`` set, an editable
bvpnav is compiled from source on every start while pandas and cvxpy have the ``.pyc``
files their installation wrote. ``--bytecode`` gives the children a bytecode cache (a
temporary ``PYTHONPYCACHEPREFIX``, filled by the warm-up round), as installing a wheel does.

The aims (issue "A library people can learn from"): ``import bvpnav`` at most 1.5x
``import pandas``, ``bvpnav --help`` under 1 s. Timings belong here, never in tests
(``tests/test_startup.py`` checks only what is imported).

Run ``python examples/benchmarks/startup.py [--runs 11] [--bytecode]``.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HEAVY = ("cvxpy", "matplotlib", "tqdm", "scipy.optimize", "scipy.interpolate", "scipy.integrate",
         "scipy.spatial", "scipy.stats", "scipy.sparse.linalg")


def cli_command() -> list[str]:
    """The installed ``bvpnav`` console script (next to this interpreter, else on PATH);
    the same entry point through the interpreter when it is not installed."""
    here = os.path.join(os.path.dirname(sys.executable), "bvpnav")
    script = here if os.path.exists(here) else shutil.which("bvpnav")
    if script:
        return [script, "--help"]
    return [sys.executable, "-c", "import sys; from bvpnav.cli import main; sys.exit(main(['--help']))"]


def commands() -> dict[str, list[str]]:
    py = sys.executable
    return {
        "python (empty)": [py, "-c", "pass"],
        "import pandas": [py, "-c", "import pandas"],
        "import bvpnav": [py, "-c", "import bvpnav"],
        "bvpnav --help": cli_command(),
        "import cvxpy": [py, "-c", "import cvxpy"],
    }


def run_once(cmd: list[str], env: dict | None = None) -> tuple[float, float]:
    """(wall s, CPU s) of one run of ``cmd`` (its output discarded; a failure raises)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True, env=env)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def loaded_by_import(env: dict | None = None) -> list[str]:
    """The packages of :data:`HEAVY` that ``import bvpnav`` loads, in a fresh process."""
    code = ("import sys, bvpnav; print(' '.join(m for m in sys.argv[1:] if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code, *HEAVY], capture_output=True, text=True,
                         check=True, env=env)
    return out.stdout.split()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=11, help="counted runs per command (default 11)")
    ap.add_argument("--warmup", type=int, default=1, help="uncounted rounds first (default 1)")
    ap.add_argument("--bytecode", action="store_true",
                    help="give the children a bytecode cache (as an installed wheel has)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bvpnav-pyc-") as cache:
        env = None
        if args.bytecode:
            env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
            env["PYTHONPYCACHEPREFIX"] = cache
        report(args, env)


def report(args, env: dict | None) -> None:
    cmds = commands()
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in cmds}
    for k in range(max(args.warmup, 1 if env else 0) + args.runs):
        for name, cmd in cmds.items():
            wall, cpu = run_once(cmd, env)
            if k >= max(args.warmup, 1 if env else 0):
                times[name].append((wall, cpu))

    def med(name: str, i: int) -> float:
        return statistics.median(t[i] for t in times[name])

    def ratio(a: str, b: str, i: int) -> float:
        return statistics.median(x[i] / y[i] for x, y in zip(times[a], times[b], strict=True))

    env_now = os.environ if env is None else env
    cached = "on" if not env_now.get("PYTHONDONTWRITEBYTECODE") else "off (PYTHONDONTWRITEBYTECODE)"
    print(f"start-up, median of {args.runs} runs per command (fresh processes, taking turns; "
          f"Python {sys.version.split()[0]}, {os.cpu_count()} CPUs; bytecode cache {cached})")
    print(f"{'command':<18}{'wall s':>9}{'cpu s':>9}{'min wall':>10}{'max wall':>10}")
    for name in cmds:
        walls = [t[0] for t in times[name]]
        print(f"{name:<18}{med(name, 0):>9.3f}{med(name, 1):>9.3f}{min(walls):>10.3f}{max(walls):>10.3f}")
    print()
    for a, b in (("import bvpnav", "import pandas"), ("import cvxpy", "import pandas")):
        print(f"{a} / {b}: wall {ratio(a, b, 0):.2f}x, cpu {ratio(a, b, 1):.2f}x "
              "(median of the per-round ratios)")
    print(f"bvpnav --help: median wall {med('bvpnav --help', 0):.3f} s")
    heavy = loaded_by_import(env)
    print(f"loaded by `import bvpnav` of {', '.join(HEAVY)}: {', '.join(heavy) or 'none'}")


if __name__ == "__main__":
    main()
