"""The scenario itself: :class:`Scenario` (checked, to and from TOML), :func:`make_scenario`
as ``gaitnet-mpc run`` makes one, and :func:`build_episode` (see the package docstring)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import tomli_w

from gaitnet_mpc import config as configio
from gaitnet_mpc.command import Command
from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.control.registry import (
    CONTROLLERS,
    KD_FAMILY,
    ControllerContext,
    config_type,
    controller_config,
    make_controller,
)
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import ROBOTS, RobotModel, load_robot
from gaitnet_mpc.sim.cart import Cart
from gaitnet_mpc.sim.disturbances import Push
from gaitnet_mpc.sim.simulator import SimConfig, Simulator, check_payload
from gaitnet_mpc.terrain import BUILTIN_COURSES, SEEDED_COURSES, Course, load_course

if TYPE_CHECKING:
    from gaitnet_mpc.mpc.sequential import DtPolicy

#: Shortest and longest simulated time of a scenario [s]: one control tick, one hour.
MIN_DURATION_S = 0.01
MAX_DURATION_S = 3600.0


@dataclass(frozen=True)
class Scenario:
    """Everything that decides what one episode simulates.

    Attributes:
        robot: a registered robot (``humanoid3d``, ``biped2d``).
        controller: a registered controller (``gaitnet``, ``kd``, ``oracle``, ``srbm``,
            ``wbmpc``, ``stand``).
        course: a built-in course name, or a course JSON file.
        course_seed: layout seed of a seeded built-in course (``uneven``,
            ``stepping-stones``, ``gap``); None: the built-in layout. Ignored (with a
            warning in the summary) for other courses.
        command: the velocity command.
        duration_s: simulated time [s].
        pushes: forces at the trunk CoM (:class:`~gaitnet_mpc.sim.disturbances.Push`).
        payload_kg: mass on the trunk no controller is told about [kg].
        cart: a cart ahead of the robot that its hands push, with a load no controller is
            told about (:class:`~gaitnet_mpc.sim.cart.Cart`); None: no cart.
        config: the controller's full settings (a dataclass tree, e.g. ``KDWalkConfig``);
            None for a controller without settings. :func:`make_scenario` fills it.
        origin: how ``config`` was made (``preset``, ``config``, ``dt_s``, ``preview``,
            ``gaitnet_weights``, ``set``): a record for the reader, not applied again.
    """

    robot: str = "humanoid3d"
    controller: str = "gaitnet"
    course: str = "flat"
    course_seed: int | None = None
    command: Command = field(default_factory=Command)
    duration_s: float = 10.0
    pushes: tuple[Push, ...] = ()
    payload_kg: float = 0.0
    cart: Cart | None = None
    config: Any = None
    origin: tuple[tuple[str, Any], ...] = ()

    def __post_init__(self) -> None:
        if self.robot not in ROBOTS:
            raise ConfigError("robot", self.robot, f"one of {sorted(ROBOTS)}")
        if self.controller not in CONTROLLERS:
            raise ConfigError("controller", self.controller, f"one of {sorted(CONTROLLERS)}")
        d = self.duration_s
        if not (math.isfinite(d) and MIN_DURATION_S <= d <= MAX_DURATION_S):
            raise ConfigError(
                "duration_s", d, f"a simulated time in [{MIN_DURATION_S:g}, {MAX_DURATION_S:g}] s"
            )
        seed = self.course_seed
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
            raise ConfigError("course_seed", seed, "an integer >= 0 (none: the built-in layout)")
        check_payload(self.payload_kg, field="payload_kg")
        if self.cart is not None and not ROBOTS[self.robot].arm_joints:
            raise ConfigError("cart", self.robot, "a robot with arms to push it (humanoid3d)")
        cls = config_type(self.controller)
        if cls is None and self.config is not None:
            raise ConfigError("config", type(self.config).__name__, f"None for {self.controller}")
        if cls is not None and not isinstance(self.config, cls):
            expected = f"a {cls.__name__} (make_scenario fills it)"
            raise ConfigError("config", type(self.config).__name__, expected)

    # ------------------------------------------------------------------ TOML
    def to_table(self) -> dict[str, Any]:
        """The scenario as TOML-ready nested dicts (``None`` as ``"none"``)."""
        out: dict[str, Any] = {
            "robot": self.robot,
            "controller": self.controller,
            "course": self.course,
            "course_seed": configio.NONE if self.course_seed is None else self.course_seed,
            "duration_s": self.duration_s,
            "payload_kg": self.payload_kg,
            **({} if self.cart is None else {"cart": self.cart.to_dict()}),
            "command": self.command.to_dict(),
            "pushes": [
                {"t_s": p.t_s, "force_world_n": list(p.force_world_n), "duration_s": p.duration_s}
                for p in self.pushes
            ],
            "origin": {k: configio.NONE if v is None else v for k, v in self.origin},
        }
        if self.config is not None:
            out["config"] = configio.to_table(self.config)
        return out

    def to_toml(self, header: str = "") -> str:
        """TOML text of the whole scenario, after ``header`` lines written as comments."""
        comment = "".join(f"# {line}".rstrip() + "\n" for line in header.splitlines())
        return comment + tomli_w.dumps(self.to_table())

    @classmethod
    def from_table(cls, data: dict[str, Any], base_dir: Path | None = None) -> Scenario:
        """The scenario of a table as :meth:`to_table` writes it; a relative course file is
        read from ``base_dir``. :class:`ConfigError` names a missing or bad key."""
        known = {f.name for f in fields(cls)}  # the table's keys are the fields
        for key in data:
            if key not in known:
                raise ConfigError(f"scenario.{key}", data[key], f"one of {sorted(known)}")
        for key in ("robot", "controller", "course", "duration_s"):
            if key not in data:
                raise ConfigError(f"scenario.{key}", "missing", "a value")
        robot, controller = (
            _typed("robot", data["robot"], str),
            _typed("controller", data["controller"], str),
        )
        course = _typed("course", data["course"], str)
        if course not in BUILTIN_COURSES and base_dir is not None:
            path = Path(course)
            course = str(path if path.is_absolute() else base_dir / path)
        seed = data.get("course_seed", configio.NONE)
        values = _floats("command", data.get("command", {}), Command().to_dict())
        command = Command.from_table(values, "command")
        pushes = [
            Push.from_table(raw, f"pushes[{i}]")
            for i, raw in enumerate(_typed("pushes", data.get("pushes", []), list))
        ]
        cart = Cart(**_floats("cart", data["cart"], Cart().to_dict())) if "cart" in data else None
        origin = _typed("origin", data.get("origin", {}), dict)
        config = None
        cfg_cls = config_type(controller) if controller in CONTROLLERS else None
        if cfg_cls is not None:
            table = _typed("config", data.get("config", {}), dict)
            config = configio.apply(cfg_cls(), table, "config.")
        elif "config" in data:
            raise ConfigError("config", "a table", f"none: {controller} has no settings")
        return cls(
            robot=robot,
            controller=controller,
            course=course,
            course_seed=None if seed == configio.NONE else seed,
            command=command,
            duration_s=_number("duration_s", data["duration_s"]),
            pushes=tuple(pushes),
            payload_kg=_number("payload_kg", data.get("payload_kg", 0.0)),
            cart=cart,
            config=config,
            origin=tuple((k, None if v == configio.NONE else v) for k, v in origin.items()),
        )

    @classmethod
    def from_toml(cls, path: str | Path) -> Scenario:
        """The scenario of a ``scenario.toml`` (e.g. a run folder's)."""
        data = configio.read_toml(path, "--scenario")
        try:
            return cls.from_table(data, Path(path).parent)
        except ConfigError as exc:
            raise ConfigError(f"{path}: {exc.field}", exc.value, exc.expected) from None


def _typed(key: str, value: Any, tp: type) -> Any:
    if not isinstance(value, tp):
        raise ConfigError(key, value, f"a {tp.__name__}")
    return value


def _number(key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(key, value, "a number")
    return float(value)


def _floats(key: str, table: Any, defaults: dict[str, float]) -> dict[str, float]:
    table = _typed(key, table, dict)
    for name in table:
        if name not in defaults:
            raise ConfigError(f"{key}.{name}", table[name], f"one of {sorted(defaults)}")
    return {name: _number(f"{key}.{name}", table.get(name, v)) for name, v in defaults.items()}


def make_scenario(
    *,
    robot: str = "humanoid3d",
    controller: str = "gaitnet",
    course: str = "flat",
    course_seed: int | None = None,
    vx_mps: float = 0.0,
    vy_mps: float = 0.0,
    yaw_rate_radps: float = 0.0,
    duration_s: float = 10.0,
    pushes: Sequence[Push] = (),
    payload_kg: float = 0.0,
    cart: Cart | None = None,
    preset: str | None = None,
    config_file: str | Path | None = None,
    overrides: Sequence[str] = (),
    dt_s: float | None = None,
    preview: bool = False,
    gaitnet_weights: str | None = None,
) -> Scenario:
    """A scenario whose controller settings are made as ``gaitnet-mpc run`` makes them:
    the preset (default "default"), ``config_file``, the flags (``preview``, ``dt_s``,
    ``gaitnet_weights``), then ``overrides`` (``KEY=VALUE``), see
    :func:`~gaitnet_mpc.control.registry.controller_config`. With a ``cart``, a walking
    controller holds its arms in the pushing pose (``low_level.arm_push = true``, before the
    overrides): it knows that it pushes, not the load. Every input is checked here, before
    anything is simulated (:class:`ConfigError` names the field)."""
    if robot not in ROBOTS:
        raise ConfigError("--robot", robot, f"one of {sorted(ROBOTS)}")
    if preview and controller not in KD_FAMILY:
        raise ConfigError("--preview", controller, f"one of {', '.join(KD_FAMILY)}")
    cls = config_type(controller)
    if cart is not None and cls is not None and "low_level" in {f.name for f in fields(cls)}:
        overrides = ("low_level.arm_push=true", *overrides)
    config = controller_config(
        controller,
        ROBOTS[robot].planar,
        preset=preset,
        config_file=config_file,
        preview=preview,
        dt_s=dt_s,
        gaitnet_weights=gaitnet_weights,
        overrides=tuple(overrides),
    )
    origin: dict[str, Any] = {}
    if dt_s is not None:
        origin["dt_s"] = dt_s
    if preview:
        origin["preview"] = True
    if gaitnet_weights is not None:
        origin["gaitnet_weights"] = gaitnet_weights
    if preset is not None:
        origin["preset"] = preset
    if config_file is not None:
        origin["config"] = str(config_file)
    if overrides:
        origin["set"] = list(overrides)
    scenario = Scenario(
        robot=robot,
        controller=controller,
        course=str(course),
        course_seed=course_seed,
        command=Command(vx_mps, vy_mps, yaw_rate_radps),
        duration_s=duration_s,
        pushes=tuple(pushes),
        payload_kg=payload_kg,
        cart=cart,
        config=config,
        origin=tuple(origin.items()),
    )
    load_scenario_course(scenario)  # a bad course name or file fails here
    return scenario


def load_scenario_course(scenario: Scenario) -> Course:
    """The course of ``scenario``, its seed applied where the course is seeded."""
    seeded = scenario.course_seed is not None and scenario.course in SEEDED_COURSES
    return load_course(scenario.course, **({"seed": scenario.course_seed} if seeded else {}))


@dataclass
class Episode:
    """A scenario built: the robot, course, controller and simulator of one episode, for
    callers that step the loop themselves (data collection, Table II recording; see
    :class:`~gaitnet_mpc.scenario.stepper.EpisodeStepper` for a loop that records and
    summarises as ``gaitnet-mpc run`` does)."""

    scenario: Scenario
    robot: RobotModel
    course: Course
    controller: Controller
    sim: Simulator

    @property
    def command(self) -> Command:
        return self.scenario.command


def build_episode(
    scenario: Scenario,
    *,
    robot: RobotModel | None = None,
    sim_config: SimConfig | None = None,
    dt_policy: DtPolicy | None = None,
) -> Episode:
    """The robot, course, controller and simulator of ``scenario``.

    Args:
        robot: an already loaded model of ``scenario.robot`` (saves the load); None: load.
        sim_config: simulator settings beyond the scenario's disturbances (fall margins);
            its ``payload_kg`` and ``pushes`` are replaced by the scenario's.
        dt_policy: for the kd family, a dt policy object in place of the one the
            scenario's settings name (e.g. :class:`~gaitnet_mpc.control.dt_policies.ExternalDt`,
            whose dt the caller sets step by step); the scenario then no longer says
            everything the episode does. None: the settings' policy.
    """
    if robot is None:
        robot = load_robot(scenario.robot)
    elif robot.name != scenario.robot:
        raise ConfigError("robot", robot.name, f"a model of {scenario.robot}")
    check_payload(scenario.payload_kg, robot.total_mass_kg, "payload_kg")
    course = load_scenario_course(scenario)
    ctx = ControllerContext(robot, course, scenario.command, scenario.config, dt_policy)
    controller = make_controller(scenario.controller, ctx)
    sim_config = replace(
        sim_config or SimConfig(),
        payload_kg=scenario.payload_kg,
        pushes=scenario.pushes,
        cart=scenario.cart,
    )
    return Episode(scenario, robot, course, controller, Simulator(robot, course, sim_config))


def scenario_warnings(scenario: Scenario) -> list[str]:
    """Settings of ``scenario`` that have no effect on its run (recorded in the summary)."""
    out = []
    s = scenario
    if s.course_seed is not None and s.course not in SEEDED_COURSES:
        out.append(
            f"--seed {s.course_seed} has no effect: course {s.course!r} has a fixed layout "
            f"(seeded courses: {', '.join(sorted(SEEDED_COURSES))})"
        )
    cmd = s.command
    if s.controller == "stand":
        flags = ("--vx", "--vy", "--yaw-rate")
        for flag, value in zip(flags, (cmd.vx_mps, cmd.vy_mps, cmd.yaw_rate_radps), strict=True):
            if value != 0.0:
                out.append(f"{flag} {value:g} has no effect: the stand controller does not walk")
    origin = dict(s.origin)
    dt = origin.get("dt_s")
    if dt is not None and s.controller in ("stand", "gaitnet", "oracle"):
        why = {
            "stand": "the stand controller has no MPC",
            "gaitnet": "Gait-Net chooses every step's dt",
            "oracle": "the oracle chooses every step's dt",
        }[s.controller]
        out.append(f"--dt {dt:g} has no effect: {why}")
    if ROBOTS[s.robot].planar:
        for flag, value in (("--vy", cmd.vy_mps), ("--yaw-rate", cmd.yaw_rate_radps)):
            if value != 0.0:
                out.append(f"{flag} {value:g} has no effect on the planar robot")
    if s.cart is not None and not getattr(getattr(s.config, "low_level", None), "arm_push", 0):
        out.append("the arms do not hold the pushing pose (low_level.arm_push): cart not held")
    for i, push in enumerate(s.pushes):
        if push in s.pushes[:i]:
            out.append(
                f"push {i} ({_push_text(push)}) is given twice: both are applied (twice the force)"
            )
        if push.t_s >= s.duration_s:
            out.append(
                f"--push at t = {push.t_s:g} s has no effect: the run ends at {s.duration_s:g} s"
            )
    return out


def _push_text(p: Push) -> str:
    fx, fy, fz = p.force_world_n
    return f"t={p.t_s:g},fx={fx:g},fy={fy:g},fz={fz:g},dur={p.duration_s:g}"


def scenario_meta(episode: Episode, warnings: list[str]) -> dict[str, Any]:
    """The fields of ``summary.json`` that say what was run."""
    s = episode.scenario
    return {
        "warnings": warnings,
        "robot": s.robot,
        "controller": s.controller,
        "controller_options": dict(s.origin),
        "course": episode.course.name,
        "command": s.command.to_dict(),
        "pushes": [
            {"t_s": p.t_s, "force_n": list(p.force_world_n), "dur_s": p.duration_s}
            for p in s.pushes
        ],
        "payload_kg": s.payload_kg,
        "cart": None if s.cart is None else s.cart.to_dict(),
        "seed": s.course_seed,
        "terrain_knowledge": episode.controller.terrain_knowledge(),
    }
