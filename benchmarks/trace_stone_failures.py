"""Trace every run of a controller on seeded stepping stones that is not clean (issue 32,
item 3): when it tipped, which way, from which step and foothold.

For each seed the episode is run as ``gaitnet-mpc run --course stepping-stones --seed S
--vx 0.75 --duration 8`` would run it. A hook keeps the trunk's roll and pitch each tick.
The tilt *onset* is the first tick with roll or pitch beyond ``--onset-rad`` (0.2 rad)
that stays beyond it until the fall. The report gives, per run that is not clean, the
fall, the axis and sign of the tilt at the onset, the last touchdowns before the onset
(foot, x, patch, allowed), the step durations then, and a first reading of the cause.

    .venv/bin/python benchmarks/trace_stone_failures.py --controller gaitnet --seeds 20
"""

from __future__ import annotations

import argparse
import math
import time
from typing import Any

import numpy as np

from common import (
    add_out_option,
    clean_run,
    command_line,
    git_state,
    machine_info,
    run_pool,
    write_report,
)


def trace(job: tuple[str, int, float, float, tuple[str, ...]]) -> dict[str, Any]:
    """One seed's episode and what it did before it tipped."""
    from gaitnet_mpc.scenario import build_episode, make_scenario, run_scenario

    controller, seed, duration_s, onset_rad, overrides = job
    dt = 0.045 if controller == "kd" else None
    scenario = make_scenario(controller=controller, course="stepping-stones", course_seed=seed,
                             vx_mps=0.75, duration_s=duration_s, dt_s=dt,
                             overrides=overrides)  # fmt: skip
    episode = build_episode(scenario)
    trunk = episode.sim.model.body(episode.robot.spec.trunk_body).id
    rows: list[tuple[float, float, float, float]] = []

    def hook(sim: Any) -> None:
        r = sim.data.xmat[trunk].reshape(3, 3)
        roll = math.atan2(r[2, 1], r[2, 2])
        pitch = math.atan2(-r[2, 0], math.hypot(r[2, 1], r[2, 2]))
        rows.append((sim.time_s, float(sim.data.subtree_com[trunk, 0]), roll, pitch))

    summary = run_scenario(scenario, episode=episode, on_step=hook)
    a = np.asarray(rows).reshape(-1, 4)
    beyond = np.maximum(np.abs(a[:, 2]), np.abs(a[:, 3])) > onset_rad
    onset = None
    if beyond.any() and beyond[-1]:
        below = np.flatnonzero(~beyond)
        i = int(below[-1]) + 1 if below.size else 0
        onset = {"t_s": a[i, 0], "com_x_m": a[i, 1], "roll_rad": a[i, 2], "pitch_rad": a[i, 3]}
    return {
        "seed": seed,
        "clean": clean_run(summary),
        "fell": bool(summary["fell"]),
        "fall_time_s": summary.get("fall_time_s"),
        "fall_reason": summary.get("fall_reason") or "",
        "distance_m": float(summary["distance_m"]),
        "violations": int(summary["foothold_violations"]),
        "self_collisions": int(summary["self_collisions"] or 0),
        "footholds": summary.get("footholds") or [],
        "steps_s": summary.get("step_durations_s") or [],
        "onset": onset,
    }


def cause(r: dict[str, Any]) -> str:
    """A first reading of why the run is not clean."""
    holds = r["footholds"]
    t_end = r["onset"]["t_s"] if r["onset"] else (r["fall_time_s"] or math.inf)
    bad = [h for h in holds if not h["allowed"] and h["t_s"] <= t_end]
    parts = []
    if bad:
        h = bad[0]
        x, t = h["pos_m"][0], h["t_s"]
        parts.append(f"{h['foot']} foot off the stones at x {x:.2f} m, {t:.2f} s")
    if r["self_collisions"]:
        parts.append(f"{r['self_collisions']} ticks of leg contact")
    if r["onset"]:
        o = r["onset"]
        axis = "roll" if abs(o["roll_rad"]) >= abs(o["pitch_rad"]) else "pitch"
        angle = o[f"{axis}_rad"]
        way = {
            ("roll", True): "to the left", ("roll", False): "to the right",
            ("pitch", True): "forward", ("pitch", False): "backward",
        }[(axis, angle > 0)]  # fmt: skip
        parts.append(f"trunk tips {way} ({axis} {angle:+.2f} rad) from {o['t_s']:.2f} s")
    elif r["fell"]:
        parts.append(r["fall_reason"])
    return "; ".join(parts) or "not clean"


