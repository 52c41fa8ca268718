"""Recovery labels for Gait-Net by a rollout oracle, on the states the student visits
(issue 48, item 5: DAgger with labels that say which dt recovers).

Each episode: the student (``gaitnet``) walks flat ground at a drawn speed; one 0.2 s push
of a drawn force and direction acts at a drawn time after the settling time. At each step
start from just before the push to ``--window`` seconds after it,
:class:`~gaitnet_mpc.experiments.dt_rollouts.RolloutDt` tries every candidate dt in a
forked copy for ``--horizon`` seconds (later steps: the student's own choice) and keeps
a label by :meth:`~gaitnet_mpc.experiments.dt_rollouts.StepStart.label_dt_s`: the
student's own dt where it survives, else the surviving candidate nearest to it. Each
feature vector the student saw at that step start becomes a row with that label. Step
starts where every candidate fell give no row.

Draws come from ``--first-seed`` on (tuning seeds are >= 100). One JSON line per episode
in ``--out`` (resumable: seeds already there are skipped).

    .venv/bin/python benchmarks/rollout_labels.py --episodes 60 --workers 2 \
        --out data/rollout-labels/episodes.jsonl
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

SETTLE_S = 3.0
SPEEDS_MPS = (0.25, 0.5, 0.75)
FORCE_RANGE_N = (30.0, 110.0)


def draw(seed: int) -> dict[str, Any]:
    """The episode of ``seed``: speed, push time, force and direction."""
    rng = np.random.default_rng(seed)
    return {
        "seed": seed,
        "speed_mps": float(rng.choice(SPEEDS_MPS)),
        "t_push_s": round(SETTLE_S + float(rng.uniform(0.0, 0.3)), 3),
        "force_n": round(float(rng.uniform(*FORCE_RANGE_N)), 1),
        "angle_deg": round(float(rng.uniform(0.0, 360.0)), 1),
    }


def run_episode(
    item: tuple[dict[str, Any], float, float, str | None, tuple[str, ...]],
) -> dict[str, Any]:
    os.environ.setdefault("MUJOCO_GL", "egl")
    from gaitnet_mpc.control.dt_policies import make_dt_policy
    from gaitnet_mpc.experiments.dt_rollouts import RolloutDt, drive
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.runner.loop import EpisodeLoop
    from gaitnet_mpc.scenario import build_episode, make_scenario
    from gaitnet_mpc.sim.disturbances import Push

    d, window_s, horizon_s, weights, overrides = item
    t0 = time.perf_counter()
    a = math.radians(d["angle_deg"])
    f = d["force_n"]
    push = Push(d["t_push_s"], (f * math.cos(a), f * math.sin(a), 0.0), 0.2)
    duration = d["t_push_s"] + 0.2 + window_s + horizon_s
    scenario = make_scenario(
        controller="gaitnet",
        vx_mps=d["speed_mps"],
        duration_s=duration,
        pushes=(push,),
        gaitnet_weights=weights,
        overrides=list(overrides),
    )
    robot = load_robot("humanoid3d")
    inner = make_dt_policy(scenario.config.dt_policy, robot, scenario.config.sequential)
    lo, hi = d["t_push_s"] - 0.05, d["t_push_s"] + window_s  # window 0: no oracle
    if window_s <= 0:
        lo, hi = np.inf, -np.inf
    policy = RolloutDt(inner, lambda t: lo <= t <= hi, horizon_s)
    episode = build_episode(scenario, robot=robot, dt_policy=policy)
    loop = EpisodeLoop(episode.sim, episode.controller, scenario.command, duration)
    drive(loop, policy)
    steps = []
    for s in policy.steps:
        steps.append(
            {
                "t_s": round(s.t_s, 4),
                "own_dt_s": s.own_dt_s,
                "label_dt_s": s.label_dt_s(),
                "features": s.features,
                "outcomes": {str(k): v.__dict__ for k, v in s.outcomes.items()},
            }
        )
    return {
        **d,
        "fell": episode.sim.fall.fell,
        "fall_time_s": episode.sim.fall.t_s,
        "steps": steps,
        "wall_s": round(time.perf_counter() - t0, 1),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--episodes", type=int, default=60)
    ap.add_argument("--first-seed", type=int, default=100)
    ap.add_argument("--window", type=float, default=0.8, help="s after the push")
    ap.add_argument("--horizon", type=float, default=1.5, help="s of each rollout")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--weights", default=None, help="the student's Gait-Net weights")
    ap.add_argument(
        "--no-oracle", action="store_true", help="only the student: its falls, no labels"
    )
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a setting of the student (as gaitnet-mpc run --set)")  # fmt: skip
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    if args.first_seed < 100:
        sys.exit("--first-seed: tuning seeds are >= 100 (0-99 are for reporting)")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    done = set()
    if args.out.exists():
        done = {json.loads(line)["seed"] for line in args.out.read_text().splitlines() if line}
    sets = tuple(args.set)
    todo = [
        (draw(s), 0.0 if args.no_oracle else args.window, args.horizon, args.weights, sets)
        for s in range(args.first_seed, args.first_seed + args.episodes)
        if s not in done
    ]
    print(f"{len(todo)} episodes to run ({len(done)} done)", file=sys.stderr)
    fell = 0
    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(args.workers, maxtasksperchild=10) as pool:
        for i, rec in enumerate(pool.imap_unordered(run_episode, todo), 1):
            with args.out.open("a") as fh:  # one whole line per episode
                fh.write(json.dumps(rec) + "\n")
            fell += rec["fell"]
            labels = sum(s["label_dt_s"] is not None for s in rec["steps"])
            changed = sum(s["label_dt_s"] not in (None, s["own_dt_s"]) for s in rec["steps"])
            print(
                f"[{i}/{len(todo)}] seed {rec['seed']}: {rec['force_n']} N at "
                f"{rec['angle_deg']} deg, {'fell' if rec['fell'] else 'ok'}, "
                f"{len(rec['steps'])} step starts, {labels} labelled ({changed} corrected), "
                f"{rec['wall_s']} s",
                file=sys.stderr,
            )
    print(f"{fell} of {len(todo)} new episodes fell", file=sys.stderr)


if __name__ == "__main__":
    main()
