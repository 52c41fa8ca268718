"""The step-by-step API (issue 51, item 2): :class:`EpisodeStepper` runs the loop of
``gaitnet-mpc run`` in pieces, the fall status reads false until a fall, and a dt policy
object can be handed to the kd controller."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gaitnet_mpc.control.dt_policies import ExternalDt
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.scenario import (
    EpisodeOverError,
    EpisodeStepper,
    build_episode,
    make_scenario,
    run_scenario,
)
from gaitnet_mpc.sim.simulator import FallStatus

#: summary fields that are wall-clock measurements (differ between two identical runs)
_WALL = ("wall_time_s", "render_time_s", "realtime_factor")


def _facts(summary: dict) -> dict:
    """``summary`` without its wall-clock figures (the MPC block's ``*_ms_*`` included)."""
    out = {k: v for k, v in summary.items() if k not in _WALL}
    if out.get("mpc") is not None:
        out["mpc"] = {k: v for k, v in out["mpc"].items() if "_ms_" not in k}
    return out


def test_fall_status_is_false_until_a_fall(humanoid: RobotModel) -> None:
    """``if sim.fall:`` was true at t = 0 (a dataclass without ``__bool__``)."""
    episode = build_episode(make_scenario(controller="stand", duration_s=1.0), robot=humanoid)
    assert not episode.sim.fall
    assert not episode.sim.fall.fell
    assert FallStatus(True, 0.5, "trunk tilt") and not FallStatus()


def test_stepper_runs_the_loop_of_run_scenario(humanoid: RobotModel) -> None:
    """Ticks and footsteps stepped by hand give the summary of one ``run_scenario`` call
    (same ticks, same records), and each footstep starts on the tick it was told."""
    scenario = make_scenario(controller="kd", course="flat", vx_mps=0.5, duration_s=1.0)
    whole = run_scenario(scenario, robot=humanoid)
    stepper = EpisodeStepper(scenario, robot=humanoid)
    assert stepper.starts_footstep_next and stepper.time_s == 0.0
    started = 0
    while not stepper.done:
        r = stepper.step(n_ticks=7)
        assert r.ticks == 7 or r.done
        if r.done:
            break
        if not stepper.starts_footstep_next:
            r = stepper.step_footstep()
        if r.done:
            break
        assert stepper.starts_footstep_next
        started = r.steps_started
        nxt = stepper.step(n_ticks=1)  # the tick that starts the next footstep
        assert nxt.steps_started == started + 1
        assert nxt.t_s - 1e-3 == pytest.approx(r.step_end_s)
    assert stepper.truncated and not stepper.fell
    assert len(stepper.loop.log.rows) == 1000
    stepped = stepper.summary()
    assert list(stepped) == [k for k in whole if k != "video"]
    assert _facts(stepped) == _facts(whole)


def test_step_result_reports_the_controllers_decisions(humanoid: RobotModel) -> None:
    scenario = make_scenario(controller="kd", course="flat", vx_mps=0.5, duration_s=0.5)
    stepper = EpisodeStepper(scenario, robot=humanoid)
    r = stepper.step_footstep()
    assert r.ticks == 225 and r.t_s == pytest.approx(0.225)  # 5 stages of the nominal 45 ms
    assert r.step_dt_s == pytest.approx(0.045) and r.steps_started == 1
    assert (r.stance_foot, r.swing_foot) == ("left", "right")
    assert set(r.planned_footholds) == {"left", "right"}
    assert r.state.t_s == r.t_s and r.tau_nm.shape == (humanoid.mj_model.nu,)
    assert not r.fell and not r.done


def test_reset_starts_the_same_episode_again(humanoid: RobotModel) -> None:
    scenario = make_scenario(controller="kd", course="flat", vx_mps=0.5, duration_s=0.05)
    stepper = EpisodeStepper(scenario, robot=humanoid)
    first = stepper.step(n_ticks=100)
    assert first.done and first.ticks == 50
    with pytest.raises(EpisodeOverError, match="reset"):
        stepper.step()
    state0 = stepper.reset()
    assert state0.t_s == 0.0 and not stepper.done
    again = stepper.step(n_ticks=50)
    np.testing.assert_array_equal(again.state.qpos, first.state.qpos)
    assert again.steps_started == first.steps_started


@pytest.mark.parametrize("n_ticks", [0, -3, 1.5, True, "2"])
def test_step_checks_n_ticks(humanoid: RobotModel, n_ticks: object) -> None:
    scenario = make_scenario(controller="stand", duration_s=0.05)
    stepper = EpisodeStepper(scenario, robot=humanoid)
    with pytest.raises(ConfigError, match="n_ticks"):
        stepper.step(n_ticks=n_ticks)  # type: ignore[arg-type]


def test_step_footstep_needs_a_gait(humanoid: RobotModel) -> None:
    stepper = EpisodeStepper(make_scenario(controller="stand", duration_s=0.05), robot=humanoid)
    assert not stepper.starts_footstep_next
    r = stepper.step(n_ticks=3)
    assert math.isnan(r.step_dt_s) and r.stance_foot is None and r.planned_footholds == {}
    with pytest.raises(ConfigError, match="step_footstep"):
        stepper.step_footstep()


def test_a_dt_policy_object_goes_to_the_kd_family_only(humanoid: RobotModel) -> None:
    stand = make_scenario(controller="stand", duration_s=1.0)
    with pytest.raises(ConfigError, match="dt_policy"):
        build_episode(stand, robot=humanoid, dt_policy=ExternalDt())
    policy = ExternalDt(0.05)
    scenario = make_scenario(controller="kd", course="flat", vx_mps=0.5, duration_s=0.6)
    stepper = EpisodeStepper(scenario, robot=humanoid, dt_policy=policy)
    assert stepper.episode.controller.dt_policy is policy  # type: ignore[attr-defined]
    stepper.step_footstep()  # the first footstep: the nominal dt
    policy.dt_s = 0.06
    r = stepper.step_footstep()
    assert r.step_dt_s == pytest.approx(0.06)
    assert stepper.episode.controller.step_durations_s == pytest.approx([0.25, 0.3])
    assert policy.history_s == [0.06]


@pytest.mark.parametrize("dt_s", [0.0, 0.5, math.nan, math.inf])
def test_external_dt_checks_its_dt(dt_s: float) -> None:
    with pytest.raises(ConfigError, match="dt_s"):
        ExternalDt(dt_s)
    policy = ExternalDt()
    with pytest.raises(ConfigError, match="dt_s"):
        policy.dt_s = dt_s
