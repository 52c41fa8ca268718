"""Toe strikes on boxes taller than the robot assumes (``KDWalkConfig.toe_strike_raise_m``).

Each course is flat ground with one box 10 cm long across the path at x = 1.5 m; its height
is swept. The robot knows the box's footprint, not its height (``obstacle_heights=false``),
so its swings clear it as if it were ``unknown_obstacle_height_m`` (4 cm) high. Each case
runs with toe-strike handling (the default) and without it (``toe_strike_raise_m=0``) and
reports the outcome, the ticks with a foot on the box (MuJoCo contacts, the recorder of
``reproduce obstacle``), the strikes the controller detected and the least sole clearance
over the box.

    .venv/bin/python benchmarks/toe_strike.py --jobs 2
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path
from typing import Any

from common import add_out_option, command_line, machine_info, run_pool, write_report

HEIGHTS_M = (0.06, 0.08, 0.10, 0.12)
SPEEDS_MPS = (0.5, 0.75)
BOX_X_M = (1.5, 1.6)


def _course(height_m: float, folder: Path) -> Path:
    path = folder / f"box_{height_m:.2f}.json"
    course = {
        "name": f"box {height_m:.2f} m",
        "patches": [{"x": [-1.0, 25.0], "y": [-1.5, 1.5], "z": 0.0, "feet": "both"}],
        "obstacles": [{"x": list(BOX_X_M), "y": [-1.5, 1.5], "height": height_m}],
    }
    path.write_text(json.dumps(course))
    return path


def run_case(job: tuple[float, float, bool, str]) -> dict[str, Any]:
    """One episode: (box height [m], speed [m/s], handling on, course folder)."""
    from gaitnet_mpc.experiments.figure_obstacle import _recorder
    from gaitnet_mpc.scenario import build_episode, make_scenario, run_scenario

    height, speed, handled, folder = job
    overrides = ["obstacle_heights=false"] + ([] if handled else ["toe_strike_raise_m=0"])
    scenario = make_scenario(
        controller="gaitnet",
        course=str(_course(height, Path(folder))),
        vx_mps=speed,
        duration_s=6.0,
        overrides=overrides,
    )
    episode = build_episode(scenario)
    recorder = _recorder(episode)
    summary = run_scenario(scenario, episode=episode, on_step=recorder)
    passes = recorder.passes(episode.sim.model.opt.timestep)
    return {
        "fell": summary["fell"],
        "fall_time_s": summary["fall_time_s"],
        "distance_m": summary["distance_m"],
        "touch_ticks": sum(len(v) for v in recorder.foot_contacts.values()),
        "strikes": sum(e["kind"] == "toe_strike" for e in summary["swing_events"]),
        "clearance_m": min((p["clearance_m"] for p in passes), default=None),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=int, default=2)
    add_out_option(parser, "toe_strike.md")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        jobs = [
            (h, v, handled, folder)
            for h in HEIGHTS_M
            for v in SPEEDS_MPS
            for handled in (True, False)
        ]
        results = run_pool(run_case, jobs, args.jobs, describe=lambda j, r: f"{j[:3]}: {r}")
    lines = [
        "# Toe strikes on boxes of unknown height",
        "",
        machine_info(),
        "",
        "humanoid3d, `gaitnet`, flat ground with one box across the path (x 1.5-1.6 m), 6 s. "
        "The footprint is known, the height is not (`obstacle_heights=false`): swings clear it "
        "as if 4 cm high. Handling on = the default `toe_strike_raise_m` (0.04 m); off = 0. "
        "Touch ticks: 1 ms ticks with a foot in contact with the "
        "box. Clearance: least sole height above the box top while part of a foot is over it "
        "(negative: below the top).",
        "",
        "| box [cm] | speed [m/s] | handling | outcome | distance [m] | strikes "
        "| touch ticks | least clearance [cm] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for (h, v, handled, _), r in results.items():
        outcome = f"fell at {r['fall_time_s']:.2f} s" if r["fell"] else "walked 6 s"
        clear = "-" if r["clearance_m"] is None else f"{100 * r['clearance_m']:.1f}"
        lines.append(
            f"| {100 * h:.0f} | {v} | {'on' if handled else 'off'} | {outcome} | "
            f"{r['distance_m']:.2f} | {r['strikes']} | {r['touch_ticks']} | {clear} |"
        )
    lines += ["", f"Command: `{command_line()}`", ""]
    write_report(args.out, "\n".join(lines))


if __name__ == "__main__":
    main()
