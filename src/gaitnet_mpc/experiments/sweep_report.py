"""The files of a ``gaitnet-mpc sweep`` folder made from its finished cases: ``sweep.csv``
(one row per case), ``sweep.md`` (the tables, the machine and versions, the command and
its wall time) and, for ``push``, ``push_polar.png``.

The polar plot shows, per direction, the survivable impulse ``0.2 s x F`` [N s] at the
*worst* phase of the step (the smallest survived force over the phases), one curve per
controller, one panel per speed; it is drawn with matplotlib's object-oriented API on
the Agg canvas (no pyplot) and written atomically.
"""

from __future__ import annotations

import csv
import io
import math
import statistics
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from gaitnet_mpc.experiments.sweep_cases import DIRECTIONS, PUSH_DURATION_S

Record = dict[str, Any]

#: The columns of ``sweep.csv`` per mode.
CSV_FIELDS: dict[str, tuple[str, ...]] = {
    "push": (
        "controller", "speed_mps", "direction", "phase", "push_t_s", "phase_measured",
        "swing_foot", "survived_n", "survived_impulse_ns", "failed_n", "falls_unpushed",
        "non_monotone", "spot_failed_n", "bisected_n", "episodes", "wall_s",
    ),
    "payload": (
        "controller", "course", "survived_kg", "failed_kg", "falls_unloaded", "non_monotone",
        "spot_failed_kg", "episodes", "wall_s",
    ),
    "protocol": (
        "controller", "seed", "survived", "fall_time_s", "fall_reason", "pushes",
        "distance_m", "wall_s",
    ),
    "terrain": (
        "controller", "course", "seed", "success", "fell", "fall_time_s", "fall_reason",
        "foothold_violations", "self_collisions", "distance_m", "wall_s",
    ),
}  # fmt: skip


def _num(x: float | None) -> str:
    return "" if x is None else f"{x:g}"


def csv_row(mode: str, r: Record) -> dict[str, Any]:
    """One row of ``sweep.csv``."""
    case, res = r["case"], r["result"]
    base = {"controller": case["controller"], "wall_s": r["wall_s"]}
    if mode in ("push", "payload"):
        unit = "n" if mode == "push" else "kg"
        row = {
            **base,
            f"survived_{unit}": _num(res["survived"]),
            f"failed_{unit}": _num(res["failed"]),
            "falls_unpushed" if mode == "push" else "falls_unloaded": res["survived"] is None,
            "non_monotone": res["non_monotone"],
            f"spot_failed_{unit}": " ".join(f"{x:g}" for x in res["spot_failed"]),
            "episodes": len(res["episodes"]),
        }
        if mode == "payload":
            return {**row, "course": case["course"]}
        impulse = None if res["survived"] is None else res["survived"] * PUSH_DURATION_S
        return {
            **row,
            "bisected_n": _num(res.get("bisected")),
            "speed_mps": case["speed_mps"],
            "direction": case["direction"],
            "phase": case["phase"],
            "push_t_s": res["push_t_s"],
            "phase_measured": _num(res["phase_measured"]),
            "swing_foot": res["swing_foot"],
            "survived_impulse_ns": _num(impulse),
        }
    keys = CSV_FIELDS[mode]
    row = {**base, **{k: res[k] for k in keys if k in res}}
    row.update({k: case[k] for k in ("course", "seed") if k in case})
    return {k: "" if row.get(k) is None else row[k] for k in keys}


def csv_text(mode: str, records: Sequence[Record]) -> str:
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=CSV_FIELDS[mode], lineterminator="\n")
    writer.writeheader()
    for r in sorted(records, key=lambda r: r["key"]):
        writer.writerow(csv_row(mode, r))
    return buf.getvalue()


# ----------------------------------------------------------------------------- tables
def _bound_text(res: dict[str, Any], unit: str) -> str:
    if res["survived"] is None:
        return "falls unpushed" if unit == "N" else "falls unloaded"
    text = f"{res['survived']:g}"
    if res["failed"] is None:
        text = f">= {text}"
    if res["non_monotone"]:
        text += " (!" + ",".join(f"{x:g}" for x in res["spot_failed"]) + ")"
    if res.get("bisected") is not None:
        text += f" (^{res['bisected']:g})"
    return text


