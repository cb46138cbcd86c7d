"""The ``bvpnav`` command.

Exit codes: 0 success; 2 bad input (a file, a spec, an argument, an output that would
replace an input or cannot be written); 3 the solve failed (infeasible information, no
solver produced a verified answer -- for ``compare``: no row verified; for ``batch``: a
recording failed --, or out of memory); 130 interrupted (Ctrl-C), 143 terminated
(SIGTERM), temporary files removed in both cases; 1 anything else (an internal error: a
bug, please report it; ``BVPNAV_DEBUG=1`` shows its traceback).

Every command checks its outputs before any work (:func:`bvpnav.io.check_outputs`): no
output may be an input or another output (after symlinks and hard links), figure and
table suffixes must be formats bvpnav writes, and the output folders must be writable.
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import time
import warnings

from . import __version__, log
from .errors import BvpnavError, InputError, SolveError, SolverNotFound

EXIT_OK, EXIT_BUG, EXIT_INPUT, EXIT_SOLVE = 0, 1, 2, 3

DESCRIPTION = """\
bvpnav: post-processed inertial navigation as a boundary value problem.

Accelerations are integrated with linear finite elements between what you know at
the ends (and elsewhere): positions, velocities, average velocities, symmetry,
stationary intervals... posed as one convex problem and solved with a verified solver.

Start here:
  bvpnav demo                                  the bundled scenario: a table and a PNG
  bvpnav simulate tikhonov2011 --out rec       a synthetic recording and its spec
  bvpnav solve rec/recording.csv --spec rec/spec.toml --out traj.csv --plot traj.png
  bvpnav lcurve rec/recording.csv --spec rec/spec.toml --plot lcurve.png
  bvpnav compare rec/recording.csv --spec rec/spec.toml
  bvpnav batch recordings/ --spec spec.toml --out results/ --workers 2

