"""Algorithm 1: the sequential convex MPC of the implicit kino-dynamic controller.

One solve of a :class:`KDProblem`::

    x_0   = f_j2m(q, v)                                  (line 1)
    ref   = f_ref(q, command, footholds, dt^0)           (lines 2-3)
    u^0   = references (weight shared by stance feet)    (line 4)
    repeat j = 0 .. j_max - 1:                            (line 5)
        du^j   = cmpc(x_ref, p_f_ref, p_c_ref, x_0, dt^j, u^j)     (line 6, eqs. 13-24)
        u^j+1  = u^j + du^j                                         (line 7)
        dt^j+1 = dt_policy(problem, u^j+1, dt^j)                    (line 8: Gait-Net slot)
        ref    = f_IK(p_f^j+1, p_c^j+1, dt^j+1)                     (line 9, Remark 1)
    until every search direction is below Table X's tolerances and dt has settled.

The dt policy acts only where the problem asks for it, at a step start (Remark 4); its dt
becomes the sampling time of every stage (the paper's single MPC dt; a partial stage 0 is
scaled with it). During a step the same dt is kept and the loop re-solves footholds and
wrenches, warm-started from the previous plan's footholds.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Protocol, cast

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.dt_policy import (
    ACCEPTED_DT_INTERVAL,
    ACCEPTED_DT_RANGE_S,
    ACCEPTED_DT_REASON,
    NOMINAL_DT_S,
)
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.kinematics.centroidal import euler_map_and_coordinates, f_j2m
from gaitnet_mpc.kinematics.reference import (
    POSE_METHODS,
    CentroidalReference,
    PoseMethod,
    ReferenceConfig,
    ReferenceTiming,
    ReferenceWorkspace,
    make_reference,
    update_reference,
)
from gaitnet_mpc.mpc.implicit_kd import (
    KDConfig,
    KDIterate,
    KDStep,
    KDSubproblem,
    KDTolerances,
)
from gaitnet_mpc.mpc.kd_iterate import shift_iterate
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.state import RobotState


@dataclass(frozen=True)
class FootholdBox:
    """Eq. 24 box of one foot's next touchdown: ``lo_m <= p_f <= hi_m`` (3,) [m] (an
    infinite entry leaves that axis free)."""

    lo_m: np.ndarray
    hi_m: np.ndarray


@dataclass(frozen=True)
class CoMReference:
    """CoM path ``p_m`` and velocity ``v_mps`` (h+1, 3) that replace ``f_ref``'s in eq. 18's
    CoM term, the linear centroidal pose ``m p_c`` and the linear momentum ``m v_c``; NaN
    entries keep ``f_ref``'s value."""

    p_m: np.ndarray
    v_mps: np.ndarray


@dataclass(frozen=True)
class StepState:
    """The measured state at a step start, with the step's stance and swing foot."""

    state: RobotState
    stance_foot: str
    swing_foot: str


@dataclass(frozen=True)
class KDProblem:
    """Everything one solve of Algorithm 1 needs (world frame, Pinocchio coordinates).

    Attributes:
        q, v: measured configuration and velocity.
        timing: stage durations ``dt^0`` and contact sequence from now.
        command: velocity command, already ramped.
        heading_rad: commanded trunk heading at the start of the horizon [rad]; yaw in the
            centroidal pose is measured from it.
        footholds_m: foot -> (n, 3) initial touchdown targets of its swings in the horizon
            (the warm start ``u^0``; the MPC moves them).
        p_foot_now_m: foot -> (3,) measured foot centres.
        p_liftoff_m: foot -> (3,) lift-off point of the foot swinging now.
        foot_yaw_rad: (h, 2) foot headings for the line-foot wrench limits.
        foothold_boxes: foot -> eq. 24 box of its next touchdown.
        p_com_start_m: start of the reference CoM path (None: the measured CoM); a point on
            the commanded path lets the MPC correct drift.
        com_reference: function of the timing giving the CoM reference that replaces
            ``f_ref``'s (e.g. a LIP sway orbit over the footholds); it is called again
            when the dt changes (line 9). None: ``f_ref``'s.
        j_max: iteration cap (None: ``SequentialConfig.j_max``).
        choose_dt: True at a step start: the solver's dt policy sets the stage durations
            inside the iterations (line 8). False: ``timing`` is kept (Remark 4).
        step_index: index of the step the horizon starts in (0 = the first step); a
            policy that gives each step a set dt (:class:`ScheduledDt`) reads it.
        state: the measured state with the stance and swing foot of the step, for a dt
            policy that reads more than ``q`` and ``v`` (Gait-Net's features); None if the
            caller gives none.
        warm_start: a previous plan (its ``t_plan_s`` on the clock of ``t_s``) to start
            the iterations from, shifted to this horizon (:func:`shift_iterate`); None:
            :meth:`KDIterate.initial`.
        t_s: time of the measurement [s] (read with ``warm_start`` only).
        wrench_ext: (6,) estimated external wrench ``[f_ext (N); tau_ext about the CoM
            (N m)]``, held through the horizon (an affine term of eqs. 14-15; the
            disturbance observer's); None: none.
    """

    q: np.ndarray
    v: np.ndarray
    timing: ReferenceTiming
    command: Command
    heading_rad: float
    footholds_m: Mapping[str, np.ndarray]
    p_foot_now_m: Mapping[str, np.ndarray]
    p_liftoff_m: Mapping[str, np.ndarray]
    foot_yaw_rad: np.ndarray
    foothold_boxes: Mapping[str, FootholdBox] = field(default_factory=dict)
    p_com_start_m: np.ndarray | None = None
    com_reference: Callable[[ReferenceTiming], CoMReference | None] | None = None
    j_max: int | None = None
    choose_dt: bool = False
    step_index: int = 0
    state: StepState | None = None
    warm_start: SequentialResult | None = None
    t_s: float = 0.0
    wrench_ext: np.ndarray | None = None


