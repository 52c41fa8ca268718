"""The built-in courses (``flat``, ``gap``, ``stepping-stones``, ``obstacle``, ``uneven``),
their registry, and :func:`load_course` (a built-in name or a course file).

Every built-in course runs from x = -1 m to x = 25 m on platforms 3 m wide (y in
[-1.5, 1.5] m); ``gap``, ``stepping-stones``, ``obstacle`` and ``uneven`` can be drawn
from a seed
(:data:`SEEDED_COURSES`).
"""

from __future__ import annotations

import inspect
import types
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.terrain.course import Course
from gaitnet_mpc.terrain.fields import finite_number, layout_seed
from gaitnet_mpc.terrain.patch import Obstacle, Patch

#: x extent (m) shared by every built-in course.
_COURSE_X_START_M = -1.0
_COURSE_X_END_M = 25.0
#: Half width (m) of the built-in platforms (y in [-1.5, 1.5]).
_PLATFORM_HALF_WIDTH_M = 1.5
#: End of the start platform (m) of the courses with a terrain section.
_START_PLATFORM_END_M = 0.8


def _platform(x_min: float, x_max: float, z_top_m: float = 0.0) -> Patch:
    return Patch(x_min, x_max, -_PLATFORM_HALF_WIDTH_M, _PLATFORM_HALF_WIDTH_M, z_top_m, "both")


def _param(value: object, field_path: str, lo: float, hi: float, expected: str) -> float:
    v = finite_number(value, field_path)
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


def _or(value: float | None, default: float) -> float:
    return default if value is None else value


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
    seed = layout_seed(seed, "gap.seed")
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
    seed = layout_seed(seed, "stepping-stones.seed")
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


#: Randomised ``obstacle`` layouts (integer millimetres): sections, first box start, box
#: length and height, ground from a box to its hole, hole width, and ground from a hole to
#: the next box. The ground after a box is at least 0.25 m so that a foot fits between a
#: box and its hole (a foot centre keeps 0.10 m from a box and 0.08 m from an edge, the
#: eq. 24 margins of ``kd``, and the foot is 0.15 m long).
_RO_COUNT = (1, 3)
_RO_X0_MM = (1000, 1500)
_RO_LENGTH_MM = (50, 150)
_RO_HEIGHT_MM = (20, 60)
_RO_TO_HOLE_MM = (250, 450)
_RO_HOLE_MM = (100, 200)
_RO_GROUND_MM = (500, 900)


