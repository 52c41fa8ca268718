"""Re-timing the step under way (issue 48, item 3; control/step_retiming.py).

The rule shortens a step only when the linear inverted pendulum puts the foothold that
walks on beyond the swing hip's reach at the planned touchdown; the schedule and the swing
then end the step earlier without a jump in the swing foot's motion.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gaitnet_mpc.control.registry import controller_config
from gaitnet_mpc.control.step_retiming import reach_excess_m, retime_step
from gaitnet_mpc.dt_policy import StepRetimingConfig
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait import GaitSchedule, GaitScheduleConfig, SwingConfig
from gaitnet_mpc.geometry import GRAVITY_MPS2
from gaitnet_mpc.runner.loop import EpisodeLoop
from gaitnet_mpc.scenario import build_episode, make_scenario
from gaitnet_mpc.sim.disturbances import Push

Z_M = 0.55  # CoM height above the stance foot
HIP_RIGHT = np.array([0.009, -0.065])  # humanoid3d's right hip from the CoM, heading frame
REACH_M = 0.15


def _rule(
    com_vel_mps: tuple[float, float],
    *,
    dt_s: float = 0.045,
    t_in_s: float = 0.05,
    config: StepRetimingConfig | None = None,
    box_xy_m: tuple[np.ndarray, np.ndarray] | None = None,
):
    """The rule for a right swing over a left stance foot 0.03 m beside the CoM."""
    return retime_step(
        config or StepRetimingConfig(),
        dt_s=dt_s,
        max_dt_s=0.07,
        time_in_step_s=t_in_s,
        com_m=np.array([0.0, 0.0, Z_M]),
        com_vel_mps=np.array([*com_vel_mps, 0.0]),
        stance_m=np.array([0.0, 0.03, 0.0]),
        heading_rad=0.0,
        hip_offset_xy_m=HIP_RIGHT,
        reach_m=REACH_M,
        speed_cmd_mps=0.5,
        box_xy_m=box_xy_m,
    )


def test_the_pendulum_prediction_is_the_lip_solution() -> None:
    """At tau = 0 the foothold is the capture point less the gait offset; xi grows as
    exp(omega tau) from the stance foot."""
    omega = math.sqrt(GRAVITY_MPS2 / Z_M)
    c, v, s = np.array([0.02, 0.0]), np.array([0.3, 0.1]), np.zeros(2)
    tau = np.array([0.0, 0.1])
    excess = reach_excess_m(tau, c, v, s, omega, 0.0, np.zeros(2), 0.0, 0.0)
    xi0 = c + v / omega
    xi1 = s + (xi0 - s) * math.exp(omega * 0.1)
    c1 = s + (c - s) * math.cosh(omega * 0.1) + v / omega * math.sinh(omega * 0.1)
    np.testing.assert_allclose(excess, [np.abs(xi0 - c).max(), np.abs(xi1 - c1).max()])


def test_walking_on_command_keeps_the_step() -> None:
    assert _rule((0.5, 0.0)) is None


def test_a_push_shortens_the_step_within_its_bounds() -> None:
    d = _rule((0.8, 0.0))  # pushed forward: at the step's end the foothold is past reach
    assert d is not None
    assert StepRetimingConfig().min_dt_s <= d.dt_s < 0.045
    assert d.excess_before_m > 0.0 >= d.excess_after_m
    # at least min_remaining_s of swing is left
    assert 5 * d.dt_s - 0.05 >= StepRetimingConfig().min_remaining_s - 1e-12
    # a step already at its shortest cannot be shortened
    assert _rule((0.8, 0.0), dt_s=0.03) is None


def test_where_the_terrain_sets_the_foothold_only_an_end_it_offers_is_taken() -> None:
    """On a stone the swing lands in its eq. 24 box whatever the timing: an end whose
    foothold p* is off the box would only hurry the swing to the same stone. A box that
    holds p* (open ground) leaves the rule as it is."""
    d = _rule((0.8, 0.0))
    assert d is not None
    wide = (np.array([-10.0, -10.0]), np.array([10.0, 10.0]))
    assert _rule((0.8, 0.0), box_xy_m=wide) == d
    stone = (np.array([0.40, -0.2]), np.array([0.45, 0.0]))  # far ahead: p* is not on it
    assert _rule((0.8, 0.0), box_xy_m=stone) is None
    assert _rule((0.5, 0.8), box_xy_m=stone) is None  # nor the crossing case's end


def test_where_no_timing_reaches_the_step_is_kept() -> None:
    """Far out of reach at every end: the pendulum says no timing recovers, so the rule
    leaves the braking to the MPC instead of taking the shortest step."""
    assert _rule((1.6, 0.0)) is None


def test_a_foothold_beyond_the_stance_foot_ends_the_step_early() -> None:
    """Pushed toward the stance side, the foothold lies beyond the left stance foot at
    every end: the right foot cannot catch (it would cross), so its step ends as early as
    allowed and the left foot catches next. Without the option the step is kept, and a
    push away from the stance side that no end reaches keeps it too."""
    config = StepRetimingConfig()
    d = _rule((0.5, 0.8))
    assert d is not None
    assert d.dt_s == pytest.approx(config.min_dt_s)  # 5 x 0.03 - 0.05 s >= 0.04 s left
    assert d.excess_after_m > 0.0  # still out of the right hip's reach
    off = StepRetimingConfig(shortest_when_crossing=False)
    assert _rule((0.5, 0.8), config=off) is None
    assert _rule((0.5, -1.6)) is None  # beyond reach on the swing side: no crossing


def test_bad_settings_are_named() -> None:
    with pytest.raises(ConfigError, match="min_dt_s"):
        StepRetimingConfig(min_dt_s=0.01)
    with pytest.raises(ConfigError, match="min_remaining_s"):
        StepRetimingConfig(min_remaining_s=0.0)


def test_the_schedule_ends_a_retimed_step_earlier() -> None:
    sched = GaitSchedule(GaitScheduleConfig(dt_bounds_s=(0.03, 0.07)))
    sched.set_step_dt(0.05)
    sched.advance_to(0.1)
    sched.retime_step(0.03)
    assert sched.step_end_time_s == pytest.approx(0.15)
    assert sched.stage_in_step == 3 and sched.horizon_dts()[0] == 0.03
    with pytest.raises(ConfigError, match="dt_s"):
        sched.retime_step(0.02)  # below the bounds
    sched.advance_to(0.151)
    assert sched.step_index == 1 and sched.step_log[0].duration_s == pytest.approx(0.15)
    assert sched.step_log[0].planned_duration_s == pytest.approx(0.25)  # as it started
    sched.advance_to(0.151 + 0.2)  # 0.2 s into a step of 5 x 0.045 s
    with pytest.raises(ConfigError, match="ends after the current time"):
        sched.retime_step(0.035)  # it would have ended 0.025 s ago


def test_a_loaded_landing_in_the_second_half_ends_the_step_at_the_next_tick() -> None:
    from types import SimpleNamespace

    from gaitnet_mpc.control.step_retiming import StepRetimer
    from gaitnet_mpc.robots import load_robot

    robot = load_robot("humanoid3d")
    retimer = StepRetimer(StepRetimingConfig(), robot)  # on by default
    weight = robot.total_mass_kg * GRAVITY_MPS2

    def state(t_s: float, fz_n: float) -> SimpleNamespace:
        wrench = {"left": np.zeros(6), "right": np.zeros(6)}
        wrench[sched.swing_foot] = np.array([0.0, 0.0, fz_n, 0.0, 0.0, 0.0])
        feet = {"left": np.zeros(3), "right": np.zeros(3)}
        return SimpleNamespace(t_s=t_s, foot_wrench_world=wrench, foot_pos_world_m=feet)

    sched = GaitSchedule(GaitScheduleConfig(dt_bounds_s=(0.03, 0.07)))
    sched.set_step_dt(0.045)  # a 0.225 s step
    swing = SwingConfig(apex_height_m=0.06).trajectory(np.zeros(3), np.ones(3) * 0.1, 0.225)
    sched.advance_to(0.09)  # phase 0.4: a contact is the lift-off's scuff
    assert not retimer.end_at_touchdown(state(0.09, weight), sched, swing)
    sched.advance_to(0.18)  # phase 0.8
    assert not retimer.end_at_touchdown(state(0.18, 0.3 * weight), sched, swing)  # grazing
    assert retimer.end_at_touchdown(state(0.18, 0.6 * weight), sched, swing)
    assert sched.step_end_time_s == pytest.approx(0.181)
    assert swing.duration_s == pytest.approx(0.181)
    assert retimer.events[-1]["kind"] == "landing" and retimer.events[-1]["dt_s"] < 0.045
    sched.advance_to(0.181)
    assert sched.step_index == 1
    off = StepRetimer(StepRetimingConfig(end_at_touchdown=False), robot)  # no such ending
    sched.advance_to(0.181 + 0.18)
    assert not off.end_at_touchdown(state(0.361, weight), sched, swing)


@pytest.mark.parametrize(
    ("x_m", "foot", "ends"),
    [
        (0.50, "left", True),  # on the stone
        (0.42, "left", True),  # on its edge, the centre on it
        (0.30, "left", False),  # short of the stone: its centre over the hole
        (0.50, "right", False),  # a stone for the left foot only
    ],
)
def test_a_landing_ends_the_step_only_on_a_patch_the_foot_may_use(
    x_m: float, foot: str, ends: bool
) -> None:
    from types import SimpleNamespace

    from gaitnet_mpc.control.step_retiming import StepRetimer
    from gaitnet_mpc.control.terrain_view import TerrainKnowledge, TerrainView
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.terrain import Course, Patch

    robot = load_robot("humanoid3d")
    stones = (Patch(-0.3, 0.1, -0.3, 0.3, 0.0), Patch(0.4, 0.6, -0.3, 0.3, 0.1, "left"))
    view = TerrainView(Course("stones", stones))
    retimer = StepRetimer(StepRetimingConfig(end_at_touchdown=True), robot, None, view.holds_foot)
    sched = GaitSchedule(GaitScheduleConfig(dt_bounds_s=(0.03, 0.07)))
    if sched.swing_foot != foot:  # the next step swings the other foot
        sched.advance_to(0.226)
    sched.set_step_dt(0.045)
    t_s = sched.step_start_time_s + 0.18  # phase 0.8
    sched.advance_to(t_s)
    assert sched.swing_foot == foot
    swing = SwingConfig(apex_height_m=0.06).trajectory(np.zeros(3), np.ones(3) * 0.1, 0.225)
    pos = {"left": np.zeros(3), "right": np.zeros(3)}
    pos[foot] = np.array([x_m, 0.0, 0.11])
    wrench = {"left": np.zeros(6), "right": np.zeros(6)}
    wrench[foot][2] = robot.total_mass_kg * GRAVITY_MPS2
    state = SimpleNamespace(t_s=t_s, foot_wrench_world=wrench, foot_pos_world_m=pos)
    assert retimer.end_at_touchdown(state, sched, swing) is ends
    blind = TerrainView(Course("stones", stones), TerrainKnowledge(blind=True))
    assert not blind.holds_foot(foot, np.array([0.5, 0.0, 0.11]))  # it cannot tell


@pytest.mark.parametrize("t_now", [0.05, 0.12])
def test_a_retimed_swing_is_continuous_and_lands_at_its_new_end(t_now: float) -> None:
    p0, p1 = np.array([0.0, -0.1, 0.05]), np.array([0.2, -0.1, 0.05])
    tr = SwingConfig(apex_height_m=0.06).trajectory(p0, p1, 0.25)
    before = [tr.position(t_now), tr.velocity(t_now), tr.acceleration(t_now)]
    tr.retime(0.17, t_now)
    after = [tr.position(t_now), tr.velocity(t_now), tr.acceleration(t_now)]
    for b, a in zip(before, after, strict=True):
        np.testing.assert_allclose(a, b, atol=1e-7)
    assert tr.duration_s == 0.17
    np.testing.assert_allclose(tr.position(0.17), p1, atol=1e-9)
    np.testing.assert_allclose(tr.velocity(0.17), 0.0, atol=1e-8)
    with pytest.raises(ConfigError, match="duration_s"):
        tr.retime(t_now, t_now)


def _walk(seconds: float, pushes: tuple[Push, ...], controller: str = "gaitnet") -> EpisodeLoop:
    scenario = make_scenario(
        controller=controller, course="flat", vx_mps=0.5, duration_s=seconds, pushes=pushes
    )
    episode = build_episode(scenario)
    loop = EpisodeLoop(episode.sim, episode.controller, episode.command, seconds)
    while not loop.done:
        loop.tick()
    return loop


PUSH_LEFT = (Push(2.2, (0.0, 70.0, 0.0), 0.2),)


def _retimes(loop: EpisodeLoop) -> list[dict]:
    return [e for e in loop.controller.swing_events if e["kind"] == "retime"]


def test_in_the_loop_only_a_push_retimes_and_each_retiming_is_logged() -> None:
    calm = _walk(3.0, ())
    assert not calm.fell
    assert not _retimes(calm)

    pushed = _walk(3.0, PUSH_LEFT)
    events = _retimes(pushed)
    assert events and all(e["t_s"] >= 2.2 for e in events)
    assert all(0.03 <= e["dt_s"] < e["dt_before_s"] for e in events)
    # the executed step durations are the shortened ones
    durations = pushed.controller.step_durations_s
    assert min(durations) < 5 * 0.045 - 1e-9


def test_a_fixed_frequency_and_the_paper_preset_keep_their_timing() -> None:
    kd = _walk(2.6, PUSH_LEFT, controller="kd")
    assert not _retimes(kd)
    assert set(kd.controller.step_durations_s) == {5 * 0.045}
    paper = controller_config("gaitnet", preset="paper", planar=False)
    assert paper.dt_policy.gaitnet.retime_steps is None
