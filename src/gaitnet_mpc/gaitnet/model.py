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
from typing import Any

import numpy as np

from gaitnet_mpc.dataset.schema import FEATURE_NAMES
from gaitnet_mpc.errors import ConfigError

FORMAT_VERSION = 1
ACTIVATIONS = ("tanh",)
#: The weights file in a model folder of ``gaitnet-mpc train --out DIR``.
WEIGHTS_FILE = "gaitnet.npz"


def _not_npz(path: Path) -> str | None:
    """None if ``path`` starts as an ``.npz`` (a zip archive) does; else what it is."""
    with path.open("rb") as fh:
        head = fh.read(512)
    if head.startswith((b"PK\x03\x04", b"PK\x05\x06")):
        return None
    if head.startswith(b"\x93NUMPY"):
        return "one .npy array"
    try:
        text = b"\0" not in head and bool(head.decode("utf-8", errors="strict").strip())
    except UnicodeDecodeError:
        text = False
    return "a text file" if text else ("an empty file" if not head else "other binary data")


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
        unknown = [n for n in self.feature_names if n not in FEATURE_NAMES]
        if not self.feature_names or unknown:
            raise ConfigError("feature_names", unknown or [], f"names among {FEATURE_NAMES}")
        n_in = len(self.feature_names)
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            if w.ndim != 3 or b.ndim != 2 or b.shape != w.shape[:2] or w.shape[2] != n_in:
                raise ConfigError(
                    f"layer{i}_w / layer{i}_b",
                    (w.shape, b.shape),
                    f"(K, out, {n_in}) and (K, out), K and out the same in both",
                )
            n_in = w.shape[1]
        if n_in != 1 or len({w.shape[0] for w in self.weights}) != 1:
            raise ConfigError(
                "layers", [w.shape for w in self.weights], "K members ending in 1 output"
            )
        if self.x_mean.shape != (len(self.feature_names),) or self.x_std.shape != self.x_mean.shape:
            raise ConfigError("x_mean / x_std", (self.x_mean.shape, self.x_std.shape), "(f,) each")
        arrays = (*self.weights, *self.biases, self.x_mean, self.x_std)
        if not all(np.all(np.isfinite(a)) for a in arrays) or not np.all(self.x_std > 0):
            raise ConfigError("weights", "non-finite values", "finite weights and x_std > 0")
        if not (math.isfinite(self.y_mean) and math.isfinite(self.y_std) and self.y_std > 0):
            raise ConfigError("y_mean / y_std", (self.y_mean, self.y_std), "finite, y_std > 0")
        lo, hi = self.dt_clip_s
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
            raise ConfigError("dt_clip_s", self.dt_clip_s, "0 < lo < hi [s]")

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
        """Read a weights file; a :class:`ConfigError` names the file and what is wrong
        (not a ``.npz``, a missing entry, inconsistent shapes, non-finite values)."""
        import zipfile

        path = Path(path)
        if not path.is_file():
            raise ConfigError("Gait-Net weights", str(path), "an existing .npz file")
        try:
            what = _not_npz(path)
            if what is not None:  # np.load would read it as a pickle and say so
                expected = f"a Gait-Net weights .npz from `gaitnet-mpc train` (this is {what})"
                raise ConfigError("Gait-Net weights", str(path), expected)
            f = np.load(path, allow_pickle=False)
            if not isinstance(f, np.lib.npyio.NpzFile):
                raise ConfigError("Gait-Net weights", str(path), "an .npz archive, not one array")
            with f:
                return cls._from_arrays(f)
        except ConfigError as exc:
            if exc.field == "Gait-Net weights":
                raise
            raise ConfigError(f"{path}: {exc.field}", exc.value, exc.expected) from None
        except KeyError as exc:
            missing = str(exc.args[0] if exc.args else exc)
            raise ConfigError(str(path), missing, "a Gait-Net weights file") from None
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            expected = f"a Gait-Net weights .npz (gaitnet-mpc train) ({type(exc).__name__}: {exc})"
            raise ConfigError("Gait-Net weights", str(path), expected) from None

    @classmethod
    def _from_arrays(cls, f: Any) -> GaitNetWeights:
        if int(f["format_version"]) != FORMAT_VERSION:
            raise ConfigError("format_version", int(f["format_version"]), str(FORMAT_VERSION))
        n = sum(1 for k in f.files if k.endswith("_w"))
        return cls(
            weights=tuple(np.asarray(f[f"layer{i}_w"], dtype=float) for i in range(n)),
            biases=tuple(np.asarray(f[f"layer{i}_b"], dtype=float) for i in range(n)),
            feature_names=tuple(str(s) for s in np.atleast_1d(f["feature_names"])),
            x_mean=np.atleast_1d(np.asarray(f["x_mean"], dtype=float)),
            x_std=np.atleast_1d(np.asarray(f["x_std"], dtype=float)),
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

    def predict(self, x: np.ndarray, x_mirror: np.ndarray | None = None) -> tuple[float, float]:
        """(dt [s] clipped into ``dt_clip_s``, spread [s]: the members' standard deviation)
        for one feature vector (f,) in ``feature_names`` order. With ``x_mirror``, the
        features of the step start's mirror image, each member answers the mean of its dts
        of the two (a policy symmetric by construction). Not thread-safe (it reuses
        buffers); give each thread its own :class:`GaitNet`."""
        dts = self._one(np.asarray(x, dtype=float)).tolist()
        if x_mirror is not None:
            mirrored = self._one(np.asarray(x_mirror, dtype=float)).tolist()
            dts = [0.5 * (a + b) for a, b in zip(dts, mirrored, strict=True)]
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
