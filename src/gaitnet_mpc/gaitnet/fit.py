"""From a data-set folder to trained Gait-Net weights and a report (``gaitnet-mpc train``).

The rows are split by set (:func:`~gaitnet_mpc.gaitnet.data.split_by_set`); the feature
selection (PCA, Sec. IV-A-2) and the standardisation see the training sets only. The
report compares the test RMSE with the RMSE of always predicting the training mean (what
the features add), overall and on the pushed steps.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.dataset.schema import FEATURE_NAMES
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gaitnet.data import GaitData, SetSplit, split_by_set
from gaitnet_mpc.gaitnet.features import PCASelection, pca_select
from gaitnet_mpc.gaitnet.model import WEIGHTS_FILE, GaitNet
from gaitnet_mpc.gaitnet.train import MemberFit, TrainConfig, TrainResult, train_ensemble

FEATURE_SETS = ("pca", "full")


@dataclass
class FitReport:
    """What one training produced (``report.json``)."""

    features: str
    feature_names: tuple[str, ...]
    split: SetSplit
    rows: dict[str, int]
    test_rmse_s: float
    test_rmse_pushed_s: float | None
    mean_predictor_rmse_s: float
    test_spread_median_unpushed_s: float
    test_spread_median_pushed_s: float | None
    best_epochs: list[int]
    train_wall_s: float
    robot: str
    teacher: str
    data_manifest_sha256: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def feature_subset(kind: str) -> tuple[str, ...] | None:
    """The feature names of ``kind`` when it lists them (``"com_x_m,com_vx_mps"``), None
    for a named set (:data:`FEATURE_SETS`).

    Raises:
        ConfigError: ``kind`` is neither a named set nor a list of known feature names.
    """
    if kind in FEATURE_SETS:
        return None
    names = tuple(n.strip() for n in kind.split(",") if n.strip())
    unknown = [n for n in names if n not in FEATURE_NAMES]
    if not names or unknown or len(set(names)) != len(names):
        raise ConfigError(
            "--features", kind,
            f"one of {list(FEATURE_SETS)}, or distinct names from {list(FEATURE_NAMES)} "
            "separated by commas",
        )  # fmt: skip
    return names


def feature_columns(x_train: np.ndarray, kind: str) -> tuple[list[int], PCASelection | None]:
    """The input columns of the ``kind`` feature set (all 16, the names it lists, or the
    PCA selection on the training rows ``x_train``) and that selection (None but for
    ``"pca"``)."""
    subset = feature_subset(kind)
    if subset is not None:
        return [FEATURE_NAMES.index(n) for n in subset], None
    if kind == "full":
        return list(range(len(FEATURE_NAMES))), None
    selection = pca_select(x_train, FEATURE_NAMES)
    return list(selection.indices), selection


def fit(
    data: GaitData,
    kind: str,
    config: TrainConfig | None = None,
    split_seed: int = 0,
    progress: bool = True,
    done: Mapping[int, MemberFit] | None = None,
    on_member: Callable[[int, MemberFit], None] | None = None,
) -> tuple[TrainResult, FitReport, PCASelection | None]:
    """Train on ``data`` with the ``kind`` feature set; evaluate on the held-out sets.

    ``done`` and ``on_member`` resume a training member by member (see
    :func:`~gaitnet_mpc.gaitnet.train.train_ensemble`)."""
    cfg = config or TrainConfig()
    split = split_by_set(data.set_id, seed=split_seed)
    part = {name: np.isin(data.set_id, getattr(split, name)) for name in ("train", "val", "test")}
    cols, selection = feature_columns(data.x[part["train"]], kind)
    names = tuple(FEATURE_NAMES[i] for i in cols)
    x = data.x[:, cols]
    bar, update = _bar(cfg) if progress else (None, None)
    t0 = time.perf_counter()
    result = train_ensemble(
        x[part["train"]],
        data.y[part["train"]],
        x[part["val"]],
        data.y[part["val"]],
        names,
        data.dt_range_s,
        cfg,
        progress=update,
        done=done,
        on_member=on_member,
        provenance={
            "data_manifest_sha256": data.manifest_sha256,
            "robot": data.robot,
            "teacher": data.teacher,
        },
    )
    wall = time.perf_counter() - t0
    if bar is not None:
        bar.close()
    net = GaitNet(result.weights)
    test = part["test"]
    members = net.members_dt(x[test])
    lo, hi = data.dt_range_s
    pred = np.clip(members.mean(axis=1), lo, hi)
    err = pred - data.y[test]
    pushed = data.pushed[test]
    spread = members.std(axis=1)
    report = FitReport(
        features=kind,
        feature_names=names,
        split=split,
        rows={k: int(v.sum()) for k, v in part.items()},
        test_rmse_s=_rmse(err),
        test_rmse_pushed_s=_rmse(err[pushed]) if np.any(pushed) else None,
        mean_predictor_rmse_s=_rmse(data.y[test] - data.y[part["train"]].mean()),
        test_spread_median_unpushed_s=float(np.median(spread[~pushed])) if np.any(~pushed) else 0.0,
        test_spread_median_pushed_s=float(np.median(spread[pushed])) if np.any(pushed) else None,
        best_epochs=result.best_epoch,
        train_wall_s=wall,
        robot=data.robot,
        teacher=data.teacher,
        data_manifest_sha256=data.manifest_sha256,
    )
    return result, report, selection


def write_fit(
    out: Path, result: TrainResult, report: FitReport, selection: PCASelection | None
) -> None:
    """``gaitnet.npz``, ``report.json``, ``loss.csv`` and ``loss.png`` (and ``fig4.png``
    for a PCA selection) in ``out``."""
    from gaitnet_mpc.gaitnet.plots import plot_loadings, plot_loss
    from gaitnet_mpc.results.io import write_atomic, write_json_atomic

    out.mkdir(parents=True, exist_ok=True)
    result.weights.save(out / WEIGHTS_FILE)
    write_json_atomic(out / "report.json", report.to_dict())
    lines = ["member,epoch,train_mse,val_mse"]
    for m, (t, v) in enumerate(zip(result.train_loss, result.val_loss, strict=True)):
        lines += [f"{m},{e},{a:.6g},{b:.6g}" for e, (a, b) in enumerate(zip(t, v, strict=True))]
    write_atomic(out / "loss.csv", "\n".join(lines) + "\n")
    plot_loss(result, out / "loss.png")
    if selection is not None:
        plot_loadings(selection, FEATURE_NAMES, out / "fig4.png")


def _rmse(err: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(err))))


def _bar(cfg: TrainConfig) -> tuple[Any, Any]:
    from tqdm import tqdm

    bar = tqdm(total=cfg.members * cfg.epochs, unit="epoch", leave=False, mininterval=0.5)

    def update(member: int, epoch: int) -> None:
        # early stopping skips a member's remaining epochs: the bar jumps over them
        bar.update(member * cfg.epochs + epoch + 1 - bar.n)
        bar.set_postfix_str(f"member {member + 1}/{cfg.members}", refresh=False)

    return bar, update
