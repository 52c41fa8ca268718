"""Machine and version header shared by the benchmark reports."""

from __future__ import annotations

import os
import platform
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path


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
