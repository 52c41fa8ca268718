"""``gaitnet-mpc compare RUN_DIR ...``: one figure and one table over several runs."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

SUMMARY = "compare several run folders (figure + table)"


def add_parser(sub: Any) -> None:
    compare = sub.add_parser("compare", help=SUMMARY)
    compare.add_argument("run_dirs", type=Path, nargs="+", metavar="RUN_DIR")
    compare.add_argument(
        "--out", default=None, help="output folder (default runs/compare-<time>-<id>)"
    )


def main(args: argparse.Namespace) -> int:

    from gaitnet_mpc.results.compare import compare_runs
    from gaitnet_mpc.results.rundir import COMPARE_ARTIFACTS, prepare_output_folder

    out = prepare_output_folder(
        args.out,
        option="--out",
        default_prefix="compare-",
        artifacts=COMPARE_ARTIFACTS,
        overwrite=True,  # a comparison is cheap to remake; its own files are replaced
    )
    paths = compare_runs(args.run_dirs, out)
    print(paths["markdown"].read_text(), end="")
    print(f"results in {out}/")
    return 0
