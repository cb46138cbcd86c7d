"""Benchmark: calibration of ``solve(uncertainty=True)`` by Monte Carlo through the public API.

The truth is generated from the very model bvpnav estimates: nodal acceleration residuals
``w* ~ N(0, sigma_a^2)``, error-model parameters ``l*`` (fixed, or drawn from the prior the
problem states), the exact FEM recurrence
``r_{j+1} = r_j + h v_j + h^2 (2 a_j + a_{j+1}) / 6``, ``v_{j+1} = v_j + h (a_j + a_{j+1}) / 2``
with ``a = a_hat + G l* + w*``; soft item values are the truth plus N(0, sigma^2) noise, hard
values the truth. The error of the estimate is then exactly N(0, Cov), so the fraction of
errors within 1 and 2 reported standard deviations must be 0.683 and 0.954. The model and
the four configurations (N = 41 samples over 4 s, sigma_a = 0.02 m/s^2: 1-D with hard items
only, soft items only (with a bias prior), hard and soft items mixed (each with ``Bias()``),
and 3-D mixed with ``Bias() + ScaleFactor()``) are defined once, in the sibling module
``_calibration.py``, which ``tests/test_uncertainty_calibration.py`` uses too. Every
realisation is one ``solve(solver="direct", lam=1, uncertainty=True)``.

Columns of the table:

- ``config``: the configuration;
- ``quantity``: ``position`` / ``velocity`` (all axes and samples pooled, except samples a
  hard item fixes exactly, where the std is ~0), or one error-model parameter by name;
- ``count``: number of (realisation, sample, axis) errors pooled (the number of
  realisations for a parameter);
- ``within 1 sigma`` / ``within 2 sigma``: fraction of errors with ``|error| <= k std``,
  and in brackets its standard error from the spread of the per-realisation fractions
  (realisations are independent; samples along one trajectory are not);
- ``target``: 0.683 +/- 0.03 and 0.954 +/- 0.015 (the issue's acceptance);
- ``ok``: both fractions within the target;
- ``variance factor``: mean a-posteriori variance factor over the realisations (1 expected;
  in brackets its standard error ``sqrt(2 / (dof R))``) and the degrees of freedom.

Run ``python examples/benchmarks/uncertainty_calibration.py [--runs 2000] [--jobs 2]``;
it writes ``examples/benchmarks/uncertainty_calibration.md``. With the defaults (8000 solves
of 60-250 ms each) that is roughly 20 CPU-minutes, so about 10 minutes with ``--jobs 2`` on
an idle 2-core machine (an estimate from the per-solve times); the saved table took 1328 s
of wall time on a shared 2-core machine under a load of about 6.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from _calibration import configs, hard_nodes, reported, simulate, solve_public

import bvpnav as bv

P1, P2 = 0.6826894921370859, 0.9544997361036416
TOL1, TOL2 = 0.03, 0.015
CHUNK = 50


def chunk(job: tuple[int, int, int, int]) -> dict:
    """Solve one chunk of realisations; per quantity the per-realisation counts within
    1 and 2 sigma and the number of samples, and the variance factors."""
    ci, k, runs, seed = job
    cfg = list(configs().values())[ci]
    tr = simulate(cfg, np.random.default_rng([seed, ci, k]), runs)
    params, _ = reported(cfg, tr.l)
    out: dict = {"vf": [], "dof": None}
    masks = {"position": ~hard_nodes(cfg, "position"), "velocity": ~hard_nodes(cfg, "velocity")}
    for j in range(runs):
        sol = solve_public(cfg, [v[j] for v in tr.values])
        trj = sol.trajectory
        for kind, cols, true in (("position", list(cfg.axes), tr.r[j]),
                                 ("velocity", [f"v{a}" for a in cfg.axes], tr.v[j])):
            err = (trj[cols].to_numpy() - true)[masks[kind]]
            z = np.abs(err) / trj[[f"{c}_std" for c in cols]].to_numpy()[masks[kind]]
            out.setdefault(kind, []).append((np.sum(z <= 1), np.sum(z <= 2), z.size))
        z = np.abs(sol.error_params.to_numpy(dtype=float) - params[j]) / sol.error_params_std.to_numpy()
        for name, zi in zip(sol.error_params.index, z, strict=True):
            out.setdefault(name, []).append((int(zi <= 1), int(zi <= 2), 1))
        out["vf"].append(sol.stats["uncertainty"]["variance_factor"])
        out["dof"] = sol.stats["uncertainty"]["dof"]
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=2000, help="realisations per configuration")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes")
    ap.add_argument("--seed", type=int, default=20261202)
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "uncertainty_calibration.md"))
    args = ap.parse_args(argv)
    cfgs = list(configs().values())
    jobs = [(ci, k, min(CHUNK, args.runs - k * CHUNK), args.seed)
            for ci in range(len(cfgs)) for k in range(-(-args.runs // CHUNK))]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.jobs) as ex:
        results = list(ex.map(chunk, jobs))
    wall = time.perf_counter() - t0
    head = ("| config | quantity | count | within 1 sigma | within 2 sigma | target | ok | "
            "variance factor |\n|---|---|---:|---:|---:|---|---|---|")
    lines = [head]
    for ci, cfg in enumerate(cfgs):
        res = [r for (c, *_), r in zip(jobs, results, strict=True) if c == ci]
        vf = np.concatenate([r["vf"] for r in res])
        dof = res[0]["dof"]
        vtxt = f"{vf.mean():.4f} ({np.sqrt(2.0 / (dof * vf.size)):.4f}), dof {dof}"
        names = [k for k in res[0] if k not in ("vf", "dof")]
        for name in names:
            c = np.array([row for r in res for row in r[name]], dtype=float)  # (R, 3)
            f1, f2 = c[:, 0].sum() / c[:, 2].sum(), c[:, 1].sum() / c[:, 2].sum()
            se1 = (c[:, 0] / c[:, 2]).std(ddof=1) / np.sqrt(len(c))
            se2 = (c[:, 1] / c[:, 2]).std(ddof=1) / np.sqrt(len(c))
            ok = abs(f1 - P1) <= TOL1 and abs(f2 - P2) <= TOL2
            lines.append(f"| {cfg.name} | {name} | {int(c[:, 2].sum())} | {f1:.4f} ({se1:.4f}) | "
                         f"{f2:.4f} ({se2:.4f}) | {P1:.3f}+/-{TOL1}, {P2:.3f}+/-{TOL2} | "
                         f"{'yes' if ok else 'NO'} | {vtxt} |")
    table = "\n".join(lines)
    print(table)
    print(f"\n{args.runs} realisations per configuration, wall time {wall:.0f} s with {args.jobs} jobs")
    cmd = "python examples/benchmarks/uncertainty_calibration.py " + " ".join(argv if argv is not None
                                                                              else sys.argv[1:])
    with open(args.out, "w") as fh:
        fh.write("# Calibration of `solve(uncertainty=True)`: Monte Carlo through the public API\n\n")
        fh.write(f"Produced by `{cmd.strip()}` (bvpnav {bv.__version__}, Python "
                 f"{platform.python_version()}, {os.cpu_count()} CPUs): {args.runs} realisations per "
                 f"configuration, seed {args.seed}, wall time {wall:.0f} s with {args.jobs} jobs. See the "
                 "script's docstring for the configurations and what each column is; standard errors "
                 "in brackets.\n\n")
        fh.write(table + "\n")


if __name__ == "__main__":
    main()
