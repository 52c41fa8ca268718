"""Snapshot strip of one run (paper Fig. 6): several poses of the robot over one run, drawn
over one side view of the terrain, so that one sees the robot step over the gaps.

``snapshot_strip(sim, qpos, path)`` renders with MuJoCo's offscreen renderer and one fixed
free camera that looks from -y toward +y (azimuth 90 deg, elevation -8 deg):

1. a background frame, with the robot moved :data:`HIDE_X_M` along world x (out of view);
2. one frame per pose (the rows of ``qpos``, in time order);

and composites them: the pixels of a pose's frame that differ from the background by more
than :data:`MASK_THRESHOLD` (of 255) in some colour channel are the robot's (the
background-difference mask: the scene has no shadows or reflections, so nothing else
changes). Those pixels are painted over the background in time order, tinted along a ramp
from :data:`TINT_FIRST_RGB` (first pose) to :data:`TINT_LAST_RGB` (last pose) and with an
opacity growing from :data:`FIRST_ALPHA` to 1, so the sequence reads left to right: early
poses faint and cool, the last one opaque and warm, later poses over earlier ones.

Camera: the lookat point is at the middle of the shown x range, at the poses' mean trunk y,
and halfway up the vertical span of the robot's geoms over all poses (with
:data:`GROUND_MARGIN_M` of terrain below and :data:`TOP_MARGIN_M` above). A perspective
camera with vertical field of view ``fovy`` (``model.vis.global_.fovy``) shows, at distance
``d`` along its axis, a width ``2 d tan(fovy / 2) W / H``; ``d`` is chosen so that this is
the x range, unless the robot's height would not fit, in which case ``d`` grows until it
fits (the strip then shows more than the x range, centred on it), and it is kept
:data:`NEAR_CLEARANCE_M` beyond the near clipping plane.

Rendering uses its own ``MjData``, so the simulator's state (``sim.data``) is not touched;
the model's offscreen buffer size is enlarged only while the renderer is created. The PNG is
written atomically (Pillow, which matplotlib already depends on).
"""

from __future__ import annotations

import io
import math
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.results.io import write_bytes_atomic
from gaitnet_mpc.sim.simulator import Simulator

#: Camera direction [deg]: azimuth 90 looks along +y (from -y), slightly from above.
CAMERA_AZIMUTH_DEG = 90.0
CAMERA_ELEVATION_DEG = -8.0
#: Padding of the default x range on each side of the poses' base x span [m].
X_PAD_M = 0.4
#: Terrain shown below the lowest robot geom, and room above the highest one [m] (more
#: above: looking down, the camera sees less above its lookat point than below it).
GROUND_MARGIN_M = 0.1
TOP_MARGIN_M = 0.15
#: Least distance of the lookat point beyond the camera's near clipping plane [m].
NEAR_CLEARANCE_M = 0.5
#: How far the robot is moved along x for the background frame [m].
HIDE_X_M = 1000.0
#: A pixel belongs to the robot when one channel differs from the background by more.
MASK_THRESHOLD = 24
#: Opacity of the first pose (the last one is opaque).
FIRST_ALPHA = 0.3
#: Weight of the tint colour in a painted pixel (the rest is the rendered colour).
TINT_WEIGHT = 0.4
#: Tint colours of the first and the last pose (RGB, 0-255); the others in between.
TINT_FIRST_RGB = (60, 120, 230)
TINT_LAST_RGB = (225, 85, 35)
#: Accepted image sizes [px].
MIN_PX, MAX_PX = 16, 8192


