"""The trunk placement of ``f_ref`` and ``f_IK`` as one compiled loop (3-D humanoid).

:func:`gaitnet_mpc.kinematics.reference` places the trunk of every stage boundary so that
the CoM lands on its target with both feet at theirs: the leg IK of both legs
(:mod:`.leg_ik_kernel`), the configurations, their CoM (:mod:`.rigid_body_kernel`), then
the fixed-point correction ``p_B <- p_B + (c_target - c(q)) / G`` (``G`` the CoM gain of
the trunk), repeated ``n_corrections`` times, and a last IK at the corrected trunk. Done
from Python this is about fifteen NumPy and kernel calls per iteration, called every
``f_IK`` of a sequential solve; here it is one call. The arithmetic is the same, operation
for operation, so the result is bitwise that of the Python loop
(``tests/test_reference.py`` checks it).
"""

from __future__ import annotations

import numpy as np

from gaitnet_mpc.jit import njit_cached
from gaitnet_mpc.kinematics.leg_ik_kernel import leg_ik_rows
from gaitnet_mpc.kinematics.rigid_body_kernel import com_rows


@njit_cached()
def place_trunk_rows(
    p_base: np.ndarray,
    rot: np.ndarray,
    quat: np.ndarray,
    p_foot: np.ndarray,
    foot_yaw: np.ndarray,
    has_yaw: bool,
    p_com_target: np.ndarray,
    com_gain: np.ndarray,
    n_corrections: int,
    nominal_q: np.ndarray,
    leg_q_index: np.ndarray,
    p_yaw: np.ndarray,
    p_roll: np.ndarray,
    p_pitch: np.ndarray,
    thigh: np.ndarray,
    shank: np.ndarray,
    c_foot: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    parent: np.ndarray,
    kind: np.ndarray,
    idx_q: np.ndarray,
    tree_rot: np.ndarray,
    tree_trans: np.ndarray,
    mass: np.ndarray,
    lever: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Configurations ``q`` (N, nq), trunk positions (N, 3) and reachability (N,).

    ``p_base`` (N, 3) the first trunk guess (not modified), ``rot`` (N, 3, 3) and ``quat``
    (N, 4, ``x y z w``) the trunk rotations, ``p_foot`` (N, 2, 3) and ``foot_yaw`` (N, 2,
    read with ``has_yaw``) the feet's targets; ``nominal_q`` (nq,) the configuration the
    joints not of a leg keep, ``leg_q_index`` (2, 5) the legs' entries of ``q``; the legs'
    geometries stacked per leg (:class:`~gaitnet_mpc.kinematics.leg_ik.LegGeometry`) and
    the kinematic tree's arrays (:class:`~gaitnet_mpc.kinematics.rigid_body_kernel.KinematicTree`).
    """
    n = p_base.shape[0]
    base = p_base.copy()
    q = np.empty((n, nominal_q.size))
    leg_q = np.empty((n, 5))
    reach = np.empty(n, dtype=np.bool_)
    reachable = np.empty(n, dtype=np.bool_)
    for it in range(n_corrections + 1):
        for k in range(n):
            q[k] = nominal_q
            q[k, 0:3] = base[k]
            q[k, 3:7] = quat[k]
            reachable[k] = True
        for leg in range(2):
            leg_ik_rows(
                np.ascontiguousarray(p_foot[:, leg]), base, rot,
                np.ascontiguousarray(foot_yaw[:, leg]), has_yaw, p_yaw[leg], p_roll[leg],
                p_pitch[leg], thigh[leg], shank[leg], c_foot[leg], lower[leg], upper[leg],
                1e-9, leg_q, reach,
            )  # fmt: skip
            for k in range(n):
                for j in range(5):
                    q[k, leg_q_index[leg, j]] = leg_q[k, j]
                reachable[k] = reachable[k] and reach[k]
        if it == n_corrections:
            break
        com = com_rows(q, parent, kind, idx_q, tree_rot, tree_trans, mass, lever)
        for k in range(n):
            for b in range(3):
                base[k, b] = base[k, b] + (p_com_target[k, b] - com[k, b]) / com_gain[b]
    return q, base, reachable
