"""Analytic leg IK (paper Appendix B): round trips through Pinocchio and MuJoCo FK."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitnet_mpc.kinematics.leg_ik import (
    LegGeometry,
    leg_geometry,
    leg_ik,
    planar_leg_geometry,
    planar_leg_ik,
    whole_body_ik,
)
from gaitnet_mpc.robots import FEET, RobotModel, load_robot

POS_TOL_M = 1e-9
ROT_TOL = 1e-9
MAX_TILT_RAD = 0.3


# ----------------------------------------------------------------------- helpers
def _pin_q(
    robot: RobotModel, p_base: np.ndarray, rot_base: np.ndarray, joints: np.ndarray
) -> np.ndarray:
    """Pinocchio configuration (nq,) of a trunk pose and the actuated joint angles."""
    if robot.spec.planar:  # [x, z, pitch, joints]
        root = [p_base[0], p_base[2], np.arctan2(rot_base[0, 2], rot_base[0, 0])]
        return np.concatenate([root, joints])
    return np.concatenate([p_base, pin.Quaternion(rot_base).coeffs(), joints])  # xyzw


def _trunk_yaw(rot: np.ndarray) -> np.ndarray:
    """(N,) heading of the trunk x axis of (N, 3, 3) rotations."""
    return np.arctan2(rot[:, 1, 0], rot[:, 0, 0])


def _trunk_pose(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    rpy = np.array(
        [
            rng.uniform(-MAX_TILT_RAD, MAX_TILT_RAD),
            rng.uniform(-MAX_TILT_RAD, MAX_TILT_RAD),
            rng.uniform(-np.pi, np.pi),
        ]
    )
    return rng.uniform(-2.0, 2.0, 3), pin.rpy.rpyToMatrix(rpy)


def _foot_fk(
    robot: RobotModel, data: pin.Data, foot: str, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    pin.framesForwardKinematics(robot.pin_model, data, q)
    placement = data.oMf[robot.pin_foot_frame_ids[foot]]
    return placement.translation.copy(), placement.rotation.copy()


def _feasible_sample(
    robot: RobotModel,
    data: pin.Data,
    foot: str,
    p_base: np.ndarray,
    rot_base: np.ndarray,
    u: np.ndarray,
    zero_yaw: bool = False,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Leg angles from fractions ``u`` (4,) of the joint ranges; the ankle is set (through
    Pinocchio's ankle joint frame, independently of the IK) so the foot axis is level.
    Returns ``(q_leg (5,), q_full)`` or None if the ankle angle is outside its range."""
    geom = leg_geometry(robot, foot)
    idx = robot.leg_joint_index[foot]
    q_leg = np.zeros(5)
    q_leg[:4] = geom.lower_rad[:4] + u * (geom.upper_rad[:4] - geom.lower_rad[:4])
    if zero_yaw:
        q_leg[0] = 0.0
    joints = robot.nominal_joint_pos()
    joints[idx] = q_leg
    q = _pin_q(robot, p_base, rot_base, joints)
    pin.forwardKinematics(robot.pin_model, data, q)
    rot_ankle = data.oMi[robot.pin_model.getJointId(robot.joint_names[idx[4]])].rotation
    q_leg[4] = np.arctan2(rot_ankle[2, 0], rot_ankle[2, 2])  # world-level foot x axis
    if not geom.lower_rad[4] < q_leg[4] < geom.upper_rad[4]:
        return None
    q[robot.n_root_q + idx[4]] = q_leg[4]
    return q_leg, q


def _samples(
    robot: RobotModel, foot: str, n: int, seed: int, zero_yaw: bool = False
) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    data = robot.pin_model.createData()
    out: dict[str, list[np.ndarray]] = {k: [] for k in ("q_leg", "q", "p_foot", "p", "rot")}
    while len(out["q"]) < n:
        p_base, rot_base = _trunk_pose(rng)
        sample = _feasible_sample(
            robot, data, foot, p_base, rot_base, rng.uniform(size=4), zero_yaw
        )
        if sample is None:
            continue
        p_foot, _ = _foot_fk(robot, data, foot, sample[1])
        for key, val in zip(out, (*sample, p_foot, p_base, rot_base), strict=True):
            out[key].append(val)
    return {k: np.array(v) for k, v in out.items()}


