"""Nothing lost, nothing mixed (issue 37): exit codes, exclusive output folders, inputs
checked before work, named errors for malformed files, interruption at any time, and
kill-and-resume of ``collect`` and ``train`` equal to an uninterrupted run."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from gaitnet_mpc.cli import main
from gaitnet_mpc.cli.main import EXIT_CODES
from gaitnet_mpc.results.outdir import LOCK, folder_lock

ROOT = Path(__file__).resolve().parents[1]
CLI = [sys.executable, "-m", "gaitnet_mpc.cli"]
ENV = {**os.environ, "MUJOCO_GL": "egl"}
#: A push that tips the standing biped over within 0.3 s.
TIPPING_PUSH = "t=0.1,fx=300,dur=0.3"


def _stand(out: Path, *extra: str, duration_s: str = "0.05") -> int:
    argv = ["run", "--controller", "stand", "--duration", duration_s, "--no-progress"]
    return main([*argv, "--no-plots", "--no-video", "--out", str(out), *extra])


@pytest.fixture(scope="module")
def stand_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("jobs") / "stand"
    assert _stand(out) == 0
    return out


# ----------------------------------------------------------------------------- exit codes
def test_a_fall_exits_1_unless_allow_fall(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    fall = ["--robot", "biped2d", "--push", TIPPING_PUSH]
    assert _stand(tmp_path / "a", *fall, duration_s="1.5") == 1
    assert "FELL at t = " in capsys.readouterr().out
    status = json.loads((tmp_path / "a" / "status.json").read_text())
    assert status["state"] == "done" and status["exit_code"] == 1 and status["todo"] == []
    assert _stand(tmp_path / "b", *fall, "--allow-fall", duration_s="1.5") == 0


def test_exit_codes_are_listed_in_help_and_readme(capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit):
        main(["--help"])
    text = capsys.readouterr().out
    readme = (ROOT / "README.md").read_text()
    for code in EXIT_CODES:
        assert f"  {code} " in text
        assert f"| {code} |" in readme


def test_an_unexpected_exception_is_exit_4_and_ctrl_c_130(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    from gaitnet_mpc.cli import plot

    def boom(args: object) -> int:
        raise RuntimeError("a bug")

    monkeypatch.setattr(plot, "main", boom)
    assert main(["plot", "somewhere"]) == 4
    assert "internal error" in capsys.readouterr().err

    def interrupted(args: object) -> int:
        raise KeyboardInterrupt

    monkeypatch.setattr(plot, "main", interrupted)
    assert main(["plot", "somewhere"]) == 130


# from 0.3 s on: before that the interpreter itself may still be starting (site, .pth
# files), where a signal is Python's own business, before any code of the package runs
@pytest.mark.parametrize("delay_s", [0.3, 0.7, 1.2])
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_during_start_up_exits_130_without_traceback(
    tmp_path: Path, delay_s: float, sig: signal.Signals
) -> None:
    cmd = [*CLI, "run", "--controller", "kd", "--duration", "30", "--no-video", "--no-progress"]
    proc = subprocess.Popen(
        [*cmd, "--out", str(tmp_path / "r")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
    )
    time.sleep(delay_s)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err


# ----------------------------------------------------------------------------- folders
def test_a_folder_another_process_writes_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "run"
    with folder_lock(out):  # as a run in progress holds it
        assert _stand(out) == 2
    err = capsys.readouterr().err
    assert "--out" in err and f"locked by pid {os.getpid()}" in err
    assert _stand(out) == 0  # free again; the lock file went with the lock
    assert not (out / LOCK).exists()


def test_two_runs_started_at_once_into_one_folder_never_both_write(tmp_path: Path) -> None:
    out = tmp_path / "run"
    cmd = [*CLI, "run", "--controller", "stand", "--duration", "0.3", "--no-video"]
    cmd += ["--no-plots", "--no-progress", "--out", str(out)]
    procs = [
        subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
        for _ in range(2)
    ]
    codes = sorted(p.wait(timeout=120) for p in procs)
    errs = " ".join(p.stderr.read() for p in procs if p.stderr is not None)
    assert codes == [0, 2], errs  # one ran, the other was refused (locked or not empty)
    assert "--out" in errs
    summary = json.loads((out / "summary.json").read_text())
    assert summary["duration_s"] == pytest.approx(0.3)


def test_train_refuses_an_existing_model_unless_overwrite(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "model"
    out.mkdir()
    (out / "gaitnet.npz").write_bytes(b"an earlier model")
    data = ROOT / "data" / "gaitnet-kd-biped2d"
    assert main(["train", "--data", str(data), "--out", str(out)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    (out / "notes.txt").write_text("mine")
    assert main(["train", "--data", str(data), "--out", str(out), "--overwrite"]) == 2
    assert "notes.txt" in capsys.readouterr().err
    assert (out / "gaitnet.npz").read_bytes() == b"an earlier model"


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["reproduce", "table1", "--data", "no/such/folder"], "no/such/folder"),
        (["reproduce", "table2", "--problems", "0"], "--problems"),
        (["reproduce", "table2", "--problems", "100000000"], "--problems"),
        (["collect", "--course", "no-such-course.json", "--no-progress"], "course"),
        (["collect", "--workers", "0", "--no-progress"], "--workers"),
        (["train", "--data", "no/such/folder"], "no/such/folder"),
        (["train", "--data", "data/gaitnet-kd-biped2d", "--members", "0"], "--members"),
        (["train", "--data", "data/gaitnet-kd-biped2d", "--epochs", "10000000"], "--epochs"),
        (["compare", "no/such/run"], "no/such/run"),
        (["plot", "no/such/run"], "no/such/run"),
    ],
)
def test_inputs_are_checked_before_any_work_or_write(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture,
    argv: list[str],
    field: str,
) -> None:
    monkeypatch.chdir(ROOT)
    out = tmp_path / "out"
    extra = [] if argv[0] == "plot" else ["--out", str(out)]
    assert main([*argv, *extra]) == 2
    assert field in capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())


def test_an_out_that_is_a_file_is_refused_by_every_command(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    file = tmp_path / "file"
    file.write_text("x")
    data = str(ROOT / "data" / "gaitnet-kd-biped2d")
    for argv in (
        ["collect", "--no-progress"],
        ["train", "--data", data],
        ["reproduce", "table1", "--data", data],
    ):
        assert main([*argv, "--out", str(file / "sub")]) == 2, argv
        assert "is a file" in capsys.readouterr().err
    assert file.read_text() == "x"


def test_bench_refuses_an_existing_report_before_timing(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    report = tmp_path / "perf.md"
    report.write_text("earlier")
    argv = ["bench", "--case", "s=kd", "--seconds", "0.05", "--rounds", "1", "--no-profile"]
    assert main([*argv, "--out", str(report)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert report.read_text() == "earlier"


# ----------------------------------------------------------------------------- files
def test_a_malformed_weights_file_is_a_named_error(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    bad = tmp_path / "w.npz"
    bad.write_bytes(b"not an npz archive")
    np.savez(tmp_path / "partial.npz", format_version=np.array(1))
    for path in (bad, tmp_path / "partial.npz"):
        argv = ["--controller", "gaitnet", "--gaitnet-weights", str(path)]
        assert _stand(tmp_path / "r", *argv) == 2
        err = capsys.readouterr().err
        assert str(path) in err and "Traceback" not in err
    assert not (tmp_path / "r").exists()


def test_compare_names_a_wrong_typed_summary_field(
    stand_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    bad = tmp_path / "bad"
    shutil.copytree(stand_run, bad)
    summary = json.loads((bad / "summary.json").read_text())
    (bad / "summary.json").write_text(json.dumps({**summary, "duration_s": "long"}))
    assert main(["compare", str(stand_run), str(bad), "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert "duration_s: got 'long', expected a number" in err
    assert not (tmp_path / "c").exists()


def test_compare_warns_when_runs_are_not_like_for_like(
    stand_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    other = tmp_path / "biped"
    assert _stand(other, "--robot", "biped2d", "--course", "gap") == 0
    capsys.readouterr()
    assert main(["compare", str(stand_run), str(other), "--out", str(tmp_path / "c")]) == 0
    err = capsys.readouterr().err
    assert "different robots" in err and "different courses" in err
    assert "different robots" in (tmp_path / "c" / "compare.md").read_text()


# ----------------------------------------------------------------------------- pool errors
def test_a_worker_error_in_collect_is_logged_with_its_set_and_traceback(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitnet_mpc.dataset import CollectProtocol
    from gaitnet_mpc.errors import PartialFailure
    from gaitnet_mpc.experiments import collect as collect_mod
    from gaitnet_mpc.parallel import Outcome

    def runs(specs, options, on_progress):  # type: ignore[no-untyped-def]
        for spec in specs:
            if spec.index == 0:
                try:
                    raise RuntimeError("the teacher broke")
                except RuntimeError as exc:
                    yield Outcome(spec, error=exc)
            else:
                yield Outcome(spec, collect_mod._walk_set(spec))

    monkeypatch.setattr(collect_mod, "_runs", runs)
    protocol = CollectProtocol(robot="biped2d", teacher="kd", sets=2, seconds_total=2.0)
    options = collect_mod.CollectOptions(progress=False)
    with pytest.raises(PartialFailure, match="1 failed") as info:
        collect_mod.collect(protocol, tmp_path, options, "cmd", log=lambda _: None)
    log = (tmp_path / collect_mod.ERRORS_LOG).read_text()
    name = protocol.set_spec(0).name
    assert name in log and "RuntimeError: the teacher broke" in log and "Traceback" in log
    status = json.loads((tmp_path / "status.json").read_text())
    assert status["state"] == "failed" and status["exit_code"] == 3
    assert status["done"] == [protocol.set_spec(1).name] and status["todo"] == [name]
    assert info.value.failed == [name]
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert not manifest["complete"] and len(manifest["sets"]) == 1


# ----------------------------------------------------------------------------- kill + resume
def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _status_done(folder: Path) -> list[str]:
    """The items ``folder/status.json`` says are done (none while it is unreadable)."""
    try:
        return list(json.loads((folder / "status.json").read_text())["done"])
    except (OSError, ValueError, KeyError):
        return []


def _kill_when(
    cmd: list[str], ready: Callable[[], bool], timeout_s: float = 300.0
) -> tuple[int, str]:
    """Start ``cmd``, SIGTERM it once ``ready()``; its exit code and stderr."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
    deadline = time.monotonic() + timeout_s
    while not ready() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    return proc.returncode, err


