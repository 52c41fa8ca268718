"""Where Table II's SQP time goes: NLP sizes, build times and a per-solve time split.

:func:`profile_table2` solves recorded problems (the first ``N`` of a
:mod:`~gaitnet_mpc.table2.problems` file) with the ``sqpmethod`` columns of Table II, built
exactly as :mod:`~gaitnet_mpc.table2.run` builds them, plus **CD-SQP (PIQP)**: CD-SQP with
the joint-space columns' QP solver and Hessian regularisation (:data:`~.run.JOINT_SQP`),
so that the three formulations can also be compared with one QP solver, and **WBD-SQP
(point test)**: WBD-SQP's NLPs stopped by each contact point's force and no moment (its
step test before 2026-12). It records

* per built NLP: ``n_x``, ``n_g``, the nonzeros of the constraint Jacobian and of the
  Lagrangian Hessian (as CasADi's ``nlp_jac_fg`` / ``nlp_hess_l`` store them: the
  Hessian's upper triangle) and the build time (symbolic transcription + ``nlpsol``);
* per solve: wall time, SQP iterations (one QP each), converged (as in the table), the
  return status, and ``sqpmethod``'s own split of the time into QP solves, Hessian and
  Jacobian evaluations and the step-test callback.

``python -m gaitnet_mpc.table2.diagnose PROBLEMS.npz --problems N --out FILE.md`` writes
:func:`profile_markdown` (atomically) and a JSON-lines file of the raw records beside it.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.machine import machine_info
from gaitnet_mpc.mpc.cd_problem import centroidal_problem
from gaitnet_mpc.table2.cd_sqp import CDSQP, CDSQPConfig
from gaitnet_mpc.table2.cd_sqp import GROUPS as CD_GROUPS
from gaitnet_mpc.table2.joint_space import (
    SymbolicKinematics,
    joint_space_problem,
    max_dt_variables,
)
from gaitnet_mpc.table2.kd_sqp import ExplicitKDSQP, KDSQPConfig
from gaitnet_mpc.table2.problems import kd_solver, load_problems
from gaitnet_mpc.table2.run import JOINT_SQP
from gaitnet_mpc.table2.sqp_common import build_sqp, run_sqp
from gaitnet_mpc.table2.wbd_sqp import WBDSQP

#: The profiled methods, in table order.
METHODS = ("WBD-SQP", "WBD-SQP (point test)", "explicit KD-SQP", "CD-SQP", "CD-SQP (PIQP)")
#: ``sqpmethod`` statistics of the time split: column -> stats key.
SPLIT = {
    "qp": "t_wall_QP",
    "hess": "t_wall_nlp_hess_l",
    "jac": "t_wall_nlp_jac_fg",
    "callback": "t_wall_callback_fun",
}


@dataclass(frozen=True)
class Structure:
    """One built NLP: sizes, nonzeros and build time [s] (module docstring)."""

    method: str
    n_x: int
    n_g: int
    nnz_jac_g: int
    nnz_hess_l: int
    build_s: float


@dataclass(frozen=True)
class SolveProfile:
    """One timed solve (module docstring); ``t_*_s`` from ``sqpmethod``'s statistics."""

    method: str
    problem: int
    course: str
    time_s: float
    n_qps: int
    converged: bool
    status: str
    t_qp_s: float
    t_hess_s: float
    t_jac_s: float
    t_callback_s: float


def nlp_structure(method: str, solver: Any, build_s: float) -> Structure:
    """:class:`Structure` of an ``nlpsol`` built by :func:`~.sqp_common.build_sqp`."""
    jac = solver.get_function("nlp_jac_fg")
    hess = solver.get_function("nlp_hess_l")
    return Structure(
        method=method,
        n_x=int(solver.size1_in("x0")),
        n_g=int(solver.size1_in("lbg")),
        nnz_jac_g=int(jac.sparsity_out("jac_g_x").nnz()),
        nnz_hess_l=int(hess.sparsity_out(0).nnz()),
        build_s=build_s,
    )


