"""Gait-Net inference in NumPy, from a plain ``.npz`` (no pickle, no framework).

The network (paper Fig. 3) is an MLP from the features at a step start (raw units; the
standardisation is folded into the first layer) to the step's MPC dt [s]. A file holds
an ensemble of ``K`` such MLPs trained from different seeds; their mean is the
prediction and their spread (standard deviation) says when an input lies outside what
the data taught (the members agree where there was data, and disagree elsewhere).

For speed the members are fused into one wider MLP at load time: the first layers are
stacked, the hidden ones made block-diagonal, so one call evaluates all ``K`` with the
same three matrix-vector products a single net needs.

File format (``np.savez``; every entry a plain array):

* ``format_version`` (1), ``activation`` (``"tanh"``);
* ``layer{i}_w`` (K, out, in) and ``layer{i}_b`` (K, out) for i = 0 .. L-1;
* ``feature_names`` (f,) strings, the columns of the data set's schema it reads;
* ``x_mean``, ``x_std`` (f,), ``y_mean``, ``y_std`` (): the training standardisation;
* ``dt_clip_s`` (2,): predictions are clipped into this range (the data's);
* ``data_manifest_sha256``, ``robot``, ``teacher``: the data it was trained on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitnet_mpc.errors import ConfigError

FORMAT_VERSION = 1
ACTIVATIONS = ("tanh",)


@dataclass(frozen=True)
class GaitNetWeights:
    """The contents of a weights file (see the module docstring)."""

    weights: tuple[np.ndarray, ...]  # (K, out, in) per layer
    biases: tuple[np.ndarray, ...]  # (K, out) per layer
    feature_names: tuple[str, ...]
    x_mean: np.ndarray
    x_std: np.ndarray
    y_mean: float
    y_std: float
    dt_clip_s: tuple[float, float]
    activation: str = "tanh"
    data_manifest_sha256: str = ""
    robot: str = ""
    teacher: str = ""

    def __post_init__(self) -> None:
        if self.activation not in ACTIVATIONS:
            raise ConfigError("activation", self.activation, f"one of {list(ACTIVATIONS)}")
        if len(self.weights) != len(self.biases) or not self.weights:
            raise ConfigError("layers", len(self.weights), "as many weight as bias arrays (>0)")
        if self.weights[0].shape[2] != len(self.feature_names):
            raise ConfigError(
                "layer0_w", self.weights[0].shape, f"(K, h, {len(self.feature_names)})"
            )

    @property
    def members(self) -> int:
        return int(self.weights[0].shape[0])

    def save(self, path: str | Path) -> None:
        """Write the ``.npz`` atomically."""
        import io

        from gaitnet_mpc.results.io import write_bytes_atomic

        arrays: dict[str, np.ndarray] = {
            "format_version": np.array(FORMAT_VERSION),
            "activation": np.array(self.activation),
            "feature_names": np.array(self.feature_names),
            "x_mean": self.x_mean,
            "x_std": self.x_std,
            "y_mean": np.array(self.y_mean),
            "y_std": np.array(self.y_std),
            "dt_clip_s": np.array(self.dt_clip_s),
            "data_manifest_sha256": np.array(self.data_manifest_sha256),
            "robot": np.array(self.robot),
            "teacher": np.array(self.teacher),
        }
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            arrays[f"layer{i}_w"], arrays[f"layer{i}_b"] = w, b
        buf = io.BytesIO()
        np.savez(buf, **arrays)  # type: ignore[arg-type]
        write_bytes_atomic(path, buf.getvalue())

    @classmethod
    def load(cls, path: str | Path) -> GaitNetWeights:
        path = Path(path)
        if not path.is_file():
            raise ConfigError("Gait-Net weights", str(path), "an existing .npz file")
        with np.load(path, allow_pickle=False) as f:
            if int(f["format_version"]) != FORMAT_VERSION:
                raise ConfigError(
                    f"{path.name}: format_version", int(f["format_version"]), str(FORMAT_VERSION)
                )
            n = sum(1 for k in f.files if k.endswith("_w"))
            return cls(
                weights=tuple(np.asarray(f[f"layer{i}_w"], dtype=float) for i in range(n)),
                biases=tuple(np.asarray(f[f"layer{i}_b"], dtype=float) for i in range(n)),
                feature_names=tuple(str(s) for s in f["feature_names"]),
                x_mean=np.asarray(f["x_mean"], dtype=float),
                x_std=np.asarray(f["x_std"], dtype=float),
                y_mean=float(f["y_mean"]),
                y_std=float(f["y_std"]),
                dt_clip_s=(float(f["dt_clip_s"][0]), float(f["dt_clip_s"][1])),
                activation=str(f["activation"]),
                data_manifest_sha256=str(f["data_manifest_sha256"]),
                robot=str(f["robot"]),
                teacher=str(f["teacher"]),
            )


class GaitNet:
    """Fast NumPy inference of an ensemble (:class:`GaitNetWeights`)."""

    def __init__(self, weights: GaitNetWeights) -> None:
        self.spec = weights
        k = weights.members
        w0 = np.concatenate(list(weights.weights[0]), axis=0)  # (K h, f)
        b0 = np.concatenate(list(weights.biases[0]))
        w0 = w0 / weights.x_std[None, :]  # standardisation folded into layer 0
        self._w = [w0] + [_block_diag(w) for w in weights.weights[1:]]
        self._b = [b0 - w0 @ weights.x_mean] + [np.concatenate(list(b)) for b in weights.biases[1:]]
        # label de-standardisation folded into the last layer
        self._w[-1] = self._w[-1] * weights.y_std
        self._b[-1] = self._b[-1] * weights.y_std + weights.y_mean
        self._k = k
        self._buffers = [np.empty(w.shape[0]) for w in self._w]  # one-vector calls
        self.feature_names = weights.feature_names
        self.dt_clip_s = weights.dt_clip_s

    @classmethod
    def load(cls, path: str | Path) -> GaitNet:
        return cls(GaitNetWeights.load(path))

    def members_dt(self, x: np.ndarray) -> np.ndarray:
        """Each member's dt [s] (unclipped): (K,) for a feature vector (f,), (n, K) for rows."""
        z = np.asarray(x, dtype=float)
        if z.ndim == 1:
            return self._one(z).copy()
        for w, b in zip(self._w[:-1], self._b[:-1], strict=True):
            z = np.tanh(z @ w.T + b)
        return np.asarray(z @ self._w[-1].T + self._b[-1])

    def _one(self, x: np.ndarray) -> np.ndarray:
        """Members' dts of one vector in preallocated buffers (no allocation per layer)."""
        z = x
        last = len(self._w) - 1
        for i, (w, b, buf) in enumerate(zip(self._w, self._b, self._buffers, strict=True)):
            np.dot(w, z, out=buf)
            buf += b
            if i < last:
                np.tanh(buf, out=buf)
            z = buf
        return z

    def predict(self, x: np.ndarray) -> tuple[float, float]:
        """(dt [s] clipped into ``dt_clip_s``, spread [s]: the members' standard deviation)
        for one feature vector (f,) in ``feature_names`` order. Not thread-safe (it reuses
        buffers); give each thread its own :class:`GaitNet`."""
        dts = self._one(np.asarray(x, dtype=float)).tolist()
        mean = sum(dts) / self._k
        spread = math.sqrt(sum((d - mean) ** 2 for d in dts) / self._k)
        lo, hi = self.dt_clip_s
        return min(max(mean, lo), hi), spread


def _block_diag(w: np.ndarray) -> np.ndarray:
    """(K, out, in) -> (K out, K in) block-diagonal."""
    k, n_out, n_in = w.shape
    out = np.zeros((k * n_out, k * n_in))
    for i in range(k):
        out[i * n_out : (i + 1) * n_out, i * n_in : (i + 1) * n_in] = w[i]
    return out
