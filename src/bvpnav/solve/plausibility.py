"""Diagnostics that say the model does not fit: the misfit against the stated noise, and
estimates no sensor can have.

A solve can succeed, pass verification and have a well-conditioned error model, and
still be wrong: the error model may be missing what really corrupts the data (a drifting
bias, an attitude error), so the other parameters absorb it and take absurd values (an
accelerometer bias of 9.98 m/s^2 next to a vertical gravity of +0.17 m/s^2, a
misalignment of -2.88 rad). The singular-value test
(:mod:`bvpnav.solve.conditioning`) cannot see this: the absurd answer may be very well
determined. Two kinds of check run after every solve, whatever that test says
(:func:`check`; the pipeline adds each message to ``solution.warnings``, issues it once
as a :class:`bvpnav.log.BvpnavWarning` and records the numbers in
``solution.stats["plausibility"]``):

1. **Misfit** (acceleration form with a stated ``sigma_a`` only): the acceleration
   residual's RMS against the stated noise, per axis and overall, and the a-posteriori
   variance factor (the weighted residual sum of squares over its degrees of freedom).
2. **Plausibility** of every error-model estimate in ``solution.error_params``, found
   through the error model's components (the model class decides the check, the
   component's own parameter names select the values): accelerometer bias, gravity,
   scale factors, misalignments, the attitude correction, gyro bias and gyro scale,
   odometer scale; and the installation and timing (found by the role the items look the
   component up by): the fixes' delay, the GNSS lever arm, the no-slip point and the
   mounting, each against its physical limit and, with a stated prior, against that.

Every threshold is a module constant, documented where it is defined.
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from ..formulation import Formulation
from ..imu import STANDARD_GRAVITY
from ..linalg.lsq import non_least_squares_term
from ..log import warn
from ..result import Solution

__all__ = ["check", "assess", "attach", "MISFIT_HIGH", "MISFIT_LOW", "MISFIT_MIN_DOF", "ACC_BIAS_LIMIT",
           "GRAVITY_MAGNITUDE_LIMIT", "GRAVITY_TILT_LIMIT", "SCALE_LIMIT", "MISALIGNMENT_LIMIT",
           "TILT_LIMIT", "GYRO_BIAS_LIMIT", "GYRO_MEAN_FRACTION", "GYRO_TURNING", "GYRO_TURN_RATE",
           "GYRO_PRIOR_SIGMAS", "GYRO_SCALE_LIMIT", "GYRO_STANCE_ERRORS"]

# ------------------------------------------------------------------ thresholds
#: Misfit: warn when the acceleration residual's RMS, ``rms(w / sigma_a)``, on an axis or
#: overall, or the square root of the variance factor exceeds this. With the stated noise
#: right and the model complete, the minimizing residual is at most the noise itself (it
#: is the projection of the noise onto what the items see, or smaller with soft items),
#: so ``rms(w / sigma_a)^2`` is at most about a chi-square variable over its N degrees of
#: freedom: above ``3^2 = 9`` with probability below ``chi2.sf(9 N, N)``, 1e-12 already for
#: N = 10. Likewise ``sigma_0^2 > 9`` with at least :data:`MISFIT_MIN_DOF` degrees of
#: freedom has probability below 5e-15. A factor 3 is a model that does not fit, not bad
#: luck; the uncertainty stage's 1 % test (``solve(uncertainty=True)``) is the fine one.
MISFIT_HIGH = 3.0

#: Misfit: warn when the square root of the variance factor is below this (with at least
#: :data:`MISFIT_MIN_DOF` degrees of freedom): ``chi2.cdf(0.04 f, f)`` is below 2e-8 for
#: f = 10, so the stated sigmas are too large (by about ``1 / sqrt(variance factor)``).
#: The residual's own RMS is *not* used for this side: with sparse information (fixes
#: every few seconds) the minimizing residual sees only a small part of the noise and
#: ``rms(w / sigma_a)`` is far below 1 for correctly stated noise.
MISFIT_LOW = 0.2

#: Fewest degrees of freedom (redundant rows: objective rows minus unknowns plus hard
#: rows) for a verdict from the variance factor.
MISFIT_MIN_DOF = 10

#: Accelerometer bias limit, m/s^2: 0.1 g = 0.98 m/s^2 (100 mg). The consumer-MEMS
#: bias sigma of the sensor grades (:mod:`bvpnav.sensors`) is 0.05 m/s^2 and even an
#: uncalibrated low-cost part stays within a few tens of mg; a larger estimate is gravity
#: leaking into the axis (a tilt error ``theta`` puts ``g sin(theta)`` on it: 0.1 g is
#: 5.7 degrees) or a unit mistake, not a bias.
ACC_BIAS_LIMIT = 0.1 * STANDARD_GRAVITY

#: Gravity magnitude limit, m/s^2: ``| |g| - |g_nominal| |`` above 0.5. Gravity on the
#: Earth's surface ranges over 9.78..9.83 m/s^2 and falls by 3e-3 m/s^2 per km of height,
#: so 0.5 m/s^2 is ten times every real difference from the nominal value.
GRAVITY_MAGNITUDE_LIMIT = 0.5

#: Gravity direction limit, rad: the estimated gravity vector tilted from the nominal by
#: more than 0.1 rad (5.7 degrees, a horizontal component of 0.98 m/s^2, the bias limit).
#: The deflection of the vertical is below 1e-4 rad; horizontal gravity components only
#: absorb an initial tilt error, which is 0.02 rad for consumer sensors.
GRAVITY_TILT_LIMIT = 0.1

#: Accelerometer scale-factor limit (dimensionless): ``|s| > 0.2`` (20 %). MEMS scale
#: errors are below about 3 % (navigation grade 1e-4); beyond 20 % the factor absorbs an
#: acceleration proportional to the signal (gravity on a tilted axis, a unit mistake).
SCALE_LIMIT = 0.2

#: Odometer scale-factor limit (dimensionless): ``|k| > 0.2`` (20 %). A worn or soft tyre
#: changes the rolling radius by a few percent; beyond 20 % the speeds are in other units or
#: along another axis (:class:`~bvpnav.error_models.OdometerScale`).
ODOMETER_SCALE_LIMIT = 0.2

#: Misalignment limit, rad: ``|Theta_ij| > 0.05`` (2.9 degrees). Triads are orthogonal to
#: a few mrad; a rotation of the whole triad shows as antisymmetric misalignment pairs, so
#: a larger value is an attitude error.
MISALIGNMENT_LIMIT = 0.05

#: Attitude tilt-correction limit, rad: the tilt angle ``hypot(attitude_x, attitude_y)`` above 0.2
#: (11.5 degrees). Initial tilt sigmas are 0.001..0.02 rad (sensor grades), and the
#: small-angle error of a 0.2 rad correction is already 2 %: a larger one says that the
#: given attitude is wrong (frames, axes), not slightly off. The heading ``attitude_z`` is
#: free (unknown heading is the normal case): no limit.
TILT_LIMIT = 0.2

#: Gyro bias absolute limit, rad/s: ``|b| > 0.05`` (2.9 deg/s), ten times the consumer
#: gyro bias sigma of the sensor grades (5e-3 rad/s).
GYRO_BIAS_LIMIT = 0.05

#: Gyro bias against the motion: warn when the (time-averaged) gyro bias removes more than
#: this fraction of the axis's mean measured rate, ``|b| > 0.5 |mean(omega_hat)|``, while
#: the axis really turns (see :data:`GYRO_TURNING`, :data:`GYRO_TURN_RATE`): the model may
#: have explained real turning as bias (heading and the vertical gyro bias slide together
#: when heading is weakly observed).
GYRO_MEAN_FRACTION = 0.5

#: "The axis really turns": its RMS measured rate is more than this times its mean ...
GYRO_TURNING = 3.0

#: ... and above this rate, rad/s (3 deg/s: motion, not gyro noise, which is about 1e-3
#: rad/s per sample for consumer gyros at 100 Hz).
GYRO_TURN_RATE = 0.05

#: A gyro bias within this many prior sigmas of its prior (``GyroBias(sigma=...)``) is
#: what the user's own datasheet allows: no warning against the mean rate then.
GYRO_PRIOR_SIGMAS = 3.0

#: A gyro bias within this many standard errors of the bias the still intervals state
#: (``ZeroAngularRate`` items: the body does not turn there, so the gyro reads its bias) is
#: what the stances show: no warning against the whole recording's mean rate then; beyond,
#: a warning. The stated bias is the mean of the readings weighted by the items' own
#: ``1 / sigma^2`` (per sample and axis, e.g. ``angular_rate="spread"``), its standard error
#: ``sqrt(1 / sum(1 / sigma^2))``, scaled up when the intervals scatter more than that
#: (see :func:`_stance_rates`), floored at 1e-6 rad/s. Under the items' noise the
#: difference to the solve's estimate has at most that standard error (the estimate uses
#: the same rows and more), so 3 of them are exceeded with probability below 0.3 %.
GYRO_STANCE_ERRORS = 3.0

#: Gyro scale-factor limit (dimensionless): ``|s| > 0.1``. MEMS gyro scale errors are
#: below about 1 %.
GYRO_SCALE_LIMIT = 0.1

_NAME = re.compile(r"^(?P<base>.+)_(?P<axis>[^_\[\]]+)(\[(?P<k>\d+)\])?$")

#: Class names of the error models, by what they estimate (subclasses match through
#: their MRO; the gyro and attitude models are found by name so this module needs none).
_KINDS = {"Bias": "acc_bias", "ScaleFactor": "scale", "Misalignment": "misalignment",
          "UnknownGravity": "gravity", "GyroBias": "gyro_bias", "AttitudeError": "attitude",
          "GyroScaleFactor": "gyro_scale"}


def _kind(component) -> str | None:
    """What a component estimates: its declared ``plausibility_kind`` (one of the values of
    :data:`_KINDS`), else found by class name (plug-ins written before the declaration)."""
    declared = getattr(type(component), "plausibility_kind", None)
    if isinstance(declared, str):
        return declared
    for cls in type(component).__mro__:
        if cls.__name__ in _KINDS:
            return _KINDS[cls.__name__]
    return None


def _axis(name: str) -> str:
    m = _NAME.match(name)
    return m.group("axis") if m else name


def _fmt(v: float, unit: str = "") -> str:
    s = f"{v:+.3g}"
    return f"{s} {unit}" if unit else s


# ---------------------------------------------------------------- the misfit
def _variance_factor(sol: Solution, form: Formulation) -> tuple[float, int, dict[str, float]] | None:
    """Weighted residual sum of squares over its degrees of freedom, with each group's
    share of it; None when the problem is not equality-constrained least squares."""
    if non_least_squares_term(form) is not None:
        return None
    model = form.model
    x = np.asarray(sol.x, dtype=float)
    w = sol.residuals.to_numpy(dtype=float)
    data = float(np.sum((w / form.sigma_a_used) ** 2))
    parts = {"acceleration residual": data}
    rows, hard = form.data_rows().m, model.fem_rows().m   # a coarse mesh's: fewer rows, fewer unknowns
    for term in form.terms():
        role = term.least_squares_role()
        if role == "D":
            r = term.residual.value(x) / np.asarray(term.sigma, dtype=float)
            parts[term.label] = parts.get(term.label, 0.0) + float(term.weight(sol.lam) * (r @ r))
            rows += term.residual.m
        elif role == "E":
            hard += term.residual.m
    dof = int(rows - model.size + hard)  # redundant hard rows counted as independent
    rss = float(sum(parts.values()))
    return (rss / dof if dof > 0 else float("nan")), dof, parts


def _misfit(sol: Solution, form: Formulation) -> tuple[dict[str, Any], list[str]]:
    axes = list(form.model.axes)
    sa = np.asarray(form.sigma_a_used, dtype=float)
    names = [f"w_{ax}" for ax in axes]
    res = sol.residuals
    # the columns in their order (a solution's own table) without a selected copy of the table
    w = (res if list(res.columns) == names else res[names]).to_numpy(dtype=float)
    per = np.sqrt(np.mean((w / sa) ** 2, axis=0))
    overall = float(np.sqrt(np.mean(per**2)))
    out: dict[str, Any] = {"residual_ratio": {ax: float(r) for ax, r in zip(axes, per, strict=True)},
                           "residual_ratio_overall": overall, "variance_factor": None, "dof": None}
    vf = _variance_factor(sol, form) if sol.lam_rule == "fixed" else None
    noise = None
    shares = ""
    if vf is not None:
        out["variance_factor"], out["dof"] = float(vf[0]), int(vf[1])
        if vf[1] >= MISFIT_MIN_DOF and np.isfinite(vf[0]):
            noise = float(np.sqrt(max(vf[0], 0.0)))
            total = sum(vf[2].values())
            if total > 0:
                top = sorted(vf[2].items(), key=lambda kv: -kv[1])[:3]
                shares = ", ".join(f"{k} {100 * v / total:.0f} %" for k, v in top)
    out["noise_ratio"] = noise
    if sa.ndim == 2 and not np.all(sa == sa.flat[0]):
        sig = f"{sa.min():g}..{sa.max():g} m/s^2 (per sample, median {np.median(sa):g})"
    else:
        sa = sa.reshape(-1, len(axes))[0]
        sig = (f"{sa[0]:g} m/s^2" if np.all(sa == sa[0])
               else ", ".join(f"{ax} {s:g}" for ax, s in zip(axes, sa, strict=True)) + " m/s^2")
    lam = f"; lam = {sol.lam:g} weighs each item as if its sigma were sigma/sqrt(lam)" if sol.lam != 1 else ""
    causes = ("likely causes: an unmodelled drifting bias (try Bias(interval=...) or GyroBias(...)), a "
              "wrong attitude (try AttitudeError() + GyroBias()), or a sigma_a far too small (from the "
              "datasheet: bvpnav.sensors.grade(...).sigma_a(rate_hz))")
    msgs = []
    bad = [ax for ax, r in zip(axes, per, strict=True) if r > MISFIT_HIGH]
    vf_txt = "" if noise is None else (f"; the a-posteriori variance factor is {out['variance_factor']:.3g} "
                                       f"({out['dof']} degrees of freedom; {shares})")
    if bad or overall > MISFIT_HIGH:
        shown = bad or axes
        worst = max(per[axes.index(ax)] for ax in shown)
        each = ", ".join(f"{ax} {per[axes.index(ax)]:.2g}" for ax in axes)
        msgs.append(
            f"misfit: the acceleration residual is {worst:.2g} x the stated sigma_a = {sig} on "
            f"ax{'is' if len(shown) == 1 else 'es'} {', '.join(shown)} (RMS of w / sigma_a: {each}; "
            f"overall {overall:.2g}){vf_txt}. Noise of the stated size cannot need a correction "
            f"more than {MISFIT_HIGH:g} x itself (the minimizing residual is at most the noise), so "
            f"the model does not fit the data: {causes}; or hard items noisier than exact (give "
            f"them sigma=){lam}")
    elif noise is not None and noise > MISFIT_HIGH:
        msgs.append(
            f"misfit: the weighted residuals are {noise:.2g} x what the stated sigmas predict "
            f"(a-posteriori variance factor {out['variance_factor']:.3g} with {out['dof']} degrees "
            f"of freedom; {shares or 'no residual'}; sigma_a = {sig}): the noise is larger "
            f"than sigma_a and the items' sigma say, or the model does not fit: {causes}; or "
            f"items whose sigma is too small{lam}")
    elif noise is not None and noise < MISFIT_LOW:
        by = (f"by about a factor {1 / noise:.2g}" if noise > 0
              else "the residuals are zero (noise-free data?)")
        msgs.append(
            f"misfit: the weighted residuals are only {noise:.2g} x what the stated sigmas "
            f"predict (a-posteriori variance factor {out['variance_factor']:.3g} with "
            f"{out['dof']} degrees of freedom{'; ' + shares if shares else ''}): sigma_a = {sig} (or "
            f"the items' sigma) is probably overstated, {by}; the stated "
            f"sigmas set the balance between the accelerometer and the items, so state the "
            f"datasheet's noise (bvpnav.sensors.grade(...).sigma_a(rate_hz)){lam}")
    return out, msgs


# -------------------------------------------------------------- plausibility
def _groups(sol: Solution, form: Formulation) -> dict[str, list[tuple[Any, list[str]]]]:
    """Error-model components by kind, each with its parameter names in ``error_params``."""
    em = form.error_model
    out: dict[str, list] = {}
    if em is None or not len(sol.error_params):
        return out
    for c in getattr(em, "components", (em,)):
        kind = _kind(c)
        if kind is None:
            continue
        try:
            names = [n for n in c.names(form.data) if n in sol.error_params.index]
        except Exception:  # noqa: BLE001 - a component that cannot name its parameters is skipped
            continue
        if names:
            out.setdefault(kind, []).append((c, names))
    return out


def _values(sol: Solution, names: list[str]) -> np.ndarray:
    return sol.error_params[names].to_numpy(dtype=float)


def _worst_by_axis(sol: Solution, names: list[str]) -> dict[str, tuple[str, float]]:
    """Per axis the parameter (knot) of largest finite magnitude."""
    out: dict[str, tuple[str, float]] = {}
    for n, v in zip(names, _values(sol, names), strict=True):
        if not np.isfinite(v):
            continue
        ax = _axis(n)
        if ax not in out or abs(v) > abs(out[ax][1]):
            out[ax] = (n, float(v))
    return out


def _knots(name: str, count: int) -> str:
    return f" (the largest of {count} knots)" if count > 1 and "[" in name else ""


def _gravity(sol: Solution, form: Formulation, groups) -> tuple[list[str], list[tuple[str, float]]]:
    """Problems with the gravity estimate, and its components."""
    from ..error_models._base import _nominal_gravity

    g0 = _nominal_gravity(form.data)
    n0 = float(np.linalg.norm(g0))
    if "gravity" not in groups or n0 == 0.0:  # navigation-frame data: a constant offset, no nominal
        return [], []
    axes = list(form.data.axes)
    g = np.array(g0, dtype=float)
    comps = []
    for _, names in groups["gravity"]:
        for n, v in zip(names, _values(sol, names), strict=True):
            ax = _axis(n)
            if ax in axes and np.isfinite(v):
                g[axes.index(ax)] = v
                comps.append((n, float(v)))
    if not comps:
        return [], []
    mag = float(np.linalg.norm(g))
    tilt = float(np.arccos(np.clip(g @ g0 / (mag * n0), -1.0, 1.0))) if mag > 0 else float(np.pi)
    why = []
    if abs(mag - n0) > GRAVITY_MAGNITUDE_LIMIT:
        why.append(f"|g| = {mag:.4g} m/s^2 against the nominal {n0:.6g} "
                   f"(limit +-{GRAVITY_MAGNITUDE_LIMIT:g})")
    if tilt > GRAVITY_TILT_LIMIT:
        why.append(f"tilted {tilt:.3g} rad ({np.degrees(tilt):.3g} deg) from the nominal direction "
                   f"(limit {GRAVITY_TILT_LIMIT:g} rad)")
    return why, comps


def _gravity_text(form: Formulation, comps: list[tuple[str, float]]) -> str:
    """The gravity components that differ from the nominal by more than 0.05 m/s^2 (the
    largest difference when none does)."""
    from ..error_models._base import _nominal_gravity

    if not comps:
        return ""
    g0 = dict(zip(form.data.axes, _nominal_gravity(form.data), strict=True))
    dev = [(n, v, abs(v - g0.get(_axis(n), 0.0))) for n, v in comps]
    shown = [c for c in dev if c[2] > 0.05] or [max(dev, key=lambda c: c[2])]
    return ", ".join(f"{n} = {_fmt(v, 'm/s^2')} (nominal {_fmt(g0.get(_axis(n), 0.0))})" for n, v, _ in shown)


def _acc_checks(sol: Solution, form: Formulation, groups) -> list[str]:
    """Accelerometer bias, gravity (and their confusion), scale and misalignment."""
    msgs: list[str] = []
    g_why, g_comps = _gravity(sol, form, groups)
    gtxt = _gravity_text(form, g_comps)
    # parameters of a sensor axis the conditioning check already calls degenerate (their
    # values are meaningless and named there): not judged again
    cond = (getattr(sol, "stats", None) or {}).get("conditioning") or {}
    named = {n for dg in cond.get("degenerate_axes", []) for n in dg.get("parameters", [])}

    # accelerometer bias (and its confusion with gravity)
    bad_bias = []
    for _, names in groups.get("acc_bias", []):
        for ax, (n, v) in _worst_by_axis(sol, [n for n in names if n not in named]).items():
            if abs(v) > ACC_BIAS_LIMIT:
                bad_bias.append((ax, n, v, _knots(n, len(names))))
    if bad_bias and g_why:
        btxt = ", ".join(f"{n} = {_fmt(v, 'm/s^2')}{k}" for _, n, v, k in bad_bias)
        msgs.append(
            f"implausible estimates: gravity and bias cannot be told apart here: {btxt} with {gtxt} "
            f"({'; '.join(g_why)}; bias limit {ACC_BIAS_LIMIT:.3g} m/s^2 = 0.1 g). While the "
            "attitude changes little, a body-axis bias and the navigation-frame gravity move the "
            "acceleration alike, and together they trade gravity for bias; drop UnknownGravity() "
            "(the nominal gravity is good to 0.05 m/s^2) or give it a prior (UnknownGravity(sigma=0.05)) "
            "and give Bias a datasheet sigma (bvpnav.sensors), and model the attitude error "
            "(AttitudeError() + GyroBias()) that the pair was absorbing")
    else:
        for _ax, n, v, k in bad_bias:
            tilt = np.degrees(np.arcsin(min(1.0, abs(v) / STANDARD_GRAVITY)))
            msgs.append(
                f"implausible estimate: {n} = {_fmt(v, 'm/s^2')}{k} is {abs(v) / STANDARD_GRAVITY:.2g} g, "
                f"beyond the limit {ACC_BIAS_LIMIT:.3g} m/s^2 (0.1 g) of any accelerometer bias: it is "
                f"gravity leaking into the axis (an attitude error of {tilt:.3g} deg would put it there) "
                "or a unit mistake; check the attitude and the frames (ENU z up by default, NED with "
                "frame='NED'), model the attitude error (AttitudeError() + GyroBias()), or give Bias a "
                "datasheet sigma (bvpnav.sensors)")
        if g_why:
            msgs.append(
                f"implausible estimate: gravity {gtxt}: {'; '.join(g_why)}. The gravity estimate has "
                "absorbed something else: an attitude error (try AttitudeError() + GyroBias()), a "
                "scale error of the vertical axis, or the units; give UnknownGravity a prior "
                "(sigma=0.05) or drop it")

    for _, names in groups.get("scale", []):
        for n, v in _worst_by_axis(sol, [n for n in names if n not in named]).values():
            if abs(v) > SCALE_LIMIT:
                msgs.append(
                    f"implausible estimate: {n} = {_fmt(v)} ({100 * v:+.3g} %) is beyond the limit "
                    f"+-{SCALE_LIMIT:g} of an accelerometer's scale error: it absorbs an acceleration "
                    "proportional to the signal (gravity on a tilted axis: model the attitude error "
                    "with AttitudeError() + GyroBias(); or the data are in other units); give "
                    "ScaleFactor a prior (sigma=0.01) or drop it")

    bad = []
    for _, names in groups.get("misalignment", []):
        bad += [(n, float(v)) for n, v in zip(names, _values(sol, names), strict=True)
                if np.isfinite(v) and abs(v) > MISALIGNMENT_LIMIT and n not in named]
    if bad:
        txt = ", ".join(f"{n} = {_fmt(v, 'rad')} ({np.degrees(v):+.3g} deg)" for n, v in bad)
        msgs.append(
            f"implausible estimate{'s' if len(bad) > 1 else ''}: {txt} beyond the limit "
            f"{MISALIGNMENT_LIMIT:g} rad of a sensor triad's non-orthogonality"
            + (" (beyond any small angle: meaningless values)" if any(abs(v) > 1 for _, v in bad) else "")
            + ": misalignment pairs absorb a rotation of the whole triad, i.e. an attitude error; "
            "model it with AttitudeError() + GyroBias(), or give Misalignment a prior (sigma=0.005)")
    return msgs


def _attitude_checks(sol: Solution, groups) -> list[str]:
    """The initial tilt correction: the angle of ``(attitude_x, attitude_y)``."""
    msgs = []
    for _, names in groups.get("attitude", []):
        tilt = {n: float(v) for n, v in zip(names, _values(sol, names), strict=True)
                if _axis(n) != "z" and np.isfinite(v)}  # the heading attitude_z is free
        angle = float(np.sqrt(sum(v * v for v in tilt.values())))
        if angle > TILT_LIMIT:
            txt = ", ".join(f"{n} = {_fmt(v, 'rad')} ({np.degrees(v):+.3g} deg)" for n, v in tilt.items())
            msgs.append(
                f"implausible estimate: {txt} correct the initial tilt by {angle:.3g} rad "
                f"({np.degrees(angle):.3g} deg), beyond the limit {TILT_LIMIT:g} rad: the given initial "
                "attitude is wrong rather than slightly off (a frame or axis mix-up: ENU/NED, body "
                "axes); align roll and pitch from a stationary interval, or check the frames")
    return msgs


def _mean_bias(c, sol: Solution, data, ax: str, vals: list[tuple[str, float]]) -> float:
    """Time average of a gyro bias on one axis, rad/s: from the model's own per-sample bias
    (``GyroBias.bias``) when it has one, else the mean of its values."""
    per_sample = getattr(c, "bias", None)
    if callable(per_sample):
        try:
            return float(np.mean(np.asarray(per_sample(sol, data), dtype=float)[:, "xyz".index(ax)]))
        except Exception:  # noqa: BLE001 - fall back to the values
            pass
    return float(np.mean([v for _, v in vals]))


def _stance_weights(it, k: int) -> np.ndarray | None:
    """An item's per-row weights ``1 / sigma^2`` (rad/s)^-2 as ``(k, axes)``; None for hard rows.
    A band's half-width ``tol`` stands for its sigma (the rows allow that much)."""
    a = 3 if it.axes is None else len(it.axes)
    try:
        sig = it.weight_rows(k * a) if it.sigma is not None else it.tol_rows(k * a)
    except Exception:  # noqa: BLE001 - the item's own compile names a bad sigma; weigh it equally here
        sig = None
    if sig is None:
        return None
    return 1.0 / np.square(np.asarray(sig, dtype=float).reshape(k, a))


