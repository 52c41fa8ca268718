"""The paper's pipeline beside this project's defaults, in one table (issue 49, item 3).

Rows: the default settings and ``--preset paper``, each with ``kd`` at fixed dts of 0.045,
0.055 and 0.065 s, ``gaitnet`` with each shipped humanoid net, and the grid-search
``oracle``. Cases: seeded stepping stones and gaps 0-19 (8 s at 0.75 m/s; no constant was
chosen on them) and flat ground for 20 s at 0.25, 0.5, 0.75 and 1.0 m/s. Columns: clean
(no fall, no foothold violation, no leg contact), fell, foothold violations, ticks of leg
contact, the range of the step durations, and the median and p99 of the full solves (step
starts) and of all solves.

Every finished episode is one line of ``<out>/cases.jsonl``; a second run of the same
command runs only the episodes missing there, so the job resumes after a stop, and the
report ``<out>/paper_pipeline.md`` is rewritten from the file at the end (or alone, with
``--report-only``)::

    .venv/bin/python benchmarks/paper_pipeline.py [--jobs 2] [--seeds 20] \
        [--out benchmarks/results/paper_pipeline] [--report-only]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from common import RESULTS, clean_run, command_line, machine_info, run_pool, write_report

PRESETS = ("default", "paper")
CONTROLLERS = (
    "kd@0.045",
    "kd@0.055",
    "kd@0.065",
    "gaitnet:humanoid3d-dagger",
    "gaitnet:humanoid3d-kd",
    "gaitnet:humanoid3d-wbmpc",
    "gaitnet:humanoid3d-kd-paper",
    "oracle",
)
FLAT_SPEEDS_MPS = (0.25, 0.5, 0.75, 1.0)
SEEDED_S, FLAT_S, SEEDED_VX_MPS = 8.0, 20.0, 0.75

Job = tuple[str, str, str, float, int | None]  # preset, controller, course, speed, seed


def key(job: Job) -> str:
    preset, controller, course, vx, seed = job
    return f"{preset}|{controller}|{course}|{vx:g}|{seed}"


def run(job: Job) -> dict:
    from gaitnet_mpc.scenario import make_scenario, run_scenario

    preset, controller, course, vx, seed = job
    kw: dict = {}
    if controller.startswith("kd@"):
        kw = {"controller": "kd", "dt_s": float(controller.split("@")[1])}
    elif controller.startswith("gaitnet:"):
        kw = {"controller": "gaitnet", "gaitnet_weights": controller.split(":")[1]}
    else:
        kw = {"controller": controller}
    scenario = make_scenario(
        course=course,
        course_seed=seed,
        vx_mps=vx,
        duration_s=FLAT_S if course == "flat" else SEEDED_S,
        preset=None if preset == "default" else preset,
        **kw,
    )
    s = run_scenario(scenario)
    mpc = s.get("mpc") or {}
    steps = [float(d) for d in s.get("step_durations_s") or []]
    return {
        "key": key(job),
        "clean": clean_run(s),
        "fell": bool(s["fell"]),
        "fall_time_s": s["fall_time_s"],
        "violations": int(s["foothold_violations"]),
        "leg_contact_ticks": int(s["self_collisions"] or 0),
        "step_min_s": min(steps) if steps else None,
        "step_max_s": max(steps) if steps else None,
        "full_ms_median": mpc.get("full_ms_median"),
        "full_ms_p99": mpc.get("full_ms_p99"),
        "solve_ms_median": mpc.get("solve_ms_median"),
        "solve_ms_p99": mpc.get("solve_ms_p99"),
    }


def jobs(seeds: int) -> list[Job]:
    out: list[Job] = []
    for preset in reversed(PRESETS):  # the paper's rows first
        for controller in CONTROLLERS:
            out += [(preset, controller, "flat", v, None) for v in FLAT_SPEEDS_MPS]
            for course in ("stepping-stones", "gap"):
                out += [(preset, controller, course, SEEDED_VX_MPS, s) for s in range(seeds)]
    return out


def _cell(rows: list[dict], field: str) -> str:
    return f"{sum(bool(r[field]) for r in rows)}/{len(rows)}"


def _median(rows: list[dict], field: str) -> str:
    vals = [r[field] for r in rows if r[field] is not None]
    return f"{np.median(vals):.1f}" if vals else "-"


def report(all_jobs: list[Job], records: dict[str, dict], wall_s: float | None, n_jobs: int) -> str:
    lines = [
        "# The paper's pipeline beside the defaults",
        "",
        machine_info(("numpy", "mujoco", "pin")),
        "",
        f"humanoid3d, one-step preview, self-collision on. Seeded stepping stones and gaps: "
        f"{SEEDED_S:g} s at {SEEDED_VX_MPS:g} m/s, seeds 0-{max(j[4] or 0 for j in all_jobs)} "
        f"(none tuned on); flat: {FLAT_S:g} s at {', '.join(f'{v:g}' for v in FLAT_SPEEDS_MPS)} "
        "m/s. Clean: no fall, no foothold violation, no leg contact. Step durations: the "
        "range over the episodes' steps. Solve times: medians over the episodes of each "
        "episode's median and p99 (full: step starts; all: every solve). `gaitnet:NET`: "
        "Gait-Net with the shipped weights NET (`humanoid3d-dagger` is the default, "
        "`humanoid3d-kd-paper` the paper preset's).",
        "",
        "| preset | controller | course | clean | fell | violations | leg-contact ticks | "
        "step duration [s] | full solve median / p99 [ms] | any solve median / p99 [ms] |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for preset in PRESETS:
        for controller in CONTROLLERS:
            for course in ("stepping-stones", "gap", "flat"):
                mine = [j for j in all_jobs if j[:3] == (preset, controller, course)]
                rows = [records[key(j)] for j in mine if key(j) in records]
                if not rows:
                    continue
                lo = [r["step_min_s"] for r in rows if r["step_min_s"] is not None]
                hi = [r["step_max_s"] for r in rows if r["step_max_s"] is not None]
                steps = f"{min(lo):.3f}-{max(hi):.3f}" if lo else "-"
                done = "" if len(rows) == len(mine) else f" ({len(rows)} of {len(mine)} run)"
                lines.append(
                    f"| {preset} | `{controller}` | {course}{done} | {_cell(rows, 'clean')} | "
                    f"{_cell(rows, 'fell')} | {sum(r['violations'] for r in rows)} | "
                    f"{sum(r['leg_contact_ticks'] for r in rows)} | {steps} | "
                    f"{_median(rows, 'full_ms_median')} / {_median(rows, 'full_ms_p99')} | "
                    f"{_median(rows, 'solve_ms_median')} / {_median(rows, 'solve_ms_p99')} |"
                )
    lines.append("")
    for preset in PRESETS:
        rows = [records[key(j)] for j in all_jobs if j[0] == preset and key(j) in records]
        falls = [r["fall_time_s"] for r in rows if r["fell"] and r["fall_time_s"] is not None]
        last = f", the latest fall at {max(falls):.2f} s" if falls else ""
        lines.append(
            f"- `{preset}`: {len(rows)} episodes, {sum(r['clean'] for r in rows)} clean, "
            f"{len(falls)} fell{last}."
        )
    lines += [
        "",
        f"{len(records)} of {len(all_jobs)} episodes; "
        + (
            "this report rewritten from `cases.jsonl`"
            if wall_s is None
            else f"this run: {wall_s / 60:.1f} min on {n_jobs} processes"
        )
        + f". Command: `{command_line()}`.",
        "",
    ]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=RESULTS / "paper_pipeline")
    parser.add_argument(
        "--report-only", action="store_true", help="rewrite the report from the cases so far"
    )
    args = parser.parse_args()
    if args.seeds < 1:
        parser.error(f"--seeds: {args.seeds} is not a positive number of layouts")
    args.out.mkdir(parents=True, exist_ok=True)
    cases = args.out / "cases.jsonl"
    records: dict[str, dict] = {}
    if cases.exists():
        for line in cases.read_text().splitlines():
            try:
                r = json.loads(line)
            except json.JSONDecodeError:
                continue  # a line cut by a kill
            records[r["key"]] = r
    all_jobs = jobs(args.seeds)
    todo = [] if args.report_only else [j for j in all_jobs if key(j) not in records]
    print(f"{len(todo)} of {len(all_jobs)} episodes to run", flush=True)
    t0 = time.perf_counter()

    def describe(job: Job, r: dict) -> str:
        with cases.open("a") as f:  # the parent appends each result as it arrives
            f.write(json.dumps(r) + "\n")
        records[r["key"]] = r
        return f"{key(job)}: {'clean' if r['clean'] else 'fell' if r['fell'] else 'not clean'}"

    try:
        run_pool(run, todo, args.jobs, describe=describe)
    finally:
        wall_s = None if args.report_only else time.perf_counter() - t0
        text = report(all_jobs, records, wall_s, args.jobs)
        write_report(args.out / "paper_pipeline.md", text, echo=False)


if __name__ == "__main__":
    main()
