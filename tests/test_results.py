"""Run-folder results: plots, ``gaitnet-mpc plot``, ``gaitnet-mpc compare``, MPC log."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from gaitnet_mpc.cli import main
from gaitnet_mpc.control.base import MomentumPrediction, MPCStats, Telemetry
from gaitnet_mpc.results import load_run
from gaitnet_mpc.results.plots import make_plots
from gaitnet_mpc.runner.logs import EpisodeLog, MPCLog, TelemetryRecorder
from gaitnet_mpc.terrain import load_course

BASE_PLOTS = ("velocity.png", "course_top.png", "steps.png", "contact_torque.png")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _assert_png(path: Path) -> None:
    """The file exists, is > 1 kB, is a PNG that imageio decodes to a plausible image."""
    import imageio.v3 as iio

    assert path.is_file(), path
    assert path.stat().st_size > 1024, path
    assert path.read_bytes()[:8] == PNG_MAGIC
    img = iio.imread(path)
    assert img.ndim == 3 and img.shape[2] in (3, 4)
    assert 300 <= img.shape[0] <= 3000 and 400 <= img.shape[1] <= 3000
    assert img.std() > 1.0  # not blank


@pytest.fixture(scope="module")
def stand_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 1 s standing run with a push, with video and plots (the default outputs)."""
    out = tmp_path_factory.mktemp("results") / "stand"
    rc = main(
        [
            "run",
            "--controller",
            "stand",
            "--duration",
            "1.0",
            "--push",
            "t=0.3,fx=30,fy=0,dur=0.1",
            "--out",
            str(out),
            "--no-progress",
        ]
    )
    assert rc == 0
    return out


def test_run_folder_has_summary_video_and_plots(stand_run: Path) -> None:
    import imageio.v3 as iio

    summary = json.loads((stand_run / "summary.json").read_text())
    assert summary["controller"] == "stand"
    assert summary["duration_s"] == pytest.approx(1.0)
    assert summary["torque_limits_nm"] == [33.5, 67.0]
    assert (stand_run / "course.json").is_file()
    assert not (stand_run / "mpc_log.csv").exists()  # no MPC
    frames = iio.imread(stand_run / "video.mp4")
    assert frames.shape[0] == pytest.approx(30, abs=1)
    assert frames.shape[1:3] == (480, 640)
    for name in BASE_PLOTS:
        _assert_png(stand_run / "plots" / name)
    assert not (stand_run / "plots" / "momentum.png").exists()  # kd only
    assert not list((stand_run / "plots").glob(".*"))  # no temporary files left


def test_plot_command_regenerates_the_plots(stand_run: Path) -> None:
    for png in (stand_run / "plots").glob("*.png"):
        png.unlink()
    assert main(["plot", str(stand_run)]) == 0
    for name in BASE_PLOTS:
        _assert_png(stand_run / "plots" / name)


