"""``gaitnet-mpc compare RUN_DIR ...``: one figure and one table over several runs."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

SUMMARY = "compare several run folders (figure + table)"


def add_parser(sub: Any) -> None:
    compare = sub.add_parser("compare", help=SUMMARY)
    compare.add_argument("run_dirs", type=Path, nargs="+", metavar="RUN_DIR")
    compare.add_argument(
        "--out", default=None, help="output folder (default runs/compare-<time>-<id>)"
    )


def main(args: argparse.Namespace) -> int:
    import sys

    from gaitnet_mpc.results.compare import compare_runs
    from gaitnet_mpc.results.outdir import claim_output_folder
    from gaitnet_mpc.results.rundir import COMPARE_ARTIFACTS, load_run

    _check_distinct(args.run_dirs)
    runs = [load_run(p) for p in args.run_dirs]  # every input is checked before --out
    with claim_output_folder(
        args.out,
        option="--out",
        default_prefix="compare-",
        artifacts=COMPARE_ARTIFACTS,
        overwrite=True,  # a comparison is cheap to remake; its own files are replaced
    ) as out:
        result = compare_runs(runs, out)
    for text in result["warnings"]:
        print(f"gaitnet-mpc: warning: {text}", file=sys.stderr)
    print(result["markdown"].read_text(), end="")
    print(f"results in {out}/")
    return 0


def _check_distinct(run_dirs: list[Path]) -> None:
    """Each run folder once: a run compared with itself is a mistake in the command."""
    from gaitnet_mpc.errors import ConfigError

    seen: dict[Path, Path] = {}
    for path in run_dirs:
        key = path.resolve()
        if key in seen:
            first = seen[key]
            same = "it is given twice" if path == first else f"it is the same folder as {first}"
            raise ConfigError("RUN_DIR", str(path), f"a different run folder each time ({same})")
        seen[key] = path
