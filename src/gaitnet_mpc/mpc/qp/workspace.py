"""Abstract QP workspace: solver state kept across repeated solves.

A workspace is created once per MPC (``make_workspace("osqp", eps_abs=1e-6)``) and
:meth:`QPWorkspace.solve` is called every control tick.  Backends that support it
(OSQP, PIQP, qpOASES) keep their factorisation/setup and only push new numbers
when the sparsity structure of the problem is unchanged; otherwise they set up
from scratch.  The counters :attr:`QPWorkspace.n_setups` and
:attr:`QPWorkspace.n_updates` tell which path was taken.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np

from gaitnet_mpc.errors import ConfigError, QPSolveError
from gaitnet_mpc.mpc.qp.problem import QPProblem
from gaitnet_mpc.mpc.qp.solution import SOLVED_STATUSES, QPSolution

#: Statuses for which the backend's iterate is handed back in ``QPSolution.x``.
_ITERATE_STATUSES = frozenset({"solved", "solved_inaccurate", "max_iter"})


@dataclass(frozen=True)
class BackendResult:
    """What a backend's :meth:`QPWorkspace._solve` reports, before post-processing.

    Attributes:
        x: The backend's primal iterate (any array-like of length ``n``) or ``None``.
        status: The backend status mapped to one of ``solution.STATUSES``.
        native_status: The backend's own status text.
        iterations: Iteration count reported by the backend.
    """

    x: Any
    status: str
    native_status: str
    iterations: int = 0


class QPWorkspace(ABC):
    """Base class of every QP backend.

    Subclasses set :attr:`name`, :attr:`default_options`, optionally
    :attr:`available`/:attr:`import_error`, and implement :meth:`_solve` and
    :meth:`_check_options`.

    Args:
        inaccurate_tol: Largest primal residual with which a
            ``"solved_inaccurate"`` result still counts as found.
        check_problem: Call :meth:`QPProblem.validate` on every solve (cheap for
            MPC-sized problems; switch off only in hot loops with trusted data).
        **options: Backend settings, overriding :attr:`default_options`.

    Raises:
        ConfigError: the backend package is not importable, or an option is
            unknown to the backend.
    """

    #: Registry name of the backend.
    name: ClassVar[str] = "abstract"
    #: Whether the backend package could be imported.
    available: ClassVar[bool] = True
    #: Text of the import failure when :attr:`available` is ``False``.
    import_error: ClassVar[str | None] = None
    #: Settings applied unless overridden by keyword options.
    default_options: ClassVar[Mapping[str, Any]] = MappingProxyType({})
    #: Whether unchanged structure leads to an in-place update instead of a setup.
    supports_update: ClassVar[bool] = False
    #: Whether the ``warm_start`` argument of :meth:`solve` is used.
    supports_warm_start: ClassVar[bool] = False

    def __init__(
        self, *, inaccurate_tol: float = 1e-3, check_problem: bool = True, **options: Any
    ) -> None:
        if not self.available:
            raise ConfigError(
                "qp_backend",
                self.name,
                f"an installed backend (importing it failed: {self.import_error})",
            )
        if not inaccurate_tol >= 0.0:
            raise ConfigError("inaccurate_tol", inaccurate_tol, "a non-negative float")
        self.inaccurate_tol = float(inaccurate_tol)
        self.check_problem = bool(check_problem)
        self.options: dict[str, Any] = {**self.default_options, **options}
        self._check_options(self.options)
        #: Number of full backend setups performed so far.
        self.n_setups = 0
        #: Number of solves that reused the previous setup via an in-place update.
        self.n_updates = 0
        self._structure: tuple[Any, ...] | None = None

    # ------------------------------------------------------------ public API
    def solve(self, problem: QPProblem, warm_start: np.ndarray | None = None) -> QPSolution:
        """Solve ``problem``, reusing solver state when its structure is unchanged.

        Args:
            problem: The QP.
            warm_start: Primal guess of shape ``(n,)``; ignored by backends without
                warm-start support (see :attr:`supports_warm_start`) and when it
                contains non-finite values.

        Returns:
            A :class:`QPSolution`; failures are reported through ``status`` and
            ``found``, never raised (backend exceptions become
            ``"numerical_error"`` with the exception text in ``native_status``).

        Raises:
            ConfigError: ``problem`` fails :meth:`QPProblem.validate` (when
                ``check_problem``) or ``warm_start`` has the wrong shape.
        """
        if self.check_problem:
            problem.validate()
        guess = self._check_warm_start(warm_start, problem.n)
        crossed = problem.crossed_bounds()
        if crossed is not None:
            result = BackendResult(None, "infeasible", f"{crossed}: lower bound above upper")
            return self._finish(problem, result, 0.0)
        start = time.perf_counter()
        try:
            result = self._solve(problem, guess)
        except Exception as exc:  # backend failures are data, not crashes
            self._structure = None
            self._reset_backend()
            result = BackendResult(None, "numerical_error", f"{type(exc).__name__}: {exc}")
        elapsed = time.perf_counter() - start
        if result.status not in SOLVED_STATUSES:
            self._after_failure()
        return self._finish(problem, result, elapsed)

    def solve_or_raise(
        self, problem: QPProblem, warm_start: np.ndarray | None = None
    ) -> QPSolution:
        """Like :meth:`solve` but raise when no usable solution was found.

        Raises:
            QPSolveError: ``found`` is ``False``; carries backend name and status.
        """
        sol = self.solve(problem, warm_start)
        if not sol.found:
            detail = sol.native_status
            if sol.primal_residual is not None:
                detail = f"{detail} (primal residual {sol.primal_residual:.3g})"
            raise QPSolveError(self.name, sol.status, detail)
        return sol

    def reset(self) -> None:
        """Forget all solver state; the next solve performs a full setup."""
        self._structure = None
        self._reset_backend()

    # ------------------------------------------------------ subclass hooks
    @abstractmethod
    def _solve(self, problem: QPProblem, warm_start: np.ndarray | None) -> BackendResult:
        """Run the backend on ``problem`` (validated) and map its status."""

    @abstractmethod
    def _check_options(self, options: Mapping[str, Any]) -> None:
        """Raise :class:`ConfigError` for an option the backend does not know."""

    def _reset_backend(self) -> None:  # noqa: B027 - optional hook
        """Drop backend objects (called by :meth:`reset` and after exceptions)."""

    def _after_failure(self) -> None:  # noqa: B027 - optional hook
        """Called after every solve that did not end in a solved status."""

    # ----------------------------------------------------------- helpers
    def _structure_changed(self, structure: tuple[Any, ...]) -> bool:
        """Record ``structure`` and say whether a full setup is needed.

        Increments :attr:`n_setups` or :attr:`n_updates` accordingly.
        """
        if self._structure is not None and self._structure == structure:
            self.n_updates += 1
            return False
        self._structure = structure
        self.n_setups += 1
        return True

    def _invalidate_structure(self) -> None:
        """Force the next solve to set up from scratch."""
        self._structure = None

    def _unknown_options(self, options: Mapping[str, Any], known: set[str]) -> None:
        unknown = sorted(set(options) - known)
        if unknown:
            raise ConfigError(f"{self.name} options", unknown, f"names among {sorted(known)}")

    @staticmethod
    def _check_warm_start(warm_start: np.ndarray | None, n: int) -> np.ndarray | None:
        if warm_start is None:
            return None
        guess = np.asarray(warm_start, dtype=np.float64)
        if guess.shape != (n,):
            raise ConfigError("warm_start", guess.shape, f"shape ({n},)")
        if not np.all(np.isfinite(guess)):
            return None
        return guess

    def _finish(self, problem: QPProblem, result: BackendResult, elapsed: float) -> QPSolution:
        status = result.status
        x: np.ndarray | None = None
        if result.x is not None and status in _ITERATE_STATUSES:
            x = np.array(result.x, dtype=np.float64).reshape(-1)  # copy: detach from backend
            if x.shape != (problem.n,):
                x, status = None, "unknown"
            elif not np.all(np.isfinite(x)):
                x = None
                if status in SOLVED_STATUSES:
                    status = "nan"
        if x is None and status in SOLVED_STATUSES:
            status = "nan"
        sol = QPSolution(
            x=x,
            status=status,
            found=status == "solved",
            iterations=int(result.iterations),
            solve_time_s=float(elapsed),
            backend=self.name,
            native_status=result.native_status,
            problem=problem,
        )
        if status == "solved_inaccurate":
            residual = sol.primal_residual
            sol.found = residual is not None and residual <= self.inaccurate_tol
        return sol
