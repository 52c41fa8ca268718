"""The cart of Fig. 10 (``sim/cart.py``): checked settings, a scene where the hands can
only push (frictionless plate, no pull), a load no controller is told about, and a
walking controller that pushes it forward, slower the heavier it is."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

from dataclasses import replace

import numpy as np
import pytest

from gaitnet_mpc import config as configio
from gaitnet_mpc.control.stand import StandController
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.experiments.figure_fig10 import CartRecorder, cart_scenario
from gaitnet_mpc.robots import load_robot
from gaitnet_mpc.scenario import Scenario, build_episode, make_scenario, run_scenario
from gaitnet_mpc.sim.cart import Cart
from gaitnet_mpc.sim.simulator import SimConfig, Simulator
from gaitnet_mpc.terrain import load_course


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"load_kg": -1.0}, "cart.load_kg"),
        ({"load_kg": float("nan")}, "cart.load_kg"),
        ({"load_kg": 1e4}, "cart.load_kg"),
        ({"rolling_resistance": 0.9}, "cart.rolling_resistance"),
        ({"plate_ahead_m": 0.0}, "cart.plate_ahead_m"),
        ({"cart_mass_kg": 0.0}, "cart.cart_mass_kg"),
    ],
)
def test_bad_cart_settings_name_the_field(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(ConfigError) as info:
        Cart(**kwargs)
    assert info.value.field == field


def test_a_robot_without_arms_cannot_push_a_cart() -> None:
    with pytest.raises(ConfigError) as info:
        make_scenario(robot="biped2d", controller="kd", cart=Cart())
    assert info.value.field == "cart"


def test_the_load_is_in_the_scenario_not_the_controller(tmp_path) -> None:
    with_cart = make_scenario(controller="gaitnet", vx_mps=0.5, cart=Cart(load_kg=35.0))
    pose_only = make_scenario(
        controller="gaitnet", vx_mps=0.5, overrides=["low_level.arm_push=true"]
    )
    assert with_cart.config.low_level.arm_push  # the pose is set for the task ...
    assert configio.to_table(with_cart.config) == configio.to_table(pose_only.config)  # ... only
    path = tmp_path / "scenario.toml"
    path.write_text(with_cart.to_toml())
    back = Scenario.from_toml(path)
    assert back.cart == Cart(load_kg=35.0)
    assert replace(back, origin=with_cart.origin) == with_cart
    no_cart = make_scenario(controller="srbm", overrides=["low_level.arm_push=false"])
    assert no_cart.cart is None and "cart" not in no_cart.to_table()


def test_standing_beside_the_cart_leaves_it_at_rest() -> None:
    robot = load_robot("humanoid3d")
    course = load_course("flat")
    cart = Cart(load_kg=35.0)
    sim = Simulator(robot, course, SimConfig(cart=cart))
    state = sim.state()
    assert state.qpos.shape == (robot.mj_model.nq,)  # the cart's coordinate is not the robot's
    assert sim.model.nq == robot.mj_model.nq + 1
    stand = StandController(robot)
    stand.reset(state)
    x0, _, _ = sim.cart_reading()
    assert x0 == pytest.approx(course.start_xy[0] + cart.plate_ahead_m)
    for _ in range(500):
        sim.step(stand.compute(sim.state()))
    x, v, force = sim.cart_reading()
    assert abs(x - x0) < 1e-6 and abs(v) < 1e-6  # rolling resistance holds it
    assert np.allclose(force, 0.0)  # the hanging arms do not reach it
    assert not sim.fall.fell and sim.self_collisions.ticks == 0


@pytest.mark.slow
def test_srbm_pushes_the_cart_forward_slower_when_heavier() -> None:
    pushed = {}
    for load in (0.0, 20.0):
        rec = CartRecorder()
        scenario = cart_scenario("srbm", load, 2.5)
        episode = build_episode(scenario)
        forces = []

        def hook(sim, rec=rec, forces=forces) -> None:
            rec(sim)
            forces.append(sim.cart_reading()[2])

        summary = run_scenario(scenario, episode=episode, on_step=hook)
        assert not summary["fell"], (load, summary.get("fall_reason"))
        assert summary["self_collisions"] == 0  # hands on the cart are not self-contacts
        f = np.array(forces)
        assert np.all(f[:, 0] <= 1e-9)  # the plate pushes the hands back, never pulls
        # frictionless: along the normal only, horizontal on the plate's face and sides
        assert np.allclose(f[:, 2], 0.0, atol=1e-9)
        assert -f[:, 0].min() > 10.0 and rec.first_contact_s is not None
        a = rec.array()
        assert np.all(a[:, 2] > a[:, 1])  # the cart stays ahead of the CoM
        pushed[load] = rec.pushed_m
    assert pushed[20.0] > 0.3  # 2.5 s at up to 0.5 m/s, contact at 0.4 s
    assert pushed[0.0] > pushed[20.0] + 0.05  # 25 kg of cart resists more than 5 kg
