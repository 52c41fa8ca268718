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
