"""External disturbances: impulses at the trunk CoM and unknown payloads."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.errors import ConfigError


@dataclass(frozen=True)
class Push:
    """A constant force ``force_world_n`` (3,) [N] at the trunk CoM during [t_s, t_s + duration_s).

    The impulse is ``force_world_n * duration_s`` [N s].
    """

    t_s: float
    force_world_n: tuple[float, float, float]
    duration_s: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.t_s) and self.t_s >= 0):
            raise ConfigError("push.t", self.t_s, "a finite time >= 0 s")
        if not (np.isfinite(self.duration_s) and self.duration_s > 0):
            raise ConfigError("push.dur", self.duration_s, "a finite duration > 0 s")
        if not np.all(np.isfinite(self.force_world_n)):
            raise ConfigError("push.f", self.force_world_n, "finite forces [N]")

    def active(self, t_s: float) -> bool:
        return self.t_s <= t_s < self.t_s + self.duration_s

    @property
    def impulse_ns(self) -> np.ndarray:
        return np.asarray(self.force_world_n) * self.duration_s

    @classmethod
    def parse(cls, text: str) -> Push:
        """Parse ``t=3,fx=50,fy=0,fz=0,dur=0.1`` (fx, fy, fz default 0; t and dur required)."""
        allowed = {"t", "fx", "fy", "fz", "dur"}
        values: dict[str, float] = {}
        for item in text.split(","):
            key, sep, raw = item.partition("=")
            key = key.strip()
            if not sep or key not in allowed:
                raise ConfigError(
                    "--push", text, f"comma-separated key=value with keys {sorted(allowed)}"
                )
            try:
                values[key] = float(raw)
            except ValueError:
                raise ConfigError(f"--push {key}", raw, "a number") from None
        for key in ("t", "dur"):
            if key not in values:
                raise ConfigError("--push", text, f"a value for '{key}'")
        force = (values.get("fx", 0.0), values.get("fy", 0.0), values.get("fz", 0.0))
        return cls(t_s=values["t"], force_world_n=force, duration_s=values["dur"])
