"""Machine and version header shared by the benchmark reports."""

from __future__ import annotations

import os
import platform
import sys
from collections.abc import Callable
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any


def machine_info(packages: tuple[str, ...] = ("numpy", "mujoco", "pin")) -> str:
    """One Markdown line naming the CPU, core count, Python and package versions."""
    parts = [
        f"CPU: {platform.processor() or platform.machine()}",
        f"cores: {os.cpu_count()}",
        f"Python {platform.python_version()}",
    ]
    for name in packages:
        try:
            parts.append(f"{name} {version(name)}")
        except PackageNotFoundError:
            parts.append(f"{name} (not installed)")
    return ", ".join(parts)


def write_report(name: str, report: str) -> None:
    """Write ``report`` to ``benchmarks/results/<name>`` atomically and print it."""
    from gaitnet_mpc.results.io import write_atomic

    write_atomic(Path(__file__).parent / "results" / name, report)
    print(report)


def run_pool(fn: Callable[..., Any], jobs: list[Any], workers: int) -> dict[Any, Any]:
    """``{job: fn(job)}`` over a process pool of ``workers``, counting finished jobs on
    stderr."""
    from concurrent.futures import ProcessPoolExecutor, as_completed

    results = {}
    with ProcessPoolExecutor(workers) as pool:
        futures = {pool.submit(fn, job): job for job in jobs}
        for n, fut in enumerate(as_completed(futures), 1):
            results[futures[fut]] = fut.result()
            print(f"\r{n}/{len(jobs)} episodes", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return results
