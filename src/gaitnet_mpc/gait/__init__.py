"""Gait timing and foot motion: contact schedule with per-step dt, swing trajectories, footholds.

* :class:`GaitSchedule` - fixed periodic contact sequence (h = 10 stages, h' = 5 per step, no
  double support) with one MPC sampling time per footstep (paper Sec. III-A, IV-B1).
* :class:`SwingTrajectory` - swing-foot path over Δt = h'·dt with apex and obstacle clearance.
* :class:`RaibertHeuristic` - foothold heuristic for controllers that do not optimise footholds.
* :class:`LandingBias` - averaged swing landing error, subtracted from later swing aims.
"""

from gaitnet_mpc.gait.foothold import RaibertConfig, RaibertHeuristic, keep_beside_stance
from gaitnet_mpc.gait.landing import LandingBias
from gaitnet_mpc.gait.schedule import (
    GaitHorizon,
    GaitSchedule,
    GaitScheduleConfig,
    StepDtLockedError,
    StepRecord,
)
from gaitnet_mpc.gait.swing import SwingConfig, SwingTrajectory, obstacle_array

__all__ = [
    "GaitHorizon",
    "GaitSchedule",
    "GaitScheduleConfig",
    "LandingBias",
    "RaibertConfig",
    "RaibertHeuristic",
    "StepDtLockedError",
    "StepRecord",
    "SwingConfig",
    "SwingTrajectory",
    "keep_beside_stance",
    "obstacle_array",
]
