"""Fig. 6: the gap-row courses, the optimised-dt policy (``kd-optdt``: an NLP with dt as a
variable) and ``gaitnet-mpc reproduce fig6 --quick`` end to end (files, resuming, a
folder of other settings refused)."""

from __future__ import annotations

import csv
import itertools
import json
from pathlib import Path

import numpy as np
import pytest

from gaitnet_mpc.cli import main
from gaitnet_mpc.errors import CourseFormatError
from gaitnet_mpc.mpc.dt_nlp import SOLVED, NLPDt
from gaitnet_mpc.terrain.builtin_courses import gap_row_course


# ----------------------------------------------------------------------------- courses
@pytest.mark.parametrize("width_m", [0.05, 0.075, 0.15])
def test_gap_row_has_four_gaps_of_the_width(width_m: float) -> None:
    course = gap_row_course(width_m, seed=7)
    patches = sorted(course.patches, key=lambda p: p.x_min)
    gaps = [b.x_min - a.x_max for a, b in itertools.pairwise(patches)]
    grounds = [p.x_max - p.x_min for p in patches[1:-1]]
    assert len(gaps) == 4 and np.allclose(gaps, width_m, atol=1e-9)
    assert 1.0 <= patches[0].x_max <= 1.5  # the first gap's start
    assert all(0.4 - 1e-9 <= g <= 0.8 + 1e-9 for g in grounds)
    assert patches[-1].x_min < 4.5  # four 15 cm gaps end before x = 4.5 m
    assert course.seed == 7
    assert gap_row_course(width_m, seed=7).to_dict() == course.to_dict()  # seeded
    assert gap_row_course(width_m, seed=8).to_dict() != course.to_dict()


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"width_m": 0.0, "seed": 1}, "gap-row.width_m"),
        ({"width_m": 0.1, "seed": -1}, "gap-row.seed"),
        ({"width_m": 0.1, "seed": 1, "count": 0}, "gap-row.count"),
    ],
)
def test_gap_row_refuses_bad_parameters(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(CourseFormatError, match=field):
        gap_row_course(**kwargs)  # type: ignore[arg-type]


# ----------------------------------------------------------------------------- kd-optdt
@pytest.fixture(scope="module")
def optdt_walk() -> tuple[NLPDt, dict[str, object]]:
    """1.2 s of kd-optdt on the biped over flat ground: its policy and the summary."""
    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.scenario import build_episode, make_scenario

    scenario = make_scenario(robot="biped2d", controller="kd-optdt", vx_mps=0.5, duration_s=1.2)
    episode = build_episode(scenario)
    summary = run_episode(
        episode.sim, episode.controller, scenario.command, scenario.duration_s, progress=False
    )
    policy = episode.controller.dt_policy  # type: ignore[attr-defined]
    assert isinstance(policy, NLPDt)
    return policy, summary


def test_optdt_walks_with_each_step_dt_from_the_nlp(
    optdt_walk: tuple[NLPDt, dict[str, object]],
) -> None:
    policy, summary = optdt_walk
    assert not summary["fell"] and float(summary["distance_m"]) > 0.3  # type: ignore[arg-type]
    block = summary["dt_policy"]
    assert isinstance(block, dict) and block["policy"] == "optdt"
    assert len(policy.decisions) >= 4  # one NLP per step start (0.15-0.3 s steps)
    lo, hi = policy.config.bounds_s
    for d in policy.decisions:
        assert d.status in SOLVED and d.fallback is None
        assert lo <= d.dt_s <= hi and np.isfinite(d.cost)


def test_optdt_optimum_is_no_worse_than_either_dt_bound(
    optdt_walk: tuple[NLPDt, dict[str, object]],
) -> None:
    """The NLP's dt ranges over the bounds, where its references are the probes' own: its
    optimum is at most the CD problem's optimum at either bound (solved by CD-SQP)."""
    from gaitnet_mpc.table2.cd_sqp import CDSQP, CDSQPConfig

    policy, _ = optdt_walk
    problem = policy._problem  # the last step start's problem
    assert problem is not None
    last = policy.decisions[-1]
    sqp = CDSQP(CDSQPConfig(qpsol="qpoases", qpsol_options=(("sparse", True),)))
    for dt in policy.config.bounds_s:
        res = sqp.solve(policy._probe(problem, dt))
        assert res.converged, res.status
        assert last.cost <= res.cost * (1 + 1e-3) + 1e-6, (dt, last.cost, res.cost)


# ----------------------------------------------------------------------------- command
def test_reproduce_fig6_quick_end_to_end(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "fig6"
    argv = ["reproduce", "fig6", "--quick", "--workers", "2", "--out", str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "| (1) fixed dt (`kd`) |" in printed and "## The paper's claims" in printed
    for name in ("fig6.md", "fig6.csv", "fig6.png", "cases.jsonl", "status.json"):
        assert (out / name).is_file(), name
    for method in ("kd", "kd-optdt", "gaitnet"):
        assert (out / f"strip_{method}.png").is_file()
    rows = list(csv.DictReader((out / "fig6.csv").open()))
    assert sorted(r["method"] for r in rows) == ["gaitnet", "kd", "kd-optdt"]
    for r in rows:  # 3 s at 0.5 m/s over the 10 cm layout of seed 0: every method walks
        assert r["success"] == "True" and float(r["distance_m"]) > 1.0, r
    steps = {r["method"]: float(r["step_std_s"]) for r in rows}
    assert steps["kd"] == 0.0  # a fixed dt: every step 0.225 s
    course = json.loads((out / "courses/gap-row-10cm-seed0.json").read_text())
    assert len(course["patches"]) == 5
    status = json.loads((out / "status.json").read_text())
    assert status["state"] == "done" and not status["todo"]
    # resuming: nothing left to run, the same files again
    before = (out / "cases.jsonl").read_text()
    assert main(argv) == 0
    assert (out / "cases.jsonl").read_text() == before
    # a folder of other settings is refused before any work
    assert main([*argv, "--seeds", "2"]) == 2
    assert "--out" in capsys.readouterr().err
