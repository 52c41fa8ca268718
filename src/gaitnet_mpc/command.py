"""The user's velocity command, and how walking controllers follow it over time.

The command ``(vx, vy)`` (heading frame) is ramped up from rest at a bounded acceleration,
``k(t) = min(1, a t / max(|vx|, |vy|))`` of it applied ``t`` after the start, and the
commanded heading is the initial yaw plus the integrated yaw rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gaitnet_mpc.errors import ConfigError

#: Each field of :class:`Command` and the ``gaitnet-mpc run`` option that sets it (the
#: name its errors give; a scenario file names its own key instead).
OPTIONS = {"vx_mps": "--vx", "vy_mps": "--vy", "yaw_rate_radps": "--yaw-rate"}


@dataclass(frozen=True)
class Command:
    """User velocity command in the world frame."""

    vx_mps: float = 0.0
    vy_mps: float = 0.0
    yaw_rate_radps: float = 0.0

    def __post_init__(self) -> None:
        for name, value, bound in (
            ("vx_mps", self.vx_mps, 1.5),
            ("vy_mps", self.vy_mps, 0.5),
            ("yaw_rate_radps", self.yaw_rate_radps, 1.5),
        ):
            if not (math.isfinite(value) and abs(value) <= bound):
                raise ConfigError(OPTIONS[name], value, f"a finite value in [-{bound}, {bound}]")

    def to_dict(self) -> dict[str, float]:
        return {"vx_mps": self.vx_mps, "vy_mps": self.vy_mps, "yaw_rate_radps": self.yaw_rate_radps}

    @classmethod
    def from_table(cls, values: dict[str, float], key: str) -> Command:
        """The command of a file's table ``key``; an error names ``key.<field>``, not the
        ``run`` option that sets it."""
        try:
            return cls(**values)
        except ConfigError as exc:
            names = {option: f"{key}.{name}" for name, option in OPTIONS.items()}
            raise ConfigError(names.get(exc.field, exc.field), exc.value, exc.expected) from None


@dataclass(frozen=True)
class CommandProfile:
    """Ramped velocity command and commanded heading of one episode.

    Attributes:
        command: the velocity command.
        t0_s: start time of the episode [s].
        yaw0_rad: measured heading at the start [rad].
        max_accel_mps2: the command is ramped up from rest at this rate [m/s^2].
    """

    command: Command
    t0_s: float
    yaw0_rad: float
    max_accel_mps2: float

    @property
    def _v_max_mps(self) -> float:
        return max(abs(self.command.vx_mps), abs(self.command.vy_mps), 1e-9)

    def ramp(self, t_since_start_s: float) -> float:
        """Fraction ``k`` of the command applied ``t_since_start_s`` after the start [-]."""
        return min(1.0, max(t_since_start_s, 0.0) * self.max_accel_mps2 / self._v_max_mps)

    def ramp_integral_s(self, t_since_start_s: float) -> float:
        """``int_0^t k dt`` [s]: the distance covered along a fixed commanded velocity
        ``v`` by then is ``v`` times this."""
        t = t_since_start_s
        t_ramp = self._v_max_mps / self.max_accel_mps2
        return t * t / (2 * t_ramp) if t < t_ramp else t - t_ramp / 2

    def heading_rad(self, t_s: float) -> float:
        """Commanded heading [rad] at (absolute) time ``t_s``."""
        return self.yaw0_rad + self.command.yaw_rate_radps * (t_s - self.t0_s)
