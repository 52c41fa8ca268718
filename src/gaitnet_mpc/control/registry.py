"""Controller registry: name -> factory building a :class:`Controller` for one episode, and
the controller's settings (a dataclass tree) from a preset, a TOML file and overrides."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from gaitnet_mpc import config as configio
from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.dt_policy import CONTROLLER_OF_POLICY
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.terrain import Course

if TYPE_CHECKING:
    from gaitnet_mpc.mpc.sequential import DtPolicy


@dataclass(frozen=True)
class ControllerContext:
    """What a controller factory may use: the robot model, the course (handed to a walking
    controller only through a :class:`TerrainView`), the velocity command and the
    controller's settings (``KDWalkConfig``, ``SRBMWalkConfig``, ``WBWalkConfig``; None:
    the defaults of :func:`controller_config`).

    ``dt_policy``: a dt policy object that replaces the one the settings name
    (``KDWalkConfig.dt_policy``), for the kd family only: a caller that chooses each
    step's dt itself, e.g. :class:`~gaitnet_mpc.control.dt_policies.ExternalDt` of the
    Gymnasium environment. None: the settings' policy."""

    robot: RobotModel
    course: Course
    command: Any
    config: Any = None
    dt_policy: DtPolicy | None = None


#: The controllers that are ``kd`` with another dt policy: the same settings and presets,
#: and the ``KDWalkConfig.dt_policy.kind`` each name sets.
KD_FAMILY = ("kd", "gaitnet", "oracle", "kd-optdt")
POLICY_OF_CONTROLLER = {
    "kd": "fixed",
    "gaitnet": "gaitnet",
    "oracle": "oracle",
    "kd-optdt": "optdt",
}
#: The dt policies each of them may run (``drawn``: the data-collection teacher).
POLICIES_OF_CONTROLLER = {
    name: tuple(k for k, c in CONTROLLER_OF_POLICY.items() if c == name) for name in KD_FAMILY
}


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
    gaitnet_weights: str | None = None,
    overrides: Sequence[str] = (),
) -> Any:
    """The settings of controller ``name``, in this order: the preset file (default
    "default"; robot-dependent through ``planar``), for the kd family the dt policy the
    name stands for, ``config_file``, the flags (kd family ``preview``: the multi-step
    footstep preview; ``dt_s``: the fixed dt of kd, srbm and wbmpc; gaitnet
    ``gaitnet_weights``), then ``overrides`` (``KEY=VALUE`` items of ``--set``). None for
    a controller without settings.

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
    if name in KD_FAMILY:
        kind = POLICY_OF_CONTROLLER[name]
        config = replace(config, dt_policy=replace(config.dt_policy, kind=kind))
    if config_file is not None:
        config = configio.apply(config, configio.read_toml(config_file), f"{config_file}: ")
    if preview and config.preview is None:
        from gaitnet_mpc.control.kd_walk_config import preview_walk_config

        config = preview_walk_config(config)
    if dt_s is not None:
        if name == "kd":
            config = replace(config, dt_policy=replace(config.dt_policy, dt_s=dt_s))
        elif name == "srbm":
            config = replace(config, dt_s=dt_s)
        elif name == "wbmpc":
            config = replace(config, step_durations=replace(config.step_durations, dt_s=dt_s))
    if gaitnet_weights is not None:
        if name != "gaitnet":
            raise ConfigError("--gaitnet-weights", gaitnet_weights, "--controller gaitnet")
        config = replace(
            config, dt_policy=replace(config.dt_policy, gaitnet_weights=gaitnet_weights)
        )
    if overrides:
        config = configio.apply(config, configio.parse_overrides(overrides), "--set ")
    if name in KD_FAMILY and config.dt_policy.kind not in POLICIES_OF_CONTROLLER[name]:
        raise ConfigError(
            "dt_policy.kind",
            config.dt_policy.kind,
            f"one of {POLICIES_OF_CONTROLLER[name]} for --controller {name} (the "
            "controller's name chooses the dt policy)",
        )
    return config


def _config(name: str, ctx: ControllerContext) -> Any:
    if ctx.config is not None:
        return ctx.config
    return controller_config(name, ctx.robot.spec.planar)


def _stand(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.stand import StandController

    return StandController(ctx.robot)


def _srbm(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.srbm_walk import SRBMWalkController

    config = _config("srbm", ctx)
    return SRBMWalkController(ctx.robot, TerrainView(ctx.course), ctx.command, config)


def _kd_family(name: str) -> Callable[[ControllerContext], Controller]:
    """The factory of ``kd``, ``gaitnet`` or ``oracle``: one controller, the dt policy of
    its settings."""

    def make(ctx: ControllerContext) -> Controller:
        from gaitnet_mpc.control.kd_walk import KDWalkController
        from gaitnet_mpc.control.kd_walk_config import walk_terrain

        config = _config(name, ctx)
        terrain = walk_terrain(ctx.course, config)
        return KDWalkController(
            ctx.robot, terrain, ctx.command, dt_policy=ctx.dt_policy, config=config
        )

    return make


def _wbmpc(ctx: ControllerContext) -> Controller:
    from gaitnet_mpc.control.wbmpc_walk import WBWalkController

    config = _config("wbmpc", ctx)
    return WBWalkController(ctx.robot, TerrainView(ctx.course), ctx.command, config)


CONTROLLERS: dict[str, Callable[[ControllerContext], Controller]] = {
    "gaitnet": _kd_family("gaitnet"),
    "kd": _kd_family("kd"),
    "kd-optdt": _kd_family("kd-optdt"),
    "oracle": _kd_family("oracle"),
    "stand": _stand,
    "srbm": _srbm,
    "wbmpc": _wbmpc,
}


def make_controller(name: str, ctx: ControllerContext) -> Controller:
    if name not in CONTROLLERS:
        raise ConfigError("--controller", name, f"one of {sorted(CONTROLLERS)}")
    if ctx.dt_policy is not None and name not in KD_FAMILY:
        expected = f"None for {name} (only {', '.join(KD_FAMILY)} take a dt policy)"
        raise ConfigError("dt_policy", type(ctx.dt_policy).__name__, expected)
    return CONTROLLERS[name](ctx)
