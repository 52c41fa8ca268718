"""Robot models: sizes from the issue, and MuJoCo / Pinocchio / adam agreement."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import RobotModel, load_robot


def test_unknown_robot_names_choices() -> None:
    with pytest.raises(ConfigError, match=r"robot: got 'atlas'.*humanoid3d"):
        load_robot("atlas")


@pytest.mark.parametrize(
    ("name", "nv", "mass_kg"), [("humanoid3d", 24, 16.0), ("biped2d", 7, 10.0)]
)
def test_dof_and_mass(name: str, nv: int, mass_kg: float) -> None:
    r = load_robot(name)
    assert r.nv == nv
    assert r.pin_model.nv == nv
    assert r.total_mass_kg == pytest.approx(mass_kg, abs=1e-9)


def test_humanoid_structure() -> None:
    r = load_robot("humanoid3d")
    m = r.mj_model
    assert m.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    assert r.n_joints == 18
    for f in ("left", "right"):
        assert len(r.spec.leg_joints[f]) == 5
        assert len(r.spec.arm_joints[f]) == 4
        # thigh 0.22 m (hip pitch -> knee), shank 0.22 m (knee -> ankle)
        assert np.linalg.norm(m.body(f"{f}_shank").pos) == pytest.approx(0.22)
        assert np.linalg.norm(m.body(f"{f}_foot").pos) == pytest.approx(0.22)
        # line foot: 0.15 m long, 0.02 m wide, toe 0.09 m ahead of the ankle, heel 0.06 m behind
        g = m.geom(f"{f}_foot")
        assert g.type == mujoco.mjtGeom.mjGEOM_BOX
        x_toe = g.pos[0] + g.size[0]
        x_heel = g.pos[0] - g.size[0]
        assert x_toe - x_heel == pytest.approx(0.15)
        assert x_toe == pytest.approx(0.09)
        assert x_heel == pytest.approx(-0.06)
        assert 2 * g.size[1] == pytest.approx(0.02)
    knees = [i for i, n in enumerate(r.joint_names) if n.endswith("knee")]
    assert np.all(r.torque_limit_nm[knees] == 67.0)
    assert np.all(np.delete(r.torque_limit_nm, knees) == 33.5)


def test_humanoid_trunk_inertia_is_physical() -> None:
    m = load_robot("humanoid3d").mj_model
    i = np.sort(m.body_inertia[m.body("trunk").id])
    assert i[0] + i[1] >= i[2]  # triangle inequality (Appendix C's values violate it)


def test_biped_structure() -> None:
    r = load_robot("biped2d")
    m = r.mj_model
    assert r.n_joints == 4
    assert m.body_inertia[r.trunk_body_id][1] == pytest.approx(0.15)
    for f in ("left", "right"):
        assert np.linalg.norm(m.body(f"{f}_shank").pos) == pytest.approx(0.22)
        assert np.linalg.norm(m.site(f"{f}_foot_center").pos) == pytest.approx(0.22)
    assert np.all(r.torque_limit_nm == [33.5, 67.0, 33.5, 67.0])


def test_standing_pose_puts_feet_on_ground_and_com_near_055(robot: RobotModel) -> None:
    m = robot.mj_model
    d = mujoco.MjData(m)
    d.qpos[:] = robot.standing_qpos()
    mujoco.mj_forward(m, d)
    for sid in robot.foot_site_ids.values():
        assert d.site_xpos[sid, 2] == pytest.approx(robot.spec.foot_contact_radius_m, abs=1e-9)
    assert 0.50 < d.subtree_com[robot.trunk_body_id, 2] < 0.60


def _random_state(robot: RobotModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    m = robot.mj_model
    qpos = robot.standing_qpos()
    lo, hi = robot.joint_lower_rad, robot.joint_upper_rad
    qpos[robot.joint_qpos_adr] = rng.uniform(lo, hi)
    if robot.spec.planar:
        qpos[:3] += rng.normal(scale=0.3, size=3)
    else:
        qpos[:3] += rng.normal(scale=0.3, size=3)
        quat = rng.normal(size=4)
        qpos[3:7] = quat / np.linalg.norm(quat)
    qvel = rng.normal(size=m.nv)
    return qpos, qvel


def test_mujoco_pinocchio_adam_agree(robot: RobotModel) -> None:
    """Total mass, CoM and centroidal momentum agree to 1e-8 over random states."""
    rng = np.random.default_rng(0)
    m = robot.mj_model
    d = mujoco.MjData(m)
    pdata = robot.pin_model.createData()
    kd = robot.adam
    assert pin.computeTotalMass(robot.pin_model) == pytest.approx(robot.total_mass_kg, abs=1e-10)
    assert float(kd.get_total_mass()) == pytest.approx(robot.total_mass_kg, abs=1e-10)
    for _ in range(20):
        qpos, qvel = _random_state(robot, rng)
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d)
        mujoco.mj_subtreeVel(m, d)
        root = 1  # the trunk: its subtree is the whole robot
        com_mj = d.subtree_com[root].copy()
        h_mj = np.concatenate(
            [robot.total_mass_kg * d.subtree_linvel[root], d.subtree_angmom[root]]
        )

        q, v = robot.mj_to_pin(qpos, qvel)
        hg = pin.computeCentroidalMomentum(robot.pin_model, pdata, q, v)
        np.testing.assert_allclose(pdata.com[0], com_mj, atol=1e-8)
        np.testing.assert_allclose(hg.vector, h_mj, atol=1e-8)

        base_h, base_twist = robot.adam_base(qpos, qvel)
        s = qpos[robot.joint_qpos_adr]
        sd = qvel[robot.joint_dof_adr]
        np.testing.assert_allclose(
            np.asarray(kd.CoM_position(base_h, s)).ravel(), com_mj, atol=1e-8
        )
        cmm = np.asarray(kd.centroidal_momentum_matrix(base_h, s))
        h_adam = cmm @ np.concatenate([base_twist, sd])
        np.testing.assert_allclose(h_adam, h_mj, atol=1e-8)


def test_state_conversion_round_trip(robot: RobotModel) -> None:
    rng = np.random.default_rng(1)
    qpos, qvel = _random_state(robot, rng)
    q, v = robot.mj_to_pin(qpos, qvel)
    qpos2, qvel2 = robot.pin_to_mj(q, v)
    np.testing.assert_allclose(qpos2, qpos, atol=1e-12)
    np.testing.assert_allclose(qvel2, qvel, atol=1e-12)


def test_left_and_right_legs_collide(robot: RobotModel) -> None:
    """Self-collision is on: every left-leg link (thigh, shank, foot) has a contact pair
    with every right-leg link, and a pose with the feet pushed into each other makes
    MuJoCo report leg-leg contacts (the contype/conaffinity bits alone filter them out)."""
    m = robot.mj_model
    pairs = {
        frozenset((m.geom(int(a)).name, m.geom(int(b)).name))
        for a, b in zip(m.pair_geom1, m.pair_geom2, strict=True)
    }
    links = ("thigh", "shank", "foot")
    for a in links:
        for b in links:
            assert frozenset((f"left_{a}", f"right_{b}")) in pairs
    data = mujoco.MjData(m)
    data.qpos[:] = robot.standing_qpos(0.0, 0.0, 0.0)
    if robot.spec.planar:
        return  # the legs move in planes 8 cm apart: no pose of the model makes them meet
    hip_roll = {f: m.joint(f"{f}_hip_roll").qposadr[0] for f in ("left", "right")}
    data.qpos[hip_roll["left"]] = -0.35  # both legs rolled inward to their joint limits
    data.qpos[hip_roll["right"]] = 0.35
    mujoco.mj_forward(m, data)
    robot_bodies = {m.body(n).id for f in ("left", "right") for n in (f"{f}_shank", f"{f}_foot")}
    touching = [
        (int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2]))
        for c in data.contact[: data.ncon]
    ]
    assert any(b1 in robot_bodies and b2 in robot_bodies for b1, b2 in touching)
