"""Condensing: eliminate the equality rows (and fixed variables) of a :class:`QPProblem`.

Variable elimination.  The equality rows ``A_eq x = b_eq`` (``m_eq`` rows of full row
rank) are solved for a set ``D`` of ``m_eq`` *dependent* columns whose block
``A_D = A_eq[:, D]`` is invertible.  Optionally a set ``Phi`` of variables with known
values ``v`` (*fixed* variables, e.g. ``lb = ub``; see :func:`fixed_variables`) is
substituted too.  The remaining columns ``F`` are the condensed variables ``u = x_F``::

    x_D = T u + t,      T = -A_D^{-1} A_F,   t = A_D^{-1} (b_eq - A_Phi v),   x_Phi = v

so every feasible ``x`` is ``x = Z u + z`` with ``Z`` the columns ``[T; I; 0]`` and
``z = [t; 0; v]`` scattered to ``D``, ``F`` and ``Phi``.  For an MPC whose equality rows
are the dynamics, ``D`` are the states and ``F`` the inputs (the classical "condensed"
MPC); with the states in stage order ``A_D`` is lower triangular with a unit diagonal
and ``T`` comes from one triangular solve.

Substituting gives the dense QP in ``u`` (``n_F`` variables, no equality rows)::

    min_u 0.5 u^T H u + f^T u + c
    s.t.  l_r - s_r  <= (A_F + A_D T)_r u  <= u_r - s_r,   s = A_D t + A_Phi v  (rows of A)
          lb_D - t   <= T u                <= ub_D - t     (finite box rows of D)
          lb_F       <= u                  <= ub_F

    H = Z^T P Z,   f = Z^T (P z + q),   c = 0.5 z^T P z + q^T z

(for a diagonal ``P``: ``H = P_FF + T^T P_DD T``, ``f = q_F + T^T (q_D + P_DD t)``).
Rows whose condensed coefficients are all zero (they only touch fixed variables or
states fixed by the equality rows) are constants and are dropped; their worst violation
is kept in :attr:`CondensedQP.dropped_violation` (> 0 means the problem is infeasible).
The kept rows are listed in :attr:`CondensedQP.rows`, so two problems of one sparsity
structure and one fixed set condense to the same rows, which a dual warm start of an
active-set solver (DAQP) needs.  The transformation is exact: the original objective of
``expand(u)`` is the condensed one plus ``c`` (up to rounding).  Units are the
problem's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.qp.problem import QPProblem

#: Relative tolerance of the singularity / rank / consistency checks.
RANK_RTOL = 1e-10


@dataclass(frozen=True)
class FixedVariables:
    """Variables with a known value: ``x[mask] = values[mask]`` (other entries unused)."""

    mask: np.ndarray
    values: np.ndarray

    @classmethod
    def none(cls, n: int) -> FixedVariables:
        """No fixed variable among ``n``."""
        return cls(np.zeros(n, dtype=bool), np.zeros(n))


@dataclass(frozen=True)
class CondensedQP:
    """A dense QP without equality rows and the map back to the original variables.

    Attributes:
        H: (n_F, n_F) dense Hessian, symmetric positive (semi)definite.
        f: (n_F,) linear cost.
        constant: objective offset ``c`` (original objective = condensed one + ``c``).
        A: (m, n_F) dense C-contiguous rows: the kept rows of the original ``A``, then
            the kept finite box rows of the dependent variables.
        l: (m,) lower bounds of ``A u`` (may hold ``-inf``).
        u: (m,) upper bounds of ``A u`` (may hold ``+inf``).
        lb: (n_F,) lower box of the condensed variables (may hold ``-inf``).
        ub: (n_F,) upper box of the condensed variables (may hold ``+inf``).
        free: (n_F,) columns ``F`` of the original problem, increasing.
        dependent: (m_eq,) columns ``D``, in the order of the rows of ``T``.
        fixed: the substituted variables ``Phi``.
        T: (m_eq, n_F) ``x_D = T u + t``.
        t: (m_eq,) offset of the dependent variables.
        rows: indices of the kept rows: ``i < m_ineq`` is row ``i`` of the original
            ``A``, ``m_ineq + j`` the box of dependent column ``dependent[j]``.
        dropped_violation: largest violation of a dropped constant row (0 if none).
        n: number of variables of the original problem.
    """

    H: np.ndarray
    f: np.ndarray
    constant: float
    A: np.ndarray
    l: np.ndarray
    u: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    free: np.ndarray
    dependent: np.ndarray
    fixed: FixedVariables
    T: np.ndarray
    t: np.ndarray
    rows: np.ndarray
    dropped_violation: float
    n: int

    @property
    def n_free(self) -> int:
        """Number of condensed variables ``n_F``."""
        return int(self.free.size)

    def expand(self, u: np.ndarray) -> np.ndarray:
        """The original variables ``x`` (n,) of the condensed point ``u`` (n_F,)."""
        x = np.where(self.fixed.mask, self.fixed.values, 0.0)
        x[self.free] = u
        x[self.dependent] = self.T @ u + self.t
        return x

    def reduce(self, x: np.ndarray) -> np.ndarray:
        """The condensed variables ``u = x_F`` of an original point ``x`` (n,)."""
        return np.asarray(x, dtype=np.float64)[self.free]

    def objective(self, u: np.ndarray) -> float:
        """Condensed cost ``0.5 u^T H u + f^T u`` (without :attr:`constant`)."""
        return float(0.5 * u @ (self.H @ u) + self.f @ u)

    def to_problem(self) -> QPProblem:
        """The condensed QP as a :class:`QPProblem` (sparse storage of the dense data),
        for backends of :func:`~gaitnet_mpc.mpc.qp.make_workspace`."""
        return QPProblem(
            sp.csc_matrix(self.H),
            self.f,
            A=sp.csc_matrix(self.A),
            l=self.l,
            u=self.u,
            lb=self.lb,
            ub=self.ub,
        )


def _singular() -> ConfigError:
    return ConfigError("dependent", "a singular A_eq[:, dependent]", "an invertible block")


def _lower_triangular(a_eq: sp.csc_matrix, dep: np.ndarray) -> bool:
    """Whether ``A_eq[:, dep]`` is lower triangular, from the stored pattern only."""
    pos = np.full(a_eq.shape[1], -1)
    pos[dep] = np.arange(dep.size)
    col_pos = np.repeat(pos, np.diff(a_eq.indptr))  # position in dep of each entry's column
    stored = col_pos >= 0
    return bool(np.all(a_eq.indices[stored] >= col_pos[stored]))


def _eliminate(a_d: np.ndarray, rhs: np.ndarray, lower: bool) -> np.ndarray:
    """``A_D^{-1} rhs``: a triangular solve when ``A_D`` is lower triangular (an MPC's
    dynamics with the states in stage order), else a dense LU solve.

    Raises:
        ConfigError: ``A_D`` is singular.
    """
    if lower:
        d = np.abs(np.diag(a_d))
        if not d.min(initial=1.0) > RANK_RTOL * max(float(d.max(initial=0.0)), 1.0):
            raise _singular()
        sol = la.solve_triangular(a_d, rhs, lower=True, check_finite=False)
    else:
        lu, piv = la.lu_factor(a_d, check_finite=False)
        d = np.abs(np.diag(lu))
        if not d.min(initial=1.0) > RANK_RTOL * max(float(d.max(initial=0.0)), 1.0):
            raise _singular()
        sol = la.lu_solve((lu, piv), rhs, check_finite=False)
    if not np.all(np.isfinite(sol[:, -1])):  # an exactly singular pivot spreads to all
        raise _singular()
    return np.asarray(sol)


def choose_dependent(problem: QPProblem) -> np.ndarray:
    """Columns ``D`` that make ``A_eq[:, D]`` square and invertible, preferring columns
    without a finite box bound (whose box would otherwise become general rows).

    A dense QR factorisation with column pivoting of ``A_eq`` (of the unbounded columns
    if they suffice); meant to run once per sparsity structure, not per solve.

    Raises:
        ConfigError: ``problem`` has no equality rows, or they are rank deficient.
    """
    if problem.A_eq is None or problem.m_eq == 0:
        raise ConfigError("A_eq", None, "equality rows to condense")
    a_eq = problem.A_eq.toarray()
    m = problem.m_eq
    lb, ub = problem.box_bounds()
    bounded = np.isfinite(lb) | np.isfinite(ub)
    for cols in (np.flatnonzero(~bounded), np.arange(problem.n)):
        if cols.size < m:
            continue
        _, r, piv = la.qr(a_eq[:, cols], mode="economic", pivoting=True)
        d = np.abs(np.diag(r))
        if d.size >= m and d[m - 1] > RANK_RTOL * max(d[0], 1.0):
            return np.sort(cols[piv[:m]])
    raise ConfigError("A_eq", "rank-deficient rows", "equality rows of full row rank")


@dataclass(frozen=True)
class _RowGroups:
    """Groups of equality-like rows (``l == u``) with one shared column support, usable to
    fix their columns, batched by shape: per shape ``(cols (g, nc), rows (g, nr))``, rows
    as indices into the problem's ``A``."""

    batches: tuple[tuple[np.ndarray, np.ndarray], ...]


