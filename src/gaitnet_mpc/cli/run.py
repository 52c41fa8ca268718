"""``gaitnet-mpc run``: simulate one episode (a :class:`~gaitnet_mpc.scenario.Scenario`)
and write a run folder."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

from gaitnet_mpc.dt_policy import ACCEPTED_DT_RANGE_S, NOMINAL_DT_S
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.runner.episode import CAMERAS

#: Bounds checked by :class:`~gaitnet_mpc.command.Command`, for ``--help``.
VX_MAX_MPS = 1.5
VY_MAX_MPS = 0.5
YAW_RATE_MAX_RADPS = 1.5
#: The fixed dt of kd, srbm and wbmpc when ``--dt`` is not given [s].
DEFAULT_DT_S = NOMINAL_DT_S
DT_RANGE_S = ACCEPTED_DT_RANGE_S

#: One line per controller for ``run --help``.
CONTROLLER_HELP = {
    "stand": "joint PD + gravity compensation, stands still (no MPC; ignores --vx, --dt)",
    "kd": "the paper's implicit kino-dynamic MPC, fixed dt (default {dt:g} s)",
    "gaitnet": "kd with Gait-Net choosing every step's dt (the paper's method; ignores --dt)",
    "oracle": "kd with a grid search choosing every step's dt (slow; ignores --dt)",
    "kd-optdt": "kd with each step's dt a variable of an NLP (Fig. 6 baseline 2; ignores --dt)",
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
#: The scenario's own options, with their defaults (None in the parser, so that
#: ``--scenario`` can tell which were given).
SCENARIO_DEFAULTS: dict[str, Any] = {
    "robot": "humanoid3d",
    "controller": "gaitnet",
    "course": "flat",
    "vx": 0.0,
    "vy": 0.0,
    "yaw_rate": 0.0,
    "duration": 10.0,
    "dt": None,
    "preview": False,
    "blind": False,
    "gaitnet_weights": None,
    "preset": None,
    "config": None,
    "overrides": [],
    "push": [],
    "payload_kg": 0.0,
    "cart_load_kg": None,
    "seed": None,
}

#: Fields of a :class:`~gaitnet_mpc.scenario.Scenario` and the option that sets each (the
#: name an error about the field gives).
RUN_OPTIONS = {
    "course_seed": "--seed",
    "duration_s": "--duration",
    "payload_kg": "--payload-kg",
    "cart.load_kg": "--cart-load-kg",
}

SUMMARY = "simulate one episode and write a run folder"

#: Imported before the command starts, with Ctrl-C held back (cli/main.py).
PRELOAD = ("gaitnet_mpc.scenario", "gaitnet_mpc.mpc.qp")


def add_parser(sub: Any) -> None:
    from gaitnet_mpc.control.registry import CONTROLLERS
    from gaitnet_mpc.robots import ROBOTS
    from gaitnet_mpc.scenario import MAX_DURATION_S, MIN_DURATION_S

    run = sub.add_parser(
        "run",
        help=SUMMARY,
        description="Simulate one episode and write a run folder (scenario.toml, summary.json, "
        "timing.json, log.csv, mpc_log.csv, events.csv, course.json, config.toml, video.mp4, "
        "plots/). The last line printed is the outcome: OK, NOT UPRIGHT, FELL or "
        "INTERRUPTED, with key numbers.",
        epilog=_epilog(sorted(CONTROLLERS)),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    d = SCENARIO_DEFAULTS
    run.add_argument(
        "--scenario",
        type=Path,
        default=None,
        metavar="FILE.toml",
        help="run the scenario of this file (a run folder's scenario.toml replays that run); "
        "then no other option that describes the run may be given",
    )
    run.add_argument("--robot", choices=sorted(ROBOTS), help=f"default: {d['robot']}")
    run.add_argument(
        "--controller",
        help=f"one of {', '.join(sorted(CONTROLLERS))} (one line each below); "
        f"default: {d['controller']}",
    )
    run.add_argument(
        "--course",
        help="a built-in course (one line each below) or a course JSON file "
        f"(default: {d['course']})",
    )
    run.add_argument(
        "--vx",
        type=float,
        help=f"forward velocity command [m/s], in [-{VX_MAX_MPS:g}, {VX_MAX_MPS:g}] "
        f"(default: {d['vx']})",
    )
    run.add_argument(
        "--vy",
        type=float,
        help=f"lateral velocity command [m/s], in [-{VY_MAX_MPS:g}, {VY_MAX_MPS:g}]; "
        f"humanoid3d only (default: {d['vy']})",
    )
    run.add_argument(
        "--yaw-rate",
        type=float,
        help=f"yaw-rate command [rad/s], in [-{YAW_RATE_MAX_RADPS:g}, {YAW_RATE_MAX_RADPS:g}]; "
        f"humanoid3d only (default: {d['yaw_rate']})",
    )
    run.add_argument(
        "--duration",
        type=float,
        help=f"simulated time [s], in [{MIN_DURATION_S:g}, {MAX_DURATION_S:g}] "
        f"(default: {d['duration']})",
    )
    run.add_argument(
        "--dt",
        type=float,
        help=f"fixed MPC sampling time [s] of kd, srbm, wbmpc, in [{DT_RANGE_S[0]:g}, "
        f"{DT_RANGE_S[1]:g}] (step = 5 dt; default: {DEFAULT_DT_S:g} s); kd records it as "
        "dt_policy.dt_s in config.toml",
    )
    run.add_argument(
        "--preview",
        action="store_true",
        default=None,
        help="kd, gaitnet, oracle: choose patches and the CoM path with a multi-step LIP "
        "footstep plan (gait/preview.py) instead of the one-step preview",
    )
    run.add_argument(
        "--blind",
        action="store_true",
        default=None,
        help="kd, gaitnet, oracle: the controller is told no terrain (the paper's unknown "
        "terrain): footholds at the stance foot's height, the swing foot finds the ground; "
        "the same as --set blind=true",
    )
    run.add_argument(
        "--gaitnet-weights",
        metavar="NAME|PATH",
        help="gaitnet only: Gait-Net weights, a shipped name (e.g. humanoid3d-wbmpc, taught "
        "by the whole-body NMPC), the folder DIR of `gaitnet-mpc train --out DIR` or its "
        "DIR/gaitnet.npz (default: the robot's)",
    )
    run.add_argument(
        "--preset",
        help="settings preset (gaitnet_mpc/presets/): kd family 'default' (tuned, see README "
        "'Deviations from the paper'), 'paper' (the numbers of Tables VIII / V and X, the "
        "weights read per unit of motion, docs/design/paper_weights.md), 'realtime', "
        "'fastdt' or 'blind'; srbm, wbmpc 'default'",
    )
    run.add_argument(
        "--config",
        type=Path,
        metavar="FILE.toml",
        help="controller settings over the preset (a partial TOML file, or a run's "
        "config.toml to repeat its settings)",
    )
    run.add_argument(
        "--set",
        dest="overrides",
        action="append",
        metavar="KEY=VALUE",
        help="one controller setting, applied last (repeatable), e.g. "
        "sequential.kd.w_force=1e-3, lateral_return_time_s=none or "
        "dt_policy.gaitnet.max_retimes=3",
    )
    run.add_argument(
        "--push",
        action="append",
        metavar="t=..,fx=..,fy=..,fz=..,dur=..",
        help="force at the trunk CoM from t for dur seconds (repeatable); t and dur "
        "required, fx, fy, fz (world frame) default 0; forces in N (|f| <= 1000 N), times "
        "in s (0 < dur <= 5 s), impulse |f| dur <= 100 N s; e.g. t=2,fy=50,dur=0.2",
    )
    run.add_argument(
        "--payload-kg",
        type=float,
        help="unknown mass on the trunk [kg], in [0, 50] and at most the robot's own mass "
        f"(default: {d['payload_kg']})",
    )
    run.add_argument(
        "--cart-load-kg",
        type=float,
        help="push a cart (Fig. 10) carrying this load [kg] that no controller is told about, "
        "in [0, 350]; the arms hold the pushing pose; humanoid3d only (default: no cart)",
    )
    run.add_argument(
        "--seed",
        type=int,
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
        "--allow-fall",
        action="store_true",
        help="exit 0 when the robot falls (default: a fall exits 1; the run folder is "
        "written either way)",
    )
    run.add_argument(
        "--viewer",
        action="store_true",
        help="watch the episode in MuJoCo's interactive viewer (needs a display)",
    )


def _epilog(controllers: list[str]) -> str:
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
        "  SIGTERM: what was simulated is saved, exit status 130)\n"
        "exit status: 0 done, 1 the robot fell (0 with --allow-fall), 2 bad input, "
        "130 interrupted"
    )
    return "\n".join(lines)


def scenario_from_args(args: argparse.Namespace) -> Any:
    """The :class:`~gaitnet_mpc.scenario.Scenario` the options describe (``--scenario``:
    the file's, and then no other scenario option may be given)."""
    from gaitnet_mpc.scenario import MAX_DURATION_S, MIN_DURATION_S, Scenario
    from gaitnet_mpc.sim.simulator import check_payload

    given = {k: getattr(args, k) for k in SCENARIO_DEFAULTS if getattr(args, k) is not None}
    if args.scenario is not None:
        if given:
            flags = ", ".join("--" + k.replace("_", "-") for k in given)
            raise ConfigError(
                "--scenario", str(args.scenario), f"no other option describing the run ({flags})"
            )
        return Scenario.from_toml(args.scenario)
    v = {**SCENARIO_DEFAULTS, **given}
    lo_s, hi_s = MIN_DURATION_S, MAX_DURATION_S
    if not (math.isfinite(v["duration"]) and lo_s <= v["duration"] <= hi_s):
        raise ConfigError(
            "--duration", v["duration"], f"a simulated time in [{lo_s:g}, {hi_s:g}] s"
        )
    check_payload(v["payload_kg"], None, "--payload-kg")
    if v["dt"] is not None:
        lo, hi = DT_RANGE_S
        if not (lo <= v["dt"] <= hi):
            raise ConfigError("--dt", v["dt"], f"a sampling time in [{lo:g}, {hi:g}] s")
    try:
        return _make_scenario(v)
    except ConfigError as exc:  # a scenario's field, named by the option that sets it
        option = RUN_OPTIONS.get(exc.field)
        if option is None:
            raise
        raise type(exc)(option, exc.value, exc.expected) from None


def _make_scenario(v: dict[str, Any]) -> Any:
    """:func:`~gaitnet_mpc.scenario.make_scenario` of the options ``v``."""
    from gaitnet_mpc.scenario import make_scenario
    from gaitnet_mpc.scenario.model import KD_FAMILY
    from gaitnet_mpc.sim.cart import Cart
    from gaitnet_mpc.sim.disturbances import Push

    if v["blind"] and v["controller"] not in KD_FAMILY:
        raise ConfigError("--blind", v["controller"], f"one of {', '.join(KD_FAMILY)}")
    blind = ("blind=true",) if v["blind"] else ()
    return make_scenario(
        robot=v["robot"],
        controller=v["controller"],
        course=v["course"],
        course_seed=v["seed"],
        vx_mps=v["vx"],
        vy_mps=v["vy"],
        yaw_rate_radps=v["yaw_rate"],
        duration_s=v["duration"],
        pushes=tuple(Push.parse(p) for p in v["push"]),
        payload_kg=v["payload_kg"],
        cart=None if v["cart_load_kg"] is None else Cart(load_kg=v["cart_load_kg"]),
        preset=v["preset"],
        config_file=v["config"],
        overrides=(*v["overrides"], *blind),
        dt_s=v["dt"],
        preview=bool(v["preview"]),
        gaitnet_weights=v["gaitnet_weights"],
    )


def main(args: argparse.Namespace) -> int:
    from gaitnet_mpc.cli.viewer import check_viewer
    from gaitnet_mpc.results.outdir import check_output_path, claim_output_folder
    from gaitnet_mpc.results.rundir import RUN_ARTIFACTS
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.scenario import build_episode
    from gaitnet_mpc.sim.simulator import check_payload

    if args.viewer:
        check_viewer()
    if args.out is not None:  # a path that cannot be written, before the episode is built
        check_output_path(args.out, "--out")
    scenario = scenario_from_args(args)
    robot = load_robot(scenario.robot)
    field = "--payload-kg" if args.scenario is None else f"{args.scenario}: payload_kg"
    check_payload(scenario.payload_kg, robot.total_mass_kg, field)
    episode = build_episode(scenario, robot=robot)  # every error before the folder is touched
    with claim_output_folder(
        args.out,
        option="--out",
        default_prefix="",
        artifacts=RUN_ARTIFACTS,
        overwrite=args.overwrite,
    ) as out:
        return _run(args, scenario, episode, out)


def _run(args: argparse.Namespace, scenario: Any, episode: Any, out: Path) -> int:
    """Simulate ``episode`` into the claimed folder ``out``; plots; the outcome; the code."""
    import shlex

    from gaitnet_mpc.cli.main import EXIT_FELL, EXIT_INTERRUPTED, EXIT_OK
    from gaitnet_mpc.cli.viewer import open_viewer
    from gaitnet_mpc.results.outdir import write_status
    from gaitnet_mpc.runner.episode import VideoConfig
    from gaitnet_mpc.scenario import scenario_warnings, simulate_episode

    command = shlex.join(["gaitnet-mpc", *args.argv])
    extra = []
    if args.no_video and (args.camera != "oblique" or args.no_overlay):
        extra.append("--camera / --no-overlay have no effect with --no-video")
    for text in [*scenario_warnings(scenario), *extra]:
        print(f"gaitnet-mpc: warning: {text}", file=sys.stderr)
    video = None if args.no_video else VideoConfig(camera=args.camera, overlay=not args.no_overlay)
    todo = ["simulation"] + ["video"] * (video is not None) + ["plots"] * (not args.no_plots)
    write_status(out, command=command, state="running", todo=todo)  # until it ends
    print(
        f"simulating {scenario.duration_s:g} s: {scenario.controller} on {scenario.robot}, "
        f"{scenario.course}",
        file=sys.stderr,
        flush=True,
    )
    summary = simulate_episode(  # run_scenario's simulation, in the folder claimed above
        episode,
        out,
        video=video,
        progress=not args.no_progress,
        viewer_factory=open_viewer if args.viewer else None,
        extra_warnings=extra,
    )
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
    brief_keys = (
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
    print(json.dumps({k: summary[k] for k in brief_keys}, indent=2))
    render_s = summary["render_time_s"]
    timing = f"simulation {summary['wall_time_s'] - render_s:.1f} s, video {render_s:.1f} s"
    if plots_s is not None:
        timing += f", plots {plots_s:.1f} s"
    print(f"wall time: {timing}")
    print(f"results in {out}/")
    print(outcome_line(summary))
    interrupted = bool(summary["interrupted"]) or plots_interrupted
    code = EXIT_INTERRUPTED if interrupted else EXIT_OK
    if not interrupted and summary["fell"] and not args.allow_fall:
        code = EXIT_FELL
    done = [f"simulated {summary['duration_s']:g} of {scenario.duration_s:g} s"]
    if video is not None and (out / "video.mp4").is_file():
        done.append("video")
    if not args.no_plots and not plots_interrupted:
        done.append("plots")
    left = [t for t in todo if t != "simulation" and t not in done]
    if summary["interrupted"]:
        left.insert(0, "the rest of the simulation")
    note = outcome_line(summary)
    if interrupted:  # an episode is not resumed mid-way: it is simulated again
        note += f"; to finish, run the command again with --overwrite (or `gaitnet-mpc plot {out}`)"
    write_status(
        out,
        command=command,
        state="interrupted" if interrupted else "done",
        exit_code=code,
        done=done,
        todo=left,
        note=note,
    )
    return code


def outcome_line(summary: dict[str, Any]) -> str:
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
