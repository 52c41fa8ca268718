"""The data-set folder: one Parquet file per set, ``manifest.json``, and a lock.

::

    DIR/
      manifest.json        schema, protocol, teacher settings, versions, per-file rows/sha256
      set_000.parquet      the rows of set 0; its own metadata repeats the protocol's
      ...                  fingerprint, the set's spec and what happened (falls, drops)
      .collect.lock        held (flock) by the one ``collect`` writing the folder

Each set file carries everything needed to list it in the manifest again, so a
``collect`` killed between writing a set and updating the manifest loses nothing: the
next run finds the file, checks it and takes it over. A set file is written whole
(temporary file, fsync, rename) by the process that owns the lock, and never changes
afterwards; a set killed mid-way is redone from its start (no checkpoints within a set).
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from gaitnet_mpc.dataset.protocol import SetSpec
from gaitnet_mpc.dataset.schema import SCHEMA_VERSION, arrow_schema
from gaitnet_mpc.errors import GaitNetMPCError
from gaitnet_mpc.results import outdir

MANIFEST = "manifest.json"
LOCK = ".collect.lock"
_META_KEY = b"gaitnet_mpc.set"


class DatasetError(GaitNetMPCError):
    """A data-set folder or file is not what its manifest and schema say.

    The message reads ``<file>: <field>: got <value>, expected <what>``.
    """

    def __init__(self, file: str, field: str, value: object, expected: str) -> None:
        self.file, self.field, self.value, self.expected = file, field, value, expected
        super().__init__(f"{file}: {field}: got {value!r}, expected {expected}")

    def __reduce__(self) -> tuple[type, tuple[str, str, object, str]]:
        return (type(self), (self.file, self.field, self.value, self.expected))


def set_file(spec: SetSpec) -> str:
    return f"{spec.name}.parquet"


def sha256_file(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def encode_set(spec: SetSpec, rows: list[dict[str, object]], stats: dict[str, object]) -> bytes:
    """The Parquet bytes of one set: its rows, and in the file's metadata the schema
    version, the protocol's fingerprint, the set's spec and ``stats``. Deterministic:
    the same rows give the same bytes (with the same pyarrow)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema = arrow_schema()
    meta = {
        "schema_version": SCHEMA_VERSION,
        "fingerprint": spec.protocol.fingerprint(),
        "spec": spec.to_dict(),
        "stats": stats,
    }
    schema = schema.with_metadata({**schema.metadata, _META_KEY: json.dumps(meta).encode()})
    table = pa.Table.from_pylist(rows, schema=schema)
    buf = io.BytesIO()
    pq.write_table(table, buf, compression="zstd")
    return buf.getvalue()


def read_set_meta(path: Path) -> dict[str, Any]:
    """The metadata :func:`encode_set` stored in a set file."""
    import pyarrow.parquet as pq

    try:
        schema = pq.read_schema(path)
    except Exception as exc:
        raise DatasetError(
            path.name, "file", type(exc).__name__, "a readable Parquet file"
        ) from exc
    raw = (schema.metadata or {}).get(_META_KEY)
    if raw is None:
        raise DatasetError(path.name, "metadata", None, f"a '{_META_KEY.decode()}' entry")
    return dict(json.loads(raw))


def read_manifest(folder: Path) -> dict[str, Any] | None:
    path = folder / MANIFEST
    if not path.exists():
        return None
    try:
        return dict(json.loads(path.read_text()))
    except (OSError, ValueError) as exc:
        raise DatasetError(MANIFEST, "file", str(exc), "readable JSON") from exc


@contextlib.contextmanager
def folder_lock(folder: Path) -> Iterator[None]:
    """Hold the folder's lock for the block; a second ``collect`` gets a clear error at
    once (:func:`gaitnet_mpc.results.outdir.folder_lock`, on :data:`LOCK`)."""
    with outdir.folder_lock(folder, name=LOCK, what="collect"):
        yield


def remove_partial_files(folder: Path) -> list[str]:
    """Delete temporary files a killed writer left (``.NAME.*.part``); their names."""
    removed = []
    for path in sorted(folder.glob(".*.part")):
        path.unlink(missing_ok=True)
        removed.append(path.name)
    return removed
