"""Walking on a periodic gait: the parts every walking controller shares.

Per control tick (1 kHz): advance the gait schedule; at each step start, plan the swing
foot's foothold (Raibert heuristic evaluated at the LIP-predicted touchdown state) and its
swing trajectory; every ``replan_period_s`` (and at each step start or touchdown) run the
subclass's MPC (:meth:`WalkingController._replan`); send the stance wrenches of the plan
and the swing target to the low-level controller. ``srbm`` is built on it; ``kd`` shares
only :class:`~gaitnet_mpc.control.walking_base.WalkingBase` (its footholds come from the
MPC, and on this class's LIP/Raibert planning with the sub-problem's weights they drifted
toward the CoM line).

Design notes (each setting of :class:`WalkingConfig` says why it has its value):

* **Footholds from the linear inverted pendulum (LIP).** With line feet and no ankle roll,
  the stance foot cannot exert a moment about its long axis, so sideways the robot is a
  point-foot pendulum that only foot placement stabilises. The Raibert law
  ``p = p_hip + v T/2 + k_v (v - v_cmd)`` is evaluated with the CoM position and velocity
  *predicted at touchdown* by the LIP about the stance foot (closed form, ``omega =
  sqrt(g / z0)``), not with the current ones. Its gain is the LIP deadbeat gain
  ``T/2 + k_v = coth(omega T) / omega`` (one step cancels a velocity error), and its lateral
  offset is chosen so that the heuristic's fixed point is the period-2 sway orbit of a
  stance half-width ``d``: ``hip_lateral_offset = d (1 - tanh^2(omega T / 2)) / 2``. With
  the geometric hip offset (0.065 m) instead, the same law converges to a 0.2 m half-width
  with +-0.4 m/s of lateral sway, which made the robot trip over its own feet at 1 m/s.
  Footholds are also limited to the leg's reach from the predicted CoM.
* **The MPC leaves the lateral CoM to the footholds** (``srbm``: small lateral weights in
  the heading frame, see :class:`SRBMConfig`); tracking vy = 0 made it lean and drift
  sideways.
* **Measured touchdown.** A swing foot that touches the ground in the second half of its
  swing is switched to stance at once: the MPC gets it as a second contact for the rest of
  the step (double support) and the low-level controller maps its wrench through ``J^T``
  instead of pressing it into the ground with the swing PD. Scheduled touchdowns are
  slightly early by design (the swing ends 5 mm below the ground at 0.3 m/s), so without
  this every step began with an uncontrolled braking impulse. A foot still in the air
  when its stance begins is not waited for: the other foot swings on schedule (waiting
  up to 0.03-0.09 s turned a survived 56 N x 0.2 s backward push into a sideways fall).
* **Swing overshoot compensation.** The measured touchdown error of the PD-tracked swing
  foot is averaged and subtracted from later swing targets.
* **Bent-knee walking height and stance-leg gravity feedforward**, so the knee never locks
  straight and the ground reaction equals the MPC's wrench.
* **Commanded path with anti-windup.** The CoM path is the integral of the (ramped) velocity
  command along the commanded heading, integrated every tick so turning is exact. It is kept
  within ``path_max_error_m`` of the CoM (anti-windup), so after a push the robot resumes
  the commanded velocity instead of walking back to where it was. The measured yaw is
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from gaitnet_mpc.command import Command
from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.control.lowlevel import LowLevelConfig
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.control.walking_base import WalkingBase
from gaitnet_mpc.dt_policy import (
    ACCEPTED_DT_INTERVAL,
    ACCEPTED_DT_REASON,
    NOMINAL_DT_S,
    PERIOD_INTERVAL,
    PERIOD_REASON,
)
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait import (
    GaitScheduleConfig,
    LandingBias,
    RaibertConfig,
    RaibertHeuristic,
    SwingConfig,
    SwingTrajectory,
    keep_beside_stance,
)
from gaitnet_mpc.gait.lip import lip_gains, lip_propagate
from gaitnet_mpc.geometry import heading_axes, rotate2, to_heading2
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.state import RobotState

#: Declared ranges shared by the walking controllers' settings (KDWalkConfig, WalkingConfig,
#: WBWalkConfig): the command's ramp rate, a swing target's depth below the ground and the
#: time constant of a return to the commanded path.
ACCEL_INTERVAL, ACCEL_REASON = "(0, 10] m/s^2", "> 0 to start; 10 m/s^2 is about 1 g"
DEPTH_INTERVAL, DEPTH_REASON = "[0, 0.05] m", "below the foothold; 5 cm is into the ground"
RETURN_INTERVAL, RETURN_REASON = "(0, 10] s", "None: off; past 10 s it is too slow to act"
_STANDS = "the humanoid's CoM stands 0.55 m high"
_FAR = "1 m is past any tracking error"
_HIPS = "the hips are 0.13 m apart"
_REACH = "1 m is past the legs' reach"


@dataclass(frozen=True)
class WalkingConfig:
    """Settings shared by the walking controllers (gait, footholds, swing, low level)."""

    # MPC stage = 1/5 of a step [s]
    dt_s: float = bounded(NOMINAL_DT_S, ACCEPTED_DT_INTERVAL, "a sampling time", ACCEPTED_DT_REASON)
    replan_period_s: float = bounded(0.01, PERIOD_INTERVAL, "a period", PERIOD_REASON)
    # walking CoM height; default: reset height + offset
    com_height_m: float | None = bounded(None, "(0, 1.5] m", "a height", _STANDS)
    # Walk with bent knees: at the standing height (knee 0.7 rad) a leg reaching 0.12 m
    # or more ahead at touchdown is nearly straight; the knee then locks at its limit,
    # carries the load with no torque and vaults the CoM up, so the MPC loses control of
    # the height and the swing leg cannot reach its foothold. 3 cm lower bends the knee
    # to about 1.0 rad (knee torque for m g about 18 N m of the 67 N m available).
    com_height_offset_m: float = bounded(
        -0.03, "[-0.3, 0.05] m", "an offset", "-0.3 m is a deep squat; straight legs: +0.04 m"
    )
    # the height reference moves there over this time
    com_height_ramp_s: float = bounded(0.5, "[0, 10] s", "a duration", "0: at once")
    # clamp of the position-tracking error in the reference
    max_pos_error_m: float = bounded(0.05, "[0, 1] m", "a distance", _FAR)
    # anti-windup: the commanded path stays this close
    path_max_error_m: float = bounded(0.10, "[0, 1] m", "a distance", _FAR)
    # the command is ramped up from rest at this rate
    max_accel_mps2: float = bounded(1.0, ACCEL_INTERVAL, "an acceleration", ACCEL_REASON)
    # CoM path error -> velocity added to the foothold command
    path_gain_per_s: float = bounded(1.0, "[0, 20] 1/s", "a gain", "20 /s acts within a stage")
    # bound of that added velocity
    max_path_feedback_mps: float = bounded(
        0.2, "[0, 2] m/s", "a speed", "past the fastest command, 1.5 m/s"
    )
    # footholds are frozen in the last 20 % of a swing
    retarget_stop_fraction: float = bounded(0.8, "[0, 1]", "a fraction", "of the swing")
    # lateral CoM-to-foot distance of the sway orbit
    stance_half_width_m: float = bounded(0.07, "[0, 0.3] m", "a distance", _HIPS)
    # forward/backward foothold limit from the stance foot
    max_step_m: float = bounded(0.35, "(0, 1] m", "a distance", _REACH)
    # feet never closer sideways (legs collide)
    min_lateral_separation_m: float = bounded(0.08, "[0, 1] m", "a distance", _REACH)
    # Widest step sideways from the stance foot. The hip roll reaches 0.6 rad outward, about
    # 0.22 m beside the hip at walking height, so 0.40 m between the feet is reachable;
    # it is what catching a 10 N s sideways push needs (0.30 m was not enough).
    max_lateral_separation_m: float = bounded(0.40, "[0, 1] m", "a distance", _REACH)
    # swing contact after this phase = touchdown
    early_touchdown_phase: float = bounded(0.5, "[0, 1]", "a phase", "of the swing")
    # a shorter swing is skipped (the foot stays down)
    min_swing_s: float = bounded(0.08, "[0, 1] s", "a duration", "1 s: 5 stages of 0.2 s")
    # Forward/backward reach of a foothold from the CoM predicted at touchdown (heading
    # frame): about the hip's reach with the knee still bent at walking height. A foothold
    # beyond it is not reached; the foot then lands late and short of the plan.
    max_reach_m: float = bounded(0.20, "(0, 1] m", "a distance", _REACH)
    # Swing-tracking bias compensation: the joint-PD swing leg (no inertial feedforward)
    # lands the foot 3 cm (0.5 m/s) to 5 cm (1 m/s) beyond its target, which puts the
    # stance foot ahead of where the LIP law wants it and costs ~10 % of the speed. The
    # overshoot (touchdown point minus swing target, heading frame, lateral outward) is
    # averaged over steps and subtracted from later swing targets; the MPC and the LIP
    # keep using the intended foothold.
    # per-step weight of the new measurement
    landing_bias_gain: float = bounded(0.3, "(0, 1]", "a weight", "an exponential average's")
    landing_bias_max_m: float = bounded(0.06, "[0, 0.3] m", "a bound", _FAR)
    # Stance legs get tau = [g(q) - J^T lambda]_leg (control/stance.py with qdd = 0) rather
    # than -J^T lambda alone: without the leg's own gravity torques the ground reaction
    # exceeds the MPC's wrench by about 12 N (the weight of the lower leg pushing on the
    # foot), so the CoM stood 1.5 cm above its reference while the MPC kept asking for less
    # force. Set False if the low-level controller compensates stance-leg gravity itself.
    stance_gravity_ff: bool = True
    low_level: LowLevelConfig = field(default_factory=LowLevelConfig)
    swing: SwingConfig = field(
        default_factory=lambda: SwingConfig(touchdown_speed_mps=0.3, foot_half_length_m=0.075)
    )
    # swing targets end this far below the ground
    touchdown_depth_m: float = bounded(0.005, DEPTH_INTERVAL, "a depth", DEPTH_REASON)

    def __post_init__(self) -> None:
        check_ranges(self)
        if self.min_lateral_separation_m > self.max_lateral_separation_m:
            raise ConfigError(
                "min_lateral_separation_m",
                self.min_lateral_separation_m,
                f"<= max_lateral_separation_m = {self.max_lateral_separation_m} m",
            )


def swing_beside_stance(
    robot: RobotModel, state: RobotState, swing: str, p_swing_m: np.ndarray, heading_rad: float
) -> np.ndarray:
    """The swing target ``p_swing_m`` (3,) kept :meth:`RobotModel.foot_separation_m` on its
    own side of the stance foot in the heading frame, so that a swing never sweeps through
    the stance leg (:func:`~gaitnet_mpc.gait.foothold.keep_beside_stance`)."""
    stance = FEET[1 - FEET.index(swing)]
    return keep_beside_stance(
        p_swing_m,
        swing,
        state.foot_pos_world_m[stance],
        heading_rad,
        robot.foot_separation_m(state.foot_yaw_rad[stance] - heading_rad),
    )


class WalkingController(WalkingBase):
    """Gait schedule + LIP/Raibert footholds + swing + low-level control around an MPC.

    Subclasses build their MPC, implement :meth:`_replan` (which sets the stance wrenches
    returned by :meth:`_wrenches_now`) and may override :meth:`_update_foothold`.
    """

    def __init__(
        self,
        robot: RobotModel,
        terrain: TerrainView,
        command: Command,
        config: WalkingConfig,
    ) -> None:
        super().__init__(
            robot,
            terrain,
            command,
            GaitScheduleConfig(default_dt_s=config.dt_s),
            config.low_level,
            config.max_accel_mps2,
        )
        self.config = config
        self._pin_data = robot.pin_model.createData()

    # --------------------------------------------------------------- episode
    def reset(self, state: RobotState) -> None:
        c = self.config
        super().reset(state)
        self.t_prev_s = state.t_s
        self.path_xy = state.com_world_m[:2].copy()
        self.z_start = float(state.com_world_m[2])
        self.z_walk = c.com_height_m or self.z_start + c.com_height_offset_m
        planar = self.robot.spec.planar
        step_s = self.schedule.config.stages_per_step * c.dt_s
        self.omega, k_v, lateral, self.cmd_scale = lip_gains(
            self.z_walk - self.ground_z, step_s, c.stance_half_width_m
        )
        self.raibert = RaibertHeuristic(
            RaibertConfig(
                hip_lateral_offset_m=0.0 if planar else lateral,
                velocity_gain_s=k_v,
                max_step_m=c.max_step_m,
                min_lateral_separation_m=0.0 if planar else c.min_lateral_separation_m,
                max_lateral_separation_m=0.0 if planar else c.max_lateral_separation_m,
            )
        )
        self.foot_pos = {f: state.foot_pos_world_m[f].copy() for f in FEET}
        self.foothold = dict(self.foot_pos)
        self.swing: SwingTrajectory | None = None
        self.landed = False  # the swing foot touched down early (stance for the rest)
        self.swing_t0_s = 0.0  # time in the step at which the swing trajectory starts
        self.aim: dict[str, np.ndarray] = {}  # swing target of a foot not yet landed
        self.landing = LandingBias(
            c.landing_bias_gain, c.landing_bias_max_m, planar=self.robot.spec.planar
        )
        self.step_seen = -1
        self.next_replan_s = -np.inf

    def planned_footholds(self) -> list[tuple[str, np.ndarray]]:
        foot = self.schedule.swing_foot
        if self.swing is None or self.landed:
            return []
        return [(foot, self.foothold[foot].copy())]

    # ------------------------------------------------------------- helpers
    def _z_ref(self, t_s: float) -> float:
        """CoM height reference at absolute time ``t_s`` (linear ramp from the start)."""
        ramp_s = self.config.com_height_ramp_s
        k = 1.0 if ramp_s <= 0.0 else min(1.0, max(t_s - self.t0_s, 0.0) / ramp_s)
        return self.z_start + k * (self.z_walk - self.z_start)

    def _cmd_world(self, yaw: float, t_s: float) -> np.ndarray:
        """Commanded CoM velocity (3,) in the world at time ``t_s`` after the start."""
        k = self.profile.ramp(t_s)
        vx, vy = k * self.command.vx_mps, k * self.command.vy_mps
        return np.array([*rotate2(yaw, (vx, vy)), 0.0])

    def _update_path(self, state: RobotState) -> None:
        """Integrate the commanded path to ``state.t_s`` and apply the anti-windup clamp."""
        dt = state.t_s - self.t_prev_s
        self.t_prev_s = state.t_s
        if dt > 0.0:
            v = self._cmd_world(self.profile.heading_rad(state.t_s), state.t_s - self.t0_s)
            self.path_xy += v[:2] * dt
        err = self.path_xy - state.com_world_m[:2]
        norm = float(np.linalg.norm(err))
        if norm > self.config.path_max_error_m:
            self.path_xy = state.com_world_m[:2] + err * (self.config.path_max_error_m / norm)

    def _path_feedback(self, state: RobotState, yaw: float) -> np.ndarray:
        """Bounded velocity (heading frame) that steers the footholds back to the path."""
        ex, ey = self.path_xy - state.com_world_m[:2]
        err_heading = to_heading2(yaw, (ex, ey))
        lim = self.config.max_path_feedback_mps
        return np.clip(self.config.path_gain_per_s * err_heading, -lim, lim)

    def _foothold(
        self,
        state: RobotState,
        foot: str,
        p_td_xy: np.ndarray,
        v_td_xy: np.ndarray,
        p_stance: np.ndarray,
        t_td_s: float,
        stance_s: float,
    ) -> np.ndarray:
        """Foothold (3,) of ``foot`` touching down at absolute time ``t_td_s`` with the CoM at
        (``p_td_xy``, ``v_td_xy``); the foot on ``p_stance`` stands until then."""
        yaw = self.profile.heading_rad(t_td_s)
        ramp = self.profile.ramp(t_td_s - self.t0_s)
        cmd = ramp * self.cmd_scale * np.array([self.command.vx_mps, self.command.vy_mps])
        p = self.raibert.foothold(
            foot,
            p_com_world_m=np.array([p_td_xy[0], p_td_xy[1], state.com_world_m[2]]),
            v_com_world_mps=v_td_xy,
            cmd_vel_mps=cmd + self._path_feedback(state, yaw),
            stance_duration_s=stance_s,
            time_to_touchdown_s=0.0,
            p_stance_foot_world_m=p_stance,
            ground_z_m=self.ground_z,
            yaw_rad=yaw,
            cmd_yaw_rate_radps=self.command.yaw_rate_radps,
        )
        e_x, _ = heading_axes(yaw)
        dx, dy = p[:2] - p_td_xy
        fwd = e_x[0] * dx + e_x[1] * dy
        lim = self.config.max_reach_m
        if abs(fwd) > lim:
            p[:2] -= (fwd - np.clip(fwd, -lim, lim)) * e_x
        p[2] = self.ground_z + self.robot.spec.foot_contact_radius_m - self.config.touchdown_depth_m
        if self.robot.spec.planar:
            p[1] = state.foot_pos_world_m[foot][1]
        return p

    def _stance_pos(self, state: RobotState, foot: str) -> np.ndarray:
        """Where ``foot`` stands: measured while in contact, else the last stored position."""
        if state.foot_contact[foot]:
            self.foot_pos[foot] = state.foot_pos_world_m[foot].copy()
        return self.foot_pos[foot]

    def _plan_swing_foothold(self, state: RobotState, t_left_s: float) -> np.ndarray:
        """Foothold of the current swing foot: Raibert at the LIP-predicted touchdown."""
        sched = self.schedule
        p_st = self._stance_pos(state, sched.stance_foot)
        p_td, v_td = lip_propagate(
            state.com_world_m[:2], state.com_vel_world_mps[:2], p_st[:2], self.omega, t_left_s
        )
        next_dt = sched.next_step_dt_s or sched.current_step_dt_s
        stance_s = sched.config.stages_per_step * next_dt
        return self._foothold(
            state, sched.swing_foot, p_td, v_td, p_st, state.t_s + t_left_s, stance_s
        )

    def _measure_landing(self, state: RobotState, foot: str) -> None:
        """Update the swing overshoot estimate with ``foot``'s touchdown point (once per
        swing; ``self.aim[foot]`` is where its swing was aimed)."""
        aim = self.aim.pop(foot, None)
        if aim is not None:
            yaw = self.profile.heading_rad(state.t_s)
            self.landing.measure(foot, state.foot_pos_world_m[foot], aim, yaw)

    def _swing_target(self, foot: str, foothold: np.ndarray, t_s: float) -> np.ndarray:
        """Where to aim the swing foot so that it lands on ``foothold`` (bias removed)."""
        return self.landing.aim(foot, foothold, self.profile.heading_rad(t_s))

    def _start_swing(self, state: RobotState) -> None:
        """Plan the swing foot's foothold and a swing over the time left in the step."""
        sched = self.schedule
        foot = sched.swing_foot
        t_left = sched.time_left_in_step_s
        self.next_replan_s = -np.inf
        if t_left < self.config.min_swing_s:  # too late to step: stay down this step
            self.swing = None
            self.landed = True
            self.foothold[foot] = state.foot_pos_world_m[foot].copy()
            return
        foothold = self._plan_swing_foothold(state, t_left)
        self.foothold[foot] = foothold
        target = self._swing_target(foot, foothold, state.t_s + t_left)
        p0 = state.foot_pos_world_m[foot]
        obstacles = self.terrain.swing_obstacles(p0[0], target[0])
        self.swing = self.config.swing.trajectory(
            p0, target, t_left, [(o.x_min, o.x_max, o.z_top_m) for o in obstacles]
        )
        self.swing_t0_s = sched.time_in_step_s
        self.aim[foot] = target

    def _on_step_start(self, state: RobotState) -> None:
        sched = self.schedule
        stance = sched.stance_foot
        self._steps.append(sched.current_step_duration_s)
        self.landed = False
        self.foot_pos[stance] = state.foot_pos_world_m[stance].copy()
        if sched.step_index > 0 and not state.foot_contact[stance]:
            # Landing late: not waited for (module docstring). Its landing is not measured,
            # the other foot's foothold starts from where it stands, the MPC replans now.
            self.foothold[sched.swing_foot] = state.foot_pos_world_m[sched.swing_foot].copy()
            self.next_replan_s = -np.inf
        elif sched.step_index > 0:
            self._measure_landing(state, stance)  # it did not touch down early
        self._start_swing(state)

    def _update_foothold(self, state: RobotState) -> None:
        """Re-plan the swing foot's foothold with the current CoM state (until the last
        ``retarget_stop_fraction`` of the swing) and bend the swing path to it."""
        sched = self.schedule
        if (
            self.swing is None
            or self.landed
            or sched.phase_in_step > self.config.retarget_stop_fraction
        ):
            return
        foot = sched.swing_foot
        foothold = self._plan_swing_foothold(state, sched.time_left_in_step_s)
        target = self._swing_target(foot, foothold, state.t_s + sched.time_left_in_step_s)
        if self.swing.retarget(target, sched.time_in_step_s - self.swing_t0_s):
            self.foothold[foot] = foothold
            self.aim[foot] = target

    # ------------------------------------------------------------- the MPC
    @abstractmethod
    def _replan(self, state: RobotState) -> None:
        """Solve the MPC from ``state`` (sets what :meth:`_wrenches_now` returns)."""

    @abstractmethod
    def _wrenches_now(self, state: RobotState) -> np.ndarray | None:
        """(2, 6) planned ``[f; tau]`` per foot (``FEET`` order) for now, None before the
        first plan."""

    # --------------------------------------------------------------- control
    def compute(self, state: RobotState) -> np.ndarray:
        sched = self.schedule
        sched.advance_to(state.t_s)
        if sched.step_index != self.step_seen:
            self.step_seen = sched.step_index
            self._on_step_start(state)
        self._update_path(state)
        swing, stance = sched.swing_foot, sched.stance_foot
        if (
            not self.landed
            and sched.phase_in_step >= self.config.early_touchdown_phase
            and state.foot_contact[swing]
        ):
            # Early touchdown: stance from now on (double support for the rest of the step).
            self.landed = True
            self.next_replan_s = -np.inf
            self._measure_landing(state, swing)
        if state.t_s >= self.next_replan_s:
            self._update_foothold(state)
            self._replan(state)
            self.next_replan_s = state.t_s + self.config.replan_period_s
        wrench = {}
        planned = self._wrenches_now(state)
        if planned is not None:
            wrench[stance] = planned[FEET.index(stance)]
            if self.landed:
                wrench[swing] = planned[FEET.index(swing)]
        target = {}
        yaw = None if self.robot.spec.planar else self.profile.heading_rad(state.t_s)
        if not self.landed and self.swing is not None:
            t_swing = sched.time_in_step_s - self.swing_t0_s
            p_swing = self.swing.position(t_swing)
            if yaw is not None:
                p_swing = swing_beside_stance(self.robot, state, swing, p_swing, yaw)
            target[swing] = (p_swing, self.swing.velocity(t_swing))
        tau = self.low.torques(state, wrench, target, yaw)
        if self.config.stance_gravity_ff and wrench:
            r = self.robot
            q, _ = r.mj_to_pin(state.qpos, state.qvel)
            g = pin.computeGeneralizedGravity(r.pin_model, self._pin_data, q)[r.n_root_dofs :]
            for foot in wrench:
                idx = r.leg_joint_index[foot]
                tau[idx] = np.clip(
                    tau[idx] + g[idx], -r.torque_limit_nm[idx], r.torque_limit_nm[idx]
                )
        return tau
