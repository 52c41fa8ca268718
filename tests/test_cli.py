"""The ``gaitnet-mpc`` commands: outputs, and clear errors on bad input.

Plots and ``compare`` are tested in ``test_results.py``.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from gaitnet_mpc.cli import main

SUMMARY_KEYS = {
    "robot",
    "controller",
    "course",
    "command",
    "duration_s",
    "fell",
    "fall_time_s",
    "distance_m",
    "mean_speed_mps",
    "speed_rmse_mps",
    "footholds",
    "foothold_violations",
    "step_durations_s",
    "mpc",
    "diverged",
    "self_collisions",
    "self_collision_first_t_s",
    "self_collision_max_depth_m",
    "self_collision_pairs",
    "final_tilt_rad",
    "final_com_height_m",
}


def test_run_writes_summary_log_and_video(tmp_path: Path) -> None:
    out = tmp_path / "run"
    rc = main(
        [
            "run",
            "--robot",
            "humanoid3d",
            "--controller",
            "stand",
            "--course",
            "flat",
            "--duration",
            "1.2",
            "--push",
            "t=0.5,fx=20,fy=0,dur=0.1",
            "--out",
            str(out),
            "--no-progress",
            "--no-plots",
        ]
    )
    assert rc == 0
    assert not (out / "plots").exists()
    assert (out / "course.json").is_file()
    summary = json.loads((out / "summary.json").read_text())
    assert SUMMARY_KEYS <= summary.keys()
    timing = json.loads((out / "timing.json").read_text())  # the wall-clock figures
    assert {"wall_time_s", "render_time_s", "realtime_factor"} <= timing.keys()
    assert not timing.keys() & summary.keys()
    assert tomllib.loads((out / "scenario.toml").read_text())["controller"] == "stand"
    assert summary["fell"] is False and summary["diverged"] is False
    assert summary["self_collisions"] == 0 and summary["self_collision_pairs"] == []
    assert summary["duration_s"] == pytest.approx(1.2)
    assert summary["mpc"] is None
    lines = (out / "log.csv").read_text().splitlines()
    assert len(lines) == 1 + 1200
    header = lines[0].split(",")
    for col in ("tau_abs_max_nm", "mpc_dt_s", "mpc_n_qps", "mpc_solve_ms", "stance_foot"):
        assert col in header
    last = dict(zip(header, lines[-1].split(","), strict=True))
    assert last["mpc_dt_s"] == "nan" and last["stance_foot"] == "nan"  # no gait schedule
    assert last["self_contact"] == "0"
    assert header[-6:] == [f"fext_{a}_n" for a in "xyz"] + [f"text_{a}_nm" for a in "xyz"]
    assert last["fext_z_n"] == "nan"  # `stand` has no disturbance observer
    import imageio.v3 as iio

    frames = iio.imread(out / "video.mp4")
    assert frames.shape[0] == pytest.approx(1.2 * 30, abs=1)
    assert frames.std() > 1.0  # not a blank image


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--controller", "nope"], "--controller: got 'nope'"),
        (["--course", "moon"], "course"),
        (["--course", "/nonexistent/course.json"], "course"),
        (["--push", "t=1,fx=2"], "--push"),
        (["--duration", "-1"], "--duration: got -1.0"),
        (["--vx", "9"], "--vx: got 9.0"),
        (["--payload-kg", "-2"], "--payload-kg: got -2.0"),
        (["--payload-kg", "17"], "--payload-kg: got 17.0, expected a mass in [0, 16] kg"),
        (["--robot", "biped2d", "--payload-kg", "10.5"], "--payload-kg: got 10.5"),
        (["--push", "t=0.1,fx=1e9,dur=0.1"], "--push fx: got 1000000000.0, expected a force"),
        (["--push", "t=0.1,fx=500,dur=0.5"], "--push impulse: got '250 N s"),
        (
            ["--controller", "srbm", "--preview"],
            "--preview: got 'srbm', expected one of kd, gaitnet, oracle",
        ),
        (
            ["--controller", "kd", "--set", "sequential.kd.w_forse=1"],
            "--set sequential.kd.w_forse: got 1, expected a field of KDConfig; close matches: "
            "sequential.kd.w_force",
        ),
        (
            ["--controller", "kd", "--set", "sequential.kd.horizon=0.5"],
            "--set sequential.kd.horizon: got 0.5, expected an integer",
        ),
        (["--controller", "srbm", "--set", "mpc.horizon=0"], "--set mpc.horizon: got 0"),
        (["--controller", "kd", "--set", "oops"], "--set: got 'oops', expected KEY=VALUE"),
        (["--controller", "srbm", "--preset", "paper"], "--preset: got 'paper', expected one of"),
        (["--controller", "stand", "--set", "dt_s=1"], "the stand controller has no settings"),
        (["--controller", "kd", "--config", "/nonexistent/x.toml"], "--config: got '/nonex"),
    ],
)
def test_bad_input_fails_fast_with_the_field(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc = main(["run", "--no-video", "--no-progress", "--out", str(tmp_path / "x"), *args])
    assert rc == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "x").exists()  # refused before the run


def test_unknown_robot_is_an_argparse_error() -> None:
    with pytest.raises(SystemExit) as exc:
        main(["run", "--robot", "atlas"])
    assert exc.value.code == 2


def test_viewer_without_a_display_fails_fast(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    out = tmp_path / "never"
    rc = main(["run", "--viewer", "--duration", "0.1", "--out", str(out), "--no-progress"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "gaitnet-mpc: error: --viewer: got 'no display" in err
    assert "drop --viewer" in err
    assert not out.exists()  # failed before simulating anything


def test_viewer_with_an_unreachable_display_fails_fast(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("DISPLAY", ":98765")  # no X server there
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    out = tmp_path / "never"
    rc = main(["run", "--viewer", "--duration", "0.1", "--out", str(out), "--no-progress"])
    assert rc == 2
    assert "--viewer: got \"display ':98765'" in capsys.readouterr().err
    assert not out.exists()


def test_subcommands_parse() -> None:
    from gaitnet_mpc.cli import build_parser

    parser = build_parser()
    args = parser.parse_args(["plot", "runs/a"])
    assert args.cmd == "plot" and args.run_dir == Path("runs/a")
    args = parser.parse_args(["compare", "runs/a", "runs/b", "--out", "cmp"])
    assert args.run_dirs == [Path("runs/a"), Path("runs/b")] and args.out == "cmp"
    args = parser.parse_args(["run", "--no-plots", "--viewer"])
    assert args.no_plots and args.viewer
    with pytest.raises(SystemExit):
        parser.parse_args(["compare"])  # at least one run folder


def test_kd_preview_run_records_its_options(tmp_path: Path) -> None:
    """`--preview` builds kd with the footstep preview, walks, and is recorded in the run."""
    out = tmp_path / "pv"
    argv = ["run", "--controller", "kd", "--preview", "--course", "stepping-stones"]
    argv += ["--vx", "0.5", "--dt", "0.055", "--duration", "0.6"]
    rc = main([*argv, "--no-video", "--no-plots", "--no-progress", "--out", str(out)])
    assert rc == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controller_options"] == {"dt_s": 0.055, "preview": True}
    assert not summary["fell"]


def test_set_is_written_to_config_toml_and_config_repeats_the_run(tmp_path: Path) -> None:
    """``--set`` changes the run's ``config.toml``; ``--config`` of that file repeats the
    run (same settings, same log but for the wall-clock solve times)."""
    import tomllib

    quiet = ["--no-video", "--no-plots", "--no-progress"]
    argv = ["run", "--controller", "srbm", "--vx", "0.3", "--duration", "0.3", *quiet]
    first, second = tmp_path / "a", tmp_path / "b"
    sets = ["--set", "mpc.w_force=2e-6", "--set", "max_step_m=0.3", "--dt", "0.05"]
    assert main([*argv, *sets, "--out", str(first)]) == 0
    config = tomllib.loads((first / "config.toml").read_text())
    assert config["mpc"]["w_force"] == 2e-6 and config["max_step_m"] == 0.3
    assert config["dt_s"] == 0.05 and config["com_height_m"] == "none"
    summary = json.loads((first / "summary.json").read_text())
    assert summary["controller_options"]["set"] == ["mpc.w_force=2e-6", "max_step_m=0.3"]
    assert main([*argv, "--config", str(first / "config.toml"), "--out", str(second)]) == 0
    assert (second / "config.toml").read_text() == (first / "config.toml").read_text()

    def without_solve_ms(run: Path) -> list[list[str]]:
        rows = [line.split(",") for line in (run / "log.csv").read_text().splitlines()]
        col = rows[0].index("mpc_solve_ms")
        return [row[:col] + row[col + 1 :] for row in rows]

    assert without_solve_ms(second) == without_solve_ms(first)


def test_kd_config_toml_holds_preset_and_overrides(tmp_path: Path) -> None:
    """kd on the planar robot: ``--preset paper`` (Table V) and ``--set`` in config.toml."""
    import tomllib

    out = tmp_path / "kd"
    argv = ["run", "--robot", "biped2d", "--controller", "kd", "--preset", "paper"]
    argv += ["--set", "replan_j_max=7", "--set", "sequential.kd.w_force=2e-4"]
    argv += ["--duration", "0.05", "--no-video", "--no-plots", "--no-progress"]
    assert main([*argv, "--out", str(out)]) == 0
    config = tomllib.loads((out / "config.toml").read_text())
    assert config["replan_j_max"] == 7 and config["keep_feet_apart"] is True
    kd = config["sequential"]["kd"]
    assert kd["w_force"] == 2e-4 and kd["w_pose"] == [200.0, 200.0, 200.0, 300.0, 300.0, 300.0]
    assert kd["weight_units"] == "motion"
    assert kd["qp_options"] == {} and config["preview"] == "none"


def _stand_run(out: Path, *extra: str) -> int:
    args = ["run", "--controller", "stand", "--duration", "0.05", "--no-progress"]
    return main([*args, "--no-video", "--no-plots", "--out", str(out), *extra])


def test_out_is_checked_before_the_simulation(tmp_path: Path, capsys) -> None:
    """A file, a path under a file, and '' as --out fail at once (exit 2) with a named
    error; nothing is simulated or written."""
    a_file = tmp_path / "file.txt"
    a_file.write_text("x")
    for bad, expected in (
        (a_file, "this path is a file"),
        (a_file / "run", "is a file"),
        (Path(""), "not empty"),
    ):
        assert _stand_run(bad) == 2
        err = capsys.readouterr().err
        assert "--out" in err and expected in err
    assert a_file.read_text() == "x"


def test_a_folder_with_a_run_is_refused_unless_overwrite(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    assert _stand_run(out) == 0
    (out / "video.mp4").write_bytes(b"an old video")  # an artifact the new run will not make
    before = (out / "summary.json").read_text()
    assert _stand_run(out) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert (out / "summary.json").read_text() == before  # untouched
    assert _stand_run(out, "--overwrite") == 0
    assert not (out / "video.mp4").exists()  # only the new run's files remain
    names = sorted(p.name for p in out.iterdir())
    assert names == [
        "course.json",
        "events.csv",
        "log.csv",
        "scenario.toml",
        "status.json",
        "summary.json",
        "timing.json",
    ]
    (out / "notes.txt").write_text("mine")
    assert _stand_run(out, "--overwrite") == 2  # never deletes what a run did not write
    assert "notes.txt" in capsys.readouterr().err


def test_default_run_folders_are_unique(tmp_path: Path, monkeypatch) -> None:
    from gaitnet_mpc.results.outdir import claim_output_folder
    from gaitnet_mpc.results.rundir import RUN_ARTIFACTS

    monkeypatch.chdir(tmp_path)
    made = set()
    for _ in range(3):
        with claim_output_folder(
            None, option="--out", default_prefix="", artifacts=RUN_ARTIFACTS
        ) as out:
            made.add(out)
    assert len(made) == 3 and all(p.is_dir() and p.parent.name == "runs" for p in made)
    assert not any(any(p.iterdir()) for p in made)  # the lock file is gone with the lock


def test_duration_under_a_few_ticks_is_refused(tmp_path: Path, capsys) -> None:
    assert main(["run", "--duration", "0.0004", "--out", str(tmp_path / "r")]) == 2
    assert "--duration: got 0.0004" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_ctrl_c_and_sigterm_save_the_run_and_exit_130(tmp_path: Path, sig: str) -> None:
    """Stopped mid-run by Ctrl-C (SIGINT) or SIGTERM, ``run`` writes what was simulated
    (``interrupted: true``), says INTERRUPTED and exits 130."""
    import os
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "gaitnet_mpc.cli", "run", "--controller", "stand"]
    cmd += ["--duration", "120", "--no-video", "--no-plots", "--no-progress", "--out", str(out)]
    env = {**os.environ, "MUJOCO_GL": "egl"}
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, text=True)
    assert proc.stderr is not None
    for line in proc.stderr:  # printed just before the simulation loop starts
        if line.startswith("simulating "):
            break
    time.sleep(1.0)
    proc.send_signal(getattr(signal, sig))
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "INTERRUPTED at t = " in stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and 0 < summary["duration_s"] < 120


def test_options_without_effect_are_warned_and_recorded(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    assert _stand_run(out, "--vx", "0.5", "--dt", "0.05", "--push", "t=5,fx=10,dur=0.1") == 0
    err = capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["warnings"]) == 3
    for text in summary["warnings"]:
        assert f"warning: {text}" in err
    assert any("--vx 0.5 has no effect" in w for w in summary["warnings"])
    assert any("the run ends at 0.05 s" in w for w in summary["warnings"])


def test_a_push_key_given_twice_is_refused(capsys) -> None:
    assert main(["run", "--push", "t=1,fx=10,fx=20,dur=0.1"]) == 2
    assert "'fx' is given twice" in capsys.readouterr().err


def test_a_course_file_that_is_not_utf8_is_a_named_error(tmp_path: Path, capsys) -> None:
    course = tmp_path / "bad.json"
    course.write_bytes(b'{"name": "\xff\xfe"}')
    assert main(["run", "--course", str(course), "--out", str(tmp_path / "r")]) == 2
    assert "UTF-8" in capsys.readouterr().err


def test_gaitnet_options_are_checked(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    argv = ["run", "--controller", "gaitnet", "--robot", "biped2d", "--dt", "0.05"]
    argv += ["--duration", "0.05", "--out", str(out), "--no-video", "--no-plots", "--no-progress"]
    assert main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert any("Gait-Net chooses every step's dt" in w for w in summary["warnings"])
    assert summary["dt_policy"]["policy"] == "gaitnet"
    capsys.readouterr()
    missing = str(tmp_path / "none.npz")
    assert main([*argv[:5], "--gaitnet-weights", missing, "--out", str(tmp_path / "r2")]) == 2
    assert "--gaitnet-weights" in capsys.readouterr().err
    assert main(["run", "--controller", "kd", "--gaitnet-weights", missing]) == 2
    assert "expected --controller gaitnet" in capsys.readouterr().err
