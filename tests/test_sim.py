"""Simulator, disturbances, fall detection, foothold log and the standing controller."""

from __future__ import annotations

import numpy as np
import pytest

from gaitnet_mpc.control.stand import StandController
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.sim.disturbances import Push
from gaitnet_mpc.sim.simulator import SimConfig, Simulator
from gaitnet_mpc.terrain import load_course

GRAVITY = 9.81


@pytest.fixture(scope="module")
def humanoid():
    return load_robot("humanoid3d")


def _run(sim: Simulator, controller, seconds: float) -> None:
    controller.reset(sim.state())
    for _ in range(round(seconds / sim.config.timestep_s)):
        sim.step(controller.compute(sim.state()))
        if sim.fall.fell:
            return


def test_push_parse() -> None:
    p = Push.parse("t=3,fx=50,fy=-10,dur=0.1")
    assert p.t_s == 3.0
    assert p.force_world_n == (50.0, -10.0, 0.0)
    np.testing.assert_allclose(p.impulse_ns, [5.0, -1.0, 0.0])
    assert p.active(3.05) and not p.active(3.1)


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("t=3,fx=50", "--push"),
        ("t=3,fx=abc,dur=1", "--push fx"),
        ("x=1,t=1,dur=1", "--push"),
        ("t=-1,dur=1", "push.t"),
        ("t=1,dur=0", "push.dur"),
    ],
)
def test_push_parse_errors_name_the_field(text: str, field: str) -> None:
    with pytest.raises(ConfigError) as err:
        Push.parse(text)
    assert err.value.field == field


def test_bad_torques_are_rejected(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    with pytest.raises(ConfigError, match="tau_nm"):
        sim.step(np.zeros(3))
    with pytest.raises(ConfigError, match="NaN"):
        sim.step(np.full(18, np.nan))


def test_standing_contact_wrenches_carry_the_weight(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    _run(sim, StandController(humanoid), 0.5)
    s = sim.state()
    assert all(s.foot_contact.values())
    total_fz = sum(w[2] for w in s.foot_wrench_world.values())
    assert total_fz == pytest.approx(humanoid.total_mass_kg * GRAVITY, rel=0.02)
    np.testing.assert_allclose(s.h_measured[:3] / humanoid.total_mass_kg, s.com_vel_world_mps)


def test_zero_torque_robot_falls_and_fall_is_timed(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    for _ in range(3000):
        sim.step(np.zeros(humanoid.n_joints))
        if sim.fall.fell:
            break
    assert sim.fall.fell
    assert 0.0 < sim.fall.t_s < 3.0


def test_standing_survives_a_5ns_push(humanoid) -> None:
    push = Push(0.3, (50.0, 0.0, 0.0), 0.1)
    sim = Simulator(humanoid, load_course("flat"), SimConfig(pushes=(push,)))
    _run(sim, StandController(humanoid), 2.0)
    assert not sim.fall.fell
    assert sim.state().com_world_m[2] > 0.5


def test_payload_is_in_the_simulation_only(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"), SimConfig(payload_kg=2.0))
    assert sim.model.body_subtreemass[1] == pytest.approx(18.0)
    assert humanoid.total_mass_kg == pytest.approx(16.0)
    _run(sim, StandController(humanoid), 0.5)
    total_fz = sum(w[2] for w in sim.state().foot_wrench_world.values())
    assert total_fz == pytest.approx(18.0 * GRAVITY, rel=0.03)


def test_robot_placed_over_a_gap_falls_into_it(humanoid) -> None:
    course = load_course("gap", width_m=0.4, x_m=1.5)
    sim = Simulator(humanoid, course)
    sim.reset(humanoid.standing_qpos(x_m=1.7))
    _run(sim, StandController(humanoid), 1.5)
    assert sim.fall.fell
    assert sim.state().com_world_m[2] < 0.3


def test_touchdowns_are_logged_with_patch_and_permission(humanoid) -> None:
    course = load_course("stepping-stones")
    sim = Simulator(humanoid, course)
    qpos = humanoid.standing_qpos(x_m=0.0)
    qpos[2] += 0.05  # drop from 5 cm: both feet touch down once
    sim.reset(qpos)
    _run(sim, StandController(humanoid), 0.6)
    feet = sorted(f.foot for f in sim.footholds)
    assert feet == ["left", "right"]
    for f in sim.footholds:
        assert f.allowed
        assert f.patch == course.patch_at(*f.pos_world_m[:2])
        assert 0.0 < f.t_s < 0.3


def test_biped_stands() -> None:
    biped = load_robot("biped2d")
    sim = Simulator(biped, load_course("flat"))
    _run(sim, StandController(biped), 1.0)
    assert not sim.fall.fell
