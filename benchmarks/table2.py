"""Table II: record kd problems in closed loop, then solve them with every method.

Records ``--problems`` problems of walking (humanoid3d, 0.75 m/s, fixed dt 0.05 s), half
on the flat course and half on stepping stones, into ``--out/problems.npz`` (reused if
it holds enough), solves them (resumable: run again after an interruption) and writes
``--out/table2.md``; with ``--results`` also a copy there. Run::

    .venv/bin/python benchmarks/table2.py [--problems 40] [--out runs/table2]
        [--no-joint-space]   # skip explicit KD-SQP and WBD-SQP (NLP builds of 2-20 s each)
        [--results benchmarks/results/table2.md]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gaitnet_mpc.table2.run import reproduce_table2


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", type=int, default=40, help="problems in the table")
    parser.add_argument("--out", type=Path, default=Path("runs/table2"))
    parser.add_argument(
        "--no-joint-space", action="store_true", help="skip explicit KD-SQP and WBD-SQP"
    )
    parser.add_argument("--results", type=Path, help="also copy the table here")
    args = parser.parse_args()
    report = reproduce_table2(
        args.out,
        args.problems,
        progress=lambda n, total: print(f"\r{n}/{total}", end="", file=sys.stderr, flush=True),
        with_joint_space=not args.no_joint_space,
    )
    print(file=sys.stderr)
    print(report.read_text(), end="")
    if args.results is not None:
        args.results.write_text(report.read_text())


if __name__ == "__main__":
    main()