A recording is a CSV or Parquet file (or a bag, a phone export: `bvpnav readers`) with a
time column and navigation-frame acceleration columns, or strapdown channels (specific
force and gyro rates in the sensor's axes, aligned from an interval at rest by the spec's
[align]: `bvpnav solve --help`); the spec (TOML) says which columns and units, what else
is known (items), the error model, the solver and how to choose lambda. See `bvpnav
simulate --help` for the samples and what each writes.
"""

EPILOG = ("Exit codes: 0 ok, 2 bad input, 3 infeasible or failed solve (compare: nothing verified; "
          "batch: a recording failed), 130 interrupted, 143 terminated, 1 internal error "
          "(BVPNAV_DEBUG=1 shows the traceback).")
EXIT_INTERRUPT, EXIT_TERM = 130, 143

_log = logging.getLogger("bvpnav.cli")


def verbosity(args) -> int:
    """``-q`` -> -1 (errors only), nothing -> 0, ``-v`` -> 1 (INFO), ``-vv`` -> 2 (DEBUG)."""
    v = int(getattr(args, "verbose", 0) or 0)
    if getattr(args, "quiet", False):
        if v:
            raise InputError("-q and -v together: give -v (more: INFO, -vv DEBUG) or -q (errors only), "
                             "not both")
        return -1
    return v


def _cmd_demo(args) -> int:
    from .demo import run_demo
    from .scenarios import SCENARIOS

    if args.scenario not in SCENARIOS:
        raise InputError(f"unknown scenario {args.scenario!r}; choose one of {sorted(SCENARIOS)}")
    if args.plot:
        _check(args, {}, {"--plot": args.plot}, figures=("--plot",))
    run_demo(png=args.plot, seed=args.seed, quiet=verbosity(args) < 0)
    return EXIT_OK


#: ``bvpnav compare``'s time limit per solver run when neither ``--time-limit`` nor the spec's
#: ``[solve] time_limit`` gives one, s.
COMPARE_TIME_LIMIT = 60.0

#: What a declared flag's help adds on one command.
_FLAG_NOTES = {("compare", "time_limit"): f" (compare: default {COMPARE_TIME_LIMIT:g} s per solver run)",
               ("solve", "uncertainty"): "; in OUT, with a +/-2 sigma band on --plot"}


def declared_flags(parser, command: str) -> None:
    """Add a flag for every declared solve option that has one on ``command``
    (:func:`bvpnav.declare.cli_options`)."""
    from .declare import cli_options

    for opt in cli_options(command):
        kw = {"default": None, "dest": opt.name, **opt.cli_kwargs}
        parser.add_argument(opt.cli, help=opt.cli_help + _FLAG_NOTES.get((command, opt.name), ""), **kw)


def overrides(args, command: str) -> dict:
    """The declared solve options given as flags on ``command``: each text read by its
    option and checked by its declaration (the message of ``solve()``, after the flag)."""
    from .declare import cli_options, from_flag

    out = {}
    for opt in cli_options(command):
        text = getattr(args, opt.name, None)
        if text is not None:
            out[opt.name] = from_flag(opt, text)
    return out


def _uncertainty_report(sol, out, asked=None) -> list[str]:
    """Lines of the printed report about the standard deviations (none without them);
    ``asked``: the ``uncertainty`` the solve was given."""
    from .batch import uncertainty_summary

    rec = uncertainty_summary(sol)
    if rec is None:
        return []
    vf, dof = rec.get("variance_factor"), rec.get("dof")
    vf_text = "n/a" if vf is None else f"{vf:.4g}"
    if rec.get("scale") == "scaled":
        what = f"are scaled by the a-posteriori variance factor {vf_text} ({dof} degrees of freedom)"
        if asked is True:
            what += "; the load form has no noise model, so they are always scaled"
    else:
        what = (f"assume the stated noise (sigma_a and the items' sigma); the a-posteriori variance "
                f"factor is {vf_text} on {dof} degrees of freedom (about 1 if those sigmas are right)")
    std = rec.get("std", {})

    def fmt(keys, unit):
        return ", ".join(f"{k} {std[k]['median']:.3g} {unit}" for k in keys if std.get(k, {}).get("median")
                         is not None)

    axes = sol._pos_cols
    lines = [f"uncertainty ({rec.get('model')} covariance): the standard deviations {what}",
             f"  median std: position {fmt(axes, 'm')}; velocity {fmt(['v' + a for a in axes], 'm/s')} "
             f"(columns {', '.join(rec.get('columns', []))} in {out})"]
    ep_std = getattr(sol, "error_params_std", None)
    if ep_std is not None and len(ep_std):
        units = ep_std.attrs.get("units", {})
        lines.append("  error model: " + ", ".join(
            f"{k} = {sol.error_params[k]:.4g} +/- {ep_std[k]:.2g}{(' ' + units[k]) if units.get(k) else ''}"
            for k in ep_std.index))
    return lines


def _check(args, inputs: dict, outputs: dict, figures=(), tables=()) -> None:
    """The output policy before any work: suffixes, then :func:`bvpnav.io.check_outputs`."""
    from .io import check_figure_path, check_outputs, check_table_path

    for opt in figures:
        if outputs.get(opt) is not None:
            check_figure_path(outputs[opt], opt)
    for opt in tables:
        if outputs.get(opt) is not None:
            check_table_path(outputs[opt], opt)
    check_outputs(inputs, outputs)


def _load(args):
    from .readers import read
    from .spec import load_spec

    spec = load_spec(args.spec)
    rec = read(args.input, spec.input)
    for note in rec.notes:
        _log.info("%s: %s", args.input, note)
    info = rec.items_in(spec.input.get("frame", "enu"))
    return spec, spec.build(spec.imu_data(rec, info), info=info)


def _say(args, text: str) -> None:
    if verbosity(args) >= 0:
        print(text)


def _lam_range(args):
    """``--lam-range LO HI`` as two floats, or InputError saying what is wrong and the fix."""
    if args.lam_range is None:
        return None
    import numpy as np

    from .formulation import LAM_RANGE

    text = " ".join(args.lam_range)
    try:
        lo, hi = (float(v) for v in args.lam_range)
    except ValueError:
        raise InputError(f"--lam-range {text}: give two numbers LOW HIGH, e.g. --lam-range 1e-4 "
                         "1e4") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
        raise InputError(f"--lam-range {text}: need 0 < LOW < HIGH (finite), e.g. --lam-range 1e-4 1e4")
    if lo < LAM_RANGE[0] or hi > LAM_RANGE[1]:
        raise InputError(f"--lam-range {text}: reaches beyond {LAM_RANGE[0]:g} .. {LAM_RANGE[1]:g}, the "
                         "lambdas double precision can weigh against the data term; sweep inside it (default "
                         "1e-6 1e6)")
    return lo, hi


def _points(args) -> int | None:
    if args.points is not None and not 7 <= args.points <= 1000:
        raise InputError(f"--points {args.points}: give 7 to 1000 sweep points (each is one solve; the "
                         "chosen lambda is refined anyway; default: the sweep of 'bvpnav solve')")
    return args.points


def read_truth(path, sol, implicit: bool = False):
    """True positions (N, d) from a truth table (``t`` and one column per axis, m; the
    ``truth.csv`` that ``bvpnav simulate`` writes), at the solution's sample times; (N, 2)
    from a 2-D truth (``t, x, y``: the usual motion-capture case) of an x, y, z solution.

    A truth sampled at other times is interpolated linearly when it covers the
    recording's window. Raises InputError naming the file and the fix; with
    ``implicit=True`` (a ``truth.csv`` found beside the recording) returns None instead.
    """
    from pathlib import Path

    import numpy as np
    import pandas as pd

    where = "truth.csv beside the recording" if implicit else f"--truth {str(path)!r}"
    try:
        if Path(path).suffix.lower() in (".parquet", ".pq"):
            from .io import parquet_frame

            df = parquet_frame(path)
        else:
            df = pd.read_csv(path)
        axes = sol._pos_cols
        if list(axes) == ["x", "y", "z"] and {"t", "x", "y"} <= set(df.columns) and "z" not in df.columns:
            axes = ["x", "y"]  # a 2-D truth (motion capture): the horizontal positions are scored
        missing = [c for c in ["t", *axes] if c not in df.columns]
        if missing:
            raise InputError(f"{where}: no column(s) {missing}; it has {list(df.columns)}. A truth file has "
                             f"t (s) and one position column per axis {axes} (m), like the truth.csv "
                             "`bvpnav simulate` writes")
        tt = df["t"].to_numpy(dtype=float)
        vals = df[axes].to_numpy(dtype=float)
        if not (np.all(np.isfinite(tt)) and np.all(np.isfinite(vals))):
            raise InputError(f"{where}: holds empty or non-numeric cells; give finite numbers")
        t = sol.t
        if tt.shape == t.shape and np.allclose(tt, t, rtol=0, atol=1e-9 * max(1.0, abs(t[-1]))):
            return vals
        if tt.size < 2 or np.any(np.diff(tt) <= 0) or tt[0] > t[0] + 1e-9 or tt[-1] < t[-1] - 1e-9:
            raise InputError(f"{where}: its times ({tt.size} rows, {tt[0]:g} .. {tt[-1]:g} s) do not "
                             f"cover the recording's {t.size} samples ({t[0]:g} .. {t[-1]:g} s) in "
                             "increasing order; give the truth at the recording's times")
        return np.column_stack([np.interp(t, tt, vals[:, j]) for j in range(len(axes))])
    except InputError:
        if implicit:
            _log.warning("not drawing %s: it does not match this recording", where)
            return None
        raise
    except (OSError, ValueError) as exc:
        if implicit:
            return None
        raise InputError(f"{where}: cannot be read ({exc}); give a CSV with t and positions") from None


def _cmd_simulate(args) -> int:
    from .samples import write_sample

    paths = write_sample(args.scenario, args.out, seed=args.seed, rate=args.rate, force=args.force)
    _say(args, "wrote " + ", ".join(str(p) for p in paths))
    return EXIT_OK


def _info_options(pairs: list[str], has_info: bool) -> dict:
    """``--info-option KEY=VALUE`` pairs as a dict; a value is read as a TOML value (a number,
    ``true``, ``[0.5, 0, 1.2]``, a quoted string) or else taken as the text itself."""
    import datetime as _dt

    if pairs and not has_info:
        raise InputError("--info-option sets a reader option of the --info files, but no --info file is "
                         "given: add --info FILE or drop the option")

    out = {}
    for pair in pairs:
        key, sep, text = str(pair).partition("=")
        key = key.strip()
        if not sep or not key or not text.strip():
            raise InputError(f"--info-option {pair!r}: give KEY=VALUE, e.g. --info-option speed_as=odometer")
        if key in out:
            raise InputError(f"--info-option {key}: given twice; give each reader option once")
        from .spec import tomllib

        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        # a date or time stays its text (date=2026-05-01), as the readers and the JSON summary take it
        out[key] = text.strip() if isinstance(value, _dt.date | _dt.time) else value
    return out


def _cmd_solve(args) -> int:
    from pathlib import Path

    from .batch import solve_recording
    from .spec import parse_spec, read_spec_text

    over = overrides(args, "solve")
    info_options = _info_options(args.info_option, bool(args.info))
    if not args.info and (args.clock_offset is not None or args.same_clock):
        opt = "--clock-offset" if args.clock_offset is not None else "--same-clock"
        raise InputError(f"{opt} relates the clock of an --info file to INPUT's, but no --info file is "
                         "given: add --info FILE or drop the option")
    summary = args.summary if args.summary is not None else str(Path(args.out).with_suffix(".json"))
    if args.summary is not None and Path(args.summary).suffix.lower() != ".json":
        raise InputError(f"--summary {args.summary!r}: the summary is JSON; end its name with .json")
    opt_summary = "--summary" if args.summary is not None else "--summary (default: --out with .json)"
    inputs = {"INPUT": args.input, "--spec": args.spec, **({"--truth": args.truth} if args.truth else {}),
              **{f"--info {p}": p for p in args.info}}
    _check(args, inputs,
           {"--out": args.out, opt_summary: summary, "--plot": args.plot, "--geodetic": args.geodetic,
            "--report": args.report},
           figures=("--plot",), tables=("--out", "--geodetic"))
    if args.report is not None and Path(args.report).suffix.lower() not in (".html", ".htm"):
        raise InputError(f"--report {args.report!r}: the report is one HTML file; end its name with .html")
    if args.summary is None:  # a path bvpnav chose: replace only a summary of its own
        from .io import check_implicit_outputs

        check_implicit_outputs({opt_summary: (summary, "summary")},
                               "move it away, or give --summary PATH to write the summary elsewhere (or to "
                               "replace that file)")
    truth_path, implicit = args.truth, False
    if truth_path is None and (args.plot or args.report) and Path(args.input).name == "recording.csv":
        beside = Path(args.input).with_name("truth.csv")  # what `bvpnav simulate` writes
        if beside.is_file():
            truth_path, implicit = beside, True
    if args.truth is not None and not Path(args.truth).is_file():
        raise InputError(f"--truth {args.truth!r}: no such file; give the CSV of true positions (t and one "
                         "column per axis, m), e.g. the truth.csv `bvpnav simulate` writes")
    spec_text = read_spec_text(args.spec)
    spec = parse_spec(spec_text, str(args.spec))
    _log.info("spec %s: %d item(s) (%s), error model %s", args.spec, len(spec.items),
              ", ".join(f"{it.label} {it.mode}" for it in spec.items) or "none",
              " + ".join(type(m).__name__ for m in spec.error_models) or "none")
    t0 = time.perf_counter()
    sol, row = solve_recording(args.input, spec, args.out, summary_path=summary, spec_text=spec_text,
                               information=args.info, clock_offset=args.clock_offset,
                               same_clock=args.same_clock, origin=args.origin, info_options=info_options,
                               **over)
    _log.info("solved in %.3g s (solver %s, %s); wrote %s and %s", time.perf_counter() - t0,
              row["solver"], row["status"], args.out, summary)
    _log.debug("solver options in force: %s", sol.stats.get("options"))
    if args.geodetic:
        _write_geodetic(sol, row.get("geodetic_origin"), args.geodetic, spec.input.get("frame", "enu"))
        _log.info("geodetic trajectory written to %s", args.geodetic)
    truth = read_truth(truth_path, sol, implicit=implicit) if truth_path is not None else None
    if truth is not None:
        _log.info("truth from %s", truth_path)
    if args.plot:
        from . import plot
        from .io import atomic_savefig

        fig = plot.solution(sol, items=row.get("items", spec.items), truth=truth)  # the files' items too
        atomic_savefig(fig, args.plot, "--plot", dpi=90)
        _log.info("figure written to %s", args.plot)
    if args.report:
        from .report import write_report

        write_report(sol, args.report, items=row.get("items", spec.items), truth=truth,
                     title=f"bvpnav report: {Path(args.input).name}")
        _log.info("report written to %s", args.report)
    _say(args, f"{row['samples']} samples; lam = {sol.lam:.6g} ({sol.lam_rule}); solver {row['solver']} "
               f"({row['status']}, verified); wrote {args.out}")
    for line in _align_lines(sol) + ([] if truth is None else [_truth_line(sol, truth, truth_path)]):
        _say(args, line)
    asked = over.get("uncertainty", spec.solve.get("uncertainty"))
    for line in _uncertainty_report(sol, args.out, asked):
        _say(args, line)
    for w in sol.warnings:
        _say(args, f"warning: {w}")
    return EXIT_OK


def _align_lines(sol) -> list[str]:
    """The printed line about the spec's ``[align]`` (none without it)."""
    rec = (sol.stats.get("data_checks") or {}).get("align")
    if not rec:
        return []
    src = {"fixes": "from the position fixes", "search": "0, searched by the solve"}.get(
        rec["heading_source"], "given")
    return [f"aligned at t[0]: roll {rec['roll_deg']:.4g} deg, pitch {rec['pitch_deg']:.4g} deg from the "
            f"rest {rec['rest'][0]:g} .. {rec['rest'][1]:g} s; yaw {rec['yaw_deg']:.4g} deg ({src})"]


