"""Snapshot strips (results/snapshots.py): poses of a run as silhouettes over one side view."""

from __future__ import annotations

import itertools
import os

os.environ.setdefault("MUJOCO_GL", "egl")

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.results.snapshots import MASK_THRESHOLD, snapshot_strip
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course

#: Base x shifts of the four poses [m], and the strip's x range: 4 m, centred on the poses,
#: at 1600 x 480 px the x range (not the robot's height) sets the camera distance, so world
#: x maps to column 1600 (x + 1.25) / 4 near the robot's plane.
SHIFTS_M = (0.0, 0.5, 1.0, 1.5)
X_RANGE_M = (-1.25, 2.75)
W, H = 1600, 480


def _column(x_m: float) -> float:
    return W * (x_m - X_RANGE_M[0]) / (X_RANGE_M[1] - X_RANGE_M[0])


@pytest.fixture
def sim(biped: RobotModel) -> Simulator:
    """biped2d standing at the start of the gap course (hole at x in [1.5, 1.7] m)."""
    return Simulator(biped, load_course("gap"))


def _poses(sim: Simulator, shifts_m: tuple[float, ...]) -> np.ndarray:
    """The initial pose with the base x (biped2d's ``root_x``, qpos[0]) shifted."""
    q0 = sim.data.qpos.copy()
    poses = np.repeat(q0[None], len(shifts_m), axis=0)
    poses[:, 0] += shifts_m
    return poses


def _read(path: Path) -> np.ndarray:
    with Image.open(path) as img:
        assert img.format == "PNG"
        return np.asarray(img.convert("RGB")).astype(np.int16)


@pytest.fixture
def strip_and_background(sim: Simulator, tmp_path: Path) -> tuple[np.ndarray, np.ndarray]:
    """The strip of the four poses, and the same view without the robot: the strip of one
    pose 50 m further on, of which nothing is in view."""
    images = []
    for name, shifts in (("strip", SHIFTS_M), ("empty", (50.0,))):
        out = tmp_path / f"{name}.png"
        snapshot_strip(sim, _poses(sim, shifts), out, width_px=W, height_px=H, x_range_m=X_RANGE_M)
        images.append(_read(out))
    return images[0], images[1]


def _robot_mask(strip: np.ndarray, background: np.ndarray) -> np.ndarray:
    return np.abs(strip - background).max(axis=2) > MASK_THRESHOLD


def test_strip_is_a_png_of_the_requested_size_written_atomically(
    sim: Simulator, tmp_path: Path
) -> None:
    out = tmp_path / "sub" / "fig6.png"
    assert snapshot_strip(sim, _poses(sim, SHIFTS_M), out, width_px=640, height_px=200) == out
    with Image.open(out) as img:
        assert (img.format, img.size, img.mode) == ("PNG", (640, 200), "RGB")
    assert sorted(p.name for p in out.parent.iterdir()) == ["fig6.png"]  # no .part left
    # wider than the scene's 1280 x 720 offscreen buffer: the buffer is enlarged for the
    # renderer only
    wide = snapshot_strip(sim, _poses(sim, SHIFTS_M), tmp_path / "w.png", width_px=1900)
    with Image.open(wide) as img:
        assert img.size == (1900, 400)
    assert (sim.model.vis.global_.offwidth, sim.model.vis.global_.offheight) == (1280, 720)


def test_each_pose_is_drawn_where_its_base_x_projects(
    strip_and_background: tuple[np.ndarray, np.ndarray],
) -> None:
    strip, background = strip_and_background
    assert strip.shape == background.shape == (H, W, 3)
    per_column = _robot_mask(strip, background).sum(axis=0)
    centres = [_column(s) for s in SHIFTS_M]  # 500, 700, 900, 1100 px
    for c in centres:  # the robot (0.1 m trunk, legs) around each pose's column
        assert per_column[round(c) - 40 : round(c) + 40].sum() > 2000, c
    for a, b in itertools.pairwise(centres):  # 0.25 m from either pose: nothing
        mid = round(0.5 * (a + b))
        assert per_column[mid - 10 : mid + 10].sum() == 0, mid
    assert per_column[: round(centres[0]) - 120].sum() == 0  # left of the first pose
    assert per_column[round(centres[-1]) + 120 :].sum() == 0  # right of the last one
    # four separate silhouettes, left to right
    cols = np.flatnonzero(per_column)
    bands = np.split(cols, np.flatnonzero(np.diff(cols) > 1) + 1)
    assert len(bands) == 4
    mids = [0.5 * (b[0] + b[-1]) for b in bands]
    assert np.all(np.abs(np.array(mids) - centres) < 40), mids


