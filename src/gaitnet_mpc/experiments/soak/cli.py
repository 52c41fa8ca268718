"""The soak's command line (``benchmarks/soak.py``): :func:`main` parses the arguments and
runs a soak (exit code 0 when every episode is done, 130 when it was interrupted) or, with
``--replay K``, runs episode K in this process (:func:`replay`)."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from gaitnet_mpc.experiments.soak.draw import (
    CONTROLLER_WEIGHTS,
    PROFILES,
    DrawSettings,
    draw_episode,
)
from gaitnet_mpc.experiments.soak.engine import RESULTS, SoakOptions, soak
from gaitnet_mpc.experiments.soak.worker import simulate

#: ``--help``'s description.
DESCRIPTION = (
    "Soak test: many random short episodes, looking for crashes rather than for good walking."
)


def replay(settings: DrawSettings, index: int) -> int:
    """Run episode ``index`` here, letting any exception propagate; print its outcome."""
    spec = draw_episode(settings, index)
    print(json.dumps(spec.to_dict()))
    print(spec.label(), flush=True)
    summary = simulate(spec)
    keys = ("fell", "fall_time_s", "fall_reason", "diverged", "wall_time_s", "mpc")
    brief = {k: summary.get(k) for k in keys}
    print(json.dumps(brief, indent=2))
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=DESCRIPTION)
    parser.add_argument("--episodes", type=int, default=12)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--backend", choices=("process", "ray"), default="process")
    parser.add_argument("--address", default=None, help="Ray cluster address (--backend ray)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--controllers",
        default=",".join(CONTROLLER_WEIGHTS),
        help="controllers to draw from (default: %(default)s)",
    )
    parser.add_argument("--max-duration-s", type=float, default=None, help="cap on durations")
    parser.add_argument(
        "--profile",
        choices=PROFILES,
        default="short",
        help="short: 1-5 s on every course; long: 20 s on seeded stones, gaps, uneven tiles "
        "with 1-3 pushes (default: %(default)s)",
    )
    parser.add_argument("--out", type=Path, default=RESULTS / "soak.md")
    parser.add_argument("--work-dir", type=Path, default=None, help="default: --out's folder")
    parser.add_argument("--replay", type=int, default=None, metavar="K", help="run episode K")
    args = parser.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # inherited by the workers
    settings = DrawSettings(
        args.seed,
        tuple(c for c in args.controllers.split(",") if c),
        args.max_duration_s,
        args.profile,
    )
    if args.replay is not None:
        return replay(settings, args.replay)
    options = SoakOptions(
        args.episodes, args.workers, args.backend, args.out, args.work_dir, args.address
    )
    command = "MUJOCO_GL=egl .venv/bin/python benchmarks/soak.py " + " ".join(
        sys.argv[1:] if argv is None else argv
    )
    records = soak(options, settings, command)
    done = sum(i < options.episodes for i in records)
    return 0 if done == options.episodes else 130
