"""Condensing (mpc/qp/condensed.py): the condensed QP has the direct QP's solution."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.qp import QPProblem, make_workspace
from gaitnet_mpc.mpc.qp.condensed import (
    FixedVariableFinder,
    choose_dependent,
    condense,
    fixed_variables,
)


def _mpc_like(rng: np.random.Generator, diagonal_p: bool = True) -> tuple[QPProblem, np.ndarray]:
    """A small MPC: states s_k (2) and inputs u_k (2) of 4 stages, s_0 fixed, dynamics
    s_{k+1} = A s_k + B u_k as equality rows, input rows and a box; returns the problem
    and the state columns. Layout z = [s_0, u_0, s_1, u_1, ..., s_4]."""
    h, ns, nu = 4, 2, 2
    n = h * (ns + nu) + ns
    col_s = np.array([k * (ns + nu) + np.arange(ns) for k in range(h + 1)])
    col_u = np.array([k * (ns + nu) + ns + np.arange(nu) for k in range(h)])
    a_dyn = np.eye(ns) + 0.1 * rng.standard_normal((ns, ns))
    b_dyn = rng.standard_normal((ns, nu))
    a_eq = np.zeros((ns * (h + 1), n))
    b_eq = np.zeros(ns * (h + 1))
    a_eq[:ns, col_s[0]] = np.eye(ns)
    b_eq[:ns] = 0.1 * rng.standard_normal(ns)
    for k in range(h):
        rows = ns * (k + 1) + np.arange(ns)
        a_eq[np.ix_(rows, col_s[k + 1])] = np.eye(ns)
        a_eq[np.ix_(rows, col_s[k])] = -a_dyn
        a_eq[np.ix_(rows, col_u[k])] = -b_dyn
        b_eq[rows] = 0.01 * rng.standard_normal(ns)
    if diagonal_p:
        P = sp.diags(rng.uniform(0.5, 2.0, n), format="csc")
    else:
        m = rng.standard_normal((n, n))
        P = sp.csc_matrix(m @ m.T / n + 0.5 * np.eye(n))
    q = rng.standard_normal(n)
    # inequality rows: sum of each stage's inputs, one row on a state, three rows l == u:
    # one on both inputs of stage 3 (fixes nothing alone) and two that fix u_2
    a_in = np.zeros((h + 4, n))
    for k in range(h):
        a_in[k, col_u[k]] = 1.0
    a_in[h, col_s[2, 0]] = 1.0
    a_in[h + 1, col_u[3]] = [1.0, -1.0]
    a_in[h + 2, col_u[2]] = [1.0, 2.0]
    a_in[h + 3, col_u[2]] = [1.0, -1.0]  # with the row above: u_2 = (0, 0.05)
    lo = np.r_[np.full(h, -0.3), -0.2, 0.05, 0.1, -0.05]
    hi = np.r_[np.full(h, 0.3), 0.2, 0.05, 0.1, -0.05]
    lb = np.full(n, -np.inf)
    ub = np.full(n, np.inf)
    lb[col_u.ravel()], ub[col_u.ravel()] = -0.25, 0.25
    lb[col_u[3, 0]] = ub[col_u[3, 0]] = 0.1  # fixed by the box
    lb[col_s[3, 1]], ub[col_s[3, 1]] = -0.1, 0.1  # a box on a state becomes a row
    problem = QPProblem(P, q, A_eq=a_eq, b_eq=b_eq, A=a_in, l=lo, u=hi, lb=lb, ub=ub)
    return problem, np.sort(col_s.ravel())


def _solve_condensed(c) -> np.ndarray:  # type: ignore[no-untyped-def]
    sol = make_workspace("daqp").solve(c.to_problem())
    assert sol.found, sol.status
    assert sol.x is not None
    return c.expand(sol.x)


@pytest.mark.parametrize("diagonal_p", [True, False])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_condensed_solution_equals_direct(seed: int, diagonal_p: bool) -> None:
    problem, states = _mpc_like(np.random.default_rng(seed), diagonal_p)
    direct = make_workspace("piqp", eps_abs=1e-10, eps_rel=1e-10).solve(problem)
    assert direct.found and direct.x is not None
    for dependent in (states, None):  # given (lower triangular), chosen by QR (dense LU)
        for fixed in (None, fixed_variables(problem, states)):
            if dependent is None and fixed is not None:
                continue  # the chosen columns may differ from the states
            c = condense(problem, dependent, fixed)
            x = _solve_condensed(c)
            assert problem.primal_residual(x) < 1e-8
            assert np.allclose(x, direct.x, atol=1e-6)
            assert problem.objective(x) == pytest.approx(direct.obj, rel=1e-8, abs=1e-9)
            u = c.reduce(x)
            assert c.objective(u) + c.constant == pytest.approx(problem.objective(x), abs=1e-9)


def test_fixed_variables_box_and_row_groups() -> None:
    problem, states = _mpc_like(np.random.default_rng(3))
    finder = FixedVariableFinder()
    for _ in range(2):  # the second call reuses the cached row grouping
        fixed = finder(problem, states)
        assert np.flatnonzero(fixed.mask).tolist() == [10, 11, 14]  # u_2 (rows), u_3[0] (box)
        assert np.allclose(fixed.values[[10, 11, 14]], [0.0, 0.05, 0.1])
    c = condense(problem, states, fixed)
    assert c.n_free == problem.n - states.size - 3
    assert c.dropped_violation < 1e-12  # the rows on u_2 only are constant and dropped
    assert c.rows.size == c.A.shape[0] < problem.m_ineq + 1


def test_rejects_bad_dependent_columns() -> None:
    problem, states = _mpc_like(np.random.default_rng(4))
    with pytest.raises(ConfigError):
        condense(problem, states[:-1])
    with pytest.raises(ConfigError):
        condense(problem, np.r_[states[:-1], states[0]])
    assert choose_dependent(problem).size == problem.m_eq
    tiny = QPProblem(
        sp.identity(3, format="csc"), np.zeros(3), A_eq=np.array([[1.0, 1.0, 0.0]]), b_eq=np.ones(1)
    )
    with pytest.raises(ConfigError):
        condense(tiny, np.array([2]))  # column 2 is in no equality row: singular
