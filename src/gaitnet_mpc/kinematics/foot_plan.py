"""Foot plan of the reference trajectory: where each foot is at every stage boundary.

Each foot's contact column is split into stance and swing segments
(:func:`foot_timeline`). A foot stands on foothold ``F_j`` during a stance segment; the
``j``-th swing goes from ``F_j`` to ``F_{j+1}``. ``F_0`` is the foot's current position
(or, for a foot swinging now, its lift-off point), ``F_1, F_2, ...`` the planned touchdown
targets; a missing target falls back to the neutral point of the commanded CoM path
(:func:`neutral_foothold`). The current swing runs over the whole current step, from
``-time_in_step_s`` to its touchdown; later swings over their step (``h' dt``).

:func:`foot_plan` turns the timeline into foot positions along the obstacle-free swing
path :func:`gaitnet_mpc.gait.swing.swing_profile` and foot headings: a standing foot keeps
its heading, a new foothold gets the trunk heading at touchdown, a swinging foot blends the
two with the same minimum-jerk phase. These are the IK targets ``p_f^ref`` of Algorithm 1
(``f_ref``, lines 2-3, and ``f_IK``, line 9).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.timing import ReferenceTiming
from gaitnet_mpc.geometry import heading_axes, rotate2
from gaitnet_mpc.kinematics.foot_plan_kernel import foothold_means, plan_rows
from gaitnet_mpc.robots.spec import FEET

__all__ = [
    "FootPlan",
    "FootTimeline",
    "Swing",
    "foot_plan",
    "foot_timeline",
    "footholds_from_iterates",
    "heading_displacement",
    "neutral_foothold",
    "stacked_index",
]

_N_FEET = len(FEET)


@dataclass(frozen=True)
class Swing:
    """One swing of one foot inside the horizon (times relative to now) [s]."""

    first_stage: int
    t_liftoff_s: float
    t_touchdown_s: float


@dataclass(frozen=True)
class FootTimeline:
    """Per-boundary foothold index and swing phase of one foot, and its swings."""

    index: np.ndarray  # (h+1,) int
    phase: np.ndarray  # (h+1,) float in [0, 1]
    swings: tuple[Swing, ...]


@dataclass(frozen=True)
class FootPlan:
    """Foot targets over the horizon and the foothold data behind them."""

    p_foot_m: np.ndarray  # (h+1, 2, 3) foot-centre targets
    foot_yaw_rad: np.ndarray  # (h+1, 2) foot headings
    footholds_m: dict[str, np.ndarray]  # foot -> (n_f, 3)
    foothold_yaw_rad: dict[str, np.ndarray]  # foot -> (n_f,)
    index: np.ndarray  # (h+1, 2) int foothold F_j
    phase: np.ndarray  # (h+1, 2) swing phase from F_j to F_{j+1}
    time_in_swing_s: np.ndarray  # (2,)


def heading_displacement(
    v_xy_mps: np.ndarray, yaw0_rad: float, yaw_rate_radps: float, t_s: np.ndarray
) -> np.ndarray:
    """(N, 2) ``int_0^t R_z(yaw0 + omega s) v ds``: the chord ``R_z(yaw0 + omega t/2) v t
    sinc(omega t / 2)`` of the commanded arc (exact for constant v, omega)."""
    half = 0.5 * yaw_rate_radps * t_s
    mid = yaw0_rad + half
    scale = t_s * np.sinc(half / np.pi)  # np.sinc(x) = sin(pi x) / (pi x)
    c, s = np.cos(mid), np.sin(mid)
    vx, vy = v_xy_mps
    return np.stack([(c * vx - s * vy) * scale, (s * vx + c * vy) * scale], axis=1)


def foot_timeline(
    timing: ReferenceTiming, foot_col: int, times_s: np.ndarray, time_in_swing_s: float
) -> FootTimeline:
    """Split one contact column into stance / swing segments (module docstring).

    ``time_in_swing_s``: how long ago a foot swinging in stage 0 lifted off [s]. Plain
    Python over the ``h + 1`` boundaries: cheaper than NumPy at these sizes.
    """
    c = timing.contact[:, foot_col].tolist()  # (h,)
    t = times_s.tolist()  # (h+1,)
    h = len(c)
    index = [0] * (h + 1)
    phase = [0.0] * (h + 1)
    swings: list[Swing] = []
    j = 0
    a = 0
    while a < h:
        b = a + 1
        while b < h and c[b] == c[a]:
            b += 1  # stages a..b-1 form one segment, boundaries a..b
        if c[a]:  # stance on F_j (also at the touchdown boundary a)
            index[a : b + 1] = [j] * (b + 1 - a)
            phase[a : b + 1] = [0.0] * (b + 1 - a)
        else:  # swing from F_j to F_{j+1}
            t_lo = -time_in_swing_s if a == 0 else t[a]
            if b < h:
                t_td = t[b]
            else:  # lands after the horizon: the swing lasts one step (h' dt)
                t_step = timing.stages_per_step * float(timing.stage_lengths_s[a])
                t_td = max(t_lo + t_step, t[h])
            duration = max(t_td - t_lo, 1e-12)
            for k in range(a, b + 1):
                index[k] = j
                phase[k] = min(max((t[k] - t_lo) / duration, 0.0), 1.0)
            swings.append(Swing(a, t_lo, t_td))
            j += 1
        a = b
    return FootTimeline(np.array(index), np.array(phase), tuple(swings))


def neutral_foothold(
    p_com_start_m: np.ndarray,
    v_cmd_mps: np.ndarray,
    yaw0_rad: float,
    yaw_rate_radps: float,
    swing: Swing,
    t_step_s: float,
    previous_m: np.ndarray,
    lateral_m: float,
    planar: bool,
) -> np.ndarray:
    """(3,) fallback touchdown target: ``p_c(t_td) + R_z(psi_td) (0, y_nom) + v T / 2`` in
    x-y (commanded CoM path, Raibert neutral point without feedback), previous height.

    ``lateral_m`` is the nominal lateral foot offset ``y_nom`` from the CoM [m];
    ``planar``: keep the previous foothold's y (biped2d).
    """
    t_td = np.array([swing.t_touchdown_s])
    p_c = p_com_start_m[:2] + heading_displacement(v_cmd_mps, yaw0_rad, yaw_rate_radps, t_td)[0]
    yaw_td = yaw0_rad + yaw_rate_radps * swing.t_touchdown_s
    v_world = rotate2(yaw_td, v_cmd_mps)
    _, e_y = heading_axes(yaw_td)
    out = previous_m.copy()
    out[:2] = p_c + e_y * lateral_m + 0.5 * t_step_s * v_world
    if planar:
        out[1] = previous_m[1]
    return out


def stacked_index(
    index: np.ndarray, footholds: dict[str, np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Footholds of both feet stacked (n_l + n_r, 3), and per boundary the stacked row of
    ``F_j`` and of ``F_{j+1}`` (clipped to the foot's last foothold), each (h+1, 2)."""
    first, second = (footholds[f] for f in FEET)
    n0, n1 = first.shape[0], second.shape[0]
    stacked = np.concatenate((first, second))
    j0 = index + np.array([0, n0])  # each foot's rows start at its offset
    j1 = np.minimum(j0 + 1, np.array([n0 - 1, n0 + n1 - 1]))
    return stacked, j0, j1


