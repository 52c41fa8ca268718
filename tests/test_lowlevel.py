"""Low-level control: stance wrench mapping and the optional trunk-yaw feedback."""

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
