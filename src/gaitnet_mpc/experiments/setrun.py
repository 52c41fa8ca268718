"""Walk one set of the protocol with the teacher and return its rows.

A set runs on the set clock from 0 to ``spec.seconds``. The robot starts standing and the
command ramps up as in any run. After a fall the set goes on from a fresh standing start
(a new *segment*, new draws of the step durations), at most ``max_restarts`` times; the
time lost to the fall counts against the set. Pushes are fixed on the set clock, so a
restart does not move them.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from gaitnet_mpc.command import Command
from gaitnet_mpc.dataset.protocol import SetSpec
from gaitnet_mpc.experiments.sampler import StepSampler
from gaitnet_mpc.experiments.teachers import teacher_scenario
from gaitnet_mpc.robots import ROBOTS
from gaitnet_mpc.scenario import MAX_DURATION_S, MIN_DURATION_S, build_episode
from gaitnet_mpc.sim.disturbances import protocol_pushes
from gaitnet_mpc.terrain import SEEDED_COURSES

#: Simulated seconds between two progress reports of a set.
PROGRESS_PERIOD_S = 0.5


@dataclass
class SetResult:
    """A set's rows and what happened while walking it.

    Attributes:
        rows: the samples (column name -> value).
        steps_dropped_fall: steps dropped because the robot fell before they ended.
        steps_incomplete: steps still open when the set's time ran out.
        fall_times_s: set time of each fall [s].
        segments: episodes walked (1 + restarts after falls).
        sim_seconds: simulated time walked [s] (less than the set's when it ended short).
        ended_short: the set stopped early, having used up its restarts.
        wall_s: wall-clock time of the set [s] (not stored in the data file, which stays
            reproducible bit for bit).
    """

    spec: SetSpec
    rows: list[dict[str, object]] = field(default_factory=list)
    steps_dropped_fall: int = 0
    steps_incomplete: int = 0
    fall_times_s: list[float] = field(default_factory=list)
    segments: int = 0
    sim_seconds: float = 0.0
    ended_short: bool = False
    wall_s: float = 0.0

    def stats(self) -> dict[str, object]:
        """Everything but the rows and the wall time (stored with the data file)."""
        return {
            "rows": len(self.rows),
            "steps_dropped_fall": self.steps_dropped_fall,
            "steps_incomplete": self.steps_incomplete,
            "falls": len(self.fall_times_s),
            "fall_times_s": [round(t, 4) for t in self.fall_times_s],
            "segments": self.segments,
            "sim_seconds": round(self.sim_seconds, 4),
            "ended_short": self.ended_short,
        }


def run_set(spec: SetSpec, progress: Callable[[float], None] | None = None) -> SetResult:
    """Walk set ``spec``; ``progress(simulated_seconds)`` is called every
    :data:`PROGRESS_PERIOD_S` of simulated time (and with the rest at the end)."""
    t_wall = time.perf_counter()
    protocol = spec.protocol
    p = protocol.pushes
    set_pushes = protocol_pushes(
        spec.pushes_seed, spec.push_start_s, spec.seconds, p.period_s, p.force_range_n, p.duration_s
    )
    command = Command(spec.vx_mps)
    sampler = StepSampler(spec.index, spec.vx_mps)
    result = SetResult(spec)
    t_set, reported = 0.0, 0.0
    while t_set < spec.seconds - 1e-9:
        if result.segments > protocol.max_restarts:
            result.ended_short = True
            break
        pushes = tuple(replace(q, t_s=q.t_s - t_set) for q in set_pushes if q.t_s >= t_set)
        scenario = teacher_scenario(
            protocol,
            spec.course_seed if protocol.course in SEEDED_COURSES else None,
            command,
            spec.durations_seed + result.segments,
            # the loop below keeps the set's clock; the scenario only records the time left
            min(max(spec.seconds - t_set, MIN_DURATION_S), MAX_DURATION_S),
            pushes,
            ROBOTS[protocol.robot].planar,
        )
        episode = build_episode(scenario)
        sim, controller = episode.sim, episode.controller
        state = sim.state()
        controller.reset(state)
        sampler.start_segment(result.segments)
        result.segments += 1
        n_ticks = round((spec.seconds - t_set) / sim.config.timestep_s)
        for _ in range(n_ticks):
            state = sim.state()
            tau = controller.compute(state)
            t_now = t_set + state.t_s
            active = any(q.active(state.t_s) for q in pushes)
            sampler.observe(state, controller, t_now, t_now >= spec.push_start_s, active)
            sim.step(tau)
            if progress is not None and t_set + sim.time_s - reported >= PROGRESS_PERIOD_S:
                progress(t_set + sim.time_s - reported)
                reported = t_set + sim.time_s
            if sim.fall.fell:
                break
        sampler.end_segment(sim.fall.fell)
        t_set += sim.time_s
        if not sim.fall.fell:
            break
        result.fall_times_s.append(t_set)
    if progress is not None:
        progress(spec.seconds - reported)  # the rest, including time a short set skipped
    result.rows = sampler.rows
    result.steps_dropped_fall = sampler.dropped_fall
    result.steps_incomplete = sampler.incomplete
    result.sim_seconds = t_set
    result.wall_s = time.perf_counter() - t_wall
    return result
