"""Table II: solve the same recorded MPC problems with every method and tabulate.

:func:`run_table2` loads ``N`` problems recorded by :mod:`~gaitnet_mpc.table2.problems`
and, problem by problem (methods interleaved, so that machine load hits all alike), solves
each with

* **proposed**: Algorithm 1 (:class:`~gaitnet_mpc.mpc.sequential.SequentialKDMPC`) on the
  :class:`KDProblem` itself, configured as the ``kd`` controller;
* **CD-SQP** (the normalising baseline): :class:`~gaitnet_mpc.table2.cd_sqp.CDSQP` with
  qpOASES (sparse mode), and with ``with_osqp`` an extra row with OSQP (which asserts on
  the indefinite QPs of the exact Hessian now and then: counted as not converged);
* **AD(3)**: :class:`~gaitnet_mpc.table2.ad3.AD3`;
* with ``with_joint_space``: **explicit KD-SQP** (:class:`~gaitnet_mpc.table2.kd_sqp.
  ExplicitKDSQP`, eqs. 5-9) and **WBD-SQP** (:class:`~gaitnet_mpc.table2.wbd_sqp.WBDSQP`,
  eqs. 1-4), both with one dt variable per step, on the problem mapped to joint space
  (:func:`~gaitnet_mpc.table2.joint_space.joint_space_problem`), ``sqpmethod`` with PIQP
  on the regularised exact Hessian (qpOASES needed 92 s per solve on the 650-variable KD
  QPs, sparse mode, 310 s dense: :data:`JOINT_SQP`);

all cold from the same ``u^0`` (the references, weight shared by the stance feet) and
stopped by the same step test (Table X). The CD problem of each KD problem is built
outside the timed region. Each method's plan is also scored by eq. 18 on the CD problem
(:func:`~gaitnet_mpc.mpc.cd_problem.cd_cost`; the proposed plan's states rolled out
through the exact dynamics), reported as the median ratio to CD-SQP's cost.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.machine import machine_info
from gaitnet_mpc.mpc.cd_problem import CDSolution, cd_cost, centroidal_problem, rollout
from gaitnet_mpc.table2.ad3 import AD3
from gaitnet_mpc.table2.cd_sqp import CDSQP, CDSQPConfig
from gaitnet_mpc.table2.joint_space import (
    SymbolicKinematics,
    joint_space_problem,
    max_dt_variables,
)
from gaitnet_mpc.table2.kd_sqp import ExplicitKDSQP, KDSQPConfig
from gaitnet_mpc.table2.problems import RecordedProblem, kd_solver, load_problems
from gaitnet_mpc.table2.sqp_common import SQPConfig
from gaitnet_mpc.table2.wbd_sqp import WBDSQP

#: ``sqpmethod`` settings of the joint-space baselines: PIQP on the exact Hessian made
#: positive definite by CasADi's ``regularize`` (qpOASES: module docstring).
JOINT_SQP = SQPConfig(qpsol="piqp", convexify="regularize")

#: The paper's Table II: method -> (variable size, normalised solve time, QPs per solve).
PAPER_TABLE2: dict[str, tuple[str, float, float]] = {
    "WBD-SQP": ("78h", 12.05, 18.2),
    "explicit KD-SQP": ("60h", 7.28, 17.7),
    "CD-SQP": ("34h-22", 1.00, 19.5),
    "AD(3)": ("27h-15, 21h-9, 16h-4", 2.58, 27.5),
    "proposed (implicit KD)": ("33h-21", 0.76, 17.1),
}
#: Solves per simulated second of the ``kd`` walk (a replan every 20 ms, plus the step
#: starts): sizes the flat recording.
SOLVES_PER_S = 50.0
#: Seeded stepping-stone layouts tried at most when recording the stones half.
MAX_STONE_SEEDS = 100
#: Our variable counts (formula in h) per method row.
OUR_VARIABLES: dict[str, str] = {
    "WBD-SQP": "103h+n_dt",
    "explicit KD-SQP": "64h+n_dt",
    "CD-SQP": "30h",
    "CD-SQP (OSQP)": "30h",
    "AD(3)": "24h, 12h, 18h",
    "proposed (implicit KD)": "33h+15",
}


def variable_counts(horizon: int) -> dict[str, list[int]]:
    """Variables of each built method at ``horizon`` (AD(3): one per sub-problem)."""
    from gaitnet_mpc.mpc.kd_layout import KDLayout

    ad = AD3.n_variables(horizon)
    nq, nv, nj, nc = 25, 24, 18, 4  # humanoid3d: qpos, qvel, joints, contact points
    return {
        "WBD-SQP": [(nq + 2 * nv + nj + 3 * nc) * horizon],
        "explicit KD-SQP": [(nq + nv + 15) * horizon],
        "CD-SQP": [CDSQP.n_variables(horizon)],
        "AD(3)": [ad["forces"], ad["com"], ad["footholds"]],
        "proposed (implicit KD)": [KDLayout(horizon).n],
    }


@dataclass
class MethodStats:
    """Per-problem records of one method."""

    times_s: list[float] = field(default_factory=list)
    qps: list[int] = field(default_factory=list)
    converged: list[bool] = field(default_factory=list)
    costs: list[float] = field(default_factory=list)

    def add(self, time_s: float, n_qps: int, converged: bool, cost: float) -> None:
        self.times_s.append(time_s)
        self.qps.append(n_qps)
        self.converged.append(converged)
        self.costs.append(cost)


@dataclass(frozen=True)
class MethodRow:
    """One row of the table: mean solve time [s] and its ratio to CD-SQP's, the median
    of the per-problem time ratios to CD-SQP (robust to one slow solve), mean QPs per
    solve, share converged, median eq. 18 cost ratio to CD-SQP, variable formula."""

    method: str
    mean_time_s: float
    time_ratio: float
    median_time_ratio: float
    mean_qps: float
    convergence_rate: float
    cost_ratio: float
    variables: str


@dataclass(frozen=True)
class Table2Result:
    rows: list[MethodRow]
    n_problems: int
    courses: dict[str, int]
    horizon: int
    machine: str


def run_table2(
    problems_path: Path | str,
    n_problems: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    with_osqp: bool = False,
    with_joint_space: bool = True,
    records_path: Path | str | None = None,
) -> Table2Result:
    """Solve the first ``n_problems`` recorded problems with every method (module
    docstring) and return the table's rows; ``with_joint_space=False`` skips the slow
    explicit KD-SQP and WBD-SQP columns (their NLPs take 2-20 s to build per contact
    pattern).

    With ``records_path`` (a JSON-lines file), each problem's results are appended to it
    as soon as the problem is solved, and problems already there (from an interrupted
    run with the same problems and columns) are not solved again.
    """
    recorded = load_problems(problems_path, n_problems)
    if not recorded:
        raise ConfigError("problems", str(problems_path), "a file with at least one problem")
    names = ["proposed (implicit KD)", "CD-SQP", "AD(3)"]
    names += ["CD-SQP (OSQP)"] if with_osqp else []
    names += ["explicit KD-SQP", "WBD-SQP"] if with_joint_space else []
    done = _read_records(records_path, names) if records_path is not None else {}
    solve = _ProblemSolver(with_osqp, with_joint_space, recorded[0].cop_fraction)
    horizon = 0
    for n, rec in enumerate(recorded):
        if n not in done:
            done[n] = solve(rec)
            if records_path is not None:
                _append_record(records_path, n, rec.course, done[n])
        horizon = int(rec.problem.timing.dts_s.size)
        if progress is not None:
            progress(n + 1, len(recorded))
    stats: dict[str, MethodStats] = {name: MethodStats() for name in names}
    for n in range(len(recorded)):
        for name in names:
            stats[name].add(*done[n][name])
    base_time = float(np.mean(stats["CD-SQP"].times_s))
    base_cost = np.asarray(stats["CD-SQP"].costs)
    rows = []
    order = ["WBD-SQP", "explicit KD-SQP", "CD-SQP", "CD-SQP (OSQP)", "AD(3)"]
    order += ["proposed (implicit KD)"]
    for name in order:
        if name not in stats:
            if name in ("WBD-SQP", "explicit KD-SQP"):
                nan = math.nan
                rows.append(MethodRow(name, nan, nan, nan, nan, nan, nan, "skipped"))
            continue
        st = stats[name]
        mean_t = float(np.mean(st.times_s))
        rows.append(
            MethodRow(
                method=name,
                mean_time_s=mean_t,
                time_ratio=mean_t / base_time,
                median_time_ratio=_median_ratio(
                    np.asarray(st.times_s), np.asarray(stats["CD-SQP"].times_s)
                ),
                mean_qps=float(np.mean(st.qps)),
                convergence_rate=float(np.mean(st.converged)),
                cost_ratio=_median_ratio(np.asarray(st.costs), base_cost),
                variables=OUR_VARIABLES[name],
            )
        )
    courses: dict[str, int] = {}
    for rec in recorded:
        courses[rec.course] = courses.get(rec.course, 0) + 1
    return Table2Result(
        rows,
        len(recorded),
        courses,
        horizon,
        machine_info(("numpy", "casadi", "piqp", "mujoco", "pin")),
    )


#: One method's result on one problem: (solve time [s], QPs, converged, eq. 18 cost).
Record = tuple[float, int, bool, float]


class _ProblemSolver:
    """Every method, built once, solving one recorded problem (methods interleaved)."""

    def __init__(self, with_osqp: bool, with_joint_space: bool, cop_fraction: float) -> None:
        self.kd = kd_solver(cop_fraction=cop_fraction)
        self.cd_builder = kd_solver(cop_fraction=cop_fraction)
        self.sqp = CDSQP(CDSQPConfig(qpsol="qpoases", qpsol_options=(("sparse", True),)))
        self.sqp_osqp = CDSQP(CDSQPConfig(qpsol="osqp")) if with_osqp else None
        self.ad3 = AD3()
        self.kd_sqp: ExplicitKDSQP | None = None
        self.wbd_sqp: WBDSQP | None = None
        if with_joint_space:
            kin = SymbolicKinematics(self.kd.robot)
            self.kd_sqp = ExplicitKDSQP(kin, KDSQPConfig(sqp=JOINT_SQP))
            self.wbd_sqp = WBDSQP(kin, sqp=JOINT_SQP)

    def __call__(self, rec: RecordedProblem) -> dict[str, Record]:
        out: dict[str, Record] = {}
        cd = centroidal_problem(self.cd_builder, rec.problem)
        self.sqp.prepare(cd)
        res = self.kd.solve(rec.problem)
        it = res.iterate
        plan = CDSolution(rollout(cd, it.f, it.tau, it.p_foot), it.f, it.tau, it.p_foot)
        out["proposed (implicit KD)"] = (
            res.solve_time_s,
            res.n_qps,
            res.converged,
            cd_cost(cd, plan),
        )
        r = self.sqp.solve(cd)
        out["CD-SQP"] = (r.solve_time_s, r.n_qps, r.converged, r.cost)
        if self.sqp_osqp is not None:
            self.sqp_osqp.prepare(cd)
            r = self.sqp_osqp.solve(cd)
            out["CD-SQP (OSQP)"] = (r.solve_time_s, r.n_qps, r.converged, r.cost)
        r_ad = self.ad3.solve(cd)
        out["AD(3)"] = (r_ad.solve_time_s, r_ad.n_qps, r_ad.converged, r_ad.cost)
        if self.kd_sqp is not None and self.wbd_sqp is not None:
            sps = int(rec.problem.timing.stages_per_step)
            jp = joint_space_problem(
                self.cd_builder, rec.problem, max_dt_variables(cd.horizon, sps), cd
            )
            self.kd_sqp.prepare(jp)
            self.wbd_sqp.prepare(jp)
            r_kd = self.kd_sqp.solve(jp)
            out["explicit KD-SQP"] = (r_kd.solve_time_s, r_kd.n_qps, r_kd.converged, r_kd.eq18_cost)
            r_wb = self.wbd_sqp.solve(jp)
            out["WBD-SQP"] = (r_wb.solve_time_s, r_wb.n_qps, r_wb.converged, r_wb.eq18_cost)
        return out


def _read_records(path: Path | str, names: list[str]) -> dict[int, dict[str, Record]]:
    """Problem index -> results, from a records file (missing file: none); a record
    without every column of ``names`` is ignored (solved again)."""
    path = Path(path)
    if not path.exists():
        return {}
    done: dict[int, dict[str, Record]] = {}
    for line in path.read_text().splitlines():
        try:
            row = json.loads(line)
        except json.JSONDecodeError:  # a line cut by an interruption
            continue
        methods = row.get("methods", {})
        if all(name in methods for name in names):
            done[int(row["problem"])] = {
                name: (float(t), int(q), bool(c), float(cost))
                for name, (t, q, c, cost) in methods.items()
            }
    return done


def _append_record(path: Path | str, n: int, course: str, results: dict[str, Record]) -> None:
    """Append one problem's results as one JSON line, flushed to disk."""
    line = json.dumps({"problem": n, "course": course, "methods": results})
    with open(path, "a", encoding="utf-8") as fh:
        fh.write(line + "\n")
        fh.flush()
        os.fsync(fh.fileno())


