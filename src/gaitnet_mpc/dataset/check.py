"""``gaitnet-mpc dataset check DIR``: is a data-set folder what its manifest says?

Checked in this order, stopping at the first problem (a :class:`DatasetError` naming the
file and the field): the manifest's schema version and columns; per set file, that it
exists, its sha256 and row count, its columns and types, and per column that no value is
NaN or infinite and that values lie in the column's range; the label ``dt_s`` must lie in
the protocol's drawn range (duration range over ``h'`` stages).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.dataset.protocol import STAGES_PER_STEP
from gaitnet_mpc.dataset.schema import COLUMNS, SCHEMA_VERSION, arrow_schema, describe
from gaitnet_mpc.dataset.store import MANIFEST, DatasetError, read_manifest, sha256_file

_DT_TOLERANCE_S = 1e-6


def check_dataset(folder: Path) -> dict[str, int]:
    """Validate ``folder``; return ``{"files": ..., "rows": ...}``.

    Raises:
        DatasetError: the first problem found, naming file and field.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DatasetError(str(folder), "folder", str(folder), "an existing data-set folder")
    manifest = read_manifest(folder)
    if manifest is None:
        raise DatasetError(MANIFEST, "file", None, f"a {MANIFEST} in {folder}")
    if manifest.get("schema_version") != SCHEMA_VERSION:
        raise DatasetError(
            MANIFEST, "schema_version", manifest.get("schema_version"), str(SCHEMA_VERSION)
        )
    if manifest.get("columns") != describe():
        raise DatasetError(MANIFEST, "columns", "(differs)", "the columns of this schema version")
    lo, hi = manifest["protocol"]["duration_range_s"]
    dt_range = (lo / STAGES_PER_STEP - _DT_TOLERANCE_S, hi / STAGES_PER_STEP + _DT_TOLERANCE_S)
    rows = 0
    for entry in manifest.get("sets", []):
        rows += _check_file(folder, entry, dt_range)
    return {"files": len(manifest.get("sets", [])), "rows": rows}


def _check_file(folder: Path, entry: dict[str, Any], dt_range: tuple[float, float]) -> int:
    import pyarrow.parquet as pq

    name = str(entry.get("file"))
    path = folder / name
    if not path.is_file():
        raise DatasetError(name, "file", "missing", "the file the manifest lists")
    digest = sha256_file(path)
    if digest != entry.get("sha256"):
        raise DatasetError(name, "sha256", digest, f"{entry.get('sha256')} (the manifest's)")
    try:
        table = pq.read_table(path)
    except Exception as exc:
        raise DatasetError(name, "file", type(exc).__name__, "a readable Parquet file") from exc
    if table.num_rows != entry.get("rows"):
        raise DatasetError(name, "rows", table.num_rows, f"{entry.get('rows')} (the manifest's)")
    expected = arrow_schema()
    for field in expected:
        if field.name not in table.column_names:
            raise DatasetError(name, field.name, "missing", "a column of the schema")
        got = table.schema.field(field.name).type
        if got != field.type:
            raise DatasetError(name, field.name, str(got), f"type {field.type}")
    extra = sorted(set(table.column_names) - {f.name for f in expected})
    if extra:
        raise DatasetError(name, extra[0], "extra column", "only the schema's columns")
    for column in COLUMNS:
        if column.dtype != "float64":
            continue
        values = table.column(column.name).to_numpy()
        bad = ~np.isfinite(values)
        if np.any(bad):
            raise DatasetError(
                name, column.name, float(values[bad][0]), f"finite values (row {np.argmax(bad)})"
            )
        low, high = dt_range if column.name == "dt_s" else (column.range or (-np.inf, np.inf))
        out = (values < low) | (values > high)
        if np.any(out):
            raise DatasetError(
                name,
                column.name,
                float(values[out][0]),
                f"values in [{low:g}, {high:g}] {column.unit} (row {np.argmax(out)})",
            )
    feet = set(table.column("stance_foot").to_pylist())
    if not feet <= {"left", "right"}:
        raise DatasetError(name, "stance_foot", sorted(feet), "'left' or 'right'")
    return int(table.num_rows)
