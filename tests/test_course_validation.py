"""Tests of the course checks (issue 37, "nothing nonsensical accepted"): geometry
(overlap, a clear start, bounds) in :class:`Course` and safe reading of course files.

Every refusal is a :class:`CourseFormatError` whose message names the field and what was
expected; random inputs (Hypothesis) give a valid course or that error, never another
exception; inputs that once failed are replayed from ``tests/corpus/courses.json``.
"""

from __future__ import annotations

import copy
import json
import re
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.terrain import (
    BUILTIN_COURSES,
    SEEDED_COURSES,
    Course,
    Obstacle,
    Patch,
    load_course,
)
from gaitnet_mpc.terrain.checks import (
    MAX_ABS_XY_M,
    MAX_ABS_Z_M,
    MAX_OBSTACLE_HEIGHT_M,
    MAX_OBSTACLES,
    MAX_PATCHES,
    MAX_SIDE_M,
    MIN_SIDE_M,
    START_CLEARANCE_M,
    first_overlap,
)
from gaitnet_mpc.terrain.fields import EPS_M
from gaitnet_mpc.terrain.json_format import MAX_COURSE_FILE_BYTES, MAX_JSON_DEPTH, json_depth
from gaitnet_mpc.terrain.patch import footprints, top_patch_index, top_patch_indices

CORPUS = Path(__file__).resolve().parent / "corpus" / "courses.json"
START = {"x": [-1.0, 0.8], "y": [-1.5, 1.5], "z": 0.0}


def _course(*patches: dict[str, Any], obstacles: tuple[dict[str, Any], ...] = ()) -> dict[str, Any]:
    """A course dict: the start platform, then ``patches``."""
    return {"name": "t", "patches": [START, *patches], "obstacles": list(obstacles)}


def _refused(d: dict[str, Any]) -> CourseFormatError:
    with pytest.raises(CourseFormatError) as info:
        Course.from_dict(d)
    return info.value


def _write(tmp_path: Path, text: str, name: str = "c.json") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# ------------------------------------------------------------------------- geometry


def test_overlapping_patches_refused_naming_both() -> None:
    a = {"x": [1.0, 1.5], "y": [-0.5, 0.5], "z": 0.0}
    b = {"x": [2.0, 2.5], "y": [-0.5, 0.5], "z": 0.0}
    c = {"x": [1.4, 1.7], "y": [0.4, 0.9], "z": 0.05}  # overlaps a by 0.1 m x 0.1 m
    err = _refused(_course(a, b, c))
    assert err.field == "patches[3]"
    msg = str(err)
    assert msg.startswith("patches[3]: got {'x': [1.4, 1.7], 'y': [0.4, 0.9]}"), msg
    assert "no overlap with patches[1] (x [1.0, 1.5], y [-0.5, 0.5])" in msg, msg
    assert "touching edges are fine" in msg
    # the same course built in Python
    with pytest.raises(CourseFormatError, match=r"^patches\[1\]: .*no overlap with patches\[0\]"):
        Course("o", (Patch(-1.0, 1.0, -1.0, 1.0, 0.0), Patch(0.5, 0.8, -0.2, 0.2, 0.1)))


def test_touching_edges_and_corners_accepted() -> None:
    east = {"x": [0.8, 1.2], "y": [-0.5, 0.5], "z": 0.1}  # shares x = 0.8 with the start
    corner = {"x": [1.2, 1.6], "y": [0.5, 0.9], "z": 0.0}  # touches east at a corner
    north = {"x": [1.2, 1.6], "y": [-0.5, 0.5 - EPS_M / 2], "z": 0.0}  # overlap < EPS_M
    c = Course.from_dict(_course(east, corner, north))
    assert len(c.patches) == 4
    assert c.patch_at(0.8, 0.0) == 1  # shared edge: the higher top wins


def test_obstacle_on_start_platform_refused() -> None:
    box = {"x": [0.1, 0.2], "y": [-1.0, 1.0], "height": 0.03}
    err = _refused(_course(obstacles=(box,)))
    assert err.field == "obstacles[0]"
    msg = str(err)
    assert f"at least {START_CLEARANCE_M:g} m from the start point (0.0, 0.0)" in msg, msg
    assert "robot stands" in msg
    with pytest.raises(CourseFormatError, match=r"^obstacles\[0\]: .*from the start point"):
        Course("c", (Patch(-1.0, 1.0, -1.0, 1.0, 0.0),), (Obstacle(-0.1, 0.1, 0.2, 0.3, 0.05),))
    clear = {"x": [START_CLEARANCE_M + 0.01, 0.4], "y": [-1.0, 1.0], "height": 0.03}
    assert len(Course.from_dict(_course(obstacles=(clear,))).obstacles) == 1