def _check_round_trip(
    robot: RobotModel, foot: str, s: dict[str, np.ndarray], q_leg: np.ndarray
) -> None:
    data = robot.pin_model.createData()
    idx = robot.leg_joint_index[foot]
    for k in range(q_leg.shape[0]):
        q = s["q"][k].copy()
        q[robot.n_root_q + idx] = q_leg[k]
        p_foot, rot_foot = _foot_fk(robot, data, foot, q)
        assert np.linalg.norm(p_foot - s["p_foot"][k]) < POS_TOL_M
        assert abs(rot_foot[2, 0]) < ROT_TOL  # foot x axis horizontal in the world


# ------------------------------------------------------------------------- geometry
def test_geometry_matches_mjcf(humanoid: RobotModel) -> None:
    for foot, side in (("left", 1.0), ("right", -1.0)):
        g = leg_geometry(humanoid, foot)
        np.testing.assert_allclose(g.p_yaw_trunk_m, [0.0, side * 0.045, -0.17])
        np.testing.assert_allclose(g.p_roll_yaw_m, [0.0, 0.0, -0.05])
        np.testing.assert_allclose(g.p_pitch_roll_m, [0.0, side * 0.02, 0.0])
        assert g.thigh_m == pytest.approx(0.22)
        assert g.shank_m == pytest.approx(0.22)
        np.testing.assert_allclose(g.p_foot_ankle_m, [0.015, 0.0, 0.0])


def test_wrong_geometry_kind_raises(humanoid: RobotModel, biped: RobotModel) -> None:
    with pytest.raises(ValueError, match="planar"):
        leg_geometry(biped, "left")
    with pytest.raises(ValueError, match="not planar"):
        planar_leg_geometry(humanoid, "left")


# -------------------------------------------------------------------- round trips
@pytest.mark.parametrize("foot", FEET)
def test_round_trip_pinocchio_thousands(humanoid: RobotModel, foot: str) -> None:
    s = _samples(humanoid, foot, 1500, seed=1 if foot == "left" else 2)
    yaw = _trunk_yaw(s["rot"]) + s["q_leg"][:, 0]
    sol = leg_ik(leg_geometry(humanoid, foot), s["p_foot"], s["p"], s["rot"], yaw)
    assert sol.q_rad.shape == (1500, 5)
    assert sol.reachable.all()
    np.testing.assert_allclose(sol.q_rad, s["q_leg"], atol=1e-8)  # unique branch
    _check_round_trip(humanoid, foot, s, sol.q_rad)


@pytest.mark.parametrize("foot", FEET)
def test_default_yaw_is_zero_hip_yaw(humanoid: RobotModel, foot: str) -> None:
    """Eq. 31: without a desired foot yaw, q0 = 0 even for a tilted trunk."""
    s = _samples(humanoid, foot, 400, seed=3, zero_yaw=True)
    sol = leg_ik(leg_geometry(humanoid, foot), s["p_foot"], s["p"], s["rot"])
    assert sol.reachable.all()
    assert np.all(sol.q_rad[:, 0] == 0.0)
    np.testing.assert_allclose(sol.q_rad, s["q_leg"], atol=1e-8)
    _check_round_trip(humanoid, foot, s, sol.q_rad)


@pytest.mark.parametrize("foot", FEET)
def test_round_trip_mujoco(humanoid: RobotModel, foot: str) -> None:
    s = _samples(humanoid, foot, 300, seed=4)
    sol = leg_ik(
        leg_geometry(humanoid, foot),
        s["p_foot"],
        s["p"],
        s["rot"],
        _trunk_yaw(s["rot"]) + s["q_leg"][:, 0],
    )
    assert sol.reachable.all()
    m = humanoid.mj_model
    data = mujoco.MjData(m)
    site = humanoid.foot_site_ids[foot]
    idx = humanoid.leg_joint_index[foot]
    for k in range(sol.q_rad.shape[0]):
        q = s["q"][k].copy()
        q[humanoid.n_root_q + idx] = sol.q_rad[k]
        data.qpos[:], _ = humanoid.pin_to_mj(q, np.zeros(m.nv))
        mujoco.mj_kinematics(m, data)
        assert np.linalg.norm(data.site_xpos[site] - s["p_foot"][k]) < POS_TOL_M
        assert abs(data.site_xmat[site].reshape(3, 3)[2, 0]) < ROT_TOL


