"""The cases of ``gaitnet-mpc sweep`` and the worker that runs one: what each mode measures.

A case is a JSON-ready dict (``key``, ``mode``, ``controller`` and the mode's fields); the
worker :func:`run_case` runs it (one bisection, or one episode) and returns its record.
Every episode is a scenario (:func:`~gaitnet_mpc.scenario.make_scenario`,
:func:`~gaitnet_mpc.scenario.build_episode`, :func:`~gaitnet_mpc.runner.episode.run_episode`;
no run folder), as ``gaitnet-mpc run`` would run it.

Modes (:data:`MODES`), humanoid3d throughout:

* ``push``: the largest survivable push of :data:`PUSH_DURATION_S` at the trunk CoM per
  controller x direction (:data:`DIRECTIONS`, 8) x phase of a step x speed, by bisection
  on the force (:func:`bisect_largest`). The push starts at phase ``p`` of the controller's
  own step: the first one at or after the settling time with the left foot in the air
  (:mod:`~gaitnet_mpc.experiments.push_timing`; sweeps made before 2026-12-07 used a
  nominal step grid). Survived: no fall within the time after the push. The episodes of
  one bisection are the same up to the push, so that part is simulated once and each
  force finishes in a forked copy of the process
  (:mod:`~gaitnet_mpc.experiments.forked_episode`; the same records, 2-3x less time).
* ``protocol``: one episode per controller x seed under the data-collection protocol's
  pushes (:func:`~gaitnet_mpc.sim.disturbances.protocol_pushes`).
* ``payload``: the largest unknown trunk payload [kg] walked for the whole episode, per
  controller x course (``flat``, ``gap``), by bisection.
* ``terrain``: one episode per controller x course x seed: seeded ``uneven`` courses of
  growing amplitude (written into the sweep folder as course files, since a scenario
  names a course and a seed only) and seeded ``stepping-stones``. Success: no fall, no
  foothold violation, no leg-leg contact.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from typing import Any, NamedTuple

from gaitnet_mpc.experiments.bisection import Bisection, bisect_largest
from gaitnet_mpc.experiments.push_timing import (
    PHASE_RULES,
    executed_push_time_s,
    measured_phase,
    push_time_s,
    step_s,
)

MODES = ("push", "protocol", "payload", "terrain")

PUSH_DURATION_S = 0.2
#: direction name -> angle of the push in the world xy plane [deg] (x forward, y left)
DIRECTIONS: dict[str, float] = {
    "fwd": 0.0,
    "fwd-left": 45.0,
    "left": 90.0,
    "bwd-left": 135.0,
    "bwd": 180.0,
    "bwd-right": 225.0,
    "right": 270.0,
    "fwd-right": 315.0,
}
#: The stages of a footstep of every walking controller at start (``T = 5 dt``).


@dataclass(frozen=True)
class ModePlan:
    """The grid of one mode (full or ``--quick``); part of a sweep's identity.

    Attributes:
        speeds_mps: forward speed commands [m/s].
        directions: push directions (``push``), names of :data:`DIRECTIONS`.
        phases: push start phases in a step, in [0, 1) (``push``).
        settle_s: time before the first push [s] (``push``, ``protocol``).
        after_s: simulated time after the push ends [s] (``push``).
        duration_s: episode duration [s] (``protocol``, ``payload``, ``terrain``).
        hi: top of the bisected range (N for ``push``, kg for ``payload``).
        resolution: bisection grid step (same unit as ``hi``).
        spot_fractions: fractions of the found bound re-run as checks of monotonicity.
        scan_from: None, or a fraction of the bisection's bound: every grid point from
            there up to the bound is then run in order, and the first fall sets the bound
            below it (:func:`bisect_largest`); sweeps made before 2026-12-07 (night) did
            not scan, and their plans do not name it.
        courses: courses (``payload``: built-in names; ``terrain``: ``uneven`` amplitudes
            as ``uneven:<amplitude m>`` and ``stepping-stones``).
        seeds: seeds (``protocol``: push draws; ``terrain``: course layouts).
        phase_of: where a push's phase is measured (``push``;
            :mod:`~gaitnet_mpc.experiments.push_timing`): ``"executed"``, in the
            controller's own step, or ``"nominal"``, on the grid of its nominal step (the
            rule of sweeps made before 2026-12-07, whose plans do not name it).
    """

    speeds_mps: tuple[float, ...] = (0.5,)
    directions: tuple[str, ...] = ()
    phases: tuple[float, ...] = ()
    settle_s: float = 0.0
    after_s: float = 0.0
    duration_s: float = 0.0
    hi: float = 0.0
    resolution: float = 1.0
    spot_fractions: tuple[float, ...] = ()
    scan_from: float | None = None
    courses: tuple[str, ...] = ()
    seeds: tuple[int, ...] = ()
    phase_of: str = "nominal"

    def __post_init__(self) -> None:
        from gaitnet_mpc.errors import ConfigError

        if self.phase_of not in PHASE_RULES:
            raise ConfigError("phase_of", self.phase_of, f"one of {list(PHASE_RULES)}")

    def to_dict(self) -> dict[str, Any]:
        from dataclasses import asdict

        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ModePlan:
        values: dict[str, Any] = {
            k: tuple(v) if isinstance(v, list) else v for k, v in data.items()
        }
        return cls(**values)


UNEVEN_AMPLITUDES_M = (0.01, 0.02, 0.03, 0.04, 0.05, 0.06)


def mode_plan(mode: str, quick: bool, seeds: int) -> ModePlan:
    """The grid of ``mode``; ``seeds`` seeds for ``protocol`` and ``terrain``."""
    seed_list = tuple(range(1 if quick else seeds))
    if mode == "push":
        if quick:
            return ModePlan(
                (0.5,), ("fwd", "left"), (0.25,), 0.5, 0.6, hi=200.0, resolution=100.0,
                phase_of="executed",
            )  # fmt: skip
        return ModePlan(
            (0.25, 0.5, 0.75),
            tuple(DIRECTIONS),
            (0.0, 0.25, 0.5, 0.75),
            settle_s=3.0,
            after_s=3.0,
            hi=500.0,
            resolution=5.0,
            spot_fractions=(0.5, 0.25),
            scan_from=0.5,
            phase_of="executed",
        )
    if mode == "protocol":
        settle_s, duration_s = (0.5, 2.0) if quick else (2.0, 12.0)
        return ModePlan((0.5,), settle_s=settle_s, duration_s=duration_s, seeds=seed_list)
    if mode == "payload":
        if quick:
            return ModePlan((0.5,), duration_s=1.5, hi=4.0, resolution=2.0, courses=("flat",))
        return ModePlan(
            (0.5,),
            duration_s=20.0,
            hi=8.0,
            resolution=0.25,
            spot_fractions=(0.5,),
            courses=("flat", "gap"),
        )
    if mode == "terrain":
        amplitudes = (0.02,) if quick else UNEVEN_AMPLITUDES_M
        courses = (*(f"uneven:{a:g}" for a in amplitudes), "stepping-stones")
        duration_s = 2.0 if quick else 14.0
        return ModePlan((0.5,), duration_s=duration_s, courses=courses, seeds=seed_list)
    from gaitnet_mpc.errors import ConfigError

    raise ConfigError("MODE", mode, f"one of {list(MODES)}")


class ControllerSpec(NamedTuple):
    """A sweep's controller: a registry name, an optional fixed dt [s], preset (or a
    settings file ``*.toml`` over the default preset) and Gait-Net weights."""

    name: str
    dt_s: float | None = None
    preset: str | None = None
    weights: str | None = None

    def scenario_args(self) -> dict[str, Any]:
        """The controller's arguments of :func:`~gaitnet_mpc.scenario.make_scenario`."""
        is_file = self.preset is not None and self.preset.endswith(".toml")
        return {
            "controller": self.name,
            "dt_s": self.dt_s,
            "preset": None if is_file else self.preset,
            "config_file": self.preset if is_file else None,
            "gaitnet_weights": self.weights,
        }


