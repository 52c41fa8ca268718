"""PIQP backend (sparse proximal interior point, ``piqp.SparseSolver``, 0.6/0.7 API).

PIQP's own form matches ours almost one-to-one::

    min 0.5 x'Px + c'x  s.t.  A x = b,  h_l <= G x <= h_u,  x_l <= x <= x_u

``setup(P, c, A, b, G, h_l, h_u, x_l, x_u)`` takes ``None`` for absent blocks and
only the upper triangle of ``P`` is used.  Inequality rows with *both* bounds
infinite are dropped before they reach PIQP (otherwise PIQP prints a warning and
zeroes those rows of ``G`` internally).  With unchanged structure the solver is
updated in place with ``SparseSolver.update(...)``; matrices are only sent when
their values changed.  Being an interior-point method PIQP has no primal warm
start: the ``warm_start`` argument is ignored.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np
import scipy.sparse as sp

from gaitnet_mpc.mpc.qp.problem import QPProblem
from gaitnet_mpc.mpc.qp.structure import SparsityPattern, canonical_csc, triu_csc
from gaitnet_mpc.mpc.qp.workspace import BackendResult, QPWorkspace

try:
    import piqp
except ImportError as _exc:  # pragma: no cover - depends on the environment
    piqp = None
    _IMPORT_ERROR: str | None = repr(_exc)
else:
    _IMPORT_ERROR = None

_STATUS = MappingProxyType(
    {
        "PIQP_SOLVED": "solved",
        "PIQP_MAX_ITER_REACHED": "max_iter",
        "PIQP_PRIMAL_INFEASIBLE": "infeasible",
        "PIQP_DUAL_INFEASIBLE": "infeasible",
        "PIQP_NUMERICS": "numerical_error",
        "PIQP_UNSOLVED": "unknown",
        "PIQP_INVALID_SETTINGS": "numerical_error",
    }
)


class PIQPWorkspace(QPWorkspace):
    """Sparse PIQP workspace with in-place updates.

    Options are attributes of ``piqp.SparseSolver().settings`` (``eps_abs``,
    ``eps_rel``, ``max_iter``, ``verbose``, ...).
    """

    name: ClassVar[str] = "piqp"
    available: ClassVar[bool] = piqp is not None
    import_error: ClassVar[str | None] = _IMPORT_ERROR
    supports_update: ClassVar[bool] = True
    default_options: ClassVar[Mapping[str, Any]] = MappingProxyType({"verbose": False})

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._solver: Any = None
        self._last: dict[str, np.ndarray] = {}

    def _check_options(self, options: Mapping[str, Any]) -> None:
        settings = piqp.SparseSolver().settings
        known = {k for k in dir(settings) if not k.startswith("_")}
        self._unknown_options(options, known)

    def _reset_backend(self) -> None:
        self._solver = None
        self._last = {}

    def _solve(self, problem: QPProblem, warm_start: np.ndarray | None) -> BackendResult:
        P = triu_csc(problem.P)
        A_eq, b_eq = problem.A_eq, problem.b_eq
        G: sp.csc_matrix | None = None
        h_l = h_u = None
        if problem.A is not None:
            l, u = problem.ineq_bounds()
            keep = np.isfinite(l) | np.isfinite(u)
            if keep.all():
                G, h_l, h_u = problem.A, l, u
            elif keep.any():
                G = canonical_csc(problem.A[np.flatnonzero(keep)])
                h_l, h_u = l[keep], u[keep]
        x_l = x_u = None
        if problem.has_box:
            x_l, x_u = problem.box_bounds()

        matrices = {"P": P, "A": A_eq, "G": G}
        structure = (
            SparsityPattern.of(P),
            SparsityPattern.of(A_eq),
            SparsityPattern.of(G),
            problem.has_box,
        )
        if self._structure_changed(structure) or self._solver is None:
            self._solver = piqp.SparseSolver()
            for key, value in self.options.items():
                setattr(self._solver.settings, key, value)
            self._solver.setup(P, problem.q, A_eq, b_eq, G, h_l, h_u, x_l, x_u)
        else:
            update: dict[str, Any] = {"c": problem.q}
            for key, matrix in matrices.items():
                if matrix is not None and not np.array_equal(matrix.data, self._last[key]):
                    update[key] = matrix
            if A_eq is not None:
                update["b"] = b_eq
            if G is not None:
                update["h_l"], update["h_u"] = h_l, h_u
            if problem.has_box:
                update["x_l"], update["x_u"] = x_l, x_u
            self._solver.update(**update)
        self._last = {k: m.data.copy() for k, m in matrices.items() if m is not None}

        native = self._solver.solve()
        result = self._solver.result
        status = _STATUS.get(native.name, "unknown")
        return BackendResult(result.x, status, native.name, int(result.info.iter))
