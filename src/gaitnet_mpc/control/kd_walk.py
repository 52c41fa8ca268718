"""``kd``, ``gaitnet``, ``oracle``, ``kd-optdt``: walking with the implicit kino-dynamic
sequential MPC (paper Sec. IV-B), the four differing only in the dt policy of
``KDWalkConfig.dt_policy``.

At each step start the dt policy (a fixed dt for ``kd``; Gait-Net from the state and the
iterate's touchdown for ``gaitnet``, Algorithm 1 line 8; a grid search for ``oracle``; an
NLP with dt as a variable for ``kd-optdt``) sets the step's MPC sampling time and the full
sequential solve runs (Algorithm 1, up to ``j_max`` QPs); during the step the same dt is
kept and the MPC replans every ``replan_period_s`` (at least once per stage, Remark 4).
The footholds the MPC chooses are the swing targets of the low-level controller; the next
touchdown is bounded by the one-step terrain preview (eq. 24). With ``KDWalkConfig.preview``
set, a multi-step LIP footstep plan re-made at every solve gives instead the patch of that
touchdown and the CoM path (:mod:`gaitnet_mpc.gait.preview`, beyond the paper).
"""

from __future__ import annotations

import time
from dataclasses import replace
from functools import cached_property
from typing import Any

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.base import MomentumPrediction
from gaitnet_mpc.control.blind_touchdown import TouchdownSearch
from gaitnet_mpc.control.disturbance_observer import MomentumObserver
from gaitnet_mpc.control.dt_policies import make_dt_policy
from gaitnet_mpc.control.kd_walk_config import KDWalkConfig, robot_kd_config
from gaitnet_mpc.control.lip_reference import lip_com_reference
from gaitnet_mpc.control.step_retiming import StepRetimer
from gaitnet_mpc.control.swing_obstacles import SwingObstacles
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.control.walking import swing_beside_stance
from gaitnet_mpc.control.walking_base import WalkingBase
from gaitnet_mpc.dt_policy import CONTROLLER_OF_POLICY
from gaitnet_mpc.errors import ConfigError, QPSolveError
from gaitnet_mpc.gait import GaitScheduleConfig, RaibertConfig, RaibertHeuristic, SwingTrajectory
from gaitnet_mpc.gait.preview import PreviewPlan, plan_areas, plan_preview
from gaitnet_mpc.gaitnet.policy import GaitNetDt
from gaitnet_mpc.geometry import heading_axes
from gaitnet_mpc.kinematics.reference import ReferenceTiming
from gaitnet_mpc.mpc.dt_nlp import NLPDt
from gaitnet_mpc.mpc.dt_oracle import OracleDt
from gaitnet_mpc.mpc.sequential import (
    CoMReference,
    DtPolicy,
    FootholdBox,
    KDProblem,
    SequentialKDMPC,
    SequentialResult,
    StepState,
)
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.state import RobotState
from gaitnet_mpc.terrain import Patch


def _kd_raibert(planar: bool) -> RaibertHeuristic:
    """The Raibert heuristic of ``kd``'s initial footholds (the MPC then moves them): hip
    offset 0.065 m, feet 0.08-0.30 m apart sideways (none for a biped)."""
    return RaibertHeuristic(
        RaibertConfig(
            hip_lateral_offset_m=0.0 if planar else 0.065,
            min_lateral_separation_m=0.0 if planar else 0.08,
            max_lateral_separation_m=0.0 if planar else 0.30,
        )
    )


