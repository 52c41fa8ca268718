"""``srbm``: walking with the SRBM convex MPC, fixed gait frequency and heuristic footholds.

Per control tick (1 kHz): advance the gait schedule; at each step start, plan the swing
foot's foothold (Raibert heuristic) and its swing trajectory; every ``replan_period_s``
(and at each step start) solve the SRBM MPC over the next two steps; send the first
stage's stance wrench and the swing target to the low-level controller.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from gaitnet_mpc.control.base import Controller, MPCStats
from gaitnet_mpc.control.lowlevel import LowLevelConfig, LowLevelController
from gaitnet_mpc.control.stance import StanceMap
from gaitnet_mpc.errors import QPSolveError
from gaitnet_mpc.gait import (
    GaitSchedule,
    GaitScheduleConfig,
    RaibertConfig,
    RaibertHeuristic,
    SwingConfig,
    SwingTrajectory,
)
from gaitnet_mpc.mpc.srbm import NX, SRBMMPC, SRBMConfig
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.sim.state import RobotState
from gaitnet_mpc.terrain import Course


@dataclass(frozen=True)
class SRBMWalkConfig:
    """Settings of the SRBM walking controller."""

    dt_s: float = 0.045  # MPC stage = 1/5 of a step (step 0.225 s)
    replan_period_s: float = 0.01
    com_height_m: float | None = None  # default: the height at reset
    max_pos_error_m: float = 0.05  # clamp of the position-tracking error in the reference
    max_accel_mps2: float = 1.0  # the command is ramped up from rest at this rate
    path_gain_per_s: float = 1.0  # CoM path error -> velocity added to the foothold command
    retarget_stop_fraction: float = 0.8  # footholds are frozen in the last 20 % of a swing
    mpc: SRBMConfig = field(default_factory=SRBMConfig)
    low_level: LowLevelConfig = field(default_factory=LowLevelConfig)
    swing: SwingConfig = field(
        default_factory=lambda: SwingConfig(touchdown_speed_mps=0.3, foot_half_length_m=0.075)
    )
    touchdown_depth_m: float = 0.005  # swing targets end this far below the ground


def centroidal_inertia_body(robot: RobotModel) -> np.ndarray:
    """Composite rotational inertia about the CoM at the nominal pose (3, 3) [kg m^2]."""
    q, v = robot.mj_to_pin(robot.standing_qpos(), np.zeros(robot.nv))
    data = robot.pin_model.createData()
    pin.ccrba(robot.pin_model, data, q, v)
    return np.array(data.Ig.inertia)


class SRBMWalkController(Controller):
    """SRBM MPC + gait schedule + Raibert footholds + low-level control."""

    name = "srbm"

    def __init__(
        self,
        robot: RobotModel,
        course: Course,
        command: object,
        config: SRBMWalkConfig | None = None,
    ) -> None:
        self.robot = robot
        self.course = course
        self.command = command
        self.config = config or SRBMWalkConfig()
        c = self.config
        planar = robot.spec.planar
        self.mpc = SRBMMPC(
            robot.total_mass_kg,
            centroidal_inertia_body(robot),
            robot.spec.foot_toe_m,
            robot.spec.foot_heel_m,
            c.mpc,
        )
        self.low = LowLevelController(robot, c.low_level)
        self.stance_map = StanceMap(robot)
        lateral = 0.0 if planar else 0.065
        self.raibert = RaibertHeuristic(
            RaibertConfig(
                hip_lateral_offset_m=lateral,
                min_lateral_separation_m=0.0 if planar else 0.08,
                max_lateral_separation_m=0.0 if planar else 0.30,
            )
        )
        self.schedule = GaitSchedule(GaitScheduleConfig(default_dt_s=c.dt_s))
        self._stats = MPCStats()
        self._steps: list[float] = []

    # --------------------------------------------------------------- episode
    def reset(self, state: RobotState) -> None:
        self.schedule.reset(state.t_s)
        self.mpc.reset()
        self.t0_s = state.t_s
        self.com0 = state.com_world_m.copy()
        self.yaw0 = float(state.base_rpy_rad[2])
        self.z_ref = self.config.com_height_m or float(state.com_world_m[2])
        self.ground_z = float(min(p[2] for p in state.foot_pos_world_m.values()))
        self.ground_z -= self.robot.spec.foot_contact_radius_m
        self.foot_pos = {f: state.foot_pos_world_m[f].copy() for f in FEET}
        self.foothold = dict(self.foot_pos)
        self.swing: SwingTrajectory | None = None
        self.wrench: np.ndarray | None = None
        self.next_replan_s = -np.inf

    @property
    def mpc_stats(self) -> MPCStats:
        return self._stats

    @property
    def step_durations_s(self) -> list[float]:
        return self._steps

    # ------------------------------------------------------------- helpers
    def _ramp(self, t_s: float) -> float:
        """Fraction of the command applied ``t_s`` after the start (acceleration limit)."""
        v_max = max(abs(self.command.vx_mps), abs(self.command.vy_mps), 1e-9)
        return min(1.0, t_s * self.config.max_accel_mps2 / v_max)

    def _cmd_world(self, yaw: float, t_s: float) -> np.ndarray:
        """Commanded CoM velocity (3,) in the world at time ``t_s`` after the start."""
        c, s = np.cos(yaw), np.sin(yaw)
        k = self._ramp(t_s)
        vx, vy = k * self.command.vx_mps, k * self.command.vy_mps
        return np.array([c * vx - s * vy, s * vx + c * vy, 0.0])

    def _desired_com_xy(self, t_s: float) -> np.ndarray:
        """Commanded CoM path (2,) at ``t_s`` after the start (ramped command integrated;
        the heading is taken at ``t_s``, exact for straight walking)."""
        v_max = max(abs(self.command.vx_mps), abs(self.command.vy_mps), 1e-9)
        t_ramp = v_max / self.config.max_accel_mps2
        travel_s = t_s * t_s / (2 * t_ramp) if t_s < t_ramp else t_s - t_ramp / 2
        yaw = self._heading_cmd(self.t0_s + t_s)
        c, s = np.cos(yaw), np.sin(yaw)
        vx, vy = self.command.vx_mps, self.command.vy_mps
        return self.com0[:2] + travel_s * np.array([c * vx - s * vy, s * vx + c * vy])

    def _x0(self, state: RobotState) -> np.ndarray:
        rpy = state.base_rpy_rad
        return np.concatenate(
            [rpy, state.com_world_m, state.base_ang_vel_world_radps, state.com_vel_world_mps, [1]]
        )

    def _reference(self, state: RobotState, stage_times: np.ndarray) -> np.ndarray:
        """(h + 1, 13) references at the stage boundaries ``stage_times`` (from now)."""
        t_now = state.t_s - self.t0_s
        yaw_rate = self.command.yaw_rate_radps
        yaw_now = self.yaw0 + yaw_rate * t_now
        x_ref = np.zeros((len(stage_times), NX))
        # Desired CoM path integrated from the start, error clamped to avoid wind-up.
        lim = self.config.max_pos_error_m
        err = np.clip(self._desired_com_xy(t_now) - state.com_world_m[:2], -lim, lim)
        base_xy = state.com_world_m[:2] + err
        for k, tk in enumerate(stage_times):
            yaw_k = yaw_now + yaw_rate * tk
            v_cmd = self._cmd_world(yaw_k, t_now + tk)
            x_ref[k, 2] = yaw_k
            x_ref[k, 3:5] = base_xy + v_cmd[:2] * tk
            x_ref[k, 5] = self.z_ref
            x_ref[k, 8] = yaw_rate
            x_ref[k, 9:12] = v_cmd
            x_ref[k, 12] = 1.0
        if self.robot.spec.planar:
            x_ref[:, [0, 2, 4, 6, 8, 10]] = 0.0
        return x_ref

    def _plan_foothold(self, state: RobotState, foot: str, t_touchdown_s: float) -> np.ndarray:
        sched = self.schedule
        yaw = float(state.base_rpy_rad[2])
        stance = sched.stance_foot
        # Steer the footholds back to the commanded path: a position error adds a bounded
        # velocity to the command the heuristic sees (heading frame).
        t_now = state.t_s - self.t0_s
        ex, ey = self._desired_com_xy(t_now) - state.com_world_m[:2]
        c, s_ = np.cos(yaw), np.sin(yaw)
        err_heading = np.array([c * ex + s_ * ey, -s_ * ex + c * ey])
        v_fb = np.clip(self.config.path_gain_per_s * err_heading, -0.2, 0.2)
        ramp = self._ramp(t_now)
        p = self.raibert.foothold(
            foot,
            p_com_world_m=state.com_world_m,
            v_com_world_mps=state.com_vel_world_mps,
            cmd_vel_mps=ramp * np.array([self.command.vx_mps, self.command.vy_mps]) + v_fb,
            stance_duration_s=sched.current_step_duration_s,
            time_to_touchdown_s=t_touchdown_s,
            p_stance_foot_world_m=state.foot_pos_world_m[stance],
            ground_z_m=self.ground_z,
            yaw_rad=yaw,
            cmd_yaw_rate_radps=self.command.yaw_rate_radps,
        )
        p[2] = self.ground_z + self.robot.spec.foot_contact_radius_m - self.config.touchdown_depth_m
        if self.robot.spec.planar:
            p[1] = state.foot_pos_world_m[foot][1]
        return p

    def _on_step_start(self, state: RobotState) -> None:
        sched = self.schedule
        self._steps.append(sched.current_step_duration_s)
        swing_foot = sched.swing_foot
        self.foot_pos[sched.stance_foot] = state.foot_pos_world_m[sched.stance_foot].copy()
        target = self._plan_foothold(state, swing_foot, sched.current_step_duration_s)
        self.foothold[swing_foot] = target
        obstacles = self.course.obstacles_between(
            min(state.foot_pos_world_m[swing_foot][0], target[0]),
            max(state.foot_pos_world_m[swing_foot][0], target[0]),
        )
        self.swing = self.config.swing.trajectory(
            state.foot_pos_world_m[swing_foot],
            target,
            sched.current_step_duration_s,
            [(o.x_min, o.x_max, o.z_top_m) for o in obstacles],
        )
        self.next_replan_s = -np.inf

    def _update_foothold(self, state: RobotState) -> None:
        """Re-plan the swing foot's foothold with the current CoM velocity (until the
        last ``retarget_stop_fraction`` of the swing) and bend the swing path to it."""
        sched = self.schedule
        if self.swing is None or sched.phase_in_step > self.config.retarget_stop_fraction:
            return
        foot = sched.swing_foot
        target = self._plan_foothold(state, foot, sched.time_left_in_step_s)
        if self.swing.retarget(target, sched.time_in_step_s):
            self.foothold[foot] = target

    def _torque_limits(
        self, state: RobotState, foot_index: int, mask: np.ndarray
    ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        """Stance-leg torque limits for the MPC: ``|J_leg^T [f; m]| <= tau_max`` with the
        current leg Jacobian, on the stages of the current step."""
        q, v = self.robot.mj_to_pin(state.qpos, state.qvel)
        self.stance_map.update(q, v)
        foot = FEET[foot_index]
        idx = self.robot.n_root_dofs + self.robot.leg_joint_index[foot]
        j_t = self.stance_map.foot_jacobian(foot)[:, idx].T  # (n_leg, 6)
        tau_max = self.robot.torque_limit_nm[self.robot.leg_joint_index[foot]]
        return foot_index, mask, j_t, tau_max

    def _replan(self, state: RobotState) -> None:
        sched = self.schedule
        hz = sched.horizon()
        dts = np.array(hz.dts_s, dtype=float)
        dts[0] = max(hz.first_stage_remaining_s, 0.005)
        stage_times = np.concatenate([[0.0], np.cumsum(dts)])
        x_ref = self._reference(state, stage_times)
        contact = np.asarray(hz.contact, dtype=bool)
        steps = np.asarray(hz.step_index)
        h = len(dts)
        stance_now, swing_now = sched.stance_foot, sched.swing_foot
        t_left = sched.time_left_in_step_s
        next_dt = sched.next_step_dt_s or sched.current_step_dt_s
        future = self._plan_foothold(state, stance_now, t_left + 5 * next_dt)
        # Where each foot stands in each stage (swinging feet carry no wrench, eq. 23):
        # the stance foot stays put in step 0 and lands at `future` in step 2; the swing
        # foot stands on its planned foothold in step 1.
        feet_pos = np.zeros((h, 2, 3))
        i_st, i_sw = FEET.index(stance_now), FEET.index(swing_now)
        feet_pos[:, i_st] = np.where((steps >= 2)[:, None], future, self.foot_pos[stance_now])
        feet_pos[:, i_sw] = self.foothold[swing_now]
        if self.robot.spec.planar:
            feet_pos[:, :, 1] = state.com_world_m[1]
        # Stance feet keep their measured heading; a foot that lands later takes the
        # commanded heading its swing is steered to.
        yaw = np.full((h, 2), self._heading_cmd(state.t_s))
        yaw[steps == 0, i_st] = state.foot_yaw_rad[stance_now]
        t0 = time.perf_counter()
        limits = self._torque_limits(state, i_st, steps == 0)
        try:
            plan = self.mpc.solve(self._x0(state), x_ref, dts, contact, feet_pos, yaw, limits)
        except QPSolveError:
            self._stats.record(time.perf_counter() - t0, 1, False, False)
            return  # keep the last good wrench
        self._stats.record(time.perf_counter() - t0, 1, True, True)
        self.wrench = plan.wrenches[0]

    # --------------------------------------------------------------- control
    def compute(self, state: RobotState) -> np.ndarray:
        sched = self.schedule
        sched.advance_to(state.t_s)
        if sched.at_step_start and (self.swing is None or sched.time_in_step_s < 1e-3):
            if sched.step_index > 0 or self.swing is None:
                self._on_step_start(state)
        if state.t_s >= self.next_replan_s:
            self._update_foothold(state)
            self._replan(state)
            self.next_replan_s = state.t_s + self.config.replan_period_s
        stance, swing = sched.stance_foot, sched.swing_foot
        wrench = {}
        if self.wrench is not None:
            wrench[stance] = self.wrench[FEET.index(stance)]
        t_swing = sched.time_in_step_s
        target = {swing: (self.swing.position(t_swing), self.swing.velocity(t_swing))}
        yaw = None if self.robot.spec.planar else self._heading_cmd(state.t_s)
        return self.low.torques(state, wrench, target, yaw)

    def _heading_cmd(self, t_s: float) -> float:
        """Commanded heading [rad] at time ``t_s``: initial yaw plus integrated yaw rate."""
        return self.yaw0 + self.command.yaw_rate_radps * (t_s - self.t0_s)
