"""Fig. 8 of the paper: the spatial momenta, measured against the MPC's prediction (run by
:func:`~gaitnet_mpc.experiments.paper_figures.reproduce_figure`; shared pieces in
:mod:`~gaitnet_mpc.experiments.figure_common`).

``fig8`` (spatial momenta): ``gaitnet`` and ``kd`` on the same scenario. ``mpc_log.csv``
holds, for each solve, the momentum its plan predicts one MPC stage ahead (``t_pred_s``
= the solve's time plus the first stage's dt, ``KDWalkController._prediction``) and the
momentum measured at the first tick at or after ``t_pred_s`` (``*_meas``): the
prediction is already paired with the measurement at the predicted time, the pairing
``plot_momentum`` draws. Only the step starts (``full_solve == 1``, the paper's scatter
"at the beginning of each footstep") are used; the paper may show more of each plan
than its first stage, which is all that is logged here. Per axis (l_G,x, k_G,y, k_G,z)
and controller: RMSE, the std of the measured values at the same instants, their ratio
(NRMSE) and the correlation. Claim: the prediction follows the measurement. Rule: no
fall and NRMSE < :data:`NRMSE_MAX` on every axis (judged for ``gaitnet``, the paper's
method; ``kd`` beside it).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from gaitnet_mpc.experiments.figure_common import (
    CONTROLLER_COLORS,
    KD_DT_S,
    ROBOT,
    VX_MPS,
    Log,
    Report,
    fell,
    figure_scenario,
    outcome,
    run_in_folder,
    save_figure,
    word,
    write_csv,
)
from gaitnet_mpc.results.plots import new_figure
from gaitnet_mpc.results.rundir import RunFolder
from gaitnet_mpc.runner.episode import VideoConfig

#: Fig. 8: a prediction "follows" the measurement when RMSE / std(measured) is below this.
NRMSE_MAX = 0.5
#: (column, name, unit, axis label) of the three momenta of Fig. 8.
MOMENTA = (
    ("lGx", "l_G,x", "kg m/s", "$l_{G,x}$ [kg m/s]"),
    ("kGy", "k_G,y", "kg m²/s", "$k_{G,y}$ [kg m²/s]"),
    ("kGz", "k_G,z", "kg m²/s", "$k_{G,z}$ [kg m²/s]"),
)


def momentum_pairs(run: RunFolder) -> dict[str, np.ndarray]:
    """The step starts of ``run`` (``full_solve == 1``) with a finite prediction and
    measurement on every axis: ``t_s``, ``t_pred_s``, ``<axis>_pred``, ``<axis>_meas``."""
    mpc = run.mpc_log
    cols = ["t_s", "t_pred_s"] + [f"{k}_{w}" for k, *_ in MOMENTA for w in ("pred", "meas")]
    if mpc is None or any(c not in mpc for c in cols):
        return {c: np.zeros(0) for c in cols}
    ok = mpc["full_solve"] > 0.5
    for c in cols[2:]:
        ok &= np.isfinite(mpc[c])
    return {c: mpc[c][ok] for c in cols}


def prediction_errors(pairs: dict[str, np.ndarray]) -> dict[str, dict[str, float]]:
    """Per axis: ``n``, ``rmse``, ``std`` (of the measurement), ``nrmse`` and ``corr``."""
    out = {}
    for key, *_ in MOMENTA:
        p, m = pairs[f"{key}_pred"], pairs[f"{key}_meas"]
        n = int(p.size)
        rmse = float(np.sqrt(np.mean((p - m) ** 2))) if n else math.nan
        std = float(np.std(m)) if n else math.nan
        corr = float(np.corrcoef(p, m)[0, 1]) if n > 2 and np.std(p) > 0 < std else math.nan
        out[key] = {"n": n, "rmse": rmse, "std": std, "nrmse": rmse / std if std > 0 else math.nan,
                    "corr": corr}  # fmt: skip
    return out


def build_fig8(
    out: Path, duration_s: float, video: VideoConfig | None, log: Log, quick: bool
) -> Report:
    runs = {
        c: run_in_folder(figure_scenario(c, "stepping-stones", VX_MPS, duration_s),
                         out / "runs" / f"{c}-stones", video, log)
        for c in ("gaitnet", "kd")
    }  # fmt: skip
    pairs = {c: momentum_pairs(r) for c, r in runs.items()}
    errs = {c: prediction_errors(p) for c, p in pairs.items()}
    rows = [
        {"controller": c, **{k: float(v[i]) for k, v in p.items()}}
        for c, p in pairs.items()
        for i in range(p["t_s"].size)
    ]
    write_csv(out, "fig8", rows)

    fig = new_figure(10.0, 8.0)
    axes = fig.subplots(3, 1, sharex=True)
    for ax, (key, label, _, axis_label) in zip(axes, MOMENTA, strict=True):
        for c, run in runs.items():
            color = CONTROLLER_COLORS[c]
            ax.plot(run.log["t_s"], run.log[key], color=color, lw=0.8, alpha=0.6,
                    label=f"{c}: measured")  # fmt: skip
            ax.scatter(pairs[c]["t_pred_s"], pairs[c][f"{key}_pred"], s=22, facecolors="none",
                       edgecolors=color, linewidths=1.1, zorder=3,
                       label=f"{c}: MPC prediction made at a step start")  # fmt: skip
        nrmse = ", ".join(f"{c} {e[key]['nrmse']:.2f}" for c, e in errs.items())
        ax.set_title(f"{label}: RMSE / std of the measurement: {nrmse}", fontsize=9)
        ax.set_ylabel(axis_label)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="best", fontsize=7, ncols=2)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(
        f"Fig. 8: spatial momenta, measured vs predicted one MPC stage ahead, {ROBOT} on the "
        f"stepping stones at {VX_MPS:g} m/s", fontsize=10,
    )  # fmt: skip
    save_figure(fig, out, "fig8")

    table = [
        "| controller | axis | step starts | RMSE | std measured | RMSE / std | correlation |",
        "|---|---|---|---|---|---|---|",
    ]
    for c, e in errs.items():
        for key, label, unit, _ in MOMENTA:
            v = e[key]
            table.append(
                f"| `{c}` | {label} [{unit}] | {v['n']} | {v['rmse']:.3f} | {v['std']:.3f} | "
                f"{v['nrmse']:.2f} | {v['corr']:.2f} |"
            )
    table.append('| paper | all three | each footstep | - | - | - | "a good prediction" |')
    follow = {
        c: not fell(runs[c]) and all(e[k]["nrmse"] < NRMSE_MAX for k, *_ in MOMENTA)
        for c, e in errs.items()
    }
    claims = [
        "- *the MPC's prediction follows the measured spatial momenta (Gait-Net-augmented "
        f"method)*: **{word(follow['gaitnet'])}** for `gaitnet` (rule: no fall and RMSE / "
        f"std of the measurement < {NRMSE_MAX:g} on each of l_G,x, k_G,y and k_G,z); `kd` "
        f"by the same rule: {word(follow['kd'])}."
    ]
    notes = [
        "Prediction: the plan of each step start's solve at its first stage (one MPC dt "
        "ahead), against the momentum measured at the first tick at or after that time "
        "(`mpc_log.csv` `*_pred`, `*_meas`); only the first stage of a plan is logged. The "
        "std is over the same instants, so the ramp from rest enters l_G,x's. Runs: "
        + "; ".join(f"`{c}` {outcome(r)}" for c, r in runs.items())
        + "."
    ]
    setup = (
        f"`{ROBOT}` on the built-in `stepping-stones` at {VX_MPS:g} m/s: `gaitnet` and `kd` "
        f"(fixed dt {KD_DT_S:g} s), default settings."
    )
    return Report(
        "Fig. 8: spatial momenta, measured vs MPC prediction", setup, table, claims, notes,
        list(runs.values()),
    )  # fmt: skip


__all__ = ["MOMENTA", "NRMSE_MAX", "build_fig8", "momentum_pairs", "prediction_errors"]
