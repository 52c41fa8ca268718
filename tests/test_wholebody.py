"""Whole-body NMPC (Sec. III-A): the symbolic dynamics against MuJoCo, the transcription's
constraints at a solution, and input validation."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from gaitnet_mpc.command import Command
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.wholebody import (
    WBConfig,
    WholeBodyDynamics,
    WholeBodyMPC,
    contact_schedule,
    make_problem,
    stage_dt,
)
from gaitnet_mpc.mpc.wholebody.problem import swing_height_profile
from gaitnet_mpc.robots import FEET, RobotModel, load_robot

# MuJoCo and the RNEA evaluate the same rigid-body model in double precision: agreement to
# round-off; one Euler step integrates the quaternion with a truncated series (< 1e-12).
TOL_ACC = 1e-8
TOL_STEP = 1e-9
# A solution satisfies eq. (3a)/(4) up to the NLP tolerance (1e-6 on scaled residuals).
TOL_SOLUTION = 1e-5


@pytest.fixture(scope="module", params=["humanoid3d", "biped2d"])
def robot_dyn(request: pytest.FixtureRequest) -> tuple[RobotModel, WholeBodyDynamics]:
    robot = load_robot(request.param)
    return robot, WholeBodyDynamics(robot)


def _random_state(robot: RobotModel, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    qpos = robot.standing_qpos()
    qpos[robot.joint_qpos_adr] += 0.2 * rng.standard_normal(robot.n_joints)
    if not robot.spec.planar:
        quat = qpos[3:7] + 0.2 * rng.standard_normal(4)
        qpos[3:7] = quat / np.linalg.norm(quat)
    qvel = rng.standard_normal(robot.nv)
    tau = rng.uniform(-5.0, 5.0, robot.n_joints)
    return qpos, qvel, tau


def _mujoco_in_air(robot: RobotModel, dt_s: float) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """A copy of the robot's model without ground contact, Euler without implicit damping."""
    model = mujoco.MjModel.from_xml_path(str(robot.spec.mjcf_path))
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
    model.opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)
    model.opt.timestep = dt_s
    return model, mujoco.MjData(model)


def _apply_contact_forces(
    robot: RobotModel,
    dyn: WholeBodyDynamics,
    data: mujoco.MjData,
    force_world_n: np.ndarray,
) -> None:
    """Contact forces (n_c, 3) as MuJoCo external wrenches at the foot bodies' CoMs."""
    data.xfrc_applied[:] = 0.0
    p_contact = np.array(dyn.contact_kinematics(data.qpos, data.qvel)[0])
    for i, cp in enumerate(dyn.contact_points):
        body = robot.mj_model.site_bodyid[robot.foot_site_ids[cp.foot]]
        arm = p_contact[:, i] - data.xipos[body]
        data.xfrc_applied[body, 0:3] += force_world_n[i]
        data.xfrc_applied[body, 3:6] += np.cross(arm, force_world_n[i])


def test_inverse_dynamics_matches_mujoco_acceleration(robot_dyn) -> None:
    """Eq. (4) solved for qacc equals MuJoCo's forward dynamics, with contact forces."""
    robot, dyn = robot_dyn
    model, data = _mujoco_in_air(robot, 0.01)
    for seed in range(3):
        qpos, qvel, tau = _random_state(robot, seed)
        forces = np.random.default_rng(10 + seed).uniform(-20.0, 60.0, (dyn.n_contacts, 3))
        if robot.spec.planar:
            forces[:, 1] = 0.0
        data.qpos[:], data.qvel[:], data.ctrl[:] = qpos, qvel, tau
        mujoco.mj_kinematics(model, data)
        _apply_contact_forces(robot, dyn, data, forces)
        mujoco.mj_forward(model, data)
        qacc = dyn.forward_dynamics(qpos, qvel, tau, forces.ravel())
        assert np.max(np.abs(qacc - data.qacc)) < TOL_ACC * max(1.0, np.max(np.abs(data.qacc)))


def test_one_stage_matches_mujoco_euler_step(robot_dyn) -> None:
    """Eq. (3a): one semi-implicit Euler stage equals one MuJoCo Euler step (dt = 0.05 s)."""
    robot, dyn = robot_dyn
    dt_s = 0.05
    model, data = _mujoco_in_air(robot, dt_s)
    qpos, qvel, tau = _random_state(robot, 7)
    data.qpos[:], data.qvel[:], data.ctrl[:] = qpos, qvel, tau
    mujoco.mj_step(model, data)
    qacc = dyn.forward_dynamics(qpos, qvel, tau, np.zeros(3 * dyn.n_contacts))
    qpos_next, qvel_next = (np.array(v).ravel() for v in dyn.step(qpos, qvel, qacc, dt_s))
    assert np.max(np.abs(qvel_next - data.qvel)) < TOL_STEP * max(1.0, np.max(np.abs(qvel)))
    assert np.max(np.abs(qpos_next - data.qpos)) < TOL_STEP


