"""The base of every walking controller (``srbm``, ``kd``, and those to come).

It holds what they share: the robot, the terrain the controller knows, the ramped velocity
command (:class:`~gaitnet_mpc.command.CommandProfile`), the gait schedule, the low-level
controller, the solve statistics, the log of step durations and the telemetry the episode
runner records. Planning (footholds, swing, MPC) is the subclass's.
"""

from __future__ import annotations

import numpy as np

from gaitnet_mpc.command import Command, CommandProfile
from gaitnet_mpc.control.base import Controller, MomentumPrediction, MPCStats, Telemetry
from gaitnet_mpc.control.disturbance_observer import MomentumObserver
from gaitnet_mpc.control.lowlevel import LowLevelConfig, LowLevelController
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.gait import GaitSchedule, GaitScheduleConfig
from gaitnet_mpc.geometry import rotate2
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.state import RobotState


class WalkingBase(Controller):
    """Gait schedule, command profile, low-level control and telemetry of a walker.

    Attributes set by :meth:`reset`: ``t0_s`` (start time [s]), ``profile`` (ramped
    command and commanded heading), ``com0`` (CoM at the start [m]) and ``ground_z``
    (height of the ground under the feet at the start [m]).
    """

    def __init__(
        self,
        robot: RobotModel,
        terrain: TerrainView,
        command: Command,
        schedule: GaitScheduleConfig,
        low_level: LowLevelConfig,
        max_accel_mps2: float,
    ) -> None:
        self.robot = robot
        self.terrain = terrain
        self.command = command
        self.schedule = GaitSchedule(schedule)
        self.low = LowLevelController(robot, low_level)
        self.max_accel_mps2 = max_accel_mps2
        self._stats = MPCStats()
        self._steps: list[float] = []
        self.observer: MomentumObserver | None = None  # a subclass's disturbance observer

    def reset(self, state: RobotState) -> None:
        self.schedule.reset(state.t_s)
        self.t0_s = state.t_s
        self.profile = CommandProfile(
            self.command, state.t_s, float(state.base_rpy_rad[2]), self.max_accel_mps2
        )
        self.com0 = state.com_world_m.copy()
        self.ground_z = float(min(p[2] for p in state.foot_pos_world_m.values()))
        self.ground_z -= self.robot.spec.foot_contact_radius_m

    @property
    def mpc_stats(self) -> MPCStats:
        return self._stats

    @property
    def step_durations_s(self) -> list[float]:
        return self._steps

    def terrain_knowledge(self) -> dict[str, object]:
        return self.terrain.knowledge.to_dict()

    def telemetry(self) -> Telemetry:
        sched = self.schedule
        return Telemetry(
            step_dt_s=sched.current_step_dt_s,
            stance_foot=sched.stance_foot,
            swing_foot=sched.swing_foot,
            step_end_s=sched.step_start_time_s + sched.current_step_duration_s,
            prediction=self._prediction(),
            heading_rad=self.profile.heading_rad(sched.time_s),
            wrench_ext=None if self.observer is None else self.observer.wrench,
        )

    def _commanded_path_xy(self, t_s: float) -> np.ndarray:
        """(2,) point of the commanded CoM path at ``t_s``: the ramped command integrated
        from the start along the current commanded heading [m]."""
        c = self.command
        travel = self.profile.ramp_integral_s(t_s - self.t0_s)
        yaw = self.profile.heading_rad(t_s)
        return self.com0[:2] + travel * rotate2(yaw, (c.vx_mps, c.vy_mps))

    def _prediction(self) -> MomentumPrediction | None:
        """The momentum the last plan predicts one stage ahead (None: no such plan)."""
        return None
