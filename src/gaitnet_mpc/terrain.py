"""Discrete terrain courses: patches the feet may stand on, obstacles to clear, holes between.

A *course* is a set of axis-aligned rectangular **patches** (flat tops at height ``z_top_m``)
and optional **obstacles** (boxes standing on a patch that the swing foot must step over).
Everything outside the patches is a hole.  Each patch says which foot may land on it
(``"both"``, ``"left"`` or ``"right"``), which is how the paper's stepping-stone courses
force the left and right feet onto separate lanes.

Course file format (JSON)::

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

Main entry points: :func:`load_course` (built-in name or JSON path), the query methods of
:class:`Course` (:meth:`Course.patch_at`, :meth:`Course.ground_height_at`,
:meth:`Course.height_at`, :meth:`Course.foot_allowed`, :meth:`Course.foothold_bounds`,
:meth:`Course.obstacles_between`) and :func:`course_geoms_xml` for the MuJoCo scene.
"""

from __future__ import annotations

import inspect
import json
import math
import types
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from gaitnet_mpc.errors import ConfigError, CourseFormatError

__all__ = [
    "BUILTIN_COURSES",
    "FEET_VALUES",
    "OBSTACLE_RGBA",
    "PATCH_RGBA",
    "SEEDED_COURSES",
    "Course",
    "Obstacle",
    "Patch",
    "course_bounds",
    "course_geoms_xml",
    "flat_course",
    "gap_course",
    "load_course",
    "obstacle_course",
    "stepping_stones_course",
    "uneven_course",
]

#: Allowed values of a patch's ``feet`` field.
FEET_VALUES: tuple[str, ...] = ("both", "left", "right")
_FOOT_NAMES: tuple[str, ...] = ("left", "right")

_TOP_KEYS: tuple[str, ...] = ("name", "patches", "obstacles", "start_xy", "seed")
_PATCH_KEYS: tuple[str, ...] = ("x", "y", "z", "feet")
_OBSTACLE_KEYS: tuple[str, ...] = ("x", "y", "height")

#: Tolerance (m) for comparing heights and for point-in-rectangle tests.
_EPS_M = 1e-9

#: x extent (m) shared by every built-in course.
_COURSE_X_START_M = -1.0
_COURSE_X_END_M = 25.0
#: Half width (m) of the built-in platforms (y in [-1.5, 1.5]).
_PLATFORM_HALF_WIDTH_M = 1.5
#: End of the start platform (m) of the courses with a terrain section.
_START_PLATFORM_END_M = 0.8


class _Missing:
    """Marker for a required key that is absent (prints as ``<missing>``)."""

    def __repr__(self) -> str:
        return "<missing>"


_MISSING = _Missing()


# ----------------------------------------------------------------------------------------------
# Scalar validation helpers
# ----------------------------------------------------------------------------------------------


def _number(value: object, field_path: str) -> float:
    """Return ``value`` as a float, or raise if it is not a finite real number (bool refused)."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise CourseFormatError(field_path, value, "a finite number")
    out = float(value)
    if not math.isfinite(out):
        raise CourseFormatError(field_path, value, "a finite number")
    return out


def _seed(value: object, field_path: str) -> int | None:
    """``value`` as a layout seed: None, or a non-negative integer (bool and float refused)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
        raise CourseFormatError(field_path, value, "a non-negative integer (or none)")
    return int(value)


def _interval(value: object, field_path: str) -> tuple[float, float]:
    """Parse ``[min, max]`` with finite numbers and ``min < max``."""
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise CourseFormatError(field_path, value, "a list [min, max] of two numbers")
    lo = _number(value[0], f"{field_path}[0]")
    hi = _number(value[1], f"{field_path}[1]")
    if not lo < hi:
        raise CourseFormatError(field_path, value, "[min, max] with min < max")
    return lo, hi


def _feet(value: object, field_path: str) -> str:
    if not isinstance(value, str) or value not in FEET_VALUES:
        raise CourseFormatError(field_path, value, "one of 'both', 'left', 'right'")
    return value


def _check_keys(d: Mapping[str, Any], allowed: Sequence[str], prefix: str) -> None:
    for key in d:
        if key not in allowed:
            raise CourseFormatError(
                f"{prefix}{key}", d[key], f"no such key; allowed keys are {', '.join(allowed)}"
            )


def _check_foot(foot: object) -> str:
    if not isinstance(foot, str) or foot not in _FOOT_NAMES:
        raise ConfigError("foot", foot, "'left' or 'right'")
    return foot