def test_contact_points_lie_on_the_feet(robot_dyn) -> None:
    """Toe/heel (line foot) or the sphere bottom (point foot) from the MuJoCo foot site."""
    robot, dyn = robot_dyn
    model, data = _mujoco_in_air(robot, 0.01)
    qpos, qvel, _ = _random_state(robot, 3)
    data.qpos[:], data.qvel[:] = qpos, qvel
    mujoco.mj_forward(model, data)
    p_contact, v_contact = (np.array(v) for v in dyn.contact_kinematics(qpos, qvel))
    spec = robot.spec
    for foot in FEET:
        sid = robot.foot_site_ids[foot]
        rot = data.site_xmat[sid].reshape(3, 3)
        idx = dyn.contact_points_of(foot)
        if spec.foot_toe_m > 0.0:
            offsets = [(spec.foot_toe_m, 0.0, -spec.foot_contact_radius_m)]
            offsets.append((-spec.foot_heel_m, 0.0, -spec.foot_contact_radius_m))
            expected = [data.site_xpos[sid] + rot @ np.array(o) for o in offsets]
        else:
            expected = [data.site_xpos[sid] - np.array([0, 0, spec.foot_contact_radius_m])]
        np.testing.assert_allclose(p_contact[:, idx].T, expected, atol=1e-12)
        # Material velocity of the contact point: finite difference of its body-fixed motion.
        vel6 = np.zeros(6)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_SITE, sid, vel6, 0)
        omega, v_site = vel6[0:3], vel6[3:6]
        for j, i in enumerate(idx):
            arm = expected[j] - data.site_xpos[sid]
            np.testing.assert_allclose(v_contact[:, i], v_site + np.cross(omega, arm), atol=1e-10)


def _check_solution(mpc: WholeBodyMPC, problem, sol) -> None:
    robot, dyn, cfg = mpc.robot, mpc.dyn, mpc.config
    assert sol.success, sol.status
    assert sol.constraint_violation < 1e-6
    assert np.all(np.abs(sol.tau_nm) <= robot.torque_limit_nm + 1e-6)
    joints = sol.qpos[1:, dyn.nq - dyn.n_joints :]
    assert np.all(joints >= robot.joint_lower_rad - 1e-6)
    assert np.all(joints <= robot.joint_upper_rad + 1e-6)
    f = sol.force_world_n
    assert np.all(f[:, :, 2] >= -1e-6)
    tangential = np.linalg.norm(f[:, :, 0:2], axis=2)
    assert np.all(tangential <= np.sqrt(2.0) * cfg.friction_coef * f[:, :, 2] + 1e-6)
    for k in range(problem.horizon_stages):
        for fi, foot in enumerate(FEET):
            fz = f[k, dyn.contact_points_of(foot), 2].sum()
            if problem.stance[k, fi]:
                assert cfg.f_min_n - 1e-6 <= fz <= cfg.f_max_n + 1e-6
            else:
                assert np.allclose(f[k, dyn.contact_points_of(foot)], 0.0)
        # Eq. (3a)/(4) at the solution: re-integrate stage k from the solution's inputs.
        gen = np.array(
            dyn.inverse_dynamics(sol.qpos[k], sol.qvel[k], sol.qacc[k], f[k].ravel())
        ).ravel()
        np.testing.assert_allclose(gen[dyn.n_root_dofs :], sol.tau_nm[k], atol=TOL_SOLUTION)
        np.testing.assert_allclose(gen[: dyn.n_root_dofs], 0.0, atol=TOL_SOLUTION)
        q_next, v_next = dyn.step(sol.qpos[k], sol.qvel[k], sol.qacc[k], problem.dt_stage_s[k])
        np.testing.assert_allclose(np.array(q_next).ravel(), sol.qpos[k + 1], atol=TOL_SOLUTION)
        np.testing.assert_allclose(np.array(v_next).ravel(), sol.qvel[k + 1], atol=TOL_SOLUTION)
    p_c, _ = dyn.contact_kinematics(sol.qpos[-1], sol.qvel[-1])
    assert np.all(np.array(p_c)[2] >= problem.ground_z_m - 1e-6)


def test_humanoid_standing_solution_satisfies_constraints() -> None:
    robot = load_robot("humanoid3d")
    mpc = WholeBodyMPC(robot, solver="ipopt")
    q0 = robot.standing_qpos()
    problem = make_problem(mpc.config, q0, np.zeros(robot.nv), q0, Command(), planar=False)
    sol = mpc.solve(problem)
    _check_solution(mpc, problem, sol)
    # Standing still: the trunk stays within 1 cm of its start, the weight is carried.
    assert np.max(np.abs(sol.qpos[:, 0:3] - q0[0:3])) < 0.01
    weight_n = robot.total_mass_kg * 9.81
    assert abs(sol.force_world_n[0, :, 2].sum() - weight_n) < 0.2 * weight_n
    # A warm start from the solution converges in no more iterations.
    again = mpc.solve(problem, warm_start=sol)
    assert again.success and again.iterations <= sol.iterations


