"""Real-time factor of the bare simulator and of the standing controller.

Both are measured in one run, interleaved (A B A B ...), so their ratio is meaningful on
a shared, noisy machine. Run: ``.venv/bin/python benchmarks/bench_sim.py``.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from common import machine_info
from gaitnet_mpc.control.stand import StandController
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course

SIM_SECONDS = 2.0
REPEATS = 3


def bare(robot_name: str) -> float:
    robot = load_robot(robot_name)
    sim = Simulator(robot, load_course("flat"))
    tau = np.zeros(robot.n_joints)
    t0 = time.perf_counter()
    for _ in range(round(SIM_SECONDS / sim.config.timestep_s)):
        sim.step(tau)
    return SIM_SECONDS / (time.perf_counter() - t0)


def raw_mujoco(robot_name: str) -> float:
    """mj_step alone on the same scene: the floor under the package's read-out costs."""
    import mujoco

    robot = load_robot(robot_name)
    sim = Simulator(robot, load_course("flat"))
    t0 = time.perf_counter()
    for _ in range(round(SIM_SECONDS / sim.config.timestep_s)):
        mujoco.mj_step(sim.model, sim.data)
    return SIM_SECONDS / (time.perf_counter() - t0)


def stand(robot_name: str) -> float:
    robot = load_robot(robot_name)
    sim = Simulator(robot, load_course("flat"))
    ctrl = StandController(robot)
    ctrl.reset(sim.state())
    t0 = time.perf_counter()
    for _ in range(round(SIM_SECONDS / sim.config.timestep_s)):
        sim.step(ctrl.compute(sim.state()))
    return SIM_SECONDS / (time.perf_counter() - t0)


def main() -> None:
    rows = [
        "| robot | raw mj_step RTF | bare simulator RTF | stand controller RTF | bare / stand |",
        "|---|---|---|---|---|",
    ]
    for name in ("humanoid3d", "biped2d"):
        r, b, s = [], [], []
        for _ in range(REPEATS):
            r.append(raw_mujoco(name))
            b.append(bare(name))
            s.append(stand(name))
        rr, rb, rs = (float(np.median(x)) for x in (r, b, s))
        rows.append(f"| {name} | {rr:.1f} | {rb:.1f} | {rs:.2f} | {rb / rs:.1f}x |")
    report = "\n".join(
        [
            "# Simulator real-time factor",
            "",
            f"{machine_info()}",
            "",
            f"1 kHz, {SIM_SECONDS:g} s simulated per run, median of {REPEATS} interleaved runs; "
            "RTF = simulated time / wall time (higher is faster). The bare simulator steps "
            "with zero torques and includes the state read-out and fall detection.",
            "",
            *rows,
            "",
        ]
    )
    out = Path(__file__).parent / "results" / "sim.md"
    out.write_text(report)
    print(report)


if __name__ == "__main__":
    main()
