"""What ``reproduce fig6`` runs: its settings (the identity of a results folder), the
methods and gap widths of the paper's Fig. 6, the course file of each layout, and the
cases (method x width x seed)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gaitnet_mpc.errors import ConfigError

ROBOT = "biped2d"
#: The paper's three methods, in the order of Fig. 6 (a), (b), (c).
METHODS = ("kd", "kd-optdt", "gaitnet")
METHOD_LABELS = {
    "kd": "(1) fixed dt",
    "kd-optdt": "(2) dt optimised (NLP)",
    "gaitnet": "(3) Gait-Net",
}
#: Gap widths [m]: the paper's range [5, 15] cm in 2.5 cm steps.
WIDTHS_M = (0.05, 0.075, 0.10, 0.125, 0.15)


@dataclass(frozen=True)
class Fig6Settings:
    """What ``reproduce fig6`` measures (its identity: resuming a folder checks it).

    Attributes:
        methods: controller names among :data:`METHODS`.
        widths_m: gap widths [m], each in (0, 0.3].
        seeds: layouts per width (seeds ``first_seed`` .. ``first_seed + seeds - 1``).
        first_seed: the first layout seed (0: the reported seeds; tune on >= 100).
        gaitnet_weights: Gait-Net's weights, a shipped name or a path (None: the
            robot's default).
        vx_mps: forward command [m/s].
        duration_s: simulated time per case [s].
        fixed_dt_s: the dt of method (1) [s].
        quick: the small grid of the test suite (recorded, for the report).
    """

    methods: tuple[str, ...] = METHODS
    widths_m: tuple[float, ...] = WIDTHS_M
    seeds: int = 10
    first_seed: int = 0
    gaitnet_weights: str | None = None
    vx_mps: float = 0.5
    duration_s: float = 10.0
    fixed_dt_s: float = 0.045
    quick: bool = False

    def __post_init__(self) -> None:
        if not self.methods or not set(self.methods) <= set(METHODS):
            raise ConfigError("methods", self.methods, f"names among {list(METHODS)}")
        if not self.widths_m or not all(0 < w <= 0.3 for w in self.widths_m):
            raise ConfigError("widths_m", self.widths_m, "gap widths in (0, 0.3] m")
        if isinstance(self.seeds, bool) or not (isinstance(self.seeds, int) and self.seeds >= 1):
            raise ConfigError("--seeds", self.seeds, "an integer >= 1")
        if isinstance(self.first_seed, bool) or not (
            isinstance(self.first_seed, int) and 0 <= self.first_seed <= 2**31
        ):
            raise ConfigError("--first-seed", self.first_seed, "an integer in [0, 2^31]")
        if not 0.1 <= self.vx_mps <= 1.0:
            raise ConfigError("vx_mps", self.vx_mps, "a forward speed in [0.1, 1] m/s")
        if not 1.0 <= self.duration_s <= 60.0:
            raise ConfigError("duration_s", self.duration_s, "a duration in [1, 60] s")
        if not 0.03 <= self.fixed_dt_s <= 0.06:
            raise ConfigError("fixed_dt_s", self.fixed_dt_s, "Table V's [0.03, 0.06] s")

    @classmethod
    def quick_settings(cls) -> Fig6Settings:
        """One layout of 10 cm gaps, 3 s per method: the test suite's run."""
        return cls(widths_m=(0.10,), seeds=1, duration_s=3.0, quick=True)

    def to_dict(self) -> dict[str, Any]:
        return {
            "methods": list(self.methods),
            "widths_m": list(self.widths_m),
            "seeds": self.seeds,
            "first_seed": self.first_seed,
            "gaitnet_weights": self.gaitnet_weights,
            "vx_mps": self.vx_mps,
            "duration_s": self.duration_s,
            "fixed_dt_s": self.fixed_dt_s,
            "quick": self.quick,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Fig6Settings:
        """The settings :meth:`to_dict` wrote."""
        return cls(
            methods=tuple(d["methods"]),
            widths_m=tuple(float(w) for w in d["widths_m"]),
            seeds=int(d["seeds"]),
            first_seed=int(d["first_seed"]),
            gaitnet_weights=d["gaitnet_weights"],
            vx_mps=float(d["vx_mps"]),
            duration_s=float(d["duration_s"]),
            fixed_dt_s=float(d["fixed_dt_s"]),
            quick=bool(d["quick"]),
        )

    @property
    def seed_list(self) -> range:
        """The layout seeds of every width."""
        return range(self.first_seed, self.first_seed + self.seeds)

    @property
    def strip_width_m(self) -> float:
        """The width of the strips' layout (the widest; seed 0)."""
        return max(self.widths_m)


def course_file(width_m: float, seed: int) -> str:
    """The course file of a layout, relative to the folder."""
    return f"courses/gap-row-{round(width_m * 100, 3):g}cm-seed{seed}.json"


def make_cases(settings: Fig6Settings) -> list[dict[str, Any]]:
    """Every case, widths outermost, then seeds, then methods."""
    cases = []
    for width in settings.widths_m:
        for seed in settings.seed_list:
            for method in settings.methods:
                cm = round(width * 100, 3)
                cases.append(
                    {
                        "key": f"{method}/{cm:g}cm/seed{seed}",
                        "method": method,
                        "width_m": width,
                        "seed": seed,
                        "course_file": course_file(width, seed),
                        "strip": seed == settings.first_seed and width == settings.strip_width_m,
                        "settings": settings.to_dict(),
                    }
                )
    return cases


__all__ = [
    "METHODS",
    "METHOD_LABELS",
    "ROBOT",
    "WIDTHS_M",
    "Fig6Settings",
    "course_file",
    "make_cases",
]
