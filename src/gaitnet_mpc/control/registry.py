"""Controller registry: name -> factory building a :class:`Controller` for one episode."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.terrain import Course


@dataclass(frozen=True)
class ControllerContext:
    """What a controller factory may use: the robot model, the course (handed to a walking
    controller only through a :class:`TerrainView`), the velocity command and free-form
    options from the CLI."""

    robot: RobotModel
    course: Course
    command: Any
    options: dict[str, Any]


def _stand(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.stand import StandController

    return StandController(ctx.robot)


def _srbm(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.srbm_walk import SRBMWalkConfig, SRBMWalkController

    dt_s = ctx.options.get("dt_s")
    config = SRBMWalkConfig() if dt_s is None else SRBMWalkConfig(dt_s=dt_s)
    return SRBMWalkController(ctx.robot, TerrainView(ctx.course), ctx.command, config)


def _kd(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.kd_walk import (
        KD_PRESETS,
        KDWalkController,
        preview_walk_config,
        walk_terrain,
    )
    from gaitnet_mpc.mpc.sequential import FixedDt

    dt_s = ctx.options.get("dt_s")
    policy = FixedDt() if dt_s is None else FixedDt(dt_s)
    preset = ctx.options.get("preset", "default")
    if preset not in KD_PRESETS:
        raise ConfigError("--preset", preset, f"one of {sorted(KD_PRESETS)}")
    config = KD_PRESETS[preset](ctx.robot.spec.planar)
    if ctx.options.get("preview"):
        config = preview_walk_config(config)
    terrain = walk_terrain(ctx.course, config)
    return KDWalkController(ctx.robot, terrain, ctx.command, dt_policy=policy, config=config)


CONTROLLERS: dict[str, Callable[[ControllerContext], Controller]] = {
    "kd": _kd,
    "stand": _stand,
    "srbm": _srbm,
}


def make_controller(name: str, ctx: ControllerContext) -> Controller:
    if name not in CONTROLLERS:
        raise ConfigError("--controller", name, f"one of {sorted(CONTROLLERS)}")
    return CONTROLLERS[name](ctx)
