"""Whole-body NMPC (Sec. III-A) solve times: IPOPT and FATROP on the same problems.

Problems per robot: standing (double support) and stepping (vx = 0.3 m/s, alternating single
support, a step every h' = 5 stages, dt = 0.05 / 0.06 s for the current / next step).

* cold: the measured state is the nominal pose with random joint offsets (0.05 rad) and
  velocities (0.1 rad/s), solved from :meth:`WholeBodyMPC.cold_start`;
* warm: a receding-horizon sequence on the model itself: each call's measured state is the
  previous solution's node 1 plus the same kind of noise, the gait phase advances one
  stage, and the previous solution shifted by one stage (primal variables and duals,
  :meth:`WholeBodyMPC.shift`) is the initial guess, solved with the warm-start settings
  (:data:`gaitnet_mpc.mpc.wholebody.solvers.WARM_OPTIONS`: small initial barrier parameter).

Every solver (one per contact schedule, cold or warm settings) is built before the timed
calls; the build time is reported apart. Wall and CPU (process) time are both reported:
the machine is shared, and the wall time of a single-threaded solve grows with the load.

Usage: ``python benchmarks/wbmpc_solvers.py [--quick]`` -> ``benchmarks/results/wbmpc.md``.
"""

from __future__ import annotations

import os

# One BLAS thread per solver process, set before numpy/casadi load their BLAS: CasADi's
# bundled OpenBLAS otherwise runs IPOPT's MUMPS on every core, doubling the CPU time on 2
# cores for no wall-clock gain (humanoid3d stepping: 185 ms wall, 370 ms CPU).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.mpc.wholebody import (
    WBConfig,
    WBSolution,
    WholeBodyMPC,
    make_problem,
)
from gaitnet_mpc.robots import FEET, RobotModel, load_robot
from machine import machine_info

RESULTS = Path(__file__).parent / "results" / "wbmpc.md"


@dataclass
class Stats:
    times_s: list[float]
    cpu_s: list[float]
    iterations: list[int]
    violations: list[float]
    failures: int

    def row(self) -> str:
        t, c = np.array(self.times_s) * 1e3, np.array(self.cpu_s) * 1e3
        return (
            f"{len(t)} | {np.median(t):.0f} | {np.percentile(t, 99):.0f} | "
            f"{np.median(c):.0f} | {np.percentile(c, 99):.0f} | {np.mean(c):.0f} | "
            f"{np.median(self.iterations):.0f} ({max(self.iterations)}) | "
            f"{max(self.violations):.1e} | {self.failures}"
        )


def _noisy(robot: RobotModel, qpos: np.ndarray, qvel: np.ndarray, rng: np.random.Generator):
    qpos, qvel = qpos.copy(), qvel.copy()
    qpos[robot.joint_qpos_adr] += 0.05 * rng.standard_normal(robot.n_joints)
    qpos[robot.joint_qpos_adr] = np.clip(
        qpos[robot.joint_qpos_adr], robot.joint_lower_rad, robot.joint_upper_rad
    )
    qvel[robot.joint_dof_adr] += 0.1 * rng.standard_normal(robot.n_joints)
    return qpos, qvel


def _problem(robot, cfg, qpos, qvel, walking: bool, call: int):
    q_nom = robot.standing_qpos()
    if not walking:
        return make_problem(cfg, qpos, qvel, q_nom, Command(), robot.spec.planar)
    hp = cfg.stages_per_step
    step, phase = divmod(call, hp)
    dts = (0.05, 0.06) if step % 2 == 0 else (0.06, 0.05)
    return make_problem(
        cfg,
        qpos,
        qvel,
        q_nom,
        Command(vx_mps=0.3),
        robot.spec.planar,
        step_dt_s=dts,
        phase_stage=phase,
        stance_foot=FEET[step % 2],
    )


def _record(stats: Stats, sol: WBSolution, cpu_s: float) -> None:
    stats.times_s.append(sol.solve_time_s)
    stats.cpu_s.append(cpu_s)
    stats.iterations.append(sol.iterations)
    stats.violations.append(sol.constraint_violation)
    stats.failures += int(not sol.success)


