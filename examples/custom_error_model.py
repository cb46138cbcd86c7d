"""A custom sensor error model in a few lines: a linearly drifting bias.

Subclass :class:`bvpnav.error_models.ErrorModel` and give ``names(data)`` and
``columns(data)``: the change of the navigation-frame acceleration (m/s^2) per unit of
each parameter. Everything else (composition with ``+``, the observability check,
priors and bounds, the ``error_params`` report) comes from the base class.

Here the accelerometer bias of each axis changes linearly in time (a warming
sensor): the sensor reads ``f + b + d (t - t0)``. ``BiasDrift`` is combined with the
built-in ``Bias() + UnknownGravity()`` and with ordinary items (end positions, a few
known velocities, and a soft Tikhonov-style velocity item) on simulated 3-D data.

Run ``python examples/custom_error_model.py`` or ``--small``.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np
import pandas as pd

import bvpnav
from bvpnav import simulate
from bvpnav.constraints import Position, Velocity
from bvpnav.error_models import Bias, ErrorModel, UnknownGravity, sensor_axes, sensor_frame


# --- the custom error model: everything it takes -------------------------------------
@dataclass(frozen=True, kw_only=True, eq=False)
class BiasDrift(ErrorModel):
    """Bias drift of each accelerometer axis, m/s^3: the sensor reads high by d (t - t0).

    Notes
    -----
    The correction :math:`a_c = \\hat a - C_i e_k d_k (t_i - t_0)` is linear in ``d``, so
    the column of ``d_k`` is :math:`-C_i e_k (t_i - t_0)` and the estimate is ``d`` itself.
    """

    units = "m/s^3"

    def names(self, data) -> list[str]:
        return [f"drift_{a}" for a in sensor_axes(data)]

    def columns(self, data) -> np.ndarray:
        C = sensor_frame(data)  # (N, d, 3): sensor axes in the navigation frame
        tau = data.t - data.t[0]
        return -C * tau[:, None, None]
# ---------------------------------------------------------------------------------------


def run(rate: float = 100.0, drift=(0.004, -0.003, 0.005), bias=(0.12, -0.15, 0.2),
        solver: str = "clarabel") -> dict:
    """Simulate a drifting bias and estimate it with the custom model.

    Returns
    -------
    dict
        ``params`` (DataFrame truth/estimate/error), ``pos_error`` (max, m).
    """
    sim = simulate.strapdown_3d_2010(rate=rate, accel=simulate.SensorErrors(bias=bias))
    tau = sim.t - sim.t[0]
    f = sim.specific_force + np.outer(tau, drift)  # add the drift the simulator lacks
    data = bvpnav.ImuData(sim.t, specific_force=f, attitude=sim.attitude, gravity=[0, 0, -9.80665])
    T = float(sim.t[-1])
    tv = np.linspace(0.0, T, 5)
    model = Bias() + UnknownGravity() + BiasDrift()
    prob = bvpnav.NavigationProblem(data, error_model=model)
    prob.add(Position(t=[0.0, T], value=sim.position([0.0, T])),
             Velocity(t=tv, value=sim.velocity(tv)),
             Velocity(t=[T / 4, 3 * T / 4], value=sim.velocity([T / 4, 3 * T / 4]), sigma=0.01))
    sol = prob.solve(solver=solver, accuracy="high")
    truth = pd.Series({**{f"bias_{a}": bias[k] for k, a in enumerate("xyz")},
                       **{f"gravity_{a}": sim.gravity[k] for k, a in enumerate("xyz")},
                       **{f"drift_{a}": drift[k] for k, a in enumerate("xyz")}})
    est = sol.error_params.reindex(truth.index)
    table = pd.DataFrame({"truth": truth, "estimate": est, "error": est - truth,
                          "units": [sol.error_params.attrs["units"][k] for k in truth.index]})
    pos = float(np.max(np.abs(sol.position() - sim.truth[["x", "y", "z"]].to_numpy())))
    return {"params": table, "pos_error": pos, "solution": sol}


def main(argv=None) -> dict:
    """Print and return :func:`run`'s results."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rate", type=float, default=100.0, help="sampling rate, Hz")
    ap.add_argument("--small", action="store_true", help="20 Hz (quick)")
    ap.add_argument("--solver", default="clarabel")
    args = ap.parse_args(argv)
    res = run(20.0 if args.small else args.rate, solver=args.solver)
    print("Custom error model BiasDrift + built-in Bias + UnknownGravity (noise-free data)")
    with pd.option_context("display.float_format", "{:.6g}".format):
        print(res["params"].to_string())
    print(f"  max position error: {res['pos_error']:.3g} m")
    return res


if __name__ == "__main__":
    main()
