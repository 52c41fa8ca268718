"""Command-line interface: ``gaitnet-mpc run ...``."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from gaitnet_mpc.errors import ConfigError, GaitNetMPCError


def _build_parser() -> argparse.ArgumentParser:
    from gaitnet_mpc.control.registry import CONTROLLERS
    from gaitnet_mpc.robots import ROBOTS

    parser = argparse.ArgumentParser(prog="gaitnet-mpc", description=__doc__)
    sub = parser.add_subparsers(dest="cmd", required=True)
    run = sub.add_parser("run", help="simulate one episode and write a run folder")
    run.add_argument("--robot", choices=sorted(ROBOTS), default="humanoid3d")
    run.add_argument("--controller", default="stand", help=f"one of {sorted(CONTROLLERS)}")
    run.add_argument("--course", default="flat", help="built-in course name or path to a JSON file")
    run.add_argument("--vx", type=float, default=0.0, help="forward velocity command [m/s]")
    run.add_argument("--vy", type=float, default=0.0, help="lateral velocity command [m/s]")
    run.add_argument("--yaw-rate", type=float, default=0.0, help="yaw-rate command [rad/s]")
    run.add_argument("--duration", type=float, default=10.0, help="simulated time [s]")
    run.add_argument(
        "--dt", type=float, default=None, help="fixed MPC sampling time [s] (step = 5 dt)"
    )
    run.add_argument(
        "--push",
        action="append",
        default=[],
        metavar="t=..,fx=..,fy=..,dur=..",
        help="impulse at the trunk CoM (repeatable); forces in N, times in s",
    )
    run.add_argument("--payload-kg", type=float, default=0.0, help="unknown mass on the trunk [kg]")
    run.add_argument("--seed", type=int, default=0, help="seed for randomised courses")
    run.add_argument("--out", type=Path, default=None, help="run folder (default runs/<time>)")
    run.add_argument("--no-video", action="store_true", help="skip the MP4 video")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser


def _run(args: argparse.Namespace) -> int:
    import time

    from gaitnet_mpc.control.registry import ControllerContext, make_controller
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.sim.disturbances import Push
    from gaitnet_mpc.sim.episode import Command, VideoConfig, run_episode
    from gaitnet_mpc.sim.simulator import SimConfig, Simulator
    from gaitnet_mpc.terrain import load_course

    command = Command(args.vx, args.vy, args.yaw_rate)
    pushes = tuple(Push.parse(p) for p in args.push)
    robot = load_robot(args.robot)
    params = {"seed": args.seed} if args.course == "uneven" else {}
    course = load_course(args.course, **params)
    options = {}
    if args.dt is not None:
        if not (0.03 <= args.dt <= 0.2):
            raise ConfigError("--dt", args.dt, "a sampling time in [0.03, 0.2] s")
        options["dt_s"] = args.dt
    controller = make_controller(
        args.controller, ControllerContext(robot, course, command, options)
    )
    sim = Simulator(robot, course, SimConfig(payload_kg=args.payload_kg, pushes=pushes))
    out = args.out or Path("runs") / time.strftime("%Y%m%d-%H%M%S")
    meta = {
        "robot": robot.name,
        "controller": args.controller,
        "course": course.name,
        "command": command.to_dict(),
        "pushes": [
            {"t_s": p.t_s, "force_n": list(p.force_world_n), "dur_s": p.duration_s} for p in pushes
        ],
        "payload_kg": args.payload_kg,
        "seed": args.seed,
    }
    video = None if args.no_video else VideoConfig()
    summary = run_episode(
        sim,
        controller,
        command,
        args.duration,
        out,
        video,
        progress=not args.no_progress,
        meta=meta,
    )
    brief = {
        k: summary[k]
        for k in (
            "fell",
            "fall_time_s",
            "distance_m",
            "mean_speed_mps",
            "speed_rmse_mps",
            "foothold_violations",
            "realtime_factor",
        )
    }
    print(json.dumps(brief, indent=2))
    print(f"results in {out}/")
    return 0


def main(argv: list[str] | None = None) -> int:
    # Offscreen rendering backend; must be chosen before mujoco is first imported.
    os.environ.setdefault("MUJOCO_GL", "egl")
    args = _build_parser().parse_args(argv)
    try:
        if args.cmd == "run":
            return _run(args)
    except GaitNetMPCError as exc:
        print(f"gaitnet-mpc: error: {exc}", file=sys.stderr)
        return 2
    return 1


if __name__ == "__main__":
    sys.exit(main())
