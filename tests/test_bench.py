"""`gaitnet-mpc bench` (issue 17): the timed episode measures what it claims, the RTI
replan really solves one QP per replan, and bad cases are refused before any timing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitnet_mpc.cli import main
from gaitnet_mpc.experiments.bench import (
    BenchCase,
    EpisodeSpec,
    _combine,
    perf_markdown,
    rss_mb,
    timed_episode,
)

SPEC = EpisodeSpec(seconds=0.5)


@pytest.fixture(scope="module")
def episodes() -> dict[str, object]:
    return {
        "kd": timed_episode(BenchCase("kd"), SPEC),
        "rti": timed_episode(BenchCase("rti", "kd", ("replan_j_max=1",)), SPEC),
    }


def test_timed_episode_counts_ticks_and_solves(episodes: dict) -> None:
    kd = episodes["kd"]
    assert not kd.fell and kd.sim_s == pytest.approx(0.5)
    assert kd.distance_m > 0.05  # it walked forwards
    n_solves = len(kd.solve_ms)
    assert any(kd.full) and not all(kd.full)  # a step start and replans
    # every tick is timed once in the simulator; ticks with a solve are not low-level ticks
    assert len(kd.sim_ms) == 500
    assert len(kd.tick_ms) + n_solves == 500
    assert all(t > 0.0 for t in kd.tick_ms) and kd.wall_s > 0.0
    assert kd.rss_start_mb > 10.0 and kd.rss_end_mb > 10.0


def test_rti_replans_solve_one_qp_and_full_solves_converge(episodes: dict) -> None:
    kd, rti = episodes["kd"], episodes["rti"]
    full = np.asarray(rti.full)
    assert set(np.asarray(rti.qps)[~full]) == {1}
    assert np.mean(np.asarray(kd.qps)[~np.asarray(kd.full)]) > 1.5
    # the first full solve is the same problem in both
    assert rti.qps[0] == kd.qps[0]


def test_combine_takes_the_minimum_per_solve_and_reports(episodes: dict) -> None:
    kd = episodes["kd"]
    slower = type(kd)(**{**kd.__dict__, "solve_ms": [2 * t for t in kd.solve_ms]})
    res = _combine(BenchCase("kd"), [slower, kd])
    np.testing.assert_allclose(res.solve_ms, kd.solve_ms)
    assert res.identical_rounds
    text = perf_markdown([res], SPEC, 2, None, "kd", kd, "kd", "gaitnet-mpc bench")
    assert "| kd |" in text and "RSS" in text and "gaitnet-mpc bench" in text


def test_rss_is_a_plausible_size() -> None:
    assert 10.0 < rss_mb() < 1e5


@pytest.mark.parametrize(
    "case", ["nolabel", "x=stand", "x=kd:no_such_key=1", "x=kd:replan_j_max=0"]
)
def test_bench_refuses_bad_cases_before_timing(case: str, tmp_path: Path, capsys) -> None:
    rc = main(["bench", "--case", case, "--out", str(tmp_path / "perf.md")])
    assert rc == 2
    assert "error" in capsys.readouterr().err
    assert not (tmp_path / "perf.md").exists()


def test_bench_refuses_an_unknown_baseline_revision(tmp_path: Path, capsys) -> None:
    out = tmp_path / "perf.md"
    rc = main(["bench", "--case", "x=kd", "--baseline", "no-such-revision", "--out", str(out)])
    assert rc == 2
    assert "--baseline" in capsys.readouterr().err
    assert not out.exists()


def test_the_realtime_cases_run_the_preset_itself() -> None:
    """The default cases named ``--preset realtime`` get the preset file's settings (a copy
    of them once missed its warm start)."""
    from gaitnet_mpc.experiments.bench import DEFAULT_CASES, build_case

    for case in DEFAULT_CASES:
        _, ctrl = build_case(case, SPEC)
        rti = "--preset realtime" in case.label
        assert (ctrl.config.replan_j_max == 1) == rti
        assert ctrl.config.warm_start_replans == ctrl.config.converge_new_stages == rti