def test_compare_two_runs(stand_run: Path, tmp_path: Path) -> None:
    other = tmp_path / "stand-still"
    args = ["run", "--duration", "0.3", "--out", str(other)]
    assert main([*args, "--no-video", "--no-plots", "--no-progress"]) == 0
    out = tmp_path / "cmp"
    assert main(["compare", str(stand_run), str(other), "--out", str(out)]) == 0
    with (out / "compare.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [r["run"] for r in rows] == ["stand", "stand-still"]
    assert rows[0]["controller"] == "stand" and rows[0]["fell"] == "false"
    assert rows[0]["solves"] == ""  # no MPC
    md = (out / "compare.md").read_text()
    assert "| stand |" in md and "| stand-still |" in md
    _assert_png(out / "compare.png")


def test_plot_and_compare_reject_a_folder_that_is_not_a_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plot", str(tmp_path)]) == 2
    assert "RUN_DIR" in capsys.readouterr().err
    assert main(["compare", str(tmp_path / "missing"), "--out", str(tmp_path / "c")]) == 2
    assert "RUN_DIR" in capsys.readouterr().err


# --------------------------------------------------------------- MPC log (no simulation)


class _FakeMPCController:
    """Reports what ``kd`` reports: mpc_stats and telemetry with a momentum prediction."""

    def __init__(self) -> None:
        self.mpc_stats = MPCStats()
        self.prediction: MomentumPrediction | None = None

    def telemetry(self) -> Telemetry:
        return Telemetry(0.05, "left", "right", 0.25, self.prediction)

    def last_dt_decision(self) -> dict | None:
        return {"dts_s": [0.05, 0.055], "fallback": "spread", "frozen": False}

    def solve(self, t_s: float, full: bool) -> None:
        h = np.array([1.0 + t_s, 0.0, 0.0, 0.0, 0.2, -0.1])
        self.prediction = MomentumPrediction(t_s, t_s + 0.05, h)
        self.mpc_stats.record(0.004, 3 if full else 1, True, full)


def test_telemetry_recorder_logs_each_solve_and_the_prediction() -> None:
    ctrl = _FakeMPCController()
    probe = TelemetryRecorder(ctrl)  # type: ignore[arg-type]
    assert probe.stance_code() == 0.0 and probe.step_dt() == 0.05
    ctrl.solve(0.0, True)
    probe.after_compute(0.0)
    probe.after_compute(0.001)  # no new solve: no row
    ctrl.solve(0.002, False)
    probe.after_compute(0.002)
    assert probe.log is not None and len(probe.log.rows) == 2
    assert probe.last_qps == 1 and probe.last_ms == pytest.approx(4.0)
    row = dict(zip(MPCLog.columns, probe.log.rows[0], strict=True))
    assert row["full_solve"] == 1 and row["n_qps"] == 3 and row["dt_s"] == 0.05
    assert row["t_pred_s"] == pytest.approx(0.05) and row["lGx_pred"] == pytest.approx(1.0)
    assert (row["dt_calls"], row["dt_first_s"], row["dt_fallback"]) == (2, 0.05, 1)
    assert row["failed"] == 0 and row["dt_frozen"] == 0
    replan = dict(zip(MPCLog.columns, probe.log.rows[1], strict=True))
    assert np.isnan(replan["dt_calls"]) and np.isnan(replan["dt_fallback"])
    # measured momentum at the tick at or after t_pred
    t = np.arange(0, 0.1, 0.001)
    log = np.zeros((t.size, len(EpisodeLog.columns)))
    log[:, 0] = t
    i0 = EpisodeLog.columns.index("lGx")
    log[:, i0] = 10 * t  # l_G,x
    log[:, i0 + 4] = 0.3  # k_G,y
    probe.log.fill_measured(log, slice(i0, i0 + 6))
    row = dict(zip(MPCLog.columns, probe.log.rows[0], strict=True))
    assert row["lGx_meas"] == pytest.approx(0.5) and row["kGy_meas"] == pytest.approx(0.3)


def test_controller_without_mpc_writes_no_mpc_log() -> None:
    probe = TelemetryRecorder(SimpleNamespace(mpc_stats=None, telemetry=lambda: None))  # type: ignore[arg-type]
    probe.after_compute(0.0)
    assert probe.log is None and np.isnan(probe.stance_code()) and np.isnan(probe.step_dt())


def _synthetic_kd_run(root: Path) -> Path:
    """A run folder as ``kd`` on stepping stones would write it (no simulation)."""
    course = load_course("stepping-stones")
    t = np.arange(0.0, 2.0, 0.001)
    cols = EpisodeLog.columns
    log = np.zeros((t.size, len(cols)))
    log[:, cols.index("t_s")] = t
    log[:, cols.index("com_x_m")] = 0.5 * t
    log[:, cols.index("com_vx_mps")] = 0.5 + 0.1 * np.sin(25 * t)
    log[:, cols.index("cmd_vx_mps")] = 0.5
    log[:, cols.index("lGx")] = 16 * log[:, cols.index("com_vx_mps")]
    log[:, cols.index("fz_left_n")] = 160 * (np.sin(12 * t) > 0)
    log[:, cols.index("tau_abs_max_nm")] = 20 + 10 * np.sin(t)
    log[:, cols.index("tau_limit_ratio_max")] = 0.6
    log[:, cols.index("mpc_dt_s")] = np.where(t < 1, 0.05, 0.04)
    ts = t[::20]
    mpc = np.full((ts.size, len(MPCLog.columns)), np.nan)
    mpc[:, :6] = np.column_stack(
        [ts, ts % 0.25 < 0.02, np.ones_like(ts) * 2, np.ones_like(ts), 3 + ts, 0.05 + 0 * ts]
    )
    mpc[:, 6] = ts + 0.05
    mpc[:, 7] = 8.1
    mpc[:, 8:10] = 0.1
    mpc[:, 10] = 8.0
    steps = [0.25] * 4 + [0.2] * 5
    holds = [
        {"t_s": 0.25 * (i + 1), "foot": f, "pos_m": [0.2 * (i + 1), y, 0.0], "patch": 0,
         "allowed": i != 3}
        for i, (f, y) in enumerate([("right", -0.08), ("left", 0.08)] * 4)
    ]  # fmt: skip
    summary = {
        "robot": "humanoid3d",
        "controller": "kd",
        "course": course.name,
        "command": {"vx_mps": 0.5, "vy_mps": 0.0, "yaw_rate_radps": 0.0},
        "duration_s": 2.0,
        "fell": True,
        "fall_time_s": 1.9,
        "distance_m": 0.95,
        "mean_speed_mps": 0.475,
        "speed_rmse_mps": 0.07,
        "footholds": holds,
        "foothold_violations": 1,
        "step_durations_s": steps,
        "mpc": {"solves": ts.size, "solve_ms_median": 4.0, "solve_ms_p99": 5.0,
                "qps_per_solve_mean": 2.0},
    }  # fmt: skip
    (root / "summary.json").write_text(json.dumps(summary))
    (root / "log.csv").write_text(EpisodeLog(rows=list(log)).to_csv())
    (root / "mpc_log.csv").write_text(MPCLog(rows=mpc.tolist()).to_csv())
    (root / "course.json").write_text(json.dumps(course.to_dict()))
    return root


def test_kd_run_folder_gets_the_momentum_plot(tmp_path: Path) -> None:
    run_dir = _synthetic_kd_run(tmp_path)
    run = load_run(run_dir)
    assert run.mpc_log is not None and run.course is not None
    written = make_plots(run_dir)
    assert sorted(p.name for p in written) == sorted([*BASE_PLOTS, "momentum.png"])
    for path in written:
        _assert_png(path)


def test_planned_footholds_are_drawn_as_discs_on_the_ground() -> None:
    import mujoco

    from gaitnet_mpc.runner.episode import _draw_footholds

    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
    scene = mujoco.MjvScene(model, maxgeom=3)
    holds = [("left", np.array([0.3, 0.1, 0.012])), ("right", np.array([0.5, -0.1, 0.032]))]
    _draw_footholds(scene, holds + holds, height_m=0.01)  # 4 markers, room for 3
    assert scene.ngeom == 3
    np.testing.assert_allclose(scene.geoms[0].pos, [0.3, 0.1, 0.004], atol=1e-6)
    np.testing.assert_allclose(scene.geoms[1].pos, [0.5, -0.1, 0.024], atol=1e-6)
    assert scene.geoms[0].rgba[2] > scene.geoms[0].rgba[0]  # left: blue
    assert scene.geoms[1].rgba[0] > scene.geoms[1].rgba[2]  # right: red
