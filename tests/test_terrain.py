"""Tests of gaitnet_mpc.terrain: course format, built-in courses, queries, MuJoCo geoms."""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Callable
from itertools import pairwise
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pytest

from gaitnet_mpc.errors import ConfigError, CourseFormatError
from gaitnet_mpc.terrain import (
    BUILTIN_COURSES,
    SEEDED_COURSES,
    Course,
    Obstacle,
    Patch,
    course_geoms_xml,
    load_course,
)

EXAMPLE_JSON = Path(__file__).resolve().parents[1] / "src/gaitnet_mpc/courses/example.json"


def _valid_dict() -> dict[str, Any]:
    return {
        "name": "t",
        "patches": [
            {"x": [-1.0, 1.0], "y": [-0.5, 0.5], "z": 0.0, "feet": "both"},
            {"x": [1.1, 1.4], "y": [0.0, 0.3], "z": 0.05, "feet": "left"},
            {"x": [1.2, 1.5], "y": [-0.3, 0.0], "z": -0.02, "feet": "right"},
            {"x": [1.6, 5.0], "y": [-0.5, 0.5], "z": 0.1},
        ],
        "obstacles": [{"x": [3.0, 3.1], "y": [-0.5, 0.5], "height": 0.04}],
    }


# ------------------------------------------------------------------------- format round trip


def test_from_dict_defaults_and_obstacle_base() -> None:
    c = Course.from_dict(_valid_dict())
    assert c.name == "t"
    assert c.patches[3].feet == "both"
    assert c.start_xy == (0.0, 0.0)
    (ob,) = c.obstacles
    assert ob.z_base_m == pytest.approx(0.1)
    assert ob.z_top_m == pytest.approx(0.14)
    d = _valid_dict()
    del d["obstacles"]
    assert Course.from_dict(d).obstacles == ()


def test_round_trip_dict_and_json(tmp_path: Path) -> None:
    c = Course.from_dict(_valid_dict())
    assert Course.from_dict(c.to_dict()) == c
    assert json.loads(json.dumps(c.to_dict())) == c.to_dict()
    path = tmp_path / "course.json"
    path.write_text(json.dumps(c.to_dict()))
    assert Course.from_json(path) == c
    assert load_course(str(path)) == c


@pytest.mark.parametrize("name", list(BUILTIN_COURSES))
def test_round_trip_builtins(name: str, tmp_path: Path) -> None:
    c = load_course(name)
    assert Course.from_dict(c.to_dict()) == c
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(c.to_dict()))
    assert Course.from_json(path) == c


def test_from_json_name_defaults_to_stem(tmp_path: Path) -> None:
    d = _valid_dict()
    del d["name"]
    path = tmp_path / "my-course.json"
    path.write_text(json.dumps(d))
    assert Course.from_json(path).name == "my-course"


def test_example_json_loads() -> None:
    c = load_course(str(EXAMPLE_JSON))
    assert c.name == "example"
    assert {p.feet for p in c.patches} == {"both", "left", "right"}
    assert c.obstacles[0].z_base_m == 0.0


def test_start_xy_round_trip() -> None:
    d = _valid_dict()
    d["start_xy"] = [0.5, 0.1]
    c = Course.from_dict(d)
    assert c.start_xy == (0.5, 0.1)
    assert Course.from_dict(c.to_dict()) == c


def _set(path: tuple[Any, ...], value: Any) -> Callable[[dict[str, Any]], None]:
    def mutate(d: dict[str, Any]) -> None:
        target = d
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value

    return mutate


def _delete(path: tuple[Any, ...]) -> Callable[[dict[str, Any]], None]:
    def mutate(d: dict[str, Any]) -> None:
        target = d
        for key in path[:-1]:
            target = target[key]
        del target[path[-1]]

    return mutate


