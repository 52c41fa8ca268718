"""Command-line interface: ``gaitnet-mpc run | plot | compare | collect | dataset check``.

* ``run``: simulate one episode and write a run folder (summary, logs, video, plots).
* ``plot RUN_DIR``: (re)make the PNGs of ``RUN_DIR/plots/`` from the folder's files.
* ``compare RUN_DIR RUN_DIR ... [--out DIR]``: one figure and one table over several runs.
* ``collect --out DIR``: the Gait-Net data set by the paper's protocol (resumable).
* ``dataset check DIR``: validate a data-set folder against its manifest and schema.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from gaitnet_mpc.errors import ConfigError, GaitNetMPCError

if TYPE_CHECKING:
    from gaitnet_mpc.sim.simulator import Simulator


def _build_parser() -> argparse.ArgumentParser:
    from gaitnet_mpc.control.registry import CONTROLLERS
    from gaitnet_mpc.robots import ROBOTS

    parser = argparse.ArgumentParser(prog="gaitnet-mpc", description=__doc__)
    sub = parser.add_subparsers(dest="cmd", required=True)
    run = sub.add_parser(
        "run",
        help="simulate one episode and write a run folder",
        description="Simulate one episode and write a run folder (summary.json, log.csv, "
        "mpc_log.csv, events.csv, course.json, config.toml, video.mp4, plots/). The last "
        "line printed is the outcome: OK, NOT UPRIGHT, FELL or INTERRUPTED, with key numbers.",
        epilog=_run_epilog(sorted(CONTROLLERS)),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    run.add_argument(
        "--robot", choices=sorted(ROBOTS), default="humanoid3d", help="default: %(default)s"
    )
    run.add_argument(
        "--controller",
        default="stand",
        help=f"one of {', '.join(sorted(CONTROLLERS))} (one line each below); default: %(default)s",
    )
    run.add_argument(
        "--course",
        default="flat",
        help="a built-in course (one line each below) or a course JSON file (default: %(default)s)",
    )
    run.add_argument(
        "--vx",
        type=float,
        default=0.0,
        help=f"forward velocity command [m/s], in [-{VX_MAX_MPS:g}, {VX_MAX_MPS:g}] "
        "(default: %(default)s)",
    )
    run.add_argument(
        "--vy",
        type=float,
        default=0.0,
        help=f"lateral velocity command [m/s], in [-{VY_MAX_MPS:g}, {VY_MAX_MPS:g}]; "
        "humanoid3d only (default: %(default)s)",
    )
    run.add_argument(
        "--yaw-rate",
        type=float,
        default=0.0,
        help=f"yaw-rate command [rad/s], in [-{YAW_RATE_MAX_RADPS:g}, {YAW_RATE_MAX_RADPS:g}]; "
        "humanoid3d only (default: %(default)s)",
    )
    run.add_argument(
        "--duration",
        type=float,
        default=10.0,
        help=f"simulated time [s], >= {MIN_DURATION_S:g} (default: %(default)s)",
    )
    run.add_argument(
        "--dt",
        type=float,
        default=None,
        help=f"fixed MPC sampling time [s] of kd, srbm, wbmpc, in [{DT_RANGE_S[0]:g}, "
        f"{DT_RANGE_S[1]:g}] (step = 5 dt; default: each controller's, "
        f"{DEFAULT_DT_S:g} s)",
    )
    run.add_argument(
        "--preview",
        action="store_true",
        help="kd, gaitnet, oracle: choose patches and the CoM path with a multi-step LIP "
        "footstep plan (gait/preview.py) instead of the one-step preview",
    )
    run.add_argument(
        "--gaitnet-weights",
        type=Path,
        default=None,
        metavar="PATH",
        help="gaitnet only: Gait-Net weights (.npz from `gaitnet-mpc train`; default: the "
        "weights shipped for the robot)",
    )
    run.add_argument(
        "--preset",
        default=None,
        help="settings preset (gaitnet_mpc/presets/): kd 'default' (tuned, see README "
        "'Deviations from the paper') or 'paper' (Table VIII / Table V weights and limits, "
        "one-step preview, none of the additions); srbm 'default'",
    )
    run.add_argument(
        "--config",
        type=Path,
        default=None,
        metavar="FILE.toml",
        help="controller settings over the preset (a partial TOML file, or a run's "
        "config.toml to repeat its settings)",
    )
    run.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="one controller setting, applied last (repeatable), e.g. "
        "sequential.kd.w_force=1e-3 or lateral_return_time_s=none",
    )
    run.add_argument(
        "--push",
        action="append",
        default=[],
        metavar="t=..,fx=..,fy=..,fz=..,dur=..",
        help="force at the trunk CoM from t for dur seconds (repeatable); t and dur "
        "required, fx, fy, fz (world frame) default 0; forces in N (|f| <= 1000 N), times "
        "in s (0 < dur <= 5 s), impulse |f| dur <= 100 N s; e.g. t=2,fy=50,dur=0.2",
    )
    run.add_argument(
        "--payload-kg",
        type=float,
        default=0.0,
        help="unknown mass on the trunk [kg], in [0, 50] and at most the robot's own mass "
        "(default: %(default)s)",
    )
    run.add_argument(
        "--seed",
        type=int,
        default=None,
        help="seed of a randomised layout of uneven, stepping-stones or gap (other courses: "
        "ignored, with a warning); default: the built-in layout",
    )
    run.add_argument(
        "--out",
        default=None,
        help="run folder, new or empty (with --overwrite: one holding an earlier run); "
        "checked before anything is simulated (default: a new runs/<date-time>-<id>)",
    )
    run.add_argument(
        "--overwrite",
        action="store_true",
        help="allow --out to name a folder holding an earlier run; its files are removed first",
    )
    run.add_argument("--no-video", action="store_true", help="skip the MP4 video")
    run.add_argument(
        "--camera",
        choices=CAMERAS,
        default="oblique",
        help="video camera: oblique (a higher follow camera that shows the feet on the "
        "terrain) or side (the level side view); default: %(default)s",
    )
    run.add_argument(
        "--no-overlay",
        action="store_true",
        help="no text overlay (time, commanded vx, the step's MPC dt) on the video",
    )
    run.add_argument("--no-plots", action="store_true", help="skip the PNGs in plots/")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.add_argument(
        "--viewer",
        action="store_true",
        help="watch the episode in MuJoCo's interactive viewer (needs a display)",
    )
    plot = sub.add_parser("plot", help="(re)make the plots of a run folder")
    plot.add_argument("run_dir", type=Path, metavar="RUN_DIR", help="folder written by `run`")
    compare = sub.add_parser("compare", help="compare several run folders (figure + table)")
    compare.add_argument("run_dirs", type=Path, nargs="+", metavar="RUN_DIR")
    compare.add_argument(
        "--out", default=None, help="output folder (default runs/compare-<time>-<id>)"
    )
    _add_collect_parsers(sub)
    return parser


#: Bounds checked by :class:`~gaitnet_mpc.command.Command` and :func:`_run`, for ``--help``.
VX_MAX_MPS = 1.5
VY_MAX_MPS = 0.5
YAW_RATE_MAX_RADPS = 1.5
MIN_DURATION_S = 0.01
DT_RANGE_S = (0.03, 0.2)
#: Default MPC sampling time of kd, srbm and wbmpc [s] (FixedDt, WalkingConfig,
#: StepDurations; a test checks they agree).
DEFAULT_DT_S = 0.045
CAMERAS = ("oblique", "side")

#: One line per controller for ``run --help``.
CONTROLLER_HELP = {
    "stand": "joint PD + gravity compensation, stands still (no MPC; ignores --vx, --dt)",
    "kd": "the paper's implicit kino-dynamic MPC, fixed dt (default {dt:g} s)",
    "gaitnet": "kd with Gait-Net choosing every step's dt (ignores --dt)",
    "oracle": "kd with a grid search choosing every step's dt (slow; ignores --dt)",
    "srbm": "single-rigid-body MPC with Raibert footholds, fixed dt (default {dt:g} s)",
    "wbmpc": "whole-body NMPC (the data-set teacher), fixed dt (default {dt:g} s)",
}
#: One line per built-in course for ``run --help``.
COURSE_HELP = {
    "flat": "flat ground, 25 m",
    "gap": "ground with holes across the walkway (--seed: random widths)",
    "stepping-stones": "left-only / right-only stones, the paper's Fig. 7 (--seed: random)",
    "obstacle": "a box across the walkway, then a hole (fixed layout)",
    "uneven": "contiguous tiles of random heights (--seed: another draw)",
}


def _run_epilog(controllers: list[str]) -> str:
    """The controller and course lists below ``run --help``'s options."""
    from gaitnet_mpc.terrain.builtin_courses import BUILTIN_COURSES

    lines = ["controllers:"]
    for name in controllers:
        text = CONTROLLER_HELP.get(name, "(see its module docstring)").format(dt=DEFAULT_DT_S)
        lines.append(f"  {name:<16} {text}")
    lines.append("courses:")
    for name in BUILTIN_COURSES:
        lines.append(f"  {name:<16} {COURSE_HELP.get(name, '')}")
    lines.append(
        "outcome line: OK (ended upright), NOT UPRIGHT (no fall, but the end state is past\n"
        "  half the fall detector's tilt or CoM-height margin), FELL, INTERRUPTED (Ctrl-C or\n"
        "  SIGTERM: what was simulated is saved, exit status 130)"
    )
    return "\n".join(lines)


