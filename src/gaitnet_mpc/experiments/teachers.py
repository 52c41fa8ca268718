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
from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.dataset.protocol import STAGES_PER_STEP, CollectProtocol
from gaitnet_mpc.gait.step_durations import StepDurations
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.terrain import Course


def teacher_config(protocol: CollectProtocol, planar: bool) -> Any:
    """The teacher's settings: its preset, then the protocol's ``--set`` overrides."""
    from gaitnet_mpc.control.registry import controller_config

    return controller_config(
        protocol.teacher,
        planar,
        preset=protocol.teacher_preset,
        overrides=protocol.teacher_overrides,
    )


def make_teacher(
    protocol: CollectProtocol,
    robot: RobotModel,
    course: Course,
    command: Command,
    durations_seed: int,
) -> Controller:
    """The teacher controller of one episode, its step durations drawn from
    ``protocol.duration_range_s`` with ``durations_seed``."""
    config = teacher_config(protocol, robot.spec.planar)
    if protocol.teacher == "wbmpc":
        from gaitnet_mpc.control.terrain_view import TerrainView
        from gaitnet_mpc.control.wbmpc_walk import WBWalkController

        durations = replace(
            config.step_durations,
            duration_range_s=protocol.duration_range_s,
            seed=durations_seed,
        )
        config = replace(config, step_durations=durations)
        return WBWalkController(robot, TerrainView(course), command, config)
    from gaitnet_mpc.control.kd_walk import KDWalkController
    from gaitnet_mpc.control.kd_walk_config import walk_terrain
    from gaitnet_mpc.mpc.sequential import ScheduledDt

    durations = StepDurations(
        duration_range_s=protocol.duration_range_s,
        stages_per_step=STAGES_PER_STEP,
        seed=durations_seed,
    )
    return KDWalkController(
        robot,
        walk_terrain(course, config),
        command,
        dt_policy=ScheduledDt(durations),
        config=config,
    )