@pytest.mark.parametrize("solver", ["ipopt", "fatrop"])
def test_biped_stepping_solution_satisfies_constraints(solver: str) -> None:
    robot = load_robot("biped2d")
    mpc = WholeBodyMPC(robot, solver=solver)
    q0 = robot.standing_qpos()
    problem = make_problem(
        mpc.config,
        q0,
        np.zeros(robot.nv),
        q0,
        Command(vx_mps=0.3),
        planar=True,
        step_dt_s=(0.05, 0.06),
        phase_stage=2,
        stance_foot="left",
    )
    sol = mpc.solve(problem)
    _check_solution(mpc, problem, sol)
    # Swing clearance (3c): the swing foot's contact point clears the profile, and it is
    # on the ground at its touchdown node (swing in stage k, stance in stage k + 1).
    touchdowns = 0
    for k in range(problem.horizon_stages):
        p_c = np.array(mpc.dyn.contact_kinematics(sol.qpos[k + 1], sol.qvel[k + 1])[0])
        for fi, foot in enumerate(FEET):
            if not problem.stance[k, fi]:
                z = p_c[2, mpc.dyn.contact_points_of(foot)]
                assert np.all(z >= problem.swing_height_min_m[k] - 1e-6)
                if k + 1 < problem.horizon_stages and problem.stance[k + 1, fi]:
                    np.testing.assert_allclose(z, problem.ground_z_m, atol=1e-6)
                    touchdowns += 1
    assert touchdowns == 2  # right at node 3, left at node 8


def test_schedule_and_stage_times() -> None:
    cfg = WBConfig()
    stance = contact_schedule(cfg, phase_stage=3, stance_foot="right")
    # Right foot for the 2 remaining stages of the step, then 5 left, then right again.
    assert stance[:, 1].tolist() == [True] * 2 + [False] * 5 + [True] * 3
    assert np.all(stance.sum(axis=1) == 1)
    dt = stage_dt(cfg, phase_stage=3, step_dt_s=(0.05, 0.07))
    assert dt.tolist() == [0.05] * 2 + [0.07] * 8
    # Swing height bound at node k+1, s = (j + 1) / h' of the swing elapsed: symmetric,
    # positive inside the swing, zero at the touchdown node (the step's last stage).
    bound = swing_height_profile(cfg, phase_stage=3)
    j = (np.arange(cfg.horizon_stages) + 3) % cfg.stages_per_step
    np.testing.assert_allclose(bound[j == cfg.stages_per_step - 1], 0.0, atol=1e-12)
    assert np.all(bound[j < cfg.stages_per_step - 1] > 0.02)
    np.testing.assert_allclose(bound[j == 0], bound[j == cfg.stages_per_step - 2])


def test_validation_errors() -> None:
    cfg = WBConfig()
    with pytest.raises(ConfigError, match="phase_stage"):
        contact_schedule(cfg, phase_stage=5, stance_foot="left")
    with pytest.raises(ConfigError, match="stance_foot"):
        contact_schedule(cfg, phase_stage=0, stance_foot="middle")
    with pytest.raises(ConfigError, match="step_dt_s"):
        stage_dt(cfg, phase_stage=0, step_dt_s=(0.5,))
    with pytest.raises(ConfigError, match="f_min_n"):
        WBConfig(f_min_n=600.0)
    robot = load_robot("biped2d")
    with pytest.raises(ConfigError, match="solver"):
        WholeBodyMPC(robot, solver="snopt")
    mpc = WholeBodyMPC(robot)
    q0 = robot.standing_qpos()
    problem = make_problem(cfg, q0, np.zeros(robot.nv), q0, Command(), planar=True)
    bad = make_problem(cfg, q0[:-1], np.zeros(robot.nv), q0, Command(), planar=True)
    with pytest.raises(ConfigError, match="qpos0"):
        mpc.solve(bad)
    sol = mpc.solve(problem)
    truncated = type(sol)(**{**sol.__dict__, "x_opt": sol.x_opt[:-1]})
    with pytest.raises(ConfigError, match="warm_start"):
        mpc.solve(problem, warm_start=truncated)


def test_shifted_warm_start_solves_the_next_call() -> None:
    """Receding horizon: the shifted solution (primal and duals) seeds the next phase."""
    robot = load_robot("biped2d")
    mpc = WholeBodyMPC(robot, solver="ipopt")
    q0 = robot.standing_qpos()

    def problem(qpos: np.ndarray, qvel: np.ndarray, phase: int):
        return make_problem(
            mpc.config, qpos, qvel, q0, Command(vx_mps=0.3), planar=True,
            step_dt_s=(0.05, 0.06), phase_stage=phase, stance_foot="left",
        )  # fmt: skip

    first = mpc.solve(problem(q0, np.zeros(robot.nv), 0))
    warm = mpc.shift(first)
    assert len(warm.lam_blocks) == 2 * mpc.horizon_stages + 1
    np.testing.assert_allclose(warm.x_opt[: mpc.nx], first.x_opt[mpc.nx + mpc.nu :][: mpc.nx])
    nxt = problem(first.qpos[1], first.qvel[1], 1)
    second = mpc.solve(nxt, warm_start=warm)
    _check_solution(mpc, nxt, second)
