"""Largest push each controller survives (issue "Honest physics first", item 8).

A push is a constant force at the trunk CoM for 0.2 s (impulse 0.2 F N s), forward (``fwd``,
+x), backward (``bwd``, -x) or sideways (``left``, +y; ``right``, -y). ``stand`` stands still
(command 0) and is pushed at t = 3 s; ``srbm`` and ``kd`` walk on humanoid3d's ``flat``
course at vx = 0.5 m/s and are pushed at a phase of a step: the gait schedule starts its
first step at t = 0 and every step lasts T = 5 dt (fixed MPC dt), so the push starts at
k T + p T, with k T the first step start at or after t = 3 s (walking established) and p
the phase (``early`` = 0.2, ``late`` = 0.7, or a number in [0, 1)). A run survives when
the robot does not fall before 3 s after the push ends (the episode ends then).

Each cell (controller x direction x phase) bisects the force on a grid of ``--resolution``
N in [0, ``--f-max``] N, assuming that a push the robot survives is survived at every
smaller force (monotonicity). The ends of the range are run only when the bisection
reaches them. ``--spot-check`` (default on, off with ``--quick``) also runs half the
survived force as a check of that assumption. Cells run in a process pool (``--jobs``).

Writes ``benchmarks/results/push_recovery.md`` (table; ``--out``) and the CSV beside it
(one row per episode). Run:
``MUJOCO_GL=egl .venv/bin/python benchmarks/push_recovery.py --jobs 2``
(``--quick``: phase ``early``, directions ``fwd,left``, 20 N resolution). ``gaitnet``
chooses its own dts, so its push times come from its nominal dt; the measured phase is in
the CSV.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import time

from common import add_out_option, command_line, machine_info, run_pool, write_report

CONTROLLERS = ("stand", "srbm", "kd", "gaitnet")
#: direction name -> unit force direction (world x, y)
DIRECTIONS = {"fwd": (1.0, 0.0), "bwd": (-1.0, 0.0), "left": (0.0, 1.0), "right": (0.0, -1.0)}
PHASES = {"early": 0.2, "late": 0.7}
PUSH_DUR_S = 0.2
WALK_VX_MPS = 0.5
SETTLE_S = 3.0  # pushes start at (or, walking, after the first step start after) this time
AFTER_S = 3.0  # the episode runs this long after the push ends
CSV_FIELDS = (
    "controller",
    "direction",
    "phase",
    "force_n",
    "impulse_ns",
    "push_t_s",
    "phase_measured",
    "swing_foot",
    "fell",
    "fall_time_s",
    "fall_reason",
    "diverged",
    "self_collisions",
    "wall_s",
)

# (controller, direction, phase name or None for stand, f_max [N], resolution [N], spot check)
Cell = tuple[str, str, str | None, float, float, bool]


def phase_value(name: str) -> float:
    """``early`` / ``late`` or a number in [0, 1)."""
    if name in PHASES:
        return PHASES[name]
    value = float(name)
    if not 0.0 <= value < 1.0:
        raise ValueError(f"phase {name!r}: early, late or a number in [0, 1)")
    return value


def episode(controller_name: str, direction: str, phase: str | None, force_n: float) -> dict:
    """One pushed episode; returns its row of the raw-outcome CSV."""
    from gaitnet_mpc.dt_policy import NOMINAL_DT_S
    from gaitnet_mpc.scenario import build_episode, make_scenario, run_scenario
    from gaitnet_mpc.sim.disturbances import Push

    if phase is None or controller_name == "stand":
        push_t = SETTLE_S
    else:  # every walking controller starts with 5-stage steps of the nominal dt
        step_s = 5 * NOMINAL_DT_S
        k = math.ceil(SETTLE_S / step_s - 1e-9)
        push_t = k * step_s + phase_value(phase) * step_s
    ux, uy = DIRECTIONS[direction]
    pushes = (Push(push_t, (ux * force_n, uy * force_n, 0.0), PUSH_DUR_S),) if force_n > 0 else ()
    scenario = make_scenario(
        controller=controller_name,
        vx_mps=0.0 if controller_name == "stand" else WALK_VX_MPS,
        duration_s=push_t + PUSH_DUR_S + AFTER_S,
        pushes=pushes,
    )
    episode_ = build_episode(scenario)
    sim = episode_.sim
    sched = getattr(episode_.controller, "schedule", None)  # stand has none
    t0 = time.perf_counter()
    try:
        summary = run_scenario(scenario, episode=episode_)
    except Exception as exc:  # the controller gave up during the episode: a failure
        summary = {"fell": True, "fall_time_s": sim.time_s, "fall_reason": f"exception: {exc!r}"}
    wall = time.perf_counter() - t0
    # Where in its step the push really started, from the executed step log.
    phase_measured, swing_foot = "", ""
    if sched is not None and phase is not None:
        steps = [*sched.step_log]
        for s in steps:
            if s.start_time_s - 1e-9 <= push_t < s.start_time_s + s.duration_s - 1e-9:
                phase_measured = f"{(push_t - s.start_time_s) / s.duration_s:.3f}"
                swing_foot = s.swing_foot
                break
        else:
            if sched.step_start_time_s <= push_t:  # the episode ended inside that step
                frac = (push_t - sched.step_start_time_s) / sched.current_step_duration_s
                phase_measured = f"{frac:.3f}"
                swing_foot = sched.swing_foot
    return {
        "controller": controller_name,
        "direction": direction,
        "phase": phase or "-",
        "force_n": f"{force_n:g}",
        "impulse_ns": f"{force_n * PUSH_DUR_S:g}",
        "push_t_s": f"{push_t:.4f}",
        "phase_measured": phase_measured,
        "swing_foot": swing_foot,
        "fell": bool(summary["fell"]),
        "fall_time_s": "" if summary["fall_time_s"] is None else f"{summary['fall_time_s']:.3f}",
        "fall_reason": summary.get("fall_reason") or "",
        "diverged": bool(summary.get("diverged", False)),
        "self_collisions": summary.get("self_collisions", ""),
        "wall_s": f"{wall:.1f}",
    }


def run_cell(cell: Cell) -> dict:
    """Bisection on the force grid of one cell; returns the bracket and every episode."""
    controller, direction, phase, f_max, res, spot = cell
    t0 = time.perf_counter()
    runs: dict[int, dict] = {}  # grid index -> episode row

    def survived(i: int) -> bool:
        if i not in runs:
            runs[i] = episode(controller, direction, phase, i * res)
        return not runs[i]["fell"]

    n = round(f_max / res)
    lo, hi = 0, n  # lo: survived (or assumed), hi: failed (or assumed)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if survived(mid):
            lo = mid
        else:
            hi = mid
    top_ok = hi == n and survived(n)  # the top of the range is run only if reached
    if top_ok:
        lo, hi = n, None
    zero_fell = lo == 0 and not survived(0)  # falls without a push
    spot_fail = None
    if spot and lo and hi is not None and not zero_fell:
        half = lo // 2
        if half > 0 and not survived(half):
            spot_fail = half * res
    return {
        "controller": controller,
        "direction": direction,
        "phase": phase,
        "survived_n": None if zero_fell else lo * res,
        "failed_n": None if hi is None else hi * res,
        "zero_fell": zero_fell,
        "spot_fail_n": spot_fail,
        "survivor_self_collisions": None if zero_fell else runs.get(lo, {}).get("self_collisions"),
        "runs": [runs[i] for i in sorted(runs)],
        "wall_s": time.perf_counter() - t0,
    }


def _cell_text(r: dict | None) -> tuple[str, str]:
    """(survived force / impulse, first failing force) of one table cell."""
    if r is None:
        return "", ""
    if "error" in r:
        return "error", "error"
    if r["zero_fell"]:
        surv = "falls unpushed"
    else:
        s = r["survived_n"]
        surv = f"{s:g} / {s * PUSH_DUR_S:g}"
        if r["survivor_self_collisions"]:
            surv += " (sc)"
        if r["spot_fail_n"] is not None:
            surv += f" (!{r['spot_fail_n']:g})"
    failed = f"> {r['f_max']:g}" if r["failed_n"] is None else f"{r['failed_n']:g}"
    return surv, failed


def _push_times(results: list[dict]) -> str:
    """Push start time, measured phase and swing foot per walking controller and phase."""
    seen: dict[tuple[str, str], str] = {}
    for r in results:
        for e in r["runs"]:
            key = (e["controller"], e["phase"])
            if e["phase"] != "-" and e["phase_measured"] and key not in seen:
                seen[key] = (
                    f"{e['controller']} {e['phase']} {float(e['push_t_s']):.4g} "
                    f"({e['phase_measured']}, {e['swing_foot']})"
                )
    return "; ".join(seen[k] for k in sorted(seen)) or "-"


def report(results: list[dict], args: argparse.Namespace, wall_s: float) -> str:
    directions = args.directions
    by_key = {(r["controller"], r["direction"], r["phase"]): r for r in results}
    rows = []
    for c in args.controllers:
        for p in [None] if c == "stand" else args.phases:
            rows.append((c, p))
    head = "| controller | phase |" + "".join(
        f" {d} survived [N] / [N s] | {d} failed [N] |" for d in directions
    )
    lines = [
        "# Push recovery: largest push survived",
        "",
        f"{machine_info(('numpy', 'mujoco', 'pin', 'piqp'))}.",
        f"Run {time.strftime('%Y-%m-%d')}, wall time {wall_s / 60:.1f} min with "
        f"{args.jobs} jobs on a shared machine.",
        "",
        head,
        "|---|---|" + "---|---|" * len(directions),
    ]
    for c, p in rows:
        cells = []
        for d in directions:
            cells.extend(_cell_text(by_key.get((c, d, p))))
        label = "- (t = 3 s)" if p is None else f"{p} ({phase_value(p):g})"
        lines.append(f"| {c} | {label} | " + " | ".join(cells) + " |")
    directions_txt = ", ".join(
        f"`{d}` ({'+' if sum(DIRECTIONS[d]) > 0 else '-'}{'x' if DIRECTIONS[d][0] else 'y'})"
        for d in directions
    )
    lines += [
        "",
        f"Survived: the largest force F [N] of a {PUSH_DUR_S:g} s push at the trunk CoM "
        f"(impulse {PUSH_DUR_S:g} F [N s]) with no fall within {AFTER_S:g} s after the "
        "push; failed: the smallest force that made the robot fall (the bisection's upper "
        f"bracket; `> {args.f_max:g}` if it survived the top of the range). Directions: "
        f"{directions_txt}. `(sc)`: the survived run had robot self-collisions; `(!F)`: "
        "the spot check at half the survived force F fell (non-monotonic).",
        "",
        "Method: humanoid3d on the `flat` course; `stand` with command 0, pushed at t = "
        f"{SETTLE_S:g} s; `srbm` and `kd` (registry defaults: fixed MPC dt, step T = 5 dt) "
        f"walking at vx = {WALK_VX_MPS:g} m/s, pushed at k T + p T, k T being the first "
        f"step start at or after {SETTLE_S:g} s. Push start [s] (measured phase in the "
        f"step, swing foot): {_push_times(results)}. Each episode runs until "
        f"{AFTER_S:g} s after the push ends. Bisection on F over a {args.resolution:g} N "
        f"grid in [0, {args.f_max:g}] N, assuming monotonicity (a push that is survived "
        "is survived at every smaller force; the bisection cannot see a violation, "
        + (
            "the spot check at half the survived force can). "
            if args.spot_check
            else "no spot check was run). "
        )
        + "`push_recovery.csv` lists every episode (force, fall time and reason, "
        "self-collision ticks, where in its step the push really started).",
    ]
    if "kd" in args.controllers and "srbm" in args.controllers:
        parts, weaker, compared = [], 0, 0
        for d in directions:
            cmp = []
            for p in args.phases:
                k, s = by_key.get(("kd", d, p)), by_key.get(("srbm", d, p))
                if k is None or s is None or "error" in k or "error" in s:
                    continue
                ks = -1.0 if k["zero_fell"] else k["survived_n"]
                ss = -1.0 if s["zero_fell"] else s["survived_n"]
                mark = "<" if ks < ss else (">" if ks > ss else "=")
                weaker += ks < ss
                compared += 1
                cmp.append(f"{p} kd {max(ks, 0):g} {mark} srbm {max(ss, 0):g} N")
            parts.append(f"{d}: " + ", ".join(cmp))
        lines += [
            "",
            f"kd vs srbm (survived force): {'; '.join(parts)}. kd survives less than the SRBM "
            f"baseline in {weaker} of {compared} cells" + (" (a finding)." if weaker else "."),
        ]
    lines += ["", f"Command: `{command_line()}`.", ""]
    return "\n".join(lines)


def _describe(cell: Cell, r: dict) -> str:
    surv, failed = _cell_text({**r, "f_max": cell[3]})
    c, d, p = cell[:3]
    return f"{c} {d} {p or '-'}: survived {surv}, failed {failed} ({len(r['runs'])} episodes)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--controllers", default=",".join(CONTROLLERS))
    parser.add_argument("--directions", default=None, help="default fwd,bwd,left")
    parser.add_argument("--phases", default=None, help="default early,late")
    parser.add_argument("--quick", action="store_true", help="fewer cells, 20 N resolution")
    parser.add_argument("--f-max", type=float, default=300.0)
    parser.add_argument("--resolution", type=float, default=None, help="default 5 N")
    parser.add_argument("--spot-check", action=argparse.BooleanOptionalAction, default=None)
    add_out_option(parser, "push_recovery.md")  # the CSV beside it
    args = parser.parse_args()
    args.controllers = args.controllers.split(",")
    default_dirs, default_phases = (
        ("fwd,left", "early") if args.quick else ("fwd,bwd,left", "early,late")
    )
    args.directions = (args.directions or default_dirs).split(",")
    args.phases = (args.phases or default_phases).split(",")
    args.resolution = args.resolution or (20.0 if args.quick else 5.0)
    args.spot_check = (not args.quick) if args.spot_check is None else args.spot_check
    for c in args.controllers:
        if c not in CONTROLLERS:
            parser.error(f"controller {c!r}: one of {CONTROLLERS}")
    for d in args.directions:
        if d not in DIRECTIONS:
            parser.error(f"direction {d!r}: one of {tuple(DIRECTIONS)}")
    for p in args.phases:
        try:
            phase_value(p)
        except ValueError as exc:
            parser.error(str(exc))
    if not (args.f_max * PUSH_DUR_S <= 100.0 and args.f_max / args.resolution >= 1):
        parser.error("--f-max: at most 500 N (100 N s) and at least one --resolution")
    cells: list[Cell] = [
        (c, d, p, args.f_max, args.resolution, args.spot_check)
        for c in args.controllers
        for p in ([None] if c == "stand" else args.phases)
        for d in args.directions
    ]
    t0 = time.perf_counter()
    results, errors = [], []
    for cell, r in run_pool(
        run_cell, cells, args.jobs, describe=_describe, keep_errors=True
    ).items():
        if isinstance(r, Exception):  # setup failed (e.g. a broken import): report, go on
            c, d, p = cell[:3]
            r = {
                "controller": c,
                "direction": d,
                "phase": p,
                "error": str(r).splitlines()[0],
                "runs": [],
            }
            errors.append(f"{c} {d} {p or '-'}: {r['error']}")
        r["f_max"] = args.f_max
        results.append(r)
    wall = time.perf_counter() - t0
    text = report(results, args, wall)
    if errors:
        text += "\nCells that could not run (setup error):\n\n" + "".join(
            f"* {e}\n" for e in errors
        )
    buf = io.StringIO()
    writer = csv.DictWriter(buf, CSV_FIELDS, lineterminator="\n")
    writer.writeheader()
    for r in sorted(results, key=lambda r: (r["controller"], r["direction"], r["phase"] or "")):
        writer.writerows(r["runs"])
    path = write_report(args.out, text)
    write_report(path.with_suffix(".csv"), buf.getvalue(), echo=False)


if __name__ == "__main__":
    main()
