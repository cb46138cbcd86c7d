"""How well the information determines the error-model parameters, and warnings when it does not.

Two things make an error-model estimate unreliable although the solve succeeds:

1. **Near collinearity.** After the trajectory is eliminated, the parameters' effect on
   the objective is the q x q Schur complement ``H`` of the KKT matrix (the reduced
   Hessian, the inverse of the parameters' covariance for a correctly weighted data
   term). Scaling it to unit diagonal gives the Gram matrix of the parameter directions
   scaled to unit length; the square roots of its eigenvalues are the *relative singular
   values* (between 0 and sqrt(q); 1 for a direction independent of all others). A
   small one means a combination of parameters that the information barely sees: e.g.
   the scale factor and the bias of a sensor axis whose true specific force is almost
   constant. Exactly collinear directions are refused before solving
   (:meth:`bvpnav.formulation.Formulation.check_observability`); nearly collinear ones get a
   warning naming them.
2. **A degenerate sensor correction.** The built-in sensor models estimate the exact
   correction ``f = (I + E) f_hat + beta`` and report the physical scale factor
   ``s_i = D_ii - 1`` and bias ``b = -D beta`` with ``D = (I + E)^{-1}``. On a sensor
   axis that feels no true specific force (the body y axis of a planar motion) the data
   are best explained by removing that axis' signal, ``1 + E_ii = 0``, which is well
   determined in the internal unknowns but leaves the physical scale factor and bias
   undefined (``D_ii`` infinite, or of either sign). A gain ``D_ii = 1 + s_i`` outside
   ``[1/GAIN_LIMIT, GAIN_LIMIT]`` (no accelerometer's gain is off by a factor of ten or
   reversed) gets a warning naming the axis' parameters.

Both checks cost ``O(q^3)`` once the Schur complement is known; the verification step
(:func:`bvpnav.solve.verify.verify`) passes its own factorization, so no extra
factorization of size N is made for equality-constrained least-squares problems. Problems
with band or inequality rows use their least-squares part, factorized by the banded path on
the acceleration form (a pivoted sparse LU elsewhere).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..error_models._base import KEPT_ZERO, SensorCorrection, SensorErrorModel, sensor_axes
from ..formulation import Formulation
from ..linalg.lsq import Factored, least_squares_form

__all__ = ["RELATIVE_SV_WARN", "GAIN_LIMIT", "information_matrix", "relative_singular_values",
           "assess_conditioning"]

#: Relative singular value below which a parameter direction is reported as nearly
#: unobservable. Its variance is then inflated by about ``1 / sv^2`` (1e8) over a
#: parameter that the information separates from all others. (The 2010 paper's
#: nine-parameter strapdown example, recovered exactly without noise, has 7.3e-4 for
#: ``scale_z``, ``bias_z`` and ``gravity_z``: poorly separated, but not warned about.)
RELATIVE_SV_WARN = 1e-4

#: Largest plausible factor between a sensor's gain ``1 + s`` and 1 (either way).
GAIN_LIMIT = 10.0

#: Components of a weak direction (unit vector) at least this large name a parameter.
_INVOLVED = 0.2


def _schur(S: sp.spmatrix, dense: np.ndarray, shift_rows: np.ndarray) -> np.ndarray:
    """Schur complement of the ``dense`` unknowns of the symmetric ``S`` (one sparse LU of
    the rest; a tiny shift on ``shift_rows`` if that block is singular)."""
    S = sp.csc_matrix(S)
    keep = np.setdiff1d(np.arange(S.shape[0]), dense)
    B = S[keep][:, keep].tocsc()
    try:
        lu = spla.splu(B, permc_spec="COLAMD")
    except RuntimeError:
        d = np.zeros(S.shape[0])
        d[shift_rows] = 1e-10 * float(abs(S).max())
        lu = spla.splu((B - sp.diags(d[keep])).tocsc(), permc_spec="COLAMD")
    SBL = S[keep][:, dense].toarray()
    return S[dense][:, dense].toarray() - SBL.T @ lu.solve(SBL)


def information_matrix(form: Formulation, lam: float, factored: Factored | None = None) -> np.ndarray:
    """The reduced Hessian of the error-model parameters, shape (q, q).

    Parameters
    ----------
    form : Formulation
    lam : float
        Regularization weight of the soft items.
    factored : Factored, optional
        A factorization of the problem's augmented matrix at this ``lam`` (its Schur
        complement is reused: no new factorization).

    Returns
    -------
    ndarray, shape (q, q)
        Symmetric positive semi-definite; in the units ``1 / (p_j p_k)`` of the internal
        parameters.

    Notes
    -----
    With the augmented matrix ``S`` of :mod:`bvpnav.linalg.lsq` (unknowns ``rho, x, mu``) split
    into the parameters ``L`` and the rest ``B``,

    .. math:: H = S_{LL} - S_{LB} S_{BB}^{-1} S_{BL},

    and :math:`H^{-1}` is the parameter block of :math:`S^{-1}`, i.e. of the covariance
    :math:`Z (Z^T D^T D Z)^{-1} Z^T` (``Z`` a basis of the null space of the equality
    rows ``E``). Problems with inequality, band, robust or cone items use their
    least-squares part (robust items as soft ones, the others left out); the left-out
    items can only add information, so the estimate errs on the side of a warning.
    """
    model = form.model
    if factored is not None and factored.factor.keep is not None:
        H = np.asarray(factored.factor.schur, dtype=float)
    else:
        ls = least_squares_form(form, lam, surrogate=True)
        H = _banded_schur(ls, form)
        if H is None:
            m, n = ls.D.A.shape
            p = ls.E.m
            H = _schur(ls.augmented(), m + model.l_index, np.arange(m + n, m + n + p))
    return 0.5 * (H + H.T)


def _banded_schur(ls, form: Formulation) -> np.ndarray | None:
    """The parameters' Schur complement from the banded factorization of ``ls`` (the
    acceleration form: the problems with band and inequality rows, whose back end hands no
    factorization of their least-squares part), or None where that is not banded or singular
    (:func:`_schur` then factorizes)."""
    from ..linalg.banded import NotBanded
    from ..linalg.lsq import banded_factor

    if form.residual != "acceleration":
        return None
    try:
        fac = banded_factor(ls, form)
        if fac.keep is None:
            return None
        H = np.asarray(fac.schur, dtype=float)
    except (NotBanded, RuntimeError, np.linalg.LinAlgError, ValueError):
        return None
    return H if np.all(np.isfinite(H)) else None


def relative_singular_values(H: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Singular values of the parameter directions scaled to unit length.

    Parameters
    ----------
    H : ndarray, shape (q, q)
        Reduced Hessian (see :func:`information_matrix`).

    Returns
    -------
    sv : ndarray, shape (q,)
        Ascending, dimensionless, between 0 and sqrt(q); a parameter without any
        information has 0.
    V : ndarray, shape (q, q)
        The matching unit directions (columns) in scaled parameters.

    Notes
    -----
    With :math:`H = A^T A` and the scaling :math:`S = \mathrm{diag}(H)^{-1/2}`, the
    columns of :math:`A S` have unit length and their singular values are
    :math:`\sqrt{\lambda_k(S H S)}`. Two parameters alone with correlation ``rho``
    between their directions have :math:`\sqrt{1 \pm \rho}`.
    """
    d = np.diag(H).astype(float)
    pos = np.isfinite(d) & (d > 0)
    scale = np.where(pos, 1.0 / np.sqrt(np.where(pos, d, 1.0)), 0.0)
    Hs = H * np.outer(scale, scale)
    Hs[~pos, :] = 0.0
    Hs[:, ~pos] = 0.0
    if not np.all(np.isfinite(Hs)):
        q = H.shape[0]
        return np.zeros(q), np.eye(q)
    w, V = np.linalg.eigh(Hs)
    return np.sqrt(np.clip(w, 0.0, None)), V


