"""Survival under the pushes of the paper's data-collection protocol (Sec. IV-A-1).

Each episode walks humanoid3d on flat ground at vx = 0.5 m/s with a fixed MPC dt of
0.045 s (step 0.225 s) and, from ``--first-push-s`` on, is pushed every 2 s at the trunk
CoM with a horizontal force drawn uniformly from 10-100 N, in a uniformly drawn
direction, for 0.2 s (:func:`gaitnet_mpc.sim.disturbances.protocol_pushes`, one seed per
episode; every controller gets the same pushes for a seed). An episode survives when it
does not fall within ``--duration-s``. Controllers run in a process pool (``--jobs``).

Writes ``benchmarks/results/protocol_pushes.md`` (``--out``). Run:
``MUJOCO_GL=egl .venv/bin/python benchmarks/protocol_pushes.py --seeds 10 --jobs 2``.
"""

from __future__ import annotations

import argparse
import os
import time

from common import add_out_option, command_line, machine_info, run_pool, write_report

VX_MPS = 0.5
DT_S = 0.045


def episode(job: tuple[str, int, float, float]) -> dict:
    """One pushed episode: survival, fall time, pushes received before the fall."""
    controller, seed, duration_s, first_push_s = job
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    from gaitnet_mpc.scenario import make_scenario, run_scenario
    from gaitnet_mpc.sim.disturbances import protocol_pushes

    pushes = protocol_pushes(seed, first_push_s, duration_s)
    dt = {"dt_s": DT_S} if controller in ("kd", "srbm", "wbmpc") else {}
    scenario = make_scenario(
        controller=controller, vx_mps=VX_MPS, duration_s=duration_s, pushes=pushes, **dt
    )
    t0 = time.perf_counter()
    summary = run_scenario(scenario)
    t_end = summary["fall_time_s"] if summary["fell"] else duration_s
    return {
        "controller": controller,
        "seed": seed,
        "fell": bool(summary["fell"]),
        "fall_time_s": summary["fall_time_s"],
        "fall_reason": summary["fall_reason"],
        "pushes": sum(p.t_s < t_end for p in pushes),
        "distance_m": summary["distance_m"],
        "wall_s": time.perf_counter() - t0,
    }


def _describe(job: tuple, row: dict) -> str:
    state = "survived" if not row["fell"] else f"fell at {row['fall_time_s']:.2f} s"
    return f"{row['controller']} seed {row['seed']}: {state}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--controllers", default="wbmpc,kd,srbm")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--duration-s", type=float, default=12.0)
    parser.add_argument("--first-push-s", type=float, default=2.0)
    parser.add_argument("--jobs", type=int, default=2)
    add_out_option(parser, "protocol_pushes.md")
    args = parser.parse_args()
    names = args.controllers.split(",")
    jobs = [(c, s, args.duration_s, args.first_push_s) for c in names for s in range(args.seeds)]
    rows = list(run_pool(episode, jobs, args.jobs, describe=_describe).values())
    lines = [
        "# Survival under the data-collection protocol's pushes",
        "",
        f"Machine: {machine_info(('numpy', 'mujoco', 'casadi', 'piqp'))}.",
        "",
        f"humanoid3d, flat, vx {VX_MPS} m/s, MPC dt {DT_S} s, {args.duration_s:g} s per "
        f"episode, pushes of 10-100 N for 0.2 s in a random horizontal direction every 2 s "
        f"from t = {args.first_push_s:g} s (seeds 0-{args.seeds - 1}; the same pushes for "
        f"every controller). Command: `{command_line()}`.",
        "",
        "| controller | survived | pushes received (mean) | falls at [s] | wall per episode [s] |",
        "|---|---|---|---|---|",
    ]
    for c in names:
        mine = [r for r in rows if r["controller"] == c]
        falls = sorted(r["fall_time_s"] for r in mine if r["fell"])
        lines.append(
            f"| {c} | {sum(not r['fell'] for r in mine)}/{len(mine)} | "
            f"{sum(r['pushes'] for r in mine) / len(mine):.1f} | "
            f"{', '.join(f'{t:.1f}' for t in falls) or '-'} | "
            f"{sum(r['wall_s'] for r in mine) / len(mine):.0f} |"
        )
    lines += ["", "Falls:", ""]
    lines += [
        f"- {r['controller']} seed {r['seed']}: {r['fall_time_s']:.2f} s, {r['fall_reason']}"
        for r in rows
        if r["fell"]
    ] or ["- none"]
    write_report(args.out, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