def foot_plan(
    index: np.ndarray,
    phase: np.ndarray,
    footholds: dict[str, np.ndarray],
    foothold_yaw: dict[str, np.ndarray],
    time_in_swing_s: np.ndarray,
    apex_height_m: float,
    planar: bool,
) -> FootPlan:
    """Foot positions (h+1, 2, 3) and headings (h+1, 2) from the timeline (the swing
    profile of :func:`gaitnet_mpc.gait.swing.swing_profile` for both feet, compiled:
    :func:`~gaitnet_mpc.kinematics.foot_plan_kernel.plan_rows`; swing apex
    ``apex_height_m`` [m]; ``planar``: zero headings, biped2d)."""
    stacked, j0, j1 = stacked_index(index, footholds)  # (n_fh, 3), (h+1, 2) x2
    yaws = np.zeros(stacked.shape[0]) if planar else np.concatenate([foothold_yaw[f] for f in FEET])
    p_foot, yaw = plan_rows(stacked, yaws, j0, j1, phase, apex_height_m, planar)
    return FootPlan(p_foot, yaw, footholds, foothold_yaw, index, phase, time_in_swing_s)


def footholds_from_iterates(
    p_iter_m: np.ndarray,
    contact: np.ndarray,
    index: np.ndarray,
    phase: np.ndarray,
    footholds: dict[str, np.ndarray],
    planar: bool,
) -> dict[str, np.ndarray]:
    """New footholds from the MPC's foot iterates ``p_f^j`` (``f_IK``, Alg. 1 line 9).

    Each foothold becomes its mean iterate over the rows where the foot stands on it. Row
    ``k`` is read iff the foot is in contact in stage ``k`` (row ``h`` of a boundary
    array: stage ``h - 1``), so a swinging foot's row is never read. Footholds without
    such a row keep their value; ``planar`` (biped2d) keeps y.

    Args:
        p_iter_m: (h+1, 2, 3) boundary or (h, 2, 3) stage foot iterates [m].
        contact: (h, 2) bool stance mask.
        index: (h+1, 2) foothold index ``j`` per boundary (:class:`FootPlan`).
        phase: (h+1, 2) swing phase per boundary.
        footholds: foot -> (n_f, 3) current footholds [m].
        planar: keep the footholds' y.
    """
    h = contact.shape[0]
    if p_iter_m.shape == (h + 1, _N_FEET, 3):
        rows = h + 1
        on_ground = np.concatenate([contact, contact[-1:]])  # (h+1, 2)
    elif p_iter_m.shape == (h, _N_FEET, 3):
        rows = h
        on_ground = contact
    else:
        raise ConfigError(
            "p_foot_iter_m", p_iter_m.shape, f"({h + 1}, 2, 3) or ({h}, 2, 3) foot iterates [m]"
        )
    stacked, j0, _ = stacked_index(index[:rows], footholds)
    j = j0 + (phase[:rows] == 1.0)  # (rows, 2) stacked foothold rows
    new = foothold_means(p_iter_m, on_ground, j, stacked)
    if planar:
        new[:, 1] = stacked[:, 1]
    out: dict[str, np.ndarray] = {}
    start = 0
    for f in FEET:
        size = footholds[f].shape[0]
        out[f] = new[start : start + size]
        start += size
    return out
