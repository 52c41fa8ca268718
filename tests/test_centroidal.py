"""Centroidal momentum map, its time derivative and the centroidal pose (eqs. 6, 11, 12, 30)."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from gaitnet_mpc.kinematics.centroidal import (
    _euler_maps,  # A_xi, dA_xi and xi of eq. 30 along a trajectory
    _has_free_flyer,
    _root_maps,  # the free-flyer block T6 of v = T(xi) xi_dot
    _rot_rpy,
    centroidal_map,
    centroidal_map_dot,
    centroidal_map_euler,
    centroidal_pose_eq30,
    centroidal_pose_riemann,
    euler_coordinates,
    f_j2m,
)
from gaitnet_mpc.robots import RobotModel, load_robot


def _random_state(robot: RobotModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Random MuJoCo (qpos, qvel) with joints inside their limits."""
    m = robot.mj_model
    qpos = np.zeros(m.nq)
    if robot.spec.planar:
        qpos[:3] = rng.uniform(-1.0, 1.0, 3)
    else:
        qpos[:3] = rng.uniform(-1.0, 1.0, 3)
        quat = rng.normal(size=4)
        qpos[3:7] = quat / np.linalg.norm(quat)
    qpos[robot.joint_qpos_adr] = rng.uniform(robot.joint_lower_rad, robot.joint_upper_rad)
    return qpos, rng.normal(0.0, 2.0, m.nv)


# ---------------------------------------------------------------- eqs. 6 and 11
def test_f_j2m_matches_mujoco_subtree_momentum(robot: RobotModel) -> None:
    m = robot.mj_model
    data = mujoco.MjData(m)
    pdata = robot.pin_model.createData()
    rng = np.random.default_rng(0)
    for _ in range(20):
        qpos, qvel = _random_state(robot, rng)
        data.qpos[:], data.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, data)
        mujoco.mj_subtreeVel(m, data)
        h_mj = np.concatenate(
            [m.body_subtreemass[1] * data.subtree_linvel[1], data.subtree_angmom[1]]
        )
        q, v = robot.mj_to_pin(qpos, qvel)
        h = f_j2m(robot, pdata, q, v)
        np.testing.assert_allclose(h, h_mj, rtol=0, atol=1e-8)
        np.testing.assert_allclose(centroidal_map(robot, pdata, q) @ v, h, rtol=0, atol=1e-10)


def test_centroidal_map_dot_is_the_matrix_derivative(robot: RobotModel) -> None:
    """dA_G = d/dt A_G(q (+) t v), checked against a plain central difference."""
    model = robot.pin_model
    data = model.createData()
    rng = np.random.default_rng(1)
    eps = 1e-6
    for _ in range(10):
        q, v = robot.mj_to_pin(*_random_state(robot, rng))
        d_a = centroidal_map_dot(model, data, q, v)
        a_plus = centroidal_map(model, data, pin.integrate(model, q, v * eps))
        a_minus = centroidal_map(model, data, pin.integrate(model, q, -v * eps))
        np.testing.assert_allclose(d_a, (a_plus - a_minus) / (2 * eps), rtol=0, atol=1e-5)


def test_pinocchio_time_variation_only_valid_times_v() -> None:
    """Pinocchio's dAg satisfies dAg v = dA_G v (free flyer), which is all it promises."""
    robot = load_robot("humanoid3d")
    model = robot.pin_model
    data = model.createData()
    rng = np.random.default_rng(2)
    for _ in range(5):
        q, v = robot.mj_to_pin(*_random_state(robot, rng))
        d_a_pin = centroidal_map_dot(model, data, q, v, method="pinocchio")
        d_a = centroidal_map_dot(model, data, q, v)
        np.testing.assert_allclose(d_a_pin @ v, d_a @ v, rtol=0, atol=1e-7)
    with pytest.raises(ValueError, match="unknown method"):
        centroidal_map_dot(model, data, q, v, method="magic")  # type: ignore[arg-type]


