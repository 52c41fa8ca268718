"""Seeded ``uneven`` courses at one amplitude and speed (issue 50's uneven-ground lines).

Each seed draws contiguous tiles with tops uniform in ``[-A, A]`` (``uneven_course``) and
one episode walks them; the report counts falls and clean runs (no fall, no violation, no
leg contact) and lists the seeds that were not clean.

    .venv/bin/python benchmarks/uneven_runs.py --amplitude 0.05 --speed 0.75 --seeds 20 \
        [--seed-offset 100] [--blind] [--set KEY=VALUE] [--jobs 2] [--out NAME.md]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from functools import partial
from pathlib import Path

from common import clean_run, command_line, machine_info, run_pool, write_report

DURATION_S = 14.0


def run(
    seed: int, amplitude_m: float, speed_mps: float, blind: bool, overrides: tuple[str, ...] = ()
) -> dict:
    from gaitnet_mpc.scenario import make_scenario, run_scenario
    from gaitnet_mpc.terrain.builtin_courses import uneven_course

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"uneven-{seed}.json"
        path.write_text(json.dumps(uneven_course(seed=seed, amplitude_m=amplitude_m).to_dict()))
        scenario = make_scenario(
            controller="gaitnet",
            course=str(path),
            vx_mps=speed_mps,
            duration_s=DURATION_S,
            overrides=(*overrides, *(("blind=true",) if blind else ())),
        )
        s = run_scenario(scenario)
    return {
        "clean": clean_run(s),
        "fell": s["fell"],
        "fall_time_s": s["fall_time_s"],
        "distance_m": s["distance_m"],
        "leg_contact_ticks": int(s["self_collisions"] or 0),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--amplitude", type=float, default=0.05, help="tile tops in [-A, A] m")
    parser.add_argument("--speed", type=float, default=0.75, help="commanded speed [m/s]")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--seed-offset", type=int, default=0, help="first seed (tuning: 100)")
    parser.add_argument("--blind", action="store_true", help="the controller is told no terrain")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="as `gaitnet-mpc run`"
    )
    parser.add_argument("--out", default=None, help="report name in benchmarks/results/")
    args = parser.parse_args()
    seeds = list(range(args.seed_offset, args.seed_offset + args.seeds))
    tuning = args.seed_offset >= 100  # seeds 100 and up are the tuning seeds
    worker = partial(
        run,
        amplitude_m=args.amplitude,
        speed_mps=args.speed,
        blind=args.blind,
        overrides=tuple(args.set),
    )
    t0 = time.perf_counter()
    results = run_pool(
        worker, seeds, args.jobs, describe=lambda s, r: f"seed {s}: clean {r['clean']}"
    )
    wall_s = time.perf_counter() - t0
    knowledge = "blind (`--blind`)" if args.blind else "the one-step preview"
    falls = [s for s in seeds if results[s]["fell"]]
    unclean = [s for s in seeds if not results[s]["clean"]]
    lines = [
        f"# `gaitnet` on seeded uneven tiles, +-{args.amplitude * 100:g} cm, {args.speed:g} m/s",
        "",
        machine_info(("numpy", "mujoco", "pin")),
        "",
        f"humanoid3d, {'settings ' + ', '.join(args.set) if args.set else 'default settings'}, "
        f"{knowledge}; seeds {seeds[0]}-{seeds[-1]}"
        f"{' (tuning seeds)' if tuning else ''}, {DURATION_S:g} s each; tiles of "
        "0.25 x 0.5 m from x = 0.8 to 6.05 m (`uneven_course`).",
        "",
        "| no fall | clean | mean distance [m] | fell (seed: time) | not clean |",
        "|---|---|---|---|---|",
        f"| {len(seeds) - len(falls)}/{len(seeds)} | {len(seeds) - len(unclean)}/{len(seeds)} | "
        f"{sum(r['distance_m'] for r in results.values()) / len(seeds):.2f} | "
        + (", ".join(f"{s}: {results[s]['fall_time_s']:.2f} s" for s in falls) or "-")
        + f" | {', '.join(map(str, unclean)) or '-'} |",
        "",
        f"{len(seeds)} episodes in {wall_s / 60:.1f} min on {args.jobs} processes. "
        f"Command: `{command_line()}`.",
        "",
    ]
    blind = "_blind" if args.blind else ""
    suffix = "_tuning" if tuning else ""  # never over a reported file
    default = f"uneven_{args.amplitude * 100:g}cm_{args.speed:g}mps{blind}{suffix}.md"
    write_report(args.out or default, "\n".join(lines))


if __name__ == "__main__":
    main()
