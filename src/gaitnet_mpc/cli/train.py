"""``gaitnet-mpc train``: fit Gait-Net on a data set (needs PyTorch)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

SUMMARY = "train Gait-Net on a data set (needs PyTorch); re-run to resume"


def add_parser(sub: Any) -> None:
    t = sub.add_parser(
        "train",
        help=SUMMARY,
    )
    t.add_argument("--data", type=Path, required=True, help="data-set folder (collect --out)")
    t.add_argument(
        "--features",
        default="pca",
        help="pca (default: one feature per principal axis, paper Sec. IV-A2), full (all 16), "
        "or feature names separated by commas",
    )
    t.add_argument(
        "--out",
        type=Path,
        required=True,
        help="model folder (gaitnet.npz, report.json, loss.csv, loss.png, fig4.png): new or "
        "empty; written whole when training ends",
    )
    t.add_argument(
        "--overwrite", action="store_true", help="replace the model in an existing --out"
    )
    t.add_argument("--members", type=int, default=5, help="ensemble size (default: 5)")
    t.add_argument("--epochs", type=int, default=400, help="most epochs (default: 400)")
    t.add_argument("--seed", type=int, default=0, help="training and split seed (default: 0)")
    t.add_argument("--no-progress", action="store_true", help="no progress bar")


def main(args: argparse.Namespace) -> int:
    import shlex

    from gaitnet_mpc.gaitnet.train import TrainConfig
    from gaitnet_mpc.gaitnet.training_run import train_folder

    config = TrainConfig(members=args.members, epochs=args.epochs, seed=args.seed)
    report = train_folder(
        args.data,
        args.out,
        args.features,
        config,
        args.seed,
        overwrite=args.overwrite,
        progress=not args.no_progress,
        command=shlex.join(["gaitnet-mpc", *args.argv]),
    )
    print(
        f"features {', '.join(report.feature_names)}\n"
        f"test RMSE of dt {report.test_rmse_s:.2e} s (always the mean: "
        f"{report.mean_predictor_rmse_s:.2e} s) on sets {list(report.split.test)}\n"
        f"weights and report in {args.out}/"
    )
    return 0
