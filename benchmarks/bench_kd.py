"""Wall time of the implicit kino-dynamic sequential MPC over a recorded walking run.

Walks the humanoid in closed loop (``kd`` controller, flat ground, 0.5 m/s) and reports
the full sequential solve at step starts and the warm replans during steps (median, p99,
QPs per solve), timed without a profiler; then profiles a second, identical run to show
where the solve time goes (QP backend, QP assembly, reference update f_IK, reference
generation f_ref).

``--baseline REV`` also times the solver files as they were at git revision ``REV``
(:data:`SOLVER_FILES` taken from ``REV``, everything else from the working tree, so both
drive the very same controller), interleaved with the current code over ``--rounds``
runs each in fresh processes; each solve's time is its minimum over the rounds (the
closed loop is deterministic, so run ``i`` of both sides solves the same problems), and
the report says whether both closed loops were identical. Run::

    .venv/bin/python benchmarks/bench_kd.py [--seconds 2] [--baseline REV --rounds 3]
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import pstats
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from gaitnet_mpc.experiments.bench import profile_parts
from gaitnet_mpc.command import Command
from gaitnet_mpc.control.kd_walk import KDWalkController
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course
from machine import machine_info

ROOT = Path(__file__).resolve().parent.parent
#: Files whose state at ``--baseline REV`` is compared with the working tree.
#: A revision before the layout of issue 19 (``e85d4fc``) imports modules that no longer
#: exist and cannot be compared.
SOLVER_FILES = (
    "src/gaitnet_mpc/mpc/*.py",
    "src/gaitnet_mpc/mpc/qp/*.py",
    "src/gaitnet_mpc/kinematics/*.py",
    "src/gaitnet_mpc/gait/timing.py",
)


def closed_loop(seconds: float, vx_mps: float, profiler: cProfile.Profile | None = None) -> dict:
    """Run the kd walk; per-solve times [ms], full-solve flags, QP counts and end state."""
    robot = load_robot("humanoid3d")
    course = load_course("flat")
    sim = Simulator(robot, course)
    command = Command(vx_mps=vx_mps)
    ctrl = KDWalkController(robot, TerrainView(course), command)
    ctrl.reset(sim.state())
    if profiler is not None:
        profiler.enable()
    for _ in range(round(seconds / sim.config.timestep_s)):
        sim.step(ctrl.compute(sim.state()))
        if sim.fall.fell:
            break
    if profiler is not None:
        profiler.disable()
    stats = ctrl.mpc_stats
    state = sim.state()
    return {
        "ms": [1e3 * t for t in stats.solve_time_s],
        "full": [bool(f) for f in stats.full_solve],
        "qps": [int(n) for n in stats.qps_per_solve],
        "converged": [bool(c) for c in stats.converged],
        "end_state": [*map(float, state.qpos), *map(float, state.qvel)],
        "t_s": float(sim.time_s),
        "fell": bool(sim.fall.fell),
        "replan_period_ms": 1e3 * ctrl.config.replan_period_s,
    }


def solve_rows(runs: list[dict]) -> tuple[dict, np.ndarray]:
    """Per-solve minimum over runs of the same closed loop, and the first run."""
    ms = np.min([r["ms"] for r in runs], axis=0)
    return runs[0], ms


def table(run: dict, ms: np.ndarray) -> list[str]:
    full = np.asarray(run["full"])
    qps = np.asarray(run["qps"])
    conv = np.asarray(run["converged"])
    lines = [
        "| solve | count | median ms | p99 ms | QPs per solve | hit j_max |",
        "|---|---|---|---|---|---|",
    ]
    for name, mask in (("full", full), ("replan", ~full)):
        if mask.any():
            lines.append(
                f"| {name} | {mask.sum()} | {np.median(ms[mask]):.1f} | "
                f"{np.percentile(ms[mask], 99):.1f} | {qps[mask].mean():.1f} | "
                f"{100 * (~conv[mask]).mean():.0f} % |"
            )
    return lines


def baseline_tree(rev: str, folder: Path) -> Path:
    """A copy of the package with :data:`SOLVER_FILES` as they were at ``rev``."""
    src = folder / "src"
    shutil.copytree(ROOT / "src" / "gaitnet_mpc", src / "gaitnet_mpc")
    for pattern in SOLVER_FILES:
        for path in ROOT.glob(pattern):
            rel = path.relative_to(ROOT).as_posix()
            old = subprocess.run(
                ["git", "-C", str(ROOT), "show", f"{rev}:{rel}"], capture_output=True, text=True
            )
            target = src / Path(rel).relative_to("src")
            if old.returncode == 0:
                target.write_text(old.stdout)
            else:  # a file added since rev
                target.unlink()
    return src


def timed_runs(args: argparse.Namespace, pythonpath: Path | None, out: Path) -> list[dict]:
    """One timed closed loop, in a fresh process, of the package under ``pythonpath``
    (None: this tree's ``src``)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(pythonpath if pythonpath is not None else ROOT / "src")
    cmd = [sys.executable, __file__, "--timing-json", str(out)]
    cmd += ["--seconds", str(args.seconds), "--vx", str(args.vx)]
    subprocess.run(cmd, env=env, check=True)
    return [json.loads(out.read_text())]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--vx", type=float, default=0.5)
    parser.add_argument("--baseline", help="git revision of the solver files to compare with")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--timing-json", help=argparse.SUPPRESS)  # internal: one timed run
    args = parser.parse_args()
    if args.timing_json:
        Path(args.timing_json).write_text(json.dumps(closed_loop(args.seconds, args.vx)))
        return

    compare: list[str] = []
    if args.baseline:
        with tempfile.TemporaryDirectory() as tmp:
            base_src = baseline_tree(args.baseline, Path(tmp))
            base_runs: list[dict] = []
            new_runs: list[dict] = []
            for _ in range(args.rounds):  # interleaved: drift of the machine load hits both
                base_runs += timed_runs(args, base_src, Path(tmp) / "base.json")
                new_runs += timed_runs(args, None, Path(tmp) / "new.json")
        base, base_ms = solve_rows(base_runs)
        run, ms = solve_rows(new_runs)
        same = base["qps"] == run["qps"] and base["full"] == run["full"]
        state_diff = float(np.max(np.abs(np.subtract(base["end_state"], run["end_state"]))))
        compare = [
            f"Before/after, measured in one interleaved run (`--baseline {args.baseline} "
            f"--rounds {args.rounds}`: {args.rounds} closed loops each, alternating, fresh "
            "processes; per solve the minimum over the rounds):",
            "",
            "| solve | before median ms | after median ms | speed-up |",
            "|---|---|---|---|",
        ]
        full = np.asarray(run["full"])
        for name, mask in (("full", full), ("replan", ~full), ("all", np.ones_like(full))):
            if mask.any():
                b, a = np.median(base_ms[mask]), np.median(ms[mask])
                compare.append(f"| {name} | {b:.1f} | {a:.1f} | {b / a:.2f}x |")
        compare += [
            "",
            f"Same QPs per solve in both: {'yes' if same else 'NO'}; closed-loop end state "
            f"max difference {state_diff:.1e} (0 = bitwise identical trajectories).",
            "",
        ]
    else:
        run, ms = solve_rows([closed_loop(args.seconds, args.vx)])

    profiler = cProfile.Profile()
    prof_run = closed_loop(args.seconds, args.vx, profiler)
    stats = pstats.Stats(profiler)
    total_s = 1e-3 * sum(prof_run["ms"])
    rows = [
        f"| {label} | {sec:.2f} | {100 * share:.0f} % |"
        for label, sec, share in profile_parts(stats, total_s)
    ]
    lines = [
        "# Implicit kino-dynamic sequential MPC: solve times",
        "",
        machine_info(("numpy", "pin", "piqp", "mujoco")),
        "",
        f"Closed loop, humanoid3d, flat, vx = {args.vx} m/s, {run['t_s']:.2f} s simulated"
        f"{' (FELL)' if run['fell'] else ''}; replan every {run['replan_period_ms']:.0f} ms. "
        "Wall time of `SequentialKDMPC.solve` without a profiler, Python overhead included; "
        "the machine is shared, so compare only numbers taken in one run.",
        "",
        *table(run, ms),
        "",
        *compare,
        "Where the solve time goes (second run under cProfile, which inflates Python-heavy "
        f"parts; cumulative over all solves, {total_s:.2f} s of solve time):",
        "",
        "| part | seconds | share of solve time |",
        "|---|---|---|",
        *rows,
        "",
    ]
    report = "\n".join(lines)
    out = Path(__file__).parent / "results" / "kd_solve.md"
    out.write_text(report)
    print(report)


if __name__ == "__main__":
    main()