def parse_controller(spec: str) -> ControllerSpec:
    """``kd@0.055+realtime`` -> (``kd``, 0.055, ``realtime``): a registry name, an optional
    fixed dt [s] and an optional preset (as ``gaitnet-mpc run --dt 0.055 --preset
    realtime``), or a settings file ``+FILE.toml`` (as ``--config FILE.toml``);
    ``gaitnet+realtime`` has no dt; ``gaitnet:humanoid3d-dagger`` names the Gait-Net
    weights (as ``--gaitnet-weights``: a shipped name or a path without ``+``)."""
    from gaitnet_mpc.errors import ConfigError

    form = "NAME[@DT][:WEIGHTS][+PRESET]"
    rest, plus, preset = spec.partition("+")
    if plus and not preset:
        raise ConfigError("--controllers", spec, f"{form} with a preset name")
    rest, colon, weights = rest.partition(":")
    if colon and not weights:
        raise ConfigError("--controllers", spec, f"{form} with weights after ':'")
    name, sep, dt = rest.partition("@")
    value = None
    if sep:
        try:
            value = float(dt)
        except ValueError:
            raise ConfigError("--controllers", spec, f"{form} with DT a number [s]") from None
    return ControllerSpec(name, value, preset or None, weights or None)


def make_cases(mode: str, controllers: tuple[str, ...], plan: ModePlan) -> list[dict[str, Any]]:
    """Every case of the sweep, each with a unique ``key``."""
    cases: list[dict[str, Any]] = []
    for c in controllers:
        if mode == "push":
            for v in plan.speeds_mps:
                for p in plan.phases:
                    for d in plan.directions:
                        key = f"{c} v{v:g} {d} p{p:g}"
                        cases.append({"key": key, "speed_mps": v, "direction": d, "phase": p})
        elif mode == "payload":
            cases += [{"key": f"{c} {course}", "course": course} for course in plan.courses]
        elif mode == "protocol":
            cases += [{"key": f"{c} seed {s}", "seed": s} for s in plan.seeds]
        else:
            for course in plan.courses:
                for s in plan.seeds:
                    cases.append({"key": f"{c} {course} seed {s}", "course": course, "seed": s})
        for case in cases:
            case.setdefault("controller", c)
    for case in cases:
        case["mode"] = mode
        case["plan"] = plan.to_dict()
    return cases


