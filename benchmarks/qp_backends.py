"""QP backends on the project's real SRBM MPC problems, warm-started as in the controller.

Run::

    .venv/bin/python benchmarks/qp_backends.py    # ~1.5 min, 2 cores
    .venv/bin/python benchmarks/qp_backends.py --seconds 4 --passes 5

What it measures:

1. Recording: the scenario ``gaitnet-mpc run --controller srbm --vx 0.25 --duration 2``
   (``--vx``, ``--seconds``) walks ``humanoid3d`` on the ``flat`` course; every
   ``QPProblem`` its MPC builds is captured by wrapping the episode's ``mpc.build`` (the
   controller itself is untouched and solves with its configured backend). The
   problems are recorded on the fly each run, so they always match the current controller;
   nothing is stored (~200 QPs with dense 120 x 120 Hessians are ~35 MB as .npz).
   ``--save DIR`` writes them (``QPProblem.save_npz``) and ``--load DIR`` replays such a
   folder instead.
2. Replay: for every variant (each registered backend warm-chained like the controller,
   plus cold starts of osqp, piqp, daqp and qpoases) one workspace with
   ``check_problem=False`` solves the sequence in order; a warm variant passes the
   previous found solution as ``warm_start`` and keeps its workspace (in-place updates,
   qpOASES hot start), a cold variant resets its workspace and passes no guess. Solves are
   interleaved (problem i with every variant, in a rotating order, before problem i + 1),
   and the whole sequence is replayed ``--passes`` times with fresh workspaces.
3. Per solve: ``QPSolution.solve_time_s`` (backend call incl. setup/update and data
   conversion), ``found``, status and iterations, and the gap to Clarabel's solution of the
   same problem: objective ``(f - f_ref) / max(|f_ref|, 1)`` and ``max |x - x_ref|``. A
   failure is a solve that is not ``found`` or whose objective is more than 1e-3
   (relative) worse than Clarabel's.

The Markdown report goes to ``benchmarks/results/qp_backends.md`` (``--out``) and to stdout.
"""

from __future__ import annotations

import argparse
import gc
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from common import add_out_option, command_line, machine_info, write_report
from gaitnet_mpc.mpc.qp import (
    QPProblem,
    QPSolution,
    QPWorkspace,
    available_backends,
    make_workspace,
)
from gaitnet_mpc.mpc.srbm import SRBMConfig
from gaitnet_mpc.scenario import build_episode, make_scenario, run_scenario

REFERENCE = "clarabel"
FAIL_GAP = 1e-3  # relative objective excess over Clarabel that counts as a failure
COLD_BACKENDS = ("osqp", "piqp", "daqp", "qpoases")
PACKAGES = ("numpy", "scipy", "osqp", "piqp", "daqp", "clarabel", "casadi")


# ------------------------------------------------------------------ recording
@dataclass
class Recording:
    """The recorded QP sequence and how the walk that produced it went."""

    problems: list[QPProblem]
    sim_s: float = 0.0
    fell: bool = False
    distance_m: float = 0.0
    wall_s: float = 0.0
    source: str = ""


def record(seconds: float, vx_mps: float) -> Recording:
    """Walk closed loop with the ``srbm`` controller and capture every MPC QP."""
    scenario = make_scenario(controller="srbm", vx_mps=vx_mps, duration_s=seconds)
    ep = build_episode(scenario)
    mpc = ep.controller.mpc  # type: ignore[attr-defined]
    problems: list[QPProblem] = []
    build = mpc.build

    def capturing_build(*args: Any, **kwargs: Any) -> Any:
        out = build(*args, **kwargs)
        problems.append(out if isinstance(out, QPProblem) else out[0])
        return out

    mpc.build = capturing_build
    s = run_scenario(scenario, episode=ep)
    return Recording(
        problems=problems,
        sim_s=float(ep.sim.time_s),
        fell=bool(s["fell"]),
        distance_m=float(s["distance_m"]),
        wall_s=float(s["wall_time_s"]),
        source=f"recorded now: `srbm` controller (its QP backend: `{mpc.config.qp_backend}`), "
        f"humanoid3d, flat course, vx = {vx_mps:g} m/s",
    )


