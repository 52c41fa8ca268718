"""Read a data-set folder (``gaitnet-mpc collect``) into arrays, and split it by set.

Rows of one set are neighbouring steps of one walk: splitting by row would let a step's
neighbours leak between training and test. Whole sets are held out instead.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitnet_mpc.dataset.check import check_dataset
from gaitnet_mpc.dataset.protocol import STAGES_PER_STEP
from gaitnet_mpc.dataset.schema import FEATURE_NAMES, LABEL
from gaitnet_mpc.dataset.store import MANIFEST, read_manifest
from gaitnet_mpc.errors import ConfigError


@dataclass(frozen=True)
class GaitData:
    """All rows of a data set.

    Attributes:
        x: (n, 16) features in :data:`~gaitnet_mpc.dataset.schema.FEATURE_NAMES` order.
        y: (n,) label, the step's MPC dt [s].
        set_id: (n,) set of each row.
        pushed: (n,) a push acted during the step.
        dt_range_s: (min, max) dt the protocol could draw [s].
        manifest_sha256: sha256 of the folder's ``manifest.json`` (ties weights to data).
        robot, teacher: from the manifest.
    """

    x: np.ndarray
    y: np.ndarray
    set_id: np.ndarray
    pushed: np.ndarray
    dt_range_s: tuple[float, float]
    manifest_sha256: str
    robot: str
    teacher: str

    def subset(self, mask: np.ndarray) -> GaitData:
        return GaitData(
            self.x[mask],
            self.y[mask],
            self.set_id[mask],
            self.pushed[mask],
            self.dt_range_s,
            self.manifest_sha256,
            self.robot,
            self.teacher,
        )


def load_dataset(folder: Path) -> GaitData:
    """Check ``folder`` (:func:`~gaitnet_mpc.dataset.check.check_dataset`) and load it."""
    import pyarrow.parquet as pq

    folder = Path(folder)
    check_dataset(folder)
    manifest = read_manifest(folder)
    assert manifest is not None  # checked above
    tables = [pq.read_table(folder / e["file"]) for e in manifest["sets"]]
    if not tables or sum(t.num_rows for t in tables) == 0:
        raise ConfigError("--data", str(folder), "a data set with rows")
    cols = {
        name: np.concatenate([t.column(name).to_numpy() for t in tables])
        for name in (*FEATURE_NAMES, LABEL.name, "set_id", "pushed")
    }
    lo, hi = manifest["protocol"]["duration_range_s"]
    return GaitData(
        x=np.column_stack([cols[n] for n in FEATURE_NAMES]).astype(float),
        y=cols[LABEL.name].astype(float),
        set_id=cols["set_id"].astype(int),
        pushed=cols["pushed"].astype(bool),
        dt_range_s=(lo / STAGES_PER_STEP, hi / STAGES_PER_STEP),
        manifest_sha256=hashlib.sha256((folder / MANIFEST).read_bytes()).hexdigest(),
        robot=str(manifest["protocol"]["robot"]),
        teacher=str(manifest["protocol"]["teacher"]),
    )


@dataclass(frozen=True)
class SetSplit:
    """Set ids of the training, validation and test parts."""

    train: tuple[int, ...]
    val: tuple[int, ...]
    test: tuple[int, ...]


def split_by_set(
    set_ids: np.ndarray, seed: int = 0, val_sets: int = 2, test_sets: int = 3
) -> SetSplit:
    """Hold out whole sets: ``test_sets`` for the test, ``val_sets`` for early stopping."""
    sets = np.unique(set_ids)
    if len(sets) < val_sets + test_sets + 1:
        raise ConfigError(
            "data sets", len(sets), f"at least {val_sets + test_sets + 1} sets to split by set"
        )
    order = np.random.default_rng(seed).permutation(sets)
    test = tuple(sorted(int(s) for s in order[:test_sets]))
    val = tuple(sorted(int(s) for s in order[test_sets : test_sets + val_sets]))
    train = tuple(sorted(int(s) for s in order[test_sets + val_sets :]))
    return SetSplit(train, val, test)