class DtPolicy(Protocol):
    """Chooses the MPC sampling time of the step that is starting (Alg. 1, line 8)."""

    @property
    def nominal_dt_s(self) -> float:
        """``dt^0`` [s] of the first step, before the policy has seen a plan."""
        ...

    def __call__(self, problem: KDProblem, iterate: KDIterate, dt_s: float) -> float:
        """The next dt [s] given the problem (measured state) and the current iterate
        (footholds and CoM path of ``u^{j+1}``), whose stages last ``dt_s``."""
        ...


@dataclass(frozen=True)
class FixedDt:
    """The paper's baseline 1 (Fig. 6a): the same dt for every step."""

    dt_s: float = NOMINAL_DT_S

    @property
    def nominal_dt_s(self) -> float:
        return self.dt_s

    def __call__(self, problem: KDProblem, iterate: KDIterate, dt_s: float) -> float:
        return self.dt_s


class StepDtSchedule(Protocol):
    """A dt set per step in advance, e.g.
    :class:`~gaitnet_mpc.gait.step_durations.StepDurations`."""

    def dt_of_step(self, step_index: int) -> float:
        """MPC sampling time [s] of step ``step_index``."""
        ...


@dataclass(frozen=True)
class ScheduledDt:
    """Each step's dt from a schedule set in advance, blind to the plan: the teacher of
    data collection (Sec. IV-A-1) with durations drawn per stride."""

    schedule: StepDtSchedule

    @property
    def nominal_dt_s(self) -> float:
        return float(self.schedule.dt_of_step(0))

    def __call__(self, problem: KDProblem, iterate: KDIterate, dt_s: float) -> float:
        return float(self.schedule.dt_of_step(problem.step_index))


@dataclass(frozen=True)
class SequentialConfig:
    """Settings of the sequential loop (paper Table X)."""

    j_max: int = bounded(50, "[1, 1000]", "an integer", "iterations; Table X: 50")
    tolerances: KDTolerances = field(default_factory=KDTolerances)
    kd: KDConfig = field(default_factory=KDConfig)
    update_foot_reference: bool = True  # Alg. 1 line 9 re-makes p_f_ref from the iterate
    linear_reference_from_command: bool = True
    # The dt policy's output is clipped into these bounds [s] (GaitScheduleConfig's), and a
    # change smaller than ``dt_tolerance_s`` is not applied (the references stay as they are).
    dt_bounds_s: tuple[float, float] = bounded(
        ACCEPTED_DT_RANGE_S, ACCEPTED_DT_INTERVAL, "a sampling time", ACCEPTED_DT_REASON, True
    )
    dt_tolerance_s: float = bounded(
        1e-4, "[0, 0.01] s", "a dt change", "a coarser one drops most changes within 0.045-0.07 s"
    )
    # H_ref of f_ref / f_IK (ReferenceConfig.pose_method): "riemann", the left Riemann sum
    # that the MPC's eq. 10 propagates (linear part m p_c exactly); "eq30", the paper's
    # integration by parts (eq. 12 = eq. 30).
    reference_pose: str = "riemann"

    def __post_init__(self) -> None:
        if not isinstance(self.j_max, int):
            raise ConfigError("j_max", self.j_max, "an integer")
        if self.reference_pose not in POSE_METHODS:
            raise ConfigError("reference_pose", self.reference_pose, f"one of {list(POSE_METHODS)}")
        check_ranges(self)


