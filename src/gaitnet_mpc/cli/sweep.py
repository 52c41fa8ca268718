"""``gaitnet-mpc sweep``: robustness benchmarks (pushes, protocol pushes, payload,
terrain) on a process pool or Ray, resumable."""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path
from typing import Any

SUMMARY = "robustness sweeps: push, protocol, payload, terrain; re-run to resume"

#: Imported before the command starts, with Ctrl-C held back (cli/main.py).
PRELOAD = ("gaitnet_mpc.scenario", "gaitnet_mpc.mpc.qp")


def add_parser(sub: Any) -> None:
    from gaitnet_mpc.experiments.collect import BACKENDS
    from gaitnet_mpc.experiments.sweep import DEFAULT_CONTROLLERS, DEFAULT_SEEDS
    from gaitnet_mpc.experiments.sweep_cases import MODES

    s = sub.add_parser(
        "sweep",
        help=SUMMARY,
        description="push: the largest survivable 0.2 s push per controller, direction (8), "
        "phase of a step and speed (bisection on the force); protocol: survival under the "
        "data-collection protocol's random pushes; payload: the largest unknown trunk "
        "payload on flat and over the 20 cm gap (bisection); terrain: clean runs over seeded "
        "uneven courses of growing amplitude and seeded stepping stones. Writes cases.jsonl, "
        "sweep.csv, sweep.md, status.json (and push_polar.png) into --out; re-running the "
        "same command skips finished cases.",
    )
    s.add_argument("mode", metavar="MODE", choices=MODES, help=f"one of {', '.join(MODES)}")
    s.add_argument("--out", type=Path, required=True, help="sweep folder")
    s.add_argument(
        "--controllers",
        default=None,
        help=f"comma-separated, NAME[@DT][:WEIGHTS][+PRESET]: a fixed MPC dt [s], Gait-Net "
        f"weights (a shipped name or a path) and a preset or a settings file (as --config), "
        f"e.g. kd@0.055, gaitnet:humanoid3d-dagger, gaitnet+realtime or gaitnet+my.toml "
        f"(default: {','.join(DEFAULT_CONTROLLERS)}; with --quick: srbm)",
    )
    s.add_argument(
        "--seeds",
        type=int,
        default=None,  # None: not given (warned about where it has no effect)
        help=f"seeds of protocol and terrain (default: {DEFAULT_SEEDS}; --quick: 1)",
    )
    s.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="cases run in parallel (default: the machine's cores, %(default)s)",
    )
    s.add_argument("--backend", choices=BACKENDS, default="process", help="default: %(default)s")
    s.add_argument("--address", default=None, help="Ray cluster address (--backend ray)")
    s.add_argument(
        "--speeds", default=None, metavar="V,...", help="forward speeds [m/s] (default: all)"
    )
    s.add_argument(
        "--directions",
        default=None,
        metavar="NAME,...",
        help="push: directions among fwd, fwd-left, left, bwd-left, bwd, bwd-right, right, "
        "fwd-right (default: all 8)",
    )
    s.add_argument(
        "--phases",
        default=None,
        metavar="P,...",
        help="push: push start as fractions of a step in [0, 1) (default: 0, 0.25, 0.5, 0.75)",
    )
    s.add_argument("--quick", action="store_true", help="a tiny sweep (the test suite's)")
    s.add_argument("--no-progress", action="store_true", help="no line per finished case")


def main(args: argparse.Namespace) -> int:
    import shlex

    from gaitnet_mpc.experiments.sweep import (
        DEFAULT_CONTROLLERS,
        DEFAULT_SEEDS,
        QUICK_CONTROLLER,
        Options,
        SweepSettings,
        sweep,
    )

    if args.controllers is None:
        controllers = (QUICK_CONTROLLER,) if args.quick else DEFAULT_CONTROLLERS
    else:
        controllers = tuple(c.strip() for c in args.controllers.split(",") if c.strip())
    options = Options(
        workers=args.workers,
        backend=args.backend,
        address=args.address,
        progress=not args.no_progress,
    )
    settings = SweepSettings(
        args.mode,
        controllers,
        args.quick,
        DEFAULT_SEEDS if args.seeds is None else args.seeds,
        speeds_mps=_numbers(args.speeds, "--speeds"),
        directions=None if args.directions is None else _names(args.directions),
        phases=_numbers(args.phases, "--phases"),
    )
    for text in unused_options(args):
        print(f"gaitnet-mpc: warning: {text}", file=sys.stderr)
    command_line = shlex.join(["gaitnet-mpc", *args.argv])
    records = sweep(settings, args.out, options, command_line)
    print(f"{args.out}: {len(records)} case(s); see {args.out / 'sweep.md'}")
    return 0


def unused_options(args: argparse.Namespace) -> list[str]:
    """A warning for each option given that has no effect (as ``run`` warns)."""
    out = []
    if args.seeds is not None:
        if args.mode in ("push", "payload"):
            why = f"sweep {args.mode} has no seeds (protocol and terrain do)"
            out.append(f"--seeds {args.seeds} has no effect: {why}")
        elif args.quick:
            out.append(f"--seeds {args.seeds} has no effect with --quick (one seed)")
    return out  # --address without --backend ray: a named error (Options)


def _names(text: str) -> tuple[str, ...]:
    return tuple(t.strip() for t in text.split(",") if t.strip())


def _numbers(text: str | None, option: str) -> tuple[float, ...] | None:
    """``"0.25,0.5"`` -> (0.25, 0.5); a named error for anything but numbers."""
    from gaitnet_mpc.errors import ConfigError

    if text is None:
        return None
    try:
        values = tuple(float(t) for t in _names(text))
    except ValueError:
        raise ConfigError(option, text, "comma-separated numbers") from None
    if not all(math.isfinite(v) for v in values):
        raise ConfigError(option, text, "finite numbers")
    return values
