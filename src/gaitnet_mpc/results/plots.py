"""The PNGs of a run folder's ``plots/`` directory, made only from the folder's files.

``make_plots(run_dir)`` (CLI: ``gaitnet-mpc plot RUN_DIR``) writes:

* ``velocity.png``: forward CoM velocity against the command (paper Fig. 11), with the
  fall time marked.
* ``course_top.png``: top view of the course (patches green = both feet, blue = left
  only, red = right only; obstacles grey) with the CoM path and every touchdown, coloured
  by foot, each labelled with its touchdown time [s]; touchdowns on a forbidden patch or a
  hole are marked with a black X and their time in bold (Fig. 7). The same violation
  times are marked on every time axis (red dotted lines, :func:`_mark_violations`), so a
  violation seen on the map can be found on the time plots.
* ``steps.png``: duration of each step (the last one, in progress when the episode
  ended, hatched with its planned duration), MPC sampling time over time and, for MPC
  controllers, the solve time of every solve (Fig. 6d / Fig. 9) against the real-time
  budget: the MPC period, the median time between successive solves (a solve that takes
  longer than that could not run in real time).
* ``momentum.png`` (``kd`` only): measured spatial momentum l_G,x, k_G,y, k_G,z against the
  MPC's one-stage-ahead prediction (Fig. 8).
* ``contact_torque.png``: the vertical (world z) component of the summed terrain contact
  force on each foot (ground on foot, up positive: about m g / 2 per foot when standing;
  it is not the force normal to a sloped or edge contact, and is negative only when the
  terrain pushes a foot down, e.g. a foot caught under a stone's edge), and the peak
  commanded joint torque against the actuator limits (33.5 / 67 N m on both robots).

Figures are built with matplotlib's object-oriented API on the Agg canvas (no pyplot, no
global backend switch) and written atomically.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.results.rundir import RunFolder, load_run, save_figure_atomic

#: Patch colours by allowed foot (as in the MuJoCo scene) and obstacle colour.
PATCH_COLORS = {"both": "#4caf50", "left": "#2f6fd6", "right": "#d63a2f"}
OBSTACLE_COLOR = "#8c8c8c"
#: Touchdown marker colours by foot (darker than the patch colours so they stand out).
FOOT_COLORS = {"left": "#0b2f80", "right": "#8a0d05"}
FOOT_MARKERS = {"left": "^", "right": "v"}
#: Actuator limits of both robots [N m], used when a summary does not list them.
DEFAULT_TORQUE_LIMITS_NM = (33.5, 67.0)


def new_figure(width_in: float = 9.0, height_in: float = 5.0) -> Any:
    """A matplotlib Figure on an Agg canvas, independent of pyplot's global state."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def run_title(run: RunFolder) -> str:
    """One-line description of a run: robot, controller, course, command."""
    s = run.summary
    cmd = s.get("command") or {}
    parts = [
        str(s.get("robot", "?")),
        str(s.get("controller", "?")),
        str(s.get("course", "?")),
        f"vx = {cmd.get('vx_mps', float('nan')):.2f} m/s",
    ]
    if s.get("fell"):
        parts.append(f"fell at {s.get('fall_time_s', float('nan')):.2f} s")
    return f"{run.label}: " + " · ".join(parts)