@dataclass
class SequentialResult:
    """Outcome of one sequential solve."""

    iterate: KDIterate
    reference: CentroidalReference
    dts_s: np.ndarray  # (h,) stage durations the plan was made with [s]
    contact: np.ndarray  # (h, 2) stance mask
    n_qps: int
    converged: bool
    solve_time_s: float
    last_step: KDStep | None
    step_dt_s: float  # the step's MPC dt the plan was made with (the policy's) [s]
    cost: float = math.nan  # eq. 18 at the plan (KDSubproblem.plan_cost)
    t_plan_s: float = 0.0
    foothold_boxes: Mapping[str, FootholdBox] = field(default_factory=dict)  # the problem's

    def covers(self, t_s: float, dts_s: np.ndarray) -> bool:
        """Whether this plan reaches the end of a horizon of stages ``dts_s`` [s] that starts
        at ``t_s`` [s] (else the horizon has stages past it, which a shifted warm start
        fills with references)."""
        return t_s + float(np.sum(dts_s)) <= self.t_plan_s + float(np.sum(self.dts_s)) + 1e-9

    def stage_at(self, t_s: float) -> int:
        """Index of the plan's stage that contains time ``t_s`` (clamped)."""
        boundaries = self.t_plan_s + np.cumsum(self.dts_s)
        return min(int(np.searchsorted(boundaries, t_s, side="right")), len(self.dts_s) - 1)

    def touchdown(self, foot: str) -> np.ndarray | None:
        """(3,) planned touchdown of ``foot``: its position in its next stance stage."""
        i = FEET.index(foot)
        col = self.contact[:, i]
        swinging = np.flatnonzero(~col)
        if swinging.size == 0:
            return None
        after = np.flatnonzero(col[swinging[0] :])
        if after.size == 0:
            return self.iterate.p_foot[swinging[0], i]
        return self.iterate.p_foot[swinging[0] + after[0], i]


def mpc_foot_reference(ref: CentroidalReference, contact: np.ndarray) -> np.ndarray:
    """(h, 2, 3) foothold reference per stage: where a stance foot stands, and for a
    swinging foot its next touchdown (the sub-problem ties swing stages to it)."""
    out = np.zeros((contact.shape[0], 2, 3))
    for i, foot in enumerate(FEET):
        holds = np.asarray(ref.footholds_m[foot])
        stand = np.asarray(contact[:, i], dtype=bool)
        j = np.asarray(ref.foothold_index[: stand.size, i], dtype=int) + ~stand
        out[:, i] = holds[np.minimum(j, len(holds) - 1)]
    return out


def angular_pose_kgm2(
    robot: RobotModel, data: object, q: np.ndarray, yaw_origin_rad: float
) -> np.ndarray:
    """Angular part of the centroidal pose at one configuration, ``[A_xi(q) xi]_ang`` (3,).

    This is eq. 30 at the first sample (the sum is empty), in Euler coordinates
    ``xi = [p_base, rpy, joints]`` (``A_xi`` maps ``xi_dot`` to momentum). Its trunk part is
    about the composite inertia times the roll/pitch/yaw angles, so tracking ``H`` holds
    the trunk orientation. The yaw coordinate is taken relative to ``yaw_origin_rad`` so
    that long turns do not wrap.
    """
    a_xi, xi = euler_map_and_coordinates(robot.pin_model, data, q)
    if not robot.spec.planar:
        # wrapped as (a + pi) mod 2 pi - pi, not geometry.wrap_angle: the atan2 form differs in
        # the last bit and changes the closed-loop logs (measured)
        xi[5] = (xi[5] - yaw_origin_rad + np.pi) % (2 * np.pi) - np.pi
    return (a_xi @ xi)[3:]


