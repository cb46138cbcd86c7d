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

Examples
--------
The built-in rules, and the one a name stands for:

>>> from bvpnav.lam import get_rule, rule_names
>>> sorted(rule_names())
['discrepancy', 'gcv', 'lcurve', 'quasi']
>>> rule = get_rule("gcv")
>>> rule.name, sorted(rule.needs)
('gcv', ['least_squares', 'trace'])
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..plugins import discover

#: Tolerance on log(lambda) when a rule refines its choice (1 % in lambda: the
#: rules' functions are flat at their optimum, and each evaluation is a factorization).
REFINE_XATOL = 1e-2

__all__ = ["REFINE_XATOL", "LambdaRule", "register_rule", "unregister_rule", "get_rule", "rule_names",
           "NEEDS", "edge_warning", "refine_extremum", "refine_with_slopes", "hermite_peak",
           "hermite_fit_peak", "guard_samples", "half_way_points"]

#: What a rule may need from the sweep.
NEEDS = ("least_squares", "trace", "noise", "acceleration")

#: How to widen the sweep, from Python and from the command line.
WIDEN = "widen lam_range=(low, high) (CLI: --lam-range)"

#: The built-in rules in the order they are listed (and evaluated).
BUILTIN = ("lcurve", "gcv", "discrepancy", "quasi")