class KDWalkController(WalkingBase):
    """Sequential implicit kino-dynamic MPC + gait schedule + low-level control.

    ``dt_policy``: the policy that sets each step's dt; None: the one
    ``config.dt_policy`` names (:func:`~gaitnet_mpc.control.dt_policies.make_dt_policy`).
    """

    def __init__(
        self,
        robot: RobotModel,
        terrain: TerrainView,
        command: Command,
        dt_policy: DtPolicy | None = None,
        config: KDWalkConfig | None = None,
    ) -> None:
        self.config = config or KDWalkConfig()
        if self.config.preview is not None and not terrain.knowledge.multi_step:
            raise ConfigError(
                "terrain.knowledge.multi_step", False, "True with KDWalkConfig.preview set"
            )
        sequential = replace(self.config.sequential, kd=robot_kd_config(self.config, robot))
        if dt_policy is None:
            dt_policy = make_dt_policy(self.config.dt_policy, robot, sequential)
        self.name = CONTROLLER_OF_POLICY[self.config.dt_policy.kind]
        self.dt_policy = dt_policy
        self.mpc = SequentialKDMPC(robot, sequential, dt_policy)
        on_retime = getattr(dt_policy, "step_retimed", None)  # Gait-Net's fallback reads it
        self.retimer = StepRetimer.of(self.config.dt_policy, robot, on_retime, terrain.holds_foot)
        lo, hi = self.config.sequential.dt_bounds_s
        if self.retimer is not None:  # a re-timed step may go below the policy's bounds
            lo = min(lo, self.retimer.config.min_dt_s)
        schedule = GaitScheduleConfig(
            default_dt_s=self.mpc.dt_policy.nominal_dt_s, dt_bounds_s=(lo, hi)
        )
        super().__init__(
            robot, terrain, command, schedule, self.config.low_level, self.config.max_accel_mps2
        )
        self.raibert = _kd_raibert(robot.spec.planar)
        self.search = TouchdownSearch() if self.config.blind else None
        self.obstacles = SwingObstacles(robot, terrain, self.config)

    # ---------------------------------------------------------------- episode
    def reset(self, state: RobotState) -> None:
        super().reset(state)
        self.liftoff = {f: state.foot_pos_world_m[f].copy() for f in FEET}
        self.swing: SwingTrajectory | None = None
        self.plan: SequentialResult | None = None
        self.next_replan_s = -np.inf
        self._started_step = -1
        self.preview: PreviewPlan | None = None
        self._preview_t0_s = 0.0
        self.obstacles.reset(state)
        if self.retimer is not None:
            self.retimer.events.clear()
        observer = self.config.disturbance_observer  # starts from this state
        self.observer = None if observer is None else MomentumObserver(self.robot, observer, state)

    def _prediction(self) -> MomentumPrediction | None:
        plan = self.plan
        if plan is None or plan.last_step is None:
            return None
        t_pred = plan.t_plan_s + float(plan.dts_s[0])
        return MomentumPrediction(plan.t_plan_s, t_pred, plan.last_step.states[1, 6:12].copy())

    def last_dt_decision(self) -> dict[str, Any] | None:
        policy = self.dt_policy
        if isinstance(policy, GaitNetDt | OracleDt | NLPDt) and policy.decisions:
            return policy.decisions[-1].to_dict()
        return None

    def dt_policy_summary(self) -> dict[str, Any] | None:
        policy = self.dt_policy
        if isinstance(policy, GaitNetDt):
            return {**policy.summary(), "weights": policy.weights_info()}
        return policy.summary() if isinstance(policy, OracleDt | NLPDt) else None

    @property
    def swing_events(self) -> list[dict[str, Any]]:
        retimes = self.retimer.events if self.retimer else []  # "retime", "landing"
        return sorted(self.obstacles.events + retimes, key=lambda e: e["t_s"])

    def planned_footholds(self) -> list[tuple[str, np.ndarray]]:
        if self.plan is None:
            return []
        touchdowns = [(foot, self.plan.touchdown(foot)) for foot in FEET]
        return [(foot, td.copy()) for foot, td in touchdowns if td is not None]

    # ---------------------------------------------------------------- helpers
    def _command_now(self, t_s: float) -> Command:
        """The command ramped up from rest (:class:`CommandProfile`)."""
        c = self.command
        k = self.profile.ramp(t_s - self.t0_s)
        return Command(k * c.vx_mps, k * c.vy_mps, c.yaw_rate_radps)

    def _raibert(self, state: RobotState, foot: str, t_td: float, cmd: Command) -> np.ndarray:
        """Foothold of ``foot`` touching down ``t_td`` from now: the Raibert heuristic on
        the terrain's height there."""
        p = self.raibert.foothold(
            foot,
            p_com_world_m=state.com_world_m,
            v_com_world_mps=state.com_vel_world_mps,
            cmd_vel_mps=np.array([cmd.vx_mps, cmd.vy_mps]),
            stance_duration_s=self.schedule.current_step_duration_s,
            time_to_touchdown_s=t_td,
            p_stance_foot_world_m=state.foot_pos_world_m[self.schedule.stance_foot],
            ground_z_m=self.ground_z,
            yaw_rad=float(state.base_rpy_rad[2]),
            cmd_yaw_rate_radps=cmd.yaw_rate_radps,
        )
        r = self.robot.spec.foot_contact_radius_m
        ground = self.ground_z
        if self.search is not None:  # blind: the height of the stance foot's sole
            ground = state.foot_pos_world_m[self.schedule.stance_foot][2] - r
        z = self.terrain.foothold_height_m(p[0], p[1], ground)
        p[2] = z + r
        if self.robot.spec.planar:
            p[1] = state.foot_pos_world_m[foot][1]
        return p

    def _path_start(self, state: RobotState) -> np.ndarray:
        """Start of the reference CoM path: the measured CoM (the pull back to the
        commanded path is ``lateral_return_time_s``'s)."""
        return state.com_world_m.copy()

    def _converges(self, t_s: float, timing: ReferenceTiming) -> bool:
        """Whether a replan at ``t_s`` runs to convergence: its horizon has a stage past the
        last plan's (``KDWalkConfig.converge_new_stages``)."""
        return (
            self.config.converge_new_stages
            and self.plan is not None
            and not self.plan.covers(t_s, timing.dts_s)
        )

    def _bounds(self, state: RobotState, foot: str, nominal: np.ndarray) -> dict[str, FootholdBox]:
        """Eq. 24 box for the swing foot's next touchdown.

        With a preview plan, the box of the patch it chose. Otherwise (one-step preview)
        the patch is chosen by kinematic reach from the CoM predicted at touchdown
        (current CoM plus its velocity times the time left in the step), preferring the
        patch nearest the nominal (heuristic) foothold
        (:meth:`TerrainView.reachable_foothold_bounds`).
        """
        if self.search is not None:
            return {}  # blind: no patch known
        if self.preview is not None:
            lo, hi = self._preview_area(1).foothold_box(*self._margins)
        else:
            t_left = self.schedule.time_left_in_step_s
            p_td = state.com_world_m[:2] + state.com_vel_world_mps[:2] * t_left
            lo, hi, _ = self.terrain.reachable_foothold_bounds(
                p_td,
                foot,
                nominal[:2],
                reach_x_m=self.config.foothold_reach_m,
                reach_back_m=self.config.foothold_reach_back_m,
                margin_m=self.config.foothold_margin_m,
                margin_y_m=self.config.foothold_margin_y_m,
                obstacle_clearance_m=self.config.foothold_obstacle_clearance_m,
            )
        r = self.robot.spec.foot_contact_radius_m
        lo, hi = lo.copy(), hi.copy()
        lo[2] += r
        hi[2] += r
        if self.robot.spec.planar:
            lo[1], hi[1] = -np.inf, np.inf
        return {foot: FootholdBox(lo, hi)}

    def _lip_reference(
        self, state: RobotState, timing: ReferenceTiming, cmd: Command
    ) -> CoMReference | None:
        """The LIP sway reference (:func:`~gaitnet_mpc.control.lip_reference.lip_com_reference`)
        about the commanded path, its lateral offset from the measured CoM clamped by
        ``lip_anchor_max_m``; None where the lateral reference is the straight line."""
        c = self.config
        if self.robot.spec.planar or c.lateral_reference != "lip":
            return None
        yaw = self.profile.heading_rad(state.t_s)
        e_x, e_y = heading_axes(yaw)
        lat = float(e_y @ (self._commanded_path_xy(state.t_s) - state.com_world_m[:2]))
        if c.lip_anchor_max_m is not None:
            lat = float(np.clip(lat, -c.lip_anchor_max_m, c.lip_anchor_max_m))
        z = max(float(self.mpc.ref_workspace.com_height_m), c.lip_min_com_height_m)
        v_cmd = e_x * cmd.vx_mps + e_y * cmd.vy_mps
        com_xy = state.com_world_m[:2]
        return lip_com_reference(timing, com_xy, z, yaw, lat, v_cmd, c.lip_half_width_m)

    def _plan_preview(self, state: RobotState, cmd: Command, first_step: bool) -> None:
        """Multi-step LIP footstep plan from now (None if off, planar, or without a
        solution: then the one-step preview applies). Within a step (``first_step``
        False) the patch of the next touchdown stays the one chosen at the step start."""
        cfg = self.config.preview
        if cfg is None or self.robot.spec.planar:
            return
        sched = self.schedule
        stance = sched.stance_foot
        keep = None if first_step or self.preview is None else self.preview.patch[1]
        plan = plan_preview(
            self.terrain.course_for_multi_step_preview(),
            cfg,
            com_m=state.com_world_m[:2],
            com_v_mps=state.com_vel_world_mps[:2],
            com_height_m=self.mpc.ref_workspace.com_height_m,
            stance_foot=stance,
            stance_m=state.foot_pos_world_m[stance][:2],
            liftoff_m=self.liftoff[sched.swing_foot][:2],
            time_left_s=max(sched.time_left_in_step_s, 1e-3),
            dt_s=sched.current_step_dt_s,
            v_cmd_mps=cmd.vx_mps,
            y_path_m=float(self._commanded_path_xy(state.t_s)[1]),
            margin_m=self._margins,
            first_patch=keep,
            obstacle_clearance_m=self.config.foothold_obstacle_clearance_m,
        )
        if plan is not None or first_step:
            self.preview = plan
            self._preview_t0_s = state.t_s

    @property
    def _margins(self) -> tuple[float, float]:
        """(x, y) foothold margins inside a patch with the preview [m]."""
        c = self.config
        assert c.preview is not None
        return c.foothold_margin_m, c.preview.foothold_margin_y_m

    @cached_property
    def _preview_areas(self) -> tuple[Patch, ...]:
        """The landing areas (patches less the obstacles' footprints) the preview plans on;
        the course and the margins are fixed for the controller."""
        return plan_areas(
            self.terrain.course_for_multi_step_preview(),
            self.config.foothold_obstacle_clearance_m,
            self._margins,
        )

    def _preview_area(self, step: int) -> Patch:
        """The landing area of the preview's foothold of ``step``."""
        assert self.preview is not None
        return self._preview_areas[self.preview.patch[step]]

    def _on_preview(self, p: np.ndarray, step: int) -> np.ndarray:
        """``p`` (a heuristic foothold) with x from the preview's foothold of ``step`` (1 =
        the next touchdown), y clipped into its patch's box and z on the patch."""
        plan = self.preview
        assert plan is not None
        lo, hi = self._preview_area(step).foothold_box(*self._margins)
        out = np.clip(p, lo, hi)
        out[0] = plan.foothold_m[step, 0]
        out[2] = lo[2] + self.robot.spec.foot_contact_radius_m
        return out

    def _com_reference(
        self, state: RobotState, timing: ReferenceTiming, cmd: Command
    ) -> CoMReference | None:
        """CoM path and velocity (h+1, 3) that replace f_ref's where not NaN: laterally the
        LIP sway orbit (``lateral_reference="lip"``) or, with ``lateral_return_time_s``, the
        commanded path plus the measured offset decaying along the horizon (world y: the
        courses run along x); along x the preview plan's CoM."""
        ref = self._lip_reference(state, timing, cmd)
        tau = self.config.lateral_return_time_s
        line_return = (
            tau is not None
            and self.config.lateral_reference == "line"
            and not self.robot.spec.planar
        )
        if self.preview is None and not line_return:
            return ref
        if ref is None:
            shape = (timing.times_s.size, 3)
            ref = CoMReference(np.full(shape, np.nan), np.full(shape, np.nan))
        if self.preview is not None:
            pos, vel = self.preview.com_at(timing.times_s + (state.t_s - self._preview_t0_s))
            ref.p_m[:, 0], ref.v_mps[:, 0] = pos[:, 0], vel[:, 0]
        if line_return:
            assert tau is not None  # line_return needs it
            y_path = float(self._commanded_path_xy(state.t_s)[1])
            err = float(state.com_world_m[1]) - y_path
            decay = np.exp(-timing.times_s / tau)
            ref.p_m[:, 1] = y_path + err * decay
            ref.v_mps[:, 1] = -err / tau * decay
        return ref

    # ---------------------------------------------------------------- planning
    def _solve(self, state: RobotState, full: bool) -> None:
        """Algorithm 1 from ``state``; ``full`` at a step start, where the dt policy sets
        the step's dt inside the iterations (Remark 4)."""
        sched = self.schedule
        q, v = self.robot.mj_to_pin(state.qpos, state.qvel)
        cmd = self._command_now(state.t_s)
        timing = ReferenceTiming.from_horizon(sched.horizon())
        swing, stance = sched.swing_foot, sched.stance_foot
        t_left = sched.time_left_in_step_s
        if not full and self.config.preview is not None and self.config.preview.every_solve:
            self._plan_preview(state, cmd, first_step=False)
        if full or self.plan is None:
            target = self._raibert(state, swing, t_left, cmd)
            if self.preview is not None:
                target = self._on_preview(target, 1)
        else:
            planned = self.plan.touchdown(swing)
            target = self._raibert(state, swing, t_left, cmd) if planned is None else planned
        nxt = self._raibert(state, stance, t_left + sched.current_step_duration_s, cmd)
        if self.preview is not None:
            nxt = self._on_preview(nxt, 2)
        heading = self.profile.heading_rad(state.t_s)
        yaw = np.full((timing.horizon, 2), heading)
        yaw[:, FEET.index(stance)] = state.foot_yaw_rad[stance]
        problem = KDProblem(
            q=q,
            v=v,
            timing=timing,
            command=cmd,
            heading_rad=heading,
            footholds_m={swing: target[None, :], stance: nxt[None, :]},
            p_foot_now_m=state.foot_pos_world_m,
            p_liftoff_m={swing: self.liftoff[swing]},
            foot_yaw_rad=yaw,
            foothold_boxes=self._bounds(state, swing, target),
            p_com_start_m=self._path_start(state),
            com_reference=lambda t: self._com_reference(state, t, cmd),
            j_max=None if full or self._converges(state.t_s, timing) else self.config.replan_j_max,
            choose_dt=full,
            step_index=sched.step_index,
            state=StepState(state, stance, swing) if full else None,
            warm_start=None if full or not self.config.warm_start_replans else self.plan,
            t_s=state.t_s,
            wrench_ext=None if self.observer is None else self.observer.mpc_wrench(),
        )
        t0_s = time.perf_counter()
        try:
            result = self.mpc.solve(problem)
        except QPSolveError:
            self._stats.record(time.perf_counter() - t0_s, 1, False, full, failed=True)
            return  # keep the last good plan
        result.t_plan_s = state.t_s
        self._stats.record(result.solve_time_s, result.n_qps, result.converged, full)
        self.plan = result
        td = result.touchdown(swing)
        if full and result.step_dt_s != sched.current_step_dt_s:
            sched.set_step_dt(result.step_dt_s)  # the policy's dt: the swing lasts h' dt
            if self.config.carry_dt:  # dt^0 of the next step; else the nominal one
                sched.set_next_step_dt(result.step_dt_s)
            self.swing = self._swing_trajectory(target if td is None else td)
        if td is not None and self.swing is not None:
            td = td.copy()
            c = self.config
            td[2] -= c.touchdown_depth_m if self.search is None else c.blind_search_depth_m
            if sched.phase_in_step < self.config.retarget_until_phase:
                start = self.liftoff[swing]
                self.swing.retarget(
                    td, sched.time_in_step_s, obstacles=self.obstacles.near(start, td)
                )
                if not full:
                    self.obstacles.check_shank(state, sched, self.swing, self.plan, self.profile)

    def _swing_trajectory(self, target: np.ndarray) -> SwingTrajectory:
        """Swing of the step that starts, from its lift-off point to ``target``."""
        sched = self.schedule
        start = self.liftoff[sched.swing_foot]
        return self.config.swing.trajectory(
            start, target, sched.current_step_duration_s, self.obstacles.near(start, target)
        )

    def _start_step(self, state: RobotState) -> None:
        sched = self.schedule
        swing = sched.swing_foot
        self.liftoff[swing] = state.foot_pos_world_m[swing].copy()
        cmd = self._command_now(state.t_s)
        target = self._raibert(state, swing, sched.current_step_duration_s, cmd)
        self._plan_preview(state, cmd, first_step=True)
        if self.preview is not None:
            target = self._on_preview(target, 1)
        self.swing = self._swing_trajectory(target)
        if self.search is not None:
            self.search.new_step()
        self._solve(state, full=True)
        self.obstacles.check_shank(state, sched, self.swing, self.plan, self.profile)
        self._steps.append(sched.current_step_duration_s)
        self.next_replan_s = state.t_s + self.config.replan_period_s

    # ---------------------------------------------------------------- control
    def compute(self, state: RobotState) -> np.ndarray:
        sched = self.schedule
        sched.advance_to(state.t_s)
        if self.observer is not None:
            self.observer.update(state)
        if self.retimer and self.retimer.end_at_touchdown(state, sched, self.swing):
            self._steps[-1] = sched.current_step_duration_s
        if sched.at_step_start and sched.step_index != self._started_step:
            self._started_step = sched.step_index
            self._start_step(state)
        elif state.t_s >= self.next_replan_s:
            heading, vx = self.profile.heading_rad(state.t_s), self._command_now(state.t_s).vx_mps
            box = None if self.plan is None else self.plan.foothold_boxes.get(sched.swing_foot)
            if self.retimer and self.retimer.apply(state, sched, self.swing, heading, vx, box):
                self._steps[-1] = sched.current_step_duration_s  # re-timed under way
            self._solve(state, full=False)
            self.next_replan_s = state.t_s + self.config.replan_period_s
        stance, swing = sched.stance_foot, sched.swing_foot
        wrench = {}
        if self.plan is not None:
            k = self.plan.stage_at(state.t_s)
            i = FEET.index(stance)
            wrench[stance] = np.concatenate(
                [self.plan.iterate.f[k, i], self.plan.iterate.tau[k, i]]
            )
        t = sched.time_in_step_s
        assert self.swing is not None  # made by _start_step, which the first tick runs
        self.obstacles.toe_strike(state, swing, self.swing, self.liftoff[swing], t)
        yaw = None if self.robot.spec.planar else self.profile.heading_rad(state.t_s)
        p_swing, v_swing, a_swing = self.swing.sample(t)
        if yaw is not None and self.config.keep_feet_apart:
            p_swing = swing_beside_stance(self.robot, state, swing, p_swing, yaw)
        target = {swing: (p_swing, v_swing, a_swing)}
        if self.search is not None:
            target[swing] = self.search.target(state, swing, sched.phase_in_step, target[swing])
        return self.low.torques(state, wrench, target, yaw)