# ----------------------------------------------------------------------------- episodes
def _build(controller: str, *, vx_mps: float, duration_s: float, **scenario: Any) -> Any:
    """The episode of ``controller`` (a :func:`parse_controller` spec) as ``gaitnet-mpc
    run`` builds it; ``scenario``: further :func:`~gaitnet_mpc.scenario.make_scenario`
    arguments (pushes, payload, course)."""
    from gaitnet_mpc.scenario import build_episode, make_scenario

    spec = parse_controller(controller)
    return build_episode(
        make_scenario(**spec.scenario_args(), vx_mps=vx_mps, duration_s=duration_s, **scenario)
    )


def _outcome(summary: dict[str, Any], wall_s: float) -> dict[str, Any]:
    """An episode's record in a case, from its summary."""
    fall_time = summary.get("fall_time_s")
    return {
        "fell": bool(summary["fell"]),
        "fall_time_s": None if fall_time is None else round(float(fall_time), 3),
        "fall_reason": summary.get("fall_reason") or "",
        "distance_m": round(float(summary.get("distance_m") or 0.0), 3),
        "foothold_violations": int(summary.get("foothold_violations") or 0),
        "self_collisions": int(summary.get("self_collisions") or 0),
        "wall_s": round(wall_s, 2),
    }


def _episode(
    controller: str,
    *,
    vx_mps: float,
    duration_s: float,
    pushes: tuple[Any, ...] = (),
    payload_kg: float = 0.0,
    course: str = "flat",
    course_seed: int | None = None,
) -> tuple[dict[str, Any], Any]:
    """One episode; returns (its outcome, its controller). An exception in the closed loop
    propagates (the sweep logs it as a failed case)."""
    from gaitnet_mpc.runner.episode import run_episode

    episode = _build(controller, vx_mps=vx_mps, duration_s=duration_s, pushes=pushes,
                     payload_kg=payload_kg, course=course, course_seed=course_seed)  # fmt: skip
    t0 = time.perf_counter()
    summary = run_episode(
        episode.sim, episode.controller, episode.scenario.command, duration_s, progress=False
    )
    return _outcome(summary, time.perf_counter() - t0), episode.controller


