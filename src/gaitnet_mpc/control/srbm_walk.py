"""``srbm``: walking with the SRBM convex MPC, fixed gait frequency and heuristic footholds.

The gait, the LIP/Raibert footholds, touchdown handling and the low level are those of
:class:`gaitnet_mpc.control.walking.WalkingController` (its module docstring explains the
design); this module adds the SRBM MPC (:mod:`gaitnet_mpc.mpc.srbm`): every
``replan_period_s`` it plans stance wrenches over the next two steps for the footholds
the heuristic chose, and the first stage's wrenches go to the low level.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.stance import StanceMap
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.control.walking import WalkingConfig, WalkingController
from gaitnet_mpc.errors import QPSolveError
from gaitnet_mpc.gait.lip import lip_propagate
from gaitnet_mpc.mpc.srbm import NX, SRBMMPC, SRBMConfig
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.state import RobotState


@dataclass(frozen=True)
class SRBMWalkConfig(WalkingConfig):
    """Settings of the SRBM walking controller."""

    mpc: SRBMConfig = field(default_factory=SRBMConfig)


def centroidal_inertia_body(robot: RobotModel) -> np.ndarray:
    """Composite rotational inertia about the CoM at the nominal pose (3, 3) [kg m^2]."""
    q, v = robot.mj_to_pin(robot.standing_qpos(), np.zeros(robot.nv))
    data = robot.pin_model.createData()
    pin.ccrba(robot.pin_model, data, q, v)
    return np.array(data.Ig.inertia)


class SRBMWalkController(WalkingController):
    """SRBM MPC + gait schedule + LIP/Raibert footholds + low-level control."""

    name = "srbm"

    def __init__(
        self,
        robot: RobotModel,
        terrain: TerrainView,
        command: Command,
        config: SRBMWalkConfig | None = None,
    ) -> None:
        c = config or SRBMWalkConfig()
        super().__init__(robot, terrain, command, c)
        self.mpc = SRBMMPC(
            robot.total_mass_kg,
            centroidal_inertia_body(robot),
            robot.spec.foot_toe_m,
            robot.spec.foot_heel_m,
            c.mpc,
        )
        self.stance_map = StanceMap(robot)

    def reset(self, state: RobotState) -> None:
        super().reset(state)
        self.mpc.reset()
        self.wrench: np.ndarray | None = None

    def _wrenches_now(self, state: RobotState) -> np.ndarray | None:
        return self.wrench

    def _x0(self, state: RobotState) -> np.ndarray:
        rpy = state.base_rpy_rad.copy()
        # The measured yaw lives in (-pi, pi]; the reference heading is integrated without
        # wrapping, so express the measurement within pi of it (a turn past pi would
        # otherwise show the MPC a 2 pi heading error).
        ref = self.profile.heading_rad(state.t_s)
        rpy[2] = ref + (rpy[2] - ref + np.pi) % (2.0 * np.pi) - np.pi
        return np.concatenate(
            [rpy, state.com_world_m, state.base_ang_vel_world_radps, state.com_vel_world_mps, [1]]
        )

    def _reference(self, state: RobotState, stage_times: np.ndarray) -> np.ndarray:
        """(h + 1, 13) references at the stage boundaries ``stage_times`` (from now)."""
        t_now = state.t_s - self.t0_s
        yaw_rate = self.command.yaw_rate_radps
        yaw_now = self.profile.heading_rad(state.t_s)
        x_ref = np.zeros((len(stage_times), NX))
        # Start from the commanded path, its error to the CoM clamped to avoid wind-up,
        # then integrate the commanded velocity stage by stage (exact heading per stage).
        err = self.path_xy - state.com_world_m[:2]
        norm = float(np.linalg.norm(err))
        lim = self.config.max_pos_error_m
        if norm > lim:
            err *= lim / norm
        p_xy = state.com_world_m[:2] + err
        for k, tk in enumerate(stage_times):
            yaw_k = yaw_now + yaw_rate * tk
            v_cmd = self._cmd_world(yaw_k, t_now + tk)
            if k > 0:
                p_xy = p_xy + v_cmd[:2] * (tk - stage_times[k - 1])
            x_ref[k, 2] = yaw_k
            x_ref[k, 3:5] = p_xy
            x_ref[k, 5] = self._z_ref(state.t_s + tk)
            x_ref[k, 8] = yaw_rate
            x_ref[k, 9:12] = v_cmd
            x_ref[k, 12] = 1.0
        if self.robot.spec.planar:
            x_ref[:, [0, 2, 4, 6, 8, 10]] = 0.0
        return x_ref

    def _torque_limits(
        self, state: RobotState, feet: list[tuple[int, np.ndarray]]
    ) -> list[tuple[int, np.ndarray, np.ndarray, np.ndarray]]:
        """Stance-leg torque limits for the MPC: ``|J_leg^T [f; m]| <= tau_max`` with the
        current leg Jacobian, for each ``(foot_index, stage_mask)``."""
        q, v = self.robot.mj_to_pin(state.qpos, state.qvel)
        self.stance_map.update(q, v)
        out = []
        for foot_index, mask in feet:
            foot = FEET[foot_index]
            idx = self.robot.n_root_dofs + self.robot.leg_joint_index[foot]
            j_t = self.stance_map.foot_jacobian(foot)[:, idx].T  # (n_leg, 6)
            tau_max = self.robot.torque_limit_nm[self.robot.leg_joint_index[foot]]
            out.append((foot_index, mask, j_t, tau_max))
        return out

    def _replan(self, state: RobotState) -> None:
        sched = self.schedule
        hz = sched.horizon()
        dts = np.array(hz.dts_s, dtype=float)
        dts[0] = max(hz.first_stage_remaining_s, 0.005)
        stage_times = np.concatenate([[0.0], np.cumsum(dts)])
        x_ref = self._reference(state, stage_times)
        contact = np.array(hz.contact, dtype=bool)
        steps = np.asarray(hz.step_index)
        h = len(dts)
        stance_now, swing_now = sched.stance_foot, sched.swing_foot
        i_st, i_sw = FEET.index(stance_now), FEET.index(swing_now)
        t_left = sched.time_left_in_step_s
        next_dt = sched.next_step_dt_s or sched.current_step_dt_s
        t_next = sched.config.stages_per_step * next_dt
        p_st = self._stance_pos(state, stance_now)
        if self.landed:  # the swing foot stands where it touched down
            p_sw = self._stance_pos(state, swing_now)
            contact[steps == 0, i_sw] = True
        else:
            p_sw = self.foothold[swing_now]
        # The stance foot lands again (step 2) where the heuristic puts it for the CoM
        # state predicted by the LIP over the rest of this step and the next one.
        p_td, v_td = lip_propagate(
            state.com_world_m[:2], state.com_vel_world_mps[:2], p_st[:2], self.omega, t_left
        )
        p_td2, v_td2 = lip_propagate(p_td, v_td, p_sw[:2], self.omega, t_next)
        future = self._foothold(
            state, stance_now, p_td2, v_td2, p_sw, state.t_s + t_left + t_next, t_next
        )
        # Where each foot stands in each stage (swinging feet carry no wrench, eq. 23).
        feet_pos = np.zeros((h, 2, 3))
        feet_pos[:, i_st] = np.where((steps >= 2)[:, None], future, p_st)
        feet_pos[:, i_sw] = p_sw
        if self.robot.spec.planar:
            feet_pos[:, :, 1] = state.com_world_m[1]
        # Standing feet keep their measured heading; a foot that lands later takes the
        # commanded heading its swing is steered to.
        yaw = np.full((h, 2), self.profile.heading_rad(state.t_s))
        yaw[steps == 0, i_st] = state.foot_yaw_rad[stance_now]
        if self.landed:
            yaw[steps <= 1, i_sw] = state.foot_yaw_rad[swing_now]
        t0 = time.perf_counter()
        feet = [(i_st, steps == 0)] + ([(i_sw, steps == 0)] if self.landed else [])
        limits = self._torque_limits(state, feet)
        try:
            plan = self.mpc.solve(self._x0(state), x_ref, dts, contact, feet_pos, yaw, limits)
        except QPSolveError:
            self._stats.record(time.perf_counter() - t0, 1, False, True, failed=True)
            return  # keep the last good wrench
        self._stats.record(time.perf_counter() - t0, 1, True, True)
        self.wrench = plan.wrenches[0]
