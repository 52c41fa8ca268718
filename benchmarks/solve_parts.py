"""Where the time of one sequential solve goes, part by part, without a profiler's overhead.

Run: ``MUJOCO_GL=egl .venv/bin/python benchmarks/solve_parts.py [--controller gaitnet]
[--vx 0.75] [--seconds 4] [--set KEY=VALUE ...] [--out NAME]`` (writes
``results/solve_parts.md``).

One closed-loop episode on flat ground (``gaitnet-mpc run``, no video). The parts of
Algorithm 1 are wrapped with ``time.perf_counter``: f_ref (``_references``), f_IK
(``_f_ik``), the angular-pose map, the QP inputs, the condensing, DAQP with the expansion,
and the whole sub-problem solve. Each part's time is summed within a solve; the table
gives the median over the step starts (full solves) and over the replans, so the parts of
a typical replan add up to about its median. cProfile (``gaitnet-mpc bench``'s profile)
inflates the Python-heavy parts; this does not, at about 1 us per wrapped call.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

from common import add_out_option, command_line, machine_info, write_report
from gaitnet_mpc.cli import main as cli_main
from gaitnet_mpc.mpc import implicit_kd, kd_condensed, kd_inputs, sequential

#: (owner, attribute, label, nested) of each timed part; a nested part runs inside another
#: one (the condensing and DAQP inside the sub-problem solve).
PARTS: tuple[tuple[Any, str, str, bool], ...] = (
    (sequential.SequentialKDMPC, "_references", "f_ref (line 2-3)", False),
    (sequential.SequentialKDMPC, "_f_ik", "f_IK (line 9)", False),
    (sequential, "angular_pose_kgm2", "angular-pose map", False),
    (implicit_kd.KDSubproblem, "inputs", "QP inputs, checked", False),
    (kd_inputs.KDInputs, "with_references", "QP inputs, new references", False),
    (implicit_kd.KDSubproblem, "condensed_qp", "condensing", True),
    (kd_condensed.KDCondensed, "solve", "DAQP and expansion", True),
    (implicit_kd.KDSubproblem, "solve", "sub-problem solve (condensing + DAQP + step)", False),
    (implicit_kd.KDSubproblem, "plan_cost", "plan cost (eq. 18, logged)", False),
    (sequential.KDIterate, "apply", "iterate update (line 7)", False),
    (sequential, "f_j2m", "f_j2m (line 1)", False),
)

#: The parts that do not run inside one another: they add up to the solve.
TOP_LEVEL = tuple(label for _, _, label, nested in PARTS if not nested)


def _timed(fn: Callable[..., Any], label: str, acc: dict[str, float]) -> Callable[..., Any]:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            acc[label] += time.perf_counter() - t0

    return wrapper


def measure(run_args: list[str]) -> dict[str, list[dict[str, float]]]:
    """Per solve (``full`` / ``replan``) the seconds of each part and of the whole solve."""
    acc: dict[str, float] = defaultdict(float)
    solves: dict[str, list[dict[str, float]]] = {"full": [], "replan": []}
    saved = [(owner, name, getattr(owner, name)) for owner, name, _, _ in PARTS]
    solve = sequential.SequentialKDMPC.solve

    def timed_solve(self: Any, problem: Any) -> Any:
        acc.clear()
        t0 = time.perf_counter()
        result = solve(self, problem)
        acc["whole solve"] = time.perf_counter() - t0
        acc["the rest of the solve"] = acc["whole solve"] - sum(acc[p] for p in TOP_LEVEL)
        acc["QPs"] = result.n_qps
        solves["full" if problem.choose_dt else "replan"].append(dict(acc))
        return result

    try:
        for owner, name, label, _ in PARTS:
            setattr(owner, name, _timed(getattr(owner, name), label, acc))
        sequential.SequentialKDMPC.solve = timed_solve  # type: ignore[method-assign]
        with tempfile.TemporaryDirectory() as tmp:
            cli_main([*run_args, "--no-video", "--out", tmp])
    finally:
        for owner, name, fn in saved:
            setattr(owner, name, fn)
        sequential.SequentialKDMPC.solve = solve  # type: ignore[method-assign]
    return solves


def report(solves: dict[str, list[dict[str, float]]]) -> str:
    labels = ["whole solve", *(label for _, _, label, _ in PARTS), "the rest of the solve"]
    rows = ["| part | full solve, median ms | replan, median ms |", "|---|---|---|"]
    for label in labels:
        cells = [
            f"{1e3 * statistics.median(s.get(label, 0.0) for s in solves[kind]):.3f}"
            if solves[kind]
            else "-"
            for kind in ("full", "replan")
        ]
        rows.append(f"| {label} | {cells[0]} | {cells[1]} |")
    qps = [
        f"{statistics.mean(s['QPs'] for s in solves[kind]):.1f}" if solves[kind] else "-"
        for kind in ("full", "replan")
    ]
    rows.append(f"| QPs per solve (mean) | {qps[0]} | {qps[1]} |")
    n = f"{len(solves['full'])} full solves and {len(solves['replan'])} replans"
    return "\n".join(rows) + f"\n\n{n}; each part summed within a solve.\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controller", default="gaitnet")
    ap.add_argument("--vx", type=float, default=0.75)
    ap.add_argument("--seconds", type=float, default=4.0)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    add_out_option(ap, "solve_parts.md")
    args = ap.parse_args()
    run_args = ["run", "--controller", args.controller, "--course", "flat"]
    run_args += ["--vx", str(args.vx), "--duration", str(args.seconds)]
    for item in args.set:
        run_args += ["--set", item]
    table = report(measure(run_args))
    text = (
        f"# Where a sequential solve's time goes\n\n{machine_info()}\n\n"
        f"`{args.controller}` on flat ground at {args.vx} m/s, {args.seconds} s.\n\n{table}\n"
        f"Command: `{command_line()}`\n"
    )
    write_report(args.out, text)


if __name__ == "__main__":
    main()