def _stance_rates(items, data) -> dict[str, tuple[float, float, int]] | None:
    r"""Per body axis, the bias the still intervals state, its standard error (rad/s) and the
    number of intervals; None without such intervals or gyro rates.

    The intervals are those of the items that say the body does not turn (``zero_rate =
    True``: ``ZeroAngularRate``). Each of their rows states ``omega_hat_i = b + e_i`` with
    ``e_i`` of the row's sigma, so the bias they state is the weighted mean
    ``m = sum(w_i omega_hat_i) / sum(w_i)``, ``w_i = 1 / sigma_i^2``, with the standard
    error ``sqrt(1 / sum(w_i))``; when the intervals' own weighted means scatter more than
    that allows (a foot rolls differently in each stance), the error is scaled by the
    Birge ratio ``sqrt(chi2 / (K - 1))`` of the K interval means about ``m``
    (``chi2 = sum_k W_k (m_k - m)^2``, ``W_k`` an interval's summed weight). Hard rows
    outweigh any soft row: with hard items only those count, with equal weights, and the
    error is the scatter alone. Floored at 1e-6 rad/s.
    """
    gyro = getattr(data, "gyro", None)
    if gyro is None:
        return None
    w = np.asarray(gyro, dtype=float)
    t = np.asarray(data.t, dtype=float)
    hard: dict[str, list[tuple[float, float]]] = {}
    soft: dict[str, list[tuple[float, float]]] = {}
    for it in items:
        if not getattr(type(it), "zero_rate", False):
            continue
        t0, t1 = it.t
        tol = 1e-9 * max(1.0, abs(t0), abs(t1))
        sel = (t >= t0 - tol) & (t <= t1 + tol)
        k = int(sel.sum())
        if not k:
            continue
        weights = _stance_weights(it, k)
        for j, ax in enumerate(it.axes or ("x", "y", "z")):
            rate = w[sel, "xyz".index(ax)]
            if weights is None:  # (interval mean, its weight: the count of its rows)
                hard.setdefault(ax, []).append((float(rate.mean()), float(k)))
            else:
                wk = weights[:, j]
                soft.setdefault(ax, []).append((float(wk @ rate / wk.sum()), float(wk.sum())))
    out = {}
    for ax in set(hard) | set(soft):
        stated = ax not in hard
        m_k, w_k = np.array(hard.get(ax) or soft[ax]).T
        mean = float(w_k @ m_k / w_k.sum())
        se = float(np.sqrt(1.0 / w_k.sum())) if stated else 0.0
        if m_k.size > 1:
            chi2 = float(w_k @ (m_k - mean) ** 2)
            scatter = np.sqrt(chi2 / (m_k.size - 1) / w_k.sum())  # Birge-scaled error of the mean
            se = max(se, float(scatter) if stated else float(np.std(m_k) / np.sqrt(m_k.size)))
        out[ax] = (mean, max(se, 1e-6), int(m_k.size))
    return out or None


