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

    def __post_init__(self) -> None:
        # byte images of the index arrays: comparing them is one memcmp, cheaper than
        # np.array_equal (patterns are compared on every solve of a workspace)
        key = (self.indptr.tobytes(), self.indices.tobytes())
        object.__setattr__(self, "_key", key)

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
        if self.shape != other.shape:
            return False
        if self.indptr.dtype == other.indptr.dtype and self.indices.dtype == other.indices.dtype:
            return bool(self._key == other._key)  # type: ignore[attr-defined]
        return np.array_equal(self.indptr, other.indptr) and np.array_equal(
            self.indices, other.indices
        )

    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class EntrySelection:
    """A sub-matrix of a canonical CSC matrix as a position map into its ``data``.

    Built once per sparsity pattern: :attr:`positions` lists, in the sub-matrix's own
    canonical order, where each of its entries sits in the source's ``data``, so the
    sub-matrix of any matrix with the :attr:`source` pattern is
    ``(source.data[positions], pattern)``, with no sparse-matrix operation per call.
    Explicit zeros are kept.

    Attributes:
        source: pattern the map was built for.
        positions: (nnz_sub,) int positions into the source's ``data``.
        pattern: pattern of the sub-matrix.
    """

    source: SparsityPattern
    positions: np.ndarray
    pattern: SparsityPattern

    @classmethod
    def upper_triangle(cls, matrix: sp.csc_matrix) -> EntrySelection:
        """Upper triangle, diagonal included (what :func:`triu_csc` returns)."""
        source = SparsityPattern.of(matrix)
        assert source is not None
        cols = np.repeat(np.arange(source.shape[1]), np.diff(source.indptr))
        keep = source.indices <= cols
        return cls._select(source, keep, cols, source.indices, source.shape[0])

    @classmethod
    def rows(cls, matrix: sp.csc_matrix, keep_rows: np.ndarray) -> EntrySelection:
        """The rows where ``keep_rows`` (bool, one per row) is True, renumbered in order
        (what ``canonical_csc(matrix[np.flatnonzero(keep_rows)])`` returns)."""
        source = SparsityPattern.of(matrix)
        assert source is not None
        keep_rows = np.asarray(keep_rows, dtype=bool)
        cols = np.repeat(np.arange(source.shape[1]), np.diff(source.indptr))
        new_row = np.cumsum(keep_rows) - 1
        keep = keep_rows[source.indices]
        return cls._select(source, keep, cols, new_row[source.indices], int(keep_rows.sum()))

    @classmethod
    def _select(
        cls,
        source: SparsityPattern,
        keep: np.ndarray,
        cols: np.ndarray,
        rows: np.ndarray,
        n_rows: int,
    ) -> EntrySelection:
        positions = np.flatnonzero(keep)
        counts = np.bincount(cols[positions], minlength=source.shape[1])
        indptr = np.concatenate([[0], np.cumsum(counts)]).astype(source.indptr.dtype)
        indices = rows[positions].astype(source.indices.dtype)
        pattern = SparsityPattern((n_rows, source.shape[1]), indptr, indices)
        return cls(source, positions, pattern)

    def matrix(self, data: np.ndarray) -> sp.csc_matrix:
        """A new canonical CSC sub-matrix holding ``data`` (sub-matrix order, not copied)."""
        p = self.pattern
        out = sp.csc_matrix((data, p.indices.copy(), p.indptr.copy()), shape=p.shape)
        out.has_canonical_format = True
        return out
