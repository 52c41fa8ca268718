"""Linear constraints on one foot's ground wrench [f; m] (world-aligned, about the foot centre).

Friction pyramid (paper eqs. 21-22) with mu_box = mu * sqrt(2) / 2, normal-force bounds
(eq. 23) and the wrench limits of a line foot along its heading: no moment about the foot's
long axis, pitch moment bounded by f_z times the toe/heel distance, and a yaw moment bounded
by friction over the foot's half length. A point foot carries no moment at all.

:class:`StanceWrenchRows` evaluates the stance rows of one foot model at every stage and
foot of an MPC horizon in one vectorised pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.errors import ConfigError

INF = np.inf
_MU = "> 0 to walk; 2 is past rubber on concrete (about 1)"
_FZ_MAX = "2000 N is 13 times the 16 kg humanoid's weight"


@dataclass(frozen=True)
class ContactParams:
    """Contact model shared by all controllers (paper Table VIII)."""

    mu: float = bounded(0.7, "(0, 2]", "a friction coefficient", _MU)
    fz_min_n: float = bounded(10.0, "[0, 2000] N", "a normal force", "a foot cannot pull")
    fz_max_n: float = bounded(500.0, "(0, 2000] N", "a normal force", _FZ_MAX)

    def __post_init__(self) -> None:
        check_ranges(self)
        if self.fz_min_n > self.fz_max_n:
            raise ConfigError("fz_min_n", self.fz_min_n, f"<= fz_max_n = {self.fz_max_n} N")

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


class StanceWrenchRows:
    """Stance rows of :func:`foot_wrench_constraints` for one foot model, at many yaws.

    Only three rows of a line foot depend on its yaw, through ``cos`` and ``sin`` (the
    long axis and the lateral axis); the others are the same at every yaw. So the rows at
    all yaws of a horizon are the rows at yaw 0 with those entries written in one
    vectorised pass, equal bit for bit to :func:`foot_wrench_constraints` at each yaw
    (checked at construction).

    Args:
        params: friction and normal-force limits.
        toe_m, heel_m: line-foot lengths [m] (both 0: point foot).
    """

    #: Rows of a line foot whose moment columns (3, 4) follow the yaw: the long axis
    #: ``(cos, sin)`` and, twice, the lateral axis ``(-sin, cos)`` (foot_wrench_constraints).
    _AXIS_ROW, _LATERAL_ROWS = 5, (6, 7)

    def __init__(self, params: ContactParams, toe_m: float, heel_m: float) -> None:
        self.params = params
        self.toe_m = toe_m
        self.heel_m = heel_m
        c_rows, lo, hi = foot_wrench_constraints(0.0, params, toe_m, heel_m, True)
        self._base = (c_rows, lo, hi)
        self._line_foot = not (toe_m == 0.0 and heel_m == 0.0)
        #: Stance rows per foot (the same at every yaw).
        self.n_rows = int(c_rows.shape[0])
        #: Whether the stance rows have full column rank (then ``C w = 0`` forces ``w = 0``).
        self.full_column_rank = bool(np.linalg.matrix_rank(c_rows) == 6)
        self._last: tuple[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
        check = np.array([0.7, -2.9])
        for got, want in zip(self._rows(check), zip(*(
            foot_wrench_constraints(y, params, toe_m, heel_m, True) for y in check
        ), strict=True), strict=True):  # fmt: skip
            if not np.array_equal(got, np.stack(want)):  # pragma: no cover - model change
                raise ConfigError("foot_wrench_constraints", "its row layout", "rows 5-7 by yaw")

    def _rows(self, yaw_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows (n, m, 6) and bounds (n, m) at the yaws ``yaw_rad`` (n,)."""
        c_rows, lo, hi = self._base
        n = yaw_rad.size
        rows = np.broadcast_to(c_rows, (n, *c_rows.shape)).copy()
        if self._line_foot:
            c, s = np.cos(yaw_rad), np.sin(yaw_rad)
            rows[:, self._AXIS_ROW, 3], rows[:, self._AXIS_ROW, 4] = c, s
            for r in self._LATERAL_ROWS:
                rows[:, r, 3], rows[:, r, 4] = -s, c
        return (
            rows,
            np.broadcast_to(lo, (n, lo.size)).copy(),
            np.broadcast_to(hi, (n, hi.size)).copy(),
        )

    def stack(self, foot_yaw_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Stance rows ``C`` (..., m, 6) and bounds ``l, u`` (..., m) at every yaw of
        ``foot_yaw_rad`` (...); read-only, and the last result is kept (the yaws are fixed
        within a sequential solve)."""
        key = foot_yaw_rad.tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        rows, lo, hi = self._rows(np.asarray(foot_yaw_rad, dtype=float).ravel())
        shape = (*foot_yaw_rad.shape, self.n_rows)
        out = (rows.reshape(*shape, 6), lo.reshape(shape), hi.reshape(shape))
        for arr in out:
            arr.flags.writeable = False
        self._last = (key, out)
        return out


__all__ = ["ContactParams", "StanceWrenchRows", "foot_wrench_constraints"]