def _gyro_checks(sol: Solution, groups, data, items=()) -> list[str]:
    """Gyro bias (absolute, against the stances and against the mean measured rate) and gyro
    scale."""
    msgs: list[str] = []
    gyro = getattr(data, "gyro", None)
    stances = _stance_rates(items, data)
    dur = float(data.t[-1] - data.t[0]) if data.n > 1 else 0.0
    for c, names in groups.get("gyro_bias", []):
        by_axis: dict[str, list[tuple[str, float]]] = {}
        for n, v in zip(names, _values(sol, names), strict=True):
            if np.isfinite(v):
                by_axis.setdefault(_axis(n), []).append((n, float(v)))
        sig = getattr(c, "sigma", None)
        prior = getattr(c, "prior", None)
        for ax, vals in by_axis.items():
            n, v = max(vals, key=lambda nv: abs(nv[1]))
            k = _knots(n, len(vals))
            if abs(v) > GYRO_BIAS_LIMIT:
                msgs.append(
                    f"implausible estimate: {n} = {_fmt(v, 'rad/s')} ({np.degrees(v):+.3g} deg/s){k} is "
                    f"beyond the limit {GYRO_BIAS_LIMIT:g} rad/s of a gyro bias: the attitude "
                    "parameters absorb something else (a wrong initial attitude or heading, gyro data "
                    "in deg/s or in other axes); give GyroBias a datasheet sigma (bvpnav.sensors)")
                continue
            if gyro is None or ax not in ("x", "y", "z"):
                continue
            rate = np.asarray(gyro, dtype=float)[:, "xyz".index(ax)]
            mean, rms = float(np.mean(rate)), float(np.sqrt(np.mean(rate**2)))
            b = _mean_bias(c, sol, data, ax, vals)
            if stances is not None and ax in stances:
                m_s, se, k_s = stances[ax]
                if abs(b - m_s) <= GYRO_STANCE_ERRORS * se:
                    continue  # the bias is what the stances read: not turning mistaken for bias
                msgs.append(
                    f"implausible estimate: gyro bias on axis {ax} {_fmt(b, 'rad/s')} differs from the "
                    f"bias the {k_s} still interval(s) state (ZeroAngularRate: their gyro readings "
                    f"weighted by 1/sigma^2) "
                    f"{_fmt(m_s, 'rad/s')} by {_fmt(b - m_s, 'rad/s')}, more than "
                    f"{GYRO_STANCE_ERRORS:g} standard errors ({_fmt(se, 'rad/s')}): where the body does "
                    "not turn the gyro reads its bias, so the estimate has absorbed something else (a "
                    "heading or attitude error, stances that are not still); check the stances and "
                    "the ZeroAngularRate sigma")
                continue
            if sig is not None:
                s = float(np.max(np.asarray(sig, dtype=float)))
                p0 = 0.0 if prior is None else float(np.mean(np.asarray(prior, dtype=float)))
                if abs(b - p0) <= GYRO_PRIOR_SIGMAS * s:
                    continue
            if (abs(b) > GYRO_MEAN_FRACTION * abs(mean) and rms > GYRO_TURNING * abs(mean)
                    and rms > GYRO_TURN_RATE):
                frac = abs(b / mean) if mean != 0 else float("inf")
                msgs.append(
                    f"implausible estimate: gyro bias on axis {ax} {_fmt(b, 'rad/s')} (mean of {len(vals)} "
                    f"value{'s' if len(vals) > 1 else ''}) removes {100 * frac:.3g} % of the axis's mean "
                    f"measured rate {_fmt(mean, 'rad/s')} (a net {np.degrees(mean * dur):+.4g} deg over "
                    f"{dur:.4g} s; limit {100 * GYRO_MEAN_FRACTION:g} %) while the axis turns at "
                    f"{rms:.3g} rad/s RMS: the model may have explained real turning as bias (heading "
                    "and the gyro bias slide together when the heading is weakly observed); give "
                    "GyroBias a datasheet sigma (bvpnav.sensors) and check the heading against the "
                    "fixes")

    for _, names in groups.get("gyro_scale", []):
        for n, v in _worst_by_axis(sol, names).values():
            if abs(v) > GYRO_SCALE_LIMIT:
                msgs.append(
                    f"implausible estimate: {n} = {_fmt(v)} ({100 * v:+.3g} %) is beyond the limit "
                    f"+-{GYRO_SCALE_LIMIT:g} of a gyro's scale error: it absorbs a rate proportional to "
                    "the turning (a wrong heading or initial attitude, gyro data in other units); give "
                    "GyroScaleFactor a prior or drop it")
    return msgs


