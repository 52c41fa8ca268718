"""Figures of Gait-Net training: loss curves, and the PCA loadings of paper Fig. 4."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitnet_mpc.gaitnet.features import PCASelection
from gaitnet_mpc.gaitnet.train import TrainResult
from gaitnet_mpc.results.plots import new_figure
from gaitnet_mpc.results.rundir import save_figure_atomic


def plot_loss(result: TrainResult, path: Path) -> Path:
    """Training and validation loss (standardised MSE) per epoch of every member; the
    kept epoch (lowest validation loss) marked."""
    fig = new_figure(8.0, 4.0)
    ax = fig.add_subplot()
    for m, (t, v) in enumerate(zip(result.train_loss, result.val_loss, strict=True)):
        line = ax.plot(t, lw=0.8, alpha=0.6, label="train" if m == 0 else None)[0]
        ax.plot(v, lw=1.2, ls="--", color=line.get_color(), label="validation" if m == 0 else None)
        best = result.best_epoch[m]
        ax.plot(best, v[best], "o", color=line.get_color(), ms=4)
    ax.set_yscale("log")
    ax.set_xlabel("epoch")
    ax.set_ylabel("MSE of the standardised dt")
    ax.set_title(f"Gait-Net training, {len(result.train_loss)} member(s); dots: kept epoch")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure_atomic(fig, path)


def plot_loadings(selection: PCASelection, names: tuple[str, ...], path: Path) -> Path:
    """Fig. 4: each principal axis' loadings on the 16 features; the selected one red."""
    n = len(selection.indices)
    fig = new_figure(11.0, 1.9 * n)
    axes = fig.subplots(n, 1, sharex=True)
    x = np.arange(len(names))
    for k, ax in enumerate(np.atleast_1d(axes)):
        colors = ["tab:red" if i == selection.indices[k] else "tab:gray" for i in x]
        ax.bar(x, selection.loadings[k], color=colors)
        ax.axhline(0.0, color="black", lw=0.5)
        ax.set_ylabel(f"axis {k + 1}\n({100 * selection.explained[k]:.0f} %)", fontsize=8)
        ax.set_ylim(-1.0, 1.0)
        ax.grid(axis="y", alpha=0.3)
    ax.set_xticks(x, names, rotation=60, ha="right", fontsize=8)
    fig.suptitle("PCA loadings of the standardised features (red: selected)", fontsize=10)
    return save_figure_atomic(fig, path)
