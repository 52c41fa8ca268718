"""Wall time of the implicit kino-dynamic sequential MPC over a recorded walking run.

Walks the humanoid in closed loop (``kd`` controller, flat ground, 0.5 m/s) and reports
the full sequential solve at step starts and the warm replans during steps (median, p99,
QPs per solve), then profiles where the solve time goes (QP backend, QP assembly,
reference update f_IK, reference generation f_ref). Run:
``.venv/bin/python benchmarks/bench_kd.py [--seconds 2]``.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from gaitnet_mpc.control.kd_walk import KDWalkController
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.sim.episode import Command
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course
from machine import machine_info

PARTS = {
    "QP layer (workspace.solve: PIQP setup/update + solve)": "workspace.py:solve",
    "  of which PIQP itself": "piqp_.py:_solve",
    "QP assembly (KDSubproblem.build/_assemble)": "_assemble",
    "f_IK update_reference": "update_reference",
    "f_ref make_reference": "make_reference",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--vx", type=float, default=0.5)
    args = parser.parse_args()
    robot = load_robot("humanoid3d")
    course = load_course("flat")
    sim = Simulator(robot, course)
    command = Command(vx_mps=args.vx)
    ctrl = KDWalkController(robot, course, command)
    ctrl.reset(sim.state())
    profiler = cProfile.Profile()
    profiler.enable()
    for _ in range(round(args.seconds / sim.config.timestep_s)):
        sim.step(ctrl.compute(sim.state()))
        if sim.fall.fell:
            break
    profiler.disable()
    s = ctrl.mpc_stats.summary()
    stats = pstats.Stats(profiler)
    total_solve_s = sum(ctrl.mpc_stats.solve_time_s)
    rows = []
    for label, key in PARTS.items():
        cum = sum(v[3] for k, v in stats.stats.items() if key in f"{k[0]}:{k[2]}")  # type: ignore[attr-defined]
        rows.append(f"| {label} | {cum:.2f} | {100 * cum / max(total_solve_s, 1e-9):.0f} % |")
    lines = [
        "# Implicit kino-dynamic sequential MPC: solve times",
        "",
        machine_info(("numpy", "pin", "piqp", "mujoco")),
        "",
        f"Closed loop, humanoid3d, flat, vx = {args.vx} m/s, {sim.time_s:.2f} s simulated"
        f"{' (FELL)' if sim.fall.fell else ''}; replan every "
        f"{ctrl.config.replan_period_s * 1e3:.0f} ms. Times include Python overhead and, "
        "under cProfile, its instrumentation (about 1.3-2x).",
        "",
        "| solve | count | median ms | p99 ms | QPs per solve | hit j_max |",
        "|---|---|---|---|---|---|",
    ]
    for name in ("full", "replan"):
        if f"{name}_solves" in s:
            lines.append(
                f"| {name} | {s[f'{name}_solves']} | {s[f'{name}_ms_median']:.1f} | "
                f"{s[f'{name}_ms_p99']:.1f} | {s[f'qps_per_{name}_mean']:.1f} | "
                f"{100 * s[f'{name}_not_converged_fraction']:.0f} % |"
            )
    lines += [
        "",
        "Where the solve time goes (cumulative, all solves):",
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
