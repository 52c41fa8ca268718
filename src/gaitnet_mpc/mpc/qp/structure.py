"""Sparse-structure helpers: canonical CSC matrices and sparsity-pattern signatures.

A QP workspace decides between an in-place data update and a full re-setup by
comparing the :class:`SparsityPattern` of the matrices it hands to the backend
with the ones it saw last time.  Two canonical CSC matrices with equal patterns
store their nonzeros in the same order, so the new ``.data`` array can be passed
to the backend as-is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp


def canonical_csc(matrix: object) -> sp.csc_matrix:
    """Return ``matrix`` as a float64 ``scipy.sparse.csc_matrix`` in canonical format.

    Canonical means sorted row indices and no duplicate entries.  Explicit zeros
    are kept, so a caller can reserve nonzeros that are sometimes zero and keep
    the pattern (and hence the in-place update path) stable.  A matrix that is
    already a canonical float64 ``csc_matrix`` is returned without copying.
    Dense array-likes are accepted too (their zeros are *not* stored).
    """
    if isinstance(matrix, sp.csc_matrix) and matrix.dtype == np.float64:
        out = matrix
    elif sp.issparse(matrix):
        out = sp.csc_matrix(matrix, dtype=np.float64)
    else:
        out = sp.csc_matrix(np.asarray(matrix, dtype=np.float64))
    if not out.has_canonical_format:
        out = out.copy()
        out.sum_duplicates()
    return out


def triu_csc(matrix: sp.csc_matrix) -> sp.csc_matrix:
    """Upper-triangular part (diagonal included) of ``matrix`` as canonical CSC.

    OSQP, PIQP and Clarabel read only the upper triangle of the Hessian.
    Explicit zeros of the input are preserved.
    """
    return canonical_csc(sp.triu(matrix, format="csc"))


@dataclass(frozen=True, eq=False)
class SparsityPattern:
    """Shape and nonzero layout (``indptr``, ``indices``) of a canonical CSC matrix.

    Equality compares shape and index arrays element-wise, so tuples of patterns
    can be compared with ``==`` to detect a structure change.
    """

    shape: tuple[int, int]
    indptr: np.ndarray
    indices: np.ndarray

    @classmethod
    def of(cls, matrix: sp.csc_matrix | None) -> SparsityPattern | None:
        """Pattern of ``matrix`` (copied), or ``None`` when ``matrix`` is ``None``."""
        if matrix is None:
            return None
        shape = (int(matrix.shape[0]), int(matrix.shape[1]))
        return cls(shape, matrix.indptr.copy(), matrix.indices.copy())

    @property
    def nnz(self) -> int:
        """Number of stored entries."""
        return int(self.indices.size)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, SparsityPattern):
            return NotImplemented
        return (
            self.shape == other.shape
            and np.array_equal(self.indptr, other.indptr)
            and np.array_equal(self.indices, other.indices)
        )

    __hash__ = None  # type: ignore[assignment]