def _add_collect_parsers(sub: Any) -> None:
    from gaitnet_mpc.dataset.collect import BACKENDS
    from gaitnet_mpc.dataset.protocol import TEACHERS, CollectProtocol
    from gaitnet_mpc.robots import ROBOTS

    d = CollectProtocol()
    c = sub.add_parser(
        "collect",
        help="collect the Gait-Net data set (paper Sec. IV-A-1); re-run to resume",
        description="Walk the protocol's sets with the teacher and write one Parquet file per "
        "set and manifest.json into --out. Re-running the same command skips finished sets.",
    )
    c.add_argument("--out", type=Path, required=True, help="data-set folder")
    c.add_argument("--robot", choices=sorted(ROBOTS), default=d.robot)
    c.add_argument(
        "--teacher",
        choices=TEACHERS,
        default=d.teacher,
        help="wbmpc: the whole-body NMPC (the paper's); kd: the kino-dynamic MPC with the "
        "drawn dts (default: %(default)s)",
    )
    c.add_argument("--sets", type=int, default=d.sets, help="number of sets (default: %(default)s)")
    c.add_argument(
        "--seconds",
        type=float,
        default=d.seconds_total,
        help="simulated seconds of all sets together, split equally (default: %(default)s)",
    )
    c.add_argument("--seed", type=int, default=d.seed, help="protocol seed (default: %(default)s)")
    c.add_argument(
        "--course", default=d.course, help="course name or JSON file (default: %(default)s)"
    )
    c.add_argument(
        "--max-restarts",
        type=int,
        default=d.max_restarts,
        help="fresh starts after falls within a set (default: %(default)s)",
    )
    c.add_argument("--preset", default=None, help="the teacher's settings preset")
    c.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override one of the teacher's settings (repeatable)",
    )
    c.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="sets walked in parallel (default: the machine's cores, %(default)s)",
    )
    c.add_argument("--backend", choices=BACKENDS, default="process", help="default: %(default)s")
    c.add_argument("--address", default=None, help="Ray cluster address (--backend ray)")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")
    t = sub.add_parser(
        "train",
        help="train Gait-Net on a data set (needs PyTorch: pip install 'gaitnet-mpc[train]')",
    )
    t.add_argument("--data", type=Path, required=True, help="data-set folder (collect --out)")
    t.add_argument("--features", choices=("pca", "full"), default="pca", help="default: pca")
    t.add_argument("--out", type=Path, required=True, help="output folder (gaitnet.npz, ...)")
    t.add_argument("--members", type=int, default=5, help="ensemble size (default: 5)")
    t.add_argument("--epochs", type=int, default=400, help="most epochs (default: 400)")
    t.add_argument("--seed", type=int, default=0, help="training and split seed (default: 0)")
    t.add_argument("--no-progress", action="store_true", help="no progress bar")
    rep = sub.add_parser("reproduce", help="reproduce a table or figure of the paper")
    rep.add_argument(
        "what",
        choices=("table1", "table2"),
        help="table1: Gait-Net feature spaces; table2: solvers on the same MPC problems",
    )
    rep.add_argument(
        "--data",
        type=Path,
        default=Path("data/gaitnet-kd-humanoid3d"),
        help="data-set folder (default: %(default)s)",
    )
    rep.add_argument("--out", type=Path, default=None, help="default: runs/<what>")
    rep.add_argument(
        "--problems",
        type=int,
        default=40,
        help="table2: recorded MPC problems to solve, >= 1 (default: %(default)s)",
    )
    rep.add_argument(
        "--no-joint-space",
        action="store_true",
        help="table2: skip the explicit KD-SQP and WBD-SQP columns (the slow ones)",
    )
    b = sub.add_parser(
        "bench",
        help="time the closed loop: solves, low-level tick, real-time factor, memory",
        description="Walk each case (a controller with --set overrides) on the same course, "
        "--rounds times in fresh processes, interleaved; print and write perf.md: solve-time "
        "distribution, QPs per solve, low-level tick, real-time factor, a profile of the "
        "first case and (with --memory-seconds) the RSS over one long episode.",
    )
    b.add_argument(
        "--case",
        action="append",
        default=None,
        metavar="LABEL=CONTROLLER[:KEY=VALUE,...]",
        help="a case to time (repeatable); default: kd and gaitnet, each as shipped and "
        "with RTI replans (replan_j_max=1)",
    )
    b.add_argument("--course", default="flat", help="built-in course (default: %(default)s)")
    b.add_argument("--vx", type=float, default=0.75, help="m/s (default: %(default)s)")
    b.add_argument(
        "--seconds", type=float, default=4.0, help="simulated per episode (default: %(default)s)"
    )
    b.add_argument("--rounds", type=int, default=3, help="rounds per case (default: %(default)s)")
    b.add_argument(
        "--memory-seconds",
        type=float,
        default=0.0,
        help="one episode this long, stepping in place (vx 0: the course is finite), RSS "
        "at start and end (0: skip; default: %(default)s)",
    )
    b.add_argument(
        "--memory-case",
        default=None,
        metavar="LABEL",
        help="the case of the memory episode (default: the first)",
    )
    b.add_argument(
        "--baseline",
        default=None,
        metavar="REV",
        help="also time the first case with the package as it was at git revision REV, "
        "interleaved, as the first row (the before/after comparison)",
    )
    b.add_argument("--no-profile", action="store_true", help="skip the cProfile breakdown")
    b.add_argument(
        "--out",
        type=Path,
        default=Path("runs/perf.md"),
        help="report file (default: %(default)s; benchmarks/results/perf.md for the record)",
    )
    ds = sub.add_parser("dataset", help="data-set tools")
    ds_sub = ds.add_subparsers(dest="dataset_cmd", required=True)
    check = ds_sub.add_parser("check", help="validate a data-set folder")
    check.add_argument("folder", type=Path, metavar="DIR")


