"""Step a scenario's episode yourself: :class:`EpisodeStepper`.

``gaitnet-mpc run`` (:func:`~gaitnet_mpc.scenario.run.run_scenario`) simulates a whole
episode in one call. The stepper runs the same loop
(:class:`~gaitnet_mpc.runner.loop.EpisodeLoop`: the same ticks, logs and summary) in
pieces the caller chooses, and hands back after each what the robot and the controller
are doing::

    stepper = EpisodeStepper(make_scenario(controller="kd", vx_mps=0.5, duration_s=2.0))
    while not stepper.done:
        r = stepper.step(n_ticks=10)          # 10 control ticks = 10 ms
        print(r.t_s, r.state.com_world_m[0], r.step_dt_s, r.planned_footholds)
    print(stepper.summary()["outcome"])

Two granularities:

* :meth:`EpisodeStepper.step`: ``n_ticks`` control ticks of ``SimConfig.timestep_s``
  (1 ms: one physics step and one controller call each);
* :meth:`EpisodeStepper.step_footstep`: up to the next footstep start, i.e. to the state
  whose tick starts the next step of the gait (where a dt policy chooses that step's dt).
  This is what the Gymnasium environment (:mod:`gaitnet_mpc.envs.gym_env`) steps by.

The episode is over (:attr:`EpisodeStepper.done`) when the robot fell or the scenario's
duration was simulated; :meth:`EpisodeStepper.reset` builds it again from the start (the
simulation is deterministic, so a reset episode repeats itself).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from gaitnet_mpc.errors import ConfigError, GaitNetMPCError
from gaitnet_mpc.gait.schedule import TIME_EPS_S
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.runner.loop import EpisodeLoop, Tick
from gaitnet_mpc.scenario.model import (
    Episode,
    Scenario,
    build_episode,
    scenario_meta,
    scenario_warnings,
)
from gaitnet_mpc.sim.simulator import SimConfig
from gaitnet_mpc.state import RobotState

if TYPE_CHECKING:
    from gaitnet_mpc.mpc.sequential import DtPolicy


class EpisodeOverError(GaitNetMPCError, RuntimeError):
    """A stepper was stepped after its episode ended (fell or its duration was
    simulated); :meth:`EpisodeStepper.reset` starts it again."""


@dataclass(frozen=True)
class StepResult:
    """Where the episode stands after a :meth:`EpisodeStepper.step` call.

    Attributes:
        state: the measured state now (the input of the next tick).
        t_s: simulated time now [s].
        ticks: control ticks this call ran.
        tau_nm: torques of the last tick [N m] (actuator order, before saturation).
        step_dt_s: MPC sampling time of the current footstep [s] (a footstep lasts
            ``5 step_dt_s``); NaN for a controller without a gait (``stand``).
        stance_foot, swing_foot: the feet of the current footstep (None without a gait).
        step_end_s: when the current footstep is scheduled to end [s] (NaN without a gait).
        steps_started: footsteps the controller has started so far.
        planned_footholds: foot -> (3,) upcoming touchdown the controller plans now [m]
            (empty if it plans none).
        fell: the fall detector fired (see :mod:`gaitnet_mpc.runner.episode`).
        done: the episode is over (fell, or its duration was simulated).
    """

    state: RobotState
    t_s: float
    ticks: int
    tau_nm: np.ndarray
    step_dt_s: float
    stance_foot: str | None
    swing_foot: str | None
    step_end_s: float
    steps_started: int
    planned_footholds: dict[str, np.ndarray]
    fell: bool
    done: bool


class EpisodeStepper:
    """The episode of ``scenario``, stepped by the caller (see the module docstring).

    Args:
        scenario: what to simulate (its ``duration_s`` ends the episode).
        robot: an already loaded model of ``scenario.robot``; None: load it (once: a reset
            reuses it).
        sim_config: simulator settings beyond the scenario's (fall margins).
        dt_policy: for the kd family, the dt policy object that chooses each footstep's dt
            instead of the scenario's (:func:`~gaitnet_mpc.scenario.build_episode`); the
            same object serves every reset.

    Attributes:
        episode: the built episode (robot, course, controller, simulator); rebuilt by
            :meth:`reset`.
        loop: its :class:`~gaitnet_mpc.runner.loop.EpisodeLoop` (the records so far).
    """

    def __init__(
        self,
        scenario: Scenario,
        *,
        robot: RobotModel | None = None,
        sim_config: SimConfig | None = None,
        dt_policy: DtPolicy | None = None,
    ) -> None:
        self.scenario = scenario
        self._robot = robot
        self._sim_config = sim_config
        self._dt_policy = dt_policy
        self.reset()

    # ------------------------------------------------------------------ episode
    def reset(self) -> RobotState:
        """Build the episode again from the scenario; return the initial state."""
        self.episode: Episode = build_episode(
            self.scenario,
            robot=self._robot,
            sim_config=self._sim_config,
            dt_policy=self._dt_policy,
        )
        self._robot = self.episode.robot
        e, s = self.episode, self.scenario
        self.loop = EpisodeLoop(e.sim, e.controller, s.command, s.duration_s)
        self._wall_s = 0.0
        self._last: Tick | None = None
        return self.state

    @property
    def state(self) -> RobotState:
        """The measured state now."""
        return self.episode.sim.state()

    @property
    def time_s(self) -> float:
        """Simulated time now [s]."""
        return self.episode.sim.time_s

    @property
    def fell(self) -> bool:
        """Whether the robot fell (or the simulation diverged)."""
        return self.loop.fell

    @property
    def truncated(self) -> bool:
        """Whether the scenario's duration was simulated without a fall."""
        return not self.loop.fell and self.loop.ticks >= self.loop.n_ticks

    @property
    def done(self) -> bool:
        """Whether the episode is over (:attr:`fell` or :attr:`truncated`)."""
        return self.loop.done

    @property
    def starts_footstep_next(self) -> bool:
        """Whether the next tick starts a footstep (the first tick, and the tick at the
        scheduled end of the current footstep, by the gait schedule's own rule); False
        for a controller without a gait."""
        tel = self.loop.probe.telemetry
        if tel is None:
            return False
        return self.loop.ticks == 0 or self.time_s >= tel.step_end_s - TIME_EPS_S

    # ------------------------------------------------------------------ stepping
    def step(self, n_ticks: int = 1) -> StepResult:
        """Run ``n_ticks`` control ticks, fewer if the episode ends first.

        Raises:
            ConfigError: ``n_ticks`` is not an integer >= 1.
            EpisodeOverError: the episode was already over.
        """
        if isinstance(n_ticks, bool) or not isinstance(n_ticks, int | np.integer) or n_ticks < 1:
            raise ConfigError("n_ticks", n_ticks, "an integer >= 1")
        self._check_running()
        t0 = time.perf_counter()
        ticks = 0
        while ticks < n_ticks and not self.loop.done:
            self._last = self.loop.tick()
            ticks += 1
        self._wall_s += time.perf_counter() - t0
        return self._result(ticks)

    def step_footstep(self) -> StepResult:
        """Run from now to the next footstep start: through the tick that starts the
        current one (if it is next) and every tick of it, stopping before the tick that
        starts the following footstep, or where the episode ends.

        Raises:
            ConfigError: the controller has no gait (``stand``).
            EpisodeOverError: the episode was already over.
        """
        self._check_running()
        if self.loop.probe.telemetry is None:
            name = self.scenario.controller
            raise ConfigError("step_footstep", name, "a walking controller (one with footsteps)")
        t0 = time.perf_counter()
        ticks = 0
        while not self.loop.done and (ticks == 0 or not self.starts_footstep_next):
            self._last = self.loop.tick()
            ticks += 1
        self._wall_s += time.perf_counter() - t0
        return self._result(ticks)

    def _check_running(self) -> None:
        if self.loop.done:
            why = "it fell" if self.loop.fell else "its duration was simulated"
            raise EpisodeOverError(f"the episode is over ({why}): reset() before stepping")

    def _result(self, ticks: int) -> StepResult:
        tick = self._last
        assert tick is not None  # a step call runs at least one tick
        tel = tick.telemetry
        controller = self.episode.controller
        return StepResult(
            state=self.state,
            t_s=self.time_s,
            ticks=ticks,
            tau_nm=tick.tau_nm,
            step_dt_s=math.nan if tel is None else tel.step_dt_s,
            stance_foot=None if tel is None else tel.stance_foot,
            swing_foot=None if tel is None else tel.swing_foot,
            step_end_s=math.nan if tel is None else tel.step_end_s,
            steps_started=len(controller.step_durations_s),
            planned_footholds=dict(controller.planned_footholds()),
            fell=self.loop.fell,
            done=self.loop.done,
        )

    # ------------------------------------------------------------------ summary
    def summary(self) -> dict[str, Any]:
        """The summary of the episode so far: the fields of
        :func:`~gaitnet_mpc.scenario.run_scenario`'s (``wall_time_s`` counts the time
        spent in the step calls)."""
        warnings = scenario_warnings(self.scenario)
        return {**scenario_meta(self.episode, warnings), **self.loop.summary(self._wall_s)}
