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
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np
import scipy.sparse as sp

from gaitnet_mpc.errors import reraise_interrupt
from gaitnet_mpc.mpc.qp.problem import QPProblem
from gaitnet_mpc.mpc.qp.structure import EntrySelection, SparsityPattern
from gaitnet_mpc.mpc.qp.workspace import BackendResult, QPWorkspace

try:
    import piqp
except ImportError as _exc:  # pragma: no cover - depends on the environment
    reraise_interrupt(_exc)
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


@dataclass(frozen=True, eq=False)
class _Layout:
    """How problems of one structure become PIQP's matrices, fixed until it changes.

    Attributes:
        triu: upper triangle of ``P`` as a position map into ``P.data``.
        rows: inequality rows of ``A`` with a finite bound as a position map (``None``:
            every row is kept and ``A`` is passed as it is).
        P: PIQP's ``P`` (upper triangle); its ``data`` is overwritten by :meth:`P_of`.
        G: PIQP's ``G`` when rows are dropped, else ``None``; overwritten by :meth:`G_of`.
            PIQP copies its inputs on ``setup``/``update``, so reusing them is safe.
    """

    triu: EntrySelection
    rows: EntrySelection | None
    P: sp.csc_matrix
    G: sp.csc_matrix | None

    @classmethod
    def of(cls, problem: QPProblem, keep: np.ndarray | None) -> _Layout:
        triu = EntrySelection.upper_triangle(problem.P)
        rows = G = None
        if keep is not None and problem.A is not None and not keep.all():
            rows = EntrySelection.rows(problem.A, keep)
            G = rows.matrix(problem.A.data[rows.positions])
        return cls(triu, rows, triu.matrix(problem.P.data[triu.positions]), G)

    def P_of(self, problem: QPProblem) -> sp.csc_matrix:
        """Upper triangle of ``problem.P``."""
        self.P.data[:] = problem.P.data[self.triu.positions]
        return self.P

    def G_of(self, problem: QPProblem) -> sp.csc_matrix | None:
        """Rows of ``problem.A`` with a finite bound; ``None`` if there are none."""
        if self.rows is None or self.G is None:
            return problem.A
        if self.G.shape[0] == 0:
            return None
        assert problem.A is not None
        self.G.data[:] = problem.A.data[self.rows.positions]
        return self.G


class PIQPWorkspace(QPWorkspace):
    """Sparse PIQP workspace with in-place updates.

    Options are attributes of ``piqp.SparseSolver().settings`` (``eps_abs``,
    ``eps_rel``, ``max_iter``, ``verbose``, ...).

    The conversion to PIQP's form (upper triangle of ``P``, rows of ``A`` with a finite
    bound) is a :class:`_Layout` built once per structure; later solves with the same
    structure only gather value arrays through its position maps and send PIQP the
    vectors and the matrices whose values changed.
    """

    name: ClassVar[str] = "piqp"
    available: ClassVar[bool] = piqp is not None
    import_error: ClassVar[str | None] = _IMPORT_ERROR
    supports_update: ClassVar[bool] = True
    default_options: ClassVar[Mapping[str, Any]] = MappingProxyType({"verbose": False})

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._solver: Any = None
        self._layout: _Layout | None = None
        self._last: dict[str, np.ndarray] = {}

    def _check_options(self, options: Mapping[str, Any]) -> None:
        settings = piqp.SparseSolver().settings
        known = {k for k in dir(settings) if not k.startswith("_")}
        self._unknown_options(options, known)

    def _reset_backend(self) -> None:
        self._solver = None
        self._layout = None
        self._last = {}

    def _structure_of(self, problem: QPProblem, keep: np.ndarray | None) -> tuple[Any, ...]:
        """Patterns of ``P``, ``A_eq``, ``A``, the dropped rows and the box flag."""
        dropped = () if keep is None else tuple(np.flatnonzero(~keep).tolist())
        return (
            SparsityPattern.of(problem.P),
            SparsityPattern.of(problem.A_eq),
            SparsityPattern.of(problem.A),
            dropped,
            problem.has_box,
        )

    def _solve(self, problem: QPProblem, warm_start: np.ndarray | None) -> BackendResult:
        keep = h_l = h_u = None
        if problem.A is not None:
            l, u = problem.ineq_bounds()
            keep = np.isfinite(l) | np.isfinite(u)
            h_l, h_u = (l, u) if keep.all() else (l[keep], u[keep])
        x_l = x_u = None
        if problem.has_box:
            x_l, x_u = problem.box_bounds()

        changed = self._structure_changed(self._structure_of(problem, keep))
        if changed or self._solver is None or self._layout is None:
            self._layout = _Layout.of(problem, keep)
        P = self._layout.P_of(problem)
        A_eq = problem.A_eq
        G = self._layout.G_of(problem)
        if G is None:
            h_l = h_u = None
        matrices = {"P": P, "A": A_eq, "G": G}
        if changed or self._solver is None:
            self._solver = piqp.SparseSolver()
            for key, value in self.options.items():
                setattr(self._solver.settings, key, value)
            self._solver.setup(P, problem.q, A_eq, problem.b_eq, G, h_l, h_u, x_l, x_u)
        else:
            update: dict[str, Any] = {"c": problem.q}
            for key, matrix in matrices.items():
                if matrix is not None and not np.array_equal(matrix.data, self._last[key]):
                    update[key] = matrix
            if A_eq is not None:
                update["b"] = problem.b_eq
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
