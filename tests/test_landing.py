"""Landing areas: patches with the obstacles' footprints cut out (terrain/landing.py), and
the eq. 24 box of the next touchdown kept off obstacles (Course, TerrainView)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitnet_mpc.control.terrain_view import TerrainKnowledge, TerrainView
from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.terrain import Course, Obstacle, Patch, load_course
from gaitnet_mpc.terrain.landing import landing_areas, subtract_footprint

WALK = Patch(-1.0, 3.0, -1.0, 1.0, 0.0)


def _area(p: Patch) -> float:
    return (p.x_max - p.x_min) * (p.y_max - p.y_min)


def _covered(areas: tuple[Patch, ...], x: float, y: float) -> bool:
    return any(a.contains(x, y) for a in areas)


def test_a_box_across_the_walkway_leaves_before_and_after() -> None:
    box = Obstacle(1.0, 1.2, -1.0, 1.0, 0.05)
    areas, parent = landing_areas([WALK], [box], clearance_m=0.02)
    assert areas == (
        Patch(-1.0, 0.98, -1.0, 1.0, 0.0),
        Patch(1.22, 3.0, -1.0, 1.0, 0.0),
    )
    assert parent == (0, 0)


def test_a_box_inside_a_patch_leaves_four_overlapping_strips() -> None:
    box = Obstacle(1.0, 1.2, -0.1, 0.1, 0.05)
    pieces = subtract_footprint(WALK, (1.0, 1.2, -0.1, 0.1))
    assert len(pieces) == 4
    rng = np.random.default_rng(0)
    for x, y in rng.uniform((-1.0, -1.0), (3.0, 1.0), size=(500, 2)):
        inside = 1.0 < x < 1.2 and -0.1 < y < 0.1
        assert _covered(tuple(pieces), x, y) != inside, (x, y)
    areas, _ = landing_areas([WALK], [box])
    assert sorted(map(_area, areas)) == sorted(map(_area, pieces))


def test_several_footprints_keep_only_maximal_pieces() -> None:
    boxes = [Obstacle(0.5, 0.6, -0.2, 0.2, 0.05), Obstacle(1.5, 1.6, -0.3, 0.1, 0.05)]
    areas, parent = landing_areas([WALK, Patch(3.0, 4.0, -1.0, 1.0, 0.1)], boxes)
    assert parent.count(1) == 1 and areas[parent.index(1)].z_top_m == 0.1  # untouched
    mine = [a for a, i in zip(areas, parent, strict=True) if i == 0]
    for k, a in enumerate(mine):  # no piece lies inside another
        assert not any(
            o.x_min <= a.x_min and a.x_max <= o.x_max and o.y_min <= a.y_min and a.y_max <= o.y_max
            for m, o in enumerate(mine)
            if m != k
        )
    rng = np.random.default_rng(1)
    for x, y in rng.uniform((-1.0, -1.0), (3.0, 1.0), size=(1000, 2)):
        blocked = any(b.x_min < x < b.x_max and b.y_min < y < b.y_max for b in boxes)
        assert _covered(tuple(mine), x, y) != blocked, (x, y)


def test_the_touchdown_box_lies_off_the_obstacle() -> None:
    course = load_course("obstacle")  # box at x in [1.45, 1.55], a hole from 2.2 m
    kw = {"reach_x_m": 0.3, "margin_m": 0.08, "margin_y_m": 0.03}
    lo, hi, i = course.reachable_foothold_bounds([1.45, 0.0], "left", [1.5, 0.1], **kw)
    assert i == 0 and hi[0] == pytest.approx(1.45 - 0.08)  # before it
    lo, hi, i = course.reachable_foothold_bounds(
        [1.55, 0.0], "left", [1.6, 0.1], obstacle_clearance_m=0.02, **kw
    )
    assert i == 0 and lo[0] == pytest.approx(1.55 + 0.02 + 0.08)  # after it
    assert hi[0] == pytest.approx(2.2 - 0.08)
    lo, hi, _ = course.reachable_foothold_bounds(
        [1.45, 0.0], "left", [1.5, 0.1], obstacle_clearance_m=None, **kw
    )
    assert lo[0] < 1.45 < hi[0]  # None: the obstacles are not known


def test_a_strip_too_short_for_the_foot_is_no_candidate() -> None:
    # 5 cm of ground between the box and the hole: no foot fits there with its margins
    patches = (Patch(-1.0, 1.65, -1.0, 1.0, 0.0), Patch(1.9, 25.0, -1.0, 1.0, 0.0))
    course = Course("t", patches, (Obstacle(1.5, 1.6, -1.0, 1.0, 0.03),))
    lo, hi, i = course.reachable_foothold_bounds(
        [1.6, 0.0], "left", [1.62, 0.0], reach_x_m=0.3, margin_m=0.08
    )
    assert i == 0 and hi[0] == pytest.approx(1.42)  # before the box, not on the strip
    lo, hi, i = course.reachable_foothold_bounds(
        [1.8, 0.0], "left", [1.8, 0.0], reach_x_m=0.3, margin_m=0.08
    )
    assert i == 1 and lo[0] == pytest.approx(1.98)  # beyond the hole


def test_the_view_keeps_touchdowns_off_obstacles_of_unknown_height() -> None:
    course = load_course("obstacle")
    kw = {"reach_x_m": 0.3, "margin_m": 0.08}
    for knowledge in (TerrainKnowledge(), TerrainKnowledge(obstacle_heights=False)):
        view = TerrainView(course, knowledge)
        _, hi, _ = view.reachable_foothold_bounds([1.45, 0.0], "left", [1.5, 0.0], **kw)
        assert hi[0] == pytest.approx(1.45 - 0.08)
        (box,) = view.obstacle_footprints(1.3, 1.7)  # where it stands: known either way
        assert box.x_min == pytest.approx(1.45)
    assert (
        TerrainView(course, TerrainKnowledge(obstacle_heights=False)).swing_obstacles(1.3, 1.7)
        == []
    )  # its height: not known


def test_seeded_obstacle_courses_in_range() -> None:
    counts = set()
    for seed in range(50):
        c = load_course("obstacle", seed=seed)
        holes = [(a.x_max, b.x_min) for a, b in zip(c.patches, c.patches[1:], strict=False)]
        assert len(holes) == len(c.obstacles), seed
        counts.add(len(c.obstacles))
        for ob, (h0, h1) in zip(c.obstacles, holes, strict=True):
            assert 0.05 - 1e-9 <= ob.x_max - ob.x_min <= 0.15 + 1e-9, seed
            assert 0.02 - 1e-9 <= ob.height_m <= 0.06 + 1e-9, seed
            assert 0.25 - 1e-9 <= h0 - ob.x_max <= 0.45 + 1e-9, seed  # room for one foot
            assert 0.10 - 1e-9 <= h1 - h0 <= 0.20 + 1e-9, seed
            assert ob.y_min <= -1.0 and ob.y_max >= 1.0  # across the walkway
        assert 1.0 - 1e-9 <= c.obstacles[0].x_min <= 1.5 + 1e-9
        assert holes[-1][1] <= 5.7
    assert counts == {1, 2, 3}
    with pytest.raises(CourseFormatError) as info:
        load_course("obstacle", seed=1, height_m=0.03)
    assert info.value.field == "obstacle.height_m"
    with pytest.raises(CourseFormatError) as info:
        load_course("obstacle", max_height_m=0.04)  # the built-in box: no seed, no draw
    assert info.value.field == "obstacle.max_height_m"


def test_a_lower_cap_keeps_the_layout_and_caps_the_heights() -> None:
    for seed in range(20):
        tall = load_course("obstacle", seed=seed)
        low = load_course("obstacle", seed=seed, max_height_m=0.04)
        assert low.patches == tall.patches, seed
        assert [(o.x_min, o.x_max) for o in low.obstacles] == [
            (o.x_min, o.x_max) for o in tall.obstacles
        ]
        assert all(0.02 - 1e-9 <= o.height_m <= 0.04 + 1e-9 for o in low.obstacles), seed
