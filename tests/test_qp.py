"""Tests of the QP layer: problem form, status handling and every backend."""

from __future__ import annotations

import pickle
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest
import scipy.sparse as sp

from gaitnet_mpc.errors import ConfigError, QPSolveError
from gaitnet_mpc.mpc.qp import (
    BACKENDS,
    STATUSES,
    BackendResult,
    OSQPWorkspace,
    QPProblem,
    QPWorkspace,
    available_backends,
    make_workspace,
)

ALL = sorted(available_backends())
UPDATING = ["osqp", "piqp", "qpoases"]
TOL = 1e-4


def random_qp(seed: int, n: int = 24, m_eq: int = 4, m_ineq: int = 16) -> QPProblem:
    """A feasible, strictly convex sparse QP with eq, two-sided ineq and box rows.

    Some bounds are infinite, some inequality rows have ``l == u``, and the cost
    pulls the optimum onto the constraints.
    """
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((n, n)) * (rng.random((n, n)) < 0.15)
    P = M @ M.T + 0.3 * np.eye(n)
    x0 = rng.standard_normal(n)
    A_eq = rng.standard_normal((m_eq, n)) * (rng.random((m_eq, n)) < 0.4)
    A = rng.standard_normal((m_ineq, n)) * (rng.random((m_ineq, n)) < 0.4)
    A[:, 0] += 1.0  # no empty rows
    ax = A @ x0
    l = ax - rng.random(m_ineq)
    u = ax + rng.random(m_ineq)
    l[:3] = -np.inf
    u[3:6] = np.inf
    l[6] = u[6] = ax[6]  # an equality written as an inequality row
    lb = x0 - rng.random(n)
    ub = x0 + rng.random(n)
    lb[:3] = -np.inf
    ub[3:5] = np.inf
    q = 5.0 * rng.standard_normal(n)
    return QPProblem(
        P=sp.csc_matrix(P),
        q=q,
        A_eq=sp.csc_matrix(A_eq),
        b_eq=A_eq @ x0,
        A=sp.csc_matrix(A),
        l=l,
        u=u,
        lb=lb,
        ub=ub,
    )


def reference(problem: QPProblem) -> np.ndarray:
    sol = make_workspace("clarabel").solve_or_raise(problem)
    assert sol.x is not None
    return sol.x


def assert_matches(problem: QPProblem, x: np.ndarray | None, x_ref: np.ndarray) -> None:
    assert x is not None
    assert np.all(np.isfinite(x))
    assert np.max(np.abs(x - x_ref)) < TOL
    assert problem.primal_residual(x) < TOL
    # Feasible and no better than the unique optimum: optimal up to tolerance.
    f, f_ref = problem.objective(x), problem.objective(x_ref)
    assert f >= f_ref - TOL * (1.0 + abs(f_ref))
    assert f <= f_ref + TOL * (1.0 + abs(f_ref))


# --------------------------------------------------------------- (a) accuracy
def test_all_backends_are_installed() -> None:
    assert ALL == sorted(BACKENDS)


@pytest.mark.parametrize("backend", ALL)
def test_random_qps_agree_with_clarabel(backend: str) -> None:
    ws = make_workspace(backend)
    for seed in range(4):
        problem = random_qp(seed)
        x_ref = reference(problem)
        sol = ws.solve(problem)
        assert sol.status == "solved", sol.native_status
        assert sol.found
        assert sol.backend == backend
        assert sol.solve_time_s > 0.0
        assert sol.obj == pytest.approx(problem.objective(sol.x))
        assert sol.primal_residual is not None and sol.primal_residual < TOL
        assert_matches(problem, sol.x, x_ref)


@pytest.mark.parametrize("backend", ALL)
def test_problem_variants_without_some_blocks(backend: str) -> None:
    full = random_qp(7)
    variants = [
        QPProblem(full.P, full.q),  # unconstrained
        QPProblem(full.P, full.q, lb=full.lb, ub=full.ub),  # box only
        QPProblem(full.P, full.q, A_eq=full.A_eq, b_eq=full.b_eq),  # equality only
        QPProblem(full.P, full.q, A=full.A, u=full.u),  # one-sided, l missing
        QPProblem(full.P, full.q, A=full.A, l=full.l, u=full.u, ub=full.ub),  # ub only
    ]
    ws = make_workspace(backend)
    for problem in variants:
        sol = ws.solve(problem)
        assert sol.found, (backend, sol.status, sol.native_status)
        assert_matches(problem, sol.x, reference(problem))


