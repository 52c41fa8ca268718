"""The largest survivable level of a disturbance on a grid, by bisection (``gaitnet-mpc
sweep``'s push and payload modes), with a scan below the bound where survival is not
monotone (``docs/design/push_sweep.md``)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass
class Bisection:
    """A bisection's outcome on the grid ``i * resolution``, ``i`` in ``[0, n]``.

    Attributes:
        survived: the largest grid index found survivable (None: index 0 fell).
        failed: the smallest failing index above it (None: the top survived).
        spot_failed: indices below ``survived`` that were run as checks and fell.
        probes: every index run, in order, with whether it was survived.
        bisected: the bisection's own bound, before the scan lowered it (equal to
            ``survived`` without a scan or where the scan found no fall).
    """

    survived: int | None
    failed: int | None
    spot_failed: list[int] = field(default_factory=list)
    probes: list[tuple[int, bool]] = field(default_factory=list)
    bisected: int | None = None

    @property
    def non_monotone(self) -> bool:
        return bool(self.spot_failed)


def bisect_largest(
    survives: Callable[[int], bool],
    n: int,
    spot_fractions: tuple[float, ...] = (),
    scan_from: float | None = None,
) -> Bisection:
    """The largest ``i`` in ``[0, n]`` with ``survives(i)``, assuming monotonicity (every
    smaller index survives too); each index is run at most once, the ends only when the
    bisection reaches them.

    ``scan_from`` (e.g. 0.5) drops that assumption above a fraction of the bound: every
    index from ``floor(scan_from * bound) + 1`` up to the bound is run in order, and at the
    first that falls the bound is bisected again below it (and scanned again). A survived
    force above a fall (an island: a push survived by luck of where the foot happens to
    land) then does not count. ``spot_fractions`` (e.g. 0.5: half the found bound) are run
    last, as checks of the assumption below the scan: one that falls makes the result
    non-monotone."""
    seen: dict[int, bool] = {}
    probes: list[tuple[int, bool]] = []

    def ok(i: int) -> bool:
        if i not in seen:
            seen[i] = bool(survives(i))
            probes.append((i, seen[i]))
        return seen[i]

    def bisect(lo: int, hi: int) -> tuple[int, int]:  # lo: survived or assumed; hi: failed
        while hi - lo > 1:
            mid = (lo + hi) // 2
            lo, hi = (mid, hi) if ok(mid) else (lo, mid)
        return lo, hi

    lo, hi = bisect(0, n)
    failed: int | None = hi
    if hi == n and ok(n):  # the top of the range is run only if reached
        lo, failed = n, None
    bisected = lo
    while scan_from is not None and lo > 0:
        fell = next((i for i in range(math.floor(lo * scan_from) + 1, lo) if not ok(i)), None)
        if fell is None:
            break
        below = max((i for i, alive in seen.items() if alive and i < fell), default=0)
        lo, failed = bisect(below, fell)
    if lo == 0 and not ok(0):
        return Bisection(None, 0, [], probes, None)
    spot_failed = []
    for frac in spot_fractions:
        i = math.floor(lo * frac)
        if 0 < i < lo and not ok(i):
            spot_failed.append(i)
    return Bisection(lo, failed, sorted(set(spot_failed)), probes, bisected)


__all__ = ["Bisection", "bisect_largest"]
