"""Condensed dense DAQP against sparse PIQP on the QPs the ``kd`` controller solves.

Issue 17 ("real time"): a full sequential solve at a step start should take <= 5 ms. This
script records every QP (:class:`~gaitnet_mpc.mpc.qp.QPProblem`) that the ``kd``
controller solves in closed loop (humanoid3d, flat course, ``--vx`` m/s, ``--seconds``
simulated; as ``benchmarks/bench_kd.py``), tagged with its sequential solve, its
iteration in that solve and whether the solve was a full one (step start) or a replan,
by wrapping the workspace's ``solve`` of the controller's
:class:`~gaitnet_mpc.mpc.implicit_kd.KDSubproblem` (no library file is changed). It then
replays all recorded QPs ``--rounds`` times, in recording order, interleaved problem by
problem, with:

* ``piqp``: PIQP with the controller's options, one workspace kept across all solves
  (in-place updates, as the controller does);
* ``daqp-cond cold`` / ``warm``: the equality rows (dynamics) eliminated by
  :func:`~gaitnet_mpc.mpc.qp.condensed.condense` with the states as dependent variables
  (345 -> 180 variables, no equality rows), solved by ``daqp.solve`` on the dense data;
  ``warm`` passes the previous QP's multipliers of the same sequential solve as
  ``dual_start`` (its active set; the constraint rows are the same for every QP),
  ``warm-primal`` the previous QP's condensed solution as ``primal_start``;
* ``osqp`` and ``qpoases`` (full problem, workspaces with their default options kept
  across solves; qpOASES runs dense through CasADi with hot starts) for context
  (``--context``, first round only: they are slow).

Times per QP are the minimum over the rounds (the replay is deterministic); the condensed
variants' time includes condensing and the expansion back to the full ``x`` (both also
shown separately). Accuracy is measured on the original problem against PIQP's solution.
BLAS runs single-threaded (the script re-executes itself with ``OPENBLAS_NUM_THREADS=1``).
Run::

    MUJOCO_GL=egl nice -n 5 .venv/bin/python benchmarks/kd_qp_backends.py \
        [--seconds 2] [--vx 0.75] [--rounds 3] [--context]
"""

from __future__ import annotations

import argparse
import copy
import os
import pickle
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import daqp
import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.kd_walk import KDWalkController
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.mpc.qp import QPProblem, QPWorkspace, make_workspace
from gaitnet_mpc.mpc.qp.condensed import CondensedQP, FixedVariableFinder, condense
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course
from machine import machine_info, write_report

_SENSE_EQ = 5  # daqp: equality row / bound
_DAQP_OPTIMAL = (1, 2)
_DAQP_OVERDETERMINED = -6


@dataclass(frozen=True)
class RecordedQP:
    """One QP of the closed loop: the problem, its sequential solve (0-based), its
    iteration in that solve (0-based) and whether that solve was a full one."""

    problem: QPProblem
    solve: int
    iteration: int
    full: bool


@dataclass
class Recording:
    """All QPs of one closed loop, with the controller's backend settings."""

    qps: list[RecordedQP]
    backend: str
    options: dict[str, Any]
    dependent: np.ndarray  # state columns of the KD layout (x_k, dpc_k)
    t_s: float
    fell: bool


def record(seconds: float, vx_mps: float) -> Recording:
    """Run the ``kd`` walk and record every QP it solves (see the module docstring)."""
    robot = load_robot("humanoid3d")
    course = load_course("flat")
    sim = Simulator(robot, course)
    ctrl = KDWalkController(robot, TerrainView(course), Command(vx_mps=vx_mps))
    mpc = ctrl.mpc
    sub = mpc.subproblem
    ws = sub.workspace
    qps: list[RecordedQP] = []
    tag = {"solve": -1, "iteration": 0, "full": 0}
    mpc_solve, ws_solve = mpc.solve, ws.solve

    def solve_mpc(problem: Any) -> Any:
        tag.update(solve=tag["solve"] + 1, iteration=0, full=int(problem.choose_dt))
        return mpc_solve(problem)

    def solve_qp(problem: QPProblem, warm_start: np.ndarray | None = None) -> Any:
        qps.append(
            RecordedQP(copy.deepcopy(problem), tag["solve"], tag["iteration"], bool(tag["full"]))
        )
        tag["iteration"] += 1
        return ws_solve(problem, warm_start)

    mpc.solve = solve_mpc  # type: ignore[method-assign]
    ws.solve = solve_qp  # type: ignore[method-assign]
    ctrl.reset(sim.state())
    for _ in range(round(seconds / sim.config.timestep_s)):
        sim.step(ctrl.compute(sim.state()))
        if sim.fall.fell:
            break
    lay = sub.layout
    dependent = np.sort(np.concatenate([lay.col_x.ravel(), lay.col_pc.ravel()]))
    cfg = mpc.config.kd
    return Recording(
        qps,
        cfg.qp_backend,
        cfg.qp_workspace_options(),
        dependent,
        float(sim.time_s),
        bool(sim.fall.fell),
    )