def _odometer_checks(sol: Solution, groups) -> list[str]:
    msgs = []
    for _, names in groups.get("odometer_scale", []):
        for n, v in zip(names, _values(sol, names), strict=True):
            if not abs(v) <= ODOMETER_SCALE_LIMIT:
                msgs.append(
                    f"implausible estimate: {n} = {_fmt(v)} ({100 * v:+.3g} %) is beyond the limit "
                    f"+-{ODOMETER_SCALE_LIMIT:g} of an odometer's scale error: the speeds are in other "
                    "units (km/h, knots, wheel revolutions), measured along another axis than the "
                    "Odometer item's axis= (or signed the other way), or the fixes do not fix the "
                    "distance travelled; check the speeds' units and axis, or give OdometerScale a prior "
                    "(sigma=0.05)")
    return msgs


# ------------------------------------------------- installation and timing (issue 39)
#: Fix delay limits, s: a ``time_offset`` (:class:`~bvpnav.error_models.TimeOffset`, the fixes
#: of ``Position/Velocity(delay="estimated")``; positive: the fixes stamped late) above
#: +0.5 or below -0.1. A positive delay is the receiver's latency chain: the position
#: solution (tens of ms), its output (a GGA sentence over a 9600 baud serial line: 80 ms; a
#: whole NMEA burst up to a few hundred ms when it is stamped on arrival at its end) and the
#: logger's own buffering (USB, the operating system: tens of ms); the sum stays below 0.5 s.
#: A negative delay says that the IMU's samples are stamped late instead: the IMU's own
#: latency (its digital low-pass filter's group delay, a few ms; the transport and
#: batching of its samples, tens of ms), below 0.1 s. Beyond either the fixes and the
#: samples are not on one clock (GPS time against UTC differs by 18 s, time zones, two
#: devices' clocks, a fix assigned to the wrong epoch), or the delay absorbs an along-track
#: error of the rest of the model. The limits count from zero and from the stated prior
#: (``TimeOffset(prior=...)``: a known clock offset): only beyond both is it warned.
TIME_OFFSET_LATE_LIMIT = 0.5

