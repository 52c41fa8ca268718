"""``stand``: joint PD to a standing pose plus floating-base gravity compensation.

Gravity compensation of a floating base on two feet: the ground wrenches that hold the
robot's weight (plus a weak CoM and trunk feedback) are split over the feet by a small QP
that respects friction and the line-foot CoP limits (:mod:`.contact`); they are mapped to
joint torques by ``tau = [b(q, v) - J_c^T F]_joints`` (:mod:`.stance`). A joint PD holds
the pose.

Limits (measured with ``gaitnet-mpc run --controller stand --push t=3,f..=..,dur=0.1``):
the robot reacts to a push at the trunk as a nearly rigid body pivoting on its toes or
heels (ankle strategy only). It survives 5 N s forward and lateral impulses at the trunk
CoM, tips over at 6 N s forward and at 5 N s backward (the CoM rests 0.075 m behind the
toe but only 0.06 m ahead of the heel... measured, not derived).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.control.stance import StanceMap
from gaitnet_mpc.geometry import GRAVITY_MPS2, skew
from gaitnet_mpc.mpc.contact import ContactParams, foot_wrench_constraints
from gaitnet_mpc.mpc.qp import QPProblem, make_workspace
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.state import RobotState


@dataclass(frozen=True)
class StandConfig:
    """Gains of the standing controller (units per field)."""

    com_kp_per_s2: float = 20.0
    com_kd_per_s: float = 5.0
    rot_kp_per_s2: float = 20.0
    rot_kd_per_s: float = 5.0
    joint_kp_nm_per_rad: float = 60.0
    joint_kd_nms_per_rad: float = 2.0
    wrench_weights: tuple[float, ...] = (100.0, 100.0, 100.0, 1.0, 1.0, 1.0)


class StandController(Controller):
    """Joint PD + floating-base gravity compensation with weak CoM feedback."""

    name = "stand"

    def __init__(self, robot: RobotModel, config: StandConfig | None = None) -> None:
        self.robot = robot
        self.config = config or StandConfig()
        self.stance = StanceMap(robot)
        self.q_nominal = robot.nominal_joint_pos()
        self.contact = ContactParams(fz_min_n=1.0)
        self.qp = make_workspace("daqp")
        self._last: np.ndarray | None = None
        self.com_target_m = np.zeros(3)
        self.yaw0_rad = 0.0

    def reset(self, state: RobotState) -> None:
        mid = 0.5 * (state.foot_pos_world_m["left"] + state.foot_pos_world_m["right"])
        y = 0.0 if self.robot.spec.planar else mid[1]
        self.com_target_m = np.array([mid[0], y, state.com_world_m[2]])
        self.yaw0_rad = float(state.base_rpy_rad[2])

    def desired_wrench(self, state: RobotState) -> np.ndarray:
        """Centroidal wrench [force; moment about CoM] (6,): weight plus weak PD."""
        c = self.config
        m = self.robot.total_mass_kg
        acc = c.com_kp_per_s2 * (self.com_target_m - state.com_world_m)
        acc -= c.com_kd_per_s * state.com_vel_world_mps
        force = m * (acc + np.array([0.0, 0.0, GRAVITY_MPS2]))
        cy, sy = np.cos(self.yaw0_rad), np.sin(self.yaw0_rad)
        rot_des = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
        err = pin.log3(rot_des @ state.base_rot_world.T)
        inertia = np.diag([0.3, 0.3, 0.1]) * m / 16.0  # rough centroidal inertia [kg m^2]
        moment = inertia @ (c.rot_kp_per_s2 * err - c.rot_kd_per_s * state.base_ang_vel_world_radps)
        return np.concatenate([force, moment])

    def distribute(self, state: RobotState, wrench: np.ndarray) -> dict[str, np.ndarray]:
        """Split a centroidal wrench into feasible per-foot ground wrenches (small QP).

        minimise ||W (G F - wrench)||^2 + eps ||F||^2 subject to each foot's friction,
        normal-force and line-foot limits.
        """
        blocks, c_rows, lo, hi = [], [], [], []
        yaw = float(state.base_rpy_rad[2])
        spec = self.robot.spec
        for k, foot in enumerate(FEET):
            g = np.eye(6)
            g[3:, :3] = skew(state.foot_pos_world_m[foot] - state.com_world_m)
            blocks.append(g)
            cm, l_, u_ = foot_wrench_constraints(
                yaw, self.contact, spec.foot_toe_m, spec.foot_heel_m
            )
            row = np.zeros((cm.shape[0], 12))
            row[:, 6 * k : 6 * k + 6] = cm
            c_rows.append(row)
            lo.append(l_)
            hi.append(u_)
        g_all = np.hstack(blocks)
        weights = np.diag(self.config.wrench_weights)
        hess = g_all.T @ weights @ g_all + 1e-4 * np.eye(12)
        grad = -g_all.T @ weights @ wrench
        problem = QPProblem(
            hess, grad, A=np.vstack(c_rows), l=np.concatenate(lo), u=np.concatenate(hi)
        )
        sol = self.qp.solve(problem, warm_start=self._last)
        if sol.found and sol.x is not None:
            self._last = sol.x
        x = self._last if self._last is not None else np.zeros(12)
        return {foot: x[6 * k : 6 * k + 6] for k, foot in enumerate(FEET)}

    def compute(self, state: RobotState) -> np.ndarray:
        q, v = self.robot.mj_to_pin(state.qpos, state.qvel)
        self.stance.update(q, v)
        tau = self.stance.joint_torques(self.distribute(state, self.desired_wrench(state)))
        c = self.config
        tau += c.joint_kp_nm_per_rad * (self.q_nominal - state.joint_pos_rad)
        tau -= c.joint_kd_nms_per_rad * state.joint_vel_radps
        return tau