def _collect(args: argparse.Namespace) -> int:
    import shlex

    from gaitnet_mpc.dataset.collect import CollectOptions, collect
    from gaitnet_mpc.dataset.protocol import CollectProtocol

    protocol = CollectProtocol(
        robot=args.robot,
        teacher=args.teacher,
        sets=args.sets,
        seconds_total=args.seconds,
        course=args.course,
        seed=args.seed,
        max_restarts=args.max_restarts,
        teacher_preset=args.preset,
        teacher_overrides=tuple(args.overrides),
    )
    options = CollectOptions(
        workers=args.workers,
        backend=args.backend,
        address=args.address,
        progress=not args.no_progress,
    )
    command_line = shlex.join(["gaitnet-mpc", *args.argv])
    try:
        manifest = collect(protocol, args.out, options, command_line)
    except KeyboardInterrupt:
        return 130
    totals = manifest["totals"]
    print(
        f"{args.out}: {totals['sets']}/{protocol.sets} sets, {totals['rows']} rows, "
        f"{totals['falls']} fall(s), {totals['steps_dropped_fall']} step(s) dropped for falls"
    )
    return 0


def _train(args: argparse.Namespace) -> int:
    from gaitnet_mpc.gaitnet.data import load_dataset
    from gaitnet_mpc.gaitnet.fit import fit, write_fit
    from gaitnet_mpc.gaitnet.train import TrainConfig

    config = TrainConfig(members=args.members, epochs=args.epochs, seed=args.seed)
    data = load_dataset(args.data)
    result, report, selection = fit(
        data, args.features, config, split_seed=args.seed, progress=not args.no_progress
    )
    write_fit(args.out, result, report, selection)
    print(
        f"features {', '.join(report.feature_names)}\n"
        f"test RMSE of dt {report.test_rmse_s:.2e} s (always the mean: "
        f"{report.mean_predictor_rmse_s:.2e} s) on sets {list(report.split.test)}\n"
        f"weights and report in {args.out}/"
    )
    return 0


