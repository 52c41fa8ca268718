"""The CoM reference whose lateral part is the LIP sway orbit (``lateral_reference = "lip"``).

With a line foot (no roll moment) the CoM obeys ``y'' = omega^2 (y - p_y)`` about the
stance foot ``p_y``, so a gait with feet at ``+-b`` beside a centre line needs the periodic
sway of :func:`~gaitnet_mpc.gait.lip.lip_sway_orbit`; the straight line with ``l_y = 0`` is
only reachable with the feet under the CoM. The centre line runs along the commanded
velocity from the measured CoM, shifted sideways by a given offset (the controller's pull
back to the commanded path); x and the height are left to f_ref (NaN).
"""

from __future__ import annotations

import numpy as np

from gaitnet_mpc.gait.lip import lip_frequency, lip_sway_orbit, sway_phases
from gaitnet_mpc.geometry import heading_axes
from gaitnet_mpc.kinematics.reference import ReferenceTiming
from gaitnet_mpc.mpc.sequential import CoMReference


def lip_com_reference(
    timing: ReferenceTiming,
    com_xy_m: np.ndarray,
    com_height_m: float,
    heading_rad: float,
    lateral_offset_m: float,
    v_cmd_xy_mps: np.ndarray,
    half_width_m: float,
) -> CoMReference:
    """CoM path and velocity (h+1, 3) over ``timing``'s horizon (module docstring).

    ``com_xy_m``: the measured CoM (2,); ``com_height_m``: the pendulum's height;
    ``lateral_offset_m``: the centre line's offset from the CoM across ``heading_rad``;
    ``v_cmd_xy_mps``: the commanded velocity (2,, world); ``half_width_m``: the feet's
    half distance ``b`` from the centre line.
    """
    times = timing.times_s
    dts = np.asarray(timing.dts_s, dtype=float)
    contact = np.asarray(timing.contact, dtype=bool)
    h = dts.size
    side, tau, T = sway_phases(times, dts, contact, timing.time_in_step_s, timing.stages_per_step)
    w = lip_frequency(com_height_m)
    y_off, v_off = lip_sway_orbit(side, half_width_m, w, tau, T)
    e_y = heading_axes(heading_rad)[1]
    centre = com_xy_m + lateral_offset_m * e_y + times[:, None] * v_cmd_xy_mps
    p = np.full((h + 1, 3), np.nan)
    v = np.full((h + 1, 3), np.nan)
    p[:, :2] = centre + y_off[:, None] * e_y
    v[:, :2] = v_cmd_xy_mps + v_off[:, None] * e_y
    return CoMReference(p, v)


__all__ = ["lip_com_reference"]