def snapshot_strip(
    sim: Simulator,
    qpos: np.ndarray,
    path: Path,
    *,
    width_px: int = 1600,
    height_px: int = 400,
    x_range_m: tuple[float, float] | None = None,
    title: str | None = None,
) -> Path:
    """Render the poses ``qpos`` (n, nq) of ``sim``'s robot, in time order, as silhouettes
    over one side view of the terrain and write the PNG (``width_px`` x ``height_px``) to
    ``path``; see the module docstring.

    Args:
        sim: the simulator whose model (robot and course) is drawn; its state is unchanged.
        qpos: MuJoCo ``qpos`` of ``sim.model``, one finite pose per row, n >= 1.
        path: the PNG to write (atomically; its folder is created).
        x_range_m: world x span ``(lo, hi)`` to show [m]; None: the span of the poses'
            trunk x padded by :data:`X_PAD_M` on each side.
        title: a line of text drawn in the top-left corner; None: none.

    Returns:
        ``path``.

    Raises:
        ConfigError: a bad ``qpos`` (shape or non-finite values), image size or x range.
    """
    model = sim.model
    poses = _checked_poses(qpos, int(model.nq))
    for name, value in (("width_px", width_px), ("height_px", height_px)):
        is_int = isinstance(value, int | np.integer) and not isinstance(value, bool)
        if not (is_int and MIN_PX <= value <= MAX_PX):
            raise ConfigError(name, value, f"an integer in [{MIN_PX}, {MAX_PX}] px")
    width, height = int(width_px), int(height_px)
    data = mujoco.MjData(model)  # the simulator's own data stays as it is
    trunk = model.body(sim.robot.spec.trunk_body).id
    base_x = _base_x_adr(model, trunk)
    trunk_x, trunk_y, z_lo, z_hi = _pose_extent(model, data, poses, trunk)
    if x_range_m is None:
        x_lo, x_hi = float(trunk_x.min()) - X_PAD_M, float(trunk_x.max()) + X_PAD_M
    else:
        x_lo, x_hi = _checked_range(x_range_m)
    camera = _side_camera(
        model,
        (x_lo, x_hi),
        float(trunk_y.mean()),
        (z_lo - GROUND_MARGIN_M, z_hi + TOP_MARGIN_M),
        width / height,
    )
    hidden = poses[-1].copy()
    hidden[base_x] = HIDE_X_M
    with _renderer(model, height, width) as renderer:
        background = _render(renderer, model, data, hidden, camera)
        image = background.astype(np.float64)
        n = poses.shape[0]
        for i, pose in enumerate(poses):
            frame = _render(renderer, model, data, pose, camera)
            _paint(image, background, frame, 1.0 if n == 1 else i / (n - 1))
    rgb = np.clip(np.rint(image), 0, 255).astype(np.uint8)
    return _write_png(rgb, Path(path), title)


