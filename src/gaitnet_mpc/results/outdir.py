"""Output folders of the commands: claimed by one process at a time, checked before any
work starts, and a status file that says what a long job has done.

* :func:`folder_lock` holds an ``flock`` on a lock file in the folder for a block. A
  second process that wants the same folder gets a :class:`ConfigError` at once, naming
  the holder. An ``flock`` dies with its process, so a killed command leaves no stale lock;
  the lock file is removed when the block ends.
* :func:`check_output_path` is what every command calls on its output path (``--out``)
  before any work: a folder path, not a file, that can be made and written
  (:func:`check_writable`: a probe is made and removed where the results will go), so
  that a read-only location is a named error (exit 2) and not a crash after the work.
* :func:`claim_output_folder` is what ``run`` and ``compare`` call on ``--out`` before they
  start: it checks the path, creates the folder, takes its lock and checks that it is new
  or empty (or, with ``overwrite``, holds only the command's earlier results, which are
  removed).
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
    """``path`` as a folder path that can be created and written: not empty, not ``.``,
    not a file, no file among its parents, and writable (:func:`check_writable`). Nothing
    is left behind (the probe of :func:`check_writable` is removed at once)."""
    if str(path).strip() in ("", "."):  # checked on the string: Path("") is "."
        raise ConfigError(option, str(path), "a folder path for the results (not empty, not '.')")
    path = Path(path)
    try:
        if path.exists() and not path.is_dir():
            raise ConfigError(option, str(path), "a folder (this path is a file)")
        if path.is_symlink() and not path.exists():
            raise ConfigError(option, str(path), "a folder (this path is a broken link)")
        for parent in path.parents:
            if parent.exists() and not parent.is_dir():
                raise ConfigError(option, str(path), f"a folder path ({parent} is a file)")
    except OSError as exc:  # a parent that may not be searched (EACCES), a name too long
        raise ConfigError(option, str(path), f"a folder path that can be reached ({exc})") from None
    check_writable(path, option)
    return path


#: The name prefix of the probe :func:`check_writable` makes and removes.
PROBE_PREFIX = ".gaitnet-mpc-write-test-"


def unwritable_reason(folder: str | Path) -> str | None:
    """None if the folder ``folder`` can be made (where missing) and written; else why not.

    The check is a probe, as the command will write: a file made and removed in
    ``folder`` when it exists, else a folder made and removed in its nearest existing
    parent (where ``folder`` would be made). A probe sees what a permission test
    (``os.access``) misses: a read-only file system, ACLs, a root without the capability
    to override permissions.
    """
    folder = Path(folder)
    where = folder
    try:
        while not where.exists() and where != where.parent:
            where = where.parent
        if where == folder:
            fd, probe = tempfile.mkstemp(prefix=PROBE_PREFIX, dir=where)
            os.close(fd)
            os.unlink(probe)
        else:
            os.rmdir(tempfile.mkdtemp(prefix=PROBE_PREFIX, dir=where))
    except OSError as exc:
        verb = "write in" if where == folder else "create a folder in"
        return f"cannot {verb} {where}: {exc.strerror or exc}"
    return None


def check_writable(folder: str | Path, option: str, shown: str | Path | None = None) -> None:
    """Raise a :class:`ConfigError` naming ``option`` and ``shown`` (default: ``folder``)
    unless the folder ``folder`` can be made and written (:func:`unwritable_reason`)."""
    reason = unwritable_reason(folder)
    if reason is not None:
        got = str(folder if shown is None else shown)
        raise ConfigError(option, got, f"a writable folder ({reason})")


def check_output_file(path: str | Path, option: str, overwrite: bool = False) -> Path:
    """``path`` as a report file that can be written: not a folder, in a folder that can
    be made and written, new unless ``overwrite``. Nothing is left behind."""
    file = Path(path)
    if str(path).strip() in ("", ".") or file.is_dir():
        raise ConfigError(option, str(path), "a file path for the report (not a folder)")
    if file.parent != Path("."):
        check_output_path(file.parent, option)  # writable too
    else:
        check_writable(file.parent, option, shown=path)
    if file.exists() and not overwrite:
        raise ConfigError(option, str(path), "a new file; pass --overwrite to replace it")
    return file


@contextlib.contextmanager
def claim_output_file(
    path: str | Path, *, option: str, overwrite: bool = False, what: str = "command"
) -> Iterator[Path]:
    """A report file to write at the end of a long job, checked before it starts
    (:func:`check_output_file`); locked for the block (a lock file ``.<name>.lock``
    beside it)."""
    file = check_output_file(path, option, overwrite)
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        expected = f"a file in a writable folder ({exc.strerror})"
        raise ConfigError(option, str(path), expected) from None
    with folder_lock(file.parent, option=option, name=f".{file.name}.lock", what=what):
        yield file


@contextlib.contextmanager
def claim_output_folder(
    path: str | Path | None,
    *,
    option: str,
    default_prefix: str,
    artifacts: Sequence[str],
    overwrite: bool = False,
    overwrite_hint: str = "--overwrite",
) -> Iterator[Path]:
    """The output folder, locked for the block, new or emptied of earlier results.

    ``path`` None: a new folder :func:`new_folder_name`. Otherwise the folder must be new,
    empty, or, with ``overwrite``, hold only earlier ``artifacts`` (and temporary files of
    interrupted atomic writes), which are removed, so it ends up holding only the new
    results. ``overwrite_hint`` is how the caller's user asks for ``overwrite`` (a flag,
    or ``overwrite=True`` in Python), for the error message.

    Raises:
        ConfigError: naming ``option``, the path and what was expected; also when another
            process holds the folder.
    """
    folder = check_output_path(new_folder_name(default_prefix) if path is None else path, option)
    try:  # checked writable above; this is for a folder removed or changed since
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(option, str(folder), f"a writable folder ({exc.strerror})") from None
    with folder_lock(folder, option=option):
        _empty_or_overwrite(folder, option, tuple(artifacts), overwrite, overwrite_hint)
        yield folder


def _empty_or_overwrite(
    folder: Path, option: str, artifacts: tuple[str, ...], overwrite: bool, hint: str
) -> None:
    names = sorted(p.name for p in folder.iterdir() if p.name != LOCK)
    if not names:
        return
    if not overwrite:
        raise ConfigError(
            option,
            str(folder),
            f"a new or empty folder (it holds {', '.join(names[:4])}"
            f"{', ...' if len(names) > 4 else ''}); pass {hint} to replace the results in it",
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
