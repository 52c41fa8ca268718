"""Raibert-style foothold heuristic for controllers that do not optimise footholds.

For the swing foot that touches down in ``t_td`` seconds and then stands for ``T_stance``
(with no double support, one step: ``T_stance = h'·dt``, paper Sec. IV-B1), the foothold
in the horizontal plane is (Raibert [10]; Di Carlo et al. [8], eq. 33 of their paper)

    p_foot = p_hip(t_td) + v_com · T_stance / 2 + k_v (v_com - v_cmd)
             + (z0 / 2g) (v_com × ω_cmd)

* ``p_hip(t_td)``: the hip projected to the ground at touchdown, predicted with the commanded
  velocity (``p_hip + v_cmd · t_td``, hip offsets rotated with the predicted yaw);
* ``v_com · T_stance / 2``: neutral point, so that at steady state the stance is symmetric
  about the hip (the "step duration term");
* ``k_v (v_com - v_cmd)``: velocity feedback, default capture-point gain ``k_v = sqrt(z0/g)``
  with ``z0`` the CoM height above the ground;
* the last term: centripetal correction when turning (zero without a yaw-rate command).

The result is then clipped relative to the stance foot in the heading frame: forward
displacement to ``±max_step_m``, lateral separation to
``[min_lateral_separation_m, max_lateral_separation_m]`` on the swing foot's own side, so the
feet never cross.  Height: ``ground_z_m + foot_height_m``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.geometry import heading_axes, rot2
from gaitnet_mpc.robots.spec import FEET

__all__ = ["RaibertConfig", "RaibertHeuristic", "keep_beside_stance"]


def _finite(value: object, field: str, lo: float = -math.inf, strict: bool = False) -> float:
    ok = isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)
    if ok:
        v = float(value)  # type: ignore[arg-type]
        ok = math.isfinite(v) and (v > lo if strict else v >= lo)
    if not ok:
        rel = ">" if strict else ">="
        expected = "a finite number" if lo == -math.inf else f"a finite number {rel} {lo}"
        raise ConfigError(field, value, expected)
    return v


def _vec(value: ArrayLike, field: str, sizes: tuple[int, ...]) -> np.ndarray:
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(field, value, f"a finite vector of length {sizes}") from None
    if v.ndim != 1 or v.shape[0] not in sizes or not np.all(np.isfinite(v)):
        raise ConfigError(field, value, f"a finite vector of length {sizes}")
    return v


@dataclass(frozen=True)
class RaibertConfig:
    """Parameters of the Raibert heuristic (lengths in m, times in s).

    Attributes:
        hip_lateral_offset_m: nominal hip offset from the CoM along the heading's left axis
            [m]; the left hip is at ``+``, the right hip at ``-`` (0 for the planar biped).
        hip_forward_offset_m: nominal hip offset from the CoM along the heading [m].
        velocity_gain_s: ``k_v`` [s]; None = capture-point gain ``sqrt(z0 / g)``.
        com_height_m: ``z0`` [m] for the gains; None = measured CoM height above the ground.
        turn_gain_s2: coefficient of ``v × ω_cmd`` [s²]; None = ``z0 / (2 g)``.
        gravity_mps2: ``g`` [m/s²].
        max_step_m: largest forward/backward displacement from the stance foot [m].
        min_lateral_separation_m: smallest lateral distance of the new foot from the stance
            foot, on its own side [m] (0 for the planar biped).
        max_lateral_separation_m: largest lateral distance from the stance foot [m].
        foot_height_m: height of the foothold point above the ground in contact [m].
    """

    hip_lateral_offset_m: float = 0.06
    hip_forward_offset_m: float = 0.0
    velocity_gain_s: float | None = None
    com_height_m: float | None = None
    turn_gain_s2: float | None = None
    gravity_mps2: float = 9.81
    max_step_m: float = 0.35
    min_lateral_separation_m: float = 0.08
    max_lateral_separation_m: float = 0.40
    foot_height_m: float = 0.0

    def __post_init__(self) -> None:
        _finite(self.hip_lateral_offset_m, "hip_lateral_offset_m", 0.0)
        _finite(self.hip_forward_offset_m, "hip_forward_offset_m")
        for name in ("velocity_gain_s", "turn_gain_s2"):
            if getattr(self, name) is not None:
                _finite(getattr(self, name), name, 0.0)
        if self.com_height_m is not None:
            _finite(self.com_height_m, "com_height_m", 0.0, strict=True)
        _finite(self.gravity_mps2, "gravity_mps2", 0.0, strict=True)
        _finite(self.max_step_m, "max_step_m", 0.0)
        _finite(self.min_lateral_separation_m, "min_lateral_separation_m", 0.0)
        _finite(self.max_lateral_separation_m, "max_lateral_separation_m", 0.0)
        if self.max_lateral_separation_m < self.min_lateral_separation_m:
            raise ConfigError(
                "max_lateral_separation_m",
                self.max_lateral_separation_m,
                f">= min_lateral_separation_m = {self.min_lateral_separation_m}",
            )
        _finite(self.foot_height_m, "foot_height_m")


class RaibertHeuristic:
    """Foothold heuristic (see module docstring); stateless apart from its config."""

    def __init__(self, config: RaibertConfig | None = None) -> None:
        self.config = config if config is not None else RaibertConfig()

    def hip_world_m(self, foot: str, p_com_world_m: ArrayLike, yaw_rad: float = 0.0) -> np.ndarray:
        """(3,) nominal hip position of ``foot`` [m]: CoM + yaw-rotated nominal offsets."""
        if foot not in FEET:
            raise ConfigError("foot", foot, f"one of {FEET}")
        p_com = _vec(p_com_world_m, "p_com_world_m", (3,))
        side = 1.0 if foot == "left" else -1.0
        off = np.array([self.config.hip_forward_offset_m, side * self.config.hip_lateral_offset_m])
        out = p_com.copy()
        out[:2] += rot2(_finite(yaw_rad, "yaw_rad")) @ off
        return out

    def foothold(
        self,
        foot: str,
        *,
        p_com_world_m: ArrayLike,
        v_com_world_mps: ArrayLike,
        cmd_vel_mps: ArrayLike,
        stance_duration_s: float,
        time_to_touchdown_s: float,
        p_stance_foot_world_m: ArrayLike,
        ground_z_m: float = 0.0,
        yaw_rad: float = 0.0,
        cmd_yaw_rate_radps: float = 0.0,
        p_hip_world_m: ArrayLike | None = None,
    ) -> np.ndarray:
        """(3,) world foothold [m] of the swing foot ``foot`` (``"left"`` or ``"right"``).

        Args:
            foot: the swing foot.
            p_com_world_m: (3,) CoM position [m].
            v_com_world_mps: (2,) or (3,) CoM velocity [m/s] (z ignored).
            cmd_vel_mps: (2,) commanded (forward, lateral) velocity in the heading frame [m/s].
            stance_duration_s: ``T_stance``, how long the foot will stand after touchdown
                [s]; with one foot in stance at a time, the step duration ``h'·dt``.
            time_to_touchdown_s: time left in the current swing [s] (>= 0).
            p_stance_foot_world_m: (3,) the stance foot's position [m] (for clipping).
            ground_z_m: ground height at the foothold [m].
            yaw_rad: heading now [rad].
            cmd_yaw_rate_radps: commanded yaw rate [rad/s].
            p_hip_world_m: (3,) measured hip position [m]; None = CoM + nominal offset.
        """
        cfg = self.config
        if foot not in FEET:
            raise ConfigError("foot", foot, f"one of {FEET}")
        p_com = _vec(p_com_world_m, "p_com_world_m", (3,))  # (3,)
        v_com = _vec(v_com_world_mps, "v_com_world_mps", (2, 3))[:2]  # (2,)
        v_cmd_heading = _vec(cmd_vel_mps, "cmd_vel_mps", (2,))  # (2,)
        t_stance = _finite(stance_duration_s, "stance_duration_s", 0.0)
        t_td = _finite(time_to_touchdown_s, "time_to_touchdown_s", 0.0)
        p_stance = _vec(p_stance_foot_world_m, "p_stance_foot_world_m", (3,))  # (3,)
        ground_z = _finite(ground_z_m, "ground_z_m")
        yaw = _finite(yaw_rad, "yaw_rad")
        omega = _finite(cmd_yaw_rate_radps, "cmd_yaw_rate_radps")

        yaw_td = yaw + omega * t_td  # predicted heading at touchdown [rad]
        v_cmd = rot2(yaw) @ v_cmd_heading  # (2,) commanded velocity, world [m/s]
        if p_hip_world_m is None:
            hip_td = self.hip_world_m(foot, p_com, yaw_td)[:2] + v_cmd * t_td  # (2,)
        else:
            hip_td = _vec(p_hip_world_m, "p_hip_world_m", (3,))[:2] + v_cmd * t_td

        z0 = cfg.com_height_m if cfg.com_height_m is not None else p_com[2] - ground_z
        z0 = max(z0, 1e-3)
        k_v = (
            cfg.velocity_gain_s
            if cfg.velocity_gain_s is not None
            else math.sqrt(z0 / cfg.gravity_mps2)
        )
        k_w = cfg.turn_gain_s2 if cfg.turn_gain_s2 is not None else 0.5 * z0 / cfg.gravity_mps2
        turn = k_w * omega * np.array([v_com[1], -v_com[0]])  # (2,) = k_w (v × ω ẑ)_xy

        p_xy = hip_td + 0.5 * t_stance * v_com + k_v * (v_com - v_cmd) + turn  # (2,)

        # Clip relative to the stance foot in the heading frame at touchdown.
        rot = rot2(yaw_td)
        d = rot.T @ (p_xy - p_stance[:2])  # (2,) (forward, left)
        side = 1.0 if foot == "left" else -1.0
        d[0] = np.clip(d[0], -cfg.max_step_m, cfg.max_step_m)
        d[1] = side * np.clip(
            side * d[1], cfg.min_lateral_separation_m, cfg.max_lateral_separation_m
        )
        out = np.empty(3)
        out[:2] = p_stance[:2] + rot @ d
        out[2] = ground_z + cfg.foot_height_m
        return out


def keep_beside_stance(
    p_world_m: np.ndarray,
    foot: str,
    p_stance_world_m: np.ndarray,
    yaw_rad: float,
    min_separation_m: float | None,
) -> np.ndarray:
    """``p_world_m`` (3,) of the swing foot ``foot``, moved sideways in the heading frame
    of ``yaw_rad`` to at least ``min_separation_m`` on its own side of the stance foot
    (left: +y of the heading), so that a swing never sweeps through the stance leg.
    Unchanged where it already is (or where ``min_separation_m`` is None)."""
    if min_separation_m is None:
        return p_world_m
    side = 1.0 if foot == "left" else -1.0
    _, n_y = heading_axes(yaw_rad)
    lateral = side * float(n_y @ (p_world_m[:2] - p_stance_world_m[:2]))
    if lateral >= min_separation_m:
        return p_world_m
    out = np.array(p_world_m, dtype=float)
    out[:2] += side * (min_separation_m - lateral) * n_y
    return out
