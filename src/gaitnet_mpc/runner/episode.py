"""Run one closed-loop episode and summarise it (``summary.json``, logs, course, video).

The run folder that :func:`run_episode` writes (plots are made afterwards from these files
by :mod:`gaitnet_mpc.results.plots`):

* ``summary.json``: episode outcome and statistics (see :func:`_summarise`).
* ``log.csv``: one row per control tick (:class:`EpisodeLog`).
* ``mpc_log.csv``: one row per MPC solve (:class:`MPCLog`); only for MPC controllers.
* ``course.json``: the course in the JSON course format (for the top-view plot).
* ``video.mp4``: offscreen rendering, unless disabled.
"""

from __future__ import annotations

import io
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.results.io import write_atomic, write_json_atomic
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.sim.simulator import Simulator, tilt_rad


@dataclass(frozen=True)
class VideoConfig:
    """Offscreen rendering settings (``MUJOCO_GL=egl`` works without a GPU)."""

    fps: int = 30
    width_px: int = 640
    height_px: int = 480


@dataclass
class EpisodeLog:
    """Per-tick time series, kept in memory and written as CSV.

    ``self_contact`` is 1 on ticks where two robot geoms touch (see
    :class:`~gaitnet_mpc.sim.simulator.SelfCollisionStats`), else 0.
    """

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
        "tau_limit_ratio_max",
        "mpc_dt_s",
        "mpc_n_qps",
        "mpc_solve_ms",
        "stance_foot",
        "self_contact",
    )
    rows: list[np.ndarray] = field(default_factory=list)

    def to_csv(self) -> str:
        return _csv(self.columns, self.rows)


@dataclass
class MPCLog:
    """One row per MPC solve, written as ``mpc_log.csv``.

    ``dt_s`` is the MPC sampling time of the step the solve belongs to (NaN without a gait
    schedule). For controllers that expose a kino-dynamic ``plan`` (``kd``), the
    ``*_pred`` columns hold the momentum the plan predicts one stage ahead, at
    ``t_pred_s``, and the ``*_meas`` columns the momentum measured at that tick (NaN when
    the episode ended before it, or for other controllers).
    """

    columns: tuple[str, ...] = (
        "t_s",
        "full_solve",
        "n_qps",
        "converged",
        "solve_ms",
        "dt_s",
        "t_pred_s",
        "lGx_pred",
        "kGy_pred",
        "kGz_pred",
        "lGx_meas",
        "kGy_meas",
        "kGz_meas",
    )
    rows: list[list[float]] = field(default_factory=list)

    def fill_measured(self, log_rows: np.ndarray, h_cols: slice) -> None:
        """Fill the ``*_meas`` columns from the tick log (first tick at or after ``t_pred_s``)."""
        if not self.rows or log_rows.size == 0:
            return
        t = log_rows[:, 0]
        h = log_rows[:, h_cols]  # (n, 6) [l_G; k_G]
        i_pred, i_meas = self.columns.index("t_pred_s"), self.columns.index("lGx_meas")
        for row in self.rows:
            t_pred = row[i_pred]
            if not np.isfinite(t_pred) or t_pred > t[-1] + 1e-9:
                continue
            k = int(np.searchsorted(t, t_pred - 1e-9))
            row[i_meas : i_meas + 3] = [h[k, 0], h[k, 4], h[k, 5]]  # l_G,x, k_G,y, k_G,z

    def to_csv(self) -> str:
        return _csv(self.columns, self.rows)


def _csv(columns: tuple[str, ...], rows: list[Any]) -> str:
    """CSV text with a header line; ``nan`` marks values that do not apply."""
    buf = io.StringIO()
    data = np.asarray(rows, dtype=float).reshape(-1, len(columns))
    np.savetxt(buf, data, delimiter=",", header=",".join(columns), comments="", fmt="%.6g")
    return buf.getvalue()


#: Columns of ``log.csv`` holding the measured momentum ``[l_G; k_G]``.
_H_COLS = slice(EpisodeLog.columns.index("lGx"), EpisodeLog.columns.index("kGz") + 1)


class _MPCProbe:
    """Reads what a controller exposes about its MPC, tolerating controllers without it."""

    def __init__(self, controller: Controller) -> None:
        self.controller = controller
        self.n_seen = 0
        self.last_qps = np.nan
        self.last_ms = np.nan
        self.log = MPCLog() if controller.mpc_stats is not None else None

    def step_dt(self) -> float:
        sched = getattr(self.controller, "schedule", None)
        dt = getattr(sched, "current_step_dt_s", None)
        return float(dt) if dt is not None else np.nan

    def stance_code(self) -> float:
        sched = getattr(self.controller, "schedule", None)
        foot = getattr(sched, "stance_foot", None)
        return float(FEET.index(foot)) if foot in FEET else np.nan

    def after_compute(self, t_s: float) -> None:
        """Record the solves that the last ``compute`` call made."""
        stats = self.controller.mpc_stats
        if stats is None or self.log is None:
            return
        n = len(stats.solve_time_s)
        if n == self.n_seen:
            return
        dt = self.step_dt()
        n_cols = len(self.log.columns)
        for i in range(self.n_seen, n):
            row = [
                t_s,
                float(stats.full_solve[i]),
                float(stats.qps_per_solve[i]),
                float(stats.converged[i]),
                1e3 * stats.solve_time_s[i],
                dt,
            ]
            self.log.rows.append(row + [np.nan] * (n_cols - len(row)))
        i_pred = self.log.columns.index("t_pred_s")
        self.log.rows[-1][i_pred : i_pred + 4] = self._prediction(t_s)
        self.last_qps = float(stats.qps_per_solve[n - 1])
        self.last_ms = 1e3 * stats.solve_time_s[n - 1]
        self.n_seen = n

    def _prediction(self, t_s: float) -> list[float]:
        """``[t_pred, l_G,x, k_G,y, k_G,z]`` one stage ahead of a plan made at ``t_s``."""
        none = [np.nan] * 4
        plan = getattr(self.controller, "plan", None)
        step = getattr(plan, "last_step", None)
        states = getattr(step, "states", None)
        dts = getattr(plan, "dts_s", None)
        t_plan = getattr(plan, "t_plan_s", None)
        if states is None or dts is None or t_plan is None or abs(t_plan - t_s) > 1e-9:
            return none  # no plan, or the solve failed and the old plan was kept
        states = np.asarray(states)
        if states.ndim != 2 or states.shape[0] < 2 or states.shape[1] < 12:
            return none
        return [t_plan + float(dts[0]), states[1, 6], states[1, 10], states[1, 11]]


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