#: See :data:`TIME_OFFSET_LATE_LIMIT`: the negative side (the IMU's stamps late), s.
TIME_OFFSET_EARLY_LIMIT = 0.1

#: GNSS lever-arm limit, m: the antenna more than 5 m from the IMU
#: (:class:`~bvpnav.error_models.LeverArm`, the length of ``(lever_x, lever_y, lever_z)``).
#: A car is about 4.5 x 1.8 x 1.5 m, so an antenna on it and an IMU in it are at most its
#: diagonal, 5 m, apart; on a walker both are within 2 m. A larger lever arm puts the antenna
#: off the vehicle: it absorbs something else (``C(t) l`` turns with the attitude, so a
#: heading error does it). On a bus, a ship or an aircraft state the measured lever arm as
#: the prior (``LeverArm(prior=..., sigma=...)``): the limit is then counted from it too,
#: and only beyond 5 m from both zero and the prior is it warned.
LEVER_ARM_LIMIT = 5.0

#: No-slip point limit, m: the point where the vehicle does not slide sideways more than
#: 5 m from the IMU (:class:`~bvpnav.error_models.NhcLever`, the length of
#: ``(nhc_lever_x, nhc_lever_y, nhc_lever_z)``). The point is the middle of a car's rear axle,
#: and an IMU anywhere in a 4.5 m car is within 5 m of it; a point farther away is off the
#: car, so the rows absorb something else. Counted from zero and from the stated prior, as
#: :data:`LEVER_ARM_LIMIT`.
NHC_LEVER_LIMIT = 5.0

