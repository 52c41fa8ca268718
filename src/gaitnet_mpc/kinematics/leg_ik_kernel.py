"""Compiled row loops of the analytic leg IK (Appendix B, eqs. 31-40).

The closed form and its derivation are in :mod:`~gaitnet_mpc.kinematics.leg_ik`, whose
public functions check and batch their inputs and call these kernels. Each kernel takes
contiguous float64 arrays with one target per row and writes the clipped joint angles and
the reachability into output arrays, one row at a time in scalar arithmetic: a leg IK of a
few rows is then a few microseconds instead of the ~40 NumPy calls of the vectorised form
(numba, compiled on first use, cached by :mod:`gaitnet_mpc.jit`).
"""

from __future__ import annotations

import math

import numpy as np

from gaitnet_mpc.jit import njit_cached


@njit_cached(inline="always")
def _clip(x: float, lo: float, hi: float) -> float:
    return min(max(x, lo), hi)


@njit_cached(inline="always")
def _wrap(a: float) -> float:
    """``a`` wrapped to ``(-pi, pi]`` as ``atan2(sin a, cos a)``."""
    return math.atan2(math.sin(a), math.cos(a))


@njit_cached(inline="always")
def _two_link(
    bx: float, bz: float, thigh: float, shank: float, knee_lo: float, knee_hi: float
) -> tuple[float, float, float, float]:
    """Planar hip-pitch/knee IK (eqs. 34-35, 40) for ``b = -a``, ``a`` the end point in the
    hip x-z plane: ``(q_hip_raw, q_knee_raw, q_knee, cos_knee)``, the knee clipped to its
    limits and the hip computed from the clipped knee (nearest feasible solution);
    ``|cos_knee| > 1`` means out of reach. The hip is one ``atan2`` of the rotated vector,
    so it lies in ``(-pi, pi]``."""
    inv = 1.0 / (2.0 * thigh * shank)
    cos_knee = (bx * bx + bz * bz) * inv - (thigh * thigh + shank * shank) * inv
    q_knee_raw = math.acos(_clip(cos_knee, -1.0, 1.0))
    q_knee = _clip(q_knee_raw, knee_lo, knee_hi)
    u = shank * math.sin(q_knee)  # l2 sin q_k
    w = thigh + shank * math.cos(q_knee)  # l1 + l2 cos q_k
    q_hip_raw = math.atan2(bx * w - bz * u, bz * w + bx * u)
    return q_hip_raw, q_knee_raw, q_knee, cos_knee


