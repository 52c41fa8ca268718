"""``gaitnet-mpc bench``: where the closed loop's time goes, measured (issue 17's targets).

One *case* is a walking controller with a preset and settings overrides (``kd``; ``kd``
with ``--preset realtime``, the real-time-iteration replan; ...). :func:`run_bench`
walks every case on the same course for the same simulated time, ``rounds`` times, each
episode in a fresh process and the cases interleaved (``a b c a b c ...``), so that the
load of a shared machine hits all of them alike; the closed loop is deterministic, so
round ``i`` of a case solves the same problems as round ``j`` and each timing is taken as
its minimum over the rounds. Per case it reports:

* the sequential solve at a step start (``full``: Algorithm 1 with the dt policy) and the
  replans within a step: median and p99 wall time [ms], QPs per solve;
* the low-level tick: ``Controller.compute`` on the 1 kHz ticks without an MPC solve (swing
  trajectory, IK, Jacobians, PD and torque mapping) [ms];
* the simulator's step (MuJoCo, contact read-out, fall checks) [ms];
* the real-time factor: simulated time / wall time of controller + simulator (no logs);
* the physical outcome (fell, distance), so that a faster case is not a worse walker.

:func:`profile_parts` runs one more episode under :mod:`cProfile` and splits the solve time
into the condensed QP, the reference updates (f_IK, f_ref) and their trunk placement.
:func:`memory_episode` reads the resident set size at the start and end of one long
episode. :func:`perf_markdown` writes it all as ``perf.md``.
"""

from __future__ import annotations

import cProfile
import fnmatch
import json
import os
import pstats
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.machine import machine_info

#: Issue 17's targets: solve and tick times [ms], real-time factor.
TARGETS = {
    "full_median_ms": 5.0,
    "full_p99_ms": 12.0,
    "replan_median_ms": 1.5,
    "tick_median_ms": 0.2,
    "rtf": 1.5,
}


@dataclass(frozen=True)
class BenchCase:
    """One timed configuration: a controller of the ``kd`` family and ``--set`` overrides;
    with ``revision``, the package as it was at that git revision (before/after)."""

    label: str
    controller: str = "kd"
    overrides: tuple[str, ...] = ()
    revision: str | None = None
    preset: str | None = None  # a settings preset under the overrides (None: default)


def parse_case(text: str) -> BenchCase:
    """``LABEL=CONTROLLER[:KEY=VALUE,...]`` (``--case``) -> :class:`BenchCase`.

    Raises:
        ConfigError: no label or no controller.
    """
    label, sep, rest = text.partition("=")
    controller, _, sets = rest.partition(":")
    if not sep or not label or not controller:
        expected = "LABEL=CONTROLLER[:KEY=VALUE,...], e.g. rti=kd:replan_j_max=1"
        raise ConfigError("--case", text, expected)
    return BenchCase(label, controller, tuple(x for x in sets.split(",") if x))


#: The default cases: kd and gaitnet as shipped and with ``--preset realtime`` (one QP per replan).
DEFAULT_CASES = (
    BenchCase("kd"),
    BenchCase("kd --preset realtime", "kd", preset="realtime"),
    BenchCase("gaitnet"),
    BenchCase("gaitnet --preset realtime", "gaitnet", preset="realtime"),
)


@dataclass(frozen=True)
class EpisodeSpec:
    """The episode every case walks."""

    course: str = "flat"
    vx_mps: float = 0.75
    seconds: float = 4.0
    robot: str = "humanoid3d"

    def __post_init__(self) -> None:
        if not (np.isfinite(self.seconds) and self.seconds > 0.0):
            raise ConfigError("--seconds", self.seconds, "a finite time > 0 s")


@dataclass
class EpisodeTiming:
    """Raw timings of one episode (times in ms)."""

    solve_ms: list[float] = field(default_factory=list)
    full: list[bool] = field(default_factory=list)
    qps: list[int] = field(default_factory=list)
    tick_ms: list[float] = field(default_factory=list)  # compute() without a solve
    sim_ms: list[float] = field(default_factory=list)  # state() + step()
    wall_s: float = 0.0
    sim_s: float = 0.0
    fell: bool = False
    distance_m: float = 0.0
    rss_start_mb: float = 0.0
    rss_end_mb: float = 0.0