# ------------------------------------------------------------------------ replay
@dataclass
class Outcome:
    """One solve of one QP by one variant: times [s], iterations, the full ``x``."""

    time_s: float
    condense_s: float = 0.0
    solver_s: float = 0.0
    iterations: int = 0
    ok: bool = False
    x: np.ndarray | None = None
    status: str = ""


@dataclass
class DAQPState:
    """Warm-start memory of a condensed DAQP variant across the QPs of one solve."""

    solve: int = -1
    lam: np.ndarray | None = None
    u: np.ndarray | None = None
    layout: tuple[bytes, bytes] = (b"", b"")  # free columns and kept rows of the last QP
    cold_retries: int = 0
    finder: FixedVariableFinder = field(default_factory=FixedVariableFinder)


def daqp_data(c: CondensedQP) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``bupper``, ``blower`` (box of ``u`` first, then the rows) and ``sense``."""
    bupper = np.concatenate([c.ub, c.u])
    blower = np.concatenate([c.lb, c.l])
    sense = np.where(blower == bupper, _SENSE_EQ, 0).astype(np.int32)
    return bupper, blower, sense


def solve_condensed(
    rec: RecordedQP, dependent: np.ndarray, mode: str, fix: bool, state: DAQPState
) -> Outcome:
    """Condense (``fix``: also substitute the fixed variables, found by a
    :class:`FixedVariableFinder` kept across solves), solve with DAQP
    (``mode``: cold, warm = previous multipliers as dual start, warm-primal = previous
    solution as primal start; both only within one sequential solve), expand."""
    t0 = time.perf_counter()
    fixed = state.finder(rec.problem, dependent) if fix else None
    c = condense(rec.problem, dependent, fixed)
    bupper, blower, sense = daqp_data(c)
    t1 = time.perf_counter()
    layout = (c.free.tobytes(), c.rows.tobytes())
    if state.solve != rec.solve or state.layout != layout:  # no usable warm start
        state.solve, state.lam, state.u, state.layout = rec.solve, None, None, layout
    kwargs: dict[str, Any] = {}
    if mode == "warm" and state.lam is not None:
        kwargs["dual_start"] = state.lam
    elif mode == "warm-primal" and state.u is not None:
        kwargs["primal_start"] = state.u
    u, _fval, flag, info = daqp.solve(c.H, c.f, c.A, bupper, blower, sense, **kwargs)
    iterations = int(info.get("iterations", 0))
    if flag == _DAQP_OVERDETERMINED and kwargs:
        state.cold_retries += 1
        u, _fval, flag, info = daqp.solve(c.H, c.f, c.A, bupper, blower, sense)
        iterations += int(info.get("iterations", 0))
    t2 = time.perf_counter()
    ok = int(flag) in _DAQP_OPTIMAL and c.dropped_violation <= 1e-9
    x = c.expand(np.asarray(u)) if ok else None
    t3 = time.perf_counter()
    if ok:
        state.lam = np.array(info["lam"], dtype=float)
        state.u = np.array(u, dtype=float)
    else:
        state.lam = state.u = None
    return Outcome(t3 - t0, (t1 - t0) + (t3 - t2), t2 - t1, iterations, ok, x, str(int(flag)))


def solve_workspace(rec: RecordedQP, ws: QPWorkspace) -> Outcome:
    """The full sparse problem through a kept workspace (time: ``solve_time_s``)."""
    sol = ws.solve(rec.problem)
    return Outcome(
        sol.solve_time_s, 0.0, sol.solve_time_s, sol.iterations, sol.found, sol.x, sol.status
    )


def replay(rec: Recording, rounds: int, context: bool) -> dict[str, list[list[Outcome]]]:
    """``{variant: [[Outcome of QP i] for each round]}``, interleaved QP by QP."""
    out: dict[str, list[list[Outcome]]] = {}
    for round_index in range(rounds):
        solvers: dict[str, Callable[[RecordedQP], Outcome]] = {}
        piqp_ws = make_workspace("piqp", **rec.options)
        solvers["piqp"] = partial(solve_workspace, ws=piqp_ws)
        for fix, modes in ((False, ("cold",)), (True, ("cold", "warm", "warm-primal"))):
            for mode in modes:
                name = f"daqp-cond{'+fix' if fix else ''} {mode}"
                solvers[name] = partial(
                    solve_condensed, dependent=rec.dependent, mode=mode, fix=fix, state=DAQPState()
                )
        if context and round_index == 0:  # slow; for context only, one round
            osqp_ws = make_workspace("osqp")
            solvers["osqp"] = partial(solve_workspace, ws=osqp_ws)
            qpo_ws = make_workspace("qpoases")
            solvers["qpoases"] = partial(solve_workspace, ws=qpo_ws)
        results: dict[str, list[Outcome]] = {name: [] for name in solvers}
        names = list(solvers)
        for i, r in enumerate(rec.qps):
            k = i % len(names)  # rotate the order so no variant always runs first
            for name in names[k:] + names[:k]:
                results[name].append(solvers[name](r))
        for name, res in results.items():
            out.setdefault(name, []).append(res)
    return out


# ------------------------------------------------------------------------ report
def summarise(rec: Recording, out: dict[str, list[list[Outcome]]]) -> list[str]:
    """The Markdown tables of the report."""
    qps = rec.qps
    ref = out["piqp"][0]
    obj_ref = np.array([r.problem.objective(o.x) if o.x is not None else np.nan
                        for r, o in zip(qps, ref, strict=True)])  # fmt: skip
    solve_ids = np.array([r.solve for r in qps])
    full = np.array([r.full for r in qps])
    lines = [
        "| variant | median ms/QP | p99 ms/QP | of which condense+expand ms (median) | "
        "of which solver ms (median) | iterations (median / max) | failures | "
        "max rel. objective gap vs PIQP | max abs x diff vs PIQP | max constraint "
        "violation |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    per_solve: dict[str, np.ndarray] = {}
    medians: dict[str, tuple[float, float, float]] = {}
    for name, rounds in out.items():
        t = np.min([[o.time_s for o in rnd] for rnd in rounds], axis=0) * 1e3
        tc = np.min([[o.condense_s for o in rnd] for rnd in rounds], axis=0) * 1e3
        ts = np.min([[o.solver_s for o in rnd] for rnd in rounds], axis=0) * 1e3
        first = rounds[0]
        its = np.array([o.iterations for o in first])
        fails = sum(not o.ok for o in first)
        gap = dx = viol = 0.0
        for r, o, oref, oj in zip(qps, first, ref, obj_ref, strict=True):
            if not (o.ok and oref.ok) or o.x is None or oref.x is None:
                continue
            obj = r.problem.objective(o.x)
            gap = max(gap, abs(obj - oj) / max(1.0, abs(oj)))
            dx = max(dx, float(np.max(np.abs(o.x - oref.x))))
            viol = max(viol, r.problem.primal_residual(o.x))
        cond = f"{np.median(tc):.3f}" if name.startswith("daqp") else "-"
        lines.append(
            f"| {name} | {np.median(t):.3f} | {np.percentile(t, 99):.3f} | {cond} | "
            f"{np.median(ts):.3f} | {np.median(its):.0f} / {its.max()} | {fails} | "
            f"{gap:.1e} | {dx:.1e} | {viol:.1e} |"
        )
        per_solve[name] = t
        medians[name] = (float(np.median(t)), float(np.median(tc)), float(np.median(ts)))
    lines += [
        "",
        "Sum of the per-QP times over each sequential solve (QP part of a solve only; "
        "median over solves, QPs per solve in brackets):",
        "",
        "| variant | full solves: median ms (p90) | replans: median ms (p90) |",
        "|---|---|---|",
    ]
    ids = np.unique(solve_ids)
    n_qps = np.array([np.sum(solve_ids == s) for s in ids])
    is_full = np.array([full[solve_ids == s][0] for s in ids])
    for name, t in per_solve.items():
        sums = np.array([t[solve_ids == s].sum() for s in ids])
        cells = []
        for mask in (is_full, ~is_full):
            if mask.any():
                cells.append(
                    f"{np.median(sums[mask]):.2f} ({np.percentile(sums[mask], 90):.2f}) "
                    f"[{n_qps[mask].mean():.1f} QPs]"
                )
            else:
                cells.append("-")
        lines.append(f"| {name} | {cells[0]} | {cells[1]} |")
    fix = {k: v for k, v in medians.items() if k.startswith("daqp-cond+fix")}
    if fix and "piqp" in medians:
        best = min(fix, key=lambda k: fix[k][0])
        total, cond_ms, solver = fix[best]
        ref_ms = medians["piqp"][0]
        lines += [
            "",
            f"Median per QP: PIQP {ref_ms:.2f} ms, `{best}` {total:.2f} ms "
            f"({ref_ms / total:.2f}x PIQP's speed), of which condensing + expansion "
            f"{cond_ms:.2f} ms and DAQP itself {solver:.2f} ms ({ref_ms / solver:.1f}x faster "
            "than PIQP).",
        ]
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--vx", type=float, default=0.75)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--context", action="store_true", help="also OSQP and qpOASES")
    parser.add_argument("--recording", help="pickle file: reuse it if present, else write it")
    parser.add_argument("--no-report", action="store_true", help="print only, write no file")
    args = parser.parse_args()
    if os.environ.get("OPENBLAS_NUM_THREADS") != "1":
        # Single-threaded BLAS for the dense condensing: OpenBLAS threads spin on the
        # small (~100 x 165) products and, on a busy machine, slow every solver 10x.
        env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
        os.execve(sys.executable, [sys.executable, *sys.argv], env)

    path = Path(args.recording) if args.recording else None
    if path is not None and path.exists():
        rec = pickle.loads(path.read_bytes())
    else:
        rec = record(args.seconds, args.vx)
        if path is not None:
            path.write_bytes(pickle.dumps(rec))
    p0 = rec.qps[0].problem
    out = replay(rec, args.rounds, args.context)
    n_solves = len({r.solve for r in rec.qps})
    n_full = len({r.solve for r in rec.qps if r.full})
    c0 = condense(p0, rec.dependent)
    finder = FixedVariableFinder()
    sizes: list[tuple[int, int, int]] = []
    for r in rec.qps:
        c = condense(r.problem, rec.dependent, finder(r.problem, rec.dependent))
        sense = daqp_data(c)[2]
        n_eq = int(np.count_nonzero(sense[c.n_free :] == _SENSE_EQ))
        sizes.append((c.n_free, int(c.A.shape[0]), n_eq))
    lo, hi = np.min(sizes, axis=0), np.max(sizes, axis=0)
    cmd = "MUJOCO_GL=egl nice -n 5 .venv/bin/python benchmarks/kd_qp_backends.py"
    cmd += f" --seconds {args.seconds:g} --vx {args.vx:g} --rounds {args.rounds}"
    cmd += " --context" if args.context else ""
    lines = [
        "# KD controller QPs: condensed DAQP vs sparse PIQP (issue 17)",
        "",
        machine_info(("numpy", "scipy", "piqp", "daqp", "osqp", "casadi", "mujoco")),
        "",
        f"Command: `{cmd}`",
        "",
        f"Closed loop `kd`, humanoid3d, flat, vx = {args.vx:g} m/s, {rec.t_s:.2f} s "
        f"simulated{' (FELL)' if rec.fell else ''}: {len(rec.qps)} QPs in {n_solves} "
        f"sequential solves ({n_full} full). QP: n = {p0.n}, {p0.m_eq} equality rows, "
        f"{p0.m_ineq} inequality rows, box on all variables. `daqp-cond`: states "
        f"eliminated, n = {c0.n_free}, {c0.A.shape[0]} rows (+ box); `daqp-cond+fix`: also "
        "the variables that the constraints fix (box lb = ub: measured stance foot, foot "
        "heights; swing-foot wrench rows C (w + dw) = 0), n = "
        f"{lo[0]}-{hi[0]}, {lo[1]}-{hi[1]} rows of which {lo[2]}-{hi[2]} with l = u (foot "
        "ties) (+ box). "
        f"Controller backend: {rec.backend} {rec.options}. Replayed {args.rounds} times, "
        "interleaved QP by QP (rotating order); time per QP = minimum over the rounds, "
        "wall clock of the whole call (condensed: condense + DAQP + expand; workspaces: "
        "`QPSolution.solve_time_s`, i.e. conversion + setup/update + solve). Accuracy "
        "(first round, solves that succeeded) on the original problem, against PIQP's "
        "solution; OSQP/qpOASES (`--context`) are timed in the first round only. The machine "
        "is shared (2 busy cores), so compare only numbers from one run.",
        "",
        *summarise(rec, out),
        "",
    ]
    report = "\n".join(lines)
    if args.no_report:
        print(report)
    else:
        write_report("kd_qp_backends.md", report)


if __name__ == "__main__":
    main()