def _reproduce(args: argparse.Namespace) -> int:
    out = args.out if args.out is not None else Path("runs") / args.what
    if args.what == "table2":
        from gaitnet_mpc.table2.run import reproduce_table2

        if args.problems < 1:
            raise ConfigError("--problems", args.problems, "an integer >= 1")
        report = reproduce_table2(
            out,
            args.problems,
            progress=lambda n, total: print(
                f"\rsolved {n}/{total} problems", end="", file=sys.stderr, flush=True
            ),
            with_joint_space=not args.no_joint_space,
        )
        print(file=sys.stderr)
        print(report.read_text(), end="")
    else:
        from gaitnet_mpc.gaitnet.table1 import reproduce_table1

        reproduce_table1(args.data, out)
        print((out / "table1.md").read_text(), end="")
    print(f"results in {out}/")
    return 0


def _bench(args: argparse.Namespace) -> int:
    import shlex

    from gaitnet_mpc.bench import (
        DEFAULT_CASES,
        EpisodeSpec,
        build_case,
        parse_case,
        perf_markdown,
        profiled_episode,
        run_bench,
        timed_episode,
    )
    from gaitnet_mpc.results.io import write_atomic

    cases = [parse_case(c) for c in args.case] if args.case else list(DEFAULT_CASES)
    spec = EpisodeSpec(args.course, args.vx, args.seconds)
    if not (math.isfinite(args.memory_seconds) and args.memory_seconds >= 0.0):
        raise ConfigError("--memory-seconds", args.memory_seconds, "a finite time >= 0 s")
    labels = [c.label for c in cases]
    memory_case = cases[0]
    if args.memory_case is not None:
        if args.memory_case not in labels:
            raise ConfigError("--memory-case", args.memory_case, f"one of {labels}")
        memory_case = cases[labels.index(args.memory_case)]
    for case in cases:  # bad controller names or overrides fail here, before any timing
        build_case(case, spec)
    if args.baseline is not None:
        first = cases[0]
        old = replace(first, label=f"{first.label} @ {args.baseline}", revision=args.baseline)
        cases.insert(0, old)

    def say(text: str) -> None:
        print(text, file=sys.stderr, flush=True)

    results = run_bench(cases, spec, args.rounds, progress=say)
    parts = None
    profiled = cases[1] if args.baseline is not None else cases[0]  # this tree's first case
    if not args.no_profile:
        say(f"profiling {profiled.label}")
        parts = profiled_episode(profiled, spec)
    memory = None
    if args.memory_seconds > 0.0:
        say(f"memory: {memory_case.label}, {args.memory_seconds:g} s simulated in place")
        memory = timed_episode(
            memory_case,
            EpisodeSpec(args.course, 0.0, args.memory_seconds),
            on_second=lambda t: say(f"  {t:.0f} s") if round(t) % 60 == 0 else None,
            record_ticks=False,
        )
    report = perf_markdown(
        results,
        spec,
        args.rounds,
        parts,
        profiled.label,
        memory,
        memory_case.label,
        shlex.join(["gaitnet-mpc", *args.argv]),
    )
    write_atomic(args.out, report)
    print(report)
    print(f"written to {args.out}")
    return 0


