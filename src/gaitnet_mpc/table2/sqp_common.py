"""What the ``sqpmethod`` baselines of Table II share: settings, stopping test, one solve.

Every SQP column of Table II (CD-SQP, explicit KD-SQP, WBD-SQP) is CasADi's ``sqpmethod``
with qpOASES for the QP sub-problems (Sec. V-A), exact Hessian, cold from the common
``u^0``, stopped by the same step test: Table X's step norms, applied by an
``iteration_callback`` to *measured* quantities of consecutive iterates (CoM and foot
positions [m], contact forces [N], contact moments [N m], and for the variable-dt methods
the sampling times [s], held to ``position_m`` numerically). ``sqpmethod``'s own tests are
switched off (``tol_pr = tol_du = 1e-14``); a stop by the callback is CasADi's
"User_Requested_Stop" and counts as converged. Every SQP iteration solves one QP, so
"QPs per solve" is the iteration count.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.kd_iterate import KDTolerances

#: measure(x) -> group name -> values whose change between iterates is tested.
Measure = Callable[[np.ndarray], Mapping[str, np.ndarray]]


@contextlib.contextmanager
def quiet_c_stdout() -> Iterator[None]:
    """Silence C-level stdout (qpOASES prints a licence banner when set up)."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


@dataclass(frozen=True)
class SQPConfig:
    """Settings of an ``sqpmethod`` baseline.

    Attributes:
        qpsol: CasADi conic plugin of the QP sub-problems (paper: ``"qpoases"``).
        max_iter: SQP iteration cap (Algorithm 1's ``j_max``).
        tolerances: Table X step norms (module docstring).
        full_steps: no line search (``max_iter_ls = 0``).
        convexify: CasADi ``convexify_strategy`` of the exact Hessian (None: none).
        qpsol_options: extra options of the QP plugin (over the quiet defaults).
    """

    qpsol: str = "qpoases"
    max_iter: int = 50
    tolerances: KDTolerances = field(default_factory=KDTolerances)
    full_steps: bool = False
    convexify: str | None = None
    qpsol_options: tuple[tuple[str, Any], ...] = ()

    def __post_init__(self) -> None:
        if not ca.has_conic(self.qpsol):
            raise ConfigError("qpsol", self.qpsol, "a CasADi conic plugin (casadi.has_conic)")
        if not isinstance(self.max_iter, int) or self.max_iter < 1:
            raise ConfigError("max_iter", self.max_iter, "an integer >= 1")

    def tolerance_of(self, group: str) -> float:
        """Step tolerance of a measured group: ``position`` and ``dt`` [m, s] use
        ``position_m``, ``force`` [N] ``force_n``, ``moment`` [N m] ``moment_nm``."""
        tol = self.tolerances
        table = {
            "position": tol.position_m,
            "dt": tol.position_m,
            "force": tol.force_n,
            "moment": tol.moment_nm,
        }
        if group not in table:
            raise ConfigError("step test group", group, f"one of {sorted(table)}")
        return table[group]


class StepTest(ca.Callback):
    """``iteration_callback``: stop once every measured group changed by at most its
    tolerance between two consecutive iterates (module docstring)."""

    def __init__(self, name: str, n_x: int, n_g: int, n_p: int, measure: Measure) -> None:
        ca.Callback.__init__(self)
        self._sizes = {"x": n_x, "f": 1, "g": n_g, "lam_x": n_x, "lam_g": n_g, "lam_p": n_p}
        self._measure = measure
        self.tolerances: dict[str, float] = {}
        self.previous: Mapping[str, np.ndarray] | None = None
        self.converged = False
        self.construct(name, {})

    def reset(self, config: SQPConfig, groups: Sequence[str]) -> None:
        """Forget the last iterate; test ``groups`` with ``config``'s tolerances."""
        self.tolerances = {g: config.tolerance_of(g) for g in groups}
        self.previous = None
        self.converged = False

    def get_n_in(self) -> int:
        return int(ca.nlpsol_n_out())

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return str(ca.nlpsol_out(i))

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> Any:
        n = self._sizes.get(str(ca.nlpsol_out(i)), 0)
        return ca.Sparsity.dense(n, 1) if n else ca.Sparsity(0, 0)

    def eval(self, args: Sequence[Any]) -> list[Any]:  # type: ignore[override]
        now = self._measure(np.asarray(args[0], dtype=float).ravel())
        prev, self.previous = self.previous, now
        if prev is None:
            return [0]
        self.converged = all(
            np.max(np.abs(now[g] - prev[g]), initial=0.0) <= tol
            for g, tol in self.tolerances.items()
        )
        return [1 if self.converged else 0]