def _truth_line(sol, truth, truth_path) -> str:
    """The printed RMS against the truth: over every axis, or horizontal for a 2-D truth of a
    3-axis solution (:func:`bvpnav.evaluate.ape`, no alignment: ``rms_horizontal``)."""
    import numpy as np

    if truth.shape[1] == len(sol._pos_cols):
        return f"RMS position error against the truth ({truth_path}): {sol.rms_error(truth):.4g} m"
    from .evaluate import Trajectory, ape

    pos = sol.position()
    res = ape(Trajectory(sol.t, pos[:, :2]), Trajectory(sol.t, truth[:, :2]), align="none", max_diff=0.0)
    return (f"horizontal RMS position error against the 2-D truth ({truth_path}: x, y only, so z is not "
            f"scored): {res.stats()['rms_horizontal']:.4g} m (sqrt of the mean of dx^2 + dy^2; "
            f"{np.ptp(sol.t):g} s, {len(sol.t)} samples)")


def _threshold_text(threshold) -> str:
    """A detector threshold in words: the number, or the range of an adaptive one."""
    import numpy as np

    thr = np.asarray(threshold, dtype=float)
    return f"{float(thr):.4g}" if thr.ndim == 0 else f"adaptive, {thr.min():.4g}..{thr.max():.4g}"


