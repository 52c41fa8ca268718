"""The files of a ``reproduce fig6`` folder made from its finished cases.

* ``fig6.csv``: one row per case (method, width, seed, outcome, step-duration statistics);
* ``fig6.md``: the success table (method x gap width), the step durations per method
  (mean, spread, the mean change from one step to the next, the share at a dt bound),
  the full-solve time per method, every failing case, the paper's three claims with
  "holds" / "does not hold", the machine and versions, the command and its wall time;
* ``fig6.png``: (a) success rate against gap width; (b) the step durations along the
  course on the strips' layout (Fig. 6d, gaps shaded); (c) the step durations of every
  case per method (box plot). Drawn with matplotlib's object-oriented API on the Agg
  canvas and written atomically.

"Inconsistent" is measured as the mean absolute change of the step duration between
consecutive steps (``jitter``): a policy whose dt follows the terrain changes it near
the gaps and keeps it elsewhere; one that jumps between bounds scores high.
"""

from __future__ import annotations

import csv
import io
import itertools
import statistics
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.experiments.fig6_cases import METHOD_LABELS, ROBOT, Fig6Settings, course_file
from gaitnet_mpc.results.io import write_atomic, write_bytes_atomic

Record = dict[str, Any]
#: A failing case whose fall lies this close to a gap edge counts as "near a boundary" [m].
NEAR_EDGE_M = 0.3

CSV_FIELDS = (
    "method", "width_m", "seed", "success", "fell", "fall_time_s", "fall_x_m",
    "fall_edge_distance_m", "foothold_violations", "self_collisions", "distance_m",
    "steps", "step_mean_s", "step_std_s", "step_jitter_s", "full_solve_ms_median", "wall_s",
)  # fmt: skip


def _durations(r: Record) -> np.ndarray:
    return np.array([s["duration_s"] for s in r["result"]["steps"]], dtype=float)


def _jitter(d: np.ndarray) -> float:
    return float(np.mean(np.abs(np.diff(d)))) if d.size > 1 else float("nan")


def csv_text(records: Sequence[Record]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=CSV_FIELDS, lineterminator="\n")
    w.writeheader()
    for r in sorted(records, key=lambda r: (r["case"]["method"], r["case"]["width_m"],
                                             r["case"]["seed"])):  # fmt: skip
        c, res = r["case"], r["result"]
        d = _durations(r)
        w.writerow(
            {
                "method": c["method"], "width_m": c["width_m"], "seed": c["seed"],
                "success": res["success"], "fell": res["fell"],
                "fall_time_s": res["fall_time_s"], "fall_x_m": res["fall_x_m"],
                "fall_edge_distance_m": res["fall_edge_distance_m"],
                "foothold_violations": res["foothold_violations"],
                "self_collisions": res["self_collisions"], "distance_m": res["distance_m"],
                "steps": d.size,
                "step_mean_s": round(float(d.mean()), 4) if d.size else "",
                "step_std_s": round(float(d.std()), 4) if d.size else "",
                "step_jitter_s": round(_jitter(d), 4) if d.size > 1 else "",
                "full_solve_ms_median": res["full_solve_ms_median"], "wall_s": r["wall_s"],
            }
        )  # fmt: skip
    return buf.getvalue()


def _by(records: Sequence[Record], method: str, width: float | None = None) -> list[Record]:
    return [
        r for r in records
        if r["case"]["method"] == method and (width is None or r["case"]["width_m"] == width)
    ]  # fmt: skip