BAD_INPUTS: list[tuple[str, Callable[[dict[str, Any]], None], str, str]] = [
    ("missing patches", _delete(("patches",)), "patches", "<missing>"),
    ("empty patches", _set(("patches",), []), "patches", "[]"),
    ("patches not a list", _set(("patches",), "ground"), "patches", "'ground'"),
    ("x_min == x_max", _set(("patches", 1, "x"), [1.2, 1.2]), "patches[1].x", "[1.2, 1.2]"),
    ("x_min > x_max", _set(("patches", 2, "x"), [1.5, 1.2]), "patches[2].x", "[1.5, 1.2]"),
    ("y_min > y_max", _set(("patches", 0, "y"), [0.5, -0.5]), "patches[0].y", "[0.5, -0.5]"),
    ("x one number", _set(("patches", 1, "x"), 1.2), "patches[1].x", "1.2"),
    ("x three numbers", _set(("patches", 1, "x"), [1, 2, 3]), "patches[1].x", "[1, 2, 3]"),
    ("x string item", _set(("patches", 1, "x"), ["a", 2.0]), "patches[1].x[0]", "'a'"),
    ("missing x", _delete(("patches", 3, "x")), "patches[3].x", "<missing>"),
    ("non-numeric z", _set(("patches", 2, "z"), "high"), "patches[2].z", "'high'"),
    ("bool z", _set(("patches", 2, "z"), True), "patches[2].z", "True"),
    ("missing z", _delete(("patches", 1, "z")), "patches[1].z", "<missing>"),
    ("NaN z", _set(("patches", 1, "z"), math.nan), "patches[1].z", "nan"),
    ("inf x", _set(("patches", 3, "x"), [1.6, math.inf]), "patches[3].x[1]", "inf"),
    ("bad feet", _set(("patches", 1, "feet"), "middle"), "patches[1].feet", "'middle'"),
    ("feet not str", _set(("patches", 1, "feet"), 1), "patches[1].feet", "1"),
    ("patch not object", _set(("patches", 1), [1, 2]), "patches[1]", "[1, 2]"),
    ("unknown patch key", _set(("patches", 0, "colour"), "red"), "patches[0].colour", "'red'"),
    ("unknown top key", _set(("terrain",), 3), "terrain", "3"),
    ("bad name", _set(("name",), 7), "name", "7"),
    ("empty name", _set(("name",), ""), "name", "''"),
    (
        "obstacle not on a patch",
        _set(("obstacles", 0, "x"), [1.52, 1.58]),
        "obstacles[0]",
        "(1.55, 0.0)",
    ),
    ("obstacle zero height", _set(("obstacles", 0, "height"), 0.0), "obstacles[0].height", "0.0"),
    ("obstacle negative height", _set(("obstacles", 0, "height"), -1), "obstacles[0].height", "-1"),
    ("obstacle NaN y", _set(("obstacles", 0, "y"), [math.nan, 1]), "obstacles[0].y[0]", "nan"),
    ("obstacle missing height", _delete(("obstacles", 0, "height")), "obstacles[0].height", "<m"),
    ("obstacle unknown key", _set(("obstacles", 0, "z"), 0.1), "obstacles[0].z", "0.1"),
    ("obstacles not list", _set(("obstacles",), {"x": 1}), "obstacles", "{'x': 1}"),
    ("bad start_xy", _set(("start_xy",), [0.0]), "start_xy", "[0.0]"),
    ("start in a hole", _set(("start_xy",), [1.55, 0.0]), "patches", "start point"),
    ("start on left-only", _set(("start_xy",), [1.15, 0.1]), "patches", "start point"),
    (
        "no both patch at origin",
        _set(("patches", 0, "x"), [0.2, 1.0]),
        "patches",
        "no patch allowing both feet",
    ),
]


@pytest.mark.parametrize(
    ("mutate", "field", "value_text"),
    [pytest.param(m, f, v, id=i) for i, m, f, v in BAD_INPUTS],
)
def test_malformed_course_raises(
    mutate: Callable[[dict[str, Any]], None], field: str, value_text: str
) -> None:
    d = copy.deepcopy(_valid_dict())
    mutate(d)
    with pytest.raises(CourseFormatError) as info:
        Course.from_dict(d)
    msg = str(info.value)
    assert msg.startswith(f"{field}: got "), msg
    assert value_text in msg, msg
    assert info.value.field == field


