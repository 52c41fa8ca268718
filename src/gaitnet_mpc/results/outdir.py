"""Output folders of the commands: claimed by one process at a time, checked before any
work starts, and a status file that says what a long job has done.

* :func:`folder_lock` holds an ``flock`` on a lock file in the folder for a block. A
  second process that wants the same folder gets a :class:`ConfigError` at once, naming
  the holder. An ``flock`` dies with its process, so a killed command leaves no stale lock;
  the lock file is removed when the block ends.
* :func:`claim_output_folder` is what ``run``, ``compare``, ``bench``, ``reproduce`` and
  ``train`` call on ``--out`` before they start: it validates the path, creates the
  folder, takes its lock, checks that it is new or empty (or, with ``overwrite``, holds only
  the command's earlier results, which are removed) and that it is writable.
* :func:`claim_output_file` does the same for a report file (``bench --out``).
* :func:`write_status` writes ``status.json`` atomically: the command, its state
  (``running``, ``done``, ``interrupted``, ``failed``), the exit code, and the items done
  and still to do, so that an interrupted job says where it stopped.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
import tempfile
import time
import uuid
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.results.io import write_json_atomic

#: The lock file a command holds in its output folder while it writes there.
LOCK = ".gaitnet-mpc.lock"
#: The status file of a long job (:func:`write_status`).
STATUS = "status.json"
#: The states a status file can say.
STATES = ("running", "done", "interrupted", "failed")
#: How often taking a lock is retried when its file was replaced under us.
_LOCK_ATTEMPTS = 5


@contextlib.contextmanager
def folder_lock(
    folder: str | Path, *, option: str = "--out", name: str = LOCK, what: str = "command"
) -> Iterator[Path]:
    """Hold the lock of ``folder`` (created if missing) for the block; yields the folder.

    Raises:
        ConfigError: another process holds the lock (``option``, the folder, the holder).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    for _ in range(_LOCK_ATTEMPTS):
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            holder = _read_holder(path)
            raise ConfigError(
                option, str(folder), f"a folder no other {what} is writing (locked by {holder})"
            ) from None
        try:
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)  # the holder before us removed the file we locked: lock the new one
    else:  # pragma: no cover - five replacements in a row
        raise ConfigError(option, str(folder), "a folder whose lock file stays in place")
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"pid {os.getpid()}\n".encode())
        yield folder
    finally:
        with contextlib.suppress(OSError):
            path.unlink()
        os.close(fd)


def _read_holder(path: Path) -> str:
    try:
        return path.read_text().strip() or "another process"
    except OSError:
        return "another process"


def new_folder_name(default_prefix: str) -> Path:
    """``runs/<prefix><date-time>-<6 hex digits>``: unique even within one second."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    return Path("runs") / f"{default_prefix}{stamp}-{uuid.uuid4().hex[:6]}"


def check_output_path(path: str | Path, option: str) -> Path:
    """``path`` as a folder path that could be created: not empty, not ``.``, not a file,
    no file among its parents. Nothing is created."""
    if str(path).strip() in ("", "."):  # checked on the string: Path("") is "."
        raise ConfigError(option, str(path), "a folder path for the results (not empty, not '.')")
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ConfigError(option, str(path), "a folder (this path is a file)")
    for parent in path.parents:
        if parent.exists() and not parent.is_dir():
            raise ConfigError(option, str(path), f"a folder path ({parent} is a file)")
    return path


@contextlib.contextmanager
def claim_output_file(
    path: str | Path, *, option: str, overwrite: bool = False, what: str = "command"
) -> Iterator[Path]:
    """A report file to write at the end of a long job, checked before it starts: not a
    folder, in a folder that can be made and written, new unless ``overwrite``; locked for
    the block (a lock file ``.<name>.lock`` beside it)."""
    file = Path(path)
    if str(path).strip() in ("", ".") or file.is_dir():
        raise ConfigError(option, str(path), "a file path for the report (not a folder)")
    if file.parent != Path("."):
        check_output_path(file.parent, option)
    if file.exists() and not overwrite:
        raise ConfigError(option, str(path), "a new file; pass --overwrite to replace it")
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        expected = f"a file in a folder that can be made ({exc.strerror})"
        raise ConfigError(option, str(path), expected) from None
    with folder_lock(file.parent, option=option, name=f".{file.name}.lock", what=what):
        if not os.access(file.parent, os.W_OK):
            raise ConfigError(option, str(path), "a file in a writable folder")
        yield file


@contextlib.contextmanager
def claim_output_folder(
    path: str | Path | None,
    *,
    option: str,
    default_prefix: str,
    artifacts: Sequence[str],
    overwrite: bool = False,
) -> Iterator[Path]:
    """The output folder, locked for the block, new or emptied of earlier results.

    ``path`` None: a new folder :func:`new_folder_name`. Otherwise the folder must be new,
    empty, or, with ``overwrite``, hold only earlier ``artifacts`` (and temporary files of
    interrupted atomic writes), which are removed, so it ends up holding only the new
    results.

    Raises:
        ConfigError: naming ``option``, the path and what was expected; also when another
            process holds the folder.
    """
    folder = check_output_path(new_folder_name(default_prefix) if path is None else path, option)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(
            option, str(folder), f"a folder that can be made ({exc.strerror})"
        ) from None
    with folder_lock(folder, option=option):
        _empty_or_overwrite(folder, option, tuple(artifacts), overwrite)
        try:
            probe = tempfile.NamedTemporaryFile(dir=folder, prefix=".write-test-", delete=True)
            probe.close()
        except OSError as exc:
            raise ConfigError(option, str(folder), f"a writable folder ({exc.strerror})") from None
        yield folder


def _empty_or_overwrite(
    folder: Path, option: str, artifacts: tuple[str, ...], overwrite: bool
) -> None:
    names = sorted(p.name for p in folder.iterdir() if p.name != LOCK)
    if not names:
        return
    if not overwrite:
        raise ConfigError(
            option,
            str(folder),
            f"a new or empty folder (it holds {', '.join(names[:4])}"
            f"{', ...' if len(names) > 4 else ''}); pass --overwrite to replace the results in it",
        )
    ours = [n for n in names if n in artifacts or (n.startswith(".") and n.endswith(".part"))]
    foreign = [n for n in names if n not in ours]
    if foreign:
        raise ConfigError(
            option,
            str(folder),
            "a folder holding only earlier results to overwrite (it also holds "
            f"{', '.join(foreign[:4])})",
        )
    for name in ours:  # earlier results and leftover temporary files of atomic writes
        target = folder / name
        if target.is_dir():
            shutil.rmtree(target)
        else:
            target.unlink()


def write_status(
    folder: str | Path,
    *,
    command: str,
    state: str,
    exit_code: int | None = None,
    done: Sequence[Any] = (),
    todo: Sequence[Any] = (),
    note: str = "",
) -> Path:
    """Write ``folder/status.json`` (atomically) and return its path.

    Args:
        command: the command line that runs the job (to resume it: run it again).
        state: one of :data:`STATES`.
        exit_code: the exit code the job ends with (None while running).
        done: the items finished (names or short records).
        todo: the items not finished.
        note: one sentence for a reader (what to do next).
    """
    if state not in STATES:
        raise ConfigError("state", state, f"one of {list(STATES)}")
    path = Path(folder) / STATUS
    write_json_atomic(
        path,
        {
            "command": command,
            "state": state,
            "exit_code": exit_code,
            "done": list(done),
            "todo": list(todo),
            "note": note,
            "updated": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        },
    )
    return path