#: Mounting angle limit, rad: a yaw or pitch of the vehicle's forward axis in the IMU's body
#: frame (:class:`~bvpnav.error_models.Mounting`) beyond 10 degrees (0.175 rad). An IMU
#: mounted by eye is aligned with the car to a few degrees (the suggested prior sigma is
#: 0.02 rad): 10 degrees turn a 30 cm box's far end 5 cm sideways, which the eye sees. A
#: larger angle is the rows absorbing something else, or body axes that are not the
#: vehicle's (x forward, y left, z up). Counted from zero and from the stated prior (a unit
#: set at a known angle on purpose), as :data:`LEVER_ARM_LIMIT`.
MOUNTING_LIMIT = float(np.radians(10.0))

#: Side-slip limits, s^2/m: the rear axle's cornering compliance
#: (:class:`~bvpnav.error_models.SideSlip`) outside -0.002..0.02. A road tyre's cornering
#: stiffness is at least about 10 % of its load per degree (Gillespie, *Fundamentals of Vehicle
#: Dynamics*, ch. 10: 11-19 % for radial tyres), so a rear axle slips at most about 10 degrees
#: per g, 0.018 s^2/m; a negative compliance is the rear axle sliding into the turn, which a
#: tyre's lateral force cannot do (-0.002: 1.1 degrees per g, room for the estimate's noise).
#: Beyond either the rows absorb something else (a heading or gyro error in the turns, the rows
#: at a point that is not the rear axle). Counted from zero only: a stated prior cannot move
#: a tyre's physics.
SIDE_SLIP_LIMITS = (-0.002, 0.02)

#: An installation or timing estimate (time offset, lever arm, no-slip point, mounting) more
#: than this many of its prior sigmas from its prior mean is warned (with ``sigma=`` given),
#: whatever its size. With the truth drawn from the stated prior, the estimate's distance
#: from the prior mean has at most the prior sigma (the prior's variance minus the
#: posterior's), so 3 of them are exceeded with probability below 0.3 %: beyond, the data
#: contradict the stated prior (the prior is wrong, or the estimate absorbs something else),
#: as :data:`GYRO_PRIOR_SIGMAS` judges a gyro bias against its prior.
INSTALLATION_PRIOR_SIGMAS = 3.0

__all__ += ["ODOMETER_SCALE_LIMIT", "TIME_OFFSET_LATE_LIMIT", "TIME_OFFSET_EARLY_LIMIT", "LEVER_ARM_LIMIT",
            "NHC_LEVER_LIMIT", "MOUNTING_LIMIT", "SIDE_SLIP_LIMITS", "INSTALLATION_PRIOR_SIGMAS"]

_WHY_DELAY = ("a delay moves each fix along its track, so it absorbs any along-track error the rest of "
              "the model leaves (a speed or scale error, a heading error in the turns, few fixes across a "
              "gap), or the fixes and the IMU are not on one clock (GPS time against UTC: 18 s, time zones, "
              "two devices' clocks); put both on one clock, give the receiver's known latency "
              "(Position(delay=...)) or a prior from its datasheet (TimeOffset(prior=..., sigma=0.05)), or "
              "drop TimeOffset")
_WHY_LEVER = ("the lever arm absorbs something else (C(t) l turns with the attitude, so a heading or "
              "attitude error puts it there; fixes with an offset of their own; too few turns to see it); "
              "measure it with a tape and give it as the prior (LeverArm(prior=..., sigma=0.05)); on a "
              "larger vehicle give its measured lever arm as the prior")
_WHY_NHC = ("the no-slip point (the middle of a car's rear axle) must be on the vehicle, so the "
            "NonHolonomic/ForwardMotion rows absorb something else (the tyres' lateral slip in hard turns: "
            "give the rows a larger sigma or a band; a mounting yaw: Mounting; a heading or gyro error); "
            "give NhcLever a prior from the car's drawing (NhcLever(prior=..., sigma=0.5))")
_WHY_MOUNT = ("the boresight absorbs a lateral or vertical velocity the NonHolonomic rows cannot hold "
              "otherwise (slip in the turns, the constraint at the wrong point: NhcLever; an attitude or "
              "heading error), or the body axes are not the vehicle's (x forward, y left, z up); if the "
              "unit sits at a large angle on purpose, rotate the data into the vehicle's axes or give the "
              "known angles as Mounting's prior")
