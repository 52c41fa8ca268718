"""Stance-leg torque mapping: contact wrenches -> joint torques through J_c^T.

With the floating-base equation of motion (paper eq. 4) ``M qdd + b = S^T tau + J_c^T lambda``,
the joint torques that realise ground wrenches ``lambda`` (exerted by the ground on the feet,
world-aligned, about each foot centre) at ``qdd = qdd_des`` are

    tau = [M qdd_des + b - J_c^T lambda]_joints .

With ``qdd_des = 0`` this is the paper's ``tau = -J_c^T [f; tau_c]`` plus the bias forces of
the stance chain.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from gaitnet_mpc.robots import RobotModel


class StanceMap:
    """Cached Pinocchio data for contact Jacobians and bias forces of one robot."""

    def __init__(self, robot: RobotModel) -> None:
        self.robot = robot
        self.data = robot.pin_model.createData()

    def update(self, q: np.ndarray, v: np.ndarray) -> None:
        """Compute kinematics, frame placements and joint Jacobians at (q, v)."""
        model = self.robot.pin_model
        pin.computeJointJacobians(model, self.data, q)
        pin.updateFramePlacements(model, self.data)
        self.bias = pin.nonLinearEffects(model, self.data, q, v)  # (nv,)

    def foot_jacobian(self, foot: str) -> np.ndarray:
        """(6, nv) Jacobian of the foot-centre frame, world-aligned, [linear; angular]."""
        return pin.getFrameJacobian(
            self.robot.pin_model,
            self.data,
            self.robot.pin_foot_frame_ids[foot],
            pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
        )

    def joint_torques(self, wrenches_world: dict[str, np.ndarray]) -> np.ndarray:
        """Joint torques (n_joints,) realising ``wrenches_world`` (foot -> (6,) [f; m])."""
        tau_full = self.bias.copy()
        for foot, w in wrenches_world.items():
            tau_full -= self.foot_jacobian(foot).T @ w
        return tau_full[self.robot.n_root_dofs :]
