"""Latent-space feature selection of paper Sec. IV-A-2 (Fig. 4).

PCA on the standardised features; from each of the top ``n_axes`` principal axes, the
feature with the largest absolute loading that no earlier axis took. The selected raw
features (not the projections) become the network's input, so inference needs no
projection and each input keeps its physical meaning.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.errors import ConfigError


@dataclass(frozen=True)
class PCASelection:
    """Result of :func:`pca_select`.

    Attributes:
        names: selected feature names, one per axis, in axis order.
        indices: their column indices in the input.
        loadings: (n_axes, n_features) principal axes (unit rows), sign fixed so that each
            axis' largest-magnitude loading is positive.
        explained: (n_axes,) fraction of the variance along each axis.
    """

    names: tuple[str, ...]
    indices: tuple[int, ...]
    loadings: np.ndarray
    explained: np.ndarray


def pca_select(x: np.ndarray, names: tuple[str, ...], n_axes: int = 6) -> PCASelection:
    """Select one feature per principal axis of the standardised ``x`` (n, f)."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[1] != len(names):
        raise ConfigError("features", x.shape, f"(n, {len(names)})")
    if not 1 <= n_axes <= len(names):
        raise ConfigError("n_axes", n_axes, f"an integer in [1, {len(names)}]")
    std = x.std(axis=0)
    # a constant column (e.g. roll on the planar biped) has no variance to explain
    z = (x - x.mean(axis=0)) / np.where(std > 1e-12, std, 1.0)
    _, s, vt = np.linalg.svd(z - z.mean(axis=0), full_matrices=False)
    variance = s**2
    explained = variance / variance.sum()
    axes = vt[:n_axes].copy()
    for row in axes:  # SVD signs are arbitrary; fix them for a deterministic plot
        if row[np.argmax(np.abs(row))] < 0:
            row *= -1.0
    chosen: list[int] = []
    for row in axes:
        order = np.argsort(-np.abs(row), kind="stable")
        chosen.append(int(next(i for i in order if i not in chosen)))
    return PCASelection(
        names=tuple(names[i] for i in chosen),
        indices=tuple(chosen),
        loadings=axes,
        explained=explained[:n_axes],
    )