def obstacle_course(
    height_m: float | None = None,
    x_m: float | None = None,
    gap_x_m: float | None = None,
    gap_width_m: float | None = None,
    seed: int | None = None,
    max_height_m: float | None = None,
) -> Course:
    """``obstacle``: boxes across the walkway, each followed by a hole (the paper's
    Fig. 1(e)), then ground to x = 25 m.

    Without ``seed``: one 0.10 m (x) box of ``height_m`` (default 0.03 m) centred at
    ``x_m`` (default 1.5 m), then a hole of ``gap_width_m`` (default 0.15 m) from
    ``gap_x_m`` (default 2.2 m). With ``seed`` (a non-negative integer),
    ``numpy.random.default_rng(seed)`` draws 1 to 3 sections (equally likely), in whole
    millimetres: a box 0.05-0.15 m long and 0.02-0.06 m high (the first starts uniformly
    in [1.0, 1.5] m), 0.25-0.45 m of ground, a hole 0.10-0.20 m wide, then 0.5-0.9 m of
    ground before the next box; all uniform, so the last hole ends before x = 5.7 m
    (8 s at 0.75 m/s). The heights come from a generator of their own
    (``default_rng([seed, 1])``), uniform in [0.02, ``max_height_m``] m (default 0.06),
    so another ``max_height_m`` gives the same layout with other heights. Other parameters
    together with a seed are refused (the seed draws them), as is ``max_height_m``
    without one. The course records ``seed``.
    """
    seed = layout_seed(seed, "obstacle.seed")
    if seed is not None:
        given = (("height_m", height_m), ("x_m", x_m), ("gap_x_m", gap_x_m),
                 ("gap_width_m", gap_width_m))  # fmt: skip
        for name, value in given:
            if value is not None:
                raise CourseFormatError(f"obstacle.{name}", value, "no value with a seed")
        top_mm = _RO_HEIGHT_MM[1]
        if max_height_m is not None:
            top_m = _RO_HEIGHT_MM[0] / 1000.0
            v = _param(max_height_m, "obstacle.max_height_m", top_m - 1e-9, 0.5,
                       f"a height in [{top_m:g}, 0.5) m")  # fmt: skip
            top_mm = round(1000 * v)
        rng = np.random.default_rng(seed)
        heights = np.random.default_rng([seed, 1])
        boxes_mm: list[tuple[int, int, int]] = []
        holes_mm: list[tuple[int, int]] = []
        x0 = _draw_mm(rng, _RO_X0_MM)
        for _ in range(_draw_mm(rng, _RO_COUNT)):
            x1 = x0 + _draw_mm(rng, _RO_LENGTH_MM)
            boxes_mm.append((x0, x1, _draw_mm(heights, (_RO_HEIGHT_MM[0], top_mm))))
            h0 = x1 + _draw_mm(rng, _RO_TO_HOLE_MM)
            holes_mm.append((h0, h0 + _draw_mm(rng, _RO_HOLE_MM)))
            x0 = holes_mm[-1][1] + _draw_mm(rng, _RO_GROUND_MM)
        boxes = [(a / 1000.0, b / 1000.0, h / 1000.0) for a, b, h in boxes_mm]
        holes = [(a / 1000.0, b / 1000.0) for a, b in holes_mm]
    else:
        if max_height_m is not None:
            raise CourseFormatError(
                "obstacle.max_height_m", max_height_m, "no value without a seed (one box)"
            )
        height_m = _param(_or(height_m, 0.03), "obstacle.height_m", 0.0, 0.5, "in (0, 0.5) m")
        x_m = _param(_or(x_m, 1.5), "obstacle.x_m", 0.1, 15.0, "in (0.1, 15) m")
        gap_x_m = _param(_or(gap_x_m, 2.2), "obstacle.gap_x_m", x_m + 0.05, 15.0, f"> {x_m + 0.05}")
        gap_width_m = _param(_or(gap_width_m, 0.15), "obstacle.gap_width_m", 0.0, 5.0, "in (0, 5)")
        boxes = [(x_m - 0.05, x_m + 0.05, height_m)]
        holes = [(gap_x_m, gap_x_m + gap_width_m)]
    edges = [_COURSE_X_START_M, *(x for hole in holes for x in hole), _COURSE_X_END_M]
    patches = tuple(_platform(edges[i], edges[i + 1]) for i in range(0, len(edges), 2))
    w = _PLATFORM_HALF_WIDTH_M
    obstacles = tuple(Obstacle(a, b, -w, w, h, 0.0) for a, b, h in boxes)
    return Course("obstacle", patches, obstacles, seed=seed)


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


#: ``gap_row_course`` (Fig. 6): holes, first hole start and ground between holes [mm].
_ROW_COUNT = 4
_ROW_X0_MM = (1000, 1500)
_ROW_GROUND_MM = (400, 800)


def gap_row_course(width_m: float, seed: int, count: int = _ROW_COUNT) -> Course:
    """A row of ``count`` holes of one width ``width_m`` at seeded positions: Fig. 6's
    2-D gap courses (gaps of 5-15 cm), named ``gap-row``.

    ``numpy.random.default_rng(seed)`` draws the first hole's start uniformly in
    [1.0, 1.5] m and the ground between consecutive holes uniformly in [0.4, 0.8] m
    (whole millimetres), so four 15 cm holes end before x = 4.5 m.  Not a built-in name
    (its width is a parameter the command line has no place for): ``gaitnet-mpc reproduce
    fig6`` writes each layout it runs as a course file.
    """
    seed_checked = layout_seed(seed, "gap-row.seed")
    if seed_checked is None:
        raise CourseFormatError("gap-row.seed", seed, "a non-negative integer")
    width_m = _param(width_m, "gap-row.width_m", 0.0, 1.0, "a gap width in (0, 1) m")
    if isinstance(count, bool) or not isinstance(count, int | np.integer) or not 1 <= count <= 20:
        raise CourseFormatError("gap-row.count", count, "an integer in [1, 20]")
    width_mm = round(width_m * 1000)
    rng = np.random.default_rng(seed_checked)
    edges_mm = [round(_COURSE_X_START_M * 1000)]
    x0 = _draw_mm(rng, _ROW_X0_MM)
    for _ in range(int(count)):
        edges_mm += [x0, x0 + width_mm]
        x0 += width_mm + _draw_mm(rng, _ROW_GROUND_MM)
    edges = [e / 1000.0 for e in edges_mm] + [_COURSE_X_END_M]
    patches = tuple(_platform(edges[i], edges[i + 1]) for i in range(0, len(edges), 2))
    return Course("gap-row", patches, seed=seed_checked)


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
