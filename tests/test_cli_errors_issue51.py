"""Everyday use (issue 51): bad input is exit 2 with a message naming the field, the value
and what was expected, never a traceback; and before any work.

* An output location that cannot be written (a folder in a read-only folder, a path
  under a file) is refused by every command before its work starts.

Root ignores file permissions; where the tests run as root, the read-only cases drop the
capability that lets root write anyway (``CAP_DAC_OVERRIDE``, from this thread's
effective set, restored after the test) and are skipped where that is not possible. The
path-under-a-file cases hold for root too and always run.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

from gaitnet_mpc.cli import main

ROOT = Path(__file__).resolve().parents[1]
DATA = str(ROOT / "data" / "gaitnet-kd-biped2d")

#: Every command with an output location, as the argument list before ``--out``; RUN and
#: RUN2 stand for two run folders; bench's ``--out`` is a report file in the location.
COMMANDS: dict[str, list[str]] = {
    "run": ["run", "--controller", "stand", "--duration", "0.05", "--no-video", "--no-progress"],
    "compare": ["compare", "RUN", "RUN2"],
    "sweep": ["sweep", "push", "--quick", "--workers", "1", "--no-progress"],
    "collect": ["collect", "--sets", "1", "--seconds", "1", "--workers", "1", "--no-progress"],
    "bench": ["bench", "--case", "a=kd", "--seconds", "0.05", "--rounds", "1", "--no-profile"],
    "train": ["train", "--data", DATA, "--members", "1", "--epochs", "1", "--no-progress"],
    "reproduce table1": ["reproduce", "table1", "--data", DATA],
    "reproduce table2": ["reproduce", "table2", "--problems", "1"],
    "reproduce fig6": ["reproduce", "fig6", "--quick", "--workers", "1", "--no-progress"],
    "reproduce fig7": ["reproduce", "fig7", "--quick", "--no-video"],
    "reproduce all": ["reproduce", "all", "--quick"],
}


def _stand(out: Path, *extra: str) -> int:
    argv = ["run", "--controller", "stand", "--duration", "0.05", "--no-progress"]
    return main([*argv, "--no-plots", "--no-video", "--out", str(out), *extra])


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Two short run folders (RUN, RUN2: the same run in two folders)."""
    folder = tmp_path_factory.mktemp("issue51")
    assert _stand(folder / "RUN") == 0
    shutil.copytree(folder / "RUN", folder / "RUN2")
    return {"RUN": folder / "RUN", "RUN2": folder / "RUN2"}


def _argv(name: str, runs: dict[str, Path], location: Path) -> list[str]:
    """``name``'s argument list with ``--out`` in ``location``."""
    argv = [str(runs[a]) if a in runs else a for a in COMMANDS[name]]
    return [*argv, "--out", str(location / "perf.md" if name == "bench" else location)]


@pytest.fixture
def no_training(monkeypatch: pytest.MonkeyPatch) -> None:
    """``train`` fails the test (exit 4) if it starts training."""
    from gaitnet_mpc.gaitnet import training_run

    def fail(*args: object, **kwargs: object) -> None:
        raise AssertionError("training started")

    monkeypatch.setattr(training_run, "load_dataset", fail)
    monkeypatch.setattr(training_run, "fit", fail)


@pytest.fixture
def no_bench_cases(monkeypatch: pytest.MonkeyPatch) -> None:
    """``bench`` fails the test (exit 4) if it starts building its cases (slow)."""
    from gaitnet_mpc.experiments import bench

    def fail(*args: object, **kwargs: object) -> None:
        raise AssertionError("bench built a case")

    monkeypatch.setattr(bench, "build_case", fail)


# ----------------------------------------------------------------------------- read-only
class _CapHeader(ctypes.Structure):
    _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]


class _CapData(ctypes.Structure):
    _fields_ = [
        ("effective", ctypes.c_uint32),
        ("permitted", ctypes.c_uint32),
        ("inheritable", ctypes.c_uint32),
    ]


_CAPABILITY_VERSION_3 = 0x20080522
_CAP_DAC_OVERRIDE = 1


