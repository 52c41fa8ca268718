"""DAQP backend (dense dual active-set, ``daqp`` 0.11 Python API).

Call used::

    x, fval, exitflag, info = daqp.solve(H, f, A, bupper, blower, sense,
                                         primal_start=..., **settings)

Quirks this module handles:

* ``H`` and ``A`` are dense C-contiguous float64 arrays; ``A`` has shape ``(m, n)``.
* If ``bupper``/``blower`` are *longer* than ``A`` has rows, their first
  ``len - m`` entries are simple bounds on ``x[0], x[1], ...``.  The box is passed
  that way (all ``n`` entries, ``±inf`` where unbounded).
* ``sense`` must be ``int32`` (an ``int64`` array raises "Buffer dtype mismatch");
  ``5`` marks an equality row (``blower == bupper``), ``0`` an inequality.
  Inequality rows with ``l == u`` are flagged as equalities too.
* ``±inf`` bounds are accepted.
* Exit flags: 1 optimal, 2 soft-optimal, -1 infeasible, -2 cycling, -3
  unbounded, -4 iteration limit, -5 non-convex, -6 over-determined initial
  active set; others (e.g. time limit in newer versions) map to "unknown".
* The returned ``x`` can be a stale buffer when the solve fails, so ``x`` is
  only used for (soft-)optimal exits, also for ``max_iter``.

DAQP has no persistent workspace in this API: every solve is a full (cheap, dense)
setup.  ``warm_start`` is passed as ``primal_start`` (initial active set guess); if
DAQP rejects it (exit -6) the solve is repeated cold.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np
import scipy.sparse as sp

from gaitnet_mpc.errors import reraise_interrupt
from gaitnet_mpc.mpc.qp.problem import QPProblem
from gaitnet_mpc.mpc.qp.workspace import BackendResult, QPWorkspace

try:
    import daqp
except ImportError as _exc:  # pragma: no cover - depends on the environment
    reraise_interrupt(_exc)
    daqp = None
    _IMPORT_ERROR: str | None = repr(_exc)
else:
    _IMPORT_ERROR = None

_SENSE_EQUALITY = 5
_EXIT_OVERDETERMINED_INITIAL = -6
_STATUS = MappingProxyType(
    {
        1: ("solved", "optimal"),
        2: ("solved_inaccurate", "soft optimal"),
        -1: ("infeasible", "infeasible"),
        -2: ("numerical_error", "cycling"),
        -3: ("infeasible", "unbounded"),
        -4: ("max_iter", "iteration limit"),
        -5: ("numerical_error", "non-convex"),
        -6: ("numerical_error", "overdetermined initial active set"),
    }
)
# Arguments of daqp.solve that carry problem data rather than settings.
_DATA_ARGS = frozenset(
    {"H", "f", "A", "bupper", "blower", "sense", "break_points", "primal_start", "dual_start"}
)


def _known_settings() -> set[str]:
    try:
        params = inspect.signature(daqp.solve).parameters
    except (TypeError, ValueError):  # pragma: no cover - compiled without signatures
        return {"iter_limit", "primal_tol", "dual_tol", "eps_prox", "time_limit"}
    return set(params) - _DATA_ARGS


class DAQPWorkspace(QPWorkspace):
    """Dense DAQP workspace (full setup each solve, optional primal warm start).

    Options are ``daqp.solve`` keyword settings (``iter_limit``, ``primal_tol``,
    ``dual_tol``, ``eps_prox``, ``time_limit``, ...).
    """

    name: ClassVar[str] = "daqp"
    available: ClassVar[bool] = daqp is not None
    import_error: ClassVar[str | None] = _IMPORT_ERROR
    supports_warm_start: ClassVar[bool] = True

    def _check_options(self, options: Mapping[str, Any]) -> None:
        self._unknown_options(options, _known_settings())

    def _solve(self, problem: QPProblem, warm_start: np.ndarray | None) -> BackendResult:
        self.n_setups += 1  # no persistent workspace: always a fresh setup
        n = problem.n
        H = np.ascontiguousarray(problem.P.toarray())
        rows: list[sp.csc_matrix] = []
        uppers: list[np.ndarray] = []
        lowers: list[np.ndarray] = []
        senses: list[np.ndarray] = []
        if problem.has_box:
            lb, ub = problem.box_bounds()
            uppers.append(ub)
            lowers.append(lb)
            senses.append(np.where(lb == ub, _SENSE_EQUALITY, 0).astype(np.int32))
        if problem.A_eq is not None:
            assert problem.b_eq is not None  # given together (QPProblem.__post_init__)
            rows.append(problem.A_eq)
            uppers.append(problem.b_eq)
            lowers.append(problem.b_eq)
            senses.append(np.full(problem.m_eq, _SENSE_EQUALITY, dtype=np.int32))
        if problem.A is not None:
            l, u = problem.ineq_bounds()
            rows.append(problem.A)
            uppers.append(u)
            lowers.append(l)
            senses.append(np.where(l == u, _SENSE_EQUALITY, 0).astype(np.int32))
        if rows:
            A = np.ascontiguousarray(sp.vstack(rows).toarray())
        else:
            A = np.zeros((0, n))
        bupper = np.concatenate(uppers) if uppers else np.zeros(0)
        blower = np.concatenate(lowers) if lowers else np.zeros(0)
        sense = np.concatenate(senses) if senses else np.zeros(0, dtype=np.int32)
        f = np.ascontiguousarray(problem.q)

        x, _fval, exitflag, info = daqp.solve(
            H, f, A, bupper, blower, sense, primal_start=warm_start, **self.options
        )
        if exitflag == _EXIT_OVERDETERMINED_INITIAL and warm_start is not None:
            x, _fval, exitflag, info = daqp.solve(H, f, A, bupper, blower, sense, **self.options)
        status, text = _STATUS.get(int(exitflag), ("unknown", "unknown"))
        x_out = x if status in ("solved", "solved_inaccurate") else None
        return BackendResult(x_out, status, f"{exitflag} ({text})", int(info.get("iterations", 0)))
