"""Clarabel backend (sparse conic interior point, ``clarabel`` 0.11 Python API).

Clarabel solves ``min 0.5 x'Px + q'x  s.t.  A x + s = b, s in K``.  The QP is
mapped to one zero cone (equalities: ``A_eq`` rows, inequality rows with
``l == u`` and box entries with ``lb == ub``) followed by one nonnegative cone
holding ``A x <= u``, ``-A x <= -l``, ``x <= ub``, ``-x <= -lb`` for the *finite*
bounds only (infinite ones are skipped).  ``P`` is passed as its upper triangle.

Because which rows exist depends on which bounds are finite, this backend sets
the solver up from scratch on every solve; as an interior-point method it has no
use for ``warm_start`` either.  It is the reference backend of the tests.
``DefaultSolution.x`` comes back as a Python list.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np
import scipy.sparse as sp

from gaitnet_mpc.errors import reraise_interrupt
from gaitnet_mpc.mpc.qp.problem import QPProblem
from gaitnet_mpc.mpc.qp.structure import canonical_csc, triu_csc
from gaitnet_mpc.mpc.qp.workspace import BackendResult, QPWorkspace

try:
    import clarabel
except ImportError as _exc:  # pragma: no cover - depends on the environment
    reraise_interrupt(_exc)
    clarabel = None
    _IMPORT_ERROR: str | None = repr(_exc)
else:
    _IMPORT_ERROR = None

_STATUS = MappingProxyType(
    {
        "Solved": "solved",
        "AlmostSolved": "solved_inaccurate",
        "PrimalInfeasible": "infeasible",
        "DualInfeasible": "infeasible",
        "AlmostPrimalInfeasible": "infeasible",
        "AlmostDualInfeasible": "infeasible",
        "MaxIterations": "max_iter",
        "MaxTime": "max_iter",
        "NumericalError": "numerical_error",
        "InsufficientProgress": "numerical_error",
    }
)


class _ConeBuilder:
    """Collects rows of Clarabel's ``A x + s = b`` for the zero and nonnegative cones."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.eq_rows: list[sp.csc_matrix] = []
        self.eq_rhs: list[np.ndarray] = []
        self.ineq_rows: list[sp.csc_matrix] = []
        self.ineq_rhs: list[np.ndarray] = []

    def add_two_sided(self, M: sp.csc_matrix, low: np.ndarray, up: np.ndarray) -> None:
        """Add ``low <= M x <= up`` (equal finite sides become equalities)."""
        equal = np.isfinite(low) & (low == up)
        has_up = np.isfinite(up) & ~equal
        has_low = np.isfinite(low) & ~equal
        M = M.tocsr()
        if equal.any():
            self.eq_rows.append(M[np.flatnonzero(equal)])
            self.eq_rhs.append(up[equal])
        if has_up.any():
            self.ineq_rows.append(M[np.flatnonzero(has_up)])
            self.ineq_rhs.append(up[has_up])
        if has_low.any():
            self.ineq_rows.append(-M[np.flatnonzero(has_low)])
            self.ineq_rhs.append(-low[has_low])

    def build(self) -> tuple[sp.csc_matrix, np.ndarray, list[Any]]:
        """Stacked ``(A, b, cones)``."""
        rows = self.eq_rows + self.ineq_rows
        rhs = self.eq_rhs + self.ineq_rhs
        cones: list[Any] = []
        m_eq = sum(r.shape[0] for r in self.eq_rows)
        m_in = sum(r.shape[0] for r in self.ineq_rows)
        if m_eq:
            cones.append(clarabel.ZeroConeT(m_eq))
        if m_in:
            cones.append(clarabel.NonnegativeConeT(m_in))
        if not rows:
            return sp.csc_matrix((0, self.n)), np.zeros(0), cones
        return canonical_csc(sp.vstack(rows, format="csc")), np.concatenate(rhs), cones


class ClarabelWorkspace(QPWorkspace):
    """Clarabel workspace (full setup every solve).

    Options are attributes of ``clarabel.DefaultSettings`` (``tol_gap_abs``,
    ``tol_feas``, ``max_iter``, ``verbose``, ...).
    """

    name: ClassVar[str] = "clarabel"
    available: ClassVar[bool] = clarabel is not None
    import_error: ClassVar[str | None] = _IMPORT_ERROR
    default_options: ClassVar[Mapping[str, Any]] = MappingProxyType({"verbose": False})

    def _check_options(self, options: Mapping[str, Any]) -> None:
        settings = clarabel.DefaultSettings()
        known = {k for k in dir(settings) if not k.startswith("_") and k != "default"}
        self._unknown_options(options, known)

    def _solve(self, problem: QPProblem, warm_start: np.ndarray | None) -> BackendResult:
        self.n_setups += 1
        n = problem.n
        cones = _ConeBuilder(n)
        if problem.A_eq is not None:
            assert problem.b_eq is not None  # given together (QPProblem.__post_init__)
            cones.eq_rows.append(problem.A_eq)
            cones.eq_rhs.append(problem.b_eq)
        if problem.A is not None:
            cones.add_two_sided(problem.A, *problem.ineq_bounds())
        if problem.has_box:
            cones.add_two_sided(sp.identity(n, format="csr"), *problem.box_bounds())
        A, b, cone_list = cones.build()

        settings = clarabel.DefaultSettings()
        for key, value in self.options.items():
            setattr(settings, key, value)
        solver = clarabel.DefaultSolver(triu_csc(problem.P), problem.q, A, b, cone_list, settings)
        sol = solver.solve()
        native = str(sol.status)
        return BackendResult(
            np.asarray(sol.x, dtype=np.float64),
            _STATUS.get(native, "unknown"),
            native,
            int(sol.iterations),
        )