@settings(max_examples=150, deadline=None)
@given(
    u=st.lists(st.floats(0.0, 1.0), min_size=4, max_size=4),
    roll=st.floats(-MAX_TILT_RAD, MAX_TILT_RAD),
    pitch=st.floats(-MAX_TILT_RAD, MAX_TILT_RAD),
    yaw=st.floats(-np.pi, np.pi),
    left=st.booleans(),
)
def test_round_trip_property(
    humanoid: RobotModel, u: list[float], roll: float, pitch: float, yaw: float, left: bool
) -> None:
    robot = humanoid
    foot = "left" if left else "right"
    data = robot.pin_model.createData()
    p_base, rot_base = np.array([0.3, -0.2, 0.6]), pin.rpy.rpyToMatrix(roll, pitch, yaw)
    sample = _feasible_sample(robot, data, foot, p_base, rot_base, np.array(u))
    if sample is None:
        return
    q_leg, q = sample
    p_foot, _ = _foot_fk(robot, data, foot, q)
    geom = leg_geometry(robot, foot)
    sol = leg_ik(geom, p_foot, p_base, rot_base, yaw + q_leg[0])
    assert sol.reachable[0]
    s = {"q": q[None], "p_foot": p_foot[None]}
    _check_round_trip(robot, foot, s, sol.q_rad)


def test_foot_yaw_sets_world_heading_for_level_trunk(humanoid: RobotModel) -> None:
    geom = leg_geometry(humanoid, "left")
    data = humanoid.pin_model.createData()
    rng = np.random.default_rng(5)
    for _ in range(50):
        trunk_yaw = rng.uniform(-np.pi, np.pi)
        rot = pin.rpy.rpyToMatrix(0.0, 0.0, trunk_yaw)
        p_base = np.array([0.0, 0.0, 0.55])
        foot_yaw = trunk_yaw + rng.uniform(-0.5, 0.5)
        target = p_base + rot @ np.array([rng.uniform(-0.1, 0.1), 0.07, -0.6])
        sol = leg_ik(geom, target, p_base, rot, foot_yaw)
        assert sol.reachable[0]
        joints = humanoid.nominal_joint_pos()
        joints[humanoid.leg_joint_index["left"]] = sol.q_rad[0]
        q = _pin_q(humanoid, p_base, rot, joints)
        p_foot, rot_foot = _foot_fk(humanoid, data, "left", q)
        assert np.linalg.norm(p_foot - target) < POS_TOL_M
        heading = np.arctan2(rot_foot[1, 0], rot_foot[0, 0])
        assert abs(np.angle(np.exp(1j * (heading - foot_yaw)))) < ROT_TOL


def test_broadcast_single_trunk_pose(humanoid: RobotModel) -> None:
    s = _samples(humanoid, "right", 1, seed=6, zero_yaw=True)
    targets = np.repeat(s["p_foot"], 10, axis=0)  # (10, 3)
    sol = leg_ik(leg_geometry(humanoid, "right"), targets, s["p"][0], s["rot"][0])
    assert sol.q_rad.shape == (10, 5)
    assert sol.reachable.all()
    np.testing.assert_allclose(sol.q_rad, np.repeat(s["q_leg"], 10, axis=0), atol=1e-8)


# --------------------------------------------------------------------- unreachable
def _assert_feasible_output(geom: LegGeometry, q: np.ndarray) -> None:
    assert np.all(np.isfinite(q))
    assert np.all(q >= geom.lower_rad) and np.all(q <= geom.upper_rad)


