"""Toe strikes on an obstacle taller than the robot assumes: detected by the swing foot's
contact sensor, the obstacle's assumed top raised, the swing re-planned over it
(``SwingObstacles.toe_strike``, ``KDWalkConfig.toe_strike_raise_m``)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gaitnet_mpc.control.kd_walk_config import KDWalkConfig
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.experiments.figure_obstacle import _recorder
from gaitnet_mpc.scenario import build_episode, make_scenario, run_scenario

BOX_X_M = (1.5, 1.6)
BOX_HEIGHT_M = 0.10  # the robot takes it as unknown_obstacle_height_m = 0.04 m high


def _box_course(tmp_path: Path) -> Path:
    path = tmp_path / "box.json"
    course = {
        "name": "box",
        "patches": [{"x": [-1.0, 25.0], "y": [-1.5, 1.5], "z": 0.0, "feet": "both"}],
        "obstacles": [{"x": list(BOX_X_M), "y": [-1.5, 1.5], "height": BOX_HEIGHT_M}],
    }
    path.write_text(json.dumps(course))
    return path


def test_a_struck_box_of_unknown_height_is_stepped_over(tmp_path: Path) -> None:
    """A 10 cm box taken as 4 cm high: the first foot strikes it, the robot raises the box
    and lifts that foot over it, the other foot clears it, and the robot walks on."""
    scenario = make_scenario(
        controller="gaitnet",
        course=str(_box_course(tmp_path)),
        vx_mps=0.5,
        duration_s=4.5,
        overrides=["obstacle_heights=false"],
    )
    episode = build_episode(scenario)
    recorder = _recorder(episode)
    summary = run_scenario(scenario, episode=episode, on_step=recorder)
    assert not summary["fell"], summary["fall_reason"]
    assert summary["foothold_violations"] == 0
    strikes = [e for e in summary["swing_events"] if e["kind"] == "toe_strike"]
    assert strikes, "no strike detected on a box 6 cm taller than assumed"
    first = strikes[0]
    x = first["foot_pos_m"][0]
    assert BOX_X_M[0] - 0.1 <= x <= BOX_X_M[1] + 0.1  # at the box, toe and heel included
    assert first["obstacle_tops_m"][0] >= 0.04 + 0.04  # raised above the assumed top
    # both feet end beyond the box, the second one without touching it
    assert summary["distance_m"] > BOX_X_M[1] + 0.3
    struck = {s["foot"] for s in strikes}
    other = [f for f in recorder.foot_contacts if f not in struck]
    assert other and all(not recorder.foot_contacts[f] for f in other)


def test_toe_strike_raise_is_checked() -> None:
    with pytest.raises(ConfigError, match="toe_strike_raise_m"):
        KDWalkConfig(toe_strike_raise_m=-0.01)


def test_shank_event_without_an_obstacle_below_is_json(monkeypatch: pytest.MonkeyPatch) -> None:
    """A shank check over two obstacles, the shank passing over only one: the other's
    clearance (infinite) is recorded as None, so ``summary.json`` can be written (it
    raised "Out of range float values are not JSON compliant" at the end of the run)."""
    from types import SimpleNamespace

    import numpy as np

    import gaitnet_mpc.control.swing_obstacles as so
    from gaitnet_mpc.robots import load_robot

    robot = load_robot("humanoid3d")
    checker = so.SwingObstacles(robot, None, KDWalkConfig())  # type: ignore[arg-type]
    monkeypatch.setattr(so, "swing_shank_clearance_m", lambda *a: np.array([np.inf, 0.001]))
    times = np.linspace(0.0, 0.5, 11)
    zeros = np.zeros((11, 3))
    ref = SimpleNamespace(times_s=times, p_base_ref=zeros, rot_base_ref=np.zeros((11, 3, 3)))
    checker.check_shank(
        SimpleNamespace(t_s=1.0),  # type: ignore[arg-type]
        SimpleNamespace(swing_foot="left", step_index=3, time_in_step_s=0.1),  # type: ignore[arg-type]
        SimpleNamespace(obstacles=[(0.0,) * 5, (1.0,) * 5], duration_s=0.25,
                        position=lambda t: np.zeros((len(t), 3))),  # type: ignore[arg-type]
        SimpleNamespace(reference=ref, t_plan_s=1.0),  # type: ignore[arg-type]
        SimpleNamespace(heading_rad=lambda t: 0.0),  # type: ignore[arg-type]
    )  # fmt: skip
    (event,) = checker.events
    assert event["kind"] == "shank" and event["clearance_m"] == [None, 0.001]
    json.dumps(checker.events, allow_nan=False)
