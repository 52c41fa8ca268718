"""Stage timing of the MPC horizon as the reference trajectory needs it.

:class:`ReferenceTiming` holds the stage durations ``dt_k`` of the horizon measured from
*now* (stage 0 may be the unelapsed part of the current stage), the contact sequence, the
boundary times ``t_k = sum(dts_s[:k])`` and the finite-difference matrix on them that turns
a configuration path into velocities (``v_ref``, eq. 11's input). Gait-Net's sampling time
(Algorithm 1, line 8) enters through :meth:`ReferenceTiming.with_dts`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.schedule import GaitHorizon
from gaitnet_mpc.robots.spec import FEET

__all__ = ["ReferenceTiming"]

_N_FEET = len(FEET)


def _is_number(value: object) -> bool:
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)


@dataclass(frozen=True, eq=False)
class ReferenceTiming:
    """Stage timing and contact sequence of the horizon, as the reference needs it.

    Attributes:
        dts_s: (h,) duration of each stage from *now* [s]; stage 0 may be the unelapsed
            part of the current stage (see :meth:`from_horizon`). Boundary ``k`` lies at
            ``t_k = sum(dts_s[:k])``.
        contact: (h, 2) bool stance mask per stage, columns in ``FEET`` order.
        time_in_step_s: time since the current step began [s]; a foot swinging in stage 0
            lifted off this long ago.
        stages_per_step: ``h'`` [-]; a swing that runs past the horizon end lasts
            ``h' * full_dts_s[first stage of the swing]``.
        full_dts_s: (h,) full stage lengths [s] (differs from ``dts_s`` only in a partial
            stage 0); None: ``dts_s``.
    """

    dts_s: np.ndarray
    contact: np.ndarray
    time_in_step_s: float = 0.0
    stages_per_step: int = 5
    full_dts_s: np.ndarray | None = None

    def __post_init__(self) -> None:
        dts = np.array(self.dts_s, dtype=float).reshape(-1)
        if dts.size == 0 or not np.all(np.isfinite(dts)) or np.any(dts <= 0.0):
            raise ConfigError("dts_s", self.dts_s, "(h,) finite stage durations > 0 s, h >= 1")
        contact = np.array(self.contact, dtype=bool)
        if contact.shape != (dts.size, _N_FEET):
            raise ConfigError("contact", self.contact, f"a ({dts.size}, {_N_FEET}) bool mask")
        t_in = self.time_in_step_s
        if not (_is_number(t_in) and math.isfinite(t_in) and t_in >= 0.0):
            raise ConfigError("time_in_step_s", t_in, "a finite time >= 0 s")
        n = self.stages_per_step
        if not isinstance(n, int | np.integer) or isinstance(n, bool) or n < 1:
            raise ConfigError("stages_per_step", n, "an integer >= 1")
        full = dts if self.full_dts_s is None else np.array(self.full_dts_s, dtype=float)
        if full.shape != dts.shape or not np.all(np.isfinite(full)) or np.any(full <= 0.0):
            raise ConfigError("full_dts_s", self.full_dts_s, f"({dts.size},) durations > 0 s")
        for name, arr in (("dts_s", dts), ("contact", contact), ("full_dts_s", full)):
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "time_in_step_s", float(t_in))
        object.__setattr__(self, "stages_per_step", int(n))

    @property
    def horizon(self) -> int:
        """Number of stages ``h``."""
        return int(self.dts_s.size)

    @property
    def stage_lengths_s(self) -> np.ndarray:
        """(h,) full stage lengths [s]: ``full_dts_s`` (never None after construction)."""
        assert self.full_dts_s is not None
        return self.full_dts_s

    @cached_property
    def times_s(self) -> np.ndarray:
        """(h+1,) stage boundary times from now [s], ``t_0 = 0`` (read-only)."""
        t = np.concatenate([[0.0], np.cumsum(self.dts_s)])
        t.flags.writeable = False
        return t

    @cached_property
    def derivative_matrix(self) -> np.ndarray:
        """(h+1, h+1) finite-difference matrix ``D`` on the boundary times: ``D @ x`` is
        ``numpy.gradient(x, times_s, axis=0, edge_order=2)`` (three-point, second order on
        the non-uniform grid; two-point for ``h = 1``)."""
        d = _derivative_matrix(self.times_s)
        d.flags.writeable = False
        return d

    def with_dts(self, dts_s: ArrayLike) -> ReferenceTiming:
        """Same contact sequence with new stage durations (e.g. a Gait-Net dt, Alg. 1 l. 8).

        The full stage lengths follow the new ``dts_s`` except for a partial stage 0,
        whose full length is scaled with it.
        """
        dts = np.array(dts_s, dtype=float).reshape(-1)
        if dts.shape != self.dts_s.shape or not (np.all(np.isfinite(dts)) and dts.min() > 0.0):
            raise ConfigError("dts_s", dts_s, f"({self.horizon},) finite durations > 0 s")
        full = dts.copy()
        full[0] = dts[0] * float(self.stage_lengths_s[0] / self.dts_s[0])
        dts.flags.writeable = full.flags.writeable = False
        # the other fields were validated already: skip __post_init__ (runs in the f_IK loop)
        new = object.__new__(ReferenceTiming)
        for name, value in (
            ("dts_s", dts),
            ("contact", self.contact),
            ("time_in_step_s", self.time_in_step_s),
            ("stages_per_step", self.stages_per_step),
            ("full_dts_s", full),
        ):
            object.__setattr__(new, name, value)
        if np.array_equal(dts, self.dts_s):  # the same durations (every f_IK call of a
            # sequential solve): share the read-only boundary times and D, functions of
            # dts_s alone, instead of recomputing them (cached_property reads __dict__)
            new.__dict__["times_s"] = self.times_s
            new.__dict__["derivative_matrix"] = self.derivative_matrix
        return new

    @classmethod
    def from_horizon(
        cls,
        horizon: GaitHorizon,
        stages_per_step: int = 5,
        partial_first_stage: bool = True,
        min_first_stage_s: float = 1e-3,
    ) -> ReferenceTiming:
        """Timing from a :class:`gaitnet_mpc.gait.GaitHorizon` snapshot.

        Args:
            horizon: the schedule's snapshot.
            stages_per_step: ``h'`` of the schedule (``GaitScheduleConfig.stages_per_step``).
            partial_first_stage: True: boundary 0 is *now* and stage 0 lasts
                ``max(first_stage_remaining_s, min_first_stage_s)``; False: boundary 0 is
                the start of the current stage and every stage has its full length.
            min_first_stage_s: lower bound of a partial stage 0 [s].
        """
        full = np.array(horizon.dts_s, dtype=float)
        dt0 = float(full[0])
        stage_start_in_step = float(horizon.stage_in_step[0]) * dt0
        dts = full.copy()
        if partial_first_stage:
            remaining = float(horizon.first_stage_remaining_s)
            dts[0] = max(remaining, min_first_stage_s)
            t_in = stage_start_in_step + max(dt0 - remaining, 0.0)
        else:
            t_in = stage_start_in_step
        return cls(
            dts_s=dts,
            contact=np.array(horizon.contact, dtype=bool),
            time_in_step_s=t_in,
            stages_per_step=stages_per_step,
            full_dts_s=full,
        )


def _derivative_matrix(times_s: np.ndarray) -> np.ndarray:
    """(n, n) matrix of ``numpy.gradient(., times_s, edge_order=2)`` (see there)."""
    n = times_s.size
    d = np.zeros((n, n))
    if n == 1:
        return d
    if n == 2:
        w = 1.0 / (times_s[1] - times_s[0])
        d[:, 0], d[:, 1] = -w, w
        return d
    h = np.diff(times_s)  # (n-1,)
    h1, h2 = h[:-1], h[1:]  # spacing before / after each interior point
    k = np.arange(1, n - 1)
    d[k, k - 1] = -h2 / (h1 * (h1 + h2))
    d[k, k] = (h2 - h1) / (h1 * h2)
    d[k, k + 1] = h1 / (h2 * (h1 + h2))
    a, b = h[0], h[1]  # first point: one-sided, second order
    d[0, :3] = [-(2.0 * a + b) / (a * (a + b)), (a + b) / (a * b), -a / (b * (a + b))]
    a, b = h[-1], h[-2]  # last point
    d[-1, -3:] = [a / (b * (a + b)), -(a + b) / (a * b), (2.0 * a + b) / (a * (a + b))]
    return d
