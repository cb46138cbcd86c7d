"""See what bvpnav builds: the problem in readable mathematics, and its matrices.

:func:`describe` writes the assembled optimization problem as plain text or LaTeX
(each line a formula that matplotlib's mathtext renders): the unknowns with sizes and
units, the FEM hard constraints, the error model's columns, each item's equation with
its mode and weight, the objective with lambda, and the problem's size and an estimate
of its conditioning. :func:`matrices` returns the same problem as sparse matrices, so a
student can reproduce a solve with numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .cvx import current_lam
from .errors import InputError
from .formulation import Formulation, as_formulation
from .linalg.lsq import least_squares_form
from .model import Affine

__all__ = ["describe", "matrices", "Matrices"]


@dataclass(eq=False)
class Matrices:
    """The assembled problem, all over the stacked unknown vector ``x``.

    Attributes
    ----------
    K : scipy.sparse.csr_matrix, shape (N d, N d)
        Block-diagonal stiffness matrix, 1/s.
    M : scipy.sparse.csr_matrix, shape (N d, N d)
        Block-diagonal consistent mass matrix, s.
    f : ndarray, shape (N d,)
        Load vector ``f = -M a_hat`` (m/s), axis-major.
    F : ndarray, shape (N d, q)
        Error-model load columns ``F = -M G`` (m/s per unit parameter).
    A_eq, b_eq : sparse matrix and ndarray
        All hard equalities ``A_eq x = b_eq``: the FEM rows first, then hard items.
    J : sparse matrix
        Data-term rows: the data term is ``||J x||^2``.
    D, e, sigma : sparse matrix, ndarrays
        Stacked soft-item rows ``D x - e`` (item units) and their standard deviations;
        the soft term is ``lam * sum(((D x - e) / sigma)^2)``.
    legend : list of tuple
        ``(label, mode, matrix, rows)``: which rows of ``A_eq`` or ``D`` belong to what
        (``matrix`` is ``"A_eq"`` or ``"D"``, ``rows`` a slice).
    layout : dict
        Slices of ``x``: ``r_<axis>``, ``w_<axis>``, ``v0_<axis>``, ``v1_<axis>``, ``l``.
    """

    K: sp.csr_matrix
    M: sp.csr_matrix
    f: np.ndarray
    F: np.ndarray
    A_eq: sp.csr_matrix
    b_eq: np.ndarray
    J: sp.csr_matrix
    D: sp.csr_matrix
    e: np.ndarray
    sigma: np.ndarray
    legend: list
    layout: dict


def matrices(problem) -> Matrices:
    r"""Assemble :class:`Matrices` for a problem whose items are hard or soft.

    Raises
    ------
    InputError
        If an item is robust, band or an inequality (they are not linear rows).

    Notes
    -----
    The problem solved by ``problem.solve(lam=lam)`` is then

    .. math:: \min_x \|J x\|^2 + \lambda \|(D x - e)/\sigma\|^2
              \quad \text{s.t.} \quad A_{eq} x = b_{eq}.
    """
    form = as_formulation(problem)
    model = form.model
    d, n = model.d, model.N
    K = sp.block_diag([model.K] * d, format="csr")
    M = sp.block_diag([model.M] * d, format="csr")
    f = np.concatenate([-model._acc_load(a) for a in range(d)])
    F = np.zeros((n * d, model.q))
    for a in range(d if model.q else 0):   # -M G by the columns acting on the axis (condensed on a mesh)
        cols, vals = model.mg_columns(a)
        F[a * n:(a + 1) * n, cols] = -vals
    fem = model.fem_rows()
    eq = [fem]
    legend = [("fem", "hard", "A_eq", slice(0, fem.m))]
    soft, sig = [], []
    row_eq, row_d = fem.m, 0
    for term in form.terms():
        role = term.least_squares_role()
        if role is None:
            raise InputError(
                f"{term.label}: mode {term.mode!r} ({term.kind}) is not a linear row; matrices() "
                "covers hard and soft equality items"
            )
        if role == "E":
            eq.append(term.residual)
            legend.append((term.label, "hard", "A_eq", slice(row_eq, row_eq + term.residual.m)))
            row_eq += term.residual.m
        else:
            soft.append(term.residual)
            sig.append(term.sigma)
            legend.append((term.label, "soft", "D", slice(row_d, row_d + term.residual.m)))
            row_d += term.residual.m
    E = Affine.vstack(eq)
    if soft:
        S = Affine.vstack(soft)
        D, e, sigma = S.A, -S.c, np.concatenate(sig)
    else:
        D, e, sigma = sp.csr_matrix((0, model.size)), np.zeros(0), np.zeros(0)
    layout = {}
    for a, ax in enumerate(model.axes):
        r, w = model.r_index(a), model.w_index(a)
        i0, i1 = model.v_end_index(a)
        layout[f"r_{ax}"] = slice(r[0], r[-1] + 1)
        layout[f"w_{ax}"] = slice(w[0], w[-1] + 1)
        layout[f"v0_{ax}"] = slice(i0, i0 + 1)
        layout[f"v1_{ax}"] = slice(i1, i1 + 1)
        u = model.element_index(a)   # a coarse mesh's whitened element residuals (bvpnav.mesh)
        if u.size:
            layout[f"u_{ax}"] = slice(u[0], u[-1] + 1)
    o = model.d * model.block
    layout["l"] = slice(o, o + model.q)
    if model.ns:   # node states (ErrorStates): after l
        layout["s"] = slice(o + model.q, model.size)
    J = form.data_rows().A
    return Matrices(K=K, M=M, f=f, F=F, A_eq=E.A, b_eq=-E.c, J=J, D=D, e=e, sigma=sigma,
                    legend=legend, layout=layout)


def _condition_estimate(form: Formulation, lam: float) -> float | None:
    """1-norm condition estimate of the augmented KKT matrix (None if not least squares)."""
    ls = least_squares_form(form, lam)
    if ls is None:
        return None
    S = ls.augmented()
    try:
        lu = spla.splu(S, permc_spec="COLAMD")
    except RuntimeError:
        return float("inf")
    inv = spla.LinearOperator(S.shape, matvec=lu.solve, rmatvec=lambda v: lu.solve(v, trans="T"),
                              dtype=float)
    return float(spla.onenormest(S) * spla.onenormest(inv))


def _fmt(v) -> str:
    v = np.atleast_1d(np.asarray(v, dtype=float))
    if v.size == 1 or np.allclose(v, v[0]):
        return f"{v[0]:.4g}"
    return f"{v.min():.4g}..{v.max():.4g}"


def _penalty_latex(t) -> str:
    """The numerator of a penalty term's LaTeX: its residual, or for a band with soft edges
    the excess beyond the band."""
    lhs = _item_latex(t, lhs=True)
    if not t.soft_edges:
        return lhs
    if t.kind == "equality":
        return r"\max(|" + lhs + r"| - \mathrm{tol}_k, 0)"
    if "," in lhs:   # a two-sided bound's rows, "l - r, r - u": the larger of them
        lhs = r"\max(" + lhs + ")"
    return r"\max(" + lhs + r" - \mathrm{tol}_k, 0)"


def describe(problem, format: str = "text", lam: float | None = None,
             conditioning: bool = True) -> str:
    """The assembled problem in readable mathematics.

    Parameters
    ----------
    problem : NavigationProblem
    format : {"text", "latex"}
        Plain text, or LaTeX lines (each ``$...$`` renders with matplotlib's mathtext).
    lam : float, optional
        The lambda to print (default: the problem's current parameter value).
    conditioning : bool
        Include a 1-norm condition estimate of the KKT matrix (one sparse LU).

    Returns
    -------
    str
    """
    if format not in ("text", "latex"):
        raise InputError(f"format={format!r}; choose 'text' or 'latex'")
    tex = format == "latex"
    form = as_formulation(problem)
    model = form.model
    if lam is None:
        lam = current_lam(form)
    g = model.grid
    h = g.h
    terms = form.terms()
    lines: list[str] = []

    def head(s: str) -> None:
        lines.append(("% " if tex else "") + s)

    def math(text: str, latex: str) -> None:
        lines.append(f"${latex}$" if tex else text)

    step = f"h = {h[0]:.4g} s" if np.allclose(h, h[0]) else f"h = {h.min():.4g}..{h.max():.4g} s"
    head(f"bvpnav problem: N = {g.n} samples on [{g.t0:g}, {g.t1:g}] s ({step}); axes: "
         f"{', '.join(model.axes)}; residual form: {form.residual}")
    head(f"unknowns x ({model.size} entries):")
    for ax in model.axes:
        math(f"  r_{ax}  ({g.n})  nodal positions, m",
             rf"r_{{{ax}}} \in \mathbb{{R}}^{{{g.n}}}\ \mathrm{{(positions,\ m)}}")
        math(f"  w_{ax}  ({g.n})  acceleration residuals, m/s^2",
             rf"w_{{{ax}}} \in \mathbb{{R}}^{{{g.n}}}\ \mathrm{{(acceleration\ residuals,\ m/s^2)}}")
        math(f"  v0_{ax}, v1_{ax}  end velocities, m/s",
             rf"v_{{0,{ax}}},\ v_{{1,{ax}}} \in \mathbb{{R}}\ \mathrm{{(end\ velocities,\ m/s)}}")
    if model.q:
        names = ", ".join(model.param_names)
        math(f"  l  ({model.q})  error-model parameters: {names}",
             rf"l \in \mathbb{{R}}^{{{model.q}}}\ \mathrm{{(error\ model:\ {names.replace('_', ' ')})}}")
    if model.ns:
        kinds = ", ".join(model.state_model.state_kinds(model.data))
        math(f"  s  ({model.ns})  node states at every sample: {kinds}",
             rf"s \in \mathbb{{R}}^{{{model.ns}}}\ \mathrm{{(node\ states:\ {kinds.replace('_', ' ')})}}")
    head("hard constraints:")
    gl = (" + G l" if model.q else "") + (" + G_s s" if model.ns else "")
    math(f"  FEM ({g.n * model.d} rows): K r + e_1 v_0 - e_N v_1 + M (a_hat{gl} + w) = 0",
         r"K r + e_1 v_0 - e_N v_1 + M\,(\hat a" + (r" + G l" if model.q else "")
         + (r" + G_s s" if model.ns else "") + r" + w) = 0"
         + rf"\quad \mathrm{{FEM,\ {g.n * model.d}\ rows}}")
    if model.q:
        math("  G: acceleration change per unit error parameter (columns of F = -M G)",
             r"F = -M G\quad \mathrm{(error\ model\ columns)}")
    for t in terms:
        if t.is_constraint:
            rel = t.table.relation(t, _fmt(t.tol) if t.tol is not None else "")
            body = t.item.math() if t.item is not None else t.label
            math(f"  {t.label} [{t.mode}, {t.residual.m} rows]: {body}  ({rel})",
                 _item_latex(t) + rf"\quad \mathrm{{[{_tex_text(t.label)},\ {t.mode},\ "
                 rf"{t.residual.m}\ rows]}}")
    head("objective:")
    if form.residual == "acceleration":
        math(f"  minimize  sum_i (w_i / sigma_a)^2,  sigma_a = {_fmt(form.sigma_a)} m/s^2",
             rf"\min\ \sum_i (w_i/\sigma_a)^2,\quad \sigma_a = {_fmt(form.sigma_a)}\ \mathrm{{m/s^2}}")
    else:
        math("  minimize  ||K r + B v - f - F l||^2  (= ||M w||^2, the 2011 paper's load form)",
             r"\min\ \|K r + B v - f - F l\|^2 = \|M w\|^2")
    for t in terms:
        if t.is_penalty:
            k = "lam * " if t.scaled_by_lam else ""
            pen = t.table.penalty_symbol(t)  # inequalities and cones: only the violation
            body = (t.item.math() if t.item is not None else t.label).replace(" = 0", "")
            body = body.replace(" <= 0", "")
            edge = f", tol = {_fmt(t.tol)} {t.units}" if t.soft_edges else ""
            lhs = _penalty_latex(t)
            math(f"  + {k}sum {pen} of ({body}) / sigma   [{t.label}, {t.mode}, sigma = "
                 f"{_fmt(t.sigma)} {t.units}{edge}, {t.residual.m} rows]",
                 (r"+\ \lambda " if t.scaled_by_lam else "+ ") + r"\sum_k \left(\frac{"
                 + lhs + r"}{\sigma_k}\right)^2"
                 + rf"\quad \mathrm{{[{_tex_text(t.label)},\ {t.mode},\ \sigma = {_fmt(t.sigma)}\ "
                 rf"{_tex_text(t.units)}" + (rf",\ tol = {_fmt(t.tol)}\ {_tex_text(t.units)}" if t.soft_edges
                                              else "") + "]}")
    math(f"  lam = {lam:.6g}", rf"\lambda = {lam:.6g}")
    A_eq = Affine.vstack([model.fem_rows()] + [t.residual for t in terms
                                                if t.mode == "hard" and t.kind == "equality"]).A
    n_ineq = sum(t.residual.m for t in terms if t.kind == "inequality" and t.is_constraint)
    n_cone = sum(t.residual.groups for t in terms if t.kind == "cone" and t.is_constraint)
    n_obj = form.data_rows().m + sum(t.residual.m for t in terms if t.is_penalty)
    nnz = A_eq.nnz + form.data_rows().A.nnz + sum(
        t.residual.A.nnz for t in terms if not (t.mode == "hard" and t.kind == "equality"))
    extra = (f"{n_ineq} inequality rows, " if n_ineq else "") + (f"{n_cone} cones, " if n_cone else "")
    head(f"size: {model.size} unknowns, {A_eq.shape[0]} equality rows, {extra}{n_obj} objective rows, "
         f"{nnz} non-zeros")
    if conditioning:
        c = _condition_estimate(form, lam)
        head("condition estimate (1-norm, augmented KKT matrix): "
             + ("n/a (not least squares)" if c is None else f"{c:.3g}"))
    return "\n".join(lines)


def _tex_text(s: str) -> str:
    return (str(s).replace("\\", "").replace("_", r"\_").replace(" ", r"\ ").replace("#", r"\#")
            .replace("^", r"\^{}").replace("%", r"\%").replace("{", "").replace("}", ""))


def _item_latex(term, lhs: bool = False) -> str:
    """An item's equation in mathtext-compatible LaTeX."""
    item = term.item
    tex = getattr(item, "latex", None)
    body = tex() if callable(tex) else None
    if body is None:
        body = r"\mathrm{" + _tex_text(item.math() if item is not None else term.label) + "}"
    if lhs:
        if r"\leq" in body:  # inequality: the penalised quantity is the left side of <= 0
            return body.split(r"\leq")[0]
        return body.split("=")[0] if "=" in body else body
    return body