def test_not_a_dict_and_bad_files(tmp_path: Path) -> None:
    with pytest.raises(CourseFormatError, match="course"):
        Course.from_dict([1, 2])  # type: ignore[arg-type]
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(CourseFormatError, match="valid JSON"):
        Course.from_json(bad)
    with pytest.raises(CourseFormatError, match="readable"):
        Course.from_json(tmp_path / "missing.json")


def test_dataclass_validation() -> None:
    with pytest.raises(CourseFormatError, match=r"Patch\.x_max"):
        Patch(1.0, 0.0, 0.0, 1.0, 0.0)
    with pytest.raises(CourseFormatError, match=r"Patch\.feet"):
        Patch(0.0, 1.0, 0.0, 1.0, 0.0, "middle")
    with pytest.raises(CourseFormatError, match=r"Obstacle\.height_m"):
        Obstacle(0.0, 1.0, 0.0, 1.0, 0.0)
    ground = Patch(-1.0, 1.0, -1.0, 1.0, 0.1)
    with pytest.raises(CourseFormatError, match=r"obstacles\[0\]\.z_base_m"):
        Course("c", (ground,), (Obstacle(0.0, 0.1, -1.0, 1.0, 0.05, 0.0),))
    with pytest.raises(CourseFormatError, match="patches"):
        Course("c", ())
    assert Course("c", [ground]).patches == (ground,)  # lists are frozen into tuples


# ------------------------------------------------------------------------- built-in courses


def test_load_course_unknown_name_lists_valid_names() -> None:
    with pytest.raises(CourseFormatError) as info:
        load_course("moon")
    msg = str(info.value)
    assert msg.startswith("course: got 'moon'")
    for name in BUILTIN_COURSES:
        assert name in msg


def test_load_course_bad_params() -> None:
    with pytest.raises(CourseFormatError, match="gap parameters"):
        load_course("gap", depth_m=1.0)
    with pytest.raises(CourseFormatError, match=r"gap\.width_m: got -0\.1"):
        load_course("gap", width_m=-0.1)
    with pytest.raises(CourseFormatError, match=r"uneven\.seed"):
        load_course("uneven", seed=-1)


@pytest.mark.parametrize("name", list(BUILTIN_COURSES))
def test_builtin_course_basics(name: str) -> None:
    c = load_course(name)
    assert c.name == name
    k = c.patch_at(0.0, 0.0)
    assert k is not None and c.patches[k].feet == "both"
    assert c.foot_allowed(0.0, 0.06, "left") and c.foot_allowed(0.0, -0.06, "right")
    final = max(c.patches, key=lambda p: p.x_max)
    assert final.x_max >= 22.0 and final.x_min < 21.0
    assert final.feet == "both" and final.y_min <= -0.5 and final.y_max >= 0.5
    # A straight walk along y = 0 for 20 s at 1 m/s ends on ground.
    assert c.ground_height_at(20.0, 0.0) is not None


def test_flat() -> None:
    c = load_course("flat")
    assert c.patches == (Patch(-1.0, 25.0, -1.5, 1.5, 0.0, "both"),)


@pytest.mark.parametrize(("width_m", "x_m"), [(0.2, 1.5), (0.35, 2.0), (0.05, 0.5)])
def test_gap(width_m: float, x_m: float) -> None:
    c = load_course("gap", width_m=width_m, x_m=x_m)
    for x in np.linspace(x_m + 1e-6, x_m + width_m - 1e-6, 7):
        assert c.ground_height_at(float(x), 0.0) is None
    assert c.ground_height_at(x_m - 0.01, 0.0) == 0.0
    assert c.ground_height_at(x_m + width_m + 0.01, 0.0) == 0.0


