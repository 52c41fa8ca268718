"""The centroidal-momentum disturbance observer (issue 50, item 1) and its use by ``kd``.

The observer must read only what a robot measures (joint state, trunk pose and twist, the
feet's wrenches) and its estimate must be the wrench the model lacks: zero when nothing
else acts, an unknown payload's weight when one rides on the trunk. In the loop, the MPC
plans with it (eqs. 14-15's affine term), so the feet carry the payload.
"""

from __future__ import annotations

import numpy as np
import pytest

from gaitnet_mpc.control.disturbance_observer import DisturbanceObserverConfig, MomentumObserver
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.geometry import GRAVITY_MPS2
from gaitnet_mpc.runner.logs import EpisodeLog
from gaitnet_mpc.runner.loop import EpisodeLoop
from gaitnet_mpc.scenario import build_episode, make_scenario

PAYLOAD_KG = 3.0


def _walk(payload_kg: float, seconds: float, *overrides: str) -> tuple[EpisodeLoop, np.ndarray]:
    """``kd`` on flat at 0.5 m/s with an unknown payload; the loop and its log rows."""
    scenario = make_scenario(
        controller="kd",
        course="flat",
        vx_mps=0.5,
        duration_s=seconds,
        payload_kg=payload_kg,
        overrides=overrides,
    )
    episode = build_episode(scenario)
    loop = EpisodeLoop(episode.sim, episode.controller, episode.command, seconds)
    while not loop.done:
        loop.tick()
    return loop, np.asarray(loop.log.rows)


def _estimate(rows: np.ndarray, from_s: float) -> np.ndarray:
    """Mean of the logged estimate ``[f_ext; tau_ext]`` after ``from_s``."""
    cols = EpisodeLog.columns
    i = cols.index("fext_x_n")
    return rows[rows[:, 0] >= from_s, i : i + 6].mean(axis=0)


def test_the_estimate_is_the_unknown_payloads_weight_and_the_robot_carries_it() -> None:
    loop, rows = _walk(PAYLOAD_KG, 8.0)
    assert not loop.fell
    w = _estimate(rows, 6.0)
    np.testing.assert_allclose(w[2], -PAYLOAD_KG * GRAVITY_MPS2, rtol=0.05)
    assert np.abs(w[:2]).max() < 2.0  # N
    assert np.abs(w[3:]).max() < 1.5  # N m: the payload sits near the CoM
    # the CoM holds its height: the MPC's feet carry the weight it was not told about
    cols = EpisodeLog.columns
    z = rows[rows[:, 0] >= 6.0, cols.index("com_z_m")]
    assert abs(float(z.mean()) - float(rows[0, cols.index("com_z_m")])) < 0.03


def test_without_a_disturbance_the_estimate_stays_near_zero() -> None:
    _, rows = _walk(0.0, 3.0)
    cols = EpisodeLog.columns
    i = cols.index("fext_x_n")
    assert np.abs(rows[:, i : i + 3]).max() < 2.0  # N, at every tick
    assert np.abs(rows[:, i + 3 : i + 6]).max() < 1.0  # N m


def test_the_observer_can_be_switched_off() -> None:
    loop, rows = _walk(0.0, 0.2, "disturbance_observer=none")
    assert loop.controller.observer is None  # type: ignore[attr-defined]
    i = EpisodeLog.columns.index("fext_x_n")
    assert np.isnan(rows[:, i : i + 6]).all()


def test_a_step_of_external_force_is_followed_with_the_bandwidth() -> None:
    """dr/dt = K (w_ext - r): after a step of force at t = 0, r = w (1 - e^{-K t}). The robot
    is lifted 1 m, so no ground wrench acts; gravity alone is what the model expects, and a
    40 N upward force on the trunk is the only thing it lacks."""
    import mujoco

    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.sim.disturbances import Push
    from gaitnet_mpc.sim.simulator import SimConfig, Simulator
    from gaitnet_mpc.terrain import load_course

    robot = load_robot("humanoid3d")
    push = Push.parse("t=0,fz=40,dur=1")  # at the trunk's CoM
    sim = Simulator(robot, load_course("flat"), SimConfig(pushes=(push,)))
    sim.data.qpos[2] += 1.0
    mujoco.mj_forward(sim.model, sim.data)
    observer = MomentumObserver(robot, DisturbanceObserverConfig(bandwidth_radps=5.0), sim.state())
    tau = np.zeros(robot.n_joints)
    for _ in range(200):  # 0.2 s = 1/K
        sim.step(tau)
        observer.update(sim.state())
    assert observer.wrench[2] == pytest.approx(40.0 * (1.0 - np.exp(-1.0)), rel=0.05)
    assert np.abs(observer.wrench[:2]).max() < 0.5


def test_the_mpc_gets_the_force_beyond_the_dead_band_and_no_torque() -> None:
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.sim.simulator import Simulator
    from gaitnet_mpc.terrain import load_course

    robot = load_robot("humanoid3d")
    state = Simulator(robot, load_course("flat")).state()
    observer = MomentumObserver(robot, DisturbanceObserverConfig(), state)
    observer.wrench = np.array([1.0, -2.0, 2.0, 0.5, 0.5, 0.5])  # |f| = 3 N: in the band
    assert not observer.mpc_wrench().any()
    observer.wrench = np.array([0.0, 0.0, -29.4, 0.1, -0.4, 0.0])  # a 3 kg payload
    np.testing.assert_array_equal(observer.mpc_wrench(), [0.0, 0.0, -29.4, 0.0, 0.0, 0.0])
    with_torque = DisturbanceObserverConfig(torque_to_mpc=True, dead_band_n=0.0)
    observer = MomentumObserver(robot, with_torque, state)
    observer.wrench = np.array([1.0, 0.0, 0.0, 0.5, 0.5, 0.5])
    np.testing.assert_array_equal(observer.mpc_wrench(), observer.wrench)


def test_an_undisturbed_run_is_bitwise_the_run_without_the_observer() -> None:
    """Within the dead band the MPC plans as if there were no observer."""
    _, rows = _walk(0.0, 2.0)
    _, rows_off = _walk(0.0, 2.0, "disturbance_observer=none")
    cols = EpisodeLog.columns
    same = [i for i, c in enumerate(cols[: cols.index("fext_x_n")]) if c != "mpc_solve_ms"]
    np.testing.assert_array_equal(rows[:, same], rows_off[:, same])


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("bandwidth_radps", 0.0),
        ("max_force_n", -1.0),
        ("max_torque_nm", float("nan")),
        ("dead_band_n", 60.0),
    ],
)
def test_bad_settings_name_the_field(name: str, value: float) -> None:
    with pytest.raises(ConfigError) as err:
        DisturbanceObserverConfig(**{name: value})
    assert err.value.field == name
