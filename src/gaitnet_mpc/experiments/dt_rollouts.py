"""A rollout oracle for step durations: at a step start, try every candidate dt in a forked
copy of the episode and see which recovers (issue 48, "a Gait-Net that knows recovery").

:class:`RolloutDt` sits in the dt-policy slot of a kino-dynamic controller around the
controller's own policy (``inner``, e.g. Gait-Net). At each step start that
``window(t)`` accepts, before ``inner`` answers, the process forks once per candidate dt
(``os.fork``: a copy of the simulator, controller and solver state at that instant). The
child takes its candidate for this step (later steps are ``inner``'s again), runs on for
``horizon_s`` or to the episode's end, and reports its :class:`RolloutOutcome`; the parent
collects them in a :class:`StepStart` record, then lets ``inner`` choose and goes on. The
features ``inner`` would see at each of its calls (the measured state and the iterate's
touchdown, :func:`~gaitnet_mpc.dataset.step_features.step_features`) are recorded too: they
are what a student sees, so that a label for them teaches the student where it goes wrong
(DAgger).

The episode must be driven by :func:`drive`, which ends a child when its rollout is over.
The child runs in the same process image, so nothing it does reaches the parent.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NoReturn

import numpy as np

from gaitnet_mpc.dataset.step_features import step_features
from gaitnet_mpc.experiments.forked_episode import read_reply, reply_and_exit
from gaitnet_mpc.mpc.sequential import KDProblem, planned_touchdowns
from gaitnet_mpc.runner.loop import EpisodeLoop

#: The dts [s] tried at a step start: the paper's bounds (0.045-0.07 s) and two below.
CANDIDATES_S = (0.035, 0.04, 0.045, 0.05, 0.055, 0.06, 0.065, 0.07)


@dataclass(frozen=True)
class RolloutOutcome:
    """How a rollout ended: ``fell`` (and when), and at its end the CoM velocity error to
    the command in the horizontal plane [m/s] and the trunk tilt [rad] (None if it fell)."""

    fell: bool
    fall_time_s: float | None
    speed_error_mps: float | None
    tilt_rad: float | None

    @property
    def score(self) -> float:
        """Lower is better: a fall is worst; else speed error plus tilt (1 rad ~ 1 m/s)."""
        if self.fell or self.speed_error_mps is None or self.tilt_rad is None:
            return float("inf")
        return self.speed_error_mps + self.tilt_rad


@dataclass
class StepStart:
    """One step start the oracle examined.

    Attributes:
        t_s: its time [s].
        features: the features ``inner`` saw at each of its calls (16 each).
        own_dt_s: ``inner``'s dt for the step.
        outcomes: candidate dt -> outcome of the rollout with it.
    """

    t_s: float
    features: list[list[float]] = field(default_factory=list)
    own_dt_s: float | None = None
    outcomes: dict[float, RolloutOutcome] = field(default_factory=dict)

    def label_dt_s(self) -> float | None:
        """The dt this step start teaches (DAgger that corrects failures only): the
        student's own dt if the candidate nearest to it survived, else the surviving
        candidate nearest to it (ties: the better score); None when every candidate fell
        or the student was not asked."""
        if self.own_dt_s is None:
            return None
        own = self.own_dt_s
        nearest = min(self.outcomes, key=lambda dt: abs(dt - own))
        if not self.outcomes[nearest].fell:
            return own
        ok = [dt for dt, o in self.outcomes.items() if not o.fell]
        if not ok:
            return None
        return min(ok, key=lambda dt: (round(abs(dt - own), 6), self.outcomes[dt].score))


class RolloutDt:
    """The oracle around ``inner`` (see the module docstring).

    Args:
        inner: the controller's own dt policy.
        window: whether a step start at time t [s] is examined.
        horizon_s: a rollout's simulated time from the step start [s]; None: to the
            episode's end.
        candidates_s: the dts tried.
    """

    def __init__(
        self,
        inner: Any,
        window: Callable[[float], bool],
        horizon_s: float | None = 1.5,
        candidates_s: tuple[float, ...] = CANDIDATES_S,
    ) -> None:
        self.inner = inner
        self.window = window
        self.horizon_s = horizon_s
        self.candidates_s = candidates_s
        self.steps: list[StepStart] = []
        self.child_dt_s: float | None = None  # set in a child: its forced dt
        self._child_end_s = float("inf")
        self._child_problem: KDProblem | None = None
        self._problem: KDProblem | None = None
        self._pipe_fd = -1

    @property
    def nominal_dt_s(self) -> float:
        return float(self.inner.nominal_dt_s)

    @property
    def is_child(self) -> bool:
        return self.child_dt_s is not None

    def step_retimed(self, dt_s: float) -> None:
        """The step under way was re-timed: told to the inner policy, whose spread fallback
        keeps the dt the previous step ran with (``GaitNetDt.step_retimed``)."""
        if hasattr(self.inner, "step_retimed"):
            self.inner.step_retimed(dt_s)

    def __call__(self, problem: KDProblem, iterate: Any, dt_s: float) -> float:
        if problem is self._child_problem:
            assert self.child_dt_s is not None
            return self.child_dt_s
        assert problem.state is not None
        t = problem.state.state.t_s
        if problem is not self._problem:  # a new step start
            self._problem = problem
            if not self.is_child and self.window(t):
                record = StepStart(t)
                for dt in self.candidates_s:
                    outcome = self._fork(problem, t, dt)
                    if outcome is None:  # this process is the child that takes dt
                        return dt
                    record.outcomes[dt] = outcome
                self.steps.append(record)
        step = self.steps[-1] if self.steps and self.steps[-1].t_s == t else None
        if step is not None:
            s = problem.state
            touchdown = planned_touchdowns(iterate, np.asarray(problem.timing.contact))
            x = step_features(
                s.state, s.stance_foot, s.swing_foot, touchdown[s.swing_foot][0],
                problem.heading_rad,
            )  # fmt: skip
            step.features.append([float(v) for v in x])
        dt = float(self.inner(problem, iterate, dt_s))
        if step is not None:
            step.own_dt_s = dt  # the last call's dt is the step's
        return dt

    def _fork(self, problem: KDProblem, t_s: float, dt: float) -> RolloutOutcome | None:
        read_fd, write_fd = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(read_fd)
            self.child_dt_s, self._child_problem, self._pipe_fd = dt, problem, write_fd
            self._child_end_s = t_s + self.horizon_s if self.horizon_s is not None else np.inf
            return None
        os.close(write_fd)
        return RolloutOutcome(**read_reply(pid, read_fd, f"a rollout child (dt {dt} s)"))

    def child_done(self, loop: EpisodeLoop) -> bool:
        """In a child: whether its rollout is over (a fall, the episode's end, the horizon)."""
        return self.is_child and (loop.done or loop.sim.time_s >= self._child_end_s - 1e-9)

    def report_and_exit(self, loop: EpisodeLoop) -> NoReturn:
        """In a child: send the outcome to the parent and end the process."""
        reply_and_exit(self._pipe_fd, lambda: rollout_outcome(loop).__dict__)


def rollout_outcome(loop: EpisodeLoop) -> RolloutOutcome:
    """The outcome of the episode of ``loop`` as it stands."""
    from gaitnet_mpc.sim.simulator import tilt_rad

    sim = loop.sim
    if sim.fall.fell:
        return RolloutOutcome(True, sim.fall.t_s, None, None)
    state = sim.state()
    cmd = loop.command
    err = state.com_vel_world_mps[:2] - np.array([cmd.vx_mps, cmd.vy_mps])
    return RolloutOutcome(False, None, float(np.hypot(*err)), tilt_rad(state.base_rot_world))


def drive(loop: EpisodeLoop, policy: RolloutDt) -> None:
    """Tick ``loop`` to its end; in a rollout child, until its rollout is over, then report
    to the parent and exit (this call then never returns there)."""
    while not loop.done:
        loop.tick()
        if policy.child_done(loop):
            policy.report_and_exit(loop)
    if policy.is_child:
        policy.report_and_exit(loop)
