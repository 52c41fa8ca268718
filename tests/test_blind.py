"""Blind walking (``--blind``, issue 50 item 2): the controller is told no terrain, plans on
its stance foot's height and finds the ground with the swing foot; the course still
decides what the feet touch."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gaitnet_mpc.cli import main as cli_main
from gaitnet_mpc.control.blind_touchdown import EARLY_TOUCHDOWN_PHASE, TouchdownSearch
from gaitnet_mpc.control.terrain_view import TerrainKnowledge, TerrainView
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.scenario import make_scenario, run_scenario
from gaitnet_mpc.terrain import load_course
from gaitnet_mpc.terrain.builtin_courses import uneven_course


def test_a_blind_view_answers_nothing_about_the_course() -> None:
    course = load_course("stepping-stones")
    view = TerrainView(course, TerrainKnowledge(blind=True))
    x, y = 1.5, 0.1  # over a stone of the built-in layout or a hole: the answer is the same
    assert view.foothold_height_m(x, y, default_m=0.123) == 0.123
    assert view.obstacle_footprints(0.0, 10.0) == []
    assert view.swing_obstacles(0.0, 10.0) == []
    for query in (
        lambda: view.patch_at(x, y),
        lambda: view.reachable_foothold_bounds(
            (x, y), "left", (x, y), reach_x_m=0.3, margin_m=0.05
        ),
    ):
        with pytest.raises(ConfigError) as err:
            query()
        assert err.value.field == "terrain_knowledge.blind"
    with pytest.raises(ConfigError) as err:
        TerrainKnowledge(blind=True, multi_step=True)
    assert err.value.field == "blind"


class _State:
    def __init__(self, contact: bool, z: float) -> None:
        self.foot_contact = {"left": contact, "right": False}
        self.foot_pos_world_m = {"left": np.array([0.3, 0.1, z]), "right": np.zeros(3)}


def test_the_first_contact_in_the_second_half_of_the_step_ends_the_swing() -> None:
    search = TouchdownSearch()
    sampled = (np.array([0.3, 0.1, -0.01]), np.array([0.0, 0.0, -0.1]), np.zeros(3))
    early = EARLY_TOUCHDOWN_PHASE - 0.1
    assert search.target(_State(True, 0.02), "left", early, sampled) is sampled  # a scuff
    assert search.target(_State(False, 0.05), "left", 0.7, sampled) is sampled  # in the air
    held = search.target(_State(True, 0.03), "left", 0.8, sampled)
    np.testing.assert_array_equal(held[0], [0.3, 0.1, 0.03])
    assert not held[1].any() and not held[2].any()
    # held where it landed for the rest of the step, whatever the contact sensor says next
    again = search.target(_State(False, 0.031), "left", 0.9, sampled)
    np.testing.assert_array_equal(again[0], [0.3, 0.1, 0.03])
    search.new_step()
    assert search.target(_State(False, 0.05), "left", 0.6, sampled) is sampled


def test_gaitnet_walks_blind_over_unknown_uneven_tiles(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """+-3 cm tiles the controller is not told about, 0.5 m/s: no fall, and the run records
    that the controller was blind."""
    path = tmp_path / "uneven.json"
    path.write_text(json.dumps(uneven_course(seed=7, amplitude_m=0.03).to_dict()))
    scenario = make_scenario(
        controller="gaitnet",
        course=str(path),
        vx_mps=0.5,
        duration_s=8.0,
        overrides=("blind=true",),
    )
    summary = run_scenario(scenario)
    assert summary["terrain_knowledge"]["blind"] is True
    assert not summary["fell"]
    assert summary["distance_m"] > 3.0  # onto the tiles, which start at x = 0.8 m


def test_blind_is_for_the_kd_family(capsys: pytest.CaptureFixture[str]) -> None:
    rc = cli_main(["run", "--controller", "srbm", "--blind", "--duration", "0.1", "--no-video"])
    assert rc == 2
    assert "--blind" in capsys.readouterr().err