class LambdaRule:
    r"""The contract of a lambda rule (subclass it).

    Attributes
    ----------
    name : str
        Lowercase name, passed as ``solve(lam=name)``.
    needs : frozenset of str
        Subset of :data:`NEEDS`.

    Examples
    --------
    A rule that balances the two terms, choosing the sampled lambda where the data term
    :math:`\rho^2` and the lambda-weighted term :math:`\eta^2` are closest (a plug-in
    written for this example, not a recommended rule):

    >>> import numpy as np
    >>> import bvpnav
    >>> from bvpnav.constraints import Position
    >>> rng = np.random.default_rng(0)
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> acc = -0.5 * np.sin(t) + 0.05 * rng.standard_normal(t.size)  # truth r = 0.5 sin t (m)
    >>> prob = bvpnav.NavigationProblem(bvpnav.ImuData(t=t, acc=acc), sigma_a=0.05)
    >>> tk = t[::10]
    >>> fixes = Position(t=tk, value=0.5 * np.sin(tk) + 0.01 * rng.standard_normal(tk.size), sigma=0.01)
    >>> prob = prob.add(fixes)
    >>> from bvpnav.lam import LambdaRule, register_rule, unregister_rule
    >>> class Balance(LambdaRule):
    ...     name = "balance"
    ...     uses_derivative = False
    ...     reads_quasi = False
    ...     def scores(self, sweep, pts, s):
    ...         return np.array([-abs(np.log(p["rho2"] / p["eta2"])) for p in pts])
    ...     def refine(self, sweep, pts, s, scores, curve):
    ...         return float(curve.lam[int(np.argmax(scores))])
    >>> _ = register_rule(Balance())
    >>> curve = bvpnav.lambda_curve(prob, rules=["balance"], rule="balance", lam_range=(1e-3, 1e3), points=7)
    >>> print(f"{curve.lam_chosen:g}")
    1
    >>> unregister_rule("balance")
    """

    name: str = ""
    needs: frozenset = frozenset()
    #: Whether its scores use the points' ``deta2`` or ``quasi`` (:math:`dx/d\lambda`, one
    #: more solve per lambda on the direct sweep); rules that read only ``rho2``, ``eta2``
    #: and ``trace`` set it False.
    uses_derivative: bool = True
    #: Whether it reads the points' ``quasi`` (the norm of the whole :math:`dx/d\lambda`);
    #: rules that read only the lambda rows' change (``deta2``, ``d2eta2``) set it False,
    #: and a sweep of such rules alone solves for :math:`dx/d\lambda` on those rows' reach
    #: (:class:`bvpnav.linalg.condensed.CondensedKKT`; ``quasi`` is then NaN).
    reads_quasi: bool = True
    #: Whether its refinement reads the exact slope of its score at every point (the
    #: direct sweep's ``d2eta2``, :func:`refine_with_slopes`; it needs
    #: ``uses_derivative``).
    slopes: bool = False
    #: Whether its refinement evaluates the half-way points beside its best sample when the
    #: samples lie more than a decade apart (:func:`half_way_points`): then such a
    #: rule reads every other sample of the 13-point grid on a range of 12 decades or more
    #: (:data:`bvpnav.lam.sweep.SLOPE_POINTS`, two decades apart; only those are solved
    #: when every rule of the sweep is coarse; the neighbourhood of the best sample is
    #: then as fine as one sample per decade).
    coarse: bool = False

    def scores(self, sweep, pts: list[dict], s: np.ndarray) -> np.ndarray:
        """The rule's score at each sampled point (``s = log lambda``).

        Each point is a dict with ``lam``, ``rho2`` (the squared norm of the terms not
        weighted by lambda), ``eta2`` (the lambda-weighted terms), ``x`` (the stacked
        solution) and, with the direct sweep, ``deta2`` (d eta2 / d lam), ``d2eta2``
        (d^2 eta2 / d lam^2), ``quasi`` (``||lam dr/dlam||`` in m) and, when a rule needs
        it, ``trace``.
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
    """Add (or replace) a rule under its name.

    Examples
    --------
    >>> from bvpnav.lam import LambdaRule, register_rule, rule_names, unregister_rule
    >>> class Fixed(LambdaRule):
    ...     name = "ten"
    ...     def scores(self, sweep, pts, s):
    ...         return s
    ...     def refine(self, sweep, pts, s, scores, curve):
    ...         return 10.0
    >>> register_rule(Fixed())
    <bvpnav lambda rule 'ten'>
    >>> "ten" in rule_names()
    True
    >>> unregister_rule("ten")
    >>> "ten" in rule_names()
    False
    """
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
    """Remove a registered rule (e.g. one a test added).

    Examples
    --------
    >>> from bvpnav.lam import LambdaRule, register_rule, rule_names, unregister_rule
    >>> class Fixed(LambdaRule):
    ...     name = "ten"
    >>> _ = register_rule(Fixed())
    >>> unregister_rule("ten")
    >>> "ten" in rule_names()
    False
    >>> unregister_rule("ten")  # removing an absent rule is no error
    """
    _RULES.pop(name, None)


def _discover() -> None:
    """Import every rule module of this folder once, the built-ins first."""
    discover(__name__, __path__, first=BUILTIN, skip=("sweep",))


def rule_names() -> tuple[str, ...]:
    """Names of every registered rule (the built-ins first).

    Examples
    --------
    >>> from bvpnav.lam import rule_names
    >>> sorted(rule_names())
    ['discrepancy', 'gcv', 'lcurve', 'quasi']
    """
    _discover()
    return tuple(_RULES)


def get_rule(name: str) -> LambdaRule:
    """The rule of a name, or :class:`InputError` listing the known ones.

    Examples
    --------
    >>> import bvpnav
    >>> from bvpnav.lam import get_rule
    >>> get_rule("lcurve")
    <bvpnav lambda rule 'lcurve'>
    >>> try:
    ...     get_rule("lcruve")
    ... except bvpnav.InputError as exc:
    ...     print(exc)
    lam rule 'lcruve' is not known; choose one of [...] or a number
    """
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

    Examples
    --------
    The best of seven samples one decade apart is the first a rule may choose, and the
    excluded sample beyond it scores better still:

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from bvpnav.lam import edge_warning
    >>> curve = SimpleNamespace(lam=np.logspace(-3, 3, 7), lam_range=(1e-3, 1e3), warnings=[])
    >>> edge_warning(curve, "gcv", k=1, guard=1, scores=[5.0, 4.0, 3.0, 2.0, 1.0, 0.0, -1.0])
    True
    >>> print(curve.warnings[0])
    gcv: the best value lies at the low edge lam=0.001 of lam_range=(0.001, 1000) (the score ...
    >>> edge_warning(curve, "gcv", k=3, guard=1)  # an interior sample
    False
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
    edge = lo if low else hi
    inner = "" if k in (0, n - 1) else (f"; the end samples are not chosen, the best chosen one is "
                                        f"lam={curve.lam[k]:.3g}")
    curve.warnings.append(
        f"{name}: the best value lies at the {side} edge lam={edge:g} of lam_range=({lo:g}, {hi:g}) "
        f"(the score still improves towards it{inner}), the optimum may lie beyond it: {WIDEN}, "
        f"e.g. {fix}")
    return True


def refine_extremum(f, s: np.ndarray, scores: np.ndarray, k: int, best: str = "max",
                    xatol: float = REFINE_XATOL, maxiter: int = 30,
                    bounds: tuple[float, float] | None = None) -> float:
    r"""The extremum of a smooth function of ``u = log lambda`` near sample ``k``.

    Successive parabolic interpolation seeded with the sweep's own samples ``k - 1, k,
    k + 1`` (no evaluation is spent re-discovering them, as a cold Brent search would),
    safeguarded by golden-section steps; every new evaluation ``f(u)`` is a score at a
    new lambda (one factorization).

    Parameters
    ----------
    f : callable
        ``f(u) -> float``, the score at ``lambda = exp(u)``.
    s, scores : ndarray
        The samples' ``log lambda`` (increasing) and scores.
    k : int
        The best sample a rule may choose.
    best : {"max", "min"}
    xatol : float
        Tolerance on ``log lambda``.
    maxiter : int
        At most this many new evaluations.
    bounds : (float, float), optional
        The ``log lambda`` interval the answer may take (a rule that never chooses its
        outermost samples): samples outside it still shape the parabolas, but an extremum
        beyond a bound is returned as that bound.

    Returns
    -------
    float
        ``log lambda`` of the extremum.

    Notes
    -----
    With the best evaluated point :math:`u_1` and its evaluated neighbours
    :math:`u_0 < u_1 < u_2`, the parabola through the three has its vertex at

    .. math:: v = u_1 - \frac{1}{2}\frac{(u_1 - u_0)^2 (g_1 - g_2) - (u_1 - u_2)^2 (g_1 - g_0)}
                                       {(u_1 - u_0)(g_1 - g_2) - (u_1 - u_2)(g_1 - g_0)}

    (:math:`g` the score, negated for a minimum), inside :math:`[u_0, u_2]` since
    :math:`g_1 \ge g_0, g_2`; it converges superlinearly (order about 1.32) at a smooth
    extremum. As in Brent's method, a vertex within ``xatol`` of :math:`u_1` is moved to
    :math:`u_1 \pm` ``xatol`` on its side so that the bracket closes, a vertex within
    ``xatol / 2`` of a bracket end (the parabola is no model there) is replaced by the
    golden-section point of the larger side, and the search stops when
    :math:`u_2 - u_0 \le 4` ``xatol``; when two steps have not shrunk the bracket to 0.7 of
    its width (parabolas creeping towards the extremum from one side, past a far bracket
    end), the next step is golden-section. When the best point is an end of the bracket the
    extremum lies at (or beyond) it: the end is returned, as a bounded search would. With
    ``bounds``, a best point or vertex beyond a bound (the model's extremum lies in the
    excluded range, and the best allowed point is the bound itself) returns the bound.

    Examples
    --------
    The maximum of :math:`g(u) = -(u - 0.3)^2` from samples at :math:`u = -1, 0, 1`:

    >>> import numpy as np
    >>> from bvpnav.lam import refine_extremum
    >>> g = lambda u: -(u - 0.3) ** 2
    >>> s = np.array([-1.0, 0.0, 1.0])
    >>> print(f"{refine_extremum(g, s, g(s), k=1):.3f}")
    0.300
    """
    lo, hi = (-np.inf, np.inf) if bounds is None else (float(bounds[0]), float(bounds[1]))

    def inside(u: float) -> float:
        return min(max(u, lo), hi)

    sign = 1.0 if best == "max" else -1.0
    n = len(s)
    pts = {float(s[j]): sign * float(scores[j]) for j in (k - 1, k, k + 1) if 0 <= j < n}
    golden = 0.5 * (3.0 - 5.0**0.5)
    widths: list[float] = []
    for _ in range(maxiter):
        xs = sorted(pts)
        i = max(range(len(xs)), key=lambda j: pts[xs[j]])
        u1 = xs[i]
        if i == 0 or i == len(xs) - 1 or not lo <= u1 <= hi:
            return inside(u1)   # the best is a bracket end, or beyond a bound
        u0, u2 = xs[i - 1], xs[i + 1]
        g0, g1, g2 = pts[u0], pts[u1], pts[u2]
        p = (u1 - u0) ** 2 * (g1 - g2) - (u1 - u2) ** 2 * (g1 - g0)
        q = (u1 - u0) * (g1 - g2) - (u1 - u2) * (g1 - g0)
        v = u1 - 0.5 * p / q if q > 0 else float("nan")
        h = u2 - u0
        if np.isfinite(v) and not lo <= v <= hi:
            return inside(v)   # the vertex lies beyond a bound: the bound is the best allowed
        if h <= 4.0 * xatol:
            return v if np.isfinite(v) else u1
        widths.append(h)
        # creeping: parabolas through a far bracket end step towards the extremum from one
        # side; when two steps have not shrunk the bracket to 0.7 of its width, a
        # golden-section step goes into the larger side instead
        creeping = len(widths) > 2 and h > 0.7 * widths[-3]
        if creeping:
            widths.clear()
            v = float("nan")
        near = bool(np.isfinite(v) and abs(v - u1) < xatol)
        if near:   # the parabola says u1, but is not trusted yet: close the bracket beside it
            v = u1 + xatol if (v > u1 if v != u1 else u2 - u1 > u1 - u0) else u1 - xatol
        if not (np.isfinite(v) and u0 + 0.5 * xatol < v < u2 - 0.5 * xatol):
            v = u1 + golden * (u2 - u1) if u2 - u1 > u1 - u0 else u1 - golden * (u1 - u0)
        pts[v] = sign * float(f(v))
    xs = sorted(pts)
    return inside(max(xs, key=lambda u: pts[u]))


def hermite_peak(a: float, b: float, ga: float, gb: float, da: float, db: float) -> float:
    r"""The maximiser inside ``[a, b]`` of the cubic with values ``ga, gb`` and slopes
    ``da, db`` at the ends (the midpoint when the cubic has no interior maximum).

    Notes
    -----
    With :math:`h = b - a`, :math:`t = (u - a)/h`, :math:`m_0 = h\,d_a`, :math:`m_1 = h\,d_b`,
    the cubic Hermite interpolant's derivative is :math:`h^{-1}(\alpha t^2 + \beta t + m_0)`
    with :math:`\alpha = 6(g_a - g_b) + 3(m_0 + m_1)` and
    :math:`\beta = -6(g_a - g_b) - 4m_0 - 2m_1`; its maximiser is the root in :math:`[0, 1]`
    where the second derivative :math:`2\alpha t + \beta` is negative (roots taken in the
    cancellation-free form of the quadratic formula). With :math:`m_0 > 0 > m_1` exactly one
    root lies in :math:`(0, 1)` and it is the maximum.

    Examples
    --------
    Values 0 at both ends of :math:`[0, 1]`, slopes +1 and -1: the symmetric cubic peaks at the
    middle:

    >>> from bvpnav.lam import hermite_peak
    >>> hermite_peak(0.0, 1.0, 0.0, 0.0, 1.0, -1.0)
    0.5
    """
    h = b - a
    m0, m1 = h * da, h * db
    alpha = 6.0 * (ga - gb) + 3.0 * (m0 + m1)
    beta = -6.0 * (ga - gb) - 4.0 * m0 - 2.0 * m1
    if abs(alpha) <= 1e-12 * (abs(beta) + abs(m0)):
        roots = [-m0 / beta] if beta != 0 else []
    else:
        disc = beta * beta - 4.0 * alpha * m0
        if disc < 0:
            roots = []
        else:
            q = -0.5 * (beta + math.copysign(math.sqrt(disc), beta))
            roots = [q / alpha] + ([m0 / q] if q != 0 else [])
    peaks = [t for t in roots if 0.0 <= t <= 1.0 and 2.0 * alpha * t + beta < 0]
    return a + (peaks[0] if peaks else 0.5) * h


def hermite_fit_peak(points: list, a: float, b: float) -> float | None:
    r"""The highest local maximiser inside ``[a, b]`` of the polynomial with the given
    values and slopes (``points``: ``(u, g, slope)`` at distinct ``u``; degree
    ``2 len(points) - 1``), or None when it has none there.

    Notes
    -----
    Confluent divided differences in :math:`t = (u - c)/r` (:math:`c, r` the centre and
    half-width of ``[a, b]``, slopes times :math:`r`), the Newton form expanded to powers of
    :math:`t`; the maximisers are the real roots of the derivative in :math:`[-1, 1]` where
    the second derivative is negative. Only a step's position: the bracket's proof never
    reads it.

    Examples
    --------
    Three points of :math:`g(u) = \sin 2u` with their slopes: the quintic through them peaks
    near :math:`\pi/4 = 0.7854`:

    >>> import math
    >>> from bvpnav.lam import hermite_fit_peak
    >>> points = [(u, math.sin(2 * u), 2 * math.cos(2 * u)) for u in (0.0, 0.5, 1.0)]
    >>> print(f"{hermite_fit_peak(points, 0.0, 1.0):.3f}")
    0.785
    """
    c, r = 0.5 * (a + b), 0.5 * (b - a)
    z = [(x[0] - c) / r for x in points for _ in (0, 1)]
    q = [x[1] for x in points for _ in (0, 1)]
    dq = [x[2] * r for x in points]
    m = len(z)
    coef, col = [q[0]], list(q)
    for order in range(1, m):   # column `order` of the divided-difference table
        new = []
        for i in range(m - order):
            dz = z[i + order] - z[i]
            new.append(dq[i // 2] if dz == 0 else (col[i + 1] - col[i]) / dz)
        col = new
        coef.append(col[0])
    if not np.all(np.isfinite(coef)):
        return None
    poly, basis = np.polynomial.Polynomial([0.0]), np.polynomial.Polynomial([1.0])
    for i, cf in enumerate(coef):
        poly = poly + cf * basis
        basis = basis * np.polynomial.Polynomial([-z[i], 1.0])
    d1, d2 = poly.deriv(), poly.deriv(2)
    peaks = [float(t.real) for t in d1.roots()
             if abs(t.imag) <= 1e-9 and -1.0 < t.real < 1.0 and d2(t.real) < 0]
    if not peaks:
        return None
    return c + r * max(peaks, key=poly)


def _model_step(a: tuple, b: tuple, p: tuple, q: tuple, seen: list, cubic: float) -> float:
    """Where :func:`refine_with_slopes` steps inside the bracket ``[a, b]`` (each point
    ``(u, g, slope)``; ``p, q`` the two newest, ``seen`` every evaluated one): the peak of
    the polynomial through the bracket's ends and the two evaluated points nearest outside
    it (values and slopes, degree 7: the bracket's cubic ignores the curve beyond its ends,
    which shapes the peak as much once one end is near it), else the secant of the newest
    slopes when both lie on one side of it, else the bracket's cubic peak ``cubic``."""
    out = sorted((x for x in seen if not a[0] <= x[0] <= b[0] and np.isfinite(x[1] + x[2])),
                 key=lambda x: min(abs(x[0] - a[0]), abs(x[0] - b[0])))[:2]
    w = hermite_fit_peak([a, b, *out], a[0], b[0])
    if w is not None:
        return w
    if p[2] * q[2] > 0 and p[2] != q[2]:
        w = q[0] - q[2] * (q[0] - p[0]) / (q[2] - p[2])
        if a[0] < w < b[0]:
            return w
    return cubic


