"""A Gymnasium environment whose agent is a dt policy: :class:`DtPolicyEnv`.

The paper's Gait-Net makes one decision per footstep: the MPC sampling time ``dt`` of
the step that starts (a step lasts ``5 dt``, paper Sec. IV-B). This environment hands
that decision to an agent and lets the ``kd`` controller do everything else (footholds,
wrenches, swing, low level):

* **action**: ``[dt]`` [s], a ``Box`` over the robot's dt bounds (the humanoid's
  [0.045, 0.07] s, the biped's [0.03, 0.06] s: ``KDWalkConfig.dt_policy.bounds_for``);
  a value outside is clipped into them, then rounded to 1 us. It reaches the controller
  through the dt-policy slot of Algorithm 1
  (:class:`~gaitnet_mpc.control.dt_policies.ExternalDt`), as a fixed dt would for that
  step.
* **one env step** = one footstep: from the state before the tick that starts a
  footstep to the state before the tick that starts the next one
  (:meth:`~gaitnet_mpc.scenario.stepper.EpisodeStepper.step_footstep`), 5 dt (0.225-0.35
  s) of simulated time; the MPC runs at about real time, so about as much wall time.
* **observation**: the 16 Gait-Net features of that step start
  (:data:`~gaitnet_mpc.dataset.schema.FEATURE_NAMES`, float32, made by
  :func:`~gaitnet_mpc.dataset.step_features.step_features`, the function data
  collection and Gait-Net use): CoM relative to the new stance foot, CoM velocity, trunk
  roll/pitch/yaw and rate, and both feet relative to the CoM, in the commanded heading's
  frame. The swing foot's position is its *planned* touchdown in the controller's
  current plan (made at its last replan, at most ``replan_period_s`` ago); Gait-Net reads
  the same feature from the iterate inside the solve, but an agent decides before the
  solve runs, so it sees the plan's. Where no plan has one, the foot's position.
* **reward**: forward progress, the CoM's world-x change over the footstep [m] (the
  courses run along +x), minus ``fall_penalty`` on the footstep where the robot fell.
* **terminated**: the robot fell (the simulator's fall detector); **truncated**: the
  scenario's ``duration_s`` was simulated (possibly mid-footstep).

:meth:`DtPolicyEnv.reset` builds the episode again (deterministic: ``seed`` changes
nothing in the simulation) and runs the first footstep with the scenario's nominal dt,
so the first observation already has a plan's touchdown. ``info`` holds ``t_s``,
``step_dt_s`` (the dt the footstep ran with), ``steps_started``, ``distance_m`` (CoM x
since the start) and ``fall_reason``; :meth:`DtPolicyEnv.summary` the episode's
``summary.json`` fields.

Needs the optional extra ``gym`` (``pip install 'gaitnet-mpc[gym]'``)::

    env = DtPolicyEnv(make_scenario(controller="kd", course="flat", vx_mps=0.5, duration_s=5))
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(np.array([0.05], dtype=np.float32))
"""

from __future__ import annotations

from typing import Any

import numpy as np

try:
    import gymnasium as gym
    from gymnasium import spaces
except ImportError as exc:  # the optional extra is missing
    raise ImportError(
        "gaitnet_mpc.envs.gym_env needs Gymnasium, from the optional extra 'gym': "
        "pip install 'gaitnet-mpc[gym]' (or `pip install gymnasium==1.3.0`)"
    ) from exc

from gaitnet_mpc.control.dt_policies import ExternalDt
from gaitnet_mpc.dataset.schema import FEATURE_NAMES
from gaitnet_mpc.dataset.step_features import step_features
from gaitnet_mpc.dt_policy import NOMINAL_DT_S
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import ROBOTS, RobotModel
from gaitnet_mpc.scenario import Scenario, make_scenario
from gaitnet_mpc.scenario.stepper import EpisodeStepper

#: The id :func:`register` gives the environment (``gymnasium.make(ENV_ID, ...)``).
ENV_ID = "gaitnet_mpc/DtPolicy-v0"

#: Stages of a footstep (``h'``, paper Sec. IV-B): a footstep lasts ``5 dt``.
_STAGES_PER_STEP = 5


def default_scenario() -> Scenario:
    """The environment's scenario when none is given: ``kd`` on the humanoid, flat
    course, 0.5 m/s forward, 10 s."""
    return make_scenario(controller="kd", course="flat", vx_mps=0.5, duration_s=10.0)


