"""Result of one whole-body NMPC solve (trajectories of eq. 1, statistics, warm start)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class WBSolution:
    """Result of one NMPC solve: trajectories, solver statistics, warm-start data."""

    qpos: np.ndarray  # (h+1, nq)
    qvel: np.ndarray  # (h+1, nv)
    qacc: np.ndarray  # (h, nv)
    tau_nm: np.ndarray  # (h, n_joints)
    force_world_n: np.ndarray  # (h, n_contacts, 3)
    cost: float
    success: bool
    status: str
    iterations: int
    solve_time_s: float
    constraint_violation: float  # max bound/constraint violation at the returned point
    solver: str
    x_opt: np.ndarray  # raw decision vector (warm start)
    lam_g: np.ndarray
    lam_x: np.ndarray
    # lam_g split per stage block: gap_0, path_0, ..., gap_{h-1}, path_{h-1}, path_h.
    lam_blocks: tuple[np.ndarray, ...] = ()
