"""What the benchmark scripts share: the machine and version header, one process pool, one
report writer, and what counts as a clean run. Every episode is a scenario
(:func:`gaitnet_mpc.scenario.make_scenario`, :func:`~gaitnet_mpc.scenario.run_scenario`);
before/after timing against a git revision is ``gaitnet-mpc bench --baseline REV``."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from gaitnet_mpc.machine import machine_info

__all__ = ["clean_run", "machine_info", "run_pool", "write_report"]


def clean_run(summary: dict[str, Any]) -> bool:
    """A run's ``summary.json`` counts as clean in the success-rate reports: no fall, no
    foothold violation and no leg-leg contact."""
    no_contact = not summary["self_collisions"]  # a tick count, or None without any
    return not summary["fell"] and summary["foothold_violations"] == 0 and no_contact


def write_report(name: str, report: str) -> None:
    """Write ``report`` to ``benchmarks/results/<name>`` atomically (a path with a folder:
    there) and print it."""
    from gaitnet_mpc.results.io import write_atomic

    path = Path(name) if Path(name).parent != Path() else Path(__file__).parent / "results" / name
    write_atomic(path, report)
    print(report)


def run_pool(fn: Callable[..., Any], jobs: list[Any], workers: int) -> dict[Any, Any]:
    """``{job: fn(job)}`` over a process pool of ``workers``, counting finished jobs on
    stderr."""
    from concurrent.futures import ProcessPoolExecutor, as_completed

    results = {}
    with ProcessPoolExecutor(workers) as pool:
        futures = {pool.submit(fn, job): job for job in jobs}
        for n, fut in enumerate(as_completed(futures), 1):
            try:
                results[futures[fut]] = fut.result()
            except Exception as exc:
                raise RuntimeError(f"job {futures[fut]!r} failed: {exc!r}") from exc
            print(f"\r{n}/{len(jobs)} episodes", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return results