def _split(stats: dict[str, Any]) -> dict[str, float]:
    return {name: float(stats.get(key, math.nan)) for name, key in SPLIT.items()}


class _Profiler:
    """The profiled methods, built as :mod:`~.run` builds them, with build timing."""

    def __init__(self, cop_fraction: float) -> None:
        self.cd_builder = kd_solver(cop_fraction=cop_fraction)
        self.cd = {
            "CD-SQP": CDSQP(CDSQPConfig(qpsol="qpoases", qpsol_options=(("sparse", True),))),
            "CD-SQP (PIQP)": CDSQP(CDSQPConfig(qpsol="piqp", convexify="regularize")),
        }
        kin = SymbolicKinematics(self.cd_builder.robot)
        self.kd_sqp = ExplicitKDSQP(kin, KDSQPConfig(sqp=JOINT_SQP))
        self.wbd_sqp = WBDSQP(kin, sqp=JOINT_SQP)
        # the same NLPs, stopped by each contact point's force and no moment
        self.wbd_point = WBDSQP(kin, sqp=JOINT_SQP, foot_wrench_test=False)
        self.wbd_point._cache = self.wbd_sqp._cache
        self.structures: list[Structure] = []
        self._cd_seen: set[tuple[str, int]] = set()

    def _joint(
        self, method: str, sqp: ExplicitKDSQP | WBDSQP, jp: Any, n: int, course: str
    ) -> SolveProfile:
        n_cached = len(sqp._cache)
        t0 = time.perf_counter()
        entry = sqp._build(jp)
        build_s = time.perf_counter() - t0
        if len(sqp._cache) > n_cached:  # a new NLP (the point test shares WBD's)
            self.structures.append(nlp_structure(method, entry["solver"], build_s))
        res = sqp.solve(jp)
        split = _split(entry["solver"].stats())
        return SolveProfile(
            method, n, course, res.solve_time_s, res.n_qps, res.converged, res.status,
            split["qp"], split["hess"], split["jac"], split["callback"],
        )  # fmt: skip

    def _cd(self, method: str, cd: Any, n: int, course: str) -> SolveProfile:
        sqp = self.cd[method]
        nlp, measure = sqp._nlp(cd)
        t0 = time.perf_counter()
        solver, test = build_sqp("cd_sqp", nlp, sqp.config, measure)  # fresh, as in run.py
        build_s = time.perf_counter() - t0
        key = (method, cd.horizon)
        if key not in self._cd_seen:
            self._cd_seen.add(key)
            self.structures.append(nlp_structure(method, solver, build_s))
        run = run_sqp(solver, test, sqp.config, CD_GROUPS, sqp._arguments(cd))
        split = _split(solver.stats())
        return SolveProfile(
            method, n, course, run.solve_time_s, run.n_qps, run.converged, run.status,
            split["qp"], split["hess"], split["jac"], split["callback"],
        )  # fmt: skip

    def __call__(self, rec: Any, n: int) -> list[SolveProfile]:
        cd = centroidal_problem(self.cd_builder, rec.problem)
        sps = int(rec.problem.timing.stages_per_step)
        jp = joint_space_problem(
            self.cd_builder, rec.problem, max_dt_variables(cd.horizon, sps), cd
        )
        return [
            self._joint("WBD-SQP", self.wbd_sqp, jp, n, rec.course),
            self._joint("WBD-SQP (point test)", self.wbd_point, jp, n, rec.course),
            self._joint("explicit KD-SQP", self.kd_sqp, jp, n, rec.course),
            self._cd("CD-SQP", cd, n, rec.course),
            self._cd("CD-SQP (PIQP)", cd, n, rec.course),
        ]


