"""What the benchmark scripts share: the machine and version line, one process pool, one
report writer, the command line that made a report, and what counts as a clean run.

Every closed-loop episode is a scenario (:func:`gaitnet_mpc.scenario.make_scenario`,
:func:`~gaitnet_mpc.scenario.run_scenario`, or :func:`~gaitnet_mpc.scenario.build_episode`
for a script that needs the controller's internals). Before/after timing against a git
revision is ``gaitnet-mpc bench --baseline REV``. Scripts import this module as
``from common import ...`` (Python puts the script's folder on ``sys.path``).
"""

from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys
import time
import traceback
from collections.abc import Callable, Hashable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

RESULTS = Path(__file__).resolve().parent / "results"
ROOT = RESULTS.parent.parent

__all__ = [
    "JobFailed",
    "add_out_option",
    "clean_run",
    "command_line",
    "git_state",
    "machine_info",
    "run_pool",
    "write_report",
]


class JobFailed(RuntimeError):
    """A job of :func:`run_pool` raised; the message names the job."""


def clean_run(summary: dict[str, Any]) -> bool:
    """A run's summary counts as clean in the success-rate reports: no fall, no foothold
    violation and no leg-leg contact."""
    no_contact = not summary["self_collisions"]  # a tick count, or None without any
    return not summary["fell"] and summary["foothold_violations"] == 0 and no_contact


def git_state() -> str:
    """The working tree's commit, and whether tracked files differ from it."""

    def git(*args: str) -> str:
        proc = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True)
        return proc.stdout.strip()

    try:
        head = git("rev-parse", "--short", "HEAD")
        dirty = git("status", "--porcelain", "--untracked-files=no")
    except OSError:
        head = dirty = ""
    if not head:
        return "commit unknown"
    return f"commit {head}" + (" with uncommitted changes to tracked files" if dirty else "")


def machine_info(packages: tuple[str, ...] = ("numpy", "mujoco", "pin")) -> str:
    """One line: CPU, cores, Python, the versions of ``packages`` (as
    :func:`gaitnet_mpc.machine.machine_info`), the CPU model and the git commit."""
    from gaitnet_mpc.machine import machine_info as versions

    parts = [versions(packages)]
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        models = [ln for ln in cpuinfo.read_text().splitlines() if ln.startswith("model name")]
        parts += [f"CPU model: {models[0].split(':', 1)[1].strip()}"] if models else []
    return ", ".join([*parts, git_state()])


def command_line() -> str:
    """The command that is running, as one would type it in the repository root."""
    argv = [os.path.relpath(sys.executable, ROOT), os.path.relpath(sys.argv[0], ROOT)]
    gl = os.environ.get("MUJOCO_GL")
    return (f"MUJOCO_GL={gl} " if gl else "") + shlex.join([*argv, *sys.argv[1:]])


def add_out_option(parser: argparse.ArgumentParser, default: str) -> None:
    """``--out``: the report's name in ``benchmarks/results`` or a path elsewhere."""
    parser.add_argument(
        "--out", default=default, help=f"report: a name in benchmarks/results or a path ({default})"
    )


def write_report(name: str | Path, text: str, *, echo: bool = True) -> Path:
    """Write ``text`` atomically to ``benchmarks/results/<name>`` (a path with a folder:
    there), print it unless ``echo`` is False, and return the path."""
    from gaitnet_mpc.results.io import write_atomic

    path = Path(name) if Path(name).parent != Path() else RESULTS / name
    write_atomic(path, text)
    if echo:
        print(text)
    print(f"wrote {path}", file=sys.stderr)
    return path


def _call(fn: Callable[[Any], Any], job: Any) -> Any:
    """``fn(job)`` in a worker; an exception comes back as a :class:`JobFailed` carrying the
    worker's traceback (the package's exceptions with several arguments, such as
    ``ConfigError``, do not survive pickling and would break the pool instead)."""
    try:
        return fn(job)
    except Exception as exc:
        raise JobFailed(f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}") from None


def run_pool(
    fn: Callable[[Any], Any],
    jobs: Sequence[Hashable],
    workers: int,
    *,
    describe: Callable[[Any, Any], str] | None = None,
    keep_errors: bool = False,
) -> dict[Any, Any]:
    """``{job: fn(job)}`` over ``workers`` spawn processes
    (:func:`gaitnet_mpc.parallel.run_processes`), in the order of ``jobs``.

    Each finished job prints a line on stderr: ``[n/N] describe(job, result)`` (default:
    the job). A job that raises stops the pool with :class:`JobFailed` naming it; with
    ``keep_errors`` its value is the exception and the others go on. ``fn`` must be a
    module-level function (or a ``functools.partial`` of one).
    """
    from gaitnet_mpc.parallel import run_processes

    done: dict[Any, Any] = {}
    t0 = time.perf_counter()
    for n, out in enumerate(run_processes(partial(_call, fn), list(jobs), workers), 1):
        if out.error is not None:
            message = f"job {out.item!r} failed: {out.error}"
            if not keep_errors:
                raise JobFailed(message) from None
            done[out.item], text = out.error, message
        else:
            done[out.item] = out.result
            text = describe(out.item, out.result) if describe else repr(out.item)
        elapsed = time.perf_counter() - t0
        print(f"[{n}/{len(jobs)}] {text} ({elapsed:.0f} s)", file=sys.stderr, flush=True)
    return {job: done[job] for job in jobs}
