"""What the paper's humanoid figures share (:mod:`~gaitnet_mpc.experiments.paper_figures`
runs them; one module each: :mod:`~gaitnet_mpc.experiments.figure_fig7`,
:mod:`~gaitnet_mpc.experiments.figure_fig8`, :mod:`~gaitnet_mpc.experiments.figure_fig9`,
:mod:`~gaitnet_mpc.experiments.figure_fig10`,
:mod:`~gaitnet_mpc.experiments.figure_fig11`,
:mod:`~gaitnet_mpc.experiments.figure_obstacle`).

The robot, the commanded speeds and ``kd``'s fixed dt (:data:`KD_DT_S`); the scenario of a
figure's run (:func:`figure_scenario`: default settings) and the episode runner
(:func:`run_in_folder`); what a figure's Markdown says (:class:`Report`, written by
:func:`markdown`); the helpers every figure's verdict uses (:func:`fell`, :func:`outcome`,
:func:`word`, ...); and the files (:func:`write_csv` with the columns of
:data:`CSV_FIELDS`, :func:`save_figure`) and drawing helpers (:func:`rect`,
:func:`touchdowns`, :data:`CONTROLLER_COLORS`).
"""

from __future__ import annotations

import csv
import io
import itertools
import math
import shutil
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.machine import machine_info
from gaitnet_mpc.results.io import write_atomic, write_bytes_atomic
from gaitnet_mpc.results.plots import FOOT_COLORS, FOOT_MARKERS
from gaitnet_mpc.results.rundir import RUN_ARTIFACTS, RunFolder, load_run
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.runner.episode import VideoConfig
from gaitnet_mpc.scenario import (
    Episode,
    Scenario,
    build_episode,
    make_scenario,
    simulate_episode,
)
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import Course

ROBOT = "humanoid3d"
#: Commanded forward speeds [m/s]: the paper's 0.75 m/s; the obstacle run at 0.5 m/s.
VX_MPS = 0.75
VX_OBSTACLE_MPS = 0.5
#: Fixed dt of ``kd`` [s] (the README's headline ``kd`` row and the demo's stones run).
KD_DT_S = 0.045
#: Time series in the CSV files: one row every this many control ticks (5 ms).
CSV_EVERY_TICKS = 5
CONTROLLER_COLORS = {"gaitnet": "tab:blue", "kd": "tab:orange"}
#: Columns of each figure's CSV file.
CSV_FIELDS = {
    "fig7": "kind index foot t_s x_m y_m z_m x_min_m x_max_m y_min_m y_max_m patch allowed",
    "fig8": "controller t_s t_pred_s lGx_pred lGx_meas kGy_pred kGy_meas kGz_pred kGz_meas",
    "fig9": "run t_s dt_s step_s disturbed nominal",
    "fig10": "controller t_s t_since_contact_s com_x_m cart_x_m cart_vx_mps hand_push_n "
    "max_tau_ratio",
    "fig11": "controller t_s com_x_m com_vx_mps cmd_vx_mps ramped_cmd_vx_mps com_over_gap",
    "obstacle": "case kind t_s foot x_m sole_z_m over_obstacle allowed",
}
_TOUCHDOWN_STYLE = {"s": 34, "edgecolors": "white", "linewidths": 0.5, "zorder": 3}

Log = Callable[[str], None]


@dataclass
class Report:
    """What a figure's Markdown says; :func:`markdown` adds the run lines."""

    title: str
    setup: str
    table: list[str]
    claims: list[str]
    notes: list[str] = field(default_factory=list)
    runs: list[RunFolder] = field(default_factory=list)


def figure_scenario(controller: str, course: str, vx_mps: float, duration_s: float) -> Scenario:
    dt = KD_DT_S if controller == "kd" else None
    return make_scenario(
        robot=ROBOT, controller=controller, course=course, vx_mps=vx_mps,
        duration_s=duration_s, dt_s=dt,
    )  # fmt: skip


def run_in_folder(
    scenario: Scenario,
    folder: Path,
    video: VideoConfig | None,
    log: Log,
    episode: Episode | None = None,
    on_step: Callable[[Simulator], None] | None = None,
) -> RunFolder:
    """One episode into the run folder ``folder`` (an earlier run's files there removed):
    ``simulate_episode`` (the folder is the figure's own), with ``on_step`` as its hook.

    Raises:
        KeyboardInterrupt: the episode was interrupted (its run folder is kept).
    """
    for item in RUN_ARTIFACTS:
        target = folder / item
        if target.is_dir():
            shutil.rmtree(target)
        elif target.exists():
            target.unlink()
    t0 = time.perf_counter()
    episode = build_episode(scenario) if episode is None else episode
    simulate_episode(episode, folder, video=video, on_step=on_step)
    run = load_run(folder)
    s = run.summary
    if s.get("interrupted"):  # run_episode stops on Ctrl-C / SIGTERM: so does the figure
        raise KeyboardInterrupt
    log(
        f"{run.label}: {outcome(run)}, {s['distance_m']:.2f} m, "
        f"{s['foothold_violations']} foothold violations ({time.perf_counter() - t0:.0f} s)"
    )
    return run


