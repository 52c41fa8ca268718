"""Centroidal momentum map and the centroidal pose (paper eqs. 6, 11, 12 and Appendix A).

Conventions
-----------

* Spatial momentum ``h = [l (3); k (3)]`` (linear [kg m/s]; angular [kg m^2/s]) about the
  centre of mass, world-aligned axes (Pinocchio's ``data.hg``).
* ``A_G(q)`` (eq. 6) maps Pinocchio's velocity ``v`` to ``h``: ``h = A_G(q) v``. For the
  humanoid, ``v = [v_base_body (3), omega_base_body (3), joint rates]`` (local free-flyer
  frame), so ``v`` is **not** the time derivative of any coordinate vector.
* ``dA_G(q, v)`` is the true matrix derivative ``d/dt A_G(q (+) t v)`` (finite difference,
  see :func:`centroidal_map_dot`): Pinocchio's ``computeCentroidalMapTimeVariation`` only
  guarantees the product ``dAg v`` and is not the matrix derivative that eqs. 12 / 30
  multiply by a coordinate vector.

Coordinates for eq. 30 / eq. 12
-------------------------------

Appendix A integrates ``h = A_G qdot`` by parts, which requires ``qdot = d/dt q`` for some
coordinate vector ``q``. We use the *Euler coordinates* (``nv`` entries)::

    xi = [p_base_world (3), rpy (3), joints (n_j)],  R_base = Rz(yaw) Ry(pitch) Rx(roll)

(``rpy = (roll, pitch, yaw)``, Pinocchio's ``pin.rpy`` convention), whose rate is related
to Pinocchio's ``v`` by ``v = T(xi) xi_dot`` with ``T = blkdiag(R^T, J_rpy(rpy), I)``,
``J_rpy`` the local-frame RPY Jacobian (``omega_body = J_rpy rpy_dot``). The map in these
coordinates and its time derivative are::

    A_xi = A_G T,     dA_xi = dA_G T + A_G dT,     dT = blkdiag(-[omega_body]x R^T, dJ_rpy, 0)

so that ``h = A_xi xi_dot`` and ``d/dt (A_xi xi) - dA_xi xi = A_xi xi_dot = h`` exactly in
continuous time, which is the identity behind eq. 29. The planar biped's root
(slide x, slide z, hinge pitch) already has ``v = qdot``, so ``xi = q`` and ``T = I``.
Euler coordinates are singular at ``pitch = +-pi/2`` (irrelevant for walking); roll and
yaw are unwrapped along a trajectory so that ``xi`` is continuous.

Accuracy of eq. 30: both eq. 30 and the Riemann sum of ``h`` are left Riemann sums, so
with ``f = d/dt (A_xi xi) = h + dA_xi xi`` their difference is
``(dt / 2) (f(t_k) - f(t_0)) + O(dt^2)`` (first order in ``dt``). The columns of ``A_xi``
for the base position are constant (``[m I; 0]``), so the world position of the robot does
not affect the error; a constant offset in the other coordinates does, which the option
``subtract_initial`` (use ``xi - xi_0``, ``H_0 = 0``) removes.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pinocchio as pin

from gaitnet_mpc.robots.model import RobotModel

_FREE_FLYER = "JointModelFreeFlyer"
_FD_STEP = 1e-3  # tangent-space step of the dA_G finite difference [m or rad]


# --------------------------------------------------------------------- helpers
def _pin_model(model: pin.Model | RobotModel) -> pin.Model:
    return model.pin_model if isinstance(model, RobotModel) else model


def _data(model: pin.Model, data: pin.Data | None) -> pin.Data:
    return model.createData() if data is None else data


def _has_free_flyer(model: pin.Model) -> bool:
    if model.njoints > 1 and model.joints[1].shortname() == _FREE_FLYER:
        return True
    if model.nq != model.nv:
        raise ValueError("only free-flyer or Euclidean (nq == nv) roots are supported")
    return False


def _rot_rpy(quat_xyzw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation matrices (K, 3, 3) and ZYX angles rpy (K, 3) of quaternions (K, 4) xyzw."""
    quat = quat_xyzw / np.linalg.norm(quat_xyzw, axis=1, keepdims=True)
    x, y, z, w = quat.T
    rot = np.empty((quat.shape[0], 3, 3))
    rot[:, 0, 0] = 1 - 2 * (y * y + z * z)
    rot[:, 0, 1] = 2 * (x * y - z * w)
    rot[:, 0, 2] = 2 * (x * z + y * w)
    rot[:, 1, 0] = 2 * (x * y + z * w)
    rot[:, 1, 1] = 1 - 2 * (x * x + z * z)
    rot[:, 1, 2] = 2 * (y * z - x * w)
    rot[:, 2, 0] = 2 * (x * z - y * w)
    rot[:, 2, 1] = 2 * (y * z + x * w)
    rot[:, 2, 2] = 1 - 2 * (x * x + y * y)
    rpy = np.stack(
        [
            np.arctan2(rot[:, 2, 1], rot[:, 2, 2]),
            np.arctan2(-rot[:, 2, 0], np.hypot(rot[:, 0, 0], rot[:, 1, 0])),
            np.arctan2(rot[:, 1, 0], rot[:, 0, 0]),
        ],
        axis=1,
    )
    return rot, rpy


