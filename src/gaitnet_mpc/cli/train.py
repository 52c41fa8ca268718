"""``gaitnet-mpc train``: fit Gait-Net on a data set (needs PyTorch)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

SUMMARY = "train Gait-Net on a data set (needs PyTorch: pip install 'gaitnet-mpc[train]')"


def add_parser(sub: Any) -> None:
    t = sub.add_parser(
        "train",
        help=SUMMARY,
    )
    t.add_argument("--data", type=Path, required=True, help="data-set folder (collect --out)")
    t.add_argument("--features", choices=("pca", "full"), default="pca", help="default: pca")
    t.add_argument("--out", type=Path, required=True, help="output folder (gaitnet.npz, ...)")
    t.add_argument("--members", type=int, default=5, help="ensemble size (default: 5)")
    t.add_argument("--epochs", type=int, default=400, help="most epochs (default: 400)")
    t.add_argument("--seed", type=int, default=0, help="training and split seed (default: 0)")
    t.add_argument("--no-progress", action="store_true", help="no progress bar")


def main(args: argparse.Namespace) -> int:
    from gaitnet_mpc.gaitnet.data import load_dataset
    from gaitnet_mpc.gaitnet.fit import fit, write_fit
    from gaitnet_mpc.gaitnet.train import TrainConfig

    config = TrainConfig(members=args.members, epochs=args.epochs, seed=args.seed)
    data = load_dataset(args.data)
    result, report, selection = fit(
        data, args.features, config, split_seed=args.seed, progress=not args.no_progress
    )
    write_fit(args.out, result, report, selection)
    print(
        f"features {', '.join(report.feature_names)}\n"
        f"test RMSE of dt {report.test_rmse_s:.2e} s (always the mean: "
        f"{report.mean_predictor_rmse_s:.2e} s) on sets {list(report.split.test)}\n"
        f"weights and report in {args.out}/"
    )
    return 0
