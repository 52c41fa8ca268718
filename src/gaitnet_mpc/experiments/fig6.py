"""``gaitnet-mpc reproduce fig6``: the paper's Fig. 6 as a resumable experiment.

The planar five-link biped walks over rows of gaps of one width (5, 7.5, 10, 12.5 and
15 cm, :func:`~gaitnet_mpc.terrain.builtin_courses.gap_row_course`, four gaps at seeded
positions) with the implicit kino-dynamic MPC under three dt policies, the paper's
comparison (Sec. V-B):

* ``kd``: (1) a fixed gait frequency, dt 0.045 s (a 0.225 s step);
* ``kd-optdt``: (2) each step's dt a decision variable of an NLP
  (:mod:`~gaitnet_mpc.mpc.dt_nlp`);
* ``gaitnet``: (3) Gait-Net choosing each step's dt (the shipped ``biped2d`` weights).

A case is one episode (method x width x seed, 10 s at 0.5 m/s by default); success is no
fall, no foothold violation and no leg contact. Each case is one item of a spawn process
pool or of Ray, run by :func:`~gaitnet_mpc.experiments.case_runs.run_cases` as ``sweep``'s
cases are. The folder holds:

* ``cases.jsonl``: the settings (first line), then one line per finished case, flushed
  and fsync'ed (a torn last line is ignored); the same command resumes;
* ``courses/``: every layout run, as course files (``gaitnet-mpc run --course FILE``
  replays a case);
* ``fig6.md`` / ``fig6.csv`` / ``fig6.png`` / ``strip_<method>.png``
  (:mod:`~gaitnet_mpc.experiments.fig6_report`); ``status.json``; ``errors.log``.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from gaitnet_mpc.experiments.case_runs import CaseRun, read_records, run_cases
from gaitnet_mpc.experiments.collect import CollectOptions
from gaitnet_mpc.experiments.fig6_cases import (
    METHOD_LABELS,
    ROBOT,
    Fig6Settings,
    course_file,
    make_cases,
)
from gaitnet_mpc.results.io import append_json_line, write_atomic
from gaitnet_mpc.results.outdir import check_output_path, folder_lock

CASES = "cases.jsonl"
#: Poses of the snapshot strip: one every this many seconds, while the CoM is in the
#: strip's x range [m].
SNAPSHOT_PERIOD_S = 0.4
STRIP_X_RANGE_M = (0.7, 4.6)
#: The CoM x is sampled this often for the plot of step durations along the course [s].
TRACE_PERIOD_S = 0.01

Options = CollectOptions  # workers, backend, address, progress: the same checks as collect


def _write_courses(folder: Path, settings: Fig6Settings) -> None:
    from gaitnet_mpc.terrain.builtin_courses import gap_row_course

    for width in settings.widths_m:
        for seed in settings.seed_list:
            course = gap_row_course(width, seed)
            text = json.dumps(course.to_dict(), indent=1) + "\n"
            write_atomic(folder / course_file(width, seed), text)


# ----------------------------------------------------------------------------- worker
def run_case(item: tuple[dict[str, Any], str]) -> dict[str, Any]:
    """Worker body: one episode; returns its record (``key``, ``case``, ``result``,
    ``wall_s``). Exceptions propagate."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    import numpy as np

    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.scenario import build_episode, make_scenario
    from gaitnet_mpc.sim.simulator import Simulator

    case, folder = item
    s = Fig6Settings.from_dict(case["settings"])
    method = case["method"]
    scenario = make_scenario(
        robot=ROBOT,
        controller=method,
        course=os.path.join(folder, case["course_file"]),
        vx_mps=s.vx_mps,
        duration_s=s.duration_s,
        dt_s=s.fixed_dt_s if method == "kd" else None,
        gaitnet_weights=s.gaitnet_weights if method == "gaitnet" else None,
    )
    episode = build_episode(scenario)
    trace: list[tuple[float, float]] = []
    poses: list[np.ndarray] = []
    next_pose = [0.0]
    trunk = episode.sim.model.body(episode.robot.spec.trunk_body).id

    def keep(sim: Simulator) -> None:
        t = sim.time_s
        x = float(sim.data.subtree_com[trunk][0])
        if not trace or t >= trace[-1][0] + TRACE_PERIOD_S - 1e-9:
            trace.append((t, x))
        lo, hi = STRIP_X_RANGE_M
        if case["strip"] and t >= next_pose[0] - 1e-9 and lo <= x <= hi:
            poses.append(sim.data.qpos.copy())
            next_pose[0] = t + SNAPSHOT_PERIOD_S

    t0 = time.perf_counter()
    summary = run_episode(
        episode.sim, episode.controller, scenario.command, s.duration_s, progress=False,
        on_step=keep,
    )  # fmt: skip
    controller: Any = episode.controller
    ts, xs = np.array([p[0] for p in trace]), np.array([p[1] for p in trace])
    steps = [
        {
            "t_s": round(st.start_time_s, 4),
            "duration_s": round(st.duration_s, 5),
            "com_x_m": round(float(np.interp(st.start_time_s, ts, xs)), 4),
        }
        for st in controller.schedule.step_log
    ]
    stats = controller.mpc_stats
    full_ms = [1e3 * t for t, f in zip(stats.solve_time_s, stats.full_solve, strict=True) if f]
    fall_x = float(xs[-1]) if summary["fell"] and xs.size else None
    edges = _gap_edges(Path(folder) / case["course_file"])
    policy = controller.dt_policy_summary() or {}
    result = {
        "success": not summary["fell"]
        and not summary["foothold_violations"]
        and not summary["self_collisions"],
        "fell": bool(summary["fell"]),
        "fall_time_s": summary.get("fall_time_s"),
        "fall_reason": summary.get("fall_reason") or "",
        "fall_x_m": None if fall_x is None else round(fall_x, 3),
        "fall_edge_distance_m": None
        if fall_x is None
        else round(min(abs(fall_x - e) for e in edges), 3),
        "distance_m": round(float(summary["distance_m"]), 3),
        "foothold_violations": int(summary["foothold_violations"]),
        "self_collisions": int(summary["self_collisions"]),
        "steps": steps,
        "full_solve_ms_median": round(float(np.median(full_ms)), 2) if full_ms else None,
        "fallbacks": policy.get("fallbacks", {}),
    }
    if case["strip"] and poses:
        from gaitnet_mpc.results.snapshots import snapshot_strip

        snapshot_strip(
            episode.sim,
            np.array(poses),
            Path(folder) / f"strip_{method}.png",
            x_range_m=STRIP_X_RANGE_M,
            title=f"{METHOD_LABELS[method]}: {case['key']}",
        )
    return {
        "key": case["key"],
        "case": {k: v for k, v in case.items() if k != "settings"},
        "result": result,
        "wall_s": round(time.perf_counter() - t0, 2),
    }