def _checked_poses(qpos: Any, nq: int) -> np.ndarray:
    """``qpos`` as a float array (n, nq), n >= 1, all finite; else :class:`ConfigError`."""
    expected = f"(n, {nq}) finite poses with n >= 1"
    try:
        poses = np.array(qpos, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError("qpos", qpos, expected) from None
    if poses.ndim != 2 or poses.shape[0] < 1 or poses.shape[1] != nq:
        raise ConfigError("qpos", poses.shape, expected)
    bad = np.flatnonzero(~np.isfinite(poses).all(axis=1))
    if bad.size:
        raise ConfigError("qpos", f"non-finite values in rows {bad.tolist()}", expected)
    return poses


def _checked_range(x_range_m: Any) -> tuple[float, float]:
    """``x_range_m`` as two finite floats ``lo < hi``; else :class:`ConfigError`."""
    expected = "two finite x coordinates (lo, hi) with lo < hi [m]"
    try:
        lo, hi = (float(v) for v in x_range_m)
    except (TypeError, ValueError):
        raise ConfigError("x_range_m", x_range_m, expected) from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ConfigError("x_range_m", x_range_m, expected)
    return lo, hi


def _base_x_adr(model: Any, trunk: int) -> int:
    """The ``qpos`` address of the trunk's world x: its free joint's (humanoid3d) or its
    slide joint along x (biped2d's ``root_x``)."""
    for j in np.flatnonzero(model.jnt_bodyid == trunk):
        kind = int(model.jnt_type[j])
        along_x = np.allclose(model.jnt_axis[j], (1.0, 0.0, 0.0))
        if kind == mujoco.mjtJoint.mjJNT_FREE or (kind == mujoco.mjtJoint.mjJNT_SLIDE and along_x):
            return int(model.jnt_qposadr[j])
    raise ConfigError(
        "sim.robot", model.body(trunk).name, "a trunk with a free joint or an x slide joint"
    )


def _pose_extent(
    model: Any, data: Any, poses: np.ndarray, trunk: int
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Trunk world x and y (n,) of each pose, and the lowest and highest world z of the
    robot's geoms (their axis-aligned boxes) over all poses [m]."""
    robot_geoms = np.flatnonzero(model.geom_bodyid != 0)
    centre_local = model.geom_aabb[robot_geoms, :3]
    half_local = model.geom_aabb[robot_geoms, 3:]
    xs, ys, lo, hi = [], [], np.inf, -np.inf
    for pose in poses:
        data.qpos[:] = pose
        mujoco.mj_kinematics(model, data)
        xs.append(float(data.xpos[trunk, 0]))
        ys.append(float(data.xpos[trunk, 1]))
        rot_z = data.geom_xmat[robot_geoms].reshape(-1, 3, 3)[:, 2, :]  # rows z of R
        centre_z = data.geom_xpos[robot_geoms, 2] + np.sum(rot_z * centre_local, axis=1)
        half_z = np.sum(np.abs(rot_z) * half_local, axis=1)
        lo = min(lo, float((centre_z - half_z).min()))
        hi = max(hi, float((centre_z + half_z).max()))
    return np.array(xs), np.array(ys), lo, hi


def _side_camera(
    model: Any,
    x_range_m: tuple[float, float],
    y_m: float,
    z_range_m: tuple[float, float],
    aspect: float,
) -> Any:
    """A free camera from -y looking at the middle of ``x_range_m`` x ``z_range_m`` (at
    ``y_m``), as close as lets it show both spans (see the module docstring)."""
    tan_half = math.tan(math.radians(float(model.vis.global_.fovy)) / 2.0)
    elevation = math.radians(CAMERA_ELEVATION_DEG)
    d_width = (x_range_m[1] - x_range_m[0]) / (2.0 * tan_half * aspect)
    d_height = (z_range_m[1] - z_range_m[0]) * math.cos(elevation) / (2.0 * tan_half)
    d_near = float(model.vis.map.znear * model.stat.extent) + NEAR_CLEARANCE_M
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FREE
    camera.lookat[:] = (0.5 * sum(x_range_m), y_m, 0.5 * sum(z_range_m))
    camera.azimuth = CAMERA_AZIMUTH_DEG
    camera.elevation = CAMERA_ELEVATION_DEG
    camera.distance = max(d_width, d_height, d_near)
    return camera


@contextmanager
def _renderer(model: Any, height: int, width: int) -> Iterator[Any]:
    """A ``mujoco.Renderer`` of ``width`` x ``height``; the model's offscreen buffer is
    enlarged while it is made (the scene XML asks for 1280 x 720), then set back."""
    vis = model.vis.global_
    old = (int(vis.offwidth), int(vis.offheight))
    vis.offwidth, vis.offheight = max(old[0], width), max(old[1], height)
    try:
        renderer = mujoco.Renderer(model, height, width)
    finally:
        vis.offwidth, vis.offheight = old
    try:
        yield renderer
    finally:
        renderer.close()


def _render(renderer: Any, model: Any, data: Any, pose: np.ndarray, camera: Any) -> np.ndarray:
    """The frame (H, W, 3) uint8 of the scene with the robot in ``pose``."""
    data.qpos[:] = pose
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)
    renderer.update_scene(data, camera=camera)
    return np.asarray(renderer.render()).copy()


def _paint(image: np.ndarray, background: np.ndarray, frame: np.ndarray, w: float) -> None:
    """Paint the robot pixels of ``frame`` (those differing from ``background``) over
    ``image`` (float, H x W x 3), tinted and as opaque as pose time ``w`` in [0, 1] says."""
    diff = np.abs(frame.astype(np.int16) - background.astype(np.int16)).max(axis=2)
    mask = diff > MASK_THRESHOLD
    if not mask.any():
        return
    tint = (1.0 - w) * np.array(TINT_FIRST_RGB, float) + w * np.array(TINT_LAST_RGB, float)
    colour = (1.0 - TINT_WEIGHT) * frame[mask].astype(np.float64) + TINT_WEIGHT * tint
    alpha = FIRST_ALPHA + (1.0 - FIRST_ALPHA) * w
    image[mask] = (1.0 - alpha) * image[mask] + alpha * colour


def _write_png(rgb: np.ndarray, path: Path, title: str | None) -> Path:
    """Write ``rgb`` (H, W, 3) uint8 as a PNG, with ``title`` top-left in white on a dark
    box, through a temporary file and an atomic rename."""
    from PIL import Image, ImageDraw

    img = Image.fromarray(rgb)
    if title:
        draw = ImageDraw.Draw(img)
        box = draw.multiline_textbbox((8, 6), title)
        draw.rectangle((box[0] - 4, box[1] - 3, box[2] + 4, box[3] + 3), fill=(0, 0, 0))
        draw.multiline_text((8, 6), title, fill=(255, 255, 255))
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    write_bytes_atomic(path, buf.getvalue())
    return path
