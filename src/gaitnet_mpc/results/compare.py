"""Compare several run folders: one figure and one table (``gaitnet-mpc compare``).

``compare_runs([run_a, run_b, ...], out_dir)`` writes into ``out_dir``:

* ``compare.png``: forward velocity against the command over time (0.25 s moving
  average, falls marked with an X), step durations per step, the distribution of MPC
  solve times per run, and each run's mean forward speed, its distance divided by its
  duration, so runs of different durations compare (fallen runs hatched).
* ``compare.md`` and ``compare.csv``: one row per run with :data:`TABLE_COLUMNS`: the
  duration, the median MPC sampling time (``dt_s_median``, from ``log.csv``; empty
  without a gait) and whether the multi-step preview was on, next to the outcome.

Only the run folders' files are read (see :mod:`gaitnet_mpc.results.rundir`).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.results.io import write_atomic
from gaitnet_mpc.results.plots import moving_average, new_figure
from gaitnet_mpc.results.rundir import RunFolder, load_run, save_figure_atomic

#: Columns of the comparison table (``compare.csv`` / ``compare.md``).
TABLE_COLUMNS: tuple[str, ...] = (
    "run",
    "robot",
    "controller",
    "course",
    "duration_s",
    "dt_s_median",
    "preview",
    "outcome",
    "fell",
    "fall_time_s",
    "distance_m",
    "mean_speed_mps",
    "speed_rmse_mps",
    "violations",
    "solves",
    "solve_ms_median",
    "solve_ms_p99",
    "qps_per_solve",
)

_FORMATS = {
    "duration_s": "{:.2f}",
    "dt_s_median": "{:.3f}",
    "fall_time_s": "{:.3f}",
    "distance_m": "{:.3f}",
    "mean_speed_mps": "{:.3f}",
    "speed_rmse_mps": "{:.3f}",
    "solve_ms_median": "{:.2f}",
    "solve_ms_p99": "{:.2f}",
    "qps_per_solve": "{:.2f}",
}


def _labels(runs: Sequence[RunFolder]) -> list[str]:
    """Folder names, made unique with the parent folder (then an index) where needed."""
    names = [r.label for r in runs]
    if len(set(names)) < len(names):
        names = [f"{r.path.parent.name}/{r.label}" for r in runs]
    if len(set(names)) < len(names):
        names = [f"{i}:{n}" for i, n in enumerate(names)]
    return names


def table_row(run: RunFolder, label: str) -> dict[str, Any]:
    """The table row of one run (None where a value does not apply)."""
    s = run.summary
    mpc = s.get("mpc") or {}
    dt = run.column("mpc_dt_s")
    dt_ok = dt[np.isfinite(dt)] if dt is not None else np.zeros(0)
    options = s.get("controller_options") or {}
    return {
        "run": label,
        "robot": s.get("robot"),
        "controller": s.get("controller"),
        "course": s.get("course"),
        "duration_s": s.get("duration_s"),
        "dt_s_median": float(np.median(dt_ok)) if dt_ok.size else None,
        "preview": bool(options.get("preview", False)),
        "outcome": s.get("outcome"),
        "fell": bool(s.get("fell")),
        "fall_time_s": s.get("fall_time_s"),
        "distance_m": s.get("distance_m"),
        "mean_speed_mps": s.get("mean_speed_mps"),
        "speed_rmse_mps": s.get("speed_rmse_mps"),
        "violations": s.get("foothold_violations"),
        "solves": mpc.get("solves"),
        "solve_ms_median": mpc.get("solve_ms_median"),
        "solve_ms_p99": mpc.get("solve_ms_p99"),
        "qps_per_solve": mpc.get("qps_per_solve_mean"),
    }


def _fmt(key: str, value: Any, missing: str) -> str:
    if value is None:
        return missing
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float) and key in _FORMATS:
        return _FORMATS[key].format(value)
    return str(value)


def _csv_cell(value: Any) -> Any:
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value).lower()
    return value


def table_csv(rows: Sequence[dict[str, Any]]) -> str:
    """CSV text of the table (empty cells where a value does not apply)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(TABLE_COLUMNS)
    for row in rows:
        w.writerow([_csv_cell(row[k]) for k in TABLE_COLUMNS])
    return buf.getvalue()


