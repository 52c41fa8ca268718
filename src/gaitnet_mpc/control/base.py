"""The interface every controller implements, its telemetry, and the per-episode MPC
statistics."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gaitnet_mpc.state import RobotState


@dataclass
class MPCStats:
    """Per-solve records of an MPC controller (one entry per solve).

    A *failed* solve found no usable solution (the QP backend raised
    :class:`~gaitnet_mpc.errors.QPSolveError`, or the NLP solver reported failure); it is
    also unconverged. An unconverged solve that did not fail (e.g. a sequential solve
    stopped at its iteration cap) still produced a plan.

    Attributes:
        solve_time_s: wall time of each solve, failed ones included [s].
        qps_per_solve: QPs (or NLP iterations) of each solve.
        converged: whether each solve converged.
        full_solve: whether each solve was a full one (at a step start) or a replan.
        failed: whether each solve failed.
    """

    solve_time_s: list[float] = field(default_factory=list)
    qps_per_solve: list[int] = field(default_factory=list)
    converged: list[bool] = field(default_factory=list)
    full_solve: list[bool] = field(default_factory=list)
    failed: list[bool] = field(default_factory=list)

    def record(
        self, solve_time_s: float, n_qps: int, converged: bool, full: bool, failed: bool = False
    ) -> None:
        """Append one solve's record (``failed``: no usable solution was found)."""
        self.solve_time_s.append(solve_time_s)
        self.qps_per_solve.append(n_qps)
        self.converged.append(converged)
        self.full_solve.append(full)
        self.failed.append(failed)

    def summary(self) -> dict[str, float | int | None]:
        """The ``mpc`` block of ``summary.json``."""
        if not self.solve_time_s:
            return {
                "solves": 0,
                "solve_ms_median": None,
                "solve_ms_p99": None,
                "qps_per_solve_mean": None,
                "failed_solves": 0,
            }
        ms = 1e3 * np.asarray(self.solve_time_s)
        qps = np.asarray(self.qps_per_solve, dtype=float)
        full = np.asarray(self.full_solve, dtype=bool)
        out: dict[str, float | int | None] = {
            "solves": len(ms),
            "solve_ms_median": float(np.median(ms)),
            "solve_ms_p99": float(np.percentile(ms, 99)),
            "qps_per_solve_mean": float(np.mean(qps)),
            "converged_fraction": float(np.mean(self.converged)),
            "failed_solves": int(sum(self.failed)),
        }
        for name, mask in (("full", full), ("replan", ~full)):
            if np.any(mask):
                out[f"{name}_solves"] = int(mask.sum())
                out[f"{name}_ms_median"] = float(np.median(ms[mask]))
                out[f"{name}_ms_p99"] = float(np.percentile(ms[mask], 99))
                out[f"qps_per_{name}_mean"] = float(np.mean(qps[mask]))
                out[f"{name}_not_converged_fraction"] = float(
                    1.0 - np.mean(np.asarray(self.converged)[mask])
                )
        return out


@dataclass(frozen=True)
class MomentumPrediction:
    """What a plan made at ``t_plan_s`` predicts for one stage later (``t_pred_s``): the
    centroidal momentum ``h_pred = [l_G (kg m/s); k_G (kg m^2/s)]`` (6,)."""

    t_plan_s: float
    t_pred_s: float
    h_pred: np.ndarray


@dataclass(frozen=True)
class Telemetry:
    """What a walking controller reports at each tick (``log.csv``, ``mpc_log.csv``).

    Attributes:
        step_dt_s: MPC sampling time of the current step [s].
        stance_foot: the foot that stands in the current step.
        swing_foot: the foot that swings in the current step.
        step_end_s: when the current step is scheduled to end (the swing foot's planned
            touchdown) [s].
        prediction: the last plan's one-stage momentum prediction (None: no plan, or a
            controller whose MPC does not predict momentum).
        heading_rad: the commanded trunk heading [rad] (Gait-Net's features are measured
            in its frame, :func:`~gaitnet_mpc.dataset.step_features.step_features`).
        wrench_ext: the disturbance observer's estimate ``[f_ext (N); tau_ext (N m)]`` (6,)
            (None: no observer).
    """

    step_dt_s: float
    stance_foot: str
    swing_foot: str
    step_end_s: float
    prediction: MomentumPrediction | None
    heading_rad: float = 0.0
    wrench_ext: np.ndarray | None = None


class Controller(ABC):
    """Maps a measured :class:`RobotState` to joint torques [N m] in actuator order."""

    name: str = "controller"

    def reset(self, state: RobotState) -> None:  # noqa: B027 - optional hook
        """Called once with the initial state before the first :meth:`compute`."""

    @abstractmethod
    def compute(self, state: RobotState) -> np.ndarray:
        """Joint torques for this tick; the simulator saturates them at the limits."""

    @property
    def mpc_stats(self) -> MPCStats | None:
        """Solve statistics, or None for controllers without an MPC."""
        return None

    @property
    def step_durations_s(self) -> list[float]:
        """Planned duration of each step the controller started (empty if it does not step)."""
        return []

    def last_dt_decision(self) -> dict[str, Any] | None:
        """The dt policy's decision at the latest step start (``dts_s``, ``fallback``,
        ``frozen``; ``mpc_log.csv``'s ``dt_*`` columns); None: no dt policy."""
        return None

    def dt_policy_summary(self) -> dict[str, object] | None:
        """How a learned dt policy decided (``summary.json``'s ``dt_policy``); None: the
        controller has none."""
        return None

    @property
    def swing_events(self) -> list[dict[str, Any]]:
        """Each time the controller raised an obstacle's assumed top for its swings
        (``summary.json``'s ``swing_events``: ``kind`` "toe_strike" or "shank", time,
        foot, the obstacle tops then assumed); empty for controllers that do not."""
        return []

    def telemetry(self) -> Telemetry | None:
        """This tick's telemetry, after :meth:`compute`; None for controllers without a
        gait (e.g. ``stand``)."""
        return None

    def terrain_knowledge(self) -> dict[str, object] | None:
        """What the controller knows about the terrain (``summary.json``'s
        ``terrain_knowledge``, see :mod:`~gaitnet_mpc.control.terrain_view`); None: nothing
        (e.g. ``stand``)."""
        return None

    def planned_footholds(self) -> list[tuple[str, np.ndarray]]:
        """(foot, position (3,) [m]) of each upcoming touchdown the controller plans now
        (drawn in the video); empty if it plans none."""
        return []