def _gap_edges(course_path: Path) -> list[float]:
    """x of every gap edge of a course file [m]."""
    from gaitnet_mpc.terrain import Course

    patches = sorted(Course.from_json(course_path).patches, key=lambda p: p.x_min)
    return [e for a, b in itertools.pairwise(patches) for e in (a.x_max, b.x_min)]


# ----------------------------------------------------------------------------- run
def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def reproduce_fig6(
    folder: Path,
    settings: Fig6Settings,
    options: Options,
    command_line: str = "",
    log: Callable[[str], None] = _stderr,
) -> dict[str, dict[str, Any]]:
    """Run every case of ``settings`` not yet in ``folder``, write the report; return all
    finished records.

    Raises:
        ConfigError: a folder of other settings, or one locked by another process (before
            any case starts), or a named error of a worker.
        PartialFailure: after the other cases finished, when some cases failed.
        KeyboardInterrupt: on Ctrl-C / SIGTERM, after writing what was finished.
    """
    from gaitnet_mpc.experiments.fig6_report import write_report

    t0 = time.perf_counter()
    folder = check_output_path(Path(folder), "--out")
    with folder_lock(folder, what="reproduce fig6"):
        path = folder / CASES
        records = read_records(path, settings, header="fig6_settings")
        if not path.exists():
            append_json_line(path, {"fig6_settings": settings.to_dict()})
        _write_courses(folder, settings)
        cases = make_cases(settings)

        def outputs(failed: list[str]) -> None:
            wall = time.perf_counter() - t0
            write_report(folder, settings, list(records.values()), command_line, wall, failed)

        run = CaseRun("reproduce fig6", folder, path, run_case, outputs, case_line, command_line)
        return run_cases(run, cases, records, options, log)


def case_line(record: dict[str, Any]) -> str:
    """The progress line of a finished case."""
    r = record["result"]
    if r["success"]:
        what = "ok"
    elif r["fell"]:
        what = f"FELL at {r['fall_time_s']:.2f} s, x {r['fall_x_m']:.2f} m"
    else:
        what = f"{r['foothold_violations']} violations, {r['self_collisions']} leg contacts"
    durations = [s["duration_s"] for s in r["steps"]] or [math.nan]
    return (
        f"{record['key']}: {what}, {r['distance_m']:.2f} m, steps "
        f"{min(durations):.3f}-{max(durations):.3f} s ({record['wall_s']:.0f} s)"
    )


__all__ = ["Options", "case_line", "reproduce_fig6", "run_case"]