@pytest.mark.slow
def test_train_killed_mid_run_resumes_to_the_uninterrupted_model(tmp_path: Path) -> None:
    pytest.importorskip("torch")
    data = ROOT / "data" / "gaitnet-kd-biped2d"
    args = ["train", "--data", str(data), "--members", "3", "--epochs", "60", "--no-progress"]
    killed = tmp_path / "killed"
    staging = tmp_path / ".killed.training"
    code, err = _kill_when([*CLI, *args, "--out", str(killed)], lambda: bool(_status_done(staging)))
    assert code == 130, err
    assert not killed.exists()  # the model folder appears whole or not at all
    status = json.loads((staging / "status.json").read_text())
    assert status["state"] == "interrupted" and "member 0" in status["done"]
    assert "member 2" in status["todo"]

    assert main([*args, "--out", str(killed)]) == 0  # resumes from the kept members
    assert main([*args, "--out", str(tmp_path / "whole")]) == 0
    assert not staging.exists()
    for name in ("gaitnet.npz", "loss.csv"):
        assert _sha256(killed / name) == _sha256(tmp_path / "whole" / name), name


@pytest.mark.slow
def test_collect_killed_mid_run_resumes_to_the_uninterrupted_folder(tmp_path: Path) -> None:
    args = ["collect", "--robot", "biped2d", "--teacher", "kd", "--no-progress"]
    args += ["--sets", "2", "--seconds", "4", "--workers", "1"]
    killed = tmp_path / "killed"
    code, err = _kill_when([*CLI, *args, "--out", str(killed)], lambda: bool(_status_done(killed)))
    assert code == 130, err
    status = json.loads((killed / "status.json").read_text())
    assert status["state"] == "interrupted" and status["exit_code"] == 130
    assert len(status["done"]) == 1 and len(status["todo"]) == 1

    assert main([*args, "--out", str(killed)]) == 0
    assert main([*args, "--out", str(tmp_path / "whole")]) == 0
    for name in ("set_000.parquet", "set_001.parquet"):
        assert _sha256(killed / name) == _sha256(tmp_path / "whole" / name), name
    assert json.loads((killed / "status.json").read_text())["state"] == "done"