def test_patch_top_1e9_refused() -> None:
    err = _refused(_course({"x": [1.0, 2.0], "y": [-0.5, 0.5], "z": 1e9}))
    assert err.field == "patches[1].z"
    assert str(err).startswith("patches[1].z: got 1000000000.0, expected ")
    assert f"|z| <= {MAX_ABS_Z_M:g} m" in str(err)


def test_patch_1e6_m_long_refused() -> None:
    err = _refused(_course({"x": [1.0, 1e6], "y": [-0.5, 0.5], "z": 0.0}))
    assert err.field == "patches[1].x"
    assert str(err).startswith("patches[1].x: got [1.0, 1000000.0], expected ")
    assert f"a side of at most {MAX_SIDE_M:g} m" in str(err)


@pytest.mark.parametrize(
    ("patch", "obstacle", "field", "expected"),
    [
        (
            {"x": [1.0, 1.005], "y": [0, 1], "z": 0},
            None,
            "patches[1].x",
            f"at least {MIN_SIDE_M:g}",
        ),
        ({"x": [1.0, 2.0], "y": [1e4, 1e4 + 1], "z": 0}, None, "patches[1].y", "within ±1000"),
        (None, {"x": [0.5, 0.6], "y": [0, 1], "height": 3.0}, "obstacles[0].height", "at most 2"),
        (None, {"x": [0.5, 0.6], "y": [0, 1e-4], "height": 0.1}, "obstacles[0].y", "at least 0.01"),
    ],
)
def test_other_bounds_refused(
    patch: dict[str, Any] | None, obstacle: dict[str, Any] | None, field: str, expected: str
) -> None:
    d = _course(*([patch] if patch else []), obstacles=(obstacle,) if obstacle else ())
    err = _refused(d)
    assert err.field == field and expected in str(err), str(err)


def test_too_many_patches_and_obstacles_refused() -> None:
    tile = {"x": [0.0, 0.1], "y": [0.0, 0.1], "z": 0.0}
    err = _refused({"patches": [tile] * (MAX_PATCHES + 1)})
    assert err.field == "patches" and f"at most {MAX_PATCHES} patches" in str(err)
    box = {"x": [0.5, 0.6], "y": [0.0, 0.1], "height": 0.1}
    err = _refused({"patches": [START], "obstacles": [box] * (MAX_OBSTACLES + 1)})
    assert err.field == "obstacles" and f"at most {MAX_OBSTACLES} obstacles" in str(err)


def _grid(nx: int, ny: int, tile_m: float = 0.1) -> list[Patch]:
    rng = np.random.default_rng(0)
    return [
        Patch(-1 + i * tile_m, -1 + (i + 1) * tile_m, j * tile_m - 5, (j + 1) * tile_m - 5, z)
        for i in range(nx)
        for j in range(ny)
        for z in [round(float(rng.uniform(-0.02, 0.02)), 4)]
    ]


def _strips(n: int) -> list[Patch]:
    """``n`` 10 m long strips 1 cm wide side by side (every x range overlaps every other)."""
    return [Patch(-1.0, 9.0, k * 0.01 - 0.5, (k + 1) * 0.01 - 0.5, 0.0) for k in range(n)]


@pytest.mark.parametrize("layout", ["grid", "strips"])
def test_many_patches_checked_fast(layout: str) -> None:
    patches = _grid(200, 100) if layout == "grid" else _strips(MAX_PATCHES)
    assert len(patches) == MAX_PATCHES
    t0 = time.perf_counter()
    c = Course("big", tuple(patches), start_xy=(-0.95, patches[50].y_center_m))
    assert time.perf_counter() - t0 < 5.0  # 0.03-0.2 s; a Python loop over all pairs: ~150 s
    assert len(c.patches) == MAX_PATCHES
    late = Patch(5.02, 5.07, -0.4, -0.36, 0.0)  # inside a tile / strip of the last third
    t0 = time.perf_counter()
    with pytest.raises(CourseFormatError) as info:
        Course("big", (*patches[:-1], late), start_xy=c.start_xy)
    assert time.perf_counter() - t0 < 5.0  # 0.9 s: the pass that finds the first pair
    assert info.value.field == f"patches[{MAX_PATCHES - 1}]"
    first = next(
        i
        for i, p in enumerate(patches)
        if min(p.x_max, late.x_max) - max(p.x_min, late.x_min) > EPS_M
        and min(p.y_max, late.y_max) - max(p.y_min, late.y_min) > EPS_M
    )
    assert f"no overlap with patches[{first}]" in str(info.value)


