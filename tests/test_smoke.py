"""Smoke test: every registered controller on every robot and built-in course, one second of
simulated time through the path of ``gaitnet-mpc run`` (:func:`make_scenario` with the
default preset, :func:`run_scenario` without an output folder).

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

from gaitnet_mpc.control.registry import CONTROLLERS
from gaitnet_mpc.robots import ROBOTS, RobotModel
from gaitnet_mpc.scenario import make_scenario, run_scenario
from gaitnet_mpc.terrain import BUILTIN_COURSES

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
    scenario = make_scenario(
        robot=robot_name,
        controller=controller,
        course=course_name,
        vx_mps=0.0 if controller == "stand" else WALK_VX_MPS,
        duration_s=DURATION_S,
    )
    summary = run_scenario(scenario, robot=robots(robot_name))

    assert not summary["diverged"], summary["fall_reason"]
    assert not summary["fell"], summary["fall_reason"]
    assert summary["duration_s"] == pytest.approx(DURATION_S)
    assert summary["final_tilt_rad"] < MAX_FINAL_TILT_RAD
    if controller == "stand":
        assert abs(summary["distance_m"]) < 0.05
    else:
        assert summary["distance_m"] > 0.0  # it walks the way it is told