def moving_average(t: np.ndarray, x: np.ndarray, window_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Centred moving average of ``x`` over ``window_s`` seconds (uniform samples assumed)."""
    if t.size < 2:
        return t, x
    n = max(1, round(window_s / max(float(np.median(np.diff(t))), 1e-9)))
    if n >= x.size or n == 1:
        return t, x
    c = np.cumsum(np.insert(x, 0, 0.0))
    avg = (c[n:] - c[:-n]) / n
    t_mid = t[n // 2 : n // 2 + avg.size]
    return t_mid, avg


def _mark_pushes(ax: Any, run: RunFolder) -> None:
    """Shade the time of every push (``summary.json``'s ``pushes``) on a time axis."""
    for i, push in enumerate(run.summary.get("pushes") or []):
        t0, dur = float(push["t_s"]), float(push["dur_s"])
        label = "push" if i == 0 else None
        ax.axvspan(t0, t0 + dur, color="tab:orange", alpha=0.3, lw=0, label=label)


def _mark_fall(ax: Any, run: RunFolder) -> None:
    t_fall = run.summary.get("fall_time_s")
    if run.summary.get("fell") and t_fall is not None:
        ax.axvline(t_fall, color="black", ls="--", lw=1.2)
        ax.annotate(
            "fall",
            (t_fall, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(3, -12),
            textcoords="offset points",
        )


def violation_times_s(run: RunFolder) -> list[float]:
    """Times [s] of the touchdowns on a forbidden patch or a hole (``summary.json``)."""
    holds = run.summary.get("footholds") or []
    return [float(h["t_s"]) for h in holds if not h.get("allowed", True) and "t_s" in h]


def _mark_violations(ax: Any, run: RunFolder, label: bool = False) -> None:
    """A red dotted vertical line at every foothold violation on a time axis."""
    for i, t in enumerate(violation_times_s(run)):
        ax.axvline(
            t,
            color="tab:red",
            ls=":",
            lw=1.2,
            label="foothold violation" if label and i == 0 else None,
        )


def _note(ax: Any, text: str) -> None:
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, color="0.35")


# ----------------------------------------------------------------------------- plots


def plot_velocity(run: RunFolder, path: Path) -> Path:
    """Forward CoM velocity and its 0.25 s moving average against the command (Fig. 11)."""
    fig = new_figure(9.0, 4.5)
    ax = fig.add_subplot()
    t, vx = run.log["t_s"], run.log["com_vx_mps"]
    ax.plot(t, vx, color="tab:blue", lw=0.6, alpha=0.45, label="CoM $v_x$ (measured)")
    ta, va = moving_average(t, vx, 0.25)
    ax.plot(ta, va, color="tab:blue", lw=1.8, label="CoM $v_x$, 0.25 s mean")
    cmd = run.column("cmd_vx_mps")
    if cmd is not None:
        ax.plot(t, cmd, color="black", lw=1.5, ls="-.", label="command")
    _mark_fall(ax, run)
    _mark_violations(ax, run, label=True)
    rmse = run.summary.get("speed_rmse_mps")
    extra = f" (speed RMSE {rmse:.3f} m/s after 1 s)" if isinstance(rmse, float) else ""
    ax.set_title(run_title(run) + extra, fontsize=9)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("forward velocity [m/s]")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return save_figure_atomic(fig, path)


def plot_course_top(run: RunFolder, path: Path) -> Path:
    """Top view: patches by allowed foot, obstacles, CoM path, touchdowns, violations."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch as LegendPatch
    from matplotlib.patches import Rectangle

    holds = run.summary.get("footholds") or []
    x_c, y_c = run.log["com_x_m"], run.log["com_y_m"]
    xs = np.concatenate([x_c, [h["pos_m"][0] for h in holds]])
    ys = np.concatenate([y_c, [h["pos_m"][1] for h in holds]])
    x_lo, x_hi = float(np.min(xs, initial=0.0)) - 0.4, float(np.max(xs, initial=0.0)) + 0.6
    y_mid = 0.5 * (float(np.min(ys, initial=0.0)) + float(np.max(ys, initial=0.0)))
    half_y = max(0.5, 0.5 * float(np.ptp(ys)) + 0.3) if ys.size else 0.5
    width = 10.0
    height = float(np.clip(width * 2 * half_y / max(x_hi - x_lo, 1e-3), 2.5, 7.0)) + 1.6
    fig = new_figure(width, height)
    ax = fig.add_subplot()
    course = run.course
    if course is not None:
        # add_artist: the course (25 m long) must not widen the data limits of the view
        for p in course.patches:
            ax.add_artist(
                Rectangle(
                    (p.x_min, p.y_min),
                    p.x_max - p.x_min,
                    p.y_max - p.y_min,
                    facecolor=PATCH_COLORS.get(p.feet, "0.7"),
                    edgecolor="0.2",
                    lw=0.5,
                    alpha=0.45,
                )
            )
        for ob in course.obstacles:
            ax.add_artist(
                Rectangle(
                    (ob.x_min, ob.y_min),
                    ob.x_max - ob.x_min,
                    ob.y_max - ob.y_min,
                    facecolor=OBSTACLE_COLOR,
                    edgecolor="0.2",
                    lw=0.5,
                    hatch="//",
                )
            )
    else:
        _note(ax, "course.json missing: terrain not drawn")
    ax.plot(x_c, y_c, color="black", lw=1.0, alpha=0.7)
    for foot in ("left", "right"):
        pts = np.array([h["pos_m"][:2] for h in holds if h["foot"] == foot]).reshape(-1, 2)
        ax.scatter(
            pts[:, 0],
            pts[:, 1],
            marker=FOOT_MARKERS[foot],
            s=40,
            color=FOOT_COLORS[foot],
            edgecolors="white",
            linewidths=0.6,
            zorder=3,
        )
    bad = np.array([h["pos_m"][:2] for h in holds if not h["allowed"]]).reshape(-1, 2)
    ax.scatter(bad[:, 0], bad[:, 1], marker="x", s=140, color="black", linewidths=2.5, zorder=4)
    for h in holds:  # touchdown times, to find a touchdown on the time plots
        if "t_s" not in h:
            continue
        side = 1.0 if h["foot"] == "left" else -1.0
        ax.annotate(
            f"{float(h['t_s']):.2f}",
            (h["pos_m"][0], h["pos_m"][1]),
            xytext=(0, 9 * side),
            textcoords="offset points",
            ha="center",
            va="bottom" if side > 0 else "top",
            fontsize=6 if h["allowed"] else 7.5,
            fontweight="normal" if h["allowed"] else "bold",
            color=FOOT_COLORS.get(h["foot"], "black") if h["allowed"] else "black",
            zorder=5,
        )
    ax.update_datalim([(x_lo, y_mid - half_y), (x_hi, y_mid + half_y)])
    ax.margins(0.0)
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")  # the axes fill the layout box
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    n_bad = len(bad)
    when = ", ".join(f"{t:.2f}" for t in violation_times_s(run)[:8])
    at = f" (t = {when}{', ...' if n_bad > 8 else ''} s)" if n_bad else ""
    ax.set_title(
        f"{run_title(run)}\n{len(holds)} touchdowns (labels: time [s]), {n_bad} violations{at}",
        fontsize=9,
    )
    handles = [
        LegendPatch(facecolor=PATCH_COLORS["both"], alpha=0.45, label="patch: both feet"),
        LegendPatch(facecolor=PATCH_COLORS["left"], alpha=0.45, label="patch: left only"),
        LegendPatch(facecolor=PATCH_COLORS["right"], alpha=0.45, label="patch: right only"),
        LegendPatch(facecolor=OBSTACLE_COLOR, hatch="//", label="obstacle"),
        Line2D([], [], color="black", lw=1.0, label="CoM path"),
        Line2D([], [], ls="", marker="^", color=FOOT_COLORS["left"], label="left touchdown"),
        Line2D([], [], ls="", marker="v", color=FOOT_COLORS["right"], label="right touchdown"),
        Line2D([], [], ls="", marker="x", color="black", mew=2.5, label="violation (time bold)"),
    ]
    fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=8)
    return save_figure_atomic(fig, path)


def plot_steps(run: RunFolder, path: Path) -> Path:
    """Step durations, MPC sampling time over time with pushes shaded, and solve times
    against the real-time budget (Fig. 6d / Fig. 9)."""
    from matplotlib.ticker import MaxNLocator

    mpc = run.mpc_log
    n_rows = 3 if mpc is not None else 2
    fig = new_figure(9.0, 2.4 * n_rows + 0.6)
    axes = fig.subplots(n_rows, 1)
    steps = np.asarray(run.summary.get("step_durations_s") or [], dtype=float)
    ax = axes[0]
    if steps.size:
        # a step is recorded when it starts, with its planned duration: the last one was
        # still in progress when the episode ended (or fell), so it is drawn apart
        done = steps[:-1]
        ax.bar(np.arange(done.size), done, color="tab:purple", alpha=0.8, width=0.8)
        ax.bar(
            [steps.size - 1],
            steps[-1:],
            color="none",
            edgecolor="tab:purple",
            hatch="//",
            width=0.8,
            label="unfinished at the end (planned duration)",
        )
        ax.legend(loc="lower right", fontsize=8)
        ax.set_ylim(0.0, 1.15 * float(steps.max()))
    else:
        _note(ax, "no steps (the controller does not step)")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("step index")
    ax.set_ylabel("step duration [s]")
    ax.set_title(run_title(run), fontsize=9)
    ax.grid(alpha=0.3, axis="y")
    ax = axes[1]
    t, dt = run.log["t_s"], run.column("mpc_dt_s")
    if dt is not None and np.isfinite(dt).any():
        ax.step(t, dt, where="post", color="tab:purple", lw=1.5)
        lo, hi = float(np.nanmin(dt)), float(np.nanmax(dt))
        ax.set_ylim(max(0.0, lo - 0.01), hi + 0.01)
    else:
        _note(ax, "no MPC sampling time (no gait schedule)")
    _mark_pushes(ax, run)
    _mark_fall(ax, run)
    _mark_violations(ax, run, label=True)
    if run.summary.get("pushes") or violation_times_s(run):
        ax.legend(loc="upper right", fontsize=8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("MPC dt [s]")
    ax.grid(alpha=0.3)
    if mpc is not None:
        ax = axes[2]
        if mpc["t_s"].size:
            full = mpc["full_solve"] > 0.5
            ax.scatter(mpc["t_s"][~full], mpc["solve_ms"][~full], s=5, label="replan", alpha=0.6)
            ax.scatter(mpc["t_s"][full], mpc["solve_ms"][full], s=18, color="tab:red", label="full")
            bad = mpc["converged"] < 0.5
            if bad.any():
                ax.scatter(
                    mpc["t_s"][bad],
                    mpc["solve_ms"][bad],
                    s=40,
                    marker="x",
                    color="black",
                    label="not converged",
                )
            budget_ms = mpc_period_ms(mpc["t_s"])
            if budget_ms is not None:
                over = int(np.sum(mpc["solve_ms"] > budget_ms))
                ax.axhline(
                    budget_ms,
                    color="black",
                    ls="--",
                    lw=1.2,
                    label=f"real-time budget: MPC period {budget_ms:.0f} ms "
                    f"({over}/{mpc['t_s'].size} solves over)",
                )
            ax.legend(loc="upper right", fontsize=8)
            ax.set_yscale("log")
        else:
            _note(ax, "no MPC solves")
        _mark_fall(ax, run)
        _mark_violations(ax, run)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("solve time [ms]")
        ax.grid(alpha=0.3, which="both")
    return save_figure_atomic(fig, path)


def mpc_period_ms(solve_t_s: np.ndarray) -> float | None:
    """The MPC period [ms]: the median time between successive solves (the time a solve
    may take in real time), or None with fewer than two solves."""
    if solve_t_s.size < 2:
        return None
    gaps = np.diff(solve_t_s)
    gaps = gaps[gaps > 0]
    return float(np.median(gaps)) * 1e3 if gaps.size else None


def has_momentum_prediction(run: RunFolder) -> bool:
    """True for ``kd`` runs whose ``mpc_log.csv`` holds one-stage-ahead predictions."""
    mpc = run.mpc_log
    return (
        run.summary.get("controller") == "kd"
        and mpc is not None
        and "lGx_pred" in mpc
        and bool(np.isfinite(mpc["lGx_pred"]).any())
    )


def plot_momentum(run: RunFolder, path: Path) -> Path:
    """Measured l_G,x, k_G,y, k_G,z against the MPC prediction one stage ahead (Fig. 8)."""
    mpc = run.mpc_log
    assert mpc is not None
    fig = new_figure(9.0, 7.0)
    axes = fig.subplots(3, 1, sharex=True)
    t = run.log["t_s"]
    rows = (
        ("lGx", "$l_{G,x}$ [kg m/s]"),
        ("kGy", "$k_{G,y}$ [kg m²/s]"),
        ("kGz", "$k_{G,z}$ [kg m²/s]"),
    )
    for ax, (name, label) in zip(axes, rows, strict=True):
        ax.plot(t, run.log[name], color="black", lw=1.0, label="measured")
        ax.plot(
            mpc["t_pred_s"],
            mpc[f"{name}_pred"],
            color="tab:orange",
            lw=0,
            marker=".",
            ms=3,
            label="MPC prediction (one stage ahead)",
        )
        _mark_fall(ax, run)
        _mark_violations(ax, run)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    meas, pred = mpc["lGx_meas"], mpc["lGx_pred"]
    ok = np.isfinite(meas) & np.isfinite(pred)
    err = f" (l_G,x prediction RMSE {np.sqrt(np.mean((meas[ok] - pred[ok]) ** 2)):.3f})"
    axes[0].set_title(run_title(run) + (err if ok.any() else ""), fontsize=9)
    axes[0].legend(loc="best", fontsize=8)
    axes[-1].set_xlabel("time [s]")
    return save_figure_atomic(fig, path)


def plot_contact_torque(run: RunFolder, path: Path) -> Path:
    """Vertical (world z) contact force on each foot, and the peak commanded torque
    against the limits (see the module docstring for the sign convention)."""
    ratio = run.column("tau_limit_ratio_max")
    n_rows = 3 if ratio is not None else 2
    fig = new_figure(9.0, 2.4 * n_rows + 0.6)
    axes = fig.subplots(n_rows, 1, sharex=True)
    t = run.log["t_s"]
    ax = axes[0]
    for foot, color in (("left", "tab:blue"), ("right", "tab:red")):
        ax.plot(t, run.log[f"fz_{foot}_n"], color=color, lw=0.9, label=f"{foot} foot")
    ax.axhline(0.0, color="0.4", lw=0.6)
    _mark_fall(ax, run)
    _mark_violations(ax, run, label=True)
    ax.set_ylabel("vertical contact force\n(world z, up > 0) [N]")
    ax.set_title(run_title(run) + "\nterrain force on each foot, world-z component", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    ax = axes[1]
    ax.plot(t, run.log["tau_abs_max_nm"], color="tab:green", lw=0.9, label="peak |τ| (command)")
    limits = run.summary.get("torque_limits_nm") or DEFAULT_TORQUE_LIMITS_NM
    for lim, ls in zip(sorted(limits), ("--", ":", "-."), strict=False):
        ax.axhline(lim, color="black", ls=ls, lw=1.0, label=f"limit {lim:g} N m")
    _mark_violations(ax, run)
    ax.set_ylabel("torque [N m]")
    ax.set_ylim(0.0, 1.1 * max(max(limits), float(np.nanmax(run.log["tau_abs_max_nm"]))))
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    if ratio is not None:
        ax = axes[2]
        ax.plot(t, ratio, color="tab:green", lw=0.9)
        ax.axhline(1.0, color="black", ls="--", lw=1.0)
        ax.set_ylabel("peak |τ| / limit")
        ax.set_ylim(0.0, max(1.1, 1.05 * float(np.nanmax(ratio))))
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    return save_figure_atomic(fig, path)


#: Plot file name -> (function, whether it applies to a run).
PLOTS: dict[str, tuple[Callable[[RunFolder, Path], Path], Callable[[RunFolder], bool]]] = {
    "velocity.png": (plot_velocity, lambda run: True),
    "course_top.png": (plot_course_top, lambda run: True),
    "steps.png": (plot_steps, lambda run: True),
    "momentum.png": (plot_momentum, has_momentum_prediction),
    "contact_torque.png": (plot_contact_torque, lambda run: True),
}


def make_plots(run_dir: str | Path) -> list[Path]:
    """Write every applicable plot of a run folder into ``<run_dir>/plots/``.

    Reads only the folder's files (``summary.json``, ``log.csv`` and, where present,
    ``mpc_log.csv`` and ``course.json``), so it can be re-run at any time. Returns the
    paths written. An empty log (a run stopped before its first tick) gives no plots.
    """
    run = load_run(run_dir)
    if run.log["t_s"].size == 0:
        return []
    written = []
    for name, (plot, applies) in PLOTS.items():
        if applies(run):
            written.append(plot(run, run.plots_dir / name))
    return written