def run_case(robot: RobotModel, variant: str, walking: bool, n_cold: int, n_warm: int) -> dict:
    """``variant`` is a solver name, or ``name:N`` for that solver capped at N iterations."""
    cfg = WBConfig()
    solver, _, cap = variant.partition(":")
    options = {f"{solver}.max_iter": int(cap)} if cap else {}
    mpc = WholeBodyMPC(robot, cfg, solver=solver, solver_options=options)
    rng = np.random.default_rng(0)
    q_nom, v_zero = robot.standing_qpos(), np.zeros(robot.nv)
    # Build every solver the calls will use first, so that no solve time includes a build.
    builds = [mpc.prepare(_problem(robot, cfg, q_nom, v_zero, walking, 0))]
    for call in range(1, n_warm + 1 if walking else 2):
        built = mpc.prepare(_problem(robot, cfg, q_nom, v_zero, walking, call), warm=True)
        builds += [built] if built > 0.0 else []

    def solve(problem, warm=None) -> tuple[WBSolution, float]:
        cpu0 = time.process_time()
        sol = mpc.solve(problem, warm_start=warm)
        return sol, time.process_time() - cpu0

    cold = Stats([], [], [], [], 0)
    for _ in range(n_cold):
        qpos, qvel = _noisy(robot, q_nom, v_zero, rng)
        _record(cold, *solve(_problem(robot, cfg, qpos, qvel, walking, 0)))
    warm = Stats([], [], [], [], 0)
    sol, _ = solve(_problem(robot, cfg, q_nom, v_zero, walking, 0))
    for call in range(1, n_warm + 1):
        qpos, qvel = _noisy(robot, sol.qpos[1], sol.qvel[1], rng)
        if not robot.spec.planar:
            qpos[3:7] /= np.linalg.norm(qpos[3:7])
        sol, cpu = solve(_problem(robot, cfg, qpos, qvel, walking, call), mpc.shift(sol))
        _record(warm, sol, cpu)
    return {"cold": cold, "warm": warm, "builds": builds, "n_var": mpc.n_variables()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="3 cold, 5 warm solves per case")
    parser.add_argument("--robots", nargs="+", default=["biped2d", "humanoid3d"])
    parser.add_argument(
        "--solvers",
        nargs="+",
        default=["ipopt", "fatrop", "ipopt:5", "fatrop:5"],
        help="solver names; name:N caps the iterations at N (a real-time-iteration budget)",
    )
    args = parser.parse_args()
    n_cold, n_warm = (3, 5) if args.quick else (10, 20)
    lines = [
        "# Whole-body NMPC (Sec. III-A): solver comparison",
        "",
        f"Machine: {machine_info(('numpy', 'mujoco', 'pin', 'casadi'))}; "
        f"OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}; load average at start "
        f"{os.getloadavg()[0]:.1f} (shared machine; the 'load' column is the 1-min load "
        "average after each case).",
        "",
        "Generated by `benchmarks/wbmpc_solvers.py` (problem definitions in its docstring). "
        "h = 10 stages, Table VI weights and limits, IPOPT (MUMPS) and FATROP through CasADi "
        "3.8.2 with exact Hessians of the expanded SX graph, tolerance 1e-6. Times in ms; "
        "p99 of few samples is close to the maximum; iterations: median (max); violation: "
        "max over the solves of the largest bound/constraint violation. `name:5` rows cap "
        "the solver at 5 iterations (a fixed real-time budget): their 'failed' column counts "
        "the solves stopped before convergence, and the violation says how far from "
        "feasible the returned point is. Interpretation and decisions: "
        "`docs/design/wholebody_nmpc.md`.",
        "",
        "| robot | problem | solver | vars | build [s] | start | n | wall median [ms] "
        "| wall p99 [ms] | CPU median [ms] | CPU p99 [ms] | CPU mean [ms] | iterations "
        "| violation | failed | load |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name in args.robots:
        robot = load_robot(name)
        for walking in (False, True):
            for solver in args.solvers:
                res = run_case(robot, solver, walking, n_cold, n_warm)
                build = f"{np.mean(res['builds']):.1f} x {len(res['builds'])}"
                label = "stepping" if walking else "standing"
                for start in ("cold", "warm"):
                    lines.append(
                        f"| {name} | {label} | {solver} | {res['n_var']} | {build} | {start} | "
                        f"{res[start].row()} | {os.getloadavg()[0]:.1f} |"
                    )
                print(lines[-2], lines[-1], sep="\n", flush=True)
    RESULTS.write_text("\n".join(lines) + "\n")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
