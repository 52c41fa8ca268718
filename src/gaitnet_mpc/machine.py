"""One line naming the machine and package versions, for every results file."""

from __future__ import annotations

import os
import platform
from importlib.metadata import PackageNotFoundError, version


def machine_info(packages: tuple[str, ...] = ("numpy", "mujoco", "pin")) -> str:
    """CPU, core count, Python and the versions of ``packages`` (Markdown-ready)."""
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
