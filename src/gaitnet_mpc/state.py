"""What the simulator tells a controller at one control tick."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RobotState:
    """Measured state at time ``t_s``; all vectors in the world frame unless named ``_body``.

    Attributes:
        t_s: simulation time [s].
        qpos, qvel: MuJoCo generalized coordinates and velocities (see ``robots.model``).
        base_pos_world_m: trunk origin (3,) [m].
        base_rot_world: trunk orientation, rotation matrix body -> world (3, 3).
        base_lin_vel_world_mps: trunk origin velocity (3,) [m/s].
        base_ang_vel_world_radps: trunk angular velocity (3,) [rad/s].
        joint_pos_rad, joint_vel_radps: actuated joints in actuator order.
        com_world_m, com_vel_world_mps: whole-body centre of mass and its velocity.
        h_measured: centroidal momentum [l_G (kg m/s); k_G (kg m^2/s)] about the CoM (6,).
        foot_pos_world_m: per foot, the foot-centre site position (3,).
        foot_yaw_rad: per foot, heading of the foot's long (x) axis in the world [rad].
        foot_contact: per foot, True if any of its geoms touches terrain.
        foot_wrench_world: per foot, [force (N); moment about the foot centre (N m)] (6,)
            that the ground exerts on the foot, summed over contact points.
    """

    t_s: float
    qpos: np.ndarray
    qvel: np.ndarray
    base_pos_world_m: np.ndarray
    base_rot_world: np.ndarray
    base_lin_vel_world_mps: np.ndarray
    base_ang_vel_world_radps: np.ndarray
    joint_pos_rad: np.ndarray
    joint_vel_radps: np.ndarray
    com_world_m: np.ndarray
    com_vel_world_mps: np.ndarray
    h_measured: np.ndarray
    foot_pos_world_m: dict[str, np.ndarray]
    foot_yaw_rad: dict[str, float]
    foot_contact: dict[str, bool]
    foot_wrench_world: dict[str, np.ndarray]

    @property
    def base_rpy_rad(self) -> np.ndarray:
        """Roll, pitch, yaw (ZYX convention) of the trunk [rad]."""
        r = self.base_rot_world
        pitch = -np.arcsin(np.clip(r[2, 0], -1.0, 1.0))
        roll = np.arctan2(r[2, 1], r[2, 2])
        yaw = np.arctan2(r[1, 0], r[0, 0])
        return np.array([roll, pitch, yaw])
