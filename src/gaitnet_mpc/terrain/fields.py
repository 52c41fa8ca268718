"""Validation of the scalar fields of a course and of the arguments of its queries.

Course fields (numbers, ``[min, max]`` intervals, ``feet``, seeds, object keys) raise
:class:`CourseFormatError` naming the field as a path, e.g. ``patches[2].x``; query
arguments (a foot name, an xy point) raise :class:`ConfigError`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from gaitnet_mpc.errors import ConfigError, CourseFormatError

#: Allowed values of a patch's ``feet`` field.
FEET_VALUES: tuple[str, ...] = ("both", "left", "right")
#: Allowed values of a query's ``foot`` argument.
FOOT_NAMES: tuple[str, ...] = ("left", "right")

#: Tolerance (m) for comparing heights and for point-in-rectangle tests.
EPS_M = 1e-9


class _Missing:
    """Marker for a required key that is absent (prints as ``<missing>``)."""

    def __repr__(self) -> str:
        return "<missing>"


#: The value reported for a required key that is absent.
MISSING = _Missing()


def finite_number(value: object, field_path: str) -> float:
    """Return ``value`` as a float, or raise if it is not a finite real number (bool refused)."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise CourseFormatError(field_path, value, "a finite number")
    try:
        out = float(value)
    except OverflowError:  # an int beyond the float range (e.g. 10**400)
        out = math.inf
    if not math.isfinite(out):
        raise CourseFormatError(field_path, value, "a finite number")
    return out


def layout_seed(value: object, field_path: str) -> int | None:
    """``value`` as a layout seed: None, or a non-negative integer (bool and float refused)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
        raise CourseFormatError(field_path, value, "a non-negative integer (or none)")
    return int(value)


def interval(value: object, field_path: str) -> tuple[float, float]:
    """Parse ``[min, max]`` with finite numbers and ``min < max``."""
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise CourseFormatError(field_path, value, "a list [min, max] of two numbers")
    lo = finite_number(value[0], f"{field_path}[0]")
    hi = finite_number(value[1], f"{field_path}[1]")
    if not lo < hi:
        raise CourseFormatError(field_path, value, "[min, max] with min < max")
    return lo, hi


def feet_field(value: object, field_path: str) -> str:
    """``value`` as a patch's ``feet`` field: one of :data:`FEET_VALUES`."""
    if not isinstance(value, str) or value not in FEET_VALUES:
        raise CourseFormatError(field_path, value, "one of 'both', 'left', 'right'")
    return value


def check_keys(d: Mapping[str, Any], allowed: Sequence[str], prefix: str) -> None:
    """Raise for the first key of ``d`` not in ``allowed`` (field path ``prefix + key``)."""
    for key in d:
        if key not in allowed:
            raise CourseFormatError(
                f"{prefix}{key}", d[key], f"no such key; allowed keys are {', '.join(allowed)}"
            )


def check_foot(foot: object) -> str:
    """``foot`` as a query's foot name, "left" or "right" (:class:`ConfigError` otherwise)."""
    if not isinstance(foot, str) or foot not in FOOT_NAMES:
        raise ConfigError("foot", foot, "'left' or 'right'")
    return foot


def point_xy(p_xy: ArrayLike, field_path: str) -> tuple[float, float]:
    """(x, y) [m] of a finite (x, y) or (x, y, z) point (:class:`ConfigError` otherwise)."""
    try:
        arr = np.asarray(p_xy, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        arr = np.full(1, np.nan)
    if arr.shape[0] not in (2, 3) or not np.all(np.isfinite(arr)):
        raise ConfigError(field_path, p_xy, "a finite (x, y) or (x, y, z) point in metres")
    return float(arr[0]), float(arr[1])
