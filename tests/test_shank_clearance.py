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


@pytest.mark.parametrize("name", ["humanoid3d", "biped2d"])
def test_qpos_of_inverts_base_pose(name: str) -> None:
    """``RobotModel.qpos_of`` gives the qpos whose trunk pose and joints are the ones asked
    (the planar biped: x, z and pitch)."""
    robot = load_robot(name)
    rng = np.random.default_rng(1)
    joints = rng.uniform(-0.3, 0.3, robot.n_joints)
    c, s = np.cos(0.2), np.sin(0.2)
    if robot.spec.planar:
        p, rot = np.array([0.3, 0.0, 0.55]), np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    else:  # yawed 0.2 rad, then pitched 0.2 rad
        yaw = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        p, rot = np.array([0.3, -0.1, 0.6]), yaw @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    qpos = robot.qpos_of(p, rot, joints)
    assert qpos.shape == (robot.mj_model.nq,)
    p_got, rot_got = robot.base_pose(qpos)
    np.testing.assert_allclose(p_got, p, atol=1e-12)
    np.testing.assert_allclose(rot_got, rot, atol=1e-12)
    np.testing.assert_allclose(qpos[robot.joint_qpos_adr], joints)


@pytest.mark.parametrize("name", ["humanoid3d", "biped2d"])
def test_each_robots_shank_clears_a_box_under_a_lifted_foot(name: str) -> None:
    """From the standing trunk, the left foot 4 cm above a 5 cm box keeps its shank above
    the box, and the same foot on the ground in the box's x range cuts into it, for the 3-D
    humanoid and the planar biped alike (the biped's qpos has x, z and pitch)."""
    robot = load_robot(name)
    qpos = robot.standing_qpos()
    p, rot = robot.base_pose(qpos)
    d = mujoco.MjData(robot.mj_model)
    d.qpos[:] = qpos
    mujoco.mj_kinematics(robot.mj_model, d)
    foot = d.site_xpos[robot.foot_site_ids["left"]].copy()
    box = np.array([[foot[0] + 0.05, foot[0] + 0.15, 0.05]])
    p_base, rots = np.stack([p, p]), np.stack([rot, rot])
    high = np.array([[foot[0] + 0.1, foot[1], 0.09]] * 2)
    cap, data = shank_capsules(robot)["left"], robot.pin_model.createData()
    assert swing_shank_clearance_m(robot, data, cap, "left", p_base, rots, high, box)[0] > 0.03
    low = high.copy()
    low[:, 2] = 0.0
    assert swing_shank_clearance_m(robot, data, cap, "left", p_base, rots, low, box)[0] < 0.0


def test_the_planar_biped_walks_onto_the_built_in_stones() -> None:
    """Closed loop through the shank check of each swing over the stones (it crashed on the
    biped's x-z-pitch qpos before ``RobotModel.qpos_of``): `gaitnet` on the planar biped
    walks 4 s of the built-in stepping stones at 0.5 m/s without a fall."""
    from gaitnet_mpc.scenario import make_scenario, run_scenario

    scenario = make_scenario(
        robot="biped2d", controller="gaitnet", course="stepping-stones", vx_mps=0.5,
        duration_s=4.0,
    )  # fmt: skip
    summary = run_scenario(scenario)
    assert not summary["fell"], summary["fall_reason"]
    assert summary["foothold_violations"] == 0
    assert summary["distance_m"] > 1.5
