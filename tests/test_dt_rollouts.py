"""The rollout oracle: forked candidate dts at a step start, the student's features
recorded, the parent's episode untouched; and the DAgger label rule."""

from __future__ import annotations

import pytest

from gaitnet_mpc.experiments import forked_episode
from gaitnet_mpc.experiments.dt_rollouts import RolloutDt, RolloutOutcome, StepStart, drive
from gaitnet_mpc.mpc.sequential import FixedDt
from gaitnet_mpc.runner.loop import EpisodeLoop
from gaitnet_mpc.scenario import build_episode, make_scenario


def _ok(score: float) -> RolloutOutcome:
    return RolloutOutcome(False, None, score, 0.0)


FELL = RolloutOutcome(True, 1.0, None, None)


def test_labels_keep_a_surviving_own_dt_and_correct_a_falling_one() -> None:
    survives_own = StepStart(0.0, own_dt_s=0.064, outcomes={0.045: _ok(0.1), 0.065: _ok(0.9)})
    assert survives_own.label_dt_s() == 0.064
    falls_own = StepStart(
        0.0, own_dt_s=0.064, outcomes={0.045: _ok(0.1), 0.05: _ok(0.2), 0.065: FELL}
    )
    assert falls_own.label_dt_s() == 0.05  # the surviving candidate nearest to 0.064
    all_fall = StepStart(0.0, own_dt_s=0.05, outcomes={0.045: FELL, 0.05: FELL})
    assert all_fall.label_dt_s() is None
    assert FELL.score == float("inf") and _ok(0.3).score == pytest.approx(0.3)


@pytest.mark.skipif(not forked_episode.fork_usable(), reason="needs os.fork")
def test_the_oracle_tries_each_candidate_in_a_child_and_the_parent_goes_on() -> None:
    duration = 0.8
    scenario = make_scenario(controller="kd", vx_mps=0.3, duration_s=duration)
    policy = RolloutDt(FixedDt(0.045), lambda t: 0.2 <= t <= 0.5, 0.15, (0.04, 0.05))
    episode = build_episode(scenario, dt_policy=policy)
    loop = EpisodeLoop(episode.sim, episode.controller, scenario.command, duration)
    drive(loop, policy)
    assert not policy.is_child  # the parent came back; the children exited
    assert loop.sim.time_s == pytest.approx(duration, abs=1e-3) and not loop.fell
    assert policy.steps, "no step start in the window"
    for step in policy.steps:
        assert 0.2 <= step.t_s <= 0.5
        assert set(step.outcomes) == {0.04, 0.05}
        assert all(not o.fell and o.speed_error_mps is not None for o in step.outcomes.values())
        assert step.own_dt_s == 0.045 and step.label_dt_s() == 0.045
        assert step.features and all(len(x) == 16 for x in step.features)
    # the parent's steps kept the student's dt: 5 stages of 0.045 s each
    assert all(d == pytest.approx(0.225) for d in episode.controller.step_durations_s[1:])


def test_the_oracle_tells_the_inner_policy_of_a_retimed_step() -> None:
    """The re-timer reports a shortened step to the controller's policy; around Gait-Net
    that is the oracle, which must pass it on (the inner policy's spread fallback keeps the
    dt the previous step ran with)."""
    told: list[float] = []

    class Inner(FixedDt):
        def step_retimed(self, dt_s: float) -> None:
            told.append(dt_s)

    RolloutDt(Inner(0.045), lambda t: False).step_retimed(0.0325)
    assert told == [0.0325]
    RolloutDt(FixedDt(0.045), lambda t: False).step_retimed(0.0325)  # nothing to tell
