"""Acceptance runs of the ``srbm`` controller; writes ``results/srbm_runs.md``.

Every row is one scenario as ``gaitnet-mpc run --controller srbm --course flat ...`` runs it
(:func:`~gaitnet_mpc.scenario.run_scenario`, default settings):

* matrix: humanoid3d on ``flat`` for ``--duration`` s at vx 0, 0.25, 0.5, 0.75, 1.0; a turn
  (vx 0.2, yaw rate 0.3: a 0.67 m radius circle, which stays on the 3 m wide ``flat``
  course for 20 s); the turn the issue suggests (vx 0.3, yaw rate 0.3: a 1 m radius
  circle, run for 6 s because it reaches the course edge at y = 1.5 m after about 7 s); a
  sideways walk (vy 0.1 for 12 s: 1.2 m, the course ends 1.5 m to the side); 10 N s
  sagittal and lateral pushes at 0.5 m/s (50 N for 0.2 s from t = 5 s); biped2d at 0.5 m/s.
* push: bisection on the force of a 0.2 s push at t = 5 s while walking at 0.5 m/s, in
  +x, -x, +y and -y, each run lasting until t = 10 s.

Run: ``.venv/bin/python benchmarks/srbm_runs.py`` (``--only matrix`` or ``--only push``,
``--jobs N`` parallel runs, ``--duration S``, ``--out NAME``).
"""

from __future__ import annotations

import argparse
import time

from common import add_out_option, command_line, machine_info, run_pool, write_report

PUSH_T_S = 5.0
PUSH_DUR_S = 0.2
PUSH_END_S = 10.0
#: direction -> (unit force (x, y), bisection range [N])
PUSH_DIRECTIONS = {
    "+x": ((1.0, 0.0), (50.0, 150.0)),
    "-x": ((-1.0, 0.0), (50.0, 150.0)),
    "+y": ((0.0, 1.0), (50.0, 100.0)),
    "-y": ((0.0, -1.0), (50.0, 100.0)),
}


def matrix(duration_s: float) -> list[tuple[str, tuple[tuple[str, object], ...]]]:
    """(name, ``make_scenario`` keywords) of the acceptance scenarios."""
    from gaitnet_mpc.sim.disturbances import Push

    d, walk = duration_s, {"vx_mps": 0.5, "duration_s": duration_s}
    rows: list[tuple[str, dict]] = [
        (f"humanoid3d vx {v:g}", {"vx_mps": v, "duration_s": d})
        for v in (0.0, 0.25, 0.5, 0.75, 1.0)
    ]
    rows += [
        (
            "humanoid3d vx 0.2, yaw rate 0.3",
            {"vx_mps": 0.2, "yaw_rate_radps": 0.3, "duration_s": d},
        ),
        ("humanoid3d vy 0.1", {"vy_mps": 0.1, "duration_s": min(d, 12.0)}),
        (
            "humanoid3d vx 0.3, yaw rate 0.3",
            {"vx_mps": 0.3, "yaw_rate_radps": 0.3, "duration_s": min(d, 6.0)},
        ),
        (
            "humanoid3d vx 0.5, push +x 10 N s",
            {**walk, "pushes": (Push(PUSH_T_S, (50.0, 0.0, 0.0), PUSH_DUR_S),)},
        ),
        (
            "humanoid3d vx 0.5, push +y 10 N s",
            {**walk, "pushes": (Push(PUSH_T_S, (0.0, 50.0, 0.0), PUSH_DUR_S),)},
        ),
        ("biped2d vx 0.5", {**walk, "robot": "biped2d"}),
    ]
    return [(name, tuple(kw.items())) for name, kw in rows]


def episode(**kw: object) -> dict:
    from gaitnet_mpc.scenario import make_scenario, run_scenario

    return run_scenario(make_scenario(controller="srbm", course="flat", **kw))  # type: ignore[arg-type]


def bisect_push(direction: str, iters: int) -> dict:
    """Largest survived force [N] of a 0.2 s push: bisection over the direction's range."""
    from gaitnet_mpc.sim.disturbances import Push

    (ux, uy), (lo, hi) = PUSH_DIRECTIONS[direction]
    tried, survived, failed = [], None, None
    for k in range(iters):
        force = hi if k == 0 else 0.5 * (lo + hi)
        push = Push(PUSH_T_S, (ux * force, uy * force, 0.0), PUSH_DUR_S)
        s = episode(vx_mps=0.5, duration_s=PUSH_END_S, pushes=(push,))
        tried.append((force, not s["fell"]))
        if not s["fell"]:
            lo, survived = force, force
            if k == 0:
                break  # survives the top of the range
        else:
            hi, failed = force, force
    return {"direction": direction, "survived_n": survived, "failed_n": failed, "tried": tried}