def test_stepping_stones() -> None:
    c = load_course("stepping-stones")
    feet = {p.feet for p in c.patches}
    assert feet == {"both", "left", "right"}
    for p in c.patches:
        if p.feet == "left":
            assert p.y_min >= -1e-9 and p.y_max <= 0.3
        if p.feet == "right":
            assert p.y_max <= 1e-9 and p.y_min >= -0.3
    ordered = sorted(c.patches, key=lambda p: p.x_min)
    gaps = [b.x_min - max(p.x_max for p in ordered[: i + 1]) for i, b in enumerate(ordered[1:])]
    assert max(gaps) >= 0.05
    assert max(gaps) <= 0.12  # nothing wider than a long step can clear
    stones = [p for p in c.patches if p.x_max < 20.0 and p.x_min > 0.8 - 1e-9]
    assert 2.3 <= max(p.x_max for p in stones) - 0.8 <= 3.2
    assert c == load_course("stepping-stones")  # deterministic
    assert all(p.z_top_m == 0.0 for p in load_course("stepping-stones", dz_m=0.0).patches)


def test_obstacle_course() -> None:
    c = load_course("obstacle")
    (ob,) = c.obstacles
    assert ob.x_max - ob.x_min == pytest.approx(0.10)
    assert ob.height_m == pytest.approx(0.03)
    assert 1.4 <= ob.x_center_m <= 1.6
    assert ob.y_min <= -0.5 and ob.y_max >= 0.5
    assert c.ground_height_at(1.5, 0.0) == 0.0
    assert c.ground_height_at(2.25, 0.0) is None
    assert c.ground_height_at(2.19, 0.0) == 0.0 and c.ground_height_at(2.36, 0.0) == 0.0
    assert c.obstacles_between(1.3, 1.7) == [ob]
    assert c.obstacles_between(1.7, 1.3) == [ob]
    assert c.obstacles_between(1.6, 2.0) == []


def test_uneven() -> None:
    c = load_course("uneven")
    tiles = c.patches[1:-1]
    assert len(tiles) > 20
    assert all(-0.02 <= p.z_top_m <= 0.02 for p in tiles)
    assert len({p.z_top_m for p in tiles}) > len(tiles) // 2
    assert c == load_course("uneven", seed=0)
    assert c != load_course("uneven", seed=1)
    assert max(p.x_max for p in tiles) >= 5.9
    # Contiguous: every point of the walkway up to the final platform is on a patch.
    for x in np.linspace(-0.5, 7.0, 151):
        for y in (-0.3, -0.06, 0.0, 0.06, 0.3):
            assert c.patch_at(float(x), y) is not None


# ------------------------------------------------------------------------- queries


def test_patch_at_and_heights_shared_edge_prefers_highest() -> None:
    low = Patch(-1.0, 0.5, -1.0, 1.0, 0.0)
    high = Patch(0.5, 0.8, -0.2, 0.2, 0.1, "left")
    c = Course("o", (low, high))
    assert c.patch_at(0.0, 0.0) == 0
    assert c.patch_at(0.6, 0.0) == 1
    assert c.ground_height_at(0.6, 0.0) == 0.1
    assert c.patch_at(1.5, 0.0) is None and c.ground_height_at(1.5, 0.0) is None
    assert c.patch_at(0.5, 1.0) == 0  # closed rectangles
    # on the shared edge x = 0.5 the top surface is the left-only patch
    assert c.patch_at(0.5, 0.0) == 1
    assert c.foot_allowed(0.5, 0.0, "left") and not c.foot_allowed(0.5, 0.0, "right")
    # overlapping patches (two surfaces at one point) are refused
    with pytest.raises(CourseFormatError, match=r"^patches\[1\]: .*no overlap with patches\[0\]"):
        Course("o", (Patch(-1.0, 1.0, -1.0, 1.0, 0.0), high))


