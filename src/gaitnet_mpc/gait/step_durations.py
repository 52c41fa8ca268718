"""Where a step's duration comes from when no policy chooses it: fixed, or drawn per stride.

The data-collection protocol of the paper (Sec. IV-A-1) draws the duration of every stride
uniformly from [150, 400] ms; the MPC sampling time of the step is that duration over the
``h'`` stages of a step. Drawn values are reproducible: step ``i``'s duration depends only
on the seed and ``i``, so the horizon can look ahead at the next steps' durations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.dt_policy import NOMINAL_DT_S
from gaitnet_mpc.errors import ConfigError


@dataclass(frozen=True)
class StepDurations:
    """Step ``i``'s MPC sampling time: ``dt_s`` for every step, or with
    ``duration_range_s`` a duration drawn uniformly from that range divided by
    ``stages_per_step``.

    Attributes:
        dt_s: fixed sampling time [s] (used when ``duration_range_s`` is None).
        duration_range_s: (min, max) step duration [s] to draw from, e.g. (0.15, 0.40).
        stages_per_step: ``h'``, stages of one step.
        seed: seed of the draws.
    """

    dt_s: float = NOMINAL_DT_S
    duration_range_s: tuple[float, float] | None = None
    stages_per_step: int = 5
    seed: int = 0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.dt_s) and self.dt_s > 0.0):
            raise ConfigError("dt_s", self.dt_s, "a sampling time > 0 s")
        r = self.duration_range_s
        if r is not None and not (len(r) == 2 and 0.0 < r[0] <= r[1] and math.isfinite(r[1])):
            raise ConfigError("duration_range_s", r, "(min, max) with 0 < min <= max [s]")
        if self.stages_per_step < 1:
            raise ConfigError("stages_per_step", self.stages_per_step, "an integer >= 1")

    def dt_of_step(self, step_index: int) -> float:
        """MPC sampling time [s] of step ``step_index`` (0 = the first step)."""
        if self.duration_range_s is None:
            return self.dt_s
        lo, hi = self.duration_range_s
        u = np.random.default_rng([self.seed, int(step_index)]).uniform(lo, hi)
        return float(u) / self.stages_per_step
