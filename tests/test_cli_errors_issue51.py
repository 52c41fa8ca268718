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
import time
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
    capsys: pytest.CaptureFixture[str],
) -> None:
    t0 = time.perf_counter()
    assert main(_argv(name, runs, read_only / "out")) == 2
    assert time.perf_counter() - t0 < 10.0  # before the work (and bench's slow case build)
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