def save(problems: list[QPProblem], folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for i, p in enumerate(problems):
        p.save_npz(folder / f"qp_{i:05d}.npz")


def load(folder: Path) -> Recording:
    files = sorted(folder.glob("qp_*.npz"))
    if not files:
        raise SystemExit(f"no qp_*.npz files in {folder}")
    return Recording([QPProblem.load_npz(f) for f in files], source=f"loaded from `{folder}`")


# --------------------------------------------------------------------- replay
@dataclass
class Variant:
    """One backend configuration replayed over the sequence."""

    label: str
    backend: str
    warm: bool
    options: dict[str, Any] = field(default_factory=dict)
    max_passes: int | None = None  # replay only the first passes (slow variants)
    times_s: list[float] = field(default_factory=list)
    iterations: list[int] = field(default_factory=list)
    found: list[bool] = field(default_factory=list)
    statuses: dict[str, int] = field(default_factory=dict)
    obj_gap: list[float] = field(default_factory=list)  # NaN where not comparable
    x_gap: list[float] = field(default_factory=list)
    residual: list[float] = field(default_factory=list)
    x_scale: list[float] = field(default_factory=list)  # max |x_ref| of each comparison
    failures: int = 0
    setups: int = 0  # full backend setups (the rest were in-place updates)
    # per-pass state
    workspace: QPWorkspace | None = None
    last_x: np.ndarray | None = None

    def start_pass(self) -> None:
        self.workspace = make_workspace(self.backend, check_problem=False, **self.options)
        self.last_x = None

    def solve(self, problem: QPProblem) -> QPSolution:
        ws = self.workspace
        assert ws is not None
        if self.warm:
            # The SRBM QP drops a swinging foot's variables, so its size changes with the
            # contact schedule; like the controller, warm-start only when sizes match.
            last = self.last_x
            guess = last if last is not None and last.shape == (problem.n,) else None
            sol = ws.solve(problem, warm_start=guess)
            if sol.found:  # the controller keeps its last good solution otherwise
                self.last_x = sol.x
        else:
            ws.reset()
            sol = ws.solve(problem)
        return sol

    def add(self, sol: QPSolution, ref: QPSolution | None) -> None:
        self.times_s.append(sol.solve_time_s)
        self.iterations.append(sol.iterations)
        self.found.append(sol.found)
        self.statuses[sol.status] = self.statuses.get(sol.status, 0) + 1
        self.residual.append(np.nan if sol.primal_residual is None else sol.primal_residual)
        gap = dx = np.nan
        if ref is not None and ref.found and sol.x is not None and ref.obj is not None:
            assert sol.obj is not None and ref.x is not None
            gap = (sol.obj - ref.obj) / max(abs(ref.obj), 1.0)
            dx = float(np.max(np.abs(sol.x - ref.x)))
            self.x_scale.append(float(np.max(np.abs(ref.x))))
        self.obj_gap.append(gap)
        self.x_gap.append(dx)
        if not sol.found or gap > FAIL_GAP:
            self.failures += 1


def make_variants(names: list[str]) -> list[Variant]:
    variants = [Variant(name, name, warm=True) for name in names]
    for name in COLD_BACKENDS:
        if name in names:
            if name == "qpoases":  # ~150 ms a solve: one pass is enough to see it
                variants.append(
                    Variant("qpoases (cold)", name, False, {"cold_start": True}, max_passes=1)
                )
            else:
                variants.append(Variant(f"{name} (cold)", name, warm=False))
    return variants


def replay(problems: list[QPProblem], variants: list[Variant], passes: int) -> None:
    """Solve the sequence ``passes`` times, problem by problem across all variants."""
    gc.collect()
    gc.disable()
    try:
        for p in range(passes):
            active = [v for v in variants if v.max_passes is None or p < v.max_passes]
            ref_index = next(j for j, v in enumerate(active) if v.label == REFERENCE)
            for v in active:
                v.start_pass()
            for i, problem in enumerate(problems):
                shift = (i + p) % len(active)
                order = list(range(shift, len(active))) + list(range(shift))
                sols: dict[int, QPSolution] = {j: active[j].solve(problem) for j in order}
                ref = sols[ref_index]
                for j, v in enumerate(active):
                    v.add(sols[j], ref)
                if i % 20 == 19:
                    gc.collect()
            for v in active:
                assert v.workspace is not None
                v.setups += v.workspace.n_setups
            print(f"pass {p + 1}/{passes} done", file=sys.stderr)
    finally:
        gc.enable()


# --------------------------------------------------------------------- report
def _fmt_max(values: list[float], spec: str) -> str:
    arr = np.asarray(values, dtype=float)
    arr = arr[np.isfinite(arr)]
    return "n/a" if arr.size == 0 else format(float(np.max(np.abs(arr))), spec)


def table(variants: list[Variant]) -> tuple[list[str], dict[str, float]]:
    medians = {v.label: 1e3 * float(np.median(v.times_s)) for v in variants}
    fastest = min(medians.values())
    rows = [
        "| backend | median ms | p99 ms | max ms | mean iterations | failures | "
        "max objective gap | max abs x diff | max primal residual | setups | statuses | "
        "x fastest median |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|",
    ]
    for v in sorted(variants, key=lambda v: medians[v.label]):
        ms = 1e3 * np.asarray(v.times_s)
        statuses = ", ".join(f"{k} {n}" for k, n in sorted(v.statuses.items()))
        rows.append(
            f"| {v.label} | {medians[v.label]:.3f} | {np.percentile(ms, 99):.3f} | "
            f"{ms.max():.3f} | {np.mean(v.iterations):.1f} | {v.failures}/{len(ms)} | "
            f"{_fmt_max(v.obj_gap, '.1e')} | {_fmt_max(v.x_gap, '.1e')} | "
            f"{_fmt_max(v.residual, '.1e')} | {v.setups} | {statuses} | "
            f"{medians[v.label] / fastest:.2f} |"
        )
    return rows, medians


def size_line(problems: list[QPProblem]) -> str:
    p = problems[len(problems) // 2]
    l, u = p.ineq_bounds()
    eq = int(np.sum(l == u))
    one_sided = int(np.sum(np.isinf(l) ^ np.isinf(u)))
    nnz_a = sorted({q.A.nnz for q in problems if q.A is not None})
    return (
        f"Problem size (the middle QP): n = {p.n} variables (6-d wrenches of the feet in "
        f"contact per stage), m = {p.m} constraint rows ({eq} with l = u; "
        f"{one_sided} one-sided), no box; nnz(P) = {p.P.nnz} (dense condensed Hessian, "
        f"full symmetric), nnz(A) = {p.A.nnz if p.A is not None else 0} "
        f"(values seen over the run: {nnz_a})."
    )


def conclusion(variants: list[Variant], medians: dict[str, float]) -> str:
    """Name the best backend (its best failure-free variant) and judge the default."""
    default = SRBMConfig().qp_backend
    p99 = {v.label: 1e3 * float(np.percentile(v.times_s, 99)) for v in variants}
    best_of: dict[str, Variant] = {}
    for v in sorted(variants, key=lambda v: medians[v.label]):
        if v.failures == 0:
            best_of.setdefault(v.backend, v)
    if not best_of:
        return "Every backend failed at least once; no recommendation."
    ranking = sorted(best_of.values(), key=lambda v: medians[v.label])
    best = ranking[0]
    text = [
        f"**Best backend on these QPs: `{best.backend}`** (its best row `{best.label}`: "
        f"median {medians[best.label]:.3f} ms, p99 {p99[best.label]:.3f} ms, no failures)"
    ]
    if len(ranking) > 1:
        second = ranking[1]
        text.append(
            f"; the next failure-free backend, `{second.backend}` (`{second.label}`), is "
            f"{medians[second.label] / medians[best.label]:.1f}x slower at the median."
        )
    else:
        text.append(".")
    if default == best.backend:
        text.append(f' The controller default `SRBMConfig.qp_backend = "{default}"` is confirmed.')
    else:
        d = best_of.get(default)
        why = (
            f"`{default}` failed at least once in every variant"
            if d is None
            else f"`{best.backend}` is {medians[d.label] / medians[best.label]:.1f}x faster at "
            f"the median than `{d.label}`"
        )
        text.append(
            f' The controller default `SRBMConfig.qp_backend = "{default}"` is not '
            f"confirmed: {why}."
        )
    return "".join(text)


def notes(variants: list[Variant], medians: dict[str, float]) -> list[str]:
    """Computed remarks on warm starting and in-place updates."""
    by = {v.label: v for v in variants}
    out: list[str] = []
    updating = [v for v in variants if v.warm and v.backend in ("osqp", "piqp", "qpoases")]
    if updating:
        v = updating[0]
        out.append(
            f"- In-place updates: the warm osqp/piqp/qpoases workspaces still set up from "
            f"scratch on {v.setups} of {len(v.times_s)} solves, because the sparsity of A "
            "changes whenever the contact schedule shifts by one stage (a swinging foot has "
            "6 identity rows, a stance foot friction and moment rows) or a foot's yaw makes "
            "an entry exactly zero. Each such qpoases solve is a cold `init`, hence its p99."
        )
    for name in ("daqp", "osqp", "piqp"):
        warm, cold = by.get(name), by.get(f"{name} (cold)")
        if warm is None or cold is None:
            continue
        out.append(
            f"- `{name}`: warm/cold median {medians[warm.label]:.3f}/{medians[cold.label]:.3f} "
            f"ms ({medians[cold.label] / medians[warm.label]:.2f}x), mean iterations "
            f"{np.mean(warm.iterations):.1f}/{np.mean(cold.iterations):.1f}."
        )
    return out


def report(rec: Recording, variants: list[Variant], passes: int) -> str:
    rows, medians = table(variants)
    ref = next(v for v in variants if v.label == REFERENCE)
    walk = (
        f"Recording: {rec.source}; {rec.sim_s:.2f} s simulated "
        f"({'fell' if rec.fell else 'no fall'}, CoM advanced {rec.distance_m:.2f} m), "
        f"{len(rec.problems)} QPs (one per MPC replan, 100 Hz and at each step start); "
        if rec.sim_s
        else f"Recording: {rec.source}, {len(rec.problems)} QPs; "
    )
    return "\n".join(
        [
            "# QP backends on recorded SRBM MPC problems",
            "",
            machine_info(PACKAGES),
            "",
            walk + f"replayed {passes} times (fresh workspaces each pass), so each row has "
            f"{passes * len(rec.problems)} solves.",
            "",
            size_line(rec.problems),
            "",
            "Times are `QPSolution.solve_time_s`: the backend call including setup or in-place "
            "update and the conversion to the backend's format (validation off). Warm rows "
            "keep one workspace and pass the previous solution as `warm_start`, like the "
            "controller (osqp: primal warm start plus its own primal-dual iterate; daqp: "
            "`primal_start`; piqp: in-place update, no warm start; qpoases: CasADi hot start; "
            "clarabel: full setup every solve). `(cold)` rows reset the workspace and pass no "
            "guess. Solves are interleaved problem by problem across all rows. Objective gap "
            f"= (f - f_clarabel) / max(|f_clarabel|, 1), max of its absolute value; a failure is "
            f"a solve not `found` or with gap > {FAIL_GAP:g}. Clarabel's solutions reach "
            f"max |x| = {np.median(ref.x_scale):.0f} (median over problems; N and N m), and the "
            "force/moment weights (1e-4, 1e-3) make the cost nearly flat in some directions, "
            "so x can differ more than the objective. Default backend settings throughout "
            "(osqp eps 1e-5 with polishing, the rest their own defaults). qpoases (cold) is "
            "replayed in the first pass only.",
            "",
            *rows,
            "",
            conclusion(variants, medians),
            "",
            *notes(variants, medians),
            "",
            f"Command: `{command_line()}`.",
            "",
        ]
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=2.0, help="recording length [s]")
    parser.add_argument("--vx", type=float, default=0.25, help="walking command [m/s]")
    parser.add_argument("--passes", type=int, default=3, help="replays of the sequence")
    parser.add_argument("--save", type=Path, help="also write the recorded QPs to this folder")
    parser.add_argument("--load", type=Path, help="replay QPs saved with --save instead")
    add_out_option(parser, "qp_backends.md")
    args = parser.parse_args()

    if args.load is not None:
        rec = load(args.load)
    else:
        rec = record(args.seconds, args.vx)
        print(
            f"recorded {len(rec.problems)} QPs in {rec.wall_s:.1f} s ({rec.sim_s:.2f} s simulated)",
            file=sys.stderr,
        )
    if args.save is not None:
        save(rec.problems, args.save)
    names = available_backends()
    if REFERENCE not in names:
        raise SystemExit("clarabel (the reference backend) is not installed")
    variants = make_variants(names)
    replay(rec.problems, variants, args.passes)
    write_report(args.out, report(rec, variants, args.passes))


if __name__ == "__main__":
    main()
