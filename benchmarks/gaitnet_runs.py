"""``gaitnet`` (Gait-Net choosing each step's dt) beside ``kd`` at fixed dts and the
grid-search ``oracle``: success rates.

humanoid3d at 0.75 m/s with the paper's one-step preview (``--set preview={}``: the
multi-step one). Rows:

* ``flat``: one 20 s run per controller: fall, distance, the dts Gait-Net chose;
* ``gap`` / ``stepping-stones``: ``--seeds`` randomised layouts (seeds
  ``--seed-offset`` .. + N-1, 8 s each). The reported table uses seeds 0..N-1, on which no
  constant of Gait-Net or its policy was chosen; constants are chosen on
  ``--seed-offset 100`` (written to ``gaitnet_runs_tuning.md``). Clean: no fall, no
  foothold violation, no leg-leg contact.

Controllers: ``gaitnet`` (policy settings as shipped), ``gaitnet:r<K>`` (``max_retimes``
K; ``r0``: no limit), ``oracle``, ``kd@<dt>``; ``--set KEY=VALUE`` changes a
``KDWalkConfig`` setting of all of them (as ``gaitnet-mpc run --set``). Writes
``benchmarks/results/gaitnet_runs.md`` (``--out NAME``: another name). Run::

    .venv/bin/python benchmarks/gaitnet_runs.py [--seeds 20] [--dts 0.045,0.055,0.065] \
        [--courses gap,stepping-stones] [--weights PATH] [--jobs 2] \
        [--variants gaitnet:r1,oracle] [--seed-offset 0] [--set KEY=VALUE] [--out NAME]
"""

from __future__ import annotations

import argparse
import time
from functools import partial

import numpy as np

from common import clean_run, command_line, machine_info, run_pool, write_report

SEEDED_S = 8.0
FLAT_S = 20.0
VX_MPS = 0.75

Job = tuple[str, str, int | None]  # controller ("gaitnet" or "kd@<dt>"), course, seed


def run(job: Job, weights: str | None, overrides: tuple[str, ...] = ()) -> dict:
    from gaitnet_mpc.scenario import make_scenario, run_scenario

    name, course, seed = job
    course_name, _, speed = course.partition("@")  # flat@0.5: flat at 0.5 m/s
    extra: list[str] = []
    kw: dict = {}
    if name.startswith("gaitnet"):  # as shipped; gaitnet:r0 = no limit, gaitnet:rK = K
        kw = {"controller": "gaitnet", "gaitnet_weights": weights}
        if ":r" in name:
            k = int(name.split(":r")[1])
            extra = [f"dt_policy.gaitnet.max_retimes={k if k > 0 else 'none'}"]
    elif name == "oracle":
        kw = {"controller": "oracle"}
    else:
        kw = {"controller": "kd", "dt_s": float(name.split("@")[1])}
    scenario = make_scenario(
        course=course_name,
        course_seed=seed,
        vx_mps=float(speed) if speed else VX_MPS,
        duration_s=FLAT_S if course_name == "flat" else SEEDED_S,
        overrides=(*overrides, *extra),
        **kw,
    )
    s = run_scenario(scenario)
    policy = s.get("dt_policy") or {}
    dts = [d["dts_s"][-1] for d in policy.get("steps", [])]
    return {
        "clean": clean_run(s),
        "fell": s["fell"],
        "fall_time_s": s["fall_time_s"],
        "distance_m": s["distance_m"],
        "violations": s["foothold_violations"],
        "self_collisions": int(s["self_collisions"] or 0),
        "dts": dts,
        "fallbacks": sum((policy.get("fallbacks") or {}).values()),
        "qps": (s.get("mpc") or {}).get("qps_per_full_mean"),
        "solve_ms": (s.get("mpc") or {}).get("full_ms_median"),
    }


