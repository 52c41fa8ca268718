"""What a walking controller knows about the terrain (control/terrain_view.py)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.kd_walk import KDWalkController
from gaitnet_mpc.control.kd_walk_config import KDWalkConfig, preview_walk_config, walk_terrain
from gaitnet_mpc.control.terrain_view import TerrainKnowledge, TerrainView
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.terrain import Course, Patch, load_course


def test_one_step_view_refuses_the_whole_course() -> None:
    view = TerrainView(load_course("stepping-stones"))
    with pytest.raises(ConfigError, match=r"terrain_knowledge\.multi_step"):
        view.course_for_multi_step_preview()
    multi = TerrainView(load_course("stepping-stones"), TerrainKnowledge(multi_step=True))
    assert multi.course_for_multi_step_preview().name == "stepping-stones"


def test_obstacle_heights_are_part_of_the_preview_unless_turned_off() -> None:
    course = load_course("obstacle")
    (box,) = TerrainView(course).swing_obstacles(1.7, 1.3)  # either order
    assert box.z_top_m == pytest.approx(0.03)
    blind = TerrainView(course, TerrainKnowledge(obstacle_heights=False))
    assert blind.swing_obstacles(1.3, 1.7) == []
    assert TerrainView(course).swing_obstacles(0.0, 1.0) == []  # none in that swing


def test_foothold_height_over_a_patch_and_a_hole() -> None:
    view = TerrainView(load_course("gap"))
    assert view.foothold_height_m(1.0, 0.0, default_m=-1.0) == 0.0
    assert view.foothold_height_m(1.6, 0.0, default_m=-1.0) == -1.0  # in the gap


def test_knowledge_is_recorded_and_the_preview_needs_the_multi_step_view() -> None:
    assert TerrainKnowledge().to_dict() == {
        "preview": "one-step",
        "multi_step": False,
        "obstacle_heights": True,
        "blind": False,
    }
    robot, course, cmd = load_robot("humanoid3d"), load_course("flat"), Command(0.5)
    cfg = preview_walk_config()
    with pytest.raises(ConfigError, match="multi_step"):
        KDWalkController(robot, TerrainView(course), cmd, config=cfg)
    ctrl = KDWalkController(robot, walk_terrain(course, cfg), cmd, config=cfg)
    assert ctrl.terrain_knowledge()["preview"] == "multi-step"


def test_swings_assume_a_height_where_the_obstacles_height_is_unknown() -> None:
    import numpy as np

    robot, course, cmd = load_robot("humanoid3d"), load_course("obstacle"), Command(0.5)
    start, target = np.array([1.35, 0.0, 0.01]), np.array([1.65, 0.0, 0.01])
    known_cfg = replace(preview_walk_config(), preview=None)
    known = KDWalkController(robot, walk_terrain(course, known_cfg), cmd, config=known_cfg)
    assert known.obstacles.near(start, target) == [pytest.approx((1.45, 1.55, 0.03))]
    cfg = replace(known_cfg, obstacle_heights=False, unknown_obstacle_height_m=0.05)
    blind = KDWalkController(robot, walk_terrain(course, cfg), cmd, config=cfg)
    assert blind.terrain_knowledge()["obstacle_heights"] is False
    assert blind.obstacles.near(start, target) == [pytest.approx((1.45, 1.55, 0.05))]
    assert blind.obstacles.near(start - 1.0, target - 1.0) == []  # none near that swing


def _steps_course() -> Course:
    """Three tiles in a row, the middle one 6 cm up, and a tile beside the middle one."""
    return Course(
        name="steps",
        patches=(
            Patch(-1.0, 0.25, -0.25, 0.25, 0.0),
            Patch(0.25, 0.5, -0.25, 0.25, 0.06),
            Patch(0.5, 2.0, -0.25, 0.25, 0.0),
            Patch(0.25, 0.5, 0.25, 0.75, 0.10),  # beside the path
        ),
    )


def test_a_swing_clears_the_tiles_it_passes_over() -> None:
    """The uneven-ground fix (docs/design/uneven_steps.md): a tile higher than the lower of
    the swing's ends, under its path, is cleared like an obstacle, and so is the part of a
    higher end's tile that the foot does not stand on; tiles beside the path are not."""
    import numpy as np

    robot, cmd = load_robot("humanoid3d"), Command(0.5)
    view = TerrainView(_steps_course())
    assert [p.z_top_m for p in view.patches_crossed(0.1, 0.0, 0.7, 0.0)] == [0.0, 0.06, 0.0]
    assert [p.z_top_m for p in view.patches_crossed(0.1, 0.2, 0.7, 0.3)] == [0.0, 0.06, 0.1]
    cfg = KDWalkConfig()
    ctrl = KDWalkController(robot, walk_terrain(_steps_course(), cfg), cmd, config=cfg)
    start, target = np.array([0.1, 0.0, 0.01]), np.array([0.7, 0.0, 0.01])
    assert ctrl.obstacles.near(start, target) == [(0.25, 0.5, 0.06)]
    reach = cfg.swing.foot_half_length_m + 0.01  # the foot point to its end, + 1 cm
    # onto the higher tile: its edge before the landing foot (a toe would clip it) ...
    up = ctrl.obstacles.near(start, np.array([0.4, 0.0, 0.07]))
    assert up == [pytest.approx((0.25, 0.4 - reach, 0.06))]
    # ... and off it: its edge ahead of the lifted foot (a heel would clip it)
    down = ctrl.obstacles.near(np.array([0.3, 0.0, 0.07]), target)
    assert down == [pytest.approx((0.3 + reach, 0.5, 0.06))]
    level = KDWalkController(robot, walk_terrain(load_course("flat"), cfg), cmd, config=cfg)
    assert level.obstacles.near(start, target) == []
    blind_cfg = replace(cfg, blind=True)
    blind = KDWalkController(robot, walk_terrain(_steps_course(), blind_cfg), cmd, config=blind_cfg)
    assert blind.obstacles.near(start, target) == []