def test_later_poses_are_more_opaque_and_warmer(
    strip_and_background: tuple[np.ndarray, np.ndarray],
) -> None:
    strip, background = strip_and_background
    mask = _robot_mask(strip, background)
    contrast, warmth = [], []
    for s in SHIFTS_M:
        c = round(_column(s))
        band = np.zeros_like(mask)
        band[:, c - 60 : c + 60] = True
        pixels = mask & band
        contrast.append(np.abs(strip - background).max(axis=2)[pixels].mean())
        warmth.append((strip[..., 0] - strip[..., 2])[pixels].mean())  # red minus blue
    assert np.all(np.diff(contrast) > 0), contrast  # first faint, last opaque
    assert np.all(np.diff(warmth) > 0), warmth  # cool to warm


def test_the_simulator_state_is_unchanged(sim: Simulator, tmp_path: Path) -> None:
    sim.data.qvel[:] = np.linspace(-0.3, 0.3, sim.model.nv)
    qpos, qvel, t = sim.data.qpos.copy(), sim.data.qvel.copy(), sim.data.time
    com = sim.data.subtree_com.copy()
    snapshot_strip(sim, _poses(sim, SHIFTS_M), tmp_path / "s.png", title="biped2d, gap")
    np.testing.assert_array_equal(sim.data.qpos, qpos)
    np.testing.assert_array_equal(sim.data.qvel, qvel)
    np.testing.assert_array_equal(sim.data.subtree_com, com)
    assert sim.data.time == t


def test_the_title_is_drawn_top_left_only(sim: Simulator, tmp_path: Path) -> None:
    poses = _poses(sim, SHIFTS_M)
    plain = _read(snapshot_strip(sim, poses, tmp_path / "a.png", width_px=800, height_px=240))
    titled = _read(
        snapshot_strip(sim, poses, tmp_path / "b.png", width_px=800, height_px=240, title="gap")
    )
    changed = np.abs(plain - titled).max(axis=2) > 0
    rows, cols = np.nonzero(changed)
    assert rows.size > 0
    assert rows.max() < 40 and cols.max() < 100  # "gap" in an 8 px font from (8, 6)


@pytest.mark.parametrize(
    "bad",
    [
        "1-D",
        "nq + 1 columns",
        "no poses",
        "NaN",
        "inf",
    ],
)
def test_bad_qpos_is_refused(sim: Simulator, tmp_path: Path, bad: str) -> None:
    nq = sim.model.nq
    q = {
        "1-D": sim.data.qpos.copy(),
        "nq + 1 columns": np.zeros((4, nq + 1)),
        "no poses": np.zeros((0, nq)),
        "NaN": _poses(sim, SHIFTS_M),
        "inf": _poses(sim, SHIFTS_M),
    }[bad]
    if bad == "NaN":
        q[2, 3] = np.nan
    if bad == "inf":
        q[0, 0] = np.inf
    with pytest.raises(ConfigError, match=r"^qpos: got .*expected \(n, 7\) finite poses"):
        snapshot_strip(sim, q, tmp_path / "x.png")
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"x_range_m": (2.0, 1.0)}, "x_range_m"),
        ({"x_range_m": (0.0, float("nan"))}, "x_range_m"),
        ({"width_px": 0}, "width_px"),
        ({"height_px": 400.0}, "height_px"),
    ],
)
def test_bad_view_settings_are_refused(
    sim: Simulator, tmp_path: Path, kwargs: dict[str, object], field: str
) -> None:
    with pytest.raises(ConfigError, match=f"^{field}: got"):
        snapshot_strip(sim, _poses(sim, SHIFTS_M), tmp_path / "x.png", **kwargs)  # type: ignore[arg-type]
    assert not any(tmp_path.iterdir())