def _degenerate_axes(form: Formulation, l: np.ndarray) -> list[dict[str, Any]]:
    """Sensor axes whose kept fraction of their own signal ``1 + E_ii`` is not finite or
    outside ``[1/GAIN_LIMIT, GAIN_LIMIT]``, or whose finite gain ``1 + s_i = D_ii`` is
    outside that range (built-in sensor models with a scale factor only)."""
    model = form.model
    em = model.error_model
    comps = getattr(em, "components", (em,))
    params, values, off = [], [], 0
    for c in comps:
        q = len(c.names(model.data))
        if isinstance(c, SensorErrorModel):
            params.extend(c.params(model.data))
            values.extend(l[off:off + q])
        off += q
    scaled = [p for p in params if p.role == "scale"]
    if not scaled:
        return []
    corr = SensorCorrection.from_values(params, np.asarray(values, dtype=float), model.data)
    with np.errstate(all="ignore"):
        D = corr.D
    kept = corr.kept  # within KEPT_ZERO of zero snapped to 0: not at the mercy of rounding
    axes = sensor_axes(model.data)
    out = []
    for p in scaled:
        i = p.i
        gain = float(D[i, i])
        keep = float(kept[i])
        # judged on the kept fraction 1 + E_ii of the axis's own signal: when another
        # axis is degenerate, D = (I + E)^-1 is NaN everywhere, this axis included
        kept_ok = np.isfinite(keep) and 1.0 / GAIN_LIMIT <= keep <= GAIN_LIMIT
        gain_ok = not np.isfinite(gain) or 1.0 / GAIN_LIMIT <= gain <= GAIN_LIMIT
        if kept_ok and gain_ok:
            continue
        names = [q.name for q in params if q.role in ("scale", "bias", "misalignment") and q.i == i]
        # kept fraction zero: the parameters are undetermined (reported inf/NaN), not wrong
        out.append({"axis": axes[i], "gain": gain, "kept": keep, "parameters": names,
                    "undetermined": keep == 0.0})
    return out


