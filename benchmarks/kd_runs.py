"""Closed-loop outcomes of the ``kd`` controller (issue: implicit kino-dynamic MPC).

Runs every scenario of the acceptance matrix with :func:`run_scenario` (the code path of
``gaitnet-mpc run``) and writes ``benchmarks/results/kd_runs.md`` (``--out``). Scenarios
run in a process pool (``--jobs``, default 2). Run:
``.venv/bin/python benchmarks/kd_runs.py [--only LABEL] [--max-duration S] [--out NAME]``
(``--only`` and ``--max-duration``: a quick check of a few short scenarios).
"""

from __future__ import annotations

import argparse

from common import add_out_option, command_line, machine_info, run_pool, write_report

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


def run(job: tuple[str, Scenario, float]) -> dict:
    from gaitnet_mpc.scenario import make_scenario, run_scenario

    preset, (label, robot_name, course_name, vx, dt, duration, preview), max_s = job
    scenario = make_scenario(
        robot=robot_name,
        controller="kd",
        course=course_name,
        vx_mps=vx,
        duration_s=min(duration, max_s),
        preset=preset,
        dt_s=dt,
        preview=preview,
    )
    return {"label": label, "preset": preset, **run_scenario(scenario)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--only", default="", help="scenarios whose label contains this")
    parser.add_argument("--presets", default=",".join(PRESETS))
    parser.add_argument("--max-duration", type=float, default=float("inf"), help="cap [s]")
    add_out_option(parser, "kd_runs.md")
    args = parser.parse_args()
    jobs = [
        (preset, scenario, args.max_duration)
        for scenario in SCENARIOS
        if args.only in scenario[0]
        for preset in args.presets.split(",")
    ]
    results = run_pool(run, jobs, args.jobs, describe=lambda j, r: f"{r['label']} {r['preset']}")
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
    for r in results.values():
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
        f"[--preset paper]`. This table: `{command_line()}`.",
        "",
        "Solve times and RTF are wall times on a shared machine and move with its load; "
        "`results/kd_solve.md` compares solver versions in one interleaved run.",
        "",
    ]
    write_report(args.out, "\n".join(lines))


if __name__ == "__main__":
    main()