# ------------------------------------------------------------ (b) infeasible
def infeasible_problems() -> list[QPProblem]:
    n = 4
    P = sp.identity(n, format="csc")
    q = np.ones(n)
    A = sp.csc_matrix(np.array([[1.0, 1.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0]]))
    rows = QPProblem(P, q, A=A, l=np.array([1.0, -np.inf]), u=np.array([np.inf, 0.0]))
    box_eq = QPProblem(
        P,
        q,
        A_eq=sp.csc_matrix(np.ones((1, n))),
        b_eq=np.array([10.0]),
        lb=np.zeros(n),
        ub=np.ones(n),
    )
    crossed = QPProblem(P, q, lb=np.zeros(n), ub=np.array([1.0, 1.0, -1.0, 1.0]))
    return [rows, box_eq, crossed]


@pytest.mark.parametrize("backend", ALL)
def test_infeasible_is_reported_and_workspace_recovers(backend: str) -> None:
    ws = make_workspace(backend)
    for problem in infeasible_problems():
        sol = ws.solve(problem)
        assert sol.status == "infeasible", (sol.status, sol.native_status)
        assert not sol.found
        assert sol.x is None and sol.obj is None and sol.primal_residual is None
        with pytest.raises(QPSolveError) as info:
            ws.solve_or_raise(problem)
        assert info.value.backend == backend
        assert info.value.status == "infeasible"
    problem = random_qp(11)
    sol = ws.solve(problem)
    assert sol.found
    assert_matches(problem, sol.x, reference(problem))


# -------------------------------------------------- (c) in-place update path
def problem_sequence(seed: int, steps: int = 5) -> list[QPProblem]:
    """Problems sharing one sparsity structure with changing values."""
    base = random_qp(seed)
    rng = np.random.default_rng(seed + 100)
    out = [base]
    for k in range(1, steps):
        P = base.P.copy()
        P.data = P.data * (1.0 + 0.1 * k)  # positive scaling keeps P convex
        A = base.A.copy()
        A.data = A.data + 0.05 * rng.standard_normal(A.nnz)
        if k == 3:
            A.data[0] = 0.0  # an explicit zero keeps the pattern
        A_eq = base.A_eq.copy()
        A_eq.data = A_eq.data + 0.05 * rng.standard_normal(A_eq.nnz)
        shift = 0.2 * rng.standard_normal(base.m_ineq)
        l, u = base.l + shift, base.u + shift
        l[6] = u[6]
        if k == 2:
            l[7] = -np.inf  # a bound becomes infinite, the row stays
        lb, ub = base.box_bounds()
        out.append(
            QPProblem(
                P=P,
                q=base.q + rng.standard_normal(base.n),
                A_eq=A_eq,
                b_eq=base.b_eq + 0.1 * rng.standard_normal(base.m_eq),
                A=A,
                l=l,
                u=u,
                lb=lb - 0.1 * k,
                ub=ub + 0.1 * k,
            )
        )
    return out


@pytest.mark.parametrize("backend", UPDATING)
def test_sequence_uses_in_place_updates(backend: str) -> None:
    ws = make_workspace(backend)
    sequence = problem_sequence(3)
    x_prev = None
    for problem in sequence:
        sol = ws.solve(problem, warm_start=x_prev)
        assert sol.found, sol.native_status
        assert_matches(problem, sol.x, reference(problem))
        x_prev = sol.x
    assert ws.n_setups == 1
    assert ws.n_updates == len(sequence) - 1


@pytest.mark.parametrize("backend", UPDATING)
def test_vector_only_updates_and_structure_change(backend: str) -> None:
    ws = make_workspace(backend)
    base = random_qp(5)
    for k in range(3):
        problem = QPProblem(
            base.P, base.q + k, base.A_eq, base.b_eq, base.A, base.l, base.u, base.lb, base.ub
        )
        assert_matches(problem, ws.solve(problem).x, reference(problem))
    assert (ws.n_setups, ws.n_updates) == (1, 2)
    other = random_qp(6)  # different pattern -> full setup
    assert_matches(other, ws.solve(other).x, reference(other))
    assert ws.n_setups == 2
    ws.reset()
    assert_matches(other, ws.solve(other).x, reference(other))
    assert ws.n_setups == 3


@pytest.mark.parametrize("backend", ["daqp", "clarabel"])
def test_non_updating_backends_solve_sequences(backend: str) -> None:
    ws = make_workspace(backend)
    sequence = problem_sequence(4, steps=3)
    for problem in sequence:
        assert_matches(problem, ws.solve_or_raise(problem).x, reference(problem))
    assert ws.n_setups == len(sequence)


