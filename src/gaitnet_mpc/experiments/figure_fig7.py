"""Fig. 7 of the paper: the humanoid over the 3-D stepping stones (run by
:func:`~gaitnet_mpc.experiments.paper_figures.reproduce_figure`; shared pieces in
:mod:`~gaitnet_mpc.experiments.figure_common`).

``fig7`` (3-D stepping stones): ``gaitnet`` on the built-in ``stepping-stones`` at
0.75 m/s. Left: a snapshot strip (:func:`~gaitnet_mpc.results.snapshots.snapshot_strip`,
side view) of the poses kept every :data:`SNAPSHOT_PERIOD_S` while the CoM is over the
stones (collected with ``run_episode``'s ``on_step`` hook). Right: a top view of every
patch (coloured by the foot allowed, as ``plot_course_top``), each touchdown's measured
foot centre (``summary.json`` ``footholds``) and, dashed, each stone's *CoM region*, the
paper's green boxes. How the one-step preview picks the next touchdown's patch here
(``KDWalkController._bounds``, :func:`~gaitnet_mpc.terrain.bounds.reachable_foothold_bounds`):
the CoM predicted at touchdown is the measured CoM plus its velocity times the time left
in the step; a patch that allows the swing foot is a candidate when its eq. 24 box
(shrunk by ``foothold_margin_m`` along x and ``foothold_margin_y_m`` across) meets the
window ``|x - x_CoM| <= foothold_reach_m`` (0.3 m), ``|y - y_CoM| <= reach_y_m``
(0.25 m, the default of ``Course.reachable_foothold_bounds``, which the controller does
not override); the candidate nearest the Raibert foothold wins (no candidate: the patch
nearest the CoM). The region drawn is the set of predicted touchdown CoM positions for
which the stone is a candidate: its *shrunk* box grown by the two reaches. Which
candidate wins depends on the Raibert foothold (on the velocity too), so no CoM region
alone decides it. Claim: the robot crosses with every foothold on allowed terrain.
Rule: no fall, 0 foothold violations and the CoM reaches the final platform (the last
part is not judged in a quick run).
"""

from __future__ import annotations

import inspect
import math
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.experiments.figure_common import (
    ROBOT,
    VX_MPS,
    Log,
    Report,
    fell,
    figure_scenario,
    holds_of,
    outcome,
    rect,
    run_in_folder,
    save_figure,
    touchdowns,
    word,
    write_csv,
)
from gaitnet_mpc.results.plots import FOOT_COLORS, PATCH_COLORS, new_figure
from gaitnet_mpc.runner.episode import VideoConfig
from gaitnet_mpc.scenario import build_episode
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import Course

#: A pose for the snapshot strip every this many seconds while the CoM is over the stones.
SNAPSHOT_PERIOD_S = 0.35
#: Dashed CoM-region colours by the foot a stone allows (the paper's green for both feet).
REGION_COLORS = {"both": "#1b7f2a", "left": FOOT_COLORS["left"], "right": FOOT_COLORS["right"]}


def _reach_y_m() -> float:
    """The lateral half-window of the one-step preview's patch choice [m]: the default of
    ``Course.reachable_foothold_bounds``, which the controller does not override."""
    params = inspect.signature(Course.reachable_foothold_bounds).parameters
    return float(params["reach_y_m"].default)


def com_region(patch: Any, cfg: Any) -> tuple[float, float, float, float]:
    """``(x_min, x_max, y_min, y_max)`` [m]: the predicted CoM positions at touchdown for
    which ``patch`` is a candidate of the one-step preview, with the ``KDWalkConfig``
    ``cfg`` (module docstring)."""
    lo, hi = patch.foothold_box(cfg.foothold_margin_m, cfg.foothold_margin_y_m)
    rx, ry = cfg.foothold_reach_m, _reach_y_m()
    return lo[0] - rx, hi[0] + rx, lo[1] - ry, hi[1] + ry


