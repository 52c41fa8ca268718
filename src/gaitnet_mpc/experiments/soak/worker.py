"""One soak episode in a worker process: built and run as ``gaitnet-mpc run`` does
(:func:`~gaitnet_mpc.scenario.make_scenario`, :func:`~gaitnet_mpc.scenario.build_episode`,
:func:`~gaitnet_mpc.runner.episode.run_episode`; no output folder, no video), every failure
caught and summed up in one JSON record (:func:`run_spec`, at module level so that a spawn
process pool or Ray can run it; :func:`worker_died_record` for a worker that died).

A record holds: any exception (type, message, where, traceback), non-finite torques (the
simulator refuses them with ``ConfigError("tau_nm", ...)``), a diverged simulation (the
simulator's MuJoCo-warning / non-finite-state / speed checks, MuJoCo's warning counters, a
non-finite final ``qpos``), QP failures the controller handled, unconverged MPC solves,
Python warnings, the fall and the wall time.
"""

from __future__ import annotations

import os
import time
import traceback
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gaitnet_mpc.experiments.soak.draw import EpisodeSpec


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


def worker_died_record(spec: EpisodeSpec, exc: BaseException) -> dict[str, Any]:
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
