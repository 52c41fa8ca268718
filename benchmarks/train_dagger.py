"""Train Gait-Net on its data set plus the rollout oracle's DAgger rows
(``benchmarks/rollout_labels.py``), as ``gaitnet-mpc train --features full`` would.

The DAgger rows are grouped into ``--groups`` sets by episode seed, so that the split by
set (validation for early stopping, test for the report) holds out whole episodes.

``--relabel shortest`` replaces each step start's label by the shortest candidate dt within
``--bounds`` whose rollout survived (none survived: no row), from the outcomes the records
keep; ``own`` keeps the records' labels (the student's own dt where it survived, else the
surviving candidate nearest to it). ``benchmarks/rollout_survival.py`` shows why one
would: at the step starts where the dt decided the fall, shorter dts survived more often
(``docs/design/gaitnet_recovery.md``, 2026-12-08).

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


def shortest_surviving_s(step: dict, bounds_s: tuple[float, float]) -> float | None:
    """The shortest candidate dt [s] within ``bounds_s`` whose rollout survived, or None."""
    lo, hi = bounds_s
    ok = [float(dt) for dt, o in (step.get("outcomes") or {}).items() if not o["fell"]]
    ok = [dt for dt in ok if lo - 1e-9 <= dt <= hi + 1e-9]
    return min(ok) if ok and step["own_dt_s"] is not None else None


def dagger_rows(
    path: Path, groups: int, relabel: str = "own", bounds_s: tuple[float, float] = (0.045, 0.07)
) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """Features, labels and set ids of the labelled step starts in ``path`` (``relabel``:
    the module docstring)."""
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
            if relabel == "shortest":
                label = shortest_surviving_s(step, bounds_s)
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
    ap.add_argument("--relabel", choices=("own", "shortest"), default="own")
    ap.add_argument("--bounds", type=float, nargs=2, default=(0.045, 0.07), metavar=("LO", "HI"))
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    base = load_dataset(args.data)
    bounds = (args.bounds[0], args.bounds[1])
    parts = [dagger_rows(p, args.groups, args.relabel, bounds) for p in args.labels]
    x = np.vstack([p[0] for p in parts])
    y = np.concatenate([p[1] for p in parts])
    sets = np.concatenate([p[2] for p in parts])
    counts = {k: sum(p[3][k] for p in parts) for k in parts[0][3]}
    digests = [hashlib.sha256(p.read_bytes()).hexdigest() for p in args.labels]
    keys = [base.manifest_sha256, *digests, f"{args.relabel}{bounds}"]
    sha = hashlib.sha256("".join(keys).encode()).hexdigest()
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
