"""Small helpers on sparse matrices and arrays shared by the model and the kernels.

They sit below :mod:`bvpnav.model` (which scales rows and converts to CSR) so that the
model and the terms never import the linear-algebra wing (:mod:`bvpnav.linalg`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["as_csr", "abs_max", "canonical", "row_scaled"]


def as_csr(A) -> sp.csr_matrix:
    """``A`` in CSR form, itself when it already is (``scipy.sparse.csr_matrix(A)`` copies
    even a CSR matrix)."""
    return A if sp.issparse(A) and A.format == "csr" else sp.csr_matrix(A)


def abs_max(v: np.ndarray) -> float:
    """``max |v|`` of a real array without its absolute-value copy (0 for an empty one)."""
    if not v.size:
        return 0.0
    if np.iscomplexobj(v):
        return float(np.max(np.abs(v)))
    return max(float(v.max()), -float(v.min()))


def canonical(A: sp.spmatrix) -> sp.csr_matrix:
    """``A`` as CSR without duplicates or explicit zeros (a copy when it had any: an explicit
    zero must not tie a row to a node). A matrix found canonical is marked with its data
    array, so that asking again (a lambda sweep's ``E`` at every point) does not scan it."""
    A = as_csr(A)
    if getattr(A, "_bvpnav_canonical", None) is A.data and A.has_canonical_format:
        return A
    if not A.has_canonical_format or (A.data.size and not np.all(A.data)):
        A = A.copy()
        A.sum_duplicates()
        A.eliminate_zeros()
    A._bvpnav_canonical = A.data
    return A


def row_scaled(A: sp.csr_matrix, k: np.ndarray, entries: np.ndarray | None = None) -> sp.csr_matrix:
    """``diag(k) A`` for a CSR ``A`` (a new matrix sharing ``A``'s index arrays, so in
    canonical format when ``A`` is), marked canonical when ``A`` is marked
    (:func:`canonical`) and no ``k`` is zero; ``entries`` (optional)
    is ``A``'s row of every stored entry, ``np.repeat(arange(m), diff(indptr))``."""
    rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr)) if entries is None else entries
    out = sp.csr_matrix((A.data * k[rows], A.indices, A.indptr), shape=A.shape)
    if A.has_canonical_format:   # the same sorted, unique indices
        out.has_canonical_format = True
    if getattr(A, "_bvpnav_canonical", None) is A.data and np.all(k):
        out._bvpnav_canonical = out.data
    return out