# ----------------------------------------------------------------------------- results
def test_a_duration_above_an_hour_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert _stand(tmp_path / "r", duration_s="3601") == 2
    assert "--duration: got 3601.0, expected a simulated time in [0.01, 3600] s" in (
        capsys.readouterr().err
    )


def test_the_step_in_progress_at_the_end_is_drawn_apart(
    stand_run: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from dataclasses import replace

    from gaitnet_mpc.results import plots
    from gaitnet_mpc.results.rundir import load_run

    figures = []
    monkeypatch.setattr(plots, "save_figure_atomic", lambda fig, path: figures.append(fig))
    run = load_run(stand_run)
    run = replace(run, summary={**run.summary, "step_durations_s": [0.225, 0.25, 0.3]})
    plots.plot_steps(run, stand_run / "plots" / "steps.png")

    bars = [p for p in figures[0].axes[0].patches if p.get_height() > 0]
    assert [round(b.get_height(), 3) for b in bars] == [0.225, 0.25, 0.3]
    assert [bool(b.get_hatch()) for b in bars] == [False, False, True]  # the last: unfinished
    legend = figures[0].axes[0].get_legend()
    assert "unfinished" in legend.get_texts()[0].get_text()


def test_an_import_error_caused_by_an_interrupt_stops_as_an_interrupt() -> None:
    """A Ctrl-C during a compiled extension's initialisation reaches Python as an
    ImportError caused by the KeyboardInterrupt: it must stop, not read as 'not
    installed' (seen with ``import piqp`` under load)."""
    from gaitnet_mpc.errors import reraise_interrupt

    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as ki:
            raise ImportError("initialization failed") from ki
    except ImportError as exc:
        with pytest.raises(KeyboardInterrupt):
            reraise_interrupt(exc)
    reraise_interrupt(ImportError("No module named 'piqp'"))  # a real absence: no raise


def test_an_interrupt_before_the_first_logged_tick_still_writes_the_run(tmp_path: Path) -> None:
    """Ctrl-C during the first controller call (a slow first solve under load): the run
    folder says interrupted after 0 s, instead of an IndexError on an empty log."""
    from gaitnet_mpc.scenario import build_episode, make_scenario, run_scenario

    scenario = make_scenario(robot="biped2d", controller="stand", duration_s=1.0)
    episode = build_episode(scenario)

    def interrupted(state: object) -> None:
        raise KeyboardInterrupt

    episode.controller.compute = interrupted  # type: ignore[method-assign]
    summary = run_scenario(scenario, tmp_path, video=None, progress=False, episode=episode)
    assert summary["interrupted"] and summary["outcome"] == "interrupted"
    assert summary["duration_s"] == 0.0
    assert json.loads((tmp_path / "summary.json").read_text())["interrupted"] is True
