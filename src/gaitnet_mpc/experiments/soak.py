"""Soak test: many random short episodes, looking for crashes rather than for good walking.

Each episode is drawn from ``(--seed, episode index)`` alone, so episode K of a seed is
the same whatever ``--episodes`` or ``--workers`` were: a controller (weights favour the
cheap ones: wbmpc is ~10x slower than real time on humanoid3d and builds its NLPs for
~40 s, so it gets few, short episodes), a robot, a course (seeded courses mostly with a
random layout), a velocity command in the allowed range, 0-3 random pushes, a payload
(half the episodes) and a duration of 1-5 s. It runs through the library path of
``gaitnet-mpc run`` (:func:`~gaitnet_mpc.scenario.make_scenario`,
:func:`~gaitnet_mpc.scenario.build_episode`, :func:`run_episode`; no output folder, no
video) on a spawn process pool or on Ray (``--backend ray``).

Per episode it records: any exception (type, message, where; caught in the worker),
non-finite torques (the simulator refuses them with ``ConfigError("tau_nm", ...)``), a
diverged simulation (the simulator's MuJoCo-warning / non-finite-state / speed checks,
MuJoCo's warning counters, a non-finite final ``qpos``), QP failures the controller
handled, unconverged MPC solves, Python warnings, the fall and the wall time.

Finished episodes are appended to ``<work-dir>/<report stem>.episodes.jsonl`` (flushed and
fsync'ed line by line; a torn last line is ignored). Re-running the same command skips
them; Ctrl-C / SIGTERM stops the workers and writes the report of what was done. The
report lists every failing episode with the command replaying it in this process
(``--replay K``, which lets the exception propagate with its full traceback).

Run::

    MUJOCO_GL=egl .venv/bin/python benchmarks/soak.py --episodes 1000 --workers 2 \
        [--backend process|ray] [--seed 0] [--out benchmarks/results/soak.md]

(Over 500 lines because drawing the episodes, the worker, the resumable episode log and
the report are one engine; the script ``benchmarks/soak.py`` is its command line.)
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Generator, Sequence
from contextlib import closing
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.machine import machine_info
from gaitnet_mpc.parallel import Outcome, run_processes, run_ray, stop_signals_as_keyboard_interrupt

RESULTS = Path("benchmarks") / "results"  # of the repository the script runs in

#: Relative frequency of each controller (wbmpc is ~40 s of NLP build + ~10x real time).
CONTROLLER_WEIGHTS: dict[str, float] = {
    "stand": 0.2,
    "srbm": 0.3,
    "kd": 0.25,
    "gaitnet": 0.2,
    "wbmpc": 0.05,
}
ROBOT_NAMES = ("humanoid3d", "biped2d")
DURATION_RANGE_S = (1.0, 5.0)
#: wbmpc's duration range by robot [s] (humanoid3d: ~10x slower than real time).
WBMPC_DURATION_RANGE_S = {"humanoid3d": (1.0, 1.5), "biped2d": DURATION_RANGE_S}
FLAT_PROBABILITY = 0.35
RANDOM_LAYOUT_PROBABILITY = 0.8  # a seeded course gets a random seed, else its default
VX_RANGE_MPS = (0.0, 1.5)  # Command allows |vx| <= 1.5 m/s
VY_MAX_MPS = 0.3  # Command allows 0.5 m/s
YAW_RATE_MAX_RADPS = 0.5  # Command allows 1.5 rad/s
TURN_PROBABILITY = 0.25  # humanoid3d episodes with a lateral / yaw-rate command
PUSH_COUNT_PROBABILITIES = (0.4, 0.3, 0.2, 0.1)  # 0, 1, 2 or 3 pushes
PUSH_FORCE_RANGE_N = (10.0, 80.0)  # horizontal, in a uniformly drawn direction
PUSH_DURATION_RANGE_S = (0.05, 0.2)  # at most 16 N s (the protocol: 20 N s)
PUSH_START_S = 0.2  # no push before [s]
PAYLOAD_PROBABILITY = 0.5
PAYLOAD_RANGE_KG = (0.0, 3.0)  # within both robots' bound (their own mass: 16 / 10 kg)

#: The draw profiles: ``short`` (1-5 s on every built-in course, flat included) and
#: ``long`` (20 s on a random layout of a seeded course, stones, gaps or uneven tiles, with
#: 1-3 pushes; the soak of issue 37).
PROFILES = ("short", "long")
LONG_DURATION_S = 20.0
LONG_COURSES = ("gap", "stepping-stones", "uneven")
LONG_PUSH_COUNT_PROBABILITIES = (0.0, 0.4, 0.35, 0.25)  # 1, 2 or 3 pushes

#: How each controller handles a failed solve (for the report).
FAILURE_HANDLING = {
    "kd": "QPSolveError caught in KDWalkController._solve: the last good plan is kept",
    "gaitnet": "as kd (the same KDWalkController, with the Gait-Net dt policy)",
    "srbm": "QPSolveError caught in SRBMWalkController: the last good wrench is kept",
    "wbmpc": "an unsuccessful NLP solve is not a fallback: its iterate is used as the plan",
    "stand": "no MPC",
}


# ----------------------------------------------------------------------------- episodes
@dataclass(frozen=True)
class EpisodeSpec:
    """One soak episode: everything needed to replay it.

    Attributes:
        index: episode number K (the draw's second seed).
        controller: registry name.
        robot: robot name.
        course: built-in course name.
        course_seed: layout seed of a seeded course (None: its default layout).
        vx_mps, vy_mps, yaw_rate_radps: velocity command.
        duration_s: simulated time [s].
        pushes: ``(t_s, fx_n, fy_n, fz_n, duration_s)`` of each push at the trunk CoM.
        payload_kg: unknown mass added to the trunk [kg].
    """

    index: int
    controller: str
    robot: str
    course: str
    course_seed: int | None
    vx_mps: float
    vy_mps: float
    yaw_rate_radps: float
    duration_s: float
    pushes: tuple[tuple[float, float, float, float, float], ...] = ()
    payload_kg: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "pushes": [list(p) for p in self.pushes]}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> EpisodeSpec:
        pushes = tuple(tuple(float(x) for x in p) for p in data.get("pushes", ()))
        return cls(**{**data, "pushes": pushes})  # type: ignore[arg-type]

    def label(self) -> str:
        """A one-line description for the report."""
        course = self.course if self.course_seed is None else f"{self.course}#{self.course_seed}"
        text = (
            f"{self.controller} on {self.robot}, {course}, vx {self.vx_mps:g} m/s, "
            f"{self.duration_s:g} s"
        )
        if self.vy_mps or self.yaw_rate_radps:
            text += f", vy {self.vy_mps:g} m/s, yaw rate {self.yaw_rate_radps:g} rad/s"
        if self.pushes:
            text += f", {len(self.pushes)} push(es)"
        if self.payload_kg:
            text += f", payload {self.payload_kg:g} kg"
        return text


@dataclass(frozen=True)
class DrawSettings:
    """What the episodes are drawn from (part of a soak's identity: resuming checks it).

    Attributes:
        seed: base seed; episode K uses ``numpy.random.default_rng([seed, K])``.
        controllers: the controllers drawn from (weights of :data:`CONTROLLER_WEIGHTS`).
        max_duration_s: cap on every drawn duration [s] (None: no cap).
        profile: one of :data:`PROFILES`.
    """

    seed: int = 0
    controllers: tuple[str, ...] = tuple(CONTROLLER_WEIGHTS)
    max_duration_s: float | None = None
    profile: str = "short"

    def __post_init__(self) -> None:
        from gaitnet_mpc.errors import ConfigError

        unknown = sorted(set(self.controllers) - set(CONTROLLER_WEIGHTS))
        if not self.controllers or unknown:
            raise ConfigError(
                "--controllers",
                ",".join(self.controllers),
                f"names among {list(CONTROLLER_WEIGHTS)}",
            )
        if self.max_duration_s is not None and not (
            math.isfinite(self.max_duration_s) and self.max_duration_s >= 0.01
        ):
            raise ConfigError("--max-duration-s", self.max_duration_s, "a duration >= 0.01 s")
        if self.profile not in PROFILES:
            raise ConfigError("--profile", self.profile, f"one of {list(PROFILES)}")

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "controllers": list(self.controllers)}

    def command_flags(self) -> str:
        """The command-line flags that reproduce these settings."""
        flags = f"--seed {self.seed}"
        if tuple(self.controllers) != tuple(CONTROLLER_WEIGHTS):
            flags += f" --controllers {','.join(self.controllers)}"
        if self.max_duration_s is not None:
            flags += f" --max-duration-s {self.max_duration_s:g}"
        if self.profile != "short":
            flags += f" --profile {self.profile}"
        return flags


def draw_episode(settings: DrawSettings, index: int) -> EpisodeSpec:
    """Episode ``index`` of ``settings`` (depends on nothing else)."""
    from gaitnet_mpc.terrain import BUILTIN_COURSES, SEEDED_COURSES

    rng = np.random.default_rng([settings.seed, index])
    names = list(settings.controllers)
    weights = np.array([CONTROLLER_WEIGHTS[n] for n in names])
    controller = names[int(rng.choice(len(names), p=weights / weights.sum()))]
    robot = ROBOT_NAMES[int(rng.integers(len(ROBOT_NAMES)))]
    long = settings.profile == "long"
    if long:
        course = LONG_COURSES[int(rng.integers(len(LONG_COURSES)))]
        course_seed: int | None = int(rng.integers(2**31))
        duration_s = LONG_DURATION_S
    else:
        others = sorted(c for c in BUILTIN_COURSES if c != "flat")
        flat = rng.random() < FLAT_PROBABILITY
        course = "flat" if flat else others[int(rng.integers(len(others)))]
        course_seed = None
        if course in SEEDED_COURSES and rng.random() < RANDOM_LAYOUT_PROBABILITY:
            course_seed = int(rng.integers(2**31))
        lo, hi = WBMPC_DURATION_RANGE_S[robot] if controller == "wbmpc" else DURATION_RANGE_S
        duration_s = round(float(rng.uniform(lo, hi)), 2)
    if settings.max_duration_s is not None:
        duration_s = min(duration_s, settings.max_duration_s)
    vx = vy = yaw_rate = 0.0
    if controller != "stand":
        vx = round(float(rng.uniform(*VX_RANGE_MPS)), 2)
        if robot == "humanoid3d" and rng.random() < TURN_PROBABILITY:
            vy = round(float(rng.uniform(-VY_MAX_MPS, VY_MAX_MPS)), 2)
            yaw_rate = round(float(rng.uniform(-YAW_RATE_MAX_RADPS, YAW_RATE_MAX_RADPS)), 2)
    pushes = []
    counts = LONG_PUSH_COUNT_PROBABILITIES if long else PUSH_COUNT_PROBABILITIES
    n_pushes = int(rng.choice(len(counts), p=counts))
    for _ in range(n_pushes):
        t_s = round(float(rng.uniform(PUSH_START_S, max(duration_s, PUSH_START_S))), 3)
        force_n = float(rng.uniform(*PUSH_FORCE_RANGE_N))
        angle_rad = float(rng.uniform(0.0, 2.0 * np.pi))
        fx, fy = round(force_n * math.cos(angle_rad), 1), round(force_n * math.sin(angle_rad), 1)
        pushes.append((t_s, fx, fy, 0.0, round(float(rng.uniform(*PUSH_DURATION_RANGE_S)), 3)))
    payload_kg = 0.0
    if rng.random() < PAYLOAD_PROBABILITY:
        payload_kg = round(float(rng.uniform(*PAYLOAD_RANGE_KG)), 2)
    return EpisodeSpec(
        index=index,
        controller=controller,
        robot=robot,
        course=course,
        course_seed=course_seed,
        vx_mps=vx,
        vy_mps=vy,
        yaw_rate_radps=yaw_rate,
        duration_s=duration_s,
        pushes=tuple(sorted(pushes)),
        payload_kg=payload_kg,
    )


# ----------------------------------------------------------------------------- worker
@dataclass
class _Built:
    """The objects of an episode, kept so that a failure can still be inspected."""

    controller: Any = None
    sim: Any = None
    command: Any = None


def _build(spec: EpisodeSpec, built: _Built) -> None:
    """Make the controller and simulator of ``spec`` as ``gaitnet-mpc run`` does."""
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.scenario import build_episode, make_scenario
    from gaitnet_mpc.sim.disturbances import Push
    from gaitnet_mpc.sim.simulator import check_payload

    robot = load_robot(spec.robot)
    check_payload(spec.payload_kg, robot.total_mass_kg, "payload_kg")
    scenario = make_scenario(
        robot=spec.robot,
        controller=spec.controller,
        course=spec.course,
        course_seed=spec.course_seed,
        vx_mps=spec.vx_mps,
        vy_mps=spec.vy_mps,
        yaw_rate_radps=spec.yaw_rate_radps,
        duration_s=spec.duration_s,
        pushes=tuple(Push(p[0], (p[1], p[2], p[3]), p[4]) for p in spec.pushes),
        payload_kg=spec.payload_kg,
    )
    episode = build_episode(scenario, robot=robot)
    built.command, built.controller, built.sim = scenario.command, episode.controller, episode.sim


def simulate(spec: EpisodeSpec, built: _Built | None = None) -> dict[str, Any]:
    """Run ``spec`` (exceptions propagate); return the episode summary."""
    from gaitnet_mpc.runner.episode import run_episode

    built = _Built() if built is None else built
    _build(spec, built)
    return run_episode(built.sim, built.controller, built.command, spec.duration_s, progress=False)


def _solve_counts(controller: Any) -> dict[str, int]:
    """Solves, unconverged solves and failed solves (QP / NLP failures the controller
    handled) from the controller's :class:`~gaitnet_mpc.control.base.MPCStats`."""
    stats = None if controller is None else controller.mpc_stats
    if stats is None:
        return {"solves": 0, "unconverged": 0, "qp_failures": 0}
    summary = stats.summary()
    return {
        "solves": int(summary["solves"] or 0),
        "unconverged": sum(not c for c in stats.converged),
        "qp_failures": int(summary["failed_solves"] or 0),
    }


def _mujoco_warnings(sim: Any) -> dict[str, int]:
    """MuJoCo's warning counters that are non-zero, by name."""
    import mujoco

    out = {}
    for i, n in enumerate(sim.data.warning.number):
        if n:
            out[mujoco.mjtWarning(i).name.removeprefix("mjWARN_")] = int(n)
    return out


def run_spec(spec_dict: dict[str, Any]) -> dict[str, Any]:
    """Worker body: run one episode, catching everything; return its JSON record."""
    from gaitnet_mpc.errors import ConfigError

    os.environ.setdefault("MUJOCO_GL", "egl")
    spec = EpisodeSpec.from_dict(spec_dict)
    built = _Built()
    summary: dict[str, Any] | None = None
    error: BaseException | None = None
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            summary = simulate(spec, built)
        except Exception as exc:  # a soak records failures, it does not stop on them
            error = exc
    wall_s = time.perf_counter() - t0
    sim = built.sim
    record: dict[str, Any] = {
        "index": spec.index,
        "spec": spec.to_dict(),
        "wall_s": round(wall_s, 3),
        "sim_s": None if sim is None else round(float(sim.time_s), 4),
        "exception": None,
        "nonfinite_torque": False,
        "diverged": False,
        "fell": False,
        "fall_reason": None,
        "mujoco_warnings": {} if sim is None else _mujoco_warnings(sim),
        "python_warnings": sorted({f"{w.category.__name__}: {w.message}" for w in caught})[:5],
        **_solve_counts(built.controller),
    }
    if sim is not None:
        record["diverged"] = bool(sim.diverged) or not bool(np.all(np.isfinite(sim.data.qpos)))
        record["fell"] = bool(sim.fall.fell) and not sim.diverged
        record["fall_reason"] = sim.fall.reason or None
    if summary is not None and summary.get("diverged"):
        record["diverged"] = True
    if error is not None:
        frame = traceback.extract_tb(error.__traceback__)[-1]
        record["exception"] = {
            "type": type(error).__name__,
            "message": str(error)[:500],
            "where": f"{Path(frame.filename).name}:{frame.lineno} in {frame.name}",
            "traceback": "".join(traceback.format_exception(error))[-4000:],
        }
        record["nonfinite_torque"] = (
            isinstance(error, ConfigError)
            and error.field == "tau_nm"
            and str(error.expected).startswith("finite")
        )
    return record


# ----------------------------------------------------------------------------- runners
def _worker_died(spec: EpisodeSpec, exc: BaseException) -> dict[str, Any]:
    """The record of an episode whose worker process died (segfault, OOM kill)."""
    return {
        "index": spec.index,
        "spec": spec.to_dict(),
        "wall_s": None,
        "sim_s": None,
        "exception": {
            "type": type(exc).__name__,
            "message": f"the worker died: {exc}"[:500],
            "where": "worker process",
            "traceback": "",
        },
        "nonfinite_torque": False,
        "diverged": False,
        "fell": False,
        "fall_reason": None,
        "mujoco_warnings": {},
        "python_warnings": [],
        "solves": 0,
        "unconverged": 0,
        "qp_failures": 0,
    }


def _records(
    outcomes: Generator[Outcome[dict[str, Any], dict[str, Any]], None, None],
) -> Generator[dict[str, Any], None, None]:
    """The episodes' records: :func:`run_spec`'s, or :func:`_worker_died`'s for an episode
    whose worker died (any other error, e.g. a spec that cannot be sent, stops the soak).
    Closing this generator closes ``outcomes`` (which stops the workers)."""
    with closing(outcomes):
        for outcome in outcomes:
            if outcome.worker_died and outcome.error is not None:
                yield _worker_died(EpisodeSpec.from_dict(outcome.item), outcome.error)
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


# ----------------------------------------------------------------------------- storage
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


# ----------------------------------------------------------------------------- report
@dataclass
class _Tally:
    episodes: int = 0
    exceptions: int = 0
    nonfinite: int = 0
    diverged: int = 0
    qp_failures: int = 0
    episodes_with_qp_failures: int = 0
    unconverged: int = 0
    solves: int = 0
    falls: int = 0
    sim_s: float = 0.0
    wall_s: float = 0.0
    walls: list[float] = field(default_factory=list)

    def add(self, r: dict[str, Any]) -> None:
        self.episodes += 1
        self.exceptions += r["exception"] is not None and not r["nonfinite_torque"]
        self.nonfinite += bool(r["nonfinite_torque"])
        self.diverged += bool(r["diverged"])
        self.qp_failures += int(r["qp_failures"])
        self.episodes_with_qp_failures += r["qp_failures"] > 0
        self.unconverged += int(r["unconverged"])
        self.solves += int(r["solves"])
        self.falls += bool(r["fell"])
        self.sim_s += float(r["sim_s"] or 0.0)
        self.wall_s += float(r["wall_s"] or 0.0)
        self.walls.append(float(r["wall_s"] or 0.0))


def _failing(r: dict[str, Any]) -> bool:
    return r["exception"] is not None or bool(r["nonfinite_torque"]) or bool(r["diverged"])


def make_report(
    records: dict[int, dict[str, Any]],
    settings: DrawSettings,
    n_episodes: int,
    command_line: str,
    run_wall_s: float,
    interrupted: bool,
) -> str:
    """The Markdown report of the finished episodes."""
    from gaitnet_mpc.experiments.collect import provenance

    prov = provenance()
    rows = [records[i] for i in sorted(records) if i < n_episodes]
    cells: dict[tuple[str, str], _Tally] = {}
    by_controller: dict[str, _Tally] = {}
    total = _Tally()
    for r in rows:
        key = (r["spec"]["controller"], r["spec"]["robot"])
        cells.setdefault(key, _Tally()).add(r)
        by_controller.setdefault(key[0], _Tally()).add(r)
        total.add(r)
    state = "interrupted, " if interrupted else ""
    lines = [
        "# Soak test: random episodes",
        "",
        f"Machine: {machine_info(('numpy', 'mujoco', 'pin', 'casadi', 'piqp', 'ray'))}.",
        f"Code: gaitnet_mpc {prov['gaitnet_mpc']}, commit {prov['git_commit']}.",
        "",
        f"Command: `{command_line}`. Settings: {json.dumps(settings.to_dict())}.",
        "",
        f"{len(rows)} of {n_episodes} episodes done ({state}{total.sim_s:.1f} simulated s); "
        f"wall time of the episodes {total.wall_s:.0f} s (summed over workers), of this "
        f"invocation {run_wall_s:.0f} s.",
        "",
        "| controller | robot | episodes | exceptions | non-finite torques | diverged | "
        "QP failures handled (episodes) | unconverged / solves | falls | sim [s] | wall [s] |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (controller, robot), t in sorted(cells.items()):
        lines.append(
            f"| {controller} | {robot} | {t.episodes} | {t.exceptions} | {t.nonfinite} | "
            f"{t.diverged} | {t.qp_failures} ({t.episodes_with_qp_failures}) | "
            f"{t.unconverged} / {t.solves} | {t.falls} | {t.sim_s:.1f} | {t.wall_s:.0f} |"
        )
    t = total
    lines.append(
        f"| **all** | | {t.episodes} | {t.exceptions} | {t.nonfinite} | {t.diverged} | "
        f"{t.qp_failures} ({t.episodes_with_qp_failures}) | {t.unconverged} / {t.solves} | "
        f"{t.falls} | {t.sim_s:.1f} | {t.wall_s:.0f} |"
    )
    lines += [
        "",
        "Falls exclude diverged simulations. Wall time per episode, for sizing runs:",
        "",
        "| controller | episodes | wall per episode [s] (median, max) | wall per sim-s [s] |",
        "|---|---|---|---|",
    ]
    for name, t in sorted(by_controller.items()):
        lines.append(
            f"| {name} | {t.episodes} | {np.median(t.walls):.1f}, {max(t.walls):.1f} | "
            f"{t.wall_s / max(t.sim_s, 1e-9):.1f} |"
        )
    lines += ["", "How a failed solve is handled:", ""]
    lines += [f"- {name}: {FAILURE_HANDLING[name]}" for name in sorted(by_controller)]
    handled = [r for r in rows if r["qp_failures"]]
    if handled:
        lines += ["", "## QP failures handled, by episode", ""]
        lines += [
            f"- episode {r['index']} ({EpisodeSpec.from_dict(r['spec']).label()}): "
            f"{r['qp_failures']} of {r['solves']} solves"
            + (f", then fell ({r['fall_reason']})" if r["fell"] else ", no fall")
            for r in handled
        ]
    failing = [r for r in rows if _failing(r)]
    lines += ["", "## Episodes to replay", ""]
    if not failing:
        lines.append("- none: no exception, non-finite torque or diverged simulation")
    for r in failing:
        spec = EpisodeSpec.from_dict(r["spec"])
        exc = r["exception"]
        if exc is not None:
            what = f"{exc['type']}: {exc['message']} ({exc['where']})"
        else:
            what = f"diverged: {r['fall_reason']}"
        lines += [
            f"- episode {spec.index} ({spec.label()}): {what}",
            f"  - replay: `MUJOCO_GL=egl .venv/bin/python benchmarks/soak.py "
            f"{settings.command_flags()} --replay {spec.index}`",
            f"  - spec: `{json.dumps(r['spec'])}`",
        ]
    warned = [r for r in rows if r["python_warnings"] or r["mujoco_warnings"]]
    if warned:
        lines += ["", "## Warnings", ""]
        for r in warned[:30]:
            text = "; ".join(r["python_warnings"])
            if r["mujoco_warnings"]:
                text = f"MuJoCo {r['mujoco_warnings']}; {text}"
            lines.append(f"- episode {r['index']}: {text[:300]}")
        if len(warned) > 30:
            lines.append(f"- ... {len(warned) - 30} more episodes (see the JSONL)")
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------- driver
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


def replay(settings: DrawSettings, index: int) -> int:
    """Run episode ``index`` here, letting any exception propagate; print its outcome."""
    spec = draw_episode(settings, index)
    print(json.dumps(spec.to_dict()))
    print(spec.label(), flush=True)
    summary = simulate(spec)
    keys = ("fell", "fall_time_s", "fall_reason", "diverged", "wall_time_s", "mpc")
    brief = {k: summary.get(k) for k in keys}
    print(json.dumps(brief, indent=2))
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=12)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--backend", choices=("process", "ray"), default="process")
    parser.add_argument("--address", default=None, help="Ray cluster address (--backend ray)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--controllers",
        default=",".join(CONTROLLER_WEIGHTS),
        help="controllers to draw from (default: %(default)s)",
    )
    parser.add_argument("--max-duration-s", type=float, default=None, help="cap on durations")
    parser.add_argument(
        "--profile",
        choices=PROFILES,
        default="short",
        help="short: 1-5 s on every course; long: 20 s on seeded stones, gaps, uneven tiles "
        "with 1-3 pushes (default: %(default)s)",
    )
    parser.add_argument("--out", type=Path, default=RESULTS / "soak.md")
    parser.add_argument("--work-dir", type=Path, default=None, help="default: --out's folder")
    parser.add_argument("--replay", type=int, default=None, metavar="K", help="run episode K")
    args = parser.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # inherited by the workers
    settings = DrawSettings(
        args.seed,
        tuple(c for c in args.controllers.split(",") if c),
        args.max_duration_s,
        args.profile,
    )
    if args.replay is not None:
        return replay(settings, args.replay)
    options = SoakOptions(
        args.episodes, args.workers, args.backend, args.out, args.work_dir, args.address
    )
    command = "MUJOCO_GL=egl .venv/bin/python benchmarks/soak.py " + " ".join(
        sys.argv[1:] if argv is None else argv
    )
    records = soak(options, settings, command)
    done = sum(i < options.episodes for i in records)
    return 0 if done == options.episodes else 130


if __name__ == "__main__":
    sys.exit(main())
