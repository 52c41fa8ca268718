"""Where a step's duration comes from when no policy chooses it: fixed, or drawn per stride.

The data-collection protocol of the paper (Sec. IV-A-1) draws the duration of every stride
uniformly from [150, 400] ms; the MPC sampling time of the step is that duration over the
``h'`` stages of a step. Drawn values are reproducible: step ``i``'s duration depends only
on the seed and ``i``, so the horizon can look ahead at the next steps' durations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.config import SEED_INTERVAL, SEED_REASON, bounded, check_ranges
from gaitnet_mpc.dt_policy import ACCEPTED_DT_INTERVAL, ACCEPTED_DT_REASON, NOMINAL_DT_S


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

    dt_s: float = bounded(NOMINAL_DT_S, ACCEPTED_DT_INTERVAL, "a sampling time", ACCEPTED_DT_REASON)
    duration_range_s: tuple[float, float] | None = bounded(
        None, "(0, 4] s", "a step duration", "20 stages of 0.2 s at most", ordered=True
    )
    stages_per_step: int = bounded(5, "[1, 20]", "an integer", "stages of a step; h' = 5")
    seed: int = bounded(0, SEED_INTERVAL, "a seed", SEED_REASON)

    def __post_init__(self) -> None:
        check_ranges(self)

    def dt_of_step(self, step_index: int) -> float:
        """MPC sampling time [s] of step ``step_index`` (0 = the first step)."""
        if self.duration_range_s is None:
            return self.dt_s
        lo, hi = self.duration_range_s
        u = np.random.default_rng([self.seed, int(step_index)]).uniform(lo, hi)
        return float(u) / self.stages_per_step
