"""A terrain course: its patches and obstacles, validation, and geometry queries.

Queries: :meth:`Course.patch_at`, :meth:`Course.ground_height_at`,
:meth:`Course.foot_allowed`, :meth:`Course.obstacles_between` and the eq. (24) box of the
next foothold, :meth:`Course.reachable_foothold_bounds` (computed in :mod:`.bounds`).
(De)serialisation: :meth:`Course.from_dict`, :meth:`Course.to_dict` and
:meth:`Course.from_json` (the format is in :mod:`.json_format`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.terrain.bounds import reachable_foothold_bounds
from gaitnet_mpc.terrain.fields import EPS_M, check_foot, finite_number, layout_seed
from gaitnet_mpc.terrain.json_format import (
    course_fields_from_dict,
    course_to_dict,
    read_course_json,
)
from gaitnet_mpc.terrain.patch import Obstacle, Patch, top_patch_index


@dataclass(frozen=True)
class Course:
    """A terrain course: patches (footholds), obstacles, and the start point.

    Construction validates the whole course and raises :class:`CourseFormatError`:
    at least one patch; the start point ``start_xy`` (m) lies on a patch allowing both
    feet; every obstacle's centre lies on a patch and its ``z_base_m`` equals that
    patch's top; ``seed`` is None or a non-negative integer.  Patches may overlap; where
    they do the highest top wins.

    ``seed`` records the seed that drew a randomised built-in layout (``uneven``,
    ``stepping-stones`` or ``gap`` given a seed); it is None for fixed layouts and files
    without one, and plays no part in the geometry.
    """

    name: str
    patches: tuple[Patch, ...]
    obstacles: tuple[Obstacle, ...] = ()
    start_xy: tuple[float, float] = (0.0, 0.0)
    seed: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise CourseFormatError("name", self.name, "a non-empty string")
        if isinstance(self.patches, str | bytes) or not isinstance(self.patches, Sequence):
            raise CourseFormatError("patches", self.patches, "a non-empty list of patches")
        patches = tuple(self.patches)
        if not patches:
            raise CourseFormatError("patches", list(patches), "a non-empty list of patches")
        for i, p in enumerate(patches):
            if not isinstance(p, Patch):
                raise CourseFormatError(f"patches[{i}]", p, "a Patch")
        object.__setattr__(self, "patches", patches)

        if isinstance(self.obstacles, str | bytes) or not isinstance(self.obstacles, Sequence):
            raise CourseFormatError("obstacles", self.obstacles, "a list of obstacles")
        obstacles = tuple(self.obstacles)
        for i, ob in enumerate(obstacles):
            if not isinstance(ob, Obstacle):
                raise CourseFormatError(f"obstacles[{i}]", ob, "an Obstacle")
        object.__setattr__(self, "obstacles", obstacles)

        if not isinstance(self.start_xy, Sequence) or len(self.start_xy) != 2:
            raise CourseFormatError("start_xy", self.start_xy, "a point [x, y] in metres")
        start = (
            finite_number(self.start_xy[0], "start_xy[0]"),
            finite_number(self.start_xy[1], "start_xy[1]"),
        )
        object.__setattr__(self, "start_xy", start)
        object.__setattr__(self, "seed", layout_seed(self.seed, "seed"))

        if not any(p.feet == "both" and p.contains(*start) for p in patches):
            raise CourseFormatError(
                "patches",
                f"no patch allowing both feet under the start point {start}",
                f"a patch with feet 'both' whose x and y ranges contain the start point {start}",
            )
        for i, ob in enumerate(obstacles):
            c = (ob.x_center_m, ob.y_center_m)
            z_ground = self.ground_height_at(*c)
            if z_ground is None:
                raise CourseFormatError(
                    f"obstacles[{i}]", c, "its centre (x, y) to lie on a patch (obstacles stand)"
                )
            if abs(ob.z_base_m - z_ground) > EPS_M:
                raise CourseFormatError(
                    f"obstacles[{i}].z_base_m",
                    ob.z_base_m,
                    f"the top {z_ground} of the patch under its centre",
                )

    # ------------------------------------------------------------------ (de)serialisation

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], *, default_name: str = "unnamed") -> Course:
        """Build and validate a course from the JSON-like dict of :mod:`.json_format`.

        Errors name the offending field as a path, e.g. ``patches[2].x``.
        """
        return cls(**course_fields_from_dict(d, default_name=default_name))

    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready dict; ``Course.from_dict(c.to_dict()) == c``.

        ``start_xy`` is written only when it is not the default (0, 0), ``seed`` only when
        it is not None.
        """
        return course_to_dict(self.name, self.patches, self.obstacles, self.start_xy, self.seed)

    @classmethod
    def from_json(cls, path: str | Path) -> Course:
        """Read and validate a course file; ``name`` defaults to the file stem."""
        data = read_course_json(path)
        return cls.from_dict(data, default_name=Path(path).stem)

    # ------------------------------------------------------------------ point queries

    def patch_at(self, x: float, y: float) -> int | None:
        """Index of the patch whose closed xy-rectangle holds (x, y) [m], or None (a hole).

        Where patches overlap, the one with the highest top wins (ties: lowest index).
        """
        return top_patch_index(self.patches, x, y)

    def ground_height_at(self, x: float, y: float) -> float | None:
        """Top height ``z_top_m`` of the patch under (x, y) [m], None over a hole.

        Patches only; obstacles are ignored (their tops are :attr:`Obstacle.z_top_m`).
        """
        i = self.patch_at(x, y)
        return None if i is None else self.patches[i].z_top_m

    def foot_allowed(self, x: float, y: float, foot: str) -> bool:
        """True iff the ``foot`` ("left"/"right") may land at (x, y) [m].

        That is: the point is on a patch whose ``feet`` is ``"both"`` or equals ``foot``.
        Where patches overlap, only those forming the top surface (highest ``z_top_m``)
        count.  Obstacles are not considered (they are handled by swing-height planning).
        """
        foot = check_foot(foot)
        z = self.ground_height_at(x, y)
        if z is None:
            return False
        return any(
            p.contains(x, y) and abs(p.z_top_m - z) <= EPS_M and p.allows(foot)
            for p in self.patches
        )

    def obstacles_between(self, x0_m: float, x1_m: float) -> list[Obstacle]:
        """Obstacles whose x-range overlaps ``[min(x0, x1), max(x0, x1)]``, sorted by x_min."""
        lo, hi = min(x0_m, x1_m), max(x0_m, x1_m)
        hits = [ob for ob in self.obstacles if ob.x_max >= lo and ob.x_min <= hi]
        return sorted(hits, key=lambda ob: ob.x_min)

    # ------------------------------------------------------------------ foothold constraints

    def reachable_foothold_bounds(
        self,
        p_com_td_xy: ArrayLike,
        foot: str,
        p_nominal_xy: ArrayLike,
        *,
        reach_x_m: float = 0.12,
        reach_y_m: float = 0.25,
        margin_m: float = 0.03,
        margin_y_m: float | None = None,
    ) -> tuple[np.ndarray, np.ndarray, int | None]:
        """Eq. (24) box for the next foothold, chosen by kinematic reach (one-step
        preview), on this course's patches: :func:`.bounds.reachable_foothold_bounds`."""
        return reachable_foothold_bounds(
            self.patches,
            p_com_td_xy,
            foot,
            p_nominal_xy,
            reach_x_m=reach_x_m,
            reach_y_m=reach_y_m,
            margin_m=margin_m,
            margin_y_m=margin_y_m,
        )
