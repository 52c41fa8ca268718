"""How often does ``kd`` cross ``stepping-stones``? Success rate under tiny perturbations.

The stepping-stone outcome of one run flips with 5 ms of dt or 1e-5 m of initial state
(docs/kd_lateral/README.md), so one run says little. For each configuration and fixed dt
this runs ``--runs`` episodes (humanoid3d, 0.75 m/s, 8 s) whose only difference is the
initial base x, shifted by ``i * 1e-5`` m (i = 1..N), and counts clean crossings: no fall
and no foothold violation. Writes ``benchmarks/results/kd_stones_rate.md``. Run::

    .venv/bin/python benchmarks/kd_stones_rate.py [--runs 10] [--dts 0.05,0.055,0.06]
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from gaitnet_mpc.control.kd_walk import KDWalkConfig

sys.path.insert(0, str(Path(__file__).parent))
from machine import machine_info

CONFIGS = {"one-step preview (default)": False, "--preview": True}
DURATION_S = 8.0
STEP_M = 1e-5


def run(job: tuple[KDWalkConfig, float, int]) -> dict:
    """One episode: ``(KDWalkConfig, fixed dt [s], i)``, initial base x shifted by i * STEP_M."""
    import mujoco

    from gaitnet_mpc.control.kd_walk import KDWalkController, walk_terrain
    from gaitnet_mpc.mpc.sequential import FixedDt
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.sim.episode import Command, run_episode
    from gaitnet_mpc.sim.simulator import Simulator
    from gaitnet_mpc.terrain import load_course

    config, dt, i = job
    robot, course, command = load_robot("humanoid3d"), load_course("stepping-stones"), Command(0.75)
    ctrl = KDWalkController(
        robot, walk_terrain(course, config), command, dt_policy=FixedDt(dt), config=config
    )
    sim = Simulator(robot, course)
    sim.data.qpos[0] += i * STEP_M
    mujoco.mj_forward(sim.model, sim.data)
    s = run_episode(sim, ctrl, command, DURATION_S, progress=False)
    return {
        "clean": not s["fell"] and s["foothold_violations"] == 0,
        "fell": s["fell"],
        "distance_m": s["distance_m"],
        "violations": s["foothold_violations"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10)
    parser.add_argument("--dts", default="0.05,0.055,0.06")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    from gaitnet_mpc.control.kd_walk import KDWalkConfig, preview_walk_config

    dts = [float(s) for s in args.dts.split(",")]
    configs = {True: preview_walk_config(), False: KDWalkConfig()}
    keys = [(p, dt, i) for p in CONFIGS.values() for dt in dts for i in range(1, args.runs + 1)]
    jobs = [(configs[p], dt, i) for p, dt, i in keys]
    with ProcessPoolExecutor(args.jobs) as pool:
        results = dict(zip(keys, pool.map(run, jobs), strict=True))
    lines = [
        "# kd on stepping-stones: success rate",
        "",
        machine_info(("numpy", "mujoco", "pin", "piqp", "scipy")),
        "",
        f"humanoid3d, 0.75 m/s, {DURATION_S:.0f} s, fixed dt; {args.runs} runs per cell that "
        f"differ only by the initial base x (+i * {STEP_M:g} m). Clean: no fall and no "
        "foothold violation.",
        "",
        "| configuration | dt [s] | clean crossings | no fall | mean distance [m] | violations |",
        "|---|---|---|---|---|---|",
    ]
    for name, preview in CONFIGS.items():
        for dt in dts:
            rs = [results[(preview, dt, i)] for i in range(1, args.runs + 1)]
            lines.append(
                f"| {name} | {dt:g} | {sum(r['clean'] for r in rs)}/{len(rs)} | "
                f"{sum(not r['fell'] for r in rs)}/{len(rs)} | "
                f"{sum(r['distance_m'] for r in rs) / len(rs):.2f} | "
                f"{sum(r['violations'] for r in rs)} |"
            )
    lines += ["", f"Command: `.venv/bin/python benchmarks/kd_stones_rate.py --runs {args.runs} "
              f"--dts {args.dts}`.", ""]  # fmt: skip
    report = "\n".join(lines)
    (Path(__file__).parent / "results" / "kd_stones_rate.md").write_text(report)
    print(report)


if __name__ == "__main__":
    main()