def _holds_peak(p: tuple, q: tuple) -> bool:
    """Whether ``[p, q]`` (each ``(u, g, slope)``, ``p`` left) must hold a local maximum of
    a smooth ``g``: rising at ``p`` or below ``q`` there, and falling at ``q`` or below ``p``."""
    return (p[2] > 0 or p[1] < q[1]) and (q[2] < 0 or q[1] < p[1])


def refine_with_slopes(f, s: np.ndarray, scores: np.ndarray, slopes: np.ndarray, k: int,
                       best: str = "max", xatol: float = REFINE_XATOL, maxiter: int = 30,
                       bounds: tuple[float, float] | None = None) -> float:
    r"""The extremum near sample ``k`` of a score whose slope is known at every point.

    Like :func:`refine_extremum`, but each evaluation ``f(u) -> (score, d score / du)`` also
    gives the slope: the extremum is kept in a bracket the values and slopes prove holds
    one, and each step goes to the peak of the degree-7 polynomial through the values and
    slopes of the bracket's ends and of the two evaluated points nearest outside it
    (:func:`hermite_fit_peak`: the curve beyond a bracket end shapes the peak as much as the
    bracket does once one end is near it), else of the bracket's cubic
    (:func:`hermite_peak`) or the secant of the two newest slopes when they lie on one side
    of it; the search ends after two to four evaluations from a bracket two decades wide,
    where :func:`refine_extremum` takes five or six from one decade. (On the benchmark's
    L-curve at 1e5 samples the polynomial took the refinement from five evaluations to
    three, and the L-curve rule from 14 to 12; over the test-suite's peaks 31 against 55
    with the cubic alone.) The model only places the steps: the bracket's proof never
    reads it.

    Parameters
    ----------
    f : callable
        ``f(u) -> (score, slope)`` at ``lambda = exp(u)``.
    s, scores, slopes : ndarray
        The samples' ``log lambda`` (increasing), scores and slopes (per unit of ``log lambda``).
    k, best, xatol, maxiter, bounds
        As in :func:`refine_extremum`.

    Returns
    -------
    float
        ``log lambda`` of the extremum.

    Notes
    -----
    A bracket :math:`[a, b]` holds a local maximum of the score :math:`g` (negated for a
    minimum) when :math:`g` rises at :math:`a` (:math:`g'(a) > 0`) or :math:`g(a) < g(b)`,
    and falls at :math:`b` or :math:`g(b) < g(a)`. The first is the best sample ``k`` and
    the neighbour its slope points to. Each step evaluates a point :math:`v` at least
    ``xatol`` inside, and keeps the half that still provably holds a maximum (the one with
    the better end if both do). A point within ``xatol`` of the newest one is moved to
    ``xatol`` beside it, on the side its slope points to: once the model has converged,
    that one evaluation closes the bracket on the other side of the extremum; likewise a
    point within 1.9 ``xatol`` of a bracket end is moved to 1.9 ``xatol`` from it, past the
    model's extremum, so that a right model is confirmed and the bracket closed by the
    same evaluation. After five steps in a row that moved the same end (the slope's zero
    of a flat top, where secants creep) the next step bisects. The search stops when
    :math:`b - a \le 2` ``xatol`` (or after ``maxiter`` evaluations, or at a score or
    slope that is not finite) and returns the cubic's maximiser there: for a smooth
    maximum far closer than ``xatol``, on a flat top within the bracket's width. A slope of
    exactly zero ends the search only at a point at least as good as both ends (a
    degenerate point's slope of zero is not a maximum).
    Without such a bracket beside ``k`` (a slope of zero, the best sample at an end) the
    search is :func:`refine_extremum`'s on the scores alone; a maximiser beyond a bound
    returns the bound.

    Examples
    --------
    The same maximum of :math:`g(u) = -(u - 0.3)^2`, with its slope :math:`-2 (u - 0.3)`:

    >>> import numpy as np
    >>> from bvpnav.lam import refine_with_slopes
    >>> f = lambda u: (-(u - 0.3) ** 2, -2.0 * (u - 0.3))
    >>> s = np.array([-1.0, 0.0, 1.0])
    >>> scores, slopes = f(s)
    >>> print(f"{refine_with_slopes(f, s, scores, slopes, k=1):.3f}")
    0.300
    """
    sign = 1.0 if best == "max" else -1.0
    lo, hi = (-np.inf, np.inf) if bounds is None else (float(bounds[0]), float(bounds[1]))
    n = len(s)

    def sample(j: int) -> tuple:
        return float(s[j]), sign * float(scores[j]), sign * float(slopes[j])

    j = k if sign * slopes[k] > 0 else k - 1
    if not (0 <= j < n - 1 and sign * slopes[k] != 0 and _holds_peak(sample(j), sample(j + 1))):
        return refine_extremum(lambda u: f(u)[0], s, scores, k, best=best, xatol=xatol,
                               maxiter=maxiter, bounds=bounds)
    a, b = sample(j), sample(j + 1)
    seen = [sample(i) for i in range(n)]   # every evaluated point, for the step's model
    newest = [a, b] if j == k else [b, a]   # the best sample last
    moved = ""   # which end each step replaced ("a" or "b"), newest last
    for _ in range(maxiter):
        v = hermite_peak(a[0], b[0], a[1], b[1], a[2], b[2])
        if b[0] - a[0] <= 2.0 * xatol or not lo <= v <= hi:
            break
        p, q = newest
        if moved[-5:] in ("aaaaa", "bbbbb"):
            # creeping: five steps in a row from one side (the slope's zero is of high
            # order, a flat top, where secants and cubics converge linearly; four is still
            # a secant's usual approach to a skewed peak): bisect
            v, moved = 0.5 * (a[0] + b[0]), ""
        else:
            v = _model_step(a, b, p, q, seen, v)
        if abs(v - q[0]) < xatol:   # converged on the newest point: confirm beside it
            v = q[0] + xatol if q[2] > 0 else q[0] - xatol
        elif v - a[0] < 1.9 * xatol < b[0] - v:   # near an end: close the bracket past v
            v = a[0] + 1.9 * xatol
        elif b[0] - v < 1.9 * xatol < v - a[0]:
            v = b[0] - 1.9 * xatol
        v = min(max(v, a[0] + xatol), b[0] - xatol)
        gv, dv = (sign * float(x) for x in f(v))
        if not (np.isfinite(gv) and np.isfinite(dv)):
            break   # no model beyond this: the cubic of the bracket so far
        if dv == 0.0 and gv >= max(a[1], b[1]):   # the extremum itself
            return min(max(v, lo), hi)
        c = (v, gv, dv)
        seen.append(c)
        left, right = _holds_peak(a, c), _holds_peak(c, b)
        if left and right:
            left = a[1] >= b[1]
        elif not (left or right):   # no proof either way: the scores alone, from the best
            pts = sorted([a, c, b])
            g = [x[1] for x in pts]
            return refine_extremum(lambda u: f(u)[0], np.array([x[0] for x in pts]),
                                   sign * np.array(g), int(np.argmax(g)), best=best,
                                   xatol=xatol, maxiter=maxiter, bounds=bounds)
        a, b = (a, c) if left else (c, b)
        moved += "b" if left else "a"
        newest = [newest[1], c]
    v = hermite_peak(a[0], b[0], a[1], b[1], a[2], b[2])
    return min(max(v, lo), hi)


