"""Nonlinear centroidal dynamics of the kino-dynamic MPC (paper eq. 10, with eq. 20).

State ``x = [H (6); l_G (3); k_G (3)]``: the centroidal pose ``H`` and the centroidal
momentum ``h = [l_G; k_G]`` (linear, angular about the CoM). Per stage ``k`` of length
``dt_k``, with contact forces ``f_i``, moments ``tau_i`` at the foot centres ``p_f,i`` and
the CoM ``p_c`` (explicit Euler, ``g = (0, 0, -g)``)::

    H_{k+1} = H_k + h_k dt_k
    l_{k+1} = l_k + (sum_i f_i + m g) dt_k                               (eq. 10)
    k_{k+1} = k_k + sum_i ((p_f,i - p_c,k) x f_i + tau_i) dt_k           (eq. 10)
    p_c,k+1 = p_c,k + l_k / m dt_k                                       (eq. 20)

The CMPC sub-problem (:mod:`gaitnet_mpc.mpc.implicit_kd`) linearises these about an
iterate; this is the exact model its residual is measured against.
"""

from __future__ import annotations

import numpy as np

from gaitnet_mpc.geometry import GRAVITY_MPS2

NX = 12  # [H (6); l_G (3); k_G (3)]
N_FEET = 2


def nonlinear_step(
    x_k: np.ndarray,
    f: np.ndarray,
    tau: np.ndarray,
    p_foot: np.ndarray,
    p_com: np.ndarray,
    dt: float,
    mass_kg: float,
    gravity_mps2: float = GRAVITY_MPS2,
) -> np.ndarray:
    """Exact discrete centroidal dynamics, eq. 10 with gravity, and the pose update.

    Args:
        x_k: (12,) state ``[H (6); l_G (3); k_G (3)]``.
        f: (2, 3) contact forces [N]; tau: (2, 3) contact moments [N m].
        p_foot: (2, 3) foot positions [m]; p_com: (3,) CoM position [m].
        dt: stage length [s].

    Returns:
        (12,) ``x_{k+1}``: ``H + h dt``, ``l + (sum f + m g) dt``,
        ``k + sum ((p_f - p_c) x f + tau) dt``.
    """
    x_k = np.asarray(x_k, dtype=float)
    f = np.asarray(f, dtype=float).reshape(N_FEET, 3)
    tau = np.asarray(tau, dtype=float).reshape(N_FEET, 3)
    arm = np.asarray(p_foot, dtype=float).reshape(N_FEET, 3) - np.asarray(p_com, dtype=float)
    out = x_k.copy()
    out[0:6] += x_k[6:12] * dt
    out[6:9] += (f.sum(axis=0) + np.array([0.0, 0.0, -mass_kg * gravity_mps2])) * dt
    out[9:12] += (np.cross(arm, f).sum(axis=0) + tau.sum(axis=0)) * dt
    return out


def nonlinear_rollout(
    x0: np.ndarray,
    f: np.ndarray,
    tau: np.ndarray,
    p_foot: np.ndarray,
    p_com0: np.ndarray,
    dts_s: np.ndarray,
    mass_kg: float,
    gravity_mps2: float = GRAVITY_MPS2,
) -> tuple[np.ndarray, np.ndarray]:
    """Roll eq. 10 and eq. 20 forward: states (h+1, 12) and CoM positions (h+1, 3).

    ``f, tau, p_foot`` are (h, 2, 3); the CoM follows ``p_c,k+1 = p_c,k + l_k / m dt_k``.
    """
    h = len(dts_s)
    xs = np.zeros((h + 1, NX))
    pc = np.zeros((h + 1, 3))
    xs[0] = x0
    pc[0] = p_com0
    for k in range(h):
        dt = float(dts_s[k])
        xs[k + 1] = nonlinear_step(xs[k], f[k], tau[k], p_foot[k], pc[k], dt, mass_kg, gravity_mps2)
        pc[k + 1] = pc[k] + xs[k, 6:9] / mass_kg * dt
    return xs, pc


def skew_batch(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices (..., 3, 3) of vectors (..., 3), entry for entry
    :func:`~gaitnet_mpc.geometry.skew` (the ``r x f`` terms of eq. 10, linearised)."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


__all__ = ["NX", "N_FEET", "nonlinear_rollout", "nonlinear_step", "skew_batch"]
