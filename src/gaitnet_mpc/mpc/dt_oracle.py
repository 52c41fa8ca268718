"""A grid-search dt policy: the upper bound Gait-Net's choices are compared with.

At each step start the oracle solves the step's problem to convergence once for every dt
of a grid (each with that dt fixed, Remark 4), and keeps the dt whose converged plan has
the lowest eq. 18 cost (:meth:`~gaitnet_mpc.mpc.implicit_kd.KDSubproblem.plan_cost`). The
QP's constraints (friction, wrench limits, eq. 24 foothold boxes) hold at every solution
the QP returns, so "converged" is the only filter: a dt whose iterations hit ``j_max`` or
whose QP fails is not eligible. If no dt is eligible, the previous step's dt is kept (the
nominal one at the first step) and the step is counted as a fallback.

It costs one full solve per grid point at every step start, so it is slow by design; the
point is to ask, with the same model and references, which dt the MPC itself prefers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from gaitnet_mpc.dt_policy import NOMINAL_DT_S, oracle_grid_s, paper_dt_bounds_s
from gaitnet_mpc.errors import ConfigError, QPSolveError
from gaitnet_mpc.mpc.kd_iterate import KDIterate
from gaitnet_mpc.mpc.sequential import KDProblem, SequentialKDMPC

#: The grid of the paper's 3-D bounds [0.045, 0.07] s in 5 ms steps.
DEFAULT_GRID_S = oracle_grid_s(paper_dt_bounds_s(planar=False))


@dataclass(frozen=True)
class OracleConfig:
    """Settings of :class:`OracleDt`.

    Attributes:
        dts_s: the dts tried at every step start [s], increasing.
        nominal_dt_s: dt of the first step before any plan [s].
    """

    dts_s: tuple[float, ...] = DEFAULT_GRID_S
    nominal_dt_s: float = NOMINAL_DT_S

    def __post_init__(self) -> None:
        d = np.asarray(self.dts_s, dtype=float)
        if d.size == 0 or not np.all(np.isfinite(d)) or np.any(d <= 0) or np.any(np.diff(d) <= 0):
            raise ConfigError("dts_s", self.dts_s, "one or more increasing sampling times > 0 s")
        if not (math.isfinite(self.nominal_dt_s) and self.nominal_dt_s > 0):
            raise ConfigError("nominal_dt_s", self.nominal_dt_s, "a sampling time > 0 s")


@dataclass
class OracleDecision:
    """One step start: the cost of each grid dt (NaN: not converged) and the choice."""

    t_s: float
    costs: list[float] = field(default_factory=list)
    dt_s: float = math.nan
    fallback: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "t_s": round(self.t_s, 4),
            "dts_s": [round(self.dt_s, 5)],
            "costs": [None if math.isnan(c) else round(c, 4) for c in self.costs],
            "fallback": self.fallback,
        }


class OracleDt:
    """The grid-search dt policy; :meth:`attach` gives it the solver it searches with."""

    def __init__(self, config: OracleConfig | None = None) -> None:
        self.config = config or OracleConfig()
        self.decisions: list[OracleDecision] = []
        self._solver: SequentialKDMPC | None = None
        self._problem: KDProblem | None = None

    def attach(self, mpc: SequentialKDMPC) -> None:
        """Search with a solver of ``mpc``'s robot and settings (a separate instance, so
        the grid solves leave the caller's workspaces alone)."""
        self._solver = SequentialKDMPC(mpc.robot, mpc.config)

    @property
    def nominal_dt_s(self) -> float:
        return self.config.nominal_dt_s

    def __call__(self, problem: KDProblem, iterate: KDIterate, dt_s: float) -> float:
        if problem is not self._problem:  # a new step start: search once
            self._problem = problem
            self.decisions.append(self._search(problem))
        return self.decisions[-1].dt_s

    def _search(self, problem: KDProblem) -> OracleDecision:
        if self._solver is None:
            raise ConfigError("OracleDt", "not attached", "attach(mpc) before the first solve")
        t_s = problem.state.state.t_s if problem.state is not None else math.nan
        d = OracleDecision(t_s=t_s)
        timing = problem.timing
        dt0 = float(timing.stage_lengths_s[0])
        dts = np.asarray(timing.dts_s, dtype=float)
        for dt in self.config.dts_s:
            fixed = replace(problem, timing=timing.with_dts(dts * (dt / dt0)), choose_dt=False)
            try:
                result = self._solver.solve(fixed)
            except QPSolveError:
                d.costs.append(math.nan)
                continue
            d.costs.append(result.cost if result.converged else math.nan)
        costs = np.asarray(d.costs)
        if np.all(np.isnan(costs)):
            d.fallback = "none converged"
            previous = self.decisions[-1].dt_s if self.decisions else self.config.nominal_dt_s
            d.dt_s = previous
        else:
            d.dt_s = float(self.config.dts_s[int(np.nanargmin(costs))])
        return d

    def summary(self) -> dict[str, Any]:
        """``summary.json``'s ``dt_policy`` block."""
        return {
            "policy": "oracle",
            "decisions": len(self.decisions),
            "fallbacks": {"none converged": sum(d.fallback is not None for d in self.decisions)},
            "grid_s": list(self.config.dts_s),
            "steps": [d.to_dict() for d in self.decisions],
        }
