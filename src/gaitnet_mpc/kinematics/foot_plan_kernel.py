"""Compiled row loops of the foot plan (:mod:`~gaitnet_mpc.kinematics.foot_plan`).

The foot targets of ``f_ref`` / ``f_IK`` along the horizon (the swing profile of
:func:`gaitnet_mpc.gait.swing.swing_profile` and the minimum-jerk heading blend) and the
footholds as means of the MPC's foot iterates, one row at a time in scalar arithmetic
(numba, compiled on first use, cached by :mod:`gaitnet_mpc.jit`): at ``h + 1 = 11`` rows and two
feet these are a few microseconds instead of some thirty NumPy calls each.
"""

from __future__ import annotations

import math

import numpy as np

from gaitnet_mpc.jit import njit_cached


@njit_cached(inline="always")
def _min_jerk(s: float) -> float:
    """``10 s^3 - 15 s^4 + 6 s^5``, as :func:`gaitnet_mpc.gait.swing.min_jerk`."""
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


@njit_cached()
def plan_rows(
    stacked: np.ndarray,
    yaws: np.ndarray,
    j0: np.ndarray,
    j1: np.ndarray,
    phase: np.ndarray,
    apex_height_m: float,
    planar: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Foot targets (n, 2, 3) and headings (n, 2) on the way from foothold ``j0`` to ``j1``
    (rows of ``stacked`` (n_fh, 3) and ``yaws`` (n_fh,)) at swing ``phase`` (n, 2): the
    x-y blend ``p0 + (p1 - p0) sigma(s)``, the height rising to ``max(z0, z1) + apex``
    over the first half and descending over the second, the heading ``y0 + wrap(y1 -
    y0) sigma(s)`` (zero for the planar robot)."""
    n = phase.shape[0]
    p_foot = np.empty((n, 2, 3))
    yaw = np.zeros((n, 2))
    for k in range(n):
        for i in range(2):
            a, b = j0[k, i], j1[k, i]
            s = min(max(phase[k, i], 0.0), 1.0)
            blend = _min_jerk(s)
            for axis in range(2):
                p0 = stacked[a, axis]
                p_foot[k, i, axis] = p0 + (stacked[b, axis] - p0) * blend
            z0, z1 = stacked[a, 2], stacked[b, 2]
            top = max(z0, z1) + apex_height_m
            if s < 0.5:
                p_foot[k, i, 2] = z0 + (top - z0) * _min_jerk(min(2.0 * s, 1.0))
            else:
                p_foot[k, i, 2] = top + (z1 - top) * _min_jerk(max(2.0 * s - 1.0, 0.0))
            if not planar:
                d = yaws[b] - yaws[a]
                yaw[k, i] = yaws[a] + math.atan2(math.sin(d), math.cos(d)) * _min_jerk(phase[k, i])
    return p_foot, yaw


@njit_cached()
def foothold_means(
    p_iter: np.ndarray, on_ground: np.ndarray, rows: np.ndarray, stacked: np.ndarray
) -> np.ndarray:
    """Each foothold (row of ``stacked`` (n_fh, 3)) as the mean of the iterates ``p_iter``
    (n, 2, 3) standing on it (``on_ground`` (n, 2), foothold row ``rows`` (n, 2)); a
    foothold that none stands on keeps its value."""
    sums = np.zeros(stacked.shape)
    counts = np.zeros(stacked.shape[0])
    for k in range(p_iter.shape[0]):
        for i in range(2):
            if on_ground[k, i]:
                j = rows[k, i]
                counts[j] += 1.0
                for axis in range(3):
                    sums[j, axis] += p_iter[k, i, axis]
    out = stacked.copy()
    for j in range(stacked.shape[0]):
        if counts[j] > 0.0:
            for axis in range(3):
                out[j, axis] = sums[j, axis] / counts[j]
    return out
