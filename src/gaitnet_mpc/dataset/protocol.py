"""The data-collection protocol of paper Sec. IV-A-1, split into independent sets.

The paper walks 15 sets, 600 s in all; each set at one constant commanded speed drawn
from [0, 1] m/s, with every stride's duration drawn uniformly from [150, 400] ms (the
step's MPC dt is that duration over ``h'`` stages), undisturbed in its first half and
pushed at the CoM every 2 s (10-100 N for 0.2 s, random horizontal direction) in its
second half.

A set is the unit of work, of resumption and of parallelism: everything it needs is in
its :class:`SetSpec`, whose seeds derive from the protocol seed and the set index only, so
a set gives the same rows whichever worker runs it, and in whichever order.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field

import numpy as np

from gaitnet_mpc.errors import ConfigError

TEACHERS = ("wbmpc", "kd")
#: Stages per step (``h'``) of both teachers: a drawn duration d gives the step dt d / h'.
STAGES_PER_STEP = 5


@dataclass(frozen=True)
class PushProtocol:
    """Impulses at the trunk CoM in the second half of every set.

    Attributes:
        period_s: time between push starts [s].
        force_range_n: (min, max) force magnitude [N].
        duration_s: how long each push lasts [s].
    """

    period_s: float = 2.0
    force_range_n: tuple[float, float] = (10.0, 100.0)
    duration_s: float = 0.2

    def __post_init__(self) -> None:
        if not (math.isfinite(self.period_s) and self.period_s > 0):
            raise ConfigError("pushes.period_s", self.period_s, "a period > 0 s")
        lo, hi = self.force_range_n
        if not (0.0 <= lo <= hi and math.isfinite(hi)):
            raise ConfigError("pushes.force_range_n", self.force_range_n, "0 <= min <= max [N]")
        if not (math.isfinite(self.duration_s) and 0 < self.duration_s <= self.period_s):
            raise ConfigError("pushes.duration_s", self.duration_s, "a duration in (0, period] s")


@dataclass(frozen=True)
class CollectProtocol:
    """What to collect (the paper's protocol by default).

    Attributes:
        robot: ``humanoid3d`` or ``biped2d``.
        teacher: ``wbmpc`` (the paper's whole-body NMPC) or ``kd`` (the kino-dynamic MPC
            driven by the drawn dts, :class:`~gaitnet_mpc.mpc.sequential.ScheduledDt`).
        sets: number of sets.
        seconds_total: simulated walking of all sets together [s], split equally.
        speed_range_mps: (min, max) of each set's constant forward command [m/s].
        duration_range_s: (min, max) of each stride's drawn duration [s].
        pushes: the impulses of every set's second half.
        course: course name or JSON path (flat by default); a seeded course gets the set's
            course seed.
        seed: protocol seed; every set's seeds derive from it and the set index.
        max_restarts: after a fall the set continues from a fresh standing start, at most
            this many times; then it ends short (and says so).
        teacher_preset: the teacher's settings preset (None: its default).
        teacher_overrides: ``KEY=VALUE`` overrides of the teacher's settings (``--set``).
    """

    robot: str = "humanoid3d"
    teacher: str = "wbmpc"
    sets: int = 15
    seconds_total: float = 600.0
    speed_range_mps: tuple[float, float] = (0.0, 1.0)
    duration_range_s: tuple[float, float] = (0.15, 0.40)
    pushes: PushProtocol = field(default_factory=PushProtocol)
    course: str = "flat"
    seed: int = 0
    max_restarts: int = 5
    teacher_preset: str | None = None
    teacher_overrides: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        from gaitnet_mpc.robots import ROBOTS

        if self.robot not in ROBOTS:
            raise ConfigError("--robot", self.robot, f"one of {sorted(ROBOTS)}")
        if self.teacher not in TEACHERS:
            raise ConfigError("--teacher", self.teacher, f"one of {list(TEACHERS)}")
        if not (isinstance(self.sets, int) and self.sets >= 1):
            raise ConfigError("--sets", self.sets, "an integer >= 1")
        if not (math.isfinite(self.seconds_total) and self.seconds_total / self.sets >= 1.0):
            raise ConfigError("--seconds", self.seconds_total, f">= 1 s per set ({self.sets} sets)")
        lo, hi = self.speed_range_mps
        if not (0.0 <= lo <= hi <= 2.0):
            raise ConfigError("speed_range_mps", self.speed_range_mps, "0 <= min <= max <= 2 m/s")
        lo, hi = self.duration_range_s
        if not (0.0 < lo <= hi and math.isfinite(hi)):
            raise ConfigError("duration_range_s", self.duration_range_s, "0 < min <= max [s]")
        if not (isinstance(self.max_restarts, int) and self.max_restarts >= 0):
            raise ConfigError("--max-restarts", self.max_restarts, "an integer >= 0")
        if isinstance(self.seed, bool) or not (isinstance(self.seed, int) and self.seed >= 0):
            raise ConfigError("--seed", self.seed, "an integer >= 0")  # as NumPy's seeds are

    @property
    def seconds_per_set(self) -> float:
        return self.seconds_total / self.sets

    def to_dict(self) -> dict[str, object]:
        return asdict(self)

    def fingerprint(self) -> str:
        """sha256 of the protocol's settings: a folder holds sets of one protocol only."""
        text = json.dumps(self.to_dict(), sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    def set_specs(self) -> list[SetSpec]:
        """The sets, in index order."""
        return [self.set_spec(i) for i in range(self.sets)]

    def set_spec(self, index: int) -> SetSpec:
        """Set ``index``: its speed and seeds depend only on ``seed`` and ``index``."""
        rng = np.random.default_rng([self.seed, index])
        lo, hi = self.speed_range_mps
        vx = float(rng.uniform(lo, hi))
        durations_seed, pushes_seed, course_seed = (int(x) for x in rng.integers(0, 2**31, 3))
        return SetSpec(
            protocol=self,
            index=index,
            vx_mps=vx,
            durations_seed=durations_seed,
            pushes_seed=pushes_seed,
            course_seed=course_seed,
        )


@dataclass(frozen=True)
class SetSpec:
    """One set: a constant command, its seeds, and its share of the protocol's time."""

    protocol: CollectProtocol
    index: int
    vx_mps: float
    durations_seed: int
    pushes_seed: int
    course_seed: int

    @property
    def name(self) -> str:
        return f"set_{self.index:03d}"

    @property
    def seconds(self) -> float:
        return self.protocol.seconds_per_set

    @property
    def push_start_s(self) -> float:
        """Set time [s] from which pushes come (the second half)."""
        return 0.5 * self.seconds

    def to_dict(self) -> dict[str, object]:
        return {
            "index": self.index,
            "vx_mps": self.vx_mps,
            "seconds": self.seconds,
            "push_start_s": self.push_start_s,
            "durations_seed": self.durations_seed,
            "pushes_seed": self.pushes_seed,
            "course_seed": self.course_seed,
        }
