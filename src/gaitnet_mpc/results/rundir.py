"""Reading a run folder and writing result files atomically.

A run folder (written by ``gaitnet-mpc run``, see :mod:`gaitnet_mpc.runner.episode`) holds
``summary.json`` (what happened: deterministic, so a replay of ``scenario.toml`` writes the
same file), ``timing.json`` (the wall-clock figures of this machine: solve times,
real-time factor), ``scenario.toml`` (the run, replayable), ``log.csv`` (one row per
control tick), ``mpc_log.csv`` (one row per MPC solve, MPC controllers only),
``course.json``, ``config.toml`` (the controller's settings, controllers with settings
only, see :mod:`gaitnet_mpc.config`), ``video.mp4`` and ``plots/``. Everything here reads
only those files, so plots and comparisons can be re-made at any time.
"""

from __future__ import annotations

import io
import json
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.errors import ConfigError, CourseFormatError
from gaitnet_mpc.terrain import Course

SUMMARY = "summary.json"
TIMING = "timing.json"
SCENARIO = "scenario.toml"
LOG = "log.csv"
MPC_LOG = "mpc_log.csv"
EVENTS = "events.csv"
COURSE = "course.json"
CONFIG = "config.toml"
VIDEO = "video.mp4"
PLOTS_DIR = "plots"


#: Top-level ``summary`` keys that are wall-clock figures (``timing.json``); in the
#: ``mpc`` block, every key with ``_ms_`` in it is one too.
TIMING_KEYS = ("wall_time_s", "render_time_s", "realtime_factor")