def run(job: tuple) -> dict:
    kind, name, arg = job
    return episode(**dict(arg)) if kind == "matrix" else bisect_push(name, arg)


def _fmt(x: float | None, spec: str) -> str:
    return "-" if x is None else format(x, spec)


def matrix_table(rows: list[tuple[str, dict]]) -> str:
    lines = [
        "| scenario | fell | fall time [s] | distance [m] | lateral drift [m] | mean speed [m/s] "
        "| speed RMSE [m/s] | footholds | leg-leg contact ticks | MPC solve median / p99 [ms] "
        "| realtime factor |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, s in rows:
        mpc = s.get("mpc") or {}
        lines.append(
            f"| {name} | {'yes' if s['fell'] else 'no'} | {_fmt(s['fall_time_s'], '.2f')} "
            f"| {s['distance_m']:.2f} | {s['lateral_drift_m']:.2f} | {s['mean_speed_mps']:.3f} "
            f"| {_fmt(s['speed_rmse_mps'], '.3f')} | {len(s['footholds'])} "
            f"| {s.get('self_collisions', '-')} "
            f"| {_fmt(mpc.get('solve_ms_median'), '.1f')} / {_fmt(mpc.get('solve_ms_p99'), '.1f')} "
            f"| {_fmt(s['realtime_factor'], '.2f')} |"
        )
    return "\n".join(lines) + "\n"


def push_table(results: list[dict]) -> str:
    lines = [
        f"Walking at 0.5 m/s, one push of force F for {PUSH_DUR_S:g} s from t = {PUSH_T_S:g} s "
        f"(impulse 0.2 F N s), run until t = {PUSH_END_S:g} s; bisection on F.",
        "",
        "| direction | largest survived F [N] (impulse [N s]) | smallest failed F [N] "
        "| runs (F: survived?) |",
        "|---|---|---|---|",
    ]
    for r in results:
        surv = r["survived_n"]
        surv_txt = "-" if surv is None else f"{surv:.1f} ({PUSH_DUR_S * surv:.1f})"
        runs = ", ".join(f"{f:.1f}: {'yes' if ok else 'no'}" for f, ok in r["tried"])
        lines.append(f"| {r['direction']} | {surv_txt} | {_fmt(r['failed_n'], '.1f')} | {runs} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=("matrix", "push"), default=None)
    parser.add_argument("--duration", type=float, default=20.0, help="matrix runs [s]")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--bisect-iters", type=int, default=5)
    add_out_option(parser, "srbm_runs.md")
    args = parser.parse_args()
    scenarios = matrix(args.duration) if args.only in (None, "matrix") else []
    jobs = [("matrix", name, kw) for name, kw in scenarios]
    if args.only in (None, "push"):
        jobs += [("push", d, args.bisect_iters) for d in PUSH_DIRECTIONS]
    t0 = time.perf_counter()
    results = run_pool(run, jobs, args.jobs, describe=lambda job, _: f"{job[0]} {job[1]}")
    sections = [
        "# SRBM MPC acceptance runs\n",
        f"{machine_info()}\n",
        f"Run {time.strftime('%Y-%m-%d')}, command `{command_line()}`, "
        f"{time.perf_counter() - t0:.0f} s.\n",
        "Each row is one scenario as `gaitnet-mpc run --controller srbm --course flat ...` "
        "runs it. `speed RMSE` compares the CoM x velocity with `--vx` after the first "
        "second (meaningless for the turn). Realtime factor and solve times were measured "
        f"with {args.jobs} runs in parallel on a shared machine. The turns and the sideways "
        "walk are sized to stay on the 3 m wide `flat` course (vx 0.3 with yaw rate 0.3 "
        "runs 6 s, vy 0.1 runs 12 s); their lateral drift is the CoM y displacement.\n",
    ]
    if scenarios:
        rows = [(job[1], r) for job, r in results.items() if job[0] == "matrix"]
        sections += ["## Acceptance matrix\n", matrix_table(rows)]
    pushes = [r for job, r in results.items() if job[0] == "push"]
    if pushes:
        sections += ["## Largest push survived\n", push_table(pushes)]
    write_report(args.out, "\n".join(sections))


if __name__ == "__main__":
    main()