def _describe(job: Job, r: dict) -> str:
    name, course, seed = job
    state = "clean" if r["clean"] else "fell" if r["fell"] else "not clean"
    return f"{name} {course} seed {seed}: {state}, {r['distance_m']:.2f} m"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--dts", default="0.045,0.055,0.065", help="kd's fixed dts [s]")
    parser.add_argument("--courses", default="gap,stepping-stones")
    parser.add_argument("--weights", default=None, help="Gait-Net weights (default: shipped)")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--variants", default="", help="more controllers: gaitnet:rK, oracle")
    parser.add_argument("--seed-offset", type=int, default=0, help="first seed (tuning: 100)")
    parser.add_argument("--no-flat", action="store_true", help="skip the 20 s flat runs")
    parser.add_argument(
        "--flat-speeds", default=str(VX_MPS), help="speeds of the flat runs [m/s], e.g. 0.25,0.5"
    )
    parser.add_argument("--no-gaitnet", action="store_true", help="only --variants and --dts")
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a kd-family setting for every controller (as `gaitnet-mpc run --set`)",
    )
    parser.add_argument("--out", default=None, help="report name (default by --seed-offset)")
    args = parser.parse_args()
    names = [] if args.no_gaitnet else ["gaitnet"]
    names += [v for v in args.variants.split(",") if v]
    names += [f"kd@{float(d):g}" for d in args.dts.split(",") if d]
    courses = [c for c in args.courses.split(",") if c]
    seeds = range(args.seed_offset, args.seed_offset + args.seeds)
    flats = [] if args.no_flat else [f"flat@{float(v):g}" for v in args.flat_speeds.split(",") if v]
    jobs: list[Job] = [(n, f, None) for n in names for f in flats]
    jobs += [(n, c, s) for n in names for c in courses for s in seeds]
    tuning = args.seed_offset >= 100  # seeds 100 and up are the tuning seeds
    use = "the seeds constants are chosen on" if tuning else "none used to choose"
    overrides = tuple(args.overrides)  # a bad one fails here, before any episode
    from gaitnet_mpc.scenario import make_scenario

    multi_step = make_scenario(controller="kd", overrides=overrides).config.preview is not None
    preview = "multi-step preview (`--preview`)" if multi_step else "one-step preview"
    t0 = time.perf_counter()
    worker = partial(run, weights=args.weights, overrides=overrides)
    results: dict[Job, dict] = run_pool(worker, jobs, args.jobs, describe=_describe)
    wall_s = time.perf_counter() - t0
    lines = [
        "# gaitnet beside kd at fixed dts",
        "",
        machine_info(("numpy", "mujoco", "pin", "piqp")),
        "",
        f"humanoid3d, {VX_MPS} m/s (flat: the speed after @), {preview}, "
        f"self-collision on. Flat: {FLAT_S:.0f} s; "
        f"gap and stepping-stones: {args.seeds} seeded layouts "
        f"({seeds[0] if seeds else '-'}-{seeds[-1] if seeds else '-'}"
        f"{', tuning seeds' if tuning else ''}), "
        f"{SEEDED_S:.0f} s each, {use}. Gait-Net weights: "
        f"{args.weights or 'shipped'}. Settings: "
        f"{', '.join(overrides) if overrides else 'as shipped'}. "
        "Clean: no fall, no violation, no leg-leg contact.",
        "",
        "| controller | course | clean | no fall | mean distance [m] | violations "
        "| chosen dt [s] median (min-max) | fallbacks | QPs per full solve | full solve ms |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for course in flats + courses:
        for name in names:
            rs = [r for (n, c, _), r in results.items() if n == name and c == course]
            k = len(rs)
            dts = np.concatenate([r["dts"] for r in rs]) if rs else np.array([])
            dt_text = f"{np.median(dts):.4f} ({dts.min():.4f}-{dts.max():.4f})" if dts.size else "-"
            qps = [r["qps"] for r in rs if r["qps"] is not None]
            ms = [r["solve_ms"] for r in rs if r["solve_ms"] is not None]
            falls = (
                ""
                if not course.startswith("flat") or not rs[0]["fell"]
                else f" (t {rs[0]['fall_time_s']})"
            )
            lines.append(
                f"| {name} | {course} | {sum(r['clean'] for r in rs)}/{k} | "
                f"{sum(not r['fell'] for r in rs)}/{k}{falls} | "
                f"{np.mean([r['distance_m'] for r in rs]):.2f} | "
                f"{sum(r['violations'] for r in rs)} | {dt_text} | "
                f"{sum(r['fallbacks'] for r in rs)} | "
                f"{np.mean(qps) if qps else float('nan'):.1f} | "
                f"{np.median(ms) if ms else float('nan'):.0f} |"
            )
    lines += [
        "",
        f"{len(jobs)} episodes in {wall_s / 60:.1f} min on {args.jobs} processes. "
        f"Command: `{command_line()}`.",
        "",
    ]
    name = args.out or ("gaitnet_runs_tuning.md" if tuning else "gaitnet_runs.md")
    write_report(name, "\n".join(lines))


if __name__ == "__main__":
    main()
