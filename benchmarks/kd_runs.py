"""Closed-loop outcomes of the ``kd`` controller (issue: implicit kino-dynamic MPC).

Runs every scenario of the acceptance matrix through :func:`run_episode` (the code path of
``gaitnet-mpc run``) and writes ``benchmarks/results/kd_runs.md``. Scenarios run in a
process pool (``--jobs``, default 2). Run: ``.venv/bin/python benchmarks/kd_runs.py``.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from common import machine_info

# (label, robot, course, vx [m/s], fixed dt [s], duration [s], multi-step preview)
Scenario = tuple[str, str, str, float, float, float, bool]


def _at_dts(
    label: str, course: str, duration_s: float, dts: tuple[float, ...], preview: bool
) -> tuple[Scenario, ...]:
    """One humanoid3d scenario at 0.75 m/s per fixed dt."""
    return tuple(
        (f"{label}, dt {dt:g}", "humanoid3d", course, 0.75, dt, duration_s, preview) for dt in dts
    )


SCENARIOS: tuple[Scenario, ...] = (
    ("flat 0.75 m/s", "humanoid3d", "flat", 0.75, 0.045, 20.0, False),
    *_at_dts("gap 0.20 m", "gap", 6.0, (0.045, 0.055, 0.065), False),
    *_at_dts("stepping-stones", "stepping-stones", 8.0, (0.045, 0.055, 0.065), False),
    *_at_dts("stones --preview", "stepping-stones", 8.0, (0.045, 0.05, 0.055, 0.065), True),
    ("flat 0.75 m/s --preview", "humanoid3d", "flat", 0.75, 0.045, 20.0, True),
    ("biped2d flat 0.5 m/s", "biped2d", "flat", 0.5, 0.045, 20.0, False),
)


#: Presets run side by side: the tuned default and the paper's settings (kd_walk.KD_PRESETS).
PRESETS = ("default", "paper")


def run(job: tuple[str, Scenario]) -> dict:
    from gaitnet_mpc.scenario import make_scenario, run_scenario

    preset, (label, robot_name, course_name, vx, dt, duration, preview) = job
    scenario = make_scenario(
        robot=robot_name,
        controller="kd",
        course=course_name,
        vx_mps=vx,
        duration_s=duration,
        preset=preset,
        dt_s=dt,
        preview=preview,
    )
    return {"label": label, "preset": preset, **run_scenario(scenario)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    jobs = [(preset, scenario) for scenario in SCENARIOS for preset in PRESETS]
    with ProcessPoolExecutor(args.jobs) as pool:
        results = list(pool.map(run, jobs))
    lines = [
        "# kd controller: closed-loop outcomes",
        "",
        machine_info(("numpy", "mujoco", "pin", "piqp")),
        "",
        "Self-collision on. Presets: `default` (tuned) and `paper` (`--preset paper`: Table "
        "VIII / Table V weights and limits, none of the additions listed in the README's "
        "deviations table; with `--preview` rows it gets the preview and the lateral return).",
        "",
        "| scenario | preset | fell | fall t [s] | distance [m] | speed RMSE [m/s] | "
        "lateral drift [m] | touchdowns | violations | leg-leg contact ticks | "
        "QPs/full solve | QPs/replan | full ms (median) | replan ms (median) | hit j_max | RTF |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        m = r["mpc"]
        rmse = r["speed_rmse_mps"]
        hit = 1.0 - m.get("converged_fraction", float("nan"))
        fall_t = f"{r['fall_time_s']:.2f}" if r["fell"] else "-"
        rmse_s = "-" if rmse is None else f"{rmse:.3f}"
        lines.append(
            f"| {r['label']} | {r['preset']} | {'yes' if r['fell'] else 'no'} | "
            f"{fall_t} | {r['distance_m']:.2f} | "
            f"{rmse_s} | {r['lateral_drift_m']:+.2f} | {len(r['footholds'])} | "
            f"{r['foothold_violations']} | {r['self_collisions']} | "
            f"{m.get('qps_per_full_mean', float('nan')):.1f} | "
            f"{m.get('qps_per_replan_mean', float('nan')):.1f} | "
            f"{m.get('full_ms_median', float('nan')):.0f} | "
            f"{m.get('replan_ms_median', float('nan')):.0f} | {100 * hit:.0f} % | "
            f"{r['realtime_factor']:.2f} |"
        )
    lines += [
        "",
        "Commands: the same scenario with the CLI is `gaitnet-mpc run --controller kd "
        "--robot ROBOT --course COURSE --vx VX --dt DT --duration T [--preview] "
        "[--preset paper]`. This table: `.venv/bin/python benchmarks/kd_runs.py --jobs 2`.",
        "",
        "Solve times and RTF are wall times on a shared machine and move with its load; "
        "`results/kd_solve.md` compares solver versions in one interleaved run.",
        "",
    ]
    report = "\n".join(lines)
    out = Path(__file__).parent / "results" / "kd_runs.md"
    tmp = out.with_suffix(".md.part")
    tmp.write_text(report)
    tmp.replace(out)
    print(report)


if __name__ == "__main__":
    main()