def fell(run: RunFolder) -> bool:
    return bool(run.summary.get("fell"))


def outcome(run: RunFolder) -> str:
    s = run.summary
    if s.get("fell"):
        return f"fell at {float(s['fall_time_s']):.2f} s ({s.get('fall_reason') or '?'})"
    return f"no fall in {float(s['duration_s']):g} s ({s.get('outcome', '?')})"


def word(holds: bool) -> str:
    return "holds" if holds else "does not hold"


def holds_of(run: RunFolder) -> list[dict[str, Any]]:
    return list(run.summary.get("footholds") or [])


def both_feet_beyond(run: RunFolder, x_m: float) -> bool:
    """Whether each foot has a touchdown with its centre beyond ``x_m``."""
    holds = holds_of(run)
    return all(any(h["foot"] == f and h["pos_m"][0] > x_m for h in holds) for f in FEET)


def holes(course: Course) -> list[tuple[float, float]]:
    """x ranges between consecutive patches along the walkway (holes) [m]."""
    ps = sorted(course.patches, key=lambda p: p.x_min)
    return [(a.x_max, b.x_min) for a, b in itertools.pairwise(ps) if b.x_min > a.x_max]


def cm_text(value_m: float) -> str:
    return f"{100 * value_m:.1f} cm" if math.isfinite(value_m) else "-"


def save_figure(fig: Any, out: Path, name: str) -> None:
    """``<name>.png`` and ``<name>.svg`` in ``out``, each written atomically."""
    for fmt in ("png", "svg"):
        buf = io.BytesIO()
        fig.savefig(buf, format=fmt, dpi=110)
        write_bytes_atomic(out / f"{name}.{fmt}", buf.getvalue())


def _cell(v: Any) -> Any:
    if isinstance(v, bool | np.bool_):
        return int(v)
    if isinstance(v, float | np.floating):
        return f"{float(v):.6g}" if math.isfinite(float(v)) else ""
    return "" if v is None else v


def write_csv(out: Path, name: str, rows: Sequence[dict[str, Any]]) -> None:
    """``<name>.csv``: the columns :data:`CSV_FIELDS` names (empty: not applicable)."""
    fields = CSV_FIELDS[name].split()
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    w.writeheader()
    for row in rows:
        w.writerow({k: _cell(row.get(k)) for k in fields})
    write_atomic(out / f"{name}.csv", buf.getvalue())


def markdown(r: Report, quick: bool, duration_s: float, wall_s: float) -> str:
    runs = [
        f"- `runs/{run.label}`: `{run.summary.get('controller')}` on "
        f"`{run.summary.get('course')}`, {outcome(run)}"
        + (", with video.mp4" if (run.path / "video.mp4").is_file() else "")
        for run in r.runs
    ]
    mode = f"{duration_s:g} s of simulated time per episode"
    if quick:
        mode += " (quick: no video; a check that the figure is made, not the paper's experiment)"
    lines = [
        f"# {r.title}", "", r.setup, "", *r.table, "", "## The paper's claim", "", *r.claims,
        "", *r.notes, "", "## Run", "", f"- {mode}", *runs, f"- wall time: {wall_s:.0f} s",
        f"- machine: {machine_info(('numpy', 'mujoco', 'pin'))}", "",
    ]  # fmt: skip
    return "\n".join(lines)


def rect(ax: Any, x: tuple[float, float], y: tuple[float, float], **style: Any) -> None:
    from matplotlib.patches import Rectangle

    ax.add_patch(Rectangle((x[0], y[0]), x[1] - x[0], y[1] - y[0], **style))


def touchdowns(ax: Any, holds: Sequence[dict[str, Any]], y_of: Callable[[Any], float]) -> None:
    """Each foot's touchdowns at (foot centre x, ``y_of(touchdown)``), by foot."""
    for foot in FEET:
        pts = np.array([(h["pos_m"][0], y_of(h)) for h in holds if h["foot"] == foot])
        pts = pts.reshape(-1, 2)
        ax.scatter(pts[:, 0], pts[:, 1], marker=FOOT_MARKERS[foot], color=FOOT_COLORS[foot],
                   label=f"{foot} foot at touchdown", **_TOUCHDOWN_STYLE)  # fmt: skip


__all__ = [
    "CONTROLLER_COLORS",
    "CSV_EVERY_TICKS",
    "CSV_FIELDS",
    "KD_DT_S",
    "ROBOT",
    "VX_MPS",
    "VX_OBSTACLE_MPS",
    "Log",
    "Report",
    "both_feet_beyond",
    "cm_text",
    "fell",
    "figure_scenario",
    "holds_of",
    "holes",
    "markdown",
    "outcome",
    "rect",
    "run_in_folder",
    "save_figure",
    "touchdowns",
    "word",
    "write_csv",
]
