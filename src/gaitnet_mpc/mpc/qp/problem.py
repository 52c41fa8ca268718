"""The one QP form every backend of the project solves.

.. math::

    \\min_x \\; \\tfrac12 x^T P x + q^T x
    \\quad \\text{s.t.} \\quad A_{eq} x = b_{eq},\\;
    l \\le A x \\le u,\\; lb \\le x \\le ub

Every constraint block is optional.  ``P`` is the *full symmetric* Hessian (both
triangles stored); backends that want only the upper triangle get it from the
workspace.  Bounds may contain ``±inf``; a missing ``l``/``u``/``lb``/``ub`` means
unbounded on that side.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from os import PathLike
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.qp.structure import canonical_csc

_MATRIX_FIELDS = ("P", "A_eq", "A")
_VECTOR_FIELDS = ("q", "b_eq", "l", "u", "lb", "ub")

#: Relative tolerance of the symmetry check on ``P`` in :meth:`QPProblem.validate`.
SYMMETRY_RTOL = 1e-9


def _as_vector(value: object) -> np.ndarray:
    """Coerce to a float64 ndarray without copying when already float64."""
    return np.asarray(value, dtype=np.float64)


@dataclass
class QPProblem:
    """Data of one convex QP (see module docstring for the form).

    Matrices are coerced to canonical float64 ``scipy.sparse.csc_matrix`` and
    vectors to float64 arrays on construction; shapes are checked only by
    :meth:`validate` (which :meth:`QPWorkspace.solve` calls by default).

    Attributes:
        P: Symmetric positive semidefinite Hessian, shape ``(n, n)``, both triangles.
        q: Linear cost, shape ``(n,)``.
        A_eq: Equality-constraint matrix, shape ``(m_eq, n)``; needs ``b_eq``.
        b_eq: Equality right-hand side, shape ``(m_eq,)``.
        A: Inequality-constraint matrix, shape ``(m_ineq, n)``; needs ``l`` or ``u``.
        l: Lower bounds on ``A x``, shape ``(m_ineq,)``, may hold ``-inf``.
        u: Upper bounds on ``A x``, shape ``(m_ineq,)``, may hold ``+inf``.
        lb: Lower bounds on ``x``, shape ``(n,)``, may hold ``-inf``.
        ub: Upper bounds on ``x``, shape ``(n,)``, may hold ``+inf``.
    """

    P: sp.csc_matrix
    q: np.ndarray
    A_eq: sp.csc_matrix | None = None
    b_eq: np.ndarray | None = None
    A: sp.csc_matrix | None = None
    l: np.ndarray | None = None
    u: np.ndarray | None = None
    lb: np.ndarray | None = None
    ub: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in _MATRIX_FIELDS:
            value = getattr(self, name)
            if value is not None:
                setattr(self, name, canonical_csc(value))
        for name in _VECTOR_FIELDS:
            value = getattr(self, name)
            if value is not None:
                setattr(self, name, _as_vector(value))

    # ------------------------------------------------------------------ sizes
    @property
    def n(self) -> int:
        """Number of decision variables."""
        return int(self.P.shape[0])

    @property
    def m_eq(self) -> int:
        """Number of equality rows (``A_eq``)."""
        return 0 if self.A_eq is None else int(self.A_eq.shape[0])

    @property
    def m_ineq(self) -> int:
        """Number of two-sided inequality rows (``A``)."""
        return 0 if self.A is None else int(self.A.shape[0])

    @property
    def m(self) -> int:
        """Number of general linear constraint rows, ``m_eq + m_ineq`` (box excluded)."""
        return self.m_eq + self.m_ineq

    @property
    def has_box(self) -> bool:
        """Whether ``lb`` or ``ub`` is given."""
        return self.lb is not None or self.ub is not None

    # ----------------------------------------------------------- full bounds
    def ineq_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(l, u)`` of the inequality rows with missing sides filled by ``∓inf``."""
        m = self.m_ineq
        l = np.full(m, -np.inf) if self.l is None else self.l
        u = np.full(m, np.inf) if self.u is None else self.u
        return l, u

    def box_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lb, ub)`` with missing sides filled by ``∓inf`` (all-infinite if no box)."""
        n = self.n
        lb = np.full(n, -np.inf) if self.lb is None else self.lb
        ub = np.full(n, np.inf) if self.ub is None else self.ub
        return lb, ub

    # ------------------------------------------------------------ validation
    def validate(self) -> None:
        """Check shapes, pairing of optional fields and finiteness.

        Raises:
            ConfigError: naming the offending field, the shape (or values) received
                and what was expected.  ``P``, ``q``, ``A_eq``, ``b_eq`` and ``A``
                must be finite; bounds may be infinite but not NaN; ``P`` must be
                square and symmetric.
        """
        P = self.P
        if P.ndim != 2 or P.shape[0] != P.shape[1]:
            raise ConfigError("P", P.shape, "a square shape (n, n)")
        n = self.n
        self._check_vector("q", (n,))
        if (self.A_eq is None) != (self.b_eq is None):
            missing = "b_eq" if self.b_eq is None else "A_eq"
            raise ConfigError(missing, None, "to be given together with the other of A_eq/b_eq")
        if self.A_eq is not None:
            self._check_matrix("A_eq", n)
            self._check_vector("b_eq", (self.m_eq,))
        if self.A is None:
            for name in ("l", "u"):
                if getattr(self, name) is not None:
                    raise ConfigError(name, "an array", "None because A is None")
        else:
            self._check_matrix("A", n)
            if self.l is None and self.u is None:
                raise ConfigError("l/u", None, "at least one of l, u when A is given")
            for name in ("l", "u"):
                self._check_vector(name, (self.m_ineq,), allow_inf=True)
        for name in ("lb", "ub"):
            self._check_vector(name, (n,), allow_inf=True)
        for name in ("P", "A_eq", "A"):
            matrix = getattr(self, name)
            if matrix is not None and not np.all(np.isfinite(matrix.data)):
                raise ConfigError(name, "non-finite entries", "finite values")
        asym = abs(P - P.T)
        if asym.nnz and asym.max() > SYMMETRY_RTOL * max(1.0, float(abs(P).max())):
            raise ConfigError("P", "a non-symmetric matrix", "the full symmetric Hessian")

    def _check_matrix(self, name: str, n: int) -> None:
        matrix = getattr(self, name)
        if matrix.ndim != 2 or matrix.shape[1] != n:
            raise ConfigError(name, matrix.shape, f"shape (rows, {n})")

    def _check_vector(self, name: str, shape: tuple[int, ...], *, allow_inf: bool = False) -> None:
        value = getattr(self, name)
        if value is None:
            return
        if value.shape != shape:
            raise ConfigError(name, value.shape, f"shape {shape}")
        bad = np.isnan(value) if allow_inf else ~np.isfinite(value)
        if np.any(bad):
            what = "no NaN (±inf allowed)" if allow_inf else "finite values"
            raise ConfigError(name, f"bad entries at {np.flatnonzero(bad)[:5].tolist()}", what)

    def crossed_bounds(self) -> str | None:
        """Name of the first bound pair with a lower bound above its upper bound, if any.

        Such a problem is trivially infeasible; workspaces report ``"infeasible"``
        without calling the backend.
        """
        if self.A is not None:
            l, u = self.ineq_bounds()
            if np.any(l > u):
                return "l/u"
        if self.has_box:
            lb, ub = self.box_bounds()
            if np.any(lb > ub):
                return "lb/ub"
        return None

    # ------------------------------------------------------- evaluations
    def objective(self, x: np.ndarray) -> float:
        """Cost ``0.5 x^T P x + q^T x``."""
        return float(0.5 * x @ (self.P @ x) + self.q @ x)

    def primal_residual(self, x: np.ndarray) -> float:
        """Largest constraint violation at ``x`` (max-norm, ``0.0`` if feasible)."""
        worst = 0.0
        if self.A_eq is not None and self.m_eq:
            worst = max(worst, float(np.max(np.abs(self.A_eq @ x - self.b_eq))))
        if self.A is not None and self.m_ineq:
            l, u = self.ineq_bounds()
            ax = self.A @ x
            worst = max(worst, float(np.max(np.maximum(l - ax, ax - u))))
        if self.has_box:
            lb, ub = self.box_bounds()
            worst = max(worst, float(np.max(np.maximum(lb - x, x - ub))))
        return max(worst, 0.0)

    # ---------------------------------------------------------- conversions
    def to_osqp_form(
        self, include_box: bool = True
    ) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray]:
        """Stack every constraint as ``l_all <= A_all x <= u_all``.

        Row order: equality rows (``l = u = b_eq``), then inequality rows, then, with
        ``include_box`` and a box given, one identity row per variable (all ``n`` rows,
        infinite sides kept, so the pattern does not depend on which bounds are finite).

        Returns:
            ``(A_all, l_all, u_all)`` with ``A_all`` a canonical CSC of shape
            ``(m_eq + m_ineq + n_box, n)`` (``n_box = 0`` without ``include_box``).
        """
        n = self.n
        blocks: list[sp.csc_matrix] = []
        lows: list[np.ndarray] = []
        ups: list[np.ndarray] = []
        if self.A_eq is not None:
            assert self.b_eq is not None  # given together (__post_init__)
            blocks.append(self.A_eq)
            lows.append(self.b_eq)
            ups.append(self.b_eq)
        if self.A is not None:
            l, u = self.ineq_bounds()
            blocks.append(self.A)
            lows.append(l)
            ups.append(u)
        if include_box and self.has_box:
            lb, ub = self.box_bounds()
            blocks.append(sp.identity(n, format="csc"))
            lows.append(lb)
            ups.append(ub)
        if not blocks:
            return sp.csc_matrix((0, n)), np.zeros(0), np.zeros(0)
        a_all = blocks[0] if len(blocks) == 1 else sp.vstack(blocks, format="csc")
        return canonical_csc(a_all), np.concatenate(lows), np.concatenate(ups)

    # --------------------------------------------------------------- files
    def save_npz(self, path: str | PathLike[str]) -> None:
        """Write the problem to an ``.npz`` file (no pickling; absent fields omitted)."""
        arrays: dict[str, np.ndarray] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None:
                continue
            if f.name in _MATRIX_FIELDS:
                arrays[f"{f.name}__data"] = value.data
                arrays[f"{f.name}__indices"] = value.indices
                arrays[f"{f.name}__indptr"] = value.indptr
                arrays[f"{f.name}__shape"] = np.asarray(value.shape, dtype=np.int64)
            else:
                arrays[f.name] = value
        with Path(path).open("wb") as fh:  # a handle keeps numpy from appending ".npz"
            np.savez(fh, **arrays)  # type: ignore[arg-type]  # stubs: **kwds may hit allow_pickle

    @classmethod
    def load_npz(cls, path: str | PathLike[str]) -> QPProblem:
        """Read a problem written by :meth:`save_npz`."""
        kwargs: dict[str, object] = {}
        with np.load(Path(path), allow_pickle=False) as data:
            for f in fields(cls):
                if f.name in _MATRIX_FIELDS:
                    if f"{f.name}__data" in data:
                        shape = tuple(int(s) for s in data[f"{f.name}__shape"])
                        kwargs[f.name] = sp.csc_matrix(
                            (
                                data[f"{f.name}__data"],
                                data[f"{f.name}__indices"],
                                data[f"{f.name}__indptr"],
                            ),
                            shape=shape,
                        )
                elif f.name in data:
                    kwargs[f.name] = np.array(data[f.name])
        if "P" not in kwargs or "q" not in kwargs:
            raise ConfigError("path", str(path), "an .npz written by QPProblem.save_npz")
        return cls(**kwargs)  # type: ignore[arg-type]
