"""The ``bvpnav`` command.

Exit codes: 0 success; 2 bad input (a file, a spec, an argument); 3 the solve failed
(infeasible information, or no solver produced a verified answer); 1 anything else
(a bug: please report it).
"""

from __future__ import annotations

import argparse
import sys

from . import __version__
from .errors import BvpnavError, InputError, SolveError

EXIT_OK, EXIT_BUG, EXIT_INPUT, EXIT_SOLVE = 0, 1, 2, 3

DESCRIPTION = """\
bvpnav: post-processed inertial navigation as a boundary value problem.

Accelerations are integrated with linear finite elements between what you know at
the ends (and elsewhere): positions, velocities, average velocities, symmetry,
stationary intervals... posed as one convex problem and solved with a verified solver.

Start here:
  bvpnav demo                 run the bundled scenario, print a table, write a PNG
"""

EPILOG = "Exit codes: 0 ok, 2 bad input, 3 infeasible or failed solve, 1 internal error."


def _cmd_demo(args) -> int:
    from .demo import run_demo
    from .scenarios import SCENARIOS

    if args.scenario not in SCENARIOS:
        raise InputError(f"unknown scenario {args.scenario!r}; choose one of {sorted(SCENARIOS)}")
    run_demo(png=args.plot, seed=args.seed, quiet=args.quiet)
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bvpnav", description=DESCRIPTION, epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"bvpnav {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser(
        "demo", help="run a bundled scenario and compare methods",
        description="Run the 2011 paper's quintic scenario (biased, scaled, noisy accelerometer) "
                    "three ways -- trapezoid time-stepping, FEM with both ends fixed, FEM with "
                    "Tikhonov information -- print RMS position errors and write a PNG.",
    )
    demo.add_argument("scenario", nargs="?", default="tikhonov2011", help="scenario name")
    demo.add_argument("--plot", default="bvpnav-demo.png", metavar="PNG",
                      help="figure path (default: %(default)s)")
    demo.add_argument("--seed", type=int, default=0, help="noise seed (default: %(default)s)")
    demo.add_argument("--quiet", action="store_true", help="print nothing")
    demo.set_defaults(func=_cmd_demo)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bvpnav`` command; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return EXIT_INPUT
    try:
        return int(args.func(args))
    except InputError as exc:
        print(f"bvpnav: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except SolveError as exc:
        print(f"bvpnav: solve failed: {exc}", file=sys.stderr)
        return EXIT_SOLVE
    except BvpnavError as exc:
        print(f"bvpnav: error: {exc}", file=sys.stderr)
        return EXIT_SOLVE
    except OSError as exc:
        print(f"bvpnav: error: {exc}", file=sys.stderr)
        return EXIT_INPUT


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