def _push_case(case: dict[str, Any], plan: ModePlan) -> dict[str, Any]:
    """The bisection of one push case. The episodes share everything before the push, so
    where the process may fork (:func:`~gaitnet_mpc.experiments.forked_episode.fork_usable`)
    that prefix is simulated once and each force finishes in a forked copy; otherwise each
    force runs a whole episode. Both give the same records, bit for bit (the wall times
    aside: ``prefix_wall_s`` is the shared prefix's)."""
    from gaitnet_mpc.experiments.forked_episode import ForkedEpisode, fork_usable
    from gaitnet_mpc.sim.disturbances import Push

    c, vx = case["controller"], case["speed_mps"]
    t_push = _push_time_s(c, vx, case["phase"], plan)
    duration = t_push + PUSH_DURATION_S + plan.after_s
    angle = math.radians(DIRECTIONS[case["direction"]])
    episodes: list[dict[str, Any]] = []
    measured: list[tuple[float | None, str]] = []
    prefix = (
        ForkedEpisode(_build(c, vx_mps=vx, duration_s=duration), duration, t_push)
        if (fork_usable())
        else None
    )

    def outcome(loop: Any, wall_s: float) -> dict[str, Any]:
        phase, swing = measured_phase(loop.controller, t_push)
        return {**_outcome(loop.summary(wall_s), wall_s), "_phase": [phase, swing]}

    def survives(i: int) -> bool:
        f = i * plan.resolution
        fx, fy = round(f * math.cos(angle), 6), round(f * math.sin(angle), 6)
        pushes = (Push(t_push, (fx, fy, 0.0), PUSH_DURATION_S),) if f > 0 else ()
        if prefix is not None:
            out = prefix.finish(pushes, outcome)
            phase, swing = out.pop("_phase")
        else:
            out, ctrl = _episode(c, vx_mps=vx, duration_s=duration, pushes=pushes)
            phase, swing = measured_phase(ctrl, t_push)
        if not measured:
            measured.append((phase, swing))
        episodes.append({"force_n": f, **out})
        return not out["fell"]

    n = round(plan.hi / plan.resolution)
    b = bisect_largest(survives, n, plan.spot_fractions, plan.scan_from)
    phase_measured, swing = measured[0] if measured else (None, "")
    record = {
        **_bounds(b, plan.resolution),
        "push_t_s": round(t_push, 4),
        "phase_measured": phase_measured,
        "swing_foot": swing,
        "episodes": episodes,
    }
    if prefix is not None:
        record["prefix_wall_s"] = round(prefix.prefix_wall_s, 2)
    return record


def _push_time_s(controller: str, vx_mps: float, phase: float, plan: ModePlan) -> float:
    """The push start of a case by ``plan.phase_of``; the ``"executed"`` rule falls back
    to the nominal grid where the unpushed episode fell before its step."""
    dt_s = parse_controller(controller).dt_s
    if plan.phase_of == "executed":
        from gaitnet_mpc.dt_policy import ACCEPTED_DT_RANGE_S

        longest_step_s = step_s(ACCEPTED_DT_RANGE_S[1])  # one step to wait for, then its own
        probe_s = plan.settle_s + 3 * longest_step_s
        episode = _build(controller, vx_mps=vx_mps, duration_s=probe_s)
        t_push = executed_push_time_s(episode, plan.settle_s, phase)
        if t_push is not None:
            return t_push
    return push_time_s(dt_s, plan.settle_s, phase)


