"""Course-level checks: size bounds, one surface per point, an obstacle-free start.

:class:`Course` runs these in its constructor, so they hold for built-in, Python-built and
file courses alike; each raises :class:`CourseFormatError` naming the field as a path
(``patches[7]``, ``obstacles[0].height``).  The bounds are named constants below, each
with its unit and its reason; every built-in course (seeded ones for any seed) is well
inside them (``tests/test_course_validation.py`` checks 200 seeds of each).

The overlap test is a sort-and-sweep (:func:`first_overlap`): O(n log n) plus the pairs of
patches whose ranges overlap along the sweep axis, vectorised with NumPy.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.terrain.bounds import rect_distance
from gaitnet_mpc.terrain.fields import EPS_M
from gaitnet_mpc.terrain.patch import Obstacle, Patch, footprints

#: Largest |x| and |y| of any patch or obstacle corner [m].  The built-in courses span
#: x in [-1, 25] m and |y| <= 1.5 m, and a run walks about 1 m/s for tens of seconds;
#: 1 km is far beyond any episode and keeps the float spacing of coordinates (~1e-13 m)
#: far below the edge tolerance ``EPS_M`` (1e-9 m), so "touching" means the same everywhere.
MAX_ABS_XY_M = 1000.0
#: Largest |z| of a patch top [m].  Built-in tops are within ±0.1 m (stepping-stones
#: ``dz_m`` < 0.1 m, uneven amplitude < 0.2 m); a walking humanoid about 1 m tall climbs a
#: few cm per step, so a top beyond 5 m is a unit error (mm written as m) or garbage.
MAX_ABS_Z_M = 5.0
#: Tallest obstacle [m].  Obstacles are boxes the swing foot steps over (built-in 0.03 m,
#: the ``obstacle`` factory allows < 0.5 m); at 2 m it is taller than the robot, a wall no
#: swing trajectory clears.
MAX_OBSTACLE_HEIGHT_M = 2.0
#: Longest side (x or y extent) of a patch or obstacle [m].  The longest built-in patch is
#: the 26 m platform; a side above 500 m (half the coordinate range) is a unit error.
MAX_SIDE_M = 500.0
#: Shortest side of a patch or obstacle [m].  A foot is 0.15 m long and 0.02 m wide
#: (``humanoid3d.xml``) and the foothold boxes keep 0.03 m margins; a side under 1 cm holds
#: no foothold and is a sliver from rounding or a unit error.  The shortest built-in side
#: is 0.18 m (a stone's length); the sweep in :func:`first_overlap` also needs sides
#: well above ``EPS_M``.
MIN_SIDE_M = 0.01
#: Most patches in a course.  Built-ins have at most 65; the foothold planners scan every
#: patch at each touchdown (:func:`.bounds.reachable_foothold_bounds`, ~5 µs a patch) and
#: MuJoCo gets one geom per patch, so 20000 bounds a scan at ~0.1 s (measured): slow, but
#: finite; a course meant to run in real time should stay in the hundreds.
MAX_PATCHES = 20_000
#: Most obstacles in a course.  Built-ins have at most 1; locating an obstacle on its
#: patch costs O(patches) (vectorised), so 2000 x :data:`MAX_PATCHES` stays under ~0.2 s.
MAX_OBSTACLES = 2_000
#: Least distance [m] from ``start_xy`` to any obstacle footprint.  The robot stands at
#: ``start_xy`` with its foot boxes within 0.12 m of it (x -0.06..0.09 m, |y| 0.055..0.075
#: m, ``humanoid3d.xml``); 0.3 m keeps an obstacle about one nominal step (0.17 m) beyond
#: the feet, so the robot neither starts inside an obstacle nor must clear one at once.
START_CLEARANCE_M = 0.3

#: Candidate pairs tested per NumPy block in :func:`first_overlap` (memory ~40 B a pair).
_PAIR_BLOCK = 1 << 18


def check_counts(n_patches: int, n_obstacles: int) -> None:
    """Raise if there are more than :data:`MAX_PATCHES` patches or :data:`MAX_OBSTACLES`
    obstacles (fields ``patches`` / ``obstacles``)."""
    if n_patches > MAX_PATCHES:
        raise CourseFormatError(
            "patches",
            f"a list of {n_patches} patches",
            f"at most {MAX_PATCHES} patches (the planners scan every patch at each touchdown)",
        )
    if n_obstacles > MAX_OBSTACLES:
        raise CourseFormatError(
            "obstacles",
            f"a list of {n_obstacles} obstacles",
            f"at most {MAX_OBSTACLES} obstacles (each is located on its patch at load)",
        )


def _check_footprint(lo: float, hi: float, field_path: str) -> None:
    """Side within [MIN_SIDE_M, MAX_SIDE_M] and ends within ±MAX_ABS_XY_M [m] (each bound
    with the tolerance ``EPS_M``, so that a side of 0.01 m computed as a difference passes)."""
    side = hi - lo
    if side > MAX_SIDE_M + EPS_M:
        raise CourseFormatError(
            field_path,
            [lo, hi],
            f"a side of at most {MAX_SIDE_M:g} m (this one is {side:g} m; a longer one "
            "is a unit error)",
        )
    if side < MIN_SIDE_M - EPS_M:
        raise CourseFormatError(
            field_path,
            [lo, hi],
            f"a side of at least {MIN_SIDE_M:g} m (this one is {side:g} m; a foot needs room)",
        )
    if max(abs(lo), abs(hi)) > MAX_ABS_XY_M + EPS_M:
        raise CourseFormatError(
            field_path, [lo, hi], f"coordinates within ±{MAX_ABS_XY_M:g} m of the origin"
        )


def check_patch_extent(p: Patch, field_path: str) -> None:
    """Raise if patch ``p`` breaks a bound: sides (``.x`` / ``.y``), corners, top (``.z``)."""
    _check_footprint(p.x_min, p.x_max, f"{field_path}.x")
    _check_footprint(p.y_min, p.y_max, f"{field_path}.y")
    if abs(p.z_top_m) > MAX_ABS_Z_M + EPS_M:
        raise CourseFormatError(
            f"{field_path}.z", p.z_top_m, f"a top height z with |z| <= {MAX_ABS_Z_M:g} m"
        )


def check_obstacle_extent(ob: Obstacle, field_path: str) -> None:
    """Raise if obstacle ``ob`` breaks a bound: sides, corners (``.x`` / ``.y``), height."""
    _check_footprint(ob.x_min, ob.x_max, f"{field_path}.x")
    _check_footprint(ob.y_min, ob.y_max, f"{field_path}.y")
    if ob.height_m > MAX_OBSTACLE_HEIGHT_M + EPS_M:
        raise CourseFormatError(
            f"{field_path}.height",
            ob.height_m,
            f"a height of at most {MAX_OBSTACLE_HEIGHT_M:g} m (an obstacle is stepped over)",
        )


def _overlaps(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether rectangles ``a`` and ``b`` (rows of :func:`.patch.footprints`, broadcast)
    share an area: both their x and their y ranges overlap by more than ``EPS_M``."""
    return (
        (a[..., 0] < b[..., 1] - EPS_M)
        & (b[..., 0] < a[..., 1] - EPS_M)
        & (a[..., 2] < b[..., 3] - EPS_M)
        & (b[..., 2] < a[..., 3] - EPS_M)
    )