def test_foot_allowed() -> None:
    c = Course.from_dict(_valid_dict())
    assert c.foot_allowed(0.0, 0.0, "left") and c.foot_allowed(0.0, 0.0, "right")
    assert c.foot_allowed(1.15, 0.1, "left") and not c.foot_allowed(1.15, 0.1, "right")
    assert c.foot_allowed(1.45, -0.1, "right") and not c.foot_allowed(1.45, -0.1, "left")
    assert not c.foot_allowed(1.55, 0.0, "left") and not c.foot_allowed(1.55, 0.0, "right")
    with pytest.raises(ConfigError, match="foot"):
        c.foot_allowed(0.0, 0.0, "both")


COURSES = {name: load_course(name) for name in BUILTIN_COURSES} | {
    "custom": Course.from_dict(_valid_dict()),
    "stepping-stones-seed-3": load_course("stepping-stones", seed=3),
    "gap-seed-3": load_course("gap", seed=3),
}


# ------------------------------------------------------------------------- MuJoCo geometry


@pytest.mark.parametrize("name", sorted(COURSES))
def test_geoms_xml_parses_with_right_tops(name: str) -> None:
    c = COURSES[name]
    xml = course_geoms_xml(c, thickness_m=0.4)
    model = mujoco.MjModel.from_xml_string(f"<mujoco><worldbody>{xml}</worldbody></mujoco>")
    assert model.ngeom == len(c.patches) + len(c.obstacles)
    for i, p in enumerate(c.patches):
        gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"patch_{i}")
        assert gid >= 0
        assert model.geom_type[gid] == mujoco.mjtGeom.mjGEOM_BOX
        top = model.geom_pos[gid][2] + model.geom_size[gid][2]
        assert top == pytest.approx(p.z_top_m, abs=1e-7)
        assert 2 * model.geom_size[gid][2] == pytest.approx(0.4)
        assert model.geom_pos[gid][0] - model.geom_size[gid][0] == pytest.approx(p.x_min)
        assert model.geom_pos[gid][1] + model.geom_size[gid][1] == pytest.approx(p.y_max)
    for i, ob in enumerate(c.obstacles):
        gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"obstacle_{i}")
        top = model.geom_pos[gid][2] + model.geom_size[gid][2]
        bottom = model.geom_pos[gid][2] - model.geom_size[gid][2]
        assert top == pytest.approx(ob.z_top_m, abs=1e-7)
        assert bottom == pytest.approx(ob.z_base_m, abs=1e-7)


def test_geom_colours_follow_feet() -> None:
    c = Course.from_dict(_valid_dict())
    xml = course_geoms_xml(c)
    model = mujoco.MjModel.from_xml_string(f"<mujoco><worldbody>{xml}</worldbody></mujoco>")
    rgba = {p.feet: model.geom_rgba[i] for i, p in enumerate(c.patches)}
    assert rgba["both"][1] > rgba["both"][0]  # green
    assert rgba["left"][2] > rgba["left"][0]  # blue
    assert rgba["right"][0] > rgba["right"][2]  # red
    with pytest.raises(ConfigError, match="thickness_m"):
        course_geoms_xml(c, thickness_m=0.0)


def test_reachable_foothold_bounds_prefers_the_patch_the_leg_can_reach() -> None:
    """CoM at touchdown 0.02 m before a 0.20 m gap: the far side is out of reach (0.12 m),
    so the near patch is chosen even though the nominal foothold lies over the gap."""
    course = load_course("gap", width_m=0.2, x_m=1.5)
    lo, hi, patch = course.reachable_foothold_bounds(
        (1.48, 0.0), "left", (1.56, 0.06), reach_x_m=0.12, margin_m=0.03
    )
    assert patch == course.patch_at(1.0, 0.0)
    assert hi[0] == pytest.approx(1.47)
    # CoM at touchdown over the middle of the gap: only the far side is within reach.
    lo, hi, patch = course.reachable_foothold_bounds(
        (1.65, 0.0), "left", (1.70, 0.06), reach_x_m=0.12, margin_m=0.03
    )
    assert patch == course.patch_at(2.0, 0.0)
    assert lo[0] == pytest.approx(1.73)


