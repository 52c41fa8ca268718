"""The 16 Gait-Net features of a step start (:data:`~gaitnet_mpc.dataset.schema.FEATURES`).

One function serves both sides: data collection (with the touchdown the teacher made) and
the controller (with the touchdown of the current plan), so the network sees at run time
exactly what it was trained on.

:func:`mirror_features` gives the features of the left-right mirror image of a step start
(the reflection ``y -> -y`` of the heading frame, left and right leg swapped): the robot
is symmetric, so a dt policy should give a step start and its mirror image the same dt.
"""

from __future__ import annotations

import numpy as np

from gaitnet_mpc.geometry import rot2, wrap_angle
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.state import RobotState


def step_features(
    state: RobotState,
    stance_foot: str,
    swing_foot: str,
    touchdown_m: np.ndarray,
    heading_rad: float = 0.0,
) -> np.ndarray:
    """(16,) features in ``FEATURE_NAMES`` order, from the state at the step start and the
    swing foot's touchdown ``touchdown_m`` (x, y[, z]) [m], in the frame of
    ``heading_rad`` (see :mod:`~gaitnet_mpc.dataset.schema`)."""
    to_heading = rot2(-heading_rad)
    com = state.com_world_m
    stance = state.foot_pos_world_m[stance_foot]
    com_rel = to_heading @ (com[:2] - stance[:2])
    v = state.com_vel_world_mps
    v_h = to_heading @ v[:2]
    w = state.base_ang_vel_world_radps
    w_h = to_heading @ w[:2]
    roll, pitch, yaw = (float(x) for x in state.base_rpy_rad)
    where = {stance_foot: stance[:2], swing_foot: np.asarray(touchdown_m, dtype=float)[:2]}
    feet = [to_heading @ (where[foot] - com[:2]) for foot in FEET]
    return np.array(
        [
            com_rel[0],
            com_rel[1],
            com[2] - stance[2],
            v_h[0],
            v_h[1],
            v[2],
            roll,
            pitch,
            float(wrap_angle(yaw - heading_rad)),
            w_h[0],
            w_h[1],
            w[2],
            feet[0][0],
            feet[0][1],
            feet[1][0],
            feet[1][1],
        ]
    )


#: Features whose sign the mirror ``y -> -y`` flips: y positions and velocities, roll, yaw,
#: and the angular velocities about x and z (an axial vector's x and z components flip
#: under a reflection of y).
_MIRROR_SIGN = np.array([1, -1, 1, 1, -1, 1, -1, 1, -1, -1, 1, -1, 1, -1, 1, -1], dtype=float)
#: The mirror swaps the legs: left foot (x, y) <-> right foot (x, y).
_MIRROR_ORDER = np.array([0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 14, 15, 12, 13])


def mirror_features(x: np.ndarray) -> np.ndarray:
    """(..., 16) the features of the mirror image of the step starts ``x`` (..., 16), in
    ``FEATURE_NAMES`` order (module docstring)."""
    return np.asarray(x, dtype=float)[..., _MIRROR_ORDER] * _MIRROR_SIGN