def _point_xy(p_xy: ArrayLike, field_path: str) -> tuple[float, float]:
    try:
        arr = np.asarray(p_xy, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        arr = np.full(1, np.nan)
    if arr.shape[0] not in (2, 3) or not np.all(np.isfinite(arr)):
        raise ConfigError(field_path, p_xy, "a finite (x, y) or (x, y, z) point in metres")
    return float(arr[0]), float(arr[1])


def _rect_distance(
    x: float, y: float, x_min: float, x_max: float, y_min: float, y_max: float
) -> float:
    """Euclidean distance (m) from point (x, y) to a closed rectangle (0 inside)."""
    dx = max(x_min - x, 0.0, x - x_max)
    dy = max(y_min - y, 0.0, y - y_max)
    return math.hypot(dx, dy)


# ----------------------------------------------------------------------------------------------
# Data classes
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Patch:
    """A flat rectangular foothold region: ``[x_min, x_max] x [y_min, y_max]`` at ``z_top_m``.

    ``feet`` is ``"both"``, ``"left"`` (left foot only) or ``"right"`` (right foot only).
    Lengths in metres.
    """

    x_min: float
    x_max: float
    y_min: float
    y_max: float
    z_top_m: float
    feet: str = "both"

    def __post_init__(self) -> None:
        for name in ("x_min", "x_max", "y_min", "y_max", "z_top_m"):
            object.__setattr__(self, name, _number(getattr(self, name), f"Patch.{name}"))
        if not self.x_min < self.x_max:
            raise CourseFormatError("Patch.x_max", self.x_max, f"> x_min = {self.x_min}")
        if not self.y_min < self.y_max:
            raise CourseFormatError("Patch.y_max", self.y_max, f"> y_min = {self.y_min}")
        _feet(self.feet, "Patch.feet")

    @property
    def x_center_m(self) -> float:
        return 0.5 * (self.x_min + self.x_max)

    @property
    def y_center_m(self) -> float:
        return 0.5 * (self.y_min + self.y_max)

    def foothold_box(
        self, margin_x_m: float, margin_y_m: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Eq. (24) box ``(p_min (3,), p_max (3,))`` of a foot centre kept ``margin_x_m``
        (``margin_y_m``, default the same) inside the patch (its centre line where the
        patch is narrower than twice that); z is the patch top."""
        margin_y_m = margin_x_m if margin_y_m is None else margin_y_m
        x_lo, x_hi = _shrink(self.x_min, self.x_max, margin_x_m)
        y_lo, y_hi = _shrink(self.y_min, self.y_max, margin_y_m)
        return np.array([x_lo, y_lo, self.z_top_m]), np.array([x_hi, y_hi, self.z_top_m])

    def contains(self, x: float, y: float) -> bool:
        """True iff (x, y) lies in the closed rectangle (tolerance 1 nm)."""
        return (
            self.x_min - _EPS_M <= x <= self.x_max + _EPS_M
            and self.y_min - _EPS_M <= y <= self.y_max + _EPS_M
        )

    def allows(self, foot: str) -> bool:
        """True iff ``foot`` ("left" or "right") may land on this patch."""
        return self.feet == "both" or self.feet == foot

    def to_dict(self) -> dict[str, Any]:
        return {
            "x": [self.x_min, self.x_max],
            "y": [self.y_min, self.y_max],
            "z": self.z_top_m,
            "feet": self.feet,
        }


@dataclass(frozen=True)
class Obstacle:
    """A box of height ``height_m`` on ``[x_min, x_max] x [y_min, y_max]``, base at ``z_base_m``.

    ``z_base_m`` is the top of the patch under the obstacle's centre.  Obstacles are not
    footholds: the swing trajectory must clear ``z_top_m``.  Lengths in metres.
    """

    x_min: float
    x_max: float
    y_min: float
    y_max: float
    height_m: float
    z_base_m: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x_min", "x_max", "y_min", "y_max", "height_m", "z_base_m"):
            object.__setattr__(self, name, _number(getattr(self, name), f"Obstacle.{name}"))
        if not self.x_min < self.x_max:
            raise CourseFormatError("Obstacle.x_max", self.x_max, f"> x_min = {self.x_min}")
        if not self.y_min < self.y_max:
            raise CourseFormatError("Obstacle.y_max", self.y_max, f"> y_min = {self.y_min}")
        if not self.height_m > 0.0:
            raise CourseFormatError("Obstacle.height_m", self.height_m, "a height > 0 m")

    @property
    def z_top_m(self) -> float:
        return self.z_base_m + self.height_m

    @property
    def x_center_m(self) -> float:
        return 0.5 * (self.x_min + self.x_max)

    @property
    def y_center_m(self) -> float:
        return 0.5 * (self.y_min + self.y_max)

    def contains(self, x: float, y: float) -> bool:
        """True iff (x, y) lies in the obstacle's closed footprint."""
        return (
            self.x_min - _EPS_M <= x <= self.x_max + _EPS_M
            and self.y_min - _EPS_M <= y <= self.y_max + _EPS_M
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "x": [self.x_min, self.x_max],
            "y": [self.y_min, self.y_max],
            "height": self.height_m,
        }


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
            _number(self.start_xy[0], "start_xy[0]"),
            _number(self.start_xy[1], "start_xy[1]"),
        )
        object.__setattr__(self, "start_xy", start)
        object.__setattr__(self, "seed", _seed(self.seed, "seed"))

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
            if abs(ob.z_base_m - z_ground) > _EPS_M:
                raise CourseFormatError(
                    f"obstacles[{i}].z_base_m",
                    ob.z_base_m,
                    f"the top {z_ground} of the patch under its centre",
                )

    # ------------------------------------------------------------------ (de)serialisation

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], *, default_name: str = "unnamed") -> Course:
        """Build and validate a course from the JSON-like dict described in the module doc.

        Errors name the offending field as a path, e.g. ``patches[2].x``.
        """
        if not isinstance(d, Mapping):
            raise CourseFormatError("course", d, "a JSON object (dict) with a 'patches' list")
        _check_keys(d, _TOP_KEYS, "")
        name = d.get("name", default_name)
        if not isinstance(name, str) or not name:
            raise CourseFormatError("name", name, "a non-empty string")

        raw_patches = d.get("patches", _MISSING)
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
            _check_keys(ob, _OBSTACLE_KEYS, f"{path}.")
            x_min, x_max = _interval(ob.get("x", _MISSING), f"{path}.x")
            y_min, y_max = _interval(ob.get("y", _MISSING), f"{path}.y")
            height_m = _number(ob.get("height", _MISSING), f"{path}.height")
            if not height_m > 0.0:
                raise CourseFormatError(f"{path}.height", ob["height"], "a height > 0 m")
            c = (0.5 * (x_min + x_max), 0.5 * (y_min + y_max))
            k = _top_patch_index(patches, *c)
            if k is None:
                raise CourseFormatError(
                    path, c, "its centre (x, y) to lie on a patch (obstacles stand on the ground)"
                )
            z_base_m = patches[k].z_top_m
            obstacles.append(Obstacle(x_min, x_max, y_min, y_max, height_m, z_base_m))

        raw_start = d.get("start_xy", [0.0, 0.0])
        if not isinstance(raw_start, list | tuple) or len(raw_start) != 2:
            raise CourseFormatError("start_xy", raw_start, "a point [x, y] in metres")
        start = (_number(raw_start[0], "start_xy[0]"), _number(raw_start[1], "start_xy[1]"))
        seed = _seed(d.get("seed"), "seed")
        return cls(
            name=name, patches=patches, obstacles=tuple(obstacles), start_xy=start, seed=seed
        )

    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready dict; ``Course.from_dict(c.to_dict()) == c``.

        ``start_xy`` is written only when it is not the default (0, 0), ``seed`` only when
        it is not None.
        """
        out: dict[str, Any] = {
            "name": self.name,
            "patches": [p.to_dict() for p in self.patches],
            "obstacles": [ob.to_dict() for ob in self.obstacles],
        }
        if self.start_xy != (0.0, 0.0):
            out["start_xy"] = list(self.start_xy)
        if self.seed is not None:
            out["seed"] = self.seed
        return out

    @classmethod
    def from_json(cls, path: str | Path) -> Course:
        """Read and validate a course file; ``name`` defaults to the file stem."""
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
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise CourseFormatError("course", str(path), f"valid JSON ({exc})") from exc
        return cls.from_dict(data, default_name=p.stem)

    def to_json(self, path: str | Path, *, indent: int = 2) -> None:
        """Write the course to ``path`` in the file format read by :meth:`from_json`."""
        Path(path).write_text(json.dumps(self.to_dict(), indent=indent) + "\n", encoding="utf-8")

    # ------------------------------------------------------------------ point queries

    def patch_at(self, x: float, y: float) -> int | None:
        """Index of the patch whose closed xy-rectangle holds (x, y) [m], or None (a hole).

        Where patches overlap, the one with the highest top wins (ties: lowest index).
        """
        return _top_patch_index(self.patches, x, y)

    def ground_height_at(self, x: float, y: float) -> float | None:
        """Top height ``z_top_m`` of the patch under (x, y) [m], None over a hole.

        Patches only; obstacles are ignored (see :meth:`height_at`).
        """
        i = self.patch_at(x, y)
        return None if i is None else self.patches[i].z_top_m

    def height_at(self, x: float, y: float) -> float | None:
        """Highest solid surface at (x, y) [m]: patches *and* obstacle tops; None over a hole.

        Use this for collision / clearance checks; use :meth:`ground_height_at` for the
        height of a foothold.
        """
        z = self.ground_height_at(x, y)
        for ob in self.obstacles:
            if ob.contains(x, y) and (z is None or ob.z_top_m > z):
                z = ob.z_top_m
        return z

    def foot_allowed(self, x: float, y: float, foot: str) -> bool:
        """True iff the ``foot`` ("left"/"right") may land at (x, y) [m].

        That is: the point is on a patch whose ``feet`` is ``"both"`` or equals ``foot``.
        Where patches overlap, only those forming the top surface (highest ``z_top_m``)
        count.  Obstacles are not considered (they are handled by swing-height planning).
        """
        foot = _check_foot(foot)
        z = self.ground_height_at(x, y)
        if z is None:
            return False
        return any(
            p.contains(x, y) and abs(p.z_top_m - z) <= _EPS_M and p.allows(foot)
            for p in self.patches
        )

    def obstacles_between(self, x0_m: float, x1_m: float) -> list[Obstacle]:
        """Obstacles whose x-range overlaps ``[min(x0, x1), max(x0, x1)]``, sorted by x_min."""
        lo, hi = min(x0_m, x1_m), max(x0_m, x1_m)
        hits = [ob for ob in self.obstacles if ob.x_max >= lo and ob.x_min <= hi]
        return sorted(hits, key=lambda ob: ob.x_min)

    # ------------------------------------------------------------------ foothold constraints

    def foothold_patch(
        self,
        p_com_xy: ArrayLike,
        foot: str,
        *,
        reach_m: float = 0.35,
        back_m: float = 0.15,
        lead_m: float = 0.10,
        foot_offset_y_m: float = 0.06,
    ) -> int | None:
        """Index of the patch that constrains the next foothold of ``foot``, or None.

        Rule (deterministic, one-step preview):

        1. *Trigger*: patch ``k`` is a candidate iff it allows ``foot`` and the CoM x
           ``x_c`` lies in its trigger window ``[x_min - reach_m, x_max + back_m]`` (the
           paper's per-patch CoM bounding box that activates a patch's constraints).
        2. *Choice*: among candidates, take the one nearest (2-D Euclidean distance to its
           rectangle, 0 inside) to the nominal foothold target
           ``(x_c + lead_m, y_c + s * foot_offset_y_m)`` with ``s = +1`` for the left foot and
           ``-1`` for the right.  Ties go to the higher top, then the patch further ahead
           (larger x centre), then the lower index.

        Returns None when no patch triggers.
        """
        foot = _check_foot(foot)
        x_c, y_c = _point_xy(p_com_xy, "p_com_xy")
        side = 1.0 if foot == "left" else -1.0
        x_t, y_t = x_c + lead_m, y_c + side * foot_offset_y_m
        best: tuple[float, float, float, int] | None = None
        for i, p in enumerate(self.patches):
            if not p.allows(foot):
                continue
            if not (p.x_min - reach_m <= x_c <= p.x_max + back_m):
                continue
            d = _rect_distance(x_t, y_t, p.x_min, p.x_max, p.y_min, p.y_max)
            key = (round(d, 12), -p.z_top_m, -p.x_center_m, i)
            if best is None or key < best:
                best = key
        return None if best is None else best[3]

    def foothold_bounds(
        self,
        p_com_xy: ArrayLike,
        foot: str,
        *,
        reach_m: float = 0.35,
        back_m: float = 0.15,
        lead_m: float = 0.10,
        foot_offset_y_m: float = 0.06,
        margin_m: float = 0.02,
        z_tol_m: float = 0.0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Box bounds ``p_min <= p_foot <= p_max`` (eq. 24) on the next foothold of ``foot``.

        The patch is chosen by :meth:`foothold_patch` (same keyword parameters) from the CoM
        position ``p_com_xy`` [m] ((x, y) or (x, y, z)).  Its x and y ranges are shrunk
        inward by ``margin_m`` so the foot centre stays inside; a range narrower than
        ``2 * margin_m`` collapses to its centre.  z bounds are the patch top
        ``± z_tol_m``.

        Obstacles: if an obstacle on the chosen patch spans the whole y range of the bounds
        and cuts their x range, the x range is reduced (again with ``margin_m``) to the
        side of the obstacle nearest the target ``x_c + lead_m``, so the foot never lands on
        the obstacle.  Obstacles only partly across the bounds are ignored here.

        If no patch triggers, wide bounds are returned: ``x_c ± 1``, ``y_c ± 1`` and z equal
        to the top of the allowed patch nearest to the CoM.

        Returns ``(p_min, p_max)``, each a float array of shape (3,).
        """
        foot = _check_foot(foot)
        x_c, y_c = _point_xy(p_com_xy, "p_com_xy")
        if not margin_m >= 0.0:
            raise ConfigError("margin_m", margin_m, "a margin >= 0 m")
        if not z_tol_m >= 0.0:
            raise ConfigError("z_tol_m", z_tol_m, "a tolerance >= 0 m")
        k = self.foothold_patch(
            (x_c, y_c),
            foot,
            reach_m=reach_m,
            back_m=back_m,
            lead_m=lead_m,
            foot_offset_y_m=foot_offset_y_m,
        )
        if k is None:
            allowed = [p for p in self.patches if p.allows(foot)] or list(self.patches)
            nearest = min(
                allowed, key=lambda p: _rect_distance(x_c, y_c, p.x_min, p.x_max, p.y_min, p.y_max)
            )
            z = nearest.z_top_m
            return (
                np.array([x_c - 1.0, y_c - 1.0, z - z_tol_m]),
                np.array([x_c + 1.0, y_c + 1.0, z + z_tol_m]),
            )

        p = self.patches[k]
        x_lo, x_hi = _shrink(p.x_min, p.x_max, margin_m)
        y_lo, y_hi = _shrink(p.y_min, p.y_max, margin_m)
        x_target = x_c + lead_m
        for ob in sorted(self.obstacles, key=lambda o: o.x_min):
            spans_y = ob.y_min <= y_lo + _EPS_M and ob.y_max >= y_hi - _EPS_M
            cuts_x = ob.x_max + margin_m > x_lo and ob.x_min - margin_m < x_hi
            if not (spans_y and cuts_x):
                continue
            pieces = [
                (a, b)
                for a, b in ((x_lo, ob.x_min - margin_m), (ob.x_max + margin_m, x_hi))
                if b >= a
            ]
            if pieces:
                x_lo, x_hi = min(
                    pieces, key=lambda ab: max(ab[0] - x_target, 0.0, x_target - ab[1])
                )
        z = p.z_top_m
        return np.array([x_lo, y_lo, z - z_tol_m]), np.array([x_hi, y_hi, z + z_tol_m])

    def reachable_foothold_bounds(
        self,
        p_com_td_xy: ArrayLike,
        foot: str,
        p_nominal_xy: ArrayLike,
        *,
        reach_x_m: float = 0.12,
        reach_y_m: float = 0.25,
        margin_m: float = 0.03,
    ) -> tuple[np.ndarray, np.ndarray, int | None]:
        """Eq. (24) box for the next foothold, chosen by kinematic reach (one-step preview).

        The foot can land only within ``reach`` of the CoM at touchdown, ``p_com_td_xy``
        (the hip is above it). Among the patches that allow ``foot``, each shrunk by
        ``margin_m``, those whose box meets that window are candidates; the one whose part
        inside the window is closest to the nominal foothold ``p_nominal_xy`` wins, and the
        bounds are its whole shrunk box (the window only chooses the patch; the MPC keeps
        the freedom to step beyond it). If no patch meets the window, the patch closest to
        the window is used.

        Returns:
            ``(p_min (3,), p_max (3,), patch index or None)``; z bounds are the patch top.
        """
        foot = _check_foot(foot)
        xc, yc = _point_xy(p_com_td_xy, "p_com_td_xy")
        xn, yn = _point_xy(p_nominal_xy, "p_nominal_xy")
        win = (xc - reach_x_m, xc + reach_x_m, yc - reach_y_m, yc + reach_y_m)
        best: tuple[float, int] | None = None
        fallback: tuple[float, int] | None = None
        for i, patch in enumerate(self.patches):
            if not patch.allows(foot):
                continue
            lo, hi = patch.foothold_box(margin_m)
            box = (max(lo[0], win[0]), min(hi[0], win[1]), max(lo[1], win[2]), min(hi[1], win[3]))
            if box[0] <= box[1] and box[2] <= box[3]:
                dx = max(box[0] - xn, 0.0, xn - box[1])
                dy = max(box[2] - yn, 0.0, yn - box[3])
                score = dx * dx + dy * dy
                if best is None or score < best[0]:
                    best = (score, i)
            else:
                gap = _rect_distance(xc, yc, lo[0], hi[0], lo[1], hi[1])
                if fallback is None or gap < fallback[0]:
                    fallback = (gap, i)
        chosen = best or fallback
        if chosen is None:
            return np.array([win[0], win[2], 0.0]), np.array([win[1], win[3], 0.0]), None
        i = chosen[1]
        lo, hi = self.patches[i].foothold_box(margin_m)
        return lo, hi, i


