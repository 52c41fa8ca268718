"""Train Gait-Net on its data set plus the rollout oracle's DAgger rows
(``benchmarks/rollout_labels.py``), as ``gaitnet-mpc train --features full`` would.

The DAgger rows are grouped into ``--groups`` sets by episode seed, so that the split by
set (validation for early stopping, test for the report) holds out whole episodes.

    .venv/bin/python benchmarks/train_dagger.py --data data/gaitnet-kd-humanoid3d \
        --labels data/rollout-labels/episodes.jsonl [round2.jsonl ...] --out runs/gaitnet-dagger
"""

from __future__ import annotations

import argparse
import hashlib
import json
from pathlib import Path

import numpy as np

from gaitnet_mpc.gaitnet.data import GaitData, load_dataset
from gaitnet_mpc.gaitnet.fit import fit, write_fit
from gaitnet_mpc.gaitnet.train import TrainConfig


def dagger_rows(path: Path, groups: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """Features, labels and set ids of the labelled step starts in ``path``."""
    xs, ys, sets = [], [], []
    counts = {"episodes": 0, "step_starts": 0, "labelled": 0, "corrected": 0}
    for line in path.read_text().splitlines():
        if not line:
            continue
        rec = json.loads(line)
        counts["episodes"] += 1
        for step in rec["steps"]:
            counts["step_starts"] += 1
            label = step["label_dt_s"]
            if label is None:
                continue
            counts["labelled"] += 1
            counts["corrected"] += label != step["own_dt_s"]
            for x in step["features"]:
                xs.append(x)
                ys.append(label)
                sets.append(1000 + rec["seed"] % groups)
    return np.asarray(xs, float), np.asarray(ys, float), np.asarray(sets, int), counts


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, required=True)
    ap.add_argument("--labels", type=Path, nargs="+", required=True, help="DAgger rounds")
    ap.add_argument("--groups", type=int, default=5)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    base = load_dataset(args.data)
    parts = [dagger_rows(p, args.groups) for p in args.labels]
    x = np.vstack([p[0] for p in parts])
    y = np.concatenate([p[1] for p in parts])
    sets = np.concatenate([p[2] for p in parts])
    counts = {k: sum(p[3][k] for p in parts) for k in parts[0][3]}
    digests = [hashlib.sha256(p.read_bytes()).hexdigest() for p in args.labels]
    sha = hashlib.sha256("".join([base.manifest_sha256, *digests]).encode()).hexdigest()
    data = GaitData(
        x=np.vstack([base.x, x]),
        y=np.concatenate([base.y, y]),
        set_id=np.concatenate([base.set_id, sets]),
        pushed=np.concatenate([base.pushed, np.ones(len(y), bool)]),
        dt_range_s=base.dt_range_s,
        manifest_sha256=sha,
        robot=base.robot,
        teacher=f"{base.teacher}+rollout-dagger",
    )
    result, report, selection = fit(data, "full", TrainConfig(), progress=False)
    write_fit(args.out, result, report, selection)
    (args.out / "dagger.json").write_text(
        json.dumps({"base_rows": len(base.y), "dagger_rows": len(y), **counts}, indent=1)
    )
    print(json.dumps({**counts, "rows": len(y), "test_rmse_s": report.test_rmse_s}))


if __name__ == "__main__":
    main()
