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
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.experiments.case_runs import CaseRun, read_records, run_cases
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
from gaitnet_mpc.results.io import append_json_line, write_atomic
from gaitnet_mpc.results.outdir import check_output_path, folder_lock

CASES = "cases.jsonl"
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
            c = parse_controller(spec)
            if c.name not in CONTROLLERS:
                raise ConfigError(
                    "--controllers",
                    spec,
                    f"names among {sorted(CONTROLLERS)} (NAME[@DT][:WEIGHTS][+PRESET])",
                )
            if c.dt_s is not None and c.name not in ("kd", "srbm", "wbmpc", "oracle"):
                raise ConfigError("--controllers", spec, "@DT only for a fixed-dt controller")
            if c.weights is not None and c.name != "gaitnet":
                raise ConfigError("--controllers", spec, ":WEIGHTS only for gaitnet")
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


def check_inputs(settings: SweepSettings, folder: Path) -> Path:
    """What a worker would find wrong, found before any case starts: the output path and
    every controller's settings (``@DT`` in the accepted range, ``+PRESET`` one of the
    controller's presets or a settings file)."""
    from gaitnet_mpc.scenario import make_scenario

    folder = check_output_path(folder, "--out")
    for spec in settings.controllers:
        try:
            make_scenario(**parse_controller(spec).scenario_args(), duration_s=1.0)
        except ConfigError as exc:
            raise ConfigError("--controllers", spec, f"a valid controller ({exc})") from None
    return folder


# ----------------------------------------------------------------------------- storage
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

        def outputs(failed: list[str]) -> None:
            wall = time.perf_counter() - t0
            _write_outputs(folder, settings, records, command_line, wall, len(cases), failed)

        run = CaseRun(f"sweep {settings.mode}", folder, path, run_case, outputs, case_line,
                      command_line, hidden="plan")  # fmt: skip
        return run_cases(run, cases, records, options, log)


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
        if res.get("bisected") is not None:
            text += f", survived {res['bisected']:g} {unit} above that fall (not counted)"
        text += f" ({len(res['episodes'])} episodes)"
    elif mode == "protocol":
        text = "survived" if res["survived"] else f"fell at {res['fall_time_s']:.2f} s"
    elif res["success"]:
        text = "clean"
    else:
        text = f"fell at {res['fall_time_s']:.2f} s" if res["fell"] else "not clean"
    return f"{r['key']}: {text}, {r['wall_s']:.1f} s wall"
