r"""Bands and inequalities for the direct back end where few rows press: a primal-dual
active-set method (semismooth Newton) whose every step is one banded factorization, the
interior-point method of :mod:`bvpnav.linalg.ipm` its fallback.

For the quadratic program of :func:`bvpnav.linalg.ipm.quadratic_form`,

.. math::

    \min_x \|A x + c\|^2 \quad \text{s.t.} \quad E x + e = 0, \quad G x + g \le 0,

a guess :math:`W` of the rows at their bounds turns it into an equality-constrained least
squares problem: the rows of :math:`W` as hard rows :math:`G_i x + g_i = 0`, the others
left out. Its KKT system is the interior-point method's Newton system
(:class:`~bvpnav.linalg.ipm.MultiplierBand`) with the multipliers' diagonal
:math:`\Delta_k = 0` on the rows of :math:`W` and huge on the others: one banded
factorization from the same plan. Its answer :math:`(x, y, z)` (:math:`z_i = 0` off
:math:`W`) is the optimum when

.. math::

    G_i x + g_i \le \epsilon_g \ (i \notin W), \qquad z_i \ge -\epsilon_z \ (i \in W),

(stationarity, the equalities and complementarity hold by construction); otherwise the
next guess adds the violated rows and drops the rows whose multiplier has the wrong sign,

.. math::

    W^+ = \{i \notin W : G_i x + g_i > \epsilon_g\} \cup \{i \in W : z_i \ge -\epsilon_z\},

the primal-dual active-set step of Hintermüller, Ito and Kunisch (2002), a semismooth
Newton step on :math:`\min(z, -(G x + g)) = 0`. A penalty row (a soft inequality, a band's
soft edge: :mod:`bvpnav.linalg.ipm`'s "Penalty rows") in :math:`W` is held with its diagonal
:math:`1/p_i` instead of 0, i.e. as a soft row pulling :math:`G_i x + g_i` to 0, and its
multiplier :math:`z_i = 2 p_i (G_i x + g_i)` has the wrong sign exactly where the row is
satisfied; every violated penalty row enters :math:`W` at once (the semismooth Newton step of
the piecewise quadratic penalty), the peak rule below being for the hard rows.

With few rows at their bounds it ends in a few factorizations; it can cycle on problems that
are not of its kind, so a repeated guess, a singular KKT matrix (rows at their bounds that
determine no unknown alone) or ``max_iter`` updates hand the problem to the interior-point
method. A band's two sides
share one row of the system; at most one of them is in :math:`W`.

The tolerances are the interior-point method's measures (:data:`bvpnav.linalg.ipm.IPM_TOL`):
:math:`\epsilon_g` the tolerance times :math:`\max_i (|G| |x| + |g|)_i`, :math:`\epsilon_z`
times the largest term of the stationarity residual. A multiplier within
:math:`[-\epsilon_z, 0)` is reported as 0.

An outer loop that solves a sequence of such problems (the attitude loop re-linearizes
the same items) passes the rows at their bounds from one solve to the next
(:class:`ActiveHint`, in :attr:`bvpnav.linalg.workspace.Workspace.active_hint`): the
next solve starts from them instead of from none, and assembles into the same banded plan
(refitted where the next linearization's rows gain or lose entries,
:func:`bvpnav.linalg.ipm._refit`) instead of analysing the pattern again. The node-state
loop's intermediate steps, which only move the linearization point, take at most
:data:`QUICK_PASSES` passes of the method from those rows (:func:`quick_step`): the rows
at their bounds then settle along with the loop, and its last step is solved in full.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..sparse import abs_max
from .ipm import (
    _DECOUPLED,
    IPM_TOL,
    QuadraticForm,
    _info,
    _Newton,
    _Steps,
    interior_point,
    quadratic_form,
    unsupported_term,
)
from .workspace import Workspace

__all__ = ["ActiveHint", "solve_bands", "active_set", "quick_step", "QP_METHODS"]

#: Values of the direct back end's ``qp`` option: ``auto`` tries the active set first.
QP_METHODS = ("auto", "active set", "interior point")

#: Largest number of active-set updates before the interior-point method takes over.
MAX_UPDATES = 25

#: Largest number of active-set passes (factorizations) of an outer loop's intermediate step
#: (:func:`quick_step`).
QUICK_PASSES = 3

#: The active set gives way when this many updates have not lowered the fewest rows to
#: change (violated rows off the set plus rows on it whose multiplier pulls) seen so far.
STALL = 6


@dataclass(frozen=True, eq=False)
class ActiveHint:
    """The rows at their bounds in one solve, for the next solve of the same items.

    Attributes
    ----------
    signature : tuple
        :func:`signature` of the quadratic program they belong to.
    active : ndarray of bool
        One per row of :attr:`bvpnav.linalg.ipm.QuadraticForm.G`.
    gave_way : bool
        Whether the active set gave way in that solve: the next one (``qp="auto"``) goes
        straight to the interior-point method, spending no factorization on it again.
    plan : tuple or None
        That solve's banded plan with the pattern it was made for
        (:attr:`bvpnav.linalg.ipm._Steps.plan_key`): a solve of the same pattern assembles
        into it instead of analysing the pattern again.
    """

    signature: tuple
    active: np.ndarray
    gave_way: bool = False
    plan: tuple | None = None


def signature(qp: QuadraticForm) -> tuple:
    """The inequality terms' labels and row counts: a hint is used only for the same ones."""
    return (qp.G.m,) + tuple((label, tuple(sl.stop - sl.start for sl in pieces))
                             for label, pieces in qp.ineq_blocks)