@pytest.mark.parametrize("foot", FEET)
def test_unreachable_targets_are_flagged(humanoid: RobotModel, foot: str) -> None:
    geom = leg_geometry(humanoid, foot)
    hip = geom.p_yaw_trunk_m + geom.p_roll_yaw_m  # roll joint, level trunk at the origin
    offsets = np.array(
        [
            [0.0, 0.0, -1.0],  # 1 m below the hip: too far
            [0.0, 0.0, 0.3],  # above the hip
            [0.0, 0.0, -0.1],  # too close (knee limit)
            [0.6, 0.0, 0.0],  # too far forward
            [0.0, 0.0, 0.0],  # on the roll axis
            [0.0, 0.0, -0.03],  # inside the r_{21,y} offset cylinder
            [0.0, np.sign(geom.p_pitch_roll_m[1]) * -0.4, -0.3],  # roll past its limit
        ]
    )
    targets = hip + offsets  # (7, 3)
    sol = leg_ik(geom, targets, np.zeros(3), np.eye(3))
    assert not sol.reachable.any()
    _assert_feasible_output(geom, sol.q_rad)
    sol = leg_ik(geom, targets, np.zeros(3), np.eye(3), foot_yaw_rad=np.full(7, 2.0))
    assert not sol.reachable.any()  # hip yaw past its limit as well
    _assert_feasible_output(geom, sol.q_rad)


def test_too_far_target_returns_straight_leg_towards_it(humanoid: RobotModel) -> None:
    geom = leg_geometry(humanoid, "left")
    hip = geom.p_yaw_trunk_m + geom.p_roll_yaw_m + [0.0, geom.p_pitch_roll_m[1], 0.0]
    offset = np.array([geom.p_foot_ankle_m[0], 0.0, -1.0])  # straight below, 1 m
    sol = leg_ik(geom, hip + offset, np.zeros(3), np.eye(3))
    assert not sol.reachable[0]
    np.testing.assert_allclose(sol.q_rad[0], np.zeros(5), atol=1e-12)


@settings(max_examples=300, deadline=None)
@given(
    target=st.tuples(st.floats(-0.3, 0.3), st.floats(-0.2, 0.3), st.floats(-0.7, -0.1)),
    roll=st.floats(-MAX_TILT_RAD, MAX_TILT_RAD),
    pitch=st.floats(-MAX_TILT_RAD, MAX_TILT_RAD),
    foot_yaw=st.one_of(st.none(), st.floats(-4.0, 4.0)),
    left=st.booleans(),
)
def test_any_target_gives_finite_angles_and_honest_flag(
    humanoid: RobotModel,
    target: tuple[float, float, float],
    roll: float,
    pitch: float,
    foot_yaw: float | None,
    left: bool,
) -> None:
    """Any target: finite angles within limits; ``reachable`` implies an exact solution."""
    foot = "left" if left else "right"
    side = 1.0 if left else -1.0
    rot = pin.rpy.rpyToMatrix(roll, pitch, 0.4)
    p_base = np.array([0.1, 0.0, 0.5])
    p_target = p_base + rot @ (np.array(target) * [1.0, side, 1.0])
    _check_any_targets(humanoid, foot, p_target[None], p_base, rot, foot_yaw)


def _check_any_targets(
    robot: RobotModel,
    foot: str,
    p_target: np.ndarray,
    p_base: np.ndarray,
    rot: np.ndarray,
    foot_yaw: float | None,
) -> None:
    geom = leg_geometry(robot, foot)
    sol = leg_ik(geom, p_target, p_base, rot, foot_yaw)
    _assert_feasible_output(geom, sol.q_rad)
    data = robot.pin_model.createData()
    for k in np.flatnonzero(sol.reachable):
        joints = robot.nominal_joint_pos()
        joints[robot.leg_joint_index[foot]] = sol.q_rad[k]
        q = _pin_q(robot, p_base, rot, joints)
        p_foot, rot_foot = _foot_fk(robot, data, foot, q)
        assert np.linalg.norm(p_foot - p_target[k]) < POS_TOL_M
        assert abs(rot_foot[2, 0]) < ROT_TOL


@pytest.mark.parametrize("foot", FEET)
def test_random_box_targets(humanoid: RobotModel, foot: str) -> None:
    """20000 targets in a box around the hip: ~16 % reachable, all exact, none NaN."""
    rng = np.random.default_rng(8)
    rot = pin.rpy.rpyToMatrix(0.1, -0.2, 1.0)
    p_base = np.array([0.0, 0.0, 0.5])
    side = 1.0 if foot == "left" else -1.0
    local = rng.uniform([-0.3, -0.2, -0.7], [0.3, 0.3, -0.1], (20000, 3)) * [1.0, side, 1.0]
    p_target = p_base + local @ rot.T
    geom = leg_geometry(humanoid, foot)
    assert leg_ik(geom, p_target, p_base, rot).reachable.mean() > 0.1
    _check_any_targets(humanoid, foot, p_target, p_base, rot, None)