_WHY_SLIP = ("the side slip absorbs a lateral velocity the tyres cannot make (a heading or gyro error "
             "in the turns, a mounting yaw: Mounting, the rows at a point that is not the rear axle: "
             "NhcLever or lever=), or the body axes are not the vehicle's (x forward, y left, z up); give "
             "SideSlip the published prior (SideSlip(prior=SIDE_SLIP_PRIOR, sigma=SIDE_SLIP_SIGMA)) or drop "
             "slip=")

#: The installation and timing models, by the role the items look them up by (``provides``):
#: (what, unit, the limit of a vector's length (None: each value has its own), the point the
#: vector places and on what, likely causes and fix).
_INSTALLED = {"time_offset": ("the fixes' delay", "s", None, "", _WHY_DELAY),
              "lever_arm": ("the GNSS lever arm", "m", "LEVER_ARM_LIMIT", "the antenna; a car or a walker",
                            _WHY_LEVER),
              "nhc_lever": ("the no-slip point", "m", "NHC_LEVER_LIMIT", "the no-slip point; a car",
                            _WHY_NHC),
              "mounting": ("the mounting", "rad", None, "", _WHY_MOUNT),
              "side_slip": ("the side slip", "s^2/m", None, "", _WHY_SLIP)}


def _installed(sol: Solution, form: Formulation) -> list[tuple[str, Any, list[str], list[str]]]:
    """The installation and timing components: ``(role, component, its estimated names, all
    its names)``, the names the conditioning check calls degenerate left out."""
    em = getattr(form, "error_model", None)
    if em is None or not len(sol.error_params):
        return []
    cond = (getattr(sol, "stats", None) or {}).get("conditioning") or {}
    named = {n for dg in cond.get("degenerate_axes", []) for n in dg.get("parameters", [])}
    out = []
    for c in getattr(em, "components", (em,)):
        role = getattr(type(c), "provides", None)
        if role not in _INSTALLED:
            continue
        try:
            full = list(c.names(form.data))
        except Exception:  # noqa: BLE001 - a component that cannot name its parameters is skipped
            continue
        names = [n for n in full if n in sol.error_params.index and n not in named]
        if names:
            out.append((role, c, names, full))
    return out


def _per(value, full: list[str], names: list[str], default: float) -> np.ndarray:
    """A component's scalar-or-vector ``sigma``/``prior`` at ``names`` (``default`` when None)."""
    if value is None:
        return np.full(len(names), default)
    v = np.asarray(value, dtype=float).ravel()
    v = np.full(len(full), float(v[0])) if v.size == 1 else v
    return np.array([v[full.index(n)] for n in names])


def _as_given(value) -> str:
    """A scalar-or-vector ``sigma``/``prior`` as the user gave it (None: the default 0)."""
    v = np.zeros(1) if value is None else np.asarray(value, dtype=float).ravel()
    return f"{v[0]:g}" if v.size == 1 else "(" + ", ".join(f"{x:g}" for x in v) + ")"


def _show(role: str, n: str, v: float) -> str:
    if role == "time_offset":
        return f"{n} = {_fmt(v, 's')} ({1e3 * v:+.4g} ms)"
    if role == "mounting":
        return f"{n} = {_fmt(v, 'rad')} ({np.degrees(v):+.3g} deg)"
    if role == "side_slip":
        return f"{n} = {_fmt(v, 's^2/m')} ({np.degrees(v * 9.80665):+.3g} deg/g)"
    return f"{n} = {_fmt(v, 'm')}"


def _installation_checks(sol: Solution, form: Formulation) -> list[str]:
    """The fixes' delay, the GNSS lever arm, the no-slip point and the mounting: each against
    its physical limit (:data:`TIME_OFFSET_LATE_LIMIT`, :data:`TIME_OFFSET_EARLY_LIMIT`,
    :data:`LEVER_ARM_LIMIT`, :data:`NHC_LEVER_LIMIT`, :data:`MOUNTING_LIMIT`, counted from
    zero and from the stated prior) and, with a stated ``sigma``, against its prior
    (:data:`INSTALLATION_PRIOR_SIGMAS`)."""
    msgs: list[str] = []
    for role, c, names, full in _installed(sol, form):
        what, unit, vec_limit, where, why = _INSTALLED[role]
        v = _values(sol, names)
        ok = np.isfinite(v)
        if not ok.any():
            continue
        names, v = [n for n, k in zip(names, ok, strict=True) if k], v[ok]
        p = _per(getattr(c, "prior", None), full, names, 0.0)
        sig = getattr(c, "sigma", None)
        s = None if sig is None else _per(sig, full, names, np.inf)
        z = None if s is None else np.abs(v - p) / s
        prior_txt = "" if s is None else (
            f"; {'up to ' if len(names) > 1 else ''}{float(np.max(z)):.3g} prior sigmas from its prior "
            f"({type(c).__name__}(sigma="
            f"{_as_given(sig)}), prior {_as_given(getattr(c, 'prior', None))} {unit})")
        shown = ", ".join(_show(role, n, x) for n, x in zip(names, v, strict=True))
        absurd = None
        if role == "time_offset":
            lo, hi = -TIME_OFFSET_EARLY_LIMIT, TIME_OFFSET_LATE_LIMIT
            bad = [(n, x, q) for n, x, q in zip(names, v, p, strict=True)
                   if not (lo <= x <= hi or lo <= x - q <= hi)]
            if bad:   # the side of the delay past what was stated (the prior; zero without one)
                side = ("the IMU's samples stamped that much late, beyond any IMU's own latency"
                        if bad[0][1] - bad[0][2] < 0 else "a latency beyond any receiver's output chain")
                absurd = (f"{', '.join(_show(role, n, x) for n, x, _ in bad)} is beyond the limits "
                          f"{lo:+g}..{hi:+g} s of {what} ({side})")
        elif role == "mounting":
            bad = [(n, x) for n, x, q in zip(names, v, p, strict=True)
                   if abs(x) > MOUNTING_LIMIT and abs(x - q) > MOUNTING_LIMIT]
            if bad:
                absurd = (f"{', '.join(_show(role, n, x) for n, x in bad)} is beyond the limit "
                          f"{MOUNTING_LIMIT:.3g} rad ({np.degrees(MOUNTING_LIMIT):.3g} deg) of an IMU "
                          "mounted by eye")
        elif role == "side_slip":
            lo, hi = SIDE_SLIP_LIMITS
            # an absolute property of the tyres: counted from zero only (a prior cannot move it)
            bad = [(n, x) for n, x in zip(names, v, strict=True) if not lo <= x <= hi]
            if bad:
                deg = np.degrees(np.array([lo, hi]) * 9.80665)
                absurd = (f"{', '.join(_show(role, n, x) for n, x in bad)} is beyond the limits "
                          f"{lo:g}..{hi:g} s^2/m of a road tyre ({deg[0]:+.2g}..{deg[1]:+.3g} deg of side "
                          "slip per g)")
        else:
            limit = float(globals()[vec_limit])
            length, off = float(np.linalg.norm(v)), float(np.linalg.norm(v - p))
            if length > limit and off > limit:
                point, vehicle = where.split("; ")
                absurd = (f"{shown} put {point} {length:.3g} m from the IMU, beyond the limit {limit:g} m "
                          f"of {vehicle}"
                          + (f" (and {off:.3g} m from the stated prior)" if np.any(p != 0) else ""))
        if absurd is not None:
            msgs.append(f"implausible estimate: {absurd}{prior_txt}: {why}")
        elif z is not None and np.max(z) > INSTALLATION_PRIOR_SIGMAS:
            far = [(n, x, q, sd) for n, x, q, sd, zz in zip(names, v, p, s, z, strict=True)
                   if zz > INSTALLATION_PRIOR_SIGMAS]
            txt = ", ".join(f"{_show(role, n, x)} is {abs(x - q) / sd:.3g} prior sigmas "
                            f"({sd:g} {unit}) from its prior {q:g} {unit}" for n, x, q, sd in far)
            msgs.append(
                f"implausible estimate: {what}: {txt}, beyond {INSTALLATION_PRIOR_SIGMAS:g}: the data "
                f"contradict the stated prior (with the truth drawn from it, the estimate is within "
                f"{INSTALLATION_PRIOR_SIGMAS:g} prior sigmas of it but for "
                f"{100 * math.erfc(INSTALLATION_PRIOR_SIGMAS / math.sqrt(2)):.2g} % of cases): the prior is "
                f"too tight or wrong; otherwise: {why}")
    return msgs


