"""The closed loop of one episode, one control tick at a time, and its summary.

:class:`EpisodeLoop` is the one place where a tick happens: read the measured state, ask
the controller for torques, record the tick (``log.csv``, ``mpc_log.csv``, the foot
events), step the physics. :func:`~gaitnet_mpc.runner.episode.run_episode` (whole
episodes, with video, viewer and progress bar) and
:class:`~gaitnet_mpc.scenario.stepper.EpisodeStepper` (a caller steps the episode) both
drive it, so an episode stepped by hand records and summarises exactly what
``gaitnet-mpc run`` does.

The summary fields are described in :mod:`gaitnet_mpc.runner.episode` (outcome) and
:meth:`EpisodeLoop.summary`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.base import Controller, Telemetry
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.results.events import EventRecorder
from gaitnet_mpc.results.io import write_atomic, write_json_atomic
from gaitnet_mpc.results.rundir import SUMMARY, TIMING, split_timing
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.runner.logs import H_COLS, EpisodeLog, TelemetryRecorder
from gaitnet_mpc.sim.simulator import Simulator, tilt_rad
from gaitnet_mpc.state import RobotState


@dataclass(frozen=True)
class Tick:
    """One control tick as it happened.

    Attributes:
        state: the measured state the controller was given (at the tick's start).
        tau_nm: the torques it returned [N m] (actuator order; the simulator saturates
            them at the actuator limits).
        telemetry: the controller's telemetry after the tick (None: a controller without
            a gait, e.g. ``stand``).
    """

    state: RobotState
    tau_nm: np.ndarray
    telemetry: Telemetry | None


def ended_upright(
    final_tilt_rad: float, final_com_height_m: float, com_height0_m: float, sim_config: Any
) -> bool:
    """Whether the episode ended upright: the fall detector's tilt and CoM-height measures
    at half its margins, ``tilt <= fall_tilt_rad / 2`` and
    ``h >= h0 (1 + fall_com_height_ratio) / 2`` (see :mod:`gaitnet_mpc.runner.episode`)."""
    tilt_ok = final_tilt_rad <= 0.5 * sim_config.fall_tilt_rad
    height_ok = final_com_height_m >= 0.5 * (1.0 + sim_config.fall_com_height_ratio) * (
        com_height0_m
    )
    return bool(tilt_ok and height_ok)


def _log_row(
    state: Any,
    cmd: Command,
    tau: np.ndarray,
    tau_limit: np.ndarray,
    probe: TelemetryRecorder,
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
            probe.wrench_ext(),
        ]
    )


class EpisodeLoop:
    """The simulator and controller of one episode, ticked together until ``duration_s``
    or a fall, with the records of every tick.

    Made at the episode's start: it resets the controller with the simulator's current
    state (so make it right after the simulator, and only once per episode).

    Attributes:
        sim, controller, command: what runs (``command`` is logged as ``cmd_vx_mps``).
        n_ticks: ticks of the full duration (``round(duration_s / timestep_s)``).
        ticks: ticks done so far.
        log: the per-tick table (``log.csv``); ``probe``: the MPC records
            (``mpc_log.csv``) and this tick's telemetry; ``events``: the feet's events.
        com0: CoM at the start [m]; ``com_height0_m``: its height above the start ground.
    """

    def __init__(
        self, sim: Simulator, controller: Controller, command: Command, duration_s: float
    ) -> None:
        if not (np.isfinite(duration_s) and duration_s > 0):
            raise ConfigError("--duration", duration_s, "a finite duration > 0 s")
        self.sim = sim
        self.controller = controller
        self.command = command
        self.n_ticks = round(duration_s / sim.config.timestep_s)
        self.ticks = 0
        state = sim.state()
        controller.reset(state)
        self.com0 = state.com_world_m.copy()
        self.com_height0_m = sim.com_height_m
        self.log = EpisodeLog()
        self.probe = TelemetryRecorder(controller)
        self.events = EventRecorder()
        self._tau_limit = np.maximum(sim.model.actuator_ctrlrange[:, 1].copy(), 1e-9)

    @property
    def fell(self) -> bool:
        """Whether the simulator's fall detector fired (a fall or a divergence)."""
        return self.sim.fall.fell

    @property
    def done(self) -> bool:
        """Whether the episode is over: it fell, or its duration was simulated."""
        return self.fell or self.ticks >= self.n_ticks

    def tick(self) -> Tick:
        """One control tick: measure, compute, record, step the physics (one timestep)."""
        sim, probe = self.sim, self.probe
        state = sim.state()
        tau = self.controller.compute(state)
        probe.after_compute(state.t_s)
        tel = probe.telemetry
        self.events.update(state, None if tel is None else {tel.swing_foot: tel.step_end_s})
        self.log.rows.append(
            _log_row(state, self.command, tau, self._tau_limit, probe, sim.self_contact)
        )
        sim.step(tau)
        self.ticks += 1
        return Tick(state, tau, tel)

    def summary(
        self, wall_s: float, render_wall_s: float = 0.0, interrupted: bool = False
    ) -> dict[str, Any]:
        """The ``summary.json`` fields of the episode so far (the wall-clock ones included:
        :func:`~gaitnet_mpc.results.rundir.split_timing` moves them to ``timing.json``).

        ``fell`` / ``fall_time_s`` / ``fall_reason``: how the episode ended early;
        ``diverged`` is true when that was a numerical divergence of the simulation (reason
        ``"simulation diverged: ..."``). ``self_collisions``: ticks with a contact between
        two robot geoms; ``self_collision_first_t_s`` (null if none),
        ``self_collision_max_depth_m`` and ``self_collision_pairs`` (sorted
        ``"bodyA/bodyB"``) describe them. ``interrupted``, ``ended_upright`` and
        ``outcome``: see :mod:`gaitnet_mpc.runner.episode`.
        """
        sim, controller, log = self.sim, self.controller, self.log
        final = sim.state()
        # (n, columns) even for n = 0: a run interrupted before its first tick was logged
        rows = np.asarray(log.rows, dtype=float).reshape(len(log.rows), len(log.columns))
        t = rows[:, 0]
        sim_s = float(sim.time_s)
        after_1s = t >= 1.0
        if np.any(after_1s):
            err = rows[after_1s, 4] - self.command.vx_mps
            rmse = float(np.sqrt(np.mean(err**2)))
        else:
            rmse = None
        distance = float(final.com_world_m[0] - self.com0[0])
        stats = controller.mpc_stats
        footholds = [f.to_dict() for f in sim.footholds]
        summary: dict[str, Any] = {
            "duration_s": round(sim_s, 4),
            "fell": sim.fall.fell,
            "fall_time_s": sim.fall.t_s,
            "fall_reason": sim.fall.reason or None,
            "diverged": sim.diverged,
            "distance_m": distance,
            "lateral_drift_m": float(final.com_world_m[1] - self.com0[1]),
            # how the episode ended: a run cut short by its duration can still end tilted
            "final_tilt_rad": tilt_rad(final.base_rot_world),
            "final_com_height_m": sim.com_height_m,
            "mean_speed_mps": distance / sim_s if sim_s > 0 else 0.0,
            "speed_rmse_mps": rmse,
            "footholds": footholds,
            "foothold_violations": sum(not f["allowed"] for f in footholds),
            "step_durations_s": [round(x, 4) for x in controller.step_durations_s],
            "mpc": None if stats is None else stats.summary(),
            "dt_policy": controller.dt_policy_summary(),
            "swing_events": controller.swing_events,
            "wall_time_s": wall_s,
            "render_time_s": render_wall_s,
            "torque_limits_nm": sorted({float(x) for x in sim.model.actuator_ctrlrange[:, 1]}),
            "realtime_factor": sim_s / wall_s if wall_s > 0 else None,
            **sim.self_collisions.to_dict(),
        }
        summary["interrupted"] = interrupted
        summary["com_height0_m"] = self.com_height0_m
        summary["ended_upright"] = ended_upright(
            summary["final_tilt_rad"], summary["final_com_height_m"], self.com_height0_m, sim.config
        )
        summary["outcome"] = (
            "interrupted"
            if interrupted
            else "fell"
            if summary["fell"]
            else "ok"
            if summary["ended_upright"]
            else "not_upright"
        )
        return summary

    def write_files(
        self, out_dir: Path, summary: dict[str, Any], video_part: Path | None = None
    ) -> None:
        """The run folder's files of the episode: ``log.csv``, ``mpc_log.csv`` (MPC
        controllers), ``events.csv``, ``course.json``, ``video.mp4`` (renamed from
        ``video_part``, if given), ``timing.json`` and, last, ``summary.json``."""
        out = Path(out_dir)
        log, probe = self.log, self.probe
        write_atomic(out / "log.csv", log.to_csv())
        if probe.log is not None:
            probe.log.fill_measured(np.asarray(log.rows).reshape(-1, len(log.columns)), H_COLS)
            write_atomic(out / "mpc_log.csv", probe.log.to_csv())
        write_atomic(out / "events.csv", self.events.to_csv())
        write_json_atomic(out / "course.json", self.sim.course.to_dict())
        if video_part is not None:
            video_part.replace(out / "video.mp4")
        facts, timing = split_timing(summary)
        write_json_atomic(out / TIMING, timing)
        write_json_atomic(out / SUMMARY, facts)