def test_many_obstacles_and_progress_on_stderr(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    patches = _grid(200, 100)
    boxes = [
        {
            "x": [p.x_min + 0.02, p.x_max - 0.02],
            "y": [p.y_min + 0.02, p.y_max - 0.02],
            "height": 0.03,
        }
        for p in patches[2000 : 2000 + MAX_OBSTACLES]
    ]
    d = {"patches": [p.to_dict() for p in patches], "obstacles": boxes, "start_xy": [-0.95, 0.0]}
    path = _write(tmp_path, json.dumps(d), "big.json")
    assert path.stat().st_size > 1024 * 1024
    t0 = time.perf_counter()
    c = load_course(path)
    assert time.perf_counter() - t0 < 10.0  # about 0.7 s
    assert (len(c.patches), len(c.obstacles)) == (MAX_PATCHES, MAX_OBSTACLES)
    err = capsys.readouterr().err
    assert re.search(r"^reading course big\.json \(\d\.\d MB\) \.\.\.$", err, re.MULTILINE), err
    assert f"... {MAX_PATCHES} patches, {MAX_OBSTACLES} obstacles checked" in err


def test_first_overlap_matches_brute_force() -> None:
    rng = np.random.default_rng(1)
    for _ in range(300):
        n = int(rng.integers(1, 25))
        lo = rng.integers(0, 8, size=(n, 2)) * 0.25  # a coarse grid: many shared edges
        size = rng.integers(1, 4, size=(n, 2)) * 0.25
        r = np.column_stack([lo[:, 0], lo[:, 0] + size[:, 0], lo[:, 1], lo[:, 1] + size[:, 1]])
        brute = [
            (i, j)
            for j in range(n)
            for i in range(j)
            if min(r[i, 1], r[j, 1]) - max(r[i, 0], r[j, 0]) > EPS_M
            and min(r[i, 3], r[j, 3]) - max(r[i, 2], r[j, 2]) > EPS_M
        ]
        assert first_overlap(r) == (brute[0] if brute else None), r


def test_vectorised_patch_lookup_matches_the_scalar_one() -> None:
    rng = np.random.default_rng(2)
    for course in (load_course("stepping-stones"), load_course("uneven", seed=4)):
        pts = np.column_stack([rng.uniform(-1.2, 7.0, 400), rng.uniform(-1.7, 1.7, 400)])
        n = min(40, len(course.patches))
        pts[:n, 0] = [p.x_max for p in course.patches[:n]]  # on edges
        got = top_patch_indices(course.patches, pts)
        want = [top_patch_index(course.patches, x, y) for x, y in pts]
        assert got.tolist() == [-1 if k is None else k for k in want]
    assert footprints([]).shape == (0, 4)


# ------------------------------------------------------------------------- built-in courses


def _well_inside_bounds(c: Course) -> None:
    for p in c.patches:
        assert MIN_SIDE_M * 10 <= min(p.x_max - p.x_min, p.y_max - p.y_min)
        assert max(p.x_max - p.x_min, p.y_max - p.y_min) <= MAX_SIDE_M / 10
        assert max(map(abs, (p.x_min, p.x_max, p.y_min, p.y_max))) <= MAX_ABS_XY_M / 10
        assert abs(p.z_top_m) <= MAX_ABS_Z_M / 10
    for ob in c.obstacles:
        assert ob.height_m <= MAX_OBSTACLE_HEIGHT_M / 10
    assert first_overlap(footprints(c.patches)) is None


@pytest.mark.parametrize("name", sorted(BUILTIN_COURSES))
def test_builtin_courses_pass(name: str) -> None:
    c = load_course(name)
    _well_inside_bounds(c)
    assert Course.from_dict(c.to_dict()) == c


@pytest.mark.parametrize("name", sorted(SEEDED_COURSES))
def test_seeded_courses_pass_for_200_seeds(name: str) -> None:
    for seed in range(200):
        c = load_course(name, seed=seed)  # the constructor runs every check
        _well_inside_bounds(c)
        assert Course.from_dict(c.to_dict()) == c, seed


# ------------------------------------------------------------------------- reading files


def test_duplicate_keys_refused(tmp_path: Path) -> None:
    text = (
        '{"name": "d", "patches": [{"x": [-1, 1], "y": [-1, 1], "z": 0},'
        ' {"x": [2, 3], "y": [-1, 1], "z": 0.1, "z": 0.2}]}'
    )
    with pytest.raises(CourseFormatError) as info:
        load_course(_write(tmp_path, text))
    assert info.value.field == "patches[1].z"
    msg = str(info.value)
    assert msg.startswith("patches[1].z: got [0.1, 0.2], expected the key 'z' once in patches[1]")
    text = '{"name": "a", "patches": [{"x": [-1, 1], "y": [-1, 1], "z": 0}], "name": "b"}'
    with pytest.raises(
        CourseFormatError, match=r"^name: got \['a', 'b'\], expected the key 'name'"
    ):
        load_course(_write(tmp_path, text))


def test_deep_nesting_refused_before_parsing(tmp_path: Path) -> None:
    path = _write(tmp_path, "[" * 100_000 + "]" * 100_000)
    with pytest.raises(CourseFormatError) as info:
        load_course(path)
    assert info.value.field == "course"
    assert f"expected JSON nested at most {MAX_JSON_DEPTH} deep" in str(info.value)
    assert "nested 100000 deep" in str(info.value)
    assert json_depth('{"a": "[[[{{{", "b": [[1], {"c": "\\"]]"}]}') == 3
    assert json_depth("3.5") == 0


def test_deep_value_in_a_dict_is_a_named_error() -> None:
    deep: Any = 0
    for _ in range(5000):
        deep = [deep]
    err = _refused({"patches": [START, {"x": deep, "y": [0, 1], "z": 0}]})
    assert err.field in ("course", "patches[1].x")


def test_size_limit_checked_before_reading(tmp_path: Path) -> None:
    path = tmp_path / "huge.json"
    with path.open("wb") as f:  # a sparse 4 GiB file: reading it would take long
        f.truncate(4 * 2**30)
    t0 = time.perf_counter()
    with pytest.raises(CourseFormatError) as info:
        load_course(path)
    assert time.perf_counter() - t0 < 0.5
    assert info.value.field == "course"
    assert f"{4 * 2**30} bytes" in str(info.value)
    assert f"expected a course file of at most {MAX_COURSE_FILE_BYTES} bytes" in str(info.value)
    just_over = tmp_path / "over.json"
    just_over.write_bytes(b" " * MAX_COURSE_FILE_BYTES + b"1")
    with pytest.raises(CourseFormatError, match="at most 8388608 bytes"):
        load_course(just_over)


def test_big_numbers_are_named_errors(tmp_path: Path) -> None:
    err = _refused(_course({"x": [1.0, 2.0], "y": [0, 1], "z": 10**400}))
    assert err.field == "patches[1].z" and "a finite number" in str(err)
    text = json.dumps(_course()).replace('"z": 0.0', '"z": 1' + "0" * 5000)
    with pytest.raises(CourseFormatError, match="valid JSON numbers"):
        load_course(_write(tmp_path, text))


# ------------------------------------------------------------------------- random inputs

_NUMBERS = st.one_of(
    st.floats(-3.0, 3.0),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-5, 5),
    st.sampled_from([0.0, 1e9, -1e9, 1e6, 1e-12, 5.000001, 10**400, True]),
)
_JSON = st.recursive(
    st.none() | st.booleans() | _NUMBERS | st.text(max_size=4),
    lambda kids: (
        st.lists(kids, max_size=3) | st.dictionaries(st.text(max_size=3), kids, max_size=3)
    ),
    max_leaves=6,
)