def table_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """Markdown pipe table of the runs ("–" where a value does not apply)."""
    lines = [
        "| " + " | ".join(TABLE_COLUMNS) + " |",
        "|" + "|".join("---" for _ in TABLE_COLUMNS) + "|",
    ]
    for row in rows:
        cells = [_fmt(k, row[k], "–").replace("|", "\\|") for k in TABLE_COLUMNS]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot_compare(runs: Sequence[RunFolder], labels: Sequence[str], path: Path) -> Path:
    """The comparison figure (see the module docstring)."""
    from matplotlib.ticker import MaxNLocator

    fig = new_figure(12.0, 8.0)
    (ax_v, ax_s), (ax_t, ax_d) = fig.subplots(2, 2)
    colors = [f"C{i % 10}" for i in range(len(runs))]
    for run, label, c in zip(runs, labels, colors, strict=True):
        t = run.log["t_s"]
        ta, va = moving_average(t, run.log["com_vx_mps"], 0.25)
        ax_v.plot(ta, va, color=c, lw=1.5, label=label)
        cmd = run.column("cmd_vx_mps")
        if cmd is not None:
            ax_v.plot(t, cmd, color=c, lw=1.0, ls="--", alpha=0.8)
        t_fall = run.summary.get("fall_time_s")
        if run.summary.get("fell") and t_fall is not None and ta.size:
            k = int(np.clip(np.searchsorted(ta, t_fall), 0, ta.size - 1))
            ax_v.scatter([t_fall], [va[k]], marker="x", s=120, color=c, linewidths=2.5, zorder=4)
        steps = np.asarray(run.summary.get("step_durations_s") or [], dtype=float)
        if steps.size:  # the last step was in progress at the end: a hollow marker
            ax_s.plot(np.arange(steps.size), steps, color=c, marker="o", ms=3, lw=1.0)
            ax_s.plot([steps.size - 1], steps[-1:], ls="", marker="o", ms=6, mfc="white", color=c)
    ax_v.set_title("forward velocity (0.25 s mean; dashed: command; X: fall)", fontsize=9)
    ax_v.set_xlabel("time [s]")
    ax_v.set_ylabel("$v_x$ [m/s]")
    ax_v.grid(alpha=0.3)
    ax_v.legend(loc="best", fontsize=8)
    ax_s.set_title("step durations (hollow: unfinished at the end)", fontsize=9)
    ax_s.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax_s.set_xlabel("step index")
    ax_s.set_ylabel("duration [s]")
    ax_s.grid(alpha=0.3)
    if not any(run.summary.get("step_durations_s") for run in runs):
        ax_s.text(0.5, 0.5, "no steps", ha="center", va="center", transform=ax_s.transAxes)
    solve_ms = [run.mpc_log["solve_ms"] if run.mpc_log is not None else np.zeros(0) for run in runs]
    with_mpc = [i for i, ms in enumerate(solve_ms) if ms.size]
    if with_mpc:
        box = ax_t.boxplot(
            [solve_ms[i] for i in with_mpc],
            positions=np.arange(len(with_mpc)),
            whis=(1, 99),
            showfliers=True,
            flierprops={"markersize": 2},
            patch_artist=True,
        )
        for patch, i in zip(box["boxes"], with_mpc, strict=True):
            patch.set_facecolor(colors[i])
            patch.set_alpha(0.5)
        ax_t.set_xticks(np.arange(len(with_mpc)), [labels[i] for i in with_mpc], fontsize=8)
        ax_t.set_yscale("log")
    else:
        ax_t.text(0.5, 0.5, "no MPC solves", ha="center", va="center", transform=ax_t.transAxes)
    ax_t.set_title("MPC solve time per solve (whiskers: 1-99 %)", fontsize=9)
    ax_t.set_ylabel("solve time [ms]")
    ax_t.grid(alpha=0.3, axis="y", which="both")
    speed = [_mean_speed_mps(run) for run in runs]
    x = np.arange(len(runs))
    bars = ax_d.bar(x, speed, color=colors, alpha=0.8)
    for bar, run in zip(bars, runs, strict=True):
        if run.summary.get("fell"):
            bar.set_hatch("xx")
            bar.set_edgecolor("black")
            ax_d.annotate(
                f"fell {run.summary.get('fall_time_s') or 0.0:.2f} s",
                (bar.get_x() + bar.get_width() / 2, bar.get_height()),
                ha="center",
                va="bottom",
                fontsize=8,
            )
    for bar, run in zip(bars, runs, strict=True):
        bar_label = f"{float(run.summary.get('distance_m') or 0.0):.2f} m / "
        bar_label += f"{float(run.summary.get('duration_s') or 0.0):.1f} s"
        ax_d.annotate(
            bar_label,
            (bar.get_x() + bar.get_width() / 2, 0.0),
            xytext=(0, 3),
            textcoords="offset points",
            ha="center",
            va="bottom",
            fontsize=7,
        )
    ax_d.set_xticks(x, labels, fontsize=8)
    ax_d.set_title("mean speed = distance / duration (hatched: fell)", fontsize=9)
    ax_d.set_ylabel("mean forward speed [m/s]")
    ax_d.grid(alpha=0.3, axis="y")
    return save_figure_atomic(fig, path)


