"""The condensed CMPC QP with DAQP against the sparse one with PIQP (issue 47, step 2).

Run::

    .venv/bin/python benchmarks/kd_qp_condensed.py      # ~4 min, 2 cores

1. Recording: ``gaitnet`` walks ``humanoid3d`` at 0.75 m/s on ``flat`` and on the seeded
   ``gap`` course (seed 3, foothold boxes of eq. 24 in play) for ``--seconds`` each;
   every CMPC QP it solves is kept with the iterate it was built about.
2. Each QP is solved ``--rounds`` times by both forms, interleaved QP by QP: the sparse
   QP by the controller's PIQP workspace (``QPSolution.solve_time_s``: update + solve +
   conversions, not the sparse QP's assembly), the condensed one as the controller solves
   it (``KDSubproblem._solve_condensed``: foot bounds, the compiled condensing straight
   from the iterate, DAQP, expansion). Time per QP: the minimum over the rounds.
3. Accuracy, on the sparse QP: objective gap, largest constraint violation, and the
   largest difference of the foot and CoM positions and of the wrenches from PIQP's.

Writes ``benchmarks/results/kd_qp_condensed.md``.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

from common import add_out_option, command_line, machine_info, write_report


def record(course: str, seconds: float) -> tuple[Any, list[tuple[Any, Any]]]:
    """The subproblem and the QPs ``gaitnet`` solves walking ``seconds`` on ``course``:
    ``(iterate, inputs)`` each."""
    from gaitnet_mpc.mpc.implicit_kd import KDSubproblem
    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.scenario import build_episode, make_scenario

    seed = 3 if course == "gap" else None
    scenario = make_scenario(
        controller="gaitnet", course=course, course_seed=seed, vx_mps=0.75, duration_s=seconds
    )
    episode = build_episode(scenario)
    sub: KDSubproblem = episode.controller.mpc.subproblem
    kept: list[tuple[Any, Any]] = []
    solve = sub.solve

    def keep(iterate: Any, inputs: Any) -> Any:
        kept.append((iterate, inputs))
        return solve(iterate, inputs)

    sub.solve = keep  # type: ignore[method-assign]
    run_episode(episode.sim, episode.controller, scenario.command, seconds, progress=False)
    return sub, kept


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--rounds", type=int, default=3)
    add_out_option(parser, "kd_qp_condensed.md")
    args = parser.parse_args()
    lines = [
        "# KD controller QPs: condensed DAQP against sparse PIQP (issue 47, step 2)",
        "",
        machine_info(("numpy", "scipy", "piqp", "daqp")),
        "",
        f"CMPC QPs recorded from `gaitnet`, humanoid3d, 0.75 m/s, {args.seconds:g} s per "
        f"course; each solved {args.rounds} times by both forms, interleaved, time = the "
        "minimum over the rounds (PIQP: the controller's workspace, update + solve; "
        "condensed: condensing + DAQP + expansion). Accuracy on the sparse QP against "
        "PIQP's solution. The machine is shared: compare rows of one run.",
        "",
        "| course | QPs | condensed variables (min-max) | PIQP median ms (p99) | condensed "
        "median ms (p99) | speed-up (median) | DAQP iterations median (max) | failures "
        "| worst rel. objective gap | worst violation | worst foot / CoM dx [m] "
        "| worst wrench dx [N, N m] |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for course in ("flat", "gap"):
        sub, kept = record(course, args.seconds)
        t_piqp = np.full(len(kept), np.inf)
        t_cond = np.full(len(kept), np.inf)
        gap, viol, d_pos, d_wrench, n_u, iters, failures = [], [], [], [], [], [], 0
        for r in range(args.rounds):
            for q, (iterate, inputs) in enumerate(kept):
                problem = sub.build(iterate, inputs)
                ref = sub.workspace.solve(problem)
                t_piqp[q] = min(t_piqp[q], ref.solve_time_s)
                t0 = time.perf_counter()
                ours, _ = sub._solve_condensed(iterate, inputs)
                t_cond[q] = min(t_cond[q], time.perf_counter() - t0)
                if r:
                    continue
                if not (ours.found and ref.found):
                    failures += 1
                    continue
                ours.problem = problem
                n_u.append(sub.condensed_qp(iterate, inputs).n_u)
                iters.append(ours.iterations)
                gap.append(abs(ours.obj - ref.obj) / max(1.0, abs(ref.obj)))
                viol.append(ours.primal_residual)
                a, b = sub.layout.unpack(ours.x), sub.layout.unpack(ref.x)
                d_pos.append(
                    max(np.abs(a[k] - b[k]).max() for k in ("delta_p_foot", "delta_p_com"))
                )
                d_wrench.append(max(np.abs(a[k] - b[k]).max() for k in ("delta_f", "delta_tau")))
        tp, tc = 1e3 * t_piqp, 1e3 * t_cond
        lines.append(
            f"| {course} | {len(kept)} | {min(n_u)}-{max(n_u)} | {np.median(tp):.2f} "
            f"({np.percentile(tp, 99):.2f}) | {np.median(tc):.2f} ({np.percentile(tc, 99):.2f})"
            f" | {np.median(tp) / np.median(tc):.2f}x | {np.median(iters):.0f} ({max(iters)}) "
            f"| {failures} | {max(gap):.1e} | {max(viol):.1e} | {max(d_pos):.1e} "
            f"| {max(d_wrench):.1e} |"
        )
    lines += ["", f"Command: `{command_line()}`", ""]
    write_report(args.out, "\n".join(lines))


if __name__ == "__main__":
    main()
