"""Tie groups of one foot's positions along a contact schedule (the foot ties of the CMPC).

In the CMPC sub-problem (:mod:`gaitnet_mpc.mpc.implicit_kd`) consecutive stages share the
foot position ``p_f`` unless the foot lifts off between them, so a stance foot stays put
over its contact phase and the stages of a swing hold the next touchdown location. The
stages sharing one ``p_f`` form a *tie group*; the group of the next touchdown is where the
foothold bounds of eq. 24 apply by default.
"""

from __future__ import annotations

import numpy as np


def tie_groups(contact_foot: np.ndarray) -> np.ndarray:
    """Group label (h,) of each stage's foot position for one foot.

    Consecutive stages share ``p_f`` unless the foot lifts off between them, so the groups
    are ``[initial stance] [swing + following stance] [swing + following stance] ...``.
    """
    c = np.asarray(contact_foot, dtype=bool)
    liftoff = c[:-1] & ~c[1:]
    return np.concatenate([[0], np.cumsum(liftoff)]).astype(int)


def next_touchdown_mask(contact_foot: np.ndarray) -> np.ndarray:
    """Stages (h,) bool of one foot's next touchdown (default mask of eq. 24).

    This is the first tie group holding a swing stage (its swing stages and the stance
    phase after them, see :func:`tie_groups`); all ``False`` if the foot never swings.
    """
    c = np.asarray(contact_foot, dtype=bool)
    if c.all():
        return np.zeros(c.shape, dtype=bool)
    groups = tie_groups(c)
    return groups == groups[int(np.argmax(~c))]


__all__ = ["next_touchdown_mask", "tie_groups"]
