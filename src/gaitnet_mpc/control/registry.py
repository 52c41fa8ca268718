"""Controller registry: name -> factory building a :class:`Controller` for one episode, and
the controller's settings (a dataclass tree) from a preset, a TOML file and overrides."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from gaitnet_mpc import config as configio
from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.terrain import Course


@dataclass(frozen=True)
class ControllerContext:
    """What a controller factory may use: the robot model, the course (handed to a walking
    controller only through a :class:`TerrainView`), the velocity command, options and the
    controller's settings.

    ``options``: ``dt_s`` (kd: the fixed MPC sampling time of its dt policy; srbm, wbmpc:
    their fixed dt when ``config`` is None), and when ``config`` is None ``preset`` and
    ``preview`` (see :func:`controller_config`). ``config``: the settings dataclass
    (``KDWalkConfig``, ``SRBMWalkConfig``); None: made by :func:`controller_config`.
    """

    robot: RobotModel
    course: Course
    command: Any
    options: dict[str, Any] = field(default_factory=dict)
    config: Any = None


#: The controllers that are ``kd`` with another dt policy: the same settings and presets.
KD_FAMILY = ("kd", "gaitnet", "oracle")


def config_type(name: str) -> type | None:
    """The settings dataclass of controller ``name`` (None: it has none)."""
    if name in KD_FAMILY:
        from gaitnet_mpc.control.kd_walk_config import KDWalkConfig

        return KDWalkConfig
    if name == "srbm":
        from gaitnet_mpc.control.srbm_walk import SRBMWalkConfig

        return SRBMWalkConfig
    if name == "wbmpc":
        from gaitnet_mpc.control.wbmpc_walk import WBWalkConfig

        return WBWalkConfig
    return None


def controller_config(
    name: str,
    planar: bool,
    *,
    preset: str | None = None,
    config_file: str | Path | None = None,
    preview: bool = False,
    dt_s: float | None = None,
    overrides: Sequence[str] = (),
) -> Any:
    """The settings of controller ``name``, in this order: the preset file (default
    "default"; robot-dependent through ``planar``), ``config_file``, the flags (kd
    ``preview``: the multi-step footstep preview; srbm ``dt_s``), then ``overrides``
    (``KEY=VALUE`` items of ``--set``). None for a controller without settings.

    Raises:
        ConfigError: naming the option or the full key, before anything is simulated.
    """
    if name not in CONTROLLERS:
        raise ConfigError("--controller", name, f"one of {sorted(CONTROLLERS)}")
    cls = config_type(name)
    if cls is None:
        for option, value in (("--preset", preset), ("--config", config_file)):
            if value is not None:
                raise ConfigError(option, value, f"no {option} (the {name} controller has none)")
        if overrides:
            raise ConfigError(
                "--set", overrides[0], f"nothing: the {name} controller has no settings"
            )
        return None
    preset_of = "kd" if name in KD_FAMILY else name
    config = configio.load_preset(cls, preset_of, preset or "default", planar)
    if config_file is not None:
        config = configio.apply(config, configio.read_toml(config_file), f"{config_file}: ")
    if preview and config.preview is None:
        from gaitnet_mpc.control.kd_walk_config import preview_walk_config

        config = preview_walk_config(config)
    if dt_s is not None and name == "srbm":
        config = replace(config, dt_s=dt_s)
    if dt_s is not None and name == "wbmpc":
        config = replace(config, step_durations=replace(config.step_durations, dt_s=dt_s))
    if overrides:
        config = configio.apply(config, configio.parse_overrides(overrides), "--set ")
    return config


def _config(name: str, ctx: ControllerContext) -> Any:
    if ctx.config is not None:
        return ctx.config
    options = ctx.options
    return controller_config(
        name,
        ctx.robot.spec.planar,
        preset=options.get("preset"),
        preview=bool(options.get("preview")),
        dt_s=options.get("dt_s"),
    )


def _stand(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.stand import StandController

    return StandController(ctx.robot)


def _srbm(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.srbm_walk import SRBMWalkController

    config = _config("srbm", ctx)
    return SRBMWalkController(ctx.robot, TerrainView(ctx.course), ctx.command, config)


def _kd(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.kd_walk import KDWalkController
    from gaitnet_mpc.control.kd_walk_config import walk_terrain
    from gaitnet_mpc.mpc.sequential import FixedDt

    dt_s = ctx.options.get("dt_s")
    policy = FixedDt() if dt_s is None else FixedDt(dt_s)
    config = _config("kd", ctx)
    terrain = walk_terrain(ctx.course, config)
    return KDWalkController(ctx.robot, terrain, ctx.command, dt_policy=policy, config=config)


def _gaitnet(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.gaitnet_walk import GaitNetWalkController, load_gaitnet
    from gaitnet_mpc.control.kd_walk_config import walk_terrain
    from gaitnet_mpc.gaitnet.policy import GaitNetPolicyConfig

    config = _config("gaitnet", ctx)
    net = load_gaitnet(ctx.robot, ctx.options.get("gaitnet_weights"))
    terrain = walk_terrain(ctx.course, config)
    # the paper preset runs Algorithm 1 as printed: no fallbacks, no cap on re-timings
    policy = GaitNetPolicyConfig(safeguards=ctx.options.get("preset") != "paper")
    return GaitNetWalkController(ctx.robot, terrain, ctx.command, net, config, policy)


def _oracle(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.kd_walk_config import walk_terrain
    from gaitnet_mpc.control.oracle_walk import OracleWalkController

    config = _config("oracle", ctx)
    terrain = walk_terrain(ctx.course, config)
    return OracleWalkController(ctx.robot, terrain, ctx.command, config)


def _wbmpc(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.wbmpc_walk import WBWalkController

    config = _config("wbmpc", ctx)
    return WBWalkController(ctx.robot, TerrainView(ctx.course), ctx.command, config)


CONTROLLERS: dict[str, Callable[[ControllerContext], Controller]] = {
    "gaitnet": _gaitnet,
    "kd": _kd,
    "oracle": _oracle,
    "stand": _stand,
    "srbm": _srbm,
    "wbmpc": _wbmpc,
}


def make_controller(name: str, ctx: ControllerContext) -> Controller:
    if name not in CONTROLLERS:
        raise ConfigError("--controller", name, f"one of {sorted(CONTROLLERS)}")
    return CONTROLLERS[name](ctx)
