"""Run one closed-loop episode and summarise it (``summary.json``, log, video)."""

from __future__ import annotations

import io
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.sim.io import write_atomic, write_json_atomic
from gaitnet_mpc.sim.simulator import Simulator


@dataclass(frozen=True)
class Command:
    """User velocity command in the world frame."""

    vx_mps: float = 0.0
    vy_mps: float = 0.0
    yaw_rate_radps: float = 0.0

    def __post_init__(self) -> None:
        for name, value, bound in (
            ("--vx", self.vx_mps, 1.5),
            ("--vy", self.vy_mps, 0.5),
            ("--yaw-rate", self.yaw_rate_radps, 1.5),
        ):
            if not (np.isfinite(value) and abs(value) <= bound):
                raise ConfigError(name, value, f"a finite value in [-{bound}, {bound}]")

    def to_dict(self) -> dict[str, float]:
        return {"vx_mps": self.vx_mps, "vy_mps": self.vy_mps, "yaw_rate_radps": self.yaw_rate_radps}


@dataclass(frozen=True)
class VideoConfig:
    """Offscreen rendering settings (``MUJOCO_GL=egl`` works without a GPU)."""

    fps: int = 30
    width_px: int = 640
    height_px: int = 480


@dataclass
class EpisodeLog:
    """Per-tick time series, kept in memory and written as CSV."""

    columns: tuple[str, ...] = (
        "t_s",
        "com_x_m",
        "com_y_m",
        "com_z_m",
        "com_vx_mps",
        "com_vy_mps",
        "com_vz_mps",
        "roll_rad",
        "pitch_rad",
        "yaw_rad",
        "cmd_vx_mps",
        "contact_left",
        "contact_right",
        "fz_left_n",
        "fz_right_n",
        "lGx",
        "lGy",
        "lGz",
        "kGx",
        "kGy",
        "kGz",
        "tau_abs_max_nm",
    )
    rows: list[np.ndarray] = field(default_factory=list)

    def to_csv(self) -> str:
        buf = io.StringIO()
        np.savetxt(
            buf,
            np.asarray(self.rows),
            delimiter=",",
            header=",".join(self.columns),
            comments="",
            fmt="%.6g",
        )
        return buf.getvalue()


def _log_row(state: Any, cmd: Command, tau: np.ndarray) -> np.ndarray:
    return np.concatenate(
        [
            [state.t_s],
            state.com_world_m,
            state.com_vel_world_mps,
            state.base_rpy_rad,
            [cmd.vx_mps],
            [float(state.foot_contact[f]) for f in FEET],
            [state.foot_wrench_world[f][2] for f in FEET],
            state.h_measured,
            [np.abs(tau).max()],
        ]
    )


def run_episode(
    sim: Simulator,
    controller: Controller,
    command: Command,
    duration_s: float,
    out_dir: Path | None = None,
    video: VideoConfig | None = None,
    progress: bool = True,
    meta: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Simulate until ``duration_s`` or a fall; return (and write) the summary.

    Ctrl-C stops the episode early; what was simulated is still summarised and written,
    with ``"interrupted": true``.
    """
    if not (np.isfinite(duration_s) and duration_s > 0):
        raise ConfigError("--duration", duration_s, "a finite duration > 0 s")
    n_ticks = round(duration_s / sim.config.timestep_s)
    state = sim.state()
    controller.reset(state)
    com0 = state.com_world_m.copy()
    log = EpisodeLog()
    renderer, writer, frame_dt, next_frame_t = None, None, np.inf, 0.0
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
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(
            total=round(duration_s, 3),
            unit="sim-s",
            leave=False,
            mininterval=0.5,
            bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} sim-s [{elapsed}, {postfix}]",
        )
    t_wall0 = time.perf_counter()
    render_wall_s = 0.0
    interrupted = False
    try:
        for tick in range(n_ticks):
            state = sim.state()
            tau = controller.compute(state)
            log.rows.append(_log_row(state, command, tau))
            sim.step(tau)
            if renderer is not None and sim.time_s >= next_frame_t - 1e-9:
                t_r = time.perf_counter()
                renderer.update_scene(sim.data, camera="track")
                writer.append_data(renderer.render())
                render_wall_s += time.perf_counter() - t_r
                next_frame_t += frame_dt
            if bar is not None and tick % 100 == 99:
                bar.n = round(sim.time_s, 3)
                elapsed = time.perf_counter() - t_wall0
                bar.set_postfix_str(f"RTF {sim.time_s / max(elapsed, 1e-9):.2f}")
            if sim.fall.fell:
                break
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
    final = sim.state()
    summary = _summarise(sim, controller, command, final, com0, log, wall_s, render_wall_s)
    summary["interrupted"] = interrupted
    if meta:
        summary = {**meta, **summary}
    if out_dir is not None:
        out = Path(out_dir)
        write_atomic(out / "log.csv", log.to_csv())
        if tmp_video is not None:
            tmp_video.replace(out / "video.mp4")
        write_json_atomic(out / "summary.json", summary)
    return summary


def _summarise(
    sim: Simulator,
    controller: Controller,
    command: Command,
    final: Any,
    com0: np.ndarray,
    log: EpisodeLog,
    wall_s: float,
    render_wall_s: float,
) -> dict[str, Any]:
    rows = np.asarray(log.rows)
    t = rows[:, 0]
    sim_s = float(sim.time_s)
    after_1s = t >= 1.0
    if np.any(after_1s):
        err = rows[after_1s, 4] - command.vx_mps
        rmse = float(np.sqrt(np.mean(err**2)))
    else:
        rmse = None
    distance = float(final.com_world_m[0] - com0[0])
    stats = controller.mpc_stats
    footholds = [f.to_dict() for f in sim.footholds]
    return {
        "duration_s": round(sim_s, 4),
        "fell": sim.fall.fell,
        "fall_time_s": sim.fall.t_s,
        "fall_reason": sim.fall.reason or None,
        "distance_m": distance,
        "lateral_drift_m": float(final.com_world_m[1] - com0[1]),
        "mean_speed_mps": distance / sim_s if sim_s > 0 else 0.0,
        "speed_rmse_mps": rmse,
        "footholds": footholds,
        "foothold_violations": sum(not f["allowed"] for f in footholds),
        "step_durations_s": [round(x, 4) for x in controller.step_durations_s],
        "mpc": None if stats is None else stats.summary(),
        "wall_time_s": wall_s,
        "render_time_s": render_wall_s,
        "realtime_factor": sim_s / wall_s if wall_s > 0 else None,
    }
