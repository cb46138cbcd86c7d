"""Synthetic recordings with their specs, for trying the command line without data.

Each sample writes ``recording.csv``, ``spec.toml`` and ``truth.csv`` (true positions, m)
into a folder. The recording is navigation-frame acceleration (``t`` in s, ``acc_<axis>``
in m/s^2) or, for the strapdown samples, what an IMU measures in its own axes (specific
force ``f_x, f_y, f_z`` in m/s^2, gyro rates ``w_x, w_y, w_z`` in rad/s, or an
orientation as quaternion columns), with the spec's ``[input]`` saying so.
"""

from __future__ import annotations

import os
from pathlib import Path

from .errors import InputError

# numpy, pandas and the problem's classes are imported by the functions that use them:
# the command line's parser reads SAMPLES (names and one-line descriptions) for --help,
# which must not pay for them

__all__ = ["SAMPLES", "write_sample"]


def _clean(values) -> list[float]:
    """Computed values at 15 significant digits (``0.00047872``, not the polynomial's
    ``0.00047871999999999997``): the spec is written with each float's shortest round-trip
    text, so the problem solved and the one in the spec are the same problem."""
    import numpy as np

    return [float(f"{v:.15g}") for v in np.asarray(values, dtype=float).ravel()]


def _tikhonov2011(seed: int, rate: float | None):
    """The 2011 paper's Example 1 (quintic, biased and scaled, unit noise; cubic prior)."""
    import numpy as np

    from .constraints import Position
    from .imu import ImuData
    from .problem import NavigationProblem
    from .scenarios import tikhonov2011

    sc = tikhonov2011(rate=rate or 50.0, seed=seed)
    t = sc.t
    tp = np.concatenate([t[1:11], t[-11:-1]])
    prob = NavigationProblem(ImuData(t=t, acc=sc.data.acc), residual="load")
    prob.add(Position(t=[0.0, 10.0], value=[0.0, 10.0], name="ends"),
             Position(t=tp, value=_clean(sc.prior(tp)), sigma=1.0, name="cubic prior"))
    solve = {"solver": "direct", "accuracy": "default", "lam": "lcurve"}
    return _nav_sample(t, sc.data.acc, sc.position[:, None], prob, solve)


def _shuttle(seed: int, rate: float | None):
    """A shuttle run out 10 m and back in 20 s: symmetry, stopwatch, bias model."""
    import numpy as np

    from .constraints import AverageVelocity, Position, Symmetry, Velocity
    from .error_models import Bias
    from .imu import ImuData
    from .problem import NavigationProblem
    from .scenarios import quintic_trajectory

    p, _, a = quintic_trajectory()
    rate = rate or 50.0
    t = np.linspace(0.0, 20.0, int(round(20 * rate)) + 1)
    mirror = np.where(t <= 10.0, t, 20.0 - t)
    rng = np.random.default_rng(seed)
    acc = (1.02 * a(mirror) + rng.normal(0.3, 1.0, t.size))[:, None]
    prob = NavigationProblem(ImuData(t=t, acc=acc), sigma_a=1.0, error_model=Bias())
    prob.add(Position(t=[0.0, 20.0], value=[0.0, 0.0], name="ends"),
             Velocity(t=[0.0, 20.0], value=[0.0, 0.0], name="at rest"),
             Symmetry(about=10.0, sigma=0.01, name="mirror"),
             AverageVelocity(t0=[0.0, 10.0], t1=[10.0, 20.0], value=[1.0, -1.0], name="stopwatch"))
    solve = {"solver": "direct", "accuracy": "default", "lam": 1.0}
    return _nav_sample(t, acc, p(mirror)[:, None], prob, solve)


def _nav_sample(t, acc, truth, prob, solve) -> dict:
    """The parts of a navigation-frame sample: recording, truth, spec (problem, solve, input)."""
    import pandas as pd

    axes = prob.data.axes
    return {"recording": pd.DataFrame({"t": t, **{f"acc_{ax}": acc[:, k] for k, ax in enumerate(axes)}}),
            "truth": pd.DataFrame({"t": t, **{ax: truth[:, k] for k, ax in enumerate(axes)}}),
            "problem": prob, "solve": solve,
            "input": {"time": "t", "time_unit": "s", "columns": {ax: f"acc_{ax}" for ax in axes},
                      "unit": "m/s^2"}}