@pytest.mark.parametrize("backend", ["osqp", "daqp"])
def test_warm_start_with_solution(backend: str) -> None:
    problem = random_qp(9)
    x_ref = reference(problem)
    cold = make_workspace(backend).solve(problem)
    warm = make_workspace(backend).solve(problem, warm_start=x_ref)
    assert warm.found
    assert_matches(problem, warm.x, x_ref)
    assert warm.iterations <= cold.iterations


def test_qpoases_cold_start_option() -> None:
    ws = make_workspace("qpoases", cold_start=True)
    for problem in problem_sequence(8, steps=3):
        assert_matches(problem, ws.solve(problem).x, reference(problem))
    assert ws.n_setups == 3


# ----------------------------------------------------- (d) validation errors
def _with(problem: QPProblem, **changes: Any) -> QPProblem:
    data = {k: getattr(problem, k) for k in ("P", "q", "A_eq", "b_eq", "A", "l", "u", "lb", "ub")}
    data.update(changes)
    return QPProblem(**data)


@pytest.mark.parametrize(
    ("field", "changes"),
    [
        ("q", {"q": np.zeros(3)}),
        ("q", {"q": np.zeros((24, 1))}),
        ("P", {"P": sp.csc_matrix(np.ones((24, 23)))}),
        ("A", {"A": sp.csc_matrix(np.ones((16, 5)))}),
        ("A_eq", {"A_eq": sp.csc_matrix(np.ones((4, 25)))}),
        ("b_eq", {"b_eq": np.zeros(5)}),
        ("l", {"l": np.zeros(15)}),
        ("u", {"u": np.zeros(17)}),
        ("lb", {"lb": np.zeros(2)}),
        ("ub", {"ub": np.zeros(30)}),
        ("b_eq", {"b_eq": None}),
        ("l/u", {"l": None, "u": None}),
    ],
)
def test_shape_errors_name_the_field(field: str, changes: dict[str, Any]) -> None:
    problem = _with(random_qp(0), **changes)
    with pytest.raises(ConfigError) as info:
        problem.validate()
    assert info.value.field == field
    assert str(info.value).startswith(f"{field}: got ")
    with pytest.raises(ConfigError):
        make_workspace("osqp").solve(problem)


def test_shape_error_message_shows_got_and_expected() -> None:
    with pytest.raises(ConfigError, match=r"q: got \(3,\), expected shape \(24,\)"):
        _with(random_qp(0), q=np.zeros(3)).validate()


def test_value_errors() -> None:
    base = random_qp(0)
    q = base.q.copy()
    q[2] = np.nan
    with pytest.raises(ConfigError, match=r"^q: "):
        _with(base, q=q).validate()
    b_eq = base.b_eq.copy()
    b_eq[0] = np.inf
    with pytest.raises(ConfigError, match=r"^b_eq: "):
        _with(base, b_eq=b_eq).validate()
    P = base.P.toarray()
    P[0, 1] += 1.0
    with pytest.raises(ConfigError, match=r"^P: .*symmetric"):
        _with(base, P=P).validate()
    l = base.l.copy()
    l[0] = np.nan
    with pytest.raises(ConfigError, match=r"^l: "):
        _with(base, l=l).validate()
    with pytest.raises(ConfigError, match=r"^warm_start: "):
        make_workspace("osqp").solve(base, warm_start=np.zeros(3))


# ------------------------------------------------------- (e) registry errors
def test_unknown_backend_name() -> None:
    with pytest.raises(ConfigError) as info:
        make_workspace("gurobi")
    assert info.value.field == "qp_backend"
    assert "osqp" in str(info.value)


@pytest.mark.parametrize("backend", ALL)
def test_unknown_option_is_rejected(backend: str) -> None:
    with pytest.raises(ConfigError):
        make_workspace(backend, not_an_option_xyz=1)


def test_options_are_forwarded() -> None:
    ws = make_workspace("osqp", eps_abs=1e-7, max_iter=10, polishing=False)
    sol = ws.solve(random_qp(1))
    assert sol.status == "max_iter"
    assert not sol.found
    assert sol.iterations == 10
    assert sol.x is not None  # last iterate is handed back for max_iter
    with pytest.raises(QPSolveError, match="max_iter"):
        ws.solve_or_raise(random_qp(1))


def test_missing_package_gives_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(OSQPWorkspace, "available", False)
    monkeypatch.setattr(OSQPWorkspace, "import_error", "ModuleNotFoundError('osqp')")
    assert "osqp" not in available_backends()
    with pytest.raises(ConfigError, match="importing it failed"):
        make_workspace("osqp")


