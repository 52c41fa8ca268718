"""OSQP backend (sparse ADMM, ``osqp`` 1.x Python API).

The problem is passed in OSQP's own form (see :meth:`QPProblem.to_osqp_form`):
equality rows have ``l = u``, the box becomes identity rows.  When the sparsity
of ``triu(P)`` and of the stacked constraint matrix is unchanged, the solver is
updated in place with ``OSQP.update(q=, l=, u=, Px=, Ax=)``; ``Px``/``Ax`` are
only sent when their values changed, so a pure vector update skips the
refactorisation.  OSQP warm-starts from its previous primal-dual iterate by
itself (``warm_starting=True``); an explicit ``warm_start`` overrides the primal
part via ``OSQP.warm_start(x=...)``.  After a failed solve the iterate is reset
to zero so that a garbage infeasibility iterate does not poison the next solve.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np

from gaitnet_mpc.errors import reraise_interrupt
from gaitnet_mpc.mpc.qp.problem import QPProblem
from gaitnet_mpc.mpc.qp.structure import SparsityPattern, triu_csc
from gaitnet_mpc.mpc.qp.workspace import BackendResult, QPWorkspace

try:
    import osqp
    from osqp.interface import SolverStatus as _OSQPStatus
except ImportError as _exc:  # pragma: no cover - depends on the environment
    reraise_interrupt(_exc)
    osqp = None
    _IMPORT_ERROR: str | None = repr(_exc)
else:
    _IMPORT_ERROR = None


def _status_map() -> dict[int, str]:
    if osqp is None:  # pragma: no cover
        return {}
    table = {
        "OSQP_SOLVED": "solved",
        "OSQP_SOLVED_INACCURATE": "solved_inaccurate",
        "OSQP_PRIMAL_INFEASIBLE": "infeasible",
        "OSQP_PRIMAL_INFEASIBLE_INACCURATE": "infeasible",
        "OSQP_DUAL_INFEASIBLE": "infeasible",
        "OSQP_DUAL_INFEASIBLE_INACCURATE": "infeasible",
        "OSQP_MAX_ITER_REACHED": "max_iter",
        "OSQP_TIME_LIMIT_REACHED": "max_iter",
        "OSQP_NON_CVX": "numerical_error",
    }
    members = _OSQPStatus.__members__
    return {int(members[k]): v for k, v in table.items() if k in members}


_STATUS = MappingProxyType(_status_map())
# Setting names handled by osqp.OSQP.update_settings besides the raw OSQPSettings fields.
_EXTRA_SETTINGS = frozenset({"rho", "solver_type", "cg_preconditioner", "algebra"})


class OSQPWorkspace(QPWorkspace):
    """Sparse OSQP workspace with in-place updates and warm starts.

    Options are OSQP settings (``eps_abs``, ``eps_rel``, ``max_iter``,
    ``polishing``, ``rho``, ``adaptive_rho``, ``time_limit``, ...) plus
    ``algebra`` (``"builtin"``/``"mkl"``/``"cuda"`` if installed).
    """

    name: ClassVar[str] = "osqp"
    available: ClassVar[bool] = osqp is not None
    import_error: ClassVar[str | None] = _IMPORT_ERROR
    supports_update: ClassVar[bool] = True
    supports_warm_start: ClassVar[bool] = True
    default_options: ClassVar[Mapping[str, Any]] = MappingProxyType(
        {
            "eps_abs": 1e-5,
            "eps_rel": 1e-5,
            "polishing": True,
            "max_iter": 4000,
            "verbose": False,
            "warm_starting": True,
        }
    )

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._solver: Any = None
        self._p_data: np.ndarray | None = None
        self._a_data: np.ndarray | None = None

    def _check_options(self, options: Mapping[str, Any]) -> None:
        known = {k for k in osqp.OSQP().ext.OSQPSettings.__dict__ if not k.startswith("_")}
        self._unknown_options(options, known | _EXTRA_SETTINGS)

    def _reset_backend(self) -> None:
        self._solver = None
        self._p_data = None
        self._a_data = None

    def _after_failure(self) -> None:
        if self._solver is not None and self._solver.m is not None:
            self._solver.warm_start(x=np.zeros(self._solver.n), y=np.zeros(self._solver.m))

    def _solve(self, problem: QPProblem, warm_start: np.ndarray | None) -> BackendResult:
        P = triu_csc(problem.P)
        A, l, u = problem.to_osqp_form()
        structure = (SparsityPattern.of(P), SparsityPattern.of(A))
        if self._structure_changed(structure) or self._solver is None:
            settings = dict(self.options)
            algebra = settings.pop("algebra", None)
            self._solver = osqp.OSQP() if algebra is None else osqp.OSQP(algebra=algebra)
            self._solver.setup(P, problem.q, A, l, u, **settings)
        else:
            update: dict[str, np.ndarray] = {"q": problem.q}
            if A.shape[0]:
                update["l"], update["u"] = l, u
            # None (a failed setup) compares unequal: the stubs do not allow it
            if P.nnz and not np.array_equal(P.data, self._p_data):  # type: ignore[arg-type]
                update["Px"] = P.data
            if A.nnz and not np.array_equal(A.data, self._a_data):  # type: ignore[arg-type]
                update["Ax"] = A.data
            self._solver.update(**update)
        self._p_data, self._a_data = P.data.copy(), A.data.copy()
        if warm_start is not None:
            self._solver.warm_start(x=warm_start)
        res = self._solver.solve(raise_error=False)
        info = res.info
        status = _STATUS.get(int(info.status_val), "unknown")
        return BackendResult(res.x, status, str(info.status), int(info.iter))