def _strapdown_frame(t, f, w=None, quat=None) -> dict:
    """Columns of a strapdown recording: t, specific force, gyro rates and/or quaternion (w first)."""
    import pandas as pd

    cols = {"t": t, **{f"f_{a}": f[:, k] for k, a in enumerate("xyz")}}
    if w is not None:
        cols.update({f"w_{a}": w[:, k] for k, a in enumerate("xyz")})
    if quat is not None:  # scipy is scalar-last; the file is scalar-first, as the spec states
        cols.update({f"q{a}": quat[:, k] for a, k in zip("wxyz", (3, 0, 1, 2), strict=True)})
    return pd.DataFrame(cols)


def _walking(seed: int, rate: float | None):
    """A foot-mounted IMU walking 10 strides (strapdown: specific force + gyro; stance detected)."""
    import numpy as np
    import pandas as pd

    from .constraints import Position
    from .imu import ImuData
    from .problem import NavigationProblem
    from .scenarios import walking

    sc = walking(rate=rate or 100.0, n_strides=10, seed=seed)
    d = sc.data
    q0 = _clean(d.attitude[0].as_quat())
    q0 = _clean(np.asarray(q0) / np.linalg.norm(q0))
    init = {"quaternion": q0, "scalar": "last"}
    prob = NavigationProblem(ImuData(t=d.t, acc=d.acc, axes=("x", "y", "z")))
    prob.add(Position(t=[0.0], value=_clean(sc.position[0]), name="start"))
    t = d.t
    return {"recording": _strapdown_frame(t, d.specific_force, w=d.gyro),
            "truth": pd.DataFrame({"t": t, **{a: sc.position[:, k] for k, a in enumerate("xyz")}}),
            "problem": prob, "solve": {"solver": "direct", "accuracy": "default", "lam": 1.0},
            "input": {"time": "t", "time_unit": "s", "specific_force": ["f_x", "f_y", "f_z"],
                      "gyro": ["w_x", "w_y", "w_z"], "gyro_unit": "rad/s", "unit": "m/s^2", "frame": "enu",
                      "initial_attitude": init},
            "stationary": {"method": "shoe", "name": "stance"}}


def _strapdown3d(seed: int, rate: float | None):
    """The 2010 paper's 3-D strapdown motion: body-frame IMU and orientation, nine-parameter model."""
    import pandas as pd

    from .constraints import Position, Velocity
    from .error_models import Bias, ScaleFactor, UnknownGravity
    from .imu import ImuData
    from .problem import NavigationProblem
    from .simulate import strapdown_3d_2010

    sim = strapdown_3d_2010(rate=rate or 100.0, noise=0.02, seed=seed)
    t = sim.t
    data = sim.imu_data(gravity=[0.0, 0.0, -9.80665])
    prob = NavigationProblem(ImuData(t=t, specific_force=sim.specific_force, attitude=sim.attitude),
                             error_model=ScaleFactor() + Bias() + UnknownGravity(), sigma_a=0.02)
    pos = sim.position(t)
    ends = [_clean(pos[0]), _clean(pos[-1])]
    tv = [float(t[0]), float(t[-1]) / 2.0, float(t[-1])]
    prob.add(Position(t=[t[0], t[-1]], value=ends, name="ends"),
             Velocity(t=tv, value=[_clean(v) for v in sim.velocity(tv)], name="velocities"))
    return {"recording": _strapdown_frame(t, sim.specific_force, quat=data.attitude.as_quat()),
            "truth": pd.DataFrame({"t": t, **{a: pos[:, k] for k, a in enumerate("xyz")}}),
            "problem": prob, "solve": {"solver": "direct", "accuracy": "default", "lam": 1.0},
            "input": {"time": "t", "time_unit": "s", "specific_force": ["f_x", "f_y", "f_z"], "unit": "m/s^2",
                      "attitude": {"quaternion": ["qw", "qx", "qy", "qz"], "scalar": "first"},
                      "attitude_frame": "enu", "frame": "enu"}}


#: Sample scenarios by name.
SAMPLES = {"tikhonov2011": _tikhonov2011, "shuttle": _shuttle, "walking": _walking,
           "strapdown3d": _strapdown3d}
