"""The shank capsule posed by Pinocchio is MuJoCo's, and its clearance over a box is the
lowest point of its surface within the box's x range minus the top."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from gaitnet_mpc.kinematics.shank_clearance import (
    capsule_clearance_m,
    shank_capsules,
    swing_shank_clearance_m,
)
from gaitnet_mpc.robots import FEET, load_robot


def test_capsule_clearance_is_the_lowest_surface_point_over_the_box() -> None:
    box = np.array([[1.0, 1.2, 0.05]])
    # axis from (0.9, 0.2) to (1.3, 0.4): inside x in [0.98, 1.22] it is lowest at x 0.98
    p0, p1 = np.array([0.9, 0.0, 0.2]), np.array([1.3, 0.0, 0.4])
    z_low = 0.2 + 0.2 * (0.98 - 0.9) / 0.4
    assert capsule_clearance_m(p0, p1, 0.02, box)[0] == pytest.approx(z_low - 0.02 - 0.05)
    # a vertical shank beside the box, beyond its radius: over nothing
    far = capsule_clearance_m(np.array([0.97, 0, 0.1]), np.array([0.97, 0, 0.3]), 0.02, box)
    assert far[0] == np.inf
    # cutting into the box: negative
    low = capsule_clearance_m(np.array([1.1, 0, 0.03]), np.array([1.1, 0, 0.2]), 0.02, box)
    assert low[0] == pytest.approx(0.03 - 0.02 - 0.05)


def test_the_posed_capsule_is_mujocos_shank() -> None:
    robot = load_robot("humanoid3d")
    capsules = shank_capsules(robot)
    assert set(capsules) == set(FEET)
    m = robot.mj_model
    d = mujoco.MjData(m)
    rng = np.random.default_rng(0)
    d.qpos[:3] = [0.3, -0.1, 0.6]
    d.qpos[3:7] = [np.cos(0.2), 0.0, 0.0, np.sin(0.2)]  # yawed 0.4 rad
    d.qpos[robot.joint_qpos_adr] = rng.uniform(-0.3, 0.3, robot.n_joints)
    d.qpos[robot.joint_qpos_adr[robot.leg_joint_index["left"][3]]] = 0.8  # knee flexed
    mujoco.mj_forward(m, d)
    import pinocchio as pin

    data = robot.pin_model.createData()
    pin.forwardKinematics(robot.pin_model, data, robot.mj_to_pin_q(d.qpos[: m.nq]))
    for foot, cap in capsules.items():
        gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"{foot}_shank")
        axis = d.geom_xmat[gid].reshape(3, 3)[:, 2] * m.geom_size[gid, 1]
        want = np.stack([d.geom_xpos[gid] + axis, d.geom_xpos[gid] - axis])
        placement = data.oMi[cap.joint_id]
        got = cap.ends_m @ placement.rotation.T + placement.translation
        np.testing.assert_allclose(got, want, atol=1e-9)
        assert cap.radius_m == pytest.approx(m.geom_size[gid, 0])


def test_a_foot_lifted_over_a_box_keeps_its_shank_above_it() -> None:
    """The leg posed by the IK to a foot 3 cm above a 5 cm box keeps the shank above it;
    the same foot pushed into the box's x range at its height cuts into it."""
    robot = load_robot("humanoid3d")
    cap = shank_capsules(robot)["left"]
    data = robot.pin_model.createData()
    box = np.array([[0.15, 0.25, 0.05]])
    p_base = np.array([[0.0, 0.0, 0.62], [0.05, 0.0, 0.62]])
    rot = np.stack([np.eye(3)] * 2)
    high = np.array([[0.2, 0.09, 0.05 + 0.03 + 0.01], [0.2, 0.09, 0.05 + 0.03 + 0.01]])
    clear = swing_shank_clearance_m(robot, data, cap, "left", p_base, rot, high, box)
    assert clear[0] > 0.03
    low = high.copy()
    low[:, 2] = 0.0
    assert swing_shank_clearance_m(robot, data, cap, "left", p_base, rot, low, box)[0] < 0.0
