"""``gaitnet-mpc sweep``: robustness benchmarks as one resumable command.

One mode per run (:data:`~gaitnet_mpc.experiments.sweep_cases.MODES`: ``push``,
``protocol``, ``payload``, ``terrain``; what each measures is in
:mod:`~gaitnet_mpc.experiments.sweep_cases`). Each case (one bisection, or one episode)
is one item on a spawn process pool or on Ray (:mod:`gaitnet_mpc.parallel`), as
``collect`` runs its sets.

The folder ``--out`` holds:

* ``cases.jsonl``: the sweep's settings (first line), then one line per finished case,
  flushed and fsync'ed line by line (a torn last line is ignored). The same command run
  again skips the finished cases; a folder of other settings is refused before any work.
* ``sweep.csv`` (one row per case), ``sweep.md`` (tables, machine and versions, command,
  wall time), ``push_polar.png`` (``push``), :mod:`~gaitnet_mpc.experiments.sweep_report`.
* ``status.json`` (:func:`~gaitnet_mpc.results.outdir.write_status`): the cases done and
  left; ``errors.log``: each case whose worker raised or died, with its traceback (the
  sweep goes on, then ends with :class:`~gaitnet_mpc.errors.PartialFailure`, exit 3).
* ``courses/`` (``terrain``): the ``uneven`` course files of each amplitude and seed.

Ctrl-C / SIGTERM stops the workers, writes the files of what was finished and re-raises
(exit 130); the same command resumes.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable, Generator
from contextlib import closing
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Protocol

from gaitnet_mpc.errors import ConfigError, GaitNetMPCError, PartialFailure
from gaitnet_mpc.experiments.collect import CollectOptions
from gaitnet_mpc.experiments.sweep_cases import (
    DIRECTIONS,
    MODES,
    ModePlan,
    make_cases,
    mode_plan,
    parse_controller,
    run_case,
    uneven_file_name,
)
from gaitnet_mpc.experiments.sweep_report import csv_text, markdown, push_polar
from gaitnet_mpc.parallel import Outcome, run_processes, run_ray, stop_signals_as_keyboard_interrupt
from gaitnet_mpc.results.io import append_failure, append_json_line, write_atomic
from gaitnet_mpc.results.outdir import check_output_path, folder_lock, write_status

CASES = "cases.jsonl"
ERRORS_LOG = "errors.log"
CSV = "sweep.csv"
REPORT = "sweep.md"
POLAR = "push_polar.png"
DEFAULT_CONTROLLERS = ("gaitnet", "kd", "srbm")
#: The one controller of ``--quick`` (the cheapest walker) unless ``--controllers`` is given.
QUICK_CONTROLLER = "srbm"
DEFAULT_SEEDS = 10

Options = CollectOptions  # workers, backend, address, progress: the same checks as collect


@dataclass(frozen=True)
class SweepSettings:
    """What a sweep measures (its identity: resuming a folder checks it).

    Attributes:
        mode: one of :data:`MODES`.
        controllers: registry names, ``NAME@DT`` for a fixed MPC dt [s] (``kd@0.055``).
        quick: the tiny grid of the test suite.
        seeds: seeds of ``protocol`` and ``terrain``.
        speeds_mps, directions, phases: a part of the grid (None: the mode's whole grid);
            directions are names of :data:`~.sweep_cases.DIRECTIONS` (``push``), phases
            fractions of a step in [0, 1) (``push``), speeds in [0, 1.5] m/s.
    """

    mode: str
    controllers: tuple[str, ...] = DEFAULT_CONTROLLERS
    quick: bool = False
    seeds: int = DEFAULT_SEEDS
    speeds_mps: tuple[float, ...] | None = None
    directions: tuple[str, ...] | None = None
    phases: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        from gaitnet_mpc.control.registry import CONTROLLERS

        if self.mode not in MODES:
            raise ConfigError("MODE", self.mode, f"one of {list(MODES)}")
        if not self.controllers or len(set(self.controllers)) != len(self.controllers):
            raise ConfigError("--controllers", ",".join(self.controllers), "distinct names")
        for spec in self.controllers:
            name, dt = parse_controller(spec)
            if name not in CONTROLLERS:
                raise ConfigError(
                    "--controllers", spec, f"names among {sorted(CONTROLLERS)} (NAME or NAME@DT)"
                )
            if dt is not None and name not in ("kd", "srbm", "wbmpc", "oracle"):
                raise ConfigError("--controllers", spec, "@DT only for a fixed-dt controller")
        if isinstance(self.seeds, bool) or not (isinstance(self.seeds, int) and self.seeds >= 1):
            raise ConfigError("--seeds", self.seeds, "an integer >= 1")
        if self.speeds_mps is not None and not (
            self.speeds_mps and all(0.0 <= v <= 1.5 for v in self.speeds_mps)
        ):
            raise ConfigError("--speeds", self.speeds_mps, "speeds in [0, 1.5] m/s")
        if self.directions is not None and not (
            self.directions and set(self.directions) <= set(DIRECTIONS)
        ):
            raise ConfigError("--directions", self.directions, f"names among {list(DIRECTIONS)}")
        if self.phases is not None and not (self.phases and all(0 <= p < 1 for p in self.phases)):
            raise ConfigError("--phases", self.phases, "fractions of a step in [0, 1)")
        if self.mode != "push" and (self.directions is not None or self.phases is not None):
            raise ConfigError("--directions / --phases", self.mode, "the push mode")

    @property
    def plan(self) -> ModePlan:
        plan = mode_plan(self.mode, self.quick, self.seeds)
        if self.speeds_mps is not None:
            plan = replace(plan, speeds_mps=self.speeds_mps)
        if self.directions is not None:
            plan = replace(plan, directions=self.directions)
        if self.phases is not None:
            plan = replace(plan, phases=self.phases)
        return plan

    def to_dict(self) -> dict[str, Any]:
        return {
            "mode": self.mode,
            "controllers": list(self.controllers),
            "quick": self.quick,
            "seeds": self.seeds,
            "plan": self.plan.to_dict(),
        }


class SettingsLike(Protocol):
    """Settings that identify a folder of cases (:func:`read_records`)."""

    def to_dict(self) -> dict[str, Any]: ...


def check_inputs(settings: SweepSettings, folder: Path) -> Path:
    """What a worker would find wrong, found before any case starts: the output path and
    every controller's settings (``@DT`` in the accepted range)."""
    from gaitnet_mpc.scenario import make_scenario

    folder = check_output_path(folder, "--out")
    for spec in settings.controllers:
        name, dt = parse_controller(spec)
        try:
            make_scenario(controller=name, dt_s=dt, duration_s=1.0)
        except ConfigError as exc:
            raise ConfigError("--controllers", spec, f"a valid controller ({exc})") from None
    return folder


# ----------------------------------------------------------------------------- storage
def read_records(
    path: Path, settings: SettingsLike, header: str = "sweep_settings"
) -> dict[str, dict[str, Any]]:
    """The finished cases in ``path`` by key (a torn last line is ignored); the line with
    the key ``header`` holds the settings (``reproduce fig6`` keeps its cases this way).

    Raises:
        ConfigError: the file holds another sweep's settings.
    """
    if not path.exists():
        return {}
    records: dict[str, dict[str, Any]] = {}
    for line in path.read_text().splitlines():
        try:
            item = json.loads(line)
        except json.JSONDecodeError:
            continue  # a line cut by a kill during the write
        if header in item:
            if item[header] != settings.to_dict():
                old, new = item[header], settings.to_dict()
                diff = sorted(k for k in old.keys() | new.keys() if old.get(k) != new.get(k))
                raise ConfigError(
                    "--out",
                    str(path.parent),
                    f"a folder of the same sweep settings (it differs in: {', '.join(diff)}); "
                    "use another --out",
                )
            continue
        records[str(item["key"])] = item
    return records


def _write_courses(folder: Path, settings: SweepSettings) -> None:
    """The ``uneven`` course files of ``terrain`` (the same bytes each time)."""
    from gaitnet_mpc.terrain.builtin_courses import uneven_course

    plan = settings.plan
    for course in plan.courses:
        if not course.startswith("uneven:"):
            continue
        amplitude = float(course.split(":", 1)[1])
        for seed in plan.seeds:
            path = folder / uneven_file_name(course, seed)
            c = uneven_course(seed=seed, amplitude_m=amplitude)
            write_atomic(path, json.dumps(c.to_dict(), indent=1) + "\n")


def _write_outputs(
    folder: Path,
    settings: SweepSettings,
    records: dict[str, dict[str, Any]],
    command: str,
    wall_s: float,
    total: int,
    failed: list[str],
) -> None:
    rows = list(records.values())
    write_atomic(folder / CSV, csv_text(settings.mode, rows))
    text = markdown(
        settings.mode,
        settings.controllers,
        rows,
        settings=settings.to_dict(),
        command=command,
        wall_s=wall_s,
        total=total,
        failed=failed,
    )
    write_atomic(folder / REPORT, text)
    if settings.mode == "push" and rows:
        push_polar(folder / POLAR, rows, settings.controllers)


# ----------------------------------------------------------------------------- run
def _runs(
    cases: list[dict[str, Any]], folder: Path, options: Options
) -> Generator[Outcome[Any, dict[str, Any]], None, None]:
    items = [(case, str(folder.resolve())) for case in cases]
    if options.backend == "ray":
        return run_ray(run_case, items, options.workers, options.address, max_retries=0)
    return run_processes(run_case, items, options.workers)


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def sweep(
    settings: SweepSettings,
    folder: Path,
    options: Options,
    command_line: str = "",
    log: Callable[[str], None] = _stderr,
) -> dict[str, dict[str, Any]]:
    """Run every case of ``settings`` not yet in ``folder``; return all finished records.

    Raises:
        ConfigError: bad settings, a folder of other settings, or one locked by another
            process (all before any case starts), or a named error of a worker.
        PartialFailure: after the other cases finished, when some cases failed.
        KeyboardInterrupt: on Ctrl-C / SIGTERM, after writing what was finished.
    """
    t0 = time.perf_counter()
    folder = check_inputs(settings, Path(folder))
    with folder_lock(folder, what="sweep"):
        path = folder / CASES
        records = read_records(path, settings)
        if not path.exists():
            append_json_line(path, {"sweep_settings": settings.to_dict()})
        if settings.mode == "terrain":
            _write_courses(folder, settings)
        cases = make_cases(settings.mode, settings.controllers, settings.plan)
        keys = [c["key"] for c in cases]
        todo = [c for c in cases if c["key"] not in records]
        failed: list[str] = []

        def status(state: str, code: int | None = None) -> None:
            left = [k for k in keys if k not in records]
            note = "run the same command again to run the cases left"
            if failed:
                note = f"{len(failed)} case(s) failed (see {ERRORS_LOG}); " + note
            write_status(
                folder,
                command=command_line,
                state=state,
                exit_code=code,
                done=[k for k in keys if k in records],
                todo=left,
                note=note if left else "",
            )

        def outputs() -> None:
            wall = time.perf_counter() - t0
            _write_outputs(folder, settings, records, command_line, wall, len(cases), failed)

        if not todo:
            log(f"nothing to do: all {len(cases)} cases are in {path}")
            outputs()
            status("done", 0)
            return records
        log(
            f"sweep {settings.mode}: {len(todo)} of {len(cases)} cases to run "
            f"({len(records)} already in {path}), {options.workers} worker(s), "
            f"backend {options.backend}"
        )
        status("running")
        runs = _runs(todo, folder, options)
        n = 0
        try:
            with closing(runs), stop_signals_as_keyboard_interrupt():
                for outcome in runs:
                    case = outcome.item[0]
                    n += 1
                    if outcome.error is not None:
                        if isinstance(outcome.error, GaitNetMPCError):
                            raise outcome.error  # bad input the checks above did not see
                        failed.append(case["key"])
                        brief = {k: v for k, v in case.items() if k != "plan"}
                        append_failure(
                            folder / ERRORS_LOG,
                            case["key"],
                            "case",
                            brief,
                            outcome.error,
                            outcome.worker_died,
                        )
                        status("running")
                        log(
                            f"[{n}/{len(todo)}] {case['key']}: FAILED "
                            f"({type(outcome.error).__name__}: {str(outcome.error)[:200]}); "
                            f"see {folder / ERRORS_LOG}"
                        )
                        continue
                    record = outcome.get()
                    append_json_line(path, record)
                    records[record["key"]] = record
                    status("running")
                    if options.progress:
                        log(f"[{n}/{len(todo)}] {case_line(record)}")
        except KeyboardInterrupt:
            outputs()
            status("interrupted", 130)
            log(
                f"interrupted: {len(records)} of {len(cases)} cases are in {path}; "
                "run the same command again to run the rest"
            )
            raise
        outputs()
        log(f"ran {n - len(failed)} cases in {time.perf_counter() - t0:.0f} s into {folder}")
        if failed:
            status("failed", 3)
            raise PartialFailure("sweep", failed, str(folder / ERRORS_LOG))
        status("done", 0)
        return records


def case_line(r: dict[str, Any]) -> str:
    """The progress line of a finished case."""
    res, mode = r["result"], r["case"]["mode"]
    if mode in ("push", "payload"):
        unit = "N" if mode == "push" else "kg"
        s, f = res["survived"], res["failed"]
        text = "falls at 0" if s is None else f"survived {s:g} {unit}"
        text += "" if f is None else f", fell at {f:g} {unit}"
        if res["non_monotone"]:
            text += ", NON-MONOTONE (fell at " + ", ".join(f"{x:g}" for x in res["spot_failed"])
            text += f" {unit})"
        text += f" ({len(res['episodes'])} episodes)"
    elif mode == "protocol":
        text = "survived" if res["survived"] else f"fell at {res['fall_time_s']:.2f} s"
    elif res["success"]:
        text = "clean"
    else:
        text = f"fell at {res['fall_time_s']:.2f} s" if res["fell"] else "not clean"
    return f"{r['key']}: {text}, {r['wall_s']:.1f} s wall"
