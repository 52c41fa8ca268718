"""The Gymnasium environment of a dt policy (issue 51, item 2): Gymnasium's own checker,
the action reaching the controller as each footstep's dt, the reward, the episode's end,
and the message when the ``gym`` extra is missing."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

from gaitnet_mpc.dataset.schema import FEATURE_NAMES
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.scenario import make_scenario

gym = pytest.importorskip("gymnasium")
from gaitnet_mpc.envs.gym_env import ENV_ID, DtPolicyEnv, register  # noqa: E402

#: Gymnasium's advice that does not apply here: the action is a dt in seconds on purpose,
#: and the features have no hard bounds (a falling robot leaves any box).
_ADVICE = ("symmetric and normalized", "infinity", "not having a spec")


def test_env_passes_gymnasiums_checker(humanoid: RobotModel) -> None:
    from gymnasium.utils.env_checker import check_env

    register()
    scenario = make_scenario(controller="kd", course="flat", vx_mps=0.5, duration_s=0.8)
    env = gym.make(ENV_ID, scenario=scenario, robot=humanoid)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    other = [str(w.message) for w in caught if not any(a in str(w.message) for a in _ADVICE)]
    assert not other, other
    env.close()


def test_action_is_each_footsteps_dt(humanoid: RobotModel) -> None:
    scenario = make_scenario(controller="kd", course="flat", vx_mps=0.5, duration_s=1.0)
    env = DtPolicyEnv(scenario, robot=humanoid)
    assert env.action_space.low[0] == np.float32(0.045)
    assert env.action_space.high[0] == np.float32(0.07)
    obs, info = env.reset(seed=0)
    assert obs.shape == (len(FEATURE_NAMES),) and obs.dtype == np.float32
    assert info["steps_started"] == 1 and info["t_s"] == pytest.approx(0.225)
    x0 = float(env.stepper.state.com_world_m[0])
    obs, reward, terminated, truncated, info = env.step(np.array([0.06], dtype=np.float32))
    assert info["step_dt_s"] == 0.06 and info["t_s"] == pytest.approx(0.525)
    assert reward == pytest.approx(float(env.stepper.state.com_world_m[0]) - x0) and reward > 0
    assert not terminated and not truncated
    # outside the bounds: clipped
    obs, reward, terminated, truncated, info = env.step(np.array([0.5], dtype=np.float32))
    assert info["step_dt_s"] == 0.07
    while not (terminated or truncated):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert truncated and not terminated and info["t_s"] == pytest.approx(1.0)
    summary = env.summary()
    assert summary["step_durations_s"][:3] == [0.225, 0.3, 0.35]
    assert summary["outcome"] == "ok"


def test_env_checks_its_inputs(humanoid: RobotModel) -> None:
    with pytest.raises(ConfigError, match=r"scenario\.controller"):
        DtPolicyEnv(make_scenario(controller="gaitnet", duration_s=1.0), robot=humanoid)
    with pytest.raises(ConfigError, match=r"scenario\.duration_s"):
        DtPolicyEnv(make_scenario(controller="kd", duration_s=0.2), robot=humanoid)
    with pytest.raises(ConfigError, match="fall_penalty"):
        DtPolicyEnv(make_scenario(controller="kd", duration_s=1.0), fall_penalty=-1.0)
    with pytest.raises(ConfigError, match="render_mode"):
        DtPolicyEnv(make_scenario(controller="kd", duration_s=1.0), render_mode="human")
    env = DtPolicyEnv(make_scenario(controller="kd", duration_s=1.0), robot=humanoid)
    with pytest.raises(ConfigError, match="reset"):
        env.step(np.array([0.05], dtype=np.float32))


def test_missing_extra_names_it() -> None:
    code = (
        "import sys; sys.modules['gymnasium'] = None\n"
        "try:\n"
        "    import gaitnet_mpc.envs.gym_env\n"
        "except ImportError as exc:\n"
        "    print(exc)\n"
        "import gaitnet_mpc.envs\n"  # the package itself imports without the extra
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "gaitnet-mpc[gym]" in out.stdout
