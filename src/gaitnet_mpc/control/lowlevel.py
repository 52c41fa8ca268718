"""Low-level control: MPC wrenches and swing targets -> saturated joint torques.

* Stance legs: ``tau = -J_c^T [f; m]`` restricted to the leg joints (the ground wrench
  ``[f; m]`` acts on the foot, world-aligned, about the foot centre), plus light damping.
* Swing legs: joint PD to the analytic IK of the swing-foot trajectory, with the joint-rate
  target from the IK of the trajectory a moment later, plus gravity compensation and,
  optionally, the inertial feedforward ``a M_ll qdd_des`` (``M_ll`` the leg's block of the
  joint-space mass matrix, ``qdd_des`` the second difference of the IK at three lookahead
  times along the trajectory's position, velocity and acceleration, ``a`` =
  ``swing_accel_ff``). Without it the PD lags the fast swings of short steps: at 0.75 m/s
  with 0.225 s steps the foot accelerates at ~40 m/s^2, the hip needs ~7 N m and the
  PD (60 N m/rad) lags by ~0.1 rad, and ``kd``'s feet landed 3.7-5.2 cm beyond their aim;
  with ``a = 0.75`` the error was within +-0.4 cm (1.0 landed 1-1.7 cm short, 0.5 up to
  1.7 cm long; flat, dt 0.045, ``docs/design/walking_low_level.md``).
* Optional trunk-yaw feedback on the stance hip-yaw joint (off by default): the stance foot
  is fixed to the ground, so a hip-yaw torque ``tau`` turns the pelvis by ``-tau``;
  ``tau += kp (psi - psi_cmd) + kd psi_dot`` holds the commanded heading. Measured with
  ``kd`` and its LIP lateral reference (feet 0.07 m beside the CoM, flat, 0.75 m/s, dt
  0.065, 4 s): trunk yaw rms 0.35 -> 0.10 rad with kp 10 N m/rad, kd 1 N m s/rad.
* Optional trunk roll / pitch feedback on the stance hip roll / pitch (off by default), by
  the same reasoning, split evenly over the stance legs. On seeded stones (gaitnet, tuning
  seeds 100-139) kp 20 N m/rad, kd 2 N m s/rad gave 31/40 clean against 28/40 without.
* Arms: PD to the nominal pose with a counter-swing opposite to the hips, or, with
  ``arm_push``, to a still pushing pose (arms forward at shoulder height, for the cart of
  Fig. 10). The controller knows the pose, not what the hands push against.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.kinematics.leg_ik import foot_ik, leg_geometries
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.state import RobotState

_KP, _KP_REASON = "[0, 1000] N m/rad", "1000 saturates a 33.5 N m hip at 0.03 rad"
_KD, _KD_REASON = "[0, 100] N m s/rad", "100 saturates a 33.5 N m hip at 0.3 rad/s"


@dataclass(frozen=True)
class LowLevelConfig:
    """Gains of the low-level controller."""

    swing_kp_nm_per_rad: float = bounded(60.0, _KP, "a stiffness", _KP_REASON)
    swing_kd_nms_per_rad: float = bounded(2.0, _KD, "a damping", _KD_REASON)
    stance_kd_nms_per_rad: float = bounded(0.3, _KD, "a damping", _KD_REASON)
    # trunk-yaw feedback on the stance hip yaw
    stance_yaw_kp_nm_per_rad: float = bounded(0.0, _KP, "a stiffness", _KP_REASON)
    stance_yaw_kd_nms_per_rad: float = bounded(0.0, _KD, "a damping", _KD_REASON)
    # trunk roll / pitch feedback on the stance hip roll / pitch, shared by the stance legs
    stance_tilt_kp_nm_per_rad: float = bounded(0.0, _KP, "a stiffness", _KP_REASON)
    stance_tilt_kd_nms_per_rad: float = bounded(0.0, _KD, "a damping", _KD_REASON)
    arm_kp_nm_per_rad: float = bounded(20.0, _KP, "a stiffness", _KP_REASON)
    arm_kd_nms_per_rad: float = bounded(0.5, _KD, "a damping", _KD_REASON)
    # the arm's shoulder pitch swings by this fraction of the other leg's hip pitch [-]
    arm_counter_swing: float = bounded(0.6, "[0, 2]", "a ratio", "0: arms still; 2: twice the hip")
    # hold the arms still in the pushing pose below instead of swinging them
    arm_push: bool = False
    arm_push_shoulder_pitch_rad: float = bounded(
        -1.35, "[-2.6, 2.6] rad", "a shoulder pitch", "the joint's range; -pi/2: arm forward"
    )
    arm_push_elbow_rad: float = bounded(-0.3, "[-2.2, 0] rad", "an elbow angle", "its range")
    # the pose's stiffness: 30 N at the hands (0.3 m from the shoulder) within 0.05 rad
    arm_push_kp_nm_per_rad: float = bounded(180.0, _KP, "a stiffness", _KP_REASON)
    arm_push_kd_nms_per_rad: float = bounded(3.0, _KD, "a damping", _KD_REASON)
    # time step of the swing IK's lookahead (the feedforward divides by its square) [s]
    ik_lookahead_s: float = bounded(0.005, "(0, 0.1] s", "a lookahead", "0.1 s: half a step")
    # fraction of the swing legs' inertial feedforward [-]
    swing_accel_ff: float = bounded(0.0, "[0, 2]", "a fraction", "1: the model's full term")

    def __post_init__(self) -> None:
        check_ranges(self)


class LowLevelController:
    """Maps stance wrenches and swing-foot targets to joint torques for one robot."""

    def __init__(self, robot: RobotModel, config: LowLevelConfig | None = None) -> None:
        self.robot = robot
        self.config = config or LowLevelConfig()
        self.data = robot.pin_model.createData()
        self.geometries = leg_geometries(robot)
        self.q_nominal = robot.nominal_joint_pos()
        names = robot.joint_names
        self.arm_index = np.array(
            [i for i, n in enumerate(names) if any(n in robot.spec.arm_joints[f] for f in FEET)]
            if robot.spec.arm_joints
            else [],
            dtype=int,
        )
        self.shoulder_pitch = {
            f: names.index(f"{f}_shoulder_pitch") for f in FEET if robot.spec.arm_joints
        }
        self.elbow = {f: names.index(f"{f}_elbow") for f in FEET if robot.spec.arm_joints}
        self.hip_pitch = {f: names.index(f"{f}_hip_pitch") for f in FEET}
        # per foot, the flat indices of the leg's block of the (nv, nv) mass matrix, and
        # which entries of the block lie in its upper triangle (crba fills only that one)
        nv = robot.pin_model.nv
        self._mass_block = {
            f: (v[:, None] * nv + v).ravel()
            for f, v in ((f, robot.leg_joint_index[f] + robot.n_root_dofs) for f in FEET)
        }
        n_leg = len(robot.leg_joint_index[FEET[0]])
        self._upper = np.triu(np.ones((n_leg, n_leg), dtype=bool))
        # per foot, the joints the trunk-tilt feedback drives: (hip roll, hip pitch) or
        # (hip pitch,) on the planar biped, and which of [roll, pitch] each takes
        self.tilt_joints = {
            f: [
                (a, names.index(f"{f}_hip_{n}"))
                for a, n in enumerate(("roll", "pitch"))
                if f"{f}_hip_{n}" in names
            ]
            for f in FEET
        }

    def torques(
        self,
        state: RobotState,
        stance_wrench: dict[str, np.ndarray],
        swing_target: Mapping[str, tuple[np.ndarray, ...]],
        swing_yaw_rad: float | None = None,
    ) -> np.ndarray:
        """Joint torques (n_joints,).

        Args:
            state: measured state.
            stance_wrench: stance foot -> ground wrench (6,) [N; N m].
            swing_target: swing foot -> (position (3,), velocity (3,)[, acceleration (3,)])
                of the foot centre [m, m/s, m/s^2]; the acceleration is used only by the
                inertial feedforward (``swing_accel_ff``, zero acceleration if absent).
            swing_yaw_rad: heading of the swing feet in the world [rad] (default: the
                trunk's heading, i.e. hip yaw 0 as in Appendix B eq. 31).
        """
        r, c = self.robot, self.config
        model, data = r.pin_model, self.data
        q = r.mj_to_pin_q(state.qpos)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        gravity = pin.computeGeneralizedGravity(model, data, q)[r.n_root_dofs :]
        tau = np.zeros(r.n_joints)
        qj, qdj = state.joint_pos_rad, state.joint_vel_radps
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        tilt = None  # the trunk-tilt feedback's torques per stance leg, made once per tick
        if stance_wrench and (
            c.stance_tilt_kp_nm_per_rad > 0.0 or c.stance_tilt_kd_nms_per_rad > 0.0
        ):
            tilt = self._tilt_torque(state) / len(stance_wrench)
        for foot, wrench in stance_wrench.items():
            idx = r.leg_joint_index[foot]
            jac = pin.getFrameJacobian(model, data, r.pin_foot_frame_ids[foot], lwa)
            tau[idx] = -(jac.T @ wrench)[r.n_root_dofs :][idx] - c.stance_kd_nms_per_rad * qdj[idx]
            if swing_yaw_rad is not None and c.stance_yaw_kp_nm_per_rad > 0.0:
                # (a + pi) mod 2 pi - pi, not geometry.wrap_angle (atan2): that differs in the
                # last bit and would change the closed-loop logs
                rot = state.base_rot_world
                psi = math.atan2(rot[1, 0], rot[0, 0])  # trunk yaw (base_rpy_rad[2])
                err = (psi - swing_yaw_rad + np.pi) % (2 * np.pi) - np.pi
                tau[idx[0]] += (  # idx[0]: hip yaw, the first leg joint
                    c.stance_yaw_kp_nm_per_rad * err
                    + c.stance_yaw_kd_nms_per_rad * state.base_ang_vel_world_radps[2]
                )
            if tilt is not None:
                for axis, j in self.tilt_joints[foot]:
                    tau[j] += tilt[axis]
        if swing_target:
            p_base, rot = state.base_pos_world_m, state.base_rot_world
            v_base = state.base_lin_vel_world_mps
            dt = c.ik_lookahead_s
            feet = list(swing_target)
            ff = c.swing_accel_ff
            k = np.arange(3.0 if ff > 0.0 else 2.0)[:, None] * dt  # lookahead times (n, 1)
            targets = {}
            for f in feet:
                p, v, *rest = swing_target[f]
                a = rest[0] if rest and ff > 0.0 else np.zeros(3)
                targets[f] = p + k * v + 0.5 * k**2 * a  # (n, 3)
            base_next = p_base + k * v_base
            yaw = None if swing_yaw_rad is None else np.full(len(k), swing_yaw_rad)
            upper = pin.crba(model, data, q) if ff > 0.0 else None  # upper triangle filled
            for foot in feet:
                idx = r.leg_joint_index[foot]
                q_ik = foot_ik(self.geometries[foot], targets[foot], base_next, rot, yaw).q_rad
                q_des = q_ik[0]
                qd_des = (q_ik[1] - q_des) / dt
                tau[idx] = (
                    c.swing_kp_nm_per_rad * (q_des - qj[idx])
                    + c.swing_kd_nms_per_rad * (qd_des - qdj[idx])
                    + gravity[idx]
                )
                if upper is not None:
                    qdd_des = (q_ik[2] - 2.0 * q_ik[1] + q_ik[0]) / dt**2
                    n_leg = len(idx)  # joints ascending: the block's upper triangle is M's
                    block = upper.ravel()[self._mass_block[foot]].reshape(n_leg, n_leg)
                    tau[idx] += ff * np.where(self._upper, block, block.T) @ qdd_des
        if self.arm_index.size:
            q_arm = self.q_nominal.copy()
            for side, other in (("left", "right"), ("right", "left")):
                if c.arm_push:
                    q_arm[self.shoulder_pitch[side]] = c.arm_push_shoulder_pitch_rad
                    q_arm[self.elbow[side]] = c.arm_push_elbow_rad
                    continue
                swing = qj[self.hip_pitch[other]] - self.q_nominal[self.hip_pitch[other]]
                q_arm[self.shoulder_pitch[side]] += c.arm_counter_swing * swing
            idx = self.arm_index
            kp, kd = (
                (c.arm_push_kp_nm_per_rad, c.arm_push_kd_nms_per_rad)
                if c.arm_push
                else (c.arm_kp_nm_per_rad, c.arm_kd_nms_per_rad)
            )
            tau[idx] = kp * (q_arm[idx] - qj[idx]) - kd * qdj[idx] + gravity[idx]
        return np.minimum(np.maximum(tau, -r.torque_limit_nm), r.torque_limit_nm)  # np.clip

    def _tilt_torque(self, state: RobotState) -> np.ndarray:
        """Hip roll and pitch torques (2,) [N m] that level the trunk, about the heading frame.

        The stance foot holds the thigh, so a hip torque ``tau`` turns the pelvis by ``-tau``:
        ``tau = kp [roll, pitch] + kd [roll rate, pitch rate]`` pushes the trunk upright.
        """
        c = self.config
        r = state.base_rot_world  # roll, pitch, yaw as RobotState.base_rpy_rad, in scalars
        pitch = -math.asin(min(max(r[2, 0], -1.0), 1.0))
        roll = math.atan2(r[2, 1], r[2, 2])
        yaw = math.atan2(r[1, 0], r[0, 0])
        cy, sy = math.cos(yaw), math.sin(yaw)
        w = state.base_ang_vel_world_radps
        rate = np.array([cy * w[0] + sy * w[1], -sy * w[0] + cy * w[1]])  # heading frame
        return c.stance_tilt_kp_nm_per_rad * np.array([roll, pitch]) + (
            c.stance_tilt_kd_nms_per_rad * rate
        )
