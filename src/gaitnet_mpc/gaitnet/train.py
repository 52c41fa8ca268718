"""Train Gait-Net (paper Sec. IV-A, Fig. 3) with PyTorch; export for NumPy inference.

An ensemble of ``members`` MLPs (``hidden`` units per layer, tanh), each trained from its
own seed with Adam on the mean squared error of the standardised dt, mini-batches, and
early stopping on validation sets (the epoch with the lowest validation loss is kept).
Standardisation is fitted on the training sets only. PyTorch runs single-threaded and
deterministic, so the same data, split and seed give the same weights.

PyTorch is needed only here (``pip install 'gaitnet-mpc[train]'``); the controller uses
:class:`~gaitnet_mpc.gaitnet.model.GaitNet`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.errors import ConfigError, reraise_interrupt
from gaitnet_mpc.gaitnet.model import GaitNetWeights

#: Most ensemble members (the paper's ensemble is 5; 100 is a training of hours).
MAX_MEMBERS = 100
#: Most epochs per member (early stopping ends members within a few hundred).
MAX_EPOCHS = 100_000


@dataclass(frozen=True)
class TrainConfig:
    """Training settings.

    Attributes:
        hidden: units of each hidden layer.
        members: ensemble size (1: a single net, no spread).
        epochs: most passes over the training rows.
        patience: stop after this many epochs without a better validation loss.
        batch_size: rows per Adam step.
        learning_rate: Adam's step size.
        weight_decay: L2 penalty (AdamW's decoupled decay).
        seed: seed of member 0 (member i uses seed + i).
    """

    hidden: tuple[int, ...] = (32, 32)
    members: int = 5
    epochs: int = 400
    patience: int = 40
    batch_size: int = 64
    learning_rate: float = 3e-3
    weight_decay: float = 1e-4
    seed: int = 0

    def __post_init__(self) -> None:
        if not self.hidden or any(int(h) < 1 for h in self.hidden):
            raise ConfigError("hidden", self.hidden, "one or more layer sizes >= 1")
        for name, most in (
            ("members", MAX_MEMBERS),
            ("epochs", MAX_EPOCHS),
            ("patience", MAX_EPOCHS),
            ("batch_size", 1 << 20),
        ):
            value = getattr(self, name)
            if not (isinstance(value, int) and 1 <= value <= most):
                raise ConfigError(f"--{name}", value, f"an integer in [1, {most}]")
        if not (math.isfinite(self.learning_rate) and self.learning_rate > 0):
            raise ConfigError("learning_rate", self.learning_rate, "a value > 0")
        seed = self.seed  # member i seeds PyTorch (a 64-bit integer) with seed + i
        if isinstance(seed, bool) or not (isinstance(seed, int) and 0 <= seed <= 2**31):
            raise ConfigError("--seed", seed, "an integer in [0, 2^31]")


@dataclass
class TrainResult:
    """The exported ensemble and each member's loss curves (standardised MSE per epoch)."""

    weights: GaitNetWeights
    train_loss: list[list[float]] = field(default_factory=list)
    val_loss: list[list[float]] = field(default_factory=list)
    best_epoch: list[int] = field(default_factory=list)


def _import_torch():  # type: ignore[no-untyped-def]
    try:
        import torch
    except ImportError as exc:
        reraise_interrupt(exc)
        raise ConfigError(
            "training", "PyTorch missing", "pip install 'gaitnet-mpc[train]' (torch==2.13.0)"
        ) from None
    return torch


@dataclass(frozen=True)
class MemberFit:
    """One trained member: its layers (best validation epoch) and loss curves.

    Members are independent (each from its own seed), so a training interrupted after some
    members resumes from them and gives the same ensemble as one that was not.
    """

    weights: tuple[np.ndarray, ...]  # (out, in) per layer
    biases: tuple[np.ndarray, ...]  # (out,) per layer
    train_loss: tuple[float, ...]
    val_loss: tuple[float, ...]
    best_epoch: int

    def save(self, path: str | Path) -> None:
        """Write the member as a ``.npz`` (exact float64), atomically."""
        import io

        from gaitnet_mpc.results.io import write_bytes_atomic

        arrays: dict[str, Any] = {f"w{i}": w for i, w in enumerate(self.weights)}
        arrays |= {f"b{i}": b for i, b in enumerate(self.biases)}
        arrays["train_loss"] = np.array(self.train_loss, dtype=float)
        arrays["val_loss"] = np.array(self.val_loss, dtype=float)
        arrays["best_epoch"] = np.array(self.best_epoch)
        buf = io.BytesIO()
        np.savez(buf, **arrays)
        write_bytes_atomic(path, buf.getvalue())

    @classmethod
    def load(cls, path: str | Path) -> MemberFit:
        with np.load(path, allow_pickle=False) as f:
            n = sum(1 for k in f.files if k.startswith("w"))
            return cls(
                weights=tuple(np.asarray(f[f"w{i}"], dtype=float) for i in range(n)),
                biases=tuple(np.asarray(f[f"b{i}"], dtype=float) for i in range(n)),
                train_loss=tuple(float(v) for v in f["train_loss"]),
                val_loss=tuple(float(v) for v in f["val_loss"]),
                best_epoch=int(f["best_epoch"]),
            )


def train_ensemble(
    x_train: np.ndarray,
    y_train: np.ndarray,
    x_val: np.ndarray,
    y_val: np.ndarray,
    feature_names: tuple[str, ...],
    dt_clip_s: tuple[float, float],
    config: TrainConfig | None = None,
    progress: Callable[[int, int], None] | None = None,
    provenance: dict[str, str] | None = None,
    done: Mapping[int, MemberFit] | None = None,
    on_member: Callable[[int, MemberFit], None] | None = None,
) -> TrainResult:
    """Train ``config.members`` nets on (x_train, y_train [s]); early-stop on the
    validation rows. ``progress(member, epoch)`` is called after every epoch.

    ``done`` holds members trained before (a resumed training): they are taken as they
    are. ``on_member(member, fit)`` is called after each member is trained (to keep it)."""
    torch = _import_torch()
    cfg = config or TrainConfig()
    if len(x_train) < 2 or len(x_val) < 1:
        raise ConfigError("training rows", (len(x_train), len(x_val)), ">= 2 train, >= 1 val")
    x_mean = x_train.mean(axis=0)
    x_std = x_train.std(axis=0)
    x_std = np.where(x_std > 1e-9, x_std, 1.0)  # constant columns (planar robot) pass through
    y_mean, y_std = float(y_train.mean()), float(max(y_train.std(), 1e-9))
    xt = torch.tensor((x_train - x_mean) / x_std, dtype=torch.float64)
    yt = torch.tensor((y_train - y_mean) / y_std, dtype=torch.float64)[:, None]
    xv = torch.tensor((x_val - x_mean) / x_std, dtype=torch.float64)
    yv = torch.tensor((y_val - y_mean) / y_std, dtype=torch.float64)[:, None]
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    fits: list[MemberFit] = []
    try:
        torch.use_deterministic_algorithms(True)
        for member in range(cfg.members):
            if done is not None and member in done:
                fits.append(done[member])
                continue
            fit = _train_member(torch, member, cfg, (xt, yt, xv, yv), progress)
            fits.append(fit)
            if on_member is not None:
                on_member(member, fit)
    finally:
        torch.set_num_threads(threads)
        torch.use_deterministic_algorithms(False)
    info = provenance or {}
    n_layers = len(fits[0].weights)
    weights = GaitNetWeights(
        weights=tuple(np.stack([f.weights[i] for f in fits]) for i in range(n_layers)),
        biases=tuple(np.stack([f.biases[i] for f in fits]) for i in range(n_layers)),
        feature_names=tuple(feature_names),
        x_mean=x_mean,
        x_std=x_std,
        y_mean=y_mean,
        y_std=y_std,
        dt_clip_s=dt_clip_s,
        activation="tanh",
        data_manifest_sha256=info.get("data_manifest_sha256", ""),
        robot=info.get("robot", ""),
        teacher=info.get("teacher", ""),
    )
    return TrainResult(
        weights=weights,
        train_loss=[list(f.train_loss) for f in fits],
        val_loss=[list(f.val_loss) for f in fits],
        best_epoch=[f.best_epoch for f in fits],
    )


def _train_member(
    torch: Any,
    member: int,
    cfg: TrainConfig,
    tensors: tuple[Any, Any, Any, Any],
    progress: Callable[[int, int], None] | None,
) -> MemberFit:
    """Member ``member`` trained from seed ``cfg.seed + member`` alone (nothing of the
    other members), early-stopped on the validation loss."""
    xt, yt, xv, yv = tensors
    torch.manual_seed(cfg.seed + member)
    net = _mlp(torch, [xt.shape[1], *cfg.hidden, 1])
    opt = torch.optim.AdamW(net.parameters(), lr=cfg.learning_rate, weight_decay=cfg.weight_decay)
    gen = torch.Generator().manual_seed(cfg.seed + member)
    best, best_state, best_epoch = math.inf, None, 0
    curve_t: list[float] = []
    curve_v: list[float] = []
    for epoch in range(cfg.epochs):
        net.train()
        order = torch.randperm(len(xt), generator=gen)
        total = 0.0
        for start in range(0, len(xt), cfg.batch_size):
            idx = order[start : start + cfg.batch_size]
            opt.zero_grad()
            loss = torch.mean((net(xt[idx]) - yt[idx]) ** 2)
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
        net.eval()
        with torch.no_grad():
            val = float(torch.mean((net(xv) - yv) ** 2))
        curve_t.append(total / len(xt))
        curve_v.append(val)
        if val < best - 1e-9:
            best, best_epoch = val, epoch
            best_state = {k: v.clone() for k, v in net.state_dict().items()}
        if progress is not None:
            progress(member, epoch)
        if epoch - best_epoch >= cfg.patience:
            break
    assert best_state is not None
    net.load_state_dict(best_state)
    linears = [m for m in net if isinstance(m, torch.nn.Linear)]
    return MemberFit(
        weights=tuple(lin.weight.detach().numpy().copy() for lin in linears),
        biases=tuple(lin.bias.detach().numpy().copy() for lin in linears),
        train_loss=tuple(curve_t),
        val_loss=tuple(curve_v),
        best_epoch=best_epoch,
    )


def _mlp(torch: Any, sizes: list[int]) -> Any:
    """A float64 MLP with tanh between its linear layers of ``sizes``."""
    modules: list[Any] = []
    for i in range(len(sizes) - 1):
        modules.append(torch.nn.Linear(sizes[i], sizes[i + 1], dtype=torch.float64))
        if i < len(sizes) - 2:
            modules.append(torch.nn.Tanh())
    return torch.nn.Sequential(*modules)


def torch_members(weights: GaitNetWeights) -> list[Any]:
    """The ensemble's members as PyTorch modules (eval mode) from exported weights; they
    take standardised features and return the standardised dt."""
    torch = _import_torch()
    sizes = [weights.weights[0].shape[2], *(w.shape[1] for w in weights.weights)]
    members = []
    for k in range(weights.members):
        net = _mlp(torch, sizes)
        linears = [m for m in net if isinstance(m, torch.nn.Linear)]
        for lin, w, b in zip(linears, weights.weights, weights.biases, strict=True):
            lin.weight.data = torch.tensor(w[k])
            lin.bias.data = torch.tensor(b[k])
        members.append(net.eval())
    return members


def torch_predict(result: TrainResult, x: np.ndarray) -> np.ndarray:
    """The ensemble mean dt [s] of ``x`` (n, f) evaluated by PyTorch, from the exported
    weights (the reference that the NumPy inference must match)."""
    torch = _import_torch()
    w = result.weights
    z = torch.tensor((x - w.x_mean) / w.x_std, dtype=torch.float64)
    with torch.no_grad():
        outs = [net(z)[:, 0].numpy() * w.y_std + w.y_mean for net in torch_members(w)]
    return np.mean(outs, axis=0)
