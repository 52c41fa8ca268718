"""The soak's Markdown report (:func:`make_report`) of the finished episodes' records: the
counts by controller and robot, the wall time per episode (for sizing runs), how each
controller handles a failed solve, the episodes with handled QP failures, every failing
episode (an exception, non-finite torques, a diverged simulation) with the command
replaying it, and the warnings."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gaitnet_mpc.experiments.soak.draw import DrawSettings, EpisodeSpec
from gaitnet_mpc.machine import machine_info

#: How each controller handles a failed solve (for the report).
FAILURE_HANDLING = {
    "kd": "QPSolveError caught in KDWalkController._solve: the last good plan is kept",
    "gaitnet": "as kd (the same KDWalkController, with the Gait-Net dt policy)",
    "srbm": "QPSolveError caught in SRBMWalkController: the last good wrench is kept",
    "wbmpc": "an unsuccessful NLP solve is not a fallback: its iterate is used as the plan",
    "stand": "no MPC",
}


@dataclass
class _Tally:
    episodes: int = 0
    exceptions: int = 0
    nonfinite: int = 0
    diverged: int = 0
    qp_failures: int = 0
    episodes_with_qp_failures: int = 0
    unconverged: int = 0
    solves: int = 0
    falls: int = 0
    sim_s: float = 0.0
    wall_s: float = 0.0
    walls: list[float] = field(default_factory=list)

    def add(self, r: dict[str, Any]) -> None:
        self.episodes += 1
        self.exceptions += r["exception"] is not None and not r["nonfinite_torque"]
        self.nonfinite += bool(r["nonfinite_torque"])
        self.diverged += bool(r["diverged"])
        self.qp_failures += int(r["qp_failures"])
        self.episodes_with_qp_failures += r["qp_failures"] > 0
        self.unconverged += int(r["unconverged"])
        self.solves += int(r["solves"])
        self.falls += bool(r["fell"])
        self.sim_s += float(r["sim_s"] or 0.0)
        self.wall_s += float(r["wall_s"] or 0.0)
        self.walls.append(float(r["wall_s"] or 0.0))


def _failing(r: dict[str, Any]) -> bool:
    return r["exception"] is not None or bool(r["nonfinite_torque"]) or bool(r["diverged"])


def make_report(
    records: dict[int, dict[str, Any]],
    settings: DrawSettings,
    n_episodes: int,
    command_line: str,
    run_wall_s: float,
    interrupted: bool,
) -> str:
    """The Markdown report of the finished episodes."""
    from gaitnet_mpc.experiments.collect import provenance

    prov = provenance()
    rows = [records[i] for i in sorted(records) if i < n_episodes]
    cells: dict[tuple[str, str], _Tally] = {}
    by_controller: dict[str, _Tally] = {}
    total = _Tally()
    for r in rows:
        key = (r["spec"]["controller"], r["spec"]["robot"])
        cells.setdefault(key, _Tally()).add(r)
        by_controller.setdefault(key[0], _Tally()).add(r)
        total.add(r)
    state = "interrupted, " if interrupted else ""
    lines = [
        "# Soak test: random episodes",
        "",
        f"Machine: {machine_info(('numpy', 'mujoco', 'pin', 'casadi', 'piqp', 'ray'))}.",
        f"Code: gaitnet_mpc {prov['gaitnet_mpc']}, commit {prov['git_commit']}.",
        "",
        f"Command: `{command_line}`. Settings: {json.dumps(settings.to_dict())}.",
        "",
        f"{len(rows)} of {n_episodes} episodes done ({state}{total.sim_s:.1f} simulated s); "
        f"wall time of the episodes {total.wall_s:.0f} s (summed over workers), of this "
        f"invocation {run_wall_s:.0f} s.",
        "",
        "| controller | robot | episodes | exceptions | non-finite torques | diverged | "
        "QP failures handled (episodes) | unconverged / solves | falls | sim [s] | wall [s] |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (controller, robot), t in sorted(cells.items()):
        lines.append(
            f"| {controller} | {robot} | {t.episodes} | {t.exceptions} | {t.nonfinite} | "
            f"{t.diverged} | {t.qp_failures} ({t.episodes_with_qp_failures}) | "
            f"{t.unconverged} / {t.solves} | {t.falls} | {t.sim_s:.1f} | {t.wall_s:.0f} |"
        )
    t = total
    lines.append(
        f"| **all** | | {t.episodes} | {t.exceptions} | {t.nonfinite} | {t.diverged} | "
        f"{t.qp_failures} ({t.episodes_with_qp_failures}) | {t.unconverged} / {t.solves} | "
        f"{t.falls} | {t.sim_s:.1f} | {t.wall_s:.0f} |"
    )
    lines += [
        "",
        "Falls exclude diverged simulations. Wall time per episode, for sizing runs:",
        "",
        "| controller | episodes | wall per episode [s] (median, max) | wall per sim-s [s] |",
        "|---|---|---|---|",
    ]
    for name, t in sorted(by_controller.items()):
        lines.append(
            f"| {name} | {t.episodes} | {np.median(t.walls):.1f}, {max(t.walls):.1f} | "
            f"{t.wall_s / max(t.sim_s, 1e-9):.1f} |"
        )
    lines += ["", "How a failed solve is handled:", ""]
    lines += [f"- {name}: {FAILURE_HANDLING[name]}" for name in sorted(by_controller)]
    handled = [r for r in rows if r["qp_failures"]]
    if handled:
        lines += ["", "## QP failures handled, by episode", ""]
        lines += [
            f"- episode {r['index']} ({EpisodeSpec.from_dict(r['spec']).label()}): "
            f"{r['qp_failures']} of {r['solves']} solves"
            + (f", then fell ({r['fall_reason']})" if r["fell"] else ", no fall")
            for r in handled
        ]
    failing = [r for r in rows if _failing(r)]
    lines += ["", "## Episodes to replay", ""]
    if not failing:
        lines.append("- none: no exception, non-finite torque or diverged simulation")
    for r in failing:
        spec = EpisodeSpec.from_dict(r["spec"])
        exc = r["exception"]
        if exc is not None:
            what = f"{exc['type']}: {exc['message']} ({exc['where']})"
        else:
            what = f"diverged: {r['fall_reason']}"
        lines += [
            f"- episode {spec.index} ({spec.label()}): {what}",
            f"  - replay: `MUJOCO_GL=egl .venv/bin/python benchmarks/soak.py "
            f"{settings.command_flags()} --replay {spec.index}`",
            f"  - spec: `{json.dumps(r['spec'])}`",
        ]
    warned = [r for r in rows if r["python_warnings"] or r["mujoco_warnings"]]
    if warned:
        lines += ["", "## Warnings", ""]
        for r in warned[:30]:
            text = "; ".join(r["python_warnings"])
            if r["mujoco_warnings"]:
                text = f"MuJoCo {r['mujoco_warnings']}; {text}"
            lines.append(f"- episode {r['index']}: {text[:300]}")
        if len(warned) > 30:
            lines.append(f"- ... {len(warned) - 30} more episodes (see the JSONL)")
    return "\n".join(lines) + "\n"