def _rpy_jacobian(
    rpy: np.ndarray, omega_body: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Local RPY Jacobian ``J`` (K, 3, 3) with ``omega_body = J rpy_dot``; if ``omega_body``
    (K, 3) is given also ``rpy_dot`` (K, 3) and ``dJ/dt`` (K, 3, 3)."""
    sr, cr = np.sin(rpy[:, 0]), np.cos(rpy[:, 0])
    sp, cp = np.sin(rpy[:, 1]), np.cos(rpy[:, 1])
    jac = np.zeros((rpy.shape[0], 3, 3))
    jac[:, 0, 0] = 1.0
    jac[:, 0, 2] = -sp
    jac[:, 1, 1] = cr
    jac[:, 1, 2] = sr * cp
    jac[:, 2, 1] = -sr
    jac[:, 2, 2] = cr * cp
    if omega_body is None:
        return jac, None, None
    rpy_dot = np.linalg.solve(jac, omega_body[:, :, None])[:, :, 0]
    dr, dp = rpy_dot[:, 0], rpy_dot[:, 1]
    djac = np.zeros_like(jac)
    djac[:, 0, 2] = -cp * dp
    djac[:, 1, 1] = -sr * dr
    djac[:, 1, 2] = cr * cp * dr - sr * sp * dp
    djac[:, 2, 1] = -cr * dr
    djac[:, 2, 2] = -sr * cp * dr - cr * sp * dp
    return jac, rpy_dot, djac


def _skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


# --------------------------------------------------------------------- eq. 6 / 11
def centroidal_map(
    model: pin.Model | RobotModel, data: pin.Data | None, q: np.ndarray
) -> np.ndarray:
    """Centroidal momentum matrix ``A_G(q)`` (6, nv) of eq. 6 (``pin.computeCentroidalMap``).

    Rows ``[linear; angular]`` about the CoM in world-aligned axes; columns follow
    Pinocchio's velocity ``v`` (local free-flyer frame for the humanoid).
    """
    m = _pin_model(model)
    return pin.computeCentroidalMap(m, _data(m, data), np.asarray(q, dtype=float))


def _centroidal_map_dot_fd(m: pin.Model, d: pin.Data, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Fourth-order central difference of ``A_G`` along ``q (+) t v``."""
    eps = _FD_STEP / max(float(np.max(np.abs(v))), 1.0)
    a_p1 = pin.computeCentroidalMap(m, d, pin.integrate(m, q, v * eps))
    a_m1 = pin.computeCentroidalMap(m, d, pin.integrate(m, q, v * -eps))
    a_p2 = pin.computeCentroidalMap(m, d, pin.integrate(m, q, v * (2.0 * eps)))
    a_m2 = pin.computeCentroidalMap(m, d, pin.integrate(m, q, v * (-2.0 * eps)))
    return (8.0 * (a_p1 - a_m1) - (a_p2 - a_m2)) / (12.0 * eps)


def centroidal_map_dot(
    model: pin.Model | RobotModel,
    data: pin.Data | None,
    q: np.ndarray,
    v: np.ndarray,
    method: Literal["finite_difference", "pinocchio"] = "finite_difference",
) -> np.ndarray:
    """Time derivative ``dA_G(q, v)`` (6, nv) of eq. 6's ``A_G`` along the velocity ``v``.

    Methods:
        ``"finite_difference"`` (default): the true matrix derivative
        ``d/dt A_G(q (+) t v)|_{t=0}`` (``(+)`` = ``pin.integrate``) by a fourth-order
        central difference with a tangent-space step of 1e-3 / max(1, |v|_inf)
        (truncation and round-off ~1e-10 relative; 4 ``computeCentroidalMap`` calls).
        This is what eqs. 12 and 30 need, because there ``dA_G`` multiplies a coordinate
        vector, not ``v``.
        ``"pinocchio"``: ``pin.computeCentroidalMapTimeVariation``. Pinocchio only
        guarantees ``dh/dt = A_G a + dAg v``; its ``dAg`` is one factorisation of that
        velocity product and differs from the matrix derivative (humanoid3d: entries off
        by O(1-10) in the root and joint columns while ``dAg v`` agrees). For a composite
        root joint (biped2d's slide-slide-hinge) even ``dAg v`` is wrong in Pinocchio 4.1.
        Use it only for ``dAg @ v`` on free-flyer models.
    """
    m = _pin_model(model)
    d = _data(m, data)
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    if method == "pinocchio":
        return pin.computeCentroidalMapTimeVariation(m, d, q, v)
    if method != "finite_difference":
        raise ValueError(f"unknown method {method!r}")
    return _centroidal_map_dot_fd(m, d, q, v)


def f_j2m(
    model: pin.Model | RobotModel, data: pin.Data | None, q: np.ndarray, v: np.ndarray
) -> np.ndarray:
    """Joint-space state to spatial momentum, ``h = A_G(q) v`` (eqs. 6, 11; Alg. 1 ``f_j2m``).

    Returns:
        h (6,) = ``[linear momentum [kg m/s]; angular momentum about the CoM [kg m^2/s]]``,
        world-aligned axes.
    """
    m = _pin_model(model)
    hg = pin.computeCentroidalMomentum(
        m, _data(m, data), np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    )
    return np.concatenate([hg.linear, hg.angular])


# ------------------------------------------------------------ Euler coordinates
def euler_coordinates(model: pin.Model | RobotModel, q: np.ndarray) -> np.ndarray:
    """Euler coordinates ``xi`` = ``[p_base_world, rpy, joints]`` of Pinocchio ``q``.

    Args:
        model: Pinocchio model or robot.
        q: (nq,) or (K, nq) configurations.

    Returns:
        xi (nv,) or (K, nv); for a Euclidean root (biped2d) ``xi = q``. A (K, nq) input is
        treated as a trajectory: roll and yaw are unwrapped along K.
    """
    m = _pin_model(model)
    q = np.asarray(q, dtype=float)
    if not _has_free_flyer(m):
        return q.copy()
    q2 = q.reshape(-1, m.nq)
    _, rpy = _rot_rpy(q2[:, 3:7])
    if q.ndim == 2:
        rpy = np.unwrap(rpy, axis=0)
    xi = np.concatenate([q2[:, 0:3], rpy, q2[:, 7:]], axis=1)
    return xi if q.ndim == 2 else xi[0]


def euler_coordinate_rates(
    model: pin.Model | RobotModel, q: np.ndarray, v: np.ndarray
) -> np.ndarray:
    """``xi_dot`` (nv,) with ``v = T(xi) xi_dot``: ``[R v_lin, J_rpy^-1 omega, qdot_j]``."""
    m = _pin_model(model)
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    if not _has_free_flyer(m):
        return v.copy()
    rot, rpy = _rot_rpy(q[None, 3:7])
    _, rpy_dot, _ = _rpy_jacobian(rpy, v[None, 3:6])
    return np.concatenate([rot[0] @ v[0:3], rpy_dot[0], v[6:]])


def centroidal_map_euler(
    model: pin.Model | RobotModel, data: pin.Data | None, q: np.ndarray
) -> np.ndarray:
    """``A_xi = A_G T`` (6, nv): eq. 6's map acting on Euler-coordinate rates ``xi_dot``."""
    m = _pin_model(model)
    q = np.asarray(q, dtype=float)
    a_g = centroidal_map(m, data, q)
    if not _has_free_flyer(m):
        return a_g
    rot, rpy = _rot_rpy(q[None, 3:7])
    jac, _, _ = _rpy_jacobian(rpy, None)
    a_g[:, 0:3] = a_g[:, 0:3] @ rot[0].T
    a_g[:, 3:6] = a_g[:, 3:6] @ jac[0]
    return a_g


def _euler_map_and_dot(
    m: pin.Model,
    d: pin.Data,
    q: np.ndarray,
    v: np.ndarray,
    blocks: tuple[np.ndarray, np.ndarray, np.ndarray] | None,
) -> tuple[np.ndarray, np.ndarray]:
    """``(A_xi, dA_xi)`` at one state; ``blocks = (R, J_rpy, dJ_rpy)`` or None (no root map)."""
    a_g = pin.computeCentroidalMap(m, d, q)
    d_a_g = _centroidal_map_dot_fd(m, d, q, v)
    if blocks is None:
        return a_g, d_a_g
    rot, jac, djac = blocks
    rot_t = rot.T
    d_rot_t = -_skew(v[3:6]) @ rot_t  # d/dt R^T = -[omega_body]x R^T
    a_lin, a_ang = a_g[:, 0:3], a_g[:, 3:6]
    d_a_g[:, 0:3] = d_a_g[:, 0:3] @ rot_t + a_lin @ d_rot_t
    d_a_g[:, 3:6] = d_a_g[:, 3:6] @ jac + a_ang @ djac
    a_g[:, 0:3] = a_lin @ rot_t
    a_g[:, 3:6] = a_ang @ jac
    return a_g, d_a_g


def centroidal_map_euler_dot(
    model: pin.Model | RobotModel, data: pin.Data | None, q: np.ndarray, v: np.ndarray
) -> np.ndarray:
    """``dA_xi = dA_G T + A_G dT`` (6, nv), the time derivative of :func:`centroidal_map_euler`."""
    m = _pin_model(model)
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    blocks = None
    if _has_free_flyer(m):
        rot, rpy = _rot_rpy(q[None, 3:7])
        jac, _, djac = _rpy_jacobian(rpy, v[None, 3:6])
        assert djac is not None
        blocks = (rot[0], jac[0], djac[0])
    return _euler_map_and_dot(m, _data(m, data), q, v, blocks)[1]


# ------------------------------------------------------------ centroidal pose H
def _dt_array(dt_s: np.ndarray | float, k: int) -> np.ndarray:
    dt = np.asarray(dt_s, dtype=float)
    return np.full(k, float(dt)) if dt.ndim == 0 else dt.reshape(k)


def centroidal_pose_eq30(
    model: pin.Model | RobotModel,
    q_traj: np.ndarray,
    v_traj: np.ndarray,
    dt_s: np.ndarray | float,
    data: pin.Data | None = None,
    subtract_initial: bool = False,
) -> np.ndarray:
    """Centroidal pose ``H`` over a trajectory by integration by parts (eq. 30, eq. 12).

    ``H_k = A_xi(xi_k) xi_k - sum_{i<k} dA_xi(xi_i, xi_dot_i) xi_i dt_i``, with ``xi`` the
    Euler coordinates of the module docstring (so that ``d/dt xi`` is consistent with
    ``A_xi``; Pinocchio's local ``v`` is not a coordinate rate).

    Args:
        model: Pinocchio model or robot.
        q_traj: Pinocchio configurations (K, nq).
        v_traj: Pinocchio velocities (K, nv).
        dt_s: stage durations [s], scalar or (K,); ``dt_s[i]`` is the time from stage ``i``
            to ``i + 1`` (the last entry is unused).
        data: optional Pinocchio data to reuse.
        subtract_initial: use ``xi - xi_0`` instead of ``xi`` (same continuous-time
            primitive up to a constant, smaller ``O(dt)`` error; ``H_0 = 0``).

    Returns:
        H (K, 6): linear part [kg m], angular part [kg m^2]; only differences
        ``H_k - H_0`` are meaningful (eq. 29's ``+ const``). ``H_k - H_0`` approximates
        ``int_{t_0}^{t_k} h dt`` to first order in ``dt`` (module docstring).
    """
    m = _pin_model(model)
    d = _data(m, data)
    q_traj = np.asarray(q_traj, dtype=float).reshape(-1, m.nq)
    v_traj = np.asarray(v_traj, dtype=float).reshape(-1, m.nv)
    k_stages = q_traj.shape[0]
    dt = _dt_array(dt_s, k_stages)
    blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray] | None] = [None] * k_stages
    if _has_free_flyer(m):
        rot, rpy = _rot_rpy(q_traj[:, 3:7])  # (K, 3, 3), (K, 3)
        rpy = np.unwrap(rpy, axis=0)
        jac, _, djac = _rpy_jacobian(rpy, v_traj[:, 3:6])  # (K, 3, 3) each
        assert djac is not None
        blocks = [(rot[k], jac[k], djac[k]) for k in range(k_stages)]
        xi = np.concatenate([q_traj[:, 0:3], rpy, q_traj[:, 7:]], axis=1)  # (K, nv)
    else:
        xi = q_traj.copy()
    if subtract_initial:
        xi = xi - xi[0]
    h_pose = np.empty((k_stages, 6))
    correction = np.zeros(6)  # sum_{i<k} dA_xi_i xi_i dt_i
    for k in range(k_stages):
        a_xi, da_xi = _euler_map_and_dot(m, d, q_traj[k], v_traj[k], blocks[k])
        h_pose[k] = a_xi @ xi[k] - correction
        correction += (da_xi @ xi[k]) * dt[k]
    return h_pose


def centroidal_pose_riemann(
    h_traj: np.ndarray, dt_s: np.ndarray | float, h_pose0: np.ndarray | None = None
) -> np.ndarray:
    """Left Riemann sum of the momentum: ``H_k = H_0 + sum_{i<k} h_i dt_i`` (eqs. 25, 30 LHS).

    Args:
        h_traj: spatial momenta (K, 6), e.g. from :func:`f_j2m` (eq. 11).
        dt_s: stage durations [s], scalar or (K,); ``dt_s[i]`` spans stage ``i`` to ``i + 1``.
        h_pose0: initial centroidal pose ``H_0`` (6,); zeros if None.

    Returns:
        H (K, 6).
    """
    h = np.asarray(h_traj, dtype=float).reshape(-1, 6)
    dt = _dt_array(dt_s, h.shape[0])
    h0 = np.zeros(6) if h_pose0 is None else np.asarray(h_pose0, dtype=float).reshape(6)
    out = np.empty_like(h)
    out[0] = h0
    if h.shape[0] > 1:
        out[1:] = h0 + np.cumsum(h[:-1] * dt[:-1, None], axis=0)
    return out