def build_fig7(
    out: Path, duration_s: float, video: VideoConfig | None, log: Log, quick: bool
) -> Report:
    from PIL import Image

    from gaitnet_mpc.results.snapshots import snapshot_strip

    scenario = figure_scenario("gaitnet", "stepping-stones", VX_MPS, duration_s)
    episode = build_episode(scenario)
    course, cfg = episode.course, scenario.config
    first = min(course.patches, key=lambda p: p.x_min)
    last = max(course.patches, key=lambda p: p.x_max)
    stones = [(i, p) for i, p in enumerate(course.patches) if p is not first and p is not last]
    x_lo, x_hi = min(p.x_min for _, p in stones), max(p.x_max for _, p in stones)
    trunk = episode.sim.model.body(episode.robot.spec.trunk_body).id
    poses: list[tuple[float, np.ndarray]] = []
    next_t = [0.0]

    def keep(sim: Simulator) -> None:
        if sim.time_s >= next_t[0] - 1e-9:
            poses.append((float(sim.data.subtree_com[trunk][0]), sim.data.qpos.copy()))
            next_t[0] += SNAPSHOT_PERIOD_S

    run = run_in_folder(scenario, out / "runs" / "gaitnet-stones", video, log, episode, keep)
    # the poses over the stones; a run that never reached them: its last six
    kept = [q for x, q in poses if x_lo <= x <= x_hi] or [q for _, q in poses[-6:]]
    strip = snapshot_strip(
        episode.sim, np.array(kept), out / "fig7_strip.png", width_px=1400, height_px=600,
        title=f"gaitnet, {VX_MPS:g} m/s: a pose every {SNAPSHOT_PERIOD_S:g} s over the stones",
    )  # fmt: skip
    holds = holds_of(run)
    rows: list[dict[str, Any]] = [
        {"kind": "touchdown", "index": i, "foot": h["foot"], "t_s": h["t_s"],
         "x_m": h["pos_m"][0], "y_m": h["pos_m"][1], "z_m": h["pos_m"][2],
         "patch": h["patch"], "allowed": h["allowed"]}
        for i, h in enumerate(holds)
    ]  # fmt: skip
    box_keys = ("x_min_m", "x_max_m", "y_min_m", "y_max_m")
    for i, p in enumerate(course.patches):
        box = dict(zip(box_keys, (p.x_min, p.x_max, p.y_min, p.y_max), strict=True))
        rows.append({"kind": "patch", "index": i, "foot": p.feet, "z_m": p.z_top_m, **box})
    for i, p in stones:
        box = dict(zip(box_keys, com_region(p, cfg), strict=True))
        rows.append({"kind": "com_region", "index": i, "foot": p.feet, "z_m": p.z_top_m, **box})
    write_csv(out, "fig7", rows)

    fig = new_figure(17.0, 4.3)
    ax_s, ax_t = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.0, 1.45]})
    with Image.open(strip) as img:
        ax_s.imshow(np.asarray(img.convert("RGB")))
    ax_s.set_axis_off()
    ax_s.set_title("simulation snapshots (side view, earlier poses fainter)", fontsize=9)
    for p in course.patches:
        rect(ax_t, (p.x_min, p.x_max), (p.y_min, p.y_max), facecolor=PATCH_COLORS[p.feet],
             edgecolor="0.2", lw=0.5, alpha=0.45)  # fmt: skip
    for i, p in stones:
        rx0, rx1, ry0, ry1 = com_region(p, cfg)
        rect(ax_t, (rx0, rx1), (ry0, ry1), fill=False, ls="--", lw=0.8, alpha=0.8,
             edgecolor=REGION_COLORS[p.feet])  # fmt: skip
        ax_t.annotate(str(i), (p.x_center_m, p.y_center_m), ha="center", va="center", fontsize=7)
    ax_t.plot(run.log["com_x_m"], run.log["com_y_m"], color="black", lw=0.8, alpha=0.6,
              label="CoM path")  # fmt: skip
    touchdowns(ax_t, holds, lambda h: h["pos_m"][1])
    bad = np.array([h["pos_m"][:2] for h in holds if not h["allowed"]]).reshape(-1, 2)
    if bad.size:
        ax_t.scatter(bad[:, 0], bad[:, 1], marker="x", s=120, color="black", linewidths=2.2,
                     zorder=4, label="touchdown on a forbidden patch / hole")  # fmt: skip
    ax_t.plot([], [], ls="--", color=REGION_COLORS["both"], label="CoM region of a stone")
    x_view = max(x_hi + 0.5, max((h["pos_m"][0] for h in holds), default=0.0) + 0.15)
    ax_t.set(xlim=(-0.3, x_view), ylim=(-0.65, 0.65), xlabel="x [m]", ylabel="y [m]")
    ax_t.set_aspect("equal")
    ax_t.set_title(
        f"{len(holds)} touchdowns, {run.summary['foothold_violations']} violations; dashed: CoM "
        f"at touchdown within {cfg.foothold_reach_m:g} m (x) of the stone's shrunk box",
        fontsize=9,
    )
    fig.legend(*ax_t.get_legend_handles_labels(), loc="outside lower right", fontsize=7, ncols=6)
    fig.suptitle(f"Fig. 7: {ROBOT} on the 3-D stepping stones, {outcome(run)}", fontsize=10)
    save_figure(fig, out, "fig7")

    com_x = float(run.log["com_x_m"][-1])
    crossed = com_x >= last.x_min
    on_stones = sum(1 for h in holds if h["patch"] is not None and x_lo <= h["pos_m"][0] <= x_hi)
    n_bad = int(run.summary["foothold_violations"])
    ok = not fell(run) and n_bad == 0 and (quick or crossed)
    steps = run.summary.get("step_durations_s") or [math.nan]
    table = [
        "| quantity | ours | paper (Fig. 7, Sec. V-D) |", "|---|---|---|",
        f"| outcome | {outcome(run)} | reaches the end of the course |",
        f"| CoM x at the end | {com_x:.2f} m (final platform from {last.x_min:.2f} m: "
        f"{'reached' if crossed else 'not reached'}) | the end of the course |",
        f"| touchdowns (on the stones) | {len(holds)} ({on_stones}) | the feet's centres plotted |",
        f"| foothold violations | {n_bad} | 0: every foothold on an allowed patch |",
        f"| leg-contact ticks | {run.summary.get('self_collisions', 0)} | not stated |",
        f"| step durations | {min(steps):.3f}-{max(steps):.3f} s | variable (Gait-Net) |",
    ]  # fmt: skip
    rule = "no fall, 0 foothold violations" + ("" if quick else ", CoM on the final platform")
    claims = [
        "- *the robot crosses the stepping stones with every foothold on allowed terrain*: "
        f"**{word(ok)}** (rule: {rule})."
        + (" The crossing is not judged in a quick run." if quick else "")
    ]
    notes = [
        "CoM regions (dashed): for each stone, the CoM predicted at touchdown (measured CoM "
        "plus its velocity times the time left in the step) for which the one-step preview "
        "counts the stone as a candidate for the next touchdown: its eq. 24 box (shrunk "
        f"{cfg.foothold_margin_m:g} m along x, {cfg.foothold_margin_y_m:g} m across) grown by "
        f"foothold_reach_m = {cfg.foothold_reach_m:g} m along x and {_reach_y_m():g} m across; "
        "of the candidates the one nearest the Raibert foothold is chosen. The paper does "
        "not specify its trigger regions further. Snapshots: `fig7_strip.png`."
    ]
    setup = (
        f"`{ROBOT}`, `gaitnet` (default settings, one-step preview), built-in "
        f"`stepping-stones`, {VX_MPS:g} m/s."
    )
    return Report("Fig. 7: 3-D stepping stones", setup, table, claims, notes, [run])


__all__ = ["REGION_COLORS", "SNAPSHOT_PERIOD_S", "build_fig7", "com_region"]
