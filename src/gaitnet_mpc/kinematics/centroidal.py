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
_FD_STEP = 1e-5  # tangent-space step of the dA_G central difference [m or rad]


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


def _quat_to_rot_tensor() -> np.ndarray:
    """Constant (16, 9) map from ``vec(q q^T)`` (q = xyzw) to ``vec(R) |q|^2``.

    ``R |q|^2 = (w^2 - v.v) I + 2 v v^T + 2 w [v]x`` with ``v = (x, y, z)``.
    """
    m = np.zeros((4, 4, 3, 3))
    for i in range(3):
        m[3, 3, i, i] = 1.0
        for j in range(3):
            m[j, j, i, i] -= 1.0
            m[i, j, i, j] += 2.0
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):  # [v]x: (i, j) entry -v_k, (j, i) +v_k
        m[3, k, j, i] += 2.0
        m[3, k, i, j] -= 2.0
    return m.reshape(16, 9)


def _skew_tensor() -> np.ndarray:
    """Constant (3, 9) map from ``w`` to ``vec([w]x)``."""
    s = np.zeros((3, 3, 3))
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        s[k, i, j], s[k, j, i] = -1.0, 1.0
    return s.reshape(3, 9)


_QUAT_TO_ROT = _quat_to_rot_tensor()  # read-only constants
_QUAT_TO_ROT.flags.writeable = False
_SKEW = _skew_tensor()
_SKEW.flags.writeable = False