def _top_patch_index(patches: Sequence[Patch], x: float, y: float) -> int | None:
    """Index of the highest patch holding (x, y) (ties: lowest index), None if none does."""
    best: int | None = None
    for i, p in enumerate(patches):
        if p.contains(x, y) and (best is None or p.z_top_m > patches[best].z_top_m):
            best = i
    return best


def _shrink(lo: float, hi: float, margin_m: float) -> tuple[float, float]:
    """``[lo + margin, hi - margin]``, or the centre twice if that is empty."""
    if hi - lo >= 2.0 * margin_m:
        return lo + margin_m, hi - margin_m
    mid = 0.5 * (lo + hi)
    return mid, mid


def _patch_from_dict(d: object, path: str) -> Patch:
    if not isinstance(d, Mapping):
        raise CourseFormatError(path, d, "an object with keys x, y, z and optional feet")
    _check_keys(d, _PATCH_KEYS, f"{path}.")
    x_min, x_max = _interval(d.get("x", _MISSING), f"{path}.x")
    y_min, y_max = _interval(d.get("y", _MISSING), f"{path}.y")
    z_top_m = _number(d.get("z", _MISSING), f"{path}.z")
    feet = _feet(d.get("feet", "both"), f"{path}.feet")
    return Patch(x_min, x_max, y_min, y_max, z_top_m, feet)


