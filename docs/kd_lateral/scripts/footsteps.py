"""Footstep sequence over discrete terrain: which patch each of the next steps uses.

The MPC bounds its next touchdown by one patch (eq. 24, one-step preview). Choosing that
patch greedily (the one nearest a heuristic foothold) can pick a stone from which the
following steps have no reachable stone, or one that needs a swing the leg cannot make
in the step time. The paper assigns a patch to each region of CoM positions by hand
(the green boxes of Fig. 7); this module chooses automatically by looking a few steps
ahead (beyond the paper):

    minimise  sum_i (x_i - x_{i-1} - L)^2 + w_y (y_i - y_i^nom)^2          (dynamic program)
    s.t.      x_i on a patch that foot i may use (shrunk by the margin),
              s_min <= x_i - x_{i-1} <= s_max,   |x_1 - x_com,td| <= reach,

with ``x_0`` the standing foot, ``L = v T_step`` the nominal step advance for the
commanded speed and step time, feet alternating, and ``y_i^nom`` the nominal lateral foot
position beside the commanded path. Positions are along the course axis (world x); the
courses of this project are laid out along x. Candidates are a grid on every allowed
patch; the lateral coordinate of a candidate is its patch's closest point to the nominal.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.terrain import Course


@dataclass(frozen=True)
class FootstepPlannerConfig:
    """Settings of :func:`plan_footsteps` (lengths in m along the course axis)."""

    n_steps: int = 4  # steps looked ahead, the swing foot's next touchdown first
    grid_m: float = 0.01  # candidate spacing on a patch
    min_advance_m: float = 0.0  # smallest x_i - x_{i-1} (no backward steps)
    max_advance_m: float = 0.30  # largest x_i - x_{i-1}
    reach_m: float = 0.20  # |x_1 - x_com at touchdown|
    margin_m: float = 0.05  # candidates stay this far inside a patch
    lateral_offset_m: float = 0.07  # nominal |y - y_path| of a foot
    w_lateral: float = 0.1  # weight of the lateral deviation against the advance error

    def __post_init__(self) -> None:
        if not isinstance(self.n_steps, int) or self.n_steps < 1:
            raise ConfigError("n_steps", self.n_steps, "an integer >= 1")
        for name in ("grid_m", "max_advance_m", "reach_m"):
            if not getattr(self, name) > 0.0:
                raise ConfigError(name, getattr(self, name), "a length > 0 m")
        if not 0.0 <= self.min_advance_m < self.max_advance_m:
            raise ConfigError("min_advance_m", self.min_advance_m, "in [0, max_advance_m)")


@dataclass(frozen=True)
class Footstep:
    """One planned touchdown."""

    foot: str
    patch: int  # index into ``course.patches``
    x_m: float
    y_m: float


def _candidates(
    course: Course, foot: str, y_nominal: float, config: FootstepPlannerConfig
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, patch index) of every grid point on the patches ``foot`` may use."""
    xs, ys, idx = [], [], []
    m = config.margin_m
    for i, p in enumerate(course.patches):
        if not p.allows(foot):
            continue
        x_lo, x_hi = p.x_min + m, p.x_max - m
        if x_hi < x_lo:
            x_lo = x_hi = p.x_center_m
        y_lo, y_hi = p.y_min + m, p.y_max - m
        if y_hi < y_lo:
            y_lo = y_hi = p.y_center_m
        x = np.arange(x_lo, x_hi + 1e-9, config.grid_m)
        y = float(np.clip(y_nominal, y_lo, y_hi))
        free = np.ones(x.size, dtype=bool)
        for ob in course.obstacles:  # nothing lands on or against an obstacle
            if ob.y_min - m <= y <= ob.y_max + m:
                free &= (x < ob.x_min - m) | (x > ob.x_max + m)
        xs.append(x[free])
        ys.append(np.full(int(free.sum()), y))
        idx.append(np.full(int(free.sum()), i))
    if not xs:
        return np.zeros(0), np.zeros(0), np.zeros(0, dtype=int)
    return np.concatenate(xs), np.concatenate(ys), np.concatenate(idx)


def plan_footsteps(
    course: Course,
    first_foot: str,
    x_stance_m: float,
    x_com_touchdown_m: float,
    y_path_m: float,
    advance_m: float,
    config: FootstepPlannerConfig | None = None,
) -> list[Footstep] | None:
    """The next ``n_steps`` footholds, ``first_foot`` first (module docstring).

    Args:
        x_stance_m: x of the standing foot (``x_0``) [m].
        x_com_touchdown_m: CoM x predicted at the first touchdown [m].
        y_path_m: lateral position of the commanded path [m].
        advance_m: nominal advance per step ``L`` [m].

    Returns:
        The planned steps (fewer than ``n_steps`` if the later ones have no feasible
        candidate), or None if no candidate satisfies the first step's constraints.
    """
    cfg = config or FootstepPlannerConfig()
    other = {"left": "right", "right": "left"}
    if first_foot not in other:
        raise ConfigError("first_foot", first_foot, "'left' or 'right'")
    foot = first_foot
    prev_x = np.array([float(x_stance_m)])
    prev_cost = np.zeros(1)
    layers: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, str]] = []
    for i in range(cfg.n_steps):
        side = 1.0 if foot == "left" else -1.0
        y_nom = y_path_m + side * cfg.lateral_offset_m
        x, y, patch = _candidates(course, foot, y_nom, cfg)
        if i == 0:
            keep = np.abs(x - x_com_touchdown_m) <= cfg.reach_m
            x, y, patch = x[keep], y[keep], patch[keep]
        d = x[None, :] - prev_x[:, None]  # (n_prev, n) advance
        total = prev_cost[:, None] + (d - advance_m) ** 2
        total = np.where((d >= cfg.min_advance_m) & (d <= cfg.max_advance_m), total, np.inf)
        back = np.argmin(total, axis=0)
        cost = total[back, np.arange(x.size)] + cfg.w_lateral * (y - y_nom) ** 2
        ok = np.isfinite(cost)
        if not np.any(ok):
            if i == 0:
                return None
            break
        layers.append((x[ok], y[ok], patch[ok], back[ok], foot))
        prev_x, prev_cost = x[ok], cost[ok]
        foot = other[foot]
    # Walk back from the cheapest end point.
    j = int(np.argmin(prev_cost))
    steps: list[Footstep] = []
    for x, y, patch, back, f in reversed(layers):
        steps.append(Footstep(f, int(patch[j]), float(x[j]), float(y[j])))
        j = int(back[j])
    return steps[::-1]