@contextlib.contextmanager
def _permissions_enforced() -> Iterator[bool]:
    """Yield whether file permissions bind this thread: always for a user; for root, by
    dropping ``CAP_DAC_OVERRIDE`` from the thread's effective capabilities for the block
    (kept in the permitted set, so it is restored after)."""
    if os.geteuid() != 0:
        yield True
        return
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        header = _CapHeader(_CAPABILITY_VERSION_3, 0)
        data = (_CapData * 2)()
        if libc.capget(ctypes.byref(header), data) != 0:
            raise OSError(ctypes.get_errno(), "capget")
    except (OSError, AttributeError):
        yield False
        return
    saved = data[0].effective
    data[0].effective = saved & ~(1 << _CAP_DAC_OVERRIDE)
    if libc.capset(ctypes.byref(header), data) != 0:
        yield False
        return
    try:
        yield True
    finally:
        data[0].effective = saved
        libc.capset(ctypes.byref(header), data)


@contextlib.contextmanager
def _read_only(folder: Path) -> Iterator[Path]:
    """``folder`` made read-only (mode 555) for the block, for this test even as root;
    the test is skipped where that cannot be done."""
    folder.chmod(0o555)
    try:
        with _permissions_enforced() as enforced:
            probe = folder / "probe"
            try:
                probe.touch()
            except PermissionError:
                pass
            else:
                probe.unlink()
                enforced = False
            if not enforced:
                pytest.skip("cannot make a folder read-only for this user (root)")
            yield folder
    finally:
        folder.chmod(0o755)


@pytest.fixture
def read_only(tmp_path: Path) -> Iterator[Path]:
    """An empty folder that this test cannot write into."""
    (tmp_path / "read-only").mkdir()
    with _read_only(tmp_path / "read-only") as folder:
        yield folder