# ----------------------------------------------------------------------------------------------
# Built-in courses
# ----------------------------------------------------------------------------------------------


def _platform(x_min: float, x_max: float, z_top_m: float = 0.0) -> Patch:
    return Patch(x_min, x_max, -_PLATFORM_HALF_WIDTH_M, _PLATFORM_HALF_WIDTH_M, z_top_m, "both")


def _param(value: object, field_path: str, lo: float, hi: float, expected: str) -> float:
    v = _number(value, field_path)
    if not lo < v < hi:
        raise CourseFormatError(field_path, value, expected)
    return v


def flat_course() -> Course:
    """``flat``: one patch, x in [-1, 25] m, y in [-1.5, 1.5] m, at z = 0."""
    return Course("flat", (_platform(_COURSE_X_START_M, _COURSE_X_END_M),))


#: Default gap of ``gap`` without a seed: width and start (m).
_GAP_WIDTH_M = 0.20
_GAP_X_M = 1.5
#: Randomised ``gap`` layouts (integer millimetres): number of gaps, first gap start,
#: gap width, and ground between two gaps.
_RG_COUNT = (1, 3)
_RG_X0_MM = (1000, 2500)
_RG_WIDTH_MM = (50, 200)
_RG_GROUND_MM = (600, 1200)


def _draw_mm(rng: np.random.Generator, bounds_mm: tuple[int, int]) -> int:
    """An integer uniform in the closed range ``bounds_mm`` (millimetres, or a count)."""
    return int(rng.integers(bounds_mm[0], bounds_mm[1] + 1))


