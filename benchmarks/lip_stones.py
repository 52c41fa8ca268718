"""Can a fixed step time cross ``stepping-stones``? The preview MILP over the whole course.

For each fixed dt (step time 5 dt), start from a steady LIP gait at the commanded speed on
the start platform, with the stance foot at one of ``--phases`` positions over one stride,
and plan every step to the final platform at once: ``gait/preview.py`` (sagittal LIP with
a CoP offset, lateral LIP with a line foot, a binary patch choice per step; scipy ``milp``)
with a horizon covering the course instead of the controller's 6 steps. Counts the start
phases with a plan that holds every bound (no slack) and reports the CoM speed range of
the best one (least deviation from the command) over the stones, within-step LIP
oscillation included. This is the feasibility argument of
``docs/design/footstep_preview.md``. Writes ``benchmarks/results/lip_stones.md``. Run::

    .venv/bin/python benchmarks/lip_stones.py [--dts 0.04,0.045,0.055,0.065,0.07] \
        [--cop 0.04] [--seed S] [--jobs 2]
"""

from __future__ import annotations

import argparse
import math
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from gaitnet_mpc.gait.preview import PreviewConfig, plan_preview
from gaitnet_mpc.geometry import GRAVITY_MPS2
from gaitnet_mpc.results.io import write_atomic
from gaitnet_mpc.terrain import load_course
from machine import machine_info

STAGES_PER_STEP = 5  # h', as the gait schedule
X_MARGIN_M = 0.08  # KDWalkConfig.foothold_margin_m, as `kd --preview`


@dataclass(frozen=True)
class Case:
    """One fixed dt over all start phases."""

    dt_s: float
    v_cmd_mps: float
    z_c_m: float
    cop_m: float
    phases: int
    seed: int | None


def run(case: Case) -> dict:
    """Plans of ``case`` from each start phase: how many exist, the best one's speed range."""
    course = load_course("stepping-stones", **({} if case.seed is None else {"seed": case.seed}))
    stones_x = (course.patches[0].x_max, course.patches[-1].x_min)  # start and final platform
    w = math.sqrt(GRAVITY_MPS2 / case.z_c_m)
    step_s = STAGES_PER_STEP * case.dt_s
    advance_m = case.v_cmd_mps * step_s
    # Steady symmetric LIP step: x - p = -L/2 at its start, v0 from periodicity.
    v0 = w * math.sinh(w * step_s) * (-advance_m / 2) / (1 - math.cosh(w * step_s))
    n_steps = math.ceil((stones_x[1] + 0.2) / (0.5 * advance_m)) + 2
    cfg = replace(PreviewConfig(cop_m=case.cop_m, n_steps=n_steps), time_limit_s=60.0)
    t0 = time.perf_counter()
    ok, best = 0, None
    for x0 in np.linspace(0.0, 2 * advance_m, case.phases, endpoint=False):
        plan = plan_preview(
            course,
            cfg,
            com_m=np.array([x0 - advance_m / 2, 0.0]),
            com_v_mps=np.array([v0, 0.0]),
            com_height_m=case.z_c_m,
            stance_foot="left",
            stance_m=np.array([x0, 0.065]),
            liftoff_m=np.array([x0 - advance_m, -0.065]),
            time_left_s=step_s,
            dt_s=case.dt_s,
            v_cmd_mps=case.v_cmd_mps,
            y_path_m=0.0,
            margin_m=(X_MARGIN_M, PreviewConfig.foothold_margin_y_m),
        )
        if plan is None or plan.max_violation_m > 1e-6:
            continue
        ok += 1
        on = (plan.com_m[:, 0] > stones_x[0]) & (plan.com_m[:, 0] < stones_x[1])
        vx = plan.com_v_mps[on, 0]
        dev = float(np.abs(vx - case.v_cmd_mps).max())
        if best is None or dev < best[0]:
            best = (dev, float(vx.min()), float(vx.max()))
    return {"ok": ok, "best": best, "wall_s": time.perf_counter() - t0}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dts", default="0.04,0.045,0.055,0.065,0.07", help="fixed dts [s]")
    parser.add_argument("--z-c", type=float, default=0.555, help="CoM height [m] (humanoid3d)")
    parser.add_argument("--cop", type=float, default=PreviewConfig.cop_m, help="|CoP| [m]")
    parser.add_argument("--v-cmd", type=float, default=0.75, help="commanded speed [m/s]")
    parser.add_argument("--phases", type=int, default=8, help="start phases over one stride")
    parser.add_argument("--seed", type=int, default=None, help="seeded layout (default built-in)")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    cases = [
        Case(float(s), args.v_cmd, args.z_c, args.cop, args.phases, args.seed)
        for s in args.dts.split(",")
    ]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        results = list(pool.map(run, cases))
    wall_s = time.perf_counter() - t0
    layout = "built-in layout" if args.seed is None else f"layout seed {args.seed}"
    lines = [
        "# Fixed-dt feasibility of stepping-stones (LIP preview MILP over the whole course)",
        "",
        machine_info(("numpy", "scipy")),
        "",
        f"`stepping-stones` ({layout}), {args.v_cmd:g} m/s, CoM height {args.z_c:g} m, "
        f"|CoP| <= {args.cop:g} m, foothold margins {X_MARGIN_M:g} m (x) / "
        f"{PreviewConfig.foothold_margin_y_m:g} m (y). A plan holds every bound (no slack); "
        "the speed range is the CoM's over the stones for the plan that deviates least "
        "from the command.",
        "",
        "| dt [s] | step [s] | start phases with a plan | best plan's vx on the stones [m/s] "
        "| wall [s] |",
        "|---|---|---|---|---|",
    ]
    for case, r in zip(cases, results, strict=True):
        best = "-" if r["best"] is None else f"{r['best'][1]:.2f} - {r['best'][2]:.2f}"
        lines.append(
            f"| {case.dt_s:g} | {STAGES_PER_STEP * case.dt_s:.3f} | {r['ok']}/{case.phases} "
            f"| {best} | {r['wall_s']:.0f} |"
        )
    seed = "" if args.seed is None else f" --seed {args.seed}"
    lines += [
        "",
        f"{wall_s:.0f} s on {args.jobs} processes. Command: `.venv/bin/python "
        f"benchmarks/lip_stones.py --dts {args.dts} --cop {args.cop:g} --phases "
        f"{args.phases}{seed} --jobs {args.jobs}`.",
        "",
    ]
    report = "\n".join(lines)
    write_atomic(Path(__file__).parent / "results" / "lip_stones.md", report)
    print(report)


if __name__ == "__main__":
    main()