# ---------------------------------------------------------------- Euler coordinates
def _xi_rate(model: pin.Model, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``xi_dot`` with ``v = T(xi) xi_dot``: ``[R v_lin, J_rpy^-1 omega, qdot_j]``."""
    if not _has_free_flyer(model):
        return v.copy()
    rot, rpy = _rot_rpy(q[None, 3:7])
    t6 = _root_maps(rot, rpy, None)[0][0]
    return np.concatenate([np.linalg.solve(t6, v[:6]), v[6:]])


def test_euler_coordinates_and_map(robot: RobotModel) -> None:
    """xi_dot (from v = T(xi) xi_dot) is the rate of xi along q (+) t v; A_xi xi_dot = h;
    dA_xi = d/dt A_xi."""
    model = robot.pin_model
    data = model.createData()
    rng = np.random.default_rng(3)
    eps = 1e-6
    for _ in range(10):
        q, v = robot.mj_to_pin(*_random_state(robot, rng))
        q_plus, q_minus = pin.integrate(model, q, v * eps), pin.integrate(model, q, -v * eps)
        xi_dot = _xi_rate(model, q, v)
        xi_fd = (euler_coordinates(model, q_plus) - euler_coordinates(model, q_minus)) / (2 * eps)
        np.testing.assert_allclose(xi_dot, xi_fd, rtol=0, atol=1e-6)
        h = f_j2m(model, data, q, v)
        np.testing.assert_allclose(
            centroidal_map_euler(model, data, q) @ xi_dot, h, rtol=0, atol=1e-10
        )
        d_a_fd = (
            centroidal_map_euler(model, data, q_plus) - centroidal_map_euler(model, data, q_minus)
        ) / (2 * eps)
        d_a = _euler_maps(model, data, q[None], v[None])[1][0]
        np.testing.assert_allclose(d_a, d_a_fd, rtol=0, atol=1e-5)


# ------------------------------------------------------------------ eq. 30
def _smooth_trajectory(
    robot: RobotModel, dt_s: float, duration_s: float = 0.5
) -> tuple[np.ndarray, np.ndarray]:
    """Sinusoidal joints, base translation and rotation (yaw crosses +-pi); Pinocchio q, v."""
    model = robot.pin_model
    t = np.arange(0.0, duration_s + 1e-12, dt_s)[:, None]  # (K, 1)
    rng = np.random.default_rng(4)
    nj = robot.n_joints
    amp, omega, phase = rng.uniform(0.1, 0.4, nj), rng.uniform(3, 12, nj), rng.uniform(0, 6, nj)
    qj = robot.nominal_joint_pos() + amp * np.sin(omega * t + phase)
    qj_dot = amp * omega * np.cos(omega * t + phase)
    t = t[:, 0]
    if robot.spec.planar:
        root = np.column_stack([0.3 * t, 0.6 + 0.02 * np.sin(8 * t), 0.1 * np.sin(5 * t)])
        root_dot = np.column_stack([0.3 + 0 * t, 0.16 * np.cos(8 * t), 0.5 * np.cos(5 * t)])
        return np.hstack([root, qj]), np.hstack([root_dot, qj_dot])
    p = np.column_stack([0.4 * t, 0.05 * np.sin(6 * t), 0.6 + 0.02 * np.sin(8 * t)])
    p_dot = np.column_stack([0.4 + 0 * t, 0.3 * np.cos(6 * t), 0.16 * np.cos(8 * t)])
    rpy = np.column_stack([0.1 * np.sin(5 * t), 0.15 * np.sin(4 * t + 1), 2.5 + 1.5 * t])
    rpy_dot = np.column_stack([0.5 * np.cos(5 * t), 0.6 * np.cos(4 * t + 1), 1.5 + 0 * t])
    q = np.zeros((t.size, model.nq))
    v = np.zeros((t.size, model.nv))
    for k in range(t.size):
        rot = pin.rpy.rpyToMatrix(rpy[k])
        q[k, :3], q[k, 3:7], q[k, 7:] = p[k], pin.Quaternion(rot).coeffs(), qj[k]
        v[k, :3] = rot.T @ p_dot[k]
        v[k, 3:6] = pin.rpy.computeRpyJacobian(rpy[k], pin.LOCAL) @ rpy_dot[k]
        v[k, 6:] = qj_dot[k]
    return q, v


def _eq30_error(
    robot: RobotModel, dt_s: float, subtract_initial: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(H_eq30 - H_eq30[0]) - Riemann(h), the first-order bound, the predicted leading term."""
    model = robot.pin_model
    data = model.createData()
    q, v = _smooth_trajectory(robot, dt_s)
    h_pose = centroidal_pose_eq30(model, q, v, dt_s, data, subtract_initial=subtract_initial)
    h = np.array([f_j2m(model, data, q[k], v[k]) for k in range(q.shape[0])])  # (K, 6)
    err = (h_pose - h_pose[0]) - centroidal_pose_riemann(h, dt_s)
    _, d_a, xi = _euler_maps(model, data, q, v)  # (K, 6, nv), xi (K, nv) unwrapped
    if subtract_initial:
        xi = xi - xi[0]
    g = np.einsum("kij,kj->ki", d_a, xi)  # dA_xi xi
    # Left-Riemann error of int f is <= dt/2 * total variation of f (first order).
    bound = dt_s / 2 * (np.abs(np.diff(h, axis=0)).sum(0) + np.abs(np.diff(g, axis=0)).sum(0))
    # Both sums are left Riemann sums of f = d/dt(A_xi xi) = h + g, so the leading error
    # telescopes to dt/2 (f_k - f_0).
    f = h + g
    leading = dt_s / 2 * (f - f[0])
    return err, bound, leading


@pytest.mark.parametrize("subtract_initial", [False, True])
def test_eq30_matches_riemann_momentum_to_first_order(
    robot: RobotModel, subtract_initial: bool
) -> None:
    """Eq. 30 vs the Riemann sum of h (dt = 1 ms over 0.5 s), up to H_0.

    Tolerances: the raw difference is a first-order (O(dt)) left-Riemann error, bounded by
    dt/2 times the total variation of h and of dA_xi xi (~1e-3 here, against |H| ~ 0.1-3);
    after removing its predicted leading term dt/2 (f_k - f_0) the remainder is O(dt^2)
    (~2e-6 here; tolerance 1e-5); halving dt halves the raw error.
    """
    dt_s = 1e-3
    err, bound, leading = _eq30_error(robot, dt_s, subtract_initial)
    assert np.all(np.abs(err).max(axis=0) <= 1.05 * bound + 1e-12)
    np.testing.assert_allclose(err, leading, rtol=0, atol=1e-5)
    err_coarse, _, _ = _eq30_error(robot, 2 * dt_s, subtract_initial)
    ratio = np.abs(err_coarse).max() / np.abs(err).max()
    assert 1.8 < ratio < 2.2


def test_eq30_variable_dt_and_riemann_h0(robot: RobotModel) -> None:
    model = robot.pin_model
    q, v = _smooth_trajectory(robot, 0.03, duration_s=0.3)  # 11 stages
    k = q.shape[0]
    h_scalar = centroidal_pose_eq30(model, q, v, 0.03)
    h_array = centroidal_pose_eq30(model, q, v, np.full(k, 0.03))
    np.testing.assert_array_equal(h_scalar, h_array)
    assert h_scalar.shape == (k, 6)
    h_rel = centroidal_pose_eq30(model, q, v, 0.03, subtract_initial=True)
    np.testing.assert_allclose(h_rel[0], 0.0, atol=1e-15)

    h = np.ones((4, 6))
    dt = np.array([0.1, 0.2, 0.3, 0.4])
    out = centroidal_pose_riemann(h, dt, np.arange(6.0))
    np.testing.assert_allclose(out[:, 0], [0.0, 0.1, 0.3, 0.6])
    np.testing.assert_allclose(out[0], np.arange(6.0))