def _rot_rpy(quat_xyzw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation matrices (K, 3, 3) and ZYX angles rpy (K, 3) of quaternions (K, 4) xyzw."""
    outer = (quat_xyzw[:, :, None] * quat_xyzw[:, None, :]).reshape(-1, 16)  # (K, 16)
    rot = (outer @ _QUAT_TO_ROT).reshape(-1, 3, 3)
    rot /= np.einsum("ka,ka->k", quat_xyzw, quat_xyzw)[:, None, None]  # normalise
    rpy = np.stack(
        [
            np.arctan2(rot[:, 2, 1], rot[:, 2, 2]),
            np.arctan2(-rot[:, 2, 0], np.hypot(rot[:, 0, 0], rot[:, 1, 0])),
            np.arctan2(rot[:, 1, 0], rot[:, 0, 0]),
        ],
        axis=1,
    )
    return rot, rpy


def _root_maps(
    rot: np.ndarray, rpy: np.ndarray, v: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray | None]:
    """Free-flyer blocks of ``T`` and ``dT/dt`` (module docstring), batched over K.

    Args:
        rot: (K, 3, 3) base rotations; rpy: (K, 3) their ZYX angles; v: (K, nv) or None.

    Returns:
        ``T6`` (K, 6, 6) = ``blkdiag(R^T, J_rpy)``, and if ``v`` is given ``dT6`` (K, 6, 6) =
        ``blkdiag(-[omega]x R^T, dJ_rpy)``.
    """
    k_stages = rpy.shape[0]
    sr, cr = np.sin(rpy[:, 0]), np.cos(rpy[:, 0])
    sp, cp = np.sin(rpy[:, 1]), np.cos(rpy[:, 1])
    rot_t = rot.transpose(0, 2, 1)
    t6 = np.zeros((k_stages, 6, 6))
    t6[:, :3, :3] = rot_t
    jac = t6[:, 3:, 3:]  # local RPY Jacobian, omega_body = J rpy_dot
    jac[:, 0, 0] = 1.0
    jac[:, 0, 2] = -sp
    jac[:, 1, 1] = cr
    jac[:, 1, 2] = sr * cp
    jac[:, 2, 1] = -sr
    jac[:, 2, 2] = cr * cp
    if v is None:
        return t6, None
    wx, wy, wz = v[:, 3], v[:, 4], v[:, 5]
    a = sr * wy + cr * wz  # = cos(pitch) yaw_dot
    dr = wx + sp / cp * a  # roll rate
    dp = cr * wy - sr * wz  # pitch rate
    dt6 = np.zeros((k_stages, 6, 6))
    skew = (v[:, 3:6] @ _SKEW).reshape(-1, 3, 3)
    dt6[:, :3, :3] = -skew @ rot_t  # d/dt R^T = -[omega_body]x R^T
    djac = dt6[:, 3:, 3:]
    djac[:, 0, 2] = -cp * dp
    djac[:, 1, 1] = -sr * dr
    djac[:, 1, 2] = cr * cp * dr - sr * sp * dp
    djac[:, 2, 1] = -cr * dr
    djac[:, 2, 2] = -sr * cp * dr - cr * sp * dp
    return t6, dt6


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
    """Central difference of ``A_G`` along ``q (+) t v`` (step ``_FD_STEP`` in q)."""
    eps = _FD_STEP / max(float(np.sqrt(v @ v)), 1.0)
    a_plus = pin.computeCentroidalMap(m, d, pin.integrate(m, q, v * eps))
    a_minus = pin.computeCentroidalMap(m, d, pin.integrate(m, q, v * -eps))
    return (a_plus - a_minus) * (0.5 / eps)


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
        ``d/dt A_G(q (+) t v)|_{t=0}`` (``(+)`` = ``pin.integrate``) by a central
        difference whose configuration step is 1e-5 (``eps = 1e-5 / max(1, |v|)``);
        truncation plus round-off ~3e-9 absolute on entries up to ~30 (humanoid3d);
        2 ``computeCentroidalMap`` calls.
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


def _euler_maps(
    m: pin.Model, d: pin.Data, q: np.ndarray, v: np.ndarray, with_dot: bool = True
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """``A_xi`` (K, 6, nv), ``dA_xi`` (K, 6, nv) (or None) and ``xi`` (K, nv) along a
    trajectory ``q`` (K, nq), ``v`` (K, nv); roll and yaw unwrapped along K."""
    k_stages = q.shape[0]
    a_xi = np.empty((k_stages, 6, m.nv))
    da_xi = np.empty((k_stages, 6, m.nv)) if with_dot else None
    for k in range(k_stages):
        a_xi[k] = pin.computeCentroidalMap(m, d, q[k])
        if da_xi is not None:
            da_xi[k] = _centroidal_map_dot_fd(m, d, q[k], v[k])
    if not _has_free_flyer(m):
        return a_xi, da_xi, q.copy()
    rot, rpy = _rot_rpy(q[:, 3:7])
    if k_stages > 1:  # a single sample is its own unwrapping (np.unwrap costs ~40 us)
        rpy = np.unwrap(rpy, axis=0)
    t6, dt6 = _root_maps(rot, rpy, v if with_dot else None)
    a_root = a_xi[:, :, :6].copy()  # (K, 6, 6), Pinocchio's local root columns
    if da_xi is not None and dt6 is not None:  # dA_xi = dA_G T + A_G dT
        da_xi[:, :, :6] = da_xi[:, :, :6] @ t6 + a_root @ dt6
    a_xi[:, :, :6] = a_root @ t6  # A_xi = A_G T
    xi = np.concatenate([q[:, 0:3], rpy, q[:, 7:]], axis=1)
    return a_xi, da_xi, xi


def centroidal_map_euler(
    model: pin.Model | RobotModel, data: pin.Data | None, q: np.ndarray
) -> np.ndarray:
    """``A_xi = A_G T`` (6, nv): eq. 6's map acting on Euler-coordinate rates ``xi_dot``."""
    return euler_map_and_coordinates(model, data, q)[0]


def euler_map_and_coordinates(
    model: pin.Model | RobotModel, data: pin.Data | None, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`centroidal_map_euler` (6, nv) and :func:`euler_coordinates` (nv,) of one
    configuration ``q`` (nq,), from one pass."""
    m = _pin_model(model)
    q = np.asarray(q, dtype=float).reshape(1, m.nq)
    a_xi, _, xi = _euler_maps(m, _data(m, data), q, np.zeros((1, m.nv)), with_dot=False)
    return a_xi[0], xi[0]


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
    q_traj = np.asarray(q_traj, dtype=float).reshape(-1, m.nq)
    v_traj = np.asarray(v_traj, dtype=float).reshape(-1, m.nv)
    k_stages = q_traj.shape[0]
    dt = _dt_array(dt_s, k_stages)
    a_xi, da_xi, xi = _euler_maps(m, _data(m, data), q_traj, v_traj)  # (K,6,nv) x2, (K,nv)
    assert da_xi is not None
    if subtract_initial:
        xi = xi - xi[0]
    h_pose = np.einsum("kij,kj->ki", a_xi, xi)  # A_xi(xi_k) xi_k, (K, 6)
    increments = np.einsum("kij,kj->ki", da_xi[:-1], xi[:-1]) * dt[:-1, None]  # (K-1, 6)
    h_pose[1:] -= np.cumsum(increments, axis=0)
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
