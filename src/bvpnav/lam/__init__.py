"""Lambda rules: how the regularization weight is chosen from a sweep.

A rule is an object with the :class:`LambdaRule` contract: a ``name`` (what users pass as
``lam=``), what it ``needs`` (``"least_squares"``: the exact sweep of a linear
least-squares problem; ``"trace"``: the influence trace; ``"noise"``: a stated
accelerometer noise), ``scores(sweep, pts, s)`` (its score at every sampled lambda) and
``refine(sweep, pts, s, scores, curve)`` (the chosen lambda, refined between samples);
``"acceleration"``: the data term is the acceleration residual (``residual="acceleration"``,
with or without ``sigma_a``).
One generic sweep (:func:`bvpnav.lam.sweep.sweep_curve`) runs every rule.

The family is a discovered folder, like ``bvpnav.constraints``: each module here defines
a rule and registers it with :func:`register_rule`; adding a rule is one file (here, or
anywhere that calls :func:`register_rule`), checked by :func:`bvpnav.testing.check_rule`.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..plugins import discover

#: Brent's tolerance on log(lambda) when a rule refines its choice (1 % in lambda: the
#: rules' functions are flat at their optimum, and each evaluation is a factorization).
REFINE_XATOL = 1e-2

__all__ = ["REFINE_XATOL", "LambdaRule", "register_rule", "unregister_rule", "get_rule", "rule_names",
           "NEEDS", "edge_warning"]

#: What a rule may need from the sweep.
NEEDS = ("least_squares", "trace", "noise", "acceleration")

#: How to widen the sweep, from Python and from the command line.
WIDEN = "widen lam_range=(low, high) (CLI: --lam-range)"

#: The built-in rules in the order they are listed (and evaluated).
BUILTIN = ("lcurve", "gcv", "discrepancy", "quasi")


class LambdaRule:
    """The contract of a lambda rule (subclass it).

    Attributes
    ----------
    name : str
        Lowercase name, passed as ``solve(lam=name)``.
    needs : frozenset of str
        Subset of :data:`NEEDS`.
    """

    name: str = ""
    needs: frozenset = frozenset()

    def scores(self, sweep, pts: list[dict], s: np.ndarray) -> np.ndarray:
        """The rule's score at each sampled point (``s = log lambda``).

        Each point is a dict with ``lam``, ``rho2`` (the squared norm of the terms not
        weighted by lambda), ``eta2`` (the lambda-weighted terms), ``x`` (the stacked
        solution) and, with the direct sweep, ``deta2`` (d eta2 / d lam), ``quasi``
        (``||lam dr/dlam||`` in m) and, when a rule needs it, ``trace``.
        """
        raise NotImplementedError

    def refine(self, sweep, pts: list[dict], s: np.ndarray, scores: np.ndarray, curve) -> float:
        """The chosen lambda (dimensionless); may append to ``curve.warnings`` and
        evaluate more points with ``sweep.point(lam)``."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"<bvpnav lambda rule {self.name!r}>"


_RULES: dict[str, LambdaRule] = {}


def register_rule(rule: LambdaRule) -> LambdaRule:
    """Add (or replace) a rule under its name."""
    if not isinstance(getattr(rule, "name", None), str) or not rule.name:
        raise InputError(f"register_rule({rule!r}): a rule needs a non-empty name")
    needs = set(getattr(rule, "needs", ()))
    unknown = needs - set(NEEDS)
    if unknown:
        raise InputError(f"register_rule({rule.name!r}): unknown needs {sorted(unknown)}; valid: "
                         f"{list(NEEDS)}")
    if "trace" in needs and "least_squares" not in needs:
        raise InputError(f"register_rule({rule.name!r}): needs 'trace' but not 'least_squares'; only the "
                         "direct sweep of a least-squares problem computes the trace: declare both")
    _RULES[rule.name] = rule
    return rule


def unregister_rule(name: str) -> None:
    """Remove a registered rule (e.g. one a test added)."""
    _RULES.pop(name, None)


def _discover() -> None:
    """Import every rule module of this folder once, the built-ins first."""
    discover(__name__, __path__, first=BUILTIN, skip=("sweep",))


def rule_names() -> tuple[str, ...]:
    """Names of every registered rule (the built-ins first)."""
    _discover()
    return tuple(_RULES)


def get_rule(name: str) -> LambdaRule:
    """The rule of a name, or :class:`InputError` listing the known ones."""
    _discover()
    if isinstance(name, str) and name in _RULES:
        return _RULES[name]
    raise InputError(f"lam rule {name!r} is not known; choose one of {list(_RULES)} or a number")


def edge_warning(curve, name: str, k: int, guard: int, scores=None, best: str = "max") -> bool:
    """Warn in ``curve`` when the best sample ``k`` may lie beyond the range.

    Sample ``k`` is the best of those a rule may choose (``guard`` samples at each end are
    excluded). It is at the edge when ``k`` is the first or last of them *and*, given
    ``scores``, the score still improves towards the end of the range (the excluded samples
    there score better, or ``k`` is an end sample): a local extremum at the first or last
    allowed sample is interior, and its refined lambda lies between the samples. Without
    ``scores`` every ``k`` within ``guard`` of an end warns. Returns True when it warned.
    """
    n = len(curve.lam)
    low, high = k <= guard, k >= n - 1 - guard
    if not (low or high):
        return False
    if scores is not None and 0 < k < n - 1:
        sc = np.asarray(scores, dtype=float)
        outer = sc[:k] if low else sc[k + 1:]
        better = outer > sc[k] if best == "max" else outer < sc[k]
        if not np.any(better):
            return False
    side = "low" if low else "high"
    lo, hi = (float(v) for v in curve.lam_range)
    fix = (f"lam_range=({max(lo / 1e3, 1e-12):g}, {hi:g})" if low
           else f"lam_range=({lo:g}, {min(hi * 1e3, 1e12):g})")  # inside formulation.LAM_RANGE
    curve.warnings.append(
        f"{name}: the best value lies at the {side} edge of lam_range=({lo:g}, {hi:g}) (best sample "
        f"lam={curve.lam[k]:.3g}), the optimum may lie beyond it: {WIDEN}, e.g. {fix}")
    return True


def bracket(s: np.ndarray, k: int) -> tuple[float, float]:
    """The log-lambda interval around sample ``k`` (its neighbours)."""
    return s[max(k - 1, 0)], s[min(k + 1, len(s) - 1)]
