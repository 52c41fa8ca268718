"""The two kinds of terrain element: foothold patches and obstacles.

A :class:`Patch` is an axis-aligned rectangle with a flat top that one or both feet may
stand on; an :class:`Obstacle` is a box standing on a patch that the swing foot must step
over.  Lengths in metres, world frame, x forward.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.terrain.fields import EPS_M, feet_field, finite_number


def _shrink(lo: float, hi: float, margin_m: float) -> tuple[float, float]:
    """``[lo + margin, hi - margin]``, or the centre twice if that is empty."""
    if hi - lo >= 2.0 * margin_m:
        return lo + margin_m, hi - margin_m
    mid = 0.5 * (lo + hi)
    return mid, mid


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
            object.__setattr__(self, name, finite_number(getattr(self, name), f"Patch.{name}"))
        if not self.x_min < self.x_max:
            raise CourseFormatError("Patch.x_max", self.x_max, f"> x_min = {self.x_min}")
        if not self.y_min < self.y_max:
            raise CourseFormatError("Patch.y_max", self.y_max, f"> y_min = {self.y_min}")
        feet_field(self.feet, "Patch.feet")

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
            self.x_min - EPS_M <= x <= self.x_max + EPS_M
            and self.y_min - EPS_M <= y <= self.y_max + EPS_M
        )

    def allows(self, foot: str) -> bool:
        """True iff ``foot`` ("left" or "right") may land on this patch."""
        return self.feet == "both" or self.feet == foot

    def to_dict(self) -> dict[str, Any]:
        """The patch's entry of the course file format (see :mod:`.json_format`)."""
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
            value = finite_number(getattr(self, name), f"Obstacle.{name}")
            object.__setattr__(self, name, value)
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

    def to_dict(self) -> dict[str, Any]:
        """The obstacle's entry of the course file format (``z_base_m`` is not written)."""
        return {
            "x": [self.x_min, self.x_max],
            "y": [self.y_min, self.y_max],
            "height": self.height_m,
        }


def top_patch_index(patches: Sequence[Patch], x: float, y: float) -> int | None:
    """Index of the highest patch holding (x, y) (ties: lowest index), None if none does."""
    best: int | None = None
    for i, p in enumerate(patches):
        if p.contains(x, y) and (best is None or p.z_top_m > patches[best].z_top_m):
            best = i
    return best


def footprints(items: Sequence[Patch] | Sequence[Obstacle]) -> np.ndarray:
    """``(n, 4)`` array of the items' xy-rectangles, rows ``[x_min, x_max, y_min, y_max]`` [m]."""
    rows = [(r.x_min, r.x_max, r.y_min, r.y_max) for r in items]
    return np.array(rows, dtype=float).reshape(-1, 4)


#: Point-patch pairs tested per NumPy block in :func:`top_patch_indices`.
_POINT_BLOCK = 1 << 20


def top_patch_indices(patches: Sequence[Patch], xy_m: np.ndarray) -> np.ndarray:
    """:func:`top_patch_index` of many points at once: ``xy_m`` (m, 2) [m] -> (m,) indices,
    -1 over a hole.  Same rule (closed rectangles within ``EPS_M``, highest top, ties to
    the lowest index), vectorised over the patches in blocks of points."""
    pts = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    r = footprints(patches)
    z = np.array([p.z_top_m for p in patches], dtype=float)
    out = np.full(pts.shape[0], -1, dtype=int)
    if r.size == 0:
        return out
    step = max(1, _POINT_BLOCK // r.shape[0])
    for s in range(0, pts.shape[0], step):
        x, y = pts[s : s + step, :1], pts[s : s + step, 1:]
        inside = (
            (r[:, 0] - EPS_M <= x)
            & (x <= r[:, 1] + EPS_M)
            & (r[:, 2] - EPS_M <= y)
            & (y <= r[:, 3] + EPS_M)
        )
        best = np.argmax(np.where(inside, z, -np.inf), axis=1)
        out[s : s + step] = np.where(inside.any(axis=1), best, -1)
    return out
