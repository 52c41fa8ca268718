"""Low-level control: stance wrench mapping and the optional trunk yaw / tilt feedback."""

from __future__ import annotations

import numpy as np

from gaitnet_mpc.control.lowlevel import LowLevelConfig, LowLevelController
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course


def test_trunk_yaw_feedback_acts_on_the_stance_hip_yaw_only() -> None:
    robot = load_robot("humanoid3d")
    qpos = robot.standing_qpos()
    qpos[3:7] = [np.cos(0.05), 0.0, 0.0, np.sin(0.05)]  # trunk yawed 0.1 rad to the left
    state = Simulator(robot, load_course("flat")).reset(qpos)
    assert abs(state.base_rpy_rad[2] - 0.1) < 1e-9
    wrench = {"left": np.array([0.0, 0.0, 80.0, 0.0, 0.0, 0.0])}
    off = LowLevelController(robot).torques(state, wrench, {}, swing_yaw_rad=0.0)
    on = LowLevelController(robot, LowLevelConfig(stance_yaw_kp_nm_per_rad=10.0)).torques(
        state, wrench, {}, swing_yaw_rad=0.0
    )
    hip_yaw = robot.joint_names.index("left_hip_yaw")
    diff = on - off
    np.testing.assert_allclose(diff[hip_yaw], 1.0, atol=1e-9)  # kp * error
    assert np.count_nonzero(np.abs(diff) > 1e-12) == 1


def test_trunk_tilt_feedback_is_shared_by_the_stance_hip_roll_and_pitch() -> None:
    robot = load_robot("humanoid3d")
    qpos = robot.standing_qpos()
    qpos[3:7] = [np.cos(0.05), np.sin(0.05), 0.0, 0.0]  # trunk rolled 0.1 rad
    state = Simulator(robot, load_course("flat")).reset(qpos)
    assert abs(state.base_rpy_rad[0] - 0.1) < 1e-9
    stance = np.array([0.0, 0.0, 80.0, 0.0, 0.0, 0.0])
    wrench = {"left": stance, "right": stance}
    off = LowLevelController(robot).torques(state, wrench, {}, swing_yaw_rad=0.0)
    on = LowLevelController(robot, LowLevelConfig(stance_tilt_kp_nm_per_rad=10.0)).torques(
        state, wrench, {}, swing_yaw_rad=0.0
    )
    diff = on - off
    for foot in ("left", "right"):  # kp * roll, half on each stance leg
        np.testing.assert_allclose(diff[robot.joint_names.index(f"{foot}_hip_roll")], 0.5)
    assert np.count_nonzero(np.abs(diff) > 1e-12) == 2  # pitch is level: no pitch torque


def _swing_torques(robot, state, accel, ff: float) -> np.ndarray:
    foot = state.foot_pos_world_m["right"]
    target = {"right": (foot, np.zeros(3), np.asarray(accel, dtype=float))}
    wrench = {"left": np.array([0.0, 0.0, 150.0, 0.0, 0.0, 0.0])}
    low = LowLevelController(robot, LowLevelConfig(swing_accel_ff=ff))
    return low.torques(state, wrench, target, swing_yaw_rad=0.0)


def test_swing_inertial_feedforward_scales_with_the_target_acceleration() -> None:
    robot = load_robot("humanoid3d")
    state = Simulator(robot, load_course("flat")).reset(robot.standing_qpos())
    legs = robot.leg_joint_index["right"]
    off = _swing_torques(robot, state, [20.0, 0.0, 0.0], 0.0)
    # no feedforward: the acceleration is ignored
    np.testing.assert_allclose(off, _swing_torques(robot, state, [0.0, 0.0, 0.0], 0.0))
    # a target at rest needs no feedforward
    np.testing.assert_allclose(off, _swing_torques(robot, state, [0.0, 0.0, 0.0], 1.0), atol=1e-9)
    # with swing_accel_ff > 0 the acceleration also enters the joint-rate target
    # (lookahead point p + dt v + dt^2 a / 2), so compare differences of the gain
    ahead = [20.0, 0.0, 0.0]
    quarter, half, full = (_swing_torques(robot, state, ahead, a) for a in (0.25, 0.5, 1.0))
    inertial = full - half  # 0.5 M_ll qdd_des
    np.testing.assert_allclose(inertial, 2.0 * (half - quarter), atol=1e-9)  # linear in the gain
    others = np.setdiff1d(np.arange(robot.n_joints), legs)
    assert np.abs((full - off)[others]).max() < 1e-9  # only the swing leg gets it
    back = _swing_torques(robot, state, [-20.0, 0.0, 0.0], 1.0) - _swing_torques(
        robot, state, [-20.0, 0.0, 0.0], 0.5
    )
    np.testing.assert_allclose(back, -inertial, atol=0.02 * np.abs(inertial).max())  # odd in a
    # 20 m/s^2 of foot acceleration needs a few N m at the hip pitch (leg ~0.07 kg m^2)
    hip_pitch = robot.joint_names.index("right_hip_pitch")
    assert 0.5 < abs(2.0 * inertial[hip_pitch]) < 10.0
