"""``gaitnet-mpc reproduce``: a table or figure of the paper."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from gaitnet_mpc.experiments.reproduce import REPRODUCIBLE

SUMMARY = "reproduce a table or figure of the paper"


def add_parser(sub: Any) -> None:
    rep = sub.add_parser("reproduce", help=SUMMARY)
    rep.add_argument(
        "what",
        choices=sorted(REPRODUCIBLE),
        help="; ".join(f"{k}: {v}" for k, v in REPRODUCIBLE.items()),
    )
    rep.add_argument(
        "--data",
        type=Path,
        default=Path("data/gaitnet-kd-humanoid3d"),
        help="data-set folder (default: %(default)s)",
    )
    rep.add_argument("--out", type=Path, default=None, help="default: runs/<what>")
    rep.add_argument(
        "--problems",
        type=int,
        default=40,
        help="table2: recorded MPC problems to solve, >= 1 (default: %(default)s)",
    )
    rep.add_argument(
        "--no-joint-space",
        action="store_true",
        help="table2: skip the explicit KD-SQP and WBD-SQP columns (the slow ones)",
    )


def main(args: argparse.Namespace) -> int:
    from gaitnet_mpc.experiments import reproduce

    out = args.out if args.out is not None else Path("runs") / args.what
    if args.what == "table2":
        report = reproduce.table2(
            out,
            args.problems,
            with_joint_space=not args.no_joint_space,
            progress=lambda n, total: print(
                f"\rsolved {n}/{total} problems", end="", file=sys.stderr, flush=True
            ),
        )
        print(file=sys.stderr)
    else:
        report = reproduce.table1(args.data, out)
    print(report.read_text(), end="")
    print(f"results in {out}/")
    return 0
