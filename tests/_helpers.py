"""Shared helpers of the test suite: analytic trajectories, example loading, reference
problems and independent reference solutions.

Every test module imports them the same way, ``from _helpers import ...``, whatever its
folder: ``tests/`` is on ``sys.path`` (``pythonpath = ["tests"]`` in pyproject.toml).
The hostile matrices' harness is the sibling module ``_hostile.py``.
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import bvpnav
from bvpnav.constraints import Position, Velocity
from bvpnav.scenarios import tikhonov2011


# ------------------------------------------------------------ a fresh interpreter
def run_python(code: str) -> dict:
    """Run ``code`` in a fresh interpreter (this test process may already have imported what a
    check looks for); it prints one JSON object as its last line, returned parsed."""
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


# ------------------------------------------------------------ analytic trajectories
def quintic():
    """The 2011 paper's reference trajectory p(t) on [0, 10] s and its derivatives."""
    A = np.array(
        [[t**k for k in range(6)] for t in (0.0, 5.0, 10.0)]
        + [[k * t ** (k - 1) if k else 0.0 for k in range(6)] for t in (0.0, 5.0, 10.0)]
    )
    p = np.polynomial.Polynomial(np.linalg.solve(A, [0.0, -10.0, 10.0, 0.0, 0.0, 0.0]))
    return p, p.deriv(), p.deriv(2)


def cubic_prior():
    """Cubic through p(0)=0, p'(0)=0, p(10)=10, p'(10)=0 (the 2011 paper's prior)."""
    B = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [1, 10, 100, 1000], [0, 1, 20, 300]], float)
    return np.polynomial.Polynomial(np.linalg.solve(B, [0.0, 0.0, 10.0, 0.0]))


def exact_piecewise_linear(t, acc, r0, v0):
    """Exact positions and velocities when acceleration is linear between samples."""
    t = np.asarray(t, float)
    acc = np.asarray(acc, float)
    h = np.diff(t)
    r = np.empty_like(acc)
    v = np.empty_like(acc)
    r[0], v[0] = r0, v0
    for j in range(len(h)):
        v[j + 1] = v[j] + h[j] * (acc[j] + acc[j + 1]) / 2.0
        r[j + 1] = r[j] + v[j] * h[j] + h[j] ** 2 * (2.0 * acc[j] + acc[j + 1]) / 6.0
    return r, v


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _load(module: str, path: Path):
    spec = importlib.util.spec_from_file_location(module, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def load_example(name: str):
    """Import ``examples/<name>.py`` afresh as module ``_example_<name>`` (registered in
    ``sys.modules`` so that dataclasses and inspect can find it)."""
    return _load(f"_example_{name}", EXAMPLES / f"{name}.py")


def load_benchmark_module(name: str):
    """Import ``examples/benchmarks/<name>.py`` (a module the benchmark scripts import as
    ``from <name> import ...``, e.g. ``_calibration``) afresh as module ``_benchmark_<name>``,
    registered in ``sys.modules`` like :func:`load_example`'s."""
    return _load(f"_benchmark_{name}", EXAMPLES / "benchmarks" / f"{name}.py")


# ------------------------------------------------------------ the 2011 paper's Table 1 problem
def table1_problem(n, residual="acceleration", seed=1, scale=0.05, bias=-0.5):
    """The 2011 paper's scenario: quintic, biased/scaled/noisy accelerometer, both ends
    fixed, the cubic prior as soft positions on the first and last N/50 samples."""
    p, v, a = quintic()
    t = np.linspace(0.0, 10.0, n)
    rng = np.random.default_rng(seed)
    acc = (1 + scale) * a(t) + rng.normal(bias, 1.0, n)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), residual=residual)
    k = max(n // 50, 1)
    tp = np.concatenate([t[:k], t[-k:]])
    prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0]),
             Position(t=tp, value=cubic_prior()(tp), sigma=1.0, name="prior"))
    return prob, p(t)


def kkt_reference(prob, lam, refinements=3):
    """An independent reference: the KKT system of the same problem, sparse LU plus
    iterative refinement (written here from the definitions, not from bvpnav.linalg.lsq)."""
    m = prob.model
    terms = prob.terms()
    E = bvpnav.Affine.vstack([m.fem_rows()] + [t.residual for t in terms if t.mode == "hard"])
    D = bvpnav.Affine.vstack([prob.data_rows()] + [t.residual * (np.sqrt(lam) / t.sigma)
                                                   for t in terms if t.mode == "soft"])
    H = (D.A.T @ D.A).tocsc()
    K = sp.bmat([[2 * H, E.A.T], [E.A, None]]).tocsc()
    rhs = np.concatenate([-2 * (D.A.T @ D.c), -E.c])
    lu = spla.splu(K)
    z = lu.solve(rhs)
    for _ in range(refinements):
        z += lu.solve(rhs - K @ z)
    return z[: m.size]


# ------------------------------------------------------------ lambda rules (tests/lam, tests/solve)
def table1(seed=0, scale=0.05, bias=-0.5):
    sc = tikhonov2011(scale=scale, bias=bias, seed=seed)
    t = sc.t
    tp = np.concatenate([t[:10], t[-10:]])
    prob = bvpnav.NavigationProblem(sc.data, residual="load").add(
        Position(t=[0.0, 10.0], value=[0.0, 10.0]),
        Position(t=tp, value=sc.prior(tp), sigma=1.0, name="prior"))
    return prob, sc


def known_noise(seed, n=1001, sa=0.3, sp=0.01):
    """Accelerometer noise sa and position noise sp stated correctly: lambda = 1 is the
    maximum-likelihood weight (2011 paper, Section 2.2)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 10.0, n)
    acc = -np.sin(t) + rng.normal(0, sa, n)
    z = np.sin(t) + rng.normal(0, sp, n)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=sa)
    prob.add(Position(t=t, value=z, sigma=sp))
    return prob, np.sin(t)


# ------------------------------------------------------------ conflicting information
def conflict_problem(*extra):
    """Ten seconds at rest with hard ends at 0 m and a hard zero velocity at 2 s, plus
    ``extra`` items: the base of the conflict tests (a hard item that contradicts it is
    named, or demoted)."""
    t = np.linspace(0.0, 10.0, 201)
    prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=np.zeros_like(t)))
    return prob.add(Position(t=[0.0, 10.0], value=[0.0, 0.0], name="ends"),
                    Velocity(t=2.0, value=0.0, name="v at 2 s"), *extra)


def hard_vehicle_rows_solve(data, pos, error_model, **nhc):
    """A noise-free drive's solve with hard ``NonHolonomic`` rows (at 2 Hz, options ``nhc``: the
    point's ``lever``, ``mounting=``/``slip="estimated"``) and fixes every 20th sample, the
    attitude loop to 1e-12 rad: the vehicle tests' exactness check at a point off the IMU."""
    from bvpnav.constraints import NonHolonomic

    k = np.arange(0, data.n, 20)
    prob = bvpnav.NavigationProblem(data, error_model=error_model, grade=None)
    prob.add(Position(t=data.t[k], value=pos[k], name="fixes"),
             NonHolonomic(mode="hard", rate=2.0, name="nhc", **nhc))
    sol = prob.solve(solver="direct", attitude={"tol": 1e-12})
    assert sol.stats["verified"]
    return sol
