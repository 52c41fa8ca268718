"""Gait-Net as the dt policy of Algorithm 1 (line 8), with the safeguards a network inside
a fixed-point loop needs.

At a step start every sequential iteration asks the policy for the step's dt. The policy
builds the features of the step start (:func:`~gaitnet_mpc.dataset.step_features.step_features`)
from the measured state and the iterate's planned touchdown of the swing foot, and returns
the network's dt, clipped into the paper's bounds of the robot
(:data:`~gaitnet_mpc.dt_policy.PAPER_DT_BOUNDS_S`, Sec. V-E1). Three safeguards (paper
Sec. VI names the failure: dts that do not settle and solves that hit ``j_max``):

* **out of distribution**: when the ensemble's spread exceeds ``max_spread_s`` the input
  lies outside what the data taught; the step keeps the dt the previous step ran with
  (re-timed under way or not; the nominal one at the first step), clipped into the
  bounds, for the rest of this solve;
* **cycling**: when the last three dt changes alternate in sign, the next dt is the
  midpoint of the last two; after ``max_damped`` damped iterations the previous step's dt
  is kept;
* **drift** (``max_retimes``): the network maps a touchdown back to the dt that made it,
  and the planner moves the touchdown with the dt, so the fixed point ``dt = net(x,
  p_td(dt))`` is at best neutrally stable: dts can drift in one direction to a bound
  (measured, docs/design/gaitnet.md). After ``max_retimes`` changes of the dt the step's
  dt is frozen and the iterations only converge the plan (not a fallback: counted as
  ``frozen``).

Every decision is recorded (``decisions``): time, the dt of each iteration, the spread,
the fallback reason if any, and the 16 features (``FEATURE_NAMES`` order) of its last call
to the network.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gaitnet_mpc.dataset.step_features import mirror_features, step_features
from gaitnet_mpc.dt_policy import (
    NOMINAL_DT_S,
    GaitNetPolicyConfig,
    clip_dt,
    paper_dt_bounds_s,
)
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gaitnet.model import GaitNet
from gaitnet_mpc.mpc.kd_iterate import KDIterate
from gaitnet_mpc.mpc.sequential import KDProblem, planned_touchdowns

FALLBACKS = ("spread", "cycle")


@dataclass
class Decision:
    """One step start: the dt asked at each iteration and how it ended."""

    t_s: float
    start_dt_s: float
    dts_s: list[float] = field(default_factory=list)
    spreads_s: list[float] = field(default_factory=list)
    fallback: str | None = None
    damped: int = 0
    frozen: bool = False
    features: np.ndarray | None = None  # (16,) the last input the network was given
    retimed_dt_s: float | None = None  # the dt the step under way was re-timed to

    @property
    def executed_dt_s(self) -> float:
        """The dt the step ran with: the chosen one, or the one it was re-timed to."""
        return self.dts_s[-1] if self.retimed_dt_s is None else self.retimed_dt_s

    def to_dict(self) -> dict[str, Any]:
        return {
            "t_s": round(self.t_s, 4),
            "dts_s": [round(d, 5) for d in self.dts_s],
            "spread_max_s": round(max(self.spreads_s, default=0.0), 5),
            "fallback": self.fallback,
            "frozen": self.frozen,
            "retimed_dt_s": None if self.retimed_dt_s is None else round(self.retimed_dt_s, 5),
            "features": None
            if self.features is None
            else [round(float(v), 5) for v in self.features],
        }


class GaitNetDt:
    """Gait-Net in the dt-policy slot of :class:`~gaitnet_mpc.mpc.sequential.SequentialKDMPC`.

    Args:
        net: the network.
        planar: the robot kind, for the paper's bounds when ``bounds_s`` is None.
        config: the safeguards.
        bounds_s: (min, max) of a chosen dt [s]; None: the paper's bounds of the robot.
        nominal_dt_s: dt of the first step, and the fallback before any step [s].
    """

    def __init__(
        self,
        net: GaitNet,
        planar: bool,
        config: GaitNetPolicyConfig | None = None,
        *,
        bounds_s: tuple[float, float] | None = None,
        nominal_dt_s: float = NOMINAL_DT_S,
    ) -> None:
        self.net = net
        self.config = config or GaitNetPolicyConfig()
        self.bounds_s = bounds_s or paper_dt_bounds_s(planar)
        self._nominal_dt_s = nominal_dt_s
        from gaitnet_mpc.dataset.schema import FEATURE_NAMES

        self._columns = [FEATURE_NAMES.index(n) for n in net.feature_names]
        self.decisions: list[Decision] = []
        self._problem: KDProblem | None = None

    @property
    def nominal_dt_s(self) -> float:
        return self._nominal_dt_s

    def __call__(self, problem: KDProblem, iterate: KDIterate, dt_s: float) -> float:
        if problem.state is None:
            raise ConfigError("KDProblem.state", None, "the step-start state (Gait-Net's input)")
        if problem is not self._problem:  # a new step start
            self._problem = problem
            self.decisions.append(Decision(t_s=problem.state.state.t_s, start_dt_s=dt_s))
        d = self.decisions[-1]
        dt = self._choose(problem, iterate, d)
        d.dts_s.append(dt)
        return dt

    def _choose(self, problem: KDProblem, iterate: KDIterate, d: Decision) -> float:
        if d.fallback is not None or d.frozen:
            return d.dts_s[-1]
        limit = self.config.max_retimes if self.config.safeguards else None
        if limit is not None and d.dts_s:
            changes = np.abs(np.diff([d.start_dt_s, *d.dts_s])) > self.config.cycle_tolerance_s
            if int(np.sum(changes)) >= limit:
                d.frozen = True
                return d.dts_s[-1]
        s = problem.state
        assert s is not None
        touchdown = planned_touchdowns(iterate, np.asarray(problem.timing.contact))
        x = step_features(
            s.state, s.stance_foot, s.swing_foot, touchdown[s.swing_foot][0], problem.heading_rad
        )
        d.features = x
        if self.config.mirror_symmetric:
            dt, spread = self.net.predict(x[self._columns], mirror_features(x)[self._columns])
        else:
            dt, spread = self.net.predict(x[self._columns])
        d.spreads_s.append(spread)
        bounds = self.bounds_s
        if not self.config.safeguards:
            return clip_dt(dt, bounds)
        if spread > self.config.max_spread_s:
            d.fallback = "spread"
            return clip_dt(self._previous_dt_s(), bounds)
        dt = clip_dt(dt, bounds)
        if self._cycling([*d.dts_s, dt]):
            if d.damped >= self.config.max_damped:
                d.fallback = "cycle"
                return clip_dt(self._previous_dt_s(), bounds)
            d.damped += 1
            return 0.5 * (d.dts_s[-1] + dt)
        return dt

    def step_retimed(self, dt_s: float) -> None:
        """The step under way was re-timed to ``dt_s`` [s]
        (:class:`~gaitnet_mpc.control.step_retiming.StepRetimer`)."""
        if self.decisions:
            self.decisions[-1].retimed_dt_s = dt_s

    def _previous_dt_s(self) -> float:
        """The dt the previous step ran with (the nominal dt before the first)."""
        if len(self.decisions) < 2:
            return self._nominal_dt_s
        return self.decisions[-2].executed_dt_s

    def _cycling(self, dts: list[float]) -> bool:
        """The last three changes alternate in sign and exceed the tolerance."""
        if len(dts) < 4:
            return False
        steps = np.diff(dts[-4:])
        if np.any(np.abs(steps) < self.config.cycle_tolerance_s):
            return False
        return bool(steps[0] * steps[1] < 0 and steps[1] * steps[2] < 0)

    def weights_info(self) -> dict[str, Any]:
        """Where the network came from (``summary.json``'s ``dt_policy.weights``)."""
        spec = self.net.spec
        return {
            "teacher": spec.teacher,
            "data_manifest_sha256": spec.data_manifest_sha256,
            "features": list(self.net.feature_names),
            "members": spec.members,
        }

    def summary(self) -> dict[str, Any]:
        """``summary.json``'s ``dt_policy`` block: counts and every decision."""
        n = len(self.decisions)
        counts = {r: sum(d.fallback == r for d in self.decisions) for r in FALLBACKS}
        iters = [len(d.dts_s) for d in self.decisions]
        return {
            "policy": "gaitnet",
            "decisions": n,
            "fallbacks": counts,
            "frozen": sum(d.frozen for d in self.decisions),
            "dt_bounds_s": list(self.bounds_s),
            "calls_per_decision_mean": float(np.mean(iters)) if iters else None,
            "steps": [d.to_dict() for d in self.decisions],
        }