def test_reachable_foothold_bounds_reach_back_narrows_the_window_behind_the_com() -> None:
    """Gap 1.6-1.8 m, CoM at touchdown 1.65 m: the near side (ends 1.57 m shrunk) is closer
    to the nominal foothold than the far one (from 1.83 m); a 0.05 m reach behind the CoM
    rules it out."""
    course = load_course("gap", width_m=0.2, x_m=1.6)
    args = ((1.65, 0.0), "left", (1.66, 0.06))
    _, hi, patch = course.reachable_foothold_bounds(*args, reach_x_m=0.2, margin_m=0.03)
    assert patch == course.patch_at(1.0, 0.0)
    assert hi[0] == pytest.approx(1.57)
    lo, _, patch = course.reachable_foothold_bounds(
        *args, reach_x_m=0.2, reach_back_m=0.05, margin_m=0.03
    )
    assert patch == course.patch_at(2.0, 0.0)
    assert lo[0] == pytest.approx(1.83)


def test_reachable_foothold_bounds_respect_the_foot_of_a_patch() -> None:
    course = load_course("stepping-stones")
    for foot in ("left", "right"):
        for x in np.linspace(0.9, 3.2, 12):
            lo, hi, patch = course.reachable_foothold_bounds((x, 0.0), foot, (x + 0.08, 0.0))
            assert patch is not None
            assert course.patches[patch].allows(foot)
            assert np.all(lo <= hi)


# ------------------------------------------------------------------------- randomised layouts