def _cmd_stationary(args) -> int:
    from . import detect
    from .readers import read
    from .spec import load_spec

    _check(args, {"INPUT": args.input, "--spec": args.spec}, {"--plot": args.plot, "--out": args.out},
           figures=("--plot",), tables=("--out",))
    spec = load_spec(args.spec)
    rec = read(args.input, spec.input)
    data = spec.imu_data(rec, rec.items_in(spec.input.get("frame", "enu")))
    opts = spec.stationary_options(data)
    if args.method is not None:
        opts["method"] = args.method
    found = detect.stationary(data, return_statistic=True, **opts)
    still = sum(b - a for a, b in found.intervals)
    span = data.t[-1] - data.t[0]
    _say(args, f"{len(found.intervals)} stationary interval(s), {still:.4g} s of {span:.4g} s "
               f"({found.method}, window {found.window} samples, "
               f"threshold {_threshold_text(found.threshold)})")
    for a, b in found.intervals[:20]:
        _say(args, f"  {a:.4f} .. {b:.4f} s")
    if len(found.intervals) > 20:
        _say(args, f"  ... {len(found.intervals) - 20} more" + (f" (all in {args.out})" if args.out else ""))
    if args.out:
        import pandas as pd

        from .io import write_table

        write_table(pd.DataFrame(found.intervals, columns=["t0", "t1"]), args.out, "--out")
    if args.plot:
        from . import plot
        from .io import atomic_savefig

        atomic_savefig(plot.stationary(data, found), args.plot, "--plot", dpi=90)
        _say(args, f"figure written to {args.plot}")
    return EXIT_OK


def _cmd_readers(args) -> int:
    import importlib.util

    from .readers import registry

    for r in registry().values():
        missing = [m for m in r.modules if importlib.util.find_spec(m) is None]
        state = f"needs pip install 'bvpnav[{r.extra}]'" if missing else "ready"
        _say(args, f"{r.name:<8} {', '.join(r.suffixes):<22} {state:<34} {r.description}")
    return EXIT_OK


def _cmd_evaluate(args) -> int:
    from . import evaluate as ev
    from .io import plain_json, write_json

    _check(args, {"TRAJ": args.trajectory, "--truth": args.truth}, {"--plot": args.plot, "--out": args.out},
           figures=("--plot",))
    if args.out is not None and not str(args.out).lower().endswith(".json"):
        raise InputError(f"--out {args.out!r}: the figures are written as JSON; give a .json path")
    res = ev.evaluate(args.trajectory, args.truth, align=args.align, rpe_delta=args.delta,
                      rpe_unit=args.delta_unit, all_pairs=args.all_pairs, max_diff=args.max_diff,
                      method=args.sync, offset=args.offset)
    for r in res.values():
        _say(args, ev.format_result(r))
    if args.out is not None:
        record = {k: {"stats": r.stats(), "settings": r.settings,
                      "alignment": {"method": r.alignment.method, "rotation": r.alignment.rotation,
                                    "translation": r.alignment.translation, "scale": r.alignment.scale}}
                  for k, r in res.items()}
        record |= {"estimate": str(args.trajectory), "reference": str(args.truth)}
        write_json(plain_json(record), args.out)
    if args.plot is not None:
        ev.plot(list(res.values()), args.plot)
    return 0


def _write_geodetic(sol, origin, path, frame: str) -> None:
    """Write t, lat, lon (degrees), height (m, WGS-84) of a 3-axis solution about ``origin``."""
    from .geodesy import trajectory_to_geodetic
    from .io import write_table

    if origin is None:
        raise InputError("--geodetic: the local frame's geodetic origin is not known (the recording and "
                         "the --info files hold no geodetic fixes); give it with --origin LAT LON HEIGHT "
                         "(degrees, degrees, m above the WGS-84 ellipsoid)")
    axes = tuple(sol._pos_cols)
    if len(axes) != 3:
        raise InputError(f"--geodetic: the solution has {len(axes)} axis/axes {list(axes)}; geodetic "
                         "coordinates need the three axes of the local frame (x, y, z)")
    df = sol.trajectory.reset_index()[["t", *axes]]
    geo = trajectory_to_geodetic(df, origin, frame=frame, axes=axes)
    write_table(geo[["t", "lat", "lon", "height"]], path, "--geodetic")


