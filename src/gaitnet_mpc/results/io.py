"""Atomic file writes (results appear complete or not at all) and durable appends (a log
line is on disk before the next piece of work starts)."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any


def write_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and an atomic rename."""
    write_bytes_atomic(path, text.encode())


def write_bytes_atomic(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path``: a temporary file in the same folder (``.NAME.*.part``),
    flushed to disk, then renamed over ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_json_atomic(path: str | Path, obj: Any) -> None:
    write_atomic(path, json.dumps(obj, indent=2, allow_nan=False) + "\n")


def append_durable(path: str | Path, text: str) -> None:
    """Append ``text`` to ``path`` (created with its folder if missing), flushed to disk."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())


def append_json_line(path: str | Path, item: Any) -> None:
    """Append ``item`` as one JSON line (:func:`append_durable`); a reader of the file
    skips a last line cut by a kill."""
    append_durable(path, json.dumps(item, allow_nan=False) + "\n")


def append_failure(
    path: str | Path, name: str, label: str, item: Any, error: BaseException, died: bool
) -> None:
    """Append one failed item of a pool to an ``errors.log``: its name, the item as JSON
    after ``label`` (``"spec"``, ``"case"``) and the traceback of ``error`` (the worker's,
    where it raised; ``died``: the worker process died instead)."""
    import time
    import traceback

    what = "its worker died" if died else "its worker raised"
    text = "".join(traceback.format_exception(error))
    stamp = time.strftime("%Y-%m-%dT%H:%M:%S")
    append_durable(path, f"=== {stamp} {name}: {what}\n{label}: {json.dumps(item)}\n{text}\n")
