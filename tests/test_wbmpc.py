"""The ``wbmpc`` controller: whole-body NMPC walking in closed loop (issue 20)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.registry import ControllerContext, controller_config, make_controller
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.control.wbmpc_walk import WBWalkConfig, WBWalkController
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.step_durations import StepDurations
from gaitnet_mpc.runner.episode import run_episode
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course


def test_wbmpc_settings_are_checked() -> None:
    with pytest.raises(ConfigError, match="solver"):
        WBWalkConfig(solver="snopt")
    with pytest.raises(ConfigError, match=r"step_durations\.stages_per_step"):
        WBWalkConfig(step_durations=StepDurations(stages_per_step=4))
    config = controller_config("wbmpc", False, dt_s=0.06, overrides=["joint_kp_nm_per_rad=5"])
    assert config.step_durations.dt_s == 0.06 and config.joint_kp_nm_per_rad == 5.0


@pytest.mark.parametrize("seed", [0, 1])
def test_biped_walks_with_step_durations_drawn_per_stride(biped, seed: int) -> None:
    """Closed loop, 2.5 s at 0.5 m/s, every stride's duration drawn from [150, 400] ms (the
    data-collection protocol): no fall, forward progress, and the steps really last what
    was drawn. Seed 0 draws long first steps (0.31 s, 0.37 s): the biped fell backward at
    0.69 s before the front foot swung first and touchdowns were put on their nodes."""
    course = load_course("flat")
    command = Command(vx_mps=0.5)
    durations = StepDurations(duration_range_s=(0.15, 0.40), seed=seed)
    config = WBWalkConfig(step_durations=durations)
    ctrl = WBWalkController(biped, TerrainView(course), command, config)
    summary = run_episode(Simulator(biped, course), ctrl, command, 2.5, progress=False)
    assert not summary["fell"]
    assert summary["distance_m"] > 0.3
    steps = ctrl.step_durations_s
    assert len(steps) >= 6
    drawn = [5 * durations.dt_of_step(i) for i in range(len(steps))]
    np.testing.assert_allclose(steps, drawn)
    assert max(steps) - min(steps) > 0.05  # not one fixed duration
    assert summary["mpc"]["converged_fraction"] > 0.95


def test_humanoid_steps_in_closed_loop(humanoid) -> None:
    """Closed loop through the registry (the CLI's path), 1.5 s at 0.5 m/s, dt 0.045: no
    fall, it steps (both feet touch down) and moves forward."""
    course = load_course("flat")
    command = Command(vx_mps=0.5)
    ctx = ControllerContext(
        humanoid, course, command, controller_config("wbmpc", False, dt_s=0.045)
    )
    ctrl = make_controller("wbmpc", ctx)
    summary = run_episode(Simulator(humanoid, course), ctrl, command, 1.5, progress=False)
    assert not summary["fell"]
    assert summary["self_collisions"] == 0
    assert summary["distance_m"] > 0.1
    assert {f["foot"] for f in summary["footholds"]} == {"left", "right"}


def test_front_foot_swings_first(biped, humanoid) -> None:
    """The biped starts with its feet 0.16 m apart along x: walking forward, the front
    foot swings first, so the CoM starts ahead of the stance (point) foot; walking back,
    the other one; standing still or with the feet side by side (humanoid), the
    schedule's default (right)."""
    course = load_course("flat")
    for robot, vx, first in (
        (biped, 0.5, "left"),
        (biped, -0.3, "right"),
        (biped, 0.0, "right"),
        (humanoid, 0.5, "right"),
    ):
        state = Simulator(robot, course).state()
        assert (state.foot_pos_world_m["left"][0] > state.foot_pos_world_m["right"][0]) == (
            robot is biped
        )
        command = Command(vx_mps=vx)
        ctrl = WBWalkController(robot, TerrainView(course), command)
        ctrl.reset(state)
        assert ctrl.schedule.swing_foot == first


def test_horizon_and_footholds_use_each_steps_drawn_duration(humanoid) -> None:
    """With drawn durations the horizon's third step (reached from stage 1 on) gets its own
    dt, not a repeat of the next step's; each foothold's deadbeat gain uses the duration
    of the stance after its touchdown."""
    course = load_course("flat")
    durations = StepDurations(duration_range_s=(0.15, 0.40), seed=0)
    command = Command(vx_mps=0.5)
    ctrl = WBWalkController(
        humanoid, TerrainView(course), command, WBWalkConfig(step_durations=durations)
    )
    sim = Simulator(humanoid, course)
    state = sim.state()
    ctrl.reset(state)
    ctrl.compute(state)  # step 0 starts: the schedule takes the dts of steps 0 and 1
    dts = [durations.dt_of_step(i) for i in range(3)]
    assert len(set(dts)) == 3
    sched = ctrl.schedule
    sched.advance_to(state.t_s + 2.5 * dts[0])  # stage 2 of step 0
    timing = ctrl._timing()
    expected = [dts[0]] * 3 + [dts[1]] * 5 + [dts[2]] * 2
    np.testing.assert_allclose(timing.full_dts_s, expected)
    np.testing.assert_allclose(timing.dts_s[1:], expected[1:])
    assert 0.0 < timing.dts_s[0] <= dts[0]
    # The swing foot's foothold moves with the next step's duration only.
    t_left = sched.time_left_in_step_s
    velocity = ctrl._returning_command(state, command)
    base = ctrl._footholds(state, t_left, velocity)[0]
    other = replace(durations, seed=1)
    ctrl.config = replace(ctrl.config, step_durations=other)
    moved = ctrl._footholds(state, t_left, velocity)[0]
    assert other.dt_of_step(1) != durations.dt_of_step(1)
    assert np.linalg.norm(moved[:2] - base[:2]) > 1e-4


def test_reference_returns_to_the_commanded_heading_and_path(humanoid) -> None:
    """A trunk yawed 0.2 rad off the commanded heading and a CoM 5 cm left of the
    commanded path give a reference that turns back at -0.2 / T_psi rad/s and moves
    right at 0.05 / T_lat m/s; with both returns off, the command is unchanged."""
    course = load_course("flat")
    command = Command(vx_mps=0.5)
    sim = Simulator(humanoid, course)
    ctrl = WBWalkController(humanoid, TerrainView(course), command)
    ctrl.reset(sim.state())
    qpos = humanoid.standing_qpos(y_m=0.05)
    yaw = 0.2
    qpos[3:7] = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
    state = sim.reset(qpos)
    c = ctrl.config
    assert c.heading_return_time_s is not None and c.lateral_return_time_s is not None
    out = ctrl._returning_command(state, command)
    assert out.vx_mps == command.vx_mps
    np.testing.assert_allclose(out.yaw_rate_radps, -yaw / c.heading_return_time_s, rtol=1e-6)
    offset = state.com_world_m[1] - ctrl.com0[1]
    assert offset > 0.04
    np.testing.assert_allclose(out.vy_mps, -offset / c.lateral_return_time_s, rtol=1e-6)
    ctrl.config = replace(c, heading_return_time_s=None, lateral_return_time_s=None)
    assert tuple(ctrl._returning_command(state, command)) == (0.5, 0.0, 0.0)