def default_rules(residual: str) -> tuple[str, ...]:
    """The rules ``bvpnav lcurve`` evaluates without ``--rules``.

    GCV treats the data residuals as independent observations. The acceleration form's are
    (``w_j / sigma_a``); the load form's ``M w`` are correlated by the mass matrix, and on
    the 2011 example (the README's ``lcurve`` line) GCV's function falls all the way to the
    edge of any range: it is left out of the load form's default (``--rules`` still runs it).
    """
    return ("lcurve", "gcv", "quasi") if residual == "acceleration" else ("lcurve", "quasi")


def _cmd_lcurve(args) -> int:
    from .io import atomic_savefig, write_table
    from .lam import rule_names
    from .solve import lambda_curve

    RULES = rule_names()

    rules = None
    if args.rules is not None:  # checked before any work
        rules = [r.strip() for r in args.rules.split(",")]
        if not any(rules) or not all(rules):
            k = next((i for i, r in enumerate(rules) if not r), 0)
            raise InputError(f"--rules {args.rules!r}: " + ("no rule named" if not any(rules) else
                             f"entry {k + 1} is empty") + f"; give one or more of {', '.join(RULES)} "
                             "separated by commas, e.g. --rules lcurve,gcv")
    _check(args, {"INPUT": args.input, "--spec": args.spec}, {"--plot": args.plot, "--out": args.out},
           figures=("--plot",), tables=("--out",))
    lam_range, points = _lam_range(args), _points(args)
    spec, prob = _load(args)
    if rules is None:
        rules = list(default_rules(prob.residual))
    kw = {} if lam_range is None else {"lam_range": lam_range}
    curve = lambda_curve(prob, rules=rules, rule=rules[0], points=points,
                         progress=False if verbosity(args) < 0 else None, **kw)
    _log.info("sweep: %d lambdas in %g .. %g, %d evaluations, %.3g s (%s engine)", len(curve.lam),
              curve.lam_range[0], curve.lam_range[1], curve.evaluations, curve.seconds, curve.engine)
    if args.plot:
        atomic_savefig(curve.plot(), args.plot, "--plot", dpi=110)
    if args.out:
        write_table(curve.to_frame(), args.out, "--out")
    for r, lam in curve.chosen.items():
        _say(args, f"{r:<12} lam = {lam:.6g}")
    for w in curve.warnings:
        _say(args, f"warning: {w}")
    return EXIT_OK


def _cmd_compare(args) -> int:
    from .compare import compare_solvers
    from .io import write_table

    for opt, text in (("--solvers", args.solvers), ("--presets", args.presets)):
        if text is not None and not all(x.strip() for x in text.split(",")):
            eg = "--solvers direct,clarabel" if opt == "--solvers" else "--presets low,default"
            raise InputError(f"{opt} {text!r}: an entry is empty; give names separated by commas, e.g. {eg}")
    _check(args, {"INPUT": args.input, "--spec": args.spec}, {"--out": args.out, "--plot": args.plot},
           figures=("--plot",), tables=("--out",))
    spec, prob = _load(args)
    solvers = [x.strip() for x in args.solvers.split(",")] if args.solvers else None
    over = {**spec.solve, **overrides(args, "compare")}
    table = compare_solvers(prob, solvers=solvers, presets=[x.strip() for x in args.presets.split(",")],
                            lam=over.get("lam", 1.0), time_limit=over.get("time_limit", COMPARE_TIME_LIMIT))
    if args.out:
        write_table(table, args.out, "--out")
    if args.plot:
        from . import plot
        from .io import atomic_savefig

        atomic_savefig(plot.comparison(table), args.plot, "--plot", dpi=90)
    cols = ["solver", "preset", "status", "verified", "wall_time", "forward_error", "max_violation"]
    shown = table[cols].assign(note=table["error"].fillna("").astype(str).str.slice(0, 90))
    _say(args, shown.to_string(index=False, float_format="{:.3g}".format))
    if not table["verified"].astype(bool).any():
        # a comparison in which nothing was verified has no answer to trust: a failed solve
        print(f"bvpnav: solve failed: none of the {len(table)} runs gave a verified answer (see the "
              "status column); try another solver or preset, or check the spec", file=sys.stderr)
        return EXIT_SOLVE
    return EXIT_OK


def _cmd_batch(args) -> int:
    from pathlib import Path

    from .batch import run_batch

    df = run_batch(args.directory, args.spec, args.out, scheduler=args.scheduler, workers=args.workers,
                   resume=args.resume, progress=verbosity(args) >= 0, suffix="." + args.format,
                   **overrides(args, "batch"))
    bad = df[~df.ok.astype(bool)]
    _say(args, f"{len(df)} recordings, {len(bad)} failed; summary: {Path(args.out) / 'summary.csv'}")
    for _, r in bad.iterrows():  # the full error (an internal error's traceback) is in summary.csv
        _say(args, f"  FAILED {r.recording}: {str(r.error).split(' | ')[0]}")
    return EXIT_OK if bad.empty else EXIT_SOLVE


def _wrap(text: str, indent: int) -> str:
    """``text`` wrapped at 88 columns, the lines after the first indented by ``indent``."""
    import textwrap

    return ("\n" + " " * indent).join(textwrap.wrap(text, 88 - indent))


