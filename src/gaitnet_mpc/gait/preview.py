"""Multi-step footstep preview over discrete terrain: a LIP plan solved as a MILP.

The MPC bounds only its next touchdown (eq. 24, one-step preview). On stepping stones the
patch that is best for the next step can leave the following steps without a reachable
stone at the fixed step time (e.g. both feet at the far end of a stone, then a 0.32 m
step onto a one-foot stone), and a foothold forced short by a patch edge while the CoM
reference keeps the commanded speed leaves the CoM ahead of the stance foot. The paper
avoids this by hand: each patch of its Fig. 7 is triggered by a CoM region. This module
chooses the patches automatically (beyond the paper) together with a CoM path that is
dynamically consistent with them, a linear inverted pendulum (LIP) per horizontal axis:

    x'' = w^2 (x - p_x,i - u_ik),  y'' = w^2 (y - p_y,i),   w = sqrt(g / z_c)
        (stance foot p_i; sagittal CoP offset u_ik constant over MPC stage k; a line foot
        has no roll moment, so no lateral CoP offset)
    min  sum_i |(x(t_i+1) - x(t_i)) / T_i - v_cmd| + w_lat |y(t_i) - y_path| + w_cop sum |u_ik|
         + w_step sum |p_x,i+1 - p_x,i - v_cmd T| + w_width sum |width_i - width|
    s.t. p_i in the box of a patch foot i may use, shrunk by the margin (binary choice)
         |x - p_x,i| <= reach, |y - p_y,i| <= reach_y at every stage boundary of step i (*)
         -back <= p_x,i+1 - p_x,i <= max_advance, feet min..max width apart on their sides
         p_x,i+1 - p_x,i-1 <= max_swing_speed T (the swing foot's travel in a step)
    (*) and the width bounds: soft, a slack costs w_soft per metre, so that a measured
    state outside them still has a plan
         v_min <= vx <= v_max, |u_ik| <= cop

Step i = 0 is the current stance (foot position and remaining time given), the feet
alternate and each later step lasts ``stages_per_step * dt``: the fixed dt of the step
policy. Each stage is integrated exactly (``cosh``/``sinh``), so the dynamics are linear
equalities. Positions are world x (the course axis) and y.

A study of the sagittal part over the whole ``stepping-stones`` course
(``benchmarks/results/lip_stones.md``) found solutions at near-constant speed with dt
0.045-0.07 s, so the fixed-dt baseline can cross in principle.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import Bounds, LinearConstraint, milp

from gaitnet_mpc.config import bounded, check_ranges, weight
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.lip import lip_frequency
from gaitnet_mpc.robots.spec import FEET
from gaitnet_mpc.terrain import Course, Patch

__all__ = ["PreviewConfig", "PreviewPlan", "plan_areas", "plan_preview"]

_BIG_M = 50.0  # big-M of the patch constraints [m]; larger than any course
#: Ranges of a distance a leg spans and of a CoM speed (the fastest command is 1.5 m/s).
_LEG, _LEG_REASON = "(0, 1] m", "1 m is past the legs' reach"
_SPEED = "5 m/s is 3x the fastest command"


@dataclass(frozen=True)
class PreviewConfig:
    """Settings of :func:`plan_preview` (lengths in m, speeds in m/s)."""

    n_steps: int = bounded(6, "[1, 20]", "an integer", "steps after the current one")
    stages_per_step: int = bounded(5, "[1, 20]", "an integer", "h', as the gait schedule")
    # |x_com - p_stance| and |y_com - p_stance,y| at every stage boundary
    reach_m: float = bounded(0.2, _LEG, "a distance", _LEG_REASON)
    reach_y_m: float = bounded(0.2, _LEG, "a distance", _LEG_REASON)
    # lateral distance of a foot from the other, on its own side
    min_width_m: float = bounded(0.08, "[0, 1] m", "a distance", _LEG_REASON)
    max_width_m: float = bounded(0.35, _LEG, "a distance", _LEG_REASON)
    # nominal lateral distance of the feet (hips 0.13 m apart)
    width_m: float = bounded(0.13, "[0, 1] m", "a distance", _LEG_REASON)
    # |CoP - foot centre| (the line foot is +-0.075 m long)
    cop_m: float = bounded(0.04, "[0, 0.3] m", "a distance", "humanoid3d's toe: 0.075 m")
    max_advance_m: float = bounded(0.35, _LEG, "a step", _LEG_REASON)  # p_i+1 - p_i
    # Mean horizontal speed of a swing foot: bounds p_i+1 - p_i-1 by this times the step
    # time (at 0.75 m/s a steady gait needs 1.5 m/s).
    max_swing_speed_mps: float = bounded(1.7, "(0, 10] m/s", "a speed", "1.5 m/s at 0.75 m/s")
    # -(p_i+1 - p_i) allowed (0: no backward steps)
    back_m: float = bounded(0.0, "[0, 1] m", "a step", _LEG_REASON)
    v_min_mps: float = bounded(0.0, "[0, 5] m/s", "a speed", _SPEED)
    v_max_mps: float = bounded(1.3, "(0, 5] m/s", "a speed", _SPEED)
    w_cop: float = weight(0.1)  # weight of |u| against the mean-speed error of a step [1/s]
    w_step: float = weight(0.01)  # weight of the step-length deviation [1/s]
    w_lateral: float = weight(0.1)  # weight of |y_com - y_path| at step starts [1/s]
    w_width: float = weight(0.01)  # weight of the step-width deviation from width_m [1/s]
    # weight of a violated reach or width bound [1/s per m]
    w_soft: float = bounded(100.0, "(0, 1e9]", "a weight", "> 0, or a violation is free")
    time_limit_s: float = bounded(2.0, "(0, 60] s", "a time limit", "of one MILP solve")
    every_solve: bool = True  # re-plan at every MPC solve (else at step starts only)
    # Lateral margin of a foot centre inside a patch (the x margin is the controller's):
    # the line foot is 2 cm wide.
    foothold_margin_y_m: float = bounded(
        0.03, "[0, 0.1] m", "a margin", "under half the narrowest built-in stone, 0.20 m"
    )

    def __post_init__(self) -> None:
        for name in ("n_steps", "stages_per_step"):
            value = getattr(self, name)
            if not isinstance(value, int):
                raise ConfigError(name, value, "an integer")
        check_ranges(self)
        if self.v_min_mps >= self.v_max_mps:
            raise ConfigError("v_min_mps", self.v_min_mps, f"< v_max_mps = {self.v_max_mps}")
        if self.min_width_m > self.max_width_m:
            raise ConfigError(
                "min_width_m", self.min_width_m, f"<= max_width_m = {self.max_width_m}"
            )


@dataclass(frozen=True)
class PreviewPlan:
    """Footholds and CoM path of one preview solve (world frame, times from the solve)."""

    feet: tuple[str, ...]  # stance foot of step i (step 0: the current stance)
    foothold_m: np.ndarray  # (n+1, 2) p_i in x, y (step 0: the measured stance foot)
    patch: tuple[int, ...]  # index of each p_i's area in plan_areas (step 0: -1, given)
    times_s: np.ndarray  # (S+1,) stage boundaries from now
    com_m: np.ndarray  # (S+1, 2) CoM x, y
    com_v_mps: np.ndarray  # (S+1, 2)
    cop_offset_m: np.ndarray  # (S,) sagittal CoP offset u of each stage
    max_violation_m: float  # largest slack of a soft (reach, width) bound; 0: all held

    def com_at(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """CoM position (n_t, 2) [m] and velocity (n_t, 2) [m/s] at times ``t_s`` from the
        solve (linear interpolation between stage boundaries, held after the last)."""
        t = np.asarray(t_s, dtype=float)

        def at(values: np.ndarray) -> np.ndarray:
            return np.stack([np.interp(t, self.times_s, values[:, a]) for a in range(2)], -1)

        return at(self.com_m), at(self.com_v_mps)


class _Program:
    """Rows ``lo <= A z <= hi`` and variable bounds of a MILP, built term by term."""

    def __init__(self) -> None:
        self.n = 0
        self.lo: list[float] = []
        self.hi: list[float] = []
        self.integer: list[bool] = []
        self.cost: list[float] = []
        self.rows: list[int] = []
        self.cols: list[int] = []
        self.vals: list[float] = []
        self.rlo: list[float] = []
        self.rhi: list[float] = []
        self.slacks: list[int] = []

    def var(self, size: int, lo: float = -np.inf, hi: float = np.inf, cost: float = 0.0,
            integer: bool = False) -> np.ndarray:  # fmt: skip
        first = self.n
        self.n += size
        self.lo += [lo] * size
        self.hi += [hi] * size
        self.cost += [cost] * size
        self.integer += [integer] * size
        return np.arange(first, self.n)

    def fix(self, col: int, value: float) -> None:
        self.lo[col] = self.hi[col] = value

    def row(self, terms: list[tuple[int, float]], lo: float, hi: float) -> None:
        r = len(self.rlo)
        for col, a in terms:
            self.rows.append(r)
            self.cols.append(int(col))
            self.vals.append(a)
        self.rlo.append(lo)
        self.rhi.append(hi)

    def soft_row(self, terms: list[tuple[int, float]], lo: float, hi: float, cost: float) -> None:
        """``lo <= sum terms <= hi`` up to a slack ``e >= 0`` with ``cost`` per unit."""
        e = int(self.var(1, 0.0, np.inf, cost)[0])
        self.slacks.append(e)
        self.row([*terms, (e, 1.0)], lo, np.inf)
        self.row([*terms, (e, -1.0)], -np.inf, hi)

    def abs_of(self, terms: list[tuple[int, float]], offset: float, cost: float) -> None:
        """A variable ``e >= |sum terms - offset|`` with ``cost`` per unit."""
        e = int(self.var(1, 0.0, np.inf, cost)[0])
        self.row([(e, 1.0)] + [(c, -a) for c, a in terms], -offset, np.inf)
        self.row([(e, 1.0), *terms], offset, np.inf)

    def solve(self, time_limit_s: float) -> np.ndarray | None:
        A = sp.csr_matrix((self.vals, (self.rows, self.cols)), shape=(len(self.rlo), self.n))
        res = milp(
            np.asarray(self.cost),
            constraints=LinearConstraint(A, self.rlo, self.rhi),
            integrality=np.asarray(self.integer, dtype=float),
            bounds=Bounds(self.lo, self.hi),
            options={"time_limit": time_limit_s},
        )
        return None if res.x is None else res.x


def plan_areas(
    course: Course, obstacle_clearance_m: float | None, margin_m: tuple[float, float]
) -> tuple[Patch, ...]:
    """The areas a preview plans footholds on: the course's patches (None), or its landing
    areas with the obstacles' footprints widened by ``obstacle_clearance_m`` cut out, as
    the one-step preview's (:meth:`Course.foothold_areas` with the (x, y) margins
    ``margin_m``)."""
    return course.foothold_areas(obstacle_clearance_m, *margin_m)[0]


def plan_preview(
    course: Course,
    config: PreviewConfig,
    *,
    com_m: np.ndarray,
    com_v_mps: np.ndarray,
    com_height_m: float,
    stance_foot: str,
    stance_m: np.ndarray,
    liftoff_m: np.ndarray,
    time_left_s: float,
    dt_s: float,
    v_cmd_mps: float,
    y_path_m: float,
    margin_m: tuple[float, float],
    first_patch: int | None = None,
    obstacle_clearance_m: float | None = None,
) -> PreviewPlan | None:
    """Solve the preview MILP (module docstring) from the measured CoM state.

    Args:
        com_m, com_v_mps: CoM position [m] and velocity [m/s] in x, y (2,) now.
        com_height_m: z_c, the CoM height above the stance foot [m].
        stance_foot: ``"left"`` or ``"right"``, the foot standing now (step 0).
        stance_m: its x, y (2,) [m].
        liftoff_m: x, y (2,) [m] where the swinging foot lifted off.
        time_left_s: time to the next touchdown [s] (split into whole stages of ~dt).
        dt_s: MPC sampling time of the following steps [s] (the fixed-dt policy).
        v_cmd_mps: commanded forward speed [m/s].
        y_path_m: lateral position of the commanded path [m] (the CoM sways about it).
        margin_m: (x, y) distance of the foot centre from a patch's edges [m].
        first_patch: index (in :func:`plan_areas`) of the area the next touchdown must
            use (None: free).
        obstacle_clearance_m: plan on the landing areas, the patches with the obstacles'
            footprints widened by this much cut out (:func:`plan_areas`); None: on the
            whole patches.

    Returns:
        The plan, or ``None`` when the program has no solution (e.g. the CoM is already
        out of reach of every patch) or the time limit passed without one.
    """
    if stance_foot not in FEET:
        raise ConfigError("stance_foot", stance_foot, f"one of {FEET}")
    for name, value in (
        ("time_left_s", time_left_s),
        ("dt_s", dt_s),
        ("com_height_m", com_height_m),
    ):
        if not (math.isfinite(value) and value > 0.0):
            raise ConfigError(name, value, "a finite number > 0")
    c = config
    n = c.n_steps
    n0 = max(1, round(time_left_s / dt_s))
    stage_dt = np.concatenate([np.full(n0, time_left_s / n0), np.full(n * c.stages_per_step, dt_s)])
    starts = np.concatenate([[0], n0 + c.stages_per_step * np.arange(n)])  # first stage of step i
    stage_step = np.searchsorted(starts, np.arange(stage_dt.size), side="right") - 1
    S = stage_dt.size
    other = FEET[1 - FEET.index(stance_foot)]
    feet = tuple(stance_foot if i % 2 == 0 else other for i in range(n + 1))
    x0, y0 = float(com_m[0]), float(com_m[1])
    x_far = x0 + (n + 1) * c.max_advance_m + 0.5  # patches the plan may reach
    areas = plan_areas(course, obstacle_clearance_m, margin_m)
    near = [
        j
        for j, p in enumerate(areas)
        if p.x_max - margin_m[0] > x0 - 0.5
        and p.x_min + margin_m[0] < x_far
        and p.x_max - p.x_min > 2 * margin_m[0]
    ]

    prog = _Program()
    px, py = prog.var(n + 1), prog.var(n + 1)  # footholds
    u = prog.var(S, -c.cop_m, c.cop_m)  # sagittal CoP offsets
    x, vx = prog.var(S + 1), prog.var(S + 1, c.v_min_mps, c.v_max_mps)
    y, vy = prog.var(S + 1), prog.var(S + 1)
    prog.fix(px[0], float(stance_m[0]))
    prog.fix(py[0], float(stance_m[1]))
    prog.fix(x[0], x0)
    for k in range(n0):  # the measured speed may lie outside [v_min, v_max]
        prog.lo[vx[k]], prog.hi[vx[k]] = -np.inf, np.inf
    prog.fix(vx[0], float(com_v_mps[0]))
    prog.fix(y[0], y0)
    prog.fix(vy[0], float(com_v_mps[1]))

    w = lip_frequency(com_height_m)
    for k in range(S):
        ch, sh = math.cosh(w * stage_dt[k]), math.sinh(w * stage_dt[k])
        i = int(stage_step[k])
        # Exact LIP stage about the CoP c: q+ = ch (q - c) + sh/w v + c, v+ = w sh (q - c)
        # + ch v; sagittal c = p_x + u, lateral c = p_y (a line foot has no roll moment).
        for q, v, cop in ((x, vx, [(px[i], 1.0), (u[k], 1.0)]), (y, vy, [(py[i], 1.0)])):
            prog.row(
                [(q[k + 1], 1), (q[k], -ch), (v[k], -sh / w)]
                + [(cc, (ch - 1) * a) for cc, a in cop],
                0,
                0,
            )
            prog.row(
                [(v[k + 1], 1), (q[k], -w * sh), (v[k], -ch)] + [(cc, w * sh * a) for cc, a in cop],
                0,
                0,
            )
        for q, p, r in ((x, px, c.reach_m), (y, py, c.reach_y_m)):
            if i > 0:  # (the current stance is as measured)
                for kk in (k, k + 1):  # reach at each stage start and end
                    prog.soft_row([(q[kk], 1), (p[i], -1)], -r, r, c.w_soft)
        prog.abs_of([(u[k], 1.0)], 0.0, c.w_cop)
    bounds = [*starts.tolist(), S]
    for k0, k1 in itertools.pairwise(bounds):  # mean speed of each step
        t_step = float(np.sum(stage_dt[k0:k1]))
        prog.abs_of([(x[k1], 1.0 / t_step), (x[k0], -1.0 / t_step)], v_cmd_mps, 1.0)
    for k0 in bounds:
        prog.abs_of([(y[k0], 1.0)], y_path_m, c.w_lateral)
    step_m = v_cmd_mps * c.stages_per_step * dt_s  # nominal step advance
    stride_m = c.max_swing_speed_mps * c.stages_per_step * dt_s  # largest swing travel
    choices: list[tuple[list[int], np.ndarray]] = []
    for i in range(1, n + 1):
        prog.row([(px[i], 1), (px[i - 1], -1)], -c.back_m, c.max_advance_m)
        # swing travel of foot i from its previous foothold (step 1: its lift-off)
        if i == 1:
            prog.row([(px[1], 1)], -np.inf, float(liftoff_m[0]) + stride_m)
        else:
            prog.row([(px[i], 1), (px[i - 2], -1)], -np.inf, stride_m)
        prog.abs_of([(px[i], 1.0), (px[i - 1], -1.0)], step_m, c.w_step)
        side = 1.0 if feet[i] == "left" else -1.0  # foot i beside foot i-1 on its own side
        prog.soft_row([(py[i], side), (py[i - 1], -side)], c.min_width_m, c.max_width_m, c.w_soft)
        prog.abs_of([(py[i], side), (py[i - 1], -side)], c.width_m, c.w_width)
        choice = [j for j in near if areas[j].allows(feet[i])]
        if i == 1 and first_patch is not None:
            choice = [j for j in choice if j == first_patch]
        if not choice:
            return None
        s = prog.var(len(choice), 0.0, 1.0, integer=True)
        prog.row([(sj, 1.0) for sj in s], 1, 1)
        for j, sj in zip(choice, s, strict=True):
            lo, hi = areas[j].foothold_box(*margin_m)
            for p, a in ((px[i], 0), (py[i], 1)):
                prog.row([(p, 1), (sj, -_BIG_M)], lo[a] - _BIG_M, np.inf)
                prog.row([(p, 1), (sj, _BIG_M)], -np.inf, hi[a] + _BIG_M)
        choices.append((choice, s))
    z = prog.solve(c.time_limit_s)
    if z is None:
        return None
    patch = [-1] + [choice[int(np.argmax(z[s]))] for choice, s in choices]
    return PreviewPlan(
        feet=feet,
        foothold_m=np.stack([z[px], z[py]], -1),
        patch=tuple(patch),
        times_s=np.concatenate([[0.0], np.cumsum(stage_dt)]),
        com_m=np.stack([z[x], z[y]], -1),
        com_v_mps=np.stack([z[vx], z[vy]], -1),
        cop_offset_m=z[u],
        max_violation_m=float(max(z[prog.slacks], default=0.0)),
    )