def rss_mb() -> float:
    """Resident set size of this process [MB] (Linux ``/proc``; elsewhere the peak)."""
    try:
        with open("/proc/self/statm") as fh:
            pages = int(fh.read().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / 1e6
    except (OSError, ValueError):
        import resource

        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3


def build_case(case: BenchCase, spec: EpisodeSpec) -> tuple[Any, Any]:
    """(simulator, controller) of one episode.

    Raises:
        ConfigError: an unknown controller or a bad override.
    """
    from gaitnet_mpc.control.registry import KD_FAMILY

    if case.controller not in KD_FAMILY:
        raise ConfigError("bench controller", case.controller, f"one of {KD_FAMILY}")
    try:
        from gaitnet_mpc.scenario import build_episode, make_scenario
    except ImportError:  # a --baseline revision from before the scenario API (2026-12)
        return _build_case_before_scenarios(case, spec)
    scenario = make_scenario(
        robot=spec.robot,
        controller=case.controller,
        course=spec.course,
        vx_mps=spec.vx_mps,
        duration_s=spec.seconds,
        preset=case.preset,
        overrides=tuple(case.overrides),
    )
    episode = build_episode(scenario)
    return episode.sim, episode.controller


def _build_case_before_scenarios(case: BenchCase, spec: EpisodeSpec) -> tuple[Any, Any]:
    """:func:`build_case` with the package of a revision that has no ``scenario`` module."""
    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.registry import (
        ControllerContext,
        controller_config,
        make_controller,
    )
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.sim.simulator import Simulator
    from gaitnet_mpc.terrain import load_course

    robot, course = load_robot(spec.robot), load_course(spec.course)
    if case.preset is not None:  # no presets before the scenario API
        raise ConfigError("bench case preset", case.preset, "None at this revision")
    config = controller_config(case.controller, robot.spec.planar, overrides=list(case.overrides))
    ctx = ControllerContext(robot, course, Command(vx_mps=spec.vx_mps), config=config)
    return Simulator(robot, course), make_controller(case.controller, ctx)


def timed_episode(
    case: BenchCase,
    spec: EpisodeSpec,
    profiler: cProfile.Profile | None = None,
    on_second: Callable[[float], None] | None = None,
    record_ticks: bool = True,
) -> EpisodeTiming:
    """Walk ``spec`` with ``case`` and time every tick (stops at a fall). With
    ``record_ticks=False`` the per-tick times are not kept (a long memory episode:
    1000 list entries per simulated second would be the growth it measures)."""
    sim, ctrl = build_case(case, spec)
    state = sim.state()
    ctrl.reset(state)
    x0 = float(state.qpos[0])
    out = EpisodeTiming(rss_start_mb=rss_mb())
    stats = ctrl.mpc_stats
    clock = time.perf_counter
    n_ticks = round(spec.seconds / sim.config.timestep_s)
    ticks_per_s = round(1.0 / sim.config.timestep_s)
    if profiler is not None:
        profiler.enable()
    t_start = clock()
    for tick in range(n_ticks):
        n_solves = len(stats.solve_time_s)
        t0 = clock()
        tau = ctrl.compute(state)
        t1 = clock()
        sim.step(tau)
        state = sim.state()
        t2 = clock()
        if record_ticks:
            if len(stats.solve_time_s) == n_solves:
                out.tick_ms.append(1e3 * (t1 - t0))
            out.sim_ms.append(1e3 * (t2 - t1))
        if sim.fall.fell:
            break
        if on_second is not None and (tick + 1) % ticks_per_s == 0:
            on_second(sim.time_s)
    out.wall_s = clock() - t_start
    if profiler is not None:
        profiler.disable()
    out.solve_ms = [1e3 * t for t in stats.solve_time_s]
    out.full = [bool(f) for f in stats.full_solve]
    out.qps = [int(n) for n in stats.qps_per_solve]
    out.sim_s = float(sim.time_s)
    out.fell = bool(sim.fall.fell)
    out.distance_m = float(state.qpos[0]) - x0
    out.rss_end_mb = rss_mb()
    return out


# --------------------------------------------------------------------------- interleaving
def _episode_in_subprocess(
    case: BenchCase, spec: EpisodeSpec, out: Path, source: Path | None = None
) -> EpisodeTiming:
    """:func:`timed_episode` in a fresh Python process (no warm caches, no shared heap);
    with ``source``, the package is imported from that ``src`` folder (this file's
    :func:`timed_episode` drives it, so both sides are timed the same way)."""
    payload = json.dumps({"case": asdict(case), "spec": asdict(spec), "out": str(out)})
    env = dict(os.environ)
    if source is not None:
        env["PYTHONPATH"] = str(source)
    # run_path, not ``python FILE``: the file's folder must not shadow top-level modules
    runner = f"import runpy; runpy.run_path({str(Path(__file__))!r}, run_name='__main__')"
    subprocess.run([sys.executable, "-c", runner, payload], check=True, env=env)
    return EpisodeTiming(**json.loads(out.read_text()))


def export_revision(revision: str, folder: Path) -> Path:
    """The ``src`` folder of git revision ``revision`` of this repository, written under
    ``folder``.

    Raises:
        ConfigError: not a git checkout, or an unknown revision.
    """
    repo = Path(__file__).resolve().parents[3]  # src/gaitnet_mpc/experiments/bench.py
    archive = subprocess.run(
        ["git", "-C", str(repo), "archive", "--format=tar", revision, "src"],
        capture_output=True,
    )
    if archive.returncode != 0:
        raise ConfigError("--baseline", revision, "a git revision of this checkout")
    target = folder / revision
    target.mkdir(parents=True, exist_ok=True)
    subprocess.run(["tar", "-x", "-C", str(target)], input=archive.stdout, check=True)
    return target / "src"


@dataclass(frozen=True)
class CaseResult:
    """One case over its rounds: per-solve and per-tick minima over the rounds [ms]."""

    case: BenchCase
    solve_ms: np.ndarray
    full: np.ndarray
    qps: np.ndarray
    tick_ms: np.ndarray
    sim_ms: np.ndarray
    rtf: float  # best over the rounds
    sim_s: float
    fell: bool
    distance_m: float
    identical_rounds: bool  # every round solved the same number of QPs per solve

    def row(self) -> dict[str, float]:
        """Summary numbers (ms unless named)."""
        full, rep = self.solve_ms[self.full], self.solve_ms[~self.full]

        def pct(x: np.ndarray, p: float) -> float:
            return float(np.percentile(x, p)) if x.size else float("nan")

        return {
            "full_median_ms": pct(full, 50),
            "full_p99_ms": pct(full, 99),
            "full_qps": float(self.qps[self.full].mean()) if full.size else float("nan"),
            "replan_median_ms": pct(rep, 50),
            "replan_p99_ms": pct(rep, 99),
            "replan_qps": float(self.qps[~self.full].mean()) if rep.size else float("nan"),
            "tick_median_ms": pct(self.tick_ms, 50),
            "sim_median_ms": pct(self.sim_ms, 50),
            "rtf": self.rtf,
        }


def _combine(case: BenchCase, runs: list[EpisodeTiming]) -> CaseResult:
    """Minimum over the rounds of each solve and tick (the rounds are the same episode)."""
    n_solve = min(len(r.solve_ms) for r in runs)
    n_tick = min(len(r.tick_ms) for r in runs)
    n_sim = min(len(r.sim_ms) for r in runs)
    first = runs[0]
    return CaseResult(
        case=case,
        solve_ms=np.min([r.solve_ms[:n_solve] for r in runs], axis=0),
        full=np.asarray(first.full[:n_solve], dtype=bool),
        qps=np.asarray(first.qps[:n_solve]),
        tick_ms=np.min([r.tick_ms[:n_tick] for r in runs], axis=0),
        sim_ms=np.min([r.sim_ms[:n_sim] for r in runs], axis=0),
        rtf=max(r.sim_s / r.wall_s for r in runs),
        sim_s=first.sim_s,
        fell=first.fell,
        distance_m=first.distance_m,
        identical_rounds=all(r.qps == first.qps for r in runs),
    )


def run_bench(
    cases: Sequence[BenchCase],
    spec: EpisodeSpec,
    rounds: int = 3,
    progress: Callable[[str], None] | None = None,
) -> list[CaseResult]:
    """Every case ``rounds`` times, interleaved, each episode in a fresh process."""
    if rounds < 1:
        raise ConfigError("--rounds", rounds, "an integer >= 1")
    runs: dict[int, list[EpisodeTiming]] = {i: [] for i in range(len(cases))}
    with tempfile.TemporaryDirectory() as tmp:
        sources = {
            rev: export_revision(rev, Path(tmp))
            for rev in {c.revision for c in cases if c.revision is not None}
        }
        for r in range(rounds):
            for i, case in enumerate(cases):
                if progress is not None:
                    progress(f"round {r + 1}/{rounds}: {case.label}")
                source = None if case.revision is None else sources[case.revision]
                out = Path(tmp) / f"{i}.json"
                runs[i].append(_episode_in_subprocess(case, spec, out, source))
    return [_combine(case, runs[i]) for i, case in enumerate(cases)]


# --------------------------------------------------------------------------- profile
#: Profile rows: label -> (file name, function name pattern[, caller's file name]) of the
#: profiled function; with a caller, only the time of calls made from that file counts.
PARTS: dict[str, tuple[str, ...]] = {
    "condensed QP (KDSubproblem._solve_condensed: kernels + DAQP)": (
        "implicit_kd.py",
        "_solve_condensed",
    ),
    "  of which the condensing (KDSubproblem.condensed_qp)": ("implicit_kd.py", "condensed_qp"),
    "  of which DAQP and the expansion (KDCondensed.solve)": ("kd_condensed.py", "solve"),
    "sparse QP fallback (QPWorkspace.solve: PIQP)": ("workspace.py", "solve"),
    "QP input checks (KDSubproblem.inputs)": ("implicit_kd.py", "inputs"),
    "f_IK update_reference": ("reference.py", "update_reference"),
    "f_ref make_reference": ("reference.py", "make_reference"),
    "  in f_IK + f_ref: trunk placement (ReferenceWorkspace.place_trunk, compiled)": (
        "reference_workspace.py",
        "place_trunk",
    ),
    "dt policy (Gait-Net forward pass and features)": ("policy.py", "__call__"),
}


def profile_parts(stats: pstats.Stats, total_s: float) -> list[tuple[str, float, float]]:
    """(label, seconds, share of ``total_s``) of each :data:`PARTS` row."""
    rows = []
    for label, (file_name, function, *caller) in PARTS.items():
        cum = 0.0
        for (path, _, name), v in stats.stats.items():  # type: ignore[attr-defined]
            if fnmatch.fnmatchcase(name, function) and Path(path).name == file_name:
                if caller:  # only the calls made from the caller's file
                    cum += sum(c[3] for k, c in v[4].items() if Path(k[0]).name == caller[0])
                else:
                    cum += v[3]
        rows.append((label, cum, cum / max(total_s, 1e-9)))
    return rows


def profiled_episode(case: BenchCase, spec: EpisodeSpec) -> list[tuple[str, float, float]]:
    """:func:`profile_parts` of one episode of ``case`` (in this process)."""
    profiler = cProfile.Profile()
    timing = timed_episode(case, spec, profiler)
    return profile_parts(pstats.Stats(profiler), 1e-3 * sum(timing.solve_ms))


# --------------------------------------------------------------------------- report
def _fmt(x: float, spec: str = ".2f") -> str:
    return "n/a" if not np.isfinite(x) else format(x, spec)


def _target_cell(key: str, value: float) -> str:
    target = TARGETS[key]
    met = value >= target if key == "rtf" else value <= target
    return f"{_fmt(value)} {'(met)' if met else f'(target {target:g})'}"


def perf_markdown(
    results: list[CaseResult],
    spec: EpisodeSpec,
    rounds: int,
    parts: list[tuple[str, float, float]] | None,
    parts_case: str,
    memory: EpisodeTiming | None,
    memory_case: str,
    command: str,
) -> str:
    """``perf.md``: the cases side by side, their ratios to the first, the profile and the
    memory episode."""
    base = results[0].row()
    lines = [
        "# Closed-loop performance",
        "",
        machine_info(("numpy", "mujoco", "pin", "piqp", "torch")),
        "",
        f"Episode: {spec.robot}, {spec.course}, vx = {spec.vx_mps} m/s, {spec.seconds} s; "
        f"{rounds} rounds per case in fresh processes, cases interleaved; each solve and "
        "tick is the minimum over the rounds (the closed loop is deterministic), the "
        "real-time factor the best round. The machine is shared: compare numbers of one "
        "run, not across runs.",
        "",
        "| case | full solve median ms | full p99 ms | QPs per full solve | replan median ms "
        "| replan p99 ms | QPs per replan | low-level tick median ms | sim step median ms "
        "| real-time factor | outcome |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for res in results:
        r = res.row()
        outcome = "FELL" if res.fell else "walked"
        outcome += f" {res.distance_m:.2f} m in {res.sim_s:.1f} s"
        if not res.identical_rounds:
            outcome += " (rounds differ)"
        lines.append(
            f"| {res.case.label} | {_target_cell('full_median_ms', r['full_median_ms'])} | "
            f"{_target_cell('full_p99_ms', r['full_p99_ms'])} | {_fmt(r['full_qps'], '.1f')} | "
            f"{_target_cell('replan_median_ms', r['replan_median_ms'])} | "
            f"{_fmt(r['replan_p99_ms'])} | {_fmt(r['replan_qps'], '.1f')} | "
            f"{_target_cell('tick_median_ms', r['tick_median_ms'])} | "
            f"{_fmt(r['sim_median_ms'], '.3f')} | {_target_cell('rtf', r['rtf'])} | {outcome} |"
        )
    lines += [
        "",
        f"Ratios to `{results[0].case.label}` (same run; > 1 = faster):",
        "",
        "| case | full solve | replan | low-level tick | real-time factor |",
        "|---|---|---|---|---|",
    ]
    for res in results:
        r = res.row()
        lines.append(
            f"| {res.case.label} | {_fmt(base['full_median_ms'] / r['full_median_ms'])}x | "
            f"{_fmt(base['replan_median_ms'] / r['replan_median_ms'])}x | "
            f"{_fmt(base['tick_median_ms'] / r['tick_median_ms'])}x | "
            f"{_fmt(r['rtf'] / base['rtf'])}x |"
        )
    if parts is not None:
        lines += [
            "",
            f"Where the solve time of `{parts_case}` goes (one more episode under cProfile, "
            "which inflates Python-heavy parts):",
            "",
            "| part | seconds | share of solve time |",
            "|---|---|---|",
            *[f"| {label} | {s:.2f} | {100 * share:.0f} % |" for label, s, share in parts],
        ]
    if memory is not None:
        growth = memory.rss_end_mb - memory.rss_start_mb
        lines += [
            "",
            f"Memory: `{memory_case}`, one episode of {memory.sim_s:.0f} s simulated stepping "
            "in place (vx 0) "
            f"({'FELL' if memory.fell else 'no fall'}, {memory.wall_s:.0f} s wall): RSS "
            f"{memory.rss_start_mb:.1f} MB after set-up, {memory.rss_end_mb:.1f} MB at the "
            f"end ({growth:+.1f} MB; this includes what the run keeps by design: "
            f"{len(memory.solve_ms)} solves of per-solve statistics and the foothold log).",
        ]
    lines += ["", f"Command: `{command}`", ""]
    return "\n".join(lines)


def _worker(payload: str) -> None:
    """Entry of :func:`_episode_in_subprocess`: one timed episode, written as JSON."""
    args = json.loads(payload)
    case = BenchCase(**{**args["case"], "overrides": tuple(args["case"]["overrides"])})
    if case.revision is not None:  # this file drives the package of PYTHONPATH's revision
        case = replace(case, revision=None)
    timing = timed_episode(case, EpisodeSpec(**args["spec"]))
    Path(args["out"]).write_text(json.dumps(asdict(timing)))


if __name__ == "__main__":
    _worker(sys.argv[1])