class SequentialKDMPC:
    """The implicit kino-dynamic MPC solved by sequential convex QPs (Algorithm 1).

    ``dt_policy`` (default :class:`FixedDt`) is consulted inside the iterations of a
    problem with ``choose_dt`` (line 8).
    """

    def __init__(
        self,
        robot: RobotModel,
        config: SequentialConfig | None = None,
        dt_policy: DtPolicy | None = None,
    ) -> None:
        self.robot = robot
        self.config = config or SequentialConfig()
        self.dt_policy: DtPolicy = dt_policy or FixedDt()
        self.subproblem = KDSubproblem(self.config.kd)
        pose_method = cast(PoseMethod, self.config.reference_pose)  # checked in the config
        self.ref_workspace = ReferenceWorkspace(robot, ReferenceConfig(pose_method=pose_method))
        self.pin_data = robot.pin_model.createData()

    def _references(
        self, problem: KDProblem, timing: ReferenceTiming, footholds: Mapping[str, np.ndarray]
    ) -> _References:
        """``f_ref`` on ``timing`` (lines 2-3) with the problem's CoM override applied."""
        robot = self.robot
        mass = robot.total_mass_kg
        ref = make_reference(
            robot,
            problem.q,
            timing,
            problem.command,
            footholds,
            p_foot_now_m=problem.p_foot_now_m,
            p_liftoff_m=problem.p_liftoff_m,
            p_com_start_m=problem.p_com_start_m,
            workspace=self.ref_workspace,
        )
        # The reference's angular pose starts at 0; H_ref's angular part is additive in its
        # start value (eq. 30 and the Riemann sum alike), so shift it to the same map of
        # q_ref[0] instead of building the reference a second time.
        pose0_ref = angular_pose_kgm2(robot, self.pin_data, ref.q_ref[0], problem.heading_rad)
        H_ref = ref.H_ref.copy()
        H_ref[:, 3:] += pose0_ref - ref.pose0_angular_kgm2
        ref = replace(ref, H_ref=H_ref, pose0_angular_kgm2=pose0_ref)
        p_com_ref = ref.p_com_ref  # f_ref's CoM path; line 9 updates x_ref and p_f_ref only
        h_lin_ref, pose_lin_ref = ref.h_ref[:, :3].copy(), ref.H_ref[:, :3].copy()
        h_ref, pose_ref = ref.h_ref, ref.H_ref
        com = problem.com_reference(timing) if problem.com_reference is not None else None
        if com is not None:
            pc, vc = np.asarray(com.p_m, dtype=float), np.asarray(com.v_mps, dtype=float)
            p_com_ref = np.where(np.isnan(pc), p_com_ref, pc)
            pose_lin_ref = np.where(np.isnan(pc), pose_lin_ref, mass * pc)
            h_lin_ref = np.where(np.isnan(vc), h_lin_ref, mass * vc)
            h_ref = np.hstack([h_lin_ref, ref.h_ref[:, 3:]])
            pose_ref = np.hstack([pose_lin_ref, ref.H_ref[:, 3:]])
        return _References(
            ref, h_ref, pose_ref, p_com_ref, h_lin_ref, pose_lin_ref, com is not None
        )

    def _f_ik(
        self,
        r: _References,
        iterate: KDIterate,
        dts: np.ndarray,
        contact: np.ndarray,
        pf_ref: np.ndarray,
    ) -> tuple[_References, np.ndarray, np.ndarray, np.ndarray]:
        """Line 9: the references re-made from ``iterate`` (f_IK), with eq. 18's tracked
        momentum, pose and foot references."""
        cfg = self.config
        ref = update_reference(self.robot, r.ref, iterate.p_foot, iterate.p_com, dts)
        r = replace(r, ref=ref)
        h_ref, pose_ref = ref.h_ref, ref.H_ref
        if cfg.linear_reference_from_command or r.com_override:
            h_ref = np.hstack([r.h_lin_ref, ref.h_ref[:, 3:]])
            pose_ref = np.hstack([r.pose_lin_ref, ref.H_ref[:, 3:]])
        if cfg.update_foot_reference:
            pf_ref = mpc_foot_reference(ref, contact)
        return r, h_ref, pose_ref, pf_ref

    def _next_dt(self, problem: KDProblem, iterate: KDIterate, dt_s: float) -> float:
        """Line 8: the policy's dt for the step, clipped into ``dt_bounds_s`` [s]."""
        lo, hi = self.config.dt_bounds_s
        dt = float(self.dt_policy(problem, iterate, dt_s))
        if not math.isfinite(dt):
            raise ConfigError("dt_policy output", dt, f"a sampling time in [{lo}, {hi}] s")
        return min(max(dt, lo), hi)

    def solve(self, problem: KDProblem) -> SequentialResult:
        """Run Algorithm 1 on ``problem`` from its measured state."""
        t0 = time.perf_counter()
        cfg = self.config
        robot = self.robot
        mass = robot.total_mass_kg
        q, v = problem.q, problem.v
        # Centroidal pose: measured H_0 and the reference's H_0 from the same map (eq. 30),
        # with yaw measured from the commanded heading at the start of the horizon.
        pose0_meas = angular_pose_kgm2(robot, self.pin_data, q, problem.heading_rad)
        timing = problem.timing
        r = self._references(problem, timing, problem.footholds_m)
        h0 = f_j2m(robot.pin_model, self.pin_data, q, v)
        com0 = np.array(self.pin_data.com[0])
        x0 = np.concatenate([mass * com0, pose0_meas, h0])
        contact = np.asarray(timing.contact, dtype=bool)
        dts = np.asarray(timing.dts_s, dtype=float)
        dt = float(timing.stage_lengths_s[0])  # the step's dt^j (full stage 0)
        p_measured = np.stack([np.asarray(problem.p_foot_now_m[f], dtype=float) for f in FEET])
        boxes = {f: (b.lo_m, b.hi_m, None) for f, b in problem.foothold_boxes.items()}
        pf_ref = mpc_foot_reference(r.ref, contact)
        h_ref, pose_ref = r.h_ref, r.pose_ref
        iterate = KDIterate.initial(com0, r.p_com_ref, pf_ref, contact, mass)
        prev = problem.warm_start
        if prev is not None:
            iterate = shift_iterate(
                prev.iterate, prev.dts_s, prev.contact, problem.t_s - prev.t_plan_s, dts,
                contact, iterate,
            )  # fmt: skip
            r, h_ref, pose_ref, pf_ref = self._f_ik(r, iterate, dts, contact, pf_ref)
        step: KDStep | None = None
        converged = False
        n_qps = 0
        j_max = problem.j_max or cfg.j_max
        sub = self.subproblem
        inputs = None
        for _ in range(j_max):
            if inputs is None:
                inputs = sub.inputs(
                    iterate, x0, h_ref, pose_ref, pf_ref, r.p_com_ref, dts, contact,
                    problem.foot_yaw_rad, boxes or None, p_measured, problem.wrench_ext,
                )  # fmt: skip
            else:  # the same state, contacts and boxes: only the references and dts move
                inputs = inputs.with_references(h_ref, pose_ref, pf_ref, r.p_com_ref, dts)
            step = sub.solve(iterate, inputs)
            n_qps += 1
            iterate = iterate.apply(step, 1.0)
            retimed = False
            if problem.choose_dt:
                dt_new = self._next_dt(problem, iterate, dt)
                if abs(dt_new - dt) > cfg.dt_tolerance_s:
                    timing = timing.with_dts(dts * (dt_new / dt))
                    dts = np.asarray(timing.dts_s, dtype=float)
                    dt, retimed = dt_new, True
                    touchdowns = planned_touchdowns(iterate, contact)
                    r = self._references(problem, timing, touchdowns)
            if step.converged(cfg.tolerances) and not retimed:
                converged = True
                break
            if n_qps == j_max:  # no QP follows: line 9 would re-make references unused
                break
            r, h_ref, pose_ref, pf_ref = self._f_ik(r, iterate, dts, contact, pf_ref)
        return SequentialResult(
            iterate=iterate,
            reference=r.ref,
            dts_s=dts,
            contact=contact,
            n_qps=n_qps,
            converged=converged,
            solve_time_s=time.perf_counter() - t0,
            last_step=step,
            step_dt_s=dt,
            cost=(
                math.nan
                if step is None or inputs is None
                else sub.plan_cost(iterate, step.states, inputs)
            ),
            foothold_boxes=problem.foothold_boxes,
        )


@dataclass(frozen=True)
class _References:
    """The references of one timing: ``f_ref`` / ``f_IK`` output and what eq. 18 tracks."""

    ref: CentroidalReference
    h_ref: np.ndarray  # (h+1, 6) momentum reference
    pose_ref: np.ndarray  # (h+1, 6) centroidal-pose reference
    p_com_ref: np.ndarray  # (h+1, 3) CoM reference [m]
    h_lin_ref: np.ndarray  # (h+1, 3) linear momentum of f_ref (or the CoM override)
    pose_lin_ref: np.ndarray  # (h+1, 3) m p_c of f_ref (or the CoM override)
    com_override: bool


def planned_touchdowns(iterate: KDIterate, contact: np.ndarray) -> dict[str, np.ndarray]:
    """foot -> (n, 3) the iterate's footholds of the swings in the horizon, in order."""
    out: dict[str, np.ndarray] = {}
    for i, foot in enumerate(FEET):
        col = contact[:, i]
        starts = [k for k in range(1, col.size) if col[k] and not col[k - 1]]
        out[foot] = iterate.p_foot[starts, i] if starts else iterate.p_foot[-1:, i]
    return out