def _median_ratio(costs: np.ndarray, base: np.ndarray) -> float:
    """Median of ``costs / base`` over the finite entries (NaN if none)."""
    ratio = costs / base
    ratio = ratio[np.isfinite(ratio)]
    return float(np.median(ratio)) if ratio.size else math.nan


def _fmt(x: float, spec: str) -> str:
    return "n/a" if not math.isfinite(x) else format(x, spec)


def table2_markdown(result: Table2Result) -> str:
    """The measured table beside the paper's (Markdown)."""
    lines = [
        f"# Table II reproduced ({result.n_problems} problems, h = {result.horizon})",
        "",
        f"Machine: {result.machine}",
        "",
        "| method | variables (ours) | variables (paper) | mean solve time / CD-SQP's (ours) "
        "| (paper) | median of time / CD-SQP per problem | mean solve time ms "
        "| QPs per solve (ours) | (paper) | converged | eq. 18 cost / CD-SQP (median) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in result.rows:
        key = row.method if row.method in PAPER_TABLE2 else ""
        paper = PAPER_TABLE2.get(key, ("", math.nan, math.nan))
        lines.append(
            f"| {row.method} | {row.variables} | {paper[0] or '-'} | "
            f"{_fmt(row.time_ratio, '.2f')} | {_fmt(paper[1], '.2f')} | "
            f"{_fmt(row.median_time_ratio, '.2f')} | {_fmt(1e3 * row.mean_time_s, '.1f')} | "
            f"{_fmt(row.mean_qps, '.1f')} | "
            f"{_fmt(paper[2], '.1f')} | {_fmt(100 * row.convergence_rate, '.0f')} % | "
            f"{_fmt(row.cost_ratio, '.4f')} |"
        )
    lines += [
        "",
        "Problems: "
        + ", ".join(f"{n} {course}" for course, n in result.courses.items())
        + " (recorded from the `kd` controller in closed loop at 0.75 m/s, fixed dt "
        "0.05 s; the stones with the footstep preview, on the built-in layout and then "
        "seeded ones, kept while the base is over the stones).",
        "",
        "Same problems, cold from the "
        "same u^0, stopped by the Table X step test; CD-SQP = CasADi sqpmethod + qpOASES "
        "(sparse), exact Hessian. Proposed = Algorithm 1 with PIQP, whose references are "
        "re-made by IK each iteration (line 9); its cost column scores its plan on the CD "
        "problem's frozen references.",
        "",
        "Explicit KD-SQP (eqs. 5-9) and WBD-SQP (eqs. 1-4) keep q, qdot in the variables "
        "and one dt per step in [0.045, 0.07] s (the step in progress keeps its recorded "
        "stage lengths unless the problem is a step start); sqpmethod with PIQP on the "
        "regularised exact Hessian (qpOASES took 92 s per KD solve); the same step test "
        "on the CoM and foot centres (forward kinematics), forces, moments and dt, and a "
        "converged solve must also be feasible to 1e-6. KD-SQP's cost column scores its "
        "plan (p_c(q), A_G(q) qdot, its own dt) by eq. 18; WBD-SQP minimises eq. 2, not "
        "comparable (n/a). n_dt: steps in the horizon (2-3).",
    ]
    return "\n".join(lines)


def record_table2_problems(path: Path | str, n_problems: int) -> Path:
    """Record ``n_problems`` problems into ``path`` (Table II's inputs), alternating the
    courses: half on ``flat`` (every solve after the start-up transient of one walk),
    half on the stones, with the footstep preview: the built-in ``stepping-stones``
    first, then seeded layouts (seeds 0, 1, ...) until enough, each kept only while the
    base is over the stones (:class:`RecordingSpec`, ``stones_only``)."""
    from gaitnet_mpc.mpc.sequential import KDProblem
    from gaitnet_mpc.table2.problems import RecordingSpec, record_problems, save_problems

    n_stones = n_problems // 2
    n_flat = n_problems - n_stones
    flat_spec = RecordingSpec("flat", duration_s=0.3 + n_flat / SOLVES_PER_S + 1.0)
    flat = record_problems(flat_spec)[:n_flat]
    stones: list[KDProblem] = []
    seeds: list[int | None] = [None, *range(MAX_STONE_SEEDS)]
    for seed in seeds:
        if len(stones) >= n_stones:
            break
        spec = RecordingSpec(
            "stepping-stones",
            duration_s=30.0,
            skip_s=0.0,
            preview=True,
            seed=seed,
            stones_only=True,
            cop_fraction=flat_spec.cop_fraction,
        )
        stones += record_problems(spec)
    stones = stones[:n_stones]
    if len(flat) < n_flat or len(stones) < n_stones:
        raise RuntimeError(
            f"recorded {len(flat)} flat and {len(stones)} stepping-stone problems, "
            f"wanted {n_flat} and {n_stones}"
        )
    problems, courses = [], []
    for i in range(n_flat):  # alternate the courses
        for got, course in ((flat, "flat"), (stones, "stepping-stones")):
            if i < len(got):
                problems.append(got[i])
                courses.append(course)
    return save_problems(path, problems, courses, cop_fraction=flat_spec.cop_fraction)


def reproduce_table2(
    out_dir: Path | str,
    n_problems: int = 40,
    progress: Callable[[int, int], None] | None = None,
    with_joint_space: bool = True,
) -> Path:
    """Table II on ``n_problems`` problems: record them into ``out_dir/problems.npz``
    (:func:`record_table2_problems`) unless a file with at least that many is there,
    solve them with :func:`run_table2` (resumable through ``out_dir/records.jsonl``:
    run it again after an interruption) and write ``out_dir/table2.md``; returns that
    path. ``with_joint_space=False`` skips explicit KD-SQP and WBD-SQP."""
    from gaitnet_mpc.table2.problems import problem_count

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "problems.npz"
    if not path.exists() or problem_count(path) < n_problems:
        if path.exists():  # records of the old, smaller set no longer apply
            (out / "records.jsonl").unlink(missing_ok=True)
        tmp = record_table2_problems(out / "problems.tmp.npz", n_problems)
        os.replace(tmp, path)
    result = run_table2(
        path,
        n_problems,
        progress=progress,
        with_joint_space=with_joint_space,
        records_path=out / "records.jsonl",
    )
    report = out / "table2.md"
    tmp_report = report.with_suffix(".md.tmp")
    tmp_report.write_text(table2_markdown(result) + "\n")
    os.replace(tmp_report, report)
    return report


__all__ = [
    "JOINT_SQP",
    "OUR_VARIABLES",
    "PAPER_TABLE2",
    "MethodRow",
    "Table2Result",
    "record_table2_problems",
    "reproduce_table2",
    "run_table2",
    "table2_markdown",
    "variable_counts",
]
