"""The course as MuJoCo scene geometry: one MJCF box ``<geom>`` per patch and obstacle."""

from __future__ import annotations

import types
from collections.abc import Mapping

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.terrain.course import Course
from gaitnet_mpc.terrain.fields import finite_number

#: RGBA colours of the scene geoms.  Convention: green = both feet, blue = left foot only,
#: red = right foot only, grey = obstacle.
PATCH_RGBA: Mapping[str, str] = types.MappingProxyType(
    {"both": "0.45 0.70 0.40 1", "left": "0.30 0.45 0.85 1", "right": "0.85 0.35 0.30 1"}
)
OBSTACLE_RGBA = "0.55 0.55 0.55 1"


def _f(v: float) -> str:
    return f"{v:.9g}"


def course_geoms_xml(
    course: Course,
    thickness_m: float = 0.5,
    friction: tuple[float, float, float] = (1.0, 0.005, 0.0001),
) -> str:
    """MJCF ``<geom>`` elements (one per line) for the course, to put inside ``<worldbody>``.

    Patch ``i`` is a box named ``patch_{i}`` with its top at ``z_top_m`` and extending
    ``thickness_m`` below; obstacle ``i`` is a grey box named ``obstacle_{i}`` from
    ``z_base_m`` to ``z_top_m``.  Colours: green = both feet, blue = left only, red = right
    only.  Holes between patches get no geometry.  ``friction`` is MuJoCo's
    (sliding, torsional, rolling) triple; the default is MuJoCo's own default.
    contype/conaffinity are left at their defaults (1/1).
    """
    thickness_m = finite_number(thickness_m, "thickness_m")
    if not thickness_m > 0.0:
        raise ConfigError("thickness_m", thickness_m, "a thickness > 0 m")
    fr = " ".join(_f(finite_number(v, "friction")) for v in friction)
    half_t = 0.5 * thickness_m
    lines = []
    for i, p in enumerate(course.patches):
        pos = (p.x_center_m, p.y_center_m, p.z_top_m - half_t)
        size = (0.5 * (p.x_max - p.x_min), 0.5 * (p.y_max - p.y_min), half_t)
        lines.append(
            f'<geom name="patch_{i}" type="box" pos="{" ".join(map(_f, pos))}" '
            f'size="{" ".join(map(_f, size))}" rgba="{PATCH_RGBA[p.feet]}" friction="{fr}"/>'
        )
    for i, ob in enumerate(course.obstacles):
        pos = (ob.x_center_m, ob.y_center_m, ob.z_base_m + 0.5 * ob.height_m)
        size = (0.5 * (ob.x_max - ob.x_min), 0.5 * (ob.y_max - ob.y_min), 0.5 * ob.height_m)
        lines.append(
            f'<geom name="obstacle_{i}" type="box" pos="{" ".join(map(_f, pos))}" '
            f'size="{" ".join(map(_f, size))}" rgba="{OBSTACLE_RGBA}" friction="{fr}"/>'
        )
    return "\n".join(lines)
