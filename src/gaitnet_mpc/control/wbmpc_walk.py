"""``wbmpc``: walking with the whole-body NMPC of paper Sec. III-A (the teacher of Gait-Net).

Per control tick (1 kHz):

* advance the gait schedule; at a step start take the step's MPC sampling time from
  :class:`~gaitnet_mpc.gait.step_durations.StepDurations` (fixed ``--dt``, or drawn per
  stride for data collection) and tell the schedule the next step's;
* at every stage boundary of the schedule, solve the NMPC (eqs. 1-4) from the measured
  state, warm-started from the previous solution shifted by one stage: the horizon starts
  in the current stage of the current step, every stage of a step lasts that step's dt,
  and stage 0 lasts what is left of the current stage;
* apply the first stage's joint torques plus a joint PD toward the predicted state
  (interpolated between nodes 0 and 1 over stage 0).

Every step of the horizon has its own dt (drawn durations are known ahead), the footholds
of the reference use the duration of the stance after their touchdown, the front foot
swings first, and the reference returns to the commanded heading and path
(``heading_return_time_s``, ``lateral_return_time_s``); see
``docs/design/wholebody_nmpc.md`` for the measurements behind each.

Re-solving once per stage (every 30-80 ms) is the issue's minimum; the solve takes
~0.1-0.2 s of CPU on the humanoid, so a 100 Hz re-solve would make data collection about
3x slower (``benchmarks/results/wbmpc.md``). The reference of eq. 2 is the project's
joint-space walking reference ``f_ref`` (:func:`~gaitnet_mpc.kinematics.make_reference`,
the one ``kd`` starts Algorithm 1 from): the CoM along the commanded path (from a point
within ``path_max_error_m`` of the measured CoM, so a push does not wind it up), swing
feet to Raibert footholds, legs by the analytic IK. A standing posture carried along the
path instead made the plan walk at a fraction of the command (biped 0.5 m/s: 0.19 m in
3 s), as every joint's deviation from the posture costs and no step is demanded.
The NMPC knows nothing of the terrain beyond the ground height at the start: it
is made for flat ground (the data-collection protocol), and says so in the run's
``terrain_knowledge``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.control.lowlevel import LowLevelConfig
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.control.walking import (
    ACCEL_INTERVAL,
    ACCEL_REASON,
    RETURN_INTERVAL,
    RETURN_REASON,
)
from gaitnet_mpc.control.walking_base import WalkingBase
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait import GaitSchedule, GaitScheduleConfig, RaibertConfig, RaibertHeuristic
from gaitnet_mpc.gait.lip import lip_gains, lip_propagate
from gaitnet_mpc.gait.step_durations import StepDurations
from gaitnet_mpc.geometry import heading_axes, rotate2, to_heading2, wrap_angle
from gaitnet_mpc.kinematics.reference import ReferenceTiming, ReferenceWorkspace, make_reference
from gaitnet_mpc.mpc.wholebody import (
    WBConfig,
    WBProblem,
    WBSolution,
    WBWeights,
    WholeBodyMPC,
)
from gaitnet_mpc.mpc.wholebody.nlp import SOLVERS
from gaitnet_mpc.mpc.wholebody.problem import swing_height_profile
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.state import RobotState

_KP, _KP_REASON = "[0, 1000] N m/rad", "1000 saturates a 33.5 N m hip at 0.03 rad"
_KD, _KD_REASON = "[0, 100] N m s/rad", "100 saturates a 33.5 N m hip at 0.3 rad/s"


class ReferenceVelocity(NamedTuple):
    """Velocity the reference follows, in the heading frame of the commanded heading:
    the ramped command plus the return terms (not bounded like a user
    :class:`~gaitnet_mpc.command.Command`; :func:`make_reference` takes its fields)."""

    vx_mps: float
    vy_mps: float
    yaw_rate_radps: float


@dataclass(frozen=True)
class WBWalkConfig:
    """Settings of the whole-body NMPC walking controller.

    Attributes:
        mpc: horizon, Table VI weights and limits of the NMPC, and a terminal weight 10x
            the stage weight (beyond the paper; without it the plan let the robot sink and
            fall back at the horizon end, and it fell within 1 s at 1 m/s).
        solver: NLP solver, ``"ipopt"`` (the paper's; measured fastest here) or ``"fatrop"``.
        step_durations: where each step's dt comes from (``--dt`` sets ``dt_s``; with
            ``duration_range_s`` drawn per stride).
        joint_kp_nm_per_rad, joint_kd_nms_per_rad: joint PD toward the predicted state,
            on top of the planned torques.
        max_accel_mps2: the command is ramped up from rest at this rate.
        path_max_error_m: the reference path stays within this of the measured base [m].
        lateral_return_time_s: time constant [s] of the return to the commanded path
            sideways: the reference (and the footholds) get the lateral velocity
            ``-e_y / T`` for a CoM ``e_y`` beside the path (heading frame); None: off.
        heading_return_time_s: time constant [s] of the return to the commanded heading:
            the reference trunk turns at ``yaw_rate - e_psi / T`` for a heading error
            ``e_psi``; None: off (the reference then starts at, and keeps, the measured
            heading, so a heading drift is never undone).
        lateral_return_max_mps, heading_return_max_radps: bounds of the two return
            terms (a large error is taken back at this rate).
        stance_half_width_m: lateral CoM-to-foot distance of the LIP sway orbit that the
            footholds of the reference aim at [m].
    """

    mpc: WBConfig = field(default_factory=lambda: WBConfig(weights=WBWeights(terminal_scale=10.0)))
    solver: str = "ipopt"
    step_durations: StepDurations = field(default_factory=StepDurations)
    joint_kp_nm_per_rad: float = bounded(50.0, _KP, "a stiffness", _KP_REASON)
    joint_kd_nms_per_rad: float = bounded(1.0, _KD, "a damping", _KD_REASON)
    max_accel_mps2: float = bounded(1.0, ACCEL_INTERVAL, "an acceleration", ACCEL_REASON)
    path_max_error_m: float = bounded(0.03, "[0, 1] m", "a distance", "1 m is past any error")
    stance_half_width_m: float = bounded(0.07, "[0, 0.3] m", "a distance", "hips 0.13 m apart")
    lateral_return_time_s: float | None = bounded(
        0.7, RETURN_INTERVAL, "a time constant", RETURN_REASON
    )
    heading_return_time_s: float | None = bounded(
        0.5, RETURN_INTERVAL, "a time constant", RETURN_REASON
    )
    lateral_return_max_mps: float = bounded(
        0.2, "[0, 2] m/s", "a speed", "past the fastest command, 1.5 m/s"
    )
    heading_return_max_radps: float = bounded(
        0.5, "[0, 10] rad/s", "a yaw rate", "10 rad/s turns half round in 0.3 s"
    )

    def __post_init__(self) -> None:
        if self.solver not in SOLVERS:
            raise ConfigError("solver", self.solver, f"one of {SOLVERS}")
        check_ranges(self)
        lo, hi = self.mpc.dt_min_s, self.mpc.dt_max_s
        d = self.step_durations
        if not lo <= d.dt_s <= hi:
            raise ConfigError("--dt (step_durations.dt_s)", d.dt_s, f"a time in [{lo}, {hi}] s")
        n = d.stages_per_step
        r = d.duration_range_s
        if r is not None and not (lo * n <= r[0] and r[1] <= hi * n):
            raise ConfigError(
                "step_durations.duration_range_s", r, f"durations in [{lo * n:g}, {hi * n:g}] s"
            )
        if self.step_durations.stages_per_step != self.mpc.stages_per_step:
            raise ConfigError(
                "step_durations.stages_per_step",
                self.step_durations.stages_per_step,
                f"mpc.stages_per_step = {self.mpc.stages_per_step}",
            )


class WBWalkController(WalkingBase):
    """Whole-body NMPC + gait schedule + joint PD toward the plan."""

    name = "wbmpc"

    def __init__(
        self,
        robot: RobotModel,
        terrain: TerrainView,
        command: Command,
        config: WBWalkConfig | None = None,
    ) -> None:
        self.config = config or WBWalkConfig()
        c = self.config
        # CasADi's bundled OpenBLAS would spread IPOPT's linear algebra over every core for
        # no gain at this size (benchmarks/results/wbmpc.md); it reads this at first use.
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
        lo, hi = c.mpc.dt_min_s, c.mpc.dt_max_s
        schedule = GaitScheduleConfig(
            stages_per_step=c.mpc.stages_per_step,
            horizon_stages=c.mpc.horizon_stages,
            default_dt_s=c.step_durations.dt_of_step(0),
            dt_bounds_s=(lo, hi),
        )
        # the low level is not used (torques come from the plan), but the base needs one
        super().__init__(robot, terrain, command, schedule, LowLevelConfig(), c.max_accel_mps2)
        self.mpc = WholeBodyMPC(robot, c.mpc, solver=c.solver)
        self.ref_workspace = ReferenceWorkspace(robot)
        self._joints_q = robot.joint_qpos_adr
        self._joints_v = robot.joint_dof_adr

    # ---------------------------------------------------------------- episode
    def reset(self, state: RobotState) -> None:
        self.schedule = GaitSchedule(
            replace(self.schedule.config, first_swing_foot=self._first_swing_foot(state))
        )
        super().reset(state)
        self.liftoff = {f: state.foot_pos_world_m[f].copy() for f in FEET}
        self.plan: WBSolution | None = None
        self.t_plan_s = state.t_s
        self.stage0_s = 1.0
        self._solved_stage: tuple[int, int] | None = None
        self._started_step = -1

    def terrain_knowledge(self) -> dict[str, object]:
        out = super().terrain_knowledge()
        return {**out, "used": "ground height at the start only (flat ground)"}

    def _first_swing_foot(self, state: RobotState) -> str:
        """The foot that swings first: the one further ahead along the commanded velocity,
        so that the CoM starts ahead of the stance foot and the first step falls forward.

        The biped starts with its feet 0.16 m apart along x; standing on the front (point)
        foot with the CoM 7 cm behind it, the first plan fell backward during a long first
        step (0.375 s: -0.43 m, a fall at 0.77 s at 0.5 m/s). Feet side by side (humanoid),
        or no commanded velocity: the schedule's default (right)."""
        default = self.schedule.config.first_swing_foot
        c = self.command
        v = np.array([c.vx_mps, c.vy_mps])
        if float(np.linalg.norm(v)) < 1e-6:
            return default
        yaw = float(state.base_rpy_rad[2])
        direction = rotate2(yaw, v / float(np.linalg.norm(v)))
        ahead_m = [float(state.foot_pos_world_m[f][:2] @ direction) for f in FEET]
        if abs(ahead_m[0] - ahead_m[1]) < 0.02:
            return default
        return FEET[0] if ahead_m[0] > ahead_m[1] else FEET[1]

    # ---------------------------------------------------------------- planning
    def _step_dts(self) -> tuple[float, float]:
        """dt [s] of the current step and of the next."""
        i = self.schedule.step_index
        d = self.config.step_durations
        return d.dt_of_step(i), d.dt_of_step(i + 1)

    def _timing(self) -> ReferenceTiming:
        """Stage timing of the horizon with every step's own dt: the schedule knows the
        current and the next step's, and repeats the next one's for a third step that the
        horizon reaches inside a step; the drawn durations are known ahead
        (:class:`~gaitnet_mpc.gait.step_durations.StepDurations`), so that step gets its own."""
        sched = self.schedule
        horizon = sched.horizon()
        timing = ReferenceTiming.from_horizon(horizon, self.config.mpc.stages_per_step)
        d = self.config.step_durations
        full = np.array(
            [d.dt_of_step(sched.step_index + int(k)) for k in horizon.step_index], dtype=float
        )
        full[horizon.step_index == 0] = sched.current_step_dt_s
        dts = full.copy()
        dts[0] = timing.dts_s[0]
        return ReferenceTiming(
            dts_s=dts,
            contact=timing.contact,
            time_in_step_s=timing.time_in_step_s,
            stages_per_step=timing.stages_per_step,
            full_dts_s=full,
        )

    def _footholds(
        self, state: RobotState, t_left_s: float, cmd: ReferenceVelocity
    ) -> tuple[np.ndarray, np.ndarray]:
        """Footholds (3,) of the swing foot and of the stance foot's next step: the Raibert
        law with the LIP deadbeat gains at the CoM state the LIP predicts for touchdown
        (as ``srbm``, :func:`~gaitnet_mpc.gait.lip.lip_gains`). The geometric hip offset
        instead let the lateral sway grow: feet 0.46 m apart and the legs rolled 0.3-0.5
        rad within 0.5 s at 1 m/s, then a fall.

        Each foothold's gains and half-stride use the duration of the stance that follows
        its touchdown (steps i+1 and i+2 when step i is under way), and the LIP is
        propagated over the step in between with its own duration: with drawn durations
        these differ from the current step's (0.15-0.40 s)."""
        sched, c = self.schedule, self.config
        i = sched.step_index
        n = c.mpc.stages_per_step
        durations_s = [n * c.step_durations.dt_of_step(i + j) for j in (1, 2)]
        z0 = float(state.com_world_m[2]) - self.ground_z
        planar = self.robot.spec.planar
        out = []
        p_com, v_com = state.com_world_m[:2], state.com_vel_world_mps[:2]
        p_stance, t_s = state.foot_pos_world_m[sched.stance_foot], t_left_s
        for foot, stance_s in zip((sched.swing_foot, sched.stance_foot), durations_s, strict=True):
            omega, k_v, lateral, cmd_scale = lip_gains(z0, stance_s, c.stance_half_width_m)
            raibert = RaibertHeuristic(
                RaibertConfig(
                    hip_lateral_offset_m=0.0 if planar else lateral,
                    velocity_gain_s=k_v,
                    min_lateral_separation_m=0.0 if planar else 0.08,
                )
            )
            v_cmd = cmd_scale * np.array([cmd.vx_mps, cmd.vy_mps])
            p_com, v_com = lip_propagate(p_com, v_com, p_stance[:2], omega, t_s)
            p = raibert.foothold(
                foot,
                p_com_world_m=np.array([p_com[0], p_com[1], state.com_world_m[2]]),
                v_com_world_mps=v_com,
                cmd_vel_mps=v_cmd,
                stance_duration_s=stance_s,
                time_to_touchdown_s=0.0,
                p_stance_foot_world_m=p_stance,
                ground_z_m=self.ground_z,
                yaw_rad=self.profile.heading_rad(state.t_s),
                cmd_yaw_rate_radps=cmd.yaw_rate_radps,
            )
            p[2] = self.ground_z + self.robot.spec.foot_contact_radius_m
            if planar:
                p[1] = state.foot_pos_world_m[foot][1]
            out.append(p)
            p_stance, t_s = p, stance_s
        return out[0], out[1]

    def _returning_command(self, state: RobotState, cmd: Command) -> ReferenceVelocity:
        """The command with the returns to the commanded path and heading (heading frame
        of the commanded heading): lateral velocity ``vy - e_y / T_lat`` and yaw rate
        ``omega - e_psi / T_psi`` (``lateral_return_time_s``, ``heading_return_time_s``;
        as ``kd``'s lateral return, docs/design/lateral_return.md). Without them a heading
        drift stays in the reference, which starts at the measured heading: before the
        touchdown fix of :mod:`~gaitnet_mpc.mpc.wholebody.nlp`, 0.94 rad of yaw and 1.3 m
        beside the path after 15 s at 0.5 m/s (drawn durations), then a fall."""
        c = self.config
        if self.robot.spec.planar:
            return ReferenceVelocity(cmd.vx_mps, cmd.vy_mps, cmd.yaw_rate_radps)
        heading = self.profile.heading_rad(state.t_s)
        vy, yaw_rate = cmd.vy_mps, cmd.yaw_rate_radps
        if c.lateral_return_time_s is not None:
            offset = state.com_world_m[:2] - self._commanded_path_xy(state.t_s)
            e_y = float(heading_axes(heading)[1] @ offset)
            lim = c.lateral_return_max_mps
            vy += float(np.clip(-e_y / c.lateral_return_time_s, -lim, lim))
        if c.heading_return_time_s is not None:
            e_yaw = float(wrap_angle(float(state.base_rpy_rad[2]) - heading))
            lim = c.heading_return_max_radps
            yaw_rate += float(np.clip(-e_yaw / c.heading_return_time_s, -lim, lim))
        return ReferenceVelocity(cmd.vx_mps, vy, yaw_rate)

    def _reference(
        self, state: RobotState, timing: ReferenceTiming, cmd: ReferenceVelocity
    ) -> tuple[np.ndarray, np.ndarray]:
        """``f_ref`` at nodes 1..h in MuJoCo coordinates: (qpos (h, nq), qvel (h, nv)).

        ``cmd`` is in the frame of the commanded heading (as the footholds take it);
        :func:`make_reference` reads the velocity in the frame of the measured trunk
        heading, so it gets the same world velocity rotated into that frame."""
        sched = self.schedule
        swing, stance = sched.swing_foot, sched.stance_foot
        t_left = sched.time_left_in_step_s
        target, nxt = self._footholds(state, t_left, cmd)
        lim = self.config.path_max_error_m
        p_com = state.com_world_m.copy()
        p_com[:2] += np.clip(self._commanded_path_xy(state.t_s) - p_com[:2], -lim, lim)
        q, _ = self.robot.mj_to_pin(state.qpos, state.qvel)
        ref_cmd = cmd
        if not self.robot.spec.planar:
            v_world = rotate2(self.profile.heading_rad(state.t_s), (cmd.vx_mps, cmd.vy_mps))
            vx, vy = to_heading2(float(state.base_rpy_rad[2]), v_world)
            ref_cmd = ReferenceVelocity(float(vx), float(vy), cmd.yaw_rate_radps)
        ref = make_reference(
            self.robot,
            q,
            timing,
            ref_cmd,
            {swing: target[None, :], stance: nxt[None, :]},
            p_foot_now_m=state.foot_pos_world_m,
            p_liftoff_m={swing: self.liftoff[swing]},
            p_com_start_m=p_com,
            workspace=self.ref_workspace,
        )
        nodes = [
            self.robot.pin_to_mj(ref.q_ref[k], ref.v_ref[k]) for k in range(1, timing.horizon + 1)
        ]
        return np.stack([n[0] for n in nodes]), np.stack([n[1] for n in nodes])

    def _problem(self, state: RobotState, phase_stage: int) -> WBProblem:
        k = self.profile.ramp(state.t_s - self.t0_s)
        c = self.command
        ramped = self._returning_command(
            state, Command(k * c.vx_mps, k * c.vy_mps, c.yaw_rate_radps)
        )
        timing = self._timing()
        qpos_ref, qvel_ref = self._reference(state, timing, ramped)
        return WBProblem(
            qpos0=state.qpos.copy(),
            qvel0=state.qvel.copy(),
            stance=timing.contact.copy(),
            dt_stage_s=timing.dts_s.copy(),
            qpos_ref=qpos_ref,
            qvel_ref=qvel_ref,
            swing_height_min_m=swing_height_profile(self.config.mpc, phase_stage),
            ground_z_m=self.ground_z,
        )

    def _solve(self, state: RobotState, phase_stage: int, full: bool) -> None:
        problem = self._problem(state, phase_stage)
        warm = None if self.plan is None else self.mpc.shift(self.plan)
        sol = self.mpc.solve(problem, warm)
        # An unsuccessful NLP solve is counted as failed, but its iterate is still the plan
        # (wbmpc keeps no last good plan to fall back on).
        self._stats.record(
            sol.solve_time_s, sol.iterations, sol.success, full, failed=not sol.success
        )
        self.plan = sol
        self.t_plan_s = state.t_s
        self.stage0_s = float(problem.dt_stage_s[0])

    # ---------------------------------------------------------------- control
    def compute(self, state: RobotState) -> np.ndarray:
        sched = self.schedule
        sched.advance_to(state.t_s)
        full = False
        if sched.at_step_start and sched.step_index != self._started_step:
            self._started_step = sched.step_index
            dt0, dt1 = self._step_dts()
            sched.set_step_dt(dt0)
            sched.set_next_step_dt(dt1)
            self._steps.append(sched.current_step_duration_s)
            self.liftoff[sched.swing_foot] = state.foot_pos_world_m[sched.swing_foot].copy()
            full = True
        stage = (sched.step_index, sched.stage_in_step)
        if stage != self._solved_stage:
            self._solved_stage = stage
            self._solve(state, stage[1], full)
        plan = self.plan
        assert plan is not None
        s = min(max((state.t_s - self.t_plan_s) / self.stage0_s, 0.0), 1.0)
        q_pred = (1 - s) * plan.qpos[0] + s * plan.qpos[1]
        v_pred = (1 - s) * plan.qvel[0] + s * plan.qvel[1]
        c = self.config
        tau = plan.tau_nm[0].copy()
        tau += c.joint_kp_nm_per_rad * (q_pred[self._joints_q] - state.qpos[self._joints_q])
        tau += c.joint_kd_nms_per_rad * (v_pred[self._joints_v] - state.qvel[self._joints_v])
        return tau
