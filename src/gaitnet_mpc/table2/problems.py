"""Record the MPC problems the ``kd`` controller solves in closed loop (Table II's inputs).

Table II compares solving methods "on the same MPC problems"; here they are the
:class:`~gaitnet_mpc.mpc.sequential.KDProblem` objects Algorithm 1 receives while the
humanoid walks. :class:`RecordingKDMPC` is a :class:`SequentialKDMPC` that keeps a plain
copy of every problem it solves; :func:`record_problems` walks a course with it in place
of the controller's own solver (``kd_walk.py`` is not touched).

File format (:func:`save_problems` / :func:`load_problems`): one ``.npz`` of plain arrays,
no pickle. Problem ``i`` is stored under keys ``"{i}/<field>"``; a mapping field per foot
under ``"{i}/<field>.<foot>"``; optional fields are simply absent when ``None``; the
``com_reference`` callable is stored as the :class:`CoMReference` it returned at the
problem's own timing (``"{i}/com_reference.p_m"``, ``".v_mps"``) and rebuilt as a constant
callable on load (exact while the timing is the recorded one: with :class:`FixedDt` a
problem is never re-timed). The measured :class:`RobotState` of a step start (``state``)
is kept field by field, so a dt policy that reads it (Gait-Net) sees the same input.
The file-level ``"cop_fraction"`` is the recording's :attr:`RecordingSpec.cop_fraction`:
the wrench rows of the QP depend on it, so :func:`kd_solver` must be built with it to
solve the problems as they were solved in the loop.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.timing import ReferenceTiming
from gaitnet_mpc.mpc.sequential import (
    CoMReference,
    FootholdBox,
    KDProblem,
    SequentialKDMPC,
    SequentialResult,
    StepState,
)
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.state import RobotState

if TYPE_CHECKING:
    from gaitnet_mpc.control.kd_walk_config import KDWalkConfig

#: Format version written into every file (key ``"format"``); 2 added ``"cop_fraction"``.
FORMAT_VERSION = 2
#: Courses of Table II's recording (``"flat"``, ``"stepping-stones"``).
TABLE2_COURSES = ("flat", "stepping-stones")
#: Problems solved in the last this-many seconds before a fall are not recorded [s].
FALL_MARGIN_S = 0.5


# --------------------------------------------------------------------------- freeze
def _constant_reference(
    ref: CoMReference | None,
) -> Callable[[ReferenceTiming], CoMReference | None]:
    """A ``com_reference`` callable that returns ``ref`` whatever the timing."""

    def com_reference(timing: ReferenceTiming) -> CoMReference | None:
        return ref

    return com_reference


def freeze_problem(problem: KDProblem) -> KDProblem:
    """``problem`` with its arrays copied and ``com_reference`` replaced by a constant
    callable holding its value at ``problem.timing`` (what gets recorded)."""
    ref = None if problem.com_reference is None else problem.com_reference(problem.timing)
    if ref is not None:
        ref = CoMReference(np.array(ref.p_m, dtype=float), np.array(ref.v_mps, dtype=float))
    return replace(
        problem,
        q=np.array(problem.q, dtype=float),
        v=np.array(problem.v, dtype=float),
        footholds_m={f: np.array(p, dtype=float) for f, p in problem.footholds_m.items()},
        p_foot_now_m={f: np.array(p, dtype=float) for f, p in problem.p_foot_now_m.items()},
        p_liftoff_m={f: np.array(p, dtype=float) for f, p in problem.p_liftoff_m.items()},
        foot_yaw_rad=np.array(problem.foot_yaw_rad, dtype=float),
        com_reference=None if problem.com_reference is None else _constant_reference(ref),
    )


class RecordingKDMPC(SequentialKDMPC):
    """Algorithm 1 that keeps a frozen copy (:func:`freeze_problem`) of every problem.

    Attributes:
        problems: the recorded problems, in solve order.
        results: the closed-loop result of each (same order).
    """

    def __init__(self, base: SequentialKDMPC) -> None:
        super().__init__(base.robot, base.config, base.dt_policy)
        self.problems: list[KDProblem] = []
        self.results: list[SequentialResult] = []

    def solve(self, problem: KDProblem) -> SequentialResult:
        frozen = freeze_problem(problem)  # before the solve: the callable reads live state
        result = super().solve(problem)
        self.problems.append(frozen)
        self.results.append(result)
        return result


# --------------------------------------------------------------------------- record
@dataclass(frozen=True)
class RecordingSpec:
    """One closed-loop recording run.

    Attributes:
        course: built-in course name.
        vx_mps: commanded forward speed [m/s] (Table II: 0.75).
        duration_s: simulated time [s].
        dt_s: fixed MPC sampling time [s] (:class:`FixedDt`).
        skip_s: problems solved before this time are dropped (start-up transient; on the
            stepping stones, the start platform) [s].
        preview: walk with the multi-step footstep preview (``--preview``), which crosses
            the built-in stones (the one-step preview falls on them).
        seed: layout seed of a seeded course (None: the built-in layout).
        stones_only: keep only problems solved while the base is over the course's
            middle (x from the start of its second patch to the start of its last one:
            on ``stepping-stones``, the stones), and stop once past it.
        cop_fraction: :attr:`KDWalkConfig.cop_fraction` of the recording walk. Default
            1.0, the paper's whole foot, with which Table II's problems were recorded
            (``kd``'s own default, 0.6, slows AD(3)'s convergence: it meets Table X's
            step test on none of a 0.6 s flat walk's 21 problems, on 7 with 1.0).
    """

    course: str = "flat"
    vx_mps: float = 0.75
    duration_s: float = 2.0
    dt_s: float = 0.05
    skip_s: float = 0.3
    preview: bool = False
    seed: int | None = None
    stones_only: bool = False
    cop_fraction: float = 1.0

    def __post_init__(self) -> None:
        if not (0.0 < self.cop_fraction <= 1.0):
            raise ConfigError("cop_fraction", self.cop_fraction, "a fraction in (0, 1]")
        if not (np.isfinite(self.duration_s) and self.duration_s > 0.0):
            raise ConfigError("duration_s", self.duration_s, "a finite time > 0 s")
        if not (np.isfinite(self.skip_s) and 0.0 <= self.skip_s < self.duration_s):
            raise ConfigError("skip_s", self.skip_s, f"a time in [0, {self.duration_s}) s")


@dataclass(frozen=True)
class Recording:
    """What one recording run solved: the frozen problems, the closed loop's result of
    each, the simulation time of each solve [s] (all after ``skip_s``) and the walk's
    :attr:`RecordingSpec.cop_fraction` (to pass on to :func:`save_problems`)."""

    problems: list[KDProblem]
    results: list[SequentialResult]
    times_s: list[float]
    cop_fraction: float


def table2_walk_config(cop_fraction: float) -> KDWalkConfig:
    """``kd``'s settings as Table II's problems were recorded and are solved: the
    recording's ``cop_fraction``, and the trunk settings from before
    ``docs/design/trunk_attitude.md`` (angular centroidal-pose weight 2000 on all three axes,
    no trunk roll / pitch feedback), so that ``benchmarks/results/table2.md`` stays
    reproducible. Those settings change the states the walk visits and the angular
    weights of every problem: with roll / pitch 6000, AD(3) meets Table X's step test on
    none of the first three problems of a 0.6 s flat walk."""
    from gaitnet_mpc.control.kd_walk_config import KDWalkConfig

    config = KDWalkConfig(cop_fraction=cop_fraction)
    kd = replace(config.sequential.kd, w_pose=(1.0, 1.0, 1.0, 2000.0, 2000.0, 2000.0))
    low_level = replace(
        config.low_level, stance_tilt_kp_nm_per_rad=0.0, stance_tilt_kd_nms_per_rad=0.0
    )
    return replace(config, sequential=replace(config.sequential, kd=kd), low_level=low_level)


def record_run(spec: RecordingSpec, robot_name: str = "humanoid3d") -> Recording:
    """Walk ``spec.course`` with the ``kd`` controller, its solver replaced by a
    :class:`RecordingKDMPC` (stops early at a fall)."""
    from gaitnet_mpc.control.kd_walk import KDWalkController
    from gaitnet_mpc.control.kd_walk_config import preview_walk_config
    from gaitnet_mpc.dt_policy import DtPolicyConfig
    from gaitnet_mpc.scenario import Scenario, build_episode

    config = replace(
        table2_walk_config(spec.cop_fraction), dt_policy=DtPolicyConfig(dt_s=spec.dt_s)
    )
    config = preview_walk_config(config) if spec.preview else config
    scenario = Scenario(
        robot=robot_name,
        controller="kd",
        course=spec.course,
        course_seed=spec.seed,
        command=Command(vx_mps=spec.vx_mps),
        duration_s=spec.duration_s,
        config=config,
    )
    episode = build_episode(scenario)
    course, sim, ctrl = episode.course, episode.sim, episode.controller
    assert isinstance(ctrl, KDWalkController)
    if spec.stones_only and len(course.patches) < 3:
        raise ConfigError("stones_only", spec.course, "a course with stones between platforms")
    x_window_m = (course.patches[1].x_min, course.patches[-1].x_min) if spec.stones_only else (0, 0)
    recorder = RecordingKDMPC(ctrl.mpc)
    ctrl.mpc = recorder
    ctrl.reset(sim.state())
    times: list[float] = []
    x_base_m: list[float] = []
    for _ in range(round(spec.duration_s / sim.config.timestep_s)):
        n_before = len(recorder.problems)
        state = sim.state()
        sim.step(ctrl.compute(state))
        times += [state.t_s] * (len(recorder.problems) - n_before)
        x_base_m += [float(state.qpos[0])] * (len(recorder.problems) - n_before)
        if sim.fall.fell or (spec.stones_only and state.qpos[0] > x_window_m[1]):
            break
    t_end_s = times[-1] - FALL_MARGIN_S if sim.fall.fell and times else np.inf
    keep = [
        i
        for i, (t, x) in enumerate(zip(times, x_base_m, strict=True))
        if spec.skip_s <= t < t_end_s
        and (not spec.stones_only or x_window_m[0] <= x <= x_window_m[1])
    ]
    return Recording(
        [recorder.problems[i] for i in keep],
        [recorder.results[i] for i in keep],
        [times[i] for i in keep],
        spec.cop_fraction,
    )


def record_problems(spec: RecordingSpec, robot_name: str = "humanoid3d") -> list[KDProblem]:
    """The problems of :func:`record_run`."""
    return record_run(spec, robot_name).problems


# --------------------------------------------------------------------------- save / load
def _put_mapping(out: dict[str, np.ndarray], key: str, value: Mapping[str, object]) -> None:
    for foot, arr in value.items():
        out[f"{key}.{foot}"] = np.asarray(arr)


def _problem_arrays(problem: KDProblem, course: str) -> dict[str, np.ndarray]:
    """Plain arrays of one problem (keys without the ``"{i}/"`` prefix)."""
    t = problem.timing
    out: dict[str, np.ndarray] = {
        "course": np.array(course),
        "q": np.asarray(problem.q, dtype=float),
        "v": np.asarray(problem.v, dtype=float),
        "timing.dts_s": np.asarray(t.dts_s, dtype=float),
        "timing.contact": np.asarray(t.contact, dtype=bool),
        "timing.time_in_step_s": np.array(t.time_in_step_s),
        "timing.stages_per_step": np.array(t.stages_per_step),
        "timing.full_dts_s": np.asarray(t.stage_lengths_s, dtype=float),
        "command": np.array(
            [problem.command.vx_mps, problem.command.vy_mps, problem.command.yaw_rate_radps]
        ),
        "heading_rad": np.array(problem.heading_rad),
        "foot_yaw_rad": np.asarray(problem.foot_yaw_rad, dtype=float),
        "choose_dt": np.array(problem.choose_dt),
        "step_index": np.array(problem.step_index),
    }
    _put_mapping(out, "footholds_m", problem.footholds_m)
    _put_mapping(out, "p_foot_now_m", problem.p_foot_now_m)
    _put_mapping(out, "p_liftoff_m", problem.p_liftoff_m)
    for foot, box in problem.foothold_boxes.items():
        out[f"foothold_boxes.{foot}.lo_m"] = np.asarray(box.lo_m, dtype=float)
        out[f"foothold_boxes.{foot}.hi_m"] = np.asarray(box.hi_m, dtype=float)
    if problem.p_com_start_m is not None:
        out["p_com_start_m"] = np.asarray(problem.p_com_start_m, dtype=float)
    if problem.com_reference is not None:
        ref = problem.com_reference(t)
        if ref is not None:
            out["com_reference.p_m"] = np.asarray(ref.p_m, dtype=float)
            out["com_reference.v_mps"] = np.asarray(ref.v_mps, dtype=float)
        else:
            out["com_reference.none"] = np.array(True)
    if problem.j_max is not None:
        out["j_max"] = np.array(problem.j_max)
    if problem.state is not None:
        s = problem.state
        out["state.stance_foot"] = np.array(s.stance_foot)
        out["state.swing_foot"] = np.array(s.swing_foot)
        for fld in fields(RobotState):
            value = getattr(s.state, fld.name)
            if isinstance(value, Mapping):
                _put_mapping(out, f"state.robot.{fld.name}", value)
            else:
                out[f"state.robot.{fld.name}"] = np.asarray(value)
    return out


def save_problems(
    path: Path | str,
    problems: list[KDProblem],
    courses: list[str] | None = None,
    *,
    cop_fraction: float,
) -> Path:
    """Write ``problems`` (with the name of the course each was recorded on, and the
    recording's :attr:`RecordingSpec.cop_fraction`) to one ``.npz`` (format in the module
    docstring); returns the path written."""
    courses = courses if courses is not None else [""] * len(problems)
    if len(courses) != len(problems):
        raise ConfigError("courses", len(courses), f"{len(problems)} course names")
    arrays: dict[str, np.ndarray] = {
        "format": np.array(FORMAT_VERSION),
        "count": np.array(len(problems)),
        "cop_fraction": np.array(float(cop_fraction)),
    }
    for i, (problem, course) in enumerate(zip(problems, courses, strict=True)):
        for key, value in _problem_arrays(problem, course).items():
            arrays[f"{i}/{key}"] = value
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **arrays)  # type: ignore[arg-type]
    return path if path.suffix == ".npz" else path.with_name(path.name + ".npz")


@dataclass(frozen=True)
class RecordedProblem:
    """A problem read back from a file, with the course it was recorded on and the
    recording's CoP fraction (:func:`kd_solver` solves it as the loop did with it)."""

    problem: KDProblem
    course: str
    cop_fraction: float


def _mapping(arr: Mapping[str, np.ndarray], key: str) -> dict[str, np.ndarray]:
    return {f: np.array(arr[f"{key}.{f}"]) for f in FEET if f"{key}.{f}" in arr}


def _plain(value: np.ndarray) -> object:
    """A 0-d array as a Python float or bool, anything else as a copied array."""
    if value.ndim == 0 and value.dtype.kind == "b":
        return bool(value)
    if value.ndim == 0:
        return float(value)
    return np.array(value)


def _rebuild(a: Mapping[str, np.ndarray]) -> KDProblem:
    """One :class:`KDProblem` from its arrays (keys without the prefix)."""
    timing = ReferenceTiming(
        dts_s=a["timing.dts_s"],
        contact=a["timing.contact"],
        time_in_step_s=float(a["timing.time_in_step_s"]),
        stages_per_step=int(a["timing.stages_per_step"]),
        full_dts_s=a["timing.full_dts_s"],
    )
    vx, vy, wz = (float(x) for x in a["command"])
    boxes = {
        f: FootholdBox(
            np.array(a[f"foothold_boxes.{f}.lo_m"]), np.array(a[f"foothold_boxes.{f}.hi_m"])
        )
        for f in FEET
        if f"foothold_boxes.{f}.lo_m" in a
    }
    com_reference: Callable[[ReferenceTiming], CoMReference | None] | None = None
    if "com_reference.p_m" in a:
        ref = CoMReference(np.array(a["com_reference.p_m"]), np.array(a["com_reference.v_mps"]))
        com_reference = _constant_reference(ref)
    elif "com_reference.none" in a:
        com_reference = _constant_reference(None)
    state = None
    if "state.stance_foot" in a:
        kw: dict[str, object] = {}
        for fld in fields(RobotState):
            key = f"state.robot.{fld.name}"
            if key in a:
                kw[fld.name] = _plain(a[key])
            else:
                kw[fld.name] = {f: _plain(v) for f, v in _mapping(a, key).items()}
        state = StepState(
            RobotState(**kw),  # type: ignore[arg-type]
            str(a["state.stance_foot"]),
            str(a["state.swing_foot"]),
        )
    return KDProblem(
        q=np.array(a["q"]),
        v=np.array(a["v"]),
        timing=timing,
        command=Command(vx, vy, wz),
        heading_rad=float(a["heading_rad"]),
        footholds_m=_mapping(a, "footholds_m"),
        p_foot_now_m=_mapping(a, "p_foot_now_m"),
        p_liftoff_m=_mapping(a, "p_liftoff_m"),
        foot_yaw_rad=np.array(a["foot_yaw_rad"]),
        foothold_boxes=boxes,
        p_com_start_m=np.array(a["p_com_start_m"]) if "p_com_start_m" in a else None,
        com_reference=com_reference,
        j_max=int(a["j_max"]) if "j_max" in a else None,
        choose_dt=bool(a["choose_dt"]),
        step_index=int(a["step_index"]),
        state=state,
    )


def iter_problems(path: Path | str, limit: int | None = None) -> Iterator[RecordedProblem]:
    """The problems of a file written by :func:`save_problems`, in order.

    Raises:
        ConfigError: not a file of this format.
    """
    with np.load(Path(path), allow_pickle=False) as data:
        if "format" not in data.files or int(data["format"]) != FORMAT_VERSION:
            raise ConfigError("problems file", str(path), f"format {FORMAT_VERSION} (.npz)")
        count = int(data["count"])
        cop_fraction = float(data["cop_fraction"])
        count = count if limit is None else min(count, limit)
        by_index: dict[int, dict[str, np.ndarray]] = {i: {} for i in range(count)}
        for key in data.files:
            head, _, rest = key.partition("/")
            if rest and head.isdigit() and int(head) < count:
                by_index[int(head)][rest] = data[key]
    for i in range(count):
        arrays = by_index[i]
        yield RecordedProblem(_rebuild(arrays), str(arrays["course"]), cop_fraction)


def problem_count(path: Path | str) -> int:
    """How many problems a file written by :func:`save_problems` holds."""
    with np.load(Path(path), allow_pickle=False) as data:
        if "format" not in data.files or int(data["format"]) != FORMAT_VERSION:
            raise ConfigError("problems file", str(path), f"format {FORMAT_VERSION} (.npz)")
        return int(data["count"])


def load_problems(path: Path | str, limit: int | None = None) -> list[RecordedProblem]:
    """All (or the first ``limit``) problems of a file written by :func:`save_problems`."""
    return list(iter_problems(path, limit))


__all__ = [
    "FORMAT_VERSION",
    "TABLE2_COURSES",
    "RecordedProblem",
    "Recording",
    "RecordingKDMPC",
    "RecordingSpec",
    "freeze_problem",
    "iter_problems",
    "kd_solver",
    "load_problems",
    "problem_count",
    "record_problems",
    "record_run",
    "save_problems",
]


def kd_solver(
    robot_name: str = "humanoid3d", dt_s: float = 0.05, cop_fraction: float = 1.0
) -> SequentialKDMPC:
    """A fresh :class:`SequentialKDMPC` configured exactly as the ``kd`` controller's
    (robot mass, line-foot lengths, foot separation; :class:`FixedDt` of ``dt_s``), with
    the recording's ``cop_fraction`` (:attr:`RecordedProblem.cop_fraction`)."""
    from gaitnet_mpc.control.kd_walk import KDWalkController
    from gaitnet_mpc.control.kd_walk_config import walk_terrain
    from gaitnet_mpc.mpc.sequential import FixedDt
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.terrain import load_course

    robot = load_robot(robot_name)
    config = table2_walk_config(cop_fraction)
    ctrl = KDWalkController(
        robot, walk_terrain(load_course("flat"), config), Command(), FixedDt(dt_s), config
    )
    return SequentialKDMPC(robot, ctrl.mpc.config, ctrl.mpc.dt_policy)
