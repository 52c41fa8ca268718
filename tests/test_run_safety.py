"""Trustworthy runs (issue 18): the help text, warnings for options without effect, how a
run's end state is reported, SIGTERM outside the simulation loop, the video camera and
overlay, and what the plots and ``compare`` show.

Each test simulates at most a fraction of a second of the ``stand`` controller.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitnet_mpc.cli import main
from gaitnet_mpc.cli import run as run_cli
from gaitnet_mpc.errors import ConfigError


def _stand(out: Path, *extra: str, duration_s: str = "0.05", video: bool = False) -> int:
    argv = ["run", "--controller", "stand", "--duration", duration_s, "--no-progress"]
    argv += ["--no-plots", "--out", str(out), *extra]
    return main(argv if video else [*argv, "--no-video"])


@pytest.fixture(scope="module")
def stand_video_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 0.2 s standing run with the side camera and a push (video, no plots)."""
    out = tmp_path_factory.mktemp("safety") / "stand"
    push = "t=0.05,fx=20,dur=0.05"
    assert _stand(out, "--camera", "side", "--push", push, duration_s="0.2", video=True) == 0
    return out


# ----------------------------------------------------------------------------- --help


def test_run_help_lists_every_option_default_range_controller_and_course(capsys) -> None:
    from gaitnet_mpc.control.registry import CONTROLLERS
    from gaitnet_mpc.terrain.builtin_courses import BUILTIN_COURSES

    with pytest.raises(SystemExit):
        main(["run", "--help"])
    text = " ".join(capsys.readouterr().out.split())  # unwrap argparse's line breaks
    for name in [*CONTROLLERS, *BUILTIN_COURSES]:
        assert f" {name} " in text, name
    for part in (
        "default: humanoid3d",
        "default: gaitnet",
        "default: flat",
        "[-1.5, 1.5]",
        "[-0.5, 0.5]",
        "in [0.01, 3600] (default: 10.0)",
        "[0.03, 0.2]",
        "0.045 s",
        "fz",
        "default: oblique",
        "NOT UPRIGHT",
        "INTERRUPTED",
    ):
        assert part in text, part


def test_help_bounds_agree_with_the_code() -> None:
    """The numbers ``--help`` states are the ones the code uses."""
    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.walking import WalkingConfig
    from gaitnet_mpc.dt_policy import NOMINAL_DT_S
    from gaitnet_mpc.gait.step_durations import StepDurations
    from gaitnet_mpc.mpc.sequential import FixedDt

    assert run_cli.DEFAULT_DT_S == FixedDt().dt_s == WalkingConfig().dt_s == StepDurations().dt_s
    assert run_cli.DEFAULT_DT_S == NOMINAL_DT_S
    Command(run_cli.VX_MAX_MPS, run_cli.VY_MAX_MPS, run_cli.YAW_RATE_MAX_RADPS)  # accepted
    with pytest.raises(ConfigError):
        Command(run_cli.VX_MAX_MPS + 1e-6)


# ----------------------------------------------------------------------------- warnings


def test_seed_on_a_fixed_course_and_a_repeated_push_are_warned_and_recorded(
    tmp_path: Path, capsys
) -> None:
    out = tmp_path / "run"
    push = "t=0.01,fx=5,dur=0.01"
    assert _stand(out, "--seed", "3", "--push", push, "--push", push) == 0
    err = capsys.readouterr().err
    warnings = json.loads((out / "summary.json").read_text())["warnings"]
    assert any("--seed 3 has no effect" in w and "'flat'" in w for w in warnings)
    assert any("given twice" in w for w in warnings)
    for text in warnings:
        assert f"warning: {text}" in err


