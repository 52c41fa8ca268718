"""What a soak episode is and how it is drawn: :class:`EpisodeSpec` (everything needed to
replay one episode), :class:`DrawSettings` (what the episodes are drawn from; part of a
soak's identity) and :func:`draw_episode`.

Episode K of a seed depends on ``numpy.random.default_rng([seed, K])`` alone. The
controller weights favour the cheap ones: wbmpc is ~10x slower than real time on
humanoid3d and builds its NLPs for ~40 s, so it gets few, short episodes.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

#: Relative frequency of each controller (wbmpc is ~40 s of NLP build + ~10x real time).
CONTROLLER_WEIGHTS: dict[str, float] = {
    "stand": 0.2,
    "srbm": 0.3,
    "kd": 0.25,
    "gaitnet": 0.2,
    "wbmpc": 0.05,
}
ROBOT_NAMES = ("humanoid3d", "biped2d")
DURATION_RANGE_S = (1.0, 5.0)
#: wbmpc's duration range by robot [s] (humanoid3d: ~10x slower than real time).
WBMPC_DURATION_RANGE_S = {"humanoid3d": (1.0, 1.5), "biped2d": DURATION_RANGE_S}
FLAT_PROBABILITY = 0.35
RANDOM_LAYOUT_PROBABILITY = 0.8  # a seeded course gets a random seed, else its default
VX_RANGE_MPS = (0.0, 1.5)  # Command allows |vx| <= 1.5 m/s
VY_MAX_MPS = 0.3  # Command allows 0.5 m/s
YAW_RATE_MAX_RADPS = 0.5  # Command allows 1.5 rad/s
TURN_PROBABILITY = 0.25  # humanoid3d episodes with a lateral / yaw-rate command
PUSH_COUNT_PROBABILITIES = (0.4, 0.3, 0.2, 0.1)  # 0, 1, 2 or 3 pushes
PUSH_FORCE_RANGE_N = (10.0, 80.0)  # horizontal, in a uniformly drawn direction
PUSH_DURATION_RANGE_S = (0.05, 0.2)  # at most 16 N s (the protocol: 20 N s)
PUSH_START_S = 0.2  # no push before [s]
PAYLOAD_PROBABILITY = 0.5
PAYLOAD_RANGE_KG = (0.0, 3.0)  # within both robots' bound (their own mass: 16 / 10 kg)

#: The draw profiles: ``short`` (1-5 s on every built-in course, flat included) and
#: ``long`` (20 s on a random layout of a seeded course, stones, gaps or uneven tiles, with
#: 1-3 pushes; the soak of issue 37).
PROFILES = ("short", "long")
LONG_DURATION_S = 20.0
LONG_COURSES = ("gap", "stepping-stones", "uneven")
LONG_PUSH_COUNT_PROBABILITIES = (0.0, 0.4, 0.35, 0.25)  # 1, 2 or 3 pushes


@dataclass(frozen=True)
class EpisodeSpec:
    """One soak episode: everything needed to replay it.

    Attributes:
        index: episode number K (the draw's second seed).
        controller: registry name.
        robot: robot name.
        course: built-in course name.
        course_seed: layout seed of a seeded course (None: its default layout).
        vx_mps, vy_mps, yaw_rate_radps: velocity command.
        duration_s: simulated time [s].
        pushes: ``(t_s, fx_n, fy_n, fz_n, duration_s)`` of each push at the trunk CoM.
        payload_kg: unknown mass added to the trunk [kg].
    """

    index: int
    controller: str
    robot: str
    course: str
    course_seed: int | None
    vx_mps: float
    vy_mps: float
    yaw_rate_radps: float
    duration_s: float
    pushes: tuple[tuple[float, float, float, float, float], ...] = ()
    payload_kg: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "pushes": [list(p) for p in self.pushes]}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> EpisodeSpec:
        pushes = tuple(tuple(float(x) for x in p) for p in data.get("pushes", ()))
        return cls(**{**data, "pushes": pushes})  # type: ignore[arg-type]

    def label(self) -> str:
        """A one-line description for the report."""
        course = self.course if self.course_seed is None else f"{self.course}#{self.course_seed}"
        text = (
            f"{self.controller} on {self.robot}, {course}, vx {self.vx_mps:g} m/s, "
            f"{self.duration_s:g} s"
        )
        if self.vy_mps or self.yaw_rate_radps:
            text += f", vy {self.vy_mps:g} m/s, yaw rate {self.yaw_rate_radps:g} rad/s"
        if self.pushes:
            text += f", {len(self.pushes)} push(es)"
        if self.payload_kg:
            text += f", payload {self.payload_kg:g} kg"
        return text


@dataclass(frozen=True)
class DrawSettings:
    """What the episodes are drawn from (part of a soak's identity: resuming checks it).

    Attributes:
        seed: base seed; episode K uses ``numpy.random.default_rng([seed, K])``.
        controllers: the controllers drawn from (weights of :data:`CONTROLLER_WEIGHTS`).
        max_duration_s: cap on every drawn duration [s] (None: no cap).
        profile: one of :data:`PROFILES`.
    """

    seed: int = 0
    controllers: tuple[str, ...] = tuple(CONTROLLER_WEIGHTS)
    max_duration_s: float | None = None
    profile: str = "short"

    def __post_init__(self) -> None:
        from gaitnet_mpc.errors import ConfigError

        unknown = sorted(set(self.controllers) - set(CONTROLLER_WEIGHTS))
        if not self.controllers or unknown:
            raise ConfigError(
                "--controllers",
                ",".join(self.controllers),
                f"names among {list(CONTROLLER_WEIGHTS)}",
            )
        if self.max_duration_s is not None and not (
            math.isfinite(self.max_duration_s) and self.max_duration_s >= 0.01
        ):
            raise ConfigError("--max-duration-s", self.max_duration_s, "a duration >= 0.01 s")
        if self.profile not in PROFILES:
            raise ConfigError("--profile", self.profile, f"one of {list(PROFILES)}")

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "controllers": list(self.controllers)}

    def command_flags(self) -> str:
        """The command-line flags that reproduce these settings."""
        flags = f"--seed {self.seed}"
        if tuple(self.controllers) != tuple(CONTROLLER_WEIGHTS):
            flags += f" --controllers {','.join(self.controllers)}"
        if self.max_duration_s is not None:
            flags += f" --max-duration-s {self.max_duration_s:g}"
        if self.profile != "short":
            flags += f" --profile {self.profile}"
        return flags


def draw_episode(settings: DrawSettings, index: int) -> EpisodeSpec:
    """Episode ``index`` of ``settings`` (depends on nothing else)."""
    from gaitnet_mpc.terrain import BUILTIN_COURSES, SEEDED_COURSES

    rng = np.random.default_rng([settings.seed, index])
    names = list(settings.controllers)
    weights = np.array([CONTROLLER_WEIGHTS[n] for n in names])
    controller = names[int(rng.choice(len(names), p=weights / weights.sum()))]
    robot = ROBOT_NAMES[int(rng.integers(len(ROBOT_NAMES)))]
    long = settings.profile == "long"
    if long:
        course = LONG_COURSES[int(rng.integers(len(LONG_COURSES)))]
        course_seed: int | None = int(rng.integers(2**31))
        duration_s = LONG_DURATION_S
    else:
        others = sorted(c for c in BUILTIN_COURSES if c != "flat")
        flat = rng.random() < FLAT_PROBABILITY
        course = "flat" if flat else others[int(rng.integers(len(others)))]
        course_seed = None
        if course in SEEDED_COURSES and rng.random() < RANDOM_LAYOUT_PROBABILITY:
            course_seed = int(rng.integers(2**31))
        lo, hi = WBMPC_DURATION_RANGE_S[robot] if controller == "wbmpc" else DURATION_RANGE_S
        duration_s = round(float(rng.uniform(lo, hi)), 2)
    if settings.max_duration_s is not None:
        duration_s = min(duration_s, settings.max_duration_s)
    vx = vy = yaw_rate = 0.0
    if controller != "stand":
        vx = round(float(rng.uniform(*VX_RANGE_MPS)), 2)
        if robot == "humanoid3d" and rng.random() < TURN_PROBABILITY:
            vy = round(float(rng.uniform(-VY_MAX_MPS, VY_MAX_MPS)), 2)
            yaw_rate = round(float(rng.uniform(-YAW_RATE_MAX_RADPS, YAW_RATE_MAX_RADPS)), 2)
    pushes = []
    counts = LONG_PUSH_COUNT_PROBABILITIES if long else PUSH_COUNT_PROBABILITIES
    n_pushes = int(rng.choice(len(counts), p=counts))
    for _ in range(n_pushes):
        t_s = round(float(rng.uniform(PUSH_START_S, max(duration_s, PUSH_START_S))), 3)
        force_n = float(rng.uniform(*PUSH_FORCE_RANGE_N))
        angle_rad = float(rng.uniform(0.0, 2.0 * np.pi))
        fx, fy = round(force_n * math.cos(angle_rad), 1), round(force_n * math.sin(angle_rad), 1)
        pushes.append((t_s, fx, fy, 0.0, round(float(rng.uniform(*PUSH_DURATION_RANGE_S)), 3)))
    payload_kg = 0.0
    if rng.random() < PAYLOAD_PROBABILITY:
        payload_kg = round(float(rng.uniform(*PAYLOAD_RANGE_KG)), 2)
    return EpisodeSpec(
        index=index,
        controller=controller,
        robot=robot,
        course=course,
        course_seed=course_seed,
        vx_mps=vx,
        vy_mps=vy,
        yaw_rate_radps=yaw_rate,
        duration_s=duration_s,
        pushes=tuple(sorted(pushes)),
        payload_kg=payload_kg,
    )
