"""Linear constraints on one foot's ground wrench [f; m] (world-aligned, about the foot centre).

Friction pyramid (paper eqs. 21-22) with mu_box = mu * sqrt(2) / 2, normal-force bounds
(eq. 23) and the wrench limits of a line foot along its heading: no moment about the foot's
long axis, pitch moment bounded by f_z times the toe/heel distance, and a yaw moment bounded
by friction over the foot's half length. A point foot carries no moment at all.

The yaw bound ``|m_z| <= mu half f_z`` (``ContactParams.yaw_moment = "line"``) holds only
while the normal force is shared by both ends. The contact wrench cone of a rectangle
(Caron, Pham and Nakamura, ICRA 2015, closed form) taken for the segment of half length
``X`` (zero width, no moment about the axis) gives, in the foot frame,
``-mu X f_z + |X f_lat - mu m_lat| <= m_z <= mu X f_z - |X f_lat + mu m_lat|``: with the
centre of pressure at an end (``m_lat = -+X f_z``) the foot holds only the yaw moment of its
lateral force at that end, ``X f_lat`` (``"cwc"``, four rows).

:class:`StanceWrenchRows` evaluates the stance rows of one foot model at every stage and
foot of an MPC horizon in one vectorised pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.errors import ConfigError

INF = np.inf
YAW_MOMENT_MODELS = ("line", "cwc")
_MU = "> 0 to walk; 2 is past rubber on concrete (about 1)"
_FZ_MAX = "2000 N is 13 times the 16 kg humanoid's weight"


@dataclass(frozen=True)
class ContactParams:
    """Contact model shared by all controllers (paper Table VIII)."""

    mu: float = bounded(0.7, "(0, 2]", "a friction coefficient", _MU)
    fz_min_n: float = bounded(10.0, "[0, 2000] N", "a normal force", "a foot cannot pull")
    fz_max_n: float = bounded(500.0, "(0, 2000] N", "a normal force", _FZ_MAX)
    # The yaw moment a line foot can hold. "line": |m_z| <= mu half f_z, as if the normal
    # force sat at both ends. "cwc": the contact wrench cone of the segment (module
    # docstring), where a centre of pressure near one end, or a lateral force, leaves less.
    yaw_moment: str = "line"

    def __post_init__(self) -> None:
        check_ranges(self)
        if self.fz_min_n > self.fz_max_n:
            raise ConfigError("fz_min_n", self.fz_min_n, f"<= fz_max_n = {self.fz_max_n} N")
        if self.yaw_moment not in YAW_MOMENT_MODELS:
            raise ConfigError("yaw_moment", self.yaw_moment, f"one of {list(YAW_MOMENT_MODELS)}")

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
    cone_half_m: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows ``C`` (m, 6) and bounds ``l, u`` with ``l <= C [f; m] <= u`` for one foot.

    In swing (``in_stance=False``) the whole wrench is bounded to zero (eq. 23 with sigma=0).
    ``cone_half_m``: half length of the segment of the yaw rows' wrench cone (``"cwc"``);
    None: ``(toe_m + heel_m) / 2``, the centre-of-pressure rows' segment.
    """
    if not in_stance:
        return np.eye(6), np.zeros(6), np.zeros(6)
    yaw = np.array([yaw_rad], dtype=float)
    c_yaw, s_yaw = np.cos(yaw), np.sin(yaw)
    rows, lo, hi = _stance_rows(c_yaw, s_yaw, params, toe_m, heel_m, cone_half_m)
    return rows[0], lo, hi


