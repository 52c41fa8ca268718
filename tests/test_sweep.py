"""``gaitnet-mpc sweep``: the bisection on fake survival functions, the case grids, bad
input refused before any work, and ``--quick`` push and protocol sweeps end to end
(files, resuming, the polar plot)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from gaitnet_mpc.cli import main
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.experiments.bisection import bisect_largest
from gaitnet_mpc.experiments.sweep_cases import DIRECTIONS, make_cases, mode_plan


# ----------------------------------------------------------------------------- bisection
def test_bisection_finds_the_bound_of_a_monotone_function() -> None:
    calls: list[int] = []

    def survives(i: int) -> bool:
        calls.append(i)
        return i <= 37

    b = bisect_largest(survives, 100, spot_fractions=(0.5, 0.25))
    assert (b.survived, b.failed) == (37, 38)
    assert not b.non_monotone and b.spot_failed == []
    assert len(calls) == len(set(calls)) <= 10  # each index once: log2(100) + spot checks
    assert 0 not in calls and 100 not in calls  # the ends only when reached


def test_bisection_ends_of_the_range() -> None:
    top = bisect_largest(lambda i: True, 8)
    assert (top.survived, top.failed) == (8, None)
    assert top.probes[-1] == (8, True)
    zero = bisect_largest(lambda i: False, 8, spot_fractions=(0.5,))
    assert (zero.survived, zero.failed) == (None, 0)
    assert zero.probes[-1] == (0, False) and not zero.non_monotone


def test_bisection_spot_checks_report_non_monotonicity() -> None:
    def survives(i: int) -> bool:  # a hole of falls below the bound
        return i <= 60 and not 25 <= i <= 35

    b = bisect_largest(survives, 100, spot_fractions=(0.5, 0.25))
    assert b.survived is not None and b.survived >= 36
    assert b.non_monotone and b.spot_failed and all(25 <= i <= 35 for i in b.spot_failed)
    # without spot checks the bisection cannot see the hole
    assert not bisect_largest(survives, 100).non_monotone


def test_the_scan_drops_a_survived_island_above_a_fall() -> None:
    """Survives up to 18, falls 19-22, survives 23-25 by luck, falls above: the bisection
    lands on the island at 25; the scan from half of it runs 13..24 in order, meets the
    fall at 19 and sets the bound to 18, the largest force below every fall."""
    calls: list[int] = []

    def survives(i: int) -> bool:
        calls.append(i)
        return i <= 18 or 23 <= i <= 25

    plain = bisect_largest(survives, 100)
    assert (plain.survived, plain.failed) == (25, 26)
    calls.clear()
    b = bisect_largest(survives, 100, spot_fractions=(0.5, 0.25), scan_from=0.5)
    assert (b.survived, b.failed, b.bisected) == (18, 19, 25)
    assert len(calls) == len(set(calls))  # each index run once
    assert not b.non_monotone
    # a monotone function: the scan confirms the bound and changes nothing
    mono = bisect_largest(lambda i: i <= 37, 100, scan_from=0.5)
    assert (mono.survived, mono.failed, mono.bisected) == (37, 38, 37)


def test_the_scan_bisects_again_when_the_first_scanned_force_falls() -> None:
    def survives(i: int) -> bool:  # survives to 9, and 25 by luck (the bisection's probes)
        return i <= 9 or i == 25

    b = bisect_largest(survives, 100, scan_from=0.5)
    assert (b.survived, b.failed, b.bisected) == (9, 10, 25)


def test_full_push_grid() -> None:
    plan = mode_plan("push", quick=False, seeds=10)
    assert len(plan.directions) == 8 and set(plan.directions) == set(DIRECTIONS)
    assert len(plan.phases) >= 4 and plan.speeds_mps == (0.25, 0.5, 0.75)
    cases = make_cases("push", ("gaitnet", "kd@0.055", "srbm"), plan)
    assert len({c["key"] for c in cases}) == len(cases) == 3 * 8 * len(plan.phases) * 3
    assert round(plan.hi / plan.resolution) == 100  # 0..500 N at 5 N


def test_terrain_courses_are_written_with_their_amplitude(tmp_path: Path) -> None:
    from gaitnet_mpc.experiments.sweep import SweepSettings, _write_courses
    from gaitnet_mpc.experiments.sweep_cases import uneven_file_name
    from gaitnet_mpc.terrain import load_course

    settings = SweepSettings("terrain", ("srbm",), quick=False, seeds=2)
    _write_courses(tmp_path, settings)
    path = tmp_path / uneven_file_name("uneven:0.06", 1)
    course = load_course(str(path))
    tops = [p.z_top_m for p in course.patches]
    assert 0.03 < max(abs(z) for z in tops) <= 0.06
    assert len(list((tmp_path / "courses").glob("*.json"))) == 6 * 2


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["push", "--controllers", "atlas"], "--controllers: got 'atlas'"),
        (["push", "--controllers", "kd@fast"], "--controllers: got 'kd@fast'"),
        (["push", "--controllers", "kd@5"], "--controllers: got 'kd@5'"),
        (["push", "--controllers", "kd+"], "--controllers: got 'kd+'"),
        (["push", "--controllers", "kd+fastest"], "--controllers: got 'kd+fastest'"),
        (["push", "--controllers", "srbm+realtime"], "--controllers: got 'srbm+realtime'"),
        (["push", "--workers", "0"], "--workers: got 0"),
        (["protocol", "--seeds", "0"], "--seeds: got 0"),
        (["push", "--directions", "up"], "--directions: got ('up',)"),
        (["push", "--phases", "1.0"], "--phases: got (1.0,)"),
        (["push", "--speeds", "x"], "--speeds: got 'x'"),
        (["push", "--speeds", "nan"], "--speeds: got 'nan'"),
        (["protocol", "--directions", "fwd"], "expected the push mode"),
    ],
)
def test_bad_input_is_refused_before_any_work(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "sw"
    assert main(["sweep", *args, "--quick", "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_controller_specs_carry_a_dt_and_a_preset() -> None:
    from gaitnet_mpc.experiments.sweep_cases import ControllerSpec, parse_controller

    assert parse_controller("gaitnet") == ControllerSpec("gaitnet", None, None)
    assert parse_controller("kd@0.055") == ControllerSpec("kd", 0.055, None)
    assert parse_controller("kd@0.045+realtime") == ControllerSpec("kd", 0.045, "realtime")
    assert parse_controller("gaitnet+realtime") == ControllerSpec("gaitnet", None, "realtime")
    assert parse_controller("gaitnet:humanoid3d-dagger+realtime") == ControllerSpec(
        "gaitnet", None, "realtime", "humanoid3d-dagger"
    )


def test_a_settings_file_in_a_controller_spec_is_a_config_file(tmp_path: Path) -> None:
    """``gaitnet+FILE.toml`` builds the scenario as ``run --config FILE.toml`` would; a
    file with an unknown key is refused before any case starts."""
    from gaitnet_mpc.experiments.sweep import SweepSettings, check_inputs
    from gaitnet_mpc.experiments.sweep_cases import parse_controller
    from gaitnet_mpc.scenario import make_scenario

    file = tmp_path / "pose.toml"
    file.write_text("[sequential.kd]\nw_pose = [1.0, 1.0, 1.0, 20000.0, 20000.0, 2000.0]\n")
    args = parse_controller(f"gaitnet+{file}").scenario_args()
    assert args["preset"] is None and args["config_file"] == str(file)
    scenario = make_scenario(**args, duration_s=1.0)
    assert scenario == make_scenario(controller="gaitnet", config_file=file, duration_s=1.0)
    assert scenario != make_scenario(controller="gaitnet", duration_s=1.0)
    bad = tmp_path / "bad.toml"
    bad.write_text("[sequential.kd]\nw_posture = 1.0\n")
    settings = SweepSettings("push", (f"gaitnet+{bad}",), speeds_mps=(0.5,))
    with pytest.raises(ConfigError, match="w_posture"):
        check_inputs(settings, tmp_path / "out")


def test_a_part_of_the_push_grid() -> None:
    from gaitnet_mpc.experiments.sweep import SweepSettings

    settings = SweepSettings(
        "push", ("srbm",), speeds_mps=(0.5,), directions=("fwd",), phases=(0.0,)
    )
    plan = settings.plan
    assert (plan.speeds_mps, plan.directions, plan.phases) == ((0.5,), ("fwd",), (0.0,))
    assert plan.hi == 500.0  # the rest of the full grid's settings
    assert settings.to_dict() != SweepSettings("push", ("srbm",)).to_dict()  # its identity


def test_unknown_mode_and_file_out_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["sweep", "jump", "--out", str(tmp_path / "x")])
    assert exc.value.code == 2
    assert "invalid choice: 'jump'" in capsys.readouterr().err
    file = tmp_path / "file.txt"
    file.write_text("x")
    assert main(["sweep", "push", "--quick", "--out", str(file)]) == 2
    assert "--out: got" in capsys.readouterr().err and file.read_text() == "x"


# ----------------------------------------------------------------------------- end to end
def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as fh:
        return list(csv.DictReader(fh))


def test_quick_push_sweep_end_to_end_and_resume(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "push"
    argv = ["sweep", "push", "--quick", "--workers", "2", "--out", str(out)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert err.count("[1/2]") == 1 and err.count("[2/2]") == 1  # one line per case
    for name in ("cases.jsonl", "sweep.csv", "sweep.md", "status.json", "push_polar.png"):
        assert (out / name).is_file(), name
    assert (out / "push_polar.png").read_bytes()[:4] == b"\x89PNG"
    lines = (out / "cases.jsonl").read_text().splitlines()
    records = [json.loads(line) for line in lines[1:]]
    rows = _rows(out / "sweep.csv")
    assert len(rows) == len(records) == 2
    assert {r["direction"] for r in rows} == {"fwd", "left"}
    assert sum(int(r["episodes"]) for r in rows) == sum(
        len(r["result"]["episodes"]) for r in records
    )
    for row in rows:
        assert row["controller"] == "srbm" and row["phase_measured"] == "0.25"
        if row["survived_n"]:
            assert float(row["survived_impulse_ns"]) == pytest.approx(
                0.2 * float(row["survived_n"])
            )
    status = json.loads((out / "status.json").read_text())
    assert status["state"] == "done" and len(status["done"]) == 2 and status["todo"] == []
    report = (out / "sweep.md").read_text()
    assert "gaitnet-mpc sweep push" in report
    assert "Phase: where in the controller's own executed step" in report  # the rule used

    # the same command again: no new work, the same cases
    assert main(argv) == 0
    assert "nothing to do" in capsys.readouterr().err
    assert (out / "cases.jsonl").read_text().splitlines() == lines
    assert len(_rows(out / "sweep.csv")) == 2

    # another sweep's settings in this folder: refused before any work
    other = ["sweep", "protocol", "--quick", "--out", str(out)]
    assert main(other) == 2
    assert "a folder of the same sweep settings" in capsys.readouterr().err
    assert (out / "cases.jsonl").read_text().splitlines() == lines


def test_quick_protocol_sweep_end_to_end(tmp_path: Path) -> None:
    out = tmp_path / "protocol"
    argv = ["sweep", "protocol", "--quick", "--no-progress", "--workers", "1", "--out", str(out)]
    assert main(argv) == 0
    rows = _rows(out / "sweep.csv")
    assert len(rows) == 1 and rows[0]["seed"] == "0" and int(rows[0]["pushes"]) >= 1
    text = (out / "sweep.md").read_text()
    assert "| srbm |" in text and "CPU:" in text and "Wall time" in text
    assert json.loads((out / "status.json").read_text())["state"] == "done"
    assert not (out / "push_polar.png").exists()


# ----------------------------------------------------------------------------- push timing
@pytest.mark.parametrize("controller", ["gaitnet", "kd@0.055"])
def test_a_push_lands_at_its_phase_of_the_controllers_own_step(controller: str) -> None:
    """The ``"executed"`` rule: every controller is pushed at the asked phase of its own
    step with the left foot in the air, whatever its step durations (``gaitnet``'s vary;
    for ``kd`` at 0.055 s the nominal grid's step after the settling time, step 2, has the
    right foot in the air)."""
    from gaitnet_mpc.experiments.sweep_cases import _push_case

    plan = mode_plan("push", quick=True, seeds=1)
    assert plan.phase_of == "executed"
    case = {"controller": controller, "speed_mps": 0.5, "direction": "fwd", "phase": 0.25}
    record = _push_case(case, plan)
    assert record["swing_foot"] == "left"
    assert record["phase_measured"] == pytest.approx(0.25, abs=0.01)


def test_sweeps_made_before_the_rule_keep_the_nominal_grid() -> None:
    from gaitnet_mpc.experiments.push_timing import push_time_s
    from gaitnet_mpc.experiments.sweep_cases import ModePlan

    old = mode_plan("push", quick=False, seeds=1).to_dict()
    del old["phase_of"]  # a sweep folder written before the rule existed
    assert ModePlan.from_dict(old).phase_of == "nominal"
    assert push_time_s(None, 3.0, 0.25) == pytest.approx(14 * 0.225 + 0.25 * 0.225)
    with pytest.raises(ConfigError, match="phase_of"):
        ModePlan(phase_of="measured")
