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
        ("t=-1,dur=1", "--push t"),
        ("t=1,dur=0", "--push dur"),
        ("t=0.1,fx=1e9,dur=0.1", "--push fx"),
        ("t=0.1,fz=-1001,dur=0.1", "--push fz"),
        ("t=0.1,fx=800,fy=800,dur=0.1", "--push fx,fy,fz"),
        ("t=0.1,fx=100,dur=1.01", "--push impulse"),
        ("t=0.1,fx=1,dur=6", "--push dur"),
    ],
)
def test_push_parse_errors_name_the_field(text: str, field: str) -> None:
    with pytest.raises(ConfigError) as err:
        Push.parse(text)
    assert err.value.field == field


def test_push_bounds_are_inclusive() -> None:
    assert Push.parse("t=0,fx=1000,dur=0.1").impulse_ns[0] == pytest.approx(100.0)
    assert Push.parse("t=0,fy=20,dur=5").duration_s == 5.0


def test_payload_above_the_robot_mass_is_refused(humanoid) -> None:
    with pytest.raises(ConfigError, match=r"payload_kg: got 60\.0, expected a mass in \[0, 50\]"):
        SimConfig(payload_kg=60.0)
    with pytest.raises(ConfigError, match=r"payload_kg: got 16\.5, expected a mass in \[0, 16\]"):
        Simulator(humanoid, load_course("flat"), SimConfig(payload_kg=16.5))
    with pytest.raises(ConfigError, match=r"\[0, 10\] kg"):
        Simulator(load_robot("biped2d"), load_course("flat"), SimConfig(payload_kg=11.0))


def test_crossed_legs_are_self_collisions_not_a_fall(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    if sim.model.npair == 0:
        pytest.skip("the humanoid3d MJCF has no <contact><pair> self-collision entries yet")
    qpos = humanoid.standing_qpos()
    qpos[sim.model.joint("left_hip_roll").qposadr[0]] = -0.35  # both legs inward: they cross
    qpos[sim.model.joint("right_hip_roll").qposadr[0]] = 0.35
    qpos[2] += 0.1  # feet in the air: no terrain contact at all
    sim.reset(qpos)
    assert sim.self_contact  # the first log row already sees it
    sim.step(np.zeros(humanoid.n_joints))
    stats = sim.self_collisions
    assert sim.self_contact and stats.ticks == 1
    assert stats.first_t_s == pytest.approx(sim.config.timestep_s)
    assert 0.0 < stats.max_depth_m < 0.1
    assert ("left_shank", "right_shank") in stats.body_pairs
    assert all(a < b for a, b in stats.body_pairs)
    assert not sim.fall.fell  # a self-contact is not "a body other than a foot touched"
    assert not any(sim.state().foot_contact.values())
    summary = stats.to_dict()
    assert summary["self_collisions"] == 1
    assert "left_shank/right_shank" in summary["self_collision_pairs"]


def test_standing_has_no_self_collision(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    _run(sim, StandController(humanoid), 0.3)
    assert sim.self_collisions.to_dict() == {
        "self_collisions": 0,
        "self_collision_first_t_s": None,
        "self_collision_max_depth_m": 0.0,
        "self_collision_pairs": [],
    }
    assert not sim.self_contact and not sim.diverged


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


def test_protocol_pushes_follow_the_papers_protocol() -> None:
    from gaitnet_mpc.sim.disturbances import protocol_pushes

    pushes = protocol_pushes(seed=2, t_start_s=10.0, t_end_s=40.0)
    assert [p.t_s for p in pushes] == [10.0 + 2.0 * i for i in range(15)]
    forces = np.array([p.force_world_n for p in pushes])
    magnitude = np.linalg.norm(forces, axis=1)
    assert np.all((magnitude >= 10.0) & (magnitude <= 100.0)) and np.all(forces[:, 2] == 0.0)
    assert all(p.duration_s == 0.2 for p in pushes)
    assert len({round(float(np.arctan2(f[1], f[0])), 3) for f in forces}) == 15  # random
    assert protocol_pushes(seed=2, t_start_s=10.0, t_end_s=40.0) == pushes