def _sweep(r: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Sort-and-sweep along ``axis`` (0: x, 1: y): the sort order, and for each sorted
    position k the end of its candidates: positions k+1 .. end[k]-1 start before rectangle
    k ends (minus ``EPS_M``), i.e. overlap it along ``axis``."""
    lo, hi = r[:, 2 * axis], r[:, 2 * axis + 1]
    order = np.argsort(lo, kind="stable")
    end = np.searchsorted(lo[order], hi[order] - EPS_M, side="left")
    return order, end


def first_overlap(r: np.ndarray) -> tuple[int, int] | None:
    """The first pair ``(i, j)``, ``i < j``, of rectangles sharing an area, or None.

    ``r``: rows of :func:`.patch.footprints`, every side longer than ``2 EPS_M``.  "First": the
    smallest ``j`` (the first rectangle in list order that overlaps an earlier one), then
    the smallest ``i``.  Rectangles that only touch (an overlap of at most ``EPS_M``) do
    not count.  Cost: a sort-and-sweep along whichever of x and y has fewer candidate
    pairs, tested in NumPy blocks (20000 tiles or strips: 0.01-0.07 s); only when an
    overlap exists, a second pass over the rectangles up to the one found picks the first
    pair (O(j^2): 0.9 s for j = 20000).
    """
    n = r.shape[0]
    if n < 2:
        return None
    sweeps = [_sweep(r, axis) for axis in (0, 1)]
    counts = [end - np.arange(n) - 1 for _, end in sweeps]
    axis = int(np.argmin([int(c.sum()) for c in counts]))
    (order, _), count = sweeps[axis], counts[axis]
    rs = r[order]
    pos = np.flatnonzero(count > 0)
    csum = np.cumsum(count[pos])
    found: tuple[int, int] | None = None
    k = 0
    while k < pos.size and found is None:
        done = int(csum[k - 1]) if k else 0
        m = max(k + 1, int(np.searchsorted(csum, done + _PAIR_BLOCK, side="right")))
        cnt = count[pos[k:m]]
        i = np.repeat(pos[k:m], cnt)
        j = i + 1 + np.arange(i.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        hit = _overlaps(rs[i], rs[j])
        if hit.any():
            h = int(np.argmax(hit))
            a, b = int(order[i[h]]), int(order[j[h]])
            found = (min(a, b), max(a, b))
        k = m
    if found is None:
        return None
    for j_first in range(1, found[1] + 1):
        hit = _overlaps(r[:j_first], r[j_first])
        if hit.any():
            return int(np.argmax(hit)), j_first
    return found  # pragma: no cover - the pair found is itself overlapping


def _intervals_text(r: Sequence[float]) -> str:
    return f"x [{r[0]!r}, {r[1]!r}], y [{r[2]!r}, {r[3]!r}]"


def check_no_overlap(patches: Sequence[Patch]) -> None:
    """Raise if two patches share an area (field: the later one, ``patches[j]``).

    A point of the course has one surface: patches may touch along edges (within
    ``EPS_M``) but not overlap.  Needs the sides checked first (:func:`check_patch_extent`).
    """
    r = footprints(patches)
    pair = first_overlap(r)
    if pair is None:
        return
    i, j = pair
    raise CourseFormatError(
        f"patches[{j}]",
        {"x": [float(r[j, 0]), float(r[j, 1])], "y": [float(r[j, 2]), float(r[j, 3])]},
        f"no overlap with patches[{i}] ({_intervals_text(r[i].tolist())}); touching edges are fine",
    )


def check_start_clear(obstacles: Sequence[Obstacle], start_xy: tuple[float, float]) -> None:
    """Raise if an obstacle footprint comes within :data:`START_CLEARANCE_M` of the start.

    Distance: Euclidean, from ``start_xy`` to the obstacle's closed xy-rectangle [m].
    """
    x0, y0 = start_xy
    for i, ob in enumerate(obstacles):
        d = rect_distance(x0, y0, ob.x_min, ob.x_max, ob.y_min, ob.y_max)
        if d < START_CLEARANCE_M:
            raise CourseFormatError(
                f"obstacles[{i}]",
                {"x": [ob.x_min, ob.x_max], "y": [ob.y_min, ob.y_max]},
                f"a footprint at least {START_CLEARANCE_M:g} m from the start point "
                f"{start_xy}, where the robot stands (this one is {d:.3g} m from it)",
            )
