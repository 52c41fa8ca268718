"""``gaitnet-mpc reproduce table1``: paper Table I (full R^16 vs PCA-selected R^6 features)
and Fig. 4, from a committed data set.

Both nets are trained on the same split by set with the same settings; the test RMSE of
dt is over the held-out sets; the inference times are NumPy calls on one feature vector
each (as inside the sequential loop), the two nets interleaved in one run, the fastest of
15 rounds of 200 calls kept, and reported as the ratio PCA / full, as the paper
normalises them. PyTorch's own inference on the
same vectors is timed beside it, and the NumPy outputs are checked against it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitnet_mpc.errors import reraise_interrupt
from gaitnet_mpc.gaitnet.data import load_dataset
from gaitnet_mpc.gaitnet.fit import FitReport, fit, write_fit
from gaitnet_mpc.gaitnet.model import GaitNet
from gaitnet_mpc.gaitnet.train import TrainConfig, TrainResult, torch_members, torch_predict

#: Paper Table I: test RMSE of dt [s] and inference time normalised to the full net.
PAPER = {"full": (4.98e-3, 1.00), "pca": (6.79e-3, 0.74)}


@dataclass
class Table1Row:
    features: str
    n_features: int
    rmse_s: float
    mean_predictor_rmse_s: float
    numpy_us_per_call: float
    torch_us_per_call: float | None
    numpy_vs_torch_max_abs_s: float | None


def _time_calls(fn, xs: np.ndarray, repeats: int) -> float:  # type: ignore[no-untyped-def]
    """Fastest over ``repeats`` of the mean time [us] of one call of ``fn`` per row (the
    minimum: on a shared machine other work only ever adds time)."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for x in xs:
            fn(x)
        times.append((time.perf_counter() - t0) / len(xs))
    return 1e6 * float(np.min(times))


def _torch_single_call(result: TrainResult):  # type: ignore[no-untyped-def]
    """The ensemble in PyTorch, called on one vector (None: no torch)."""
    try:
        import torch
    except ImportError as exc:
        reraise_interrupt(exc)
        return None
    w = result.weights
    nets = torch_members(w)
    mean, std = torch.tensor(w.x_mean), torch.tensor(w.x_std)

    def call(x: np.ndarray) -> float:
        with torch.no_grad():
            z = (torch.from_numpy(x) - mean) / std
            return float(torch.stack([n(z) for n in nets]).mean()) * w.y_std + w.y_mean

    return call


def reproduce_table1(
    data_dir: Path, out: Path, config: TrainConfig | None = None, repeats: int = 15
) -> list[Table1Row]:
    """Train both nets, time them, write ``table1.md`` / ``.csv``, ``fig4.png`` and each
    net's training outputs (``full/``, ``pca/``) into ``out``."""
    from gaitnet_mpc.dataset.schema import FEATURE_NAMES

    data = load_dataset(data_dir)
    fits: dict[str, tuple[TrainResult, FitReport]] = {}
    for kind in ("full", "pca"):
        result, report, selection = fit(data, kind, config)
        write_fit(out / kind, result, report, selection)
        fits[kind] = (result, report)
    if (out / "pca" / "fig4.png").exists():
        (out / "fig4.png").write_bytes((out / "pca" / "fig4.png").read_bytes())
    test = np.isin(data.set_id, fits["full"][1].split.test)
    rows = []
    nets = {k: GaitNet(r.weights) for k, (r, _) in fits.items()}
    inputs = {
        k: np.ascontiguousarray(
            data.x[test][:, [FEATURE_NAMES.index(n) for n in nets[k].feature_names]]
        )
        for k in fits
    }
    numpy_us = {k: [] for k in fits}  # type: dict[str, list[float]]
    for _ in range(repeats):  # interleaved: both see the same machine load
        for k in fits:
            numpy_us[k].append(_time_calls(nets[k].predict, inputs[k][:200], 1))
    for kind, (result, report) in fits.items():
        torch_call = _torch_single_call(result)
        torch_us = diff = None
        if torch_call is not None:
            torch_us = _time_calls(torch_call, inputs[kind][:200], 3)
            ref = torch_predict(result, inputs[kind])
            diff = float(np.max(np.abs(nets[kind].members_dt(inputs[kind]).mean(axis=1) - ref)))
        rows.append(
            Table1Row(
                features=kind,
                n_features=len(report.feature_names),
                rmse_s=report.test_rmse_s,
                mean_predictor_rmse_s=report.mean_predictor_rmse_s,
                numpy_us_per_call=float(np.min(numpy_us[kind])),
                torch_us_per_call=torch_us,
                numpy_vs_torch_max_abs_s=diff,
            )
        )
    _write_table(out, rows, data.robot, data.teacher, fits["pca"][1])
    return rows


def table_markdown(rows: list[Table1Row], robot: str, teacher: str, pca: FitReport) -> str:
    full = next(r for r in rows if r.features == "full")
    lines = [
        f"Table I ({robot}, teacher {teacher}; test: held-out sets {list(pca.split.test)})",
        "",
        "| feature space | size | test RMSE dt [s] | paper | always-the-mean RMSE [s] "
        "| inference (normalised) | paper | NumPy [us/call] | PyTorch [us/call] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        paper_rmse, paper_t = PAPER[r.features]
        torch_us = "-" if r.torch_us_per_call is None else f"{r.torch_us_per_call:.1f}"
        lines.append(
            f"| {r.features} | R^{r.n_features} | {r.rmse_s:.2e} | {paper_rmse:.2e} "
            f"| {r.mean_predictor_rmse_s:.2e} | {r.numpy_us_per_call / full.numpy_us_per_call:.2f} "
            f"| {paper_t:.2f} | {r.numpy_us_per_call:.1f} | {torch_us} |"
        )
    lines += ["", f"PCA selection: {', '.join(pca.feature_names)}"]
    return "\n".join(lines) + "\n"


def _write_table(
    out: Path, rows: list[Table1Row], robot: str, teacher: str, pca: FitReport
) -> None:
    from gaitnet_mpc.results.io import write_atomic

    write_atomic(out / "table1.md", table_markdown(rows, robot, teacher, pca))
    header = ",".join(Table1Row.__dataclass_fields__)
    body = [",".join(str(getattr(r, f)) for f in Table1Row.__dataclass_fields__) for r in rows]
    write_atomic(out / "table1.csv", "\n".join([header, *body]) + "\n")