def gap_course(
    width_m: float | None = None, x_m: float | None = None, seed: int | None = None
) -> Course:
    """``gap``: ground from x = -1 m, holes across the walkway, ground again to x = 25 m.

    Without ``seed``: one hole of ``width_m`` (default 0.20 m) starting at ``x_m`` (default
    1.5 m).  With ``seed`` (a non-negative integer), ``numpy.random.default_rng(seed)``
    draws 1 to 3 holes (equally likely): the first starts uniformly in [1.0, 2.5] m, each
    is uniformly 0.05-0.20 m wide (the paper's gaps go up to 20 cm), and consecutive holes
    are separated by 0.6-1.2 m of ground (uniform), so the last one ends before x = 5.5 m;
    values are whole millimetres.  ``width_m`` or ``x_m`` together with a seed is refused
    (the seed draws them).  The course records ``seed``.
    """
    seed = _seed(seed, "gap.seed")
    if seed is not None:
        for field, value in (("gap.width_m", width_m), ("gap.x_m", x_m)):
            if value is not None:
                raise CourseFormatError(
                    field, value, "no value together with a seed (the seed draws the gaps)"
                )
        rng = np.random.default_rng(seed)
        holes_mm: list[tuple[int, int]] = []
        for _ in range(_draw_mm(rng, _RG_COUNT)):
            if holes_mm:
                x0 = holes_mm[-1][1] + _draw_mm(rng, _RG_GROUND_MM)
            else:
                x0 = _draw_mm(rng, _RG_X0_MM)
            holes_mm.append((x0, x0 + _draw_mm(rng, _RG_WIDTH_MM)))
        holes = [(a / 1000.0, b / 1000.0) for a, b in holes_mm]
    else:
        width_m = _GAP_WIDTH_M if width_m is None else width_m
        x_m = _GAP_X_M if x_m is None else x_m
        width_m = _param(width_m, "gap.width_m", 0.0, 5.0, "a gap width in (0, 5) m")
        x_m = _param(x_m, "gap.x_m", 0.0, 15.0, "a gap start in (0, 15) m")
        holes = [(x_m, x_m + width_m)]
    edges = [_COURSE_X_START_M, *(x for hole in holes for x in hole), _COURSE_X_END_M]
    patches = tuple(_platform(edges[i], edges[i + 1]) for i in range(0, len(edges), 2))
    return Course("gap", patches, seed=seed)


#: Stepping-stone layout: (x_min, x_max, y_min, y_max, feet, z in units of dz_m).
#: Both-feet stones are 0.30 m long and 0.5 m wide; left-only stones (0.20-0.22 m long) sit
#: on y >= 0 and right-only stones on y <= 0, with a few cm of lateral offset between them.
#: Along x, consecutive stones are either staggered (a left and a right stone overlap) or
#: separated by 0.08-0.10 m; within one foot's lane the gaps are 0.08-0.20 m.  A feasible
#: footstep sequence needs steps of 0.13-0.25 m, several longer than the nominal 0.17 m.
_STONES: tuple[tuple[float, float, float, float, str, int], ...] = (
    (0.88, 1.18, -0.25, 0.25, "both", 0),
    (1.26, 1.46, 0.01, 0.24, "left", 1),
    (1.34, 1.56, -0.23, -0.02, "right", 1),
    (1.54, 1.76, 0.03, 0.26, "left", 0),
    (1.64, 1.86, -0.25, -0.01, "right", -1),
    (1.96, 2.26, -0.22, 0.28, "both", 0),
    (2.34, 2.54, 0.00, 0.23, "left", 1),
    (2.42, 2.64, -0.24, -0.03, "right", 0),
    (2.62, 2.84, 0.02, 0.25, "left", -1),
    (2.72, 2.92, -0.22, 0.00, "right", -1),
    (3.00, 3.30, -0.27, 0.23, "both", 0),
)
_STONES_END_M = 3.40

