"""Does Gait-Net's ensemble spread flag inputs unlike its training data?

For a weights file and several data-set folders (``gaitnet-mpc collect``), the ensemble
spread (standard deviation of the members' dt) and the RMSE of dt per folder, split into
pushed and unpushed steps. The first folder should be the training data's (its held-out
test sets are evaluated, read from the training report next to the weights when given);
the others, data the net never saw (another course, another teacher).

Writes ``benchmarks/results/gaitnet_spread.md``. Run::

    .venv/bin/python benchmarks/gaitnet_spread.py --weights W.npz --data D1 D2 ... \
        [--test-sets 2,3,11]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from gaitnet_mpc.dataset.schema import FEATURE_NAMES
from gaitnet_mpc.gaitnet import GaitNet
from gaitnet_mpc.gaitnet.data import load_dataset
from machine import machine_info, write_report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--weights", type=Path, required=True)
    parser.add_argument("--data", type=Path, nargs="+", required=True)
    parser.add_argument(
        "--test-sets", default="", help="set ids of the first folder to evaluate (its test)"
    )
    args = parser.parse_args()
    net = GaitNet.load(args.weights)
    cols = [FEATURE_NAMES.index(n) for n in net.feature_names]
    lines = [
        "# Gait-Net ensemble spread in and out of its training data",
        "",
        machine_info(("numpy",)),
        "",
        f"Weights `{args.weights}` ({net.spec.members} members, {len(cols)} features, "
        f"trained on data `{net.spec.data_manifest_sha256[:12]}`).",
        "",
        "| data | course | teacher | steps | pushed | spread median [s] | spread p90 [s] "
        "| RMSE dt [s] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for i, folder in enumerate(args.data):
        data = load_dataset(folder)
        from gaitnet_mpc.dataset.store import read_manifest

        course = (read_manifest(folder) or {})["protocol"]["course"]
        mask = np.ones(len(data.y), dtype=bool)
        if i == 0 and args.test_sets:
            mask = np.isin(data.set_id, [int(s) for s in args.test_sets.split(",")])
        for pushed in (False, True):
            m = mask & (data.pushed == pushed)
            if not np.any(m):
                continue
            members = net.members_dt(data.x[m][:, cols])
            spread = members.std(axis=1)
            lo, hi = net.dt_clip_s
            rmse = float(np.sqrt(np.mean((np.clip(members.mean(1), lo, hi) - data.y[m]) ** 2)))
            name = f"{folder}" + (" (test sets)" if i == 0 and args.test_sets else "")
            lines.append(
                f"| {name} | {course} | {data.teacher} | {int(m.sum())} | {pushed} | "
                f"{np.median(spread):.2e} | {np.percentile(spread, 90):.2e} | {rmse:.2e} |"
            )
    cmd = " ".join(str(d) for d in args.data)
    lines += [
        "",
        f"Command: `.venv/bin/python benchmarks/gaitnet_spread.py --weights {args.weights} "
        f"--data {cmd}" + (f" --test-sets {args.test_sets}`." if args.test_sets else "`."),
        "",
    ]
    write_report("gaitnet_spread.md", "\n".join(lines))


if __name__ == "__main__":
    main()
