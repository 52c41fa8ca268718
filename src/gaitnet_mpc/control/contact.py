"""Linear constraints on one foot's ground wrench [f; m] (world-aligned, about the foot centre).

Friction pyramid (paper eqs. 21-22) with mu_box = mu * sqrt(2) / 2, normal-force bounds
(eq. 23) and the wrench limits of a line foot along its heading: no moment about the foot's
long axis, pitch moment bounded by f_z times the toe/heel distance, and a yaw moment bounded
by friction over the foot's half length. A point foot carries no moment at all.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

INF = np.inf


@dataclass(frozen=True)
class ContactParams:
    """Contact model shared by all controllers (paper Table VIII)."""

    mu: float = 0.7
    fz_min_n: float = 10.0
    fz_max_n: float = 500.0

    @property
    def mu_box(self) -> float:
        """Inscribed friction-pyramid coefficient, eq. (21)."""
        return self.mu * np.sqrt(2.0) / 2.0


def foot_wrench_constraints(
    yaw_rad: float,
    params: ContactParams,
    toe_m: float,
    heel_m: float,
    in_stance: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows ``C`` (m, 6) and bounds ``l, u`` with ``l <= C [f; m] <= u`` for one foot.

    In swing (``in_stance=False``) the whole wrench is bounded to zero (eq. 23 with sigma=0).
    """
    c_yaw, s_yaw = np.cos(yaw_rad), np.sin(yaw_rad)
    axis = np.array([c_yaw, s_yaw, 0.0])  # foot long axis (toe direction)
    lateral = np.array([-s_yaw, c_yaw, 0.0])
    mu = params.mu_box
    rows: list[np.ndarray] = []
    lo: list[float] = []
    hi: list[float] = []

    def add(row: np.ndarray, lower: float, upper: float) -> None:
        rows.append(row)
        lo.append(lower)
        hi.append(upper)

    if not in_stance:
        for i in range(6):
            add(np.eye(6)[i], 0.0, 0.0)
        return np.array(rows), np.array(lo), np.array(hi)
    ez = np.array([0.0, 0.0, 1.0])
    add(np.r_[ez, 0, 0, 0], params.fz_min_n, params.fz_max_n)
    for tangent in (np.array([1.0, 0, 0]), np.array([0, 1.0, 0])):
        add(np.r_[tangent - mu * ez, 0, 0, 0], -INF, 0.0)  # f_t <= mu f_z
        add(np.r_[tangent + mu * ez, 0, 0, 0], 0.0, INF)  # f_t >= -mu f_z
    if toe_m == 0.0 and heel_m == 0.0:
        for i in range(3):
            add(np.eye(6)[3 + i], 0.0, 0.0)
        return np.array(rows), np.array(lo), np.array(hi)
    add(np.r_[0, 0, 0, axis], 0.0, 0.0)  # no moment about the line
    # Pitch moment about the lateral axis: the CoP stays between heel and toe.
    # m_lat = -(x_cop) f_z along the axis, so -toe f_z <= m_lat <= heel f_z.
    add(np.r_[toe_m * ez, lateral], 0.0, INF)
    add(np.r_[-heel_m * ez, lateral], -INF, 0.0)
    half = 0.5 * (toe_m + heel_m)
    add(np.r_[-mu * half * ez, ez], -INF, 0.0)  # |m_z| <= mu * half length * f_z
    add(np.r_[mu * half * ez, ez], 0.0, INF)
    return np.array(rows), np.array(lo), np.array(hi)
