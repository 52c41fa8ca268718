"""What a walking controller knows about the terrain: one explicit, recorded object.

The paper's controller has a *one-step terrain preview* (Sec. IV-B, eq. 24): at each step
it knows the patches the next touchdown may use, with their boxes and heights. A robot that
perceives its next foothold also perceives what stands between its swing foot and that
foothold, so the one-step preview here includes where the obstacles between a swing's
lift-off and its touchdown stand, the patches under its path (the tiles of uneven ground
a long step passes over), and the obstacles' heights
(``TerrainKnowledge.obstacle_heights``, on by default; off, as in the paper's Fig. 1(e)
hardware run, the heights are not known and the controller assumes one). The multi-step
footstep preview of ``kd --preview`` (beyond the paper) may in addition read every patch
of the course ahead (:meth:`TerrainView.course_for_multi_step_preview`). A *blind*
controller (``TerrainKnowledge.blind``, ``--blind``, the paper's "unknown terrain" of
Fig. 1(c)) is told nothing: no patch, no height, no obstacle; it plans on the height of
its stance foot and finds the ground with the swing foot (``control/blind_touchdown.py``).

Controllers get a :class:`TerrainView`, never the :class:`~gaitnet_mpc.terrain.Course`
itself, and ``summary.json`` records the run's :class:`TerrainKnowledge` under
``terrain_knowledge``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.terrain import Course, Obstacle, Patch

__all__ = ["TerrainKnowledge", "TerrainView"]


@dataclass(frozen=True)
class TerrainKnowledge:
    """Which terrain information a controller may use.

    Attributes:
        multi_step: the multi-step footstep preview (``--preview``) may read the patches of
            the course ahead (beyond the paper); False: the paper's one-step preview.
        obstacle_heights: swing trajectories know the heights of the obstacles between
            lift-off and touchdown; where an obstacle stands (its footprint) is known
            either way.
        blind: nothing is known: every query answers as over unbroken ground of unknown
            height (no patch, the caller's default height, no obstacles).
    """

    multi_step: bool = False
    obstacle_heights: bool = True
    blind: bool = False

    def __post_init__(self) -> None:
        if self.blind and self.multi_step:
            raise ConfigError("blind", True, "False with the multi-step preview (--preview)")

    def to_dict(self) -> dict[str, object]:
        return {"preview": "multi-step" if self.multi_step else "one-step", **asdict(self)}


class TerrainView:
    """The queries a walking controller may make of the course (module docstring)."""

    def __init__(self, course: Course, knowledge: TerrainKnowledge | None = None) -> None:
        self._course = course
        self.knowledge = knowledge or TerrainKnowledge()

    # ------------------------------------------------------------- one-step preview
    def patch_at(self, x_m: float, y_m: float) -> int | None:
        """Index of the patch under a candidate foothold (None: a hole).

        Raises:
            ConfigError: the controller is blind.
        """
        if self.knowledge.blind:
            raise ConfigError("terrain_knowledge.blind", True, "False for a patch query")
        return self._course.patch_at(x_m, y_m)

    def patch(self, index: int) -> Patch:
        """The patch (box, height, feet allowed) of a foothold found by a query here."""
        return self._course.patches[index]

    def foothold_height_m(self, x_m: float, y_m: float, default_m: float) -> float:
        """Top of the patch under a candidate foothold, ``default_m`` over a hole or when
        blind [m]."""
        if self.knowledge.blind:
            return default_m
        j = self.patch_at(x_m, y_m)
        return self.patch(j).z_top_m if j is not None else default_m

    def holds_foot(self, foot: str, pos_m: ArrayLike) -> bool:
        """True iff a ``foot`` whose centre is at ``pos_m`` (x, y, ...) stands on a patch
        that allows it: the simulator's foothold rule (a landing elsewhere is a
        violation). When blind, False: a blind controller cannot tell a foothold from a
        stone's edge, and its touchdown search (``control/blind_touchdown.py``) handles
        its landings."""
        if self.knowledge.blind:
            return False
        x, y = (float(v) for v in np.asarray(pos_m, dtype=float)[:2])
        return self._course.foot_allowed(x, y, foot)

    def reachable_foothold_bounds(
        self,
        p_com_touchdown_xy: ArrayLike,
        foot: str,
        nominal_xy: ArrayLike,
        *,
        reach_x_m: float,
        margin_m: float,
        margin_y_m: float | None = None,
        reach_back_m: float | None = None,
        obstacle_clearance_m: float = 0.0,
    ) -> tuple[np.ndarray, np.ndarray, int | None]:
        """Eq. 24 box of the next touchdown: :meth:`Course.reachable_foothold_bounds`.

        The box lies off the obstacles' footprints, widened by ``obstacle_clearance_m``:
        the preview sees where an obstacle stands even where its height is not known (the
        paper's Fig. 1(e) hardware run: "the obstacle's height is unknown to the robot").

        Raises:
            ConfigError: the controller is blind (it has no box to ask for).
        """
        if self.knowledge.blind:
            raise ConfigError("terrain_knowledge.blind", True, "False for an eq. 24 box")
        return self._course.reachable_foothold_bounds(
            p_com_touchdown_xy,
            foot,
            nominal_xy,
            reach_x_m=reach_x_m,
            margin_m=margin_m,
            margin_y_m=margin_y_m,
            reach_back_m=reach_back_m,
            obstacle_clearance_m=obstacle_clearance_m,
        )

    def swing_obstacles(self, x0_m: float, x1_m: float) -> list[Obstacle]:
        """Obstacles between a swing's lift-off ``x0_m`` and touchdown ``x1_m`` (either
        order), or none where ``obstacle_heights`` is off."""
        if not self.knowledge.obstacle_heights:
            return []
        return self.obstacle_footprints(x0_m, x1_m)

    def obstacle_footprints(self, x0_m: float, x1_m: float) -> list[Obstacle]:
        """The obstacles between ``x0_m`` and ``x1_m`` (either order) whatever
        ``obstacle_heights`` says: where they stand is part of the preview, their height
        only with ``obstacle_heights`` (read ``height_m`` only then); none when blind."""
        if self.knowledge.blind:
            return []
        return self._course.obstacles_between(min(x0_m, x1_m), max(x0_m, x1_m))

    def patches_crossed(self, x0_m: float, y0_m: float, x1_m: float, y1_m: float) -> list[Patch]:
        """The patches whose footprint the segment from ``(x0, y0)`` to ``(x1, y1)`` meets:
        the ground under a swing's straight path; none when blind."""
        if self.knowledge.blind:
            return []
        out = []
        for p in self._course.patches:
            lo, hi = max(p.x_min, min(x0_m, x1_m)), min(p.x_max, max(x0_m, x1_m))
            if lo > hi:
                continue
            if x1_m == x0_m:  # a sideways path: its whole y-range at x0
                ya, yb = sorted((y0_m, y1_m))
            else:  # the path's y over the patch's x-interval
                slope = (y1_m - y0_m) / (x1_m - x0_m)
                ya, yb = sorted((y0_m + slope * (lo - x0_m), y0_m + slope * (hi - x0_m)))
            if ya <= p.y_max and yb >= p.y_min:
                out.append(p)
        return out

    # ------------------------------------------------------------- beyond the paper
    def course_for_multi_step_preview(self) -> Course:
        """The whole course, for the multi-step footstep preview only.

        Raises:
            ConfigError: the run's knowledge is the one-step preview.
        """
        if not self.knowledge.multi_step:
            raise ConfigError(
                "terrain_knowledge.multi_step",
                False,
                "True (--preview) for a multi-step footstep preview",
            )
        return self._course