def _log_row(
    state: Any,
    cmd: Command,
    tau: np.ndarray,
    tau_limit: np.ndarray,
    probe: _MPCProbe,
    self_contact: bool,
) -> np.ndarray:
    """One row of :class:`EpisodeLog` (columns in its order)."""
    tau_abs = np.abs(tau)
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
            [tau_abs.max(), (tau_abs / tau_limit).max()],
            [probe.step_dt(), probe.last_qps, probe.last_ms, probe.stance_code()],
            [float(self_contact)],
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
    viewer: Any | None = None,
) -> dict[str, Any]:
    """Simulate until ``duration_s`` or a fall; return (and write) the summary.

    Ctrl-C (or closing ``viewer``) stops the episode early; what was simulated is still
    summarised and written, with ``"interrupted": true``.

    Args:
        viewer: an open ``mujoco.viewer.launch_passive`` handle on ``sim.model`` /
            ``sim.data``, synchronised at 60 Hz of simulated time and paced to real time
            (it never runs faster than real time; it may run slower). None: no viewer.
    """
    if not (np.isfinite(duration_s) and duration_s > 0):
        raise ConfigError("--duration", duration_s, "a finite duration > 0 s")
    n_ticks = round(duration_s / sim.config.timestep_s)
    state = sim.state()
    controller.reset(state)
    com0 = state.com_world_m.copy()
    log = EpisodeLog()
    probe = _MPCProbe(controller)
    tau_limit = np.maximum(sim.model.actuator_ctrlrange[:, 1].copy(), 1e-9)
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
        foot_r = sim.robot.spec.foot_contact_radius_m
    bar = _progress_bar(duration_s) if progress else None
    viewer_dt, next_view_t = 1.0 / 60.0, 0.0
    t_wall0 = time.perf_counter()
    render_wall_s = 0.0
    interrupted = False
    try:
        for tick in range(n_ticks):
            state = sim.state()
            tau = controller.compute(state)
            probe.after_compute(state.t_s)
            log.rows.append(_log_row(state, command, tau, tau_limit, probe, sim.self_contact))
            sim.step(tau)
            if renderer is not None and sim.time_s >= next_frame_t - 1e-9:
                t_r = time.perf_counter()
                renderer.update_scene(sim.data, camera="track")
                _draw_footholds(renderer.scene, controller.planned_footholds(), foot_r)
                writer.append_data(renderer.render())
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
            if bar is not None and tick % 100 == 99:
                _update_bar(bar, sim.time_s, time.perf_counter() - t_wall0)
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
        if probe.log is not None:
            probe.log.fill_measured(np.asarray(log.rows).reshape(-1, len(log.columns)), _H_COLS)
            write_atomic(out / "mpc_log.csv", probe.log.to_csv())
        write_json_atomic(out / "course.json", sim.course.to_dict())
        if tmp_video is not None:
            tmp_video.replace(out / "video.mp4")
        write_json_atomic(out / "summary.json", summary)
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
    """The ``summary.json`` fields.

    ``fell`` / ``fall_time_s`` / ``fall_reason``: how the episode ended early; ``diverged``
    is true when that was a numerical divergence of the simulation (reason ``"simulation
    diverged: ..."``). ``self_collisions``: ticks with a contact between two robot geoms;
    ``self_collision_first_t_s`` (null if none), ``self_collision_max_depth_m`` and
    ``self_collision_pairs`` (sorted ``"bodyA/bodyB"``) describe them.
    """
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
        "diverged": sim.diverged,
        "distance_m": distance,
        "lateral_drift_m": float(final.com_world_m[1] - com0[1]),
        # how the episode ended: a run cut short by its duration can still end tilted
        "final_tilt_rad": tilt_rad(final.base_rot_world),
        "final_com_height_m": sim.com_height_m,
        "mean_speed_mps": distance / sim_s if sim_s > 0 else 0.0,
        "speed_rmse_mps": rmse,
        "footholds": footholds,
        "foothold_violations": sum(not f["allowed"] for f in footholds),
        "step_durations_s": [round(x, 4) for x in controller.step_durations_s],
        "mpc": None if stats is None else stats.summary(),
        "wall_time_s": wall_s,
        "render_time_s": render_wall_s,
        "torque_limits_nm": sorted({float(x) for x in sim.model.actuator_ctrlrange[:, 1]}),
        "realtime_factor": sim_s / wall_s if wall_s > 0 else None,
        **sim.self_collisions.to_dict(),
    }
