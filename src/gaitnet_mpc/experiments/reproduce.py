"""The paper's tables and figures, one function each: name -> what writes it.

Each writes its results into a folder and returns the Markdown report it wrote, so that
``gaitnet-mpc reproduce NAME`` can print it.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from gaitnet_mpc.errors import ConfigError


def table1(data_dir: Path, out: Path) -> Path:
    """Table I: Gait-Net's test error over feature spaces, on the data set ``data_dir``."""
    from gaitnet_mpc.gaitnet.table1 import reproduce_table1

    reproduce_table1(data_dir, out)
    return out / "table1.md"


def check_problems(problems: int) -> None:
    """``--problems`` of table2: an integer in [1, :data:`MAX_PROBLEMS`]."""
    if not (isinstance(problems, int) and 1 <= problems <= MAX_PROBLEMS):
        raise ConfigError("--problems", problems, f"an integer in [1, {MAX_PROBLEMS}]")


def table2(
    out: Path,
    problems: int,
    *,
    with_joint_space: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Table II: the solvers on the same recorded MPC problems (``problems`` of them)."""
    from gaitnet_mpc.table2.run import reproduce_table2

    check_problems(problems)
    return reproduce_table2(out, problems, progress=progress, with_joint_space=with_joint_space)


def fig6(
    out: Path,
    *,
    quick: bool = False,
    seeds: int | None = None,
    first_seed: int = 0,
    gaitnet_weights: str | None = None,
    workers: int = 1,
    backend: str = "process",
    address: str | None = None,
    progress: bool = True,
    command_line: str = "",
) -> Path:
    """Fig. 6: the 2-D biped over gaps of 5-15 cm with a fixed, an optimised and a
    Gait-Net dt (:mod:`~gaitnet_mpc.experiments.fig6`); resumes an interrupted run."""
    from dataclasses import replace

    from gaitnet_mpc.experiments.fig6 import Options, reproduce_fig6
    from gaitnet_mpc.experiments.fig6_cases import Fig6Settings

    settings = Fig6Settings.quick_settings() if quick else Fig6Settings()
    if seeds is not None:
        settings = replace(settings, seeds=seeds)
    settings = replace(settings, first_seed=first_seed, gaitnet_weights=gaitnet_weights)
    options = Options(workers=workers, backend=backend, address=address, progress=progress)
    reproduce_fig6(out, settings, options, command_line)
    return out / "fig6.md"


def figure(
    out: Path,
    name: str,
    *,
    quick: bool = False,
    video: bool = True,
    config_file: Path | None = None,
) -> Path:
    """Figs. 7-11 and 1(e) (``obstacle``): the humanoid's figures
    (:mod:`~gaitnet_mpc.experiments.paper_figures`); ``config_file``: fig9's settings."""
    from gaitnet_mpc.experiments.paper_figures import reproduce_figure

    return reproduce_figure(name, out, quick=quick, video=video, config_file=config_file)


def _figure_artifacts() -> dict[str, tuple[str, ...]]:
    from gaitnet_mpc.experiments.paper_figures import ARTIFACTS as FIGURE_ARTIFACTS

    return dict(FIGURE_ARTIFACTS)


def _figure_names() -> dict[str, str]:
    from gaitnet_mpc.experiments.paper_figures import FIGURES

    return dict(FIGURES)


#: The files each one writes into its folder (what ``--overwrite`` may replace; a table2
#: folder with its own files is resumed, not refused).
ARTIFACTS: dict[str, tuple[str, ...]] = {
    "table1": ("table1.md", "table1.csv", "fig4.png", "full", "pca"),
    "table2": ("problems.npz", "problems.tmp.npz", "records.jsonl", "table2.md", "table2.md.tmp"),
    "fig6": (
        "cases.jsonl", "courses", "errors.log", "fig6.md", "fig6.csv", "fig6.png",
        "strip_kd.png", "strip_kd-optdt.png", "strip_gaitnet.png",
    ),
    **_figure_artifacts(),
}  # fmt: skip
#: What ``reproduce all`` (:mod:`~gaitnet_mpc.experiments.reproduce_all`) runs, in this
#: order, each into a folder of its name.
ALL_ITEMS = ("table1", "table2", "fig6", "fig7", "fig8", "fig9", "fig10", "fig11", "obstacle")
ARTIFACTS["all"] = (*ALL_ITEMS, "reproduction.md")
#: The ones that resume from what an earlier, interrupted run left in the folder.
RESUMABLE = frozenset({"table2", "fig6", "fig10", "all"})
#: Most recorded problems of table2 (the paper's table is over 100; each is ~1 s to record).
MAX_PROBLEMS = 10_000

#: What ``gaitnet-mpc reproduce`` knows, with a line each for ``--help``.
REPRODUCIBLE = {
    "table1": "Gait-Net feature spaces (Table I)",
    "table2": "solvers on the same MPC problems (Table II)",
    "fig6": "2-D biped over 5-15 cm gaps: fixed, optimised and Gait-Net dt (Fig. 6)",
    **_figure_names(),
    "all": "every table and figure above, then reproduction.md (resumable)",
}
#: The humanoid's figures (:func:`figure`).
FIGURES = frozenset(_figure_names())
