"""Finding the ground with the swing foot when the terrain is unknown (``--blind``).

A blind controller (``TerrainKnowledge.blind``) plans each foothold at the height of its
stance foot. The ground under the foothold may be higher or lower:

* **higher**: the foot touches down before its swing ends. The first contact in the second
  half of the step ends the swing: the foot is held where it landed until its stance
  begins (the low level's swing PD, to the landing point at rest), instead of being driven
  on into the ground.
* **lower**: the swing aims ``search_depth_m`` below the stance foot's height
  (``KDWalkConfig.blind_search_depth_m``), so it keeps descending to that bounded depth
  and lands where the ground is.

The contact is the foot's contact sensor (:attr:`RobotState.foot_contact`), as a robot's
foot switch or force sensor would report it.
"""

from __future__ import annotations

import numpy as np

from gaitnet_mpc.state import RobotState

#: A contact before this fraction of the step is the lift-off's scuff, not a landing.
EARLY_TOUCHDOWN_PHASE = 0.5


class TouchdownSearch:
    """The blind swing's end: where a foot that touched down early is held."""

    def __init__(self) -> None:
        self.landed_at_m: np.ndarray | None = None

    def new_step(self) -> None:
        """A step starts: its swing foot has not landed."""
        self.landed_at_m = None

    def target(
        self,
        state: RobotState,
        swing_foot: str,
        phase_in_step: float,
        sampled: tuple[np.ndarray, np.ndarray, np.ndarray],
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The swing foot's target (position, velocity, acceleration): ``sampled`` (the
        swing trajectory's) until the foot lands, then the landing point at rest."""
        if (
            self.landed_at_m is None
            and phase_in_step >= EARLY_TOUCHDOWN_PHASE
            and state.foot_contact[swing_foot]
        ):
            self.landed_at_m = state.foot_pos_world_m[swing_foot].copy()
        if self.landed_at_m is None:
            return sampled
        return self.landed_at_m, np.zeros(3), np.zeros(3)


__all__ = ["EARLY_TOUCHDOWN_PHASE", "TouchdownSearch"]
