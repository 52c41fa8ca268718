"""Discrete terrain courses: patches the feet may stand on, obstacles to clear, holes between.

A *course* is a set of axis-aligned rectangular **patches** (flat tops at height ``z_top_m``)
and optional **obstacles** (boxes standing on a patch that the swing foot must step over).
Everything outside the patches is a hole.  Each patch says which foot may land on it
(``"both"``, ``"left"`` or ``"right"``), which is how the paper's stepping-stone courses
force the left and right feet onto separate lanes.

Modules:

- :mod:`.patch`: :class:`Patch` and :class:`Obstacle`;
- :mod:`.course`: :class:`Course`, its validation and geometry queries;
- :mod:`.checks`: the course-level checks and their bounds (no overlapping patches, a
  start clear of obstacles, sizes, heights and counts);
- :mod:`.bounds`: eq. (24) foothold boxes;
- :mod:`.json_format`: the course file format (JSON), with errors naming the field, and
  bounded reading of course files (size, nesting depth, duplicate keys);
- :mod:`.fields`: validation of single fields and query arguments;
- :mod:`.builtin_courses`: the built-in and seeded courses and :func:`load_course`;
- :mod:`.mjcf`: the course as MuJoCo geoms.

Main entry points: :func:`load_course` (built-in name or JSON path), the query methods of
:class:`Course` (:meth:`Course.patch_at`, :meth:`Course.ground_height_at`,
:meth:`Course.foot_allowed`, :meth:`Course.reachable_foothold_bounds`,
:meth:`Course.obstacles_between`) and :func:`course_geoms_xml` for the MuJoCo scene.
"""

from gaitnet_mpc.terrain.builtin_courses import (
    BUILTIN_COURSES,
    SEEDED_COURSES,
    flat_course,
    gap_course,
    load_course,
    obstacle_course,
    stepping_stones_course,
    uneven_course,
)
from gaitnet_mpc.terrain.course import Course
from gaitnet_mpc.terrain.fields import FEET_VALUES
from gaitnet_mpc.terrain.mjcf import OBSTACLE_RGBA, PATCH_RGBA, course_geoms_xml
from gaitnet_mpc.terrain.patch import Obstacle, Patch

__all__ = [
    "BUILTIN_COURSES",
    "FEET_VALUES",
    "OBSTACLE_RGBA",
    "PATCH_RGBA",
    "SEEDED_COURSES",
    "Course",
    "Obstacle",
    "Patch",
    "course_geoms_xml",
    "flat_course",
    "gap_course",
    "load_course",
    "obstacle_course",
    "stepping_stones_course",
    "uneven_course",
]