@dataclass
class _Answer:
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    active: np.ndarray
    updates: int


class _Refined:
    """Solves of the KKT system with the rows of ``W`` hard and the others decoupled, refined
    against that system itself (not against the factorization's scaled copy)."""

    def __init__(self, qp: QuadraticForm, newton: _Newton):
        self.qp, self.nw = qp, newton
        self.B = qp.base
        self.Bt = qp.base.T.tocsr()

    def apply(self, z: np.ndarray, delta: np.ndarray) -> np.ndarray:
        nw = self.nw
        m, n, pE = nw.m, nw.n, nw.pE
        u, x, yh, nu = z[:m], z[m:m + n], z[m + n:m + n + pE], z[m + n + pE:]
        return np.concatenate([nw.A @ x - u, nw.At @ u + nw.Et @ yh + self.Bt @ nu, nw.E @ x,
                               self.B @ x - delta * nu])

    def solve(self, fac, rhs: np.ndarray, delta: np.ndarray, steps: int = 3,
              z: np.ndarray | None = None) -> np.ndarray:
        """The solution refined by up to ``steps`` steps (``z``: continue from it)."""
        z = fac.solve(rhs) if z is None else z
        n0 = max(abs_max(rhs), 1e-300)
        for _ in range(steps):
            res = rhs - self.apply(z, delta)
            if abs_max(res) <= 1e-15 * max(n0, abs_max(z)):
                break
            z += fac.solve(res)
        return z


def active_set(qp: QuadraticForm, newton: _Newton, tol: float, max_iter: int = MAX_UPDATES,
               start: np.ndarray | None = None) -> tuple[_Answer | None, str | None]:
    """The primal-dual active-set method (module Notes) from the rows ``start`` (None: none).

    Returns
    -------
    answer : _Answer or None
        ``x``, the equality multipliers ``y`` (cvxpy's convention), the inequality
        multipliers ``z``, the rows at their bounds and the number of updates; None when the
        method gave way.
    why : str or None
        Why it gave way.
    """
    mi = qp.G.m
    act = np.zeros(mi, dtype=bool) if start is None else start.copy()
    kkt = _Refined(qp, newton)
    seen: set[bytes] = set()
    fewest, since = mi + 1, 0
    for it in range(max_iter + 1):
        act = _one_side(qp, act)
        seen.add(act.tobytes())
        try:
            held = _Held(qp, newton, act)
        except np.linalg.LinAlgError:
            return None, f"the KKT matrix with {int(act.sum())} rows at their bounds is singular"
        # no refinement while the guess may change (as a quick step); three steps once it holds
        sol = held.solve(kkt, steps=0)
        for final in (False, True):
            if final:
                sol = held.solve(kkt, steps=3, z=sol)
            x, y, z, r, violated, wrong = held.check(sol, tol)
            if violated.any() or wrong.any():
                break
            if final:
                return _Answer(x, y, np.maximum(z, 0.0), act, it), None
        changes = int(violated.sum() + wrong.sum())
        if changes < fewest:
            fewest, since = changes, it
        elif it - since >= STALL:
            return None, (f"no fewer than {fewest} rows to change in {STALL} updates (after {it + 1}: "
                          f"{int(violated.sum())} violated, {int(wrong.sum())} pulling)")
        act = _next_guess(qp, act, r, violated, wrong)
        if it < max_iter and _one_side(qp, act).tobytes() in seen:
            return None, (f"the rows at their bounds repeat after {it + 1} updates "
                          f"({int(violated.sum())} violated, {int(wrong.sum())} pulling)")
    return None, f"no answer in {max_iter} updates ({int(violated.sum())} rows violated, " \
                 f"{int(wrong.sum())} pulling)"