def _refused(err: str, location: Path) -> None:
    assert "Traceback" not in err, err
    assert "--out" in err and str(location) in err and "a writable folder" in err, err


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_an_out_in_a_read_only_folder_is_refused_before_any_work(
    name: str,
    runs: dict[str, Path],
    read_only: Path,
    no_training: None,
    no_bench_cases: None,
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(_argv(name, runs, read_only / "out")) == 2  # before any work
    _refused(capsys.readouterr().err, read_only / "out")
    assert not any(read_only.iterdir())


@pytest.mark.parametrize("name", ["run", "collect", "train", "reproduce fig7"])
def test_an_existing_read_only_out_is_refused_before_any_work(
    name: str,
    runs: dict[str, Path],
    read_only: Path,
    no_training: None,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """An empty, read-only ``--out`` (train trained every member, then failed to rename
    the model into place)."""
    argv = [str(runs[a]) if a in runs else a for a in COMMANDS[name]]
    assert main([*argv, "--out", str(read_only)]) == 2
    _refused(capsys.readouterr().err, read_only)
    assert not list(read_only.parent.glob(".*.training"))  # train: no staging folder


def test_train_into_a_read_only_parent_is_refused_before_training(
    tmp_path: Path, no_training: None, capsys: pytest.CaptureFixture[str]
) -> None:
    """A writable ``--out`` in a read-only folder: the training works beside ``--out`` and
    renames the model into place, so the parent is checked too."""
    parent = tmp_path / "parent"
    (parent / "model").mkdir(parents=True)
    with _read_only(parent):
        assert main([*COMMANDS["train"], "--out", str(parent / "model")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "a writable folder" in err
    assert f"--out: got '{parent / 'model'}'" in err and f"cannot write in {parent}" in err


def test_plot_refuses_a_read_only_run_folder(
    runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "run"
    shutil.copytree(runs["RUN"], run)
    with _read_only(run):
        assert main(["plot", str(run)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and f"RUN_DIR: got '{run}'" in err
    assert "a writable folder" in err
    assert not (run / "plots").exists()


def test_the_probe_leaves_nothing_behind(tmp_path: Path) -> None:
    """:func:`check_output_path` writes nothing: a missing folder stays missing, an
    existing one keeps its files."""
    from gaitnet_mpc.results.outdir import PROBE_PREFIX, check_output_path, unwritable_reason

    assert unwritable_reason(tmp_path / "a" / "b") is None
    check_output_path(tmp_path / "a" / "b", "--out")
    (tmp_path / "kept.txt").write_text("x")
    check_output_path(tmp_path, "--out")
    assert [p.name for p in tmp_path.iterdir()] == ["kept.txt"]
    assert not any(p.name.startswith(PROBE_PREFIX) for p in tmp_path.rglob("*"))


# ----------------------------------------------------------------------------- under a file
@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_an_out_under_a_file_is_refused_by_every_command(
    name: str,
    runs: dict[str, Path],
    tmp_path: Path,
    no_training: None,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A location root cannot write either: its parent is a file."""
    file = tmp_path / "file"
    file.write_text("x")
    assert main(_argv(name, runs, file / "out")) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "--out" in err and f"({file} is a file)" in err
    assert file.read_text() == "x"


# ----------------------------------------------------------------------------- messages
def _weights_run(tmp_path: Path, weights: Path | str) -> int:
    argv = ["--robot", "biped2d", "--controller", "gaitnet", "--gaitnet-weights", str(weights)]
    return _stand(tmp_path / "gaitnet-run", *argv)


def test_gaitnet_weights_accept_the_model_folder_train_writes(tmp_path: Path) -> None:
    """``--gaitnet-weights DIR`` with DIR the ``--out`` of ``train`` (its gaitnet.npz)."""
    from gaitnet_mpc.control.dt_policies import weights_path
    from gaitnet_mpc.gaitnet import WEIGHTS_DIR, WEIGHTS_FILE
    from gaitnet_mpc.gaitnet.training_run import MODEL_FILES
    from gaitnet_mpc.robots import load_robot

    assert WEIGHTS_FILE in MODEL_FILES  # the layout train writes
    model = tmp_path / "model"
    model.mkdir()
    shutil.copy(WEIGHTS_DIR / "biped2d.npz", model / WEIGHTS_FILE)
    (model / "report.json").write_text("{}")
    assert weights_path(load_robot("biped2d"), str(model)) == model / WEIGHTS_FILE
    assert _weights_run(tmp_path, model) == 0


def test_a_folder_without_weights_names_what_is_missing(
    runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    empty = tmp_path / "empty"
    empty.mkdir()
    for folder, held in ((empty, "it is empty"), (runs["RUN"], "it holds course.json")):
        assert _weights_run(tmp_path, folder) == 2
        err = capsys.readouterr().err
        assert f"--gaitnet-weights: got '{folder}'" in err and "with gaitnet.npz in it" in err
        assert held in err and "Traceback" not in err


def test_a_text_file_as_weights_is_not_a_weights_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = tmp_path / "weights.npz"
    text.write_text("these are not weights\n")
    assert _weights_run(tmp_path, text) == 2
    err = capsys.readouterr().err
    assert f"--gaitnet-weights: got '{text}', expected a Gait-Net weights .npz" in err
    assert "(this is a text file)" in err and "allow_pickle" not in err


@pytest.mark.parametrize("command", ["plot", "compare"])
def test_a_truncated_or_malformed_log_is_named(
    command: str, runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "run"
    shutil.copytree(runs["RUN"], run)
    log = run / "log.csv"
    lines = log.read_text().splitlines()
    n = len(lines)
    not_a_number = "x" + lines[2][lines[2].index(",") :]  # t_s of line 3
    cases = (
        ([*lines[:-1], lines[-1][:12]], f"on its last line {n}", "the file is truncated"),
        ([*lines[:3], lines[3] + ",1", *lines[4:]], "fields on line 4", "the file is malformed"),
        ([*lines[:2], not_a_number, *lines[3:]], "line 3, t_s: got 'x'", "expected a number"),
    )
    for text, where, what in cases:
        log.write_text("\n".join(text) + "\n")
        argv = [command, str(run)] + (
            [str(runs["RUN"]), "--out", str(tmp_path / "c")] * (command == "compare")
        )
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert f"{log}" in err and where in err and what in err, err
        assert "usecols" not in err and "Traceback" not in err


def test_a_course_or_scenario_file_with_a_byte_order_mark_is_read(
    runs: dict[str, Path], tmp_path: Path
) -> None:
    """UTF-8 with a byte-order mark (some Windows editors write one) is UTF-8."""
    course = tmp_path / "course.json"
    course.write_bytes(b"\xef\xbb\xbf" + (runs["RUN"] / "course.json").read_bytes())
    assert _stand(tmp_path / "a", "--course", str(course)) == 0
    scenario = tmp_path / "scenario.toml"
    scenario.write_bytes(b"\xef\xbb\xbf" + (runs["RUN"] / "scenario.toml").read_bytes())
    argv = ["run", "--scenario", str(scenario), "--no-video", "--no-plots", "--no-progress"]
    assert main([*argv, "--out", str(tmp_path / "b")]) == 0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--course", "gap", "--seed", "-1"], "--seed: got -1, expected an integer >= 0"),
        (["--push", "t=-1,fx=10,dur=0.1"], "--push t: got -1.0, expected a finite time >= 0 s"),
        (["--push", "t=1,dur=9"], "--push dur: got 9.0"),
        (["--push", "t=1,fx=800,fy=800,dur=0.1"], "--push fx,fy,fz: got (800.0, 800.0, 0.0)"),
        (["--cart-load-kg", "-1"], "--cart-load-kg: got -1.0"),
    ],
)
def test_errors_name_the_option_that_was_given(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _stand(tmp_path / "r", *args) == 2
    err = capsys.readouterr().err
    assert message in err and "course_seed" not in err and "push." not in err, err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["collect", "--seed", "-1"], "--seed: got -1, expected an integer >= 0"),
        (["collect", "--max-restarts", "-1"], "--max-restarts: got -1"),
        (["train", "--data", DATA, "--seed", "-1"], "--seed: got -1, expected an integer in"),
        (["train", "--data", DATA, "--seed", str(10**23)], f"--seed: got {10**23}"),
    ],
)
def test_bad_seeds_of_collect_and_train_are_named_before_any_work(
    argv: list[str],
    message: str,
    tmp_path: Path,
    no_training: None,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Once NumPy's or PyTorch's ValueError after the folder was made (exit 4)."""
    assert main([*argv, "--no-progress", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err, err
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        ({"command": {"vx_mps": float("nan")}}, "command.vx_mps: got nan, expected a finite"),
        ({"command": {"yaw_rate_radps": 9.0}}, "command.yaw_rate_radps: got 9.0"),
        (
            {"pushes": [{"t_s": -1.0, "force_world_n": [1.0, 0.0, 0.0], "duration_s": 0.1}]},
            "pushes[0].t_s: got -1.0",
        ),
        (
            {"pushes": [{"t_s": 0.1, "force_world_n": [900.0, 0.0, 0.0], "duration_s": 1.0}]},
            "pushes[0].force_world_n x duration_s: got '900 N s",
        ),
    ],
)
def test_a_scenario_file_error_names_the_files_key(
    edit: dict[str, object],
    message: str,
    runs: dict[str, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    import tomllib

    import tomli_w

    table = tomllib.loads((runs["RUN"] / "scenario.toml").read_text())
    for key, value in edit.items():
        table[key] = {**table[key], **value} if isinstance(value, dict) else value
    scenario = tmp_path / "scenario.toml"
    scenario.write_text(tomli_w.dumps(table))
    argv = ["run", "--scenario", str(scenario), "--no-video", "--out", str(tmp_path / "r")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{scenario}: {message}" in err, err
    assert "--vx" not in err and "--yaw-rate" not in err and "--push" not in err


def test_an_unknown_option_is_the_subcommands_error(capsys: pytest.CaptureFixture[str]) -> None:
    for argv, usage, error in (
        (["run", "--bogus"], "usage: gaitnet-mpc run ", "gaitnet-mpc run: error: "),
        (["compare", "a", "--bogus", "1"], "usage: gaitnet-mpc compare ", "compare: error: "),
        (["--bogus", "run"], "usage: gaitnet-mpc [-h]", "gaitnet-mpc: error: "),
    ):
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == 2
        err = capsys.readouterr().err
        assert usage in err and f"{error}unrecognized arguments: --bogus" in err, err


def test_compare_refuses_a_run_compared_with_itself(
    runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = runs["RUN"]
    link = tmp_path / "link"
    link.symlink_to(run)
    for pair, why in (((run, run), "it is given twice"), ((run, link), f"same folder as {run}")):
        argv = ["compare", *(str(p) for p in pair), "--out", str(tmp_path / "c")]
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "RUN_DIR: got" in err and "a different run folder each time" in err
        assert why in err
    assert not (tmp_path / "c").exists()
    assert main(["compare", str(run), str(runs["RUN2"]), "--out", str(tmp_path / "c")]) == 0


# ----------------------------------------------------------------------------- no effect
@pytest.fixture
def fake_reproduce(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The reproductions replaced by a one-line report; yields the targets run."""
    from gaitnet_mpc.experiments import reproduce

    ran: list[str] = []

    def report(out: Path, name: str) -> Path:
        ran.append(name)
        out.mkdir(parents=True, exist_ok=True)  # fig6 makes its own folder
        (out / f"{name}.md").write_text(f"# {name}\n")
        return out / f"{name}.md"

    monkeypatch.setattr(reproduce, "figure", lambda out, name, **kw: report(out, name))
    monkeypatch.setattr(reproduce, "table2", lambda out, n, **kw: report(out, "table2"))
    monkeypatch.setattr(reproduce, "table1", lambda data, out: report(out, "table1"))
    monkeypatch.setattr(reproduce, "fig6", lambda out, **kw: report(out, "fig6"))
    return ran


def test_reproduce_warns_about_options_its_target_does_not_use(
    fake_reproduce: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["reproduce", "fig7", "--seeds", "5", "--problems", "3", "--quick", "--no-video"]
    assert main([*argv, "--out", str(tmp_path / "fig7")]) == 0
    assert fake_reproduce == ["fig7"]
    warnings = [w for w in capsys.readouterr().err.splitlines() if "warning:" in w]
    assert warnings == [
        "gaitnet-mpc: warning: --problems 3 has no effect: reproduce fig7 does not use it "
        "(it is for table2)",
        "gaitnet-mpc: warning: --seeds 5 has no effect: reproduce fig7 does not use it "
        "(it is for fig6)",
        "gaitnet-mpc: warning: --no-video has no effect with --quick (quick runs make no video)",
    ]


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["table2", "--problems", "3", "--no-joint-space"], []),
        (["table1", "--overwrite", "--workers", "2"], ["--workers 2 has no effect"]),
        (["table2", "--overwrite"], ["--overwrite has no effect: reproduce table2 resumes"]),
        (["fig6", "--quick", "--address", "x:1"], []),  # without ray: a named error later
        (["table1", "--address", "x:1"], ["--address x:1 has no effect: reproduce table1"]),
        (["fig6", "--quick", "--no-video", "--data", "d"], ["--data d", "--no-video has no"]),
        (["all", "--quick", "--first-seed", "3"], ["--first-seed 3 has no effect"]),
    ],
)
def test_reproduce_warns_only_about_unused_options(argv: list[str], expected: list[str]) -> None:
    from gaitnet_mpc.cli.main import parse_args
    from gaitnet_mpc.cli.reproduce import unused_options

    warnings = unused_options(parse_args(["reproduce", *argv]))
    assert len(warnings) == len(expected), warnings
    for text, start in zip(warnings, expected, strict=True):
        assert text.startswith(start), warnings


def test_reproduce_fills_in_the_defaults_of_options_not_given(
    fake_reproduce: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from gaitnet_mpc.cli import reproduce as cli
    from gaitnet_mpc.experiments import reproduce

    seen: dict[str, object] = {}

    def fig6(out: Path, **kwargs: object) -> Path:
        seen.update(kwargs)
        out.mkdir(parents=True)
        (out / "fig6.md").write_text("# fig6\n")
        return out / "fig6.md"

    monkeypatch.setattr(reproduce, "fig6", fig6)
    assert main(["reproduce", "fig6", "--out", str(tmp_path / "f")]) == 0
    assert "warning" not in capsys.readouterr().err
    assert seen["quick"] is False and seen["seeds"] is None and seen["first_seed"] == 0
    assert seen["workers"] == cli.DEFAULTS["workers"] and seen["backend"] == "process"
    assert seen["progress"] is True and seen["gaitnet_weights"] is None


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["sweep", "push", "--seeds", "3"], ["--seeds 3 has no effect: sweep push has no seeds"]),
        (["sweep", "terrain", "--quick", "--seeds", "3"], ["--seeds 3 has no effect with --quick"]),
        (["sweep", "protocol", "--seeds", "3"], []),
        (["bench", "--memory-case", "a"], ["--memory-case a has no effect without"]),
    ],
)
def test_sweep_and_bench_warn_about_options_without_effect(
    argv: list[str],
    expected: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The work behind each command is replaced: what is tested is what it says first."""
    from gaitnet_mpc.cli import bench
    from gaitnet_mpc.experiments import bench as bench_work
    from gaitnet_mpc.experiments import sweep

    monkeypatch.setattr(sweep, "sweep", lambda *args, **kwargs: {})
    monkeypatch.setattr(bench_work, "build_case", lambda case, spec: None)
    monkeypatch.setattr(bench, "_bench", lambda *args: 0)
    out = tmp_path / ("perf.md" if argv[0] == "bench" else "out")
    extra = ["--case", "a=kd"] if argv[0] == "bench" else []
    assert main([*argv, *extra, "--out", str(out)]) == 0
    warnings = [w for w in capsys.readouterr().err.splitlines() if "warning:" in w]
    assert len(warnings) == len(expected), warnings
    for text, start in zip(warnings, expected, strict=True):
        assert text.startswith(f"gaitnet-mpc: warning: {start}"), warnings
