"""Which candidate dts survived, at the step starts where the dt decided the fall: from the
rollout oracle's records (``benchmarks/rollout_labels.py``), the step starts where some
candidates fell and others walked on, by the forward CoM velocity error to the command
at the step start, and per candidate dt the number that survived (issue 48, item 5).

    .venv/bin/python benchmarks/rollout_survival.py data/rollout-labels/episodes.jsonl \\
        data/rollout-labels/round2.jsonl data/rollout-labels/round5_retime.jsonl
"""

from __future__ import annotations

import argparse
import itertools
import json
from collections import defaultdict
from pathlib import Path

from gaitnet_mpc.dataset.schema import FEATURE_NAMES

#: Forward velocity error bins [m/s] (lower ends; the last is open).
EDGES_MPS = (-0.3, -0.1, 0.1, 0.3)


def survival_table(paths: list[Path]) -> str:
    vx = FEATURE_NAMES.index("com_vx_mps")
    bins: dict[int, dict[float, int]] = defaultdict(lambda: defaultdict(int))
    starts: dict[int, int] = defaultdict(int)
    total = 0
    for path in paths:
        for line in path.read_text().splitlines():
            rec = json.loads(line)
            for step in rec["steps"]:
                outcomes = step.get("outcomes") or {}
                total += bool(outcomes)
                fell = [o["fell"] for o in outcomes.values()]
                if all(fell) or not any(fell):
                    continue
                error = step["features"][0][vx] - rec["speed_mps"]
                b = sum(error >= e for e in EDGES_MPS)
                starts[b] += 1
                for dt, o in outcomes.items():
                    bins[b][round(float(dt), 4)] += not o["fell"]
    dts = sorted({dt for b in bins.values() for dt in b})
    names = [f"< {EDGES_MPS[0]:g}"]
    names += [f"{lo:g} to {hi:g}" for lo, hi in itertools.pairwise(EDGES_MPS)]
    names += [f">= {EDGES_MPS[-1]:g}"]
    lines = [
        "| forward velocity error [m/s] | step starts | "
        + " | ".join(f"{1000 * dt:g} ms" for dt in dts) + " |",
        "|---|---|" + "---|" * len(dts),
    ]  # fmt: skip
    for b, name in enumerate(names):
        cells = " | ".join(str(bins[b][dt]) for dt in dts)
        lines.append(f"| {name} | {starts[b]} | {cells} |")
    all_cells = " | ".join(str(sum(bins[b][dt] for b in bins)) for dt in dts)
    lines.append(f"| all | {sum(starts.values())} | {all_cells} |")
    lines.append("")
    lines.append(
        f"{sum(starts.values())} of {total} examined step starts had candidates that fell "
        "and candidates that survived; each cell counts the survivors of that dt."
    )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("records", type=Path, nargs="+")
    print(survival_table(ap.parse_args().records))


if __name__ == "__main__":
    main()