class _Held:
    """The KKT system with the rows of a guess ``act`` held hard and the others decoupled,
    factorized once (:class:`~bvpnav.linalg.ipm._Steps`), and the optimality test of its
    answers (module Notes)."""

    def __init__(self, qp: QuadraticForm, newton: _Newton, act: np.ndarray):
        ls, G, nb = qp.ls, qp.G, qp.base.shape[0]
        self.qp, self.nw, self.act = qp, newton, act
        self.ia = np.flatnonzero(act)
        self.kb = qp.base_of[self.ia]
        self.delta = np.full(nb, _DECOUPLED)
        self.delta[self.kb] = qp.soft[self.kb]   # 0: held hard; a penalty row's 1 / p
        rk = np.zeros(nb)
        rk[self.kb] = -qp.sign[self.ia] * G.c[self.ia]
        self.fac = newton.steps.factor(self.delta)
        self.rhs = np.concatenate([-ls.D.c, np.zeros(newton.n), -ls.E.c, rk])

    def solve(self, kkt: _Refined, steps: int, z: np.ndarray | None = None) -> np.ndarray:
        return kkt.solve(self.fac, self.rhs, self.delta, steps=steps, z=z)

    def check(self, sol: np.ndarray, tol: float) -> tuple:
        """``(x, y, z, r, violated, wrong)`` of the solution ``sol``: the unknowns, the
        multipliers, the rows' values ``G x + g``, the rows off the guess above their bound
        and the rows on it whose multiplier pulls."""
        qp, nw, G, ia = self.qp, self.nw, self.qp.G, self.ia
        m, n, pE = nw.m, nw.n, nw.pE
        x, y, w = sol[m:m + n], 2.0 * sol[m + n:m + n + pE], 2.0 * sol[m + n + pE:]
        z = np.zeros(G.m)
        z[ia] = qp.sign[ia] * w[self.kb]
        r = G.value(x)
        eps_g = tol * max(abs_max(nw.absG @ np.abs(x)) + abs_max(G.c), 1e-300)
        grad = 2.0 * (nw.At @ qp.ls.D.value(x))
        eps_z = tol * max(abs_max(grad), abs_max(nw.Et @ y), abs_max(nw.Gt @ z), 1e-300)
        return x, y, z, r, ~self.act & (r > eps_g), self.act & (z < -eps_z)


def _next_guess(qp: QuadraticForm, act: np.ndarray, r: np.ndarray, violated: np.ndarray,
                wrong: np.ndarray) -> np.ndarray:
    """The next guess: the rows whose multiplier pulls dropped, the violated rows that peak
    (:func:`_peaks`) added."""
    return (act & ~wrong) | (violated & ((qp.soft_rows > 0) | _peaks(qp, r)))


def _peaks(qp: QuadraticForm, r: np.ndarray) -> np.ndarray:
    """Rows whose value is at least their neighbours' in time (the same item's row of the
    same axis and side at the instants before and after: :attr:`QuadraticForm.before`,
    :attr:`~QuadraticForm.after`)."""
    left = np.where(qp.before >= 0, r[qp.before], -np.inf)
    right = np.where(qp.after >= 0, r[qp.after], -np.inf)
    return (r >= left) & (r >= right)


def _one_side(qp: QuadraticForm, act: np.ndarray) -> np.ndarray:
    """``act`` with at most one side of each band (the first) at its bound."""
    ia = np.flatnonzero(act)
    if ia.size < 2:
        return act
    _, first = np.unique(qp.base_of[ia], return_index=True)
    if first.size == ia.size:
        return act
    out = np.zeros_like(act)
    out[ia[first]] = True
    return out


