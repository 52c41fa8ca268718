"""A terrain course: its patches and obstacles, validation, and geometry queries.

Queries: :meth:`Course.patch_at`, :meth:`Course.ground_height_at`,
:meth:`Course.foot_allowed`, :meth:`Course.obstacles_between` and the eq. (24) box of the
next foothold, :meth:`Course.reachable_foothold_bounds` (computed in :mod:`.bounds`, on the
patches with the obstacles cut out, :mod:`.landing`).
(De)serialisation: :meth:`Course.from_dict`, :meth:`Course.to_dict` and
:meth:`Course.from_json` (the format is in :mod:`.json_format`).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.terrain.bounds import reachable_foothold_bounds
from gaitnet_mpc.terrain.checks import (
    check_counts,
    check_no_overlap,
    check_obstacle_extent,
    check_patch_extent,
    check_start_clear,
)
from gaitnet_mpc.terrain.fields import EPS_M, check_foot, finite_number, layout_seed
from gaitnet_mpc.terrain.json_format import (
    MAX_JSON_DEPTH,
    PROGRESS_FILE_BYTES,
    course_fields_from_dict,
    course_to_dict,
    read_course_json,
)
from gaitnet_mpc.terrain.landing import landing_areas
from gaitnet_mpc.terrain.patch import Obstacle, Patch, top_patch_index, top_patch_indices


@dataclass(frozen=True)
class Course:
    """A terrain course: patches (footholds), obstacles, and the start point.

    Construction validates the whole course and raises :class:`CourseFormatError`
    naming the field (checks in :mod:`.checks`, bounds with their reasons there):

    - 1 to :data:`.checks.MAX_PATCHES` (20000) patches, at most
      :data:`.checks.MAX_OBSTACLES` (2000) obstacles;
    - every patch and obstacle side between :data:`.checks.MIN_SIDE_M` (0.01 m) and
      :data:`.checks.MAX_SIDE_M` (500 m), every corner within
      :data:`.checks.MAX_ABS_XY_M` (±1000 m) in x and y, every patch top within
      :data:`.checks.MAX_ABS_Z_M` (±5 m), every obstacle at most
      :data:`.checks.MAX_OBSTACLE_HEIGHT_M` (2 m) tall;
    - the start point ``start_xy`` (m) lies on a patch allowing both feet;
    - no two patches overlap: a point of the course has one surface.  Patches may touch
      along edges (within ``EPS_M`` = 1 nm); on a shared edge the higher top wins;
    - every obstacle's centre lies on a patch and its ``z_base_m`` equals that patch's
      top, and no obstacle footprint comes within :data:`.checks.START_CLEARANCE_M`
      (0.3 m) of the start point, where the robot stands;
    - ``seed`` is None or a non-negative integer.

    ``seed`` records the seed that drew a randomised built-in layout (``uneven``,
    ``stepping-stones`` or ``gap`` given a seed); it is None for fixed layouts and files
    without one, and plays no part in the geometry.
    """

    name: str
    patches: tuple[Patch, ...]
    obstacles: tuple[Obstacle, ...] = ()
    start_xy: tuple[float, float] = (0.0, 0.0)
    seed: int | None = None
    _landing_cache: dict[float, tuple[tuple[Patch, ...], tuple[int, ...]]] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

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

        check_counts(len(patches), len(obstacles))
        for i, p in enumerate(patches):
            check_patch_extent(p, f"patches[{i}]")
        for i, ob in enumerate(obstacles):
            check_obstacle_extent(ob, f"obstacles[{i}]")
        if not any(p.feet == "both" and p.contains(*start) for p in patches):
            raise CourseFormatError(
                "patches",
                f"no patch allowing both feet under the start point {start}",
                f"a patch with feet 'both' whose x and y ranges contain the start point {start}",
            )
        check_no_overlap(patches)
        centres = np.array([(ob.x_center_m, ob.y_center_m) for ob in obstacles]).reshape(-1, 2)
        for i, k in enumerate(top_patch_indices(patches, centres).tolist()):
            ob = obstacles[i]
            if k < 0:
                raise CourseFormatError(
                    f"obstacles[{i}]",
                    (ob.x_center_m, ob.y_center_m),
                    "its centre (x, y) to lie on a patch (obstacles stand)",
                )
            z_ground = patches[k].z_top_m
            if abs(ob.z_base_m - z_ground) > EPS_M:
                raise CourseFormatError(
                    f"obstacles[{i}].z_base_m",
                    ob.z_base_m,
                    f"the top {z_ground} of the patch under its centre",
                )
        check_start_clear(obstacles, start)

    # ------------------------------------------------------------------ (de)serialisation

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], *, default_name: str = "unnamed") -> Course:
        """Build and validate a course from the JSON-like dict of :mod:`.json_format`.

        Errors name the offending field as a path, e.g. ``patches[2].x``.  A value nested
        too deeply to print in the message (deeper than the interpreter's recursion limit)
        is reported as such, on field ``course``.
        """
        try:
            return cls(**course_fields_from_dict(d, default_name=default_name))
        except RecursionError:
            raise CourseFormatError(
                "course",
                "a value nested too deeply to print",
                f"the course format, nested at most {MAX_JSON_DEPTH} deep",
            ) from None

    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready dict; ``Course.from_dict(c.to_dict()) == c``.

        ``start_xy`` is written only when it is not the default (0, 0), ``seed`` only when
        it is not None.
        """
        return course_to_dict(self.name, self.patches, self.obstacles, self.start_xy, self.seed)

    @classmethod
    def from_json(cls, path: str | Path) -> Course:
        """Read and validate a course file; ``name`` defaults to the file stem.

        Reading is bounded (:func:`.json_format.read_course_json`: size, nesting depth,
        duplicate keys); a file over :data:`.json_format.PROGRESS_FILE_BYTES` (1 MiB)
        reports on stderr when it is read and when it has been checked.
        """
        t0_s = time.perf_counter()
        read = read_course_json(path)
        course = cls.from_dict(read.data, default_name=Path(path).stem)
        if read.size_bytes > PROGRESS_FILE_BYTES:
            print(
                f"... {len(course.patches)} patches, {len(course.obstacles)} obstacles checked "
                f"({time.perf_counter() - t0_s:.1f} s)",
                file=sys.stderr,
                flush=True,
            )
        return course

    # ------------------------------------------------------------------ point queries

    def patch_at(self, x: float, y: float) -> int | None:
        """Index of the patch whose closed xy-rectangle holds (x, y) [m], or None (a hole).

        Patches do not overlap; on an edge shared by two patches (within ``EPS_M``) the one
        with the higher top wins (ties: lowest index).
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
        On an edge shared by two patches, only those forming the top surface (highest
        ``z_top_m``) count.  Obstacles are not considered (they are handled by swing-height
        planning).
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
        reach_back_m: float | None = None,
        obstacle_clearance_m: float | None = 0.0,
    ) -> tuple[np.ndarray, np.ndarray, int | None]:
        """Eq. (24) box for the next foothold, chosen by kinematic reach (one-step
        preview): :func:`.bounds.reachable_foothold_bounds` on the parts of the patches
        that no obstacle covers (:meth:`landing_areas`, footprints widened by
        ``obstacle_clearance_m``; None: the obstacles are not known, the patches are
        taken whole). A part cut by an obstacle is a candidate only where it holds the
        margins (``2 margin`` long and wide), so that the foot centre can keep them from
        the obstacle's side.

        Returns:
            ``(p_min (3,), p_max (3,), index of the patch the box lies on, or None)``.
        """
        margin_y = margin_m if margin_y_m is None else margin_y_m
        areas, parent = self.foothold_areas(obstacle_clearance_m, margin_m, margin_y)
        lo, hi, k = reachable_foothold_bounds(
            areas,
            p_com_td_xy,
            foot,
            p_nominal_xy,
            reach_x_m=reach_x_m,
            reach_y_m=reach_y_m,
            margin_m=margin_m,
            margin_y_m=margin_y_m,
            reach_back_m=reach_back_m,
        )
        return lo, hi, (None if k is None else parent[k])

    def foothold_areas(
        self, obstacle_clearance_m: float | None, margin_x_m: float, margin_y_m: float
    ) -> tuple[tuple[Patch, ...], tuple[int, ...]]:
        """``(areas, parent)``: the :meth:`landing_areas` (None: the patches whole) that can
        hold a foot centre ``margin_x_m`` / ``margin_y_m`` from their edges: a whole patch
        always, a part cut by an obstacle only where it is at least twice the margins long
        and wide; and the patch index of each."""
        if obstacle_clearance_m is None:
            return self.patches, tuple(range(len(self.patches)))
        areas, parent = self.landing_areas(obstacle_clearance_m)
        keep = [
            k
            for k, a in enumerate(areas)
            if a is self.patches[parent[k]]
            or (a.x_max - a.x_min >= 2.0 * margin_x_m and a.y_max - a.y_min >= 2.0 * margin_y_m)
        ]
        return tuple(areas[k] for k in keep), tuple(parent[k] for k in keep)

    def landing_areas(
        self, obstacle_clearance_m: float = 0.0
    ) -> tuple[tuple[Patch, ...], tuple[int, ...]]:
        """``(areas, parent)``: the patches with the obstacles' footprints (widened by
        ``obstacle_clearance_m`` [m]) cut out, and the patch index of each area
        (:func:`.landing.landing_areas`; computed once per clearance)."""
        key = float(obstacle_clearance_m)
        if key not in self._landing_cache:
            self._landing_cache[key] = landing_areas(self.patches, self.obstacles, key)
        return self._landing_cache[key]
