"""Would another step duration have saved the robot? A what-if trace of one pushed episode.

The episode runs as the push sweep runs it (0.2 s push at the trunk CoM, 0.5 m/s, the
controller's settings). At each step start in a window around the push, the process forks
once per candidate dt: in each child that one step takes the candidate dt (every later
step is the controller's own choice again), and the child runs to the episode's end and
reports whether it fell. The parent takes the controller's own dt and goes on. So each
row answers: had this one step lasted ``5 dt`` instead, would the episode have survived?

    .venv/bin/python benchmarks/dt_whatif.py --controller gaitnet \
        --case right:0.5:55 --case left:0:55 --out benchmarks/results/dt_whatif.md

``--case DIRECTION:PHASE:FORCE`` as the sweep names them (phase in the nominal step).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

from gaitnet_mpc.control.dt_policies import make_dt_policy
from gaitnet_mpc.experiments.dt_rollouts import CANDIDATES_S, RolloutDt, drive
from gaitnet_mpc.experiments.push_timing import push_time_s
from gaitnet_mpc.experiments.sweep_cases import DIRECTIONS, PUSH_DURATION_S, parse_controller
from gaitnet_mpc.results.io import write_atomic
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.runner.loop import EpisodeLoop
from gaitnet_mpc.scenario import build_episode, make_scenario
from gaitnet_mpc.sim.disturbances import Push


def run_case(controller: str, direction: str, phase: float, force_n: float, speed: float) -> dict:
    name, dt_s, preset, weights = parse_controller(controller)
    t_push = push_time_s(dt_s, 3.0, phase)
    duration = t_push + PUSH_DURATION_S + 3.0
    angle = math.radians(DIRECTIONS[direction])
    push = Push(t_push, (force_n * math.cos(angle), force_n * math.sin(angle), 0.0), 0.2)
    scenario = make_scenario(
        controller=name, preset=preset, vx_mps=speed, duration_s=duration, pushes=(push,),
        dt_s=dt_s, gaitnet_weights=weights,
    )  # fmt: skip
    robot = load_robot("humanoid3d")
    config = scenario.config
    inner = make_dt_policy(config.dt_policy, robot, config.sequential)
    lo, hi = t_push - 0.05, t_push + 0.6
    policy = RolloutDt(inner, lambda t: lo <= t <= hi, horizon_s=None)  # to the episode's end
    episode = build_episode(scenario, robot=robot, dt_policy=policy)
    loop = EpisodeLoop(episode.sim, episode.controller, scenario.command, duration)
    drive(loop, policy)
    fallback = {d.t_s: d.fallback for d in getattr(inner, "decisions", [])}  # Gait-Net's record
    rows = [
        {
            "t_s": step.t_s,
            "own_dt_s": step.own_dt_s,
            "fallback": fallback.get(step.t_s),
            "outcomes": {dt: o.__dict__ for dt, o in step.outcomes.items()},
        }
        for step in policy.steps
    ]
    sim = episode.sim
    return {"direction": direction, "phase": phase, "force_n": force_n, "t_push_s": t_push,
            "own": {"fell": sim.fall.fell, "fall_time_s": sim.fall.t_s}, "rows": rows}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--controller", default="gaitnet")
    ap.add_argument("--case", action="append", required=True, help="DIRECTION:PHASE:FORCE")
    ap.add_argument("--speed", type=float, default=0.5)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    results = []
    t0 = time.perf_counter()
    for spec in args.case:
        d, p, f = spec.split(":")
        r = run_case(args.controller, d, float(p), float(f), args.speed)
        results.append(r)
        print(json.dumps(r), file=sys.stderr)
    lines = [
        "# What-if step durations under a push",
        "",
        f"CPU: {platform.machine()}, cores: {os.cpu_count()}, Python {platform.python_version()}, "
        f"numpy {np.__version__}, mujoco {mujoco.__version__}.",
        "",
        f"Command: `benchmarks/dt_whatif.py --controller {args.controller} "
        + " ".join(f"--case {c}" for c in args.case)
        + f"` ({time.perf_counter() - t0:.0f} s). Each row: a step start near the push; "
        "`own`: the controller's dt there; a candidate column: `ok` if forcing that one "
        "step's dt (later steps the controller's own) survives to the episode's end, else "
        "the fall time [s].",
        "",
        "| case | own outcome | step start [s] | own dt [ms] | "
        + " | ".join(f"{dt * 1e3:.0f}" for dt in CANDIDATES_S)
        + " |",
        "|---|---|---|---|" + "---|" * len(CANDIDATES_S),
    ]
    for r in results:
        own = "survived" if not r["own"]["fell"] else f"fell {r['own']['fall_time_s']:.2f} s"
        case = f"{r['direction']} p{r['phase']:g} {r['force_n']:g} N (push {r['t_push_s']:.3f} s)"
        for row in r["rows"]:
            cells = []
            for dt in CANDIDATES_S:
                o = row["outcomes"][dt]
                cells.append("ok" if not o.get("fell") else f"{o['fall_time_s']:.2f}")
            own_dt = row.get("own_dt_s")
            own_ms = f"{own_dt * 1e3:.1f}" if own_dt is not None else "-"
            if row.get("fallback"):
                own_ms += f" ({row['fallback']} fallback)"
            lines.append(
                f"| {case} | {own} | {row['t_s']:.3f} | {own_ms} | " + " | ".join(cells) + " |"
            )
    write_atomic(args.out, "\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
