"""Acceptance runs of the ``srbm`` controller through the CLI; writes ``results/srbm_runs.md``.

Every scenario is one ``gaitnet-mpc run ... --no-video`` (``python -m gaitnet_mpc.cli``, the
CLI code path) in its own run folder; the table is built from the ``summary.json`` files.

* matrix: humanoid3d on ``flat`` for ``--duration`` s at vx 0, 0.25, 0.5, 0.75, 1.0; a turn
  (vx 0.2, yaw rate 0.3: a 0.67 m radius circle, which stays on the 3 m wide ``flat``
  course for 20 s); the turn the issue suggests (vx 0.3, yaw rate 0.3: a 1 m radius
  circle, run for 6 s because it reaches the course edge at y = 1.5 m after about 7 s); a
  sideways walk (vy 0.1 for 12 s: 1.2 m, the course ends 1.5 m to the side); 10 N s
  sagittal and lateral pushes at 0.5 m/s (50 N for 0.2 s from t = 5 s); biped2d at 0.5 m/s.
* push: bisection on the force of a 0.2 s push at t = 5 s while walking at 0.5 m/s, in
  +x, -x, +y and -y, each run lasting until t = 10 s.

Run: ``.venv/bin/python benchmarks/srbm_runs.py`` (``--only matrix`` or ``--only push``,
``--jobs N`` parallel runs, ``--keep DIR`` to keep the run folders).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from machine import machine_info

RESULTS = Path(__file__).parent / "results" / "srbm_runs.md"
PUSH_T_S = 5.0
PUSH_DUR_S = 0.2
PUSH_END_S = 10.0


def matrix(duration_s: float) -> list[tuple[str, list[str]]]:
    """(name, CLI arguments) of the acceptance scenarios."""
    d = f"{duration_s:g}"
    rows = [
        (f"humanoid3d vx {v:g}", ["--vx", f"{v:g}", "--duration", d])
        for v in (0.0, 0.25, 0.5, 0.75, 1.0)
    ]
    rows += [
        ("humanoid3d vx 0.2, yaw rate 0.3", ["--vx", "0.2", "--yaw-rate", "0.3", "--duration", d]),
        ("humanoid3d vy 0.1", ["--vy", "0.1", "--duration", f"{min(duration_s, 12.0):g}"]),
        (
            "humanoid3d vx 0.3, yaw rate 0.3",
            ["--vx", "0.3", "--yaw-rate", "0.3", "--duration", f"{min(duration_s, 6.0):g}"],
        ),
        (
            "humanoid3d vx 0.5, push +x 10 N s",
            ["--vx", "0.5", "--duration", d, "--push", "t=5,fx=50,fy=0,dur=0.2"],
        ),
        (
            "humanoid3d vx 0.5, push +y 10 N s",
            ["--vx", "0.5", "--duration", d, "--push", "t=5,fx=0,fy=50,dur=0.2"],
        ),
        ("biped2d vx 0.5", ["--robot", "biped2d", "--vx", "0.5", "--duration", d]),
    ]
    return rows


REUSE = False  # --reuse: take summary.json from an earlier run in the --keep folder


def run_cli(args: list[str], out: Path) -> dict:
    """One ``gaitnet-mpc run`` in a subprocess; returns its ``summary.json``."""
    if REUSE and (out / "summary.json").exists():
        return json.loads((out / "summary.json").read_text())
    robot = [] if "--robot" in args else ["--robot", "humanoid3d"]
    cmd = [sys.executable, "-m", "gaitnet_mpc.cli", "run", *robot, "--controller", "srbm"]
    cmd += ["--course", "flat", *args, "--no-video", "--no-progress", "--out", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stderr}")
    return json.loads((out / "summary.json").read_text())


def _fmt(x: float | None, spec: str) -> str:
    return "-" if x is None else format(x, spec)


def table(rows: list[tuple[str, dict]]) -> str:
    head = (
        "| scenario | fell | fall time [s] | distance [m] | lateral drift [m] | mean speed [m/s] "
        "| speed RMSE [m/s] | footholds | leg-leg contact ticks | MPC solve median / p99 [ms] "
        "| realtime factor |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    lines = []
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
    return head + "\n".join(lines) + "\n"


def push_args(direction: str, force_n: float) -> list[str]:
    fx = {"+x": force_n, "-x": -force_n}.get(direction, 0.0)
    fy = {"+y": force_n, "-y": -force_n}.get(direction, 0.0)
    push = f"t={PUSH_T_S:g},fx={fx:g},fy={fy:g},dur={PUSH_DUR_S:g}"
    return ["--vx", "0.5", "--duration", f"{PUSH_END_S:g}", "--push", push]


def bisect_push(direction: str, root: Path, iters: int, lo: float, hi: float) -> dict:
    """Largest survived force [N] of a 0.2 s push: bisection between ``lo`` and ``hi``."""
    tried = []
    survived, failed = None, None
    for k in range(iters):
        force = hi if k == 0 else 0.5 * (lo + hi)
        s = run_cli(push_args(direction, force), root / f"push{direction}_{force:.0f}")
        ok = not s["fell"]
        tried.append((force, ok, s["fall_time_s"]))
        if ok:
            lo, survived = force, force
            if k == 0:
                break  # survives the top of the range
        else:
            hi, failed = force, force
    return {"direction": direction, "survived_n": survived, "failed_n": failed, "tried": tried}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--only", choices=("matrix", "push"), default=None)
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--bisect-iters", type=int, default=5)
    parser.add_argument("--keep", type=Path, default=None, help="keep run folders here")
    parser.add_argument(
        "--reuse", action="store_true", help="reuse summaries found in the --keep folder"
    )
    args = parser.parse_args()
    global REUSE
    REUSE = args.reuse and args.keep is not None
    tmp = None
    if args.keep is None:
        tmp = tempfile.TemporaryDirectory(prefix="srbm_runs_")
        root = Path(tmp.name)
    else:
        root = args.keep
        root.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    sections = [
        "# SRBM MPC acceptance runs\n",
        f"{machine_info()}\n",
        f"Run {time.strftime('%Y-%m-%d')}.\n",
        "Generated by `benchmarks/srbm_runs.py` (each row is one `gaitnet-mpc run "
        "--controller srbm --course flat ... --no-video`). `speed RMSE` compares the CoM x "
        "velocity with `--vx` after the first second (meaningless for the turn). Realtime "
        f"factor and solve times were measured with {args.jobs} runs in parallel on a "
        "shared machine. The turns and the sideways walk are sized to stay on the 3 m wide "
        "`flat` course (vx 0.3 with yaw rate 0.3 runs 6 s, vy 0.1 runs 12 s); their "
        "lateral drift is the CoM y displacement.\n",
    ]
    with ThreadPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
        if args.only in (None, "matrix"):
            scenarios = matrix(args.duration)
            futures = [
                pool.submit(run_cli, a, root / f"m{i:02d}") for i, (_, a) in enumerate(scenarios)
            ]
            rows = [(name, f.result()) for (name, _), f in zip(scenarios, futures, strict=True)]
            sections.append("## Acceptance matrix\n")
            sections.append(table(rows))
            for name, s in rows:
                print(f"{name}: fell={s['fell']} t={s['fall_time_s']} rmse={s['speed_rmse_mps']}")
        if args.only in (None, "push"):
            ranges = {
                "+x": (50.0, 150.0),
                "-x": (50.0, 150.0),
                "+y": (50.0, 100.0),
                "-y": (50.0, 100.0),
            }
            futures = [
                pool.submit(bisect_push, d, root, args.bisect_iters, *r) for d, r in ranges.items()
            ]
            results = [f.result() for f in futures]
            push_md = (
                "## Largest push survived\n\n"
                f"Walking at 0.5 m/s, one push of force F for {PUSH_DUR_S:g} s from "
                f"t = {PUSH_T_S:g} s (impulse 0.2 F N s), run until t = {PUSH_END_S:g} s; "
                "bisection on F. At t = 5 s the right foot has just started a swing and the "
                "left foot stands.\n\n"
                "| direction | largest survived F [N] (impulse [N s]) | smallest failed F [N] "
                "| runs (F: survived?) |\n|---|---|---|---|\n"
            )
            for r in results:
                surv = r["survived_n"]
                surv_txt = "-" if surv is None else f"{surv:.1f} ({PUSH_DUR_S * surv:.1f})"
                runs = ", ".join(f"{f:.1f}: {'yes' if ok else 'no'}" for f, ok, _ in r["tried"])
                push_md += (
                    f"| {r['direction']} | {surv_txt} | {_fmt(r['failed_n'], '.1f')} | {runs} |\n"
                )
                print(r)
            sections.append(push_md)
    if not REUSE:
        sections.append(f"Total wall time {time.perf_counter() - t0:.0f} s.\n")
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    if args.only is not None and RESULTS.exists():
        print(f"--only {args.only}: writing {RESULTS.with_suffix('.partial.md')}")
        RESULTS.with_suffix(".partial.md").write_text("\n".join(sections))
    else:
        RESULTS.write_text("\n".join(sections))
    if tmp is not None:
        tmp.cleanup()


if __name__ == "__main__":
    main()