#: What ``solve --help`` says about strapdown recordings (the spec's [input] and [align]).
STRAPDOWN_HELP = """\
Strapdown recordings (what an IMU measures in its own axes) are read when the spec's
[input] names the channels:
  specific_force = ["f_x", "f_y", "f_z"]  specific force in the sensor's axes (unit =
                                          "m/s^2", "g", ...); at rest +9.81 m/s^2 on the
                                          axis pointing up
  gyro = ["w_x", "w_y", "w_z"]            body rates, gyro_unit = "rad/s" or "deg/s"; the
                                          attitude is integrated from them
  attitude = { quaternion = [...], scalar = "first" }  or an orientation from the file
                                          (attitude_frame = "enu"/"ned": relative to what)
  frame = "enu"                           navigation frame: enu (x east, y north, z up) or
                                          ned (x north, y east, z down); gravity follows
  gravity, body_to_sensor, gyro_range     gravity magnitude or vector, the mounting
                                          rotation, the gyro's full-scale range (rad/s)
  initial_attitude = { euler = [...] }    the attitude at the first sample, when known
The attitude at the first sample can instead come from an interval at rest ([align]):
  [align]
  rest = [0.0, 4.5]        (s; or "first": the first interval the detector finds)
  heading = "fixes"        (from the position fixes; a yaw in degrees; or "search": the
                            solve searches it, with an attitude_error model)
bvpnav prints the aligned roll, pitch and yaw; `bvpnav stationary` shows the intervals at
rest. See docs/guide/readers.md and docs/guide/strapdown.md."""