def _row_groups(a: sp.csc_matrix, eq_rows: np.ndarray, allowed: np.ndarray) -> _RowGroups:
    """The :class:`_RowGroups` of rows ``eq_rows`` of ``a`` (stored pattern)."""
    n = a.shape[1]
    sub = a.tocsr()[eq_rows]
    k = eq_rows.size
    support = np.zeros((k, n), dtype=bool)  # structural support (stored entries)
    support[np.repeat(np.arange(k), np.diff(sub.indptr)), sub.indices] = True
    keys: dict[bytes, int] = {}
    group_of = np.array(
        [keys.setdefault(row.tobytes(), len(keys)) for row in np.packbits(support, axis=1)]
    )
    _, first = np.unique(group_of, return_index=True)
    patterns = support[first]  # (G, n) column support of each group
    n_cols = patterns.sum(axis=1)
    n_rows = np.bincount(group_of, minlength=len(keys))
    usable = (n_cols > 0) & (n_rows >= n_cols) & ~np.any(patterns & ~allowed, axis=1)
    rows_sorted = eq_rows[np.argsort(group_of, kind="stable")]
    row_start = np.concatenate([[0], np.cumsum(n_rows)[:-1]])
    batches = []
    for shape in sorted({(int(n_rows[g]), int(n_cols[g])) for g in np.flatnonzero(usable)}):
        gs = np.flatnonzero(usable & (n_rows == shape[0]) & (n_cols == shape[1]))
        cols = np.nonzero(patterns[gs])[1].reshape(gs.size, shape[1])
        rows = rows_sorted[row_start[gs][:, None] + np.arange(shape[0])]
        batches.append((cols, rows))
    return _RowGroups(tuple(batches))