_INTERVAL = st.tuples(st.floats(-2.0, 4.0), st.floats(0.001, 2.0)).map(
    lambda t: [t[0], t[0] + t[1]]
)
_PATCH = st.fixed_dictionaries(
    {"x": _INTERVAL, "y": _INTERVAL, "z": st.floats(-0.1, 0.1)},
    optional={"feet": st.sampled_from(["both", "left", "right"])},
)
_OBSTACLE = st.fixed_dictionaries({"x": _INTERVAL, "y": _INTERVAL, "height": st.floats(0.01, 0.1)})
#: Where a corruption goes: a top-level key, or (list, item, key) of a patch or obstacle.
_TARGETS = st.one_of(
    st.sampled_from(["name", "patches", "obstacles", "start_xy", "seed", "other"]).map(
        lambda k: (k,)
    ),
    st.tuples(st.just("patches"), st.integers(0, 6), st.sampled_from(["x", "y", "z", "feet", "q"])),
    st.tuples(st.just("obstacles"), st.integers(0, 3), st.sampled_from(["x", "y", "height", "q"])),
    st.tuples(st.sampled_from(["patches", "obstacles"]), st.integers(0, 6)),
)


@st.composite
def _courses(draw: st.DrawFn) -> dict[str, Any]:
    """A course dict with random geometry (overlaps, holes, obstacles anywhere), then 0-3
    corruptions: a value replaced by random JSON (nesting, types, nan/inf/huge numbers)
    or a key deleted."""
    d: dict[str, Any] = {"patches": [copy.deepcopy(START), *draw(st.lists(_PATCH, max_size=6))]}
    for key, value in (
        ("name", st.text(min_size=1, max_size=3)),
        ("obstacles", st.lists(_OBSTACLE, max_size=3)),
        ("start_xy", st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)).map(list)),
        ("seed", st.integers(0, 10**30)),
    ):
        if draw(st.booleans()):
            d[key] = draw(value)
    for target in draw(st.lists(_TARGETS, max_size=3)):
        if len(target) == 1:
            parent, key = d, target[0]
        else:
            items = d.get(target[0])
            if not isinstance(items, list) or not items:
                continue
            i = target[1] % len(items)
            if len(target) == 2:
                items[i] = draw(_JSON)
                continue
            parent, key = items[i], target[2]
            if not isinstance(parent, dict):
                continue
        if draw(st.booleans()):
            parent[key] = draw(_JSON)
        else:
            parent.pop(key, None)
    return d