def build_parser() -> argparse.ArgumentParser:
    from .samples import SAMPLES, WRITES

    parser = argparse.ArgumentParser(
        prog="bvpnav", description=DESCRIPTION, epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"bvpnav {__version__}")
    # -v/-q on every subcommand (after its name: bvpnav solve ... -v)
    talk = argparse.ArgumentParser(add_help=False)
    group = talk.add_argument_group("output")
    group.add_argument("-v", "--verbose", action="count", default=0,
                       help="say more on stderr: -v what bvpnav does (INFO), -vv solver details (DEBUG)")
    group.add_argument("-q", "--quiet", action="store_true", help="errors only: no report, warning or "
                       "progress bar")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    def add(name, **kw):
        return sub.add_parser(name, parents=[talk], **kw)

    demo = add(
        "demo", help="run a bundled scenario and compare methods",
        description="Run the 2011 paper's quintic scenario (biased, scaled, noisy accelerometer) "
                    "four ways -- trapezoid time-stepping, FEM with both ends fixed, FEM with "
                    "Tikhonov information (the 2011 paper), FEM with the four boundary values "
                    "(bvpnav's default) -- print RMS position errors and write a PNG.",
    )
    demo.add_argument("scenario", nargs="?", default="tikhonov2011", help="scenario name")
    demo.add_argument("--plot", default="bvpnav-demo.png", metavar="PNG",
                      help="figure path (default: %(default)s)")
    demo.add_argument("--seed", type=int, default=0, help="noise seed (default: %(default)s)")
    demo.set_defaults(func=_cmd_demo)

    def common(p, command: str | None = None):
        p.add_argument("input", metavar="INPUT", help="recording: .csv, .parquet, or any format of `bvpnav "
                       "readers` (its [input] format, or the suffix, picks the reader): navigation-frame "
                       "accelerations, or strapdown specific force with gyro rates or an orientation (see "
                       "`bvpnav solve --help`)")
        p.add_argument("--spec", required=True, metavar="SPEC", help="spec file (TOML)")
        if command is not None:
            declared_flags(p, command)

    sim = add(
        "simulate", help="write a synthetic recording and its spec",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=_wrap("Write DIR/recording.csv (the samples), DIR/spec.toml (the [input] that reads "
                          "them, what is known, error model, solver, lambda rule) and DIR/truth.csv (t and "
                          "the true positions per axis, m), so every command can be tried without data.", 0)
                    + "\n\nScenarios:\n"
                    + "\n".join(f"  {k:<14} {v.__doc__.strip().splitlines()[0]}\n{'':<17}writes "
                                 + _wrap(WRITES[k], 17) for k, v in SAMPLES.items()))
    sim.add_argument("scenario", choices=sorted(SAMPLES), metavar="SCENARIO", help=", ".join(sorted(SAMPLES)))
    sim.add_argument("--out", required=True, metavar="DIR", help="output folder (created)")
    sim.add_argument("--seed", type=int, default=0, help="noise seed (default: %(default)s)")
    sim.add_argument("--rate", type=float, default=None, help="sampling rate, Hz (scenario default)")
    sim.add_argument("--force", action="store_true", help="replace recording.csv, spec.toml, truth.csv "
                     "if DIR already holds them (default: refuse)")
    sim.set_defaults(func=_cmd_simulate)

    solve = add(
        "solve", help="solve one recording",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=_wrap("Solve a recording with a spec; write the trajectory (t, positions in m, "
                          "velocities in m/s; CSV or Parquet by OUT's suffix) and a JSON summary beside it "
                          "(lambda and rule, error-model estimates with units, solver statistics, item "
                          "residuals). With --uncertainty (or uncertainty = true in the spec's [solve]) also "
                          "their standard deviations. Outputs are written atomically; the input is never "
                          "modified.", 0) + "\n\n" + STRAPDOWN_HELP)
    common(solve, "solve")
    solve.add_argument("--out", required=True, metavar="OUT", help="trajectory file (.csv or .parquet)")
    solve.add_argument("--summary", metavar="JSON", help="summary path (default: OUT with .json)")
    solve.add_argument("--plot", metavar="PNG", help="also draw the solution (format from the suffix: "
                       ".png, .pdf, .svg ...): position and velocity per axis with the items where they "
                       "act, the residuals, the path for 2-3 axes, and the truth if known")
    solve.add_argument("--report", metavar="HTML", help="also write a quality report: one self-contained "
                       "HTML file (figures embedded) with the map view and uncertainty ellipses, position "
                       "and velocity with their bands, each item's normalized residuals and the worst ones, "
                       "the estimated sensor errors, attitude corrections, the solve's record and warnings")
    solve.add_argument("--truth", metavar="FILE", help="true positions (CSV or Parquet: t in s and one "
                       "column per axis in m, like the truth.csv `bvpnav simulate` writes; or t, x, y only, "
                       "a 2-D motion-capture truth of an x, y, z solution): drawn on --plot and --report "
                       "and the RMS error printed (the horizontal RMS for a 2-D truth). Default with --plot "
                       "or --report: truth.csv beside an INPUT named recording.csv, if there is one")
    solve.add_argument("--info", action="append", default=[], metavar="FILE",
                       help="a file of more information (e.g. an NMEA log: GNSS fixes as position items), "
                            "read by its suffix; repeat for several. Its clock is aligned explicitly: ISO "
                            "timestamps with a time zone by themselves, otherwise --clock-offset or "
                            "--same-clock")
    solve.add_argument("--info-option", action="append", default=[], metavar="KEY=VALUE",
                       help="a reader option for the --info files that take it (repeat for several), e.g. "
                            "speed_as=odometer (an NMEA log's speed over ground as an Odometer item), "
                            "velocity_sigma=0.1; VALUE is read as TOML (numbers, true, [0.5, 0, 1.2]) or "
                            "else as text")
    solve.add_argument("--clock-offset", type=float, metavar="SECONDS",
                       help="seconds to add to the --info files' times to put them on INPUT's clock")
    solve.add_argument("--geodetic", metavar="OUT", help="also write the trajectory in geodetic coordinates: "
                       "t, lat, lon (degrees), height (m above the WGS-84 ellipsoid), CSV or Parquet; needs "
                       "3 axes and a geodetic origin (from the GNSS fixes, or --origin)")
    solve.add_argument("--origin", nargs=3, type=float, metavar=("LAT", "LON", "HEIGHT"),
                       help="geodetic origin of the local frame (degrees, degrees, m): for --info fixes and "
                            "--geodetic (default: the first fix)")
    solve.add_argument("--same-clock", action="store_true",
                       help="the --info files and INPUT count time from one epoch (e.g. Unix nanoseconds): "
                            "shift by the difference of their origins")
    solve.set_defaults(func=_cmd_solve)

    lc = add(
        "lcurve", help="sweep lambda, print each rule's choice (and plot the L-curve)",
        description="Sweep lambda, evaluate the selection rules and print each rule's choice; with "
                    "--plot also draw the L-curve with each choice marked, with --out write the sweep.")
    common(lc)
    lc.add_argument("--plot", metavar="PNG", help="also draw the L-curve (format from the suffix)")
    lc.add_argument("--rules", default=None, help="rules, comma separated (default: lcurve,gcv,quasi "
                    "for the acceleration form, lcurve,quasi for the load form, where GCV's "
                    "independence assumption fails; discrepancy needs sigma_a)")
    lc.add_argument("--points", type=int, default=None, help="sweep size (default: the sweep of "
                    "'bvpnav solve' with lam = <the first rule>, which then chooses the same lambda)")
    lc.add_argument("--lam-range", nargs=2, metavar=("LO", "HI"), help="sweep lambda from LO to HI "
                    "(log-spaced; default 1e-6 1e6); widen it when a rule's choice is at the edge")
    lc.add_argument("--out", metavar="CSV", help="also write the sweep as a table")
    lc.set_defaults(func=_cmd_lcurve)

    cmp_ = add(
        "compare", help="solve one recording with several solvers",
        description="One problem, several solvers and presets: status, times, bvpnav's verification "
                    "and errors, one row each (failures are rows too). Exit code 3 if no row is "
                    "verified.")
    common(cmp_, "compare")
    cmp_.add_argument("--solvers", help="comma separated (default: clarabel, osqp and, for least "
                      "squares, direct and csne)")
    cmp_.add_argument("--presets", default="default", help="comma separated: low, default, high")
    cmp_.add_argument("--out", metavar="CSV", help="write the table")
    cmp_.add_argument("--plot", metavar="PNG", help="draw the table")
    cmp_.set_defaults(func=_cmd_compare)

    st = add(
        "stationary", help="find the stationary intervals of a strapdown recording",
        description="Detect where the IMU is at rest (SHOE or magnitude detector, the spec's "
                    "[stationary] options) and print the intervals; --plot draws the statistic with its "
                    "threshold and the signals with the intervals shaded, to check the threshold before "
                    "[stationary] adds them to a solve as ZeroVelocity items.")
    common(st)
    st.add_argument("--method", choices=("shoe", "magnitude"), help="override the spec's [stationary] method")
    st.add_argument("--plot", metavar="PNG", help="draw the detector's statistic and the intervals")
    st.add_argument("--out", metavar="CSV", help="write the intervals (t0, t1 in s)")
    st.set_defaults(func=_cmd_stationary)

    ev = add(
        "evaluate", help="score a trajectory against a reference (ATE / RPE)",
        description="Absolute trajectory error (APE) and, with --delta, relative error (RPE) of TRAJ "
                    "against --truth, computed as evo_ape / evo_rpe compute the translation part: pairs "
                    "in time within --max-diff, an alignment fitted first, then rmse, mean, median, std, "
                    "min and max (m) with the RMS per axis, horizontal and vertical. TRAJ and REF are "
                    "TUM files (t x y z qx qy qz qw) or tables with t, x, y[, z] (bvpnav solve's --out, "
                    "a truth.csv; a 2-D reference scores x and y only).")
    ev.add_argument("trajectory", metavar="TRAJ", help="the estimate: .tum/.txt (TUM) or .csv/.parquet")
    ev.add_argument("--truth", required=True, metavar="REF", help="the reference, same formats")
    ev.add_argument("--align", default="rigid", choices=("none", "translation", "yaw", "rigid", "similarity",
                    "scale"), help="fit before scoring: yaw = rotation about z and a translation (the rigid "
                    "2-D fit); rigid = SE(3); similarity = Sim(3); scale = scale only (default: %(default)s)")
    ev.add_argument("--max-diff", type=float, default=0.01, metavar="S", help="largest time difference of a "
                    "pair, s (default: %(default)s, as evo)")
    ev.add_argument("--sync", choices=("nearest", "interpolate"), default="nearest", help="pair the nearest "
                    "samples (as evo) or interpolate TRAJ at REF's times (default: %(default)s)")
    ev.add_argument("--offset", type=float, default=0.0, metavar="S", help="seconds added to TRAJ's times")
    ev.add_argument("--delta", type=float, metavar="D", help="also the RPE over pairs D apart")
    ev.add_argument("--delta-unit", choices=("m", "s", "frames"), default="m", help="D in metres of path, "
                    "seconds or samples (default: %(default)s)")
    ev.add_argument("--all-pairs", action="store_true", help="RPE over all pairs D apart, not consecutive")
    ev.add_argument("--plot", metavar="PNG", help="draw the map view and the errors over time")
    ev.add_argument("--out", metavar="JSON", help="write the figures (and the alignment) as JSON")
    ev.set_defaults(func=_cmd_evaluate)

    rd = add("readers", help="list the file formats bvpnav reads",
             description="Every reader: its name ([input] format), the suffixes it claims, whether its "
                         "optional dependencies are installed, and what it reads.")
    rd.set_defaults(func=_cmd_readers)

    bt = add(
        "batch", help="solve every recording in a folder (Dask)",
        description="Solve every *.csv/*.parquet in DIR with one spec on dask.distributed: an "
                    "in-process LocalCluster by default, or --scheduler ADDRESS for a cluster. A "
                    "failing recording becomes a row of OUT/summary.csv with its error; the others "
                    "go on. Exit code 3 if any failed. OUT must not be DIR; two recordings with one "
                    "name (a.csv, a.parquet) and a second run into the same OUT at the same time are "
                    "refused before any work.")
    bt.add_argument("directory", metavar="DIR", help="folder of recordings")
    bt.add_argument("--spec", required=True, metavar="SPEC", help="spec file (TOML)")
    bt.add_argument("--out", required=True, metavar="DIR", help="output folder")
    bt.add_argument("--scheduler", metavar="ADDRESS", help="dask scheduler, e.g. tcp://host:8786, or "
                    "'serial' to solve one by one in this process without Dask")
    bt.add_argument("--workers", type=int, default=2, help="local workers (default: %(default)s)")
    declared_flags(bt, "batch")
    bt.add_argument("--format", choices=("csv", "parquet"), default="csv", help="trajectory files")
    bt.add_argument("--resume", action="store_true", help="skip recordings already solved with the same "
                    "spec, options (--solver, --lam, --uncertainty, --format) and recording content "
                    "(their JSON summary's fingerprint); solve the "
                    "others again, saying why in summary.csv's resume column")
    bt.set_defaults(func=_cmd_batch)
    return parser