class FixedVariableFinder:
    """Finds the variables that the constraints fix to one value (see
    :meth:`__call__`), remembering the row grouping per structure.

    The grouping depends only on the sparsity pattern of ``A``, on which rows have
    ``l == u`` and on ``exclude``; for an MPC these change with the contact schedule only,
    so the QPs of one sequential solve reuse it.  The cache holds at most ``cache_size``
    structures (oldest dropped first).
    """

    def __init__(self, cache_size: int = 64) -> None:
        self.cache_size = int(cache_size)
        self._cache: dict[bytes, _RowGroups] = {}

    def __call__(self, problem: QPProblem, exclude: np.ndarray | None = None) -> FixedVariables:
        """Variables fixed by the constraints of ``problem``, outside ``exclude`` (columns).

        * a box with ``lb == ub`` (fixed to ``lb``);
        * a group of inequality rows with ``l == u`` that share one column support (stored
          pattern) and have full column rank on it, e.g. ``C (w^j + dw) = 0`` for a
          swing foot's wrench: its columns are fixed to the group's least-squares
          solution (a group whose equations are inconsistent is left to the solver,
          which will report the infeasibility).
        """
        n = problem.n
        lb, ub = problem.box_bounds()
        mask = (lb == ub) & np.isfinite(lb)
        values = np.where(mask, lb, 0.0)
        allowed = np.ones(n, dtype=bool)
        if exclude is not None:
            allowed[np.asarray(exclude, dtype=int)] = False
        mask &= allowed
        if problem.A is None or problem.m_ineq == 0:
            return FixedVariables(mask, np.where(mask, values, 0.0))
        a = problem.A
        l_in, u_in = problem.ineq_bounds()
        is_eq = (l_in == u_in) & np.isfinite(l_in)
        key = b"".join(
            (is_eq.tobytes(), allowed.tobytes(), a.indptr.tobytes(), a.indices.tobytes())
        )
        groups = self._cache.get(key)
        if groups is None:
            groups = _row_groups(a, np.flatnonzero(is_eq), allowed)
            if len(self._cache) >= self.cache_size:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = groups
        a_dense = a.toarray() if groups.batches else np.zeros((0, n))
        for cols, rows in groups.batches:
            c = a_dense[rows[:, :, None], cols[:, None, :]]  # (g, nr, nc)
            b = l_in[rows]
            u_svd, sv, vt = np.linalg.svd(c, full_matrices=False)  # batched
            rank_ok = sv[:, -1] > RANK_RTOL * np.maximum(sv[:, 0], 1.0)
            coef = np.einsum("gji,gj->gi", u_svd, b) / np.where(rank_ok[:, None], sv, 1.0)
            x = np.einsum("gji,gj->gi", vt, coef)  # least-squares solution
            resid = np.abs(np.einsum("gij,gj->gi", c, x) - b).max(axis=1)
            scale = np.maximum(np.abs(b).max(axis=1), 1.0)
            ok = rank_ok & (resid <= 1e-9 * scale)
            cols_ok = cols[ok].ravel()
            x_ok = x[ok].ravel()
            values[cols_ok] = np.where(mask[cols_ok], values[cols_ok], x_ok)  # box wins
            mask[cols_ok] = True
        return FixedVariables(mask, np.where(mask, values, 0.0))