def assess_conditioning(form: Formulation, xval: np.ndarray, lam: float, factored: Factored | None = None,
                        threshold: float = RELATIVE_SV_WARN) -> dict[str, Any] | None:
    """Conditioning of the error-model parameters at a solution, with warnings.

    Parameters
    ----------
    form : Formulation
    xval : ndarray
        The stacked solution.
    lam : float
    factored : Factored, optional
        Reused for the Schur complement (see :func:`information_matrix`).
    threshold : float
        Relative singular value below which a direction is reported.

    Returns
    -------
    dict or None
        None without error-model parameters. Else ``relative_singular_values``
        (ascending list), ``min_relative_sv``, ``condition`` (ratio of the largest to the
        smallest relative singular value, inf when one is 0), ``weak`` (list of
        ``{"parameters", "relative_sv"}`` below ``threshold``), ``degenerate_axes``
        (list of ``{"axis", "gain", "kept", "parameters", "undetermined", "message"}``;
        ``undetermined`` when the kept fraction is within ``KEPT_ZERO`` of zero, reported
        as 0: the axis's parameters are then inf/NaN), ``threshold`` and
        ``warnings`` (list of str).

    Notes
    -----
    See the module notes for the two criteria. A direction's parameters are those with
    a component of at least 0.2 in the unit direction.
    """
    model = form.model
    if model.q == 0:
        return None
    names = list(model.param_names)
    warn: list[str] = []
    try:
        H = information_matrix(form, lam, factored)
        sv, V = relative_singular_values(H)
    except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
        return {"relative_singular_values": None, "min_relative_sv": None, "condition": None,
                "weak": [], "degenerate_axes": [], "threshold": threshold,
                "warnings": [f"the conditioning of the error-model parameters could not be "
                             f"estimated ({exc})"]}
    weak = []
    for k in np.flatnonzero(sv < threshold):
        v = np.abs(V[:, k])
        who = [names[j] for j in np.flatnonzero(v >= _INVOLVED * v.max())]
        weak.append({"parameters": who, "relative_sv": float(sv[k])})
        if len(who) == 1:
            what = f"{who[0]} is nearly unobservable"
        else:
            what = (", ".join(who[:-1]) + f" and {who[-1]} are nearly indistinguishable")
        warn.append(f"{what} (relative singular value {sv[k]:.1e} < {threshold:g}): their "
                    "estimates are unreliable; add information that separates them or drop "
                    "one of them (e.g. ScaleFactor(axes=(...)) on the axes that feel varying "
                    "specific force)")
    l = model.split(xval)["l"]
    degenerate = _degenerate_axes(form, np.asarray(l, dtype=float))
    for dg in degenerate:
        who = dg["parameters"]
        dg["message"] = (
            f"sensor axis {dg['axis']}: the estimated correction keeps a fraction "
            + (f"0 (within {KEPT_ZERO:g} of zero) " if dg["undetermined"] else f"{dg['kept']:.2g} ")
            + f"of the measured signal (gain 1 + scale = {dg['gain']:.3g}): the "
            "data are explained best with no true specific force along this axis, so "
            + (", ".join(who[:-1]) + f" and {who[-1]} are" if len(who) > 1 else f"{who[0]} is")
            + " not determined and the reported values are meaningless; model no scale factor "
            f"on axis {dg['axis']} (ScaleFactor(axes=(...)) without {dg['axis']!r})"
        )
        warn.append(dg["message"])
    smin = float(sv[0]) if sv.size else None
    cond = float(sv[-1] / sv[0]) if sv.size and sv[0] > 0 else float("inf")
    return {"relative_singular_values": [float(s) for s in sv], "min_relative_sv": smin,
            "condition": cond, "weak": weak, "degenerate_axes": degenerate, "threshold": threshold,
            "warnings": warn}
