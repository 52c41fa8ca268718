"""``gaitnet-mpc collect``: walk the protocol's sets in parallel and keep the folder whole.

The sets run in a local process pool (``backend="process"``) or as Ray tasks
(``backend="ray"``, on a local Ray instance or the cluster at ``address``), through
:mod:`gaitnet_mpc.parallel`. Workers only
simulate and return a set's bytes; this process, which holds the folder's lock, writes
each set file atomically and the manifest after every set. So:

* re-running the same command skips finished sets (and says so when none is left);
* a deleted set file is collected again, and only it;
* Ctrl-C or SIGTERM stops the workers; finished sets stay, the sets in progress are lost
  (redone by the next run);
* two runs into one folder cannot both write: the second stops at the lock.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from collections.abc import Callable, Generator
from contextlib import closing
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from gaitnet_mpc.config import dumps
from gaitnet_mpc.dataset.protocol import CollectProtocol, SetSpec
from gaitnet_mpc.dataset.schema import FEATURE_NAMES, LABEL, SCHEMA_VERSION, describe
from gaitnet_mpc.dataset.store import (
    MANIFEST,
    DatasetError,
    encode_set,
    folder_lock,
    read_manifest,
    read_set_meta,
    remove_partial_files,
    set_file,
    sha256_file,
)
from gaitnet_mpc.errors import ConfigError, GaitNetMPCError, PartialFailure
from gaitnet_mpc.experiments.setrun import SetResult, run_set
from gaitnet_mpc.experiments.teachers import teacher_config
from gaitnet_mpc.parallel import Outcome, run_processes, run_ray, stop_signals_as_keyboard_interrupt
from gaitnet_mpc.results.io import append_failure, write_bytes_atomic, write_json_atomic
from gaitnet_mpc.results.outdir import check_output_path, write_status

BACKENDS = ("process", "ray")


@dataclass(frozen=True)
class CollectOptions:
    """How to run the sets (not part of the data: any choice gives the same files).

    Attributes:
        workers: parallel sets (processes, or Ray tasks' CPUs on a local Ray).
        backend: ``"process"`` or ``"ray"``.
        address: Ray cluster address (None: start a local Ray instance).
        progress: show a progress bar and a line per finished set.
    """

    workers: int = 1
    backend: str = "process"
    address: str | None = None
    progress: bool = True

    def __post_init__(self) -> None:
        if not (isinstance(self.workers, int) and self.workers >= 1):
            raise ConfigError("--workers", self.workers, "an integer >= 1")
        if self.backend not in BACKENDS:
            raise ConfigError("--backend", self.backend, f"one of {list(BACKENDS)}")
        if self.address is not None and self.backend != "ray":
            raise ConfigError("--address", self.address, "no address unless --backend ray")


# ----------------------------------------------------------------------------- workers
SetBytes = tuple[bytes, dict[str, object], float]


def _walk_set(spec: SetSpec, queue: Any = None) -> SetBytes:
    """Worker body: walk ``spec``; return the set file's bytes, its stats and wall time."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    progress = None if queue is None else (lambda s: queue.put((spec.index, s)))
    result: SetResult = run_set(spec, progress)
    stats = result.stats()
    return encode_set(spec, result.rows, stats), stats, result.wall_s


def _runs(
    specs: list[SetSpec], options: CollectOptions, on_progress: Callable[[int, float], None] | None
) -> Generator[Outcome[SetSpec, SetBytes], None, None]:
    """The sets' outcomes, in the order they finish, from the backend ``options`` names."""
    if options.backend == "ray":
        return run_ray(_walk_set, specs, options.workers, options.address)
    report = None if on_progress is None else (lambda message: on_progress(*message))
    return run_processes(_walk_set, specs, options.workers, report)


# ----------------------------------------------------------------------------- manifest
def provenance() -> dict[str, object]:
    """Package versions, git commit and machine of the collecting process."""
    from gaitnet_mpc import __version__

    packages: dict[str, str | None] = {}
    for name in ("numpy", "mujoco", "pin", "casadi", "piqp", "pyarrow"):
        try:
            packages[name] = version(name)
        except PackageNotFoundError:
            packages[name] = None
    commit: str | None = None
    try:
        here = Path(__file__).resolve().parent
        out = subprocess.run(
            ["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5
        )
        if out.returncode == 0:
            dirty = subprocess.run(
                ["git", "-C", str(here), "status", "--porcelain", "--untracked-files=no"],
                capture_output=True,
                text=True,
                timeout=5,
            ).stdout.strip()
            commit = out.stdout.strip() + ("+dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        pass
    return {
        "gaitnet_mpc": __version__,
        "git_commit": commit,
        "python": platform.python_version(),
        "packages": packages,
        "machine": f"{platform.machine()}, {os.cpu_count()} cores",
    }


def _entry(spec: SetSpec, path: Path, stats: dict[str, Any], wall_s: float | None) -> dict:
    return {
        "file": path.name,
        "rows": stats["rows"],
        "sha256": sha256_file(path),
        "spec": spec.to_dict(),
        "stats": stats,
        "wall_s": None if wall_s is None else round(wall_s, 2),
    }


def _manifest_header(
    protocol: CollectProtocol, teacher_toml: str, command_line: str
) -> dict[str, Any]:
    """The manifest's fields that do not change while a run collects (provenance asks git
    once per run, not once per set)."""
    return {
        "schema_version": SCHEMA_VERSION,
        "format": "parquet",
        "command": command_line,
        "protocol": protocol.to_dict(),
        "protocol_fingerprint": protocol.fingerprint(),
        "teacher_config_toml": teacher_toml,
        "provenance": provenance(),
        "columns": describe(),
        "features": list(FEATURE_NAMES),
        "label": LABEL.name,
    }


def _write_manifest(
    folder: Path, header: dict[str, Any], n_sets: int, entries: dict[int, dict[str, Any]]
) -> dict[str, Any]:
    sets = [entries[i] for i in sorted(entries)]
    stats = [e["stats"] for e in sets]
    walls = [e["wall_s"] for e in sets if e["wall_s"] is not None]
    manifest = {
        **header,
        "complete": len(sets) == n_sets,
        "totals": {
            "sets": len(sets),
            "rows": sum(int(s["rows"]) for s in stats),
            "steps_dropped_fall": sum(int(s["steps_dropped_fall"]) for s in stats),
            "falls": sum(int(s["falls"]) for s in stats),
            "sim_seconds": round(sum(float(s["sim_seconds"]) for s in stats), 3),
            "wall_s_of_sets": round(sum(walls), 1),
        },
        "sets": sets,
    }
    write_json_atomic(folder / MANIFEST, manifest)
    return manifest


def _protocol_difference(old: dict[str, Any], new: dict[str, Any]) -> str:
    keys = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
    return ", ".join(f"{k} {old.get(k)!r} -> {new.get(k)!r}" for k in keys) or "?"


def _finished_sets(
    folder: Path, protocol: CollectProtocol, manifest: dict[str, Any] | None, log: Callable
) -> dict[int, dict[str, Any]]:
    """The sets already in ``folder``: files of this protocol that read back whole."""
    known = {e["file"]: e for e in (manifest or {}).get("sets", [])}
    done = {}
    for spec in protocol.set_specs():
        path = folder / set_file(spec)
        if not path.exists():
            continue
        try:
            meta = read_set_meta(path)
        except DatasetError as exc:
            log(f"{path.name}: unreadable ({exc}); collecting it again")
            continue
        if meta.get("fingerprint") != protocol.fingerprint() or meta.get("spec") != spec.to_dict():
            raise ConfigError(
                "--out",
                str(folder),
                f"a folder of this protocol only ({path.name} was collected with other settings)",
            )
        old = known.get(path.name)
        entry = _entry(spec, path, meta["stats"], None)
        if old is not None and old.get("sha256") == entry["sha256"]:
            entry["wall_s"] = old.get("wall_s")
        done[spec.index] = entry
    return done


#: The log of sets whose worker raised or died (set, spec, traceback), in the folder.
ERRORS_LOG = "errors.log"


def check_inputs(protocol: CollectProtocol, folder: Path) -> Path:
    """Everything a worker would find wrong, found here before any set starts: the output
    path, the teacher's settings, and the course of every set."""
    from gaitnet_mpc.robots import ROBOTS
    from gaitnet_mpc.terrain import SEEDED_COURSES, load_course

    folder = check_output_path(folder, "--out")
    teacher_config(protocol, ROBOTS[protocol.robot].planar)
    seeded = protocol.course in SEEDED_COURSES
    seeds = sorted({s.course_seed for s in protocol.set_specs()}) if seeded else [None]
    for seed in seeds:
        load_course(protocol.course, **({} if seed is None else {"seed": seed}))
    return folder


def collect(
    protocol: CollectProtocol,
    folder: Path,
    options: CollectOptions,
    command_line: str = "",
    log: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Collect every set of ``protocol`` not yet in ``folder``; return the manifest.

    A set whose worker raises (other than a named bad-input error) or dies is logged with
    its traceback in ``folder/errors.log`` and the other sets go on; ``status.json`` says
    which sets are done, failed and left.

    Raises:
        ConfigError: bad settings, a folder of another protocol, or a folder locked by
            another ``collect`` (all before any set starts), or a named error of a worker.
        PartialFailure: after the other sets finished, when some sets failed.
        KeyboardInterrupt: on Ctrl-C / SIGTERM, after writing what was finished.
    """
    from gaitnet_mpc.robots import ROBOTS

    folder = check_inputs(protocol, Path(folder))
    teacher_toml = dumps(teacher_config(protocol, ROBOTS[protocol.robot].planar))
    with folder_lock(folder):
        for name in remove_partial_files(folder):
            log(f"removed {name}, a partial file of an interrupted write")
        manifest = read_manifest(folder)
        if manifest is not None and manifest.get("protocol_fingerprint") != protocol.fingerprint():
            new = json.loads(json.dumps(protocol.to_dict()))  # tuples as the manifest's lists
            diff = _protocol_difference(manifest.get("protocol", {}), new)
            raise ConfigError(
                "--out", str(folder), f"a folder of the same protocol (it differs in: {diff})"
            )
        entries = _finished_sets(folder, protocol, manifest, log)
        header = _manifest_header(protocol, teacher_toml, command_line)
        todo = [s for s in protocol.set_specs() if s.index not in entries]
        failed: dict[int, str] = {}

        def status(state: str, code: int | None = None) -> None:
            names = {s.index: s.name for s in protocol.set_specs()}
            left = [names[i] for i in sorted(names) if i not in entries and i not in failed]
            note = "run the same command again to collect the sets left"
            if failed:
                note = f"sets failed: {', '.join(failed.values())} (see {ERRORS_LOG}); " + note
            write_status(
                folder,
                command=command_line,
                state=state,
                exit_code=code,
                done=[names[i] for i in sorted(entries)],
                todo=[*left, *failed.values()],
                note=note,
            )

        if not todo:
            log(f"nothing to do: all {protocol.sets} sets are in {folder}")
            status("done", 0)
            return _write_manifest(folder, header, protocol.sets, entries)
        log(
            f"collecting {len(todo)} of {protocol.sets} sets ({len(entries)} already in "
            f"{folder}), {protocol.seconds_per_set:g} s each, teacher {protocol.teacher}, "
            f"{options.workers} worker(s), backend {options.backend}"
        )
        bar = _progress_bar(len(todo) * protocol.seconds_per_set) if options.progress else None
        t0 = time.perf_counter()

        def on_progress(index: int, sim_s: float) -> None:
            if bar is not None:
                bar.update(sim_s)

        try:  # checks Ray and --address before the status says running
            runs = _runs(todo, options, on_progress if bar is not None else None)
        except BaseException:
            if bar is not None:
                bar.close()
            raise
        status("running")
        manifest = None
        try:
            with closing(runs), stop_signals_as_keyboard_interrupt():
                for outcome in runs:
                    spec = outcome.item
                    if outcome.error is not None:
                        if isinstance(outcome.error, GaitNetMPCError):
                            raise outcome.error  # bad input the checks above did not see
                        failed[spec.index] = spec.name
                        append_failure(
                            folder / ERRORS_LOG,
                            spec.name,
                            "spec",
                            spec.to_dict(),
                            outcome.error,
                            outcome.worker_died,
                        )
                        status("running")
                        line = f"{spec.name}: FAILED ({type(outcome.error).__name__}: "
                        line += f"{str(outcome.error)[:200]}); see {folder / ERRORS_LOG}"
                        (bar.write if bar is not None else log)(line)
                        continue
                    data, stats, wall_s = outcome.get()
                    path = folder / set_file(spec)
                    write_bytes_atomic(path, data)
                    entries[spec.index] = _entry(spec, path, stats, wall_s)
                    manifest = _write_manifest(folder, header, protocol.sets, entries)
                    status("running")
                    if bar is not None and options.backend == "ray":
                        bar.update(protocol.seconds_per_set)
                    line = _set_line(spec, stats, wall_s, len(entries), protocol.sets)
                    (bar.write if bar is not None else log)(line)
        except (KeyboardInterrupt, SystemExit):  # SystemExit: a library's SIGTERM handler
            left = protocol.sets - len(entries)
            status("interrupted", 130)
            log(
                f"interrupted: {len(entries)} of {protocol.sets} sets are in {folder}, {left} "
                "left; run the same command again to collect them"
            )
            raise
        except Exception:  # a worker's named error, a crash: the status does not stay running
            status("failed")
            raise
        finally:
            if bar is not None:
                bar.close()
        if manifest is None:
            manifest = _write_manifest(folder, header, protocol.sets, entries)
        wall_s = time.perf_counter() - t0
        log(f"collected {len(todo) - len(failed)} sets in {wall_s:.0f} s into {folder}")
        if failed:
            status("failed", 3)
            raise PartialFailure("collect", list(failed.values()), str(folder / ERRORS_LOG))
        status("done", 0)
        return manifest


def _set_line(spec: SetSpec, stats: dict[str, Any], wall_s: float, n: int, total: int) -> str:
    falls = int(stats["falls"])
    fall_text = f", {falls} fall(s), {stats['steps_dropped_fall']} step(s) dropped" if falls else ""
    short = " (ended short)" if stats["ended_short"] else ""
    return (
        f"[{n}/{total}] {spec.name}: vx {spec.vx_mps:.2f} m/s, {stats['sim_seconds']:g} sim-s, "
        f"{stats['rows']} rows{fall_text}{short}, {wall_s:.0f} s wall"
    )


def _progress_bar(total_sim_s: float) -> Any:
    from tqdm import tqdm

    return tqdm(
        total=round(total_sim_s, 3),
        unit="sim-s",
        file=sys.stderr,
        bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} sim-s [{elapsed}<{remaining}]",
    )
