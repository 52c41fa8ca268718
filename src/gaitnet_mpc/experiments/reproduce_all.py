"""``gaitnet-mpc reproduce all``: every table and figure of the paper, then one document.

Each item (:data:`ITEMS`: Tables I and II, Figs. 6-11 and 1(e)) runs into its own
folder ``<out>/<name>`` through :mod:`~gaitnet_mpc.experiments.reproduce`, in the order
of :data:`ITEMS`. An item whose report (``<out>/<name>/<name>.md``) exists is not run
again, so an interrupted run resumes where it stopped (and Table II and Fig. 6, resumable
themselves, resume inside the item). Then :func:`write_document` writes
``<out>/reproduction.md``: one section per table and figure of the paper in the paper's
order, each with its images, the item's report (our numbers beside the paper's, and the
verdicts) and, for what has no command of its own (Fig. 4, drawn by Table I), where it is.

``quick``: each item's quick form (Table I: one net per feature space, 20 epochs; Table II:
:data:`QUICK_TABLE2_PROBLEMS` problems without the joint-space columns; the figures'
``quick``), a check that everything runs and is written, not the paper's experiments; the
full run's numbers are in ``benchmarks/results/`` and ``docs/reproduction.md``.
"""

from __future__ import annotations

import re
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from gaitnet_mpc.experiments import reproduce
from gaitnet_mpc.results.io import write_atomic

#: Problems of Table II: the full run's (all five columns on the first 100) and quick's.
TABLE2_PROBLEMS = 100
QUICK_TABLE2_PROBLEMS = 1  # a flat one: recording a stepping-stones one walks 30 s
#: The data set Table I is trained on (the paper's teacher, the whole-body NMPC).
TABLE1_DATA = Path("data/gaitnet-wbmpc-humanoid3d")


@dataclass(frozen=True)
class Section:
    """One section of ``reproduction.md``: a table or figure of the paper.

    Attributes:
        title: the section's heading.
        item: the :data:`ITEMS` name whose report it shows; None: no command yet.
        images: image files of the item's folder shown above its report.
        missing: why it cannot be reproduced yet (``item`` None).
    """

    title: str
    item: str | None
    images: tuple[str, ...] = ()
    missing: str = ""


#: What ``reproduce all`` runs, in this order.
ITEMS = reproduce.ALL_ITEMS
#: The document's sections, in the paper's order.
SECTIONS = (
    Section("Table I: Gait-Net feature spaces", "table1", ("fig4.png",)),
    Section("Fig. 4: PCA feature selection", None, (),
            "drawn by Table I: `table1/fig4.png` (above)"),
    Section("Table II: solvers on the same MPC problems", "table2"),
    Section("Fig. 6: the 2-D biped over 5-15 cm gaps", "fig6", ("fig6.png",)),
    Section("Fig. 7: 3-D stepping stones", "fig7", ("fig7.png", "fig7_strip.png")),
    Section("Fig. 8: spatial momenta, measured and predicted", "fig8", ("fig8.png",)),
    Section("Fig. 9: step durations under disturbances", "fig9", ("fig9.png",)),
    Section("Fig. 10: pushing a cart with an unknown load", "fig10", ("fig10.png",)),
    Section("Fig. 11: velocity tracking over a 20 cm gap", "fig11", ("fig11.png",)),
    Section("Fig. 1(e): an obstacle, then a gap", "obstacle", ("obstacle.png",)),
)  # fmt: skip

Log = Callable[[str], None]


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def run_item(name: str, folder: Path, quick: bool, video: bool) -> Path:
    """Run one item into ``folder``; return its report."""
    if name == "table1":
        from gaitnet_mpc.gaitnet.table1 import reproduce_table1
        from gaitnet_mpc.gaitnet.train import TrainConfig

        config = TrainConfig(members=1, epochs=20, patience=5) if quick else None
        reproduce_table1(TABLE1_DATA, folder, config)
        return folder / "table1.md"
    if name == "table2":
        n = QUICK_TABLE2_PROBLEMS if quick else TABLE2_PROBLEMS
        return reproduce.table2(folder, n, with_joint_space=not quick)
    if name == "fig6":
        return reproduce.fig6(folder, quick=quick, progress=False, workers=2)
    return reproduce.figure(folder, name, quick=quick, video=video)


def reproduce_all(
    out: Path, *, quick: bool = False, video: bool = True, log: Log = _stderr
) -> Path:
    """Every item of :data:`ITEMS` into ``out/<name>`` (skipping those with a report),
    then ``out/reproduction.md``; returns its path (module docstring).

    Raises:
        KeyboardInterrupt: an item was interrupted (the finished ones are kept).
    """
    out.mkdir(parents=True, exist_ok=True)
    for name in ITEMS:
        folder = out / name
        if (folder / f"{name}.md").is_file():
            log(f"{name}: done earlier ({folder / name}.md)")
            continue
        t0 = time.perf_counter()
        log(f"{name}: running{' (quick)' if quick else ''} ...")
        run_item(name, folder, quick, video)
        log(f"{name}: done in {time.perf_counter() - t0:.0f} s")
    path = out / "reproduction.md"
    write_atomic(path, write_document(out, quick))
    return path


def _demote(markdown: str) -> str:
    """The report with its headings one level down and its title line dropped."""
    lines = markdown.splitlines()
    if lines and lines[0].startswith("# "):
        lines = lines[1:]
    return "\n".join(re.sub(r"^(#+) ", r"#\1# ", line) for line in lines).strip()


def write_document(out: Path, quick: bool) -> str:
    """The text of ``reproduction.md`` from the reports under ``out``."""
    mode = (
        "quick runs: a check that every item runs and writes its files, not the paper's experiments"
        if quick
        else "the full runs"
    )
    parts = [
        "# Reproduction: every table and figure of the paper",
        "",
        f"Written by `gaitnet-mpc reproduce all{' --quick' if quick else ''}` ({mode}). Each "
        "section shows the item's images and its report from `<name>/<name>.md`: our "
        "numbers, the paper's, and a verdict (holds / does not hold) with its rule.",
    ]
    for sec in SECTIONS:
        parts += ["", f"## {sec.title}", ""]
        if sec.item is None:
            parts.append(f"Not reproduced by a command of its own: {sec.missing}.")
            continue
        report = out / sec.item / f"{sec.item}.md"
        if not report.is_file():
            parts.append(f"Not run: `{sec.item}/{sec.item}.md` is missing.")
            continue
        images = [f"{sec.item}/{i}" for i in sec.images]
        parts += [f"![{i}]({i})" for i in images if (out / i).is_file()]
        parts += ["", _demote(report.read_text())]
    return "\n".join(parts) + "\n"


__all__ = ["ITEMS", "SECTIONS", "Section", "reproduce_all", "run_item", "write_document"]
