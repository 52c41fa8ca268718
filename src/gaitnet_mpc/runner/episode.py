"""Run one closed-loop episode and summarise it (``summary.json``, logs, course, video).

The run folder that :func:`run_episode` writes (plots are made afterwards from these files
by :mod:`gaitnet_mpc.results.plots`):

* ``summary.json``: episode outcome and statistics (see
  :meth:`~gaitnet_mpc.runner.loop.EpisodeLoop.summary`), without the
  wall-clock figures, which go to ``timing.json``
  (:func:`~gaitnet_mpc.results.rundir.split_timing`); the returned summary has both.
* ``log.csv``: one row per control tick (:class:`EpisodeLog`).
* ``mpc_log.csv``: one row per MPC solve (:class:`MPCLog`); only for MPC controllers.
* ``events.csv``: touchdowns, lift-offs, slips, pivots and scuffs of the feet
  (:mod:`gaitnet_mpc.results.events`).
* ``course.json``: the course in the JSON course format (for the top-view plot).
* ``video.mp4``: offscreen rendering, unless disabled (:class:`VideoConfig`: an oblique
  follow camera by default, ``camera="side"`` for the robot model's side view; a text
  overlay of time, commanded vx and the current step's MPC dt).

How the episode ended (``summary.json``): ``fell`` when the simulator's fall detector fired
(CoM height below ``fall_com_height_ratio`` of its start height, trunk tilt above
``fall_tilt_rad``, a non-foot body on the terrain, or divergence). A run that reaches its
duration without a fall may still end badly, so ``ended_upright`` applies the same two
measures at *half* the fall margins (:func:`ended_upright`): tilt at most
``fall_tilt_rad / 2`` (0.5 rad) and CoM no more than half the way down to the fall
height (at most 25 % below its start height). ``outcome`` is ``"interrupted"``,
``"fell"``, ``"not_upright"`` or ``"ok"``, in that order of precedence.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.runner.loop import EpisodeLoop
from gaitnet_mpc.runner.loop import ended_upright as ended_upright  # re-exported
from gaitnet_mpc.sim.simulator import Simulator

#: Video cameras: ``oblique`` (a higher follow camera, behind and to the side, that shows
#: the feet on the terrain) and ``side`` (the robot model's ``track`` camera, level).
CAMERAS = ("oblique", "side")


@dataclass(frozen=True)
class VideoConfig:
    """Offscreen rendering settings (``MUJOCO_GL=egl`` works without a GPU).

    Attributes:
        fps: frames per second of simulated time [1/s].
        width_px, height_px: frame size [px].
        camera: one of :data:`CAMERAS`.
        overlay: draw time, commanded vx and the current step's MPC dt onto each frame.
        oblique_distance_m: distance of the oblique camera from the trunk [m].
        oblique_elevation_deg: its elevation (negative: looking down) [deg].
        oblique_azimuth_deg: its azimuth about world z (90: from -y, the side) [deg].
    """

    fps: int = 30
    width_px: int = 640
    height_px: int = 480
    camera: str = "oblique"
    overlay: bool = True
    oblique_distance_m: float = 2.6
    oblique_elevation_deg: float = -32.0
    oblique_azimuth_deg: float = 125.0

    def __post_init__(self) -> None:
        if self.camera not in CAMERAS:
            raise ConfigError("--camera", self.camera, f"one of {list(CAMERAS)}")
        if not (self.fps > 0 and self.width_px >= 64 and self.height_px >= 64):
            raise ConfigError(
                "video", (self.fps, self.width_px, self.height_px), "fps > 0, frames >= 64 px"
            )


def _video_camera(sim: Simulator, video: VideoConfig) -> Any:
    """The camera to render with: the model's ``track`` camera name (side) or a free
    ``MjvCamera`` tracking the trunk from above and behind (oblique)."""
    import mujoco

    if video.camera == "side":
        return "track"
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
    cam.trackbodyid = sim.model.body(sim.robot.spec.trunk_body).id
    cam.distance = video.oblique_distance_m
    cam.elevation = video.oblique_elevation_deg
    cam.azimuth = video.oblique_azimuth_deg
    return cam


def overlay_text(frame: np.ndarray, lines: list[str]) -> np.ndarray:
    """``frame`` (H, W, 3) uint8 with ``lines`` drawn top-left in white on a dark box
    (Pillow, which matplotlib already depends on)."""
    from PIL import Image, ImageDraw

    img = Image.fromarray(frame)
    draw = ImageDraw.Draw(img)
    text = "\n".join(lines)
    box = draw.multiline_textbbox((8, 6), text)
    draw.rectangle((box[0] - 4, box[1] - 3, box[2] + 4, box[3] + 3), fill=(0, 0, 0))
    draw.multiline_text((8, 6), text, fill=(255, 255, 255))
    return np.asarray(img)


def _overlay_lines(t_s: float, command: Command, step_dt_s: float) -> list[str]:
    """The overlay's text: time, commanded vx and the current step's MPC dt."""
    dt = f"{step_dt_s * 1e3:.0f} ms" if np.isfinite(step_dt_s) else "-"
    return [f"t = {t_s:6.2f} s", f"cmd vx = {command.vx_mps:+.2f} m/s", f"step dt = {dt}"]


#: Marker colours (RGBA) of planned footholds, as the course colours: left blue, right red.
_FOOT_RGBA = {"left": (0.15, 0.3, 0.9, 0.9), "right": (0.9, 0.15, 0.15, 0.9)}


def _draw_footholds(scene: Any, footholds: list[tuple[str, np.ndarray]], height_m: float) -> None:
    """Add a flat disc (radius 3 cm) on the ground under each planned foothold (foot
    centre ``height_m`` above the sole) to the rendered scene."""
    import mujoco

    for foot, pos in footholds:
        if scene.ngeom >= scene.maxgeom:
            return
        mujoco.mjv_initGeom(
            scene.geoms[scene.ngeom],
            mujoco.mjtGeom.mjGEOM_CYLINDER,
            np.array([0.03, 0.002, 0.0]),
            np.asarray(pos, dtype=float) - np.array([0.0, 0.0, height_m - 0.002]),
            np.eye(3).ravel(),
            np.array(_FOOT_RGBA[foot], dtype=np.float32),
        )
        scene.ngeom += 1


def run_episode(
    sim: Simulator,
    controller: Controller,
    command: Command,
    duration_s: float,
    out_dir: Path | None = None,
    video: VideoConfig | None = None,
    progress: bool = True,
    meta: dict[str, Any] | None = None,
    viewer: Any | None = None,
    on_step: Callable[[Simulator], None] | None = None,
) -> dict[str, Any]:
    """Simulate until ``duration_s`` or a fall; return (and write) the summary.

    Ctrl-C (or closing ``viewer``) stops the episode early; what was simulated is still
    summarised and written, with ``"interrupted": true``.

    Args:
        viewer: an open ``mujoco.viewer.launch_passive`` handle on ``sim.model`` /
            ``sim.data``, synchronised at 60 Hz of simulated time and paced to real time
            (it never runs faster than real time; it may run slower). None: no viewer.
        on_step: called with ``sim`` after every physics step (e.g. to keep poses for a
            snapshot strip); it must not change the simulation.
    """
    loop = EpisodeLoop(sim, controller, command, duration_s)
    renderer, writer, frame_dt, next_frame_t = None, None, np.inf, 0.0
    overlay = False
    tmp_video = None
    if video is not None and out_dir is not None:
        import imageio.v2 as imageio
        import mujoco

        renderer = mujoco.Renderer(sim.model, video.height_px, video.width_px)
        tmp_video = Path(out_dir) / "video.part.mp4"
        tmp_video.parent.mkdir(parents=True, exist_ok=True)
        writer = imageio.get_writer(
            tmp_video, fps=video.fps, codec="libx264", quality=7, macro_block_size=8
        )
        frame_dt = 1.0 / video.fps
        foot_r = sim.robot.spec.foot_contact_radius_m
        camera = _video_camera(sim, video)
        overlay = video.overlay
    bar = _progress_bar(duration_s) if progress else None
    viewer_dt, next_view_t = 1.0 / 60.0, 0.0
    t_wall0 = time.perf_counter()
    render_wall_s = 0.0
    interrupted = False
    try:
        while not loop.done:
            loop.tick()
            if on_step is not None:
                on_step(sim)
            if renderer is not None and sim.time_s >= next_frame_t - 1e-9:
                assert writer is not None  # made together with the renderer
                t_r = time.perf_counter()
                renderer.update_scene(sim.data, camera=camera)
                _draw_footholds(renderer.scene, controller.planned_footholds(), foot_r)
                frame = renderer.render()
                if overlay:
                    lines = _overlay_lines(sim.time_s, command, loop.probe.step_dt())
                    frame = overlay_text(frame, lines)
                writer.append_data(frame)
                render_wall_s += time.perf_counter() - t_r
                next_frame_t += frame_dt
            if viewer is not None and sim.time_s >= next_view_t - 1e-9:
                if not viewer.is_running():
                    interrupted = True
                    break
                viewer.sync()
                ahead_s = sim.time_s - (time.perf_counter() - t_wall0)
                if ahead_s > 0:
                    time.sleep(ahead_s)
                next_view_t += viewer_dt
            if bar is not None and loop.ticks % 100 == 0:
                _update_bar(bar, sim.time_s, time.perf_counter() - t_wall0)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        if bar is not None:
            bar.close()
        if writer is not None:
            writer.close()
        if renderer is not None:
            renderer.close()
    wall_s = time.perf_counter() - t_wall0
    summary = loop.summary(wall_s, render_wall_s, interrupted)
    if video is not None:
        summary["video"] = {"camera": video.camera, "overlay": video.overlay, "fps": video.fps}
    if meta:
        summary = {**meta, **summary}
    if out_dir is not None:
        loop.write_files(Path(out_dir), summary, tmp_video)
    return summary


def _progress_bar(duration_s: float) -> Any:
    """A tqdm bar counting simulated seconds, with the real-time factor as postfix."""
    from tqdm import tqdm

    return tqdm(
        total=round(duration_s, 3),
        unit="sim-s",
        leave=False,
        mininterval=0.5,
        bar_format="{l_bar}{bar}| t = {n:.2f}/{total:.2f} sim-s [{elapsed}<{remaining}{postfix}]",
        postfix="RTF -",
    )


def _update_bar(bar: Any, sim_s: float, wall_s: float) -> None:
    """Move the bar to ``sim_s`` simulated seconds and show the real-time factor."""
    bar.set_postfix_str(f"RTF {sim_s / max(wall_s, 1e-9):.2f}", refresh=False)
    bar.update(round(sim_s, 3) - bar.n)
