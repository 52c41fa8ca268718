"""Landing areas: the patches with the obstacles' footprints cut out.

An obstacle is not a foothold: a foot set down over part of it rests tilted on its edge,
and a foot under it is the obstacle's top pressed into the sole. So the next touchdown's
eq. (24) box is chosen among the parts of the patches that no obstacle covers
(:meth:`Course.reachable_foothold_bounds`). A patch minus one footprint is written as the
*maximal* rectangles of the difference: the strips before, after, right and left of the
obstacle, each as long or as wide as the patch allows. They may overlap (a box across
part of a walkway leaves the strip beside it as well as those before and after); each is
a candidate box of its own. The footprint is widened by a clearance before it is cut out,
so that the eq. (24) margin (the foot's half-length and the landing error, as at a patch's
edge) plus that clearance keeps the foot off the obstacle's side: at an edge the toe may
overhang a little, against an obstacle it presses on it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from gaitnet_mpc.terrain.fields import EPS_M
from gaitnet_mpc.terrain.patch import Obstacle, Patch

__all__ = ["landing_areas", "subtract_footprint"]


#: A footprint ``(x_min, x_max, y_min, y_max)`` [m].
Rect = tuple[float, float, float, float]


def _footprint(ob: Obstacle, clearance_m: float) -> Rect:
    c = clearance_m
    return (ob.x_min - c, ob.x_max + c, ob.y_min - c, ob.y_max + c)


def _overlaps(p: Patch, r: Rect) -> bool:
    return (
        r[0] < p.x_max - EPS_M
        and r[1] > p.x_min + EPS_M
        and r[2] < p.y_max - EPS_M
        and r[3] > p.y_min + EPS_M
    )


def subtract_footprint(patch: Patch, footprint: Rect) -> list[Patch]:
    """The maximal rectangles of ``patch`` minus ``footprint`` (``[patch]`` if they do
    not overlap, ``[]`` if the footprint covers the patch). Each piece keeps the patch's
    top and ``feet``."""
    if not _overlaps(patch, footprint):
        return [patch]
    x_min, x_max, y_min, y_max = footprint
    pieces = []
    if x_min > patch.x_min + EPS_M:  # before
        pieces.append(replace(patch, x_max=x_min))
    if x_max < patch.x_max - EPS_M:  # after
        pieces.append(replace(patch, x_min=x_max))
    if y_min > patch.y_min + EPS_M:  # right of it
        pieces.append(replace(patch, y_max=y_min))
    if y_max < patch.y_max - EPS_M:  # left of it
        pieces.append(replace(patch, y_min=y_max))
    return pieces


def _contains(outer: Patch, inner: Patch) -> bool:
    return (
        outer.x_min <= inner.x_min + EPS_M
        and inner.x_max <= outer.x_max + EPS_M
        and outer.y_min <= inner.y_min + EPS_M
        and inner.y_max <= outer.y_max + EPS_M
    )


def landing_areas(
    patches: Sequence[Patch], obstacles: Sequence[Obstacle], clearance_m: float = 0.0
) -> tuple[tuple[Patch, ...], tuple[int, ...]]:
    """The parts of ``patches`` that no obstacle footprint, widened by ``clearance_m`` on
    every side [m], covers (module docstring).

    Returns:
        ``(areas, parent)``: the areas, and for each the index of the patch it was cut
        from. A patch no obstacle touches is its own single area.
    """
    areas: list[Patch] = []
    parent: list[int] = []
    rects = [_footprint(ob, clearance_m) for ob in obstacles]
    for i, patch in enumerate(patches):
        pieces = [patch]
        for r in rects:
            if not _overlaps(patch, r):
                continue
            cut = [q for piece in pieces for q in subtract_footprint(piece, r)]
            # drop pieces inside another (the maximal rectangles of a difference of
            # several footprints repeat each other)
            pieces = [
                q
                for k, q in enumerate(cut)
                if not any(
                    _contains(o, q) and (not _contains(q, o) or m < k)
                    for m, o in enumerate(cut)
                    if m != k
                )
            ]
        areas.extend(pieces)
        parent.extend([i] * len(pieces))
    return tuple(areas), tuple(parent)
