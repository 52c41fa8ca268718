"""Table II: record kd problems in closed loop, then solve them with every method.

Records ``--seconds`` of walking (humanoid3d, 0.75 m/s, fixed dt 0.05 s) on the flat
course and on the stepping stones, keeps every ``--every``-th problem, saves them to
``--out/problems.npz`` (reused if present) and writes ``--out/table2.md``. Run::

    .venv/bin/python benchmarks/table2.py [--seconds 3] [--problems 40] [--out runs/table2]
        [--no-joint-space]   # skip explicit KD-SQP and WBD-SQP (NLP builds of 2-20 s each)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gaitnet_mpc.table2.run import reproduce_table2


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="walking per course [s]")
    parser.add_argument("--every", type=int, default=2, help="keep every n-th problem")
    parser.add_argument("--problems", type=int, default=40, help="problems in the table")
    parser.add_argument("--out", type=Path, default=Path("runs/table2"))
    parser.add_argument(
        "--no-joint-space", action="store_true", help="skip explicit KD-SQP and WBD-SQP"
    )
    args = parser.parse_args()
    report = reproduce_table2(
        args.out,
        args.problems,
        args.seconds,
        args.every,
        progress=lambda n, total: print(f"\r{n}/{total}", end="", file=sys.stderr, flush=True),
        with_joint_space=not args.no_joint_space,
    )
    print(file=sys.stderr)
    print(report.read_text(), end="")


if __name__ == "__main__":
    main()
