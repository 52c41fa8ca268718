"""How far the swing leg's shank stays above the obstacles along a planned swing.

The swing planner (:mod:`~gaitnet_mpc.gait.swing`) keeps the foot, a segment of the foot's
length, a clearance above every obstacle top it passes over. The shank is a capsule from
just below the knee to just above the ankle (``{foot}_shank`` in the MJCF); it leans with
the leg, so near a box's face it can reach over the box lower than the foot's plan
accounts for. Here the leg is posed along the plan (trunk from the MPC reference, the leg
by the analytic IK of Appendix B to the planned foot position) and the capsule is
checked against each obstacle, taken across the foot's lane as the swing planner takes
it: the clearance over an obstacle is the lowest point of the capsule's surface within
the obstacle's x range minus its top (negative: the shank would cut into it).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import pinocchio as pin

from gaitnet_mpc.kinematics.leg_ik import whole_body_ik
from gaitnet_mpc.robots import FEET, RobotModel


@dataclass(frozen=True)
class ShankCapsule:
    """One leg's shank: a capsule of ``radius_m`` about the segment ``ends_m`` (2, 3),
    given in the frame of Pinocchio joint ``joint_id`` (the knee)."""

    joint_id: int
    ends_m: np.ndarray
    radius_m: float


def shank_capsules(robot: RobotModel) -> dict[str, ShankCapsule]:
    """foot -> its leg's shank capsule, read from the MJCF geom ``{foot}_shank`` on the
    body whose joint is ``{foot}_knee``; empty for a robot without such geoms."""
    m = robot.mj_model
    out = {}
    for foot in FEET:
        gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"{foot}_shank")
        if gid < 0 or m.geom_type[gid] != mujoco.mjtGeom.mjGEOM_CAPSULE:
            continue
        knee = f"{foot}_knee"
        if not robot.pin_model.existJointName(knee):
            continue
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, m.geom_quat[gid])
        half = rot.reshape(3, 3)[:, 2] * m.geom_size[gid, 1]
        centre = m.geom_pos[gid]  # in the shank body's frame, which is the knee joint's
        ends = np.stack([centre + half, centre - half])
        out[foot] = ShankCapsule(robot.pin_model.getJointId(knee), ends, float(m.geom_size[gid, 0]))
    return out


def capsule_clearance_m(
    p0_m: np.ndarray, p1_m: np.ndarray, radius_m: float, obstacles: np.ndarray
) -> np.ndarray:
    """(n,) least height of a capsule (axis ``p0_m``-``p1_m``, world frame) above each
    obstacle ``(x_min, x_max, top_z)`` row of ``obstacles`` (n, 3) it lies over [m];
    ``inf`` where no part of it is within the obstacle's x range.

    The axis is linear in its parameter, so its lowest point over an x interval is at an
    end of the sub-segment inside the (radius-widened) interval.
    """
    out = np.full(len(obstacles), np.inf)
    dx = p1_m[0] - p0_m[0]
    for i, (x_min, x_max, top) in enumerate(obstacles):
        lo, hi = x_min - radius_m, x_max + radius_m
        if abs(dx) < 1e-12:
            if not lo <= p0_m[0] <= hi:
                continue
            s0, s1 = 0.0, 1.0
        else:
            a, b = (lo - p0_m[0]) / dx, (hi - p0_m[0]) / dx
            s0, s1 = max(min(a, b), 0.0), min(max(a, b), 1.0)
            if s0 > s1:
                continue
        z = p0_m[2] + (p1_m[2] - p0_m[2]) * np.array([s0, s1])
        out[i] = float(z.min()) - radius_m - top
    return out


def swing_shank_clearance_m(
    robot: RobotModel,
    data: pin.Data,
    capsule: ShankCapsule,
    foot: str,
    p_base_m: np.ndarray,
    rot_base: np.ndarray,
    p_foot_m: np.ndarray,
    obstacles: np.ndarray,
    foot_yaw_rad: np.ndarray | None = None,
) -> np.ndarray:
    """(n,) least shank clearance over each obstacle (:func:`capsule_clearance_m`) along N
    poses of the leg: trunk positions ``p_base_m`` (N, 3) and rotations ``rot_base`` (N, 3,
    3), foot centre ``p_foot_m`` (N, 3) reached by the leg IK (the other leg stays at the
    nominal pose; it does not move this one), foot headings ``foot_yaw_rad`` (N,) or None
    (the trunk's)."""
    yaw = None if foot_yaw_rad is None else {foot: foot_yaw_rad}
    joints = whole_body_ik(robot, p_base_m, rot_base, {foot: p_foot_m}, yaw).joint_pos_rad
    model = robot.pin_model
    out = np.full(len(obstacles), np.inf)
    for k in range(p_base_m.shape[0]):
        qpos = robot.qpos_of(p_base_m[k], rot_base[k], joints[k])
        pin.forwardKinematics(model, data, robot.mj_to_pin_q(qpos))
        placement = data.oMi[capsule.joint_id]
        ends = capsule.ends_m @ placement.rotation.T + placement.translation
        clear = capsule_clearance_m(ends[0], ends[1], capsule.radius_m, obstacles)
        out = np.minimum(out, clear)
    return out


__all__ = [
    "ShankCapsule",
    "capsule_clearance_m",
    "shank_capsules",
    "swing_shank_clearance_m",
]
