"""``gaitnet-mpc bench``: time the closed loop (solves, tick, real-time factor, memory)."""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from gaitnet_mpc.errors import ConfigError

SUMMARY = "time the closed loop: solves, low-level tick, real-time factor, memory"

#: Imported before the command starts, with Ctrl-C held back (cli/main.py).
PRELOAD = ("gaitnet_mpc.scenario", "gaitnet_mpc.mpc.qp")


def add_parser(sub: Any) -> None:
    b = sub.add_parser(
        "bench",
        help=SUMMARY,
        description="Walk each case (a controller with --set overrides) on the same course, "
        "--rounds times in fresh processes, interleaved; print and write perf.md: solve-time "
        "distribution, QPs per solve, low-level tick, real-time factor, a profile of the "
        "first case and (with --memory-seconds) the RSS over one long episode.",
    )
    b.add_argument(
        "--case",
        action="append",
        default=None,
        metavar="LABEL=CONTROLLER[:KEY=VALUE,...]",
        help="a case to time (repeatable); default: kd and gaitnet, each as shipped and "
        "with RTI replans (--preset realtime)",
    )
    b.add_argument("--course", default="flat", help="built-in course (default: %(default)s)")
    b.add_argument("--vx", type=float, default=0.75, help="m/s (default: %(default)s)")
    b.add_argument(
        "--seconds", type=float, default=4.0, help="simulated per episode (default: %(default)s)"
    )
    b.add_argument("--rounds", type=int, default=3, help="rounds per case (default: %(default)s)")
    b.add_argument(
        "--memory-seconds",
        type=float,
        default=0.0,
        help="one episode this long, stepping in place (vx 0: the course is finite), RSS "
        "at start and end (0: skip; default: %(default)s)",
    )
    b.add_argument(
        "--memory-case",
        default=None,
        metavar="LABEL",
        help="the case of the memory episode (default: the first)",
    )
    b.add_argument(
        "--baseline",
        default=None,
        metavar="REV",
        help="also time the first case with the package as it was at git revision REV, "
        "interleaved, as the first row (the before/after comparison)",
    )
    b.add_argument("--no-profile", action="store_true", help="skip the cProfile breakdown")
    b.add_argument(
        "--out",
        type=Path,
        default=Path("runs/perf.md"),
        help="report file, new unless --overwrite (default: %(default)s; "
        "benchmarks/results/perf.md for the record)",
    )
    b.add_argument("--overwrite", action="store_true", help="replace an existing --out")


def main(args: argparse.Namespace) -> int:
    from gaitnet_mpc.experiments.bench import DEFAULT_CASES, EpisodeSpec, build_case, parse_case
    from gaitnet_mpc.results.outdir import check_output_file, claim_output_file

    check_output_file(args.out, "--out", args.overwrite)  # at once: building cases is slow
    cases = [parse_case(c) for c in args.case] if args.case else list(DEFAULT_CASES)
    spec = EpisodeSpec(args.course, args.vx, args.seconds)
    if not (math.isfinite(args.memory_seconds) and args.memory_seconds >= 0.0):
        raise ConfigError("--memory-seconds", args.memory_seconds, "a finite time >= 0 s")
    labels = [c.label for c in cases]
    memory_case = cases[0]
    if args.memory_case is not None:
        if args.memory_case not in labels:
            raise ConfigError("--memory-case", args.memory_case, f"one of {labels}")
        memory_case = cases[labels.index(args.memory_case)]
    for case in cases:  # bad controller names or overrides fail here, before any timing
        build_case(case, spec)
    if args.memory_case is not None and args.memory_seconds == 0.0:
        text = f"--memory-case {args.memory_case} has no effect without --memory-seconds"
        print(f"gaitnet-mpc: warning: {text}", file=sys.stderr)
    with claim_output_file(args.out, option="--out", overwrite=args.overwrite, what="bench"):
        return _bench(args, cases, spec, memory_case)


def _bench(args: argparse.Namespace, cases: list[Any], spec: Any, memory_case: Any) -> int:
    """Time ``cases`` and write the report (``--out`` is claimed)."""
    import shlex

    from gaitnet_mpc.experiments.bench import EpisodeSpec as Spec
    from gaitnet_mpc.experiments.bench import (
        perf_markdown,
        profiled_episode,
        run_bench,
        timed_episode,
    )
    from gaitnet_mpc.results.io import write_atomic

    if args.baseline is not None:
        first = cases[0]
        old = replace(first, label=f"{first.label} @ {args.baseline}", revision=args.baseline)
        cases.insert(0, old)

    def say(text: str) -> None:
        print(text, file=sys.stderr, flush=True)

    results = run_bench(cases, spec, args.rounds, progress=say)
    parts = None
    profiled = cases[1] if args.baseline is not None else cases[0]  # this tree's first case
    if not args.no_profile:
        say(f"profiling {profiled.label}")
        parts = profiled_episode(profiled, spec)
    memory = None
    if args.memory_seconds > 0.0:
        say(f"memory: {memory_case.label}, {args.memory_seconds:g} s simulated in place")
        memory = timed_episode(
            memory_case,
            Spec(args.course, 0.0, args.memory_seconds),
            on_second=lambda t: say(f"  {t:.0f} s") if round(t) % 60 == 0 else None,
            record_ticks=False,
        )
    report = perf_markdown(
        results,
        spec,
        args.rounds,
        parts,
        profiled.label,
        memory,
        memory_case.label,
        shlex.join(["gaitnet-mpc", *args.argv]),
    )
    write_atomic(args.out, report)
    print(report)
    print(f"written to {args.out}")
    return 0