def _dataset(args: argparse.Namespace) -> int:
    from gaitnet_mpc.dataset.check import check_dataset

    result = check_dataset(args.folder)
    print(f"{args.folder}: OK ({result['files']} files, {result['rows']} rows)")
    return 0


def _has_display() -> bool:
    """Whether an interactive window can be opened (X11 or Wayland on Linux)."""
    if not sys.platform.startswith("linux"):
        return True  # macOS / Windows: the viewer reports its own requirements
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _glfw_can_open() -> str | None:
    """None if GLFW (the viewer's window library) initialises, else the reason it did not.

    Probed here because ``mujoco.viewer.launch_passive`` initialises GLFW in a thread and
    waits forever when that fails (e.g. ``DISPLAY`` set but no X server reachable).
    """
    import warnings

    try:
        import glfw
    except ImportError as exc:  # pragma: no cover - glfw is a mujoco dependency
        return f"the glfw package is missing ({exc})"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ok = glfw.init()
    if ok:
        glfw.terminate()
        return None
    return "; ".join(str(w.message) for w in caught) or "glfw.init() failed"


def _check_viewer() -> None:
    """Fail fast when ``--viewer`` cannot open a window."""
    if not _has_display():
        raise ConfigError(
            "--viewer",
            "no display (DISPLAY and WAYLAND_DISPLAY are unset)",
            "a graphical session for MuJoCo's interactive viewer; without one, drop "
            "--viewer and watch video.mp4 (rendered offscreen)",
        )
    if sys.platform.startswith("linux"):
        reason = _glfw_can_open()
        if reason is not None:
            display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
            raise ConfigError(
                "--viewer",
                f"display {display!r} ({reason})",
                "a display the viewer can open; without one, drop --viewer and watch "
                "video.mp4 (rendered offscreen)",
            )


