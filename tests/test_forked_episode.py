"""The push sweep's shared prefix: an episode simulated once up to the push and finished
in forked copies gives the records whole episodes give, bit for bit; a push that would
have acted before the fork is refused; a failing child is reported with its traceback."""

from __future__ import annotations

from typing import Any

import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.experiments import forked_episode
from gaitnet_mpc.experiments.forked_episode import ForkedEpisode
from gaitnet_mpc.experiments.sweep_cases import _build, _push_case, mode_plan
from gaitnet_mpc.sim.disturbances import Push

pytestmark = pytest.mark.skipif(not forked_episode.fork_usable(), reason="needs os.fork")


def _without_wall_times(record: dict[str, Any]) -> dict[str, Any]:
    out = {k: v for k, v in record.items() if k != "prefix_wall_s"}
    out["episodes"] = [{k: v for k, v in e.items() if k != "wall_s"} for e in out["episodes"]]
    return out


def test_forked_push_case_equals_whole_episodes(monkeypatch: pytest.MonkeyPatch) -> None:
    plan = mode_plan("push", quick=True, seeds=1)
    case = {"controller": "srbm", "speed_mps": 0.5, "direction": "left", "phase": 0.25}
    forked = _push_case(case, plan)
    assert forked["prefix_wall_s"] > 0
    monkeypatch.setattr(forked_episode, "fork_usable", lambda: False)
    whole = _push_case(case, plan)
    assert "prefix_wall_s" not in whole
    assert len(whole["episodes"]) >= 2  # more than one force, so more than one child
    assert _without_wall_times(forked) == _without_wall_times(whole)


def test_a_push_that_would_have_acted_before_the_fork_is_refused() -> None:
    episode = _build("srbm", vx_mps=0.0, duration_s=0.5)
    prefix = ForkedEpisode(episode, 0.5, 0.1)
    t_now = episode.sim.time_s
    assert t_now == pytest.approx(0.1, abs=1e-3)
    with pytest.raises(ConfigError, match=r"pushes\[0\]\.t_s"):
        episode.sim.set_pushes((Push(t_now - 0.01, (10.0, 0.0, 0.0), 0.1),))
    # the parent is untouched by its children: still at the prefix's end, without pushes
    push = Push(t_now, (10.0, 0.0, 0.0), 0.1)
    out = prefix.finish((push,), lambda loop, wall_s: {"t": loop.sim.time_s})
    assert out["t"] == pytest.approx(0.5, abs=1e-3)
    assert episode.sim.time_s == t_now and episode.sim.config.pushes == ()


def test_a_failing_child_is_reported_with_its_traceback() -> None:
    prefix = ForkedEpisode(_build("srbm", vx_mps=0.0, duration_s=0.2), 0.2, 0.1)

    def broken(loop: Any, wall_s: float) -> dict[str, Any]:
        raise ValueError("outcome broke")

    with pytest.raises(RuntimeError, match="outcome broke"):
        prefix.finish((), broken)