#: Randomised stepping-stone layouts, in integer millimetres (see
#: :func:`stepping_stones_course`).  Closed ranges ``(min, max)``.
_RS_GAP_MM = (60, 120)  # x gap before a stone that does not overlap the previous one
_RS_LANE_HOLE_MM = (60, 220)  # x hole between consecutive patches of one foot's lane
_RS_STAGGER_MM = 60  # a lane stone starts at least this far ahead of the previous stone
_RS_OVERLAP_MM = 40  # a lane stone overlapping the previous one shares at least this
_RS_BOTH_LENGTH_MM = (250, 350)
_RS_BOTH_WIDTH_MM = 500
_RS_BOTH_Y_MIN_MM = (-280, -220)
_RS_LANE_LENGTH_MM = (180, 240)
_RS_LANE_WIDTH_MM = (200, 250)
_RS_LANE_INNER_MM = (0, 30)  # |y| of a lane stone's inner edge (the one nearest y = 0)
_RS_P_BOTH = 0.35  # chance that a section is a both stone (where one may follow)
_RS_P_OVERLAP = 0.6  # chance that a lane stone overlaps the previous one (where both fit)
_RS_MIN_END_MM = 3050  # sections are added until the last stone ends past this

#: A stone in millimetres: (x_min, x_max, y_min, y_max, feet, z in units of dz_m).
_StoneMM = tuple[int, int, int, int, str, int]


def _random_stones(rng: np.random.Generator) -> tuple[list[_StoneMM], int]:
    """Draw a stepping-stone layout; return its stones and the final platform's x start (mm).

    Rules (see :func:`stepping_stones_course`): each new stone's x start is drawn uniformly
    in the window that keeps (a) lengths >= 0.18 m, (b) each foot's lane holes in
    [0.06, 0.22] m and (c) a lane stone at most 0.12 m past the stone before it, and the
    stones of a lane apart.  A both stone or the final platform comes only where (b)
    allows it.  Look-ahead keeps every window non-empty: a pair's leading stone leaves
    room for the trailing one, and the closing pair (drawn when the course is long enough
    but a lane lags too far behind for a platform) has its leading stone end far enough
    ahead, and its trailing one short enough, for the final platform to follow.
    """
    gap_min, gap_max = _RS_GAP_MM
    hole_min, hole_max = _RS_LANE_HOLE_MM
    len_min, len_max = _RS_LANE_LENGTH_MM
    x_start = round(_START_PLATFORM_END_M * 1000)
    stones: list[_StoneMM] = []
    lane_end = {"left": x_start, "right": x_start}  # x_max of each lane's last patch
    other = {"left": "right", "right": "left"}

    def last_end() -> int:  # x_max never decreases along the stones
        return stones[-1][1] if stones else x_start

    def both_window() -> tuple[int, int]:
        """x start window of a both stone or the final platform (empty: a lane lags)."""
        e = last_end()
        return e + gap_min, min(e + gap_max, min(lane_end.values()) + hole_max)

    def place_lane_stone(
        foot: str, x0_max: int | None = None, end_min: int | None = None, end_max: int | None = None
    ) -> None:
        """Append a ``foot`` stone; optional bounds on its x start and its x end (mm)."""
        lo, hi = lane_end[foot] + hole_min, lane_end[foot] + hole_max
        if x0_max is not None:
            hi = min(hi, x0_max)
        if end_min is not None:
            lo = max(lo, end_min - len_max)
        if end_max is not None:
            hi = min(hi, end_max - len_min)
        prev = stones[-1] if stones else None
        if prev is None or prev[4] in ("both", foot):
            options = [(last_end() + gap_min, last_end() + gap_max)]
        else:  # staggered after the other foot's stone: overlapping it, or separated
            options = [
                (prev[0] + _RS_STAGGER_MM, prev[1] - _RS_OVERLAP_MM),
                (prev[1] + gap_min, prev[1] + gap_max),
            ]
        windows = [(max(a, lo), min(b, hi)) for a, b in options]
        windows = [w for w in windows if w[0] <= w[1]]
        if not windows:  # pragma: no cover - excluded by the look-ahead
            raise RuntimeError(f"stepping-stones generator: no room for a {foot} stone")
        window = windows[0]
        if len(windows) == 2 and rng.random() >= _RS_P_OVERLAP:
            window = windows[1]
        x0 = _draw_mm(rng, window)
        length_lo = len_min if end_min is None else max(len_min, end_min - x0)
        length_hi = len_max if end_max is None else min(len_max, end_max - x0)
        x1 = x0 + _draw_mm(rng, (length_lo, length_hi))
        inner = _draw_mm(rng, _RS_LANE_INNER_MM)
        outer = inner + _draw_mm(rng, _RS_LANE_WIDTH_MM)
        y = (inner, outer) if foot == "left" else (-outer, -inner)
        stones.append((x0, x1, y[0], y[1], foot, _draw_mm(rng, (-1, 1))))
        lane_end[foot] = x1

    def place_pair(closing: bool) -> None:
        prev_feet = stones[-1][4] if stones else "both"
        lead = ("left", "right")[_draw_mm(rng, (0, 1))] if prev_feet == "both" else other[prev_feet]
        trail = other[lead]
        # The trailing stone starts >= STAGGER after the lead, and within its own lane.
        x0_max = lane_end[trail] + hole_max - _RS_STAGGER_MM
        if not closing:
            place_lane_stone(lead, x0_max)
            place_lane_stone(trail)
            return
        # Closing: the trail starts >= hole_min past its lane and overlaps the lead, so the
        # lead must end >= hole_min + overlap past the trail's lane; the trail then ends
        # early enough for the platform (gap_min after it) to be within hole_max of the lead.
        place_lane_stone(lead, x0_max, end_min=lane_end[trail] + hole_min + _RS_OVERLAP_MM)
        place_lane_stone(trail, end_max=lane_end[lead] + hole_max - gap_min)

    lo, hi = both_window()
    while last_end() < _RS_MIN_END_MM:
        if lo <= hi and rng.random() < _RS_P_BOTH:
            x0 = _draw_mm(rng, (lo, hi))
            x1 = x0 + _draw_mm(rng, _RS_BOTH_LENGTH_MM)
            y0 = _draw_mm(rng, _RS_BOTH_Y_MIN_MM)
            stones.append((x0, x1, y0, y0 + _RS_BOTH_WIDTH_MM, "both", _draw_mm(rng, (-1, 1))))
            lane_end.update(left=x1, right=x1)
        else:
            place_pair(closing=False)
        lo, hi = both_window()
    if lo > hi:
        place_pair(closing=True)
        lo, hi = both_window()
    if lo > hi:  # pragma: no cover - excluded by the closing pair's bounds
        raise RuntimeError("stepping-stones generator: the layout does not close")
    return stones, _draw_mm(rng, (lo, hi))


