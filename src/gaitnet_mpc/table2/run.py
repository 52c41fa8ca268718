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

all cold from the same ``u^0`` (the references, weight shared by the stance feet) and
stopped by the same step test (Table X). The CD problem of each KD problem is built
outside the timed region. Each method's plan is also scored by eq. 18 on the CD problem
(:func:`~gaitnet_mpc.table2.cd_problem.cd_cost`; the proposed plan's states rolled out
through the exact dynamics), reported as the median ratio to CD-SQP's cost.
"""

from __future__ import annotations

import math
import os
import platform
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.table2.ad3 import AD3
from gaitnet_mpc.table2.cd_problem import CDSolution, cd_cost, centroidal_problem, rollout
from gaitnet_mpc.table2.cd_sqp import CDSQP, CDSQPConfig
from gaitnet_mpc.table2.problems import kd_solver, load_problems

#: The paper's Table II: method -> (variable size, normalised solve time, QPs per solve).
PAPER_TABLE2: dict[str, tuple[str, float, float]] = {
    "WBD-SQP": ("78h", 12.05, 18.2),
    "explicit KD-SQP": ("60h", 7.28, 17.7),
    "CD-SQP": ("34h-22", 1.00, 19.5),
    "AD(3)": ("27h-15, 21h-9, 16h-4", 2.58, 27.5),
    "proposed (implicit KD)": ("33h-21", 0.76, 17.1),
}
#: Our variable counts (formula in h) per method row.
OUR_VARIABLES: dict[str, str] = {
    "WBD-SQP": "not built",
    "explicit KD-SQP": "not built",
    "CD-SQP": "30h",
    "CD-SQP (OSQP)": "30h",
    "AD(3)": "24h, 12h, 18h",
    "proposed (implicit KD)": "33h+15",
}


def variable_counts(horizon: int) -> dict[str, list[int]]:
    """Variables of each built method at ``horizon`` (AD(3): one per sub-problem)."""
    from gaitnet_mpc.mpc.kd_layout import KDLayout

    ad = AD3.n_variables(horizon)
    return {
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
    """One row of the table: mean solve time [s], its ratio to CD-SQP's, mean QPs per
    solve, share converged, median eq. 18 cost ratio to CD-SQP, variable formula."""

    method: str
    mean_time_s: float
    time_ratio: float
    mean_qps: float
    convergence_rate: float
    cost_ratio: float
    variables: str


@dataclass(frozen=True)
class Table2Result:
    rows: list[MethodRow]
    n_problems: int
    horizon: int
    machine: str


def machine_line(packages: tuple[str, ...] = ("numpy", "casadi", "piqp", "mujoco", "pin")) -> str:
    """CPU, cores, Python and package versions (as ``benchmarks/machine.py`` prints)."""
    parts = [
        f"CPU: {platform.processor() or platform.machine()}",
        f"cores: {os.cpu_count()}",
        f"Python {platform.python_version()}",
    ]
    for name in packages:
        try:
            parts.append(f"{name} {version(name)}")
        except PackageNotFoundError:
            parts.append(f"{name} (not installed)")
    return ", ".join(parts)


def run_table2(
    problems_path: Path | str,
    n_problems: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    with_osqp: bool = False,
) -> Table2Result:
    """Solve the first ``n_problems`` recorded problems with every method (module
    docstring) and return the table's rows."""
    recorded = load_problems(problems_path, n_problems)
    if not recorded:
        raise ConfigError("problems", str(problems_path), "a file with at least one problem")
    kd = kd_solver()
    cd_builder = kd_solver()
    sqp = CDSQP(CDSQPConfig(qpsol="qpoases", qpsol_options=(("sparse", True),)))
    sqp_osqp = CDSQP(CDSQPConfig(qpsol="osqp")) if with_osqp else None
    ad3 = AD3()
    stats: dict[str, MethodStats] = {
        name: MethodStats()
        for name in ("proposed (implicit KD)", "CD-SQP", "CD-SQP (OSQP)", "AD(3)")
        if name != "CD-SQP (OSQP)" or with_osqp
    }
    horizon = 0
    for n, rec in enumerate(recorded):
        cd = centroidal_problem(cd_builder, rec.problem)
        horizon = cd.horizon
        sqp.prepare(cd)
        res = kd.solve(rec.problem)
        it = res.iterate
        plan = CDSolution(rollout(cd, it.f, it.tau, it.p_foot), it.f, it.tau, it.p_foot)
        stats["proposed (implicit KD)"].add(
            res.solve_time_s, res.n_qps, res.converged, cd_cost(cd, plan)
        )
        r_sqp = sqp.solve(cd)
        stats["CD-SQP"].add(r_sqp.solve_time_s, r_sqp.n_qps, r_sqp.converged, r_sqp.cost)
        if sqp_osqp is not None:
            sqp_osqp.prepare(cd)
            r_o = sqp_osqp.solve(cd)
            stats["CD-SQP (OSQP)"].add(r_o.solve_time_s, r_o.n_qps, r_o.converged, r_o.cost)
        r_ad = ad3.solve(cd)
        stats["AD(3)"].add(r_ad.solve_time_s, r_ad.n_qps, r_ad.converged, r_ad.cost)
        if progress is not None:
            progress(n + 1, len(recorded))
    base_time = float(np.mean(stats["CD-SQP"].times_s))
    base_cost = np.asarray(stats["CD-SQP"].costs)
    rows = []
    for name in ("WBD-SQP", "explicit KD-SQP"):
        rows.append(MethodRow(name, math.nan, math.nan, math.nan, math.nan, math.nan, "not built"))
    for name, st in stats.items():
        mean_t = float(np.mean(st.times_s))
        rows.append(
            MethodRow(
                method=name,
                mean_time_s=mean_t,
                time_ratio=mean_t / base_time,
                mean_qps=float(np.mean(st.qps)),
                convergence_rate=float(np.mean(st.converged)),
                cost_ratio=float(np.nanmedian(np.asarray(st.costs) / base_cost)),
                variables=OUR_VARIABLES[name],
            )
        )
    return Table2Result(rows, len(recorded), horizon, machine_line())


