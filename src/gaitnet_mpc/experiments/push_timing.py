"""When a push sweep's push starts: at a phase of a step, and which step.

``sweep push`` compares controllers "in each direction and at each phase" of a step. Two
rules (``ModePlan.phase_of``):

* ``"executed"`` (new sweeps): the phase of the controller's own executed step. The push
  starts at ``t_0 + p T``, with ``t_0`` the start of the first step at or after the
  settling time in which :data:`PUSH_SWING_FOOT` swings, and ``T`` that step's duration as
  the controller chose it at its start. Found by simulating the episode without a push up
  to that step (the closed loop is deterministic, so the pushed episodes reach the same
  state). Every controller is then pushed at the same point of its gait, with the same
  foot in the air.
* ``"nominal"`` (sweeps made before 2026-12-07): ``k T + p T`` with ``T = 5 dt`` the
  controller's fixed dt, or the nominal 0.045 s, and ``k T`` the first multiple at or after
  the settling time. Exact for a fixed dt. A variable-dt controller's steps drift from
  that grid: `gaitnet` pushed at "phase 0.25" was measured at 0.81 of a step with the other
  foot in the air, against `kd`'s 0.25 (``benchmarks/results/leg_reach/``), so its cells
  compared different situations.
"""

from __future__ import annotations

import math
from typing import Any

#: Stages per step (Sec. IV-B1: a step lasts ``5 dt``).
STAGES_PER_STEP = 5
#: The swing foot of the step an ``"executed"`` push lands in.
PUSH_SWING_FOOT = "left"
#: The rules of :data:`ModePlan.phase_of <gaitnet_mpc.experiments.sweep_cases.ModePlan>`.
PHASE_RULES = ("executed", "nominal")


def step_s(dt_s: float | None) -> float:
    """The nominal step duration of a controller with fixed ``dt_s`` (None: the nominal
    0.045 s): ``5 dt`` [s]."""
    from gaitnet_mpc.dt_policy import NOMINAL_DT_S

    return STAGES_PER_STEP * (NOMINAL_DT_S if dt_s is None else dt_s)


def push_time_s(dt_s: float | None, settle_s: float, phase: float) -> float:
    """The ``"nominal"`` rule: ``k T + p T``, ``k T`` the first step start at or after
    ``settle_s`` on the grid of :func:`step_s`."""
    t_step = step_s(dt_s)
    return math.ceil(settle_s / t_step - 1e-9) * t_step + phase * t_step


def executed_push_time_s(episode: Any, settle_s: float, phase: float) -> float | None:
    """The ``"executed"`` rule on ``episode`` (built without pushes, not yet stepped; it is
    stepped here): the push start [s], no earlier than the tick after that step's first
    one (the controller fixes the step's duration on it). None where the controller has
    no step schedule or the episode ended (a fall) before that step."""
    from gaitnet_mpc.control.walking_base import WalkingBase
    from gaitnet_mpc.runner.loop import EpisodeLoop

    controller = episode.controller
    if not isinstance(controller, WalkingBase):
        return None
    duration_s = float(episode.scenario.duration_s)
    loop = EpisodeLoop(episode.sim, controller, episode.scenario.command, duration_s)
    sched = controller.schedule
    while not loop.done:
        loop.tick()
        if sched.step_start_time_s >= settle_s - 1e-9 and sched.swing_foot == PUSH_SWING_FOOT:
            start = sched.step_start_time_s + phase * sched.current_step_duration_s
            return max(start, loop.sim.time_s)
    return None


def measured_phase(controller: Any, t_s: float) -> tuple[float | None, str]:
    """Where in its executed step the push started (phase, swing foot), from the gait log:
    a fraction of the duration the step started with (a push may shorten it,
    :mod:`~gaitnet_mpc.control.step_retiming`)."""
    from gaitnet_mpc.control.walking_base import WalkingBase

    if not isinstance(controller, WalkingBase):
        return None, ""
    sched = controller.schedule
    for s in sched.step_log:
        if s.start_time_s - 1e-9 <= t_s < s.start_time_s + s.duration_s - 1e-9:
            return round((t_s - s.start_time_s) / s.planned_duration_s, 3), s.swing_foot
    if sched.step_start_time_s <= t_s:  # the episode ended inside that step
        frac = (t_s - sched.step_start_time_s) / sched.planned_step_duration_s
        return round(frac, 3), sched.swing_foot
    return None, ""


__all__ = [
    "PHASE_RULES",
    "PUSH_SWING_FOOT",
    "STAGES_PER_STEP",
    "executed_push_time_s",
    "measured_phase",
    "push_time_s",
    "step_s",
]