def test_lateral_commands_on_the_planar_robot_are_warned(tmp_path: Path) -> None:
    out = tmp_path / "run"
    assert _stand(out, "--robot", "biped2d", "--vy", "0.2", "--yaw-rate", "0.5") == 0
    warnings = json.loads((out / "summary.json").read_text())["warnings"]
    assert any("--vy 0.2 has no effect on the planar robot" in w for w in warnings)
    assert any("--yaw-rate 0.5 has no effect on the planar robot" in w for w in warnings)


# ----------------------------------------------------------------------------- end state


def test_ended_upright_uses_half_the_fall_detector_margins() -> None:
    from gaitnet_mpc.runner.episode import ended_upright
    from gaitnet_mpc.sim.simulator import SimConfig

    config = SimConfig()  # falls: tilt > 1 rad, CoM below 50 % of its start height
    h0 = 0.555
    assert ended_upright(0.1, h0, h0, config)
    assert not ended_upright(0.8, h0 - 0.16, h0, config)  # the example
    assert not ended_upright(0.8, h0, h0, config)  # tilted only
    assert not ended_upright(0.1, h0 - 0.16, h0, config)  # low only (> 25 % of 0.555 m)
    assert ended_upright(0.5, 0.75 * h0, h0, config)  # exactly at both margins


def _summary(**over: Any) -> dict[str, Any]:
    base = {
        "duration_s": 2.0,
        "distance_m": 0.5,
        "foothold_violations": 1,
        "self_collisions": 0,
        "final_tilt_rad": 0.1,
        "final_com_height_m": 0.55,
        "com_height0_m": 0.555,
        "interrupted": False,
        "fell": False,
        "fall_time_s": None,
        "fall_reason": None,
        "ended_upright": True,
    }
    return {**base, **over}


def test_outcome_line_says_ok_not_upright_fell_or_interrupted() -> None:
    ok = run_cli.outcome_line(_summary())
    assert ok.startswith("OK: 0.50 m in 2.00 s, 1 foothold violations")
    assert "final tilt 0.10 rad" in ok and "final CoM height 0.550 m (0.5 cm below" in ok
    tilted = run_cli.outcome_line(
        _summary(ended_upright=False, final_tilt_rad=0.8, final_com_height_m=0.395)
    )
    assert tilted.startswith("NOT UPRIGHT at the end (t = 2.000 s")
    assert "final tilt 0.80 rad" in tilted and "16.0 cm below the start" in tilted
    fell = run_cli.outcome_line(_summary(fell=True, fall_time_s=1.25, fall_reason="tilt"))
    assert fell.startswith("FELL at t = 1.250 s (tilt)")
    stopped = run_cli.outcome_line(_summary(interrupted=True, fell=True, fall_time_s=1.0))
    assert stopped.startswith("INTERRUPTED at t = 2.000 s")


