"""Survival under the pushes of the paper's data-collection protocol (Sec. IV-A-1).

Each episode walks humanoid3d on flat ground at vx = 0.5 m/s with a fixed MPC dt of
0.045 s (step 0.225 s) and, from ``--first-push-s`` on, is pushed every 2 s at the trunk
CoM with a horizontal force drawn uniformly from 10-100 N, in a uniformly drawn
direction, for 0.2 s (:func:`gaitnet_mpc.sim.disturbances.protocol_pushes`, one seed per
episode; every controller gets the same pushes for a seed). An episode survives when it
does not fall within ``--duration-s``. Controllers run in a process pool (``--jobs``).

Writes ``benchmarks/results/protocol_pushes.md``. Run:
``MUJOCO_GL=egl .venv/bin/python benchmarks/protocol_pushes.py --seeds 10 --jobs 2``.
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from common import machine_info

RESULTS = Path(__file__).parent / "results" / "protocol_pushes.md"
VX_MPS = 0.5
DT_S = 0.045


def episode(controller: str, seed: int, duration_s: float, first_push_s: float) -> dict:
    """One pushed episode: survival, fall time, pushes received before the fall."""
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--controllers", default="wbmpc,kd,srbm")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--duration-s", type=float, default=12.0)
    parser.add_argument("--first-push-s", type=float, default=2.0)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    names = args.controllers.split(",")
    jobs = [(c, s, args.duration_s, args.first_push_s) for c in names for s in range(args.seeds)]
    rows: list[dict] = []
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        for row in pool.map(episode, *zip(*jobs, strict=True)):
            rows.append(row)
            state = "survived" if not row["fell"] else f"fell at {row['fall_time_s']:.2f} s"
            print(f"{row['controller']} seed {row['seed']}: {state}", flush=True)
    lines = [
        "# Survival under the data-collection protocol's pushes",
        "",
        f"Machine: {machine_info(('numpy', 'mujoco', 'casadi', 'piqp'))}.",
        "",
        f"humanoid3d, flat, vx {VX_MPS} m/s, MPC dt {DT_S} s, {args.duration_s:g} s per "
        f"episode, pushes of 10-100 N for 0.2 s in a random horizontal direction every 2 s "
        f"from t = {args.first_push_s:g} s (seeds 0-{args.seeds - 1}; the same pushes for "
        "every controller). Command: `.venv/bin/python benchmarks/protocol_pushes.py "
        f"--seeds {args.seeds} --duration-s {args.duration_s:g}`.",
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
    RESULTS.write_text("\n".join(lines) + "\n")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
