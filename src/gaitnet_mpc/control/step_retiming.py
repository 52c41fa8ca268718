"""Re-timing the step under way (beyond the paper; issue 48, item 3).

The paper sets a step's dt once, at its start (Remark 4). A push in mid-swing then cannot
shorten the step under way, and until the next step start a variable and a fixed frequency
react alike. With ``dt_policy.gaitnet.retime_steps`` set (:class:`StepRetimingConfig`; on
by default, off under ``--preset paper``), each replan within a step of ``gaitnet`` may
shorten the rest of the step, by the capture-point rule below. A fixed-frequency
controller (``kd``) keeps its timing, so that comparisons stay fair.

The rule. The linear inverted pendulum about the stance foot ``p_s`` (``omega = sqrt(g /
z)``, ``z`` the CoM's height above the stance foot) predicts, ``tau`` from now, the CoM and
its divergent component of motion (the capture point) ``xi = c + v / omega``:

    c(tau)  = p_s + (c_0 - p_s) cosh(omega tau) + (v_0 / omega) sinh(omega tau)
    xi(tau) = p_s + (xi_0 - p_s) exp(omega tau)

The foothold from which a periodic LIP gait walks on at the commanded speed ``v`` along
the heading is ``p*(tau) = xi(tau) - b e_x``, with the gait's offset ``b = v T / (exp(omega
T) - 1)`` (``T`` the step's duration; from ``xi`` at a step's end being ``b`` past the next
foot, ``xi_end = p + b exp(omega T)`` and ``xi_end = p + v T + b``). Sideways the offset is
taken as 0: the default lateral reference plans the feet 2-7 cm apart.

``p*`` is in reach when it lies in the horizontal section, at the standing hip height, of
the QP's reach pyramid (:mod:`~gaitnet_mpc.mpc.kinematic_rows`): within ``l sin(alpha)``
(humanoid3d: 0.15 m) of the swing leg's hip at ``c(tau)`` along the heading and across it.
If the step's present end keeps ``p*`` in reach, nothing changes. Otherwise the step is
shortened to the longest duration ``5 dt`` (``dt`` on a grid from ``min_dt_s`` up) whose
``p*`` is in reach.

Where the terrain decides the foothold (stones, a gap's far side), an end counts only if
its ``p*`` also lies in the eq. 24 box of the step's touchdown: the swing lands in that box
whatever the timing, so a shorter step there only asks the swing to cover the same
distance in less time. Traced on tuning stones, seed 124: Gait-Net chose a 0.33 s step for
the 0.56 m stride to the next stone, the rule cut it to 0.19 s at its start, and the foot
landed 3.5 cm short of the stone and the robot fell. On open ground the box holds every
``p*`` and the rule is unchanged.

When no duration puts ``p*`` in reach, nothing changes either: the pendulum, which has no
ankle torque and no angular momentum, then says that no timing recovers, while the MPC
may still brake through the stance foot's centre of pressure and the trunk. Taking the
shortest step there made forward pushes worse (a 75 N push at 0.25 m/s, tuning seed 312:
six 0.15 s steps, each too short to catch up, and a fall, where the unchanged controller
took one 0.325 s step and walked on).

The exception (``shortest_when_crossing``): where ``p*`` lies beyond the stance foot,
across from the swing leg, the swing foot cannot get there at any end without crossing
under the body (the QP's separation rows keep the feet apart). The catching step is then
the other foot's next one, and the step under way ends as early as allowed. Traced on a
60 N push to the left at phase 0.5 (``docs/design/step_retiming.md``): the right foot's
step ran its full 0.243 s, the robot rolled over its left stance foot, that leg ran out
of length and the robot fell; ending the right step at 0.15 s let the left foot catch.

The rule only shortens: a step made longer after a push is what Gait-Net's own answers
already do wrong (``docs/design/gaitnet_recovery.md``).

A landing (``end_at_touchdown``, on by default): a swing foot that touches down in the second
half of its step with at least half the robot's weight on it ends the step at the next
tick, so that the MPC takes it as its stance foot where it landed; otherwise the swing PD
drives it on along the rest of its swing, below the ground. Only where the foot's centre
is on a patch it may use (:meth:`TerrainView.holds_foot`): on stones an early landing may
fall short of the stone, onto its edge, and ending the step there makes the landing a
foothold violation, where the swing would have carried the foot on (seeded stones,
seed 5: `benchmarks/results/end_at_touchdown/on_patch/`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from gaitnet_mpc.control.blind_touchdown import EARLY_TOUCHDOWN_PHASE
from gaitnet_mpc.dt_policy import DtPolicyConfig, StepRetimingConfig
from gaitnet_mpc.gait import GaitSchedule, SwingTrajectory
from gaitnet_mpc.gait.lip import lip_frequency
from gaitnet_mpc.geometry import GRAVITY_MPS2, heading_axes
from gaitnet_mpc.mpc.kinematic_rows import reach_geometry
from gaitnet_mpc.mpc.sequential import FootholdBox
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.state import RobotState

LandingCheck = Callable[[str, np.ndarray], bool]
"""Whether a foot (``"left"``/``"right"``) whose centre is at a point (3,) [m] stands on a
foothold (``end_at_touchdown``)."""


@dataclass(frozen=True)
class RetimeDecision:
    """A shortened step: its new dt [s] and what the rule saw (for ``swing_events``:
    ``kind`` "retime" for the capture-point rule, "landing" for a landed foot)."""

    dt_s: float
    dt_before_s: float
    time_in_step_s: float
    excess_before_m: float
    excess_after_m: float
    kind: str = "retime"

    def to_dict(self, t_s: float, foot: str) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "t_s": round(t_s, 4),
            "foot": foot,
            "dt_before_s": round(self.dt_before_s, 4),
            "dt_s": round(self.dt_s, 4),
            "time_in_step_s": round(self.time_in_step_s, 4),
            "excess_before_m": round(self.excess_before_m, 4),
            "excess_after_m": round(self.excess_after_m, 4),
        }


def capture_point_m(
    tau_s: np.ndarray,
    com_xy_m: np.ndarray,
    com_vel_xy_mps: np.ndarray,
    stance_xy_m: np.ndarray,
    omega_radps: float,
) -> np.ndarray:
    """(n, 2) the pendulum's capture point ``xi(tau)`` (module docstring) at each of the
    ``n`` times ``tau_s``."""
    rel = com_xy_m - stance_xy_m + com_vel_xy_mps / omega_radps
    return stance_xy_m + rel * np.exp(omega_radps * tau_s)[:, None]


def reach_excess_m(
    tau_s: np.ndarray,
    com_xy_m: np.ndarray,
    com_vel_xy_mps: np.ndarray,
    stance_xy_m: np.ndarray,
    omega_radps: float,
    heading_rad: float,
    hip_offset_xy_m: np.ndarray,
    offset_b_m: float,
    reach_m: float,
) -> np.ndarray:
    """(n,) how far ``p*(tau)`` lies outside the swing hip's reach square, for each of the
    ``n`` times ``tau_s`` [m] (<= 0: in reach; module docstring). The pendulum of
    :func:`~gaitnet_mpc.gait.lip.lip_propagate`, for many times at once."""
    ch, sh = np.cosh(omega_radps * tau_s), np.sinh(omega_radps * tau_s)
    rel = com_xy_m - stance_xy_m
    c = stance_xy_m + rel * ch[:, None] + (com_vel_xy_mps / omega_radps) * sh[:, None]
    xi = capture_point_m(tau_s, com_xy_m, com_vel_xy_mps, stance_xy_m, omega_radps)
    e_x, e_y = heading_axes(heading_rad)
    hip = c + hip_offset_xy_m[0] * e_x + hip_offset_xy_m[1] * e_y
    d = xi - offset_b_m * e_x - hip  # (n, 2)
    along, across = d @ e_x, d @ e_y
    return np.maximum(np.abs(along), np.abs(across)) - reach_m


def retime_step(
    config: StepRetimingConfig,
    *,
    dt_s: float,
    max_dt_s: float,
    time_in_step_s: float,
    com_m: np.ndarray,
    com_vel_mps: np.ndarray,
    stance_m: np.ndarray,
    heading_rad: float,
    hip_offset_xy_m: np.ndarray,
    reach_m: float,
    speed_cmd_mps: float,
    stages_per_step: int = 5,
    box_xy_m: tuple[np.ndarray, np.ndarray] | None = None,
) -> RetimeDecision | None:
    """The rule of the module docstring at one replan; None: keep the step's end.

    ``dt_s``: the step's dt now; ``max_dt_s``: the longest dt it may take (its dt
    bounds); ``com_m``, ``com_vel_mps``, ``stance_m``: measured CoM, its velocity and the
    stance foot (world, each (3,)); ``hip_offset_xy_m``: (2,) the swing leg's hip from the
    CoM in the heading frame; ``reach_m``: the reach square's half-width [m];
    ``speed_cmd_mps``: the commanded speed along the heading; ``box_xy_m``: (lo, hi),
    each (2,), the eq. 24 box of the step's touchdown, or None (unbounded).
    """
    z = float(com_m[2] - stance_m[2])
    if z <= 0.05:  # not a pendulum
        return None
    omega = lip_frequency(z)
    n = stages_per_step
    hi = min(dt_s, max_dt_s)
    dts = np.arange(config.min_dt_s, hi + 1e-12, config.grid_dt_s)
    dts = np.append(dts[dts < dt_s - 1e-9], dt_s)  # candidates, the step's own dt last
    tau = n * dts - time_in_step_s
    keep = tau >= config.min_remaining_s
    keep[-1] = True
    dts, tau = dts[keep], np.maximum(tau[keep], 0.0)
    period = n * dt_s
    b = speed_cmd_mps * period / math.expm1(omega * period)
    pendulum = (
        np.asarray(com_m[:2], dtype=float),
        np.asarray(com_vel_mps[:2], dtype=float),
        np.asarray(stance_m[:2], dtype=float),
        omega,
    )
    excess = reach_excess_m(tau, *pendulum, heading_rad, hip_offset_xy_m, b, reach_m)
    if excess[-1] <= 0.0:
        return None
    on_box = np.ones(len(tau), dtype=bool)
    if box_xy_m is not None:  # the foothold p* must be one the terrain offers
        p_star = capture_point_m(tau, *pendulum) - b * heading_axes(heading_rad)[0]
        on_box = np.all((p_star >= box_xy_m[0]) & (p_star <= box_xy_m[1]), axis=1)
    ok = np.flatnonzero((excess <= 0.0) & on_box)
    if not ok.size and config.shortest_when_crossing and len(dts) > 1 and on_box[0]:
        # the capture point at the step's end, across the heading from the stance foot,
        # on the swing leg's side (> 0) or beyond the stance foot (< 0: crossing)
        xi_rel = capture_point_m(tau[-1:], *pendulum)[0] - pendulum[2]
        side = math.copysign(1.0, float(hip_offset_xy_m[1]))
        if side * float(xi_rel @ heading_axes(heading_rad)[1]) < 0.0:
            ok = np.array([0])  # the shortest end
    if not ok.size:
        return None
    i = int(ok[-1])
    return RetimeDecision(
        dt_s=float(dts[i]),
        dt_before_s=dt_s,
        time_in_step_s=time_in_step_s,
        excess_before_m=float(excess[-1]),
        excess_after_m=float(excess[i]),
    )


class StepRetimer:
    """The rule in a controller's loop: the robot's reach geometry, and the re-timings made
    (``events``, for ``summary.json``'s ``swing_events``). ``on_retime`` is told each new
    dt [s] (the dt policy, whose fallback keeps the previous step's executed dt)."""

    def __init__(
        self,
        config: StepRetimingConfig,
        robot: RobotModel,
        on_retime: Callable[[float], None] | None = None,
        landing: LandingCheck | None = None,
    ) -> None:
        hips, leg_m, tilt_rad = reach_geometry(robot)
        self.config = config
        self.on_retime = on_retime
        self.landing = landing
        self.hips_xy_m = {f: np.array(hips[3 * i : 3 * i + 2]) for i, f in enumerate(FEET)}
        self.reach_m = leg_m * math.sin(tilt_rad)
        self.half_weight_n = 0.5 * robot.total_mass_kg * GRAVITY_MPS2
        self.events: list[dict[str, Any]] = []

    @classmethod
    def of(
        cls,
        policy: DtPolicyConfig,
        robot: RobotModel,
        on_retime: Callable[[float], None] | None = None,
        landing: LandingCheck | None = None,
    ) -> StepRetimer | None:
        """The re-timer of a controller with ``policy`` on ``robot``, or None. Only
        ``gaitnet`` re-times (a fixed frequency keeps its timing), and only a robot with a
        3-D humanoid's legs (the planar biped has no reach geometry)."""
        config = policy.gaitnet.retime_steps
        if policy.kind != "gaitnet" or config is None or robot.spec.planar:
            return None
        return cls(config, robot, on_retime, landing)

    def end_at_touchdown(
        self, state: RobotState, schedule: GaitSchedule, swing: SwingTrajectory | None
    ) -> bool:
        """With ``config.end_at_touchdown``: where the swing foot has landed in the second
        half of the step, carrying at least half the robot's weight, on a foothold that
        ``landing`` (if given) accepts, the step ends at the next tick (or as soon as the
        schedule's bounds allow); True if it was re-timed. Logged as a ``landing`` event
        (zero reach excess)."""
        foot = schedule.swing_foot
        if (
            not self.config.end_at_touchdown
            or swing is None
            or schedule.phase_in_step < EARLY_TOUCHDOWN_PHASE
            or state.foot_wrench_world[foot][2] < self.half_weight_n
        ):
            return False
        if self.landing is not None and not self.landing(foot, state.foot_pos_world_m[foot]):
            return False
        n = schedule.config.stages_per_step
        dt = max((schedule.time_in_step_s + 0.001) / n, schedule.config.dt_bounds_s[0])
        if dt >= schedule.current_step_dt_s - 1e-9:
            return False
        t_in = schedule.time_in_step_s
        decision = RetimeDecision(dt, schedule.current_step_dt_s, t_in, 0.0, 0.0, "landing")
        self._shorten(state, schedule, swing, decision)
        return True

    def _shorten(
        self,
        state: RobotState,
        schedule: GaitSchedule,
        swing: SwingTrajectory,
        decision: RetimeDecision,
    ) -> None:
        """End the step under way (schedule and swing) as ``decision`` says, log it and tell
        ``on_retime``."""
        schedule.retime_step(decision.dt_s)
        swing.retime(schedule.current_step_duration_s, schedule.time_in_step_s)
        self.events.append(decision.to_dict(state.t_s, schedule.swing_foot))
        if self.on_retime is not None:
            self.on_retime(decision.dt_s)

    def apply(
        self,
        state: RobotState,
        schedule: GaitSchedule,
        swing: SwingTrajectory | None,
        heading_rad: float,
        speed_cmd_mps: float,
        box: FootholdBox | None = None,
    ) -> bool:
        """Shorten the step under way (schedule and swing) if the rule asks; True if so.
        ``box``: the eq. 24 box of the step's touchdown (None: unbounded)."""
        if swing is None:  # no step under way yet
            return False
        decision = retime_step(
            self.config,
            dt_s=schedule.current_step_dt_s,
            max_dt_s=schedule.config.dt_bounds_s[1],
            time_in_step_s=schedule.time_in_step_s,
            com_m=state.com_world_m,
            com_vel_mps=state.com_vel_world_mps,
            stance_m=state.foot_pos_world_m[schedule.stance_foot],
            heading_rad=heading_rad,
            hip_offset_xy_m=self.hips_xy_m[schedule.swing_foot],
            reach_m=self.reach_m,
            speed_cmd_mps=speed_cmd_mps,
            stages_per_step=schedule.config.stages_per_step,
            box_xy_m=None if box is None else (box.lo_m[:2], box.hi_m[:2]),
        )
        if decision is None:
            return False
        self._shorten(state, schedule, swing, decision)
        return True


__all__ = [
    "LandingCheck",
    "RetimeDecision",
    "StepRetimer",
    "capture_point_m",
    "reach_excess_m",
    "retime_step",
]