def solve_bands(form, lam: float, tol: float, max_iter: int = 80, workspace: Workspace | None = None,
                method: str = "auto", qp_method: str = "auto"):
    """A problem with band and inequality rows: the active set first (``qp_method`` ``auto``
    or ``active set``), the interior-point method when it gives way (``auto``) or alone
    (``interior point``); one plan of the banded factorization for both.

    Parameters
    ----------
    form : Formulation
    lam : float
    tol : float
        Relative tolerance (:data:`bvpnav.linalg.ipm.IPM_TOL`).
    max_iter : int
        The interior-point method's largest number of steps.
    workspace : Workspace, optional
        Its :attr:`~bvpnav.linalg.workspace.Workspace.active_hint` starts the active set
        and receives the rows at their bounds of this answer.
    method : {"auto", "banded", "lu"}
        The factorization (:func:`bvpnav.linalg.ipm.solve_qp`).
    qp_method : {"auto", "active set", "interior point"}

    Returns
    -------
    x : ndarray
    info : dict
        As :func:`bvpnav.linalg.ipm.solve_qp`'s, with ``qp_method`` (the method that gave
        the answer), ``active_rows`` (rows at their bounds, a band's side each) and
        ``active_set`` (the active set's updates, or why it gave way).

    Raises
    ------
    SolveError
        When the interior-point method stalls (:func:`~bvpnav.linalg.ipm.solve_qp`), or when
        ``qp_method="active set"`` and the active set gives way (the message says why).
    """
    from ..errors import SolveError

    if qp_method not in QP_METHODS:
        raise ValueError(f"qp_method {qp_method!r}: use one of {', '.join(QP_METHODS)}")
    qp = quadratic_form(form, lam)
    banded = method == "banded" or (method == "auto" and form.residual == "acceleration")
    hint = getattr(workspace, "active_hint", None)
    sig = signature(qp)
    hint = hint if isinstance(hint, ActiveHint) and hint.signature == sig else None
    steps = _Steps(qp, form, workspace, banded, reuse=None if hint is None else hint.plan)
    newton = _Newton(qp, steps)
    start = None if hint is None else hint.active
    why = "not tried (qp='interior point')"
    skip = qp_method == "auto" and hint is not None and hint.gave_way
    if skip:
        why = "not tried: it gave way in an earlier solve of these rows"
    if qp_method != "interior point" and qp.G.m and not skip:
        ans, why = active_set(qp, newton, tol, max_iter=MAX_UPDATES, start=start)
        if ans is not None:
            info = _info(qp, ans.y, ans.z, ans.updates, steps, 0.0, [], "optimal", method="active set")
            info.update(active_rows=int(ans.active.sum()), warm_start=start is not None,
                        active_set=f"{ans.updates} updates" + (" from the last solve's rows"
                                                               if start is not None else ""))
            _keep(workspace, sig, ans.active, plan=steps.plan_key)
            return ans.x, info
        if qp_method == "active set":
            raise SolveError(f"direct: the active-set method gave way: {why}; use qp='auto' (the "
                             "interior-point method then takes over) or qp='interior point'",
                             attempts=[{"solver": "direct", "status": "not converged", "reason": why}])
        steps.notes.append(f"the active set gave way: {why}")
    x, info = interior_point(qp, steps, newton, tol, max_iter)
    active = _ipm_active(qp, x, info)
    info.update(active_rows=int(active.sum()), warm_start=False, active_set=why or "")
    if qp.G.m:
        # tried and gave way, or skipped
        _keep(workspace, sig, active, gave_way=qp_method == "auto", plan=steps.plan_key)
    return x, info


def _ipm_active(qp: QuadraticForm, x: np.ndarray, info: dict) -> np.ndarray:
    """The rows of ``G`` at their bounds in an interior-point answer: multiplier (in the
    rows' scaled units) above the slack."""
    z = np.zeros(qp.G.m)
    for label, pieces in qp.ineq_blocks:
        for sl, zi in zip(pieces, info["duals"][label], strict=True):
            z[sl] = zi
    z = z * qp.scale
    return z > -qp.G.value(x)


def _keep(workspace: Workspace | None, sig: tuple, active: np.ndarray, gave_way: bool = False,
          plan: tuple | None = None) -> None:
    if workspace is not None:
        workspace.active_hint = ActiveHint(sig, active.copy(), gave_way, plan)


def quick_step(form, lam: float, workspace: Workspace | None, tol: float = IPM_TOL["default"]
               ) -> np.ndarray | None:
    """The unknowns of one pass of the active set from the last answer's rows: an outer
    loop's intermediate step, whose answer only moves the linearization point.

    The rows at their bounds in the workspace's :class:`ActiveHint` are held hard (one banded
    factorization, no refinement, no verification) and the hint takes the next guess
    (the rows whose multiplier pulls dropped, the violated rows that peak added), so the
    active set is updated along with the outer loop instead of to convergence at every
    step; the loop's last step is solved in full (:func:`solve_bands`), starting from that
    guess.

    Returns
    -------
    ndarray or None
        None (the caller then solves in full) without a hint of these rows, when the active
        set gave way on them, when the form is not the banded acceleration form, or when
        the KKT matrix of the guess is singular.
    """
    hint = getattr(workspace, "active_hint", None)
    if (not isinstance(hint, ActiveHint) or hint.gave_way or form.residual != "acceleration"
            or unsupported_term(form) is not None):
        return None
    qp = quadratic_form(form, lam)
    sig = signature(qp)
    if hint.signature != sig or not qp.G.m:
        return None
    steps = _Steps(qp, form, workspace, True, reuse=hint.plan)
    if steps.band is None:
        return None
    newton = _Newton(qp, steps)
    act = _one_side(qp, hint.active)
    for _ in range(QUICK_PASSES):
        try:
            held = _Held(qp, newton, act)
        except np.linalg.LinAlgError:
            return None
        x, _, _, r, violated, wrong = held.check(held.fac.solve(held.rhs), tol)   # unrefined
        if not (violated.any() or wrong.any()):
            break
        act = _one_side(qp, _next_guess(qp, act, r, violated, wrong))
    _keep(workspace, sig, act, plan=steps.plan_key)
    return x
