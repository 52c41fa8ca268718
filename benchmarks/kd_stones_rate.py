"""How often does ``kd`` cross ``stepping-stones`` (and ``gap``)? Success rates.

One run says little: the stepping-stone outcome flips with 5 ms of dt or 1e-5 m of initial
state. Two measures, each over a set of episodes (humanoid3d, 0.75 m/s, 8 s, fixed dt):

* ``built-in``: the built-in layout, ``--runs`` episodes whose only difference is the
  initial base x, shifted by ``i * 1e-5`` m (i = 1..N). The lateral return time (0.7 s)
  and the CI test's dt (0.05 s) were chosen on this course, so these rows are not a
  fair estimate of them;
* ``seeded``: ``--seeds`` randomised layouts (``load_course(name, seed=s)``, s = 0..N-1) that
  no constant was chosen on: the honest rate.

A run is clean when it does not fall, has no foothold violation and no leg-leg contact.
Writes ``benchmarks/results/kd_stones_rate.md``. Run::

    .venv/bin/python benchmarks/kd_stones_rate.py [--runs 10] [--seeds 20] \
        [--dts 0.045,0.05,0.055] [--courses stepping-stones,gap]
"""

from __future__ import annotations

import argparse
import time

from machine import clean_run, machine_info, run_pool, write_report

#: Configurations: name -> multi-step preview on (the gap is run without it only).
CONFIGS = {
    "one-step preview (default)": False,
    "--preview": True,
}
DURATION_S = 8.0
STEP_M = 1e-5

Job = tuple[str, str, int | None, float, int]  # config, course, seed, dt [s], i


def run(job: Job) -> dict:
    """One episode of ``job`` = (config name, course, seed or None, fixed dt, i); the
    initial base x is shifted by ``i * STEP_M``."""
    import mujoco

    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.kd_walk import KDWalkController
    from gaitnet_mpc.control.kd_walk_config import KDWalkConfig, preview_walk_config, walk_terrain
    from gaitnet_mpc.mpc.sequential import FixedDt
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.sim.simulator import Simulator
    from gaitnet_mpc.terrain import load_course

    name, course_name, seed, dt, i = job
    config = preview_walk_config() if CONFIGS[name] else KDWalkConfig()
    robot, command = load_robot("humanoid3d"), Command(0.75)
    course = load_course(course_name, **({} if seed is None else {"seed": seed}))
    ctrl = KDWalkController(
        robot, walk_terrain(course, config), command, dt_policy=FixedDt(dt), config=config
    )
    sim = Simulator(robot, course)
    sim.data.qpos[0] += i * STEP_M
    mujoco.mj_forward(sim.model, sim.data)
    s = run_episode(sim, ctrl, command, DURATION_S, progress=False)
    contacts = int(s.get("self_collisions") or 0)
    return {
        "clean": clean_run(s),
        "fell": s["fell"],
        "distance_m": s["distance_m"],
        "violations": s["foothold_violations"],
        "self_collisions": contacts,
    }


def _jobs(args: argparse.Namespace, dts: dict[str, list[float]]) -> list[Job]:
    jobs: list[Job] = []
    for name, preview in CONFIGS.items():
        for course in dts:
            if course == "gap" and preview:
                continue  # the gap is the one-step preview's course
            for dt in dts[course]:
                if course == "stepping-stones":
                    jobs += [(name, course, None, dt, i) for i in range(1, args.runs + 1)]
                jobs += [(name, course, s, dt, 0) for s in range(args.seeds)]
    return jobs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10, help="perturbed built-in runs per cell")
    parser.add_argument("--seeds", type=int, default=20, help="seeded layouts per cell")
    parser.add_argument("--dts", default="0.05", help="fixed dts on the stepping stones [s]")
    parser.add_argument("--gap-dts", default="0.045,0.055,0.065", help="fixed dts on the gap")
    parser.add_argument("--courses", default="stepping-stones,gap")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    courses = args.courses.split(",")
    dts = {
        c: [float(x) for x in (args.gap_dts if c == "gap" else args.dts).split(",")]
        for c in courses
    }
    jobs = _jobs(args, dts)
    t0 = time.perf_counter()
    results: dict[Job, dict] = run_pool(run, jobs, args.jobs)
    wall_s = time.perf_counter() - t0
    lines = [
        "# kd on stepping-stones and gap: success rates",
        "",
        machine_info(("numpy", "mujoco", "pin", "piqp", "scipy")),
        "",
        f"humanoid3d, 0.75 m/s, {DURATION_S:.0f} s, fixed dt, self-collision on. `built-in`: "
        f"{args.runs} runs of the built-in layout that differ only by the initial base x "
        f"(+i * {STEP_M:g} m); the lateral return time and the CI test's dt were chosen on "
        f"these. `seeded`: {args.seeds} randomised layouts (seeds 0-{args.seeds - 1}), on "
        "which nothing was chosen. Clean: no fall, no foothold violation, no leg-leg contact.",
        "",
        "| configuration | course | layouts | dt [s] | clean | no fall | mean distance [m] "
        "| violations | runs with leg-leg contact |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name in CONFIGS:
        for course in courses:
            for kind in ("built-in", "seeded"):
                for dt in dts[course]:
                    rs = [
                        r
                        for (n, c, seed, d, _), r in results.items()
                        if n == name
                        and c == course
                        and d == dt
                        and (seed is None) == (kind == "built-in")
                    ]
                    if not rs:
                        continue
                    k = len(rs)
                    lines.append(
                        f"| {name} | {course} | {kind} | {dt:g} | "
                        f"{sum(r['clean'] for r in rs)}/{k} | "
                        f"{sum(not r['fell'] for r in rs)}/{k} | "
                        f"{sum(r['distance_m'] for r in rs) / k:.2f} | "
                        f"{sum(r['violations'] for r in rs)} | "
                        f"{sum(r['self_collisions'] > 0 for r in rs)}/{k} |"
                    )
    lines += [
        "",
        f"{len(jobs)} episodes in {wall_s / 60:.1f} min on {args.jobs} processes. Command: "
        f"`.venv/bin/python benchmarks/kd_stones_rate.py --runs {args.runs} --seeds "
        f"{args.seeds} --dts {args.dts} --gap-dts {args.gap_dts} --courses {args.courses}`.",
        "",
    ]
    write_report("kd_stones_rate.md", "\n".join(lines))


if __name__ == "__main__":
    main()
