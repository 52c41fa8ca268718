"""The soak engine (``benchmarks/soak.py``) on a few tiny episodes: the report is written,
its counts add up, a finished soak resumes without rerunning anything, and a failing
episode is recorded with its replayable spec instead of stopping the soak."""

from __future__ import annotations

import importlib
import json
from pathlib import Path
from types import ModuleType

import pytest


@pytest.fixture(scope="module")
def soak() -> ModuleType:
    """The soak engine (``benchmarks/soak.py`` is its command line)."""
    return importlib.import_module("gaitnet_mpc.experiments.soak")


def _table_rows(report: str) -> list[list[str]]:
    """The cells of the first Markdown table's body rows."""
    lines = report.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("| controller | robot"))
    rows = []
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def test_soak_writes_report_and_resumes(soak: ModuleType, tmp_path: Path) -> None:
    settings = soak.DrawSettings(seed=3, controllers=("stand", "srbm"), max_duration_s=0.05)
    options = soak.SoakOptions(episodes=3, workers=1, backend="process", out=tmp_path / "s.md")
    lines: list[str] = []

    records = soak.soak(options, settings, "test", log=lines.append)

    assert sorted(records) == [0, 1, 2]
    report = (tmp_path / "s.md").read_text()
    rows = _table_rows(report)
    cells, total = rows[:-1], rows[-1]
    assert total[0] == "**all**"
    # episodes, exceptions, non-finite torques, diverged, falls: the cells sum to the total
    for col in (2, 3, 4, 5, 8):
        assert sum(int(r[col]) for r in cells) == int(total[col])
    assert int(total[2]) == 3
    for r in records.values():
        assert r["exception"] is None, r["exception"]
        assert r["sim_s"] == pytest.approx(0.05)
        assert r["spec"]["controller"] in ("stand", "srbm")
    jsonl = options.jsonl
    assert jsonl.parent == tmp_path
    items = [json.loads(line) for line in jsonl.read_text().splitlines()]
    assert items[0] == {"soak_settings": settings.to_dict()}
    assert sorted(i["index"] for i in items[1:]) == [0, 1, 2]

    # a finished soak resumes without running anything; the spec of an episode is its draw
    lines.clear()
    again = soak.soak(options, settings, "test", log=lines.append)
    assert again == records
    assert lines[0].startswith("0 of 3 episodes to run")
    assert records[1]["spec"] == soak.draw_episode(settings, 1).to_dict()

    # other settings into the same JSONL are refused
    from gaitnet_mpc.errors import ConfigError

    with pytest.raises(ConfigError, match="--work-dir"):
        soak.soak(options, soak.DrawSettings(seed=4), "test", log=lines.append)


def test_failing_episode_is_recorded_and_listed(soak: ModuleType) -> None:
    settings = soak.DrawSettings(seed=0, controllers=("stand",), max_duration_s=0.05)
    good = soak.draw_episode(settings, 0)
    bad = soak.EpisodeSpec.from_dict({**good.to_dict(), "index": 1, "payload_kg": 100.0})

    record = soak.run_spec(bad.to_dict())

    assert record["exception"]["type"] == "ConfigError"
    assert "payload_kg" in record["exception"]["message"]
    assert not record["nonfinite_torque"]
    report = soak.make_report({1: record}, settings, 2, "test", 0.0, interrupted=False)
    assert "episode 1 (stand on" in report
    assert "--replay 1" in report
    assert json.dumps(record["spec"]) in report
    rows = _table_rows(report)
    assert rows[-1][2:4] == ["1", "1"]  # one episode, one exception


def test_nonfinite_torque_is_counted_apart(
    soak: ModuleType, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitnet_mpc.errors import ConfigError

    def nan_torques(spec: object, built: object) -> dict:
        # what Simulator.step raises for a controller's NaN torques
        raise ConfigError(
            "tau_nm", [float("nan")], "finite torques (a controller produced NaN/inf)"
        )

    monkeypatch.setattr(soak.worker, "simulate", nan_torques)  # what run_spec calls
    settings = soak.DrawSettings(seed=0, controllers=("kd",), max_duration_s=0.05)
    record = soak.run_spec(soak.draw_episode(settings, 0).to_dict())

    assert record["nonfinite_torque"]
    assert record["exception"]["type"] == "ConfigError"
    total = _table_rows(soak.make_report({0: record}, settings, 1, "test", 0.0, False))[-1]
    assert total[2:5] == ["1", "0", "1"]  # episodes, exceptions (others), non-finite torques


def test_solve_counts_read_the_failed_solves_of_the_mpc_stats(soak: ModuleType) -> None:
    from types import SimpleNamespace

    from gaitnet_mpc.control.base import MPCStats

    stats = MPCStats()
    stats.record(0.004, 3, True, True)
    stats.record(0.0, 5, False, False)  # unconverged, but a plan (and no solve time)
    stats.record(0.002, 1, False, True, failed=True)

    counts = soak.worker._solve_counts(SimpleNamespace(mpc_stats=stats))

    assert counts == {"solves": 3, "unconverged": 2, "qp_failures": 1}
    assert soak.worker._solve_counts(None) == {"solves": 0, "unconverged": 0, "qp_failures": 0}


def test_long_profile_draws_20_s_on_seeded_courses_with_pushes(soak: ModuleType) -> None:
    settings = soak.DrawSettings(seed=0, profile="long")
    specs = [soak.draw_episode(settings, i) for i in range(40)]

    assert {s.duration_s for s in specs} == {soak.LONG_DURATION_S}
    assert {s.course for s in specs} == set(soak.LONG_COURSES)
    assert all(s.course_seed is not None and 1 <= len(s.pushes) <= 3 for s in specs)
    assert "--profile long" in settings.command_flags()
    # the profile is part of the draw: the short profile of the same seed differs
    assert soak.draw_episode(soak.DrawSettings(seed=0), 0) != specs[0]