def stepping_stones_course(dz_m: float = 0.02, seed: int | None = None) -> Course:
    """``stepping-stones``: a 3-D stepping-stone course (cf. the paper's Fig. 7).

    Without ``seed``, the built-in deterministic layout: start platform x in [-1, 0.8] m;
    stones from x = 0.88 to 3.30 m mixing 0.30 m long, 0.5 m wide "both" stones with narrow
    "left"-only (y >= 0) and "right"-only (y <= 0) stones laterally offset by a few cm;
    gaps of 0.08-0.10 m between stones along x (up to 0.20 m within one foot's lane); stone
    tops at 0 or ``±dz_m`` (m); final platform from 3.40 m to 25 m.  ``dz_m = 0`` gives
    level stones.

    With ``seed`` (a non-negative integer), ``numpy.random.default_rng(seed)`` draws a
    layout of the same kind, in whole millimetres: start platform to 0.8 m, stones from
    about 0.86 m, final platform from about 3.1-3.9 m (mean 3.34 m) to 25 m.  Sections
    follow one another until the last stone ends past 3.05 m, each a "both" stone
    (probability 0.35 where one fits; 0.25-0.35 m long, 0.5 m wide, y centre within
    ±3 cm of 0) or a staggered pair of lane stones (leading foot drawn after a both stone,
    then alternating, so a run of pairs zig-zags L, R, L, R).  Lane stones are 0.18-0.24 m
    long and 0.20-0.25 m wide with the inner edge 0-3 cm off y = 0 ("left" on y >= 0,
    "right" on y <= 0); each starts >= 0.06 m ahead of the stone before it and overlaps
    it by >= 0.04 m (probability 0.6 where both fit) or follows it after a 0.06-0.12 m
    gap; a both stone or the final platform follows its predecessor after 0.06-0.12 m.
    Every stone top is ``dz_m`` times -1, 0 or +1.  Guarantees: (a) every stone is
    >= 0.18 m long in x; (b) along each foot's lane, consecutive usable patches
    (platforms, both stones, that foot's stones) leave x holes of 0.06-0.22 m; (c) a left
    and a right stone that follow each other in x leave at most 0.12 m of x gap; stones of
    one lane never overlap.  The course records ``seed``.
    """
    dz_m = _param(dz_m, "stepping-stones.dz_m", -1e-12, 0.1, "a height step in [0, 0.1) m")
    seed = _seed(seed, "stepping-stones.seed")
    patches = [_platform(_COURSE_X_START_M, _START_PLATFORM_END_M)]
    if seed is None:
        for x_min, x_max, y_min, y_max, feet, level in _STONES:
            patches.append(Patch(x_min, x_max, y_min, y_max, level * dz_m, feet))
        patches.append(_platform(_STONES_END_M, _COURSE_X_END_M))
        return Course("stepping-stones", tuple(patches))
    stones_mm, x_final_mm = _random_stones(np.random.default_rng(seed))
    for x_min, x_max, y_min, y_max, feet, level in stones_mm:
        xy_m = (x_min / 1000.0, x_max / 1000.0, y_min / 1000.0, y_max / 1000.0)
        patches.append(Patch(*xy_m, level * dz_m, feet))
    patches.append(_platform(x_final_mm / 1000.0, _COURSE_X_END_M))
    return Course("stepping-stones", tuple(patches), seed=seed)


def obstacle_course(
    height_m: float = 0.03, x_m: float = 1.5, gap_x_m: float = 2.2, gap_width_m: float = 0.15
) -> Course:
    """``obstacle``: a 0.10 m (x) by ``height_m`` box across the walkway centred at ``x_m``,
    then a hole of ``gap_width_m`` starting at ``gap_x_m``, then ground to x = 25 m.
    """
    height_m = _param(height_m, "obstacle.height_m", 0.0, 0.5, "a height in (0, 0.5) m")
    x_m = _param(x_m, "obstacle.x_m", 0.1, 15.0, "an obstacle position in (0.1, 15) m")
    gap_x_m = _param(gap_x_m, "obstacle.gap_x_m", x_m + 0.05, 15.0, f"a gap start > {x_m + 0.05}")
    gap_width_m = _param(gap_width_m, "obstacle.gap_width_m", 0.0, 5.0, "a width in (0, 5) m")
    patches = (
        _platform(_COURSE_X_START_M, gap_x_m),
        _platform(gap_x_m + gap_width_m, _COURSE_X_END_M),
    )
    box = Obstacle(
        x_m - 0.05, x_m + 0.05, -_PLATFORM_HALF_WIDTH_M, _PLATFORM_HALF_WIDTH_M, height_m, 0.0
    )
    return Course("obstacle", patches, (box,))