#: The built-in stepping-stone table as of the randomised layouts' introduction (a copy, so
#: that a change to terrain.builtin_courses._STONES shows up here).
_BUILTIN_STONES = (
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
SEEDS = range(50)
TOL_M = 1e-9


def _platform(x_min: float, x_max: float) -> Patch:
    return Patch(x_min, x_max, -1.5, 1.5, 0.0, "both")


def _whole_mm(v: float) -> bool:
    return abs(v * 1000.0 - round(v * 1000.0)) < 1e-6


def _lane_holes_m(c: Course, foot: str) -> list[float]:
    """x holes between consecutive patches usable by ``foot`` (sorted by x_min)."""
    usable = sorted((p for p in c.patches if p.allows(foot)), key=lambda p: p.x_min)
    holes, end = [], usable[0].x_max
    for p in usable[1:]:
        holes.append(p.x_min - end)
        end = max(end, p.x_max)
    return holes


def _footstep_sequence_exists(
    c: Course, step_min_m: float, step_max_m: float, margin_m: float, res_m: float = 0.005
) -> bool:
    """Whether alternating footholds (foot centres ``margin_m`` inside an allowed patch,
    each ``step_min_m``-``step_max_m`` ahead of the other foot's) lead from x = 0 onto
    the final platform.  Lateral placement is not modelled (lanes contain y = ±0.06 m)."""
    xs = np.arange(-0.2, 4.5, res_m)
    allowed = {}
    for foot in ("left", "right"):
        ok = np.zeros(xs.shape, bool)
        for p in c.patches:
            if p.allows(foot):
                ok |= (xs >= p.x_min + margin_m - TOL_M) & (xs <= p.x_max - margin_m + TOL_M)
        allowed[foot] = ok
    reach = {foot: np.zeros(xs.shape, bool) for foot in allowed}
    i0 = int(np.argmin(np.abs(xs)))
    for foot in reach:
        reach[foot][i0] = True  # either foot may step first
    lo, hi = round(step_min_m / res_m), round(step_max_m / res_m)
    for i in range(xs.size):
        for foot, nxt in (("left", "right"), ("right", "left")):
            if reach[foot][i]:
                j = np.arange(i + lo, min(i + hi + 1, xs.size))
                reach[nxt][j] |= allowed[nxt][j]
    x_final = max(c.patches, key=lambda p: p.x_max).x_min
    done = xs >= x_final + margin_m
    return bool(reach["left"][done].any() or reach["right"][done].any())


def test_default_layouts_unchanged() -> None:
    stones = load_course("stepping-stones")
    expected = (
        _platform(-1.0, 0.8),
        *(
            Patch(x0, x1, y0, y1, level * 0.02, feet)
            for x0, x1, y0, y1, feet, level in _BUILTIN_STONES
        ),
        _platform(3.4, 25.0),
    )
    assert stones.patches == expected
    assert stones.seed is None and "seed" not in stones.to_dict()
    assert load_course("stepping-stones", seed=None) == stones
    gap = load_course("gap")
    assert gap.patches == (_platform(-1.0, 1.5), _platform(1.7, 25.0))
    assert gap.seed is None and "seed" not in gap.to_dict()
    assert load_course("gap", width_m=0.2, x_m=1.5) == gap
    assert load_course("uneven").seed == 0  # uneven keeps its default seed, now recorded


def test_seeded_courses_are_the_ones_taking_a_seed() -> None:
    assert SEEDED_COURSES == {"uneven", "stepping-stones", "gap", "obstacle"}


@pytest.mark.parametrize("name", sorted(SEEDED_COURSES))
def test_seeded_layout_deterministic_recorded_and_varied(name: str) -> None:
    for seed in (0, 3, 49):
        c = load_course(name, seed=seed)
        assert c == load_course(name, seed=seed)
        assert c.name == name and c.seed == seed
        assert load_course(name, seed=np.int64(seed)) == c
    layouts = {load_course(name, seed=seed).patches for seed in range(20)}
    assert len(layouts) == 20
    if name != "uneven":
        assert load_course(name, seed=0).patches != load_course(name).patches


@pytest.mark.parametrize("name", sorted(SEEDED_COURSES))
@pytest.mark.parametrize("bad", [-1, True, 1.0, 2.5, "3"])
def test_bad_seed_names_the_field(name: str, bad: object) -> None:
    with pytest.raises(CourseFormatError) as info:
        load_course(name, seed=bad)
    assert info.value.field == f"{name}.seed"


def test_random_stepping_stones_feasible_and_in_range() -> None:
    dz_m = 0.02
    kinds: set[str] = set()
    lr_overlapping = lr_separated = 0
    for seed in SEEDS:
        c = load_course("stepping-stones", seed=seed, dz_m=dz_m)
        start, *stones, final = c.patches
        assert start == _platform(-1.0, 0.8), seed
        assert final.feet == "both" and final.x_max == 25.0 and final.y_min == -1.5, seed
        assert 3.1 - TOL_M <= final.x_min <= 3.95, seed
        assert 0.86 - TOL_M <= stones[0].x_min <= 0.92 + TOL_M, seed
        assert 3.05 - TOL_M <= stones[-1].x_max <= 3.9, seed
        for p in stones:
            kinds.add(p.feet)
            length_m, width_m = p.x_max - p.x_min, p.y_max - p.y_min
            assert length_m >= 0.18 - TOL_M, (seed, p)  # (a)
            assert p.z_top_m in (-dz_m, 0.0, dz_m), (seed, p)
            assert all(_whole_mm(v) for v in (p.x_min, p.x_max, p.y_min, p.y_max)), (seed, p)
            if p.feet == "both":
                assert 0.25 - TOL_M <= length_m <= 0.35 + TOL_M, (seed, p)
                assert width_m == pytest.approx(0.5) and abs(p.y_center_m) <= 0.03 + TOL_M
            else:
                assert 0.18 - TOL_M <= length_m <= 0.24 + TOL_M, (seed, p)
                assert 0.20 - TOL_M <= width_m <= 0.25 + TOL_M, (seed, p)
                inner = p.y_min if p.feet == "left" else -p.y_max
                assert -TOL_M <= inner <= 0.03 + TOL_M, (seed, p)
        for foot in ("left", "right"):  # (b), and no overlap within a lane
            holes = _lane_holes_m(c, foot)
            assert 0.06 - TOL_M <= min(holes) and max(holes) <= 0.22 + TOL_M, (seed, foot)
        for a, b in pairwise(stones):
            gap_m = b.x_min - a.x_max
            assert b.x_min >= a.x_min + 0.06 - TOL_M, (seed, a, b)
            if {a.feet, b.feet} == {"left", "right"}:
                assert gap_m <= 0.12 + TOL_M, (seed, a, b)  # (c)
                lr_overlapping += gap_m < 0.0
                lr_separated += gap_m > 0.0
            if gap_m > 0.0 or "both" in (a.feet, b.feet):
                assert 0.06 - TOL_M <= gap_m <= 0.12 + TOL_M, (seed, a, b)
        assert 0.06 - TOL_M <= final.x_min - stones[-1].x_max <= 0.12 + TOL_M, seed
    assert kinds == {"both", "left", "right"}
    assert lr_overlapping > 0 and lr_separated > 0


@pytest.mark.parametrize("seed", [None, *range(0, 50, 7)])
def test_stepping_stones_walkable_with_steps_of_10_to_28_cm(seed: int | None) -> None:
    c = load_course("stepping-stones", seed=seed)
    assert _footstep_sequence_exists(c, 0.10, 0.28, margin_m=0.03)
    if seed is None:  # the check can fail: a 0.20 m gap needs a step > 0.26 m
        gap = load_course("gap", width_m=0.2, x_m=1.5)
        assert _footstep_sequence_exists(gap, 0.10, 0.28, margin_m=0.03)
        assert not _footstep_sequence_exists(gap, 0.10, 0.25, margin_m=0.03)


def test_random_gap_in_range() -> None:
    counts = set()
    for seed in SEEDS:
        c = load_course("gap", seed=seed)
        assert all(p.feet == "both" and p.z_top_m == 0.0 for p in c.patches), seed
        assert c.patches[0].x_min == -1.0 and c.patches[-1].x_max == 25.0, seed
        holes = [(a.x_max, b.x_min) for a, b in pairwise(c.patches)]
        counts.add(len(holes))
        assert 1 <= len(holes) <= 3, seed
        assert 1.0 - TOL_M <= holes[0][0] <= 2.5 + TOL_M, seed
        for x0, x1 in holes:
            assert 0.05 - TOL_M <= x1 - x0 <= 0.20 + TOL_M, (seed, x0, x1)
            assert _whole_mm(x0) and _whole_mm(x1), (seed, x0, x1)
            assert c.ground_height_at(0.5 * (x0 + x1), 0.0) is None
        for (_, a), (b, _) in pairwise(holes):
            assert 0.6 - TOL_M <= b - a <= 1.2 + TOL_M, seed
    assert counts == {1, 2, 3}


@pytest.mark.parametrize("field", ["width_m", "x_m"])
def test_gap_seed_with_explicit_geometry_is_refused(field: str) -> None:
    with pytest.raises(CourseFormatError) as info:
        load_course("gap", seed=1, **{field: 0.1})
    assert info.value.field == f"gap.{field}"


def test_seed_json_round_trip(tmp_path: Path) -> None:
    c = load_course("stepping-stones", seed=7)
    assert c.to_dict()["seed"] == 7
    assert Course.from_dict(c.to_dict()) == c
    path = tmp_path / "course.json"
    path.write_text(json.dumps(c.to_dict()))
    assert json.loads(path.read_text())["seed"] == 7
    assert Course.from_json(path) == c and load_course(path) == c
    d = c.to_dict()
    d["seed"] = None
    assert Course.from_dict(d).seed is None
    assert Course.from_dict(d).patches == c.patches
    for bad in (-1, True, 1.5, "7"):
        d["seed"] = bad
        with pytest.raises(CourseFormatError) as info:
            Course.from_dict(d)
        assert info.value.field == "seed"
    with pytest.raises(CourseFormatError, match="seed"):
        Course("c", (_platform(-1.0, 1.0),), seed=-2)
