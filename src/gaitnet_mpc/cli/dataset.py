"""``gaitnet-mpc dataset check``: validate a data-set folder."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

SUMMARY = "data-set tools (check a folder against its manifest)"


def add_parser(sub: Any) -> None:
    ds = sub.add_parser("dataset", help=SUMMARY)
    ds_sub = ds.add_subparsers(dest="dataset_cmd", required=True)
    check = ds_sub.add_parser("check", help="validate a data-set folder")
    check.add_argument("folder", type=Path, metavar="DIR")


def main(args: argparse.Namespace) -> int:
    from gaitnet_mpc.dataset.check import check_dataset

    result = check_dataset(args.folder)
    print(f"{args.folder}: OK ({result['files']} files, {result['rows']} rows)")
    return 0