def profile_table2(
    problems_path: Path | str,
    n_problems: int,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[list[Structure], list[SolveProfile]]:
    """Profile the first ``n_problems`` problems of ``problems_path`` (module
    docstring); methods interleaved per problem, one process."""
    recorded = load_problems(problems_path, n_problems)
    prof = _Profiler(recorded[0].cop_fraction)
    solves: list[SolveProfile] = []
    for n, rec in enumerate(recorded):
        solves += prof(rec, n)
        if progress is not None:
            progress(n + 1, len(recorded))
    return prof.structures, solves


def _median(values: Sequence[float]) -> float:
    arr = np.asarray(values, dtype=float)
    arr = arr[np.isfinite(arr)]
    return float(np.median(arr)) if arr.size else math.nan


def profile_markdown(structures: Sequence[Structure], solves: Sequence[SolveProfile]) -> str:
    """Two tables: the built NLPs (median over the contact patterns met) and the
    per-solve split (means over problems; per-QP times are total / QPs)."""
    lines = [
        "| method | NLPs built | n_x | n_g | nnz(jac g) | nnz(hess L, triu) "
        "| build s (median, max) |",
        "|---|---|---|---|---|---|---|",
    ]
    for m in METHODS:
        rows = [s for s in structures if s.method == m]
        if not rows:
            continue
        med = {k: _median([getattr(s, k) for s in rows]) for k in asdict(rows[0]) if k != "method"}
        lines.append(
            f"| {m} | {len(rows)} | {med['n_x']:.0f} | {med['n_g']:.0f} | "
            f"{med['nnz_jac_g']:.0f} | {med['nnz_hess_l']:.0f} | "
            f"{med['build_s']:.2f}, {max(s.build_s for s in rows):.2f} |"
        )
    lines += [
        "",
        "| method | solves | mean ms | median ms | QPs per solve (mean, median) | converged "
        "| ms per QP iteration | QP share | Hessian share | Jacobian share | step-test share "
        "| statuses |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for m in METHODS:
        rows_s = [s for s in solves if s.method == m]
        if not rows_s:
            continue
        t = np.array([s.time_s for s in rows_s])
        qps = np.array([s.n_qps for s in rows_s], dtype=float)
        total = float(t.sum())
        shares = [sum(getattr(s, f"t_{k}_s") for s in rows_s) / total for k in SPLIT]
        statuses: dict[str, int] = {}
        for s in rows_s:
            statuses[s.status] = statuses.get(s.status, 0) + 1
        status_txt = ", ".join(f"{k} {v}" for k, v in sorted(statuses.items()))
        lines.append(
            f"| {m} | {len(rows_s)} | {1e3 * t.mean():.1f} | {1e3 * np.median(t):.1f} | "
            f"{qps.mean():.1f}, {np.median(qps):.0f} | "
            f"{100 * np.mean([s.converged for s in rows_s]):.0f} % | "
            f"{1e3 * total / max(qps.sum(), 1.0):.1f} | "
            + " | ".join(f"{100 * x:.0f} %" for x in shares)
            + f" | {status_txt} |"
        )
    return "\n".join(lines)


def _write_atomic(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def main(argv: Sequence[str] | None = None) -> int:
    """Command line (module docstring)."""
    ap = argparse.ArgumentParser(prog="python -m gaitnet_mpc.table2.diagnose")
    ap.add_argument("problems", type=Path, help="a problems.npz of `reproduce table2`")
    ap.add_argument("--problems", dest="n", type=int, default=20, help="first N (20)")
    ap.add_argument("--out", type=Path, required=True, help="Markdown report")
    args = ap.parse_args(argv)
    structures, solves = profile_table2(
        args.problems, args.n, progress=lambda i, n: print(f"profiled {i}/{n}", flush=True)
    )
    text = profile_markdown(structures, solves)
    machine = machine_info(("numpy", "casadi", "piqp"))
    _write_atomic(args.out, f"Machine: {machine}\n\n{text}\n")
    records: list[Structure | SolveProfile] = [*structures, *solves]
    raw = "".join(json.dumps(asdict(r)) + "\n" for r in records)
    _write_atomic(args.out.with_suffix(".jsonl"), raw)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


__all__ = [
    "METHODS",
    "SolveProfile",
    "Structure",
    "nlp_structure",
    "profile_markdown",
    "profile_table2",
]
