"""Foothold boxes: the eq. (24) bounds ``p_min <= p_foot <= p_max`` a patch puts on a foot.

The box of one patch is :meth:`Patch.foothold_box`;
:func:`reachable_foothold_bounds` chooses the patch of the next touchdown by kinematic reach
(:meth:`Course.reachable_foothold_bounds`, one-step preview).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from gaitnet_mpc.terrain.fields import check_foot, point_xy
from gaitnet_mpc.terrain.patch import Patch


def rect_distance(
    x: float, y: float, x_min: float, x_max: float, y_min: float, y_max: float
) -> float:
    """Euclidean distance (m) from point (x, y) to a closed rectangle (0 inside)."""
    dx = max(x_min - x, 0.0, x - x_max)
    dy = max(y_min - y, 0.0, y - y_max)
    return math.hypot(dx, dy)


def reachable_foothold_bounds(
    patches: Sequence[Patch],
    p_com_td_xy: ArrayLike,
    foot: str,
    p_nominal_xy: ArrayLike,
    *,
    reach_x_m: float = 0.12,
    reach_y_m: float = 0.25,
    margin_m: float = 0.03,
    margin_y_m: float | None = None,
    reach_back_m: float | None = None,
) -> tuple[np.ndarray, np.ndarray, int | None]:
    """Eq. (24) box for the next foothold, chosen by kinematic reach (one-step preview).

    The foot can land only within ``reach`` of the CoM at touchdown, ``p_com_td_xy``
    (the hip is above it): ``reach_x_m`` ahead along x, ``reach_back_m`` behind (default
    the same), ``reach_y_m`` across. Among the ``patches`` that allow ``foot``, each shrunk by
    ``margin_m`` (``margin_y_m`` across, default the same), those whose box meets that
    window are candidates; the one whose part inside the window is closest to the
    nominal foothold ``p_nominal_xy`` wins, and the bounds are its whole shrunk box (the
    window only chooses the patch; the MPC keeps the freedom to step beyond it). If no
    patch meets the window, the patch closest to the window is used.

    Returns:
        ``(p_min (3,), p_max (3,), patch index or None)``; z bounds are the patch top.
    """
    foot = check_foot(foot)
    xc, yc = point_xy(p_com_td_xy, "p_com_td_xy")
    xn, yn = point_xy(p_nominal_xy, "p_nominal_xy")
    back_m = reach_x_m if reach_back_m is None else reach_back_m
    win = (xc - back_m, xc + reach_x_m, yc - reach_y_m, yc + reach_y_m)
    best: tuple[float, int] | None = None
    fallback: tuple[float, int] | None = None
    for i, patch in enumerate(patches):
        if not patch.allows(foot):
            continue
        lo, hi = patch.foothold_box(margin_m, margin_y_m)
        box = (max(lo[0], win[0]), min(hi[0], win[1]), max(lo[1], win[2]), min(hi[1], win[3]))
        if box[0] <= box[1] and box[2] <= box[3]:
            dx = max(box[0] - xn, 0.0, xn - box[1])
            dy = max(box[2] - yn, 0.0, yn - box[3])
            score = dx * dx + dy * dy
            if best is None or score < best[0]:
                best = (score, i)
        else:
            gap = rect_distance(xc, yc, lo[0], hi[0], lo[1], hi[1])
            if fallback is None or gap < fallback[0]:
                fallback = (gap, i)
    chosen = best or fallback
    if chosen is None:
        return np.array([win[0], win[2], 0.0]), np.array([win[1], win[3], 0.0]), None
    i = chosen[1]
    lo, hi = patches[i].foothold_box(margin_m, margin_y_m)
    return lo, hi, i