# ------------------------------------------------ status post-processing
class _FakeWorkspace(QPWorkspace):
    """Backend returning a canned result, to test the shared post-processing."""

    name: ClassVar[str] = "fake"
    canned: BackendResult = BackendResult(None, "unknown", "")

    def _check_options(self, options: Mapping[str, Any]) -> None:
        self._unknown_options(options, set())

    def _solve(self, problem: QPProblem, warm_start: np.ndarray | None) -> BackendResult:
        return self.canned


def _fake(result: BackendResult, **kwargs: Any) -> _FakeWorkspace:
    ws = _FakeWorkspace(**kwargs)
    ws.canned = result
    return ws


def test_nan_solution_is_never_found() -> None:
    problem = random_qp(0)
    x = np.zeros(problem.n)
    x[3] = np.nan
    sol = _fake(BackendResult(x, "solved", "ok")).solve(problem)
    assert (sol.status, sol.found, sol.x) == ("nan", False, None)
    sol = _fake(BackendResult(None, "solved", "ok")).solve(problem)
    assert (sol.status, sol.found) == ("nan", False)


def test_solved_inaccurate_needs_small_residual() -> None:
    problem = random_qp(0)
    x_ref = reference(problem)
    good = _fake(BackendResult(x_ref, "solved_inaccurate", "")).solve(problem)
    assert good.found and good.status == "solved_inaccurate"
    bad = _fake(BackendResult(x_ref + 1.0, "solved_inaccurate", "")).solve(problem)
    assert not bad.found and bad.primal_residual > 1e-3
    loose = _fake(BackendResult(x_ref + 1.0, "solved_inaccurate", ""), inaccurate_tol=1e3)
    assert loose.solve(problem).found


def test_backend_exception_becomes_numerical_error() -> None:
    class Boom(_FakeWorkspace):
        def _solve(self, problem: QPProblem, warm_start: np.ndarray | None) -> BackendResult:
            raise RuntimeError("factorisation failed")

    sol = Boom().solve(random_qp(0))
    assert sol.status == "numerical_error"
    assert "factorisation failed" in sol.native_status
    assert sol.status in STATUSES


# ---------------------------------------------------------- problem helpers
def test_to_osqp_form_stacks_eq_ineq_box() -> None:
    problem = random_qp(2)
    A_all, l_all, u_all = problem.to_osqp_form()
    n, m_eq, m_in = problem.n, problem.m_eq, problem.m_ineq
    assert problem.m == m_eq + m_in
    assert A_all.shape == (m_eq + m_in + n, n)
    assert isinstance(A_all, sp.csc_matrix)
    dense = A_all.toarray()
    np.testing.assert_array_equal(dense[:m_eq], problem.A_eq.toarray())
    np.testing.assert_array_equal(dense[m_eq : m_eq + m_in], problem.A.toarray())
    np.testing.assert_array_equal(dense[m_eq + m_in :], np.eye(n))
    np.testing.assert_array_equal(l_all, np.concatenate([problem.b_eq, problem.l, problem.lb]))
    np.testing.assert_array_equal(u_all, np.concatenate([problem.b_eq, problem.u, problem.ub]))
    bare = QPProblem(problem.P, problem.q)
    A_bare, l_bare, _ = bare.to_osqp_form()
    assert A_bare.shape == (0, n) and l_bare.shape == (0,)


def test_save_load_and_pickle_roundtrip(tmp_path: Path) -> None:
    problem = random_qp(4)
    path = tmp_path / "qp.npz"
    problem.save_npz(path)
    loaded = QPProblem.load_npz(path)
    for copy in (loaded, pickle.loads(pickle.dumps(problem))):
        for name in ("P", "A_eq", "A"):
            assert (getattr(copy, name) != getattr(problem, name)).nnz == 0
        for name in ("q", "b_eq", "l", "u", "lb", "ub"):
            np.testing.assert_array_equal(getattr(copy, name), getattr(problem, name))
    partial = QPProblem(problem.P, problem.q, lb=problem.lb)
    partial.save_npz(tmp_path / "partial.npz")
    again = QPProblem.load_npz(tmp_path / "partial.npz")
    assert again.A is None and again.ub is None and again.lb is not None


def test_dense_inputs_are_coerced() -> None:
    problem = QPProblem(np.eye(2), [1.0, 2.0], A=[[1.0, 1.0]], l=[0.0])
    assert isinstance(problem.P, sp.csc_matrix) and isinstance(problem.A, sp.csc_matrix)
    sol = make_workspace("osqp").solve_or_raise(problem)
    assert sol.x is not None and sol.x.sum() == pytest.approx(0.0, abs=1e-5)
