"""The paper's 3-D humanoid figures (Figs. 7-11 and 1(e)), one results folder each.

:func:`reproduce_figure` runs the figure's episodes (``humanoid3d``, each a full run folder
under ``<out>/runs/<label>``, video included unless ``video=False``), reads them back with
:func:`~gaitnet_mpc.results.rundir.load_run` and writes ``<name>.png`` / ``<name>.svg``
(the figure in the paper's layout), ``<name>.csv`` (the plotted data) and ``<name>.md``
(our numbers beside the paper's number or claim, a verdict "holds" / "does not hold" with
its rule, the machine line and the wall time). No controller setting is changed for a
figure: every run uses the default settings, as ``gaitnet-mpc run`` would (with a cart,
Fig. 10, the arms hold the pushing pose, as ``run --cart-load-kg`` sets); ``kd`` runs at
the fixed dt of the README's headline ``kd`` row,
:data:`~gaitnet_mpc.experiments.figure_common.KD_DT_S`. A run that falls is reported with
its fall time, and its verdict is "does not hold".

One module per figure, each with its episodes, drawing, table and verdict rule in its
docstring: ``fig7`` (3-D stepping stones) :mod:`~gaitnet_mpc.experiments.figure_fig7`,
``fig8`` (spatial momenta) :mod:`~gaitnet_mpc.experiments.figure_fig8`, ``fig9`` (step
durations under disturbances) :mod:`~gaitnet_mpc.experiments.figure_fig9`, ``fig10``
(pushing a cart with an unknown load) :mod:`~gaitnet_mpc.experiments.figure_fig10`, ``fig11``
(velocity tracking over a 20 cm gap) :mod:`~gaitnet_mpc.experiments.figure_fig11` and
``obstacle`` (Fig. 1(e)) :mod:`~gaitnet_mpc.experiments.figure_obstacle`; what they share
(the episode runner, the report writer, the CSV columns :data:`CSV_FIELDS`) is in
:mod:`~gaitnet_mpc.experiments.figure_common`. This module is the one the CLI calls: the
figure names (:data:`FIGURES`), their files (:data:`ARTIFACTS`), the durations and
:func:`reproduce_figure`; it re-exports the figure modules' public names.

``quick=True``: :data:`QUICK_DURATION_S` of simulated time per episode and no video (all
six figures in about a minute on two cores; ``fig10`` skips its load search). The video
and the snapshot strip render offscreen: without a display, ``MUJOCO_GL=egl`` must be set
before MuJoCo is first imported (``gaitnet-mpc`` sets it). :func:`reproduce_figure` checks
``out`` but takes no lock on it: the caller (the CLI) holds the folder's lock, as it does
for ``table1`` and ``table2``; :data:`ARTIFACTS` lists what each figure writes there.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.experiments.figure_common import (
    CONTROLLER_COLORS,
    CSV_EVERY_TICKS,
    CSV_FIELDS,
    KD_DT_S,
    ROBOT,
    VX_MPS,
    VX_OBSTACLE_MPS,
    Log,
    Report,
    markdown,
)
from gaitnet_mpc.experiments.figure_fig7 import (
    REGION_COLORS,
    SNAPSHOT_PERIOD_S,
    build_fig7,
    com_region,
)
from gaitnet_mpc.experiments.figure_fig8 import (
    MOMENTA,
    NRMSE_MAX,
    build_fig8,
    momentum_pairs,
    prediction_errors,
)
from gaitnet_mpc.experiments.figure_fig9 import PAYLOAD_KG, PUSH, build_fig9
from gaitnet_mpc.experiments.figure_fig10 import (
    CART_LOAD_KG,
    HEADROOM_MAX,
    PUSH_DISTANCE_M,
    VX_CART_MPS,
    CartRecorder,
    build_fig10,
    largest_load,
)
from gaitnet_mpc.experiments.figure_fig11 import (
    RMSE_AFTER_S,
    SPEED_RMSE_MAX_MPS,
    build_fig11,
    ramped_command,
    speed_rmse,
)
from gaitnet_mpc.experiments.figure_obstacle import SOLE_SAMPLES, FootRecorder, build_obstacle
from gaitnet_mpc.results.io import write_atomic
from gaitnet_mpc.results.outdir import check_output_path
from gaitnet_mpc.runner.episode import VideoConfig

#: Figure name -> one line for ``--help``.
FIGURES: dict[str, str] = {
    "fig7": "humanoid over the 3-D stepping stones: snapshots, touchdowns, CoM regions (Fig. 7)",
    "fig8": "spatial momenta, measured vs MPC-predicted, gaitnet and kd (Fig. 8)",
    "fig9": "gaitnet's step durations under a push, a payload and uneven ground (Fig. 9)",
    "fig10": "pushing a cart with an unknown 35 kg load, srbm and gaitnet; largest load (Fig. 10)",
    "fig11": "x-velocity tracking over a 20 cm gap, gaitnet and kd (Fig. 11)",
    "obstacle": "over a 3 cm obstacle and a 15 cm hole at 0.5 and 0.75 m/s, obstacle known "
    "and unknown, then 20 seeded obstacle courses: swing-foot clearance (Fig. 1(e))",
}
_EXTRA = {
    "fig7": ("fig7_strip.png",), "fig10": ("fig10_loads.jsonl",), "obstacle": ("courses",),
}  # fmt: skip
#: What each figure writes into its folder (what an ``--overwrite`` may replace).
ARTIFACTS: dict[str, tuple[str, ...]] = {
    name: (f"{name}.md", f"{name}.csv", f"{name}.png", f"{name}.svg", "runs", *_EXTRA.get(name, ()))
    for name in FIGURES
}
#: Simulated time per episode [s], full and quick.
DURATION_S = {
    "fig7": 8.0, "fig8": 8.0, "fig9": 12.0, "fig10": 16.0, "fig11": 8.0, "obstacle": 8.0,
}  # fmt: skip
QUICK_DURATION_S = {
    "fig7": 2.5, "fig8": 2.5, "fig9": 2.0, "fig10": 2.5, "fig11": 3.0, "obstacle": 4.0,
}  # fmt: skip


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def reproduce_figure(
    name: str,
    out: Path,
    *,
    quick: bool = False,
    video: bool = True,
    log: Log = _stderr,
    config_file: Path | None = None,
) -> Path:
    """Run figure ``name``'s episodes and write its files into ``out``; return
    ``out / f"{name}.md"`` (module docstring).

    Args:
        quick: :data:`QUICK_DURATION_S` per episode, no video.
        video: write each run folder's ``video.mp4`` (no effect with ``quick``).
        log: called with one line per finished episode.
        config_file: a settings file for every run (``fig9`` only; as ``run --config``).

    Raises:
        ConfigError: ``name`` is not one of :data:`FIGURES` (field ``figure``), ``out``
            is not a folder path (field ``--out``), or ``config_file`` is given for a
            figure other than ``fig9`` (field ``--config``).
        KeyboardInterrupt: Ctrl-C / SIGTERM stopped an episode (the run folders written so
            far are kept; the figure files are not written).
    """
    if name not in FIGURES:
        raise ConfigError("figure", name, f"one of {sorted(FIGURES)}")
    out = check_output_path(Path(out), "--out")
    builder = _BUILDERS[name]
    if config_file is not None:
        if name != "fig9":
            raise ConfigError("--config", str(config_file), "a settings file for fig9 only")
        builder = partial(build_fig9, config_file=Path(config_file))
    t0 = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    duration = (QUICK_DURATION_S if quick else DURATION_S)[name]
    camera = VideoConfig() if video and not quick else None
    report = builder(out, duration, camera, log, quick)
    path = out / f"{name}.md"
    write_atomic(path, markdown(report, quick, duration, time.perf_counter() - t0))
    return path


_BUILDERS: dict[str, Callable[[Path, float, VideoConfig | None, Log, bool], Report]] = {
    "fig7": build_fig7,
    "fig8": build_fig8,
    "fig9": build_fig9,
    "fig10": build_fig10,
    "fig11": build_fig11,
    "obstacle": build_obstacle,
}

__all__ = [
    "ARTIFACTS",
    "CART_LOAD_KG",
    "CONTROLLER_COLORS",
    "CSV_EVERY_TICKS",
    "CSV_FIELDS",
    "DURATION_S",
    "FIGURES",
    "HEADROOM_MAX",
    "KD_DT_S",
    "MOMENTA",
    "NRMSE_MAX",
    "PAYLOAD_KG",
    "PUSH",
    "PUSH_DISTANCE_M",
    "QUICK_DURATION_S",
    "REGION_COLORS",
    "RMSE_AFTER_S",
    "ROBOT",
    "SNAPSHOT_PERIOD_S",
    "SOLE_SAMPLES",
    "SPEED_RMSE_MAX_MPS",
    "VX_CART_MPS",
    "VX_MPS",
    "VX_OBSTACLE_MPS",
    "CartRecorder",
    "FootRecorder",
    "Log",
    "com_region",
    "largest_load",
    "momentum_pairs",
    "prediction_errors",
    "ramped_command",
    "reproduce_figure",
    "speed_rmse",
]