def _bounds(b: Bisection, res: float) -> dict[str, Any]:
    out = {
        "survived": None if b.survived is None else b.survived * res,
        "failed": None if b.failed is None else b.failed * res,
        "non_monotone": b.non_monotone,
        "spot_failed": [i * res for i in b.spot_failed],
    }
    if b.bisected is not None and b.bisected != b.survived:  # an island the scan dropped
        out["bisected"] = b.bisected * res
    return out


def _payload_case(case: dict[str, Any], plan: ModePlan) -> dict[str, Any]:
    episodes: list[dict[str, Any]] = []

    def survives(i: int) -> bool:
        kg = i * plan.resolution
        out, _ = _episode(
            case["controller"],
            vx_mps=plan.speeds_mps[0],
            duration_s=plan.duration_s,
            payload_kg=kg,
            course=case["course"],
        )
        episodes.append({"payload_kg": kg, **out})
        return not out["fell"]

    b = bisect_largest(survives, round(plan.hi / plan.resolution), plan.spot_fractions)
    return {**_bounds(b, plan.resolution), "episodes": episodes}


def uneven_file_name(course: str, seed: int) -> str:
    """The course file of ``uneven:<amplitude>`` and ``seed`` in the sweep folder."""
    amplitude_cm = round(float(course.split(":", 1)[1]) * 100, 3)
    return f"courses/uneven-{amplitude_cm:g}cm-seed{seed}.json"


def _terrain_case(case: dict[str, Any], plan: ModePlan, folder: str) -> dict[str, Any]:
    course, seed = case["course"], case["seed"]
    if course.startswith("uneven:"):
        kwargs: dict[str, Any] = {"course": os.path.join(folder, uneven_file_name(course, seed))}
    else:
        kwargs = {"course": course, "course_seed": seed}
    out, _ = _episode(
        case["controller"], vx_mps=plan.speeds_mps[0], duration_s=plan.duration_s, **kwargs
    )
    clean = not out["fell"] and not out["foothold_violations"] and not out["self_collisions"]
    return {"success": clean, **out}


def _protocol_case(case: dict[str, Any], plan: ModePlan) -> dict[str, Any]:
    from gaitnet_mpc.sim.disturbances import protocol_pushes

    pushes = protocol_pushes(case["seed"], plan.settle_s, plan.duration_s)
    out, _ = _episode(
        case["controller"],
        vx_mps=plan.speeds_mps[0],
        duration_s=plan.duration_s,
        pushes=pushes,
    )
    t_end = out["fall_time_s"] if out["fell"] else plan.duration_s
    return {"survived": not out["fell"], "pushes": sum(p.t_s < t_end for p in pushes), **out}


def run_case(item: tuple[dict[str, Any], str]) -> dict[str, Any]:
    """Worker body: run one case (``item``: the case and the sweep folder); return its
    record (``key``, ``case``, ``result``, ``wall_s``). Exceptions propagate."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    case, folder = item
    plan = ModePlan.from_dict(case["plan"])
    t0 = time.perf_counter()
    mode = case["mode"]
    if mode == "push":
        result = _push_case(case, plan)
    elif mode == "payload":
        result = _payload_case(case, plan)
    elif mode == "protocol":
        result = _protocol_case(case, plan)
    else:
        result = _terrain_case(case, plan, folder)
    case_out = {k: v for k, v in case.items() if k != "plan"}
    return {
        "key": case["key"],
        "case": case_out,
        "result": result,
        "wall_s": round(time.perf_counter() - t0, 2),
    }
