"""Cost of the reference trajectory f_ref (make_reference) and its update f_IK
(update_reference), h = 10, humanoid3d, walking at 0.4 m/s.

Run: ``.venv/bin/python benchmarks/bench_reference.py [--reps 2000] [--out NAME]`` (writes
``results/reference.md``).
Single-threaded wall-clock time per call (``time.perf_counter``); the kernels are measured
interleaved (A B C A B C ...) so that their ratios hold on a shared, noisy machine.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable

import numpy as np

from common import add_out_option, machine_info, write_report
from gaitnet_mpc.gait import GaitSchedule, GaitScheduleConfig
from gaitnet_mpc.kinematics import leg_geometries, whole_body_ik
from gaitnet_mpc.kinematics.reference import (
    ReferenceConfig,
    ReferenceTiming,
    ReferenceWorkspace,
    make_reference,
    update_reference,
)
from gaitnet_mpc.robots import FEET, load_robot

WARMUP = 50


def _setup(config: ReferenceConfig) -> dict[str, Callable[[], object]]:
    robot = load_robot("humanoid3d")
    ws = ReferenceWorkspace(robot, config)
    q, _ = robot.mj_to_pin(robot.standing_qpos(), np.zeros(robot.nv))
    sched = GaitSchedule(GaitScheduleConfig())
    sched.advance_to(0.06)  # mid-step: partial first stage, three steps in the horizon
    timing = ReferenceTiming.from_horizon(sched.horizon())
    ref0 = make_reference(robot, q, timing, (0.4, 0.0, 0.0), {}, workspace=ws)
    swing, stance = sched.swing_foot, sched.stance_foot
    footholds = {swing: ref0.footholds_m[swing][1:], stance: ref0.footholds_m[stance][1:]}
    liftoff = {swing: ref0.footholds_m[swing][0]}

    def make() -> object:
        return make_reference(
            robot, q, timing, (0.4, 0.0, 0.0), footholds, p_liftoff_m=liftoff, workspace=ws
        )

    ref = make()
    rng = np.random.default_rng(0)
    p_foot_iter = ref.p_foot_ref + rng.normal(0.0, 0.01, ref.p_foot_ref.shape)  # (h+1, 2, 3)
    p_com_iter = ref.p_com_ref + rng.normal(0.0, 0.01, ref.p_com_ref.shape)  # (h+1, 3)
    dts_new = timing.dts_s * 1.1

    def update() -> object:
        return update_reference(robot, ref, p_foot_iter, p_com_iter)

    def update_dt() -> object:
        return update_reference(robot, ref, p_foot_iter, p_com_iter, dts_new)

    turning = make_reference(
        robot, q, timing, (0.4, 0.0, 0.5), footholds, p_liftoff_m=liftoff, workspace=ws
    )

    def update_turning() -> object:  # feet headings differ from the trunk's: IK with hip yaw
        return update_reference(robot, turning, p_foot_iter, p_com_iter)

    geoms = leg_geometries(robot)
    targets = {f: ref.p_foot_ref[:, i] for i, f in enumerate(FEET)}
    yaws = {f: ref.foot_yaw_ref_rad[:, i] for i, f in enumerate(FEET)}

    def ik() -> object:
        return whole_body_ik(
            robot, ref.p_base_ref, ref.rot_base_ref, targets, foot_yaw_rad=yaws, geometries=geoms
        )

    return {
        "make_reference (f_ref)": make,
        "update_reference (f_IK), same dt": update,
        "update_reference (f_IK), new dt": update_dt,
        "update_reference (f_IK), same dt, turning 0.5 rad/s": update_turning,
        "one whole_body_ik, N = 11 (inside both)": ik,
    }


def _time(kernels: dict[str, Callable[[], object]], reps: int) -> dict[str, np.ndarray]:
    for fn in kernels.values():
        for _ in range(WARMUP):
            fn()
    out = {name: np.empty(reps) for name in kernels}
    for r in range(reps):
        for name, fn in kernels.items():
            t0 = time.perf_counter()
            fn()
            out[name][r] = time.perf_counter() - t0
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=2000, help="timed calls per kernel")
    add_out_option(parser, "reference.md")
    args = parser.parse_args()
    load = os.getloadavg()
    rows = [
        "| kernel (humanoid3d, h = 10) | com_iterations | median [us] | p90 [us] | min [us] "
        "| calls |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for iters in (1, 0):
        cfg = ReferenceConfig(com_iterations=iters)
        kernels = _setup(cfg)
        if iters == 0:
            kernels = {k: v for k, v in kernels.items() if k.startswith("update")}
        times = _time(kernels, args.reps if iters == 1 else args.reps // 2)
        for name, t in times.items():
            us = t * 1e6
            rows.append(
                f"| {name} | {iters} | {np.median(us):.0f} | {np.percentile(us, 90):.0f} "
                f"| {us.min():.0f} | {us.size} |"
            )
    write_report(
        args.out,
        "\n".join(
            [
                "# Reference trajectory (f_ref, f_IK) timings",
                "",
                f"{machine_info()}",
                "",
                f"Load average at start: {load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f}. A shared "
                "2-core VM whose speed drifts by up to 1.5x between runs: compare rows of one "
                "run (interleaved), e.g. against the whole_body_ik row; min = the unloaded floor.",
                "",
                "Setup: humanoid3d standing pose, gait schedule 0.06 s into step 0 (partial "
                "first stage, the horizon spans three steps), command 0.4 m/s, h = 10 "
                "(11 boundaries). The update moves every foothold and CoM iterate by "
                "N(0, 1 cm) noise; 'new dt' also scales every stage by 1.1 (Gait-Net). "
                "`com_iterations` = trunk fixed-point corrections = extra whole-body IK calls "
                "(default 1). One call = IK (1 + com_iterations times) + (h + 1) CoM / "
                "centroidal-momentum evaluations + finite differences + H. 'turning': yaw-rate "
                "command, so the IK also solves the hip yaw for the foot headings.",
                "",
                *rows,
                "",
            ]
        ),
    )


if __name__ == "__main__":
    main()
