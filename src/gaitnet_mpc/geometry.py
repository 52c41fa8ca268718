"""Small geometry shared by every layer: gravity, cross-product matrix, planar rotations,
angle wrapping.

Conventions: right-handed world frame, z up; yaw ``psi`` is the rotation about z, positive
counter-clockwise seen from above; angles in rad, lengths in m.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

GRAVITY_MPS2 = 9.81  # magnitude of the gravity acceleration [m/s^2], along -z


def skew(v: ArrayLike) -> np.ndarray:
    """(3, 3) cross-product matrix: ``skew(a) @ b == np.cross(a, b)``."""
    v = np.asarray(v, dtype=float)
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rot2(yaw_rad: float) -> np.ndarray:
    """(2, 2) rotation of the horizontal plane by ``yaw_rad``."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[c, -s], [s, c]])


def heading_axes(yaw_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal unit vectors ``(e_x, e_y)`` of the heading ``yaw_rad``: forward and left."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([c, s]), np.array([-s, c])


def rotate2(yaw_rad: float, v_xy: Sequence[float] | np.ndarray) -> np.ndarray:
    """(2,) ``R(yaw) v``: a horizontal vector given in the heading frame, in the world."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    x, y = v_xy
    return np.array([c * x - s * y, s * x + c * y])


def to_heading2(yaw_rad: float, v_xy: Sequence[float] | np.ndarray) -> np.ndarray:
    """(2,) ``R(yaw)^T v``: a horizontal world vector in the heading frame of ``yaw_rad``."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    x, y = v_xy
    return np.array([c * x + s * y, -s * x + c * y])


def wrap_angle(angle_rad: ArrayLike) -> np.ndarray:
    """Angle(s) wrapped to ``(-pi, pi]`` (``atan2(sin a, cos a)``, elementwise)."""
    a = np.asarray(angle_rad, dtype=float)
    return np.arctan2(np.sin(a), np.cos(a))


def unwrap_angles(angles_rad: list[float]) -> np.ndarray:
    """``np.unwrap`` of a short sequence of angles [rad], without its dozen array calls
    where no two neighbours are half a turn apart or more (then nothing moves)."""
    if all(abs(b - a) < math.pi for a, b in itertools.pairwise(angles_rad)):
        return np.array(angles_rad, dtype=float)
    return np.unwrap(np.array(angles_rad, dtype=float))
