"""Real-time factor of raw ``mj_step``, the bare simulator and the standing controller.

All three are measured in one run, interleaved (A B C A B C ...), so their ratios are
meaningful on a shared, noisy machine. The bare simulator is the one script that needs a
:class:`Simulator` without a scenario: it times the physics alone. Run
(``make bench``): ``.venv/bin/python benchmarks/bench_sim.py [--repeats 3] [--out NAME]``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

from common import add_out_option, machine_info, write_report
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.scenario import build_episode, make_scenario
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course

SIM_SECONDS = 2.0


def rtf(sim: Simulator, step: Callable[[], object]) -> float:
    """Real-time factor of ``SIM_SECONDS`` of ``step()`` calls at the simulator's rate."""
    t0 = time.perf_counter()
    for _ in range(round(SIM_SECONDS / sim.config.timestep_s)):
        step()
    return SIM_SECONDS / (time.perf_counter() - t0)


def raw_mujoco(robot_name: str) -> float:
    """mj_step alone on the same scene: the floor under the package's read-out costs."""
    import mujoco

    sim = Simulator(load_robot(robot_name), load_course("flat"))
    return rtf(sim, lambda: mujoco.mj_step(sim.model, sim.data))


def bare(robot_name: str) -> float:
    robot = load_robot(robot_name)
    sim = Simulator(robot, load_course("flat"))
    tau = np.zeros(robot.n_joints)
    return rtf(sim, lambda: sim.step(tau))


def stand(robot_name: str) -> float:
    ep = build_episode(make_scenario(robot=robot_name, controller="stand", duration_s=SIM_SECONDS))
    sim, ctrl = ep.sim, ep.controller
    ctrl.reset(sim.state())
    return rtf(sim, lambda: sim.step(ctrl.compute(sim.state())))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    add_out_option(parser, "sim.md")
    args = parser.parse_args()
    rows = [
        "| robot | raw mj_step RTF | bare simulator RTF | stand controller RTF | bare / stand |",
        "|---|---|---|---|---|",
    ]
    for name in ("humanoid3d", "biped2d"):
        times = np.array(
            [[f(name) for f in (raw_mujoco, bare, stand)] for _ in range(args.repeats)]
        )
        rr, rb, rs = np.median(times, axis=0)
        rows.append(f"| {name} | {rr:.1f} | {rb:.1f} | {rs:.2f} | {rb / rs:.1f}x |")
    lines = [
        "# Simulator real-time factor",
        "",
        machine_info(),
        "",
        f"1 kHz, {SIM_SECONDS:g} s simulated per run, median of {args.repeats} interleaved "
        "runs; RTF = simulated time / wall time (higher is faster). The bare simulator steps "
        "with zero torques and includes the state read-out and fall detection.",
        "",
        *rows,
        "",
    ]
    write_report(args.out, "\n".join(lines))


if __name__ == "__main__":
    main()
