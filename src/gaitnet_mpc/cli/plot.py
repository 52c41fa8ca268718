"""``gaitnet-mpc plot RUN_DIR``: (re)make the PNGs of a run folder from its files."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

SUMMARY = "(re)make the plots of a run folder"


def add_parser(sub: Any) -> None:
    plot = sub.add_parser("plot", help=SUMMARY)
    plot.add_argument("run_dir", type=Path, metavar="RUN_DIR", help="folder written by `run`")


def main(args: argparse.Namespace) -> int:
    from gaitnet_mpc.results.outdir import check_writable, folder_lock
    from gaitnet_mpc.results.plots import make_plots
    from gaitnet_mpc.results.rundir import PLOTS_DIR, load_run

    load_run(args.run_dir)  # a named error for anything but a readable run folder
    check_writable(args.run_dir, "RUN_DIR")  # the plots go to RUN_DIR/plots
    if (args.run_dir / PLOTS_DIR).is_dir():
        check_writable(args.run_dir / PLOTS_DIR, "RUN_DIR", shown=args.run_dir)
    with folder_lock(args.run_dir, option="RUN_DIR"):  # not while a run writes it
        written = make_plots(args.run_dir)
    for path in written:
        print(path)
    if not written:
        print(f"{args.run_dir}: empty log, no plots written", file=sys.stderr)
    return 0
