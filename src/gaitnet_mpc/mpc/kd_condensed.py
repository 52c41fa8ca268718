"""The CMPC QP condensed to its free variables and solved by a dense active set (DAQP).

The sparse QP of :mod:`~gaitnet_mpc.mpc.implicit_kd` keeps every state as a variable:
345 variables, 165 equality rows, a box on each variable. Most of them are determined
by the constraints, and eliminating them leaves a small dense QP that an active-set
method solves in a fraction of an interior point's time
(``benchmarks/results/kd_qp_condensed.md``). Eliminated, with ``z`` the sparse QP's
variables (layout :class:`~gaitnet_mpc.mpc.kd_layout.KDLayout`):

* **the states** ``x_k`` and ``delta p_c,k`` (the dynamics, eqs. 14-15, 19-20). In stage
  order the equality rows are lower triangular with a unit diagonal in these columns
  (``A_S``), so ``z_S = A_S^{-1} (b_eq - A_I z_I)`` with ``I`` the other columns;
* **a swing foot's wrench**: its rows ``C (w^j + delta w) = 0`` have full column rank
  (:mod:`~gaitnet_mpc.mpc.contact`), so ``delta w = -w^j``;
* **the foot ties**: a tie group (the stages of one swing and the stance after it, or
  the measured stance) has one position, so ``delta p_f,k = delta p_f,k0 + p_f,k0^j -
  p_f,k^j`` from the group's first stage ``k0``, and its tie rows hold by construction;
* **fixed axes** (box ``lb = ub``: the measured stance foot, heights taken from the
  reference).

What remains, ``u``, is the wrench of every stance foot and stage and the free axes of
the other tie groups: 90-100 variables for ``h = 10``. With ``z = M u + m``::

    min_u 0.5 u^T (M^T P M) u + (M^T (P m + q))^T u
    s.t.  l - A m <= A M u <= u - A m     (stance wrench rows, separation rows)
          lb_z - m_S <= M_S u <= ub_z - m_S  (finite boxes on states, e.g. the CoM trust
                                            region)
          box of each group's first stage    (eq. 24 and the trust region, on u)

The objective and the feasible set are those of the sparse QP restricted to the
eliminated variables' values, so the minimiser is the same (checked against PIQP on
recorded problems in ``tests/test_kd_condensed.py``). ``M`` comes from a forward
substitution over the stages with ``n_u + 1`` right-hand sides; products with the input
rows of ``M`` (copies of ``u``) are scatter-adds of the sparse QP's stored entries into
their ``u`` columns (``np.bincount``, maps made once per structure), not matrix products.

The remaining products (``M_S^T P_S M_S``: 66 x 150 x 66) are small enough that
OpenBLAS's threads cost more than they save: on this 2-core machine, loaded by another
process, a condensing took 6 ms with two BLAS threads and 0.6 ms with one. :meth:`solve`
therefore runs with BLAS limited to one thread (``threadpoolctl``, ~10 us per solve) and
restores the process's setting afterwards.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from threadpoolctl import ThreadpoolController

from gaitnet_mpc.errors import ConfigError, reraise_interrupt
from gaitnet_mpc.mpc.centroidal_model import N_FEET, NX
from gaitnet_mpc.mpc.kd_layout import KDLayout
from gaitnet_mpc.mpc.qp import QPProblem
from gaitnet_mpc.mpc.qp.solution import QPSolution

try:
    import daqp
except ImportError as _exc:  # pragma: no cover - depends on the environment
    reraise_interrupt(_exc)
    daqp = None

_NS = NX + 3  # state rows (and columns) per stage: x_k, delta p_c,k
_SENSE_EQUALITY = 5  # DAQP's flag of an equality row (l == u)
_CACHE_SIZE = 64  # condensing structures kept, keyed by contact schedule and fixed axes
#: DAQP exit flags: 1 optimal, 2 soft-optimal; the rest are failures.
_SOLVED = {1: "solved", 2: "solved_inaccurate"}


def _dense(shape: tuple[int, ...], put: np.ndarray, values: np.ndarray) -> np.ndarray:
    """A zero array of ``shape`` with ``values`` at the flat positions ``put``."""
    out = np.zeros(shape)
    out.reshape(-1)[put] = values
    return out


@dataclass(frozen=True)
class _Pattern:
    """Row and column of each stored entry of a CSC matrix, in ``data`` order."""

    indptr: np.ndarray
    indices: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    shape: tuple[int, int]

    @classmethod
    def empty(cls) -> _Pattern:
        none = np.zeros(0, dtype=np.int64)
        return cls(none, none, none, none, (0, 0))

    @classmethod
    def of(cls, a: Any) -> _Pattern:
        cols = np.repeat(np.arange(a.shape[1]), np.diff(a.indptr))
        return cls(a.indptr.copy(), a.indices.copy(), a.indices.astype(np.int64), cols, a.shape)

    def matches(self, a: Any) -> bool:
        """Whether ``a`` has this pattern (cheap checks first)."""
        return (
            a.shape == self.shape
            and a.indices.size == self.indices.size
            and np.array_equal(a.indptr, self.indptr)
            and np.array_equal(a.indices, self.indices)
        )


@dataclass(frozen=True)
class _Structure:
    """What the eliminations of one contact schedule and one set of fixed axes keep.

    ``M_I`` (the input rows of ``M``) is a 0/1 matrix: each free input is a copy of one
    ``u``. Products with it are sums over each ``u``'s copies (scatter-adds of a sparse
    matrix's entries, or gathers of a vector over the free inputs sorted by ``u``).

    Attributes:
        free: (n_I,) bool, inputs (``I`` columns) that are a free variable or a copy of
            one (a tie group's later stages);
        base: (n_I,) input position (in ``I``) of the group's first stage for foot
            positions, the input itself otherwise;
        by_u: the free inputs (positions in ``I``), sorted by their ``u``;
        u_start: (n_u,) first entry of each ``u`` in ``by_u``;
        u_source: (n_u,) input position whose box bounds ``u``;
        rows: kept inequality rows (stance wrench rows, separation rows);
        n_u: number of condensed variables;
        eq_take, eq_put: the entries of ``A_eq.data`` in free input columns, and their flat
            positions in the (m_eq, n_u + 1) right-hand side ``A_I M_I`` (column ``u``);
        a_take, a_put: the same for ``A.data`` in kept rows, into (kept rows, n_u);
        a_m_take, a_m_row, a_m_input: the entries of ``A.data`` in kept rows and any input
            column, their kept row and their input position (for ``A m``);
        p_input_u: (n_u,) ``sum P_I`` over each ``u``'s copies (``M_I^T P_I M_I``, diagonal).
    """

    free: np.ndarray
    base: np.ndarray
    by_u: np.ndarray
    u_start: np.ndarray
    u_of_input: np.ndarray
    u_source: np.ndarray
    rows: np.ndarray
    n_u: int
    eq_take: np.ndarray
    eq_put: np.ndarray
    a_take: np.ndarray
    a_put: np.ndarray
    a_m_take: np.ndarray
    a_m_row: np.ndarray
    a_m_input: np.ndarray
    p_input_u: np.ndarray

    def sum_by_u(self, values: np.ndarray) -> np.ndarray:
        """``M_I^T values`` (n_u,) for ``values`` (n_I,): each ``u``'s copies summed."""
        return np.add.reduceat(values[self.by_u], self.u_start)


@dataclass(frozen=True)
class CondensedQP:
    """The dense QP of one sparse CMPC QP, in DAQP's form, and the way back.

    Attributes:
        qp: ``daqp.solve``'s ``H, f, A, bupper, blower, sense`` (the first ``n_u``
            bounds are the box on ``u``).
        m_input: (n_I,) ``m`` on the inputs (``z_I = M_I u + m_I``).
        m_mat_state, m_state: ``z_S = M_S u + m_S``.
    """

    qp: dict[str, np.ndarray]
    structure: _Structure
    m_input: np.ndarray
    m_mat_state: np.ndarray
    m_state: np.ndarray
    cols_input: np.ndarray
    cols_state: np.ndarray
    n: int

    @property
    def n_u(self) -> int:
        """Number of condensed variables."""
        return self.structure.n_u

    def expand(self, u: np.ndarray) -> np.ndarray:
        """The sparse QP's variables ``z = M u + m`` (n,) of a condensed point ``u``."""
        st = self.structure
        z = np.empty(self.n)
        z_i = self.m_input.copy()
        z_i[st.free] += u[st.u_of_input[st.free]]
        z[self.cols_input] = z_i
        z[self.cols_state] = self.m_mat_state @ u + self.m_state
        return z


class KDCondensed:
    """Condenses the sparse CMPC QP (see the module docstring) and solves it with DAQP.

    Args:
        layout: the sparse QP's variable layout.
        n_wrench_rows: inequality rows per foot and stage (the wrench rows come first,
            stage by stage, foot by foot).
        n_sep_rows: separation rows at the end of the inequality rows (0 or ``h``).
        daqp_options: ``daqp.solve`` settings.

    Raises:
        ConfigError: DAQP is not installed.
    """

    backend = "daqp-condensed"

    def __init__(
        self,
        layout: KDLayout,
        n_wrench_rows: int,
        n_sep_rows: int,
        daqp_options: dict[str, Any] | None = None,
    ) -> None:
        if daqp is None:
            raise ConfigError("qp_form", "condensed", "the daqp package installed")
        self.layout = lay = layout
        h = lay.horizon
        self.n_wrench_rows = n_wrench_rows
        self.n_sep_rows = n_sep_rows
        self.options = dict(daqp_options or {})
        # states S in the order of the equality rows (x_0, dpc_0, x_1, dpc_1, ...)
        self.cols_s = np.concatenate([lay.col_x, lay.col_pc], axis=1).ravel()
        # inputs I: all df, then all dtau, then all dpf, each (h, 2, 3) in C order
        self.cols_i = np.concatenate([lay.col_f.ravel(), lay.col_tau.ravel(), lay.col_pf.ravel()])
        self.n_i = self.cols_i.size
        self._n_w = 2 * h * N_FEET * 3  # inputs that are wrench entries
        self._cache: dict[bytes, _Structure] = {}
        self.n_structures = 0  # structures built (cache misses)
        self._input_pos = np.full(lay.n, -1)  # column -> position in I
        self._input_pos[self.cols_i] = np.arange(self.n_i)
        self._a_pattern = _Pattern.empty()  # of the sparse QP's A_eq and A, on first use
        self._eq_pattern = _Pattern.empty()
        self._p_matrix: Any = None  # the sparse QP's P (diagonal) and its diagonal
        self._p_diag = np.zeros(0)
        # BLAS on one thread during a solve (module docstring): its products are small
        self._blas = ThreadpoolController()

    def _patterns(self, problem: QPProblem) -> None:
        """Read the sparsity patterns of ``A_eq`` and ``A`` and the diagonal of ``P`` on the
        first call, and again whenever they change (never, for the problems of one
        :class:`KDSubproblem`: it lays its patterns out once and keeps one ``P``); the
        scatter maps of the condensing depend on them."""
        assert problem.A_eq is not None and problem.A is not None
        same = (
            problem.P is self._p_matrix
            and self._eq_pattern.matches(problem.A_eq)
            and self._a_pattern.matches(problem.A)
        )
        if same:
            return
        self._cache.clear()
        self._p_matrix = problem.P
        self._p_diag = problem.P.diagonal()
        self._a_pattern = _Pattern.of(problem.A)
        eq = self._eq_pattern = _Pattern.of(problem.A_eq)
        # A_I (m_eq, n_I): every entry in an input column
        c = self._input_pos[eq.cols]
        self._eq_i_take = np.flatnonzero(c >= 0)
        self._eq_i_row = eq.rows[self._eq_i_take]
        self._eq_i_input = c[self._eq_i_take]
        # sub-diagonal blocks (h, NS, NS): rows of stage k + 1 on the states of stage k
        state_pos = np.full(self.layout.n, -1)
        state_pos[self.cols_s] = np.arange(self.cols_s.size)
        s_pos = state_pos[eq.cols]
        k = eq.rows // _NS - 1  # the stage whose states the row's stage reads
        lower = (s_pos >= 0) & (k >= 0) & (s_pos // _NS == k)
        self._eq_l_take = np.flatnonzero(lower)
        rk, sk = eq.rows[lower], s_pos[lower]
        self._eq_l_put = ((rk // _NS - 1) * _NS + rk % _NS) * _NS + sk % _NS

    # ------------------------------------------------------------------ structure
    def _structure(self, contact: np.ndarray, fixed_pf: np.ndarray) -> _Structure:
        key = contact.tobytes() + fixed_pf.tobytes()
        found = self._cache.get(key)
        if found is not None:
            return found
        h = self.layout.horizon
        stance = np.broadcast_to(contact[:, :, None], (h, N_FEET, 3)).ravel()
        free_w = np.concatenate([stance, stance])  # df, dtau: stance feet only
        # tie groups per foot: a new group starts at each lift-off (k-1 stance, k swing)
        start = np.zeros((h, N_FEET), dtype=bool)
        start[0] = True
        start[1:] = contact[:-1] & ~contact[1:]
        first = np.maximum.accumulate(np.where(start, np.arange(h)[:, None], 0), axis=0)
        k0 = np.broadcast_to(first[:, :, None], (h, N_FEET, 3))
        foot = np.broadcast_to(np.arange(N_FEET)[None, :, None], (h, N_FEET, 3))
        axis = np.broadcast_to(np.arange(3)[None, None, :], (h, N_FEET, 3))
        base_pf = ((k0 * N_FEET + foot) * 3 + axis).ravel()  # flat (h, 2, 3) index
        fixed = fixed_pf.ravel()
        free_pf = ~fixed[base_pf]
        is_base = base_pf == np.arange(base_pf.size)
        free = np.concatenate([free_w, free_pf])
        base = np.concatenate([np.arange(self._n_w), self._n_w + base_pf])
        owner = np.concatenate([free_w, free_pf & is_base])  # inputs that own a u
        u_of_owner = np.cumsum(owner) - 1
        u_of_input = np.where(free, u_of_owner[base], -1)
        by_u = np.flatnonzero(free)
        by_u = by_u[np.argsort(u_of_input[by_u], kind="stable")]
        u_start = np.searchsorted(u_of_input[by_u], np.arange(int(owner.sum())))
        mw = self.n_wrench_rows
        wrench_rows = np.flatnonzero(np.repeat(contact.ravel(), mw))
        sep0 = h * N_FEET * mw + N_FEET * 3 * (h - 1)
        rows = np.concatenate([wrench_rows, sep0 + np.arange(self.n_sep_rows)])
        n_u = u_start.size
        row_pos = np.full(self._a_pattern.shape[0], -1)
        row_pos[rows] = np.arange(rows.size)
        r, c = row_pos[self._a_pattern.rows], self._input_pos[self._a_pattern.cols]
        take = np.flatnonzero((r >= 0) & (c >= 0))  # A: kept rows, input columns
        u_a = u_of_input[c[take]]
        a_u = u_a >= 0  # ... and free inputs
        u_eq = u_of_input[self._eq_i_input]
        eq_u = u_eq >= 0
        found = _Structure(
            free, base, by_u, u_start, u_of_input, np.flatnonzero(owner), rows, n_u,
            eq_take=self._eq_i_take[eq_u],
            eq_put=self._eq_i_row[eq_u] * (n_u + 1) + u_eq[eq_u],
            a_take=take[a_u],
            a_put=r[take[a_u]] * n_u + u_a[a_u],
            a_m_take=take,
            a_m_row=r[take],
            a_m_input=c[take],
            p_input_u=np.add.reduceat(self._p_diag[self.cols_i][by_u], u_start),
        )  # fmt: skip
        if len(self._cache) >= _CACHE_SIZE:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = found
        self.n_structures += 1
        return found

    # ------------------------------------------------------------------ condense
    def condense(
        self,
        problem: QPProblem,
        wrench_iterate: np.ndarray,
        p_foot_iterate: np.ndarray,
        contact: np.ndarray,
    ) -> CondensedQP:
        """The dense QP of ``problem`` (module docstring) and its map ``z = M u + m``.

        Args:
            problem: the sparse QP that :meth:`KDSubproblem.build` made.
            wrench_iterate: (2, h, 2, 3) the iterate's forces and moments ``w^j``.
            p_foot_iterate: (h, 2, 3) the iterate's foot positions.
            contact: (h, 2) stance mask.

        """
        assert problem.A_eq is not None and problem.b_eq is not None and problem.A is not None
        self._patterns(problem)
        lb, ub = problem.box_bounds()
        cols_i, cols_s = self.cols_i, self.cols_s
        lb_i, ub_i = lb[cols_i], ub[cols_i]
        fixed_pf = (lb_i == ub_i)[self._n_w :]
        st = self._structure(contact, fixed_pf)
        n_u = st.n_u
        # inputs: z_I = M_I u + m_I
        m_i = np.zeros(self.n_i)
        m_i[: self._n_w] = np.where(st.free[: self._n_w], 0.0, -wrench_iterate.ravel())
        pf = p_foot_iterate.ravel()
        base_pf = st.base[self._n_w :] - self._n_w
        m_pf = pf[base_pf] - pf  # ties: p^j_k0 - p^j_k
        m_i[self._n_w :] = np.where(fixed_pf[base_pf], m_pf + lb_i[self._n_w :][base_pf], m_pf)
        # states: A_S z_S = b - A_I z_I, A_S block lower bidiagonal with identity diagonal
        # blocks (stage k + 1's rows read stage k's states only). The right-hand sides
        # -A_I M_I (one column per u) and b - A_I m_I are scatter-adds of A_I's entries.
        m_eq, h = problem.b_eq.size, self.layout.horizon
        eq_data = problem.A_eq.data
        rhs = np.bincount(
            st.eq_put, weights=-eq_data[st.eq_take], minlength=m_eq * (n_u + 1)
        ).reshape(m_eq, n_u + 1)
        a_i_m = np.bincount(
            self._eq_i_row,
            weights=eq_data[self._eq_i_take] * m_i[self._eq_i_input],
            minlength=m_eq,
        )
        rhs[:, -1] = problem.b_eq - a_i_m
        lower = _dense((h, _NS, _NS), self._eq_l_put, eq_data[self._eq_l_take])
        sol = rhs  # forward substitution in place, stage by stage
        b = _NS
        for k in range(h):
            sol[b * (k + 1) : b * (k + 2)] -= lower[k] @ sol[b * k : b * (k + 1)]
        m_s, m_mat_s = sol[:, -1], sol[:, :-1]
        # cost: M^T P M = M_I^T P_I M_I (diagonal) + M_S^T P_S M_S; states 0 are fixed
        p_i, p_s = self._p_diag[cols_i], self._p_diag[cols_s]
        w_s = np.sqrt(p_s[b:])[:, None] * m_mat_s[b:]
        hess = w_s.T @ w_s
        hess.flat[:: n_u + 1] += st.p_input_u
        g_i = p_i * m_i + problem.q[cols_i]
        g_s = p_s * m_s + problem.q[cols_s]
        grad = st.sum_by_u(g_i) + m_mat_s.T @ g_s
        # rows: kept inequality rows (inputs only), then finite boxes on states
        a_data = problem.A.data
        n_rows = st.rows.size
        g_in = np.bincount(st.a_put, weights=a_data[st.a_take], minlength=n_rows * n_u)
        g_in = g_in.reshape(n_rows, n_u)
        shift = np.bincount(
            st.a_m_row, weights=a_data[st.a_m_take] * m_i[st.a_m_input], minlength=n_rows
        )
        l_in, u_in = problem.ineq_bounds()
        g_rows = [g_in]
        lo = [l_in[st.rows] - shift]
        hi = [u_in[st.rows] - shift]
        lb_s, ub_s = lb[cols_s], ub[cols_s]
        boxed = np.flatnonzero(np.isfinite(lb_s[b:]) | np.isfinite(ub_s[b:])) + b
        if boxed.size:
            g_rows.append(m_mat_s[boxed])
            lo.append(lb_s[boxed] - m_s[boxed])
            hi.append(ub_s[boxed] - m_s[boxed])
        lo_all = np.concatenate([lb_i[st.u_source], *lo])
        hi_all = np.concatenate([ub_i[st.u_source], *hi])
        sense = np.where(lo_all == hi_all, _SENSE_EQUALITY, 0).astype(np.int32)
        qp = {
            "H": np.ascontiguousarray(hess),
            "f": np.ascontiguousarray(grad),
            "A": g_in if len(g_rows) == 1 else np.vstack(g_rows),
            "bupper": hi_all,
            "blower": lo_all,
            "sense": sense,
        }
        return CondensedQP(qp, st, m_i, m_mat_s, m_s, cols_i, cols_s, problem.n)

    # ------------------------------------------------------------------ solve
    def solve(
        self,
        problem: QPProblem,
        wrench_iterate: np.ndarray,
        p_foot_iterate: np.ndarray,
        contact: np.ndarray,
    ) -> QPSolution:
        """Condense ``problem``, solve it with DAQP and expand the solution to ``z``.

        The returned :class:`QPSolution` refers to the sparse ``problem`` (its
        objective and residual are evaluated there); ``solve_time_s`` includes the
        condensing.
        """
        start = time.perf_counter()
        with self._blas.limit(limits=1, user_api="blas"):
            dense = self.condense(problem, wrench_iterate, p_foot_iterate, contact)
            u, _fval, exitflag, info = daqp.solve(**dense.qp, **self.options)
        status = _SOLVED.get(int(exitflag), "numerical_error" if exitflag != -1 else "infeasible")
        x = dense.expand(u) if status in _SOLVED.values() and np.all(np.isfinite(u)) else None
        if x is None and status in _SOLVED.values():
            status = "nan"
        sol = QPSolution(
            x=x,
            status=status,
            found=False,
            iterations=int(info.get("iterations", 0)),
            solve_time_s=time.perf_counter() - start,
            backend=self.backend,
            native_status=f"daqp exit {exitflag}",
            problem=problem,
        )
        sol.found = status == "solved" or (
            status == "solved_inaccurate"
            and sol.primal_residual is not None
            and sol.primal_residual <= 1e-3
        )
        return sol


__all__ = ["KDCondensed"]
