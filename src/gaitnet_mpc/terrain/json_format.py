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

Reading a file (:func:`read_course_json`) is bounded: at most
:data:`MAX_COURSE_FILE_BYTES` (8 MiB, checked with ``os.stat`` before reading and again
while reading), objects and arrays nested at most :data:`MAX_JSON_DEPTH` (16) deep
(checked before parsing), and each key at most once per object.  The course-level bounds
(counts, sizes, heights, overlap, a clear start) are :class:`Course`'s, in :mod:`.checks`.

:meth:`Course.from_dict`, :meth:`Course.to_dict` and :meth:`Course.from_json` are the
entry points; they delegate to the functions here.
"""

from __future__ import annotations

import json
import os
import re
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.terrain.checks import check_counts
from gaitnet_mpc.terrain.fields import (
    MISSING,
    check_keys,
    feet_field,
    finite_number,
    interval,
    layout_seed,
)
from gaitnet_mpc.terrain.patch import Obstacle, Patch, top_patch_indices

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
    raw_obstacles = d.get("obstacles", [])
    if not isinstance(raw_obstacles, list | tuple):
        raise CourseFormatError("obstacles", raw_obstacles, "a list of obstacles")
    check_counts(len(raw_patches), len(raw_obstacles))  # before parsing them one by one
    patches = tuple(_patch_from_dict(p, f"patches[{i}]") for i, p in enumerate(raw_patches))

    footprints: list[tuple[float, float, float, float, float]] = []
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
        footprints.append((x_min, x_max, y_min, y_max, height_m))
    centres = [(0.5 * (f[0] + f[1]), 0.5 * (f[2] + f[3])) for f in footprints]
    under = top_patch_indices(patches, np.array(centres, dtype=float).reshape(-1, 2))
    obstacles = []
    for i, (f, c, k) in enumerate(zip(footprints, centres, under.tolist(), strict=True)):
        if k < 0:
            raise CourseFormatError(
                f"obstacles[{i}]",
                c,
                "its centre (x, y) to lie on a patch (obstacles stand on the ground)",
            )
        obstacles.append(Obstacle(*f, z_base_m=patches[k].z_top_m))

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


#: Largest course file [bytes], checked with ``os.stat`` before reading (and the read
#: stops one byte past it).  A course at the bounds of :mod:`.checks` (20000 patches,
#: 2000 obstacles) is 1.5 MB as compact JSON, 3.3 MB indented by 2 and 8.2 MB indented by
#: 8 (``json.dumps(indent=...)``), and loads in under a second; a larger file (or an
#: endless special file) is refused before it costs memory or time.
MAX_COURSE_FILE_BYTES = 8 * 1024 * 1024
#: Deepest nesting of JSON objects and arrays.  The course format nests 4 deep (course
#: object, ``patches`` list, patch object, ``[min, max]`` list); 16 leaves room for
#: anything sensible and stays far below the interpreter's recursion limit (~1000), which
#: ``json.loads`` would otherwise hit as a ``RecursionError`` on ``[[[[...]]]]``.
MAX_JSON_DEPTH = 16
#: Files larger than this [bytes] report progress on stderr while they are read and
#: checked (about a second's work and up).
PROGRESS_FILE_BYTES = 1024 * 1024

#: A JSON string (with escapes) and a run of characters that are not brackets.
_JSON_STRING = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"', re.DOTALL)
_NOT_BRACKETS = re.compile(r"[^\[\]{}]+")


class CourseJSON(NamedTuple):
    """A course file read by :func:`read_course_json`: its parsed JSON (not yet validated
    as a course) and its size [bytes]."""

    data: Any
    size_bytes: int


def json_depth(text: str) -> int:
    """Deepest nesting of ``[`` / ``{`` in JSON ``text`` outside strings (0 for a scalar).

    Computed without parsing (strings removed by a regex, then a cumulative sum over the
    brackets), so it is safe on any text.  Unbalanced text gives its deepest open count.
    """
    brackets = _NOT_BRACKETS.sub("", _JSON_STRING.sub("", text))
    if not brackets:
        return 0
    b = np.frombuffer(brackets.encode("ascii"), dtype=np.uint8)
    step = np.where((b == ord("[")) | (b == ord("{")), np.int8(1), np.int8(-1))
    return max(0, int(np.cumsum(step, dtype=np.int32).max()))


class _RepeatedKeys(dict[str, Any]):
    """A JSON object in which a key appeared more than once; ``repeats`` maps each such
    key to all its values, in file order."""

    repeats: dict[str, list[Any]]


def _object_without_repeats(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """``object_pairs_hook`` of :func:`read_course_json`: marks objects with a repeated key."""
    out: dict[str, Any] = {}
    repeats: dict[str, list[Any]] = {}
    for key, value in pairs:
        if key in out:
            repeats.setdefault(key, [out[key]]).append(value)
        out[key] = value
    if not repeats:
        return out
    marked = _RepeatedKeys(out)
    marked.repeats = repeats
    return marked


def _first_repeat(node: Any, path: str) -> tuple[str, str, list[Any]] | None:
    """``(object path, key, values)`` of the first object (pre-order) with a repeated key."""
    if isinstance(node, _RepeatedKeys):
        key, values = next(iter(node.repeats.items()))
        return path, key, values
    items: list[tuple[str, Any]] = []
    if isinstance(node, dict):
        items = [(f"{path}.{k}" if path else k, v) for k, v in node.items()]
    elif isinstance(node, list):
        items = [(f"{path}[{i}]", v) for i, v in enumerate(node)]
    for sub_path, value in items:
        found = _first_repeat(value, sub_path)
        if found is not None:
            return found
    return None


def _read_bounded(p: Path, shown: str) -> tuple[bytes, int]:
    """The bytes of file ``p`` and its ``os.stat`` size, refusing more than the limit."""
    limit = MAX_COURSE_FILE_BYTES
    expected = f"a course file of at most {limit} bytes (8 MiB; 20000 patches take 1.5-3.3 MB)"
    try:
        size = os.stat(p).st_size
        if size > limit:
            raise CourseFormatError("course", f"{shown} ({size} bytes)", expected)
        with p.open("rb") as f:
            raw = f.read(limit + 1)
    except OSError as exc:
        raise CourseFormatError(
            "course", shown, f"a readable JSON course file ({exc.strerror or exc})"
        ) from exc
    if len(raw) > limit:  # grew since stat, or a special file
        raise CourseFormatError("course", f"{shown} (more than {limit} bytes)", expected)
    return raw, size


def read_course_json(path: str | Path) -> CourseJSON:
    """The parsed JSON of a course file (not yet validated as a course), and its size.

    Refused with :class:`CourseFormatError` (field ``course`` unless said): a file that
    cannot be read, larger than :data:`MAX_COURSE_FILE_BYTES` (checked with ``os.stat``
    before reading), not UTF-8, nested deeper than :data:`MAX_JSON_DEPTH` (checked
    before parsing), not valid JSON, or with a key given twice in one object (field: the
    key's JSON path, e.g. ``patches[3].x``).  A file over :data:`PROGRESS_FILE_BYTES`
    prints ``reading course <name> (<size> MB) ...`` on stderr first.
    """
    p = Path(path)
    raw, size = _read_bounded(p, str(path))
    if size > PROGRESS_FILE_BYTES:
        print(f"reading course {p.name} ({size / 1e6:.1f} MB) ...", file=sys.stderr, flush=True)
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark (some Windows editors) skipped
    except UnicodeDecodeError as exc:
        raise CourseFormatError(
            "course", str(path), f"a UTF-8 text JSON course file (byte {exc.start} is not)"
        ) from None
    depth = json_depth(text)
    if depth > MAX_JSON_DEPTH:
        raise CourseFormatError(
            "course",
            f"{path} (objects and arrays nested {depth} deep)",
            f"JSON nested at most {MAX_JSON_DEPTH} deep (the course format nests 4 deep)",
        )
    marked: list[_RepeatedKeys] = []

    def pairs_hook(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
        d = _object_without_repeats(pairs)
        if isinstance(d, _RepeatedKeys):
            marked.append(d)
        return d

    try:
        data = json.loads(text, object_pairs_hook=pairs_hook)
    except json.JSONDecodeError as exc:
        raise CourseFormatError("course", str(path), f"valid JSON ({exc})") from exc
    except ValueError as exc:  # e.g. an integer of over 4300 digits
        raise CourseFormatError("course", str(path), f"valid JSON numbers ({exc})") from None
    except RecursionError:  # not reached after the depth check; kept as a named error
        raise CourseFormatError(
            "course", str(path), f"JSON nested at most {MAX_JSON_DEPTH} deep"
        ) from None
    repeat = _first_repeat(data, "") if marked else None  # the walk only to name the path
    if repeat is not None:
        where, key, values = repeat
        raise CourseFormatError(
            f"{where}.{key}" if where else key,
            values,
            f"the key {key!r} once in {where or 'the course object'} (it is given "
            f"{len(values)} times)",
        )
    return CourseJSON(data, size)