def _push_tables(records: Sequence[Record], controllers: Sequence[str]) -> list[str]:
    by = {}
    for r in records:
        case = r["case"]
        by[case["controller"], case["speed_mps"], case["phase"], case["direction"]] = r["result"]
    speeds = sorted({k[1] for k in by})
    phases = sorted({k[2] for k in by})
    dirs = [d for d in DIRECTIONS if any(k[3] == d for k in by)]
    lines = [
        "| controller | speed [m/s] | phase | " + " | ".join(dirs) + " |",
        "|---|---|---|" + "---|" * len(dirs),
    ]
    for c in controllers:
        for v in speeds:
            for p in phases:
                keys = [(c, v, p, d) for d in dirs]
                cells = [_bound_text(by[k], "N") if k in by else "" for k in keys]
                if any(cells):
                    lines.append(f"| {c} | {v:g} | {p:g} | " + " | ".join(cells) + " |")
    return lines


def _payload_table(records: Sequence[Record], controllers: Sequence[str]) -> list[str]:
    by = {(r["case"]["controller"], r["case"]["course"]): r["result"] for r in records}
    courses = sorted({k[1] for k in by})
    lines = ["| controller | " + " | ".join(f"{c} [kg]" for c in courses) + " |"]
    lines.append("|---|" + "---|" * len(courses))
    for c in controllers:
        cells = [_bound_text(by[c, k], "kg") if (c, k) in by else "" for k in courses]
        lines.append(f"| {c} | " + " | ".join(cells) + " |")
    return lines


def _protocol_table(records: Sequence[Record], controllers: Sequence[str]) -> list[str]:
    lines = [
        "| controller | survived | pushes received (mean) | falls at [s] | wall per episode [s] |",
        "|---|---|---|---|---|",
    ]
    for c in controllers:
        mine = [r for r in records if r["case"]["controller"] == c]
        if not mine:
            continue
        res = [r["result"] for r in mine]
        falls = sorted(x["fall_time_s"] for x in res if x["fell"])
        lines.append(
            f"| {c} | {sum(x['survived'] for x in res)}/{len(res)} | "
            f"{statistics.fmean(x['pushes'] for x in res):.1f} | "
            f"{', '.join(f'{t:.1f}' for t in falls) or '-'} | "
            f"{statistics.fmean(r['wall_s'] for r in mine):.0f} |"
        )
    return lines


def _terrain_table(records: Sequence[Record], controllers: Sequence[str]) -> list[str]:
    courses = sorted({r["case"]["course"] for r in records})
    lines = ["| controller | " + " | ".join(courses) + " |", "|---|" + "---|" * len(courses)]
    for c in controllers:
        cells = []
        for k in courses:
            mine = [
                r["result"]
                for r in records
                if r["case"]["controller"] == c and r["case"]["course"] == k
            ]
            cells.append(f"{sum(x['success'] for x in mine)}/{len(mine)}" if mine else "")
        lines.append(f"| {c} | " + " | ".join(cells) + " |")
    return lines


LEGENDS = {
    "push": f"Cells: the largest force [N] of a {PUSH_DURATION_S:g} s push at the trunk CoM "
    "(impulse 0.2 F [N s]) survived without a fall until the episode ends, by bisection on "
    "the force grid; where the plan scans (`scan_from`), every force from that fraction of "
    "the bisection's bound up to it was run too, and the cell is the force below the first "
    "fall; `(^F)`: the bisection had found F survived above that fall (an island, not "
    "counted); `>= F`: the top of the range was survived; `(!F)`: a spot check below "
    "the bound fell at F (non-monotone); `falls unpushed`: the unpushed run fell.",
    "payload": "Cells: the largest unknown trunk payload [kg] walked for the whole episode "
    "without a fall, by bisection; `>= m`: the top of the range was walked; `(!m)`: a spot "
    "check below the bound fell (non-monotone).",
    "protocol": "Survived: no fall within the episode, under the data-collection protocol's "
    "pushes (10-100 N for 0.2 s in a random horizontal direction every 2 s; the same pushes "
    "for every controller and seed).",
    "terrain": "Cells: clean runs (no fall, no foothold violation, no leg-leg contact) of "
    "the seeds; `uneven:A`: tiles with tops uniform in [-A, A] m (a course file in "
    "`courses/`), `stepping-stones`: its seeded layouts.",
}