def split_timing(summary: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """``summary`` as (``summary.json``: without wall-clock figures, ``timing.json``)."""
    facts = {k: v for k, v in summary.items() if k not in TIMING_KEYS}
    timing = {k: summary[k] for k in TIMING_KEYS if k in summary}
    mpc = summary.get("mpc")
    if isinstance(mpc, dict):
        facts["mpc"] = {k: v for k, v in mpc.items() if "_ms_" not in k}
        timing["mpc"] = {k: v for k, v in mpc.items() if "_ms_" in k}
    return facts, timing


def merge_timing(facts: dict[str, Any], timing: dict[str, Any]) -> dict[str, Any]:
    """The whole summary again from :func:`split_timing`'s two parts."""
    out = {**facts, **{k: v for k, v in timing.items() if k != "mpc"}}
    if isinstance(facts.get("mpc"), dict) and isinstance(timing.get("mpc"), dict):
        out["mpc"] = {**facts["mpc"], **timing["mpc"]}
    return out


def read_csv_columns(path: str | Path) -> dict[str, np.ndarray]:
    """Columns of a CSV file with one header line, as ``name -> (n,) float array``.

    Missing values (``nan``) stay NaN. A file with only a header gives empty columns.

    Raises:
        ConfigError: naming the file and the line: not UTF-8 text, a line with another
            number of fields than the header (a truncated or malformed file), or a value
            that is not a number.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(str(path), f"byte {exc.start}", "a UTF-8 text CSV file") from None
    lines = text.splitlines()
    if not lines:
        raise ConfigError(str(path), "an empty file", "a CSV file with a header line")
    names = [c.strip() for c in lines[0].split(",")]
    if len(lines) < 2:
        return {n: np.zeros(0) for n in names}
    for number, line in enumerate(lines[1:], start=2):
        fields = line.count(",") + 1
        if fields != len(names):
            last = number == len(lines)
            raise ConfigError(
                str(path),
                f"{fields} fields on {'its last ' if last else ''}line {number}",
                f"{len(names)} fields on every line, as in the header: the file is "
                f"{'truncated (an interrupted write?)' if last else 'malformed'}",
            )
    try:
        data = np.loadtxt(io.StringIO("\n".join(lines[1:])), delimiter=",", ndmin=2)
    except ValueError as exc:
        for number, line in enumerate(lines[1:], start=2):  # name the line and column
            for name, value in zip(names, line.split(","), strict=True):
                try:
                    float(value)
                except ValueError:
                    raise ConfigError(f"{path}: line {number}, {name}", value, "a number") from None
        raise ConfigError(str(path), "unreadable values", f"numbers ({exc})") from None
    if data.shape[1] != len(names):
        raise ConfigError(str(path), f"{data.shape[1]} columns", f"{len(names)} (the header)")
    return {n: data[:, i] for i, n in enumerate(names)}


#: The type of each ``summary.json`` field the plots and comparisons read: a number
#: (int or float, not bool), a bool, a string, a list, a table, "number?" (a number or
#: null), "numbers" (a list of numbers).
SUMMARY_TYPES: dict[str, str] = {
    "robot": "string",
    "controller": "string",
    "course": "string",
    "outcome": "string",
    "duration_s": "number",
    "distance_m": "number",
    "mean_speed_mps": "number?",
    "speed_rmse_mps": "number?",
    "foothold_violations": "number",
    "self_collisions": "number",
    "fall_time_s": "number?",
    "fell": "bool",
    "interrupted": "bool",
    "step_durations_s": "numbers",
    "footholds": "list",
    "mpc": "table?",
    "controller_options": "table?",
}
#: Columns ``log.csv`` must have for the plots and comparisons.
LOG_COLUMNS_REQUIRED = ("t_s", "com_vx_mps")


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def check_summary(summary: dict[str, Any], path: Path) -> None:
    """Refuse a ``summary.json`` whose known fields have the wrong type (a hand-edited or
    corrupted file), naming the file, the field and the expected type."""
    checks = {
        "string": (lambda v: isinstance(v, str), "a string"),
        "number": (_is_number, "a number"),
        "number?": (lambda v: v is None or _is_number(v), "a number or null"),
        "bool": (lambda v: isinstance(v, bool), "true or false"),
        "list": (lambda v: isinstance(v, list), "a list"),
        "numbers": (
            lambda v: isinstance(v, list) and all(_is_number(x) for x in v),
            "a list of numbers",
        ),
        "table?": (lambda v: v is None or isinstance(v, dict), "a JSON object or null"),
    }
    for key, kind in SUMMARY_TYPES.items():
        if key in summary:
            ok, expected = checks[kind]
            if not ok(summary[key]):
                raise ConfigError(f"{path}: {key}", summary[key], expected)


@dataclass(frozen=True)
class RunFolder:
    """The files of one run folder, loaded.

    Attributes:
        path: the folder.
        summary: ``summary.json``.
        log: ``log.csv`` columns (per control tick).
        mpc_log: ``mpc_log.csv`` columns (per MPC solve), or None when absent.
        course: ``course.json`` as a :class:`Course`, or None when absent (older runs).
    """

    path: Path
    summary: dict[str, Any]
    log: dict[str, np.ndarray]
    mpc_log: dict[str, np.ndarray] | None
    course: Course | None

    @property
    def label(self) -> str:
        """Short name of the run: the folder name."""
        return self.path.name or str(self.path)

    def column(self, name: str) -> np.ndarray | None:
        """A ``log.csv`` column, or None if this log lacks it (older runs)."""
        return self.log.get(name)

    @property
    def plots_dir(self) -> Path:
        return self.path / PLOTS_DIR


#: Largest ``summary.json`` / ``timing.json`` read [bytes]: a 1 h run's summary (a
#: foothold per step) is about 1 MB.
MAX_JSON_BYTES = 64 << 20


def _read_json(path: Path) -> Any:
    """A run's JSON file; a named error if it is too big, not UTF-8, not JSON or too deep."""
    size = path.stat().st_size
    if size > MAX_JSON_BYTES:
        raise ConfigError(str(path), f"{size} bytes", f"at most {MAX_JSON_BYTES} bytes")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(str(path), "invalid JSON", f"valid UTF-8 JSON ({exc})") from None
    except RecursionError:
        raise ConfigError(str(path), "JSON nested too deep", "a run's JSON file") from None


def load_run(path: str | Path) -> RunFolder:
    """Load a run folder; raises :class:`ConfigError` naming the missing or bad file."""
    root = Path(path)
    expected = "a run folder written by `gaitnet-mpc run` (with summary.json and log.csv)"
    if not root.is_dir():
        raise ConfigError("RUN_DIR", str(path), expected)
    for name in (SUMMARY, LOG):
        if not (root / name).is_file():
            raise ConfigError("RUN_DIR", str(path), f"{expected}; {name} is missing")
    summary = _read_json(root / SUMMARY)
    if not isinstance(summary, dict):
        raise ConfigError(str(root / SUMMARY), type(summary).__name__, "a JSON object")
    check_summary(summary, root / SUMMARY)
    if (root / TIMING).is_file():
        timing = _read_json(root / TIMING)
        if isinstance(timing, dict):
            summary = merge_timing(summary, timing)
    log = read_csv_columns(root / LOG)
    missing = [c for c in LOG_COLUMNS_REQUIRED if c not in log]
    if missing:
        raise ConfigError(
            str(root / LOG), f"no column {missing[0]}", f"columns {LOG_COLUMNS_REQUIRED}"
        )
    mpc_log = read_csv_columns(root / MPC_LOG) if (root / MPC_LOG).is_file() else None
    course = None
    if (root / COURSE).is_file():
        try:
            course = Course.from_json(root / COURSE)
        except CourseFormatError:
            course = None  # the top view is then drawn without the terrain
    return RunFolder(root, summary, log, mpc_log, course)


def save_figure_atomic(fig: Any, path: str | Path, dpi: int = 110) -> Path:
    """Save a matplotlib figure as PNG through a temporary file and an atomic rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    try:
        with os.fdopen(fd, "wb") as fh:
            fig.savefig(fh, format="png", dpi=dpi)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


#: Files and folders a run writes into its run folder (``--overwrite`` removes these).
RUN_ARTIFACTS = (
    SUMMARY,
    TIMING,
    SCENARIO,
    LOG,
    MPC_LOG,
    EVENTS,
    COURSE,
    CONFIG,
    VIDEO,
    "video.part.mp4",
    "status.json",
    PLOTS_DIR,
)
#: Files ``compare`` writes into its output folder.
COMPARE_ARTIFACTS = ("compare.png", "compare.md", "compare.csv")