_COURSE = _courses()


def _mutate(text: str, how: str, k: int) -> str:
    if how == "truncate":
        return text[: k % (len(text) + 1)]
    if how == "wrap":
        return "[" * (k % 40) + text + "]" * (k % 40)
    if how == "repeat key":
        return text.replace("{", '{"patches": [], ', 1)
    if how == "insert":
        i = k % (len(text) + 1)
        return text[:i] + '[{"],:'[k % 6] + text[i:]
    return text


def _outcome_ok(load: Any) -> None:
    try:
        assert isinstance(load(), Course)
    except CourseFormatError:
        pass


@settings(max_examples=150, deadline=None)
@given(_COURSE)
def test_random_dicts_give_a_course_or_a_named_error(d: dict[str, Any]) -> None:
    _outcome_ok(lambda: Course.from_dict(d))


@settings(max_examples=150, deadline=None)
@given(
    _COURSE | _JSON,
    st.sampled_from(["none", "none", "truncate", "wrap", "repeat key", "insert"]),
    st.integers(0, 10**6),
)
def test_random_files_give_a_course_or_a_named_error(d: Any, how: str, k: int) -> None:
    text = _mutate(json.dumps(d), how, k)
    with tempfile.TemporaryDirectory() as tmp:
        path = _write(Path(tmp), text)
        _outcome_ok(lambda: load_course(path))


# ------------------------------------------------------------------------- regression corpus


def _corpus() -> list[dict[str, Any]]:
    return list(json.loads(CORPUS.read_text(encoding="utf-8")))


@pytest.mark.parametrize("case", _corpus(), ids=lambda case: str(case["id"]))
def test_corpus_replay(case: dict[str, Any], tmp_path: Path) -> None:
    """Each case: ``text`` is read as a course file (``"as": "file"``) or parsed by Python's
    ``json`` and given to :meth:`Course.from_dict` (``"as": "dict"``); ``field`` is the
    field the error must name, or null for a valid course."""
    text = case["text"] * case.get("repeat", 1)
    try:
        if case["as"] == "file":
            course = load_course(_write(tmp_path, text))
        else:
            course = Course.from_dict(json.loads(text))
    except CourseFormatError as err:
        assert case["field"] is not None, f"refused a valid course: {err}"
        assert err.field == case["field"], str(err)
        assert case.get("expected", "") in str(err), str(err)
    else:
        assert case["field"] is None, f"accepted: {course}"