#: What a push's phase means under each rule of ``SweepPlan.phase_of``.
PHASE_LEGENDS = {
    "nominal": "where in the nominal step (5 dt) the push starts, after the settling time",
    "executed": "where in the controller's own executed step the push starts: the first "
    "step that starts after the settling time with the left foot in the air",
}


def _phase_legend(mode: str, settings: dict[str, Any]) -> str:
    """The push legend's last sentence: what the phase column means in this sweep."""
    if mode != "push":
        return ""
    rule = settings["plan"].get("phase_of", "nominal")
    return f" Phase: {PHASE_LEGENDS[rule]}."


def markdown(
    mode: str,
    controllers: Sequence[str],
    records: Sequence[Record],
    *,
    settings: dict[str, Any],
    command: str,
    wall_s: float,
    total: int,
    failed: Sequence[str] = (),
) -> str:
    """``sweep.md``."""
    import time

    from gaitnet_mpc.machine import machine_info

    tables = {
        "push": _push_tables,
        "payload": _payload_table,
        "protocol": _protocol_table,
        "terrain": _terrain_table,
    }[mode](records, controllers)
    work_s = sum(float(r["wall_s"]) for r in records)
    lines = [
        f"# gaitnet-mpc sweep {mode}",
        "",
        f"{machine_info(('numpy', 'mujoco', 'pin', 'piqp'))}.",
        "",
        f"Command: `{command}`. Wall time of this run {wall_s:.0f} s ({time.strftime('%Y-%m-%d')}"
        f"); {work_s:.0f} s of case wall time in all {len(records)} finished cases of {total}"
        + (f"; {len(failed)} failed (see `errors.log`)" if failed else "")
        + ".",
        "",
        *tables,
        "",
        LEGENDS[mode] + _phase_legend(mode, settings),
        "",
        "Settings: humanoid3d, flat unless named, "
        + ", ".join(f"{k} {v}" for k, v in settings["plan"].items() if v not in ([], 0.0))
        + ".",
        "",
    ]
    return "\n".join(lines)


# ----------------------------------------------------------------------------- polar plot
def push_polar(path: Path, records: Sequence[Record], controllers: Sequence[str]) -> None:
    """``push_polar.png``: survivable impulse [N s] at the worst phase, per direction."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.projections.polar import PolarAxes

    from gaitnet_mpc.results.io import write_bytes_atomic

    speeds = sorted({r["case"]["speed_mps"] for r in records})
    fig = Figure(figsize=(4.4 * max(len(speeds), 1), 4.8), layout="constrained")
    FigureCanvasAgg(fig)
    for j, v in enumerate(speeds):
        ax = fig.add_subplot(1, len(speeds), j + 1, projection="polar")
        assert isinstance(ax, PolarAxes)
        for c in controllers:
            worst: dict[str, float] = {}
            for r in records:
                case = r["case"]
                if case["controller"] != c or case["speed_mps"] != v:
                    continue
                s = r["result"]["survived"]
                impulse = 0.0 if s is None else s * PUSH_DURATION_S
                d = case["direction"]
                worst[d] = min(worst.get(d, math.inf), impulse)
            dirs = [d for d in DIRECTIONS if d in worst]
            if not dirs:
                continue
            theta = [math.radians(DIRECTIONS[d]) for d in dirs]
            rho = [worst[d] for d in dirs]
            if len(dirs) > 2:  # a closed curve
                theta, rho = [*theta, theta[0]], [*rho, rho[0]]
            ax.plot(theta, rho, marker="o", label=c)
        ax.set_title(f"vx {v:g} m/s", fontsize=10)
        ax.set_xticks([math.radians(a) for a in DIRECTIONS.values()])
        ax.set_xticklabels(list(DIRECTIONS), fontsize=7)
        ax.set_rlabel_position(100)
        ax.tick_params(axis="y", labelsize=7)
    if speeds:
        fig.axes[0].legend(loc="lower left", bbox_to_anchor=(-0.2, -0.2), fontsize=8)
    fig.suptitle(
        "Survivable 0.2 s push impulse [N s]\n(worst phase; x forward, y left)", fontsize=10
    )
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    write_bytes_atomic(path, buf.getvalue())