def guard_samples(s: np.ndarray) -> int:
    """How many samples at each end of a sweep a rule that never chooses the range's ends
    leaves out: the two outermost, or the outermost one when samples lie two decades or
    more apart (the same two decades at each end of the default range with 13 samples one
    decade apart or 7 two decades apart; the same sixth of any range of 12 decades or more
    with 13 or 7 samples).

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.lam import guard_samples
    >>> guard_samples(np.log(np.logspace(-6, 6, 13)))  # one decade apart
    2
    >>> guard_samples(np.log(np.logspace(-6, 6, 7)))   # two decades apart
    1
    """
    return 1 if len(s) > 1 and s[1] - s[0] >= 2.0 * math.log(10.0) * (1.0 - 1e-9) else 2


def half_way_points(s: np.ndarray, k: int, lo: float | None = None, hi: float | None = None) -> list[float]:
    """The ``log lambda`` half-way between sample ``k`` and each neighbour, within ``[lo,
    hi]`` (default: the samples' range), when the samples lie more than 1.5 decades apart
    (none otherwise): a coarse sweep's rule evaluates them so that an extremum between
    the best sample and a neighbour is bracketed as on a grid one decade apart.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.lam import half_way_points
    >>> s = np.log(np.logspace(-6, 6, 7))  # two decades apart
    >>> [f"{np.exp(u):g}" for u in half_way_points(s, 3)]
    ['0.1', '10']
    >>> half_way_points(np.log(np.logspace(-6, 6, 13)), 6)  # one decade apart: none
    []
    """
    s = np.asarray(s, dtype=float)
    if len(s) < 2 or s[1] - s[0] <= 1.5 * math.log(10.0):
        return []
    lo = float(s[0]) if lo is None else lo
    hi = float(s[-1]) if hi is None else hi
    mids = [0.5 * (s[j] + s[j + 1]) for j in (k - 1, k) if 0 <= j < len(s) - 1]
    return [float(m) for m in mids if lo <= m <= hi]


def bracket(s: np.ndarray, k: int) -> tuple[float, float]:
    """The log-lambda interval around sample ``k`` (its neighbours)."""
    return s[max(k - 1, 0)], s[min(k + 1, len(s) - 1)]