def _mean_speed_mps(run: RunFolder) -> float:
    """Distance divided by the simulated duration [m/s] (0 for an empty run)."""
    s = run.summary
    duration = float(s.get("duration_s") or 0.0)
    if s.get("mean_speed_mps") is not None:
        return float(s["mean_speed_mps"])
    return float(s.get("distance_m") or 0.0) / duration if duration > 0 else 0.0


def compare_warnings(runs: Sequence[RunFolder], labels: Sequence[str]) -> list[str]:
    """What makes the runs not like for like: different robots or courses."""
    out = []
    for key, what in (("robot", "robots"), ("course", "courses")):
        values = {
            label: _course_name(run) if key == "course" else run.summary.get(key)
            for run, label in zip(runs, labels, strict=True)
        }
        if len(set(values.values())) > 1:
            listed = ", ".join(f"{label}: {value}" for label, value in values.items())
            out.append(f"the runs are of different {what} ({listed})")
    return out


def _course_name(run: RunFolder) -> str:
    """The course and its layout seed (a seeded layout is another course)."""
    name = str(run.summary.get("course"))
    seed = run.summary.get("seed")
    return name if seed is None else f"{name} (seed {seed})"


def compare_runs(runs: Sequence[RunFolder | str | Path], out_dir: str | Path) -> dict[str, Any]:
    """Write ``compare.png``, ``compare.md`` and ``compare.csv`` into ``out_dir``.

    ``runs`` are run folders, loaded or as paths. Returns the paths written, keyed by
    ``"figure"``, ``"markdown"`` and ``"csv"``, and the :func:`compare_warnings` under
    ``"warnings"`` (also written into ``compare.md``). Raises :class:`ConfigError` for
    fewer than one run or a folder that is not a run.
    """
    if not runs:
        raise ConfigError("RUN_DIR", [], "at least one run folder")
    loaded = [r if isinstance(r, RunFolder) else load_run(r) for r in runs]
    labels = _labels(loaded)
    warnings = compare_warnings(loaded, labels)
    rows = [table_row(run, label) for run, label in zip(loaded, labels, strict=True)]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "compare.csv", table_csv(rows))
    sources = "\n".join(
        f"* `{label}`: `{run.path}`" for run, label in zip(loaded, labels, strict=True)
    )
    notes = "".join(f"**Warning:** {w}.\n\n" for w in warnings)
    text = f"# Run comparison\n\n{notes}{table_markdown(rows)}\n{sources}\n"
    write_atomic(out / "compare.md", text)
    figure = plot_compare(loaded, labels, out / "compare.png")
    return {
        "figure": figure,
        "markdown": out / "compare.md",
        "csv": out / "compare.csv",
        "warnings": warnings,
    }