def fixed_variables(problem: QPProblem, exclude: np.ndarray | None = None) -> FixedVariables:
    """:meth:`FixedVariableFinder.__call__` without a cache across problems."""
    return FixedVariableFinder(cache_size=1)(problem, exclude)


def condense(
    problem: QPProblem,
    dependent: np.ndarray | None = None,
    fixed: FixedVariables | None = None,
) -> CondensedQP:
    """Eliminate the equality rows (and ``fixed`` variables) of ``problem``.

    See the module docstring for the equations.

    Args:
        problem: the QP; must have equality rows of full row rank.
        dependent: (m_eq,) columns to eliminate, ``A_eq[:, dependent]`` invertible (for
            an MPC: the state columns); ``None``: :func:`choose_dependent`.
        fixed: variables to substitute by known values (none of them dependent), e.g.
            :func:`fixed_variables`; ``None``: none.

    Returns:
        The :class:`CondensedQP`.

    Raises:
        ConfigError: no equality rows, a wrong number of dependent columns, a fixed
            dependent column, or a singular ``A_eq[:, dependent]``.
    """
    if problem.A_eq is None or problem.b_eq is None or problem.m_eq == 0:
        raise ConfigError("A_eq", None, "equality rows to condense")
    n = problem.n
    dep = choose_dependent(problem) if dependent is None else np.asarray(dependent, dtype=int)
    is_dep = np.zeros(n, dtype=bool)
    is_dep[dep] = True
    if dep.shape != (problem.m_eq,) or np.count_nonzero(is_dep) != dep.size:
        raise ConfigError("dependent", dep.shape, f"{problem.m_eq} distinct column indices")
    fix = FixedVariables.none(n) if fixed is None else fixed
    if fix.mask[dep].any():
        raise ConfigError("fixed", "a dependent column", "only non-dependent columns")
    free = np.flatnonzero(~is_dep & ~fix.mask)
    phi = np.flatnonzero(fix.mask)
    v = fix.values[phi]

    # ---- elimination: x_D = T u + t
    a_eq = problem.A_eq.toarray()
    rhs = np.empty((problem.m_eq, free.size + 1), order="F")  # LAPACK's column order
    rhs[:, :-1] = a_eq[:, free]
    rhs[:, -1] = problem.b_eq - a_eq[:, phi] @ v
    sol = _eliminate(np.asfortranarray(a_eq[:, dep]), rhs, _lower_triangular(problem.A_eq, dep))
    T = -sol[:, :-1]
    t = sol[:, -1]
    z = np.where(fix.mask, fix.values, 0.0)  # x = Z u + z
    z[dep] = t

    # ---- cost
    P = problem.P
    q = problem.q
    p_diag = P.diagonal()
    if P.nnz == np.count_nonzero(p_diag):
        p_dd = p_diag[dep]
        H = T.T @ (p_dd[:, None] * T)
        H[np.diag_indices_from(H)] += p_diag[free]
        f = q[free] + T.T @ (q[dep] + p_dd * t)
        pz = p_diag * z
    else:
        Z = np.zeros((n, free.size))
        Z[free, np.arange(free.size)] = 1.0
        Z[dep] = T
        pz = P @ z
        H = Z.T @ np.asarray(P @ Z)
        H = 0.5 * (H + H.T)
        f = Z.T @ (pz + q)
    constant = float(0.5 * z @ pz + q @ z)

    # ---- constraint rows
    lb, ub = problem.box_bounds()
    m_ineq = problem.m_ineq
    blocks: list[np.ndarray] = []
    lows: list[np.ndarray] = []
    ups: list[np.ndarray] = []
    if problem.A is not None and m_ineq:
        l_in, u_in = problem.ineq_bounds()
        a_in = problem.A.toarray()
        a_c = a_in[:, free]
        if np.diff(problem.A.indptr)[dep].any():  # rows of A touch dependent columns
            a_c = a_c + a_in[:, dep] @ T
        shift = a_in @ z
        blocks.append(a_c)
        lows.append(l_in - shift)
        ups.append(u_in - shift)
    boxed = np.flatnonzero(np.isfinite(lb[dep]) | np.isfinite(ub[dep]))
    blocks.append(T[boxed])
    lows.append(lb[dep][boxed] - t[boxed])
    ups.append(ub[dep][boxed] - t[boxed])
    a_all = np.vstack(blocks)
    l_all = np.concatenate(lows)
    u_all = np.concatenate(ups)
    row_ids = np.concatenate([np.arange(m_ineq), m_ineq + boxed])
    live = np.any(a_all != 0.0, axis=1)
    dropped = 0.0
    if not live.all():  # constant rows: 0 must lie in [l, u]
        dead = ~live
        dropped = float(max(np.max(l_all[dead], initial=0.0), np.max(-u_all[dead], initial=0.0)))
    return CondensedQP(
        H=np.ascontiguousarray(H),
        f=np.asarray(f, dtype=np.float64),
        constant=constant,
        A=np.ascontiguousarray(a_all[live]),
        l=l_all[live],
        u=u_all[live],
        lb=lb[free].copy(),
        ub=ub[free].copy(),
        free=free,
        dependent=dep,
        fixed=fix,
        T=T,
        t=t,
        rows=row_ids[live],
        dropped_violation=max(dropped, 0.0),
        n=n,
    )


__all__ = [
    "RANK_RTOL",
    "CondensedQP",
    "FixedVariableFinder",
    "FixedVariables",
    "choose_dependent",
    "condense",
    "fixed_variables",
]