class DtPolicyEnv(gym.Env[np.ndarray, np.ndarray]):
    """The ``kd`` controller walking ``scenario``, each footstep's dt chosen by the agent
    (see the module docstring).

    Args:
        scenario: a ``kd`` scenario (its settings' dt policy is replaced by the agent's;
            its ``dt_policy.dt_s`` is the first footstep's dt); None:
            :func:`default_scenario`.
        fall_penalty: subtracted from the reward of the footstep where the robot fell.
        robot: an already loaded model of ``scenario.robot`` (saves the load).
        render_mode: None (rendering: run the scenario with ``gaitnet-mpc run``).

    Raises:
        ConfigError: a scenario of another controller, a duration not longer than the
            first footstep, a negative or non-finite ``fall_penalty``, a render mode.
    """

    metadata: dict[str, Any] = {"render_modes": []}  # noqa: RUF012 - gymnasium.Env's

    def __init__(
        self,
        scenario: Scenario | None = None,
        *,
        fall_penalty: float = 1.0,
        robot: RobotModel | None = None,
        render_mode: str | None = None,
    ) -> None:
        scenario = default_scenario() if scenario is None else scenario
        if scenario.controller != "kd":
            raise ConfigError(
                "scenario.controller", scenario.controller, "kd (the agent is its dt policy)"
            )
        if not (np.isfinite(fall_penalty) and fall_penalty >= 0):
            raise ConfigError("fall_penalty", fall_penalty, "a finite reward >= 0")
        if render_mode is not None:
            raise ConfigError("render_mode", render_mode, "None (no rendering)")
        policy = scenario.config.dt_policy
        self.nominal_dt_s = NOMINAL_DT_S if policy.dt_s is None else float(policy.dt_s)
        first_step_s = _STAGES_PER_STEP * self.nominal_dt_s
        if scenario.duration_s <= first_step_s:
            expected = f"longer than the first footstep ({first_step_s:g} s at the nominal dt)"
            raise ConfigError("scenario.duration_s", scenario.duration_s, expected)
        self.scenario = scenario
        self.fall_penalty = float(fall_penalty)
        self.render_mode = render_mode
        self.dt_bounds_s = policy.bounds_for(ROBOTS[scenario.robot].planar)
        lo, hi = self.dt_bounds_s
        self.action_space = spaces.Box(
            low=np.float32(lo), high=np.float32(hi), shape=(1,), dtype=np.float32
        )
        n = len(FEATURE_NAMES)
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(n,), dtype=np.float32)
        self._robot = robot
        self._stepper: EpisodeStepper | None = None

    @property
    def stepper(self) -> EpisodeStepper:
        """The episode under way (after :meth:`reset`)."""
        if self._stepper is None:
            raise ConfigError("DtPolicyEnv", "not reset", "reset() before step()")
        return self._stepper

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Build the episode, run its first footstep at the nominal dt, and return the
        features of the second footstep's start."""
        super().reset(seed=seed)
        self._policy = ExternalDt(self.nominal_dt_s)
        self._stepper = EpisodeStepper(self.scenario, robot=self._robot, dt_policy=self._policy)
        self._robot = self._stepper.episode.robot
        self._x0_m = float(self._stepper.state.com_world_m[0])
        result = self._stepper.step_footstep()
        return self._observation(), self._info(result.step_dt_s)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Run one footstep with the dt ``action[0]`` [s] (clipped into the bounds)."""
        stepper = self.stepper
        a = np.asarray(action, dtype=float).reshape(-1)
        if a.size != 1 or not np.isfinite(a[0]):
            raise ConfigError("action", action, "[dt] with a finite dt [s]")
        lo, hi = self.dt_bounds_s
        # to 1 us: a float32 action of 0.06 is 0.0599999986...
        self._policy.dt_s = round(min(max(float(a[0]), lo), hi), 6)
        x_before = float(stepper.state.com_world_m[0])
        result = stepper.step_footstep()
        reward = float(result.state.com_world_m[0]) - x_before
        if result.fell:
            reward -= self.fall_penalty
        return (
            self._observation(),
            reward,
            stepper.fell,
            stepper.truncated,
            self._info(result.step_dt_s),
        )

    def summary(self) -> dict[str, Any]:
        """The episode's ``summary.json`` fields so far
        (:meth:`~gaitnet_mpc.scenario.stepper.EpisodeStepper.summary`)."""
        return self.stepper.summary()

    def _observation(self) -> np.ndarray:
        """The Gait-Net features of the footstep that starts at the next tick."""
        stepper = self.stepper
        tel = stepper.loop.probe.telemetry
        assert tel is not None  # kd has a gait
        state = stepper.state
        # the footstep that starts next swings the foot that stands now
        swing, stance = tel.stance_foot, tel.swing_foot
        planned = dict(stepper.episode.controller.planned_footholds())
        touchdown = planned.get(swing, state.foot_pos_world_m[swing])
        x = step_features(state, stance, swing, touchdown, tel.heading_rad)
        return x.astype(np.float32)

    def _info(self, step_dt_s: float) -> dict[str, Any]:
        stepper = self.stepper
        return {
            "t_s": stepper.time_s,
            "step_dt_s": step_dt_s,
            "steps_started": len(stepper.episode.controller.step_durations_s),
            "distance_m": float(stepper.state.com_world_m[0]) - self._x0_m,
            "fall_reason": stepper.episode.sim.fall.reason or None,
        }


def register() -> None:
    """Register :class:`DtPolicyEnv` with Gymnasium as :data:`ENV_ID` (once), so that
    ``gymnasium.make(ENV_ID, scenario=...)`` makes it."""
    if ENV_ID not in gym.registry:
        gym.register(id=ENV_ID, entry_point=f"{__name__}:DtPolicyEnv")