def test_summary_records_the_end_state_and_outcome(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    assert _stand(out) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["outcome"] == "ok" and summary["ended_upright"] is True
    assert summary["com_height0_m"] == pytest.approx(summary["final_com_height_m"], abs=0.01)
    assert 0.0 <= summary["final_tilt_rad"] < 0.1
    stdout = capsys.readouterr().out
    assert '"outcome": "ok"' in stdout and stdout.rstrip().splitlines()[-1].startswith("OK: ")


# ----------------------------------------------------------------------------- signals


@pytest.mark.parametrize("where", ["start-up", "plotting"])
def test_sigterm_outside_the_simulation_loop_exits_130_without_traceback(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys, where: str
) -> None:
    """SIGTERM while ``run`` starts up or plots is handled as Ctrl-C (exit 130, one line);
    the previous SIGTERM handler is restored afterwards."""

    def sigterm_self(*args: Any) -> Any:
        os.kill(os.getpid(), signal.SIGTERM)
        raise AssertionError("SIGTERM did not interrupt")  # pragma: no cover

    monkeypatch.chdir(tmp_path)
    before = signal.getsignal(signal.SIGTERM)
    target = "robots.load_robot" if where == "start-up" else "results.plots.make_plots"
    monkeypatch.setattr(f"gaitnet_mpc.{target}", sigterm_self)
    out = tmp_path / "run"
    argv = ["run", "--duration", "0.02", "--no-video", "--no-progress", "--out", str(out)]
    assert main(argv) == 130
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    assert signal.getsignal(signal.SIGTERM) == before
    if where == "plotting":  # the run was saved before plotting began; its outcome is printed
        assert "plotting interrupted" in captured.err
        assert captured.out.rstrip().splitlines()[-1].startswith("OK: ")
        assert json.loads((out / "summary.json").read_text())["interrupted"] is False
    else:
        assert "gaitnet-mpc: interrupted" in captured.err
        assert not out.exists()


# ----------------------------------------------------------------------------- video


def test_video_config_checks_the_camera() -> None:
    from gaitnet_mpc.runner.episode import VideoConfig

    assert VideoConfig().camera == "oblique" and VideoConfig().overlay
    with pytest.raises(ConfigError, match="--camera"):
        VideoConfig(camera="top")


def test_overlay_draws_text_top_left_only() -> None:
    from gaitnet_mpc.runner.episode import _overlay_lines, overlay_text

    frame = np.full((120, 200, 3), 128, dtype=np.uint8)
    from gaitnet_mpc.command import Command

    lines = _overlay_lines(1.234, Command(0.5), 0.045)
    assert lines == ["t =   1.23 s", "cmd vx = +0.50 m/s", "step dt = 45 ms"]
    assert _overlay_lines(0.0, Command(), float("nan"))[-1] == "step dt = -"
    drawn = overlay_text(frame, lines)
    assert drawn.shape == frame.shape and drawn.dtype == np.uint8
    changed = np.any(drawn != frame, axis=2)
    assert changed[:40, :120].any() and not changed[60:, :].any()


def test_run_records_the_video_camera(stand_video_run: Path) -> None:
    import imageio.v3 as iio

    summary = json.loads((stand_video_run / "summary.json").read_text())
    assert summary["video"] == {"camera": "side", "overlay": True, "fps": 30}
    frame = iio.imread(stand_video_run / "video.mp4", index=0)
    assert np.median(frame[6:40, 6:90]) < 60  # the overlay's dark box in the corner


# ----------------------------------------------------------------------------- plots


def _with_violation_and_solves(src: Path, dst: Path) -> Path:
    """A copy of run folder ``src`` with a foothold violation and a fake ``mpc_log.csv``
    (a solve every 20 ms, some longer than that)."""
    shutil.copytree(src, dst)
    summary = json.loads((dst / "summary.json").read_text())
    summary["footholds"] = [
        {"t_s": 0.08, "foot": "left", "pos_m": [0.1, 0.1, 0.0], "patch": 0, "allowed": True},
        {"t_s": 0.12, "foot": "right", "pos_m": [0.2, -0.1, 0.0], "patch": None, "allowed": False},
    ]
    summary["foothold_violations"] = 1
    summary["step_durations_s"] = [0.225, 0.25, 0.2]
    (dst / "summary.json").write_text(json.dumps(summary))
    t = np.arange(0.0, 0.2, 0.02)
    rows = ["t_s,full_solve,n_qps,converged,solve_ms"]
    rows += [f"{ti:g},0,3,1,{15.0 if i % 2 else 30.0}" for i, ti in enumerate(t)]
    (dst / "mpc_log.csv").write_text("\n".join(rows) + "\n")
    return dst


def _figures(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """Capture the figures ``make_plots`` saves, by file name."""
    from gaitnet_mpc.results import plots

    figs: dict[str, Any] = {}

    def keep(fig: Any, path: Any, dpi: int = 110) -> Path:
        figs[Path(path).name] = fig
        return Path(path)

    monkeypatch.setattr(plots, "save_figure_atomic", keep)
    return figs


def test_plots_label_forces_mark_violations_and_show_the_budget(
    stand_video_run: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitnet_mpc.results.plots import make_plots, mpc_period_ms

    assert mpc_period_ms(np.array([0.0, 0.02, 0.04, 0.045, 0.065])) == pytest.approx(20.0)
    assert mpc_period_ms(np.array([0.3])) is None
    run = _with_violation_and_solves(stand_video_run, tmp_path / "run")
    figs = _figures(monkeypatch)
    make_plots(run)
    force_ax = figs["contact_torque.png"].axes[0]
    assert "vertical contact force" in force_ax.get_ylabel()
    assert "world z" in force_ax.get_ylabel() and "normal" not in force_ax.get_ylabel()
    for name in ("velocity.png", "steps.png", "contact_torque.png"):
        xs = [line.get_xdata()[0] for ax in figs[name].axes for line in ax.get_lines()]
        assert 0.12 in xs, name  # the violation's time on every time plot
    steps = figs["steps.png"].axes
    labels = [t.get_text() for t in steps[2].get_legend().get_texts()]
    assert any("real-time budget: MPC period 20 ms (5/10 solves over)" in x for x in labels)
    assert steps[0].xaxis.get_major_locator()._integer
    top = figs["course_top.png"].axes[0]
    texts = {t.get_text(): t for t in top.texts}
    assert "0.08" in texts and texts["0.12"].get_fontweight() == "bold"
    assert "violations (t = 0.12 s)" in top.get_title()


def test_compare_normalises_by_duration_and_lists_duration_dt_preview(
    stand_video_run: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import csv

    from gaitnet_mpc.results import compare

    short = tmp_path / "short"
    assert _stand(short) == 0
    figs: dict[str, Any] = {}
    real_save = compare.save_figure_atomic

    def keep(fig: Any, path: Any, dpi: int = 110) -> Path:
        figs[Path(path).name] = fig
        return real_save(fig, path, dpi)

    monkeypatch.setattr(compare, "save_figure_atomic", keep)
    out = tmp_path / "cmp"
    assert main(["compare", str(stand_video_run), str(short), "--out", str(out)]) == 0
    rows = list(csv.DictReader((out / "compare.csv").open()))
    assert [float(r["duration_s"]) for r in rows] == [0.2, 0.05]
    assert all(r["preview"] == "false" and r["outcome"] == "ok" for r in rows)
    assert all(r["dt_s_median"] == "" for r in rows)  # stand has no gait
    _, ax_s, _, ax_d = figs["compare.png"].axes
    assert "mean forward speed" in ax_d.get_ylabel()
    heights = [bar.get_height() for bar in ax_d.patches]
    assert heights == pytest.approx([float(r["mean_speed_mps"]) for r in rows])
    assert ax_s.xaxis.get_major_locator()._integer


def test_empty_out_is_reported_as_given(capsys) -> None:
    assert main(["run", "--out", ""]) == 2
    assert "--out: got ''" in capsys.readouterr().err


def test_compare_out_pointing_at_a_file_is_a_named_error(
    stand_video_run: Path, tmp_path: Path, capsys
) -> None:
    a_file = tmp_path / "file.txt"
    a_file.write_text("x")
    assert main(["compare", str(stand_video_run), "--out", str(a_file)]) == 2
    assert "--out" in capsys.readouterr().err and a_file.read_text() == "x"


def test_named_errors_survive_pickling() -> None:
    """A worker's named error reaches the parent process as itself (issue 37)."""
    import pickle

    from gaitnet_mpc.errors import ConfigError, CourseFormatError, QPSolveError

    for err in (
        ConfigError("--set", "a=b", "a known key"),
        CourseFormatError("patches[0].x", [1, 0], "x_min < x_max"),
        QPSolveError("piqp", "max_iter", "after 200 iterations"),
    ):
        back = pickle.loads(pickle.dumps(err))
        assert type(back) is type(err) and str(back) == str(err)