def sqp_options(config: SQPConfig, callback: StepTest) -> dict[str, Any]:
    """``nlpsol`` options of ``sqpmethod`` (module docstring)."""
    opts: dict[str, Any] = {
        "qpsol": config.qpsol,
        "hessian_approximation": "exact",
        "max_iter": config.max_iter,
        "tol_pr": 1e-14,
        "tol_du": 1e-14,
        "min_step_size": 1e-16,
        "iteration_callback": callback,
        "print_header": False,
        "print_iteration": False,
        "print_status": False,
        "print_time": False,
        "error_on_fail": False,
    }
    qp_opts: dict[str, Any]
    if config.qpsol == "qpoases":
        qp_opts = {"printLevel": "none", "error_on_fail": False}
    elif config.qpsol == "osqp":
        qp_opts = {"osqp": {"verbose": False}, "error_on_fail": False}
    else:
        qp_opts = {"error_on_fail": False}
    qp_opts.update(dict(config.qpsol_options))
    opts["qpsol_options"] = qp_opts
    if config.convexify is not None:
        opts["convexify_strategy"] = config.convexify
    if config.full_steps:
        opts["max_iter_ls"] = 0
    return opts


def build_sqp(
    name: str, nlp: Mapping[str, Any], config: SQPConfig, measure: Measure
) -> tuple[Any, StepTest]:
    """An ``sqpmethod`` solver of ``nlp`` (keys x, p, f, g) with its step test."""
    x, g, p = nlp["x"], nlp["g"], nlp["p"]
    test = StepTest(f"{name}_step_test", x.numel(), g.numel(), p.numel(), measure)
    with quiet_c_stdout():
        solver = ca.nlpsol(name, "sqpmethod", dict(nlp), sqp_options(config, test))
    return solver, test


@dataclass(frozen=True)
class SQPRun:
    """Raw outcome of one ``sqpmethod`` call.

    Attributes:
        x: (n,) last iterate (the initial guess where the QP plugin raised);
        n_qps: SQP iterations; converged: stopped by the step test; solve_time_s: wall
        time of the call [s]; status: CasADi's return status or ``"error: ..."``.
    """

    x: np.ndarray
    n_qps: int
    converged: bool
    solve_time_s: float
    status: str


def run_sqp(
    solver: Any,
    test: StepTest,
    config: SQPConfig,
    groups: Sequence[str],
    args: Mapping[str, Any],
) -> SQPRun:
    """One timed solve from ``args["x0"]``. A QP plugin that fails hard (CasADi raises)
    gives ``converged=False``, the guess and ``max_iter`` QPs."""
    test.reset(config, groups)
    t0 = time.perf_counter()
    try:
        with quiet_c_stdout():  # PIQP warns on rows with two infinite bounds
            out = solver(**args)
    except RuntimeError as exc:  # a QP plugin that asserts (OSQP on an indefinite H)
        elapsed = time.perf_counter() - t0
        status = f"error: {str(exc).splitlines()[-1]}"
        x0 = np.asarray(args["x0"], dtype=float).ravel()
        return SQPRun(x0, config.max_iter, False, elapsed, status)
    elapsed = time.perf_counter() - t0
    stats = solver.stats()
    x = np.asarray(out["x"], dtype=float).ravel()
    return SQPRun(x, int(stats["iter_count"]), test.converged, elapsed, str(stats["return_status"]))


def constraint_violation(
    g: np.ndarray, lbg: np.ndarray, ubg: np.ndarray, x: np.ndarray, lbx: np.ndarray,
    ubx: np.ndarray,
) -> float:  # fmt: skip
    """Largest violation of ``lbg <= g <= ubg`` and ``lbx <= x <= ubx``."""
    parts = [lbg - g, g - ubg, lbx - x, x - ubx]
    return max(float(np.max(np.nan_to_num(v, nan=0.0, neginf=0.0), initial=0.0)) for v in parts)


def objective_and_violation(g_fun: Any, args: dict[str, Any], x: np.ndarray) -> tuple[float, float]:
    """(objective, largest constraint/bound violation) at ``x`` of an NLP whose
    ``g_fun(x, p)`` gives (g, objective) and whose ``args`` hold p and the bounds."""
    g, obj = g_fun(x, args["p"])
    viol = constraint_violation(
        np.asarray(g).ravel(), args["lbg"], args["ubg"], x, args["lbx"], args["ubx"]
    )
    return float(obj), viol


__all__ = [
    "Measure",
    "SQPConfig",
    "SQPRun",
    "StepTest",
    "build_sqp",
    "constraint_violation",
    "objective_and_violation",
    "quiet_c_stdout",
    "run_sqp",
    "sqp_options",
]
