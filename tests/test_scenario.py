"""The scenario: one typed description of a run, its TOML round trip, and replay."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gaitnet_mpc.cli import main
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.scenario import Scenario, make_scenario
from gaitnet_mpc.sim.disturbances import Push

QUIET = ["--no-video", "--no-plots", "--no-progress"]


def test_scenario_toml_round_trip_keeps_every_field(tmp_path: Path) -> None:
    """``to_toml`` then ``from_toml`` gives the same scenario, settings included."""
    scenario = make_scenario(
        controller="gaitnet",
        course="stepping-stones",
        course_seed=4,
        vx_mps=0.6,
        duration_s=2.5,
        pushes=(Push(t_s=1.0, force_world_n=(20.0, -5.0, 0.0), duration_s=0.2),),
        payload_kg=0.5,
        overrides=("dt_policy.gaitnet.max_retimes=3", "foothold_margin_m=0.07"),
    )
    path = tmp_path / "scenario.toml"
    path.write_text(scenario.to_toml("a header"))
    again = Scenario.from_toml(path)
    assert again == scenario
    assert again.config.dt_policy.kind == "gaitnet"
    assert again.config.dt_policy.gaitnet.max_retimes == 3


def test_controller_name_sets_the_dt_policy_and_a_mismatch_is_refused() -> None:
    kd = make_scenario(controller="kd", dt_s=0.055)
    assert kd.config.dt_policy.kind == "fixed" and kd.config.dt_policy.dt_s == 0.055
    assert make_scenario(controller="oracle").config.dt_policy.kind == "oracle"
    with pytest.raises(ConfigError, match=r"dt_policy\.kind"):
        make_scenario(controller="kd", overrides=("dt_policy.kind=gaitnet",))
    with pytest.raises(ConfigError, match="--gaitnet-weights"):
        make_scenario(controller="kd", gaitnet_weights="humanoid3d-wbmpc")


def test_bad_scenario_fields_are_named() -> None:
    with pytest.raises(ConfigError, match="duration_s"):
        Scenario(controller="stand", duration_s=0.0)
    with pytest.raises(ConfigError, match="controller"):
        Scenario(controller="walker")
    with pytest.raises(ConfigError, match="config"):
        Scenario(controller="kd")  # settings missing: make_scenario fills them
    with pytest.raises(ConfigError, match=r"scenario\.robots"):
        Scenario.from_table({"robots": "humanoid3d"})


@pytest.mark.slow
def test_scenario_toml_replays_the_run_with_an_identical_summary(tmp_path: Path) -> None:
    """``run --scenario RUN/scenario.toml`` simulates the same episode: summary.json is
    identical to the byte (the wall-clock figures live in timing.json)."""
    first, second = tmp_path / "a", tmp_path / "b"
    argv = ["run", "--controller", "gaitnet", "--course", "gap", "--seed", "3"]
    argv += ["--vx", "0.75", "--duration", "1.2", "--push", "t=0.6,fy=20,dur=0.1"]
    assert main([*argv, *QUIET, "--out", str(first)]) == 0
    scenario_file = first / "scenario.toml"
    assert main(["run", "--scenario", str(scenario_file), *QUIET, "--out", str(second)]) == 0
    a, b = (first / "summary.json").read_text(), (second / "summary.json").read_text()
    assert a == b
    summary = json.loads(a)
    assert summary["controller"] == "gaitnet" and summary["seed"] == 3
    assert summary["dt_policy"]["steps"], "Gait-Net chose the dts"
    assert "wall_time_s" not in summary
    assert "wall_time_s" in json.loads((first / "timing.json").read_text())
    assert (second / "scenario.toml").read_text() == scenario_file.read_text()


def test_scenario_option_excludes_the_other_run_options(tmp_path: Path) -> None:
    path = tmp_path / "scenario.toml"
    path.write_text(make_scenario(controller="stand", duration_s=0.1).to_toml())
    rc = main(["run", "--scenario", str(path), "--vx", "0.5", *QUIET, "--out", str(tmp_path / "o")])
    assert rc == 2
    assert not (tmp_path / "o").exists()