class _Terminated(BaseException):
    """Raised by the SIGTERM handler so that cleanup (temporary files) runs as for Ctrl-C."""


def _on_sigterm(signum, frame):
    raise _Terminated


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bvpnav`` command; returns the exit code.

    Every failure is one line on stderr: ``bvpnav: error: ...`` (exit 2), ``bvpnav: solve
    failed: ...`` (exit 3), ``bvpnav: interrupted`` (Ctrl-C, exit 130), ``bvpnav:
    terminated`` (SIGTERM, exit 143) or ``bvpnav: internal error: ...`` (exit 1; set
    ``BVPNAV_DEBUG=1`` to see the traceback).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return EXIT_INPUT
    with log.signal_handled(signal.SIGTERM, _on_sigterm):  # not on the main thread: SIGTERM left alone
        return _dispatch(args)


def _dispatch(args) -> int:
    debug = os.environ.get("BVPNAV_DEBUG", "") not in ("", "0")
    try:
        level = verbosity(args)
        with log.configured(level), warnings.catch_warnings():
            if level < 0:  # -q: errors only
                warnings.simplefilter("ignore")
            return int(args.func(args))
    except (InputError, SolverNotFound) as exc:  # a bad file, spec or argument
        print(f"bvpnav: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except SolveError as exc:
        print(f"bvpnav: solve failed: {exc}", file=sys.stderr)
        return EXIT_SOLVE
    except BvpnavError as exc:
        print(f"bvpnav: error: {exc}", file=sys.stderr)
        return EXIT_SOLVE
    except KeyboardInterrupt:  # the atomic writers have removed their temporary files
        print("bvpnav: interrupted", file=sys.stderr)
        return EXIT_INTERRUPT
    except _Terminated:
        print("bvpnav: terminated", file=sys.stderr)
        return EXIT_TERM
    except MemoryError:
        print("bvpnav: solve failed: out of memory; solve a shorter window (fewer samples), split the "
              "recording, or use a machine with more memory", file=sys.stderr)
        return EXIT_SOLVE
    except OSError as exc:  # writes are reported by the io layer; this is a read or a folder
        where = f" {exc.filename!r}" if exc.filename else ""
        print(f"bvpnav: error:{where} {exc.strerror or exc}; check the path and permissions", file=sys.stderr)
        return EXIT_INPUT
    except Exception as exc:
        if debug:
            import traceback

            traceback.print_exc()
        print(f"bvpnav: internal error: {type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''} "
              "(a bug in bvpnav, please report it; run again with BVPNAV_DEBUG=1 to see the traceback)",
              file=sys.stderr)
        return EXIT_BUG


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
