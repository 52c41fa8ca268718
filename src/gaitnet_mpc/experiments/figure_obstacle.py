"""Fig. 1(e) of the paper: the humanoid over an obstacle and a hole, swing-foot clearance
(run by :func:`~gaitnet_mpc.experiments.paper_figures.reproduce_figure`; shared pieces in
:mod:`~gaitnet_mpc.experiments.figure_common`).

``obstacle`` (Fig. 1(e)): ``gaitnet`` on the built-in ``obstacle`` course (a 10 cm long,
3 cm high box across the walkway at x = 1.5 m, then a 15 cm hole from x = 2.2 m), in the
cases of :data:`CASES`: at 0.5 m/s (the paper's) and 0.75 m/s, with the obstacle's box
and height known to the controller (``terrain_knowledge.obstacle_heights``, the default
one-step preview) and unknown (as on the paper's hardware). Then (not in a quick run)
the seeded ``obstacle`` courses :data:`SEEDS` at 0.75 m/s, heights known, and the same
layouts with boxes up to :data:`UNKNOWN_MAX_HEIGHT_M` with heights unknown. The run files
hold no foot position per tick, so :class:`FootRecorder` (the ``on_step`` hook) reads
``sim.data``: per foot, the lowest point of its box (points along its four long edges,
:data:`SOLE_SAMPLES` each) overall and inside an obstacle's x range, and every contact
of an obstacle with a robot geom. A *pass* is a stretch of ticks with part of a foot
over an obstacle's x range; its clearance is the least height above that obstacle's top
of a foot point inside the range (at most 0: the foot hit it). Touchdowns:
``summary.json`` ``footholds``, located against the obstacle (by the foot's extent, toe
to heel) and the hole. Claim: the robot clears the obstacle and the gap. Rule (per
case): no fall, 0 foothold violations, no tick with a robot body touching the obstacle
(feet included: a foot neither lands on nor clips it), no touchdown over it, both feet
beyond the obstacle and (not judged in a quick run) beyond the hole. A seeded course is
*clean* as the issue tracker counts it: no fall, no foothold violation (a non-foot
contact with the terrain is a fall); feet that touched an obstacle are counted beside.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.experiments.figure_common import (
    CSV_EVERY_TICKS,
    ROBOT,
    VX_OBSTACLE_MPS,
    Log,
    Report,
    RunFolder,
    both_feet_beyond,
    cm_text,
    fell,
    holds_of,
    holes,
    outcome,
    rect,
    run_in_folder,
    save_figure,
    touchdowns,
    word,
    write_csv,
)
from gaitnet_mpc.results.io import write_atomic
from gaitnet_mpc.results.plots import FOOT_COLORS, OBSTACLE_COLOR, PATCH_COLORS, new_figure
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.runner.episode import VideoConfig
from gaitnet_mpc.scenario import Episode, Scenario, build_episode, make_scenario
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import Course, Obstacle, load_course

#: Points along each long edge of a foot's box where its height is taken.
SOLE_SAMPLES = 31
#: Seeded ``obstacle`` layouts run after the built-in course (full runs only).
SEEDS = tuple(range(20))
#: Speed of the seeded runs [m/s] (the paper's walking speed).
VX_SEEDED_MPS = 0.75
#: Tallest box of the seeded layouts run with the obstacle unknown [m]: the height the
#: swings assume then (``KDWalkConfig.unknown_obstacle_height_m``).
UNKNOWN_MAX_HEIGHT_M = 0.04


@dataclass(frozen=True)
class Case:
    """One run on the built-in course: speed and whether the obstacle is known."""

    vx_mps: float
    heights_known: bool

    @property
    def label(self) -> str:
        return f"{self.vx_mps:g} m/s, obstacle " + ("known" if self.heights_known else "unknown")

    @property
    def folder(self) -> str:
        return f"gaitnet-obstacle-{self.vx_mps:g}" + ("" if self.heights_known else "-unknown")


#: The built-in course's cases; a quick run takes the first only.
CASES = (
    Case(VX_OBSTACLE_MPS, True),
    Case(0.75, True),
    Case(VX_OBSTACLE_MPS, False),
    Case(0.75, False),
)


def _scenario(
    course: str, vx_mps: float, duration_s: float, known: bool, seed: int | None
) -> Scenario:
    overrides = [] if known else ["obstacle_heights=false"]
    return make_scenario(
        robot=ROBOT, controller="gaitnet", course=course, vx_mps=vx_mps,
        duration_s=duration_s, course_seed=seed, overrides=overrides,
    )  # fmt: skip


class FootRecorder:
    """``on_step`` hook: each foot's height per tick, overall and over the obstacles' x
    ranges, and the obstacles' contacts with robot geoms (module docstring). It reads
    ``sim.data`` only.

    Attributes:
        trace: per foot, ``(t_s, foot centre x, lowest point z, over an obstacle)`` every
            :data:`CSV_EVERY_TICKS` ticks.
        over: per foot, ``(t_s, least height of the foot above the top of the obstacle
            it is over)`` at every tick with part of the foot in an obstacle's x range.
        foot_contacts: per foot, the times [s] it touched an obstacle.
        other_contact_ticks: ticks a robot geom other than a foot touched an obstacle;
            ``other_bodies``: their bodies' names.
    """

    def __init__(self, sim: Simulator, obstacles: Sequence[Obstacle], geom_ids: list[int]):
        m, spec = sim.model, sim.robot.spec
        self.ranges = np.array([(o.x_min, o.x_max, o.z_top_m) for o in obstacles]).reshape(-1, 3)
        self.obstacle_geoms = np.array(geom_ids, dtype=int)
        # ids in the scene model (the course's geoms come first: not the robot model's ids)
        self.foot_geoms = {f: [m.geom(name).id for name in spec.foot_geoms[f]] for f in FEET}
        self.foot_of = {g: f for f in FEET for g in self.foot_geoms[f]}
        self.site = {f: m.site(spec.foot_sites[f]).id for f in FEET}
        u = np.linspace(-1.0, 1.0, SOLE_SAMPLES)
        unit = np.array([[x, a, b] for a in (-1.0, 1.0) for b in (-1.0, 1.0) for x in u])
        self.local = {g: unit * m.geom_size[g][None, :] for g in self.foot_of}  # box geoms
        self.trace: dict[str, list[tuple[float, float, float, bool]]] = {f: [] for f in FEET}
        self.over: dict[str, list[tuple[float, float]]] = {f: [] for f in FEET}
        self.foot_contacts: dict[str, list[float]] = {f: [] for f in FEET}
        self.other_contact_ticks = 0
        self.other_bodies: set[str] = set()
        self._tick = 0

    def __call__(self, sim: Simulator) -> None:
        d, t = sim.data, sim.time_s
        keep = self._tick % CSV_EVERY_TICKS == 0
        self._tick += 1
        lo, hi, top = self.ranges[:, 0], self.ranges[:, 1], self.ranges[:, 2]
        for f in FEET:
            pts = np.concatenate([
                d.geom_xpos[g] + self.local[g] @ d.geom_xmat[g].reshape(3, 3).T
                for g in self.foot_geoms[f]
            ])  # fmt: skip
            inside = (pts[:, :1] >= lo) & (pts[:, :1] <= hi)  # (points, obstacles)
            over = inside.any()
            if over:
                above = np.where(inside, pts[:, 2:3] - top, np.inf)
                self.over[f].append((t, float(above.min())))
            if keep:
                x = float(d.site_xpos[self.site[f]][0])
                self.trace[f].append((t, x, float(pts[:, 2].min()), bool(over)))
        if d.ncon == 0:
            return
        pairs = np.asarray(d.contact.geom).reshape(-1, 2)
        hit = np.isin(pairs, self.obstacle_geoms)
        partner = np.where(hit[:, 0], pairs[:, 1], np.where(hit[:, 1], pairs[:, 0], -1))
        other = [int(g) for g in partner if g >= 0 and sim.model.geom_bodyid[g] != 0]
        for f in {self.foot_of[g] for g in other if g in self.foot_of}:
            self.foot_contacts[f].append(t)
        rest = [g for g in other if g not in self.foot_of]
        if rest:
            self.other_contact_ticks += 1
            self.other_bodies.update(
                sim.model.body(int(sim.model.geom_bodyid[g])).name for g in rest
            )

    def passes(self, timestep_s: float) -> list[dict[str, Any]]:
        """Each stretch of ticks with part of a foot over an obstacle's x range: ``foot``,
        ``t0_s``, ``t1_s``, ``clearance_m`` (least height above the obstacle's top) and
        ``touched`` (the foot touched an obstacle then)."""
        out = []
        for f in FEET:
            ticks = self.over[f]
            start = 0
            for i in range(1, len(ticks) + 1):
                if i < len(ticks) and ticks[i][0] - ticks[i - 1][0] <= 1.5 * timestep_s:
                    continue
                seg = ticks[start:i]
                t0, t1 = seg[0][0], seg[-1][0]
                touched = any(t0 <= tc <= t1 for tc in self.foot_contacts[f])
                clearance = min(z for _, z in seg)
                out.append({"foot": f, "t0_s": t0, "t1_s": t1, "clearance_m": clearance,
                            "touched": touched})  # fmt: skip
                start = i
        return sorted(out, key=lambda p: p["t0_s"])


def _recorder(episode: Episode) -> FootRecorder:
    course, sim = episode.course, episode.sim
    ids = [sim.model.geom(f"obstacle_{i}").id for i in range(len(course.obstacles))]
    return FootRecorder(sim, course.obstacles, ids)


def _where(course: Course, foot_extent_m: tuple[float, float], x: float) -> str:
    """Where a touchdown at foot-centre ``x`` lies: over an obstacle, before, between an
    obstacle and the next hole, in a hole, or beyond (the first obstacle and hole)."""
    toe, heel = foot_extent_m
    if any(x + toe >= ob.x_min and x - heel <= ob.x_max for ob in course.obstacles):
        return "over the obstacle"
    box = course.obstacles[0]
    h0, h1 = holes(course)[0]
    if x < box.x_min:
        return "before the obstacle"
    return "obstacle to hole" if x <= h0 else "in the hole" if x < h1 else "beyond the hole"


@dataclass
class CaseResult:
    """What one run on an obstacle course showed (module docstring's rule)."""

    run: RunFolder
    recorder: FootRecorder
    passes: list[dict[str, Any]]
    on_obstacle: int
    beyond_box: bool
    beyond_hole: bool
    violations: int

    @property
    def least_clearance_m(self) -> float:
        return min((p["clearance_m"] for p in self.passes), default=math.inf)

    @property
    def foot_touch_ticks(self) -> int:
        return sum(len(v) for v in self.recorder.foot_contacts.values())

    def holds(self, quick: bool) -> bool:
        return (
            not fell(self.run)
            and self.violations == 0
            and self.recorder.other_contact_ticks == 0
            and self.foot_touch_ticks == 0
            and self.on_obstacle == 0
            and self.beyond_box
            and (quick or self.beyond_hole)
        )


def _run(
    out: Path, folder: str, scenario: Scenario, video: VideoConfig | None, log: Log
) -> tuple[CaseResult, Episode]:
    episode = build_episode(scenario)
    rec = _recorder(episode)
    run = run_in_folder(scenario, out / "runs" / folder, video, log, episode, rec)
    course, spec = episode.course, episode.robot.spec
    holds = holds_of(run)
    extent = (spec.foot_toe_m, spec.foot_heel_m)
    last_box = course.obstacles[-1].x_max
    result = CaseResult(
        run=run,
        recorder=rec,
        passes=rec.passes(episode.sim.model.opt.timestep),
        on_obstacle=sum(
            1 for h in holds if _where(course, extent, h["pos_m"][0]) == "over the obstacle"
        ),
        beyond_box=both_feet_beyond(run, last_box),
        beyond_hole=both_feet_beyond(run, holes(course)[-1][1]),
        violations=int(run.summary["foothold_violations"]),
    )
    return result, episode


def _figure(out: Path, course: Course, res: CaseResult, r_foot: float) -> None:
    rec, run = res.recorder, res.run
    box = course.obstacles[0]
    h0, h1 = holes(course)[0]
    holds = holds_of(run)
    z_top = max((z for f in FEET for _, _, z, _ in rec.trace[f]), default=0.1)
    x_end = max([h1, *(x for f in FEET for _, x, _, _ in rec.trace[f])]) + 0.2
    fig = new_figure(11.0, 7.5)
    axes = fig.subplots(2, 1)
    views = ((-0.3, x_end), (box.x_min - 0.35, box.x_max + 0.35))
    cm = 100 * box.height_m
    for ax, (xa, xb) in zip(axes, views, strict=True):
        for p in course.patches:
            rect(ax, (p.x_min, p.x_max), (p.z_top_m - 0.03, p.z_top_m),
                 facecolor=PATCH_COLORS[p.feet], alpha=0.5, lw=0)  # fmt: skip
        rect(ax, (box.x_min, box.x_max), (box.z_base_m, box.z_top_m), hatch="//",
             facecolor=OBSTACLE_COLOR, edgecolor="0.2", label=f"obstacle, {cm:g} cm")  # fmt: skip
        ax.axvspan(h0, h1, color="tab:red", alpha=0.2, lw=0, label=f"hole, {100 * (h1 - h0):g} cm")
        for f in FEET:
            tr = np.array(rec.trace[f]).reshape(-1, 4)
            ax.plot(tr[:, 1], tr[:, 2], color=FOOT_COLORS[f], lw=1.0,
                    label=f"{f} foot: its lowest point")  # fmt: skip
        touchdowns(ax, holds, lambda h: h["pos_m"][2] - r_foot)
        ax.set(xlim=(xa, xb), ylim=(-0.04, min(0.4, z_top + 0.02)),
               xlabel="x of the foot centre [m]", ylabel="height [m]")  # fmt: skip
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=7, ncols=3)
    passes = res.passes
    axes[1].set_title(
        "over the obstacle (the foot is 15 cm long): least clearance per pass "
        + ", ".join(f"{p['foot']} {cm_text(p['clearance_m'])}" for p in passes),
        fontsize=9,
    )
    fig.suptitle(f"Fig. 1(e): {ROBOT} over an obstacle and a hole at {VX_OBSTACLE_MPS:g} m/s, "
                 f"{outcome(run)}", fontsize=10)  # fmt: skip
    save_figure(fig, out, "obstacle")


def build_obstacle(
    out: Path, duration_s: float, video: VideoConfig | None, log: Log, quick: bool
) -> Report:
    cases = CASES[:1] if quick else CASES
    results: list[CaseResult] = []
    rows: list[dict[str, Any]] = []
    first = None
    for case in cases:
        scenario = _scenario("obstacle", case.vx_mps, duration_s, case.heights_known, None)
        res, episode = _run(out, case.folder, scenario, video if first is None else None, log)
        results.append(res)
        r_foot = episode.robot.spec.foot_contact_radius_m
        rows += [
            {"case": case.label, "kind": "trace", "t_s": t, "foot": f, "x_m": x,
             "sole_z_m": z, "over_obstacle": ob}
            for f in FEET
            for t, x, z, ob in res.recorder.trace[f]
        ]  # fmt: skip
        rows += [
            {"case": case.label, "kind": "touchdown", "t_s": h["t_s"], "foot": h["foot"],
             "x_m": h["pos_m"][0], "sole_z_m": h["pos_m"][2] - r_foot, "allowed": h["allowed"]}
            for h in holds_of(res.run)
        ]  # fmt: skip
        if first is None:
            first = episode
            _figure(out, episode.course, res, r_foot)
    assert first is not None
    write_csv(out, "obstacle", rows)
    course, spec = first.course, first.robot.spec
    box = course.obstacles[0]
    h0, h1 = holes(course)[0]
    extent = (spec.foot_toe_m, spec.foot_heel_m)

    def column(res: CaseResult) -> list[str]:
        rec = res.recorder
        near = [h for h in holds_of(res.run) if box.x_min - 0.4 <= h["pos_m"][0] <= h1 + 0.4]
        td = "; ".join(
            f"{h['foot']} {h['pos_m'][0]:.3f} m ({_where(course, extent, h['pos_m'][0])})"
            for h in near
        )
        passes = "; ".join(
            f"{p['foot']} {p['t0_s']:.2f}-{p['t1_s']:.2f} s: {cm_text(p['clearance_m'])}"
            + (" (touched it)" if p["touched"] else "")
            for p in res.passes
        )
        others = f" ({', '.join(sorted(rec.other_bodies))})" if rec.other_bodies else ""
        return [
            outcome(res.run),
            cm_text(res.least_clearance_m),
            passes or "none",
            f"{rec.other_contact_ticks}{others}",
            ", ".join(f"{f} {len(rec.foot_contacts[f])}" for f in FEET),
            str(res.on_obstacle),
            f"{'yes' if res.beyond_box else 'no'} / {'yes' if res.beyond_hole else 'no'}",
            str(res.violations),
            td or "none",
        ]

    names = [
        "outcome", "least clearance over the obstacle",
        "passes over the obstacle: foot, time, clearance",
        "ticks a non-foot body touched the obstacle", "ticks a foot touched the obstacle",
        "touchdowns with the foot over the obstacle", "both feet beyond the obstacle / the hole",
        "foothold violations", "touchdowns near the obstacle and the hole: foot, x",
    ]  # fmt: skip
    paper = [
        "crosses", "clears it (not quantified)", "the left leg takes a slightly longer step",
        "0", "-", "-", "yes / yes", "0", "-",
    ]  # fmt: skip
    cols = [column(r) for r in results]
    table = [
        "| quantity | " + " | ".join(c.label for c in cases)
        + " | paper (Fig. 1(e), Sec. V-E, hardware) |",
        "|---|" + "---|" * (len(cases) + 1),
        *(
            f"| {name} | " + " | ".join(c[i] for c in cols) + f" | {paper[i]} |"
            for i, name in enumerate(names)
        ),
    ]  # fmt: skip
    rule = (
        "no fall, 0 foothold violations, no robot body (feet included) touching the "
        "obstacle, no touchdown over it, both feet beyond the obstacle"
        + ("" if quick else " and beyond the hole")
    )
    claims = [
        f"- *the robot clears the obstacle and the gap*, {case.label}: "
        f"**{word(res.holds(quick))}**; least clearance {cm_text(res.least_clearance_m)}."
        for case, res in zip(cases, results, strict=True)
    ]
    claims.append(f"- Rule: {rule}." + (" The hole is not judged in a quick run." if quick else ""))
    if not quick:
        for known in (True, False):
            table += ["", *_seeded(out, duration_s, log, known)]
    notes = [
        "Clearance: per pass of a foot over the obstacle's x range, the least height above "
        f"the obstacle's top of a point of the foot (its box's long edges, {SOLE_SAMPLES} "
        "points each) inside that range, read every tick from `sim.data` by the `on_step` "
        "hook (the run files hold no foot position per tick); at most 0: the foot hit the "
        "obstacle. Heights in the figure (the first case): the foot's lowest point, over "
        "its centre's x.",
        "Obstacle known: the one-step preview holds the obstacle's footprint and height "
        "(`terrain_knowledge.obstacle_heights` = true, the default): the swing clears its "
        "top and the touchdown boxes keep off its footprint (docs/design/obstacles.md). "
        "Unknown (`--set obstacle_heights=false`), as on the paper's hardware (\"the "
        "obstacle's height is unknown to the robot\"): the footprint is known, and the "
        "swing clears the obstacle as if it were `unknown_obstacle_height_m` (4 cm) high.",
        "Seeded courses: *clean* counts falls and foothold violations; a foot that touched "
        "a box (a negative clearance) is in its own column.",
    ]
    setup = (
        f"`{ROBOT}`, `gaitnet` (default settings), built-in `obstacle` course (a "
        f"{100 * (box.x_max - box.x_min):g} cm long, {100 * box.height_m:g} cm high box at x "
        f"in [{box.x_min:g}, {box.x_max:g}] m, a hole at x in [{h0:g}, {h1:g}] m)."
    )
    runs = [r.run for r in results]
    return Report("Fig. 1(e): over an obstacle and a gap", setup, table, claims, notes, runs)


def _seeded(out: Path, duration_s: float, log: Log, known: bool) -> list[str]:
    """Seeded ``obstacle`` courses :data:`SEEDS` at :data:`VX_SEEDED_MPS`: the table's
    lines. Obstacle unknown: the same layouts with boxes up to
    :data:`UNKNOWN_MAX_HEIGHT_M` (each written to ``courses/`` and run from its file)."""
    if known:
        what = "obstacle known (1-3 boxes 2-6 cm high"
    else:
        what = f"obstacle unknown (1-3 boxes 2-{100 * UNKNOWN_MAX_HEIGHT_M:g} cm high"
    lines = [
        f"Seeded `obstacle` courses {SEEDS[0]}-{SEEDS[-1]} at {VX_SEEDED_MPS:g} m/s, {what}, "
        "5-15 cm long, each followed within 0.45 m by a 10-20 cm hole):",
        "",
        "| seed | boxes: x [m], height [cm] | outcome | foothold violations | feet touched a box "
        "[ticks] | least clearance | touchdowns over a box | clean |",
        "|---|---|---|---|---|---|---|---|",
    ]
    clean = 0
    for seed in SEEDS:
        course: str = "obstacle"
        if not known:
            layout = load_course("obstacle", seed=seed, max_height_m=UNKNOWN_MAX_HEIGHT_M)
            path = out / "courses" / f"obstacle-seed{seed}-max{100 * UNKNOWN_MAX_HEIGHT_M:g}cm.json"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_atomic(path, json.dumps(layout.to_dict(), indent=1) + "\n")
            course = str(path)
        scenario = _scenario(course, VX_SEEDED_MPS, duration_s, known, seed if known else None)
        folder = f"gaitnet-obstacle-seed{seed}" + ("" if known else "-unknown")
        res, episode = _run(out, folder, scenario, None, log)
        ok = not fell(res.run) and res.violations == 0
        clean += ok
        boxes = ", ".join(
            f"{ob.x_min:.2f} ({100 * ob.height_m:.1f})" for ob in episode.course.obstacles
        )
        lines.append(
            f"| {seed} | {boxes} | {outcome(res.run)} | {res.violations} | "
            f"{res.foot_touch_ticks} | {cm_text(res.least_clearance_m)} | {res.on_obstacle} | "
            f"{'yes' if ok else 'no'} |"
        )
    lines += ["", f"Clean (no fall, no foothold violation): **{clean}/{len(SEEDS)}**."]
    return lines


__all__ = ["CASES", "SEEDS", "SOLE_SAMPLES", "Case", "FootRecorder", "build_obstacle"]
