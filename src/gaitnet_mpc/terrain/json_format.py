"""The course file format (JSON): parsing with named errors, writing, reading a file.

Course file format::

    {
      "name": "my-course",
      "patches": [
        {"x": [x_min, x_max], "y": [y_min, y_max], "z": z_top_m, "feet": "both"}
      ],
      "obstacles": [
        {"x": [x_min, x_max], "y": [y_min, y_max], "height": height_m}
      ],
      "start_xy": [0.0, 0.0],
      "seed": 3
    }

``name`` (default ``"unnamed"``, or the file stem for :meth:`Course.from_json`),
``obstacles`` (default ``[]``), ``feet`` (default ``"both"``), ``start_xy``
(default ``[0, 0]``) and ``seed`` (default none: the seed that drew a randomised built-in
layout, a record only) are optional.  All lengths are metres in the world frame, x forward.
An obstacle stands on the patch under its centre: its base height ``z_base_m`` is that
patch's top and is not written in the file.  The start point must lie on a patch that
allows both feet.

:meth:`Course.from_dict`, :meth:`Course.to_dict` and :meth:`Course.from_json` are the
entry points; they delegate to the functions here.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.terrain.fields import (
    MISSING,
    check_keys,
    feet_field,
    finite_number,
    interval,
    layout_seed,
)
from gaitnet_mpc.terrain.patch import Obstacle, Patch, top_patch_index

_TOP_KEYS: tuple[str, ...] = ("name", "patches", "obstacles", "start_xy", "seed")
_PATCH_KEYS: tuple[str, ...] = ("x", "y", "z", "feet")
_OBSTACLE_KEYS: tuple[str, ...] = ("x", "y", "height")


def course_fields_from_dict(d: Mapping[str, Any], *, default_name: str) -> dict[str, Any]:
    """The :class:`Course` constructor's keyword arguments parsed from a course dict.

    Errors name the offending field as a path, e.g. ``patches[2].x``; the course-level
    checks (start point, obstacle bases) are the constructor's.
    """
    if not isinstance(d, Mapping):
        raise CourseFormatError("course", d, "a JSON object (dict) with a 'patches' list")
    check_keys(d, _TOP_KEYS, "")
    name = d.get("name", default_name)
    if not isinstance(name, str) or not name:
        raise CourseFormatError("name", name, "a non-empty string")

    raw_patches = d.get("patches", MISSING)
    if not isinstance(raw_patches, list | tuple) or len(raw_patches) == 0:
        raise CourseFormatError("patches", raw_patches, "a non-empty list of patches")
    patches = tuple(_patch_from_dict(p, f"patches[{i}]") for i, p in enumerate(raw_patches))

    raw_obstacles = d.get("obstacles", [])
    if not isinstance(raw_obstacles, list | tuple):
        raise CourseFormatError("obstacles", raw_obstacles, "a list of obstacles")
    obstacles = []
    for i, ob in enumerate(raw_obstacles):
        path = f"obstacles[{i}]"
        if not isinstance(ob, Mapping):
            raise CourseFormatError(path, ob, "an object with keys x, y, height")
        check_keys(ob, _OBSTACLE_KEYS, f"{path}.")
        x_min, x_max = interval(ob.get("x", MISSING), f"{path}.x")
        y_min, y_max = interval(ob.get("y", MISSING), f"{path}.y")
        height_m = finite_number(ob.get("height", MISSING), f"{path}.height")
        if not height_m > 0.0:
            raise CourseFormatError(f"{path}.height", ob["height"], "a height > 0 m")
        c = (0.5 * (x_min + x_max), 0.5 * (y_min + y_max))
        k = top_patch_index(patches, *c)
        if k is None:
            raise CourseFormatError(
                path, c, "its centre (x, y) to lie on a patch (obstacles stand on the ground)"
            )
        z_base_m = patches[k].z_top_m
        obstacles.append(Obstacle(x_min, x_max, y_min, y_max, height_m, z_base_m))

    raw_start = d.get("start_xy", [0.0, 0.0])
    if not isinstance(raw_start, list | tuple) or len(raw_start) != 2:
        raise CourseFormatError("start_xy", raw_start, "a point [x, y] in metres")
    start = (
        finite_number(raw_start[0], "start_xy[0]"),
        finite_number(raw_start[1], "start_xy[1]"),
    )
    seed = layout_seed(d.get("seed"), "seed")
    return {
        "name": name,
        "patches": patches,
        "obstacles": tuple(obstacles),
        "start_xy": start,
        "seed": seed,
    }


def _patch_from_dict(d: object, path: str) -> Patch:
    if not isinstance(d, Mapping):
        raise CourseFormatError(path, d, "an object with keys x, y, z and optional feet")
    check_keys(d, _PATCH_KEYS, f"{path}.")
    x_min, x_max = interval(d.get("x", MISSING), f"{path}.x")
    y_min, y_max = interval(d.get("y", MISSING), f"{path}.y")
    z_top_m = finite_number(d.get("z", MISSING), f"{path}.z")
    feet = feet_field(d.get("feet", "both"), f"{path}.feet")
    return Patch(x_min, x_max, y_min, y_max, z_top_m, feet)


def course_to_dict(
    name: str,
    patches: Sequence[Patch],
    obstacles: Sequence[Obstacle],
    start_xy: tuple[float, float],
    seed: int | None,
) -> dict[str, Any]:
    """The JSON-ready dict of a course's fields (:meth:`Course.to_dict`).

    ``start_xy`` is written only when it is not the default (0, 0), ``seed`` only when
    it is not None.
    """
    out: dict[str, Any] = {
        "name": name,
        "patches": [p.to_dict() for p in patches],
        "obstacles": [ob.to_dict() for ob in obstacles],
    }
    if start_xy != (0.0, 0.0):
        out["start_xy"] = list(start_xy)
    if seed is not None:
        out["seed"] = seed
    return out


def read_course_json(path: str | Path) -> Any:
    """The parsed JSON of a course file (not yet validated as a course)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise CourseFormatError(
            "course", str(path), f"a readable JSON course file ({exc.strerror or exc})"
        ) from exc
    except UnicodeDecodeError as exc:
        raise CourseFormatError(
            "course", str(path), f"a UTF-8 text JSON course file (byte {exc.start} is not)"
        ) from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise CourseFormatError("course", str(path), f"valid JSON ({exc})") from exc
