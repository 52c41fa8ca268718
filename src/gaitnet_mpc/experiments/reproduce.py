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


def table2(
    out: Path,
    problems: int,
    *,
    with_joint_space: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Table II: the solvers on the same recorded MPC problems (``problems`` of them)."""
    from gaitnet_mpc.table2.run import reproduce_table2

    if problems < 1:
        raise ConfigError("--problems", problems, "an integer >= 1")
    return reproduce_table2(out, problems, progress=progress, with_joint_space=with_joint_space)


#: What ``gaitnet-mpc reproduce`` knows, with a line each for ``--help``.
REPRODUCIBLE = {
    "table1": "Gait-Net feature spaces (Table I)",
    "table2": "solvers on the same MPC problems (Table II)",
}
