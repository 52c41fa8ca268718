"""Timing of the kinematics kernels used by the kino-dynamic MPC (plain script, no pytest).

Run: ``.venv/bin/python benchmarks/bench_kinematics.py [--reps 2000] [--out NAME]``. Prints
a Markdown table (median and 90th percentile per call, in microseconds,
``time.perf_counter``) and writes it to ``benchmarks/results/kinematics.md``.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from common import add_out_option, machine_info, write_report
from gaitnet_mpc.kinematics import (
    centroidal_map,
    centroidal_map_dot,
    centroidal_pose_eq30,
    f_j2m,
    leg_geometries,
    leg_geometry,
    leg_ik,
    whole_body_ik,
)
from gaitnet_mpc.robots import load_robot

HORIZON = 10  # MPC stages (paper Table V: h = 10)


def time_us(fn: Callable[[], object], reps: int, warmup: int = 50) -> tuple[float, float]:
    """Median and 90th percentile of ``reps`` single-call timings [us]."""
    for _ in range(warmup):
        fn()
    samples_s = np.empty(reps)
    for i in range(reps):
        t0 = time.perf_counter()
        fn()
        samples_s[i] = time.perf_counter() - t0
    return float(np.median(samples_s) * 1e6), float(np.percentile(samples_s, 90) * 1e6)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--reps", type=int, default=2000, help="timed calls per kernel")
    add_out_option(parser, "kinematics.md")
    args = parser.parse_args()
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())

    robot = load_robot("humanoid3d")
    model = robot.pin_model
    data = model.createData()
    rng = np.random.default_rng(0)

    # A 10-stage horizon of tilted trunk poses and left-foot targets from the standing pose.
    p_base = np.column_stack(
        [np.linspace(0.0, 0.3, HORIZON), np.zeros(HORIZON), np.full(HORIZON, 0.62)]
    )
    rot_base = np.array(
        [pin.rpy.rpyToMatrix(*rng.uniform(-0.1, 0.1, 2), rng.uniform(-0.3, 0.3)) for _ in p_base]
    )
    geom = leg_geometry(robot, "left")
    targets = p_base + np.einsum("nij,j->ni", rot_base, [0.02, 0.065, -0.6])  # (N, 3)
    foot_yaw = np.zeros(HORIZON)
    assert leg_ik(geom, targets, p_base, rot_base).reachable.all()

    qpos = robot.standing_qpos()
    qpos[robot.joint_qpos_adr] += rng.uniform(-0.1, 0.1, robot.n_joints)
    q, v = robot.mj_to_pin(qpos, rng.normal(0.0, 1.0, model.nv))
    q_traj = np.tile(q, (HORIZON, 1))
    v_traj = np.tile(v, (HORIZON, 1))
    feet = {"left": targets, "right": targets - rot_base[:, :, 1] * 0.13}
    geoms = leg_geometries(robot)

    small = np.ones(HORIZON)
    cases: list[tuple[str, Callable[[], object]]] = [
        (f"reference: one NumPy add of two ({HORIZON},) arrays", lambda: small + small),
        (f"leg_ik, N={HORIZON} (q0 = 0, eq. 31)", lambda: leg_ik(geom, targets, p_base, rot_base)),
        (
            f"leg_ik, N={HORIZON}, desired foot yaw",
            lambda: leg_ik(geom, targets, p_base, rot_base, foot_yaw),
        ),
        (
            f"whole_body_ik, N={HORIZON}, both legs (cached geometry)",
            lambda: whole_body_ik(robot, p_base, rot_base, feet, geometries=geoms),
        ),
        ("A_G: centroidal_map (pin.computeCentroidalMap)", lambda: centroidal_map(model, data, q)),
        (
            "dA_G: centroidal_map_dot (central difference, default)",
            lambda: centroidal_map_dot(model, data, q, v),
        ),
        (
            "dA_G: pin.computeCentroidalMapTimeVariation (only dAg v valid)",
            lambda: centroidal_map_dot(model, data, q, v, method="pinocchio"),
        ),
        ("f_j2m: h = A_G v (pin.computeCentroidalMomentum)", lambda: f_j2m(model, data, q, v)),
        (
            f"centroidal_pose_eq30, K={HORIZON} stages",
            lambda: centroidal_pose_eq30(model, q_traj, v_traj, 0.045, data),
        ),
    ]
    rows = [
        "| kernel (humanoid3d, nv = 24) | median [us] | p90 [us] | calls |",
        "|---|---:|---:|---:|",
    ]
    for name, fn in cases:
        reps = args.reps if "eq30" not in name else max(args.reps // 10, 50)
        median_us, p90_us = time_us(fn, reps)
        rows.append(f"| {name} | {median_us:.1f} | {p90_us:.1f} | {reps} |")

    text = "\n".join(
        [
            "# Kinematics kernel timings",
            "",
            "Single-threaded wall-clock time per call (`time.perf_counter`), "
            "from `benchmarks/bench_kinematics.py`. The first row (one small NumPy "
            "operation) calibrates the machine: the IK kernels cost about 100-150 of them.",
            "",
            f"{machine_info(('numpy', 'pin'))}; load average at start: {load}.",
            "",
            *rows,
            "",
        ]
    )
    write_report(args.out, text)


if __name__ == "__main__":
    main()