# ------------------------------------------------------------------------ planar biped
def _biped_samples(
    biped: RobotModel, foot: str, n: int, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    geom = planar_leg_geometry(biped, foot)
    data = biped.pin_model.createData()
    q_leg = rng.uniform(geom.lower_rad, geom.upper_rad, (n, 2))
    root = np.column_stack(
        [rng.uniform(-2, 2, n), rng.uniform(0.3, 0.8, n), rng.uniform(-0.5, 0.5, n)]
    )
    p_foot = np.empty((n, 2))
    for k in range(n):
        q = np.concatenate([root[k], biped.nominal_joint_pos()])
        q[3 + biped.leg_joint_index[foot]] = q_leg[k]
        p_foot[k] = _foot_fk(biped, data, foot, q)[0][[0, 2]]
    return q_leg, root, p_foot, rng.uniform(-1, 1, (n, 2))


@pytest.mark.parametrize("foot", FEET)
def test_planar_round_trip(biped: RobotModel, foot: str) -> None:
    q_leg, root, p_foot, _ = _biped_samples(biped, foot, 1000, seed=7)
    geom = planar_leg_geometry(biped, foot)
    sol = planar_leg_ik(geom, p_foot, root[:, :2], root[:, 2])
    assert sol.reachable.all()
    np.testing.assert_allclose(sol.q_rad, q_leg, atol=1e-8)
    data = biped.pin_model.createData()
    for k in range(0, 1000, 10):
        q = np.concatenate([root[k], biped.nominal_joint_pos()])
        q[3 + biped.leg_joint_index[foot]] = sol.q_rad[k]
        assert np.linalg.norm(_foot_fk(biped, data, foot, q)[0][[0, 2]] - p_foot[k]) < POS_TOL_M


def test_planar_unreachable(biped: RobotModel) -> None:
    geom = planar_leg_geometry(biped, "left")
    targets = np.array([[0.0, -1.2], [0.0, -0.2], [0.0, 0.5], [0.3, -0.5]])
    sol = planar_leg_ik(geom, targets, np.zeros(2), 0.0)
    assert not sol.reachable.any()
    assert np.all(np.isfinite(sol.q_rad))
    assert np.all(sol.q_rad >= geom.lower_rad) and np.all(sol.q_rad <= geom.upper_rad)


# ------------------------------------------------------------------------ whole body
@pytest.mark.parametrize("name", ["humanoid3d", "biped2d"])
def test_whole_body_ik_recovers_standing_pose(name: str) -> None:
    robot = load_robot(name)
    qpos = robot.standing_qpos(x_m=0.4)
    m = robot.mj_model
    data = mujoco.MjData(m)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(m, data)
    p_base, rot_base = robot.base_pose(qpos)
    targets = {f: np.tile(data.site_xpos[robot.foot_site_ids[f]], (3, 1)) for f in FEET}
    sol = whole_body_ik(robot, np.tile(p_base, (3, 1)), np.tile(rot_base, (3, 1, 1)), targets)
    assert sol.joint_pos_rad.shape == (3, robot.n_joints)
    assert sol.reachable.all()
    np.testing.assert_allclose(
        sol.joint_pos_rad, np.tile(robot.nominal_joint_pos(), (3, 1)), atol=1e-9
    )
    q = _pin_q(robot, p_base, rot_base, sol.joint_pos_rad[0])
    q_expected, _ = robot.mj_to_pin(qpos, np.zeros(m.nv))
    np.testing.assert_allclose(q, q_expected, atol=1e-12)


def test_whole_body_ik_unknown_foot(humanoid: RobotModel) -> None:
    with pytest.raises(ValueError, match="unknown foot"):
        whole_body_ik(humanoid, np.zeros(3), np.eye(3), {"middle": np.zeros(3)})
