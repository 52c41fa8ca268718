"""Backend-independent result of one QP solve."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Final

import numpy as np

from gaitnet_mpc.mpc.qp.problem import QPProblem

#: Every status a :class:`QPSolution` can carry.
#:
#: * ``"solved"`` - the backend converged to its tolerances.
#: * ``"solved_inaccurate"`` - converged to relaxed tolerances (OSQP
#:   ``solved inaccurate``, Clarabel ``AlmostSolved``, DAQP soft-optimal).
#: * ``"infeasible"`` - primal *or* dual infeasibility (unboundedness) was
#:   certified, or a lower bound exceeds its upper bound.
#: * ``"max_iter"`` - iteration or time limit reached.
#: * ``"numerical_error"`` - the backend gave up (factorisation failure, cycling,
#:   non-convexity detected, or the backend raised an exception).
#: * ``"nan"`` - the backend claimed success but returned no or non-finite values.
#: * ``"unknown"`` - any other native status.
STATUSES: Final = (
    "solved",
    "solved_inaccurate",
    "infeasible",
    "max_iter",
    "numerical_error",
    "nan",
    "unknown",
)

#: Statuses that may count as found (see :attr:`QPSolution.found`).
SOLVED_STATUSES: Final = frozenset({"solved", "solved_inaccurate"})


@dataclass
class QPSolution:
    """Outcome of :meth:`QPWorkspace.solve`.

    Attributes:
        x: Primal solution, a fresh array owned by the caller.  Given for
            ``"solved"``, ``"solved_inaccurate"`` and ``"max_iter"`` (the last
            iterate, to be used with care); ``None`` for every other status.
            Never contains NaN/inf.
        status: One of :data:`STATUSES`.
        found: ``True`` when ``x`` can be applied: status ``"solved"``, or
            ``"solved_inaccurate"`` with ``primal_residual`` at most the
            workspace's ``inaccurate_tol`` (default ``1e-3``).
        iterations: Iterations reported by the backend (0 if none were run).
        solve_time_s: Wall time (``time.perf_counter``) of the backend call,
            including the setup or in-place update this workspace performed and
            the data conversion for the backend; excludes validation and the
            residual computation.
        backend: Registry name of the backend (``"osqp"``, ...).
        native_status: The backend's own status text (or the exception text),
            for logs and debugging.
        problem: The solved problem (for :attr:`obj` and :attr:`primal_residual`).
        obj: ``0.5 x^T P x + q^T x`` computed by us, or ``None`` without ``x``.
        primal_residual: Largest constraint violation of ``x`` computed by us
            (max-norm over equality, inequality and box rows), or ``None``.

    ``obj`` and ``primal_residual`` are evaluated on first access and then cached (two
    sparse products each, which a controller solving hundreds of QPs a second need not
    pay); the workspace hands over a problem it does not modify afterwards.
    """

    x: np.ndarray | None
    status: str
    found: bool
    iterations: int
    solve_time_s: float
    backend: str
    native_status: str = ""
    problem: QPProblem | None = field(default=None, repr=False, compare=False)

    @cached_property
    def obj(self) -> float | None:
        """``0.5 x^T P x + q^T x``, or ``None`` without ``x``."""
        if self.x is None or self.problem is None:
            return None
        return self.problem.objective(self.x)

    @cached_property
    def primal_residual(self) -> float | None:
        """Largest constraint violation of ``x`` (max-norm), or ``None`` without ``x``."""
        if self.x is None or self.problem is None:
            return None
        return self.problem.primal_residual(self.x)
