"""Backend-independent result of one QP solve."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Final

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


class _FromProblem:
    """A :class:`QPSolution` field evaluated from its problem on first read.

    Given a value (``QPSolution(obj=...)``) the field holds it; left ``None`` (the
    default) it is ``problem.<method>(x)`` on the first read, then cached, and stays
    ``None`` without ``x`` or ``problem``.
    """

    def __init__(self, method: str) -> None:
        self.method = method
        self.slot = ""

    def __set_name__(self, owner: type, name: str) -> None:
        self.slot = f"_{name}"

    def __get__(self, solution: Any, owner: type | None = None) -> float | None:
        if solution is None:
            return None  # the dataclass field's default
        value = solution.__dict__.get(self.slot)
        if value is None and solution.x is not None and solution.problem is not None:
            value = getattr(solution.problem, self.method)(solution.x)
            solution.__dict__[self.slot] = value
        return value

    def __set__(self, solution: Any, value: float | None) -> None:
        solution.__dict__[self.slot] = value


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
        obj: ``0.5 x^T P x + q^T x`` computed by us, or ``None`` without ``x``.
        primal_residual: Largest constraint violation of ``x`` computed by us
            (max-norm over equality, inequality and box rows), or ``None``.
        native_status: The backend's own status text (or the exception text),
            for logs and debugging.
        problem: The solved problem, from which ``obj`` and ``primal_residual`` are
            evaluated on first read and then cached (two sparse products each, which
            a controller solving hundreds of QPs a second need not pay); workspaces
            hand over the problem they solved, which the caller owns and should not
            modify.
    """

    x: np.ndarray | None
    status: str
    found: bool
    iterations: int
    solve_time_s: float
    backend: str
    obj: float | None = _FromProblem("objective")  # type: ignore[assignment]
    primal_residual: float | None = _FromProblem("primal_residual")  # type: ignore[assignment]
    native_status: str = ""
    problem: QPProblem | None = field(default=None, repr=False, compare=False)
