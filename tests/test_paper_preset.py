"""``--preset paper`` walks (issue 49): Table VIII / Table V read per unit of motion
(``docs/design/paper_weights.md``), closed loop through the path of ``gaitnet-mpc run``.

Measured when written: ``gaitnet --preset paper`` crosses the built-in 20 cm gap clean
(10.9 m in 15 s); with the same numbers read on ``[m p_c; angular pose]`` in kg m and
kg m^2 (``weight_units = "quantity"``) the humanoid falls within 1 s on flat ground.
"""

from __future__ import annotations

from collections.abc import Callable

from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.scenario import make_scenario, run_scenario


def _run(robot: RobotModel, controller: str, course: str, seconds: float, *sets: str) -> dict:
    scenario = make_scenario(
        robot=robot.name,
        controller=controller,
        course=course,
        vx_mps=0.75,
        duration_s=seconds,
        preset="paper",
        overrides=list(sets),
    )
    return run_scenario(scenario, robot=robot)


def test_gaitnet_paper_preset_crosses_the_gap_clean(
    robots: Callable[[str], RobotModel],
) -> None:
    """The gap lies at about 1.7 m: 4 s at 0.75 m/s carries the robot across it."""
    s = _run(robots("humanoid3d"), "gaitnet", "gap", 4.0)
    assert not s["fell"], s["fall_reason"]
    assert s["distance_m"] > 2.5
    assert s["foothold_violations"] == 0
    assert not s["self_collisions"]


def test_table_viii_read_as_quantities_falls(robots: Callable[[str], RobotModel]) -> None:
    s = _run(robots("humanoid3d"), "kd", "flat", 2.0, "sequential.kd.weight_units=quantity")
    assert s["fell"] and s["fall_time_s"] < 1.5


def test_biped_paper_preset_walks(robots: Callable[[str], RobotModel]) -> None:
    s = _run(robots("biped2d"), "gaitnet", "flat", 3.0)
    assert not s["fell"], s["fall_reason"]
    assert s["distance_m"] > 1.5
