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
from typing import Any

import mujoco
import numpy as np

from gaitnet_mpc.control.dt_policies import make_dt_policy
from gaitnet_mpc.experiments.sweep_cases import (
    DIRECTIONS,
    PUSH_DURATION_S,
    parse_controller,
    push_time_s,
)
from gaitnet_mpc.mpc.sequential import KDProblem
from gaitnet_mpc.results.io import write_atomic
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.runner.loop import EpisodeLoop
from gaitnet_mpc.scenario import build_episode, make_scenario
from gaitnet_mpc.sim.disturbances import Push

CANDIDATES_S = (0.035, 0.04, 0.045, 0.05, 0.055, 0.06, 0.065, 0.07)


class WhatIfDt:
    """A dt policy around ``inner``: at step starts in ``window_s`` it forks one child per
    candidate dt, each child forced to that dt for this step; ``outcomes`` collects, per
    step start, the candidates' outcomes (parent only)."""

    def __init__(self, inner: Any, window_s: tuple[float, float]) -> None:
        self.inner = inner
        self.window_s = window_s
        self.forced_dt_s: float | None = None
        self.child = False
        self._problem: KDProblem | None = None
        self._forced_problem: KDProblem | None = None
        self.rows: list[dict[str, Any]] = []
        self.pipe_fd = -1

    @property
    def nominal_dt_s(self) -> float:
        return float(self.inner.nominal_dt_s)

    def __call__(self, problem: KDProblem, iterate: Any, dt_s: float) -> float:
        if problem is self._forced_problem:  # a child, at the step it forces
            assert self.forced_dt_s is not None
            return self.forced_dt_s
        assert problem.state is not None
        t = problem.state.state.t_s
        if problem is not self._problem:  # a new step start
            self._problem = problem
            lo, hi = self.window_s
            if not self.child and lo <= t <= hi:
                row: dict[str, Any] = {"t_s": t, "outcomes": {}}
                for dt in CANDIDATES_S:
                    out = self._fork(problem, dt)
                    if out is None:  # this process is the child forced to dt
                        return dt
                    row["outcomes"][dt] = out
                self.rows.append(row)
        dt = float(self.inner(problem, iterate, dt_s))
        if self.rows and self.rows[-1]["t_s"] == t:
            self.rows[-1]["own_dt_s"] = dt  # the last iteration's dt is the step's
            decisions = getattr(self.inner, "decisions", None)  # Gait-Net's record
            self.rows[-1]["fallback"] = decisions[-1].fallback if decisions else None
        return dt

    def _fork(self, problem: KDProblem, dt: float) -> dict[str, Any] | None:
        """The outcome of the child forced to ``dt``; None in that child."""
        read_fd, write_fd = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(read_fd)
            self.child, self.forced_dt_s, self._forced_problem = True, dt, problem
            self.pipe_fd = write_fd
            return None
        os.close(write_fd)
        with os.fdopen(read_fd, "rb") as fh:
            data = fh.read()
        os.waitpid(pid, 0)
        return json.loads(data) if data else {"fell": True, "fall_time_s": float("nan")}


def run_case(controller: str, direction: str, phase: float, force_n: float, speed: float) -> dict:
    name, dt_s, preset, weights = parse_controller(controller)
    t_push = push_time_s(controller, 3.0, phase)
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
    policy = WhatIfDt(inner, (t_push - 0.05, t_push + 0.6))
    episode = build_episode(scenario, robot=robot, dt_policy=policy)
    loop = EpisodeLoop(episode.sim, episode.controller, scenario.command, duration)

    def outcome() -> dict[str, Any]:
        s = episode.sim
        return {"fell": s.fall.fell, "fall_time_s": s.fall.t_s}

    while not loop.done:
        loop.tick()
    out = outcome()
    if policy.child:
        with os.fdopen(policy.pipe_fd, "wb") as fh:
            fh.write(json.dumps(out).encode())
        os._exit(0)
    return {"direction": direction, "phase": phase, "force_n": force_n, "t_push_s": t_push,
            "own": out, "rows": policy.rows}  # fmt: skip


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