def _fmt(x: float, spec: str) -> str:
    return "n/a" if not math.isfinite(x) else format(x, spec)


def table2_markdown(result: Table2Result) -> str:
    """The measured table beside the paper's (Markdown)."""
    lines = [
        f"# Table II reproduced ({result.n_problems} problems, h = {result.horizon})",
        "",
        f"Machine: {result.machine}",
        "",
        "| method | variables (ours) | variables (paper) | solve time / CD-SQP (ours) "
        "| (paper) | mean solve time ms | QPs per solve (ours) | (paper) | converged "
        "| eq. 18 cost / CD-SQP (median) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in result.rows:
        key = row.method if row.method in PAPER_TABLE2 else ""
        paper = PAPER_TABLE2.get(key, ("", math.nan, math.nan))
        lines.append(
            f"| {row.method} | {row.variables} | {paper[0] or '-'} | "
            f"{_fmt(row.time_ratio, '.2f')} | {_fmt(paper[1], '.2f')} | "
            f"{_fmt(1e3 * row.mean_time_s, '.1f')} | {_fmt(row.mean_qps, '.1f')} | "
            f"{_fmt(paper[2], '.1f')} | {_fmt(100 * row.convergence_rate, '.0f')} % | "
            f"{_fmt(row.cost_ratio, '.4f')} |"
        )
    lines += [
        "",
        "Same problems (recorded from the `kd` controller in closed loop), cold from the "
        "same u^0, stopped by the Table X step test; CD-SQP = CasADi sqpmethod + qpOASES "
        "(sparse), exact Hessian. Proposed = Algorithm 1 with PIQP, whose references are "
        "re-made by IK each iteration (line 9); its cost column scores its plan on the CD "
        "problem's frozen references.",
    ]
    return "\n".join(lines)


def reproduce_table2(
    out_dir: Path | str,
    n_problems: int = 40,
    seconds_per_course: float = 3.0,
    every: int = 2,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Record problems into ``out_dir/problems.npz`` unless present (every ``every``-th
    problem of ``seconds_per_course`` of walking on each of :data:`TABLE2_COURSES`,
    courses alternating), run :func:`run_table2` on the first ``n_problems`` and write
    ``out_dir/table2.md``; returns that path."""
    from gaitnet_mpc.table2.problems import (
        TABLE2_COURSES,
        RecordingSpec,
        record_problems,
        save_problems,
    )

    out = Path(out_dir)
    path = out / "problems.npz"
    if not path.exists():
        per_course = [
            record_problems(RecordingSpec(course=c, duration_s=seconds_per_course))[::every]
            for c in TABLE2_COURSES
        ]
        problems, courses = [], []
        for i in range(max(len(x) for x in per_course)):  # alternate the courses
            for course, got in zip(TABLE2_COURSES, per_course, strict=True):
                if i < len(got):
                    problems.append(got[i])
                    courses.append(course)
        save_problems(path, problems, courses)
    result = run_table2(path, n_problems, progress=progress)
    report = out / "table2.md"
    report.write_text(table2_markdown(result) + "\n")
    return report


__all__ = [
    "OUR_VARIABLES",
    "PAPER_TABLE2",
    "MethodRow",
    "Table2Result",
    "machine_line",
    "reproduce_table2",
    "run_table2",
    "table2_markdown",
    "variable_counts",
]