@njit_cached()
def leg_ik_rows(
    p_f: np.ndarray,
    p_b: np.ndarray,
    rot: np.ndarray,
    yaw: np.ndarray,
    has_yaw: bool,
    p_yaw: np.ndarray,
    p_roll: np.ndarray,
    p_pitch: np.ndarray,
    thigh: float,
    shank: float,
    c_foot: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    tol: float,
    q: np.ndarray,
    reachable: np.ndarray,
) -> None:
    """5-DoF leg IK of every row (steps 1-7 of :mod:`.leg_ik`'s docstring).

    ``p_f``, ``p_b`` (N, 3) foothold and trunk positions, ``rot`` (N, 3, 3) world<-trunk,
    ``yaw`` (N,) desired foot headings (read only with ``has_yaw``; else ``q0 = 0``), the
    leg geometry, and outputs ``q`` (N, 5) and ``reachable`` (N,).
    """
    for i in range(p_f.shape[0]):
        # eqs. 36-37: target in the trunk frame relative to the yaw joint; world up there
        dx, dy, dz = p_f[i, 0] - p_b[i, 0], p_f[i, 1] - p_b[i, 1], p_f[i, 2] - p_b[i, 2]
        tx = dx * rot[i, 0, 0] + dy * rot[i, 1, 0] + dz * rot[i, 2, 0] - p_yaw[0]
        ty = dx * rot[i, 0, 1] + dy * rot[i, 1, 1] + dz * rot[i, 2, 1] - p_yaw[1]
        tz = dx * rot[i, 0, 2] + dy * rot[i, 1, 2] + dz * rot[i, 2, 2] - p_yaw[2]
        ux, uy, uz = rot[i, 2, 0], rot[i, 2, 1], rot[i, 2, 2]
        # eq. 31: hip yaw from the desired foot heading
        if has_yaw:
            q0_raw = _wrap(yaw[i] - math.atan2(rot[i, 1, 0], rot[i, 0, 0]))
            q0 = _clip(q0_raw, lo[0], hi[0])
            c0, s0 = math.cos(q0), math.sin(q0)
            x_yaw, y_yaw = c0 * tx + s0 * ty, c0 * ty - s0 * tx
            gx, gy = c0 * ux + s0 * uy, c0 * uy - s0 * ux
        else:
            q0_raw = 0.0
            x_yaw, y_yaw, gx, gy = tx, ty, ux, uy
        z_yaw, gz = tz, uz
        # eqs. 33, 36, 38: hip roll, one atan2
        r1y, r1z = y_yaw - p_roll[1], z_yaw - p_roll[2]
        w = p_pitch[1]
        excess = r1y * r1y + r1z * r1z - w * w  # rho^2 - w^2, < 0: unreachable
        root = math.sqrt(max(excess, 0.0))
        q1_raw = math.atan2(r1z * w + r1y * root, r1y * w - r1z * root)
        q1 = _clip(q1_raw, lo[1], hi[1])
        c1, s1 = math.cos(q1), math.sin(q1)
        # eq. 32 generalised: the foot axis orthogonal to world up
        theta = math.atan2(gx, gz * c1 - gy * s1)
        ct, st = math.cos(theta), math.sin(theta)
        # hip-pitch x-z plane, foot offset removed; b = -ankle
        cx, cz = c_foot[0], c_foot[2]
        bx = (p_pitch[0] + p_roll[0] - x_yaw) + (cx * ct + cz * st)
        bz = (s1 * r1y - c1 * r1z + p_pitch[2]) + (cz * ct - cx * st)
        # eqs. 34, 35, 40: hip pitch and knee; eq. 32: the ankle levels the foot
        q2_raw, q3_raw, q3, cos_knee = _two_link(bx, bz, thigh, shank, lo[3], hi[3])
        q2 = _clip(q2_raw, lo[2], hi[2])
        q4_raw = _wrap(theta - q2 - q3)
        worst = 0.0
        for j, raw in enumerate((q0_raw, q1_raw, q2_raw, q3_raw, q4_raw)):
            q[i, j] = _clip(raw, lo[j], hi[j])
            worst = max(worst, abs(raw - q[i, j]))
        reachable[i] = worst <= tol and abs(cos_knee) <= 1.0 + tol and excess >= 0.0


@njit_cached()
def planar_leg_ik_rows(
    ax: np.ndarray,
    az: np.ndarray,
    thigh: float,
    shank: float,
    lo: np.ndarray,
    hi: np.ndarray,
    tol: float,
    q: np.ndarray,
    reachable: np.ndarray,
) -> None:
    """Planar biped leg IK of every row: ``ax``, ``az`` (N,) the foot point relative to
    the hip in the trunk's x-z plane; outputs ``q`` (N, 2) ``[hip_pitch, knee]`` and
    ``reachable`` (N,)."""
    for i in range(ax.shape[0]):
        q_hip_raw, q_knee_raw, _, cos_knee = _two_link(-ax[i], -az[i], thigh, shank, lo[1], hi[1])
        q[i, 0] = _clip(q_hip_raw, lo[0], hi[0])
        q[i, 1] = _clip(q_knee_raw, lo[1], hi[1])
        worst = max(abs(q_hip_raw - q[i, 0]), abs(q_knee_raw - q[i, 1]))
        reachable[i] = worst <= tol and abs(cos_knee) <= 1.0 + tol