def _stance_rows(
    c_yaw: np.ndarray,
    s_yaw: np.ndarray,
    params: ContactParams,
    toe_m: float,
    heel_m: float,
    cone_half_m: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stance rows ``C`` (n, m, 6) at the yaws of cosines ``c_yaw`` and sines ``s_yaw``
    (n,), bounds ``l, u`` (m,). Each entry of ``C`` is a constant, or a constant times the
    cosine or the sine: :class:`StanceWrenchRows` builds it from three evaluations."""
    n = c_yaw.size
    zero = np.zeros(n)
    axis = np.stack([c_yaw, s_yaw, zero], axis=1)  # (n, 3) foot long axis (toe direction)
    lateral = np.stack([-s_yaw, c_yaw, zero], axis=1)
    mu = params.mu_box
    rows: list[np.ndarray] = []
    lo: list[float] = []
    hi: list[float] = []

    def add(force: np.ndarray, moment: np.ndarray, lower: float, upper: float) -> None:
        """One row ``force . f + moment . m``, each part (3,) or (n, 3)."""
        parts = [np.broadcast_to(force, (n, 3)), np.broadcast_to(moment, (n, 3))]
        rows.append(np.concatenate(parts, axis=1))
        lo.append(lower)
        hi.append(upper)

    ez, none = np.array([0.0, 0.0, 1.0]), np.zeros(3)
    add(ez, none, params.fz_min_n, params.fz_max_n)
    for tangent in (np.array([1.0, 0, 0]), np.array([0, 1.0, 0])):
        add(tangent - mu * ez, none, -INF, 0.0)  # f_t <= mu f_z
        add(tangent + mu * ez, none, 0.0, INF)  # f_t >= -mu f_z
    if toe_m == 0.0 and heel_m == 0.0:
        for i in range(3):
            add(none, np.eye(3)[i], 0.0, 0.0)
    else:
        add(none, axis, 0.0, 0.0)  # no moment about the line
        # Pitch moment about the lateral axis: the CoP stays between heel and toe.
        # m_lat = -(x_cop) f_z along the axis, so -toe f_z <= m_lat <= heel f_z.
        add(toe_m * ez, lateral, 0.0, INF)
        add(-heel_m * ez, lateral, -INF, 0.0)
        half = 0.5 * (toe_m + heel_m)
        if params.yaw_moment == "line":
            add(-mu * half * ez, ez, -INF, 0.0)  # |m_z| <= mu * half length * f_z
            add(mu * half * ez, ez, 0.0, INF)
        else:  # the segment's wrench cone (module docstring): m_z <= mu x f_z -
            # |x f_lat + mu m_lat| and m_z >= -mu x f_z + |x f_lat - mu m_lat|
            x = half if cone_half_m is None else cone_half_m
            for sign in (1.0, -1.0):
                add(sign * x * lateral - mu * x * ez, ez + sign * mu * lateral, -INF, 0.0)
                add(sign * x * lateral - mu * x * ez, -ez - sign * mu * lateral, -INF, 0.0)
    return np.stack(rows, axis=1), np.array(lo), np.array(hi)


class StanceWrenchRows:
    """Stance rows of :func:`foot_wrench_constraints` for one foot model at every yaw of a
    horizon, in one vectorised pass.

    Args:
        params: friction and normal-force limits.
        toe_m, heel_m: line-foot lengths [m] (both 0: point foot).
        cone_half_m: as :func:`foot_wrench_constraints`.
    """

    def __init__(
        self,
        params: ContactParams,
        toe_m: float,
        heel_m: float,
        cone_half_m: float | None = None,
    ) -> None:
        self.params = params
        self.toe_m = toe_m
        self.heel_m = heel_m
        self.cone_half_m = cone_half_m
        # C(yaw) = C_0 + cos(yaw) C_c + sin(yaw) C_s (see _stance_rows)
        unit = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
        rows, self._lo, self._hi = _stance_rows(*unit, params, toe_m, heel_m, cone_half_m)
        self._c0, self._cc, self._cs = rows[0], rows[1] - rows[0], rows[2] - rows[0]
        c_rows = self._c0 + self._cc
        #: Stance rows per foot (the same at every yaw).
        self.n_rows = int(c_rows.shape[0])
        #: Whether the stance rows have full column rank (then ``C w = 0`` forces ``w = 0``).
        self.full_column_rank = bool(np.linalg.matrix_rank(c_rows) == 6)
        self._last: tuple[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None

    def stack(self, foot_yaw_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Stance rows ``C`` (..., m, 6) and bounds ``l, u`` (..., m) at every yaw of
        ``foot_yaw_rad`` (...); read-only, and the last result is kept (the yaws are fixed
        within a sequential solve)."""
        key = foot_yaw_rad.tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        yaw = np.asarray(foot_yaw_rad, dtype=float)[..., None, None]
        rows = self._c0 + np.cos(yaw) * self._cc + np.sin(yaw) * self._cs
        shape = (*foot_yaw_rad.shape, self.n_rows)
        out = (
            rows,
            np.broadcast_to(self._lo, shape).copy(),
            np.broadcast_to(self._hi, shape).copy(),
        )
        for arr in out:
            arr.flags.writeable = False
        self._last = (key, out)
        return out


__all__ = ["ContactParams", "StanceWrenchRows", "foot_wrench_constraints"]
