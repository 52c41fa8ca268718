"""The soak itself (:func:`soak`): the episodes not yet done run on a spawn process pool or
as Ray tasks, each finished one is appended to the resumable episode log, and the report is
written at the end, also after Ctrl-C / SIGTERM.

The log is ``<work-dir>/<report stem>.episodes.jsonl`` (:attr:`SoakOptions.jsonl`): a first
line with the draw settings (resuming with other settings is refused), then one record per
finished episode, flushed and fsync'ed line by line; a torn last line is ignored.
Re-running the same command skips the episodes it holds.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Generator
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gaitnet_mpc.experiments.soak.draw import DrawSettings, EpisodeSpec, draw_episode
from gaitnet_mpc.experiments.soak.report import make_report
from gaitnet_mpc.experiments.soak.worker import run_spec, worker_died_record
from gaitnet_mpc.parallel import Outcome, run_processes, run_ray, stop_signals_as_keyboard_interrupt

RESULTS = Path("benchmarks") / "results"  # of the repository the script runs in


def _records(
    outcomes: Generator[Outcome[dict[str, Any], dict[str, Any]], None, None],
) -> Generator[dict[str, Any], None, None]:
    """The episodes' records: :func:`run_spec`'s, or :func:`worker_died_record`'s for an episode
    whose worker died (any other error, e.g. a spec that cannot be sent, stops the soak).
    Closing this generator closes ``outcomes`` (which stops the workers)."""
    with closing(outcomes):
        for outcome in outcomes:
            if outcome.worker_died and outcome.error is not None:
                yield worker_died_record(EpisodeSpec.from_dict(outcome.item), outcome.error)
            else:
                yield outcome.get()


def _runs(options: SoakOptions, specs: list[EpisodeSpec]) -> Generator[dict[str, Any], None, None]:
    """Records of ``specs`` from a spawn process pool or Ray tasks (as ``gaitnet-mpc
    collect`` runs its sets), at most ``options.workers`` episodes in flight (so a dead
    worker is blamed on at most that many episodes, and the pool is started again)."""
    items = [spec.to_dict() for spec in specs]
    if options.backend == "ray":
        return _records(run_ray(run_spec, items, options.workers, options.address, max_retries=0))
    return _records(run_processes(run_spec, items, options.workers))


def _read_records(path: Path, settings: DrawSettings) -> dict[int, dict[str, Any]]:
    """The finished episodes in ``path`` (a torn last line is ignored)."""
    from gaitnet_mpc.errors import ConfigError

    if not path.exists():
        return {}
    records: dict[int, dict[str, Any]] = {}
    for line in path.read_text().splitlines():
        try:
            item = json.loads(line)
        except json.JSONDecodeError:
            continue  # a line cut by a kill during the write
        if "soak_settings" in item:
            if item["soak_settings"] != settings.to_dict():
                raise ConfigError(
                    "--work-dir",
                    str(path),
                    f"episodes of the same settings (it holds {item['soak_settings']}); "
                    "use another --work-dir or --out",
                )
            continue
        records[int(item["index"])] = item
    return records


@dataclass(frozen=True)
class SoakOptions:
    """How to run a soak (not part of its identity).

    Attributes:
        episodes: number of episodes (indices 0..episodes-1).
        workers: parallel episodes.
        backend: ``"process"`` or ``"ray"``.
        out: report path.
        work_dir: folder of the episodes' JSONL (None: the report's folder).
        address: Ray cluster address (None: a local Ray instance).
    """

    episodes: int
    workers: int = 1
    backend: str = "process"
    out: Path = RESULTS / "soak.md"
    work_dir: Path | None = None
    address: str | None = None

    def __post_init__(self) -> None:
        from gaitnet_mpc.errors import ConfigError
        from gaitnet_mpc.experiments.collect import CollectOptions

        if not (isinstance(self.episodes, int) and self.episodes >= 1):
            raise ConfigError("--episodes", self.episodes, "an integer >= 1")
        CollectOptions(self.workers, self.backend, self.address)  # the same checks

    @property
    def jsonl(self) -> Path:
        folder = self.out.parent if self.work_dir is None else self.work_dir
        return folder / f"{self.out.stem}.episodes.jsonl"


def soak(
    options: SoakOptions,
    settings: DrawSettings,
    command_line: str = "",
    log: Callable[[str], None] = print,
) -> dict[int, dict[str, Any]]:
    """Run the episodes of ``settings`` not yet in the JSONL, write the report, return all
    finished episodes' records. Ctrl-C / SIGTERM stops early and still writes the report."""
    from gaitnet_mpc.results.io import append_json_line, write_atomic

    path = options.jsonl
    records = _read_records(path, settings)
    if not path.exists():
        append_json_line(path, {"soak_settings": settings.to_dict()})
    todo = [draw_episode(settings, i) for i in range(options.episodes) if i not in records]
    log(
        f"{len(todo)} of {options.episodes} episodes to run ({len(records)} already in {path}), "
        f"{options.workers} worker(s), backend {options.backend}"
    )
    runs = _runs(options, todo)
    t0 = time.perf_counter()
    interrupted = False
    try:
        with stop_signals_as_keyboard_interrupt():
            for n, record in enumerate(runs, 1):
                append_json_line(path, record)
                records[record["index"]] = record
                log(_episode_line(record, n, len(todo)))
    except KeyboardInterrupt:
        interrupted = True
        log(f"interrupted: {len(records)} of {options.episodes} episodes are in {path}")
    finally:
        runs.close()  # stops the workers now, not when the generator is collected
    report = make_report(
        records, settings, options.episodes, command_line, time.perf_counter() - t0, interrupted
    )
    write_atomic(options.out, report)
    log(f"wrote {options.out}")
    return records


def _episode_line(r: dict[str, Any], n: int, total: int) -> str:
    spec = EpisodeSpec.from_dict(r["spec"])
    if r["exception"] is not None:
        outcome = f"{r['exception']['type']}: {r['exception']['message'][:120]}"
    elif r["diverged"]:
        outcome = f"DIVERGED ({r['fall_reason']})"
    elif r["fell"]:
        outcome = f"fell ({r['fall_reason']})"
    else:
        outcome = "ok"
    extra = f", {r['qp_failures']} QP failure(s)" if r["qp_failures"] else ""
    wall = "?" if r["wall_s"] is None else f"{r['wall_s']:.1f}"
    return f"[{n}/{total}] #{spec.index} {spec.label()}: {outcome}{extra}, {wall} s wall"