def _plausibility(sol: Solution, form: Formulation, data) -> list[str]:
    groups = _groups(sol, form)
    items = getattr(form, "items", ())
    return (_acc_checks(sol, form, groups) + _attitude_checks(sol, groups)
            + _gyro_checks(sol, groups, data, items) + _odometer_checks(sol, groups)
            + _installation_checks(sol, form))


# ---------------------------------------------------------------------- API
def assess(sol: Solution, form: Formulation, data=None) -> dict[str, Any]:
    r"""The misfit numbers and every plausibility warning of a solution.

    Parameters
    ----------
    sol : Solution
        A solved answer (its ``residuals``, ``error_params``, ``x`` and ``lam``).
    form : Formulation
        The formulation ``sol`` solves (the demoted or last linearized one).
    data : ImuData, optional
        Where the measured gyro rates are read (``data.gyro``, rad/s); default
        ``form.data``.

    Returns
    -------
    dict
        ``residual_ratio`` (axis -> RMS of ``w / sigma_a``, dimensionless),
        ``residual_ratio_overall``, ``variance_factor`` and ``dof`` (None for
        problems that are not least squares or whose ``lam`` a rule chose),
        ``noise_ratio`` (square root of the variance factor, None below
        :data:`MISFIT_MIN_DOF` degrees of freedom) -- the misfit entries only when
        the acceleration form has a stated ``sigma_a`` --, ``thresholds`` and
        ``warnings`` (list of str).

    Notes
    -----
    Misfit, per axis :math:`a` with the stated :math:`\sigma_a`:

    .. math:: \rho_a = \sqrt{\tfrac{1}{N}\sum_i (w_{i,a}/\sigma_a)^2}, \quad
              \rho = \sqrt{\tfrac{1}{d}\sum_a \rho_a^2}, \quad
              \hat\sigma_0^2 = \frac{\sum_i \|w_i/\sigma_a\|^2
              + \sum_{\text{soft rows}} \lambda_k (r_k/\sigma_k)^2}{f},

    with :math:`f` the objective rows minus the unknowns plus the hard rows. A warning
    when :math:`\rho_a` or :math:`\rho` exceeds :data:`MISFIT_HIGH` (the residual is
    more than the noise could need), when :math:`\hat\sigma_0` is above :data:`MISFIT_HIGH`,
    or below :data:`MISFIT_LOW` (the sigmas overstated).
    Plausibility: each estimate against the module's limits (accelerometer bias
    :data:`ACC_BIAS_LIMIT` m/s^2, gravity :data:`GRAVITY_MAGNITUDE_LIMIT` m/s^2 and
    :data:`GRAVITY_TILT_LIMIT` rad, scale :data:`SCALE_LIMIT`, misalignment
    :data:`MISALIGNMENT_LIMIT` rad, initial tilt :data:`TILT_LIMIT` rad, gyro bias
    :data:`GYRO_BIAS_LIMIT` rad/s and against the mean measured rate
    (:data:`GYRO_MEAN_FRACTION`), gyro scale :data:`GYRO_SCALE_LIMIT`, odometer scale
    :data:`ODOMETER_SCALE_LIMIT`). Installation and timing: the fixes' delay
    :math:`\delta` below minus :data:`TIME_OFFSET_EARLY_LIMIT` s or above
    :data:`TIME_OFFSET_LATE_LIMIT` s, the lever arm's and the no-slip point's
    length beyond :data:`LEVER_ARM_LIMIT` and :data:`NHC_LEVER_LIMIT` m, a mounting angle
    beyond :data:`MOUNTING_LIMIT` rad (each only when beyond it from the stated prior too);
    and any of them with a stated prior :math:`(p, \sigma)` when
    :math:`|\hat x - p| > k\sigma`, :math:`k =` :data:`INSTALLATION_PRIOR_SIGMAS`.
    """
    data = form.data if data is None else data
    out: dict[str, Any] = {}
    msgs: list[str] = []
    if form.residual == "acceleration" and form.sigma_a_given and len(sol.residuals):
        nums, m = _misfit(sol, form)
        out.update(nums)
        msgs += m
    msgs += _plausibility(sol, form, data)
    out["thresholds"] = {k: globals()[k] for k in __all__ if k.isupper()}
    out["warnings"] = msgs
    return out


def check(sol: Solution, form: Formulation, data=None) -> list[str]:
    """The plausibility warnings of a solution (see :func:`assess`).

    Parameters
    ----------
    sol : Solution
    form : Formulation
        The formulation ``sol`` solves.
    data : ImuData, optional
        Where the measured gyro rates are read; default ``form.data``.

    Returns
    -------
    list of str
        One message per finding: the quantity, its value with units, the limit and the
        likely cause.
    """
    return assess(sol, form, data)["warnings"]


def attach(sol: Solution, form: Formulation, data=None) -> Solution:
    """Run :func:`assess` on ``sol``: each message into ``sol.warnings`` and issued once as
    a :class:`bvpnav.log.BvpnavWarning`, the numbers in ``sol.stats["plausibility"]``; the
    data's own checks (``data.checks``: frame and gravity, gyro saturation; warned when the
    data were built) into ``sol.warnings`` and ``sol.stats["data_checks"]``."""
    rep = assess(sol, form, data)
    checks = dict(getattr(data if data is not None else getattr(form, "data", None), "checks", None) or {})
    for msg in [c.get("warning") for c in checks.values()] + rep["warnings"]:
        if msg and msg not in sol.warnings:
            sol.warnings.append(msg)
    for msg in rep["warnings"]:
        warn(msg)
    return sol.record(plausibility=rep, data_checks=checks or None)
