"""What a ``kd``-family swing knows of the obstacles, and what it learns by striking them.

The footprints of the obstacles are always known; their tops are known with
``obstacle_heights`` and otherwise taken as ``unknown_obstacle_height_m`` high. A toe
strike raises the struck obstacle's assumed top and re-plans the swing over it; the
shank is checked along the planned swing and a low pass is recorded
(docs/design/obstacles.md, decisions 3, 5 and 6). Both go to ``swing_events``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gaitnet_mpc.command import CommandProfile
from gaitnet_mpc.control.kd_walk_config import KDWalkConfig
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.gait import SwingTrajectory
from gaitnet_mpc.gait.schedule import GaitSchedule
from gaitnet_mpc.kinematics.shank_clearance import shank_capsules, swing_shank_clearance_m
from gaitnet_mpc.mpc.sequential import SequentialResult
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.state import RobotState
from gaitnet_mpc.terrain import Obstacle

#: Gap between the foot at a swing's end and the part of its patch it clears [m].
_EDGE_GAP_M = 0.01


def _footprint(ob: Obstacle) -> tuple[float, ...]:
    """A key of one obstacle: its footprint."""
    return (ob.x_min, ob.x_max, ob.y_min, ob.y_max)


class SwingObstacles:
    """The obstacles' tops as the swings take them, toe strikes and the shank check.

    Attributes:
        events: ``summary.json``'s ``swing_events``: kind ``toe_strike`` (time, foot, foot
            position, the struck obstacles' tops after the strike) or ``shank`` (time,
            foot, the least shank clearance over each obstacle of the swing, None where the
            shank never passes over it, and their tops).
    """

    def __init__(self, robot: RobotModel, terrain: TerrainView, config: KDWalkConfig) -> None:
        self.robot, self.terrain, self.config = robot, terrain, config
        self.events: list[dict[str, Any]] = []
        self._raised_top_m: dict[tuple[float, ...], float] = {}  # footprint -> raised top
        self._shanks = shank_capsules(robot)
        self._pin_data = robot.pin_model.createData()
        self._touching: dict[str, bool] = {}
        self._shank_recorded_step = -1

    def reset(self, state: RobotState) -> None:
        """Forget what earlier episodes learnt; read the feet's contact sensors."""
        self.events.clear()
        self._raised_top_m.clear()
        self._touching = dict(state.foot_contact)
        self._shank_recorded_step = -1

    def near(self, start: np.ndarray, target: np.ndarray) -> list[tuple[float, float, float]]:
        """``(x_min, x_max, top_z)`` of what the swing from ``start`` to ``target`` clears:
        the obstacles near it (``swing_obstacle_window_m``), with the tops of :meth:`top`,
        and the terrain steps it passes over (:meth:`steps_between`)."""
        x0, x1 = sorted((start[0], target[0]))
        behind_m, ahead_m = self.config.swing_obstacle_window_m
        found = self.terrain.obstacle_footprints(x0 - behind_m, x1 + ahead_m)
        return [(o.x_min, o.x_max, self.top(o)) for o in found] + self.steps_between(start, target)

    def steps_between(
        self, start: np.ndarray, target: np.ndarray
    ) -> list[tuple[float, float, float]]:
        """``(x_min, x_max, top_z)`` of the ground the swing passes over that stands higher
        than the lower of its lift-off and touchdown patches (uneven tiles): a patch in
        between, and of a higher end's own patch the part the foot does not stand on (ahead
        of the lifted foot when stepping down, behind the landing foot when stepping up:
        the edge a heel or a toe would clip). A patch counts where the foot's centre
        passes over it: the clearance is reckoned along x over the patch's whole length,
        so a patch that the foot's edge only grazes beside the path (a stepping stone of
        the other foot) would lift the whole swing. Level ground gives none, so swings
        there are unchanged."""
        patches = self.terrain.patches_crossed(*start[:2], *target[:2])
        first = [p for p in patches if p.contains(*start[:2])]
        last = [p for p in patches if p.contains(*target[:2])]
        if not first or not last:  # an end over a hole: its height is not known here
            return []
        lower = min(first[0].z_top_m, last[0].z_top_m) + 1e-3  # the lower end, + 1 mm
        ahead = 1.0 if target[0] >= start[0] else -1.0
        reach = self.config.swing.foot_half_length_m + _EDGE_GAP_M  # from the foot point
        out = []
        for p in patches:
            if p.z_top_m <= lower:
                continue
            lo, hi = p.x_min, p.x_max
            for end, sign in ((start, ahead), (target, -ahead)):  # off the foot at each end
                if p.contains(*end[:2]):
                    lo, hi = (
                        (max(lo, end[0] + reach), hi) if sign > 0 else (lo, min(hi, end[0] - reach))
                    )
            if lo < hi:
                out.append((lo, hi, p.z_top_m))
        return out

    def top(self, ob: Obstacle) -> float:
        """The top [m] a swing clears over ``ob``: its known top, or with
        ``obstacle_heights`` off ``unknown_obstacle_height_m`` above its base; raised by
        toe strikes on it (:meth:`toe_strike`)."""
        if self.terrain.knowledge.obstacle_heights:
            top = ob.z_top_m
        else:
            top = ob.z_base_m + self.config.unknown_obstacle_height_m
        return max(top, self._raised_top_m.get(_footprint(ob), -np.inf))

    def toe_strike(
        self,
        state: RobotState,
        foot: str,
        swing: SwingTrajectory,
        liftoff_m: np.ndarray,
        t_in_step_s: float,
    ) -> None:
        """Lift and re-place a swing foot that struck an obstacle.

        A strike is the swing foot's contact sensor turning on while the foot (its toe
        and heel extent, 1 cm wider) is over or against a known obstacle footprint:
        footholds keep off footprints by more than that (``foothold_obstacle_clearance_m``
        and the eq. 24 margin), so a planned touchdown never counts. Each obstacle the foot
        meets is then taken as ``toe_strike_raise_m`` higher than the foot point or than
        its previous top, and the rest of the swing is re-planned over it to the same
        target (:meth:`SwingTrajectory.retarget`: a new apex, continuous with the plan so
        far). Re-planning from the measured foot position instead, with a lift in place,
        jerked the foot: the 8 and 10 cm boxes of the design record fell that way.
        """
        touching, before = state.foot_contact, self._touching
        self._touching = dict(touching)
        raise_m = self.config.toe_strike_raise_m
        if raise_m <= 0.0 or not touching[foot] or before.get(foot, True):
            return
        p = state.foot_pos_world_m[foot]
        spec, margin = self.robot.spec, 0.01
        struck = [
            ob
            for ob in self.terrain.obstacle_footprints(
                p[0] - spec.foot_heel_m - margin, p[0] + spec.foot_toe_m + margin
            )
            if ob.y_min - margin <= p[1] <= ob.y_max + margin
        ]
        if not struck:
            return
        for ob in struck:
            self._raised_top_m[_footprint(ob)] = max(self.top(ob), float(p[2])) + raise_m
        self.events.append({
            "kind": "toe_strike", "t_s": round(state.t_s, 4), "foot": foot,
            "foot_pos_m": [round(float(x), 4) for x in p],
            "obstacle_tops_m": [round(self.top(ob), 4) for ob in struck],
        })  # fmt: skip
        target = swing.p1_world_m
        swing.retarget(target, t_in_step_s, obstacles=self.near(liftoff_m, target))

    def check_shank(
        self,
        state: RobotState,
        schedule: GaitSchedule,
        swing: SwingTrajectory | None,
        plan: SequentialResult | None,
        profile: CommandProfile,
    ) -> None:
        """Check the swing leg's shank against the obstacles along the rest of the planned
        swing (:mod:`~gaitnet_mpc.kinematics.shank_clearance`: trunk from the plan's
        reference, the leg by the IK to the planned foot path) and record, once per step,
        a plan that passes it less than ``shank_clearance_m`` above an obstacle's assumed
        top.

        Only recorded, not acted on: the shank reaches over a box only with the foot beside
        it (leaning back at a touchdown just past it, forward at a lift-off just before
        it), where raising the swing changes nothing; how far footholds keep off a box is
        ``foothold_obstacle_clearance_m``'s (docs/design/obstacles.md)."""
        foot = schedule.swing_foot
        capsule = self._shanks.get(foot)
        if swing is None or plan is None or capsule is None or len(swing.obstacles) == 0:
            return
        if self._shank_recorded_step == schedule.step_index:
            return
        t_now = schedule.time_in_step_s
        times = np.linspace(t_now, swing.duration_s, 10)
        ref = plan.reference
        rel = times - t_now + (state.t_s - plan.t_plan_s)  # on the plan's clock
        p_base = np.stack([np.interp(rel, ref.times_s, ref.p_base_ref[:, a]) for a in range(3)], 1)
        k = np.minimum(np.searchsorted(ref.times_s, rel), ref.times_s.size - 1)
        yaw = None
        if not self.robot.spec.planar:
            yaw = np.array([profile.heading_rad(state.t_s + t - t_now) for t in times])
        clear = swing_shank_clearance_m(
            self.robot, self._pin_data, capsule, foot, p_base, ref.rot_base_ref[k],
            swing.position(times), swing.obstacles, yaw,
        )  # fmt: skip
        if np.min(clear) < self.config.shank_clearance_m:
            self._shank_recorded_step = schedule.step_index
            self.events.append({
                "kind": "shank", "t_s": round(state.t_s, 4), "foot": foot,
                "clearance_m": [round(float(c), 4) if np.isfinite(c) else None for c in clear],
                "obstacle_tops_m": [round(float(o[2]), 4) for o in swing.obstacles],
            })  # fmt: skip