def success_table(settings: Fig6Settings, records: Sequence[Record]) -> str:
    """Markdown: success ``k/n`` per method (rows) and gap width (columns)."""
    head = "| method | " + " | ".join(f"{w * 100:g} cm" for w in settings.widths_m) + " | all |"
    lines = [head, "|---" * (len(settings.widths_m) + 2) + "|"]
    for m in settings.methods:
        cells = []
        for w in [*settings.widths_m, None]:
            rs = _by(records, m, w)
            ok = sum(r["result"]["success"] for r in rs)
            cells.append(f"{ok}/{len(rs)}" if rs else "-")
        lines.append(f"| {METHOD_LABELS[m]} (`{m}`) | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _step_rows(settings: Fig6Settings, records: Sequence[Record]) -> list[str]:
    rows = [
        "| method | steps | mean [s] | std [s] | min-max [s] | jitter [s] | at a bound | "
        "full solve, median [ms] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    lo, hi = 5 * 0.03, 5 * 0.06  # Table V's dt bounds as step durations
    for m in settings.methods:
        rs = _by(records, m)
        d = np.concatenate([_durations(r) for r in rs]) if rs else np.zeros(0)
        if d.size == 0:
            continue
        jit = [_jitter(_durations(r)) for r in rs if _durations(r).size > 1]
        at_bound = float(np.mean((d <= lo + 1e-4) | (d >= hi - 1e-4)))
        ms = [r["result"]["full_solve_ms_median"] for r in rs]
        ms_ok = [x for x in ms if x is not None]
        rows.append(
            f"| {METHOD_LABELS[m]} | {d.size} | {d.mean():.3f} | {d.std():.3f} | "
            f"{d.min():.3f}-{d.max():.3f} | {statistics.fmean(jit) if jit else float('nan'):.4f} | "
            f"{100 * at_bound:.0f} % | {statistics.median(ms_ok) if ms_ok else float('nan'):.1f} |"
        )
    return rows


def _failures(records: Sequence[Record]) -> list[str]:
    rows = []
    for r in sorted(records, key=lambda r: r["key"]):
        res = r["result"]
        if res["success"]:
            continue
        if res["fell"]:
            what = (
                f"fell at {res['fall_time_s']:.2f} s, CoM x {res['fall_x_m']:.2f} m, "
                f"{res['fall_edge_distance_m']:.2f} m from a gap edge ({res['fall_reason']})"
            )
        else:
            what = "no fall"
        rows.append(
            f"- `{r['key']}`: {what}; {res['foothold_violations']} foothold violations, "
            f"{res['self_collisions']} leg-contact ticks, {res['distance_m']:.2f} m"
        )
    return rows or ["- none"]


def verdicts(settings: Fig6Settings, records: Sequence[Record]) -> list[str]:
    """The paper's three claims of Sec. V-B, each with what was measured here."""
    out = []

    def rate(m: str) -> tuple[int, int]:
        rs = _by(records, m)
        return sum(r["result"]["success"] for r in rs), len(rs)

    if "kd" in settings.methods:
        ok, n = rate("kd")
        falls = [r["result"] for r in _by(records, "kd") if r["result"]["fell"]]
        near = sum((f["fall_edge_distance_m"] or 99) <= NEAR_EDGE_M for f in falls)
        holds = ok < n and near == len(falls)
        out.append(
            f"- (1) *a fixed step frequency is un-optimised near terrain boundaries* "
            f"(it fails there): **{'holds' if holds else 'does not hold'}**. Fixed dt "
            f"succeeds on {ok}/{n}; {near} of its {len(falls)} falls are within "
            f"{NEAR_EDGE_M} m of a gap edge."
        )
    if "kd-optdt" in settings.methods and "gaitnet" in settings.methods:
        jo = [_jitter(_durations(r)) for r in _by(records, "kd-optdt")]
        jg = [_jitter(_durations(r)) for r in _by(records, "gaitnet")]
        jo = [x for x in jo if np.isfinite(x)]
        jg = [x for x in jg if np.isfinite(x)]
        if jo and jg:
            mo, mg = statistics.fmean(jo), statistics.fmean(jg)
            d = np.concatenate([_durations(r) for r in _by(records, "kd-optdt")])
            share_lo = float(np.mean(d <= 5 * 0.03 + 1e-4)) if d.size else float("nan")
            out.append(
                f"- (2) *dt as a decision variable gives inconsistent, unintuitive step "
                f"durations*: **{'holds' if mo > mg else 'does not hold'}** as measured by "
                f"the step-to-step change: {mo * 1e3:.1f} ms (optimised) against "
                f"{mg * 1e3:.1f} ms (Gait-Net); {100 * share_lo:.0f} % of the optimised "
                f"steps sit at the lower dt bound."
            )
    if "gaitnet" in settings.methods:
        ok, n = rate("gaitnet")
        others = [rate(m) for m in settings.methods if m != "gaitnet"]
        worse = [
            f"{w * 100:g} cm"
            for w in settings.widths_m
            for m in settings.methods
            if m != "gaitnet"
            and sum(r["result"]["success"] for r in _by(records, "gaitnet", w))
            < sum(r["result"]["success"] for r in _by(records, m, w))
        ]
        holds = ok == n
        out.append(
            f"- (3) *Gait-Net succeeds*: **{'holds' if holds else 'does not hold'}**: "
            f"{ok}/{n} (the others: "
            + ", ".join(f"{a}/{b}" for a, b in others)
            + "); below a baseline at: "
            + (", ".join(sorted(set(worse))) if worse else "no width")
            + "."
        )
    return out


def markdown(
    settings: Fig6Settings,
    records: Sequence[Record],
    command: str,
    wall_s: float,
    failed: Sequence[str],
) -> str:
    from gaitnet_mpc.machine import machine_info

    n_total = len(settings.methods) * len(settings.widths_m) * settings.seeds
    lines = [
        "# Fig. 6: the 2-D biped over gaps, fixed vs optimised vs Gait-Net step duration",
        "",
        f"`{ROBOT}`, {settings.vx_mps:g} m/s, {settings.duration_s:g} s per case, "
        f"seeds {settings.first_seed}-{settings.seed_list[-1]} per width (four gaps per "
        "layout at seeded positions); "
        f"success = no fall, no foothold violation, no leg contact. Fixed dt "
        f"{settings.fixed_dt_s:g} s; the optimised dt and Gait-Net within Table V's "
        "[0.03, 0.06] s.",
        "",
        "## Success",
        "",
        success_table(settings, records),
        "",
        "## Step durations and solve time",
        "",
        *_step_rows(settings, records),
        "",
        "`jitter`: mean |change| of the step duration from one step to the next, per case, "
        "averaged. Full solve: the MPC solve at a step start, dt policy included.",
        "",
        "## The paper's claims",
        "",
        *verdicts(settings, records),
        "",
        "## Failing cases",
        "",
        *_failures(records),
        "",
        "## Run",
        "",
        f"- {len(records)} of {n_total} cases finished"
        + (f"; {len(failed)} raised (errors.log)" if failed else ""),
        f"- command: `{command}`" if command else "- command: (library call)",
        f"- wall time of this invocation: {wall_s:.0f} s",
        f"- machine: {machine_info(('numpy', 'mujoco', 'pin', 'casadi'))}",
        "",
    ]
    return "\n".join(lines)


def figure(folder: Path, settings: Fig6Settings, records: Sequence[Record]) -> Path:
    """``fig6.png`` (module docstring)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from gaitnet_mpc.terrain import Course

    fig = Figure(figsize=(15, 4.4))
    FigureCanvasAgg(fig)
    ax_a, ax_b, ax_c = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1, 2, 1]})
    widths_cm = [w * 100 for w in settings.widths_m]
    for m in settings.methods:
        rates = []
        for w in settings.widths_m:
            rs = _by(records, m, w)
            rates.append(100 * sum(r["result"]["success"] for r in rs) / len(rs) if rs else np.nan)
        ax_a.plot(widths_cm, rates, marker="o", label=METHOD_LABELS[m])
    ax_a.set(xlabel="gap width [cm]", ylabel="success [%]", ylim=(-5, 105), title="(a) success")
    ax_a.legend(fontsize=8)
    strip_w = settings.strip_width_m
    course = Course.from_json(folder / course_file(strip_w, settings.first_seed))
    patches = sorted(course.patches, key=lambda p: p.x_min)
    for a, b in itertools.pairwise(patches):
        ax_b.axvspan(a.x_max, b.x_min, color="0.85")
    for m in settings.methods:
        rs = [r for r in _by(records, m, strip_w) if r["case"]["seed"] == settings.first_seed]
        if not rs:
            continue
        steps = rs[0]["result"]["steps"]
        ax_b.step(
            [s["com_x_m"] for s in steps], [s["duration_s"] for s in steps], where="post",
            marker=".", label=METHOD_LABELS[m] + ("" if rs[0]["result"]["success"] else " (fails)"),
        )  # fmt: skip
    ax_b.set(
        xlabel="CoM x at the step start [m] (gaps shaded)",
        ylabel="step duration 5 dt [s]",
        xlim=(0.5, 5.0),
        title=f"(b) step durations, {strip_w * 100:g} cm gaps, seed {settings.first_seed} "
        "(Fig. 6d)",
    )
    ax_b.legend(fontsize=8)
    data = [
        np.concatenate([_durations(r) for r in _by(records, m)] or [np.zeros(0)])
        for m in settings.methods
    ]
    ax_c.boxplot(data, tick_labels=list(settings.methods))
    ax_c.set(ylabel="step duration [s]", title="(c) every step of every case")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    path = folder / "fig6.png"
    write_bytes_atomic(path, buf.getvalue())
    return path


def write_report(
    folder: Path,
    settings: Fig6Settings,
    records: Sequence[Record],
    command: str,
    wall_s: float,
    failed: Sequence[str],
) -> str:
    """Write ``fig6.csv``, ``fig6.md`` and (with any record) ``fig6.png``; return the
    Markdown text."""
    write_atomic(folder / "fig6.csv", csv_text(records))
    text = markdown(settings, records, command, wall_s, failed)
    write_atomic(folder / "fig6.md", text)
    if records:
        figure(folder, settings, records)
    return text


__all__ = ["csv_text", "figure", "markdown", "success_table", "verdicts", "write_report"]
