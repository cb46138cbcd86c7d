"""Shared fixtures: analytic trajectories used across the tests."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest


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


@pytest.fixture
def quintic_traj():
    return quintic()


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


def load_example(name: str):
    """Import ``examples/<name>.py`` afresh as module ``_example_<name>`` (registered in
    ``sys.modules`` so that dataclasses and inspect can find it)."""
    spec = importlib.util.spec_from_file_location(f"_example_{name}", EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod
