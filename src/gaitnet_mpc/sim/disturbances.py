"""External disturbances: impulses at the trunk CoM and unknown payloads."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.errors import ConfigError

#: Bounds on a push, far beyond the paper's pushes (10-100 N for 0.2 s, i.e. 2-20 N s) yet
#: ruling out forces that only make the simulation diverge. 100 N s gives the 16 kg
#: humanoid 6 m/s and the 10 kg biped 10 m/s: no controller can recover from more.
MAX_PUSH_FORCE_N = 1000.0  # force magnitude [N]
MAX_PUSH_DURATION_S = 5.0  # duration [s]
MAX_PUSH_IMPULSE_NS = 100.0  # impulse magnitude [N s]
#: The fields :class:`Push` checks, as the keys of ``--push`` and of a ``[[pushes]]`` table
#: of ``scenario.toml`` that set them (the names their errors give).
_KEYS = {
    "push.t": ("t", "t_s"),
    "push.dur": ("dur", "duration_s"),
    "push.f": ("fx,fy,fz", "force_world_n"),
    "push.force": ("fx,fy,fz", "force_world_n"),
    "push.impulse": ("impulse", "force_world_n x duration_s"),
}


@dataclass(frozen=True)
class Push:
    """A constant force ``force_world_n`` (3,) [N] at the trunk CoM during [t_s, t_s + duration_s).

    The impulse is ``force_world_n * duration_s`` [N s]. The force magnitude is at most
    :data:`MAX_PUSH_FORCE_N`, the duration at most :data:`MAX_PUSH_DURATION_S` and the
    impulse magnitude at most :data:`MAX_PUSH_IMPULSE_NS`.
    """

    t_s: float
    force_world_n: tuple[float, float, float]
    duration_s: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.t_s) and self.t_s >= 0):
            raise ConfigError("push.t", self.t_s, "a finite time >= 0 s")
        if not (np.isfinite(self.duration_s) and 0 < self.duration_s <= MAX_PUSH_DURATION_S):
            raise ConfigError(
                "push.dur", self.duration_s, f"a duration in (0, {MAX_PUSH_DURATION_S:g}] s"
            )
        if not np.all(np.isfinite(self.force_world_n)):
            raise ConfigError("push.f", self.force_world_n, "finite forces [N]")
        force = float(np.linalg.norm(self.force_world_n))
        if force > MAX_PUSH_FORCE_N:
            raise ConfigError(
                "push.force", self.force_world_n, f"a force magnitude <= {MAX_PUSH_FORCE_N:g} N"
            )
        impulse = force * self.duration_s
        if impulse > MAX_PUSH_IMPULSE_NS:
            raise ConfigError(
                "push.impulse",
                f"{impulse:g} N s ({force:g} N for {self.duration_s:g} s)",
                f"an impulse magnitude <= {MAX_PUSH_IMPULSE_NS:g} N s",
            )

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
            if key in values:
                raise ConfigError("--push", text, f"each key once ('{key}' is given twice)")
            try:
                values[key] = float(raw)
            except ValueError:
                raise ConfigError(f"--push {key}", raw, "a number") from None
            if key in ("fx", "fy", "fz") and not abs(values[key]) <= MAX_PUSH_FORCE_N:
                bound = f"{MAX_PUSH_FORCE_N:g}"
                raise ConfigError(f"--push {key}", values[key], f"a force in [-{bound}, {bound}] N")
        for key in ("t", "dur"):
            if key not in values:
                raise ConfigError("--push", text, f"a value for '{key}'")
        force = (values.get("fx", 0.0), values.get("fy", 0.0), values.get("fz", 0.0))
        try:
            return cls(t_s=values["t"], force_world_n=force, duration_s=values["dur"])
        except ConfigError as exc:
            field = f"--push {_KEYS[exc.field][0]}" if exc.field in _KEYS else exc.field
            raise ConfigError(field, exc.value, exc.expected) from None

    @classmethod
    def from_table(cls, raw: object, key: str) -> Push:
        """The push of a ``[[pushes]]`` entry of ``scenario.toml`` (``t_s``,
        ``force_world_n = [fx, fy, fz]``, ``duration_s``); ``key`` names it in errors."""
        if not isinstance(raw, dict) or set(raw) != {"t_s", "force_world_n", "duration_s"}:
            raise ConfigError(key, raw, "a table with t_s, force_world_n, duration_s")
        force = raw["force_world_n"]
        if not isinstance(force, list) or len(force) != 3:
            raise ConfigError(f"{key}.force_world_n", force, "[fx, fy, fz] in N")
        for name, value in (("t_s", raw["t_s"]), ("duration_s", raw["duration_s"])):
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ConfigError(f"{key}.{name}", value, "a number")
        for value in force:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ConfigError(f"{key}.force_world_n", value, "a number")
        fx, fy, fz = (float(v) for v in force)
        try:
            return cls(float(raw["t_s"]), (fx, fy, fz), float(raw["duration_s"]))
        except ConfigError as exc:
            field = f"{key}.{_KEYS[exc.field][1]}" if exc.field in _KEYS else exc.field
            raise ConfigError(field, exc.value, exc.expected) from None


def protocol_pushes(
    seed: int,
    t_start_s: float,
    t_end_s: float,
    period_s: float = 2.0,
    force_range_n: tuple[float, float] = (10.0, 100.0),
    duration_s: float = 0.2,
) -> tuple[Push, ...]:
    """The pushes of the paper's data-collection protocol (Sec. IV-A-1): every ``period_s``
    from ``t_start_s`` (exclusive of ``t_end_s``), a horizontal force at the trunk CoM of a
    magnitude drawn uniformly from ``force_range_n`` [N], in a direction drawn uniformly,
    for ``duration_s``. Reproducible from ``seed``."""
    if not (np.isfinite(period_s) and period_s > 0):
        raise ConfigError("period_s", period_s, "a period > 0 s")
    lo, hi = force_range_n
    if not 0.0 <= lo <= hi:
        raise ConfigError("force_range_n", force_range_n, "(min, max) with 0 <= min <= max [N]")
    rng = np.random.default_rng(seed)
    pushes = []
    t = float(t_start_s)
    while t < t_end_s - 1e-9:
        force = rng.uniform(lo, hi)
        angle = rng.uniform(-np.pi, np.pi)
        f = (force * float(np.cos(angle)), force * float(np.sin(angle)), 0.0)
        pushes.append(Push(t, f, duration_s))
        t += period_s
    return tuple(pushes)
