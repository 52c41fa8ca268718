"""``run_scenario(out_dir=...)`` follows the rules of ``gaitnet-mpc run --out``: a new or
empty folder, a lock while it writes, ``overwrite=True`` to replace its own earlier run
(nothing stale left), a refusal otherwise; video and plots on request (issue 51)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.results.outdir import LOCK, folder_lock
from gaitnet_mpc.scenario import Scenario, make_scenario, run_scenario

SHORT_S = 0.2  # simulated time of every run here [s]


@pytest.fixture(scope="module")
def scenario() -> Scenario:
    return make_scenario(robot="biped2d", controller="stand", duration_s=SHORT_S)


def test_a_new_folder_gets_the_run_and_no_video_or_plots_by_default(
    tmp_path: Path, scenario: Scenario
) -> None:
    out = tmp_path / "run"
    summary = run_scenario(scenario, out_dir=out)
    assert summary["duration_s"] == pytest.approx(SHORT_S)
    assert (out / "summary.json").is_file() and (out / "scenario.toml").is_file()
    assert not (out / "video.mp4").exists() and not (out / "plots").exists()
    assert not (out / LOCK).exists()  # the lock went with the run


def test_a_folder_holding_other_files_is_refused(tmp_path: Path, scenario: Scenario) -> None:
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("not a run")
    for overwrite in (False, True):
        with pytest.raises(ConfigError, match="out_dir") as info:
            run_scenario(scenario, out_dir=out, overwrite=overwrite)
        assert str(out) in str(info.value)
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]  # untouched


def test_an_earlier_run_is_replaced_only_with_overwrite_and_nothing_stale_remains(
    tmp_path: Path, scenario: Scenario
) -> None:
    out = tmp_path / "run"
    run_scenario(scenario, out_dir=out)
    (out / "video.mp4").write_bytes(b"an older run's video")  # as an older run left them
    (out / "plots").mkdir()
    (out / "plots" / "x.png").write_bytes(b"an older run's plot")
    (out / "status.json").write_text('{"state": "running"}')
    with pytest.raises(ConfigError, match="overwrite=True") as info:
        run_scenario(scenario, out_dir=out)
    assert str(out) in str(info.value)
    assert (out / "video.mp4").exists()  # a refusal removes nothing
    run_scenario(scenario, out_dir=out, overwrite=True)
    assert not (out / "video.mp4").exists()
    assert not (out / "plots").exists()
    assert not (out / "status.json").exists()
    assert (out / "summary.json").is_file()


def test_a_folder_another_process_writes_is_refused(tmp_path: Path, scenario: Scenario) -> None:
    out = tmp_path / "run"
    with folder_lock(out):  # as a run in progress (gaitnet-mpc run or run_scenario) holds it
        with pytest.raises(ConfigError, match=f"locked by pid {os.getpid()}"):
            run_scenario(scenario, out_dir=out)
    assert not (out / "summary.json").exists()
    run_scenario(scenario, out_dir=out)  # free again; the lock file went with the lock
    assert not (out / LOCK).exists()


def test_plots_true_writes_the_plots_folder(tmp_path: Path, scenario: Scenario) -> None:
    out = tmp_path / "run"
    run_scenario(scenario, out_dir=out, plots=True)
    assert any((out / "plots").glob("*.png"))


def test_video_or_plots_without_a_folder_are_refused(scenario: Scenario) -> None:
    for options in ({"video": True}, {"plots": True}):
        with pytest.raises(ConfigError, match="out_dir"):
            run_scenario(scenario, **options)  # type: ignore[arg-type]