def _open_viewer(sim: Simulator, trunk_body: str) -> Any:
    """MuJoCo's passive viewer on the simulator, its camera tracking the trunk."""
    import mujoco
    import mujoco.viewer

    handle = mujoco.viewer.launch_passive(sim.model, sim.data)
    with handle.lock():
        handle.cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        handle.cam.trackbodyid = sim.model.body(trunk_body).id
        handle.cam.distance = 2.5
    return handle


def _run(args: argparse.Namespace) -> int:
    import time

    from gaitnet_mpc.command import Command
    from gaitnet_mpc.config import dumps
    from gaitnet_mpc.control.registry import ControllerContext, controller_config, make_controller
    from gaitnet_mpc.results.io import write_atomic
    from gaitnet_mpc.results.rundir import CONFIG, RUN_ARTIFACTS, prepare_output_folder
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.runner.episode import VideoConfig, run_episode
    from gaitnet_mpc.sim.disturbances import Push
    from gaitnet_mpc.sim.simulator import SimConfig, Simulator, check_payload
    from gaitnet_mpc.terrain import SEEDED_COURSES, load_course

    if not (math.isfinite(args.duration) and args.duration >= MIN_DURATION_S):
        raise ConfigError("--duration", args.duration, f"a simulated time >= {MIN_DURATION_S:g} s")
    if args.viewer:
        _check_viewer()
    command = Command(args.vx, args.vy, args.yaw_rate)
    pushes = tuple(Push.parse(p) for p in args.push)
    robot = load_robot(args.robot)
    check_payload(args.payload_kg, robot.total_mass_kg, "--payload-kg")
    seeded = args.seed is not None and args.course in SEEDED_COURSES
    course = load_course(args.course, **({"seed": args.seed} if seeded else {}))
    options = {}
    if args.dt is not None:
        lo, hi = DT_RANGE_S
        if not (lo <= args.dt <= hi):
            raise ConfigError("--dt", args.dt, f"a sampling time in [{lo:g}, {hi:g}] s")
        options["dt_s"] = args.dt
    if args.preview:
        from gaitnet_mpc.control.registry import KD_FAMILY

        if args.controller not in KD_FAMILY:
            raise ConfigError("--preview", args.controller, f"one of {', '.join(KD_FAMILY)}")
        options["preview"] = True
    if args.gaitnet_weights is not None:
        if args.controller != "gaitnet":
            raise ConfigError(
                "--gaitnet-weights", str(args.gaitnet_weights), "--controller gaitnet"
            )
        options["gaitnet_weights"] = str(args.gaitnet_weights)
    if args.preset is not None:
        options["preset"] = args.preset
    if args.config is not None:
        options["config"] = str(args.config)
    if args.overrides:
        options["set"] = list(args.overrides)
    config = controller_config(
        args.controller,
        robot.spec.planar,
        preset=args.preset,
        config_file=args.config,
        preview=args.preview,
        dt_s=args.dt,
        overrides=args.overrides,
    )
    controller = make_controller(
        args.controller, ControllerContext(robot, course, command, options, config)
    )
    sim = Simulator(robot, course, SimConfig(payload_kg=args.payload_kg, pushes=pushes))
    out = prepare_output_folder(
        args.out,
        option="--out",
        default_prefix="",
        artifacts=RUN_ARTIFACTS,
        overwrite=args.overwrite,
    )
    if config is not None:
        write_atomic(out / CONFIG, dumps(config, _config_header(args, robot.name, config)))
    warnings = _ineffective_options(args, robot.spec.planar, pushes, SEEDED_COURSES)
    for text in warnings:
        print(f"gaitnet-mpc: warning: {text}", file=sys.stderr)
    meta = {
        "warnings": warnings,
        "robot": robot.name,
        "controller": args.controller,
        "controller_options": options,
        "course": course.name,
        "command": command.to_dict(),
        "pushes": [
            {"t_s": p.t_s, "force_n": list(p.force_world_n), "dur_s": p.duration_s} for p in pushes
        ],
        "payload_kg": args.payload_kg,
        "seed": args.seed,
        "terrain_knowledge": controller.terrain_knowledge(),
    }
    video = None if args.no_video else VideoConfig(camera=args.camera, overlay=not args.no_overlay)
    viewer = _open_viewer(sim, robot.spec.trunk_body) if args.viewer else None
    print(
        f"simulating {args.duration:g} s: {args.controller} on {robot.name}, {args.course}",
        file=sys.stderr,
        flush=True,
    )
    try:
        summary = run_episode(
            sim,
            controller,
            command,
            args.duration,
            out,
            video,
            progress=not args.no_progress,
            meta=meta,
            viewer=viewer,
        )
    finally:
        if viewer is not None:
            viewer.close()
    plots_s = None
    plots_interrupted = False
    if not args.no_plots:
        from gaitnet_mpc.results.plots import make_plots

        t0 = time.perf_counter()
        try:
            make_plots(out)
        except KeyboardInterrupt:  # the run is saved; `gaitnet-mpc plot` remakes the plots
            plots_interrupted = True
            print(
                f"gaitnet-mpc: plotting interrupted; `gaitnet-mpc plot {out}` makes the plots",
                file=sys.stderr,
            )
        plots_s = time.perf_counter() - t0
    brief = {
        k: summary[k]
        for k in (
            "outcome",
            "fell",
            "fall_time_s",
            "ended_upright",
            "final_tilt_rad",
            "final_com_height_m",
            "distance_m",
            "mean_speed_mps",
            "speed_rmse_mps",
            "foothold_violations",
            "realtime_factor",
        )
    }
    print(json.dumps(brief, indent=2))
    render_s = summary["render_time_s"]
    timing = f"simulation {summary['wall_time_s'] - render_s:.1f} s, video {render_s:.1f} s"
    if plots_s is not None:
        timing += f", plots {plots_s:.1f} s"
    print(f"wall time: {timing}")
    print(f"results in {out}/")
    print(_outcome_line(summary))
    return 130 if summary["interrupted"] or plots_interrupted else 0