#: What each sample writes: the recording's columns and what its spec holds (``bvpnav simulate
#: --help``).
WRITES = {
    "tikhonov2011": "recording.csv: t (s), acc_x (m/s^2, navigation frame, 1 axis); spec: the two end "
                    "positions (hard) and a cubic prior (soft, load form), lam = \"lcurve\"",
    "shuttle": "recording.csv: t, acc_x (m/s^2, navigation frame); spec: end positions and velocities, "
               "symmetry about 10 s, two stopwatch average velocities, a bias model",
    "walking": "recording.csv: t, f_x f_y f_z (specific force, m/s^2, sensor axes), w_x w_y w_z (gyro, "
               "rad/s); spec: [input] specific_force, gyro, frame = \"enu\", initial_attitude (the true "
               "start), [stationary] (SHOE: a zero-velocity item per stance), the start position",
    "strapdown3d": "recording.csv: t, f_x f_y f_z (specific force, m/s^2, body axes), qw qx qy qz (the "
                   "orientation, body to ENU, scalar first); spec: [input] specific_force, attitude, "
                   "attitude_frame; end positions, three velocities, scale factor + bias + unknown gravity",
}
#: Duration of each sample's recording, s.
DURATIONS = {"tikhonov2011": 10.0, "shuttle": 20.0, "walking": 12.65, "strapdown3d": 20.0}
#: Fewest samples a sample recording may have (its items need samples near both ends).
MIN_SAMPLES = 41
#: Most samples a sample recording may have (a CSV of about 50 MB).
MAX_SAMPLES = 1_000_000


def check_seed(seed, option: str = "--seed") -> int:
    """``seed`` as an int, or InputError naming ``option``: a noise seed is an integer >= 0."""
    import numbers

    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise InputError(f"{option} {seed!r}: a noise seed is an integer >= 0 (e.g. {option} 0)")
    return int(seed)


def write_sample(name: str, out, seed: int = 0, rate: float | None = None, force: bool = False) -> list[Path]:
    """Write a sample scenario's recording, spec and truth into folder ``out``.

    Parameters
    ----------
    name : str
        A key of :data:`SAMPLES`.
    out : path-like
        Folder (created if missing).
    seed : int
        Noise seed (>= 0).
    rate : float, optional
        Sampling rate, Hz (scenario default if None); the recording must have between
        :data:`MIN_SAMPLES` and :data:`MAX_SAMPLES` samples (its duration is
        :data:`DURATIONS`).
    force : bool
        Replace ``recording.csv``, ``spec.toml`` and ``truth.csv`` if they already exist in
        ``out``; without it an existing one is refused (nothing is written).

    Returns
    -------
    list of Path
        ``recording.csv``, ``spec.toml``, ``truth.csv``.

    Raises
    ------
    InputError
        Unknown scenario, bad seed or rate (naming the rates allowed), existing files
        without ``force``, or an output that cannot be written (see :func:`bvpnav.io.check_outputs`).
    """
    import numpy as np

    from .io import atomic_write_text, check_outputs, write_table
    from .spec import dumps_spec, problem_to_spec

    if name not in SAMPLES:
        raise InputError(f"unknown scenario {name!r}; choose one of {sorted(SAMPLES)}")
    if rate is not None and not (np.isfinite(rate) and rate > 0):
        raise InputError(f"--rate {rate!r}: give a positive sampling rate in Hz")
    seed = check_seed(seed)
    if rate is not None:
        dur = DURATIONS[name]
        n = int(round(dur * rate)) + 1 if dur * rate < 1e18 else float("inf")
        lo, hi = (MIN_SAMPLES - 1) / dur, (MAX_SAMPLES - 1) / dur
        if n < MIN_SAMPLES:
            raise InputError(f"--rate {rate:g}: the {dur:g} s scenario {name!r} would have {n} samples; it "
                             f"needs at least {MIN_SAMPLES}: give --rate {lo:g} Hz or more")
        if n > MAX_SAMPLES:
            raise InputError(f"--rate {rate:g}: the {dur:g} s scenario {name!r} would have {n:.3g} samples, "
                             f"more than the {MAX_SAMPLES:,} a sample recording may have: give --rate "
                             f"{hi:g} Hz or less")
    out = Path(out)
    paths = [out / "recording.csv", out / "spec.toml", out / "truth.csv"]
    existing = [p.name for p in paths if os.path.lexists(p)]
    if existing and not force:
        raise InputError(f"--out {str(out)!r} already holds {', '.join(existing)}: simulate does not replace "
                         "files it did not write in this run; give --out a new or empty folder, or add "
                         "--force to replace them")
    check_outputs({}, {f"--out ({p.name})": p for p in paths})
    part = SAMPLES[name](seed, rate)
    out.mkdir(parents=True, exist_ok=True)
    spec = problem_to_spec(part["problem"], solve=part["solve"], input=part["input"])
    spec.stationary = dict(part.get("stationary", {}))
    write_table(part["recording"], paths[0])
    header = (f"# bvpnav sample scenario {name!r} (seed {seed}): "
              f"{SAMPLES[name].__doc__.strip().splitlines()[0]}\n")
    atomic_write_text(paths[1], header + dumps_spec(spec))
    write_table(part["truth"], paths[2])
    return paths