def _last_holds(r: dict[str, Any], n: int = 3) -> str:
    t_end = r["onset"]["t_s"] if r["onset"] else (r["fall_time_s"] or math.inf)
    before = [h for h in r["footholds"] if h["t_s"] <= t_end][-n:]
    return (
        ", ".join(
            f"{h['foot'][0]} {h['pos_m'][0]:.2f} m p{h['patch']}{'' if h['allowed'] else ' (off)'}"
            for h in before
        )
        or "-"
    )


def report(
    controller: str, results: list[dict[str, Any]], wall_s: float, onset: float, sets: list[str]
) -> str:
    bad = [r for r in results if not r["clean"]]
    overrides = ", ".join(f"`{x}`" for x in sets) or "none"
    role = "tuning seeds" if results[0]["seed"] >= 100 else "none used to choose anything"
    lines = [
        f"# `{controller}` on seeded stepping stones: every run that is not clean, traced",
        "",
        machine_info(("numpy", "mujoco", "pin", "piqp")),
        "",
        f"humanoid3d, 0.75 m/s, one-step preview, 8 s per seed, seeds "
        f"{results[0]['seed']}-{results[-1]['seed']} ({role}); {git_state()}; "
        f"overrides: {overrides}. Clean: no fall, no foothold violation, no leg contact. "
        f"Tilt onset: the first tick after which roll or pitch stays beyond {onset:g} rad "
        "until the fall.",
        "",
        f"Clean: **{len(results) - len(bad)}/{len(results)}**.",
        "",
        "| seed | outcome | distance | tilt onset (CoM x) | last touchdowns before it "
        "(foot, x, patch) | last step durations | first reading of the cause |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in bad:
        o = r["onset"]
        when = f"{o['t_s']:.2f} s ({o['com_x_m']:.2f} m)" if o else "-"
        fell = f"fell at {r['fall_time_s']:.2f} s" if r["fell"] else "no fall"
        steps = ", ".join(f"{s:.3f}" for s in r["steps_s"][-3:]) or "-"
        lines.append(
            f"| {r['seed']} | {fell}, {r['violations']} violations | {r['distance_m']:.2f} m | "
            f"{when} | {_last_holds(r)} | {steps} s | {cause(r)} |"
        )
    took = f"{len(results)} episodes in {wall_s / 60:.1f} min"
    lines += ["", f"{took}. Command: `{command_line()}`.", ""]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controller", default="gaitnet", help="gaitnet, kd (dt 0.045) or oracle")
    ap.add_argument("--seeds", type=int, default=20, help="layouts 0 .. seeds-1 (+ --first-seed)")
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--duration", type=float, default=8.0)
    ap.add_argument("--onset-rad", type=float, default=0.2)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a configuration override, as `gaitnet-mpc run --set`")  # fmt: skip
    add_out_option(ap, "stone_failures_gaitnet.md")
    args = ap.parse_args()
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    jobs = [(args.controller, s, args.duration, args.onset_rad, tuple(args.set)) for s in seeds]
    t0 = time.perf_counter()
    done = run_pool(
        trace, jobs, args.workers,
        describe=lambda job, r: f"seed {job[1]}: {'clean' if r['clean'] else cause(r)}",
    )  # fmt: skip
    results = [done[j] for j in jobs]
    wall_s = time.perf_counter() - t0
    write_report(args.out, report(args.controller, results, wall_s, args.onset_rad, args.set))


if __name__ == "__main__":
    main()