def _config_header(args: argparse.Namespace, robot: str, config: object) -> str:
    """Comment lines at the top of a run's ``config.toml``."""
    text = (
        f"Settings of `gaitnet-mpc run --controller {args.controller}` "
        f"({type(config).__name__}) on {robot},\n"
        "after the preset, --config, --preview / --dt and --set. `--config config.toml`\n"
        'repeats them; "none" stands for None.'
    )
    if args.controller in ("kd", "gaitnet", "oracle"):
        text += (
            "\nsequential.kd.mass_kg and min_foot_separation_m are set from the robot; kd's\n"
            "--dt (its MPC sampling time) is not a setting here and is given again."
        )
    return text


def _ineffective_options(
    args: argparse.Namespace, planar: bool, pushes: tuple, seeded_courses: frozenset[str]
) -> list[str]:
    """Options given that will have no effect on this run (printed to stderr and recorded
    in ``summary.json``'s ``warnings``)."""
    out = []
    if args.seed is not None and args.course not in seeded_courses:
        out.append(
            f"--seed {args.seed} has no effect: course {args.course!r} has a fixed layout "
            f"(seeded courses: {', '.join(sorted(seeded_courses))})"
        )
    if args.controller == "stand":
        for flag, value in (("--vx", args.vx), ("--vy", args.vy), ("--yaw-rate", args.yaw_rate)):
            if value != 0.0:
                out.append(f"{flag} {value:g} has no effect: the stand controller does not walk")
        if args.dt is not None:
            out.append(f"--dt {args.dt:g} has no effect: the stand controller has no MPC")
    if args.controller == "gaitnet" and args.dt is not None:
        out.append(f"--dt {args.dt:g} has no effect: Gait-Net chooses every step's dt")
    if args.controller == "oracle" and args.dt is not None:
        out.append(f"--dt {args.dt:g} has no effect: the oracle chooses every step's dt")
    if args.no_video and (args.camera != "oblique" or args.no_overlay):
        out.append("--camera / --no-overlay have no effect with --no-video")
    if planar:
        for flag, value in (("--vy", args.vy), ("--yaw-rate", args.yaw_rate)):
            if value != 0.0:
                out.append(f"{flag} {value:g} has no effect on the planar robot")
    for i, push in enumerate(pushes):
        if push in pushes[:i]:
            out.append(f"--push {args.push[i]} is given twice: both are applied (twice the force)")
        if push.t_s >= args.duration:
            out.append(
                f"--push at t = {push.t_s:g} s has no effect: the run ends at {args.duration:g} s"
            )
    return out


