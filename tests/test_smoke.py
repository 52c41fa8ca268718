"""Smoke test: every registered controller on every robot and built-in course, one second of
simulated time through the path of ``gaitnet-mpc run`` (settings from the default preset,
:func:`make_controller`, :func:`run_episode` without an output folder).

Measured (this test's setup, 1 s, forward command 0.5 m/s for the walkers): no combination
falls or diverges; kd covers 0.23 m (biped2d) / 0.34 m (humanoid3d), srbm 0.13 m / 0.34 m,
stand drifts < 5 mm. The kd/srbm/stand episodes took 60-75 s on a loaded 2-core machine.
wbmpc runs on flat only: it knows no terrain, and building its NLPs takes ~40 s per
humanoid controller. Within one second the robots are still on the start platform of
every course, so the terrain features themselves are covered by the closed-loop tests of
the controllers, not here.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.registry import (
    CONTROLLERS,
    ControllerContext,
    controller_config,
    make_controller,
)
from gaitnet_mpc.robots import ROBOTS, RobotModel
from gaitnet_mpc.runner.episode import run_episode
from gaitnet_mpc.sim.simulator import Simulator
from gaitnet_mpc.terrain import BUILTIN_COURSES, load_course

DURATION_S = 1.0
WALK_VX_MPS = 0.5
MAX_FINAL_TILT_RAD = 0.5  # well short of a fall, far above a walking sway


@pytest.mark.parametrize("course_name", list(BUILTIN_COURSES))
@pytest.mark.parametrize("robot_name", sorted(ROBOTS))
@pytest.mark.parametrize("controller", sorted(CONTROLLERS))
def test_one_second_without_fall_or_divergence(
    controller: str,
    robot_name: str,
    course_name: str,
    robots: Callable[[str], RobotModel],
) -> None:
    if controller == "wbmpc" and course_name != "flat":
        pytest.skip("wbmpc is made for flat ground; its NLP build costs ~40 s per humanoid")
    robot = robots(robot_name)
    course = load_course(course_name)
    command = Command() if controller == "stand" else Command(WALK_VX_MPS)
    config = controller_config(controller, robot.spec.planar)
    ctrl = make_controller(controller, ControllerContext(robot, course, command, config))
    sim = Simulator(robot, course)

    summary = run_episode(sim, ctrl, command, DURATION_S, progress=False)

    assert not summary["diverged"], summary["fall_reason"]
    assert not summary["fell"], summary["fall_reason"]
    assert summary["duration_s"] == pytest.approx(DURATION_S)
    assert summary["final_tilt_rad"] < MAX_FINAL_TILT_RAD
    if controller == "stand":
        assert abs(summary["distance_m"]) < 0.05
    else:
        assert summary["distance_m"] > 0.0  # it walks the way it is told
