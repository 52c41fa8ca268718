"""The teachers of data collection: walking controllers whose step durations are drawn.

* ``wbmpc``: the whole-body NMPC (paper Sec. III-A), the paper's teacher; each step's dt
  comes from its :class:`~gaitnet_mpc.gait.step_durations.StepDurations`.
* ``kd``: the kino-dynamic MPC with :class:`~gaitnet_mpc.mpc.sequential.ScheduledDt`
  over the same draws, an explicit alternative so that the two teachers can be compared.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from gaitnet_mpc.command import Command
from gaitnet_mpc.dataset.protocol import CollectProtocol
from gaitnet_mpc.scenario import Scenario
from gaitnet_mpc.sim.disturbances import Push


def teacher_config(protocol: CollectProtocol, planar: bool) -> Any:
    """The teacher's settings: its preset, then the protocol's ``--set`` overrides."""
    from gaitnet_mpc.control.registry import controller_config

    return controller_config(
        protocol.teacher,
        planar,
        preset=protocol.teacher_preset,
        overrides=protocol.teacher_overrides,
    )


def teacher_scenario(
    protocol: CollectProtocol,
    course_seed: int | None,
    command: Command,
    durations_seed: int,
    duration_s: float,
    pushes: tuple[Push, ...],
    planar: bool,
) -> Scenario:
    """One episode of the teacher, its step durations drawn from
    ``protocol.duration_range_s`` with ``durations_seed``."""
    config = teacher_config(protocol, planar)
    if protocol.teacher == "wbmpc":
        durations = replace(
            config.step_durations,
            duration_range_s=protocol.duration_range_s,
            seed=durations_seed,
        )
        config = replace(config, step_durations=durations)
    else:
        drawn = replace(
            config.dt_policy,
            kind="drawn",
            drawn_step_range_s=protocol.duration_range_s,
            drawn_seed=durations_seed,
        )
        config = replace(config, dt_policy=drawn)
    return Scenario(
        robot=protocol.robot,
        controller=protocol.teacher,
        course=protocol.course,
        course_seed=course_seed,
        command=command,
        duration_s=duration_s,
        pushes=pushes,
        config=config,
    )