def _outcome_line(summary: dict[str, Any]) -> str:
    """One line that says how the run ended: OK, FELL or INTERRUPTED, with key numbers."""
    t = summary["duration_s"]
    drop_m = summary["com_height0_m"] - summary["final_com_height_m"]
    numbers = (
        f"{summary['distance_m']:.2f} m in {t:.2f} s, "
        f"{summary['foothold_violations']} foothold violations, "
        f"{summary['self_collisions']} ticks of leg contact, "
        f"final tilt {summary['final_tilt_rad']:.2f} rad, "
        f"final CoM height {summary['final_com_height_m']:.3f} m "
        f"({abs(drop_m) * 100:.1f} cm {'below' if drop_m >= 0 else 'above'} the start)"
    )
    if summary["interrupted"]:
        return f"INTERRUPTED at t = {t:.3f} s: {numbers}"
    if summary["fell"]:
        return f"FELL at t = {summary['fall_time_s']:.3f} s ({summary['fall_reason']}): {numbers}"
    if not summary["ended_upright"]:
        return f"NOT UPRIGHT at the end (t = {t:.3f} s, no fall detected): {numbers}"
    return f"OK: {numbers}"


def _plot(args: argparse.Namespace) -> int:
    from gaitnet_mpc.results.plots import make_plots

    written = make_plots(args.run_dir)
    for path in written:
        print(path)
    if not written:
        print(f"{args.run_dir}: empty log, no plots written", file=sys.stderr)
    return 0


def _compare(args: argparse.Namespace) -> int:

    from gaitnet_mpc.results.compare import compare_runs
    from gaitnet_mpc.results.rundir import COMPARE_ARTIFACTS, prepare_output_folder

    out = prepare_output_folder(
        args.out,
        option="--out",
        default_prefix="compare-",
        artifacts=COMPARE_ARTIFACTS,
        overwrite=True,  # a comparison is cheap to remake; its own files are replaced
    )
    paths = compare_runs(args.run_dirs, out)
    print(paths["markdown"].read_text(), end="")
    print(f"results in {out}/")
    return 0


def main(argv: list[str] | None = None) -> int:
    # Offscreen rendering backend; must be chosen before mujoco is first imported.
    os.environ.setdefault("MUJOCO_GL", "egl")
    argv = sys.argv[1:] if argv is None else list(argv)
    args = _build_parser().parse_args(argv)
    args.argv = argv
    try:
        if args.cmd == "run":
            # SIGTERM and SIGINT stop a run like Ctrl-C, from start-up through plotting
            from gaitnet_mpc.parallel import stop_signals_as_keyboard_interrupt

            with stop_signals_as_keyboard_interrupt():
                return _run(args)
        if args.cmd == "plot":
            return _plot(args)
        if args.cmd == "compare":
            return _compare(args)
        if args.cmd == "collect":
            return _collect(args)
        if args.cmd == "dataset":
            return _dataset(args)
        if args.cmd == "train":
            return _train(args)
        if args.cmd == "reproduce":
            return _reproduce(args)
        if args.cmd == "bench":
            return _bench(args)
    except GaitNetMPCError as exc:
        print(f"gaitnet-mpc: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # Ctrl-C outside the simulation loop (start-up, plotting, training); what a
        # command had finished is already on disk (every file is written atomically)
        print("gaitnet-mpc: interrupted", file=sys.stderr)
        return 130
    return 1


if __name__ == "__main__":
    sys.exit(main())
