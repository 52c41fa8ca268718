"""``gaitnet-mpc collect``: the Gait-Net data set by the paper's protocol (resumable)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

SUMMARY = "collect the Gait-Net data set (paper Sec. IV-A-1); re-run to resume"

#: Imported before the command starts, with Ctrl-C held back (cli/main.py).
PRELOAD = ("gaitnet_mpc.scenario", "gaitnet_mpc.mpc.qp")


def add_parser(sub: Any) -> None:
    from gaitnet_mpc.dataset.protocol import TEACHERS, CollectProtocol
    from gaitnet_mpc.experiments.collect import BACKENDS
    from gaitnet_mpc.robots import ROBOTS

    d = CollectProtocol()
    c = sub.add_parser(
        "collect",
        help=SUMMARY,
        description="Walk the protocol's sets with the teacher and write one Parquet file per "
        "set and manifest.json into --out. Re-running the same command skips finished sets.",
    )
    c.add_argument("--out", type=Path, required=True, help="data-set folder")
    c.add_argument("--robot", choices=sorted(ROBOTS), default=d.robot)
    c.add_argument(
        "--teacher",
        choices=TEACHERS,
        default=d.teacher,
        help="wbmpc: the whole-body NMPC (the paper's); kd: the kino-dynamic MPC with the "
        "drawn dts (default: %(default)s)",
    )
    c.add_argument("--sets", type=int, default=d.sets, help="number of sets (default: %(default)s)")
    c.add_argument(
        "--seconds",
        type=float,
        default=d.seconds_total,
        help="simulated seconds of all sets together, split equally (default: %(default)s)",
    )
    c.add_argument("--seed", type=int, default=d.seed, help="protocol seed (default: %(default)s)")
    c.add_argument(
        "--course", default=d.course, help="course name or JSON file (default: %(default)s)"
    )
    c.add_argument(
        "--max-restarts",
        type=int,
        default=d.max_restarts,
        help="fresh starts after falls within a set (default: %(default)s)",
    )
    c.add_argument("--preset", default=None, help="the teacher's settings preset")
    c.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override one of the teacher's settings (repeatable)",
    )
    c.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="sets walked in parallel (default: the machine's cores, %(default)s)",
    )
    c.add_argument("--backend", choices=BACKENDS, default="process", help="default: %(default)s")
    c.add_argument("--address", default=None, help="Ray cluster address (--backend ray)")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")


def main(args: argparse.Namespace) -> int:
    import shlex

    from gaitnet_mpc.dataset.protocol import CollectProtocol
    from gaitnet_mpc.experiments.collect import CollectOptions, collect

    protocol = CollectProtocol(
        robot=args.robot,
        teacher=args.teacher,
        sets=args.sets,
        seconds_total=args.seconds,
        course=args.course,
        seed=args.seed,
        max_restarts=args.max_restarts,
        teacher_preset=args.preset,
        teacher_overrides=tuple(args.overrides),
    )
    options = CollectOptions(
        workers=args.workers,
        backend=args.backend,
        address=args.address,
        progress=not args.no_progress,
    )
    command_line = shlex.join(["gaitnet-mpc", *args.argv])
    try:
        manifest = collect(protocol, args.out, options, command_line)
    except KeyboardInterrupt:
        return 130
    totals = manifest["totals"]
    print(
        f"{args.out}: {totals['sets']}/{protocol.sets} sets, {totals['rows']} rows, "
        f"{totals['falls']} fall(s), {totals['steps_dropped_fall']} step(s) dropped for falls"
    )
    return 0
