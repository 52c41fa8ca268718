"""Periodic contact schedule with one MPC sampling time per footstep.

The paper fixes the contact sequence and varies the gait frequency through the MPC
sampling time (Sec. III-A, Sec. IV-B1): the horizon has ``h = 10`` stages, each footstep
(one swing of one foot, no double support) spans ``h' = h/2 = 5`` stages, and every
stage of one footstep has the same sampling time ``dt``, so the swing time is

    Δt = h' · dt                                                    (Sec. IV-B1)

The step's ``dt`` is chosen once, at the beginning of the footstep (Remark 4: Gait-Net runs
at the beginning of each footstep; the rest of the footstep keeps that ``dt``).

:class:`GaitSchedule` is driven by time.  A controller ticks it with
:meth:`GaitSchedule.advance_to` and, when :attr:`GaitSchedule.at_step_start` is True, may set
the new step's ``dt`` with :meth:`GaitSchedule.set_step_dt` before the next advance::

    schedule.advance_to(state.t_s)
    if schedule.at_step_start:                  # a new footstep begins on this tick
        schedule.set_step_dt(schedule.clip_dt(policy_dt))   # may be called repeatedly
    dts = schedule.horizon_dts()                # (h,) [s], starting at the current stage
    stance = schedule.horizon_contact()         # (h, 2) bool, columns FEET = (left, right)

Steps after the current one start with the *policy slot* dt (:meth:`set_next_step_dt`),
or with ``default_dt_s`` while the slot is empty.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.dt_policy import ACCEPTED_DT_RANGE_S, NOMINAL_DT_S
from gaitnet_mpc.errors import ConfigError, GaitNetMPCError
from gaitnet_mpc.robots.spec import FEET

__all__ = [
    "TIME_EPS_S",
    "GaitHorizon",
    "GaitSchedule",
    "GaitScheduleConfig",
    "StepDtLockedError",
    "StepRecord",
]

#: Tolerance [s] for time comparisons (a tick landing 1e-12 s before a boundary crosses it):
#: a tick at ``t_s >= step_end - TIME_EPS_S`` starts the next step.
TIME_EPS_S = 1e-9


class StepDtLockedError(GaitNetMPCError, RuntimeError):
    """:meth:`GaitSchedule.set_step_dt` was called after the current step got under way."""


def _is_number(value: object) -> bool:
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)


@dataclass(frozen=True)
class GaitScheduleConfig:
    """Configuration of the periodic contact schedule (paper Sec. III-A, Table V).

    Attributes:
        stages_per_step: ``h'``, MPC stages per footstep (one swing) [-].
        horizon_stages: ``h``, MPC stages in the horizon [-] (two steps by default).
        default_dt_s: sampling time of a step whose dt nobody set [s]
            (:data:`~gaitnet_mpc.dt_policy.NOMINAL_DT_S`).
        dt_bounds_s: (min, max) allowed sampling time [s]; every dt is checked against it.
        first_swing_foot: the foot that swings in step 0 (``"left"`` or ``"right"``).
    """

    stages_per_step: int = 5
    horizon_stages: int = 10
    default_dt_s: float = NOMINAL_DT_S
    dt_bounds_s: tuple[float, float] = ACCEPTED_DT_RANGE_S
    first_swing_foot: str = "right"

    def __post_init__(self) -> None:
        for name in ("stages_per_step", "horizon_stages"):
            v = getattr(self, name)
            if not isinstance(v, int | np.integer) or isinstance(v, bool) or v < 1:
                raise ConfigError(name, v, "an integer >= 1")
        b = self.dt_bounds_s
        if (
            not isinstance(b, tuple | list)
            or len(b) != 2
            or not all(_is_number(x) and math.isfinite(x) for x in b)
            or not 0.0 < b[0] <= b[1]
        ):
            raise ConfigError("dt_bounds_s", b, "(min, max) with 0 < min <= max [s]")
        object.__setattr__(self, "dt_bounds_s", (float(b[0]), float(b[1])))
        d = self.default_dt_s
        if not _is_number(d) or not b[0] <= d <= b[1]:
            raise ConfigError("default_dt_s", d, f"a sampling time in dt_bounds_s = {b} [s]")
        object.__setattr__(self, "default_dt_s", float(d))
        if self.first_swing_foot not in FEET:
            raise ConfigError("first_swing_foot", self.first_swing_foot, f"one of {FEET}")


@dataclass(frozen=True)
class StepRecord:
    """One executed footstep: index, swing foot, start time [s], dt [s], duration [s], and
    the duration it started with [s] (longer when it was re-timed under way)."""

    index: int
    swing_foot: str
    start_time_s: float
    dt_s: float
    duration_s: float
    planned_duration_s: float


@dataclass(frozen=True)
class GaitHorizon:
    """Snapshot of the schedule over the MPC horizon, starting at the current stage.

    Attributes:
        time_s: schedule time of the snapshot [s].
        dts_s: (h,) sampling time of each stage [s] (full stage lengths).
        contact: (h, 2) bool stance mask, columns in ``FEET`` order (left, right).
        step_index: (h,) which step each stage belongs to, 0 = current step.
        stage_in_step: (h,) stage index inside its step, 0..h'-1.
        boundaries_s: (h+1,) absolute stage boundary times [s]; ``boundaries_s[0]`` is the
            start of the current stage (<= ``time_s``), ``boundaries_s[j+1]`` the end of stage j.
        first_stage_remaining_s: ``boundaries_s[1] - time_s`` [s], the unelapsed part of
            stage 0.
    """

    time_s: float
    dts_s: np.ndarray
    contact: np.ndarray
    step_index: np.ndarray
    stage_in_step: np.ndarray
    boundaries_s: np.ndarray
    first_stage_remaining_s: float


class GaitSchedule:
    """Fixed periodic contact sequence (no double support) with a dt per footstep.

    Step ``k`` (k = 0, 1, ...) swings ``first_swing_foot`` when k is even and the other foot
    when k is odd; the other foot stands.  It lasts ``h' · dt_k`` (Sec. IV-B1, Δt = h'·dt)
    and starts where step ``k-1`` ended.  A step's dt is the policy-slot dt (or
    ``default_dt_s``) when the step starts, and may be changed with :meth:`set_step_dt`
    only while :attr:`at_step_start` is True.

    :attr:`at_step_start` is True from the :meth:`advance_to` call that entered a new step
    (or from construction / :meth:`reset` for step 0) until the next :meth:`advance_to` that
    moves time forward.  If one advance crosses several boundaries, the skipped steps run
    with the policy-slot dt and only the last one entered is "at start".

    All queries refer to the current schedule time :attr:`time_s`.  Deterministic; no
    global state.
    """

    def __init__(self, config: GaitScheduleConfig | None = None, start_time_s: float = 0.0) -> None:
        self.config = config if config is not None else GaitScheduleConfig()
        self._policy_dt_s: float | None = None
        self.reset(start_time_s)

    # ------------------------------------------------------------------ driving

    def reset(self, start_time_s: float = 0.0) -> None:
        """Restart at step 0 at ``start_time_s`` [s]; clears the log and the policy slot."""
        if not _is_number(start_time_s) or not math.isfinite(start_time_s):
            raise ConfigError("start_time_s", start_time_s, "a finite time [s]")
        self._t_s = float(start_time_s)
        self._step_index = 0
        self._step_start_s = float(start_time_s)
        self._policy_dt_s = None
        self._step_dt_s = self._start_dt_s = self.config.default_dt_s
        self._at_step_start = True
        self._log: list[StepRecord] = []

    def advance_to(self, t_s: float) -> int:
        """Move the schedule to time ``t_s`` [s] (monotonic), crossing step boundaries.

        Returns the number of steps that started during this call (0 if still in the same
        step).  Raises :class:`ConfigError` if ``t_s`` is not finite or lies before the
        current time.
        """
        if not _is_number(t_s) or not math.isfinite(t_s):
            raise ConfigError("t_s", t_s, "a finite time [s]")
        t = float(t_s)
        if t < self._t_s - TIME_EPS_S:
            raise ConfigError("t_s", t_s, f">= the schedule time {self._t_s!r} s (monotonic)")
        if t <= self._t_s:
            return 0
        started = 0
        while t >= self.step_end_time_s - TIME_EPS_S:
            self._log.append(
                StepRecord(
                    index=self._step_index,
                    swing_foot=self.swing_foot,
                    start_time_s=self._step_start_s,
                    dt_s=self._step_dt_s,
                    duration_s=self.current_step_duration_s,
                    planned_duration_s=self.planned_step_duration_s,
                )
            )
            self._step_start_s = self.step_end_time_s
            self._step_index += 1
            self._step_dt_s = self._start_dt_s = self.next_step_dt_s
            started += 1
        self._t_s = t
        self._at_step_start = started > 0
        return started

    def set_step_dt(self, dt_s: float) -> None:
        """Set the sampling time ``dt_s`` [s] of the step that is starting.

        Allowed only while :attr:`at_step_start` is True (any number of times, e.g. once per
        sequential iteration of Algorithm 1); otherwise raises :class:`StepDtLockedError`.
        ``dt_s`` outside ``dt_bounds_s`` raises :class:`ConfigError` (use :meth:`clip_dt`).
        The step keeps its start time; if the new duration h'·dt ends at or before the
        current time (a tick that landed late), the next :meth:`advance_to` ends the step.
        """
        dt = self._check_dt(dt_s, "dt_s")
        if not self._at_step_start:
            raise StepDtLockedError(
                f"set_step_dt: step {self._step_index} started at {self._step_start_s!r} s is "
                f"under way at t = {self._t_s!r} s; its dt can only be set at the step start "
                "(when at_step_start is True); use set_next_step_dt for later steps"
            )
        self._step_dt_s = self._start_dt_s = dt

    def retime_step(self, dt_s: float) -> None:
        """Change the dt of the step under way to ``dt_s`` [s] (beyond the paper's Remark 4,
        :mod:`~gaitnet_mpc.control.step_retiming`): the step keeps its start time and ends
        at ``start + h' dt_s``; its remaining stages take ``dt_s``.

        ``dt_s`` outside ``dt_bounds_s``, or one whose step would end at or before the
        current time, raises :class:`ConfigError`.
        """
        dt = self._check_dt(dt_s, "dt_s")
        end = self._step_start_s + self.config.stages_per_step * dt
        if end <= self._t_s + TIME_EPS_S:
            raise ConfigError(
                "dt_s", dt_s, f"a dt whose step ends after the current time {self._t_s!r} s"
            )
        self._step_dt_s = dt

    def set_next_step_dt(self, dt_s: float | None) -> None:
        """Fill the policy slot: the dt [s] that every later step starts with.

        ``None`` empties the slot (later steps start with ``default_dt_s``).  The slot also
        sets the dt of next-step stages in :meth:`horizon_dts`.
        """
        self._policy_dt_s = None if dt_s is None else self._check_dt(dt_s, "dt_s")

    def clip_dt(self, dt_s: float) -> float:
        """``dt_s`` [s] clipped into ``dt_bounds_s`` (for network outputs)."""
        if not _is_number(dt_s) or math.isnan(dt_s):
            raise ConfigError("dt_s", dt_s, "a number [s]")
        lo, hi = self.config.dt_bounds_s
        return float(min(max(float(dt_s), lo), hi))

    def _check_dt(self, dt_s: object, field: str) -> float:
        lo, hi = self.config.dt_bounds_s
        if not _is_number(dt_s) or not lo <= float(dt_s) <= hi:  # type: ignore[arg-type]
            raise ConfigError(field, dt_s, f"a sampling time in [{lo}, {hi}] s (dt_bounds_s)")
        return float(dt_s)  # type: ignore[arg-type]

    # ------------------------------------------------------------------ current-time queries

    @property
    def time_s(self) -> float:
        """Current schedule time [s]."""
        return self._t_s

    @property
    def at_step_start(self) -> bool:
        """True while the current step's dt may still be set (see class docstring)."""
        return self._at_step_start

    @property
    def step_index(self) -> int:
        """Index of the current step (= number of completed steps)."""
        return self._step_index

    def swing_foot_of_step(self, step_index: int) -> str:
        """The foot that swings in step ``step_index`` (absolute index)."""
        first = FEET.index(self.config.first_swing_foot)
        return FEET[(first + step_index) % 2]

    @property
    def swing_foot(self) -> str:
        """Foot swinging in the current step."""
        return self.swing_foot_of_step(self._step_index)

    @property
    def stance_foot(self) -> str:
        """Foot standing in the current step."""
        return self.swing_foot_of_step(self._step_index + 1)

    @property
    def stance_mask(self) -> np.ndarray:
        """(2,) bool, True for the stance foot, in ``FEET`` order."""
        return np.array([f == self.stance_foot for f in FEET])

    @property
    def current_step_dt_s(self) -> float:
        """Sampling time of the current step [s]."""
        return self._step_dt_s

    @property
    def current_step_duration_s(self) -> float:
        """Duration of the current step, h' · dt [s] (Sec. IV-B1)."""
        return self.config.stages_per_step * self._step_dt_s

    @property
    def planned_step_duration_s(self) -> float:
        """Duration the current step started with, h' · its dt at the start [s]: before a
        re-timing under way (:meth:`retime_step`) it is :attr:`current_step_duration_s`."""
        return self.config.stages_per_step * self._start_dt_s

    @property
    def next_step_dt_s(self) -> float:
        """dt [s] the next step will start with: the policy slot, else ``default_dt_s``."""
        return self._policy_dt_s if self._policy_dt_s is not None else self.config.default_dt_s

    @property
    def step_start_time_s(self) -> float:
        """Start time of the current step [s]."""
        return self._step_start_s

    @property
    def step_end_time_s(self) -> float:
        """End time of the current step with its current dt [s]."""
        return self._step_start_s + self.current_step_duration_s

    @property
    def time_in_step_s(self) -> float:
        """Time elapsed in the current step [s], in [0, duration]."""
        return min(max(self._t_s - self._step_start_s, 0.0), self.current_step_duration_s)

    @property
    def time_left_in_step_s(self) -> float:
        """Time until the current step ends [s]."""
        return self.current_step_duration_s - self.time_in_step_s

    @property
    def phase_in_step(self) -> float:
        """Fraction of the current step elapsed, in [0, 1)."""
        return min(self.time_in_step_s / self.current_step_duration_s, math.nextafter(1.0, 0.0))

    @property
    def stage_in_step(self) -> int:
        """Current MPC stage inside the step, 0 .. h'-1."""
        k = math.floor((self.time_in_step_s + TIME_EPS_S) / self._step_dt_s)
        return min(k, self.config.stages_per_step - 1)

    @property
    def stage_start_time_s(self) -> float:
        """Start time of the current stage [s] (<= :attr:`time_s`)."""
        return self._step_start_s + self.stage_in_step * self._step_dt_s

    @property
    def first_stage_remaining_s(self) -> float:
        """Unelapsed part of the current stage (horizon stage 0) [s], in (0, dt]."""
        end = self._step_start_s + (self.stage_in_step + 1) * self._step_dt_s
        return max(end - self._t_s, 0.0)

    # ------------------------------------------------------------------ log

    @property
    def step_log(self) -> tuple[StepRecord, ...]:
        """Completed steps, oldest first (the current step is not included)."""
        return tuple(self._log)

    @property
    def step_durations_s(self) -> list[float]:
        """Durations [s] of the completed steps, oldest first."""
        return [r.duration_s for r in self._log]

    # ------------------------------------------------------------------ horizon queries

    def _horizon_layout(self) -> tuple[np.ndarray, np.ndarray]:
        """(h,) step offset and (h,) stage-in-step of each horizon stage."""
        n = self.config.stages_per_step
        s = self.stage_in_step + np.arange(self.config.horizon_stages)  # (h,)
        return s // n, s % n

    def horizon_step_index(self) -> np.ndarray:
        """(h,) int: which step each horizon stage belongs to, 0 = current step."""
        return self._horizon_layout()[0]

    def horizon_stage_in_step(self) -> np.ndarray:
        """(h,) int: stage index inside its own step, 0 .. h'-1."""
        return self._horizon_layout()[1]

    def horizon_dts(self) -> np.ndarray:
        """(h,) full sampling time of each horizon stage [s], from the current stage.

        Stages of the current step use :attr:`current_step_dt_s`; stages of later steps use
        :attr:`next_step_dt_s` (policy slot or default).  Stage 0 may be partly elapsed:
        see :attr:`first_stage_remaining_s`.
        """
        offset = self.horizon_step_index()
        return np.where(offset == 0, self._step_dt_s, self.next_step_dt_s)

    def horizon_contact(self) -> np.ndarray:
        """(h, 2) bool stance mask from the current stage; columns FEET = (left, right).

        Exactly one foot stands in each stage; the stance foot swaps every h' stages.
        """
        steps = self._step_index + self.horizon_step_index()  # (h,) absolute step index
        first = FEET.index(self.config.first_swing_foot)
        swing_col = (first + steps) % 2  # (h,)
        return np.arange(len(FEET))[None, :] != swing_col[:, None]

    def horizon_stage_boundaries_s(self) -> np.ndarray:
        """(h+1,) absolute stage boundary times [s]; element 0 = current stage start."""
        out = np.empty(self.config.horizon_stages + 1)
        out[0] = self.stage_start_time_s
        out[1:] = out[0] + np.cumsum(self.horizon_dts())
        return out

    def horizon(self) -> GaitHorizon:
        """All horizon queries in one snapshot."""
        offset, stage = self._horizon_layout()
        return GaitHorizon(
            time_s=self._t_s,
            dts_s=self.horizon_dts(),
            contact=self.horizon_contact(),
            step_index=offset,
            stage_in_step=stage,
            boundaries_s=self.horizon_stage_boundaries_s(),
            first_stage_remaining_s=self.first_stage_remaining_s,
        )

    def __repr__(self) -> str:
        return (
            f"GaitSchedule(t={self._t_s:.4f} s, step={self._step_index}, "
            f"swing={self.swing_foot}, dt={self._step_dt_s:.4f} s, "
            f"stage={self.stage_in_step}, at_step_start={self._at_step_start})"
        )
