"""Injected QP failures in a closed loop: the controller keeps its last good plan, its
torques stay finite, and the failures are counted in its MPC statistics (as failed solves,
apart from solves that merely did not converge).

The backend's ``_solve`` is replaced (for the backend class the controller's settings name;
for ``kd`` the condensed DAQP solve as well, whose failures fall back to that backend) by
one that, inside a window of simulated time, either reports a failed status or raises;
:meth:`QPWorkspace.solve` turns the exception into a ``"numerical_error"`` status and
:meth:`QPWorkspace.solve_or_raise` into a :class:`QPSolveError`, which the controller
catches. Outside the window the real backend runs.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.base import MPCStats
from gaitnet_mpc.control.registry import ControllerContext, controller_config, make_controller
from gaitnet_mpc.errors import QPSolveError
from gaitnet_mpc.mpc.qp import BACKENDS
from gaitnet_mpc.mpc.qp.workspace import BackendResult
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import load_course

DURATION_S = 0.4
FAIL_FROM_S = 0.1  # the failure window [s]: several replans (every 0.02 s) and a step start
FAIL_UNTIL_S = 0.25
VX_MPS = 0.5


def _backend_name(controller: str, config: Any) -> str:
    """The QP backend the controller's settings name."""
    return config.sequential.kd.qp_backend if controller == "kd" else config.mpc.qp_backend


@pytest.mark.parametrize("controller", ["kd", "srbm"])
@pytest.mark.parametrize("mode", ["status", "raise"])
def test_failed_qp_keeps_last_plan_and_is_counted(
    controller: str,
    mode: str,
    robots: Callable[[str], RobotModel],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    robot = robots("humanoid3d")
    course = load_course("flat")
    command = Command(VX_MPS)
    config = controller_config(controller, robot.spec.planar)
    ctrl = make_controller(controller, ControllerContext(robot, course, command, config))
    backend = BACKENDS[_backend_name(controller, config)]
    real_solve = backend._solve
    window = {"on": False, "calls": 0}

    def flaky_solve(self: Any, problem: Any, warm_start: Any) -> BackendResult:
        if not window["on"]:
            return real_solve(self, problem, warm_start)
        window["calls"] += 1
        if mode == "raise":
            raise RuntimeError("injected backend crash")
        return BackendResult(None, "infeasible", "injected failure")

    monkeypatch.setattr(backend, "_solve", flaky_solve)
    if controller == "kd":  # the condensed form fails too, so the sparse backend is called
        from gaitnet_mpc.mpc.kd_condensed import KDCondensed

        real_condensed = KDCondensed.solve

        def flaky_condensed(self: Any, dense: Any) -> Any:
            sol, parts = real_condensed(self, dense)
            if window["on"]:
                sol.found, sol.status = False, "infeasible"
            return sol, parts

        monkeypatch.setattr(KDCondensed, "solve", flaky_condensed)
    # the MPC solves the injected failures made fail (a solve may call the backend more
    # than once, e.g. kd's dt search; each failed MPC solve raises QPSolveError once)
    real_mpc_solve = ctrl.mpc.solve
    raised = {"n": 0}

    def counting_mpc_solve(*args: Any, **kwargs: Any) -> Any:
        try:
            return real_mpc_solve(*args, **kwargs)
        except QPSolveError:
            raised["n"] += 1
            raise

    monkeypatch.setattr(ctrl.mpc, "solve", counting_mpc_solve)
    # what the controller acts on: kd's plan, srbm's stance wrench
    kept = "plan" if controller == "kd" else "wrench"

    sim = Simulator(robot, course)
    ctrl.reset(sim.state())
    stats = ctrl.mpc_stats
    assert stats is not None
    solves_before = last_good = None
    n_ticks = round(DURATION_S / sim.config.timestep_s)
    for _ in range(n_ticks):
        state = sim.state()
        if not window["on"] and FAIL_FROM_S <= state.t_s < FAIL_UNTIL_S:
            window["on"] = True
            solves_before = len(stats.converged)
            last_good = getattr(ctrl, kept)
            assert last_good is not None, "no good plan before the failures start"
        elif window["on"] and state.t_s >= FAIL_UNTIL_S:
            window["on"] = False
            solves_in_window = len(stats.converged) - solves_before
        tau = ctrl.compute(state)
        assert np.all(np.isfinite(tau)), f"non-finite torque at t = {state.t_s:.3f} s"
        if window["on"]:
            assert getattr(ctrl, kept) is last_good, "the plan changed during a failed solve"
        sim.step(tau)
        assert not sim.fall.fell, sim.fall.reason

    assert window["calls"] >= 3, "the failure window saw too few solves"
    # every solve of the window failed and was recorded as such: failed, not converged,
    # one QP, its real (non-zero) solve time, and the same full / replan flag as a success
    assert solves_in_window >= 3
    assert solves_before is not None
    failed = slice(solves_before, solves_before + solves_in_window)
    assert all(stats.failed[failed])
    assert not any(stats.converged[failed])
    assert all(n == 1 for n in stats.qps_per_solve[failed])
    assert all(t > 0.0 for t in stats.solve_time_s[failed])
    if controller == "srbm":
        assert all(stats.full_solve)  # srbm solves fully every time, failed or not
    summary = stats.summary()
    assert summary["solves"] == len(stats.converged)
    # failed solves are exactly the injected failures (none outside the window)
    assert raised["n"] == solves_in_window
    assert summary["failed_solves"] == raised["n"]
    assert raised["n"] <= window["calls"]
    converged_fraction = summary["converged_fraction"]
    assert isinstance(converged_fraction, float)
    assert converged_fraction <= 1.0 - solves_in_window / len(stats.converged) + 1e-12
    # and the controller recovered: solves after the window succeed and replace the plan
    assert any(stats.converged[solves_before + solves_in_window :])
    assert getattr(ctrl, kept) is not last_good


def test_mpc_stats_counts_failed_apart_from_unconverged() -> None:
    stats = MPCStats()
    assert stats.summary()["failed_solves"] == 0
    stats.record(0.004, 3, True, True)
    stats.record(0.006, 8, False, False)  # hit its iteration cap: a plan, not converged
    stats.record(0.002, 1, False, True, failed=True)
    summary = stats.summary()
    assert summary["solves"] == 3
    assert summary["failed_solves"] == 1
    assert summary["converged_fraction"] == pytest.approx(1 / 3)
    assert stats.failed == [False, False, True]
