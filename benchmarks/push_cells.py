"""Issue 48's push lines from push-sweep records: per controller the weakest cell and the
mean, in how many cells the first controller survives at least each other one and at
least the best of the others, the ratio of the weakest cells (the issue asks 1.3), and the
issue's absolute floors (100 N forward and backward, 50 N elsewhere).

Each ``--sweep LABEL=PATH[:CONTROLLER]`` names a sweep's ``cases.jsonl`` and, if it holds
several controllers, which one. The first is the one compared.

    .venv/bin/python benchmarks/push_cells.py \\
        --sweep gaitnet=benchmarks/results/sweep_push_scan/gaitnet/cases.jsonl \\
        --sweep kd@0.045=benchmarks/results/sweep_push_scan/kd045/cases.jsonl
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from gaitnet_mpc.experiments.sweep_cases import DIRECTIONS

Cells = dict[tuple[str, float], float]


def load_cells(path: Path, controller: str | None) -> Cells:
    """(direction, phase) -> survived force [N] (0 where the unpushed run fell)."""
    cells: Cells = {}
    for line in path.read_text().splitlines():
        record = json.loads(line)
        case = record.get("case")
        if case is None or (controller is not None and case["controller"] != controller):
            continue
        survived = record["result"]["survived"]
        cells[case["direction"], case["phase"]] = 0.0 if survived is None else survived
    return cells


def floor_n(direction: str) -> float:
    return 100.0 if direction in ("fwd", "bwd") else 50.0


def report(sweeps: dict[str, Cells]) -> str:
    labels = list(sweeps)
    first, others = labels[0], labels[1:]
    mine = sweeps[first]
    keys = [k for k in mine if all(k in sweeps[o] for o in others)]
    lines = ["| controller | cells | weakest [N] | mean [N] | cells where "
             f"`{first}` >= it | `{first}`'s weakest / its weakest |",
             "|---|---|---|---|---|---|"]  # fmt: skip
    weakest = min(mine[k] for k in keys)
    for label in labels:
        vals = [sweeps[label][k] for k in keys]
        ge = sum(mine[k] >= sweeps[label][k] for k in keys)
        ratio = weakest / min(vals) if min(vals) > 0 else float("inf")
        lines.append(
            f"| `{label}` | {len(vals)} | {min(vals):g} | {sum(vals) / len(vals):.1f} | "
            + ("| |" if label == first else f"{ge}/{len(keys)} | {ratio:.2f} |")
        )
    if others:
        best = sum(mine[k] >= max(sweeps[o][k] for o in others) for k in keys)
        lines.append("")
        lines.append(f"`{first}` at least the best of the others: {best}/{len(keys)} cells.")
    order = list(DIRECTIONS)
    by_cell = sorted(keys, key=lambda k: (k[1], order.index(k[0])))
    if others:
        short = []
        for d, p in by_cell:
            top = max(others, key=lambda o: sweeps[o][d, p])
            if mine[d, p] < sweeps[top][d, p]:
                short.append(f"{d} p{p:g} {mine[d, p]:g} < {sweeps[top][d, p]:g} N (`{top}`)")
        lines.append("Below the best of the others: " + (", ".join(short) or "none") + ".")
    below = [k for k in by_cell if mine[k] < floor_n(k[0])]
    lines.append(
        f"Below the floor (100 N fwd / bwd, 50 N elsewhere): {len(below)}/{len(keys)} cells"
        + ("" if not below else ": " + ", ".join(f"{d} p{p:g} {mine[d, p]:g} N" for d, p in below))
        + "."
    )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sweep", action="append", required=True, metavar="LABEL=PATH[:CTRL]")
    args = ap.parse_args()
    sweeps: dict[str, Cells] = {}
    for spec in args.sweep:
        label, _, rest = spec.partition("=")
        path, _, controller = rest.partition(":")
        sweeps[label] = load_cells(Path(path), controller or None)
    print(report(sweeps))


if __name__ == "__main__":
    main()