def uneven_course(
    seed: int = 0,
    amplitude_m: float = 0.02,
    tile_length_m: float = 0.25,
    tile_width_m: float = 0.5,
    n_tiles_x: int = 21,
    n_tiles_y: int = 3,
) -> Course:
    """``uneven``: contiguous tiles with tops uniform in ``[-amplitude_m, amplitude_m]``.

    Start platform to x = 0.8 m; then ``n_tiles_x`` x ``n_tiles_y`` tiles of
    ``tile_length_m`` (x) by ``tile_width_m`` (y), centred on y = 0, with no holes
    (21 x 0.25 m: to x = 6.05 m); then a flat final platform to x = 25 m.  Heights come
    from ``numpy.random.default_rng(seed)`` (rounded to 0.1 mm), so a seed fixes the course.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise CourseFormatError("uneven.seed", seed, "a non-negative integer")
    amplitude_m = _param(amplitude_m, "uneven.amplitude_m", -1e-12, 0.2, "an amplitude in [0, 0.2)")
    tile_length_m = _param(tile_length_m, "uneven.tile_length_m", 0.0, 5.0, "a length in (0, 5)")
    tile_width_m = _param(tile_width_m, "uneven.tile_width_m", 0.0, 3.0, "a width in (0, 3) m")
    for name, n in (("n_tiles_x", n_tiles_x), ("n_tiles_y", n_tiles_y)):
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or not 1 <= n <= 200:
            raise CourseFormatError(f"uneven.{name}", n, "an integer in [1, 200]")
    x_end = _START_PLATFORM_END_M + n_tiles_x * tile_length_m
    if x_end > 20.0:
        raise CourseFormatError("uneven.n_tiles_x", n_tiles_x, "tiles ending before x = 20 m")
    rng = np.random.default_rng(int(seed))
    z = rng.uniform(-amplitude_m, amplitude_m, size=(n_tiles_x, n_tiles_y))
    y0 = -0.5 * n_tiles_y * tile_width_m
    xs = [round(_START_PLATFORM_END_M + i * tile_length_m, 9) for i in range(n_tiles_x + 1)]
    ys = [round(y0 + j * tile_width_m, 9) for j in range(n_tiles_y + 1)]
    patches = [_platform(_COURSE_X_START_M, _START_PLATFORM_END_M)]
    for i in range(n_tiles_x):
        for j in range(n_tiles_y):
            z_ij = float(np.clip(round(float(z[i, j]), 4), -amplitude_m, amplitude_m))
            patches.append(Patch(xs[i], xs[i + 1], ys[j], ys[j + 1], z_ij, "both"))
    patches.append(_platform(xs[-1], _COURSE_X_END_M))
    return Course("uneven", tuple(patches), seed=int(seed))


#: Built-in course factories by name (read-only).  Each accepts keyword parameters
#: (see the factory's docstring) and returns a validated :class:`Course`.
BUILTIN_COURSES: Mapping[str, Callable[..., Course]] = types.MappingProxyType(
    {
        "flat": flat_course,
        "gap": gap_course,
        "stepping-stones": stepping_stones_course,
        "obstacle": obstacle_course,
        "uneven": uneven_course,
    }
)


#: Names of the built-in courses whose factory takes a ``seed`` (a randomised layout).
SEEDED_COURSES: frozenset[str] = frozenset(
    name
    for name, factory in BUILTIN_COURSES.items()
    if "seed" in inspect.signature(factory).parameters
)


def load_course(name_or_path: str | Path, **params: Any) -> Course:
    """A built-in course by name (``params`` go to its factory) or a course JSON file.

    A string naming a built-in course wins; otherwise a path ending in ``.json`` (or an
    existing file) is read with :meth:`Course.from_json`.  Raises
    :class:`CourseFormatError` for unknown names, bad parameters or malformed files.
    """
    valid = ", ".join(BUILTIN_COURSES)
    if isinstance(name_or_path, str) and name_or_path in BUILTIN_COURSES:
        factory = BUILTIN_COURSES[name_or_path]
        sig = inspect.signature(factory)
        try:
            sig.bind(**params)
        except TypeError:
            allowed = ", ".join(sig.parameters) or "none"
            raise CourseFormatError(
                f"{name_or_path} parameters", params, f"keyword parameters among: {allowed}"
            ) from None
        return factory(**params)
    if isinstance(name_or_path, str | Path):
        path = Path(name_or_path)
        if path.suffix.lower() == ".json" or path.is_file():
            if params:
                raise CourseFormatError(
                    "course parameters", params, "no parameters with a course file"
                )
            return Course.from_json(path)
    raise CourseFormatError(
        "course", name_or_path, f"one of the built-in courses ({valid}) or a path to a .json file"
    )


# ----------------------------------------------------------------------------------------------
# MuJoCo geometry
# ----------------------------------------------------------------------------------------------

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
    thickness_m = _number(thickness_m, "thickness_m")
    if not thickness_m > 0.0:
        raise ConfigError("thickness_m", thickness_m, "a thickness > 0 m")
    fr = " ".join(_f(_number(v, "friction")) for v in friction)
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


def course_bounds(course: Course) -> tuple[float, float, float, float]:
    """Overall xy extent ``(x_min, x_max, y_min, y_max)`` [m] of patches and obstacles."""
    items: list[Patch | Obstacle] = [*course.patches, *course.obstacles]
    return (
        min(it.x_min for it in items),
        max(it.x_max for it in items),
        min(it.y_min for it in items),
        max(it.y_max for it in items),
    )
