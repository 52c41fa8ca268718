"""A resumable run of independent cases into one folder (``sweep``, ``reproduce fig6``).

The folder keeps its finished cases as JSON lines in one file, after a header line with
the settings that made them (:func:`read_records` refuses a file of other settings), a
``status.json`` (:func:`~gaitnet_mpc.results.outdir.write_status`) and an ``errors.log``
of the cases that raised. :func:`run_cases` runs the cases not yet in the file on a
process pool or on Ray, appends each as it finishes, and rewrites the reports after the
last (or on Ctrl-C / SIGTERM), so that running the same command again resumes the work.
The caller holds the folder's lock.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from gaitnet_mpc.errors import ConfigError, GaitNetMPCError, PartialFailure
from gaitnet_mpc.parallel import run_processes, run_ray, stop_signals_as_keyboard_interrupt
from gaitnet_mpc.results.io import append_failure, append_json_line
from gaitnet_mpc.results.outdir import write_status

#: The failures of a run's cases, one block each (beside its cases file).
ERRORS_LOG = "errors.log"

Log = Callable[[str], None]


class SettingsLike(Protocol):
    def to_dict(self) -> dict[str, Any]: ...


def read_records(
    path: Path, settings: SettingsLike, header: str = "sweep_settings"
) -> dict[str, dict[str, Any]]:
    """The finished cases in ``path`` by key (a torn last line is ignored); the line with
    the key ``header`` holds the settings.

    Raises:
        ConfigError: the file holds other settings.
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


@dataclass(frozen=True)
class CaseRun:
    """What :func:`run_cases` needs to know of its caller.

    Attributes:
        what: the command, in messages (``"sweep push"``, ``"reproduce fig6"``).
        folder: the results folder (locked by the caller).
        path: the cases file in it, already holding its header line.
        worker: runs one ``(case, folder)`` item in a worker, returns its record (with a
            ``key``).
        outputs: rewrites the reports from the records so far and the failed keys.
        case_line: the progress line of a finished record.
        command_line: the command as typed, for ``status.json``.
        hidden: the case's field that ``errors.log`` leaves out (the full settings).
    """

    what: str
    folder: Path
    path: Path
    worker: Callable[[tuple[dict[str, Any], str]], dict[str, Any]]
    outputs: Callable[[list[str]], None]
    case_line: Callable[[dict[str, Any]], str]
    command_line: str = ""
    hidden: str = "settings"


def run_cases(
    run: CaseRun,
    cases: list[dict[str, Any]],
    records: dict[str, dict[str, Any]],
    options: Any,
    log: Log,
) -> dict[str, dict[str, Any]]:
    """Run the ``cases`` whose key is not in ``records`` (``options``: ``workers``,
    ``backend``, ``address``, ``progress``); return ``records`` with them added.

    Raises:
        GaitNetMPCError: a worker's named error (bad input no check before saw).
        PartialFailure: after the other cases finished, when some cases failed.
        KeyboardInterrupt: on Ctrl-C / SIGTERM, after writing what was finished.
    """
    t0 = time.perf_counter()
    keys = [c["key"] for c in cases]
    todo = [c for c in cases if c["key"] not in records]
    failed: list[str] = []
    errors = run.folder / ERRORS_LOG

    def status(state: str, code: int | None = None) -> None:
        left = [k for k in keys if k not in records]
        note = "run the same command again to run the cases left"
        if failed:
            note = f"{len(failed)} case(s) failed (see {ERRORS_LOG}); " + note
        write_status(
            run.folder,
            command=run.command_line,
            state=state,
            exit_code=code,
            done=[k for k in keys if k in records],
            todo=left,
            note=note if left else "",
        )

    if not todo:
        log(f"{run.what}: nothing to do, all {len(cases)} cases are in {run.path}")
        run.outputs(failed)
        status("done", 0)
        return records
    log(
        f"{run.what}: {len(todo)} of {len(cases)} cases to run ({len(records)} already in "
        f"{run.path}), {options.workers} worker(s), backend {options.backend}"
    )
    items = [(case, str(run.folder.resolve())) for case in todo]
    if options.backend == "ray":  # checks Ray and --address before the status says running
        runs = run_ray(run.worker, items, options.workers, options.address, max_retries=0)
    else:
        runs = run_processes(run.worker, items, options.workers)
    status("running")
    n = 0
    try:
        with closing(runs), stop_signals_as_keyboard_interrupt():
            for outcome in runs:
                case = outcome.item[0]
                n += 1
                if outcome.error is not None:
                    if isinstance(outcome.error, GaitNetMPCError):
                        raise outcome.error
                    failed.append(case["key"])
                    brief = {k: v for k, v in case.items() if k != run.hidden}
                    append_failure(errors, case["key"], "case", brief, outcome.error,
                                   outcome.worker_died)  # fmt: skip
                    status("running")
                    log(
                        f"[{n}/{len(todo)}] {case['key']}: FAILED "
                        f"({type(outcome.error).__name__}: {str(outcome.error)[:200]}); "
                        f"see {errors}"
                    )
                    continue
                record = outcome.get()
                append_json_line(run.path, record)
                records[record["key"]] = record
                status("running")
                if options.progress:
                    log(f"[{n}/{len(todo)}] {run.case_line(record)}")
    except (KeyboardInterrupt, SystemExit):  # SystemExit: a library's own SIGTERM handler
        run.outputs(failed)
        status("interrupted", 130)
        log(
            f"interrupted: {len(records)} of {len(cases)} cases are in {run.path}; "
            "run the same command again to run the rest"
        )
        raise
    except Exception:  # a worker's named error, a crash: the status does not stay running
        status("failed")
        raise
    run.outputs(failed)
    log(f"ran {n - len(failed)} cases in {time.perf_counter() - t0:.0f} s into {run.folder}")
    if failed:
        status("failed", 3)
        raise PartialFailure(run.what, failed, str(errors))
    status("done", 0)
    return records


__all__ = ["ERRORS_LOG", "CaseRun", "SettingsLike", "read_records", "run_cases"]
