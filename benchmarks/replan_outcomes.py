"""What a cheaper replan costs in walking: closed-loop outcomes of timing cases side by side.

Issue 17 asks that a real-time-iteration replan (one QP per replan within a step, full
convergence only at step starts: ``--set replan_j_max=1``) be measured in tracking and
robustness before it becomes a default. Each case (``LABEL=CONTROLLER[:KEY=VALUE,...]``,
as ``gaitnet-mpc bench --case``) walks humanoid3d at 0.75 m/s:

* ``flat``: 20 s; fall, distance, lateral CoM drift at the end;
* ``gap`` and ``stepping-stones``: the seeded layouts ``--seeds`` (default 0-19), 8 s each,
  with the paper's one-step preview; clean = no fall, no foothold violation, no leg-leg
  contact (the stones with the one-step preview are hard for every controller here);
* ``stones-preview``: the built-in stepping stones with the multi-step preview, 15 s;
* ``push``: at 0.5 m/s on flat, a 0.2 s forward or leftward push at t = 4 s of each force in
  ``--push-forces`` N, survived = no fall within 3 s after it.

No constant was chosen on these runs. Writes ``benchmarks/results/replan_outcomes.md``
(``--out``: another name there).
Run::

    MUJOCO_GL=egl .venv/bin/python benchmarks/replan_outcomes.py [--jobs 2] [--seeds 20]
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time

from gaitnet_mpc.experiments.bench import parse_case
from machine import clean_run, machine_info, run_pool, write_report

SEEDED_S = 8.0
FLAT_S = 20.0
STONES_PREVIEW_S = 15.0
VX_MPS = 0.75
PUSH_VX_MPS = 0.5
PUSH_T_S, PUSH_DUR_S, AFTER_S = 4.0, 0.2, 3.0
DEFAULT_CASES = (
    "kd=kd",
    "kd RTI=kd:replan_j_max=1",
    "gaitnet=gaitnet",
    "gaitnet RTI=gaitnet:replan_j_max=1",
)

Job = tuple[str, str, str, float]  # case text, course kind, seed or push direction, force


def run(job: Job) -> dict:
    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.registry import (
        ControllerContext,
        controller_config,
        make_controller,
    )
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.sim.disturbances import Push
    from gaitnet_mpc.sim.simulator import SimConfig, Simulator
    from gaitnet_mpc.terrain import load_course

    case, kind, arg, force_n = job
    parsed = parse_case(case)
    controller, overrides = parsed.controller, parsed.overrides
    robot = load_robot("humanoid3d")
    pushes: tuple = ()
    vx, duration, preview = VX_MPS, SEEDED_S, False
    if kind == "flat":
        course, duration = load_course("flat"), FLAT_S
    elif kind == "stones-preview":
        course, duration, preview = load_course("stepping-stones"), STONES_PREVIEW_S, True
    elif kind == "push":
        course, vx, duration = load_course("flat"), PUSH_VX_MPS, PUSH_T_S + PUSH_DUR_S + AFTER_S
        fx, fy = (force_n, 0.0) if arg == "fwd" else (0.0, force_n)
        pushes = (Push.parse(f"t={PUSH_T_S},fx={fx},fy={fy},dur={PUSH_DUR_S}"),)
    else:
        course = load_course(kind, seed=int(arg))
    command = Command(vx)
    config = controller_config(controller, planar=False, preview=preview, overrides=list(overrides))
    ctrl = make_controller(controller, ControllerContext(robot, course, command, config=config))
    sim = Simulator(robot, course, SimConfig(pushes=pushes))
    s = run_episode(sim, ctrl, command, duration, progress=False)
    mpc = s.get("mpc") or {}
    return {
        "clean": clean_run(s),
        "fell": s["fell"],
        "fall_time_s": s["fall_time_s"],
        "distance_m": s["distance_m"],
        "violations": s["foothold_violations"],
        "lateral_m": abs(float(s["lateral_drift_m"])),
        "replan_ms": mpc.get("replan_ms_median"),
        "full_ms": mpc.get("full_ms_median"),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", action="append", default=None, help="LABEL=CTRL[:K=V,...]")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--courses", default="gap,stepping-stones")
    parser.add_argument("--push-forces", default="20,30,40,60")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default="replan_outcomes.md", help="file in results/")
    args = parser.parse_args()
    cases = args.case or list(DEFAULT_CASES)
    courses = [c for c in args.courses.split(",") if c]
    forces = [float(f) for f in args.push_forces.split(",") if f]
    jobs: list[Job] = []
    for case in cases:
        jobs += [(case, "flat", "", 0.0), (case, "stones-preview", "", 0.0)]
        jobs += [(case, c, str(s), 0.0) for c in courses for s in range(args.seeds)]
        jobs += [(case, "push", d, f) for d in ("fwd", "left") for f in forces]
    t0 = time.perf_counter()
    results: dict[Job, dict] = run_pool(run, jobs, args.jobs)
    wall_s = time.perf_counter() - t0

    def of(case: str, kind: str) -> list[dict]:
        return [r for (c, k, _, _), r in results.items() if c == case and k == kind]

    lines = [
        "# Replan modes: closed-loop outcomes side by side",
        "",
        machine_info(("numpy", "mujoco", "pin", "piqp")),
        "",
        f"humanoid3d, {VX_MPS} m/s, self-collision on. Flat {FLAT_S:.0f} s; seeded gap and "
        f"stepping-stones layouts 0-{args.seeds - 1}, {SEEDED_S:.0f} s each, one-step "
        f"preview (clean = no fall, no foothold violation, no leg-leg contact); built-in "
        f"stepping stones with the multi-step preview (`--preview`), {STONES_PREVIEW_S:.0f} s; "
        f"pushes at {PUSH_VX_MPS} m/s on flat, {PUSH_DUR_S} s at t = {PUSH_T_S} s, survived = "
        f"no fall in the {AFTER_S:.0f} s after. Solve times are medians of the run summaries "
        "(taken beside other jobs; `gaitnet-mpc bench` measures them properly).",
        "",
        "| case | flat 20 s | replan / full solve ms (flat) | "
        + " | ".join(f"{c} clean" for c in courses)
        + " | stones --preview 15 s | largest push survived fwd / left [N] |",
        "|---|---|---|" + "---|" * len(courses) + "---|---|",
    ]
    for case in cases:
        label = parse_case(case).label
        flat = of(case, "flat")[0]
        flat_text = (
            f"FELL at {flat['fall_time_s']:.2f} s" if flat["fell"] else "no fall"
        ) + f", {flat['distance_m']:.2f} m, drift {flat['lateral_m']:.2f} m"
        ms = f"{flat['replan_ms'] or float('nan'):.1f} / {flat['full_ms'] or float('nan'):.1f}"
        seeded = []
        for c in courses:
            rs = of(case, c)
            seeded.append(
                f"{sum(r['clean'] for r in rs)}/{len(rs)} "
                f"({sum(not r['fell'] for r in rs)} no fall)"
            )
        sp = of(case, "stones-preview")[0]
        sp_text = (
            f"FELL at {sp['fall_time_s']:.2f} s" if sp["fell"] else "no fall"
        ) + f", {sp['violations']} violations, {sp['distance_m']:.2f} m"
        best = []
        for d in ("fwd", "left"):
            ok = [
                f
                for (c, k, dd, f), r in results.items()
                if c == case and k == "push" and dd == d and not r["fell"]
            ]
            best.append(f"{max(ok):g}" if ok else "none")
        lines.append(
            f"| {label} | {flat_text} | {ms} | {' | '.join(seeded)} | {sp_text} | "
            f"{' / '.join(best)} |"
        )
    command = shlex.join(["benchmarks/replan_outcomes.py", *sys.argv[1:]])
    lines += [
        "",
        f"Pushes tried: {', '.join(f'{f:g}' for f in forces)} N (each run separately; "
        "'largest' is the largest survived of those).",
        "",
        f"Cases: {'; '.join(f'`{c}`' for c in cases)}. {len(jobs)} episodes in "
        f"{wall_s / 60:.1f} min on {args.jobs} processes. Command: "
        f"`MUJOCO_GL=egl .venv/bin/python {command}`",
        "",
    ]
    write_report(args.out, "\n".join(lines))


if __name__ == "__main__":
    main()
